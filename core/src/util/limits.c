/* The limits of user-given numbers and their checking (tunetrace/limits.h): one table, so
 * the host's options and the Python API accept and refuse the same values, saying the same. */
#include <tunetrace/limits.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct tt__limit_row {
  const char *name; /* tt_limit_find */
  uint64_t lo, hi;  /* integers */
  double rlo, rhi;  /* reals: (rlo, rhi], or [rlo, rhi] when lo_closed */
  int real, lo_closed;
  const char *expected; /* reals: what the message says was expected */
} tt__limit_row;

static const tt__limit_row tt__limits[] = {
    [TT_LIMIT_SPP] = {"spp", 1, 1u << 24},
    [TT_LIMIT_WIDTH] = {"width", 1, 65536},
    [TT_LIMIT_HEIGHT] = {"height", 1, 65536},
    [TT_LIMIT_SEED] = {"seed", 0, UINT64_MAX},
    [TT_LIMIT_THREADS] = {"threads", 1, 1024},
    [TT_LIMIT_ITERATIONS] = {"iterations", 1, 1000000},
    [TT_LIMIT_TUNE_SPP] = {"tune_spp", 1, 1u << 16},
    [TT_LIMIT_EXPLORE] = {"explore", 1, 1000000},
    [TT_LIMIT_VERIFY] = {"verify", 1, 10000},
    [TT_LIMIT_ROUNDS] = {"rounds", 1, 10000},
    [TT_LIMIT_REFERENCE_SCALE] = {"reference_scale", 1, 16},
    [TT_LIMIT_CAMERA_INDEX] = {"camera_index", 0, 99},
    [TT_LIMIT_TIME] = {"time", 0, 0, 0, 1e7, 1, 0, "seconds > 0 (at most 1e7)"},
    [TT_LIMIT_FPS] = {"fps", 0, 0, 0, 1000, 1, 0, "frames per second in (0, 1000]"},
    [TT_LIMIT_EPSILON] = {"epsilon", 0, 0, 0, 1, 1, 1,
                          "the probability of exploring a state, a number in [0, 1]"},
    [TT_LIMIT_WARMUP] = {"warmup", 0, 1000},
    [TT_LIMIT_FRAME] = {"frame", 0, UINT32_MAX - 1},
};

#define TT__LIMITS (sizeof tt__limits / sizeof tt__limits[0])

/* The row of `which`, or NULL (and the error set). */
static const tt__limit_row *tt__limit(tt_limit which) {
  if ((unsigned)which < TT__LIMITS) return &tt__limits[which];
  tt_set_error(TT_ERR_INVALID_ARGUMENT, "unknown limit %d", (int)which);
  return NULL;
}

tt_status tt_limit_find(const char *name, tt_limit *out) {
  for (size_t k = 0; name && out && k < TT__LIMITS; k++)
    if (!strcmp(name, tt__limits[k].name)) {
      *out = (tt_limit)k;
      return TT_OK;
    }
  return tt_set_error(TT_ERR_INVALID_ARGUMENT, "unknown limit \"%s\"", name ? name : "");
}

tt_status tt_limit_range(tt_limit which, double *lo, double *hi) {
  const tt__limit_row *r = tt__limit(which);
  if (!r) return TT_ERR_INVALID_ARGUMENT;
  if (lo) *lo = r->real ? r->rlo : (double)r->lo;
  if (hi) *hi = r->real ? r->rhi : (double)r->hi;
  return TT_OK;
}

/* The unsigned decimal of the whole `text` in [lo, hi]; -1 when it is not that. */
static int tt__uint_in(const char *text, uint64_t lo, uint64_t hi, uint64_t *out) {
  if (!text || !(*text >= '0' && *text <= '9')) return -1;
  char *end = NULL;
  errno = 0;
  unsigned long long v = strtoull(text, &end, 10);
  if (errno || *end || v < lo || v > hi) return -1;
  *out = v;
  return 0;
}

tt_status tt_limit_parse_uint(tt_limit which, const char *text, uint64_t *out) {
  const tt__limit_row *r = tt__limit(which);
  if (!r) return TT_ERR_INVALID_ARGUMENT;
  if (r->real || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "limit %d is not an integer", (int)which);
  if (tt__uint_in(text, r->lo, r->hi, out) == 0) return TT_OK;
  return tt_set_error(TT_ERR_INVALID_ARGUMENT, "expected an integer in [%llu, %llu], got \"%s\"",
                      (unsigned long long)r->lo, (unsigned long long)r->hi, text ? text : "");
}

tt_status tt_limit_parse_real(tt_limit which, const char *text, double *out) {
  const tt__limit_row *r = tt__limit(which);
  if (!r) return TT_ERR_INVALID_ARGUMENT;
  if (!r->real || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "limit %d is not a real number", (int)which);
  char *end = NULL;
  double x = text && *text ? strtod(text, &end) : NAN;
  int in = end && !*end && (r->lo_closed ? x >= r->rlo : x > r->rlo) && x <= r->rhi;
  if (in) {
    *out = x;
    return TT_OK;
  }
  return tt_set_error(TT_ERR_INVALID_ARGUMENT, "expected %s, got \"%s\"", r->expected,
                      text ? text : "");
}

/* The two integers of "A:B" (first, second) within [lo, hi]; -1 when `text` is not that. */
static int tt__pair_in(const char *text, char sep, uint64_t lo, uint64_t hi, uint64_t *a,
                       uint64_t *b) {
  const char *mid = text ? strchr(text, sep) : NULL;
  char first[32];
  if (!mid || (size_t)(mid - text) >= sizeof first) return -1;
  snprintf(first, sizeof first, "%.*s", (int)(mid - text), text);
  return tt__uint_in(first, lo, hi, a) || tt__uint_in(mid + 1, lo, hi, b) ? -1 : 0;
}

tt_status tt_limit_parse_span(tt_limit which, const char *text, uint64_t *first, uint64_t *last) {
  const tt__limit_row *r = tt__limit(which);
  if (!r) return TT_ERR_INVALID_ARGUMENT;
  uint64_t a = 0, b = 0;
  if (!r->real && first && last && !tt__pair_in(text, ':', r->lo, r->hi, &a, &b) && a <= b) {
    *first = a;
    *last = b;
    return TT_OK;
  }
  return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                      "expected A:B with A <= B, each an integer in "
                      "[%llu, %llu], got \"%s\"",
                      (unsigned long long)r->lo, (unsigned long long)r->hi, text ? text : "");
}

tt_status tt_limit_parse_resolution(const char *text, uint32_t *width, uint32_t *height) {
  const tt__limit_row *w = &tt__limits[TT_LIMIT_WIDTH]; /* the same range as the height's */
  uint64_t wv = 0, hv = 0;
  if (!width || !height || tt__pair_in(text, 'x', w->lo, w->hi, &wv, &hv))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "expected WIDTHxHEIGHT (%llu..%llu each), got "
                        "\"%s\"",
                        (unsigned long long)w->lo, (unsigned long long)w->hi, text ? text : "");
  *width = (uint32_t)wv;
  *height = (uint32_t)hv;
  return TT_OK;
}
