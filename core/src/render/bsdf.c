/* tunetrace: BSDFs of the scene materials (bsdf_internal.h).
 *   diffuse    Lambert, or Oren-Nayar (qualitative model, sigma = roughness) when > 0
 *   mirror     ideal reflector tinted by `specular` (delta)
 *   dielectric smooth glass, Fresnel reflect/refract chosen by the lobe dimension (delta);
 *              rough glass (alpha > 0): GGX reflection + transmission through the generalised
 *              half vector (Walter et al. 2007), visible-normal sampling, lobe by Fresnel
 *   conductor  anisotropic GGX (Walter 2007) with visible-normal sampling (Heitz 2018),
 *              complex Fresnel (eta, k), height-correlated Smith G2; delta below alpha 1e-3
 *   plastic    Lambert base under a GGX dielectric coat; the lobe is chosen with a
 *              Fresnel-weighted probability and f/pdf cover both lobes
 * Opaque BSDFs are two-sided: a viewer below the shading normal sees them mirrored. */
#include "render/bsdf_internal.h"
#include "render/warp_internal.h"

#include <complex.h>

#define TT__INV_PI 0.31830988618379067f
#define TT__PI 3.14159265358979324f
#define TT__MIN_ALPHA 1e-3f

/* ---- helpers ---- */

float tt__fresnel_dielectric(float cos_i, float eta) {
  if (cos_i > 1.0f) cos_i = 1.0f;
  if (cos_i < -1.0f) cos_i = -1.0f;
  if (cos_i < 0.0f) {
    eta = 1.0f / eta;
    cos_i = -cos_i;
  }
  float sin2_i = 1.0f - cos_i * cos_i;
  float sin2_t = sin2_i / (eta * eta);
  if (sin2_t >= 1.0f) return 1.0f;
  float cos_t = sqrtf(1.0f - sin2_t);
  float r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return 0.5f * (r_parl * r_parl + r_perp * r_perp);
}

/* Fresnel reflectance of a conductor with complex IOR eta + i k (pbrt-v4 FrComplex). */
static float tt__fresnel_conductor(float cos_i, float eta_re, float k) {
  if (cos_i < 0.0f) cos_i = 0.0f;
  if (cos_i > 1.0f) cos_i = 1.0f;
  double complex eta = (double)eta_re + (double)k * I;
  double c = cos_i, sin2 = 1.0 - c * c;
  double complex sin2_t = sin2 / (eta * eta);
  double complex cos_t = csqrt(1.0 - sin2_t);
  double complex r_parl = (eta * c - cos_t) / (eta * c + cos_t);
  double complex r_perp = (c - eta * cos_t) / (c + eta * cos_t);
  double f = 0.5 * (creal(r_parl * conj(r_parl)) + creal(r_perp * conj(r_perp)));
  return (float)f;
}

/* ---- GGX (anisotropic, Walter 2007 / Heitz 2014, 2018) ---- */

/* Normal distribution D(wm). */
static float tt__ggx_d(float ax, float ay, const float wm[3]) {
  float cos2 = wm[2] * wm[2];
  if (!(cos2 > 0.0f)) return 0.0f;
  float e = (wm[0] * wm[0] / (ax * ax) + wm[1] * wm[1] / (ay * ay)) / cos2;
  float c4 = cos2 * cos2;
  return 1.0f / (TT__PI * ax * ay * c4 * (1.0f + e) * (1.0f + e));
}

/* Smith Lambda(w) for the anisotropic GGX. */
static float tt__ggx_lambda(float ax, float ay, const float w[3]) {
  float cos2 = w[2] * w[2];
  if (!(cos2 > 0.0f)) return INFINITY;
  float a2t2 = (ax * ax * w[0] * w[0] + ay * ay * w[1] * w[1]) / cos2;
  return 0.5f * (sqrtf(1.0f + a2t2) - 1.0f);
}

static float tt__ggx_g1(float ax, float ay, const float w[3]) {
  return 1.0f / (1.0f + tt__ggx_lambda(ax, ay, w));
}

