/* predictor_nn: the nearest-neighbour predictor of thesis 3.3.2 ("record a table of previous
 * states, configurations, and the observed runtime ... If the current state is unknown,
 * respond with the best configuration for the state that is closest regarding the distance
 * metric (Euclidean in our case)").
 *
 * The table holds, per distinct state, every distinct configuration observed there with the
 * sum and count of its costs; a state's answer is the configuration with the lowest mean
 * cost (ties: the one observed first), the same rule the host uses to keep its best
 * (host/README.md: a configuration re-measured against noise is judged by its mean, so one
 * lucky pass does not win). A query returns the answer of the nearest stored state (ties:
 * the state stored first); a stored state is found at distance 0 and returns exactly its
 * configuration. States are compared as given: the caller normalises them
 * (tunetrace/indicators.h). Infeasible observations are skipped: they are never an answer.
 * The table holds what searches found (thesis 3.3.5.1): an observation of the model's own
 * answer (TT_PREDICTOR_EXPLOIT: an exploited state of the hybrid loop) updates the costs of
 * a state the table already holds, and is otherwise not stored, so an exploited state never
 * becomes the nearest neighbour that answers the next one.
 *
 * maxStates (0: unbounded) caps the table: once full, a new state's observations are added
 * to its nearest stored state, so the table becomes a quantisation of the states seen first.
 * The model-size sweep of tools/hybrid varies it.
 *
 * Model files: predictor_common/model_file.h, payload version 1 (see tt__nn_save).
 */
#include "../predictor_common/model_file.h"
#include "../predictor_common/state_table.h"

#include <tunetrace/plugin.h>
#include <tunetrace/predictor.h>
#include <tt_util/strings.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TT__NN_NAME "predictor_nn"
#define TT__NN_VERSION "0.1.0"
#define TT__NN_FORMAT 1u

static tt_space *tt__nn_settings;

struct tt_predictor {
  const tt_space *target;
  size_t params; /* parameters of target */
  uint32_t dim;
  char *state_space;
  char **names;       /* dim names or NULL */
  char *signature;    /* tt__pm_space_signature(target) */
  tt__pm_table table; /* the stored states (predictor_common/state_table.h) */
  uint64_t observations;
};

/* ---- model ---- */

static void tt__nn_clear(tt_predictor *p) {
  tt__pm_table_clear(&p->table);
  p->observations = 0;
}

static void tt__nn_destroy(tt_predictor *p) {
  if (!p) return;
  tt__nn_clear(p);
  free(p->state_space);
  if (p->names)
    for (uint32_t i = 0; i < p->dim; i++) free(p->names[i]);
  free(p->names);
  free(p->signature);
  free(p);
}

static const tt_space *tt__nn_space(void) { return tt__nn_settings; }

static tt_status tt__nn_create_ex(const tt_predictor_setup *su, tt_predictor **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": create: out is NULL");
  *out = NULL;
  if (!su || !TT_HAS_FIELD(tt_predictor_setup, su, seed) || !su->target)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": create: no target space");
  if (su->state_dim < 1 || su->state_dim > 4096)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__NN_NAME ": create: state dimension %u outside "
                                    "[1, 4096]",
                        su->state_dim);
  int64_t max_states = su->settings ? tt_config_get_int(su->settings, "maxStates", 0) : 0;
  tt_predictor *p = calloc(1, sizeof *p);
  if (!p) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__NN_NAME ": out of memory");
  p->target = su->target;
  p->params = tt_space_count(su->target);
  p->dim = su->state_dim;
  tt__pm_table_init(&p->table, p->dim, p->params, max_states);
  p->state_space = tt__strdup(su->state_space ? su->state_space : "");
  p->signature = tt__pm_space_signature(su->target);
  int bad = !p->state_space || !p->signature;
  if (su->state_names && !bad) {
    p->names = calloc(p->dim, sizeof *p->names);
    bad = !p->names;
    for (uint32_t i = 0; !bad && i < p->dim; i++) {
      const char *name = su->state_names[i] ? su->state_names[i] : ""; /* unnamed: "" */
      bad = !(p->names[i] = tt__strdup(name));
    }
  }
  if (bad) {
    tt__nn_destroy(p);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__NN_NAME ": out of memory");
  }
  *out = p;
  return TT_OK;
}

