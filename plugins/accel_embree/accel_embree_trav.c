/* accel_embree: SIMD single-ray traversal of the custom backend's BVH (layout in
 * accel_embree_bvh.h).
 *
 * This file is compiled three times (see meson.build): with -msse4.1 (the baseline every
 * x86-64 CI machine has), with -mavx2 -mfma, and with AVX-512 F/VL/DQ/BW (same source: the
 * compiler gets 32 vector registers, so the ray constants stay in registers);
 * TT__EMBREE_TRAV_ISA names the copy. The plugin picks a table at run time only when the CPU
 * reports its features, so no AVX instruction ever runs on an older CPU. Everything here
 * is static except the table getter, so the copies cannot be mixed up by the linker.
 *
 * Traversal: one stack per ray; at each inner node all child boxes are tested at once;
 * hit children are visited front to back by entry distance (closest hit) or in node order
 * (occlusion, which stops at the first hit); a popped entry farther than the closest hit
 * so far is skipped. Leaves are tested one SIMD packet (4 or 2 triangles) at a time.
 *
 * BVH2 (tt__embree_intersect2, tt__embree_occluded2), the default tree: a 64-byte node holds both
 * children's boxes as three rows (lower c0, lower c1, upper c0, upper c1); one 4-wide
 * multiply-subtract per axis with constants (a, a, -a, -a), a = |1/d|, then a permute
 * chosen once per ray by the direction's sign gives (near, near, -far, -far), and three
 * max ops give both children's [tmin, tmax] (tt__embree_box2). The next child is chosen by
 * branches on the hit mask, never by an index computed from it: a predicted branch lets
 * the next node's load start while the box test is still running, which halved the cost
 * of a node. Nodes and leaves share one arena of lines (accel_embree_bvh.h), so any
 * reference's address is one mask and shift: the kernel prefetches the chosen child's
 * first two lines (for an inner child, that includes its first child) and the node's
 * grand[] hint (the child's second child), i.e. two levels ahead, without branching on
 * leaf versus node. */
#include "accel_embree_bvh.h"

#include <immintrin.h>
#include <math.h>
#include <string.h>

#ifndef TT__EMBREE_TRAV_ISA
#  error "compile with -DTT__EMBREE_TRAV_ISA=sse41, avx2 or avx512"
#endif
#define TT__EMBREE_CAT2(a, b) a##b
#define TT__EMBREE_CAT(a, b) TT__EMBREE_CAT2(a, b)

#if defined(__AVX2__) && defined(__FMA__)
#  define TT__EMBREE_HAVE_AVX2 1
#else
#  define TT__EMBREE_HAVE_AVX2 0
#endif

#define TT__EMBREE_INLINE static inline __attribute__((always_inline))

/* Stack entries: 64 levels (maxDepth <= 64, checked at build) x (8 - 1) siblings + slack. */
#define TT__EMBREE_STACK 640
/* BVH2: at most one entry per level; the builder refuses trees deeper than 88. */
#define TT__EMBREE_MAX_DEPTH2 96

/* 1 + 2 * gamma(3) (pbrt's bound on the error of a slab distance): far plane distances
 * are scaled by it in robust mode so round-off cannot make a box look missed. */
#define TT__EMBREE_ROBUST_FAR 1.0000003576f

/* Per-ray data, broadcast to SIMD registers once. With AVX2 only the 8-wide copies exist
 * and the 4-wide views are their lower halves (a free cast): one copy of the ray state
 * keeps more of it in the 16 registers. */
#if TT__EMBREE_HAVE_AVX2
typedef __m256 tt__embree_vreg;
#  define TT__EMBREE_SET1(x) _mm256_set1_ps(x)
#  define TT__EMBREE_V4(v) _mm256_castps256_ps128(v)
#else
typedef __m128 tt__embree_vreg;
#  define TT__EMBREE_SET1(x) _mm_set1_ps(x)
#  define TT__EMBREE_V4(v) (v)
#endif
typedef struct tt__embree_rc {
  tt__embree_vreg o[3], d[3];    /* origin, direction */
  tt__embree_vreg rd[3], ord[3]; /* 1/dir (zero guarded) and org * rd */
  tt__embree_vreg tnear,
      tfar;    /* closest hit: tfar is tt__embree_tfar_slack(the closest hit so far) */
  int near[3]; /* near-plane row per axis: 2k + signbit(dir[k]) */
  /* Watertight test (Woop, Benthin, Wald 2013): axes permuted so that kz has the largest
   * |dir| and the shear constants. */
  int kx, ky, kz;
  __m128 sx, sy, sz;
} tt__embree_rc;

/* Best hit so far. */
typedef struct tt__embree_best {
  float t, u, v;
  const float *pk;         /* packet of the hit, NULL for none */
  int W, lane;             /* its width and the hit's lane */
  const tt__embree_id *id; /* the hit triangle's ids */
} tt__embree_best;

/* The far limit of closest-hit box and triangle tests: a little beyond the closest hit so
 * far. The triangle test compares T <= |det| * tfar before dividing, and a box's entry
 * distance is rounded otherwise than a triangle's t = T / |det| in it: when tfar is another
 * triangle's t, a triangle at exactly that distance (a ray through the edge two triangles
 * share) could fail either test by a rounding, in one order of visit and not in the other,
 * and the tie (tt__embree_id_less) was decided by the order. With the slack (2^-20 relative, far
 * more than those roundings where the box is not much farther from the origin than its
 * size) such a triangle is tested; the decision is taken on the divided t (the nearest
 * lane, t <= the best t, which starts as the ray's own tfar), so no hit beyond tfar is
 * reported. Occlusion keeps the exact limit. */
TT__EMBREE_INLINE float tt__embree_tfar_slack(float t) { return t + fabsf(t) * 0x1p-20f; }

/* Prepares the ray; returns 0 when no hit is possible (NaN/inf input, empty interval). */
TT__EMBREE_INLINE int tt__embree_setup(tt__embree_rc *r, const tt_ray *ray, int robust) {
  float o[3] = {ray->org[0], ray->org[1], ray->org[2]};
  float d[3] = {ray->dir[0], ray->dir[1], ray->dir[2]};
  for (int k = 0; k < 3; k++)
    if (!isfinite(o[k]) || !isfinite(d[k])) return 0;
  if (!(ray->tnear <= ray->tfar)) return 0; /* also rejects NaN */
  for (int k = 0; k < 3; k++) {
    /* A zero component would give 1/0 = inf and 0 * inf = NaN on a slab through the
     * origin; a tiny value of the same sign keeps every slab distance well defined. */
    float dk = fabsf(d[k]) < 1e-18f ? copysignf(1e-18f, d[k]) : d[k];
    float rk = 1.0f / dk;
    r->o[k] = TT__EMBREE_SET1(o[k]);
    r->d[k] = TT__EMBREE_SET1(d[k]);
    r->rd[k] = TT__EMBREE_SET1(rk);
    r->ord[k] = TT__EMBREE_SET1(o[k] * rk);
    r->near[k] = 2 * k + (signbit(dk) ? 1 : 0);
  }
  /* + 0.0f turns a tnear of -0 into +0 (the same interval; the integer box test below
   * needs the bits of a non-negative tnear to be non-negative). */
  r->tnear = TT__EMBREE_SET1(ray->tnear + 0.0f);
  r->tfar = TT__EMBREE_SET1(ray->tfar);
  if (robust) {
    int kz = 0;
    if (fabsf(d[1]) > fabsf(d[kz])) kz = 1;
    if (fabsf(d[2]) > fabsf(d[kz])) kz = 2;
    int kx = kz == 2 ? 0 : kz + 1, ky = kx == 2 ? 0 : kx + 1;
    if (d[kz] < 0.0f) { /* keep the winding so U, V, W signs mean the same thing */
      int t = kx;
      kx = ky;
      ky = t;
    }
    if (d[kz] == 0.0f) return 0; /* zero direction: nothing can be hit */
    r->kx = kx, r->ky = ky, r->kz = kz;
    r->sx = _mm_set1_ps(d[kx] / d[kz]);
    r->sy = _mm_set1_ps(d[ky] / d[kz]);
    r->sz = _mm_set1_ps(1.0f / d[kz]);
  }
  return 1;
}

/* Sets the far limit of a closest-hit query to just beyond t (tt__embree_tfar_slack). */
TT__EMBREE_INLINE void tt__embree_set_tfar(tt__embree_rc *r, float t) {
  r->tfar = TT__EMBREE_SET1(tt__embree_tfar_slack(t));
}

/* Slab distance of 4 planes on one axis. FMA form (b*rd - o*rd, one rounding) where
 * available and not robust; otherwise (b - o) * rd, whose error pbrt's bound covers. */
TT__EMBREE_INLINE __m128 tt__embree_slab4(__m128 b, const tt__embree_rc *r, int k, int robust) {
#if TT__EMBREE_HAVE_AVX2
  if (!robust) return _mm_fmsub_ps(b, TT__EMBREE_V4(r->rd[k]), TT__EMBREE_V4(r->ord[k]));
#else
  (void)robust;
#endif
  return _mm_mul_ps(_mm_sub_ps(b, TT__EMBREE_V4(r->o[k])), TT__EMBREE_V4(r->rd[k]));
}

/* Integer min/max of slab distances (Embree's maxi/mini, node_intersector1.h). For floats
 * whose bits are non-negative (+0 up to +inf), the order of the bits read as signed integers
 * is the order of the values, and every negative float (or -0) reads as a negative integer.
 * With tnear >= +0 (tt__embree_ray_ibox; tt__embree_setup makes -0 into +0):
 *   tmin = maxi(near distances, tnear) is the float max exactly (the max is >= tnear >= 0,
 *     and negative candidates lose in both orders);
 *   tmax = mini(far distances, tfar) is the float min exactly when no far distance is
 *     negative; otherwise both are <= 0 and the integer compare tmin <= tmax says "missed",
 *     as the float compare does, except where tmin = tmax = 0 (a box the ray's interval
 *     touches in the single point t = tnear = 0): such a box is skipped, as Embree skips it.
 * So the boxes hit are the float test's (that one point aside) and the entry distances are
 * the same values. Why: an integer max/min/compare has 1 cycle of latency, a float one 3-4
 * on Intel cores (1-2 on AMD Zen), and the box test's max/min chain is on the path from a
 * node's load to the branch that picks the next node. Not robust only: the robust test
 * keeps the float form (its far distances are scaled after the min). */
#define TT__EMBREE_IMAX4(a, b)                                                                     \
  _mm_castsi128_ps(_mm_max_epi32(_mm_castps_si128(a), _mm_castps_si128(b)))
#define TT__EMBREE_IMIN4(a, b)                                                                     \
  _mm_castsi128_ps(_mm_min_epi32(_mm_castps_si128(a), _mm_castps_si128(b)))
TT__EMBREE_INLINE int tt__embree_ile4(__m128 a, __m128 b) {
#ifdef __AVX512VL__
  return (int)_mm_cmple_epi32_mask(_mm_castps_si128(a), _mm_castps_si128(b));
#else
  return _mm_movemask_ps(
             _mm_castsi128_ps(_mm_cmpgt_epi32(_mm_castps_si128(a), _mm_castps_si128(b)))) ^
         0xF;
#endif
}

/* Whether a ray's box tests may use the integer form: not robust and tnear >= 0. */
TT__EMBREE_INLINE int tt__embree_ray_ibox(const tt_ray *ray, const int robust) {
  return !robust && ray->tnear >= 0.0f;
}

/* Tests 4 boxes given as row pointers (stride between rows `stride` floats); writes entry
 * distances and returns the hit mask. `two` loads only 2 lanes (BVH2 nodes). `ib`: integer
 * max/min (see above; the caller checked tt__embree_ray_ibox). */
TT__EMBREE_INLINE int tt__embree_box4(const float *rows, size_t stride, const tt__embree_rc *r,
                                      int robust, int two, float *dist, const int ib) {
  __m128 tn[3], tf[3];
  for (int k = 0; k < 3; k++) {
    const float *pn = rows + (size_t)r->near[k] * stride;
    const float *pf = rows + (size_t)(r->near[k] ^ 1) * stride;
    __m128 bn, bf;
    if (two) {
      bn = _mm_castpd_ps(_mm_load_sd((const double *)pn));
      bf = _mm_castpd_ps(_mm_load_sd((const double *)pf));
    } else {
      bn = _mm_load_ps(pn);
      bf = _mm_load_ps(pf);
    }
    tn[k] = tt__embree_slab4(bn, r, k, robust);
    tf[k] = tt__embree_slab4(bf, r, k, robust);
  }
  if (ib && !robust) {
    __m128 tmin = TT__EMBREE_IMAX4(TT__EMBREE_IMAX4(tn[0], tn[1]),
                                   TT__EMBREE_IMAX4(tn[2], TT__EMBREE_V4(r->tnear)));
    __m128 tmax = TT__EMBREE_IMIN4(TT__EMBREE_IMIN4(tf[0], tf[1]),
                                   TT__EMBREE_IMIN4(tf[2], TT__EMBREE_V4(r->tfar)));
    _mm_storeu_ps(dist, tmin);
    int m = tt__embree_ile4(tmin, tmax);
    return two ? m & 3 : m;
  }
  __m128 tmin = _mm_max_ps(_mm_max_ps(tn[0], tn[1]), _mm_max_ps(tn[2], TT__EMBREE_V4(r->tnear)));
  __m128 tmax = _mm_min_ps(_mm_min_ps(tf[0], tf[1]), tf[2]);
  if (robust) tmax = _mm_mul_ps(tmax, _mm_set1_ps(TT__EMBREE_ROBUST_FAR));
  tmax = _mm_min_ps(tmax, TT__EMBREE_V4(r->tfar));
  _mm_storeu_ps(dist, tmin);
  int m = _mm_movemask_ps(_mm_cmple_ps(tmin, tmax));
  return two ? m & 3 : m;
}

