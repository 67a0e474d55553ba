/* accel_embree: an acceleration-structure plugin over Embree 3.
 *
 * Backend "native" builds through Embree's scene API: one RTC_GEOMETRY_TYPE_TRIANGLE per
 * scene mesh (geomID = mesh index), build quality and scene flags from the configuration,
 * rtcCommitScene. Queries map one to one onto rtcIntersect1/rtcOccluded1 and the stream
 * calls rtcIntersect1M/rtcOccluded1M.
 *
 * Backend "custom" builds with rtcBuildBVH and every numeric parameter, lays the tree out
 * itself and traverses it with its own SIMD kernels (accel_embree_custom.c,
 * accel_embree_trav.c); `compact` falls back to native, which has the only compact layout.
 *
 * update() (an animated scene moved): "updateMethod" rebuild builds from scratch with the
 * same settings; refit keeps the tree and recomputes its boxes -- native: the moving meshes
 * were attached with RTC_BUILD_QUALITY_REFIT to a dynamic scene, their vertex buffers are
 * rewritten and the scene committed again; custom: tt__embree_custom_refit, bottom-up -- with a
 * rebuild every refitInterval updates or once the SAH cost grew by refitSahGrowth;
 * instances (native; custom falls back to it) is two-level: each rigid mesh an Embree
 * instance of its own BVH, only the top level rebuilt (accel_embree_inst.c). */
#include "accel_embree.h"
#include "accel_embree_bvh.h"

#include <tunetrace/plugin.h>

#include <embree3/rtcore.h>

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#if RTC_VERSION_MAJOR != 3
#  error "accel_embree needs Embree 3 (rtcore.h of another major version found)"
#endif

/* Rays converted per stream chunk: 64 RTCRayHit live on the stack (about 6 KiB), so the
 * stream calls never allocate. */
#define TT__EMBREE_CHUNK 64

struct tt_accel {
  RTCScene scene;             /* native backend (NULL for custom) */
  tt__embree_bvh *bvh;        /* custom backend (NULL for native) */
  tt__embree_kernels kernels; /* custom: the traversal kernels for this tree's shape */
  int counting;               /* custom with counters on */
  const tt_scene *source;     /* must outlive us (accel.h contract) */
  tt__embree_settings settings;
  /* update(): native refit keeps each moving mesh's Embree vertex buffer (NULL for meshes
   * attached with the tuned quality) and the revision it holds */
  float **vbuf;
  uint64_t *vrev;
  tt__embree_inst *inst;     /* updateMethod=instances on an animated scene (native): the
                                two-level structure, whose top level is `scene` */
  tt__embree_growth *growth; /* native refit with refitSahGrowth: the SAH estimate */
  uint32_t since_rebuild;    /* updates since the last build from scratch */
  double sah_built;          /* SAH cost when last built from scratch (0 unknown) */
};

/* Plugin-wide state: set in init, released in deinit (both on the host's main thread). */
static const tt_host *g_host;
static RTCDevice g_device;
static tt_space *g_space;
/* Bytes Embree holds right now, fed by the device's memory monitor from any thread. */
static _Atomic long long g_embree_bytes;
/* Set once the native-backend "these parameters do nothing" warning has been logged. */
static atomic_flag g_warned_custom_only = ATOMIC_FLAG_INIT;
/* Set once the "compact falls back to native" note has been logged. */
static atomic_flag g_noted_compact = ATOMIC_FLAG_INIT;
/* Set once the "instances fall back to native" note has been logged. */
static atomic_flag g_noted_instances = ATOMIC_FLAG_INIT;
/* Last Embree error message seen on this thread, so build() can put it in its error. */
static _Thread_local char g_embree_error[256];
/* Non-zero while this thread expects (and reports) Embree errors itself. */
static _Thread_local int g_embree_quiet;
/* Custom backend kernels for this CPU (chosen at init). */
static const tt__embree_kernel_table *g_kernels;
static const char *g_kernels_isa;

/* Embree's error callback: log through the host and keep the text for tt_set_error. */
static void tt__embree_error(void *user, enum RTCError code, const char *str) {
  const tt_host *host = user;
  snprintf(g_embree_error, sizeof g_embree_error, "Embree error %d: %s", (int)code,
           str ? str : "(no message)");
  if (host)
    tt_host_log(host, g_embree_quiet ? TT_LOG_DEBUG : TT_LOG_ERROR, TT__EMBREE_NAME, "%s",
                g_embree_error);
}

/* The device (accel_embree_inst.c creates its scenes and instances on it). */
RTCDevice tt__embree_device(void) { return g_device; }

/* The calling thread's last Embree error text. */
const char *tt__embree_last_error(void) { return g_embree_error; }

