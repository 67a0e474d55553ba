/* accel_embree: the custom backend's builder.
 *
 * Embree's generic builder (rtcBuildBVH) decides the tree with every numeric parameter of
 * thesis Table 3.1; its callbacks only record a temporary tree in Embree's thread-local
 * allocator. A single-threaded depth-first pass then lays that tree out our way (BVH2/4/8
 * nodes with SoA child boxes, padded with empty boxes, BVH2 nodes with grandchild prefetch
 * hints; leaves of precomputed 4-triangle packets with a 2-triangle tail packet, ids apart;
 * nodes in pre-order so a parent and its first child are close in memory), counts
 * the statistics, and the Embree BVH object is released. Traversal: accel_embree_trav.c. */
#include "accel_embree.h"
#include "accel_embree_bvh.h"

#include <embree3/rtcore.h>

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

/* Spatial-split builds keep a split budget in the top 5 bits of geomID (Embree 3.13.5,
 * RESERVED_NUM_SPATIAL_SPLITS_GEOMID_BITS); leaves must mask them off. */
#define TT__EMBREE_GEOMID_BITS 27
#define TT__EMBREE_GEOMID_MASK ((1u << TT__EMBREE_GEOMID_BITS) - 1u)

/* Deepest tree the kernels' fixed stacks accept (Embree keeps depth <= maxDepth <= 64). */
#define TT__EMBREE_MAX_TREE_DEPTH 88

/* Temporary tree, allocated by Embree's thread-local allocator (freed with the RTCBVH). */
typedef struct tt__embree_tmp_inner {
  uint32_t is_leaf; /* 0 */
  uint32_t count;
  void *child[8];
  struct RTCBounds bounds[8];
} tt__embree_tmp_inner;

typedef struct tt__embree_tmp_leaf {
  uint32_t is_leaf; /* 1 */
  uint32_t count;
  uint32_t ids[]; /* count (geomID, primID) pairs */
} tt__embree_tmp_leaf;

/* State shared by the callbacks (called from Embree's worker threads). */
typedef struct tt__embree_cb_ctx {
  const tt_scene *scene;
  uint32_t geom_mask; /* TT__EMBREE_GEOMID_MASK for spatial splits, else all ones */
  _Atomic uint64_t inner, leaves, slots;
  _Atomic int too_wide; /* a node with more than 8 children was requested */
} tt__embree_cb_ctx;

/* createNode: an inner node sized for 8 children (we never ask for more). */
static void *tt__embree_cb_node(RTCThreadLocalAllocator alloc, unsigned int count, void *user) {
  tt__embree_cb_ctx *c = user;
  tt__embree_tmp_inner *n = rtcThreadLocalAlloc(alloc, sizeof *n, 16);
  if (!n) return NULL;
  if (count > 8) {
    atomic_store(&c->too_wide, 1);
    count = 8;
  }
  n->is_leaf = 0;
  n->count = count;
  atomic_fetch_add_explicit(&c->inner, 1, memory_order_relaxed);
  return n;
}

/* setNodeChildren: keep the child pointers. */
static void tt__embree_cb_children(void *node, void **children, unsigned int count, void *user) {
  (void)user;
  tt__embree_tmp_inner *n = node;
  for (unsigned i = 0; i < count && i < 8; i++) n->child[i] = children[i];
}

/* setNodeBounds: keep the child boxes (the parent's boxes are what the SoA node stores). */
static void tt__embree_cb_bounds(void *node, const struct RTCBounds **bounds, unsigned int count,
                                 void *user) {
  (void)user;
  tt__embree_tmp_inner *n = node;
  for (unsigned i = 0; i < count && i < 8; i++) n->bounds[i] = *bounds[i];
}

/* createLeaf: the (geomID, primID) pairs; the triangles are packed later, in one pass. */
static void *tt__embree_cb_leaf(RTCThreadLocalAllocator alloc,
                                const struct RTCBuildPrimitive *prims, size_t count, void *user) {
  tt__embree_cb_ctx *c = user;
  tt__embree_tmp_leaf *l = rtcThreadLocalAlloc(alloc, sizeof *l + 8 * count, 16);
  if (!l) return NULL;
  l->is_leaf = 1;
  l->count = (uint32_t)count;
  for (size_t i = 0; i < count; i++) {
    l->ids[2 * i] = prims[i].geomID & c->geom_mask;
    l->ids[2 * i + 1] = prims[i].primID;
  }
  atomic_fetch_add_explicit(&c->leaves, 1, memory_order_relaxed);
  atomic_fetch_add_explicit(&c->slots, 2 * ((count + 1) / 2), memory_order_relaxed);
  return l;
}

/* Vertex pointers of a triangle. */
static inline void tt__embree_tri_verts(const tt_mesh *m, uint32_t prim, const float *v[3]) {
  for (int k = 0; k < 3; k++) v[k] = m->positions + 3 * (size_t)m->indices[3 * (size_t)prim + k];
}

/* splitPrimitive (quality 3): clips the triangle at the plane and intersects each side's
 * box with the primitive's current box (which may already be a fragment), as Embree's own
 * triangle splitter does. */
