/* predictor_rbf: RBF features with myopic Greedy-GQ (thesis 3.3.2).
 *
 * Model: Q(s, a) = theta . phi(s, enc(a)) (rbf_model.h: features, encoding, update rule).
 * Reward of an observation: `reward = relative` (the default) R = default_cost / cost, the
 * speed-up over the state's default configuration, which puts cheap and expensive scenes on
 * one scale (a sample without a known default cost is then skipped); `inverse` (the thesis)
 * R = 1 / cost. An infeasible configuration has reward 0 in both.
 *
 * Exploitation = argmax_a Q(s, a) over candidate actions, in three sources:
 *   1. the pool of observed configurations ("DB configurations"), at most `poolSize`:
 *      `poolSource = states` (the default) every observed state's best configuration by
 *      mean cost (predictor_common/state_table.h), those best in the most states first;
 *      `rewards` the configurations with the highest single reward so far, in any state,
 *      which on the baseline were mostly configurations measured once whose one sample was
 *      lucky (README: "Why the states' bests"). By default the pool alone (and the default
 *      configuration): the thesis' actions are "the configurations investigated by the
 *      tuning search", and on the baseline of tools/hybrid/README.md ("Studies") the argmax
 *      over points nobody measured found the model's errors, not faster configurations;
 *   2. `lhsCandidates` points of a Latin hypercube over the target space (drawn once from
 *      the seed), so that the answer is not limited to what was measured (default 0);
 *   3. local refinement: from the `refineStarts` best of 1+2, `refine` rounds of coordinate
 *      search in the unit cube (every other value of a NOM parameter, +-step for INT/FLOAT,
 *      step 1/8 halved each round), keeping each improvement (default 0 rounds).
 * The default configuration of the space is always a candidate. tools/hybrid/README.md shows
 * that beyond 256 LHS points + 3 rounds more candidates no longer change the answer.
 *
 * Offline data (a tuning DB: observe_ex with TT_PREDICTOR_OFFLINE) is learnt in `epochs`
 * passes, each in a fresh order shuffled from the seed; online samples update once each.
 * Greedy-GQ is off-policy: samples may come from any search (thesis). The model's own answers
 * (TT_PREDICTOR_EXPLOIT) update theta like any sample, but add no state to the table the
 * candidate pool is drawn from (poolSource = states: what the searches found).
 *
 * Model files: predictor_common/model_file.h, payload version 2 (see tt__rbf_save; version 1,
 * without the state table, still loads as a `poolSource = rewards` model).
 */
#include "../predictor_common/model_file.h"
#include "../predictor_common/state_table.h"
#include "rbf_argmax.h"
#include "rbf_model.h"

#include <tt_util/rng.h>

#include <tunetrace/plugin.h>
#include <tunetrace/predictor.h>
#include <tt_util/strings.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TT__RBF_NAME "predictor_rbf"
#define TT__RBF_VERSION "0.1.0"
#define TT__RBF_FORMAT 2u /* 2: the state table after the pool (poolSource = states) */

static tt_space *tt__rbf_settings;

enum { TT__RBF_REWARD_INVERSE = 0, TT__RBF_REWARD_RELATIVE = 1 };
static const char *const tt__rbf_reward_names[] = {"inverse", "relative"};
enum { TT__RBF_POOL_REWARDS = 0, TT__RBF_POOL_STATES = 1 };
static const char *const tt__rbf_pool_names[] = {"rewards", "states"};

typedef struct tt__rbf_settings_values {
  int64_t features; /* 0: round(3.5 x (state dims + parameters)) */
  double width, alpha, decay;
  int64_t epochs, lhs, refine, starts, pool;
  int reward;
  int pool_source; /* TT__RBF_POOL_REWARDS or TT__RBF_POOL_STATES */
} tt__rbf_settings_values;

struct tt_predictor {
  const tt_space *target;
  size_t params;
  uint32_t d, m;
  char *state_space;
  char **names;
  char *signature;
  uint64_t seed;
  tt__rbf_settings_values set;
  tt__rbf_model model;
  /* LHS candidates (regenerated from the seed): values (params), encodings (m) and the
   * action parts of their distances to the centres (F, tt__rbf_action_part) */
  size_t ncand;
  double *cand_values, *cand_enc, *cand_da;
  float *cand_daf; /* cand_da in float, rows of tt__rbf_f8(F): the argmax's coarse level */
  /* pool of observed configurations, the `pool` highest rewards; pool_da as cand_da, kept
   * with each entry so that predict() does not recompute F x m sums per candidate */
  size_t npool;
  double *pool_values, *pool_enc, *pool_reward, *pool_da;
  float *pool_daf; /* as cand_daf */
  /* poolSource = states: every observed state's configurations and mean costs; the pool is
   * the states' best configurations (tt__rbf_pool_from_states) */
  tt__pm_table table;
  uint64_t observations;
  double *phi; /* F scratch for updates (observe is single-threaded) */
  double *x;   /* d + m scratch */
};

static const tt_space *tt__rbf_space(void) { return tt__rbf_settings; }

/* Reads the settings (NULL: defaults) into v. */
static void tt__rbf_read_settings(const tt_config *c, tt__rbf_settings_values *v) {
  const tt_config *s = c;
  tt_config *def = NULL;
  if (!s) s = def = tt_config_create(tt__rbf_settings);
  v->features = tt_config_get_int(s, "features", 0);
  v->width = tt_config_get_float(s, "width", 1.0);
  v->alpha = tt_config_get_float(s, "alpha", 0.1);
  v->decay = tt_config_get_float(s, "decay", 0.0);
  v->epochs = tt_config_get_int(s, "epochs", 10);
  v->lhs = tt_config_get_int(s, "lhsCandidates", 0);
  v->refine = tt_config_get_int(s, "refine", 0);
  v->starts = tt_config_get_int(s, "refineStarts", 4);
  v->pool = tt_config_get_int(s, "poolSize", 256);
  const char *r = tt_config_get_string(s, "reward");
  v->reward = r && !strcmp(r, "relative") ? TT__RBF_REWARD_RELATIVE : TT__RBF_REWARD_INVERSE;
  const char *ps = tt_config_get_string(s, "poolSource");
  v->pool_source = ps && !strcmp(ps, "states") ? TT__RBF_POOL_STATES : TT__RBF_POOL_REWARDS;
  tt_config_destroy(def);
}

