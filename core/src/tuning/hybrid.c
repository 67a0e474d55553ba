/* Hybrid online autotuning (tunetrace/hybrid.h): eps-greedy between a K-iteration search and
 * one predicted configuration per state, every state a tuning session (tuning.h) over the
 * caller's target, every cost observed by the model. */
#include <tunetrace/hybrid.h>

#include "tuning/tuning_internal.h"

#include <tt_util/clock.h>
#include <tt_util/rng.h>
#include <tt_util/strings.h>

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct tt_hybrid {
  const tt_host *host;
  tt_host session_host; /* host for the per-state sessions: no progress of its own */
  const tt_space *space, *search;
  tt_config *start; /* the default configuration (full space) */
  tt_objective objective;
  const tt_tuner_iface *ti;
  const tt_config *tuner_settings;
  char *tuner_name, *predictor_name, *plugin, *plugin_version, *run_id;
  const tt_predictor_iface *pi;
  tt_predictor *model;
  double epsilon;
  uint32_t K, spp, warmup;
  uint64_t seed;
  tt__pcg32 rng; /* the eps-greedy draws */
  tt_tunedb *db;
  tt_indicator_norm norm;
  int no_exploit_feedback;
  uint32_t states; /* steps so far */
  /* scratch and the current state */
  tt_config *full, *sub;
  double state[TT_SCENE_INDICATOR_COUNT];
  double default_cost; /* of the current state, once known */
  int default_cached;  /* ... answered by the database (an earlier run) */
  char *config_json;   /* the last report's configuration */
  /* the default's cost per state where it was measured (this run's states, a warm start's
   * "default" rows): an exploited state's default cost is estimated from the nearest */
  double *dstate, *dcost; /* nd x TT_SCENE_INDICATOR_COUNT states, nd costs */
  size_t nd, capd;
  int dropped_said; /* "not searched" was said (once per run, not per state) */
  char *warm_strings[2 * TT_HYBRID_WARM_MAX_KEYS]; /* tt_hybrid_warm_result's values */
};

void tt_hybrid_destroy(tt_hybrid *h) {
  if (!h) return;
  tt_config_destroy(h->start);
  tt_config_destroy(h->full);
  tt_config_destroy(h->sub);
  free(h->tuner_name);
  free(h->predictor_name);
  free(h->plugin);
  free(h->plugin_version);
  free(h->run_id);
  free(h->config_json);
  free(h->dstate);
  free(h->dcost);
  for (int i = 0; i < 2 * TT_HYBRID_WARM_MAX_KEYS; i++) free(h->warm_strings[i]);
  free(h);
}

/* Remembers the default's cost in a (normalised) state; an existing entry of the same state
 * keeps the mean. Out of memory only loses the estimate. */
static void tt__default_add(tt_hybrid *h, const double *state, double cost) {
  if (!(cost < TT_COST_INFEASIBLE) || !isfinite(cost)) return;
  const size_t D = TT_SCENE_INDICATOR_COUNT;
  for (size_t i = 0; i < h->nd; i++)
    if (!memcmp(h->dstate + i * D, state, D * sizeof *state)) {
      h->dcost[i] = 0.5 * (h->dcost[i] + cost);
      return;
    }
  if (h->nd == h->capd) {
    size_t cap = h->capd ? 2 * h->capd : 64;
    double *ds = realloc(h->dstate, cap * D * sizeof *ds);
    if (!ds) return;
    h->dstate = ds;
    double *dc = realloc(h->dcost, cap * sizeof *dc);
    if (!dc) return;
    h->dcost = dc;
    h->capd = cap;
  }
  memcpy(h->dstate + h->nd * D, state, D * sizeof *state);
  h->dcost[h->nd++] = cost;
}

/* The default's cost in the nearest state where it was measured (NAN when none), and the
 * distance to it. */
