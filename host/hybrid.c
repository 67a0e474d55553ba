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
#include "hybrid_shared.h"
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

const char *const tt__hyb_context_keys[] = {"clock", "spp", "threads", "measure", NULL};
const char *const tt__hyb_camera_keys[] = {"resolution", NULL};

/* The hybrid job (--hybrid, --predict): the host session, the library's hybrid tuner with
 * its model, tuner and database, and what the states measured. tt__hyb_close frees what it
 * holds at any stage. */
typedef struct tt__hyb_totals {
  uint32_t states, explored, exploited, builds, remeasured, cached, samples;
  double sum_cost, sum_search;
} tt__hyb_totals;

typedef struct tt__hyb {
  tt__session s;
  const tt__host_options *opt;
  tt_space *subset;
  const tt_space *space;
  size_t accel_index;
  const tt_predictor_iface *pi;
  tt_predictor *model;
  const char *predictor_name, *tuner_name;
  tt_tunedb *db;
  uint32_t spp;           /* spp of one measurement pass */
  cJSON *warm;            /* [{db, rows, skipped}] */
  tt_indicator_norm norm; /* the state space (--indicator-norm) */
  tt_objective obj;
  const char *context_extra; /* the clock, besides the library's context */
  char *context, *camera0;   /* the state's context and first camera (warm-start filter) */
  double epsilon;
  uint32_t explore_iterations;
  tt_hybrid *hy;
  tt_tuning_target target; /* the render session as the tuning target */
  uint32_t first, end;     /* path samples first..end-1 (--camera-index A:B) */
  cJSON *states;           /* the report of every state done */
  tt__hyb_totals tot;
  int interrupted;
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
  h->subset = tt_space_subset(h->space, names, n, h->s.configs[h->accel_index]);
  if (!h->subset) {
    tt__say("--tune-params: %s\n", tt_last_error());
    return -1;
  }
  return 0;
}

/* Creates the model over the searched parameters; loads --model FILE when it exists. */
static int tt__hyb_model(tt__hyb *h, tt_loaded_plugin *pp) {
  h->predictor_name = tt_loaded_plugin_entry(pp)->name;
  return tt__hyb_model_create(h->s.lib, h->s.host, pp, h->subset ? h->subset : h->space, &h->norm,
                              h->s.rec.seed, h->opt->model, &h->pi, &h->model);
}

int tt__hyb_model_create(tt_session *lib, const tt_host *host, tt_loaded_plugin *pp,
                         const tt_space *target, const tt_indicator_norm *norm, uint64_t seed,
                         const char *model_path, const tt_predictor_iface **pi_out,
                         tt_predictor **model) {
  const tt_predictor_iface *pi = *pi_out = tt_loaded_plugin_iface(pp);
  const char *name = tt_loaded_plugin_entry(pp)->name;
  *model = NULL;
  if (!TT_PREDICTOR_HAS(pi, create_ex) || !TT_PREDICTOR_HAS(pi, observe_ex) ||
      !TT_PREDICTOR_HAS(pi, predict_ex)) {
    tt__say("--hybrid: %s serves the ABI 1.0 predictor table; the hybrid loop "
            "needs ABI 1.1 (create_ex, observe_ex, predict_ex)\n",
            name);
    return TT_EXIT_PLUGIN;
  }
  static const char *names[TT_SCENE_INDICATOR_COUNT];
  for (uint32_t i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) names[i] = tt_scene_indicator_name(i);
  char id[96];
  tt_predictor_setup su;
  memset(&su, 0, sizeof su);
  su.struct_size = sizeof su;
  su.target = target;
  su.state_dim = TT_SCENE_INDICATOR_COUNT;
  su.state_space = tt_indicator_norm_id(norm, id, sizeof id);
  su.state_names = names;
  su.settings = tt_session_config(lib, name);
  su.seed = seed;
  if (pi->create_ex(&su, model) != TT_OK) {
    tt__say("%s: %s\n", name, tt_last_error());
    *model = NULL;
    return TT_EXIT_FAILURE;
  }
  struct stat st;
  if (model_path && stat(model_path, &st) == 0) {
    if (pi->load(*model, model_path) != TT_OK) {
      tt__say("--model %s: %s (the file is left as it is)\n", model_path, tt_last_error());
      return TT_EXIT_USAGE;
    }
    host->log(TT_LOG_INFO, NULL, "hybrid: %s: loaded the model %s", name, model_path);
  }
  return TT_EXIT_OK;
}

/* --warm-start DB...: each file exists, checked before the scene loads (a typo must not
 * cost the scene's loading time). Prints and returns an exit code. */
