/* check_fabric.c: the fabric loader (fabric.h).  Expected SI values are
 * computed here by hand from the numbers printed in the YAML text and the
 * unit definitions (1 gf = 9.80665e-3 N, 1 deg = pi/180 rad); the KES-F
 * construction is checked against its defining equations
 * (docs/fabrics.md), not against the loader's own output. */
#include "drape/fabric.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "drape/alloc.h"
#include "testutil.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define GF 9.80665e-3 /* N */

/* Collects warnings. */
typedef struct warnings {
    int n;
    drape_error first;
} warnings;

static void collect(void *ctx, const drape_error *w)
{
    warnings *ws = ctx;
    if (ws->n++ == 0) ws->first = *w;
}

static double poly(const double *c, int n, double x)
{
    double y = 0;
    for (int k = n - 1; k >= 0; k--) y = y * x + c[k];
    return y;
}

START_TEST(test_cotton_breen)
{
    drape_fabric f;
    drape_error err;
    warnings ws = {0};
    drape_error_clear(&err);
    int rc = drape_fabric_load(tu_src("fabrics/cotton-breen.yaml"), &f, &err,
                               collect, &ws);
    ck_assert_msg(rc == 0, "%s:%d:%d: %s: %s", err.file, err.line, err.column,
                  err.key, err.msg);
    ck_assert_int_eq(ws.n, 0); /* C1 to 8 digits: no slope warning */
    ck_assert_str_eq(f.name, "cotton-breen");
    ck_assert_ptr_nonnull(strstr(f.description, "Breen"));
    ck_assert_str_eq(f.path, tu_src("fabrics/cotton-breen.yaml"));
    ck_assert_int_eq(f.from_kes, 0);
    ck_assert_close_rel(f.weight, 20e-6 / 1e-4, 1e-14); /* 20 mg/cm^2 */
    ck_assert_close_rel(f.k[DRAPE_WARP], 10000.0, 1e-15);
    ck_assert_close_rel(f.k[DRAPE_WEFT], 10000.0, 1e-15);

    /* warp bending: pieces at 0, 0.4, 2.52 1/cm = 0, 40, 252 1/m */
    const drape_fit *bw = &f.bend[DRAPE_WARP];
    ck_assert_int_eq(bw->n, 3);
    ck_assert_close_rel(bw->p[1].from, 40.0, 1e-14);
    ck_assert_close_rel(bw->p[2].from, 252.0, 1e-14);
    ck_assert(isinf(bw->p[2].to));
    /* K = 0.3 1/cm = 30 1/m, first piece, M in gf.cm/cm times GF */
    static const double w1[] = {0, 0.85984849, -0.71212123};
    static const double w2[] = {0.11090909, 0.30530303, -0.018939394};
    static const double w3[] = {0.23118183, 0.20984848};
    ck_assert_close_rel(drape_fit_value(bw, 30.0), poly(w1, 3, 0.3) * GF, 1e-12);
    ck_assert_close_rel(drape_fit_value(bw, 30.0),
                        (0.85984849 * 0.3 - 0.71212123 * 0.09) * 9.80665e-3,
                        1e-12);
    ck_assert_close_rel(drape_fit_value(bw, 100.0), poly(w2, 3, 1.0) * GF, 1e-12);
    ck_assert_close_rel(drape_fit_value(bw, 500.0), poly(w3, 2, 5.0) * GF, 1e-12);
    /* odd extension */
    ck_assert_close_rel(drape_fit_value(bw, -30.0), -poly(w1, 3, 0.3) * GF,
                        1e-12);
    /* weft: knot at 0.5 1/cm = 50 1/m */
    const drape_fit *bf = &f.bend[DRAPE_WEFT];
    static const double f1[] = {0, 0.43128713, -0.30257426};
    static const double f2[] = {0.075643564, 0.12871287};
    ck_assert_int_eq(bf->n, 2);
    ck_assert_close_rel(bf->p[1].from, 50.0, 1e-14);
    ck_assert_close_rel(drape_fit_value(bf, 20.0), poly(f1, 3, 0.2) * GF, 1e-12);
    ck_assert_close_rel(drape_fit_value(bf, 60.0), poly(f2, 2, 0.6) * GF, 1e-12);
    /* bending rigidity = initial slope: gf.cm/cm per 1/cm = GF * 1e-2 N.m */
    ck_assert_close_rel(drape_fabric_bending_rigidity(&f, DRAPE_WARP),
                        0.85984849 * GF * 1e-2, 1e-12);
    ck_assert_close_rel(drape_fabric_bending_rigidity(&f, DRAPE_WEFT),
                        0.43128713 * GF * 1e-2, 1e-12);

    /* shear: rad and gf/cm -> N/m is x 0.980665 */
    static const double s1[] = {0, 420.54446, -17993.714};
    static const double s2[] = {1.3713532, 106.37421};
    static const double t1[] = {0, 412.96917, -17125.983};
    static const double t2[] = {1.3052208, 113.94950};
    const double fs = GF / 1e-2;
    ck_assert_close_rel(drape_fit_value(&f.shear[DRAPE_WARP], 0.005),
                        poly(s1, 3, 0.005) * fs, 1e-12);
    ck_assert_close_rel(drape_fit_value(&f.shear[DRAPE_WARP], 0.05),
                        poly(s2, 2, 0.05) * fs, 1e-12);
    ck_assert_close_rel(drape_fit_value(&f.shear[DRAPE_WEFT], 0.05),
                        poly(t2, 2, 0.05) * fs, 1e-12);
    /* mean of warp and weft */
    ck_assert_close_rel(drape_fit_value(&f.shear_mean, 0.005),
                        0.5 * (poly(s1, 3, 0.005) + poly(t1, 3, 0.005)) * fs,
                        1e-12);
    ck_assert_close_rel(drape_fit_value(&f.shear_mean, 0.1),
                        0.5 * (poly(s2, 2, 0.1) + poly(t2, 2, 0.1)) * fs, 1e-12);
    ck_assert_close_rel(drape_fabric_shear_rigidity(&f),
                        0.5 * (420.54446 + 412.96917) * fs, 1e-12);
    /* integral is cached by prepare: W(K) over the first piece in closed form */
    double K = 0.3; /* 1/cm */
    double W = (0.85984849 * K * K / 2 - 0.71212123 * K * K * K / 3) * GF * 100;
    ck_assert_close_rel(drape_fit_integral(bw, 30.0), W, 1e-12);
}
END_TEST

/* fabric head (lines 1-3), bending units (4-5), `  warp:` is line 6 */
#define HEAD "fabric: t\nweight: 200 g/m^2\ntensile_stiffness: 1000 N/m\n"
#define BEND "bending:\n  units: {curvature: 1/m, moment: N.m/m}\n  warp:\n"
#define WEFT "  weft:\n    - {from: 0, poly: [0, 1]}\n"
#define SHEAR                                                                 \
    "shear:\n  units: {angle: rad, force: N/m}\n  curve:\n"                   \
    "    - {from: 0, poly: [0, 1]}\n"
#define P_ONE "    - {from: 0, poly: [0, 1]}\n"

static int load_text(const char *text, drape_fabric *f, drape_error *err,
                     warnings *ws)
{
    const char *p = tu_write_file("fabric.yaml", text);
    drape_error_clear(err);
    return drape_fabric_load(p, f, err, ws ? collect : NULL, ws);
}

