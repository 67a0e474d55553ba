/* tunetrace: the bidirectional path sampler (bdpt.h): subpaths from the camera and from the
 * lights, their connections and the multiple-importance weights of the strategies, after
 * pbrt-v3's bdpt.cpp (Veach 1997, ch. 10), with Russian roulette on the subpaths and the
 * sample streams of bdpt.h. */
#include <tunetrace/bdpt.h>

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "render/bdpt_internal.h"

#define TT__PI 3.14159265358979324f
/* Offset of ray origins off surfaces, relative to 1 + |p|_max (as path.c's). The subpaths
 * store the densities of the directions they sampled, a connection recomputes some from the
 * vertex positions: the offset makes them differ by about eps / distance. A white-box test
 * shrinks it to compare the two exactly. */
#ifndef TT__BDPT_OFFSET_EPS
#  define TT__BDPT_OFFSET_EPS 5e-5f
#endif

TT_API void tt_bdpt_options_default(tt_bdpt_options *options) {
  if (!options) return;
  memset(options, 0, sizeof *options);
  options->struct_size = sizeof *options;
  options->max_depth = 5;
  options->rr_depth = 3;
  options->heuristic = TT_MIS_POWER;
}

/* The caller's options over the defaults (struct_size-aware): the caller's struct itself
 * when it is whole and valid (the per-connection path), else a completed copy in *tmp. */
static const tt_bdpt_options *tt__bdpt_opts(const tt_bdpt_options *options, tt_bdpt_options *tmp) {
  if (options && options->struct_size == sizeof *options && options->max_depth <= 64)
    return options;
  tt_bdpt_options_default(tmp);
  if (options) {
    size_t n = options->struct_size < sizeof *tmp ? options->struct_size : sizeof *tmp;
    if (n > 0) memcpy(tmp, options, n);
    tmp->struct_size = sizeof *tmp;
  }
  if (tmp->max_depth > 64) tmp->max_depth = 64;
  return tmp;
}

TT_API tt_status tt_bdpt_paths_create(uint32_t max_depth, tt_bdpt_paths **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_bdpt_paths_create: out is NULL");
  *out = NULL;
  if (max_depth > 64)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_bdpt_paths_create: max_depth %u exceeds 64",
                        max_depth);
  tt_bdpt_paths *p = calloc(1, sizeof *p);
  if (!p) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_bdpt_paths_create: out of memory");
  p->cap = max_depth + 2;
  p->camera = calloc(p->cap, sizeof *p->camera);
  p->light = calloc(p->cap, sizeof *p->light);
  if (!p->camera || !p->light) {
    tt_bdpt_paths_destroy(p);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_bdpt_paths_create: out of memory");
  }
  *out = p;
  return TT_OK;
}

TT_API void tt_bdpt_paths_destroy(tt_bdpt_paths *paths) {
  if (!paths) return;
  free(paths->camera);
  free(paths->light);
  free(paths);
}

TT_API uint32_t tt_bdpt_rays(const tt_bdpt_paths *paths) { return paths ? paths->rays : 0; }

TT_API void tt_bdpt_first_hit(const tt_bdpt_paths *paths, tt_path_result *out) {
  tt_bdpt_first_hit_ex(paths, out, TT_PATH_RESULT_SIZE_1_1);
}

TT_API void tt_bdpt_first_hit_ex(const tt_bdpt_paths *paths, tt_path_result *out,
                                 size_t result_size) {
  tt_path_result r;
  memset(&r, 0, sizeof r);
  r.distance = INFINITY;
  if (paths && paths->hit) {
    r.hit = 1;
    r.distance = paths->hit_distance;
    memcpy(r.normal, paths->hit_normal, sizeof r.normal);
    memcpy(r.albedo, paths->hit_albedo, sizeof r.albedo);
    if (paths->n_camera > 1) memcpy(r.position, paths->camera[1].p, sizeof r.position);
    memcpy(r.prev_position, paths->hit_prev, sizeof r.prev_position);
  }
  /* an older caller's result ends before prev_position */
  memcpy(out, &r, result_size >= sizeof r ? sizeof r : TT_PATH_RESULT_SIZE_1_1);
}

/* ---- geometry helpers ---- */

/* Reads dimension `dim` of a source, clamped into [0, 1). */
static inline float tt__bdpt_dim(const tt_sample_source *src, uint32_t dim) {
  float u = src->get(src->self, dim);
  if (!(u >= 0.0f)) u = 0.0f;
  if (u >= 1.0f) u = 0x1.fffffep-1f;
  return u;
}

