/* The tuning session (tunetrace/tuning.h): the loop of thesis Fig. 3.2 / 3.14 and random
 * exploration, the tuning database's answers, the best configuration and the side-by-side
 * verification.
 *
 * The database answers configurations already measured in the same state on this machine
 * by an earlier run, so no (state, configuration) pair is measured twice across runs
 * (thesis 3.3); every measurement is committed as soon as it is taken. Within one session,
 * a configuration the tuner proposes again after it was measured in this session is
 * measured again: that is a tuner re-measuring its incumbent against noise (tuner_nm's
 * reevaluate), and a database answer would feed it the same number back and make the
 * noise invisible. */
#include "tuning/tuning_internal.h"

#include <tt_util/rng.h>
#include <tt_util/stats.h>
#include <tt_util/strings.h>

#include <tunetrace/indicators.h>

#include <cjson/cJSON.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

struct tt_tuning {
  const tt_host *host;
  const tt_space *space;  /* the target's full space: what is measured and checked */
  const tt_space *search; /* the searched parameters, or NULL to search all of space */
  tt_space *own_search;   /* search without the parameters tuners leave alone */
  tt_config *start;       /* the configured values (the default configuration) */
  tt_config *cand;        /* the proposal being settled */
  tt_config *sub;         /* a config of the searched space (tuner / draws) */
  tt_config *work;        /* the outstanding configuration (repaired), after next() */
  double *unit;           /* exploration draw, one per searched parameter */
  tt_objective objective;
  const tt_tuner_iface *ti;
  tt_tuner *tuner;
  char *tuner_name, *plugin, *plugin_version, *run_id;
  uint64_t rng; /* exploration stream */
  uint32_t requested, spp, warmup;
  double budget_s;
  tt_tunedb *db;
  tt_tuning_state state; /* strings below are owned copies */
  char *state_strings[4];
  uint32_t width, height;
  const double *ref;
  int want_images;
  void (*on_sample)(void *user, const tt_tuning_sample *sample);
  void *user;

  tt_tuning_sample *samples; /* configs are owned (malloc) */
  size_t count, cap;
  uint32_t measured, cached, infeasible, failed;
  uint32_t unrecorded; /* database writes that failed */
  int converged, interrupted;
  int32_t next_iteration; /* -1: the default comes next */
  int pending;            /* next() returned `work`; report() is expected */
  char *pending_json;
  uint64_t t0;
  int started;
  double ms;
  char *applied; /* config JSON the target runs with (run/verify/apply_best) */
  char *default_json;
  char *best_json;     /* cache of tt_tuning_best_json */
  double *verify_ms;   /* rounds x 2 x 3 of the last verify */
  char *mode;          /* desc->mode: the database's mode column, or NULL */
  int context_sent;    /* the tuner's set_context was called (or cannot be) */
  int quiet;           /* no per-run summaries (the hybrid loop's per-state sessions:
                                   it says them once per run) */
  char *dropped;       /* the parameters not searched (tt__drop_untunable), or NULL */
  uint32_t remeasured; /* proposals of a configuration measured earlier in the run */
  /* the last verification's decision, about the best it verified (verified_json) */
  tt_tuning_verdict verdict;
  char *verified_json;
  char reason[384];
};

/* Canonical JSON of a configuration as a malloc'ed string (tt_config_to_json uses tt_free). */
static char *tt__config_json(const tt_config *cfg) {
  char *json = tt_config_to_json(cfg);
  char *out = tt__strdup(json);
  tt_free(json);
  return out;
}

static uint64_t tt__now(const tt_tuning *t) { return t->host->clock_ns(); }

/* Takes a copy of `state` (NULL: unknown) as the session's state; -1 when out of memory. */
static int tt__copy_state(tt_tuning *t, const tt_tuning_state *state) {
  for (int i = 0; i < 4; i++) free(t->state_strings[i]);
  memset(t->state_strings, 0, sizeof t->state_strings);
  memset(&t->state, 0, sizeof t->state);
  t->state.struct_size = sizeof t->state;
  if (!state) return 0;
  const char *src[4] = {state->scene_id, state->scene, state->camera, state->context};
  int failed = 0;
  for (int i = 0; i < 4; i++) {
    t->state_strings[i] = tt__strdup(src[i]);
    failed |= src[i] && !t->state_strings[i];
  }
  t->state.scene_id = t->state_strings[0];
  t->state.scene = t->state_strings[1];
  t->state.camera = t->state_strings[2];
  t->state.context = t->state_strings[3];
  t->state.has_indicators = state->has_indicators;
  memcpy(t->state.indicators, state->indicators, sizeof t->state.indicators);
  return failed ? -1 : 0;
}

tt_status tt_tuning_set_state(tt_tuning *t, const tt_tuning_state *state) {
  if (!t || !state || state->struct_size < sizeof *state)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_set_state: NULL or short state");
  if (t->pending)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_tuning_set_state: a configuration is outstanding (report it "
                        "first: a measurement belongs to the state it was asked for in)");
  if (t->db && !state->scene_id)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_tuning_set_state: a session with a database needs the state's "
                        "scene_id");
  if (tt__copy_state(t, state))
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_tuning_set_state: out of memory");
  return TT_OK;
}

void tt_tuning_destroy(tt_tuning *t) {
  if (!t) return;
  if (t->tuner) t->ti->destroy(t->tuner);
  tt_config_destroy(t->start);
  tt_config_destroy(t->cand);
  tt_config_destroy(t->sub);
  tt_config_destroy(t->work);
  tt_space_destroy(t->own_search);
  free(t->unit);
  free(t->tuner_name);
  free(t->plugin);
  free(t->plugin_version);
  free(t->run_id);
  for (int i = 0; i < 4; i++) free(t->state_strings[i]);
  for (size_t i = 0; i < t->count; i++) free((char *)t->samples[i].config);
  free(t->samples);
  free(t->pending_json);
  free(t->applied);
  free(t->default_json);
  free(t->best_json);
  free(t->verify_ms);
  free(t->mode);
  free(t->verified_json);
  free(t->dropped);
  free(t);
}

/* Field `f` of a descriptor the caller built with struct_size `size`, or 0/NULL. */
#define TT__DESC(d, f) (TT_HAS_FIELD(tt_tuning_desc, d, f) ? (d)->f : 0)

/* Searches only what tuners may change (tunetrace/params.h): a parameter marked not
 * tunable, or one that can never act because a condition names a parameter left out of the
 * search whose fixed value fails it, is dropped from the searched space (t->own_search,
 * which keeps the conditions among the rest), and said once. No parameter left: an error. */
