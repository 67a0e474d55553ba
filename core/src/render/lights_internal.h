/* tunetrace internal: light sampling for the path sampler. Lights are chosen in proportion
 * to their power; on an area light a triangle is chosen in proportion to its area (its
 * radiance is uniform, so this is area * luminance), then a uniform point on it. Constant
 * environments are sampled with a cosine lobe around the receiver's normal; image
 * environments (lat-long, Mitsuba's y-up convention: u = (1 + atan2(d.x, -d.z) / pi) / 2,
 * v = acos(d.y) / pi, row 0 at the top) by a 2D piecewise-constant distribution over their
 * texels weighted by luminance * sin(theta). Built once per tt_path_tracer; queries are
 * pure and allocation-free. */
#ifndef TT_LIGHTS_INTERNAL_H
#define TT_LIGHTS_INTERNAL_H

#include <math.h>
#include <stddef.h>

#include <tunetrace/scene.h>

typedef struct tt__light {
  tt_light_type type;
  uint32_t mesh;       /* AREA */
  float radiance[3];   /* AREA/ENV radiance, POINT/SPOT intensity, DISTANT irradiance */
  int two_sided;       /* AREA */
  float area;          /* AREA: total area (computed from the triangles) */
  uint32_t tri_offset; /* AREA: first entry of its triangle CDF in tri_cdf */
  uint32_t tri_count;
  float position[3];  /* POINT/SPOT */
  float direction[3]; /* SPOT/DISTANT: unit direction the light travels */
  float cos_inner, cos_outer;
} tt__light;

typedef struct tt__lights {
  const tt_scene *scene;
  uint32_t count;
  tt__light *lights;
  float *pmf;          /* selection probability per light */
  float *cdf;          /* count + 1 entries */
  float *tri_cdf;      /* per area light: tri_count + 1 entries, normalised */
  int32_t *mesh_light; /* per mesh: index into lights, or -1 */
  int32_t env;         /* index of the environment light, or -1 */
  /* ENV_IMAGE: texel radiance (scale applied, nearest lookup, so the sampling density is
   * proportional to the luminance it integrates) and its sampling distribution. */
  uint32_t env_w, env_h;
  float *env_rgb;         /* 3 * env_w * env_h, row 0 = +y */
  float *env_marginal;    /* env_h + 1: CDF over rows */
  float *env_conditional; /* env_h * (env_w + 1): CDF over columns, per row */
  float *env_weight;      /* env_w * env_h sampling weights */
  float env_pdf_scale;    /* pdf in (u, v) of a texel = weight * env_pdf_scale */
  /* Bounding sphere of the geometry: environment and distant lights emit from a disk of
   * this radius facing the scene (light tracing). */
  float center[3], radius;
} tt__lights;

typedef struct tt__light_sample {
  float wi[3]; /* unit direction from the receiver towards the light */
  float dist;  /* distance to the sampled point (INFINITY for env/distant) */
  float L[3];  /* radiance (or irradiance-like for delta lights) arriving */
  float pdf;   /* solid-angle pdf including selection; delta lights: pmf */
  int delta;   /* a point/spot/distant light: not reachable by BSDF sampling */
} tt__light_sample;

/* ---- shared helpers (lights.c, light_emission.c) ---- */

/* Index i with cdf[i] <= u < cdf[i+1], skipping zero-width entries; u is remapped to [0, 1)
 * within the chosen entry so it can drive a second choice. */
static inline uint32_t tt__cdf_pick(const float *cdf, uint32_t n, float *u) {
  uint32_t lo = 0, hi = n; /* invariant: cdf[lo] <= u < cdf[hi] */
  while (hi - lo > 1) {
    uint32_t mid = (lo + hi) / 2;
    if (cdf[mid] <= *u) lo = mid;
    else hi = mid;
  }
  float width = cdf[lo + 1] - cdf[lo];
  float r = width > 0.0f ? (*u - cdf[lo]) / width : 0.0f;
  *u = r < 1.0f ? (r > 0.0f ? r : 0.0f) : 0x1.fffffep-1f;
  return lo;
}

