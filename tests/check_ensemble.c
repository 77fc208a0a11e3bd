/* check_ensemble.c: the statistics of repeated specimens against
 * independent values: sums computed here, Student's t quantiles from a
 * printed table, Fisher's exact test against hand-counted hypergeometric
 * sums and published examples, Welch's test against its textbook example.
 */
#include <math.h>
#include <string.h>

#include "drape/ensemble.h"
#include "testutil.h"

START_TEST(test_stats_by_hand)
{
    const double dc[] = {0.80, 0.82, 0.85, 0.81, NAN, 0.83};
    const int nodes[] = {4, 3, 2, 4, 3, 3};
    drape_ensemble_stats s;
    drape_ensemble_stats_compute(dc, nodes, 6, &s);
    ck_assert_int_eq(s.n, 5); /* the NaN specimen is left out */
    double mean = (0.80 + 0.82 + 0.85 + 0.81 + 0.83) / 5.0;
    ck_assert_close_rel(s.dc_mean, mean, 1e-14);
    double ss = 0;
    const double v[] = {0.80, 0.82, 0.85, 0.81, 0.83};
    for (int k = 0; k < 5; k++) ss += (v[k] - mean) * (v[k] - mean);
    double sd = sqrt(ss / 4.0);
    ck_assert_close_rel(s.dc_sd, sd, 1e-12);
    /* t_{0.975, 4} = 2.776 (any printed t table) */
    ck_assert_close_rel(s.dc_ci95, 2.7764451 * sd / sqrt(5.0), 1e-6);
    ck_assert_int_eq(s.hist[2], 1);
    ck_assert_int_eq(s.hist[3], 2); /* 0.82, 0.83 (the third 3 had no DC) */
    ck_assert_int_eq(s.hist[4], 2);
    /* tie between 3 and 4 nodes: the smaller wins */
    ck_assert_int_eq(s.nodes_mode, 3);
    ck_assert_close_rel(s.dc_mode, (0.82 + 0.83) / 2.0, 1e-14);
    ck_assert_close_rel(s.dc_min, 0.80, 1e-15);
    ck_assert_close_rel(s.dc_max, 0.85, 1e-15);
}
END_TEST

START_TEST(test_stats_small)
{
    drape_ensemble_stats s;
    const double one[] = {0.7};
    const int n1[] = {5};
    drape_ensemble_stats_compute(one, n1, 1, &s);
    ck_assert_int_eq(s.n, 1);
    ck_assert_double_eq(s.dc_mean, 0.7);
    ck_assert(isnan(s.dc_sd) && isnan(s.dc_ci95));
    ck_assert_int_eq(s.nodes_mode, 5);
    drape_ensemble_stats_compute(one, n1, 0, &s);
    ck_assert_int_eq(s.n, 0);
    ck_assert(isnan(s.dc_mean));
    ck_assert_int_eq(s.nodes_mode, -1);
}
END_TEST

START_TEST(test_t95_table)
{
    /* two-sided 95 % points of Student's t, printed tables */
    ck_assert_close_rel(drape_ensemble_t95(1), 12.7062, 1e-5);
    ck_assert_close_rel(drape_ensemble_t95(9), 2.2622, 1e-4);
    ck_assert_close_rel(drape_ensemble_t95(15), 2.1314, 1e-4);
    ck_assert_close_rel(drape_ensemble_t95(30), 2.0423, 1e-4);
    ck_assert(isnan(drape_ensemble_t95(0)));
}
END_TEST

/* Hypergeometric probability of a 2 x 2 table with first row (a, b) and
 * columns (a + c, b + d), by factorials. */
static double hyper(int a, int b, int c, int d)
{
    return exp(lgamma(a + b + 1) + lgamma(c + d + 1) + lgamma(a + c + 1) + lgamma(b + d + 1) -
               lgamma(a + 1) - lgamma(b + 1) - lgamma(c + 1) - lgamma(d + 1) -
               lgamma(a + b + c + d + 1));
}

