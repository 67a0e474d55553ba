/* tunetrace: the limits of the numbers a user gives (samples per pixel, resolution, seed,
 * iterations, ...), and one way to check them.
 *
 * The host's options and the Python API read every such number through these functions, so
 * both accept the same values and refuse the others with the same message: a value out of
 * range is refused, never wrapped or clamped (2^32 + 8 is not 8). Numbers are given as text
 * (decimal, as typed), so that a caller holding a wider integer than C's -- a Python int --
 * passes it exactly. Thread-safe, no allocation.
 */
#ifndef TUNETRACE_LIMITS_H
#define TUNETRACE_LIMITS_H

#include <tunetrace/common.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The numbers checked here; the host option and Python argument of each in parentheses. */
typedef enum tt_limit {
  TT_LIMIT_SPP = 0,              /* samples per pixel, 1..2^24 (--spp; render(spp)) */
  TT_LIMIT_WIDTH = 1,            /* image width, 1..65536 (--res; resolution) */
  TT_LIMIT_HEIGHT = 2,           /* image height, 1..65536 (--res; resolution) */
  TT_LIMIT_SEED = 3,             /* random seed, 0..2^64-1 (--seed; seed) */
  TT_LIMIT_THREADS = 4,          /* worker threads, 1..1024 (--threads; set_threads) */
  TT_LIMIT_ITERATIONS = 5,       /* tuner iterations, 1..10^6 (--iterations; tune) */
  TT_LIMIT_TUNE_SPP = 6,         /* spp of one measurement pass, 1..65536 (--tune-spp) */
  TT_LIMIT_EXPLORE = 7,          /* random configurations, 1..10^6 (--explore) */
  TT_LIMIT_VERIFY = 8,           /* verification rounds, 1..10000 (--verify; tune) */
  TT_LIMIT_ROUNDS = 9,           /* --measure rounds, 1..10000 (--rounds) */
  TT_LIMIT_REFERENCE_SCALE = 10, /* supersampling factor, 1..16 (--reference-scale) */
  TT_LIMIT_CAMERA_INDEX = 11,    /* camera path sample, 0..99 (--camera-index) */
  TT_LIMIT_TIME = 12,            /* time budget in seconds, (0, 10^7] (--time; time_budget) */
  TT_LIMIT_FPS = 13,             /* frames per second, (0, 1000] (--fps) */
  TT_LIMIT_EPSILON = 14,         /* probability of exploring a state, [0, 1] (--epsilon) */
  TT_LIMIT_WARMUP = 15,          /* warm-up passes before tuning, 0..1000 (tune) */
  TT_LIMIT_FRAME = 16            /* frame number, 0..2^32-2 (--sequence, --frames) */
} tt_limit;

/* The limit named `name` (the tt_limit name in lower case without the prefix: "spp",
 * "width", "tune_spp", "warmup", ...); TT_ERR_INVALID_ARGUMENT naming it when unknown. For
 * bindings that have the names, not the enum values. */
TT_API tt_status tt_limit_find(const char *name, tt_limit *out);

/* The range of `which`: [*lo, *hi] (for TIME and FPS the low end is excluded). For SEED the
 * high end 2^64-1 is not exact as a double. TT_ERR_INVALID_ARGUMENT for an unknown `which`. */
TT_API tt_status tt_limit_range(tt_limit which, double *lo, double *hi);

/* Reads `text` (decimal digits only: no sign, no spaces) as the integer `which` within its
 * range; otherwise TT_ERR_INVALID_ARGUMENT with "expected an integer in [LO, HI], got
 * \"TEXT\"" (the caller names the setting). */
TT_API tt_status tt_limit_parse_uint(tt_limit which, const char *text, uint64_t *out);

/* Reads `text` (the whole of it: a decimal or exponent number) as the real number `which`
 * within its range; otherwise TT_ERR_INVALID_ARGUMENT saying what was expected. */
TT_API tt_status tt_limit_parse_real(tt_limit which, const char *text, double *out);

/* Reads "A:B" (two integers of `which` with A <= B, e.g. frames A..B); otherwise
 * TT_ERR_INVALID_ARGUMENT with "expected A:B with A <= B, each an integer in [LO, HI], got
 * \"TEXT\"". */
TT_API tt_status tt_limit_parse_span(tt_limit which, const char *text, uint64_t *first,
                                     uint64_t *last);

/* Reads "WIDTHxHEIGHT" (each within TT_LIMIT_WIDTH / TT_LIMIT_HEIGHT); otherwise
 * TT_ERR_INVALID_ARGUMENT with "expected WIDTHxHEIGHT (1..65536 each), got \"TEXT\"". */
TT_API tt_status tt_limit_parse_resolution(const char *text, uint32_t *width, uint32_t *height);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_LIMITS_H */