START_TEST(test_stiffness_forms)
{
    drape_fabric f;
    drape_error err;
    /* k_warp / k_weft (docs/model.md 3.1) with gf/cm */
    int rc = load_text("fabric: t\nweight: 0.2\nk_warp: 5 gf/cm\n"
                       "k_weft: 3000 N/m\n" BEND P_ONE WEFT SHEAR, &f, &err,
                       NULL);
    ck_assert_msg(rc == 0, "%s", err.msg);
    ck_assert_close_rel(f.k[DRAPE_WARP], 5 * 9.80665e-3 / 1e-2, 1e-14);
    ck_assert_close_rel(f.k[DRAPE_WEFT], 3000.0, 1e-15);
    ck_assert_close_rel(f.weight, 0.2, 1e-15);
    /* mapping form */
    rc = load_text("fabric: t\nweight: 0.2\ntensile_stiffness: {warp: 2 kN/m, "
                   "weft: 1}\n", &f, &err, NULL);
    ck_assert_int_eq(rc, -1); /* kN is not a unit */
    ck_assert_str_eq(err.key, "tensile_stiffness.warp");
    rc = load_text("fabric: t\nweight: 0.2\ntensile_stiffness: {warp: 2000 N/m,"
                   " weft: 1000}\n" BEND P_ONE WEFT SHEAR, &f, &err, NULL);
    ck_assert_msg(rc == 0, "%s", err.msg);
    ck_assert_close_rel(f.k[DRAPE_WARP], 2000.0, 1e-15);
    ck_assert_close_rel(f.k[DRAPE_WEFT], 1000.0, 1e-15);
}
END_TEST

/* The internal shear damping (docs/model.md 3.6): `damping: {shear: T}` in any
 * time unit, 0 allowed (off), 0.5 ms when the key is absent. */
START_TEST(test_damping_shear)
{
    drape_fabric f;
    drape_error err;
    const char *base = "fabric: t\nweight: 0.2\ntensile_stiffness: 1000 N/m\n" BEND P_ONE WEFT SHEAR;
    char text[1024];
    ck_assert_msg(load_text(base, &f, &err, NULL) == 0, "%s", err.msg);
    ck_assert(f.damping_shear == 0.5e-3);
    static const struct { const char *v; double s; } ok[] = {
        {"2 ms", 2e-3}, {"0.25e-3 s", 0.25e-3}, {"0 s", 0.0}, {"0", 0.0}};
    for (size_t k = 0; k < sizeof ok / sizeof ok[0]; k++) {
        snprintf(text, sizeof text, "%sdamping: {shear: %s}\n", base, ok[k].v);
        ck_assert_msg(load_text(text, &f, &err, NULL) == 0, "%s: %s", ok[k].v, err.msg);
        ck_assert_msg(fabs(f.damping_shear - ok[k].s) <= 1e-15 * ok[k].s, "%s: %.17g",
                      ok[k].v, f.damping_shear);
    }
    snprintf(text, sizeof text, "%sdamping: {}\n", base);
    ck_assert_msg(load_text(text, &f, &err, NULL) == 0, "%s", err.msg);
    ck_assert(f.damping_shear == 0.5e-3);
}
END_TEST

START_TEST(test_shear_per_direction_and_units)
{
    drape_fabric f;
    drape_error err;
    /* shear in deg and gf/cm, given per direction */
    int rc = load_text(HEAD BEND P_ONE WEFT
                       "shear:\n  units: {angle: deg, force: gf/cm}\n"
                       "  warp:\n    - {from: 0, to: 1, poly: [0, 2]}\n"
                       "    - {from: 1, poly: [1, 1]}\n"
                       "  weft:\n    - {from: 0, poly: [0, 4]}\n",
                       &f, &err, NULL);
    ck_assert_msg(rc == 0, "%s", err.msg);
    const double d = M_PI / 180, fs = 9.80665e-3 / 1e-2;
    /* knot at 1 deg */
    ck_assert_close_rel(f.shear[DRAPE_WARP].p[1].from, d, 1e-14);
    /* 0.5 deg on the first piece: 2 * 0.5 gf/cm */
    ck_assert_close_rel(drape_fit_value(&f.shear[DRAPE_WARP], 0.5 * d),
                        1.0 * fs, 1e-13);
    /* 3 deg: 1 + 3 = 4 gf/cm */
    ck_assert_close_rel(drape_fit_value(&f.shear[DRAPE_WARP], 3 * d), 4 * fs,
                        1e-13);
    ck_assert_close_rel(drape_fit_value(&f.shear[DRAPE_WEFT], 3 * d), 12 * fs,
                        1e-13);
    /* mean slope at 0: (2 + 4) / 2 gf/cm per deg */
    ck_assert_close_rel(drape_fabric_shear_rigidity(&f), 3 * fs / d, 1e-13);
}
END_TEST

START_TEST(test_last_piece_with_to)
{
    drape_fabric f;
    drape_error err;
    warnings ws = {0};
    /* line 8: the last piece has `to: 5` (column 21) */
    int rc = load_text(HEAD BEND "    - {from: 0, to: 1, poly: [0, 1]}\n"
                       "    - {from: 1, to: 5, poly: [0.5, 0.5]}\n" WEFT SHEAR,
                       &f, &err, &ws);
    ck_assert_msg(rc == 0, "%s", err.msg);
    /* also a slope jump (1 -> 0.5) at K = 1: two warnings, the first for
     * the extended last piece */
    ck_assert_int_eq(ws.n, 2);
    ck_assert_int_eq(ws.first.kind, DRAPE_OK);
    ck_assert_int_eq(ws.first.line, 8);
    ck_assert_int_eq(ws.first.column, 21);
    ck_assert_str_eq(ws.first.key, "bending.warp[1].to");
    ck_assert_ptr_nonnull(strstr(ws.first.msg, "extended to infinity"));
    ck_assert(isinf(f.bend[DRAPE_WARP].p[1].to));
    /* beyond 5 1/m the last piece continues: 0.5 + 0.5 * 9 */
    ck_assert_close_rel(drape_fit_value(&f.bend[DRAPE_WARP], 9.0), 5.0, 1e-15);
}
END_TEST

START_TEST(test_slope_jump_warning)
{
    drape_fabric f;
    drape_error err;
    warnings ws = {0};
    /* C0 but not C1 at K = 1: slope 1 on the left, 0.5 on the right */
    int rc = load_text(HEAD BEND "    - {from: 0, to: 1, poly: [0, 1]}\n"
                       "    - {from: 1, poly: [0.5, 0.5]}\n" WEFT SHEAR,
                       &f, &err, &ws);
    ck_assert_msg(rc == 0, "%s", err.msg);
    ck_assert_int_eq(ws.n, 1);
    ck_assert_int_eq(ws.first.line, 8);
    ck_assert_int_eq(ws.first.column, 7);
    ck_assert_str_eq(ws.first.key, "bending.warp[1]");
    ck_assert_ptr_nonnull(strstr(ws.first.msg, "slope"));
    ck_assert_ptr_nonnull(strstr(ws.first.msg, "50%"));
    /* a NULL callback is fine */
    ck_assert_int_eq(load_text(HEAD BEND "    - {from: 0, to: 1, poly: [0, 1]}\n"
                               "    - {from: 1, poly: [0.5, 0.5]}\n" WEFT SHEAR,
                               &f, &err, NULL), 0);
}
END_TEST

