/* pbrt-v4 importer: PLY meshes (through io/ply, the reader scene.json shares) and the
 * analytic shapes the shared scenes use (sphere, disk, Loop subdivision surfaces), all
 * turned into triangles. */
#include "io/pbrt/pbrt_internal.h"
#include "io/ply/ply.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TT__PI 3.14159265358979323846

/* ---- PLY: the shared reader (io/ply) ---------------------------------------------------- */

tt_status tt__pbrt_read_ply(const char *path, const char *where, tt__mesh_data *out) {
  return tt__ply_read(path, where, out);
}

/* ---- analytic shapes ------------------------------------------------------------------- */

/* Allocates the arrays of a mesh_data; normals/uvs on request. */
static tt_status tt__alloc_mesh(tt__mesh_data *d, uint32_t nv, uint32_t nt, int normals, int uvs) {
  memset(d, 0, sizeof *d);
  d->vertex_count = nv;
  d->triangle_count = nt;
  d->positions = malloc(3 * (size_t)nv * sizeof(float));
  d->indices = malloc(3 * (size_t)nt * sizeof(uint32_t));
  if (normals) d->normals = malloc(3 * (size_t)nv * sizeof(float));
  if (uvs) d->uvs = malloc(2 * (size_t)nv * sizeof(float));
  if (!d->positions || !d->indices || (normals && !d->normals) || (uvs && !d->uvs)) {
    tt__mesh_data_free(d);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory tessellating a shape");
  }
  return TT_OK;
}

/* A UV sphere with pole fans (no degenerate triangles): 48 segments x 24 rings keeps the
 * silhouette error under 0.25% of the radius. */
tt_status tt__pbrt_sphere(double r, tt__mesh_data *d) {
  const uint32_t seg = 48, rings = 24;
  uint32_t nv = 2 + (rings - 1) * (seg + 1);
  uint32_t nt = 2 * seg + 2 * seg * (rings - 2);
  tt_status st = tt__alloc_mesh(d, nv, nt, 1, 1);
  if (st != TT_OK) return st;
  uint32_t v = 0;
  /* pole vertices first: 0 = +z (theta 0), 1 = -z */
  for (int s = 0; s < 2; s++, v++) {
    float z = s ? -1.0f : 1.0f;
    d->positions[3 * v] = 0;
    d->positions[3 * v + 1] = 0;
    d->positions[3 * v + 2] = (float)(z * r);
    d->normals[3 * v] = 0;
    d->normals[3 * v + 1] = 0;
    d->normals[3 * v + 2] = z;
    d->uvs[2 * v] = 0.5f;
    d->uvs[2 * v + 1] = s ? 1.0f : 0.0f;
  }
  for (uint32_t i = 1; i < rings; i++) {
    double th = TT__PI * i / rings;
    for (uint32_t j = 0; j <= seg; j++, v++) {
      double ph = 2 * TT__PI * j / seg;
      double n[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)};
      for (int k = 0; k < 3; k++) {
        d->positions[3 * v + k] = (float)(r * n[k]);
        d->normals[3 * v + k] = (float)n[k];
      }
      d->uvs[2 * v] = (float)j / seg;
      d->uvs[2 * v + 1] = (float)i / rings;
    }
  }
  uint32_t *t = d->indices;
#define TT__RV(i, j) (2 + ((i)-1) * (seg + 1) + (j))
  /* winding chosen so (b-a)x(c-a) points outward */
  for (uint32_t j = 0; j < seg; j++) {
    *t++ = 0;
    *t++ = TT__RV(1, j);
    *t++ = TT__RV(1, j + 1);
    *t++ = 1;
    *t++ = TT__RV(rings - 1, j + 1);
    *t++ = TT__RV(rings - 1, j);
  }
  for (uint32_t i = 1; i + 1 < rings; i++)
    for (uint32_t j = 0; j < seg; j++) {
      uint32_t a = TT__RV(i, j), b = TT__RV(i, j + 1), c = TT__RV(i + 1, j),
               e = TT__RV(i + 1, j + 1);
      *t++ = a;
      *t++ = c;
      *t++ = e;
      *t++ = a;
      *t++ = e;
      *t++ = b;
    }
#undef TT__RV
  return TT_OK;
}