static void tt__embree_cb_split(const struct RTCBuildPrimitive *prim, unsigned int dim, float pos,
                                struct RTCBounds *lo, struct RTCBounds *hi, void *user) {
  tt__embree_cb_ctx *c = user;
  const tt_mesh *m = tt_scene_mesh(c->scene, prim->geomID & c->geom_mask);
  const float *v[3];
  tt__embree_tri_verts(m, prim->primID, v);
  float l[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
  float r[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
#define TT__EMBREE_EXT(b, p)                                                                       \
  for (int k = 0; k < 3; k++) {                                                                    \
    b[k] = fminf(b[k], (p)[k]);                                                                    \
    b[3 + k] = fmaxf(b[3 + k], (p)[k]);                                                            \
  }
  for (int i = 0; i < 3; i++) {
    const float *a = v[i], *b = v[(i + 1) % 3];
    float ad = a[dim], bd = b[dim];
    if (ad <= pos) TT__EMBREE_EXT(l, a);
    if (ad >= pos) TT__EMBREE_EXT(r, a);
    if ((ad < pos && pos < bd) || (bd < pos && pos < ad)) {
      float t = (pos - ad) / (bd - ad), p[3];
      for (int k = 0; k < 3; k++) p[k] = a[k] + t * (b[k] - a[k]);
      p[dim] = pos;
      TT__EMBREE_EXT(l, p);
      TT__EMBREE_EXT(r, p);
    }
  }
#undef TT__EMBREE_EXT
  const float pl[3] = {prim->lower_x, prim->lower_y, prim->lower_z};
  const float pu[3] = {prim->upper_x, prim->upper_y, prim->upper_z};
  float *lo_lo = &lo->lower_x, *lo_up = &lo->upper_x, *hi_lo = &hi->lower_x, *hi_up = &hi->upper_x;
  for (int k = 0; k < 3; k++) {
    lo_lo[k] = fmaxf(l[k], pl[k]);
    lo_up[k] = fminf(l[3 + k], pu[k]);
    hi_lo[k] = fmaxf(r[k], pl[k]);
    hi_up[k] = fminf(r[3 + k], pu[k]);
  }
  lo->align0 = lo->align1 = hi->align0 = hi->align1 = 0.0f;
}

/* ---- flattening into our layout ---- */

typedef struct tt__embree_flat {
  const tt_scene *scene;
  int N, robust;
  char *arena; /* lines: leaf blocks (BVH2: and nodes), accel_embree_bvh.h */
  uint64_t arena_lines, arena_cap;
  char *nodes; /* BVH4/8: capacity node_cap nodes of 32 * N bytes */
  uint64_t node_count, node_cap;
  uint64_t slot_count; /* triangle slots used (2 per pair) */
  uint64_t leaves;
  double area_inner, area_leaf_tris;
  uint32_t max_depth;
  const char *error; /* set on the first structural problem */
} tt__embree_flat;

/* Surface area of a box given as lower[3], upper[3]. */
static double tt__embree_area(const float *lower, const float *upper) {
  double d[3];
  for (int k = 0; k < 3; k++) d[k] = upper[k] > lower[k] ? (double)upper[k] - lower[k] : 0.0;
  return 2.0 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]);
}

/* Writes a triangle into lane `lane` of the width-W packet at `pk`: vertices or edges,
 * and Ng computed in double from the same float data the test uses, so den and T agree
 * with it. */
static void tt__embree_pack_tri(tt__embree_flat *f, float *pk, int W, int lane, tt__embree_id *id,
                                uint32_t geom, uint32_t prim) {
  const float *v[3];
  tt__embree_tri_verts(tt_scene_mesh(f->scene, geom), prim, v);
  float e1[3], e2[3];
  for (int k = 0; k < 3; k++) {
    e1[k] = v[0][k] - v[1][k];
    e2[k] = v[2][k] - v[0][k];
    pk[k * W + lane] = v[0][k];
    pk[(3 + k) * W + lane] = f->robust ? v[1][k] : e1[k];
    pk[(6 + k) * W + lane] = f->robust ? v[2][k] : e2[k];
  }
  double a[3], b[3]; /* v1 - v0 and v2 - v0 */
  for (int k = 0; k < 3; k++) {
    a[k] = f->robust ? (double)v[1][k] - v[0][k] : -(double)e1[k];
    b[k] = f->robust ? (double)v[2][k] - v[0][k] : (double)e2[k];
  }
  pk[9 * W + lane] = (float)(a[1] * b[2] - a[2] * b[1]);
  pk[10 * W + lane] = (float)(a[2] * b[0] - a[0] * b[2]);
  pk[11 * W + lane] = (float)(a[0] * b[1] - a[1] * b[0]);
  id->geom = geom;
  id->prim = prim;
}

/* Lays out the temporary subtree `tmp` (whose box is lower/upper, at `depth`, root = 1)
 * and returns its reference, or TT__EMBREE_REF_NONE for an empty leaf. */
