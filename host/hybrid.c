/* host --hybrid: hybrid online autotuning (thesis 3.3) over the scene's camera path, as
 * option mapping over the library's hybrid tuner (tunetrace/hybrid.h); host --predict: the
 * model's answer per state, nothing rendered.
 *
 * One host session (the scene is loaded once); for every path sample of --camera-index A:B (all
 * 100 by default) the camera moves, the film is cleared, and tt_hybrid_step explores (the
 * tuner, --iterations K) or exploits (the predictor's one configuration) through the same
 * target callbacks as the tuning phase: the accel is rebuilt per applied configuration and
 * one pass of --tune-spp is measured with the host's clock (--clock cpu for CPU time). The
 * state then renders up to --spp passes with its configuration (--out-dir DIR writes
 * DIR/state_NNNN.exr). --stats records every state (mode, configuration, cost, predicted
 * cost, builds, predict ms) and the totals.
 */
#define _POSIX_C_SOURCE 200809L
#include "tune.h"

#include <tt_util/clock.h>
#include <tt_util/stats.h>
#include <tt_util/strings.h>

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

typedef struct tt__hyb {
  tt__session *s;
  const tt__host_options *opt;
  tt_space *subset;
  const tt_space *space;
  size_t accel_index;
  const tt_predictor_iface *pi;
  tt_predictor *model;
  const char *predictor_name, *tuner_name;
  tt_tunedb *db;
  uint32_t spp;               /* spp of one measurement pass */
  cJSON *warm;                /* [{db, rows, skipped}] */
} tt__hyb;

/* The searched parameters (--tune-params), NULL: all of the accel's. */
static int tt__hyb_subset(tt__hyb *h) {
  const char *list = h->opt->tune_params;
  if (!list) return 0;
  const char *names[256];
  size_t n = 0;
  char buf[4096];
  snprintf(buf, sizeof buf, "%s", list);
  for (char *tok = strtok(buf, ","); tok && n < 256; tok = strtok(NULL, ",")) names[n++] = tok;
  h->subset = tt_space_subset(h->space, names, n, h->s->configs[h->accel_index]);
  if (!h->subset) {
    tt__say("--tune-params: %s\n", tt_last_error());
    return -1;
  }
  return 0;
}

/* Creates the model; loads --model FILE when it exists. Prints and returns an exit code. */
static int tt__hyb_model(tt__hyb *h, tt_loaded_plugin *pp, const tt_indicator_norm *norm) {
  tt__session *s = h->s;
  h->pi = tt_loaded_plugin_iface(pp);
  h->predictor_name = tt_loaded_plugin_entry(pp)->name;
  if (!TT_PREDICTOR_HAS(h->pi, create_ex) || !TT_PREDICTOR_HAS(h->pi, observe_ex) ||
      !TT_PREDICTOR_HAS(h->pi, predict_ex)) {
    tt__say("--hybrid: %s serves the ABI 1.0 predictor table; the hybrid loop "
            "needs ABI 1.1 (create_ex, observe_ex, predict_ex)\n", h->predictor_name);
    return TT_EXIT_PLUGIN;
  }
  static const char *names[TT_SCENE_INDICATOR_COUNT];
  for (uint32_t i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) names[i] = tt_scene_indicator_name(i);
  char id[96];
  tt_predictor_setup su;
  memset(&su, 0, sizeof su);
  su.struct_size = sizeof su;
  su.target = h->subset ? h->subset : h->space;
  su.state_dim = TT_SCENE_INDICATOR_COUNT;
  su.state_space = tt_indicator_norm_id(norm, id, sizeof id);
  su.state_names = names;
  su.settings = tt_session_config(s->lib, h->predictor_name);
  su.seed = s->rec.seed;
  if (h->pi->create_ex(&su, &h->model) != TT_OK) {
    tt__say("%s: %s\n", h->predictor_name, tt_last_error());
    h->model = NULL;
    return TT_EXIT_FAILURE;
  }
  struct stat st;
  if (h->opt->model && stat(h->opt->model, &st) == 0) {
    if (h->pi->load(h->model, h->opt->model) != TT_OK) {
      tt__say("--model %s: %s (the file is left as it is)\n", h->opt->model,
              tt_last_error());
      return TT_EXIT_USAGE;
    }
    s->host->log(TT_LOG_INFO, NULL, "hybrid: %s: loaded the model %s", h->predictor_name,
                 h->opt->model);
  }
  return TT_EXIT_OK;
}

/* --warm-start DB...: each file exists, checked before the scene loads (a typo must not
 * cost the scene's loading time). Prints and returns an exit code. */