/* The settings as a configuration JSON (what the model file records). */
static char *tt__rbf_settings_json(const tt__rbf_settings_values *v) {
  tt_config *c = tt_config_create(tt__rbf_settings);
  if (!c) return NULL;
  char buf[64];
  struct {
    const char *name;
    double value;
  } num[] = {{"features", (double)v->features},
             {"width", v->width},
             {"alpha", v->alpha},
             {"decay", v->decay},
             {"epochs", (double)v->epochs},
             {"lhsCandidates", (double)v->lhs},
             {"refine", (double)v->refine},
             {"refineStarts", (double)v->starts},
             {"poolSize", (double)v->pool}};
  for (size_t i = 0; i < sizeof num / sizeof num[0]; i++)
    tt_config_set_number(c, (size_t)tt_space_find(tt__rbf_settings, num[i].name), num[i].value);
  snprintf(buf, sizeof buf, "%s", tt__rbf_reward_names[v->reward]);
  tt_config_set_string(c, "reward", buf);
  snprintf(buf, sizeof buf, "%s", tt__rbf_pool_names[v->pool_source]);
  tt_config_set_string(c, "poolSource", buf);
  char *j = tt_config_to_json(c);
  tt_config_destroy(c);
  return j;
}

static void tt__rbf_free_model_parts(tt_predictor *p) {
  tt__rbf_model_free(&p->model);
  free(p->cand_values);
  free(p->cand_enc);
  free(p->cand_da);
  free(p->cand_daf);
  free(p->pool_values);
  free(p->pool_enc);
  free(p->pool_reward);
  free(p->pool_da);
  free(p->pool_daf);
  free(p->phi);
  free(p->x);
  tt__pm_table_clear(&p->table);
  p->cand_values = p->cand_enc = p->cand_da = NULL;
  p->pool_values = p->pool_enc = p->pool_reward = p->pool_da = NULL;
  p->cand_daf = p->pool_daf = NULL;
  p->phi = p->x = NULL;
  p->ncand = p->npool = 0;
}

static void tt__rbf_destroy(tt_predictor *p) {
  if (!p) return;
  tt__rbf_free_model_parts(p);
  free(p->state_space);
  if (p->names)
    for (uint32_t i = 0; i < p->d; i++) free(p->names[i]);
  free(p->names);
  free(p->signature);
  free(p);
}

/* Draws the LHS candidates from the seed (every point through the space's check: repaired
 * points kept repaired, infeasible ones dropped). 0 or -1 when out of memory. */
static int tt__rbf_make_candidates(tt_predictor *p) {
  size_t n = (size_t)p->set.lhs, np = p->params ? p->params : 1;
  p->cand_values = malloc((n ? n : 1) * np * sizeof(double));
  p->cand_enc = malloc((n ? n : 1) * (p->m ? p->m : 1) * sizeof(double));
  p->cand_da = malloc((n ? n : 1) * p->model.features * sizeof(double));
  p->cand_daf = malloc((n ? n : 1) * tt__rbf_f8(p->model.features) * sizeof(float));
  double *unit = malloc((n ? n : 1) * np * sizeof(double));
  tt_config *c = tt_config_create(p->target);
  if (!p->cand_values || !p->cand_enc || !p->cand_da || !p->cand_daf || !unit || !c) {
    free(unit);
    tt_config_destroy(c);
    return -1;
  }
  tt__rbf_lhs(p->seed ^ 0x63616e646964ull, (uint32_t)n, (uint32_t)p->params, unit);
  p->ncand = 0;
  char why[128];
  for (size_t k = 0; k < n; k++) {
    tt_config_from_unit(c, unit + k * p->params);
    if (tt_space_check(p->target, c, why, sizeof why) == TT_CHECK_INFEASIBLE) continue;
    tt__pm_config_values(c, p->cand_values + p->ncand * p->params);
    tt__rbf_encode_action(c, p->cand_enc + p->ncand * p->m);
    tt__rbf_action_part(&p->model, p->cand_enc + p->ncand * p->m,
                        p->cand_da + p->ncand * p->model.features);
    tt__rbf_action_part_float(p->model.features, p->cand_da + p->ncand * p->model.features,
                              p->cand_daf + p->ncand * tt__rbf_f8(p->model.features));
    p->ncand++;
  }
  free(unit);
  tt_config_destroy(c);
  return 0;
}

/* Allocates the model, candidates, pool and scratch for p->set; 0 or -1. */
/* Features of a model: the setting, or 3.5 x (state values + parameters) for 0. */
static uint32_t tt__rbf_feature_count(const tt_predictor *p) {
  uint32_t f = p->set.features > 0 ? (uint32_t)p->set.features
                                   : (uint32_t)lround(3.5 * (double)(p->d + p->params));
  return f ? f : 1;
}

static int tt__rbf_alloc(tt_predictor *p) {
  uint32_t f = tt__rbf_feature_count(p);
  if (tt__rbf_model_init(&p->model, p->d, p->m, f, p->set.width, p->set.alpha, p->set.decay,
                         p->seed ^ 0x63656e747265ull))
    return -1;
  size_t pool = (size_t)p->set.pool ? (size_t)p->set.pool : 1;
  p->pool_values = malloc(pool * (p->params ? p->params : 1) * sizeof(double));
  p->pool_enc = malloc(pool * (p->m ? p->m : 1) * sizeof(double));
  p->pool_reward = malloc(pool * sizeof(double));
  p->pool_da = malloc(pool * f * sizeof(double));
  p->pool_daf = malloc(pool * tt__rbf_f8(f) * sizeof(float));
  p->phi = malloc(f * sizeof(double));
  p->x = malloc((p->d + p->m) * sizeof(double));
  tt__pm_table_init(&p->table, p->d, p->params, 0);
  if (!p->pool_values || !p->pool_enc || !p->pool_reward || !p->pool_da || !p->pool_daf ||
      !p->phi || !p->x)
    return -1;
  return tt__rbf_make_candidates(p);
}