/* Downgrades this thread's Embree error logging while a failure is expected. */
void tt__embree_set_quiet(int quiet) { g_embree_quiet = quiet; }

/* Embree's memory monitor: every allocation/free is reported once; keep a running total. */
static bool tt__embree_memory(void *user, ssize_t bytes, bool post) {
  (void)user;
  (void)post;
  atomic_fetch_add_explicit(&g_embree_bytes, (long long)bytes, memory_order_relaxed);
  return true; /* never veto: the host has no memory budget in ABI 1.0 */
}

/* Reads and clears Embree's per-thread error code; returns TT_OK or an error naming it. */
tt_status tt__embree_status(const char *what) {
  enum RTCError e = rtcGetDeviceError(g_device);
  if (e == RTC_ERROR_NONE) return TT_OK;
  tt_status s = e == RTC_ERROR_OUT_OF_MEMORY      ? TT_ERR_OUT_OF_MEMORY
                : e == RTC_ERROR_UNSUPPORTED_CPU  ? TT_ERR_UNSUPPORTED
                : e == RTC_ERROR_INVALID_ARGUMENT ? TT_ERR_INVALID_ARGUMENT
                                                  : TT_ERR_INTERNAL;
  return tt_set_error(s, "accel_embree: %s failed: %s", what,
                      g_embree_error[0] ? g_embree_error : "Embree reported an error");
}

/* ---- parameter space ---- */

/* The space built at init. */
static const tt_space *tt__embree_space(void) { return g_space; }

/* ---- build / destroy ---- */

/* Releases the Embree scene or our tree (the wrapper stays, for a rebuild in place). */
static void tt__embree_release(tt_accel *accel) {
  if (accel->scene) rtcReleaseScene(accel->scene);
  accel->scene = NULL;
  tt__embree_custom_free(accel->bvh);
  accel->bvh = NULL;
  tt__embree_inst_free(accel->inst);
  accel->inst = NULL;
  tt__embree_growth_free(accel->growth);
  accel->growth = NULL;
  free(accel->vbuf);
  free(accel->vrev);
  accel->vbuf = NULL;
  accel->vrev = NULL;
}

/* Releases the structure and the wrapper. */
static void tt__embree_destroy(tt_accel *accel) {
  if (!accel) return;
  tt__embree_release(accel);
  free(accel);
}

/* Non-zero when tt_scene_set_time may move the mesh (read only where struct_size has it). */
int tt__embree_mesh_moves(const tt_mesh *m) {
  return TT_HAS_FIELD(tt_mesh, m, motion) && m->motion != TT_MESH_STATIC;
}

/* Checks a mesh before Embree sees it: Embree does not validate indices and would read out
 * of bounds on a bad one, so we reject instead of crashing. */
static tt_status tt__embree_check_mesh(const tt_mesh *m, uint32_t index) {
  if (!m) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "accel_embree: mesh %u is NULL", index);
  if (m->triangle_count == 0) return TT_OK;
  if (!m->positions || !m->indices || m->vertex_count == 0)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "accel_embree: mesh %u (\"%s\") has triangles but no vertex or index "
                        "data",
                        index, m->name ? m->name : "?");
  const uint64_t n = 3ull * m->triangle_count;
  for (uint64_t k = 0; k < n; k++) {
    if (m->indices[k] >= m->vertex_count)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          "accel_embree: mesh %u (\"%s\") triangle %llu uses vertex %u of %u",
                          index, m->name ? m->name : "?", (unsigned long long)(k / 3),
                          m->indices[k], m->vertex_count);
  }
  return TT_OK;
}

/* Creates the triangle geometry for mesh `index` over `positions` (3 * vertex_count: the
 * mesh's world positions, or its object-space ones for an instance) and attaches it under
 * geomID = index; `*vbuf` (if set) receives its Embree vertex buffer. */
tt_status tt__embree_attach_mesh(RTCScene scene, const tt_mesh *m, const float *positions,
                                 uint32_t index, int quality, float **vbuf) {
  RTCGeometry g = rtcNewGeometry(g_device, RTC_GEOMETRY_TYPE_TRIANGLE);
  if (!g) return tt__embree_status("rtcNewGeometry");
  /* Positions are copied into an Embree-allocated buffer: Embree reads vertices with
   * 16-byte loads, i.e. 4 bytes past the last float, which the scene's array does not
   * promise. Indices have no such requirement and are shared. */
  float *pos = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       3 * sizeof(float), m->vertex_count);
  if (!pos) {
    rtcReleaseGeometry(g);
    return tt__embree_status("rtcSetNewGeometryBuffer (vertices)");
  }
  memcpy(pos, positions, (size_t)m->vertex_count * 3 * sizeof(float));
  if (vbuf) *vbuf = pos;
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m->indices, 0,
                             3 * sizeof(uint32_t), m->triangle_count);
  /* Per-geometry quality matters for two-level (dynamic) builds, where each mesh gets its
   * own BVH; setting it too keeps "quality" meaningful in every flag combination. */
  rtcSetGeometryBuildQuality(g, (enum RTCBuildQuality)quality);
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(scene, g, index);
  rtcReleaseGeometry(g); /* the scene holds its own reference */
  return tt__embree_status("attaching a mesh");
}

