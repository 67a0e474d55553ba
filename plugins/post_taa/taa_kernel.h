/* post_taa: what the fast path's kernel sources (taa_kernel_*.c) share. meson.build
 * compiles each of them once per instruction set, with TT__NET_ISA naming the copy:
 *   generic  no -m flags (x86-64: SSE2; elsewhere the target's baseline)
 *   avx2     -mavx2 -mfma
 *   avx512   -mavx2 -mfma -mavx512f -mavx512vl (16-lane code, 32 vector registers)
 * by gcc and clang alike (the sanitizer build runs all three). A copy's functions are named
 * after it (TT__NET_K), so the three link side by side; the driver reaches them only
 * through the copy's table (taa_kernel_table.c), chosen at run time where the CPU reports
 * the features, so no AVX instruction runs on an older CPU.
 *
 * Vectors are GCC vector extensions (tt__net_v8f: 8 floats) for the portable code, with
 * <immintrin.h> intrinsics where x86 has a better instruction; TT__NET_HAVE_AVX2 and
 * TT__NET_HAVE_AVX512 say which code a copy holds. The 16-lane (AVX-512) code repeats the
 * 8-lane code's operations per lane in the same order (same contractions into FMA, same
 * roundings), so the avx512 and avx2 copies give the same bits (tests/taa_net.c). */
#ifndef TT_POST_TAA_KERNEL_H
#define TT_POST_TAA_KERNEL_H

#include <math.h>
#include <string.h>

#include "taa_fast.h"

#ifndef TT__NET_ISA
#  error "compile with -DTT__NET_ISA=generic, avx2 or avx512 (see meson.build)"
#endif
#define TT__NET_CAT3(a, b, c) a##b##c
#define TT__NET_CAT(a, b, c) TT__NET_CAT3(a, b, c)
/* This copy's name for kernel `name`: tt__net_<name>_<isa>. */
#define TT__NET_K(name) TT__NET_CAT(tt__net_##name, _, TT__NET_ISA)

#if defined(__x86_64__) && defined(__AVX2__) && defined(__FMA__)
#  define TT__NET_HAVE_AVX2 1
#  include <immintrin.h>
#else
#  define TT__NET_HAVE_AVX2 0
#endif
#if TT__NET_HAVE_AVX2 && defined(__AVX512F__) && defined(__AVX512VL__)
#  define TT__NET_HAVE_AVX512 1
#else
#  define TT__NET_HAVE_AVX512 0
#endif

/* This copy's kernels (the table's entries). */
void TT__NET_K(conv)(const tt__net_conv_args *a);
void TT__NET_K(mix)(const tt__net_mix_args *a);
void TT__NET_K(input_rows)(void *ctx, uint32_t y0, uint32_t y1);
#if TT__NET_HAVE_AVX2
void TT__NET_K(wino)(const tt__net_wino_args *a, uint32_t oblk);
void TT__NET_K(wino4)(const tt__net_wino4_args *a, uint32_t oblk);
#endif

#pragma GCC diagnostic ignored                                                                     \
    "-Wpsabi" /* tt__net_v8f helpers are always inlined (gcc and clang) */
typedef float tt__net_v8f __attribute__((vector_size(32)));
typedef float tt__net_v8fu __attribute__((vector_size(32), aligned(4)));
typedef int32_t tt__net_v8i __attribute__((vector_size(32)));

/* Always inlined (the templates' int parameters fold to constants); `unused`: a copy keeps
 * some it does not call (the AVX-512 copy runs the 16-lane forms of the 8-lane ones). */
#define TT__NET_AI static inline __attribute__((always_inline, unused))
/* A constant shuffle of the 16 lanes a:b into 8: GCC spells it __builtin_shuffle, clang
 * __builtin_shufflevector; same code either way. */
#if defined(__clang__)
#  define TT__NET_WINO_SHUF8(a, b, ...) __builtin_shufflevector(a, b, __VA_ARGS__)
#else
#  define TT__NET_WINO_SHUF8(a, b, ...) __builtin_shuffle(a, b, (tt__net_v8i){__VA_ARGS__})
#endif