/* Slope jumps at several knots of the bending curves are one warning at
 * the `bending` block (a tabulated curve has one at every knot), with
 * their number, the curves and the largest jump by hand: warp slopes
 * 1 -> 0.5 at K = 1 and 0.5 -> 0.2 at K = 2 (50 % and 30 % of its largest
 * slope at a knot, 1), weft 1 -> 0.1 at K = 1 (90 %). */
START_TEST(test_slope_jumps_one_line)
{
    drape_fabric f;
    drape_error err;
    warnings ws = {0};
    int rc = load_text(HEAD BEND "    - {from: 0, to: 1, poly: [0, 1]}\n"
                       "    - {from: 1, to: 2, poly: [0.5, 0.5]}\n"
                       "    - {from: 2, poly: [1.1, 0.2]}\n"
                       "  weft:\n    - {from: 0, to: 1, poly: [0, 1]}\n"
                       "    - {from: 1, poly: [0.9, 0.1]}\n" SHEAR,
                       &f, &err, &ws);
    ck_assert_msg(rc == 0, "%s", err.msg);
    ck_assert_int_eq(ws.n, 1);
    ck_assert_str_eq(ws.first.key, "bending");
    ck_assert_int_eq(ws.first.line, 5);
    ck_assert_msg(strstr(ws.first.msg, "jumps at 3 knots of warp, weft, by up to 90% of a "
                                       "curve's largest slope at a knot (weft[1], at 1 1/m: "
                                       "1 before, 0.1 after)") != NULL,
                  "%s", ws.first.msg);
    /* the curves are what the file says, jumps and all */
    ck_assert_close_rel(drape_fit_value(&f.bend[DRAPE_WARP], 3.0), 1.7, 1e-14);
}
END_TEST

START_TEST(test_value_jump_tolerance)
{
    drape_fabric f;
    drape_error err;
    /* values at the knot K = 1: 1 and 1 + 5e-7 (below 1e-6 relative) */
    int rc = load_text(HEAD BEND "    - {from: 0, to: 1, poly: [0, 1]}\n"
                       "    - {from: 1, poly: [0.0000005, 1]}\n" WEFT SHEAR,
                       &f, &err, NULL);
    ck_assert_msg(rc == 0, "%s", err.msg);
    /* 1 and 1 + 2e-6: rejected */
    rc = load_text(HEAD BEND "    - {from: 0, to: 1, poly: [0, 1]}\n"
                   "    - {from: 1, poly: [0.000002, 1]}\n" WEFT SHEAR,
                   &f, &err, NULL);
    ck_assert_int_eq(rc, -1);
    ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
    ck_assert_str_eq(err.key, "bending.warp[1]");
    ck_assert_ptr_nonnull(strstr(err.msg, "jump 2e-06 N.m/m"));
}
END_TEST

/* KES-F block of the brief's example; weft without hysteresis. */
#define KES_HEAD "fabric: k\nweight: 20 mg/cm^2\ntensile_stiffness: 10000 N/m\n"

START_TEST(test_kes_construction)
{
    drape_fabric f;
    drape_error err;
    int rc = load_text(KES_HEAD "kes:\n"
                       "  warp: {B: 0.085 gf.cm^2/cm, 2HB: 0.05 gf.cm/cm, "
                       "G: 0.9 gf/cm/deg, 2HG: 1.2 gf/cm}\n"
                       "  weft: {B: 0.06 gf.cm^2/cm, G: 0.8 gf/cm/deg}\n",
                       &f, &err, NULL);
    ck_assert_msg(rc == 0, "%s", err.msg);
    ck_assert_int_eq(f.from_kes, 1);

    /* bending, by hand in SI: B = 0.085 gf.cm^2/cm, HB = 0.025 gf.cm/cm,
     * K0 = 0.5 1/cm = 50 1/m */
    const double B = 0.085 * 9.80665e-3 * 1e-4 / 1e-2; /* N.m */
    const double HB = 0.05 / 2 * 9.80665e-3;            /* N.m/m */
    const double K0 = 50.0;
    const drape_fit *bw = &f.bend[DRAPE_WARP];
    ck_assert_int_eq(bw->n, 2);
    ck_assert_close_rel(bw->p[1].from, K0, 1e-15);
    /* beyond the knee: M = B K + HB */
    ck_assert_close_rel(drape_fit_value(bw, 120.0), B * 120.0 + HB, 1e-13);
    ck_assert_close_rel(drape_fit_slope(bw, 120.0), B, 1e-13);
    /* inside: (B + 2 HB / K0) K - HB K^2 / K0^2 */
    ck_assert_close_rel(drape_fit_value(bw, 20.0),
                        (B + 2 * HB / K0) * 20.0 - HB / (K0 * K0) * 400.0,
                        1e-13);
    /* M(0) = 0; value and slope continuous at the knee (left piece
     * evaluated from its coefficients, right one through the fit) */
    ck_assert(drape_fit_value(bw, 0.0) == 0.0);
    const drape_fit_piece *q = &bw->p[0];
    double yl = poly(q->c, q->ncoef, K0);
    double sl = q->c[1] + 2 * q->c[2] * K0;
    ck_assert_close_rel(yl, B * K0 + HB, 1e-13);
    ck_assert_close_rel(drape_fit_value(bw, K0), B * K0 + HB, 1e-13);
    ck_assert_close_rel(sl, B, 1e-12);
    double jv, js;
    drape_fit_knot_jumps(bw, &jv, &js);
    ck_assert(jv <= 1e-12 * (B * K0 + HB));
    ck_assert(js <= 1e-12 * B);
    ck_assert_close_rel(drape_fabric_bending_rigidity(&f, DRAPE_WARP),
                        B + 2 * HB / K0, 1e-13);
    /* weft without 2HB: M = B K, one piece */
    const double Bf = 0.06 * 9.80665e-5;
    ck_assert_int_eq(f.bend[DRAPE_WEFT].n, 1);
    ck_assert_close_rel(drape_fit_value(&f.bend[DRAPE_WEFT], 77.0), Bf * 77.0,
                        1e-13);

    /* shear: G = 0.9 gf/cm/deg = 0.9 * 0.980665 * 180 / pi N/m per rad,
     * HG = 0.6 gf/cm, knee g0 = 0.5 deg */
    const double G = 0.9 * 0.980665 * 180 / M_PI;
    const double HG = 1.2 / 2 * 0.980665;
    const double g0 = 0.5 * M_PI / 180;
    const drape_fit *sw = &f.shear[DRAPE_WARP];
    ck_assert_int_eq(sw->n, 2);
    ck_assert_close_rel(sw->p[1].from, g0, 1e-15);
    ck_assert_close_rel(drape_fit_value(sw, 0.1), G * 0.1 + HG, 1e-13);
    ck_assert_close_rel(drape_fit_value(sw, 0.004),
                        (G + 2 * HG / g0) * 0.004 - HG / (g0 * g0) * 0.004 * 0.004,
                        1e-13);
    q = &sw->p[0];
    ck_assert_close_rel(poly(q->c, q->ncoef, g0), G * g0 + HG, 1e-13);
    ck_assert_close_rel(q->c[1] + 2 * q->c[2] * g0, G, 1e-12);
    /* weft G only: F = G g */
    const double Gf = 0.8 * 0.980665 * 180 / M_PI;
    ck_assert_close_rel(drape_fit_value(&f.shear[DRAPE_WEFT], 0.2), Gf * 0.2,
                        1e-13);
    /* mean */
    ck_assert_close_rel(drape_fit_value(&f.shear_mean, 0.1),
                        0.5 * (G * 0.1 + HG + Gf * 0.1), 1e-13);
    ck_assert_close_rel(drape_fabric_shear_rigidity(&f),
                        0.5 * (G + 2 * HG / g0 + Gf), 1e-13);
}
END_TEST

