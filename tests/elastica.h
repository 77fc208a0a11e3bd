/* elastica.h: reference solutions for the validation tests (test-only
 * code, independent of the drape library): the heavy cantilever elastica
 * and the elastic catenary.
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

#endif /* DRAPE_TESTS_ELASTICA_H */
