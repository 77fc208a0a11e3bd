/* integrator.h: time integrators for the particle model (docs/model.md section 4)
 * behind one small vtable (STYLE.md 10).
 *
 * The ODE.  Unknowns are the free particles only, blocked
 *     y = [ x_free (3 nf) ; v_free (3 nf) ],   dim = 6 nf,
 *     x' = v,   v' = M^-1 f(x, v)                           (docs/model.md 4, seed 16-17)
 * Fixed particles stay at lattice->xinit with v = 0.  The right-hand side
 * scatters y into full x, v, calls drape_model_forces and gathers f / m.
 *
 * Tolerances.  One relative tolerance rtol and a vector absolute tolerance:
 *     atol_x = atol                       (positions, m)
 *     atol_v = atol / T,  T = sqrt(L / g) (velocities, m/s)
 * with L the largest extent of the rest lattice and g standard gravity
 * (numerics.md 3.1): a body falling under gravity over L moves at about
 * L / T, so both blocks get about the same relative weight.
 *
 * Backends (the names are a contract; docs/integrators.md):
 *   cvode-bdf    CVODE BDF, max order 2 by default, KLU on the exact sparse
 *                first-order Jacobian;
 *   arkode-imex  ARKStep ARK436L2SA: implicit x' = v, stretch, edge dashpots
 *                and shear; explicit bend, gravity and air drag; KLU on the
 *                Jacobian of the implicit part;
 *   arkode-dirk  ARKStep ESDIRK436L2SA (L-stable, stiffly accurate), fully
 *                implicit, KLU on the exact Jacobian;
 *   arkode-erk   ERKStep Dormand-Prince 5(4), explicit adaptive;
 *   gsl-msbdf    GSL gsl_odeiv2 msbdf (the seed's Gear method), dense
 *                Jacobian; refused when its two dense matrices would exceed
 *                a memory limit;
 *   gsl-rk8pd    GSL Runge-Kutta Prince-Dormand 8(9), explicit;
 *   auto         cvode-bdf, switching to arkode-erk and back while it runs,
 *                on a work estimate from its step sizes
 *                (src/integrator_auto.c, docs/integrators.md);
 *   animate      fixed step opts.fixed_step, one linearised backward Euler
 *                solve per step with the exact Jacobian (Baraff & Witkin
 *                1998), CHOLMOD on M - h D - h^2 K; rtol and atol unused
 *                (src/integrator_animate.c, docs/animate.md).
 *
 * Errors.  Every solver failure sets a drape_error of kind DRAPE_E_NUMERIC
 * whose message names the integrator, the time, the solver's reason (the
 * SUNDIALS flag name or GSL status) and a hint.  Model evaluations that
 * return 1 (folded hinge) or produce a non-finite number are reported to the
 * solver as recoverable failures, so it retries with a smaller step.
 */
#ifndef DRAPE_INTEGRATOR_H
#define DRAPE_INTEGRATOR_H

#include <signal.h>
#include <stddef.h>

#include "drape/error.h"
#include "drape/model.h"

/* Defaults (one place; drape_integrator_opts_default). */
#define DRAPE_INTEGRATOR_MAX_ORDER_DEFAULT 2     /* cvode-bdf, numerics.md 1.4 */
#define DRAPE_INTEGRATOR_MAX_STEPS_DEFAULT 1000000L /* per step_to call, numerics.md 6.4 */
#define DRAPE_INTEGRATOR_DENSE_LIMIT_DEFAULT (2.0 * 1024.0 * 1024.0 * 1024.0) /* bytes, 2 GiB */
#define DRAPE_INTEGRATOR_GSL_H0_DEFAULT 1e-6     /* s, GSL's first trial step */

typedef struct drape_integrator_opts {
    double rtol;        /* relative tolerance (> 0) */
    double atol;        /* absolute tolerance on positions, m (> 0) */
    double t_scale;     /* T of atol_v = atol / T, s; 0 = sqrt(L / g) */
    double t_stop;      /* never step past this time, s; 0 = no limit */
    int max_order;      /* cvode-bdf maximum BDF order 1..5; 0 = default */
    long max_steps;     /* steps allowed per step_to call; 0 = default */
    double dense_limit_bytes; /* gsl-msbdf refuses above this; 0 = default */
    double h_init;      /* first step, s; 0 = solver's own choice (GSL: default above) */
    int linsol;         /* drape_linsol: Newton linear solver of the SUNDIALS
                           implicit backends; 0 = DRAPE_LINSOL_AUTO */
    const volatile sig_atomic_t *stop; /* when *stop != 0 every right-hand
                           side fails at once (unrecoverably), so step_to
                           returns within one evaluation (SIGINT/SIGTERM,
                           docs/reliability.md); NULL = never */
    double auto_hw;     /* auto: BDF2's h omega below which it switches to
                           arkode-erk; 0 = from the step Dormand-Prince took
                           (integrator_auto.c;
                           tests raise it to force switches) */
    double fixed_step;  /* animate: its fixed step, s (> 0 required there;
                           ignored by the others) */
} drape_integrator_opts;

