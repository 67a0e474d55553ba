/* argmax_a Q(s, a) over candidates given by their action parts (rbf_model.h), the first
 * maximum of tt__rbf_q_parts in candidate order: what a loop of tt__rbf_q_parts with a strict `>`
 * answers, bit for bit, at a fraction of its cost.
 *
 * tt__rbf_argmax_bounded computes every candidate's Q approximately together with a bound
 * tol_k >= |qa_k - Q_k|, and keeps only the candidates that the bounds cannot rule out:
 * those with qa_k + tol_k >= max_j (qa_j - tol_j). Every other candidate has
 * Q_k < that maximum <= the best Q, so it can neither be the argmax nor tie with it. Three
 * levels, each on what the previous one kept:
 *   1. coarse (tt__rbf_kernels.coarse: single precision, about 1e-6), where the CPU has it;
 *   2. fine (tt__rbf_kernels.fine: double precision, a polynomial exp, about 1e-14);
 *   3. tt__rbf_q_parts itself, in candidate order with a strict `>`: the reference's answer.
 * Usually a handful of candidates reach level 2 and one reaches level 3.
 *
 * The bounds (u = 2^-53, F features, S_k = sum_i |theta_i e_i|, rbf_*_tol):
 *   fine:   |qa_k - Q_k| <= sum_i |theta_i| |e~_i - e_i| + 2 gamma_F S_k (both sums' roundings)
 *           <= (1e-14 + 2u + 2 gamma_F) S_k + 3.4e-308 sum_i |theta_i| + (2F + 16) 2^-1022
 *     (e~ within 1e-14 of exp, libm's exp within 1 ulp, both below 3.4e-308 where the
 *     argument is below -708; the last term: every product and sum flushed to zero where it
 *     is subnormal, should the thread run with FTZ/DAZ). tol_k = (1e-11 + 4 F u) qabs_k +
 *     1e-300 sum |theta_i| + (2F + 16) 2^-1021: more than 100 times the relative part, twice
 *     the absolute ones, which also covers qabs_k's own error and the roundings of qa +- tol.
 *   coarse: x_i = nw sqrt(ds_i + da_i) carries the float roundings of ds, da (both >= 0),
 *     their sum, the sqrt, nw and the product: relative 4 v, v = 2^-24, so exp(x_i) is off
 *     by 4 v |x_i| relative; the float exp by 1e-7
 *     (8e-8 measured over [-86, 0]); theta's rounding, the product's and the float sums'
 *     (ceil(F/8) terms per lane, 3 levels across) by (F/8 + 5) v; below the float range
 *     (x < -86, flushed products and sums) 4.5e-38 |theta_i| and 1.2e-38 per operation.
 *     tol_k = (2e-6 + 1.2e-7 (F/8 + 4)) qabs_k + 5e-7 qx_k + 1e-37 sum |theta_i| +
 *     (3F + 16) 2^-125, qx_k = sum_i |theta_i e_i| |x_i|: at least twice each part. Used for
 *     F <= 8192 and sum |theta_i| < 1e34 only.
 * A model whose sums are not finite (theta near the double range) takes the reference loop.
 * tests/rbf_argmax.c checks each kernel against tt__rbf_q_parts at half its bound. */
#ifndef TT_PREDICTOR_RBF_ARGMAX_H
#define TT_PREDICTOR_RBF_ARGMAX_H

#include "rbf_model.h"
#include "rbf_qbound.h"

#include <stddef.h>

typedef struct tt__rbf_argmax_stats {
  size_t fine;  /* candidates that reached level 2 */
  size_t exact; /* candidates evaluated by tt__rbf_q_parts */
} tt__rbf_argmax_stats;

/* The kernels of this CPU: AVX2+FMA where built and the CPU has them (coarse and fine),
 * otherwise the baseline's fine kernel alone. */
tt__rbf_kernels tt__rbf_kernels_pick(void);

/* The scratch tt__rbf_argmax_bounded needs, in doubles. */
size_t tt__rbf_argmax_work(uint32_t features, size_t n);

/* Features rounded up to a multiple of 8: the length of the coarse level's float rows. */
static inline uint32_t tt__rbf_f8(uint32_t features) { return (features + 7u) & ~7u; }

/* The float copy of an action part (or of any F values) that the coarse level reads:
 * tt__rbf_f8(features) floats, zeros after the first F. */
void tt__rbf_action_part_float(uint32_t features, const double *da, float *daf);

/* The reference: tt__rbf_q_parts for every candidate, the first strict maximum. n >= 1;
 * *best_q = its Q (-inf if no Q compares greater than -inf, then index 0). */
size_t tt__rbf_argmax_reference(const tt__rbf_model *r, const double *ds, const double *const *da,
                                size_t n, double *best_q);

/* The same answer through the bounds. `daf`: the candidates' float action parts
 * (tt__rbf_action_part_float; NULL: no coarse level); `kernels`: NULL for tt__rbf_kernels_pick();
 * `work`: tt__rbf_argmax_work(features, n) doubles; `stats` may be NULL. */
size_t tt__rbf_argmax_bounded(const tt__rbf_model *r, const double *ds, const double *const *da,
                              const float *const *daf, size_t n, const tt__rbf_kernels *kernels,
                              double *work, double *best_q, tt__rbf_argmax_stats *stats);

/* The bounds above, given a kernel's qabs (and qx) and sum_i |theta_i|. */
double tt__rbf_fine_tol(uint32_t features, double qabs, double theta_abs);
double tt__rbf_coarse_tol(uint32_t features, double qabs, double qx, double theta_abs);

#endif /* TT_PREDICTOR_RBF_ARGMAX_H */
