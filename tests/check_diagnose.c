/* check_diagnose.c: numerical faults (diagnose.h) and the driver's use of
 * them (sim.h: stop on a fault before an observer sees the state; stop
 * flag; resume from a state).  Expected strains and energies are computed
 * here from the geometry, not by the module under test. */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/diagnose.h"
#include "drape/sim.h"
#include "drape/units.h"
#include "fixture.h"
#include "testutil.h"

static int id_at(const drape_lattice *L, int i, int j)
{
    int id = L->grid[j * L->ni + i];
    ck_assert_int_ge(id, 0);
    return id;
}

static double *copy3n(const drape_lattice *L, const double *src)
{
    double *a = calloc((size_t)(3 * L->n), sizeof *a);
    ck_assert_ptr_nonnull(a);
    if (src) memcpy(a, src, sizeof *a * (size_t)(3 * L->n));
    return a;
}

START_TEST(test_rest_state_is_clean)
{
    tf_scene t;
    tf_build(&t, 0.5, 0.0);
    double *v = copy3n(t.L, NULL);
    drape_diag_ref ref;
    drape_diag_ref_init(t.m, t.L->xinit, v, &ref);
    /* flat at z = 0, at rest: every energy 0, scale = M g L, M = W x area,
     * L = the side (cotton-breen: 20 mg/cm^2 = 0.2 kg/m^2) */
    ck_assert(ref.valid);
    ck_assert_close_abs(ref.energy_J, 0.0, 1e-15);
    ck_assert_close_rel(ref.scale_J, 0.2 * TF_SIDE * TF_SIDE * DRAPE_G_STANDARD * TF_SIDE, 1e-9);
    drape_diagnosis d;
    ck_assert_int_eq(drape_diagnose(t.m, 0.0, t.L->xinit, v, DRAPE_DIAG_STRAIN_LIMIT_DEFAULT,
                                    DRAPE_DIAG_ENERGY_GAIN_DEFAULT, &ref, &d), 0);
    ck_assert_int_eq(d.kind, DRAPE_DIAG_NONE);
    free(v);
    tf_free(&t);
}
END_TEST

START_TEST(test_nonfinite_located)
{
    tf_scene t;
    tf_build(&t, 0.5, 0.0);
    double *x = copy3n(t.L, t.L->xinit), *v = copy3n(t.L, NULL);
    int p = id_at(t.L, 2, 3);
    x[3 * p + 1] = NAN;
    drape_diagnosis d;
    ck_assert_int_eq(drape_diagnose(t.m, 0.25, x, v, 0.2, 1.0, NULL, &d), 1);
    ck_assert_int_eq(d.kind, DRAPE_DIAG_NONFINITE);
    ck_assert_str_eq(d.term, "position");
    ck_assert_int_eq(d.particle, p);
    ck_assert_int_eq(d.i, 2);
    ck_assert_int_eq(d.j, 3);
    ck_assert_int_eq(d.component, 1);
    char buf[512], want[64];
    drape_diagnosis_format(&d, buf, sizeof buf);
    snprintf(want, sizeof want, "particle %d (i 2, j 3)", p);
    ck_assert_msg(strstr(buf, want) && strstr(buf, "t = 0.25 s") && strstr(buf, "position"),
                  "%s", buf);

    /* a velocity: positions finite, every force finite -> "velocity" */
    x[3 * p + 1] = t.L->xinit[3 * p + 1];
    int q = id_at(t.L, 4, 0);
    v[3 * q + 2] = INFINITY;
    ck_assert_int_eq(drape_diagnose(t.m, 0.5, x, v, 0.2, 1.0, NULL, &d), 1);
    ck_assert_str_eq(d.term, "velocity");
    ck_assert_int_eq(d.particle, q);
    ck_assert_int_eq(d.i, 4);
    ck_assert_int_eq(d.j, 0);
    ck_assert_int_eq(d.component, 2);
    free(x);
    free(v);
    tf_free(&t);
}
END_TEST

