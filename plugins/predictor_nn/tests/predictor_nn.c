/* predictor_nn (thesis 3.3.2): a stored state returns exactly its best configuration, any
 * other state the best configuration of its Euclidean nearest stored state; the best is the
 * lowest mean cost; infeasible samples are never an answer; maxStates merges into the nearest
 * state; model files round-trip bit-exactly and bad files are refused. */
#include "predictor_util.h"

#include <stdlib.h>
#include <tt_util/rng.h>

enum { DIM = 5 };

static const tt_predictor_iface *P, *RBF;
static tt_space *target;

static tt_status observe(tt_predictor *p, const double *s, const tt_config *c, double cost) {
  tt_predictor_sample x = {
      .struct_size = sizeof x, .state = s, .config = c, .cost = cost, .default_cost = NAN};
  return P->observe_ex(p, &x, 1, TT_PREDICTOR_ONLINE);
}

/* Predicted configuration of `s` as JSON (caller frees with tt_free), distance in *d. */
static char *answer(const tt_predictor *p, const double *s, double *d, double *cost) {
  tt_config *c = tt_config_create(target);
  tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = NAN};
  tt_predictor_result r = {.struct_size = sizeof r};
  tt_status st = P->predict_ex(p, &q, c, &r);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (d) *d = r.distance;
  if (cost) *cost = r.expected_cost;
  char *j = tt_config_to_json(c);
  tt_config_destroy(c);
  return j;
}

static double uni(uint64_t *x) { return tt__u64_to_unit(tt__splitmix64(x)); }

