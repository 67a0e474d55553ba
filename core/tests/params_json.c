/* JSON for spaces and configurations: round trips preserve everything, and malformed
 * inputs fail with messages naming the source, the JSON path and what was expected. */
#include <tunetrace/params.h>

#include "tt_test.h"

#include <stdint.h>
#include <string.h>

/* The accel_embree-like space of params_space.c, with a log FLOAT and large INT bounds. */
static tt_space *make_space(void) {
  tt_space *s = tt_space_create("accel_embree", "1.2.3");
  const int64_t quality[] = {1, 2, 3};
  const int64_t branch[] = {2, 4, 8};
  const char *const backend[] = {"native", "custom \"quoted\""};
  CHECK(tt_space_add_nom_int(s, "quality", quality, 3, 1, "1 Morton, 2 binned SAH, 3 SBVH") == 0);
  CHECK(tt_space_add_nom_int(s, "branchingFactor", branch, 3, 0, "BVH width") == 1);
  CHECK(tt_space_add_int(s, "maxDepth", 4, 64, 32, "maximum tree depth") == 2);
  CHECK(tt_space_add_float(s, "intcost", 0.1, 10.0, 1.0, 0, "") == 3);
  CHECK(tt_space_add_nom_bool(s, "static", 1, "static scene") == 4);
  CHECK(tt_space_add_nom_bool(s, "compact", 0, NULL) == 5);
  CHECK(tt_space_add_nom_string(s, "backend", backend, 2, 1, "kernel backend") == 6);
  CHECK(tt_space_add_float(s, "travcost", 1e-3, 1e3, 0.3, 1, "log-scaled cost") == 7);
  /* At the +-2^53 limit, where cJSON's default printing would switch to exponents. */
  CHECK(tt_space_add_int(s, "seed", -9007199254740992LL, 9007199254740992LL, 9007199254740991LL,
                         "seed") == 8);
  tt_space_add_constraint_text(s, "branchingFactor^(maxDepth-1)*maxLeafSize >= N");
  tt_space_add_constraint_text(s, "robust implies !compact");
  return s;
}

/* Values equal in every field that matters (string pointers differ between spaces). */
static int value_equal(tt_value a, tt_value b) {
  if (a.kind != b.kind || a.index != b.index) return 0;
  if (a.kind == TT_VALUE_STRING) return strcmp(a.s, b.s) == 0;
  return a.i == b.i && a.f == b.f;
}

/* Space -> JSON -> space keeps names, types, ranges, values, defaults, texts. */
static void test_space_round_trip(void) {
  tt_space *s = make_space();
  char *json = tt_space_to_json(s);
  CHECK(json != NULL);
  CHECK_CONTAINS(json, "\"plugin\":\t\"accel_embree\"");
  CHECK_CONTAINS(json, "\"type\":\t\"NOM\"");
  CHECK_CONTAINS(json, "\"possibleValues\":\t[2, 4, 8]");
  CHECK_CONTAINS(json, "\"possibleValues\":\t[false, true]");
  CHECK_CONTAINS(json, "\"log\":\ttrue");
  CHECK_CONTAINS(json, "\"max\":\t9007199254740992");
  CHECK_CONTAINS(json, "\"description\":\t\"robust implies !compact\"");
  CHECK(strstr(json, "\"log\":\tfalse") == NULL); /* "log" only when true */

  tt_space *r = tt_space_from_json(json, "roundtrip.json");
  CHECK_MSG(r != NULL, "%s", tt_last_error());
  if (r) {
    CHECK(strcmp(tt_space_plugin(r), "accel_embree") == 0);
    CHECK(tt_space_count(r) == tt_space_count(s));
    for (size_t i = 0; i < tt_space_count(s); i++) {
      CHECK(strcmp(tt_space_name(r, i), tt_space_name(s, i)) == 0);
      CHECK(tt_space_type(r, i) == tt_space_type(s, i));
      CHECK(strcmp(tt_space_description(r, i), tt_space_description(s, i)) == 0);
      CHECK(tt_space_min(r, i) == tt_space_min(s, i));
      CHECK(tt_space_max(r, i) == tt_space_max(s, i));
      CHECK(tt_space_is_log(r, i) == tt_space_is_log(s, i));
      CHECK(tt_space_nom_count(r, i) == tt_space_nom_count(s, i));
      for (size_t k = 0; k < tt_space_nom_count(s, i); k++)
        CHECK(value_equal(tt_space_nom_value(r, i, k), tt_space_nom_value(s, i, k)));
      CHECK_MSG(value_equal(tt_space_default(r, i), tt_space_default(s, i)), "param %zu", i);
    }
    CHECK(tt_space_default(r, 8).i == 9007199254740991LL);
    /* Serialising again gives the same text: nothing was lost or reordered. */
    char *again = tt_space_to_json(r);
    CHECK(again && strcmp(again, json) == 0);
    tt_free(again);
    tt_space_destroy(r);
  }
  tt_free(json);
  tt_space_destroy(s);
}

