/* sim.c: the driver loop (sim.h): time, output points, end conditions,
 * statistics.
 *
 * End conditions (docs/model.md 6): t >= t_max, or equilibrium: the largest
 * particle speed stays below eq_speed at every check over a span of
 * eq_window; checks are eq_window / DRAPE_SIM_EQ_CHECKS_PER_WINDOW apart
 * and read the integrator's dense output, so they never force small steps.
 * The speed at a check is the mean over the interval since the previous
 * check, max_i |x_i(t_k) - x_i(t_k-1)| / (t_k - t_k-1), not the
 * instantaneous max_i |v_i|: a settled drape can carry velocity jitter of
 * the stiff modes (arkode-imex on the default Cusick scene: 4e-4 m/s at
 * t = 20 s while no particle moved more than 1.3e-7 m between frames 0.05 s
 * apart), which is integration error, not motion (docs/integrators.md).
 * The mean speed also sees motion between checks that the instantaneous
 * one missed.
 * Energies reported at the end: E_kin = 1/2 sum m_i |v_i|^2 (docs/model.md 4) and
 * the potential terms of drape_model_energy (docs/model.md 3).
 */
#include "drape/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "drape/alloc.h"

/* Two output times closer than this fraction of the larger are the same
 * point (frame and check grids computed as k * step). */
#define SIM_TIME_FUZZ 1e-9

const char *drape_sim_status_name(drape_sim_status s)
{
    switch (s) {
    case DRAPE_SIM_EQUILIBRIUM: return "equilibrium";
    case DRAPE_SIM_T_MAX: return "t_max";
    case DRAPE_SIM_FAILED: return "failed";
    case DRAPE_SIM_INTERRUPTED: return "interrupted";
    }
    return "failed";
}

void drape_sim_opts_default(drape_sim_opts *o)
{
    memset(o, 0, sizeof *o);
    snprintf(o->integrator, sizeof o->integrator, "auto");
    o->rtol = 1e-4;
    o->atol = 1e-7;
    o->t_max = 20.0;
    o->eq_speed = 1e-4;
    o->eq_window = 0.2;
    o->strain_limit = DRAPE_DIAG_STRAIN_LIMIT_DEFAULT;
    o->energy_gain = DRAPE_DIAG_ENERGY_GAIN_DEFAULT;
    o->eq_below_since = -1.0;
}

void drape_sim_opts_from_scene(const drape_scene *s, drape_sim_opts *o)
{
    drape_sim_opts_default(o);
    if (s->integrator[0]) snprintf(o->integrator, sizeof o->integrator, "%s", s->integrator);
    o->rtol = s->rtol;
    o->atol = s->atol;
    o->t_max = s->t_max;
    o->has_equilibrium = s->has_equilibrium;
    if (s->has_equilibrium) {
        o->eq_speed = s->eq_speed;
        o->eq_window = s->eq_window;
    }
    o->frame_every = s->has_frames ? s->frame_every : 0.0;
    o->max_order = s->max_order;
    o->strain_limit = s->strain_limit;
    o->fixed_step = drape_scene_animate_step(s, NULL, NULL); /* animate only */
}

void drape_sim_result_free(drape_sim_result *r)
{
    if (!r) return;
    drape_free(r->x);
    drape_free(r->v);
    r->x = r->v = NULL;
}

double drape_sim_kinetic_energy(const drape_lattice *L, const double *v)
{
    double e = 0.0;
    for (int i = 0; i < L->n; i++) {
        const double *q = v + 3 * i;
        e += 0.5 * L->mass[i] * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    }
    return e;
}

double drape_sim_max_speed(const drape_lattice *L, const double *v)
{
    double s2 = 0.0;
    for (int i = 0; i < L->n; i++) {
        const double *q = v + 3 * i;
        double a = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
        if (a > s2) s2 = a;
    }
    return sqrt(s2);
}

/* Largest particle displacement from xa to xb over dt, m/s (dt > 0). */
static double mean_speed(const drape_lattice *L, const double *xa,
                         const double *xb, double dt)
{
    double d2 = 0.0;
    for (int i = 0; i < L->n; i++) {
        double dx = xb[3 * i] - xa[3 * i], dy = xb[3 * i + 1] - xa[3 * i + 1],
               dz = xb[3 * i + 2] - xa[3 * i + 2];
        double q = dx * dx + dy * dy + dz * dz;
        if (q > d2) d2 = q;
    }
    return dt > 0.0 ? sqrt(d2) / dt : INFINITY;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int all_finite(const double *a, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(a[i])) return 0;
    return 1;
}

