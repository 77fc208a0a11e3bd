/* units.h: quantities with units, as written in drape's input files and on
 * its command line ("20 mg/cm^2", "10000 N/m", "1 cm", "2 1/s", "1/30 s",
 * "5mm", "0.02 N.s/m", "1e-5 m/s").  See docs/model.md section 1.
 *
 * A quantity is a number (decimal, exponent, or a fraction "a/b" of two
 * decimals) optionally followed by a unit, with or without a space.  A unit
 * is a product of factors joined by '.', '*' or '/', each a symbol with an
 * optional integer power "^n"; a leading "1/" is allowed ("1/s", "1/cm").
 * Symbols: m cm mm um km; s ms us min h; kg g mg; N mN gf kgf; rad deg; and the
 * dimensionless "1".  A bare number is taken as SI.
 *
 * Every quantity is converted to SI once, at load time, and checked against
 * the expected dimension (exponents of kg, m, s; angles are dimensionless).
 */
#ifndef DRAPE_UNITS_H
#define DRAPE_UNITS_H

#include <stddef.h>

/* A physical dimension as integer exponents of kg, m and s. */
typedef struct drape_dim {
    signed char kg, m, s;
} drape_dim;

/* Dimensions used by drape's inputs. */
extern const drape_dim DRAPE_DIM_NONE;           /* rad, plain numbers */
extern const drape_dim DRAPE_DIM_LENGTH;         /* m */
extern const drape_dim DRAPE_DIM_TIME;           /* s */
extern const drape_dim DRAPE_DIM_RATE;           /* 1/s */
extern const drape_dim DRAPE_DIM_SPEED;          /* m/s */
extern const drape_dim DRAPE_DIM_CURVATURE;      /* 1/m */
extern const drape_dim DRAPE_DIM_AREAL_DENSITY;  /* kg/m^2 */
extern const drape_dim DRAPE_DIM_FORCE;          /* N = kg.m/s^2; also N.m/m */
extern const drape_dim DRAPE_DIM_FORCE_PER_LENGTH; /* N/m (stiffness, shear force per length) */
extern const drape_dim DRAPE_DIM_MOMENT;         /* N.m (flexural rigidity per width N.m^2/m) */
extern const drape_dim DRAPE_DIM_DAMPING;        /* N.s/m */

/* Parse `text` as a quantity of dimension `dim` and store it in SI.
 * Returns 0 on success.  On failure returns -1 and writes a one-line reason
 * into why[0..nwhy) ("unknown unit \"furlong\"", "expected a length, got
 * kg/m^2", "not a number: \"x\""). A bare number is accepted as SI.
 * The value must be finite; range checks are the caller's. */
int drape_units_parse(const char *text, drape_dim dim, double *si, char *why,
                      size_t nwhy);

/* strtod(s, end) that also says whether the literal lies outside the
 * normal doubles: *range = 1 when it overflows to inf, underflows to 0 or
 * lands among the denormals below DBL_MIN (no quantity drape reads is
 * meant to be 1e400, 1e-400 or 1e-310; taking 1e-400 as 0 would pass
 * checks such as "non-negative").  An exact zero ("0", "0e-400") is 0
 * and in range.  One check for every number reader (units, yread, scene,
 * run options, the KES import). */
double drape_units_strtod(const char *s, char **end, int *range);

/* Parse a unit expression alone (no number), e.g. "gf.cm/cm", and return its
 * SI scale factor and dimension.  Returns 0 on success, -1 with a reason. */
int drape_units_parse_unit(const char *unit, double *scale, drape_dim *dim,
                           char *why, size_t nwhy);

/* Human name of a dimension for messages: "length", "time", "1/s", ...; for
 * other dimensions a string like "kg^1 m^-1 s^-2" in a static buffer. */
const char *drape_units_dim_name(drape_dim dim);

/* 1 if the two dimensions are equal. */
int drape_units_dim_eq(drape_dim a, drape_dim b);

/* Named constants (SI), with their sources. */
#define DRAPE_G_STANDARD 9.80665   /* m/s^2, standard gravity (CGPM 1901) */
#define DRAPE_GRAM_FORCE 9.80665e-3 /* N, 1 gf = 1 g x standard gravity */

#endif /* DRAPE_UNITS_H */