/* Linear solver of the Newton systems (I - gamma J) dy = r of cvode-bdf,
 * arkode-dirk and arkode-imex (docs/integrators.md, "Linear solvers"):
 *   klu           sparse LU (KLU, AMD ordering) of the 6 nf first-order
 *                 matrix, refactored only when J or gamma changed;
 *   schur         GMRES (SUNDIALS SPGMR, left preconditioning) with the
 *                 Schur-reduced 3 nf system S = M - gamma D - gamma^2 K
 *                 factored by CHOLMOD as preconditioner (numerics.md 3.3)
 *                 and the exact J*v from the model's K and D;
 *   schur-direct  the same Schur solve applied once per Newton iteration
 *                 (no Krylov iteration): the modified Newton iteration of
 *                 klu with a cheaper factorisation;
 *   auto          schur-direct when 3 nf >= DRAPE_LINSOL_SCHUR_MIN_NF3,
 *                 klu below (measured crossover). */
typedef enum drape_linsol {
    DRAPE_LINSOL_AUTO = 0,
    DRAPE_LINSOL_KLU = 1,
    DRAPE_LINSOL_SCHUR = 2,
    DRAPE_LINSOL_SCHUR_DIRECT = 3
} drape_linsol;
#define DRAPE_LINSOL_SCHUR_MIN_NF3 450L /* 150 free particles (docs/integrators.md) */

/* "auto", "klu", "schur", "schur-direct" -> *out; 0, or -1 for an unknown
 * name.  (Implemented in src/linsol_schur.c.) */
int drape_linsol_parse(const char *name, int *out);
/* Name of a drape_linsol value (as parsed above), "none" otherwise. */
const char *drape_linsol_name(int linsol);

/* A command line's maximum BDF order, "1" to "5" -> *out; 0, or -1. */
int drape_max_order_parse(const char *text, int *out);
/* The highest BDF order integrator `name` runs with when asked for
 * max_order (0 = not set): cvode-bdf and auto use max_order or
 * DRAPE_INTEGRATOR_MAX_ORDER_DEFAULT; 0 for integrators without one. */
int drape_integrator_bdf_order(const char *name, int max_order);

/* Fill o with the defaults: rtol 1e-4, atol 1e-7 m, everything else 0
 * (= the documented default). */
void drape_integrator_opts_default(drape_integrator_opts *o);

/* Counters since the last (re)initialisation; -1 = not available from this
 * backend.  rhs_evals counts calls of the right-hand side (for arkode-imex
 * its explicit and implicit parts are counted separately); conv_fails counts
 * steps rejected because the nonlinear solve failed. */
typedef struct drape_integrator_stats {
    long steps, rhs_evals, jac_evals, lin_setups, nonlin_iters, err_test_fails,
        conv_fails;
    long lin_iters; /* Krylov iterations (linsol schur); 0 for direct solvers */
    long lin_factors; /* numeric factorisations: lin_setups minus the setups
                         that found J and gamma unchanged and kept the factor
                         (SUNDIALS backends; 0 = not counted) */
    int linsol;     /* drape_linsol in use (KLU or SCHUR); 0 = none (explicit,
                       GSL's dense LU) */
    long switches;  /* auto: changes between cvode-bdf and arkode-erk; -1 for
                       the other backends */
    long energy_rescales; /* animate: steps whose velocities were scaled down
                       so that the total energy did not rise; -1 for the
                       others */
} drape_integrator_stats;

/* ---- Backend interface --------------------------------------------------
 * The problem as a backend sees it.  Built by drape_integrator_new; a
 * backend only reads it and calls drape_ode_rhs / drape_ode_jacobian. */
typedef struct drape_ode {
    drape_model *model;            /* borrowed */
    const drape_lattice *lattice;  /* borrowed (the model's) */
    long nf3;                      /* 3 n_free */
    long dim;                      /* 6 n_free */
    unsigned parts;                /* drape_model_parts(model) */
    const drape_pattern *pattern;  /* first-order pattern (dim x dim) */
    double *atol;                  /* dim: absolute tolerance per unknown */
    double *inv_mass;              /* n_free: 1 / m */
    double *x, *v, *f;             /* full 3n scratch (fixed: xinit, 0) */
    long n_rhs, n_jac;             /* evaluation counters */
    const volatile sig_atomic_t *stop; /* drape_integrator_opts.stop */
} drape_ode;

