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

#include <tunetrace/scene.h>

typedef struct tt__light {
  tt_light_type type;
  uint32_t mesh;             /* AREA */
  float radiance[3];         /* AREA/ENV radiance, POINT/SPOT intensity, DISTANT irradiance */
  int two_sided;             /* AREA */
  float area;                /* AREA: total area (computed from the triangles) */
  uint32_t tri_offset;       /* AREA: first entry of its triangle CDF in tri_cdf */
  uint32_t tri_count;
  float position[3];         /* POINT/SPOT */
  float direction[3];        /* SPOT/DISTANT: unit direction the light travels */
  float cos_inner, cos_outer;
} tt__light;

typedef struct tt__lights {
  const tt_scene *scene;
  uint32_t count;
  tt__light *lights;
  float *pmf;                /* selection probability per light */
  float *cdf;                /* count + 1 entries */
  float *tri_cdf;            /* per area light: tri_count + 1 entries, normalised */
  int32_t *mesh_light;       /* per mesh: index into lights, or -1 */
  int32_t env;               /* index of the environment light, or -1 */
  /* ENV_IMAGE: texel radiance (scale applied, nearest lookup, so the sampling density is
   * proportional to the luminance it integrates) and its sampling distribution. */
  uint32_t env_w, env_h;
  float *env_rgb;            /* 3 * env_w * env_h, row 0 = +y */
  float *env_marginal;       /* env_h + 1: CDF over rows */
  float *env_conditional;    /* env_h * (env_w + 1): CDF over columns, per row */
  float *env_weight;         /* env_w * env_h sampling weights */
  float env_pdf_scale;       /* pdf in (u, v) of a texel = weight * env_pdf_scale */
} tt__lights;

typedef struct tt__light_sample {
  float wi[3];               /* unit direction from the receiver towards the light */
  float dist;                /* distance to the sampled point (INFINITY for env/distant) */
  float L[3];                /* radiance (or irradiance-like for delta lights) arriving */
  float pdf;                 /* solid-angle pdf including selection; delta lights: pmf */
  int delta;                 /* a point/spot/distant light: not reachable by BSDF sampling */
} tt__light_sample;

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

#endif /* TT_LIGHTS_INTERNAL_H */