static double tt__default_nearest(const tt_hybrid *h, const double *state, double *distance) {
  const size_t D = TT_SCENE_INDICATOR_COUNT;
  double best = INFINITY, cost = NAN;
  for (size_t i = 0; i < h->nd; i++) {
    double d2 = 0;
    for (size_t k = 0; k < D; k++) {
      double d = h->dstate[i * D + k] - state[k];
      d2 += d * d;
    }
    if (d2 < best) {
      best = d2;
      cost = h->dcost[i];
    }
  }
  *distance = isfinite(best) ? sqrt(best) : NAN;
  return cost;
}

#define TT__HDESC(d, f) (TT_HAS_FIELD(tt_hybrid_desc, d, f) ? (d)->f : 0)

tt_status tt_hybrid_create(const tt_hybrid_desc *d, tt_hybrid **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_hybrid_create: out is NULL");
  *out = NULL;
  if (!d || !TT__HDESC(d, space))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_hybrid_create: no target space");
  if (!TT__HDESC(d, tuner))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_hybrid_create: no tuner for exploration");
  const tt_predictor_iface *pi = TT__HDESC(d, predictor);
  if (!pi || !TT__HDESC(d, model))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_hybrid_create: no predictor (table and "
                                                 "model) for exploitation");
  if (!TT_PREDICTOR_HAS(pi, observe_ex) || !TT_PREDICTOR_HAS(pi, predict_ex))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_hybrid_create: the predictor %s serves an "
                        "ABI 1.0 table (no observe_ex/predict_ex); the hybrid loop needs 1.1",
                        TT__HDESC(d, predictor_name) ? TT__HDESC(d, predictor_name) : "");
  double eps = TT__HDESC(d, epsilon);
  if (!(eps >= 0.0 && eps <= 1.0))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_hybrid_create: epsilon %g is outside "
                        "[0, 1]",
                        eps);
  uint32_t K = TT__HDESC(d, explore_iterations);
  if (K < 1)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_hybrid_create: explore_iterations (K) "
                                                 "must be at least 1");
  tt_hybrid *h = calloc(1, sizeof *h);
  if (!h) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_hybrid_create: out of memory");
  const char *objective = TT__HDESC(d, objective);
  tt_status st = tt_objective_parse(objective ? objective : "render", &h->objective);
  if (st != TT_OK) {
    free(h);
    return st;
  }
  h->host = TT__HDESC(d, host) ? TT__HDESC(d, host) : tt_default_host();
  /* a state's session is one step of the caller's progress, not a task of its own */
  size_t hs =
      h->host->struct_size < sizeof h->session_host ? h->host->struct_size : sizeof h->session_host;
  memcpy(&h->session_host, h->host, hs);
  h->session_host.struct_size = (uint32_t)hs;
  if (hs >= offsetof(tt_host, progress) + sizeof h->session_host.progress)
    h->session_host.progress = NULL;
  h->space = d->space;
  h->search = TT__HDESC(d, search);
  const tt_config *start = TT__HDESC(d, start);
  h->start = start ? tt_config_clone(start) : tt_config_create(d->space);
  h->full = tt_config_create(d->space);
  h->sub = tt_config_create(h->search ? h->search : d->space);
  h->ti = d->tuner;
  h->tuner_settings = TT__HDESC(d, tuner_settings);
  h->tuner_name = tt__strdup(TT__HDESC(d, tuner_name) ? TT__HDESC(d, tuner_name) : "tuner");
  h->pi = pi;
  h->model = d->model;
  h->predictor_name =
      tt__strdup(TT__HDESC(d, predictor_name) ? TT__HDESC(d, predictor_name) : "predictor");
  h->epsilon = eps;
  h->K = K;
  h->spp = TT__HDESC(d, spp) ? TT__HDESC(d, spp) : 1;
  h->warmup = TT__HDESC(d, warmup_passes);
  h->seed = TT__HDESC(d, seed);
  tt__pcg32_seed(&h->rng, h->seed, 0x687962726964ull); /* "hybrid" */
  h->plugin = tt__strdup(TT__HDESC(d, plugin) ? TT__HDESC(d, plugin) : tt_space_plugin(d->space));
  h->plugin_version = tt__strdup(TT__HDESC(d, plugin_version) ? TT__HDESC(d, plugin_version) : "");
  h->db = TT__HDESC(d, db);
  const tt_indicator_norm *norm = TT__HDESC(d, norm);
  tt_indicator_norm_init(&h->norm);
  if (norm) h->norm = *norm;
  h->no_exploit_feedback = TT__HDESC(d, no_exploit_feedback);
  const char *run_id = TT__HDESC(d, run_id);
  char id[64];
  if (!run_id) {
    tt__default_run_id(id, sizeof id, "hybrid-");
    run_id = id;
  }
  h->run_id = tt__strdup(run_id);
  if (!h->start || !h->full || !h->sub || !h->tuner_name || !h->predictor_name || !h->plugin ||
      !h->plugin_version || !h->run_id) {
    tt_hybrid_destroy(h);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_hybrid_create: out of memory");
  }
  if (tt_config_space(h->start) != d->space) {
    tt_hybrid_destroy(h);
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_hybrid_create: the start configuration is "
                                                 "not a configuration of the target space");
  }
  *out = h;
  return TT_OK;
}

