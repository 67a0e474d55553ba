/* post_taa kernels: the 5x5 layers by Winograd F(2x2, 5x5) and F(4x4, 5x5) (README.md,
 * "How the fast path works"), compiled for the AVX2 and AVX-512 copies only (taa_kernel.h;
 * the generic copy runs direct convolutions). The weights' transforms U = G g G^T are made
 * once per weight set at load (taa_fast_pack.c); here the input transform V = B^T d B, the
 * products summed over input channels, and the output transform A^T [.] A. */
#include "taa_kernel.h"

#if !TT__NET_HAVE_AVX2
#  error "the Winograd kernels need AVX2 and FMA (meson.build compiles them for avx2, avx512)"
#endif

/* ---- F(2x2, 5x5): the kernel layer and 5x5 body layers with output blocks of 10 or 12 ----
 *
 * Tiles are vectorised: 8 tiles (16 columns) per vector, P vectors per group; per group the
 * input transform fills V[36][in][8P], then per block of O outputs the 36 products
 * M[pos][O][8P] = U[pos][O][in] x V[pos][in][8P] and the output transform. Every tile's
 * arithmetic is the same whatever lane or group it is in, so results do not depend on the
 * band or tile split. */

/* Even lanes of the 16 floats a:b (stride-2 gather of 8 tiles' column). */
TT__NET_AI tt__net_v8f tt__net_wino_even(tt__net_v8f a, tt__net_v8f b) {
  return TT__NET_WINO_SHUF8(a, b, 0, 2, 4, 6, 8, 10, 12, 14);
}

/* B^T of one 6-vector (rows of B^T: 4 0 -5 0 1 0 / 0 4 4 -1 -1 0 / 0 -4 4 1 -1 0 /
 * 0 -2 -1 2 1 0 / 0 2 -1 -2 1 0 / 0 4 0 -5 0 1). */
TT__NET_AI void tt__net_wino_bt(const tt__net_v8f d[6], tt__net_v8f v[6]) {
  tt__net_v8f s12 = d[1] + d[2], s34 = d[3] + d[4], a21 = d[2] - d[1], a34 = d[3] - d[4];
  tt__net_v8f a31 = d[3] - d[1], a42 = d[4] - d[2];
  v[0] = d[0] * 4.0f - d[2] * 5.0f + d[4];
  v[1] = s12 * 4.0f - s34;
  v[2] = a21 * 4.0f + a34;
  v[3] = a31 * 2.0f + a42;
  v[4] = a42 - a31 * 2.0f;
  v[5] = d[1] * 4.0f - d[3] * 5.0f + d[5];
}

/* A^T of one 6-vector: m0 + m1 + m2 + m3 + m4, m1 - m2 + 2 (m3 - m4) + m5. */
TT__NET_AI void tt__net_wino_at(const tt__net_v8f m[6], tt__net_v8f *y0, tt__net_v8f *y1) {
  *y0 = (m[0] + m[1]) + (m[2] + m[3]) + m[4];
  *y1 = (m[1] - m[2]) + (m[3] - m[4]) * 2.0f + m[5];
}