static tt_status tt__rbf_create_ex(const tt_predictor_setup *su, tt_predictor **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__RBF_NAME ": create: out is NULL");
  *out = NULL;
  if (!su || !TT_HAS_FIELD(tt_predictor_setup, su, seed) || !su->target)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__RBF_NAME ": create: no target space");
  if (su->state_dim < 1 || su->state_dim > 4096)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__RBF_NAME ": create: state dimension %u outside "
                                     "[1, 4096]",
                        su->state_dim);
  tt_predictor *p = calloc(1, sizeof *p);
  if (!p) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__RBF_NAME ": out of memory");
  p->target = su->target;
  p->params = tt_space_count(su->target);
  p->d = su->state_dim;
  p->m = tt__rbf_action_dims(su->target);
  p->seed = su->seed;
  tt__rbf_read_settings(su->settings, &p->set);
  p->state_space = tt__strdup(su->state_space ? su->state_space : "");
  p->signature = tt__pm_space_signature(su->target);
  int bad = !p->state_space || !p->signature;
  if (su->state_names && !bad) {
    p->names = calloc(p->d, sizeof *p->names);
    bad = !p->names;
    for (uint32_t i = 0; !bad && i < p->d; i++) {
      const char *name = su->state_names[i] ? su->state_names[i] : ""; /* unnamed: "" */
      bad = !(p->names[i] = tt__strdup(name));
    }
  }
  if (bad || tt__rbf_alloc(p)) {
    tt__rbf_destroy(p);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__RBF_NAME ": out of memory");
  }
  *out = p;
  return TT_OK;
}

static tt_status tt__rbf_create(const tt_space *target, uint32_t state_dim,
                                const tt_config *settings, uint64_t seed, tt_predictor **out) {
  tt_predictor_setup su = {.struct_size = sizeof su,
                           .target = target,
                           .state_dim = state_dim,
                           .settings = settings,
                           .seed = seed};
  return tt__rbf_create_ex(&su, out);
}

/* The reward of a sample, or NAN when it cannot be learnt (relative without a default). */
static double tt__rbf_reward(const tt_predictor *p, double cost, double default_cost) {
  if (cost >= TT_COST_INFEASIBLE) return 0.0;
  if (p->set.reward == TT__RBF_REWARD_INVERSE) return 1.0 / cost;
  if (!(default_cost > 0) || default_cost >= TT_COST_INFEASIBLE || !isfinite(default_cost))
    return NAN;
  return default_cost / cost;
}

/* Puts a configuration (its values and encoding) into pool slot `slot` with the cached action
 * parts of its distances to the centres. */
static void tt__rbf_pool_put(tt_predictor *p, size_t slot, const double *values, const double *enc,
                             double reward) {
  memcpy(p->pool_values + slot * p->params, values, p->params * sizeof(double));
  memcpy(p->pool_enc + slot * p->m, enc, p->m * sizeof(double));
  tt__rbf_action_part(&p->model, enc, p->pool_da + slot * p->model.features);
  tt__rbf_action_part_float(p->model.features, p->pool_da + slot * p->model.features,
                            p->pool_daf + slot * tt__rbf_f8(p->model.features));
  p->pool_reward[slot] = reward;
}

/* poolSource = rewards: keeps the configuration in the pool if its reward ranks among the
 * `pool` best (an equal configuration keeps its highest reward). */
static void tt__rbf_pool_add(tt_predictor *p, const double *values, const double *enc,
                             double reward) {
  size_t np = p->params;
  for (size_t k = 0; k < p->npool; k++)
    if (!memcmp(p->pool_values + k * np, values, np * sizeof(double))) {
      if (reward > p->pool_reward[k]) p->pool_reward[k] = reward;
      return;
    }
  size_t slot = p->npool;
  if (p->npool == (size_t)p->set.pool) {
    slot = 0; /* replace the lowest reward if this one is higher */
    for (size_t k = 1; k < p->npool; k++)
      if (p->pool_reward[k] < p->pool_reward[slot]) slot = k;
    if (!(reward > p->pool_reward[slot]) || p->set.pool == 0) return;
  } else {
    p->npool++;
  }
  tt__rbf_pool_put(p, slot, values, enc, reward);
}

/* A distinct best configuration of the state table: the first state it is best in and how
 * many states it is best in. */
typedef struct tt__rbf_state_best {
  size_t first, states;
} tt__rbf_state_best;

static int tt__rbf_state_best_order(const void *a, const void *b) {
  const tt__rbf_state_best *x = a, *y = b;
  if (x->states != y->states) return x->states > y->states ? -1 : 1;
  return x->first < y->first ? -1 : x->first > y->first;
}

/* poolSource = states: the pool becomes the distinct best configurations of the observed
 * states (each state's lowest mean cost, i.e. what a search there found), those that are
 * best in the most states first (ties: the state observed first), at most poolSize of them;
 * pool_reward holds the number of states each is best in. Deterministic in the table, so a
 * loaded model rebuilds the same pool. 0, or -1 when out of memory. */
static int tt__rbf_pool_from_states(tt_predictor *p) {
  const tt__pm_table *t = &p->table;
  tt__rbf_state_best *d = malloc((t->n ? t->n : 1) * sizeof *d);
  double *enc = malloc((p->m ? p->m : 1) * sizeof(double));
  tt_config *c = tt_config_create(p->target);
  if (!d || !enc || !c) {
    free(d);
    free(enc);
    tt_config_destroy(c);
    return -1;
  }
  size_t nd = 0;
  for (size_t i = 0; i < t->n; i++) {
    const double *v = tt__pm_table_best(t, i)->values;
    size_t k = 0;
    while (k < nd &&
           memcmp(tt__pm_table_best(t, d[k].first)->values, v, p->params * sizeof(double)))
      k++;
    if (k == nd) d[nd++] = (tt__rbf_state_best){i, 0};
    d[k].states++;
  }
  qsort(d, nd, sizeof *d, tt__rbf_state_best_order);
  size_t keep = nd < (size_t)p->set.pool ? nd : (size_t)p->set.pool;
  char why[128];
  p->npool = 0;
  for (size_t k = 0; k < keep; k++) {
    const double *v = tt__pm_table_best(t, d[k].first)->values;
    if (tt__pm_config_from_values(c, v, why, sizeof why)) continue; /* checked when added */
    tt__rbf_encode_action(c, enc);
    tt__rbf_pool_put(p, p->npool++, v, enc, (double)d[k].states);
  }
  free(d);
  free(enc);
  tt_config_destroy(c);
  return 0;
}

