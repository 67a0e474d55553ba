/* tunetrace: the path sampler shared by every integrator (thesis 2.5.4, 4.4).
 *
 * tt_path_trace builds one path from a camera ray, drawing every random decision from a
 * tt_sample_source dimension by dimension, with a fixed layout so that one decision never
 * shifts another's dimension (pbrt-v4 interleaves streams for the same reason):
 *
 *   dims 0-1  film position (the caller's; a path tracer maps them to sub-pixel jitter,
 *             PSSMLT to the whole film)
 *   dims 2-3  lens (reserved)
 *   then per bounce b (b = 0 is the first surface hit), at 4 + TT_PATH_DIMS_PER_BOUNCE*b:
 *     +0 light selection, +1..2 point on the light, +3 BSDF lobe choice,
 *     +4..5 BSDF direction, +6 Russian roulette, +7 reserved.
 *
 * A source may report, for every BSDF-direction dimension pair, the solid-angle pdf of the
 * direction it produced (0 for a delta lobe): PSSMLT's sigma-binning (thesis 4.4) picks
 * each dimension's mutation size from it. The same path construction therefore drives the
 * path tracer (sampler = independent/Halton/Sobol) and PSSMLT (sampler = the chain's
 * primary-sample vector).
 *
 * Threads: a tt_path_tracer is immutable after creation; tt_path_trace is thread-safe.
 */
#ifndef TUNETRACE_PATH_H
#define TUNETRACE_PATH_H

#include <tunetrace/accel.h>
#include <tunetrace/camera.h>
#include <tunetrace/film.h>
#include <tunetrace/scene.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_PATH_DIM_FILM 0
#define TT_PATH_DIM_LENS 2
#define TT_PATH_DIM_FIRST_BOUNCE 4
#define TT_PATH_DIMS_PER_BOUNCE 8
#define TT_PATH_BOUNCE_LIGHT_SELECT 0
#define TT_PATH_BOUNCE_LIGHT_POS 1
#define TT_PATH_BOUNCE_BSDF_LOBE 3
#define TT_PATH_BOUNCE_BSDF_DIR 4
#define TT_PATH_BOUNCE_RR 6
/* Number of dimensions a path of up to `max_depth` bounces can use. */
#define TT_PATH_DIM_COUNT(max_depth)                                                               \
  (TT_PATH_DIM_FIRST_BOUNCE + TT_PATH_DIMS_PER_BOUNCE * ((max_depth) + 1))

typedef enum tt_dim_kind {
  TT_DIM_FILM = 1,
  TT_DIM_LENS = 2,
  TT_DIM_LIGHT_SELECT = 3,
  TT_DIM_LIGHT_POS = 4,
  TT_DIM_BSDF_LOBE = 5,
  TT_DIM_BSDF_DIR = 6,
  TT_DIM_RR = 7,
  TT_DIM_RESERVED = 8
} tt_dim_kind;

/* What dimension `dim` is used for. */
TT_API tt_dim_kind tt_path_dim_kind(uint32_t dim);

/* Source of primary samples. get() returns dimension `dim` in [0, 1). report_pdf (may be
 * NULL) is called once per sampled BSDF direction with its first dimension and the pdf
 * (solid angle; 0 for specular/delta). */
typedef struct tt_sample_source {
  float (*get)(void *self, uint32_t dim);
  void (*report_pdf)(void *self, uint32_t dim, float pdf);
  void *self;
} tt_sample_source;

/* Which acceleration structure to trace against. */
typedef struct tt_tracer {
  const tt_accel_iface *iface;
  const tt_accel *accel;
} tt_tracer;

typedef enum tt_mis_heuristic {
  TT_MIS_NONE = 0, /* light sampling only for area lights (NEE), BSDF hits on lights not counted */
  TT_MIS_BALANCE = 1,
  TT_MIS_POWER = 2 /* beta = 2 */
} tt_mis_heuristic;

typedef enum tt_light_strategy {
  TT_STRATEGY_MIS = 0,   /* NEE + BSDF sampling combined with the MIS heuristic */
  TT_STRATEGY_LIGHT = 1, /* NEE only (emission found by BSDF sampling ignored after bounce 0) */
  TT_STRATEGY_BSDF = 2   /* BSDF sampling only (no NEE) */
} tt_light_strategy;

typedef struct tt_path_options {
  uint32_t struct_size;
  uint32_t max_depth; /* bounces; 0 = directly visible emission only */
  uint32_t rr_depth;  /* Russian roulette from this bounce on (>= max_depth: never) */
  tt_light_strategy strategy;
  tt_mis_heuristic heuristic;
  /* ---- appended (ABI 1.2): read only when struct_size covers it ---- */
  uint32_t result_size; /* sizeof(tt_path_result) the caller passes to tt_path_trace /
                                tt_path_finish: only that much is written. 0 (the default):
                                the ABI 1.1 result, TT_PATH_RESULT_SIZE_1_1 bytes */
} tt_path_options;

/* Fills options with the defaults: max_depth 3 (thesis ch. 3), rr_depth 3, MIS, power. */
TT_API void tt_path_options_default(tt_path_options *options);

