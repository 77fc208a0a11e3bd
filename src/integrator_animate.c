/* integrator_animate.c: "animate", a fixed-step backward Euler for frames
 * at graphics speed (docs/animate.md).
 *
 * Backward Euler from (x_n, v_n) over a step h, x = x_n + h v,
 *     M (v - v_n) = h f_c(x_n + h v) + h D_n v,
 * (f_c = -grad E the conservative forces, gravity included; the dampers
 * linear in v with D_n = df/dv at x_n, exact for air drag, the dashpot
 * directions frozen at x_n for the edge dampers) is the stationary point
 * of the incremental potential (Martin et al. 2011; Gast et al. 2015)
 *     Phi(v) = 1/2 (v - v_n)^T M (v - v_n) + E(x_n + h v) - h/2 v^T D_n v.
 * Each step minimises Phi by at most DRAPE_ANIMATE_NEWTON_MAX Newton
 * iterations with a backtracking (Armijo) line search on Phi, from the
 * better of v_n and the velocity extrapolated from the last step.  The
 * Newton matrix
 *     S = M - h D_n - h^2 (K + Kc),
 * K = df_c/dx at the current iterate and Kc the clamp of compressed
 * springs (model.h), is factored by CHOLMOD (linsol_schur.h) and kept
 * while the corrections shrink fast and take full steps, refactored
 * otherwise; where bending or shear make S indefinite, S + mu M (a
 * Levenberg-Marquardt shift, kept from step to step) so the direction is
 * one of descent and the factor a supernodal LL^T.  The iterations stop
 * when a correction changes no edge length by more than DRAPE_ANIMATE_XTOL
 * spacings.  The first iteration with a full step is the linearised
 * backward Euler of Baraff & Witkin (1998); the line search is what makes
 * a step safe when the linearisation overshoots (a stretch edge at the
 * pins at a 33 ms step): Phi never increases, and nothing can fail to
 * converge, since the step is taken after the iterations whatever their
 * residual.  Then the energy guard: the state may not hold more kinetic +
 * potential energy than the one before (the supports do no work); if it
 * does, v is scaled down (be_step).  The error is first order in h
 * (docs/animate.md).
 *
 * The step h is fixed (opts.fixed_step).  Only a step whose evaluation
 * reports a folded hinge or a non-finite value, or whose S cannot be
 * factored, is redone as two half steps (at most DRAPE_ANIMATE_MAX_HALVINGS
 * times; conv_fails counts them; each retry starts from the state, energy
 * and extrapolation the step started with), and a last step is shortened
 * to land on t_stop.  Steps run on the grid t0 + k h (the frames, h
 * divides their interval); an output point off the grid (an equilibrium
 * check) splits its grid step in two, so that every state reported is a
 * state of the one trajectory (no interpolation: the energy balance
 * holds at every output point) and the grid is kept.  Nothing is
 * allocated after alloc except CHOLMOD's first factorisation
 * (linsol_schur.h).
 */
#include <math.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/integrator.h"
#include "drape/lattice.h"
#include "drape/linsol_schur.h"
#include "drape/units.h"

/* A step that fails is halved at most this often (h / 2^10). */
#define DRAPE_ANIMATE_MAX_HALVINGS 10
/* Newton iterations per step at most; fewer once a correction changes no
 * edge length by more than XTOL spacings (docs/animate.md). */
#define DRAPE_ANIMATE_NEWTON_MAX 6
#define DRAPE_ANIMATE_XTOL 2e-3
/* Armijo constant and the smallest step fraction of the line search. */
#define ANIM_ARMIJO 1e-4
#define ANIM_ALPHA_MIN (1.0 / 1024.0)
/* Refactor when a correction is more than this fraction of the last one
 * or the line search shortened it (adaptive refresh). */
