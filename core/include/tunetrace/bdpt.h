/* tunetrace: the bidirectional path sampler shared by integrator_bdpt and the multiplexed MLT
 * of integrator_pssmlt (Veach 1997, ch. 10; the structure of pbrt-v3's BDPT and
 * MLTIntegrator), on the same materials, textures and lights as the path sampler (path.h).
 *
 * A sample is a camera subpath (vertex 0 the pinhole, then surface vertices, and a last
 * vertex at infinity when it escapes into an environment) and a light subpath (vertex 0 a
 * point on a light chosen by power, then surface vertices). Connection (s, t) joins the first
 * s light vertices with the first t camera vertices into a path of depth s + t - 2 bounces:
 *
 *   s = 0   the camera subpath's vertex t-1 is on a light (or the environment): its emission;
 *   t = 1   light vertex s-1 is joined to the camera (light tracing): the contribution lands
 *           at another film position (*fx, *fy), to be splatted with scale 1 / (samples per
 *           pixel) (camera.h, "importance");
 *   s = 1   a fresh point on a light, sampled from camera vertex t-1 (next-event estimation);
 *   other   light vertex s-1 and camera vertex t-1 joined by a shadow ray.
 *
 * Every contribution comes weighted by multiple importance sampling over all strategies that
 * could have produced its path (pbrt-v3's MISWeight: the densities of each vertex in both
 * directions, those of delta events re-mapped to 1 and their strategies skipped), with the
 * balance or power heuristic; for any path the weights of its strategies sum to 1. Light
 * subpaths carry importance: refraction without the radiance's 1/eta^2, and the shading-
 * normal correction |wo.ns||wi.ng| / (|wo.ng||wi.ns|) (Veach 5.3). A pair of directions at a
 * surface counts only when each lies on the same side of the geometric and the shading normal
 * (no light through surfaces: the rule is symmetric, so that both directions of transport
 * define one integrand), and an opaque surface reflects only.
 *
 * Random numbers come from three sample streams, each with a fixed layout so that no
 * decision shifts another's dimension (MLT mutates the streams; a path tracer's sampler
 * serves them interleaved):
 *
 *   camera stream     dims 0-1 film position (read by the caller), 2-3 lens (reserved), then
 *                     per bounce b at 4 + 4b: +0 lobe, +1..2 BSDF direction, +3 roulette;
 *   light stream      dim 0 light choice, 1-2 point on it, 3-4 direction, then per bounce b at
 *                     5 + 4b as above;
 *   connection stream at the caller's base: +0 light choice, +1..2 point on it (s = 1), +3
 *                     reserved.
 *
 * A source's report_pdf (may be NULL) receives every BSDF direction's solid-angle pdf (0 for
 * a delta lobe) with the direction's first dimension in its stream, as path.h does.
 *
 * Threads: the tracer (path.h) is shared and immutable; a tt_bdpt_paths object holds one
 * sample's subpaths and is used by one thread at a time.
 */
#ifndef TUNETRACE_BDPT_H
#define TUNETRACE_BDPT_H

#include <tunetrace/path.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_BDPT_CAMERA_DIM_FILM 0
#define TT_BDPT_CAMERA_DIM_LENS 2
#define TT_BDPT_CAMERA_DIM_FIRST_BOUNCE 4
#define TT_BDPT_LIGHT_DIM_SELECT 0
#define TT_BDPT_LIGHT_DIM_POS 1
#define TT_BDPT_LIGHT_DIM_DIR 3
#define TT_BDPT_LIGHT_DIM_FIRST_BOUNCE 5
#define TT_BDPT_DIMS_PER_BOUNCE 4
#define TT_BDPT_BOUNCE_LOBE 0
#define TT_BDPT_BOUNCE_DIR 1
#define TT_BDPT_BOUNCE_RR 3
#define TT_BDPT_CONNECT_DIM_SELECT 0
#define TT_BDPT_CONNECT_DIM_POS 1
#define TT_BDPT_CONNECT_DIMS 4
/* Dimensions a stream can use for paths of up to `max_depth` bounces. */
#define TT_BDPT_CAMERA_DIM_COUNT(max_depth)                                                        \
  (TT_BDPT_CAMERA_DIM_FIRST_BOUNCE + TT_BDPT_DIMS_PER_BOUNCE * ((max_depth) + 1))