/* ---- the model's view of a sample ---- */

/* Reads configuration JSON into h->sub (through the full space, so the searched parameters
 * are taken from it); 0, or -1 if it does not fit the space. */
static int tt__to_sub(tt_hybrid *h, const char *json) {
  tt_config_copy(h->full, h->start);
  if (tt_config_from_json(h->full, json, "tuning database") != TT_OK) return -1;
  if (h->search) return tt_config_assign(h->sub, h->full) < 0 ? -1 : 0;
  tt_config_copy(h->sub, h->full);
  return 0;
}

/* Gives one sample to the model (online; `flags` adds TT_PREDICTOR_EXPLOIT for the model's
 * own answer); failures are logged, not fatal. */
static void tt__observe(tt_hybrid *h, const char *json, double cost, double default_cost,
                        uint32_t flags) {
  if (tt__to_sub(h, json)) return;
  tt_predictor_sample s = {.struct_size = sizeof s,
                           .state = h->state,
                           .config = h->sub,
                           .cost = cost,
                           .default_cost = default_cost};
  if (h->pi->observe_ex(h->model, &s, 1, TT_PREDICTOR_ONLINE | flags) != TT_OK)
    tt_host_log(h->host, TT_LOG_WARN, NULL, "hybrid: %s: observe: %s", h->predictor_name,
                tt_last_error());
}

/* tt_tuning_desc.on_sample of an explored state: every sample goes to the model. */
static void tt__explore_sample(void *user, const tt_tuning_sample *s) {
  tt_hybrid *h = user;
  if (s->status == TT_TUNEDB_FAILED) return; /* maybe transient: says nothing of the config */
  if (s->iteration < 0 && s->status == TT_TUNEDB_OK) {
    h->default_cost = s->cost;
    h->default_cached = s->cached != 0;
    tt__default_add(h, h->state, s->cost);
  }
  tt__observe(h, s->config, s->cost, h->default_cost, 0);
}

/* The target, counting the configurations it applies (builds). */
typedef struct tt__counting {
  const tt_tuning_target *inner;
  uint32_t applies;
} tt__counting;

static tt_status tt__count_apply(void *user, const tt_config *cfg, double *build_ms) {
  tt__counting *c = user;
  c->applies++;
  return c->inner->apply(c->inner->user, cfg, build_ms);
}

static tt_status tt__count_render(void *user, uint32_t spp, tt_tuning_measurement *m) {
  tt__counting *c = user;
  return c->inner->render(c->inner->user, spp, m);
}

/* The database's cost of the default configuration in `state`, or NAN. */
static double tt__db_default_cost(tt_hybrid *h, const tt_tuning_state *state) {
  if (!h->db) return NAN;
  char *json = tt_config_to_json(h->start);
  tt_tunedb_row key;
  memset(&key, 0, sizeof key);
  key.struct_size = sizeof key;
  key.scene_id = state->scene_id;
  key.camera = state->camera;
  key.context = state->context;
  key.plugin = h->plugin;
  key.plugin_version = h->plugin_version;
  key.config = json;
  key.objective = h->objective.spec;
  double cost = NAN;
  if (!json || tt_tunedb_lookup(h->db, &key, &cost, NULL) != TT_OK || cost >= TT_COST_INFEASIBLE)
    cost = NAN;
  tt_free(json);
  return cost;
}