typedef struct tt_path_result {
  float L[3];        /* radiance along the camera ray (finite: non-finite -> 0) */
  float albedo[3];   /* first hit reflectance (0 on a miss) */
  float normal[3];   /* first hit shading normal (0 on a miss) */
  float position[3]; /* first hit position (for motion vectors) */
  float distance;    /* first hit distance along the ray (+inf on a miss) */
  uint32_t rays;     /* rays traced (closest + shadow) */
  uint32_t bounces;  /* surface interactions */
  uint32_t max_dim;  /* highest dimension + 1 that get() was asked for */
  int32_t hit;       /* non-zero if the camera ray hit geometry */
  int32_t nonfinite; /* non-zero if a non-finite value was produced and zeroed */
  /* ---- appended (ABI 1.2): written only when the options' result_size covers it ---- */
  float prev_position[3]; /* where the first hit's surface point was at the previous
                                frame (tt_mesh.prev_positions at the hit's barycentrics; ==
                                position on a still mesh and on a miss): object motion */
} tt_path_result;

/* Size of the ABI 1.1 result (before prev_position). */
#define TT_PATH_RESULT_SIZE_1_1 offsetof(tt_path_result, prev_position)

typedef struct tt_path_tracer tt_path_tracer;

/* Prepares light sampling (area-weighted over emissive triangles, power-weighted over
 * lights) and material data for `scene`, which must outlive it. Free with destroy. */
TT_API tt_status tt_path_tracer_create(const tt_scene *scene, tt_path_tracer **out);
TT_API void tt_path_tracer_destroy(tt_path_tracer *pt);

/* Traces one path starting with `camera_ray`. Thread-safe. */
TT_API void tt_path_trace(const tt_path_tracer *pt, const tt_tracer *tracer,
                          const tt_path_options *options, const tt_ray *camera_ray,
                          const tt_sample_source *source, tt_path_result *out);

/* Folds the first-hit AOVs of one camera sample (`ray` through film position (fx, fy) of
 * `frame`, traced into `r`) into pixel (x, y) of every AOV plane `film` has, as the running
 * mean over the pixel's samples: `n` is this sample's number since the film was cleared
 * (1: stored as is, so equal samples, e.g. a sequence frame's fixed jitter, give exactly
 * that value). Depth along the view axis (0 on a miss), shading normal, albedo, and motion
 * in pixels from (fx, fy) to where `prev` (the previous frame's camera, NULL: no motion)
 * saw the hit (a miss moves with the camera's rotation only). The integrators share it, so
 * every one writes the same AOVs. Not thread-safe for one pixel: callers split pixels. */
TT_API void tt_path_write_aovs(tt_film *film, uint32_t x, uint32_t y, const tt_camera_frame *frame,
                               const tt_camera_frame *prev, float fx, float fy, const tt_ray *ray,
                               const tt_path_result *r, uint64_t n);
/* tt_path_write_aovs with the hit's previous position (ABI 1.2): the motion AOV projects
 * `prev_position` (r->prev_position of a result traced with result_size covering it; NULL:
 * r->position) into `prev`, so objects that move show their own motion, not only the
 * camera's. */
TT_API void tt_path_write_aovs_ex(tt_film *film, uint32_t x, uint32_t y,
                                  const tt_camera_frame *frame, const tt_camera_frame *prev,
                                  float fx, float fy, const tt_ray *ray, const tt_path_result *r,
                                  const float prev_position[3], uint64_t n);

/* ---- the same path, one step at a time (wavefront integrators) ----
 *
 * tt_path_trace is exactly this loop, so both forms give identical results (same random
 * dimensions, same arithmetic, same order of additions):
 *
 *   more = tt_path_begin(pt, options, camera_ray, st, &ray);
 *   while (more) {
 *     intersect ray -> hit;
 *     more = tt_path_hit(pt, st, &ray, &hit, source, &shadow, &has_shadow, &ray);
 *     if (has_shadow) tt_path_shadow(st, occluded(shadow));
 *   }
 *   tt_path_finish(st, &result);
 *
 * A wavefront integrator keeps many states, traces the rays of all of them with one
 * intersect_stream call and the shadow rays with one occluded_stream call per bounce, and
 * so lets the accel trace many rays back to back (its tree stays in cache; stream kernels
 * can overlap the memory latency of several rays). Each state must see its shadow result
 * before its next tt_path_hit. States are plain memory of tt_path_state_size() bytes,
 * 16-byte aligned, owned by the caller; a state is used by one thread at a time. */
typedef struct tt_path_state tt_path_state;

/* Bytes of one tt_path_state (fixed for a given libtunetrace). */
TT_API size_t tt_path_state_size(void);

/* Starts a path at `camera_ray`: writes the first ray to intersect to *ray and returns 1,
 * or returns 0 when there is nothing to trace (zero direction; finish at once). */
TT_API int tt_path_begin(const tt_path_tracer *pt, const tt_path_options *options,
                         const tt_ray *camera_ray, tt_path_state *st, tt_ray *ray);

/* Consumes the closest hit of `traced` (hit->geom_id == TT_INVALID_ID: a miss). May ask
 * for a shadow ray (*has_shadow = 1, ray in *shadow): pass its occlusion to tt_path_shadow
 * before the next tt_path_hit, whether or not the path goes on. Returns 1 with the next
 * ray in *next (which may alias `traced`), or 0 when the path ended. Thread-safe for
 * distinct states. */
TT_API int tt_path_hit(const tt_path_tracer *pt, tt_path_state *st, const tt_ray *traced,
                       const tt_hit *hit, const tt_sample_source *source, tt_ray *shadow,
                       int *has_shadow, tt_ray *next);

/* Adds the pending next-event contribution unless `occluded`. */
TT_API void tt_path_shadow(tt_path_state *st, int occluded);

/* The path's result (as tt_path_trace's). */
TT_API void tt_path_finish(const tt_path_state *st, tt_path_result *out);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_PATH_H */
