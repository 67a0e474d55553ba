/* The SDK example tuner (examples/tuner_random), loaded through the loader like any
 * third-party plugin: settings space, Latin-hypercube stratification, determinism,
 * feasibility through tt_space_check, the ask/tell protocol, and exact resume from
 * save_state/load_state.
 *
 * argv[1]: path of tuner_random.so (built by examples/tests/meson.build from the example source). */
#include <tunetrace/loader.h>
#include <tunetrace/tuner.h>

#include "tt_test.h"

#include <stdarg.h>

/* Quiet log: the tuner does not log, other plugins are not loaded. */
static void quiet_log(tt_log_level level, const char *plugin, const char *fmt, ...) {}

static const tt_host g_host = {.struct_size = sizeof(tt_host),
                               .abi_major = TT_ABI_MAJOR,
                               .abi_minor = TT_ABI_MINOR,
                               .host_name = "sdk test",
                               .host_version = "0",
                               .log = quiet_log};

static const tt_tuner_iface *T;

/* Target: two plain floats (for stratification), an INT, a bool, a NOM int. */
static tt_space *make_target(void) {
  tt_space *s = tt_space_create("target", "1.0.0");
  static const int64_t widths[] = {1, 2, 4, 8};
  CHECK(tt_space_add_float(s, "x", 0.0, 1.0, 0.5, 0, "plain float") == 0);
  CHECK(tt_space_add_float(s, "y", 0.0, 1.0, 0.5, 0, "plain float") == 1);
  CHECK(tt_space_add_int(s, "a", 0, 99, 50, "int") == 2);
  CHECK(tt_space_add_nom_bool(s, "b", 0, "bool") == 3);
  CHECK(tt_space_add_nom_int(s, "w", widths, 4, 0, "nom int") == 4);
  return s;
}

/* Constraint: a > 90 is infeasible; x > 0.5 with a < 10 is repaired to a = 10. */
static tt_check_result check_fn(const tt_space *space, tt_config *c, char *why, size_t n,
                                void *user) {
  (void)space;
  (void)user;
  int64_t a = tt_config_get_int(c, "a", -1);
  if (a > 90) {
    snprintf(why, n, "a = %lld > 90", (long long)a);
    return TT_CHECK_INFEASIBLE;
  }
  if (tt_config_get_float(c, "x", 0) > 0.5 && a < 10) {
    tt_config_set_number(c, 2, 10);
    snprintf(why, n, "a raised to 10");
    return TT_CHECK_REPAIRED;
  }
  return TT_CHECK_OK;
}

/* Rejects everything, to see the tuner give up cleanly. */
static tt_check_result never_fn(const tt_space *space, tt_config *c, char *why, size_t n,
                                void *user) {
  snprintf(why, n, "never feasible");
  return TT_CHECK_INFEASIBLE;
}

/* A smooth cost with its minimum near x = 0.3, y = 0.7. */
static double cost_of(const tt_config *c) {
  double x = tt_config_get_float(c, "x", 0), y = tt_config_get_float(c, "y", 0);
  return (x - 0.3) * (x - 0.3) + (y - 0.7) * (y - 0.7) + 0.001 * tt_config_get_int(c, "a", 0);
}

/* Settings of the tuner's own space. */
static tt_config *settings(int64_t samples, int lhs) {
  const tt_space *ss = T->space();
  tt_config *c = tt_config_create(ss);
  CHECK(tt_config_set_number(c, (size_t)tt_space_find(ss, "samples"), (double)samples) == TT_OK);
  char text[8];
  snprintf(text, sizeof text, "%s", lhs ? "true" : "false");
  CHECK(tt_config_set_string(c, "lhs", text) == TT_OK);
  return c;
}

/* The settings space is published with the documented parameters and defaults. */
static void test_settings_space(void) {
  const tt_space *ss = T->space();
  CHECK(ss != NULL);
  if (!ss) return;
  CHECK(strcmp(tt_space_plugin(ss), "tuner_random") == 0);
  int si = tt_space_find(ss, "samples"), li = tt_space_find(ss, "lhs");
  CHECK(si >= 0 && tt_space_type(ss, (size_t)si) == TT_PARAM_INT);
  CHECK(si >= 0 && tt_space_default(ss, (size_t)si).i == 16);
  CHECK(li >= 0 && tt_space_type(ss, (size_t)li) == TT_PARAM_NOM);
  CHECK(li >= 0 && tt_space_default(ss, (size_t)li).kind == TT_VALUE_BOOL);
  char *json = tt_space_to_json(ss);
  CHECK_CONTAINS(json, "\"samples\"");
  CHECK_CONTAINS(json, "\"lhs\"");
  tt_free(json);
}

/* The first N proposals hit every one of the N strata of each float exactly once; uniform
 * random search (lhs=false) does not (for this seed: the chance is 20!/20^20). */