static uint32_t tt__embree_flatten(tt__embree_flat *f, const void *tmp, uint32_t depth,
                                   const float *lower, const float *upper) {
  if (f->error) return TT__EMBREE_REF_NONE;
  if (!tmp) {
    f->error = "Embree returned a NULL child";
    return TT__EMBREE_REF_NONE;
  }
  if (depth > f->max_depth) f->max_depth = depth;
  if (depth > TT__EMBREE_MAX_TREE_DEPTH) {
    f->error = "tree deeper than the traversal stack allows";
    return TT__EMBREE_REF_NONE;
  }
  if (((const tt__embree_tmp_leaf *)tmp)->is_leaf) {
    const tt__embree_tmp_leaf *l = tmp;
    if (l->count == 0) return TT__EMBREE_REF_NONE;
    const uint32_t pairs = (l->count + 1) / 2, nslots = 2 * pairs, wide = pairs / 2;
    if (pairs > TT__EMBREE_LEAF_MAX_PAIRS) {
      f->error = "a leaf holds more than 32 triangles";
      return TT__EMBREE_REF_NONE;
    }
    /* A leaf block in the arena: packets then ids, whole lines (accel_embree_bvh.h), so the
     * hit's ids come from lines the leaf test already read. */
    const uint64_t line = f->arena_lines, lines = (112u * pairs + 63u) / 64u;
    if (line + lines > f->arena_cap || line + lines - 1 > TT__EMBREE_LINE2_MASK) {
      f->error = line + lines > f->arena_cap ? "more leaf lines than counted"
                                             : "leaf arena too large for 27-bit lines";
      return TT__EMBREE_REF_NONE;
    }
    f->arena_lines += lines;
    float *base = (float *)(f->arena + line * 64u);
    tt__embree_id *id = (tt__embree_id *)((char *)base + (size_t)pairs * 96u);
    for (uint32_t i = 0; i < nslots; i++) id[i].geom = id[i].prim = TT_INVALID_ID;
    for (uint32_t j = 0; j < l->count; j++) {
      /* Slot j: lane j % 4 of 4-wide packet j / 4, or lane j - 4 * wide of the 2-wide
       * packet that closes a leaf with an odd number of pairs. */
      int W = j < 4 * wide ? 4 : 2;
      uint32_t p0 = W == 4 ? j - j % 4 : 4 * wide; /* packet's first slot */
      tt__embree_pack_tri(f, base + (size_t)p0 * TT__EMBREE_SLOT_FLOATS, W, (int)(j - p0), &id[j],
                          l->ids[2 * j], l->ids[2 * j + 1]);
    }
    f->slot_count += nslots;
    f->leaves++;
    f->area_leaf_tris += tt__embree_area(lower, upper) * l->count;
    return TT__EMBREE_REF_LEAF | ((pairs - 1) << TT__EMBREE_LEAF_SHIFT) | (uint32_t)line;
  }
  const tt__embree_tmp_inner *n = tmp;
  if (f->node_count >= f->node_cap || f->node_count > TT__EMBREE_NODE_MAX_INDEX) {
    f->error = "more inner nodes than Embree created";
    return TT__EMBREE_REF_NONE;
  }
  const int N = f->N;
  uint64_t index = f->node_count++;
  if (N == 2) { /* BVH2: the node's line, before its children's (pre-order) */
    if (f->arena_lines >= f->arena_cap || f->arena_lines > TT__EMBREE_LINE2_MASK) {
      f->error = f->arena_lines >= f->arena_cap ? "more BVH2 lines than counted"
                                                : "BVH2 arena too large for 27-bit lines";
      return TT__EMBREE_REF_NONE;
    }
    index = f->arena_lines++;
  }
  f->area_inner += tt__embree_area(lower, upper);
  /* Children first (they may be anywhere later in the arrays), then this node's rows; the
   * node is addressed by index because nothing moves, but computing rows after the
   * recursion keeps the code obviously independent of it. */
  uint32_t refs[8];
  float box[8][6];
  /* Children in order of decreasing surface area (the builder gives them by primitive
   * count). Closest-hit traversal orders hit children by distance whatever their lanes, so
   * this only decides occlusion, which visits children in lane order and stops at the
   * first hit: the child a random ray most likely hits (large triangles high in the tree,
   * a floor, a wall) goes first. The tree itself is unchanged. */
  int order[8];
  double area[8];
  const int kids = n->count < 8 ? (int)n->count : 8;
  for (int i = 0; i < kids; i++) {
    const struct RTCBounds *b = &n->bounds[i];
    const float lo[3] = {b->lower_x, b->lower_y, b->lower_z},
                hi[3] = {b->upper_x, b->upper_y, b->upper_z};
    area[i] = tt__embree_area(lo, hi);
    int j = i;
    for (; j > 0 && area[order[j - 1]] < area[i]; j--) order[j] = order[j - 1];
    order[j] = i;
  }
  for (int i = 0; i < N; i++) {
    refs[i] = TT__EMBREE_REF_NONE;
    if (i < kids) {
      const struct RTCBounds *b = &n->bounds[order[i]];
      box[i][0] = b->lower_x, box[i][1] = b->lower_y, box[i][2] = b->lower_z;
      box[i][3] = b->upper_x, box[i][4] = b->upper_y, box[i][5] = b->upper_z;
      refs[i] = tt__embree_flatten(f, n->child[order[i]], depth + 1, box[i], box[i] + 3);
    }
  }
  float *rows = (float *)(N == 2 ? f->arena + index * 64u : f->nodes + index * (uint64_t)(32 * N));
  uint32_t *child = (uint32_t *)(rows + 6 * N);
  for (int i = 0; i < N; i++) {
    int empty = refs[i] == TT__EMBREE_REF_NONE;
    for (int k = 0; k < 3; k++) {
      /* BVH2: row k = (lower c0, lower c1, upper c0, upper c1); wider: rows 2k, 2k+1. */
      float *lo = N == 2 ? &rows[4 * k + i] : &rows[(2 * k) * N + i];
      float *up = N == 2 ? &rows[4 * k + 2 + i] : &rows[(2 * k + 1) * N + i];
      *lo = empty ? INFINITY : box[i][k];
      *up = empty ? -INFINITY : box[i][3 + k];
    }
    child[i] = empty ? 0u : refs[i];
  }
  for (int i = N; i < 2 * N; i++) child[i] = 0u; /* padding */
  if (N == 2) {
    /* Grandchild hints (tt__embree_node2.grand): the children were laid out first, so an inner
     * child's node is already written. */
    for (int i = 0; i < 2; i++) {
      uint32_t g = child[i]; /* a leaf (or empty) child: its own lines, or the root's */
      if (refs[i] != TT__EMBREE_REF_NONE && !(refs[i] & TT__EMBREE_REF_LEAF)) {
        const tt__embree_node2 *cn = (const tt__embree_node2 *)(f->arena + (uint64_t)refs[i] * 64u);
        if (cn->b[0][1] <= cn->b[0][3]) g = cn->child[1]; /* non-empty second box */
      }
      child[2 + i] = g;
    }
  }
  return (uint32_t)index;
}

