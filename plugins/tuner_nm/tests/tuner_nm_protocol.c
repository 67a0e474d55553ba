/* tuner_nm protocol and invariants: constraint repair/rejection never leaks an infeasible
 * proposal, the Latin hypercube initial simplex, exact save/load resumption, the duplicate
 * cache, noise detection, purely nominal spaces, settings and argument errors. */
#include "tuner_nm_common.h"

#include <math.h>
#include <tt_util/rng.h>

/* ---- constraints ---- */

static int g_repairs, g_rejects;

/* lo <= hi is repaired by swapping; the region n >= 14 && lo > 0.5 is rejected. */
static tt_check_result pair_check(const tt_space *space, tt_config *c, char *why, size_t sz,
                                  void *user) {
  (void)space, (void)user;
  double lo = tt_config_get(c, 0).f, hi = tt_config_get(c, 1).f;
  if (tt_config_get(c, 2).i >= 14 && lo > 0.5) {
    snprintf(why, sz, "n >= 14 requires lo <= 0.5");
    return TT_CHECK_INFEASIBLE;
  }
  if (lo > hi) {
    tt_config_set_number(c, 0, hi);
    tt_config_set_number(c, 1, lo);
    snprintf(why, sz, "swapped lo and hi");
    return TT_CHECK_REPAIRED;
  }
  return TT_CHECK_OK;
}

static double pair_cost(const tt_config *c, void *user) {
  (void)user;
  double lo = tt_config_get(c, 0).f, hi = tt_config_get(c, 1).f;
  double n = (double)tt_config_get(c, 2).i;
  return (lo - 0.6) * (lo - 0.6) + (hi - 0.65) * (hi - 0.65) + 0.01 * (n - 17) * (n - 17);
}

typedef struct visit_ctx {
  int proposals, not_ok, outside;
} visit_ctx;

/* Every proposal must pass the check unchanged and lie inside the bounds. */
static void pair_visit(const tt_config *c, void *user) {
  visit_ctx *v = user;
  v->proposals++;
  int r0 = g_repairs, j0 = g_rejects;
  tt_config *copy = tt_config_clone(c);
  if (tt_space_check(tt_config_space(c), copy, NULL, 0) != TT_CHECK_OK) v->not_ok++;
  tt_config_destroy(copy);
  g_repairs = r0, g_rejects = j0; /* count only the tuner's own checks */
  for (size_t i = 0; i < 3; i++) {
    double x = tt_config_get(c, i).f;
    if (x < tt_space_min(tt_config_space(c), i) || x > tt_space_max(tt_config_space(c), i))
      v->outside++;
  }
}

/* Counting wrapper (the tests are single-threaded). */
static tt_check_result counting_check(const tt_space *space, tt_config *c, char *why, size_t sz,
                                      void *user) {
  tt_check_result r = pair_check(space, c, why, sz, user);
  g_repairs += r == TT_CHECK_REPAIRED;
  g_rejects += r == TT_CHECK_INFEASIBLE;
  return r;
}

static void test_constraints(const tt_tuner_iface *nm) {
  tt_space *s = tt_space_create("pair", "1.0");
  tt_space_add_float(s, "lo", 0.0, 1.0, 0.7, 0, NULL);
  tt_space_add_float(s, "hi", 0.0, 1.0, 0.3, 0, NULL); /* default violates lo <= hi */
  tt_space_add_int(s, "n", 0, 20, 15, NULL);           /* and starts next to the region */
  tt_space_set_check(s, counting_check, NULL);
  tt_config *b = tt_config_create(s);
  for (uint64_t seed = 1; seed <= 4; seed++) {
    visit_ctx v = {0};
    g_repairs = g_rejects = 0;
    tnm_run r = tnm_drive(nm, s, NULL, seed, pair_cost, NULL, pair_visit, &v, 400, b);
    printf("constraints seed %d: %d proposals, %d repaired and %d rejected internally, "
           "best %.5f (lo %.3f hi %.3f n %d)\n",
           (int)seed, v.proposals, g_repairs, g_rejects, r.best_cost, tt_config_get(b, 0).f,
           tt_config_get(b, 1).f, (int)tt_config_get(b, 2).i);
    CHECK(v.not_ok == 0);
    CHECK(v.outside == 0);
    CHECK(g_repairs > 0);
    CHECK(g_rejects > 0);
    /* Constrained optimum: lo = 0.5, hi = 0.65, n = 17, cost 0.01. */
    CHECK_MSG(r.best_cost < 0.0102, "seed %d best %g", (int)seed, r.best_cost);
    tt_config *copy = tt_config_clone(b);
    CHECK(tt_space_check(s, copy, NULL, 0) == TT_CHECK_OK);
    tt_config_destroy(copy);
  }
  tt_config_destroy(b);
  tt_space_destroy(s);
}

