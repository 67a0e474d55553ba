/* tunetrace: emission sampling and direct light points for the bidirectional methods
 * (lights_internal.h): where a light subpath starts, the densities of that start, and the
 * light point of BDPT's s = 1 strategy, whose position densities are the emission's (so
 * that multiple importance sampling compares like with like, as pbrt-v3 does). */
#include <float.h>
#include <math.h>
#include <string.h>

#include "render/bsdf_internal.h"
#include "render/lights_internal.h"
#include "render/warp_internal.h"

#define TT__PI 3.14159265358979324f
#define TT__INV_PI 0.31830988618379067f
#define TT__INV_4PI 0.0795774715459476679f

/* Uniform direction on the unit sphere. */
static void tt__uniform_sphere(float u1, float u2, float out[3]) {
  float z = 1.0f - 2.0f * u1, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 2.0f * TT__PI * u2;
  out[0] = r * cosf(phi);
  out[1] = r * sinf(phi);
  out[2] = z;
}

/* Cosine-weighted direction around the unit normal n. */
static void tt__cosine_around(const float n[3], float u1, float u2, float out[3]) {
  float local[3];
  tt__cosine_hemisphere(u1, u2, local);
  tt__frame fr;
  tt__frame_from(&fr, n, n);
  tt__to_world(&fr, local, out);
  tt__normalize3(out);
}

/* Solid-angle density of the environment's direction sampling for wi (towards it). */
static float tt__env_dir_pdf(const tt__lights *ls, const float wi[3]) {
  if (!ls->env_rgb) return TT__INV_4PI;
  float st;
  size_t i = tt__env_texel(ls, wi, &st);
  if (!(st > 0.0f)) return 0.0f;
  float pdf = ls->env_weight[i] * ls->env_pdf_scale / (2.0f * TT__PI * TT__PI * st);
  return isfinite(pdf) ? pdf : 0.0f;
}

/* A direction towards the environment from (u1, u2) and its density; 0 if none. */
static int tt__env_sample_dir(const tt__lights *ls, float u1, float u2, float wi[3], float *pdf) {
  if (ls->env_rgb) {
    float st;
    if (!(ls->env_pdf_scale > 0.0f) || !tt__env_image_dir(ls, u1, u2, wi, &st)) return 0;
  } else {
    tt__uniform_sphere(u1, u2, wi);
  }
  *pdf = tt__env_dir_pdf(ls, wi);
  return *pdf > 0.0f;
}

/* Uniform point on the light's triangles (chosen by area with u_sel): position and unit
 * winding normal; 0 for a degenerate triangle. */
static int tt__area_point(const tt__lights *ls, const tt__light *l, float u_sel, float u1, float u2,
                          float p[3], float n[3]) {
  const tt_mesh *m = tt_scene_mesh(ls->scene, l->mesh);
  uint32_t t = tt__cdf_pick(ls->tri_cdf + l->tri_offset, l->tri_count, &u_sel);
  const float *p0, *p1, *p2;
  tt__tri_verts(m, t, &p0, &p1, &p2);
  float su = sqrtf(u1), b0 = 1.0f - su, b1 = u2 * su, b2 = 1.0f - b0 - b1, e1[3], e2[3];
  for (int i = 0; i < 3; ++i) {
    p[i] = b0 * p0[i] + b1 * p1[i] + b2 * p2[i];
    e1[i] = p1[i] - p0[i];
    e2[i] = p2[i] - p0[i];
  }
  tt__cross3(e1, e2, n);
  return tt__normalize3(n) > 0.0f;
}

/* A point of the disk of radius R centred on the scene, facing along `dir`, set back by R. */
static void tt__disk_point(const tt__lights *ls, const float dir[3], float u1, float u2,
                           float p[3]) {
  tt__frame fr;
  tt__frame_from(&fr, dir, dir);
  float x, y;
  tt__concentric_disk(u1, u2, &x, &y);
  for (int i = 0; i < 3; ++i)
    p[i] = ls->center[i] + ls->radius * (x * fr.s[i] + y * fr.t[i] - dir[i]);
}

/* Chooses a light by power with *u_sel (remapped for the next choice): the light, its index
 * and probability; NULL when there is none or it cannot be chosen. */
static const tt__light *tt__pick_light(const tt__lights *ls, float *u_sel, uint32_t *li,
                                       float *pmf) {
  if (ls->count == 0) return NULL;
  *li = tt__cdf_pick(ls->cdf, ls->count, u_sel);
  *pmf = ls->pmf[*li];
  return *pmf > 0.0f ? &ls->lights[*li] : NULL;
}