/* A 64-gon disk (or annulus) facing +z at height h. */
tt_status tt__pbrt_disk(double r, double ri, double h, tt__mesh_data *d) {
  const uint32_t seg = 64;
  int annulus = ri > 0 && ri < r;
  uint32_t nv = annulus ? 2 * (seg + 1) : seg + 2;
  uint32_t nt = annulus ? 2 * seg : seg;
  tt_status st = tt__alloc_mesh(d, nv, nt, 0, 1);
  if (st != TT_OK) return st;
  uint32_t v = 0;
  if (!annulus) {
    d->positions[0] = 0;
    d->positions[1] = 0;
    d->positions[2] = (float)h;
    d->uvs[0] = 0;
    d->uvs[1] = 1;
    v = 1;
  }
  for (int ring = annulus ? 0 : 1; ring < 2; ring++)
    for (uint32_t j = 0; j <= seg; j++, v++) {
      double ph = 2 * TT__PI * j / seg, rr = ring ? r : ri;
      d->positions[3 * v] = (float)(rr * cos(ph));
      d->positions[3 * v + 1] = (float)(rr * sin(ph));
      d->positions[3 * v + 2] = (float)h;
      d->uvs[2 * v] = (float)j / seg;
      d->uvs[2 * v + 1] = (float)((r - rr) / (r - (annulus ? ri : 0)));
    }
  uint32_t *t = d->indices;
  for (uint32_t j = 0; j < seg; j++) {
    if (!annulus) {
      *t++ = 0;
      *t++ = 1 + j;
      *t++ = 2 + j;
    } else {
      uint32_t a = j, b = j + 1, c = seg + 1 + j, e = seg + 2 + j;
      *t++ = a;
      *t++ = c;
      *t++ = e;
      *t++ = a;
      *t++ = e;
      *t++ = b;
    }
  }
  return TT_OK;
}

/* ---- Loop subdivision ------------------------------------------------------------------ */

/* Open-addressing table of undirected edges (a < b) -> edge index. */
typedef struct tt__edges {
  uint64_t *keys; /* (a << 32 | b) + 1; 0 = empty */
  uint32_t *ids;
  size_t cap;
  uint32_t count;
  uint32_t *ends;  /* 2 per edge */
  uint32_t *faces; /* faces per edge (saturating) */
  uint32_t *opp;   /* 2 per edge: opposite vertex of the first two faces */
} tt__edges;

/* Frees an edge table. */
static void tt__edges_free(tt__edges *e) {
  free(e->keys);
  free(e->ids);
  free(e->ends);
  free(e->faces);
  free(e->opp);
  memset(e, 0, sizeof *e);
}

/* Builds the edge table of a triangle list; 0 when out of memory. */
static int tt__edges_build(tt__edges *e, const uint32_t *idx, uint32_t nt) {
  memset(e, 0, sizeof *e);
  size_t cap = 16;
  while (cap < (size_t)nt * 4) cap *= 2;
  e->cap = cap;
  e->keys = calloc(cap, sizeof *e->keys);
  e->ids = malloc(cap * sizeof *e->ids);
  size_t maxe = (size_t)nt * 3 + 1;
  e->ends = malloc(2 * maxe * sizeof *e->ends);
  e->faces = calloc(maxe, sizeof *e->faces);
  e->opp = malloc(2 * maxe * sizeof *e->opp);
  if (!e->keys || !e->ids || !e->ends || !e->faces || !e->opp) return 0;
  for (uint32_t t = 0; t < nt; t++)
    for (int k = 0; k < 3; k++) {
      uint32_t a = idx[3 * (size_t)t + k], b = idx[3 * (size_t)t + (k + 1) % 3],
               c = idx[3 * (size_t)t + (k + 2) % 3];
      if (a > b) {
        uint32_t x = a;
        a = b;
        b = x;
      }
      uint64_t key = (((uint64_t)a << 32) | b) + 1;
      size_t h = (size_t)((key * 0x9E3779B97F4A7C15ull) >> 17) & (cap - 1);
      while (e->keys[h] && e->keys[h] != key) h = (h + 1) & (cap - 1);
      uint32_t id;
      if (!e->keys[h]) {
        e->keys[h] = key;
        id = e->ids[h] = e->count++;
        e->ends[2 * (size_t)id] = a;
        e->ends[2 * (size_t)id + 1] = b;
      } else {
        id = e->ids[h];
      }
      if (e->faces[id] < 2) e->opp[2 * (size_t)id + e->faces[id]] = c;
      if (e->faces[id] < 3) e->faces[id]++;
    }
  return 1;
}