#define ANIM_CONTRACTION 0.25
/* Bisection steps of the energy cut-back (beta to 1/256). */
#define ANIM_CUTBACK_MAX 8
/* The shift mu M of an indefinite S: from ANIM_SHIFT_MIN by factors of 10. */
#define ANIM_SHIFT_MIN 1e-2
#define ANIM_SHIFT_MAX 1e4

#define PARTS_CONS (DRAPE_PART_STRETCH | DRAPE_PART_BEND | DRAPE_PART_SHEAR | DRAPE_PART_GRAVITY)

typedef struct anim {
    drape_ode *ode;
    long nf3, dim;
    double h;             /* the fixed step, s */
    double t_stop;        /* never step past it; 0 = none */
    long max_steps;       /* per step_to call */
    double t0;            /* start: the step grid is t0 + k h */
    double t;             /* current time */
    double *y, *y_prev;   /* dim */
    double *r, *z, *w;    /* dim: right-hand sides and solutions; w: [0; v] */
    double *vn, *vt, *g, *dv; /* nf3: v_n, trial v, gradient of Phi, direction */
    double *K, *D, *Kc;   /* nnz of the model pattern */
    double *Kd;           /* nnz: the dampers' dK (not used: D_n frozen) */
    int have_d;
    int d_const, d_valid; /* D does not depend on the state (air drag only); computed */
    drape_schur *schur;
    long steps, halvings, factors, failed_factors, newton, backtracks;
    long rescales;        /* steps whose velocities were scaled down */
    double *vlast;        /* nf3: v at the start of the last step */
    double h_last;        /* its size; 0 = none (restart) */
    double *vlast_prev;   /* nf3: vlast, h_last, e_tot and e_valid before */
    double h_last_prev;   /* the step being attempted (attempt_save) */
    double e_tot_prev;
    int e_valid_prev;
    double mu_last;       /* the shift of the last factorisation */
    long *dpos;           /* nf3: the diagonal's slots in the pattern */
    double e_tot;         /* total energy (kinetic + potential) at y, J */
    int e_valid;          /* e_tot is that of the current y */
    double e_tol;         /* rises below this are roundoff, J */
    drape_error serr;     /* scratch for the Schur solver's errors */
} anim;

static void anim_free(void *st)
{
    anim *s = st;
    if (!s) return;
    drape_schur_free(s->schur);
    drape_free(s->y);
    drape_free(s->y_prev);
    drape_free(s->r);
    drape_free(s->K);
    drape_free(s->D);
    drape_free(s->Kc);
    drape_free(s->Kd);
    drape_free(s->dpos);
    drape_free(s->vlast);
    drape_free(s->vlast_prev);
    drape_free(s->z);
    drape_free(s->w);
    drape_free(s->vn);
    drape_free(s->vt);
    drape_free(s->g);
    drape_free(s->dv);
    drape_free(s);
}