/* ---- Latin hypercube initial simplex ---- */

typedef struct lhs_ctx {
  int dims, seen;
  double pts[16][16];
} lhs_ctx;

static void lhs_visit(const tt_config *c, void *user) {
  lhs_ctx *l = user;
  if (l->seen < l->dims + 1)
    for (int d = 0; d < l->dims; d++) l->pts[l->seen][d] = tt_config_get(c, (size_t)d).f;
  l->seen++;
}

static double lhs_cost(const tt_config *c, void *user) {
  lhs_ctx *l = user;
  double s = 0;
  for (int d = 0; d < l->dims; d++) s += tt_config_get(c, (size_t)d).f;
  return s;
}

/* The first n+1 proposals form the initial simplex: inside the box of side initSize around
 * the default (shifted inside [0,1]), one point per stratum in every dimension. */
static void test_lhs(const tt_tuner_iface *nm) {
  static const int dims[3] = {2, 4, 10};
  static const double def[3] = {0.5, 0.95, 0.1};
  for (int k = 0; k < 3; k++) {
    int n = dims[k];
    tt_space *s = tt_space_create("lhs", "1.0");
    char name[16];
    for (int d = 0; d < n; d++) {
      snprintf(name, sizeof name, "x%d", d);
      tt_space_add_float(s, name, 0.0, 1.0, def[k], 0, NULL);
    }
    double size = 0.35, lo = def[k] - size / 2;
    if (lo > 1 - size) lo = 1 - size;
    if (lo < 0) lo = 0;
    for (uint64_t seed = 1; seed <= 3; seed++) {
      lhs_ctx l = {.dims = n};
      tnm_drive(nm, s, NULL, seed, lhs_cost, NULL, lhs_visit, &l, n + 1, NULL);
      int bad = 0;
      for (int d = 0; d < n; d++) {
        int hits[16] = {0};
        for (int j = 0; j <= n; j++) {
          int st = (int)floor((l.pts[j][d] - lo) / size * (n + 1));
          if (st < 0 || st > n) bad++;
          else hits[st]++;
        }
        for (int st = 0; st <= n; st++) bad += hits[st] != 1;
      }
      CHECK_MSG(bad == 0, "%d dims, default %g, seed %d: %d strata not hit exactly once", n, def[k],
                (int)seed, bad);
    }
    tt_space_destroy(s);
  }
}

/* ---- save/load ---- */

/* A cost with deterministic pseudo-noise (a hash of the values and the call number), so
 * both runs see identical costs. */
typedef struct resume_ctx {
  int calls;
} resume_ctx;

static double resume_cost(const tt_config *c, void *user) {
  resume_ctx *r = user;
  uint64_t h = (uint64_t)(r->calls++) * 0x9e3779b97f4a7c15ull;
  h ^= h >> 29;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 32;
  double noise = ((double)(h & 0xffff) / 65536.0 - 0.5) * 0.02;
  double x = tt_config_get(c, 0).f, y = (double)tt_config_get(c, 1).i;
  int m = tt_config_get(c, 2).index, b = (int)tt_config_get(c, 3).i;
  double extra = 0.0;
  if (tt_space_count(tt_config_space(c)) > 5) /* the many-arm variant */
    extra = 0.03 * (double)tt_config_get(c, 5).index + 0.07 * (double)tt_config_get(c, 6).i;
  return (x - 0.3 * m) * (x - 0.3 * m) + 0.01 * (y - 7) * (y - 7) + 0.05 * m + 0.1 * b + noise +
         extra;
}

