/* The tuning session of tunetrace/tuning.h driven in-process (no host process), over an
 * analytic target whose "render time" is a known function of its configuration:
 *  - the loop: default first (iteration -1), tuner_nm finds the minimum's neighbourhood,
 *    best = the lowest mean cost, counters add up, progress reaches 1;
 *  - ask/tell and tt_tuning_run give the same samples for the same seed and costs;
 *  - the database: a second session in the same state measures nothing, one in another
 *    state everything; a configuration measured earlier in the session is measured again;
 *  - constraints: infeasible proposals are recorded, never applied;
 *  - objectives: build+render, metric min/max/target, a missing metric, rrmse (known
 *    value), spec parsing and canonical spelling;
 *  - verify: alternating order, exact ratios; apply_best applies only what is not applied;
 *    a lucky best that is not faster side by side is rejected and the default applied;
 *  - warm-up passes, interruption, convergence of a tuner. */
#include <tunetrace/loader.h>
#include <tunetrace/tuning.h>

#include "tt_test.h"

#include <stdarg.h>
#include <unistd.h>

/* ---- the analytic target ---- */

typedef struct target_state {
  tt_config *applied; /* what apply() got last */
  int applies, renders, warmups;
  int interrupt_at;       /* render number that returns TT_ERR_INTERRUPTED (0: never) */
  int infeasible_applied; /* apply() saw a configuration the constraint rejects */
  int publish_metric;
  char order[64]; /* 'd' / 'b' per apply during verify (see verify test) */
  int record_order;
  const char *best_json, *default_json;
  float image[4 * 3]; /* 2x2 pass image (rrmse) */
} target_state;

/* Cost surface: minimum at x = 0.3, y = 0.7, n = 1; 1 ms offset keeps ratios finite. */
static double cost_of(const tt_config *c) {
  double x = tt_config_get_float(c, "x", 0), y = tt_config_get_float(c, "y", 0);
  double n = (double)tt_config_get_int(c, "n", 0);
  return 1.0 + 10.0 * ((x - 0.3) * (x - 0.3) + (y - 0.7) * (y - 0.7)) + 0.05 * (n - 1);
}

/* x + y > 1.6 is infeasible. */
static tt_check_result check_fn(const tt_space *space, tt_config *c, char *why, size_t n,
                                void *user) {
  (void)space;
  (void)user;
  if (tt_config_get_float(c, "x", 0) + tt_config_get_float(c, "y", 0) > 1.6) {
    snprintf(why, n, "x + y > 1.6");
    return TT_CHECK_INFEASIBLE;
  }
  return TT_CHECK_OK;
}

static tt_space *make_space(void) {
  tt_space *s = tt_space_create("analytic", "1.0.0");
  CHECK(tt_space_add_float(s, "x", 0.0, 1.0, 0.9, 0, "x") == 0);
  CHECK(tt_space_add_float(s, "y", 0.0, 1.0, 0.1, 0, "y") == 1);
  CHECK(tt_space_add_int(s, "n", 1, 8, 4, "n") == 2);
  tt_space_set_check(s, check_fn, NULL);
  return s;
}

static tt_status t_apply(void *user, const tt_config *cfg, double *build_ms) {
  target_state *ts = user;
  char why[64];
  tt_config *copy = tt_config_clone(cfg);
  if (tt_space_check(tt_config_space(cfg), copy, why, sizeof why) == TT_CHECK_INFEASIBLE)
    ts->infeasible_applied++;
  tt_config_destroy(copy);
  if (!ts->applied) ts->applied = tt_config_clone(cfg);
  else tt_config_copy(ts->applied, cfg);
  ts->applies++;
  *build_ms = 2.0 * tt_config_get_float(cfg, "x", 0); /* build cost grows with x */
  if (ts->record_order && ts->applies < (int)sizeof ts->order) {
    char *json = tt_config_to_json(cfg);
    ts->order[strlen(ts->order)] = !strcmp(json, ts->default_json) ? 'd'
                                   : !strcmp(json, ts->best_json)  ? 'b'
                                                                   : '?';
    tt_free(json);
  }
  return TT_OK;
}

static tt_pass_stats g_ps;

static tt_status t_render(void *user, uint32_t spp, tt_tuning_measurement *m) {
  target_state *ts = user;
  if (!m) {
    ts->warmups++;
    return TT_OK;
  }
  ts->renders++;
  if (ts->interrupt_at && ts->renders == ts->interrupt_at) return TT_ERR_INTERRUPTED;
  CHECK(spp == 2);
  double cost = cost_of(ts->applied);
  m->render_ms = cost;
  memset(&g_ps, 0, sizeof g_ps);
  g_ps.struct_size = sizeof g_ps;
  if (ts->publish_metric) {
    g_ps.metric_count = 1;
    g_ps.metrics[0].name = "acceptance";
    g_ps.metrics[0].value = tt_config_get_float(ts->applied, "x", 0);
  }
  m->pass = &g_ps;
  for (int i = 0; i < 12; i++) ts->image[i] = (float)tt_config_get_float(ts->applied, "y", 0);
  m->image = ts->image;
  return TT_OK;
}

/* ---- helpers ---- */

