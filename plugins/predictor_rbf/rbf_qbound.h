/* The argmax's vectorised approximate Q (rbf_qbound.c, one copy per instruction set).
 *
 * For one candidate with action parts da (rbf_model.h), given the state parts ds:
 *   *q    ~ sum_i theta_i e_i,   *qabs ~ sum_i |theta_i e_i|,   e_i ~ exp(nw sqrt(ds_i + da_i))
 * with e_i from a polynomial exp (relative error below 1e-14; arguments below -708 taken as
 * -708) and the sums in 8 partial sums instead of rbf_q_parts' one chain. rbf_argmax.c turns
 * qabs into a bound on |q - rbf_q_parts(...)| and uses it to decide which candidates need
 * the exact value. `e` is f scratch values. */
#ifndef TT_PREDICTOR_RBF_QBOUND_H
#define TT_PREDICTOR_RBF_QBOUND_H

#include <stdint.h>

typedef void rbf_qbound_fn(const double *theta, const double *ds, const double *da, uint32_t f,
                           double nw, double *e, double *q, double *qabs);

rbf_qbound_fn rbf_qbound_base;
#ifdef RBF_HAVE_AVX2
rbf_qbound_fn rbf_qbound_avx2;  /* runs only where the CPU has AVX2 and FMA */
#endif

#endif /* TT_PREDICTOR_RBF_QBOUND_H */