static int tt__hyb_warm_files(const tt__host_options *opt) {
  for (int i = 0; i < opt->warm_start_count; i++) {
    struct stat st;
    if (stat(opt->warm_start[i], &st) != 0) {
      tt__say("--warm-start %s: %s\n", opt->warm_start[i], strerror(errno));
      return TT_EXIT_USAGE;
    }
  }
  return TT_EXIT_OK;
}

/* The option that sets a context or camera key, and how an absent value reads. */
static const char *tt__hyb_key_option(const char *key) {
  return !strcmp(key, "clock") ? "--clock" : !strcmp(key, "threads") ? "--threads"
         : !strcmp(key, "spp") ? "--tune-spp" : !strcmp(key, "resolution") ? "--res" : key;
}
static const char *tt__hyb_key_value(const char *key, const char *value, char *buf, size_t n) {
  unsigned w, h;
  if (!strcmp(key, "clock") && !strcmp(value, "(none)")) return "wall";
  if (!strcmp(key, "clock") && !strcmp(value, "\"cpu\"")) return "cpu";
  if (!strcmp(key, "resolution") && sscanf(value, "[%u,%u]", &w, &h) == 2) {
    snprintf(buf, n, "%ux%u", w, h);
    return buf;
  }
  return value;
}

/* Says what a warm start learnt and, for every row it did not, why: the rows of another
 * objective, and per key of the context (clock, threads, spp) and camera (resolution) the
 * rows measured otherwise, with their value and this run's. A warm start that learns
 * nothing while the database has rows is a warning. */
static void tt__hyb_warm_log(const tt__hyb *h, const char *path, const tt_hybrid_warm_result *r,
                             const char *objective) {
  char why[2048] = "";
  size_t n = 0;
#define TT__WHY(...) \
  do { \
    int w_ = snprintf(why + n, n < sizeof why ? sizeof why - n : 0, __VA_ARGS__); \
    if (w_ > 0) n += (size_t)w_; \
  } while (0)
  for (uint32_t k = 0; k < r->key_count; k++) {
    if (!r->mismatch[k]) continue;
    char a[64], b[64];
    TT__WHY("%s%llu measured with %s %s (this run: %s %s)", n ? "; " : "",
            (unsigned long long)r->mismatch[k], tt__hyb_key_option(r->key[k]),
            tt__hyb_key_value(r->key[k], r->mismatch_value[k], a, sizeof a),
            tt__hyb_key_option(r->key[k]),
            tt__hyb_key_value(r->key[k], r->expected_value[k], b, sizeof b));
  }
  if (r->other_objective)
    TT__WHY("%s%llu of another objective (this run: %s)", n ? "; " : "",
            (unsigned long long)r->other_objective, objective);
  if (r->other_space)
    TT__WHY("%s%llu of another parameter space", n ? "; " : "", (unsigned long long)r->other_space);
  if (r->failed) TT__WHY("%s%llu failed measurements", n ? "; " : "", (unsigned long long)r->failed);
  if (r->no_indicators)
    TT__WHY("%s%llu without indicators", n ? "; " : "", (unsigned long long)r->no_indicators);
#undef TT__WHY
  uint64_t left = r->considered - r->rows;
  int none = r->rows == 0 && r->considered > 0;
  h->s->host->log(none ? TT_LOG_WARN : TT_LOG_INFO, NULL, "hybrid: %s learnt %llu of the %llu "
                  "rows of %s in %s%s%s%s", h->predictor_name, (unsigned long long)r->rows,
                  (unsigned long long)r->considered, tt_loaded_plugin_entry(h->s->accel_p)->name,
                  path, left ? "; left out: " : "", left ? why : "",
                  none && r->other_context ? " (a warm start learns only costs measured as this "
                  "run measures them: match those options, see host/README.md)" : "");
}

/* --warm-start DB...: every usable row teaches the model; the clock, spp and threads of the
 * rows' context and the resolution of their camera must be this run's. */