/* ---- the build ---- */

/* Frees a tree (NULL is ignored). */
void tt__embree_custom_free(tt__embree_bvh *bvh) {
  if (!bvh) return;
  free(bvh->arena);
  free(bvh->nodes);
  free(bvh);
}

/* Rounds up to a multiple of 64 (aligned_alloc wants size % alignment == 0). */
static size_t tt__embree_round64(size_t n) { return (n + 63) & ~(size_t)63; }

/* Allocates a tree array (64-byte aligned, `bytes` rounded up to 64). Arrays of 2 MiB and
 * more start on a 2 MiB boundary and are marked MADV_HUGEPAGE before they are first
 * written: incoherent rays touch lines all over a large tree, and with 4 KiB pages nearly
 * every node visit also misses the TLB (a page walk on top of the cache miss). Transparent
 * huge pages need the kernel's "madvise" or "always" mode; otherwise this is a no-op. */
#define TT__EMBREE_HUGE ((size_t)2 << 20)
static void *tt__embree_tree_alloc(size_t bytes) {
  if (!bytes) return NULL;
  size_t n = tt__embree_round64(bytes);
  if (n < TT__EMBREE_HUGE) return aligned_alloc(64, n);
  n = (n + TT__EMBREE_HUGE - 1) & ~(TT__EMBREE_HUGE - 1);
  void *p = aligned_alloc(TT__EMBREE_HUGE, n);
#ifdef MADV_HUGEPAGE
  if (p) madvise(p, n, MADV_HUGEPAGE); /* advice only: failure changes nothing */
#endif
  return p;
}

/* Smallest maxDepth with bf^(maxDepth-1) * maxLeafSize >= n (a tree of that depth can hold
 * n primitives at all; SAH's unbalanced splits may need more). */
static int tt__embree_min_depth(uint64_t n, int bf, int max_leaf) {
  int d = 1;
  double cap = (double)max_leaf;
  while (cap < (double)n && d < 1000) {
    cap *= bf;
    d++;
  }
  return d;
}

