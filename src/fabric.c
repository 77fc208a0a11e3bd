/* fabric.c: load a fabric description (see fabric.h, docs/fabrics.md).
 *
 * Implements docs/model.md 1 (units: everything converted to SI once, here),
 * 3.1 (tensile stiffness k per direction, `k_warp`/`k_weft`), 3.4 (piecewise
 * polynomial fits: consecutive pieces from 0, the last one extending to
 * infinity, a value jump at a knot is an error, a slope jump is reported)
 * and numerics.md 4.3 (M(0) != 0 makes the energy a cone at flat: rejected).
 *
 * Fits are checked in the file's own units (knots compared exactly as
 * written) and then rescaled with drape_fit_scale: K_si = K * sx,
 * M_si = M * sy, coefficient k times sy / sx^k.
 *
 * KES-F summary values (Kawabata 1980) are turned into fits by the loading-
 * curve construction of docs/fabrics.md, built directly in SI:
 *
 *   bending, HB = 2HB / 2, knee K0 (DRAPE_FABRIC_KES_K0):
 *     M(K) = (B + 2 HB / K0) K - (HB / K0^2) K^2      0 <= K < K0   (K1)
 *     M(K) = HB + B K                                 K >= K0       (K2)
 *   shear, HG = 2HG / 2, knee g0 (DRAPE_FABRIC_KES_G0):
 *     F(g) = (G + 2 HG / g0 - D) g + ((D - HG / g0) / g0) g^2   g < g0 (S1)
 *     F(g) = G g + o(g - g0), o(t) = HG + D t + (D / h) t^2 - (D / h^2) t^3
 *                                                       g0 <= g < g5 (S2)
 *     F(g) = G g + HG5                                  g >= g5      (S3)
 *   with HG5 = 2HG5 / 2, g5 = 5 deg, h = g5 - g0 and D = (HG5 - HG) / h;
 *   without 2HG5, D = 0 and S2, S3 merge into F = G g + HG.
 *   Each fit has M(0) = 0 and is C1 (value and slope match at the knees).
 *
 * References: Kawabata S. (1980) The standardization and analysis of hand
 * evaluation, 2nd ed., Textile Machinery Society of Japan; Breen, House &
 * Wozny (1994); Chen & Xu (2000) eqs. 2-5.
 */
#include "drape/fabric.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_poly.h>

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/units.h"
#include "drape/yamldoc.h"
#include "yread.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Relative tolerance for the knot checks: a value jump larger than this
 * times the largest |value| at any knot of the fit is an error; a slope
 * jump larger than this times the largest |slope| at any knot is a warning.
 * Breen's printed 8-digit coefficients meet at 1e-8..6e-8. */
#define DRAPE_FABRIC_KNOT_RTOL 1e-6

/* KES knees (docs/fabrics.md): K0 = 0.5 1/cm, the lower end of the range
 * 0.5..1.5 1/cm over which KES-FB2 takes the slope B; g0 = 0.5 deg, where
 * KES-FB1 reads 2HG, and g5 = 5 deg, where it reads 2HG5 (G is the slope
 * between them). */
#define DRAPE_FABRIC_KES_K0 50.0                      /* 1/m */
#define DRAPE_FABRIC_KES_G0 (0.5 * M_PI / 180.0)      /* rad */
#define DRAPE_FABRIC_KES_G5 (5.0 * M_PI / 180.0)      /* rad */

/* Values far outside any textile (docs/fabrics.md, "Plausible values"):
 * accepted, but warned about, since they are most likely a wrong unit or
 * exponent (`20 g/cm^2` for 20 mg/cm^2) and otherwise fail only in the
 * run.  Each bound is at least 10x beyond every shipped fabric (weights
 * 113..324 g/m^2, tensile stiffness 33..10000 N/m). */
#define DRAPE_FABRIC_WEIGHT_LO 5e-3  /* kg/m^2 (5 g/m^2) */
#define DRAPE_FABRIC_WEIGHT_HI 5.0   /* kg/m^2 (5000 g/m^2) */
#define DRAPE_FABRIC_K_LO 1.0        /* N/m */
#define DRAPE_FABRIC_K_HI 1e7        /* N/m */

/* ------------------------------------------------------------ fits */

/* The unit block of a fit: scales to SI for x and y. */
typedef struct fit_units {
    double sx, sy;
    char xname[64], yname[64]; /* as written, for messages */
} fit_units;

/* Where the fit is not positive for x > 0, or 0 where it is positive
 * throughout (*piece is then untouched).  Each piece is tested between its
 * real roots inside its interval (GSL's companion-matrix solver) at the
 * midpoints, and past its last root, for the last piece, by the sign of
 * its leading coefficient: exact up to rounding, where a grid of points
 * can step over a dip.  -1 if GSL runs out of memory. */
static int fit_nonpositive(const drape_fit *fit, double *where, int *piece)
{
    for (int k = 0; k < fit->n; k++) {
        const drape_fit_piece *p = &fit->p[k];
        double a = k == 0 ? 0.0 : p->from, b = p->to;
        int deg = p->ncoef - 1;
        while (deg > 0 && p->c[deg] == 0.0) deg--;
        double pts[DRAPE_FIT_MAX_COEFS + 2];
        int np = 0;
        pts[np++] = a;
        if (deg >= 1) {
            double z[2 * (DRAPE_FIT_MAX_COEFS - 1)];
            /* GSL's default handler aborts: off here, as the caller had it */
            gsl_error_handler_t *old = gsl_set_error_handler_off();
            gsl_poly_complex_workspace *ws = gsl_poly_complex_workspace_alloc((size_t)deg + 1);
            int rc = ws ? gsl_poly_complex_solve(p->c, (size_t)deg + 1, ws, z) : GSL_ENOMEM;
            if (ws) gsl_poly_complex_workspace_free(ws);
            gsl_set_error_handler(old);
            if (rc == GSL_ENOMEM) return -1;
            for (int i = 0; rc == GSL_SUCCESS && i < deg; i++) {
                double re = z[2 * i], im = z[2 * i + 1];
                if (fabs(im) > 1e-9 * fmax(1.0, fabs(re)) || !(re > a && re < b)) continue;
                int j = np++; /* insertion, sorted */
                while (j > 1 && pts[j - 1] > re) { pts[j] = pts[j - 1]; j--; }
                pts[j] = re;
            }
        }
        if (isfinite(b)) pts[np++] = b;
        for (int i = 0; i + 1 < np; i++) {
            double x = 0.5 * (pts[i] + pts[i + 1]);
            if (!(drape_fit_piece_value(p, x) > 0.0)) {
                *where = x;
                *piece = k;
                return 1;
            }
        }
        if (!isfinite(b) && !(p->c[deg] > 0.0)) { /* beyond its last root */
            *where = INFINITY;
            *piece = k;
            return 1;
        }
    }
    return 0;
}