/* One validated sample: updates theta and the pool. */
static void tt__rbf_learn(tt_predictor *p, const tt_predictor_sample *s, double reward,
                          double *values) {
  memcpy(p->x, s->state, p->d * sizeof(double));
  tt__rbf_encode_action(s->config, p->x + p->d);
  tt__rbf_update(&p->model, p->x, reward, p->phi);
  if (reward > 0 && p->set.pool_source == TT__RBF_POOL_REWARDS) {
    tt__pm_config_values(s->config, values);
    tt__rbf_pool_add(p, values, p->x + p->d, reward);
  }
  p->observations++;
}

static tt_status tt__rbf_observe_ex(tt_predictor *p, const tt_predictor_sample *s, size_t count,
                                    uint32_t flags) {
  if (!p || (!s && count))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__RBF_NAME ": observe: NULL argument");
  for (size_t i = 0; i < count; i++) {
    if (!TT_HAS_FIELD(tt_predictor_sample, &s[i], default_cost))
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          TT__RBF_NAME ": observe: sample %zu is too short", i);
    if (!s[i].state || !s[i].config)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          TT__RBF_NAME ": observe: sample %zu has no state "
                                       "or configuration",
                          i);
    if (tt_space_count(tt_config_space(s[i].config)) != p->params)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          TT__RBF_NAME ": observe: sample %zu: the "
                                       "configuration is not of the target space",
                          i);
    for (uint32_t k = 0; k < p->d; k++)
      if (!isfinite(s[i].state[k]))
        return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                            TT__RBF_NAME ": observe: sample %zu: state value "
                                         "%u is not finite",
                            i, k);
    if (isnan(s[i].cost) || (s[i].cost < TT_COST_INFEASIBLE && !(s[i].cost > 0)))
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          TT__RBF_NAME ": observe: sample %zu: cost %g is "
                                       "not a finite positive number",
                          i, s[i].cost);
  }
  double *values = malloc((p->params ? p->params : 1) * sizeof(double));
  size_t *order = malloc((count ? count : 1) * sizeof *order);
  if (!values || !order) {
    free(values);
    free(order);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__RBF_NAME ": out of memory");
  }
  if (p->set.pool_source == TT__RBF_POOL_STATES) {
    /* the table learns each sample once, whatever the passes of the update below; the
     * pool is rebuilt only when a state's best changed (a new state, another best) */
    int changed = 0;
    for (size_t i = 0; i < count; i++) {
      if (s[i].cost >= TT_COST_INFEASIBLE) continue;
      /* the model's own answers (TT_PREDICTOR_EXPLOIT) train Q below, but enter the table
       * (the candidate actions) only for states it holds from searches */
      if ((flags & TT_PREDICTOR_EXPLOIT) && tt__pm_table_find(&p->table, s[i].state) == SIZE_MAX)
        continue;
      tt__pm_config_values(s[i].config, values);
      if (tt__pm_table_add(&p->table, s[i].state, values, s[i].cost, &changed) == SIZE_MAX) {
        free(values);
        free(order);
        return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__RBF_NAME ": out of memory");
      }
    }
    if (changed && tt__rbf_pool_from_states(p)) {
      free(values);
      free(order);
      return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__RBF_NAME ": out of memory");
    }
  }
  int64_t passes = flags & TT_PREDICTOR_OFFLINE ? p->set.epochs : 1;
  tt__pcg32 rng;
  tt__pcg32_seed(&rng, p->seed ^ p->model.updates, 0x73687566ull); /* "shuf" */
  for (size_t i = 0; i < count; i++) order[i] = i;
  for (int64_t e = 0; e < passes; e++) {
    if (flags & TT_PREDICTOR_OFFLINE)
      for (size_t i = count; i > 1; i--) { /* Fisher-Yates, 64-bit draws */
        uint64_t r = ((uint64_t)tt__pcg32_next(&rng) << 32 | tt__pcg32_next(&rng)) % i;
        size_t t = order[i - 1];
        order[i - 1] = order[r];
        order[r] = t;
      }
    for (size_t i = 0; i < count; i++) {
      const tt_predictor_sample *x = &s[order[i]];
      double reward = tt__rbf_reward(p, x->cost, x->default_cost);
      if (isnan(reward)) continue;
      tt__rbf_learn(p, x, reward, values);
    }
  }
  free(values);
  free(order);
  return TT_OK;
}

static tt_status tt__rbf_observe(tt_predictor *p, const double *state, const tt_config *config,
                                 double cost) {
  tt_predictor_sample s = {
      .struct_size = sizeof s, .state = state, .config = config, .cost = cost, .default_cost = NAN};
  return tt__rbf_observe_ex(p, &s, 1, TT_PREDICTOR_ONLINE);
}

/* Expected cost of a value Q under the reward (NAN when it says nothing). */
static double tt__rbf_cost_of(const tt_predictor *p, double q, double default_cost) {
  if (!(q > 0)) return NAN;
  if (p->set.reward == TT__RBF_REWARD_INVERSE) return 1.0 / q;
  return default_cost > 0 && isfinite(default_cost) ? default_cost / q : NAN;
}

/* One candidate of the argmax: its values and encoding in scratch, its Q. */
typedef struct tt__rbf_best {
  double q;
  size_t src; /* index into the candidate list of the first phase */
} tt__rbf_best;

