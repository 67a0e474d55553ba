/* argmax_a Q(s, a) over candidates given by their action parts (rbf_model.h), the first
 * maximum of rbf_q_parts in candidate order: what a loop of rbf_q_parts with a strict `>`
 * answers, bit for bit, at a fraction of its cost.
 *
 * rbf_argmax_bounded computes every candidate's Q approximately (rbf_qbound.h: vectorised,
 * a polynomial exp) together with a bound tol_k >= |qa_k - Q_k|, and evaluates Q exactly
 * (rbf_q_parts) only for the candidates that the bounds cannot rule out: those with
 * qa_k + tol_k >= max_j (qa_j - tol_j). Every other candidate has Q_k < that maximum <= the
 * best Q, so it cannot be the argmax, nor tie with it; the exact maximum and its index are
 * therefore those of the reference loop. Usually one candidate is evaluated exactly.
 *
 * The bound (u = 2^-53, F features, S_k = sum_i |theta_i e_i|):
 *   |qa_k - Q_k| <= sum_i |theta_i| |e~_i - e_i| + 2 gamma_F S_k        (both sums' roundings)
 *               <= (1e-14 + 2u + 2 gamma_F) S_k + 3.4e-308 sum_i |theta_i| + (2F + 16) 2^-1022
 * (e~ within 1e-14 of exp, libm's exp within 1 ulp, both below 3.4e-308 where the argument is
 * below -708; the last term: every product and sum flushed to zero where it is subnormal, if
 * the thread runs with FTZ/DAZ). tol_k = (1e-11 + 4 F u) qabs_k + 1e-300 sum_i |theta_i| +
 * (2F + 16) 2^-1021 is more than 100 times the relative part and twice the absolute ones,
 * which also covers qabs_k's own error and the roundings of qa_k +- tol_k.
 * A model whose sums are not finite (theta near the double range) takes the reference loop. */
#ifndef TT_PREDICTOR_RBF_ARGMAX_H
#define TT_PREDICTOR_RBF_ARGMAX_H

#include "rbf_model.h"
#include "rbf_qbound.h"

#include <stddef.h>

/* The reference: rbf_q_parts for every candidate, the first strict maximum. n >= 1;
 * *best_q = its Q (-inf if no Q compares greater than -inf, then index 0). */
size_t rbf_argmax_reference(const rbf_model *r, const double *ds, const double *const *da,
                            size_t n, double *best_q);

/* The same answer through the bounds. `fn`: the approximate kernel (NULL: the fastest this
 * CPU runs, rbf_qbound_pick); `work`: features + 2 n doubles; *exact (may be NULL): how
 * many candidates were evaluated exactly. */
size_t rbf_argmax_bounded(const rbf_model *r, const double *ds, const double *const *da,
                          size_t n, rbf_qbound_fn *fn, double *work, double *best_q,
                          size_t *exact);

/* The kernel of this CPU: rbf_qbound_avx2 where built and the CPU has AVX2 and FMA,
 * otherwise rbf_qbound_base. */
rbf_qbound_fn *rbf_qbound_pick(void);

#endif /* TT_PREDICTOR_RBF_ARGMAX_H */