/* Looks up the id of edge (a, b). */
static uint32_t tt__edges_find(const tt__edges *e, uint32_t a, uint32_t b) {
  if (a > b) {
    uint32_t x = a;
    a = b;
    b = x;
  }
  uint64_t key = (((uint64_t)a << 32) | b) + 1;
  size_t h = (size_t)((key * 0x9E3779B97F4A7C15ull) >> 17) & (e->cap - 1);
  while (e->keys[h] != key) h = (h + 1) & (e->cap - 1);
  return e->ids[h];
}

/* Loop's vertex weight for valence n. */
static double tt__loop_beta(uint32_t n) { return n == 3 ? 3.0 / 16.0 : 3.0 / (8.0 * n); }

/* Per-vertex rule: even vertices (limit == 0) or limit-surface positions (limit == 1), from
 * the neighbour sums over the edge table. Boundary and non-manifold vertices use the 1-D
 * boundary rule over their boundary neighbours. */
static int tt__loop_vertices(const float *pos, uint32_t nv, const tt__edges *e, int limit,
                             float *out) {
  double *sum = calloc(3 * (size_t)nv, sizeof *sum), *bsum = calloc(3 * (size_t)nv, sizeof *bsum);
  uint32_t *val = calloc(nv, sizeof *val), *bval = calloc(nv, sizeof *bval);
  if (!sum || !bsum || !val || !bval) {
    free(sum);
    free(bsum);
    free(val);
    free(bval);
    return 0;
  }
  for (uint32_t i = 0; i < e->count; i++) {
    uint32_t a = e->ends[2 * (size_t)i], b = e->ends[2 * (size_t)i + 1];
    int boundary = e->faces[i] != 2;
    for (int k = 0; k < 3; k++) {
      sum[3 * (size_t)a + k] += pos[3 * (size_t)b + k];
      sum[3 * (size_t)b + k] += pos[3 * (size_t)a + k];
      if (boundary) {
        bsum[3 * (size_t)a + k] += pos[3 * (size_t)b + k];
        bsum[3 * (size_t)b + k] += pos[3 * (size_t)a + k];
      }
    }
    val[a]++;
    val[b]++;
    if (boundary) {
      bval[a]++;
      bval[b]++;
    }
  }
  for (uint32_t v = 0; v < nv; v++) {
    const float *p = pos + 3 * (size_t)v;
    float *o = out + 3 * (size_t)v;
    if (bval[v] == 2) {
      double wv = limit ? 3.0 / 5.0 : 3.0 / 4.0, wn = limit ? 1.0 / 5.0 : 1.0 / 8.0;
      for (int k = 0; k < 3; k++) o[k] = (float)(wv * p[k] + wn * bsum[3 * (size_t)v + k]);
    } else if (bval[v] == 0 && val[v] >= 3) {
      double beta = tt__loop_beta(val[v]);
      double w = limit ? 1.0 / (val[v] + 3.0 / (8.0 * beta)) : beta;
      for (int k = 0; k < 3; k++)
        o[k] = (float)((1.0 - val[v] * w) * p[k] + w * sum[3 * (size_t)v + k]);
    } else {
      memcpy(o, p, 3 * sizeof *o); /* corners and non-manifold vertices stay put */
    }
  }
  free(sum);
  free(bsum);
  free(val);
  free(bval);
  return 1;
}

