/* Myopic Greedy-GQ (plugins/predictor_rbf/rbf_model.c) converges to the least-squares theta.
 *
 * A synthetic problem with a known answer: rewards R_j = theta* . phi(x_j) + noise at random
 * points x_j. The least-squares theta solves the normal equations (Phi^T Phi) theta =
 * Phi^T R (computed here by Cholesky, independently of the model code). Greedy-GQ with
 * gamma = 0 and decaying steps alpha / (1 + t / decay) over many shuffled passes must reach
 * it: theta within 1% (relative norm) and Q within 1e-3 of the least-squares Q at the data.
 * A check that it does not converge with too few updates guards against a test that cannot
 * fail. Also: features, the state/action split of Q, the one-hot action encoding. */
#include "rbf_model.h"

#include "tt_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <tt_util/rng.h>

static double uni(uint64_t *x) { return tt__u64_to_unit(tt__splitmix64(x)); }

/* Solves A t = b for symmetric positive definite A (n x n) by Cholesky; 0 on success. */
static int cholesky_solve(double *A, double *b, int n) {
  for (int j = 0; j < n; j++) {
    double d = A[j * n + j];
    for (int k = 0; k < j; k++) d -= A[j * n + k] * A[j * n + k];
    if (!(d > 0)) return -1;
    A[j * n + j] = sqrt(d);
    for (int i = j + 1; i < n; i++) {
      double s = A[i * n + j];
      for (int k = 0; k < j; k++) s -= A[i * n + k] * A[j * n + k];
      A[i * n + j] = s / A[j * n + j];
    }
  }
  for (int i = 0; i < n; i++) { /* L y = b */
    double s = b[i];
    for (int k = 0; k < i; k++) s -= A[i * n + k] * b[k];
    b[i] = s / A[i * n + i];
  }
  for (int i = n - 1; i >= 0; i--) { /* L^T t = y */
    double s = b[i];
    for (int k = i + 1; k < n; k++) s -= A[k * n + i] * b[k];
    b[i] = s / A[i * n + i];
  }
  return 0;
}

enum { F = 8, D = 3, N = 300 };

/* Runs `passes` shuffled passes of Greedy-GQ over the data; returns the relative error of
 * theta against theta_ls and the largest |Q - Q_ls| at the data points. */
static void run_gq(const tt__rbf_model *init, double (*X)[D], const double *R,
                   const double *theta_ls, int passes, double *theta_err, double *q_err) {
  tt__rbf_model r = *init;
  r.theta = calloc(F, sizeof(double));
  r.updates = 0;
  double phi[F];
  int order[N];
  for (int j = 0; j < N; j++) order[j] = j;
  uint64_t x = 77;
  for (int p = 0; p < passes; p++) {
    for (int j = N - 1; j > 0; j--) {
      int k = (int)(uni(&x) * (j + 1)), t = order[j];
      order[j] = order[k];
      order[k] = t;
    }
    for (int j = 0; j < N; j++) tt__rbf_update(&r, X[order[j]], R[order[j]], phi);
  }
  double num = 0, den = 0;
  for (int i = 0; i < F; i++) {
    num += (r.theta[i] - theta_ls[i]) * (r.theta[i] - theta_ls[i]);
    den += theta_ls[i] * theta_ls[i];
  }
  *theta_err = sqrt(num / den);
  tt__rbf_model ls = r;
  ls.theta = (double *)theta_ls;
  *q_err = 0;
  for (int j = 0; j < N; j++) {
    double e = fabs(tt__rbf_q(&r, X[j]) - tt__rbf_q(&ls, X[j]));
    if (e > *q_err) *q_err = e;
  }
  free(r.theta);
}