/* A tuning session of this hybrid tuner for one state. */
static tt_status tt__session(tt_hybrid *h, const tt_tuning_state *state, const tt_config *start,
                             int explore, tt_tuning **out) {
  tt_tuning_desc d;
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.host = &h->session_host;
  d.space = h->space;
  d.start = start;
  d.search = h->search;
  d.objective = h->objective.spec;
  d.tuner = explore ? h->ti : NULL;
  d.tuner_settings = explore ? h->tuner_settings : NULL;
  d.tuner_name = explore ? h->tuner_name : h->predictor_name;
  d.seed = h->seed; /* every explored state searches as a tuning run would */
  d.iterations = explore ? h->K : 0;
  d.spp = h->spp;
  d.warmup_passes = h->states == 0 ? h->warmup : 0;
  d.plugin = h->plugin;
  d.plugin_version = h->plugin_version;
  d.db = h->db;
  d.state = state;
  d.run_id = h->run_id;
  d.on_sample = explore ? tt__explore_sample : NULL;
  d.user = h;
  d.mode = explore ? NULL : "exploit";
  /* what a session says once per run (the parameters not searched, its summaries) the
   * hybrid loop says once, not per state */
  tt_status st = tt__tuning_create(&d, 1, out);
  if (st == TT_OK && !h->dropped_said) {
    h->dropped_said = 1;
    const char *dropped = tt__tuning_dropped(*out);
    if (dropped)
      tt_host_log(h->host, TT_LOG_INFO, NULL,
                  "hybrid: not searched in any state: %s (not tunable, or "
                  "cannot act with the values the other parameters are fixed at)",
                  dropped);
  }
  return st;
}

/* Sums of a session's samples: every finite cost, and the count of cached ones. */
static void tt__sums(const tt_tuning *t, double *cost_sum, uint32_t *cached) {
  *cost_sum = 0;
  *cached = 0;
  for (size_t i = 0; i < tt_tuning_sample_count(t); i++) {
    const tt_tuning_sample *s = tt_tuning_sample_at(t, i);
    if (s->status == TT_TUNEDB_OK) *cost_sum += s->cost;
    *cached += s->cached != 0;
  }
}