/* Builds with backend native: Embree's scene API and its own builders. */
static tt_status tt__embree_build_native(const tt_scene *scene, const tt__embree_settings *st,
                                         tt_accel *acc, tt_accel_build_stats *stats) {
  static const enum RTCBuildQuality qualities[] = {RTC_BUILD_QUALITY_LOW, RTC_BUILD_QUALITY_MEDIUM,
                                                   RTC_BUILD_QUALITY_HIGH};
  enum RTCBuildQuality quality =
      qualities[st->quality >= 1 && st->quality <= 3 ? st->quality - 1 : 1];
  /* Refit needs Embree's two-level (dynamic) scene: each moving mesh gets its own BVH,
   * refitted on commit; the still meshes keep the tuned quality. A still scene builds as
   * if updateMethod were rebuild. */
  const int refit = st->update_method == TT__EMBREE_UPDATE_REFIT && tt_scene_animated(scene);
  int flags = RTC_SCENE_FLAG_NONE;
  if (!st->is_static || refit) flags |= RTC_SCENE_FLAG_DYNAMIC;
  if (st->compact) flags |= RTC_SCENE_FLAG_COMPACT;
  if (st->robust) flags |= RTC_SCENE_FLAG_ROBUST;

  long long bytes0 = atomic_load(&g_embree_bytes);
  if (st->update_method == TT__EMBREE_UPDATE_INSTANCES && tt_scene_animated(scene)) {
    const uint64_t t0 = g_host->clock_ns();
    tt_status s = tt__embree_inst_build(scene, st, (int)quality, &acc->inst, &acc->scene);
    if (s != TT_OK) return s;
    rtcRetainScene(acc->scene); /* acc->scene is released like any native scene */
    long long bytes = atomic_load(&g_embree_bytes) - bytes0;
    stats->build_ms = (double)(g_host->clock_ns() - t0) * 1e-6;
    stats->memory_bytes = bytes > 0 ? (uint64_t)bytes : 0;
    return TT_OK;
  }
  acc->scene = rtcNewScene(g_device);
  if (!acc->scene) return tt__embree_status("rtcNewScene");
  rtcSetSceneFlags(acc->scene, (enum RTCSceneFlags)flags);
  /* Embree honours the per-geometry build quality (REFIT for the moving meshes, the tuned
   * quality for the still ones) only in its two-level build, which the scene's quality LOW
   * selects; at MEDIUM or HIGH it builds one BVH over every triangle and rebuilds it all on
   * each commit, so a "refit" cost a full rebuild (living-room-cylinder: 204 ms against
   * 220 ms). */
  rtcSetSceneBuildQuality(acc->scene, refit ? RTC_BUILD_QUALITY_LOW : quality);

  const uint32_t meshes = tt_scene_mesh_count(scene);
  if (refit) {
    acc->vbuf = calloc(meshes, sizeof *acc->vbuf);
    acc->vrev = calloc(meshes, sizeof *acc->vrev);
    if (!acc->vbuf || !acc->vrev)
      return tt_set_error(TT_ERR_OUT_OF_MEMORY, "accel_embree: out of memory");
  }
  for (uint32_t i = 0; i < meshes; i++) {
    const tt_mesh *m = tt_scene_mesh(scene, i);
    if (m->triangle_count == 0) continue; /* geomIDs may have gaps; Embree allows it */
    const int moving = refit && tt__embree_mesh_moves(m);
    tt_status s = tt__embree_attach_mesh(acc->scene, m, m->positions, i,
                                         moving ? RTC_BUILD_QUALITY_REFIT : quality,
                                         moving ? &acc->vbuf[i] : NULL);
    if (s != TT_OK) return s;
    if (moving) acc->vrev[i] = m->revision;
  }

  const uint64_t t0 = g_host->clock_ns();
  rtcCommitScene(acc->scene);
  if (refit && st->refit_sah_growth > 0.0f) {
    /* part of the build: it is redone with every build from scratch */
    acc->growth = tt__embree_growth_create(scene, (const float *const *)acc->vbuf);
    if (!acc->growth) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "accel_embree: out of memory");
  }
  const uint64_t t1 = g_host->clock_ns();
  tt_status s = tt__embree_status("rtcCommitScene");
  if (s != TT_OK) return s;

  long long bytes = atomic_load(&g_embree_bytes) - bytes0;
  stats->build_ms = (double)(t1 - t0) * 1e-6;
  stats->memory_bytes = bytes > 0 ? (uint64_t)bytes : 0;
  return TT_OK;
}