/* Config -> JSON -> config over a non-default configuration. */
static void test_config_round_trip(void) {
  tt_space *s = make_space();
  tt_config *a = tt_config_create(s), *b = tt_config_create(s);
  CHECK(tt_config_set_string(a, "quality", "3") == TT_OK);
  CHECK(tt_config_set_string(a, "maxDepth", "17") == TT_OK);
  CHECK(tt_config_set_string(a, "intcost", "0.30000000000000004") == TT_OK);
  CHECK(tt_config_set_string(a, "static", "false") == TT_OK);
  CHECK(tt_config_set_string(a, "backend", "native") == TT_OK);
  CHECK(tt_config_set_string(a, "seed", "-9007199254740991") == TT_OK);
  char *json = tt_config_to_json(a);
  CHECK(json != NULL);
  CHECK_CONTAINS(json, "\"quality\":3");
  CHECK_CONTAINS(json, "\"static\":false");
  CHECK_CONTAINS(json, "\"backend\":\"native\"");
  CHECK_CONTAINS(json, "\"seed\":-9007199254740991");
  CHECK(!tt_config_equal(a, b));
  CHECK(tt_config_from_json(b, json, "cfg.json") == TT_OK);
  CHECK(tt_config_equal(a, b));
  CHECK(tt_config_get_float(b, "intcost", 0) == 0.30000000000000004);
  tt_free(json);

  /* A partial object changes only the named parameters. */
  CHECK(tt_config_from_json(b, "{\"maxDepth\": 5, \"compact\": true}", "partial") == TT_OK);
  CHECK(tt_config_get_int(b, "maxDepth", -1) == 5 && tt_config_get_int(b, "compact", -1) == 1);
  CHECK(tt_config_get_int(b, "quality", -1) == 3);

  /* Config JSON errors leave the configuration untouched. */
  tt_config *before = tt_config_clone(b);
  struct {
    const char *json, *expect;
  } bad[] = {
      {"{\"maxDepth\": 6, \"bogus\": 1}",
       "cfg.json: unknown parameter \"bogus\" of accel_embree (known: quality"},
      {"{\"maxDepth\": 65}", "cfg.json: accel_embree.maxDepth: 65 is out of range [4, 64]"},
      {"{\"maxDepth\": 6.5}", "accel_embree.maxDepth: 6.5 is not an integer"},
      {"{\"maxDepth\": \"6\"}",
       "cfg.json: accel_embree.maxDepth: expected an integer, got a string (\"6\")"},
      {"{\"branchingFactor\": 3}",
       "cfg.json: accel_embree.branchingFactor: 3 is not one of 2, 4, 8"},
      {"{\"static\": 1}",
       "cfg.json: accel_embree.static: expected true or false, got the number 1"},
      {"{\"backend\": \"cuda\"}", "accel_embree.backend: expected one of \"native\", \"custom "
                                  "\"quoted\"\", got a string (\"cuda\")"},
      {"{\"intcost\": null}", "accel_embree.intcost: expected a number, got null"},
      {"{\"quality\": 1, \"quality\": 2}", "cfg.json: quality: appears twice"},
      {"[1, 2]", "cfg.json: expected a JSON object"},
      {"{\"quality\": 1,", "cfg.json: invalid JSON at line 1"},
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
    CHECK_MSG(tt_config_from_json(b, bad[k].json, "cfg.json") == TT_ERR_PARSE, "case %zu", k);
    CHECK_CONTAINS(tt_last_error(), bad[k].expect);
    CHECK_MSG(tt_config_equal(b, before), "case %zu changed the config", k);
  }
  tt_config_destroy(before);
  tt_config_destroy(a);
  tt_config_destroy(b);
  tt_space_destroy(s);
}

