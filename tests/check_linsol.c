/* check_linsol.c: the Newton linear solvers of the SUNDIALS backends
 * (src/linsol_schur.c, linsol option of src/integrator_sundials.c).
 *
 * Expected values are independent of the code under test:
 *   - the Schur-reduced solve of (I - gamma J) z = r (numerics.md 3.3) is
 *     compared with a dense GSL LU solve of the 6 nf matrix assembled here
 *     from the model's K and D, at a perturbed state, a compressed state
 *     (S indefinite: the LDL^T path) and with velocities (K unsymmetric:
 *     the preconditioner is then inexact, and preconditioned Richardson
 *     iteration with the dense matrix must converge to the LU solution);
 *   - J v is compared with the dense J times v;
 *   - integrations with klu, schur and schur-direct reach the state of an
 *     explicit reference (gsl-rk8pd at rtol 1e-10) within what the
 *     tolerance promises, on the small hang scene of check_integrator.c.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_blas.h>
#include <gsl/gsl_linalg.h>

#include "drape/alloc.h"
#include "drape/fabric.h"
#include "drape/integrator.h"
#include "drape/lattice.h"
#include "drape/linsol_schur.h"
#include "drape/model.h"
#include "drape/scene.h"
#include "fixture.h"
#include "testutil.h"

/* Deterministic uniform numbers in [-1, 1). */
static double urand(unsigned long *s)
{
    *s = *s * 6364136223846793005UL + 1442695040888963407UL;
    return (double)(*s >> 11) / 4503599627370496.0 - 1.0;
}

/* Everything one linear-algebra case needs. */
typedef struct lcase {
    tf_scene t;
    long n3, dim, nnz;
    double *x, *v, *K, *D, *invm;
    gsl_matrix *J; /* dense first-order Jacobian, dim x dim */
} lcase;

/* State: x = c + scale (xinit - c) + perturbation (c the centroid), v as
 * given by vel (0 = at rest); K, D from the model; J assembled densely. */
static void lc_build(lcase *c, double scale, double pert, double vel)
{
    tf_build(&c->t, 2.0, 0.02);
    const drape_lattice *L = c->t.L;
    const drape_pattern *P = drape_model_pattern(c->t.m);
    c->n3 = 3L * L->n_free;
    c->dim = 2 * c->n3;
    c->nnz = (long)P->nnz;
    size_t n3full = 3 * (size_t)L->n;
    c->x = malloc(sizeof(double) * n3full);
    c->v = calloc(n3full, sizeof(double));
    c->K = malloc(sizeof(double) * (size_t)c->nnz);
    c->D = malloc(sizeof(double) * (size_t)c->nnz);
    c->invm = malloc(sizeof(double) * (size_t)L->n_free);
    double cen[3] = {0, 0, 0};
    for (int i = 0; i < L->n; i++)
        for (int k = 0; k < 3; k++) cen[k] += L->xinit[3 * i + k] / L->n;
    unsigned long seed = 12345;
    for (int i = 0; i < L->n; i++) {
        for (int k = 0; k < 3; k++) {
            c->x[3 * i + k] = cen[k] + scale * (L->xinit[3 * i + k] - cen[k]) +
                              pert * TF_SPACING * urand(&seed);
            c->v[3 * i + k] = vel * urand(&seed);
        }
    }
    for (int k = 0; k < L->n_free; k++) c->invm[k] = 1.0 / L->mass[L->free_to_id[k]];
    ck_assert_int_eq(drape_model_jacobian(c->t.m, DRAPE_PART_ALL, c->x, c->v, c->K, c->D), 0);
    /* J = [0 I; M^-1 K  M^-1 D], assembled entry by entry from the CSC pattern */
    c->J = gsl_matrix_calloc((size_t)c->dim, (size_t)c->dim);
    for (long i = 0; i < c->n3; i++) gsl_matrix_set(c->J, (size_t)i, (size_t)(c->n3 + i), 1.0);
    for (long j = 0; j < c->n3; j++) {
        for (int64_t k = P->colptr[j]; k < P->colptr[j + 1]; k++) {
            long r = (long)P->rowind[k];
            double im = c->invm[r / 3];
            gsl_matrix_set(c->J, (size_t)(c->n3 + r), (size_t)j, im * c->K[k]);
            gsl_matrix_set(c->J, (size_t)(c->n3 + r), (size_t)(c->n3 + j), im * c->D[k]);
        }
    }
}

