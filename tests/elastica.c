/* elastica.c: reference solutions for check_validation.c (test-only code,
 * not part of the drape library): the heavy cantilever elastica by
 * shooting, the elastic catenary in closed form, the hanging chain's
 * frequencies (continuum: Bernoulli's J0 modes; lumped: Sturm bisection),
 * and a least-squares fit of sums of sinusoids for reading frequencies off
 * a simulated time series.
 *
 * ---- Heavy cantilever ----
 *
 * Inextensible strip, linear bending M = B K, weight w = W g per unit
 * length (all per unit width), clamped horizontally at s = 0, free at
 * s = L.  theta(s) is the slope angle below horizontal, x(s) the reach,
 * d(s) the drop (positive down).  The bending moment at s is that of the
 * weight of the part beyond s about the point s:
 *
 *   M(s) = integral_s^L w (x(s') - x(s)) ds'                        (E1)
 *   B theta'(s) = M(s)                                             (E2)
 *   M'(s) = -w integral_s^L x'(s) ds' = -w (L - s) cos theta(s)     (E3)
 *   x' = cos theta,  d' = sin theta                                (E4)
 *   theta(0) = 0,  M(L) = 0,  x(0) = d(0) = 0.                     (E5)
 *
 * With t = s / L and mu = M L / B:
 *   theta_t = mu,  mu_t = -Gamma (1 - t) cos theta,  Gamma = w L^3 / B.
 *
 * Shooting: integrate from t = 0 with theta = 0, mu = mu0 (GSL rk8pd,
 * absolute and relative tolerance 1e-12) and find the root of
 * r(mu0) = mu(1) by Brent's method on [0, Gamma / 2].  In the physical
 * solution M > 0 on [0, L) and theta rises monotonically in [0, pi/2)
 * (then every x(s') > x(s) in (E1)).  For large Gamma, mu(1) = 0 has
 * further roots where the strip curls past the vertical or up above the
 * horizontal and round (|theta| > pi/2, where cos theta < 0 makes mu grow
 * again); so a shot whose theta leaves [0, pi/2] counts as too much
 * (theta > pi/2: r = +Gamma) or too little (theta < 0: r = -Gamma) clamp
 * moment.  Inside [0, pi/2], r(0) <= -Gamma int (1 - t) cos theta < 0 and
 * r(Gamma / 2) = Gamma int (1 - t) (1 - cos theta) > 0, so the bracket
 * holds and Brent finds the physical root.  Small Gamma: mu0 -> Gamma / 2 and the tip drop
 * -> Gamma / 8 (Euler-Bernoulli, w L^4 / (8 B)).
 *
 * Peirce's closed form (Peirce 1930, J. Textile Inst. 21 T377; ASTM D1388):
 * c = L (cos(theta/2) / (8 tan theta))^(1/3) with theta the chord angle;
 * the exact bending length c = (B / (W g))^(1/3) = L Gamma^(-1/3).
 *
 * ---- Elastic catenary (Irvine 1981, Cable Structures, MIT Press, 1.3) ----
 * Flexible cable, unstretched length l0, weight w per unit unstretched
 * length, tension T = k eps (eps = stretched / unstretched length - 1),
 * supports at the same height a distance l apart.  With H the constant
 * horizontal tension, V = w l0 / 2 and s the unstretched arc length from
 * the left support:
 *   T(s) = sqrt(H^2 + (V - w s)^2)                                  (C1)
 *   x(s) = H s / k + (H / w) [asinh(V / H) - asinh((V - w s) / H)]   (C2)
 *   z(s) = (V s - w s^2 / 2) / k
 *          + (H / w) [sqrt(1 + (V / H)^2) - sqrt(1 + ((V - w s) / H)^2)]  (C3)
 * (z downward), from dx/ds = (1 + T / k) H / T, dz/ds = (1 + T / k)
 * (V - w s) / T.  H solves x(l0) = l:
 *   H l0 / k + (2 H / w) asinh(w l0 / (2 H)) = l,                    (C4)
 * whose left side rises monotonically from 0 (H -> 0) to infinity; sag =
 * z(l0 / 2), support tension T(0).  As k -> infinity this is the common
 * catenary l0 = 2 a sinh(l / (2 a)), sag = a (cosh(l / (2 a)) - 1),
 * a = H / w.
 *
 * ---- Hanging chain (D. Bernoulli, 1732)
 * Small lateral motion u(y, t) of a flexible chain of weight w per unit
 * length and mass w / g, y measured up from the free end, tension w y:
 *   (w / g) u_tt = (w y u_y)_y;  u = f(y) cos(omega t) with
 *   f = J0(2 omega sqrt(y / g)) (bounded at y = 0), and the fixed top
 *   f(L) = 0 gives omega_n = (z_n / 2) sqrt(g / L), J0(z_n) = 0.
 * The lumped chain of elastica.h is solved exactly (to rounding) as the
 * eigenvalues of M^-1/2 K M^-1/2, a symmetric tridiagonal matrix, by Sturm
 * sequence bisection.
 *
 * ---- Sums of sinusoids
 * Variable projection (Golub & Pereyra 1973): the amplitudes enter
 * linearly and are eliminated by an exact linear least-squares solve (the
 * 2m x 2m normal equations by Cholesky), leaving m frequencies for
 * Nelder-Mead (GSL nmsimplex2).  A sampled pure cosine at omega is matched
 * exactly, so the fitted frequency carries no window or bin error; the
 * periodogram only supplies starting points.
 */