/* One group of 8P tiles (16P columns from xl). */
TT__NET_AI void tt__net_wino_group_t(const tt__net_wino_args *a, uint32_t xl, const int O,
                                     const int P) {
  const uint32_t I = a->in;
  const int T = 8 * P;
  float *V = a->vbuf, *M = a->mbuf;
  for (uint32_t c = 0; c < I; c++) {
#pragma GCC unroll 2
    for (int j = 0; j < P; j++) {
      tt__net_v8f e[6][6];
#pragma GCC unroll 6
      for (int i = 0; i < 6; i++) {
        const float *q = a->rowp[i] + c * a->cs + TT__NET_COL_OFF + a->x0 + xl + 16 * j - 2;
        tt__net_v8f d[6];
#pragma GCC unroll 3
        for (int k = 0; k < 6; k += 2) {
          tt__net_v8f lo = tt__net_vload(q + k), hi = tt__net_vload(q + k + 8),
                      lo1 = tt__net_vload(q + k + 1), hi1 = tt__net_vload(q + k + 9);
          d[k] = tt__net_wino_even(lo, hi);
          d[k + 1] = tt__net_wino_even(lo1, hi1);
        }
        tt__net_wino_bt(d, e[i]); /* along the row: e[i][s] */
      }
#pragma GCC unroll 6
      for (int s2 = 0; s2 < 6; s2++) {
        tt__net_v8f col[6], v[6];
#pragma GCC unroll 6
        for (int i = 0; i < 6; i++) col[i] = e[i][s2];
        tt__net_wino_bt(col, v); /* along the column: V[r][s2] */
#pragma GCC unroll 6
        for (int r = 0; r < 6; r++)
          tt__net_vstore(V + ((size_t)(r * 6 + s2) * I + c) * T + 8 * j, v[r]);
      }
    }
  }
  /* Block ob's 36 products go to one half of M while the output transforms of block
   * ob - 1 (one output channel and vector after each product) read the other: their adds
   * and loads overlap the products' multiply-adds. */
  for (uint32_t ob = 0; ob <= a->nob; ob++) {
    float *Mc = M + (size_t)(ob & 1) * TT__NET_WINO_POS * O * T;
    float *Mp = M + (size_t)(~ob & 1) * TT__NET_WINO_POS * O * T;
    const float *u = a->u + (size_t)(ob < a->nob ? ob : 0) * TT__NET_WINO_POS * I * O;
    for (uint32_t pos = 0; pos < TT__NET_WINO_POS; pos++) {
      if (ob < a->nob) {
        tt__net_v8f acc[12][2];
#pragma GCC unroll 12
        for (int o = 0; o < O; o++)
#pragma GCC unroll 2
          for (int j = 0; j < P; j++) acc[o][j] = tt__net_vsplat(0.0f);
        const float *vp = V + (size_t)pos * I * T;
        for (uint32_t c = 0; c < I; c++) {
          tt__net_v8f in[2];
#pragma GCC unroll 2
          for (int j = 0; j < P; j++) in[j] = tt__net_vload(vp + 8 * j);
#pragma GCC unroll 12
          for (int o = 0; o < O; o++) {
            float wv = u[o];
#pragma GCC unroll 2
            for (int j = 0; j < P; j++) acc[o][j] += in[j] * wv;
          }
          u += O;
          vp += T;
        }
#pragma GCC unroll 12
        for (int o = 0; o < O; o++)
#pragma GCC unroll 2
          for (int j = 0; j < P; j++)
            tt__net_vstore(Mc + ((size_t)pos * O + o) * T + 8 * j, acc[o][j]);
      }
      if (ob == 0 || pos >= (uint32_t)(O * P)) continue;
      int o = (int)pos / P, j = (int)pos % P;
      uint32_t oc = (ob - 1) * O + (uint32_t)o;
      if (oc >= a->out) continue;
      tt__net_v8f bias = tt__net_vsplat(a->b[oc]);
      tt__net_v8f r0[6], r1[6];
#pragma GCC unroll 6
      for (int i = 0; i < 6; i++) {
        tt__net_v8f m[6];
#pragma GCC unroll 6
        for (int k = 0; k < 6; k++)
          m[k] = tt__net_vload(Mp + ((size_t)(i * 6 + k) * O + o) * T + 8 * j);
        tt__net_wino_at(m, &r0[i], &r1[i]); /* along the row: output columns 0, 1 */
      }
      tt__net_v8f y00, y10, y01, y11;
      tt__net_wino_at(r0, &y00, &y10); /* along the column: output rows 0, 1 */
      tt__net_wino_at(r1, &y01, &y11);
      y00 += bias, y01 += bias, y10 += bias, y11 += bias;
      if (a->relu) {
        tt__net_v8f z = tt__net_vsplat(0.0f);
        y00 = tt__net_vsel(y00 > z, y00, z), y01 = tt__net_vsel(y01 > z, y01, z);
        y10 = tt__net_vsel(y10 > z, y10, z), y11 = tt__net_vsel(y11 > z, y11, z);
      }
      /* Tile t's columns 2t, 2t + 1: interleave the column-0 and column-1 vectors. */
      float *d0 = a->dst[0] + oc * a->dcs + xl + 16 * j;
      float *d1 = a->dst[1] + oc * a->dcs + xl + 16 * j;
      tt__net_vstore(d0, TT__NET_WINO_SHUF8(y00, y01, 0, 8, 1, 9, 2, 10, 3, 11));
      tt__net_vstore(d0 + 8, TT__NET_WINO_SHUF8(y00, y01, 4, 12, 5, 13, 6, 14, 7, 15));
      tt__net_vstore(d1, TT__NET_WINO_SHUF8(y10, y11, 0, 8, 1, 9, 2, 10, 3, 11));
      tt__net_vstore(d1 + 8, TT__NET_WINO_SHUF8(y10, y11, 4, 12, 5, 13, 6, 14, 7, 15));
    }
  }
}

