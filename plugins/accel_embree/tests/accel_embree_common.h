/* Helpers shared by the accel_embree tests: loading the plugin through the registry,
 * random-triangle scenes as inline-mesh JSON, random rays, and a brute-force double
 * precision Moller-Trumbore reference. Header-only (static functions): each test is one
 * executable. */
#ifndef TT_ACCEL_EMBREE_COMMON_H
#define TT_ACCEL_EMBREE_COMMON_H

#include <tunetrace/accel.h>
#include <tunetrace/loader.h>
#include <tunetrace/tunetrace.h>

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tt_test.h"

/* ---- deterministic random numbers (xorshift64*) ---- */

typedef struct ae_rng {
  uint64_t s;
} ae_rng;

/* Next 64 random bits. */
static inline uint64_t ae_next(ae_rng *r) {
  r->s ^= r->s >> 12;
  r->s ^= r->s << 25;
  r->s ^= r->s >> 27;
  return r->s * 2685821657736338717ull;
}

/* Uniform in [lo, hi). */
static inline double ae_uniform(ae_rng *r, double lo, double hi) {
  return lo + (hi - lo) * (double)(ae_next(r) >> 11) * (1.0 / 9007199254740992.0);
}

/* ---- growable text buffer for building scene JSON ---- */

typedef struct ae_buf {
  char *p;
  size_t len, cap;
} ae_buf;

/* Appends printf-formatted text, growing the buffer geometrically. */
static inline void ae_printf(ae_buf *b, const char *fmt, ...) TT_PRINTF(2, 3);
static inline void ae_printf(ae_buf *b, const char *fmt, ...) {
  for (;;) {
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(b->p ? b->p + b->len : NULL, b->p ? b->cap - b->len : 0, fmt, ap);
    va_end(ap);
    if (n < 0) abort();
    if (b->p && b->len + (size_t)n < b->cap) {
      b->len += (size_t)n;
      return;
    }
    size_t cap = b->cap ? b->cap * 2 : 1 << 16;
    while (cap < b->len + (size_t)n + 1) cap *= 2;
    b->p = realloc(b->p, cap);
    if (!b->p) abort();
    b->cap = cap;
  }
}

/* ---- scenes ---- */

/* Opens the JSON of a scene whose meshes follow (camera and one material). */
static inline void ae_scene_begin(ae_buf *b) {
  ae_printf(b, "{\"version\":1,\"camera\":{\"position\":[0,0,5],\"target\":[0,0,0],"
               "\"up\":[0,1,0],\"fov\":45,\"resolution\":[64,64]},"
               "\"materials\":{\"m\":{\"type\":\"diffuse\",\"albedo\":[0.5,0.5,0.5]}},"
               "\"meshes\":[");
}

/* Appends one inline mesh; `first` omits the separating comma. %.9g round-trips floats. */
static inline void ae_scene_mesh(ae_buf *b, int first, const char *name, const float *pos,
                                 uint32_t vertex_count, const uint32_t *idx, uint32_t tri_count) {
  ae_printf(b, "%s{\"name\":\"%s\",\"material\":\"m\",\"positions\":[", first ? "" : ",", name);
  for (uint32_t i = 0; i < 3 * vertex_count; i++)
    ae_printf(b, "%s%.9g", i ? "," : "", (double)pos[i]);
  ae_printf(b, "],\"indices\":[");
  for (uint32_t i = 0; i < 3 * tri_count; i++) ae_printf(b, "%s%u", i ? "," : "", idx[i]);
  ae_printf(b, "]}");
}

/* Closes the JSON and loads it; fails the test (exit 1) when the loader refuses. */
static inline tt_scene *ae_scene_end(ae_buf *b, const char *source) {
  ae_printf(b, "]}");
  tt_scene *scene = NULL;
  tt_status s = tt_scene_load_json(b->p, b->len, source, NULL, &scene);
  if (s != TT_OK || !scene) {
    fprintf(stderr, "tt_scene_load_json(%s) failed: %s\n", source, tt_last_error());
    exit(1);
  }
  free(b->p);
  memset(b, 0, sizeof *b);
  return scene;
}

/* A scene of `meshes` meshes with `tris[i]` random triangles each (edge ~0.05..0.35, in
 * [-1,1]^3). Vertices are shuffled so that indices are not the identity. */