/* Moves p off the surface along ng, to the side of w (as path.c does). */
static inline void tt__bdpt_offset(const float p[3], const float ng[3], const float w[3],
                                   float out[3]) {
  float m = fmaxf(fabsf(p[0]), fmaxf(fabsf(p[1]), fabsf(p[2])));
  float eps = TT__BDPT_OFFSET_EPS * (1.0f + m);
  if (tt__dot3(w, ng) < 0.0f) eps = -eps;
  for (int i = 0; i < 3; ++i) out[i] = p[i] + eps * ng[i];
}

/* Unit direction from a to b and the squared distance (INFINITY when either is at infinity:
 * then the direction is that of the light at infinity). 0 if they coincide. */
static int tt__bv_dir(const tt__bvertex *a, const tt__bvertex *b, float w[3], float *dist2) {
  if (b->infinite) {
    for (int i = 0; i < 3; ++i) w[i] = -b->wo[i];
    *dist2 = INFINITY;
    return 1;
  }
  if (a->infinite) {
    memcpy(w, a->wo, 3 * sizeof(float));
    *dist2 = INFINITY;
    return 1;
  }
  for (int i = 0; i < 3; ++i) w[i] = b->p[i] - a->p[i];
  float d2 = tt__dot3(w, w);
  if (!(d2 > 0.0f) || !isfinite(d2)) return 0;
  float inv = 1.0f / sqrtf(d2);
  for (int i = 0; i < 3; ++i) w[i] *= inv;
  *dist2 = d2;
  return 1;
}

/* A solid-angle density at `from` towards `to` as an area density at `to` (pbrt-v3
 * ConvertDensity; unchanged towards a vertex at infinity). */
static float tt__bv_convert(const tt__bvertex *from, float pdf, const tt__bvertex *to) {
  if (to->infinite) return pdf;
  float w[3], d2;
  if (!tt__bv_dir(from, to, w, &d2)) return 0.0f;
  if (to->on_surface) pdf *= fabsf(tt__dot3(to->ng, w));
  return pdf / d2;
}

/* Non-zero if direction w (unit, leaving the surface) lies on the same side of the geometric
 * and the shading normal: no light passes through a surface by its interpolated normals. */
static inline int tt__bv_side_ok(const tt__bvertex *v, const float w[3]) {
  return tt__dot3(w, v->ng) * tt__dot3(w, v->ns) > 0.0f;
}

/* Importance transport's shading-normal correction for light arriving from wo and leaving
 * towards wi (Veach 5.3; pbrt-v3 CorrectShadingNormal). */
static float tt__bv_adjoint_shading(const tt__bvertex *v, const float wo[3], const float wi[3]) {
  float den = fabsf(tt__dot3(wo, v->ng)) * fabsf(tt__dot3(wi, v->ns));
  if (!(den > 0.0f)) return 0.0f;
  return fabsf(tt__dot3(wo, v->ns)) * fabsf(tt__dot3(wi, v->ng)) / den;
}

/* BSDF of surface vertex v between its subpath's previous vertex (v->wo) and `next`: the
 * radiance BSDF f(wo, w_next) on camera subpaths, the adjoint f(w_next, wo) times the
 * shading correction on light subpaths (`adjoint`). */
static void tt__bv_f(const tt__bvertex *v, const tt__bvertex *next, int adjoint, float f[3]) {
  f[0] = f[1] = f[2] = 0.0f;
  float wn[3], d2;
  if (!tt__bv_dir(v, next, wn, &d2)) return;
  if (!tt__bv_side_ok(v, wn) || !tt__bv_side_ok(v, v->wo)) return;
  if (!tt__bsdf_transmissive(&v->bsdf) && !(tt__dot3(wn, v->ng) * tt__dot3(v->wo, v->ng) > 0.0f))
    return;
  float a[3], b[3];
  tt__to_local(&v->frame, v->wo, a);
  tt__to_local(&v->frame, wn, b);
  if (!adjoint) {
    tt__bsdf_eval(&v->bsdf, a, b, f);
    return;
  }
  tt__bsdf_eval(&v->bsdf, b, a, f);
  float k = tt__bv_adjoint_shading(v, v->wo, wn);
  for (int i = 0; i < 3; ++i) f[i] *= k;
}

static inline int tt__bv_is_light(const tt__bvertex *v) {
  return v->kind == TT__BV_LIGHT || (v->kind == TT__BV_SURFACE && v->light >= 0);
}

