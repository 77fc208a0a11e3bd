/* ensemble.h: statistics of repeated specimens (docs/model.md 6, "Repeated
 * specimens"; docs/ensemble.md).
 *
 * Where a scene has several stable rest states, one run's drape
 * coefficient and node count depend on its path, as they do on a real
 * drape meter.  A drape test is then N specimens that differ only in the
 * perturbation seed, and its result is their distribution:
 *
 *   mean DC        dc = (1/n) sum dc_k
 *   spread         dc_sd = sqrt( sum (dc_k - dc)^2 / (n - 1) )
 *   95 % interval  dc_ci95 = t_{0.975, n-1} dc_sd / sqrt(n)   (Student t)
 *   node count     nodes = the most frequent count (ties: the smaller),
 *                  dc_mode = mean DC of the specimens with that count
 *                  (Jeong 1998's standard value), and the histogram.
 *
 * Only specimens that produced a DC enter the statistics (n of them);
 * the caller counts the failed ones.  Two ensembles (a fast method against
 * an accurate one) are compared by their node histograms with the exact
 * test of Freeman and Halton (1951) (Fisher's exact test for a 2 x k
 * table) and by their means with Welch's t test.
 *
 * The DC distributions as a whole are compared by a two-sample
 * Kolmogorov-Smirnov test with permutation p values.
 *
 * Pure functions: no I/O; no allocation but the random number generators
 * of the permutation and Monte Carlo tests and the exact test's table of
 * bounds.
 */
#ifndef DRAPE_ENSEMBLE_H
#define DRAPE_ENSEMBLE_H

/* Node counts above this are counted in the last bin (a 30 cm specimen
 * shows at most about 12 folds). */
#define DRAPE_ENSEMBLE_MAX_NODES 32

typedef struct drape_ensemble_stats {
    int n;              /* specimens with a DC */
    double dc_mean;     /* NaN when n = 0 */
    double dc_sd;       /* sample standard deviation; NaN when n < 2 */
    double dc_ci95;     /* half-width of the 95 % interval of the mean;
                           NaN when n < 2 */
    double dc_min, dc_max;
    int nodes_mode;     /* most frequent node count (ties: the smaller);
                           -1 when n = 0 */
    double dc_mode;     /* mean DC of the specimens with nodes_mode */
    int hist[DRAPE_ENSEMBLE_MAX_NODES + 1]; /* hist[k]: specimens with k nodes */
} drape_ensemble_stats;

/* Statistics of n specimens (dc[k], nodes[k]; entries with a non-finite
 * dc or negative nodes are skipped).  Always fills *s. */
void drape_ensemble_stats_compute(const double *dc, const int *nodes, int n,
                                  drape_ensemble_stats *s);

/* t_{0.975, dof}: the two-sided 95 % quantile of Student's t (GSL); NaN
 * for dof < 1. */
double drape_ensemble_t95(int dof);

/* Exact test of two histograms a[0..k), b[0..k) (a 2 x k contingency
 * table, Freeman-Halton): the probability, under the hypothesis that both
 * samples come from one distribution (margins fixed), of a table no more
 * probable than the observed one.  Columns empty in both are ignored.
 * Returns a p value in [0, 1], 1 when fewer than two columns are
 * occupied, NaN when a sample is empty. */
double drape_ensemble_exact_p(const int *a, const int *b, int k);
/* Branches of the exact enumeration before drape_ensemble_exact_p falls
 * back to Monte Carlo (about a second), and the random tables it then
 * draws (seeded; the p value's standard error at p = 0.05 is about
 * 0.0015, as for the KS test's permutations). */
#define DRAPE_ENSEMBLE_EXACT_WORK 20000000L
#define DRAPE_ENSEMBLE_EXACT_DRAWS 20000

/* Welch's two-sample t test of the means (two-sided p value); NaN when
 * either sample has fewer than two members or both have zero spread. */
double drape_ensemble_welch_p(const drape_ensemble_stats *a,
                              const drape_ensemble_stats *b);

/* Half-width of the 95 % confidence interval of the difference of the
 * two means (Welch: t_{0.975, nu} sqrt(s_a^2/n_a + s_b^2/n_b), nu the
 * Welch-Satterthwaite degrees of freedom); |difference| <= it exactly when
 * drape_ensemble_welch_p >= 0.05.  NaN where welch_p is. */
double drape_ensemble_welch_ci95(const drape_ensemble_stats *a,
                                 const drape_ensemble_stats *b);

/* Largest sample for drape_ensemble_ks_p (each side). */
#define DRAPE_ENSEMBLE_KS_MAX 1000
/* Random splits of the pooled sample in drape_ensemble_ks_p. */
#define DRAPE_ENSEMBLE_KS_PERMUTATIONS 20000

/* DCs closer than this count as one value in the distribution test: one
 * rest state reached by different methods (a dynamic run stopped by its
 * speed criterion, a static minimum) has DCs within 3e-5 (measured on
 * cotton-poly-wang at 1 cm: 0.70937-0.70940), rest states differ by
 * 1e-3 and more. */
#define DRAPE_ENSEMBLE_DC_RES 1e-4

/* Two-sample Kolmogorov-Smirnov statistic of a[0..na) and b[0..nb): the
 * largest difference of their empirical distribution functions, evaluated
 * after every distinct value (ties handled); values of the pooled sample
 * that follow each other in sorted order within DRAPE_ENSEMBLE_DC_RES are
 * one value.  The inputs are not modified. */
double drape_ensemble_ks_d(const double *a, int na, const double *b, int nb);

/* Permutation p value of that statistic: the fraction of random splits of
 * the pooled sample into groups of na and nb (DRAPE_ENSEMBLE_KS_PERMUTATIONS
 * of them, GSL's MT19937 with a fixed seed: reproducible) whose D is at
 * least the observed one, (1 + count) / (1 + splits).  Exact under the
 * hypothesis of one distribution whatever the ties (a drape test's DCs
 * repeat where specimens end in one rest state), to the sampling error
 * of the splits (about 0.0015 at p = 0.05).  Compares the DC
 * distributions where the means (Welch) could agree by chance of shape.
 * NaN when a sample is empty or larger than DRAPE_ENSEMBLE_KS_MAX. */
double drape_ensemble_ks_p(const double *a, int na, const double *b, int nb);

#endif /* DRAPE_ENSEMBLE_H */