static void lc_free(lcase *c)
{
    gsl_matrix_free(c->J);
    free(c->x);
    free(c->v);
    free(c->K);
    free(c->D);
    free(c->invm);
    tf_free(&c->t);
}

/* A = I - gamma J (dense, new). */
static gsl_matrix *newton_matrix(const lcase *c, double gamma)
{
    gsl_matrix *A = gsl_matrix_alloc((size_t)c->dim, (size_t)c->dim);
    gsl_matrix_memcpy(A, c->J);
    gsl_matrix_scale(A, -gamma);
    for (long i = 0; i < c->dim; i++)
        gsl_matrix_set(A, (size_t)i, (size_t)i, gsl_matrix_get(A, (size_t)i, (size_t)i) + 1.0);
    return A;
}

/* z = A^-1 r by dense LU with partial pivoting. */
static void lu_solve(const gsl_matrix *A, const double *r, double *z)
{
    size_t n = A->size1;
    gsl_matrix *LU = gsl_matrix_alloc(n, n);
    gsl_permutation *p = gsl_permutation_alloc(n);
    int sgn;
    gsl_matrix_memcpy(LU, A);
    ck_assert_int_eq(gsl_linalg_LU_decomp(LU, p, &sgn), 0);
    gsl_vector_const_view rv = gsl_vector_const_view_array(r, n);
    gsl_vector_view zv = gsl_vector_view_array(z, n);
    ck_assert_int_eq(gsl_linalg_LU_solve(LU, p, &rv.vector, &zv.vector), 0);
    gsl_permutation_free(p);
    gsl_matrix_free(LU);
}