#include "elastica.h"

#include <math.h>

#include "drape/alloc.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_multimin.h>
#include <gsl/gsl_odeiv2.h>
#include <gsl/gsl_roots.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define ELASTICA_ODE_TOL 1e-12
#define ELASTICA_ROOT_TOL 1e-13
#define ELASTICA_MAX_ITER 200
/* Shooting from the clamp amplifies errors by about exp((2/3) sqrt(Gamma))
 * (near the vertical the deviation pi/2 - theta obeys Airy's equation
 * phi'' = Gamma (1 - t) phi, whose growing solution Bi sets the
 * sensitivity of mu(1) to mu0): 6e5 at Gamma = 400, where the tip slope
 * is within 1e-4 rad of the vertical. */
#define ELASTICA_GAMMA_MAX 400.0
/* Below this the shot's residual mu(1) ~ Gamma^3 is lost in rounding. */
#define ELASTICA_GAMMA_MIN 1e-6

static int rhs(double t, const double y[], double dydt[], void *params)
{
    double gamma = *(const double *)params;
    dydt[0] = y[1];
    dydt[1] = -gamma * (1.0 - t) * cos(y[0]);
    dydt[2] = cos(y[0]);
    dydt[3] = sin(y[0]);
    return GSL_SUCCESS;
}

/* Integrate from t = 0 to each of the n times ts[] (increasing, last 1)
 * with mu(0) = mu0; y_at (4 n, may be NULL) gets the state at each. */
static int shoot(double gamma, double mu0, int n, const double *ts,
                 double *y_at, double yend[4])
{
    gsl_odeiv2_system sys = {rhs, NULL, 4, &gamma};
    /* theta and mu scale with gamma when it is small */
    gsl_odeiv2_driver *d = gsl_odeiv2_driver_alloc_y_new(
        &sys, gsl_odeiv2_step_rk8pd, 1e-3, ELASTICA_ODE_TOL * fmin(1.0, gamma),
        ELASTICA_ODE_TOL);
    if (!d) return -1;
    double y[4] = {0.0, mu0, 0.0, 0.0}, t = 0.0;
    int rc = 0;
    for (int k = 0; k < n && rc == 0; k++) {
        if (ts[k] > t && gsl_odeiv2_driver_apply(d, &t, ts[k], y) != GSL_SUCCESS)
            rc = -1;
        if (y_at)
            for (int c = 0; c < 4; c++) y_at[4 * k + c] = y[c];
    }
    for (int c = 0; c < 4; c++) yend[c] = y[c];
    gsl_odeiv2_driver_free(d);
    return rc;
}

typedef struct residual_ctx {
    double gamma;
    int failed;
} residual_ctx;

/* mu(1) for mu(0) = mu0; +gamma (too much clamp moment) if the strip
 * turns past the vertical, -gamma (too little) if it turns up above the
 * horizontal (both checked at ELASTICA_CHECKS points). */