static int g_progress_calls;
static double g_progress_last;
static void quiet_log(tt_log_level level, const char *plugin, const char *fmt, ...) {
  (void)level;
  (void)plugin;
  (void)fmt;
}
static void count_progress(const char *task, double fraction) {
  (void)task;
  g_progress_calls++;
  g_progress_last = fraction;
}
static int g_stop;
static int should_stop(void) { return g_stop; }
static tt_host g_host;

static const tt_tuner_iface *g_nm;

static tt_tuning_desc base_desc(const tt_space *space, const tt_tuning_state *state) {
  tt_tuning_desc d;
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.host = &g_host;
  d.space = space;
  d.tuner = g_nm;
  d.tuner_name = "tuner_nm";
  d.seed = 7;
  d.iterations = 30;
  d.spp = 2;
  d.plugin = "analytic";
  d.plugin_version = "1.0.0";
  d.state = state;
  return d;
}

static tt_tuning_target target_of(target_state *ts) {
  tt_tuning_target t = {sizeof t, ts, t_apply, t_render};
  return t;
}

/* Lowest mean cost over identical configurations, computed here independently. */
static double best_mean(const tt_tuning *t) {
  double best = TT_COST_INFEASIBLE;
  size_t n = tt_tuning_sample_count(t);
  for (size_t i = 0; i < n; i++) {
    double sum = 0;
    int k = 0;
    for (size_t j = 0; j < n; j++) {
      const tt_tuning_sample *a = tt_tuning_sample_at(t, i), *b = tt_tuning_sample_at(t, j);
      if (strcmp(a->config, b->config) || b->status == TT_TUNEDB_FAILED) continue;
      sum += b->cost;
      k++;
    }
    if (k && sum / k < best) best = sum / k;
  }
  return best;
}

/* ---- tests ---- */

static void test_loop(const tt_space *space) {
  target_state ts = {0};
  tt_tuning_desc d = base_desc(space, NULL);
  d.warmup_passes = 2;
  tt_tuning *t = NULL;
  g_progress_calls = 0;
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  tt_tuning_target tg = target_of(&ts);
  CHECK(tt_tuning_run(t, &tg) == TT_OK);
  CHECK(ts.warmups == 2);
  tt_tuning_stats st = {.struct_size = sizeof st};
  tt_tuning_get_stats(t, &st);
  size_t n = tt_tuning_sample_count(t);
  CHECK(n == 1 + st.iterations);
  CHECK(st.iterations <= 30 && (st.iterations == 30 || st.converged));
  CHECK(st.measured == n && st.cached == 0 && st.failed == 0);
  CHECK(!strcmp(tt_tuning_mode(t), "tune"));
  /* default first, with the space's defaults */
  const tt_tuning_sample *s0 = tt_tuning_sample_at(t, 0);
  CHECK(s0->iteration == -1 && !strcmp(s0->config, tt_tuning_default_json(t)));
  tt_config *defaults = tt_config_create(space);
  CHECK_NEAR(s0->cost, cost_of(defaults), 1e-12);
  tt_config_destroy(defaults);
  double def = 0, best = 0;
  CHECK(tt_tuning_default_cost(t, &def) == TT_OK && def == s0->cost);
  tt_config *b = tt_config_create(space);
  CHECK(tt_tuning_best(t, b, &best) == TT_OK);
  CHECK(best == best_mean(t));
  CHECK(best < def);
  /* Nelder-Mead on a bowl gets close to its minimum in 30 steps */
  CHECK_MSG(best < 1.25, "best %.4f", best);
  CHECK(fabs(tt_config_get_float(b, "x", 0) - 0.3) < 0.2);
  char *bj = tt_config_to_json(b);
  CHECK(!strcmp(bj, tt_tuning_best_json(t)));
  tt_free(bj);
  /* every proposal but the infeasible ones was applied once and rendered once */
  CHECK(ts.applies == (int)(st.measured - st.infeasible));
  CHECK(ts.renders == ts.applies);
  CHECK(ts.infeasible_applied == 0);
  for (size_t i = 0; i < n; i++) {
    const tt_tuning_sample *s = tt_tuning_sample_at(t, i);
    CHECK(s->iteration == (int32_t)i - 1);
    if (s->status == TT_TUNEDB_INFEASIBLE) CHECK(s->cost == TT_COST_INFEASIBLE);
    else CHECK(s->status == TT_TUNEDB_OK && s->render_ms == s->cost);
  }
  CHECK(g_progress_calls == (int)n && fabs(g_progress_last - (double)st.iterations / 30) < 1e-12);
  /* apply_best: the target runs the last proposal, so the best is applied once, then not */
  int before = ts.applies;
  CHECK(tt_tuning_apply_best(t, &tg, NULL) == TT_OK);
  CHECK(ts.applies ==
        before + (strcmp(tt_tuning_best_json(t), tt_tuning_sample_at(t, n - 1)->config) != 0));
  before = ts.applies;
  CHECK(tt_tuning_apply_best(t, &tg, NULL) == TT_OK && ts.applies == before);

  /* verify: 4 rounds, default/best alternating d b | b d | d b | b d, exact ratios */
  ts.record_order = 1;
  ts.best_json = tt_tuning_best_json(t);
  ts.default_json = tt_tuning_default_json(t);
  tt_tuning_verification v = {.struct_size = sizeof v};
  CHECK(tt_tuning_verify(t, &tg, 4, &v) == TT_OK);
  CHECK_MSG(!strcmp(ts.order, "dbbddbbd"), "order %s", ts.order);
  CHECK(v.rounds == 4 && v.spp == 2);
  CHECK_NEAR(v.median_render_ms[0], def, 1e-12);
  CHECK_NEAR(v.median_cost[1], cost_of(b), 1e-12);
  CHECK_NEAR(v.render_ratio, cost_of(b) / def, 1e-12);
  CHECK_NEAR(v.cost_ratio, v.render_ratio, 1e-12);
  CHECK_NEAR(v.rounds_ms[(3 * 2 + 1) * 3 + 1], cost_of(b), 1e-12); /* round 3, best, render */
  CHECK(tt_tuning_sample_count(t) == n); /* verification records nothing */
  /* the bowl's best is faster in every round: kept, and said so */
  const char *reason = NULL;
  CHECK(v.verdict == TT_TUNING_CONFIRMED && v.best_faster == 4 && v.cost_difference < 0);
  CHECK(tt_tuning_get_verdict(t, &reason) == TT_TUNING_CONFIRMED && reason == v.reason);
  CHECK_MSG(reason && strstr(reason, "keeping the tuned configuration"), "%s", reason);
  CHECK(!strcmp(tt_tuning_kept_json(t), tt_tuning_best_json(t)));
  tt_config_destroy(b);
  tt_config_destroy(ts.applied);
  tt_tuning_destroy(t);
}

