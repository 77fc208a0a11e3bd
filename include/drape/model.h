/* model.h: the mechanical model of a lattice: energies, forces and their
 * exact sparse Jacobian (docs/model.md sections 3, 4).
 *
 *   E_pot = E_stretch + E_bend + E_shear + E_gravity       (docs/model.md 3, seed 18)
 *   m_i dv_i/dt = -dE_pot/dx_i + f_diss,i,  dx_i/dt = v_i  (docs/model.md 4, seed 16-17)
 *   f_air  = -c_air m v,  f_edge = -c_edge ((v_b - v_a).e) e  (docs/model.md 3.6)
 *   f_shear_damping = -beta_shear q G0 (dgamma/dt) grad gamma per shear corner
 *                     (q its area / 4, G0 the flat fabric's shear rigidity;
 *                     docs/model.md 3.6: on by default, 0.5 ms)
 *
 * Force "parts" are selected by a bit mask so an IMEX integrator can put
 * some in its implicit and some in its explicit partition; parts that the
 * scene does not use are never built and cost nothing.
 *
 * State vectors are full: x and v hold 3 numbers per particle (all n
 * particles, fixed ones included, in particle-id order).  Jacobians are
 * taken with respect to free particles only, in a fixed CSC sparsity
 * pattern (computed once, diagonal stored explicitly: numerics.md
 * recommendation 2) whose index type matches SUNDIALS' sunindextype
 * (int64_t), so an integrator copies the pattern once and then lets
 * drape_model_jacobian* write straight into the SUNMatrix data.
 *
 * Return codes of evaluations: 0 ok; 1 recoverable (a hinge or corner
 * folded back onto itself, psi ~ pi, or a zero-length edge: a smaller step
 * may avoid it); never NaN in the outputs.  No allocation happens inside
 * any evaluation.
 */
#ifndef DRAPE_MODEL_H
#define DRAPE_MODEL_H

#include <stdint.h>

#include "drape/error.h"
#include "drape/fabric.h"
#include "drape/lattice.h"
#include "drape/scene.h"

/* Force parts (bit mask).  The first four equal the DRAPE_TERM_* bits. */
enum {
    DRAPE_PART_STRETCH = 1u << 0,
    DRAPE_PART_BEND = 1u << 1,
    DRAPE_PART_SHEAR = 1u << 2,
    DRAPE_PART_GRAVITY = 1u << 3,
    DRAPE_PART_AIR = 1u << 4,  /* air drag */
    DRAPE_PART_EDGE = 1u << 5, /* edge dashpots */
    DRAPE_PART_SHEAR_DAMPING = 1u << 6, /* shear-rate damping of the corners */
    DRAPE_PART_ALL = 0x7fu
};

/* The dissipative parts: those whose force depends on the velocities (the
 * damping matrix D = df/dv is nonzero). */
#define DRAPE_PARTS_DAMPING (DRAPE_PART_AIR | DRAPE_PART_EDGE | DRAPE_PART_SHEAR_DAMPING)

typedef struct drape_model_opts {
    unsigned terms;               /* DRAPE_TERM_* mask of energy terms to build */
    drape_energy_form form;       /* consistent or seed */
    double c_air;                 /* 1/s, 0 = off */
    double c_edge;                /* N.s/m, 0 = off */
    double g;                     /* m/s^2, along -z (DRAPE_G_STANDARD) */
    double beta_shear;            /* s, 0 = off: the internal shear
                                     damping (docs/model.md 3.6), a viscous
                                     shear force per length beta_shear G0
                                     dgamma/dt, G0 the initial slope of the
                                     shear curve; DRAPE_SCENE_DAMPING_SHEAR_FABRIC
                                     (-1) = the fabric's damping_shear (last,
                                     so that positional initialisers leave
                                     it 0) */
} drape_model_opts;

/* Options from a scene (terms, form, damping, standard gravity). */
void drape_model_opts_from_scene(const drape_scene *s, drape_model_opts *o);

typedef struct drape_energies {
    double stretch, bend, shear, gravity; /* J */
} drape_energies;

/* Sparsity pattern, compressed sparse column, 0-based. */
typedef struct drape_pattern {
    int64_t n;        /* rows = columns */
    int64_t nnz;
    int64_t *colptr;  /* n + 1 */
    int64_t *rowind;  /* nnz, sorted within each column */
} drape_pattern;

typedef struct drape_model drape_model;