static tt_status tt__nn_create(const tt_space *target, uint32_t state_dim,
                               const tt_config *settings, uint64_t seed, tt_predictor **out) {
  tt_predictor_setup su = {.struct_size = sizeof su,
                           .target = target,
                           .state_dim = state_dim,
                           .settings = settings,
                           .seed = seed};
  return tt__nn_create_ex(&su, out);
}

/* Adds one validated observation; TT_OK or out of memory. */
static tt_status tt__nn_add(tt_predictor *p, const double *state, const double *values,
                            double cost) {
  if (tt__pm_table_add(&p->table, state, values, cost, NULL) == SIZE_MAX)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__NN_NAME ": out of memory");
  p->observations++;
  return TT_OK;
}

/* Checks one sample; 1 = learn it, 0 = skip (infeasible), or an error status < 0. */
static int tt__nn_check_sample(const tt_predictor *p, const double *state, const tt_config *config,
                               double cost) {
  if (!state || !config)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__NN_NAME ": observe: NULL state or configuration");
  if (tt_config_space(config) != p->target && tt_space_count(tt_config_space(config)) != p->params)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__NN_NAME ": observe: the configuration is not of "
                                    "the target space");
  for (uint32_t i = 0; i < p->dim; i++)
    if (!isfinite(state[i]))
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          TT__NN_NAME ": observe: state value %u is not "
                                      "finite",
                          i);
  if (cost >= TT_COST_INFEASIBLE) return 0;
  if (!(cost > 0) || !isfinite(cost))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__NN_NAME ": observe: cost %g is not a finite "
                                    "positive number",
                        cost);
  return 1;
}

static tt_status tt__nn_observe_ex(tt_predictor *p, const tt_predictor_sample *s, size_t count,
                                   uint32_t flags) {
  /* a table learns the same from a data set and from a stream; the model's own answers
   * (TT_PREDICTOR_EXPLOIT) only refine states the table holds from searches: stored as
   * states of their own they would be the nearest state of the next state along a path,
   * which would then get the same answer again, and so on for the whole path */
  int exploit = (flags & TT_PREDICTOR_EXPLOIT) != 0;
  if (!p || (!s && count))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": observe: NULL argument");
  for (size_t i = 0; i < count; i++) {
    if (!TT_HAS_FIELD(tt_predictor_sample, &s[i], cost))
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": observe: sample %zu is too short",
                          i);
    int ok = tt__nn_check_sample(p, s[i].state, s[i].config, s[i].cost);
    if (ok < 0) return (tt_status)ok;
  }
  double *v = malloc((p->params ? p->params : 1) * sizeof(double));
  if (!v) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__NN_NAME ": out of memory");
  for (size_t i = 0; i < count; i++) {
    if (s[i].cost >= TT_COST_INFEASIBLE) continue;
    if (exploit && tt__pm_table_find(&p->table, s[i].state) == SIZE_MAX) continue;
    tt__pm_config_values(s[i].config, v);
    tt_status st = tt__nn_add(p, s[i].state, v, s[i].cost);
    if (st != TT_OK) {
      free(v);
      return st;
    }
  }
  free(v);
  return TT_OK;
}

static tt_status tt__nn_observe(tt_predictor *p, const double *state, const tt_config *config,
                                double cost) {
  tt_predictor_sample s = {
      .struct_size = sizeof s, .state = state, .config = config, .cost = cost, .default_cost = NAN};
  return tt__nn_observe_ex(p, &s, 1, TT_PREDICTOR_ONLINE);
}

static tt_status tt__nn_predict_ex(const tt_predictor *p, const tt_predictor_query *q,
                                   tt_config *out, tt_predictor_result *res) {
  if (!p || !q || !q->state || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": predict: NULL argument");
  if (!p->table.n)
    return tt_set_error(TT_ERR_NO_DATA,
                        TT__NN_NAME ": predict: the table is empty (nothing observed)");
  double d2;
  size_t i = tt__pm_table_nearest(&p->table, q->state, &d2);
  if (i == SIZE_MAX)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": predict: the state is not finite");
  const tt__pm_table_cfg *best = tt__pm_table_best(&p->table, i);
  char why[256];
  if (tt__pm_config_from_values(out, best->values, why, sizeof why))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": predict: %s", why);
  if (res && TT_HAS_FIELD(tt_predictor_result, res, candidates)) {
    res->expected_cost = tt__pm_table_mean(best);
    res->value = NAN;
    res->distance = sqrt(d2);
    res->candidates = p->table.n;
  }
  return TT_OK;
}