static double residual(double mu0, void *params)
{
    enum { ELASTICA_CHECKS = 256 };
    residual_ctx *c = params;
    double ts[ELASTICA_CHECKS], ys[4 * ELASTICA_CHECKS], y[4];
    for (int k = 0; k < ELASTICA_CHECKS; k++) ts[k] = (k + 1.0) / ELASTICA_CHECKS;
    if (shoot(c->gamma, mu0, ELASTICA_CHECKS, ts, ys, y) != 0) {
        c->failed = 1;
        return NAN;
    }
    for (int k = 0; k < ELASTICA_CHECKS; k++) {
        if (ys[4 * k] > 0.5 * M_PI) return c->gamma;
        if (ys[4 * k] < 0.0) return -c->gamma;
    }
    return y[1];
}

/* Brent on f over [lo, hi] (a sign change is assumed), absolute tolerance
 * epsabs, relative ELASTICA_ROOT_TOL. */
static int brent(gsl_function *f, double lo, double hi, double epsabs, double *root)
{
    gsl_root_fsolver *s = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    if (!s) return -1;
    int rc = -1;
    if (gsl_root_fsolver_set(s, f, lo, hi) != GSL_SUCCESS) goto out;
    for (int it = 0; it < ELASTICA_MAX_ITER; it++) {
        if (gsl_root_fsolver_iterate(s) != GSL_SUCCESS) goto out;
        double a = gsl_root_fsolver_x_lower(s), b = gsl_root_fsolver_x_upper(s);
        if (gsl_root_test_interval(a, b, epsabs, ELASTICA_ROOT_TOL) ==
            GSL_SUCCESS) {
            *root = gsl_root_fsolver_root(s);
            rc = 0;
            break;
        }
    }
out:
    gsl_root_fsolver_free(s);
    return rc;
}

static int solve_mu0(double gamma, double *mu0)
{
    gsl_set_error_handler_off();
    if (!(gamma >= ELASTICA_GAMMA_MIN) || gamma > ELASTICA_GAMMA_MAX) return -1;
    residual_ctx c = {gamma, 0};
    gsl_function f = {residual, &c};
    if (brent(&f, 0.0, 0.5 * gamma, ELASTICA_ROOT_TOL * fmin(1.0, gamma), mu0) != 0 ||
        c.failed)
        return -1;
    return 0;
}

int elastica_solve(double gamma, elastica_solution *out)
{
    double mu0, one = 1.0, y[4];
    if (solve_mu0(gamma, &mu0) != 0) return -1;
    if (shoot(gamma, mu0, 1, &one, NULL, y) != 0) return -1;
    out->gamma = gamma;
    out->mu0 = mu0;
    out->tip_slope = y[0];
    out->tip_x = y[2];
    out->tip_drop = y[3];
    out->chord = atan2(y[3], y[2]);
    out->ratio = y[3] / y[2];
    return 0;
}

int elastica_shape(double gamma, int n, double *x, double *drop)
{
    enum { NMAX = 4096 };
    static double ts[NMAX], ys[4 * NMAX];
    double mu0, y[4];
    if (n < 2 || n > NMAX) return -1;
    if (solve_mu0(gamma, &mu0) != 0) return -1;
    for (int k = 0; k < n; k++) ts[k] = (double)k / (n - 1);
    if (shoot(gamma, mu0, n, ts, ys, y) != 0) return -1;
    for (int k = 0; k < n; k++) {
        x[k] = ys[4 * k + 2];
        drop[k] = ys[4 * k + 3];
    }
    return 0;
}

/* ---- nonlinear moment curve ---- */

typedef struct curve_ctx {
    double L, w;
    elastica_moment_fn M;
    void *mctx;
    int failed;
    double s_at, x_at, d_at;
} curve_ctx;

/* K with M(K) = m (M odd and increasing): bracket, then bisection to
 * 1e-14 relative. */