static tt_space *resume_space(void) {
  tt_space *s = tt_space_create("resume", "1.0");
  static const char *const modes[3] = {"a", "b", "c"};
  tt_space_add_float(s, "x", -1.0, 1.0, 0.0, 0, NULL);
  tt_space_add_int(s, "y", 0, 20, 3, NULL);
  tt_space_add_nom_string(s, "mode", modes, 3, 0, NULL);
  tt_space_add_nom_bool(s, "flag", 1, NULL);
  tt_space_add_float(s, "z", 0.01, 100.0, 1.0, 1, NULL);
  return s;
}

/* 48 arms x 4 points > 50: tuner_nm probes every arm before building simplices. */
static tt_space *resume_space_many(void) {
  tt_space *s = resume_space();
  static const int64_t kinds[4] = {1, 2, 3, 4};
  tt_space_add_nom_int(s, "kind", kinds, 4, 2, NULL);
  tt_space_add_nom_bool(s, "flag2", 0, NULL);
  return s;
}

#define RESUME_TOTAL 150

static void test_save_load_at(const tt_tuner_iface *nm, tt_space *(*make)(void), int cut,
                              int checks_mismatch) {
  const int RESUME_CUT = cut;
  tt_space *s = make();
  tt_config *set = tnm_settings(nm, "reevaluate", "2", NULL);
  tt_config *c = tt_config_create(s);
  static char *ref[RESUME_TOTAL];
  resume_ctx rc = {0};
  tt_tuner *a = NULL, *b = NULL;
  CHECK(nm->create(s, set, 42, &a) == TT_OK);
  int n_ref = 0;
  for (; n_ref < RESUME_TOTAL; n_ref++) {
    if (nm->next(a, c) != TT_OK) break;
    ref[n_ref] = tt_config_to_json(c);
    nm->feedback(a, resume_cost(c, &rc));
  }
  nm->destroy(a);

  /* Interrupted run: save at RESUME_CUT with a proposal outstanding, destroy, resume. */
  rc.calls = 0;
  CHECK(nm->create(s, set, 42, &a) == TT_OK);
  int same = 0, i = 0;
  char *state = NULL;
  for (; i < RESUME_CUT; i++) {
    nm->next(a, c);
    char *j = tt_config_to_json(c);
    same += !strcmp(j, ref[i]);
    tt_free(j);
    nm->feedback(a, resume_cost(c, &rc));
  }
  nm->next(a, c); /* outstanding at the cut */
  CHECK(nm->save_state(a, &state) == TT_OK);
  nm->destroy(a);
  CHECK(nm->create(s, set, 42, &b) == TT_OK);
  CHECK(nm->load_state(b, state) == TT_OK);
  for (; i < n_ref; i++) {
    if (nm->next(b, c) != TT_OK) break;
    char *j = tt_config_to_json(c);
    same += !strcmp(j, ref[i]);
    tt_free(j);
    nm->feedback(b, resume_cost(c, &rc));
  }
  printf("save/load (%zu parameters): %d of %d proposals identical after resuming at %d\n",
         tt_space_count(s), same, n_ref, RESUME_CUT);
  CHECK(n_ref == RESUME_TOTAL);
  CHECK(same == n_ref);

  /* A second save of the resumed tuner equals a save of the uninterrupted one. */
  char *s2 = NULL;
  CHECK(nm->save_state(b, &s2) == TT_OK);
  CHECK_CONTAINS(s2, "\"tuner\":\"tuner_nm\"");
  tt_free(s2);

  /* An arm whose pending point disagrees with its phase (waiting for a reflection, pending
   * vertex 0) is refused: such a state loaded, ran on and saved one that no longer loaded
   * (found by tests/fuzz/fuzz_tuning_state, #13). */
  {
    const char *arm = strstr(state, "\"armStates\":[{");
    const char *ph = arm ? strstr(arm, "\"phase\":") : NULL;
    const char *pe = ph ? strstr(ph, "\"pend\":") : NULL;
    CHECK(ph && pe);
    if (ph && pe) {
      const char *ph_end = ph + strlen("\"phase\":"), *pe_end = pe + strlen("\"pend\":");
      ph_end += strspn(ph_end, "-0123456789.e");
      pe_end += strspn(pe_end, "-0123456789.e");
      size_t n = strlen(state) + 64;
      char *bad = malloc(n);
      snprintf(bad, n, "%.*s\"phase\":3%.*s\"pend\":0%s", (int)(ph - state), state,
               (int)(pe - ph_end), ph_end, pe_end);
      tt_tuner *w = NULL;
      CHECK(nm->create(s, set, 42, &w) == TT_OK);
      CHECK(nm->load_state(w, bad) == TT_ERR_PARSE);
      CHECK_CONTAINS(tt_last_error(), "arm state 0");
      CHECK_MSG(nm->load_state(w, state) == TT_OK, "%s", tt_last_error()); /* left usable */
      nm->destroy(w);
      free(bad);
    }
  }
  /* Counts beyond what an int64_t holds (a cache entry measured 1.1e91 times, found by
   * tests/fuzz/fuzz_tuning_state: the cast was undefined behaviour) or fractional ones are
   * refused; the tuner is left usable. */
  {
    static const char *const keys[][2] = {{"\"cache\":", "\"n\":["},
                                          {"\"armStates\":[{", "\"iter\":"},
                                          {"\"armStates\":[{", "\"evals\":"},
                                          {"{", "\"evaluations\":"},
                                          {"{", "\"deterministic\":"}};
    static const char *const values[] = {"1.1e91", "2.5"};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++)
      for (int v = 0; v < 2; v++) {
        const char *at = strstr(state, keys[i][0]);
        const char *num = at ? strstr(at, keys[i][1]) : NULL;
        CHECK_MSG(num != NULL, "%s in the saved state", keys[i][1]);
        if (!num) continue;
        num += strlen(keys[i][1]);
        const char *end = num + strspn(num, "-0123456789.e+");
        size_t n = strlen(state) + 64;
        char *bad = malloc(n);
        snprintf(bad, n, "%.*s%s%s", (int)(num - state), state, values[v], end);
        tt_tuner *w = NULL;
        CHECK(nm->create(s, set, 42, &w) == TT_OK);
        CHECK_MSG(nm->load_state(w, bad) == TT_ERR_PARSE, "%s%s accepted", keys[i][1], values[v]);
        CHECK_MSG(nm->load_state(w, state) == TT_OK, "%s", tt_last_error());
        nm->destroy(w);
        free(bad);
      }
  }
  /* nothing after the state is read: appended text is refused, a final newline is not */
  {
    size_t n = strlen(state) + 32;
    char *longer = malloc(n);
    snprintf(longer, n, "%s\n{\"tuner\":\"x\"}", state);
    tt_tuner *w = NULL;
    CHECK(nm->create(s, set, 42, &w) == TT_OK);
    CHECK(nm->load_state(w, longer) == TT_ERR_PARSE);
    CHECK_CONTAINS(tt_last_error(), "unexpected text after the state");
    longer[strlen(state) + 1] = '\0';
    CHECK_MSG(nm->load_state(w, longer) == TT_OK, "%s", tt_last_error());
    nm->destroy(w);
    free(longer);
  }
  if (!checks_mismatch) {
    tt_free(state);
    for (int k = 0; k < n_ref; k++) tt_free(ref[k]);
    nm->destroy(b);
    tt_config_destroy(c);
    tt_config_destroy(set);
    tt_space_destroy(s);
    return;
  }

  /* Mismatches are refused with a message naming what differs. */
  tt_config *other_set = tnm_settings(nm, "reevaluate", "3", NULL);
  tt_tuner *o = NULL;
  CHECK(nm->create(s, other_set, 42, &o) == TT_OK);
  CHECK(nm->load_state(o, state) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "reevaluate");
  nm->destroy(o);
  tt_space *s3 = tt_space_create("resume", "1.0");
  tt_space_add_float(s3, "x", -1.0, 1.0, 0.0, 0, NULL);
  CHECK(nm->create(s3, set, 42, &o) == TT_OK);
  CHECK(nm->load_state(o, state) != TT_OK);
  CHECK_CONTAINS(tt_last_error(), "parameters");
  CHECK(nm->load_state(o, "{not json") == TT_ERR_PARSE);
  nm->destroy(o);
  tt_space_destroy(s3);
  tt_config_destroy(other_set);

  tt_free(state);
  for (int k = 0; k < n_ref; k++) tt_free(ref[k]);
  nm->destroy(b);
  tt_config_destroy(c);
  tt_config_destroy(set);
  tt_space_destroy(s);
}

