/* accel_embree: SIMD single-ray traversal of the custom backend's BVH (layout in
 * accel_embree_bvh.h).
 *
 * This file is compiled twice (see meson.build): once with -msse4.1 (the baseline every
 * x86-64 CI machine has) and once with -mavx2 -mfma; TT__TRAV_ISA names the copy. The
 * plugin picks the AVX2 table at run time only when the CPU reports AVX2 and FMA, so no
 * AVX instruction ever runs on an older CPU. Everything here is static except the table
 * getter, so the two copies cannot be mixed up by the linker.
 *
 * Traversal: one stack per ray; at each inner node all N child boxes are tested at once
 * (SoA rows, near/far planes chosen by the ray direction's signs, so no min/max per axis);
 * hit children are visited front to back by entry distance (closest hit) or in node order
 * (occlusion, which stops at the first hit); a popped entry farther than the closest hit
 * so far is skipped. Hit children are prefetched, and in a BVH2 their children too (the
 * node's grand[] hints), so consecutive node misses overlap. Leaves are tested one SIMD
 * packet (4 or 2 triangles) at a time. */
#include "accel_embree_bvh.h"

#include <immintrin.h>
#include <math.h>
#include <string.h>

#ifndef TT__TRAV_ISA
#  error "compile with -DTT__TRAV_ISA=sse41 or avx2"
#endif
#define TT__CAT2(a, b) a##b
#define TT__CAT(a, b) TT__CAT2(a, b)

#if defined(__AVX2__) && defined(__FMA__)
#  define TT__HAVE_AVX2 1
#else
#  define TT__HAVE_AVX2 0
#endif

#define TT__INLINE static inline __attribute__((always_inline))

/* Stack entries: 64 levels (maxDepth <= 64, checked at build) x (8 - 1) siblings + slack. */
#define TT__STACK 640

/* 1 + 2 * gamma(3) (pbrt's bound on the error of a slab distance): far plane distances
 * are scaled by it in robust mode so round-off cannot make a box look missed. */
#define TT__ROBUST_FAR 1.0000003576f

/* Per-ray data, broadcast to SIMD registers once. With AVX2 only the 8-wide copies exist
 * and the 4-wide views are their lower halves (a free cast): one copy of the ray state
 * keeps more of it in the 16 registers. */
#if TT__HAVE_AVX2
typedef __m256 tt__vreg;
#  define TT__SET1(x) _mm256_set1_ps(x)
#  define TT__V4(v) _mm256_castps256_ps128(v)
#else
typedef __m128 tt__vreg;
#  define TT__SET1(x) _mm_set1_ps(x)
#  define TT__V4(v) (v)
#endif
typedef struct tt__rc {
  tt__vreg o[3], d[3];     /* origin, direction */
  tt__vreg rd[3], ord[3];  /* 1/dir (zero guarded) and org * rd */
  tt__vreg tnear, tfar;
  int near[3];             /* near-plane row per axis: 2k + signbit(dir[k]) */
  /* Watertight test (Woop, Benthin, Wald 2013): axes permuted so that kz has the largest
   * |dir| and the shear constants. */
  int kx, ky, kz;
  __m128 sx, sy, sz;
} tt__rc;

/* Best hit so far. */
typedef struct tt__best {
  float t, u, v;
  const float *pk;  /* packet of the hit, NULL for none */
  int W, lane;      /* its width and the hit's lane */
  uint32_t slot;    /* the hit triangle's slot (ids) */
} tt__best;