/* All groups of a chunk: 16 tiles per group with 32 registers (`wide`), else 8. Output
 * blocks of 10 (the kernel layer's 50 outputs) or 12 (12-channel body layers). */
#define TT__NET_WINO_CASE(O_)                                                                      \
  case O_:                                                                                         \
    for (uint32_t xl = 0; xl < a->n;) {                                                            \
      if (wide && a->n - xl >= 32) tt__net_wino_group_t(a, xl, O_, 2), xl += 32;                   \
      else tt__net_wino_group_t(a, xl, O_, 1), xl += 16;                                           \
    }                                                                                              \
    break;
TT__NET_AI void tt__net_wino_dispatch(const tt__net_wino_args *a, uint32_t oblk, const int wide) {
  switch (oblk) {
    TT__NET_WINO_CASE(10)
    TT__NET_WINO_CASE(12)
  default: break;
  }
}

/* ---- F(4x4, 5x5): the kernel layer and 5x5 body layers with output blocks of 6, 10 or 12 ----
 *
 * 8 tiles (32 columns) per vector; their lanes hold tiles 0 2 4 6 1 3 5 7, the order a
 * 4 x 4 transpose inside each 128-bit half gives, undone by the same transpose at the
 * output. Per group: the input transform fills V[64][in][8]; per block of O outputs the 64
 * products M[pos][O][8] = U[pos][O][in] x V[pos][in][8], then the output transform. Every
 * tile's arithmetic is the same whatever lane or group it is in. */

/* 4 x 4 transpose inside each 128-bit half of (r0, r1, r2, r3). */
#define TT__NET_WINO4_T4(r0, r1, r2, r3)                                                           \
  do {                                                                                             \
    __m256 t0_ = _mm256_unpacklo_ps(r0, r1), t1_ = _mm256_unpackhi_ps(r0, r1);                     \
    __m256 t2_ = _mm256_unpacklo_ps(r2, r3), t3_ = _mm256_unpackhi_ps(r2, r3);                     \
    r0 = _mm256_shuffle_ps(t0_, t2_, 0x44);                                                        \
    r1 = _mm256_shuffle_ps(t0_, t2_, 0xEE);                                                        \
    r2 = _mm256_shuffle_ps(t1_, t3_, 0x44);                                                        \
    r3 = _mm256_shuffle_ps(t1_, t3_, 0xEE);                                                        \
  } while (0)

/* B^T of one 8-vector (rows: -1 0 21/4 0 -21/4 0 1 0 / 0 1 1 -17/4 -17/4 1 1 0 /
 * 0 -1 1 17/4 -17/4 -1 1 0 / 0 1/2 1/4 -5/2 -5/4 2 1 0 / 0 -1/2 1/4 5/2 -5/4 -2 1 0 /
 * 0 2 4 -5/2 -5 1/2 1 0 / 0 -2 4 5/2 -5 -1/2 1 0 / 0 -1 0 21/4 0 -21/4 0 1), the even and
 * odd halves of each +-pair computed once. */