/* The slope jumps at the knots of the bending curves, gathered so that a
 * file whose curves all have them (the tabulated curves of `drape import
 * arcsim`, a stiffness interpolated linearly between measured points, so
 * that the moment K k(K) is continuous and its slope is not) gets one
 * line, not one per knot: how many, and the largest with its place. */
typedef struct knot_jumps {
    int n;                          /* knots whose slope jumps */
    int curves;                     /* bit k: curve k (warp, weft, bias) has one */
    double pct;                     /* the largest, % of its curve's largest slope */
    const drape_ynode *node;        /* its piece */
    char path[DRAPE_YREAD_PATH_MAX];
    double x, sl, sr;               /* its knot (file units), slopes before and after */
    char xname[64];
} knot_jumps;

/* Read one list of pieces (`bending.warp`) into *fit in the file's units,
 * check it (docs/model.md 3.4), and convert it to SI.  Slope jumps at knots
 * are warned about one by one, or, with kj, gathered into *kj (curve: its
 * bit in kj->curves). */
static int get_fit(const drape_yread *r, const drape_ynode *list,
                   const char *path, const fit_units *u,
                   const char *yquantity, drape_fit *fit, knot_jumps *kj, int curve)
{
    static const char *const piece_keys[] = {"from", "to", "poly", NULL};
    const drape_ynode *to_node[DRAPE_FIT_MAX_PIECES];
    char kp[DRAPE_YREAD_PATH_MAX], pp[DRAPE_YREAD_PATH_MAX];

    memset(fit, 0, sizeof *fit);
    if (drape_yread_want(r, list, path, DRAPE_YNODE_SEQUENCE,
                         "a list of pieces {from, to, poly}"))
        return -1;
    if (list->n == 0)
        return drape_yread_error(r, list, path, DRAPE_E_INPUT,
                                 "empty list: give at least one piece "
                                 "{from: 0, poly: [...]}");
    if (list->n > DRAPE_FIT_MAX_PIECES) {
        drape_yread_item_path(pp, sizeof pp, path, DRAPE_FIT_MAX_PIECES);
        return drape_yread_error(r, list->items[DRAPE_FIT_MAX_PIECES], pp,
                                 DRAPE_E_INPUT,
                                 "too many pieces (%zu; at most %d)", list->n,
                                 DRAPE_FIT_MAX_PIECES);
    }
    fit->n = (int)list->n;
    for (size_t i = 0; i < list->n; i++) {
        const drape_ynode *pn = list->items[i];
        drape_fit_piece *p = &fit->p[i];
        int last = i + 1 == list->n;
        drape_yread_item_path(pp, sizeof pp, path, i);
        if (drape_yread_want(r, pn, pp, DRAPE_YNODE_MAPPING,
                             "a piece {from: ..., to: ..., poly: [...]}") ||
            drape_ynode_check_keys(r->doc, pn, pp, piece_keys, r->err))
            return -1;
        const drape_ynode *from =
            drape_yread_need(r, pn, pp, "from", "from: 0");
        if (!from) return -1;
        drape_yread_path(kp, sizeof kp, pp, "from");
        if (drape_yread_number(r, from, kp, DRAPE_YREAD_NONNEGATIVE, &p->from))
            return -1;
        const drape_ynode *to = drape_ynode_get(pn, "to", NULL);
        to_node[i] = to;
        p->to = INFINITY;
        if (to) {
            drape_yread_path(kp, sizeof kp, pp, "to");
            if (drape_yread_number(r, to, kp, DRAPE_YREAD_ANY, &p->to))
                return -1;
            if (!(p->to > p->from))
                return drape_yread_error(r, to, kp, DRAPE_E_INPUT,
                                         "`to` (%s) must be greater than "
                                         "`from` (%s)", to->scalar,
                                         from->scalar);
        } else if (!last) {
            return drape_yread_error(r, pn, pp, DRAPE_E_INPUT,
                                     "missing key `to`: only the last piece "
                                     "may leave it out (it extends to "
                                     "infinity)");
        }
        const drape_ynode *poly =
            drape_yread_need(r, pn, pp, "poly", "poly: [0, 1]");
        if (!poly) return -1;
        drape_yread_path(kp, sizeof kp, pp, "poly");
        if (drape_yread_want(r, poly, kp, DRAPE_YNODE_SEQUENCE,
                             "a list of coefficients in ascending powers"))
            return -1;
        if (poly->n == 0)
            return drape_yread_error(r, poly, kp, DRAPE_E_INPUT,
                                     "no coefficients");
        if (poly->n > DRAPE_FIT_MAX_COEFS)
            return drape_yread_error(r, poly, kp, DRAPE_E_INPUT,
                                     "too many coefficients (%zu; at most %d, "
                                     "degree %d)", poly->n,
                                     DRAPE_FIT_MAX_COEFS,
                                     DRAPE_FIT_MAX_COEFS - 1);
        p->ncoef = (int)poly->n;
        for (size_t k = 0; k < poly->n; k++) {
            char cp[DRAPE_YREAD_PATH_MAX];
            drape_yread_item_path(cp, sizeof cp, kp, k);
            if (drape_yread_number(r, poly->items[k], cp, DRAPE_YREAD_ANY,
                                   &p->c[k]))
                return -1;
        }
        /* placement */
        drape_yread_path(kp, sizeof kp, pp, "from");
        if (i == 0 && p->from != 0.0)
            return drape_yread_error(r, from, kp, DRAPE_E_INPUT,
                                     "the first piece must start at 0, not %s",
                                     from->scalar);
        if (i > 0) {
            const drape_fit_piece *q = &fit->p[i - 1];
            if (p->from > q->to)
                return drape_yread_error(r, from, kp, DRAPE_E_INPUT,
                                         "gap between %s[%zu] (to %s) and "
                                         "%s[%zu] (from %s): pieces must be "
                                         "consecutive", path, i - 1,
                                         to_node[i - 1]->scalar, path, i,
                                         from->scalar);
            if (p->from < q->to)
                return drape_yread_error(r, from, kp, DRAPE_E_INPUT,
                                         "%s[%zu] (from %s) overlaps %s[%zu] "
                                         "(to %s): pieces must be "
                                         "consecutive", path, i, from->scalar,
                                         path, i - 1, to_node[i - 1]->scalar);
        }
    }
    /* the last piece extends to infinity (docs/model.md 3.4) */
    if (to_node[fit->n - 1]) {
        snprintf(pp, sizeof pp, "%s[%d].to", path, fit->n - 1);
        drape_yread_warn(r, to_node[fit->n - 1], pp,
                         "the last piece ends at %s but is extended to "
                         "infinity (docs/model.md 3.4)",
                         to_node[fit->n - 1]->scalar);
        fit->p[fit->n - 1].to = INFINITY;
    }
    /* M(0) = 0 (numerics.md 4.3) */
    if (fit->p[0].c[0] != 0.0) {
        const drape_ynode *c0 =
            drape_ynode_get(list->items[0], "poly", NULL)->items[0];
        snprintf(pp, sizeof pp, "%s[0].poly[0]", path);
        return drape_yread_error(r, c0, pp, DRAPE_E_INPUT,
                                 "the %s at 0 must be 0, got %s %s: a fit "
                                 "with a non-zero value at 0 makes the energy "
                                 "a cone at the flat state (numerics.md 4.3)",
                                 yquantity, c0->scalar, u->yname);
    }
    /* knots: value jumps are errors, slope jumps warnings */
    double vscale = 0.0, sscale = 0.0;
    for (int i = 1; i < fit->n; i++) {
        double x = fit->p[i].from;
        const drape_fit_piece *a = &fit->p[i - 1], *b = &fit->p[i];
        vscale = fmax(vscale, fmax(fabs(drape_fit_piece_value(a, x)),
                                   fabs(drape_fit_piece_value(b, x))));
        sscale = fmax(sscale, fmax(fabs(drape_fit_piece_slope(a, x)),
                                   fabs(drape_fit_piece_slope(b, x))));
    }
    for (int i = 1; i < fit->n; i++) {
        double x = fit->p[i].from;
        const drape_fit_piece *a = &fit->p[i - 1], *b = &fit->p[i];
        double yl = drape_fit_piece_value(a, x), yr = drape_fit_piece_value(b, x);
        double sl = drape_fit_piece_slope(a, x), sr = drape_fit_piece_slope(b, x);
        drape_yread_item_path(pp, sizeof pp, path, (size_t)i);
        if (fabs(yr - yl) > DRAPE_FABRIC_KNOT_RTOL * vscale)
            return drape_yread_error(
                r, list->items[i], pp, DRAPE_E_INPUT,
                "the %s jumps at the knot %.9g %s: %.9g %s at the end of "
                "%s[%d], %.9g at the start of %s[%d] (jump %.3g %s, %.2g%% of "
                "the largest value at a knot; the tolerance is %g%%)",
                yquantity, x, u->xname, yl, u->yname, path, i - 1, yr, path,
                i, yr - yl, u->yname, 100 * fabs(yr - yl) / vscale,
                100 * DRAPE_FABRIC_KNOT_RTOL);
        if (fabs(sr - sl) > DRAPE_FABRIC_KNOT_RTOL * sscale && kj) {
            double pct = 100 * fabs(sr - sl) / sscale;
            kj->n++;
            kj->curves |= 1 << curve;
            if (kj->n == 1 || pct > kj->pct) {
                kj->pct = pct;
                kj->node = list->items[i];
                snprintf(kj->path, sizeof kj->path, "%s", pp);
                kj->x = x;
                kj->sl = sl;
                kj->sr = sr;
                snprintf(kj->xname, sizeof kj->xname, "%s", u->xname);
            }
        } else if (fabs(sr - sl) > DRAPE_FABRIC_KNOT_RTOL * sscale)
            drape_yread_warn(r, list->items[i], pp,
                             "the slope of the %s jumps at the knot %.9g %s: "
                             "%.9g before, %.9g after (%.2g%% of the largest "
                             "slope at a knot); the fit is not C1 there",
                             yquantity, x, u->xname, sl, sr,
                             100 * fabs(sr - sl) / sscale);
    }
    /* a moment or force that opposes the bending or shear: a rigidity
     * (slope at 0) above 0 and a value above 0 for every x > 0 (the KES
     * path asks B > 0 and G > 0 likewise); a fit that turns negative,
     * even past its data, drives the cloth the wrong way where it folds */
    double s0 = drape_fit_piece_slope(&fit->p[0], 0.0);
    if (!(s0 > 0.0)) {
        snprintf(pp, sizeof pp, "%s[0].poly", path);
        return drape_yread_error(r, drape_ynode_get(list->items[0], "poly", NULL), pp,
                                 DRAPE_E_INPUT,
                                 "the %s must rise from 0: its slope at 0 (the rigidity) "
                                 "is %g %s per %s, expected > 0", yquantity, s0, u->yname,
                                 u->xname);
    }
    double bad;
    int bk = 0, nz = fit_nonpositive(fit, &bad, &bk);
    if (nz < 0)
        return drape_yread_error(r, list, path, DRAPE_E_NOMEM, "out of memory");
    if (nz > 0) {
        drape_yread_item_path(pp, sizeof pp, path, (size_t)bk);
        if (isinf(bad))
            return drape_yread_error(r, list->items[bk], pp, DRAPE_E_INPUT,
                                     "the %s turns negative for large %s (the last piece's "
                                     "leading coefficient is not positive): it must oppose "
                                     "the deformation for every %s > 0", yquantity,
                                     u->xname, u->xname);
        return drape_yread_error(r, list->items[bk], pp, DRAPE_E_INPUT,
                                 "the %s is not positive at %.6g %s (%.6g %s): it must "
                                 "oppose the deformation for every %s > 0", yquantity, bad,
                                 u->xname, drape_fit_piece_value(&fit->p[bk], bad), u->yname,
                                 u->xname);
    }
    drape_fit_scale(fit, u->sx, u->sy);
    drape_fit_prepare(fit);
    return 0;
}

