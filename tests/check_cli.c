/* check_cli.c: the command line, end to end through the drape binary:
 * help and version, exit statuses, every shipped fabric and scene accepted,
 * the shared examples accepted unchanged, every file of the bad-input
 * corpus (tests/bad) rejected with FILE:LINE:COL and a non-zero status;
 * the data directories (src/cli_data.h, issue 17). */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <json-c/json.h>

#include "testutil.h"

#define CAP 65536
static char out[CAP], err[CAP];

START_TEST(test_help_version)
{
    ck_assert_int_eq(tu_run_drape("--help", out, CAP, err, CAP), 0);
    ck_assert_ptr_nonnull(strstr(out, "Usage: drape"));
    ck_assert_ptr_nonnull(strstr(out, "Exit status"));
    ck_assert_int_eq(tu_run_drape("--version", out, CAP, err, CAP), 0);
    ck_assert_ptr_nonnull(strstr(out, "drape "));
    ck_assert_int_eq(tu_run_drape("check --help", out, CAP, err, CAP), 0);
    ck_assert_int_eq(tu_run_drape("run --help", out, CAP, err, CAP), 0);
    ck_assert_ptr_nonnull(strstr(out, "--spacing"));
    /* the help names the shipped scenes' numbers of specimens, read here
     * from the scene files' own `specimens:` lines */
    int n[2] = {0, 0};
    const char *scenes[2] = {"../scenes/cusick.yaml", "../scenes/table.yaml"};
    for (int k = 0; k < 2; k++) {
        FILE *fp = fopen(scenes[k], "r");
        ck_assert_ptr_nonnull(fp);
        char line[512];
        while (fgets(line, sizeof line, fp))
            if (sscanf(line, "specimens: %d", &n[k]) == 1) break;
        fclose(fp);
        ck_assert_int_gt(n[k], 1);
    }
    char want[128];
    snprintf(want, sizeof want, "Cusick scene asks for %d, the table scene for %d.", n[0], n[1]);
    ck_assert_msg(strstr(out, want) != NULL, "run --help does not say: %s", want);

    /* every key of a result (an ensemble's: all of them) is named in the
     * help, as a whole word */
    static char help[CAP];
    snprintf(help, sizeof help, "%s", out);
    ck_assert_int_eq(tu_run_drape("run -q ../scenes/cusick.yaml --spacing 3cm --method static "
                                  "--specimens 2 -j 1", out, CAP, err, CAP), 0);
    json_object *o = json_tokener_parse(out);
    ck_assert_msg(o != NULL, "%s", out);
    int nkeys = 0;
    json_object_object_foreach(o, key, val) {
        (void)val;
        size_t kl = strlen(key);
        int found = 0;
        for (const char *p = strstr(help, key); p && !found; p = strstr(p + 1, key)) {
            char before = p > help ? p[-1] : ' ', after = p[kl];
            found = !(before == '_' || (before >= 'a' && before <= 'z')) &&
                    !(after == '_' || (after >= 'a' && after <= 'z') || (after >= '0' && after <= '9'));
        }
        ck_assert_msg(found, "run --help does not name the result key %s", key);
        nkeys++;
    }
    ck_assert_int_gt(nkeys, 70);
    json_object_put(o);

    /* an unknown option, or one without its argument, is named (exit 2) */
    static const char *const bad[][2] = {
        {"run --bogus", "--bogus"},       {"run --spacing", "--spacing"},
        {"run -Z", "'Z'"},                {"batch --bogus x.yaml", "--bogus"},
        {"check --bogus", "--bogus"},     {"bench --bogus", "--bogus"},
        {"import --bogus", "--bogus"},    {"compare --bogus a.json b.json", "--bogus"}};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        int st = tu_run_drape(bad[k][0], out, CAP, err, CAP);
        ck_assert_msg(st == 2 && strstr(err, bad[k][1]) && strstr(err, "--help"),
                      "drape %s: exit %d, %s", bad[k][0], st, err);
    }
}
END_TEST

/* Paths that name no file in the current directory come from DRAPE_DATA
 * (the tests run in tests/, where there is no scenes/ or fabrics/): the
 * default scene, a fabric given to check and --fabric; a path starting
 * with ./ is the current directory's only; a missing one names every place
 * looked in. */