tt_status tt_hybrid_step(tt_hybrid *h, const tt_tuning_state *state, const tt_tuning_target *target,
                         tt_hybrid_report *out) {
  if (!h || !state || !target || !target->apply || !target->render)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_hybrid_step: NULL argument");
  if (!state->has_indicators)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_hybrid_step: the state has no indicators "
                                                 "(the model's input)");
  if (h->host->should_stop()) return TT_ERR_INTERRUPTED;
  tt_indicators_normalize(&h->norm, state->indicators, h->state);
  h->default_cost = NAN;
  h->default_cached = 0;
  /* eps-greedy: one draw per state, whatever the model knows */
  double u = (double)tt__pcg32_next(&h->rng) * 0x1.0p-32;
  int explore = u < h->epsilon;
  tt__counting counting = {target, 0};
  tt_tuning_target wrapped = {sizeof wrapped, &counting, tt__count_apply, tt__count_render};
  tt_tuning *t = NULL;
  tt_hybrid_report r;
  memset(&r, 0, sizeof r);
  r.state_index = h->states;
  r.mode = explore ? TT_HYBRID_EXPLORE : TT_HYBRID_EXPLOIT;
  r.predicted_cost = NAN;
  r.default_cost = NAN;
  r.default_distance = NAN;
  tt_status st;
  const tt_config *start = h->start;
  tt_config *predicted = NULL;
  if (!explore) {
    /* one configuration from the model: predicted, put into the configured values, checked.
     * The default is not measured here (exploitation is one build): its cost is an earlier
     * run's in this very state, else that of the nearest state where it was measured, so
     * that the report (and a relative-reward model's expected cost) can compare with it */
    double def = tt__db_default_cost(h, state);
    if (isfinite(def)) {
      r.default_source = TT_HYBRID_COST_DATABASE;
      r.default_distance = 0;
      tt__default_add(h, h->state, def);
    } else {
      def = tt__default_nearest(h, h->state, &r.default_distance);
      if (isfinite(def)) r.default_source = TT_HYBRID_COST_NEAREST;
    }
    tt_predictor_query q = {.struct_size = sizeof q, .state = h->state, .default_cost = def};
    tt_predictor_result pr = {.struct_size = sizeof pr};
    double t0 = tt__thread_cpu_ms();
    st = h->pi->predict_ex(h->model, &q, h->sub, &pr);
    r.predict_ms = tt__thread_cpu_ms() - t0;
    r.default_cost = def;
    if (st == TT_OK) {
      predicted = tt_config_clone(h->start);
      if (!predicted) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "hybrid: out of memory");
      if (h->search) tt_config_assign(predicted, h->sub);
      else tt_config_copy(predicted, h->sub);
      char why[256];
      if (tt_space_check(h->space, predicted, why, sizeof why) == TT_CHECK_INFEASIBLE) {
        tt_host_log(h->host, TT_LOG_WARN, NULL,
                    "hybrid: state %u: %s predicted an infeasible "
                    "configuration (%s); using the default",
                    h->states, h->predictor_name, why);
        r.fallback = 1;
      } else {
        start = predicted;
        r.predicted_cost = pr.expected_cost;
      }
    } else if (st == TT_ERR_NO_DATA) {
      r.fallback = 1; /* nothing learnt yet: the default, still one build */
    } else {
      tt_host_log(h->host, TT_LOG_ERROR, NULL, "hybrid: %s: predict: %s", h->predictor_name,
                  tt_last_error());
      return st;
    }
  }
  st = tt__session(h, state, start, explore, &t);
  tt_config_destroy(predicted);
  if (st != TT_OK) return st;
  st = tt_tuning_run(t, &wrapped);
  if (st == TT_OK) st = tt_tuning_apply_best(t, &wrapped, NULL);
  if (st != TT_OK) {
    tt_tuning_destroy(t);
    return st;
  }
  double best = NAN;
  tt_tuning_best(t, NULL, &best);
  free(h->config_json);
  h->config_json = tt__strdup(tt_tuning_best_json(t));
  r.config = h->config_json;
  r.cost = best;
  tt__sums(t, &r.search_cost, &r.cached);
  r.samples = (uint32_t)tt_tuning_sample_count(t);
  r.builds = counting.applies;
  tt_tuning_stats ts = {.struct_size = sizeof ts};
  tt_tuning_get_stats(t, &ts);
  r.remeasured = ts.remeasured;
  if (explore) {
    double def;
    if (tt_tuning_default_cost(t, &def) == TT_OK && def < TT_COST_INFEASIBLE) {
      r.default_cost = def;
      r.default_source = h->default_cached ? TT_HYBRID_COST_DATABASE : TT_HYBRID_COST_MEASURED;
      r.default_distance = 0;
    }
  } else if (tt_tuning_sample_count(t)) {
    const tt_tuning_sample *s = tt_tuning_sample_at(t, 0);
    if (r.fallback && s->status == TT_TUNEDB_OK) {
      /* the default itself ran: its cost is measured (or the database's) here */
      r.default_cost = s->cost;
      r.default_source = s->cached ? TT_HYBRID_COST_DATABASE : TT_HYBRID_COST_MEASURED;
      r.default_distance = 0;
      tt__default_add(h, h->state, s->cost);
    }
    /* the model's own answer (or the default it fell back to): it refines what the model
     * knows, but is no search result (TT_PREDICTOR_EXPLOIT); a relative reward is learnt
     * against a default measured in this state only, never against an estimate */
    if (!h->no_exploit_feedback && s->status != TT_TUNEDB_FAILED)
      tt__observe(h, s->config, s->cost,
                  r.default_source == TT_HYBRID_COST_NEAREST ? NAN : r.default_cost,
                  TT_PREDICTOR_EXPLOIT);
  }
  memcpy(r.state, h->state, sizeof r.state);
  tt_tuning_destroy(t);
  h->states++;
  if (out && out->struct_size >= sizeof(uint32_t)) {
    uint32_t size = out->struct_size < sizeof r ? out->struct_size : (uint32_t)sizeof r;
    r.struct_size = out->struct_size;
    memcpy(out, &r, size);
  }
  return TT_OK;
}