static int tt__hyb_warm(tt__hyb *h, tt_hybrid *hy, const char *context, const char *camera,
                        const char *objective) {
  static const char *const keys[] = {"clock", "spp", "threads", NULL};
  static const char *const camera_keys[] = {"resolution", NULL};
  h->warm = cJSON_CreateArray();
  for (int i = 0; i < h->opt->warm_start_count; i++) {
    const char *path = h->opt->warm_start[i];
    tt_tunedb *db = NULL;
    if (tt_tunedb_open_readonly(path, &db) != TT_OK) {
      tt__say("--warm-start %s: %s\n", path, tt_last_error());
      return TT_EXIT_USAGE;
    }
    tt_hybrid_warm_filter f = {.struct_size = sizeof f, .context_keys = keys, .context = context,
                               .camera_keys = camera_keys, .camera = camera};
    tt_hybrid_warm_result r = {.struct_size = sizeof r};
    tt_status ws = tt_hybrid_warm_start_ex(hy, db, &f, &r);
    tt_tunedb_close(db);
    if (ws != TT_OK) {
      tt__say("--warm-start %s: %s\n", path, tt_last_error());
      return TT_EXIT_FAILURE;
    }
    tt__hyb_warm_log(h, path, &r, objective);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "db", path);
    cJSON_AddNumberToObject(o, "rows", (double)r.rows);
    cJSON_AddNumberToObject(o, "skipped", (double)(r.considered - r.rows));
    cJSON_AddNumberToObject(o, "considered", (double)r.considered);
    cJSON_AddNumberToObject(o, "exploit_rows", (double)r.exploit_rows);
    cJSON *why = cJSON_AddObjectToObject(o, "skipped_because");
    cJSON_AddNumberToObject(why, "other_objective", (double)r.other_objective);
    cJSON_AddNumberToObject(why, "other_space", (double)r.other_space);
    cJSON_AddNumberToObject(why, "failed", (double)r.failed);
    cJSON_AddNumberToObject(why, "no_indicators", (double)r.no_indicators);
    cJSON_AddNumberToObject(why, "other_context", (double)r.other_context);
    cJSON *keys_o = cJSON_AddObjectToObject(o, "mismatch");
    for (uint32_t k = 0; k < r.key_count; k++) {
      cJSON *m = cJSON_AddObjectToObject(keys_o, r.key[k]);
      cJSON_AddNumberToObject(m, "rows", (double)r.mismatch[k]);
      cJSON *v = r.mismatch[k] ? cJSON_Parse(r.mismatch_value[k]) : NULL;
      cJSON_AddItemToObject(m, "value", v ? v : cJSON_CreateNull());
      cJSON *e = cJSON_Parse(r.expected_value[k]);
      cJSON_AddItemToObject(m, "this_run", e ? e : cJSON_CreateNull());
    }
    cJSON_AddItemToArray(h->warm, o);
  }
  return TT_EXIT_OK;
}

/* Writes `root` to `path` atomically (tunetrace/file.h). */
static int tt__hyb_write_json(const char *path, cJSON *root) {
  char *text = cJSON_Print(root);
  tt_status st = text ? tt_file_write_atomic(path, text, strlen(text)) : TT_ERR_OUT_OF_MEMORY;
  cJSON_free(text);
  if (st != TT_OK) {
    tt__say("--stats %s: %s\n", path, tt_last_error());
    return TT_EXIT_OUTPUT;
  }
  return TT_EXIT_OK;
}

/* The report of one state as JSON. */
static cJSON *tt__hyb_state_json(const tt_hybrid_report *r, uint32_t path_index, double total_ms,
                                 uint32_t passes) {
  cJSON *o = cJSON_CreateObject();
  cJSON_AddNumberToObject(o, "state", r->state_index);
  cJSON_AddNumberToObject(o, "path_index", path_index);
  cJSON_AddStringToObject(o, "mode", r->mode == TT_HYBRID_EXPLORE ? "explore" : "exploit");
  cJSON_AddBoolToObject(o, "fallback", r->fallback != 0);
  cJSON *cfg = r->config ? cJSON_Parse(r->config) : NULL;
  cJSON_AddItemToObject(o, "config", cfg ? cfg : cJSON_CreateNull());
  const struct { const char *name; double v; } num[] = {
    {"cost", r->cost}, {"predicted_cost", r->predicted_cost}, {"default_cost", r->default_cost},
    {"default_distance", r->default_distance},
    {"search_cost", r->search_cost}, {"predict_ms", r->predict_ms}, {"total_ms", total_ms}};
  for (size_t i = 0; i < sizeof num / sizeof num[0]; i++) {
    if (isfinite(num[i].v) && num[i].v < TT_COST_INFEASIBLE) cJSON_AddNumberToObject(o, num[i].name, num[i].v);
    else cJSON_AddNullToObject(o, num[i].name);
  }
  static const char *const from[] = {NULL, "measured", "database", "nearest state"};
  if (r->default_source > 0 && r->default_source <= 3)
    cJSON_AddStringToObject(o, "default_cost_from", from[r->default_source]);
  else
    cJSON_AddNullToObject(o, "default_cost_from");
  cJSON_AddNumberToObject(o, "remeasured", r->remeasured);
  cJSON_AddNumberToObject(o, "samples", r->samples);
  cJSON_AddNumberToObject(o, "builds", r->builds);
  cJSON_AddNumberToObject(o, "cached", r->cached);
  cJSON_AddNumberToObject(o, "passes", passes);
  cJSON *st = cJSON_AddArrayToObject(o, "indicators");
  for (int i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) cJSON_AddItemToArray(st, cJSON_CreateNumber(r->state[i]));
  return o;
}