/* The same search driven by ask/tell: the same samples, bit for bit. */
static void test_ask_tell(const tt_space *space) {
  target_state a = {0}, b = {0};
  tt_tuning_desc d = base_desc(space, NULL);
  tt_tuning *run = NULL, *ask = NULL;
  CHECK(tt_tuning_create(&d, &run) == TT_OK && tt_tuning_create(&d, &ask) == TT_OK);
  tt_tuning_target tg = target_of(&a);
  CHECK(tt_tuning_run(run, &tg) == TT_OK);
  tt_config *cfg = tt_config_create(space);
  tt_tuning_measurement m0 = {.struct_size = sizeof m0};
  CHECK(tt_tuning_report(ask, &m0, NULL) == TT_ERR_INVALID_ARGUMENT); /* nothing asked */
  tt_status st;
  int steps = 0;
  while ((st = tt_tuning_next(ask, cfg)) == TT_OK) {
    tt_config *again = tt_config_create(space);
    CHECK(tt_tuning_next(ask, again) == TT_OK && tt_config_equal(again, cfg)); /* re-asked */
    tt_config_destroy(again);
    tt_tuning_measurement m = {.struct_size = sizeof m};
    t_apply(&b, cfg, &m.build_ms);
    m.status = t_render(&b, 2, &m);
    double cost = 0;
    CHECK(tt_tuning_report(ask, &m, &cost) == TT_OK && cost == cost_of(cfg));
    steps++;
  }
  CHECK(st == TT_DONE);
  CHECK(tt_tuning_next(ask, cfg) == TT_DONE);
  CHECK(tt_tuning_sample_count(ask) == tt_tuning_sample_count(run));
  for (size_t i = 0; i < tt_tuning_sample_count(run); i++) {
    const tt_tuning_sample *x = tt_tuning_sample_at(run, i), *y = tt_tuning_sample_at(ask, i);
    CHECK(!strcmp(x->config, y->config) && x->cost == y->cost && x->status == y->status);
  }
  CHECK(!strcmp(tt_tuning_best_json(run), tt_tuning_best_json(ask)));
  tt_config_destroy(cfg);
  tt_config_destroy(a.applied);
  tt_config_destroy(b.applied);
  tt_tuning_destroy(run);
  tt_tuning_destroy(ask);
}

/* A tuner that proposes a fixed list, then converges: A, A, B. */
typedef struct fixed_tuner {
  const tt_space *space;
  int next, fed;
} fixed_tuner;
static tt_status ft_create(const tt_space *target, const tt_config *settings, uint64_t seed,
                           tt_tuner **out) {
  (void)settings;
  (void)seed;
  fixed_tuner *f = calloc(1, sizeof *f);
  f->space = target;
  *out = (tt_tuner *)f;
  return TT_OK;
}
static tt_status ft_next(tt_tuner *t, tt_config *out) {
  fixed_tuner *f = (fixed_tuner *)t;
  static const char *list[] = {"{\"x\":0.5,\"y\":0.5}", "{\"x\":0.5,\"y\":0.5}",
                               "{\"x\":0.3,\"y\":0.7}"};
  if (f->next >= 3) return TT_DONE;
  return tt_config_from_json(out, list[f->next], "fixed");
}
static tt_status ft_feedback(tt_tuner *t, double cost) {
  (void)cost;
  fixed_tuner *f = (fixed_tuner *)t;
  f->next++;
  f->fed++;
  return TT_OK;
}
static void ft_destroy(tt_tuner *t) { free(t); }
static const tt_tuner_iface g_fixed = {sizeof g_fixed, NULL, ft_create, ft_next,    ft_feedback,
                                       NULL,           NULL, NULL,      ft_destroy, NULL};

