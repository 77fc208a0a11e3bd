/* diagnose.h: numerical faults of a simulated state and where they are
 * (docs/reliability.md "Numerical faults").
 *
 * The driver (sim.c) checks the state at every output point; a fault stops
 * the run (status failed, E_NUMERIC) before the state is handed to an
 * observer, so no bad frame is ever written as a good one.  Three faults,
 * checked in this order:
 *
 *  - non-finite: a NaN or inf in the positions or velocities.  Located at
 *    the first such particle; the term is "position" or "velocity", or,
 *    when every position is finite, the first conservative force part
 *    (stretch, bend, shear, gravity) that is not finite there.
 *  - strain: a stretch edge with |l - sigma| / sigma above the limit (the
 *    strain of drape_model_max_strain).  Located at the most strained
 *    edge, both end particles; the term is "stretch".
 *  - energy: the total energy E = E_kin + E_stretch + E_bend + E_shear +
 *    E_gravity rose above its value at the start by more than
 *    gain x scale_J.  Without driving forces (fixed particles do not move,
 *    air drag and edge dashpots only dissipate) E never increases in the
 *    exact solution, so a gain is numerical.  scale_J = M g L (the work of
 *    lifting the whole specimen, mass M, by its largest rest extent L;
 *    only with the gravity term) + the sum of the magnitudes of the
 *    starting energies.  The term is the one that grew most; it is
 *    located at the fastest particle (kinetic), the most strained edge
 *    (stretch) or the particle with the largest force of that term.
 *
 * Particles are named by id and lattice indices (i along the weft, j along
 * the warp; lattice.h).  Only the public model and lattice API is used.
 * No allocation on the path that finds nothing; locating an energy fault
 * in the bend, shear or gravity term allocates one 3n workspace (if that
 * fails the location is left out).
 */
#ifndef DRAPE_DIAGNOSE_H
#define DRAPE_DIAGNOSE_H

#include <stddef.h>

#include "drape/model.h"

/* Defaults (docs/reliability.md): 20 % strain (cloth tears or the lattice
 * has blown up long before; the shipped scenes stay below 0.5 %), and an
 * energy gain of one M g L. */
#define DRAPE_DIAG_STRAIN_LIMIT_DEFAULT 0.2
#define DRAPE_DIAG_ENERGY_GAIN_DEFAULT 1.0

typedef enum drape_diag_kind {
    DRAPE_DIAG_NONE = 0,
    DRAPE_DIAG_NONFINITE,
    DRAPE_DIAG_STRAIN,
    DRAPE_DIAG_ENERGY
} drape_diag_kind;

/* Reference of the energy check: the state at the start of the run. */
typedef struct drape_diag_ref {
    int valid;          /* 0: no energy check (energies not evaluable) */
    double energy_J;    /* total energy at the start, J */
    double scale_J;     /* see above, J; 0 = no energy check */
    double kinetic_J;   /* the terms at the start, J */
    drape_energies E;
} drape_diag_ref;

typedef struct drape_diagnosis {
    drape_diag_kind kind;
    double t;            /* s */
    const char *term;    /* static string: "position", "velocity", "stretch",
                            "bend", "shear", "gravity", "kinetic" */
    int particle, i, j;  /* particle id and lattice indices; -1 if unknown */
    int other, oi, oj;   /* strain / stretch: the edge's other particle; else -1 */
    int component;       /* non-finite: 0, 1, 2 for x, y, z; else -1 */
    double value;        /* strain, or energy gain (J), or the bad number */
    double limit;        /* the limit it exceeded (strain or J) */
} drape_diagnosis;

/* The reference at the start state (x, v; v may be NULL = at rest). */
void drape_diag_ref_init(drape_model *m, const double *x, const double *v,
                         drape_diag_ref *ref);

/* Check the state (x, v) at time t.  strain_limit <= 0 switches the strain
 * check off; energy_gain <= 0 or ref == NULL (or !ref->valid) the energy
 * check.  Returns 0 when nothing is wrong (d->kind = NONE), 1 when a fault
 * was found (d filled). */
int drape_diagnose(drape_model *m, double t, const double *x, const double *v,
                   double strain_limit, double energy_gain,
                   const drape_diag_ref *ref, drape_diagnosis *d);

/* One-line description ("strain 0.31 of the stretch edge between particle
 * 12 (i 5, j 1) and particle 13 (i 6, j 1) exceeds the limit 0.2 at
 * t = 0.1 s").  Returns buf. */
char *drape_diagnosis_format(const drape_diagnosis *d, char *buf, size_t n);

#endif /* DRAPE_DIAGNOSE_H */
