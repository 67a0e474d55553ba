/* The hybrid tuner of tunetrace/hybrid.h driven in-process over a scripted target whose
 * best configuration changes along a camera path (thesis 3.3):
 *  - nearest neighbour at epsilon 0, warm-started from two searched states A and B, follows
 *    the path: states nearer A get A's best, states nearer B get B's. An exploited state
 *    is not a stored state (the table holds what searches found), so it never shadows A
 *    or B as the next state's neighbour (which would repeat the first answer forever);
 *  - an exploited state reports the model's predicted cost and the default's cost (the
 *    nearest state's where it was measured, and how near), for NN and RBF alike;
 *  - a warm start names what it left out: rows of another objective, and per context or
 *    camera key (clock, threads, resolution) the rows measured otherwise, with the value. */
#include <tunetrace/hybrid.h>
#include <tunetrace/loader.h>

#include "tt_test.h"

#include <stdarg.h>
#include <unistd.h>

enum { TRI = 1 };                    /* raw indicator index of the triangle count */
static const double TRI_SCALE = 1e6; /* path position t = triangles / TRI_SCALE */

/* ---- the target: configuration c in {0 (default), 1, 2}; cost depends on the state ---- */

static double g_t; /* the current state's position on the path, [0, 1] */
static int64_t g_applied = -1;

static double cost_at(int64_t c, double t) {
  return c == 0 ? 3.0 : c == 1 ? 1.0 + t : 2.0 - t; /* best: 1 before t = 0.5, 2 after */
}

static tt_status t_apply(void *user, const tt_config *cfg, double *build_ms) {
  (void)user;
  g_applied = tt_config_get_int(cfg, "c", -1);
  *build_ms = 0;
  return TT_OK;
}

static tt_status t_render(void *user, uint32_t spp, tt_tuning_measurement *m) {
  (void)user;
  (void)spp;
  if (m) m->render_ms = cost_at(g_applied, g_t);
  return TT_OK;
}

static void quiet_log(tt_log_level level, const char *plugin, const char *fmt, ...) {
  (void)level, (void)plugin, (void)fmt;
}

/* ---- helpers ---- */

static const char *CONTEXT = "{\"spp\":1,\"threads\":1,\"clock\":\"cpu\"}";
static const char *CAMERA = "{\"resolution\":[24,24]}";

static void raw_state(double t, double raw[TT_SCENE_INDICATOR_COUNT]) {
  memset(raw, 0, TT_SCENE_INDICATOR_COUNT * sizeof *raw);
  raw[TRI] = t * TRI_SCALE;
}

/* Records one row of state t: configuration c measured cost_at(c, t) under `objective`. */
static void record(tt_tunedb *db, double t, int64_t c, const char *objective, const char *context,
                   const char *camera) {
  char cfg[64], cam[128];
  snprintf(cfg, sizeof cfg, "{\"c\":%lld}", (long long)c);
  snprintf(cam, sizeof cam, "%.*s,\"t\":%g}", (int)strlen(camera) - 1, camera, t);
  tt_tunedb_row r;
  memset(&r, 0, sizeof r);
  r.struct_size = sizeof r;
  r.scene_id = "path";
  r.scene = "path.json";
  r.camera = cam;
  r.context = context;
  r.has_indicators = 1;
  raw_state(t, r.indicators);
  r.plugin = "scripted";
  r.plugin_version = "1.0.0";
  r.config = cfg;
  r.objective = objective;
  r.render_ms = r.cost = cost_at(c, t);
  r.status = TT_TUNEDB_OK;
  r.mode = c == 0 ? "default" : "tune";
  r.iteration = c == 0 ? -1 : (int32_t)c;
  r.run_id = "search";
  r.tuner = "tuner_nm";
  CHECK_MSG(tt_tunedb_record(db, &r) == TT_OK, "%s", tt_last_error());
}

static const tt_tuner_iface *g_nm;
static tt_host g_host;

/* One path from t = 0.05 to 0.95 at epsilon 0 with `predictor`, warm-started from `db`;
 * returns the configurations used per state in `used` and checks the reports. */