static inline tt_scene *ae_random_scene(uint64_t seed, int meshes, const uint32_t *tris) {
  ae_rng rng = {seed};
  ae_buf b = {0};
  ae_scene_begin(&b);
  for (int m = 0; m < meshes; m++) {
    uint32_t tc = tris[m], vc = 3 * tris[m];
    float *pos = malloc(sizeof(float) * 3 * vc);
    uint32_t *idx = malloc(sizeof(uint32_t) * 3 * tc);
    uint32_t *perm = malloc(sizeof(uint32_t) * vc);
    for (uint32_t i = 0; i < vc; i++) perm[i] = i;
    for (uint32_t i = vc - 1; i > 0; i--) {
      uint32_t j = (uint32_t)(ae_next(&rng) % (i + 1)), t = perm[i];
      perm[i] = perm[j];
      perm[j] = t;
    }
    for (uint32_t t = 0; t < tc; t++) {
      double c[3], size = ae_uniform(&rng, 0.05, 0.35);
      for (int k = 0; k < 3; k++) c[k] = ae_uniform(&rng, -1.0, 1.0);
      for (int v = 0; v < 3; v++) {
        uint32_t vi = perm[3 * t + (uint32_t)v];
        idx[3 * t + (uint32_t)v] = vi;
        for (int k = 0; k < 3; k++)
          pos[3 * vi + (uint32_t)k] = (float)(c[k] + size * ae_uniform(&rng, -0.5, 0.5));
      }
    }
    char name[16];
    snprintf(name, sizeof name, "rand%d", m);
    ae_scene_mesh(&b, m == 0, name, pos, vc, idx, tc);
    free(pos);
    free(idx);
    free(perm);
  }
  return ae_scene_end(&b, "accel_embree random scene");
}

/* Random rays: origins in [-1.5,1.5]^3, unnormalised directions, a mix of default and
 * restricted [tnear, tfar] intervals. */
static inline void ae_random_rays(uint64_t seed, tt_ray *rays, size_t n) {
  ae_rng rng = {seed};
  for (size_t i = 0; i < n; i++) {
    tt_ray *r = &rays[i];
    double d[3], len2;
    do {
      for (int k = 0; k < 3; k++) d[k] = ae_uniform(&rng, -1.0, 1.0);
      len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    } while (len2 > 1.0 || len2 < 1e-4);
    double scale = ae_uniform(&rng, 0.5, 2.0) / sqrt(len2);
    for (int k = 0; k < 3; k++) {
      r->org[k] = (float)ae_uniform(&rng, -1.5, 1.5);
      r->dir[k] = (float)(d[k] * scale);
    }
    r->tnear = (i % 4 == 1) ? (float)ae_uniform(&rng, 0.0, 1.0) : 0.0f;
    r->tfar = (i % 3 == 2) ? (float)ae_uniform(&rng, 0.3, 3.0) : INFINITY;
  }
}

/* Rays from one origin through a grid toward the scene (a pinhole camera: coherent). */
static inline void ae_camera_rays(tt_ray *rays, size_t w, size_t h) {
  for (size_t y = 0; y < h; y++)
    for (size_t x = 0; x < w; x++) {
      tt_ray *r = &rays[y * w + x];
      r->org[0] = 0.1f, r->org[1] = 0.2f, r->org[2] = 4.0f;
      r->dir[0] = (float)(((double)x + 0.5) / (double)w * 0.8 - 0.4);
      r->dir[1] = (float)(((double)y + 0.5) / (double)h * 0.8 - 0.4);
      r->dir[2] = -1.0f;
      r->tnear = 0.0f;
      r->tfar = INFINITY;
    }
}

/* ---- brute-force reference ---- */

/* Result of the reference for one ray. `ambiguous` marks rays whose answer float round-off
 * may legitimately change: the closest hit lies within AE_EPS of a triangle edge or of the
 * interval ends, or another triangle (edges grown by AE_EPS) is hit within AE_EPS relative
 * distance of it (or, for a miss, at all). */
typedef struct ae_ref {
  double t, u, v;
  uint32_t geom, prim; /* TT_INVALID_ID on a miss */
  int ambiguous;
} ae_ref;

#define AE_EPS 1e-4

/* Double-precision Moller-Trumbore; returns 1 with t,u,v when the ray's line meets the
 * triangle with barycentrics >= -margin (no interval test). */