static int check_opts(const drape_sim_opts *o, drape_error *err)
{
    if (!(o->t_max > 0.0) || !isfinite(o->t_max))
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "end.t_max",
                               "must be a positive time, got %g s", o->t_max);
    if (o->has_equilibrium && (!(o->eq_speed > 0.0) || !(o->eq_window > 0.0) ||
                               !isfinite(o->eq_window)))
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "end.equilibrium",
                               "speed and window must be positive, got %g m/s, %g s",
                               o->eq_speed, o->eq_window);
    if (!(o->frame_every >= 0.0) || !isfinite(o->frame_every))
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "output.frames.every",
                               "must be a positive time, got %g s", o->frame_every);
    if (!(o->strain_limit >= 0.0) || !(o->energy_gain >= 0.0))
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "end.strain_limit",
                               "limits must be non-negative, got strain %g, energy gain %g",
                               o->strain_limit, o->energy_gain);
    if (!(o->t0 >= 0.0) || !(o->t0 < o->t_max))
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "end.t_max",
                               "the start time %.9g s must lie in [0, t_max = %.9g s)",
                               o->t0, o->t_max);
    return 0;
}

static int same_time(double a, double b)
{
    return fabs(a - b) <= SIM_TIME_FUZZ * fmax(fabs(a), fabs(b));
}

/* Index k >= 1 of the first grid point k * step after t0 (a point that is
 * t0 itself, up to SIM_TIME_FUZZ, was handled before the resume). */
static long first_after(double t0, double step)
{
    long k = (long)floor(t0 / step) + 1;
    if (k < 1) k = 1;
    while (k > 1 && (double)(k - 1) * step > t0 && !same_time((double)(k - 1) * step, t0)) k--;
    while ((double)k * step < t0 || same_time((double)k * step, t0)) k++;
    return k;
}

/* Check the state at an output point; a fault sets err (E_NUMERIC). */
static int diagnose_point(drape_model *m, const drape_sim_opts *o, const drape_integrator *I,
                          double t, const double *x, const double *v, drape_sim_result *r,
                          drape_error *err)
{
    char what[400];
    if (drape_diagnose(m, t, x, v, o->strain_limit, o->energy_gain, &r->diag_ref,
                       &r->diagnosis) == 0)
        return 0;
    drape_diagnosis_format(&r->diagnosis, what, sizeof what);
    const char *name = drape_integrator_name(I);
    /* explicit methods: an implicit one is the cure; implicit ones at loose
     * tolerance (gsl-msbdf at rtol 1e-2 in the hard-case suite): an
     * L-stable one or a tighter rtol */
    int expl = strcmp(name, "arkode-erk") == 0 || strcmp(name, "gsl-rk8pd") == 0;
    const char *hint = expl ? "tighten rtol or use an implicit integrator (cvode-bdf, arkode-dirk)"
                            : "tighten rtol, or use an L-stable integrator (arkode-dirk, or "
                              "cvode-bdf at its default maximum order 2)";
    if (r->diagnosis.kind == DRAPE_DIAG_STRAIN)
        hint = "tighten rtol, or raise end.strain_limit (--strain-limit) if such a "
               "strain is physical";
    return drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL, "%s: %s; hint: %s",
                           name, what, hint);
}

static int notify(drape_sim_observer obs, void *ctx, unsigned what, double t,
                  const double *x, const double *v, long steps, double speed,
                  drape_error *err)
{
    if (!obs) return 0;
    drape_sim_event ev = {what, t, x, v, steps, speed};
    if (obs(ctx, &ev, err) == 0) return 0;
    drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                    "an observer stopped the run at t = %.9g s without a message", t);
    return -1;
}