START_TEST(test_data_dirs)
{
    char data[4096]; /* the checkout: the parent of tests/ */
    ck_assert_ptr_nonnull(getcwd(data, sizeof data));
    char *slash = strrchr(data, '/');
    ck_assert(slash && strcmp(slash, "/tests") == 0);
    *slash = 0;
    ck_assert_int_eq(setenv("DRAPE_DATA", data, 1), 0);
    ck_assert_int_eq(tu_run_drape("--version", out, CAP, err, CAP), 0);
    ck_assert_msg(strstr(out, data) && strstr(out, "(DRAPE_DATA)"), "%s", out);
    ck_assert_int_eq(tu_run_drape("check fabrics/denim-wang.yaml", out, CAP, err, CAP), 0);
    char want[4200];
    snprintf(want, sizeof want, "%s/fabrics/denim-wang.yaml: valid fabric", data);
    ck_assert_msg(strstr(out, want) != NULL, "%s", out);
    ck_assert_int_eq(tu_run_drape("check ./fabrics/denim-wang.yaml", out, CAP, err, CAP), 3);
    /* the default scene, with a fabric from the data directory */
    ck_assert_int_eq(tu_run_drape("run -q --spacing 2cm --method static --specimens 1 "
                                  "--fabric fabrics/denim-wang.yaml", out, CAP, err, CAP), 0);
    ck_assert_msg(strstr(out, "\"scene\": \"cusick\"") && strstr(out, "denim-wang"), "%s", out);
    ck_assert_int_eq(setenv("DRAPE_DATA", "/nonexistent-drape-data", 1), 0);
    ck_assert_int_eq(tu_run_drape("run -q", out, CAP, err, CAP), 3);
    ck_assert_msg(strstr(err, "scenes/cusick.yaml") && strstr(err, "/nonexistent-drape-data (DRAPE_DATA)"),
                  "%s", err);
    ck_assert_int_eq(tu_run_drape("check ../fabrics/denim-wang.yaml", out, CAP, err, CAP), 0);
    unsetenv("DRAPE_DATA");
}
END_TEST