/* A light vertex of a point or spot (position delta) or distant (direction delta) light. */
static int tt__bv_delta_light(const tt_path_tracer *pt, const tt__bvertex *v) {
  if (v->kind != TT__BV_LIGHT || v->light < 0 || (uint32_t)v->light >= pt->lights.count) return 0;
  const tt__light *l = &pt->lights.lights[v->light];
  return tt__light_delta_pos(l) || tt__light_delta_dir(l);
}

/* Can be joined to another vertex by a shadow ray. */
static int tt__bv_connectible(const tt_path_tracer *pt, const tt__bvertex *v) {
  switch (v->kind) {
  case TT__BV_CAMERA: return 1;
  case TT__BV_LIGHT:
    return v->light >= 0 && (uint32_t)v->light < pt->lights.count &&
           !tt__light_delta_dir(&pt->lights.lights[v->light]);
  default: return !v->bsdf.delta;
  }
}

/* ---- densities (pbrt-v3 Vertex::Pdf, PdfLight, PdfLightOrigin) ---- */

float tt__bv_pdf_light(const tt_path_tracer *pt, const tt__bvertex *v, const tt__bvertex *next) {
  const tt__lights *ls = &pt->lights;
  float w[3], pdf;
  if (v->infinite) {
    memcpy(w, v->wo, sizeof w);
    pdf = 1.0f / (TT__PI * ls->radius * ls->radius);
  } else {
    float d2, pos, dir;
    if (v->light < 0 || !tt__bv_dir(v, next, w, &d2)) return 0.0f;
    tt__lights_pdf_emission(ls, (uint32_t)v->light, v->ng, w, &pos, &dir);
    pdf = isinf(d2) ? dir : dir / d2;
  }
  if (next->on_surface) pdf *= fabsf(tt__dot3(next->ng, w));
  return pdf;
}

float tt__bv_pdf_light_origin(const tt_path_tracer *pt, const tt__bvertex *v,
                              const tt__bvertex *next) {
  const tt__lights *ls = &pt->lights;
  if (v->light < 0 || (uint32_t)v->light >= ls->count) return 0.0f;
  if (v->infinite) {
    if (tt__light_delta_dir(&ls->lights[v->light])) return 0.0f;
    return tt__lights_pdf_infinite(ls, v->wo);
  }
  float w[3], d2, pos, dir;
  if (!tt__bv_dir(v, next, w, &d2)) return 0.0f;
  tt__lights_pdf_emission(ls, (uint32_t)v->light, v->ng, w, &pos, &dir);
  return pos * ls->pmf[v->light];
}

float tt__bv_pdf(const tt_path_tracer *pt, const tt_camera_frame *frame, const tt__bvertex *v,
                 const tt__bvertex *prev, const tt__bvertex *next) {
  if (v->kind == TT__BV_LIGHT) return tt__bv_pdf_light(pt, v, next);
  float wn[3], d2, pdf = 0.0f;
  if (!tt__bv_dir(v, next, wn, &d2)) return 0.0f;
  if (v->kind == TT__BV_CAMERA) {
    pdf = tt_camera_pdf_dir(frame, wn);
  } else {
    float wp[3], dp2, a[3], b[3];
    if (!prev || !tt__bv_dir(v, prev, wp, &dp2)) return 0.0f;
    tt__to_local(&v->frame, wp, a);
    tt__to_local(&v->frame, wn, b);
    pdf = tt__bsdf_pdf(&v->bsdf, a, b);
  }
  return tt__bv_convert(v, pdf, next);
}

/* ---- multiple importance sampling (pbrt-v3 MISWeight) ---- */

#define TT__BDPT_MAX_VERTS 66

