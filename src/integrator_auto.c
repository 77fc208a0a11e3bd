/* integrator_auto.c: the "auto" backend: cvode-bdf and
 * arkode-erk, switching between them while it runs, like LSODA's switch
 * between BDF and Adams (Petzold 1983), on a work estimate from step counts
 * (never from clocks, so a run is reproducible).
 *
 * Measured (docs/integrators.md, "What auto picks"): a BDF2 step of
 * cvode-bdf costs about 1/AUTO_COST of a Dormand-Prince step on these
 * lattices, and Dormand-Prince steps at h omega ~ 2.2 once it is
 * stability-limited (omega: Gershgorin bound of the stiffest mode,
 * drape_model_omega_bound), less when accuracy limits it.  While the cloth
 * moves fast (a fall, a swing) BDF2 resolves the lightly damped stretch
 * vibrations to the velocity tolerance and its steps shrink to
 * h omega ~ 0.04-0.4; as the motion dies out they grow again.
 *
 * Rule.  Start with cvode-bdf.  Every AUTO_WINDOW steps the mean step h of
 * the window is judged (not the first window after a (re)start: the
 * solver's ramp-up):
 *   cvode-bdf:  h omega < erk_hw / AUTO_COST (erk_hw: Dormand-Prince's
 *               h omega in its last window, AUTO_ERK_HW0 before it ran;
 *               or opts.auto_hw when set) -> switch to arkode-erk;
 *   arkode-erk: record erk_hw; every AUTO_PROBE of its steps, if it is
 *               stability-limited (erk_hw >= AUTO_ERK_STIFF), probe
 *               cvode-bdf; a probe whose first judged window is below
 *               AUTO_HYST times the threshold goes back to arkode-erk.
 * A switch restarts the other solver from the accepted state at the
 * current internal time, just before the next step (both have dense output,
 * so output times in between are interpolated by the solver that stepped
 * over them).
 */
#include "drape/integrator.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/model.h"

#define AUTO_WINDOW 100      /* steps per judged window */
#define AUTO_COST 3.4        /* cost of a Dormand-Prince step / a BDF2 step */
#define AUTO_ERK_HW0 2.2     /* Dormand-Prince h omega before it was seen:
                                its stability step */
#define AUTO_HYST 1.23       /* a BDF2 probe must beat the threshold by this */
#define AUTO_ERK_STIFF 1.5   /* Dormand-Prince h omega at or above which its
                                stability limits it; below, accuracy does:
                                the motion is fast, and BDF2 restarted from
                                its state would resolve the same vibrations
                                (every such probe failed, on the hang and
                                limp-silk scenes) */
#define AUTO_PROBE 2000      /* Dormand-Prince steps between probes: a failed
                                probe costs 2 windows of BDF2 steps, a few per
                                cent of this */

typedef struct {
    drape_ode *ode;
    const drape_integrator_type *type[2]; /* 0 cvode-bdf, 1 arkode-erk */
    void *st[2];
    int cur;               /* index of the active solver */
    int next;              /* the solver judge() chose; taken at the next step
                              (so the last step's dense output stays valid) */
    double omega;          /* rad/s, Gershgorin bound at the rest state */
    double theta;          /* fixed threshold (opts.auto_hw), 0 = from erk_hw */
    double erk_hw;         /* Dormand-Prince's h omega in its last window */
    long max_steps;        /* per step_to call */
    double t;              /* internal time of the active solver */
    double *y;             /* dim: its state at t */
    drape_integrator_stats acc; /* counters of the solvers' earlier spells */
    long win_steps;        /* steps in the current window */
    double win_t0;         /* time at its start */
    int windows;           /* windows completed since the last (re)start */
    long spell_steps;      /* steps since the last (re)start */
    int probing;           /* the active cvode-bdf is a probe */
    long switches;
} auto_state;

static void add_stats(drape_integrator_stats *a, const drape_integrator_stats *b)
{
    a->steps += b->steps;
    a->lin_setups += b->lin_setups;
    a->nonlin_iters += b->nonlin_iters;
    a->err_test_fails += b->err_test_fails;
    a->conv_fails += b->conv_fails;
    a->lin_iters += b->lin_iters;
    a->lin_factors += b->lin_factors;
}

static void restart_window(auto_state *a)
{
    a->win_steps = 0;
    a->win_t0 = a->t;
    a->windows = 0;
    a->spell_steps = 0;
}

/* Make solver k the active one, restarted at (a->t, a->y).  The active
 * solver's counters move to a->acc only once the restart succeeded: a
 * failed one leaves it active, and auto_stats counts it once. */
static int switch_to(auto_state *a, int k, drape_error *err)
{
    drape_integrator_stats s;
    if (a->type[k]->reinit(a->st[k], a->t, a->y, err) != 0) return -1;
    a->type[a->cur]->stats(a->st[a->cur], &s);
    add_stats(&a->acc, &s);
    a->cur = k;
    a->switches++;
    restart_window(a);
    return 0;
}

/* h omega below which BDF2 costs more per unit time than Dormand-Prince */
static double threshold(const auto_state *a)
{
    return a->theta > 0.0 ? a->theta : a->erk_hw / AUTO_COST;
}