/* ---- warm start ---- */

/* One usable row, kept until the batch is built. */
typedef struct tt__warm_row {
  double state[TT_SCENE_INDICATOR_COUNT];
  tt_config *config;
  double cost;
  char *key;   /* scene id, camera, context: the state's identity */
  int exploit; /* mode "exploit": the model's own answer, not a search's */
} tt__warm_row;

typedef struct tt__default_cost {
  char *key;
  double sum;
  uint32_t n;
  double state[TT_SCENE_INDICATOR_COUNT];
} tt__default_cost;

typedef struct tt__warm {
  tt_hybrid *h;
  const tt_hybrid_warm_filter *f;
  const char *const *keys[2]; /* the filter's context keys and camera keys */
  cJSON *expected[2];         /* the filter's context and camera, parsed */
  tt__warm_row *rows;
  size_t n, cap;
  tt__default_cost *defaults;
  size_t nd, capd;
  tt_hybrid_warm_result res;
  int oom;
} tt__warm;

static char *tt__state_key(const tt_tunedb_row *r) {
  size_t n = strlen(r->scene_id) + (r->camera ? strlen(r->camera) : 0) +
             (r->context ? strlen(r->context) : 0) + 3;
  char *k = malloc(n);
  if (k)
    snprintf(k, n, "%s\n%s\n%s", r->scene_id, r->camera ? r->camera : "",
             r->context ? r->context : "");
  return k;
}

/* Field `f` of a warm filter the caller built with struct_size `size`, or 0/NULL. */
#define TT__WF(f_, field) ((f_) && TT_HAS_FIELD(tt_hybrid_warm_filter, f_, field) ? (f_)->field : 0)

/* JSON text of `v` (malloc), "(none)" for a missing value. */
static char *tt__json_text(const cJSON *v) {
  if (!v) return tt__strdup("(none)");
  char *t = cJSON_PrintUnformatted(v);
  char *out = tt__strdup(t ? t : "?");
  cJSON_free(t);
  return out;
}

/* Counts the row's mismatches on the filter's keys (context, then camera); non-zero if any. */
static int tt__mismatches(tt__warm *w, const char *context, const char *camera) {
  const char *text[2] = {context, camera};
  int any = 0;
  uint32_t slot = 0;
  for (int part = 0; part < 2; part++) {
    if (!w->keys[part]) continue;
    cJSON *row = text[part] ? cJSON_Parse(text[part]) : NULL;
    for (const char *const *k = w->keys[part]; *k; k++, slot++) {
      if (slot >= TT_HYBRID_WARM_MAX_KEYS) break;
      const cJSON *a =
          w->expected[part] ? cJSON_GetObjectItemCaseSensitive(w->expected[part], *k) : NULL;
      const cJSON *b = row ? cJSON_GetObjectItemCaseSensitive(row, *k) : NULL;
      if ((!a && !b) || (a && b && cJSON_Compare(a, b, 1))) continue;
      any = 1;
      if (w->res.mismatch[slot]++ == 0) {
        w->h->warm_strings[slot] = tt__json_text(b);
        w->res.mismatch_value[slot] = w->h->warm_strings[slot];
      }
    }
    cJSON_Delete(row);
  }
  return any;
}