/* Tests the 8 boxes of a BVH8 node: one AVX pass, or two SSE halves on the baseline. */
TT__EMBREE_INLINE int tt__embree_box8(const tt__embree_node8 *n, const tt__embree_rc *r, int robust,
                                      float *dist, const int ib) {
#if TT__EMBREE_HAVE_AVX2
  __m256 tn[3], tf[3];
  for (int k = 0; k < 3; k++) {
    __m256 bn = _mm256_load_ps(n->b[r->near[k]]), bf = _mm256_load_ps(n->b[r->near[k] ^ 1]);
    if (robust) {
      tn[k] = _mm256_mul_ps(_mm256_sub_ps(bn, r->o[k]), r->rd[k]);
      tf[k] = _mm256_mul_ps(_mm256_sub_ps(bf, r->o[k]), r->rd[k]);
    } else {
      tn[k] = _mm256_fmsub_ps(bn, r->rd[k], r->ord[k]);
      tf[k] = _mm256_fmsub_ps(bf, r->rd[k], r->ord[k]);
    }
  }
  if (ib && !robust) {
#  define TT__EMBREE_IMAX8(a, b) _mm256_max_epi32(a, b)
#  define TT__EMBREE_IMIN8(a, b) _mm256_min_epi32(a, b)
#  define TT__EMBREE_I8(v) _mm256_castps_si256(v)
    __m256i tmin =
        TT__EMBREE_IMAX8(TT__EMBREE_IMAX8(TT__EMBREE_I8(tn[0]), TT__EMBREE_I8(tn[1])),
                         TT__EMBREE_IMAX8(TT__EMBREE_I8(tn[2]), TT__EMBREE_I8(r->tnear)));
    __m256i tmax = TT__EMBREE_IMIN8(TT__EMBREE_IMIN8(TT__EMBREE_I8(tf[0]), TT__EMBREE_I8(tf[1])),
                                    TT__EMBREE_IMIN8(TT__EMBREE_I8(tf[2]), TT__EMBREE_I8(r->tfar)));
#  undef TT__EMBREE_I8
#  undef TT__EMBREE_IMIN8
#  undef TT__EMBREE_IMAX8
    _mm256_storeu_si256((__m256i *)dist, tmin);
#  ifdef __AVX512VL__
    return (int)_mm256_cmple_epi32_mask(tmin, tmax);
#  else
    return _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(tmin, tmax))) ^ 0xFF;
#  endif
  }
  __m256 tmin = _mm256_max_ps(_mm256_max_ps(tn[0], tn[1]), _mm256_max_ps(tn[2], r->tnear));
  __m256 tmax = _mm256_min_ps(_mm256_min_ps(tf[0], tf[1]), tf[2]);
  if (robust) tmax = _mm256_mul_ps(tmax, _mm256_set1_ps(TT__EMBREE_ROBUST_FAR));
  tmax = _mm256_min_ps(tmax, r->tfar);
  _mm256_storeu_ps(dist, tmin);
  return _mm256_movemask_ps(_mm256_cmp_ps(tmin, tmax, _CMP_LE_OQ));
#else
  int lo = tt__embree_box4(&n->b[0][0], 8, r, robust, 0, dist, ib);
  int hi = tt__embree_box4(&n->b[0][4], 8, r, robust, 0, dist + 4, ib);
  return lo | hi << 4;
#endif
}

/* Tests one inner node of width N; returns the hit mask, distances in `dist`. */
TT__EMBREE_INLINE int tt__embree_node_test(const void *node, const tt__embree_rc *r, int N,
                                           int robust, float *dist, const int ib) {
  if (N == 4)
    return tt__embree_box4(&((const tt__embree_node4 *)node)->b[0][0], 4, r, robust, 0, dist, ib);
  return tt__embree_box8((const tt__embree_node8 *)node, r, robust, dist, ib);
}

/* Address of node `index` of a width-N tree (node sizes are 32 * N bytes). */
TT__EMBREE_INLINE const void *tt__embree_node_at(const tt__embree_bvh *bvh, uint32_t index, int N) {
  return (const char *)bvh->nodes + (size_t)index * (size_t)(32 * N);
}

/* Child references of a width-N node (after its 6 rows of N floats). */
TT__EMBREE_INLINE const uint32_t *tt__embree_children(const void *node, int N) {
  return (const uint32_t *)((const char *)node + 24 * N);
}

/* Prefetches what visiting `ref` reads first: the node (32 * N bytes) or the leaf's first
 * lines. Traversal is bound by memory latency, and the hit children are known one box
 * test before they are visited (or much longer, for the ones pushed on the stack).
 * Branch-free and a fixed number of prefetches (BVH8: 4 lines, a node or a leaf of up to 4
 * triangles; BVH4: 3): the address is selected arithmetically from the leaf / node bit,
 * so a mix of leaf and node children costs no mispredicted branch and no loop whose trip
 * count depends on the leaf's size. The lines of a larger leaf's later packets are not
 * prefetched (they are read one packet test later); a prefetch beyond a small leaf's
 * block reads a neighbour's line (harmless: hints never fault or change a result). */
TT__EMBREE_INLINE void tt__embree_prefetch(const tt__embree_bvh *bvh, uint32_t ref, int N) {
  const uintptr_t leaf = (uintptr_t)bvh->arena + ((uintptr_t)(ref & TT__EMBREE_LINE2_MASK) << 6);
  const uintptr_t node = (uintptr_t)bvh->nodes + (uintptr_t)ref * (uintptr_t)(32 * N);
  const uintptr_t is_leaf = (uintptr_t)0 - (uintptr_t)(ref >> 31);
  const char *p = (const char *)((leaf & is_leaf) | (node & ~is_leaf));
  _mm_prefetch(p, _MM_HINT_T0);
  _mm_prefetch(p + 64, _MM_HINT_T0);
  _mm_prefetch(p + 128, _MM_HINT_T0);
  if (N == 8) _mm_prefetch(p + 192, _MM_HINT_T0);
}

/* Prefetches the hit children of a BVH4/8 node (BVH2: tt__embree_pf2). */
TT__EMBREE_INLINE void tt__embree_prefetch_children(const tt__embree_bvh *bvh,
                                                    const uint32_t *child, int mask, int N) {
  for (int m = mask; m; m &= m - 1) tt__embree_prefetch(bvh, child[__builtin_ctz((unsigned)m)], N);
}

/* Tests the (up to) 4 triangles of a packet against the ray's current [tnear, tfar]. Returns the
 * valid-lane mask; T, U, V are scaled by |det| (division postponed to the winner). */
/* Row r of a width-W packet (W = 2: lanes 2 and 3 read as zero, i.e. never hit). */
TT__EMBREE_INLINE __m128 tt__embree_row(const float *pk, int W, int r) {
  if (W == 4) return _mm_load_ps(pk + 4 * r);
  return _mm_castpd_ps(_mm_load_sd((const double *)(pk + 2 * r)));
}

TT__EMBREE_INLINE int tt__embree_tri_test(const float *pk, int W, const tt__embree_rc *r,
                                          int robust, __m128 *T_out, __m128 *U_out, __m128 *V_out,
                                          __m128 *den_out, __m128 *valid_out) {
  const __m128 sign = _mm_set1_ps(-0.0f), zero = _mm_setzero_ps();
  __m128 T, U, V, absden, valid;
  if (!robust) {
    /* Moller-Trumbore with precomputed Ng: C = v0 - o, R = C x D, den = Ng.D,
     * u = R.e2 / den, v = R.e1 / den, t = Ng.C / den. */
    __m128 cx = _mm_sub_ps(tt__embree_row(pk, W, 0), TT__EMBREE_V4(r->o[0]));
    __m128 cy = _mm_sub_ps(tt__embree_row(pk, W, 1), TT__EMBREE_V4(r->o[1]));
    __m128 cz = _mm_sub_ps(tt__embree_row(pk, W, 2), TT__EMBREE_V4(r->o[2]));
#if TT__EMBREE_HAVE_AVX2
    /* FMA builds: Embree's cross and dot (common/math/vec3.h: msub(a.y, b.z, a.z * b.y),
     * madd(a.x, b.x, madd(a.y, b.y, a.z * b.z))), 11 operations fewer per packet; the
     * packet kernels (tt__embree_ptri) use the same forms, lane by lane. */
    const __m128 dx = TT__EMBREE_V4(r->d[0]), dy = TT__EMBREE_V4(r->d[1]),
                 dz = TT__EMBREE_V4(r->d[2]);
    __m128 rx = _mm_fmsub_ps(cy, dz, _mm_mul_ps(cz, dy));
    __m128 ry = _mm_fmsub_ps(cz, dx, _mm_mul_ps(cx, dz));
    __m128 rz = _mm_fmsub_ps(cx, dy, _mm_mul_ps(cy, dx));
    __m128 nx = tt__embree_row(pk, W, 9), ny = tt__embree_row(pk, W, 10),
           nz = tt__embree_row(pk, W, 11);
    __m128 den = _mm_fmadd_ps(nx, dx, _mm_fmadd_ps(ny, dy, _mm_mul_ps(nz, dz)));
    __m128 sgn = _mm_and_ps(den, sign);
    absden = _mm_xor_ps(den, sgn);
    U = _mm_xor_ps(_mm_fmadd_ps(rx, tt__embree_row(pk, W, 6),
                                _mm_fmadd_ps(ry, tt__embree_row(pk, W, 7),
                                             _mm_mul_ps(rz, tt__embree_row(pk, W, 8)))),
                   sgn);
    V = _mm_xor_ps(_mm_fmadd_ps(rx, tt__embree_row(pk, W, 3),
                                _mm_fmadd_ps(ry, tt__embree_row(pk, W, 4),
                                             _mm_mul_ps(rz, tt__embree_row(pk, W, 5)))),
                   sgn);
    valid = _mm_and_ps(_mm_cmpge_ps(U, zero), _mm_cmpge_ps(V, zero));
    valid = _mm_and_ps(valid, _mm_cmple_ps(_mm_add_ps(U, V), absden));
    valid = _mm_and_ps(valid, _mm_cmpgt_ps(absden, zero));
    if (!_mm_movemask_ps(valid)) return 0;
    T = _mm_xor_ps(_mm_fmadd_ps(nx, cx, _mm_fmadd_ps(ny, cy, _mm_mul_ps(nz, cz))), sgn);
#else
    __m128 rx =
        _mm_sub_ps(_mm_mul_ps(cy, TT__EMBREE_V4(r->d[2])), _mm_mul_ps(cz, TT__EMBREE_V4(r->d[1])));
    __m128 ry =
        _mm_sub_ps(_mm_mul_ps(cz, TT__EMBREE_V4(r->d[0])), _mm_mul_ps(cx, TT__EMBREE_V4(r->d[2])));
    __m128 rz =
        _mm_sub_ps(_mm_mul_ps(cx, TT__EMBREE_V4(r->d[1])), _mm_mul_ps(cy, TT__EMBREE_V4(r->d[0])));
    __m128 nx = tt__embree_row(pk, W, 9), ny = tt__embree_row(pk, W, 10),
           nz = tt__embree_row(pk, W, 11);
    __m128 den = _mm_add_ps(
        _mm_add_ps(_mm_mul_ps(nx, TT__EMBREE_V4(r->d[0])), _mm_mul_ps(ny, TT__EMBREE_V4(r->d[1]))),
        _mm_mul_ps(nz, TT__EMBREE_V4(r->d[2])));
    __m128 sgn = _mm_and_ps(den, sign);
    absden = _mm_xor_ps(den, sgn);
    U = _mm_xor_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, tt__embree_row(pk, W, 6)),
                                         _mm_mul_ps(ry, tt__embree_row(pk, W, 7))),
                              _mm_mul_ps(rz, tt__embree_row(pk, W, 8))),
                   sgn);
    V = _mm_xor_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, tt__embree_row(pk, W, 3)),
                                         _mm_mul_ps(ry, tt__embree_row(pk, W, 4))),
                              _mm_mul_ps(rz, tt__embree_row(pk, W, 5))),
                   sgn);
    valid = _mm_and_ps(_mm_cmpge_ps(U, zero), _mm_cmpge_ps(V, zero));
    valid = _mm_and_ps(valid, _mm_cmple_ps(_mm_add_ps(U, V), absden));
    valid = _mm_and_ps(valid, _mm_cmpgt_ps(absden, zero));
    if (!_mm_movemask_ps(valid)) return 0;
    T = _mm_xor_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, cx), _mm_mul_ps(ny, cy)), _mm_mul_ps(nz, cz)), sgn);