static void *anim_alloc(drape_ode *ode, const drape_integrator_opts *o, double t0,
                        const double *y0, drape_error *err)
{
    if (!(o->fixed_step > 0.0) || !isfinite(o->fixed_step)) {
        drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "solver.step",
                        "animate: needs a positive fixed step, got %g s", o->fixed_step);
        return NULL;
    }
    anim *s = drape_calloc(1, sizeof *s);
    if (!s) goto nomem;
    const drape_pattern *P = drape_model_pattern(ode->model);
    s->ode = ode;
    s->nf3 = ode->nf3;
    s->dim = ode->dim;
    s->h = o->fixed_step;
    s->t_stop = o->t_stop;
    s->max_steps = o->max_steps > 0 ? o->max_steps : DRAPE_INTEGRATOR_MAX_STEPS_DEFAULT;
    s->t = s->t0 = t0;
    size_t dim = (size_t)s->dim, nnz = (size_t)(P->nnz ? P->nnz : 1);
    s->y = drape_malloc(sizeof(double) * dim);
    s->y_prev = drape_malloc(sizeof(double) * dim);
    s->r = drape_malloc(sizeof(double) * dim);
    s->K = drape_malloc(sizeof(double) * nnz);
    s->D = drape_malloc(sizeof(double) * nnz);
    s->Kc = drape_malloc(sizeof(double) * nnz);
    s->Kd = drape_malloc(sizeof(double) * nnz);
    s->z = drape_malloc(sizeof(double) * dim);
    s->w = drape_malloc(sizeof(double) * dim);
    size_t n3 = (size_t)(s->nf3 ? s->nf3 : 1);
    s->vn = drape_malloc(sizeof(double) * n3);
    s->vt = drape_malloc(sizeof(double) * n3);
    s->g = drape_malloc(sizeof(double) * n3);
    s->dv = drape_malloc(sizeof(double) * n3);
    s->dpos = drape_malloc(sizeof(long) * n3);
    s->vlast = drape_malloc(sizeof(double) * n3);
    s->vlast_prev = drape_malloc(sizeof(double) * n3);
    if (!s->y || !s->y_prev || !s->r || !s->K || !s->D || !s->Kc || !s->Kd || !s->z || !s->w ||
        !s->vn || !s->vt || !s->g || !s->dv || !s->dpos || !s->vlast || !s->vlast_prev)
        goto nomem;
    drape_model_diagonal_slots(ode->model, s->dpos);
    s->have_d = (ode->parts & DRAPE_PARTS_DAMPING) != 0;
    s->d_const = (ode->parts & (DRAPE_PART_EDGE | DRAPE_PART_SHEAR_DAMPING)) == 0;
    s->schur = drape_schur_new(P, ode->inv_mass, err);
    if (!s->schur) {
        anim_free(s);
        return NULL;
    }
    drape_schur_ldl_fallback(s->schur, 0);
    memcpy(s->y, y0, sizeof(double) * dim);
    memcpy(s->y_prev, y0, sizeof(double) * dim);
    /* roundoff of the energy: relative 1e-12 of M g over the extent */
    const drape_lattice *L = ode->lattice;
    s->e_tol = 1e-12 * L->mass_total * DRAPE_G_STANDARD * drape_lattice_extent(L);
    return s;
nomem:
    anim_free(s);
    drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "animate: out of memory");
    return NULL;
}

static int anim_reinit(void *st, double t0, const double *y0, drape_error *err)
{
    (void)err;
    anim *s = st;
    memcpy(s->y, y0, sizeof(double) * (size_t)s->dim);
    memcpy(s->y_prev, y0, sizeof(double) * (size_t)s->dim);
    /* the grid t0 + k h stays the run's (a resumed run restarts at an
     * output point, which may be off the grid: an equilibrium check) */
    s->t = t0;
    s->steps = s->halvings = s->factors = s->failed_factors = s->newton = s->backtracks = 0;
    s->rescales = 0;
    s->e_valid = 0;
    s->h_last = 0.0;
    s->mu_last = 0.0;
    return 0;
}

/* Full positions x_n + h v into o->x (free entries; the fixed ones hold
 * xinit from drape_ode's set-up) and v into o->v. */
static void scatter_xv(anim *s, const double *xn, const double *v, double h)
{
    drape_ode *o = s->ode;
    const drape_lattice *L = o->lattice;
    for (int k = 0; k < L->n_free; k++) {
        long id = 3 * (long)L->free_to_id[k];
        for (int c = 0; c < 3; c++) {
            o->x[id + c] = xn[3 * k + c] + h * v[3 * k + c];
            o->v[id + c] = v[3 * k + c];
        }
    }
}

/* out = D_n v (free coordinates): the diagonal alone for air drag (D =
 * -c M), else the sparse product over the model pattern. */
