/* tunetrace: pinhole camera model shared by integrators and the host (motion vectors).
 * Right-handed world, camera looks from position to target, up is approximately `up`.
 * Film coordinates (fx, fy) are continuous pixels: (0,0) is the top-left corner of the
 * top-left pixel, pixel (x, y) covers [x, x+1) x [y, y+1). Thread-safe (pure functions). */
#ifndef TUNETRACE_CAMERA_H
#define TUNETRACE_CAMERA_H

#include <tunetrace/ray.h>
#include <tunetrace/scene.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Precomputed camera basis. */
typedef struct tt_camera_frame {
  float origin[3];
  float forward[3], right[3], up[3]; /* orthonormal */
  float tan_half_fov_y;
  float aspect; /* width / height */
  uint32_t width, height;
} tt_camera_frame;

/* Computes the basis of `camera`; TT_ERR_INVALID_ARGUMENT if position == target, up is
 * parallel to the view direction, fov is outside (0, 180) or the resolution is zero. */
TT_API tt_status tt_camera_frame_init(tt_camera_frame *frame, const tt_camera *camera);

/* Primary ray through film position (fx, fy); dir is normalised, tnear 0, tfar +inf. */
TT_API void tt_camera_generate_ray(const tt_camera_frame *frame, float fx, float fy, tt_ray *ray);

/* Projects world point p to film coordinates; returns 0 if p is behind the camera. `depth`
 * (may be NULL) receives the distance along the view axis. */
TT_API int tt_camera_project(const tt_camera_frame *frame, const float p[3], float *fx, float *fy,
                             float *depth);

/* ---- importance (bidirectional integrators: light tracing, BDPT, MLT) ----
 * The pinhole's importance W_e (pbrt-v3 PerspectiveCamera::We) is defined over the whole
 * film, normalised so that its integral of W_e cos(theta) over the directions the film sees
 * is 1: W_e = 1 / (A cos^4 theta), A = the film's area at distance 1 along forward. A pixel
 * of a film of N pixels is the measurement N * W_e restricted to it, so light-tracing
 * splats are scaled by 1 / (samples per pixel). */

/* W_e of the unit direction `dir` leaving the camera's origin, and the film position it
 * reaches in (*fx, *fy) (either may be NULL); 0 behind the camera or outside the film. */
TT_API float tt_camera_importance(const tt_camera_frame *frame, const float dir[3], float *fx,
                                  float *fy);

/* Solid-angle density of the directions tt_camera_generate_ray produces for film positions
 * uniform over the whole film: 1 / (A cos^3 theta); 0 behind the camera or outside the film. */
TT_API float tt_camera_pdf_dir(const tt_camera_frame *frame, const float dir[3]);

/* Area A of the film at distance 1 in front of the pinhole (4 tan^2(fov/2) aspect). */
TT_API float tt_camera_film_area(const tt_camera_frame *frame);

/* Halton(2,3) sub-pixel jitter, index in [0, 2^31): offset in [-0.5, 0.5)^2 (the first
 * point, index 0, uses Halton index 1 as Unreal and Bevy do). */
TT_API void tt_jitter_halton23(uint32_t index, float offset[2]);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_CAMERA_H */
