/* check_bench.c: `drape bench` end to end through the binary on tiny
 * scenes (the hang scene at 10 cm spacing: 16 particles; Cusick at 5 cm).
 * Checked: the CSV header is the documented column list (written out here,
 * from docs/performance.md, not taken from the code); every error is finite;
 * the reference pair agrees far below the errors measured; the error
 * decreases when the tolerance tightens by 100x (what any convergent method
 * must do, independent of drape's own numbers); the timed-out row and the
 * skipped rows of --max-wall; --out DIR; --kernels; exit statuses.  The
 * CSV is read back with a parser of this file. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#define CAP 65536
static char out[CAP], err[CAP];

#define HANG "../scenes/hang.yaml --spacing 10cm --t-end 0.1s --samples 5 --repeat 1"
#define MAXF 48
#define MAXR 32

/* The columns documented in docs/performance.md and `drape bench --help`. */
static const char *const columns[] = {
    "role", "scene", "fabric", "particles", "free_particles", "size_m", "t_end_s",
    "samples", "integrator", "default", "linear_solver", "rtol", "atol_m", "status",
    "wall_s", "cpu_s", "repeats", "steps", "rhs_evals", "jac_evals", "lin_setups",
    "lin_factors", "nonlin_iters", "err_test_fails", "conv_fails", "err_pos_rel",
    "err_pos_rms_rel", "err_final_rel", "err_final_v_rel", "dc", "dc_ref", "err_dc",
    "nodes", "message", "max_order", "step_s", NULL};

typedef struct table {
    int nrow, ncol;
    char *hdr[MAXF];
    char *row[MAXR][MAXF];
    char text[CAP];
} table;

/* Split one CSV line in place (quoted fields with "" inside). */
static int split(char *s, char **f, int max)
{
    int n = 0;
    for (;;) {
        char *w = s, *start = s;
        if (*s == '"') {
            s++;
            for (;;) {
                if (*s == '"' && s[1] == '"') { *w++ = '"'; s += 2; }
                else if (*s == '"') { s++; break; }
                else if (!*s) break;
                else *w++ = *s++;
            }
        } else {
            while (*s && *s != ',') *w++ = *s++;
        }
        char sep = *s;
        *w = 0;
        if (n < max) f[n++] = start;
        if (sep != ',') break;
        s++;
    }
    return n;
}

static void parse(table *t, const char *text)
{
    snprintf(t->text, sizeof t->text, "%s", text);
    t->nrow = 0;
    char *line = t->text, *nl;
    int first = 1;
    while (*line) {
        nl = strchr(line, '\n');
        if (nl) *nl = 0;
        if (first) {
            t->ncol = split(line, t->hdr, MAXF);
            first = 0;
        } else if (*line) {
            ck_assert_int_lt(t->nrow, MAXR);
            int n = split(line, t->row[t->nrow], MAXF);
            ck_assert_int_eq(n, t->ncol);
            t->nrow++;
        }
        if (!nl) break;
        line = nl + 1;
    }
}

static const char *cell(const table *t, int r, const char *col)
{
    for (int c = 0; c < t->ncol; c++)
        if (strcmp(t->hdr[c], col) == 0) return t->row[r][c];
    ck_abort_msg("no column %s", col);
    return NULL;
}

static double num(const table *t, int r, const char *col)
{
    const char *s = cell(t, r, col);
    char *end;
    double v = strtod(s, &end);
    ck_assert_msg(*s && !*end, "row %d column %s: `%s' is not a number", r, col, s);
    return v;
}

static void check_header(const table *t)
{
    int n = 0;
    while (columns[n]) n++;
    ck_assert_int_eq(t->ncol, n);
    for (int i = 0; i < n; i++) ck_assert_str_eq(t->hdr[i], columns[i]);
}

static table tab;

/* Hang at 10 cm: columns, finite errors, reference agreement, and a 100x
 * tighter tolerance lowers the error of both implicit integrators. */