#endif
  } else {
    /* Watertight: vertices relative to the origin, sheared so the ray is the +z axis;
     * U, V, W are 2D edge functions, evaluated identically for a shared edge. */
    const int kx = r->kx, ky = r->ky, kz = r->kz;
    __m128 az = _mm_sub_ps(tt__embree_row(pk, W, 0 + kz), TT__EMBREE_V4(r->o[kz]));
    __m128 bz = _mm_sub_ps(tt__embree_row(pk, W, 3 + kz), TT__EMBREE_V4(r->o[kz]));
    __m128 cz = _mm_sub_ps(tt__embree_row(pk, W, 6 + kz), TT__EMBREE_V4(r->o[kz]));
    __m128 ax = _mm_sub_ps(_mm_sub_ps(tt__embree_row(pk, W, 0 + kx), TT__EMBREE_V4(r->o[kx])),
                           _mm_mul_ps(r->sx, az));
    __m128 ay = _mm_sub_ps(_mm_sub_ps(tt__embree_row(pk, W, 0 + ky), TT__EMBREE_V4(r->o[ky])),
                           _mm_mul_ps(r->sy, az));
    __m128 bx = _mm_sub_ps(_mm_sub_ps(tt__embree_row(pk, W, 3 + kx), TT__EMBREE_V4(r->o[kx])),
                           _mm_mul_ps(r->sx, bz));
    __m128 by = _mm_sub_ps(_mm_sub_ps(tt__embree_row(pk, W, 3 + ky), TT__EMBREE_V4(r->o[ky])),
                           _mm_mul_ps(r->sy, bz));
    __m128 cx = _mm_sub_ps(_mm_sub_ps(tt__embree_row(pk, W, 6 + kx), TT__EMBREE_V4(r->o[kx])),
                           _mm_mul_ps(r->sx, cz));
    __m128 cy = _mm_sub_ps(_mm_sub_ps(tt__embree_row(pk, W, 6 + ky), TT__EMBREE_V4(r->o[ky])),
                           _mm_mul_ps(r->sy, cz));
    __m128 u = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
    __m128 v = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
    __m128 w = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
    __m128 pos =
        _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(u, zero), _mm_cmpge_ps(v, zero)), _mm_cmpge_ps(w, zero));
    __m128 neg =
        _mm_and_ps(_mm_and_ps(_mm_cmple_ps(u, zero), _mm_cmple_ps(v, zero)), _mm_cmple_ps(w, zero));
    __m128 det = _mm_add_ps(_mm_add_ps(u, v), w);
    valid = _mm_and_ps(_mm_or_ps(pos, neg), _mm_cmpneq_ps(det, zero));
    if (!_mm_movemask_ps(valid)) return 0;
    __m128 sgn = _mm_and_ps(det, sign);
    absden = _mm_xor_ps(det, sgn);
    az = _mm_mul_ps(r->sz, az);
    bz = _mm_mul_ps(r->sz, bz);
    cz = _mm_mul_ps(r->sz, cz);
    T = _mm_xor_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(u, az), _mm_mul_ps(v, bz)), _mm_mul_ps(w, cz)),
                   sgn);
    U = _mm_xor_ps(v, sgn); /* weight of v1 */
    V = _mm_xor_ps(w, sgn); /* weight of v2 */
  }
  valid = _mm_and_ps(valid, _mm_cmpge_ps(T, _mm_mul_ps(absden, TT__EMBREE_V4(r->tnear))));
  valid = _mm_and_ps(valid, _mm_cmple_ps(T, _mm_mul_ps(absden, TT__EMBREE_V4(r->tfar))));
  *T_out = T, *U_out = U, *V_out = V, *den_out = absden, *valid_out = valid;
  return _mm_movemask_ps(valid);
}

/* Real triangles in a leaf's packets (for the counters only). */
TT__EMBREE_INLINE uint64_t tt__embree_leaf_tris(const tt__embree_id *id, uint32_t n) {
  uint64_t c = 0;
  for (uint32_t i = 0; i < n; i++) c += id[i].prim != TT_INVALID_ID;
  return c;
}

/* Ties: of two hits at exactly the same distance (a ray through the edge two triangles
 * share, common in voxel and architectural meshes), the one with the smaller (geomID,
 * primID) wins, whatever the order in which they were found. Packets visit leaves in
 * another order than single rays; with "the last one found wins" they answered such rays
 * with the other triangle (kernel bench, voxel monument: 1-3 camera rays of 262,144). The
 * ids are read only on a tie, from lines the leaf test has just read. */
TT__EMBREE_INLINE int tt__embree_id_less(const tt__embree_id *a, const tt__embree_id *b) {
  return a->geom < b->geom || (a->geom == b->geom && a->prim < b->prim);
}

/* Tests one width-W packet (ids of its lanes at `ids`) for a closer hit; updates `best`
 * and the ray's tfar. Returns 1 when the hit became closer (or won a tie). */
TT__EMBREE_INLINE int tt__embree_leaf_packet(const float *pk, const int W, const tt__embree_id *ids,
                                             tt__embree_rc *restrict r, const int robust,
                                             tt__embree_best *restrict best) {
  __m128 T, U, V, den, valid;
  int m = tt__embree_tri_test(pk, W, r, robust, &T, &U, &V, &den, &valid);
  if (!m) return 0;
  /* Nearest valid lane: t = T / |det| for valid lanes, +inf elsewhere. */
  __m128 t = _mm_div_ps(T, den);
  int lane;
  if (m & (m - 1)) {
    __m128 tv = _mm_blendv_ps(_mm_set1_ps(INFINITY), t, valid);
    __m128 mn = _mm_min_ps(tv, _mm_shuffle_ps(tv, tv, _MM_SHUFFLE(2, 3, 0, 1)));
    mn = _mm_min_ps(mn, _mm_shuffle_ps(mn, mn, _MM_SHUFFLE(1, 0, 3, 2)));
    int eq = _mm_movemask_ps(_mm_cmpeq_ps(tv, mn)) & m;
    lane = __builtin_ctz((unsigned)eq);
    for (eq &= eq - 1; eq; eq &= eq - 1) /* a tie within the packet (rare) */
      if (tt__embree_id_less(&ids[__builtin_ctz((unsigned)eq)], &ids[lane]))
        lane = __builtin_ctz((unsigned)eq);
  } else {
    lane = __builtin_ctz((unsigned)m);
  }
  _Alignas(16) float t4[4], u4[4], v4[4], d4[4];
  _mm_store_ps(t4, t);
  if (!(t4[lane] <= best->t)) return 0;
  if (t4[lane] == best->t && best->pk && !tt__embree_id_less(&ids[lane], best->id)) return 0;
  _mm_store_ps(u4, U);
  _mm_store_ps(v4, V);
  _mm_store_ps(d4, den);
  best->t = t4[lane];
  best->u = u4[lane] / d4[lane];
  best->v = v4[lane] / d4[lane];
  best->pk = pk;
  best->W = W;
  best->lane = lane;
  best->id = ids + lane;
  /* The ids are read once, after traversal: fetch their line meanwhile. */
  _mm_prefetch((const char *)best->id, _MM_HINT_T0);
  tt__embree_set_tfar(r, best->t);
  return 1;
}

/* Tests the `pairs` triangle pairs of a leaf (packets at `pk`, ids at `ids`) for a closer
 * hit; returns 1 when one was found. */
TT__EMBREE_INLINE int tt__embree_leaf_closest(const float *pk, const tt__embree_id *ids,
                                              uint32_t pairs, tt__embree_rc *restrict r,
                                              const int robust, tt__embree_best *restrict best) {
  int found = 0;
  uint32_t q = 0;
  for (; q + 1 < pairs; q += 2, pk += 4 * TT__EMBREE_SLOT_FLOATS)
    found |= tt__embree_leaf_packet(pk, 4, ids + 2 * q, r, robust, best);
  if (q < pairs) found |= tt__embree_leaf_packet(pk, 2, ids + 2 * q, r, robust, best);
  return found;
}

/* Returns 1 when some triangle of a leaf lies within the ray's [tnear, tfar]. */
TT__EMBREE_INLINE int tt__embree_leaf_any(const float *pk, uint32_t pairs, const tt__embree_rc *r,
                                          const int robust) {
  __m128 T, U, V, den, valid;
  uint32_t q = 0;
  for (; q + 1 < pairs; q += 2, pk += 4 * TT__EMBREE_SLOT_FLOATS)
    if (tt__embree_tri_test(pk, 4, r, robust, &T, &U, &V, &den, &valid)) return 1;
  return q < pairs && tt__embree_tri_test(pk, 2, r, robust, &T, &U, &V, &den, &valid);
}

/* Leaf fields of a reference: its pairs, its block's packets and ids. */
TT__EMBREE_INLINE uint32_t tt__embree_leaf_pairs(uint32_t ref) {
  return ((ref >> TT__EMBREE_LEAF_SHIFT) & 0xFu) + 1u;
}
TT__EMBREE_INLINE const float *tt__embree_leaf_pk(const tt__embree_bvh *bvh, uint32_t ref) {
  return (const float *)((const char *)bvh->arena + ((size_t)(ref & TT__EMBREE_LINE2_MASK) << 6));
}
TT__EMBREE_INLINE const tt__embree_id *tt__embree_leaf_ids(const tt__embree_bvh *bvh,
                                                           uint32_t ref) {
  return (const tt__embree_id *)(tt__embree_leaf_pk(bvh, ref) +
                                 tt__embree_leaf_pairs(ref) * (2 * TT__EMBREE_SLOT_FLOATS));
}

/* Writes the final hit (or the miss) of a closest-hit query. */
TT__EMBREE_INLINE void tt__embree_finish(const tt__embree_bvh *bvh, const tt__embree_best *best,
                                         tt_ray *ray, tt_hit *hit) {
  if (!best->pk) {
    hit->t = INFINITY;
    hit->u = hit->v = 0.0f;
    hit->geom_id = hit->prim_id = TT_INVALID_ID;
    hit->ng[0] = hit->ng[1] = hit->ng[2] = 0.0f;
    return;
  }
  ray->tfar = best->t;
  hit->t = best->t;
  hit->u = best->u;
  hit->v = best->v;
  hit->geom_id = best->id->geom;
  hit->prim_id = best->id->prim;
  hit->ng[0] = best->pk[9 * best->W + best->lane];
  hit->ng[1] = best->pk[10 * best->W + best->lane];
  hit->ng[2] = best->pk[11 * best->W + best->lane];
}

/* Adds one ray's work to the tree's counters. */
TT__EMBREE_INLINE void tt__embree_count(const tt__embree_bvh *bvh, uint64_t nodes, uint64_t tris) {
  tt__embree_bvh *mut =
      (tt__embree_bvh *)bvh; /* counters are the one mutable part of a built tree */
  atomic_fetch_add_explicit(&mut->c_rays, 1, memory_order_relaxed);
  atomic_fetch_add_explicit(&mut->c_nodes, nodes, memory_order_relaxed);
  atomic_fetch_add_explicit(&mut->c_tris, tris, memory_order_relaxed);
}

/* ---- BVH2 ---- */

/* Box-test constants of a BVH2 node row (lower c0, lower c1, upper c0, upper c1): with
 * a = |1/d|, lanes (a, a, -a, -a) turn the row into (lower - o) * a and -(upper - o) * a,
 * i.e. (near, near, -far, -far) when d >= 0 and (-far, -far, near, near) when d < 0;
 * perm swaps the halves in the second case. After the per-axis permute, the max over
 * the axes and (tnear, tnear, -tfar, -tfar) gives (tmin c0, tmin c1, -tmax c0, -tmax c1):
 * one max op tests both children on all three axes, no per-child min/max. */
typedef struct tt__embree_rc2 {
  __m128 a[3];     /* a * (1, 1, -1, -1) */
  __m128 b[3];     /* FMA, not robust: o * a * (1, 1, -1, -1); otherwise o */
  __m128i perm[3]; /* identity or half swap */
  __m128 lim;      /* (tnear, tnear, -tfar, -tfar) */
} tt__embree_rc2;

