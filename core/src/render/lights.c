/* tunetrace: light sampling (lights_internal.h). Selection among lights by power (the
 * integral of emitted radiance, as pbrt's PowerLightSampler), triangles of an area light by
 * area, uniform points on triangles (pdf 1/area turned into solid angle by d^2/|cos|), image
 * environments by a 2D piecewise-constant distribution (pbrt's Distribution2D). */
#include "render/lights_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <tunetrace/image.h>

#include "render/bsdf_internal.h"
#include "render/warp_internal.h"

#define TT__PI 3.14159265358979324f
#define TT__INV_PI 0.31830988618379067f

/* Fills a normalised CDF (n + 1 entries) from non-negative weights; returns the total. */
static double tt__build_cdf(const double *w, uint32_t n, float *cdf) {
  double total = 0.0;
  for (uint32_t i = 0; i < n; ++i) total += w[i];
  double acc = 0.0;
  cdf[0] = 0.0f;
  for (uint32_t i = 0; i < n; ++i) {
    acc += w[i];
    cdf[i + 1] = total > 0.0 ? (float)(acc / total) : (float)(i + 1) / (float)n;
  }
  cdf[n] = 1.0f;
  return total;
}

/* Area of triangle (p0, p1, p2) in double for a stable CDF. */
static double tt__tri_area(const float *p0, const float *p1, const float *p2) {
  double e1[3], e2[3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = (double)p1[i] - p0[i];
    e2[i] = (double)p2[i] - p0[i];
  }
  double c0 = e1[1] * e2[2] - e1[2] * e2[1];
  double c1 = e1[2] * e2[0] - e1[0] * e2[2];
  double c2 = e1[0] * e2[1] - e1[1] * e2[0];
  return 0.5 * sqrt(c0 * c0 + c1 * c1 + c2 * c2);
}

/* Loads image environment `index` (light `l`), scales it by l->radiance and builds its
 * sampling distribution; *mean_lum gets the solid-angle mean luminance (for its power). */
static tt_status tt__env_image_init(tt__lights *ls, uint32_t index, const tt_light *l,
                                    double *mean_lum) {
  const char *path = l->image ? l->image : "";
  uint32_t w = 0, h = 0, c = 0;
  float *px = NULL;
  if (tt_image_read(path, &w, &h, &c, &px) != TT_OK)
    return tt_set_error(TT_ERR_IO, "light %u: cannot read environment image '%s': %s", index, path,
                        tt_last_error());
  if (w == 0 || h == 0 || c == 0) {
    tt_free(px);
    return tt_set_error(TT_ERR_PARSE, "light %u: environment image '%s' is empty", index, path);
  }
  size_t n = (size_t)w * h;
  ls->env_rgb = malloc(3 * n * sizeof *ls->env_rgb);
  ls->env_weight = malloc(n * sizeof *ls->env_weight);
  ls->env_marginal = malloc((h + 1) * sizeof *ls->env_marginal);
  ls->env_conditional = malloc((size_t)h * (w + 1) * sizeof *ls->env_conditional);
  double *row_w = malloc(w * sizeof *row_w);
  double *marg_w = malloc(h * sizeof *marg_w);
  if (!ls->env_rgb || !ls->env_weight || !ls->env_marginal || !ls->env_conditional || !row_w ||
      !marg_w) {
    tt_free(px);
    free(row_w);
    free(marg_w);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "light %u: out of memory for environment image",
                        index);
  }
  ls->env_w = w;
  ls->env_h = h;
  double total = 0.0, lum_sum = 0.0;
  for (uint32_t y = 0; y < h; ++y) {
    /* Texel rows are bands of equal dtheta: solid angle and weight scale with sin(theta). */
    double th0 = M_PI * y / h, th1 = M_PI * (y + 1) / h;
    double sin_c = sin(0.5 * (th0 + th1)), band = (cos(th0) - cos(th1)) * 2.0 * M_PI / w;
    for (uint32_t x = 0; x < w; ++x) {
      size_t i = (size_t)y * w + x;
      float *rgb = ls->env_rgb + 3 * i;
      for (int k = 0; k < 3; ++k) {
        float v = px[i * c + (c >= 3 ? (uint32_t)k : 0)] * l->radiance[k];
        rgb[k] = v >= 0.0f && isfinite(v) ? v : 0.0f; /* negative/NaN texels emit nothing */
      }
      /* Luminance weights; a texel that is non-black but of zero luminance keeps a chance. */
      double lu = tt__luminance(rgb);
      if (!(lu > 0.0) && tt__max3(rgb) > 0.0f) lu = tt__max3(rgb);
      row_w[x] = lu * sin_c;
      ls->env_weight[i] = (float)row_w[x];
      lum_sum += tt__luminance(rgb) * band;
    }
    marg_w[y] = tt__build_cdf(row_w, w, ls->env_conditional + (size_t)y * (w + 1));
    total += marg_w[y];
  }
  tt__build_cdf(marg_w, h, ls->env_marginal);
  ls->env_pdf_scale = total > 0.0 ? (float)((double)n / total) : 0.0f;
  *mean_lum = lum_sum / (4.0 * M_PI);
  tt_free(px);
  free(row_w);
  free(marg_w);
  return TT_OK;
}