static tt_status tt__embree_build_backend(tt_accel *acc, tt_accel_build_stats *out);

/* Validates the inputs, checks/repairs the configuration and dispatches on the backend. */
static tt_status tt__embree_build(const tt_scene *scene, const tt_config *config, tt_accel **out,
                                  tt_accel_build_stats *stats_out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "accel_embree: build: out is NULL");
  *out = NULL;
  if (!g_device || !g_space)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "accel_embree: build before init");
  if (!scene) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "accel_embree: build: scene is NULL");
  if (config) {
    const char *owner = tt_space_plugin(tt_config_space(config));
    if (!owner || strcmp(owner, TT__EMBREE_NAME) != 0)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          "accel_embree: build: the configuration belongs to plugin \"%s\"",
                          owner ? owner : "?");
  }

  uint64_t triangles = 0;
  const uint32_t meshes = tt_scene_mesh_count(scene);
  for (uint32_t i = 0; i < meshes; i++) {
    const tt_mesh *m = tt_scene_mesh(scene, i);
    tt_status s = tt__embree_check_mesh(m, i);
    if (s != TT_OK) return s;
    triangles += m->triangle_count;
  }
  if (triangles == 0)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "accel_embree: scene \"%s\" has no triangles (%u meshes): nothing to "
                        "build",
                        tt_scene_source(scene) ? tt_scene_source(scene) : "?", meshes);

  /* The check may repair, and `config` is const: work on a copy. */
  tt_config *cfg = config ? tt_config_clone(config) : tt_config_create(g_space);
  if (!cfg) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "accel_embree: cannot copy the config");
  char why[256] = "";
  tt_check_result cr = tt__embree_check_config(cfg, why, sizeof why);
  if (cr == TT_CHECK_INFEASIBLE) {
    tt_config_destroy(cfg);
    return tt_set_error(TT_ERR_INFEASIBLE, "accel_embree: infeasible configuration: %s", why);
  }
  tt__embree_settings st;
  tt__embree_settings_from_config(cfg, &st);

  if (st.backend == TT__EMBREE_BACKEND_CUSTOM && st.compact) {
    /* Our layout has no compact (index-leaf) variant; Embree's scene API has one. */
    if (!atomic_flag_test_and_set(&g_noted_compact))
      tt_host_log(g_host, TT_LOG_INFO, TT__EMBREE_NAME,
                  "compact=true: backend custom falls back to native (Embree's compact BVH4 "
                  "with index leaves); logged once");
    st.backend = TT__EMBREE_BACKEND_NATIVE;
  } else if (st.backend == TT__EMBREE_BACKEND_CUSTOM &&
             st.update_method == TT__EMBREE_UPDATE_INSTANCES && tt_scene_animated(scene)) {
    /* Our kernels traverse one tree; instances are Embree's (RTC_GEOMETRY_TYPE_INSTANCE). */
    if (!atomic_flag_test_and_set(&g_noted_instances))
      tt_host_log(g_host, TT_LOG_INFO, TT__EMBREE_NAME,
                  "updateMethod=instances: backend custom falls back to native (Embree's "
                  "instances over per-object BVHs); logged once");
    st.backend = TT__EMBREE_BACKEND_NATIVE;
  } else if (st.backend == TT__EMBREE_BACKEND_NATIVE) {
    char names[160];
    if (tt__embree_custom_only_changed(cfg, names, sizeof names) > 0 &&
        !atomic_flag_test_and_set(&g_warned_custom_only))
      tt_host_log(g_host, TT_LOG_WARN, TT__EMBREE_NAME,
                  "backend native ignores %s (they act only in the custom backend); "
                  "logged once",
                  names);
  }
  tt_config_destroy(cfg);

  tt_accel *acc = calloc(1, sizeof *acc);
  if (!acc) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "accel_embree: out of memory");
  acc->source = scene;
  acc->settings = st;

  tt_accel_build_stats stats;
  memset(&stats, 0, sizeof stats);
  tt_status s = tt__embree_build_backend(acc, &stats);
  if (s != TT_OK) {
    tt__embree_destroy(acc);
    return s;
  }
  stats.repaired = cr == TT_CHECK_REPAIRED;
  if (stats.repaired)
    tt_host_log(g_host, TT_LOG_DEBUG, TT__EMBREE_NAME, "configuration repaired: %s", why);

  if (stats_out && stats_out->struct_size > sizeof stats_out->struct_size) {
    /* Fill only the prefix the caller knows (it may be built against an older header). */
    size_t n = stats_out->struct_size < sizeof stats ? stats_out->struct_size : sizeof stats;
    uint32_t caller_size = stats_out->struct_size;
    memcpy(stats_out, &stats, n);
    stats_out->struct_size = caller_size;
  }
  *out = acc;
  return TT_OK;
}

