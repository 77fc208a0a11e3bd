/* check_animate.c: the animate method (issue 16, src/integrator_animate.c,
 * docs/animate.md) against independent expectations:
 *   - the total energy (kinetic + potential, computed here from the model
 *     at every output point) never rises, with and without damping, while
 *     the cloth falls and swings: no work is done on it;
 *   - first order: the error at t = 0.05 s against cvode-bdf at rtol 1e-10
 *     halves with the step;
 *   - the rest state of the cantilever (a unique minimum) is the static
 *     solver's certified minimum;
 *   - no allocation per step (drape's allocator counter), the step grid
 *     kept through off-grid output points, the command line's keys;
 *   - a step retried after a failed attempt is the step a fresh attempt
 *     from the same state computes (cholmod_l_solve2 interposed). */
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cholmod.h>

#include "drape/alloc.h"
#include "drape/drape.h"
#include "drape/equilibrium.h"
#include "drape/integrator.h"
#include "drape/sim.h"
#include "fixture.h"
#include "testutil.h"

/* ---- the energy balance ---------------------------------------------------- */

typedef struct ebal {
    drape_model *m;
    int n;
    double e0, prev, max_rise, drop, scale;
    const double *xinit;
} ebal;

static int ebal_observe(void *ctx, const drape_sim_event *ev, drape_error *err)
{
    (void)err;
    ebal *b = ctx;
    const drape_lattice *L = drape_model_lattice(b->m);
    drape_energies E;
    ck_assert_int_eq(drape_model_energy(b->m, ev->x, &E), 0);
    double ke = 0.0;
    for (int i = 0; i < L->n; i++)
        for (int c = 0; c < 3; c++) ke += 0.5 * L->mass[i] * ev->v[3 * i + c] * ev->v[3 * i + c];
    double e = ke + E.stretch + E.bend + E.shear + E.gravity;
    if (b->n == 0) {
        b->e0 = e;
        b->max_rise = -INFINITY;
    } else if (e - b->prev > b->max_rise) {
        b->max_rise = e - b->prev;
    }
    for (int i = 0; i < L->n; i++)
        b->drop = fmax(b->drop, b->xinit[3 * i + 2] - ev->x[3 * i + 2]);
    b->prev = e;
    b->n++;
    return 0;
}

/* The fixture's hang (6 x 6 at 2 cm, two corner pins) for 1.5 s at 30
 * frames per second and every output point between (observe_progress):
 * _i = 0 undamped, 1 with air drag and edge dashpots. */
