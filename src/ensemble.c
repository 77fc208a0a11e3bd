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
 * are enumerated column by column with branch and bound (below); where
 * that would take too long (DRAPE_ENSEMBLE_EXACT_WORK branches) the same
 * p value is estimated from DRAPE_ENSEMBLE_EXACT_DRAWS random tables.
 *
 * Welch's t test: t = (m_a - m_b) / sqrt(s_a^2/n_a + s_b^2/n_b) with the
 * Welch-Satterthwaite degrees of freedom, two-sided p from GSL's t
 * distribution.
 *
 * Two-sample Kolmogorov-Smirnov test of the DC distributions by
 * permutation (Good, "Permutation, Parametric and Bootstrap Tests of
 * Hypotheses", 3rd ed. 2005, ch. 3): D = max |F_a - F_b| over the pooled
 * values; its p value is the fraction of random re-splits of the pooled
 * sample with a D at least as large.  The asymptotic Kolmogorov
 * distribution would be wrong here: the DCs of specimens in one rest state
 * repeat (ties), and samples are small.
 */
#include "drape/ensemble.h"

#include "drape/alloc.h"

#include <math.h>
#include <string.h>

#include <gsl/gsl_cdf.h>
#include <gsl/gsl_rng.h>
#include <gsl/gsl_sort.h>
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
    /* all equal: exactly that value, no spread (sum / m rounds: 3 x 0.1
     * gave 0.10000000000000002 and sd 1e-17, and Welch's test then called
     * two identical ensembles different) */
    if (m > 0 && s->dc_min == s->dc_max) s->dc_mean = s->dc_min;
    s->dc_sd = s->dc_ci95 = NAN;
    if (m == 0) s->dc_min = s->dc_max = NAN;
    if (m >= 2) {
        double ss = 0.0;
        for (int k = 0; k < n; k++) {
            if (!isfinite(dc[k]) || nodes[k] < 0) continue;
            ss += (dc[k] - s->dc_mean) * (dc[k] - s->dc_mean);
        }
        s->dc_sd = s->dc_min == s->dc_max ? 0.0 : sqrt(ss / (m - 1));
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

/* The enumeration of first rows x with sum na, column by column, with
 * two bounds (branch and bound): the partial product of the binomials
 * only grows (every ln C >= 0), so a branch whose partial probability is
 * already above the observed one holds no table that counts; and where
 * even the largest completion (maxrest, by dynamic programming) stays at
 * or below it, every table below counts and their sum is known in closed
 * form: sum over x_j.. of prod C(c_i, x_i) with sum `left` is C(room,
 * left) (Vandermonde).  Plain enumeration visited every table: 80 against
 * 80 specimens over 8 node counts took a minute, 200 against 200 about
 * twenty (a review's measurement).  work counts the branches visited; past
 * DRAPE_ENSEMBLE_EXACT_WORK the caller falls back to Monte Carlo. */
typedef struct exact_ctx {
    const int *col;   /* column totals, occupied columns only */
    int k, na;
    double log_denom; /* ln C(N, n_a) */
    double thr;       /* ln P(observed) + slack */
    const double *maxrest; /* [j * (na + 1) + l] */
    double p;         /* accumulated */
    long work;
} exact_ctx;

static int enumerate(exact_ctx *c, int j, int left, int room, double log_num)
{
    if (++c->work > DRAPE_ENSEMBLE_EXACT_WORK) return -1;
    if (log_num - c->log_denom > c->thr) return 0; /* every completion more probable */
    if (j == c->k) {
        if (left == 0) c->p += exp(log_num - c->log_denom);
        return 0;
    }
    if (log_num + c->maxrest[j * (c->na + 1) + left] - c->log_denom <= c->thr) {
        c->p += exp(log_num + gsl_sf_lnchoose((unsigned)room, (unsigned)left) - c->log_denom);
        return 0; /* every completion counts */
    }
    int cj = c->col[j];
    int lo = left - (room - cj); /* the later columns cannot take more */
    if (lo < 0) lo = 0;
    int hi = left < cj ? left : cj;
    for (int x = lo; x <= hi; x++)
        if (enumerate(c, j + 1, left - x, room - cj,
                      log_num + gsl_sf_lnchoose((unsigned)cj, (unsigned)x)) != 0)
            return -1;
    return 0;
}

/* Monte Carlo p value of the same test (seeded: the same answer every
 * time): random tables with the observed margins, drawn as the first na
 * of a random permutation of the N column labels, counted when no more
 * probable than the observed one; p = (1 + hits) / (1 + draws). */
static double exact_p_mc(const int *col, int m, int na, int nb, double thr)
{
    int n = na + nb, *lab = drape_malloc(sizeof(int) * (size_t)n);
    gsl_rng *r = gsl_rng_alloc(gsl_rng_mt19937);
    if (!lab || !r) {
        drape_free(lab);
        if (r) gsl_rng_free(r);
        return NAN;
    }
    gsl_rng_set(r, 15u);
    int q = 0;
    for (int j = 0; j < m; j++)
        for (int t = 0; t < col[j]; t++) lab[q++] = j;
    int hits = 0;
    for (int d = 0; d < DRAPE_ENSEMBLE_EXACT_DRAWS; d++) {
        int x[DRAPE_ENSEMBLE_MAX_NODES + 1] = {0};
        for (int i = 0; i < na; i++) { /* partial Fisher-Yates */
            int k = i + (int)gsl_rng_uniform_int(r, (unsigned long)(n - i));
            int t = lab[i];
            lab[i] = lab[k];
            lab[k] = t;
            x[lab[i]]++;
        }
        double lp = 0.0;
        for (int j = 0; j < m; j++) lp += gsl_sf_lnchoose((unsigned)col[j], (unsigned)x[j]);
        if (lp <= thr) hits++;
    }
    gsl_rng_free(r);
    drape_free(lab);
    return (1.0 + hits) / (1.0 + DRAPE_ENSEMBLE_EXACT_DRAWS);
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
    double log_denom = gsl_sf_lnchoose((unsigned)(na + nb), (unsigned)na), lo = 0.0;
    for (int j = 0; j < m; j++) lo += gsl_sf_lnchoose((unsigned)col[j], (unsigned)xa[j]);
    /* the slack: a relative 1e-7 in P, as R's fisher.test */
    double thr_num = lo + 1e-7;
    /* maxrest[j][l]: the largest sum of ln C(c_i, x_i) over i >= j with
     * sum l (-inf where no such x exists) */
    size_t w = (size_t)na + 1;
    double *mr = drape_malloc(sizeof(double) * (size_t)(m + 1) * w);
    if (!mr) return NAN;
    for (int l = 0; l <= na; l++) mr[(size_t)m * w + (size_t)l] = l == 0 ? 0.0 : -INFINITY;
    for (int j = m - 1; j >= 0; j--)
        for (int l = 0; l <= na; l++) {
            double best = -INFINITY;
            for (int x = 0; x <= col[j] && x <= l; x++) {
                double v = gsl_sf_lnchoose((unsigned)col[j], (unsigned)x) +
                           mr[(size_t)(j + 1) * w + (size_t)(l - x)];
                if (v > best) best = v;
            }
            mr[(size_t)j * w + (size_t)l] = best;
        }
    exact_ctx c = {col, m, na, log_denom, thr_num - log_denom, mr, 0.0, 0};
    int rc = enumerate(&c, 0, na, na + nb, 0.0);
    drape_free(mr);
    if (rc != 0) return exact_p_mc(col, m, na, nb, thr_num);
    return c.p > 1.0 ? 1.0 : c.p;
}

/* Welch: the standard error of the difference of the means and the
 * Welch-Satterthwaite degrees of freedom; -1 where undefined (fewer than
 * two members, or no spread on either side). */
static int welch(const drape_ensemble_stats *a, const drape_ensemble_stats *b, double *se,
                 double *dof)
{
    if (a->n < 2 || b->n < 2) return -1;
    double va = a->dc_sd * a->dc_sd / a->n, vb = b->dc_sd * b->dc_sd / b->n;
    if (!(va + vb > 0.0)) return -1;
    *se = sqrt(va + vb);
    *dof = (va + vb) * (va + vb) / (va * va / (a->n - 1) + vb * vb / (b->n - 1));
    return 0;
}

double drape_ensemble_welch_p(const drape_ensemble_stats *a,
                              const drape_ensemble_stats *b)
{
    double se, dof;
    if (welch(a, b, &se, &dof) != 0) return NAN;
    return 2.0 * gsl_cdf_tdist_Q(fabs(a->dc_mean - b->dc_mean) / se, dof);
}

double drape_ensemble_welch_ci95(const drape_ensemble_stats *a,
                                 const drape_ensemble_stats *b)
{
    double se, dof;
    if (welch(a, b, &se, &dof) != 0) return NAN;
    return gsl_cdf_tdist_Pinv(0.975, dof) * se;
}

/* D of two sorted samples. */
static double ks_sorted(const double *a, int na, const double *b, int nb)
{
    int i = 0, j = 0;
    double d = 0.0;
    while (i < na && j < nb) {
        double x = a[i] < b[j] ? a[i] : b[j];
        while (i < na && a[i] <= x) i++;
        while (j < nb && b[j] <= x) j++;
        double e = fabs((double)i / na - (double)j / nb);
        if (e > d) d = e;
    }
    return d; /* past here one function is 1 and the other rises to 1 */
}

/* The pooled sample a, b into pool[0..na+nb) with values grouped (in
 * sorted order, a group spans at most DRAPE_ENSEMBLE_DC_RES from its first
 * value) and replaced by the rank of their group.  Returns 0, or -1 for bad sizes. */
static int pool_ranks(const double *a, int na, const double *b, int nb, double *pool)
{
    if (na < 1 || nb < 1 || na > DRAPE_ENSEMBLE_KS_MAX || nb > DRAPE_ENSEMBLE_KS_MAX) return -1;
    int n = na + nb;
    double v[2 * DRAPE_ENSEMBLE_KS_MAX];
    size_t idx[2 * DRAPE_ENSEMBLE_KS_MAX];
    memcpy(v, a, sizeof(double) * (size_t)na);
    memcpy(v + na, b, sizeof(double) * (size_t)nb);
    gsl_sort_index(idx, v, 1, (size_t)n);
    /* a group is at most DRAPE_ENSEMBLE_DC_RES wide, from its first value:
     * chained neighbours (each within it of the next) made a dense sample
     * one value, and two samples of 100 DCs 0.005 apart, every one of the
     * first below every one of the second, got D = 0 and p = 1 */
    double rank = 0.0, start = 0.0;
    for (int k = 0; k < n; k++) {
        if (k == 0) start = v[idx[k]];
        else if (v[idx[k]] - start > DRAPE_ENSEMBLE_DC_RES) {
            rank += 1.0;
            start = v[idx[k]];
        }
        pool[idx[k]] = rank;
    }
    return 0;
}

/* D of the first na and the last nb entries of pool. */
static double ks_split(const double *pool, int na, int nb)
{
    double sa[DRAPE_ENSEMBLE_KS_MAX], sb[DRAPE_ENSEMBLE_KS_MAX];
    memcpy(sa, pool, sizeof(double) * (size_t)na);
    memcpy(sb, pool + na, sizeof(double) * (size_t)nb);
    gsl_sort(sa, 1, (size_t)na);
    gsl_sort(sb, 1, (size_t)nb);
    return ks_sorted(sa, na, sb, nb);
}

double drape_ensemble_ks_d(const double *a, int na, const double *b, int nb)
{
    double pool[2 * DRAPE_ENSEMBLE_KS_MAX];
    if (pool_ranks(a, na, b, nb, pool) != 0) return NAN;
    return ks_split(pool, na, nb);
}

double drape_ensemble_ks_p(const double *a, int na, const double *b, int nb)
{
    double pool[2 * DRAPE_ENSEMBLE_KS_MAX];
    if (pool_ranks(a, na, b, nb, pool) != 0) return NAN;
    double d_obs = ks_split(pool, na, nb);
    gsl_rng *r = gsl_rng_alloc(gsl_rng_mt19937);
    if (!r) return NAN;
    gsl_rng_set(r, 15u);
    int n = na + nb, hits = 0;
    for (int k = 0; k < DRAPE_ENSEMBLE_KS_PERMUTATIONS; k++) {
        /* a random split: the first na of a partial Fisher-Yates shuffle */
        for (int i = 0; i < na; i++) {
            int j = i + (int)gsl_rng_uniform_int(r, (unsigned long)(n - i));
            double t = pool[i];
            pool[i] = pool[j];
            pool[j] = t;
        }
        if (ks_split(pool, na, nb) >= d_obs * (1.0 - 1e-12)) hits++;
    }
    gsl_rng_free(r);
    return (1.0 + hits) / (1.0 + DRAPE_ENSEMBLE_KS_PERMUTATIONS);
}
