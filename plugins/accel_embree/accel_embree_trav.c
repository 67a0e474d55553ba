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
 * so far is skipped. Leaves are tested 4 triangles at a time. */
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
  const tt__tri4 *pk;
  int lane;
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
    p = (const char *)(bvh->packets + (ref & TT__LEAF_MAX_FIRST));
    lines = 4;
  } else {
    p = (const char *)bvh->nodes + (size_t)ref * (size_t)(32 * N);
    lines = N / 2;
  }
  for (int i = 0; i < lines; i++) _mm_prefetch(p + 64 * i, _MM_HINT_T0);
}

/* Tests the 4 triangles of a packet against the ray's current [tnear, tfar]. Returns the
 * valid-lane mask; T, U, V are scaled by |det| (division postponed to the winner). */
TT__INLINE int tt__tri_test(const tt__tri4 *pk, const tt__rc *r, int robust, __m128 *T_out,
                            __m128 *U_out, __m128 *V_out, __m128 *den_out) {
  const __m128 sign = _mm_set1_ps(-0.0f), zero = _mm_setzero_ps();
  __m128 T, U, V, absden, valid;
  if (!robust) {
    /* Moller-Trumbore with precomputed Ng: C = v0 - o, R = C x D, den = Ng.D,
     * u = R.e2 / den, v = R.e1 / den, t = Ng.C / den. */
    __m128 cx = _mm_sub_ps(_mm_load_ps(pk->p[0]), TT__V4(r->o[0]));
    __m128 cy = _mm_sub_ps(_mm_load_ps(pk->p[1]), TT__V4(r->o[1]));
    __m128 cz = _mm_sub_ps(_mm_load_ps(pk->p[2]), TT__V4(r->o[2]));
    __m128 rx = _mm_sub_ps(_mm_mul_ps(cy, TT__V4(r->d[2])), _mm_mul_ps(cz, TT__V4(r->d[1])));
    __m128 ry = _mm_sub_ps(_mm_mul_ps(cz, TT__V4(r->d[0])), _mm_mul_ps(cx, TT__V4(r->d[2])));
    __m128 rz = _mm_sub_ps(_mm_mul_ps(cx, TT__V4(r->d[1])), _mm_mul_ps(cy, TT__V4(r->d[0])));
    __m128 nx = _mm_load_ps(pk->p[9]), ny = _mm_load_ps(pk->p[10]), nz = _mm_load_ps(pk->p[11]);
    __m128 den = _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, TT__V4(r->d[0])), _mm_mul_ps(ny, TT__V4(r->d[1]))),
                            _mm_mul_ps(nz, TT__V4(r->d[2])));
    __m128 sgn = _mm_and_ps(den, sign);
    absden = _mm_xor_ps(den, sgn);
    U = _mm_xor_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, _mm_load_ps(pk->p[6])),
                                         _mm_mul_ps(ry, _mm_load_ps(pk->p[7]))),
                              _mm_mul_ps(rz, _mm_load_ps(pk->p[8]))), sgn);
    V = _mm_xor_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, _mm_load_ps(pk->p[3])),
                                         _mm_mul_ps(ry, _mm_load_ps(pk->p[4]))),
                              _mm_mul_ps(rz, _mm_load_ps(pk->p[5]))), sgn);
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
    __m128 az = _mm_sub_ps(_mm_load_ps(pk->p[0 + kz]), TT__V4(r->o[kz]));
    __m128 bz = _mm_sub_ps(_mm_load_ps(pk->p[3 + kz]), TT__V4(r->o[kz]));
    __m128 cz = _mm_sub_ps(_mm_load_ps(pk->p[6 + kz]), TT__V4(r->o[kz]));
    __m128 ax = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(pk->p[0 + kx]), TT__V4(r->o[kx])), _mm_mul_ps(r->sx, az));
    __m128 ay = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(pk->p[0 + ky]), TT__V4(r->o[ky])), _mm_mul_ps(r->sy, az));
    __m128 bx = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(pk->p[3 + kx]), TT__V4(r->o[kx])), _mm_mul_ps(r->sx, bz));
    __m128 by = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(pk->p[3 + ky]), TT__V4(r->o[ky])), _mm_mul_ps(r->sy, bz));
    __m128 cx = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(pk->p[6 + kx]), TT__V4(r->o[kx])), _mm_mul_ps(r->sx, cz));
    __m128 cy = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(pk->p[6 + ky]), TT__V4(r->o[ky])), _mm_mul_ps(r->sy, cz));
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
TT__INLINE uint64_t tt__leaf_tris(const tt__tri4 *pk, uint32_t n) {
  uint64_t c = 0;
  for (uint32_t i = 0; i < n; i++)
    for (int l = 0; l < 4; l++) c += pk[i].prim[l] != TT_INVALID_ID;
  return c;
}