float tt__bdpt_mis_weight(const tt_path_tracer *pt, const tt_camera_frame *frame,
                          tt_mis_heuristic heuristic, const tt__bvertex *light,
                          const tt__bvertex *camera, const tt__bvertex *sampled, uint32_t s,
                          uint32_t t) {
  if (s + t == 2) return 1.0f;
  if (s > TT__BDPT_MAX_VERTS || t > TT__BDPT_MAX_VERTS || t == 0) return 0.0f;
  /* Copies of the densities: the connection's vertices get the densities of this strategy. */
  float cf[TT__BDPT_MAX_VERTS], cr[TT__BDPT_MAX_VERTS], lf[TT__BDPT_MAX_VERTS],
      lr[TT__BDPT_MAX_VERTS];
  uint8_t cd[TT__BDPT_MAX_VERTS], ld[TT__BDPT_MAX_VERTS];
  const tt__bvertex *qs = s == 0 ? NULL : s == 1 ? sampled : &light[s - 1];
  const tt__bvertex *ptv = t == 1 ? sampled : &camera[t - 1];
  const tt__bvertex *qsm = s > 1 ? &light[s - 2] : NULL;
  const tt__bvertex *ptm = t > 1 ? &camera[t - 2] : NULL;
  for (uint32_t i = 0; i < t; ++i) {
    const tt__bvertex *v = i == t - 1 ? ptv : &camera[i];
    cf[i] = v->pdf_fwd;
    cr[i] = v->pdf_rev;
    cd[i] = v->delta;
  }
  for (uint32_t i = 0; i < s; ++i) {
    const tt__bvertex *v = i == s - 1 ? qs : &light[i];
    lf[i] = v->pdf_fwd;
    lr[i] = v->pdf_rev;
    ld[i] = v->delta;
  }
  /* The connected vertices are not delta (they were joined), and their reverse densities
   * (and their predecessors') are those of this strategy's path. */
  cd[t - 1] = 0;
  if (s > 0) ld[s - 1] = 0;
  cr[t - 1] = s > 0 ? tt__bv_pdf(pt, frame, qs, qsm, ptv) : tt__bv_pdf_light_origin(pt, ptv, ptm);
  if (ptm) cr[t - 2] = s > 0 ? tt__bv_pdf(pt, frame, ptv, qs, ptm) : tt__bv_pdf_light(pt, ptv, ptm);
  if (qs) lr[s - 1] = tt__bv_pdf(pt, frame, ptv, ptm, qs);
  if (qsm) lr[s - 2] = tt__bv_pdf(pt, frame, qs, ptv, qsm);
  const int power = heuristic != TT_MIS_BALANCE;
#define TT__REMAP(x) ((x) != 0.0f ? (x) : 1.0f)
  double sum = 0.0, ri = 1.0;
  for (uint32_t i = t - 1; i > 0; --i) {
    ri *= (double)TT__REMAP(cr[i]) / (double)TT__REMAP(cf[i]);
    if (!cd[i] && !cd[i - 1]) sum += power ? ri * ri : ri;
  }
  ri = 1.0;
  for (uint32_t k = s; k > 0; --k) {
    uint32_t i = k - 1;
    ri *= (double)TT__REMAP(lr[i]) / (double)TT__REMAP(lf[i]);
    int delta_before = i > 0 ? ld[i - 1] : tt__bv_delta_light(pt, s == 1 ? sampled : &light[0]);
    if (!ld[i] && !delta_before) sum += power ? ri * ri : ri;
  }
#undef TT__REMAP
  double w = 1.0 / (1.0 + sum);
  return isfinite(w) ? (float)w : 0.0f;
}

/* ---- subpaths ---- */

/* Extends a subpath from vertex `k0 - 1` along `ray` (pbrt-v3 RandomWalk): up to `max_new`
 * vertices, each sampling the next direction from the stream at dim_base + 4 (index - 1).
 * `pdf` is the solid-angle density of `ray`'s direction at the previous vertex. Camera
 * subpaths (radiance) end with a vertex at infinity when they escape into an environment.
 * Returns the number of vertices added. */