static double max_abs(const double *a, long n)
{
    double m = 0.0;
    for (long i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
    return m;
}

static double rel_diff(const double *a, const double *b, long n)
{
    double d = 0.0;
    for (long i = 0; i < n; i++) d = fmax(d, fabs(a[i] - b[i]));
    return d / max_abs(b, n);
}

/* Schur solve against dense LU for several gamma; returns the schur stats. */
static void check_schur_exact(lcase *c, const double *gammas, int ng,
                              drape_schur_stats *st)
{
    drape_error err;
    drape_error_clear(&err);
    drape_schur *s = drape_schur_new(drape_model_pattern(c->t.m), c->invm, &err);
    ck_assert_msg(s != NULL, "%s", err.msg);
    double *r = malloc(sizeof(double) * (size_t)c->dim);
    double *z = malloc(sizeof(double) * (size_t)c->dim);
    double *zr = malloc(sizeof(double) * (size_t)c->dim);
    unsigned long seed = 777;
    for (int g = 0; g < ng; g++) {
        double gamma = gammas[g];
        for (long i = 0; i < c->dim; i++) r[i] = urand(&seed);
        gsl_matrix *A = newton_matrix(c, gamma);
        lu_solve(A, r, zr);
        gsl_matrix_free(A);
        ck_assert_int_eq(drape_schur_factor(s, c->K, c->D, gamma, &err), 0);
        ck_assert_double_eq(drape_schur_gamma(s), gamma);
        ck_assert_int_eq(drape_schur_solve(s, c->K, gamma, r, z), 0);
        double e = rel_diff(z, zr, c->dim);
        ck_assert_msg(e <= 1e-10, "gamma %g: schur vs LU relative difference %g", gamma, e);
        /* in place (r and z alias) */
        memcpy(z, r, sizeof(double) * (size_t)c->dim);
        ck_assert_int_eq(drape_schur_solve(s, c->K, gamma, z, z), 0);
        ck_assert_msg(rel_diff(z, zr, c->dim) <= 1e-10, "gamma %g in place", gamma);
    }
    drape_schur_get_stats(s, st);
    free(r);
    free(z);
    free(zr);
    drape_schur_free(s);
}

/* ---- the Schur-reduced solve ------------------------------------------------ */

START_TEST(test_schur_matches_lu)
{
    /* at rest (v = 0: K symmetric), perturbed by 1 % of the spacing */
    lcase c;
    lc_build(&c, 1.0, 0.01, 0.0);
    const double gammas[] = {1e-6, 1e-4, 1e-3, 3e-3};
    drape_schur_stats st;
    check_schur_exact(&c, gammas, 4, &st);
    ck_assert_int_eq(st.factorizations, 4);
    ck_assert_int_eq(st.failures, 0);
    lc_free(&c);
}
END_TEST

START_TEST(test_schur_indefinite)
{
    /* Every spring compressed by 2 %: the geometric stiffness
     * k (1 - L/l) (I - u u^T) is negative, so K has positive eigenvalues of
     * about k * 0.02 = 200 N/m per spring while m = 8e-5 kg: at gamma = 0.03,
     * gamma^2 * 200 = 0.18 >> m, S is indefinite and LL^T must fail. */
    lcase c;
    lc_build(&c, 0.98, 0.0, 0.0);
    const double g1[] = {1e-5};
    drape_schur_stats st;
    check_schur_exact(&c, g1, 1, &st);
    ck_assert_int_eq(st.ldl_fallbacks, 0); /* S ~ M: definite */
    const double g2[] = {0.03};
    check_schur_exact(&c, g2, 1, &st);
    ck_assert_int_eq(st.ldl_fallbacks, 1); /* definite no more: LDL^T */
    lc_free(&c);
}
END_TEST

START_TEST(test_schur_not_finite)
{
    lcase c;
    lc_build(&c, 1.0, 0.01, 0.0);
    drape_error err;
    drape_error_clear(&err);
    drape_schur *s = drape_schur_new(drape_model_pattern(c.t.m), c.invm, &err);
    ck_assert_ptr_nonnull(s);
    double *r = calloc((size_t)c.dim, sizeof(double));
    /* nothing factored yet: recoverable failure */
    ck_assert_int_eq(drape_schur_solve(s, c.K, 1e-3, r, r), 1);
    c.K[0] = NAN;
    ck_assert_int_eq(drape_schur_factor(s, c.K, c.D, 1e-3, &err), 1);
    ck_assert_int_eq(drape_schur_solve(s, c.K, 1e-3, r, r), 1);
    drape_schur_stats st;
    drape_schur_get_stats(s, &st);
    ck_assert_int_eq(st.failures, 1);
    free(r);
    drape_schur_free(s);
    lc_free(&c);
}
END_TEST

START_TEST(test_jtimes)
{
    lcase c;
    lc_build(&c, 1.0, 0.01, 0.05); /* with velocities: dashpot K unsymmetric */
    drape_error err;
    drape_error_clear(&err);
    drape_schur *s = drape_schur_new(drape_model_pattern(c.t.m), c.invm, &err);
    ck_assert_ptr_nonnull(s);
    size_t n = (size_t)c.dim;
    double *v = malloc(sizeof(double) * n), *jv = malloc(sizeof(double) * n);
    double *ref = malloc(sizeof(double) * n);
    unsigned long seed = 99;
    for (size_t i = 0; i < n; i++) v[i] = urand(&seed);
    gsl_vector_view vv = gsl_vector_view_array(v, n), rv = gsl_vector_view_array(ref, n);
    gsl_blas_dgemv(CblasNoTrans, 1.0, c.J, &vv.vector, 0.0, &rv.vector);
    drape_schur_jtimes(s, c.K, c.D, v, jv);
    ck_assert_msg(rel_diff(jv, ref, c.dim) <= 1e-13, "J v: %g", rel_diff(jv, ref, c.dim));
    /* D = NULL means D = 0 */
    memset(c.D, 0, sizeof(double) * (size_t)c.nnz);
    drape_schur_jtimes(s, c.K, c.D, v, ref);
    drape_schur_jtimes(s, c.K, NULL, v, jv);
    ck_assert_msg(rel_diff(jv, ref, c.dim) == 0.0, "D = NULL");
    free(v);
    free(jv);
    free(ref);
    drape_schur_free(s);
    lc_free(&c);
}
END_TEST

START_TEST(test_schur_preconditioner_unsymmetric)
{
    /* With velocities the dashpots make K unsymmetric; S is built from the
     * symmetric part, so P^-1 is inexact.  Preconditioned Richardson
     * z += P^-1 (r - A z) with the dense A must still converge to A^-1 r. */
    lcase c;
    lc_build(&c, 1.0, 0.01, 0.5);
    double gamma = 1e-3;
    drape_error err;
    drape_error_clear(&err);
    drape_schur *s = drape_schur_new(drape_model_pattern(c.t.m), c.invm, &err);
    ck_assert_ptr_nonnull(s);
    ck_assert_int_eq(drape_schur_factor(s, c.K, c.D, gamma, &err), 0);
    size_t n = (size_t)c.dim;
    double *r = malloc(sizeof(double) * n), *z = calloc(n, sizeof(double));
    double *zr = malloc(sizeof(double) * n), *res = malloc(sizeof(double) * n);
    unsigned long seed = 4242;
    for (size_t i = 0; i < n; i++) r[i] = urand(&seed);
    gsl_matrix *A = newton_matrix(&c, gamma);
    lu_solve(A, r, zr);
    double first = 0.0, e = 1.0;
    for (int it = 0; it < 30 && e > 1e-12; it++) {
        memcpy(res, r, sizeof(double) * n);
        gsl_vector_view zv = gsl_vector_view_array(z, n), qv = gsl_vector_view_array(res, n);
        gsl_blas_dgemv(CblasNoTrans, -1.0, A, &zv.vector, 1.0, &qv.vector);
        ck_assert_int_eq(drape_schur_solve(s, c.K, gamma, res, res), 0);
        for (size_t i = 0; i < n; i++) z[i] += res[i];
        e = rel_diff(z, zr, c.dim);
        if (it == 0) first = e;
    }
    ck_assert_msg(first > 1e-14, "the dashpot asymmetry should be visible: %g", first);
    ck_assert_msg(first < 0.1, "one application should already be close: %g", first);
    ck_assert_msg(e <= 1e-10, "Richardson did not converge: %g", e);
    gsl_matrix_free(A);
    free(r);
    free(z);
    free(zr);
    free(res);
    drape_schur_free(s);
    lc_free(&c);
}
END_TEST

/* ---- option names ------------------------------------------------------------- */

START_TEST(test_names)
{
    int v = -1;
    ck_assert_int_eq(drape_linsol_parse("auto", &v), 0);
    ck_assert_int_eq(v, DRAPE_LINSOL_AUTO);
    ck_assert_int_eq(drape_linsol_parse("klu", &v), 0);
    ck_assert_int_eq(v, DRAPE_LINSOL_KLU);
    ck_assert_int_eq(drape_linsol_parse("schur", &v), 0);
    ck_assert_int_eq(v, DRAPE_LINSOL_SCHUR);
    ck_assert_int_eq(drape_linsol_parse("schur-direct", &v), 0);
    ck_assert_int_eq(v, DRAPE_LINSOL_SCHUR_DIRECT);
    ck_assert_int_eq(drape_linsol_parse("lu", &v), -1);
    ck_assert_int_eq(drape_linsol_parse(NULL, &v), -1);
    ck_assert_str_eq(drape_linsol_name(DRAPE_LINSOL_KLU), "klu");
    ck_assert_str_eq(drape_linsol_name(DRAPE_LINSOL_SCHUR_DIRECT), "schur-direct");
    ck_assert_str_eq(drape_linsol_name(99), "none");

    drape_integrator_opts o;
    drape_integrator_opts_default(&o);
    ck_assert_int_eq(o.linsol, DRAPE_LINSOL_AUTO);
}
END_TEST

/* ---- integrations --------------------------------------------------------------- */

/* Run `name` with linear solver ls to t_end; full x, v out. */
static void run(drape_model *m, const char *name, int ls, double rtol, double t_end,
                double *x, double *v, drape_integrator_stats *st)
{
    drape_error err;
    drape_error_clear(&err);
    drape_integrator_opts o;
    drape_integrator_opts_default(&o);
    o.rtol = rtol;
    o.atol = 1e-3 * rtol;
    o.t_stop = t_end;
    o.linsol = ls;
    drape_integrator *I = drape_integrator_new(m, name, &o, &err);
    ck_assert_msg(I != NULL, "%s/%s: %s", name, drape_linsol_name(ls), err.msg);
    ck_assert_msg(drape_integrator_step_to(I, t_end, DRAPE_STEP_NORMAL, &err) == 0,
                  "%s/%s: %s", name, drape_linsol_name(ls), err.msg);
    ck_assert_double_eq_tol(drape_integrator_time(I), t_end, 1e-12);
    drape_integrator_state(I, x, v);
    drape_integrator_get_stats(I, st);
    drape_integrator_free(I);
}

START_TEST(test_integration_agrees)
{
    const double t_end = 0.2, rtol = 1e-5;
    tf_scene t;
    tf_build(&t, 2.0, 0.02);
    size_t n3 = 3 * (size_t)t.L->n;
    double *xr = malloc(sizeof(double) * n3), *vr = malloc(sizeof(double) * n3);
    double *x = malloc(sizeof(double) * n3), *v = malloc(sizeof(double) * n3);
    double *xk = malloc(sizeof(double) * n3), *vk = malloc(sizeof(double) * n3);
    drape_integrator_stats st;
    run(t.m, "gsl-rk8pd", DRAPE_LINSOL_AUTO, 1e-10, t_end, xr, vr, &st);
    ck_assert_int_eq(st.linsol, 0); /* explicit: no linear solver */
    ck_assert_msg(max_abs(vr, (long)n3) > 0.05, "the cloth should be moving");
    static const char *const impl[] = {"cvode-bdf", "arkode-dirk", "arkode-imex"};
    static const int ls[] = {DRAPE_LINSOL_KLU, DRAPE_LINSOL_SCHUR, DRAPE_LINSOL_SCHUR_DIRECT};
    for (int k = 0; k < 3; k++) {
        for (int l = 0; l < 3; l++) {
            run(t.m, impl[k], ls[l], rtol, t_end, x, v, &st);
            ck_assert_int_eq(st.linsol, ls[l]);
            if (ls[l] == DRAPE_LINSOL_KLU) {
                ck_assert_int_eq(st.lin_iters, 0);
                memcpy(xk, x, sizeof(double) * n3);
                memcpy(vk, v, sizeof(double) * n3);
            } else {
                ck_assert_int_gt(st.lin_iters, 0);
                /* an exact preconditioner: about one Krylov iteration per
                 * Newton iteration */
                ck_assert_msg(st.lin_iters <= 3 * st.nonlin_iters, "%s: %ld lin, %ld nonlin",
                              impl[k], st.lin_iters, st.nonlin_iters);
            }
            /* within 100 rtol of the specimen size of the reference, as
             * check_integrator.c asks of every integrator */
            double dx = 0.0;
            for (size_t i = 0; i < n3; i++) dx = fmax(dx, fabs(x[i] - xr[i]));
            ck_assert_msg(dx / TF_SIDE <= 100 * rtol, "%s/%s: position error %g", impl[k],
                          drape_linsol_name(ls[l]), dx / TF_SIDE);
            /* and klu vs schur: the same Newton iteration up to the linear
             * solve's tolerance, so much closer than the error above */
            double dk = 0.0;
            for (size_t i = 0; i < n3; i++) dk = fmax(dk, fabs(x[i] - xk[i]));
            ck_assert_msg(dk / TF_SIDE <= 10 * rtol, "%s/%s vs klu: %g", impl[k],
                          drape_linsol_name(ls[l]), dk / TF_SIDE);
        }
    }
    free(xr); free(vr); free(x); free(v); free(xk); free(vk);
    tf_free(&t);
}
END_TEST

START_TEST(test_auto_and_bad_option)
{
    tf_scene t;
    tf_build(&t, 2.0, 0.02);
    size_t n3 = 3 * (size_t)t.L->n;
    double *x = malloc(sizeof(double) * n3), *v = malloc(sizeof(double) * n3);
    drape_integrator_stats st;
    run(t.m, "cvode-bdf", DRAPE_LINSOL_AUTO, 1e-4, 0.01, x, v, &st);
    int want = 3L * t.L->n_free >= DRAPE_LINSOL_SCHUR_MIN_NF3 ? DRAPE_LINSOL_SCHUR_DIRECT
                                                             : DRAPE_LINSOL_KLU;
    ck_assert_int_eq(st.linsol, want);

    drape_error err;
    drape_error_clear(&err);
    drape_integrator_opts o;
    drape_integrator_opts_default(&o);
    o.linsol = 7;
    ck_assert_ptr_null(drape_integrator_new(t.m, "cvode-bdf", &o, &err));
    ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
    free(x);
    free(v);
    tf_free(&t);
}
END_TEST

/* Every allocation failure inside drape_integrator_new with each linear
 * solver is reported as E_NOMEM (run under valgrind for leaks). */
START_TEST(test_alloc_failures)
{
    tf_scene t;
    tf_build(&t, 2.0, 0.02);
    static const char *const impl[] = {"cvode-bdf", "arkode-imex"};
    static const int ls[] = {DRAPE_LINSOL_KLU, DRAPE_LINSOL_SCHUR, DRAPE_LINSOL_SCHUR_DIRECT};
    for (int k = 0; k < 2; k++) {
        for (int l = 0; l < 3; l++) {
            int done = 0;
            for (long n = 1; n < 200 && !done; n++) {
                drape_integrator_opts o;
                drape_integrator_opts_default(&o);
                o.linsol = ls[l];
                drape_error err;
                drape_error_clear(&err);
                drape_alloc_fail_at(n);
                drape_integrator *I = drape_integrator_new(t.m, impl[k], &o, &err);
                drape_alloc_fail_at(0);
                if (I) {
                    done = 1;
                    /* and it runs */
                    ck_assert_int_eq(drape_integrator_step_to(I, 1e-3, DRAPE_STEP_NORMAL,
                                                              &err), 0);
                    drape_integrator_free(I);
                } else {
                    ck_assert_msg(err.kind == DRAPE_E_NOMEM, "%s/%s, fail at %ld: %s",
                                  impl[k], drape_linsol_name(ls[l]), n, err.msg);
                }
            }
            ck_assert(done);
        }
    }
    tf_free(&t);
}
END_TEST

Suite *linsol_suite(void)
{
    Suite *s = suite_create("linsol");
    TCase *tc = tcase_create("schur");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_schur_matches_lu);
    tcase_add_test(tc, test_schur_indefinite);
    tcase_add_test(tc, test_schur_not_finite);
    tcase_add_test(tc, test_jtimes);
    tcase_add_test(tc, test_schur_preconditioner_unsymmetric);
    tcase_add_test(tc, test_names);
    suite_add_tcase(s, tc);
    TCase *ti = tcase_create("integration");
    tcase_set_timeout(ti, 120);
    tcase_add_test(ti, test_integration_agrees);
    tcase_add_test(ti, test_auto_and_bad_option);
    tcase_add_test(ti, test_alloc_failures);
    suite_add_tcase(s, ti);
    return s;
}