START_TEST(test_energy_never_rises)
{
    tf_scene t;
    tf_build(&t, _i ? 0.5 : 0.0, _i ? 0.02 : 0.0);
    drape_sim_opts so;
    drape_sim_opts_default(&so);
    snprintf(so.integrator, sizeof so.integrator, "animate");
    so.t_max = 1.5;
    so.frame_every = 1.0 / 30.0;
    so.fixed_step = so.frame_every;
    so.observe_progress = 1;
    so.strain_limit = 0.0;
    ebal b = {t.m, 0, 0, 0, 0, 0, 0, t.L->xinit};
    b.scale = t.L->mass_total * 9.80665 * TF_SIDE; /* M g L */
    drape_sim_result r;
    drape_error err;
    drape_error_clear(&err);
    ck_assert_msg(drape_sim_run(t.m, &so, ebal_observe, &b, &r, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(r.status, DRAPE_SIM_T_MAX);
    ck_assert_int_eq(r.stats.steps, 45);
    ck_assert_int_eq(b.n, 46); /* start + 45 frames (the end is the last frame) */
    /* it fell and swung: several centimetres, energy spent */
    ck_assert_msg(b.drop > 0.03, "dropped only %g m", b.drop);
    ck_assert_msg(b.prev < b.e0 - 0.05 * b.scale, "E %g -> %g J, M g L %g J", b.e0, b.prev, b.scale);
    ck_assert_msg(b.max_rise <= 1e-12 * b.scale, "the energy rose by %g J (M g L %g J)",
                  b.max_rise, b.scale);
    ck_assert(r.max_strain < 0.01);
    drape_sim_result_free(&r);
    tf_free(&t);
}
END_TEST

/* ---- order ------------------------------------------------------------------- */

static double max_diff(const double *a, const double *b, int n3)
{
    double e = 0.0;
    for (int k = 0; k < n3; k++) e = fmax(e, fabs(a[k] - b[k]));
    return e;
}

/* The fixture's hang from rest to t = 0.05 s (it has dropped about 1 cm):
 * the error of animate against cvode-bdf at rtol 1e-10 halves with the
 * step (backward Euler, first order), and is small at the smallest. */
START_TEST(test_first_order)
{
    tf_scene t;
    tf_build(&t, 0.5, 0.02);
    const double T = 0.05;
    drape_sim_opts so;
    drape_sim_opts_default(&so);
    snprintf(so.integrator, sizeof so.integrator, "cvode-bdf");
    so.rtol = 1e-10;
    so.atol = 1e-13;
    so.max_order = 5;
    so.t_max = T;
    so.strain_limit = 0.0;
    drape_sim_result ref;
    drape_error err;
    drape_error_clear(&err);
    ck_assert_msg(drape_sim_run(t.m, &so, NULL, NULL, &ref, &err) == 0, "%s", err.msg);
    double drop = 0.0;
    for (int i = 0; i < t.L->n; i++) drop = fmax(drop, t.L->xinit[3 * i + 2] - ref.x[3 * i + 2]);
    ck_assert(drop > 0.008);
    double e[4];
    for (int q = 0; q < 4; q++) {
        drape_sim_opts ao;
        drape_sim_opts_default(&ao);
        snprintf(ao.integrator, sizeof ao.integrator, "animate");
        ao.t_max = T;
        ao.fixed_step = 0.0025 / (1 << q);
        ao.strain_limit = 0.0;
        drape_sim_result r;
        ck_assert_msg(drape_sim_run(t.m, &ao, NULL, NULL, &r, &err) == 0, "%s", err.msg);
        ck_assert_int_eq(r.stats.steps, 20 << q);
        e[q] = max_diff(r.x, ref.x, 3 * t.L->n);
        drape_sim_result_free(&r);
    }
    for (int q = 1; q < 4; q++)
        ck_assert_msg(e[q - 1] / e[q] > 1.6 && e[q - 1] / e[q] < 2.6,
                      "errors %.3g %.3g %.3g %.3g m at 2.5, 1.25, 0.63, 0.31 ms", e[0], e[1],
                      e[2], e[3]);
    ck_assert_msg(e[3] < 0.05 * drop, "error %.3g m, drop %.3g m", e[3], drop);
    drape_sim_result_free(&ref);
    tf_free(&t);
}
END_TEST

/* ---- the rest state -------------------------------------------------------------- */

/* The shipped cantilever (Peirce, 6 cm overhang at 2.5 mm, a unique
 * minimum) settles under animate, one step per 1/30 s, to the static
 * solver's certified minimum: the tip angle within 0.01 degree. */
START_TEST(test_cantilever_rest)
{
    drape_scene sc;
    drape_fabric fab;
    drape_error err;
    drape_error_clear(&err);
    ck_assert_msg(drape_scene_load(tu_src("scenes/cantilever.yaml"), &sc, &err, NULL, NULL) == 0,
                  "%s", err.msg);
    ck_assert_msg(drape_fabric_load(sc.fabric_path, &fab, &err, NULL, NULL) == 0, "%s", err.msg);
    drape_lattice *L = drape_lattice_new(&sc, &fab, &err);
    ck_assert_msg(L != NULL, "%s", err.msg);
    drape_model_opts mo;
    drape_model_opts_from_scene(&sc, &mo);
    drape_model *m = drape_model_new(L, &fab, &mo, &err);
    ck_assert_msg(m != NULL, "%s", err.msg);

    drape_equilibrium_opts eo;
    drape_equilibrium_opts_from_fabric(&eo, &fab);
    drape_equilibrium_result er;
    ck_assert_msg(drape_equilibrium_solve(m, L->xinit, &eo, &er, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(er.status, DRAPE_EQ_CONVERGED);
    ck_assert_int_eq(er.certified, 1);
    drape_cantilever ce, ca;
    ck_assert_msg(drape_cantilever_measure(L, er.x, fab.weight, 9.80665, &ce, &err) == 0, "%s",
                  err.msg);

    drape_sim_opts so;
    drape_sim_opts_from_scene(&sc, &so);
    snprintf(so.integrator, sizeof so.integrator, "animate");
    ck_assert_double_eq_tol(so.fixed_step, 1.0 / 30.0, 1e-15); /* the scene writes no frames */
    drape_sim_result r;
    ck_assert_msg(drape_sim_run(m, &so, NULL, NULL, &r, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(r.status, DRAPE_SIM_EQUILIBRIUM);
    ck_assert_msg(drape_cantilever_measure(L, r.x, fab.weight, 9.80665, &ca, &err) == 0, "%s",
                  err.msg);
    ck_assert_msg(fabs(ca.tip_angle_deg - ce.tip_angle_deg) < 0.01, "animate %.5f, static %.5f deg",
                  ca.tip_angle_deg, ce.tip_angle_deg);
    ck_assert(ce.tip_angle_deg > 30.0); /* it droops */
    drape_sim_result_free(&r);
    drape_equilibrium_result_free(&er);
    drape_model_free(m);
    drape_lattice_free(L);
}
END_TEST

/* ---- the integrator itself ------------------------------------------------------- */

/* Steps after the first few allocate nothing; an off-grid output point
 * splits its step and the grid continues (the frame at 2 h is reached in
 * the same number of steps as without it); a missing step is refused. */
START_TEST(test_steps_and_grid)
{
    tf_scene t;
    tf_build(&t, 0.5, 0.0);
    drape_integrator_opts o;
    drape_integrator_opts_default(&o);
    drape_error err;
    drape_error_clear(&err);
    ck_assert_ptr_null(drape_integrator_new(t.m, "animate", &o, &err));
    ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
    drape_error_clear(&err);
    const double h = 0.01;
    o.fixed_step = h;
    drape_integrator *I = drape_integrator_new(t.m, "animate", &o, &err);
    ck_assert_msg(I != NULL, "%s", err.msg);
    ck_assert_int_eq(drape_integrator_step_to(I, 2 * h, DRAPE_STEP_NORMAL, &err), 0);
    long a0 = drape_alloc_count();
    ck_assert_int_eq(drape_integrator_step_to(I, 2.5 * h, DRAPE_STEP_NORMAL, &err), 0);
    ck_assert_double_eq_tol(drape_integrator_time(I), 2.5 * h, 1e-15);
    ck_assert_int_eq(drape_integrator_step_to(I, 30 * h, DRAPE_STEP_NORMAL, &err), 0);
    ck_assert_double_eq_tol(drape_integrator_time(I), 30 * h, 1e-12);
    ck_assert_int_eq(drape_alloc_count(), a0); /* nothing allocated by 28 steps */
    drape_integrator_stats st;
    drape_integrator_get_stats(I, &st);
    ck_assert_int_eq(st.steps, 31); /* 30 on the grid, one split by 2.5 h */
    ck_assert(st.lin_factors >= 31);   /* at least one per step */
    ck_assert_int_eq(st.conv_fails, 0);
    ck_assert(st.energy_rescales >= 0);
    /* a resumed run restarts at its last output point, which may lie off
     * the grid (an equilibrium check at 30.5 h): the grid stays the run's
     * (t = k h), so 30.5 h -> 31 h -> 32 h is two steps, not three (a
     * grid moved to 30.5 h + k h splits every later frame's step) */
    size_t n3 = 3 * (size_t)t.L->n;
    double *x = malloc(sizeof(double) * n3), *v = malloc(sizeof(double) * n3);
    ck_assert(x && v);
    drape_integrator_state(I, x, v);
    ck_assert_int_eq(drape_integrator_reinit(I, 30.5 * h, x, v, &err), 0);
    ck_assert_int_eq(drape_integrator_step_to(I, 31 * h, DRAPE_STEP_NORMAL, &err), 0);
    ck_assert_int_eq(drape_integrator_step_to(I, 32 * h, DRAPE_STEP_NORMAL, &err), 0);
    drape_integrator_get_stats(I, &st);
    ck_assert_int_eq(st.steps, 2);
    free(x);
    free(v);
    drape_integrator_free(I);
    tf_free(&t);
}
END_TEST

/* ---- a failed attempt rolled back ------------------------------------------------ */

/* cholmod_l_solve2 interposed (the test binary's definition wins over
 * libcholmod's; it calls the library's unless told to fail): it counts
 * its calls from solve_calls = 0 and fails the ones numbered in
 * solve_fail (1-based; 0 = none).  A failed solve is one of the step
 * failures animate redoes as two half steps. */
static long solve_calls, solve_fail[2];

int cholmod_l_solve2(int sys, cholmod_factor *L, cholmod_dense *B, cholmod_sparse *Bset,
                     cholmod_dense **X, cholmod_sparse **Xset, cholmod_dense **Y,
                     cholmod_dense **E, cholmod_common *c)
{
    typedef int (*solve_fn)(int, cholmod_factor *, cholmod_dense *, cholmod_sparse *,
                            cholmod_dense **, cholmod_sparse **, cholmod_dense **,
                            cholmod_dense **, cholmod_common *);
    static solve_fn real;
    solve_calls++;
    if (solve_calls == solve_fail[0] || solve_calls == solve_fail[1]) return 0;
    if (!real) real = (solve_fn)dlsym(RTLD_NEXT, "cholmod_l_solve2");
    ck_assert_msg(real != NULL, "no cholmod_l_solve2 in the libraries");
    return real(sys, L, B, Bset, X, Xset, Y, E, c);
}

/* animate at step h on the fixture's hang (air drag), stepped to k h */
static drape_integrator *anim_at(tf_scene *t, double h, int k)
{
    drape_integrator_opts o;
    drape_integrator_opts_default(&o);
    o.fixed_step = h;
    drape_error err;
    drape_error_clear(&err);
    drape_integrator *I = drape_integrator_new(t->m, "animate", &o, &err);
    ck_assert_msg(I != NULL, "%s", err.msg);
    ck_assert_msg(drape_integrator_step_to(I, k * h, DRAPE_STEP_NORMAL, &err) == 0, "%s", err.msg);
    return I;
}

/* Step k + 1 of I with the solves numbered f1 and f2 from its start
 * failing; the solves of the step after f2 into *after.  No factorisation
 * may be refused (then the Levenberg-Marquardt shift, which is kept from
 * step to step, plays no part). */
static void step_failing(drape_integrator *I, double h, int k, long f1, long f2, long *after)
{
    drape_error err;
    drape_error_clear(&err);
    solve_calls = 0;
    solve_fail[0] = f1;
    solve_fail[1] = f2;
    ck_assert_msg(drape_integrator_step_to(I, (k + 1) * h, DRAPE_STEP_NORMAL, &err) == 0, "%s",
                  err.msg);
    solve_fail[0] = solve_fail[1] = 0;
    ck_assert_msg(solve_calls > f2, "%ld solves, the %ld-th was to fail", solve_calls, f2);
    *after = solve_calls - f2;
    drape_integrator_stats st;
    drape_integrator_get_stats(I, &st);
    ck_assert_int_eq(st.conv_fails, 2); /* as 1, 2 failed; as 4 steps it succeeded */
    ck_assert_int_eq(st.lin_setups, st.lin_factors);
}

/* A step whose attempt fails after some of its half steps succeeded is
 * rolled back whole: the retry (four quarter steps) starts its Newton
 * iterations from the velocity extrapolated from the last step taken,
 * not from the discarded half step.  Schedule: step k + 1 = 4 of h =
 * 10 ms (the cloth is falling, its velocity changing) fails as one step
 * (its first solve fails), then as two half steps, the first of which
 * succeeds (its N solves, counted by an off-grid output point at
 * (k + 1/2) h, a half step from the same state) and the second fails at
 * its first solve.  Independent expectation: the same step where the half
 * steps fail at once (solves 1 and 2), so that nothing but the state was
 * there to roll back: the same state after the step, bit for bit, and the
 * same number of solves in the retry (before: the retry extrapolated from
 * the half step, a zero acceleration, and differed). */
START_TEST(test_retry_rolls_back)
{
    tf_scene t;
    tf_build(&t, 0.5, 0.0);
    const double h = 0.01;
    const int k = 3;
    drape_error err;
    drape_error_clear(&err);
    /* N: the solves of the half step from the state at k h */
    drape_integrator *C = anim_at(&t, h, k);
    solve_calls = 0;
    ck_assert_int_eq(drape_integrator_step_to(C, (k + 0.5) * h, DRAPE_STEP_NORMAL, &err), 0);
    long N = solve_calls;
    ck_assert(N >= 1);
    drape_integrator_stats st;
    drape_integrator_get_stats(C, &st);
    ck_assert_int_eq(st.lin_setups, st.lin_factors);
    drape_integrator_free(C);

    long n_late, n_fresh;
    drape_integrator *I = anim_at(&t, h, k), *R = anim_at(&t, h, k);
    step_failing(I, h, k, 1, N + 2, &n_late);
    step_failing(R, h, k, 1, 2, &n_fresh);
    ck_assert_double_eq_tol(drape_integrator_time(I), (k + 1) * h, 1e-15);
    size_t n3 = 3 * (size_t)t.L->n;
    double *x = malloc(sizeof(double) * n3), *v = malloc(sizeof(double) * n3);
    double *xr = malloc(sizeof(double) * n3), *vr = malloc(sizeof(double) * n3);
    ck_assert(x && v && xr && vr);
    drape_integrator_state(I, x, v);
    drape_integrator_state(R, xr, vr);
    double dx = max_diff(x, xr, (int)n3), dv = max_diff(v, vr, (int)n3), vmax = 0.0;
    for (size_t i = 0; i < n3; i++) vmax = fmax(vmax, fabs(vr[i]));
    ck_assert(vmax > 0.05); /* falling: 9.8 m/s^2 over 40 ms */
    ck_assert_msg(dx == 0.0 && dv == 0.0, "retry after a half step: |dx| %.17g m, |dv| %.17g m/s "
                  "from the fresh retry's", dx, dv);
    ck_assert_int_eq(n_late, n_fresh);
    free(x);
    free(v);
    free(xr);
    free(vr);
    drape_integrator_free(I);
    drape_integrator_free(R);
    tf_free(&t);
}
END_TEST

/* ---- the command line -------------------------------------------------------- */

#define CAP 65536
static char out[CAP], err_text[CAP];

START_TEST(test_cli)
{
    ck_assert_int_eq(tu_run_drape("run -q ../scenes/hang.yaml --method animate --t-max 0.2s "
                                  "--spacing 2cm",
                                  out, CAP, err_text, CAP),
                     0);
    ck_assert_msg(strstr(out, "\"method\": \"animate\"") && strstr(out, "\"integrator\": \"animate\""),
                  "%s", out);
    ck_assert_msg(strstr(out, "\"step_s\": 0.03333333333") && strstr(out, "\"substeps\": 1,"), "%s", out);
    ck_assert_msg(strstr(out, "\"energy_max_rise_J\": ") && strstr(out, "\"energy_rescales\": "), "%s",
                  out);
    ck_assert_int_eq(tu_run_drape("run -q ../scenes/hang.yaml --method animate --t-max 0.2s "
                                  "--spacing 2cm --substeps 4",
                                  out, CAP, err_text, CAP),
                     0);
    ck_assert_msg(strstr(out, "\"step_s\": 0.008333333333") && strstr(out, "\"steps\": 24,"), "%s", out);
    ck_assert_int_eq(tu_run_drape("run ../scenes/hang.yaml --method animate --substeps 0", out, CAP,
                                  err_text, CAP),
                     2);
    ck_assert_ptr_nonnull(strstr(err_text, "--substeps"));
    /* the scene keys */
    char path[512];
    snprintf(path, sizeof path, "%s/anim.yaml", tu_scratch_dir());
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    char fabric[4096];
    ck_assert_ptr_nonnull(getcwd(fabric, sizeof fabric - 40)); /* tests/ */
    strcat(fabric, "/../fabrics/cotton-breen.yaml");
    fprintf(f, "scene: hang\nfabric: %s\nspecimen: {shape: rectangle, width: 10 cm, "
               "height: 10 cm}\nspacing: 2 cm\npins: [[0, -1], [-1, -1]]\n"
               "solver: {method: animate, substeps: 0}\nend: {t_max: 0.1 s}\n",
            fabric);
    fclose(f);
    char args[600];
    snprintf(args, sizeof args, "check %s", path);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err_text, CAP), 1);
    ck_assert_msg(strstr(err_text, "solver.substeps") != NULL, "%s", err_text);
    f = fopen(path, "r+");
    ck_assert_ptr_nonnull(f);
    char text[8192];
    size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = 0;
    fclose(f);
    char *p = strstr(text, "substeps: 0");
    ck_assert_ptr_nonnull(p);
    p[10] = '2'; /* substeps: 2 */
    f = fopen(path, "w");
    fputs(text, f);
    fclose(f);
    snprintf(args, sizeof args, "run -q %s", path);
    ck_assert_int_eq(tu_run_drape(args, out, CAP, err_text, CAP), 0);
    ck_assert_msg(strstr(out, "\"method\": \"animate\"") && strstr(out, "\"substeps\": 2,") &&
                      strstr(out, "\"step_s\": 0.01666666667"),
                  "%s", out);
}
END_TEST

Suite *animate_suite(void)
{
    Suite *s = suite_create("animate");
    TCase *tc = tcase_create("animate");
    tcase_set_timeout(tc, 60);
    tcase_add_loop_test(tc, test_energy_never_rises, 0, 2);
    tcase_add_test(tc, test_first_order);
    tcase_add_test(tc, test_cantilever_rest);
    tcase_add_test(tc, test_steps_and_grid);
    tcase_add_test(tc, test_retry_rolls_back);
    tcase_add_test(tc, test_cli);
    suite_add_tcase(s, tc);
    return s;
}