static uint32_t tt__bdpt_walk(const tt_path_tracer *pt, const tt_tracer *tracer,
                              const tt_bdpt_options *o, tt_ray ray, float beta[3], float pdf,
                              uint32_t max_new, int adjoint, const tt_sample_source *src,
                              uint32_t dim_base, tt__bvertex *verts, uint32_t k0,
                              tt_bdpt_paths *paths) {
  const tt__lights *ls = &pt->lights;
  const float beta0 = tt__max3(beta);
  uint32_t n = 0;
  float pdf_fwd = pdf;
  if (max_new == 0 || !(beta0 > 0.0f)) return 0;
  for (;;) {
    tt_hit hit;
    hit.geom_id = TT_INVALID_ID;
    hit.prim_id = TT_INVALID_ID;
    tracer->iface->intersect1(tracer->accel, &ray, &hit);
    paths->rays++;
    const uint32_t k = k0 + n;
    tt__bvertex *v = &verts[k], *prev = &verts[k - 1];
    memset(v, 0, offsetof(tt__bvertex, frame));
    v->light = -1;
    memcpy(v->beta, beta, sizeof v->beta);
    if (hit.geom_id == TT_INVALID_ID) {
      if (!adjoint && ls->env >= 0 && ls->count > 0) { /* the environment as a light vertex */
        v->kind = TT__BV_LIGHT;
        v->infinite = 1;
        v->light = ls->env;
        for (int i = 0; i < 3; ++i) v->wo[i] = -ray.dir[i];
        v->pdf_fwd = pdf_fwd;
        n++;
      }
      break;
    }
    tt__surface surf;
    if (!tt__surface_at(pt, &hit, &surf)) break; /* degenerate triangle: the path ends */
    v->kind = TT__BV_SURFACE;
    v->on_surface = 1;
    v->mesh = hit.geom_id;
    v->light = ls->mesh_light ? ls->mesh_light[hit.geom_id] : -1;
    memcpy(v->p, surf.p, sizeof v->p);
    memcpy(v->ng, surf.ng_w, sizeof v->ng);
    memcpy(v->ns, surf.ns, sizeof v->ns);
    for (int i = 0; i < 3; ++i) v->wo[i] = -ray.dir[i];
    v->bsdf = *surf.bsdf;
    tt__frame_from(&v->frame, v->ns, surf.e1);
    v->pdf_fwd = tt__bv_convert(prev, pdf_fwd, v);
    n++;
    if (k == 1 && !adjoint) { /* the camera subpath's first hit, for the AOVs */
      paths->hit = 1;
      paths->hit_distance = hit.t;
      float sg = tt__dot3(v->ns, v->wo) < 0.0f ? -1.0f : 1.0f;
      for (int i = 0; i < 3; ++i) paths->hit_normal[i] = sg * v->ns[i];
      tt__bsdf_albedo(&v->bsdf, paths->hit_albedo);
      tt__surface_prev_position(surf.mesh, &hit, surf.p, paths->hit_prev);
    }
    if (n >= max_new) break;

    /* The next direction. */
    if (!tt__bv_side_ok(v, v->wo)) break;
    const uint32_t base = dim_base + TT_BDPT_DIMS_PER_BOUNCE * (k - 1);
    float wo_l[3];
    tt__to_local(&v->frame, v->wo, wo_l);
    float u_lobe = tt__bdpt_dim(src, base + TT_BDPT_BOUNCE_LOBE);
    float u1 = tt__bdpt_dim(src, base + TT_BDPT_BOUNCE_DIR);
    float u2 = tt__bdpt_dim(src, base + TT_BDPT_BOUNCE_DIR + 1);
    tt__bsdf_result bs;
    int ok = adjoint ? tt__bsdf_sample_adjoint(&v->bsdf, wo_l, u_lobe, u1, u2, &bs)
                     : tt__bsdf_sample(&v->bsdf, wo_l, u_lobe, u1, u2, &bs);
    if (!ok) break;
    if (src->report_pdf)
      src->report_pdf(src->self, base + TT_BDPT_BOUNCE_DIR, bs.delta ? 0.0f : bs.pdf);
    float wi[3];
    tt__to_world(&v->frame, bs.wi, wi);
    tt__normalize3(wi);
    float side = tt__dot3(wi, v->ng);
    if (side == 0.0f || (side > 0.0f) != (bs.wi[2] > 0.0f)) break;
    if (!tt__bsdf_transmissive(&v->bsdf) && !(side * tt__dot3(v->wo, v->ng) > 0.0f)) break;
    float scale = fabsf(bs.wi[2]) / bs.pdf;
    if (adjoint) scale *= tt__bv_adjoint_shading(v, v->wo, wi);
    for (int i = 0; i < 3; ++i) beta[i] *= bs.f[i] * scale;
    if (!(tt__max3(beta) > 0.0f) || !isfinite(tt__max3(beta))) break;
    float pdf_rev = 0.0f;
    pdf_fwd = bs.pdf;
    if (bs.delta) {
      v->delta = 1;
      pdf_fwd = 0.0f;
    } else {
      float wi_l[3] = {bs.wi[0], bs.wi[1], bs.wi[2]};
      pdf_rev = tt__bsdf_pdf(&v->bsdf, wi_l, wo_l);
    }
    /* Russian roulette on the throughput relative to the subpath's first: unbiased for every
     * strategy (each divides by its own survival), the weights still sum to 1. */
    if (k - 1 >= o->rr_depth) {
      float q = fminf(1.0f, tt__max3(beta) / beta0);
      float u = tt__bdpt_dim(src, base + TT_BDPT_BOUNCE_RR);
      if (!(u < q)) break;
      for (int i = 0; i < 3; ++i) beta[i] /= q;
    }
    prev->pdf_rev = tt__bv_convert(v, pdf_rev, prev);
    tt__bdpt_offset(v->p, v->ng, wi, ray.org);
    memcpy(ray.dir, wi, sizeof ray.dir);
    ray.tnear = 0.0f;
    ray.tfar = INFINITY;
  }
  return n;
}