START_TEST(test_hang_convergence)
{
    int st = tu_run_drape("bench " HANG " --integrators cvode-bdf,arkode-dirk --rtols 1e-4,1e-6",
                          out, CAP, err, CAP);
    ck_assert_msg(st == 0, "status %d: %s", st, err);
    ck_assert_msg(err[0] == 0, "stderr is not a terminal, expected nothing: %s", err);
    parse(&tab, out);
    check_header(&tab);
    ck_assert_int_eq(tab.nrow, 2 + 2 * 2);
    ck_assert_str_eq(cell(&tab, 0, "role"), "ref");
    ck_assert_str_eq(cell(&tab, 1, "role"), "ref-check");
    double worst_sweep = INFINITY;
    for (int r = 0; r < tab.nrow; r++) {
        ck_assert_str_eq(cell(&tab, r, "status"), "ok");
        ck_assert_str_eq(cell(&tab, r, "scene"), "hang");
        ck_assert_int_eq((int)num(&tab, r, "particles"), 16);
        ck_assert_double_eq_tol(num(&tab, r, "size_m"), 0.30, 1e-12);
        ck_assert_double_eq_tol(num(&tab, r, "atol_m"), num(&tab, r, "rtol") * 1e-3, 1e-20);
        ck_assert(num(&tab, r, "wall_s") > 0);
        ck_assert(num(&tab, r, "cpu_s") > 0);
        ck_assert(num(&tab, r, "steps") > 0);
        const char *e[] = {"err_pos_rel", "err_pos_rms_rel", "err_final_rel", "err_final_v_rel"};
        for (int k = 0; k < 4; k++) ck_assert(isfinite(num(&tab, r, e[k])));
        /* t_end is one of the sample times; RMS <= max */
        ck_assert(num(&tab, r, "err_final_rel") <= num(&tab, r, "err_pos_rel"));
        ck_assert(num(&tab, r, "err_pos_rms_rel") <= num(&tab, r, "err_pos_rel"));
        ck_assert_str_eq(cell(&tab, r, "dc"), ""); /* a hang scene has no DC */
        /* the BDF order column: cvode-bdf's default, empty for the others */
        ck_assert_str_eq(cell(&tab, r, "max_order"),
                         strcmp(cell(&tab, r, "integrator"), "cvode-bdf") == 0 ? "2" : "");
        if (r >= 2) {
            ck_assert(num(&tab, r, "err_pos_rel") > 0);
            if (num(&tab, r, "err_pos_rel") < worst_sweep) worst_sweep = num(&tab, r, "err_pos_rel");
            ck_assert(num(&tab, r, "jac_evals") > 0);
        }
    }
    /* the reference pair (two explicit Runge-Kutta codes of order 5 and 8 at
     * rtol 1e-10) agrees 100x better than the smallest error measured */
    double agree = num(&tab, 1, "err_pos_rel");
    ck_assert_msg(agree < 0.01 * worst_sweep, "reference agreement %g, smallest error %g",
                  agree, worst_sweep);
    ck_assert_double_eq(num(&tab, 0, "err_pos_rel"), 0.0);
    /* tolerance 100x tighter: error at least 3x smaller (a method of order
     * p with error ~ rtol^(p/(p+1)) gives 10-40x) */
    for (int i = 0; i < 2; i++) {
        int loose = 2 + 2 * i, tight = loose + 1;
        ck_assert_str_eq(cell(&tab, loose, "integrator"), cell(&tab, tight, "integrator"));
        ck_assert_double_eq_tol(num(&tab, loose, "rtol"), 1e-4, 1e-18);
        ck_assert_double_eq_tol(num(&tab, tight, "rtol"), 1e-6, 1e-18);
        const char *e[] = {"err_pos_rel", "err_final_rel"};
        for (int k = 0; k < 2; k++)
            ck_assert_msg(num(&tab, tight, e[k]) < num(&tab, loose, e[k]) / 3,
                          "%s %s: %g at 1e-6 vs %g at 1e-4", cell(&tab, loose, "integrator"),
                          e[k], num(&tab, tight, e[k]), num(&tab, loose, e[k]));
    }
}
END_TEST

/* --max-order 1 (backward Euler) reaches cvode-bdf: the column says 1, and
 * the error still falls with the tolerance, but as a first-order method's
 * does (error ~ rtol^(1/2): 10x for a 100x tighter rtol; at least 3x is
 * asserted, as for the default order above). */
START_TEST(test_max_order_bdf1)
{
    int st = tu_run_drape("bench " HANG " --integrators cvode-bdf --rtols 1e-3,1e-5 --max-order 1",
                          out, CAP, err, CAP);
    ck_assert_msg(st == 0, "status %d: %s", st, err);
    parse(&tab, out);
    check_header(&tab);
    ck_assert_int_eq(tab.nrow, 2 + 2);
    ck_assert_str_eq(cell(&tab, 0, "max_order"), ""); /* the reference is arkode-erk */
    for (int r = 2; r < 4; r++) {
        ck_assert_str_eq(cell(&tab, r, "status"), "ok");
        ck_assert_str_eq(cell(&tab, r, "integrator"), "cvode-bdf");
        ck_assert_str_eq(cell(&tab, r, "max_order"), "1");
    }
    double loose = num(&tab, 2, "err_pos_rel"), tight = num(&tab, 3, "err_pos_rel");
    ck_assert_msg(tight > 0 && tight < loose / 3, "BDF1: error %g at 1e-5, %g at 1e-3", tight,
                  loose);
    ck_assert_int_eq(tu_run_drape("bench " HANG " --max-order 0", out, CAP, err, CAP), 2);
    ck_assert_msg(strstr(err, "--max-order"), "%s", err);
}
END_TEST

