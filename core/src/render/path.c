/* tunetrace: the shared path sampler (path.h): unidirectional path tracing with next-event
 * estimation and BSDF sampling combined by multiple importance sampling (Veach 1997), with
 * every random decision read from a fixed dimension of a tt_sample_source so that the same
 * code serves the path tracer (quasi-random samplers) and PSSMLT (primary-sample vectors). */
#include <tunetrace/path.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <tunetrace/image.h>

#include "render/path_internal.h"

/* sRGB decoding of one channel. */
static float tt__srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

/* Loads texture `index` of the scene into linear RGB (once, at tracer creation), or opens
 * it in the OIIO TextureSystem when `use_oiio`. */
static tt_status tt__load_texture(const tt_scene *scene, uint32_t index, int use_oiio,
                                  tt__texture_data *out) {
  const tt_texture *t = tt_scene_texture(scene, index);
  if (use_oiio) return tt__oiio_tex_open(t->path, t->srgb, &out->oiio);
  uint32_t w = 0, h = 0, c = 0;
  float *px = NULL;
  tt_status st = tt_image_read(t->path, &w, &h, &c, &px);
  if (st != TT_OK) return st;
  if (w == 0 || h == 0 || c == 0) {
    tt_free(px);
    return tt_set_error(TT_ERR_PARSE, "texture '%s' is empty", t->path);
  }
  out->rgb = malloc(sizeof(float) * 3 * (size_t)w * h);
  if (!out->rgb) {
    tt_free(px);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "texture '%s': out of memory", t->path);
  }
  for (size_t i = 0; i < (size_t)w * h; ++i)
    for (int k = 0; k < 3; ++k) {
      float v = px[i * c + (c >= 3 ? (uint32_t)k : 0)];
      out->rgb[3 * i + k] = t->srgb ? tt__srgb_to_linear(v) : v;
    }
  out->width = w;
  out->height = h;
  tt_free(px);
  return TT_OK;
}

/* Bilinear lookup with wrap-around; v = 0 is the bottom of the image (OBJ convention). */
static void tt__texture_lookup(const tt__texture_data *t, float u, float v, float out[3]) {
  if (t->oiio) {
    tt__oiio_tex_lookup(t->oiio, u, v, out);
    return;
  }
  float x = (u - floorf(u)) * (float)t->width - 0.5f;
  float y = (1.0f - (v - floorf(v))) * (float)t->height - 0.5f;
  float fx = floorf(x), fy = floorf(y), ax = x - fx, ay = y - fy;
  int64_t x0 = (int64_t)fx, y0 = (int64_t)fy;
  out[0] = out[1] = out[2] = 0.0f;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      int64_t xi = ((x0 + i) % t->width + t->width) % t->width;
      int64_t yi = ((y0 + j) % t->height + t->height) % t->height;
      float wgt = (i ? ax : 1.0f - ax) * (j ? ay : 1.0f - ay);
      const float *p = t->rgb + 3 * ((size_t)yi * t->width + (size_t)xi);
      for (int k = 0; k < 3; ++k) out[k] += wgt * p[k];
    }
}

void tt__surface_prev_position(const tt_mesh *mesh, const tt_hit *hit, const float p[3],
                               float out[3]) {
  memcpy(out, p, 3 * sizeof(float));
  if (!TT_HAS_FIELD(tt_mesh, mesh, revision) || mesh->motion == TT_MESH_STATIC ||
      !mesh->prev_positions || mesh->prev_positions == mesh->positions)
    return;
  const uint32_t *idx = mesh->indices + 3 * (size_t)hit->prim_id;
  const float w[3] = {1.0f - hit->u - hit->v, hit->u, hit->v};
  for (int i = 0; i < 3; ++i) {
    float d = 0.0f;
    for (int k = 0; k < 3; ++k)
      d += w[k] *
           (mesh->prev_positions[3 * (size_t)idx[k] + i] - mesh->positions[3 * (size_t)idx[k] + i]);
    out[i] = p[i] + d;
  }
}

