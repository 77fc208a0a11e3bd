/* check_perturbation.c: the smooth random height field of docs/model.md section 2
 * (perturbation.h), against its defining statistics:
 * - over seeds, phi = h / A has mean 0 and mean square 1 at any point;
 * - its mean squared slope is A^2 4 pi^2 / (lambda_min lambda_max) (P2);
 * - a field of one wavelength lambda solves Helmholtz's equation
 *   lap h = -(2 pi / lambda)^2 h (finite differences);
 * - the same seed draws the same field; bad arguments are refused.
 * Statistical checks allow 5 standard errors, estimated from the sample. */
#include <check.h>
#include <math.h>
#include <stdlib.h>

#include "drape/perturbation.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define SEEDS 20000

/* mean and standard error of the mean of v[0..n) */
static void mean_se(const double *v, int n, double *mean, double *se)
{
    double s = 0.0, s2 = 0.0;
    for (int k = 0; k < n; k++) s += v[k];
    *mean = s / n;
    for (int k = 0; k < n; k++) s2 += (v[k] - *mean) * (v[k] - *mean);
    *se = sqrt(s2 / (n - 1) / n);
}

START_TEST(test_field_moments)
{
    static drape_field f;
    const double A = 1e-4, lo = 0.02, hi = 0.30, px = 0.031, py = -0.047, d = 1e-6;
    double *h = malloc(sizeof(double) * SEEDS), *h2 = malloc(sizeof(double) * SEEDS);
    double *g2 = malloc(sizeof(double) * SEEDS);
    for (int s = 0; s < SEEDS; s++) {
        ck_assert_int_eq(drape_field_draw(&f, (uint64_t)s + 1, DRAPE_FIELD_MODES, lo, hi, A), 0);
        double z = drape_field_height(&f, px, py) / A;
        double gx = (drape_field_height(&f, px + d, py) - drape_field_height(&f, px - d, py)) / (2 * d);
        double gy = (drape_field_height(&f, px, py + d) - drape_field_height(&f, px, py - d)) / (2 * d);
        h[s] = z;
        h2[s] = z * z;
        g2[s] = (gx * gx + gy * gy) / (A * A);
    }
    double m, se;
    mean_se(h, SEEDS, &m, &se);
    ck_assert_msg(fabs(m) < 5 * se, "mean %.17g (se %g)", m, se);
    mean_se(h2, SEEDS, &m, &se);
    ck_assert_msg(fabs(m - 1.0) < 5 * se, "mean square %.17g, expected 1 (se %g)", m, se);
    double slope = 4 * M_PI * M_PI / (lo * hi); /* (P2) */
    mean_se(g2, SEEDS, &m, &se);
    ck_assert_msg(fabs(m - slope) < 5 * se, "mean squared slope %.17g, expected %.17g (se %g)",
                  m, slope, se);
    /* and a band twice as short has twice the mean squared slope */
    for (int s = 0; s < SEEDS; s++) {
        ck_assert_int_eq(drape_field_draw(&f, (uint64_t)s + 1, DRAPE_FIELD_MODES, lo, hi / 2, A), 0);
        double gx = (drape_field_height(&f, px + d, py) - drape_field_height(&f, px - d, py)) / (2 * d);
        double gy = (drape_field_height(&f, px, py + d) - drape_field_height(&f, px, py - d)) / (2 * d);
        g2[s] = (gx * gx + gy * gy) / (A * A);
    }
    mean_se(g2, SEEDS, &m, &se);
    ck_assert_msg(fabs(m - 2 * slope) < 5 * se, "mean squared slope %.17g, expected %.17g",
                  m, 2 * slope);
    free(h);
    free(h2);
    free(g2);
}
END_TEST

START_TEST(test_field_one_wavelength)
{
    static drape_field f;
    const double A = 2e-4, lambda = 0.05, q = 2 * M_PI / lambda, d = 1e-4;
    ck_assert_int_eq(drape_field_draw(&f, 7, 64, lambda, lambda, A), 0);
    double worst = 0.0;
    for (int k = 0; k < 50; k++) {
        double x = -0.15 + 0.3 * k / 49.0, y = 0.1 * sin(3.0 * k);
        double h = drape_field_height(&f, x, y);
        double lap = (drape_field_height(&f, x + d, y) + drape_field_height(&f, x - d, y) +
                      drape_field_height(&f, x, y + d) + drape_field_height(&f, x, y - d) -
                      4 * h) / (d * d);
        worst = fmax(worst, fabs(lap + q * q * h));
    }
    /* bound of |h|: A sqrt(2 M); the difference quotient errs by about
     * q^4 d^2 / 12 of it */
    double tol = 1e-3 * q * q * A * sqrt(128.0);
    ck_assert_msg(worst < tol, "Helmholtz residual %g (tolerance %g)", worst, tol);
}
END_TEST

START_TEST(test_field_reproducible_and_refusals)
{
    static drape_field a, b, c;
    ck_assert_int_eq(drape_field_draw(&a, 12, 64, 0.02, 0.3, 1e-4), 0);
    ck_assert_int_eq(drape_field_draw(&b, 12, 64, 0.02, 0.3, 1e-4), 0);
    ck_assert_int_eq(drape_field_draw(&c, 13, 64, 0.02, 0.3, 1e-4), 0);
    int differ = 0;
    for (int k = 0; k < 20; k++) {
        double x = 0.01 * k - 0.1, y = 0.007 * k;
        ck_assert(drape_field_height(&a, x, y) == drape_field_height(&b, x, y));
        differ += drape_field_height(&a, x, y) != drape_field_height(&c, x, y);
    }
    ck_assert_int_eq(differ, 20);
    /* amplitude scales the field */
    ck_assert_int_eq(drape_field_draw(&b, 12, 64, 0.02, 0.3, 3e-4), 0);
    ck_assert(fabs(drape_field_height(&b, 0.05, 0.02) - 3 * drape_field_height(&a, 0.05, 0.02)) <
              1e-15);
    ck_assert_int_eq(drape_field_draw(&b, 1, 0, 0.02, 0.3, 1e-4), -1);
    ck_assert_int_eq(drape_field_draw(&b, 1, DRAPE_FIELD_MODES_MAX + 1, 0.02, 0.3, 1e-4), -1);
    ck_assert_int_eq(drape_field_draw(&b, 1, 64, 0.0, 0.3, 1e-4), -1);
    ck_assert_int_eq(drape_field_draw(&b, 1, 64, 0.04, 0.03, 1e-4), -1);
    ck_assert_int_eq(drape_field_draw(&b, 1, 64, 0.02, INFINITY, 1e-4), -1);
    ck_assert_int_eq(drape_field_draw(&b, 1, 64, 0.02, 0.3, -1e-4), -1);
    ck_assert_int_eq(drape_field_draw(&b, 1, 64, 0.02, 0.3, NAN), -1);
}
END_TEST

Suite *perturbation_suite(void); /* found by the runner */
Suite *perturbation_suite(void)
{
    Suite *s = suite_create("perturbation");
    TCase *tc = tcase_create("field");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_field_moments);
    tcase_add_test(tc, test_field_one_wavelength);
    tcase_add_test(tc, test_field_reproducible_and_refusals);
    suite_add_tcase(s, tc);
    return s;
}
