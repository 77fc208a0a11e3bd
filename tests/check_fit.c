/* check_fit.c: piecewise polynomial fits against independent evaluations:
 * integrals against composite Simpson quadrature, derivatives against
 * central differences, the mean against the average of two evaluations,
 * unit scaling against the polynomial evaluated in input units. */
#include <math.h>
#include <string.h>

#include "drape/fit.h"
#include "testutil.h"

/* Breen's warp bending fit for cotton, in 1/cm and gf.cm/cm (seed eq. 2). */
static drape_fit cotton_warp(void)
{
    drape_fit f;
    memset(&f, 0, sizeof f);
    f.n = 3;
    f.p[0] = (drape_fit_piece){0.0, 0.4, 3, {0, 0.85984849, -0.71212123}};
    f.p[1] = (drape_fit_piece){0.4, 2.52, 3, {0.11090909, 0.30530303, -0.018939394}};
    f.p[2] = (drape_fit_piece){2.52, INFINITY, 2, {0.23118183, 0.20984848}};
    drape_fit_prepare(&f);
    return f;
}

static double simpson(const drape_fit *f, double a, double b, int n)
{
    double h = (b - a) / n, s = drape_fit_value(f, a) + drape_fit_value(f, b);
    for (int i = 1; i < n; i++) s += (i % 2 ? 4 : 2) * drape_fit_value(f, a + i * h);
    return s * h / 3;
}

START_TEST(test_value_pieces)
{
    drape_fit f = cotton_warp();
    double K = 0.3;
    ck_assert_close_rel(drape_fit_value(&f, K), 0.85984849 * K - 0.71212123 * K * K, 1e-15);
    K = 1.7;
    ck_assert_close_rel(drape_fit_value(&f, K),
                        0.11090909 + 0.30530303 * K - 0.018939394 * K * K, 1e-15);
    K = 4.0;
    ck_assert_close_rel(drape_fit_value(&f, K), 0.23118183 + 0.20984848 * K, 1e-15);
    /* odd extension */
    ck_assert_close_rel(drape_fit_value(&f, -1.7), -drape_fit_value(&f, 1.7), 1e-15);
}
END_TEST

START_TEST(test_integral_vs_simpson)
{
    drape_fit f = cotton_warp();
    const double xs[] = {0.1, 0.4, 1.0, 2.52, 3.3, 7.0};
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++) {
        /* integrate piecewise-smooth y with Simpson split at the knots */
        double x = xs[i], w = 0.0, a = 0.0;
        const double knots[] = {0.4, 2.52};
        for (int k = 0; k < 2 && knots[k] < x; k++) {
            w += simpson(&f, a, knots[k], 2000);
            a = knots[k];
        }
        w += simpson(&f, a, x, 2000);
        ck_assert_close_rel(drape_fit_integral(&f, x), w, 1e-11);
        ck_assert_close_rel(drape_fit_integral(&f, -x), w, 1e-11); /* even */
    }
}
END_TEST

START_TEST(test_derivatives_vs_fd)
{
    drape_fit f = cotton_warp();
    const double xs[] = {0.05, 0.3, 1.0, 2.0, 5.0, -1.0};
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++) {
        double x = xs[i], h = 1e-5;
        double d1 = (drape_fit_value(&f, x + h) - drape_fit_value(&f, x - h)) / (2 * h);
        double d2 = (drape_fit_slope(&f, x + h) - drape_fit_slope(&f, x - h)) / (2 * h);
        ck_assert_close_abs(drape_fit_slope(&f, x), d1, 1e-8);
        ck_assert_close_abs(drape_fit_slope2(&f, x), d2, 1e-7);
    }
}
END_TEST

