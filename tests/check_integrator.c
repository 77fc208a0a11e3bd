/* check_integrator.c: the integrators and the driver loop on a small hang
 * scene (6 x 6 particles at 2 cm, cotton, pinned at the two far corners).
 *
 * Expected values are independent of the code under test:
 *   - agreement: each integrator at rtol 1e-5 against a reference made by a
 *     DIFFERENT integrator at rtol 1e-10, itself checked against a third
 *     (two independent libraries must agree to 1/100 of the tested bound);
 *   - conservation: without dissipation E_kin + E_pot is constant (docs/model.md 4:
 *     forces are the exact negative gradient), with air drag and dashpots it
 *     never increases;
 *   - equilibrium: at the reported equilibrium the conservative forces
 *     balance (|f_i| small against the particle's weight m_i g);
 *   - memory refusal: 2 * dim^2 * 8 bytes computed by hand.
 */
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <arkode/arkode_erkstep.h>

#include "drape/alloc.h"
#include "drape/fabric.h"
#include "drape/integrator.h"
#include "drape/lattice.h"
#include "drape/model.h"
#include "drape/scene.h"
#include "drape/sim.h"
#include "drape/units.h"
#include "fixture.h"
#include "testutil.h"

/* the fixture, with its particle count checked by hand: 6 x 6 */
static void ts_build(tf_scene *t, double c_air, double c_edge)
{
    tf_build(t, c_air, c_edge);
    ck_assert_int_eq(t->L->n, 36);
}

static void sim_opts(drape_sim_opts *o, const char *name, double rtol, double t_max)
{
    drape_sim_opts_default(o);
    snprintf(o->integrator, sizeof o->integrator, "%s", name);
    o->rtol = rtol;
    o->atol = 1e-3 * rtol; /* m: 1e-3 of the rtol-scale of a 1 m coordinate */
    o->t_max = t_max;
}

static double max_abs_diff(const double *a, const double *b, size_t n)
{
    double d = 0.0;
    for (size_t i = 0; i < n; i++) d = fmax(d, fabs(a[i] - b[i]));
    return d;
}

static int all_finite(const double *a, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(a[i])) return 0;
    return 1;
}

static const char *const ALL[] = {"cvode-bdf", "arkode-imex", "arkode-dirk",
                                  "arkode-erk", "gsl-msbdf", "gsl-rk8pd"};
#define N_ALL (sizeof ALL / sizeof ALL[0])

/* ---- registry ------------------------------------------------------------ */

START_TEST(test_registry)
{
    /* every name the scene loader accepts has a backend */
    for (int k = 0; drape_integrator_names[k]; k++)
        ck_assert_msg(drape_integrator_type_find(drape_integrator_names[k]) != NULL,
                      "no backend for %s", drape_integrator_names[k]);
    for (size_t k = 0; k < N_ALL; k++)
        ck_assert_str_eq(drape_integrator_type_find(ALL[k])->name, ALL[k]);
    ck_assert_str_eq(drape_integrator_type_find("auto")->name, "auto");
    ck_assert_ptr_null(drape_integrator_type_find("rk4"));

    tf_scene t;
    ts_build(&t, 0, 0);
    drape_integrator_opts o;
    drape_integrator_opts_default(&o);
    drape_error err;
    drape_error_clear(&err);
    ck_assert_ptr_null(drape_integrator_new(t.m, "rk4", &o, &err));
    ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
    ck_assert_ptr_nonnull(strstr(err.msg, "rk4"));
    ck_assert_ptr_nonnull(strstr(err.msg, "cvode-bdf"));
    drape_error_clear(&err);
    o.rtol = -1;
    ck_assert_ptr_null(drape_integrator_new(t.m, "cvode-bdf", &o, &err));
    ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
    tf_free(&t);
}
END_TEST

/* gsl-msbdf refuses when its two dense matrices exceed the limit, and says
 * how much it needs: dim = 6 * 34 = 204, 2 * 204^2 * 8 B = 665 856 B =
 * 0.00062 GiB. */
START_TEST(test_msbdf_refuses)
{
    tf_scene t;
    ts_build(&t, 0, 0);
    drape_integrator_opts o;
    drape_integrator_opts_default(&o);
    o.dense_limit_bytes = 665856 - 1;
    drape_error err;
    drape_error_clear(&err);
    ck_assert_ptr_null(drape_integrator_new(t.m, "gsl-msbdf", &o, &err));
    ck_assert_int_eq(err.kind, DRAPE_E_NOMEM);
    ck_assert_msg(strstr(err.msg, "0.00062 GiB") && strstr(err.msg, "204 x 204"),
                  "%s", err.msg);
    o.dense_limit_bytes = 665856;
    drape_error_clear(&err);
    drape_integrator *I = drape_integrator_new(t.m, "gsl-msbdf", &o, &err);
    ck_assert_msg(I != NULL, "%s", err.msg);
    ck_assert_int_eq(drape_integrator_dim(I), 204);
    drape_integrator_free(I);
    tf_free(&t);
}
END_TEST

/* Every allocation failure inside drape_integrator_new and drape_sim_run is
 * reported as E_NOMEM (run under valgrind for leaks). */
