/* check_batch.c: `drape batch` end to end through the binary, on tiny runs
 * (the hang scene at 5 cm spacing, 0.05 s): one row per fabric with the
 * keys of `drape run --format csv` (compared with a direct run of the same
 * fabric), an error row for an invalid fabric, exit statuses, --resume
 * (which fabrics run again is seen from the per-fabric logs), -j 2 giving
 * the rows of -j 1, and a clean stop on SIGINT.  The CSV is read back with
 * a parser of this file, not the one under test. */
#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "testutil.h"

#define CAP 65536
static char out[CAP], err[CAP];

#define SCENE "../scenes/hang.yaml"
#define TINY "--spacing 5cm --t-max 0.05s"
#define COTTON "../fabrics/cotton-breen.yaml"
#define DENIM "../fabrics/denim-wang.yaml"
#define MAXF 96
#define MAXR 16

typedef struct table {
    int nrow, ncol;
    char *hdr[MAXF];
    char *row[MAXR][MAXF];
    char text[CAP];
} table;

static const char *subdir(const char *name)
{
    static char p[4][512];
    static int slot;
    char *d = p[slot++ % 4];
    snprintf(d, 512, "%s/%s", tu_scratch_dir(), name);
    return d;
}

static int read_text(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    size_t n = fread(buf, 1, cap - 1, f);
    buf[n] = 0;
    fclose(f);
    return 0;
}

/* Split one CSV line in place (quoted fields with "" inside); returns the
 * number of fields. */
static int split(char *s, char **f, int max)
{
    int n = 0;
    for (;;) {
        ck_assert(n < max);
        if (*s == '"') {
            char *w = ++s;
            f[n++] = w;
            for (;;) {
                ck_assert_msg(*s, "unterminated quote");
                if (*s == '"' && s[1] == '"') *w++ = '"', s += 2;
                else if (*s == '"') { s++; break; }
                else *w++ = *s++;
            }
            char *end = s;
            *w = 0;
            if (*end == 0) return n;
            ck_assert_int_eq(*end, ',');
            s = end + 1;
        } else {
            f[n++] = s;
            char *c = strchr(s, ',');
            if (!c) return n;
            *c = 0;
            s = c + 1;
        }
    }
}

/* results.csv of a batch directory */
static void load_table(const char *dir, table *t)
{
    char p[1024];
    snprintf(p, sizeof p, "%s/results.csv", dir);
    ck_assert_msg(read_text(p, t->text, sizeof t->text) == 0, "no %s", p);
    char *line = t->text, *nl;
    t->nrow = -1;
    while (*line && (nl = strchr(line, '\n'))) {
        *nl = 0;
        if (t->nrow < 0) t->ncol = split(line, t->hdr, MAXF);
        else {
            ck_assert(t->nrow < MAXR);
            int n = split(line, t->row[t->nrow], MAXF);
            ck_assert_msg(n == t->ncol, "row %d: %d fields, header %d", t->nrow, n, t->ncol);
        }
        t->nrow++;
        line = nl + 1;
    }
    ck_assert_msg(*line == 0, "results.csv does not end with a line break");
}

static int col(const table *t, const char *key)
{
    for (int i = 0; i < t->ncol; i++)
        if (strcmp(t->hdr[i], key) == 0) return i;
    ck_abort_msg("no column %s", key);
    return -1;
}

static const char *cell(const table *t, int r, const char *key)
{
    return t->row[r][col(t, key)];
}

static int has_log(const char *dir, const char *name)
{
    char p[1024];
    snprintf(p, sizeof p, "%s/logs/%s.stderr", dir, name);
    return access(p, F_OK) == 0;
}

static void clear_logs(const char *dir)
{
    char p[1024];
    snprintf(p, sizeof p, "rm -f '%s'/logs/*", dir);
    ck_assert_int_eq(system(p), 0);
}

static const char *bad_fabric(void)
{
    return tu_write_file("bad-fabric.yaml", "fabric: bad\nwieght: 1\n");
}

static int batch(const char *dir, const char *fabrics, const char *extra)
{
    char args[4096];
    snprintf(args, sizeof args, "batch -q %s %s " TINY " --out %s %s", SCENE, fabrics, dir,
             extra ? extra : "");
    return tu_run_drape(args, out, CAP, err, CAP);
}

START_TEST(test_rows_and_errors)
{
    const char *dir = subdir("rows");
    char fabrics[1024];
    snprintf(fabrics, sizeof fabrics, "%s %s %s", COTTON, bad_fabric(), DENIM);
    ck_assert_msg(batch(dir, fabrics, NULL) == 6, "exit status 6 expected: %s", err);
    ck_assert_str_eq(out, ""); /* stdout stays clean */

    /* a direct run of the first fabric, for the header and the values */
    static char direct[CAP];
    ck_assert_int_eq(tu_run_drape("run -q " SCENE " --fabric " COTTON " " TINY " --format csv",
                                  direct, CAP, err, CAP), 0);
    char *nl = strchr(direct, '\n');
    ck_assert_ptr_nonnull(nl);
    *nl = 0;
    char *dval = nl + 1;
    if ((nl = strchr(dval, '\n'))) *nl = 0;

    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 3);
    /* header: fabric_file, exactly the run's keys, error */
    static char want[CAP + 32], got[CAP + 32];
    snprintf(want, sizeof want, "fabric_file,%s,error", direct);
    got[0] = 0;
    for (int i = 0; i < t->ncol; i++) {
        strcat(got, i ? "," : "");
        strcat(got, t->hdr[i]);
    }
    ck_assert_str_eq(got, want);

    /* row 0 = the direct run, field by field (wall_s and cpu_s are timings) */
    char *dk[MAXF], *dv[MAXF];
    int nk = split(direct, dk, MAXF), nv = split(dval, dv, MAXF);
    ck_assert_int_eq(nk, nv);
    ck_assert_int_eq(nk + 2, t->ncol);
    for (int i = 0; i < nk; i++)
        if (strcmp(dk[i], "wall_s") != 0 && strcmp(dk[i], "cpu_s") != 0)
            ck_assert_msg(strcmp(cell(t, 0, dk[i]), dv[i]) == 0, "%s: batch %s, run %s", dk[i],
                          cell(t, 0, dk[i]), dv[i]);
    ck_assert_str_eq(cell(t, 0, "fabric_file"), COTTON);
    ck_assert_str_eq(cell(t, 0, "status"), "t_max");
    ck_assert_str_eq(cell(t, 0, "error"), "");

    /* row 1: the invalid fabric: no result, the run's message and status */
    ck_assert_str_eq(cell(t, 1, "status"), "error");
    ck_assert_str_eq(cell(t, 1, "fabric"), "");
    ck_assert_str_eq(cell(t, 1, "particles"), "");
    const char *e = cell(t, 1, "error");
    ck_assert_msg(strstr(e, "bad-fabric.yaml:2:1: wieght: unknown key") != NULL, "%s", e);
    ck_assert_msg(strstr(e, "(exit status 1)") != NULL, "%s", e);

    /* row 2 ran too: the batch continues past a failure */
    ck_assert_str_eq(cell(t, 2, "fabric"), "denim-wang");
    ck_assert_str_eq(cell(t, 2, "status"), "t_max");
    ck_assert_str_eq(cell(t, 2, "error"), "");
    /* a run's warnings are in its log, not in the error column */
    ck_assert(has_log(dir, "denim-wang"));

    /* no temporary files left */
    DIR *d = opendir(dir);
    ck_assert_ptr_nonnull(d);
    struct dirent *de;
    while ((de = readdir(d)))
        ck_assert_msg(strstr(de->d_name, ".tmp") == NULL, "left over: %s", de->d_name);
    closedir(d);
    free(t);

    /* all fabrics fine: exit status 0 */
    ck_assert_msg(batch(subdir("ok"), COTTON, NULL) == 0, "%s", err);
}
END_TEST

