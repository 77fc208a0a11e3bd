/* check_import.c: `drape import arcsim` and `drape import kes` through the
 * binary.  Expected values are independent of the importer: the shipped
 * fabrics that were converted by hand (fabrics/denim-wang.yaml,
 * cotton-poly-wang.yaml from the same ARCSim numbers; cotton-breen-kes.yaml
 * from the same KES values), and hand computations of M(K) = K ke(K) / 4
 * (docs/fabric-library.md) and of the KES construction's straight parts
 * M = HB + B K, F = HG + G gamma (docs/fabrics.md). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "drape/error.h"
#include "drape/fabric.h"
#include "drape/fit.h"
#include "testutil.h"

#define CAP 65536
static char out[CAP], err[CAP];

#define GF 9.80665e-3 /* N per gram-force (1 gf = 1 g x standard gravity) */

static const char *subdir(const char *name)
{
    static char p[4][512];
    static int slot;
    char *d = p[slot++ % 4];
    snprintf(d, 512, "%s/%s", tu_scratch_dir(), name);
    mkdir(d, 0700);
    return d;
}

static int exists(const char *dir, const char *file)
{
    char p[1024];
    snprintf(p, sizeof p, "%s/%s", dir, file);
    return access(p, F_OK) == 0;
}

static void load(const char *path, drape_fabric *f)
{
    drape_error e;
    drape_error_clear(&e);
    int rc = drape_fabric_load(path, f, &e, NULL, NULL);
    char buf[2048];
    ck_assert_msg(rc == 0, "%s does not load: %s", path, drape_error_format(&e, buf, sizeof buf));
}

static void load_in(const char *dir, const char *file, drape_fabric *f)
{
    char p[1024];
    snprintf(p, sizeof p, "%s/%s", dir, file);
    load(p, f);
}

/* |a - b| <= rtol * max(|a|, |b|) + tiny, printed on failure */
static void close_to(double a, double b, double rtol, const char *what, double at)
{
    double s = fabs(a) > fabs(b) ? fabs(a) : fabs(b);
    ck_assert_msg(fabs(a - b) <= rtol * s + 1e-300, "%s at %g: %.17g, expected %.17g", what, at,
                  a, b);
}

/* Loaded SI values of two fabrics agree at many points. */
static void same_fabric(const drape_fabric *a, const drape_fabric *b, double rtol)
{
    close_to(a->weight, b->weight, rtol, "weight", 0);
    close_to(a->k[DRAPE_WARP], b->k[DRAPE_WARP], rtol, "k_warp", 0);
    close_to(a->k[DRAPE_WEFT], b->k[DRAPE_WEFT], rtol, "k_weft", 0);
    static const double K[] = {1e-4, 0.3, 5, 9.9999, 10, 10.0001, 14, 19.5, 20, 25, 30,
                               33.3, 39.99, 40, 41, 75, 250, 1000, -3, -37};
    for (int d = 0; d < 2; d++)
        for (size_t i = 0; i < sizeof K / sizeof K[0]; i++) {
            close_to(drape_fit_value(&a->bend[d], K[i]), drape_fit_value(&b->bend[d], K[i]),
                     rtol, d ? "M_warp" : "M_weft", K[i]);
            close_to(drape_fit_integral(&a->bend[d], K[i]),
                     drape_fit_integral(&b->bend[d], K[i]), rtol, "bending energy", K[i]);
            if (fabs(K[i] - 10 * round(K[i] / 10)) > 1e-3) /* slopes off the knots */
                close_to(drape_fit_slope(&a->bend[d], K[i]), drape_fit_slope(&b->bend[d], K[i]),
                         1e-8, "dM/dK", K[i]);
        }
    static const double g[] = {1e-5, 0.004, 0.0087266, 0.01, 0.05, 0.0872665, 0.1, 0.3, 0.7, -0.2};
    for (int d = 0; d < 2; d++)
        for (size_t i = 0; i < sizeof g / sizeof g[0]; i++)
            close_to(drape_fit_value(&a->shear[d], g[i]), drape_fit_value(&b->shear[d], g[i]),
                     rtol, d ? "F_warp" : "F_weft", g[i]);
    for (size_t i = 0; i < sizeof g / sizeof g[0]; i++)
        close_to(drape_fit_value(&a->shear_mean, g[i]), drape_fit_value(&b->shear_mean, g[i]),
                 rtol, "F_mean", g[i]);
    for (int d = 0; d < 2; d++)
        close_to(drape_fabric_bending_rigidity(a, (drape_dir)d),
                 drape_fabric_bending_rigidity(b, (drape_dir)d), rtol, "B(0)", 0);
    close_to(drape_fabric_shear_rigidity(a), drape_fabric_shear_rigidity(b), rtol, "G(0)", 0);
    ck_assert_int_eq(a->has_bias, b->has_bias);
    for (size_t i = 0; a->has_bias && i < sizeof K / sizeof K[0]; i++)
        close_to(drape_fit_value(&a->bend_bias, K[i]), drape_fit_value(&b->bend_bias, K[i]), rtol,
                 "M_bias", K[i]);
}