/* Builds acc's structure from scratch over acc->source with acc->settings (the wrapper
 * holds none: a new one, or one released for a rebuild). */
static tt_status tt__embree_build_backend(tt_accel *acc, tt_accel_build_stats *out) {
  const tt_scene *scene = acc->source;
  const tt__embree_settings st = acc->settings;
  tt_accel_build_stats stats;
  memset(&stats, 0, sizeof stats);
  rtcGetDeviceError(g_device); /* clear a stale code so only this build's errors count */
  g_embree_error[0] = '\0';

  tt_status s;
  switch (st.backend) {
  case TT__EMBREE_BACKEND_NATIVE: s = tt__embree_build_native(scene, &st, acc, &stats); break;
  case TT__EMBREE_BACKEND_CUSTOM: {
    if (!g_kernels) {
      s = tt_set_error(TT_ERR_UNSUPPORTED,
                       "accel_embree: backend custom needs SSE4.1, which this CPU lacks");
      break;
    }
    const uint64_t t0 = g_host->clock_ns();
    s = tt__embree_custom_build(scene, &st, g_device, &acc->bvh, &stats);
    stats.build_ms = (double)(g_host->clock_ns() - t0) * 1e-6;
    if (s != TT_OK) break;
    int w = st.branching_factor == 2 ? 0 : st.branching_factor == 4 ? 1 : 2;
    acc->counting = st.counters != 0;
    acc->kernels = (*g_kernels)[w][st.robust ? 1 : 0][acc->counting];
    break;
  }
  default:
    s = tt_set_error(TT_ERR_UNSUPPORTED, "accel_embree: unknown backend index %d", st.backend);
    break;
  }
  if (s != TT_OK) {
    tt__embree_release(acc);
    return s;
  }
  acc->since_rebuild = 0;
  acc->sah_built = acc->growth ? tt__embree_growth_cost(acc->growth, scene) : stats.sah_cost;
  *out = stats;
  return TT_OK;
}

/* ---- update (animated scenes) ---- */

/* Native refit: the moving meshes' vertex buffers take the new positions (only those
 * whose revision changed), and the commit refits their BVHs and rebuilds the top level. */
static tt_status tt__embree_refit_native(tt_accel *acc) {
  const tt_scene *scene = acc->source;
  const uint32_t meshes = tt_scene_mesh_count(scene);
  for (uint32_t i = 0; acc->vbuf && i < meshes; i++) {
    const tt_mesh *m = tt_scene_mesh(scene, i);
    if (!acc->vbuf[i] || m->revision == acc->vrev[i]) continue;
    memcpy(acc->vbuf[i], m->positions, (size_t)m->vertex_count * 3 * sizeof(float));
    RTCGeometry g = rtcGetGeometry(acc->scene, i);
    rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(g);
    acc->vrev[i] = m->revision;
  }
  rtcCommitScene(acc->scene);
  return tt__embree_status("rtcCommitScene (refit)");
}