/* The unit under key in the units block un (key path kp): its SI scale
 * and its name as written; unit is an example for the message when the
 * key is missing. */
static int get_unit(const drape_yread *r, const drape_ynode *un,
                    const char *kp, const char *key, const char *unit,
                    drape_dim dim, const char *noun, double *scale,
                    char *name, size_t nname)
{
    char up[DRAPE_YREAD_PATH_MAX], example[64];
    snprintf(example, sizeof example, "%s: %s", key, unit);
    const drape_ynode *n = drape_yread_need(r, un, kp, key, example);
    if (!n) return -1;
    drape_yread_path(up, sizeof up, kp, key);
    if (drape_yread_unit(r, n, up, dim, noun, scale)) return -1;
    snprintf(name, nname, "%s", n->scalar);
    return 0;
}

/* The units block of bending {curvature, moment} or shear {angle, force}. */
static int get_units_block(const drape_yread *r, const drape_ynode *map,
                           const char *path, int bending, fit_units *u)
{
    static const char *const keys_bend[] = {"curvature", "moment", NULL};
    static const char *const keys_shear[] = {"angle", "force", NULL};
    const char *block = bending ? "{curvature: 1/cm, moment: gf.cm/cm}"
                                : "{angle: rad, force: gf/cm}";
    char kp[DRAPE_YREAD_PATH_MAX], example[64], expected[64];
    snprintf(example, sizeof example, "units: %s", block);
    snprintf(expected, sizeof expected, "a mapping %s", block);
    drape_yread_path(kp, sizeof kp, path, "units");
    const drape_ynode *un = drape_yread_need(r, map, path, "units", example);
    if (!un ||
        drape_yread_want(r, un, kp, DRAPE_YNODE_MAPPING, expected) ||
        drape_ynode_check_keys(r->doc, un, kp,
                               bending ? keys_bend : keys_shear, r->err))
        return -1;
    if (bending) {
        if (get_unit(r, un, kp, "curvature", "1/cm", DRAPE_DIM_CURVATURE,
                     "curvature (1/m, 1/cm)", &u->sx, u->xname,
                     sizeof u->xname) ||
            get_unit(r, un, kp, "moment", "gf.cm/cm", DRAPE_DIM_FORCE,
                     "moment per width (N.m/m, gf.cm/cm)", &u->sy, u->yname,
                     sizeof u->yname))
            return -1;
    } else if (get_unit(r, un, kp, "angle", "rad", DRAPE_DIM_NONE,
                        "angle (rad, deg)", &u->sx, u->xname,
                        sizeof u->xname) ||
               get_unit(r, un, kp, "force", "gf/cm",
                        DRAPE_DIM_FORCE_PER_LENGTH,
                        "force per length (N/m, gf/cm)", &u->sy, u->yname,
                        sizeof u->yname)) {
        return -1;
    }
    return 0;
}

