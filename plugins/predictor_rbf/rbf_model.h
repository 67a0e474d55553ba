/* The RBF value function of predictor_rbf (thesis 3.3.2), independent of the plugin ABI so
 * that tests can check it directly:
 *
 *   Q(s, a) = theta . phi(x),   phi_i(x) = exp(-omega ||x - c_i||),   x = (s, enc(a))
 *
 * trained by myopic Greedy-GQ (gamma = 0): theta += alpha_t (R - theta . phi) phi, with
 * alpha_t = alpha / (1 + t / decay) after t updates (decay 0: constant alpha). With decaying
 * steps this is a Robbins-Monro iteration whose fixed point is the least-squares theta
 * (E[(R - theta.phi) phi] = 0).
 *
 * Action encoding enc(a), in [0,1] per coordinate: an INT or FLOAT parameter is one
 * coordinate, its unit-cube value (log-scaled if the space says so, tt_config_to_unit); a NOM
 * parameter with two values is one coordinate, 0 or 1; a NOM parameter with k > 2 values is k
 * coordinates, one-hot. One-hot because nominal values have no order: quality 1/2/3 or
 * branchingFactor 2/4/8 at (index + 0.5)/k would make "2" nearer to "1" than "3" is, a
 * distance the kernel would then believe. Every pair of distinct values of a one-hot
 * parameter is sqrt(2) apart; the two values of a boolean 1 apart.
 */
#ifndef TT_PREDICTOR_RBF_MODEL_H
#define TT_PREDICTOR_RBF_MODEL_H

#include <tunetrace/params.h>

#include <stddef.h>
#include <stdint.h>

typedef struct tt__rbf_model {
  uint32_t d;        /* state coordinates */
  uint32_t m;        /* action coordinates (tt__rbf_action_dims) */
  uint32_t dim;      /* d + m */
  uint32_t features; /* F */
  double width;      /* omega, the same for every feature */
  double alpha;      /* step size */
  double decay;      /* updates after which the step has halved; 0: constant */
  uint64_t updates;  /* t */
  double *centres;   /* F x dim, row-major */
  double *theta;     /* F */
} tt__rbf_model;

/* Action coordinates of a space's configurations. */
uint32_t tt__rbf_action_dims(const tt_space *space);
/* Writes enc(config) (tt__rbf_action_dims values). */
void tt__rbf_encode_action(const tt_config *config, double *out);

/* Allocates centres and theta (theta = 0) for F features over d + m coordinates; the centres
 * are a Latin hypercube in [0,1]^(d+m) drawn from `seed`. 0, or -1 when out of memory. */
int tt__rbf_model_init(tt__rbf_model *r, uint32_t d, uint32_t m, uint32_t features, double width,
                       double alpha, double decay, uint64_t seed);
void tt__rbf_model_free(tt__rbf_model *r);

/* phi(x) into `phi` (F values). */
void tt__rbf_features(const tt__rbf_model *r, const double *x, double *phi);
/* theta . phi(x). */
double tt__rbf_q(const tt__rbf_model *r, const double *x);
/* One update towards reward R at x; `phi` is F scratch values. */
void tt__rbf_update(tt__rbf_model *r, const double *x, double reward, double *phi);

/* The argmax's split of ||x - c_i||^2 = ds[i] + da[i] into the state part ds (once per
 * predict) and the action part da (once per candidate action, kept with the candidate:
 * predictor_rbf caches it per pool entry, so that a predict over the pool costs one sqrt and
 * one exp per candidate and feature, not the m-term sums too). tt__rbf_q_action and tt__rbf_q_parts
 * sum in the same order, so they agree bit for bit; tt__rbf_q sums all d + m terms in one chain,
 * so it agrees with them within a few ulp of each distance. */
/* Squared distances of the state part of x to every centre: ds[i] (F values). */
void tt__rbf_state_part(const tt__rbf_model *r, const double *state, double *ds);
/* Squared distances of the action coordinates `a` to every centre's action part: da[i]. */
void tt__rbf_action_part(const tt__rbf_model *r, const double *a, double *da);
/* Q given the state part ds and the action part da. */
double tt__rbf_q_parts(const tt__rbf_model *r, const double *ds, const double *da);
/* Q of the action coordinates `a` given the state part ds (tt__rbf_q_parts with da computed). */
double tt__rbf_q_action(const tt__rbf_model *r, const double *ds, const double *a);

/* n points of a Latin hypercube in [0,1]^dim into out (n x dim), from `seed`. */
void tt__rbf_lhs(uint64_t seed, uint32_t n, uint32_t dim, double *out);

#endif /* TT_PREDICTOR_RBF_MODEL_H */
