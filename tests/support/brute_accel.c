/* Test support: brute-force ray/triangle queries over a tt_scene (see brute_accel.h). */
#include "brute_accel.h"

#include <math.h>
#include <stdlib.h>

typedef struct tt__brute_mesh {
  const tt_mesh *mesh;
  float lo[3], hi[3];
} tt__brute_mesh;

struct tt_accel {
  uint32_t count;
  tt__brute_mesh *meshes;
};

/* Collects meshes and their bounds. */
static tt_status brute_build(const tt_scene *scene, const tt_config *config, tt_accel **out,
                             tt_accel_build_stats *stats) {
  tt_accel *a = calloc(1, sizeof *a);
  if (!a) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "brute accel: out of memory");
  a->count = tt_scene_mesh_count(scene);
  a->meshes = calloc(a->count ? a->count : 1, sizeof *a->meshes);
  if (!a->meshes) {
    free(a);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "brute accel: out of memory");
  }
  for (uint32_t m = 0; m < a->count; ++m) {
    tt__brute_mesh *bm = &a->meshes[m];
    bm->mesh = tt_scene_mesh(scene, m);
    for (int i = 0; i < 3; ++i) {
      bm->lo[i] = INFINITY;
      bm->hi[i] = -INFINITY;
    }
    for (uint32_t v = 0; v < bm->mesh->vertex_count; ++v)
      for (int i = 0; i < 3; ++i) {
        float x = bm->mesh->positions[3 * v + i];
        if (x < bm->lo[i]) bm->lo[i] = x;
        if (x > bm->hi[i]) bm->hi[i] = x;
      }
  }
  if (stats && stats->struct_size >= sizeof(double) * 2) stats->build_ms = 0.0;
  *out = a;
  return TT_OK;
}

/* Slab test of the ray against a box, padded for flat meshes. */
static int box_hit(const tt__brute_mesh *bm, const tt_ray *r) {
  float t0 = r->tnear, t1 = r->tfar;
  for (int i = 0; i < 3; ++i) {
    float pad = 1e-4f * (1.0f + fabsf(bm->lo[i]) + fabsf(bm->hi[i]));
    float inv = 1.0f / r->dir[i];
    float a = (bm->lo[i] - pad - r->org[i]) * inv, b = (bm->hi[i] + pad - r->org[i]) * inv;
    if (a > b) {
      float t = a;
      a = b;
      b = t;
    }
    if (!(a <= b)) { /* NaN from 0 * inf: the ray is parallel and inside the slab */
      if (r->org[i] < bm->lo[i] - pad || r->org[i] > bm->hi[i] + pad) return 0;
      continue;
    }
    if (a > t0) t0 = a;
    if (b < t1) t1 = b;
    if (t0 > t1) return 0;
  }
  return 1;
}

/* Moeller-Trumbore; returns t in (tnear, tfar) or -1. */
static float tri_hit(const float *p0, const float *p1, const float *p2, const tt_ray *r,
                     float *u_out, float *v_out) {
  float e1[3], e2[3], pv[3], tv[3], qv[3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = p1[i] - p0[i];
    e2[i] = p2[i] - p0[i];
  }
  pv[0] = r->dir[1] * e2[2] - r->dir[2] * e2[1];
  pv[1] = r->dir[2] * e2[0] - r->dir[0] * e2[2];
  pv[2] = r->dir[0] * e2[1] - r->dir[1] * e2[0];
  float det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
  if (det == 0.0f) return -1.0f;
  float inv = 1.0f / det;
  for (int i = 0; i < 3; ++i) tv[i] = r->org[i] - p0[i];
  float u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) * inv;
  if (u < 0.0f || u > 1.0f) return -1.0f;
  qv[0] = tv[1] * e1[2] - tv[2] * e1[1];
  qv[1] = tv[2] * e1[0] - tv[0] * e1[2];
  qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
  float v = (r->dir[0] * qv[0] + r->dir[1] * qv[1] + r->dir[2] * qv[2]) * inv;
  if (v < 0.0f || u + v > 1.0f) return -1.0f;
  float t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) * inv;
  if (!(t > r->tnear) || !(t < r->tfar)) return -1.0f;
  *u_out = u;
  *v_out = v;
  return t;
}

/* Closest hit over all triangles (any_hit: stop at the first). */
static int brute_trace(const tt_accel *a, tt_ray *r, tt_hit *hit, int any_hit) {
  int found = 0;
  for (uint32_t m = 0; m < a->count; ++m) {
    const tt__brute_mesh *bm = &a->meshes[m];
    if (!box_hit(bm, r)) continue;
    const tt_mesh *mesh = bm->mesh;
    for (uint32_t t = 0; t < mesh->triangle_count; ++t) {
      const uint32_t *idx = mesh->indices + 3 * (size_t)t;
      const float *p0 = mesh->positions + 3 * idx[0], *p1 = mesh->positions + 3 * idx[1],
                  *p2 = mesh->positions + 3 * idx[2];
      float u, v, th = tri_hit(p0, p1, p2, r, &u, &v);
      if (th < 0.0f) continue;
      if (any_hit) return 1;
      found = 1;
      r->tfar = th;
      hit->t = th;
      hit->u = u;
      hit->v = v;
      hit->geom_id = m;
      hit->prim_id = t;
      float e1[3], e2[3];
      for (int i = 0; i < 3; ++i) {
        e1[i] = p1[i] - p0[i];
        e2[i] = p2[i] - p0[i];
      }
      hit->ng[0] = e1[1] * e2[2] - e1[2] * e2[1];
      hit->ng[1] = e1[2] * e2[0] - e1[0] * e2[2];
      hit->ng[2] = e1[0] * e2[1] - e1[1] * e2[0];
    }
  }
  return found;
}

static void brute_intersect1(const tt_accel *a, tt_ray *r, tt_hit *hit) {
  hit->geom_id = TT_INVALID_ID;
  hit->prim_id = TT_INVALID_ID;
  brute_trace(a, r, hit, 0);
}

static int brute_occluded1(const tt_accel *a, const tt_ray *r) {
  tt_ray copy = *r;
  tt_hit h;
  return brute_trace(a, &copy, &h, 1);
}

static void brute_intersect_stream(const tt_accel *a, tt_ray *rays, tt_hit *hits, size_t n) {
  for (size_t i = 0; i < n; ++i) brute_intersect1(a, &rays[i], &hits[i]);
}

static void brute_occluded_stream(const tt_accel *a, const tt_ray *rays, uint8_t *occ, size_t n) {
  for (size_t i = 0; i < n; ++i) occ[i] = (uint8_t)brute_occluded1(a, &rays[i]);
}

static tt_status brute_counters(tt_accel *a, tt_accel_counters *out, int reset) {
  return tt_set_error(TT_ERR_UNSUPPORTED, "brute accel: no counters");
}

static const tt_space *brute_space(void) { return NULL; }

static void brute_destroy(tt_accel *a) {
  if (!a) return;
  free(a->meshes);
  free(a);
}

/* An ABI 1.1 table (no update): callers that move the scene build it again. */
static const tt_accel_iface brute_iface = {TT_ACCEL_IFACE_SIZE_1_1,
                                           brute_space,
                                           brute_build,
                                           brute_intersect1,
                                           brute_occluded1,
                                           brute_intersect_stream,
                                           brute_occluded_stream,
                                           brute_counters,
                                           brute_destroy,
                                           NULL};

const tt_accel_iface *tt_test_brute_accel(void) { return &brute_iface; }