START_TEST(test_kes_reproduces_breen)
{
    /* Breen's weft bending fit and both shear fits (Chen & Xu eqs. 2-5)
     * have exactly the shape of the KES construction: a quadratic from 0
     * joined C1 to a line at a knee.  Reading B (or G) and HB (or HG) off
     * the printed linear pieces and building the knee must give back the
     * printed quadratic coefficients.  Weft bending: knee 0.5 1/cm, line
     * 0.075643564 + 0.12871287 K; printed quadratic 0.43128713 K
     * - 0.30257426 K^2 (gf.cm/cm, K in 1/cm). */
    drape_fabric f;
    drape_error err;
    int rc = load_text(KES_HEAD "kes:\n"
                       "  warp: {B: 0.12871287 gf.cm^2/cm, "
                       "2HB: 0.151287128 gf.cm/cm, G: 106.37421 gf/cm/rad, "
                       "2HG: 2.7427064 gf/cm}\n"
                       "  weft: {B: 0.12871287 gf.cm^2/cm, "
                       "2HB: 0.151287128 gf.cm/cm, G: 113.94950 gf/cm/rad, "
                       "2HG: 2.6104416 gf/cm}\n",
                       &f, &err, NULL);
    ck_assert_msg(rc == 0, "%s", err.msg);
    const drape_fit_piece *q = &f.bend[DRAPE_WEFT].p[0];
    /* coefficient k in SI is (gf.cm/cm) GF times (1 cm)^k = 1e-2^k m^k */
    ck_assert_close_rel(q->c[1], 0.43128713 * GF * 1e-2, 1e-7);
    ck_assert_close_rel(q->c[2], -0.30257426 * GF * 1e-4, 1e-7);
    /* Shear: Breen's knee is 0.00873 rad, 0.5 deg rounded to 3 digits
     * (0.5 deg = 0.0087266 rad), so the quadratic coefficients agree to
     * about 3.9e-4 (a: 1/g0) and 7.8e-4 (b: 1/g0^2), not to 8 digits. */
    const double fs = GF / 1e-2;
    q = &f.shear[DRAPE_WARP].p[0];
    ck_assert_close_rel(q->c[1], 420.54446 * fs, 1e-3);
    ck_assert_close_rel(q->c[2], -17993.714 * fs, 1e-3);
    q = &f.shear[DRAPE_WEFT].p[0];
    ck_assert_close_rel(q->c[1], 412.96917 * fs, 1e-3);
    ck_assert_close_rel(q->c[2], -17125.983 * fs, 1e-3);
    /* and beyond the knee the lines are Breen's exactly */
    ck_assert_close_rel(drape_fit_value(&f.shear[DRAPE_WARP], 0.1),
                        (1.3713532 + 106.37421 * 0.1) * fs, 1e-12);
}
END_TEST

START_TEST(test_kes_2hg5)
{
    drape_fabric f;
    drape_error err;
    /* 2HG = 1.2, 2HG5 = 2.4 gf/cm: offset grows from 0.6 to 1.2 gf/cm
     * between 0.5 and 5 deg and stays 1.2 beyond */
    int rc = load_text(KES_HEAD "kes:\n"
                       "  warp: {B: 0.085 gf.cm^2/cm, G: 0.9 gf/cm/deg, "
                       "2HG: 1.2 gf/cm, 2HG5: 2.4 gf/cm}\n"
                       "  weft: {B: 0.085 gf.cm^2/cm, G: 0.9 gf/cm/deg, "
                       "2HG: 1.2 gf/cm, 2HG5: 2.4 gf/cm}\n",
                       &f, &err, NULL);
    ck_assert_msg(rc == 0, "%s", err.msg);
    const double G = 0.9 * 0.980665 * 180 / M_PI;
    const double HG = 0.6 * 0.980665, HG5 = 1.2 * 0.980665;
    const double g0 = 0.5 * M_PI / 180, g5 = 5 * M_PI / 180;
    const drape_fit *s = &f.shear[DRAPE_WARP];
    ck_assert_int_eq(s->n, 3);
    /* at and beyond 5 deg: G g + HG5 */
    ck_assert_close_rel(drape_fit_value(s, 0.2), G * 0.2 + HG5, 1e-13);
    ck_assert_close_rel(drape_fit_value(s, g5), G * g5 + HG5, 1e-12);
    /* at 0.5 deg: G g0 + HG */
    ck_assert_close_rel(drape_fit_value(s, g0), G * g0 + HG, 1e-12);
    /* C1 everywhere: knot jumps at rounding level; slope G beyond 5 deg */
    double jv, js;
    drape_fit_knot_jumps(s, &jv, &js);
    ck_assert_msg(jv <= 1e-10 * (G * g5 + HG5), "value jump %g", jv);
    ck_assert_msg(js <= 1e-9 * G, "slope jump %g", js);
    ck_assert_close_rel(drape_fit_slope(s, 0.2), G, 1e-12);
    /* the loading curve rises monotonically and its offset F - G g stays
     * between HG and HG5 on [g0, g5] (sampled) */
    double prev = 0.0;
    for (int i = 1; i <= 200; i++) {
        double g = 0.2 * i / 200;
        double v = drape_fit_value(s, g);
        ck_assert_msg(v > prev, "not increasing at %g", g);
        prev = v;
        if (g >= g0 && g <= g5) {
            double o = v - G * g;
            ck_assert_msg(o >= HG * (1 - 1e-12) && o <= HG5 * (1 + 1e-12),
                          "offset %g at %g", o, g);
        }
    }
}
END_TEST

START_TEST(test_single_shear_curve)
{
    drape_fabric f;
    drape_error err;
    int rc = load_text(HEAD BEND P_ONE WEFT SHEAR, &f, &err, NULL);
    ck_assert_msg(rc == 0, "%s", err.msg);
    ck_assert_close_rel(drape_fit_value(&f.shear[DRAPE_WARP], 0.3), 0.3, 1e-15);
    ck_assert_close_rel(drape_fit_value(&f.shear[DRAPE_WEFT], 0.3), 0.3, 1e-15);
    ck_assert_close_rel(drape_fit_value(&f.shear_mean, 0.3), 0.3, 1e-15);
    ck_assert_str_eq(f.description, "");
}
END_TEST

/* ---------------------------------------------------------- bad input */

typedef struct bad_case {
    const char *text;
    drape_error_kind kind;
    int line, column;
    const char *key;
    const char *msg_part;
} bad_case;

