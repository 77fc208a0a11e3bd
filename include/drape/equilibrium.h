/* equilibrium.h: the static drape by energy minimisation (numerics.md 3.7,
 * docs/model.md 6), the fast path for scenes that ask only for the equilibrium.
 *
 * Finds free positions x* with F(x*) = -grad E_pot(x*) = 0 (E_pot = stretch +
 * bend + shear + gravity, the model's conservative parts; damping does not
 * move an equilibrium) that is a strict local minimum of E_pot, reached
 * from the given start (normally lattice->xinit: the flat state plus the
 * seeded perturbation that breaks the symmetry).
 *
 *  0. Optional (dyn_time > 0): damped implicit dynamics (linearly implicit
 *     BDF2, fixed step or one chosen by its error in position (dyn_tol),
 *     the model's own damping) from rest for dyn_time.
 *  1. Pseudo-transient continuation: backward-Euler-from-rest steps
 *       (M / dt^2 + Hc) dx = F,    Hc = Hess E_pot, compressed springs
 *     clamped when clamp_k is given, dt grown by switched evolution
 *     relaxation, halved when the matrix is not positive definite;
 *     Armijo line search on E_pot.
 *  2. Newton polish once dt > dt_newton: exact Hessian (else the clamped
 *     one), line search on E_pot, until every free particle has
 *     |F_i| <= tol * m_i g.
 *  3. Certification: LL^T Cholesky (CHOLMOD) of the exact Hessian at the
 *     solution, nothing clamped or shifted; success means a strict local
 *     minimum.  The smallest pivot and the lowest natural frequency
 *     (inverse iteration on H v = omega^2 M v) are reported as margins;
 *     failure means a saddle (or a maximum).
 * docs/equilibrium.md gives the algorithm, its choices and measurements.
 */
#ifndef DRAPE_EQUILIBRIUM_H
#define DRAPE_EQUILIBRIUM_H

#include <signal.h>

#include "drape/error.h"
#include "drape/fabric.h"
#include "drape/model.h"

/* One iteration, for tracing (opts.trace). */
typedef struct drape_equilibrium_iter {
    int iter;             /* iterations so far (accepted + refused) */
    int newton;           /* 1: a Newton (unshifted) step, 0: a PTC step */
    double dt_s;          /* pseudo time step after the iteration, the one
                             the next PTC iteration uses (a refused one's
                             half the step it tried); inf for a Newton
                             iteration (refused: the next, PTC, starts at
                             dt_newton / 4) */
    int posdef;           /* 1 if the iteration matrix factorised */
    int accepted;         /* 1 if the step was taken */
    double alpha;         /* line-search fraction of the step */
    double energy_J;      /* E_pot after the iteration */
    double max_force_rel; /* max_i |F_i| / w_i after the iteration */
    double step_m;        /* max_i |alpha dx_i| of the last step tried, m */
} drape_equilibrium_iter;

typedef void (*drape_equilibrium_trace_fn)(void *ctx, const drape_equilibrium_iter *it);

/* Time scale of the defaults: T = sqrt(sigma / g) (sigma the lattice
 * spacing; with force_ref instead of gravity, sqrt(sigma m / force_ref)). */
#define DRAPE_EQ_DT0_FACTOR 0.3       /* dt0 = 0.3 T */
#define DRAPE_EQ_DT_NEWTON_FACTOR 1e3 /* dt_newton = 1000 T */