/* Prepares the ray; returns 0 when no hit is possible (NaN/inf input, empty interval). */
TT__INLINE int tt__setup(tt__rc *r, const tt_ray *ray, int robust) {
  float o[3] = {ray->org[0], ray->org[1], ray->org[2]};
  float d[3] = {ray->dir[0], ray->dir[1], ray->dir[2]};
  for (int k = 0; k < 3; k++)
    if (!isfinite(o[k]) || !isfinite(d[k])) return 0;
  if (!(ray->tnear <= ray->tfar)) return 0;  /* also rejects NaN */
  for (int k = 0; k < 3; k++) {
    /* A zero component would give 1/0 = inf and 0 * inf = NaN on a slab through the
     * origin; a tiny value of the same sign keeps every slab distance well defined. */
    float dk = fabsf(d[k]) < 1e-18f ? copysignf(1e-18f, d[k]) : d[k];
    float rk = 1.0f / dk;
    r->o[k] = TT__SET1(o[k]);
    r->d[k] = TT__SET1(d[k]);
    r->rd[k] = TT__SET1(rk);
    r->ord[k] = TT__SET1(o[k] * rk);
    r->near[k] = 2 * k + (signbit(dk) ? 1 : 0);
  }
  r->tnear = TT__SET1(ray->tnear);
  r->tfar = TT__SET1(ray->tfar);
  if (robust) {
    int kz = 0;
    if (fabsf(d[1]) > fabsf(d[kz])) kz = 1;
    if (fabsf(d[2]) > fabsf(d[kz])) kz = 2;
    int kx = kz == 2 ? 0 : kz + 1, ky = kx == 2 ? 0 : kx + 1;
    if (d[kz] < 0.0f) {  /* keep the winding so U, V, W signs mean the same thing */
      int t = kx;
      kx = ky;
      ky = t;
    }
    if (d[kz] == 0.0f) return 0;  /* zero direction: nothing can be hit */
    r->kx = kx, r->ky = ky, r->kz = kz;
    r->sx = _mm_set1_ps(d[kx] / d[kz]);
    r->sy = _mm_set1_ps(d[ky] / d[kz]);
    r->sz = _mm_set1_ps(1.0f / d[kz]);
  }
  return 1;
}

/* Sets the current far distance in every register that uses it. */
TT__INLINE void tt__set_tfar(tt__rc *r, float t) { r->tfar = TT__SET1(t); }

/* Slab distance of 4 planes on one axis. FMA form (b*rd - o*rd, one rounding) where
 * available and not robust; otherwise (b - o) * rd, whose error pbrt's bound covers. */
TT__INLINE __m128 tt__slab4(__m128 b, const tt__rc *r, int k, int robust) {
#if TT__HAVE_AVX2
  if (!robust) return _mm_fmsub_ps(b, TT__V4(r->rd[k]), TT__V4(r->ord[k]));
#else
  (void)robust;
#endif
  return _mm_mul_ps(_mm_sub_ps(b, TT__V4(r->o[k])), TT__V4(r->rd[k]));
}

/* Tests 4 boxes given as row pointers (stride between rows `stride` floats); writes entry
 * distances and returns the hit mask. `two` loads only 2 lanes (BVH2 nodes). */
TT__INLINE int tt__box4(const float *rows, size_t stride, const tt__rc *r, int robust,
                        int two, float *dist) {
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
    tn[k] = tt__slab4(bn, r, k, robust);
    tf[k] = tt__slab4(bf, r, k, robust);
  }
  __m128 tmin = _mm_max_ps(_mm_max_ps(tn[0], tn[1]), _mm_max_ps(tn[2], TT__V4(r->tnear)));
  __m128 tmax = _mm_min_ps(_mm_min_ps(tf[0], tf[1]), tf[2]);
  if (robust) tmax = _mm_mul_ps(tmax, _mm_set1_ps(TT__ROBUST_FAR));
  tmax = _mm_min_ps(tmax, TT__V4(r->tfar));
  _mm_storeu_ps(dist, tmin);
  int m = _mm_movemask_ps(_mm_cmple_ps(tmin, tmax));
  return two ? m & 3 : m;
}

/* Tests the 8 boxes of a BVH8 node: one AVX pass, or two SSE halves on the baseline. */
TT__INLINE int tt__box8(const tt__node8 *n, const tt__rc *r, int robust, float *dist) {
#if TT__HAVE_AVX2
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
  __m256 tmin = _mm256_max_ps(_mm256_max_ps(tn[0], tn[1]), _mm256_max_ps(tn[2], r->tnear));
  __m256 tmax = _mm256_min_ps(_mm256_min_ps(tf[0], tf[1]), tf[2]);
  if (robust) tmax = _mm256_mul_ps(tmax, _mm256_set1_ps(TT__ROBUST_FAR));
  tmax = _mm256_min_ps(tmax, r->tfar);
  _mm256_storeu_ps(dist, tmin);
  return _mm256_movemask_ps(_mm256_cmp_ps(tmin, tmax, _CMP_LE_OQ));
#else
  int lo = tt__box4(&n->b[0][0], 8, r, robust, 0, dist);
  int hi = tt__box4(&n->b[0][4], 8, r, robust, 0, dist + 4);
  return lo | hi << 4;
#endif
}