/* Refit or rebuild, as the settings say (accel.h, update). */
static tt_status tt__embree_update(tt_accel *acc, tt_accel_update_stats *out) {
  if (!acc) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "accel_embree: update: accel is NULL");
  const tt__embree_settings *st = &acc->settings;
  const uint64_t t0 = g_host->clock_ns();
  rtcGetDeviceError(g_device);
  g_embree_error[0] = '\0';
  int rebuild = st->update_method == TT__EMBREE_UPDATE_REBUILD ||
                (st->refit_interval > 0 && acc->since_rebuild + 1u >= (uint32_t)st->refit_interval);
  double sah = 0.0;
  tt_status s = TT_OK;
  if (!rebuild && acc->inst) {
    s = tt__embree_inst_update(acc->inst);
  } else if (!rebuild && acc->bvh) {
    sah = tt__embree_custom_refit(acc->source, acc->bvh, g_host);
    /* the growth test needs the refitted cost, so a rebuild it asks for comes after */
    if (st->refit_sah_growth > 0.0f && acc->sah_built > 0.0 &&
        sah > (double)st->refit_sah_growth * acc->sah_built)
      rebuild = 1;
  } else if (!rebuild) {
    /* the estimate reads the new positions before Embree refits: a rebuild it asks for
     * replaces the refit instead of following it */
    if (acc->growth) {
      sah = tt__embree_growth_cost(acc->growth, acc->source);
      if (acc->sah_built > 0.0 && sah > (double)st->refit_sah_growth * acc->sah_built) rebuild = 1;
    }
    if (!rebuild) s = tt__embree_refit_native(acc);
  }
  if (s == TT_OK && rebuild) {
    tt__embree_release(acc);
    tt_accel_build_stats bs;
    s = tt__embree_build_backend(acc, &bs);
    sah = acc->growth ? acc->sah_built : bs.sah_cost;
  } else if (s == TT_OK) {
    acc->since_rebuild++;
  }
  if (s != TT_OK) return s;
  tt_accel_update_stats u;
  memset(&u, 0, sizeof u);
  u.update_ms = (double)(g_host->clock_ns() - t0) * 1e-6;
  u.rebuilt = rebuild;
  u.since_rebuild = acc->since_rebuild;
  u.sah_cost = sah;
  u.sah_growth = acc->sah_built > 0.0 && sah > 0.0 ? sah / acc->sah_built : 0.0;
  if (out && out->struct_size > sizeof out->struct_size) {
    uint32_t caller_size = out->struct_size;
    size_t n = caller_size < sizeof u ? caller_size : sizeof u;
    memcpy(out, &u, n);
    out->struct_size = caller_size;
  }
  return TT_OK;
}

/* ---- queries ---- */

/* tt_ray -> RTCRay (mask all ones, time 0, no ray id). */
static inline void tt__embree_to_rtc_ray(const tt_ray *r, struct RTCRay *e) {
  e->org_x = r->org[0];
  e->org_y = r->org[1];
  e->org_z = r->org[2];
  e->tnear = r->tnear;
  e->dir_x = r->dir[0];
  e->dir_y = r->dir[1];
  e->dir_z = r->dir[2];
  e->time = 0.0f;
  e->tfar = r->tfar;
  e->mask = 0xFFFFFFFFu;
  e->id = 0;
  e->flags = 0;
}

/* Marks an RTCHit as "no hit yet", as Embree requires before intersecting. */
static inline void tt__embree_clear_rtc_hit(struct RTCHit *h) {
  h->geomID = RTC_INVALID_GEOMETRY_ID;
  h->primID = RTC_INVALID_GEOMETRY_ID;
  for (int l = 0; l < RTC_MAX_INSTANCE_LEVEL_COUNT; l++) h->instID[l] = RTC_INVALID_GEOMETRY_ID;
}

/* Copies Embree's result back; on a miss the hit gets invalid ids, t = +inf and the ray
 * keeps its tfar. */
static inline void tt__embree_from_rtc_hit(const struct RTCRayHit *e, tt_ray *r, tt_hit *h) {
  if (e->hit.geomID == RTC_INVALID_GEOMETRY_ID) {
    h->t = INFINITY;
    h->u = h->v = 0.0f;
    h->geom_id = h->prim_id = TT_INVALID_ID;
    h->ng[0] = h->ng[1] = h->ng[2] = 0.0f;
    return;
  }
  r->tfar = e->ray.tfar;
  h->t = e->ray.tfar;
  h->u = e->hit.u;
  h->v = e->hit.v;
  h->geom_id = e->hit.geomID; /* == mesh index: attached by ID */
  h->prim_id = e->hit.primID;
  h->ng[0] = e->hit.Ng_x;
  h->ng[1] = e->hit.Ng_y;
  h->ng[2] = e->hit.Ng_z;
}

/* Closest hit of one ray. */
static void tt__embree_intersect1(const tt_accel *accel, tt_ray *ray, tt_hit *hit) {
  if (accel->bvh) {
    accel->kernels.intersect(accel->bvh, ray, hit);
    return;
  }
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  struct RTCRayHit rh;
  tt__embree_to_rtc_ray(ray, &rh.ray);
  tt__embree_clear_rtc_hit(&rh.hit);
  rtcIntersect1(accel->scene, &ctx, &rh);
  tt__embree_from_rtc_hit(&rh, ray, hit);
  if (accel->inst && rh.hit.geomID != RTC_INVALID_GEOMETRY_ID)
    tt__embree_inst_normal(accel->inst, rh.hit.instID[0], hit->ng);
}

/* Occlusion of one ray: Embree sets tfar to -inf when something blocks it. */
static int tt__embree_occluded1(const tt_accel *accel, const tt_ray *ray) {
  if (accel->bvh) return accel->kernels.occluded(accel->bvh, ray);
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  struct RTCRay r;
  tt__embree_to_rtc_ray(ray, &r);
  rtcOccluded1(accel->scene, &ctx, &r);
  return r.tfar < 0.0f && isinf(r.tfar);
}

