/* What a tuner may change (#17 defect 9): parameters marked not tunable and parameters
 * active only under a condition (tunetrace/params.h), in the space API, its JSON, subsets,
 * and what tuner_nm, tuner_random (the SDK example) and the session's exploration (host
 * --explore) do with them.
 *
 * The space: mode in {a, b, c}; x (INT 0..7) acts only with mode b or c; y (FLOAT) only
 * with mode c and x's parent active (a chain: y needs mode c, which already makes x
 * active); debug (bool) is instrumentation, not tunable. So the distinct configurations a
 * tuner can meaningfully propose are: mode a (1), mode b x 8, mode c x 8 x y. */
#include <tunetrace/loader.h>
#include <tunetrace/tuning.h>

#include "tt_test.h"

static const char *space_json =
    "{\"plugin\": \"marked\", \"version\": \"1\", \"parameters\": ["
    " {\"name\": \"x\", \"type\": \"INT\", \"min\": 0, \"max\": 7, \"value\": 3,"
    "  \"activeWhen\": {\"mode\": [\"b\", \"c\"]}},"
    " {\"name\": \"mode\", \"type\": \"NOM\", \"possibleValues\": [\"a\", \"b\", \"c\"],"
    "  \"value\": \"a\"},"
    " {\"name\": \"y\", \"type\": \"FLOAT\", \"min\": 0, \"max\": 1, \"value\": 0.5,"
    "  \"activeWhen\": {\"mode\": [\"c\"]}},"
    " {\"name\": \"debug\", \"type\": \"NOM\", \"possibleValues\": [false, true],"
    "  \"value\": false, \"tunable\": false}]}";

/* Analytic cost: what acts. The minimum is mode c, x = 6, y = 0.25. */
static double cost_of(const tt_config *c) {
  int64_t mode = tt_config_get_int(c, "mode", 0);
  double x = (double)tt_config_get_int(c, "x", 0), y = tt_config_get_float(c, "y", 0);
  if (mode == 0) return 10.0;
  if (mode == 1) return 5.0 + 0.1 * (x - 6) * (x - 6);
  return 1.0 + 0.1 * (x - 6) * (x - 6) + 4.0 * (y - 0.25) * (y - 0.25);
}

/* Non-zero if canonicalising `c` changes nothing (every inactive parameter is at `base`'s
 * value and every setting too). */
static int is_canonical(const tt_config *c, const tt_config *base) {
  tt_config *k = tt_config_clone(c);
  int changed = tt_config_canonicalize(k, base);
  tt_config_destroy(k);
  return changed == 0;
}