static tt_status tt__nn_predict(const tt_predictor *p, const double *state, tt_config *out,
                                double *expected_cost) {
  tt_predictor_query q = {.struct_size = sizeof q, .state = state, .default_cost = NAN};
  tt_predictor_result r = {.struct_size = sizeof r};
  tt_status st = tt__nn_predict_ex(p, &q, out, &r);
  if (expected_cost) *expected_cost = st == TT_OK ? r.expected_cost : NAN;
  return st;
}

static tt_status tt__nn_estimate(const tt_predictor *p, const tt_predictor_query *q,
                                 const tt_config *config, double *cost) {
  if (!p || !q || !q->state || !config || !cost)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": estimate: NULL argument");
  *cost = NAN;
  size_t i = tt__pm_table_nearest(&p->table, q->state, NULL);
  if (i == SIZE_MAX) return TT_OK;
  double *v = malloc((p->params ? p->params : 1) * sizeof(double));
  if (!v) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__NN_NAME ": out of memory");
  tt__pm_config_values(config, v);
  size_t k = tt__pm_table_find_cfg(&p->table, i, v);
  if (k != SIZE_MAX) *cost = tt__pm_table_mean(&p->table.entries[i].cfgs[k]);
  free(v);
  return TT_OK;
}

static tt_status tt__nn_info(const tt_predictor *p, tt_predictor_info *out) {
  if (!p || !out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": info: NULL argument");
  uint64_t bytes = sizeof *p + tt__pm_table_bytes(&p->table);
  if (TT_HAS_FIELD(tt_predictor_info, out, format_version)) {
    out->memory_bytes = bytes;
    out->entries = p->table.n;
    out->observations = p->observations;
    out->format_version = TT__NN_FORMAT;
  }
  return TT_OK;
}

/* ---- files ---- */

static char *tt__nn_settings_json(const tt_predictor *p) {
  tt_config *c = tt_config_create(tt__nn_settings);
  if (!c) return NULL;
  tt_config_set_number(c, (size_t)tt_space_find(tt__nn_settings, "maxStates"),
                       (double)p->table.max_states);
  char *j = tt_config_to_json(c);
  tt_config_destroy(c);
  return j;
}

static tt_status tt__nn_save(const tt_predictor *p, const char *path) {
  if (!p || !path)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": save: NULL argument");
  char *settings = tt__nn_settings_json(p);
  tt__pm_header h = {.kind = TT__NN_NAME,
                     .plugin_version = TT__NN_VERSION,
                     .state_space = p->state_space,
                     .state_dim = p->dim,
                     .state_names = p->names,
                     .target = p->signature,
                     .settings = settings};
  tt__pm_writer w = {0};
  tt__pm_put_header(&w, &h);
  tt__pm_put_u64(&w, p->params);
  tt__pm_put_u64(&w, p->observations);
  tt__pm_table_put(&w, &p->table);
  tt_status st = settings ? tt__pm_save(TT__NN_NAME, path, TT__NN_FORMAT, &w)
                          : tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__NN_NAME ": out of memory");
  tt_free(settings);
  free(w.data);
  return st;
}

/* Checks the file's header against the model it is loaded into (kind, state space,
 * target); 0 or -1 with a message naming both sides. */
static int tt__nn_check_header(const tt_predictor *p, const tt__pm_header *h, const char *path) {
  char diff[400];
  if (strcmp(h->kind, TT__NN_NAME)) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 TT__NN_NAME ": model %s was written by %s %s, not by " TT__NN_NAME
                             " (load it with --plugin %s)",
                 path, h->kind, h->plugin_version, h->kind);
    return -1;
  }
  if (h->state_dim != p->dim || strcmp(h->state_space, p->state_space)) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 TT__NN_NAME ": model %s is for states \"%s\" of %u values, "
                             "but this predictor gets states \"%s\" of %u values",
                 path, h->state_space, h->state_dim, p->state_space, p->dim);
    return -1;
  }
  if (strcmp(h->target, p->signature)) {
    tt__pm_signature_diff(h->target, p->signature, diff, sizeof diff);
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 TT__NN_NAME ": model %s predicts configurations of another "
                             "parameter space: the file's %s; this one's %s (first difference: %s)",
                 path, h->target, p->signature, diff);
    return -1;
  }
  return 0;
}

