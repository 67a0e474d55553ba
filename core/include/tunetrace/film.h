/* tunetrace: the film, where integrators accumulate radiance.
 *
 * Two accumulators, as in pbrt: per-pixel weighted samples (sum of w*L and sum of w) for
 * pixel-parallel integrators, and a splat buffer (sum of L) scaled by a global factor for
 * MLT-style integrators that deposit contributions anywhere. The resolved image is
 *   rgb = sum_wL / sum_w + splat * splat_scale       (the first term is 0 where sum_w = 0).
 * Optional AOV planes (depth, normal, albedo, motion) hold first-hit values the integrator
 * writes per pixel (integrator_pt: the mean over the pixel's samples since the film was
 * cleared, like the colour). All planes are float, row-major, y = 0 at the top.
 */
#ifndef TUNETRACE_FILM_H
#define TUNETRACE_FILM_H

#include <tunetrace/common.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tt_film tt_film;

/* AOV planes, combinable as a bit mask at creation. */
typedef enum tt_aov {
  TT_AOV_DEPTH = 1 << 0,  /* 1 channel: camera-space distance along the view axis */
  TT_AOV_NORMAL = 1 << 1, /* 3 channels: world-space shading normal of the first hit */
  TT_AOV_ALBEDO = 1 << 2, /* 3 channels: reflectance of the first hit */
  TT_AOV_MOTION = 1 << 3, /* 2 channels: screen-space motion in pixels, current -> previous */
  /* appended (ABI 1.2) */
  TT_AOV_PREV_DEPTH = 1 << 4 /* 1 channel: the first hit's depth in the previous frame's camera
                                at its previous position (0: a miss, behind that camera) */
} tt_aov;

/* Creates a black film of width x height with the AOV planes in `aov_mask`. Free with
 * tt_film_destroy. NULL on bad size or out of memory (see tt_last_error). */
TT_API tt_film *tt_film_create(uint32_t width, uint32_t height, uint32_t aov_mask);
TT_API void tt_film_destroy(tt_film *film);
/* Resets every accumulator and AOV to zero and the splat scale to 1. */
TT_API void tt_film_clear(tt_film *film);

TT_API uint32_t tt_film_width(const tt_film *film);
TT_API uint32_t tt_film_height(const tt_film *film);
TT_API uint32_t tt_film_aov_mask(const tt_film *film);

/* Adds one weighted sample to pixel (x, y). Not thread-safe for the same pixel: callers
 * partition pixels among threads (tiles). Non-finite values are dropped and counted. */
TT_API void tt_film_add_sample(tt_film *film, uint32_t x, uint32_t y, const float rgb[3],
                               float weight);

/* Adds `rgb` to the splat buffer at continuous film position (fx, fy) in pixels. Thread-safe
 * (atomic adds). Positions outside the film and non-finite values are dropped (counted). */
TT_API void tt_film_splat(tt_film *film, float fx, float fy, const float rgb[3]);

/* Sets the factor applied to the splat buffer at resolve time. */
TT_API void tt_film_set_splat_scale(tt_film *film, double scale);
TT_API double tt_film_splat_scale(const tt_film *film);

/* Writable AOV plane (one of tt_aov), NULL if the film has none. Layout: channels
 * interleaved per pixel (1, 3, 3 or 2 channels). */
TT_API float *tt_film_aov(tt_film *film, tt_aov aov);
TT_API const float *tt_film_aov_const(const tt_film *film, tt_aov aov);
/* Number of channels of an AOV. */
TT_API uint32_t tt_aov_channels(tt_aov aov);

/* Raw accumulators: sum of w*L (3 per pixel), sum of w (1 per pixel), splats (3 per pixel). */
TT_API float *tt_film_sum_rgb(tt_film *film);
TT_API float *tt_film_sum_weight(tt_film *film);
TT_API float *tt_film_splat_rgb(tt_film *film);

/* Number of non-finite samples or splats dropped since creation/clear. Thread-safe. */
TT_API uint64_t tt_film_dropped(const tt_film *film);

/* Resolves into `rgb` (3 * width * height floats, caller-owned). Thread-safe with respect
 * to other readers; not with concurrent writers. */
TT_API void tt_film_resolve(const tt_film *film, float *rgb);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_FILM_H */
