/* integrator.c: the integrator registry, the handle, and the first-order
 * right-hand side and Jacobian shared by all backends.
 *
 * Equations (docs/model.md 4, seed eqs. 16-17; numerics.md 3.1-3.2), over free
 * particles with y = [x_free; v_free]:
 *     x' = v                                   (kinematic part)
 *     v' = M^-1 f(x, v)                        (lumped masses)
 *     J  = [ 0  I ; M^-1 K  M^-1 D ]           (drape_model_jacobian_first_order)
 * Absolute tolerances (numerics.md 3.1): atol_x = atol, atol_v = atol / T,
 * T = sqrt(L / g), L = largest extent of the rest lattice.
 */
#include "drape/integrator.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/units.h"

static const drape_integrator_type *const registry[] = {
    &drape_integrator_cvode_bdf,  &drape_integrator_arkode_imex,
    &drape_integrator_arkode_dirk, &drape_integrator_arkode_erk,
    &drape_integrator_gsl_msbdf,  &drape_integrator_gsl_rk8pd,
    &drape_integrator_animate, NULL};

/* "auto": cvode-bdf and arkode-erk with switching (integrator_auto.c). */
#define AUTO_BACKEND (&drape_integrator_auto)

struct drape_integrator {
    const drape_integrator_type *type;
    void *state;
    drape_ode ode;
    double t;
    double *y;  /* dim: state at t */
    double *yd; /* dim: dense output buffer */
};

void drape_integrator_opts_default(drape_integrator_opts *o)
{
    memset(o, 0, sizeof *o);
    o->rtol = 1e-4;
    o->atol = 1e-7;
}

int drape_max_order_parse(const char *text, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (errno || *end || end == text || v < 1 || v > 5) return -1;
    *out = (int)v;
    return 0;
}

int drape_integrator_bdf_order(const char *name, int max_order)
{
    if (strcmp(name, "cvode-bdf") != 0 && strcmp(name, "auto") != 0) return 0;
    return max_order > 0 ? max_order : DRAPE_INTEGRATOR_MAX_ORDER_DEFAULT;
}

const drape_integrator_type *drape_integrator_type_find(const char *name)
{
    if (!name) return NULL;
    if (strcmp(name, "auto") == 0) return AUTO_BACKEND;
    for (int k = 0; registry[k]; k++)
        if (strcmp(registry[k]->name, name) == 0) return registry[k];
    return NULL;
}

const drape_integrator_type *const *drape_integrator_types(void)
{
    return registry;
}

/* ---- right-hand side and Jacobian --------------------------------------- */

void drape_ode_scatter(drape_ode *o, const double *y)
{
    const drape_lattice *L = o->lattice;
    for (int k = 0; k < L->n_free; k++) {
        int id = L->free_to_id[k];
        for (int c = 0; c < 3; c++) {
            o->x[3 * id + c] = y[3 * k + c];
            o->v[3 * id + c] = y[o->nf3 + 3 * k + c];
        }
    }
}

int drape_ode_rhs(drape_ode *o, unsigned parts, int include_kinematic,
                  const double *y, double *ydot)
{
    const drape_lattice *L = o->lattice;
    if (o->stop && *o->stop) return -1;
    o->n_rhs++;
    drape_ode_scatter(o, y);
    parts &= o->parts;
    int rc = 0;
    if (parts) {
        rc = drape_model_forces(o->model, parts, o->x, o->v, o->f);
    } else {
        memset(o->f, 0, sizeof(double) * 3 * (size_t)L->n);
    }
    if (rc != 0) return 1;
    for (long i = 0; i < o->nf3; i++)
        ydot[i] = include_kinematic ? y[o->nf3 + i] : 0.0;
    int bad = 0;
    for (int k = 0; k < L->n_free; k++) {
        int id = L->free_to_id[k];
        for (int c = 0; c < 3; c++) {
            double a = o->f[3 * id + c] * o->inv_mass[k];
            if (!isfinite(a)) bad = 1;
            ydot[o->nf3 + 3 * k + c] = a;
        }
    }
    return bad;
}