TT__NET_AI tt__net_v8f tt__net_vsplat(float f) { return (tt__net_v8f){f, f, f, f, f, f, f, f}; }

TT__NET_AI tt__net_v8f tt__net_vsel(tt__net_v8i mask, tt__net_v8f a, tt__net_v8f b) {
  tt__net_v8i ai, bi;
  memcpy(&ai, &a, sizeof ai);
  memcpy(&bi, &b, sizeof bi);
  ai = (ai & mask) | (bi & ~mask);
  memcpy(&a, &ai, sizeof a);
  return a;
}

TT__NET_AI tt__net_v8f tt__net_vmax(tt__net_v8f a, tt__net_v8f b) {
  return tt__net_vsel(a > b, a, b);
}
TT__NET_AI tt__net_v8f tt__net_vmin(tt__net_v8f a, tt__net_v8f b) {
  return tt__net_vsel(a < b, a, b);
}
TT__NET_AI tt__net_v8f tt__net_vload(const float *p) { return *(const tt__net_v8fu *)p; }
TT__NET_AI void tt__net_vstore(float *p, tt__net_v8f v) { *(tt__net_v8fu *)p = v; }

/* exp(x) for x <= 0: 2^n * p(r), degree-6 polynomial (rel. error ~2e-7). */
TT__NET_AI tt__net_v8f tt__net_vexp_neg(tt__net_v8f x) {
  x = tt__net_vmax(x, tt__net_vsplat(-87.0f));
  tt__net_v8f t = x * 1.44269504088896341f;
  tt__net_v8f n = (t + 12582912.0f) - 12582912.0f;
  tt__net_v8f r = x - n * 0.693145751953125f - n * 1.428606765330187045e-06f;
  tt__net_v8f p = r * (1.0f / 720.0f) + 1.0f / 120.0f;
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  tt__net_v8i e = (__builtin_convertvector(n, tt__net_v8i) + 127) << 23;
  tt__net_v8f scale;
  memcpy(&scale, &e, sizeof scale);
  return p * scale;
}

/* 8 x 8 transpose: t[l][c] = v[c][l] (channel vectors of 8 pixels <-> the pixels' 8
 * channels). */
TT__NET_AI void tt__net_t8x8(const tt__net_v8f v[8], tt__net_v8f t[8]) {
  tt__net_v8f a[8], b[8];
#pragma GCC unroll 4
  for (int k = 0; k < 8; k += 2) { /* a[k]: lanes 0 1 | 4 5 of rows k, k + 1 interleaved */
    a[k] = TT__NET_WINO_SHUF8(v[k], v[k + 1], 0, 8, 1, 9, 4, 12, 5, 13);
    a[k + 1] = TT__NET_WINO_SHUF8(v[k], v[k + 1], 2, 10, 3, 11, 6, 14, 7, 15);
  }
#pragma GCC unroll 2
  for (int k = 0; k < 8; k += 4) /* b[k + i]: lanes (0 2 1 3)[i] | + 4 of rows k..k + 3 */
#pragma GCC unroll 2
    for (int j = 0; j < 2; j++) {
      b[k + j] = TT__NET_WINO_SHUF8(a[k + j], a[k + j + 2], 0, 1, 8, 9, 4, 5, 12, 13);
      b[k + j + 2] = TT__NET_WINO_SHUF8(a[k + j], a[k + j + 2], 2, 3, 10, 11, 6, 7, 14, 15);
    }
  static const int lane[4] = {0, 2, 1, 3};
#pragma GCC unroll 4
  for (int k = 0; k < 4; k++) {
    t[lane[k]] = TT__NET_WINO_SHUF8(b[k], b[k + 4], 0, 1, 2, 3, 8, 9, 10, 11);
    t[lane[k] + 4] = TT__NET_WINO_SHUF8(b[k], b[k + 4], 4, 5, 6, 7, 12, 13, 14, 15);
  }
}

#if TT__NET_HAVE_AVX512
/* 16-lane vectors (AVX-512). */
typedef float tt__net_v16f __attribute__((vector_size(64)));
typedef float tt__net_v16fu __attribute__((vector_size(64), aligned(4)));
typedef int32_t tt__net_v16i __attribute__((vector_size(64)));
#endif

#endif