/* Height-correlated masking-shadowing G2. */
static float tt__ggx_g2(float ax, float ay, const float wo[3], const float wi[3]) {
  return 1.0f / (1.0f + tt__ggx_lambda(ax, ay, wo) + tt__ggx_lambda(ax, ay, wi));
}

/* Samples a visible normal for wo (wo[2] > 0), Heitz 2018. */
static void tt__ggx_sample_vndf(float ax, float ay, const float wo[3], float u1, float u2,
                                float wm[3]) {
  float vh[3] = {ax * wo[0], ay * wo[1], wo[2]};
  tt__normalize3(vh);
  float lensq = vh[0] * vh[0] + vh[1] * vh[1];
  float t1v[3] = {1.0f, 0.0f, 0.0f};
  if (lensq > 0.0f) {
    float inv = 1.0f / sqrtf(lensq);
    t1v[0] = -vh[1] * inv;
    t1v[1] = vh[0] * inv;
    t1v[2] = 0.0f;
  }
  float t2v[3];
  tt__cross3(vh, t1v, t2v);
  float r = sqrtf(u1), phi = 2.0f * TT__PI * u2;
  float t1 = r * cosf(phi), t2 = r * sinf(phi);
  float s = 0.5f * (1.0f + vh[2]);
  t2 = (1.0f - s) * sqrtf(fmaxf(0.0f, 1.0f - t1 * t1)) + s * t2;
  float tz = sqrtf(fmaxf(0.0f, 1.0f - t1 * t1 - t2 * t2));
  float nh[3];
  for (int i = 0; i < 3; ++i) nh[i] = t1 * t1v[i] + t2 * t2v[i] + tz * vh[i];
  wm[0] = ax * nh[0];
  wm[1] = ay * nh[1];
  wm[2] = fmaxf(1e-7f, nh[2]);
  tt__normalize3(wm);
}

/* pdf of reflecting wo into wi through VNDF sampling (wo[2], wi[2] > 0). */
static float tt__ggx_reflect_pdf(float ax, float ay, const float wo[3], const float wi[3]) {
  float wm[3] = {wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]};
  if (tt__normalize3(wm) == 0.0f) return 0.0f;
  return tt__ggx_g1(ax, ay, wo) * tt__ggx_d(ax, ay, wm) / (4.0f * wo[2]);
}

/* ---- init ---- */

/* Non-negative finite colour check for material validation. */
static int tt__colour_ok(const float c[3]) {
  for (int i = 0; i < 3; ++i)
    if (!(c[i] >= 0.0f) || !isfinite(c[i])) return 0;
  return 1;
}

tt_status tt__bsdf_init(tt__bsdf *b, const tt_material *m) {
  const char *name = m->name ? m->name : "(unnamed)";
  *b = (tt__bsdf){0};
  b->type = m->type;
  for (int i = 0; i < 3; ++i) {
    b->albedo[i] = m->albedo[i];
    b->specular[i] = m->specular[i];
    b->eta[i] = m->eta[i];
    b->k[i] = m->k[i];
  }
  if (!tt__colour_ok(m->albedo) || !tt__colour_ok(m->specular))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "material '%s': albedo and specular must be finite and >= 0", name);
  b->ior = m->ior;
  b->alpha_x = fmaxf(m->alpha[0], TT__MIN_ALPHA);
  b->alpha_y = fmaxf(m->alpha[1], TT__MIN_ALPHA);
  switch (m->type) {
  case TT_MATERIAL_DIFFUSE:
    if (m->roughness > 0.0f) {
      float s2 = m->roughness * m->roughness;
      b->on_a = 1.0f - s2 / (2.0f * (s2 + 0.33f));
      b->on_b = 0.45f * s2 / (s2 + 0.09f);
    } else {
      b->on_a = 1.0f;
      b->on_b = 0.0f;
    }
    return TT_OK;
  case TT_MATERIAL_MIRROR: b->delta = 1; return TT_OK;
  case TT_MATERIAL_DIELECTRIC:
    if (!(m->ior > 0.0f) || !isfinite(m->ior))
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, "material '%s': dielectric ior %g must be > 0",
                          name, (double)m->ior);
    /* Rough glass below alpha 1e-3 is treated as smooth (the GGX lobe is numerically a delta). */
    b->delta = m->alpha[0] < TT__MIN_ALPHA && m->alpha[1] < TT__MIN_ALPHA;
    return TT_OK;
  case TT_MATERIAL_CONDUCTOR:
    for (int i = 0; i < 3; ++i)
      if (!(m->eta[i] > 0.0f) || !(m->k[i] >= 0.0f))
        return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                            "material '%s': conductor needs eta > 0 and k >= 0 per channel", name);
    b->delta = m->alpha[0] < TT__MIN_ALPHA && m->alpha[1] < TT__MIN_ALPHA;
    return TT_OK;
  case TT_MATERIAL_PLASTIC:
    if (!(m->ior > 0.0f) || !isfinite(m->ior))
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, "material '%s': plastic ior %g must be > 0",
                          name, (double)m->ior);
    return TT_OK;
  }
  return tt_set_error(TT_ERR_UNSUPPORTED,
                      "material '%s': type %d is not supported by the path sampler", name,
                      (int)m->type);
}

