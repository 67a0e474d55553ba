/* tunetrace internal: the clocks of timings, written once for the library (the hybrid
 * loop's prediction time), the host (--indicators, --predict) and the benchmarks. Include
 * as <tt_util/clock.h> (tunetrace_util_dep; see rng.h). Header-only, thread-safe. */
#ifndef TT_UTIL_CLOCK_H
#define TT_UTIL_CLOCK_H

#include <time.h>

/* Milliseconds of `clk` (CLOCK_MONOTONIC, CLOCK_THREAD_CPUTIME_ID, ...). */
static inline double tt__clock_ms(clockid_t clk) {
  struct timespec ts;
  clock_gettime(clk, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* Wall-clock ms (monotonic): elapsed time, load included. */
static inline double tt__wall_ms(void) { return tt__clock_ms(CLOCK_MONOTONIC); }

/* CPU ms of the whole process (all threads): the figure that survives load best. */
static inline double tt__process_cpu_ms(void) { return tt__clock_ms(CLOCK_PROCESS_CPUTIME_ID); }

/* CPU ms of the calling thread: what one computation on this thread cost it. */
static inline double tt__thread_cpu_ms(void) { return tt__clock_ms(CLOCK_THREAD_CPUTIME_ID); }

#endif /* TT_UTIL_CLOCK_H */
