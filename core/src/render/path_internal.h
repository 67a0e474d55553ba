/* tunetrace internal: the path tracer object shared by the path sampler (path.c) and the
 * bidirectional path sampler (bdpt.c): materials prepared as BSDFs, albedo textures, light
 * sampling data, and the surface a hit lands on. */
#ifndef TT_PATH_INTERNAL_H
#define TT_PATH_INTERNAL_H

#include <tunetrace/path.h>

#include "render/bsdf_internal.h"
#include "render/lights_internal.h"

/* OpenImageIO TextureSystem lookups (texture_oiio.cpp), used instead of direct loading
 * when TT_TEXTURES=oiio (measured slower on the textured Cornell box: README, "Textures"). */
typedef struct tt__oiio_tex tt__oiio_tex;
tt_status tt__oiio_tex_open(const char *path, int srgb, tt__oiio_tex **out);
void tt__oiio_tex_close(tt__oiio_tex *t);
void tt__oiio_tex_lookup(const tt__oiio_tex *t, float u, float v, float out[3]);

/* An albedo texture: linear RGB in memory, or an OIIO texture handle. */
typedef struct tt__texture_data {
  uint32_t width, height;
  float *rgb;         /* 3 * width * height, row 0 at the top of the image */
  tt__oiio_tex *oiio; /* non-NULL: looked up through the TextureSystem instead */
} tt__texture_data;

struct tt_path_tracer {
  const tt_scene *scene;
  tt__lights lights;
  uint32_t material_count;
  tt__bsdf *bsdfs;
  int32_t *material_texture; /* per material: texture index or -1 */
  uint32_t texture_count;
  tt__texture_data *textures;
};

/* The surface of a hit: position, first edge (the shading frame's tangent), unit winding
 * normal, shading normal (interpolated, turned to the winding normal's side; the winding
 * normal without vertex normals) and the BSDF (the material's, or `textured` when an
 * albedo texture modulates it: copy *bsdf, not the pointer, when the struct is copied). */
typedef struct tt__surface {
  const tt_mesh *mesh;
  float p[3], e1[3], ng_w[3], ns[3];
  const tt__bsdf *bsdf;
  tt__bsdf textured;
} tt__surface;

/* Fills `s` for a hit (geom_id valid); 0 for a degenerate triangle (no normal). */
int tt__surface_at(const tt_path_tracer *pt, const tt_hit *hit, tt__surface *s);
/* Where the surface point `p` of `hit` on `mesh` was at the previous frame: p moved by the
 * displacement of the triangle's vertices since then (tt_mesh.prev_positions at the hit's
 * barycentrics), so a still mesh gives p exactly. */
void tt__surface_prev_position(const tt_mesh *mesh, const tt_hit *hit, const float p[3],
                               float out[3]);

#endif /* TT_PATH_INTERNAL_H */
