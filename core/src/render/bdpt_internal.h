/* tunetrace internal: the vertices of the bidirectional path sampler (bdpt.c) and its
 * multiple-importance weights, visible to white-box tests (core/tests/bdpt_mis.c). */
#ifndef TT_BDPT_INTERNAL_H
#define TT_BDPT_INTERNAL_H

#include <tunetrace/bdpt.h>

#include "render/path_internal.h"

typedef enum tt__bv_kind { TT__BV_CAMERA = 0, TT__BV_LIGHT = 1, TT__BV_SURFACE = 2 } tt__bv_kind;

/* A subpath vertex. Densities are area densities (solid angle towards a vertex at infinity):
 * pdf_fwd that of sampling it from the previous vertex of its own subpath, pdf_rev that of
 * sampling it from the next one (the other direction of transport). */
typedef struct tt__bvertex {
  uint8_t kind;       /* tt__bv_kind */
  uint8_t delta;      /* surface: scattered by a delta lobe */
  uint8_t infinite;   /* light at infinity (environment, distant): `wo` is the
                                direction its light travels */
  uint8_t on_surface; /* surface vertices and points on area lights */
  int32_t light;      /* light index (light vertices; surfaces of an area light), or -1 */
  uint32_t mesh;      /* surface: its mesh */
  float p[3];
  float ng[3];   /* unit winding normal (surface, area light); camera: forward */
  float ns[3];   /* shading normal, on ng's side */
  float wo[3];   /* surface: unit direction to the previous vertex of its subpath */
  float beta[3]; /* throughput of the subpath up to here */
  float pdf_fwd, pdf_rev;
  tt__frame frame; /* surface: shading frame */
  tt__bsdf bsdf;   /* surface: BSDF (textured) */
} tt__bvertex;

struct tt_bdpt_paths {
  uint32_t cap; /* vertices per subpath */
  uint32_t n_camera, n_light;
  uint32_t rays;
  tt__bvertex *camera, *light;
  /* the camera subpath's first hit (AOVs) */
  int32_t hit;
  float hit_distance, hit_normal[3], hit_albedo[3];
  float hit_prev[3]; /* the first hit's previous-frame position (object motion) */
};

/* Density of sampling `next` from `v`, which was reached from `prev` (NULL at a camera or
 * a light), as an area density at next (pbrt-v3 Vertex::Pdf). */
float tt__bv_pdf(const tt_path_tracer *pt, const tt_camera_frame *frame, const tt__bvertex *v,
                 const tt__bvertex *prev, const tt__bvertex *next);
/* Density of light emission from v (a light, or a surface on an area light) reaching next
 * (PdfLight), and of choosing v as the light subpath's origin (PdfLightOrigin). */
float tt__bv_pdf_light(const tt_path_tracer *pt, const tt__bvertex *v, const tt__bvertex *next);
float tt__bv_pdf_light_origin(const tt_path_tracer *pt, const tt__bvertex *v,
                              const tt__bvertex *next);

/* MIS weight of strategy (s, t) over light[0..s) and camera[0..t); `sampled` replaces
 * light[0] when s == 1 and camera[0] when t == 1 (the vertex the connection sampled). */
float tt__bdpt_mis_weight(const tt_path_tracer *pt, const tt_camera_frame *frame,
                          tt_mis_heuristic heuristic, const tt__bvertex *light,
                          const tt__bvertex *camera, const tt__bvertex *sampled, uint32_t s,
                          uint32_t t);

#endif /* TT_BDPT_INTERNAL_H */
