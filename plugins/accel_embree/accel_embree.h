/* accel_embree: internals shared by the plugin's translation units (not installed). */
#ifndef TT_ACCEL_EMBREE_H
#define TT_ACCEL_EMBREE_H

#include <tunetrace/accel.h>
#include <tunetrace/host.h>
#include <tunetrace/params.h>

#define TT__EMBREE_NAME "accel_embree"
#define TT__EMBREE_VERSION "0.1.0"

/* Backends, in the order of the "backend" NOM parameter's possible values. */
typedef enum tt__embree_backend {
  TT__EMBREE_BACKEND_NATIVE = 0, /* Embree's scene API (rtcCommitScene) */
  TT__EMBREE_BACKEND_CUSTOM = 1  /* rtcBuildBVH, our layout and SIMD traversal */
} tt__embree_backend;

/* A configuration decoded into plain values (thesis Table 3.1 + backend). */
typedef struct tt__embree_settings {
  int quality;            /* 1 Morton (LOW), 2 binned SAH (MEDIUM), 3 spatial splits (HIGH) */
  int branching_factor;   /* 2, 4, 8 */
  int max_depth;          /* [8, 64] */
  int sah_block_size;     /* [1, 32] */
  int min_leaf_size;      /* [1, 32] */
  int max_leaf_size;      /* [1, 32] */
  float trav_cost;        /* [0.1, 10] */
  float int_cost;         /* [0.1, 10] */
  int is_static;          /* scene will not change: no RTC_SCENE_FLAG_DYNAMIC */
  int compact;            /* RTC_SCENE_FLAG_COMPACT */
  int robust;             /* RTC_SCENE_FLAG_ROBUST */
  int backend;            /* a tt__embree_backend */
  int counters;           /* custom backend: count rays, nodes and triangles per query */
  int update_method;      /* a tt__embree_update_method: what update() does when the scene moves */
  int refit_interval;     /* refit: build from scratch every this many updates (0 never) */
  float refit_sah_growth; /* refit: build from scratch once the refitted tree's SAH cost
                             exceeds this many times its cost when built (0 never; native:
                             the estimate of accel_embree_growth.c) */
} tt__embree_settings;

/* Update methods, in the order of the "updateMethod" NOM parameter's values. */
typedef enum tt__embree_update_method {
  TT__EMBREE_UPDATE_REBUILD = 0,  /* build from scratch with the same configuration */
  TT__EMBREE_UPDATE_REFIT = 1,    /* keep the tree, recompute its boxes for the new positions */
  TT__EMBREE_UPDATE_INSTANCES = 2 /* two-level: rigid meshes as instances of their own BVHs,
                                     only the top level rebuilt (accel_embree_inst.c) */
} tt__embree_update_method;

/* Builds the published parameter space (once, at init); NULL with tt_set_error on failure. */
tt_space *tt__embree_space_create(void);

/* Runs the constraint check on `config` through whatever space it belongs to (ours, or one
 * parsed from JSON, which has no check function installed). */
tt_check_result tt__embree_check_config(tt_config *config, char *why, size_t why_size);

/* Decodes a configuration of the plugin's space into settings. */
void tt__embree_settings_from_config(const tt_config *config, tt__embree_settings *out);

/* Names (comma-separated, into `buf`) of the parameters that only the custom backend uses
 * and that differ from their defaults; returns how many there are. */
int tt__embree_custom_only_changed(const tt_config *config, char *buf, size_t size);

/* ---- native refit's SAH-growth estimate (accel_embree_growth.c) ---- */

typedef struct tt__embree_growth tt__embree_growth;
/* Freezes the grouping of the meshes whose `moving[i]` is non-NULL at their current
 * positions (Morton order, leaves of 4, nodes of 4); NULL when out of memory. */
tt__embree_growth *tt__embree_growth_create(const tt_scene *scene, const float *const *moving);
/* The frozen trees' SAH cost at the meshes' current positions (triangle-weighted mean; 0
 * when no mesh has an extent). */
