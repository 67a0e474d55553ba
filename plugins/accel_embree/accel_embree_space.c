/* accel_embree: the parameter space of thesis Table 3.1 (plus "backend"), its constraint
 * check, and decoding a configuration into plain settings. */
#include "accel_embree.h"

#include <stdio.h>
#include <string.h>

/* Embree's own defaults for the numeric builder settings (RTCBuildArguments defaults,
 * rtcDefaultBuildArguments), so the default configuration reproduces stock Embree. */
#define TT__EMBREE_DEF_QUALITY 2
#define TT__EMBREE_DEF_BF 2
#define TT__EMBREE_DEF_MAX_DEPTH 32
#define TT__EMBREE_DEF_SAH_BLOCK 1
#define TT__EMBREE_DEF_MIN_LEAF 1
#define TT__EMBREE_DEF_MAX_LEAF 32
#define TT__EMBREE_DEF_TRAV_COST 1.0
#define TT__EMBREE_DEF_INT_COST 1.0
/* Default backend: index into {"native", "custom"}; the faster one in the bench on the
 * project's scene set (README.md, "Choosing the default backend"). */
#define TT__EMBREE_DEF_BACKEND TT__EMBREE_BACKEND_NATIVE

/* Parameters that act only in the custom (rtcBuildBVH) backend, with their defaults. */
static const struct {
  const char *name;
  double def;
} tt__embree_custom_only[] = {
    {"branchingFactor", TT__EMBREE_DEF_BF},     {"maxDepth", TT__EMBREE_DEF_MAX_DEPTH},
    {"sahBlockSize", TT__EMBREE_DEF_SAH_BLOCK}, {"minLeafSize", TT__EMBREE_DEF_MIN_LEAF},
    {"maxLeafSize", TT__EMBREE_DEF_MAX_LEAF},   {"travcost", TT__EMBREE_DEF_TRAV_COST},
    {"intcost", TT__EMBREE_DEF_INT_COST},
};

/* Writes a reason into `why` if there is room (the check's contract allows a NULL buffer). */
static void tt__embree_why(char *why, size_t size, const char *text) {
  if (why && size) snprintf(why, size, "%s", text);
}

/* Largest power of two <= v (v >= 1). */
static int64_t tt__embree_pow2_floor(int64_t v) {
  int64_t p = 1;
  while (p * 2 <= v) p *= 2;
  return p;
}

/* Constraint check: repairs minLeafSize > maxLeafSize by swapping and sahBlockSize to the
 * power of two Embree actually uses; rejects Morton settings the custom builder cannot
 * honour. Scene-dependent constraints (maxDepth vs triangle count) are checked at build.
 * Pure and thread-safe (touches only `config`). */
static tt_check_result tt__embree_check(const tt_space *space, tt_config *config, char *why,
                                        size_t why_size, void *user) {
  (void)user;
  int64_t quality = tt_config_get_int(config, "quality", TT__EMBREE_DEF_QUALITY);
  int64_t bf = tt_config_get_int(config, "branchingFactor", TT__EMBREE_DEF_BF);
  int64_t min_leaf = tt_config_get_int(config, "minLeafSize", TT__EMBREE_DEF_MIN_LEAF);
  int64_t max_leaf = tt_config_get_int(config, "maxLeafSize", TT__EMBREE_DEF_MAX_LEAF);

  /* Checked before repairing: a swap cannot make a Morton configuration feasible. */
  if (quality == 1 && (bf > 8 || max_leaf > 32 || min_leaf > 32)) {
    tt__embree_why(why, why_size,
                   "quality 1 (Morton) supports branchingFactor <= 8 and leaf sizes <= 32");
    return TT_CHECK_INFEASIBLE;
  }
  /* Embree uses only the largest power of two <= sahBlockSize (bsr of it): 5..7 act as 4.
   * Canonicalising spares a tuner from measuring the same tree three times. */
  int64_t block = tt_config_get_int(config, "sahBlockSize", TT__EMBREE_DEF_SAH_BLOCK);
  char block_why[128] = "";
  if (block >= 1 && tt__embree_pow2_floor(block) != block) {
    int ib = tt_space_find(space, "sahBlockSize");
    if (ib < 0 ||
        tt_config_set_number(config, (size_t)ib, (double)tt__embree_pow2_floor(block)) != TT_OK) {
      tt__embree_why(why, why_size, "sahBlockSize is not a power of two and could not be rounded");
      return TT_CHECK_INFEASIBLE;
    }
    snprintf(block_why, sizeof block_why,
             "sahBlockSize %lld acts as %lld (Embree uses its largest power of two)",
             (long long)block, (long long)tt__embree_pow2_floor(block));
  }
  if (min_leaf > max_leaf) {
    int imin = tt_space_find(space, "minLeafSize");
    int imax = tt_space_find(space, "maxLeafSize");
    if (imin < 0 || imax < 0 ||
        tt_config_set_number(config, (size_t)imin, (double)max_leaf) != TT_OK ||
        tt_config_set_number(config, (size_t)imax, (double)min_leaf) != TT_OK) {
      tt__embree_why(why, why_size, "minLeafSize > maxLeafSize and the swap failed");
      return TT_CHECK_INFEASIBLE;
    }
    if (why && why_size)
      snprintf(why, why_size, "minLeafSize %lld > maxLeafSize %lld: swapped%s%s",
               (long long)min_leaf, (long long)max_leaf, block_why[0] ? "; " : "", block_why);
    return TT_CHECK_REPAIRED;
  }
  if (block_why[0]) {
    tt__embree_why(why, why_size, block_why);
    return TT_CHECK_REPAIRED;
  }
  return TT_CHECK_OK;
}