static double curve_k(const curve_ctx *c, double m)
{
    if (m == 0.0) return 0.0;
    double sg = m < 0 ? -1.0 : 1.0, am = fabs(m), lo = 0.0, hi = 1.0;
    while (c->M(hi, c->mctx) < am && hi < 1e9) { lo = hi; hi *= 2.0; }
    for (int it = 0; it < 200 && hi - lo > 1e-14 * hi; it++) {
        double mid = 0.5 * (lo + hi);
        if (c->M(mid, c->mctx) < am) lo = mid;
        else hi = mid;
    }
    return sg * 0.5 * (lo + hi);
}

static int curve_rhs(double s, const double y[], double dydt[], void *params)
{
    const curve_ctx *c = params;
    dydt[0] = curve_k(c, y[1]);
    dydt[1] = -c->w * (c->L - s) * cos(y[0]);
    dydt[2] = cos(y[0]);
    dydt[3] = sin(y[0]);
    return GSL_SUCCESS;
}

/* m(L) for m(0) = m0, with the same out-of-range rule as residual(). */
static double curve_residual(double m0, void *params)
{
    enum { CHECKS = 128 };
    curve_ctx *c = params;
    gsl_odeiv2_system sys = {curve_rhs, NULL, 4, c};
    gsl_odeiv2_driver *d = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rkf45,
                                                         1e-4 * c->L, 1e-11, 1e-11);
    if (!d) { c->failed = 1; return NAN; }
    double y[4] = {0.0, m0, 0.0, 0.0}, s = 0.0, big = c->w * c->L * c->L;
    double r = NAN;
    int done_at = 0;
    for (int k = 1; k <= CHECKS; k++) {
        double sk = c->L * k / CHECKS;
        if (!done_at && c->s_at <= sk) {
            if (c->s_at > s && gsl_odeiv2_driver_apply(d, &s, c->s_at, y) != GSL_SUCCESS) {
                c->failed = 1;
                break;
            }
            c->x_at = y[2];
            c->d_at = y[3];
            done_at = 1;
        }
        if (sk > s && gsl_odeiv2_driver_apply(d, &s, sk, y) != GSL_SUCCESS) {
            c->failed = 1;
            break;
        }
        if (y[0] > 0.5 * M_PI) { r = big; break; }
        if (y[0] < 0.0) { r = -big; break; }
        if (k == CHECKS) r = y[1];
    }
    gsl_odeiv2_driver_free(d);
    return r;
}

int elastica_curve_point(double L, double w, elastica_moment_fn M, void *ctx, double s_at,
                         double *x_at, double *drop_at)
{
    gsl_set_error_handler_off();
    if (!(L > 0) || !(w > 0) || !(s_at > 0) || s_at > L * (1.0 + 1e-9)) return -1;
    if (s_at > L) s_at = L;
    curve_ctx c = {L, w, M, ctx, 0, s_at, NAN, NAN};
    gsl_function f = {curve_residual, &c};
    double m0;
    if (brent(&f, 0.0, 0.5 * w * L * L, 1e-13 * w * L * L, &m0) != 0 || c.failed) return -1;
    curve_residual(m0, &c);
    if (c.failed || !isfinite(c.x_at)) return -1;
    *x_at = c.x_at;
    *drop_at = c.d_at;
    return 0;
}

typedef struct chord_ctx {
    double target;
    int failed;
} chord_ctx;

static double chord_residual(double log_gamma, void *params)
{
    chord_ctx *c = params;
    elastica_solution s;
    if (elastica_solve(exp(log_gamma), &s) != 0) {
        c->failed = 1;
        return NAN;
    }
    return s.chord - c->target;
}

int elastica_gamma_for_chord(double chord, double *gamma)
{
    gsl_set_error_handler_off();
    if (!(chord >= 1e-4 * M_PI / 180.0) || chord > 80.0 * M_PI / 180.0) return -1;
    chord_ctx c = {chord, 0};
    gsl_function f = {chord_residual, &c};
    double lg;
    /* chord(Gamma) rises from 4e-5 deg (Gamma = 1e-6) to 86 deg (400) */
    if (brent(&f, log(ELASTICA_GAMMA_MIN), log(ELASTICA_GAMMA_MAX), ELASTICA_ROOT_TOL, &lg) !=
            0 ||
        c.failed)
        return -1;
    *gamma = exp(lg);
    return 0;
}

