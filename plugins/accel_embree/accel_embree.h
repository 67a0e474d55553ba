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
  float refit_sah_growth; /* refit, custom: build from scratch once the refitted tree's SAH
                             cost exceeds this many times its cost when built (0 never) */
} tt__embree_settings;

/* Update methods, in the order of the "updateMethod" NOM parameter's values. */
typedef enum tt__embree_update_method {
  TT__EMBREE_UPDATE_REBUILD = 0, /* build from scratch with the same configuration */
  TT__EMBREE_UPDATE_REFIT = 1    /* keep the tree, recompute its boxes for the new positions */
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

/* ---- custom backend (accel_embree_custom.c) ---- */

struct tt__bvh;
struct RTCDeviceTy;

/* Builds the custom backend's tree for `st` over `scene` with Embree's rtcBuildBVH on
 * `device`; fills nodes/leaves/sah_cost/max_depth/memory_bytes of `stats`. Configurations
 * the builder cannot honour (depth limit, ...) give TT_ERR_INFEASIBLE with a message. */
tt_status tt__custom_build(const tt_scene *scene, const tt__embree_settings *st,
                           struct RTCDeviceTy *device, struct tt__bvh **out,
                           tt_accel_build_stats *stats);
/* Frees a custom tree (NULL is ignored). */
void tt__custom_free(struct tt__bvh *bvh);
/* Refits a custom tree to the scene's current positions: every leaf's triangle data is
 * recomputed from the mesh and every box set bottom-up to the union of its children (the
 * topology stays). Returns the tree's SAH cost after the refit (as the build reports it). */
double tt__custom_refit(const tt_scene *scene, struct tt__bvh *bvh);

/* Text of the calling thread's last Embree error ("" if none). */
const char *tt__embree_last_error(void);
/* While on, Embree errors on this thread are logged at DEBUG, not ERROR: the caller expects
 * them and reports them itself (an infeasible custom build). */
void tt__embree_set_quiet(int quiet);

#endif /* TT_ACCEL_EMBREE_H */