/* ydot = [ include_kinematic ? v : 0 ; M^-1 f_parts(x, v) ] at y.  Returns
 * 0, 1 (recoverable: the model folded, or a non-finite value), or -1 when
 * o->stop is raised (the backends pass it on as an unrecoverable failure). */
int drape_ode_rhs(drape_ode *o, unsigned parts, int include_kinematic,
                  const double *y, double *ydot);
/* o->x, o->v (full 3n) from y (free particles only; fixed keep xinit, 0). */
void drape_ode_scatter(drape_ode *o, const double *y);
/* J (nnz of o->pattern) = Jacobian of that right-hand side.  Returns 0/1. */
int drape_ode_jacobian(drape_ode *o, unsigned parts, int include_kinematic,
                       const double *y, double *J);

typedef enum drape_step_mode {
    DRAPE_STEP_NORMAL, /* reach t_out (dense output if the solver passed it) */
    DRAPE_STEP_ONE     /* one internal step, never past t_stop */
} drape_step_mode;

typedef struct drape_integrator_type {
    const char *name;    /* contract name, e.g. "cvode-bdf" */
    const char *summary; /* one line for --help and docs */
    /* New state at (t0, y0 (dim)).  NULL with err set on failure. */
    void *(*alloc)(drape_ode *ode, const drape_integrator_opts *o, double t0,
                   const double *y0, drape_error *err);
    /* Restart at (t0, y0); counters reset.  May be NULL (not supported). */
    int (*reinit)(void *state, double t0, const double *y0, drape_error *err);
    /* Advance; *t and y (dim) receive the time reached and the state there.
     * On failure returns -1 with err set (E_NUMERIC), *t and y the last
     * state the solver accepted. */
    int (*step_to)(void *state, double t_out, drape_step_mode mode, double *t,
                   double *y, drape_error *err);
    /* Dense output at t inside the last step (y: dim).  Backends without
     * dense output accept only the current time. */
    int (*get_state)(void *state, double t, double *y, drape_error *err);
    void (*stats)(const void *state, drape_integrator_stats *s);
    void (*free)(void *state);
} drape_integrator_type;

extern const drape_integrator_type drape_integrator_cvode_bdf;
extern const drape_integrator_type drape_integrator_arkode_imex;
extern const drape_integrator_type drape_integrator_arkode_dirk;
extern const drape_integrator_type drape_integrator_arkode_erk;
extern const drape_integrator_type drape_integrator_gsl_msbdf;
extern const drape_integrator_type drape_integrator_gsl_rk8pd;
extern const drape_integrator_type drape_integrator_auto;
extern const drape_integrator_type drape_integrator_animate;

/* Registry: the backend called `name` (including "auto"), or NULL. */
const drape_integrator_type *drape_integrator_type_find(const char *name);
/* All backends, NULL-terminated (without "auto"). */
const drape_integrator_type *const *drape_integrator_types(void);

/* ---- The handle ---------------------------------------------------------- */
typedef struct drape_integrator drape_integrator;

/* New integrator `name` for model m (borrowed: must outlive it) starting at
 * t = 0 from the lattice's initial state (xinit, v = 0).  Returns NULL with
 * err set: E_INPUT for an unknown name or bad option, E_NOMEM (also for
 * gsl-msbdf above its memory limit), E_NUMERIC if the solver refuses to
 * start.  Caller frees with drape_integrator_free. */
drape_integrator *drape_integrator_new(drape_model *m, const char *name,
                                       const drape_integrator_opts *o,
                                       drape_error *err);
void drape_integrator_free(drape_integrator *I);

/* Restart at time t0 from full positions x and velocities v (3n each; the
 * entries of fixed particles are ignored).  Counters reset. */
int drape_integrator_reinit(drape_integrator *I, double t0, const double *x,
                            const double *v, drape_error *err);

/* Advance to t_out (NORMAL) or by one internal step (ONE).  0 or -1 with err
 * set (E_NUMERIC naming time, integrator, reason, hint). */
int drape_integrator_step_to(drape_integrator *I, double t_out,
                             drape_step_mode mode, drape_error *err);

/* Time reached by the last step_to (or the start time). */
double drape_integrator_time(const drape_integrator *I);
/* Full positions and velocities (3n each) at drape_integrator_time. */
void drape_integrator_state(const drape_integrator *I, double *x, double *v);
/* Full state at t inside the last step (dense output), 0 or -1. */
int drape_integrator_state_at(drape_integrator *I, double t, double *x,
                              double *v, drape_error *err);

void drape_integrator_get_stats(const drape_integrator *I,
                            drape_integrator_stats *s);
/* Backend name ("auto" for auto; its result keys give the counts of both
 * solvers it used). */
const char *drape_integrator_name(const drape_integrator *I);
/* Number of unknowns (6 n_free). */
long drape_integrator_dim(const drape_integrator *I);

#endif /* DRAPE_INTEGRATOR_H */
