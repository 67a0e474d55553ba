/* accel_embree: memory layout of the custom backend's BVH, shared by the builder
 * (accel_embree_custom.c) and the traversal kernels (accel_embree_trav.c, compiled once per
 * instruction set). Not installed.
 *
 * Inner nodes hold N = 2, 4 or 8 children with their boxes stored SoA (BVH4/8: one row of
 * N floats per box plane, so one SIMD operation tests one plane of all children; BVH2: one
 * row per axis holding both children's lower and upper planes). Lanes without a
 * child hold an empty box (lower = +inf, upper = -inf) that no ray can hit, so the kernels
 * never need to know how many children a node really has. Leaves are runs of triangle
 * packets of 4 triangles (the last one 2 when that suffices), with the data the
 * intersection test needs precomputed. */
#ifndef TT_ACCEL_EMBREE_BVH_H
#define TT_ACCEL_EMBREE_BVH_H

#include <tunetrace/ray.h>

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

/* Child references (32 bits):
 *   inner node: bit 31 clear, bits 0..30 = node index (BVH2: the node's line);
 *   leaf:       bit 31 set, bits 27..30 = triangle pairs - 1 (1..16 pairs, 2..32 triangle
 *               slots), bits 0..26 = the leaf block's first line in the arena.
 * TT__EMBREE_REF_NONE marks "no tree" (a scene whose triangles are all invalid). */
#define TT__EMBREE_REF_LEAF 0x80000000u
#define TT__EMBREE_REF_NONE 0xFFFFFFFFu
#define TT__EMBREE_LEAF_SHIFT 27
#define TT__EMBREE_LEAF_MAX_PAIRS 16u
#define TT__EMBREE_NODE_MAX_INDEX 0x7FFFFFFEu

/* Box rows of a BVH4/BVH8 node: lower x, upper x, lower y, upper y, lower z, upper z (so
 * that the near plane of axis k is row 2k + (dir[k] < 0) and the far plane the other one).
 *
 * A BVH2 node packs both children's boxes per axis into one 4-wide row (lower c0, lower
 * c1, upper c0, upper c1): the kernel tests both children on an axis with one 4-wide
 * multiply-subtract (upper lanes negated by the ray constants) and one permute chosen by
 * the direction's sign, then combines the axes with three max ops (see
 * accel_embree_trav.c, tt__embree_box2). */
typedef struct tt__embree_node2 {
  float b[3][4];
  uint32_t child[2];
  /* Prefetch hints (they change no result): for each inner child c, grand[c] = c's
   * second child reference (its first child, when inner, is node c + 1 by pre-order);
   * for a leaf child (or an inner child without a second box) child[c] itself, so the
   * kernel prefetches hints without testing them. A binary tree's traversal is a chain of
   * dependent node loads; knowing the grandchildren one level early lets the kernel fetch
   * two levels ahead, so two node misses overlap instead of following each other. */
  uint32_t grand[2];
} tt__embree_node2; /* 64 bytes */
typedef struct tt__embree_node4 {
  float b[6][4];
  uint32_t child[4];
  uint32_t pad[4];
} tt__embree_node4; /* 128 bytes */
typedef struct tt__embree_node8 {
  float b[6][8];
  uint32_t child[8];
  uint32_t pad[8];
} tt__embree_node8; /* 256 bytes */

/* Leaf triangles live in 48-byte slots (12 floats, one triangle each), grouped into SoA
 * packets: a leaf of n triangles has ceil(n/2) pairs of slots, i.e. floor(pairs/2) packets
 * of width W = 4 (192 bytes) followed, when pairs is odd, by one packet of width W = 2 (96
 * bytes). A leaf of 1-2 triangles thus takes 96 bytes, not a 4-wide packet's 192. Packet
 * rows (W floats each, row r lane l at float r * W + l; 16-byte aligned): 0-2 v0; 3-5 / 6-8
 * e1 = v0 - v1 and e2 = v2 - v0 (fast Moller-Trumbore test), or v1 and v2 themselves when
 * the tree is robust (the watertight test must see the original vertices: reconstructing
 * them from edges would round and open cracks); 9-11 Ng = cross(v1 - v0, v2 - v0). Unused
 * lanes have all-zero geometry (determinant 0: never hit). Triangle j of a leaf is slot j
 * whatever its packet; its ids follow the packets (below). */