static inline int ae_mt(const tt_ray *r, const float *p0, const float *p1, const float *p2,
                        double margin, double *t, double *u, double *v) {
  double e1[3], e2[3], s[3], pv[3], qv[3];
  for (int k = 0; k < 3; k++) {
    e1[k] = (double)p1[k] - p0[k];
    e2[k] = (double)p2[k] - p0[k];
    s[k] = (double)r->org[k] - p0[k];
  }
  const double *d = (const double[3]){r->dir[0], r->dir[1], r->dir[2]};
  pv[0] = d[1] * e2[2] - d[2] * e2[1];
  pv[1] = d[2] * e2[0] - d[0] * e2[2];
  pv[2] = d[0] * e2[1] - d[1] * e2[0];
  double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
  if (fabs(det) < 1e-300) return 0;
  double inv = 1.0 / det;
  *u = (s[0] * pv[0] + s[1] * pv[1] + s[2] * pv[2]) * inv;
  if (*u < -margin || *u > 1.0 + margin) return 0;
  qv[0] = s[1] * e1[2] - s[2] * e1[1];
  qv[1] = s[2] * e1[0] - s[0] * e1[2];
  qv[2] = s[0] * e1[1] - s[1] * e1[0];
  *v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) * inv;
  if (*v < -margin || *u + *v > 1.0 + margin) return 0;
  *t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) * inv;
  return 1;
}

/* Vertex pointers of triangle `prim` of mesh `m`. */
static inline void ae_tri(const tt_mesh *m, uint32_t prim, const float **p0, const float **p1,
                          const float **p2) {
  *p0 = m->positions + 3 * m->indices[3 * prim + 0];
  *p1 = m->positions + 3 * m->indices[3 * prim + 1];
  *p2 = m->positions + 3 * m->indices[3 * prim + 2];
}

/* Reference closest hit of one ray over every triangle of the scene. */
static inline ae_ref ae_brute(const tt_scene *scene, const tt_ray *r) {
  ae_ref best = {INFINITY, 0, 0, TT_INVALID_ID, TT_INVALID_ID, 0};
  double near_t[2] = {INFINITY, INFINITY}; /* two closest grown-edge hits */
  uint64_t near_id[2] = {UINT64_MAX, UINT64_MAX};
  const double lo = r->tnear, hi = r->tfar;
  for (uint32_t g = 0; g < tt_scene_mesh_count(scene); g++) {
    const tt_mesh *m = tt_scene_mesh(scene, g);
    for (uint32_t p = 0; p < m->triangle_count; p++) {
      const float *p0, *p1, *p2;
      double t, u, v;
      ae_tri(m, p, &p0, &p1, &p2);
      if (!ae_mt(r, p0, p1, p2, AE_EPS, &t, &u, &v)) continue;
      if (t < lo - AE_EPS * fabs(lo) - 1e-7 || t > hi + AE_EPS * fabs(hi) + 1e-7) continue;
      uint64_t id = ((uint64_t)g << 32) | p;
      if (t < near_t[0]) {
        near_t[1] = near_t[0], near_id[1] = near_id[0];
        near_t[0] = t, near_id[0] = id;
      } else if (t < near_t[1]) {
        near_t[1] = t, near_id[1] = id;
      }
      if (u >= 0 && v >= 0 && u + v <= 1 && t >= lo && t <= hi && t < best.t) {
        best.t = t, best.u = u, best.v = v, best.geom = g, best.prim = p;
      }
    }
  }
  if (best.geom == TT_INVALID_ID) {
    best.ambiguous = near_t[0] < INFINITY;
    return best;
  }
  uint64_t bid = ((uint64_t)best.geom << 32) | best.prim;
  double other = near_id[0] == bid ? near_t[1] : near_t[0];
  double w = 1.0 - best.u - best.v;
  best.ambiguous = other <= best.t * (1 + AE_EPS) + 1e-7 || best.u < AE_EPS || best.v < AE_EPS ||
                   w < AE_EPS || best.t - lo <= AE_EPS * fabs(best.t) + 1e-7 ||
                   hi - best.t <= AE_EPS * fabs(best.t) + 1e-7;
  return best;
}

/* ---- plugin loading ---- */

typedef struct ae_plugin {
  tt_registry *reg;
  const tt_plugin *entry;
  const tt_accel_iface *accel;
} ae_plugin;

/* Loads <TT_PLUGIN_PATH>/accel_embree/accel_embree.so through the registry with `host`
 * (NULL: tt_default_host); exits 77 (skip) when TT_PLUGIN_PATH is not set. */