#define TT_BDPT_LIGHT_DIM_COUNT(max_depth)                                                         \
  (TT_BDPT_LIGHT_DIM_FIRST_BOUNCE + TT_BDPT_DIMS_PER_BOUNCE * ((max_depth) + 1))

typedef struct tt_bdpt_options {
  uint32_t struct_size;
  uint32_t max_depth;         /* bounces of a connected path (s + t - 2), as path.h's */
  uint32_t rr_depth;          /* Russian roulette on subpath vertices from this bounce on,
                                   survival min(1, throughput / the subpath's first) */
  tt_mis_heuristic heuristic; /* TT_MIS_POWER (beta 2) or TT_MIS_BALANCE */
} tt_bdpt_options;

/* Defaults: max_depth 5 (pbrt-v3), rr_depth 3, power heuristic. */
TT_API void tt_bdpt_options_default(tt_bdpt_options *options);

/* One sample's subpaths (per thread). */
typedef struct tt_bdpt_paths tt_bdpt_paths;

/* Room for subpaths of paths up to `max_depth` bounces (<= 64). Free with destroy. */
TT_API tt_status tt_bdpt_paths_create(uint32_t max_depth, tt_bdpt_paths **out);
TT_API void tt_bdpt_paths_destroy(tt_bdpt_paths *paths);

/* Starts a sample: the camera subpath through film position (fx, fy), of at most
 * `max_vertices` vertices (the pinhole included; 0..max_depth + 2). Returns the vertex count.
 * Resets the sample's ray count. */
TT_API uint32_t tt_bdpt_camera_subpath(const tt_path_tracer *pt, const tt_tracer *tracer,
                                       const tt_bdpt_options *options, const tt_camera_frame *frame,
                                       float fx, float fy, const tt_sample_source *camera,
                                       uint32_t max_vertices, tt_bdpt_paths *paths);

/* The sample's light subpath of at most `max_vertices` vertices (0..max_depth + 1). Returns
 * the vertex count (0: no light emits anything). */
TT_API uint32_t tt_bdpt_light_subpath(const tt_path_tracer *pt, const tt_tracer *tracer,
                                      const tt_bdpt_options *options, const tt_sample_source *light,
                                      uint32_t max_vertices, tt_bdpt_paths *paths);

/* One strategy's contribution. */
typedef struct tt_bdpt_contribution {
  float L[3];          /* weighted: weight * unweighted (finite; 0 if not) */
  float unweighted[3]; /* the strategy's own estimate */
  float weight;        /* MIS weight */
  float fx, fy;        /* t = 1: film position the light path reaches */
  int32_t nonfinite;   /* a non-finite value was produced and zeroed */
} tt_bdpt_contribution;

/* Strategy (s, t) of the current subpaths (s <= light count, 1 <= t <= camera count,
 * (s, t) != (1, 1)); the s = 1 light point reads `connect` at dims connect_base + 0..2.
 * Returns 1 if it contributed something non-zero (out is zeroed otherwise). */
TT_API int tt_bdpt_connect(const tt_path_tracer *pt, const tt_tracer *tracer,
                           const tt_bdpt_options *options, const tt_camera_frame *frame,
                           tt_bdpt_paths *paths, uint32_t s, uint32_t t,
                           const tt_sample_source *connect, uint32_t connect_base,
                           tt_bdpt_contribution *out);

/* Rays traced since the sample started (subpaths and connections). */
TT_API uint32_t tt_bdpt_rays(const tt_bdpt_paths *paths);

/* The camera subpath's first hit as path.h reports it (albedo, normal, position, distance,
 * hit; L and counters zero), for tt_path_write_aovs. */
TT_API void tt_bdpt_first_hit(const tt_bdpt_paths *paths, tt_path_result *out);
/* tt_bdpt_first_hit writing `result_size` bytes of `out` (ABI 1.2): sizeof(tt_path_result)
 * adds prev_position; tt_bdpt_first_hit writes the ABI 1.1 result. */
TT_API void tt_bdpt_first_hit_ex(const tt_bdpt_paths *paths, tt_path_result *out,
                                 size_t result_size);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_BDPT_H */