int tt__hyb_warm_files(const tt__host_options *opt) {
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
  return !strcmp(key, "clock")        ? "--clock"
         : !strcmp(key, "threads")    ? "--threads"
         : !strcmp(key, "spp")        ? "--tune-spp"
         : !strcmp(key, "resolution") ? "--res"
                                      : key;
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
static void tt__hyb_warm_log(const tt__hyb_warm_args *a, const char *path,
                             const tt_hybrid_warm_result *r) {
  const char *objective = a->objective;
  char why[2048] = "";
  size_t n = 0;
#define TT__WHY(...)                                                                               \
  do {                                                                                             \
    int w_ = snprintf(why + n, n < sizeof why ? sizeof why - n : 0, __VA_ARGS__);                  \
    if (w_ > 0) n += (size_t)w_;                                                                   \
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
  if (r->failed)
    TT__WHY("%s%llu failed measurements", n ? "; " : "", (unsigned long long)r->failed);
  if (r->no_indicators)
    TT__WHY("%s%llu without indicators", n ? "; " : "", (unsigned long long)r->no_indicators);
#undef TT__WHY
  uint64_t left = r->considered - r->rows;
  int none = r->rows == 0 && r->considered > 0;
  a->host->log(none ? TT_LOG_WARN : TT_LOG_INFO, NULL,
               "hybrid: %s learnt %llu of the %llu "
               "rows of %s in %s%s%s%s",
               a->predictor_name, (unsigned long long)r->rows, (unsigned long long)r->considered,
               a->accel_name, path, left ? "; left out: " : "", left ? why : "",
               none && r->other_context
                   ? " (a warm start learns only costs measured as this "
                     "run measures them: match those options, see host/README.md)"
                   : "");
}

/* What a warm start from `path` learnt and left out, for --stats. */
static cJSON *tt__hyb_warm_json(const char *path, const tt_hybrid_warm_result *r) {
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "db", path);
  cJSON_AddNumberToObject(o, "rows", (double)r->rows);
  cJSON_AddNumberToObject(o, "skipped", (double)(r->considered - r->rows));
  cJSON_AddNumberToObject(o, "considered", (double)r->considered);
  cJSON_AddNumberToObject(o, "exploit_rows", (double)r->exploit_rows);
  cJSON *why = cJSON_AddObjectToObject(o, "skipped_because");
  cJSON_AddNumberToObject(why, "other_objective", (double)r->other_objective);
  cJSON_AddNumberToObject(why, "other_space", (double)r->other_space);
  cJSON_AddNumberToObject(why, "failed", (double)r->failed);
  cJSON_AddNumberToObject(why, "no_indicators", (double)r->no_indicators);
  cJSON_AddNumberToObject(why, "other_context", (double)r->other_context);
  cJSON *keys_o = cJSON_AddObjectToObject(o, "mismatch");
  for (uint32_t k = 0; k < r->key_count; k++) {
    cJSON *m = cJSON_AddObjectToObject(keys_o, r->key[k]);
    cJSON_AddNumberToObject(m, "rows", (double)r->mismatch[k]);
    cJSON *v = r->mismatch[k] ? cJSON_Parse(r->mismatch_value[k]) : NULL;
    cJSON_AddItemToObject(m, "value", v ? v : cJSON_CreateNull());
    cJSON *e = cJSON_Parse(r->expected_value[k]);
    cJSON_AddItemToObject(m, "this_run", e ? e : cJSON_CreateNull());
  }
  return o;
}

int tt__hyb_warm_all(const tt__hyb_warm_args *a, tt_hybrid *hy, cJSON **out) {
  cJSON *warm = *out = cJSON_CreateArray();
  for (int i = 0; i < a->opt->warm_start_count; i++) {
    const char *path = a->opt->warm_start[i];
    tt_tunedb *db = NULL;
    if (tt_tunedb_open_readonly(path, &db) != TT_OK) {
      tt__say("--warm-start %s: %s\n", path, tt_last_error());
      return TT_EXIT_USAGE;
    }
    tt_hybrid_warm_filter f = {.struct_size = sizeof f,
                               .context_keys = tt__hyb_context_keys,
                               .context = a->context,
                               .camera_keys = tt__hyb_camera_keys,
                               .camera = a->camera};
    tt_hybrid_warm_result r = {.struct_size = sizeof r};
    tt_status ws = tt_hybrid_warm_start_ex(hy, db, &f, &r);
    tt_tunedb_close(db);
    if (ws != TT_OK) {
      tt__say("--warm-start %s: %s\n", path, tt_last_error());
      return TT_EXIT_FAILURE;
    }
    tt__hyb_warm_log(a, path, &r);
    cJSON_AddItemToArray(warm, tt__hyb_warm_json(path, &r));
  }
  return TT_EXIT_OK;
}

/* --warm-start DB...: every usable row teaches the model; the clock, spp, threads and
 * measure (a still's pass, or a sequence's frames) of the rows' context and the resolution
 * of their camera must be this run's. */
static int tt__hyb_warm(tt__hyb *h) {
  tt__hyb_warm_args a = {
      h->s.host,   h->opt,     h->predictor_name, tt_loaded_plugin_entry(h->s.accel_p)->name,
      h->obj.spec, h->context, h->camera0};
  return tt__hyb_warm_all(&a, h->hy, &h->warm);
}

/* Writes `root` to `path` atomically (tunetrace/file.h). */
int tt__hyb_write_json(const char *path, cJSON *root) {
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
cJSON *tt__hyb_state_json(const tt_hybrid_report *r, const char *where, uint32_t index,
                          double total_ms, uint32_t passes) {
  cJSON *o = cJSON_CreateObject();
  cJSON_AddNumberToObject(o, "state", r->state_index);
  cJSON_AddNumberToObject(o, where, index);
  cJSON_AddStringToObject(o, "mode", r->mode == TT_HYBRID_EXPLORE ? "explore" : "exploit");
  cJSON_AddBoolToObject(o, "fallback", r->fallback != 0);
  cJSON *cfg = tt__json_parse_exact(r->config);
  cJSON_AddItemToObject(o, "config", cfg ? cfg : cJSON_CreateNull());
  const struct {
    const char *name;
    double v;
  } num[] = {{"cost", r->cost},
             {"predicted_cost", r->predicted_cost},
             {"default_cost", r->default_cost},
             {"default_distance", r->default_distance},
             {"search_cost", r->search_cost},
             {"predict_ms", r->predict_ms},
             {"total_ms", total_ms}};
  for (size_t i = 0; i < sizeof num / sizeof num[0]; i++) {
    if (isfinite(num[i].v) && num[i].v < TT_COST_INFEASIBLE)
      cJSON_AddNumberToObject(o, num[i].name, num[i].v);
    else cJSON_AddNullToObject(o, num[i].name);
  }
  static const char *const from[] = {NULL, "measured", "database", "nearest state"};
  if (r->default_source > 0 && r->default_source <= 3)
    cJSON_AddStringToObject(o, "default_cost_from", from[r->default_source]);
  else cJSON_AddNullToObject(o, "default_cost_from");
  cJSON_AddNumberToObject(o, "remeasured", r->remeasured);
  cJSON_AddNumberToObject(o, "samples", r->samples);
  cJSON_AddNumberToObject(o, "builds", r->builds);
  cJSON_AddNumberToObject(o, "cached", r->cached);
  cJSON_AddNumberToObject(o, "passes", passes);
  cJSON *st = cJSON_AddArrayToObject(o, "indicators");
  for (int i = 0; i < TT_SCENE_INDICATOR_COUNT; i++)
    cJSON_AddItemToArray(st, cJSON_CreateNumber(r->state[i]));
  return o;
}

/* Moves the camera to path sample `i` (t = first key + i/99 of the time range; the motion
 * AOV's previous frame one --fps interval earlier). */
static void tt__hyb_camera(tt__session *s, uint32_t i) {
  const tt_camera *c0 = tt_scene_camera(s->scene);
  double t = c0->keys[0].time + (c0->keys[c0->key_count - 1].time - c0->keys[0].time) * (double)i /
                                    (TT_HOST_PATH_SAMPLES - 1.0);
  tt_session_set_camera_time(s->lib, t, 1.0 / (s->opt->fps > 0 ? s->opt->fps : 24.0));
}

/* --states FILE: [{"id": ..., "indicators": {name: raw value}}, ...]; NULL (printed) on error. */
static cJSON *tt__hyb_read_states(const char *path) {
  cJSON *root = NULL;
  if (tt__json_read("--states", path, "states file", &root)) return NULL;
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

/* The raw indicators of a --predict state: the "indicators" of a --states item, or the
 * scene's at path sample `i`. */
static void tt__hyb_raw_state(tt__hyb *h, const cJSON *item, uint32_t i, double *raw) {
  if (item) {
    cJSON *ind = cJSON_GetObjectItemCaseSensitive(item, "indicators");
    for (uint32_t k = 0; k < TT_SCENE_INDICATOR_COUNT; k++)
      raw[k] =
          cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(ind, tt_scene_indicator_name(k)));
  } else if (h->opt->sequence) { /* frame i of an animated sequence: the scene posed too */
    double fps = h->opt->fps > 0 ? h->opt->fps : 24.0, t = i / fps;
    tt_session_set_camera_time(h->s.lib, t, 1.0 / fps);
    tt_scene_set_time(h->s.scene, t, t - 1.0 / fps);
    tt_scene_indicators(h->s.scene, raw);
  } else {
    tt__hyb_camera(&h->s, i);
    tt_scene_indicators(h->s.scene, raw);
  }
}

/* Adds a prediction to `o`: the accel's configured values with the predicted ones put in
 * (`sub` holds them, `full` is scratch), the expected cost and what the model says of it. */
static void tt__hyb_prediction_json(tt__hyb *h, cJSON *o, const tt_predictor_result *r,
                                    const tt_config *sub, tt_config *full, double predict_ms) {
  tt_config_copy(full, h->s.configs[h->accel_index]);
  if (h->subset) tt_config_assign(full, sub);
  else tt_config_copy(full, sub);
  char *j = tt_config_to_json(full);
  cJSON *cfg = tt__json_parse_exact(j);
  tt_free(j);
  cJSON_AddItemToObject(o, "config", cfg ? cfg : cJSON_CreateNull());
  if (isfinite(r->expected_cost)) cJSON_AddNumberToObject(o, "expected_cost", r->expected_cost);
  else cJSON_AddNullToObject(o, "expected_cost");
  if (isfinite(r->value)) cJSON_AddNumberToObject(o, "value", r->value);
  if (isfinite(r->distance)) cJSON_AddNumberToObject(o, "distance", r->distance);
  cJSON_AddNumberToObject(o, "candidates", (double)r->candidates);
  cJSON_AddNumberToObject(o, "predict_ms", predict_ms);
}

/* The model's answer for one state (a --states item, or path sample `i`) as JSON; `*rc`
 * becomes TT_EXIT_FAILURE when the model fails (having no data is not a failure). */
static cJSON *tt__hyb_predict_one(tt__hyb *h, const cJSON *item, uint32_t i, tt_config *sub,
                                  tt_config *full, int *rc) {
  double raw[TT_SCENE_INDICATOR_COUNT], state[TT_SCENE_INDICATOR_COUNT];
  tt__hyb_raw_state(h, item, i, raw);
  tt_indicators_normalize(&h->norm, raw, state);
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
  else cJSON_AddNumberToObject(o, h->opt->sequence ? "frame" : "path_index", i);
  if (st == TT_OK) {
    tt__hyb_prediction_json(h, o, &r, sub, full, tt__median(ms, 5));
    return o;
  }
  cJSON_AddStringToObject(o, "error", tt_last_error());
  if (st != TT_ERR_NO_DATA) *rc = TT_EXIT_FAILURE;
  return o;
}

/* The head of --predict's output: the scene, the predictor and what its model holds. */
static void tt__hyb_predict_head(tt__hyb *h, cJSON *root) {
  cJSON_AddStringToObject(root, "scene", h->opt->scene);
  cJSON_AddStringToObject(root, "scene_id", tt_scene_id(h->s.scene));
  cJSON_AddStringToObject(root, "predictor", h->predictor_name);
  tt_predictor_info info = {.struct_size = sizeof info};
  if (TT_PREDICTOR_HAS(h->pi, info) && h->pi->info(h->model, &info) == TT_OK) {
    cJSON_AddNumberToObject(root, "memory_bytes", (double)info.memory_bytes);
    cJSON_AddNumberToObject(root, "entries", (double)info.entries);
    cJSON_AddNumberToObject(root, "observations", (double)info.observations);
  }
  if (h->warm) cJSON_AddItemToObject(root, "warm_start", h->warm), h->warm = NULL;
}

/* --predict: the model's answer for every state (--states, or the path samples) as JSON on
 * stdout. */
static int tt__hyb_predict(tt__hyb *h) {
  cJSON *root = cJSON_CreateObject(), *arr = cJSON_AddArrayToObject(root, "predictions");
  tt__hyb_predict_head(h, root);
  tt_config *sub = tt_config_create(h->subset ? h->subset : h->space);
  tt_config *full = tt_config_create(h->space);
  int rc = TT_EXIT_OK;
  cJSON *given = NULL;
  uint32_t first = h->first, end = h->end;
  if (h->opt->states) {
    given = tt__hyb_read_states(h->opt->states);
    if (!given) rc = TT_EXIT_USAGE;
    first = 0;
    end = given ? (uint32_t)cJSON_GetArraySize(given) : 0;
  }
  uint32_t step = h->opt->sequence && !given && h->opt->tune_window ? h->opt->tune_window
                  : h->opt->sequence && !given                      ? TT__SEQ_HYBRID_WINDOW
                                                                    : 1;
  for (uint32_t i = first; i < end && sub && full; i += step) {
    cJSON *item = given ? cJSON_GetArrayItem(given, (int)i) : NULL;
    cJSON_AddItemToArray(arr, tt__hyb_predict_one(h, item, i, sub, full, &rc));
  }
  tt_config_destroy(sub);
  tt_config_destroy(full);
  cJSON_Delete(given);
  if (rc == TT_EXIT_USAGE) {
    cJSON_Delete(root);
    return rc;
  }
  int prc = tt__json_print(root);
  return prc != TT_EXIT_OK ? prc : rc;
}

/* Saves the model to --model FILE (atomically); prints a failure, TT_EXIT_OUTPUT. */
static int tt__hyb_save_model(tt__hyb *h) {
  if (h->pi->save(h->model, h->opt->model) == TT_OK) return TT_EXIT_OK;
  tt__say("--model %s: %s\n", h->opt->model, tt_last_error());
  return TT_EXIT_OUTPUT;
}

/* The --predict job: the predictions, and what a warm start taught the model is kept. */
static int tt__hyb_predict_job(tt__hyb *h) {
  int rc = tt__hyb_predict(h);
  if (rc == TT_EXIT_OK && h->opt->model && h->opt->warm_start_count) rc = tt__hyb_save_model(h);
  return rc;
}

/* Writes the film as DIR/state_NNNN.exr and its display preview DIR/state_NNNN.png (as a
 * still render writes both). */
static void tt__hyb_write_state(tt__hyb *h, uint32_t index) {
  tt__session *s = &h->s;
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

/* Checks the options against the scene and each other; prints and returns an exit code. */
static int tt__hyb_check(const tt__hyb *h) {
  const tt__host_options *opt = h->opt;
  const char *job = opt->hybrid ? "hybrid" : "predict";
  const char *accel = tt_loaded_plugin_entry(h->s.accel_p)->name;
  if (opt->sequence && (!tt_scene_animated(h->s.scene) || opt->states)) {
    tt__say("--predict --sequence: %s\n",
            opt->states ? "--states gives the states itself: leave out --sequence"
                        : "the scene does not move: predict along its camera path (no "
                          "--sequence)");
    return TT_EXIT_USAGE;
  }
  if (tt_scene_camera(h->s.scene)->key_count < 1 && !(opt->predict_only && opt->states) &&
      !opt->sequence) {
    tt__say("--%s: %s has no camera path (camera.path in scene.json): the hybrid "
            "loop moves through the path's states\n",
            job, opt->scene);
    return TT_EXIT_USAGE;
  }
  if (opt->tune && strcmp(opt->tune, accel)) {
    tt__say("--hybrid tunes the accel (%s), not --tune %s\n", accel, opt->tune);
    return TT_EXIT_USAGE;
  }
  if (opt->explore || opt->verify || opt->reference || (opt->states && opt->camera_index_set)) {
    tt__say("--%s: %s does not apply (the states are the path samples of "
            "--camera-index A:B)\n",
            job,
            opt->explore     ? "--explore"
            : opt->verify    ? "--verify"
            : opt->reference ? "--reference"
                             : "--camera-index with --states");
    return TT_EXIT_USAGE;
  }
  return TT_EXIT_OK;
}

/* The state space (--indicator-norm, checked when the options were read) and the objective:
 * a time (render, build+render, build). Prints and returns an exit code. */
static int tt__hyb_objective(tt__hyb *h) {
  const tt__host_options *opt = h->opt;
  tt_indicator_norm_init(&h->norm);
  if (opt->indicator_norm) tt_indicator_norm_parse(opt->indicator_norm, &h->norm);
  const char *spec = opt->objective ? opt->objective : opt->sequence ? "build+render" : "render";
  if (tt__parse_objective("--objective", spec, &h->obj)) return TT_EXIT_USAGE;
  tt_objective_kind k = h->obj.kind;
  if (k != TT_OBJECTIVE_RENDER && k != TT_OBJECTIVE_TOTAL && k != TT_OBJECTIVE_BUILD) {
    tt__say("--hybrid: --objective %s: the hybrid loop tunes the accel for time "
            "(render, build+render, build)\n",
            spec);
    return TT_EXIT_USAGE;
  }
  return TT_EXIT_OK;
}

/* Opens --db or the default database (none with --no-db, or without a home). */
static int tt__hyb_open_db(tt__hyb *h) {
  if (h->opt->no_db) return TT_EXIT_OK;
  char *path = h->opt->db ? tt__strdup(h->opt->db) : tt_tunedb_default_path();
  int rc = TT_EXIT_OK;
  if (path && tt_tunedb_open(path, &h->db) != TT_OK) {
    tt__say("--db %s: %s\n", path, tt_last_error());
    rc = TT_EXIT_FAILURE;
  }
  free(path);
  return rc;
}

/* The library's hybrid tuner over the accel. The state's context is the tuning phase's
 * (spp, threads, the other plugins) plus the clock; the camera gets "path_index" per state. */
static int tt__hyb_tuner(tt__hyb *h, tt_loaded_plugin *tp) {
  tt__session *s = &h->s;
  const tt__host_options *opt = h->opt;
  /* along a sequence (--predict --sequence) the rows learnt are the frames' */
  h->context_extra =
      opt->sequence    ? (opt->clock_cpu ? "{\"measure\":\"" TT__SEQ_MEASURE "\",\"clock\":\"cpu\"}"
                                         : "{\"measure\":\"" TT__SEQ_MEASURE "\"}")
      : opt->clock_cpu ? "{\"clock\":\"cpu\"}"
                       : NULL;
  tt_tuning_state st0;
  if (tt_session_tuning_state(s->lib, h->accel_index, h->spp, NULL, h->context_extra, 0, &st0) ==
      TT_OK) {
    h->context = tt__strdup(st0.context);
    h->camera0 = tt__strdup(st0.camera);
  }
  h->epsilon = opt->epsilon_set ? opt->epsilon : TT_HOST_DEFAULT_EPSILON;
  h->explore_iterations = opt->iterations ? opt->iterations : TT_HOST_DEFAULT_HYBRID_ITERATIONS;
  const tt_plugin *ae = tt_loaded_plugin_entry(s->accel_p);
  tt_hybrid_desc d = {.struct_size = sizeof d};
  d.host = s->host;
  d.space = h->space;
  d.start = s->configs[h->accel_index];
  d.search = h->subset;
  d.objective = h->obj.spec;
  d.tuner = tt_loaded_plugin_iface(tp);
  d.tuner_settings = tt_session_config(s->lib, h->tuner_name);
  d.tuner_name = h->tuner_name;
  d.predictor = h->pi;
  d.model = h->model;
  d.predictor_name = h->predictor_name;
  d.epsilon = h->epsilon;
  d.explore_iterations = h->explore_iterations;
  d.spp = h->spp;
  d.warmup_passes = 1;
  d.seed = s->rec.seed;
  d.plugin = ae->name;
  d.plugin_version = ae->version;
  d.db = h->db;
  d.norm = &h->norm;
  if (h->context && h->camera0 && tt_hybrid_create(&d, &h->hy) == TT_OK) return TT_EXIT_OK;
  tt__say("--hybrid: %s\n", h->context ? tt_last_error() : "out of memory");
  return TT_EXIT_FAILURE;
}

/* Create: the session (the scene loaded once), the checks, the searched parameters, the
 * model (the session loaded tuner_nm and predictor_nn unless --plugin named others), the
 * database, the hybrid tuner and its warm start, and the path samples of --camera-index A:B
 * (or I; default all of them). Prints what failed; an exit code. */
static int tt__hyb_create(tt__hyb *h, const tt__host_options *opt) {
  memset(h, 0, sizeof *h);
  h->opt = opt;
  h->spp = opt->tune_spp ? opt->tune_spp : 1;
  int rc = tt__hyb_warm_files(opt);
  if (rc == TT_EXIT_OK) rc = tt__session_open(&h->s, opt);
  if (rc == TT_EXIT_OK) rc = tt__hyb_check(h);
  if (rc == TT_EXIT_OK) rc = tt__hyb_objective(h);
  if (rc != TT_EXIT_OK) return rc;
  tt_loaded_plugin *tp = tt_registry_find_kind(h->s.reg, TT_KIND_TUNER);
  tt_loaded_plugin *pp = tt_registry_find_kind(h->s.reg, TT_KIND_PREDICTOR);
  h->tuner_name = tt_loaded_plugin_entry(tp)->name;
  h->accel_index =
      (size_t)tt_session_plugin_index(h->s.lib, tt_loaded_plugin_entry(h->s.accel_p)->name);
  h->space = tt_loaded_plugin_space(h->s.accel_p);
  if (tt__hyb_subset(h)) return TT_EXIT_USAGE;
  if ((rc = tt__hyb_model(h, pp)) != TT_EXIT_OK || (rc = tt__hyb_open_db(h)) != TT_EXIT_OK ||
      (rc = tt__hyb_tuner(h, tp)) != TT_EXIT_OK || (rc = tt__hyb_warm(h)) != TT_EXIT_OK)
    return rc;
  h->first = opt->sequence ? opt->seq_first : opt->camera_index_set ? opt->camera_index : 0;
  h->end = opt->sequence           ? opt->seq_last + 1
           : opt->camera_index_set ? opt->camera_index_last + 1
                                   : TT_HOST_PATH_SAMPLES;
  return TT_EXIT_OK;
}

/* Start (--hybrid): the --out-dir folder, the accel, integrator and film, and the render
 * session as the tuning target. Prints what failed; an exit code. */
static int tt__hyb_start(tt__hyb *h) {
  const tt__host_options *opt = h->opt;
  if (opt->out_dir && mkdir(opt->out_dir, 0777) != 0 && errno != EEXIST) {
    tt__say("--out-dir %s: %s\n", opt->out_dir, strerror(errno));
    return TT_EXIT_OUTPUT;
  }
  int rc = tt__session_start(&h->s, 0);
  if (rc != TT_EXIT_OK) return rc;
  h->s.host->log(TT_LOG_INFO, NULL,
                 "hybrid: %s states %u..%u, epsilon %g, explore %s for %u "
                 "iterations, exploit %s, objective %s, database %s",
                 opt->scene, h->first, h->end - 1, h->epsilon, h->tuner_name, h->explore_iterations,
                 h->predictor_name, h->obj.spec, h->db ? tt_tunedb_path(h->db) : "none");
  h->states = cJSON_CreateArray();
  if (tt_session_tuning_target(h->s.lib, h->accel_index, 0, &h->target) != TT_OK) {
    tt__say("--hybrid: %s\n", tt_last_error());
    return TT_EXIT_FAILURE;
  }
  return TT_EXIT_OK;
}

/* The passes the render session has rendered. */
static uint32_t tt__hyb_passes(const tt__hyb *h) {
  tt_session_stats ss = {.struct_size = sizeof ss};
  tt_session_get_stats(h->s.lib, &ss);
  return ss.passes;
}

/* The rest of a state's samples, up to --spp, with its configuration (progressive). */
static void tt__hyb_render_rest(tt__hyb *h, uint32_t pass0) {
  uint32_t target_spp = h->opt->spp ? h->opt->spp : 1;
  while ((tt__hyb_passes(h) - pass0) * h->spp < target_spp && !h->s.host->should_stop()) {
    double ms;
    tt_pass_stats ps;
    if (tt__session_render_pass(&h->s, 1, &ps, &ms) != TT_OK) break;
  }
}

/* Adds a state's report to the run's totals. */
static void tt__hyb_account(tt__hyb_totals *tot, const tt_hybrid_report *r) {
  tot->states++;
  tot->explored += r->mode == TT_HYBRID_EXPLORE;
  tot->exploited += r->mode == TT_HYBRID_EXPLOIT;
  tot->builds += r->builds;
  tot->remeasured += r->remeasured;
  tot->cached += r->cached;
  tot->samples += r->samples;
  if (r->cost < TT_COST_INFEASIBLE) tot->sum_cost += r->cost;
  tot->sum_search += r->search_cost;
}

/* Logs what a state cost, what the model expected and the default's cost beside it. */
static void tt__hyb_log_state(const tt__hyb *h, const tt_hybrid_report *r, uint32_t i) {
  if (h->opt->quiet) return;
  char cmp[160] = "";
  size_t n = 0;
  if (isfinite(r->predicted_cost))
    n += (size_t)snprintf(cmp, sizeof cmp, ", the model expected %.4g", r->predicted_cost);
  if (isfinite(r->default_cost) && !r->fallback && n < sizeof cmp)
    snprintf(cmp + n, sizeof cmp - n, ", default %s%.4g%s",
             r->default_source == TT_HYBRID_COST_NEAREST ? "~" : "", r->default_cost,
             r->default_source == TT_HYBRID_COST_NEAREST    ? " (nearest measured state)"
             : r->default_source == TT_HYBRID_COST_DATABASE ? " (database)"
                                                            : "");
  h->s.host->log(TT_LOG_INFO, NULL,
                 "hybrid: state %u (path %u): %s%s, cost %.4g%s, %u "
                 "build%s",
                 r->state_index, i, r->mode == TT_HYBRID_EXPLORE ? "explore" : "exploit",
                 r->fallback ? " (default: no usable prediction)" : "", r->cost, cmp, r->builds,
                 r->builds == 1 ? "" : "s");
}

/* Prints that state `i` failed; TT_EXIT_FAILURE. */
static int tt__hyb_state_failed(uint32_t i) {
  tt__say("--hybrid: state %u: %s\n", i, tt_last_error());
  return TT_EXIT_FAILURE;
}

/* Step: path sample `i` — the camera moves, the film starts over, the hybrid tuner explores
 * or exploits, the state renders the rest of its samples and is reported. A stop request
 * marks the run interrupted. Prints what failed; an exit code. */
static int tt__hyb_step(tt__hyb *h, uint32_t i) {
  tt__session *s = &h->s;
  tt__hyb_camera(s, i);
  tt_session_reset(s->lib); /* a new view: the film starts over */
  uint32_t pass0 = tt__hyb_passes(h);
  char camera_extra[48];
  snprintf(camera_extra, sizeof camera_extra, "{\"path_index\":%u}", i);
  tt_tuning_state state;
  if (tt_session_tuning_state(s->lib, h->accel_index, h->spp, camera_extra, h->context_extra, 1,
                              &state) != TT_OK)
    return tt__hyb_state_failed(i);
  uint64_t t0 = s->host->clock_ns();
  tt_hybrid_report r = {.struct_size = sizeof r};
  tt_status st = tt_hybrid_step(h->hy, &state, &h->target, &r);
  if (st == TT_ERR_INTERRUPTED) {
    h->interrupted = 1;
    return TT_EXIT_OK;
  }
  if (st != TT_OK) return tt__hyb_state_failed(i);
  tt__hyb_render_rest(h, pass0);
  uint32_t passes = tt__hyb_passes(h) - pass0;
  double total_ms = (s->host->clock_ns() - t0) * 1e-6;
  if (h->opt->out_dir) tt__hyb_write_state(h, i);
  cJSON_AddItemToArray(h->states, tt__hyb_state_json(&r, "path_index", i, total_ms, passes));
  tt__hyb_account(&h->tot, &r);
  tt__hyb_log_state(h, &r, i);
  tt__progress_update("hybrid", (double)(i + 1 - h->first) / (h->end - h->first));
  if (s->host->should_stop()) h->interrupted = 1;
  return TT_EXIT_OK;
}

/* The --stats record of the run: the settings, the totals and every state's report. */
static cJSON *tt__hyb_stats_json(tt__hyb *h) {
  const tt__host_options *opt = h->opt;
  const tt__hyb_totals *tot = &h->tot;
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "scene", opt->scene);
  cJSON_AddStringToObject(root, "scene_id", tt_scene_id(h->s.scene));
  cJSON_AddStringToObject(root, "clock", opt->clock_cpu ? "cpu" : "wall");
  cJSON_AddNumberToObject(root, "threads", h->s.rec.threads);
  cJSON_AddNumberToObject(root, "seed", (double)h->s.rec.seed);
  cJSON *hj = cJSON_AddObjectToObject(root, "hybrid");
  cJSON_AddStringToObject(hj, "predictor", h->predictor_name);
  cJSON_AddStringToObject(hj, "tuner", h->tuner_name);
  cJSON_AddNumberToObject(hj, "epsilon", h->epsilon);
  cJSON_AddNumberToObject(hj, "explore_iterations", h->explore_iterations);
  cJSON_AddStringToObject(hj, "objective", h->obj.spec);
  char id[96];
  cJSON_AddStringToObject(hj, "state_space", tt_indicator_norm_id(&h->norm, id, sizeof id));
  if (opt->model) cJSON_AddStringToObject(hj, "model", opt->model);
  else cJSON_AddNullToObject(hj, "model");
  if (h->db) cJSON_AddStringToObject(hj, "db", tt_tunedb_path(h->db));
  else cJSON_AddNullToObject(hj, "db");
  cJSON_AddItemToObject(hj, "warm_start", h->warm ? h->warm : cJSON_CreateArray());
  h->warm = NULL;
  cJSON_AddNumberToObject(hj, "states_done", tot->states);
  cJSON_AddNumberToObject(hj, "explored", tot->explored);
  cJSON_AddNumberToObject(hj, "exploited", tot->exploited);
  cJSON_AddNumberToObject(hj, "builds", tot->builds);
  cJSON_AddNumberToObject(hj, "sum_cost", tot->sum_cost);
  cJSON_AddNumberToObject(hj, "sum_search_cost", tot->sum_search);
  cJSON_AddBoolToObject(hj, "interrupted", h->interrupted);
  cJSON_AddItemToObject(hj, "states", h->states);
  h->states = NULL;
  return root;
}

/* Finish: what the run re-measured and took from the database (said once per run), the
 * model saved (--model), the --stats record. Returns `rc`, or what failed first, or
 * TT_EXIT_INTERRUPTED. */
static int tt__hyb_finish(tt__hyb *h, int rc) {
  const tt__hyb_totals *tot = &h->tot;
  tt__progress_finish();
  if (tot->cached)
    h->s.host->log(TT_LOG_INFO, NULL,
                   "hybrid: %u of %u costs came from the database %s "
                   "(earlier runs measured those configurations in the same state)",
                   tot->cached, tot->samples, tt_tunedb_path(h->db));
  if (tot->remeasured)
    h->s.host->log(TT_LOG_INFO, NULL,
                   "hybrid: %u of %u samples measured again a "
                   "configuration already measured in their state (%s re-evaluating its best "
                   "against noise)",
                   tot->remeasured, tot->samples, h->tuner_name);
  if (h->opt->model && rc == TT_EXIT_OK) rc = tt__hyb_save_model(h);
  if (h->opt->stats) {
    cJSON *root = tt__hyb_stats_json(h);
    int wrc = tt__hyb_write_json(h->opt->stats, root);
    cJSON_Delete(root);
    if (wrc != TT_EXIT_OK && rc == TT_EXIT_OK) rc = wrc;
  }
  return h->interrupted && rc == TT_EXIT_OK ? TT_EXIT_INTERRUPTED : rc;
}

/* Frees what the job holds, at any stage. */
static void tt__hyb_close(tt__hyb *h) {
  cJSON_Delete(h->states);
  cJSON_Delete(h->warm);
  free(h->context);
  free(h->camera0);
  tt_hybrid_destroy(h->hy);
  if (h->model) h->pi->destroy(h->model);
  tt_space_destroy(h->subset);
  tt_tunedb_close(h->db);
  tt__session_close(&h->s);
}

int tt__run_hybrid(const tt__host_options *opt) {
  tt__install_signals("pass");
  tt__hyb h;
  int rc = tt__hyb_create(&h, opt);
  if (rc == TT_EXIT_OK && opt->predict_only) {
    rc = tt__hyb_predict_job(&h);
  } else if (rc == TT_EXIT_OK && (rc = tt__hyb_start(&h)) == TT_EXIT_OK) {
    for (uint32_t i = h.first; i < h.end && rc == TT_EXIT_OK && !h.interrupted; i++)
      rc = tt__hyb_step(&h, i);
    rc = tt__hyb_finish(&h, rc);
  }
  tt__hyb_close(&h);
  return rc;
}