typedef struct drape_equilibrium_opts {
    double tol;          /* converged when |F_i| <= tol * w_i for every free
                            particle, w_i = m_i g (or force_ref); 1e-8 */
    int max_iters;       /* iterations (factorisations of the loop); 500 */
    double dt0;          /* s, first pseudo time step; 0 = 0.3 T */
    double dt_growth_min;/* smallest SER growth of dt after a full step; 1.5 */
    double dt_growth_max;/* largest SER growth of dt per step; 4 */
    double dt_newton;    /* s; dt above this switches to Newton; 0 = 1000 T */
    double clamp_k[2];   /* N/m, [DRAPE_WEFT], [DRAPE_WARP]: the fabric's
                            tensile stiffness k.  > 0: the iteration matrix
                            drops the negative transverse stiffness of
                            compressed springs (Choi & Ko); 0 = exact
                            Hessian throughout (slower on drapes) */
    double dyn_time;     /* s: damped dynamics before the minimisation; 0 =
                            off (default) */
    double dyn_dt;       /* s: its fixed step (needed when dyn_time > 0) */
    double dyn_time_fold;/* s: the first part of the fixed-step dynamics
                            (while the folds form, at most dyn_time), at the
                            step dyn_dt_fold, then dyn_dt (its first step a
                            variable-step BDF2 one; refused like the swing's
                            long step if it raises the total energy, the
                            dynamics then going on at dyn_dt_fold); 0 = none
                            (default).  Not used with dyn_tol > 0 */
    double dyn_dt_fold;  /* s: that step (needed when dyn_time_fold > 0) */
    double dyn_ke_frac;  /* > 0: after dyn_time the dynamics go on while the
                            kinetic energy exceeds this fraction of its
                            largest value so far (the cloth still swings),
                            up to dyn_time_max; 0 = stop at dyn_time */
    double dyn_time_max; /* s: the longest such dynamics (0 = 4 dyn_time) */
    double dyn_dt_swing; /* s: the step of the dynamics past dyn_time (the
                            slow swing after the folds have formed); 0 =
                            dyn_dt */
    double dyn_retry;    /* s; > 0: a longer step refused because it raised
                            the total energy (the swing's, or dyn_dt after
                            the fold phase) is tried again this long after
                            the refusal, once (a retry refused again leaves
                            the dynamics at the shorter step); its guard
                            then counts from the lowest total energy since
                            the first change of step.  0 = the
                            dynamics stay at the shorter step (default) */
    double dyn_tol;      /* m; > 0: the step of the dynamics is chosen by
                            their local error in position instead (the
                            largest particle's estimate at most dyn_tol per
                            step; variable-step BDF2, a step above 1.5
                            dyn_tol redone shorter), from dyn_dt / 4, within
                            [dyn_dt / 64, 8 dyn_dt]; dyn_dt_swing is then
                            not used.  Such a step uses the exact Jacobian
                            (no compression clamp), and one whose total
                            energy rises by more than 1e-4 of the energy
                            dissipated so far is redone at half the step
                            (counted in dyn_refused).  0 = the fixed step
                            dyn_dt (default) */
    double dyn_redo_tol; /* m; > 0 with dyn_tol = 0: a fixed-step fall whose
                            total energy climbs above its value at the
                            start (energy the model cannot have: its
                            linearly implicit step pumped it) is stopped
                            there and the dynamics go on from the state of
                            its lowest total energy with dyn_tol =
                            dyn_redo_tol (dyn_redone = 1, dyn_redo_from);
                            0 = off */
    int dyn_only;        /* 1: return after the damped dynamics (status
                            DRAPE_EQ_DYN_ONLY, x the state at dyn_time) */
    int certify;         /* 1: factor the exact Hessian at the end (default) */
    int eig_iters;       /* inverse iterations for omega_min (0 = skip); 40 */
    double force_ref;    /* N; 0 = m_i g (the model then needs gravity) */
    drape_equilibrium_trace_fn trace; /* NULL = no tracing */
    void *trace_ctx;
    const volatile sig_atomic_t *stop; /* checked before every step of the
                            damped dynamics and every iteration: when it is
                            non-zero the call ends with status interrupted
                            (x the last accepted iterate, not certified);
                            NULL = never */
} drape_equilibrium_opts;

/* Defaults (the values quoted above), no clamping, no dynamics, no trace. */
void drape_equilibrium_opts_default(drape_equilibrium_opts *o);
/* Defaults with clamp_k = f->k: what a scene run should use. */
void drape_equilibrium_opts_from_fabric(drape_equilibrium_opts *o, const drape_fabric *f);

typedef enum drape_equilibrium_status {
    DRAPE_EQ_CONVERGED, /* every |F_i| <= tol w_i */
    DRAPE_EQ_MAX_ITERS, /* max_iters used up */
    DRAPE_EQ_STALLED,   /* no step lowers E_pot any more: the roundoff floor
                           lies above tol, or dt collapsed; x is the last
                           accepted iterate */
    DRAPE_EQ_DYN_ONLY,   /* opts.dyn_only: x is the state after the damped
                           dynamics, not minimised (for tests of the fall) */
    DRAPE_EQ_INTERRUPTED /* opts.stop was raised; x is the last accepted
                           iterate, not certified */
} drape_equilibrium_status;

/* "converged", "max_iters", "stalled", "dyn_only", "interrupted". */
const char *drape_equilibrium_status_name(drape_equilibrium_status s);