static void test_save_load(const tt_tuner_iface *nm) {
  test_save_load_at(nm, resume_space, 60, 1);
  /* Probe mode: cut during the probes (20) and while simplices are being built (60). */
  test_save_load_at(nm, resume_space_many, 20, 0);
  test_save_load_at(nm, resume_space_many, 60, 0);
}

/* ---- duplicates, noise detection ---- */

typedef struct dup_ctx {
  char *seen[4096];
  int count, repeats;
} dup_ctx;

static void dup_visit(const tt_config *c, void *user) {
  dup_ctx *d = user;
  char *j = tt_config_to_json(c);
  for (int i = 0; i < d->count; i++)
    if (!strcmp(d->seen[i], j)) {
      d->repeats++;
      tt_free(j);
      return;
    }
  if (d->count < 4096) d->seen[d->count++] = j;
  else tt_free(j);
}

static void dup_free(dup_ctx *d) {
  for (int i = 0; i < d->count; i++) tt_free(d->seen[i]);
}

static double grid_cost(const tt_config *c, void *user) {
  (void)user;
  double a = (double)tt_config_get(c, 0).i, b = (double)tt_config_get(c, 1).i;
  return (a - 2) * (a - 2) + (b - 1) * (b - 1);
}

static double noisy_grid_cost(const tt_config *c, void *user) {
  static uint64_t s = 12345;
  return grid_cost(c, user) + (double)(tt__splitmix64(&s) >> 40) * 0x1p-24 * 0.1;
}

