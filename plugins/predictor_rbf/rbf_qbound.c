/* The argmax's approximate Q of one candidate (rbf_qbound.h), compiled once per instruction
 * set (RBF_ISA: base, the target's baseline, SSE2 on x86-64; avx2, with FMA, on x86-64);
 * rbf_argmax.c picks one at run time. Plain C loops that the compiler vectorises at -O3: an
 * elementwise pass (sqrt and a polynomial exp, no libm call) and a reduction into 8 explicit
 * partial sums (a reduction into one accumulator is not vectorised without -ffast-math).
 *
 * The result may differ between the copies and from rbf_q_parts: the caller bounds the
 * difference (rbf_argmax.h) and recomputes with rbf_q_parts itself the candidates that the
 * bound cannot separate, so the answer never depends on which copy ran. */
#include "rbf_qbound.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#ifndef RBF_ISA
#  error "compile with -DRBF_ISA=base or avx2"
#endif
#define RBF_CAT2(a, b) a##b
#define RBF_CAT(a, b) RBF_CAT2(a, b)

/* exp(x) for x <= 0, relative error below 1e-14 for x >= -708 (x below is taken as -708: the
 * result then is 3.3e-308 or less, an absolute error the caller's bound includes). Cody-Waite
 * reduction x = k ln2 + r, |r| <= ln2/2 (k from the 1.5 * 2^52 rounding trick, so it is an
 * integer in the low bits of t), Taylor polynomial of degree 11 (remainder r^12/12! < 7e-15),
 * scaled by 2^k built in the exponent field (k + 1023 in [1, 1023]). */
static inline double rbf_exp_neg(double x) {
  x = x < -708.0 ? -708.0 : x;
  x = x > 0.0 ? 0.0 : x;
  const double shift = 0x1.8p52;
  double t = x * 0x1.71547652b82fep0 + shift; /* log2(e) */
  double k = t - shift;
  double r = x - k * 0x1.62e42fee00000p-1;    /* ln2, high part: k * it is exact */
  r = r - k * 0x1.a39ef35793c76p-33;          /* ln2, low part */
  double p = 1.0 / 39916800.0;                /* 1/11! */
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

void RBF_CAT(rbf_qbound_, RBF_ISA)(const double *restrict theta, const double *restrict ds,
                                   const double *restrict da, uint32_t f, double nw,
                                   double *restrict e, double *q, double *qabs) {
  for (uint32_t i = 0; i < f; i++) e[i] = rbf_exp_neg(nw * sqrt(ds[i] + da[i]));
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
