/* The RBF value function and its Greedy-GQ update (rbf_model.h). */
#include "rbf_model.h"

#include <tt_util/rng.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

uint32_t tt__rbf_action_dims(const tt_space *space) {
  uint32_t m = 0;
  for (size_t i = 0; i < tt_space_count(space); i++) {
    size_t k = tt_space_type(space, i) == TT_PARAM_NOM ? tt_space_nom_count(space, i) : 1;
    m += k > 2 ? (uint32_t)k : 1u;
  }
  return m;
}

void tt__rbf_encode_action(const tt_config *config, double *out) {
  const tt_space *space = tt_config_space(config);
  size_t n = tt_space_count(space);
  double unit[512], *u = n <= 512 ? unit : malloc(n * sizeof *u);
  if (!u) return;
  tt_config_to_unit(config, u);
  uint32_t j = 0;
  for (size_t i = 0; i < n; i++) {
    if (tt_space_type(space, i) != TT_PARAM_NOM) {
      out[j++] = u[i];
      continue;
    }
    size_t k = tt_space_nom_count(space, i);
    int32_t idx = tt_config_get(config, i).index;
    if (k <= 2) {
      out[j++] = idx > 0 ? 1.0 : 0.0;
    } else {
      for (size_t v = 0; v < k; v++) out[j++] = (int32_t)v == idx ? 1.0 : 0.0;
    }
  }
  if (u != unit) free(u);
}

/* Uniform double in [0, 1) with 53 random bits. */
static double tt__rbf_uniform(tt__pcg32 *rng) {
  uint64_t hi = tt__pcg32_next(rng), lo = tt__pcg32_next(rng);
  return (double)(((hi << 32) | lo) >> 11) * 0x1.0p-53;
}

/* Uniform integer in [0, n), n >= 1, without modulo bias. */
static uint32_t tt__rbf_below(tt__pcg32 *rng, uint32_t n) {
  uint32_t limit = UINT32_MAX - UINT32_MAX % n, x;
  do x = tt__pcg32_next(rng);
  while (x >= limit);
  return x % n;
}

void tt__rbf_lhs(uint64_t seed, uint32_t n, uint32_t dim, double *out) {
  tt__pcg32 rng;
  tt__pcg32_seed(&rng, seed, 0x7262666c6873ull); /* "rbflhs" */
  uint32_t *perm = malloc((n ? n : 1) * sizeof *perm);
  if (!perm) {
    for (size_t i = 0; i < (size_t)n * dim; i++) out[i] = 0.5;
    return;
  }
  for (uint32_t j = 0; j < dim; j++) {
    for (uint32_t k = 0; k < n; k++) perm[k] = k;
    for (uint32_t k = n; k > 1; k--) { /* Fisher-Yates */
      uint32_t r = tt__rbf_below(&rng, k), t = perm[k - 1];
      perm[k - 1] = perm[r];
      perm[r] = t;
    }
    for (uint32_t k = 0; k < n; k++)
      out[(size_t)k * dim + j] = (perm[k] + tt__rbf_uniform(&rng)) / n;
  }
  free(perm);
}

int tt__rbf_model_init(tt__rbf_model *r, uint32_t d, uint32_t m, uint32_t features, double width,
                       double alpha, double decay, uint64_t seed) {
  memset(r, 0, sizeof *r);
  r->d = d;
  r->m = m;
  r->dim = d + m;
  r->features = features;
  r->width = width;
  r->alpha = alpha;
  r->decay = decay;
  r->centres = malloc((size_t)features * r->dim * sizeof(double) + 1);
  r->theta = calloc(features ? features : 1, sizeof(double));
  if (!r->centres || !r->theta) {
    tt__rbf_model_free(r);
    return -1;
  }
  tt__rbf_lhs(seed, features, r->dim, r->centres);
  return 0;
}

void tt__rbf_model_free(tt__rbf_model *r) {
  free(r->centres);
  free(r->theta);
  r->centres = r->theta = NULL;
}

void tt__rbf_features(const tt__rbf_model *r, const double *x, double *phi) {
  for (uint32_t i = 0; i < r->features; i++) {
    const double *c = r->centres + (size_t)i * r->dim;
    double s = 0;
    for (uint32_t k = 0; k < r->dim; k++) s += (x[k] - c[k]) * (x[k] - c[k]);
    phi[i] = exp(-r->width * sqrt(s));
  }
}

double tt__rbf_q(const tt__rbf_model *r, const double *x) {
  double q = 0;
  for (uint32_t i = 0; i < r->features; i++) {
    const double *c = r->centres + (size_t)i * r->dim;
    double s = 0;
    for (uint32_t k = 0; k < r->dim; k++) s += (x[k] - c[k]) * (x[k] - c[k]);
    q += r->theta[i] * exp(-r->width * sqrt(s));
  }
  return q;
}

void tt__rbf_update(tt__rbf_model *r, const double *x, double reward, double *phi) {
  tt__rbf_features(r, x, phi);
  double q = 0;
  for (uint32_t i = 0; i < r->features; i++) q += r->theta[i] * phi[i];
  double a = r->decay > 0 ? r->alpha / (1.0 + (double)r->updates / r->decay) : r->alpha;
  double delta = a * (reward - q);
  for (uint32_t i = 0; i < r->features; i++) r->theta[i] += delta * phi[i];
  r->updates++;
}

void tt__rbf_state_part(const tt__rbf_model *r, const double *state, double *ds) {
  for (uint32_t i = 0; i < r->features; i++) {
    const double *c = r->centres + (size_t)i * r->dim;
    double s = 0;
    for (uint32_t k = 0; k < r->d; k++) s += (state[k] - c[k]) * (state[k] - c[k]);
    ds[i] = s;
  }
}

void tt__rbf_action_part(const tt__rbf_model *r, const double *a, double *da) {
  for (uint32_t i = 0; i < r->features; i++) {
    const double *c = r->centres + (size_t)i * r->dim + r->d;
    double s = 0;
    for (uint32_t k = 0; k < r->m; k++) s += (a[k] - c[k]) * (a[k] - c[k]);
    da[i] = s;
  }
}

double tt__rbf_q_parts(const tt__rbf_model *r, const double *ds, const double *da) {
  double q = 0, nw = -r->width;
  for (uint32_t i = 0; i < r->features; i++) q += r->theta[i] * exp(nw * sqrt(ds[i] + da[i]));
  return q;
}

double tt__rbf_q_action(const tt__rbf_model *r, const double *ds, const double *a) {
  double q = 0, nw = -r->width;
  for (uint32_t i = 0; i < r->features; i++) {
    const double *c = r->centres + (size_t)i * r->dim + r->d;
    double s = 0;
    for (uint32_t k = 0; k < r->m; k++) s += (a[k] - c[k]) * (a[k] - c[k]);
    q += r->theta[i] * exp(nw * sqrt(ds[i] + s));
  }
  return q;
}
