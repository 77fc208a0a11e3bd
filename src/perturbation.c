/* perturbation.c: the seeded imperfection of a specimen (docs/model.md section
 * 2): the smooth random height field (P1) of perturbation.h and the
 * generator both perturbation forms draw from. */
#include "drape/perturbation.h"

#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

void drape_rng_seed(drape_rng *g, uint64_t seed) { g->state = seed; }

static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += UINT64_C(0x9e3779b97f4a7c15));
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}

double drape_rng_uniform(drape_rng *g)
{
    return (double)(splitmix64(&g->state) >> 11) * (1.0 / 9007199254740992.0);
}

double drape_rng_uniform_pm1(drape_rng *g) { return 2.0 * drape_rng_uniform(g) - 1.0; }

int drape_field_draw(drape_field *f, uint64_t seed, int modes, double lambda_min,
                     double lambda_max, double amplitude)
{
    if (!(modes >= 1 && modes <= DRAPE_FIELD_MODES_MAX) || !(lambda_min > 0.0) ||
        !(lambda_max >= lambda_min) || !isfinite(lambda_max) || !(amplitude >= 0.0) ||
        !isfinite(amplitude))
        return -1;
    drape_rng g;
    drape_rng_seed(&g, seed);
    f->modes = modes;
    f->amplitude = amplitude;
    for (int k = 0; k < modes; k++) {
        /* the fixed order of (P1): wavelength, direction, phase */
        double lambda = lambda_min + (lambda_max - lambda_min) * drape_rng_uniform(&g);
        double dir = 2.0 * M_PI * drape_rng_uniform(&g);
        double q = 2.0 * M_PI / lambda;
        f->qx[k] = q * cos(dir);
        f->qy[k] = q * sin(dir);
        f->phase[k] = 2.0 * M_PI * drape_rng_uniform(&g);
    }
    return 0;
}

double drape_field_height(const drape_field *f, double x, double y)
{
    double sum = 0.0;
    for (int k = 0; k < f->modes; k++) sum += cos(f->qx[k] * x + f->qy[k] * y + f->phase[k]);
    return f->amplitude * sqrt(2.0 / f->modes) * sum;
}
