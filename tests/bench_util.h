/* Helpers shared by the benchmark programs (suite bench): clocks and medians, over the
 * library's shared ones (<tt_util/clock.h>, <tt_util/stats.h>; tunetrace_util_dep). */
#ifndef TT_BENCH_UTIL_H
#define TT_BENCH_UTIL_H

#include <string.h>

#include <tt_util/clock.h>
#include <tt_util/stats.h>

/* Wall clock in ms (monotonic). */
static inline double bench_wall_ms(void) { return tt__wall_ms(); }

/* CPU time of the whole process (all threads) in ms: the figure that survives load. */
static inline double bench_cpu_ms(void) { return tt__process_cpu_ms(); }

/* Median of n <= 64 values (sorts a copy; v is left as it is); 0 for n <= 0. */
static inline double bench_median(const double *v, int n) {
  double t[64];
  if (n <= 0) return 0.0;
  if (n > 64) n = 64;
  memcpy(t, v, (size_t)n * sizeof *t);
  return tt__median(t, (size_t)n);
}

#endif