/* The bias curve must be at least as stiff as the warp and weft hinges
 * alone make a 45-degree strip, B_bias >= (B_warp + B_weft) / 4 (the
 * twist rigidity B_bias - (B_warp + B_weft) / 4 is not negative), and the
 * twist energy it implies should be convex: checked on a grid of twist
 * curvatures up to twice the last knot (or 100 1/m). */
static int check_bias(const drape_yread *r, const drape_ynode *b,
                      const drape_fabric *f, double *twist_worst, double *twist_at)
{
    double Bb = drape_fit_slope(&f->bend_bias, 0.0);
    double Bs = 0.25 * (drape_fit_slope(&f->bend[DRAPE_WARP], 0.0) +
                        drape_fit_slope(&f->bend[DRAPE_WEFT], 0.0));
    if (!(Bb >= Bs))
        return drape_yread_error(
            r, b, "bending.bias", DRAPE_E_INPUT,
            "the bias rigidity %g N.m is below (B_warp + B_weft) / 4 = %g N.m, "
            "what the warp and weft hinges alone give a strip cut at 45 "
            "degrees: the twist rigidity would be negative", Bb, Bs);
    double tmax = 100.0;
    const drape_fit *fs[3] = {&f->bend_bias, &f->bend[DRAPE_WARP],
                              &f->bend[DRAPE_WEFT]};
    for (int k = 0; k < 3; k++) {
        const drape_fit *fk = fs[k];
        double last = fk->n > 1 ? fk->p[fk->n - 1].from : 0.0;
        if (2.0 * last > tmax) tmax = 2.0 * last;
    }
    double worst = 0.0, at = 0.0, scale = 4.0 * Bb;
    for (int i = 1; i <= 2000; i++) {
        double t = tmax * i / 2000.0, d2;
        drape_fabric_twist_energy(f, t, NULL, &d2);
        if (d2 < worst) { worst = d2; at = t; }
    }
    *twist_worst = worst < -1e-9 * scale ? worst : 0.0;
    *twist_at = at;
    return 0;
}

/* The bending curves' warnings: their slope jumps (kj) on one line, at
 * the piece where there is one jump, else at the `bending` block (bn)
 * with the largest named; and, on a line of its own at bending.bias (a
 * run without the bias term leaves it out), a twist energy that is not
 * convex (worst < 0 at tau = at). */