int tt__lights_sample_emission(const tt__lights *ls, float u_sel, float u1, float u2, float u3,
                               float u4, tt__emission *out) {
  const tt__light *l = tt__pick_light(ls, &u_sel, &out->light, &out->pmf);
  if (!l) return 0;
  switch (l->type) {
  case TT_LIGHT_AREA: {
    if (!(l->area > 0.0f) || !tt__area_point(ls, l, u_sel, u1, u2, out->p, out->n)) return 0;
    float side = 1.0f;
    if (l->two_sided) { /* either side with probability 1/2 */
      if (u3 < 0.5f) u3 = 2.0f * u3;
      else {
        u3 = fminf(2.0f * u3 - 1.0f, 0x1.fffffep-1f);
        side = -1.0f;
      }
    }
    float ns[3] = {side * out->n[0], side * out->n[1], side * out->n[2]};
    tt__cosine_around(ns, u3, u4, out->dir);
    float c = tt__dot3(ns, out->dir);
    if (!(c > 0.0f)) return 0;
    out->pdf_pos = 1.0f / l->area;
    out->pdf_dir = c * TT__INV_PI * (l->two_sided ? 0.5f : 1.0f);
    memcpy(out->Le, l->radiance, sizeof out->Le);
    break;
  }
  case TT_LIGHT_POINT:
  case TT_LIGHT_SPOT: {
    memcpy(out->p, l->position, sizeof out->p);
    out->pdf_pos = 1.0f;
    float scale = 1.0f;
    if (l->type == TT_LIGHT_POINT) {
      tt__uniform_sphere(u3, u4, out->dir);
      out->pdf_dir = TT__INV_4PI;
    } else { /* uniform within the outer cone */
      float span = 1.0f - l->cos_outer;
      if (!(span > 0.0f)) return 0;
      float c = 1.0f - u3 * span, s = sqrtf(fmaxf(0.0f, 1.0f - c * c)), phi = 2.0f * TT__PI * u4;
      float local[3] = {s * cosf(phi), s * sinf(phi), c};
      tt__frame fr;
      tt__frame_from(&fr, l->direction, l->direction);
      tt__to_world(&fr, local, out->dir);
      tt__normalize3(out->dir);
      out->pdf_dir = 1.0f / (2.0f * TT__PI * span);
      scale = tt__spot_falloff(l, c);
    }
    memcpy(out->n, out->dir, sizeof out->n);
    for (int i = 0; i < 3; ++i) out->Le[i] = l->radiance[i] * scale;
    break;
  }
  case TT_LIGHT_DISTANT:
    memcpy(out->dir, l->direction, sizeof out->dir);
    memcpy(out->n, out->dir, sizeof out->n);
    tt__disk_point(ls, out->dir, u1, u2, out->p);
    out->pdf_pos = 1.0f / (TT__PI * ls->radius * ls->radius);
    out->pdf_dir = 1.0f;
    memcpy(out->Le, l->radiance, sizeof out->Le);
    break;
  case TT_LIGHT_ENV_CONSTANT:
  case TT_LIGHT_ENV_IMAGE: {
    float wi[3];
    if (!tt__env_sample_dir(ls, u3, u4, wi, &out->pdf_dir)) return 0;
    for (int i = 0; i < 3; ++i) out->dir[i] = -wi[i];
    memcpy(out->n, out->dir, sizeof out->n);
    tt__disk_point(ls, out->dir, u1, u2, out->p);
    out->pdf_pos = 1.0f / (TT__PI * ls->radius * ls->radius);
    if (!tt__lights_env(ls, wi, out->Le)) return 0;
    break;
  }
  default: return 0;
  }
  return tt__max3(out->Le) > 0.0f && out->pdf_pos > 0.0f && out->pdf_dir > 0.0f &&
         isfinite(out->pdf_pos) && isfinite(out->pdf_dir);
}