TT__NET_AI void tt__net_wino4_bt(const __m256 d[8], __m256 v[8]) {
  const __m256 c21 = _mm256_set1_ps(5.25f), c17 = _mm256_set1_ps(4.25f);
  v[0] = _mm256_add_ps(_mm256_sub_ps(d[6], d[0]), _mm256_mul_ps(_mm256_sub_ps(d[2], d[4]), c21));
  v[7] = _mm256_add_ps(_mm256_sub_ps(d[7], d[1]), _mm256_mul_ps(_mm256_sub_ps(d[3], d[5]), c21));
  __m256 e1 = _mm256_fnmadd_ps(d[4], c17, _mm256_add_ps(d[2], d[6]));
  __m256 o1 = _mm256_fnmadd_ps(d[3], c17, _mm256_add_ps(d[1], d[5]));
  v[1] = _mm256_add_ps(e1, o1);
  v[2] = _mm256_sub_ps(e1, o1);
  __m256 e2 = _mm256_fmadd_ps(d[2], _mm256_set1_ps(0.25f),
                              _mm256_fnmadd_ps(d[4], _mm256_set1_ps(1.25f), d[6]));
  __m256 o2 = _mm256_fmadd_ps(
      d[1], _mm256_set1_ps(0.5f),
      _mm256_fmadd_ps(d[5], _mm256_set1_ps(2.0f), _mm256_mul_ps(d[3], _mm256_set1_ps(-2.5f))));
  v[3] = _mm256_add_ps(e2, o2);
  v[4] = _mm256_sub_ps(e2, o2);
  __m256 e3 = _mm256_fmadd_ps(d[2], _mm256_set1_ps(4.0f),
                              _mm256_fnmadd_ps(d[4], _mm256_set1_ps(5.0f), d[6]));
  __m256 o3 = _mm256_fmadd_ps(
      d[1], _mm256_set1_ps(2.0f),
      _mm256_fmadd_ps(d[5], _mm256_set1_ps(0.5f), _mm256_mul_ps(d[3], _mm256_set1_ps(-2.5f))));
  v[5] = _mm256_add_ps(e3, o3);
  v[6] = _mm256_sub_ps(e3, o3);
}

/* A^T of one 8-vector (rows 1 1 1 1 1 1 1 0 / 0 1 -1 2 -2 1/2 -1/2 0 / 0 1 1 4 4 1/4 1/4 0 /
 * 0 1 -1 8 -8 1/8 -1/8 1). */
TT__NET_AI void tt__net_wino4_at(const __m256 m[8], __m256 y[4]) {
  __m256 s1 = _mm256_add_ps(m[1], m[2]), d1 = _mm256_sub_ps(m[1], m[2]);
  __m256 s2 = _mm256_add_ps(m[3], m[4]), d2 = _mm256_sub_ps(m[3], m[4]);
  __m256 s3 = _mm256_add_ps(m[5], m[6]), d3 = _mm256_sub_ps(m[5], m[6]);
  y[0] = _mm256_add_ps(_mm256_add_ps(m[0], s1), _mm256_add_ps(s2, s3));
  y[1] = _mm256_fmadd_ps(d3, _mm256_set1_ps(0.5f), _mm256_fmadd_ps(d2, _mm256_set1_ps(2.0f), d1));
  y[2] = _mm256_fmadd_ps(s3, _mm256_set1_ps(0.25f), _mm256_fmadd_ps(s2, _mm256_set1_ps(4.0f), s1));
  y[3] = _mm256_add_ps(
      _mm256_fmadd_ps(d3, _mm256_set1_ps(0.125f), _mm256_fmadd_ps(d2, _mm256_set1_ps(8.0f), d1)),
      m[7]);
}

/* One group of 8P tiles (32P columns from xl), O outputs per block; P = 2 (16 tiles)
 * needs the 32 vector registers of AVX-512VL for its 2 O accumulators. */