TT_API uint32_t tt_bdpt_camera_subpath(const tt_path_tracer *pt, const tt_tracer *tracer,
                                       const tt_bdpt_options *options, const tt_camera_frame *frame,
                                       float fx, float fy, const tt_sample_source *camera,
                                       uint32_t max_vertices, tt_bdpt_paths *paths) {
  paths->n_camera = 0;
  paths->rays = 0;
  paths->hit = 0;
  if (max_vertices > paths->cap) max_vertices = paths->cap;
  if (max_vertices == 0) return 0;
  tt_bdpt_options otmp;
  const tt_bdpt_options *o = tt__bdpt_opts(options, &otmp);
  tt__bvertex *c = &paths->camera[0];
  memset(c, 0, offsetof(tt__bvertex, frame));
  c->kind = TT__BV_CAMERA;
  c->light = -1;
  memcpy(c->p, frame->origin, sizeof c->p);
  memcpy(c->ng, frame->forward, sizeof c->ng);
  memcpy(c->ns, frame->forward, sizeof c->ns);
  c->beta[0] = c->beta[1] = c->beta[2] = 1.0f;
  tt_ray ray;
  tt_camera_generate_ray(frame, fx, fy, &ray);
  float pdf = tt_camera_pdf_dir(frame, ray.dir);
  float beta[3] = {1.0f, 1.0f, 1.0f};
  uint32_t n = 1;
  if (pdf > 0.0f)
    n += tt__bdpt_walk(pt, tracer, o, ray, beta, pdf, max_vertices - 1, 0, camera,
                       TT_BDPT_CAMERA_DIM_FIRST_BOUNCE, paths->camera, 1, paths);
  paths->n_camera = n;
  return n;
}

TT_API uint32_t tt_bdpt_light_subpath(const tt_path_tracer *pt, const tt_tracer *tracer,
                                      const tt_bdpt_options *options, const tt_sample_source *light,
                                      uint32_t max_vertices, tt_bdpt_paths *paths) {
  paths->n_light = 0;
  if (max_vertices > paths->cap) max_vertices = paths->cap;
  if (max_vertices == 0) return 0;
  tt_bdpt_options otmp;
  const tt_bdpt_options *o = tt__bdpt_opts(options, &otmp);
  const tt__lights *ls = &pt->lights;
  tt__emission em;
  float u_sel = tt__bdpt_dim(light, TT_BDPT_LIGHT_DIM_SELECT);
  float u1 = tt__bdpt_dim(light, TT_BDPT_LIGHT_DIM_POS),
        u2 = tt__bdpt_dim(light, TT_BDPT_LIGHT_DIM_POS + 1);
  float u3 = tt__bdpt_dim(light, TT_BDPT_LIGHT_DIM_DIR),
        u4 = tt__bdpt_dim(light, TT_BDPT_LIGHT_DIM_DIR + 1);
  if (!tt__lights_sample_emission(ls, u_sel, u1, u2, u3, u4, &em)) return 0;
  const tt__light *l = &ls->lights[em.light];
  tt__bvertex *v = &paths->light[0];
  memset(v, 0, offsetof(tt__bvertex, frame));
  v->kind = TT__BV_LIGHT;
  v->light = (int32_t)em.light;
  v->infinite = (uint8_t)tt__light_infinite(l);
  v->on_surface = l->type == TT_LIGHT_AREA;
  memcpy(v->p, em.p, sizeof v->p);
  memcpy(v->ng, em.n, sizeof v->ng);
  memcpy(v->ns, em.n, sizeof v->ns);
  memcpy(v->wo, em.dir, sizeof v->wo);
  memcpy(v->beta, em.Le, sizeof v->beta);
  v->pdf_fwd = em.pdf_pos * em.pmf;
  float cos_l = v->on_surface ? fabsf(tt__dot3(em.n, em.dir)) : 1.0f;
  float k = cos_l / (em.pmf * em.pdf_pos * em.pdf_dir), beta[3];
  for (int i = 0; i < 3; ++i) beta[i] = em.Le[i] * k;
  tt_ray ray;
  if (v->on_surface) tt__bdpt_offset(em.p, em.n, em.dir, ray.org);
  else memcpy(ray.org, em.p, sizeof ray.org);
  memcpy(ray.dir, em.dir, sizeof ray.dir);
  ray.tnear = 0.0f;
  ray.tfar = INFINITY;
  uint32_t n = 1;
  if (isfinite(tt__max3(beta)))
    n += tt__bdpt_walk(pt, tracer, o, ray, beta, em.pdf_dir, max_vertices - 1, 1, light,
                       TT_BDPT_LIGHT_DIM_FIRST_BOUNCE, paths->light, 1, paths);
  if (v->infinite) { /* densities of a start at infinity: the disk, then the direction */
    if (n > 1) {
      tt__bvertex *v1 = &paths->light[1];
      v1->pdf_fwd = em.pdf_pos * (v1->on_surface ? fabsf(tt__dot3(em.dir, v1->ng)) : 1.0f);
    }
    v->pdf_fwd = tt__bv_pdf_light_origin(pt, v, v);
  }
  paths->n_light = n;
  return n;
}