/* After an accepted step: judge the window when it is full; sets a->next. */
static void judge(auto_state *a)
{
    a->spell_steps++;
    if (++a->win_steps < AUTO_WINDOW) return;
    double hw = (a->t - a->win_t0) / (double)a->win_steps * a->omega;
    a->win_steps = 0;
    a->win_t0 = a->t;
    if (a->windows++ == 0) return; /* ramp-up after a (re)start */
    if (a->cur == 0) {
        double th = threshold(a);
        if (a->probing) {
            a->probing = 0;
            if (hw < AUTO_HYST * th) a->next = 1;
        }
        if (hw < th) a->next = 1;
    } else {
        a->erk_hw = hw;
        if (a->spell_steps >= AUTO_PROBE && hw >= AUTO_ERK_STIFF) {
            a->probing = 1;
            a->next = 0;
        }
    }
}

static void auto_free(void *st)
{
    auto_state *a = st;
    if (!a) return;
    for (int k = 0; k < 2; k++)
        if (a->st[k]) a->type[k]->free(a->st[k]);
    drape_free(a->y);
    drape_free(a);
}

static void *auto_alloc(drape_ode *ode, const drape_integrator_opts *o, double t0,
                        const double *y0, drape_error *err)
{
    auto_state *a = drape_calloc(1, sizeof *a);
    if (!a) goto nomem;
    a->ode = ode;
    a->type[0] = &drape_integrator_cvode_bdf;
    a->type[1] = &drape_integrator_arkode_erk;
    a->y = drape_malloc(sizeof(double) * (size_t)ode->dim);
    if (!a->y) goto nomem;
    for (int k = 0; k < 2; k++) {
        a->st[k] = a->type[k]->alloc(ode, o, t0, y0, err);
        if (!a->st[k]) goto fail;
    }
    if (drape_model_omega_bound(ode->model, ode->parts, ode->lattice->xinit, &a->omega) != 0 ||
        !(a->omega > 0.0) || !isfinite(a->omega))
        a->omega = 0.0; /* no bound: never leave cvode-bdf */
    a->max_steps = o->max_steps > 0 ? o->max_steps : DRAPE_INTEGRATOR_MAX_STEPS_DEFAULT;
    a->theta = o->auto_hw;
    a->erk_hw = AUTO_ERK_HW0;
    a->cur = a->next = 0;
    a->t = t0;
    memcpy(a->y, y0, sizeof(double) * (size_t)ode->dim);
    restart_window(a);
    return a;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "integrator auto: out of memory");
fail:
    auto_free(a);
    return NULL;
}

static int auto_reinit(void *st, double t0, const double *y0, drape_error *err)
{
    auto_state *a = st;
    if (a->type[0]->reinit(a->st[0], t0, y0, err) != 0) return -1;
    memset(&a->acc, 0, sizeof a->acc);
    a->cur = a->next = 0;
    a->t = t0;
    memcpy(a->y, y0, sizeof(double) * (size_t)a->ode->dim);
    a->probing = 0;
    a->erk_hw = AUTO_ERK_HW0;
    a->switches = 0;
    restart_window(a);
    return 0;
}

static int auto_step_to(void *st, double t_out, drape_step_mode mode, double *t,
                        double *y, drape_error *err)
{
    auto_state *a = st;
    int one = mode == DRAPE_STEP_ONE, rc = 0;
    if (!one && a->t >= t_out) /* stepped past it before */
        goto interpolate;
    for (long n = 0;; n++) {
        if (!one && n >= a->max_steps) {
            rc = drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                                 "auto (%s) failed at t = %.9g s: too much work (%ld steps "
                                 "before t = %.9g s); hint: raise --max-steps, loosen rtol, "
                                 "or look for a fault in the scene",
                                 a->type[a->cur]->name, a->t, a->max_steps, t_out);
            break;
        }
        if ((a->next != a->cur && switch_to(a, a->next, err) != 0) ||
            a->type[a->cur]->step_to(a->st[a->cur], t_out, DRAPE_STEP_ONE, &a->t, a->y, err)) {
            rc = -1;
            break;
        }
        /* a step that passes t_out is not judged in NORMAL mode */
        if (a->omega > 0.0 && (one || a->t < t_out)) judge(a);
        if (one || a->t >= t_out) break;
    }
    if (rc != 0 || one || a->t == t_out) {
        *t = a->t;
        memcpy(y, a->y, sizeof(double) * (size_t)a->ode->dim);
        return rc;
    }
interpolate:
    if (a->type[a->cur]->get_state(a->st[a->cur], t_out, y, err) != 0) return -1;
    *t = t_out;
    return 0;
}

static int auto_get_state(void *st, double t, double *y, drape_error *err)
{
    auto_state *a = st;
    return a->type[a->cur]->get_state(a->st[a->cur], t, y, err);
}

static void auto_stats(const void *st, drape_integrator_stats *r)
{
    const auto_state *a = st;
    a->type[a->cur]->stats(a->st[a->cur], r);
    add_stats(r, &a->acc);
    r->switches = a->switches;
    if (a->cur != 0) { /* cvode-bdf's linear solver (it always ran first) */
        drape_integrator_stats b;
        a->type[0]->stats(a->st[0], &b);
        r->linsol = b.linsol;
    }
}

const drape_integrator_type drape_integrator_auto = {
    "auto",
    "cvode-bdf, switching to arkode-erk while BDF2's steps are short against the "
    "explicit stability step, and back (docs/integrators.md, \"What auto picks\")",
    auto_alloc, auto_reinit, auto_step_to, auto_get_state, auto_stats, auto_free};