/* Coherent if every ray of the chunk starts at the same point (camera rays, light rays
 * toward one light): Embree's coherent stream mode then pays off; otherwise incoherent. */
static enum RTCIntersectContextFlags tt__embree_chunk_coherence(const tt_ray *rays, size_t n) {
  for (size_t i = 1; i < n; i++) {
    if (rays[i].org[0] != rays[0].org[0] || rays[i].org[1] != rays[0].org[1] ||
        rays[i].org[2] != rays[0].org[2])
      return RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  }
  return RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
}

/* Closest hits of a stream, converted TT__EMBREE_CHUNK rays at a time on the stack. */
static void tt__embree_intersect_stream(const tt_accel *accel, tt_ray *rays, tt_hit *hits,
                                        size_t count) {
  if (accel->bvh) {
    accel->kernels.intersect_stream(accel->bvh, rays, hits, count);
    return;
  }
  struct RTCRayHit buf[TT__EMBREE_CHUNK];
  struct RTCIntersectContext ctx;
  for (size_t base = 0; base < count; base += TT__EMBREE_CHUNK) {
    size_t n = count - base < TT__EMBREE_CHUNK ? count - base : TT__EMBREE_CHUNK;
    for (size_t i = 0; i < n; i++) {
      tt__embree_to_rtc_ray(&rays[base + i], &buf[i].ray);
      tt__embree_clear_rtc_hit(&buf[i].hit);
    }
    rtcInitIntersectContext(&ctx);
    ctx.flags = tt__embree_chunk_coherence(rays + base, n);
    rtcIntersect1M(accel->scene, &ctx, buf, (unsigned)n, sizeof buf[0]);
    for (size_t i = 0; i < n; i++)
      tt__embree_from_rtc_hit(&buf[i], &rays[base + i], &hits[base + i]);
    if (accel->inst)
      for (size_t i = 0; i < n; i++)
        if (buf[i].hit.geomID != RTC_INVALID_GEOMETRY_ID)
          tt__embree_inst_normal(accel->inst, buf[i].hit.instID[0], hits[base + i].ng);
  }
}

/* Occlusion of a stream, chunked like intersect_stream. */
static void tt__embree_occluded_stream(const tt_accel *accel, const tt_ray *rays, uint8_t *occluded,
                                       size_t count) {
  if (accel->bvh) {
    accel->kernels.occluded_stream(accel->bvh, rays, occluded, count);
    return;
  }
  struct RTCRay buf[TT__EMBREE_CHUNK];
  struct RTCIntersectContext ctx;
  for (size_t base = 0; base < count; base += TT__EMBREE_CHUNK) {
    size_t n = count - base < TT__EMBREE_CHUNK ? count - base : TT__EMBREE_CHUNK;
    for (size_t i = 0; i < n; i++) tt__embree_to_rtc_ray(&rays[base + i], &buf[i]);
    rtcInitIntersectContext(&ctx);
    ctx.flags = tt__embree_chunk_coherence(rays + base, n);
    rtcOccluded1M(accel->scene, &ctx, buf, (unsigned)n, sizeof buf[0]);
    for (size_t i = 0; i < n; i++)
      occluded[base + i] = (uint8_t)(buf[i].tfar < 0.0f && isinf(buf[i].tfar));
  }
}

/* Custom backend with counters=true: the totals since the build (or the last reset).
 * Embree's scene API exposes no traversal statistics. */
static tt_status tt__embree_counters(tt_accel *accel, tt_accel_counters *out, int reset) {
  if (!accel || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "accel_embree: counters: NULL argument");
  if (!accel->bvh)
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "accel_embree: backend native has no traversal counters");
  if (!accel->counting)
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "accel_embree: counters are off (set accel_embree.counters=true)");
  tt_accel_counters c;
  memset(&c, 0, sizeof c);
  c.rays = atomic_load(&accel->bvh->c_rays);
  c.nodes_visited = atomic_load(&accel->bvh->c_nodes);
  c.triangles_tested = atomic_load(&accel->bvh->c_tris);
  if (reset) {
    atomic_store(&accel->bvh->c_rays, 0);
    atomic_store(&accel->bvh->c_nodes, 0);
    atomic_store(&accel->bvh->c_tris, 0);
  }
  /* Fill only the prefix the caller knows, like the build stats. */
  if (out->struct_size > sizeof out->struct_size) {
    uint32_t caller_size = out->struct_size;
    size_t n = caller_size < sizeof c ? caller_size : sizeof c;
    memcpy(out, &c, n);
    out->struct_size = caller_size;
  }
  return TT_OK;
}

