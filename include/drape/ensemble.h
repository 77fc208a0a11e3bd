/* ensemble.h: statistics of repeated specimens (MODEL.md 6, "Repeated
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
 * Pure functions: no allocation, no I/O.
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

/* Welch's two-sample t test of the means (two-sided p value); NaN when
 * either sample has fewer than two members or both have zero spread. */
double drape_ensemble_welch_p(const drape_ensemble_stats *a,
                              const drape_ensemble_stats *b);

#endif /* DRAPE_ENSEMBLE_H */