/* A target whose costs are scripted per configuration: the default always costs 1; every
 * other configuration costs `lucky` at its first measurement and `later` after that (a
 * search's best is often one lucky pass). `sign` -1 measures through metric:acceptance:max
 * instead (value 1/cost, so the objective's costs are negative and ratios mean nothing). */
typedef struct scripted {
  tt_config *applied;
  const char *default_json;
  char *seen[16];
  int count[16], nseen;
  double lucky, later, sign;
  int applies;
} scripted;

static tt_status sc_apply(void *user, const tt_config *cfg, double *build_ms) {
  scripted *sc = user;
  if (!sc->applied) sc->applied = tt_config_clone(cfg);
  else tt_config_copy(sc->applied, cfg);
  sc->applies++;
  *build_ms = 0;
  return TT_OK;
}

static tt_status sc_render(void *user, uint32_t spp, tt_tuning_measurement *m) {
  (void)spp;
  scripted *sc = user;
  if (!m) return TT_OK;
  char *json = tt_config_to_json(sc->applied);
  double cost = 1.0;
  if (strcmp(json, sc->default_json)) {
    int k = 0;
    while (k < sc->nseen && strcmp(sc->seen[k], json)) k++;
    if (k == sc->nseen && k < 16) sc->seen[sc->nseen++] = strdup(json);
    cost = k < 16 && sc->count[k]++ ? sc->later : sc->lucky;
  }
  tt_free(json);
  memset(&g_ps, 0, sizeof g_ps);
  g_ps.struct_size = sizeof g_ps;
  g_ps.metric_count = 1;
  g_ps.metrics[0].name = "acceptance";
  /* metric:acceptance:max's cost is -value: -1/cost keeps the order, negative */
  g_ps.metrics[0].value = 1.0 / cost;
  m->render_ms = sc->sign > 0 ? cost : 1.0;
  m->pass = &g_ps;
  return TT_OK;
}

/* --verify keeps the default when the search's best is not faster side by side: the fixed
 * tuner proposes A, A, B; A measures lucky then slow (mean between), B once, lucky: B is
 * the best by its one pass. Measured again side by side it is slower than the default in
 * every round, so the session keeps the default, applies it, says why, and still reports B
 * as the search's best. When B really is faster, it is kept. Costs of either sign. */
static void test_verify_keeps_default(const tt_space *space) {
  const struct {
    double lucky, later, sign;
    const char *objective;
    int keep_best;
  } cases[] = {
      {0.5, 1.2, 1, "render", 0},
      {0.5, 0.8, 1, "render", 1},
      {0.5, 1.2, -1, "metric:acceptance:max", 0},
      {0.5, 0.8, -1, "metric:acceptance:max", 1},
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    tt_tuning_desc d = base_desc(space, NULL);
    d.tuner = &g_fixed;
    d.tuner_name = "fixed";
    d.objective = cases[c].objective;
    tt_tuning *t = NULL;
    CHECK(tt_tuning_create(&d, &t) == TT_OK);
    scripted sc = {.default_json = tt_tuning_default_json(t),
                   .lucky = cases[c].lucky,
                   .later = cases[c].later,
                   .sign = cases[c].sign};
    tt_tuning_target tg = {sizeof tg, &sc, sc_apply, sc_render};
    CHECK(tt_tuning_run(t, &tg) == TT_OK);
    const char *best = tt_tuning_best_json(t);
    CHECK_MSG(strstr(best, "\"x\":0.3") != NULL, "case %zu: best %s", c, best);
    CHECK(tt_tuning_get_verdict(t, NULL) == TT_TUNING_UNVERIFIED);
    CHECK(!strcmp(tt_tuning_kept_json(t), best)); /* unverified: the best, as found */
    tt_tuning_verification v = {.struct_size = sizeof v};
    CHECK(tt_tuning_verify(t, &tg, 5, &v) == TT_OK && v.rounds == 5);
    CHECK(tt_tuning_apply_best(t, &tg, NULL) == TT_OK);
    char *applied = tt_config_to_json(sc.applied);
    const char *reason = NULL;
    tt_tuning_verdict verdict = tt_tuning_get_verdict(t, &reason);
    if (cases[c].keep_best) {
      CHECK_MSG(verdict == TT_TUNING_CONFIRMED && v.best_faster == 5, "case %zu: verdict %d", c,
                (int)verdict);
      CHECK_MSG(!strcmp(applied, best), "case %zu: applied %s", c, applied);
      CHECK(!strcmp(tt_tuning_kept_json(t), best));
    } else {
      CHECK_MSG(verdict == TT_TUNING_REJECTED && v.verdict == TT_TUNING_REJECTED &&
                    v.best_faster == 0,
                "case %zu: verdict %d", c, (int)verdict);
      CHECK_MSG(!strcmp(applied, tt_tuning_default_json(t)), "case %zu: applied %s", c, applied);
      CHECK(!strcmp(tt_tuning_kept_json(t), tt_tuning_default_json(t)));
      CHECK(!strcmp(tt_tuning_best_json(t), best)); /* the search's best is still reported */
      CHECK_MSG(reason && strstr(reason, "keeping the default configuration") &&
                    strstr(reason, "not faster") && !strstr(reason, "-"),
                "case %zu: %s", c, reason);
    }
    CHECK_NEAR(v.cost_difference,
               cases[c].sign > 0 ? cases[c].later - 1.0 : 1.0 - 1.0 / cases[c].later, 1e-12);
    tt_free(applied);
    for (int k = 0; k < sc.nseen; k++) free(sc.seen[k]);
    tt_config_destroy(sc.applied);
    tt_tuning_destroy(t);
  }
}