/* Build the model for lattice L (borrowed: must outlive the model) and
 * fabric F (copied).  Allocates every workspace and both sparsity patterns.
 * Returns NULL with err set on failure.  Caller frees with
 * drape_model_free. */
drape_model *drape_model_new(const drape_lattice *L, const drape_fabric *F,
                             const drape_model_opts *o, drape_error *err);
void drape_model_free(drape_model *m);

const drape_lattice *drape_model_lattice(const drape_model *m);
/* Parts that this model actually has (built terms, damping that is on). */
unsigned drape_model_parts(const drape_model *m);

/* Potential energy by term at positions x (3n). Returns 0 or 1 (folded). */
int drape_model_energy(drape_model *m, const double *x, drape_energies *E);

/* f (3n, overwritten) = sum of the selected parts of the force at (x, v),
 * N, on every particle (fixed ones included).  v may be NULL when no
 * dissipative part is selected.  Returns 0 or 1. */
int drape_model_forces(drape_model *m, unsigned parts, const double *x,
                       const double *v, double *f);

/* f (3n) and the values of K and D (nnz each) of the selected parts at
 * (x, v) in one pass over the elements; each output may be NULL
 * (drape_model_forces and drape_model_jacobian are this with the others
 * NULL).  Cheaper than the two calls when both are needed: the elements
 * compute their force and Jacobian together.  Returns 0 or 1. */
int drape_model_eval(drape_model *m, unsigned parts, const double *x,
                     const double *v, double *f, double *K, double *D);

/* Pattern of K = df/dx and D = df/dv over free particles (3 n_free square,
 * union of all built parts, diagonal included). */
const drape_pattern *drape_model_pattern(const drape_model *m);

/* slots[j] = position of the diagonal entry (j, j) among the values of
 * drape_model_pattern, for the 3 n_free coordinates j (the pattern always
 * holds the diagonal). */
void drape_model_diagonal_slots(const drape_model *m, long *slots);

/* Values of K and D (each nnz of drape_model_pattern, overwritten) for the
 * selected parts at (x, v).  D may be NULL.  Returns 0 or 1. */
int drape_model_jacobian(drape_model *m, unsigned parts, const double *x,
                         const double *v, double *K, double *D);

/* Pattern of the first-order Jacobian J = d[x'; v']/d[x; v] over free
 * particles, unknowns ordered y = [x_free (3 n_free); v_free (3 n_free)],
 * 6 n_free square, diagonal included:
 *     J = [ 0          I        ]
 *         [ M^-1 K     M^-1 D   ]                          (numerics.md 3.2) */
const drape_pattern *drape_model_pattern_first_order(const drape_model *m);

/* Values of J (nnz of the first-order pattern, overwritten) for the selected
 * parts.  include_kinematic = 1 puts the identity block (x' = v) in; 0 leaves
 * those entries 0 (for a partition that does not own x' = v).  Returns 0/1. */
int drape_model_jacobian_first_order(drape_model *m, unsigned parts,
                                     int include_kinematic, const double *x,
                                     const double *v, double *J);

/* Highest natural frequency (rad/s) of the selected conservative parts at x,
 * by Gershgorin's bound on M^-1 K over free particles: an upper bound on
 * sqrt(lambda_max).  Returns 0 or 1. */
int drape_model_omega_bound(drape_model *m, unsigned parts, const double *x,
                            double *omega);

/* The correction that removes the negative geometric stiffness of
 * compressed stretch springs from K (Choi & Ko 2002; numerics 3.2): for
 * every edge shorter than sigma, c = kclamp[dir] w (sigma / l - 1) > 0 and
 * P = I - u u^T (u the edge's direction),
 *     Kc = -c P on blocks aa, bb,  +c P on ab, ba,
 * so that K + Kc >= K drops the spring's transverse stiffness
 * k w (1 - sigma/l) P < 0 when kclamp is the fabric's k (kclamp NULL:
 * the fabric's k, indexed by drape_dir).  Kc (nnz of
 * drape_model_pattern) is overwritten.  The equilibrium solver's
 * iteration matrix and the animate integrator use it to keep
 * M - h D - h^2 (K + Kc) positive definite at large steps. */
void drape_model_compression_clamp(const drape_model *m, const double *x,
                                   const double kclamp[2], double *Kc);

/* Largest |l - sigma| / sigma over stretch edges at x. */
double drape_model_max_strain(const drape_model *m, const double *x);

#endif /* DRAPE_MODEL_H */