/* Closest-hit traversal, specialised by width N, robust and counting after inlining. */
TT__INLINE void tt__intersect(const tt__bvh *bvh, tt_ray *ray, tt_hit *hit, const int N,
                              const int robust, const int counting) {
  tt__best best = {ray->tfar, 0.0f, 0.0f, NULL, 0};
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
          for (int m = mask; m; m &= m - 1) tt__prefetch(bvh, child[__builtin_ctz((unsigned)m)], N);
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
        const uint32_t n = ((ref >> TT__LEAF_SHIFT) & 0xFu) + 1u;
        const tt__tri4 *pk = bvh->packets + (ref & TT__LEAF_MAX_FIRST);
        if (counting) c_tris += tt__leaf_tris(pk, n);
        for (uint32_t i = 0; i < n; i++) {
          __m128 T, U, V, den;
          int m = tt__tri_test(&pk[i], &r, robust, &T, &U, &V, &den);
          if (!m) continue;
          /* Nearest valid lane: t = T / |det| for valid lanes, +inf elsewhere. */
          _Alignas(16) float t4[4];
          __m128 valid = _mm_castsi128_ps(
              _mm_cmpgt_epi32(_mm_and_si128(_mm_set1_epi32(m), _mm_setr_epi32(1, 2, 4, 8)),
                              _mm_setzero_si128()));
          __m128 t = _mm_blendv_ps(_mm_set1_ps(INFINITY), _mm_div_ps(T, den), valid);
          _mm_store_ps(t4, t);
          int lane = 0;
          for (int l = 1; l < 4; l++)
            if (t4[l] < t4[lane]) lane = l;
          if (!(t4[lane] <= best.t)) continue;
          _Alignas(16) float u4[4], v4[4], d4[4];
          _mm_store_ps(u4, U);
          _mm_store_ps(v4, V);
          _mm_store_ps(d4, den);
          best.t = t4[lane];
          best.u = u4[lane] / d4[lane];
          best.v = v4[lane] / d4[lane];
          best.pk = &pk[i];
          best.lane = lane;
          tt__set_tfar(&r, best.t);
        }
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
  hit->geom_id = best.pk->geom[best.lane];
  hit->prim_id = best.pk->prim[best.lane];
  hit->ng[0] = best.pk->p[9][best.lane];
  hit->ng[1] = best.pk->p[10][best.lane];
  hit->ng[2] = best.pk->p[11][best.lane];
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
          for (int m = mask; m; m &= m - 1) tt__prefetch(bvh, child[__builtin_ctz((unsigned)m)], N);
          ref = child[__builtin_ctz((unsigned)mask)];
          mask &= mask - 1;
          while (mask) {
            stack[sp++] = child[__builtin_ctz((unsigned)mask)];
            mask &= mask - 1;
          }
          continue;
        }
      } else {
        const uint32_t n = ((ref >> TT__LEAF_SHIFT) & 0xFu) + 1u;
        const tt__tri4 *pk = bvh->packets + (ref & TT__LEAF_MAX_FIRST);
        if (counting) c_tris += tt__leaf_tris(pk, n);
        for (uint32_t i = 0; i < n; i++) {
          __m128 T, U, V, den;
          if (tt__tri_test(&pk[i], &r, robust, &T, &U, &V, &den)) {
            result = 1;
            goto done;
          }
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