static int tt__warm_row_fn(void *user, const tt_tunedb_row *r) {
  tt__warm *w = user;
  tt_hybrid *h = w->h;
  w->res.considered++;
  if (!r->objective || strcmp(r->objective, h->objective.spec)) {
    w->res.other_objective++;
    return 0;
  }
  if (r->status != TT_TUNEDB_OK && r->status != TT_TUNEDB_INFEASIBLE) {
    w->res.failed++;
    return 0;
  }
  if (!r->has_indicators || !r->scene_id || !r->config) {
    w->res.no_indicators++;
    return 0;
  }
  const tt_hybrid_warm_filter *f = w->f;
  int (*keep)(void *, const tt_tunedb_row *) = TT__WF(f, keep);
  if (keep && !keep(TT__WF(f, user), r)) {
    w->res.excluded++;
    return 0;
  }
  if (tt__mismatches(w, r->context, r->camera)) {
    w->res.other_context++;
    return 0;
  }
  if (tt__to_sub(h, r->config)) {
    w->res.other_space++;
    return 0;
  }
  char *key = tt__state_key(r);
  if (!key) {
    w->oom = 1;
    return 1;
  }
  double state[TT_SCENE_INDICATOR_COUNT];
  tt_indicators_normalize(&h->norm, r->indicators, state);
  if (r->mode && !strcmp(r->mode, "default") && r->status == TT_TUNEDB_OK) {
    if (w->nd == w->capd) {
      size_t cap = w->capd ? 2 * w->capd : 256;
      tt__default_cost *d = realloc(w->defaults, cap * sizeof *d);
      if (!d) {
        free(key);
        w->oom = 1;
        return 1;
      }
      w->defaults = d;
      w->capd = cap;
    }
    tt__default_cost *d = &w->defaults[w->nd++];
    *d = (tt__default_cost){tt__strdup(key), r->cost, 1, {0}};
    memcpy(d->state, state, sizeof state);
  }
  if (w->n == w->cap) {
    size_t cap = w->cap ? 2 * w->cap : 1024;
    tt__warm_row *n = realloc(w->rows, cap * sizeof *n);
    if (!n) {
      free(key);
      w->oom = 1;
      return 1;
    }
    w->rows = n;
    w->cap = cap;
  }
  tt__warm_row *x = &w->rows[w->n];
  memcpy(x->state, state, sizeof state);
  x->config = tt_config_clone(h->sub);
  x->cost = r->status == TT_TUNEDB_OK ? r->cost : TT_COST_INFEASIBLE;
  x->key = key;
  x->exploit = r->mode && !strcmp(r->mode, "exploit");
  if (!x->config) {
    free(key);
    w->oom = 1;
    return 1;
  }
  w->n++;
  return 0;
}

static int tt__cmp_default(const void *a, const void *b) {
  return strcmp(((const tt__default_cost *)a)->key, ((const tt__default_cost *)b)->key);
}

/* The filter's keys and expected values into the result (owned strings in h). */
static void tt__warm_keys(tt__warm *w) {
  const tt_hybrid_warm_filter *f = w->f;
  w->keys[0] = TT__WF(f, context_keys);
  w->keys[1] = TT__WF(f, camera_keys);
  const char *text[2] = {TT__WF(f, context), TT__WF(f, camera)};
  uint32_t slot = 0;
  for (int part = 0; part < 2; part++) {
    w->expected[part] = text[part] ? cJSON_Parse(text[part]) : NULL;
    if (!w->keys[part]) continue;
    for (const char *const *k = w->keys[part]; *k && slot < TT_HYBRID_WARM_MAX_KEYS; k++, slot++) {
      const cJSON *v =
          w->expected[part] ? cJSON_GetObjectItemCaseSensitive(w->expected[part], *k) : NULL;
      char **s = &w->h->warm_strings[TT_HYBRID_WARM_MAX_KEYS + slot];
      free(*s);
      *s = tt__json_text(v);
      w->res.key[slot] = *k;
      w->res.expected_value[slot] = *s;
    }
  }
  w->res.key_count = slot;
}