/* Area-weighted vertex normals, so the subdivided surface shades smoothly like pbrt's. */
static int tt__smooth_normals(tt__mesh_data *d) {
  float *n = calloc(3 * (size_t)d->vertex_count, sizeof *n);
  if (!n) return 0;
  for (uint32_t t = 0; t < d->triangle_count; t++) {
    const uint32_t *ix = d->indices + 3 * (size_t)t;
    const float *a = d->positions + 3 * (size_t)ix[0], *b = d->positions + 3 * (size_t)ix[1],
                *c = d->positions + 3 * (size_t)ix[2];
    float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
          e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    float f[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                  e1[0] * e2[1] - e1[1] * e2[0]};
    for (int k = 0; k < 3; k++)
      for (int j = 0; j < 3; j++) n[3 * (size_t)ix[k] + j] += f[j];
  }
  for (uint32_t v = 0; v < d->vertex_count; v++) {
    float *p = n + 3 * (size_t)v;
    float l = sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    if (l > 0) {
      p[0] /= l;
      p[1] /= l;
      p[2] /= l;
    } else {
      p[0] = 0;
      p[1] = 0;
      p[2] = 1;
    }
  }
  free(d->normals);
  d->normals = n;
  return 1;
}

/* One Loop step, then the vertices are pushed to the limit surface as pbrt does. */
tt_status tt__pbrt_loop_subdivide(tt__mesh_data *d) {
  tt__edges e;
  tt__mesh_data n;
  memset(&n, 0, sizeof n);
  if ((uint64_t)d->triangle_count * 4 > UINT32_MAX / 3 ||
      (uint64_t)d->vertex_count + 3ull * d->triangle_count > UINT32_MAX / 3)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "loopsubdiv: mesh too large to subdivide");
  if (!tt__edges_build(&e, d->indices, d->triangle_count)) goto oom;
  uint32_t nv = d->vertex_count + e.count, nt = d->triangle_count * 4;
  n.vertex_count = nv;
  n.triangle_count = nt;
  n.positions = malloc(3 * (size_t)nv * sizeof(float));
  n.indices = malloc(3 * (size_t)nt * sizeof(uint32_t));
  if (!n.positions || !n.indices) goto oom;
  if (!tt__loop_vertices(d->positions, d->vertex_count, &e, 0, n.positions)) goto oom;
  for (uint32_t i = 0; i < e.count; i++) {
    const float *a = d->positions + 3 * (size_t)e.ends[2 * (size_t)i],
                *b = d->positions + 3 * (size_t)e.ends[2 * (size_t)i + 1];
    float *o = n.positions + 3 * ((size_t)d->vertex_count + i);
    if (e.faces[i] == 2) {
      const float *c = d->positions + 3 * (size_t)e.opp[2 * (size_t)i],
                  *f = d->positions + 3 * (size_t)e.opp[2 * (size_t)i + 1];
      for (int k = 0; k < 3; k++) o[k] = 0.375f * (a[k] + b[k]) + 0.125f * (c[k] + f[k]);
    } else {
      for (int k = 0; k < 3; k++) o[k] = 0.5f * (a[k] + b[k]);
    }
  }
  for (uint32_t t = 0; t < d->triangle_count; t++) {
    const uint32_t *ix = d->indices + 3 * (size_t)t;
    uint32_t m[3];
    for (int k = 0; k < 3; k++) m[k] = d->vertex_count + tt__edges_find(&e, ix[k], ix[(k + 1) % 3]);
    uint32_t *o = n.indices + 12 * (size_t)t;
    o[0] = ix[0];
    o[1] = m[0];
    o[2] = m[2];
    o[3] = ix[1];
    o[4] = m[1];
    o[5] = m[0];
    o[6] = ix[2];
    o[7] = m[2];
    o[8] = m[1];
    o[9] = m[0];
    o[10] = m[1];
    o[11] = m[2];
  }
  tt__edges_free(&e);
  /* limit positions need the new mesh's own neighbourhoods */
  if (!tt__edges_build(&e, n.indices, nt)) goto oom;
  float *lim = malloc(3 * (size_t)nv * sizeof *lim);
  if (!lim || !tt__loop_vertices(n.positions, nv, &e, 1, lim)) {
    free(lim);
    goto oom;
  }
  free(n.positions);
  n.positions = lim;
  tt__edges_free(&e);
  if (!tt__smooth_normals(&n)) goto oom;
  n.name = d->name;
  d->name = NULL;
  tt__mesh_data_free(d);
  *d = n;
  return TT_OK;
oom:
  tt__edges_free(&e);
  tt__mesh_data_free(&n);
  return tt_set_error(TT_ERR_OUT_OF_MEMORY, "loopsubdiv: out of memory");
}