static tt_status tt__drop_untunable(tt_tuning *t) {
  const tt_space *searched = t->search ? t->search : t->space;
  char dropped[512] = "";
  size_t used = 0;
  for (int pass = 0; pass < 4; pass++) {
    size_t n = tt_space_count(searched), keep = 0;
    const char **names = malloc((n ? n : 1) * sizeof *names);
    if (!names) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_tuning_create: out of memory");
    for (size_t i = 0; i < n; i++) {
      if (tt_space_is_tunable(searched, i)) {
        names[keep++] = tt_space_name(searched, i);
      } else if (used < sizeof dropped) {
        int w = snprintf(dropped + used, sizeof dropped - used, "%s%s", used ? ", " : "",
                         tt_space_name(searched, i));
        if (w > 0) used += (size_t)w;
      }
    }
    if (keep == n) {
      free(names);
      break;
    }
    if (!keep) {
      free(names);
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          "tuning %s: nothing to search: %s %s not "
                          "tunable or cannot act with the values the others are fixed at "
                          "(host --describe %s shows \"tunable\" and \"activeWhen\")",
                          tt_space_plugin(t->space), dropped, strchr(dropped, ',') ? "are" : "is",
                          tt_space_plugin(t->space));
    }
    tt_space *sub = tt_space_subset(searched, names, keep, searched == t->space ? t->start : NULL);
    free(names);
    if (!sub) return TT_ERR_INVALID_ARGUMENT; /* tt_space_subset set the message */
    tt_space_destroy(t->own_search);
    t->own_search = sub;
    searched = sub;
  }
  if (t->own_search) {
    t->search = t->own_search;
    t->dropped = tt__strdup(dropped);
    if (!t->quiet)
      tt_host_log(t->host, TT_LOG_INFO, NULL,
                  "tuning: not searched: %s (not tunable, or cannot act "
                  "with the values the other parameters are fixed at)",
                  dropped);
  }
  return TT_OK;
}

void tt__default_run_id(char *buf, size_t n, const char *prefix) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  snprintf(buf, n, "%s%llx-%d", prefix,
           (unsigned long long)ts.tv_sec * 1000000000ull + (unsigned long long)ts.tv_nsec,
           (int)getpid());
}

tt_status tt_tuning_create(const tt_tuning_desc *d, tt_tuning **out) {
  return tt__tuning_create(d, 0, out);
}

tt_status tt__tuning_create(const tt_tuning_desc *d, int quiet, tt_tuning **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_create: out is NULL");
  *out = NULL;
  if (!d || !TT_HAS_FIELD(tt_tuning_desc, d, space) || !d->space)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_create: no descriptor or no "
                                                 "space to tune");
  const char *objective = TT__DESC(d, objective);
  tt_tuning *t = calloc(1, sizeof *t);
  if (!t) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_tuning_create: out of memory");
  tt_status st = tt_objective_parse(objective ? objective : "render", &t->objective);
  if (st != TT_OK) {
    free(t);
    return st;
  }
  t->host = TT__DESC(d, host) ? TT__DESC(d, host) : tt_default_host();
  t->quiet = quiet;
  t->space = d->space;
  t->ti = TT__DESC(d, tuner);
  t->requested = TT__DESC(d, iterations);
  t->spp = TT__DESC(d, spp) ? TT__DESC(d, spp) : 1;
  t->warmup = TT__DESC(d, warmup_passes);
  t->budget_s = TT__DESC(d, time_budget_s);
  t->db = TT__DESC(d, db);
  t->width = TT__DESC(d, width);
  t->height = TT__DESC(d, height);
  t->ref = TT__DESC(d, reference_luminance);
  t->want_images = TT__DESC(d, want_images) || t->objective.kind == TT_OBJECTIVE_RRMSE;
  t->on_sample = TT__DESC(d, on_sample);
  t->user = TT__DESC(d, user);
  t->next_iteration = -1;
  uint64_t seed = TT__DESC(d, seed);
  t->rng = seed ^ 0x7475756e65ull;
  t->tuner_name = tt__strdup(TT__DESC(d, tuner_name));
  t->plugin = tt__strdup(TT__DESC(d, plugin) ? TT__DESC(d, plugin) : tt_space_plugin(d->space));
  t->plugin_version = tt__strdup(TT__DESC(d, plugin_version) ? TT__DESC(d, plugin_version) : "");
  t->state.struct_size = sizeof t->state;
  tt__copy_state(t, TT__DESC(d, state));
  const char *run_id = TT__DESC(d, run_id);
  char id[64];
  if (!run_id) {
    tt__default_run_id(id, sizeof id, "");
    run_id = id;
  }
  t->run_id = tt__strdup(run_id);
  t->mode = tt__strdup(TT__DESC(d, mode));
  const tt_config *start = TT__DESC(d, start);
  t->start = start ? tt_config_clone(start) : tt_config_create(d->space);
  if (!t->tuner_name && t->ti) t->tuner_name = tt__strdup("tuner");
  if (!t->plugin || !t->plugin_version || !t->run_id || !t->start) {
    tt_tuning_destroy(t);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_tuning_create: out of memory");
  }
  if (tt_config_space(t->start) != d->space) {
    tt_tuning_destroy(t);
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_create: the start configuration "
                                                 "is not a configuration of the tuned space");
  }
  if (t->objective.kind == TT_OBJECTIVE_RRMSE && (!t->ref || !t->width || !t->height)) {
    tt_tuning_destroy(t);
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "the rrmse objective needs a reference "
                                                 "image (reference_luminance, width, height)");
  }
  t->search = TT__DESC(d, search);
  if ((st = tt__drop_untunable(t)) != TT_OK) {
    tt_tuning_destroy(t);
    return st;
  }
  const tt_space *searched = t->search ? t->search : d->space;
  size_t dims = tt_space_count(searched);
  t->cand = tt_config_create(d->space);
  t->sub = tt_config_create(searched);
  t->unit = calloc(dims ? dims : 1, sizeof *t->unit);
  t->default_json = tt__config_json(t->start);
  if (!t->cand || !t->sub || !t->unit || !t->default_json) {
    tt_tuning_destroy(t);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_tuning_create: out of memory");
  }
  if (t->ti) {
    st = t->ti->create(searched, TT__DESC(d, tuner_settings), seed, &t->tuner);
    if (st != TT_OK) {
      t->tuner = NULL;
      tt_tuning_destroy(t);
      return st;
    }
  }
  *out = t;
  return TT_OK;
}

/* ---- samples ---------------------------------------------------------------------- */

/* How many times `config` was really measured (not answered from the database) so far. */
static uint32_t tt__measured_before(const tt_tuning *t, const char *config) {
  uint32_t n = 0;
  for (size_t i = 0; i < t->count; i++)
    if (!t->samples[i].cached && !strcmp(t->samples[i].config, config)) n++;
  return n;
}

/* JSON object of a pass's metrics (malloc), or NULL when it has none. */
static char *tt__metrics_json(const tt_pass_stats *ps) {
  if (!ps || !ps->metric_count) return NULL;
  cJSON *root = cJSON_CreateObject();
  for (uint32_t m = 0; m < ps->metric_count && m < TT_MAX_METRICS; m++)
    if (ps->metrics[m].name && isfinite(ps->metrics[m].value))
      cJSON_AddNumberToObject(root, ps->metrics[m].name, ps->metrics[m].value);
  char *text = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  char *out = tt__strdup(text);
  cJSON_free(text);
  return out;
}