TT__EMBREE_INLINE void tt__embree_setup2(tt__embree_rc2 *q, const tt_ray *ray, const int robust) {
  const __m128 pm = _mm_setr_ps(1.0f, 1.0f, -1.0f, -1.0f);
  for (int k = 0; k < 3; k++) {
    float o = ray->org[k], d = ray->dir[k];
    float dk = fabsf(d) < 1e-18f ? copysignf(1e-18f, d) : d;
    float a = fabsf(1.0f / dk);
    q->a[k] = _mm_mul_ps(_mm_set1_ps(a), pm);
#if TT__EMBREE_HAVE_AVX2
    q->b[k] = robust ? _mm_set1_ps(o) : _mm_mul_ps(_mm_set1_ps(o * a), pm);
#else
    (void)robust;
    q->b[k] = _mm_set1_ps(o);
#endif
    int neg = signbit(dk) != 0;
#ifdef __AVX__
    q->perm[k] = neg ? _mm_setr_epi32(2, 3, 0, 1) : _mm_setr_epi32(0, 1, 2, 3);
#else
    q->perm[k] = neg ? _mm_setr_epi8(8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7)
                     : _mm_setr_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
#endif
  }
  q->lim = _mm_setr_ps(ray->tnear, ray->tnear, -ray->tfar, -ray->tfar);
}

TT__EMBREE_INLINE void tt__embree_set_tfar2(tt__embree_rc2 *q, float tnear, float t) {
  q->lim = _mm_setr_ps(tnear, tnear, -t, -t);
}

TT__EMBREE_INLINE __m128 tt__embree_perm2(__m128 v, __m128i p) {
#ifdef __AVX__
  return _mm_permutevar_ps(v, p);
#else
  return _mm_castsi128_ps(_mm_shuffle_epi8(_mm_castps_si128(v), p));
#endif
}

/* Tests both children of a BVH2 node: returns the hit mask (bit c: child c), the entry
 * distances in lanes 0 and 1 of *m. */
TT__EMBREE_INLINE int tt__embree_box2(const tt__embree_node2 *n, const tt__embree_rc2 *q,
                                      const int robust, __m128 *m_out) {
  __m128 t[3];
  for (int k = 0; k < 3; k++) {
    __m128 row = _mm_load_ps(n->b[k]), v;
#if TT__EMBREE_HAVE_AVX2
    if (!robust) v = _mm_fmsub_ps(row, q->a[k], q->b[k]);
    else
#endif
      v = _mm_mul_ps(_mm_sub_ps(row, q->b[k]), q->a[k]);
    t[k] = tt__embree_perm2(v, q->perm[k]);
  }
  __m128 m = _mm_max_ps(_mm_max_ps(t[0], t[1]), t[2]);
  /* robust: tmax * (1 + 2 gamma(3)), i.e. -tmax scaled the same way */
  if (robust)
    m = _mm_mul_ps(m, _mm_setr_ps(1.0f, 1.0f, TT__EMBREE_ROBUST_FAR, TT__EMBREE_ROBUST_FAR));
  m = _mm_max_ps(m, q->lim);
  __m128 tmax = _mm_xor_ps(_mm_movehl_ps(m, m), _mm_set1_ps(-0.0f));
  *m_out = m;
  return _mm_movemask_ps(_mm_cmple_ps(m, tmax)) & 3;
}

/* First line of what a BVH2 reference points at (node or leaf block): one mask, no
 * branch, whatever its kind. */
TT__EMBREE_INLINE const char *tt__embree_line2(const tt__embree_bvh *bvh, uint32_t ref) {
  return (const char *)bvh->arena + ((size_t)(ref & TT__EMBREE_LINE2_MASK) << 6);
}

/* Prefetches the first two lines of what `ref` (a BVH2 child or grand[] hint) points at:
 * an inner node and, by pre-order, its first child; or a leaf's first packet (a 2-wide
 * packet spans 2 lines). Branch-free: one address computation for either kind. */
TT__EMBREE_INLINE void tt__embree_pf2(const tt__embree_bvh *bvh, uint32_t ref) {
  const char *p = tt__embree_line2(bvh, ref);
  _mm_prefetch(p, _MM_HINT_T0);
  _mm_prefetch(p + 64, _MM_HINT_T0);
}

/* Closest hit in a BVH2: the nearer hit child is visited next, the farther one pushed
 * with its entry distance (8-byte entries) and skipped when popped beyond the hit. */
TT__EMBREE_INLINE void tt__embree_intersect2(const tt__embree_bvh *bvh, tt_ray *ray, tt_hit *hit,
                                             const int robust, const int counting) {
  tt__embree_best best = {ray->tfar, 0.0f, 0.0f, NULL, 4, 0, NULL};
  uint64_t c_nodes = 0, c_tris = 0;
  tt__embree_rc r;
  tt__embree_rc2 q;
  uint32_t ref = bvh->root;
  if (ref != TT__EMBREE_REF_NONE && tt__embree_setup(&r, ray, robust)) {
    tt__embree_setup2(&q, ray, robust);
    tt__embree_set_tfar(&r, ray->tfar);
    tt__embree_set_tfar2(&q, ray->tnear, tt__embree_tfar_slack(ray->tfar));
    const float tnear = ray->tnear;
    const char *nodes = (const char *)bvh->arena;
    struct {
      uint32_t ref;
      float dist;
    } stack[TT__EMBREE_MAX_DEPTH2];
    int sp = 0;
    for (;;) {
      while (!(ref & TT__EMBREE_REF_LEAF)) {
        const tt__embree_node2 *n = (const tt__embree_node2 *)(nodes + (size_t)ref * 64u);
        __m128 m;
        int mask = tt__embree_box2(n, &q, robust, &m);
        if (counting) c_nodes++;
        /* Branches, not selects: a predicted branch lets the next node's load start
         * before the box test is done; an index computed from the mask would make
         * every step wait for the whole test. */
        if (mask == 1) {
          ref = n->child[0];
          tt__embree_pf2(bvh, ref);
          tt__embree_pf2(bvh, n->grand[0]);
        } else if (mask == 2) {
          ref = n->child[1];
          tt__embree_pf2(bvh, ref);
          tt__embree_pf2(bvh, n->grand[1]);
        } else if (mask == 3) {
          const float d0 = _mm_cvtss_f32(m), d1 = _mm_cvtss_f32(_mm_movehdup_ps(m));
          if (d1 < d0) {
            stack[sp].ref = n->child[0];
            stack[sp].dist = d0;
            ref = n->child[1];
          } else {
            stack[sp].ref = n->child[1];
            stack[sp].dist = d1;
            ref = n->child[0];
          }
          sp++;
          tt__embree_pf2(bvh, n->child[0]);
          tt__embree_pf2(bvh, n->child[1]);
          tt__embree_pf2(bvh, n->grand[0]);
          tt__embree_pf2(bvh, n->grand[1]);
        } else {
          goto pop;
        }
      }
      {
        const uint32_t pairs = tt__embree_leaf_pairs(ref);
        const float *pk = (const float *)tt__embree_line2(bvh, ref);
        const tt__embree_id *ids =
            (const tt__embree_id *)(pk + pairs * (2 * TT__EMBREE_SLOT_FLOATS));
        if (counting) c_tris += tt__embree_leaf_tris(ids, 2 * pairs);
        if (tt__embree_leaf_closest(pk, ids, pairs, &r, robust, &best))
          tt__embree_set_tfar2(&q, tnear, tt__embree_tfar_slack(best.t));
      }
    pop:
      for (;;) {
        if (sp == 0) goto done;
        --sp;
        if (stack[sp].dist <= tt__embree_tfar_slack(best.t)) break;
      }
      ref = stack[sp].ref;
    }
  }
done:
  if (counting) tt__embree_count(bvh, c_nodes, c_tris);
  tt__embree_finish(bvh, &best, ray, hit);
}

/* Any hit in a BVH2: children in node order, stop at the first hit. */
TT__EMBREE_INLINE int tt__embree_occluded2(const tt__embree_bvh *bvh, const tt_ray *ray,
                                           const int robust, const int counting) {
  uint64_t c_nodes = 0, c_tris = 0;
  int result = 0;
  tt__embree_rc r;
  tt__embree_rc2 q;
  uint32_t ref = bvh->root;
  if (ref != TT__EMBREE_REF_NONE && tt__embree_setup(&r, ray, robust)) {
    tt__embree_setup2(&q, ray, robust);
    const char *nodes = (const char *)bvh->arena;
    uint32_t stack[TT__EMBREE_MAX_DEPTH2];
    int sp = 0;
    for (;;) {
      while (!(ref & TT__EMBREE_REF_LEAF)) {
        const tt__embree_node2 *n = (const tt__embree_node2 *)(nodes + (size_t)ref * 64u);
        __m128 m;
        int mask = tt__embree_box2(n, &q, robust, &m);
        if (counting) c_nodes++;
        if (mask == 1) { /* branches, not selects: see tt__embree_intersect2 */
          ref = n->child[0];
          tt__embree_pf2(bvh, ref);
          tt__embree_pf2(bvh, n->grand[0]);
        } else if (mask == 2) {
          ref = n->child[1];
          tt__embree_pf2(bvh, ref);
          tt__embree_pf2(bvh, n->grand[1]);
        } else if (mask == 3) {
          stack[sp++] = n->child[1];
          ref = n->child[0];
          tt__embree_pf2(bvh, n->child[0]);
          tt__embree_pf2(bvh, n->child[1]);
          tt__embree_pf2(bvh, n->grand[0]);
          tt__embree_pf2(bvh, n->grand[1]);
        } else {
          goto pop;
        }
      }
      {
        const uint32_t pairs = tt__embree_leaf_pairs(ref);
        const float *pk = (const float *)tt__embree_line2(bvh, ref);
        if (counting)
          c_tris += tt__embree_leaf_tris(
              (const tt__embree_id *)(pk + pairs * (2 * TT__EMBREE_SLOT_FLOATS)), 2 * pairs);
        if (tt__embree_leaf_any(pk, pairs, &r, robust)) {
          result = 1;
          goto done;
        }
      }
    pop:
      if (sp == 0) break;
      ref = stack[--sp];
    }
  }
done:
  if (counting) tt__embree_count(bvh, c_nodes, c_tris);
  return result;
}

/* ---- BVH4 / BVH8 ---- */

/* Closest-hit traversal, specialised by width N (4 or 8), robust and counting after
 * inlining. */
TT__EMBREE_INLINE void tt__embree_intersect(const tt__embree_bvh *bvh, tt_ray *ray, tt_hit *hit,
                                            const int N, const int robust, const int counting,
                                            const int ib) {
  tt__embree_best best = {ray->tfar, 0.0f, 0.0f, NULL, 4, 0, NULL};
  uint64_t c_nodes = 0, c_tris = 0;
  tt__embree_rc r;
  uint32_t ref = bvh->root;
  if (ref != TT__EMBREE_REF_NONE && tt__embree_setup(&r, ray, robust)) {
    tt__embree_set_tfar(&r, ray->tfar);
    struct {
      uint32_t ref;
      float dist;
    } stack[TT__EMBREE_STACK];
    int sp = 0;
    /* Zeroed: BVH4 nodes write 4 lanes, the hit ordering reads 8 (and masks the rest). */
    _Alignas(32) float dist[8] = {0};
    for (;;) {
      if (!(ref & TT__EMBREE_REF_LEAF)) {
        const void *node = tt__embree_node_at(bvh, ref, N);
        int mask = tt__embree_node_test(node, &r, N, robust, dist, ib);
        if (counting) c_nodes++;
        if (mask) {
          const uint32_t *child = tt__embree_children(node, N);
          tt__embree_prefetch_children(bvh, child, mask, N);
          if (!(mask & (mask - 1))) {
            /* One hit child: a (predicted) branch per child, not child[ctz(mask)], so
             * the next node's load need not wait for the box test (see tt__embree_intersect2). */
            switch (mask) {
            case 1: ref = child[0]; break;
            case 2: ref = child[1]; break;
            case 4: ref = child[2]; break;
            case 8: ref = child[3]; break;
            case 16: ref = child[N > 4 ? 4 : 0]; break;
            case 32: ref = child[N > 5 ? 5 : 0]; break;
            case 64: ref = child[N > 6 ? 6 : 0]; break;
            default: ref = child[N > 7 ? 7 : 0]; break;
            }
            __asm__("" : "+r"(ref)); /* keep the switch a branch, not a table lookup */
            continue;
          }
          int i0 = __builtin_ctz((unsigned)mask);
          mask &= mask - 1;
          int i1 = __builtin_ctz((unsigned)mask);
          mask &= mask - 1;
          if (!mask) {
            /* Two hits (the common case): go to the nearer, keep the farther. */
            if (dist[i1] < dist[i0]) {
              int t = i0;
              i0 = i1;
              i1 = t;
            }
            stack[sp].ref = child[i1];
            stack[sp].dist = dist[i1];
            sp++;
            ref = child[i0];
            continue;
          }
          /* Three or more: push all, sorted so that the nearest is on top, take it. */
          int base = sp;
#if TT__EMBREE_HAVE_AVX2
          /* Each hit child goes straight to its sorted slot: its rank is the number of
           * hit children that belong below it (farther, or as far and in a lower lane:
           * the order the insertion sort below gives), one 8-wide compare per child.
           * No data-dependent branch: the insertion sort's shifts mispredicted (in a
           * living-room render, ~6% of the BVH8 closest-hit kernel's samples). */
          {
            const unsigned all = (unsigned)mask | 1u << i0 | 1u << i1;
            const __m256 dv = _mm256_load_ps(dist);
            for (unsigned mm = all; mm; mm &= mm - 1) {
              const int i = __builtin_ctz(mm);
              const __m256 di = _mm256_broadcast_ss(&dist[i]);
              const unsigned gt = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(dv, di, _CMP_GT_OQ));
              const unsigned eq = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(dv, di, _CMP_EQ_OQ));
              const int slot = base + __builtin_popcount((gt | (eq & ((1u << i) - 1u))) & all);
              stack[slot].ref = child[i], stack[slot].dist = dist[i];
            }
            sp = base + __builtin_popcount(all);
          }
#else
          stack[sp].ref = child[i0], stack[sp].dist = dist[i0], sp++;
          stack[sp].ref = child[i1], stack[sp].dist = dist[i1], sp++;
          do {
            int i = __builtin_ctz((unsigned)mask);
            mask &= mask - 1;
            stack[sp].ref = child[i], stack[sp].dist = dist[i], sp++;
          } while (mask);
          for (int i = base + 1; i < sp; i++) {
            uint32_t cr = stack[i].ref;
            float cd = stack[i].dist;
            int j = i;
            for (; j > base && stack[j - 1].dist < cd; j--) stack[j] = stack[j - 1];
            stack[j].ref = cr, stack[j].dist = cd;
          }
#endif
          ref = stack[--sp].ref;
          continue;
        }
      } else {
        const uint32_t pairs = tt__embree_leaf_pairs(ref);
        const tt__embree_id *ids = tt__embree_leaf_ids(bvh, ref);
        if (counting) c_tris += tt__embree_leaf_tris(ids, 2 * pairs);
        tt__embree_leaf_closest(tt__embree_leaf_pk(bvh, ref), ids, pairs, &r, robust, &best);
      }
      /* Pop the next entry that can still hold a closer hit (or an equal one). */
      for (;;) {
        if (sp == 0) goto done;
        --sp;
        if (stack[sp].dist <= tt__embree_tfar_slack(best.t)) break;
      }
      ref = stack[sp].ref;
    }
  }