void tt__lights_free(tt__lights *ls) {
  if (!ls) return;
  free(ls->lights);
  free(ls->pmf);
  free(ls->cdf);
  free(ls->tri_cdf);
  free(ls->mesh_light);
  free(ls->env_rgb);
  free(ls->env_marginal);
  free(ls->env_conditional);
  free(ls->env_weight);
  memset(ls, 0, sizeof *ls);
  ls->env = -1;
}

tt_status tt__lights_init(tt__lights *ls, const tt_scene *scene) {
  memset(ls, 0, sizeof *ls);
  ls->env = -1;
  ls->scene = scene;
  uint32_t n = tt_scene_light_count(scene), meshes = tt_scene_mesh_count(scene);
  size_t tri_total = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const tt_light *l = tt_scene_light(scene, i);
    if (l->type == TT_LIGHT_AREA) {
      if (l->mesh >= meshes)
        return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                            "light %u: mesh index %u out of range (%u meshes)", i, l->mesh, meshes);
      tri_total += tt_scene_mesh(scene, l->mesh)->triangle_count + 1;
    } else if (l->type != TT_LIGHT_ENV_IMAGE && l->type != TT_LIGHT_ENV_CONSTANT &&
               l->type != TT_LIGHT_POINT && l->type != TT_LIGHT_SPOT &&
               l->type != TT_LIGHT_DISTANT) {
      return tt_set_error(TT_ERR_UNSUPPORTED, "light %u: unknown light type %d", i, (int)l->type);
    }
  }
  ls->count = n;
  ls->lights = calloc(n ? n : 1, sizeof *ls->lights);
  ls->pmf = calloc(n ? n : 1, sizeof *ls->pmf);
  ls->cdf = calloc(n + 1, sizeof *ls->cdf);
  ls->tri_cdf = calloc(tri_total ? tri_total : 1, sizeof *ls->tri_cdf);
  ls->mesh_light = malloc((meshes ? meshes : 1) * sizeof *ls->mesh_light);
  double *power = calloc(n ? n : 1, sizeof *power);
  double *tri_w = NULL;
  size_t tri_w_cap = 0;
  if (!ls->lights || !ls->pmf || !ls->cdf || !ls->tri_cdf || !ls->mesh_light || !power) {
    free(power);
    tt__lights_free(ls);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "path tracer: out of memory building lights");
  }
  for (uint32_t m = 0; m < meshes; ++m) ls->mesh_light[m] = -1;

  float lo[3], hi[3];
  tt_scene_bounds(scene, lo, hi);
  double radius = 0.0;
  for (int i = 0; i < 3; ++i) {
    double d = isfinite(hi[i] - lo[i]) && hi[i] >= lo[i] ? (double)hi[i] - lo[i] : 0.0;
    radius += d * d;
  }
  radius = 0.5 * sqrt(radius);
  if (!(radius > 0.0)) radius = 1.0;
  ls->radius = (float)radius;
  for (int i = 0; i < 3; ++i)
    ls->center[i] = isfinite(hi[i] - lo[i]) && hi[i] >= lo[i] ? 0.5f * (lo[i] + hi[i]) : 0.0f;

  uint32_t tri_offset = 0;
  tt_status st = TT_OK;
  for (uint32_t i = 0; i < n && st == TT_OK; ++i) {
    const tt_light *l = tt_scene_light(scene, i);
    tt__light *d = &ls->lights[i];
    d->type = l->type;
    memcpy(d->radiance, l->radiance, sizeof d->radiance);
    for (int c = 0; c < 3; ++c)
      if (!(d->radiance[c] >= 0.0f) || !isfinite(d->radiance[c]))
        st = tt_set_error(TT_ERR_INVALID_ARGUMENT, "light %u: radiance must be finite and >= 0", i);
    double lum = tt__luminance(d->radiance);
    switch (l->type) {
    case TT_LIGHT_AREA: {
      const tt_mesh *m = tt_scene_mesh(scene, l->mesh);
      const tt_material *mat = tt_scene_material(scene, m->material);
      d->mesh = l->mesh;
      d->two_sided = mat ? mat->two_sided != 0 : 0;
      if (tt__max3(d->radiance) <= 0.0f && mat) {
        memcpy(d->radiance, mat->emission, sizeof d->radiance);
        lum = tt__luminance(d->radiance);
      }
      if (tri_w_cap < m->triangle_count) {
        free(tri_w);
        tri_w_cap = m->triangle_count;
        tri_w = malloc(tri_w_cap * sizeof *tri_w);
        if (!tri_w) {
          st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "path tracer: out of memory building lights");
          break;
        }
      }
      for (uint32_t t = 0; t < m->triangle_count; ++t) {
        const float *p0, *p1, *p2;
        tt__tri_verts(m, t, &p0, &p1, &p2);
        tri_w[t] = tt__tri_area(p0, p1, p2);
      }
      d->tri_offset = tri_offset;
      d->tri_count = m->triangle_count;
      d->area = m->triangle_count
                    ? (float)tt__build_cdf(tri_w, m->triangle_count, ls->tri_cdf + tri_offset)
                    : 0.0f;
      tri_offset += m->triangle_count + 1;
      power[i] = lum * d->area * TT__PI * (d->two_sided ? 2.0 : 1.0);
      if (d->area > 0.0f) ls->mesh_light[l->mesh] = (int32_t)i;
      break;
    }
    case TT_LIGHT_ENV_CONSTANT:
    case TT_LIGHT_ENV_IMAGE:
      if (ls->env >= 0) {
        st = tt_set_error(TT_ERR_UNSUPPORTED, "light %u: only one environment light is supported",
                          i);
        break;
      }
      ls->env = (int32_t)i;
      if (l->type == TT_LIGHT_ENV_IMAGE) {
        double mean_lum = 0.0; /* solid-angle mean of the image's luminance */
        st = tt__env_image_init(ls, i, l, &mean_lum);
        lum = mean_lum;
      }
      /* pi r^2 (a disk covering the scene) times the radiance integrated over the sphere. */
      power[i] = lum * 4.0 * M_PI * M_PI * radius * radius;
      break;
    case TT_LIGHT_POINT:
    case TT_LIGHT_SPOT: {
      memcpy(d->position, l->position, sizeof d->position);
      memcpy(d->direction, l->direction, sizeof d->direction);
      if (l->type == TT_LIGHT_SPOT && tt__normalize3(d->direction) == 0.0f)
        st = tt_set_error(TT_ERR_INVALID_ARGUMENT, "light %u: spot direction is zero", i);
      d->cos_inner = l->cos_inner;
      d->cos_outer = l->cos_outer;
      if (l->type == TT_LIGHT_POINT) power[i] = 4.0 * M_PI * lum;
      else power[i] = 2.0 * M_PI * lum * (1.0 - 0.5 * ((double)d->cos_inner + d->cos_outer));
      break;
    }
    case TT_LIGHT_DISTANT:
      memcpy(d->direction, l->direction, sizeof d->direction);
      if (tt__normalize3(d->direction) == 0.0f)
        st = tt_set_error(TT_ERR_INVALID_ARGUMENT, "light %u: distant light direction is zero", i);
      power[i] = M_PI * radius * radius * lum;
      break;
    default: break;
    }
    if (!(power[i] >= 0.0) || !isfinite(power[i])) power[i] = 0.0;
  }
  free(tri_w);
  if (st == TT_OK && n > 0) {
    double total = tt__build_cdf(power, n, ls->cdf);
    for (uint32_t i = 0; i < n; ++i) ls->pmf[i] = total > 0.0 ? (float)(power[i] / total) : 0.0f;
    if (!(total > 0.0)) ls->count = 0; /* all lights are black: sample none */
  }
  free(power);
  if (st != TT_OK) tt__lights_free(ls);
  return st;
}