/* The database row of the session's state, the target and `config`. */
static tt_tunedb_row tt__row(const tt_tuning *t, const char *config) {
  tt_tunedb_row row;
  memset(&row, 0, sizeof row);
  row.struct_size = sizeof row;
  row.scene_id = t->state.scene_id;
  row.scene = t->state.scene;
  row.camera = t->state.camera;
  row.context = t->state.context;
  row.has_indicators = t->state.has_indicators;
  memcpy(row.indicators, t->state.indicators, sizeof row.indicators);
  row.plugin = t->plugin;
  row.plugin_version = t->plugin_version;
  row.config = config;
  row.objective = t->objective.spec;
  row.run_id = t->run_id;
  row.tuner = t->tuner_name;
  return row;
}

/* Progress of the session after the sample of `iteration` (host->progress). */
static void tt__progress(const tt_tuning *t, int32_t iteration) {
  if (!TT_HOST_HAS(t->host, progress)) return;
  t->host->progress(t->ti ? "tuning" : "explore",
                    t->requested ? (double)(iteration + 1) / t->requested : 1.0);
}

/* Appends `s` (taking its config), tells on_sample, feeds a proposal's cost to the tuner and
 * moves on to the next iteration. TT_OK or the tuner's feedback error (logged). */
static tt_status tt__record(tt_tuning *t, tt_tuning_sample *s) {
  if (t->count == t->cap) {
    size_t cap = t->cap ? 2 * t->cap : 64;
    tt_tuning_sample *n = realloc(t->samples, cap * sizeof *n);
    if (!n) {
      free((char *)s->config);
      return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuning: out of memory");
    }
    t->samples = n;
    t->cap = cap;
  }
  s->struct_size = sizeof *s;
  t->samples[t->count++] = *s;
  free(t->best_json);
  t->best_json = NULL;
  t->next_iteration = s->iteration + 1;
  tt_status st = TT_OK;
  if (s->iteration >= 0 && t->tuner && t->ti->feedback(t->tuner, s->cost) != TT_OK) {
    tt_host_log(t->host, TT_LOG_ERROR, NULL, "tuning: %s: feedback: %s", t->tuner_name,
                tt_last_error());
    st = TT_ERR_INTERNAL;
  }
  /* after the feedback, so that the session is consistent (tt_tuning_save_state) */
  if (t->on_sample) t->on_sample(t->user, &t->samples[t->count - 1]);
  t->samples[t->count - 1].image = NULL; /* valid during on_sample only */
  if (st == TT_OK) tt__progress(t, s->iteration);
  return st;
}

/* Records a measured sample (OK, infeasible or failed) in the database. */
static void tt__record_db(tt_tuning *t, const tt_tuning_sample *s, const tt_pass_stats *ps) {
  if (!t->db) return;
  tt_tunedb_row row = tt__row(t, s->config);
  char *metrics = tt__metrics_json(ps);
  row.build_ms = s->build_ms;
  row.render_ms = s->render_ms;
  row.cost = s->cost;
  row.status = s->status;
  row.mode = t->mode ? t->mode : s->iteration < 0 ? "default" : tt_tuning_mode(t);
  row.iteration = s->iteration;
  row.metrics = metrics;
  /* one warning with the reason (a full disk fails every later write too), then a count */
  if (tt_tunedb_record(t->db, &row) != TT_OK && t->unrecorded++ == 0)
    tt_host_log(t->host, TT_LOG_WARN, NULL, "tuning: %s; later failures are counted, not repeated",
                tt_last_error());
  free(metrics);
}

/* Settles the proposal in t->cand for `iteration`: answered by the database or rejected by
 * the constraints (recorded, returns 0), or outstanding (t->work, returns 1); < 0 (a
 * tt_status) on failure. */
static int tt__settle(tt_tuning *t, int32_t iteration) {
  tt_tuning_sample s;
  memset(&s, 0, sizeof s);
  s.iteration = iteration;
  char *json = tt__config_json(t->cand);
  if (!json) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuning: out of memory");
  s.config = json;
  double cached = 0;
  uint32_t times = 0, here = tt__measured_before(t, json);
  tt_tunedb_row row = tt__row(t, json);
  if (here) {
    /* a tuner re-measuring its incumbent: routine, counted and said once per run */
    t->remeasured++;
    tt_host_log(t->host, TT_LOG_DEBUG, NULL,
                "tuning: iteration %d: measuring again a configuration "
                "measured %u time%s in this run",
                iteration, here, here == 1 ? "" : "s");
  } else if (t->db && tt_tunedb_lookup(t->db, &row, &cached, &times) == TT_OK) {
    s.cost = cached;
    s.cached = 1;
    s.status = cached >= TT_COST_INFEASIBLE ? TT_TUNEDB_INFEASIBLE : TT_TUNEDB_OK;
    t->cached++;
    if (s.status == TT_TUNEDB_INFEASIBLE) t->infeasible++;
    /* one line per answer only at debug level: the run says once how many (tt_tuning_run) */
    if (iteration < 0)
      tt_host_log(t->host, TT_LOG_DEBUG, NULL,
                  "tuning: default configuration: cost %.6g from the "
                  "database (%u earlier measurement%s), not measured again",
                  cached, times, times == 1 ? "" : "s");
    else
      tt_host_log(t->host, TT_LOG_DEBUG, NULL,
                  "tuning: iteration %d: cost %.6g from the database "
                  "(%u earlier measurement%s), not measured again",
                  iteration, cached, times, times == 1 ? "" : "s");
    tt_status st = tt__record(t, &s);
    return st == TT_OK ? 0 : st;
  }
  tt_config_destroy(t->work);
  t->work = tt_config_clone(t->cand);
  if (!t->work) {
    free(json);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuning: out of memory");
  }
  char why[512] = "";
  if (tt_space_check(t->space, t->work, why, sizeof why) == TT_CHECK_INFEASIBLE) {
    s.status = TT_TUNEDB_INFEASIBLE;
    s.cost = TT_COST_INFEASIBLE;
    tt_host_log(t->host, TT_LOG_INFO, NULL, "tuning: iteration %d: infeasible: %s", iteration, why);
    t->measured++;
    t->infeasible++;
    tt__record_db(t, &s, NULL);
    tt_status st = tt__record(t, &s);
    return st == TT_OK ? 0 : st;
  }
  t->pending = 1;
  free(t->pending_json);
  t->pending_json = json;
  return 1;
}

/* Tells a tuner of ABI 1.1 what the session knows before its first proposal (tuner.h):
 * the state (the indicators normalised as the predictors get them), the default's cost as
 * measured or answered here, and the iteration budget. A tuner that refuses the context is
 * only logged: the search works without it. */