/* ---- connections ---- */

/* Non-zero if nothing blocks the segment between a (at p, normal ng when on a surface) and b
 * (likewise; at infinity along w when `to_infinity`). */
static int tt__bdpt_visible(const tt_tracer *tracer, const tt__bvertex *a, const tt__bvertex *b,
                            tt_bdpt_paths *paths) {
  float w[3], d2;
  if (!tt__bv_dir(a, b, w, &d2)) return 0;
  tt_ray r;
  if (a->on_surface) tt__bdpt_offset(a->p, a->ng, w, r.org);
  else memcpy(r.org, a->p, sizeof r.org);
  r.tnear = 0.0f;
  if (b->infinite) {
    memcpy(r.dir, w, sizeof r.dir);
    r.tfar = INFINITY;
  } else {
    float end[3], back[3] = {-w[0], -w[1], -w[2]};
    if (b->on_surface) tt__bdpt_offset(b->p, b->ng, back, end);
    else memcpy(end, b->p, sizeof end);
    for (int i = 0; i < 3; ++i) r.dir[i] = end[i] - r.org[i];
    float len = tt__normalize3(r.dir);
    if (!(len > 0.0f)) return 1;
    r.tfar = len * (1.0f - 1e-4f);
  }
  paths->rays++;
  return !tracer->iface->occluded1(tracer->accel, &r);
}

/* Emission of light vertex / emissive surface v towards vertex `to`. */
static int tt__bv_Le(const tt_path_tracer *pt, const tt__bvertex *v, const tt__bvertex *to,
                     float L[3]) {
  if (v->infinite) {
    float d[3] = {-v->wo[0], -v->wo[1], -v->wo[2]};
    return tt__lights_env(&pt->lights, d, L);
  }
  if (v->kind != TT__BV_SURFACE || v->light < 0) return 0;
  float w[3], d2;
  if (!tt__bv_dir(v, to, w, &d2)) return 0;
  return tt__lights_emitted(&pt->lights, v->mesh, v->ng, w, L);
}

