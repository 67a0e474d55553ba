/* post_taa kernels: the direct convolutions (every layer shape), compiled once per
 * instruction set (taa_kernel.h). They vectorise over pixels: 8 or 16 (8-lane vectors) or
 * 16 or 32 (AVX-512: 16-lane vectors, whose FMA peak is twice the 8-lane one on an AVX-512
 * Xeon) neighbouring output pixels times a block of 6 to 12 output channels accumulate in
 * registers; each weight is a broadcast operand, each input vector serves the whole block.
 * Kernel size and block are compile-time constants of each case. */
#include "taa_kernel.h"

TT__NET_AI void tt__net_conv_rows_t(const tt__net_conv_args *a, const int K, const int O,
                                    const int P) {
  const uint32_t I = a->in, r = (uint32_t)K / 2;
  for (uint32_t ob = 0; ob < a->nob; ob++) {
    const float *wb = a->w + (size_t)ob * I * K * K * O;
    const float *bb = a->b + (size_t)ob * O;
    for (uint32_t xl = 0; xl < a->n; xl += 8u * P) {
      tt__net_v8f acc[12][2];
#pragma GCC unroll 12
      for (int o = 0; o < O; o++)
#pragma GCC unroll 2
        for (int j = 0; j < P; j++) acc[o][j] = tt__net_vsplat(bb[o]);
      const float *wp = wb;
      size_t col = TT__NET_COL_OFF + a->x0 + xl - r;
      for (uint32_t c = 0; c < I; c++) {
#pragma GCC unroll 5
        for (int ky = 0; ky < K; ky++) {
          const float *p = a->rowp[ky] + c * a->cs + col;
#pragma GCC unroll 5
          for (int kx = 0; kx < K; kx++) {
            tt__net_v8f in[2];
#pragma GCC unroll 2
            for (int j = 0; j < P; j++) in[j] = tt__net_vload(p + kx + 8 * j);
#pragma GCC unroll 12
            for (int o = 0; o < O; o++) {
              float wv = wp[o];
#pragma GCC unroll 2
              for (int j = 0; j < P; j++) acc[o][j] += in[j] * wv;
            }
            wp += O;
          }
        }
      }
#pragma GCC unroll 12
      for (int o = 0; o < O; o++) {
        uint32_t oc = ob * O + (uint32_t)o;
        if (oc >= a->out) break;
        float *d = a->dst + oc * a->dcs + xl;
#pragma GCC unroll 2
        for (int j = 0; j < P; j++) {
          tt__net_v8f v = acc[o][j];
          if (a->relu) v = tt__net_vsel(v > tt__net_vsplat(0.0f), v, tt__net_vsplat(0.0f));
          tt__net_vstore(d + 8 * j, v);
        }
      }
    }
  }
}

/* Dispatch on (output block, kernel size) to constant-folded loops; 16 pixels per block for
 * blocks of 6 (two vectors of accumulators fit the 16 registers), else 8. */
#define TT__NET_CONV_CASE(O_, K_)                                                                  \
  case (O_)*8 + (K_): tt__net_conv_rows_t(a, K_, O_, (O_) <= 6 ? 2 : 1); break;
TT__NET_AI void tt__net_conv_rows_dispatch(const tt__net_conv_args *a) {
  /* The macro cases form a table, one output block per row. */
  // clang-format off
  switch (a->oblk * 8 + a->ksize) {
    TT__NET_CONV_CASE(6, 1) TT__NET_CONV_CASE(6, 3) TT__NET_CONV_CASE(6, 5)
    TT__NET_CONV_CASE(8, 1) TT__NET_CONV_CASE(8, 3) TT__NET_CONV_CASE(8, 5)
    TT__NET_CONV_CASE(10, 1) TT__NET_CONV_CASE(10, 3) TT__NET_CONV_CASE(10, 5)
    TT__NET_CONV_CASE(12, 1) TT__NET_CONV_CASE(12, 3) TT__NET_CONV_CASE(12, 5)
    default: break;
  }
  // clang-format on
}

#if TT__NET_HAVE_AVX512
/* tt__net_conv_rows_t on 16-lane vectors (AVX-512): 16 or 32 output pixels per block, the same
 * multiply-adds per pixel in the same order as the 8-lane code (bit-identical results).
 * One block of 16 P output pixels from column xl, output block ob. */