TT__NET_AI void tt__net_wino4_group_t(const tt__net_wino4_args *a, uint32_t xl, const int O,
                                      const int P) {
  const uint32_t I = a->in;
  const int T = 8 * P;
  float *V = a->vbuf, *M = a->mbuf, *E = a->ebuf;
  /* lane shifts by one tile in the 0 2 4 6 1 3 5 7 order: the tile before / after */
  const __m256i prev = _mm256_setr_epi32(0, 4, 5, 6, 0, 1, 2, 3);
  const __m256i next = _mm256_setr_epi32(4, 5, 6, 7, 1, 2, 3, 0);
  for (uint32_t c = 0; c < I; c++)
#pragma GCC unroll 2
    for (int j = 0; j < P; j++) {
#pragma GCC unroll 8
      for (int i = 0; i < 8; i++) {
        const float *q = a->rowp[i] + c * a->cs + TT__NET_COL_OFF + a->x0 + xl + 32 * j;
        __m256 r0 = _mm256_loadu_ps(q), r1 = _mm256_loadu_ps(q + 8), r2 = _mm256_loadu_ps(q + 16),
               r3 = _mm256_loadu_ps(q + 24);
        TT__NET_WINO4_T4(r0, r1, r2, r3); /* rk: column 4t + k of tile t */
        __m256 d[8];
        d[0] = _mm256_blend_ps(_mm256_permutevar8x32_ps(r2, prev), _mm256_broadcast_ss(q - 2), 1);
        d[1] = _mm256_blend_ps(_mm256_permutevar8x32_ps(r3, prev), _mm256_broadcast_ss(q - 1), 1);
        d[2] = r0, d[3] = r1, d[4] = r2, d[5] = r3;
        d[6] =
            _mm256_blend_ps(_mm256_permutevar8x32_ps(r0, next), _mm256_broadcast_ss(q + 32), 0x80);
        d[7] =
            _mm256_blend_ps(_mm256_permutevar8x32_ps(r1, next), _mm256_broadcast_ss(q + 33), 0x80);
        __m256 e[8];
        tt__net_wino4_bt(d, e); /* along the row: E[i][s] */
#pragma GCC unroll 8
        for (int s2 = 0; s2 < 8; s2++) _mm256_store_ps(E + (i * 8 + s2) * 8, e[s2]);
      }
#pragma GCC unroll 8
      for (int s2 = 0; s2 < 8; s2++) {
        __m256 col[8], v[8];
#pragma GCC unroll 8
        for (int i = 0; i < 8; i++) col[i] = _mm256_load_ps(E + (i * 8 + s2) * 8);
        tt__net_wino4_bt(col, v); /* along the column: V[r][s2] */
#pragma GCC unroll 8
        for (int r = 0; r < 8; r++)
          _mm256_store_ps(V + ((size_t)(r * 8 + s2) * I + c) * T + 8 * j, v[r]);
      }
    }
  for (uint32_t ob = 0; ob < a->nob; ob++) {
    const float *u = a->u + (size_t)ob * TT__NET_WINO4_POS * I * O;
    for (uint32_t pos = 0; pos < TT__NET_WINO4_POS; pos++) {
      __m256 acc[12][2];
#pragma GCC unroll 12
      for (int o = 0; o < O; o++)
#pragma GCC unroll 2
        for (int j = 0; j < P; j++) acc[o][j] = _mm256_setzero_ps();
      const float *vp = V + (size_t)pos * I * T;
      for (uint32_t c = 0; c < I; c++) {
        __m256 in[2];
#pragma GCC unroll 2
        for (int j = 0; j < P; j++) in[j] = _mm256_load_ps(vp + 8 * j);
#pragma GCC unroll 12
        for (int o = 0; o < O; o++) {
          __m256 wv = _mm256_broadcast_ss(u + o);
#pragma GCC unroll 2
          for (int j = 0; j < P; j++) acc[o][j] = _mm256_fmadd_ps(in[j], wv, acc[o][j]);
        }
        u += O;
        vp += T;
      }
#pragma GCC unroll 12
      for (int o = 0; o < O; o++)
#pragma GCC unroll 2
        for (int j = 0; j < P; j++)
          _mm256_store_ps(M + ((size_t)pos * O + o) * T + 8 * j, acc[o][j]);
    }
    for (int o = 0; o < O; o++) {
      uint32_t oc = ob * (uint32_t)O + (uint32_t)o;
      if (oc >= a->out) break;
      __m256 bias = _mm256_broadcast_ss(a->b + oc);
#pragma GCC unroll 2
      for (int j = 0; j < P; j++) {
        __m256 t[8][4];
#pragma GCC unroll 8
        for (int i = 0; i < 8; i++) {
          __m256 m8[8];
#pragma GCC unroll 8
          for (int k = 0; k < 8; k++)
            m8[k] = _mm256_load_ps(M + ((size_t)(i * 8 + k) * O + o) * T + 8 * j);
          tt__net_wino4_at(m8, t[i]); /* along the row: tile columns 0..3 */
        }
        __m256 y[4][4]; /* [row][column] */
#pragma GCC unroll 4
        for (int k = 0; k < 4; k++) {
          __m256 col[8], yy[4];
#pragma GCC unroll 8
          for (int i = 0; i < 8; i++) col[i] = t[i][k];
          tt__net_wino4_at(col, yy); /* along the column: output rows 0..3 */
#pragma GCC unroll 4
          for (int r = 0; r < 4; r++) {
            y[r][k] = _mm256_add_ps(yy[r], bias);
            if (a->relu) y[r][k] = _mm256_max_ps(y[r][k], _mm256_setzero_ps());
          }
        }
#pragma GCC unroll 4
        for (int r = 0; r < 4; r++) {
          TT__NET_WINO4_T4(y[r][0], y[r][1], y[r][2], y[r][3]); /* back to column order */
          float *d = a->dst[r] + oc * a->dcs + xl + 32 * j;
          for (int k = 0; k < 4; k++) _mm256_storeu_ps(d + 8 * k, y[r][k]);
        }
      }
    }
  }
}