/* ---- per-material lobes ---- */

/* Lambert / Oren-Nayar value (both directions in the upper hemisphere). */
static void tt__diffuse_eval(const tt__bsdf *b, const float wo[3], const float wi[3], float f[3]) {
  float scale = b->on_a;
  if (b->on_b > 0.0f) {
    float sin_i = sqrtf(fmaxf(0.0f, 1.0f - wi[2] * wi[2]));
    float sin_o = sqrtf(fmaxf(0.0f, 1.0f - wo[2] * wo[2]));
    float max_cos = 0.0f;
    if (sin_i > 1e-4f && sin_o > 1e-4f) {
      float dcos = (wi[0] * wo[0] + wi[1] * wo[1]) / (sin_i * sin_o);
      max_cos = fmaxf(0.0f, dcos);
    }
    float sin_alpha, tan_beta;
    if (wi[2] > wo[2]) {
      sin_alpha = sin_o;
      tan_beta = sin_i / wi[2];
    } else {
      sin_alpha = sin_i;
      tan_beta = sin_o / wo[2];
    }
    scale += b->on_b * max_cos * sin_alpha * tan_beta;
  }
  for (int i = 0; i < 3; ++i) f[i] = b->albedo[i] * TT__INV_PI * scale;
}

/* Rough conductor value. */
static void tt__conductor_eval(const tt__bsdf *b, const float wo[3], const float wi[3],
                               float f[3]) {
  float wm[3] = {wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]};
  if (tt__normalize3(wm) == 0.0f) {
    f[0] = f[1] = f[2] = 0.0f;
    return;
  }
  float dg = tt__ggx_d(b->alpha_x, b->alpha_y, wm) * tt__ggx_g2(b->alpha_x, b->alpha_y, wo, wi) /
             (4.0f * wo[2] * wi[2]);
  float c = fabsf(tt__dot3(wo, wm));
  for (int i = 0; i < 3; ++i)
    f[i] = dg * b->specular[i] * tt__fresnel_conductor(c, b->eta[i], b->k[i]);
}

/* Probability of sampling the plastic's specular coat given wo (Fresnel-weighted). */
static float tt__plastic_spec_prob(const tt__bsdf *b, const float wo[3]) {
  float fo = tt__fresnel_dielectric(wo[2], b->ior);
  float ws = fo * (b->specular[0] + b->specular[1] + b->specular[2]);
  float wd = (1.0f - fo) * (b->albedo[0] + b->albedo[1] + b->albedo[2]);
  if (!(ws > 0.0f)) return 0.0f;
  if (!(wd > 0.0f)) return 1.0f;
  float p = ws / (ws + wd);
  return fminf(fmaxf(p, 0.1f), 0.9f);
}