static void warn_bending(const drape_yread *r, const drape_ynode *bn, const drape_ynode *b,
                         const knot_jumps *kj, double worst, double at)
{
    static const char *const names[3] = {"warp", "weft", "bias"};
    char curves[32] = "";
    for (int k = 0, m = 0; k < 3; k++)
        if (kj->curves & (1 << k)) {
            size_t l = strlen(curves);
            snprintf(curves + l, sizeof curves - l, "%s%s", m++ ? ", " : "", names[k]);
        }
    if (kj->n == 1)
        drape_yread_warn(r, kj->node, kj->path,
                         "the slope of the bending moment jumps at the knot %.9g %s: "
                         "%.9g before, %.9g after (%.2g%% of the largest slope at a "
                         "knot); the fit is not C1 there",
                         kj->x, kj->xname, kj->sl, kj->sr, kj->pct);
    else if (kj->n > 1) {
        const char *piece = strrchr(kj->path, '.');
        drape_yread_warn(r, bn, "bending",
                         "the slope of the bending moment jumps at %d knots of %s, by up "
                         "to %.2g%% of a curve's largest slope at a knot (%s, at %.9g %s: "
                         "%.9g before, %.9g after): the fits are C0, not C1, as a "
                         "stiffness interpolated linearly between measured points makes "
                         "them (drape import arcsim); the moment and the energy stay "
                         "continuous, only the tangent stiffness jumps",
                         kj->n, curves, kj->pct, piece ? piece + 1 : kj->path, kj->x,
                         kj->xname, kj->sl, kj->sr);
    }
    if (worst < 0.0)
        drape_yread_warn(r, b, "bending.bias",
                         "the twist energy implied by the bias, warp and weft curves is not "
                         "convex: its stiffness Wt'' = 4 M_bias'(2 tau) - M_warp'(tau) - "
                         "M_weft'(tau) reaches %.3g N.m at tau = %.3g 1/m (negative: the "
                         "bias curve softens faster than the warp and weft curves; where "
                         "the folds reach that twist a rest state can be a saddle, which "
                         "the static solver reports)", worst, at);
}

/* A fit list for the example in "missing required key" messages. */
#define FIT_EXAMPLE "[{from: 0, poly: [0, 1]}]"

static int get_bending(const drape_yread *r, const drape_ynode *bn,
                       drape_fabric *f)
{
    static const char *const keys[] = {"units", "warp", "weft", "bias", NULL};
    fit_units u;
    if (drape_yread_want(r, bn, "bending", DRAPE_YNODE_MAPPING,
                         "a mapping {units, warp, weft[, bias]}") ||
        drape_ynode_check_keys(r->doc, bn, "bending", keys, r->err) ||
        get_units_block(r, bn, "bending", 1, &u))
        return -1;
    knot_jumps kj;
    memset(&kj, 0, sizeof kj);
    const drape_ynode *w =
        drape_yread_need(r, bn, "bending", "warp", "warp: " FIT_EXAMPLE);
    if (!w || get_fit(r, w, "bending.warp", &u, "bending moment",
                      &f->bend[DRAPE_WARP], &kj, 0))
        return -1;
    const drape_ynode *t =
        drape_yread_need(r, bn, "bending", "weft", "weft: " FIT_EXAMPLE);
    if (!t || get_fit(r, t, "bending.weft", &u, "bending moment",
                      &f->bend[DRAPE_WEFT], &kj, 1))
        return -1;
    const drape_ynode *b = drape_ynode_get(bn, "bias", NULL);
    double worst = 0.0, at = 0.0;
    if (b) {
        if (get_fit(r, b, "bending.bias", &u, "bending moment", &f->bend_bias, &kj, 2))
            return -1;
        f->has_bias = 1;
        if (check_bias(r, b, f, &worst, &at) != 0) return -1;
    }
    warn_bending(r, bn, b, &kj, worst, at);
    return 0;
}

static int get_shear(const drape_yread *r, const drape_ynode *sn,
                     drape_fabric *f)
{
    static const char *const keys[] = {"units", "warp", "weft", "curve", NULL};
    fit_units u;
    if (drape_yread_want(r, sn, "shear", DRAPE_YNODE_MAPPING,
                         "a mapping {units, warp, weft} or {units, curve}") ||
        drape_ynode_check_keys(r->doc, sn, "shear", keys, r->err) ||
        get_units_block(r, sn, "shear", 0, &u))
        return -1;
    const drape_ynode *curve = drape_ynode_get(sn, "curve", NULL);
    if (curve) {
        const drape_ynode *other = drape_ynode_get(sn, "warp", NULL);
        if (!other) other = drape_ynode_get(sn, "weft", NULL);
        if (other)
            return drape_yread_error(r, other, "shear", DRAPE_E_INPUT,
                                     "give either `curve` (one curve for both "
                                     "directions) or `warp` and `weft`, not "
                                     "both");
        if (get_fit(r, curve, "shear.curve", &u, "shear force",
                    &f->shear[DRAPE_WARP], NULL, 0))
            return -1;
        f->shear[DRAPE_WEFT] = f->shear[DRAPE_WARP];
        return 0;
    }
    const drape_ynode *w =
        drape_yread_need(r, sn, "shear", "warp", "warp: " FIT_EXAMPLE);
    if (!w || get_fit(r, w, "shear.warp", &u, "shear force",
                      &f->shear[DRAPE_WARP], NULL, 0))
        return -1;
    const drape_ynode *t =
        drape_yread_need(r, sn, "shear", "weft", "weft: " FIT_EXAMPLE);
    if (!t || get_fit(r, t, "shear.weft", &u, "shear force",
                      &f->shear[DRAPE_WEFT], NULL, 0))
        return -1;
    return 0;
}

/* ------------------------------------------------------------ KES-F */

/* Coefficients in powers of x of sum_k d[k] (x - x0)^k (n <= 4). */
static void shift_poly(const double *d, int n, double x0, double *c)
{
    static const double binom[4][4] = {
        {1, 0, 0, 0}, {1, 1, 0, 0}, {1, 2, 1, 0}, {1, 3, 3, 1}};
    for (int j = 0; j < n; j++) c[j] = 0.0;
    for (int k = 0; k < n; k++)
        for (int j = 0; j <= k; j++)
            c[j] += d[k] * binom[k][j] * pow(-x0, k - j);
}

