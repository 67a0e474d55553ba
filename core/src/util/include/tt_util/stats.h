/* tunetrace internal: the median of measurements, written once for the tuning session's
 * side-by-side verification, host --measure / --indicators and the benchmarks. Include as
 * <tt_util/stats.h> (tunetrace_util_dep; see rng.h). Header-only, thread-safe. */
#ifndef TT_UTIL_STATS_H
#define TT_UTIL_STATS_H

#include <math.h>
#include <stddef.h>
#include <stdlib.h>

/* qsort comparison of doubles, ascending (NaNs compare equal to everything). */
static inline int tt__cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

/* Median of `n` values, sorting `v` in place (the mean of the two middle ones for even n);
 * NaN for n = 0. */
static inline double tt__median(double *v, size_t n) {
  if (!n) return NAN;
  qsort(v, n, sizeof *v, tt__cmp_double);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

#endif /* TT_UTIL_STATS_H */