/* Plastic value: GGX dielectric coat plus Fresnel-attenuated Lambert base. */
static void tt__plastic_eval(const tt__bsdf *b, const float wo[3], const float wi[3], float f[3]) {
  float wm[3] = {wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]};
  float spec = 0.0f;
  if (tt__normalize3(wm) > 0.0f) {
    float fr = tt__fresnel_dielectric(tt__dot3(wo, wm), b->ior);
    spec = tt__ggx_d(b->alpha_x, b->alpha_y, wm) * tt__ggx_g2(b->alpha_x, b->alpha_y, wo, wi) * fr /
           (4.0f * wo[2] * wi[2]);
  }
  float diff = (1.0f - tt__fresnel_dielectric(wo[2], b->ior)) *
               (1.0f - tt__fresnel_dielectric(wi[2], b->ior)) * TT__INV_PI;
  for (int i = 0; i < 3; ++i) f[i] = spec * b->specular[i] + diff * b->albedo[i];
}

/* ---- rough dielectric (Walter et al. 2007; pbrt-v4 DielectricBxDF) ---- */

/* Generalised half vector of (wo, wi) facing +z, and etap (IOR on wi's side over wo's side,
 * 1 for reflection). Returns 1 for reflection, 2 for transmission, 0 when no microfacet
 * can connect the pair (grazing, or a back-facing microfacet). */
static int tt__rough_glass_half(const tt__bsdf *b, const float wo[3], const float wi[3],
                                float wm[3], float *etap) {
  float co = wo[2], ci = wi[2];
  if (co == 0.0f || ci == 0.0f) return 0;
  int reflect = (co > 0.0f) == (ci > 0.0f);
  *etap = reflect ? 1.0f : (co > 0.0f ? b->ior : 1.0f / b->ior);
  for (int i = 0; i < 3; ++i) wm[i] = wi[i] * *etap + wo[i];
  if (tt__normalize3(wm) == 0.0f) return 0;
  if (wm[2] < 0.0f) {
    wm[0] = -wm[0];
    wm[1] = -wm[1];
    wm[2] = -wm[2];
  }
  if (tt__dot3(wm, wi) * ci < 0.0f || tt__dot3(wm, wo) * co < 0.0f) return 0;
  return reflect ? 1 : 2;
}

/* Rough glass value; transmission carries the 1/etap^2 radiance scaling, so it obeys
 * f(wo, wi) / eta_o^2 = f(wi, wo) / eta_i^2 instead of plain symmetry. */
static void tt__rough_glass_eval(const tt__bsdf *b, const float wo[3], const float wi[3],
                                 float f[3]) {
  f[0] = f[1] = f[2] = 0.0f;
  float wm[3], etap;
  int kind = tt__rough_glass_half(b, wo, wi, wm, &etap);
  if (!kind) return;
  float dwo = tt__dot3(wo, wm), dwi = tt__dot3(wi, wm);
  float F = tt__fresnel_dielectric(dwo, b->ior);
  float dg = tt__ggx_d(b->alpha_x, b->alpha_y, wm) * tt__ggx_g2(b->alpha_x, b->alpha_y, wo, wi);
  float v;
  if (kind == 1) {
    v = dg * F / fabsf(4.0f * wo[2] * wi[2]);
  } else {
    float denom = dwi + dwo / etap;
    denom *= denom;
    v = dg * (1.0f - F) * fabsf(dwi * dwo / (wi[2] * wo[2] * denom)) / (etap * etap);
  }
  if (!isfinite(v)) return;
  for (int i = 0; i < 3; ++i) f[i] = v * b->specular[i];
}

/* Solid-angle pdf of tt__rough_glass_sample: visible normal of +-wo, then reflect with
 * probability F or refract; the Jacobians dwm/dwi of Walter 2007 (eqs. 14 and 17). */