START_TEST(test_fisher_2x2)
{
    /* Fisher's tea-tasting table [[3, 1], [1, 3]]: two-sided p = 34/70 */
    int a[] = {3, 1}, b[] = {1, 3};
    ck_assert_close_rel(drape_ensemble_exact_p(a, b, 2), 34.0 / 70.0, 1e-10);
    /* [[1, 9], [11, 3]] (the textbook example): the tables no more
     * probable than it, summed by hand */
    int c[] = {1, 9}, d[] = {11, 3};
    double p0 = hyper(1, 9, 11, 3), p = 0;
    for (int x = 0; x <= 10; x++) { /* x = top-left count, row 1 = 10, col 1 = 12 */
        int y = 10 - x, z = 12 - x, w = 24 - 10 - z;
        if (y < 0 || z < 0 || w < 0) continue;
        double q = hyper(x, y, z, w);
        if (q <= p0 * (1 + 1e-7)) p += q;
    }
    ck_assert_close_rel(drape_ensemble_exact_p(c, d, 2), p, 1e-9);
    ck_assert_close_rel(p, 0.002759456, 1e-5);
}
END_TEST

START_TEST(test_freeman_halton)
{
    /* identical histograms: nothing is less probable than some, p = 1 up
     * to the tables as probable as it; p must be large */
    int a[] = {0, 0, 4, 4, 8}, b[] = {0, 0, 4, 4, 8};
    double p = drape_ensemble_exact_p(a, b, 5);
    ck_assert(p > 0.9 && p <= 1.0);
    /* disjoint histograms of 8 and 8: only the two extreme tables are as
     * improbable; p = 2 / C(16, 8) */
    int c[] = {8, 0}, d[] = {0, 8};
    ck_assert_close_rel(drape_ensemble_exact_p(c, d, 2), 2.0 / 12870.0, 1e-9);
    /* 2 x 3 by brute force over every first row with the margins */
    int e[] = {1, 6, 9}, f[] = {4, 3, 3};
    int col[3] = {5, 9, 12};
    double lp0 = 0, tot = 0, sum = 0;
    /* log P = sum ln C(c_j, x_j) - ln C(N, n_a) */
    double lden = lgamma(27) - lgamma(17) - lgamma(11);
    for (int j = 0; j < 3; j++) lp0 += lgamma(col[j] + 1) - lgamma(e[j] + 1) - lgamma(col[j] - e[j] + 1);
    lp0 -= lden;
    for (int x0 = 0; x0 <= 5; x0++)
        for (int x1 = 0; x1 <= 9; x1++) {
            int x2 = 16 - x0 - x1;
            if (x2 < 0 || x2 > 12) continue;
            int x[3] = {x0, x1, x2};
            double lp = -lden;
            for (int j = 0; j < 3; j++) lp += lgamma(col[j] + 1) - lgamma(x[j] + 1) - lgamma(col[j] - x[j] + 1);
            tot += exp(lp);
            if (lp <= lp0 + 1e-7) sum += exp(lp);
        }
    ck_assert_close_rel(tot, 1.0, 1e-10); /* the enumeration is complete */
    ck_assert_close_rel(drape_ensemble_exact_p(e, f, 3), sum, 1e-9);
    /* columns empty in both samples change nothing */
    int e2[] = {0, 1, 6, 0, 9}, f2[] = {0, 4, 3, 0, 3};
    ck_assert_close_rel(drape_ensemble_exact_p(e2, f2, 5), sum, 1e-12);
    int z[] = {0, 0};
    ck_assert(isnan(drape_ensemble_exact_p(z, d, 2)));
    int one_a[] = {0, 5}, one_b[] = {0, 3};
    ck_assert_double_eq(drape_ensemble_exact_p(one_a, one_b, 2), 1.0);
}
END_TEST

