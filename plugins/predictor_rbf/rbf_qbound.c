/* The argmax's approximate Q of one candidate (rbf_qbound.h), compiled once per instruction
 * set by meson.build (TT__RBF_ISA: base, the target's baseline, SSE2 on x86-64; avx2, with FMA,
 * on x86-64). Everything here is static except the copy's table (tt__rbf_kernels_<isa>), so the
 * copies cannot be mixed up by the linker; rbf_argmax.c picks one at run time, only where
 * the CPU reports the features.
 *
 * The fine level (every copy): plain C loops that the compiler vectorises at -O3: an
 * elementwise pass (sqrt and a polynomial exp, no libm call) and a reduction into 8 explicit
 * partial sums (a reduction into one accumulator is not vectorised without -ffast-math).
 * The coarse level (the AVX2 copy only): single precision, 8 lanes of AVX2+FMA.
 *
 * The result may differ between the copies and from tt__rbf_q_parts: the caller bounds the
 * difference (rbf_argmax.h) and recomputes with tt__rbf_q_parts itself the candidates that the
 * bound cannot separate, so the answer never depends on which copy ran. */
#include "rbf_qbound.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#ifndef TT__RBF_ISA
#  error "compile with -DRBF_ISA=base or avx2"
#endif
#define TT__RBF_CAT2(a, b) a##b
#define TT__RBF_CAT(a, b) TT__RBF_CAT2(a, b)
#if defined(__x86_64__) && defined(__AVX2__) && defined(__FMA__)
#  define TT__RBF_COPY_AVX2 1
#  include <immintrin.h>
#else
#  define TT__RBF_COPY_AVX2 0
#endif

/* exp(x) for x <= 0, relative error below 1e-14 for x >= -708 (x below is taken as -708: the
 * result then is 3.3e-308 or less, an absolute error the caller's bound includes). Cody-Waite
 * reduction x = k ln2 + r, |r| <= ln2/2 (k from the 1.5 * 2^52 rounding trick, so it is an
 * integer in the low bits of t), Taylor polynomial of degree 11 (remainder r^12/12! < 7e-15),
 * scaled by 2^k built in the exponent field (k + 1023 in [1, 1023]). */