/* A small hand-written space in the thesis' exact Fig. 3.1 shape parses as expected. */
static void test_fig31(void) {
  const char *json =
      "{ \"plugin\": \"accel_embree\", \"version\": \"1.0.0\",\n"
      "  \"parameters\": [\n"
      "    { \"name\": \"quality\", \"type\": \"NOM\", \"possibleValues\": [1, 2, 3], \"value\": 2 "
      "},\n"
      "    { \"name\": \"maxDepth\", \"type\": \"INT\", \"min\": 4, \"max\": 64, \"value\": 32 },\n"
      "    { \"name\": \"intcost\", \"type\": \"FLOAT\", \"min\": 0.1, \"max\": 10.0, \"value\": "
      "1.0 } ] }";
  tt_space *s = tt_space_from_json(json, "fig31.json");
  CHECK_MSG(s != NULL, "%s", tt_last_error());
  if (!s) return;
  CHECK(tt_space_count(s) == 3);
  CHECK(tt_space_default(s, 0).index == 1 && tt_space_default(s, 0).i == 2);
  CHECK(tt_space_type(s, 1) == TT_PARAM_INT && tt_space_max(s, 1) == 64);
  CHECK(tt_space_type(s, 2) == TT_PARAM_FLOAT && tt_space_min(s, 2) == 0.1);
  CHECK(strcmp(tt_space_description(s, 0), "") == 0);
  tt_space_destroy(s);
}

/* Wraps one parameter object into a whole space document. */
static void space_with(char *buf, size_t size, const char *params) {
  snprintf(buf, size,
           "{\"plugin\": \"p\", \"version\": \"1\", \"parameters\": [\n"
           "  {\"name\": \"ok\", \"type\": \"INT\", \"min\": 0, \"max\": 3, \"value\": 1},\n"
           "  %s]}",
           params);
}

