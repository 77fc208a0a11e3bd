/* integrator_gsl.c: the GSL 2.7 gsl_odeiv2 backends gsl-msbdf and gsl-rk8pd.
 *
 * Problem (integrator.h, docs/model.md 4): y' = F(y), y = [x_free; v_free],
 *     F(y) = [ v ; M^-1 f(x, v) ],   J = [ 0 I ; M^-1 K  M^-1 D ].
 *
 * gsl-msbdf  multistep BDF of orders 1-5 with Nordsieck history (Keskitalo's
 *            msbdf, after VODE/CVODE): the variable-step Gear method the seed
 *            used.  Its Newton matrix is dense: the exact sparse J is
 *            scattered into GSL's row-major dim x dim array
 *            (dfdy[i*dim + j] = dF_i/dy_j), dfdt = 0 (autonomous).  It keeps
 *            two such matrices, so the backend refuses lattices whose
 *            2 * dim^2 * 8 bytes exceed opts.dense_limit_bytes (numerics.md 2:
 *            0.47 GB at 30 x 30, 58 GB at 100 x 100).
 * gsl-rk8pd  explicit Runge-Kutta Prince-Dormand 8(9) (explicit baseline).
 *
 * Error control: GSL's "scaled" control,
 *     D_i = eps_abs * s_i + eps_rel * |y_i|,   accept if max_i |err_i| / D_i <= 1,
 * with eps_abs = 1 and s_i = the vector absolute tolerance of integrator.h,
 * eps_rel = rtol.  This is a max norm where SUNDIALS uses a WRMS norm
 * (numerics.md 1.8): equal numbers do not mean equal accuracy.
 *
 * A model evaluation that fails recoverably returns GSL_FAILURE, which makes
 * gsl_odeiv2_evolve_apply halve the step and retry.  A Jacobian that cannot
 * be evaluated returns GSL_EBADFUNC, which ends the step at once (GSL
 * manual, "Defining the ODE System"): msbdf evaluates it only where the
 * right-hand side has just succeeded (the predicted state), so it failed on
 * a stiffness that is not finite, which a shorter step does not cure (with
 * GSL_FAILURE GSL halved the step until it vanished, 1055 times at t = 0,
 * and reported a collapsed step size).  GSL's aborting error handler is
 * switched off.
 *
 * References: GSL manual, "Ordinary Differential Equations"; GSL sources
 * ode-initval2/{msbdf,driver,evolve}.c; Prince & Dormand, J. Comput. Appl.
 * Math. 7 (1981).
 */
#include "drape/integrator.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include "drape/alloc.h"

typedef struct gsl_state {
    const char *name;
    int implicit;
    drape_ode *ode;
    gsl_odeiv2_system sys;
    gsl_odeiv2_driver *d;
    double t;
    double *y;      /* dim: GSL's current state */
    double *Jsp;    /* nnz: sparse Jacobian values (msbdf) */
    double h0;      /* first trial step */
    double t_stop;
    long max_steps; /* accepted steps allowed per step_to call (NORMAL) */
    long accepted;  /* accepted steps since the last (re)init: GSL's
                       evolve->count also counts the attempts the error
                       test rejected */
    int jac_failed; /* the last step_to ended on a failed Jacobian */
} gsl_state;

static int gsl_rhs(double t, const double y[], double dydt[], void *p)
{
    gsl_state *s = p;
    (void)t;
    int rc = drape_ode_rhs(s->ode, s->ode->parts, 1, y, dydt);
    /* -1: the run is being stopped (opts.stop): GSL_EBADFUNC ends the
     * step at once instead of retrying with a smaller one */
    return rc < 0 ? GSL_EBADFUNC : rc ? GSL_FAILURE : GSL_SUCCESS;
}

static int gsl_jac(double t, const double y[], double *dfdy, double dfdt[], void *p)
{
    gsl_state *s = p;
    const drape_pattern *pt = s->ode->pattern;
    size_t n = (size_t)s->ode->dim;
    (void)t;
    if (drape_ode_jacobian(s->ode, s->ode->parts, 1, y, s->Jsp)) {
        s->jac_failed = 1;
        return GSL_EBADFUNC; /* not recoverable: see the top of the file */
    }
    memset(dfdy, 0, sizeof(double) * n * n);
    memset(dfdt, 0, sizeof(double) * n);
    for (size_t j = 0; j < n; j++)
        for (int64_t k = pt->colptr[j]; k < pt->colptr[j + 1]; k++)
            dfdy[(size_t)pt->rowind[k] * n + j] = s->Jsp[k];
    return GSL_SUCCESS;
}

