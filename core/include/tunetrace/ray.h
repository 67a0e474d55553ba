/* tunetrace: rays and hits exchanged between integrators and acceleration structures.
 * Layouts are fixed for ABI major 1 (they travel in arrays through stream calls). */
#ifndef TUNETRACE_RAY_H
#define TUNETRACE_RAY_H

#include <tunetrace/common.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_INVALID_ID 0xFFFFFFFFu

/* A ray segment org + t*dir for t in [tnear, tfar]. dir need not be normalised. */
typedef struct tt_ray {
  float org[3];
  float tnear;
  float dir[3];
  float tfar; /* intersect: shortened to the hit distance on a hit */
} tt_ray;

/* Closest hit. geom_id is the mesh index in the scene, prim_id the triangle in that mesh;
 * both TT_INVALID_ID on a miss. (u, v) are barycentrics: p = (1-u-v)*v0 + u*v1 + v*v2.
 * ng is the unnormalised geometric normal cross(v1-v0, v2-v0). */
typedef struct tt_hit {
  float t;
  float u, v;
  uint32_t geom_id;
  uint32_t prim_id;
  float ng[3];
} tt_hit;

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_RAY_H */
