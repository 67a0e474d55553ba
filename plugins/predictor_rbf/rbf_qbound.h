/* The argmax's vectorised approximate Q (rbf_qbound.c, one copy per instruction set).
 *
 * For one candidate with action parts da (rbf_model.h), given the state parts ds:
 *   *q    ~ sum_i theta_i e_i,   *qabs ~ sum_i |theta_i e_i|,   e_i ~ exp(nw sqrt(ds_i + da_i))
 * with e_i from a polynomial exp (relative error below 1e-14; arguments below -708 taken as
 * -708) and the sums in 8 partial sums instead of tt__rbf_q_parts' one chain. rbf_argmax.c turns
 * qabs into a bound on |q - tt__rbf_q_parts(...)| and uses it to decide which candidates need
 * the exact value. `e` is f scratch values. */
#ifndef TT_PREDICTOR_RBF_QBOUND_H
#define TT_PREDICTOR_RBF_QBOUND_H

#include <stdint.h>

typedef void tt__rbf_qbound_fn(const double *theta, const double *ds, const double *da, uint32_t f,
                               double nw, double *e, double *q, double *qabs);

/* The coarse level before it (AVX2 only): single precision, about 1e-6 relative
 * where the polynomial kernel is 1e-14, at a third of its cost. Float copies of theta, ds and
 * da, f8 values each, a multiple of 8 (padded with zeros: theta 0 adds nothing);
 * *qx ~ sum_i |theta_i e_i| |x_i|, x_i = nw sqrt(ds_i + da_i). */
typedef void tt__rbf_qcoarse_fn(const float *thetaf, const float *dsf, const float *daf,
                                uint32_t f8, float nw, double *q, double *qabs, double *qx);

/* One instruction set's kernels. */
typedef struct tt__rbf_kernels {
  tt__rbf_qcoarse_fn *coarse; /* NULL: no level 1 */
  tt__rbf_qbound_fn *fine;
} tt__rbf_kernels;

/* The copies (rbf_qbound.c, compiled once per instruction set): the baseline's (fine level
 * only) everywhere; AVX2+FMA (both levels) in x86-64 builds, to run only where the CPU has
 * both. rbf_argmax.c's tt__rbf_kernels_pick is the one place that chooses. */
const tt__rbf_kernels *tt__rbf_kernels_base(void);
#ifdef TT__RBF_HAVE_AVX2
const tt__rbf_kernels *tt__rbf_kernels_avx2(void);
#endif

#endif /* TT_PREDICTOR_RBF_QBOUND_H */