static float tt__rough_glass_pdf(const tt__bsdf *b, const float wo[3], const float wi[3]) {
  float wm[3], etap;
  int kind = tt__rough_glass_half(b, wo, wi, wm, &etap);
  if (!kind) return 0.0f;
  float dwo = tt__dot3(wo, wm), dwi = tt__dot3(wi, wm);
  float F = tt__fresnel_dielectric(dwo, b->ior);
  float pvn = tt__ggx_g1(b->alpha_x, b->alpha_y, wo) * tt__ggx_d(b->alpha_x, b->alpha_y, wm) *
              fabsf(dwo) / fabsf(wo[2]);
  float pdf;
  if (kind == 1) {
    pdf = pvn / (4.0f * fabsf(dwo)) * F;
  } else {
    float denom = dwi + dwo / etap;
    pdf = pvn * fabsf(dwi) / (denom * denom) * (1.0f - F);
  }
  return isfinite(pdf) ? pdf : 0.0f;
}

/* Samples rough glass: a visible microfacet normal for wo (mirrored into the upper
 * hemisphere when wo is inside), then reflection (probability F) or refraction. */
static int tt__rough_glass_sample(const tt__bsdf *b, const float wo[3], float u_lobe, float u1,
                                  float u2, tt__bsdf_result *s) {
  if (wo[2] == 0.0f) return 0;
  float sg = wo[2] > 0.0f ? 1.0f : -1.0f;
  float ws[3] = {sg * wo[0], sg * wo[1], sg * wo[2]}, wm[3], wi[3];
  tt__ggx_sample_vndf(b->alpha_x, b->alpha_y, ws, u1, u2, wm);
  float dwo = tt__dot3(wo, wm);
  float F = tt__fresnel_dielectric(dwo, b->ior);
  if (u_lobe < F) {
    for (int i = 0; i < 3; ++i) wi[i] = -wo[i] + 2.0f * dwo * wm[i];
    if (!(wi[2] * wo[2] > 0.0f)) return 0;
  } else {
    float eta = b->ior, c = dwo, n[3] = {wm[0], wm[1], wm[2]};
    if (c < 0.0f) {
      eta = 1.0f / eta;
      c = -c;
      n[0] = -n[0];
      n[1] = -n[1];
      n[2] = -n[2];
    }
    float sin2_t = (1.0f - c * c) / (eta * eta);
    if (sin2_t >= 1.0f) return 0;
    float cos_t = sqrtf(1.0f - sin2_t);
    for (int i = 0; i < 3; ++i) wi[i] = -wo[i] / eta + (c / eta - cos_t) * n[i];
    tt__normalize3(wi);
    if (!(wi[2] * wo[2] < 0.0f)) return 0;
  }
  /* f and pdf from the closed forms, so sample/eval/pdf agree exactly. */
  tt__rough_glass_eval(b, wo, wi, s->f);
  s->pdf = tt__rough_glass_pdf(b, wo, wi);
  s->wi[0] = wi[0];
  s->wi[1] = wi[1];
  s->wi[2] = wi[2];
  return s->pdf > 0.0f && isfinite(s->pdf);
}

/* ---- public ---- */

void tt__bsdf_eval(const tt__bsdf *b, const float wo_in[3], const float wi_in[3], float f[3]) {
  f[0] = f[1] = f[2] = 0.0f;
  if (b->delta) return;
  if (b->type == TT_MATERIAL_DIELECTRIC) { /* both hemispheres: no two-sided mirroring */
    tt__rough_glass_eval(b, wo_in, wi_in, f);
    return;
  }
  float wo[3] = {wo_in[0], wo_in[1], wo_in[2]}, wi[3] = {wi_in[0], wi_in[1], wi_in[2]};
  if (wo[2] < 0.0f) {
    wo[2] = -wo[2];
    wi[2] = -wi[2];
  } /* two-sided */
  if (!(wo[2] > 0.0f) || !(wi[2] > 0.0f)) return;
  switch (b->type) {
  case TT_MATERIAL_DIFFUSE: tt__diffuse_eval(b, wo, wi, f); break;
  case TT_MATERIAL_CONDUCTOR: tt__conductor_eval(b, wo, wi, f); break;
  case TT_MATERIAL_PLASTIC: tt__plastic_eval(b, wo, wi, f); break;
  default: break;
  }
}

