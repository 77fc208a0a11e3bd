/* fit.h: piecewise polynomial fits of Kawabata curves (docs/model.md 3.4).
 *
 * A fit y(x) is a list of polynomial pieces on consecutive intervals
 * [from, to) starting at x = 0; coefficients are in ascending powers of x
 * (not of x - from); the last piece extends to infinity.  The curve is
 * extended as an odd function, y(-x) = -y(x), and its integral
 * W(x) = integral_0^|x| y is even.  All values are SI once loaded (bending:
 * x = K in 1/m, y = M in N.m/m; shear: x = gamma in rad, y = F in N/m).
 *
 * Integrals are exact: each piece's polynomial is integrated in closed form
 * and the integrals up to each knot are cached by drape_fit_prepare.
 */
#ifndef DRAPE_FIT_H
#define DRAPE_FIT_H

#define DRAPE_FIT_MAX_PIECES 16
#define DRAPE_FIT_MAX_COEFS 8 /* polynomial degree <= 7 */

typedef struct drape_fit_piece {
    double from, to;                 /* to = INFINITY for the last piece */
    int ncoef;                       /* 1..DRAPE_FIT_MAX_COEFS */
    double c[DRAPE_FIT_MAX_COEFS];   /* y = sum c[k] x^k on [from, to) */
} drape_fit_piece;

typedef struct drape_fit {
    int n;                                   /* number of pieces, >= 1 */
    drape_fit_piece p[DRAPE_FIT_MAX_PIECES];
    double w0[DRAPE_FIT_MAX_PIECES];         /* W at each piece's start */
} drape_fit;

/* Compute the cached integrals; call after filling or changing pieces. */
void drape_fit_prepare(drape_fit *f);

/* y(x), odd extension. */
double drape_fit_value(const drape_fit *f, double x);
/* dy/dx at x (even); at a knot, the slope of the piece to the right. */
double drape_fit_slope(const drape_fit *f, double x);
/* d2y/dx2 at x (odd); at a knot, that of the piece to the right. */
double drape_fit_slope2(const drape_fit *f, double x);
/* W(x) = integral_0^|x| y(s) ds (even, exact). */
double drape_fit_integral(const drape_fit *f, double x);
/* y(x)/x for x != 0, and its limit dy/dx(0) at x = 0, computed without
 * cancellation when c[0] of the first piece is 0 (exact division of the
 * polynomial by x).  Even in x. */
double drape_fit_value_over_x(const drape_fit *f, double x);

/* Rescale from input units to SI: x_si = x_in * xs, y_si = y_in * ys.
 * Knots are multiplied by xs and coefficient k by ys / xs^k. */
void drape_fit_scale(drape_fit *f, double xs, double ys);

/* out = (a + b) / 2 on the union of both fits' knots (exact).  Returns 0,
 * or -1 if the union has more than DRAPE_FIT_MAX_PIECES pieces. */
int drape_fit_mean(const drape_fit *a, const drape_fit *b, drape_fit *out);

/* One piece's polynomial and its slope at x (whatever its interval). */
double drape_fit_piece_value(const drape_fit_piece *p, double x);
double drape_fit_piece_slope(const drape_fit_piece *p, double x);

/* Largest jump in value and in slope at any knot (absolute, SI). */
void drape_fit_knot_jumps(const drape_fit *f, double *value_jump,
                          double *slope_jump);

#endif /* DRAPE_FIT_H */
