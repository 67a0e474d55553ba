/* The film: per-pixel weighted accumulators, an atomic splat buffer and AOV planes.
 *
 * Splats go to the single pixel (floor(fx), floor(fy)), with no reconstruction filter:
 * MLT-style integrators already deposit many splats per pixel, and a box footprint keeps
 * each splat a single atomic update. Splat accumulation is a compare-exchange loop on
 * _Atomic float, which is lock-free on every platform we build for and needs no libatomic.
 */
#include <tunetrace/film.h>

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* The splat buffer is handed out as float * (tt_film_splat_rgb), so the atomic type must be
 * a plain float in disguise. */
_Static_assert(sizeof(_Atomic float) == sizeof(float), "_Atomic float must be a bare float");
_Static_assert(_Alignof(_Atomic float) == _Alignof(float), "_Atomic float alignment");

#define TT__AOV_COUNT 5

struct tt_film {
  uint32_t width, height;
  uint32_t aov_mask;
  size_t pixels;             /* width * height */
  float *sum_rgb;            /* 3 per pixel: sum of w * L */
  float *sum_w;              /* 1 per pixel: sum of w */
  _Atomic float *splat;      /* 3 per pixel: sum of splatted L */
  float *aov[TT__AOV_COUNT]; /* indexed by bit position of tt_aov; NULL if absent */
  double splat_scale;
  _Atomic uint64_t dropped; /* non-finite or out-of-range samples and splats */
};

/* Bit position of a single-bit tt_aov value, or -1 if it is not exactly one known bit. */
static int tt__aov_index(tt_aov aov) {
  switch (aov) {
  case TT_AOV_DEPTH: return 0;
  case TT_AOV_NORMAL: return 1;
  case TT_AOV_ALBEDO: return 2;
  case TT_AOV_MOTION: return 3;
  case TT_AOV_PREV_DEPTH: return 4;
  }
  return -1;
}

/* Channels per pixel of an AOV; 0 for anything that is not a single known AOV bit. */
uint32_t tt_aov_channels(tt_aov aov) {
  switch (aov) {
  case TT_AOV_DEPTH: return 1;
  case TT_AOV_NORMAL: return 3;
  case TT_AOV_ALBEDO: return 3;
  case TT_AOV_MOTION: return 2;
  case TT_AOV_PREV_DEPTH: return 1;
  }
  return 0;
}

/* calloc of count * size floats with an overflow check (the product can exceed size_t for
 * absurd film sizes on 32-bit targets). */
static void *tt__calloc_floats(size_t count, size_t per_pixel) {
  if (per_pixel && count > SIZE_MAX / per_pixel / sizeof(float)) return NULL;
  return calloc(count * per_pixel, sizeof(float));
}

/* Allocates the film; all planes start zeroed, which is 0.0f for IEEE floats. */
tt_film *tt_film_create(uint32_t width, uint32_t height, uint32_t aov_mask) {
  const uint32_t known =
      TT_AOV_DEPTH | TT_AOV_NORMAL | TT_AOV_ALBEDO | TT_AOV_MOTION | TT_AOV_PREV_DEPTH;
  if (width == 0 || height == 0) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT, "film: size %ux%u is empty", width, height);
    return NULL;
  }
  if (aov_mask & ~known) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT, "film: unknown AOV bits 0x%x", aov_mask & ~known);
    return NULL;
  }
  tt_film *film = calloc(1, sizeof *film);
  if (!film) goto oom;
  film->width = width;
  film->height = height;
  film->aov_mask = aov_mask;
  film->pixels = (size_t)width * height;
  film->splat_scale = 1.0;
  atomic_init(&film->dropped, 0);
  film->sum_rgb = tt__calloc_floats(film->pixels, 3);
  film->sum_w = tt__calloc_floats(film->pixels, 1);
  film->splat = tt__calloc_floats(film->pixels, 3);
  if (!film->sum_rgb || !film->sum_w || !film->splat) goto oom;
  for (int i = 0; i < TT__AOV_COUNT; i++) {
    tt_aov aov = (tt_aov)(1u << i);
    if (!(aov_mask & (uint32_t)aov)) continue;
    film->aov[i] = tt__calloc_floats(film->pixels, tt_aov_channels(aov));
    if (!film->aov[i]) goto oom;
  }
  return film;
oom:
  tt_film_destroy(film);
  {
    /* the size asked for, so the user sees how far off the machine it is */
    size_t floats = 7; /* colour sums (3), weight sums (1), splats (3) */
    for (int i = 0; i < TT__AOV_COUNT; i++)
      if (aov_mask & (1u << i)) floats += tt_aov_channels((tt_aov)(1u << i));
    double bytes = (double)width * (double)height * (double)floats * sizeof(float);
    tt_set_error(TT_ERR_OUT_OF_MEMORY,
                 "film: cannot allocate a %ux%u film: %.0f bytes (%.1f "
                 "GiB, %zu floats per pixel) are not available",
                 width, height, bytes, bytes / (1024.0 * 1024.0 * 1024.0), floats);
  }
  return NULL;
}

/* Frees every plane; NULL is ignored. */
void tt_film_destroy(tt_film *film) {
  if (!film) return;
  free(film->sum_rgb);
  free(film->sum_w);
  free((void *)film->splat);
  for (int i = 0; i < TT__AOV_COUNT; i++) free(film->aov[i]);
  free(film);
}