static void test_space_api(void) {
  tt_space *s = tt_space_from_json(space_json, "marked.json");
  CHECK_MSG(s != NULL, "%s", tt_last_error());
  if (!s) return;
  size_t ix = (size_t)tt_space_find(s, "x"), iy = (size_t)tt_space_find(s, "y");
  size_t im = (size_t)tt_space_find(s, "mode"), id = (size_t)tt_space_find(s, "debug");
  CHECK(tt_space_is_tunable(s, ix) && tt_space_is_tunable(s, im) && !tt_space_is_tunable(s, id));
  CHECK(!tt_space_is_tunable(s, 99));
  CHECK(tt_space_condition_count(s, ix) == 1 && tt_space_condition_count(s, im) == 0);
  CHECK(tt_space_condition_parent(s, ix, 0) == (int)im); /* a parent after its child */
  CHECK(!tt_space_condition_allows(s, ix, 0, 0) && tt_space_condition_allows(s, ix, 0, 1) &&
        tt_space_condition_allows(s, ix, 0, 2));

  /* active and canonical forms */
  tt_config *c = tt_config_create(s), *base = tt_config_create(s);
  CHECK(!tt_config_is_active(c, ix) && !tt_config_is_active(c, iy) && tt_config_is_active(c, im));
  CHECK(tt_config_set_string(c, "x", "6") == TT_OK &&
        tt_config_set_string(c, "y", "0.9") == TT_OK &&
        tt_config_set_string(c, "debug", "true") == TT_OK);
  CHECK(tt_config_canonicalize(c, NULL) == 3); /* x, y inactive under mode a; debug a setting */
  CHECK(tt_config_equal(c, base));
  CHECK(tt_config_set_string(c, "mode", "b") == TT_OK &&
        tt_config_set_string(c, "x", "6") == TT_OK && tt_config_set_string(c, "y", "0.9") == TT_OK);
  CHECK(tt_config_is_active(c, ix) && !tt_config_is_active(c, iy));
  CHECK(tt_config_canonicalize(c, NULL) == 1 && tt_config_get_int(c, "x", 0) == 6 &&
        tt_config_get_float(c, "y", 0) == 0.5);
  /* a base other than the defaults: inactive parameters take its values */
  CHECK(tt_config_set_string(base, "y", "0.125") == TT_OK &&
        tt_config_set_string(base, "debug", "true") == TT_OK);
  CHECK(tt_config_canonicalize(c, base) == 2 && tt_config_get_float(c, "y", 0) == 0.125 &&
        tt_config_get_int(c, "debug", 0) == 1);

  /* JSON round trip keeps the marking */
  char *json = tt_space_to_json(s);
  CHECK_CONTAINS(json, "\"tunable\":\tfalse");
  CHECK_CONTAINS(json, "\"activeWhen\":");
  tt_space *s2 = json ? tt_space_from_json(json, "again") : NULL;
  CHECK_MSG(s2 != NULL, "%s", tt_last_error());
  char *json2 = s2 ? tt_space_to_json(s2) : NULL;
  CHECK(json && json2 && !strcmp(json, json2));
  tt_free(json);
  tt_free(json2);
  tt_space_destroy(s2);

  /* bad input: the file, the field and what was expected */
  static const struct {
    const char *params, *want;
  } bad[] = {
      {"{\"name\": \"p\", \"type\": \"INT\", \"min\": 0, \"max\": 1, \"value\": 0, \"tunable\": 1}",
       "bad.json: parameters[0].tunable: expected true or false"},
      {"{\"name\": \"p\", \"type\": \"INT\", \"min\": 0, \"max\": 1, \"value\": 0, \"activeWhen\": "
       "{\"mdoe\": [\"a\"]}},"
       "{\"name\": \"mode\", \"type\": \"NOM\", \"possibleValues\": [\"a\"], \"value\": \"a\"}",
       "did you mean \"mode\""},
      {"{\"name\": \"p\", \"type\": \"INT\", \"min\": 0, \"max\": 1, \"value\": 0, \"activeWhen\": "
       "{\"mode\": [\"z\"]}},"
       "{\"name\": \"mode\", \"type\": \"NOM\", \"possibleValues\": [\"a\"], \"value\": \"a\"}",
       "\"z\" is not a value of mode"},
      {"{\"name\": \"p\", \"type\": \"INT\", \"min\": 0, \"max\": 1, \"value\": 0, \"activeWhen\": "
       "{\"q\": [0]}},"
       "{\"name\": \"q\", \"type\": \"INT\", \"min\": 0, \"max\": 1, \"value\": 0}",
       "not a NOM parameter"},
      {"{\"name\": \"p\", \"type\": \"NOM\", \"possibleValues\": [1, 2], \"value\": 1, "
       "\"activeWhen\": {\"p\": [1]}}",
       "its own ancestor"},
      {"{\"name\": \"p\", \"type\": \"NOM\", \"possibleValues\": [1, 2], \"value\": 1, "
       "\"activeWhen\": {\"q\": [1]}},"
       "{\"name\": \"q\", \"type\": \"NOM\", \"possibleValues\": [1, 2], \"value\": 1, "
       "\"activeWhen\": {\"p\": [2]}}",
       "its own ancestor"},
      {"{\"name\": \"p\", \"type\": \"INT\", \"min\": 0, \"max\": 1, \"value\": 0, \"activeWhen\": "
       "{\"mode\": []}},"
       "{\"name\": \"mode\", \"type\": \"NOM\", \"possibleValues\": [\"a\"], \"value\": \"a\"}",
       "parameters[0].activeWhen.mode: expected a non-empty array"},
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
    char text[1024];
    snprintf(text, sizeof text, "{\"plugin\": \"bad\", \"version\": \"1\", \"parameters\": [%s]}",
             bad[k].params);
    tt_space *b = tt_space_from_json(text, "bad.json");
    CHECK_MSG(b == NULL, "case %zu accepted", k);
    CHECK_CONTAINS(tt_last_error(), bad[k].want);
    tt_space_destroy(b);
  }
  /* immutable once published (configurations exist) */
  CHECK(tt_space_set_tunable(s, ix, 0) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "immutable");

  /* subsets: a condition on a parameter left out is decided by its fixed value */
  const char *only_x[] = {"x", "debug"};
  tt_space *sub_a = tt_space_subset(s, only_x, 2, NULL); /* mode fixed at a: x never acts */
  CHECK(sub_a && !tt_space_is_tunable(sub_a, 0) && !tt_space_is_tunable(sub_a, 1) &&
        tt_space_condition_count(sub_a, 0) == 0);
  tt_config *fix = tt_config_create(s);
  CHECK(tt_config_set_string(fix, "mode", "b") == TT_OK);
  tt_space *sub_b = tt_space_subset(s, only_x, 2, fix); /* mode fixed at b: x acts */
  CHECK(sub_b && tt_space_is_tunable(sub_b, 0) && tt_space_condition_count(sub_b, 0) == 0);
  const char *xm[] = {"x", "mode"};
  tt_space *sub_m = tt_space_subset(s, xm, 2, NULL); /* both in: the condition is copied */
  CHECK(sub_m && tt_space_condition_count(sub_m, 0) == 1 &&
        tt_space_condition_parent(sub_m, 0, 0) == 1);
  tt_space_destroy(sub_a);
  tt_space_destroy(sub_b);
  tt_space_destroy(sub_m);
  tt_config_destroy(fix);
  tt_config_destroy(c);
  tt_config_destroy(base);
  tt_space_destroy(s);
}