/* ---- arcsim ------------------------------------------------------------------ */

START_TEST(test_arcsim_reproduces_shipped_wang)
{
    /* the importer's mapping is the hand conversion of the shipped files */
    static const char *const pairs[][3] = {
        {"data/denim-arcsim.json", "denim-arcsim.yaml", "../fabrics/denim-wang.yaml"},
        {"data/royal-target-arcsim.json", "royal-target-arcsim.yaml",
         "../fabrics/cotton-poly-wang.yaml"}};
    const char *dir = subdir("arcsim-wang");
    char args[1024];
    snprintf(args, sizeof args, "import arcsim %s %s --out-dir %s", pairs[0][0], pairs[1][0], dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    for (int i = 0; i < 2; i++) {
        ck_assert_msg(strstr(out, pairs[i][1]) != NULL, "stdout names %s: %s", pairs[i][1], out);
        drape_fabric a, b;
        load_in(dir, pairs[i][1], &a);
        load(pairs[i][2], &b);
        /* coefficients are written with 12 digits, the shipped ones exactly */
        same_fabric(&a, &b, 1e-10);
        ck_assert_int_eq(a.from_kes, 0);
    }
    /* the softening intervals are named in the header, as in the shipped file */
    char p[1024];
    snprintf(p, sizeof p, "%s/denim-arcsim.yaml", dir);
    FILE *f = fopen(p, "r");
    ck_assert_ptr_nonnull(f);
    size_t n = fread(out, 1, CAP - 1, f);
    out[n] = 0;
    fclose(f);
    ck_assert_ptr_nonnull(strstr(out, "warp: dM/dK < 0 somewhere on [30, 40] 1/m"));
    ck_assert_ptr_nonnull(strstr(out, "weft: dM/dK < 0 somewhere on [30, 40] 1/m"));
}
END_TEST

START_TEST(test_arcsim_by_hand)
{
    /* M(K) = K ke(K) / 4 with ke linear between K = 0,10,..,40 1/m and
     * constant beyond; comments are accepted, as by ARCSim's reader */
    const char *json = tu_write_file("hand.json",
        "/* a made-up material */\n"
        "{\n"
        "  \"density\": 0.2,   // kg/m^2\n"
        "  \"stretching\": [[100, 5, 300, 20], [1,1,1,1], [1,1,1,1], [1,1,1,1],\n"
        "                 [1,1,1,1], [1,1,1,1]],\n"
        "  \"bending\": [[4e-5, 8e-5, 8e-5, 8e-5, 4e-5],\n"
        "              [1e-5, 1e-5, 1e-5, 1e-5, 1e-5],\n"
        "              [2e-5, 2e-5, 2e-5, 2e-5, 2e-5]],\n"
        "  \"comment\": \"unknown keys are ignored, as by ARCSim\"\n"
        "}\n// end\n");
    const char *dir = subdir("arcsim-hand");
    char args[1024];
    snprintf(args, sizeof args, "import arcsim %s --out-dir %s --name hand-made", json, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    drape_fabric f;
    load_in(dir, "hand-made.yaml", &f);
    ck_assert_str_eq(f.name, "hand-made");
    ck_assert_close_rel(f.weight, 0.2, 1e-15);
    ck_assert_close_rel(f.k[DRAPE_WEFT], 200.0, 1e-15); /* 2 d0, u = weft */
    ck_assert_close_rel(f.k[DRAPE_WARP], 600.0, 1e-15); /* 2 d2, v = warp */
    for (int d = 0; d < 2; d++) ck_assert_close_rel(drape_fit_value(&f.shear[d], 0.1), 2.0, 1e-14);
    const drape_fit *w = &f.bend[DRAPE_WARP], *t = &f.bend[DRAPE_WEFT];
    ck_assert_close_rel(drape_fit_value(w, 5), 5 * 6e-5 / 4, 1e-12);   /* ke(5) = 6e-5 */
    ck_assert_close_rel(drape_fit_value(w, 15), 15 * 8e-5 / 4, 1e-12);
    ck_assert_close_rel(drape_fit_value(w, 35), 35 * 6e-5 / 4, 1e-12);  /* ke(35) = 6e-5 */
    ck_assert_close_rel(drape_fit_value(w, 50), 50 * 4e-5 / 4, 1e-12);  /* clamped */
    ck_assert_close_rel(drape_fit_value(w, -5), -5 * 6e-5 / 4, 1e-12);  /* odd */
    ck_assert_close_rel(drape_fabric_bending_rigidity(&f, DRAPE_WARP), 4e-5 / 4, 1e-12);
    ck_assert_close_rel(drape_fit_value(t, 123), 123 * 2e-5 / 4, 1e-12);
    /* dM/dK = (ke + K ke') / 4 < 0 only on [30, 40] */
    FILE *fp;
    char p[1024];
    snprintf(p, sizeof p, "%s/hand-made.yaml", dir);
    ck_assert_ptr_nonnull(fp = fopen(p, "r"));
    size_t n = fread(out, 1, CAP - 1, fp);
    out[n] = 0;
    fclose(fp);
    ck_assert_ptr_nonnull(strstr(out, "warp: dM/dK < 0 somewhere on [30, 40] 1/m"));
    ck_assert_ptr_null(strstr(out, "[0, 10] 1/m"));
    ck_assert_ptr_null(strstr(out, "weft: dM/dK"));
    /* row 1 (1e-5) is softer than (B_warp + B_weft) / 4 = (4e-5 + 2e-5) / 16: the
     * model's bias term cannot represent it, so it is left out, and said so */
    ck_assert_int_eq(f.has_bias, 0);
    ck_assert_ptr_nonnull(strstr(out, "# bias: left out"));
    /* a stiffer row 1 is written as bending.bias: M = K ke / 4 */
    json = tu_write_file("hand2.json",
        "{\"density\": 0.2, \"stretching\": [[100, 5, 300, 20], [1,1,1,1], [1,1,1,1],\n"
        " [1,1,1,1], [1,1,1,1], [1,1,1,1]],\n"
        " \"bending\": [[4e-5, 8e-5, 8e-5, 8e-5, 4e-5], [3e-5, 5e-5, 5e-5, 5e-5, 5e-5],\n"
        "              [2e-5, 2e-5, 2e-5, 2e-5, 2e-5]]}\n");
    snprintf(args, sizeof args, "import arcsim %s --out-dir %s --name hand-bias", json, dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    load_in(dir, "hand-bias.yaml", &f);
    ck_assert_int_eq(f.has_bias, 1);
    ck_assert_close_rel(drape_fit_value(&f.bend_bias, 5), 5 * 4e-5 / 4, 1e-12); /* ke(5) = 4e-5 */
    ck_assert_close_rel(drape_fit_value(&f.bend_bias, 60), 60 * 5e-5 / 4, 1e-12);
}
END_TEST

START_TEST(test_arcsim_errors)
{
    const char *dir = subdir("arcsim-bad");
    char args[2048];
    static const struct {
        const char *text, *expect;
    } cases[] = {
        {"{\n  \"density\": 0.1,\n  \"stretching\": [1,}\n", ":3:"},
        {"{\"stretching\": [], \"bending\": []}", "density: missing key"},
        {"{\"density\": \"heavy\"}", "density: expected a number"},
        {"{\"density\": -0.1}", "density: must be a positive"},
        {"[1, 2]", "expected a JSON object"},
        {"{\"density\": 0.1, \"stretching\": [[1,2,3,4]]}", "stretching: expected an array of 6 rows"},
        {"{\"density\": 0.1, \"stretching\": [[1,2,3,4],[1,2,3,4],[1,2,3,4],[1,2,3,4],"
         "[1,2,3,4],[1,2,3,4]], \"bending\": [[1,1,1,1,1],[1,1,1,\"x\",1],[1,1,1,1,1]]}",
         "bending[1][3]: expected a number, got a string"},
        {"{\"density\": 0.1, \"stretching\": [[1,2,0,4],[1,2,3,4],[1,2,3,4],[1,2,3,4],"
         "[1,2,3,4],[1,2,3,4]], \"bending\": [[1,1,1,1,1],[1,1,1,1,1],[1,1,1,1,1]]}",
         "stretching[0][2]: k_v/2 (tension along v) must be positive"},
        {"{\"density\": 0.1} {}", "text after the end of the JSON object"},
        /* json-c clamps it to 2^64 - 1: not the number in the file */
        {"{\"density\": 99999999999999999999999}", "density: this integer is out of range"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *path = tu_write_file("bad.json", cases[i].text);
        snprintf(args, sizeof args, "import arcsim %s --out-dir %s", path, dir);
        int rc = tu_run_drape(args, out, CAP, err, CAP);
        ck_assert_msg(rc == 1, "case %zu: exit %d, stderr %s", i, rc, err);
        ck_assert_msg(strstr(err, "bad.json") && strstr(err, cases[i].expect),
                      "case %zu: expected `%s` in: %s", i, cases[i].expect, err);
        ck_assert(!exists(dir, "bad.yaml"));
    }
    /* all or nothing: a good and a bad file -> nothing written */
    const char *bad = tu_write_file("bad.json", "{}");
    snprintf(args, sizeof args, "import arcsim data/denim-arcsim.json %s --out-dir %s", bad, dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 1);
    ck_assert_ptr_nonnull(strstr(err, "no file written"));
    ck_assert(!exists(dir, "denim-arcsim.yaml"));
    /* an existing file is kept unless --force */
    snprintf(args, sizeof args, "import arcsim data/denim-arcsim.json --out-dir %s", dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 3);
    ck_assert_ptr_nonnull(strstr(err, "--force"));
    snprintf(args, sizeof args, "import arcsim data/denim-arcsim.json --out-dir %s --force", dir);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err, CAP), 0);
    /* --force replaces files only, and checks every output before it
     * writes any: a directory where one output goes -> nothing written */
    char sub[1200];
    snprintf(sub, sizeof sub, "%s/royal-target-arcsim.yaml", dir);
    ck_assert_int_eq(mkdir(sub, 0755), 0);
    snprintf(args, sizeof args, "import arcsim data/denim-arcsim.json data/royal-target-arcsim.json "
             "--out-dir %s --force", dir);
    int st = tu_run_drape(args, out, CAP, err, CAP);
    ck_assert_msg(st == 3 && strstr(err, "not a regular file") && strstr(err, "no file written") &&
                  out[0] == 0, "exit %d, %s", st, err);
    ck_assert_int_eq(rmdir(sub), 0);
    /* the extension goes in any case: X.JSON makes the fabric X */
    {
        char bytes[16384];
        FILE *fp = fopen("data/denim-arcsim.json", "rb");
        ck_assert_ptr_nonnull(fp);
        size_t n = fread(bytes, 1, sizeof bytes, fp);
        fclose(fp);
        snprintf(args, sizeof args, "import arcsim %s --out-dir %s",
                 tu_write_bytes("UPPER.JSON", bytes, n), dir);
        st = tu_run_drape(args, out, CAP, err, CAP);
        ck_assert_msg(st == 0 && strstr(out, "/UPPER.yaml"), "exit %d, %s %s", st, out, err);
    }
    /* a file name that is not UTF-8 still makes a valid fabric file */
    {
        char bytes[16384];
        FILE *fp = fopen("data/denim-arcsim.json", "rb");
        ck_assert_ptr_nonnull(fp);
        size_t n = fread(bytes, 1, sizeof bytes, fp);
        fclose(fp);
        const char *lat = tu_write_bytes("caf\xe9.json", bytes, n);
        snprintf(args, sizeof args, "import arcsim '%s' --out-dir %s", lat, dir);
        st = tu_run_drape(args, out, CAP, err, CAP);
        ck_assert_msg(st == 0, "exit %d, %s", st, err);
        snprintf(args, sizeof args, "check %s/caf-.yaml", dir);
        st = tu_run_drape(args, out, CAP, err, CAP);
        ck_assert_msg(st == 0 && strstr(out, "valid fabric"), "exit %d, %s", st, err);
    }
    /* command line */
    ck_assert_int_eq(tu_run_drape("import", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("import xml data/kes.csv", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("import arcsim data/denim-arcsim.json data/royal-target-arcsim.json --name x",
                                  out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("import arcsim data/denim-arcsim.json --name a/b", out, CAP, err, CAP), 2);
    ck_assert_int_eq(tu_run_drape("import arcsim data/denim-arcsim.json --out-dir /nonexistent/dir",
                                  out, CAP, err, CAP), 3);
}
END_TEST

/* The lines of an error's file:line:column count LF, CR LF and CR alone
 * (old Mac files) each as one break: the same file in the three forms
 * gives the same place, counted by hand (a CR LF file does not count
 * twice, a CR file does not stay on line 1, a // comment does not run on
 * to the end of a CR file). */
START_TEST(test_arcsim_line_endings)
{
    static const char *const eol[3] = {"\n", "\r\n", "\r"};
    static const char *const syntax[] = {"{", "  \"density\": 0.1,", "  \"stretching\": [",
                                         "    [1, 2, 3, 4],", "    [1, 2, }", NULL};
    static const char *const after[] = {"{\"density\": 0.1}", "", "  x", NULL};
    /* a // comment ends at the line's end in all three forms (json-c ends
     * it at LF only: with CR alone it ran to the end of the file) */
    static const char *const comment[] = {"{", "  // ARCSim allows comments", "  \"density\": 0.1,",
                                          "  \"stretching\": [", "    [1, 2, 3, 4],",
                                          "    [1, 2, }", NULL};
    static const struct {
        const char *const *lines, *expect;
    } cases[] = {
        {syntax, "le.json:5:12: not valid JSON"}, /* the '}' in place of a number */
        {after, "le.json:3:3: text after the end of the JSON object"},
        {comment, "le.json:6:12: not valid JSON"},
    };
    const char *dir = subdir("arcsim-eol");
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++)
        for (int k = 0; k < 3; k++) {
            char text[512] = "", args[1024];
            for (int i = 0; cases[c].lines[i]; i++) {
                strcat(text, cases[c].lines[i]);
                strcat(text, eol[k]);
            }
            snprintf(args, sizeof args, "import arcsim %s --out-dir %s",
                     tu_write_file("le.json", text), dir);
            int rc = tu_run_drape(args, out, CAP, err, CAP);
            ck_assert_msg(rc == 1 && strstr(err, cases[c].expect),
                          "case %zu, line ending %d: exit %d, expected `%s` in: %s", c, k, rc,
                          cases[c].expect, err);
        }
}
END_TEST

/* Numbers outside the normal doubles are refused on their own text, with
 * file:line:column and key (json-c reads 1e400 as inf, 1e-400 as 0 and
 * keeps 1e-310, a positive bending stiffness that passed every check);
 * places counted by hand in the template below.  An exact zero with a
 * large exponent and the smallest normal double are numbers like others. */
START_TEST(test_arcsim_number_range)
{
    static const char tmpl[] = "{%s"
                               "  \"density\": %s,%s"
                               "  \"stretching\": [[1,%s,3,4],[1,2,3,4],[1,2,3,4],%s"
                               "    [1,2,3,4],[1,2,%s,4],[1,2,3,4]],%s"
                               "  \"bending\": [[1,1,1,1,1],[1,1,1,1,1],%s"
                               "    [1,1,%s,1,1]]%s"
                               "}%s";
    static const struct {
        const char *density, *coupling, *s42, *b22, *eol, *expect;
    } cases[] = {
        {"1e400", "2", "3", "1", "\n", "nr.json:2:14: density: number out of range: \"1e400\""},
        {"0.1", "2", "1e-400", "1", "\n", "nr.json:4:20: stretching[4][2]: number out of range"},
        {"0.1", "2", "-1e999", "1", "\r\n", "nr.json:4:20: stretching[4][2]: number out of range"},
        {"0.1", "2", "3", "1e-310", "\n", "nr.json:6:10: bending[2][2]: number out of range"},
        {"0.1", "2", "3", "1e-310", "\r", "nr.json:6:10: bending[2][2]: number out of range"},
        {"0.1", "-4.9e-324", "3", "1", "\n", "nr.json:3:21: stretching[0][1]: number out of range"},
        /* in range: written */
        {"0.1", "0e-400", "2.2250738585072014e-308", "1", "\n", NULL},
        {"0.1", "-0", "1e308", "1", "\r", NULL},
    };
    const char *dir = subdir("arcsim-range");
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char text[1024], args[1024];
        const char *e = cases[i].eol;
        snprintf(text, sizeof text, tmpl, e, cases[i].density, e, cases[i].coupling, e,
                 cases[i].s42, e, e, cases[i].b22, e, e);
        snprintf(args, sizeof args, "import arcsim %s --out-dir %s --force",
                 tu_write_file("nr.json", text), dir);
        int rc = tu_run_drape(args, out, CAP, err, CAP);
        if (cases[i].expect) {
            ck_assert_msg(rc == 1 && strstr(err, cases[i].expect), "case %zu: exit %d, expected `%s` in: %s",
                          i, rc, cases[i].expect, err);
            ck_assert_msg(!exists(dir, "nr.yaml"), "case %zu: a file was written", i);
        } else {
            ck_assert_msg(rc == 0 && exists(dir, "nr.yaml"), "case %zu: exit %d, %s", i, rc, err);
            char written[1024];
            snprintf(written, sizeof written, "%s/nr.yaml", dir);
            ck_assert_int_eq(unlink(written), 0);
        }
    }
}
END_TEST

/* ---- kes --------------------------------------------------------------------- */

START_TEST(test_kes_table)
{
    const char *dir = subdir("kes");
    char args[1024];
    snprintf(args, sizeof args, "import kes data/kes.csv --out-dir %s", dir);
    ck_assert_msg(tu_run_drape(args, out, CAP, err, CAP) == 0, "%s", err);
    ck_assert_ptr_nonnull(strstr(out, "cotton-breen-csv.yaml"));
    ck_assert_ptr_nonnull(strstr(out, "synthetic-twill.yaml"));

    /* row 1 holds the values of the shipped cotton-breen-kes (G in deg) */
    drape_fabric a, b;
    load_in(dir, "cotton-breen-csv.yaml", &a);
    load("../fabrics/cotton-breen-kes.yaml", &b);
    ck_assert_int_eq(a.from_kes, 1);
    same_fabric(&a, &b, 1e-9); /* G was rounded to 10 digits in the table */
    /* and by hand: the straight parts M = HB + B K, F = HG + G gamma */
    ck_assert_close_rel(a.weight, 0.2, 1e-15);
    ck_assert_close_rel(a.k[DRAPE_WARP], 10000.0, 1e-15);
    ck_assert_close_rel(drape_fit_value(&a.bend[DRAPE_WARP], 200.0), /* 2 1/cm */
                        (0.46236366 / 2 + 0.20984848 * 2) * GF, 1e-12);
    ck_assert_close_rel(drape_fit_value(&a.bend[DRAPE_WEFT], 150.0),
                        (0.151287128 / 2 + 0.12871287 * 1.5) * GF, 1e-12);
    const double gpd = 180.0 / 3.14159265358979323846; /* deg per rad */
    ck_assert_close_rel(drape_fit_value(&a.shear[DRAPE_WARP], 0.1),
                        (2.7427064 / 2 + 1.8565802037 * gpd * 0.1) * GF / 0.01, 1e-12);

    /* row 2: no 2HB in warp (M = B K), 2HG5 in warp shear, quoted source */
    drape_fabric s;
    load_in(dir, "synthetic-twill.yaml", &s);
    ck_assert_close_rel(s.weight, 0.1505, 1e-15);
    ck_assert_close_rel(s.k[DRAPE_WARP], 800.0, 1e-15);
    ck_assert_close_rel(s.k[DRAPE_WEFT], 1200.0, 1e-15);
    ck_assert_close_rel(drape_fit_value(&s.bend[DRAPE_WARP], 7.0), 0.05 * 0.07 * GF, 1e-12);
    ck_assert_close_rel(drape_fit_value(&s.bend[DRAPE_WARP], 100.0), 0.05 * 1.0 * GF, 1e-12);
    ck_assert_close_rel(drape_fit_value(&s.bend[DRAPE_WEFT], 100.0), (0.01 + 0.08) * GF, 1e-12);
    /* beyond 5 deg: F = G gamma + HG5 */
    ck_assert_close_rel(drape_fit_value(&s.shear[DRAPE_WARP], 10.0 / gpd),
                        (0.6 * 10 + 2.5 / 2) * GF / 0.01, 1e-12);
    ck_assert_ptr_nonnull(strstr(s.source, "a \"quoted\" field\nwith a line break"));
    ck_assert_ptr_nonnull(strstr(s.source, "kes.csv:4"));
}
END_TEST

START_TEST(test_kes_errors)
{
    const char *dir = subdir("kes-bad");
    char args[2048];
    static const char hdr[] = "name,weight_g_m2,k_warp_N_m,k_weft_N_m,B_warp,B_weft,G_warp,G_weft\n";
    static const struct {
        const char *rows, *expect;
        int header;
    } cases[] = {
        {"ok,100,1,1,0.1,0.1,1,1\nbad,100,1,1,0.1,x,1,1\n", "t.csv:3:17: B_weft: expected a number", 1},
        {"ok,100,1,1,0.1,0.1,-1,1\n", "t.csv:2:20: G_warp: must be positive", 1},
        {"ok,100,1,1,0.1,,1,1\n", "t.csv:2:16: B_weft: empty; this column is required", 1},
        {"ok,100,1,1,0.1,0.1,1\n", "t.csv:2: 7 fields, the header has 8", 1},
        {"ok,100,1,1,0.1,0.1,1,1\nok,100,1,1,0.1,0.1,1,1\n", "t.csv:3: name: fabric `ok` is also made from", 1},
        {"a/b,100,1,1,0.1,0.1,1,1\n", "t.csv:2:1: name: \"a/b\" is not usable", 1},
        {"ok,1e999,1,1,0.1,0.1,1,1\n", "weight_g_m2: number out of range", 1},
        {"ok,100,1,1,0.1,0.1,1e-400,1\n", "G_warp: number out of range", 1},
        {"ok,0x10,1,1,0.1,0.1,1,1\n", "weight_g_m2: expected a number in g/m^2", 1},
        {"name,weight_g_m2,k_warp_N_m,k_weft_N_m,B_warp,B_weft,G_warp\n", "t.csv:1: G_weft: missing column", 0},
        {"name,weight_g_m2,k_warp_N_m,k_weft_N_m,B_warp,B_weft,G_warp,G_weft,Bwarp\n",
         "t.csv:1:68: Bwarp: unknown column", 0},
        {"name,weight_g_m2 (kg/m^2),k_warp_N_m,k_weft_N_m,B_warp,B_weft,G_warp,G_weft\n",
         "weight_g_m2: unit `kg/m^2`: this column is in g/m^2", 0},
        {"name,weight_g_m2,k_warp_N_m,k_weft_N_m,B_warp,B_weft,G_warp,G_weft,2HG_warp,2HG5_warp\n"
         "ok,100,1,1,0.1,0.1,1,1,2,1\n", "2HG5_warp: 2HG5 (hysteresis at 5 deg) is smaller", 0},
        {"\"ok,100\n", "t.csv:2:1: unterminated quoted field", 1},
        {"", "t.csv: no rows after the header", 1},
        {"name,weight_g_m2,k_warp_N_m,k_weft_N_m,B_warp,B_weft,G_warp,G_weft,description\n"
         "ok,100,1,1,0.1,0.1,1,1,caf\xe9\n", "t.csv:2:24: description: not valid UTF-8", 0},
        /* a row of empty cells is skipped as a blank line, the next is read */
        {",,,,,,,\nok,100,1,1,0.1,x,1,1\n", "t.csv:3:16: B_weft: expected a number", 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char text[1024];
        snprintf(text, sizeof text, "%s%s", cases[i].header ? hdr : "", cases[i].rows);
        const char *path = tu_write_file("t.csv", text);
        snprintf(args, sizeof args, "import kes %s --out-dir %s", path, dir);
        int rc = tu_run_drape(args, out, CAP, err, CAP);
        ck_assert_msg(rc == 1, "case %zu: exit %d, stderr %s", i, rc, err);
        ck_assert_msg(strstr(err, cases[i].expect) != NULL, "case %zu: expected `%s` in: %s", i,
                      cases[i].expect, err);
        ck_assert_msg(!exists(dir, "ok.yaml"), "case %zu: a file was written", i);
    }
    ck_assert_int_eq(tu_run_drape("import kes data/kes.csv data/kes.csv", out, CAP, err, CAP), 2);
}
END_TEST

/* A KES table saved with LF, CR LF or CR alone (old Mac Excel's CSV) is
 * the same table: an error's line counts each break once, inside a quoted
 * field too (lines counted by hand), and the good table imports. */
START_TEST(test_kes_line_endings)
{
    static const char *const eol[3] = {"\n", "\r\n", "\r"};
    static const char hdr[] = "name,weight_g_m2,k_warp_N_m,k_weft_N_m,B_warp,B_weft,G_warp,G_weft,"
                              "description";
    const char *dir = subdir("kes-eol");
    char text[1024], args[1024], path[1024];
    for (int k = 0; k < 3; k++) {
        const char *e = eol[k];
        snprintf(text, sizeof text, "%s%sok,100,1,1,0.1,0.1,1,1,\"line one%sline two\"%s"
                 "bad,100,1,1,0.1,x,1,1,%s", hdr, e, e, e, e);
        snprintf(args, sizeof args, "import kes %s --out-dir %s", tu_write_file("t.csv", text), dir);
        int rc = tu_run_drape(args, out, CAP, err, CAP);
        ck_assert_msg(rc == 1 && strstr(err, "t.csv:4:17: B_weft: expected a number"),
                      "line ending %d: exit %d, %s", k, rc, err);
        snprintf(text, sizeof text, "%s%sok,150,1,1,0.1,0.1,1,1,\"line one%sline two\"%s", hdr, e,
                 e, e);
        snprintf(args, sizeof args, "import kes %s --out-dir %s --force",
                 tu_write_file("t.csv", text), dir);
        rc = tu_run_drape(args, out, CAP, err, CAP);
        ck_assert_msg(rc == 0, "line ending %d: exit %d, %s", k, rc, err);
        drape_fabric f;
        snprintf(path, sizeof path, "%s/ok.yaml", dir);
        load(path, &f);
        ck_assert_close_rel(f.weight, 0.150, 1e-15); /* 150 g/m^2 */
        ck_assert_int_eq(unlink(path), 0);
    }
}
END_TEST

Suite *import_suite(void)
{
    Suite *s = suite_create("import");
    TCase *tc = tcase_create("import");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_arcsim_reproduces_shipped_wang);
    tcase_add_test(tc, test_arcsim_by_hand);
    tcase_add_test(tc, test_arcsim_errors);
    tcase_add_test(tc, test_arcsim_line_endings);
    tcase_add_test(tc, test_arcsim_number_range);
    tcase_add_test(tc, test_kes_table);
    tcase_add_test(tc, test_kes_errors);
    tcase_add_test(tc, test_kes_line_endings);
    suite_add_tcase(s, tc);
    return s;
}