tt_status tt__embree_custom_build(const tt_scene *scene, const tt__embree_settings *st,
                                  RTCDevice device, tt__embree_bvh **out,
                                  tt_accel_build_stats *stats) {
  *out = NULL;
  const int bf = st->branching_factor;
  if (bf != 2 && bf != 4 && bf != 8)
    return tt_set_error(TT_ERR_INFEASIBLE,
                        "accel_embree: custom backend: branchingFactor %d (expected 2, 4 or 8)",
                        bf);
  /* Repaired by the check already; kept so a direct call can never reach Embree's
   * out-of-bounds paths. */
  int min_leaf = st->min_leaf_size, max_leaf = st->max_leaf_size;
  if (min_leaf > max_leaf) {
    int t = min_leaf;
    min_leaf = max_leaf;
    max_leaf = t;
  }
  if (min_leaf < 1 || max_leaf > RTC_BUILD_MAX_PRIMITIVES_PER_LEAF)
    return tt_set_error(TT_ERR_INFEASIBLE,
                        "accel_embree: custom backend: leaf sizes must lie in [1, %d] "
                        "(minLeafSize %d, maxLeafSize %d)",
                        RTC_BUILD_MAX_PRIMITIVES_PER_LEAF, min_leaf, max_leaf);
  if (st->max_depth < 1 || st->max_depth > 64 || st->sah_block_size < 1 ||
      !(st->trav_cost > 0.0f) || !(st->int_cost > 0.0f))
    return tt_set_error(TT_ERR_INFEASIBLE,
                        "accel_embree: custom backend: maxDepth %d, sahBlockSize %d, travcost "
                        "%g, intcost %g out of range",
                        st->max_depth, st->sah_block_size, (double)st->trav_cost,
                        (double)st->int_cost);

  /* Valid triangles (finite vertices) become build primitives. */
  const uint32_t meshes = tt_scene_mesh_count(scene);
  uint64_t n = 0;
  for (uint32_t g = 0; g < meshes; g++) n += tt_scene_mesh(scene, g)->triangle_count;
  const int high = st->quality == 3;
  /* Spatial splits duplicate references: the builder needs room beyond the count (about
   * twice it, as Embree's own presplit factor allows); without it HIGH silently falls back
   * to binned SAH. */
  uint64_t cap = high ? 2 * n + 64 : n;
  if (cap > ((size_t)-1) / sizeof(struct RTCBuildPrimitive) / 2)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "accel_embree: %llu triangles is too many",
                        (unsigned long long)n);
  struct RTCBuildPrimitive *prims =
      cap ? aligned_alloc(32, tt__embree_round64(cap * sizeof *prims)) : NULL;
  if (cap && !prims)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "accel_embree: cannot allocate %llu build primitives",
                        (unsigned long long)cap);
  float root_lo[3] = {INFINITY, INFINITY, INFINITY}, root_hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  uint64_t count = 0;
  for (uint32_t g = 0; g < meshes; g++) {
    const tt_mesh *m = tt_scene_mesh(scene, g);
    for (uint32_t p = 0; p < m->triangle_count; p++) {
      const float *v[3];
      tt__embree_tri_verts(m, p, v);
      float lo[3], hi[3];
      int ok = 1;
      for (int k = 0; k < 3; k++) {
        lo[k] = fminf(v[0][k], fminf(v[1][k], v[2][k]));
        hi[k] = fmaxf(v[0][k], fmaxf(v[1][k], v[2][k]));
        ok &= isfinite(v[0][k]) && isfinite(v[1][k]) && isfinite(v[2][k]);
      }
      if (!ok) continue; /* NaN/inf vertices: never hit (Embree's scene API drops them too) */
      struct RTCBuildPrimitive *b = &prims[count++];
      b->lower_x = lo[0], b->lower_y = lo[1], b->lower_z = lo[2];
      b->upper_x = hi[0], b->upper_y = hi[1], b->upper_z = hi[2];
      b->geomID = g;
      b->primID = p;
      for (int k = 0; k < 3; k++) {
        root_lo[k] = fminf(root_lo[k], lo[k]);
        root_hi[k] = fmaxf(root_hi[k], hi[k]);
      }
    }
  }

  /* Scene-dependent part of the maxDepth constraint, detected before Embree throws. */
  if (count > 0) {
    int need = tt__embree_min_depth(count, bf, max_leaf);
    if (st->max_depth < need) {
      free(prims);
      return tt_set_error(TT_ERR_INFEASIBLE,
                          "accel_embree: maxDepth %d is too small for %llu triangles with "
                          "branchingFactor %d and maxLeafSize %d: needs "
                          "branchingFactor^(maxDepth-1)*maxLeafSize >= triangles, i.e. "
                          "maxDepth >= %d",
                          st->max_depth, (unsigned long long)count, bf, max_leaf, need);
    }
  }

  tt__embree_bvh *bvh = calloc(1, sizeof *bvh);
  if (!bvh) {
    free(prims);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "accel_embree: out of memory");
  }
  bvh->width = bf;
  bvh->robust = st->robust != 0;
  bvh->root = TT__EMBREE_REF_NONE;
  if (count == 0) { /* every triangle invalid: a tree that nothing hits */
    free(prims);
    *out = bvh;
    stats->memory_bytes = sizeof *bvh;
    return TT_OK;
  }

  tt__embree_cb_ctx ctx;
  memset(&ctx, 0, sizeof ctx);
  ctx.scene = scene;
  ctx.geom_mask = high && meshes <= TT__EMBREE_GEOMID_MASK ? TT__EMBREE_GEOMID_MASK : 0xFFFFFFFFu;

  static const enum RTCBuildQuality qualities[] = {RTC_BUILD_QUALITY_LOW, RTC_BUILD_QUALITY_MEDIUM,
                                                   RTC_BUILD_QUALITY_HIGH};
  struct RTCBuildArguments args = rtcDefaultBuildArguments();
  args.byteSize = sizeof args;
  args.buildQuality = qualities[st->quality >= 1 && st->quality <= 3 ? st->quality - 1 : 1];
  /* DYNAMIC is accepted and ignored by Embree 3.13.5's builders; passed for fidelity. */
  args.buildFlags = st->is_static ? RTC_BUILD_FLAG_NONE : RTC_BUILD_FLAG_DYNAMIC;
  args.maxBranchingFactor = (unsigned)bf;
  args.maxDepth = (unsigned)st->max_depth;
  args.sahBlockSize = (unsigned)st->sah_block_size;
  args.minLeafSize = (unsigned)min_leaf;
  args.maxLeafSize = (unsigned)max_leaf;
  args.traversalCost = st->trav_cost;
  args.intersectionCost = st->int_cost;
  args.bvh = rtcNewBVH(device);
  args.primitives = prims;
  args.primitiveCount = count;
  args.primitiveArrayCapacity = high ? cap : count;
  args.createNode = tt__embree_cb_node;
  args.setNodeChildren = tt__embree_cb_children;
  args.setNodeBounds = tt__embree_cb_bounds;
  args.createLeaf = tt__embree_cb_leaf;
  args.splitPrimitive = high ? tt__embree_cb_split : NULL;
  args.buildProgress = NULL;
  args.userPtr = &ctx;
  if (!args.bvh) {
    free(prims);
    tt__embree_custom_free(bvh);
    return tt_set_error(TT_ERR_INTERNAL, "accel_embree: rtcNewBVH failed: %s",
                        tt__embree_last_error());
  }

  /* An Embree failure here is a property of the configuration (mostly "depth limit
   * reached"), reported to the tuner as infeasible: keep it out of the ERROR log. */
  tt__embree_set_quiet(1);
  void *root = rtcBuildBVH(&args);
  enum RTCError err = rtcGetDeviceError(device);
  tt__embree_set_quiet(0);
  free(prims);
  if (!root || err != RTC_ERROR_NONE || atomic_load(&ctx.too_wide)) {
    const char *msg = tt__embree_last_error();
    tt_status code = err == RTC_ERROR_OUT_OF_MEMORY ? TT_ERR_OUT_OF_MEMORY : TT_ERR_INFEASIBLE;
    int depth = msg && strstr(msg, "depth limit") != NULL;
    rtcReleaseBVH(args.bvh);
    tt__embree_custom_free(bvh);
    if (atomic_load(&ctx.too_wide))
      return tt_set_error(TT_ERR_INTERNAL,
                          "accel_embree: rtcBuildBVH made a node wider than 8 children");
    return tt_set_error(code,
                        "accel_embree: rtcBuildBVH failed for quality %d, branchingFactor %d, "
                        "maxDepth %d, leaves [%d, %d] over %llu triangles: %s%s",
                        st->quality, bf, st->max_depth, min_leaf, max_leaf,
                        (unsigned long long)count, msg && msg[0] ? msg : "no tree returned",
                        depth ? " (raise maxDepth or maxLeafSize)" : "");
  }

  tt__embree_flat f;
  memset(&f, 0, sizeof f);
  f.scene = scene;
  f.N = bf;
  f.robust = bvh->robust;
  f.node_cap = atomic_load(&ctx.inner);
  /* Leaf blocks of ceil(112 * pairs / 64) lines (at most 63 bytes of padding each), after
   * the nodes for BVH2; the exact size is known after the layout pass. */
  const uint64_t pairs = atomic_load(&ctx.slots) / 2, leaves = atomic_load(&ctx.leaves);
  f.arena_cap = (bf == 2 ? f.node_cap : 0) + (112u * pairs + 63u * leaves) / 64u + 1u;
  size_t cap_bytes = (size_t)f.arena_cap * 64u;
  size_t node_bytes = bf == 2 ? 0 : (size_t)f.node_cap * (size_t)(32 * bf);
  f.arena = tt__embree_tree_alloc(cap_bytes);
  f.nodes = node_bytes ? tt__embree_tree_alloc(node_bytes) : NULL;
  if (!f.arena || (node_bytes && !f.nodes)) {
    free(f.arena);
    free(f.nodes);
    rtcReleaseBVH(args.bvh);
    tt__embree_custom_free(bvh);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "accel_embree: cannot allocate the BVH (%zu bytes)",
                        cap_bytes + node_bytes);
  }
  memset(f.arena, 0, cap_bytes);
  bvh->root = tt__embree_flatten(&f, root, 1, root_lo, root_hi);
  rtcReleaseBVH(args.bvh);
  size_t bytes = (size_t)f.arena_lines * 64u;
  if (!f.error && f.arena_lines < f.arena_cap) { /* exact-size copy */
    char *a = tt__embree_tree_alloc(bytes);
    if (a) {
      memcpy(a, f.arena, bytes);
      free(f.arena);
      f.arena = a;
    } else {
      bytes = cap_bytes;
    }
  }
  bvh->arena = f.arena;
  bvh->nodes = f.nodes;
  bvh->arena_lines = f.arena_lines;
  bvh->node_count = f.node_count;
  bvh->slot_count = f.slot_count;
  if (f.error) {
    tt__embree_custom_free(bvh);
    return tt_set_error(TT_ERR_INTERNAL, "accel_embree: custom layout failed: %s", f.error);
  }
  stats->memory_bytes = sizeof *bvh + bytes + node_bytes;

  double root_area = tt__embree_area(root_lo, root_hi);
  stats->nodes = f.node_count;
  stats->leaves = f.leaves;
  /* Expected inner-node visits plus triangle tests of a random line through the root box
   * (SAH with unit costs, counted per triangle): comparable across configurations. */
  stats->sah_cost = root_area > 0.0 ? (f.area_inner + f.area_leaf_tris) / root_area : 0.0;
  stats->max_depth = f.max_depth;
  *out = bvh;
  return TT_OK;
}