typedef struct drape_equilibrium_result {
    drape_equilibrium_status status;
    double *x;            /* 3n full positions (fixed particles as in x0);
                             free with drape_equilibrium_result_free */
    int iterations;       /* iterations of the loop (each factorises once,
                             twice when Newton falls back to Hc) */
    int dyn_steps;        /* damped dynamics steps */
    int dyn_redone;       /* 1: the fixed-step fall gained energy and the
                             dynamics were done again with dyn_redo_tol */
    double dyn_redo_from; /* s: where they were taken up again (the state
                             of the fixed-step fall's lowest total energy);
                             NAN when not redone */
    int dyn_refused;      /* steps refused because the total energy rose:
                             swing steps at dyn_dt_swing (then dyn_dt on,
                             until dyn_retry), dyn_dt after the fold phase
                             (then dyn_dt_fold),
                             or steps of the error-controlled fall (redone
                             at half the step); after a redo (dyn_redone),
                             those of the fall as taken (as dyn_steps): the
                             fixed-step fall's up to dyn_redo_from and the
                             second fall's, not those of the part thrown
                             away */
    int dyn_pumped;       /* 1: the fixed-step fall was stopped because its
                             total energy rose above its lowest value by more
                             than a tenth of the peak kinetic energy at the
                             fold or fall step (equilibrium_fall.c,
                             DRAPE_EQ_PUMP_RISE), and fell again as in
                             dyn_redone (which is then 1 too) */
    double dyn_end;       /* s: when the damped dynamics ended */
    int dyn_rejected;     /* steps redone shorter by the error control
                             (dyn_tol) */
    double dyn_dt_min, dyn_dt_max; /* s: the shortest and longest step taken */
    double dyn_e_start, dyn_e_end; /* J: kinetic + potential energy at the
                                      start and the end of the dynamics (NaN
                                      without a dynamics stage) */
    double dyn_e_max_rise; /* J: the largest rise of that total over one step
                              (negative: it fell at every step; NaN without
                              a step).  The model dissipates, so a rise is
                              the integrator's (docs/ensemble.md) */
    double dyn_e_max;      /* J: the largest value of that total at the start
                              and after each step (NaN without a dynamics
                              stage); above dyn_e_start, the integrator
                              created energy (docs/ensemble.md, "Energy
                              gained by the fixed-step fall") */
    int ptc_steps;        /* accepted PTC steps */
    int newton_steps;     /* accepted Newton steps */
    int rejected;         /* iterations whose step was refused */
    int factorizations;   /* numeric factorisations, all stages */
    int energy_evals, force_evals, jacobian_evals; /* evaluations of the
                             model, all stages (the fall's included): of
                             E_pot alone (the line search, the fall's energy
                             balance), of the forces, of the Jacobian (the
                             fall's step evaluates forces and Jacobian in
                             one pass: counted in both) */
    drape_energies energy; /* E_pot by term at x, J */
    double energy_J;       /* their sum */
    double max_force_rel;  /* max_i |F_i| / w_i at x */
    double max_strain;     /* largest stretch strain at x */
    int certified;         /* 1 strict local minimum, 0 not one (the exact
                              Hessian is not positive definite: a saddle),
                              -1 not checked.  Where the Hessian has a zero
                              mode (a free rigid motion: a cloth hung from
                              one pin) 1 or 0 is the sign of roundoff
                              (docs/equilibrium.md, "Zero modes") */
    long not_posdef_column;/* certified 0: column (in CHOLMOD's order) where
                              LL^T failed, else -1 */
    double min_pivot;      /* certified 1: smallest pivot L_ii^2 of the exact
                              Hessian (N/m); an upper bound on its smallest
                              eigenvalue; NaN otherwise */
    double omega_min;      /* certified 1 and eig_iters > 0: lowest natural
                              frequency sqrt(lambda_min(M^-1 H)), rad/s (a
                              Rayleigh quotient: an upper bound); NaN
                              otherwise */
    double wall_s;         /* wall time of the call, s */
    double cpu_s;          /* CPU time of the process during the call, s */
} drape_equilibrium_result;

/* Minimise E_pot of model m from x0 (3n full positions; fixed particles
 * keep their x0 positions).  o may be NULL (defaults).  Returns 0 when a
 * result was produced (status converged, max_iters or stalled: check
 * r->status and r->certified), or -1 with err set: E_INPUT (bad options; no
 * gravity and no force_ref), E_NOMEM (drape's allocations or CHOLMOD's),
 * E_NUMERIC (non-finite start; a start
 * or a Hessian the model cannot evaluate: folded hinge or corner,
 * zero-length edge; a CHOLMOD failure).  r is always initialised: call
 * drape_equilibrium_result_free on it in every case.  Runs on the calling
 * thread (CHOLMOD may use BLAS/OpenMP threads above 3000 unknowns). */
int drape_equilibrium_solve(drape_model *m, const double *x0,
                            const drape_equilibrium_opts *o,
                            drape_equilibrium_result *r, drape_error *err);

/* Frees r->x (not r); safe on a zeroed or already freed result. */
void drape_equilibrium_result_free(drape_equilibrium_result *r);

#endif /* DRAPE_EQUILIBRIUM_H */