/* Triangle vertices of triangle `tri` of mesh m. */
static inline void tt__tri_verts(const tt_mesh *m, uint32_t tri, const float **p0, const float **p1,
                                 const float **p2) {
  const uint32_t *idx = m->indices + 3 * (size_t)tri;
  *p0 = m->positions + 3 * (size_t)idx[0];
  *p1 = m->positions + 3 * (size_t)idx[1];
  *p2 = m->positions + 3 * (size_t)idx[2];
}

/* Texel of the image environment seen in direction dir (leaving the scene); sets sin(theta). */
static inline size_t tt__env_texel(const tt__lights *ls, const float dir[3], float *sin_theta) {
  float y = fminf(1.0f, fmaxf(-1.0f, dir[1]));
  float u = 0.5f * (1.0f + atan2f(dir[0], -dir[2]) * 0.31830988618379067f),
        v = acosf(y) * 0.31830988618379067f;
  uint32_t xi = (uint32_t)fminf(fmaxf(u, 0.0f) * (float)ls->env_w, (float)(ls->env_w - 1));
  uint32_t yi = (uint32_t)fminf(fmaxf(v, 0.0f) * (float)ls->env_h, (float)(ls->env_h - 1));
  *sin_theta = sqrtf(fmaxf(0.0f, 1.0f - y * y));
  return (size_t)yi * ls->env_w + xi;
}

/* Smoothstep falloff of a spot light between its outer and inner cones. */
static inline float tt__spot_falloff(const tt__light *l, float cos_theta) {
  if (cos_theta >= l->cos_inner) return 1.0f;
  if (cos_theta <= l->cos_outer) return 0.0f;
  float t = (cos_theta - l->cos_outer) / (l->cos_inner - l->cos_outer);
  return t * t * (3.0f - 2.0f * t);
}

/* Direction towards the image environment for (u1, u2) drawn from its 2D distribution
 * (rows, then columns within the row); 0 at the poles. Sets sin(theta). */
static inline int tt__env_image_dir(const tt__lights *ls, float u1, float u2, float wi[3],
                                    float *sin_theta) {
  const float pi = 3.14159265358979324f;
  float uu = u1, vv = u2;
  uint32_t row = tt__cdf_pick(ls->env_marginal, ls->env_h, &vv);
  uint32_t col = tt__cdf_pick(ls->env_conditional + (size_t)row * (ls->env_w + 1), ls->env_w, &uu);
  float u = ((float)col + uu) / (float)ls->env_w, v = ((float)row + vv) / (float)ls->env_h;
  float theta = v * pi, phi = pi * (2.0f * u - 1.0f), st = sinf(theta);
  *sin_theta = st;
  if (!(st > 0.0f)) return 0;
  wi[0] = st * sinf(phi);
  wi[1] = cosf(theta);
  wi[2] = -st * cosf(phi);
  return 1;
}

/* Builds light data for `scene` (reads an image environment's file: TT_ERR_IO naming it if
 * it cannot be decoded). */
tt_status tt__lights_init(tt__lights *ls, const tt_scene *scene);
void tt__lights_free(tt__lights *ls);

/* Samples a light for receiver p with normal n (used by the environment's cosine lobe).
 * Returns 0 if nothing was sampled (no lights, back of a one-sided emitter, ...). */
int tt__lights_sample(const tt__lights *ls, const float p[3], const float n[3], float u_sel,
                      float u1, float u2, tt__light_sample *out);

/* Radiance leaving mesh `mesh` (an area light) from a surface with winding normal ng
 * towards direction w (away from the surface); 0 if the mesh emits nothing that way. */
int tt__lights_emitted(const tt__lights *ls, uint32_t mesh, const float ng[3], const float w[3],
                       float L[3]);

/* Solid-angle pdf that tt__lights_sample from p_ref produces p_light on mesh `mesh`
 * (winding normal ng_light), including the selection probability. */
float tt__lights_pdf_area(const tt__lights *ls, uint32_t mesh, const float p_ref[3],
                          const float p_light[3], const float ng_light[3]);

/* Environment radiance towards -dir (dir leaves the scene); 0 if there is none. */
int tt__lights_env(const tt__lights *ls, const float dir[3], float L[3]);

/* pdf that tt__lights_sample from a receiver with normal n produces direction dir towards
 * the environment, including the selection probability. */