static void run_path(const tt_predictor_iface *pi, const char *name, tt_space *space, tt_tunedb *db,
                     int64_t used[10]) {
  tt_indicator_norm norm;
  tt_indicator_norm_init(&norm);
  char id[96];
  tt_predictor_setup su = {.struct_size = sizeof su,
                           .target = space,
                           .state_dim = TT_SCENE_INDICATOR_COUNT,
                           .state_space = tt_indicator_norm_id(&norm, id, sizeof id),
                           .seed = 3};
  tt_predictor *model = NULL;
  CHECK(pi->create_ex(&su, &model) == TT_OK);
  tt_hybrid_desc d;
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.host = &g_host;
  d.space = space;
  d.objective = "render";
  d.tuner = g_nm;
  d.tuner_name = "tuner_nm";
  d.predictor = pi;
  d.model = model;
  d.predictor_name = name;
  d.epsilon = 0;
  d.explore_iterations = 4;
  d.plugin = "scripted";
  d.plugin_version = "1.0.0";
  d.norm = &norm;
  tt_hybrid *h = NULL;
  CHECK(tt_hybrid_create(&d, &h) == TT_OK);
  static const char *const keys[] = {"clock", "spp", "threads", NULL};
  static const char *const camera_keys[] = {"resolution", NULL};
  tt_hybrid_warm_filter f = {.struct_size = sizeof f,
                             .context_keys = keys,
                             .context = CONTEXT,
                             .camera_keys = camera_keys,
                             .camera = CAMERA};
  tt_hybrid_warm_result wr = {.struct_size = sizeof wr};
  CHECK(tt_hybrid_warm_start_ex(h, db, &f, &wr) == TT_OK);
  CHECK_MSG(wr.rows == 6, "%s: learnt %llu rows", name, (unsigned long long)wr.rows);
  tt_tuning_target tg = {sizeof tg, NULL, t_apply, t_render};
  for (int k = 0; k < 10; k++) {
    g_t = 0.05 + 0.1 * k;
    char camera[64];
    snprintf(camera, sizeof camera, "{\"path_index\":%d}", k);
    tt_tuning_state st = {.struct_size = sizeof st,
                          .scene_id = "path",
                          .scene = "path.json",
                          .camera = camera,
                          .context = CONTEXT,
                          .has_indicators = 1};
    raw_state(g_t, st.indicators);
    tt_hybrid_report r = {.struct_size = sizeof r};
    CHECK(tt_hybrid_step(h, &st, &tg, &r) == TT_OK);
    CHECK(r.mode == TT_HYBRID_EXPLOIT && !r.fallback && r.builds == 1);
    used[k] = g_applied;
    /* the model's estimate and the default's cost are known for every exploited state */
    CHECK_MSG(isfinite(r.predicted_cost) && r.predicted_cost > 0, "%s, state %d: predicted %g",
              name, k, r.predicted_cost);
    CHECK_MSG(r.default_cost == 3.0 && r.default_source == TT_HYBRID_COST_NEAREST,
              "%s, state %d: default %g from %d", name, k, r.default_cost, r.default_source);
    double nearest = fmin(g_t, 1.0 - g_t) * (TRI_SCALE / 1e7); /* triangles' bound is 1e7 */
    CHECK_NEAR(r.default_distance, nearest, 1e-12);
    if (!strcmp(name, "predictor_nn")) {
      /* NN's expected cost is the mean cost of the answer in the searched state it came
       * from (1 in A and in B), never the previous exploited state's measurement */
      CHECK_MSG(r.predicted_cost == 1.0, "state %d: predicted %g", k, r.predicted_cost);
    }
  }
  tt_hybrid_destroy(h);
  pi->destroy(model);
}