/* Particle (0, 2) on the free left edge moved by -0.3 sigma along x (the
 * weft): its weft edge to (1, 2) is 1.3 sigma long (strain 0.3), its two
 * warp edges sqrt(1 + 0.09) sigma (strain 0.044). */
START_TEST(test_strain_located)
{
    tf_scene t;
    tf_build(&t, 0.5, 0.0);
    double *x = copy3n(t.L, t.L->xinit), *v = copy3n(t.L, NULL);
    int p = id_at(t.L, 0, 2), nb = id_at(t.L, 1, 2);
    ck_assert(!t.L->fixed[p]);
    x[3 * p] -= 0.3 * t.L->sigma;
    drape_diagnosis d;
    ck_assert_int_eq(drape_diagnose(t.m, 1.0, x, v, 0.2, 0.0, NULL, &d), 1);
    ck_assert_int_eq(d.kind, DRAPE_DIAG_STRAIN);
    ck_assert_str_eq(d.term, "stretch");
    ck_assert_close_rel(d.value, 0.3, 1e-9);
    ck_assert_close_rel(d.limit, 0.2, 1e-15);
    int a = d.particle, b = d.other;
    ck_assert((a == p && b == nb) || (a == nb && b == p));
    ck_assert_int_eq(d.j, 2);
    ck_assert_int_eq(d.oj, 2);
    ck_assert_int_eq(d.i + d.oi, 1); /* i = 0 and 1 */
    char buf[512];
    drape_diagnosis_format(&d, buf, sizeof buf);
    ck_assert_msg(strstr(buf, "strain 0.3 ") && strstr(buf, "(i 0, j 2)") &&
                      strstr(buf, "(i 1, j 2)") && strstr(buf, "limit 0.2"), "%s", buf);
    /* below the limit: nothing; limit 0: no strain check */
    ck_assert_int_eq(drape_diagnose(t.m, 1.0, x, v, 0.31, 0.0, NULL, &d), 0);
    ck_assert_int_eq(drape_diagnose(t.m, 1.0, x, v, 0.0, 0.0, NULL, &d), 0);
    free(x);
    free(v);
    tf_free(&t);
}
END_TEST

/* Kinetic energy given to one particle: 1/2 m s^2 against the limit
 * gain x scale (scale = M g L here, the start being flat and at rest). */
START_TEST(test_energy_blowup_located)
{
    tf_scene t;
    tf_build(&t, 0.5, 0.0);
    double *v = copy3n(t.L, NULL);
    drape_diag_ref ref;
    drape_diag_ref_init(t.m, t.L->xinit, v, &ref);
    int p = id_at(t.L, 3, 2);
    double scale = 0.2 * TF_SIDE * TF_SIDE * DRAPE_G_STANDARD * TF_SIDE;
    drape_diagnosis d;
    /* half the limit: fine */
    v[3 * p + 2] = sqrt(2.0 * 0.5 * scale / t.L->mass[p]);
    ck_assert_int_eq(drape_diagnose(t.m, 2.0, t.L->xinit, v, 0.2, 1.0, &ref, &d), 0);
    /* twice the limit: a blow-up in the kinetic term, at p */
    v[3 * p + 2] = sqrt(2.0 * 2.0 * scale / t.L->mass[p]);
    ck_assert_int_eq(drape_diagnose(t.m, 2.0, t.L->xinit, v, 0.2, 1.0, &ref, &d), 1);
    ck_assert_int_eq(d.kind, DRAPE_DIAG_ENERGY);
    ck_assert_str_eq(d.term, "kinetic");
    ck_assert_int_eq(d.particle, p);
    ck_assert_int_eq(d.i, 3);
    ck_assert_int_eq(d.j, 2);
    ck_assert_close_rel(d.value, 2.0 * scale, 1e-9);
    ck_assert_close_rel(d.limit, scale, 1e-9);
    /* no reference, or gain 0: no energy check */
    ck_assert_int_eq(drape_diagnose(t.m, 2.0, t.L->xinit, v, 0.2, 1.0, NULL, &d), 0);
    ck_assert_int_eq(drape_diagnose(t.m, 2.0, t.L->xinit, v, 0.2, 0.0, &ref, &d), 0);
    free(v);
    tf_free(&t);
}
END_TEST