done:
  if (counting) tt__embree_count(bvh, c_nodes, c_tris);
  tt__embree_finish(bvh, &best, ray, hit);
}

/* Any-hit traversal: children in node order (sorting does not pay when the first hit
 * ends the ray), returns at the first triangle inside [tnear, tfar]. */
TT__EMBREE_INLINE int tt__embree_occluded(const tt__embree_bvh *bvh, const tt_ray *ray, const int N,
                                          const int robust, const int counting, const int ib) {
  uint64_t c_nodes = 0, c_tris = 0;
  int result = 0;
  tt__embree_rc r;
  uint32_t ref = bvh->root;
  if (ref != TT__EMBREE_REF_NONE && tt__embree_setup(&r, ray, robust)) {
    uint32_t stack[TT__EMBREE_STACK];
    int sp = 0;
    _Alignas(32) float dist[8];
    for (;;) {
      if (!(ref & TT__EMBREE_REF_LEAF)) {
        const void *node = tt__embree_node_at(bvh, ref, N);
        int mask = tt__embree_node_test(node, &r, N, robust, dist, ib);
        if (counting) c_nodes++;
        if (mask) {
          const uint32_t *child = tt__embree_children(node, N);
          tt__embree_prefetch_children(bvh, child, mask, N);
          ref = child[__builtin_ctz((unsigned)mask)];
          mask &= mask - 1;
          /* The rest pushed from the last lane down, so they are popped in lane order
           * (the builder's layout puts the child a ray most likely hits first). */
          while (mask) {
            const int i = 31 - __builtin_clz((unsigned)mask);
            stack[sp++] = child[i];
            mask &= ~(1 << i);
          }
          continue;
        }
      } else {
        const uint32_t pairs = tt__embree_leaf_pairs(ref);
        if (counting) c_tris += tt__embree_leaf_tris(tt__embree_leaf_ids(bvh, ref), 2 * pairs);
        if (tt__embree_leaf_any(tt__embree_leaf_pk(bvh, ref), pairs, &r, robust)) {
          result = 1;
          goto done;
        }
      }
      if (sp == 0) break;
      ref = stack[--sp];
    }
  }
done:
  if (counting) tt__embree_count(bvh, c_nodes, c_tris);
  return result;
}

/* ---- streams: rays bucketed by octant (direction signs), in chunks of TT__EMBREE_PCHUNK, in
 * stream order within an octant; rays that can hit nothing (non-finite, empty interval) go
 * to the single-ray kernels, which answer them in their setup. ---- */
#define TT__EMBREE_PCHUNK 256

TT__EMBREE_INLINE int tt__embree_ray_octant(const tt_ray *r) {
  for (int k = 0; k < 3; k++)
    if (!isfinite(r->org[k]) || !isfinite(r->dir[k])) return -1;
  if (!(r->tnear <= r->tfar)) return -1;
  int o = 0;
  for (int k = 0; k < 3; k++) {
    float d = r->dir[k];
    float dk = fabsf(d) < 1e-18f ? copysignf(1e-18f, d) : d;
    o |= (signbit(dk) ? 1 : 0) << k;
  }
  return o;
}

/* Buckets rays [base, base + n) by octant into `idx`; returns the bucket ends in `end`.
 * Rays with no octant (invalid) go to bucket 8. */
TT__EMBREE_INLINE void tt__embree_bucket(const tt_ray *rays, size_t base, int n, size_t *idx,
                                         int end[9]) {
  signed char oct[TT__EMBREE_PCHUNK];
  int cnt[9] = {0};
  for (int i = 0; i < n; i++) {
    int o = tt__embree_ray_octant(&rays[base + i]);
    oct[i] = (signed char)(o < 0 ? 8 : o);
    cnt[oct[i]]++;
  }
  int start[9], acc = 0;
  for (int b = 0; b < 9; b++) start[b] = acc, acc += cnt[b], end[b] = acc;
  for (int i = 0; i < n; i++) idx[start[oct[i]]++] = base + (size_t)i;
}

/* ---- occlusion streams: up to 32 rays of one octant walk the tree together ----
 *
 * Shadow rays of a tile start at nearby points, and rays of one octant near the root share
 * most nodes. A group walks the tree once: each entry of the group's stack is a node with
 * the mask of rays that reached it; at a node every ray of the mask gets its own single-ray
 * box test (SIMD over the children, as tt__embree_occluded), and each hit child is pushed with the
 * rays that hit it; at a leaf each ray gets the single-ray any-hit test, and a ray that hits
 * retires from every entry. So a node is fetched (and waited for) once for all the rays
 * that need it, and the per-ray work is the single-ray kernel's: a ray reaches a node
 * exactly when it hit every box above it, and its answer is occluded1's, bit for bit. */
#define TT__EMBREE_OS 32

/* Per-ray box-test constants of a group, one float per ray (broadcast at use): the node's
 * planes are loaded once and every ray of the mask is tested against them. */
typedef struct tt__embree_ogroup {
  _Alignas(32) float rd[3][TT__EMBREE_OS];
  _Alignas(32) float ob[3][TT__EMBREE_OS]; /* FMA kernels: o * rd; otherwise o */
  _Alignas(32) float tnear[TT__EMBREE_OS], tfar[TT__EMBREE_OS];
} tt__embree_ogroup;

#if TT__EMBREE_HAVE_AVX2
typedef __m256 tt__embree_gv; /* up to 8 children */
#  define TT__EMBREE_GLOAD(p, N)                                                                   \
    ((N) == 8 ? _mm256_load_ps(p)                                                                  \
              : _mm256_castps128_ps256(                                                            \
                    (N) == 4 ? _mm_load_ps(p) : _mm_castpd_ps(_mm_load_sd((const double *)(p)))))
#  define TT__EMBREE_GSET1(x) _mm256_set1_ps(x)
#  define TT__EMBREE_GSUB _mm256_sub_ps
#  define TT__EMBREE_GMUL _mm256_mul_ps
#  define TT__EMBREE_GMAX _mm256_max_ps
#  define TT__EMBREE_GMIN _mm256_min_ps
#  define TT__EMBREE_GFMSUB _mm256_fmsub_ps
#  define TT__EMBREE_GLE(a, b) _mm256_cmp_ps(a, b, _CMP_LE_OQ)
#  define TT__EMBREE_GMASK _mm256_movemask_ps
#  define TT__EMBREE_GOR _mm256_or_ps
#  define TT__EMBREE_GAND _mm256_and_ps
#  define TT__EMBREE_GZERO _mm256_setzero_ps()
#  define TT__EMBREE_GBITS(x) _mm256_castsi256_ps(_mm256_set1_epi32((int)(x)))
#  define TT__EMBREE_GI(v) _mm256_castps_si256(v)
#  define TT__EMBREE_GF(v) _mm256_castsi256_ps(v)
#  define TT__EMBREE_GIMAX(a, b) TT__EMBREE_GF(_mm256_max_epi32(TT__EMBREE_GI(a), TT__EMBREE_GI(b)))
#  define TT__EMBREE_GIMIN(a, b) TT__EMBREE_GF(_mm256_min_epi32(TT__EMBREE_GI(a), TT__EMBREE_GI(b)))
#  define TT__EMBREE_GIGT(a, b)                                                                    \
    TT__EMBREE_GF(_mm256_cmpgt_epi32(TT__EMBREE_GI(a), TT__EMBREE_GI(b)))
#  define TT__EMBREE_GANDNOT _mm256_andnot_ps
#else
typedef __m128 tt__embree_gv; /* up to 4 children (BVH8: two halves) */
#  define TT__EMBREE_GLOAD(p, N)                                                                   \
    ((N) >= 4 ? _mm_load_ps(p) : _mm_castpd_ps(_mm_load_sd((const double *)(p))))
#  define TT__EMBREE_GSET1(x) _mm_set1_ps(x)
#  define TT__EMBREE_GSUB _mm_sub_ps
#  define TT__EMBREE_GMUL _mm_mul_ps
#  define TT__EMBREE_GMAX _mm_max_ps
#  define TT__EMBREE_GMIN _mm_min_ps
#  define TT__EMBREE_GLE(a, b) _mm_cmple_ps(a, b)
#  define TT__EMBREE_GMASK _mm_movemask_ps
#  define TT__EMBREE_GOR _mm_or_ps
#  define TT__EMBREE_GAND _mm_and_ps
#  define TT__EMBREE_GZERO _mm_setzero_ps()
#  define TT__EMBREE_GBITS(x) _mm_castsi128_ps(_mm_set1_epi32((int)(x)))
#  define TT__EMBREE_GIMAX TT__EMBREE_IMAX4
#  define TT__EMBREE_GIMIN TT__EMBREE_IMIN4
#  define TT__EMBREE_GIGT(a, b)                                                                    \
    _mm_castsi128_ps(_mm_cmpgt_epi32(_mm_castps_si128(a), _mm_castps_si128(b)))
#  define TT__EMBREE_GANDNOT _mm_andnot_ps
#endif

/* Rays of `m` against up to G children whose near/far planes per axis are `bn`/`bf`: for
 * each child the mask of rays that hit it (as floats' bits), with the single-ray kernels'
 * arithmetic per ray (FMA where they use it, the robust far scale where they use it; `ib`:
 * integer max/min as tt__embree_box8, when every ray of the group has tnear >= 0). */