static void test_database(const tt_space *space) {
  char path[] = "/tmp/tt_tune_session_XXXXXX";
  int fd = mkstemp(path);
  CHECK(fd >= 0);
  close(fd);
  unlink(path);
  tt_tunedb *db = NULL;
  CHECK(tt_tunedb_open(path, &db) == TT_OK);
  tt_tuning_state state = {.struct_size = sizeof state,
                           .scene_id = "0123456789abcdef",
                           .scene = "analytic.json",
                           .camera = "{\"fov_y\":40}",
                           .context = "{\"spp\":2}"};
  /* first session: measures and records; A is proposed twice and measured twice */
  target_state a = {0};
  tt_tuning_desc d = base_desc(space, &state);
  d.tuner = &g_fixed;
  d.tuner_name = "fixed";
  d.db = db;
  d.iterations = 10;
  tt_tuning *t = NULL;
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  tt_tuning_target tg = target_of(&a);
  CHECK(tt_tuning_run(t, &tg) == TT_OK);
  tt_tuning_stats st = {.struct_size = sizeof st};
  tt_tuning_get_stats(t, &st);
  CHECK(st.converged && st.iterations == 3 && st.measured == 4 && st.cached == 0);
  CHECK(a.renders == 4);
  uint64_t rows = 0;
  CHECK(tt_tunedb_count(db, "analytic", &rows) == TT_OK && rows == 4);
  /* the best is the lowest mean: B (0.3, 0.7) */
  CHECK(strstr(tt_tuning_best_json(t), "\"x\":0.3") != NULL);
  tt_tuning_destroy(t);

  /* same state: everything from the database, nothing rendered */
  target_state b = {0};
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  tg = target_of(&b);
  CHECK(tt_tuning_run(t, &tg) == TT_OK);
  tt_tuning_get_stats(t, &st);
  CHECK(st.cached == 4 && st.measured == 0);
  CHECK(b.renders == 0 && b.applies == 0);
  for (size_t i = 0; i < tt_tuning_sample_count(t); i++) CHECK(tt_tuning_sample_at(t, i)->cached);
  CHECK(strstr(tt_tuning_best_json(t), "\"x\":0.3") != NULL);
  tt_tuning_destroy(t);

  /* another camera: another state, measured again */
  target_state c = {0};
  tt_tuning_state other = state;
  other.camera = "{\"fov_y\":60}";
  d.state = &other;
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  tg = target_of(&c);
  CHECK(tt_tuning_run(t, &tg) == TT_OK);
  tt_tuning_get_stats(t, &st);
  CHECK(st.cached == 0 && st.measured == 4 && c.renders == 4);
  tt_tuning_destroy(t);
  tt_tunedb_close(db);
  unlink(path);
  tt_config_destroy(a.applied);
  tt_config_destroy(c.applied);
}

/* tt_tuning_set_state (tuning along a sequence): each measurement is recorded in the state
 * it was asked for in, the database answers per state, a state change while a configuration
 * is outstanding is refused, the search goes on across states. */
static void test_set_state(const tt_space *space) {
  char path[] = "/tmp/tt_tune_set_state_XXXXXX";
  int fd = mkstemp(path);
  CHECK(fd >= 0);
  close(fd);
  unlink(path);
  tt_tunedb *db = NULL;
  CHECK(tt_tunedb_open(path, &db) == TT_OK);
  char cams[4][32];
  tt_tuning_state st[4];
  for (int i = 0; i < 4; i++) {
    snprintf(cams[i], sizeof cams[i], "{\"frame\":%d}", i);
    st[i] = (tt_tuning_state){.struct_size = sizeof st[i],
                              .scene_id = "0123456789abcdef",
                              .scene = "analytic.json",
                              .camera = cams[i],
                              .context = "{\"spp\":2}"};
  }
  target_state a = {0};
  tt_tuning_desc d = base_desc(space, &st[0]);
  d.tuner = &g_fixed;
  d.tuner_name = "fixed";
  d.db = db;
  d.iterations = 10;
  tt_tuning *t = NULL;
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  tt_config *cfg = tt_config_create(space);
  int asked = 0;
  for (int i = 0; i < 4; i++) {
    CHECK(tt_tuning_set_state(t, &st[i]) == TT_OK);
    tt_status ns = tt_tuning_next(t, cfg);
    if (ns == TT_DONE) break;
    CHECK(ns == TT_OK);
    asked++;
    CHECK(tt_tuning_set_state(t, &st[(i + 1) % 4]) == TT_ERR_INVALID_ARGUMENT); /* pending */
    CHECK_CONTAINS(tt_last_error(), "outstanding");
    tt_tuning_measurement m = {.struct_size = sizeof m};
    t_apply(&a, cfg, &m.build_ms);
    m.status = t_render(&a, 2, &m);
    CHECK(tt_tuning_report(t, &m, NULL) == TT_OK);
  }
  CHECK(asked == 4); /* default, A, A, B: the fixed tuner's list went on across the states */
  CHECK(strstr(tt_tuning_best_json(t), "\"x\":0.3") != NULL);
  tt_tuning_state nul = {.struct_size = sizeof nul}; /* no scene_id with a database */
  CHECK(tt_tuning_set_state(t, &nul) == TT_ERR_INVALID_ARGUMENT);
  CHECK(tt_tuning_set_state(t, NULL) == TT_ERR_INVALID_ARGUMENT);
  tt_tuning_destroy(t);
  uint64_t rows = 0;
  CHECK(tt_tunedb_count(db, "analytic", &rows) == TT_OK && rows == 4);
  /* the same states again: the database answers a configuration only in the state it was
   * measured in, and a configuration this session measured is measured again (the tuner
   * re-measuring against noise). State 0 answers the default (measured there), not A
   * (measured in state 1): A is measured; state 1 measures A again (this session's), state
   * 2 measures B (recorded in state 3 only); then the tuner is done: 1 answered, 3 measured */
  target_state b = {0};
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  for (int i = 0; i < 4; i++) {
    CHECK(tt_tuning_set_state(t, &st[i]) == TT_OK);
    tt_status ns = tt_tuning_next(t, cfg);
    if (ns != TT_OK) break;
    tt_tuning_measurement m = {.struct_size = sizeof m};
    t_apply(&b, cfg, &m.build_ms);
    m.status = t_render(&b, 2, &m);
    CHECK(tt_tuning_report(t, &m, NULL) == TT_OK);
  }
  tt_tuning_stats ts = {.struct_size = sizeof ts};
  tt_tuning_get_stats(t, &ts);
  CHECK_MSG(ts.cached == 1 && ts.measured == 3 && b.renders == 3,
            "answered per state: %u answered, %u measured", ts.cached, ts.measured);
  CHECK(tt_tunedb_count(db, "analytic", &rows) == TT_OK && rows == 7);
  tt_tuning_destroy(t);
  tt_config_destroy(cfg);
  tt_config_destroy(a.applied);
  tt_config_destroy(b.applied);
  tt_tunedb_close(db);
  unlink(path);
}