START_TEST(test_parallel_same_rows)
{
    const char *d1 = subdir("j1"), *d2 = subdir("j2");
    char fabrics[1024];
    snprintf(fabrics, sizeof fabrics,
             "%s %s %s ../fabrics/cotton-breen-kes.yaml ../fabrics/polyester-jacket-wang.yaml",
             COTTON, DENIM, bad_fabric());
    ck_assert_int_eq(batch(d1, fabrics, "-j 1"), 6);
    ck_assert_int_eq(batch(d2, fabrics, "-j 2"), 6);
    table *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    ck_assert(a && b);
    load_table(d1, a);
    load_table(d2, b);
    ck_assert_int_eq(a->nrow, 5);
    ck_assert_int_eq(b->nrow, 5);
    int w = col(a, "wall_s"), cpu = col(a, "cpu_s");
    for (int r = 0; r < 5; r++)
        for (int i = 0; i < a->ncol; i++)
            if (i != w && i != cpu)
                ck_assert_msg(strcmp(a->row[r][i], b->row[r][i]) == 0, "row %d %s: %s vs %s", r,
                              a->hdr[i], a->row[r][i], b->row[r][i]);
    free(a);
    free(b);
}
END_TEST

/* --method and --linear-solver reach the runs: a static batch over the
 * Cusick scene at 2 cm gives each fabric's certified minimum, the same
 * row as `drape run` with the same options. */
START_TEST(test_method_passed_on)
{
    const char *d = subdir("static");
    char args[4096];
    snprintf(args, sizeof args,
             "batch -q ../scenes/cusick.yaml %s %s --spacing 2cm --method static "
             "--linear-solver klu --out %s", COTTON, DENIM, d);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(d, t);
    ck_assert_int_eq(t->nrow, 2);
    for (int r = 0; r < 2; r++) {
        ck_assert_str_eq(cell(t, r, "method"), "static");
        ck_assert_str_eq(cell(t, r, "status"), "equilibrium");
        ck_assert_str_eq(cell(t, r, "certified"), "minimum");
    }
    ck_assert_int_eq(tu_run_drape("run -q ../scenes/cusick.yaml --fabric " COTTON
                                  " --spacing 2cm --method static --format csv",
                                  out, CAP, err, CAP), 0);
    char *nl = strchr(out, '\n');
    ck_assert_ptr_nonnull(nl);
    char *hdr[MAXF], *row[MAXF];
    *nl = 0;
    int nh = split(out, hdr, MAXF);
    char *end = strchr(nl + 1, '\n');
    if (end) *end = 0;
    ck_assert_int_eq(split(nl + 1, row, MAXF), nh);
    for (int i = 0; i < nh; i++)
        if (strcmp(hdr[i], "dc") == 0) ck_assert_str_eq(cell(t, 0, "dc"), row[i]);
    free(t);
}
END_TEST

/* Every option that batch passes on, all at once (21 of them, with
 * --frames): the runs' argument array overflowed from 14 (a stack buffer
 * of 40 entries; AddressSanitizer saw it in `make asan`), and each value
 * reaches the run. */
START_TEST(test_many_options_passed_on)
{
    const char *d = subdir("many");
    char args[4096];
    snprintf(args, sizeof args,
             "batch -q ../scenes/cantilever.yaml %s --out %s --frames --integrator cvode-bdf "
             "--rtol 1e-4 --atol 1e-7 --spacing 1cm --energy-form consistent --t-max 1s "
             "--max-steps 100000 --strain-limit 0.3 --method fall --linear-solver auto "
             "--max-order 2 --specimens 1 --seed 3 --fall-time 0.5s --fall-step 2ms "
             "--fall-swing 0.02 --fall-tol 0 --fall-fold-time 0.1s --fall-retry 0 "
             "--terms stretch,bend,shear,gravity --damping-shear 0", COTTON, d);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(d, t);
    ck_assert_int_eq(t->nrow, 1);
    ck_assert_str_eq(cell(t, 0, "method"), "fall");
    ck_assert_str_eq(cell(t, 0, "seed"), "3");
    ck_assert_double_eq_tol(atof(cell(t, 0, "spacing_m")), 0.01, 1e-12);
    ck_assert_double_eq_tol(atof(cell(t, 0, "fall_step_s")), 0.002, 1e-12);
    free(t);
}
END_TEST

/* --max-order reaches the runs: the result row says BDF1 (the scene's
 * integrator is cvode-bdf); a bad value is a usage error. */
START_TEST(test_max_order_passed_on)
{
    const char *d = subdir("bdf1");
    char args[4096];
    snprintf(args, sizeof args,
             "batch -q ../scenes/hang.yaml %s --spacing 10cm --t-max 0.05s --max-order 1 --out %s",
             COTTON, d);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(d, t);
    ck_assert_int_eq(t->nrow, 1);
    ck_assert_str_eq(cell(t, 0, "integrator"), "cvode-bdf");
    ck_assert_str_eq(cell(t, 0, "max_order"), "1");
    free(t);
    snprintf(args, sizeof args, "batch -q ../scenes/hang.yaml %s --max-order 7 --out %s", COTTON,
             subdir("bdf7"));
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
    ck_assert_msg(strstr(err, "--max-order"), "%s", err);
}
END_TEST

