/* predictor_static's model files as hostile input: crafted files with a valid checksum.
 * Nothing after the checksum line is read (text appended to a model is refused, and so is a
 * model whose configurations would only be found in text appended after it); every number
 * is range-checked against the model's own counts and the target space before it is used:
 * NaN, +-1e300, out-of-range possible-value indices, counts that exceed what the file holds
 * or what the observations allow. Each bad file is refused with an error naming the file,
 * the line and what was expected, and the model it was loaded into is left as it was. */
#include "predictor_util.h"

static const tt_predictor_iface *P;
static tt_space *T;
static char dir[] = "/tmp/tt_psf_XXXXXX";

/* A small valid model of the test target (leaf INT[1,32], cost FLOAT[0.1,10] log, quality
 * NOM{1,2,3}, fast NOM{false,true}): two states, two configurations, four observations.
 * Configuration 0 is 1/0.67 faster on average, so it is the static answer. Lines 1-12. */
static const char *const base[] = {"predictor_static 1",
                                   "state_space test",
                                   "dim 2",
                                   "params 4 target",
                                   "minShare 0.5",
                                   "states 2",
                                   "0 1 10",
                                   "0x1p-1 0.5 20",
                                   "configs 2 4",
                                   "2 1 0 0 -0.8 2 2",
                                   "9 2 2 1 -0.2 2 1",
                                   NULL};

/* The model text with line `line` (1-based; 0: none) replaced by `with` (NULL: removed),
 * sealed with its checksum line, then `tail` appended. Written to dir/NAME; returns the
 * path (static, one at a time). */
static const char *craft(const char *name, int line, const char *with, const char *tail) {
  static char path[512];
  char body[4096] = "";
  size_t n = 0;
  for (int i = 0; base[i]; i++) {
    const char *l = i + 1 == line ? with : base[i];
    if (l) n += (size_t)snprintf(body + n, sizeof body - n, "%s\n", l);
  }
  snprintf(body + n, sizeof body - n, "checksum %016llx\n%s",
           (unsigned long long)pu_fnv((const unsigned char *)body, n), tail ? tail : "");
  snprintf(path, sizeof path, "%s/%s", dir, name);
  pu_write(path, (const unsigned char *)body, (long)strlen(body));
  return path;
}

/* The configuration a model answers, as JSON (free). */
static char *answer(const tt_predictor *p) {
  double s[2] = {0.3, 0.3};
  tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = 10};
  tt_predictor_result r = {.struct_size = sizeof r};
  tt_config *c = tt_config_create(T);
  char *j = P->predict_ex(p, &q, c, &r) == TT_OK ? tt_config_to_json(c) : NULL;
  tt_config_destroy(c);
  char *out = strdup(j ? j : "(none)");
  tt_free(j);
  return out;
}

/* `path` is refused with `want`, the message names the file and holds `what`, and `l`
 * still answers `before`. */
static void refused(tt_predictor *l, const char *before, const char *path, tt_status want,
                    const char *what) {
  tt_status st = P->load(l, path);
  CHECK_MSG(st == want, "%s (%s): status %d, expected %d: %s", path, what, st, want,
            st == TT_OK ? "(loaded)" : tt_last_error());
  if (st == TT_OK) return;
  CHECK_CONTAINS(tt_last_error(), path);
  CHECK_CONTAINS(tt_last_error(), what);
  char *now = answer(l);
  CHECK_MSG(!strcmp(now, before), "a refused load changed the model: %s -> %s", before, now);
  free(now);
}