int main(int argc, char **argv) {
  const char *dir = argc > 1 ? argv[1] : NULL;
  char tmp[] = "/tmp/tt_pnn_XXXXXX";
  if (!dir) dir = mkdtemp(tmp);
  tt_registry *reg, *reg2;
  P = pu_load(&reg, "predictor_nn");
  RBF = pu_load(&reg2, "predictor_rbf");
  target = pu_target("target");
  const char *space = "tt.indicators/1 camera=extent scale=linear";
  tt_predictor *p = pu_create(P, target, DIM, space, NULL, 1);

  /* empty: no data */
  double s0[DIM] = {0};
  tt_config *out = tt_config_create(target);
  double ec;
  CHECK(P->predict(p, s0, out, &ec) == TT_ERR_NO_DATA);

  /* 40 random states, each with 4 configurations; the one with the lowest mean wins */
  enum { NS = 40, NC = 4 };
  double states[NS][DIM];
  char *best[NS];
  uint64_t x = 5;
  for (int i = 0; i < NS; i++) {
    for (int k = 0; k < DIM; k++) states[i][k] = uni(&x);
    int win = (int)(uni(&x) * NC);
    for (int c = 0; c < NC; c++) {
      tt_config *cfg = pu_config(target, 1 + (i * 7 + c * 3) % 32, 0.1 + c, c % 3, (i + c) % 2);
      double cost = c == win ? 10.0 : 12.0 + c;
      CHECK(observe(p, states[i], cfg, cost) == TT_OK);
      if (c == win) best[i] = tt_config_to_json(cfg);
      tt_config_destroy(cfg);
    }
  }
  /* a stored state returns exactly its configuration, at distance 0 */
  for (int i = 0; i < NS; i++) {
    double d, cost;
    char *j = answer(p, states[i], &d, &cost);
    CHECK_MSG(!strcmp(j, best[i]), "state %d: %s, stored best %s", i, j, best[i]);
    CHECK(d == 0.0 && cost == 10.0);
    tt_free(j);
  }
  /* any other state: the answer of the nearest stored state (brute force here) */
  for (int t = 0; t < 500; t++) {
    double q[DIM];
    for (int k = 0; k < DIM; k++) q[k] = uni(&x) * 1.2 - 0.1;
    int near = 0;
    double bd = INFINITY;
    for (int i = 0; i < NS; i++) {
      double dd = 0;
      for (int k = 0; k < DIM; k++) dd += (q[k] - states[i][k]) * (q[k] - states[i][k]);
      if (dd < bd) bd = dd, near = i;
    }
    double d;
    char *j = answer(p, q, &d, NULL);
    CHECK_MSG(!strcmp(j, best[near]), "query %d: got %s, nearest state %d has %s", t, j, near,
              best[near]);
    CHECK_NEAR(d, sqrt(bd), 1e-12);
    tt_free(j);
  }
  /* the lowest mean: A measured 5 and 25 (mean 15) loses to B measured 14 once */
  double s1[DIM] = {2, 2, 2, 2, 2};
  tt_config *a = pu_config(target, 3, 1.0, 0, 0), *b = pu_config(target, 4, 1.0, 0, 0);
  CHECK(observe(p, s1, a, 5.0) == TT_OK);
  char *ja = answer(p, s1, NULL, NULL), *jb = tt_config_to_json(b), *jaa = tt_config_to_json(a);
  CHECK(!strcmp(ja, jaa));
  tt_free(ja);
  CHECK(observe(p, s1, a, 25.0) == TT_OK);
  CHECK(observe(p, s1, b, 14.0) == TT_OK);
  ja = answer(p, s1, NULL, &ec);
  CHECK_MSG(!strcmp(ja, jb) && ec == 14.0, "%s %g", ja, ec);
  tt_free(ja);
  /* infeasible samples are skipped; NaN, zero and negative costs are errors */
  tt_config *c9 = pu_config(target, 9, 9.0, 2, 1);
  CHECK(observe(p, s1, c9, TT_COST_INFEASIBLE) == TT_OK);
  ja = answer(p, s1, NULL, NULL);
  CHECK(!strcmp(ja, jb));
  tt_free(ja);
  CHECK(observe(p, s1, c9, NAN) == TT_ERR_INVALID_ARGUMENT);
  CHECK(observe(p, s1, c9, 0.0) == TT_ERR_INVALID_ARGUMENT);
  CHECK(observe(p, s1, c9, -3.0) == TT_ERR_INVALID_ARGUMENT);
  double snan[DIM] = {NAN, 0, 0, 0, 0};
  CHECK(observe(p, snan, c9, 3.0) == TT_ERR_INVALID_ARGUMENT);
  /* a batch with one bad sample adds nothing */
  tt_predictor_info info = {.struct_size = sizeof info};
  P->info(p, &info);
  uint64_t before = info.observations;
  tt_predictor_sample batch[2] = {
      {.struct_size = sizeof batch[0], .state = s1, .config = c9, .cost = 1.0, .default_cost = NAN},
      {.struct_size = sizeof batch[0],
       .state = s1,
       .config = c9,
       .cost = -1.0,
       .default_cost = NAN}};
  CHECK(P->observe_ex(p, batch, 2, TT_PREDICTOR_OFFLINE) == TT_ERR_INVALID_ARGUMENT);
  P->info(p, &info);
  CHECK(info.observations == before && info.entries == NS + 1 && info.memory_bytes > 0);
  /* estimate: a stored configuration's mean in the nearest state, NAN for others */
  tt_predictor_query qq = {.struct_size = sizeof qq, .state = s1, .default_cost = NAN};
  CHECK(P->estimate(p, &qq, a, &ec) == TT_OK && ec == 15.0);
  CHECK(P->estimate(p, &qq, c9, &ec) == TT_OK && isnan(ec));
  /* the ABI 1.0 entry points answer the same */
  CHECK(P->predict(p, states[3], out, &ec) == TT_OK && ec == 10.0);
  char *j3 = tt_config_to_json(out);
  CHECK(!strcmp(j3, best[3]));
  tt_free(j3);

  /* maxStates: the third state merges into its nearest one */
  tt_space *ss = (tt_space *)P->space();
  tt_config *set = tt_config_create(ss);
  CHECK(tt_config_set_string(set, "maxStates", "2") == TT_OK);
  tt_predictor *m = pu_create(P, target, DIM, space, set, 1);
  double u[DIM] = {0}, v[DIM] = {1, 1, 1, 1, 1}, w[DIM] = {0.9, 1, 1, 1, 1};
  CHECK(observe(m, u, a, 10) == TT_OK && observe(m, v, a, 10) == TT_OK);
  CHECK(observe(m, w, b, 1) == TT_OK); /* merged into v: v's answer becomes b */
  P->info(m, &info);
  CHECK(info.entries == 2 && info.observations == 3);
  ja = answer(m, v, NULL, NULL);
  CHECK(!strcmp(ja, jb));
  tt_free(ja);
  ja = answer(m, u, NULL, NULL);
  CHECK(!strcmp(ja, jaa));
  tt_free(ja);

  /* model files */
  pu_check_files(P, p, target, DIM, space, dir, RBF, NULL, 1);
  pu_check_files(P, m, target, DIM, space, dir, RBF, set, 1);

  for (int i = 0; i < NS; i++) tt_free(best[i]);
  tt_free(jb);
  tt_free(jaa);
  tt_config_destroy(a);
  tt_config_destroy(b);
  tt_config_destroy(c9);
  tt_config_destroy(out);
  tt_config_destroy(set);
  P->destroy(p);
  P->destroy(m);
  tt_space_destroy(target);
  tt_registry_destroy(reg);
  tt_registry_destroy(reg2);
  if (dir == tmp) {
    char cmd[256];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
    if (system(cmd)) {}
  }
  return tt_test_finish("predictor_nn");
}