static void d_times(const anim *s, const double *v, double *out)
{
    const drape_pattern *P = drape_model_pattern(s->ode->model);
    if (s->d_const) {
        for (long i = 0; i < s->nf3; i++) out[i] = s->D[s->dpos[i]] * v[i];
        return;
    }
    memset(out, 0, sizeof(double) * (size_t)s->nf3);
    for (int64_t j = 0; j < P->n; j++)
        for (int64_t k = P->colptr[j]; k < P->colptr[j + 1]; k++) out[P->rowind[k]] += s->D[k] * v[j];
}

/* Phi(v) (at x_n + h v, scattered here); 1 if the energy cannot be
 * evaluated (folded hinge) or is not finite. */
static int phi(anim *s, const double *xn, const double *v, double h, double *out)
{
    drape_ode *o = s->ode;
    scatter_xv(s, xn, v, h);
    drape_energies E;
    if (drape_model_energy(o->model, o->x, &E) != 0) return 1;
    double kin = 0.0, damp = 0.0;
    const double *im = o->inv_mass;
    for (long i = 0; i < s->nf3; i++) {
        double d = v[i] - s->vn[i];
        kin += d * d / im[i / 3];
    }
    /* v^T D_n v (into w, not r: v may be r, the line search's trial) */
    if (s->have_d) {
        d_times(s, v, s->w);
        for (long i = 0; i < s->nf3; i++) damp += v[i] * s->w[i];
    }
    double p = 0.5 * kin + E.stretch + E.bend + E.shear + E.gravity - 0.5 * h * damp;
    if (!isfinite(p)) return 1;
    *out = p;
    return 0;
}

/* Total energy of positions x (free part of y) and velocities v. */
static int total_energy(anim *s, const double *x, const double *v, double *epot, double *ekin)
{
    drape_ode *o = s->ode;
    scatter_xv(s, x, v, 0.0);
    drape_energies E;
    if (drape_model_energy(o->model, o->x, &E) != 0) return 1;
    double k = 0.0;
    for (long i = 0; i < s->nf3; i++) k += v[i] * v[i] / o->inv_mass[i / 3];
    *epot = E.stretch + E.bend + E.shear + E.gravity;
    *ekin = 0.5 * k;
    return isfinite(*epot) && isfinite(*ekin) ? 0 : 1;
}

/* g = grad Phi(v) = M (v - v_n) - h f_c(x_n + h v) - h D_n v.  0, 1
 * (recoverable), -1 (interrupted). */
static int phi_grad(anim *s, const double *xn, const double *v, double h)
{
    drape_ode *o = s->ode;
    const double *im = o->inv_mass;
    /* y = [x_n + h v; v] for drape_ode_rhs: M^-1 f_c in z[nf3..] */
    for (long i = 0; i < s->nf3; i++) {
        s->r[i] = xn[i] + h * v[i];
        s->r[s->nf3 + i] = v[i];
    }
    int rc = drape_ode_rhs(o, o->parts & PARTS_CONS, 0, s->r, s->z);
    if (rc != 0) return rc;
    for (long i = 0; i < s->nf3; i++) s->g[i] = (v[i] - s->vn[i]) / im[i / 3] - h * s->z[s->nf3 + i] / im[i / 3];
    if (s->have_d) {
        d_times(s, v, s->w);
        for (long i = 0; i < s->nf3; i++) s->g[i] -= h * s->w[i];
    }
    for (long i = 0; i < s->nf3; i++)
        if (!isfinite(s->g[i])) return 1;
    return 0;
}

/* K + Kc at x_n + h v, and S = M - h D - h^2 (K + Kc) factored; where
 * bending or shear make it indefinite, S + mu M with mu = 1e-2, 1e-1, ...
 * (a Levenberg-Marquardt shift: the direction stays one of descent for
 * Phi, and the factor a supernodal LL^T).  0, 1 (recoverable), -1. */