/* ---- refit ---- */

/* Refits the subtree `ref` whose box the caller stores: writes its box into lo/hi and adds
 * its SAH terms to f (area_inner per inner node, area * triangles per leaf, as the layout
 * pass counts them). Leaves repack their triangles from the current positions. */
static void tt__embree_refit_ref(tt__embree_flat *f, const tt__embree_bvh *bvh, uint32_t ref,
                                 float lo[3], float hi[3]) {
  for (int k = 0; k < 3; k++) {
    lo[k] = INFINITY;
    hi[k] = -INFINITY;
  }
  if (ref == TT__EMBREE_REF_NONE) return;
  if (ref & TT__EMBREE_REF_LEAF) {
    const uint32_t pairs = ((ref >> TT__EMBREE_LEAF_SHIFT) & 0xFu) + 1u, wide = pairs / 2;
    float *base = (float *)((char *)bvh->arena + (uint64_t)(ref & TT__EMBREE_LINE2_MASK) * 64u);
    tt__embree_id *id = (tt__embree_id *)((char *)base + (size_t)pairs * 96u);
    uint32_t tris = 0;
    for (uint32_t j = 0; j < 2 * pairs; j++) {
      if (id[j].geom == TT_INVALID_ID) continue;
      int W = j < 4 * wide ? 4 : 2;
      uint32_t p0 = W == 4 ? j - j % 4 : 4 * wide;
      const uint32_t geom = id[j].geom, prim = id[j].prim;
      tt__embree_pack_tri(f, base + (size_t)p0 * TT__EMBREE_SLOT_FLOATS, W, (int)(j - p0), &id[j],
                          geom, prim);
      const float *v[3];
      tt__embree_tri_verts(tt_scene_mesh(f->scene, geom), prim, v);
      for (int c = 0; c < 3; c++)
        for (int k = 0; k < 3; k++) {
          lo[k] = fminf(lo[k], v[c][k]);
          hi[k] = fmaxf(hi[k], v[c][k]);
        }
      tris++;
    }
    f->area_leaf_tris += tt__embree_area(lo, hi) * tris;
    return;
  }
  const int N = f->N;
  float *rows = (float *)(N == 2 ? (char *)bvh->arena + (uint64_t)ref * 64u
                                 : (char *)bvh->nodes + (uint64_t)ref * (uint64_t)(32 * N));
  const uint32_t *child = (const uint32_t *)(rows + 6 * N);
  for (int i = 0; i < N; i++) {
    float *clo[3], *cup[3];
    for (int k = 0; k < 3; k++) {
      clo[k] = N == 2 ? &rows[4 * k + i] : &rows[(2 * k) * N + i];
      cup[k] = N == 2 ? &rows[4 * k + 2 + i] : &rows[(2 * k + 1) * N + i];
    }
    if (!(*clo[0] <= *cup[0])) continue; /* an empty lane stays empty */
    float b[6];
    tt__embree_refit_ref(f, bvh, child[i], b, b + 3);
    for (int k = 0; k < 3; k++) {
      *clo[k] = b[k];
      *cup[k] = b[3 + k];
      lo[k] = fminf(lo[k], b[k]);
      hi[k] = fmaxf(hi[k], b[3 + k]);
    }
  }
  f->area_inner += tt__embree_area(lo, hi);
}