/* ---- the driver ---------------------------------------------------------- */

typedef struct watch {
    drape_model *m;
    double worst_strain; /* largest strain of a state an observer saw */
    int n;
    double t[256];
    int stop_at;         /* raise *flag at this frame count (0 = never) */
    volatile sig_atomic_t *flag;
    int ends;
} watch;

static int on_event(void *ctx, const drape_sim_event *ev, drape_error *err)
{
    (void)err;
    watch *w = ctx;
    double s = drape_model_max_strain(w->m, ev->x);
    if (s > w->worst_strain) w->worst_strain = s;
    if (ev->what & DRAPE_SIM_AT_END) w->ends++;
    if (ev->what & DRAPE_SIM_AT_FRAME) {
        ck_assert(w->n < 256);
        w->t[w->n++] = ev->t;
        if (w->stop_at && w->n == w->stop_at) *w->flag = SIGINT;
    }
    return 0;
}

static void opts(drape_sim_opts *o, double t_max)
{
    drape_sim_opts_default(o);
    snprintf(o->integrator, sizeof o->integrator, "cvode-bdf");
    o->rtol = 1e-6;
    o->atol = 1e-9;
    o->t_max = t_max;
    o->frame_every = 0.02;
}

/* A strain limit below what the falling cloth reaches: the run fails with
 * a located diagnosis, and no observer ever saw a state above the limit;
 * the result holds the last good state. */
START_TEST(test_sim_stops_on_strain)
{
    tf_scene t;
    tf_build(&t, 0.5, 0.0);
    drape_sim_opts o;
    opts(&o, 0.3);
    o.strain_limit = 2e-4;
    watch w;
    memset(&w, 0, sizeof w);
    w.m = t.m;
    drape_sim_result r;
    drape_error err;
    drape_error_clear(&err);
    ck_assert_int_eq(drape_sim_run(t.m, &o, on_event, &w, &r, &err), -1);
    ck_assert_int_eq(r.status, DRAPE_SIM_FAILED);
    ck_assert_int_eq(err.kind, DRAPE_E_NUMERIC);
    ck_assert_int_eq(r.diagnosis.kind, DRAPE_DIAG_STRAIN);
    ck_assert_msg(strstr(err.msg, "cvode-bdf") && strstr(err.msg, "strain") &&
                      strstr(err.msg, "particle") && strstr(err.msg, "hint:"), "%s", err.msg);
    ck_assert_double_gt(r.diagnosis.value, 2e-4);
    ck_assert_int_ge(r.diagnosis.particle, 0);
    ck_assert_int_eq(w.ends, 0);
    ck_assert_msg(w.worst_strain <= 2e-4, "an observer saw strain %g", w.worst_strain);
    ck_assert_double_le(drape_model_max_strain(t.m, r.x), 2e-4);
    ck_assert_int_gt(w.n, 0);
    ck_assert_double_lt(w.t[w.n - 1], r.diagnosis.t);
    drape_sim_result_free(&r);
    tf_free(&t);
}
END_TEST

/* Stop flag raised at the 4th frame (t = 0.06 s): status interrupted there;
 * resuming from the result's state reaches the uninterrupted run's final
 * state within the tolerance and produces the remaining frames. */