/* Cusick at 5 cm: the DC columns are filled and err_dc = |dc - dc_ref|. */
START_TEST(test_cusick_dc)
{
    int st = tu_run_drape("bench ../scenes/cusick.yaml --spacing 5cm --t-end 0.05s --samples 2 "
                          "--repeat 1 --integrators auto --rtols 1e-4",
                          out, CAP, err, CAP);
    ck_assert_msg(st == 0, "status %d: %s", st, err);
    parse(&tab, out);
    check_header(&tab);
    ck_assert_int_eq(tab.nrow, 3);
    double dc_ref = num(&tab, 0, "dc");
    ck_assert(dc_ref > 0 && dc_ref <= 1.0 + 1e-9);
    for (int r = 0; r < 3; r++) ck_assert_double_eq(num(&tab, r, "dc_ref"), dc_ref);
    for (int r = 1; r < 3; r++) {
        ck_assert_double_eq_tol(num(&tab, r, "err_dc"), fabs(num(&tab, r, "dc") - dc_ref), 1e-5);
        ck_assert(num(&tab, r, "nodes") >= 0);
    }
    /* the default integrator is swept under its own name */
    ck_assert_str_eq(cell(&tab, 2, "integrator"), "auto");
    ck_assert_str_eq(cell(&tab, 2, "default"), "1");
}
END_TEST

/* --max-wall: a limit no run can meet gives one timeout row, then skipped
 * rows for the tighter tolerances; exit status 0. */
START_TEST(test_timeout_skips)
{
    int st = tu_run_drape("bench " HANG " --integrators arkode-dirk --rtols 1e-3:1e-5:1 "
                          "--max-wall 1e-6", out, CAP, err, CAP);
    ck_assert_msg(st == 0, "status %d: %s", st, err);
    parse(&tab, out);
    ck_assert_int_eq(tab.nrow, 5);
    ck_assert_str_eq(cell(&tab, 2, "status"), "timeout");
    ck_assert_double_eq_tol(num(&tab, 2, "rtol"), 1e-3, 1e-18);
    ck_assert_str_eq(cell(&tab, 2, "err_pos_rel"), "");
    ck_assert_str_eq(cell(&tab, 3, "status"), "skipped");
    ck_assert_str_eq(cell(&tab, 4, "status"), "skipped");
    ck_assert_double_eq_tol(num(&tab, 4, "rtol"), 1e-5, 1e-18);
}
END_TEST