static tt_status tt__rbf_predict_ex(const tt_predictor *p, const tt_predictor_query *q,
                                    tt_config *out, tt_predictor_result *res) {
  if (!p || !q || !q->state || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__RBF_NAME ": predict: NULL argument");
  if (!p->observations)
    return tt_set_error(TT_ERR_NO_DATA, TT__RBF_NAME ": predict: nothing observed yet");
  for (uint32_t k = 0; k < p->d; k++)
    if (!isfinite(q->state[k]))
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          TT__RBF_NAME ": predict: state value %u is not finite", k);
  const tt__rbf_model *r = &p->model;
  size_t np = p->params ? p->params : 1, m = p->m ? p->m : 1;
  size_t n1 = p->npool + p->ncand + 1, starts = (size_t)p->set.starts;
  int refine = p->set.refine > 0;
  double *ds = malloc(2 * (size_t)r->features * sizeof(double)), *dd = ds + r->features;
  double *defv = malloc(np * sizeof(double)), *defe = malloc(m * sizeof(double));
  double *unit = malloc(np * sizeof(double));
  double *best_vals = malloc(np * sizeof(double)), *try_enc = malloc(m * sizeof(double));
  /* without refinement: the bounded argmax's rows and scratch; with it: every candidate's
   * values, encoding and Q (the starts and the coordinate search need them) */
  uint32_t f8 = tt__rbf_f8(r->features);
  const double **rows = refine ? NULL : malloc(n1 * sizeof *rows);
  const float **frows = refine ? NULL : malloc(n1 * sizeof *frows);
  float *ddf = refine ? NULL : malloc(f8 * sizeof(float));
  double *work = refine ? NULL : malloc(tt__rbf_argmax_work(r->features, n1) * sizeof(double));
  double *vals = refine ? malloc(n1 * np * sizeof(double)) : NULL;
  double *enc = refine ? malloc(n1 * m * sizeof(double)) : NULL;
  double *qs = refine ? malloc(n1 * sizeof(double)) : NULL;
  size_t *top = refine ? malloc((starts ? starts : 1) * sizeof *top) : NULL;
  tt_config *c = tt_config_create(p->target);
  tt_status st = TT_OK;
  if (!ds || !defv || !defe || !unit || !best_vals || !try_enc || !c ||
      (refine ? !vals || !enc || !qs || !top : !rows || !frows || !ddf || !work)) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__RBF_NAME ": out of memory");
    goto done;
  }
  tt__rbf_state_part(r, q->state, ds);
  /* phase 1: the pool, the LHS candidates and the default (the last candidate). The action
   * parts are cached per pool entry and LHS candidate, computed here for the default. */
  size_t n = n1, bi = 0, nt = 0;
  double best_q = -INFINITY;
  tt__pm_config_values(c, defv); /* c holds the defaults */
  tt__rbf_encode_action(c, defe);
  tt__rbf_action_part(r, defe, dd);
  if (!refine) {
    /* the first maximum of tt__rbf_q_parts over the candidates, bit for bit, with Q evaluated
     * exactly only where the approximate bounds cannot decide (rbf_argmax.h) */
    for (size_t k = 0; k < p->npool; k++) {
      rows[k] = p->pool_da + k * r->features;
      frows[k] = p->pool_daf + k * f8;
    }
    for (size_t k = 0; k < p->ncand; k++) {
      rows[p->npool + k] = p->cand_da + k * r->features;
      frows[p->npool + k] = p->cand_daf + k * f8;
    }
    tt__rbf_action_part_float(r->features, dd, ddf);
    rows[n - 1] = dd;
    frows[n - 1] = ddf;
    bi = tt__rbf_argmax_bounded(r, ds, rows, frows, n, NULL, work, &best_q, NULL);
    const double *v = bi < p->npool              ? p->pool_values + bi * p->params
                      : bi < p->npool + p->ncand ? p->cand_values + (bi - p->npool) * p->params
                                                 : defv;
    memcpy(best_vals, v, p->params * sizeof(double));
  } else {
    memcpy(vals, p->pool_values, p->npool * p->params * sizeof(double));
    memcpy(enc, p->pool_enc, p->npool * p->m * sizeof(double));
    memcpy(vals + p->npool * p->params, p->cand_values, p->ncand * p->params * sizeof(double));
    memcpy(enc + p->npool * p->m, p->cand_enc, p->ncand * p->m * sizeof(double));
    memcpy(vals + (n - 1) * p->params, defv, p->params * sizeof(double));
    memcpy(enc + (n - 1) * p->m, defe, p->m * sizeof(double));
    for (size_t k = 0; k < p->npool; k++)
      qs[k] = tt__rbf_q_parts(r, ds, p->pool_da + k * r->features);
    for (size_t k = 0; k < p->ncand; k++)
      qs[p->npool + k] = tt__rbf_q_parts(r, ds, p->cand_da + k * r->features);
    qs[n - 1] = tt__rbf_q_parts(r, ds, dd);
    /* the `starts` best, highest first (ties: lowest index) */
    for (; nt < starts && nt < n; nt++) {
      size_t b = SIZE_MAX;
      for (size_t k = 0; k < n; k++) {
        int taken = 0;
        for (size_t j = 0; j < nt && !taken; j++) taken = top[j] == k;
        if (!taken && (b == SIZE_MAX || qs[k] > qs[b])) b = k;
      }
      top[nt] = b;
    }
    for (size_t k = 0; k < n; k++)
      if (qs[k] > best_q) best_q = qs[k], bi = k;
    memcpy(best_vals, vals + bi * p->params, p->params * sizeof(double));
  }
  uint64_t evaluated = n;
  /* phase 2: coordinate search from each start */
  char why[128];
  for (size_t t = 0; t < nt; t++) {
    double cur_q = qs[top[t]];
    if (tt__pm_config_from_values(c, vals + top[t] * p->params, why, sizeof why)) continue;
    tt_config_to_unit(c, unit);
    double step = 0.125;
    for (int64_t round = 0; round < p->set.refine; round++, step *= 0.5) {
      for (size_t i = 0; i < p->params; i++) {
        size_t alts =
            tt_space_type(p->target, i) == TT_PARAM_NOM ? tt_space_nom_count(p->target, i) : 2;
        double keep = unit[i], best_u = keep;
        for (size_t a = 0; a < alts; a++) {
          double u;
          if (tt_space_type(p->target, i) == TT_PARAM_NOM) {
            u = ((double)a + 0.5) / (double)alts;
            if (fabs(u - keep) < 0.5 / (double)alts) continue; /* the current value */
          } else {
            u = keep + (a ? step : -step);
            u = u < 0 ? 0 : u > 1 ? 1 : u;
            if (u == keep) continue;
          }
          unit[i] = u;
          tt_config_from_unit(c, unit);
          if (tt_space_check(p->target, c, why, sizeof why) == TT_CHECK_INFEASIBLE) continue;
          tt__rbf_encode_action(c, try_enc);
          double qa = tt__rbf_q_action(r, ds, try_enc);
          evaluated++;
          if (qa > cur_q) {
            cur_q = qa;
            best_u = u;
            if (qa > best_q) {
              best_q = qa;
              tt__pm_config_values(c, best_vals);
            }
          }
        }
        unit[i] = best_u;
      }
    }
  }
  if (tt__pm_config_from_values(out, best_vals, why, sizeof why)) {
    st = tt_set_error(TT_ERR_INTERNAL, TT__RBF_NAME ": predict: %s", why);
    goto done;
  }
  if (res && TT_HAS_FIELD(tt_predictor_result, res, candidates)) {
    res->expected_cost = tt__rbf_cost_of(p, best_q, q->default_cost);
    res->value = best_q;
    res->distance = NAN;
    res->candidates = evaluated;
  }