static int factor_at(anim *s, const double *xn, const double *v, double h, drape_error *err)
{
    drape_ode *o = s->ode;
    long n = s->nf3, nnz = drape_model_pattern(o->model)->nnz;
    scatter_xv(s, xn, v, h);
    o->n_jac++;
    if (drape_model_jacobian(o->model, o->parts & PARTS_CONS, o->x, o->v, s->K, NULL) != 0) return 1;
    drape_model_compression_clamp(o->model, o->x, NULL, s->Kc);
    for (long k = 0; k < nnz; k++) s->K[k] += s->Kc[k];
    /* start from the last shift that was needed (a refused LL^T costs part
     * of a factorisation; letting it decay made the 100 x 100 run slower) */
    double mu = s->mu_last;
    if (mu > 0.0)
        for (long j = 0; j < n; j++) s->K[s->dpos[j]] -= mu / (h * h) / o->inv_mass[j / 3];
    for (;;) {
        drape_error_clear(&s->serr);
        int rc = drape_schur_factor(s->schur, s->K, s->have_d ? s->D : NULL, h, &s->serr);
        if (rc < 0) {
            *err = s->serr;
            return -1;
        }
        if (rc == 0) break;
        s->failed_factors++;
        double mu_next = mu > 0.0 ? 10.0 * mu : ANIM_SHIFT_MIN;
        if (mu_next > ANIM_SHIFT_MAX) return 1;
        /* K <- K - (mu_next - mu) / h^2 M on the diagonal */
        for (long j = 0; j < n; j++)
            s->K[s->dpos[j]] -= (mu_next - mu) / (h * h) / o->inv_mass[j / 3];
        mu = mu_next;
    }
    s->mu_last = mu;
    s->factors++;
    return 0;
}

/* Largest |(dv_b - dv_a) . u| over the stretch edges, u the edge's
 * direction at x_n + h v: how much the correction dv changes a length,
 * per unit h alpha. */
static double edge_change(const anim *s, const double *xn, const double *v, double h)
{
    const drape_lattice *L = s->ode->lattice;
    double best = 0.0;
    for (int e = 0; e < L->n_edges; e++) {
        int a = L->free_id[L->edges[e].a], b = L->free_id[L->edges[e].b];
        if (a < 0 && b < 0) continue;
        double d[3], dd[3], l2 = 0.0, p = 0.0;
        for (int c = 0; c < 3; c++) {
            double xa = a >= 0 ? xn[3 * a + c] + h * v[3 * a + c] : L->xinit[3 * L->edges[e].a + c];
            double xb = b >= 0 ? xn[3 * b + c] + h * v[3 * b + c] : L->xinit[3 * L->edges[e].b + c];
            d[c] = xb - xa;
            dd[c] = (b >= 0 ? s->dv[3 * b + c] : 0.0) - (a >= 0 ? s->dv[3 * a + c] : 0.0);
            l2 += d[c] * d[c];
        }
        if (!(l2 > 0.0)) continue;
        for (int c = 0; c < 3; c++) p += d[c] * dd[c];
        p = fabs(p) / sqrt(l2);
        if (p > best) best = p;
    }
    return best;
}

/* One backward Euler step of size h from y into y.  Returns 0, 1
 * (recoverable: fold, non-finite value, S not factorable), -1 (interrupted
 * or out of memory; err set). */