START_TEST(test_sim_interrupt_and_resume)
{
    tf_scene t;
    tf_build(&t, 2.0, 0.0);
    const double t_max = 0.2;
    size_t n3 = 3 * (size_t)t.L->n;
    drape_sim_opts o;
    drape_error err;
    drape_sim_result ref, a, b;
    watch w0, wa, wb;
    memset(&w0, 0, sizeof w0);
    memset(&wa, 0, sizeof wa);
    memset(&wb, 0, sizeof wb);
    w0.m = wa.m = wb.m = t.m;
    drape_error_clear(&err);

    opts(&o, t_max);
    ck_assert_msg(drape_sim_run(t.m, &o, on_event, &w0, &ref, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(ref.status, DRAPE_SIM_T_MAX);

    volatile sig_atomic_t flag = 0;
    opts(&o, t_max);
    o.stop = &flag;
    wa.flag = &flag;
    wa.stop_at = 4;
    ck_assert_msg(drape_sim_run(t.m, &o, on_event, &wa, &a, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(a.status, DRAPE_SIM_INTERRUPTED);
    ck_assert_str_eq(drape_sim_status_name(a.status), "interrupted");
    ck_assert_close_rel(a.t_end_s, 0.06, 1e-12);
    ck_assert_int_eq(wa.n, 4);
    ck_assert_int_eq(wa.ends, 0);
    /* up to the interruption the very same computation */
    for (size_t k = 0; k < n3; k++) ck_assert(isfinite(a.x[k]));

    opts(&o, t_max);
    o.t0 = a.t_end_s;
    o.x0 = a.x;
    o.v0 = a.v;
    o.eq_below_since = a.eq_below_since;
    o.diag_ref = &a.diag_ref;
    ck_assert_msg(drape_sim_run(t.m, &o, on_event, &wb, &b, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(b.status, DRAPE_SIM_T_MAX);
    ck_assert_close_rel(b.t_end_s, t_max, 1e-12);
    ck_assert_int_eq(wb.ends, 1);
    /* frames: 0..0.06 before, 0.08..0.2 after: together the reference's */
    ck_assert_int_eq(wa.n + wb.n, w0.n);
    for (int k = 0; k < wb.n; k++) ck_assert_close_rel(wb.t[k], w0.t[wa.n + k], 1e-12);
    /* the final state: within a few times what rtol 1e-6, atol 1e-9 m
     * allow on a 10 cm cloth (the restart only changes step sizes) */
    double dmax = 0.0;
    for (size_t k = 0; k < n3; k++) dmax = fmax(dmax, fabs(b.x[k] - ref.x[k]));
    ck_assert_msg(dmax < 10.0 * (1e-6 * TF_SIDE + 1e-9), "resumed final state off by %g m", dmax);
    /* the control: the same resume without the velocities is far off, so
     * the comparison above can fail */
    drape_sim_result c;
    opts(&o, t_max);
    o.t0 = a.t_end_s;
    o.x0 = a.x;
    o.eq_below_since = a.eq_below_since;
    o.diag_ref = &a.diag_ref;
    ck_assert_msg(drape_sim_run(t.m, &o, NULL, NULL, &c, &err) == 0, "%s", err.msg);
    double dctl = 0.0;
    for (size_t k = 0; k < n3; k++) dctl = fmax(dctl, fabs(c.x[k] - ref.x[k]));
    ck_assert_msg(dctl > 100.0 * (1e-6 * TF_SIDE + 1e-9), "without velocities only %g m off", dctl);
    drape_sim_result_free(&c);
    drape_sim_result_free(&ref);
    drape_sim_result_free(&a);
    drape_sim_result_free(&b);
    tf_free(&t);
}
END_TEST

Suite *diagnose_suite(void)
{
    Suite *s = suite_create("diagnose");
    TCase *tc = tcase_create("diagnose");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_rest_state_is_clean);
    tcase_add_test(tc, test_nonfinite_located);
    tcase_add_test(tc, test_strain_located);
    tcase_add_test(tc, test_energy_blowup_located);
    tcase_add_test(tc, test_sim_stops_on_strain);
    tcase_add_test(tc, test_sim_interrupt_and_resume);
    suite_add_tcase(s, tc);
    return s;
}