START_TEST(test_welch_example)
{
    /* Welch's t test, the worked example with unequal variances (the
     * textbook A1/A2 samples, n = 15 each): t = -2.46, nu = 24.9,
     * p = 0.021 */
    const double a1[] = {27.5, 21.0, 19.0, 23.6, 17.0, 17.9, 16.9, 20.1,
                         21.9, 22.6, 23.1, 19.6, 19.0, 21.7, 21.4};
    const double a2[] = {27.1, 22.0, 20.8, 23.4, 23.4, 23.5, 25.8, 22.0,
                         24.8, 20.2, 21.9, 22.1, 22.9, 20.5, 24.4};
    int nd[15];
    for (int k = 0; k < 15; k++) nd[k] = 0;
    drape_ensemble_stats s1, s2;
    drape_ensemble_stats_compute(a1, nd, 15, &s1);
    drape_ensemble_stats_compute(a2, nd, 15, &s2);
    double p = drape_ensemble_welch_p(&s1, &s2);
    ck_assert_msg(fabs(p - 0.021) < 0.0015, "p = %.17g", p);
    /* to more digits (mpmath's Student t at the Welch-Satterthwaite
     * nu = 24.9885, a review's computation): a wrong nu (pooled, n for
     * n - 1) moves p in the third digit and failed nothing above */
    ck_assert_msg(fabs(p - 0.0213780014629) < 1e-8 * 0.0213780014629, "p = %.17g", p);
    ck_assert_msg(fabs(drape_ensemble_welch_ci95(&s1, &s2) - 1.81742960047) < 1e-9,
                  "half-width %.17g", drape_ensemble_welch_ci95(&s1, &s2));
    ck_assert_close_rel(drape_ensemble_welch_p(&s2, &s1), p, 1e-12);
    /* the interval of the difference and the test agree: moving the second
     * sample until its mean lies exactly one half-width from the first
     * gives p = 0.05 (the spreads, hence the half-width, do not change) */
    double h = drape_ensemble_welch_ci95(&s1, &s2), a3[15];
    ck_assert(h > 0.0 && h < fabs(s2.dc_mean - s1.dc_mean)); /* p < 0.05 above */
    for (int k = 0; k < 15; k++) a3[k] = a2[k] - (s2.dc_mean - s1.dc_mean) + h;
    drape_ensemble_stats s3;
    drape_ensemble_stats_compute(a3, nd, 15, &s3);
    ck_assert_close_rel(drape_ensemble_welch_ci95(&s1, &s3), h, 1e-9);
    ck_assert_msg(fabs(drape_ensemble_welch_p(&s1, &s3) - 0.05) < 1e-9, "p = %.12g",
                  drape_ensemble_welch_p(&s1, &s3));
}
END_TEST

/* The Kolmogorov-Smirnov statistic by hand: a = {1, 2, 3}, b = {2, 4}:
 * after 1, 2, 3, 4 the distribution functions are 1/3, 2/3, 1, 1 and 0,
 * 1/2, 1/2, 1, so D = 1/2.  With ties, {1, 1, 2} against {1, 2, 2}: 2/3
 * against 1/3 after 1, both 1 after 2: D = 1/3. */
START_TEST(test_ks_d_by_hand)
{
    const double a[] = {3, 1, 2}, b[] = {4, 2};
    ck_assert_double_eq_tol(drape_ensemble_ks_d(a, 3, b, 2), 0.5, 1e-15);
    ck_assert_double_eq_tol(drape_ensemble_ks_d(b, 2, a, 3), 0.5, 1e-15);
    const double c[] = {1, 2, 1}, d[] = {2, 1, 2};
    ck_assert_double_eq_tol(drape_ensemble_ks_d(c, 3, d, 3), 1.0 / 3.0, 1e-15);
    ck_assert_double_eq_tol(drape_ensemble_ks_d(c, 3, c, 3), 0.0, 1e-15);
    ck_assert(isnan(drape_ensemble_ks_d(c, 0, d, 3)));
    /* values closer than DRAPE_ENSEMBLE_DC_RES are one: {0.70937, 0.70939}
     * against {0.70938, 0.70940} is D = 0, not 1/2 */
    const double e[] = {0.70937, 0.70939}, f[] = {0.70938, 0.70940};
    ck_assert_double_eq_tol(drape_ensemble_ks_d(e, 2, f, 2), 0.0, 1e-15);
    ck_assert_double_eq(drape_ensemble_ks_p(e, 2, f, 2), 1.0);
}
END_TEST