done:
  free(ds);
  free(defv);
  free(defe);
  free(rows);
  free(frows);
  free(ddf);
  free(work);
  free(vals);
  free(enc);
  free(qs);
  free(unit);
  free(best_vals);
  free(try_enc);
  free(top);
  tt_config_destroy(c);
  return st;
}

static tt_status tt__rbf_predict(const tt_predictor *p, const double *state, tt_config *out,
                                 double *expected_cost) {
  tt_predictor_query q = {.struct_size = sizeof q, .state = state, .default_cost = NAN};
  tt_predictor_result r = {.struct_size = sizeof r};
  tt_status st = tt__rbf_predict_ex(p, &q, out, &r);
  if (expected_cost) *expected_cost = st == TT_OK ? r.expected_cost : NAN;
  return st;
}

static tt_status tt__rbf_estimate(const tt_predictor *p, const tt_predictor_query *q,
                                  const tt_config *config, double *cost) {
  if (!p || !q || !q->state || !config || !cost)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__RBF_NAME ": estimate: NULL argument");
  double *x = malloc((p->d + p->m) * sizeof(double));
  if (!x) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__RBF_NAME ": out of memory");
  memcpy(x, q->state, p->d * sizeof(double));
  tt__rbf_encode_action(config, x + p->d);
  *cost = tt__rbf_cost_of(p, tt__rbf_q(&p->model, x), q->default_cost);
  free(x);
  return TT_OK;
}

static tt_status tt__rbf_info(const tt_predictor *p, tt_predictor_info *out) {
  if (!p || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__RBF_NAME ": info: NULL argument");
  uint64_t f = p->model.features, dim = p->model.dim, pool = (uint64_t)p->set.pool;
  uint64_t bytes = sizeof *p + f * (dim + 2) * sizeof(double) + (p->d + p->m) * sizeof(double) +
                   p->ncand * (p->params + p->m + f) * sizeof(double) +
                   pool * (p->params + p->m + 1 + f) * sizeof(double) +
                   (p->ncand + pool) * tt__rbf_f8((uint32_t)f) * sizeof(float) +
                   tt__pm_table_bytes(&p->table);
  if (TT_HAS_FIELD(tt_predictor_info, out, format_version)) {
    out->memory_bytes = bytes;
    out->entries = f;
    out->observations = p->observations;
    out->format_version = TT__RBF_FORMAT;
  }
  return TT_OK;
}

/* ---- files ---- */

static tt_status tt__rbf_save(const tt_predictor *p, const char *path) {
  if (!p || !path)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__RBF_NAME ": save: NULL argument");
  char *settings = tt__rbf_settings_json(&p->set);
  tt__pm_header h = {.kind = TT__RBF_NAME,
                     .plugin_version = TT__RBF_VERSION,
                     .state_space = p->state_space,
                     .state_dim = p->d,
                     .state_names = p->names,
                     .target = p->signature,
                     .settings = settings};
  tt__pm_writer w = {0};
  const tt__rbf_model *r = &p->model;
  tt__pm_put_header(&w, &h);
  tt__pm_put_u64(&w, p->seed);
  tt__pm_put_u64(&w, p->params);
  tt__pm_put_u64(&w, p->m);
  tt__pm_put_u64(&w, r->features);
  tt__pm_put_u64(&w, r->updates);
  tt__pm_put_u64(&w, p->observations);
  tt__pm_put_f64s(&w, r->centres, (size_t)r->features * r->dim);
  tt__pm_put_f64s(&w, r->theta, r->features);
  if (p->set.pool_source == TT__RBF_POOL_STATES) {
    tt__pm_put_u64(&w, 0); /* the pool is rebuilt from the table on load */
    tt__pm_table_put(&w, &p->table);
  } else {
    tt__pm_put_u64(&w, p->npool);
    tt__pm_put_f64s(&w, p->pool_values, p->npool * p->params);
    tt__pm_put_f64s(&w, p->pool_reward, p->npool);
  }
  tt_status st = settings ? tt__pm_save(TT__RBF_NAME, path, TT__RBF_FORMAT, &w)
                          : tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__RBF_NAME ": out of memory");
  tt_free(settings);
  free(w.data);
  return st;
}