static const bad_case bad[] = {
    /* root keys */
    {"fabric: t\ntensile_stiffness: 1 N/m\n" BEND P_ONE WEFT SHEAR,
     DRAPE_E_INPUT, 1, 1, "weight", "missing required key `weight`"},
    {"weight: 1\ntensile_stiffness: 1 N/m\n", DRAPE_E_INPUT, 1, 1, "fabric",
     "missing required key `fabric`"},
    {"fabric: t\nweight: 0 kg/m^2\n", DRAPE_E_INPUT, 2, 9, "weight",
     "expected a positive areal density, got \"0 kg/m^2\""},
    {"fabric: t\nweight: -2 g/m^2\n", DRAPE_E_INPUT, 2, 9, "weight",
     "expected a positive areal density"},
    {"fabric: t\nweight: 1e999 g/m^2\n", DRAPE_E_INPUT, 2, 9, "weight",
     "out of range"},
    {"fabric: t\nweight: 1e-400 g/m^2\n", DRAPE_E_INPUT, 2, 9, "weight",
     "number out of range"},
    {"fabric: t\nweight: 20 N/m\n", DRAPE_E_INPUT, 2, 9, "weight",
     "expected an areal density (kg/m^2), got N/m"},
    {"fabric: t\nweight: heavy\n", DRAPE_E_INPUT, 2, 9, "weight",
     "not a number: \"heavy\""},
    {"fabric: t\nweight: [1]\n", DRAPE_E_INPUT, 2, 9, "weight",
     "expected a positive areal density, got a sequence"},
    {"fabric: t\nwieght: 1\n", DRAPE_E_INPUT, 2, 1, "wieght",
     "unknown key `wieght`; did you mean `weight`?"},
    {"fabric: {a: 1}\n", DRAPE_E_INPUT, 1, 9, "fabric",
     "expected text, got a mapping"},
    {"fabric: ''\n", DRAPE_E_INPUT, 1, 9, "fabric", "must not be empty"},
    {"fabric: t\nweight: 1\n" BEND P_ONE WEFT SHEAR, DRAPE_E_INPUT, 1, 1,
     "tensile_stiffness", "missing key `tensile_stiffness`"},
    {"fabric: t\nweight: 1\ntensile_stiffness: -1 N/m\n", DRAPE_E_INPUT, 3, 20,
     "tensile_stiffness", "expected a positive tensile stiffness"},
    {"fabric: t\nweight: 1\ntensile_stiffness: {warp: 1}\n", DRAPE_E_INPUT, 3,
     20, "tensile_stiffness.weft", "missing required key `weft`"},
    {"fabric: t\nweight: 1\ntensile_stiffness: 1\nk_warp: 1\n", DRAPE_E_INPUT,
     4, 9, "k_warp", "either `tensile_stiffness` or"},
    {"fabric: t\nweight: 1\nk_warp: 1\n", DRAPE_E_INPUT, 1, 1, "k_weft",
     "missing key `k_weft`"},
    {HEAD SHEAR, DRAPE_E_INPUT, 1, 1, "bending", "missing key `bending`"},
    {HEAD BEND P_ONE WEFT, DRAPE_E_INPUT, 1, 1, "shear", "missing key `shear`"},
    /* pieces (line 7 is the first piece; see the column map in
     * "    - {from: 0, to: 1, poly: [0, 1]}": from 14, to 21, poly 30) */
    {HEAD BEND "    - {from: 0, to: 1, poly: [0, 1]}\n"
              "    - {from: 2, poly: [1, 1]}\n" WEFT SHEAR,
     DRAPE_E_INPUT, 8, 14, "bending.warp[1].from",
     "gap between bending.warp[0] (to 1) and bending.warp[1] (from 2)"},
    {HEAD BEND "    - {from: 0, to: 1, poly: [0, 1]}\n"
              "    - {from: 0.5, poly: [0.5, 1]}\n" WEFT SHEAR,
     DRAPE_E_INPUT, 8, 14, "bending.warp[1].from",
     "bending.warp[1] (from 0.5) overlaps bending.warp[0] (to 1)"},
    {HEAD BEND "    - {from: 0.1, poly: [0, 1]}\n" WEFT SHEAR, DRAPE_E_INPUT, 7,
     14, "bending.warp[0].from", "must start at 0, not 0.1"},
    {HEAD "bending:\n  units: {curvature: 1/m, moment: N.m/m}\n  warp: []\n"
     WEFT SHEAR, DRAPE_E_INPUT, 6, 9, "bending.warp", "empty list"},
    {HEAD BEND "    - {from: 0, to: 0, poly: [0, 1]}\n" WEFT SHEAR,
     DRAPE_E_INPUT, 7, 21, "bending.warp[0].to",
     "`to` (0) must be greater than `from` (0)"},
    {HEAD BEND "    - {from: 0, poly: [0, 1]}\n    - {from: 1, poly: [1, 1]}\n"
     WEFT SHEAR, DRAPE_E_INPUT, 7, 7, "bending.warp[0]", "missing key `to`"},
    {HEAD BEND "    - {to: 1, poly: [0, 1]}\n" WEFT SHEAR, DRAPE_E_INPUT, 7, 7,
     "bending.warp[0].from", "missing required key `from`"},
    {HEAD BEND "    - {from: 0, to: 1}\n" WEFT SHEAR, DRAPE_E_INPUT, 7, 7,
     "bending.warp[0].poly", "missing required key `poly`"},
    {HEAD BEND "    - {from: -1, poly: [0, 1]}\n" WEFT SHEAR, DRAPE_E_INPUT, 7,
     14, "bending.warp[0].from", "expected a non-negative number, got \"-1\""},
    {HEAD "bending:\n  units: {curvature: 1/m, moment: N.m/m}\n  warp:\n" WEFT
     SHEAR, DRAPE_E_INPUT, 6, 8, "bending.warp",
     "expected a list of pieces {from, to, poly}, got an empty value"},
    {HEAD BEND "    - {form: 0, poly: [0, 1]}\n" WEFT SHEAR, DRAPE_E_INPUT, 7,
     8, "bending.warp[0].form", "did you mean `from`?"},
    {HEAD BEND "    - {from: 0, to: 1, poly: [0, 1]}\n"
              "    - {from: 1, poly: [1.5, 1]}\n" WEFT SHEAR,
     DRAPE_E_INPUT, 8, 7, "bending.warp[1]",
     "jumps at the knot 1 1/m: 1 N.m/m at the end of bending.warp[0], 2.5 at "
     "the start of bending.warp[1] (jump 1.5 N.m/m"},
    /* "    - {from: 0, poly: [" is 23 bytes: poly[0] at 24, poly[1] at 27 */
    {HEAD BEND "    - {from: 0, poly: [0.01, 1]}\n" WEFT SHEAR, DRAPE_E_INPUT,
     7, 24, "bending.warp[0].poly[0]", "at 0 must be 0, got 0.01 N.m/m"},
    /* a moment that does not oppose the bending: no rigidity, a negative
     * one, a fit negative past its data (root 0.2 1/m), one negative
     * between its knots (x - x^2 on [1, 2)), one that dips below 0 between
     * its real roots 2 -+ sqrt(0.2) and rises again */
    {HEAD BEND "    - {from: 0, poly: [0, -0.2]}\n" WEFT SHEAR, DRAPE_E_INPUT, 7, 23,
     "bending.warp[0].poly", "must rise from 0: its slope at 0 (the rigidity) is -0.2"},
    {HEAD BEND "    - {from: 0, poly: [0, 0, 1]}\n" WEFT SHEAR, DRAPE_E_INPUT, 7, 23,
     "bending.warp[0].poly", "its slope at 0 (the rigidity) is 0 N.m/m per 1/m"},
    {HEAD BEND "    - {from: 0, poly: [0, 0.2, -1]}\n" WEFT SHEAR, DRAPE_E_INPUT, 7, 7,
     "bending.warp[0]", "turns negative for large 1/m"},
    {HEAD BEND "    - {from: 0, to: 2, poly: [0, 1, -1]}\n"
              "    - {from: 2, poly: [-6, 2]}\n" WEFT SHEAR,
     DRAPE_E_INPUT, 7, 7, "bending.warp[0]", "is not positive at 1.5 1/m (-0.75 N.m/m)"},
    {HEAD BEND "    - {from: 0, to: 1, poly: [0, 1]}\n"
              "    - {from: 1, poly: [4.75, -5, 1.25]}\n" WEFT SHEAR,
     DRAPE_E_INPUT, 8, 7, "bending.warp[1]", "is not positive at 2 1/m (-0.25 N.m/m)"},
    {HEAD BEND "    - {from: 0, poly: [0, x]}\n" WEFT SHEAR, DRAPE_E_INPUT, 7,
     27, "bending.warp[0].poly[1]", "expected a number, got \"x\""},
    {HEAD BEND "    - {from: 0, poly: [0, 1 N]}\n" WEFT SHEAR, DRAPE_E_INPUT,
     7, 27, "bending.warp[0].poly[1]", "expected a number, got \"1 N\""},
    {HEAD BEND "    - {from: 0, poly: [0, inf]}\n" WEFT SHEAR, DRAPE_E_INPUT,
     7, 27, "bending.warp[0].poly[1]", "expected a number"},
    {HEAD BEND "    - {from: 0, poly: [0, 1e400]}\n" WEFT SHEAR, DRAPE_E_INPUT,
     7, 27, "bending.warp[0].poly[1]", "out of range"},
    {HEAD BEND "    - {from: 0, poly: [0, 1e-400]}\n" WEFT SHEAR, DRAPE_E_INPUT,
     7, 27, "bending.warp[0].poly[1]", "out of range"},
    {HEAD BEND "    - {from: 0, poly: [0, 1e-310]}\n" WEFT SHEAR, DRAPE_E_INPUT,
     7, 27, "bending.warp[0].poly[1]", "out of range"},
    {HEAD BEND "    - {from: 0, poly: [0, [1]]}\n" WEFT SHEAR, DRAPE_E_INPUT, 7,
     27, "bending.warp[0].poly[1]", "expected a number, got a sequence"},
    {HEAD BEND "    - {from: 0, poly: []}\n" WEFT SHEAR, DRAPE_E_INPUT, 7, 23,
     "bending.warp[0].poly", "no coefficients"},
    {HEAD BEND "    - {from: 0, poly: [0, 1, 2, 3, 4, 5, 6, 7, 8]}\n" WEFT SHEAR,
     DRAPE_E_INPUT, 7, 23, "bending.warp[0].poly",
     "too many coefficients (9; at most 8"},
    {HEAD BEND "    - {from: 0, poly: 1}\n" WEFT SHEAR, DRAPE_E_INPUT, 7, 23,
     "bending.warp[0].poly", "expected a list of coefficients"},
    {HEAD BEND "    - 5\n" WEFT SHEAR, DRAPE_E_INPUT, 7, 7, "bending.warp[0]",
     "expected a piece"},
    {HEAD "bending:\n  units: {curvature: 1/m, moment: N.m/m}\n  warp: 3\n"
     WEFT SHEAR, DRAPE_E_INPUT, 6, 9, "bending.warp",
     "expected a list of pieces"},
    /* units: "  units: {curvature: 1/m, moment: " is 34 bytes */
    {HEAD "bending:\n  units: {curvature: 1/m, moment: gf/cm}\n  warp:\n"
     P_ONE WEFT SHEAR, DRAPE_E_INPUT, 5, 35, "bending.units.moment",
     "`gf/cm` is a unit of force per length; expected a unit of moment"},
    {HEAD "bending:\n  units: {curvature: 1/m, moment: furlong}\n  warp:\n"
     P_ONE WEFT SHEAR, DRAPE_E_INPUT, 5, 35, "bending.units.moment",
     "unknown unit \"furlong\""},
    {HEAD "bending:\n  units: {curvature: cm, moment: N}\n  warp:\n"
     P_ONE WEFT SHEAR, DRAPE_E_INPUT, 5, 22, "bending.units.curvature",
     "`cm` is a unit of length; expected a unit of curvature"},
    {HEAD "bending:\n  units: {curvature: 1/m}\n  warp:\n" P_ONE WEFT SHEAR,
     DRAPE_E_INPUT, 5, 10, "bending.units.moment",
     "missing required key `moment`"},
    {HEAD "bending:\n  warp:\n" P_ONE WEFT SHEAR, DRAPE_E_INPUT, 5, 3,
     "bending.units", "missing required key `units`"},
    {HEAD BEND P_ONE WEFT "shear:\n  units: {angle: cm, force: N/m}\n"
     "  curve:\n" P_ONE, DRAPE_E_INPUT, 11, 18, "shear.units.angle",
     "expected a unit of angle"},
    {HEAD BEND P_ONE WEFT "shear:\n  units: {angle: rad, force: N/m}\n"
     "  curve:\n" P_ONE "  warp:\n" P_ONE, DRAPE_E_INPUT, 15, 5, "shear",
     "either `curve`"},
    {HEAD BEND P_ONE WEFT "shear:\n  units: {angle: rad, force: N/m}\n"
     "  warp:\n" P_ONE, DRAPE_E_INPUT, 11, 3, "shear.weft",
     "missing required key `weft`"},
    /* KES */
    {KES_HEAD "kes:\n  warp: {B: 1 gf.cm^2/cm, G: 1 gf/cm/deg}\n"
     "  weft: {G: 1 gf/cm/deg}\n", DRAPE_E_INPUT, 6, 9, "kes.weft.B",
     "missing required key `B`"},
    {KES_HEAD "kes: 3\n", DRAPE_E_INPUT, 4, 6, "kes",
     "expected a mapping {warp: {B, 2HB, G, 2HG}, weft: {...}}, got a scalar "
     "(\"3\")"},
    {KES_HEAD "kes:\n  warp: {B: 1 gf.cm^2/cm, G: 1 gf/cm}\n", DRAPE_E_INPUT,
     5, 30, "kes.warp.G", "write the angle unit"},
    /* angles are dimensionless to the unit parser: an angle multiplied in,
     * or twice, passed with a scale off by (180/pi)^2 or 180/pi */
    {KES_HEAD "kes:\n  warp: {B: 1 gf.cm^2/cm, G: 1 gf/cm.deg}\n", DRAPE_E_INPUT,
     5, 30, "kes.warp.G", "write the angle unit, last and once"},
    {KES_HEAD "kes:\n  warp: {B: 1 gf.cm^2/cm, G: 1 gf/cm/deg^2}\n", DRAPE_E_INPUT,
     5, 30, "kes.warp.G", "write the angle unit, last and once"},
    {KES_HEAD "kes:\n  warp: {B: 1 gf.cm^2/cm, G: 1 gf.rad/cm/deg}\n", DRAPE_E_INPUT,
     5, 30, "kes.warp.G", "write the angle unit, last and once"},
    /* "  warp: {B: 1 gf.cm^2/cm, G: 1 gf/cm/deg, 2HG: " is 47 bytes */
    {KES_HEAD "kes:\n  warp: {B: 1 gf.cm^2/cm, G: 1 gf/cm/deg, 2HG: 1.2 gf/cm/deg}\n",
     DRAPE_E_INPUT, 5, 48, "kes.warp.2HG", "2HG takes no angle unit"},
    {KES_HEAD "kes:\n  warp: {B: 1 gf.cm/cm, G: 1 gf/cm/deg}\n", DRAPE_E_INPUT,
     5, 13, "kes.warp.B", "expected a moment (N.m), got gf.cm/cm"},
    {KES_HEAD "kes:\n  warp: {B: 1 gf.cm^2/cm, G: 1 gf/cm/deg, 2HB: -1 "
     "gf.cm/cm}\n", DRAPE_E_INPUT, 5, 48, "kes.warp.2HB",
     "expected a non-negative bending hysteresis"},
    {KES_HEAD "kes:\n  warp: {B: 1 gf.cm^2/cm, G: 1 gf/cm/deg, 2HG: 2 gf/cm, "
     "2HG5: 1 gf/cm}\n", DRAPE_E_INPUT, 5, 63, "kes.warp.2HG5",
     "smaller than 2HG"},
    {KES_HEAD "kes:\n  warp: {B: 1 gf.cm^2/cm, G: 1 gf/cm/deg, HB: 1}\n",
     DRAPE_E_INPUT, 5, 43, "kes.warp.HB", "unknown key `HB`; did you mean"},
    {KES_HEAD "kes: {warp: {B: 1, G: 1}, weft: {B: 1, G: 1}}\n" BEND P_ONE
     WEFT, DRAPE_E_INPUT, 6, 3, "bending", "either `kes` or"},
    /* damping, on line 14 (after the 13 lines of the root keys, BEND P_ONE WEFT SHEAR) */
    {"fabric: t\nweight: 1\ntensile_stiffness: 1 N/m\n" BEND P_ONE WEFT SHEAR
     "damping: {shear: -1 ms}\n", DRAPE_E_INPUT, 14, 18, "damping.shear",
     "expected a non-negative time"},
    {"fabric: t\nweight: 1\ntensile_stiffness: 1 N/m\n" BEND P_ONE WEFT SHEAR
     "damping: {shear: 1 N/m}\n", DRAPE_E_INPUT, 14, 18, "damping.shear",
     "expected a time (s), got N/m"},
    {"fabric: t\nweight: 1\ntensile_stiffness: 1 N/m\n" BEND P_ONE WEFT SHEAR
     "damping: {air: 1 1/s}\n", DRAPE_E_INPUT, 14, 11, "damping.air",
     "unknown key `air`"},
    {"fabric: t\nweight: 1\ntensile_stiffness: 1 N/m\n" BEND P_ONE WEFT SHEAR
     "damping: 1 ms\n", DRAPE_E_INPUT, 14, 10, "damping", "expected a mapping"},
    /* YAML level errors come through */
    {"fabric: t\nfabric: u\n", DRAPE_E_INPUT, 2, 1, "fabric",
     "duplicate key `fabric`"},
    {"fabric: [t\n", DRAPE_E_SYNTAX, 2, 1, NULL, "flow sequence"},
};