int tt__surface_at(const tt_path_tracer *pt, const tt_hit *hitp, tt__surface *s) {
  const tt_hit hit = *hitp;
  const tt_mesh *mesh = tt_scene_mesh(pt->scene, hit.geom_id);
  const uint32_t *idx = mesh->indices + 3 * (size_t)hit.prim_id;
  const float *p0 = mesh->positions + 3 * (size_t)idx[0];
  const float *p1 = mesh->positions + 3 * (size_t)idx[1];
  const float *p2 = mesh->positions + 3 * (size_t)idx[2];
  float w0 = 1.0f - hit.u - hit.v, e2[3];
  float *p = s->p, *e1 = s->e1, *ng = s->ng_w, *ns = s->ns;
  s->mesh = mesh;
  for (int i = 0; i < 3; ++i) {
    p[i] = w0 * p0[i] + hit.u * p1[i] + hit.v * p2[i];
    e1[i] = p1[i] - p0[i];
    e2[i] = p2[i] - p0[i];
  }
  tt__cross3(e1, e2, ng);
  if (tt__normalize3(ng) == 0.0f) return 0; /* degenerate triangle */
  if (mesh->normals) {
    const float *n0 = mesh->normals + 3 * (size_t)idx[0];
    const float *n1 = mesh->normals + 3 * (size_t)idx[1];
    const float *n2 = mesh->normals + 3 * (size_t)idx[2];
    for (int i = 0; i < 3; ++i) ns[i] = w0 * n0[i] + hit.u * n1[i] + hit.v * n2[i];
    if (tt__normalize3(ns) == 0.0f) memcpy(ns, ng, 3 * sizeof(float));
    else if (tt__dot3(ns, ng) < 0.0f)
      for (int i = 0; i < 3; ++i) ns[i] = -ns[i]; /* to the geometric side */
  } else {
    memcpy(ns, ng, 3 * sizeof(float));
  }
  s->bsdf = &pt->bsdfs[mesh->material];
  int32_t tex = pt->material_texture[mesh->material];
  if (tex >= 0 && mesh->uvs) { /* albedo modulated by the texture at the hit's uv */
    const float *t0 = mesh->uvs + 2 * (size_t)idx[0], *t1 = mesh->uvs + 2 * (size_t)idx[1],
                *t2 = mesh->uvs + 2 * (size_t)idx[2];
    float tc[3];
    tt__texture_lookup(&pt->textures[tex], w0 * t0[0] + hit.u * t1[0] + hit.v * t2[0],
                       w0 * t0[1] + hit.u * t1[1] + hit.v * t2[1], tc);
    s->textured = *s->bsdf;
    for (int i = 0; i < 3; ++i) s->textured.albedo[i] *= fminf(fmaxf(tc[i], 0.0f), 1.0f);
    s->bsdf = &s->textured;
  }
  return 1;
}

TT_API void tt_path_options_default(tt_path_options *options) {
  if (!options) return;
  memset(options, 0, sizeof *options);
  options->struct_size = sizeof *options;
  options->max_depth = 3;
  options->rr_depth = 3;
  options->strategy = TT_STRATEGY_MIS;
  options->heuristic = TT_MIS_POWER;
}

TT_API tt_dim_kind tt_path_dim_kind(uint32_t dim) {
  if (dim < TT_PATH_DIM_LENS) return TT_DIM_FILM;
  if (dim < TT_PATH_DIM_FIRST_BOUNCE) return TT_DIM_LENS;
  switch ((dim - TT_PATH_DIM_FIRST_BOUNCE) % TT_PATH_DIMS_PER_BOUNCE) {
  case TT_PATH_BOUNCE_LIGHT_SELECT: return TT_DIM_LIGHT_SELECT;
  case TT_PATH_BOUNCE_LIGHT_POS:
  case TT_PATH_BOUNCE_LIGHT_POS + 1: return TT_DIM_LIGHT_POS;
  case TT_PATH_BOUNCE_BSDF_LOBE: return TT_DIM_BSDF_LOBE;
  case TT_PATH_BOUNCE_BSDF_DIR:
  case TT_PATH_BOUNCE_BSDF_DIR + 1: return TT_DIM_BSDF_DIR;
  case TT_PATH_BOUNCE_RR: return TT_DIM_RR;
  default: return TT_DIM_RESERVED;
  }
}