/* ---- tuners driven directly (ask/tell over the analytic cost) ---- */

typedef struct seen {
  int proposals, not_canonical, debug_changed, distinct;
  char *configs[512];
} seen;

static void see(seen *v, const tt_config *c) {
  v->proposals++;
  if (!is_canonical(c, NULL)) v->not_canonical++;
  if (tt_config_get_int(c, "debug", 0) != 0) v->debug_changed++;
  char *j = tt_config_to_json(c);
  int found = 0;
  for (int k = 0; k < v->distinct; k++) found |= !strcmp(v->configs[k], j);
  if (!found && v->distinct < 512) v->configs[v->distinct++] = j;
  else tt_free(j);
}

static void seen_free(seen *v) {
  for (int k = 0; k < v->distinct; k++) tt_free(v->configs[k]);
}

/* Drives `ti` for `budget` proposals; returns the best cost. */
static double drive(const tt_tuner_iface *ti, const tt_space *s, seen *v, int budget) {
  tt_tuner *t = NULL;
  CHECK_MSG(ti->create(s, NULL, 7, &t) == TT_OK, "%s", tt_last_error());
  if (!t) return INFINITY;
  tt_config *c = tt_config_create(s);
  for (int i = 0; i < budget && ti->next(t, c) == TT_OK; i++) {
    see(v, c);
    ti->feedback(t, cost_of(c));
  }
  double best = INFINITY;
  ti->best(t, c, &best);
  tt_config_destroy(c);
  ti->destroy(t);
  return best;
}

/* One tuner per registry (the loader's rule), so each tuner gets its own. */
static void test_tuners(tt_registry *reg, const char *random_path) {
  tt_space *s = tt_space_from_json(space_json, "marked.json");
  tt_loaded_plugin *nm = NULL, *rnd = NULL;
  tt_registry *reg2 = tt_registry_create(tt_default_host());
  CHECK_MSG(tt_registry_load(reg, "tuner_nm", &nm) == TT_OK, "%s", tt_last_error());
  CHECK_MSG(tt_registry_load(reg2, random_path, &rnd) == TT_OK, "%s", tt_last_error());
  if (!s || !nm || !rnd) {
    tt_registry_destroy(reg2);
    return;
  }
  seen v = {0}, r = {0};
  double best = drive(tt_loaded_plugin_iface(nm), s, &v, 60);
  CHECK(v.proposals == 60 && v.distinct > 10);
  CHECK_MSG(v.not_canonical == 0,
            "tuner_nm: %d of %d proposals set parameters that do "
            "nothing away from their defaults",
            v.not_canonical, v.proposals);
  CHECK_MSG(v.debug_changed == 0, "tuner_nm changed the setting debug %d times", v.debug_changed);
  /* mode a is one configuration, however many x and y the simplex passes through */
  int mode_a = 0;
  for (int k = 0; k < v.distinct; k++) mode_a += strstr(v.configs[k], "\"mode\":\"a\"") != NULL;
  CHECK_MSG(mode_a <= 1, "tuner_nm measured %d configurations of mode a", mode_a);
  CHECK_MSG(best < 1.2, "tuner_nm best %g (the minimum is 1 at mode c)", best);
  drive(tt_loaded_plugin_iface(rnd), s, &r, 40);
  CHECK_MSG(r.not_canonical == 0 && r.debug_changed == 0,
            "tuner_random: %d not canonical, "
            "debug changed %d times",
            r.not_canonical, r.debug_changed);
  seen_free(&v);
  seen_free(&r);
  tt_space_destroy(s);
  tt_registry_destroy(reg2);
}