/* --out DIR: nothing on stdout, DIR/NAME.csv with the header. */
START_TEST(test_out_dir)
{
    char args[1024], path[600];
    const char *dir = tu_scratch_dir();
    snprintf(args, sizeof args, "bench " HANG " --integrators gsl-rk8pd --rtols 1e-4 --out %s "
             "--name wp", dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    ck_assert_str_eq(out, "");
    snprintf(path, sizeof path, "%s/wp.csv", dir);
    FILE *f = fopen(path, "r");
    ck_assert_ptr_nonnull(f);
    size_t n = fread(out, 1, CAP - 1, f);
    out[n] = 0;
    fclose(f);
    parse(&tab, out);
    check_header(&tab);
    ck_assert_int_eq(tab.nrow, 3);
}
END_TEST

START_TEST(test_kernels)
{
    ck_assert_int_eq(tu_run_drape("bench --kernels ../scenes/hang.yaml --sizes 4,8", out, CAP,
                                  err, CAP), 0);
    parse(&tab, out);
    static const char *const kcols[] = {"side", "particles", "free_particles", "nnz_K",
        "rhs_ms", "jac_ms", "jac_first_order_ms", "schur_factor_ms", "rhs_us_per_free",
        "jac_us_per_free", "schur_solve_ms", NULL};
    for (int i = 0; kcols[i]; i++) ck_assert_str_eq(tab.hdr[i], kcols[i]);
    ck_assert_int_eq(tab.nrow, 2);
    ck_assert_int_eq((int)num(&tab, 0, "particles"), 16);
    ck_assert_int_eq((int)num(&tab, 1, "particles"), 64);
    ck_assert_int_eq((int)num(&tab, 1, "free_particles"), 62); /* two pinned corners */
    for (int r = 0; r < 2; r++)
        for (int i = 3; kcols[i]; i++) ck_assert(num(&tab, r, kcols[i]) > 0);
    /* more particles, more nonzeros */
    ck_assert(num(&tab, 1, "nnz_K") > num(&tab, 0, "nnz_K"));
}
END_TEST

START_TEST(test_usage)
{
    ck_assert_int_eq(tu_run_drape("bench --help", out, CAP, err, CAP), 0);
    ck_assert_ptr_nonnull(strstr(out, "Usage: drape bench"));
    ck_assert_ptr_nonnull(strstr(out, "err_pos_rel"));
    ck_assert_int_eq(tu_run_drape("bench --no-such-option", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("bench " HANG " --integrators nope", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("bench " HANG " --ref gsl-rk8pd,gsl-rk8pd", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("bench " HANG " --rtols 2", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("bench " HANG " --rtols 1e-2:1e-4:0", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("bench no-such-scene.yaml", out, CAP, err, CAP), 3);
    ck_assert_ptr_nonnull(strstr(err, "no-such-scene.yaml"));
    ck_assert_int_eq(tu_run_drape("bench --kernels ../scenes/cusick.yaml", out, CAP, err, CAP), 1);
}
END_TEST

/* bench's --rtols and --ref-rtol read each value as run's --rtol does: a
 * dimensionless quantity (fractions allowed, hex floats and numbers
 * outside the normal doubles refused) in (0, 1).  A scene that does not
 * exist tells them apart without running anything: an accepted value
 * reaches the scene (exit 3), a refused one stops at the option (exit 2,
 * the message naming it). */
static int bench_takes(const char *opt, const char *text)
{
    char cmd[256];
    snprintf(cmd, sizeof cmd, "bench %s '%s' no-such-scene.yaml", opt, text);
    int rc = tu_run_drape(cmd, out, CAP, err, CAP);
    if (rc == 3) {
        ck_assert_msg(strstr(err, "no-such-scene.yaml") != NULL, "%s: %s", cmd, err);
        return 1;
    }
    ck_assert_msg(rc == 2, "%s: exit %d, expected 2 or 3", cmd, rc);
    char named[32];
    snprintf(named, sizeof named, "drape: %s: ", opt);
    ck_assert_msg(strstr(err, named) != NULL, "%s: message does not name %s: %s", cmd, opt, err);
    return 0;
}

START_TEST(test_rtol_range)
{
    static const struct {
        const char *text;
        int ok;
    } one[] = {{"1e-3", 1}, {"0.5", 1}, {"1/1000", 1}, {"3/4", 1}, {"1e-300", 1},
               {"0", 0}, {"1", 0}, {"2", 0}, {"-1e-3", 0}, {"0x1p-10", 0},
               {"1e-400", 0}, {"1e-310", 0}, {"inf", 0}, {"nan", 0}, {"1e-3x", 0},
               {"1/0", 0}};
    for (size_t i = 0; i < sizeof one / sizeof one[0]; i++) {
        char cmd[128];
        snprintf(cmd, sizeof cmd, "run --rtol '%s' no-such-scene.yaml", one[i].text);
        int run_rc = tu_run_drape(cmd, out, CAP, err, CAP);
        ck_assert_msg(run_rc == (one[i].ok ? 3 : 2), "%s: exit %d", cmd, run_rc);
        ck_assert_msg(bench_takes("--rtols", one[i].text) == one[i].ok, "--rtols %s", one[i].text);
        ck_assert_msg(bench_takes("--ref-rtol", one[i].text) == one[i].ok, "--ref-rtol %s",
                      one[i].text);
    }
    /* the range refused in run's words, naming the option */
    ck_assert(!bench_takes("--rtols", "1e-3,2"));
    ck_assert_ptr_nonnull(strstr(err, "--rtols: must be in (0, 1), got 2"));
    ck_assert(!bench_takes("--ref-rtol", "1e-12,1e-400"));
    ck_assert_ptr_nonnull(strstr(err, "--ref-rtol: number out of range: \"1e-400\""));
    /* lists, the HI:LO:N form and the pair of --ref-rtol */
    ck_assert(bench_takes("--rtols", "1/100,1e-4,1/1000000"));
    ck_assert(!bench_takes("--rtols", "1e-3,0x1p-12"));
    ck_assert(bench_takes("--rtols", "1/100:1e-5:1"));
    ck_assert(!bench_takes("--rtols", "0x1p-4:1e-6:2"));
    ck_assert(!bench_takes("--rtols", "1e-3:1e-400:2"));
    ck_assert(!bench_takes("--rtols", "1e-4:1e-2:1")); /* LO > HI */
    ck_assert(bench_takes("--ref-rtol", "1e-12,1/1000"));
    ck_assert(!bench_takes("--ref-rtol", "1e-12,1e-11,1e-10"));
}
END_TEST

Suite *bench_suite(void)
{
    Suite *s = suite_create("bench");
    TCase *tc = tcase_create("bench");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_hang_convergence);
    tcase_add_test(tc, test_max_order_bdf1);
    tcase_add_test(tc, test_cusick_dc);
    tcase_add_test(tc, test_timeout_skips);
    tcase_add_test(tc, test_out_dir);
    tcase_add_test(tc, test_kernels);
    tcase_add_test(tc, test_usage);
    tcase_add_test(tc, test_rtol_range);
    suite_add_tcase(s, tc);
    return s;
}
