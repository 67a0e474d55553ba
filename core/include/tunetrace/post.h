/* tunetrace: post-filter plugins (kind TT_KIND_POST, interface "tt.post/1").
 *
 * A post-filter turns each rendered frame into an output frame and may keep temporal state
 * (history) between frames: temporal anti-aliasing (variance-clipping TAA, the thesis'
 * kernel-prediction network), denoisers, tone mappers.
 *
 * Threads: one thread at a time per post object; process() may use host->parallel_for.
 */
#ifndef TUNETRACE_POST_H
#define TUNETRACE_POST_H

#include <stddef.h>

#include <tunetrace/params.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_POST_INTERFACE_ID "tt.post/1"

typedef struct tt_post tt_post; /* opaque, defined by the plugin */

/* One input frame. All planes are width x height, row-major, y = 0 at the top, owned by
 * the caller and valid during process() only. Optional planes may be NULL. */
typedef struct tt_post_frame {
  uint32_t struct_size;
  uint32_t width, height;
  const float *color;    /* 3 channels, linear RGB (required) */
  const float *depth;    /* 1 channel, view depth; NULL if not rendered */
  const float *motion;   /* 2 channels, pixels from this frame back to the previous one */
  const float *normal;   /* 3 channels, world-space normal; may be NULL */
  const float *albedo;   /* 3 channels; may be NULL */
  uint32_t frame_index;  /* 0, 1, 2, ... within a sequence */
  uint32_t jitter_index; /* index in the sub-pixel jitter cycle (Halton 2,3) */
  float jitter[2];       /* sub-pixel offset of this frame in pixels, in [-0.5, 0.5) */
  int32_t reset_history; /* non-zero: a camera cut, discard temporal state first */
  /* ---- appended (ABI 1.0 hosts may not set these: read only when struct_size covers
   * the field, see TT_POST_FRAME_HAS) ---- */
  const float *prev_depth; /* 1 channel: view depth, in the previous frame's camera, of the
                             * surface point this pixel sees (the depth its reprojected
                             * history should have; 0 for the sky or a point behind that
                             * camera); lets a filter detect disocclusions. NULL if unknown */
} tt_post_frame;

/* Non-zero when frame `f` (a const tt_post_frame *) was filled by a host that knows `field`. */
#define TT_POST_FRAME_HAS(f, field) TT_HAS_FIELD(tt_post_frame, f, field)

typedef struct tt_post_iface {
  uint32_t struct_size; /* sizeof(tt_post_iface) as the plugin was built */

  /* The filter's parameter space (mode, blend factor, ...), or NULL. Thread-safe. */
  const tt_space *(*space)(void);

  /* Creates a filter for frames of width x height with `config` (NULL = defaults).
   * `*out` is owned by the caller: free with destroy. */
  tt_status (*create)(uint32_t width, uint32_t height, const tt_config *config, tt_post **out);

  /* Changes parameters between frames (temporal state is kept when possible). */
  tt_status (*configure)(tt_post *post, const tt_config *config);

  /* Filters one frame into `out_rgb` (3 * width * height floats, caller-owned). */
  tt_status (*process)(tt_post *post, const tt_post_frame *frame, float *out_rgb);

  /* Drops all temporal state. */
  void (*reset)(tt_post *post);

  /* Destroys the filter (NULL is ignored). */
  void (*destroy)(tt_post *post);

  /* ---- appended in later ABI minors: check struct_size ---- */
} tt_post_iface;

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_POST_H */