/* A 4x4 INT grid: the simplex moves continuously but many points round to the same
 * configuration; the cache answers them, so nothing is measured twice and the run ends. */
static void test_duplicates(const tt_tuner_iface *nm) {
  tt_space *s = tt_space_create("grid", "1.0");
  tt_space_add_int(s, "a", 0, 3, 0, NULL);
  tt_space_add_int(s, "b", 0, 3, 3, NULL);
  tt_config *b = tt_config_create(s);
  tt_config *set0 = tnm_settings(nm, "reevaluate", "0", NULL);
  int found = 0;
  for (uint64_t seed = 1; seed <= 7; seed++) {
    dup_ctx d = {0};
    tnm_run r = tnm_drive(nm, s, set0, seed, grid_cost, NULL, dup_visit, &d, 1000, b);
    printf("grid seed %d: %d evaluations, %d distinct, done %d, best (%d,%d)\n", (int)seed,
           r.evaluations, d.count, r.done, (int)tt_config_get(b, 0).i, (int)tt_config_get(b, 1).i);
    CHECK(r.done);
    CHECK(d.repeats == 0);
    CHECK(r.evaluations <= 16);
    found += tt_config_get(b, 0).i == 2 && tt_config_get(b, 1).i == 1;
    dup_free(&d);
  }
  /* Nelder-Mead on a 4x4 lattice is a local method: most, not all, seeds reach (2,1). */
  CHECK_MSG(found >= 5, "optimum found in %d of 7 seeds", found);

  /* Default reevaluate = 1 on a deterministic cost: one re-measurement reveals it, then
   * no more. On a noisy cost the incumbent keeps being re-measured and averaged. */
  dup_ctx d1 = {0};
  tnm_drive(nm, s, NULL, 7, grid_cost, NULL, dup_visit, &d1, 1000, NULL);
  CHECK_MSG(d1.repeats == 1, "deterministic: %d re-measurements", d1.repeats);
  dup_free(&d1);
  dup_ctx d2 = {0};
  tnm_drive(nm, s, NULL, 7, noisy_grid_cost, NULL, dup_visit, &d2, 1000, NULL);
  printf("grid with noise: %d re-measurements of incumbents\n", d2.repeats);
  CHECK(d2.repeats > 1);
  dup_free(&d2);
  tt_config_destroy(set0);
  tt_config_destroy(b);
  tt_space_destroy(s);
}

/* ---- nominal-only space ---- */

static double nom_cost(const tt_config *c, void *user) {
  (void)user;
  return (double)((tt_config_get(c, 0).index * 7 + tt_config_get(c, 1).index * 3) % 5);
}

