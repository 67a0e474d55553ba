/* The SAH-growth estimate of the native backend's refit.
 *
 * Embree's refitted BVHs are opaque, so refitSahGrowth (rebuild once the refitted tree's SAH
 * cost has grown by a factor) cannot read their cost. What refit does to a tree is keep its
 * topology and recompute its boxes; this file keeps a tree of the same kind beside Embree's:
 * each moving mesh's triangles in the Morton order of their centroids at build time, grouped
 * into leaves of 4 (Embree's triangle4 leaves) and those into nodes of 4 up to one root, the
 * grouping frozen until the next build. Its SAH cost at the current positions, with the
 * custom backend's formula (inner areas plus leaf areas times their triangles, over the root
 * area; traversal and intersection cost 1), grows as refit's does when triangles that were
 * neighbours drift apart, and stays put under translation and uniform scaling, where a
 * refitted tree is as good as a fresh one. The scene's cost is the triangle-weighted mean over
 * the moving meshes. One pass over the triangles per update, before Embree's refit, so a
 * rebuild it asks for costs no wasted refit. */
#include "accel_embree.h"

#include <stdlib.h>
#include <string.h>

typedef struct tt__growth_mesh {
  uint32_t mesh;  /* scene mesh index */
  uint32_t count; /* triangles */
  uint32_t *tris; /* the triangles' vertex indices (3 each) in the build's Morton order:
                     read in sequence, and Morton-near triangles share vertices */
} tt__growth_mesh;

struct tt__embree_growth {
  tt__growth_mesh *meshes;
  uint32_t mesh_count;
  float *boxes; /* scratch: 6 floats per leaf of the largest mesh */
};

typedef struct {
  uint32_t code, tri;
} tt__growth_key;

static int tt__growth_key_cmp(const void *a, const void *b) {
  const tt__growth_key *x = a, *y = b;
  if (x->code != y->code) return x->code < y->code ? -1 : 1;
  return x->tri < y->tri ? -1 : x->tri > y->tri; /* ties in triangle order: deterministic */
}

/* 10 bits of v in [0, 1) spread to every third bit. */
static uint32_t tt__growth_spread(float v) {
  uint32_t x = v <= 0.0f ? 0u : v >= 1.0f ? 1023u : (uint32_t)(v * 1024.0f);
  x = (x | (x << 16)) & 0x030000FFu;
  x = (x | (x << 8)) & 0x0300F00Fu;
  x = (x | (x << 4)) & 0x030C30C3u;
  x = (x | (x << 2)) & 0x09249249u;
  return x;
}

/* min / max without libm's NaN handling (positions are finite: checked at load), so they
 * compile to single instructions; fminf and fmaxf are calls and took most of the pass. */
static inline float tt__growth_min(float a, float b) { return a < b ? a : b; }
static inline float tt__growth_max(float a, float b) { return a > b ? a : b; }

static inline void tt__growth_tri_box(const float *pos, const uint32_t *v, float b[6]) {
  const float *p = pos + (size_t)3 * v[0], *q = pos + (size_t)3 * v[1], *r = pos + (size_t)3 * v[2];
  for (int a = 0; a < 3; a++) {
    b[a] = tt__growth_min(p[a], tt__growth_min(q[a], r[a]));
    b[3 + a] = tt__growth_max(p[a], tt__growth_max(q[a], r[a]));
  }
}

static inline void tt__growth_merge(float d[6], const float s[6]) {
  for (int a = 0; a < 3; a++) {
    d[a] = tt__growth_min(d[a], s[a]);
    d[3 + a] = tt__growth_max(d[3 + a], s[3 + a]);
  }
}

static double tt__growth_area(const float b[6]) {
  const double x = (double)b[3] - b[0], y = (double)b[4] - b[1], z = (double)b[5] - b[2];
  return 2.0 * (x * y + y * z + z * x);
}