/* Moves the camera to path sample `i` (t = first key + i/99 of the time range; the motion
 * AOV's previous frame one --fps interval earlier). */
static void tt__hyb_camera(tt__session *s, uint32_t i) {
  const tt_camera *c0 = tt_scene_camera(s->scene);
  double t = c0->keys[0].time + (c0->keys[c0->key_count - 1].time - c0->keys[0].time) *
                                    (double)i / (TT_HOST_PATH_SAMPLES - 1.0);
  tt_session_set_camera_time(s->lib, t, 1.0 / (s->opt->fps > 0 ? s->opt->fps : 24.0));
}

/* --states FILE: [{"id": ..., "indicators": {name: raw value}}, ...]; NULL (printed) on error. */
static cJSON *tt__hyb_read_states(const char *path) {
  char *text = NULL;
  size_t n = 0;
  if (tt_file_read(path, "states file", 0, &text, &n) != TT_OK) {
    tt__say("--states %s\n", tt_last_error());
    return NULL;
  }
  cJSON *root = cJSON_Parse(text);
  tt_free(text);
  int ok = cJSON_IsArray(root);
  for (int i = 0; ok && i < cJSON_GetArraySize(root); i++) {
    cJSON *ind = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(root, i), "indicators");
    for (uint32_t k = 0; ok && k < TT_SCENE_INDICATOR_COUNT; k++) {
      cJSON *v = cJSON_GetObjectItemCaseSensitive(ind, tt_scene_indicator_name(k));
      if (!cJSON_IsNumber(v)) {
        tt__say("--states %s: [%d].indicators.%s: expected a number\n", path, i,
                tt_scene_indicator_name(k));
        ok = 0;
      }
    }
  }
  if (!cJSON_IsArray(root)) tt__say("--states %s: expected a JSON array of states\n", path);
  if (!ok) {
    cJSON_Delete(root);
    return NULL;
  }
  return root;
}

/* --predict: the model's answer for every state as JSON on stdout. */
static int tt__hyb_predict(tt__hyb *h, const tt_indicator_norm *norm, uint32_t first, uint32_t end) {
  tt__session *s = h->s;
  cJSON *root = cJSON_CreateObject(), *arr = cJSON_AddArrayToObject(root, "predictions");
  cJSON_AddStringToObject(root, "scene", s->opt->scene);
  cJSON_AddStringToObject(root, "scene_id", tt_scene_id(s->scene));
  cJSON_AddStringToObject(root, "predictor", h->predictor_name);
  tt_predictor_info info = {.struct_size = sizeof info};
  if (TT_PREDICTOR_HAS(h->pi, info) && h->pi->info(h->model, &info) == TT_OK) {
    cJSON_AddNumberToObject(root, "memory_bytes", (double)info.memory_bytes);
    cJSON_AddNumberToObject(root, "entries", (double)info.entries);
    cJSON_AddNumberToObject(root, "observations", (double)info.observations);
  }
  if (h->warm) cJSON_AddItemToObject(root, "warm_start", h->warm), h->warm = NULL;
  tt_config *sub = tt_config_create(h->subset ? h->subset : h->space);
  tt_config *full = tt_config_create(h->space);
  int rc = TT_EXIT_OK;
  cJSON *given = NULL;
  if (h->opt->states) {
    given = tt__hyb_read_states(h->opt->states);
    if (!given) rc = TT_EXIT_USAGE;
    first = 0;
    end = given ? (uint32_t)cJSON_GetArraySize(given) : 0;
  }
  for (uint32_t i = first; i < end && sub && full; i++) {
    double raw[TT_SCENE_INDICATOR_COUNT], state[TT_SCENE_INDICATOR_COUNT];
    cJSON *item = given ? cJSON_GetArrayItem(given, (int)i) : NULL;
    if (item) {
      cJSON *ind = cJSON_GetObjectItemCaseSensitive(item, "indicators");
      for (uint32_t k = 0; k < TT_SCENE_INDICATOR_COUNT; k++)
        raw[k] = cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(ind, tt_scene_indicator_name(k)));
    } else {
      tt__hyb_camera(s, i);
      tt_scene_indicators(s->scene, raw);
    }
    tt_indicators_normalize(norm, raw, state);
    tt_predictor_query q = {.struct_size = sizeof q, .state = state, .default_cost = NAN};
    tt_predictor_result r = {.struct_size = sizeof r};
    /* median of 5 calls: predict() must stay far below one frame (issue goal: < 1%) */
    double ms[5];
    tt_status st = TT_OK;
    for (int k = 0; k < 5 && st == TT_OK; k++) {
      double t0 = tt__thread_cpu_ms();
      st = h->pi->predict_ex(h->model, &q, sub, &r);
      ms[k] = tt__thread_cpu_ms() - t0;
    }
    cJSON *o = cJSON_CreateObject();
    cJSON *id = item ? cJSON_GetObjectItemCaseSensitive(item, "id") : NULL;
    if (id) cJSON_AddItemToObject(o, "id", cJSON_Duplicate(id, 1));
    else cJSON_AddNumberToObject(o, "path_index", i);
    if (st != TT_OK) {
      cJSON_AddStringToObject(o, "error", tt_last_error());
      if (st != TT_ERR_NO_DATA) rc = TT_EXIT_FAILURE;
    } else {
      tt_config_copy(full, s->configs[h->accel_index]);
      if (h->subset) tt_config_assign(full, sub);
      else tt_config_copy(full, sub);
      char *j = tt_config_to_json(full);
      cJSON *cfg = j ? cJSON_Parse(j) : NULL;
      tt_free(j);
      cJSON_AddItemToObject(o, "config", cfg ? cfg : cJSON_CreateNull());
      if (isfinite(r.expected_cost)) cJSON_AddNumberToObject(o, "expected_cost", r.expected_cost);
      else cJSON_AddNullToObject(o, "expected_cost");
      if (isfinite(r.value)) cJSON_AddNumberToObject(o, "value", r.value);
      if (isfinite(r.distance)) cJSON_AddNumberToObject(o, "distance", r.distance);
      cJSON_AddNumberToObject(o, "candidates", (double)r.candidates);
      cJSON_AddNumberToObject(o, "predict_ms", tt__median(ms, 5));
    }
    cJSON_AddItemToArray(arr, o);
  }
  tt_config_destroy(sub);
  tt_config_destroy(full);
  cJSON_Delete(given);
  if (rc == TT_EXIT_USAGE) {
    cJSON_Delete(root);
    return rc;
  }
  char *text = cJSON_Print(root);
  cJSON_Delete(root);
  if (!text || puts(text) < 0 || fflush(stdout)) rc = TT_EXIT_OUTPUT;
  cJSON_free(text);
  return rc;
}

