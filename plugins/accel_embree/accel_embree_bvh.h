/* accel_embree: memory layout of the custom backend's BVH, shared by the builder
 * (accel_embree_custom.c) and the traversal kernels (accel_embree_trav.c, compiled once per
 * instruction set). Not installed.
 *
 * Inner nodes hold N = 2, 4 or 8 children with their boxes stored SoA (one row of N floats
 * per box plane), so one SIMD operation tests one plane of all children. Lanes without a
 * child hold an empty box (lower = +inf, upper = -inf) that no ray can hit, so the kernels
 * never need to know how many children a node really has. Leaves are runs of triangle
 * packets of 4 triangles each, with the data the intersection test needs precomputed. */
#ifndef TT_ACCEL_EMBREE_BVH_H
#define TT_ACCEL_EMBREE_BVH_H

#include <tunetrace/ray.h>

#include <stdatomic.h>
#include <stdint.h>

/* Child references (32 bits):
 *   inner node: bit 31 clear, bits 0..30 = node index;
 *   leaf:       bit 31 set, bits 27..30 = packet count - 1 (1..16 packets, 4..64 triangles),
 *               bits 0..26 = index of the first packet.
 * TT__REF_NONE marks "no tree" (a scene whose triangles are all invalid). */
#define TT__REF_LEAF 0x80000000u
#define TT__REF_NONE 0xFFFFFFFFu
#define TT__LEAF_SHIFT 27
#define TT__LEAF_MAX_PACKETS 16u
#define TT__LEAF_MAX_FIRST ((1u << TT__LEAF_SHIFT) - 1u)
#define TT__NODE_MAX_INDEX 0x7FFFFFFEu

/* Box rows of a node: lower x, upper x, lower y, upper y, lower z, upper z (so that the
 * near plane of axis k is row 2k + (dir[k] < 0) and the far plane the other one). */
typedef struct tt__node2 {
  float b[6][2];
  uint32_t child[2];
  uint32_t pad[2];
} tt__node2; /* 64 bytes */
typedef struct tt__node4 {
  float b[6][4];
  uint32_t child[4];
  uint32_t pad[4];
} tt__node4; /* 128 bytes */
typedef struct tt__node8 {
  float b[6][8];
  uint32_t child[8];
  uint32_t pad[8];
} tt__node8; /* 256 bytes */

/* Four triangles, SoA. Rows 0-2: v0; rows 3-5 / 6-8: e1 = v0 - v1 and e2 = v2 - v0 (fast
 * Moller-Trumbore test), or v1 and v2 themselves when the tree is robust (the watertight
 * test must see the original vertices: reconstructing them from edges would round and open
 * cracks); rows 9-11: Ng = cross(v1 - v0, v2 - v0). Unused lanes have all-zero geometry
 * (determinant 0: never hit) and prim = TT_INVALID_ID. */
typedef struct tt__tri4 {
  float p[12][4];
  uint32_t geom[4];
  uint32_t prim[4];
} tt__tri4; /* 224 bytes */

/* A built tree. */
typedef struct tt__bvh {
  int width;             /* 2, 4 or 8 */
  int robust;            /* packets hold vertices; watertight test, conservative boxes */
  uint32_t root;         /* a child reference, or TT__REF_NONE */
  void *nodes;           /* tt__node{2,4,8}[node_count], 64-byte aligned */
  tt__tri4 *packets;     /* packet_count packets, 64-byte aligned */
  uint64_t node_count;
  uint64_t packet_count;
  /* Traversal counters, updated (relaxed, once per ray) only by the counting kernels. */
  _Atomic uint64_t c_rays, c_nodes, c_tris;
} tt__bvh;

/* Single-ray query kernels for one tree shape. */
typedef void (*tt__isect_fn)(const tt__bvh *bvh, tt_ray *ray, tt_hit *hit);
typedef int (*tt__occl_fn)(const tt__bvh *bvh, const tt_ray *ray);

typedef struct tt__kernels {
  tt__isect_fn intersect;
  tt__occl_fn occluded;
} tt__kernels;

/* Kernel tables, indexed [width index (2,4,8 -> 0,1,2)][robust][counters]. One per
 * instruction set; each lives in its own translation unit compiled with its -m flags. */
typedef tt__kernels tt__kernel_table[3][2][2];
const tt__kernel_table *tt__trav_table_sse41(void);
const tt__kernel_table *tt__trav_table_avx2(void);

#endif /* TT_ACCEL_EMBREE_BVH_H */