static void test_stratification(const tt_space *target) {
  enum { N = 20 };
  for (int lhs = 1; lhs >= 0; lhs--) {
    tt_config *set = settings(N, lhs);
    tt_tuner *tu = NULL;
    CHECK(T->create(target, set, 7, &tu) == TT_OK);
    tt_config *c = tt_config_create(target);
    int hits[2][N] = {{0}};
    double unit[5];
    for (int k = 0; k < N; k++) {
      CHECK(T->next(tu, c) == TT_OK);
      tt_config_to_unit(c, unit);
      for (int j = 0; j < 2; j++) {
        int s = (int)(unit[j] * N);
        if (s >= 0 && s < N) hits[j][s]++;
      }
      CHECK(T->feedback(tu, cost_of(c)) == TT_OK);
    }
    int all_once = 1;
    for (int j = 0; j < 2; j++)
      for (int s = 0; s < N; s++) all_once &= hits[j][s] == 1;
    CHECK_MSG(all_once == lhs, "lhs=%d: every stratum hit once: %d", lhs, all_once);
    tt_config_destroy(c);
    tt_config_destroy(set);
    T->destroy(tu);
  }
}

/* Runs `steps` ask/tell rounds and returns the proposals (caller destroys). */
static void run(tt_tuner *tu, const tt_space *target, tt_config **out, int steps) {
  for (int k = 0; k < steps; k++) {
    out[k] = tt_config_create(target);
    CHECK(T->next(tu, out[k]) == TT_OK);
    CHECK(T->feedback(tu, cost_of(out[k])) == TT_OK);
  }
}

/* Same seed, same proposals; another seed, other proposals. */
static void test_determinism(const tt_space *target) {
  enum { S = 40 };
  tt_config *a[S], *b[S], *c[S];
  tt_tuner *ta, *tb, *tc;
  CHECK(T->create(target, NULL, 11, &ta) == TT_OK);
  CHECK(T->create(target, NULL, 11, &tb) == TT_OK);
  CHECK(T->create(target, NULL, 12, &tc) == TT_OK);
  run(ta, target, a, S);
  run(tb, target, b, S);
  run(tc, target, c, S);
  int same = 1, differ = 0;
  for (int k = 0; k < S; k++) {
    same &= tt_config_equal(a[k], b[k]);
    differ += !tt_config_equal(a[k], c[k]);
  }
  CHECK(same);
  CHECK(differ > S / 2);
  for (int k = 0; k < S; k++) {
    tt_config_destroy(a[k]);
    tt_config_destroy(b[k]);
    tt_config_destroy(c[k]);
  }
  T->destroy(ta);
  T->destroy(tb);
  T->destroy(tc);
}

/* Proposals always satisfy the space's check (infeasible re-drawn, repairs applied); the
 * protocol errors and best() behave as documented. */
static void test_protocol(tt_space *target) {
  tt_tuner *tu;
  CHECK(T->create(target, NULL, 3, &tu) == TT_OK);
  tt_config *c = tt_config_create(target), *c2 = tt_config_create(target);
  double cost = 0;
  CHECK(T->best(tu, c, &cost) == TT_ERR_NO_DATA);
  CHECK(T->feedback(tu, 1.0) == TT_ERR_INVALID_ARGUMENT);
  CHECK(T->next(tu, c) == TT_OK);
  CHECK(T->next(tu, c2) == TT_OK);
  CHECK(tt_config_equal(c, c2)); /* re-proposed without feedback */
  CHECK(T->feedback(tu, NAN) == TT_ERR_INVALID_ARGUMENT);
  CHECK(T->feedback(tu, TT_COST_INFEASIBLE) == TT_OK);
  CHECK(T->feedback(tu, 1.0) == TT_ERR_INVALID_ARGUMENT); /* nothing outstanding */

  double min_cost = TT_COST_INFEASIBLE;
  tt_config *argmin = tt_config_create(target);
  int violations = 0, repaired_seen = 0, high_a = 0;
  char why[128];
  for (int k = 0; k < 300; k++) {
    CHECK(T->next(tu, c) == TT_OK);
    tt_config_copy(c2, c);
    violations += tt_space_check(target, c2, why, sizeof why) != TT_CHECK_OK;
    high_a += tt_config_get_int(c, "a", 0) > 90;
    repaired_seen += tt_config_get_int(c, "a", 0) == 10 && tt_config_get_float(c, "x", 0) > 0.5;
    double f = cost_of(c);
    if (f < min_cost) {
      min_cost = f;
      tt_config_copy(argmin, c);
    }
    CHECK(T->feedback(tu, f) == TT_OK);
  }
  /* Re-proposal holds in the uniform phase too, where each draw moves the generator. */
  CHECK(T->next(tu, c) == TT_OK);
  CHECK(T->next(tu, c2) == TT_OK);
  CHECK(tt_config_equal(c, c2));
  CHECK(T->feedback(tu, TT_COST_INFEASIBLE) == TT_OK);
  CHECK_MSG(violations == 0, "%d proposals fail the check", violations);
  CHECK(high_a == 0);
  CHECK(repaired_seen > 0); /* a in [0,9] with x > 0.5 comes up about 4% of the time */
  CHECK(T->best(tu, c, &cost) == TT_OK);
  CHECK(cost == min_cost);
  CHECK(tt_config_equal(c, argmin));
  tt_config_destroy(argmin);
  T->destroy(tu);

  /* Nothing feasible: next() fails with a message instead of proposing garbage. */
  tt_space_set_check(target, never_fn, NULL);
  CHECK(T->create(target, NULL, 3, &tu) == TT_OK);
  CHECK(T->next(tu, c) == TT_ERR_INFEASIBLE);
  CHECK_CONTAINS(tt_last_error(), "never feasible");
  T->destroy(tu);
  tt_space_set_check(target, check_fn, NULL);
  tt_config_destroy(c);
  tt_config_destroy(c2);
}