/* Checks through the config's own space: lookups by name work in a JSON-parsed copy too. */
tt_check_result tt__embree_check_config(tt_config *config, char *why, size_t why_size) {
  return tt__embree_check(tt_config_space(config), config, why, why_size, NULL);
}

/* Builds the space; parameter names and defaults are those of thesis Table 3.1. */
tt_space *tt__embree_space_create(void) {
  tt_space *s = tt_space_create(TT__EMBREE_NAME, TT__EMBREE_VERSION);
  if (!s) return NULL;
  static const int64_t qualities[] = {1, 2, 3};
  static const int64_t factors[] = {2, 4, 8};
  static const char *const backends[] = {"native", "custom"};
  static const char *const updates[] = {"rebuild", "refit", "instances"};
  int ok = 1;
  ok &= tt_space_add_nom_int(s, "quality", qualities, 3, 1,
                             "BVH builder: 1 Morton (RTC_BUILD_QUALITY_LOW), 2 binned SAH "
                             "(MEDIUM), 3 SAH with spatial splits (HIGH); native and custom") >= 0;
  ok &= tt_space_add_nom_int(s, "branchingFactor", factors, 3, 0,
                             "children per inner node (maxBranchingFactor; our BVH2/4/8 "
                             "layout); custom backend only (native Embree picks its own "
                             "BVH4/BVH8)") >= 0;
  ok &= tt_space_add_int(s, "maxDepth", 8, 64, TT__EMBREE_DEF_MAX_DEPTH,
                         "maximum BVH depth (the last 8 levels split by object median); "
                         "custom backend only") >= 0;
  ok &= tt_space_add_int(s, "sahBlockSize", 1, 32, TT__EMBREE_DEF_SAH_BLOCK,
                         "SAH leaf cost granularity (primitives per block; only powers of two "
                         "act, others are rounded down by the check); custom backend only") >= 0;
  ok &= tt_space_add_int(s, "minLeafSize", 1, 32, TT__EMBREE_DEF_MIN_LEAF,
                         "minimum primitives per leaf; custom backend only") >= 0;
  ok &= tt_space_add_int(s, "maxLeafSize", 1, 32, TT__EMBREE_DEF_MAX_LEAF,
                         "maximum primitives per leaf; custom backend only") >= 0;
  ok &= tt_space_add_float(s, "travcost", 0.1, 10.0, TT__EMBREE_DEF_TRAV_COST, 0,
                           "SAH cost of traversing a node (only travcost/intcost acts); "
                           "custom backend only") >= 0;
  ok &= tt_space_add_float(s, "intcost", 0.1, 10.0, TT__EMBREE_DEF_INT_COST, 0,
                           "SAH cost of intersecting a primitive (only travcost/intcost "
                           "acts); custom backend only") >= 0;
  ok &= tt_space_add_nom_bool(s, "static", 0,
                              "scene never changes; false sets RTC_SCENE_FLAG_DYNAMIC (faster "
                              "build, slower traversal); native backend (custom passes "
                              "RTC_BUILD_FLAG_DYNAMIC, a no-op in Embree 3.13.5)") >= 0;
  ok &= tt_space_add_nom_bool(s, "compact", 0,
                              "RTC_SCENE_FLAG_COMPACT: smaller structure, slower traversal; "
                              "native backend (custom falls back to native)") >= 0;
  ok &= tt_space_add_nom_bool(s, "robust", 0,
                              "RTC_SCENE_FLAG_ROBUST in native; watertight triangle test and "
                              "conservative box test in custom") >= 0;
  ok &= tt_space_add_nom_string(s, "backend", backends, 2, TT__EMBREE_DEF_BACKEND,
                                "native: Embree's scene API (only quality, static, compact, "
                                "robust act); custom: rtcBuildBVH with every parameter, our "
                                "SIMD traversal") >= 0;
  ok &= tt_space_add_nom_bool(s, "counters", 0,
                              "instrumentation, not a tuning parameter: count rays, nodes "
                              "visited and triangles tested (custom backend; slows queries)") >= 0;
  /* The per-frame update of an animated scene (appended: the Table 3.1 indices stay). */
  ok &= tt_space_add_nom_string(s, "updateMethod", updates, 3, TT__EMBREE_UPDATE_REBUILD,
                                "when an animated scene moves: rebuild (from scratch with "
                                "these parameters), refit (keep the tree, recompute its "
                                "boxes; native: RTC_BUILD_QUALITY_REFIT on a dynamic scene "
                                "for the moving meshes) or instances (two-level: each rigid "
                                "mesh an Embree instance of its own BVH, built once; only "
                                "the top level rebuilt, deforming meshes refitted; native, "
                                "custom falls back to it); nothing changes for a still "
                                "scene") >= 0;
  ok &= tt_space_add_int(s, "refitInterval", 0, 64, 0,
                         "refit, instances: build from scratch every this many updates "
                         "(0: never)") >= 0;
  ok &= tt_space_add_float(s, "refitSahGrowth", 0.0, 8.0, 0.0, 0,
                           "refit: build from scratch once the refitted tree's SAH cost "
                           "exceeds this many times its cost when built (0: never; "
                           "native: Embree's trees are opaque, so the cost is that of a tree "
                           "of the moving meshes' build-time Morton groups of 4, refitted "
                           "alike)") >= 0;
  /* What tuners may change (tunetrace/params.h): counters is instrumentation, not a tuning
   * parameter; the custom builder's settings act only with backend custom and compact false
   * (compact=true builds with native). "static" acts with native and with custom+compact
   * (a disjunction the conditions cannot say), so it stays unconditional: searching a
   * parameter that sometimes does nothing wastes measurements, marking one inactive that
   * acts would lose configurations. */
  static const char *const custom[] = {"custom"}, *const no[] = {"false"};
  if (ok) ok &= tt_space_set_tunable(s, (size_t)tt_space_find(s, "counters"), 0) == TT_OK;
  /* The update parameters act only when an animated scene moves: tunable along a sequence,
   * whose tuning measures each frame's update + render, and left out of a still scene's
   * search by the tuning plan (motion-only), where no measurement tells them apart. */
  static const char *const update_params[] = {"updateMethod", "refitInterval", "refitSahGrowth"};
  for (size_t i = 0; ok && i < sizeof update_params / sizeof update_params[0]; i++)
    ok &= tt_space_set_motion_only(s, (size_t)tt_space_find(s, update_params[i]), 1) == TT_OK;
  for (size_t i = 0; ok && i < sizeof tt__embree_custom_only / sizeof tt__embree_custom_only[0];
       i++) {
    size_t k = (size_t)tt_space_find(s, tt__embree_custom_only[i].name);
    ok &= tt_space_add_condition(s, k, "backend", custom, 1) == TT_OK &&
          tt_space_add_condition(s, k, "compact", no, 1) == TT_OK;
  }
  static const char *const refit[] = {"refit", "instances"};
  if (ok)
    ok &= tt_space_add_condition(s, (size_t)tt_space_find(s, "refitInterval"), "updateMethod",
                                 refit, 2) == TT_OK &&
          tt_space_add_condition(s, (size_t)tt_space_find(s, "refitSahGrowth"), "updateMethod",
                                 refit, 1) == TT_OK;
  if (!ok) {
    tt_space_destroy(s);
    tt_set_error(TT_ERR_INTERNAL, "accel_embree: could not build the parameter space");
    return NULL;
  }
  tt_space_add_constraint_text(s, "minLeafSize <= maxLeafSize (repaired by swapping)");
  tt_space_add_constraint_text(s, "quality 1 (Morton) requires branchingFactor <= 8 and "
                                  "maxLeafSize <= 32 (custom builder)");
  tt_space_add_constraint_text(s, "branchingFactor^(maxDepth-1)*maxLeafSize >= triangle count "
                                  "(custom backend; checked at build time: TT_ERR_INFEASIBLE "
                                  "naming the smallest feasible maxDepth; an unbalanced SAH "
                                  "tree may still hit Embree's \"depth limit reached\", "
                                  "also reported as infeasible)");
  tt_space_add_constraint_text(s, "sahBlockSize acts through its largest power of two "
                                  "(repaired: rounded down)");
  tt_space_add_constraint_text(s, "only the ratio travcost/intcost acts (Embree compares "
                                  "intcost*blocks with travcost + split cost); quality 1 "
                                  "(Morton) ignores sahBlockSize, travcost and intcost");
  tt_space_add_constraint_text(s, "compact=true with backend custom builds with backend "
                                  "native (logged)");
  tt_space_set_check(s, tt__embree_check, NULL);
  return s;
}