START_TEST(test_bad_input)
{
    const bad_case *c = &bad[_i];
    drape_fabric f;
    drape_error err;
    warnings ws = {0};
    int rc = load_text(c->text, &f, &err, &ws);
    char buf[1200];
    drape_error_format(&err, buf, sizeof buf);
    ck_assert_msg(rc == -1, "case %d accepted", _i);
    ck_assert_msg(err.kind == c->kind, "case %d: kind %d, expected %d: %s", _i,
                  err.kind, c->kind, buf);
    ck_assert_msg(strstr(err.file, "fabric.yaml") != NULL, "case %d: file %s",
                  _i, err.file);
    ck_assert_msg(err.line == c->line && err.column == c->column,
                  "case %d: at %d:%d, expected %d:%d: %s", _i, err.line,
                  err.column, c->line, c->column, buf);
    if (c->key)
        ck_assert_msg(strcmp(err.key, c->key) == 0,
                      "case %d: key `%s`, expected `%s`: %s", _i, err.key,
                      c->key, buf);
    ck_assert_msg(strstr(err.msg, c->msg_part) != NULL,
                  "case %d: message lacks \"%s\": %s", _i, c->msg_part, buf);
}
END_TEST

START_TEST(test_too_many_pieces)
{
    /* 17 pieces [i, i+1): the 17th (index 16) is at line 7 + 16 */
    char text[4096];
    size_t k = (size_t)snprintf(text, sizeof text, "%s", HEAD BEND);
    for (int i = 0; i < 17; i++)
        k += (size_t)snprintf(text + k, sizeof text - k,
                              "    - {from: %d, to: %d, poly: [0, 1]}\n", i,
                              i + 1);
    snprintf(text + k, sizeof text - k, "%s", WEFT SHEAR);
    drape_fabric f;
    drape_error err;
    ck_assert_int_eq(load_text(text, &f, &err, NULL), -1);
    ck_assert_int_eq(err.line, 23);
    ck_assert_int_eq(err.column, 7);
    ck_assert_str_eq(err.key, "bending.warp[16]");
    ck_assert_ptr_nonnull(strstr(err.msg, "too many pieces (17; at most 16)"));
}
END_TEST

