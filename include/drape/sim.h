/* sim.h: the driver loop.  It owns simulated time, runs one integrator
 * (integrator.h) from the lattice's initial state, calls an observer between
 * steps (initial state, frame times, end), decides when to stop (t_max or
 * equilibrium, docs/model.md 6) and collects statistics.
 *
 * Output points.  The integrator is advanced to each output point with
 * dense output (it is not forced to step there, except at t_max, which is
 * its stop time): frame times k * frame_every, equilibrium checks
 * j * eq_window / DRAPE_SIM_EQ_CHECKS_PER_WINDOW, and t_max.
 *
 * Equilibrium (docs/model.md 6).  At each check the largest particle speed
 * averaged over the interval since the previous check is taken,
 * max_i |x_i(t_k) - x_i(t_k-1)| / (t_k - t_k-1); the run stops with status
 * "equilibrium" once every check over a span of eq_window has seen a speed
 * below eq_speed.  t_end_s is the end of that window.  The mean speed
 * ignores velocity jitter of stiff modes that moves no particle (integration
 * error; sim.c), and sees every net motion between checks; an oscillation
 * whose period divides the check interval (eq_window / 4) would pass.
 *
 * Faults and interruption (docs/reliability.md).  At every output
 * point after the start the state is checked (diagnose.h: NaN/inf, strain
 * above strain_limit, energy blow-up) before any observer sees it; a fault
 * ends the run with status failed and an E_NUMERIC error naming the time,
 * the particle(s) and the term.  When opts.stop is given it is polled at
 * every output point, after the observer, and by every right-hand side
 * evaluation (so a run stops within one evaluation, not one output
 * interval): non-zero ends the run with status interrupted at the last
 * output point, whose state and checkpoint are kept (drape_sim_run returns
 * 0; no DRAPE_SIM_AT_END call).
 *
 * Resuming.  With x0 (and v0, t0) the run starts at t0 from that state
 * instead of t = 0 from the lattice's initial state: no DRAPE_SIM_AT_START
 * call; frame and equilibrium grids continue (the first frame is the first
 * k * frame_every after t0); eq_below_since and diag_ref carry the
 * equilibrium span and the energy reference of the interrupted run
 * (drape_sim_result), so the resumed run ends like the uninterrupted one
 * up to the integrator's restart (its tolerance).
 */
#ifndef DRAPE_SIM_H
#define DRAPE_SIM_H

#include <signal.h>

#include "drape/diagnose.h"
#include "drape/error.h"
#include "drape/integrator.h"
#include "drape/model.h"
#include "drape/scene.h"

/* Checks of the largest speed per equilibrium window. */
#define DRAPE_SIM_EQ_CHECKS_PER_WINDOW 4

typedef enum drape_sim_status {
    DRAPE_SIM_EQUILIBRIUM,
    DRAPE_SIM_T_MAX,
    DRAPE_SIM_FAILED,
    DRAPE_SIM_INTERRUPTED  /* opts.stop was raised */
} drape_sim_status;

/* "equilibrium", "t_max", "failed", "interrupted". */
const char *drape_sim_status_name(drape_sim_status s);

typedef struct drape_sim_opts {
    char integrator[DRAPE_INTEGRATOR_NAME_MAX]; /* backend name or "auto" */
    double rtol, atol;   /* integrator.h: atol is on positions, m */
    double t_max;        /* s, > 0 */
    int has_equilibrium;
    double eq_speed;     /* m/s, > 0 */
    double eq_window;    /* s, > 0 */
    double frame_every;  /* s; 0 = no frames */
    int max_order;       /* cvode-bdf; 0 = default */
    int linsol;          /* drape_linsol (integrator.h); 0 = auto */
    long max_steps;      /* per output interval; 0 = default */
    int observe_progress; /* 1: also call the observer at every other output point */
    const volatile sig_atomic_t *stop; /* polled at output points and in every
                                          right-hand side; NULL = never */
    double strain_limit; /* stop (failed) above this strain; 0 = no limit */
    double energy_gain;  /* stop (failed) when E rises by this x scale (diagnose.h); 0 = off */
    double t0;           /* resume: start time, s (0 = a fresh run) */
    const double *x0, *v0; /* resume: start state, 3n each (NULL: lattice xinit, rest) */
    double eq_below_since; /* resume: start of the slow span at t0, s; -1 = none */
    const drape_diag_ref *diag_ref; /* resume: energy reference; NULL = the start state */
    double fixed_step;   /* integrator "animate": its step, s */
} drape_sim_opts;