/* Decodes by name, so the decoding survives reordering of the space. */
void tt__embree_settings_from_config(const tt_config *c, tt__embree_settings *o) {
  o->quality = (int)tt_config_get_int(c, "quality", TT__EMBREE_DEF_QUALITY);
  o->branching_factor = (int)tt_config_get_int(c, "branchingFactor", TT__EMBREE_DEF_BF);
  o->max_depth = (int)tt_config_get_int(c, "maxDepth", TT__EMBREE_DEF_MAX_DEPTH);
  o->sah_block_size = (int)tt_config_get_int(c, "sahBlockSize", TT__EMBREE_DEF_SAH_BLOCK);
  o->min_leaf_size = (int)tt_config_get_int(c, "minLeafSize", TT__EMBREE_DEF_MIN_LEAF);
  o->max_leaf_size = (int)tt_config_get_int(c, "maxLeafSize", TT__EMBREE_DEF_MAX_LEAF);
  o->trav_cost = (float)tt_config_get_float(c, "travcost", TT__EMBREE_DEF_TRAV_COST);
  o->int_cost = (float)tt_config_get_float(c, "intcost", TT__EMBREE_DEF_INT_COST);
  o->is_static = (int)tt_config_get_int(c, "static", 0);
  o->compact = (int)tt_config_get_int(c, "compact", 0);
  o->robust = (int)tt_config_get_int(c, "robust", 0);
  o->backend = (int)tt_config_get_int(c, "backend", TT__EMBREE_DEF_BACKEND);
  o->counters = (int)tt_config_get_int(c, "counters", 0);
  o->update_method = (int)tt_config_get_int(c, "updateMethod", TT__EMBREE_UPDATE_REBUILD);
  o->refit_interval = (int)tt_config_get_int(c, "refitInterval", 0);
  o->refit_sah_growth = (float)tt_config_get_float(c, "refitSahGrowth", 0.0);
}

/* Lists custom-only parameters set away from their defaults (for the native-backend WARN). */
int tt__embree_custom_only_changed(const tt_config *config, char *buf, size_t size) {
  int n = 0;
  size_t used = 0;
  if (size) buf[0] = '\0';
  for (size_t i = 0; i < sizeof tt__embree_custom_only / sizeof tt__embree_custom_only[0]; i++) {
    double v =
        tt_config_get_float(config, tt__embree_custom_only[i].name, tt__embree_custom_only[i].def);
    if (v == tt__embree_custom_only[i].def) continue;
    if (used < size) {
      int w =
          snprintf(buf + used, size - used, "%s%s", n ? ", " : "", tt__embree_custom_only[i].name);
      if (w > 0) used += (size_t)w;
    }
    n++;
  }
  return n;
}