static void tt__send_context(tt_tuning *t) {
  t->context_sent = 1;
  if (!TT_TUNER_HAS(t->ti, set_context)) return;
  tt_indicator_norm norm;
  tt_indicator_norm_init(&norm);
  double state[TT_SCENE_INDICATOR_COUNT];
  char id[96];
  tt_tuner_context ctx;
  memset(&ctx, 0, sizeof ctx);
  ctx.struct_size = sizeof ctx;
  if (t->state.has_indicators) {
    tt_indicators_normalize(&norm, t->state.indicators, state);
    ctx.state = state;
    ctx.state_dim = TT_SCENE_INDICATOR_COUNT;
    ctx.state_space = tt_indicator_norm_id(&norm, id, sizeof id);
  }
  ctx.default_cost = NAN;
  if (t->count && t->samples[0].iteration < 0 && t->samples[0].status != TT_TUNEDB_FAILED)
    ctx.default_cost = t->samples[0].cost;
  ctx.budget = t->requested;
  if (t->ti->set_context(t->tuner, &ctx) != TT_OK)
    tt_host_log(t->host, TT_LOG_WARN, NULL, "tuning: %s: set_context: %s (searching without it)",
                t->tuner_name, tt_last_error());
}

/* t->cand from t->sub: every candidate is the configured values with the searched ones put
 * in; then the parameters the candidate's own values leave inactive take the configured
 * values (tt_config_canonicalize), so proposals that differ only in what does nothing are
 * one configuration: one JSON in the database, answered instead of measured again. */
static void tt__candidate(tt_tuning *t) {
  tt_config_copy(t->cand, t->start);
  tt_config_assign(t->cand, t->sub);
  tt_config_canonicalize(t->cand, t->start);
}

/* Non-zero if this run already has a sample of `json` (measured or answered). */
static int tt__seen(const tt_tuning *t, const char *json) {
  for (size_t i = 0; i < t->count; i++)
    if (!strcmp(t->samples[i].config, json)) return 1;
  return 0;
}

/* Exploration: a uniform draw of the searched parameters into t->cand. A repairable draw is
 * measured as repaired; an infeasible one is recorded as such (settle checks again), since
 * where the constraints bite is part of the map. A draw that canonicalises to a
 * configuration this run already has (the native backend has 24 distinct configurations of
 * accel_embree) is drawn again, up to 64 times, then measured again. */
static tt_status tt__draw(tt_tuning *t) {
  size_t dims = tt_space_count(tt_config_space(t->sub));
  for (int attempt = 0; attempt < 64; attempt++) {
    for (size_t k = 0; k < dims; k++) t->unit[k] = (tt__splitmix64(&t->rng) >> 11) * 0x1.0p-53;
    tt_config_from_unit(t->sub, t->unit);
    tt__candidate(t);
    char why[256];
    tt_space_check(t->space, t->cand, why, sizeof why);
    char *json = tt__config_json(t->cand);
    if (!json) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuning: out of memory");
    int seen = tt__seen(t, json);
    free(json);
    if (!seen) break;
  }
  return TT_OK;
}

tt_status tt_tuning_next(tt_tuning *t, tt_config *out) {
  if (!t || !out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_next: NULL argument");
  if (tt_config_space(out) != t->space)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_next: `out` is not a "
                                                 "configuration of the tuned space");
  if (!t->started) {
    t->started = 1;
    t->t0 = tt__now(t);
  }
  while (!t->pending) {
    int32_t it = t->next_iteration;
    if (it < 0) {
      tt_config_copy(t->cand, t->start);
    } else {
      if ((uint32_t)it >= t->requested || t->converged) return TT_DONE;
      if (t->interrupted || t->host->should_stop()) {
        t->interrupted = 1;
        return TT_ERR_INTERRUPTED;
      }
      if (t->budget_s > 0 && (tt__now(t) - t->t0) * 1e-9 >= t->budget_s) return TT_DONE;
      if (!t->tuner) {
        tt_status st = tt__draw(t);
        if (st != TT_OK) return st;
      } else {
        if (!t->context_sent) tt__send_context(t);
        tt_status st = t->ti->next(t->tuner, t->sub);
        if (st == TT_DONE) {
          t->converged = 1;
          tt_host_log(t->host, TT_LOG_INFO, NULL,
                      "tuning: %s reports convergence after %d iterations", t->tuner_name, it);
          return TT_DONE;
        }
        if (st != TT_OK) {
          tt_host_log(t->host, TT_LOG_ERROR, NULL, "tuning: %s: next: %s", t->tuner_name,
                      tt_last_error());
          return st;
        }
      }
      if (t->tuner) tt__candidate(t);
    }
    int r = tt__settle(t, it);
    if (r < 0) return (tt_status)r;
  }
  tt_config_copy(out, t->work);
  return TT_OK;
}

/* Reports the outstanding configuration; `logged`: the caller already logged a failure. */
static tt_status tt__report(tt_tuning *t, const tt_tuning_measurement *m, double *cost,
                            int logged) {
  if (!t->pending)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_report: no configuration is "
                                                 "outstanding (call tt_tuning_next first)");
  int32_t iteration = t->next_iteration;
  if (m->status == TT_ERR_INTERRUPTED) {
    t->pending = 0;
    t->interrupted = 1;
    return TT_ERR_INTERRUPTED;
  }
  tt_tuning_sample s;
  memset(&s, 0, sizeof s);
  s.iteration = iteration;
  s.build_ms = m->build_ms;
  s.render_ms = m->render_ms;
  if (m->status != TT_OK) {
    s.status = TT_TUNEDB_FAILED;
    if (!logged)
      tt_host_log(t->host, TT_LOG_WARN, NULL, "tuning: iteration %d: the measurement failed: %s",
                  iteration, tt_last_error());
  } else {
    tt_status st =
        tt__objective_cost(&t->objective, m, t->ref, (size_t)t->width * t->height, &s.cost);
    if (st != TT_OK) {
      t->pending = 0;
      return st; /* the objective cannot work: nothing is recorded */
    }
    s.status = TT_TUNEDB_OK;
    s.image = m->image;
  }
  if (s.status != TT_TUNEDB_OK) s.cost = TT_COST_INFEASIBLE;
  if (s.status == TT_TUNEDB_FAILED) t->failed++;
  t->measured++;
  s.config = t->pending_json;
  t->pending_json = NULL;
  t->pending = 0;
  tt__record_db(t, &s, m->pass);
  if (cost) *cost = s.cost;
  return tt__record(t, &s);
}

tt_status tt_tuning_report(tt_tuning *t, const tt_tuning_measurement *m, double *cost) {
  if (!t || !m) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_report: NULL argument");
  return tt__report(t, m, cost, 0);
}

/* Applies `cfg` through the target (always: a re-measured accel is rebuilt and its build
 * time measured like any other candidate's) and remembers what the target runs. */
static tt_status tt__apply(tt_tuning *t, const tt_tuning_target *target, const tt_config *cfg,
                           const char *json, double *build_ms) {
  *build_ms = 0;
  tt_status st = target->apply(target->user, cfg, build_ms);
  free(t->applied);
  t->applied = st == TT_OK ? tt__strdup(json) : NULL;
  return st;
}

/* A measurement with the fields the target fills zeroed. */
static tt_tuning_measurement tt__measurement(void) {
  tt_tuning_measurement m;
  memset(&m, 0, sizeof m);
  m.struct_size = sizeof m;
  return m;
}

/* Says once per run what used to be a line per iteration: how many costs the database
 * answered (and which database), how many proposals re-measured a configuration. */
