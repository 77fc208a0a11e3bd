/* ensemble.c: statistics of repeated specimens (ensemble.h).
 *
 * Mean, sample standard deviation and the Student-t 95 % interval of the
 * mean:  ci95 = t_{0.975, n-1} s / sqrt(n)  (GSL's gsl_cdf_tdist_Pinv).
 *
 * Freeman-Halton exact test of a 2 x k table (Freeman & Halton 1951,
 * Biometrika 38:141; Fisher's exact test for k = 2).  With column totals
 * c_j, row totals n_a, n_b and N = n_a + n_b fixed, a table with first row
 * x has the multivariate hypergeometric probability
 *     P(x) = prod_j C(c_j, x_j) / C(N, n_a);
 * the p value sums P over every table with P <= P(observed) (a relative
 * slack of 1e-7 absorbs rounding, as R's fisher.test does).  The tables
 * are enumerated column by column.
 *
 * Welch's t test: t = (m_a - m_b) / sqrt(s_a^2/n_a + s_b^2/n_b) with the
 * Welch-Satterthwaite degrees of freedom, two-sided p from GSL's t
 * distribution.
 */
#include "drape/ensemble.h"

#include <math.h>

#include <gsl/gsl_cdf.h>
#include <gsl/gsl_sf_gamma.h>

void drape_ensemble_stats_compute(const double *dc, const int *nodes, int n,
                                  drape_ensemble_stats *s)
{
    double sum = 0.0;
    int m = 0;
    for (int k = 0; k <= DRAPE_ENSEMBLE_MAX_NODES; k++) s->hist[k] = 0;
    s->dc_min = INFINITY;
    s->dc_max = -INFINITY;
    for (int k = 0; k < n; k++) {
        if (!isfinite(dc[k]) || nodes[k] < 0) continue;
        sum += dc[k];
        m++;
        s->hist[nodes[k] > DRAPE_ENSEMBLE_MAX_NODES ? DRAPE_ENSEMBLE_MAX_NODES : nodes[k]]++;
        if (dc[k] < s->dc_min) s->dc_min = dc[k];
        if (dc[k] > s->dc_max) s->dc_max = dc[k];
    }
    s->n = m;
    s->dc_mean = m > 0 ? sum / m : NAN;
    s->dc_sd = s->dc_ci95 = NAN;
    if (m == 0) s->dc_min = s->dc_max = NAN;
    if (m >= 2) {
        double ss = 0.0;
        for (int k = 0; k < n; k++) {
            if (!isfinite(dc[k]) || nodes[k] < 0) continue;
            ss += (dc[k] - s->dc_mean) * (dc[k] - s->dc_mean);
        }
        s->dc_sd = sqrt(ss / (m - 1));
        s->dc_ci95 = drape_ensemble_t95(m - 1) * s->dc_sd / sqrt((double)m);
    }
    s->nodes_mode = -1;
    s->dc_mode = NAN;
    int best = 0;
    for (int k = 0; k <= DRAPE_ENSEMBLE_MAX_NODES; k++)
        if (s->hist[k] > best) { /* strict: the smaller count wins a tie */
            best = s->hist[k];
            s->nodes_mode = k;
        }
    if (s->nodes_mode >= 0) {
        double sm = 0.0;
        int c = 0;
        for (int k = 0; k < n; k++) {
            if (!isfinite(dc[k]) || nodes[k] < 0) continue;
            int b = nodes[k] > DRAPE_ENSEMBLE_MAX_NODES ? DRAPE_ENSEMBLE_MAX_NODES : nodes[k];
            if (b == s->nodes_mode) {
                sm += dc[k];
                c++;
            }
        }
        s->dc_mode = sm / c;
    }
}

double drape_ensemble_t95(int dof)
{
    if (dof < 1) return NAN;
    return gsl_cdf_tdist_Pinv(0.975, (double)dof);
}

/* The enumeration of first rows x with sum na, column by column. */
typedef struct exact_ctx {
    const int *col; /* column totals, occupied columns only */
    int k;
    double log_denom; /* ln C(N, n_a) */
    double log_p_obs;
    double p;         /* accumulated */
} exact_ctx;

static void enumerate(exact_ctx *c, int j, int left, int room, double log_num)
{
    /* room: sum of the column totals from j on (x_j can use at most those) */
    if (j == c->k) {
        if (left != 0) return;
        double lp = log_num - c->log_denom;
        if (lp <= c->log_p_obs + 1e-7) c->p += exp(lp);
        return;
    }
    int cj = c->col[j];
    int lo = left - (room - cj); /* the later columns cannot take more */
    if (lo < 0) lo = 0;
    int hi = left < cj ? left : cj;
    for (int x = lo; x <= hi; x++)
        enumerate(c, j + 1, left - x, room - cj, log_num + gsl_sf_lnchoose((unsigned)cj, (unsigned)x));
}

double drape_ensemble_exact_p(const int *a, const int *b, int k)
{
    int col[DRAPE_ENSEMBLE_MAX_NODES + 1], xa[DRAPE_ENSEMBLE_MAX_NODES + 1];
    int m = 0, na = 0, nb = 0;
    for (int j = 0; j < k && m <= DRAPE_ENSEMBLE_MAX_NODES; j++) {
        if (a[j] < 0 || b[j] < 0) return NAN;
        na += a[j];
        nb += b[j];
        if (a[j] + b[j] == 0) continue;
        col[m] = a[j] + b[j];
        xa[m] = a[j];
        m++;
    }
    if (na == 0 || nb == 0) return NAN;
    if (m < 2) return 1.0;
    exact_ctx c = {col, m, gsl_sf_lnchoose((unsigned)(na + nb), (unsigned)na), 0.0, 0.0};
    double lo = 0.0;
    for (int j = 0; j < m; j++) lo += gsl_sf_lnchoose((unsigned)col[j], (unsigned)xa[j]);
    c.log_p_obs = lo - c.log_denom;
    enumerate(&c, 0, na, na + nb, 0.0);
    return c.p > 1.0 ? 1.0 : c.p;
}

double drape_ensemble_welch_p(const drape_ensemble_stats *a,
                              const drape_ensemble_stats *b)
{
    if (a->n < 2 || b->n < 2) return NAN;
    double va = a->dc_sd * a->dc_sd / a->n, vb = b->dc_sd * b->dc_sd / b->n;
    if (!(va + vb > 0.0)) return NAN;
    double t = (a->dc_mean - b->dc_mean) / sqrt(va + vb);
    double dof = (va + vb) * (va + vb) /
                 (va * va / (a->n - 1) + vb * vb / (b->n - 1));
    return 2.0 * gsl_cdf_tdist_Q(fabs(t), dof);
}