/* ---- the session: exploration (host --explore) and the space a tuner gets ---- */

static tt_status t_apply(void *user, const tt_config *config, double *build_ms) {
  (void)user, (void)config;
  *build_ms = 0;
  return TT_OK;
}

static const tt_config *g_applied;

static tt_status t_apply_keep(void *user, const tt_config *config, double *build_ms) {
  (void)user;
  g_applied = config;
  *build_ms = 0;
  return TT_OK;
}

static tt_status t_render(void *user, uint32_t spp, tt_tuning_measurement *m) {
  (void)user, (void)spp;
  if (m) m->render_ms = g_applied ? cost_of(g_applied) : 1.0;
  return TT_OK;
}

static void test_session(tt_registry *reg) {
  tt_space *s = tt_space_from_json(space_json, "marked.json");
  if (!s) return;
  tt_config *start = tt_config_create(s);
  CHECK(tt_config_set_string(start, "debug", "true") == TT_OK); /* the user's --set */
  tt_tuning_desc d;
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.space = s;
  d.start = start;
  d.iterations = 12;
  d.seed = 3;
  tt_tuning *t = NULL;
  CHECK_MSG(tt_tuning_create(&d, &t) == TT_OK, "%s", tt_last_error());
  tt_tuning_target tg = {.struct_size = sizeof tg, .apply = t_apply_keep, .render = t_render};
  CHECK(t && tt_tuning_run(t, &tg) == TT_OK);
  size_t n = t ? tt_tuning_sample_count(t) : 0;
  CHECK(n == 13);
  int distinct = 1, mode_a = 0, debug_off = 0;
  for (size_t i = 0; i < n; i++) {
    const char *ci = tt_tuning_sample_at(t, i)->config;
    tt_config *c = tt_config_create(s);
    CHECK(tt_config_from_json(c, ci, "sample") == TT_OK);
    CHECK_MSG(is_canonical(c, start), "exploration sample %zu not canonical: %s", i, ci);
    debug_off += tt_config_get_int(c, "debug", 1) == 0;
    mode_a += tt_config_get_int(c, "mode", 1) == 0;
    tt_config_destroy(c);
    for (size_t j = 0; j < i; j++) distinct &= strcmp(ci, tt_tuning_sample_at(t, j)->config) != 0;
  }
  CHECK_MSG(debug_off == 0, "exploration changed the setting debug in %d samples", debug_off);
  CHECK_MSG(mode_a == 1, "exploration measured mode a %d times (one configuration)", mode_a);
  CHECK_MSG(distinct, "exploration measured a configuration twice");
  tt_tuning_destroy(t);

  /* the session hands a tuner a space without the setting (tuner_nm sees 3 parameters) */
  tt_loaded_plugin *nm = tt_registry_find_kind(reg, TT_KIND_TUNER); /* test_tuners' */
  d.tuner = nm ? tt_loaded_plugin_iface(nm) : NULL;
  d.tuner_name = "tuner_nm";
  d.iterations = 30;
  t = NULL;
  CHECK_MSG(tt_tuning_create(&d, &t) == TT_OK, "%s", tt_last_error());
  CHECK(t && tt_tuning_run(t, &tg) == TT_OK);
  for (size_t i = 0; t && i < tt_tuning_sample_count(t); i++)
    CHECK_CONTAINS(tt_tuning_sample_at(t, i)->config, "\"debug\":true");
  tt_tuning_destroy(t);

  /* nothing left to search: an error naming what was left out */
  const char *names[] = {"x", "debug"};
  tt_space *sub = tt_space_subset(s, names, 2, NULL); /* mode fixed at a: x never acts */
  d.tuner = NULL;
  d.search = sub;
  t = NULL;
  CHECK(tt_tuning_create(&d, &t) == TT_ERR_INVALID_ARGUMENT && t == NULL);
  CHECK_CONTAINS(tt_last_error(), "nothing to search: x, debug are not tunable");
  tt_space_destroy(sub);
  tt_config_destroy(start);
  tt_space_destroy(s);
  (void)t_apply;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: tune_marking TUNER_RANDOM.so\n");
    return 1;
  }
  tt_registry *reg = tt_registry_create(tt_default_host());
  test_space_api();
  test_tuners(reg, argv[1]);
  test_session(reg);
  tt_registry_destroy(reg);
  return tt_test_finish("tune_marking");
}