TT__EMBREE_INLINE tt__embree_gv tt__embree_ogroup_test(const tt__embree_ogroup *g, uint32_t m,
                                                       const tt__embree_gv bn[3],
                                                       const tt__embree_gv bf[3], const int robust,
                                                       const int ib) {
  tt__embree_gv acc = TT__EMBREE_GZERO;
  for (; m; m &= m - 1) {
    const int i = __builtin_ctz(m);
    tt__embree_gv tn[3], tf[3];
    for (int k = 0; k < 3; k++) {
      const tt__embree_gv rd = TT__EMBREE_GSET1(g->rd[k][i]), ob = TT__EMBREE_GSET1(g->ob[k][i]);
#if TT__EMBREE_HAVE_AVX2
      if (!robust) {
        tn[k] = TT__EMBREE_GFMSUB(bn[k], rd, ob);
        tf[k] = TT__EMBREE_GFMSUB(bf[k], rd, ob);
        continue;
      }
#endif
      tn[k] = TT__EMBREE_GMUL(TT__EMBREE_GSUB(bn[k], ob), rd);
      tf[k] = TT__EMBREE_GMUL(TT__EMBREE_GSUB(bf[k], ob), rd);
    }
    if (ib && !robust) {
      tt__embree_gv tmin = TT__EMBREE_GIMAX(TT__EMBREE_GIMAX(tn[0], tn[1]),
                                            TT__EMBREE_GIMAX(tn[2], TT__EMBREE_GSET1(g->tnear[i])));
      tt__embree_gv tmax = TT__EMBREE_GIMIN(TT__EMBREE_GIMIN(tf[0], tf[1]),
                                            TT__EMBREE_GIMIN(tf[2], TT__EMBREE_GSET1(g->tfar[i])));
      acc = TT__EMBREE_GOR(
          acc, TT__EMBREE_GANDNOT(TT__EMBREE_GIGT(tmin, tmax), TT__EMBREE_GBITS(1u << i)));
      continue;
    }
    tt__embree_gv tmin = TT__EMBREE_GMAX(TT__EMBREE_GMAX(tn[0], tn[1]),
                                         TT__EMBREE_GMAX(tn[2], TT__EMBREE_GSET1(g->tnear[i])));
    tt__embree_gv tmax = TT__EMBREE_GMIN(TT__EMBREE_GMIN(tf[0], tf[1]), tf[2]);
    if (robust) tmax = TT__EMBREE_GMUL(tmax, TT__EMBREE_GSET1(TT__EMBREE_ROBUST_FAR));
    tmax = TT__EMBREE_GMIN(tmax, TT__EMBREE_GSET1(g->tfar[i]));
    acc =
        TT__EMBREE_GOR(acc, TT__EMBREE_GAND(TT__EMBREE_GLE(tmin, tmax), TT__EMBREE_GBITS(1u << i)));
  }
  return acc;
}

/* Loads a node's near/far planes for the group's octant (lanes = children; BVH2: 2). */
TT__EMBREE_INLINE void tt__embree_ogroup_planes(const void *node, const int near[3], const int N,
                                                int half, tt__embree_gv bn[3],
                                                tt__embree_gv bf[3]) {
  for (int k = 0; k < 3; k++) {
    const int neg = near[k] & 1;
    if (N == 2) { /* row k: lower c0, lower c1, upper c0, upper c1 */
      const float *row = ((const tt__embree_node2 *)node)->b[k];
      bn[k] = TT__EMBREE_GLOAD(row + 2 * neg, 2);
      bf[k] = TT__EMBREE_GLOAD(row + 2 * (neg ^ 1), 2);
    } else {
      const float *rows = node;
      const int w = N > 4 && !TT__EMBREE_HAVE_AVX2 ? 4 : N; /* SSE: BVH8 rows in two halves */
      bn[k] = TT__EMBREE_GLOAD(rows + (size_t)near[k] * N + 4 * half, w);
      bf[k] = TT__EMBREE_GLOAD(rows + (size_t)(near[k] ^ 1) * N + 4 * half, w);
    }
  }
}

TT__EMBREE_INLINE void tt__embree_ostream_group(const tt__embree_bvh *bvh, const tt_ray *rays,
                                                const size_t *idx, int n, uint8_t *occ, const int N,
                                                const int robust, const int counting,
                                                const int ib) {
  tt__embree_rc r[TT__EMBREE_OS];
  tt__embree_ogroup g;
  uint64_t c_nodes[TT__EMBREE_OS], c_tris[TT__EMBREE_OS];
  uint32_t live = 0, done = 0;
  int near[3] = {0, 2, 4};
  for (int i = 0; i < n; i++) {
    c_nodes[i] = c_tris[i] = 0;
    if (bvh->root != TT__EMBREE_REF_NONE && tt__embree_setup(&r[i], &rays[idx[i]], robust)) {
      live |= 1u << i;
      for (int k = 0; k < 3; k++) {
        /* the group shares the octant: every ray's near rows are these */
        near[k] = r[i].near[k];
        const float rd = _mm_cvtss_f32(TT__EMBREE_V4(r[i].rd[k]));
        g.rd[k][i] = rd;
#if TT__EMBREE_HAVE_AVX2
        g.ob[k][i] = robust ? rays[idx[i]].org[k] : _mm_cvtss_f32(TT__EMBREE_V4(r[i].ord[k]));
#else
        g.ob[k][i] = rays[idx[i]].org[k];
#endif
      }
      g.tnear[i] = rays[idx[i]].tnear + 0.0f; /* -0 -> +0, as tt__embree_setup */
      g.tfar[i] = rays[idx[i]].tfar;
    } else {
      occ[idx[i]] = 0;
    }
  }
  struct {
    uint32_t ref, mask;
  } stack[TT__EMBREE_STACK];
  int sp = 0;
  uint32_t ref = bvh->root, m = live;
  if (!live) goto out;
  for (;;) {
    while (!(ref & TT__EMBREE_REF_LEAF)) {
      const void *node =
          N == 2 ? (const void *)tt__embree_line2(bvh, ref) : tt__embree_node_at(bvh, ref, N);
      _Alignas(32) uint32_t cm[8];
      tt__embree_gv bn[3], bf[3];
      tt__embree_ogroup_planes(node, near, N, 0, bn, bf);
#if TT__EMBREE_HAVE_AVX2
      _mm256_store_ps((float *)cm, tt__embree_ogroup_test(&g, m, bn, bf, robust, ib));
#else
      _mm_store_ps((float *)cm, tt__embree_ogroup_test(&g, m, bn, bf, robust, ib));
      if (N == 8) {
        tt__embree_ogroup_planes(node, near, N, 1, bn, bf);
        _mm_store_ps((float *)cm + 4, tt__embree_ogroup_test(&g, m, bn, bf, robust, ib));
      }
#endif
      if (counting)
        for (uint32_t mm = m; mm; mm &= mm - 1) c_nodes[__builtin_ctz(mm)]++;
      const uint32_t *child =
          N == 2 ? ((const tt__embree_node2 *)node)->child : tt__embree_children(node, N);
      int first = -1;
      for (int c = N - 1; c >= 0; c--) { /* pushed last lane first: lane order is visit order */
        if (!cm[c]) continue;
        if (first >= 0) {
          stack[sp].ref = child[first], stack[sp].mask = cm[first], sp++;
        }
        first = c;
        if (N == 2) tt__embree_pf2(bvh, child[c]);
        else tt__embree_prefetch(bvh, child[c], N);
      }
      if (first < 0) goto pop;
      ref = child[first], m = cm[first];
    }
    {
      const uint32_t pairs = tt__embree_leaf_pairs(ref);
      const float *pk = tt__embree_leaf_pk(bvh, ref);
      for (uint32_t mm = m; mm; mm &= mm - 1) {
        const int i = __builtin_ctz(mm);
        if (counting) c_tris[i] += tt__embree_leaf_tris(tt__embree_leaf_ids(bvh, ref), 2 * pairs);
        if (tt__embree_leaf_any(pk, pairs, &r[i], robust)) done |= 1u << i;
      }
      if (done == live) goto out;
    }
  pop:
    for (;;) {
      if (sp == 0) goto out;
      --sp;
      m = stack[sp].mask & ~done;
      if (m) {
        ref = stack[sp].ref;
        break;
      }
    }
  }
out:
  for (int i = 0; i < n; i++)
    if (live >> i & 1) {
      occ[idx[i]] = (uint8_t)(done >> i & 1);
      if (counting) tt__embree_count(bvh, c_nodes[i], c_tris[i]);
    }
}

/* Occlusion of a stream in octant groups of up to TT__EMBREE_OS rays. */
TT__EMBREE_INLINE void tt__embree_ostream(const tt__embree_bvh *bvh, const tt_ray *rays,
                                          uint8_t *occ, size_t count, const int N, const int robust,
                                          const int counting, tt__embree_occl_fn single) {
  size_t idx[TT__EMBREE_PCHUNK];
  for (size_t base = 0; base < count; base += TT__EMBREE_PCHUNK) {
    const int n = (int)(count - base < TT__EMBREE_PCHUNK ? count - base : TT__EMBREE_PCHUNK);
    int end[9];
    tt__embree_bucket(rays, base, n, idx, end);
    for (int i = end[7]; i < end[8]; i++) occ[idx[i]] = (uint8_t)single(bvh, &rays[idx[i]]);
    for (int b = 0, first = 0; b < 8; first = end[b], b++)
      for (int i = first; i < end[b]; i += TT__EMBREE_OS) {
        const int m = end[b] - i < TT__EMBREE_OS ? end[b] - i : TT__EMBREE_OS;
        if (m == 1) {
          occ[idx[i]] = (uint8_t)single(bvh, &rays[idx[i]]);
          continue;
        }
        int ib = !robust; /* integer box tests when every ray has tnear >= 0 */
        for (int j = 0; j < m && ib; j++) ib = tt__embree_ray_ibox(&rays[idx[i + j]], robust);
        if (ib) tt__embree_ostream_group(bvh, rays, idx + i, m, occ, N, robust, counting, 1);
        else tt__embree_ostream_group(bvh, rays, idx + i, m, occ, N, robust, counting, 0);
      }
  }
}

/* ---- packets: 8 rays of one octant traverse together (AVX2 and AVX-512 builds) ----
 *
 * Rays that start close together and point the same way (camera rays, shadow rays from a
 * tile toward a light) visit nearly the same nodes. A packet of 8 such rays fetches each
 * node once and tests it against all of them with 8-wide operations (one SIMD lane per
 * ray), so the node's load and the loop around it are paid once for 8 rays. All rays of a
 * packet share the octant (direction signs), hence the near/far plane of every axis.
 *
 * Per ray, the box and triangle tests are the single-ray kernels' arithmetic operation by
 * operation (same formulas, same order, FMA exactly where they use it), and a lane enters a
 * node only when its ray hit every box on the way down, as in single-ray traversal; so
 * occlusion answers are identical, and so are closest hits (exact ties go to the smaller ids
 * in both, tt__embree_id_less), except where two triangles are hit at distances within rounding
 * of each other but not equal and rounding of a box test culls one of them in one order
 * of visit and not in the other (never seen on the bench's scenes). The robust (watertight) and counting kernels have no packet form:
 * their streams run the single-ray kernels. */
#if TT__EMBREE_HAVE_AVX2
#  define TT__EMBREE_K 8
#  define TT__EMBREE_PSTACK (TT__EMBREE_STACK + 8)

typedef struct tt__embree_pkt {
  __m256 o[3], d[3], rd[3], ord[3];
  __m256 tnear, tfar;         /* tfar: each lane's closest hit so far */
  __m256 tfar_s;              /* tt__embree_tfar_slack(tfar), lane by lane */
  int near[3];                /* near-plane row per axis: 2k + sign (the packet's octant) */
  int n;                      /* lanes holding a ray (the rest never hit anything) */
  size_t index[TT__EMBREE_K]; /* the lanes' positions in the stream */
  /* closest hit per lane, as tt__embree_best */
  float u[TT__EMBREE_K], v[TT__EMBREE_K];
  const float *pk[TT__EMBREE_K];
  int W[TT__EMBREE_K], lane[TT__EMBREE_K];
  const tt__embree_id *id[TT__EMBREE_K];
} tt__embree_pkt;

/* tt__embree_tfar_slack lane by lane (-inf, an empty lane, gives NaN: no test passes). */
TT__EMBREE_INLINE __m256 tt__embree_ptfar_slack(__m256 t) {
  const __m256 abs = _mm256_andnot_ps(_mm256_set1_ps(-0.0f), t);
  return _mm256_add_ps(t, _mm256_mul_ps(abs, _mm256_set1_ps(0x1p-20f)));
}

/* Loads `n` rays (indices idx[0..n), all finite with tnear <= tfar and direction signs
 * `octant`) into a packet, with tt__embree_setup's constants lane by lane. */
TT__EMBREE_INLINE void tt__embree_pkt_setup(tt__embree_pkt *P, const tt_ray *rays,
                                            const size_t *idx, int n, int octant) {
  _Alignas(32) float v[14][TT__EMBREE_K];
  for (int l = 0; l < TT__EMBREE_K; l++) {
    if (l < n) {
      const tt_ray *ray = &rays[idx[l]];
      for (int k = 0; k < 3; k++) {
        float o = ray->org[k], d = ray->dir[k];
        float dk = fabsf(d) < 1e-18f ? copysignf(1e-18f, d) : d;
        float rk = 1.0f / dk;
        v[k][l] = o, v[3 + k][l] = d, v[6 + k][l] = rk, v[9 + k][l] = o * rk;
      }
      v[12][l] = ray->tnear, v[13][l] = ray->tfar;
      P->index[l] = idx[l];
    } else { /* empty lane: an interval no box or triangle passes */
      for (int k = 0; k < 12; k++) v[k][l] = 0.0f;
      for (int k = 6; k < 9; k++) v[k][l] = 1.0f;
      v[12][l] = INFINITY, v[13][l] = -INFINITY;
      P->index[l] = 0;
    }
    P->pk[l] = NULL;
    P->u[l] = P->v[l] = 0.0f;
  }
  for (int k = 0; k < 3; k++) {
    P->o[k] = _mm256_load_ps(v[k]);
    P->d[k] = _mm256_load_ps(v[3 + k]);
    P->rd[k] = _mm256_load_ps(v[6 + k]);
    P->ord[k] = _mm256_load_ps(v[9 + k]);
    P->near[k] = 2 * k + ((octant >> k) & 1);
  }
  P->tnear = _mm256_load_ps(v[12]);
  P->tfar = _mm256_load_ps(v[13]);
  P->tfar_s = tt__embree_ptfar_slack(P->tfar);
  P->n = n;
}

