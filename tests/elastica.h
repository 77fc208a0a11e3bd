/* elastica.h: reference solutions for the validation tests (test-only
 * code, independent of the drape library's physics): the heavy cantilever
 * elastica, the elastic catenary, the hanging chain's frequencies, and a
 * least-squares fit of sums of sinusoids.
 *
 * An inextensible strip with linear bending M = B K (B per unit width,
 * N.m), weight w = W g per unit length and width, clamped horizontally at
 * s = 0, free at s = L, loaded by its own weight only.  Non-dimensional
 * gravity parameter Gamma = W g L^3 / B.  The equations and the shooting
 * method are in elastica.c; docs/validation.md shows the checks.
 *
 * Everything is non-dimensional: lengths over L.  The tip's drop is
 * positive downward.
 */
#ifndef DRAPE_TESTS_ELASTICA_H
#define DRAPE_TESTS_ELASTICA_H

typedef struct elastica_solution {
    double gamma;       /* W g L^3 / B */
    double mu0;         /* clamp moment M(0) L / B (small Gamma: Gamma / 2) */
    double tip_x;       /* reach of the tip / L */
    double tip_drop;    /* drop of the tip / L (positive down) */
    double tip_slope;   /* theta(L), rad, below horizontal */
    double chord;       /* chord angle atan(drop / reach), rad (Peirce's theta) */
    double ratio;       /* drop / reach = tan(chord) */
} elastica_solution;

/* Solve the heavy cantilever for gamma in [1e-6, 400].  Returns 0 and fills
 * *out, or -1 (bad gamma, ODE or root-finder failure).  Accuracy: relative
 * 1e-10 on the tip coordinates (ODE tolerance 1e-12, root 1e-13). */
int elastica_solve(double gamma, elastica_solution *out);

/* Shape at n points s_k = k / (n - 1), k = 0..n-1, of the solved cantilever:
 * x[k], drop[k] (over L).  Returns 0 or -1. */
int elastica_shape(double gamma, int n, double *x, double *drop);

/* The gamma whose chord angle is `chord` (rad, in [1e-4 deg, 80 deg]); the exact
 * bending length is then c / L = gamma^(-1/3) (c^3 = B / (W g)).  Returns
 * 0 or -1. */
int elastica_gamma_for_chord(double chord, double *gamma);

/* Peirce's closed form (ASTM D1388): c / L = (cos(theta/2) / (8 tan theta))^(1/3),
 * theta the chord angle in rad. */
double elastica_peirce_c_over_l(double theta);

/* ---- heavy cantilever with a nonlinear moment curve (issue 18) --------
 * The same strip in SI units: overhang L (m), weight w = W g per unit
 * length and width (N/m^2), bending moment per width M(K) given by the
 * caller (odd, increasing: N.m/m for K in 1/m).  State theta, the moment
 * m (N.m/m), x, drop along s; theta' = K with M(K) = m, m' = -w (L - s)
 * cos theta; shooting on m(0) as above.  The position at arc length
 * s_at (0 < s_at <= L) goes to *x_at, *drop_at (m).  Returns 0 or -1. */
typedef double (*elastica_moment_fn)(double K, void *ctx);
int elastica_curve_point(double L, double w, elastica_moment_fn M, void *ctx, double s_at,
                         double *x_at, double *drop_at);

/* ---- elastic catenary --------------------------------------------------
 * A perfectly flexible cable (per unit width: weight w = W g per unit
 * unstretched length, N/m^2; linear stretch T = k eps, k in N/m) of
 * unstretched length l0, hung from two points at the same height a
 * distance `span` apart (Irvine 1981, Cable Structures, section 1.3).
 * Lengths in m, forces per unit width in N/m. */
typedef struct catenary_solution {
    double w, k, l0, span;
    double h;       /* horizontal tension component H (constant), N/m */
    double v;       /* vertical support reaction w l0 / 2, N/m */
    double t_end;   /* support tension sqrt(H^2 + V^2), N/m */
    double sag;     /* drop of the midpoint below the supports, m */
} catenary_solution;

/* Solve for H from the span; 0, or -1 (bad input, no bracket). */
int catenary_solve(double w, double k, double l0, double span,
                   catenary_solution *out);
/* Position at unstretched arc length s in [0, l0] from the left support:
 * *x along the span, *drop below the supports. */
void catenary_point(const catenary_solution *c, double s, double *x,
                    double *drop);

/* ---- hanging chain -----------------------------------------------------
 * A perfectly flexible chain of length L hanging from one end under
 * gravity g.  Small lateral oscillations of the continuum (tension
 * T = w y, y measured up from the free end) obey u_tt = g (y u_y)_y, whose
 * modes are u = J0(z_n sqrt(y / L)) cos(omega_n t) with
 *     omega_n = (z_n / 2) sqrt(g / L),   J0(z_n) = 0.          (Bernoulli)
 * The lumped chain (nseg segments of rest length sigma = L / nseg,
 * masses W sigma per particle and half that at the free end, per unit
 * width, top particle fixed, segments stretching as T = k eps) has its
 * own frequencies: segment j (from the top, j = 0 .. nseg-1) carries the
 * weight of the particles below it, T_j = g W sigma (nseg - j - 1/2), is
 * l_j = sigma (1 + T_j / k) long in equilibrium, and resists a lateral
 * offset of its ends with stiffness T_j / l_j; the lateral motion is then
 * M u'' = -K u with K tridiagonal, decoupled from the axial motion to
 * first order. */

/* z_n, the n-th positive zero of the Bessel function J0 (n = 1 .. 5;
 * Abramowitz & Stegun table 9.5, 15 digits); NaN outside. */
double chain_j0_zero(int n);
/* omega_n of the continuous chain, rad/s. */
double chain_omega_continuous(int n, double g, double length);
/* The nmodes lowest lateral frequencies (rad/s, ascending) of the lumped
 * chain above, by Sturm bisection on the mass-scaled tridiagonal matrix
 * (to 1e-14 relative); k <= 0 means inextensible.  seg_len (may be NULL)
 * receives the nseg equilibrium segment lengths l_j, m.  Returns 0 or -1. */
int chain_discrete(int nseg, double length, double W, double g, double k,
                   int nmodes, double *omega, double *seg_len);

/* ---- frequencies of a sampled signal ------------------------------------
 * u holds nch channels of nt samples each, channel c at u[c * nt + k],
 * taken at times t[k]. */

/* The m highest local maxima of the Hann-windowed periodogram of channel
 * u (nt samples), |sum_k h_k u_k exp(-i omega t_k)|^2, scanned on
 * omega = domega, 2 domega, .. omega_max; returned in ascending order.
 * Only starting values for sines_fit (resolution domega).  Returns the
 * number of maxima found (<= m). */
int sines_peaks(const double *t, const double *u, int nt, double omega_max,
                double domega, int m, double *omega);

/* Least-squares fit of a sum of m sinusoids with common frequencies to
 * every channel,
 *     u_c(t) ~ sum_j a_cj cos(omega_j t) + b_cj sin(omega_j t),
 * by variable projection: for given omega the amplitudes are a linear
 * least-squares problem (solved exactly); the frequencies minimise the
 * remaining sum of squares (Nelder-Mead from `guess`, simplex size down to
 * 1e-12 of the largest frequency).  rel_resid (may be NULL) receives
 * sqrt(residual / sum u^2).  Returns 0, or -1 (no convergence, singular
 * basis). */
int sines_fit(const double *t, const double *u, int nch, int nt, int m,
              const double *guess, double *omega, double *rel_resid);

#endif /* DRAPE_TESTS_ELASTICA_H */
