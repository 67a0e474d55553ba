/* tunetrace: integrator plugins (kind TT_KIND_INTEGRATOR, interface "tt.integrator/1").
 *
 * An integrator renders progressively: each render_pass() adds `spp` samples per pixel
 * (or the equivalent number of mutations for MLT) into the film and reports statistics.
 * Path construction lives in core (path.h) so that the path tracer and PSSMLT share it.
 * Between passes the host may rebuild the accel (autotuning) or call configure() with a
 * new configuration (tuning the integrator's own space); accumulated state survives both.
 *
 * Threads: all functions on one integrator object are called from the host's main thread;
 * render_pass parallelises internally with host->parallel_for.
 */
#ifndef TUNETRACE_INTEGRATOR_H
#define TUNETRACE_INTEGRATOR_H

#include <tunetrace/accel.h>
#include <tunetrace/film.h>
#include <tunetrace/sampler.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_INTEGRATOR_INTERFACE_ID "tt.integrator/1"

typedef struct tt_integrator tt_integrator; /* opaque, defined by the plugin */

/* Everything one pass needs. Owned by the host, valid during render_pass only. */
typedef struct tt_render_ctx {
  uint32_t struct_size;
  const tt_scene *scene;
  const tt_accel_iface *accel_iface;
  const tt_accel *accel;
  tt_film *film;
  const tt_camera *camera;      /* pose and resolution of this pass (= film size) */
  const tt_camera *prev_camera; /* previous frame's pose for TT_AOV_MOTION, or NULL */
  uint64_t seed;
  uint32_t pass_index;    /* 0, 1, 2, ... */
  uint32_t spp;           /* samples per pixel to add in this pass */
  uint64_t sample_offset; /* samples per pixel already in the film */
  int32_t fixed_jitter;   /* non-zero: every sample uses `jitter` (sequence frames) */
  float jitter[2];        /* sub-pixel offset in [-0.5, 0.5) when fixed_jitter */
} tt_render_ctx;

/* A named integrator-specific figure, e.g. {"acceptance", 0.31}. */
typedef struct tt_metric {
  const char *name; /* static string owned by the plugin */
  double value;
} tt_metric;

#define TT_MAX_METRICS 16

typedef struct tt_pass_stats {
  uint32_t struct_size;
  double time_ms;     /* wall time of the pass */
  uint64_t rays;      /* rays traced (closest + shadow) */
  uint64_t samples;   /* camera samples (or mutations) taken */
  uint64_t nonfinite; /* samples dropped as NaN/Inf */
  uint32_t metric_count;
  tt_metric metrics[TT_MAX_METRICS];
} tt_pass_stats;

typedef struct tt_integrator_iface {
  uint32_t struct_size; /* sizeof(tt_integrator_iface) as the plugin was built */

  /* The integrator's parameter space (maxDepth, sampler, ...). Owned by the plugin. */
  const tt_space *(*space)(void);

  /* Creates an integrator for `scene` (which must outlive it) with `config` (NULL =
   * defaults). `*out` is owned by the caller: free with destroy. */
  tt_status (*create)(const tt_scene *scene, const tt_config *config, tt_integrator **out);

  /* Applies a new configuration between passes, keeping accumulated state where the
   * method allows (PSSMLT keeps its chains). */
  tt_status (*configure)(tt_integrator *it, const tt_config *config);

  /* Renders one pass into ctx->film. `stats` (may be NULL) is filled up to its
   * struct_size. Returns TT_ERR_INTERRUPTED if host->should_stop() cut the pass short
   * (what was rendered is in the film and consistent). */
  tt_status (*render_pass)(tt_integrator *it, const tt_render_ctx *ctx, tt_pass_stats *stats);

  /* Forgets accumulated state (camera moved, new sequence frame). */
  void (*reset)(tt_integrator *it);

  /* Destroys the integrator (NULL is ignored). */
  void (*destroy)(tt_integrator *it);

  /* ---- appended in later ABI minors: check struct_size ---- */
} tt_integrator_iface;

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_INTEGRATOR_H */