static int be_step(anim *s, double h, double *y, drape_error *err)
{
    drape_ode *o = s->ode;
    long n = s->nf3;
    const double *xn = y; /* y[0..n) = x_n stays until the end */
    double *v = s->vt;
    memcpy(s->vn, y + n, sizeof(double) * (size_t)n);
    if (!s->e_valid) {
        double ep, ek;
        if (total_energy(s, y, y + n, &ep, &ek) != 0) return 1;
        s->e_tot = ep + ek;
        s->e_valid = 1;
    }
    /* D_n at (x_n, v_n) (air drag alone: D = -c M, the same at every step) */
    if (s->have_d && !(s->d_const && s->d_valid)) {
        scatter_xv(s, xn, s->vn, 0.0);
        o->n_jac++;
        if (drape_model_jacobian(o->model, o->parts & DRAPE_PARTS_DAMPING, o->x, o->v, s->Kd,
                                 s->D) != 0)
            return 1;
        s->d_valid = 1;
    }
    /* Newton from v = v_n, or from the velocity extrapolated from the last
     * step, v_n + (v_n - v_n-1) h / h_n-1, whichever has the lower Phi */
    memcpy(v, s->vn, sizeof(double) * (size_t)n);
    double p0;
    if (phi(s, xn, v, h, &p0) != 0) return 1;
    if (s->h_last > 0.0) {
        double q = h / s->h_last, pb;
        for (long i = 0; i < n; i++) s->dv[i] = s->vn[i] + q * (s->vn[i] - s->vlast[i]);
        if (phi(s, xn, s->dv, h, &pb) == 0 && pb < p0) {
            memcpy(v, s->dv, sizeof(double) * (size_t)n);
            p0 = pb;
        }
    }
    /* K + Kc at the starting iterate x_n + h v */
    int rc = factor_at(s, xn, v, h, err);
    if (rc != 0) return rc;
    int stale = 0; /* the last iteration converged slowly: refactor */
    double last_move = INFINITY;
    for (int it = 0; it < DRAPE_ANIMATE_NEWTON_MAX; it++) {
        if (stale && (rc = factor_at(s, xn, v, h, err)) != 0) return rc;
        rc = phi_grad(s, xn, v, h);
        if (rc < 0)
            return drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                                   "animate: interrupted at t = %.6g s", s->t);
        if (rc > 0) return 1;
        s->newton++;
        /* S dv = -g: the first-order solve with r = [0; -M^-1 g] */
        memset(s->r, 0, sizeof(double) * (size_t)n);
        for (long i = 0; i < n; i++) s->r[n + i] = -s->g[i] * o->inv_mass[i / 3];
        if (drape_schur_solve(s->schur, s->K, h, s->r, s->z) != 0) return 1;
        double slope = 0.0, dmax = 0.0;
        for (long i = 0; i < n; i++) {
            s->dv[i] = s->z[n + i];
            slope += s->g[i] * s->dv[i];
            if (fabs(s->dv[i]) > dmax) dmax = fabs(s->dv[i]);
        }
        if (!(slope < 0.0)) { /* not a descent direction (roundoff; S, shifted
                                 where needed, is positive definite): the
                                 mass-weighted gradient */
            slope = 0.0;
            for (long i = 0; i < n; i++) {
                s->dv[i] = -s->g[i] * o->inv_mass[i / 3];
                slope += s->g[i] * s->dv[i];
            }
            if (!(slope < 0.0)) break; /* at a stationary point */
        }
        if (h * dmax < 1e-12 * o->lattice->sigma) break; /* at the minimum */
        double alpha = 1.0, p1 = 0.0;
        for (;;) {
            for (long i = 0; i < n; i++) s->r[i] = v[i] + alpha * s->dv[i];
            int bad = phi(s, xn, s->r, h, &p1);
            if (!bad && p1 <= p0 + ANIM_ARMIJO * alpha * slope) break;
            alpha *= 0.5;
            s->backtracks++;
            if (alpha < ANIM_ALPHA_MIN) break;
        }
        if (alpha < ANIM_ALPHA_MIN) break; /* no decrease along dv: keep v */
        for (long i = 0; i < n; i++) v[i] += alpha * s->dv[i];
        p0 = p1;
        /* the frozen matrix is kept while the iteration contracts fast and
         * takes full steps */
        double move = alpha * dmax;
        stale = alpha < 1.0 || move > ANIM_CONTRACTION * last_move;
        last_move = move;
        /* converged: the last correction changed no edge's length by more
         * than DRAPE_ANIMATE_XTOL of the spacing (a strain of that size;
         * rigid motion of the cloth is not what the iteration must settle) */
        if (h * alpha * edge_change(s, xn, v, h) <= DRAPE_ANIMATE_XTOL * o->lattice->sigma) break;
    }
    /* No energy out of nothing: the supports do no work, so the total
     * energy may only fall.  Backward Euler can raise it where E is not
     * convex (compressed springs, buckling): -h^2/2 v^T H v > 0 for
     * negative curvature H.  Then the step is cut back: v <- beta v with
     * the largest beta (bisection) for which the positions x_n + h v hold
     * no more energy than the total there was (beta = 0 gives x_n, which
     * holds less), and the velocities are scaled down to the energy left:
     * more dissipation, never less, and no step is refused. */
    for (long i = 0; i < n; i++) {
        s->r[i] = xn[i] + h * v[i];
        if (!isfinite(s->r[i]) || !isfinite(v[i])) return 1;
    }
    double ep, ek;
    int guarded = 0;
    if (total_energy(s, s->r, v, &ep, &ek) != 0) return 1;
    if (ep > s->e_tot + s->e_tol) {
        /* bisect for the largest beta whose state (x_n + h beta v, beta v)
         * holds no more energy than there was: beta = 0 does */
        double lo = 0.0, hi = 1.0, ek1 = ek;
        for (int k = 0; k < ANIM_CUTBACK_MAX; k++) {
            double mid = 0.5 * (lo + hi), em, kk;
            for (long i = 0; i < n; i++) s->r[i] = xn[i] + h * mid * v[i];
            if (total_energy(s, s->r, v, &em, &kk) == 0 && em + mid * mid * ek1 <= s->e_tot + s->e_tol)
                lo = mid;
            else
                hi = mid;
        }
        for (long i = 0; i < n; i++) {
            v[i] *= lo;
            s->r[i] = xn[i] + h * v[i];
        }
        if (total_energy(s, s->r, v, &ep, &ek) != 0) return 1;
        guarded = 1;
    }
    if (ep + ek > s->e_tot + s->e_tol) {
        double sc = ek > 0.0 && s->e_tot > ep ? sqrt((s->e_tot - ep) / ek) : 0.0;
        for (long i = 0; i < n; i++) v[i] *= sc;
        ek *= sc * sc;
        guarded = 1;
    }
    s->rescales += guarded;
    memcpy(s->vlast, s->vn, sizeof(double) * (size_t)n);
    s->h_last = h;
    for (long i = 0; i < n; i++) {
        y[i] = s->r[i];
        y[n + i] = v[i];
    }
    s->e_tot = ep + ek;
    return 0;
}