static tt_status tt__rbf_load(tt_predictor *p, const char *path) {
  if (!p || !path)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__RBF_NAME ": load: NULL argument");
  unsigned char *data;
  size_t len;
  uint32_t version;
  tt_status st =
      tt__pm_load(TT__RBF_NAME, TT__RBF_VERSION, path, TT__RBF_FORMAT, &data, &len, &version);
  if (st != TT_OK) return st;
  tt__pm_reader rd = {.data = data, .len = len, .path = path};
  tt__pm_header h;
  if (tt__pm_get_header(&rd, &h)) {
    st = tt_set_error(TT_ERR_PARSE, TT__RBF_NAME ": model %s", rd.err);
    free(data);
    return st;
  }
  char diff[400];
  st = TT_OK;
  if (strcmp(h.kind, TT__RBF_NAME)) {
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT,
                      TT__RBF_NAME ": model %s was written by %s %s, not by " TT__RBF_NAME
                                   " (load it with --plugin %s)",
                      path, h.kind, h.plugin_version, h.kind);
  } else if (h.state_dim != p->d || strcmp(h.state_space, p->state_space)) {
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT,
                      TT__RBF_NAME ": model %s is for states \"%s\" of %u "
                                   "values, but this predictor gets states \"%s\" of %u values",
                      path, h.state_space, h.state_dim, p->state_space, p->d);
  } else if (strcmp(h.target, p->signature)) {
    tt__pm_signature_diff(h.target, p->signature, diff, sizeof diff);
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT,
                      TT__RBF_NAME
                      ": model %s predicts configurations of "
                      "another parameter space: the file's %s; this one's %s (first difference: "
                      "%s)",
                      path, h.target, p->signature, diff);
  }
  if (st != TT_OK) {
    tt__pm_header_free(&h);
    free(data);
    return st;
  }
  /* build the loaded model beside the current one; swap only when all of it read */
  tt_predictor tmp = *p;
  tmp.cand_values = tmp.cand_enc = tmp.cand_da = NULL;
  tmp.pool_values = tmp.pool_enc = tmp.pool_reward = tmp.pool_da = NULL;
  tmp.cand_daf = tmp.pool_daf = NULL;
  tmp.phi = tmp.x = NULL;
  tt__pm_table_init(&tmp.table, p->d, p->params, 0);
  memset(&tmp.model, 0, sizeof tmp.model);
  tt_config *sc = tt_config_create(tt__rbf_settings);
  if (!sc || tt_config_from_json(sc, h.settings, path) != TT_OK)
    tt__pm_fail(&rd, "settings: %s", sc ? tt_last_error() : "out of memory");
  else tt__rbf_read_settings(sc, &tmp.set);
  tt_config_destroy(sc);
  if (version < 2) tmp.set.pool_source = TT__RBF_POOL_REWARDS; /* version 1 had no state table */
  tmp.seed = tt__pm_get_u64(&rd, "the seed");
  uint64_t params = tt__pm_get_u64(&rd, "the parameter count");
  uint64_t m = tt__pm_get_u64(&rd, "the action dimension");
  uint64_t f = tt__pm_get_u64(&rd, "the feature count");
  uint64_t updates = tt__pm_get_u64(&rd, "the update count");
  uint64_t obs = tt__pm_get_u64(&rd, "the observation count");
  if (!rd.err[0] && (params != p->params || m != p->m))
    tt__pm_fail(&rd, "%llu parameters / %llu action coordinates, the target space has %zu / %u",
                (unsigned long long)params, (unsigned long long)m, p->params, p->m);
  if (!rd.err[0] && f != tt__rbf_feature_count(&tmp))
    tt__pm_fail(&rd, "feature count %llu does not match the settings (%u)", (unsigned long long)f,
                tt__rbf_feature_count(&tmp));
  if (!rd.err[0] && f * (p->d + p->m + 1) * 8 > rd.len - rd.pos)
    tt__pm_fail(&rd, "file cut short: %llu features need %llu bytes, %zu left",
                (unsigned long long)f, (unsigned long long)(f * (p->d + p->m + 1) * 8),
                rd.len - rd.pos);
  if (!rd.err[0] && tt__rbf_alloc(&tmp)) tt__pm_fail(&rd, "out of memory");
  if (!rd.err[0]) {
    tt__pm_get_f64s(&rd, tmp.model.centres, (size_t)f * tmp.model.dim, "the centres");
    tt__pm_get_f64s(&rd, tmp.model.theta, (size_t)f, "theta");
    tmp.model.updates = updates;
    for (size_t i = 0; !rd.err[0] && i < (size_t)f * tmp.model.dim; i++)
      if (!isfinite(tmp.model.centres[i]))
        tt__pm_fail(&rd, "centre coordinate %zu is not finite", i);
    for (size_t i = 0; !rd.err[0] && i < (size_t)f; i++)
      if (!isfinite(tmp.model.theta[i])) tt__pm_fail(&rd, "theta[%zu] is not finite", i);
    for (size_t k = 0; !rd.err[0] && k < tmp.ncand; k++) { /* the file's centres */
      tt__rbf_action_part(&tmp.model, tmp.cand_enc + k * p->m, tmp.cand_da + k * f);
      tt__rbf_action_part_float((uint32_t)f, tmp.cand_da + k * f,
                                tmp.cand_daf + k * tt__rbf_f8((uint32_t)f));
    }
  }
  uint64_t npool =
      tt__pm_get_count(&rd, (uint64_t)tmp.set.pool, (p->params + 1) * 8, "pool entries");
  tt_config *c = tt_config_create(p->target);
  char why[256];
  for (uint64_t k = 0; !rd.err[0] && k < npool; k++) {
    double *v = tmp.pool_values + k * p->params;
    tt__pm_get_f64s(&rd, v, p->params, "a pool configuration");
    if (!rd.err[0] && (!c || tt__pm_config_from_values(c, v, why, sizeof why)))
      tt__pm_fail(&rd, "pool configuration %llu: %s", (unsigned long long)k,
                  c ? why : "out of memory");
    if (!rd.err[0]) {
      tt__rbf_encode_action(c, tmp.pool_enc + k * p->m);
      tt__rbf_action_part(&tmp.model, tmp.pool_enc + k * p->m, tmp.pool_da + k * f);
      tt__rbf_action_part_float((uint32_t)f, tmp.pool_da + k * f,
                                tmp.pool_daf + k * tt__rbf_f8((uint32_t)f));
    }
  }
  if (!rd.err[0]) {
    tt__pm_get_f64s(&rd, tmp.pool_reward, (size_t)npool, "the pool rewards");
    tmp.npool = (size_t)npool;
    /* a pool holds positive rewards only (tt__rbf_learn; +inf where a cost underflows); a NaN
     * would never compare lower and so never leave the pool */
    for (size_t k = 0; !rd.err[0] && k < tmp.npool; k++)
      if (!(tmp.pool_reward[k] > 0))
        tt__pm_fail(&rd, "pool reward %zu is %g, expected a positive number", k,
                    tmp.pool_reward[k]);
  }
  if (!rd.err[0] && tmp.set.pool_source == TT__RBF_POOL_STATES) {
    if (npool)
      tt__pm_fail(&rd,
                  "%llu pool entries stored beside the state table (poolSource states "
                  "stores none)",
                  (unsigned long long)npool);
    if (!rd.err[0] && !tt__pm_table_get(&rd, &tmp.table, p->target) &&
        tt__rbf_pool_from_states(&tmp))
      tt__pm_fail(&rd, "out of memory");
  }
  tt_config_destroy(c);
  if (!rd.err[0] && rd.pos != rd.len)
    tt__pm_fail(&rd, "%zu bytes after the %s", rd.len - rd.pos,
                tmp.set.pool_source == TT__RBF_POOL_STATES ? "state table" : "pool");
  tt__pm_header_free(&h);
  free(data);
  if (rd.err[0]) {
    tt__rbf_free_model_parts(&tmp);
    return tt_set_error(TT_ERR_PARSE, TT__RBF_NAME ": model %s", rd.err);
  }
  tmp.observations = obs;
  tt__rbf_free_model_parts(p);
  *p = tmp;
  return TT_OK;
}