START_TEST(test_io_error)
{
    drape_fabric f;
    drape_error err;
    drape_error_clear(&err);
    ck_assert_int_eq(drape_fabric_load("/nonexistent/f.yaml", &f, &err, NULL,
                                       NULL), -1);
    ck_assert_int_eq(err.kind, DRAPE_E_IO);
    ck_assert_str_eq(err.file, "/nonexistent/f.yaml");
}
END_TEST

/* The bad-input corpus in tests/bad: each file fails where its first-line
 * comment says. */
typedef struct corpus_case {
    const char *file;
    int line, column;
    const char *key;
} corpus_case;

static const corpus_case corpus[] = {
    {"bad/fabric-gap.yaml", 9, 14, "bending.warp[1].from"},
    {"bad/fabric-value-jump.yaml", 11, 7, "bending.weft[1]"},
    {"bad/fabric-cone.yaml", 8, 26, "bending.warp[0].poly[0]"},
    {"bad/fabric-typo.yaml", 3, 1, "wieght"},
    {"bad/fabric-weight-unit.yaml", 3, 9, "weight"},
    {"bad/fabric-not-a-number.yaml", 8, 29, "bending.warp[0].poly[1]"},
    {"bad/fabric-kes-g-unit.yaml", 6, 54, "kes.warp.G"},
};

START_TEST(test_corpus)
{
    const corpus_case *c = &corpus[_i];
    drape_fabric f;
    drape_error err;
    drape_error_clear(&err);
    ck_assert_int_eq(drape_fabric_load(c->file, &f, &err, NULL, NULL), -1);
    char buf[1200];
    drape_error_format(&err, buf, sizeof buf);
    ck_assert_msg(err.kind == DRAPE_E_INPUT, "%s", buf);
    ck_assert_msg(err.line == c->line && err.column == c->column,
                  "%s: expected %d:%d", buf, c->line, c->column);
    ck_assert_str_eq(err.key, c->key);
}
END_TEST

START_TEST(test_alloc_failures)
{
    drape_fabric f;
    drape_error err;
    const char *p = tu_src("fabrics/cotton-breen.yaml");
    drape_error_clear(&err);
    drape_alloc_fail_at(1000000);
    ck_assert_int_eq(drape_fabric_load(p, &f, &err, NULL, NULL), 0);
    long total = drape_alloc_count();
    drape_alloc_fail_at(0);
    for (long n = 1; n <= total; n++) {
        drape_error_clear(&err);
        drape_alloc_fail_at(n);
        int rc = drape_fabric_load(p, &f, &err, NULL, NULL);
        drape_alloc_fail_at(0);
        ck_assert_msg(rc == -1, "allocation %ld of %ld failed, load succeeded",
                      n, total);
        ck_assert_int_eq(err.kind, DRAPE_E_NOMEM);
    }
}
END_TEST