/* Bending fit from B (N.m) and 2HB (N.m/m), eqs. K1, K2. */
static void kes_bending(double B, double hb2, drape_fit *fit)
{
    const double K0 = DRAPE_FABRIC_KES_K0, HB = hb2 / 2.0;
    memset(fit, 0, sizeof *fit);
    if (HB == 0.0) {
        fit->n = 1;
        fit->p[0] = (drape_fit_piece){0.0, INFINITY, 2, {0.0, B}};
    } else {
        fit->n = 2;
        fit->p[0] = (drape_fit_piece){
            0.0, K0, 3, {0.0, B + 2.0 * HB / K0, -HB / (K0 * K0)}};
        fit->p[1] = (drape_fit_piece){K0, INFINITY, 2, {HB, B}};
    }
    drape_fit_prepare(fit);
}

/* Shear fit from G (N/m per rad), 2HG and 2HG5 (N/m; < 0 if absent),
 * eqs. S1-S3. */
static void kes_shear(double G, double hg2, double hg52, drape_fit *fit)
{
    const double g0 = DRAPE_FABRIC_KES_G0, g5 = DRAPE_FABRIC_KES_G5;
    const double HG = hg2 > 0 ? hg2 / 2.0 : 0.0;
    memset(fit, 0, sizeof *fit);
    if (HG == 0.0) {
        fit->n = 1;
        fit->p[0] = (drape_fit_piece){0.0, INFINITY, 2, {0.0, G}};
        drape_fit_prepare(fit);
        return;
    }
    const double h = g5 - g0;
    const double D = hg52 >= 0 ? (hg52 / 2.0 - HG) / h : 0.0;
    fit->p[0] = (drape_fit_piece){
        0.0, g0, 3, {0.0, G + 2.0 * HG / g0 - D, (D - HG / g0) / g0}};
    if (D == 0.0) {
        fit->n = 2;
        fit->p[1] = (drape_fit_piece){g0, INFINITY, 2, {HG, G}};
    } else {
        fit->n = 3;
        double d[4] = {HG, D, D / h, -D / (h * h)}; /* o(t), t = g - g0 */
        fit->p[1].from = g0;
        fit->p[1].to = g5;
        fit->p[1].ncoef = 4;
        shift_poly(d, 4, g0, fit->p[1].c);
        fit->p[1].c[1] += G;
        fit->p[2] = (drape_fit_piece){g5, INFINITY, 2, {HG + D * h, G}};
    }
    drape_fit_prepare(fit);
}

/* The G unit must say "per angle": a bare "gf/cm" would silently be read
 * per radian, 57 times the KES value per degree.  Angles are dimensionless
 * to the unit parser, so "gf/cm.deg" (= gf deg / cm) or "gf/cm/deg^2" would
 * pass its dimension check with a scale off by (180/pi)^2 or 180/pi: the
 * unit must end in "/deg" or "/rad", its only angle. */
static int has_angle_unit(const char *s)
{
    size_t n = strlen(s);
    while (n > 0 && (s[n - 1] == ' ' || s[n - 1] == '\t')) n--;
    int angles = 0;
    for (const char *p = s; (p = strstr(p, "deg")) != NULL; p += 3) angles++;
    for (const char *p = s; (p = strstr(p, "rad")) != NULL; p += 3) angles++;
    return angles == 1 && n >= 4 &&
           (strncmp(s + n - 4, "/deg", 4) == 0 ||
            strncmp(s + n - 4, "/rad", 4) == 0);
}

static int has_letter(const char *s)
{
    for (; *s; s++)
        if (isalpha((unsigned char)*s)) return 1;
    return 0;
}

static int get_kes(const drape_yread *r, const drape_ynode *kn,
                   drape_fabric *f)
{
    static const char *const keys[] = {"warp", "weft", NULL};
    static const char *const dkeys[] = {"B", "2HB", "G", "2HG", "2HG5", NULL};
    static const char *const dname[2] = {"weft", "warp"};
    static const char *const example[2] = {
        "weft: {B: 0.085 gf.cm^2/cm, G: 0.9 gf/cm/deg}",
        "warp: {B: 0.085 gf.cm^2/cm, G: 0.9 gf/cm/deg}"};
    const int pos = DRAPE_YREAD_POSITIVE, nonneg = DRAPE_YREAD_NONNEGATIVE;
    const drape_dim fpl = DRAPE_DIM_FORCE_PER_LENGTH;
    char pp[DRAPE_YREAD_PATH_MAX], kp[DRAPE_YREAD_PATH_MAX];
    if (drape_yread_want(r, kn, "kes", DRAPE_YNODE_MAPPING,
                         "a mapping {warp: {B, 2HB, G, 2HG}, weft: {...}}") ||
        drape_ynode_check_keys(r->doc, kn, "kes", keys, r->err))
        return -1;
    for (int d = DRAPE_WARP; d >= DRAPE_WEFT; d--) {
        double B, hb2 = 0.0, G, hg2 = -1.0, hg52 = -1.0;
        const drape_ynode *g, *v;
        const drape_ynode *dn =
            drape_yread_need(r, kn, "kes", dname[d], example[d]);
        if (!dn) return -1;
        drape_yread_path(pp, sizeof pp, "kes", dname[d]);
        if (drape_yread_want(r, dn, pp, DRAPE_YNODE_MAPPING,
                             "a mapping {B, 2HB, G, 2HG, 2HG5}") ||
            drape_ynode_check_keys(r->doc, dn, pp, dkeys, r->err))
            return -1;
        /* B: gf.cm^2/cm = moment per width per curvature = N.m */
        if (drape_yread_req_quantity(r, dn, pp, "B", DRAPE_DIM_MOMENT,
                                     "bending rigidity", pos,
                                     "B: 0.085 gf.cm^2/cm", &B, NULL) ||
            drape_yread_opt_quantity(r, dn, pp, "2HB", DRAPE_DIM_FORCE,
                                     "bending hysteresis", nonneg, &hb2,
                                     NULL) ||
            drape_yread_req_quantity(r, dn, pp, "G", fpl, "shear rigidity", pos,
                                     "G: 0.9 gf/cm/deg", &G, &g))
            return -1;
        drape_yread_path(kp, sizeof kp, pp, "G");
        if (!has_angle_unit(g->scalar) && has_letter(g->scalar))
            return drape_yread_error(r, g, kp, DRAPE_E_INPUT,
                                     "G is a force per length per angle: "
                                     "write the angle unit, last and once, "
                                     "e.g. \"0.9 gf/cm/deg\" (KES) or "
                                     "\"... N/m/rad\", got \"%s\"",
                                     g->scalar);
        if (drape_yread_opt_quantity(r, dn, pp, "2HG", fpl, "shear hysteresis",
                                     nonneg, &hg2, NULL) ||
            drape_yread_opt_quantity(r, dn, pp, "2HG5", fpl,
                                     "shear hysteresis", nonneg, &hg52, &v))
            return -1;
        if (v) {
            drape_yread_path(kp, sizeof kp, pp, "2HG5");
            if (hg2 <= 0)
                return drape_yread_error(r, v, kp, DRAPE_E_INPUT,
                                         "2HG5 needs a positive 2HG (the "
                                         "hysteresis at 0.5 deg) as well");
            if (hg52 < hg2)
                return drape_yread_error(r, v, kp, DRAPE_E_INPUT,
                                         "2HG5 (hysteresis at 5 deg) is "
                                         "smaller than 2HG (at 0.5 deg); the "
                                         "construction needs 2HG5 >= 2HG");
        }
        /* the widths of the loops are forces (moments) per length, not
         * per angle: an angle unit there (dimensionless to the unit parser)
         * scaled them by 57 or 1/57 unseen */
        static const char *const no_angle[] = {"B", "2HB", "2HG", "2HG5"};
        for (int i = 0; i < 4; i++) {
            const drape_ynode *q = drape_ynode_get(dn, no_angle[i], NULL);
            if (q && q->type == DRAPE_YNODE_SCALAR &&
                (strstr(q->scalar, "deg") || strstr(q->scalar, "rad"))) {
                drape_yread_path(kp, sizeof kp, pp, no_angle[i]);
                return drape_yread_error(r, q, kp, DRAPE_E_INPUT,
                                         "%s takes no angle unit (KES gives it per length "
                                         "or per width: gf/cm, gf.cm/cm, gf.cm^2/cm), got "
                                         "\"%s\"", no_angle[i], q->scalar);
            }
        }
        kes_bending(B, hb2, &f->bend[d]);
        kes_shear(G, hg2, hg52, &f->shear[d]);
    }
    f->from_kes = 1;
    return 0;
}