static inline ae_plugin ae_load(const tt_host *host) {
  ae_plugin p = {0};
  const char *dir = getenv("TT_PLUGIN_PATH");
  if (!dir) TEST_SKIP("TT_PLUGIN_PATH is not set (run through meson test)");
  char path[4096];
  snprintf(path, sizeof path, "%s/accel_embree/accel_embree.so", dir);
  p.reg = tt_registry_create(host ? host : tt_default_host());
  tt_loaded_plugin *lp = NULL;
  if (!p.reg || tt_registry_load(p.reg, path, &lp) != TT_OK || !lp) {
    fprintf(stderr, "loading %s failed: %s\n", path, tt_last_error());
    exit(1);
  }
  p.entry = tt_loaded_plugin_entry(lp);
  p.accel = tt_loaded_plugin_iface(lp);
  return p;
}

/* Shared by the update tests (accel_embree_refit, accel_embree_instances). */

/* One mesh entry of `tc` random triangles around `c` with extra JSON (animation, morph). */
static inline void ae_mesh_json(ae_buf *b, ae_rng *rng, int first, const char *name, uint32_t tc,
                                const double c[3], double spread, const char *extra, int morph) {
  uint32_t vc = 3 * tc;
  float *pos = malloc(sizeof(float) * 3 * vc);
  for (uint32_t t = 0; t < tc; t++) {
    double m[3], size = ae_uniform(rng, 0.02, 0.2);
    for (int k = 0; k < 3; k++) m[k] = c[k] + ae_uniform(rng, -spread, spread);
    for (int v = 0; v < 3; v++)
      for (int k = 0; k < 3; k++)
        pos[3 * (3 * t + v) + k] = (float)(m[k] + size * ae_uniform(rng, -0.5, 0.5));
  }
  ae_printf(b, "%s{\"name\":\"%s\",\"material\":\"m\",\"positions\":[", first ? "" : ",", name);
  for (uint32_t i = 0; i < 3 * vc; i++) ae_printf(b, "%s%.9g", i ? "," : "", (double)pos[i]);
  ae_printf(b, "],\"indices\":[");
  for (uint32_t i = 0; i < vc; i++) ae_printf(b, "%s%u", i ? "," : "", i);
  ae_printf(b, "]");
  if (morph) { /* a target that moves every vertex a little, differently */
    ae_printf(b, ",\"morph\":{\"targets\":[{\"positions\":[");
    for (uint32_t i = 0; i < 3 * vc; i++)
      ae_printf(b, "%s%.9g", i ? "," : "", (double)pos[i] + ae_uniform(rng, -0.15, 0.15));
    ae_printf(b, "]}],\"keys\":[{\"time\":0,\"weights\":[0]},{\"time\":2,\"weights\":[1]}]}");
  }
  if (extra) ae_printf(b, ",%s", extra);
  ae_printf(b, "}");
  free(pos);
}

/* Random rays with origins in the scene's box. */
static inline void ae_rays_in(const tt_scene *scene, uint64_t seed, tt_ray *rays, size_t n) {
  float lo[3], hi[3];
  tt_scene_bounds(scene, lo, hi);
  ae_rng rng = {seed};
  for (size_t i = 0; i < n; i++) {
    double d[3], len2;
    do {
      for (int k = 0; k < 3; k++) d[k] = ae_uniform(&rng, -1.0, 1.0);
      len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    } while (len2 > 1.0 || len2 < 1e-4);
    for (int k = 0; k < 3; k++) {
      rays[i].org[k] = (float)ae_uniform(&rng, lo[k], hi[k]);
      rays[i].dir[k] = (float)(d[k] / sqrt(len2));
    }
    rays[i].tnear = 0.0f;
    rays[i].tfar = INFINITY;
  }
}

/* Closest hits of `rays` (copied: the query shortens tfar). */
static inline void ae_trace(const tt_accel_iface *ai, const tt_accel *acc, const tt_ray *rays,
                            tt_hit *hits, size_t n) {
  for (size_t i = 0; i < n; i++) {
    tt_ray r = rays[i];
    ai->intersect1(acc, &r, &hits[i]);
  }
}

/* A configuration of the plugin's space from key=value pairs (NULL-terminated). */
static inline tt_config *ae_config_of(const tt_accel_iface *ai, const char *const *kv) {
  tt_config *c = tt_config_create(ai->space());
  for (size_t i = 0; kv[i]; i += 2)
    if (tt_config_set_string(c, kv[i], kv[i + 1]) != TT_OK)
      TEST_FAIL("%s=%s: %s", kv[i], kv[i + 1], tt_last_error());
  return c;
}

#endif /* TT_ACCEL_EMBREE_COMMON_H */