TT__NET_AI void tt__net_conv16_block(const tt__net_conv_args *a, uint32_t ob, uint32_t xl,
                                     const int K, const int O, const int P) {
  const uint32_t I = a->in, r = (uint32_t)K / 2;
  const float *wp = a->w + (size_t)ob * I * K * K * O;
  const float *bb = a->b + (size_t)ob * O;
  tt__net_v16f acc[12][2];
#  pragma GCC unroll 12
  for (int o = 0; o < O; o++)
#  pragma GCC unroll 2
    for (int j = 0; j < P; j++) acc[o][j] = (tt__net_v16f)_mm512_set1_ps(bb[o]);
  size_t col = TT__NET_COL_OFF + a->x0 + xl - r;
  for (uint32_t c = 0; c < I; c++) {
    if (a->pf) {
      const float *q = a->rowp[K - 1] + c * a->cs + col + a->pf;
#  pragma GCC unroll 3
      for (int k = 0; k < P + 1; k++) _mm_prefetch((const char *)(q + 16 * k), _MM_HINT_T1);
    }
#  pragma GCC unroll 5
    for (int ky = 0; ky < K; ky++) {
      const float *q = a->rowp[ky] + c * a->cs + col;
#  pragma GCC unroll 5
      for (int kx = 0; kx < K; kx++) {
        tt__net_v16f in[2];
#  pragma GCC unroll 2
        for (int j = 0; j < P; j++) in[j] = *(const tt__net_v16fu *)(q + kx + 16 * j);
#  pragma GCC unroll 12
        for (int o = 0; o < O; o++) {
          float wv = wp[o];
#  pragma GCC unroll 2
          for (int j = 0; j < P; j++) acc[o][j] += in[j] * wv;
        }
        wp += O;
      }
    }
  }
#  pragma GCC unroll 12
  for (int o = 0; o < O; o++) {
    uint32_t oc = ob * O + (uint32_t)o;
    if (oc >= a->out) break;
    float *d = a->dst + oc * a->dcs + xl;
#  pragma GCC unroll 2
    for (int j = 0; j < P; j++) {
      tt__net_v16f v = acc[o][j];
      if (a->relu) v = (tt__net_v16f)_mm512_max_ps((__m512)v, _mm512_setzero_ps()); /* NaN -> 0 */
      *(tt__net_v16fu *)(d + 16 * j) = v;
    }
  }
}

/* 32 pixels per block while more than 16 remain, then 16 (n rounded up to 16, as the
 * 8-lane code's blocks of 16 round it). */
TT__NET_AI void tt__net_conv_rows16_t(const tt__net_conv_args *a, const int K, const int O) {
  for (uint32_t ob = 0; ob < a->nob; ob++)
    for (uint32_t xl = 0; xl < a->n;) {
      if (a->n - xl > 16) tt__net_conv16_block(a, ob, xl, K, O, 2), xl += 32;
      else tt__net_conv16_block(a, ob, xl, K, O, 1), xl += 16;
    }
}

#  define TT__NET_CONV16_CASE(O_, K_)                                                              \
  case (O_)*8 + (K_): tt__net_conv_rows16_t(a, K_, O_); break;
TT__NET_AI void tt__net_conv_rows16_dispatch(const tt__net_conv_args *a) {
  /* The macro cases form a table, one output block per row. */
  // clang-format off
  switch (a->oblk * 8 + a->ksize) {
    TT__NET_CONV16_CASE(6, 1) TT__NET_CONV16_CASE(6, 3) TT__NET_CONV16_CASE(6, 5)
    TT__NET_CONV16_CASE(8, 1) TT__NET_CONV16_CASE(8, 3) TT__NET_CONV16_CASE(8, 5)
    TT__NET_CONV16_CASE(10, 1) TT__NET_CONV16_CASE(10, 3) TT__NET_CONV16_CASE(10, 5)
    TT__NET_CONV16_CASE(12, 1) TT__NET_CONV16_CASE(12, 3) TT__NET_CONV16_CASE(12, 5)
    default: break;
  }
  // clang-format on
}
#endif

void TT__NET_K(conv)(const tt__net_conv_args *a) {
#if TT__NET_HAVE_AVX512
  tt__net_conv_rows16_dispatch(a);
#else
  tt__net_conv_rows_dispatch(a);
#endif
}