/* ------------------------------------------------------------ stiffness */

/* A tensile stiffness (force per length, > 0). */
static int get_k(const drape_yread *r, const drape_ynode *n, const char *path,
                 double *out)
{
    if (drape_yread_quantity(r, n, path, DRAPE_DIM_FORCE_PER_LENGTH,
                             "tensile stiffness", DRAPE_YREAD_POSITIVE, out))
        return -1;
    if (*out < DRAPE_FABRIC_K_LO || *out > DRAPE_FABRIC_K_HI)
        drape_yread_warn(r, n, path,
                         "%g N/m lies far outside the tensile stiffness of any "
                         "textile (%g to %g N/m, docs/fabrics.md): check the "
                         "value and its unit", *out, DRAPE_FABRIC_K_LO,
                         DRAPE_FABRIC_K_HI);
    return 0;
}

/* `damping: {shear: T}` (docs/model.md 3.6): the fabric's internal shear
 * damping, a time; DRAPE_FABRIC_DAMPING_SHEAR when the key is absent. */
static int get_damping(const drape_yread *r, const drape_ynode *root,
                       drape_fabric *f)
{
    static const char *const keys[] = {"shear", NULL};
    const drape_ynode *m = drape_ynode_get(root, "damping", NULL);
    f->damping_shear = DRAPE_FABRIC_DAMPING_SHEAR;
    if (!m) return 0;
    if (drape_yread_want_map(r, m, "damping") ||
        drape_ynode_check_keys(r->doc, m, "damping", keys, r->err) ||
        drape_yread_opt_quantity(r, m, "damping", "shear", DRAPE_DIM_TIME,
                                 "time (s)", DRAPE_YREAD_NONNEGATIVE,
                                 &f->damping_shear, NULL))
        return -1;
    return 0;
}

static int get_stiffness(const drape_yread *r, const drape_ynode *root,
                         drape_fabric *f)
{
    static const char *const keys[] = {"warp", "weft", NULL};
    const drape_ynode *ts = drape_ynode_get(root, "tensile_stiffness", NULL);
    const drape_ynode *kw = drape_ynode_get(root, "k_warp", NULL);
    const drape_ynode *kf = drape_ynode_get(root, "k_weft", NULL);
    if (ts && (kw || kf))
        return drape_yread_error(r, kw ? kw : kf, kw ? "k_warp" : "k_weft",
                                 DRAPE_E_INPUT,
                                 "give either `tensile_stiffness` or `k_warp` "
                                 "and `k_weft`, not both");
    if (kw || kf) {
        if (!kw)
            return drape_yread_error(r, root, "k_warp", DRAPE_E_INPUT,
                                     "missing key `k_warp` (`k_weft` is "
                                     "given)");
        if (!kf)
            return drape_yread_error(r, root, "k_weft", DRAPE_E_INPUT,
                                     "missing key `k_weft` (`k_warp` is "
                                     "given)");
        if (get_k(r, kw, "k_warp", &f->k[DRAPE_WARP]) ||
            get_k(r, kf, "k_weft", &f->k[DRAPE_WEFT]))
            return -1;
        return 0;
    }
    if (!ts)
        return drape_yread_error(r, root, "tensile_stiffness", DRAPE_E_INPUT,
                                 "missing key `tensile_stiffness` (or `k_warp` "
                                 "and `k_weft`)");
    if (ts->type == DRAPE_YNODE_MAPPING) {
        const drape_ynode *w, *t;
        if (drape_ynode_check_keys(r->doc, ts, "tensile_stiffness", keys,
                                   r->err) ||
            !(w = drape_yread_need(r, ts, "tensile_stiffness", "warp",
                                   "warp: 10000 N/m")) ||
            !(t = drape_yread_need(r, ts, "tensile_stiffness", "weft",
                                   "weft: 10000 N/m")))
            return -1;
        if (get_k(r, w, "tensile_stiffness.warp", &f->k[DRAPE_WARP]) ||
            get_k(r, t, "tensile_stiffness.weft", &f->k[DRAPE_WEFT]))
            return -1;
        return 0;
    }
    if (get_k(r, ts, "tensile_stiffness", &f->k[DRAPE_WARP])) return -1;
    f->k[DRAPE_WEFT] = f->k[DRAPE_WARP];
    return 0;
}