/* Malformed space JSON: each fails, and the message names source, path and expectation. */
static void test_space_errors(void) {
  struct {
    const char *param, *expect;
  } bad[] = {
      {"{\"name\": \"a\", \"min\": 0, \"max\": 1, \"value\": 0}",
       "bad.json: parameters[1].type: missing (expected \"INT\", \"FLOAT\" or \"NOM\")"},
      {"{\"name\": \"a\", \"type\": \"BOOL\", \"possibleValues\": [false, true], \"value\": true}",
       "bad.json: parameters[1].type: unknown type \"BOOL\" (expected \"INT\", \"FLOAT\" or "
       "\"NOM\""},
      {"{\"name\": \"a\", \"type\": \"INT\", \"min\": 5, \"max\": 1, \"value\": 3}",
       "bad.json: parameters[1].max: 1 is less than min 5"},
      {"{\"name\": \"a\", \"type\": \"FLOAT\", \"min\": 2.5, \"max\": 1.5, \"value\": 2}",
       "bad.json: parameters[1].max: 1.5 is less than min 2.5"},
      {"{\"name\": \"a\", \"type\": \"INT\", \"min\": 0, \"max\": 10, \"value\": 11}",
       "bad.json: parameters[1].value: default 11 is outside [0, 10]"},
      {"{\"name\": \"a\", \"type\": \"FLOAT\", \"min\": 0, \"max\": 1, \"value\": -0.5}",
       "bad.json: parameters[1].value: default -0.5 is outside [0, 1]"},
      {"{\"name\": \"a\", \"type\": \"NOM\", \"possibleValues\": [], \"value\": 1}",
       "bad.json: parameters[1].possibleValues: empty (expected at least one possible value)"},
      {"{\"name\": \"a\", \"type\": \"NOM\", \"possibleValues\": [1, \"two\", 3], \"value\": 1}",
       "bad.json: parameters[1].possibleValues[1]: mixed value kinds (possibleValues[0] is an "
       "integer, this is a string"},
      {"{\"name\": \"a\", \"type\": \"NOM\", \"possibleValues\": [1.5, 2], \"value\": 2}",
       "bad.json: parameters[1].possibleValues[0]: expected an integer, boolean or string, got "
       "the number 1.5"},
      {"{\"name\": \"a\", \"type\": \"NOM\", \"possibleValues\": [1, 2, 1], \"value\": 1}",
       "bad.json: parameters[1].possibleValues[2]: duplicate value"},
      {"{\"name\": \"a\", \"type\": \"NOM\", \"possibleValues\": [1, 2], \"value\": 3}",
       "bad.json: parameters[1].value: default the number 3 is not one of possibleValues"},
      {"{\"name\": \"a\", \"type\": \"NOM\", \"possibleValues\": [\"x\", \"y\"], \"value\": 0}",
       "bad.json: parameters[1].value: default the number 0 is not one of possibleValues"},
      {"{\"name\": \"a\", \"type\": \"NOM\", \"possibleValues\": [true, false], \"value\": true}",
       "bad.json: parameters[1].possibleValues: boolean possible values must be [false, true]"},
      {"{\"name\": \"a\", \"type\": \"NOM\", \"value\": 1}",
       "bad.json: parameters[1].possibleValues: missing (expected a non-empty array)"},
      {"{\"name\": \"ok\", \"type\": \"INT\", \"min\": 0, \"max\": 1, \"value\": 0}",
       "bad.json: parameters[1].name: duplicate name \"ok\" (already used by parameters[0])"},
      {"{\"type\": \"INT\", \"min\": 0, \"max\": 1, \"value\": 0}",
       "bad.json: parameters[1].name: expected a non-empty string, got nothing"},
      {"{\"name\": \"a\", \"type\": \"INT\", \"min\": 0.5, \"max\": 1, \"value\": 1}",
       "bad.json: parameters[1].min: expected an integer, got the number 0.5"},
      {"{\"name\": \"a\", \"type\": \"INT\", \"min\": 0, \"value\": 0}",
       "bad.json: parameters[1].max: missing (expected an integer)"},
      {"{\"name\": \"a\", \"type\": \"FLOAT\", \"min\": \"0\", \"max\": 1, \"value\": 0}",
       "bad.json: parameters[1].min: expected a number, got a string (\"0\")"},
      {"{\"name\": \"a\", \"type\": \"FLOAT\", \"min\": 0, \"max\": 1, \"value\": 0.5, \"log\": "
       "true}",
       "bad.json: parameters[1].log: log scale needs min > 0, got min 0"},
      {"{\"name\": \"a\", \"type\": \"INT\", \"min\": 1, \"max\": 8, \"value\": 2, \"log\": true}",
       "bad.json: parameters[1].log: only FLOAT parameters may be log-scaled"},
      {"{\"name\": \"a\", \"type\": \"INT\", \"min\": 0, \"max\": 1, \"value\": 0, "
       "\"description\": 7}",
       "bad.json: parameters[1].description: expected a string, got the number 7"},
      {"{\"name\": \"a\", \"type\": \"INT\", \"min\": 0, \"max\": 1e300, \"value\": 0}",
       "bad.json: parameters[1].max: expected an integer within +-2^53, got the number "
       "1.0000000000000001e+300"},
      {"{\"name\": \"a\", \"type\": \"INT\", \"min\": 0, \"max\": 9223372036854775807, \"value\": "
       "0}",
       "bad.json: parameters[1].max: expected an integer within +-2^53, got the number "
       "9.2233720368547758e+18"},
      {"{\"name\": \"a\", \"type\": \"NOM\", \"possibleValues\": [1, 9007199254740994], \"value\": "
       "1}",
       "bad.json: parameters[1]: tt_space_add_nom_int: p.a: possible value 9007199254740994 "
       "exceeds +-2^53"},
      {"42", "bad.json: parameters[1]: expected a parameter object, got the number 42"},
  };
  char buf[1024];
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
    space_with(buf, sizeof buf, bad[k].param);
    tt_clear_error();
    tt_space *s = tt_space_from_json(buf, "bad.json");
    CHECK_MSG(s == NULL, "case %zu parsed", k);
    CHECK_CONTAINS(tt_last_error(), bad[k].expect);
    tt_space_destroy(s);
  }
  /* The same wrapper with a valid parameter parses: the cases above fail for their reason. */
  space_with(buf, sizeof buf,
             "{\"name\": \"a\", \"type\": \"NOM\", \"possibleValues\": [\"x\", \"y\"], "
             "\"value\": \"y\"}");
  tt_space *good = tt_space_from_json(buf, "good.json");
  CHECK_MSG(good != NULL, "%s", tt_last_error());
  CHECK(good && tt_space_count(good) == 2 && tt_space_default(good, 1).index == 1);
  tt_space_destroy(good);

  struct {
    const char *json, *expect;
  } top[] = {
      {"{\"plugin\": \"p\", \"parameters\": [}", "bad.json: invalid JSON at line 1, column 32"},
      {"{\n  \"plugin\": \"p\",\n  \"parameters\": [\n    {\"name\": }\n]}",
       "bad.json: invalid JSON at line 4, column 14"},
      {"[]", "bad.json: expected a JSON object at the top level, got an array"},
      {"{\"parameters\": []}",
       "bad.json: plugin: expected the plugin name as a string, got nothing"},
      {"{\"plugin\": \"p\"}", "bad.json: parameters: expected an array of parameter objects"},
      {"{\"plugin\": \"p\", \"version\": 2, \"parameters\": []}",
       "bad.json: version: expected a version string"},
      {"{\"plugin\": \"p\", \"parameters\": [], \"constraints\": [{\"text\": \"x\"}]}",
       "bad.json: constraints[0]: expected {\"description\": \"...\"}, got an object"},
      {"{\"plugin\": \"p\", \"parameters\": []} trailing", "bad.json: invalid JSON at line 1"},
  };
  for (size_t k = 0; k < sizeof top / sizeof top[0]; k++) {
    tt_space *s = tt_space_from_json(top[k].json, "bad.json");
    CHECK_MSG(s == NULL, "top case %zu parsed", k);
    CHECK_CONTAINS(tt_last_error(), top[k].expect);
    tt_space_destroy(s);
  }
  CHECK(tt_space_from_json(NULL, "null.json") == NULL);
  CHECK_CONTAINS(tt_last_error(), "null.json: no JSON text");
}