double elastica_peirce_c_over_l(double theta)
{
    return cbrt(cos(0.5 * theta) / (8.0 * tan(theta)));
}

/* ---- elastic catenary ---- */

typedef struct span_ctx {
    double w, k, l0, span;
} span_ctx;

/* (C4) in log H, minus the span */
static double span_residual(double log_h, void *params)
{
    const span_ctx *c = params;
    double h = exp(log_h);
    return h * c->l0 / c->k + 2.0 * h / c->w * asinh(c->w * c->l0 / (2.0 * h)) -
           c->span;
}

int catenary_solve(double w, double k, double l0, double span,
                   catenary_solution *out)
{
    gsl_set_error_handler_off();
    if (!(w > 0.0) || !(k > 0.0) || !(l0 > 0.0) || !(span > 0.0)) return -1;
    span_ctx c = {w, k, l0, span};
    gsl_function f = {span_residual, &c};
    /* (C4) tends to 0 as H -> 0 and exceeds H l0 / k = l0 + span > span
     * at H = k (1 + span / l0) */
    double lo = log(1e-12 * w * l0), hi = log(k * (1.0 + span / l0)), lh;
    if (!(span_residual(lo, &c) < 0.0 && span_residual(hi, &c) > 0.0)) return -1;
    if (brent(&f, lo, hi, ELASTICA_ROOT_TOL, &lh) != 0) return -1;
    out->w = w;
    out->k = k;
    out->l0 = l0;
    out->span = span;
    out->h = exp(lh);
    out->v = 0.5 * w * l0;
    out->t_end = hypot(out->h, out->v);
    double xm;
    catenary_point(out, 0.5 * l0, &xm, &out->sag);
    return 0;
}

void catenary_point(const catenary_solution *c, double s, double *x,
                    double *drop)
{
    double h = c->h, v = c->v, w = c->w, r = (v - w * s) / h;
    *x = h * s / c->k + h / w * (asinh(v / h) - asinh(r));
    *drop = (v * s - 0.5 * w * s * s) / c->k +
            h / w * (sqrt(1.0 + (v / h) * (v / h)) - sqrt(1.0 + r * r));
}

/* ---- hanging chain ---- */

static const double j0_zeros[5] = {2.404825557695773, 5.520078110286311,
                                   8.653727912911013, 11.791534439014281,
                                   14.930917708487787};

double chain_j0_zero(int n)
{
    return n >= 1 && n <= 5 ? j0_zeros[n - 1] : NAN;
}

double chain_omega_continuous(int n, double g, double length)
{
    return 0.5 * chain_j0_zero(n) * sqrt(g / length);
}

/* Number of eigenvalues below x of the symmetric tridiagonal matrix with
 * diagonal d (n) and off-diagonal e (n - 1): the negative pivots of the
 * LDL^T factorisation of A - x I (Sturm). */
static int sturm_count(const double *d, const double *e, int n, double x)
{
    int c = 0;
    double q = 1.0;
    for (int i = 0; i < n; i++) {
        q = d[i] - x - (i > 0 ? e[i - 1] * e[i - 1] / q : 0.0);
        if (q == 0.0) q = -1e-300;
        if (q < 0.0) c++;
    }
    return c;
}

