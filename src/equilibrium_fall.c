/* equilibrium_fall.c: the fall (E9 of equilibrium.c), the damped implicit
 * dynamics that the fall method runs before the static solver settles the
 * cloth: linearly implicit BDF2 at a fixed step (with the swing criterion
 * and its longer step) or at a step chosen by its error in position
 * (dyn_tol), and the energy balance of every step.  docs/ensemble.md. */
#include <math.h>
#include <string.h>

#include "drape/alloc.h"
#include "equilibrium_impl.h"

/* The fall's swing at the long step: the largest rise of the total energy
 * (in units of the peak kinetic energy) before the long step is refused.
 * At the fall's own step the rises measured in the swing of the Cusick
 * scene (cotton, tablecloth, jacket at 1 cm) stay below 0.12 % per step
 * (BDF2 is not energy-monotone). */
#define DRAPE_EQ_SWING_RISE 1e-2
/* (E9) The error-controlled fall (dyn_tol): a step whose total energy rises
 * by more than this fraction of the energy dissipated so far is redone at
 * half the step (BDF1 restart).  The model dissipates; a rise is the
 * linearly implicit step's, which at long steps pumped energy into folds
 * and kept the cloth swinging (measured on the Cusick scene at 1 cm and
 * 100 um: rises of 2 % of the dissipated energy in one step, the fall run
 * to its longest; with 1e-2 here they go on, with 1e-3 and 1e-4 they
 * stop; docs/ensemble.md). */
#define DRAPE_EQ_FALL_RISE 1e-4
/* (E9) The fixed-step fall at its shorter steps (the fold step, the fall
 * step, which have no guard of their own): once the kinetic energy has
 * fallen to half its peak (before that the peak so far is no scale for
 * the fall's energy), a step that leaves the total energy more than this
 * fraction of the peak kinetic energy above its lowest value so far ends
 * the fall, and the specimen's fall goes on from the state of its lowest
 * total energy with its step chosen by its error (dyn_redo_tol, as when
 * the energy rises above its start: equilibrium.c).  The model
 * dissipates: energy that the fall keeps gaining is its linearly implicit
 * step's, whose matrix drops the compressed springs' negative stiffness.  Measured on the table scene
 * at 1 cm: seeds 11 and 12 gain 43 % and 67 % of the peak kinetic energy
 * from about 0.7 s on, step by step (seed 11: 1,134 of 2,559 steps
 * raise it), and swing on to the longest fall (4 fall times); halving the
 * step does not stop it.  In the falls that do not pump, the largest such
 * rise found was 3.3 % (cotton, 0.11 s into the fall, while the kinetic
 * energy still grows; cotton, cotton-breen-kes, cotton-poly and the
 * tablecloth on the Cusick scene and the table's other seeds, 32
 * specimens each; docs/ensemble.md, "The fall that pumps energy"). */
#define DRAPE_EQ_PUMP_RISE 0.1
/* How often a refused longer step of the fixed-step fall is tried again
 * (o->dyn_retry) after each change to it.  A retry that is refused again
 * means the state still pumps energy at the longer step: retried without
 * end on the table scene at 1 cm (seeds 7-10) every accepted retry raised
 * the total energy up to the guard, the cloth swung on to the longest fall
 * (4 fall times) and the specimens took 2,600-4,500 factorisations
 * against 985-1,049 with one retry (docs/ensemble.md, "Trying the longer step
 * again"). */
#define DRAPE_EQ_RETRY_MAX 1
/* The longest ring of kinetic energies the fall's swing criterion keeps
 * (its window at the shortest step). */
#define DRAPE_EQ_KE_WINDOW_MAX 65536

/* Kinetic energy of the free particles at velocities v (3n), J. */
static double kinetic_energy(const eq_work *w, const double *v)
{
    double ke = 0.0;
    for (int p = 0; p < w->nf; p++) {
        const double *vi = v + 3 * (long)w->L->free_to_id[p];
        ke += 0.5 * w->mrow[3 * p] * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
    }
    return ke;
}

/* Kinetic + potential energy at (x, v), J; INFINITY where folded. */
static double total_energy(eq_work *w, const double *x, const double *v)
{
    drape_energies E;
    w->r->energy_evals++;
    if (drape_model_energy(w->m, x, &E) != 0) return INFINITY;
    return kinetic_energy(w, v) + E.stretch + E.bend + E.shear + E.gravity;
}