/* ---- plugin ---- */

static const tt_predictor_iface tt__rbf_iface = {
    .struct_size = sizeof(tt_predictor_iface),
    .space = tt__rbf_space,
    .create = tt__rbf_create,
    .observe = tt__rbf_observe,
    .predict = tt__rbf_predict,
    .save = tt__rbf_save,
    .load = tt__rbf_load,
    .destroy = tt__rbf_destroy,
    .create_ex = tt__rbf_create_ex,
    .observe_ex = tt__rbf_observe_ex,
    .predict_ex = tt__rbf_predict_ex,
    .info = tt__rbf_info,
    .estimate = tt__rbf_estimate,
};

static tt_status tt__rbf_init(const tt_host *host) {
  (void)host;
  tt_space *s = tt__rbf_settings = tt_space_create(TT__RBF_NAME, TT__RBF_VERSION);
  int ok = s != NULL;
  ok = ok && tt_space_add_int(s, "features", 0, 1 << 20, 0,
                              "RBF features; 0: 3.5 x (state "
                              "values + parameters), the thesis' rule (100 for its 28)") >= 0;
  ok = ok && tt_space_add_float(s, "width", 0.01, 100.0, 1.0, 1,
                                "omega of phi_i(x) = exp(-omega ||x - c_i||) (thesis: 1)") >= 0;
  ok = ok && tt_space_add_float(s, "alpha", 1e-6, 10.0, 0.1, 1, "Greedy-GQ step size") >= 0;
  ok = ok && tt_space_add_float(s, "decay", 0.0, 1e12, 0.0, 0,
                                "updates after which the step "
                                "has halved, alpha / (1 + t / decay); 0: constant") >= 0;
  ok = ok && tt_space_add_int(s, "epochs", 1, 10000, 10,
                              "passes over offline data (a tuning "
                              "DB), each in a fresh shuffled order") >= 0;
  ok = ok && tt_space_add_nom_string(s, "reward", tt__rbf_reward_names, 2, 1,
                                     "inverse: R = 1/cost "
                                     "(thesis); relative: R = default cost / cost (the "
                                     "validated default)") >= 0;
  ok = ok &&
       tt_space_add_int(s, "lhsCandidates", 0, 1 << 20, 0,
                        "Latin-hypercube candidate "
                        "actions of the argmax (0: the pool only, the validated default)") >= 0;
  ok = ok && tt_space_add_int(s, "poolSize", 0, 1 << 20, 256,
                              "observed configurations kept "
                              "as candidates") >= 0;
  ok = ok && tt_space_add_nom_string(s, "poolSource", tt__rbf_pool_names, 2, 1,
                                     "rewards: the "
                                     "poolSize configurations with the highest single reward; "
                                     "states: each observed state's best configuration (lowest "
                                     "mean cost), those best in most states first (the "
                                     "validated default)") >= 0;
  ok = ok && tt_space_add_int(s, "refine", 0, 64, 0,
                              "rounds of coordinate search around the "
                              "best candidates (0: none, the validated default)") >= 0;
  ok = ok && tt_space_add_int(s, "refineStarts", 0, 1024, 4,
                              "candidates the coordinate search "
                              "starts from") >= 0;
  if (!ok) {
    tt_space_destroy(s);
    tt__rbf_settings = NULL;
    return tt_set_error(TT_ERR_INTERNAL, TT__RBF_NAME ": cannot build the settings space");
  }
  return TT_OK;
}

static void tt__rbf_deinit(void) {
  tt_space_destroy(tt__rbf_settings);
  tt__rbf_settings = NULL;
}

static const void *tt__rbf_get_interface(const char *id) {
  return strcmp(id, TT_PREDICTOR_INTERFACE_ID) == 0 ? &tt__rbf_iface : NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
    .struct_size = sizeof(tt_plugin),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .kind = TT_KIND_PREDICTOR,
    .name = TT__RBF_NAME,
    .version = TT__RBF_VERSION,
    .description = "RBF features with myopic Greedy-GQ: argmax_a theta.phi(s, a) (thesis 3.3.2)",
    .init = tt__rbf_init,
    .deinit = tt__rbf_deinit,
    .get_interface = tt__rbf_get_interface,
};