/* What a step attempt changes, kept before it and restored after it
 * failed: the state, its energy, and the last step's velocity and size
 * from which the first sub-step extrapolates its Newton guess (so that
 * the retry starts as a fresh attempt from the same state would, not
 * from a discarded sub-step). */
static void attempt_save(anim *s)
{
    memcpy(s->y_prev, s->y, sizeof(double) * (size_t)s->dim);
    memcpy(s->vlast_prev, s->vlast, sizeof(double) * (size_t)s->nf3);
    s->h_last_prev = s->h_last;
    s->e_tot_prev = s->e_tot;
    s->e_valid_prev = s->e_valid;
}

static void attempt_restore(anim *s)
{
    memcpy(s->y, s->y_prev, sizeof(double) * (size_t)s->dim);
    memcpy(s->vlast, s->vlast_prev, sizeof(double) * (size_t)s->nf3);
    s->h_last = s->h_last_prev;
    s->e_tot = s->e_tot_prev;
    s->e_valid = s->e_valid_prev;
}

/* One step of h from s->y, as 2^k sub-steps if needed; a failed attempt
 * is rolled back whole (attempt_restore) before the next. */
static int anim_step(anim *s, double h, drape_error *err)
{
    attempt_save(s);
    for (int k = 0; k <= DRAPE_ANIMATE_MAX_HALVINGS; k++) {
        long nsub = 1L << k;
        double hs = h / (double)nsub;
        int rc = 0;
        for (long j = 0; j < nsub && rc == 0; j++) rc = be_step(s, hs, s->y, err);
        if (rc < 0) {
            attempt_restore(s);
            return -1;
        }
        if (rc == 0) {
            s->t += h;
            s->steps++;
            return 0;
        }
        s->halvings++;
        attempt_restore(s);
    }
    return drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                           "animate: the step at t = %.6g s failed even as %ld steps of "
                           "%.3g s (a folded hinge, a non-finite force or a singular "
                           "matrix); hint: a smaller --substeps step, or a dynamic "
                           "integrator", s->t, 1L << DRAPE_ANIMATE_MAX_HALVINGS,
                           h / (double)(1L << DRAPE_ANIMATE_MAX_HALVINGS));
}