static const tt_accel_iface g_iface = {
    .struct_size = sizeof(tt_accel_iface),
    .space = tt__embree_space,
    .build = tt__embree_build,
    .intersect1 = tt__embree_intersect1,
    .occluded1 = tt__embree_occluded1,
    .intersect_stream = tt__embree_intersect_stream,
    .occluded_stream = tt__embree_occluded_stream,
    .counters = tt__embree_counters,
    .destroy = tt__embree_destroy,
    .update = tt__embree_update,
};

/* ---- plugin entry ---- */

/* Releases the device and the space (every accel has been destroyed by now). */
static void tt__embree_deinit(void) {
  if (g_device) rtcReleaseDevice(g_device);
  g_device = NULL;
  if (g_space) tt_space_destroy(g_space);
  g_space = NULL;
  g_host = NULL;
}

/* Keeps the host, creates the Embree device with our error and memory callbacks, and
 * builds the parameter space once. */
static tt_status tt__embree_init(const tt_host *host) {
  if (!host || (!host->log && !TT_HOST_HAS(host, log_str)) || !host->clock_ns)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "accel_embree: the host table lacks a log (log or log_str) or clock_ns");
  g_host = host;
  atomic_store(&g_embree_bytes, 0);
  atomic_flag_clear(&g_warned_custom_only);
  atomic_flag_clear(&g_noted_compact);
  atomic_flag_clear(&g_noted_instances);
  /* Kernel set: AVX-512 (F, VL, DQ, BW) when the CPU has it, else AVX2+FMA when it has
   * both, else the SSE4.1 baseline; TT_ACCEL_EMBREE_ISA=avx2 or sse41 caps the choice
   * (tests run every set the CPU has). */
  __builtin_cpu_init();
  const char *isa = getenv("TT_ACCEL_EMBREE_ISA");
  g_kernels = NULL;
  g_kernels_isa = "none";
  const int avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                   __builtin_cpu_supports("popcnt");
  if (avx2 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
      !(isa && (strcmp(isa, "sse41") == 0 || strcmp(isa, "avx2") == 0))) {
    g_kernels = tt__embree_trav_table_avx512();
    g_kernels_isa = "avx512";
  } else if (avx2 && !(isa && strcmp(isa, "sse41") == 0)) {
    g_kernels = tt__embree_trav_table_avx2();
    g_kernels_isa = "avx2";
  } else if (__builtin_cpu_supports("sse4.1")) {
    g_kernels = tt__embree_trav_table_sse41();
    g_kernels_isa = "sse41";
  }
  tt_host_log(host, TT_LOG_DEBUG, TT__EMBREE_NAME, "custom backend kernels: %s", g_kernels_isa);
  /* Build with the host's worker count (--threads), so build times in tuning runs are
   * measured with the same parallelism as rendering. */
  char device_config[64] = "";
  if (host->thread_count)
    snprintf(device_config, sizeof device_config, "threads=%u", host->thread_count());
  g_device = rtcNewDevice(device_config[0] ? device_config : NULL);
  if (!g_device) {
    enum RTCError e = rtcGetDeviceError(NULL);
    g_host = NULL;
    return tt_set_error(e == RTC_ERROR_UNSUPPORTED_CPU ? TT_ERR_UNSUPPORTED : TT_ERR_INTERNAL,
                        "accel_embree: rtcNewDevice failed (Embree error %d%s)", (int)e,
                        e == RTC_ERROR_UNSUPPORTED_CPU ? ": CPU not supported" : "");
  }
  rtcSetDeviceErrorFunction(g_device, tt__embree_error, (void *)host);
  rtcSetDeviceMemoryMonitorFunction(g_device, tt__embree_memory, NULL);
  g_space = tt__embree_space_create();
  if (!g_space) {
    tt__embree_deinit(); /* the space builder already set the error message */
    return TT_ERR_INTERNAL;
  }
  return TT_OK;
}

/* Serves "tt.accel/1" only. */
static const void *tt__embree_get_interface(const char *id) {
  return id && strcmp(id, TT_ACCEL_INTERFACE_ID) == 0 ? &g_iface : NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
    .struct_size = sizeof(tt_plugin),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .kind = TT_KIND_ACCEL,
    .name = TT__EMBREE_NAME,
    .version = TT__EMBREE_VERSION,
    .description = "Embree 3 BVH: backend native (Embree's scene API) or custom (rtcBuildBVH, "
                   "own SIMD traversal); thesis Table 3.1 space",
    .init = tt__embree_init,
    .deinit = tt__embree_deinit,
    .get_interface = tt__embree_get_interface,
};