/* Writes the film as DIR/state_NNNN.exr and its display preview DIR/state_NNNN.png (as a
 * still render writes both). */
static void tt__hyb_write_state(tt__hyb *h, uint32_t index) {
  tt__session *s = h->s;
  uint32_t w = s->camera->width, hh = s->camera->height;
  float *px = malloc((size_t)w * hh * 3 * sizeof *px);
  char path[4200], png[4200];
  snprintf(path, sizeof path, "%s/state_%04u.exr", h->opt->out_dir, index);
  snprintf(png, sizeof png, "%s/state_%04u.png", h->opt->out_dir, index);
  if (px) tt_film_resolve(s->film, px);
  if (!px || tt_image_write_exr(path, w, hh, 3, px, NULL, NULL, 0) != TT_OK)
    s->host->log(TT_LOG_WARN, NULL, "hybrid: cannot write %s: %s", path, tt_last_error());
  else if (tt_image_write_png_display(png, w, hh, px, 0.0f, NULL, 0) != TT_OK)
    s->host->log(TT_LOG_WARN, NULL, "hybrid: cannot write %s: %s", png, tt_last_error());
  free(px);
}

int tt__run_hybrid(const tt__host_options *opt) {
  tt__install_signals("pass");
  tt__session s;
  tt__hyb h;
  memset(&h, 0, sizeof h);
  h.s = &s;
  h.opt = opt;
  h.spp = opt->tune_spp ? opt->tune_spp : 1;
  tt_hybrid *hy = NULL;
  cJSON *states = NULL;
  char *context = NULL, *camera0 = NULL;
  memset(&s, 0, sizeof s);
  int rc = tt__hyb_warm_files(opt);
  if (rc != TT_EXIT_OK) return rc;
  rc = tt__session_open(&s, opt);
  if (rc != TT_EXIT_OK) goto done;
  const tt_camera *cam = tt_scene_camera(s.scene);
  if (cam->key_count < 1 && !(opt->predict_only && opt->states)) {
    tt__say("--%s: %s has no camera path (camera.path in scene.json): the hybrid "
            "loop moves through the path's states\n", opt->hybrid ? "hybrid" : "predict", opt->scene);
    rc = TT_EXIT_USAGE;
    goto done;
  }
  if (opt->tune && strcmp(opt->tune, tt_loaded_plugin_entry(s.accel_p)->name)) {
    tt__say("--hybrid tunes the accel (%s), not --tune %s\n",
            tt_loaded_plugin_entry(s.accel_p)->name, opt->tune);
    rc = TT_EXIT_USAGE;
    goto done;
  }
  if (opt->explore || opt->verify || opt->reference || (opt->states && opt->camera_index_set)) {
    tt__say("--%s: %s does not apply (the states are the path samples of "
            "--camera-index A:B)\n", opt->hybrid ? "hybrid" : "predict",
            opt->explore ? "--explore" : opt->verify ? "--verify"
            : opt->reference ? "--reference" : "--camera-index with --states");
    rc = TT_EXIT_USAGE;
    goto done;
  }
  tt_indicator_norm norm;
  tt_indicator_norm_init(&norm);
  if (opt->indicator_norm) tt_indicator_norm_parse(opt->indicator_norm, &norm);  /* checked */
  tt_objective obj;
  const char *spec = opt->objective ? opt->objective : "render";
  if (tt__parse_objective("--objective", spec, &obj)) {
    rc = TT_EXIT_USAGE;
    goto done;
  }
  if (obj.kind != TT_OBJECTIVE_RENDER && obj.kind != TT_OBJECTIVE_TOTAL && obj.kind != TT_OBJECTIVE_BUILD) {
    tt__say("--hybrid: --objective %s: the hybrid loop tunes the accel for time "
            "(render, build+render, build)\n", spec);
    rc = TT_EXIT_USAGE;
    goto done;
  }
  /* the session loaded tuner_nm and predictor_nn unless --plugin named others */
  tt_loaded_plugin *tp = tt_registry_find_kind(s.reg, TT_KIND_TUNER);
  tt_loaded_plugin *pp = tt_registry_find_kind(s.reg, TT_KIND_PREDICTOR);
  h.tuner_name = tt_loaded_plugin_entry(tp)->name;
  h.accel_index = (size_t)tt_session_plugin_index(s.lib, tt_loaded_plugin_entry(s.accel_p)->name);
  h.space = tt_loaded_plugin_space(s.accel_p);
  if (tt__hyb_subset(&h)) {
    rc = TT_EXIT_USAGE;
    goto done;
  }
  rc = tt__hyb_model(&h, pp, &norm);
  if (rc != TT_EXIT_OK) goto done;
  if (!opt->no_db) {
    char *path = opt->db ? tt__strdup(opt->db) : tt_tunedb_default_path();
    if (path && tt_tunedb_open(path, &h.db) != TT_OK) {
      tt__say("--db %s: %s\n", path, tt_last_error());
      free(path);
      rc = TT_EXIT_FAILURE;
      goto done;
    }
    free(path);
  }
  /* the state's context: as the tuning phase's (spp, threads, the other plugins), plus the
   * clock; the camera gets "path_index" per state */
  const char *context_extra = opt->clock_cpu ? "{\"clock\":\"cpu\"}" : NULL;
  tt_tuning_state st0;
  if (tt_session_tuning_state(s.lib, h.accel_index, h.spp, NULL, context_extra, 0, &st0) == TT_OK) {
    context = tt__strdup(st0.context);
    camera0 = tt__strdup(st0.camera);
  }
  const tt_plugin *ae = tt_loaded_plugin_entry(s.accel_p);
  tt_hybrid_desc d;
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.host = s.host;
  d.space = h.space;
  d.start = s.configs[h.accel_index];
  d.search = h.subset;
  d.objective = obj.spec;
  d.tuner = tt_loaded_plugin_iface(tp);
  d.tuner_settings = tt_session_config(s.lib, h.tuner_name);
  d.tuner_name = h.tuner_name;
  d.predictor = h.pi;
  d.model = h.model;
  d.predictor_name = h.predictor_name;
  d.epsilon = opt->epsilon_set ? opt->epsilon : TT_HOST_DEFAULT_EPSILON;
  d.explore_iterations = opt->iterations ? opt->iterations : TT_HOST_DEFAULT_HYBRID_ITERATIONS;
  d.spp = h.spp;
  d.warmup_passes = 1;
  d.seed = s.rec.seed;
  d.plugin = ae->name;
  d.plugin_version = ae->version;
  d.db = h.db;
  d.norm = &norm;
  if (!context || !camera0 || tt_hybrid_create(&d, &hy) != TT_OK) {
    tt__say("--hybrid: %s\n", context ? tt_last_error() : "out of memory");
    rc = TT_EXIT_FAILURE;
    goto done;
  }
  rc = tt__hyb_warm(&h, hy, context, camera0, obj.spec);
  if (rc != TT_EXIT_OK) goto done;
  /* --camera-index A:B (or I): path samples A..B, both included; default all of them */
  uint32_t first = opt->camera_index_set ? opt->camera_index : 0;
  uint32_t end = opt->camera_index_set ? opt->camera_index_last + 1 : TT_HOST_PATH_SAMPLES;
  if (opt->predict_only) {
    rc = tt__hyb_predict(&h, &norm, first, end);
    /* what a warm start taught the model is kept (--model FILE: saved atomically) */
    if (rc == TT_EXIT_OK && opt->model && opt->warm_start_count &&
        h.pi->save(h.model, opt->model) != TT_OK) {
      tt__say("--model %s: %s\n", opt->model, tt_last_error());
      rc = TT_EXIT_OUTPUT;
    }
    goto done;
  }
  if (opt->out_dir && mkdir(opt->out_dir, 0777) != 0 && errno != EEXIST) {
    tt__say("--out-dir %s: %s\n", opt->out_dir, strerror(errno));
    rc = TT_EXIT_OUTPUT;
    goto done;
  }
  rc = tt__session_start(&s, 0);
  if (rc != TT_EXIT_OK) goto done;
  s.host->log(TT_LOG_INFO, NULL, "hybrid: %s states %u..%u, epsilon %g, explore %s for %u "
              "iterations, exploit %s, objective %s, database %s", opt->scene, first, end - 1,
              d.epsilon, h.tuner_name, d.explore_iterations, h.predictor_name, obj.spec,
              h.db ? tt_tunedb_path(h.db) : "none");
  states = cJSON_CreateArray();
  tt_tuning_target target;
  if (tt_session_tuning_target(s.lib, h.accel_index, 0, &target) != TT_OK) {
    tt__say("--hybrid: %s\n", tt_last_error());
    rc = TT_EXIT_FAILURE;
    goto done;
  }
  uint32_t target_spp = opt->spp ? opt->spp : 1;
  double sum_cost = 0, sum_search = 0;
  uint32_t explored = 0, exploited = 0, builds = 0, done_states = 0, remeasured = 0, cached = 0;
  uint32_t samples = 0;
  int interrupted = 0;
  for (uint32_t i = first; i < end; i++) {
    tt__hyb_camera(&s, i);
    tt_session_reset(s.lib);  /* a new view: the film starts over */
    tt_session_stats ss = {.struct_size = sizeof ss};
    tt_session_get_stats(s.lib, &ss);
    uint32_t pass0 = ss.passes;
    char camera_extra[48];
    snprintf(camera_extra, sizeof camera_extra, "{\"path_index\":%u}", i);
    tt_tuning_state state;
    if (tt_session_tuning_state(s.lib, h.accel_index, h.spp, camera_extra, context_extra, 1,
                                &state) != TT_OK) {
      tt__say("--hybrid: state %u: %s\n", i, tt_last_error());
      rc = TT_EXIT_FAILURE;
      break;
    }
    uint64_t t0 = s.host->clock_ns();
    tt_hybrid_report r = {.struct_size = sizeof r};
    tt_status st = tt_hybrid_step(hy, &state, &target, &r);
    if (st == TT_ERR_INTERRUPTED) {
      interrupted = 1;
      break;
    }
    if (st != TT_OK) {
      tt__say("--hybrid: state %u: %s\n", i, tt_last_error());
      rc = TT_EXIT_FAILURE;
      break;
    }
    /* the rest of the state's samples with its configuration (progressive rendering) */
    for (;;) {
      tt_session_get_stats(s.lib, &ss);
      if ((ss.passes - pass0) * h.spp >= target_spp || s.host->should_stop()) break;
      double ms;
      tt_pass_stats ps;
      if (tt__session_render_pass(&s, 1, &ps, &ms) != TT_OK) break;
    }
    tt_session_get_stats(s.lib, &ss);
    double total_ms = (s.host->clock_ns() - t0) * 1e-6;
    if (opt->out_dir) tt__hyb_write_state(&h, i);
    cJSON_AddItemToArray(states, tt__hyb_state_json(&r, i, total_ms, ss.passes - pass0));
    done_states++;
    explored += r.mode == TT_HYBRID_EXPLORE;
    exploited += r.mode == TT_HYBRID_EXPLOIT;
    builds += r.builds;
    remeasured += r.remeasured;
    cached += r.cached;
    samples += r.samples;
    if (r.cost < TT_COST_INFEASIBLE) sum_cost += r.cost;
    sum_search += r.search_cost;
    if (!opt->quiet) {
      /* what the state cost, what the model expected and the default's cost beside it */
      char cmp[160] = "";
      size_t n = 0;
      if (isfinite(r.predicted_cost))
        n += (size_t)snprintf(cmp, sizeof cmp, ", the model expected %.4g", r.predicted_cost);
      if (isfinite(r.default_cost) && !r.fallback && n < sizeof cmp)
        snprintf(cmp + n, sizeof cmp - n, ", default %s%.4g%s",
                 r.default_source == TT_HYBRID_COST_NEAREST ? "~" : "", r.default_cost,
                 r.default_source == TT_HYBRID_COST_NEAREST ? " (nearest measured state)"
                 : r.default_source == TT_HYBRID_COST_DATABASE ? " (database)" : "");
      s.host->log(TT_LOG_INFO, NULL, "hybrid: state %u (path %u): %s%s, cost %.4g%s, %u "
                  "build%s", r.state_index, i, r.mode == TT_HYBRID_EXPLORE ? "explore" : "exploit",
                  r.fallback ? " (default: no usable prediction)" : "", r.cost, cmp, r.builds,
                  r.builds == 1 ? "" : "s");
    }
    tt__progress_update("hybrid", (double)(i + 1 - first) / (end - first));
    if (s.host->should_stop()) {
      interrupted = 1;
      break;
    }
  }
  tt__progress_finish();
  /* said once per run, not per state */
  if (cached)
    s.host->log(TT_LOG_INFO, NULL, "hybrid: %u of %u costs came from the database %s (earlier "
                "runs measured those configurations in the same state)", cached, samples,
                tt_tunedb_path(h.db));
  if (remeasured)
    s.host->log(TT_LOG_INFO, NULL, "hybrid: %u of %u samples measured again a configuration "
                "already measured in their state (%s re-evaluating its best against noise)",
                remeasured, samples, h.tuner_name);
  if (opt->model && (rc == TT_EXIT_OK)) {
    if (h.pi->save(h.model, opt->model) != TT_OK) {
      tt__say("--model %s: %s\n", opt->model, tt_last_error());
      rc = TT_EXIT_OUTPUT;
    }
  }
  if (opt->stats) {
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "scene", opt->scene);
    cJSON_AddStringToObject(root, "scene_id", tt_scene_id(s.scene));
    cJSON_AddStringToObject(root, "clock", opt->clock_cpu ? "cpu" : "wall");
    cJSON_AddNumberToObject(root, "threads", s.rec.threads);
    cJSON_AddNumberToObject(root, "seed", (double)s.rec.seed);
    cJSON *hj = cJSON_AddObjectToObject(root, "hybrid");
    cJSON_AddStringToObject(hj, "predictor", h.predictor_name);
    cJSON_AddStringToObject(hj, "tuner", h.tuner_name);
    cJSON_AddNumberToObject(hj, "epsilon", d.epsilon);
    cJSON_AddNumberToObject(hj, "explore_iterations", d.explore_iterations);
    cJSON_AddStringToObject(hj, "objective", obj.spec);
    char id[96];
    cJSON_AddStringToObject(hj, "state_space", tt_indicator_norm_id(&norm, id, sizeof id));
    if (opt->model) cJSON_AddStringToObject(hj, "model", opt->model);
    else cJSON_AddNullToObject(hj, "model");
    if (h.db) cJSON_AddStringToObject(hj, "db", tt_tunedb_path(h.db));
    else cJSON_AddNullToObject(hj, "db");
    cJSON_AddItemToObject(hj, "warm_start", h.warm ? h.warm : cJSON_CreateArray());
    h.warm = NULL;
    cJSON_AddNumberToObject(hj, "states_done", done_states);
    cJSON_AddNumberToObject(hj, "explored", explored);
    cJSON_AddNumberToObject(hj, "exploited", exploited);
    cJSON_AddNumberToObject(hj, "builds", builds);
    cJSON_AddNumberToObject(hj, "sum_cost", sum_cost);
    cJSON_AddNumberToObject(hj, "sum_search_cost", sum_search);
    cJSON_AddBoolToObject(hj, "interrupted", interrupted);
    cJSON_AddItemToObject(hj, "states", states);
    states = NULL;
    int wrc = tt__hyb_write_json(opt->stats, root);
    cJSON_Delete(root);
    if (wrc != TT_EXIT_OK && rc == TT_EXIT_OK) rc = wrc;
  }
  if (interrupted && rc == TT_EXIT_OK) rc = TT_EXIT_INTERRUPTED;

done:
  cJSON_Delete(states);
  cJSON_Delete(h.warm);
  free(context);
  free(camera0);
  tt_hybrid_destroy(hy);
  if (h.model) h.pi->destroy(h.model);
  tt_space_destroy(h.subset);
  tt_tunedb_close(h.db);
  tt__session_close(&s);
  return rc;
}
