/* Helpers shared by the benchmark programs (suite bench): clocks and medians. */
#ifndef TT_BENCH_UTIL_H
#define TT_BENCH_UTIL_H

#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Wall clock in ms (monotonic). */
static inline double bench_wall_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* CPU time of the whole process (all threads) in ms: the figure that survives load. */
static inline double bench_cpu_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

static inline int bench_cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

/* Median of n <= 64 values (sorts a copy; v is left as it is). */
static inline double bench_median(const double *v, int n) {
  double t[64];
  if (n <= 0) return 0.0;
  if (n > 64) n = 64;
  memcpy(t, v, (size_t)n * sizeof *t);
  qsort(t, (size_t)n, sizeof *t, bench_cmp_double);
  return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}

#endif