/* No INT/FLOAT dimension: every combination is one arm with a single point; the tuner
 * measures each exactly once and reports TT_DONE with the true minimum. */
static void test_nominal_only(const tt_tuner_iface *nm) {
  tt_space *s = tt_space_create("nom", "1.0");
  static const int64_t v[3] = {1, 2, 3};
  tt_space_add_nom_int(s, "q", v, 3, 1, NULL);
  tt_space_add_nom_bool(s, "robust", 0, NULL);
  tt_config *b = tt_config_create(s);
  dup_ctx d = {0};
  tnm_run r = tnm_drive(nm, s, NULL, 1, nom_cost, NULL, dup_visit, &d, 100, b);
  CHECK(r.done);
  CHECK(r.evaluations == 6);
  CHECK(d.repeats == 0);
  CHECK(r.best_cost == 0.0);
  dup_free(&d);
  tt_config_destroy(b);
  tt_space_destroy(s);
}

/* ---- protocol errors and settings ---- */

static void test_protocol(const tt_tuner_iface *nm) {
  const tt_space *ss = nm->space();
  CHECK(ss != NULL);
  static const char *const names[] = {"reflection",     "expansion", "contraction", "shrink",
                                      "init",           "initSize",  "tolerance",   "reevaluate",
                                      "maxEvaluations", "epsilon"};
  for (size_t i = 0; i < sizeof names / sizeof *names; i++)
    CHECK_MSG(tt_space_find(ss, names[i]) >= 0, "missing setting %s", names[i]);
  tt_config *def = tt_config_create(ss);
  CHECK_NEAR(tt_config_get_float(def, "reflection", 0), 1.0, 0);
  CHECK_NEAR(tt_config_get_float(def, "expansion", 0), 2.0, 0);
  CHECK_NEAR(tt_config_get_float(def, "initSize", 0), 0.35, 0);
  CHECK(!strcmp(tt_config_get_string(def, "init"), "lhs"));
  CHECK(tt_config_get_int(def, "reevaluate", -1) == 1);
  tt_config_destroy(def);

  tt_space *s = tt_space_create("p", "1.0");
  tt_space_add_float(s, "x", 0.0, 1.0, 0.5, 0, NULL);
  tt_space_add_float(s, "y", 0.0, 1.0, 0.5, 0, NULL);
  tt_config *c = tt_config_create(s), *c2 = tt_config_create(s);
  tt_tuner *t = NULL;

  tt_config *bad = tnm_settings(nm, "reflection", "2.5", "expansion", "2.0", NULL);
  CHECK(nm->create(s, bad, 1, &t) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "expansion");
  tt_config_destroy(bad);

  CHECK(nm->create(s, NULL, 1, &t) == TT_OK);
  double cost;
  CHECK(nm->best(t, c, &cost) == TT_ERR_NO_DATA);
  CHECK(nm->feedback(t, 1.0) == TT_ERR_INVALID_ARGUMENT); /* nothing outstanding */
  CHECK(nm->next(t, c) == TT_OK);
  CHECK(nm->next(t, c2) == TT_OK);
  CHECK(tt_config_equal(c, c2)); /* re-proposed */
  CHECK(nm->feedback(t, NAN) == TT_ERR_INVALID_ARGUMENT);
  CHECK(nm->feedback(t, -INFINITY) == TT_ERR_INVALID_ARGUMENT);
  CHECK(nm->feedback(t, 3.0) == TT_OK);
  CHECK(nm->feedback(t, 3.0) == TT_ERR_INVALID_ARGUMENT); /* already answered */
  CHECK(nm->best(t, c2, &cost) == TT_OK);
  CHECK(tt_config_equal(c, c2) && cost == 3.0);
  CHECK(nm->next(t, c) == TT_OK);
  CHECK(nm->feedback(t, INFINITY) == TT_OK); /* failed measurement */
  CHECK(nm->best(t, c2, &cost) == TT_OK && cost == 3.0);
  nm->destroy(t);

  /* maxEvaluations stops the search with the best configuration in `out`. */
  tt_config *lim = tnm_settings(nm, "maxEvaluations", "5", NULL);
  CHECK(nm->create(s, lim, 1, &t) == TT_OK);
  int n = 0;
  double bestc = INFINITY;
  tt_status st;
  while ((st = nm->next(t, c)) == TT_OK) {
    double f = tt_config_get(c, 0).f + tt_config_get(c, 1).f;
    if (f < bestc) bestc = f, tt_config_copy(c2, c);
    nm->feedback(t, f);
    n++;
  }
  CHECK(st == TT_DONE && n == 5);
  CHECK(tt_config_equal(c, c2));
  nm->destroy(t);
  tt_config_destroy(lim);
  nm->destroy(NULL);

  tt_config_destroy(c);
  tt_config_destroy(c2);
  tt_space_destroy(s);
}