START_TEST(test_usage_errors)
{
    ck_assert_int_eq(tu_run_drape("", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("frobnicate", out, CAP, err, CAP), 2);
    ck_assert_ptr_nonnull(strstr(err, "unknown command"));
    ck_assert_int_eq(tu_run_drape("--bogus", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("check", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("run --spacing 5kg ../scenes/hang.yaml", out, CAP, err, CAP), 2);
    ck_assert_ptr_nonnull(strstr(err, "--spacing"));
    ck_assert_int_eq(tu_run_drape("run --integrator nope ../scenes/hang.yaml", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("run --energy-form odd ../scenes/hang.yaml", out, CAP, err, CAP), 2);
}
END_TEST

/* An abbreviation that begins more than one long option is a bad command
 * line naming them, in every subcommand: getopt_long alone took the first
 * match where the options share their getopt value (`--fall-t 0.5` ran
 * with --fall-tol 0.5 m, `--ma 3` with --max-steps 3).  An exact name, or
 * a prefix of only one option, still works (the spacing and end time
 * given as --spac and --t-m are the result's), and a value that looks
 * like an option is the option's value, not an option. */
START_TEST(test_ambiguous_options)
{
    static const char *const cmd[][3] = {
        {"run -q ../scenes/hang.yaml --spacing 5cm --t-max 0.05s --fall-t 0.5", "--fall-time",
         "--fall-tol"},
        {"run -q ../scenes/hang.yaml --spacing 5cm --t-max 0.05s --fall-t=0.5", "--fall-time",
         "--fall-tol"},
        {"run -q ../scenes/hang.yaml --spacing 5cm --t-max 0.05s --ma 3", "--max-steps",
         "--max-order"},
        {"batch -q --t 0.2s ../scenes/hang.yaml ../fabrics/denim-wang.yaml", "--t-max", "--terms"},
        {"bench --re 2", "--repeat", "--ref-rtol"},
        {"import --f arcsim x.json", NULL, NULL}, /* --force only: not ambiguous */
    };
    for (size_t i = 0; i < sizeof cmd / sizeof cmd[0]; i++) {
        int st = tu_run_drape(cmd[i][0], out, CAP, err, CAP);
        if (!cmd[i][1]) {
            ck_assert_msg(!strstr(err, "ambiguous"), "drape %s: %s", cmd[i][0], err);
            continue;
        }
        ck_assert_msg(st == 2, "drape %s: status %d, %s", cmd[i][0], st, err);
        ck_assert_msg(strstr(err, "ambiguous") && strstr(err, cmd[i][1]) && strstr(err, cmd[i][2]),
                      "drape %s: %s", cmd[i][0], err);
        ck_assert_msg(out[0] == 0, "drape %s printed %s", cmd[i][0], out);
    }
    ck_assert_int_eq(tu_run_drape("run -q ../scenes/hang.yaml --spac 5cm --t-m 0.05s --format json",
                                  out, CAP, err, CAP), 0);
    ck_assert_msg(strstr(out, "\"spacing_m\": 0.05,") && strstr(out, "\"t_end_s\": 0.05,"), "%s",
                  out);
    /* --ref is a whole name, and a prefix of --ref-rtol, --ref-max-wall */
    ck_assert_int_eq(tu_run_drape("bench --ref cvode-bdf,nope", out, CAP, err, CAP), 2);
    ck_assert_msg(strstr(err, "--ref: unknown integrator `nope'"), "%s", err);
    ck_assert_int_eq(tu_run_drape("run -q --terms --fall-t", out, CAP, err, CAP), 2);
    ck_assert_msg(strstr(err, "--terms:") && !strstr(err, "ambiguous"), "%s", err);
}
END_TEST

/* An empty directory name given to --out, --resume or --out-dir was
 * taken as a path: `drape run --out ''` failed with exit 3 and "cannot
 * create directory" naming no path, and batch's directory maker read past
 * the empty string's end.  Now it is a bad command line (exit 2) naming
 * the option, before anything runs. */
START_TEST(test_empty_dir_options)
{
    static const char *const cmd[][2] = {
        {"run -q ../scenes/hang.yaml --spacing 5cm --out ''", "--out:"},
        {"run -q --resume ''", "--resume:"},
        {"batch -q ../scenes/hang.yaml ../fabrics/denim-wang.yaml --spacing 5cm --out ''", "--out:"},
        {"bench --out ''", "--out:"},
        {"import arcsim --out-dir '' nonexistent.json", "--out-dir:"}};
    for (size_t i = 0; i < sizeof cmd / sizeof cmd[0]; i++) {
        int st = tu_run_drape(cmd[i][0], out, CAP, err, CAP);
        ck_assert_msg(st == 2, "drape %s: status %d, %s", cmd[i][0], st, err);
        ck_assert_msg(strstr(err, cmd[i][1]) && strstr(err, "empty name"), "drape %s: %s",
                      cmd[i][0], err);
        ck_assert_msg(out[0] == 0, "drape %s printed %s", cmd[i][0], out);
    }
}
END_TEST

/* Every file in a directory of the source tree passes `drape check`. */
static void check_dir_valid(const char *dir)
{
    DIR *d = opendir(dir);
    ck_assert_msg(d != NULL, "cannot open %s", dir);
    struct dirent *e;
    int n = 0;
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        if (len < 6 || strcmp(e->d_name + len - 5, ".yaml") != 0) continue;
        char args[1024];
        snprintf(args, sizeof args, "check '%s/%s'", dir, e->d_name);
        int st = tu_run_drape(args, out, CAP, err, CAP);
        ck_assert_msg(st == 0, "drape %s: status %d, stderr: %s", args, st, err);
        ck_assert_msg(strstr(out, "valid") != NULL, "%s: no summary", args);
        n++;
    }
    closedir(d);
    ck_assert_msg(n > 0, "no .yaml files in %s", dir);
}

START_TEST(test_shipped_files_valid)
{
    check_dir_valid("../fabrics");
    check_dir_valid("../scenes");
}
END_TEST

/* `drape check` reports a scene's damping, and with shear damping the
 * damping ratio beta omega / 2 at the shear term's frequency bound that it
 * prints on the line above (thirteenth session). */
START_TEST(test_check_damping)
{
    char scene[8192], fabric[4096], cwd[2048];
    ck_assert_ptr_nonnull(getcwd(cwd, sizeof cwd));
    snprintf(fabric, sizeof fabric, "%s/%s", cwd, tu_src("fabrics/cotton-breen.yaml"));
    snprintf(scene, sizeof scene,
             "scene: cusick\nfabric: %s\nspecimen: {shape: circle, diameter: 30 cm}\n"
             "support: {diameter: 18 cm}\nspacing: 3 cm\n"
             "damping: {air: 2 1/s, shear: 0.5 ms}\nend: {t_max: 1 s}\n",
             fabric);
    char args[4200];
    snprintf(args, sizeof args, "check '%s'", tu_write_file("damped.yaml", scene));
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert_msg(strstr(out, "damping              air 2 1/s, edge 0 N.s/m, shear 0.0005 s"),
                  "%s", out);
    const char *sh = strstr(out, "    shear    "), *sd = strstr(out, "    shear damping ");
    ck_assert_msg(sh && sd && sd > sh, "%s", out);
    double w = strtod(sh + 13, NULL), ratio = strtod(sd + 18, NULL);
    ck_assert_msg(w > 0 && fabs(ratio - 0.5 * 5e-4 * w) <= 1e-2 * ratio, "omega %g, ratio %g", w,
                  ratio);
    /* a scene without it: the fabric's (cotton-breen gives none: 0.5 ms) */
    snprintf(scene, sizeof scene,
             "scene: cusick\nfabric: %s\nspacing: 3 cm\nend: {t_max: 1 s}\n", fabric);
    snprintf(args, sizeof args, "check '%s'", tu_write_file("default.yaml", scene));
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert_msg(strstr(out, "shear 0.0005 s") && strstr(out, "shear damping"), "%s", out);
    /* switched off: no damping ratio line */
    snprintf(scene, sizeof scene,
             "scene: cusick\nfabric: %s\nspacing: 3 cm\ndamping: {shear: 0 s}\n"
             "end: {t_max: 1 s}\n", fabric);
    snprintf(args, sizeof args, "check '%s'", tu_write_file("undamped.yaml", scene));
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert_msg(strstr(out, "shear 0 s") && !strstr(out, "shear damping"), "%s", out);
}
END_TEST

/* The shared examples are the input contract: accepted unchanged, and the
 * copies in fabrics/ and scenes/ are identical to them, but for the
 * optional `specimens:` line the shipped Cusick and table scenes add
 * (issue 15: a drape test of repeated specimens; docs/ensemble.md) and the
 * term `bias` the shipped scenes add to their lists (issue 18: bending in
 * every direction where the fabric gives a bias curve; docs/model.md). */
START_TEST(test_shared_examples)
{
    const char *shared = getenv("DRAPE_SHARED");
    if (!shared) shared = "../../shared/examples";
    DIR *d = opendir(shared);
    if (!d) {
        fprintf(stderr, "note: %s not found; shared examples not checked\n", shared);
        return;
    }
    closedir(d);
    char args[1024];
    snprintf(args, sizeof args, "check %s/fabrics/*.yaml %s/scenes/*.yaml", shared, shared);
    int st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 0, "status %d: %s", st, err);
    const char *names[] = {"fabrics/cotton-breen.yaml", "scenes/cusick.yaml", "scenes/hang.yaml",
                           "scenes/table.yaml", "scenes/cantilever.yaml"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        snprintf(args, sizeof args,
                 "grep -v '^specimens: ' ../%s | sed 's/, bias\\]/]/' | cmp -s %s/%s -",
                 names[i], shared, names[i]);
        ck_assert_msg(system(args) == 0, "%s differs from the shared example", names[i]);
    }
}
END_TEST

/* tests/bad: each file is rejected with a non-zero status and a GNU-style
 * message "drape: FILE:LINE:COL: KEY: ...".  A file's first line may say
 * what is expected: "# expect LINE KEY: why" (KEY may be empty); then the
 * message must name that line and key. */

START_TEST(test_bad_corpus)
{
    DIR *d = opendir("bad");
    ck_assert_msg(d != NULL, "tests/bad missing");
    struct dirent *e;
    int n = 0, n_expect = 0;
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        if (len < 6 || strcmp(e->d_name + len - 5, ".yaml") != 0) continue;
        char args[1024], path[600], key[256], pat[300];
        int line;
        snprintf(path, sizeof path, "bad/%s", e->d_name);
        tu_bad_header(path, &line, key, sizeof key);
        snprintf(args, sizeof args, "check '%s'", path);
        int st = tu_run_drape(args, out, CAP, err, CAP);
        ck_assert_msg(st != 0 && st != 2 && st < 64,
                      "%s: status %d (want 1, 3 or 5), stderr: %s", e->d_name, st, err);
        ck_assert_msg(strstr(out, "valid") == NULL, "%s: printed a summary", e->d_name);
        ck_assert_msg(strncmp(err, "drape: ", 7) == 0, "%s: %s", e->d_name, err);
        /* the message names a .yaml file (the bad file, or the fabric it loads) */
        ck_assert_msg(strstr(err, ".yaml") != NULL, "%s: no file named in: %s", e->d_name, err);
        if (line > 0) {
            snprintf(pat, sizeof pat, ".yaml:%d:", line);
            ck_assert_msg(strstr(err, pat) != NULL, "%s: want line %d in: %s", e->d_name,
                          line, err);
            n_expect++;
        }
        if (key[0]) {
            snprintf(pat, sizeof pat, " %s: ", key);
            ck_assert_msg(strstr(err, pat) != NULL, "%s: want key `%s` in: %s", e->d_name,
                          key, err);
        }
        n++;
    }
    closedir(d);
    ck_assert_msg(n >= 30, "only %d bad inputs", n);
    ck_assert_msg(n_expect >= n - 2, "only %d of %d bad inputs say what they expect", n_expect, n);
}
END_TEST

/* The summary for a person (--format text; the default when stdout is a
 * terminal): its numbers are the JSON result's (the DC to three digits,
 * its interval, each histogram bar's count and share, the modal count),
 * and on a pipe the default stays JSON.  The terminal is a pseudo-terminal
 * made by script(1). */
START_TEST(test_format_text)
{
    const char *args = "run -q ../scenes/cusick.yaml --spacing 3cm --specimens 3 -j 1";
    char cmd[4096];
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    json_object *o = json_tokener_parse(out), *v, *h;
    ck_assert_msg(o != NULL, "default on a pipe is not JSON: %s", out);
    ck_assert(json_object_object_get_ex(o, "dc", &v));
    double dc = json_object_get_double(v);
    ck_assert(json_object_object_get_ex(o, "dc_ci95", &v));
    double ci = json_object_get_double(v);
    ck_assert(json_object_object_get_ex(o, "nodes_hist", &h));
    snprintf(cmd, sizeof cmd, "%s --format text", args);
    ck_assert_int_eq(tu_run_drape(cmd, out, CAP, err, CAP), 0);
    char want[128];
    snprintf(want, sizeof want, "drape coefficient  %.3f +- %.3f (95 %% interval of the mean of 3 "
             "specimens)", dc, ci);
    ck_assert_msg(strstr(out, want) && strstr(out, "cotton-breen on the cusick scene, spacing 3 cm"),
                  "%s\nwanted: %s", out, want);
    json_object_object_foreach(h, k, c) {
        int n = json_object_get_int(c);
        snprintf(want, sizeof want, "# %d (%.0f %%)\n", n, 100.0 * n / 3);
        char *line = strstr(out, want);
        ck_assert_msg(line != NULL, "no bar for %s nodes: %s", k, out);
        while (line > out && line[-1] != '\n') line--;
        ck_assert_int_eq(atoi(line), atoi(k));
    }
    ck_assert_msg(strstr(out, "status             equilibrium") && strstr(out, "CPU "), "%s", out);
    json_object_put(o);
    /* on a terminal: the summary by default, JSON when asked for */
    ck_assert_int_eq(tu_run_drape_pty(args, out, CAP), 0);
    ck_assert_msg(strstr(out, "drape coefficient") && !strchr(out, '{'), "%s", out);
    snprintf(cmd, sizeof cmd, "%s --format json", args);
    ck_assert_int_eq(tu_run_drape_pty(cmd, out, CAP), 0);
    ck_assert_msg(strstr(out, "{ \"fabric\"") && !strstr(out, "drape coefficient"), "%s", out);
    ck_assert_int_eq(tu_run_drape("run --format xml", out, CAP, err, CAP), 2);
    ck_assert_msg(strstr(err, "json, csv or text"), "%s", err);
}
END_TEST

Suite *cli_suite(void)
{
    Suite *s = suite_create("cli");
    TCase *tc = tcase_create("cli");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_help_version);
    tcase_add_test(tc, test_format_text);
    tcase_add_test(tc, test_usage_errors);
    tcase_add_test(tc, test_empty_dir_options);
    tcase_add_test(tc, test_data_dirs);
    tcase_add_test(tc, test_shipped_files_valid);
    tcase_add_test(tc, test_check_damping);
    tcase_add_test(tc, test_shared_examples);
    tcase_add_test(tc, test_bad_corpus);
    tcase_add_test(tc, test_ambiguous_options);
    suite_add_tcase(s, tc);
    return s;
}