static void tt__log_summary(const tt_tuning *t) {
  uint32_t samples = (uint32_t)t->count;
  if (t->cached)
    tt_host_log(t->host, TT_LOG_INFO, NULL,
                "tuning: %u of %u costs came from the database %s (earlier "
                "runs measured those configurations in the same state; they were not measured "
                "again)",
                t->cached, samples, t->db ? tt_tunedb_path(t->db) : "");
  uint32_t iterations = 0;
  for (size_t i = 0; i < t->count; i++) iterations += t->samples[i].iteration >= 0;
  if (t->remeasured)
    tt_host_log(t->host, TT_LOG_INFO, NULL,
                "tuning: %u of %u iterations measured again a configuration "
                "already measured in this run (%s re-evaluating its best against noise; a "
                "configuration is judged by its mean cost)",
                t->remeasured, iterations, t->tuner_name ? t->tuner_name : "the tuner");
}

tt_status tt_tuning_run(tt_tuning *t, const tt_tuning_target *target) {
  if (!t || !target || !target->apply || !target->render)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_run: no target callbacks");
  if (!t->started) {
    t->started = 1;
    t->t0 = tt__now(t);
  }
  tt_status rc = TT_OK;
  /* unmeasured warm-up passes: the first pass pays for page faults and lazy
   * initialisation, which would make the default look slow */
  for (uint32_t k = 0; k < t->warmup && !t->interrupted; k++)
    if (target->render(target->user, 1, NULL) == TT_ERR_INTERRUPTED) t->interrupted = 1;
  tt_config *cfg = tt_config_create(t->space);
  if (!cfg) rc = tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuning: out of memory");
  while (rc == TT_OK && !t->interrupted) {
    tt_status st = tt_tuning_next(t, cfg);
    if (st == TT_DONE) break;
    if (st != TT_OK) {
      rc = st;
      break;
    }
    int32_t it = t->next_iteration;
    tt_tuning_measurement m = tt__measurement();
    int logged = 0;
    m.status = tt__apply(t, target, cfg, t->pending_json, &m.build_ms);
    if (m.status != TT_OK) {
      tt_host_log(t->host, TT_LOG_WARN, NULL, "tuning: iteration %d: %s rejected %s: %s", it,
                  t->plugin, t->pending_json, tt_last_error());
      logged = 1;
    } else {
      m.status = target->render(target->user, t->spp, &m);
      if (m.status != TT_OK && m.status != TT_ERR_INTERRUPTED) {
        tt_host_log(t->host, TT_LOG_WARN, NULL, "tuning: iteration %d: the pass failed: %s", it,
                    tt_last_error());
        logged = 1;
      }
    }
    rc = tt__report(t, &m, NULL, logged);
  }
  tt_config_destroy(cfg);
  t->ms = (tt__now(t) - t->t0) * 1e-6;
  if (rc == TT_OK && t->interrupted) rc = TT_ERR_INTERRUPTED;
  if (!t->quiet) tt__log_summary(t);
  return rc;
}

/* ---- results ------------------------------------------------------------------------ */

/* Index of the best sample's first occurrence and its mean cost, or -1. */
static long tt__best_index(const tt_tuning *t, double *mean_out) {
  long best = -1;
  double best_cost = TT_COST_INFEASIBLE;
  for (size_t i = 0; i < t->count; i++) {
    const char *cfg = t->samples[i].config;
    int seen = 0;
    for (size_t j = 0; j < i && !seen; j++) seen = !strcmp(t->samples[j].config, cfg);
    if (seen) continue;
    double sum = 0;
    uint32_t n = 0;
    for (size_t j = i; j < t->count; j++) {
      if (strcmp(t->samples[j].config, cfg) || t->samples[j].status == TT_TUNEDB_FAILED) continue;
      sum += t->samples[j].cost;
      n++;
    }
    if (!n) continue;
    double mean = sum / n;
    if (mean < best_cost || best < 0) {
      best_cost = mean;
      best = (long)i;
    }
  }
  *mean_out = best_cost;
  return best;
}

/* The mean over every measurement of the default's configuration, as tt__best_index averages
 * repeats: a search that proposes the default again (canonical configurations make that
 * common) must not compare its best mean against the default's first measurement alone. */
tt_status tt_tuning_default_cost(const tt_tuning *t, double *cost) {
  for (size_t i = 0; t && i < t->count; i++)
    if (t->samples[i].iteration < 0) {
      const char *cfg = t->samples[i].config;
      double sum = 0;
      uint32_t n = 0;
      for (size_t j = i; j < t->count; j++) {
        if (strcmp(t->samples[j].config, cfg) || t->samples[j].status == TT_TUNEDB_FAILED) continue;
        sum += t->samples[j].cost;
        n++;
      }
      if (cost) *cost = n ? sum / n : t->samples[i].cost;
      return TT_OK;
    }
  if (cost) *cost = TT_COST_INFEASIBLE;
  return TT_ERR_NO_DATA;
}

tt_status tt_tuning_best(const tt_tuning *t, tt_config *out, double *cost) {
  if (!t) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_best: NULL session");
  double mean = TT_COST_INFEASIBLE;
  long i = tt__best_index(t, &mean);
  const char *json = i >= 0 ? t->samples[i].config : t->default_json;
  if (i < 0) tt_tuning_default_cost(t, &mean);
  if (cost) *cost = mean;
  if (out) {
    tt_status st = tt_config_from_json(out, json, "tuning: best configuration");
    if (st != TT_OK) return st;
  }
  return i >= 0 ? TT_OK : TT_ERR_NO_DATA;
}

const char *tt_tuning_best_json(const tt_tuning *t) {
  if (!t) return NULL;
  double mean;
  long i = tt__best_index(t, &mean);
  return i >= 0 ? t->samples[i].config : t->default_json;
}

const char *tt_tuning_default_json(const tt_tuning *t) { return t ? t->default_json : NULL; }

size_t tt_tuning_sample_count(const tt_tuning *t) { return t ? t->count : 0; }

const tt_tuning_sample *tt_tuning_sample_at(const tt_tuning *t, size_t i) {
  return t && i < t->count ? &t->samples[i] : NULL;
}

void tt_tuning_get_stats(const tt_tuning *t, tt_tuning_stats *out) {
  if (!t || !out) return;
  tt_tuning_stats s;
  memset(&s, 0, sizeof s);
  s.struct_size = sizeof s;
  s.requested = t->requested;
  for (size_t i = 0; i < t->count; i++) s.iterations += t->samples[i].iteration >= 0;
  s.measured = t->measured;
  s.cached = t->cached;
  s.infeasible = t->infeasible;
  s.failed = t->failed;
  s.converged = t->converged;
  s.interrupted = t->interrupted;
  s.tuning_ms = t->ms;
  s.unrecorded = t->unrecorded;
  s.remeasured = t->remeasured;
  size_t n = out->struct_size < sizeof s ? out->struct_size : sizeof s;
  memcpy(out, &s, n);
  out->struct_size = (uint32_t)n;
}

const char *tt_tuning_mode(const tt_tuning *t) { return t && t->ti ? "tune" : "explore"; }