int chain_discrete(int nseg, double length, double W, double g, double k,
                   int nmodes, double *omega, double *seg_len)
{
    if (nseg < 2 || nmodes < 1 || nmodes > nseg || !(length > 0.0) || !(W > 0.0) ||
        !(g > 0.0))
        return -1;
    const double sig = length / nseg;
    double *d = drape_malloc(sizeof(double) * (size_t)nseg);
    double *e = drape_malloc(sizeof(double) * (size_t)nseg);
    double *m = drape_malloc(sizeof(double) * (size_t)nseg);
    double *s = drape_malloc(sizeof(double) * (size_t)(nseg + 1));
    if (!d || !e || !m || !s) {
        drape_free(d); drape_free(e); drape_free(m); drape_free(s);
        return -1;
    }
    /* unknowns: particles 1 .. nseg (index p - 1); segment j joins
     * particles j and j + 1 */
    for (int p = 1; p <= nseg; p++) m[p - 1] = p == nseg ? 0.5 * W * sig : W * sig;
    for (int j = 0; j < nseg; j++) {
        double T = g * W * sig * (nseg - j - 0.5);
        double l = k > 0.0 ? sig * (1.0 + T / k) : sig;
        if (seg_len) seg_len[j] = l;
        s[j] = T / l;
    }
    s[nseg] = 0.0;
    double hi = 0.0;
    for (int p = 1; p <= nseg; p++) {
        d[p - 1] = (s[p - 1] + s[p]) / m[p - 1];
        if (p < nseg) e[p - 1] = -s[p] / sqrt(m[p - 1] * m[p]);
    }
    for (int i = 0; i < nseg; i++) { /* Gershgorin */
        double r = d[i] + (i > 0 ? fabs(e[i - 1]) : 0.0) + (i < nseg - 1 ? fabs(e[i]) : 0.0);
        if (r > hi) hi = r;
    }
    for (int q = 0; q < nmodes; q++) {
        double lo = 0.0, up = hi;
        for (int it = 0; it < 200 && up - lo > 1e-15 * up; it++) {
            double mid = 0.5 * (lo + up);
            if (sturm_count(d, e, nseg, mid) > q) up = mid;
            else lo = mid;
        }
        omega[q] = sqrt(0.5 * (lo + up));
    }
    drape_free(d); drape_free(e); drape_free(m); drape_free(s);
    return 0;
}

/* ---- frequencies of a sampled signal ---- */

int sines_peaks(const double *t, const double *u, int nt, double omega_max,
                double domega, int m, double *omega)
{
    if (nt < 3 || !(domega > 0.0) || !(omega_max > domega) || m < 1) return 0;
    int ng = (int)(omega_max / domega);
    double *p = drape_malloc(sizeof(double) * (size_t)ng);
    double *pk = drape_malloc(sizeof(double) * (size_t)m);
    if (!p || !pk) {
        drape_free(p); drape_free(pk);
        return 0;
    }
    for (int j = 0; j < ng; j++) {
        double w = (j + 1) * domega, re = 0.0, im = 0.0;
        for (int k = 0; k < nt; k++) {
            double h = 0.5 * (1.0 - cos(2.0 * M_PI * k / (nt - 1)));
            re += h * u[k] * cos(w * t[k]);
            im -= h * u[k] * sin(w * t[k]);
        }
        p[j] = re * re + im * im;
    }
    int found = 0;
    for (int j = 1; j < ng - 1; j++) {
        if (!(p[j] > p[j - 1] && p[j] >= p[j + 1])) continue;
        /* insert into the top m by height */
        int pos = found < m ? found : m;
        while (pos > 0 && pk[pos - 1] < p[j]) pos--;
        if (pos >= m) continue;
        int last = found < m ? found : m - 1;
        for (int q = last; q > pos; q--) {
            pk[q] = pk[q - 1];
            omega[q] = omega[q - 1];
        }
        pk[pos] = p[j];
        omega[pos] = (j + 1) * domega;
        if (found < m) found++;
    }
    for (int a = 1; a < found; a++) /* ascending frequency */
        for (int b = a; b > 0 && omega[b] < omega[b - 1]; b--) {
            double tmp = omega[b];
            omega[b] = omega[b - 1];
            omega[b - 1] = tmp;
        }
    drape_free(p);
    drape_free(pk);
    return found;
}

typedef struct sines_ctx {
    const double *t, *u;
    int nch, nt, m;
    double *phi;   /* nt x 2m, row-major */
    gsl_matrix *g; /* 2m x 2m */
    gsl_vector *b, *a;
} sines_ctx;

/* Sum over channels of the squared residual of the linear least-squares
 * fit of u_c on the basis cos(omega_j t), sin(omega_j t). */