/* ------------------------------------------------------------ load */

int drape_fabric_load(const char *path, drape_fabric *out, drape_error *err,
                      drape_warn_fn warn, void *warn_ctx)
{
    static const char *const keys[] = {
        "fabric", "description", "source", "weight", "tensile_stiffness",
        "k_warp", "k_weft", "bending", "shear", "kes", "damping", NULL};
    drape_yread r = {NULL, err, 0u, warn, warn_ctx};
    drape_fabric *f = NULL;
    drape_ydoc *doc = NULL;
    const drape_ynode *root, *n;
    int rc = -1;

    doc = drape_ydoc_load(path, err);
    if (!doc) goto out;
    r.doc = doc;
    root = doc->root;
    f = drape_calloc(1, sizeof *f);
    if (!f) {
        drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL,
                        "out of memory");
        goto out;
    }
    snprintf(f->path, sizeof f->path, "%s", path);
    if (drape_ynode_check_keys(doc, root, "", keys, err)) goto out;

    if (!(n = drape_yread_need(&r, root, "", "fabric",
                               "fabric: cotton-breen")) ||
        drape_yread_text(&r, n, "fabric", 1, f->name, sizeof f->name))
        goto out;
    if ((n = drape_ynode_get(root, "description", NULL)) &&
        drape_yread_text(&r, n, "description", 0, f->description,
                         sizeof f->description))
        goto out;
    if ((n = drape_ynode_get(root, "source", NULL)) &&
        drape_yread_text(&r, n, "source", 0, f->source, sizeof f->source))
        goto out;
    const drape_ynode *wn = NULL;
    if (drape_yread_req_quantity(&r, root, "", "weight",
                                 DRAPE_DIM_AREAL_DENSITY, "areal density",
                                 DRAPE_YREAD_POSITIVE, "weight: 200 g/m^2",
                                 &f->weight, &wn))
        goto out;
    if (f->weight < DRAPE_FABRIC_WEIGHT_LO || f->weight > DRAPE_FABRIC_WEIGHT_HI)
        drape_yread_warn(&r, wn, "weight",
                         "%g g/m^2 lies far outside the weight of any textile "
                         "(%g to %g g/m^2, docs/fabrics.md): check the value "
                         "and its unit", f->weight * 1e3,
                         DRAPE_FABRIC_WEIGHT_LO * 1e3, DRAPE_FABRIC_WEIGHT_HI * 1e3);
    if (get_stiffness(&r, root, f)) goto out;
    if (get_damping(&r, root, f)) goto out;

    const drape_ynode *kes = drape_ynode_get(root, "kes", NULL);
    const drape_ynode *bend = drape_ynode_get(root, "bending", NULL);
    const drape_ynode *shear = drape_ynode_get(root, "shear", NULL);
    if (kes) {
        if (bend || shear) {
            drape_yread_error(&r, bend ? bend : shear,
                              bend ? "bending" : "shear", DRAPE_E_INPUT,
                              "give either `kes` or `bending` and `shear`, "
                              "not both");
            goto out;
        }
        if (get_kes(&r, kes, f)) goto out;
    } else {
        if (!bend) {
            drape_yread_error(&r, root, "bending", DRAPE_E_INPUT,
                              "missing key `bending` (or give KES-F values "
                              "under `kes`)");
            goto out;
        }
        if (!shear) {
            drape_yread_error(&r, root, "shear", DRAPE_E_INPUT,
                              "missing key `shear` (or give KES-F values "
                              "under `kes`)");
            goto out;
        }
        if (get_bending(&r, bend, f) || get_shear(&r, shear, f)) goto out;
    }
    if (drape_fit_mean(&f->shear[DRAPE_WEFT], &f->shear[DRAPE_WARP],
                       &f->shear_mean)) {
        drape_yread_error(&r, kes ? kes : shear, kes ? "kes" : "shear",
                          DRAPE_E_INPUT,
                          "the warp and weft shear fits have more than %d "
                          "distinct knots together; their mean cannot be "
                          "formed", DRAPE_FIT_MAX_PIECES);
        goto out;
    }
    *out = *f;
    rc = 0;
out:
    drape_free(f);
    drape_ydoc_free(doc);
    return rc;
}

double drape_fabric_bending_rigidity(const drape_fabric *f, drape_dir d)
{
    return drape_fit_slope(&f->bend[d], 0.0);
}

double drape_fabric_shear_rigidity(const drape_fabric *f)
{
    return drape_fit_slope(&f->shear_mean, 0.0);
}

double drape_fabric_twist_energy(const drape_fabric *f, double tau, double *d1,
                                 double *d2)
{
    if (!f->has_bias) {
        if (d1) *d1 = 0.0;
        if (d2) *d2 = 0.0;
        return 0.0;
    }
    double sg = tau < 0.0 ? -1.0 : 1.0, t = fabs(tau);
    const drape_fit *bb = &f->bend_bias, *bw = &f->bend[DRAPE_WARP],
                    *bf = &f->bend[DRAPE_WEFT];
    if (d1)
        *d1 = sg * (2.0 * drape_fit_value(bb, 2.0 * t) - drape_fit_value(bw, t) -
                    drape_fit_value(bf, t));
    if (d2)
        *d2 = 4.0 * drape_fit_slope(bb, 2.0 * t) - drape_fit_slope(bw, t) -
              drape_fit_slope(bf, t);
    return drape_fit_integral(bb, 2.0 * t) - drape_fit_integral(bw, t) -
           drape_fit_integral(bf, t);
}