/* Exact permutation p value of D for two samples of five, by enumerating
 * all C(10, 5) = 252 splits (here, independently of the library's sampled
 * splits), against drape_ensemble_ks_p within four standard errors of its
 * 20000 splits; once with distinct values, once with ties. */
START_TEST(test_ks_p_exact)
{
    const double sets[2][10] = {{0.10, 0.35, 0.40, 0.80, 0.90, 0.50, 0.60, 0.70, 1.00, 1.20},
                                {1, 1, 1, 2, 3, 2, 2, 3, 3, 3}};
    for (int q = 0; q < 2; q++) {
        const double *v = sets[q];
        double d_obs = drape_ensemble_ks_d(v, 5, v + 5, 5);
        int hits = 0, total = 0;
        for (unsigned m = 0; m < 1024u; m++) {
            double a[10], b[10];
            int na = 0, nb = 0;
            for (int i = 0; i < 10; i++) {
                if (m & (1u << i)) a[na++] = v[i];
                else b[nb++] = v[i];
            }
            if (na != 5) continue;
            total++;
            if (drape_ensemble_ks_d(a, 5, b, 5) >= d_obs - 1e-12) hits++;
        }
        ck_assert_int_eq(total, 252);
        double p_exact = (double)hits / total;
        double p = drape_ensemble_ks_p(v, 5, v + 5, 5);
        double se = sqrt(p_exact * (1 - p_exact) / DRAPE_ENSEMBLE_KS_PERMUTATIONS);
        ck_assert_msg(p_exact > 0.01 && p_exact < 0.99, "set %d: exact p %g", q, p_exact);
        ck_assert_msg(fabs(p - p_exact) < 4 * se + 1e-4, "set %d: p %.5f, exact %.5f", q, p, p_exact);
    }
}
END_TEST

/* Limits: identical samples, p = 1; fully separated samples of 16, p =
 * 2 / C(32, 16) = 3.3e-9 exactly, so no sampled split reaches D = 1 and p
 * is the floor 1 / (1 + splits). */
START_TEST(test_ks_p_limits)
{
    double a[16], b[16];
    for (int k = 0; k < 16; k++) {
        a[k] = 0.80 + 0.001 * k;
        b[k] = 0.90 + 0.001 * k;
    }
    ck_assert_double_eq(drape_ensemble_ks_p(a, 16, a, 16), 1.0);
    ck_assert_double_eq_tol(drape_ensemble_ks_p(a, 16, b, 16),
                            1.0 / (1.0 + DRAPE_ENSEMBLE_KS_PERMUTATIONS), 1e-15);
    ck_assert(isnan(drape_ensemble_ks_p(a, 0, b, 16)));
}
END_TEST

/* Every first row x of a 2 x k table with column totals col and sum left,
 * from column j on: the sum of P over the tables no more probable than
 * lp0 (brute force, for test_freeman_halton_large). */
static double brute(const int *col, int k, int j, int left, double lp, double lden, double lp0)
{
    if (j == k) {
        if (left != 0) return 0.0;
        return lp - lden <= lp0 + 1e-7 ? exp(lp - lden) : 0.0;
    }
    double s = 0.0;
    for (int x = 0; x <= col[j] && x <= left; x++)
        s += brute(col, k, j + 1, left - x, lp + lgamma(col[j] + 1) - lgamma(x + 1) -
                   lgamma(col[j] - x + 1), lden, lp0);
    return s;
}

/* The exact test's bounds change nothing: a 2 x 6 table against every
 * table enumerated; large ensembles no longer take minutes (200 against
 * 200 over 7 node counts enumerated about 2e10 tables: this test timed
 * out); with all 33 bins occupied the answer is still that of the test. */