double tt__embree_growth_cost(tt__embree_growth *g, const tt_scene *scene);
/* Frees it (NULL is ignored). */
void tt__embree_growth_free(tt__embree_growth *g);

/* ---- custom backend (accel_embree_custom.c) ---- */

struct tt__embree_bvh;
struct RTCDeviceTy;

/* Builds the custom backend's tree for `st` over `scene` with Embree's rtcBuildBVH on
 * `device`; fills nodes/leaves/sah_cost/max_depth/memory_bytes of `stats`. Configurations
 * the builder cannot honour (depth limit, ...) give TT_ERR_INFEASIBLE with a message. */
tt_status tt__embree_custom_build(const tt_scene *scene, const tt__embree_settings *st,
                                  struct RTCDeviceTy *device, struct tt__embree_bvh **out,
                                  tt_accel_build_stats *stats);
/* Frees a custom tree (NULL is ignored). */
void tt__embree_custom_free(struct tt__embree_bvh *bvh);
/* Refits a custom tree to the scene's current positions: every leaf's triangle data is
 * recomputed from the mesh and every box set bottom-up to the union of its children (the
 * topology stays). Subtrees are refitted in parallel through host->parallel_for (NULL:
 * one thread), split by the tree's shape only, so the result is the same whatever the thread
 * count. Returns the tree's SAH cost after the refit (as the build reports it). */
double tt__embree_custom_refit(const tt_scene *scene, struct tt__embree_bvh *bvh,
                               const tt_host *host);

/* ---- native backend, shared by accel_embree.c and accel_embree_inst.c ---- */

struct RTCSceneTy;
/* The plugin's Embree device (valid between init and deinit). */
struct RTCDeviceTy *tt__embree_device(void);
/* Reads and clears Embree's per-thread error code; returns TT_OK or an error naming `what`. */
tt_status tt__embree_status(const char *what);
/* Non-zero when tt_scene_set_time may move the mesh. */
int tt__embree_mesh_moves(const tt_mesh *m);
/* Creates the triangle geometry of mesh `index` over `positions` (3 * vertex_count floats,
 * copied) with build quality `quality` (an RTCBuildQuality) and attaches it to `scene` under
 * geomID = index; `*vbuf` (if set) receives the Embree vertex buffer. */
tt_status tt__embree_attach_mesh(struct RTCSceneTy *scene, const tt_mesh *m, const float *positions,
                                 uint32_t index, int quality, float **vbuf);

/* ---- updateMethod=instances (accel_embree_inst.c) ---- */

typedef struct tt__embree_inst tt__embree_inst;
/* Builds the two-level structure over an animated scene: one BVH per rigid mesh over its
 * object-space positions, one for the still meshes, one dynamic scene of the deforming
 * meshes (refitted per update), instanced in a top-level scene returned in `*top` (owned by
 * `*out`). `quality`: the RTCBuildQuality of the tuned configuration. */
tt_status tt__embree_inst_build(const tt_scene *scene, const tt__embree_settings *st, int quality,
                                tt__embree_inst **out, struct RTCSceneTy **top);
/* Brings the structure to the scene's current pose: the moved rigid meshes' transforms, the
 * changed deforming meshes refitted, the top level rebuilt. */
tt_status tt__embree_inst_update(tt__embree_inst *in);
/* A hit on instance `inst_id` reports Embree's object-space normal: turns it into the
 * world-space unnormalised normal of the triangle (unchanged for the identity instances). */
void tt__embree_inst_normal(const tt__embree_inst *in, uint32_t inst_id, float ng[3]);
/* Instances in the top level (0 for NULL). */
uint32_t tt__embree_inst_count(const tt__embree_inst *in);
/* Releases everything (NULL is ignored). */
void tt__embree_inst_free(tt__embree_inst *in);

/* Text of the calling thread's last Embree error ("" if none). */
const char *tt__embree_last_error(void);
/* While on, Embree errors on this thread are logged at DEBUG, not ERROR: the caller expects
 * them and reports them itself (an infeasible custom build). */
void tt__embree_set_quiet(int quiet);

#endif /* TT_ACCEL_EMBREE_H */