static double sines_resid(const gsl_vector *w, void *params)
{
    sines_ctx *c = params;
    const int nb = 2 * c->m, nt = c->nt;
    for (int k = 0; k < nt; k++)
        for (int j = 0; j < c->m; j++) {
            double a = gsl_vector_get(w, (size_t)j) * c->t[k];
            c->phi[k * nb + 2 * j] = cos(a);
            c->phi[k * nb + 2 * j + 1] = sin(a);
        }
    for (int p = 0; p < nb; p++)
        for (int q = 0; q <= p; q++) {
            double s = 0.0;
            for (int k = 0; k < nt; k++) s += c->phi[k * nb + p] * c->phi[k * nb + q];
            gsl_matrix_set(c->g, (size_t)p, (size_t)q, s);
            gsl_matrix_set(c->g, (size_t)q, (size_t)p, s);
        }
    if (gsl_linalg_cholesky_decomp1(c->g) != GSL_SUCCESS) return 1e300;
    double total = 0.0;
    for (int ch = 0; ch < c->nch; ch++) {
        const double *u = c->u + (size_t)ch * (size_t)nt;
        for (int p = 0; p < nb; p++) {
            double s = 0.0;
            for (int k = 0; k < nt; k++) s += c->phi[k * nb + p] * u[k];
            gsl_vector_set(c->b, (size_t)p, s);
        }
        gsl_linalg_cholesky_solve(c->g, c->b, c->a);
        for (int k = 0; k < nt; k++) {
            double r = u[k];
            for (int p = 0; p < nb; p++) r -= c->phi[k * nb + p] * gsl_vector_get(c->a, (size_t)p);
            total += r * r;
        }
    }
    return total;
}

int sines_fit(const double *t, const double *u, int nch, int nt, int m,
              const double *guess, double *omega, double *rel_resid)
{
    gsl_set_error_handler_off();
    if (m < 1 || nch < 1 || nt <= 2 * m) return -1;
    int rc = -1;
    sines_ctx c = {t, u, nch, nt, m, NULL, NULL, NULL, NULL};
    c.phi = drape_malloc(sizeof(double) * (size_t)nt * (size_t)(2 * m));
    c.g = gsl_matrix_alloc((size_t)(2 * m), (size_t)(2 * m));
    c.b = gsl_vector_alloc((size_t)(2 * m));
    c.a = gsl_vector_alloc((size_t)(2 * m));
    gsl_vector *w = gsl_vector_alloc((size_t)m), *step = gsl_vector_alloc((size_t)m);
    gsl_multimin_fminimizer *mm = gsl_multimin_fminimizer_alloc(
        gsl_multimin_fminimizer_nmsimplex2, (size_t)m);
    if (!c.phi || !c.g || !c.b || !c.a || !w || !step || !mm) goto out;
    double span = t[nt - 1] - t[0], wmax = 0.0;
    for (int j = 0; j < m; j++) {
        gsl_vector_set(w, (size_t)j, guess[j]);
        gsl_vector_set(step, (size_t)j, 0.05 * 2.0 * M_PI / span);
        if (guess[j] > wmax) wmax = guess[j];
    }
    gsl_multimin_function f = {sines_resid, (size_t)m, &c};
    if (gsl_multimin_fminimizer_set(mm, &f, w, step) != GSL_SUCCESS) goto out;
    int status = GSL_CONTINUE;
    for (int it = 0; it < 20000 && status == GSL_CONTINUE; it++) {
        if (gsl_multimin_fminimizer_iterate(mm) != GSL_SUCCESS) break;
        status = gsl_multimin_test_size(gsl_multimin_fminimizer_size(mm), 1e-12 * wmax);
    }
    if (status != GSL_SUCCESS) goto out;
    for (int j = 0; j < m; j++) omega[j] = gsl_vector_get(mm->x, (size_t)j);
    if (rel_resid) {
        double s2 = 0.0;
        for (size_t q = 0; q < (size_t)nch * (size_t)nt; q++) s2 += u[q] * u[q];
        *rel_resid = sqrt(sines_resid(mm->x, &c) / s2);
    }
    rc = 0;
out:
    if (mm) gsl_multimin_fminimizer_free(mm);
    if (w) gsl_vector_free(w);
    if (step) gsl_vector_free(step);
    if (c.a) gsl_vector_free(c.a);
    if (c.b) gsl_vector_free(c.b);
    if (c.g) gsl_matrix_free(c.g);
    drape_free(c.phi);
    return rc;
}