/* Defaults: "auto", rtol 1e-4, atol 1e-7 m, t_max 20 s, no equilibrium
 * (speed 1e-4 m/s and window 0.2 s if switched on), no frames, strain
 * limit DRAPE_DIAG_STRAIN_LIMIT_DEFAULT, energy gain
 * DRAPE_DIAG_ENERGY_GAIN_DEFAULT, no stop flag, a fresh start. */
void drape_sim_opts_default(drape_sim_opts *o);
/* Options of a loaded scene (solver, end (strain_limit too), output.frames). */
void drape_sim_opts_from_scene(const drape_scene *s, drape_sim_opts *o);

/* What an observer call is about (bit mask). */
enum {
    DRAPE_SIM_AT_START = 1u << 0,    /* t = 0 */
    DRAPE_SIM_AT_FRAME = 1u << 1,    /* a frame time k * frame_every */
    DRAPE_SIM_AT_END = 1u << 2,      /* the final state (not called on failure) */
    DRAPE_SIM_AT_PROGRESS = 1u << 3  /* another output point (observe_progress) */
};

typedef struct drape_sim_event {
    unsigned what;       /* DRAPE_SIM_AT_* bits */
    double t;            /* s */
    const double *x;     /* 3n full positions, borrowed for the call */
    const double *v;     /* 3n full velocities, borrowed for the call */
    long steps;          /* integrator steps so far */
    double max_speed;    /* largest particle speed at t, m/s */
} drape_sim_event;

/* Return 0 to go on, or -1 (with err set, e.g. E_IO) to stop the run. */
typedef int (*drape_sim_observer)(void *ctx, const drape_sim_event *ev,
                                  drape_error *err);

typedef struct drape_sim_result {
    drape_sim_status status;
    char integrator[DRAPE_INTEGRATOR_NAME_MAX]; /* backend name ("auto" for auto) */
    double t_end_s;      /* end of the run (failure: time the solver reached) */
    drape_integrator_stats stats; /* at t_end_s: interrupted, those at the last
                           output point (the steps after it are thrown away and
                           a resumed run takes them again) */
    double wall_s;       /* integrator set-up and stepping, observers excluded */
    drape_energies energy; /* potential energy by term at the final state, J */
    double kinetic_J;
    double max_strain;   /* largest stretch strain at the final state */
    double max_speed;    /* m/s at the final state */
    long frames;         /* observer calls with DRAPE_SIM_AT_FRAME */
    double *x, *v;       /* final state, 3n each (failure: last finite state);
                            free with drape_sim_result_free */
    drape_diagnosis diagnosis; /* kind NONE unless a numerical fault stopped the run */
    double eq_below_since;     /* at t_end_s (for a resume), s; -1 = none */
    double check_speed;        /* largest particle speed averaged over the
                                  last equilibrium-check interval, m/s (the
                                  quantity the equilibrium test compares
                                  with eq_speed); NaN if no check was made */
    drape_diag_ref diag_ref;   /* the energy reference used (for a resume) */
} drape_sim_result;

/* Run model m.  observer may be NULL.  Returns 0 when the run ended with
 * status equilibrium, t_max or interrupted; -1 with err set otherwise (E_INPUT for bad
 * options, E_NUMERIC for a solver failure, or the observer's error), the
 * result then has status failed and whatever was computed.  r is always
 * initialised: call drape_sim_result_free on it in every case. */
int drape_sim_run(drape_model *m, const drape_sim_opts *o,
                  drape_sim_observer observer, void *ctx, drape_sim_result *r,
                  drape_error *err);

/* Frees r->x and r->v (not r); safe on a zeroed or already freed result. */
void drape_sim_result_free(drape_sim_result *r);

/* 1/2 sum m |v|^2 over all particles (v full, 3n), J. */
double drape_sim_kinetic_energy(const drape_lattice *L, const double *v);
/* Largest |v_i| over particles, m/s. */
double drape_sim_max_speed(const drape_lattice *L, const double *v);

#endif /* DRAPE_SIM_H */