int main(void) {
  g_host = *tt_default_host();
  g_host.log = quiet_log;
  /* one predictor per registry */
  tt_registry *reg = tt_registry_create(&g_host), *reg2 = tt_registry_create(&g_host);
  tt_loaded_plugin *nm = NULL, *nn = NULL, *rbf = NULL;
  if (!reg || !reg2 || tt_registry_load(reg, "tuner_nm", &nm) != TT_OK ||
      tt_registry_load(reg, "predictor_nn", &nn) != TT_OK ||
      tt_registry_load(reg2, "predictor_rbf", &rbf) != TT_OK) {
    fprintf(stderr, "cannot load the plugins: %s\n", tt_last_error());
    return 1;
  }
  g_nm = tt_loaded_plugin_iface(nm);
  tt_space *space = tt_space_create("scripted", "1.0.0");
  CHECK(tt_space_add_int(space, "c", 0, 2, 0, "configuration") == 0);

  char path[] = "/tmp/tt_hybrid_session_XXXXXX";
  int fd = mkstemp(path);
  CHECK(fd >= 0);
  close(fd);
  unlink(path);
  tt_tunedb *db = NULL;
  CHECK(tt_tunedb_open(path, &db) == TT_OK);
  /* the searched states: A (t = 0, best c = 1) and B (t = 1, best c = 2), default c = 0 */
  for (int64_t c = 0; c <= 2; c++) {
    record(db, 0.0, c, "render", CONTEXT, CAMERA);
    record(db, 1.0, c, "render", CONTEXT, CAMERA);
  }
  /* rows the warm start must leave out, and name: another objective, a wall clock and two
   * threads, another resolution */
  record(db, 0.5, 1, "build+render", CONTEXT, CAMERA);
  record(db, 0.5, 1, "render", "{\"spp\":1,\"threads\":2}", CAMERA);
  record(db, 0.5, 2, "render", "{\"spp\":1,\"threads\":2}", CAMERA);
  record(db, 0.5, 2, "render", CONTEXT, "{\"resolution\":[64,48]}");
  record(db, 0.5, 1, "render", "{\"spp\":1,\"threads\":1}", CAMERA); /* a wall clock */

  int64_t used[10];
  run_path(tt_loaded_plugin_iface(nn), "predictor_nn", space, db, used);
  for (int k = 0; k < 10; k++)
    CHECK_MSG(used[k] == (k < 5 ? 1 : 2), "NN, state %d (t = %.2f): configuration %lld", k,
              0.05 + 0.1 * k, (long long)used[k]);
  run_path(tt_loaded_plugin_iface(rbf), "predictor_rbf", space, db, used);

  /* what the warm start left out, by reason and key, with the rows' values */
  {
    tt_predictor *model = NULL;
    const tt_predictor_iface *pi = tt_loaded_plugin_iface(nn);
    tt_predictor_setup su = {.struct_size = sizeof su,
                             .target = space,
                             .state_dim = TT_SCENE_INDICATOR_COUNT,
                             .seed = 1};
    CHECK(pi->create_ex(&su, &model) == TT_OK);
    tt_hybrid_desc d;
    memset(&d, 0, sizeof d);
    d.struct_size = sizeof d;
    d.host = &g_host;
    d.space = space;
    d.tuner = g_nm;
    d.predictor = pi;
    d.model = model;
    d.explore_iterations = 1;
    d.plugin = "scripted";
    tt_hybrid *h = NULL;
    CHECK(tt_hybrid_create(&d, &h) == TT_OK);
    static const char *const keys[] = {"clock", "spp", "threads", NULL};
    static const char *const camera_keys[] = {"resolution", NULL};
    /* this run: a wall clock (no "clock" key), one thread, 24x24 */
    tt_hybrid_warm_filter f = {.struct_size = sizeof f,
                               .context_keys = keys,
                               .context = "{\"spp\":1,\"threads\":1}",
                               .camera_keys = camera_keys,
                               .camera = CAMERA};
    tt_hybrid_warm_result wr = {.struct_size = sizeof wr};
    CHECK(tt_hybrid_warm_start_ex(h, db, &f, &wr) == TT_OK);
    CHECK(wr.considered == 11 && wr.other_objective == 1 && wr.rows == 1);
    CHECK_MSG(wr.other_context == 9, "%llu", (unsigned long long)wr.other_context);
    CHECK(wr.key_count == 4 && !strcmp(wr.key[0], "clock") && !strcmp(wr.key[3], "resolution"));
    /* clock: the 7 rows of A, B and the 64x48 one were measured with "cpu" */
    CHECK(wr.mismatch[0] == 7 && !strcmp(wr.mismatch_value[0], "\"cpu\"") &&
          !strcmp(wr.expected_value[0], "(none)"));
    CHECK(wr.mismatch[1] == 0);
    CHECK(wr.mismatch[2] == 2 && !strcmp(wr.mismatch_value[2], "2") &&
          !strcmp(wr.expected_value[2], "1"));
    CHECK(wr.mismatch[3] == 1 && !strcmp(wr.mismatch_value[3], "[64,48]"));
    /* the old entry point: the same rows */
    uint64_t rows = 0, skipped = 0;
    CHECK(tt_hybrid_warm_start(h, db, &f, &rows, &skipped) == TT_OK && rows == 1 && skipped == 0);
    tt_hybrid_destroy(h);
    pi->destroy(model);
  }
  tt_tunedb_close(db);
  unlink(path);
  tt_space_destroy(space);
  tt_registry_destroy(reg);
  tt_registry_destroy(reg2);
  return tt_test_finish("hybrid_session");
}
