/* The argmax's first, coarse approximation of Q (rbf_qbound.h): single precision, 8 lanes
 * of AVX2+FMA, compiled only into the AVX2 copy and run only where the CPU has both.
 *
 * Per feature: s = ds + da (the float copies of both), x = nw sqrt(s), e = exp(x) by a
 * degree-7 polynomial after the reduction x = k ln2 + r (x clamped to [-86, 0], so that p 2^k
 * stays a normal float), t = theta e; three sums in float, one lane per 8 features: q = sum t,
 * qabs = sum |t|, qx = sum |t| |x|. rbf_argmax.c turns qabs and qx into a bound: x carries
 * the float roundings of ds, da, their sum, the sqrt, nw and the product (relative 4 x 2^-24),
 * which make e's relative error grow with |x|. */
#include "rbf_qbound.h"

#include <immintrin.h>

/* exp(x) for 8 floats x <= 0 (x below -86 taken as -86). */
static inline __m256 rbf_exp8(__m256 x) {
  x = _mm256_max_ps(x, _mm256_set1_ps(-86.0f));
  x = _mm256_min_ps(x, _mm256_setzero_ps());
  const __m256 shift = _mm256_set1_ps(0x1.8p23f);  /* k lands in t's low mantissa bits */
  __m256 t = _mm256_fmadd_ps(x, _mm256_set1_ps(0x1.715476p0f), shift);  /* log2(e) */
  __m256 k = _mm256_sub_ps(t, shift);
  __m256 r = _mm256_fnmadd_ps(k, _mm256_set1_ps(0x1.62e4p-1f), x);       /* ln2, high */
  r = _mm256_fnmadd_ps(k, _mm256_set1_ps(0x1.7f7d1cp-20f), r);            /* ln2, low */
  __m256 p = _mm256_set1_ps(1.0f / 5040.0f);
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f / 720.0f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f / 120.0f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f / 24.0f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f / 6.0f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(0.5f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.0f));
  /* 2^k: k + 127 in [1, 127] into the exponent field */
  __m256i sc = _mm256_slli_epi32(_mm256_add_epi32(_mm256_castps_si256(t), _mm256_set1_epi32(127)), 23);
  return _mm256_mul_ps(p, _mm256_castsi256_ps(sc));
}

static inline double rbf_hsum8(__m256 v) {
  __m128 a = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  a = _mm_add_ps(a, _mm_movehl_ps(a, a));
  a = _mm_add_ss(a, _mm_shuffle_ps(a, a, 1));
  return (double)_mm_cvtss_f32(a);
}

void rbf_qcoarse_avx2(const float *thetaf, const float *dsf, const float *daf, uint32_t f8,
                      float nw, double *q, double *qabs, double *qx) {
  __m256 s = _mm256_setzero_ps(), a = s, b = s, nw8 = _mm256_set1_ps(nw);
  const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  for (uint32_t i = 0; i < f8; i += 8) {
    __m256 x = _mm256_mul_ps(nw8, _mm256_sqrt_ps(_mm256_add_ps(_mm256_loadu_ps(dsf + i),
                                                               _mm256_loadu_ps(daf + i))));
    __m256 t = _mm256_mul_ps(_mm256_loadu_ps(thetaf + i), rbf_exp8(x));
    __m256 at = _mm256_and_ps(t, absmask);
    s = _mm256_add_ps(s, t);
    a = _mm256_add_ps(a, at);
    b = _mm256_fnmadd_ps(at, x, b);  /* x <= 0: b += |t| |x| */
  }
  *q = rbf_hsum8(s);
  *qabs = rbf_hsum8(a);
  *qx = rbf_hsum8(b);
}