/* Random exploration over the constrained space: infeasible draws recorded, never applied;
 * the draws are a function of the seed. */
static void test_explore(const tt_space *space) {
  target_state ts = {0}, ts2 = {0};
  tt_tuning_desc d = base_desc(space, NULL);
  d.tuner = NULL;
  d.tuner_name = NULL;
  d.iterations = 60;
  tt_tuning *t = NULL, *t2 = NULL;
  CHECK(tt_tuning_create(&d, &t) == TT_OK && tt_tuning_create(&d, &t2) == TT_OK);
  CHECK(!strcmp(tt_tuning_mode(t), "explore"));
  tt_tuning_target tg = target_of(&ts), tg2 = target_of(&ts2);
  CHECK(tt_tuning_run(t, &tg) == TT_OK && tt_tuning_run(t2, &tg2) == TT_OK);
  tt_tuning_stats st = {.struct_size = sizeof st};
  tt_tuning_get_stats(t, &st);
  CHECK(st.iterations == 60);
  CHECK(st.infeasible > 0); /* x + y > 1.6 is 8% of the square: some of 60 draws hit it */
  CHECK(ts.infeasible_applied == 0);
  CHECK(ts.applies == 61 - (int)st.infeasible);
  for (size_t i = 0; i < tt_tuning_sample_count(t); i++)
    CHECK(!strcmp(tt_tuning_sample_at(t, i)->config, tt_tuning_sample_at(t2, i)->config));
  tt_config_destroy(ts.applied);
  tt_config_destroy(ts2.applied);
  tt_tuning_destroy(t);
  tt_tuning_destroy(t2);
}

/* One measurement of the default under `objective`; returns its cost. */
static double cost_under(const tt_space *space, const char *objective, int metric,
                         tt_status *report_st) {
  target_state ts = {.publish_metric = metric};
  tt_tuning_desc d = base_desc(space, NULL);
  d.objective = objective;
  d.iterations = 0;
  static const double ref[4] = {0.5, 0.5, 0.5, 0.5};
  d.width = d.height = 2;
  d.reference_luminance = ref;
  tt_tuning *t = NULL;
  double cost = NAN;
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  tt_config *cfg = tt_config_create(space);
  CHECK(tt_tuning_next(t, cfg) == TT_OK);
  tt_tuning_measurement m = {.struct_size = sizeof m};
  t_apply(&ts, cfg, &m.build_ms);
  m.status = t_render(&ts, 2, &m);
  *report_st = tt_tuning_report(t, &m, &cost);
  if (*report_st != TT_OK) CHECK(tt_tuning_sample_count(t) == 0); /* nothing recorded */
  tt_config_destroy(cfg);
  tt_config_destroy(ts.applied);
  tt_tuning_destroy(t);
  return cost;
}