static tt_status tt__nn_load(tt_predictor *p, const char *path) {
  if (!p || !path)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__NN_NAME ": load: NULL argument");
  unsigned char *data;
  size_t len;
  uint32_t version;
  tt_status st =
      tt__pm_load(TT__NN_NAME, TT__NN_VERSION, path, TT__NN_FORMAT, &data, &len, &version);
  if (st != TT_OK) return st;
  tt__pm_reader r = {.data = data, .len = len, .path = path};
  tt__pm_header h;
  if (tt__pm_get_header(&r, &h)) {
    st = tt_set_error(TT_ERR_PARSE, TT__NN_NAME ": model %s", r.err);
    free(data);
    return st;
  }
  if (tt__nn_check_header(p, &h, path)) {
    tt__pm_header_free(&h);
    free(data);
    return TT_ERR_INVALID_ARGUMENT;
  }
  /* into a fresh model: on any error the loaded-into one is left as it was */
  tt_predictor tmp = *p;
  tmp.observations = 0;
  int64_t max_states = 0;
  tt_config *s = tt_config_create(tt__nn_settings);
  if (!s || tt_config_from_json(s, h.settings, path) != TT_OK)
    tt__pm_fail(&r, "settings: %s", s ? tt_last_error() : "out of memory");
  else max_states = tt_config_get_int(s, "maxStates", 0);
  tt_config_destroy(s);
  tt__pm_table_init(&tmp.table, p->dim, p->params, max_states);
  uint64_t params = tt__pm_get_u64(&r, "the parameter count");
  if (!r.err[0] && params != p->params)
    tt__pm_fail(&r, "%llu parameters per configuration, the target space has %zu",
                (unsigned long long)params, p->params);
  uint64_t obs = tt__pm_get_u64(&r, "the observation count");
  if (!r.err[0]) tt__pm_table_get(&r, &tmp.table, p->target);
  if (!r.err[0] && r.pos != r.len) tt__pm_fail(&r, "%zu bytes after the last state", r.len - r.pos);
  tt__pm_header_free(&h);
  free(data);
  if (r.err[0]) {
    tt__pm_table_clear(&tmp.table);
    return tt_set_error(TT_ERR_PARSE, TT__NN_NAME ": model %s", r.err);
  }
  tmp.observations = obs;
  tt__nn_clear(p);
  *p = tmp;
  return TT_OK;
}

/* ---- plugin ---- */

static const tt_predictor_iface tt__nn_iface = {
    .struct_size = sizeof(tt_predictor_iface),
    .space = tt__nn_space,
    .create = tt__nn_create,
    .observe = tt__nn_observe,
    .predict = tt__nn_predict,
    .save = tt__nn_save,
    .load = tt__nn_load,
    .destroy = tt__nn_destroy,
    .create_ex = tt__nn_create_ex,
    .observe_ex = tt__nn_observe_ex,
    .predict_ex = tt__nn_predict_ex,
    .info = tt__nn_info,
    .estimate = tt__nn_estimate,
};

static tt_status tt__nn_init(const tt_host *host) {
  (void)host;
  tt__nn_settings = tt_space_create(TT__NN_NAME, TT__NN_VERSION);
  if (!tt__nn_settings ||
      tt_space_add_int(tt__nn_settings, "maxStates", 0, INT64_C(1000000000), 0,
                       "largest number of stored states (0: unbounded); once full, a new state "
                       "is merged into its nearest stored state") < 0) {
    tt_space_destroy(tt__nn_settings);
    tt__nn_settings = NULL;
    return tt_set_error(TT_ERR_INTERNAL, TT__NN_NAME ": cannot build the settings space");
  }
  return TT_OK;
}

static void tt__nn_deinit(void) {
  tt_space_destroy(tt__nn_settings);
  tt__nn_settings = NULL;
}

static const void *tt__nn_get_interface(const char *id) {
  return strcmp(id, TT_PREDICTOR_INTERFACE_ID) == 0 ? &tt__nn_iface : NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
    .struct_size = sizeof(tt_plugin),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .kind = TT_KIND_PREDICTOR,
    .name = TT__NN_NAME,
    .version = TT__NN_VERSION,
    .description = "nearest neighbour: the best configuration of the nearest stored state "
                   "(thesis 3.3.2)",
    .init = tt__nn_init,
    .deinit = tt__nn_deinit,
    .get_interface = tt__nn_get_interface,
};