static inline double tt__rbf_exp_neg(double x) {
  x = x < -708.0 ? -708.0 : x;
  x = x > 0.0 ? 0.0 : x;
  const double shift = 0x1.8p52;
  double t = x * 0x1.71547652b82fep0 + shift; /* log2(e) */
  double k = t - shift;
  double r = x - k * 0x1.62e42fee00000p-1; /* ln2, high part: k * it is exact */
  r = r - k * 0x1.a39ef35793c76p-33;       /* ln2, low part */
  double p = 1.0 / 39916800.0;             /* 1/11! */
  p = p * r + 1.0 / 3628800.0;
  p = p * r + 1.0 / 362880.0;
  p = p * r + 1.0 / 40320.0;
  p = p * r + 1.0 / 5040.0;
  p = p * r + 1.0 / 720.0;
  p = p * r + 1.0 / 120.0;
  p = p * r + 1.0 / 24.0;
  p = p * r + 1.0 / 6.0;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r + 1.0;
  uint64_t bits;
  memcpy(&bits, &t, sizeof bits);
  bits = (bits + 1023u) << 52;
  double scale;
  memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

/* The fine level (tt__rbf_qbound_fn). */
static void tt__rbf_qbound(const double *restrict theta, const double *restrict ds,
                           const double *restrict da, uint32_t f, double nw, double *restrict e,
                           double *q, double *qabs) {
  for (uint32_t i = 0; i < f; i++) e[i] = tt__rbf_exp_neg(nw * sqrt(ds[i] + da[i]));
  double s[8] = {0}, a[8] = {0};
  uint32_t i = 0;
  for (; i + 8 <= f; i += 8)
    for (uint32_t j = 0; j < 8; j++) {
      double t = theta[i + j] * e[i + j];
      s[j] += t;
      a[j] += fabs(t);
    }
  for (uint32_t j = 0; i < f; i++, j++) {
    double t = theta[i] * e[i];
    s[j] += t;
    a[j] += fabs(t);
  }
  *q = ((s[0] + s[4]) + (s[1] + s[5])) + ((s[2] + s[6]) + (s[3] + s[7]));
  *qabs = ((a[0] + a[4]) + (a[1] + a[5])) + ((a[2] + a[6]) + (a[3] + a[7]));
}

#if TT__RBF_COPY_AVX2
/* The coarse level (tt__rbf_qcoarse_fn): single precision, 8 lanes of AVX2+FMA, only in the
 * AVX2 copy.
 *
 * Per feature: s = ds + da (the float copies of both), x = nw sqrt(s), e = exp(x) by a
 * degree-7 polynomial after the reduction x = k ln2 + r (x clamped to [-86, 0], so that p 2^k
 * stays a normal float), t = theta e; three sums in float, one lane per 8 features: q = sum t,
 * qabs = sum |t|, qx = sum |t| |x|. rbf_argmax.c turns qabs and qx into a bound: x carries
 * the float roundings of ds, da, their sum, the sqrt, nw and the product (relative 4 x 2^-24),
 * which make e's relative error grow with |x|. */

/* exp(x) for 8 floats x <= 0 (x below -86 taken as -86). */
static inline __m256 tt__rbf_exp8(__m256 x) {
  x = _mm256_max_ps(x, _mm256_set1_ps(-86.0f));
  x = _mm256_min_ps(x, _mm256_setzero_ps());
  const __m256 shift = _mm256_set1_ps(0x1.8p23f); /* k lands in t's low mantissa bits */
  __m256 t = _mm256_fmadd_ps(x, _mm256_set1_ps(0x1.715476p0f), shift); /* log2(e) */
  __m256 k = _mm256_sub_ps(t, shift);
  __m256 r = _mm256_fnmadd_ps(k, _mm256_set1_ps(0x1.62e4p-1f), x); /* ln2, high */
  r = _mm256_fnmadd_ps(k, _mm256_set1_ps(0x1.7f7d1cp-20f), r);     /* ln2, low */
  __m256 p = _mm256_set1_ps(1.0f / 5040.0f);
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f / 720.0f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f / 120.0f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f / 24.0f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f / 6.0f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(0.5f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f));
  /* 2^k: k + 127 in [1, 127] into the exponent field */
  __m256i sc =
      _mm256_slli_epi32(_mm256_add_epi32(_mm256_castps_si256(t), _mm256_set1_epi32(127)), 23);
  return _mm256_mul_ps(p, _mm256_castsi256_ps(sc));
}

static inline double tt__rbf_hsum8(__m256 v) {
  __m128 a = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  a = _mm_add_ps(a, _mm_movehl_ps(a, a));
  a = _mm_add_ss(a, _mm_shuffle_ps(a, a, 1));
  return (double)_mm_cvtss_f32(a);
}

static void tt__rbf_qcoarse(const float *thetaf, const float *dsf, const float *daf, uint32_t f8,
                            float nw, double *q, double *qabs, double *qx) {
  __m256 s = _mm256_setzero_ps(), a = s, b = s, nw8 = _mm256_set1_ps(nw);
  const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  for (uint32_t i = 0; i < f8; i += 8) {
    __m256 x = _mm256_mul_ps(
        nw8, _mm256_sqrt_ps(_mm256_add_ps(_mm256_loadu_ps(dsf + i), _mm256_loadu_ps(daf + i))));
    __m256 t = _mm256_mul_ps(_mm256_loadu_ps(thetaf + i), tt__rbf_exp8(x));
    __m256 at = _mm256_and_ps(t, absmask);
    s = _mm256_add_ps(s, t);
    a = _mm256_add_ps(a, at);
    b = _mm256_fnmadd_ps(at, x, b); /* x <= 0: b += |t| |x| */
  }
  *q = tt__rbf_hsum8(s);
  *qabs = tt__rbf_hsum8(a);
  *qx = tt__rbf_hsum8(b);
}
#endif

static const tt__rbf_kernels g_kernels = {
#if TT__RBF_COPY_AVX2
    tt__rbf_qcoarse,
#else
    NULL,
#endif
    tt__rbf_qbound};

/* This instruction set's kernels (named after TT__RBF_ISA). */
const tt__rbf_kernels *TT__RBF_CAT(tt__rbf_kernels_, TT__RBF_ISA)(void) { return &g_kernels; }