/* All groups of a chunk; output blocks of 10 (the kernel layer's 50 outputs), 12 or 6
 * (12- and 6-channel body layers). */
#define TT__NET_WINO4_CASE(O_)                                                                     \
  case O_:                                                                                         \
    for (uint32_t xl = 0; xl < a->n;) {                                                            \
      if (wide && a->n - xl >= 64) tt__net_wino4_group_t(a, xl, O_, 2), xl += 64;                  \
      else tt__net_wino4_group_t(a, xl, O_, 1), xl += 32;                                          \
    }                                                                                              \
    break;
TT__NET_AI void tt__net_wino4_dispatch(const tt__net_wino4_args *a, uint32_t oblk, const int wide) {
  switch (oblk) {
    TT__NET_WINO4_CASE(6)
    TT__NET_WINO4_CASE(10)
    TT__NET_WINO4_CASE(12)
  default: break;
  }
}

#if TT__NET_HAVE_AVX512
/* ---- F(4x4, 5x5) on 16-lane (AVX-512) vectors ---- */

/* With AVX-512 the same tiles run 16 per vector (64 columns): twice the FMAs per
 * instruction of the 8-lane code above (this machine's zmm peak is twice its ymm one). The
 * lanes hold tiles 0 4 8 12 1 5 9 13 2 6 10 14 3 7 11 15 (the 4 x 4 transpose inside each
 * 128-bit quarter of 4 vectors), undone at the output. Every step mirrors the 8-lane
 * code's operation for operation (same expressions, so the same contractions and
 * roundings): a tile's results do not depend on which of the two codes ran it, so column
 * tiles and chunk tails that mix them stay bit-identical. */
#  define TT__NET_WINO4_T4_16(r0, r1, r2, r3)                                                      \
    do {                                                                                           \
      __m512 t0_ = _mm512_unpacklo_ps(r0, r1), t1_ = _mm512_unpackhi_ps(r0, r1);                   \
      __m512 t2_ = _mm512_unpacklo_ps(r2, r3), t3_ = _mm512_unpackhi_ps(r2, r3);                   \
      r0 = _mm512_shuffle_ps(t0_, t2_, 0x44);                                                      \
      r1 = _mm512_shuffle_ps(t0_, t2_, 0xEE);                                                      \
      r2 = _mm512_shuffle_ps(t1_, t3_, 0x44);                                                      \
      r3 = _mm512_shuffle_ps(t1_, t3_, 0xEE);                                                      \
    } while (0)

/* tt__net_wino4_bt on 16 lanes. */
TT__NET_AI void tt__net_wino4_bt16(const __m512 d[8], __m512 v[8]) {
  const __m512 c21 = _mm512_set1_ps(5.25f), c17 = _mm512_set1_ps(4.25f);
  v[0] = _mm512_add_ps(_mm512_sub_ps(d[6], d[0]), _mm512_mul_ps(_mm512_sub_ps(d[2], d[4]), c21));
  v[7] = _mm512_add_ps(_mm512_sub_ps(d[7], d[1]), _mm512_mul_ps(_mm512_sub_ps(d[3], d[5]), c21));
  __m512 e1 = _mm512_fnmadd_ps(d[4], c17, _mm512_add_ps(d[2], d[6]));
  __m512 o1 = _mm512_fnmadd_ps(d[3], c17, _mm512_add_ps(d[1], d[5]));
  v[1] = _mm512_add_ps(e1, o1);
  v[2] = _mm512_sub_ps(e1, o1);
  __m512 e2 = _mm512_fmadd_ps(d[2], _mm512_set1_ps(0.25f),
                              _mm512_fnmadd_ps(d[4], _mm512_set1_ps(1.25f), d[6]));
  __m512 o2 = _mm512_fmadd_ps(
      d[1], _mm512_set1_ps(0.5f),
      _mm512_fmadd_ps(d[5], _mm512_set1_ps(2.0f), _mm512_mul_ps(d[3], _mm512_set1_ps(-2.5f))));
  v[3] = _mm512_add_ps(e2, o2);
  v[4] = _mm512_sub_ps(e2, o2);
  __m512 e3 = _mm512_fmadd_ps(d[2], _mm512_set1_ps(4.0f),
                              _mm512_fnmadd_ps(d[4], _mm512_set1_ps(5.0f), d[6]));
  __m512 o3 = _mm512_fmadd_ps(
      d[1], _mm512_set1_ps(2.0f),
      _mm512_fmadd_ps(d[5], _mm512_set1_ps(0.5f), _mm512_mul_ps(d[3], _mm512_set1_ps(-2.5f))));
  v[5] = _mm512_add_ps(e3, o3);
  v[6] = _mm512_sub_ps(e3, o3);
}

