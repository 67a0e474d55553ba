/* The SDK's predictor example (examples/predictor_static), loaded like any third-party
 * plugin: it answers the configuration with the best geometric-mean speed-up over the states
 * it saw, whatever the state; a configuration seen in too few states does not qualify; its
 * model file round-trips and bad files are refused naming the file. */
#include "predictor_util.h"

static const tt_predictor_iface *P;

int main(void) {
  tt_registry *reg;
  P = pu_load(&reg, "predictor_static");
  tt_space *t = pu_target("target");
  tt_predictor *p = pu_create(P, t, 2, "test", NULL, 1);
  tt_config *a = pu_config(t, 2, 1.0, 0, 0), *b = pu_config(t, 9, 2.0, 2, 1),
            *lucky = pu_config(t, 30, 5.0, 1, 1), *out = tt_config_create(t);
  /* 10 states with defaults 10..100: a is 20% faster everywhere, b 10% faster; `lucky` is
   * 90% faster but seen in one state only */
  for (int i = 0; i < 10; i++) {
    double s[2] = {i * 0.1, 1 - i * 0.1}, def = 10.0 * (i + 1);
    tt_predictor_sample x[3] = {{.struct_size = sizeof x[0],
                                 .state = s,
                                 .config = a,
                                 .cost = 0.8 * def,
                                 .default_cost = def},
                                {.struct_size = sizeof x[0],
                                 .state = s,
                                 .config = b,
                                 .cost = 0.9 * def,
                                 .default_cost = def},
                                {.struct_size = sizeof x[0],
                                 .state = s,
                                 .config = lucky,
                                 .cost = 0.1 * def,
                                 .default_cost = def}};
    CHECK(P->observe_ex(p, x, i == 3 ? 3 : 2, TT_PREDICTOR_OFFLINE) == TT_OK);
  }
  double s[2] = {0.3, 0.3};
  tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = 50};
  tt_predictor_result r = {.struct_size = sizeof r};
  CHECK(P->predict_ex(p, &q, out, &r) == TT_OK);
  CHECK(tt_config_equal(out, a));
  CHECK_NEAR(r.expected_cost, 40.0, 1e-9);
  CHECK_NEAR(r.value, 1.25, 1e-12);
  double ec;
  CHECK(P->estimate(p, &q, b, &ec) == TT_OK);
  CHECK_NEAR(ec, 45.0, 1e-9);
  /* with minShare 0 the lucky configuration wins */
  tt_config *set = tt_config_create(P->space());
  tt_config_set_string(set, "minShare", "0");
  tt_predictor *p0 = pu_create(P, t, 2, "test", set, 1);
  for (int i = 0; i < 10; i++) {
    double st[2] = {i * 0.1, 1 - i * 0.1}, def = 10.0 * (i + 1);
    tt_predictor_sample x[2] = {{.struct_size = sizeof x[0],
                                 .state = st,
                                 .config = a,
                                 .cost = 0.8 * def,
                                 .default_cost = def},
                                {.struct_size = sizeof x[0],
                                 .state = st,
                                 .config = lucky,
                                 .cost = 0.1 * def,
                                 .default_cost = def}};
    CHECK(P->observe_ex(p0, x, i == 3 ? 2 : 1, TT_PREDICTOR_ONLINE) == TT_OK);
  }
  CHECK(P->predict_ex(p0, &q, out, &r) == TT_OK && tt_config_equal(out, lucky));
  /* model file: round trip, bad files */
  char dir[] = "/tmp/tt_pst_XXXXXX", path[256], bad[256];
  CHECK(mkdtemp(dir) != NULL);
  snprintf(path, sizeof path, "%s/static.txt", dir);
  snprintf(bad, sizeof bad, "%s/bad.txt", dir);
  CHECK(P->save(p, path) == TT_OK);
  tt_predictor *l = pu_create(P, t, 2, "test", NULL, 2);
  CHECK_MSG(P->load(l, path) == TT_OK, "%s", tt_last_error());
  CHECK(P->predict_ex(l, &q, out, &r) == TT_OK && tt_config_equal(out, a));
  CHECK_NEAR(r.expected_cost, 40.0, 1e-9);
  long n;
  unsigned char *bytes = pu_read(path, &n);
  for (long cut = 0; cut < n; cut += 1 + n / 50) {
    pu_write(bad, bytes, cut);
    CHECK_MSG(P->load(l, bad) != TT_OK, "cut at %ld loaded", cut);
    CHECK_CONTAINS(tt_last_error(), bad);
  }
  bytes[n / 2] ^= 1;
  pu_write(bad, bytes, n);
  CHECK(P->load(l, bad) == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(), "corrupt");
  tt_predictor *other = pu_create(P, t, 3, "test", NULL, 1);
  CHECK(P->load(other, path) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "(2 values)");
  CHECK(P->predict_ex(l, &q, out, &r) == TT_OK && tt_config_equal(out, a)); /* unchanged */
  free(bytes);
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd)) {}
  P->destroy(p);
  P->destroy(p0);
  P->destroy(l);
  P->destroy(other);
  tt_config_destroy(a);
  tt_config_destroy(b);
  tt_config_destroy(lucky);
  tt_config_destroy(out);
  tt_config_destroy(set);
  tt_space_destroy(t);
  tt_registry_destroy(reg);
  return tt_test_finish("sdk_predictor_static");
}