int tt__lights_sample(const tt__lights *ls, const float p[3], const float n[3], float u_sel,
                      float u1, float u2, tt__light_sample *out) {
  if (ls->count == 0) return 0;
  uint32_t li = tt__cdf_pick(ls->cdf, ls->count, &u_sel);
  const tt__light *l = &ls->lights[li];
  float pmf = ls->pmf[li];
  if (!(pmf > 0.0f)) return 0;
  out->delta = 0;
  switch (l->type) {
  case TT_LIGHT_AREA: {
    const tt_mesh *m = tt_scene_mesh(ls->scene, l->mesh);
    uint32_t t = tt__cdf_pick(ls->tri_cdf + l->tri_offset, l->tri_count, &u_sel);
    const float *p0, *p1, *p2;
    tt__tri_verts(m, t, &p0, &p1, &p2);
    float su = sqrtf(u1), b0 = 1.0f - su, b1 = u2 * su, b2 = 1.0f - b0 - b1;
    float pl[3], e1[3], e2[3], ng[3], d[3];
    for (int i = 0; i < 3; ++i) {
      pl[i] = b0 * p0[i] + b1 * p1[i] + b2 * p2[i];
      e1[i] = p1[i] - p0[i];
      e2[i] = p2[i] - p0[i];
      d[i] = pl[i] - p[i];
    }
    tt__cross3(e1, e2, ng);
    if (tt__normalize3(ng) == 0.0f) return 0;
    float dist2 = tt__dot3(d, d);
    float dist = sqrtf(dist2);
    if (!(dist > 0.0f)) return 0;
    for (int i = 0; i < 3; ++i) out->wi[i] = d[i] / dist;
    float cos_l = -tt__dot3(ng, out->wi);
    if (!l->two_sided && !(cos_l > 0.0f)) return 0;
    if (!(fabsf(cos_l) > 1e-7f)) return 0;
    out->dist = dist;
    out->pdf = pmf / l->area * dist2 / fabsf(cos_l);
    memcpy(out->L, l->radiance, sizeof out->L);
    return isfinite(out->pdf);
  }
  case TT_LIGHT_ENV_CONSTANT: {
    float local[3];
    tt__cosine_hemisphere(u1, u2, local);
    if (!(local[2] > 0.0f)) return 0;
    tt__frame fr;
    tt__frame_from(&fr, n, n);
    tt__to_world(&fr, local, out->wi);
    tt__normalize3(out->wi);
    out->dist = INFINITY;
    out->pdf = pmf * local[2] * TT__INV_PI;
    memcpy(out->L, l->radiance, sizeof out->L);
    return out->pdf > 0.0f;
  }
  case TT_LIGHT_ENV_IMAGE: {
    if (!(ls->env_pdf_scale > 0.0f)) return 0;
    float st;
    if (!tt__env_image_dir(ls, u1, u2, out->wi, &st)) return 0;
    /* The pdf of the texel the direction rounds to (as tt__lights_pdf_env computes it). */
    float st2;
    size_t i = tt__env_texel(ls, out->wi, &st2);
    out->dist = INFINITY;
    out->pdf = pmf * ls->env_weight[i] * ls->env_pdf_scale / (2.0f * TT__PI * TT__PI * st);
    memcpy(out->L, ls->env_rgb + 3 * i, sizeof out->L);
    return out->pdf > 0.0f && isfinite(out->pdf);
  }
  case TT_LIGHT_POINT:
  case TT_LIGHT_SPOT: {
    float d[3] = {l->position[0] - p[0], l->position[1] - p[1], l->position[2] - p[2]};
    float dist2 = tt__dot3(d, d), dist = sqrtf(dist2);
    if (!(dist > 0.0f)) return 0;
    for (int i = 0; i < 3; ++i) out->wi[i] = d[i] / dist;
    float scale = 1.0f / dist2;
    if (l->type == TT_LIGHT_SPOT) scale *= tt__spot_falloff(l, -tt__dot3(out->wi, l->direction));
    if (!(scale > 0.0f)) return 0;
    for (int i = 0; i < 3; ++i) out->L[i] = l->radiance[i] * scale;
    out->dist = dist;
    out->pdf = pmf;
    out->delta = 1;
    return 1;
  }
  case TT_LIGHT_DISTANT:
    for (int i = 0; i < 3; ++i) out->wi[i] = -l->direction[i];
    memcpy(out->L, l->radiance, sizeof out->L);
    out->dist = INFINITY;
    out->pdf = pmf;
    out->delta = 1;
    return 1;
  default: return 0;
  }
}