/* Tests one inner node of width N; returns the hit mask, distances in `dist`. */
TT__INLINE int tt__node_test(const void *node, const tt__rc *r, int N, int robust,
                             float *dist) {
  if (N == 2) return tt__box4(&((const tt__node2 *)node)->b[0][0], 2, r, robust, 1, dist);
  if (N == 4) return tt__box4(&((const tt__node4 *)node)->b[0][0], 4, r, robust, 0, dist);
  return tt__box8((const tt__node8 *)node, r, robust, dist);
}

/* Address of node `index` of a width-N tree (node sizes are 32 * N bytes). */
TT__INLINE const void *tt__node_at(const tt__bvh *bvh, uint32_t index, int N) {
  return (const char *)bvh->nodes + (size_t)index * (size_t)(32 * N);
}

/* Child references of a width-N node (after its 6 rows of N floats). */
TT__INLINE const uint32_t *tt__children(const void *node, int N) {
  return (const uint32_t *)((const char *)node + 24 * N);
}

/* Prefetches what visiting `ref` reads first: the node (32 * N bytes) or the leaf's first
 * packet. Traversal is bound by memory latency, and the hit children are known one box
 * test before they are visited (or much longer, for the ones pushed on the stack). */
TT__INLINE void tt__prefetch(const tt__bvh *bvh, uint32_t ref, int N) {
  const char *p;
  int lines;
  if (ref & TT__REF_LEAF) {
    /* The leaf's first packet, 3 lines from its line (a 4-wide packet is line aligned, a
     * 2-wide one of 96 bytes starts at a 32-byte boundary), and the second one of a leaf
     * of 7-8 triangles (leaves tuned to maxLeafSize 8). */
    p = (const char *)((uintptr_t)(bvh->slots + (size_t)(ref & TT__LEAF_MAX_FIRST) *
                                                    TT__SLOT_FLOATS) & ~(uintptr_t)63);
    _mm_prefetch(p, _MM_HINT_T0);
    _mm_prefetch(p + 64, _MM_HINT_T0);
    _mm_prefetch(p + 128, _MM_HINT_T0);
    if (((ref >> TT__LEAF_SHIFT) & 0xFu) >= 3u) {  /* 4+ pairs: the second packet too */
      _mm_prefetch(p + 192, _MM_HINT_T0);
      _mm_prefetch(p + 256, _MM_HINT_T0);
      _mm_prefetch(p + 320, _MM_HINT_T0);
    }
    return;
  } else {
    p = (const char *)bvh->nodes + (size_t)ref * (size_t)(32 * N);
    lines = N / 2;
  }
  for (int i = 0; i < lines; i++) _mm_prefetch(p + 64 * i, _MM_HINT_T0);
}

/* Prefetches the hit children of a node, and for BVH2 also their grandchildren (the
 * node's grand[] hints and, by pre-order, the line after an inner child). */
TT__INLINE void tt__prefetch_children(const tt__bvh *bvh, const uint32_t *child, int mask,
                                      int N) {
  for (int m = mask; m; m &= m - 1) {
    int c = __builtin_ctz((unsigned)m);
    uint32_t ref = child[c];
    tt__prefetch(bvh, ref, N);
    if (N == 2 && !(ref & TT__REF_LEAF)) {
      _mm_prefetch((const char *)bvh->nodes + (size_t)(ref + 1) * 64u, _MM_HINT_T0);
      uint32_t g = child[2 + c];
      if (g != TT__REF_NONE) tt__prefetch(bvh, g, N);
    }
  }
}

/* Tests the (up to) 4 triangles of a packet against the ray's current [tnear, tfar]. Returns the
 * valid-lane mask; T, U, V are scaled by |det| (division postponed to the winner). */
