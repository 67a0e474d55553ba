/* tunetrace: acceleration-structure plugins (kind TT_KIND_ACCEL, interface "tt.accel/1").
 *
 * An accel builds a structure over the scene's triangle meshes with a configuration of its
 * parameter space (thesis Table 3.1 for accel_embree), then answers closest-hit and
 * occlusion queries for single rays and for streams of rays. Rebuilding with another
 * configuration (the autotuning loop) is destroy + build. When an animated scene moves
 * (tt_scene_set_time), update() brings the structure up to date (refit or rebuild, as its
 * configuration says); a table without update (ABI 1.1) is destroyed and built again.
 *
 * Threads: build/destroy/update from one thread at a time (they may use host->parallel_for);
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

typedef struct tt_accel tt_accel; /* opaque, defined by the plugin */

/* Filled by build(). */
typedef struct tt_accel_build_stats {
  uint32_t struct_size;  /* set by the caller to sizeof; the plugin fills only that much */
  double build_ms;       /* wall time of the build proper */
  uint64_t memory_bytes; /* bytes held by the structure (nodes, leaves, triangle data) */
  uint64_t nodes;        /* inner nodes (0 if unknown) */
  uint64_t leaves;       /* leaves (0 if unknown) */
  double sah_cost;       /* SAH cost of the tree (0 if unknown) */
  uint32_t max_depth;    /* depth reached (0 if unknown) */
  int32_t repaired;      /* non-zero if the configuration was repaired before building */
} tt_accel_build_stats;

/* Optional traversal counters (enabled by the plugin's own parameter). */
typedef struct tt_accel_counters {
  uint32_t struct_size;
  uint64_t rays;
  uint64_t nodes_visited;
  uint64_t triangles_tested;
} tt_accel_counters;

/* Filled by update() (ABI 1.2). */
typedef struct tt_accel_update_stats {
  uint32_t struct_size;   /* set by the caller to sizeof; the plugin fills only that much */
  double update_ms;       /* wall time of the update (refit or rebuild) */
  int32_t rebuilt;        /* 1: built again from scratch; 0: refitted in place */
  uint32_t since_rebuild; /* updates since the structure was last built from scratch (0
                               after a rebuild) */
  double sah_cost;        /* SAH cost after the update, as tt_accel_build_stats (0 unknown) */
  double sah_growth;      /* sah_cost / its value at the last rebuild (0 unknown) */
} tt_accel_update_stats;

typedef struct tt_accel_iface {
  uint32_t struct_size; /* sizeof(tt_accel_iface) as the plugin was built */

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

  /* ---- appended in later ABI minors: check struct_size (TT_HAS_FIELD) ---- */

  /* ABI 1.2. Brings `accel` up to date after the positions of its scene's meshes changed
   * (tt_scene_set_time: same meshes, vertex counts and indices; tt_mesh.revision tells
   * which moved). How -- refit the boxes, or build again from scratch with the
   * configuration it was built with -- is the plugin's choice, usually a parameter.
   * Afterwards queries answer for the new positions exactly as a fresh build would (same
   * closest t and ids up to ties between equally distant triangles). `stats` may be NULL.
   * On failure the accel must not be queried again: destroy it. NULL (or a table too short
   * to hold it): the host destroys the accel and builds it again. */
  tt_status (*update)(tt_accel *accel, tt_accel_update_stats *stats);
} tt_accel_iface;

/* Size of the ABI 1.1 table (before update): the smallest table a host accepts. */
#define TT_ACCEL_IFACE_SIZE_1_1 offsetof(tt_accel_iface, update)

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_ACCEL_H */
