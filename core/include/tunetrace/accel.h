/* tunetrace: acceleration-structure plugins (kind TT_KIND_ACCEL, interface "tt.accel/1").
 *
 * An accel builds a structure over the scene's triangle meshes with a configuration of its
 * parameter space (thesis Table 3.1 for accel_embree), then answers closest-hit and
 * occlusion queries for single rays and for streams of rays. Rebuilding with another
 * configuration (the autotuning loop) is destroy + build.
 *
 * Threads: build/destroy from one thread at a time (they may use host->parallel_for);
 * every query function is thread-safe on a built accel and must not allocate.
 */
#ifndef TUNETRACE_ACCEL_H
#define TUNETRACE_ACCEL_H

#include <tunetrace/params.h>
#include <tunetrace/ray.h>
#include <tunetrace/scene.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_ACCEL_INTERFACE_ID "tt.accel/1"

typedef struct tt_accel tt_accel;  /* opaque, defined by the plugin */

/* Filled by build(). */
typedef struct tt_accel_build_stats {
  uint32_t struct_size;     /* set by the caller to sizeof; the plugin fills only that much */
  double build_ms;          /* wall time of the build proper */
  uint64_t memory_bytes;    /* bytes held by the structure (nodes, leaves, triangle data) */
  uint64_t nodes;           /* inner nodes (0 if unknown) */
  uint64_t leaves;          /* leaves (0 if unknown) */
  double sah_cost;          /* SAH cost of the tree (0 if unknown) */
  uint32_t max_depth;       /* depth reached (0 if unknown) */
  int32_t repaired;         /* non-zero if the configuration was repaired before building */
} tt_accel_build_stats;

/* Optional traversal counters (enabled by the plugin's own parameter). */
typedef struct tt_accel_counters {
  uint32_t struct_size;
  uint64_t rays;
  uint64_t nodes_visited;
  uint64_t triangles_tested;
} tt_accel_counters;

typedef struct tt_accel_iface {
  uint32_t struct_size;     /* sizeof(tt_accel_iface) as the plugin was built */

  /* The plugin's parameter space; owned by the plugin, valid until deinit. Thread-safe. */
  const tt_space *(*space)(void);

  /* Builds over `scene` (which must outlive the accel) with `config` (of space(); NULL =
   * defaults). Infeasible configurations are repaired (stats->repaired) or rejected with
   * TT_ERR_INFEASIBLE and a message. On success `*out` is owned by the caller: release it
   * with destroy. `stats` may be NULL. */
  tt_status (*build)(const tt_scene *scene, const tt_config *config, tt_accel **out,
                     tt_accel_build_stats *stats);

  /* Closest hit along `ray`; on a hit shortens ray->tfar to hit->t. Thread-safe. */
  void (*intersect1)(const tt_accel *accel, tt_ray *ray, tt_hit *hit);

  /* Non-zero if anything blocks the segment [tnear, tfar]. Thread-safe. */
  int (*occluded1)(const tt_accel *accel, const tt_ray *ray);

  /* Closest hits of `count` rays (coherent or not); same semantics as intersect1 per ray.
   * Thread-safe; distinct threads must pass distinct arrays. */
  void (*intersect_stream)(const tt_accel *accel, tt_ray *rays, tt_hit *hits, size_t count);

  /* Occlusion of `count` rays: occluded[i] = 1 or 0. Thread-safe. */
  void (*occluded_stream)(const tt_accel *accel, const tt_ray *rays, uint8_t *occluded,
                          size_t count);

  /* Reads and (if reset) clears the traversal counters; TT_ERR_UNSUPPORTED when counting
   * is off or not implemented. Not thread-safe with queries. */
  tt_status (*counters)(tt_accel *accel, tt_accel_counters *out, int reset);

  /* Releases the structure (NULL is ignored). */
  void (*destroy)(tt_accel *accel);

  /* ---- appended in later ABI minors: check struct_size ---- */
} tt_accel_iface;

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_ACCEL_H */