/* ---- set_context (ABI 1.1): budget, the default's cost, resume ---- */

/* Unit coordinates of the INT/FLOAT parameters x, y, z of resume_space(_many). */
static void xyz(const tt_config *c, double *out) {
  double u[8];
  tt_config_to_unit(c, u);
  out[0] = u[0];
  out[1] = u[1];
  out[2] = u[4];
}

/* The first `k` proposals share their INT/FLOAT coordinates (probe mode) or not. */
static int probes(const tt_tuner_iface *nm, tt_space *s, uint64_t budget, int k) {
  tt_tuner *t = NULL;
  CHECK(nm->create(s, NULL, 7, &t) == TT_OK);
  if (budget) {
    tt_tuner_context ctx = {.struct_size = sizeof ctx, .default_cost = NAN, .budget = budget};
    CHECK_MSG(nm->set_context(t, &ctx) == TT_OK, "%s", tt_last_error());
  }
  tt_config *c = tt_config_create(s);
  double first[3], cur[3];
  int shared = 1;
  resume_ctx rc = {0};
  for (int i = 0; i < k; i++) {
    CHECK(nm->next(t, c) == TT_OK);
    xyz(c, i ? cur : first);
    if (i && (cur[0] != first[0] || cur[1] != first[1] || cur[2] != first[2])) shared = 0;
    nm->feedback(t, resume_cost(c, &rc));
  }
  tt_config_destroy(c);
  nm->destroy(t);
  return shared;
}

