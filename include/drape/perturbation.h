/* perturbation.h: the seeded imperfection of a specimen (docs/model.md section 2).
 *
 * A smooth random height field defined in physical coordinates, the same
 * field at every lattice spacing for a given seed:
 *
 *   h(x, y) = A * phi(x, y),
 *   phi(x, y) = sqrt(2 / M) * sum_{k=1..M} cos(q_k . (x, y) + p_k),     (P1)
 *
 * M plane waves whose directions and phases p_k are uniform on [0, 2 pi)
 * and whose wavelengths 2 pi / |q_k| are uniform on [lambda_min,
 * lambda_max], drawn in a fixed order (for k = 1..M: wavelength,
 * direction, phase) from splitmix64 seeded with the seed; nothing of the
 * lattice enters the draw.  phi has mean 0 and variance 1 over the draw,
 * so A is the field's RMS height; its mean squared slope is
 *
 *   E |grad h|^2 = A^2 E |q|^2 = A^2 4 pi^2 / (lambda_min lambda_max).  (P2)
 *
 * The lattice samples h at the rest position of every free particle and
 * multiplies it by the scene's taper w (the Cusick scene's vanishes at the
 * support's edge; lattice.c).  The generator also serves the per-particle
 * form (`kind: particle`, amplitude * U(-1, 1) on each free particle).
 *
 * Reference: splitmix64: G. L. Steele, D. Lea, C. H. Flood, "Fast
 * splittable pseudorandom number generators", OOPSLA 2014 (constants as in
 * S. Vigna's public-domain splitmix64.c); u = (z >> 11) * 2^-53.
 */
#ifndef DRAPE_PERTURBATION_H
#define DRAPE_PERTURBATION_H

#include <stdint.h>

/* Defaults of docs/model.md section 2. */
#define DRAPE_FIELD_MODES 64          /* plane waves M */
#define DRAPE_FIELD_MODES_MAX 1024    /* the most a scene may ask for */
#define DRAPE_FIELD_LAMBDA_MIN 0.02   /* shortest wavelength, m */

/* The generator: a splitmix64 state.  Seed it with the seed itself. */
typedef struct drape_rng {
    uint64_t state;
} drape_rng;

void drape_rng_seed(drape_rng *g, uint64_t seed);
/* U[0, 1) from the top 53 bits of the next output. */
double drape_rng_uniform(drape_rng *g);
/* U[-1, 1): 2 U[0, 1) - 1. */
double drape_rng_uniform_pm1(drape_rng *g);

/* A drawn field (P1).  Plain value; q and phase hold `modes` entries. */
typedef struct drape_field {
    int modes;
    double amplitude;                  /* A, m (RMS height) */
    double qx[DRAPE_FIELD_MODES_MAX];  /* wave vectors, rad/m */
    double qy[DRAPE_FIELD_MODES_MAX];
    double phase[DRAPE_FIELD_MODES_MAX];
} drape_field;

/* Draw the field of seed: modes in [1, DRAPE_FIELD_MODES_MAX], 0 <
 * lambda_min <= lambda_max (m), amplitude >= 0 (m).  Returns 0, or -1 for
 * arguments out of range (f untouched). */
int drape_field_draw(drape_field *f, uint64_t seed, int modes, double lambda_min,
                     double lambda_max, double amplitude);

/* h(x, y) = A phi(x, y), m, at the physical point (x, y) (m). */
double drape_field_height(const drape_field *f, double x, double y);

#endif /* DRAPE_PERTURBATION_H */