int drape_sim_run(drape_model *m, const drape_sim_opts *o,
                  drape_sim_observer observer, void *ctx, drape_sim_result *r,
                  drape_error *err)
{
    const drape_lattice *L = drape_model_lattice(m);
    size_t n3 = 3 * (size_t)L->n;
    drape_integrator *I = NULL;
    double *x = NULL, *v = NULL, *xc = NULL; /* xc: positions at the last check */
    int rc = -1;
    double wall = 0.0, w0;
    drape_integrator_stats st, st_point; /* st_point: at the last output point */
    const int resume = o->x0 != NULL || o->v0 != NULL || o->t0 > 0.0;

    memset(r, 0, sizeof *r);
    r->status = DRAPE_SIM_FAILED;
    r->eq_below_since = -1.0;
    r->check_speed = NAN;
    r->stats.switches = -1; /* no integrator yet: not available */
    r->stats.energy_rescales = -1;
    r->diagnosis.kind = DRAPE_DIAG_NONE;
    r->diagnosis.term = "";
    if (check_opts(o, err)) return -1;
    r->x = drape_calloc(n3 ? n3 : 1, sizeof(double));
    r->v = drape_calloc(n3 ? n3 : 1, sizeof(double));
    x = drape_malloc(sizeof(double) * (n3 ? n3 : 1));
    v = drape_malloc(sizeof(double) * (n3 ? n3 : 1));
    xc = drape_malloc(sizeof(double) * (n3 ? n3 : 1));
    if (!r->x || !r->v || !x || !v || !xc) {
        drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
        goto out;
    }
    memcpy(r->x, o->x0 ? o->x0 : L->xinit, sizeof(double) * n3);
    if (o->v0) memcpy(r->v, o->v0, sizeof(double) * n3);
    if (o->diag_ref) r->diag_ref = *o->diag_ref;
    else drape_diag_ref_init(m, r->x, r->v, &r->diag_ref);

    drape_integrator_opts io;
    drape_integrator_opts_default(&io);
    io.rtol = o->rtol;
    io.atol = o->atol;
    io.t_stop = o->t_max;
    io.max_order = o->max_order;
    io.max_steps = o->max_steps;
    io.linsol = o->linsol;
    io.fixed_step = o->fixed_step;
    io.stop = o->stop;
    w0 = now_s();
    I = drape_integrator_new(m, o->integrator, &io, err);
    if (I && resume && drape_integrator_reinit(I, o->t0, r->x, r->v, err) != 0) {
        drape_integrator_free(I);
        I = NULL;
    }
    wall += now_s() - w0;
    if (!I) goto out;
    snprintf(r->integrator, sizeof r->integrator, "%s", drape_integrator_name(I));

    const int frames = o->frame_every > 0.0;
    const int eq = o->has_equilibrium;
    const double dt_check = eq ? o->eq_window / DRAPE_SIM_EQ_CHECKS_PER_WINDOW : 0.0;
    long k_frame = frames ? first_after(o->t0, o->frame_every) : 1;
    long k_check = eq ? first_after(o->t0, dt_check) : 1;
    double t = o->t0, below_since = -1.0, speed, t_check = o->t0;
    unsigned last_what = 0;

    drape_integrator_state(I, x, v);
    drape_integrator_get_stats(I, &st_point);
    if (resume) {
        /* the start state was checked and observed by the interrupted run */
        below_since = eq ? o->eq_below_since : -1.0;
        speed = drape_sim_max_speed(L, v);
    } else {
        if (!all_finite(x, n3)) {
            diagnose_point(m, o, I, 0.0, x, v, r, err);
            goto out;
        }
        speed = drape_sim_max_speed(L, v);
        if (eq && speed < o->eq_speed) below_since = 0.0;
        last_what = DRAPE_SIM_AT_START | (frames ? DRAPE_SIM_AT_FRAME : 0u);
        if (frames) r->frames++;
        if (notify(observer, ctx, last_what, 0.0, x, v, 0, speed, err)) goto out;
    }
    memcpy(r->x, x, sizeof(double) * n3);
    memcpy(r->v, v, sizeof(double) * n3);
    memcpy(xc, x, sizeof(double) * n3);
    r->check_speed = NAN;
    last_what = 0;

    for (;;) {
        if (o->stop && *o->stop) {
            r->status = DRAPE_SIM_INTERRUPTED;
            break;
        }
        double tf = frames ? (double)k_frame * o->frame_every : INFINITY;
        double tc = eq ? (double)k_check * dt_check : INFINITY;
        double t_next = fmin(o->t_max, fmin(tf, tc));
        int is_frame = frames && same_time(tf, t_next);
        int is_check = eq && same_time(tc, t_next);
        int is_end = same_time(o->t_max, t_next);
        if (is_end) t_next = o->t_max;

        w0 = now_s();
        int src = drape_integrator_step_to(I, t_next, DRAPE_STEP_NORMAL, err);
        wall += now_s() - w0;
        drape_integrator_state(I, x, v);
        if (src && o->stop && *o->stop) {
            /* stopped inside the interval (the right-hand side refused to
             * run): the run ends at the last output point, whose state
             * r->x, r->v hold and whose checkpoint the observer has */
            drape_error_clear(err);
            memcpy(x, r->x, sizeof(double) * n3);
            memcpy(v, r->v, sizeof(double) * n3);
            r->status = DRAPE_SIM_INTERRUPTED;
            break;
        }
        if (src) {
            t = drape_integrator_time(I);
            if (all_finite(x, n3) && all_finite(v, n3)) {
                memcpy(r->x, x, sizeof(double) * n3);
                memcpy(r->v, v, sizeof(double) * n3);
            }
            goto out;
        }
        /* a fault stops the run before any observer sees the state;
         * r->x, r->v keep the last good one */
        if (diagnose_point(m, o, I, t_next, x, v, r, err)) goto out;
        t = t_next;
        drape_integrator_get_stats(I, &st_point);
        memcpy(r->x, x, sizeof(double) * n3);
        memcpy(r->v, v, sizeof(double) * n3);
        speed = drape_sim_max_speed(L, v);
        if (is_frame) k_frame++;
        if (is_check) k_check++;

        int settled = 0;
        if (is_check) {
            double mean = mean_speed(L, xc, x, t - t_check);
            memcpy(xc, x, sizeof(double) * n3);
            t_check = t;
            r->check_speed = mean;
            if (mean < o->eq_speed) {
                if (below_since < 0.0) below_since = t;
                if (t - below_since >= o->eq_window * (1.0 - SIM_TIME_FUZZ)) settled = 1;
            } else {
                below_since = -1.0;
            }
        }
        if (settled || is_end) {
            r->status = settled ? DRAPE_SIM_EQUILIBRIUM : DRAPE_SIM_T_MAX;
            last_what = DRAPE_SIM_AT_END | (is_frame ? DRAPE_SIM_AT_FRAME : 0u);
            break;
        }
        unsigned what = is_frame ? DRAPE_SIM_AT_FRAME
                        : o->observe_progress ? DRAPE_SIM_AT_PROGRESS : 0u;
        if (what) {
            drape_integrator_get_stats(I, &st);
            if (is_frame) r->frames++;
            if (notify(observer, ctx, what, t, x, v, st.steps, speed, err)) goto out;
        }
    }

    r->t_end_s = t;
    r->eq_below_since = below_since;
    drape_integrator_get_stats(I, &st);
    if (last_what & DRAPE_SIM_AT_FRAME) r->frames++;
    if (last_what && notify(observer, ctx, last_what, t, x, v, st.steps, speed, err)) {
        r->status = DRAPE_SIM_FAILED;
        goto out;
    }
    rc = 0;

out:
    if (rc != 0) {
        r->status = DRAPE_SIM_FAILED;
        r->t_end_s = I ? drape_integrator_time(I) : o->t0;
    }
    r->wall_s = wall;
    /* an interrupted run ends at its last output point, the state a
     * resumed run starts from: the work after it was thrown away and is
     * done again, so it is not counted (docs/outputs.md) */
    if (I && r->status == DRAPE_SIM_INTERRUPTED) r->stats = st_point;
    else if (I) drape_integrator_get_stats(I, &r->stats);
    if (r->x && r->v) {
        drape_model_energy(m, r->x, &r->energy);
        r->kinetic_J = drape_sim_kinetic_energy(L, r->v);
        r->max_strain = drape_model_max_strain(m, r->x);
        r->max_speed = drape_sim_max_speed(L, r->v);
    }
    drape_integrator_free(I);
    drape_free(x);
    drape_free(v);
    drape_free(xc);
    return rc;
}