int tt__lights_emitted(const tt__lights *ls, uint32_t mesh, const float ng[3], const float w[3],
                       float L[3]) {
  int32_t li = ls->mesh_light ? ls->mesh_light[mesh] : -1;
  if (li < 0) return 0;
  const tt__light *l = &ls->lights[li];
  if (!l->two_sided && !(tt__dot3(ng, w) > 0.0f)) return 0;
  memcpy(L, l->radiance, 3 * sizeof(float));
  return tt__max3(L) > 0.0f;
}

float tt__lights_pdf_area(const tt__lights *ls, uint32_t mesh, const float p_ref[3],
                          const float p_light[3], const float ng_light[3]) {
  if (ls->count == 0) return 0.0f;
  int32_t li = ls->mesh_light[mesh];
  if (li < 0) return 0.0f;
  const tt__light *l = &ls->lights[li];
  float d[3] = {p_light[0] - p_ref[0], p_light[1] - p_ref[1], p_light[2] - p_ref[2]};
  float dist2 = tt__dot3(d, d);
  float len_n = sqrtf(tt__dot3(ng_light, ng_light));
  float cos_l = fabsf(tt__dot3(ng_light, d)) / (len_n * sqrtf(dist2));
  if (!(cos_l > 1e-7f) || !(l->area > 0.0f)) return 0.0f;
  return ls->pmf[li] / l->area * dist2 / cos_l;
}

int tt__lights_env(const tt__lights *ls, const float dir[3], float L[3]) {
  if (ls->env < 0) return 0;
  if (ls->env_rgb) {
    float st;
    memcpy(L, ls->env_rgb + 3 * tt__env_texel(ls, dir, &st), 3 * sizeof(float));
  } else {
    memcpy(L, ls->lights[ls->env].radiance, 3 * sizeof(float));
  }
  return tt__max3(L) > 0.0f;
}

float tt__lights_pdf_env(const tt__lights *ls, const float n[3], const float dir[3]) {
  if (ls->env < 0 || ls->count == 0) return 0.0f;
  if (ls->env_rgb) {
    float st;
    size_t i = tt__env_texel(ls, dir, &st);
    if (!(st > 0.0f)) return 0.0f;
    float pdf =
        ls->pmf[ls->env] * ls->env_weight[i] * ls->env_pdf_scale / (2.0f * TT__PI * TT__PI * st);
    return isfinite(pdf) ? pdf : 0.0f;
  }
  float c = tt__dot3(n, dir);
  return c > 0.0f ? ls->pmf[ls->env] * c * TT__INV_PI : 0.0f;
}
