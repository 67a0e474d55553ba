/* Parameter spaces and configurations: defaults, strict setters and their messages, the
 * unit-cube mapping, copies, and constraint checks, on an accel_embree-like space
 * (thesis Table 3.1) plus a string NOM. */
#include <tunetrace/params.h>

#include "tt_test.h"

#include <stdint.h>
#include <string.h>
#include <tt_util/rng.h>

enum {
  P_QUALITY,
  P_BRANCH,
  P_DEPTH,
  P_INTCOST,
  P_STATIC,
  P_COMPACT,
  P_ROBUST,
  P_BACKEND,
  P_LEAF,
  P_TRAV,
  P_COUNT
};

/* Builds the test space; every add must succeed and return its position. */
static tt_space *make_space(void) {
  tt_space *s = tt_space_create("accel_embree", "1.0.0");
  const int64_t quality[] = {1, 2, 3};
  const int64_t branch[] = {2, 4, 8};
  const char *const backend[] = {"native", "custom"};
  CHECK(tt_space_add_nom_int(s, "quality", quality, 3, 1, "build quality") == P_QUALITY);
  CHECK(tt_space_add_nom_int(s, "branchingFactor", branch, 3, 0, "BVH width") == P_BRANCH);
  CHECK(tt_space_add_int(s, "maxDepth", 4, 64, 32, "maximum tree depth") == P_DEPTH);
  CHECK(tt_space_add_float(s, "intcost", 0.1, 10.0, 1.0, 0, "intersection cost") == P_INTCOST);
  CHECK(tt_space_add_nom_bool(s, "static", 1, "static scene") == P_STATIC);
  CHECK(tt_space_add_nom_bool(s, "compact", 0, "compact layout") == P_COMPACT);
  CHECK(tt_space_add_nom_bool(s, "robust", 0, "robust traversal") == P_ROBUST);
  CHECK(tt_space_add_nom_string(s, "backend", backend, 2, 0, "kernel backend") == P_BACKEND);
  CHECK(tt_space_add_int(s, "maxLeafSize", 1, 16, 4, NULL) == P_LEAF);
  CHECK(tt_space_add_float(s, "travcost", 0.01, 100.0, 1.0, 1, "log-scaled") == P_TRAV);
  tt_space_add_constraint_text(s, "branchingFactor^(maxDepth-1)*maxLeafSize >= N");
  return s;
}