START_TEST(test_alloc_failures)
{
    tf_scene t;
    ts_build(&t, 2.0, 0.02);
    for (size_t k = 0; k <= N_ALL; k++) { /* and auto (both of its solvers) */
        const char *name = k < N_ALL ? ALL[k] : "auto";
        int done = 0;
        for (long n = 1; n < 200 && !done; n++) {
            drape_integrator_opts o;
            drape_integrator_opts_default(&o);
            drape_error err;
            drape_error_clear(&err);
            drape_alloc_fail_at(n);
            drape_integrator *I = drape_integrator_new(t.m, name, &o, &err);
            drape_alloc_fail_at(0);
            if (I) {
                done = 1;
                drape_integrator_free(I);
            } else {
                ck_assert_msg(err.kind == DRAPE_E_NOMEM, "%s, fail at %ld: %s", name, n,
                              err.msg);
            }
        }
        ck_assert(done);
    }
    int done = 0;
    for (long n = 1; n < 100 && !done; n++) {
        drape_sim_opts o;
        drape_sim_result r;
        drape_error err;
        drape_error_clear(&err);
        sim_opts(&o, "cvode-bdf", 1e-3, 0.01);
        drape_alloc_fail_at(n);
        int rc = drape_sim_run(t.m, &o, NULL, NULL, &r, &err);
        drape_alloc_fail_at(0);
        if (rc == 0) done = 1;
        else ck_assert_msg(err.kind == DRAPE_E_NOMEM && r.status == DRAPE_SIM_FAILED,
                           "fail at %ld: %s", n, err.msg);
        drape_sim_result_free(&r);
    }
    ck_assert(done);
    tf_free(&t);
}
END_TEST

/* ---- agreement -------------------------------------------------------------- */