/* tt__net_wino4_at on 16 lanes. */
TT__NET_AI void tt__net_wino4_at16(const __m512 m[8], __m512 y[4]) {
  __m512 s1 = _mm512_add_ps(m[1], m[2]), d1 = _mm512_sub_ps(m[1], m[2]);
  __m512 s2 = _mm512_add_ps(m[3], m[4]), d2 = _mm512_sub_ps(m[3], m[4]);
  __m512 s3 = _mm512_add_ps(m[5], m[6]), d3 = _mm512_sub_ps(m[5], m[6]);
  y[0] = _mm512_add_ps(_mm512_add_ps(m[0], s1), _mm512_add_ps(s2, s3));
  y[1] = _mm512_fmadd_ps(d3, _mm512_set1_ps(0.5f), _mm512_fmadd_ps(d2, _mm512_set1_ps(2.0f), d1));
  y[2] = _mm512_fmadd_ps(s3, _mm512_set1_ps(0.25f), _mm512_fmadd_ps(s2, _mm512_set1_ps(4.0f), s1));
  y[3] = _mm512_add_ps(
      _mm512_fmadd_ps(d3, _mm512_set1_ps(0.125f), _mm512_fmadd_ps(d2, _mm512_set1_ps(8.0f), d1)),
      m[7]);
}

/* One group of 16 tiles (64 columns from xl), O outputs per block: tt__net_wino4_group_t's steps
 * with T = 16 lanes. */