/* The frozen tree's SAH cost at the mesh's current positions (0 for a flat-rooted mesh). */
static double tt__growth_mesh_cost(const tt__growth_mesh *g, const tt_mesh *m, float *boxes) {
  uint32_t n = (g->count + 3u) / 4u;
  double sum = 0.0;
  for (uint32_t l = 0; l < n; l++) {
    float *b = boxes + (size_t)6 * l;
    const uint32_t end = 4u * l + 4u < g->count ? 4u * l + 4u : g->count;
    tt__growth_tri_box(m->positions, g->tris + (size_t)12 * l, b);
    for (uint32_t i = 4u * l + 1u; i < end; i++) {
      float t[6];
      tt__growth_tri_box(m->positions, g->tris + (size_t)3 * i, t);
      tt__growth_merge(b, t);
    }
    sum += tt__growth_area(b) * (double)(end - 4u * l);
  }
  /* inner levels: groups of 4 boxes, in place (the group's box goes to its first slot's
   * index / 4, which the loop has read already) */
  while (n > 1) {
    const uint32_t up = (n + 3u) / 4u;
    for (uint32_t p = 0; p < up; p++) {
      float b[6];
      memcpy(b, boxes + (size_t)24 * p, sizeof b);
      for (uint32_t c = 4u * p + 1u; c < 4u * p + 4u && c < n; c++)
        tt__growth_merge(b, boxes + (size_t)6 * c);
      memcpy(boxes + (size_t)6 * p, b, sizeof b);
      sum += tt__growth_area(b);
    }
    n = up;
  }
  const double root = tt__growth_area(boxes);
  return root > 0.0 ? sum / root : 0.0;
}

tt__embree_growth *tt__embree_growth_create(const tt_scene *scene, const float *const *moving) {
  tt__embree_growth *g = calloc(1, sizeof *g);
  if (!g) return NULL;
  const uint32_t meshes = tt_scene_mesh_count(scene);
  g->meshes = calloc(meshes ? meshes : 1, sizeof *g->meshes);
  if (!g->meshes) goto fail;
  uint32_t most = 0;
  for (uint32_t i = 0; i < meshes; i++) {
    const tt_mesh *m = tt_scene_mesh(scene, i);
    if (!moving[i] || m->triangle_count == 0) continue;
    tt__growth_mesh *gm = &g->meshes[g->mesh_count];
    gm->mesh = i;
    gm->count = m->triangle_count;
    gm->tris = malloc((size_t)gm->count * 3 * sizeof *gm->tris);
    tt__growth_key *keys = malloc((size_t)gm->count * sizeof *keys);
    if (!gm->tris || !keys) {
      free(keys);
      free(gm->tris);
      goto fail;
    }
    g->mesh_count++;
    float lo[3], hi[3];
    for (uint32_t v = 0; v < m->vertex_count; v++)
      for (int a = 0; a < 3; a++) {
        const float p = m->positions[(size_t)3 * v + (size_t)a];
        if (v == 0 || p < lo[a]) lo[a] = p;
        if (v == 0 || p > hi[a]) hi[a] = p;
      }
    for (uint32_t t = 0; t < gm->count; t++) {
      float b[6];
      tt__growth_tri_box(m->positions, m->indices + (size_t)3 * t, b);
      uint32_t code = 0;
      for (int a = 0; a < 3; a++) {
        const float ext = hi[a] - lo[a];
        const float c = ext > 0.0f ? (0.5f * (b[a] + b[3 + a]) - lo[a]) / ext : 0.0f;
        code |= tt__growth_spread(c) << (2 - a);
      }
      keys[t].code = code;
      keys[t].tri = t;
    }
    qsort(keys, gm->count, sizeof *keys, tt__growth_key_cmp);
    for (uint32_t t = 0; t < gm->count; t++)
      memcpy(gm->tris + (size_t)3 * t, m->indices + (size_t)3 * keys[t].tri, 3 * sizeof(uint32_t));
    free(keys);
    if (gm->count > most) most = gm->count;
  }
  g->boxes = malloc(((size_t)most + 3u) / 4u * 6u * sizeof *g->boxes + sizeof(float) * 6u);
  if (!g->boxes) goto fail;
  return g;
fail:
  tt__embree_growth_free(g);
  return NULL;
}

double tt__embree_growth_cost(tt__embree_growth *g, const tt_scene *scene) {
  double sum = 0.0, weight = 0.0;
  for (uint32_t i = 0; i < g->mesh_count; i++) {
    const tt__growth_mesh *gm = &g->meshes[i];
    const tt_mesh *m = tt_scene_mesh(scene, gm->mesh);
    const double c = tt__growth_mesh_cost(gm, m, g->boxes);
    if (c <= 0.0) continue;
    sum += c * gm->count;
    weight += gm->count;
  }
  return weight > 0.0 ? sum / weight : 0.0;
}

void tt__embree_growth_free(tt__embree_growth *g) {
  if (!g) return;
  for (uint32_t i = 0; g->meshes && i < g->mesh_count; i++) free(g->meshes[i].tris);
  free(g->meshes);
  free(g->boxes);
  free(g);
}
