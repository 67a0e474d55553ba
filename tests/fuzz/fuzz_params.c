/* libFuzzer: parameter spaces and configurations as users and plugins write them. The
 * first byte picks the reader:
 *   0  a parameter-space JSON (thesis Fig. 3.1, --describe's format): tt_space_from_json,
 *      then a round trip through tt_space_to_json and configurations of the space;
 *   1  a configuration JSON for a fixed Table 3.1-like space (tt_config_from_json: the
 *      tuning database's and the tuner state's configs);
 *   2  lines "name=value" for the same space, as --set PLUGIN.name=value passes them
 *      (tt_config_set_string), then the constraint check and a subset of the space. */
#include <tunetrace/params.h>

#include "fuzz_util.h"

#include <math.h>

/* A space with every kind of parameter, and a check that repairs or rejects. */
static tt_check_result fix_check(const tt_space *s, tt_config *c, char *why, size_t n, void *user) {
  (void)user;
  if (tt_config_get_int(c, "minLeaf", 1) > tt_config_get_int(c, "maxLeaf", 8)) {
    snprintf(why, n, "minLeaf > maxLeaf");
    return TT_CHECK_INFEASIBLE;
  }
  return TT_CHECK_OK;
}

static tt_space *fixed_space(void) {
  static tt_space *s;
  if (s) return s;
  s = tt_space_create("fuzz", "1");
  static const int64_t bf[] = {2, 4, 8};
  static const char *const backends[] = {"native", "custom"};
  tt_space_add_int(s, "quality", 0, 3, 1, "build quality");
  tt_space_add_nom_int(s, "branchingFactor", bf, 3, 2, "BVH width");
  tt_space_add_int(s, "minLeaf", 1, 16, 1, "");
  tt_space_add_int(s, "maxLeaf", 1, 32, 8, "");
  tt_space_add_float(s, "travcost", 0.1, 10, 1, 1, "log-scaled");
  tt_space_add_float(s, "sigma", -1, 1, 0, 0, "linear");
  tt_space_add_nom_bool(s, "compact", 0, "");
  tt_space_add_nom_string(s, "backend", backends, 2, 0, "");
  tt_space_set_check(s, fix_check, NULL);
  return s;
}

/* Everything a tuner does with a configuration: unit-cube round trip, JSON, check. */
static void exercise(const tt_space *s, tt_config *c) {
  size_t n = tt_space_count(s);
  double *u = calloc(n ? n : 1, sizeof *u);
  tt_config_to_unit(c, u);
  for (size_t i = 0; i < n; i++)
    if (!(u[i] >= 0.0 && u[i] <= 1.0)) abort(); /* unit coordinates stay in [0, 1] */
  tt_config_from_unit(c, u);
  free(u);
  char *j = tt_config_to_json(c);
  if (!j) abort();
  tt_config *back = tt_config_create(s);
  if (tt_config_from_json(back, j, "round trip") != TT_OK || !tt_config_equal(back, c)) abort();
  tt_config_destroy(back);
  tt_free(j);
  char why[256];
  tt_space_check(s, c, why, sizeof why);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1) return 0;
  char *text = fuzz_text(data + 1, size - 1);
  int mode = data[0] % 3;
  if (mode == 0) {
    tt_space *s = tt_space_from_json(text, "fuzz.json");
    if (s) {
      char *j = tt_space_to_json(s);
      if (!j) abort();
      tt_space *again = tt_space_from_json(j, "round trip");
      if (!again || tt_space_count(again) != tt_space_count(s)) abort();
      tt_space_destroy(again);
      tt_free(j);
      tt_config *c = tt_config_create(s);
      if (!c) abort();
      exercise(s, c);
      tt_config_destroy(c);
      tt_space_destroy(s);
    }
  } else {
    const tt_space *s = fixed_space();
    tt_config *c = tt_config_create(s);
    if (mode == 1) {
      if (tt_config_from_json(c, text, "fuzz.json") == TT_OK) exercise(s, c);
    } else {
      const char *names[8];
      size_t nn = 0;
      for (char *line = text, *next; line; line = next) {
        next = strchr(line, '\n');
        if (next) *next++ = '\0';
        char *eq = strchr(line, '=');
        if (!eq) continue;
        *eq = '\0';
        if (tt_config_set_string(c, line, eq + 1) == TT_OK && nn < 8 && tt_space_find(s, line) >= 0)
          names[nn++] = tt_space_name(s, (size_t)tt_space_find(s, line));
      }
      exercise(s, c);
      tt_space *sub = tt_space_subset(s, names, nn, c);
      if (sub) {
        tt_config *sc = tt_config_create(sub);
        exercise(sub, sc);
        tt_config_assign(c, sc);
        tt_config_destroy(sc);
        tt_space_destroy(sub);
      }
    }
    tt_config_destroy(c);
  }
  free(text);
  return 0;
}