const tt_objective *tt_tuning_objective(const tt_tuning *t) { return t ? &t->objective : NULL; }

/* ---- verification ------------------------------------------------------------------- */

/* One verification measurement: applies `cfg` and renders one pass. 0 on success, 1 when
 * interrupted, -1 when the configuration fails. */
static int tt__verify_one(tt_tuning *t, const tt_tuning_target *target, const tt_config *cfg,
                          const char *json, double out[3]) {
  tt_tuning_measurement m = tt__measurement();
  double cost = 0;
  if (tt__apply(t, target, cfg, json, &m.build_ms) != TT_OK) return -1;
  tt_status st = target->render(target->user, t->spp, &m);
  if (st == TT_ERR_INTERRUPTED) return 1;
  if (st != TT_OK ||
      tt__objective_cost(&t->objective, &m, t->ref, (size_t)t->width * t->height, &cost) != TT_OK)
    return -1;
  out[0] = m.build_ms;
  out[1] = m.render_ms;
  out[2] = cost;
  return 0;
}

/* Decides from the verification `v` of `best_json` which configuration the session keeps,
 * and says it in one sentence (t->reason, logged): the best only when its cost was lower
 * than the default's in the median round. `failed`: the best failed to render. */
static void tt__verdict(tt_tuning *t, const tt_tuning_verification *v, const char *best_json,
                        int failed) {
  free(t->verified_json);
  t->verified_json = best_json ? tt__strdup(best_json) : NULL;
  t->verdict = TT_TUNING_UNVERIFIED;
  t->reason[0] = 0;
  if (!t->verified_json) return;
  if (!strcmp(best_json, t->default_json)) {
    t->verdict = TT_TUNING_DEFAULT;
    snprintf(t->reason, sizeof t->reason,
             "keeping the default configuration: the search found "
             "nothing better than it");
  } else if (failed) {
    t->verdict = TT_TUNING_REJECTED;
    snprintf(t->reason, sizeof t->reason,
             "keeping the default configuration: the tuned one "
             "failed when measured again side by side");
  } else if (v->rounds) {
    /* how much the cost changed, as a percentage of the default's when that is meaningful */
    double def = v->median_cost[0];
    char how[96];
    if (isfinite(v->cost_ratio) && def > 0)
      snprintf(how, sizeof how, "%.1f%% %s", 100.0 * fabs(1.0 - v->cost_ratio),
               v->cost_ratio < 1 ? "lower" : "higher");
    else
      snprintf(how, sizeof how, "%.4g %s", fabs(v->cost_difference),
               v->cost_difference < 0 ? "lower" : "higher");
    if (v->cost_difference < 0) {
      t->verdict = TT_TUNING_CONFIRMED;
      snprintf(t->reason, sizeof t->reason,
               "keeping the tuned configuration: measured side by "
               "side with the default in %u rounds, its cost was lower in %u, the median round "
               "%s",
               v->rounds, v->best_faster, how);
    } else {
      t->verdict = TT_TUNING_REJECTED;
      snprintf(t->reason, sizeof t->reason,
               "keeping the default configuration: measured side "
               "by side with it in %u rounds, the tuned one was not faster (its cost was lower "
               "in only %u, the median round %s)",
               v->rounds, v->best_faster, how);
    }
  }
  if (t->verdict != TT_TUNING_UNVERIFIED)
    tt_host_log(t->host, TT_LOG_INFO, NULL, "tuning: %s", t->reason);
}

