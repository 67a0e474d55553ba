/* tunetrace internal: BSDFs of the scene.h materials, evaluated in a local shading frame
 * (z = shading normal). Used by path.c and white-box tests. All functions are pure and
 * allocation-free (per-sample hot path). Directions point away from the surface: wo towards
 * the viewer (previous vertex), wi towards the light (next vertex). f values carry no
 * cosine. Radiance transport: refraction scales f by 1/eta'^2 (pbrt's TransportMode::Radiance). */
#ifndef TT_BSDF_INTERNAL_H
#define TT_BSDF_INTERNAL_H

#include <math.h>

#include <tunetrace/scene.h>

/* ---- small vector helpers shared by bsdf/lights/path ---- */

static inline float tt__dot3(const float a[3], const float b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void tt__cross3(const float a[3], const float b[3], float out[3]) {
  float x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2], z = a[0] * b[1] - a[1] * b[0];
  out[0] = x;
  out[1] = y;
  out[2] = z;
}
/* Normalises in place; returns the old length (0 leaves v unchanged). */
static inline float tt__normalize3(float v[3]) {
  float l = sqrtf(tt__dot3(v, v));
  if (l > 0.0f) {
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
  }
  return l;
}
static inline float tt__luminance(const float c[3]) {
  return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}
static inline float tt__max3(const float c[3]) {
  float m = c[0] > c[1] ? c[0] : c[1];
  return m > c[2] ? m : c[2];
}

/* Orthonormal frame: s, t tangents, n normal. */
typedef struct tt__frame {
  float s[3], t[3], n[3];
} tt__frame;

/* Frame around unit n with s the projection of `tangent` (any vector; a fallback is chosen
 * when it is parallel to n), so anisotropic lobes are oriented consistently on a triangle. */
static inline void tt__frame_from(tt__frame *fr, const float n[3], const float tangent[3]) {
  fr->n[0] = n[0];
  fr->n[1] = n[1];
  fr->n[2] = n[2];
  float d = tt__dot3(tangent, n);
  float s[3] = {tangent[0] - d * n[0], tangent[1] - d * n[1], tangent[2] - d * n[2]};
  if (tt__normalize3(s) < 1e-6f || !(fabsf(tt__dot3(s, n)) < 1e-3f)) {
    /* Duff et al. 2017 branchless basis. */
    float sign = copysignf(1.0f, n[2]);
    float a = -1.0f / (sign + n[2]), b = n[0] * n[1] * a;
    s[0] = 1.0f + sign * n[0] * n[0] * a;
    s[1] = sign * b;
    s[2] = -sign * n[0];
  }
  fr->s[0] = s[0];
  fr->s[1] = s[1];
  fr->s[2] = s[2];
  tt__cross3(n, s, fr->t);
}
static inline void tt__to_local(const tt__frame *fr, const float v[3], float out[3]) {
  float x = tt__dot3(v, fr->s), y = tt__dot3(v, fr->t), z = tt__dot3(v, fr->n);
  out[0] = x;
  out[1] = y;
  out[2] = z;
}
static inline void tt__to_world(const tt__frame *fr, const float v[3], float out[3]) {
  for (int i = 0; i < 3; ++i) out[i] = v[0] * fr->s[i] + v[1] * fr->t[i] + v[2] * fr->n[i];
}

/* ---- BSDFs ---- */

/* Per-material data prepared once (tt__bsdf_init). */
typedef struct tt__bsdf {
  tt_material_type type;
  float albedo[3];        /* diffuse reflectance (DIFFUSE, PLASTIC) */
  float specular[3];      /* specular tint */
  float eta[3], k[3];     /* CONDUCTOR */
  float ior;              /* DIELECTRIC, PLASTIC */
  float alpha_x, alpha_y; /* GGX */
  float on_a, on_b;       /* Oren-Nayar A, B; on_b == 0: Lambert */
  int delta;              /* every lobe is a delta (mirror, smooth glass/metal) */
} tt__bsdf;

typedef struct tt__bsdf_result {
  float wi[3];
  float f[3]; /* BSDF value (for delta lobes: weight * pdf / |cos|) */
  float pdf;  /* solid angle; for delta lobes the discrete lobe probability */
  int delta;
} tt__bsdf_result;

/* Prepares `b` from `m`; TT_ERR_UNSUPPORTED (with a message naming the material) for a
 * material the path sampler cannot render correctly, instead of rendering it black. */
tt_status tt__bsdf_init(tt__bsdf *b, const tt_material *m);

/* Non-zero if directions can pass to the other side (dielectric): such BSDFs are not
 * mirrored to the viewer's side. */
static inline int tt__bsdf_transmissive(const tt__bsdf *b) {
  return b->type == TT_MATERIAL_DIELECTRIC;
}

/* f(wo, wi) for local unit directions; 0 for delta lobes. */
void tt__bsdf_eval(const tt__bsdf *b, const float wo[3], const float wi[3], float f[3]);

/* Solid-angle pdf of sampling wi given wo; 0 for delta lobes. */
float tt__bsdf_pdf(const tt__bsdf *b, const float wo[3], const float wi[3]);

/* Samples wi with lobe choice u_lobe and direction (u1, u2); returns 0 if no direction
 * was produced (the path ends). */
int tt__bsdf_sample(const tt__bsdf *b, const float wo[3], float u_lobe, float u1, float u2,
                    tt__bsdf_result *s);

/* tt__bsdf_sample for importance transport (light subpaths of the bidirectional methods):
 * the same directions and pdfs, with f the adjoint f*(wo, wi) = f(wi, wo), i.e. refraction
 * without the radiance's 1/eta'^2 (pbrt's TransportMode::Importance). */
int tt__bsdf_sample_adjoint(const tt__bsdf *b, const float wo[3], float u_lobe, float u1, float u2,
                            tt__bsdf_result *s);

/* Reflectance for the albedo AOV. */
void tt__bsdf_albedo(const tt__bsdf *b, float out[3]);

/* Unpolarised Fresnel reflectance of a dielectric interface (cos_i signed: negative means
 * from inside, eta = n_inside / n_outside). */
float tt__fresnel_dielectric(float cos_i, float eta);

#endif /* TT_BSDF_INTERNAL_H */