static void test_objectives(const tt_space *space) {
  tt_config *def = tt_config_create(space); /* x 0.9, y 0.1 */
  double render = cost_of(def);
  tt_status st;
  CHECK_NEAR(cost_under(space, "render", 0, &st), render, 1e-12);
  CHECK_NEAR(cost_under(space, "build", 0, &st), 1.8, 1e-12);
  CHECK_NEAR(cost_under(space, "total", 0, &st), render + 1.8, 1e-12);
  CHECK_NEAR(cost_under(space, "metric:acceptance", 1, &st), 0.9, 1e-12);
  CHECK_NEAR(cost_under(space, "metric:acceptance:max", 1, &st), -0.9, 1e-12);
  CHECK_NEAR(cost_under(space, "metric:acceptance:target=0.234", 1, &st), 0.9 - 0.234, 1e-12);
  cost_under(space, "metric:acceptance", 0, &st);
  CHECK(st == TT_ERR_NO_DATA);
  CHECK_CONTAINS(tt_last_error(), "no finite metric \"acceptance\"");
  /* rrmse: the pass image is y = 0.1 grey, the reference 0.5: |0.1 - 0.5| / sqrt(0.251) */
  CHECK_NEAR(cost_under(space, "rrmse", 0, &st), 0.4 / sqrt(0.25 + 1e-3), 1e-6);
  tt_config_destroy(def);

  /* the library's rRMSE and luminance */
  const float rgb[6] = {1, 1, 1, 0, 1, 0};
  double lum[2];
  tt_luminance(rgb, 3, 2, lum);
  CHECK_NEAR(lum[0], 1.0, 1e-12);
  CHECK_NEAR(lum[1], 0.7152, 1e-7);
  const double ref[2] = {1.0, 0.0};
  double e1 = (1.0 - 1.0) * (1.0 - 1.0) / (1.0 + 1e-3), e2 = lum[1] * lum[1] / 1e-3;
  CHECK_NEAR(tt_rrmse(rgb, ref, 2), sqrt((e1 + e2) / 2), 1e-9);

  /* spec parsing: one spelling per objective */
  tt_objective o;
  CHECK(tt_objective_parse("total", &o) == TT_OK && !strcmp(o.spec, "build+render"));
  CHECK(tt_objective_parse("render+build", &o) == TT_OK && o.kind == TT_OBJECTIVE_TOTAL);
  CHECK(tt_objective_parse("metric:acc:target=0.2340", &o) == TT_OK &&
        !strcmp(o.spec, "metric:acc:target=0.234") && o.goal == TT_OBJECTIVE_TARGET);
  CHECK(tt_objective_parse("metric:acc", &o) == TT_OK && !strcmp(o.spec, "metric:acc:min"));
  CHECK(tt_objective_parse("metric:acc:max", &o) == TT_OK && !strcmp(o.spec, "metric:acc:max"));
  CHECK(tt_objective_parse("fastest", &o) == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(), "unknown objective \"fastest\"");
  CHECK(tt_objective_parse("metric:x:sometimes", &o) == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(), ":target=NUMBER");
  CHECK(tt_objective_parse("metric:", &o) == TT_ERR_PARSE);
  CHECK(tt_objective_parse("metric:a:target=inf", &o) == TT_ERR_PARSE);

  /* an rrmse session without a reference is refused at creation */
  tt_tuning_desc d = base_desc(space, NULL);
  d.objective = "rrmse";
  tt_tuning *t = NULL;
  CHECK(tt_tuning_create(&d, &t) == TT_ERR_INVALID_ARGUMENT && !t);
  d.objective = "fastest";
  CHECK(tt_tuning_create(&d, &t) == TT_ERR_PARSE && !t);
}

/* The user asks to stop: in the middle of a measurement, and between iterations. */
static void test_interrupt(const tt_space *space) {
  target_state ts = {.interrupt_at = 3};
  tt_tuning_desc d = base_desc(space, NULL);
  tt_tuning *t = NULL;
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  tt_tuning_target tg = target_of(&ts);
  CHECK(tt_tuning_run(t, &tg) == TT_ERR_INTERRUPTED);
  tt_tuning_stats st = {.struct_size = sizeof st};
  tt_tuning_get_stats(t, &st);
  CHECK(st.interrupted && tt_tuning_sample_count(t) == 2); /* the cut pass is not recorded */
  tt_tuning_destroy(t);
  tt_config_destroy(ts.applied);

  target_state ts2 = {0};
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  tt_config *cfg = tt_config_create(space);
  CHECK(tt_tuning_next(t, cfg) == TT_OK); /* the default is asked even when stopping */
  tt_tuning_measurement m = {.struct_size = sizeof m};
  t_apply(&ts2, cfg, &m.build_ms);
  m.status = t_render(&ts2, 2, &m);
  CHECK(tt_tuning_report(t, &m, NULL) == TT_OK);
  g_stop = 1;
  CHECK(tt_tuning_next(t, cfg) == TT_ERR_INTERRUPTED);
  g_stop = 0;
  tt_config_destroy(cfg);
  tt_config_destroy(ts2.applied);
  tt_tuning_destroy(t);
}

/* Searching a subset: the other parameters keep their configured values. */
static void test_subset(const tt_space *space) {
  tt_config *start = tt_config_create(space);
  CHECK(tt_config_set_string(start, "n", "6") == TT_OK);
  const char *names[] = {"x"};
  tt_space *sub = tt_space_subset(space, names, 1, start);
  CHECK(sub != NULL);
  target_state ts = {0};
  tt_tuning_desc d = base_desc(space, NULL);
  d.start = start;
  d.search = sub;
  d.iterations = 12;
  tt_tuning *t = NULL;
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  tt_tuning_target tg = target_of(&ts);
  CHECK(tt_tuning_run(t, &tg) == TT_OK);
  for (size_t i = 0; i < tt_tuning_sample_count(t); i++) {
    const char *c = tt_tuning_sample_at(t, i)->config;
    CHECK(strstr(c, "\"y\":0.1") && strstr(c, "\"n\":6"));
  }
  tt_tuning_destroy(t);
  tt_space_destroy(sub);
  tt_config_destroy(start);
  tt_config_destroy(ts.applied);
}