TT_API tt_status tt_path_tracer_create(const tt_scene *scene, tt_path_tracer **out) {
  if (!scene || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_path_tracer_create: scene or out is NULL");
  *out = NULL;
  tt_path_tracer *pt = calloc(1, sizeof *pt);
  if (!pt) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_path_tracer_create: out of memory");
  pt->scene = scene;
  pt->lights.env = -1;
  pt->material_count = tt_scene_material_count(scene);
  pt->bsdfs = calloc(pt->material_count ? pt->material_count : 1, sizeof *pt->bsdfs);
  if (!pt->bsdfs) {
    free(pt);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_path_tracer_create: out of memory");
  }
  /* Only materials that a mesh uses must be renderable. */
  uint8_t *used = calloc(pt->material_count ? pt->material_count : 1, 1);
  if (!used) {
    tt_path_tracer_destroy(pt);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_path_tracer_create: out of memory");
  }
  tt_status st = TT_OK;
  for (uint32_t m = 0; m < tt_scene_mesh_count(scene) && st == TT_OK; ++m) {
    const tt_mesh *mesh = tt_scene_mesh(scene, m);
    if (mesh->material >= pt->material_count)
      st = tt_set_error(TT_ERR_INVALID_ARGUMENT, "mesh '%s': material index %u out of range",
                        mesh->name ? mesh->name : "?", mesh->material);
    else used[mesh->material] = 1;
  }
  for (uint32_t i = 0; i < pt->material_count && st == TT_OK; ++i) {
    tt_status ms = tt__bsdf_init(&pt->bsdfs[i], tt_scene_material(scene, i));
    if (ms != TT_OK && used[i]) st = ms;
  }
  /* Albedo textures of used materials, loaded once. */
  pt->texture_count = tt_scene_texture_count(scene);
  pt->material_texture =
      malloc((pt->material_count ? pt->material_count : 1) * sizeof *pt->material_texture);
  pt->textures = calloc(pt->texture_count ? pt->texture_count : 1, sizeof *pt->textures);
  if (st == TT_OK && (!pt->material_texture || !pt->textures))
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_path_tracer_create: out of memory");
  const char *tex_mode = getenv("TT_TEXTURES");
  const int use_oiio = tex_mode && strcmp(tex_mode, "oiio") == 0;
  for (uint32_t i = 0; i < pt->material_count && st == TT_OK; ++i) {
    int32_t tex = tt_scene_material(scene, i)->albedo_texture;
    pt->material_texture[i] = -1;
    if (!used[i] || tex < 0) continue;
    if ((uint32_t)tex >= pt->texture_count) {
      st = tt_set_error(TT_ERR_INVALID_ARGUMENT, "material %u: texture index %d out of range", i,
                        tex);
      break;
    }
    if (!pt->textures[tex].rgb && !pt->textures[tex].oiio)
      st = tt__load_texture(scene, (uint32_t)tex, use_oiio, &pt->textures[tex]);
    pt->material_texture[i] = tex;
  }
  free(used);
  if (st == TT_OK) st = tt__lights_init(&pt->lights, scene);
  if (st != TT_OK) {
    tt_path_tracer_destroy(pt);
    return st;
  }
  *out = pt;
  return TT_OK;
}

TT_API void tt_path_tracer_destroy(tt_path_tracer *pt) {
  if (!pt) return;
  tt__lights_free(&pt->lights);
  if (pt->textures)
    for (uint32_t i = 0; i < pt->texture_count; ++i) {
      free(pt->textures[i].rgb);
      tt__oiio_tex_close(pt->textures[i].oiio);
    }
  free(pt->textures);
  free(pt->material_texture);
  free(pt->bsdfs);
  free(pt);
}

/* Reads dimension `dim`, clamped into [0, 1) against sloppy sources, tracking max_dim. */
static inline float tt__dim(const tt_sample_source *src, uint32_t dim, uint32_t *max_dim) {
  if (dim + 1 > *max_dim) *max_dim = dim + 1;
  float u = src->get(src->self, dim);
  if (!(u >= 0.0f)) u = 0.0f;
  if (u >= 1.0f) u = 0x1.fffffep-1f;
  return u;
}

/* MIS weight of a strategy with pdf a against one with pdf b. */
static inline float tt__mis(tt_mis_heuristic h, float a, float b) {
  if (isinf(a)) return 1.0f;
  if (!(a > 0.0f)) return 0.0f;
  if (h == TT_MIS_BALANCE) return a / (a + b);
  float a2 = a * a, b2 = b * b;
  return a2 / (a2 + b2);
}

/* Moves p off the surface along the geometric normal, to the side of w, by an amount that
 * grows with |p| (float spacing grows with magnitude). */
static inline void tt__offset(const float p[3], const float ng[3], const float w[3], float out[3]) {
  float m = fmaxf(fabsf(p[0]), fmaxf(fabsf(p[1]), fabsf(p[2])));
  float eps = 5e-5f * (1.0f + m);
  if (tt__dot3(w, ng) < 0.0f) eps = -eps;
  for (int i = 0; i < 3; ++i) out[i] = p[i] + eps * ng[i];
}

/* A path between steps (tt_path_begin / tt_path_hit / tt_path_shadow / tt_path_finish).
 * Everything tt_path_trace kept in locals across bounces lives here, so a wavefront
 * integrator can hold many paths at once and trace their rays in streams. */
struct tt_path_state {
  tt_path_options o;
  float L[3], beta[3];
  float pending[3]; /* next-event contribution, added if its shadow ray is free */
  float prev_pdf, prev_p[3], prev_n[3];
  int32_t prev_delta;
  int32_t has_pending;
  uint32_t bounce; /* index of the surface interaction the next hit is */
  uint32_t max_dim;
  tt_path_result out; /* first-hit data, ray and bounce counts so far */
};

TT_API size_t tt_path_state_size(void) { return sizeof(tt_path_state); }

TT_API int tt_path_begin(const tt_path_tracer *pt, const tt_path_options *options,
                         const tt_ray *camera_ray, tt_path_state *st, tt_ray *ray) {
  (void)pt;
  memset(st, 0, sizeof *st);
  st->out.distance = INFINITY;
  tt_path_options_default(&st->o);
  if (options) {
    size_t n = options->struct_size < sizeof st->o ? options->struct_size : sizeof st->o;
    if (n > 0) memcpy(&st->o, options, n);
  }
  for (int i = 0; i < 3; ++i) st->beta[i] = 1.0f;
  st->prev_delta = 1;
  st->prev_n[2] = 1.0f;
  *ray = *camera_ray;
  float dlen = tt__normalize3(ray->dir);
  if (!(dlen > 0.0f)) return 0;
  ray->tnear *= dlen;
  ray->tfar *= dlen;
  return 1;
}

TT_API int tt_path_hit(const tt_path_tracer *pt, tt_path_state *st, const tt_ray *traced,
                       const tt_hit *hitp, const tt_sample_source *source, tt_ray *shadow,
                       int *has_shadow, tt_ray *next) {
  const tt_path_options o = st->o;
  const tt__lights *lights = &pt->lights;
  const int use_nee = o.strategy != TT_STRATEGY_BSDF;
  /* Emission found by BSDF sampling after bounce 0 counts fully (BSDF), not at all (light
   * only), or MIS-weighted. */
  const int mis_on = o.strategy == TT_STRATEGY_MIS && o.heuristic != TT_MIS_NONE;
  const int count_bsdf_hits = o.strategy == TT_STRATEGY_BSDF || mis_on;
  tt_path_result *out = &st->out;
  float *L = st->L, *beta = st->beta;
  const uint32_t b = st->bounce;
  const tt_hit hit = *hitp;
  *has_shadow = 0;
  out->rays++;
  if (hit.geom_id == TT_INVALID_ID) {
    float Le[3];
    if (tt__lights_env(lights, traced->dir, Le) && (b == 0 || st->prev_delta || count_bsdf_hits)) {
      float w = 1.0f;
      if (b > 0 && !st->prev_delta && mis_on)
        w = tt__mis(o.heuristic, st->prev_pdf, tt__lights_pdf_env(lights, st->prev_n, traced->dir));
      for (int i = 0; i < 3; ++i) L[i] += beta[i] * Le[i] * w;
    }
    return 0;
  }

  /* Surface geometry: position from barycentrics, winding normal, shading normal. */
  tt__surface surf;
  if (!tt__surface_at(pt, &hit, &surf)) return 0; /* degenerate triangle */
  const tt_mesh *mesh = surf.mesh;
  float *p = surf.p, *e1 = surf.e1, *ng_w = surf.ng_w, ng[3], ns[3], wo[3];
  for (int i = 0; i < 3; ++i) wo[i] = -traced->dir[i];
  memcpy(ng, ng_w, sizeof ng);
  memcpy(ns, surf.ns, sizeof ns);
  const tt__bsdf *bsdf = surf.bsdf;
  /* Opaque surfaces are two-sided: orient both normals towards the viewer. */
  if (!tt__bsdf_transmissive(bsdf) && tt__dot3(wo, ng) < 0.0f)
    for (int i = 0; i < 3; ++i) {
      ng[i] = -ng[i];
      ns[i] = -ns[i];
    }

  if (b == 0) {
    out->hit = 1;
    out->distance = hit.t;
    memcpy(out->position, p, sizeof out->position);
    tt__surface_prev_position(mesh, &hit, p, out->prev_position);
    float s = tt__dot3(ns, wo) < 0.0f ? -1.0f : 1.0f;
    for (int i = 0; i < 3; ++i) out->normal[i] = s * ns[i];
    tt__bsdf_albedo(bsdf, out->albedo);
  }

  /* Emission (one-sided lights emit along the winding normal only). */
  if (mesh->light >= 0 && (b == 0 || st->prev_delta || count_bsdf_hits)) {
    float Le[3];
    if (tt__lights_emitted(lights, hit.geom_id, ng_w, wo, Le)) {
      float w = 1.0f;
      if (b > 0 && !st->prev_delta && mis_on)
        w = tt__mis(o.heuristic, st->prev_pdf,
                    tt__lights_pdf_area(lights, hit.geom_id, st->prev_p, p, ng_w));
      for (int i = 0; i < 3; ++i) L[i] += beta[i] * Le[i] * w;
    }
  }
  if (b >= o.max_depth) return 0;
  out->bounces++;

  const uint32_t base = TT_PATH_DIM_FIRST_BOUNCE + TT_PATH_DIMS_PER_BOUNCE * b;
  tt__frame fr;
  tt__frame_from(&fr, ns, e1);
  float wo_l[3];
  tt__to_local(&fr, wo, wo_l);

  /* Next-event estimation: the shadow ray and, should it be free, its contribution. */
  if (use_nee && !bsdf->delta && lights->count > 0) {
    float u_sel = tt__dim(source, base + TT_PATH_BOUNCE_LIGHT_SELECT, &st->max_dim);
    float u1 = tt__dim(source, base + TT_PATH_BOUNCE_LIGHT_POS, &st->max_dim);
    float u2 = tt__dim(source, base + TT_PATH_BOUNCE_LIGHT_POS + 1, &st->max_dim);
    tt__light_sample ls;
    if (tt__lights_sample(lights, p, ns, u_sel, u1, u2, &ls)) {
      float wi_l[3], f[3] = {0.0f, 0.0f, 0.0f};
      tt__to_local(&fr, ls.wi, wi_l);
      /* The light must lie on the geometric side the shading frame says (opaque surfaces
       * face the viewer, so only the front; rough glass may also transmit). */
      float side = tt__dot3(ls.wi, ng);
      int side_ok = tt__bsdf_transmissive(bsdf) ? side != 0.0f && (side > 0.0f) == (wi_l[2] > 0.0f)
                                                : side > 0.0f;
      if (side_ok) tt__bsdf_eval(bsdf, wo_l, wi_l, f);
      if (tt__max3(f) > 0.0f) {
        tt__offset(p, ng, ls.wi, shadow->org);
        memcpy(shadow->dir, ls.wi, sizeof shadow->dir);
        shadow->tnear = 0.0f;
        shadow->tfar = isinf(ls.dist) ? INFINITY : ls.dist * (1.0f - 1e-3f);
        out->rays++;
        float w = 1.0f;
        if (!ls.delta && mis_on) w = tt__mis(o.heuristic, ls.pdf, tt__bsdf_pdf(bsdf, wo_l, wi_l));
        float scale = fabsf(wi_l[2]) * w / ls.pdf;
        for (int i = 0; i < 3; ++i) st->pending[i] = beta[i] * f[i] * ls.L[i] * scale;
        st->has_pending = 1;
        *has_shadow = 1;
      }
    }
  }

  /* BSDF sampling continues the path. */
  float u_lobe = tt__dim(source, base + TT_PATH_BOUNCE_BSDF_LOBE, &st->max_dim);
  float u1 = tt__dim(source, base + TT_PATH_BOUNCE_BSDF_DIR, &st->max_dim);
  float u2 = tt__dim(source, base + TT_PATH_BOUNCE_BSDF_DIR + 1, &st->max_dim);
  tt__bsdf_result bs;
  if (!tt__bsdf_sample(bsdf, wo_l, u_lobe, u1, u2, &bs)) return 0;
  if (source->report_pdf)
    source->report_pdf(source->self, base + TT_PATH_BOUNCE_BSDF_DIR, bs.delta ? 0.0f : bs.pdf);
  float wi[3];
  tt__to_world(&fr, bs.wi, wi);
  tt__normalize3(wi);
  /* Shading normals must not send the path through the geometric surface (light leaks). */
  float side = tt__dot3(wi, ng);
  if (side == 0.0f || (side > 0.0f) != (bs.wi[2] > 0.0f)) return 0;
  float scale = fabsf(bs.wi[2]) / bs.pdf;
  for (int i = 0; i < 3; ++i) beta[i] *= bs.f[i] * scale;
  if (!(tt__max3(beta) > 0.0f)) return 0;
  st->prev_delta = bs.delta;
  st->prev_pdf = bs.pdf;
  memcpy(st->prev_p, p, sizeof st->prev_p);
  memcpy(st->prev_n, ns, sizeof st->prev_n);

  /* Russian roulette: survive with probability min(1, max throughput). */
  if (b >= o.rr_depth) {
    float q = fminf(1.0f, tt__max3(beta));
    float u = tt__dim(source, base + TT_PATH_BOUNCE_RR, &st->max_dim);
    if (!(u < q)) return 0;
    for (int i = 0; i < 3; ++i) beta[i] /= q;
  }

  tt__offset(p, ng, wi, next->org);
  memcpy(next->dir, wi, sizeof next->dir);
  next->tnear = 0.0f;
  next->tfar = INFINITY;
  st->bounce = b + 1;
  return 1;
}

TT_API void tt_path_shadow(tt_path_state *st, int occluded) {
  if (!st->has_pending) return;
  st->has_pending = 0;
  if (occluded) return;
  for (int i = 0; i < 3; ++i) st->L[i] += st->pending[i];
}

TT_API void tt_path_finish(const tt_path_state *st, tt_path_result *out) {
  /* the caller's result may end before prev_position (ABI 1.1: result_size 0) */
  size_t size = st->o.result_size >= sizeof *out ? sizeof *out : TT_PATH_RESULT_SIZE_1_1;
  memcpy(out, &st->out, size);
  out->max_dim = st->max_dim;
  const float *L = st->L;
  if (!isfinite(L[0]) || !isfinite(L[1]) || !isfinite(L[2])) {
    out->nonfinite = 1;
    out->L[0] = out->L[1] = out->L[2] = 0.0f;
  } else {
    memcpy(out->L, L, sizeof out->L);
  }
}

TT_API void tt_path_trace(const tt_path_tracer *pt, const tt_tracer *tracer,
                          const tt_path_options *options, const tt_ray *camera_ray,
                          const tt_sample_source *source, tt_path_result *out) {
  _Alignas(16) tt_path_state st;
  tt_ray ray, shadow;
  int more = tt_path_begin(pt, options, camera_ray, &st, &ray);
  while (more) {
    tt_hit hit;
    hit.geom_id = TT_INVALID_ID;
    hit.prim_id = TT_INVALID_ID;
    tracer->iface->intersect1(tracer->accel, &ray, &hit);
    int has_shadow;
    tt_ray next;
    more = tt_path_hit(pt, &st, &ray, &hit, source, &shadow, &has_shadow, &next);
    if (has_shadow) tt_path_shadow(&st, tracer->iface->occluded1(tracer->accel, &shadow));
    if (more) ray = next;
  }
  tt_path_finish(&st, out);
}

/* ---- AOVs ---- */

/* Folds sample `n` of `ch` channels into pixel `pix` of an AOV plane (running mean). */
static void tt__aov_mean(float *plane, size_t pix, uint32_t ch, const float *v, uint64_t n) {
  if (!plane) return;
  float *p = plane + ch * pix;
  for (uint32_t c = 0; c < ch; c++) p[c] = n <= 1 ? v[c] : p[c] + (v[c] - p[c]) / (float)n;
}

void tt_path_write_aovs(tt_film *film, uint32_t x, uint32_t y, const tt_camera_frame *frame,
                        const tt_camera_frame *prev, float fx, float fy, const tt_ray *ray,
                        const tt_path_result *r, uint64_t n) {
  tt_path_write_aovs_ex(film, x, y, frame, prev, fx, fy, ray, r, NULL, n);
}

void tt_path_write_aovs_ex(tt_film *film, uint32_t x, uint32_t y, const tt_camera_frame *frame,
                           const tt_camera_frame *prev, float fx, float fy, const tt_ray *ray,
                           const tt_path_result *r, const float prev_position[3], uint64_t n) {
  size_t pix = (size_t)y * tt_film_width(film) + x;
  float *depth_plane = tt_film_aov(film, TT_AOV_DEPTH),
        *motion_plane = tt_film_aov(film, TT_AOV_MOTION);
  if (depth_plane) {
    float depth = 0.0f;
    if (r->hit) tt_camera_project(frame, r->position, NULL, NULL, &depth);
    tt__aov_mean(depth_plane, pix, 1, &depth, n);
  }
  tt__aov_mean(tt_film_aov(film, TT_AOV_NORMAL), pix, 3, r->normal, n);
  tt__aov_mean(tt_film_aov(film, TT_AOV_ALBEDO), pix, 3, r->albedo, n);
  if (motion_plane) {
    float m[2] = {0.0f, 0.0f}, pfx, pfy;
    if (prev) {
      float target[3];
      if (r->hit) { /* where the surface point was: the object's motion and the camera's */
        memcpy(target, prev_position ? prev_position : r->position, sizeof target);
      } else { /* a point at infinity moves with the camera's rotation only */
        for (int i = 0; i < 3; ++i) target[i] = prev->origin[i] + ray->dir[i];
      }
      if (tt_camera_project(prev, target, &pfx, &pfy, NULL)) {
        m[0] = pfx - fx;
        m[1] = pfy - fy;
      }
    }
    tt__aov_mean(motion_plane, pix, 2, m, n);
  }
  float *prev_depth_plane = tt_film_aov(film, TT_AOV_PREV_DEPTH);
  if (prev_depth_plane) {
    float zp = 0.0f;
    if (r->hit && prev &&
        !tt_camera_project(prev, prev_position ? prev_position : r->position, NULL, NULL, &zp))
      zp = 0.0f;
    tt__aov_mean(prev_depth_plane, pix, 1, &zp, n);
  }
}