/* Row r of a width-W packet (W = 2: lanes 2 and 3 read as zero, i.e. never hit). */
TT__INLINE __m128 tt__row(const float *pk, int W, int r) {
  if (W == 4) return _mm_load_ps(pk + 4 * r);
  return _mm_castpd_ps(_mm_load_sd((const double *)(pk + 2 * r)));
}

TT__INLINE int tt__tri_test(const float *pk, int W, const tt__rc *r, int robust, __m128 *T_out,
                            __m128 *U_out, __m128 *V_out, __m128 *den_out) {
  const __m128 sign = _mm_set1_ps(-0.0f), zero = _mm_setzero_ps();
  __m128 T, U, V, absden, valid;
  if (!robust) {
    /* Moller-Trumbore with precomputed Ng: C = v0 - o, R = C x D, den = Ng.D,
     * u = R.e2 / den, v = R.e1 / den, t = Ng.C / den. */
    __m128 cx = _mm_sub_ps(tt__row(pk, W, 0), TT__V4(r->o[0]));
    __m128 cy = _mm_sub_ps(tt__row(pk, W, 1), TT__V4(r->o[1]));
    __m128 cz = _mm_sub_ps(tt__row(pk, W, 2), TT__V4(r->o[2]));
    __m128 rx = _mm_sub_ps(_mm_mul_ps(cy, TT__V4(r->d[2])), _mm_mul_ps(cz, TT__V4(r->d[1])));
    __m128 ry = _mm_sub_ps(_mm_mul_ps(cz, TT__V4(r->d[0])), _mm_mul_ps(cx, TT__V4(r->d[2])));
    __m128 rz = _mm_sub_ps(_mm_mul_ps(cx, TT__V4(r->d[1])), _mm_mul_ps(cy, TT__V4(r->d[0])));
    __m128 nx = tt__row(pk, W, 9), ny = tt__row(pk, W, 10), nz = tt__row(pk, W, 11);
    __m128 den = _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, TT__V4(r->d[0])), _mm_mul_ps(ny, TT__V4(r->d[1]))),
                            _mm_mul_ps(nz, TT__V4(r->d[2])));
    __m128 sgn = _mm_and_ps(den, sign);
    absden = _mm_xor_ps(den, sgn);
    U = _mm_xor_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, tt__row(pk, W, 6)),
                                         _mm_mul_ps(ry, tt__row(pk, W, 7))),
                              _mm_mul_ps(rz, tt__row(pk, W, 8))), sgn);
    V = _mm_xor_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, tt__row(pk, W, 3)),
                                         _mm_mul_ps(ry, tt__row(pk, W, 4))),
                              _mm_mul_ps(rz, tt__row(pk, W, 5))), sgn);
    valid = _mm_and_ps(_mm_cmpge_ps(U, zero), _mm_cmpge_ps(V, zero));
    valid = _mm_and_ps(valid, _mm_cmple_ps(_mm_add_ps(U, V), absden));
    valid = _mm_and_ps(valid, _mm_cmpgt_ps(absden, zero));
    if (!_mm_movemask_ps(valid)) return 0;
    T = _mm_xor_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, cx), _mm_mul_ps(ny, cy)),
                              _mm_mul_ps(nz, cz)), sgn);
  } else {
    /* Watertight: vertices relative to the origin, sheared so the ray is the +z axis;
     * U, V, W are 2D edge functions, evaluated identically for a shared edge. */
    const int kx = r->kx, ky = r->ky, kz = r->kz;
    __m128 az = _mm_sub_ps(tt__row(pk, W, 0 + kz), TT__V4(r->o[kz]));
    __m128 bz = _mm_sub_ps(tt__row(pk, W, 3 + kz), TT__V4(r->o[kz]));
    __m128 cz = _mm_sub_ps(tt__row(pk, W, 6 + kz), TT__V4(r->o[kz]));
    __m128 ax = _mm_sub_ps(_mm_sub_ps(tt__row(pk, W, 0 + kx), TT__V4(r->o[kx])), _mm_mul_ps(r->sx, az));
    __m128 ay = _mm_sub_ps(_mm_sub_ps(tt__row(pk, W, 0 + ky), TT__V4(r->o[ky])), _mm_mul_ps(r->sy, az));
    __m128 bx = _mm_sub_ps(_mm_sub_ps(tt__row(pk, W, 3 + kx), TT__V4(r->o[kx])), _mm_mul_ps(r->sx, bz));
    __m128 by = _mm_sub_ps(_mm_sub_ps(tt__row(pk, W, 3 + ky), TT__V4(r->o[ky])), _mm_mul_ps(r->sy, bz));
    __m128 cx = _mm_sub_ps(_mm_sub_ps(tt__row(pk, W, 6 + kx), TT__V4(r->o[kx])), _mm_mul_ps(r->sx, cz));
    __m128 cy = _mm_sub_ps(_mm_sub_ps(tt__row(pk, W, 6 + ky), TT__V4(r->o[ky])), _mm_mul_ps(r->sy, cz));
    __m128 u = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
    __m128 v = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
    __m128 w = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
    __m128 pos = _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(u, zero), _mm_cmpge_ps(v, zero)),
                            _mm_cmpge_ps(w, zero));
    __m128 neg = _mm_and_ps(_mm_and_ps(_mm_cmple_ps(u, zero), _mm_cmple_ps(v, zero)),
                            _mm_cmple_ps(w, zero));
    __m128 det = _mm_add_ps(_mm_add_ps(u, v), w);
    valid = _mm_and_ps(_mm_or_ps(pos, neg), _mm_cmpneq_ps(det, zero));
    if (!_mm_movemask_ps(valid)) return 0;
    __m128 sgn = _mm_and_ps(det, sign);
    absden = _mm_xor_ps(det, sgn);
    az = _mm_mul_ps(r->sz, az);
    bz = _mm_mul_ps(r->sz, bz);
    cz = _mm_mul_ps(r->sz, cz);
    T = _mm_xor_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(u, az), _mm_mul_ps(v, bz)),
                              _mm_mul_ps(w, cz)), sgn);
    U = _mm_xor_ps(v, sgn);  /* weight of v1 */
    V = _mm_xor_ps(w, sgn);  /* weight of v2 */
  }
  valid = _mm_and_ps(valid, _mm_cmpge_ps(T, _mm_mul_ps(absden, TT__V4(r->tnear))));
  valid = _mm_and_ps(valid, _mm_cmple_ps(T, _mm_mul_ps(absden, TT__V4(r->tfar))));
  *T_out = T, *U_out = U, *V_out = V, *den_out = absden;
  return _mm_movemask_ps(valid);
}