/* Reader functions and defaults. */
static void test_readers_and_defaults(const tt_space *s) {
  CHECK(strcmp(tt_space_plugin(s), "accel_embree") == 0);
  CHECK(tt_space_count(s) == P_COUNT);
  CHECK(tt_space_find(s, "maxDepth") == P_DEPTH);
  CHECK(tt_space_find(s, "nope") == -1);
  CHECK(strcmp(tt_space_name(s, P_INTCOST), "intcost") == 0);
  CHECK(tt_space_type(s, P_QUALITY) == TT_PARAM_NOM);
  CHECK(tt_space_type(s, P_DEPTH) == TT_PARAM_INT);
  CHECK(tt_space_type(s, P_INTCOST) == TT_PARAM_FLOAT);
  CHECK(strcmp(tt_space_description(s, P_BRANCH), "BVH width") == 0);
  CHECK(strcmp(tt_space_description(s, P_LEAF), "") == 0);
  CHECK(tt_space_min(s, P_DEPTH) == 4.0 && tt_space_max(s, P_DEPTH) == 64.0);
  CHECK(tt_space_min(s, P_BRANCH) == 0.0 && tt_space_max(s, P_BRANCH) == 2.0);
  CHECK(tt_space_is_log(s, P_TRAV) && !tt_space_is_log(s, P_INTCOST));
  CHECK(tt_space_nom_count(s, P_BRANCH) == 3);
  CHECK(tt_space_nom_count(s, P_DEPTH) == 0);
  CHECK(tt_space_nom_value(s, P_BRANCH, 2).i == 8);
  CHECK(tt_space_nom_value(s, P_BRANCH, 3).index == -1);
  CHECK(strcmp(tt_space_nom_value(s, P_BACKEND, 1).s, "custom") == 0);

  tt_value d = tt_space_default(s, P_QUALITY);
  CHECK(d.kind == TT_VALUE_INT && d.index == 1 && d.i == 2 && d.f == 2.0);
  d = tt_space_default(s, P_BRANCH);
  CHECK(d.kind == TT_VALUE_INT && d.index == 0 && d.i == 2);
  d = tt_space_default(s, P_DEPTH);
  CHECK(d.kind == TT_VALUE_INT && d.index == -1 && d.i == 32 && d.f == 32.0);
  d = tt_space_default(s, P_INTCOST);
  CHECK(d.kind == TT_VALUE_FLOAT && d.index == -1 && d.f == 1.0);
  d = tt_space_default(s, P_STATIC);
  CHECK(d.kind == TT_VALUE_BOOL && d.index == 1 && d.i == 1 && d.f == 1.0);
  d = tt_space_default(s, P_BACKEND);
  CHECK(d.kind == TT_VALUE_STRING && d.index == 0 && strcmp(d.s, "native") == 0);

  tt_config *c = tt_config_create(s);
  CHECK(c != NULL && tt_config_space(c) == s);
  CHECK(tt_config_get_int(c, "quality", -1) == 2);
  CHECK(tt_config_get_int(c, "branchingFactor", -1) == 2);
  CHECK(tt_config_get_int(c, "maxDepth", -1) == 32);
  CHECK_NEAR(tt_config_get_float(c, "intcost", -1), 1.0, 0);
  CHECK(tt_config_get_int(c, "static", -1) == 1);
  CHECK(tt_config_get_int(c, "compact", -1) == 0);
  CHECK(tt_config_get_int(c, "backend", -1) == 0); /* string NOM -> index */
  CHECK_NEAR(tt_config_get_float(c, "static", -1), 1.0, 0);
  CHECK(strcmp(tt_config_get_string(c, "backend"), "native") == 0);
  CHECK(tt_config_get_string(c, "maxDepth") == NULL);
  CHECK(tt_config_get_int(c, "unknown", 77) == 77);
  CHECK_NEAR(tt_config_get_float(c, "unknown", 0.25), 0.25, 0);
  for (size_t i = 0; i < P_COUNT; i++) {
    tt_value a = tt_config_get(c, i), b = tt_space_default(s, i);
    CHECK(a.kind == b.kind && a.index == b.index && a.i == b.i && a.f == b.f && a.s == b.s);
  }
  tt_config_destroy(c);
}