int drape_ode_jacobian(drape_ode *o, unsigned parts, int include_kinematic,
                       const double *y, double *J)
{
    o->n_jac++;
    drape_ode_scatter(o, y);
    parts &= o->parts;
    int rc = drape_model_jacobian_first_order(o->model, parts, include_kinematic,
                                              o->x, o->v, J);
    if (rc != 0) return 1;
    for (int64_t k = 0; k < o->pattern->nnz; k++)
        if (!isfinite(J[k])) return 1;
    return 0;
}

/* ---- the handle ----------------------------------------------------------- */

static void ode_release(drape_ode *o)
{
    drape_free(o->atol);
    drape_free(o->inv_mass);
    drape_free(o->x);
    drape_free(o->v);
    drape_free(o->f);
    memset(o, 0, sizeof *o);
}

static int ode_init(drape_ode *o, drape_model *m, const drape_integrator_opts *opt,
                    drape_error *err)
{
    const drape_lattice *L = drape_model_lattice(m);
    memset(o, 0, sizeof *o);
    o->model = m;
    o->lattice = L;
    o->nf3 = 3L * L->n_free;
    o->dim = 2 * o->nf3;
    o->parts = drape_model_parts(m);
    o->pattern = drape_model_pattern_first_order(m);
    if (!o->pattern || o->pattern->n != o->dim)
        return drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                               "integrator: the model's first-order pattern is %ld square, expected %ld",
                               o->pattern ? (long)o->pattern->n : -1L, o->dim);
    size_t n3 = 3 * (size_t)L->n;
    o->atol = drape_malloc(sizeof(double) * (size_t)(o->dim ? o->dim : 1));
    o->inv_mass = drape_malloc(sizeof(double) * (size_t)(L->n_free ? L->n_free : 1));
    o->x = drape_malloc(sizeof(double) * (n3 ? n3 : 1));
    o->v = drape_calloc(n3 ? n3 : 1, sizeof(double));
    o->f = drape_calloc(n3 ? n3 : 1, sizeof(double));
    if (!o->atol || !o->inv_mass || !o->x || !o->v || !o->f) {
        ode_release(o);
        return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                               "integrator: out of memory for %ld unknowns", (long)(3 * n3));
    }
    memcpy(o->x, L->xinit, sizeof(double) * n3);
    o->stop = opt->stop;
    for (int k = 0; k < L->n_free; k++) o->inv_mass[k] = 1.0 / L->mass[L->free_to_id[k]];
    double T = opt->t_scale > 0.0 ? opt->t_scale : sqrt(drape_lattice_extent(L) / DRAPE_G_STANDARD);
    for (long i = 0; i < o->nf3; i++) {
        o->atol[i] = opt->atol;
        o->atol[o->nf3 + i] = opt->atol / T;
    }
    return 0;
}

static void full_to_y(const drape_lattice *L, long nf3, const double *x,
                      const double *v, double *y)
{
    for (int k = 0; k < L->n_free; k++) {
        int id = L->free_to_id[k];
        for (int c = 0; c < 3; c++) {
            y[3 * k + c] = x[3 * id + c];
            y[nf3 + 3 * k + c] = v ? v[3 * id + c] : 0.0;
        }
    }
}

static void y_to_full(const drape_lattice *L, long nf3, const double *y,
                      double *x, double *v)
{
    if (x) memcpy(x, L->xinit, sizeof(double) * 3 * (size_t)L->n);
    if (v) memset(v, 0, sizeof(double) * 3 * (size_t)L->n);
    for (int k = 0; k < L->n_free; k++) {
        int id = L->free_to_id[k];
        for (int c = 0; c < 3; c++) {
            if (x) x[3 * id + c] = y[3 * k + c];
            if (v) v[3 * id + c] = y[nf3 + 3 * k + c];
        }
    }
}

