/*
 * fp_stats.h: the one median and percentile of the project (timings in `run`, `bench`, the
 * viewer's report, the CyberGlove plugin's latency statistics).
 *
 * Both functions sort the n doubles of v ascending in place (qsort; v must hold no NaN) and
 * return 0 when n is 0 (v may then be NULL). O(n log n), no allocation, reentrant,
 * [any-thread] on distinct arrays. Link: the static library `fp_common` (PIC).
 */
#ifndef FP_STATS_H
#define FP_STATS_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The median: the middle value for odd n, the mean of the two middle values for even n. */
double fp_median(double *v, size_t n);

/** The q-th quantile (0 < q <= 1) by nearest rank: the ceil(q n)-th smallest value
 *  (1-based, at least the first), so fp_percentile(v, 100, 0.99) is the 99th of 100. */
double fp_percentile(double *v, size_t n, double q);

#ifdef __cplusplus
}
#endif
#endif