float tt__bsdf_pdf(const tt__bsdf *b, const float wo_in[3], const float wi_in[3]) {
  if (b->delta) return 0.0f;
  if (b->type == TT_MATERIAL_DIELECTRIC) return tt__rough_glass_pdf(b, wo_in, wi_in);
  float wo[3] = {wo_in[0], wo_in[1], wo_in[2]}, wi[3] = {wi_in[0], wi_in[1], wi_in[2]};
  if (wo[2] < 0.0f) {
    wo[2] = -wo[2];
    wi[2] = -wi[2];
  }
  if (!(wo[2] > 0.0f) || !(wi[2] > 0.0f)) return 0.0f;
  switch (b->type) {
  case TT_MATERIAL_DIFFUSE: return wi[2] * TT__INV_PI;
  case TT_MATERIAL_CONDUCTOR: return tt__ggx_reflect_pdf(b->alpha_x, b->alpha_y, wo, wi);
  case TT_MATERIAL_PLASTIC: {
    float ps = tt__plastic_spec_prob(b, wo);
    return ps * tt__ggx_reflect_pdf(b->alpha_x, b->alpha_y, wo, wi) +
           (1.0f - ps) * wi[2] * TT__INV_PI;
  }
  default: return 0.0f;
  }
}

/* Smooth dielectric: Fresnel reflection or refraction chosen by u_lobe. */
static int tt__dielectric_sample(const tt__bsdf *b, const float wo[3], float u_lobe,
                                 tt__bsdf_result *s) {
  float cos_o = wo[2];
  float r = tt__fresnel_dielectric(cos_o, b->ior), t = 1.0f - r;
  s->delta = 1;
  if (u_lobe < r || !(t > 0.0f)) {
    s->wi[0] = -wo[0];
    s->wi[1] = -wo[1];
    s->wi[2] = wo[2];
    float inv_cos = 1.0f / fabsf(wo[2]);
    for (int i = 0; i < 3; ++i) s->f[i] = b->specular[i] * r * inv_cos;
    s->pdf = r;
    return s->pdf > 0.0f && isfinite(inv_cos);
  }
  /* etap: relative IOR seen from wo's side; refract about the normal facing wo. */
  float etap = cos_o > 0.0f ? b->ior : 1.0f / b->ior;
  float nf = cos_o > 0.0f ? 1.0f : -1.0f;
  float cos_i = fabsf(cos_o);
  float sin2_t = (1.0f - cos_i * cos_i) / (etap * etap);
  if (sin2_t >= 1.0f) return 0;
  float cos_t = sqrtf(1.0f - sin2_t);
  for (int i = 0; i < 2; ++i) s->wi[i] = -wo[i] / etap;
  s->wi[2] = -wo[2] / etap + (cos_i / etap - cos_t) * nf;
  tt__normalize3(s->wi);
  float inv_cos = 1.0f / fabsf(s->wi[2]);
  for (int i = 0; i < 3; ++i) s->f[i] = b->specular[i] * t * inv_cos / (etap * etap);
  s->pdf = t;
  return isfinite(inv_cos);
}