/* save_state mid-run (past the hypercube, so the generator has moved, and with a proposal
 * outstanding) then load_state into a fresh tuner: both continue identically. */
static void test_resume(const tt_space *target) {
  enum { PRE = 9, POST = 30 };
  tt_config *set = settings(5, 1);
  tt_tuner *ta, *tb;
  CHECK(T->create(target, set, 99, &ta) == TT_OK);
  CHECK(T->create(target, set, 99, &tb) == TT_OK);
  tt_config *pre[PRE];
  run(ta, target, pre, PRE);
  tt_config *out_a = tt_config_create(target), *out_b = tt_config_create(target);
  CHECK(T->next(ta, out_a) == TT_OK); /* outstanding at save time */
  char *json = NULL;
  CHECK(T->save_state(ta, &json) == TT_OK);
  CHECK(json != NULL);
  CHECK_CONTAINS(json, "\"rng\"");
  CHECK_CONTAINS(json, "\"iteration\": 9");
  CHECK_MSG(T->load_state(tb, json) == TT_OK, "%s", tt_last_error());
  char *json_b = NULL; /* the restored tuner saves the very same state */
  CHECK(T->save_state(tb, &json_b) == TT_OK);
  CHECK_MSG(json_b && strcmp(json, json_b) == 0, "saved:\n%s\nresaved:\n%s", json, json_b);
  tt_free(json_b);
  CHECK(T->next(tb, out_b) == TT_OK);
  CHECK(tt_config_equal(out_a, out_b));
  double ca, cb;
  CHECK(T->best(tb, out_b, &cb) == TT_OK);
  CHECK(T->best(ta, out_a, &ca) == TT_OK);
  CHECK(ca == cb && tt_config_equal(out_a, out_b));
  int same = 1;
  for (int k = 0; k < POST; k++) {
    CHECK(T->next(ta, out_a) == TT_OK);
    CHECK(T->next(tb, out_b) == TT_OK);
    same &= tt_config_equal(out_a, out_b);
    CHECK(T->feedback(ta, cost_of(out_a)) == TT_OK);
    CHECK(T->feedback(tb, cost_of(out_b)) == TT_OK);
  }
  CHECK_MSG(same, "resumed tuner diverged");
  CHECK(T->best(ta, out_a, &ca) == TT_OK && T->best(tb, out_b, &cb) == TT_OK);
  CHECK(ca == cb && tt_config_equal(out_a, out_b));

  /* A state from another seed or another settings is refused, naming the mismatch. */
  tt_tuner *tc;
  CHECK(T->create(target, set, 100, &tc) == TT_OK);
  CHECK(T->load_state(tc, json) != TT_OK);
  CHECK_CONTAINS(tt_last_error(), "seed");
  T->destroy(tc);
  CHECK(T->create(target, NULL, 99, &tc) == TT_OK);
  CHECK(T->load_state(tc, json) != TT_OK);
  CHECK_CONTAINS(tt_last_error(), "samples");
  CHECK(T->load_state(tc, "{\"tuner\": \"tuner_nm\"}") == TT_ERR_PARSE);
  CHECK(T->load_state(tc, "not json") == TT_ERR_PARSE);
  T->destroy(tc);

  tt_free(json);
  for (int k = 0; k < PRE; k++) tt_config_destroy(pre[k]);
  tt_config_destroy(out_a);
  tt_config_destroy(out_b);
  tt_config_destroy(set);
  T->destroy(ta);
  T->destroy(tb);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: sdk_tuner_random PATH/tuner_random.so\n");
    return 1;
  }
  tt_registry *reg = tt_registry_create(&g_host);
  tt_loaded_plugin *p = NULL;
  if (tt_registry_load(reg, argv[1], &p) != TT_OK) {
    fprintf(stderr, "cannot load %s: %s\n", argv[1], tt_last_error());
    return 1;
  }
  CHECK(tt_loaded_plugin_entry(p)->kind == TT_KIND_TUNER);
  CHECK(strcmp(tt_loaded_plugin_entry(p)->name, "tuner_random") == 0);
  T = tt_loaded_plugin_iface(p);
  CHECK(tt_loaded_plugin_space(p) == T->space());

  tt_space *target = make_target();
  test_settings_space();
  test_stratification(target);
  test_determinism(target);
  tt_space_set_check(target, check_fn, NULL);
  test_protocol(target);
  test_resume(target);
  tt_space_destroy(target);
  tt_registry_destroy(reg);
  return tt_test_finish("sdk_tuner_random");
}