/* --terms, --fall-swing, --fall-tol and --damping-shear reach the runs
 * (issue 18, ninth, eleventh and thirteenth sessions): a fabric with a bias
 * curve runs with the twist term unless --terms leaves it out, --fall-swing
 * 0 ends every fall at its fall time, and --fall-tol and --damping-shear
 * are the values the result reports (the shear damping the fabric's, 0.5
 * ms for a fabric file without one, unless set). */
START_TEST(test_terms_passed_on)
{
    for (int k = 0; k < 2; k++) {
        const char *d = subdir(k ? "terms-seed" : "terms-all");
        char args[4096];
        snprintf(args, sizeof args,
                 "batch -q ../scenes/hang.yaml %s --spacing 10cm --t-max 0.05s %s --out %s", DENIM,
                 k ? "--terms stretch,bend,shear,gravity" : "", d);
        ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
        table *t = malloc(sizeof *t);
        ck_assert_ptr_nonnull(t);
        load_table(d, t);
        ck_assert_int_eq(t->nrow, 1);
        ck_assert_str_eq(cell(t, 0, "terms"), k ? "stretch+bend+shear+gravity"
                                                : "stretch+bend+shear+gravity+bias");
        ck_assert(strtod(cell(t, 0, "damping_shear_s"), NULL) == 5e-4);
        free(t);
    }
    const char *d = subdir("swing0");
    char args[4096];
    snprintf(args, sizeof args,
             "batch -q ../scenes/cusick.yaml %s --spacing 5cm --specimens 1 --fall-swing 0 "
             "--fall-tol 1mm --damping-shear 0.25ms --out %s",
             DENIM, d);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(d, t);
    ck_assert_str_eq(cell(t, 0, "fall_end_s"), cell(t, 0, "fall_time_s"));
    ck_assert_double_eq_tol(strtod(cell(t, 0, "fall_tol_m"), NULL), 1e-3, 1e-15);
    ck_assert_double_eq_tol(strtod(cell(t, 0, "damping_shear_s"), NULL), 2.5e-4, 1e-15);
    free(t);
    ck_assert_int_eq(tu_run_drape("batch -q ../scenes/hang.yaml --damping-shear 2m", out, CAP,
                                  err, CAP), 2);
    ck_assert_msg(strstr(err, "--damping-shear"), "%s", err);
    ck_assert_int_eq(tu_run_drape("batch -q ../scenes/hang.yaml --fall-tol -1mm", out, CAP, err,
                                  CAP), 2);
    ck_assert_msg(strstr(err, "--fall-tol"), "%s", err);
    ck_assert_int_eq(tu_run_drape("batch -q ../scenes/hang.yaml --terms bend,twist", out, CAP, err,
                                  CAP), 2);
    ck_assert_msg(strstr(err, "--terms"), "%s", err);
}
END_TEST