/* Bad ranges, duplicates and log with min <= 0 are rejected with -1 and a message. */
static void test_builder_errors(void) {
  tt_space *s = tt_space_create("p", "1");
  const int64_t v[] = {1, 2, 1};
  const char *const sv[] = {"a", "b"};
  CHECK(tt_space_add_int(s, "a", 0, 10, 5, NULL) == 0);
  CHECK(tt_space_add_int(s, "a", 0, 10, 5, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "duplicate parameter name \"a\"");
  CHECK(tt_space_add_float(s, "a", 0, 1, 0.5, 0, NULL) == -1);
  CHECK(tt_space_add_int(s, "b", 10, 0, 5, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "min 10 is greater than max 0");
  CHECK(tt_space_add_int(s, "b", 0, 10, 11, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "default 11 is outside [0, 10]");
  CHECK(tt_space_add_float(s, "b", 2.0, 1.0, 1.5, 0, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "p.b: min 2 is greater than max 1");
  CHECK(tt_space_add_float(s, "b", 0.0, 1.0, 1.5, 0, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "default 1.5 is outside [0, 1]");
  CHECK(tt_space_add_float(s, "b", 0.0, 1.0, 0.5, 1, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "log scale needs min > 0");
  CHECK(tt_space_add_float(s, "b", 0.0, NAN, 0.5, 0, NULL) == -1);
  CHECK(tt_space_add_nom_int(s, "b", v, 0, 0, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "possible values are empty");
  CHECK(tt_space_add_nom_int(s, "b", v, 2, 2, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "default index 2 is outside [0, 1]");
  CHECK(tt_space_add_nom_int(s, "b", v, 3, 0, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "possible value 1 appears twice");
  CHECK(tt_space_add_int(s, "b", 0, INT64_MAX, 0, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "exceeds +-2^53");
  const int64_t huge[] = {1, ((int64_t)1 << 53) + 1};
  CHECK(tt_space_add_nom_int(s, "b", huge, 2, 0, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "possible value 9007199254740993 exceeds +-2^53");
  CHECK(tt_space_add_nom_string(s, "b", sv, 2, 5, NULL) == -1);
  CHECK(tt_space_add_nom_string(s, "", sv, 2, 0, NULL) == -1);
  CHECK(tt_space_count(s) == 1); /* failures added nothing */
  CHECK(tt_space_add_nom_string(s, "b", sv, 2, 1, NULL) == 1);
  /* Once configurations exist the space is published and frozen. */
  tt_config *c = tt_config_create(s);
  CHECK(tt_space_add_int(s, "late", 0, 1, 0, NULL) == -1);
  CHECK_CONTAINS(tt_last_error(), "immutable once published");
  CHECK(tt_space_count(s) == 2);
  tt_config_destroy(c);
  tt_space_destroy(s);
}

/* set_string / set_number / set_index successes and every error message. */
static void test_setters(const tt_space *s) {
  tt_config *c = tt_config_create(s);
  CHECK(tt_config_set_string(c, "maxDepth", "4") == TT_OK);
  CHECK(tt_config_get_int(c, "maxDepth", -1) == 4);
  CHECK(tt_config_set_string(c, "maxDepth", " 64 ") == TT_OK);
  CHECK(tt_config_get_int(c, "maxDepth", -1) == 64);
  CHECK(tt_config_set_string(c, "maxDepth", "1e1") == TT_OK); /* integral in any form */
  CHECK(tt_config_get_int(c, "maxDepth", -1) == 10);
  CHECK(tt_config_get(c, P_DEPTH).f == 10.0);
  CHECK(tt_config_set_string(c, "intcost", "0.5") == TT_OK);
  CHECK_NEAR(tt_config_get_float(c, "intcost", -1), 0.5, 0);
  CHECK(tt_config_set_string(c, "travcost", "1e-2") == TT_OK);
  CHECK_NEAR(tt_config_get_float(c, "travcost", -1), 0.01, 0);
  CHECK(tt_config_set_string(c, "branchingFactor", "8") == TT_OK);
  CHECK(tt_config_get(c, P_BRANCH).index == 2 && tt_config_get(c, P_BRANCH).i == 8);
  CHECK(tt_config_set_string(c, "static", "false") == TT_OK);
  CHECK(tt_config_get_int(c, "static", -1) == 0);
  CHECK(tt_config_set_string(c, "compact", "true") == TT_OK);
  CHECK(tt_config_get(c, P_COMPACT).kind == TT_VALUE_BOOL && tt_config_get(c, P_COMPACT).i == 1);
  CHECK(tt_config_set_string(c, "robust", "1") == TT_OK);
  CHECK(tt_config_get_int(c, "robust", -1) == 1);
  CHECK(tt_config_set_string(c, "backend", "custom") == TT_OK);
  CHECK(strcmp(tt_config_get_string(c, "backend"), "custom") == 0);
  CHECK(tt_config_get_int(c, "backend", -1) == 1);

  tt_config *before = tt_config_clone(c);
  CHECK(tt_config_set_string(c, "branchingFactor", "3") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_embree.branchingFactor: \"3\" is not one of 2, 4, 8");
  CHECK(tt_config_set_string(c, "maxDepth", "3.5") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_embree.maxDepth: \"3.5\" is not an integer in [4, 64]");
  CHECK(tt_config_set_string(c, "maxDepth", "65") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_embree.maxDepth: \"65\" is out of range [4, 64]");
  CHECK(tt_config_set_string(c, "maxDepth", "deep") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_embree.maxDepth: \"deep\" is not an integer in [4, 64]");
  CHECK(tt_config_set_string(c, "intcost", "20") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_embree.intcost: \"20\" is out of range [0.1, 10]");
  CHECK(tt_config_set_string(c, "intcost", "0.5x") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_embree.intcost: \"0.5x\" is not a number in [0.1, 10]");
  CHECK(tt_config_set_string(c, "intcost", "nan") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "is not a finite number");
  CHECK(tt_config_set_string(c, "static", "yes") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_embree.static: \"yes\" is not one of false, true");
  CHECK(tt_config_set_string(c, "backend", "cuda") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(),
                 "accel_embree.backend: \"cuda\" is not one of \"native\", \"custom\"");
  CHECK(tt_config_set_string(c, "quality", "two") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_embree.quality: \"two\" is not one of 1, 2, 3");
  CHECK(tt_config_set_string(c, "bogus", "1") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_embree: unknown parameter \"bogus\"");
  CHECK(tt_config_equal(c, before)); /* failed sets change nothing */

  /* Numeric setter: strict, no clamping. */
  CHECK(tt_config_set_number(c, P_DEPTH, 16) == TT_OK);
  CHECK(tt_config_get_int(c, "maxDepth", -1) == 16);
  CHECK(tt_config_set_number(c, P_DEPTH, 16.5) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "maxDepth: 16.5 is not an integer");
  CHECK(tt_config_set_number(c, P_DEPTH, 100) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "maxDepth: 100 is out of range [4, 64]");
  CHECK(tt_config_set_number(c, P_DEPTH, 1e300) == TT_ERR_INVALID_ARGUMENT);
  CHECK(tt_config_get_int(c, "maxDepth", -1) == 16);
  CHECK(tt_config_set_number(c, P_INTCOST, 10.0) == TT_OK);
  CHECK(tt_config_set_number(c, P_INTCOST, 10.0001) == TT_ERR_INVALID_ARGUMENT);
  CHECK_NEAR(tt_config_get_float(c, "intcost", -1), 10.0, 0);
  CHECK(tt_config_set_number(c, P_BRANCH, 4) == TT_OK);
  CHECK(tt_config_get(c, P_BRANCH).index == 1);
  CHECK(tt_config_set_number(c, P_BRANCH, 5) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "branchingFactor: 5 is not one of 2, 4, 8");
  CHECK(tt_config_set_number(c, P_STATIC, 1) == TT_OK);
  CHECK(tt_config_set_number(c, P_STATIC, 2) == TT_ERR_INVALID_ARGUMENT);
  CHECK(tt_config_set_number(c, P_BACKEND, 0) == TT_ERR_INVALID_ARGUMENT);
  CHECK(tt_config_set_number(c, P_COUNT, 0) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "parameter index 10 is out of range");

  CHECK(tt_config_set_index(c, P_BACKEND, 0) == TT_OK);
  CHECK(strcmp(tt_config_get_string(c, "backend"), "native") == 0);
  CHECK(tt_config_set_index(c, P_QUALITY, 2) == TT_OK);
  CHECK(tt_config_get_int(c, "quality", -1) == 3);
  CHECK(tt_config_set_index(c, P_QUALITY, 3) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "quality: index 3 is out of range [0, 2]");
  CHECK(tt_config_set_index(c, P_DEPTH, 0) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "maxDepth is not a NOM parameter");

  tt_config_destroy(before);
  tt_config_destroy(c);
}

/* Small deterministic PRNG (SplitMix64), so failures reproduce. */
static uint64_t rng_state = 1;
static double rnd(void) { return tt__u64_to_unit(tt__splitmix64(&rng_state)); }

/* to_unit/from_unit: exact inverses on configs, approximate on unit points, clamping. */
static void test_unit_cube(const tt_space *s) {
  tt_config *c = tt_config_create(s), *d = tt_config_create(s);
  double u[P_COUNT], u2[P_COUNT];

  /* Defaults map where the formulas say. */
  tt_config_to_unit(c, u);
  CHECK_NEAR(u[P_QUALITY], 1.5 / 3.0, 1e-12);
  CHECK_NEAR(u[P_BRANCH], 0.5 / 3.0, 1e-12);
  CHECK_NEAR(u[P_DEPTH], (32.0 - 4.0) / 60.0, 1e-12);
  CHECK_NEAR(u[P_INTCOST], (1.0 - 0.1) / 9.9, 1e-12);
  CHECK_NEAR(u[P_STATIC], 0.75, 1e-12);
  CHECK_NEAR(u[P_BACKEND], 0.25, 1e-12);
  CHECK_NEAR(u[P_TRAV], 0.5, 1e-12); /* log: 1 is the geometric middle of [0.01, 100] */

  int bins[P_COUNT][3] = {{0}};
  for (int trial = 0; trial < 2000; trial++) {
    for (size_t i = 0; i < P_COUNT; i++) u[i] = rnd();
    tt_config_from_unit(c, u);
    /* Every value is valid: re-setting it strictly must succeed. */
    for (size_t i = 0; i < P_COUNT; i++) {
      tt_value v = tt_config_get(c, i);
      if (tt_space_type(s, i) == TT_PARAM_NOM) {
        CHECK(v.index >= 0 && (size_t)v.index < tt_space_nom_count(s, i));
        CHECK(v.index == (int)(u[i] * (double)tt_space_nom_count(s, i)));
        bins[i][v.index]++;
      } else {
        CHECK(v.f >= tt_space_min(s, i) && v.f <= tt_space_max(s, i));
        CHECK(tt_config_set_number(d, i, v.f) == TT_OK);
      }
    }
    CHECK_NEAR(tt_config_get(c, P_DEPTH).f, 4.0 + floor(u[P_DEPTH] * 60.0 + 0.5), 0);
    CHECK_NEAR(tt_config_get(c, P_INTCOST).f, 0.1 + u[P_INTCOST] * 9.9, 1e-12);
    CHECK_NEAR(log(tt_config_get(c, P_TRAV).f), log(0.01) + u[P_TRAV] * log(1e4), 1e-9);

    /* config -> unit -> config is the identity (FLOAT up to rounding). */
    tt_config_to_unit(c, u2);
    tt_config_from_unit(d, u2);
    for (size_t i = 0; i < P_COUNT; i++) {
      tt_value a = tt_config_get(c, i), b = tt_config_get(d, i);
      if (tt_space_type(s, i) == TT_PARAM_FLOAT) CHECK_NEAR(a.f, b.f, 1e-12 * fabs(a.f));
      else CHECK(a.i == b.i && a.index == b.index && a.s == b.s);
      /* unit -> config -> unit: FLOAT continuous; INT within half a step; NOM bin centre. */
      if (tt_space_type(s, i) == TT_PARAM_FLOAT) CHECK_NEAR(u2[i], u[i], 1e-12);
      else if (tt_space_type(s, i) == TT_PARAM_INT)
        CHECK_NEAR(u2[i], u[i], 0.5 / (tt_space_max(s, i) - tt_space_min(s, i)) + 1e-12);
      else CHECK_NEAR(u2[i], u[i], 0.5 / (double)tt_space_nom_count(s, i) + 1e-12);
    }
  }
  /* Uniform points hit every NOM bin. */
  for (int k = 0; k < 3; k++) CHECK(bins[P_QUALITY][k] > 500 && bins[P_BRANCH][k] > 500);
  CHECK(bins[P_BACKEND][0] > 800 && bins[P_BACKEND][1] > 800);

  /* Clamping at and beyond the faces, NaN to the low face. */
  for (size_t i = 0; i < P_COUNT; i++) u[i] = 7.0;
  tt_config_from_unit(c, u);
  CHECK(tt_config_get_int(c, "maxDepth", -1) == 64);
  CHECK_NEAR(tt_config_get_float(c, "travcost", -1), 100.0, 0);
  CHECK(tt_config_get_int(c, "branchingFactor", -1) == 8);
  CHECK(strcmp(tt_config_get_string(c, "backend"), "custom") == 0);
  for (size_t i = 0; i < P_COUNT; i++) u[i] = (i % 2) ? -3.0 : NAN;
  tt_config_from_unit(c, u);
  CHECK(tt_config_get_int(c, "quality", -1) == 1);
  CHECK(tt_config_get_int(c, "branchingFactor", -1) == 2);
  CHECK(tt_config_get_int(c, "maxDepth", -1) == 4);
  CHECK_NEAR(tt_config_get_float(c, "intcost", -1), 0.1, 0);
  CHECK_NEAR(tt_config_get_float(c, "travcost", -1), 0.01, 0);
  tt_config_to_unit(c, u);
  CHECK(u[P_DEPTH] == 0.0 && u[P_INTCOST] == 0.0 && u[P_TRAV] == 0.0);
  /* u = 1 lands in the last NOM bin, not past it. */
  for (size_t i = 0; i < P_COUNT; i++) u[i] = 1.0;
  tt_config_from_unit(c, u);
  CHECK(tt_config_get(c, P_QUALITY).index == 2);

  tt_config_destroy(c);
  tt_config_destroy(d);
}

/* copy, clone and equal. */
static void test_copy_equal(const tt_space *s) {
  tt_config *a = tt_config_create(s), *b = tt_config_create(s);
  CHECK(tt_config_equal(a, b));
  CHECK(tt_config_set_string(a, "intcost", "2.5") == TT_OK);
  CHECK(!tt_config_equal(a, b));
  tt_config_copy(b, a);
  CHECK(tt_config_equal(a, b));
  CHECK(tt_config_set_string(b, "backend", "custom") == TT_OK);
  CHECK(!tt_config_equal(a, b));
  tt_config *c = tt_config_clone(b);
  CHECK(c != NULL && tt_config_equal(b, c) && tt_config_space(c) == s);
  CHECK(tt_config_set_string(c, "robust", "true") == TT_OK);
  CHECK(!tt_config_equal(b, c));
  CHECK(tt_config_get_int(b, "robust", -1) == 0); /* clone is independent */

  /* Configurations of different spaces never compare equal and do not copy. */
  tt_space *other = make_space();
  tt_config *o = tt_config_create(other);
  tt_config *a2 = tt_config_clone(a);
  CHECK(!tt_config_equal(a, o));
  tt_config_copy(a2, o);
  CHECK(tt_config_equal(a, a2));
  tt_config_destroy(o);
  tt_space_destroy(other);
  tt_config_destroy(a2);
  tt_config_destroy(a);
  tt_config_destroy(b);
  tt_config_destroy(c);
}

/* Repairs branchingFactor^(maxDepth-1)*maxLeafSize >= 4096 by raising maxLeafSize. */
static tt_check_result repair_check(const tt_space *space, tt_config *config, char *why,
                                    size_t why_size, void *user) {
  int *calls = user;
  (*calls)++;
  int64_t b = tt_config_get_int(config, "branchingFactor", 0);
  int64_t d = tt_config_get_int(config, "maxDepth", 0);
  int64_t leaf = tt_config_get_int(config, "maxLeafSize", 0);
  double cap = pow((double)b, (double)(d - 1));
  if (cap * (double)leaf >= 4096.0) return TT_CHECK_OK;
  int64_t need = (int64_t)ceil(4096.0 / cap);
  if (need > 16) {
    snprintf(why, why_size, "needs maxLeafSize %lld > 16", (long long)need);
    return TT_CHECK_INFEASIBLE;
  }
  tt_config_set_number(config, (size_t)tt_space_find(space, "maxLeafSize"), (double)need);
  snprintf(why, why_size, "maxLeafSize raised to %lld", (long long)need);
  return TT_CHECK_REPAIRED;
}

/* Rejects robust traversal together with compact layout; writes no reason on purpose. */
static tt_check_result reject_check(const tt_space *space, tt_config *config, char *why,
                                    size_t why_size, void *user) {
  (void)space, (void)why, (void)why_size, (void)user;
  if (tt_config_get_int(config, "robust", 0) && tt_config_get_int(config, "compact", 0))
    return TT_CHECK_INFEASIBLE;
  return TT_CHECK_OK;
}

/* Constraint checks: none installed, a repairing one, a rejecting one. */
static void test_checks(void) {
  tt_space *s = make_space();
  tt_config *c = tt_config_create(s);
  char why[128] = "stale";
  CHECK(tt_space_check(s, c, why, sizeof why) == TT_CHECK_OK);
  CHECK(why[0] == '\0');

  int calls = 0;
  tt_space_set_check(s, repair_check, &calls);
  CHECK(tt_space_check(s, c, why, sizeof why) == TT_CHECK_OK); /* 2^31*4 is plenty */
  CHECK(calls == 1);
  CHECK(tt_config_set_string(c, "maxDepth", "8") == TT_OK);
  CHECK(tt_config_set_string(c, "maxLeafSize", "1") == TT_OK);
  /* 2^7 * 1 = 128 < 4096: repair to leaf 32 is impossible (max 16). */
  CHECK(tt_space_check(s, c, why, sizeof why) == TT_CHECK_INFEASIBLE);
  CHECK_CONTAINS(why, "needs maxLeafSize 32 > 16");
  CHECK(tt_config_set_string(c, "branchingFactor", "4") == TT_OK); /* 4^7 = 16384 */
  CHECK(tt_space_check(s, c, why, sizeof why) == TT_CHECK_OK);
  CHECK(tt_config_set_string(c, "maxDepth", "7") == TT_OK); /* 4^6 = 4096 */
  CHECK(tt_space_check(s, c, why, sizeof why) == TT_CHECK_OK);
  CHECK(tt_config_set_string(c, "maxDepth", "6") == TT_OK); /* 4^5 = 1024: leaf 4 */
  CHECK(tt_space_check(s, c, why, sizeof why) == TT_CHECK_REPAIRED);
  CHECK_CONTAINS(why, "maxLeafSize raised to 4");
  CHECK(tt_config_get_int(c, "maxLeafSize", -1) == 4);
  CHECK(tt_space_check(s, c, NULL, 0) == TT_CHECK_OK); /* repaired config is feasible */
  CHECK(calls == 6);

  tt_space_set_check(s, reject_check, NULL);
  CHECK(tt_space_check(s, c, why, sizeof why) == TT_CHECK_OK);
  CHECK(tt_config_set_string(c, "robust", "true") == TT_OK);
  CHECK(tt_config_set_string(c, "compact", "true") == TT_OK);
  tt_config *before = tt_config_clone(c);
  CHECK(tt_space_check(s, c, why, sizeof why) == TT_CHECK_INFEASIBLE);
  CHECK_CONTAINS(why, "accel_embree: constraint violated"); /* filled in for the plugin */
  CHECK(tt_config_equal(c, before));
  CHECK(tt_space_check(s, c, NULL, 0) == TT_CHECK_INFEASIBLE);

  tt_config_destroy(before);
  tt_config_destroy(c);
  tt_space_destroy(s);
}

int main(void) {
  tt_space *s = make_space();
  test_readers_and_defaults(s);
  test_builder_errors();
  test_setters(s);
  test_unit_cube(s);
  test_copy_equal(s);
  test_checks();
  tt_space_destroy(s);
  return tt_test_finish("params_space");
}