static void test_context(const tt_tuner_iface *nm) {
  CHECK(TT_TUNER_HAS(nm, set_context));
  tt_space *few = resume_space(), *many = resume_space_many();
  /* 6 arms x 4 points = 24 <= 50: every simplex is built up front, unless the budget is
   * smaller than that; 24 arms x 5 = 120 > 50: probe mode, unless the budget covers it */
  CHECK(!probes(nm, few, 0, 6));
  CHECK(probes(nm, few, 12, 6));
  CHECK(probes(nm, many, 0, 24)); /* 24 arms (flag2 is folded into the simplex), n = 4 */
  CHECK(!probes(nm, many, 400, 24));

  /* the default's cost: answered from the cache, never proposed (no re-measurement here:
   * reevaluate 0), and it competes for best(): it is this cost's optimum */
  tt_space *grid = tt_space_create("grid", "1");
  tt_space_add_int(grid, "a", 0, 5, 1, NULL);
  tt_space_add_int(grid, "b", 0, 5, 2, NULL);
  tt_config *c = tt_config_create(grid), *def = tt_config_create(grid);
  tt_config *noreeval = tnm_settings(nm, "reevaluate", "0", NULL);
  char *defj = tt_config_to_json(def);
  int seen_default[2] = {0, 0};
  for (int with = 0; with < 2; with++) {
    for (uint64_t seed = 1; seed <= 8; seed++) {
      tt_tuner *t = NULL;
      CHECK(nm->create(grid, noreeval, seed, &t) == TT_OK);
      if (with) {
        tt_tuner_context ctx = {.struct_size = sizeof ctx, .default_cost = 1.0, .budget = 30};
        CHECK(nm->set_context(t, &ctx) == TT_OK);
      }
      for (int n = 0; n < 30 && nm->next(t, c) == TT_OK; n++) {
        char *j = tt_config_to_json(c);
        seen_default[with] += !strcmp(j, defj);
        tt_free(j);
        nm->feedback(t, 1.0 + fabs(tt_config_get(c, 0).f - 1) + fabs(tt_config_get(c, 1).f - 2));
      }
      double best = 0;
      CHECK(nm->best(t, c, &best) == TT_OK);
      char *bj = tt_config_to_json(c);
      if (with)
        CHECK_MSG(best == 1.0 && !strcmp(bj, defj), "seed %d: best %g %s", (int)seed, best, bj);
      tt_free(bj);
      nm->destroy(t);
    }
  }
  printf("set_context: the default proposed %d times in 8 runs without its cost, %d with it\n",
         seen_default[0], seen_default[1]);
  CHECK(seen_default[0] > 0 && seen_default[1] == 0);
  tt_config_destroy(noreeval);

  /* bad contexts, and only once before the first next() */
  tt_tuner *t = NULL;
  CHECK(nm->create(many, NULL, 1, &t) == TT_OK);
  double st[2] = {0.5, 0.5};
  tt_tuner_context bad = {
      .struct_size = sizeof bad, .state = st, .state_dim = 0, .default_cost = NAN};
  CHECK(nm->set_context(t, &bad) == TT_ERR_INVALID_ARGUMENT);
  bad.state_dim = 2;
  bad.default_cost = -1;
  CHECK(nm->set_context(t, &bad) == TT_ERR_INVALID_ARGUMENT);
  bad.struct_size = 8;
  CHECK(nm->set_context(t, &bad) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "shorter");
  tt_tuner_context ok = {.struct_size = sizeof ok,
                         .state = st,
                         .state_dim = 2,
                         .state_space = "test",
                         .default_cost = 2.0,
                         .budget = 400};
  CHECK(nm->set_context(t, &ok) == TT_OK);
  CHECK(nm->set_context(t, &ok) == TT_ERR_INVALID_ARGUMENT);
  /* resume: a saved tuner keeps the context's effects without a second call */
  resume_ctx rc = {0};
  char *ref[60];
  nm->destroy(t);
  tt_config *m = tt_config_create(many);
  CHECK(nm->create(many, NULL, 1, &t) == TT_OK);
  CHECK(nm->set_context(t, &ok) == TT_OK);
  for (int i = 0; i < 60; i++) {
    CHECK(nm->next(t, m) == TT_OK);
    ref[i] = tt_config_to_json(m);
    nm->feedback(t, resume_cost(m, &rc));
  }
  nm->destroy(t);
  rc.calls = 0;
  CHECK(nm->create(many, NULL, 1, &t) == TT_OK);
  CHECK(nm->set_context(t, &ok) == TT_OK);
  char *state = NULL;
  int same = 0;
  for (int i = 0; i < 25; i++) {
    nm->next(t, m);
    char *j = tt_config_to_json(m);
    same += !strcmp(j, ref[i]);
    tt_free(j);
    nm->feedback(t, resume_cost(m, &rc));
  }
  CHECK(nm->save_state(t, &state) == TT_OK);
  CHECK_CONTAINS(state, "\"probe\":false");
  CHECK_CONTAINS(state, "\"contextSet\":true");
  nm->destroy(t);
  CHECK(nm->create(many, NULL, 1, &t) == TT_OK); /* created in probe mode (no context) */
  CHECK(nm->load_state(t, state) == TT_OK);
  CHECK(nm->set_context(t, &ok) == TT_ERR_INVALID_ARGUMENT); /* already applied */
  for (int i = 25; i < 60; i++) {
    nm->next(t, m);
    char *j = tt_config_to_json(m);
    same += !strcmp(j, ref[i]);
    tt_free(j);
    nm->feedback(t, resume_cost(m, &rc));
  }
  CHECK_MSG(same == 60, "%d of 60 proposals identical after resuming a tuner with a context", same);
  nm->destroy(t);
  for (int i = 0; i < 60; i++) tt_free(ref[i]);
  tt_free(state);
  tt_free(defj);
  tt_config_destroy(c);
  tt_config_destroy(def);
  tt_config_destroy(m);
  tt_space_destroy(grid);
  tt_space_destroy(few);
  tt_space_destroy(many);
}

int main(void) {
  const tt_tuner_iface *nm = tnm_load();
  test_protocol(nm);
  test_constraints(nm);
  test_lhs(nm);
  test_save_load(nm);
  test_duplicates(nm);
  test_nominal_only(nm);
  test_context(nm);
  tt_registry_destroy(tnm_reg);
  return tt_test_finish("tuner_nm_protocol");
}