static const char *status_name(int st)
{
    switch (st) {
    case GSL_FAILURE: return "GSL_FAILURE";
    case GSL_EMAXITER: return "GSL_EMAXITER";
    case GSL_ENOPROG: return "GSL_ENOPROG";
    case GSL_EBADFUNC: return "GSL_EBADFUNC";
    case GSL_EFAULT: return "GSL_EFAULT";
    case GSL_EINVAL: return "GSL_EINVAL";
    case GSL_ENOMEM: return "GSL_ENOMEM";
    default: return "GSL error";
    }
}

static const char *status_hint(int st)
{
    switch (st) {
    case GSL_EMAXITER:
        return "the step limit was reached: the problem is too stiff for this "
               "integrator or rtol too tight; use cvode-bdf or arkode-dirk, "
               "loosen rtol, or add damping";
    case GSL_FAILURE:
    case GSL_ENOPROG:
        return "the step size collapsed (error test or model evaluation kept "
               "failing): loosen rtol, add damping, or check the fabric";
    default:
        return "internal solver error";
    }
}

static int gsl_fail(gsl_state *s, int st, drape_error *err)
{
    if (s->jac_failed)
        return drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                               "%s failed at t = %.9g s: the Jacobian could not be evaluated "
                               "where the forces could (a stiffness entry that is not "
                               "finite); hint: check the fabric's stiffness values",
                               s->name, s->t);
    return drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                           "%s failed at t = %.9g s: %s (%s); hint: %s", s->name,
                           s->t, status_name(st), gsl_strerror(st), status_hint(st));
}

static void gsl_state_free(void *st)
{
    gsl_state *s = st;
    if (!s) return;
    if (s->d) gsl_odeiv2_driver_free(s->d);
    drape_free(s->y);
    drape_free(s->Jsp);
    drape_free(s);
}

static void *gsl_alloc(int implicit, const char *name, drape_ode *ode,
                       const drape_integrator_opts *o, double t0,
                       const double *y0, drape_error *err)
{
    gsl_state *s = NULL;
    size_t n = (size_t)ode->dim;
    gsl_set_error_handler_off(); /* the default handler aborts (STYLE.md 7) */
    if (implicit) {
        double limit = o->dense_limit_bytes > 0.0 ? o->dense_limit_bytes
                                                  : DRAPE_INTEGRATOR_DENSE_LIMIT_DEFAULT;
        double need = 2.0 * (double)n * (double)n * sizeof(double);
        if (need > limit) {
            drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, "solver.integrator",
                            "%s needs two dense %zu x %zu matrices, %.3g GiB, above "
                            "its limit of %.3g GiB; use cvode-bdf or arkode-dirk "
                            "(sparse), or a coarser spacing",
                            name, n, n, need / 1073741824.0, limit / 1073741824.0);
            return NULL;
        }
    }
    s = drape_calloc(1, sizeof *s);
    if (!s) goto nomem;
    s->name = name;
    s->implicit = implicit;
    s->ode = ode;
    s->t = t0;
    s->t_stop = o->t_stop;
    s->h0 = o->h_init > 0.0 ? o->h_init : DRAPE_INTEGRATOR_GSL_H0_DEFAULT;
    s->y = drape_malloc(sizeof(double) * n);
    if (!s->y) goto nomem;
    memcpy(s->y, y0, sizeof(double) * n);
    if (implicit) {
        s->Jsp = drape_malloc(sizeof(double) * (size_t)(ode->pattern->nnz ? ode->pattern->nnz : 1));
        if (!s->Jsp) goto nomem;
    }
    s->sys.function = gsl_rhs;
    s->sys.jacobian = implicit ? gsl_jac : NULL;
    s->sys.dimension = n;
    s->sys.params = s;
    s->d = gsl_odeiv2_driver_alloc_scaled_new(
        &s->sys, implicit ? gsl_odeiv2_step_msbdf : gsl_odeiv2_step_rk8pd, s->h0,
        1.0, o->rtol, 1.0, 0.0, ode->atol);
    if (!s->d) goto nomem;
    s->max_steps = o->max_steps > 0 ? o->max_steps : DRAPE_INTEGRATOR_MAX_STEPS_DEFAULT;
    return s;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                    "%s: out of memory setting up %zu unknowns", name, n);
    gsl_state_free(s);
    return NULL;
}