float tt__lights_pdf_env(const tt__lights *ls, const float n[3], const float dir[3]);

/* ---- emission and direct connection for bidirectional methods (light_emission.c) ----
 * Lights as pbrt-v3 defines them for light tracing: an area light emits Le (cosine-weighted
 * directions; both sides when two-sided); a point light intensity I uniformly over the
 * sphere, a spot light I times its falloff over its outer cone; a distant light's
 * irradiance E and an environment's radiance arrive as parallel rays from a disk of the
 * scene's bounding radius R facing the scene (position density 1 / (pi R^2)). An image
 * environment's directions follow its texel distribution, a constant one is uniform over the
 * sphere (PT's cosine lobe around a receiver's normal has no meaning for light tracing and
 * misses transmission, so the bidirectional methods use the sphere for both strategies). */

/* Delta in position (point, spot), delta in direction (distant), or at infinity
 * (environment, distant). */
static inline int tt__light_delta_pos(const tt__light *l) {
  return l->type == TT_LIGHT_POINT || l->type == TT_LIGHT_SPOT;
}
static inline int tt__light_delta_dir(const tt__light *l) { return l->type == TT_LIGHT_DISTANT; }
static inline int tt__light_infinite(const tt__light *l) {
  return l->type == TT_LIGHT_ENV_CONSTANT || l->type == TT_LIGHT_ENV_IMAGE ||
         l->type == TT_LIGHT_DISTANT;
}

/* A sampled emitted ray (the start of a light subpath). */
typedef struct tt__emission {
  float p[3];    /* origin: on the light, or on the disk for environment / distant */
  float n[3];    /* area: unit winding normal of the triangle; others: dir */
  float dir[3];  /* unit direction the light travels */
  float Le[3];   /* radiance (area, environment), intensity (point, spot), irradiance (distant) */
  float pdf_pos; /* area density of p (1 for point/spot: a delta) */
  float pdf_dir; /* solid-angle density of dir (1 for distant: a delta) */
  float pmf;     /* probability of choosing the light */
  uint32_t light;
} tt__emission;

/* Chooses a light by power (u_sel), a point on it (u1, u2) and a direction (u3, u4).
 * Returns 0 when nothing is emitted (no lights, a zero pdf, black). */
int tt__lights_sample_emission(const tt__lights *ls, float u_sel, float u1, float u2, float u3,
                               float u4, tt__emission *out);

/* Densities with which tt__lights_sample_emission produces, for light `li`, a ray leaving
 * with unit direction `dir` from a point whose winding normal is `n` (area lights only):
 * area density of the origin (1 / area; 1 for point/spot; 1 / (pi R^2) at infinity) and
 * solid-angle density of the direction (0 outside the emitting side or the spot's cone). */
void tt__lights_pdf_emission(const tt__lights *ls, uint32_t li, const float n[3],
                             const float dir[3], float *pdf_pos, float *pdf_dir);

/* Solid-angle density with which an infinite light's emission sampling produces rays
 * travelling along `dir`, times the light's selection probability (pbrt-v3
 * InfiniteLightDensity); 0 for a distant light (a delta direction) or none. */
float tt__lights_pdf_infinite(const tt__lights *ls, const float dir[3]);

/* A point on a light sampled from a receiver (BDPT's s = 1 strategy). */
typedef struct tt__light_point {
  float p[3];  /* the point (at infinity: receiver + 2R wi) */
  float n[3];  /* area: unit winding normal; others: -wi */
  float wi[3]; /* unit direction from the receiver towards it */
  float dist;  /* INFINITY at infinity */
  float Li[3]; /* radiance arriving (area, environment), I / d^2 (point, spot), E */
  float pdf;   /* solid-angle density at the receiver, without the selection (1: delta) */
  float pmf;
  uint32_t light;
} tt__light_point;

/* Chooses a light by power and a point on it as seen from `ref`, with the same densities as
 * tt__lights_sample_emission's origins (area: uniform over the area; environment: its
 * direction distribution). Returns 0 if nothing arrives (back of a one-sided light, ...). */
int tt__lights_sample_point(const tt__lights *ls, const float ref[3], float u_sel, float u1,
                            float u2, tt__light_point *out);

#endif /* TT_LIGHTS_INTERNAL_H */