void tt__lights_pdf_emission(const tt__lights *ls, uint32_t li, const float n[3],
                             const float dir[3], float *pdf_pos, float *pdf_dir) {
  *pdf_pos = *pdf_dir = 0.0f;
  if (li >= ls->count) return;
  const tt__light *l = &ls->lights[li];
  switch (l->type) {
  case TT_LIGHT_AREA: {
    if (!(l->area > 0.0f)) return;
    float c = tt__dot3(n, dir);
    *pdf_pos = 1.0f / l->area;
    *pdf_dir = l->two_sided ? fabsf(c) * TT__INV_PI * 0.5f : (c > 0.0f ? c * TT__INV_PI : 0.0f);
    return;
  }
  case TT_LIGHT_POINT:
    *pdf_pos = 1.0f;
    *pdf_dir = TT__INV_4PI;
    return;
  case TT_LIGHT_SPOT: {
    float span = 1.0f - l->cos_outer;
    *pdf_pos = 1.0f;
    *pdf_dir = span > 0.0f && tt__dot3(dir, l->direction) >= l->cos_outer
                   ? 1.0f / (2.0f * TT__PI * span)
                   : 0.0f;
    return;
  }
  case TT_LIGHT_DISTANT: /* a delta direction: no density */
    *pdf_pos = 1.0f / (TT__PI * ls->radius * ls->radius);
    return;
  case TT_LIGHT_ENV_CONSTANT:
  case TT_LIGHT_ENV_IMAGE: {
    float wi[3] = {-dir[0], -dir[1], -dir[2]};
    *pdf_pos = 1.0f / (TT__PI * ls->radius * ls->radius);
    *pdf_dir = tt__env_dir_pdf(ls, wi);
    return;
  }
  default: return;
  }
}

float tt__lights_pdf_infinite(const tt__lights *ls, const float dir[3]) {
  if (ls->env < 0 || ls->count == 0) return 0.0f;
  float wi[3] = {-dir[0], -dir[1], -dir[2]};
  return ls->pmf[ls->env] * tt__env_dir_pdf(ls, wi);
}

int tt__lights_sample_point(const tt__lights *ls, const float ref[3], float u_sel, float u1,
                            float u2, tt__light_point *out) {
  const tt__light *l = tt__pick_light(ls, &u_sel, &out->light, &out->pmf);
  if (!l) return 0;
  switch (l->type) {
  case TT_LIGHT_AREA: {
    if (!(l->area > 0.0f) || !tt__area_point(ls, l, u_sel, u1, u2, out->p, out->n)) return 0;
    float d[3] = {out->p[0] - ref[0], out->p[1] - ref[1], out->p[2] - ref[2]};
    float dist2 = tt__dot3(d, d), dist = sqrtf(dist2);
    if (!(dist > 0.0f)) return 0;
    for (int i = 0; i < 3; ++i) out->wi[i] = d[i] / dist;
    float cos_l = -tt__dot3(out->n, out->wi);
    if (!l->two_sided && !(cos_l > 0.0f)) return 0;
    if (!(fabsf(cos_l) > 1e-7f)) return 0;
    out->dist = dist;
    out->pdf = dist2 / (fabsf(cos_l) * l->area);
    memcpy(out->Li, l->radiance, sizeof out->Li);
    break;
  }
  case TT_LIGHT_POINT:
  case TT_LIGHT_SPOT: {
    float d[3] = {l->position[0] - ref[0], l->position[1] - ref[1], l->position[2] - ref[2]};
    float dist2 = tt__dot3(d, d), dist = sqrtf(dist2);
    if (!(dist > 0.0f)) return 0;
    for (int i = 0; i < 3; ++i) out->wi[i] = d[i] / dist;
    float scale = 1.0f / dist2;
    if (l->type == TT_LIGHT_SPOT) scale *= tt__spot_falloff(l, -tt__dot3(out->wi, l->direction));
    for (int i = 0; i < 3; ++i) {
      out->Li[i] = l->radiance[i] * scale;
      out->p[i] = l->position[i];
      out->n[i] = -out->wi[i];
    }
    out->dist = dist;
    out->pdf = 1.0f;
    break;
  }
  case TT_LIGHT_DISTANT:
    for (int i = 0; i < 3; ++i) out->wi[i] = -l->direction[i];
    memcpy(out->Li, l->radiance, sizeof out->Li);
    out->dist = INFINITY;
    out->pdf = 1.0f;
    break;
  case TT_LIGHT_ENV_CONSTANT:
  case TT_LIGHT_ENV_IMAGE:
    if (!tt__env_sample_dir(ls, u1, u2, out->wi, &out->pdf)) return 0;
    if (!tt__lights_env(ls, out->wi, out->Li)) return 0;
    out->dist = INFINITY;
    break;
  default: return 0;
  }
  if (isinf(out->dist))
    for (int i = 0; i < 3; ++i) {
      out->p[i] = ref[i] + 2.0f * ls->radius * out->wi[i];
      out->n[i] = -out->wi[i];
    }
  return tt__max3(out->Li) > 0.0f && out->pdf > 0.0f && isfinite(out->pdf);
}