tt_status tt_tuning_verify(tt_tuning *t, const tt_tuning_target *target, uint32_t rounds,
                           tt_tuning_verification *out) {
  if (!t || !target || !target->apply || !target->render || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_verify: NULL argument");
  tt_tuning_verification v;
  memset(&v, 0, sizeof v);
  v.struct_size = sizeof v;
  v.spp = t->spp;
  v.render_ratio = v.total_ratio = v.cost_ratio = NAN;
  tt_config *cfg[2] = {tt_config_create(t->space), tt_config_create(t->space)};
  const char *json[2] = {t->default_json, tt_tuning_best_json(t)};
  char *best_copy = tt__strdup(json[1]); /* the sample array does not grow here, but be safe */
  json[1] = best_copy;
  free(t->verify_ms);
  t->verify_ms = calloc((size_t)rounds * 6 + 1, sizeof *t->verify_ms); /* [r][who][3] */
  double *tmp = calloc((size_t)rounds + 1, sizeof *tmp);
  tt_status rc = TT_OK;
  uint32_t done = 0;
  int failed_best = 0;
  double *m = t->verify_ms;
  v.cost_difference = NAN;
  if (!cfg[0] || !cfg[1] || !m || !tmp || !json[0] || !json[1] ||
      tt_config_from_json(cfg[0], json[0], "default") != TT_OK ||
      tt_config_from_json(cfg[1], json[1], "best") != TT_OK) {
    tt_host_log(t->host, TT_LOG_ERROR, NULL, "tuning: --verify: cannot set up: %s",
                tt_last_error());
    rc = TT_ERR_OUT_OF_MEMORY;
    goto out;
  }
  for (uint32_t r = 0; r < rounds && rc == TT_OK; r++) {
    if (t->host->should_stop()) {
      rc = TT_ERR_INTERRUPTED;
      break;
    }
    for (int k = 0; k < 2 && rc == TT_OK; k++) {
      int who = (r % 2) ? 1 - k : k; /* 0 = default, 1 = best */
      int res = tt__verify_one(t, target, cfg[who], json[who], &m[((size_t)r * 2 + who) * 3]);
      if (res == 1) rc = TT_ERR_INTERRUPTED;
      if (res < 0) {
        tt_host_log(t->host, TT_LOG_ERROR, NULL,
                    "tuning: --verify: the %s configuration failed: %s", who ? "best" : "default",
                    tt_last_error());
        rc = TT_ERR_INTERNAL;
        failed_best = who == 1;
        goto out;
      }
    }
    if (rc == TT_OK) done++;
  }
  v.rounds = done;
  v.rounds_ms = m;
  if (!done) goto out;
  for (int who = 0; who < 2; who++) {
    for (int f = 0; f < 4; f++) {
      for (uint32_t r = 0; r < done; r++) {
        const double *x = &m[((size_t)r * 2 + who) * 3];
        tmp[r] = f < 3 ? x[f] : x[0] + x[1];
      }
      double med = tt__median(tmp, done);
      if (f == 0) v.median_build_ms[who] = med;
      if (f == 1) v.median_render_ms[who] = med;
      if (f == 2) v.median_cost[who] = med;
      if (f == 3) v.median_total_ms[who] = med;
    }
  }
  /* per-round ratios best/default: render, build+render, and the objective's cost */
  for (int q = 0; q < 3; q++) {
    uint32_t n = 0;
    for (uint32_t r = 0; r < done; r++) {
      const double *d = &m[((size_t)r * 2) * 3], *b = &m[((size_t)r * 2 + 1) * 3];
      double num = q == 0 ? b[1] : q == 1 ? b[0] + b[1] : b[2];
      double den = q == 0 ? d[1] : q == 1 ? d[0] + d[1] : d[2];
      if (den > 0 && isfinite(num / den)) tmp[n++] = num / den;
    }
    double ratio = tt__median(tmp, n);
    if (q == 0) v.render_ratio = ratio;
    if (q == 1) v.total_ratio = ratio;
    if (q == 2) v.cost_ratio = ratio;
  }
  /* per-round differences of the objective's cost: signed costs (metric:NAME:max is -value)
   * make ratios meaningless, differences are not */
  for (uint32_t r = 0; r < done; r++) {
    tmp[r] = m[((size_t)r * 2 + 1) * 3 + 2] - m[((size_t)r * 2) * 3 + 2];
    v.best_faster += tmp[r] < 0;
  }
  v.cost_difference = tt__median(tmp, done);
out:
  tt__verdict(t, &v, json[1], rc != TT_OK && failed_best);
  v.rounds = done;
  v.rounds_ms = m;
  v.verdict = t->verdict;
  v.reason = t->verdict != TT_TUNING_UNVERIFIED ? t->reason : NULL;
  size_t n = out->struct_size && out->struct_size < sizeof v ? out->struct_size : sizeof v;
  memcpy(out, &v, n);
  out->struct_size = (uint32_t)n;
  free(tmp);
  free(best_copy);
  tt_config_destroy(cfg[0]);
  tt_config_destroy(cfg[1]);
  return rc;
}

tt_status tt_tuning_apply_best(tt_tuning *t, const tt_tuning_target *target, double *build_ms) {
  if (!t || !target || !target->apply)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_apply_best: no target callbacks");
  double ms = 0;
  if (build_ms) *build_ms = 0;
  const char *json = tt_tuning_kept_json(t);
  if (t->applied && !strcmp(t->applied, json)) return TT_OK;
  tt_config *cfg = tt_config_create(t->space);
  if (!cfg) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuning: out of memory");
  char *copy = tt__strdup(json);
  tt_status st = copy ? tt_config_from_json(cfg, copy, "tuning: best configuration")
                      : tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuning: out of memory");
  if (st == TT_OK) st = tt__apply(t, target, cfg, copy, &ms);
  free(copy);
  tt_config_destroy(cfg);
  if (build_ms) *build_ms = ms;
  return st;
}

tt_tuning_verdict tt_tuning_get_verdict(const tt_tuning *t, const char **reason) {
  if (reason) *reason = NULL;
  if (!t || t->verdict == TT_TUNING_UNVERIFIED || !t->verified_json ||
      strcmp(t->verified_json, tt_tuning_best_json(t)))
    return TT_TUNING_UNVERIFIED; /* never verified, or the best changed since */
  if (reason) *reason = t->reason;
  return t->verdict;
}

const char *tt__tuning_dropped(const tt_tuning *t) { return t ? t->dropped : NULL; }

const char *tt_tuning_kept_json(const tt_tuning *t) {
  if (!t) return NULL;
  return tt_tuning_get_verdict(t, NULL) == TT_TUNING_REJECTED ? t->default_json
                                                              : tt_tuning_best_json(t);
}

/* ---- resume ------------------------------------------------------------------------ */

#define TT__STATE_FORMAT 1

tt_status tt_tuning_save_state(const tt_tuning *t, char **json) {
  if (!t || !json)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_save_state: NULL argument");
  *json = NULL;
  if (t->pending)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_save_state: a configuration is "
                                                 "outstanding (report it first)");
  char *tuner = NULL;
  if (t->tuner && t->ti->save_state(t->tuner, &tuner) != TT_OK) return TT_ERR_INTERNAL;
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "tunetrace", "tuning session");
  cJSON_AddNumberToObject(root, "format", TT__STATE_FORMAT);
  cJSON_AddStringToObject(root, "plugin", t->plugin);
  cJSON_AddStringToObject(root, "plugin_version", t->plugin_version);
  cJSON_AddStringToObject(root, "objective", t->objective.spec);
  cJSON_AddStringToObject(root, "tuner", t->tuner_name ? t->tuner_name : "");
  const char *keys[4] = {"scene_id", "scene", "camera", "context"};
  const char *vals[4] = {t->state.scene_id, t->state.scene, t->state.camera, t->state.context};
  for (int i = 0; i < 4; i++) cJSON_AddStringToObject(root, keys[i], vals[i] ? vals[i] : "");
  cJSON_AddStringToObject(root, "default", t->default_json);
  cJSON_AddNumberToObject(root, "requested", t->requested);
  cJSON_AddNumberToObject(root, "next_iteration", t->next_iteration);
  cJSON *c = cJSON_AddObjectToObject(root, "counters");
  cJSON_AddNumberToObject(c, "measured", t->measured);
  cJSON_AddNumberToObject(c, "cached", t->cached);
  cJSON_AddNumberToObject(c, "infeasible", t->infeasible);
  cJSON_AddNumberToObject(c, "failed", t->failed);
  cJSON_AddBoolToObject(root, "converged", t->converged);
  cJSON_AddBoolToObject(root, "context_sent", t->context_sent);
  char rng[32];
  snprintf(rng, sizeof rng, "%llu", (unsigned long long)t->rng);
  cJSON_AddStringToObject(root, "rng", rng);
  cJSON *arr = cJSON_AddArrayToObject(root, "samples");
  for (size_t i = 0; i < t->count; i++) {
    const tt_tuning_sample *x = &t->samples[i];
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "iteration", x->iteration);
    cJSON_AddStringToObject(o, "config", x->config);
    char num[64];
    snprintf(num, sizeof num, "%.17g", x->cost); /* exact, and 1e300 survives */
    cJSON_AddRawToObject(o, "cost", num);
    snprintf(num, sizeof num, "%.17g", x->build_ms);
    cJSON_AddRawToObject(o, "build_ms", num);
    snprintf(num, sizeof num, "%.17g", x->render_ms);
    cJSON_AddRawToObject(o, "render_ms", num);
    cJSON_AddNumberToObject(o, "status", x->status);
    cJSON_AddBoolToObject(o, "cached", x->cached);
    cJSON_AddItemToArray(arr, o);
  }
  if (tuner) {
    /* kept as the tuner wrote it: re-printing its numbers through cJSON would round them
     * (cJSON prints 15 digits when they compare equal within an epsilon) */
    cJSON_AddStringToObject(root, "tuner_state", tuner);
    tt_free(tuner);
  }
  char *text = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  if (!text) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_tuning_save_state: out of memory");
  *json = malloc(strlen(text) + 1);
  if (*json) strcpy(*json, text);
  cJSON_free(text);
  return *json ? TT_OK : tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_tuning_save_state: out of memory");
}

/* String field `k` of `o` equals `want` (NULL: ""). */
static int tt__state_is(const cJSON *o, const char *k, const char *want) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
  return cJSON_IsString(v) && !strcmp(v->valuestring, want ? want : "");
}

/* Number field `k` of `o` into *out: present, finite and within [lo, hi]; else an error
 * naming `source`, `where` and the field (a NaN or an out-of-range number would otherwise be
 * cast to an integer, or printed as "nan" into the next saved state, which then does not
 * parse: found by tests/fuzz/fuzz_tuning_state). */