#define TT__EMBREE_SLOT_FLOATS 12
typedef struct tt__embree_id {
  uint32_t geom, prim; /* TT_INVALID_ID for an unused slot */
} tt__embree_id;

/* Leaf blocks live in an arena of 64-byte lines: a leaf of p triangle pairs is its packets
 * (as above: floor(p/2) 4-wide, one 2-wide when p is odd; p * 96 bytes) then its 2p ids
 * (p * 16 bytes), padded to whole lines: a 1-2 triangle leaf is exactly two lines, and the
 * hit's ids come from a line the leaf test already read (a separate id array cost one more
 * cache miss per ray: 8% of the BVH8 kernel's time in a render profile). BVH2 keeps its
 * nodes in the same arena, interleaved with the leaves in pre-order (a node, then its first
 * child's subtree, then its second's), so a leaf child sits next to its parent and every
 * reference - node, leaf, or grand[] hint - is a line index. BVH4/8 nodes are in their own
 * array (node index * 32 * N bytes). */
#define TT__EMBREE_LINE2_MASK ((1u << TT__EMBREE_LEAF_SHIFT) - 1u)

/* A built tree. */
typedef struct tt__embree_bvh {
  int width;     /* 2, 4 or 8 */
  int robust;    /* packets hold vertices; watertight test, conservative boxes */
  uint32_t root; /* a child reference, or TT__EMBREE_REF_NONE */
  void *arena;   /* leaf blocks (BVH2: and nodes), 64-byte lines, 64-byte aligned */
  void *nodes;   /* BVH4/8: tt__embree_node{4,8}[node_count], 64-byte aligned; else NULL */
  uint64_t arena_lines;
  uint64_t node_count;
  uint64_t slot_count; /* triangle slots (2 per pair) */
  /* Traversal counters, updated (relaxed, once per ray) only by the counting kernels. */
  _Atomic uint64_t c_rays, c_nodes, c_tris;
} tt__embree_bvh;

/* Single-ray query kernels for one tree shape. */
typedef void (*tt__embree_isect_fn)(const tt__embree_bvh *bvh, tt_ray *ray, tt_hit *hit);
typedef int (*tt__embree_occl_fn)(const tt__embree_bvh *bvh, const tt_ray *ray);

/* Stream query kernels: per ray the same answers (see accel_embree_trav.c, packets). */
typedef void (*tt__embree_isect_stream_fn)(const tt__embree_bvh *bvh, tt_ray *rays, tt_hit *hits,
                                           size_t count);
typedef void (*tt__embree_occl_stream_fn)(const tt__embree_bvh *bvh, const tt_ray *rays,
                                          uint8_t *occluded, size_t count);

typedef struct tt__embree_kernels {
  tt__embree_isect_fn intersect;
  tt__embree_occl_fn occluded;
  tt__embree_isect_stream_fn intersect_stream;
  tt__embree_occl_stream_fn occluded_stream;
} tt__embree_kernels;

/* Kernel tables, indexed [width index (2,4,8 -> 0,1,2)][robust][counters]. One per
 * instruction set; each lives in its own translation unit compiled with its -m flags. */
typedef tt__embree_kernels tt__embree_kernel_table[3][2][2];
const tt__embree_kernel_table *tt__embree_trav_table_sse41(void);
const tt__embree_kernel_table *tt__embree_trav_table_avx2(void);
const tt__embree_kernel_table *tt__embree_trav_table_avx512(void);

#endif /* TT_ACCEL_EMBREE_BVH_H */