tt_status tt_hybrid_warm_start_ex(tt_hybrid *h, tt_tunedb *db, const tt_hybrid_warm_filter *f,
                                  tt_hybrid_warm_result *out) {
  if (!h || !db)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_hybrid_warm_start: NULL argument");
  tt__warm w;
  memset(&w, 0, sizeof w);
  w.h = h;
  w.f = f;
  w.res.struct_size = sizeof w.res;
  for (int i = 0; i < TT_HYBRID_WARM_MAX_KEYS; i++) {
    free(h->warm_strings[i]);
    h->warm_strings[i] = NULL;
  }
  tt__warm_keys(&w);
  tt_status st = tt_tunedb_foreach(db, h->plugin, tt__warm_row_fn, &w);
  if (st == TT_OK && w.oom)
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "hybrid: warm start: out of memory");
  /* each state's default cost: the mean of its "default" rows (several runs may have one) */
  size_t nd = 0;
  if (st == TT_OK && w.nd) {
    qsort(w.defaults, w.nd, sizeof *w.defaults, tt__cmp_default);
    for (size_t i = 0; i < w.nd; i++) {
      if (nd && !strcmp(w.defaults[nd - 1].key, w.defaults[i].key)) {
        w.defaults[nd - 1].sum += w.defaults[i].sum;
        w.defaults[nd - 1].n++;
        free(w.defaults[i].key);
      } else {
        w.defaults[nd++] = w.defaults[i];
      }
    }
  } else {
    for (size_t i = 0; i < w.nd; i++) free(w.defaults[i].key);
  }
  /* two batches: what searches found, then the model's own answers (TT_PREDICTOR_EXPLOIT) */
  tt_predictor_sample *batch = st == TT_OK && w.n ? malloc(w.n * sizeof *batch) : NULL;
  if (st == TT_OK && w.n && !batch)
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "hybrid: warm start: out of memory");
  for (int exploit = 0; exploit < 2 && st == TT_OK && w.n; exploit++) {
    size_t m = 0;
    for (size_t i = 0; i < w.n; i++) {
      if (w.rows[i].exploit != exploit) continue;
      tt__default_cost probe = {w.rows[i].key, 0, 0, {0}};
      const tt__default_cost *dc =
          nd ? bsearch(&probe, w.defaults, nd, sizeof *w.defaults, tt__cmp_default) : NULL;
      batch[m++] = (tt_predictor_sample){.struct_size = sizeof *batch,
                                         .state = w.rows[i].state,
                                         .config = w.rows[i].config,
                                         .cost = w.rows[i].cost,
                                         .default_cost = dc ? dc->sum / dc->n : NAN};
    }
    if (!m) continue;
    st = h->pi->observe_ex(h->model, batch, m,
                           TT_PREDICTOR_OFFLINE | (exploit ? TT_PREDICTOR_EXPLOIT : 0));
    if (st != TT_OK)
      st = tt_set_error(st, "hybrid: warm start from %s: %s: %s", tt_tunedb_path(db),
                        h->predictor_name, tt_last_error());
    if (exploit) w.res.exploit_rows = m;
  }
  if (st == TT_OK) {
    w.res.rows = w.n;
    /* the states' default costs estimate an exploited state's default (tt_hybrid_report) */
    for (size_t i = 0; i < nd; i++)
      tt__default_add(h, w.defaults[i].state, w.defaults[i].sum / w.defaults[i].n);
  }
  if (out && out->struct_size >= sizeof(uint32_t)) {
    size_t n = out->struct_size < sizeof w.res ? out->struct_size : sizeof w.res;
    uint32_t size = out->struct_size;
    memcpy(out, &w.res, n);
    out->struct_size = size < sizeof w.res ? size : (uint32_t)sizeof w.res;
  }
  free(batch);
  for (size_t i = 0; i < w.n; i++) {
    tt_config_destroy(w.rows[i].config);
    free(w.rows[i].key);
  }
  free(w.rows);
  for (size_t i = 0; i < nd; i++) free(w.defaults[i].key);
  free(w.defaults);
  cJSON_Delete(w.expected[0]);
  cJSON_Delete(w.expected[1]);
  return st;
}

tt_status tt_hybrid_warm_start(tt_hybrid *h, tt_tunedb *db, const tt_hybrid_warm_filter *f,
                               uint64_t *rows, uint64_t *skipped) {
  tt_hybrid_warm_result res = {.struct_size = sizeof res};
  tt_status st = tt_hybrid_warm_start_ex(h, db, f, &res);
  if (rows) *rows = st == TT_OK ? res.rows : 0;
  if (skipped) *skipped = st == TT_OK ? res.other_space : 0;
  return st;
}