/* "motionOnly": a parameter that acts only while the scene moves: read, written back, kept by
 * a subset, refused when not a boolean (naming the field). */
static void test_motion_only(void) {
  char buf[1024];
  space_with(buf, sizeof buf,
             "{\"name\": \"m\", \"type\": \"NOM\", \"possibleValues\": [\"a\", \"b\"], "
             "\"value\": \"a\", \"motionOnly\": true}");
  tt_space *s = tt_space_from_json(buf, "motion.json");
  CHECK_MSG(s != NULL, "%s", tt_last_error());
  if (!s) return;
  CHECK(tt_space_is_motion_only(s, 1) && !tt_space_is_motion_only(s, 0) &&
        tt_space_is_tunable(s, 1) && !tt_space_is_motion_only(s, 7));
  char *json = tt_space_to_json(s);
  const char *mo = json ? strstr(json, "\"motionOnly\"") : NULL;
  CHECK(mo && !strstr(mo + 1, "\"motionOnly\"")); /* written for m alone */
  tt_space *back = json ? tt_space_from_json(json, "written") : NULL;
  CHECK(back && tt_space_is_motion_only(back, 1) && !tt_space_is_motion_only(back, 0));
  const char *names[] = {"m"};
  tt_space *sub = tt_space_subset(s, names, 1, NULL);
  CHECK(sub && tt_space_is_motion_only(sub, 0));
  tt_space_destroy(sub);
  tt_space_destroy(back);
  tt_free(json);
  tt_space_destroy(s);
  space_with(buf, sizeof buf,
             "{\"name\": \"m\", \"type\": \"INT\", \"min\": 0, \"max\": 2, \"value\": 0, "
             "\"motionOnly\": 1}");
  CHECK(tt_space_from_json(buf, "bad.json") == NULL);
  CHECK_CONTAINS(tt_last_error(), "bad.json: parameters[1].motionOnly: expected true or false");
}

int main(void) {
  test_motion_only();
  test_space_round_trip();
  test_config_round_trip();
  test_fig31();
  test_space_errors();
  return tt_test_finish("params_json");
}