int main(void) {
  tt_registry *reg;
  P = pu_load(&reg, "predictor_static");
  T = pu_target("target");
  CHECK(mkdtemp(dir) != NULL);
  tt_predictor *l = pu_create(P, T, 2, "test", NULL, 1);

  /* the crafted base model loads and answers configuration 0 (leaf 2, quality 1) */
  const char *good = craft("good.txt", 0, NULL, NULL);
  CHECK_MSG(P->load(l, good) == TT_OK, "%s", tt_last_error());
  char *before = answer(l);
  CHECK_CONTAINS(before, "\"leaf\":2");
  CHECK_CONTAINS(before, "\"quality\":1");
  tt_predictor_info info = {.struct_size = sizeof info};
  CHECK(P->info(l, &info) == TT_OK && info.entries == 2 && info.observations == 4);

  /* nothing after the checksum line is read: text appended to a model, with or without a
   * newline, even a whole valid configuration list (issue: "configs 1 0" after the checksum
   * made the reader pass NULL to strtod) */
  refused(l, before, craft("tail.txt", 0, NULL, "configs 1 0"), TT_ERR_PARSE,
          "11 bytes after its checksum line");
  refused(l, before, craft("tail-nl.txt", 0, NULL, "configs 1 0\n2 1 0 0 -0.8 2 2\n"), TT_ERR_PARSE,
          "after its checksum line");
  refused(l, before, craft("tail-ck.txt", 0, NULL, "checksum 0123456789abcdef\n"), TT_ERR_PARSE,
          "corrupt");
  /* the configuration list only in the appended text: the checksummed text ends early */
  {
    char body[1024] = "";
    size_t n = 0;
    for (int i = 0; i < 8; i++) n += (size_t)snprintf(body + n, sizeof body - n, "%s\n", base[i]);
    char path[512];
    snprintf(path, sizeof path, "%s/configs-after.txt", dir);
    snprintf(body + n, sizeof body - n, "checksum %016llx\nconfigs 1 0",
             (unsigned long long)pu_fnv((const unsigned char *)body, n));
    pu_write(path, (const unsigned char *)body, (long)strlen(body));
    refused(l, before, path, TT_ERR_PARSE, "after its checksum line");
    body[n + 26] = '\0'; /* without the tail: cut short where the configurations should be */
    pu_write(path, (const unsigned char *)body, (long)strlen(body));
    refused(l, before, path, TT_ERR_PARSE, "line 9: the file ends before the configuration count");
  }

  /* every number range-checked: line, replacement, the message's expectation */
  struct {
    int line;
    const char *with;
    const char *what;
  } bad[] = {
      /* the format line */
      {1, "predictor_static 0", "format version 0"},
      {1, "predictor_static -1", "the format version: expected an integer"},
      {1, "predictor_static 99999999999999999999999", "the format version: expected an integer"},
      {1, "predictor_static 1 extra", "after the format version"},
      /* header lines */
      {2, "state-space test", "expected the state space"},
      {3, "dim -2", "dim: expected an integer in [1, 4294967295]"},
      {3, "dim 1e300", "dim: expected an integer"},
      {3, "dim", "expected the state dimension"},
      {4, "params nan target", "params: expected an integer"},
      {5, "minShare nan", "minShare: expected a number in [0, 1], got \"nan\""},
      {5, "minShare 1e300", "minShare: expected a number in [0, 1]"},
      {5, "minShare -0.5", "minShare: expected a number in [0, 1]"},
      /* counts: what the rest of the file can hold */
      {6, "states 1e30", "the state count"},
      {6, "states 1000", "line 6: the state count (at most what the rest of the file can hold)"},
      {6, "states 3", "line 9: state 2: a state value: expected a finite number, got \"configs\""},
      {6, "states 18446744073709551615", "the state count"},
      {6, "states 18446744073709551616", "the state count"},
      {9, "configs 1000000 4", "line 9: the configuration count"},
      {9, "configs 2 -4", "the observation count: expected an integer"},
      /* states: finite values, a positive finite reference, each stored once */
      {7, "nan 1 10", "line 7: state 0: a state value: expected a finite number, got \"nan\""},
      {7, "0 1e999 10", "a state value: expected a finite number"},
      {7, "0 1 0", "line 7: state 0: the state's reference cost: expected a positive number"},
      {7, "0 1 -1e300", "the state's reference cost: expected a positive number"},
      {7, "0 1 inf", "the state's reference cost: expected a finite number"},
      {7, "0 1", "the state's reference cost: expected a finite number, got \"\""},
      {7, "0 1 10 4", "unexpected \"4\" after the state's reference cost"},
      {8, "0 1 20", "line 8: state 1 is stored twice (states 0 and 1 are equal)"},
      /* configurations: values of the target space */
      {10, "2 1 1e300 0 -0.8 2 2",
       "line 10: configuration 0: target.quality: possible-value index 1.0000000000000001e+300 is "
       "not an integer in [0, 3)"},
      {10, "2 1 nan 0 -0.8 2 2",
       "configuration 0: a parameter value: expected a finite number, got \"nan\""},
      {10, "2 1 -1 0 -0.8 2 2", "target.quality: possible-value index -1 is not"},
      {10, "2 1 3 0 -0.8 2 2", "target.quality: possible-value index 3 is not"},
      {10, "2 1 0.5 0 -0.8 2 2", "target.quality: possible-value index 0.5 is not"},
      {10, "2 1 0 2 -0.8 2 2", "target.fast: possible-value index 2 is not"},
      {10, "1e300 1 0 0 -0.8 2 2", "configuration 0: target.leaf: 1e+300 is out of range"},
      {10, "2.5 1 0 0 -0.8 2 2", "target.leaf: 2.5 is not an integer"},
      {10, "-1e300 1 0 0 -0.8 2 2", "target.leaf: -1e+300 is out of range"},
      {10, "2 100 0 0 -0.8 2 2", "target.cost: 100 is out of range"},
      {10, "2 -inf 0 0 -0.8 2 2", "a parameter value: expected a finite number"},
      /* configurations: the log-ratio sum finite, the counts within the model's own */
      {10, "2 1 0 0 nan 2 2", "the sum of log cost ratios: expected a finite number"},
      {10, "2 1 0 0 -1e999 2 2", "the sum of log cost ratios: expected a finite number"},
      {10, "2 1 0 0 -0.8 1e30 2", "the number of states it was seen in"},
      {10, "2 1 0 0 -0.8 0 2", "the number of states it was seen in"},
      {10, "2 1 0 0 -0.8 5 2", "expected an integer in [1, 4]"},
      {11, "9 2 2 1 -0.2 3 1", "line 11: configuration 1"}, /* 2 + 3 > 4 observations */
      {11, "9 2 2 1 -0.2 3 1", "expected an integer in [1, 2]"},
      {10, "2 1 0 0 -0.8 2 nan", "the last state it was seen in: expected an integer in [1, 2]"},
      {10, "2 1 0 0 -0.8 2 -1e300", "the last state it was seen in"},
      {10, "2 1 0 0 -0.8 2 0", "the last state it was seen in"},
      {10, "2 1 0 0 -0.8 2 3", "the last state it was seen in: expected an integer in [1, 2]"},
      {10, "2 1 0 0 -0.8 2", "the last state it was seen in: expected an integer"},
      {10, "2 1 0 0 -0.8 2 2 7", "unexpected \"7\" after the last state"},
      {11, "2 1 0 0 -0.2 2 1",
       "line 11: configuration 1 is stored twice (configurations 0 and 1 are equal)"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char name[32];
    snprintf(name, sizeof name, "bad-%zu.txt", i);
    refused(l, before, craft(name, bad[i].line, bad[i].with, NULL), TT_ERR_PARSE, bad[i].what);
  }
  /* a line more after the configurations, inside the checksummed text */
  {
    char name[] = "extra-line.txt";
    const char *path = craft(name, 11, "9 2 2 1 -0.2 2 1\n0 0 0", NULL);
    refused(l, before, path, TT_ERR_PARSE, "line 12: unexpected text after the configurations");
  }
  /* a newer format: refused as such; another state dimension: named */
  refused(l, before, craft("newer.txt", 1, "predictor_static 2", NULL), TT_ERR_UNSUPPORTED,
          "has format 2; this predictor_static");
  refused(l, before, craft("dim3.txt", 3, "dim 3", NULL), TT_ERR_INVALID_ARGUMENT, "(3 values)");
  refused(l, before, craft("space.txt", 2, "state_space other", NULL), TT_ERR_INVALID_ARGUMENT,
          "for states \"other\"");
  refused(l, before, craft("target.txt", 4, "params 4 other", NULL), TT_ERR_INVALID_ARGUMENT,
          "4 parameters of other");
  /* a NUL byte inside the checksummed text */
  {
    char body[1024] = "";
    size_t n = 0;
    for (int i = 0; base[i]; i++) n += (size_t)snprintf(body + n, sizeof body - n, "%s\n", base[i]);
    body[20] = '\0'; /* in "state_space test" */
    uint64_t h = pu_fnv((const unsigned char *)body, n);
    n += (size_t)snprintf(body + n, sizeof body - n, "checksum %016llx\n", (unsigned long long)h);
    char path[512];
    snprintf(path, sizeof path, "%s/nul.txt", dir);
    pu_write(path, (const unsigned char *)body, (long)n);
    refused(l, before, path, TT_ERR_PARSE, "NUL byte at offset 20");
  }
  /* the checksum line: 16 hexadecimal digits and a newline, the last line */
  {
    const char *path = craft("ck.txt", 0, NULL, NULL);
    long n;
    unsigned char *b = pu_read(path, &n);
    pu_write(path, b, n - 1); /* no newline */
    refused(l, before, path, TT_ERR_PARSE, "the checksum line is not");
    b[n - 2] = 'x'; /* 15 digits */
    pu_write(path, b, n);
    refused(l, before, path, TT_ERR_PARSE, "16 hexadecimal digits");
    free(b);
  }

  /* what does load: an empty model (no states, nothing to answer) and hex floats */
  {
    char body[512];
    size_t n = (size_t)snprintf(body, sizeof body,
                                "predictor_static 1\nstate_space test\ndim 2\n"
                                "params 4 target\nminShare 0x1p-1\nstates 0\nconfigs 0 0\n");
    snprintf(body + n, sizeof body - n, "checksum %016llx\n",
             (unsigned long long)pu_fnv((const unsigned char *)body, n));
    char path[512];
    snprintf(path, sizeof path, "%s/empty.txt", dir);
    pu_write(path, (const unsigned char *)body, (long)strlen(body));
    tt_predictor *e = pu_create(P, T, 2, "test", NULL, 1);
    CHECK_MSG(P->load(e, path) == TT_OK, "%s", tt_last_error());
    tt_config *c = tt_config_create(T);
    double s[2] = {0, 0};
    tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = 1};
    CHECK(P->predict_ex(e, &q, c, NULL) == TT_ERR_NO_DATA);
    tt_config_destroy(c);
    P->destroy(e);
  }

  /* observe refuses what a model file could not hold (a non-finite state), the whole batch
   * unchanged; extreme but valid costs save a model that loads again */
  {
    tt_predictor *o = pu_create(P, T, 2, "test", NULL, 1);
    tt_config *a = pu_config(T, 2, 1.0, 0, 0), *b = pu_config(T, 9, 2.0, 2, 1);
    double s1[2] = {0, 1}, s2[2] = {NAN, 1};
    tt_predictor_sample x[2] = {
        {.struct_size = sizeof x[0], .state = s1, .config = a, .cost = 1, .default_cost = 2},
        {.struct_size = sizeof x[0], .state = s2, .config = b, .cost = 1, .default_cost = 2}};
    CHECK(P->observe_ex(o, x, 2, TT_PREDICTOR_OFFLINE) == TT_ERR_INVALID_ARGUMENT);
    CHECK_CONTAINS(tt_last_error(), "not finite");
    info = (tt_predictor_info){.struct_size = sizeof info};
    CHECK(P->info(o, &info) == TT_OK && info.observations == 0 && info.entries == 0);
    x[0].cost = 1e299, x[0].default_cost = 4.9e-324; /* ratio 2e622: not a double */
    x[1].state = s1, x[1].cost = 4.9e-324, x[1].default_cost = 1e299;
    CHECK(P->observe_ex(o, x, 2, TT_PREDICTOR_OFFLINE) == TT_OK);
    char path[512];
    snprintf(path, sizeof path, "%s/extreme.txt", dir);
    CHECK(P->save(o, path) == TT_OK);
    tt_predictor *o2 = pu_create(P, T, 2, "test", NULL, 1);
    CHECK_MSG(P->load(o2, path) == TT_OK, "%s", tt_last_error());
    char *w1 = answer(o), *w2 = answer(o2);
    CHECK(!strcmp(w1, w2) && strstr(w1, "\"leaf\":9"));
    free(w1);
    free(w2);
    P->destroy(o);
    P->destroy(o2);
    tt_config_destroy(a);
    tt_config_destroy(b);
  }
  /* a state space of two lines cannot be written as one */
  {
    tt_predictor_setup su = {
        .struct_size = sizeof su, .target = T, .state_dim = 2, .state_space = "a\nconfigs 1 0"};
    tt_predictor *z = NULL;
    CHECK(P->create_ex(&su, &z) == TT_ERR_INVALID_ARGUMENT && z == NULL);
  }

  free(before);
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd)) {}
  P->destroy(l);
  tt_space_destroy(T);
  tt_registry_destroy(reg);
  return tt_test_finish("predictor_static_files");
}