/* One child box (near/far plane values per axis for the packet's octant) against the
 * packet: entry distances, +inf where a lane misses (or is not in `lanes`). As tt__embree_box8. */
TT__EMBREE_INLINE __m256 tt__embree_pbox(const float *pn[3], const float *pf[3],
                                         const tt__embree_pkt *P, __m256 lanes, __m256 tfar) {
  __m256 tn[3], tf[3];
  for (int k = 0; k < 3; k++) {
    tn[k] = _mm256_fmsub_ps(_mm256_broadcast_ss(pn[k]), P->rd[k], P->ord[k]);
    tf[k] = _mm256_fmsub_ps(_mm256_broadcast_ss(pf[k]), P->rd[k], P->ord[k]);
  }
  __m256 tmin = _mm256_max_ps(_mm256_max_ps(tn[0], tn[1]), _mm256_max_ps(tn[2], P->tnear));
  __m256 tmax = _mm256_min_ps(_mm256_min_ps(tf[0], tf[1]), tf[2]);
  tmax = _mm256_min_ps(tmax, tfar);
  __m256 hit = _mm256_and_ps(_mm256_cmp_ps(tmin, tmax, _CMP_LE_OQ), lanes);
  return _mm256_blendv_ps(_mm256_set1_ps(INFINITY), tmin, hit);
}

/* Entry distances of child c of a width-N node for the packet (+inf: missed). */
TT__EMBREE_INLINE __m256 tt__embree_pchild(const void *node, int c, const tt__embree_pkt *P, int N,
                                           __m256 lanes, const int closest) {
  const float *pn[3], *pf[3];
  if (N == 2) {
    const tt__embree_node2 *n = node; /* row k: lower c0, lower c1, upper c0, upper c1 */
    for (int k = 0; k < 3; k++) {
      const int neg = P->near[k] & 1;
      pn[k] = &n->b[k][c + 2 * neg];
      pf[k] = &n->b[k][c + 2 * (neg ^ 1)];
    }
  } else {
    const float *rows = node;
    for (int k = 0; k < 3; k++) {
      pn[k] = rows + (size_t)P->near[k] * N + c;
      pf[k] = rows + (size_t)(P->near[k] ^ 1) * N + c;
    }
  }
  return tt__embree_pbox(pn, pf, P, lanes, closest ? P->tfar_s : P->tfar);
}

/* Children references of a node (BVH2 nodes keep them after their three rows). */
TT__EMBREE_INLINE const uint32_t *tt__embree_pchildren(const void *node, int N) {
  return N == 2 ? ((const tt__embree_node2 *)node)->child : tt__embree_children(node, N);
}

TT__EMBREE_INLINE const void *tt__embree_pnode(const tt__embree_bvh *bvh, uint32_t ref, int N) {
  return N == 2 ? (const void *)tt__embree_line2(bvh, ref) : tt__embree_node_at(bvh, ref, N);
}

/* Prefetch of a child about to be visited or pushed. */
TT__EMBREE_INLINE void tt__embree_pprefetch(const tt__embree_bvh *bvh, const void *node, int c,
                                            int N) {
  if (N == 2) {
    const tt__embree_node2 *n = node;
    tt__embree_pf2(bvh, n->child[c]);
    tt__embree_pf2(bvh, n->grand[c]);
  } else {
    tt__embree_prefetch(bvh, tt__embree_children(node, N)[c], N);
  }
}

/* Triangle j of a width-W slot packet against every lane: T, U, V, |det| and validity, as
 * tt__embree_tri_test computes them for one ray (non-robust). */
TT__EMBREE_INLINE __m256 tt__embree_ptri(const float *pk, int W, int j, const tt__embree_pkt *P,
                                         __m256 lanes, const int closest, __m256 *T_out,
                                         __m256 *U_out, __m256 *V_out, __m256 *den_out) {
  const __m256 sign = _mm256_set1_ps(-0.0f), zero = _mm256_setzero_ps();
#  define TT__EMBREE_R(r) _mm256_broadcast_ss(pk + (r)*W + j)
  __m256 cx = _mm256_sub_ps(TT__EMBREE_R(0), P->o[0]);
  __m256 cy = _mm256_sub_ps(TT__EMBREE_R(1), P->o[1]);
  __m256 cz = _mm256_sub_ps(TT__EMBREE_R(2), P->o[2]);
  /* tt__embree_tri_test's FMA forms, lane by lane */
  __m256 rx = _mm256_fmsub_ps(cy, P->d[2], _mm256_mul_ps(cz, P->d[1]));
  __m256 ry = _mm256_fmsub_ps(cz, P->d[0], _mm256_mul_ps(cx, P->d[2]));
  __m256 rz = _mm256_fmsub_ps(cx, P->d[1], _mm256_mul_ps(cy, P->d[0]));
  __m256 nx = TT__EMBREE_R(9), ny = TT__EMBREE_R(10), nz = TT__EMBREE_R(11);
  __m256 den =
      _mm256_fmadd_ps(nx, P->d[0], _mm256_fmadd_ps(ny, P->d[1], _mm256_mul_ps(nz, P->d[2])));
  __m256 sgn = _mm256_and_ps(den, sign);
  __m256 absden = _mm256_xor_ps(den, sgn);
  __m256 U = _mm256_xor_ps(
      _mm256_fmadd_ps(rx, TT__EMBREE_R(6),
                      _mm256_fmadd_ps(ry, TT__EMBREE_R(7), _mm256_mul_ps(rz, TT__EMBREE_R(8)))),
      sgn);
  __m256 V = _mm256_xor_ps(
      _mm256_fmadd_ps(rx, TT__EMBREE_R(3),
                      _mm256_fmadd_ps(ry, TT__EMBREE_R(4), _mm256_mul_ps(rz, TT__EMBREE_R(5)))),
      sgn);
  __m256 valid =
      _mm256_and_ps(_mm256_cmp_ps(U, zero, _CMP_GE_OQ), _mm256_cmp_ps(V, zero, _CMP_GE_OQ));
  valid = _mm256_and_ps(valid, _mm256_cmp_ps(_mm256_add_ps(U, V), absden, _CMP_LE_OQ));
  valid = _mm256_and_ps(valid, _mm256_cmp_ps(absden, zero, _CMP_GT_OQ));
  valid = _mm256_and_ps(valid, lanes);
  __m256 T =
      _mm256_xor_ps(_mm256_fmadd_ps(nx, cx, _mm256_fmadd_ps(ny, cy, _mm256_mul_ps(nz, cz))), sgn);
#  undef TT__EMBREE_R
  valid = _mm256_and_ps(valid, _mm256_cmp_ps(T, _mm256_mul_ps(absden, P->tnear), _CMP_GE_OQ));
  valid = _mm256_and_ps(
      valid, _mm256_cmp_ps(T, _mm256_mul_ps(absden, closest ? P->tfar_s : P->tfar), _CMP_LE_OQ));
  *T_out = T, *U_out = U, *V_out = V, *den_out = absden;
  return valid;
}

/* One slot packet of a leaf for a closer hit, lane by lane as tt__embree_leaf_packet: the nearest
 * valid triangle wins if closer than the lane's hit so far, or as far with smaller ids. */
TT__EMBREE_INLINE void tt__embree_pleaf_packet(const float *pk, const int W,
                                               const tt__embree_id *ids, tt__embree_pkt *P,
                                               __m256 lanes) {
  _Alignas(32) float tv[4][TT__EMBREE_K], U[4][TT__EMBREE_K], V[4][TT__EMBREE_K],
      D[4][TT__EMBREE_K];
  __m256 any = _mm256_setzero_ps(), mn = _mm256_set1_ps(INFINITY);
  for (int j = 0; j < W; j++) {
    __m256 T, u, v, den;
    __m256 valid = tt__embree_ptri(pk, W, j, P, lanes, 1, &T, &u, &v, &den);
    __m256 t = _mm256_blendv_ps(_mm256_set1_ps(INFINITY), _mm256_div_ps(T, den), valid);
    _mm256_store_ps(tv[j], t);
    _mm256_store_ps(U[j], u);
    _mm256_store_ps(V[j], v);
    _mm256_store_ps(D[j], den);
    mn = _mm256_min_ps(mn, t);
    any = _mm256_or_ps(any, valid);
  }
  int acc = _mm256_movemask_ps(_mm256_and_ps(any, _mm256_cmp_ps(mn, P->tfar, _CMP_LE_OQ)));
  if (!acc) return;
  _Alignas(32) float m8[TT__EMBREE_K], f8[TT__EMBREE_K];
  _mm256_store_ps(m8, mn);
  _mm256_store_ps(f8, P->tfar);
  for (; acc; acc &= acc - 1) {
    const int l = __builtin_ctz((unsigned)acc);
    int j = 0; /* the nearest triangle; on a tie the smaller ids, as tt__embree_leaf_packet */
    while (j < W - 1 && tv[j][l] != m8[l]) j++;
    for (int k = j + 1; k < W; k++)
      if (tv[k][l] == m8[l] && tt__embree_id_less(&ids[k], &ids[j])) j = k;
    if (m8[l] == f8[l] && P->pk[l] && !tt__embree_id_less(&ids[j], P->id[l])) continue;
    P->u[l] = U[j][l] / D[j][l];
    P->v[l] = V[j][l] / D[j][l];
    P->pk[l] = pk;
    P->W[l] = W;
    P->lane[l] = j;
    P->id[l] = ids + j;
  }
  P->tfar =
      _mm256_blendv_ps(P->tfar, mn, _mm256_and_ps(any, _mm256_cmp_ps(mn, P->tfar, _CMP_LE_OQ)));
  P->tfar_s = tt__embree_ptfar_slack(P->tfar);
}

/* Lanes of a packet that enter a subtree with entry distances `d`: those that hit its box
 * (a finite distance; +inf marks a lane that missed it) no farther than their closest hit
 * so far. `d <= tfar` alone is not enough: a lane with no hit yet has tfar = +inf, and
 * +inf <= +inf would let it into every box the packet visits, including boxes its ray
 * missed, where a triangle test can accept a hit within rounding of an edge that
 * intersect1 never tests (found on the voxel monument: a different, nearer triangle). */
TT__EMBREE_INLINE __m256 tt__embree_plive(__m256 d, __m256 tfar) {
  return _mm256_and_ps(_mm256_cmp_ps(d, tfar, _CMP_LE_OQ),
                       _mm256_cmp_ps(d, _mm256_set1_ps(INFINITY), _CMP_LT_OQ));
}

/* Closest hits of one packet in a width-N tree (non-robust). Stack entries carry each
 * lane's entry distance; a popped entry continues with the lanes it can still improve. */
TT__EMBREE_INLINE void tt__embree_pintersect(const tt__embree_bvh *bvh, tt__embree_pkt *P,
                                             const int N) {
  uint32_t sref[TT__EMBREE_PSTACK];
  _Alignas(32) float sdist[TT__EMBREE_PSTACK][TT__EMBREE_K];
  int sp = 0;
  uint32_t ref = bvh->root;
  __m256 cur = P->tnear; /* lanes in this subtree: entry distance, +inf if not */
  for (;;) {
    __m256 lanes = tt__embree_plive(cur, P->tfar_s);
    if (!(ref & TT__EMBREE_REF_LEAF)) {
      const void *node = tt__embree_pnode(bvh, ref, N);
      const uint32_t *child = tt__embree_pchildren(node, N);
      uint32_t next = TT__EMBREE_REF_NONE;
      __m256 nextd = cur;
      for (int c = 0; c < N; c++) {
        __m256 dc = tt__embree_pchild(node, c, P, N, lanes, 1);
        __m256 hit = _mm256_cmp_ps(dc, _mm256_set1_ps(INFINITY), _CMP_LT_OQ);
        if (!_mm256_movemask_ps(hit)) continue;
        tt__embree_pprefetch(bvh, node, c, N);
        if (next == TT__EMBREE_REF_NONE) {
          next = child[c], nextd = dc;
        } else if (_mm256_movemask_ps(_mm256_cmp_ps(dc, nextd, _CMP_LT_OQ))) {
          sref[sp] = next; /* the new child is nearer for some lane: visit it first */
          _mm256_store_ps(sdist[sp], nextd);
          sp++;
          next = child[c], nextd = dc;
        } else {
          sref[sp] = child[c];
          _mm256_store_ps(sdist[sp], dc);
          sp++;
        }
      }
      if (next != TT__EMBREE_REF_NONE) {
        ref = next, cur = nextd;
        continue;
      }
    } else {
      const uint32_t pairs = tt__embree_leaf_pairs(ref);
      const float *pk;
      const tt__embree_id *ids;
      if (N == 2) {
        pk = (const float *)tt__embree_line2(bvh, ref);
        ids = (const tt__embree_id *)(pk + pairs * (2 * TT__EMBREE_SLOT_FLOATS));
      } else {
        pk = tt__embree_leaf_pk(bvh, ref);
        ids = tt__embree_leaf_ids(bvh, ref);
      }
      uint32_t q = 0;
      for (; q + 1 < pairs; q += 2, pk += 4 * TT__EMBREE_SLOT_FLOATS)
        tt__embree_pleaf_packet(pk, 4, ids + 2 * q, P, lanes);
      if (q < pairs) tt__embree_pleaf_packet(pk, 2, ids + 2 * q, P, lanes);
    }
    for (;;) { /* pop the next entry some lane can still improve on */
      if (sp == 0) return;
      --sp;
      __m256 d = _mm256_load_ps(sdist[sp]);
      if (_mm256_movemask_ps(tt__embree_plive(d, P->tfar_s))) {
        ref = sref[sp], cur = d;
        break;
      }
    }
  }
}