/* Zeroes all planes; memset is fine for the atomics because no writer may run concurrently. */
void tt_film_clear(tt_film *film) {
  if (!film) return;
  memset(film->sum_rgb, 0, film->pixels * 3 * sizeof(float));
  memset(film->sum_w, 0, film->pixels * sizeof(float));
  memset((void *)film->splat, 0, film->pixels * 3 * sizeof(float));
  for (int i = 0; i < TT__AOV_COUNT; i++)
    if (film->aov[i])
      memset(film->aov[i], 0, film->pixels * tt_aov_channels((tt_aov)(1u << i)) * sizeof(float));
  film->splat_scale = 1.0;
  atomic_store_explicit(&film->dropped, 0, memory_order_relaxed);
}

/* Width in pixels. */
uint32_t tt_film_width(const tt_film *film) { return film ? film->width : 0; }
/* Height in pixels. */
uint32_t tt_film_height(const tt_film *film) { return film ? film->height : 0; }
/* AOV mask given at creation. */
uint32_t tt_film_aov_mask(const tt_film *film) { return film ? film->aov_mask : 0; }

/* Counts one dropped contribution; relaxed because only the total matters. */
static void tt__film_drop(tt_film *film) {
  atomic_fetch_add_explicit(&film->dropped, 1, memory_order_relaxed);
}

/* Pixel-parallel accumulation; out-of-range pixels are a caller bug but are dropped and
 * counted rather than corrupting memory. */
void tt_film_add_sample(tt_film *film, uint32_t x, uint32_t y, const float rgb[3], float weight) {
  if (!film || !rgb) return;
  if (x >= film->width || y >= film->height || !isfinite(weight) || !isfinite(rgb[0]) ||
      !isfinite(rgb[1]) || !isfinite(rgb[2])) {
    tt__film_drop(film);
    return;
  }
  size_t p = (size_t)y * film->width + x;
  film->sum_rgb[3 * p + 0] += weight * rgb[0];
  film->sum_rgb[3 * p + 1] += weight * rgb[1];
  film->sum_rgb[3 * p + 2] += weight * rgb[2];
  film->sum_w[p] += weight;
}

/* Atomic float add as a CAS loop: C11 atomic_fetch_add is not defined for floating types.
 * Relaxed order suffices: resolve runs after the writers are joined. */
static void tt__atomic_add_float(_Atomic float *dst, float v) {
  float old = atomic_load_explicit(dst, memory_order_relaxed);
  while (!atomic_compare_exchange_weak_explicit(dst, &old, old + v, memory_order_relaxed,
                                                memory_order_relaxed)) {}
}

/* Deposits rgb in pixel (floor(fx), floor(fy)); see the file comment for why no filter. */
void tt_film_splat(tt_film *film, float fx, float fy, const float rgb[3]) {
  if (!film || !rgb) return;
  /* The comparisons are false for NaN, so NaN positions are dropped too. */
  if (!(fx >= 0.0f && fx < (float)film->width && fy >= 0.0f && fy < (float)film->height) ||
      !isfinite(rgb[0]) || !isfinite(rgb[1]) || !isfinite(rgb[2])) {
    tt__film_drop(film);
    return;
  }
  uint32_t x = (uint32_t)fx, y = (uint32_t)fy; /* truncation == floor for fx >= 0 */
  /* Guard against float rounding of width near 2^24. */
  if (x >= film->width) x = film->width - 1;
  if (y >= film->height) y = film->height - 1;
  size_t p = (size_t)y * film->width + x;
  for (int c = 0; c < 3; c++)
    if (rgb[c] != 0.0f) tt__atomic_add_float(&film->splat[3 * p + c], rgb[c]);
}

/* Scale for the splat term, e.g. 1/spp or the MLT normalisation b/mutations. */
void tt_film_set_splat_scale(tt_film *film, double scale) {
  if (film) film->splat_scale = scale;
}

/* Scale for the splat term. */
double tt_film_splat_scale(const tt_film *film) { return film ? film->splat_scale : 0.0; }

/* Writable AOV plane or NULL. */
float *tt_film_aov(tt_film *film, tt_aov aov) {
  int i = tt__aov_index(aov);
  return film && i >= 0 ? film->aov[i] : NULL;
}

/* Read-only AOV plane or NULL. */
const float *tt_film_aov_const(const tt_film *film, tt_aov aov) {
  int i = tt__aov_index(aov);
  return film && i >= 0 ? film->aov[i] : NULL;
}

/* Raw sum of w * L. */
float *tt_film_sum_rgb(tt_film *film) { return film ? film->sum_rgb : NULL; }
/* Raw sum of w. */
float *tt_film_sum_weight(tt_film *film) { return film ? film->sum_w : NULL; }
/* Raw splat sums; same layout as float, see the static asserts above. */
float *tt_film_splat_rgb(tt_film *film) { return film ? (float *)film->splat : NULL; }

/* Dropped contributions since creation or clear. */
uint64_t tt_film_dropped(const tt_film *film) {
  /* atomic_load needs a non-const pointer in C11 (const was only allowed from C17). */
  return film ? atomic_load_explicit((_Atomic uint64_t *)&film->dropped, memory_order_relaxed) : 0;
}

/* rgb = sum_wL / sum_w + splat * scale, computed in double so the splat scale (often a
 * tiny 1/N) does not lose precision before the final rounding. */
void tt_film_resolve(const tt_film *film, float *rgb) {
  if (!film || !rgb) return;
  const double scale = film->splat_scale;
  for (size_t p = 0; p < film->pixels; p++) {
    const double w = film->sum_w[p];
    for (int c = 0; c < 3; c++) {
      float s =
          atomic_load_explicit((_Atomic float *)&film->splat[3 * p + c], memory_order_relaxed);
      const double mean = w != 0.0 ? film->sum_rgb[3 * p + c] / w : 0.0;
      rgb[3 * p + c] = (float)(mean + (double)s * scale);
    }
  }
}