/* Collects the range warnings ("far outside") of a load. */
typedef struct range_warnings {
    int n;
    drape_error w[4];
} range_warnings;

static void collect_range(void *ctx, const drape_error *w)
{
    range_warnings *rw = ctx;
    if (strstr(w->msg, "far outside") && rw->n < 4) rw->w[rw->n++] = *w;
}

static int load_range(const char *text, range_warnings *rw)
{
    drape_fabric f;
    drape_error err;
    memset(rw, 0, sizeof *rw);
    drape_error_clear(&err);
    const char *p = tu_write_file("fabric.yaml", text);
    int rc = drape_fabric_load(p, &f, &err, collect_range, rw);
    ck_assert_msg(rc == 0, "%s: %s", err.key, err.msg); /* a warning, not an error */
    return rw->n;
}

/* Values far outside any textile load, with a warning naming the key
 * (docs/fabrics.md: weight 5..5000 g/m^2, tensile stiffness 1..1e7 N/m);
 * the bounds themselves do not warn. */
START_TEST(test_implausible_values)
{
    range_warnings rw;
    ck_assert_int_eq(load_range("fabric: t\nweight: 20 g/cm^2\ntensile_stiffness: 1000 N/m\n"
                                BEND P_ONE WEFT SHEAR, &rw), 1);
    ck_assert_str_eq(rw.w[0].key, "weight");
    ck_assert_int_eq(rw.w[0].kind, DRAPE_OK);
    ck_assert_int_eq(rw.w[0].line, 2);
    ck_assert_int_eq(rw.w[0].column, 9);
    ck_assert_msg(strstr(rw.w[0].msg, "200000 g/m^2"), "%s", rw.w[0].msg);
    ck_assert_int_eq(load_range("fabric: t\nweight: 1e300 g/m^2\ntensile_stiffness: 1e30 N/m\n"
                                BEND P_ONE WEFT SHEAR, &rw), 2);
    ck_assert_str_eq(rw.w[0].key, "weight");
    ck_assert_str_eq(rw.w[1].key, "tensile_stiffness");
    ck_assert_int_eq(rw.w[1].line, 3);
    ck_assert_msg(strstr(rw.w[1].msg, "1e+30 N/m"), "%s", rw.w[1].msg);
    ck_assert_int_eq(load_range("fabric: t\nweight: 1 g/m^2\n"
                                "tensile_stiffness: {warp: 0.5 N/m, weft: 2e7 N/m}\n"
                                BEND P_ONE WEFT SHEAR, &rw), 3);
    ck_assert_str_eq(rw.w[0].key, "weight");
    ck_assert_str_eq(rw.w[1].key, "tensile_stiffness.warp");
    ck_assert_str_eq(rw.w[2].key, "tensile_stiffness.weft");
    ck_assert_int_eq(load_range("fabric: t\nweight: 200 g/m^2\nk_warp: 1e8 N/m\n"
                                "k_weft: 1000 N/m\n" BEND P_ONE WEFT SHEAR, &rw), 1);
    ck_assert_str_eq(rw.w[0].key, "k_warp");
    /* the bounds are inside */
    ck_assert_int_eq(load_range("fabric: t\nweight: 5 g/m^2\n"
                                "tensile_stiffness: {warp: 1 N/m, weft: 1e7 N/m}\n"
                                BEND P_ONE WEFT SHEAR, &rw), 0);
    ck_assert_int_eq(load_range("fabric: t\nweight: 5000 g/m^2\ntensile_stiffness: 1000 N/m\n"
                                BEND P_ONE WEFT SHEAR, &rw), 0);
    /* drape check prints it on stderr, and succeeds */
    const char *p = tu_write_file("absurd.yaml", "fabric: t\nweight: 1e300 g/m^2\n"
                                  "tensile_stiffness: 1e30 N/m\n" BEND P_ONE WEFT SHEAR);
    char args[600], out[4096], err[4096];
    snprintf(args, sizeof args, "check '%s'", p);
    ck_assert_int_eq(tu_run_drape(args, out, sizeof out, err, sizeof err), 0);
    ck_assert_msg(strstr(err, "absurd.yaml:2:9: weight: warning: 1e+300 g/m^2 lies far outside") &&
                      strstr(err, "absurd.yaml:3:20: tensile_stiffness: warning: 1e+30 N/m"),
                  "%s", err);
}
END_TEST

/* No shipped fabric (fabrics/, and ../shared/examples/fabrics/ when that
 * checkout is beside this one) is outside the plausible ranges. */
START_TEST(test_shipped_fabrics_plausible)
{
    static const char *const dirs[] = {"fabrics", "../shared/examples/fabrics"};
    int seen = 0;
    for (int d = 0; d < 2; d++) {
        char dir[600];
        snprintf(dir, sizeof dir, "%s", tu_src(dirs[d]));
        DIR *dp = opendir(dir);
        ck_assert_msg(dp || d == 1, "cannot open %s", dir);
        if (!dp) continue;
        struct dirent *e;
        while ((e = readdir(dp)) != NULL) {
            size_t n = strlen(e->d_name);
            if (n < 6 || strcmp(e->d_name + n - 5, ".yaml") != 0) continue;
            char path[1200];
            snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
            drape_fabric f;
            drape_error err;
            range_warnings rw = {0};
            drape_error_clear(&err);
            ck_assert_msg(drape_fabric_load(path, &f, &err, collect_range, &rw) == 0, "%s: %s",
                          path, err.msg);
            ck_assert_msg(rw.n == 0, "%s: %s: %s", path, rw.w[0].key, rw.w[0].msg);
            seen++;
        }
        closedir(dp);
    }
    ck_assert_int_ge(seen, 9);
}
END_TEST

Suite *fabric_suite(void); /* found by the runner */
Suite *fabric_suite(void)
{
    Suite *s = suite_create("fabric");
    TCase *tc = tcase_create("fabric");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_cotton_breen);
    tcase_add_test(tc, test_stiffness_forms);
    tcase_add_test(tc, test_damping_shear);
    tcase_add_test(tc, test_shear_per_direction_and_units);
    tcase_add_test(tc, test_last_piece_with_to);
    tcase_add_test(tc, test_slope_jump_warning);
    tcase_add_test(tc, test_slope_jumps_one_line);
    tcase_add_test(tc, test_value_jump_tolerance);
    tcase_add_test(tc, test_kes_construction);
    tcase_add_test(tc, test_kes_reproduces_breen);
    tcase_add_test(tc, test_kes_2hg5);
    tcase_add_test(tc, test_single_shear_curve);
    tcase_add_loop_test(tc, test_bad_input, 0, (int)(sizeof bad / sizeof bad[0]));
    tcase_add_test(tc, test_too_many_pieces);
    tcase_add_test(tc, test_io_error);
    tcase_add_loop_test(tc, test_corpus, 0,
                        (int)(sizeof corpus / sizeof corpus[0]));
    tcase_add_test(tc, test_alloc_failures);
    tcase_add_test(tc, test_implausible_values);
    tcase_add_test(tc, test_shipped_fabrics_plausible);
    suite_add_tcase(s, tc);
    return s;
}