/* The fall's state and record at time t, into *s. */
static void fall_record(const eq_work *w, eq_fall_state *s, const double *x,
                        const double *v, double t, double ke_peak, double ke_win)
{
    size_t n3 = 3 * (size_t)w->L->n;
    const drape_equilibrium_result *r = w->r;
    memcpy(s->x, x, sizeof(double) * n3);
    memcpy(s->v, v, sizeof(double) * n3);
    s->t = t;
    s->e_start = r->dyn_e_start;
    s->e_max = r->dyn_e_max;
    s->e_max_rise = r->dyn_e_max_rise;
    s->dt_min = r->dyn_dt_min;
    s->dt_max = r->dyn_dt_max;
    s->ke_peak = ke_peak;
    s->ke_win = ke_win;
    s->steps = r->dyn_steps;
    s->refused = r->dyn_refused;
}

/* (E9) Damped implicit dynamics: M x'' = f(x, v) (all of the model's
 * parts, its damping included) from rest, by linearly implicit BDF2
 * (BDF1 = backward Euler for the first step and after a refused
 * factorisation):
 *     x_{n+1} = xh + b h v_{n+1},  M (v_{n+1} - vh) = b h f(x_{n+1}, v_{n+1})
 *     BDF1: xh = x_n, vh = v_n, b = 1;
 *     BDF2: xh = (4 x_n - x_{n-1})/3, vh = (4 v_n - v_{n-1})/3, b = 2/3,
 *     and with steps of ratio r = h_n / h_{n-1} (o->dyn_tol):
 *     xh = ((1 + r)^2 x_n - r^2 x_{n-1}) / (1 + 2 r), the same for vh,
 *     b = (1 + r) / (1 + 2 r),
 * one Newton iteration from v = v_n (x0 = xh + b h v_n):
 *     (M - b h D - (b h)^2 K) dv = M (vh - v_n) + b h f(x0, v_n),
 * K (the conservative forces' df/dx) and D (the dampers' df/dv) at
 * (x0, v_n).  Runs for time o->dyn_time (it follows the physical fall,
 * with inertia, into the basin that the dynamic run would reach), the
 * first o->dyn_time_fold of it (while the folds form) at the step
 * o->dyn_dt_fold,
 * then, with o->dyn_ke_frac > 0, on while the cloth swings (up to T_max)
 * at the step o->dyn_dt_swing (0 = dyn_dt), from a BDF1 step.  A longer
 * step that raises the total energy (the fall step after the fold phase,
 * the swing's step) is refused and the dynamics go on at the shorter step;
 * with o->dyn_retry > 0 they try the longer step again that long after
 * the refusal (once per change of step: DRAPE_EQ_RETRY_MAX), its guard
 * counting from the lowest total energy since the first change of step.
 *
 * With o->dyn_tol > 0 the step is chosen instead: the local error of the
 * positions is estimated from the difference between the BDF2 result and
 * the quadratic through x_{n-1}, x_n with slope v_n (for BDF2 the error is
 * 2/5 of that difference at constant step: error constants -2/9 and 1/3),
 * its largest particle norm e is kept below dyn_tol (a step with e > 1.5
 * dyn_tol is redone), and the next step is 0.9 (dyn_tol / e)^(1/3) times
 * this one (1/4 to 2 times, within [dyn_dt / 64, 8 dyn_dt]).  Positions,
 * not velocities: the stretch vibrations that the fall excites are large
 * in velocity but small in position (a strain of 1e-4 is a micrometre at
 * 1 cm), and are damped by the step, not followed.  Its matrix keeps the
 * conservative forces' whole Jacobian (no compression clamp), and a step
 * whose total energy rises by
 * more than DRAPE_EQ_FALL_RISE of the energy dissipated so far is redone
 * at half the step: the position estimate does not see a step that pumps
 * energy into a fold.  Every step's total energy is recorded (r->dyn_e_*).
 * Returns 0, 1 (folded or too small a step), 2 (stop raised), 3 (a
 * fixed-step fall whose total energy rose above its start, or kept
 * rising at its shorter step (DRAPE_EQ_PUMP_RISE, r->dyn_pumped), with
 * o->dyn_redo_tol > 0: x is then a state of no use, and *low, if given,
 * the state of the lowest total energy, from which the caller goes on) or
 * -1 (err set).  From a state *from (the caller's *low of an earlier
 * fall), the fall's time, record and peak kinetic energy go on from
 * there, and its swing window starts with that state's largest kinetic
 * energy over the window. */