static void gq_least_squares(void) {
  tt__rbf_model r;
  /* narrow features (omega 4) keep Phi^T Phi well conditioned, so the test is about the
   * fixed point, not about waiting for a nearly singular direction */
  CHECK(tt__rbf_model_init(&r, 1, 2, F, 4.0, 0.5, 2000.0, 5) == 0);
  double X[N][D], R[N], Phi[N][F];
  double theta_star[F] = {1.0, -0.5, 2.0, 0.25, -1.5, 0.75, 1.25, -0.3};
  uint64_t x = 3;
  for (int j = 0; j < N; j++) {
    for (int k = 0; k < D; k++) X[j][k] = uni(&x);
    tt__rbf_features(&r, X[j], Phi[j]);
    double q = 0;
    for (int i = 0; i < F; i++) q += theta_star[i] * Phi[j][i];
    R[j] = q + 0.05 * (uni(&x) - 0.5); /* noise: the LS theta is not theta_star */
  }
  double A[F * F] = {0}, b[F] = {0};
  for (int j = 0; j < N; j++)
    for (int i = 0; i < F; i++) {
      b[i] += Phi[j][i] * R[j];
      for (int k = 0; k < F; k++) A[i * F + k] += Phi[j][i] * Phi[j][k];
    }
  CHECK(cholesky_solve(A, b, F) == 0); /* b = theta_ls */
  double diff = 0;
  for (int i = 0; i < F; i++) diff += fabs(b[i] - theta_star[i]);
  CHECK(diff > 1e-4); /* the noise moved the answer: the LS theta is what GQ must reach */

  double te, qe;
  run_gq(&r, X, R, b, 4000, &te, &qe);
  printf("Greedy-GQ after 4000 passes: |theta - theta_ls| / |theta_ls| = %.2e, max |Q - Q_ls| = "
         "%.2e\n",
         te, qe);
  CHECK_MSG(te < 0.01 && qe < 1e-3, "theta error %g, Q error %g", te, qe);
  run_gq(&r, X, R, b, 2, &te, &qe);
  CHECK_MSG(te > 0.01, "2 passes already at %g: the problem is too easy to test convergence", te);
  tt__rbf_model_free(&r);
}

static void features_and_split(void) {
  tt__rbf_model r;
  CHECK(tt__rbf_model_init(&r, 2, 3, 17, 1.5, 0.1, 0, 9) == 0);
  /* the centres are a Latin hypercube: one per stratum in every coordinate */
  for (uint32_t k = 0; k < r.dim; k++) {
    int seen[17] = {0};
    for (uint32_t i = 0; i < r.features; i++) {
      double c = r.centres[i * r.dim + k];
      CHECK(c >= 0 && c < 1);
      seen[(int)(c * 17)]++;
    }
    for (int s = 0; s < 17; s++) CHECK(seen[s] == 1);
  }
  uint64_t x = 1;
  for (uint32_t i = 0; i < r.features; i++) r.theta[i] = uni(&x) - 0.3;
  double xv[5] = {0.2, 0.7, 0.1, 0.9, 0.4}, phi[17], ds[17];
  tt__rbf_features(&r, xv, phi);
  for (uint32_t i = 0; i < r.features; i++) {
    double s = 0;
    for (uint32_t k = 0; k < r.dim; k++)
      s += (xv[k] - r.centres[i * r.dim + k]) * (xv[k] - r.centres[i * r.dim + k]);
    CHECK_NEAR(phi[i], exp(-1.5 * sqrt(s)), 1e-15);
  }
  tt__rbf_state_part(&r, xv, ds);
  CHECK_NEAR(tt__rbf_q_action(&r, ds, xv + 2), tt__rbf_q(&r, xv), 1e-13);
  /* the argmax's cached action part: the same sums in the same order, the same bits */
  double da[17];
  tt__rbf_action_part(&r, xv + 2, da);
  for (uint32_t i = 0; i < r.features; i++) {
    double s = 0;
    for (uint32_t k = 2; k < r.dim; k++)
      s += (xv[k] - r.centres[i * r.dim + k]) * (xv[k] - r.centres[i * r.dim + k]);
    CHECK(da[i] == s);
  }
  CHECK(tt__rbf_q_parts(&r, ds, da) == tt__rbf_q_action(&r, ds, xv + 2));
  tt__rbf_model_free(&r);
}

static void encoding(void) {
  tt_space *s = tt_space_create("t", "1");
  static const int64_t q[] = {1, 2, 3};
  tt_space_add_int(s, "leaf", 1, 33, 17, "");
  tt_space_add_nom_int(s, "quality", q, 3, 2, "");
  tt_space_add_nom_bool(s, "fast", 1, "");
  tt_space_add_float(s, "c", 0.1, 10, 1.0, 1, "");
  CHECK(tt__rbf_action_dims(s) == 1 + 3 + 1 + 1);
  tt_config *c = tt_config_create(s);
  double e[6];
  tt__rbf_encode_action(c, e);
  CHECK_NEAR(e[0], 0.5, 1e-15);
  CHECK(e[1] == 0 && e[2] == 0 && e[3] == 1 && e[4] == 1);
  CHECK_NEAR(e[5], 0.5, 1e-12); /* log scale: 1.0 is the middle of [0.1, 10] */
  tt_config_set_index(c, 1, 0);
  tt_config_set_index(c, 2, 0);
  tt__rbf_encode_action(c, e);
  CHECK(e[1] == 1 && e[2] == 0 && e[3] == 0 && e[4] == 0);
  tt_config_destroy(c);
  tt_space_destroy(s);
}

int main(void) {
  gq_least_squares();
  features_and_split();
  encoding();
  return tt_test_finish("predictor_rbf_model");
}