/* Real triangles in a leaf's packets (for the counters only). */
TT__INLINE uint64_t tt__leaf_tris(const tt__id *id, uint32_t n) {
  uint64_t c = 0;
  for (uint32_t i = 0; i < n; i++) c += id[i].prim != TT_INVALID_ID;
  return c;
}

/* Tests one width-W packet (first slot `slot`) for a closer hit; updates `best` and the
 * ray's tfar. */
TT__INLINE void tt__leaf_packet(const float *pk, const int W, uint32_t slot, const tt__bvh *bvh,
                                tt__rc *restrict r, const int robust,
                                tt__best *restrict best) {
  __m128 T, U, V, den;
  int m = tt__tri_test(pk, W, r, robust, &T, &U, &V, &den);
  if (!m) return;
  /* Nearest valid lane: t = T / |det| for valid lanes, +inf elsewhere. */
  _Alignas(16) float t4[4];
  __m128 valid = _mm_castsi128_ps(
      _mm_cmpgt_epi32(_mm_and_si128(_mm_set1_epi32(m), _mm_setr_epi32(1, 2, 4, 8)),
                      _mm_setzero_si128()));
  __m128 t = _mm_blendv_ps(_mm_set1_ps(INFINITY), _mm_div_ps(T, den), valid);
  _mm_store_ps(t4, t);
  int lane = 0;
  for (int l = 1; l < W; l++)
    if (t4[l] < t4[lane]) lane = l;
  if (!(t4[lane] <= best->t)) return;
  _Alignas(16) float u4[4], v4[4], d4[4];
  _mm_store_ps(u4, U);
  _mm_store_ps(v4, V);
  _mm_store_ps(d4, den);
  best->t = t4[lane];
  best->u = u4[lane] / d4[lane];
  best->v = v4[lane] / d4[lane];
  best->pk = pk;
  best->W = W;
  best->lane = lane;
  best->slot = slot + (uint32_t)lane;
  /* The ids are read once, after traversal: fetch their line meanwhile. */
  _mm_prefetch((const char *)(bvh->ids + best->slot), _MM_HINT_T0);
  tt__set_tfar(r, best->t);
}