static int check_opts(const drape_integrator_opts *o, drape_error *err)
{
    if (!(o->rtol > 0.0) || !isfinite(o->rtol))
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "solver.rtol",
                               "must be a positive number, got %g", o->rtol);
    if (!(o->atol > 0.0) || !isfinite(o->atol))
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "solver.atol",
                               "must be a positive number, got %g", o->atol);
    if (o->max_order < 0 || o->max_order > 5)
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "solver.max_order",
                               "must be 1..5 (0 = default %d), got %d",
                               DRAPE_INTEGRATOR_MAX_ORDER_DEFAULT, o->max_order);
    if (o->max_steps < 0 || o->t_scale < 0.0 || o->t_stop < 0.0 || o->h_init < 0.0 || !(o->fixed_step >= 0.0) ||
        o->dense_limit_bytes < 0.0 || !(o->auto_hw >= 0.0))
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "solver",
                               "negative integrator option");
    return 0;
}

drape_integrator *drape_integrator_new(drape_model *m, const char *name,
                                       const drape_integrator_opts *o,
                                       drape_error *err)
{
    drape_integrator *I = NULL;
    const drape_integrator_type *T = drape_integrator_type_find(name);
    if (!T) {
        char known[256] = "auto";
        for (int k = 0; registry[k]; k++) {
            size_t n = strlen(known);
            snprintf(known + n, sizeof known - n, ", %s", registry[k]->name);
        }
        drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "solver.integrator",
                        "unknown integrator \"%s\" (known: %s)", name ? name : "", known);
        return NULL;
    }
    if (check_opts(o, err)) return NULL;
    if (drape_model_lattice(m)->n_free == 0) {
        drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, NULL,
                        "every particle is fixed: nothing to integrate");
        return NULL;
    }
    I = drape_calloc(1, sizeof *I);
    if (!I) goto nomem;
    I->type = T;
    if (ode_init(&I->ode, m, o, err)) goto fail;
    I->y = drape_malloc(sizeof(double) * (size_t)(I->ode.dim ? I->ode.dim : 1));
    I->yd = drape_malloc(sizeof(double) * (size_t)(I->ode.dim ? I->ode.dim : 1));
    if (!I->y || !I->yd) goto nomem;
    full_to_y(I->ode.lattice, I->ode.nf3, I->ode.lattice->xinit, NULL, I->y);
    I->t = 0.0;
    I->state = T->alloc(&I->ode, o, 0.0, I->y, err);
    if (!I->state) goto fail;
    return I;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "integrator: out of memory");
fail:
    drape_integrator_free(I);
    return NULL;
}

void drape_integrator_free(drape_integrator *I)
{
    if (!I) return;
    if (I->state) I->type->free(I->state);
    ode_release(&I->ode);
    drape_free(I->y);
    drape_free(I->yd);
    drape_free(I);
}

int drape_integrator_reinit(drape_integrator *I, double t0, const double *x,
                            const double *v, drape_error *err)
{
    if (!I->type->reinit)
        return drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                               "%s: restart is not supported", I->type->name);
    full_to_y(I->ode.lattice, I->ode.nf3, x, v, I->y);
    I->ode.n_rhs = I->ode.n_jac = 0;
    if (I->type->reinit(I->state, t0, I->y, err)) return -1;
    I->t = t0;
    return 0;
}

int drape_integrator_step_to(drape_integrator *I, double t_out,
                             drape_step_mode mode, drape_error *err)
{
    return I->type->step_to(I->state, t_out, mode, &I->t, I->y, err);
}

double drape_integrator_time(const drape_integrator *I) { return I->t; }

void drape_integrator_state(const drape_integrator *I, double *x, double *v)
{
    y_to_full(I->ode.lattice, I->ode.nf3, I->y, x, v);
}

int drape_integrator_state_at(drape_integrator *I, double t, double *x,
                              double *v, drape_error *err)
{
    if (I->type->get_state(I->state, t, I->yd, err)) return -1;
    y_to_full(I->ode.lattice, I->ode.nf3, I->yd, x, v);
    return 0;
}

void drape_integrator_get_stats(const drape_integrator *I, drape_integrator_stats *s)
{
    I->type->stats(I->state, s);
}

const char *drape_integrator_name(const drape_integrator *I) { return I->type->name; }

long drape_integrator_dim(const drape_integrator *I) { return I->ode.dim; }