static void *msbdf_alloc(drape_ode *ode, const drape_integrator_opts *o,
                         double t0, const double *y0, drape_error *err)
{
    return gsl_alloc(1, "gsl-msbdf", ode, o, t0, y0, err);
}

static void *rk8pd_alloc(drape_ode *ode, const drape_integrator_opts *o,
                         double t0, const double *y0, drape_error *err)
{
    return gsl_alloc(0, "gsl-rk8pd", ode, o, t0, y0, err);
}

static int gsl_reinit(void *st, double t0, const double *y0, drape_error *err)
{
    gsl_state *s = st;
    int rc = gsl_odeiv2_driver_reset_hstart(s->d, s->h0);
    if (rc != GSL_SUCCESS) return gsl_fail(s, rc, err);
    s->t = t0;
    s->accepted = 0;
    memcpy(s->y, y0, sizeof(double) * (size_t)s->ode->dim);
    return 0;
}

static int gsl_step_to(void *st, double t_out, drape_step_mode mode, double *t,
                       double *y, drape_error *err)
{
    gsl_state *s = st;
    int rc = GSL_SUCCESS;
    double bound = t_out;
    if (s->t_stop > 0.0 && (mode == DRAPE_STEP_ONE || bound > s->t_stop)) bound = s->t_stop;
    gsl_odeiv2_driver *d = s->d;
    s->jac_failed = 0;
    if (bound > s->t) {
        if (mode == DRAPE_STEP_NORMAL) {
            /* gsl_odeiv2_driver_apply's loop (its hmin 0 and hmax DBL_MAX
             * never act), with the step limit of the other backends: at
             * most max_steps accepted steps.  The driver's nmax let
             * nmax + 1 steps succeed and failed after nmax + 2. */
            long taken = 0;
            while (s->t < bound) {
                if (taken >= s->max_steps) {
                    rc = GSL_EMAXITER;
                    break;
                }
                rc = gsl_odeiv2_evolve_apply(d->e, d->c, d->s, d->sys, &s->t, bound, &d->h, s->y);
                if (rc != GSL_SUCCESS) break;
                taken++;
            }
            s->accepted += taken;
        } else {
            rc = gsl_odeiv2_evolve_apply(d->e, d->c, d->s, d->sys, &s->t, bound, &d->h, s->y);
            s->accepted += rc == GSL_SUCCESS;
        }
    }
    *t = s->t;
    memcpy(y, s->y, sizeof(double) * (size_t)s->ode->dim);
    if (rc != GSL_SUCCESS) return gsl_fail(s, rc, err);
    return 0;
}

static int gsl_get_state(void *st, double t, double *y, drape_error *err)
{
    gsl_state *s = st;
    if (fabs(t - s->t) > 1e-12 * fmax(1.0, fabs(t)))
        return drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                               "%s has no dense output: state asked at t = %.9g s, "
                               "current t = %.9g s", s->name, t, s->t);
    memcpy(y, s->y, sizeof(double) * (size_t)s->ode->dim);
    return 0;
}

static void gsl_stats(const void *st, drape_integrator_stats *r)
{
    const gsl_state *s = st;
    memset(r, 0, sizeof *r);
    r->switches = -1;
    r->energy_rescales = -1;
    r->steps = s->accepted; /* not e->count: that includes rejected attempts */
    r->err_test_fails = (long)s->d->e->failed_steps;
    r->rhs_evals = s->ode->n_rhs;
    r->jac_evals = s->ode->n_jac;
    /* msbdf keeps its Newton counters private. */
    r->lin_setups = s->implicit ? -1 : 0;
    r->nonlin_iters = s->implicit ? -1 : 0;
    r->conv_fails = s->implicit ? -1 : 0;
}

const drape_integrator_type drape_integrator_gsl_msbdf = {
    "gsl-msbdf", "GSL msbdf (variable-order BDF, the seed's Gear method), dense Jacobian",
    msbdf_alloc, gsl_reinit, gsl_step_to, gsl_get_state, gsl_stats, gsl_state_free};

const drape_integrator_type drape_integrator_gsl_rk8pd = {
    "gsl-rk8pd", "GSL Runge-Kutta Prince-Dormand 8(9), explicit",
    rk8pd_alloc, gsl_reinit, gsl_step_to, gsl_get_state, gsl_stats, gsl_state_free};