/* Closest-hit traversal, specialised by width N, robust and counting after inlining. */
TT__INLINE void tt__intersect(const tt__bvh *bvh, tt_ray *ray, tt_hit *hit, const int N,
                              const int robust, const int counting) {
  tt__best best = {ray->tfar, 0.0f, 0.0f, NULL, 4, 0, 0};
  uint64_t c_nodes = 0, c_tris = 0;
  tt__rc r;
  uint32_t ref = bvh->root;
  if (ref != TT__REF_NONE && tt__setup(&r, ray, robust)) {
    struct {
      uint32_t ref;
      float dist;
    } stack[TT__STACK];
    int sp = 0;
    _Alignas(32) float dist[8];
    for (;;) {
      if (!(ref & TT__REF_LEAF)) {
        const void *node = tt__node_at(bvh, ref, N);
        int mask = tt__node_test(node, &r, N, robust, dist);
        if (counting) c_nodes++;
        if (mask) {
          const uint32_t *child = tt__children(node, N);
          tt__prefetch_children(bvh, child, mask, N);
          int i0 = __builtin_ctz((unsigned)mask);
          mask &= mask - 1;
          if (!mask) {
            ref = child[i0];
            continue;
          }
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
          /* Three or more: push all, sort them so the nearest is on top, take it. */
          int base = sp;
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
          ref = stack[--sp].ref;
          continue;
        }
      } else {
        const uint32_t pairs = ((ref >> TT__LEAF_SHIFT) & 0xFu) + 1u;
        const uint32_t first = ref & TT__LEAF_MAX_FIRST;
        const float *pk = bvh->slots + (size_t)first * TT__SLOT_FLOATS;
        if (counting) c_tris += tt__leaf_tris(bvh->ids + first, 2 * pairs);
        uint32_t q = 0;
        for (; q + 1 < pairs; q += 2, pk += 4 * TT__SLOT_FLOATS)
          tt__leaf_packet(pk, 4, first + 2 * q, bvh, &r, robust, &best);
        if (q < pairs) tt__leaf_packet(pk, 2, first + 2 * q, bvh, &r, robust, &best);
      }
      /* Pop the next entry that can still hold a closer hit. */
      for (;;) {
        if (sp == 0) goto done;
        --sp;
        if (stack[sp].dist <= best.t) break;
      }
      ref = stack[sp].ref;
    }
  }
done:
  if (counting) {
    tt__bvh *mut = (tt__bvh *)bvh;  /* counters are the one mutable part of a built tree */
    atomic_fetch_add_explicit(&mut->c_rays, 1, memory_order_relaxed);
    atomic_fetch_add_explicit(&mut->c_nodes, c_nodes, memory_order_relaxed);
    atomic_fetch_add_explicit(&mut->c_tris, c_tris, memory_order_relaxed);
  }
  if (!best.pk) {
    hit->t = INFINITY;
    hit->u = hit->v = 0.0f;
    hit->geom_id = hit->prim_id = TT_INVALID_ID;
    hit->ng[0] = hit->ng[1] = hit->ng[2] = 0.0f;
    return;
  }
  ray->tfar = best.t;
  hit->t = best.t;
  hit->u = best.u;
  hit->v = best.v;
  const tt__id *id = bvh->ids + best.slot;
  hit->geom_id = id->geom;
  hit->prim_id = id->prim;
  hit->ng[0] = best.pk[9 * best.W + best.lane];
  hit->ng[1] = best.pk[10 * best.W + best.lane];
  hit->ng[2] = best.pk[11 * best.W + best.lane];
}