TT_API int tt_bdpt_connect(const tt_path_tracer *pt, const tt_tracer *tracer,
                           const tt_bdpt_options *options, const tt_camera_frame *frame,
                           tt_bdpt_paths *paths, uint32_t s, uint32_t t,
                           const tt_sample_source *connect, uint32_t connect_base,
                           tt_bdpt_contribution *out) {
  memset(out, 0, sizeof *out);
  if (t == 0 || t > paths->n_camera || s > paths->n_light || (s == 1 && t == 1)) return 0;
  tt_bdpt_options otmp;
  const tt_bdpt_options *o = tt__bdpt_opts(options, &otmp);
  const tt__bvertex *cam = paths->camera, *lig = paths->light;
  /* A camera subpath that escaped is only its own (s = 0) strategy. */
  if (t > 1 && s != 0 && cam[t - 1].kind == TT__BV_LIGHT) return 0;
  tt__bvertex sampled;
  float L[3] = {0.0f, 0.0f, 0.0f};
  if (s == 0) {
    const tt__bvertex *ptv = &cam[t - 1];
    float Le[3];
    if (t < 2 || !tt__bv_is_light(ptv) || !tt__bv_Le(pt, ptv, &cam[t - 2], Le)) return 0;
    for (int i = 0; i < 3; ++i) L[i] = Le[i] * ptv->beta[i];
  } else if (t == 1) {
    const tt__bvertex *qs = &lig[s - 1];
    if (!tt__bv_connectible(pt, qs) || qs->kind != TT__BV_SURFACE) return 0;
    memset(&sampled, 0, offsetof(tt__bvertex, frame));
    sampled.kind = TT__BV_CAMERA;
    sampled.light = -1;
    memcpy(sampled.p, frame->origin, sizeof sampled.p);
    memcpy(sampled.ng, frame->forward, sizeof sampled.ng);
    memcpy(sampled.ns, frame->forward, sizeof sampled.ns);
    float w[3], d2; /* from the camera towards qs */
    if (!tt__bv_dir(&sampled, qs, w, &d2)) return 0;
    float we = tt_camera_importance(frame, w, &out->fx, &out->fy);
    if (!(we > 0.0f)) return 0;
    float pdf = d2 / tt__dot3(frame->forward, w); /* pinhole: lens area 1 */
    for (int i = 0; i < 3; ++i) sampled.beta[i] = we / pdf;
    float f[3], back[3] = {-w[0], -w[1], -w[2]};
    tt__bv_f(qs, &sampled, 1, f);
    float c = fabsf(tt__dot3(back, qs->ns));
    for (int i = 0; i < 3; ++i) L[i] = qs->beta[i] * f[i] * sampled.beta[i] * c;
    if (tt__max3(L) > 0.0f && !tt__bdpt_visible(tracer, qs, &sampled, paths)) return 0;
  } else if (s == 1) {
    const tt__bvertex *ptv = &cam[t - 1];
    if (!tt__bv_connectible(pt, ptv) || ptv->kind != TT__BV_SURFACE) return 0;
    tt__light_point lp;
    float u_sel = tt__bdpt_dim(connect, connect_base + TT_BDPT_CONNECT_DIM_SELECT);
    float u1 = tt__bdpt_dim(connect, connect_base + TT_BDPT_CONNECT_DIM_POS);
    float u2 = tt__bdpt_dim(connect, connect_base + TT_BDPT_CONNECT_DIM_POS + 1);
    if (!tt__lights_sample_point(&pt->lights, ptv->p, u_sel, u1, u2, &lp)) return 0;
    const tt__light *l = &pt->lights.lights[lp.light];
    memset(&sampled, 0, offsetof(tt__bvertex, frame));
    sampled.kind = TT__BV_LIGHT;
    sampled.light = (int32_t)lp.light;
    sampled.infinite = isinf(lp.dist) ? 1 : 0;
    sampled.on_surface = l->type == TT_LIGHT_AREA;
    memcpy(sampled.p, lp.p, sizeof sampled.p);
    memcpy(sampled.ng, lp.n, sizeof sampled.ng);
    memcpy(sampled.ns, lp.n, sizeof sampled.ns);
    for (int i = 0; i < 3; ++i) {
      sampled.wo[i] = -lp.wi[i];
      sampled.beta[i] = lp.Li[i] / (lp.pdf * lp.pmf);
    }
    sampled.pdf_fwd = tt__bv_pdf_light_origin(pt, &sampled, ptv);
    float f[3];
    tt__bv_f(ptv, &sampled, 0, f);
    float c = fabsf(tt__dot3(lp.wi, ptv->ns));
    for (int i = 0; i < 3; ++i) L[i] = ptv->beta[i] * f[i] * sampled.beta[i] * c;
    if (tt__max3(L) > 0.0f && !tt__bdpt_visible(tracer, ptv, &sampled, paths)) return 0;
  } else {
    const tt__bvertex *qs = &lig[s - 1], *ptv = &cam[t - 1];
    if (!tt__bv_connectible(pt, qs) || !tt__bv_connectible(pt, ptv)) return 0;
    float fq[3], fp[3], w[3], d2;
    tt__bv_f(qs, ptv, 1, fq);
    tt__bv_f(ptv, qs, 0, fp);
    if (!(tt__max3(fq) > 0.0f) || !(tt__max3(fp) > 0.0f) || !tt__bv_dir(qs, ptv, w, &d2)) return 0;
    float g = fabsf(tt__dot3(qs->ns, w)) * fabsf(tt__dot3(ptv->ns, w)) / d2;
    for (int i = 0; i < 3; ++i) L[i] = qs->beta[i] * fq[i] * fp[i] * ptv->beta[i] * g;
    if (tt__max3(L) > 0.0f && !tt__bdpt_visible(tracer, qs, ptv, paths)) return 0;
  }
  if (!isfinite(L[0]) || !isfinite(L[1]) || !isfinite(L[2])) {
    out->nonfinite = 1;
    return 0;
  }
  if (!(tt__max3(L) > 0.0f)) return 0;
  float w = tt__bdpt_mis_weight(pt, frame, o->heuristic, lig, cam,
                                (s == 1 || t == 1) ? &sampled : NULL, s, t);
  memcpy(out->unweighted, L, sizeof out->unweighted);
  out->weight = w;
  for (int i = 0; i < 3; ++i) out->L[i] = L[i] * w;
  if (!isfinite(out->L[0]) || !isfinite(out->L[1]) || !isfinite(out->L[2])) {
    memset(out, 0, sizeof *out);
    out->nonfinite = 1;
    return 0;
  }
  return tt__max3(out->L) > 0.0f;
}