/* A copy of `s` with the first `from` replaced by `to` (free it). */
static char *replaced(const char *s, const char *from, const char *to) {
  const char *at = strstr(s, from);
  CHECK_MSG(at != NULL, "no %s in the saved state", from);
  if (!at) return NULL;
  size_t n = strlen(s) - strlen(from) + strlen(to);
  char *r = malloc(n + 1);
  snprintf(r, n + 1, "%.*s%s%s", (int)(at - s), s, to, at + strlen(from));
  return r;
}

/* A resume file with a field missing, not finite or out of range is refused naming the
 * field, and the session stays fresh. Before: a missing build_ms loaded as NaN and the next
 * save printed "nan", a resume file that no longer parsed (found by tests/fuzz/
 * fuzz_tuning_state); a huge next_iteration or a negative counter was cast to an integer. */
static void test_state_fields(const tt_space *space) {
  target_state ts = {0};
  tt_tuning_desc d = base_desc(space, NULL);
  d.iterations = 4;
  tt_tuning *t = NULL;
  CHECK(tt_tuning_create(&d, &t) == TT_OK);
  tt_tuning_target tg = target_of(&ts);
  CHECK(tt_tuning_run(t, &tg) == TT_OK);
  char *good = NULL;
  CHECK(tt_tuning_save_state(t, &good) == TT_OK && good);
  tt_tuning_destroy(t);
  tt_config_destroy(ts.applied);
  if (!good) return;
  static const struct {
    const char *from, *to, *field;
  } bad[] = {
      {"\"build_ms\":", "\"bulid_ms\":", "build_ms"},
      {"\"render_ms\":", "\"render_ms\":\"x\",\"r\":", "render_ms"},
      {"\"cost\":", "\"cost\":1e999,\"c\":", "cost"},
      {"\"iteration\":", "\"iteration\":-5,\"i\":", "iteration"},
      {"\"status\":", "\"status\":7,\"s\":", "status"},
      {"\"next_iteration\":", "\"next_iteration\":1e300,\"n\":", "next_iteration"},
      {"\"measured\":", "\"measured\":-1,\"m\":", "measured"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char *json = replaced(good, bad[i].from, bad[i].to);
    if (!json) continue;
    tt_tuning *u = NULL;
    CHECK(tt_tuning_create(&d, &u) == TT_OK);
    CHECK_MSG(tt_tuning_load_state(u, json, "resume.json") == TT_ERR_PARSE, "%s accepted",
              bad[i].field);
    CHECK_CONTAINS(tt_last_error(), "resume.json");
    CHECK_CONTAINS(tt_last_error(), bad[i].field);
    CHECK(tt_tuning_sample_count(u) == 0);
    CHECK_MSG(tt_tuning_load_state(u, good, "resume.json") == TT_OK, "%s", tt_last_error());
    char *again = NULL;
    CHECK(tt_tuning_save_state(u, &again) == TT_OK && again && !strcmp(again, good));
    free(again);
    tt_tuning_destroy(u);
    free(json);
  }
  /* nothing after the state is read: appended text (another state, say) is refused, a
   * final newline is not */
  size_t n = strlen(good);
  char *longer = malloc(2 * n + 2);
  snprintf(longer, 2 * n + 2, "%s\n%s", good, good);
  tt_tuning *u = NULL;
  CHECK(tt_tuning_create(&d, &u) == TT_OK);
  CHECK_MSG(tt_tuning_load_state(u, longer, "resume.json") == TT_ERR_PARSE, "appended accepted");
  CHECK_CONTAINS(tt_last_error(), "resume.json: unexpected text after the state");
  CHECK(tt_tuning_sample_count(u) == 0);
  longer[n + 1] = '\0';
  CHECK_MSG(tt_tuning_load_state(u, longer, "resume.json") == TT_OK, "%s", tt_last_error());
  tt_tuning_destroy(u);
  free(longer);
  free(good);
}

int main(void) {
  g_host = *tt_default_host();
  g_host.log = quiet_log;
  g_host.progress = count_progress;
  g_host.should_stop = should_stop;
  tt_registry *reg = tt_registry_create(&g_host);
  tt_loaded_plugin *p = NULL;
  if (!reg || tt_registry_load(reg, "tuner_nm", &p) != TT_OK) {
    fprintf(stderr, "cannot load tuner_nm: %s\n", tt_last_error());
    return 1;
  }
  g_nm = tt_loaded_plugin_iface(p);
  tt_space *space = make_space();
  test_loop(space);
  test_ask_tell(space);
  test_verify_keeps_default(space);
  test_database(space);
  test_set_state(space);
  test_explore(space);
  test_objectives(space);
  test_interrupt(space);
  test_subset(space);
  test_state_fields(space);
  tt_space_destroy(space);
  tt_registry_destroy(reg);
  return tt_test_finish("tune_session");
}