START_TEST(test_value_over_x)
{
    drape_fit f = cotton_warp();
    /* limit at 0 is the initial slope; elsewhere y/x */
    ck_assert_close_rel(drape_fit_value_over_x(&f, 0.0), 0.85984849, 1e-15);
    ck_assert_close_rel(drape_fit_value_over_x(&f, 1e-300), 0.85984849, 1e-15);
    const double xs[] = {1e-9, 0.2, 1.5, 4.0, -0.2};
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++)
        ck_assert_close_rel(drape_fit_value_over_x(&f, xs[i]),
                            drape_fit_value(&f, xs[i]) / xs[i], 1e-12);
}
END_TEST

START_TEST(test_scale)
{
    drape_fit f = cotton_warp(), g = cotton_warp();
    /* 1/cm -> 1/m (x100), gf.cm/cm -> N.m/m (x9.80665e-3) */
    drape_fit_scale(&g, 100.0, 9.80665e-3);
    const double Ks[] = {0.1, 0.45, 3.0};
    for (size_t i = 0; i < 3; i++) {
        double K = Ks[i];
        ck_assert_close_rel(drape_fit_value(&g, K * 100.0),
                            drape_fit_value(&f, K) * 9.80665e-3, 1e-13);
        /* W scales by x and y factors */
        ck_assert_close_rel(drape_fit_integral(&g, K * 100.0),
                            drape_fit_integral(&f, K) * 9.80665e-3 * 100.0, 1e-13);
    }
    ck_assert_close_rel(g.p[1].from, 40.0, 1e-15);
    ck_assert(isinf(g.p[2].to));
}
END_TEST

START_TEST(test_mean_and_jumps)
{
    drape_fit a = cotton_warp(), b, m;
    memset(&b, 0, sizeof b);
    b.n = 2; /* Breen weft fit, seed eq. 3 */
    b.p[0] = (drape_fit_piece){0.0, 0.5, 3, {0, 0.43128713, -0.30257426}};
    b.p[1] = (drape_fit_piece){0.5, INFINITY, 2, {0.075643564, 0.12871287}};
    drape_fit_prepare(&b);
    ck_assert_int_eq(drape_fit_mean(&a, &b, &m), 0);
    ck_assert_int_eq(m.n, 4); /* knots 0, 0.4, 0.5, 2.52 */
    const double xs[] = {0.2, 0.45, 1.0, 3.0};
    for (size_t i = 0; i < 4; i++) {
        ck_assert_close_rel(drape_fit_value(&m, xs[i]),
                            0.5 * (drape_fit_value(&a, xs[i]) + drape_fit_value(&b, xs[i])), 1e-14);
        ck_assert_close_rel(drape_fit_integral(&m, xs[i]),
                            0.5 * (drape_fit_integral(&a, xs[i]) + drape_fit_integral(&b, xs[i])), 1e-13);
    }
    /* Breen's weft fit is C0 at 0.5: value jump tiny; the slope jump is
     * |0.43128713 - 2*0.30257426*0.5 - 0.12871287| by hand. */
    double vj, sj;
    drape_fit_knot_jumps(&b, &vj, &sj);
    ck_assert_close_abs(vj, fabs(0.43128713 * 0.5 - 0.30257426 * 0.25
                                 - (0.075643564 + 0.12871287 * 0.5)), 1e-15);
    ck_assert_close_abs(sj, fabs(0.43128713 - 0.30257426 - 0.12871287), 1e-12);
    /* a fit with a real jump */
    b.p[1].c[0] += 0.01;
    drape_fit_knot_jumps(&b, &vj, &sj);
    ck_assert(vj > 0.0099);
}
END_TEST

Suite *fit_suite(void)
{
    Suite *s = suite_create("fit");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, test_value_pieces);
    tcase_add_test(tc, test_integral_vs_simpson);
    tcase_add_test(tc, test_derivatives_vs_fd);
    tcase_add_test(tc, test_value_over_x);
    tcase_add_test(tc, test_scale);
    tcase_add_test(tc, test_mean_and_jumps);
    suite_add_tcase(s, tc);
    return s;
}