TT__NET_AI void tt__net_wino4_group16_t(const tt__net_wino4_args *a, uint32_t xl, const int O) {
  const uint32_t I = a->in;
  float *V = a->vbuf, *M = a->mbuf, *E = a->ebuf;
  /* lane shifts by one tile in the lane order above: the tile before / after */
  const __m512i prev = _mm512_setr_epi32(0, 12, 13, 14, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11);
  const __m512i next = _mm512_setr_epi32(4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 1, 2, 3, 0);
  for (uint32_t c = 0; c < I; c++) {
#  pragma GCC unroll 8
    for (int i = 0; i < 8; i++) {
      const float *q = a->rowp[i] + c * a->cs + TT__NET_COL_OFF + a->x0 + xl;
      __m512 r0 = _mm512_loadu_ps(q), r1 = _mm512_loadu_ps(q + 16), r2 = _mm512_loadu_ps(q + 32),
             r3 = _mm512_loadu_ps(q + 48);
      TT__NET_WINO4_T4_16(r0, r1, r2, r3); /* rk: column 4t + k of tile t */
      __m512 d[8];
      d[0] = _mm512_mask_blend_ps(0x0001, _mm512_permutexvar_ps(prev, r2), _mm512_set1_ps(q[-2]));
      d[1] = _mm512_mask_blend_ps(0x0001, _mm512_permutexvar_ps(prev, r3), _mm512_set1_ps(q[-1]));
      d[2] = r0, d[3] = r1, d[4] = r2, d[5] = r3;
      d[6] = _mm512_mask_blend_ps(0x8000, _mm512_permutexvar_ps(next, r0), _mm512_set1_ps(q[64]));
      d[7] = _mm512_mask_blend_ps(0x8000, _mm512_permutexvar_ps(next, r1), _mm512_set1_ps(q[65]));
      __m512 e[8];
      tt__net_wino4_bt16(d, e); /* along the row: E[i][s] */
#  pragma GCC unroll 8
      for (int s2 = 0; s2 < 8; s2++) _mm512_store_ps(E + (i * 8 + s2) * 16, e[s2]);
    }
#  pragma GCC unroll 8
    for (int s2 = 0; s2 < 8; s2++) {
      __m512 col[8], v[8];
#  pragma GCC unroll 8
      for (int i = 0; i < 8; i++) col[i] = _mm512_load_ps(E + (i * 8 + s2) * 16);
      tt__net_wino4_bt16(col, v); /* along the column: V[r][s2] */
#  pragma GCC unroll 8
      for (int r = 0; r < 8; r++) _mm512_store_ps(V + ((size_t)(r * 8 + s2) * I + c) * 16, v[r]);
    }
  }
  for (uint32_t ob = 0; ob < a->nob; ob++) {
    const float *u = a->u + (size_t)ob * TT__NET_WINO4_POS * I * O;
    for (uint32_t pos = 0; pos < TT__NET_WINO4_POS; pos++) {
      __m512 acc[12];
#  pragma GCC unroll 12
      for (int o = 0; o < O; o++) acc[o] = _mm512_setzero_ps();
      const float *vp = V + (size_t)pos * I * 16;
      for (uint32_t c = 0; c < I; c++) {
        __m512 in = _mm512_load_ps(vp);
#  pragma GCC unroll 12
        for (int o = 0; o < O; o++) acc[o] = _mm512_fmadd_ps(in, _mm512_set1_ps(u[o]), acc[o]);
        u += O;
        vp += 16;
      }
#  pragma GCC unroll 12
      for (int o = 0; o < O; o++) _mm512_store_ps(M + ((size_t)pos * O + o) * 16, acc[o]);
    }
    for (int o = 0; o < O; o++) {
      uint32_t oc = ob * (uint32_t)O + (uint32_t)o;
      if (oc >= a->out) break;
      __m512 bias = _mm512_set1_ps(a->b[oc]);
      __m512 t[8][4];
#  pragma GCC unroll 8
      for (int i = 0; i < 8; i++) {
        __m512 m8[8];
#  pragma GCC unroll 8
        for (int k = 0; k < 8; k++) m8[k] = _mm512_load_ps(M + ((size_t)(i * 8 + k) * O + o) * 16);
        tt__net_wino4_at16(m8, t[i]); /* along the row: tile columns 0..3 */
      }
      __m512 y[4][4]; /* [row][column] */
#  pragma GCC unroll 4
      for (int k = 0; k < 4; k++) {
        __m512 col[8], yy[4];
#  pragma GCC unroll 8
        for (int i = 0; i < 8; i++) col[i] = t[i][k];
        tt__net_wino4_at16(col, yy); /* along the column: output rows 0..3 */
#  pragma GCC unroll 4
        for (int r = 0; r < 4; r++) {
          y[r][k] = _mm512_add_ps(yy[r], bias);
          if (a->relu) y[r][k] = _mm512_max_ps(y[r][k], _mm512_setzero_ps());
        }
      }
#  pragma GCC unroll 4
      for (int r = 0; r < 4; r++) {
        TT__NET_WINO4_T4_16(y[r][0], y[r][1], y[r][2], y[r][3]); /* back to column order */
        float *d = a->dst[r] + oc * a->dcs + xl;
        for (int k = 0; k < 4; k++) _mm512_storeu_ps(d + 16 * k, y[r][k]);
      }
    }
  }
}

/* All groups of a chunk on AVX-512: 64 columns per 16-lane group, a 32-column tail by the
 * 8-lane code. */
#  define TT__NET_WINO4_CASE16(O_)                                                                 \
  case O_:                                                                                         \
    for (uint32_t xl = 0; xl < a->n;) {                                                            \
      if (a->n - xl >= 64) tt__net_wino4_group16_t(a, xl, O_), xl += 64;                           \
      else tt__net_wino4_group_t(a, xl, O_, 1), xl += 32;                                          \
    }                                                                                              \
    break;
TT__NET_AI void tt__net_wino4_dispatch16(const tt__net_wino4_args *a, uint32_t oblk) {
  switch (oblk) {
    TT__NET_WINO4_CASE16(6)
    TT__NET_WINO4_CASE16(10)
    TT__NET_WINO4_CASE16(12)
  default: break;
  }
}
#endif

void TT__NET_K(wino)(const tt__net_wino_args *a, uint32_t oblk) {
  tt__net_wino_dispatch(a, oblk, TT__NET_HAVE_AVX512); /* 32 registers: 16 tiles per group */
}

void TT__NET_K(wino4)(const tt__net_wino4_args *a, uint32_t oblk) {
#if TT__NET_HAVE_AVX512
  tt__net_wino4_dispatch16(a, oblk);
#else
  tt__net_wino4_dispatch(a, oblk, 0);
#endif
}