int tt__bsdf_sample(const tt__bsdf *b, const float wo_in[3], float u_lobe, float u1, float u2,
                    tt__bsdf_result *s) {
  s->delta = 0;
  s->pdf = 0.0f;
  s->f[0] = s->f[1] = s->f[2] = 0.0f;
  if (b->type == TT_MATERIAL_DIELECTRIC)
    return b->delta ? tt__dielectric_sample(b, wo_in, u_lobe, s)
                    : tt__rough_glass_sample(b, wo_in, u_lobe, u1, u2, s);
  float wo[3] = {wo_in[0], wo_in[1], wo_in[2]};
  float flip = 1.0f;
  if (wo[2] < 0.0f) {
    wo[2] = -wo[2];
    flip = -1.0f;
  }
  if (!(wo[2] > 0.0f)) return 0;
  float wi[3];
  switch (b->type) {
  case TT_MATERIAL_DIFFUSE:
    tt__cosine_hemisphere(u1, u2, wi);
    if (!(wi[2] > 0.0f)) return 0;
    tt__diffuse_eval(b, wo, wi, s->f);
    s->pdf = wi[2] * TT__INV_PI;
    break;
  case TT_MATERIAL_MIRROR:
  case TT_MATERIAL_CONDUCTOR:
    if (b->delta) {
      wi[0] = -wo[0];
      wi[1] = -wo[1];
      wi[2] = wo[2];
      for (int i = 0; i < 3; ++i) {
        float fr =
            b->type == TT_MATERIAL_MIRROR ? 1.0f : tt__fresnel_conductor(wo[2], b->eta[i], b->k[i]);
        s->f[i] = b->specular[i] * fr / wo[2];
      }
      s->pdf = 1.0f;
      s->delta = 1;
      break;
    } else {
      float wm[3];
      tt__ggx_sample_vndf(b->alpha_x, b->alpha_y, wo, u1, u2, wm);
      float d = tt__dot3(wo, wm);
      for (int i = 0; i < 3; ++i) wi[i] = -wo[i] + 2.0f * d * wm[i];
      if (!(wi[2] > 0.0f)) return 0;
      tt__conductor_eval(b, wo, wi, s->f);
      s->pdf = tt__ggx_reflect_pdf(b->alpha_x, b->alpha_y, wo, wi);
      break;
    }
  case TT_MATERIAL_PLASTIC: {
    float ps = tt__plastic_spec_prob(b, wo);
    if (u_lobe < ps) {
      float wm[3];
      tt__ggx_sample_vndf(b->alpha_x, b->alpha_y, wo, u1, u2, wm);
      float d = tt__dot3(wo, wm);
      for (int i = 0; i < 3; ++i) wi[i] = -wo[i] + 2.0f * d * wm[i];
    } else {
      tt__cosine_hemisphere(u1, u2, wi);
    }
    if (!(wi[2] > 0.0f)) return 0;
    tt__plastic_eval(b, wo, wi, s->f);
    s->pdf =
        ps * tt__ggx_reflect_pdf(b->alpha_x, b->alpha_y, wo, wi) + (1.0f - ps) * wi[2] * TT__INV_PI;
    break;
  }
  default: return 0;
  }
  s->wi[0] = wi[0];
  s->wi[1] = wi[1];
  s->wi[2] = wi[2] * flip;
  return s->pdf > 0.0f && isfinite(s->pdf);
}

int tt__bsdf_sample_adjoint(const tt__bsdf *b, const float wo[3], float u_lobe, float u1, float u2,
                            tt__bsdf_result *s) {
  if (!tt__bsdf_sample(b, wo, u_lobe, u1, u2, s)) return 0;
  /* Only refraction is not symmetric: f(wi, wo) = f(wo, wi) eta'^2, eta' = eta on wi's side
   * over eta on wo's side (the relation tt__rough_glass_eval documents; the smooth lobe
   * divides by the same eta'^2). */
  if (b->type == TT_MATERIAL_DIELECTRIC && wo[2] * s->wi[2] < 0.0f) {
    float etap = wo[2] > 0.0f ? b->ior : 1.0f / b->ior, e2 = etap * etap;
    for (int i = 0; i < 3; ++i) s->f[i] *= e2;
  }
  return 1;
}

void tt__bsdf_albedo(const tt__bsdf *b, float out[3]) {
  for (int i = 0; i < 3; ++i) {
    switch (b->type) {
    case TT_MATERIAL_DIFFUSE:
    case TT_MATERIAL_PLASTIC: out[i] = b->albedo[i]; break;
    case TT_MATERIAL_CONDUCTOR:
      out[i] = b->specular[i] * tt__fresnel_conductor(1.0f, b->eta[i], b->k[i]);
      break;
    default: out[i] = b->specular[i]; break;
    }
  }
}