START_TEST(test_freeman_halton_large)
{
    int a[] = {3, 5, 7, 6, 4, 2}, b[] = {6, 4, 3, 5, 7, 5}, col[6];
    int na = 0, nb = 0;
    for (int j = 0; j < 6; j++) {
        col[j] = a[j] + b[j];
        na += a[j];
        nb += b[j];
    }
    double lden = lgamma(na + nb + 1) - lgamma(na + 1) - lgamma(nb + 1), lp0 = -lden;
    for (int j = 0; j < 6; j++)
        lp0 += lgamma(col[j] + 1) - lgamma(a[j] + 1) - lgamma(col[j] - a[j] + 1);
    double want = brute(col, 6, 0, na, 0.0, lden, lp0);
    ck_assert(want > 0.05 && want < 0.9);
    ck_assert_close_rel(drape_ensemble_exact_p(a, b, 6), want, 1e-9);
    /* identical histograms of 200: the observed table is the most probable */
    int c[] = {10, 30, 50, 50, 35, 20, 5};
    ck_assert_close_rel(drape_ensemble_exact_p(c, c, 7), 1.0, 1e-9);
    /* 33 occupied bins */
    int u[DRAPE_ENSEMBLE_MAX_NODES + 1], v[DRAPE_ENSEMBLE_MAX_NODES + 1];
    for (int j = 0; j <= DRAPE_ENSEMBLE_MAX_NODES; j++) {
        u[j] = 20;
        v[j] = j < 16 ? 38 : 2;
    }
    ck_assert_close_rel(drape_ensemble_exact_p(u, u, DRAPE_ENSEMBLE_MAX_NODES + 1), 1.0, 1e-9);
    ck_assert(drape_ensemble_exact_p(u, v, DRAPE_ENSEMBLE_MAX_NODES + 1) < 1e-3);
}
END_TEST

/* All DCs equal: the mean is that value and there is no spread (sum / n
 * rounds: 3 x 0.1 gave 0.10000000000000002 and an sd of 1e-17, and two
 * identical ensembles then differed at p = 5e-5 by Welch's test). */
START_TEST(test_stats_equal)
{
    double x[15];
    int nd[15] = {0};
    for (int k = 0; k < 15; k++) x[k] = k < 3 ? 0.1 : 0.675;
    drape_ensemble_stats s, t, u;
    drape_ensemble_stats_compute(x, nd, 3, &s);
    ck_assert(s.dc_mean == 0.1 && s.dc_sd == 0.0 && s.dc_ci95 == 0.0);
    drape_ensemble_stats_compute(x + 3, nd, 12, &t);
    drape_ensemble_stats_compute(x + 3, nd, 10, &u);
    ck_assert(t.dc_mean == 0.675 && t.dc_sd == 0.0);
    ck_assert(isnan(drape_ensemble_welch_p(&t, &u)));
}
END_TEST

/* Two samples of 100 DCs 5e-5 apart each, 0.005 apart as a whole, every
 * DC of the first below every DC of the second: D = 1 and the smallest p.
 * Values were grouped by a chain of neighbours within 1e-4 of each
 * other, which made each sample, then both, one value: D = 0, p = 1. */
START_TEST(test_ks_dense)
{
    double a[100], b[100];
    for (int k = 0; k < 100; k++) {
        a[k] = 0.70000 + 0.00005 * k;
        b[k] = 0.70500 + 0.00005 * k;
    }
    ck_assert_double_eq_tol(drape_ensemble_ks_d(a, 100, b, 100), 1.0, 1e-15);
    ck_assert_double_eq_tol(drape_ensemble_ks_p(a, 100, b, 100),
                            1.0 / (1.0 + DRAPE_ENSEMBLE_KS_PERMUTATIONS), 1e-15);
}
END_TEST

Suite *ensemble_suite(void)
{
    Suite *s = suite_create("ensemble");
    TCase *tc = tcase_create("stats");
    tcase_add_test(tc, test_stats_by_hand);
    tcase_add_test(tc, test_stats_small);
    tcase_add_test(tc, test_t95_table);
    tcase_add_test(tc, test_fisher_2x2);
    tcase_add_test(tc, test_freeman_halton);
    tcase_add_test(tc, test_welch_example);
    tcase_add_test(tc, test_ks_d_by_hand);
    tcase_add_test(tc, test_ks_p_exact);
    tcase_add_test(tc, test_ks_p_limits);
    tcase_add_test(tc, test_freeman_halton_large);
    tcase_add_test(tc, test_stats_equal);
    tcase_add_test(tc, test_ks_dense);
    suite_add_tcase(s, tc);
    return s;
}