/* Any-hit traversal: children in node order (sorting does not pay when the first hit
 * ends the ray), returns at the first triangle inside [tnear, tfar]. */
TT__INLINE int tt__occluded(const tt__bvh *bvh, const tt_ray *ray, const int N,
                            const int robust, const int counting) {
  uint64_t c_nodes = 0, c_tris = 0;
  int result = 0;
  tt__rc r;
  uint32_t ref = bvh->root;
  if (ref != TT__REF_NONE && tt__setup(&r, ray, robust)) {
    uint32_t stack[TT__STACK];
    int sp = 0;
    _Alignas(32) float dist[8];
    for (;;) {
      if (!(ref & TT__REF_LEAF)) {
        const void *node = tt__node_at(bvh, ref, N);
        int mask = tt__node_test(node, &r, N, robust, dist);
        if (counting) c_nodes++;
        if (mask) {
          const uint32_t *child = tt__children(node, N);
          tt__prefetch_children(bvh, child, mask, N);
          ref = child[__builtin_ctz((unsigned)mask)];
          mask &= mask - 1;
          while (mask) {
            stack[sp++] = child[__builtin_ctz((unsigned)mask)];
            mask &= mask - 1;
          }
          continue;
        }
      } else {
        const uint32_t pairs = ((ref >> TT__LEAF_SHIFT) & 0xFu) + 1u;
        const uint32_t first = ref & TT__LEAF_MAX_FIRST;
        const float *pk = bvh->slots + (size_t)first * TT__SLOT_FLOATS;
        if (counting) c_tris += tt__leaf_tris(bvh->ids + first, 2 * pairs);
        __m128 T, U, V, den;
        uint32_t q = 0;
        for (; q + 1 < pairs; q += 2, pk += 4 * TT__SLOT_FLOATS)
          if (tt__tri_test(pk, 4, &r, robust, &T, &U, &V, &den)) {
            result = 1;
            goto done;
          }
        if (q < pairs && tt__tri_test(pk, 2, &r, robust, &T, &U, &V, &den)) {
          result = 1;
          goto done;
        }
      }
      if (sp == 0) break;
      ref = stack[--sp];
    }
  }
done:
  if (counting) {
    tt__bvh *mut = (tt__bvh *)bvh;
    atomic_fetch_add_explicit(&mut->c_rays, 1, memory_order_relaxed);
    atomic_fetch_add_explicit(&mut->c_nodes, c_nodes, memory_order_relaxed);
    atomic_fetch_add_explicit(&mut->c_tris, c_tris, memory_order_relaxed);
  }
  return result;
}

/* One intersect/occluded pair per (width, robust, counting). */
#define TT__DEF(N, R, C)                                                                    \
  static void tt__isect_##N##_##R##_##C(const tt__bvh *b, tt_ray *ray, tt_hit *h) {         \
    tt__intersect(b, ray, h, N, R, C);                                                      \
  }                                                                                         \
  static int tt__occl_##N##_##R##_##C(const tt__bvh *b, const tt_ray *ray) {                \
    return tt__occluded(b, ray, N, R, C);                                                   \
  }
#define TT__DEF_N(N) TT__DEF(N, 0, 0) TT__DEF(N, 0, 1) TT__DEF(N, 1, 0) TT__DEF(N, 1, 1)
TT__DEF_N(2)
TT__DEF_N(4)
TT__DEF_N(8)

#define TT__ENT(N, R, C) {tt__isect_##N##_##R##_##C, tt__occl_##N##_##R##_##C}
#define TT__ENT_N(N) \
  {{TT__ENT(N, 0, 0), TT__ENT(N, 0, 1)}, {TT__ENT(N, 1, 0), TT__ENT(N, 1, 1)}}
static const tt__kernel_table g_table = {TT__ENT_N(2), TT__ENT_N(4), TT__ENT_N(8)};

/* This instruction set's kernels (named after TT__TRAV_ISA). */
const tt__kernel_table *TT__CAT(tt__trav_table_, TT__TRAV_ISA)(void) { return &g_table; }