/* Damping of scenes/cusick.yaml: air 2 1/s, edge dashpots 0.02 N.s/m. */
START_TEST(test_agreement)
{
    const double t_end = 0.3, rtol = 1e-5, ref_rtol = 1e-10;
    tf_scene t;
    ts_build(&t, 2.0, 0.02);
    size_t n3 = 3 * (size_t)t.L->n;
    drape_sim_opts o;
    drape_sim_result ref, wit;
    drape_error err;
    drape_error_clear(&err);

    sim_opts(&o, "gsl-rk8pd", ref_rtol, t_end);
    ck_assert_msg(drape_sim_run(t.m, &o, NULL, NULL, &ref, &err) == 0, "%s", err.msg);
    sim_opts(&o, "arkode-erk", ref_rtol, t_end);
    ck_assert_msg(drape_sim_run(t.m, &o, NULL, NULL, &wit, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(ref.status, DRAPE_SIM_T_MAX);
    ck_assert_double_eq(ref.t_end_s, t_end);
    double vref = ref.max_speed;
    ck_assert_msg(vref > 0.05, "the cloth should be moving: %g m/s", vref);
    /* the references agree to 1/100 of the bound tested below */
    double dref = max_abs_diff(ref.x, wit.x, n3) / TF_SIDE;
    ck_assert_msg(dref <= 1e-2 * 100 * rtol, "references differ by %g", dref);

    for (size_t k = 0; k < N_ALL; k++) {
        drape_sim_result r;
        drape_error_clear(&err);
        sim_opts(&o, ALL[k], rtol, t_end);
        int rc = drape_sim_run(t.m, &o, NULL, NULL, &r, &err);
        ck_assert_msg(rc == 0, "%s: %s", ALL[k], err.msg);
        ck_assert_str_eq(r.integrator, ALL[k]);
        double dx = max_abs_diff(r.x, ref.x, n3) / TF_SIDE;
        double dv = max_abs_diff(r.v, ref.v, n3) / vref;
        /* positions: within 100 rtol of the specimen size.  Velocities carry
         * the stretch vibration, which L-stable / BDF methods damp at this
         * tolerance (cvode-bdf order 2: 7 % measured), so only a gross check. */
        ck_assert_msg(dx <= 100 * rtol, "%s: position error %g > %g", ALL[k], dx, 100 * rtol);
        ck_assert_msg(dv <= 0.2, "%s: velocity error %g of the speed", ALL[k], dv);
        ck_assert_int_gt(r.stats.steps, 0);
        ck_assert_int_gt(r.stats.rhs_evals, r.stats.steps - 1);
        drape_sim_result_free(&r);
    }
    drape_sim_result_free(&ref);
    drape_sim_result_free(&wit);
    tf_free(&t);
}
END_TEST

/* auto (cvode-bdf <-> arkode-erk, integrator_auto.c), 1: its own rule.
 * With air drag only (no edge dashpots) the stretch vibrations of the
 * swinging fixture are undamped and BDF2's steps shrink below the explicit
 * stability step within 0.3 s, so auto must switch.  Until it does, it is
 * cvode-bdf, whose BDF2 damps those vibrations (2.6e-3 of the side at
 * rtol 1e-5, docs/integrators.md); so its error against gsl-rk8pd at 1e-10
 * is bounded by twice cvode-bdf's own, not by 100 rtol. */
START_TEST(test_auto_switches)
{
    const double t_end = 0.3, rtol = 1e-5;
    tf_scene t;
    ts_build(&t, 0.5, 0.0);
    size_t n3 = 3 * (size_t)t.L->n;
    drape_sim_opts o;
    drape_sim_result ref, bdf, r;
    drape_error err;
    drape_error_clear(&err);
    sim_opts(&o, "gsl-rk8pd", 1e-10, t_end);
    ck_assert_msg(drape_sim_run(t.m, &o, NULL, NULL, &ref, &err) == 0, "%s", err.msg);
    sim_opts(&o, "cvode-bdf", rtol, t_end);
    ck_assert_msg(drape_sim_run(t.m, &o, NULL, NULL, &bdf, &err) == 0, "%s", err.msg);
    sim_opts(&o, "auto", rtol, t_end);
    ck_assert_msg(drape_sim_run(t.m, &o, NULL, NULL, &r, &err) == 0, "%s", err.msg);
    ck_assert_str_eq(r.integrator, "auto");
    ck_assert_int_eq(r.status, DRAPE_SIM_T_MAX);
    ck_assert_msg(r.stats.switches >= 1, "auto never left cvode-bdf (%ld steps)", r.stats.steps);
    ck_assert_int_eq(bdf.stats.switches, -1); /* not available: it never switches */
    double e_bdf = max_abs_diff(bdf.x, ref.x, n3) / TF_SIDE;
    double e_auto = max_abs_diff(r.x, ref.x, n3) / TF_SIDE;
    ck_assert_msg(e_bdf > 100 * rtol, "cvode-bdf error %g: the premise changed", e_bdf);
    ck_assert_msg(e_auto <= 2 * e_bdf, "auto: position error %g, cvode-bdf %g", e_auto, e_bdf);
    drape_sim_result_free(&ref);
    drape_sim_result_free(&bdf);
    drape_sim_result_free(&r);
    tf_free(&t);
}
END_TEST

/* auto, 2: the switching itself.  A threshold of h omega 100 makes every
 * judged BDF2 window hand over to arkode-erk and every probe fail, so the
 * run alternates (BDF2 200 steps, Dormand-Prince 2000, ...).  On the damped
 * fixture of test_agreement, where both solvers are within 100 rtol, the
 * state at every output time, restarts and interpolation included, must
 * stay within 100 rtol of gsl-rk8pd at 1e-10; the counters are the sums. */
START_TEST(test_auto_forced_switches)
{
    const double t_end = 0.3, rtol = 1e-5;
    const int n_out = 15;
    tf_scene t;
    ts_build(&t, 2.0, 0.02);
    size_t n3 = 3 * (size_t)t.L->n;
    double *x = malloc(sizeof(double) * n3), *xr = malloc(sizeof(double) * n3);
    ck_assert(x && xr);
    drape_error err;
    drape_error_clear(&err);
    drape_integrator_opts io;
    drape_integrator_opts_default(&io);
    io.rtol = rtol;
    io.atol = 1e-3 * rtol;
    io.t_stop = t_end;
    io.auto_hw = 100.0;
    drape_integrator *I = drape_integrator_new(t.m, "auto", &io, &err);
    ck_assert_msg(I != NULL, "%s", err.msg);
    drape_integrator_opts ro = io;
    ro.rtol = 1e-10;
    ro.atol = 1e-13;
    drape_integrator *R = drape_integrator_new(t.m, "gsl-rk8pd", &ro, &err);
    ck_assert_msg(R != NULL, "%s", err.msg);
    for (int k = 1; k <= n_out; k++) {
        double tk = t_end * k / n_out;
        ck_assert_msg(drape_integrator_step_to(R, tk, DRAPE_STEP_NORMAL, &err) == 0, "%s",
                      err.msg);
        drape_integrator_state(R, xr, NULL);
        ck_assert_msg(drape_integrator_step_to(I, tk, DRAPE_STEP_NORMAL, &err) == 0, "%s",
                      err.msg);
        ck_assert_double_eq(drape_integrator_time(I), tk);
        drape_integrator_state(I, x, NULL);
        double dx = max_abs_diff(x, xr, n3) / TF_SIDE;
        ck_assert_msg(dx <= 100 * rtol, "t = %g: position error %g", tk, dx);
    }
    drape_integrator_free(R);
    drape_integrator_stats st;
    drape_integrator_get_stats(I, &st);
    ck_assert_msg(st.switches >= 3, "%ld switches", st.switches);
    ck_assert_int_gt(st.steps, 2000);
    ck_assert_int_gt(st.rhs_evals, st.steps);
    ck_assert_int_gt(st.jac_evals, 0); /* cvode-bdf took part */
    drape_integrator_free(I);
    free(x);
    free(xr);
    tf_free(&t);
}
END_TEST

/* auto, 3: a switch whose restart fails.  ERKStepReInit is interposed
 * here (the test binary's definition wins over libsundials_arkode's; it
 * calls the library's unless erk_reinit_fails is set), the only way to
 * make a SUNDIALS restart fail.  Independent count: the calls of
 * DRAPE_STEP_ONE that succeeded, each one accepted step of cvode-bdf.  The
 * failed switch takes no step, so every counter stays as it was before
 * it (they were added twice: steps 400 after 200 steps); a later switch
 * that succeeds adds the arkode-erk step to them. */
static int erk_reinit_fails;

int ERKStepReInit(void *arkode_mem, ARKRhsFn f, sunrealtype t0, N_Vector y0)
{
    typedef int (*reinit_fn)(void *, ARKRhsFn, sunrealtype, N_Vector);
    if (erk_reinit_fails) return ARK_ILL_INPUT;
    reinit_fn real = (reinit_fn)dlsym(RTLD_NEXT, "ERKStepReInit");
    ck_assert_msg(real != NULL, "no ERKStepReInit in the libraries");
    return real(arkode_mem, f, t0, y0);
}

START_TEST(test_auto_failed_switch)
{
    tf_scene t;
    ts_build(&t, 2.0, 0.02);
    drape_error err;
    drape_error_clear(&err);
    drape_integrator_opts io;
    drape_integrator_opts_default(&io);
    io.rtol = 1e-5;
    io.atol = 1e-8;
    io.t_stop = 0.3;
    io.auto_hw = 100.0; /* the first judged window hands over */
    drape_integrator *I = drape_integrator_new(t.m, "auto", &io, &err);
    ck_assert_msg(I != NULL, "%s", err.msg);
    drape_integrator_stats before, st;
    memset(&before, 0, sizeof before);
    long ok = 0;
    erk_reinit_fails = 1;
    while (ok < 10000 && drape_integrator_step_to(I, 0.3, DRAPE_STEP_ONE, &err) == 0) {
        ok++;
        drape_integrator_get_stats(I, &before);
    }
    erk_reinit_fails = 0;
    ck_assert_msg(ok < 10000, "no switch was tried in %ld steps", ok);
    ck_assert_int_eq(err.kind, DRAPE_E_NUMERIC);
    ck_assert_msg(strstr(err.msg, "arkode-erk") && strstr(err.msg, "restart"), "%s", err.msg);
    drape_integrator_get_stats(I, &st);
    ck_assert_int_eq(before.steps, ok);
    ck_assert_int_eq(st.steps, ok);
    ck_assert_int_eq(st.switches, 0);
    ck_assert_int_eq(st.rhs_evals, before.rhs_evals);
    ck_assert_int_eq(st.jac_evals, before.jac_evals);
    ck_assert_int_eq(st.lin_setups, before.lin_setups);
    ck_assert_int_eq(st.nonlin_iters, before.nonlin_iters);
    ck_assert_int_eq(st.err_test_fails, before.err_test_fails);
    ck_assert_int_eq(st.conv_fails, before.conv_fails);
    ck_assert_int_eq(st.lin_factors, before.lin_factors);
    /* the switch again, now restarting: one arkode-erk step more */
    drape_error_clear(&err);
    ck_assert_msg(drape_integrator_step_to(I, 0.3, DRAPE_STEP_ONE, &err) == 0, "%s", err.msg);
    drape_integrator_get_stats(I, &st);
    ck_assert_int_eq(st.switches, 1);
    ck_assert_int_eq(st.steps, ok + 1);
    ck_assert_int_eq(st.nonlin_iters, before.nonlin_iters); /* explicit: none */
    drape_integrator_free(I);
    tf_free(&t);
}
END_TEST

/* ---- energy --------------------------------------------------------------------- */

typedef struct energy_obs {
    drape_model *m;
    double e0, max_dev, max_rise, prev;
    int calls;
} energy_obs;

static double total_energy(drape_model *m, const double *x, const double *v)
{
    drape_energies E;
    ck_assert_int_eq(drape_model_energy(m, x, &E), 0);
    return drape_sim_kinetic_energy(drape_model_lattice(m), v) + E.stretch + E.bend +
           E.shear + E.gravity;
}

static int on_energy(void *ctx, const drape_sim_event *ev, drape_error *err)
{
    energy_obs *o = ctx;
    (void)err;
    double e = total_energy(o->m, ev->x, ev->v);
    if (o->calls == 0) o->e0 = o->prev = e;
    o->max_dev = fmax(o->max_dev, fabs(e - o->e0));
    o->max_rise = fmax(o->max_rise, e - o->prev);
    o->prev = e;
    o->calls++;
    return 0;
}

/* Energy scale: M g L (total mass falling over the specimen size). */
static double energy_scale(const drape_lattice *L)
{
    return L->mass_total * DRAPE_G_STANDARD * TF_SIDE;
}

START_TEST(test_energy_conserved)
{
    const double rtol = 1e-5;
    tf_scene t;
    ts_build(&t, 0, 0);
    double bound = 10 * rtol * energy_scale(t.L);
    for (size_t k = 0; k < N_ALL; k++) {
        drape_sim_opts o;
        drape_sim_result r;
        drape_error err;
        drape_error_clear(&err);
        energy_obs eo = {t.m, 0, 0, 0, 0, 0};
        sim_opts(&o, ALL[k], rtol, 0.5);
        o.frame_every = 0.05;
        ck_assert_msg(drape_sim_run(t.m, &o, on_energy, &eo, &r, &err) == 0, "%s: %s",
                      ALL[k], err.msg);
        ck_assert_int_eq(eo.calls, 11);
        ck_assert_msg(eo.max_dev <= bound, "%s: energy drift %g J > %g J", ALL[k],
                      eo.max_dev, bound);
        /* the observer saw a moving cloth, not a frozen one */
        ck_assert_double_gt(r.kinetic_J, 1e-3 * energy_scale(t.L));
        drape_sim_result_free(&r);
    }
    tf_free(&t);
}
END_TEST

START_TEST(test_energy_dissipated)
{
    const double rtol = 1e-5;
    tf_scene t;
    ts_build(&t, 0.5, 0.02);
    double bound = 10 * rtol * energy_scale(t.L);
    for (size_t k = 0; k < N_ALL; k++) {
        drape_sim_opts o;
        drape_sim_result r;
        drape_error err;
        drape_error_clear(&err);
        energy_obs eo = {t.m, 0, 0, 0, 0, 0};
        sim_opts(&o, ALL[k], rtol, 0.5);
        o.frame_every = 0.025;
        ck_assert_msg(drape_sim_run(t.m, &o, on_energy, &eo, &r, &err) == 0, "%s: %s",
                      ALL[k], err.msg);
        ck_assert_msg(eo.max_rise <= bound, "%s: energy rose by %g J > %g J", ALL[k],
                      eo.max_rise, bound);
        ck_assert_msg(eo.prev < eo.e0 - 1e3 * bound, "%s: nothing dissipated", ALL[k]);
        drape_sim_result_free(&r);
    }
    tf_free(&t);
}
END_TEST

/* ---- failures --------------------------------------------------------------------- */

static void assert_clean_failure(const drape_sim_result *r, const drape_error *err,
                                 const char *name, const char *reason, size_t n3)
{
    ck_assert_int_eq(r->status, DRAPE_SIM_FAILED);
    ck_assert_int_eq(err->kind, DRAPE_E_NUMERIC);
    ck_assert_msg(strstr(err->msg, name) && strstr(err->msg, "t = ") &&
                      strstr(err->msg, "hint:") && (!reason || strstr(err->msg, reason)),
                  "message: %s", err->msg);
    ck_assert(all_finite(r->x, n3) && all_finite(r->v, n3));
    ck_assert(isfinite(r->t_end_s) && isfinite(r->kinetic_J) && isfinite(r->energy.stretch));
}

START_TEST(test_too_much_work)
{
    tf_scene t;
    ts_build(&t, 0, 0);
    size_t n3 = 3 * (size_t)t.L->n;
    const char *names[] = {"arkode-erk", "gsl-rk8pd", "cvode-bdf"};
    const char *reasons[] = {"ARK_TOO_MUCH_WORK", "GSL_EMAXITER", "CV_TOO_MUCH_WORK"};
    for (int k = 0; k < 3; k++) {
        drape_sim_opts o;
        drape_sim_result r;
        drape_error err;
        drape_error_clear(&err);
        sim_opts(&o, names[k], 1e-2, 1.0);
        o.max_steps = 10;
        ck_assert_int_eq(drape_sim_run(t.m, &o, NULL, NULL, &r, &err), -1);
        assert_clean_failure(&r, &err, names[k], reasons[k], n3);
        ck_assert_double_lt(r.t_end_s, 1.0);
        drape_sim_result_free(&r);
    }
    tf_free(&t);
}
END_TEST

/* A start with a hinge folded back onto itself (particle (2,0) placed on
 * (0,0), so the hinge at (1,0) has psi = pi): the model cannot be evaluated
 * there, and every integrator must stop cleanly, never with NaN. */
START_TEST(test_folded_start_fails_cleanly)
{
    tf_scene t;
    ts_build(&t, 0, 0);
    size_t n3 = 3 * (size_t)t.L->n;
    int a = t.L->grid[0 * t.L->ni + 0], c = t.L->grid[0 * t.L->ni + 2];
    ck_assert(!t.L->fixed[c]);
    for (int q = 0; q < 3; q++) t.L->xinit[3 * c + q] = t.L->xinit[3 * a + q];
    for (size_t k = 0; k < N_ALL; k++) {
        drape_sim_opts o;
        drape_sim_result r;
        drape_error err;
        drape_error_clear(&err);
        sim_opts(&o, ALL[k], 1e-4, 0.1);
        ck_assert_int_eq(drape_sim_run(t.m, &o, NULL, NULL, &r, &err), -1);
        assert_clean_failure(&r, &err, ALL[k], NULL, n3);
        drape_sim_result_free(&r);
    }
    tf_free(&t);
}
END_TEST

/* gsl-msbdf with a Jacobian that cannot be evaluated where the forces can:
 * the fixture's stretch stiffness times 1e300, so at the flat start (no
 * strain) the forces are gravity alone but K / m overflows.  A clean error
 * naming the Jacobian after its first evaluation, no step attempted again
 * (GSL halved the step 1054 times down to h = 0 and reported a collapsed
 * step size, counted as 1054 error test failures). */
START_TEST(test_msbdf_jacobian_fails_cleanly)
{
    tf_scene t;
    ts_build(&t, 0, 0);
    size_t n3 = 3 * (size_t)t.L->n;
    drape_fabric stiff = t.fab;
    stiff.k[DRAPE_WEFT] *= 1e300;
    stiff.k[DRAPE_WARP] *= 1e300;
    drape_model_opts mo;
    drape_model_opts_from_scene(&t.sc, &mo);
    drape_error err;
    drape_error_clear(&err);
    drape_model *m = drape_model_new(t.L, &stiff, &mo, &err);
    ck_assert_msg(m != NULL, "%s", err.msg);
    /* the premise: finite forces at the start */
    double *f = malloc(sizeof(double) * n3), *v0 = calloc(n3, sizeof(double));
    ck_assert(f && v0);
    ck_assert_int_eq(drape_model_forces(m, drape_model_parts(m), t.L->xinit, v0, f), 0);
    ck_assert(all_finite(f, n3));
    drape_integrator_opts io;
    drape_integrator_opts_default(&io);
    drape_integrator *I = drape_integrator_new(m, "gsl-msbdf", &io, &err);
    ck_assert_msg(I != NULL, "%s", err.msg);
    ck_assert_int_eq(drape_integrator_step_to(I, 0.01, DRAPE_STEP_NORMAL, &err), -1);
    ck_assert_int_eq(err.kind, DRAPE_E_NUMERIC);
    ck_assert_msg(strstr(err.msg, "gsl-msbdf") && strstr(err.msg, "Jacobian") &&
                      strstr(err.msg, "t = 0 s") && strstr(err.msg, "hint:"),
                  "%s", err.msg);
    ck_assert_double_eq(drape_integrator_time(I), 0.0);
    drape_integrator_stats st;
    drape_integrator_get_stats(I, &st);
    ck_assert_int_eq(st.jac_evals, 1);
    ck_assert_int_eq(st.steps, 0);
    ck_assert_int_eq(st.err_test_fails, 0);
    drape_integrator_free(I);
    /* the driver: a clean failure, the start state kept */
    drape_sim_opts o;
    drape_sim_result r;
    drape_error_clear(&err);
    sim_opts(&o, "gsl-msbdf", 1e-4, 0.1);
    ck_assert_int_eq(drape_sim_run(m, &o, NULL, NULL, &r, &err), -1);
    assert_clean_failure(&r, &err, "gsl-msbdf", "Jacobian", n3);
    ck_assert_double_eq(r.t_end_s, 0.0);
    drape_sim_result_free(&r);
    free(f);
    free(v0);
    drape_model_free(m);
    tf_free(&t);
}
END_TEST

/* ---- driver ------------------------------------------------------------------------- */

typedef struct sched_obs {
    int n;
    unsigned what[16];
    double t[16];
    int stop_at; /* call index at which to fail, -1 never */
} sched_obs;

static int on_sched(void *ctx, const drape_sim_event *ev, drape_error *err)
{
    sched_obs *s = ctx;
    if (s->n < 16) {
        s->what[s->n] = ev->what;
        s->t[s->n] = ev->t;
    }
    if (s->n++ == s->stop_at)
        return drape_error_set(err, DRAPE_E_IO, "frame.obj", 0, 0, NULL, "disk full");
    return 0;
}

START_TEST(test_observer_schedule)
{
    tf_scene t;
    ts_build(&t, 2.0, 0.02);
    drape_sim_opts o;
    drape_sim_result r;
    drape_error err;
    drape_error_clear(&err);
    sim_opts(&o, "cvode-bdf", 1e-4, 0.3);
    o.frame_every = 0.1;
    sched_obs s = {0, {0}, {0}, -1};
    ck_assert_msg(drape_sim_run(t.m, &o, on_sched, &s, &r, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(s.n, 4);
    ck_assert_uint_eq(s.what[0], DRAPE_SIM_AT_START | DRAPE_SIM_AT_FRAME);
    ck_assert_uint_eq(s.what[1], DRAPE_SIM_AT_FRAME);
    ck_assert_uint_eq(s.what[2], DRAPE_SIM_AT_FRAME);
    ck_assert_uint_eq(s.what[3], DRAPE_SIM_AT_END | DRAPE_SIM_AT_FRAME);
    ck_assert_double_eq(s.t[0], 0.0);
    ck_assert_double_eq_tol(s.t[1], 0.1, 1e-12);
    ck_assert_double_eq_tol(s.t[2], 0.2, 1e-12);
    ck_assert_double_eq(s.t[3], 0.3);
    ck_assert_int_eq(r.frames, 4);
    ck_assert_int_eq(r.status, DRAPE_SIM_T_MAX);
    ck_assert_str_eq(drape_sim_status_name(r.status), "t_max");
    ck_assert_double_gt(r.wall_s, 0.0);
    drape_sim_result_free(&r);

    /* an observer error stops the run with its own message */
    drape_error_clear(&err);
    sched_obs s2 = {0, {0}, {0}, 2};
    ck_assert_int_eq(drape_sim_run(t.m, &o, on_sched, &s2, &r, &err), -1);
    ck_assert_int_eq(s2.n, 3);
    ck_assert_int_eq(r.status, DRAPE_SIM_FAILED);
    ck_assert_int_eq(err.kind, DRAPE_E_IO);
    ck_assert_str_eq(err.msg, "disk full");
    drape_sim_result_free(&r);

    /* bad options */
    drape_error_clear(&err);
    o.t_max = 0;
    ck_assert_int_eq(drape_sim_run(t.m, &o, NULL, NULL, &r, &err), -1);
    ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
    drape_sim_result_free(&r);
    tf_free(&t);
}
END_TEST

START_TEST(test_equilibrium)
{
    tf_scene t;
    ts_build(&t, 5.0, 0.05);
    const drape_lattice *L = t.L;
    drape_sim_opts o;
    drape_sim_result r;
    drape_error err;
    drape_error_clear(&err);
    sim_opts(&o, "cvode-bdf", 1e-5, 10.0);
    o.has_equilibrium = 1;
    o.eq_speed = 1e-3;
    o.eq_window = 0.1;
    ck_assert_msg(drape_sim_run(t.m, &o, NULL, NULL, &r, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(r.status, DRAPE_SIM_EQUILIBRIUM);
    ck_assert_str_eq(drape_sim_status_name(r.status), "equilibrium");
    ck_assert_double_lt(r.t_end_s, o.t_max);
    ck_assert_double_ge(r.t_end_s, o.eq_window);
    ck_assert_double_lt(r.max_speed, o.eq_speed);
    ck_assert_double_lt(r.check_speed, o.eq_speed); /* what the test compared */
    /* static balance: conservative force on each free particle is small
     * against its weight */
    double *f = malloc(sizeof(double) * 3 * (size_t)L->n);
    ck_assert_int_eq(drape_model_forces(t.m, DRAPE_PART_STRETCH | DRAPE_PART_BEND |
                                                 DRAPE_PART_SHEAR | DRAPE_PART_GRAVITY,
                                        r.x, NULL, f), 0);
    double worst = 0.0;
    for (int i = 0; i < L->n; i++) {
        if (L->fixed[i]) continue;
        double fi = sqrt(f[3 * i] * f[3 * i] + f[3 * i + 1] * f[3 * i + 1] +
                         f[3 * i + 2] * f[3 * i + 2]);
        worst = fmax(worst, fi / (L->mass[i] * DRAPE_G_STANDARD));
    }
    free(f);
    ck_assert_msg(worst < 0.05, "residual force %g m g at equilibrium", worst);
    /* the cloth did fall: the free corners hang below the pins */
    ck_assert_double_lt(r.energy.gravity, -0.1 * energy_scale(L));
    double t_eq = r.t_end_s;
    drape_sim_result_free(&r);

    /* an unreachable threshold never triggers */
    drape_error_clear(&err);
    o.eq_speed = 1e-12;
    o.t_max = t_eq;
    ck_assert_msg(drape_sim_run(t.m, &o, NULL, NULL, &r, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(r.status, DRAPE_SIM_T_MAX);
    ck_assert_double_eq(r.t_end_s, t_eq);
    drape_sim_result_free(&r);
    tf_free(&t);
}
END_TEST

/* One internal step, dense output inside it, restart. */
START_TEST(test_one_step_dense_reinit)
{
    tf_scene t;
    ts_build(&t, 2.0, 0.02);
    size_t n3 = 3 * (size_t)t.L->n;
    double *x = malloc(sizeof(double) * n3), *v = malloc(sizeof(double) * n3);
    double *x1 = malloc(sizeof(double) * n3), *v0 = calloc(n3, sizeof(double));
    const char *names[] = {"cvode-bdf", "arkode-dirk", "arkode-imex", "arkode-erk"};
    for (int k = 0; k < 4; k++) {
        drape_integrator_opts o;
        drape_integrator_opts_default(&o);
        o.rtol = 1e-6;
        o.atol = 1e-9;
        o.t_stop = 0.05;
        drape_error err;
        drape_error_clear(&err);
        drape_integrator *I = drape_integrator_new(t.m, names[k], &o, &err);
        ck_assert_msg(I != NULL, "%s", err.msg);
        ck_assert_int_eq(drape_integrator_step_to(I, 0.05, DRAPE_STEP_ONE, &err), 0);
        double t1 = drape_integrator_time(I);
        ck_assert_double_gt(t1, 0.0);
        ck_assert_double_le(t1, 0.05);
        while (drape_integrator_time(I) < 0.01)
            ck_assert_int_eq(drape_integrator_step_to(I, 0.05, DRAPE_STEP_ONE, &err), 0);
        double tc = drape_integrator_time(I);
        /* dense output at the current time equals the state */
        drape_integrator_state(I, x1, NULL);
        ck_assert_int_eq(drape_integrator_state_at(I, tc, x, v, &err), 0);
        ck_assert_double_le(max_abs_diff(x, x1, n3), 1e-12);
        /* restart from the initial state and reach tc again in NORMAL mode:
         * same positions to within the tolerance */
        ck_assert_int_eq(drape_integrator_reinit(I, 0.0, t.L->xinit, v0, &err), 0);
        ck_assert_double_eq(drape_integrator_time(I), 0.0);
        ck_assert_int_eq(drape_integrator_step_to(I, tc, DRAPE_STEP_NORMAL, &err), 0);
        ck_assert_double_eq(drape_integrator_time(I), tc);
        drape_integrator_state(I, x, v);
        ck_assert_msg(max_abs_diff(x, x1, n3) <= 100 * o.rtol * TF_SIDE, "%s: %g", names[k],
                      max_abs_diff(x, x1, n3));
        drape_integrator_free(I);
    }
    free(x);
    free(v);
    free(x1);
    free(v0);
    tf_free(&t);
}
END_TEST

/* "steps" counts accepted steps (docs/integrators.md, statistics) for GSL
 * too.  Independent count: the calls of DRAPE_STEP_ONE, each of which
 * takes exactly one accepted step (gsl_odeiv2_evolve_apply); NORMAL mode
 * to the same bound takes the very same steps (same state to the bit).
 * GSL's evolve->count also counts the attempts its error test rejected,
 * which the scene has (err_test_fails > 0): reported as steps before. */
START_TEST(test_gsl_steps_accepted)
{
    tf_scene t;
    ts_build(&t, 0, 0);
    size_t n3 = 3 * (size_t)t.L->n;
    double *xa = malloc(sizeof(double) * n3), *xb = malloc(sizeof(double) * n3);
    const char *names[] = {"gsl-msbdf", "gsl-rk8pd"};
    for (int k = 0; k < 2; k++) {
        drape_integrator_opts o;
        drape_integrator_opts_default(&o);
        o.rtol = 1e-6;
        o.atol = 1e-9;
        o.t_stop = 0.1;
        drape_error err;
        drape_error_clear(&err);
        drape_integrator *A = drape_integrator_new(t.m, names[k], &o, &err);
        drape_integrator *B = drape_integrator_new(t.m, names[k], &o, &err);
        ck_assert_msg(A && B, "%s", err.msg);
        long calls = 0;
        while (drape_integrator_time(A) < 0.1) {
            ck_assert_msg(drape_integrator_step_to(A, 0.1, DRAPE_STEP_ONE, &err) == 0, "%s", err.msg);
            calls++;
        }
        ck_assert_msg(drape_integrator_step_to(B, 0.1, DRAPE_STEP_NORMAL, &err) == 0, "%s", err.msg);
        drape_integrator_state(A, xa, NULL);
        drape_integrator_state(B, xb, NULL);
        ck_assert_double_eq(max_abs_diff(xa, xb, n3), 0.0);
        drape_integrator_stats sa, sb;
        drape_integrator_get_stats(A, &sa);
        drape_integrator_get_stats(B, &sb);
        ck_assert_msg(sa.err_test_fails > 0, "%s: no rejected step, the test proves nothing", names[k]);
        ck_assert_msg(sa.steps == calls && sb.steps == calls,
                      "%s: %ld accepted steps, reported %ld (ONE) and %ld (NORMAL)", names[k],
                      calls, sa.steps, sb.steps);
        /* counters restart with the integrator */
        ck_assert_int_eq(drape_integrator_reinit(B, 0.0, t.L->xinit, NULL, &err), 0);
        drape_integrator_get_stats(B, &sb);
        ck_assert_int_eq(sb.steps, 0);
        drape_integrator_free(A);
        drape_integrator_free(B);
    }
    free(xa);
    free(xb);
    tf_free(&t);
}
END_TEST

/* max_steps is the number of steps a step_to call may take (integrator.h;
 * docs/integrators.md: per output interval), as for the SUNDIALS backends.
 * Independent expectation: the time and state after max_steps steps of
 * DRAPE_STEP_ONE (the same steps, to the bit, as above).  GSL's driver
 * nmax let max_steps + 1 steps succeed and failed after max_steps + 2. */
START_TEST(test_gsl_max_steps)
{
    tf_scene t;
    ts_build(&t, 0, 0);
    size_t n3 = 3 * (size_t)t.L->n;
    double *xa = malloc(sizeof(double) * n3), *xb = malloc(sizeof(double) * n3);
    const char *names[] = {"gsl-msbdf", "gsl-rk8pd"};
    const long N = 10;
    for (int k = 0; k < 2; k++) {
        drape_integrator_opts o;
        drape_integrator_opts_default(&o);
        o.rtol = 1e-6;
        o.atol = 1e-9;
        o.t_stop = 1.0;
        o.max_steps = N;
        drape_error err;
        drape_error_clear(&err);
        drape_integrator *A = drape_integrator_new(t.m, names[k], &o, &err);
        drape_integrator *B = drape_integrator_new(t.m, names[k], &o, &err);
        ck_assert_msg(A && B, "%s", err.msg);
        double tn[12];
        for (int n = 0; n < 12; n++) {
            ck_assert_msg(drape_integrator_step_to(B, 1.0, DRAPE_STEP_ONE, &err) == 0, "%s", err.msg);
            tn[n] = drape_integrator_time(B);
            if (n == N - 1) drape_integrator_state(B, xb, NULL);
        }
        ck_assert_double_lt(tn[11], 1.0);
        /* 1 s needs far more than N steps: fails after exactly N */
        ck_assert_int_eq(drape_integrator_step_to(A, 1.0, DRAPE_STEP_NORMAL, &err), -1);
        ck_assert_msg(err.kind == DRAPE_E_NUMERIC && strstr(err.msg, "GSL_EMAXITER"), "%s", err.msg);
        drape_integrator_stats st;
        drape_integrator_get_stats(A, &st);
        ck_assert_msg(drape_integrator_time(A) == tn[N - 1] && st.steps == N,
                      "%s: stopped at t = %.17g after %ld steps; %ld steps end at %.17g",
                      names[k], drape_integrator_time(A), st.steps, N, tn[N - 1]);
        drape_integrator_state(A, xa, NULL);
        ck_assert_double_eq(max_abs_diff(xa, xb, n3), 0.0);
        /* an interval of exactly N + 1 steps is refused, one of N is not */
        drape_error_clear(&err);
        ck_assert_int_eq(drape_integrator_reinit(A, 0.0, t.L->xinit, NULL, &err), 0);
        ck_assert_int_eq(drape_integrator_step_to(A, tn[N], DRAPE_STEP_NORMAL, &err), -1);
        drape_error_clear(&err);
        ck_assert_int_eq(drape_integrator_reinit(A, 0.0, t.L->xinit, NULL, &err), 0);
        ck_assert_msg(drape_integrator_step_to(A, tn[N - 1], DRAPE_STEP_NORMAL, &err) == 0, "%s", err.msg);
        ck_assert_double_eq(drape_integrator_time(A), tn[N - 1]);
        drape_integrator_free(A);
        drape_integrator_free(B);
    }
    free(xa);
    free(xb);
    tf_free(&t);
}
END_TEST

Suite *integrator_suite(void)
{
    Suite *s = suite_create("integrator");
    TCase *tc = tcase_create("api");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_registry);
    tcase_add_test(tc, test_msbdf_refuses);
    tcase_add_test(tc, test_alloc_failures);
    tcase_add_test(tc, test_observer_schedule);
    tcase_add_test(tc, test_one_step_dense_reinit);
    tcase_add_test(tc, test_gsl_steps_accepted);
    tcase_add_test(tc, test_gsl_max_steps);
    suite_add_tcase(s, tc);
    tc = tcase_create("accuracy");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_agreement);
    tcase_add_test(tc, test_auto_switches);
    tcase_add_test(tc, test_auto_forced_switches);
    tcase_add_test(tc, test_auto_failed_switch);
    tcase_add_test(tc, test_energy_conserved);
    tcase_add_test(tc, test_energy_dissipated);
    suite_add_tcase(s, tc);
    tc = tcase_create("failures");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_too_much_work);
    tcase_add_test(tc, test_folded_start_fails_cleanly);
    tcase_add_test(tc, test_msbdf_jacobian_fails_cleanly);
    suite_add_tcase(s, tc);
    tc = tcase_create("equilibrium");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, test_equilibrium);
    suite_add_tcase(s, tc);
    return s;
}