/* Parallel refit: the subtrees at depth `depth` of the tree (and the leaves above it), in
 * depth-first order, are refitted as independent tasks; the nodes above them afterwards,
 * from the tasks' boxes. The split depends on the tree only, never on the thread count, so
 * the boxes and the SAH sums (added task by task in that order) are the same bits whatever
 * --threads says. */
#define TT__EMBREE_REFIT_TASKS 64 /* at least this many subtrees, where the tree has them */
/* Below this many triangle slots the refit stays on the calling thread: waking the workers
 * costs more than the whole refit (animated-cornell, 90 triangles: median update 0.056 ms,
 * but frames of milliseconds on a loaded machine when they were woken). */
#define TT__EMBREE_REFIT_PARALLEL 8192

typedef struct tt__embree_refit_task {
  uint32_t ref;
  float box[6];
  double area_inner, area_leaf_tris;
} tt__embree_refit_task;

typedef struct tt__embree_refit_job {
  const tt__embree_flat *proto; /* scene, N, robust */
  const tt__embree_bvh *bvh;
  tt__embree_refit_task *task;
  uint32_t count, next, depth;
} tt__embree_refit_job;

/* Child slots of inner node `ref`: their references and box rows. */
static const uint32_t *tt__embree_refit_children(const tt__embree_bvh *bvh, int N, uint32_t ref,
                                                 float **rows) {
  *rows = (float *)(N == 2 ? (char *)bvh->arena + (uint64_t)ref * 64u
                           : (char *)bvh->nodes + (uint64_t)ref * (uint64_t)(32 * N));
  return (const uint32_t *)(*rows + 6 * N);
}