int eq_fall(eq_work *w, double *x, const drape_equilibrium_opts *o, double T_max,
            const eq_fall_state *from, eq_fall_state *low, drape_error *err)
{
    unsigned parts_all = drape_model_parts(w->m);
    const drape_lattice *L = w->L;
    const drape_pattern *P = w->pat;
    drape_equilibrium_result *r = w->r;
    const double T = o->dyn_time, ke_frac = o->dyn_ke_frac, tol = o->dyn_tol;
    const int adaptive = tol > 0.0;
    /* the fixed step's fold phase: [0, T_fold) at dyn_dt_fold */
    const double T_fold = adaptive ? 0.0 : fmin(o->dyn_time_fold, T);
    int folding = T_fold > 0.0;
    double h = adaptive ? 0.25 * o->dyn_dt : folding ? o->dyn_dt_fold : o->dyn_dt;
    double h_swing = adaptive ? 0.0 : o->dyn_dt_swing;
    const double h_min = o->dyn_dt / 64.0, h_max = 8.0 * o->dyn_dt;
    size_t n3 = 3 * (size_t)L->n;
    double *xp = w->xz, *vp = w->fz, *x0 = w->xt, *v = w->vel;  /* previous step, trial */
    if (from) memcpy(v, from->v, sizeof(double) * n3);
    else memset(v, 0, sizeof(double) * n3);
    double t = from ? from->t : 0.0, ke_peak = from ? from->ke_peak : 0.0;
    double ke_win = 0.0, tw = 0.2 * T;
    /* the kinetic energy's largest value over the last tw = T / 5 (two
     * pendulum times of the Cusick fall), so that a swing's turning point
     * does not end the fall: a ring of the last nwin steps' (t, E_kin),
     * enough for tw at the shortest step */
    double h_short = adaptive ? h_min : fmin(fmin(h, o->dyn_dt), h_swing > 0.0 ? h_swing : h);
    /* capped before the conversion: tw / h_short can exceed any int */
    double nw = ceil(tw / h_short) + 1.0;
    int nwin = nw < DRAPE_EQ_KE_WINDOW_MAX ? (int)nw : DRAPE_EQ_KE_WINDOW_MAX, iw = 0;
    double *ring = drape_malloc(2 * (size_t)nwin * sizeof(double)), *ring_t = ring + nwin;
    if (!ring)
        return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
    for (int k = 0; k < nwin; k++) { /* no step yet */
        ring[k] = 0.0;
        ring_t[k] = -INFINITY;
    }
    if (from) { /* the window's largest kinetic energy so far, as if at t */
        ring[0] = ke_win = from->ke_win;
        ring_t[0] = t;
        iw = 1 % nwin;
    }
    int have_prev = 0, swinging = 0, long_step = 0;
    double h_fall = h, e_low = INFINITY; /* the lowest total energy at the long step */
    double h_prev = 0.0;                 /* the last step taken */
    /* after a refused long step: when to try it again, and that step */
    double t_retry = INFINITY, h_retry = 0.0;
    int retries = 0; /* retries left for the present longer step */
    int rc = 0;
    double e_prev = total_energy(w, x, v);
    if (from) { /* the record of the fall up to from->t goes on */
        r->dyn_steps = from->steps;
        r->dyn_refused = from->refused; /* not those of the fall thrown away */
        r->dyn_dt_min = from->dt_min;
        r->dyn_dt_max = from->dt_max;
        r->dyn_e_start = from->e_start;
        r->dyn_e_max = from->e_max;
        r->dyn_e_max_rise = from->e_max_rise;
    } else {
        r->dyn_steps = 0;
        r->dyn_dt_min = INFINITY;
        r->dyn_dt_max = 0.0;
        r->dyn_e_start = r->dyn_e_max = e_prev;
        r->dyn_e_max_rise = NAN;
    }
    r->dyn_e_end = e_prev;
    double e_low_all = e_prev; /* the lowest total energy so far */
    /* the largest kinetic energy so far, and whether it has since fallen
     * to half of that (the pump guard's scale, and when it starts) */
    double ke_max = ke_peak;
    int ke_fell = 0;
    if (low) fall_record(w, low, x, v, t, ke_max, ke_win);
    for (;;) {
        /* the folds have formed: on at dyn_dt, or at the same fraction of
         * it if the fold phase's step was halved; the first longer step is
         * the variable-step BDF2 below (a BDF1 restart here, first order,
         * cost the chain of test_fall_fold more accuracy than the fold
         * phase had gained).  Like the swing's, the longer step is refused
         * if it raises the total energy (it can pump energy into folds
         * that are forming: measured on the table scene), and the fall
         * goes on at the fold step */
        if (folding && t >= T_fold * (1.0 - 1e-12)) {
            folding = 0;
            h_fall = h;
            h = o->dyn_dt * (h / o->dyn_dt_fold);
            long_step = 1;
            retries = DRAPE_EQ_RETRY_MAX;
            e_low = total_energy(w, x, v);
        }
        /* the longer step again, a while after it was refused (dyn_retry:
         * the state that it pumped has moved on; on cotton-poly at 1 cm
         * one pendulum time later it is accepted on most specimens that
         * refused it, docs/ensemble.md, "Trying the longer step again"),
         * at most DRAPE_EQ_RETRY_MAX times per change of step; from a BDF1
         * step if more than twice the step (variable-step BDF2 is
         * zero-stable up to a ratio of 1 + sqrt 2), the guard's e_low
         * going on from the shorter steps' lowest energy */
        if (!long_step && t >= t_retry * (1.0 - 1e-12)) {
            h_fall = h;
            if (h_retry > 2.0 * h * (1.0 + 1e-9)) have_prev = 0;
            h = h_retry;
            long_step = 1;
            t_retry = INFINITY;
        }
        /* past T, go on (whole steps, the last one cut at T_max) while the
         * cloth still swings, at the step h_swing (BDF1 restart) */
        int extend = 0;
        if (t >= T * (1.0 - 1e-12)) {
            if (!(ke_frac > 0.0) || ke_win <= ke_frac * ke_peak || t >= T_max * (1.0 - 1e-12))
                break;
            extend = 1;
            if (!swinging && h_swing > 0.0 && h_swing != h) {
                h_fall = h;
                h = h_swing;
                have_prev = 0;
                long_step = 1;
                t_retry = INFINITY; /* the swing's own long step */
                retries = DRAPE_EQ_RETRY_MAX;
                e_low = total_energy(w, x, v);
            }
            swinging = 1;
        }
        if (o->stop && *o->stop) { rc = 2; break; }
        double rem = (folding ? T_fold : extend ? T_max : T) - t;
        /* a whole step when the rest is h but for rounding: no BDF1
         * restart */
        double hs = rem > h * (1.0 - 1e-9) ? h : rem;
        int bdf2 = have_prev;
        /* BDF2 with a step ratio: the error-controlled fall, the first step
         * after the fold phase, and a fixed-step fall's last step when cut */
        int vs = bdf2 && (adaptive || hs != h_prev);
        double b = bdf2 ? 2.0 / 3.0 : 1.0, c1 = 4.0 / 3.0, c2 = -1.0 / 3.0;
        if (vs) {
            double q = hs / h_prev;
            c1 = (1.0 + q) * (1.0 + q) / (1.0 + 2.0 * q);
            c2 = -q * q / (1.0 + 2.0 * q);
            b = (1.0 + q) / (1.0 + 2.0 * q);
        }
        double bh = b * hs;
        /* predictor x0 = xh + b h v_n; the free part of M (vh - v_n) */
        memcpy(x0, x, sizeof(double) * n3);
        for (int p = 0; p < w->nf; p++) {
            long k = 3 * (long)L->free_to_id[p];
            for (int c = 0; c < 3; c++) {
                double xh, vh;
                if (!bdf2) {
                    xh = x[k + c];
                    vh = v[k + c];
                } else if (!vs) { /* the fixed step's own arithmetic */
                    xh = (4.0 * x[k + c] - xp[k + c]) / 3.0;
                    vh = (4.0 * v[k + c] - vp[k + c]) / 3.0;
                } else {
                    xh = c1 * x[k + c] + c2 * xp[k + c];
                    vh = c1 * v[k + c] + c2 * vp[k + c];
                }
                x0[k + c] = xh + bh * v[k + c];
                w->rch[3 * p + c] = w->mrow[3 * p] * (vh - v[k + c]);
            }
        }
        r->force_evals++;
        r->jacobian_evals++;
        /* the matrix: K of the conservative parts and D of the dampers,
         * without the dampers' own dK (their x-dependence: edge dashpots'
         * direction, shear damping's angle gradient), which is not
         * symmetric (docs/model.md) while CHOLMOD reads the lower triangle
         * only; as in animate.  With it, the lower triangle mirrored made
         * the linearly implicit step unstable on the table scene at 1 cm
         * with shear damping (seed 22: a rise of the total energy by 144 J,
         * 16,400 steps; 2e-7 J and 500 steps without it; docs/ensemble.md).
         * The force of each group comes from the same pass as its matrix
         * (the conservative one into fd, the dampers' into ft, a scratch
         * array of the static stage that follows), then fd += ft. */
        if (drape_model_eval(w->m, parts_all & ~DRAPE_PARTS_DAMPING, x0, v, w->fd, w->K,
                             NULL) != 0 ||
            drape_model_eval(w->m, parts_all & DRAPE_PARTS_DAMPING, x0, v, w->ft, NULL,
                             w->D) != 0) {
            if (h < 1e-6 * T) { rc = 1; break; }
            h *= 0.5;
            have_prev = 0;
            continue;
        }
        for (size_t k = 0; k < n3; k++) w->fd[k] += w->ft[k];
        /* the fixed step's matrix drops the compressed springs' negative
         * stiffness (E8), to stay positive definite at long steps; the
         * error-controlled step keeps the whole K: with the clamp
         * its linearly implicit step, a W-method where springs are
         * compressed, pumped energy into folds (measured on the Cusick
         * scene at 1 cm: the total energy rose by 25 % of the fall's peak
         * kinetic energy and the cloth never stopped swinging), and its
         * steps are short enough for the unclamped matrix (a matrix that
         * is not positive definite halves the step) */
        const double *Kc = NULL;
        if (w->Kc && !adaptive) {
            drape_model_compression_clamp(w->m, x0, w->kclamp, w->Kc);
            Kc = w->Kc;
        }
        double *ax = w->ax;
        for (int64_t k = 0; k < P->nnz; k++)
            ax[k] = -bh * w->D[k] - bh * bh * (w->K[k] + (Kc ? Kc[k] : 0.0));
        for (long j = 0; j < w->N; j++) ax[w->dpos[j]] += w->mrow[j];
        int pd = eq_factorize(w, err);
        if (pd < 0) { rc = -1; break; }
        if (pd == 0) { /* too long a step for the negative curvature */
            if (h < 1e-6 * T) { rc = 1; break; }
            h *= 0.5;
            have_prev = 0;
            continue;
        }
        for (int p = 0; p < w->nf; p++) {
            long k = 3 * (long)L->free_to_id[p];
            for (int c = 0; c < 3; c++) w->rch[3 * p + c] += bh * w->fd[k + c];
        }
        if (eq_solve(w, w->rch, w->dy, err) != 0) { rc = -1; break; }
        double h_next = h;
        if (adaptive) {
            double grow = 1.0; /* after a BDF1 step: no estimate */
            if (bdf2) {
                double e2 = 0.0;
                for (int p = 0; p < w->nf; p++) {
                    long k = 3 * (long)L->free_to_id[p];
                    double d2 = 0.0;
                    for (int c = 0; c < 3; c++) {
                        double cq = (xp[k + c] - x[k + c] + v[k + c] * h_prev) / (h_prev * h_prev);
                        double xq = x[k + c] + hs * (v[k + c] + cq * hs);
                        double d = 0.4 * (x0[k + c] + bh * w->dy[3 * p + c] - xq);
                        d2 += d * d;
                    }
                    if (d2 > e2) e2 = d2;
                }
                double e = sqrt(e2) / tol;
                grow = e > 0.0 ? 0.9 * pow(e, -1.0 / 3.0) : 2.0;
                grow = grow > 2.0 ? 2.0 : grow < 0.25 ? 0.25 : grow;
                if (e > 1.5 && hs > h_min * (1.0 + 1e-9)) { /* redo it shorter */
                    h = fmax(hs * grow, h_min);
                    r->dyn_rejected++;
                    continue;
                }
            }
            h_next = fmin(fmax(hs * grow, h_min), h_max);
        }
        /* shift history, update */
        memcpy(xp, x, sizeof(double) * n3);
        memcpy(vp, v, sizeof(double) * n3);
        for (int p = 0; p < w->nf; p++) {
            long k = 3 * (long)L->free_to_id[p];
            for (int c = 0; c < 3; c++) {
                v[k + c] += w->dy[3 * p + c];
                x[k + c] = x0[k + c] + bh * w->dy[3 * p + c];
            }
        }
        have_prev = adaptive || hs == h;
        h_prev = hs;
        h = h_next;
        t += hs;
        r->dyn_steps++;
        /* the energy balance of every step.  The model dissipates: its
         * total energy cannot rise, and a step that raises it is refused
         * (state back one step, BDF1 restart):
         * - the error-controlled step, by more than DRAPE_EQ_FALL_RISE of
         *   the energy dissipated so far: redone at half the step;
         * - the swing's long step (its matrix drops the compressed springs'
         *   negative stiffness and can pump energy into a compressed hem:
         *   measured on the table scene, +1.5 % of the peak kinetic energy
         *   in five steps), by more than DRAPE_EQ_SWING_RISE of the peak
         *   kinetic energy over the lowest total energy since the change of
         *   step: the swing goes on at the fall's own step; the same for
         *   the fall step after the fold phase, which then goes on at the
         *   fold step (each tried again after dyn_retry). */
        double e_now = total_energy(w, x, v), h_redo = 0.0;
        if (adaptive && e_now - e_prev > DRAPE_EQ_FALL_RISE * (r->dyn_e_start - e_low_all) &&
            hs > h_min * (1.0 + 1e-9)) {
            h_redo = fmax(0.5 * hs, h_min);
        } else if (long_step && !(e_now <= e_low + DRAPE_EQ_SWING_RISE * ke_peak)) {
            h_redo = h_fall;
            long_step = 0;
            if (o->dyn_retry > 0.0 && retries-- > 0) { /* t after the state goes back */
                t_retry = t - hs + o->dyn_retry;
                h_retry = hs;
            }
        }
        /* at the shorter steps: a fall that keeps gaining energy is
         * stopped, and the caller goes on from *low (DRAPE_EQ_PUMP_RISE) */
        if (h_redo == 0.0 && !adaptive && o->dyn_redo_tol > 0.0 && !long_step && ke_fell &&
            !(e_now <= e_low_all + DRAPE_EQ_PUMP_RISE * ke_max)) {
            r->dyn_pumped = 1;
            rc = 3;
            break;
        }
        if (h_redo > 0.0) {
            memcpy(x, xp, sizeof(double) * n3);
            memcpy(v, vp, sizeof(double) * n3);
            t -= hs;
            r->dyn_steps--;
            h = h_redo;
            have_prev = 0;
            r->dyn_refused++;
            continue;
        }
        /* a step that stands (a refused one is not the fall's) with the
         * total energy above the start: the caller falls again */
        if (!adaptive && o->dyn_redo_tol > 0.0 && !(e_now <= r->dyn_e_start)) {
            rc = 3;
            break;
        }
        double ke = kinetic_energy(w, v);
        if (ke > ke_max) ke_max = ke;
        else if (ke < 0.5 * ke_max) ke_fell = 1;
        if ((long_step || t_retry < INFINITY) && e_now < e_low) e_low = e_now;
        /* the peak is the longer steps' guard's scale too (the fold
         * phase's guard acts without the swing criterion) */
        if (ke > ke_peak) ke_peak = ke;
        if (ke_frac > 0.0) {
            ring[iw] = ke;
            ring_t[iw] = t;
            iw = (iw + 1) % nwin;
            ke_win = 0.0; /* over the steps that ended in (t - tw, t] (the
                             window is full by T >= 5 tw) */
            for (int k = 0; k < nwin; k++)
                if (ring[k] > ke_win && ring_t[k] > t - tw * (1.0 - 1e-9)) ke_win = ring[k];
        }
        /* the step stands (a refused one above did not count) */
        if (hs < r->dyn_dt_min) r->dyn_dt_min = hs;
        if (hs > r->dyn_dt_max) r->dyn_dt_max = hs;
        double rise = e_now - e_prev;
        if (!isnan(rise) && !(rise <= r->dyn_e_max_rise)) r->dyn_e_max_rise = rise;
        if (!(e_now <= r->dyn_e_max)) r->dyn_e_max = e_now;
        e_prev = r->dyn_e_end = e_now;
        if (e_now < e_low_all) {
            e_low_all = e_now;
            if (low) fall_record(w, low, x, v, t, ke_max, ke_win);
        }
    }
    drape_free(ring);
    r->dyn_end = t;
    if (r->dyn_steps == 0) r->dyn_dt_min = 0.0;
    return rc;
}