static int anim_get_state(void *st, double t, double *y, drape_error *err)
{
    anim *s = st;
    if (fabs(t - s->t) > 1e-9 * s->h)
        return drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                               "animate has no dense output: state asked at t = %.9g s, "
                               "current t = %.9g s", t, s->t);
    memcpy(y, s->y, sizeof(double) * (size_t)s->dim);
    return 0;
}

/* The next step from s->t: to the next point of the grid t0 + k h, or to
 * t_out or t_stop if one of them comes first. */
static double next_step(const anim *s, double t_out)
{
    double eps = 1e-9 * s->h;
    double k = floor((s->t - s->t0) / s->h + 1e-9) + 1.0;
    double end = s->t0 + k * s->h;
    if (t_out < end - eps) end = t_out;
    if (s->t_stop > 0.0 && s->t_stop < end - eps) end = s->t_stop;
    return end - s->t;
}

static int anim_step_to(void *st, double t_out, drape_step_mode mode, double *t,
                        double *y, drape_error *err)
{
    anim *s = st;
    int rc = 0;
    double eps = 1e-9 * s->h;
    double bound = mode == DRAPE_STEP_ONE ? INFINITY : t_out;
    if (s->t_stop > 0.0 && bound > s->t_stop) bound = s->t_stop;
    long taken = 0;
    while (s->t < bound - eps) {
        if (++taken > s->max_steps) {
            rc = drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                                 "animate failed at t = %.6g s: more than %ld steps "
                                 "(max_steps) before t = %.6g s; hint: fewer --substeps, "
                                 "or a larger --max-steps", s->t, s->max_steps, bound);
            break;
        }
        double h = next_step(s, bound);
        if ((rc = anim_step(s, h, err)) != 0) break;
        if (fabs(s->t - bound) <= eps) s->t = bound; /* no drift at output points */
        if (mode == DRAPE_STEP_ONE) break;
    }
    *t = s->t;
    memcpy(y, s->y, sizeof(double) * (size_t)s->dim);
    return rc;
}

static void anim_stats(const void *st, drape_integrator_stats *r)
{
    const anim *s = st;
    memset(r, 0, sizeof *r);
    r->switches = -1;
    r->steps = s->steps;
    r->rhs_evals = s->ode->n_rhs;
    r->jac_evals = s->ode->n_jac;
    r->lin_setups = s->factors + s->failed_factors;
    r->lin_factors = s->factors;
    r->nonlin_iters = s->newton;   /* Newton iterations, one solve each */
    r->err_test_fails = s->backtracks; /* line-search halvings (no error test) */
    r->conv_fails = s->halvings;
    r->linsol = DRAPE_LINSOL_SCHUR_DIRECT;
    r->energy_rescales = s->rescales;
}

const drape_integrator_type drape_integrator_animate = {
    "animate",
    "fixed-step linearly implicit Euler (Baraff & Witkin 1998), CHOLMOD on M - hD - h^2 K",
    anim_alloc, anim_reinit, anim_step_to, anim_get_state, anim_stats, anim_free};