/* Counts (task == NULL) or lists the tasks of a split at `depth` below `ref`. */
static uint32_t tt__embree_refit_split(tt__embree_refit_job *job, uint32_t ref, uint32_t d) {
  const int N = job->proto->N;
  if (d == job->depth || (ref & TT__EMBREE_REF_LEAF)) {
    if (job->task) job->task[job->count].ref = ref;
    return job->count++, 1;
  }
  float *rows;
  const uint32_t *child = tt__embree_refit_children(job->bvh, N, ref, &rows);
  uint32_t n = 0;
  for (int i = 0; i < N; i++)
    if (rows[N == 2 ? i : i] <= rows[N == 2 ? 2 + i : N + i]) /* lower x <= upper x: a child */
      n += tt__embree_refit_split(job, child[i], d + 1);
  return n;
}

/* Refits tasks [begin, end) (a parallel_for chunk, or all of them). */
static void tt__embree_refit_tasks(void *ctx, uint64_t begin, uint64_t end, uint32_t thread) {
  (void)thread;
  tt__embree_refit_job *job = ctx;
  for (uint64_t i = begin; i < end; i++) {
    tt__embree_flat f = *job->proto;
    tt__embree_refit_task *t = &job->task[i];
    tt__embree_refit_ref(&f, job->bvh, t->ref, t->box, t->box + 3);
    t->area_inner = f.area_inner;
    t->area_leaf_tris = f.area_leaf_tris;
  }
}

/* The nodes above the split, from the tasks' boxes (same order as tt__embree_refit_split). */
static void tt__embree_refit_top(tt__embree_refit_job *job, tt__embree_flat *f, uint32_t ref,
                                 uint32_t d, float lo[3], float hi[3]) {
  if (d == job->depth || (ref & TT__EMBREE_REF_LEAF)) {
    const tt__embree_refit_task *t = &job->task[job->next++];
    f->area_inner += t->area_inner;
    f->area_leaf_tris += t->area_leaf_tris;
    memcpy(lo, t->box, 3 * sizeof(float));
    memcpy(hi, t->box + 3, 3 * sizeof(float));
    return;
  }
  const int N = f->N;
  float *rows;
  const uint32_t *child = tt__embree_refit_children(job->bvh, N, ref, &rows);
  for (int k = 0; k < 3; k++) {
    lo[k] = INFINITY;
    hi[k] = -INFINITY;
  }
  for (int i = 0; i < N; i++) {
    float *clo[3], *cup[3];
    for (int k = 0; k < 3; k++) {
      clo[k] = N == 2 ? &rows[4 * k + i] : &rows[(2 * k) * N + i];
      cup[k] = N == 2 ? &rows[4 * k + 2 + i] : &rows[(2 * k + 1) * N + i];
    }
    if (!(*clo[0] <= *cup[0])) continue;
    float b[6];
    tt__embree_refit_top(job, f, child[i], d + 1, b, b + 3);
    for (int k = 0; k < 3; k++) {
      *clo[k] = b[k];
      *cup[k] = b[3 + k];
      lo[k] = fminf(lo[k], b[k]);
      hi[k] = fmaxf(hi[k], b[3 + k]);
    }
  }
  f->area_inner += tt__embree_area(lo, hi);
}

double tt__embree_custom_refit(const tt_scene *scene, tt__embree_bvh *bvh, const tt_host *host) {
  if (!bvh || bvh->root == TT__EMBREE_REF_NONE) return 0.0;
  tt__embree_flat f;
  memset(&f, 0, sizeof f);
  f.scene = scene;
  f.N = bvh->width;
  f.robust = bvh->robust;
  float lo[3], hi[3];
  /* the shallowest split with enough subtrees (the tree's shape decides, not the threads) */
  tt__embree_refit_job job = {.proto = &f, .bvh = bvh};
  uint32_t prev = 0;
  for (job.depth = 0; job.depth < 24; job.depth++) {
    job.count = 0;
    uint32_t n = tt__embree_refit_split(&job, bvh->root, 0);
    if (n >= TT__EMBREE_REFIT_TASKS || (job.depth > 0 && n == prev)) break;
    prev = n;
  }
  job.count = 0;
  tt__embree_refit_split(&job, bvh->root, 0);
  job.task = malloc(sizeof *job.task * job.count);
  if (!job.task) { /* no memory for the task list: refit in one pass */
    tt__embree_refit_ref(&f, bvh, bvh->root, lo, hi);
  } else {
    job.count = 0;
    tt__embree_refit_split(&job, bvh->root, 0);
    if (!host || !host->parallel_for || job.count < 2 ||
        bvh->slot_count < TT__EMBREE_REFIT_PARALLEL ||
        host->parallel_for(job.count, 1, tt__embree_refit_tasks, &job) != TT_OK)
      tt__embree_refit_tasks(&job, 0, job.count, 0);
    job.next = 0;
    tt__embree_refit_top(&job, &f, bvh->root, 0, lo, hi);
    free(job.task);
  }
  double root_area = tt__embree_area(lo, hi);
  return root_area > 0.0 ? (f.area_inner + f.area_leaf_tris) / root_area : 0.0;
}