/* Occlusion of one packet: children in lane order, a lane retires at its first hit. */
TT__EMBREE_INLINE int tt__embree_poccluded(const tt__embree_bvh *bvh, const tt__embree_pkt *P,
                                           const int N) {
  uint32_t sref[TT__EMBREE_PSTACK];
  int smask[TT__EMBREE_PSTACK];
  int sp = 0;
  const int all = (1 << P->n) - 1;
  int done = 0;
  uint32_t ref = bvh->root;
  int lanes = all;
  for (;;) {
    if (!(ref & TT__EMBREE_REF_LEAF)) {
      const void *node = tt__embree_pnode(bvh, ref, N);
      const uint32_t *child = tt__embree_pchildren(node, N);
      const __m256 lv = _mm256_castsi256_ps(
          _mm256_cmpgt_epi32(_mm256_and_si256(_mm256_set1_epi32(lanes),
                                              _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128)),
                             _mm256_setzero_si256()));
      uint32_t next = TT__EMBREE_REF_NONE;
      int nextm = 0;
      for (int c = N - 1; c >= 0; c--) { /* pushed last to first: lane order is visit order */
        __m256 dc = tt__embree_pchild(node, c, P, N, lv, 0);
        int m = _mm256_movemask_ps(_mm256_cmp_ps(dc, _mm256_set1_ps(INFINITY), _CMP_LT_OQ));
        if (!m) continue;
        tt__embree_pprefetch(bvh, node, c, N);
        if (next != TT__EMBREE_REF_NONE) {
          sref[sp] = next, smask[sp] = nextm;
          sp++;
        }
        next = child[c], nextm = m;
      }
      if (next != TT__EMBREE_REF_NONE) {
        ref = next, lanes = nextm;
        continue;
      }
    } else {
      const uint32_t pairs = tt__embree_leaf_pairs(ref);
      const float *pk =
          N == 2 ? (const float *)tt__embree_line2(bvh, ref) : tt__embree_leaf_pk(bvh, ref);
      const __m256 lv = _mm256_castsi256_ps(
          _mm256_cmpgt_epi32(_mm256_and_si256(_mm256_set1_epi32(lanes),
                                              _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128)),
                             _mm256_setzero_si256()));
      __m256 hitv = _mm256_setzero_ps();
      uint32_t q = 0;
      for (; q < pairs; q += 2, pk += 4 * TT__EMBREE_SLOT_FLOATS) {
        const int W = q + 1 < pairs ? 4 : 2;
        for (int j = 0; j < W; j++) {
          __m256 T, U, V, den;
          hitv = _mm256_or_ps(hitv, tt__embree_ptri(pk, W, j, P, lv, 0, &T, &U, &V, &den));
        }
      }
      done |= _mm256_movemask_ps(hitv);
      if (done == all) return done;
    }
    for (;;) {
      if (sp == 0) return done;
      --sp;
      lanes = smask[sp] & ~done;
      if (lanes) {
        ref = sref[sp];
        break;
      }
    }
  }
}

/* Streams through packets: see tt__embree_bucket (octants) above the packet section. */
TT__EMBREE_INLINE void tt__embree_pintersect_stream(const tt__embree_bvh *bvh, tt_ray *rays,
                                                    tt_hit *hits, size_t count, const int N,
                                                    tt__embree_isect_fn single) {
  size_t idx[TT__EMBREE_PCHUNK];
  for (size_t base = 0; base < count; base += TT__EMBREE_PCHUNK) {
    const int n = (int)(count - base < TT__EMBREE_PCHUNK ? count - base : TT__EMBREE_PCHUNK);
    int end[9];
    tt__embree_bucket(rays, base, n, idx, end);
    for (int i = end[7]; i < end[8]; i++) single(bvh, &rays[idx[i]], &hits[idx[i]]);
    for (int b = 0, first = 0; b < 8; first = end[b], b++) {
      for (int i = first; i < end[b]; i += TT__EMBREE_K) {
        const int m = end[b] - i < TT__EMBREE_K ? end[b] - i : TT__EMBREE_K;
        if (m < 3 || bvh->root == TT__EMBREE_REF_NONE) { /* too few rays for a packet */
          for (int l = 0; l < m; l++) single(bvh, &rays[idx[i + l]], &hits[idx[i + l]]);
          continue;
        }
        tt__embree_pkt P;
        tt__embree_pkt_setup(&P, rays, idx + i, m, b);
        tt__embree_pintersect(bvh, &P, N);
        for (int l = 0; l < m; l++) {
          tt__embree_best best = {0.0f, P.u[l], P.v[l], P.pk[l], P.W[l], P.lane[l], P.id[l]};
          _Alignas(32) float tf[TT__EMBREE_K];
          _mm256_store_ps(tf, P.tfar);
          best.t = tf[l];
          const size_t r = P.index[l];
          tt__embree_finish(bvh, &best, &rays[r], &hits[r]);
        }
      }
    }
  }
}

TT__EMBREE_INLINE void tt__embree_poccluded_stream(const tt__embree_bvh *bvh, const tt_ray *rays,
                                                   uint8_t *occ, size_t count, const int N,
                                                   tt__embree_occl_fn single) {
  size_t idx[TT__EMBREE_PCHUNK];
  for (size_t base = 0; base < count; base += TT__EMBREE_PCHUNK) {
    const int n = (int)(count - base < TT__EMBREE_PCHUNK ? count - base : TT__EMBREE_PCHUNK);
    int end[9];
    tt__embree_bucket(rays, base, n, idx, end);
    for (int i = end[7]; i < end[8]; i++) occ[idx[i]] = (uint8_t)single(bvh, &rays[idx[i]]);
    for (int b = 0, first = 0; b < 8; first = end[b], b++) {
      for (int i = first; i < end[b]; i += TT__EMBREE_K) {
        const int m = end[b] - i < TT__EMBREE_K ? end[b] - i : TT__EMBREE_K;
        if (m < 3 || bvh->root == TT__EMBREE_REF_NONE) {
          for (int l = 0; l < m; l++) occ[idx[i + l]] = (uint8_t)single(bvh, &rays[idx[i + l]]);
          continue;
        }
        tt__embree_pkt P;
        tt__embree_pkt_setup(&P, rays, idx + i, m, b);
        int hit = tt__embree_poccluded(bvh, &P, N);
        for (int l = 0; l < m; l++) occ[P.index[l]] = (uint8_t)((hit >> l) & 1);
      }
    }
  }
}
#endif /* TT__EMBREE_HAVE_AVX2 */

/* One intersect/occluded pair per (width, robust, counting). */
#if TT__EMBREE_HAVE_AVX2
#  define TT__EMBREE_PACKETS(R, C) (!(R) && !(C))
#else
#  define TT__EMBREE_PACKETS(R, C) 0
#endif
#define TT__EMBREE_DEF(N, R, C)                                                                    \
  static void tt__embree_isect_##N##_##R##_##C(const tt__embree_bvh *b, tt_ray *ray, tt_hit *h) {  \
    if (N == 2) tt__embree_intersect2(b, ray, h, R, C);                                            \
    else if (tt__embree_ray_ibox(ray, R)) tt__embree_intersect(b, ray, h, N, R, C, 1);             \
    else tt__embree_intersect(b, ray, h, N, R, C, 0);                                              \
  }                                                                                                \
  static int tt__embree_occl_##N##_##R##_##C(const tt__embree_bvh *b, const tt_ray *ray) {         \
    if (N == 2) return tt__embree_occluded2(b, ray, R, C);                                         \
    return tt__embree_ray_ibox(ray, R) ? tt__embree_occluded(b, ray, N, R, C, 1)                   \
                                       : tt__embree_occluded(b, ray, N, R, C, 0);                  \
  }                                                                                                \
  static void tt__embree_isects_##N##_##R##_##C(const tt__embree_bvh *b, tt_ray *rays, tt_hit *h,  \
                                                size_t n) {                                        \
    TT__EMBREE_PSTREAM_I(N, R, C)                                                                  \
    for (size_t i = 0; i < n; i++) tt__embree_isect_##N##_##R##_##C(b, &rays[i], &h[i]);           \
  }                                                                                                \
  static void tt__embree_occls_##N##_##R##_##C(const tt__embree_bvh *b, const tt_ray *rays,        \
                                               uint8_t *o, size_t n) {                             \
    TT__EMBREE_PSTREAM_O(N, R, C)                                                                  \
    tt__embree_ostream(b, rays, o, n, N, R, C, tt__embree_occl_##N##_##R##_##C);                   \
  }
/* Packets pay for coherent streams only (measured: 1.4-2.1x on camera rays, 0.6-1.0x on
 * diffuse-bounce and occlusion rays of the same scenes, bench: "streams of 1024"); rays
 * from one origin (camera rays) are the coherent streams integrators make. */
TT__EMBREE_INLINE int tt__embree_one_origin(const tt_ray *rays, size_t n) {
  for (size_t i = 1; i < n; i++)
    if (rays[i].org[0] != rays[0].org[0] || rays[i].org[1] != rays[0].org[1] ||
        rays[i].org[2] != rays[0].org[2])
      return 0;
  return 1;
}
#if TT__EMBREE_HAVE_AVX2
#  define TT__EMBREE_PSTREAM_I(N, R, C)                                                            \
    if (TT__EMBREE_PACKETS(R, C) && tt__embree_one_origin(rays, n)) {                              \
      tt__embree_pintersect_stream(b, rays, h, n, N, tt__embree_isect_##N##_##R##_##C);            \
      return;                                                                                      \
    }
#  define TT__EMBREE_PSTREAM_O(N, R, C)                                                            \
    if (TT__EMBREE_PACKETS(R, C) && tt__embree_one_origin(rays, n)) {                              \
      tt__embree_poccluded_stream(b, rays, o, n, N, tt__embree_occl_##N##_##R##_##C);              \
      return;                                                                                      \
    }
#else
#  define TT__EMBREE_PSTREAM_I(N, R, C)
#  define TT__EMBREE_PSTREAM_O(N, R, C)
#endif
#define TT__EMBREE_DEF_N(N)                                                                        \
  TT__EMBREE_DEF(N, 0, 0) TT__EMBREE_DEF(N, 0, 1) TT__EMBREE_DEF(N, 1, 0) TT__EMBREE_DEF(N, 1, 1)
TT__EMBREE_DEF_N(2)
TT__EMBREE_DEF_N(4)
TT__EMBREE_DEF_N(8)

#define TT__EMBREE_ENT(N, R, C)                                                                    \
  {                                                                                                \
    tt__embree_isect_##N##_##R##_##C, tt__embree_occl_##N##_##R##_##C,                             \
        tt__embree_isects_##N##_##R##_##C, tt__embree_occls_##N##_##R##_##C                        \
  }
#define TT__EMBREE_ENT_N(N)                                                                        \
  {                                                                                                \
    {TT__EMBREE_ENT(N, 0, 0), TT__EMBREE_ENT(N, 0, 1)}, {                                          \
      TT__EMBREE_ENT(N, 1, 0), TT__EMBREE_ENT(N, 1, 1)                                             \
    }                                                                                              \
  }
static const tt__embree_kernel_table g_table = {TT__EMBREE_ENT_N(2), TT__EMBREE_ENT_N(4),
                                                TT__EMBREE_ENT_N(8)};

/* This instruction set's kernels (named after TT__EMBREE_TRAV_ISA). */
const tt__embree_kernel_table *TT__EMBREE_CAT(tt__embree_trav_table_, TT__EMBREE_TRAV_ISA)(void) {
  return &g_table;
}