START_TEST(test_resume)
{
    const char *dir = subdir("resume");
    char fabrics[1024], p[1024];
    snprintf(fabrics, sizeof fabrics, "%s %s %s", COTTON, bad_fabric(), DENIM);
    ck_assert_int_eq(batch(dir, fabrics, NULL), 6);
    table *t = malloc(sizeof *t), *u = malloc(sizeof *u);
    ck_assert(t && u);
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 3);

    /* as if the batch had died before denim finished: drop its row */
    snprintf(p, sizeof p, "%s/results.csv", dir);
    static char text[CAP];
    ck_assert_int_eq(read_text(p, text, CAP), 0);
    char *dl = strstr(text, "\n" DENIM ",");
    ck_assert_ptr_nonnull(dl);
    char *end = strchr(dl + 1, '\n');
    memmove(dl + 1, end + 1, strlen(end + 1) + 1);
    FILE *f = fopen(p, "w");
    ck_assert_ptr_nonnull(f);
    fputs(text, f);
    fclose(f);
    clear_logs(dir);

    ck_assert_msg(batch(dir, fabrics, "--resume") == 6, "%s", err);
    /* denim ran again, and so did the error row; cotton (done) did not */
    ck_assert(has_log(dir, "denim-wang"));
    ck_assert(has_log(dir, "bad-fabric"));
    ck_assert(!has_log(dir, "cotton-breen"));
    load_table(dir, u);
    ck_assert_int_eq(u->nrow, 3);
    ck_assert_str_eq(cell(u, 0, "fabric_file"), COTTON);
    ck_assert_str_eq(cell(u, 2, "fabric_file"), DENIM);
    ck_assert_str_eq(cell(u, 2, "status"), "t_max");
    /* the kept row is the old one, timing included */
    for (int i = 0; i < t->ncol; i++) ck_assert_str_eq(u->row[0][i], t->row[0][i]);

    /* nothing left to run but the invalid fabric */
    clear_logs(dir);
    snprintf(fabrics, sizeof fabrics, "%s %s", COTTON, DENIM);
    ck_assert_int_eq(batch(dir, fabrics, "--resume"), 0);
    ck_assert(!has_log(dir, "denim-wang") && !has_log(dir, "cotton-breen"));
    load_table(dir, u); /* the other fabric's row is kept, after these */
    ck_assert_int_eq(u->nrow, 3);
    ck_assert_str_eq(cell(u, 2, "status"), "error");

    /* the same options in another order: the same batch (was refused) */
    char args[2048];
    snprintf(args, sizeof args, "batch -q %s %s --t-max 0.05s --spacing 5cm --out %s --resume",
             SCENE, COTTON, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    /* the same values written otherwise (5cm = 0.05m = 50mm, 0.05s =
     * 50ms = 5e-2): the same batch (was refused: compared as written) */
    snprintf(args, sizeof args, "batch -q %s %s --t-max 50ms --spacing 0.05m --out %s --resume",
             SCENE, COTTON, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    snprintf(args, sizeof args, "batch -q %s %s --spacing 50mm --t-max 5e-2 --out %s --resume",
             SCENE, COTTON, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    /* a value only a little different is another value */
    snprintf(args, sizeof args, "batch -q %s %s --t-max 0.05s --spacing 5.000001cm --out %s "
             "--resume", SCENE, COTTON, dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
    ck_assert_msg(strstr(err, "batch.args") != NULL, "%s", err);

    /* other run options: refused */
    snprintf(args, sizeof args, "batch -q %s %s --spacing 4cm --t-max 0.05s --out %s --resume",
             SCENE, COTTON, dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
    ck_assert_msg(strstr(err, "batch.args") != NULL, "%s", err);
    free(t);
    free(u);
}
END_TEST

/* --resume after the inputs were edited: a fabric file whose text changed
 * since its row was made runs again (its old row had been kept, made
 * from the old text); a changed scene file is refused (exit 2), as other
 * options are.  Any change of bytes counts, a comment too. */
START_TEST(test_resume_changed_inputs)
{
    const char *dir = subdir("changed");
    static char text[CAP];
    char fab[1024], scene[1024], fabrics[2200], args[4096], p[1200];
    ck_assert_int_eq(read_text(COTTON, text, CAP), 0);
    snprintf(fab, sizeof fab, "%s", tu_write_file("changed-fabric.yaml", text));
    ck_assert_int_eq(read_text(SCENE, text, CAP), 0);
    /* the scene's fabric by an absolute path, from the scratch directory */
    char cwd[600], *fl = strstr(text, "fabric: ../"), *rest;
    ck_assert_ptr_nonnull(fl);
    ck_assert_ptr_nonnull(getcwd(cwd, sizeof cwd));
    rest = strchr(fl, '\n');
    static char text2[CAP];
    snprintf(text2, sizeof text2, "%.*sfabric: %s/%.*s%s", (int)(fl - text), text, cwd,
             (int)(rest - fl - 8), fl + 8, rest);
    snprintf(scene, sizeof scene, "%s", tu_write_file("changed-scene.yaml", text2));
    snprintf(fabrics, sizeof fabrics, "%s %s", fab, DENIM);
    snprintf(args, sizeof args, "batch -q %s %s " TINY " --out %s", scene, fabrics, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    clear_logs(dir);

    snprintf(args, sizeof args, "batch -q %s %s " TINY " --out %s --resume", scene, fabrics, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert(!has_log(dir, "changed-fabric") && !has_log(dir, "denim-wang"));

    FILE *f = fopen(fab, "a");
    ck_assert_ptr_nonnull(f);
    fputs("# edited\n", f);
    fclose(f);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert(has_log(dir, "changed-fabric") && !has_log(dir, "denim-wang"));
    ck_assert_msg(strstr(err, "changed since its row was made: run again"), "%s", err);
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 2);
    ck_assert_str_eq(cell(t, 0, "status"), "t_max");
    free(t);
    clear_logs(dir); /* and now it is on record */
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert(!has_log(dir, "changed-fabric"));

    f = fopen(scene, "a");
    ck_assert_ptr_nonnull(f);
    fputs("# edited\n", f);
    fclose(f);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
    ck_assert_msg(strstr(err, "changed since this batch started"), "%s", err);
    snprintf(p, sizeof p, "%s/inputs.sum", dir);
    ck_assert_int_eq(access(p, F_OK), 0);
}
END_TEST

/* A --resume that is itself stopped before a changed fabric's new run
 * (SIGINT while another fabric runs, -j 1) wrote the fabric's new sum to
 * inputs.sum next to its old row; the next --resume then took that row,
 * made from the old text, as done and never ran the fabric again.  The
 * old row keeps its old sum until its new run replaces it. */
START_TEST(test_resume_changed_then_stopped)
{
    const char *dir = subdir("changed-stopped");
    static char text[CAP];
    char fab[1024], args[4096], first[1200];
    ck_assert_int_eq(read_text(COTTON, text, CAP), 0);
    snprintf(fab, sizeof fab, "%s", tu_write_file("edited-fabric.yaml", text));
    snprintf(args, sizeof args, "batch -q %s %s --spacing 5cm --t-max 0.3s --out %s", SCENE,
             fab, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);

    FILE *f = fopen(fab, "a");
    ck_assert_ptr_nonnull(f);
    fputs("# edited\n", f);
    fclose(f);
    clear_logs(dir);
    /* denim first; stopped while it runs, before the edited fabric starts */
    snprintf(first, sizeof first, "%s/logs/denim-wang.stderr", dir);
    const char *const a[] = {"batch", "-q", SCENE, DENIM, fab, "--spacing", "5cm", "--t-max",
                             "0.3s", "--out", dir, "--resume", NULL};
    pid_t pid = tu_spawn_drape(a, NULL, NULL, 0);
    ck_assert_file_appears(pid, first, 20.0);
    int ws = tu_signal_and_reap(pid, SIGINT, 0);
    ck_assert(WIFEXITED(ws));
    ck_assert_int_eq(WEXITSTATUS(ws), 130);
    ck_assert_msg(!has_log(dir, "edited-fabric"), "the edited fabric ran: stopped too late");

    snprintf(args, sizeof args, "batch -q %s %s --spacing 5cm --t-max 0.3s --out %s --resume",
             SCENE, fab, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert_msg(has_log(dir, "edited-fabric"), "the edited fabric's old row was kept");
    ck_assert_msg(strstr(err, "changed since its row was made: run again"), "%s", err);
}
END_TEST

START_TEST(test_failed_run)
{
    /* a numerical failure gives a row with status failed and the message;
     * it is deterministic, so --resume does not run it again */
    const char *dir = subdir("failed");
    ck_assert_int_eq(batch(dir, COTTON, "--max-steps 5"), 6);
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 1);
    ck_assert_str_eq(cell(t, 0, "status"), "failed");
    ck_assert_msg(strstr(cell(t, 0, "error"), "failed at t = ") != NULL, "%s", cell(t, 0, "error"));
    ck_assert_msg(strstr(cell(t, 0, "error"), "(exit status 4)") != NULL, "%s", cell(t, 0, "error"));
    clear_logs(dir);
    ck_assert_int_eq(batch(dir, COTTON, "--max-steps 5 --resume"), 6);
    ck_assert(!has_log(dir, "cotton-breen"));
    free(t);
}
END_TEST

START_TEST(test_usage)
{
    char args[2048];
    ck_assert_int_eq(tu_run_drape("batch", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("batch " SCENE, out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("batch " SCENE " " COTTON " -j x", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("batch " SCENE " " COTTON " --rtol 2", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("batch " SCENE " " COTTON " --spacing 5kg", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("batch " SCENE " " COTTON " --integrator euler", out, CAP, err, CAP), 2);
    /* every option passed on is refused before any run, with run's reason */
    static const char *const bad[] = {
        "--atol -1mm", "--energy-form exact", "--t-max 0", "--max-steps 0",
        "--strain-limit 0", "--method quench", "--linear-solver lu", "--max-order 6",
        "--specimens 0", "--seed -1", "--fall-time 1m", "--fall-step 0",
        "--fall-swing 1", "--fall-tol -1cm", "--fall-fold-time -1s", "--fall-retry 1e400",
        "--damping-shear 2m", "--terms stretch,twist",
        /* underflow is refused, not read as 0 */
        "--fall-tol 1e-400m", "--fall-swing 1e-400", "--damping-shear 1e-310s"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char run_err[1024];
        snprintf(args, sizeof args, "run %s " SCENE, bad[i]);
        ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
        snprintf(run_err, sizeof run_err, "%.900s", err + strlen("drape: "));
        *strchr(run_err, '\n') = 0;
        snprintf(args, sizeof args, "batch " SCENE " " COTTON " %s --out %s", bad[i],
                 subdir("badopt"));
        ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 2);
        ck_assert_msg(strncmp(err, "drape: batch: ", 14) == 0 && strstr(err, run_err) != NULL,
                      "%s: run said `%s', batch `%s'", bad[i], run_err, err);
        ck_assert_msg(access(subdir("badopt"), F_OK) != 0, "%s: --out made", bad[i]);
    }
    /* animate writes a renderer's frames: not a batch's method */
    ck_assert_int_eq(tu_run_drape("batch " SCENE " " COTTON " --method animate", out, CAP, err, CAP), 2);
    /* the scene is checked once, before any run */
    const char *scene = tu_write_file("bad-scene.yaml", "scene: hang\nspacing: 1 kg\n");
    snprintf(args, sizeof args, "batch %s %s --out %s", scene, COTTON, subdir("badscene"));
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 1);
    ck_assert_msg(strstr(err, "bad-scene.yaml") != NULL, "%s", err);
    /* an output directory that cannot be made */
    ck_assert_int_eq(tu_run_drape("batch " SCENE " " COTTON " --out /proc/drape-batch", out, CAP,
                                  err, CAP), 3);
}
END_TEST

START_TEST(test_sigint_keeps_finished_rows)
{
    /* -j 1 over three fabrics of ~0.5 s each; interrupt during the first:
     * it finishes and is written, no other starts, exit status 130 */
    const char *dir = subdir("sigint");
    char e_path[1024];
    snprintf(e_path, sizeof e_path, "%s/sigint.stderr", tu_scratch_dir());
    const char *const a[] = {"batch", "-q", SCENE, COTTON, DENIM,
                             "../fabrics/cotton-breen-kes.yaml", "--spacing", "5cm", "--t-max",
                             "0.3s", "--out", dir, NULL};
    pid_t pid = tu_spawn_drape(a, NULL, e_path, 0);
    char first[1024];
    snprintf(first, sizeof first, "%s/logs/cotton-breen.stderr", dir);
    ck_assert_msg(tu_wait_file(pid, first, 20.0) == 0, "the first run did not start");
    int ws = tu_signal_and_reap(pid, SIGINT, 0);
    ck_assert(WIFEXITED(ws));
    ck_assert_int_eq(WEXITSTATUS(ws), 130);
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(dir, t);
    /* every run that started has finished and has its row */
    int started = has_log(dir, "cotton-breen") + has_log(dir, "denim-wang") +
                  has_log(dir, "cotton-breen-kes");
    ck_assert_int_ge(t->nrow, 1);
    ck_assert_int_lt(t->nrow, 3);
    ck_assert_int_eq(t->nrow, started);
    for (int r = 0; r < t->nrow; r++) ck_assert_str_eq(cell(t, r, "status"), "t_max");
    static char e[CAP];
    ck_assert_int_eq(read_text(e_path, e, CAP), 0);
    ck_assert_msg(strstr(e, "interrupted") != NULL, "%s", e);
    free(t);
}
END_TEST

/* tests/bad through `drape batch` (check_cli.c does `drape check`,
 * check_run.c `drape run`): a bad scene stops the batch before anything is
 * written (status 1, 3 or 5, the file's line and key, no DIR); a bad fabric
 * gives its row status error with the line and key in the error column,
 * exit status 6, and no frames directory of its run.  combo- files are
 * scenes whose own fabric is bad: a batch replaces the fabric, so they run
 * (not checked here). */

static void want_line_key(const char *name, const char *text, int line, const char *key)
{
    char pat[300];
    if (line > 0) {
        snprintf(pat, sizeof pat, ".yaml:%d:", line);
        ck_assert_msg(strstr(text, pat) != NULL, "%s: want line %d in: %s", name, line, text);
    }
    if (key[0]) {
        snprintf(pat, sizeof pat, " %s: ", key);
        ck_assert_msg(strstr(text, pat) != NULL, "%s: want key `%s` in: %s", name, key, text);
    }
}

START_TEST(test_bad_corpus)
{
    DIR *d = opendir("bad");
    ck_assert_msg(d != NULL, "tests/bad missing");
    struct dirent *e;
    int n_scene = 0, n_fabric = 0, k = 0;
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        if (len < 6 || strcmp(e->d_name + len - 5, ".yaml") != 0) continue;
        char path[600], key[256], args[4096], dir[600];
        int line;
        snprintf(path, sizeof path, "bad/%s", e->d_name);
        tu_bad_header(path, &line, key, sizeof key);
        int fabric = strncmp(e->d_name, "fabric-", 7) == 0;
        int yaml = strncmp(e->d_name, "yaml-", 5) == 0;
        int scene = strncmp(e->d_name, "scene-", 6) == 0 || yaml;
        if (scene) {
            snprintf(dir, sizeof dir, "%s/bad-scene-%d", tu_scratch_dir(), k++);
            /* no --spacing: the batch checks the scene as its runs use it,
             * and --spacing would replace a bad spacing (scene-too-fine) */
            snprintf(args, sizeof args, "batch -q '%s' %s --t-max 0.05s --frames --out '%s'",
                     path, COTTON, dir);
            int st = tu_run_drape(args, out, CAP, err, CAP);
            ck_assert_msg(st == 1 || st == 3 || st == 5, "%s: status %d: %s", e->d_name, st, err);
            ck_assert_msg(strncmp(err, "drape: ", 7) == 0, "%s: %s", e->d_name, err);
            want_line_key(e->d_name, err, line, key);
            ck_assert_msg(access(dir, F_OK) != 0, "%s: %s was created", e->d_name, dir);
            n_scene++;
        }
        if (fabric || yaml) {
            snprintf(dir, sizeof dir, "%s/bad-fabric-%d", tu_scratch_dir(), k++);
            snprintf(args, sizeof args, "batch -q %s '%s' " TINY " --frames --out '%s'", SCENE,
                     path, dir);
            int st = tu_run_drape(args, out, CAP, err, CAP);
            ck_assert_msg(st == 6, "%s: status %d (want 6): %s", e->d_name, st, err);
            load_table(dir, t);
            ck_assert_int_eq(t->nrow, 1);
            ck_assert_str_eq(cell(t, 0, "status"), "error");
            want_line_key(e->d_name, cell(t, 0, "error"), line, key);
            char frames[700];
            snprintf(frames, sizeof frames, "%s/frames", dir);
            DIR *fd = opendir(frames);
            ck_assert_ptr_nonnull(fd);
            struct dirent *fe;
            while ((fe = readdir(fd)) != NULL)
                ck_assert_msg(fe->d_name[0] == '.', "%s: frames/%s was created", e->d_name,
                              fe->d_name);
            closedir(fd);
            n_fabric++;
        }
    }
    closedir(d);
    free(t);
    ck_assert_int_ge(n_scene, 25);
    ck_assert_int_ge(n_fabric, 15);
}
END_TEST

/* 1 once the run's log (logs/NAME.csv) says interrupted, 0 if it has not
 * within 10 s: a run whose batch was killed outright stops by itself. */
static int wait_log_interrupted(const char *log)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "grep -q interrupted '%s' 2>/dev/null", log);
    for (int i = 0; i < 200; i++) {
        if (system(cmd) == 0) return 1;
        struct timespec w = {0, 50 * 1000 * 1000};
        nanosleep(&w, NULL);
    }
    return 0;
}

/* SIGTERM to a batch stops its running fabric at the next output point:
 * its row says interrupted (exit status 143); --resume with --frames
 * continues that run from its checkpoint (`drape run --resume`) and the
 * row then matches a direct, uninterrupted run (up to the tolerance). */
/* A batch killed outright (SIGKILL: the OOM killer, a hard job limit)
 * cannot stop its runs; they ran on unseen to their end.  Each run now
 * gets SIGTERM when the batch dies and ends as interrupted, its row in
 * its log and its checkpoint kept for --resume. */
START_TEST(test_killed_batch_stops_runs)
{
    const char *dir = subdir("killed");
    char first[1024], log[1024], cmd[2400];
    snprintf(first, sizeof first, "%s/frames/cotton-breen/frame_000001.obj", dir);
    snprintf(log, sizeof log, "%s/logs/cotton-breen.csv", dir);
    const char *const a[] = {"batch", "-q", SCENE, COTTON, "--spacing", "5cm", "--t-max",
                             "600s", "--frames", "--out", dir, NULL};
    pid_t pid = tu_spawn_drape(a, NULL, NULL, 0);
    ck_assert_msg(tu_wait_file(pid, first, 20.0) == 0, "the run did not start");
    tu_signal_and_reap(pid, SIGKILL, 0);
    int stopped = wait_log_interrupted(log);
    if (!stopped) { /* do not leave it running */
        snprintf(cmd, sizeof cmd, "pkill -TERM -f -- '--out %s/frames/cotton-breen'", dir);
        if (system(cmd) != 0) { /* nothing matched */ }
    }
    ck_assert_msg(stopped, "the run went on after its batch was killed");
    snprintf(cmd, sizeof cmd, "%s/frames/cotton-breen/drape.h5", dir);
    ck_assert_msg(access(cmd, F_OK) == 0, "no checkpoint");
}
END_TEST

/* A fresh batch of denim alone into dir (results.csv without cotton's
 * row), then `--resume` with denim and cotton, both at --t-max tmax with
 * --frames; loads the table into t: two rows, cotton's the second. */
static void denim_then_cotton_resumed(const char *dir, const char *tmax, table *t)
{
    char args[2048];
    snprintf(args, sizeof args, "batch -q %s %s --spacing 5cm --t-max %s --frames --out %s",
             SCENE, DENIM, tmax, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    snprintf(args, sizeof args, "batch -q %s %s %s --spacing 5cm --t-max %s --frames --out %s "
             "--resume", SCENE, DENIM, COTTON, tmax, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 2);
    ck_assert_str_eq(cell(t, 1, "fabric_file"), COTTON);
}

/* After a batch killed outright, its run stopped as interrupted with its
 * checkpoint (test_killed_batch_stops_runs) but left no row in
 * results.csv; `batch --resume --frames` then ran that fabric afresh
 * over its checkpoint (frame 0 written again) instead of continuing it
 * as it does an interrupted row's run. */
START_TEST(test_killed_batch_resumed)
{
    const char *dir = subdir("killed-resumed");
    char wait_for[1024], frame0[1024], log[1024], cmd[2400], args[2048];
    snprintf(wait_for, sizeof wait_for, "%s/frames/cotton-breen/frame_000003.obj", dir);
    snprintf(frame0, sizeof frame0, "%s/frames/cotton-breen/frame_000000.obj", dir);
    snprintf(log, sizeof log, "%s/logs/cotton-breen.csv", dir);
    const char *const a[] = {"batch", "-q", SCENE, COTTON, "--spacing", "5cm", "--t-max",
                             "1s", "--frames", "--out", dir, NULL};
    pid_t pid = tu_spawn_drape(a, NULL, NULL, 0);
    ck_assert_file_appears(pid, wait_for, 20.0);
    tu_signal_and_reap(pid, SIGKILL, 0);
    int stopped = wait_log_interrupted(log);
    ck_assert_msg(stopped, "the run was not interrupted when its batch was killed");
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 0); /* the batch died before it collected the run */
    struct stat before, after;
    ck_assert_int_eq(stat(frame0, &before), 0);

    snprintf(args, sizeof args, "batch -q %s %s --spacing 5cm --t-max 1s --frames --out %s "
             "--resume", SCENE, COTTON, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert_int_eq(stat(frame0, &after), 0);
    ck_assert_msg(before.st_ino == after.st_ino, "frame 0 was written again: not continued");
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 1);
    ck_assert_str_eq(cell(t, 0, "status"), "t_max");
    ck_assert_str_eq(cell(t, 0, "t_end_s"), "1");

    /* a fabric without a row whose frames hold a finished run (its row
     * dropped: a batch without it in between) runs afresh: `drape run
     * --resume` has nothing to continue there */
    denim_then_cotton_resumed(dir, "1s", t);
    ck_assert_str_eq(cell(t, 1, "status"), "t_max");

    /* nor does one whose checkpoint is older than batch.args: a batch
     * with other options (t-max 0.5 s) was started afresh since, and the
     * run would continue with the checkpoint's (1 s) */
    clear_logs(dir);
    snprintf(cmd, sizeof cmd, "rm -f '%s/frames/cotton-breen/'*", dir);
    ck_assert_int_eq(system(cmd), 0);
    pid = tu_spawn_drape(a, NULL, NULL, 0);
    ck_assert_file_appears(pid, wait_for, 20.0);
    tu_signal_and_reap(pid, SIGKILL, 0);
    stopped = wait_log_interrupted(log);
    ck_assert_msg(stopped, "the run was not interrupted when its batch was killed");
    denim_then_cotton_resumed(dir, "0.5s", t);
    ck_assert_str_eq(cell(t, 1, "t_end_s"), "0.5");
    free(t);
}
END_TEST

/* A batch of an ensemble scene interrupted while a dynamic specimen runs:
 * `batch --resume --frames` ran that fabric's whole ensemble again from
 * the start (its specimen-001 frames rewritten).  It now continues it from
 * its manifest, the interrupted specimen from its checkpoint. */
START_TEST(test_resume_ensemble_row)
{
    const char *dir = subdir("ens-row");
    char wait_for[1024], cmd[2400], f0[1024];
    snprintf(wait_for, sizeof wait_for, "%s/frames/cotton-breen/specimen-001/frame_000002.obj",
             dir);
    snprintf(f0, sizeof f0, "%s/frames/cotton-breen/specimen-001/frame_000000.obj", dir);
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    ck_assert_int_eq(system(cmd), 0);
    const char *const a[] = {"batch", "-q", "../scenes/cusick.yaml", COTTON, "--spacing", "5cm",
                             "--method", "dynamic", "--specimens", "2", "--frames", "--out",
                             dir, NULL};
    pid_t pid = tu_spawn_drape(a, NULL, NULL, 0);
    ck_assert_file_appears(pid, wait_for, 30.0);
    tu_signal_and_reap(pid, SIGTERM, 0);
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 1);
    ck_assert_str_eq(cell(t, 0, "status"), "interrupted");
    struct stat st;
    ck_assert_int_eq(stat(f0, &st), 0);
    ino_t frame0 = st.st_ino;

    char args[2400];
    snprintf(args, sizeof args, "batch -q ../scenes/cusick.yaml %s --spacing 5cm --method "
             "dynamic --specimens 2 --frames --out %s --resume", COTTON, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 1);
    ck_assert_str_eq(cell(t, 0, "status"), "equilibrium");
    ck_assert_str_eq(cell(t, 0, "specimens"), "2");
    ck_assert_str_eq(cell(t, 0, "specimens_failed"), "0");
    /* continued, not begun again: its first frame is the one written before */
    ck_assert_int_eq(stat(f0, &st), 0);
    ck_assert_msg(st.st_ino == frame0, "specimen-001 ran again from the start");
    free(t);
}
END_TEST

/* Cotton as SCRATCH/sub1/a.yaml (f1) and denim as SCRATCH/sub2/a.yaml (f2):
 * two fabrics of one file name, so of one NAME stem. */
static void two_fabrics_named_a(const char *sub1, const char *sub2, char f1[1100], char f2[1100])
{
    char cmd[4096];
    snprintf(f1, 1100, "%s/%s/a.yaml", tu_scratch_dir(), sub1);
    snprintf(f2, 1100, "%s/%s/a.yaml", tu_scratch_dir(), sub2);
    snprintf(cmd, sizeof cmd, "mkdir -p %s/%s %s/%s && cp %s %s && cp %s %s", tu_scratch_dir(),
             sub1, tu_scratch_dir(), sub2, COTTON, f1, DENIM, f2);
    ck_assert_int_eq(system(cmd), 0);
}

/* dir's results.csv has the two rows of two_fabrics_named_a, both t_max,
 * each the run of its own file (cotton's the one under cotton_dir). */
static void assert_rows_of_a(const char *dir, const char *cotton_dir)
{
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 2);
    for (int r = 0; r < 2; r++) {
        const char *file = cell(t, r, "fabric_file"), *name = cell(t, r, "fabric");
        ck_assert_str_eq(cell(t, r, "status"), "t_max");
        ck_assert_msg(strcmp(name, strstr(file, cotton_dir) ? "cotton-breen" : "denim-wang") == 0,
                      "%s: row of %s", file, name);
    }
    free(t);
}

/* Two fabrics with one file name in two directories get the frame
 * directories a and a-2 in command-line order; a --resume that lists them
 * the other way round continued each from the other's checkpoint (rows
 * swapped, exit 0).  Each run now goes on only from its own fabric's. */
START_TEST(test_resume_swapped_names)
{
    const char *dir = subdir("swapped");
    char cmd[8192], f1[1100], f2[1100], w1[1200], w2[1200];
    two_fabrics_named_a("d1", "d2", f1, f2);
    snprintf(w1, sizeof w1, "%s/frames/a/frame_000001.obj", dir);
    snprintf(w2, sizeof w2, "%s/frames/a-2/frame_000001.obj", dir);
    const char *const a[] = {"batch", "-q", SCENE, f1, f2, "--spacing", "5cm", "--t-max",
                             "0.3s", "-j", "2", "--frames", "--out", dir, NULL};
    pid_t pid = tu_spawn_drape(a, NULL, NULL, 0);
    ck_assert_msg(tu_wait_file(pid, w1, 20.0) == 0 && tu_wait_file(pid, w2, 20.0) == 0,
                  "the runs did not start");
    int ws = tu_signal_and_reap(pid, SIGTERM, 0);
    ck_assert_msg(WIFEXITED(ws) && WEXITSTATUS(ws) == 143, "status %d", ws);
    clear_logs(dir);
    snprintf(cmd, sizeof cmd, "batch -q %s %s %s --spacing 5cm --t-max 0.3s -j 2 --frames "
             "--out %s --resume", SCENE, f2, f1, dir);
    ck_assert_msg(tu_run_drape(cmd, out, CAP, err, CAP) == 0, "%s", err);
    assert_rows_of_a(dir, "/d1/");
}
END_TEST

/* NAMEs followed the command line's order alone: a --resume listing a new
 * d2/a.yaml before the done d1/a.yaml gave the new fabric NAME a, and its
 * run wrote over d1/a.yaml's frames/a and logs/a.* (found by the batch
 * review).  A fabric whose row was made under a NAME keeps it (recorded
 * in inputs.sum); the new one takes a-2. */
START_TEST(test_resume_keeps_names)
{
    const char *dir = subdir("kept-names");
    char cmd[8192], f1[1100], f2[1100], frame[1200], log[1200];
    two_fabrics_named_a("kn1", "kn2", f1, f2);
    snprintf(cmd, sizeof cmd, "batch -q %s %s --spacing 5cm --t-max 0.1s --frames --out %s",
             SCENE, f1, dir);
    ck_assert_msg(tu_run_drape(cmd, out, CAP, err, CAP) == 0, "%s", err);
    snprintf(frame, sizeof frame, "%s/frames/a/frame_000000.obj", dir);
    snprintf(log, sizeof log, "%s/logs/a.csv", dir);
    struct stat f_before, l_before, f_after, l_after;
    ck_assert_int_eq(stat(frame, &f_before), 0);
    ck_assert_int_eq(stat(log, &l_before), 0);
    snprintf(cmd, sizeof cmd, "batch -q %s %s %s --spacing 5cm --t-max 0.1s --frames --out %s "
             "--resume", SCENE, f2, f1, dir);
    ck_assert_msg(tu_run_drape(cmd, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert_int_eq(stat(frame, &f_after), 0);
    ck_assert_int_eq(stat(log, &l_after), 0);
    ck_assert_msg(f_before.st_ino == f_after.st_ino && l_before.st_ino == l_after.st_ino &&
                      l_before.st_mtime == l_after.st_mtime,
                  "the done fabric's frames/a or logs/a.csv were written over");
    ck_assert(has_log(dir, "a-2"));
    snprintf(cmd, sizeof cmd, "grep -q denim-wang '%s'", log);
    ck_assert_msg(system(cmd) != 0, "logs/a.csv holds the new fabric's row");
    assert_rows_of_a(dir, "/kn1/");
    /* the names stay through a further --resume in yet another order */
    snprintf(cmd, sizeof cmd, "batch -q %s %s %s --spacing 5cm --t-max 0.1s --frames --out %s "
             "--resume", SCENE, f1, f2, dir);
    ck_assert_msg(tu_run_drape(cmd, out, CAP, err, CAP) == 0, "%s", err);
    snprintf(cmd, sizeof cmd, "grep -q '^[0-9a-f]*:a-2\t%s$' '%s/inputs.sum' && "
             "grep -q '^[0-9a-f]*:a\t%s$' '%s/inputs.sum'", f2, dir, f1, dir);
    ck_assert_msg(system(cmd) == 0, "inputs.sum does not record the NAMEs");
}
END_TEST

START_TEST(test_interrupted_row_resumed)
{
    const char *dir = subdir("interrupted");
    char first[1024], args[2048];
    snprintf(first, sizeof first, "%s/frames/cotton-breen/frame_000000.obj", dir);
    const char *const a[] = {"batch", "-q", SCENE, COTTON, "--spacing", "5cm", "--t-max", "0.3s",
                             "--frames", "--out", dir, NULL};
    pid_t pid = tu_spawn_drape(a, NULL, NULL, 0);
    ck_assert_msg(tu_wait_file(pid, first, 20.0) == 0, "the run did not start");
    int ws = tu_signal_and_reap(pid, SIGTERM, 0);
    ck_assert(WIFEXITED(ws));
    ck_assert_int_eq(WEXITSTATUS(ws), 143);
    table *t = malloc(sizeof *t);
    ck_assert_ptr_nonnull(t);
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 1);
    ck_assert_str_eq(cell(t, 0, "status"), "interrupted");
    ck_assert_msg(strstr(cell(t, 0, "error"), "(exit status 143)"), "%s", cell(t, 0, "error"));
    double t_int = atof(cell(t, 0, "t_end_s"));
    ck_assert(t_int < 0.3);
    /* a continued run keeps the earlier frame files (a new run would
     * replace them: a new inode) */
    struct stat before, after;
    ck_assert_int_eq(stat(first, &before), 0);
    char frame0[1024];
    snprintf(frame0, sizeof frame0, "%s", first);

    clear_logs(dir);
    snprintf(args, sizeof args, "batch -q %s %s --spacing 5cm --t-max 0.3s --frames --out %s "
             "--resume", SCENE, COTTON, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert(has_log(dir, "cotton-breen"));
    ck_assert_int_eq(stat(frame0, &after), 0);
    ck_assert_msg(before.st_ino == after.st_ino, "frame 0 was written again: not a resume");
    load_table(dir, t);
    ck_assert_int_eq(t->nrow, 1);
    ck_assert_str_eq(cell(t, 0, "status"), "t_max");
    ck_assert_str_eq(cell(t, 0, "error"), "");
    ck_assert_str_eq(cell(t, 0, "t_end_s"), "0.3");
    /* the same as a run that was never interrupted (rtol 1e-5 on a 30 cm
     * cloth: 1e-4 of the gravity energy is far above the restart's effect
     * and far below what a wrong resume would give) */
    static char direct[CAP];
    ck_assert_int_eq(tu_run_drape("run -q " SCENE " --fabric " COTTON
                                  " --spacing 5cm --t-max 0.3s --format json",
                                  direct, CAP, err, CAP), 0);
    const char *g = strstr(direct, "\"gravity\": ");
    ck_assert_ptr_nonnull(g);
    double want = atof(g + 11), got = atof(cell(t, 0, "energy_J_gravity"));
    ck_assert_msg(fabs(got - want) <= 1e-4 * fabs(want), "gravity energy %g, uninterrupted %g",
                  got, want);
    /* every frame is there once: 0 .. 0.3 s every 1/30 s */
    char frames[1024];
    snprintf(frames, sizeof frames, "%s/frames/cotton-breen", dir);
    DIR *d = opendir(frames);
    ck_assert_ptr_nonnull(d);
    int nobj = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) nobj += strstr(e->d_name, ".obj") != NULL;
    closedir(d);
    ck_assert_int_eq(nobj, 10);
    free(t);
}
END_TEST

Suite *batch_suite(void)
{
    Suite *s = suite_create("batch");
    TCase *tc = tcase_create("batch");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_rows_and_errors);
    tcase_add_test(tc, test_parallel_same_rows);
    tcase_add_test(tc, test_method_passed_on);
    tcase_add_test(tc, test_max_order_passed_on);
    tcase_add_test(tc, test_many_options_passed_on);
    tcase_add_test(tc, test_terms_passed_on);
    tcase_add_test(tc, test_resume);
    tcase_add_test(tc, test_failed_run);
    tcase_add_test(tc, test_usage);
    tcase_add_test(tc, test_sigint_keeps_finished_rows);
    tcase_add_test(tc, test_bad_corpus);
    tcase_add_test(tc, test_interrupted_row_resumed);
    tcase_add_test(tc, test_resume_swapped_names);
    tcase_add_test(tc, test_resume_keeps_names);
    tcase_add_test(tc, test_killed_batch_stops_runs);
    tcase_add_test(tc, test_killed_batch_resumed);
    tcase_add_test(tc, test_resume_ensemble_row);
    tcase_add_test(tc, test_resume_changed_inputs);
    tcase_add_test(tc, test_resume_changed_then_stopped);
    suite_add_tcase(s, tc);
    return s;
}