static tt_status tt__state_num(const cJSON *o, const char *k, double lo, double hi,
                               const char *source, const char *where, double *out) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
  if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) || v->valuedouble < lo || v->valuedouble > hi)
    return tt_set_error(TT_ERR_PARSE, "%s: %s%s: expected a number in [%g, %g]", source, where, k,
                        lo, hi);
  *out = v->valuedouble;
  return TT_OK;
}

tt_status tt_tuning_load_state(tt_tuning *t, const char *json, const char *source) {
  if (!t || !json)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tuning_load_state: NULL argument");
  if (!source) source = "tuning state";
  if (t->count || t->started)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: a session resumes before its first sample",
                        source);
  const char *end = json;
  cJSON *root = cJSON_ParseWithOpts(json, &end, 0);
  tt_status st = TT_OK;
  const cJSON *fmt = cJSON_GetObjectItemCaseSensitive(root, "format");
  if (!root || !tt__state_is(root, "tunetrace", "tuning session") || !cJSON_IsNumber(fmt)) {
    st = tt_set_error(TT_ERR_PARSE, "%s: not a tuning session state", source);
    goto done;
  }
  end += strspn(end, " \t\r\n"); /* nothing may follow the state (a file appended to) */
  if (*end) {
    st = tt_set_error(TT_ERR_PARSE,
                      "%s: unexpected text after the state, at byte %zu: "
                      "\"%.20s\"",
                      source, (size_t)(end - json), end);
    goto done;
  }
  if (fmt->valuedouble > TT__STATE_FORMAT) {
    st = tt_set_error(TT_ERR_UNSUPPORTED, "%s: state format %g is newer than this library's %d",
                      source, fmt->valuedouble, TT__STATE_FORMAT);
    goto done;
  }
  /* the same search: target, objective, tuner, state and default */
  struct {
    const char *key, *mine;
  } same[] = {{"plugin", t->plugin},       {"objective", t->objective.spec},
              {"tuner", t->tuner_name},    {"scene_id", t->state.scene_id},
              {"camera", t->state.camera}, {"context", t->state.context},
              {"default", t->default_json}};
  for (size_t i = 0; i < sizeof same / sizeof same[0]; i++)
    if (!tt__state_is(root, same[i].key, same[i].mine)) {
      const cJSON *v = cJSON_GetObjectItemCaseSensitive(root, same[i].key);
      st = tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "%s: saved for another %s (\"%.200s\"; this run: "
                        "\"%.200s\")",
                        source, same[i].key, cJSON_IsString(v) ? v->valuestring : "?",
                        same[i].mine ? same[i].mine : "");
      goto done;
    }
  const cJSON *samples = cJSON_GetObjectItemCaseSensitive(root, "samples");
  const cJSON *next = cJSON_GetObjectItemCaseSensitive(root, "next_iteration");
  const cJSON *c = cJSON_GetObjectItemCaseSensitive(root, "counters");
  const cJSON *rng = cJSON_GetObjectItemCaseSensitive(root, "rng");
  if (!cJSON_IsArray(samples) || !cJSON_IsNumber(next) || !cJSON_IsObject(c) ||
      !cJSON_IsString(rng)) {
    st = tt_set_error(TT_ERR_PARSE, "%s: samples, next_iteration, counters or rng missing", source);
    goto done;
  }
  const cJSON *ts = cJSON_GetObjectItemCaseSensitive(root, "tuner_state");
  if (t->tuner) {
    char *tj = cJSON_IsString(ts) ? NULL : cJSON_PrintUnformatted(ts);
    const char *text = cJSON_IsString(ts) ? ts->valuestring : tj;
    st = text ? t->ti->load_state(t->tuner, text)
              : tt_set_error(TT_ERR_PARSE, "%s: no tuner state", source);
    cJSON_free(tj);
    if (st != TT_OK) {
      st = tt_set_error(st, "%s: %s: %s", source, t->tuner_name, tt_last_error());
      goto done;
    }
  }
  int n = cJSON_GetArraySize(samples);
  for (int i = 0; i < n; i++) {
    const cJSON *o = cJSON_GetArrayItem(samples, i);
    const cJSON *cfg = cJSON_GetObjectItemCaseSensitive(o, "config");
    if (!cJSON_IsString(cfg)) {
      st = tt_set_error(TT_ERR_PARSE, "%s: samples[%d]: no config", source, i);
      goto done;
    }
    tt_tuning_sample x;
    memset(&x, 0, sizeof x);
    x.struct_size = sizeof x;
    char where[48];
    snprintf(where, sizeof where, "samples[%d].", i);
    double it, status;
    if ((st = tt__state_num(o, "iteration", -1, INT32_MAX, source, where, &it)) != TT_OK ||
        (st = tt__state_num(o, "cost", -DBL_MAX, DBL_MAX, source, where, &x.cost)) != TT_OK ||
        (st = tt__state_num(o, "build_ms", 0, DBL_MAX, source, where, &x.build_ms)) != TT_OK ||
        (st = tt__state_num(o, "render_ms", 0, DBL_MAX, source, where, &x.render_ms)) != TT_OK ||
        (st = tt__state_num(o, "status", TT_TUNEDB_OK, TT_TUNEDB_FAILED, source, where, &status)) !=
            TT_OK)
      goto done;
    x.iteration = (int32_t)it;
    x.status = (int32_t)status;
    x.cached = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(o, "cached"));
    x.config = tt__strdup(cfg->valuestring);
    if (!x.config) {
      st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", source);
      goto done;
    }
    if (t->count == t->cap) {
      size_t cap = t->cap ? 2 * t->cap : 64;
      tt_tuning_sample *m = realloc(t->samples, cap * sizeof *m);
      if (!m) {
        free((char *)x.config);
        st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", source);
        goto done;
      }
      t->samples = m;
      t->cap = cap;
    }
    t->samples[t->count++] = x;
  }
  double nx, cnt[4];
  static const char *const counters[4] = {"measured", "cached", "infeasible", "failed"};
  if ((st = tt__state_num(root, "next_iteration", -1, INT32_MAX, source, "", &nx)) != TT_OK)
    goto done;
  for (int i = 0; i < 4; i++)
    if ((st = tt__state_num(c, counters[i], 0, UINT32_MAX, source, "counters.", &cnt[i])) != TT_OK)
      goto done;
  t->next_iteration = (int32_t)nx;
  t->measured = (uint32_t)cnt[0];
  t->cached = (uint32_t)cnt[1];
  t->infeasible = (uint32_t)cnt[2];
  t->failed = (uint32_t)cnt[3];
  t->converged = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(root, "converged"));
  t->context_sent = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(root, "context_sent"));
  t->rng = strtoull(rng->valuestring, NULL, 10);
  free(t->best_json);
  t->best_json = NULL;
done:
  if (st != TT_OK) { /* nothing half-restored: the session starts from scratch */
    for (size_t i = 0; i < t->count; i++) free((char *)t->samples[i].config);
    t->count = 0;
    t->next_iteration = -1;
  }
  cJSON_Delete(root);
  return st;
}
