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
 *
 * maxStates (0: unbounded) caps the table: once full, a new state's observations are added
 * to its nearest stored state, so the table becomes a quantisation of the states seen first.
 * The model-size sweep of tools/hybrid varies it.
 *
 * Model files: predictor_common/model_file.h, payload version 1 (see nn_save).
 */
#include "../predictor_common/model_file.h"

#include <tunetrace/plugin.h>
#include <tunetrace/predictor.h>
#include <tt_util/strings.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NN_NAME "predictor_nn"
#define NN_VERSION "0.1.0"
#define NN_FORMAT 1u

static tt_space *nn_settings;

typedef struct nn_cfg {
  double *values;     /* ttpm_config_values of the configuration */
  double sum;         /* sum of its costs */
  uint64_t count;
} nn_cfg;

typedef struct nn_entry {
  double *state;      /* dim values */
  nn_cfg *cfgs;
  size_t ncfg, cap;
  size_t best;        /* index of the lowest mean cost */
} nn_entry;

struct tt_predictor {
  const tt_space *target;
  size_t params;            /* parameters of target */
  uint32_t dim;
  char *state_space;
  char **names;             /* dim names or NULL */
  char *signature;          /* ttpm_space_signature(target) */
  int64_t max_states;
  nn_entry *entries;
  size_t n, cap;
  uint64_t observations;
};

/* ---- model ---- */

static void nn_clear(tt_predictor *p) {
  for (size_t i = 0; i < p->n; i++) {
    for (size_t k = 0; k < p->entries[i].ncfg; k++) free(p->entries[i].cfgs[k].values);
    free(p->entries[i].cfgs);
    free(p->entries[i].state);
  }
  free(p->entries);
  p->entries = NULL;
  p->n = p->cap = 0;
  p->observations = 0;
}

static void nn_destroy(tt_predictor *p) {
  if (!p) return;
  nn_clear(p);
  free(p->state_space);
  if (p->names)
    for (uint32_t i = 0; i < p->dim; i++) free(p->names[i]);
  free(p->names);
  free(p->signature);
  free(p);
}

static const tt_space *nn_space(void) { return nn_settings; }

static tt_status nn_create_ex(const tt_predictor_setup *su, tt_predictor **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": create: out is NULL");
  *out = NULL;
  if (!su || su->struct_size < offsetof(tt_predictor_setup, seed) + sizeof su->seed || !su->target)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": create: no target space");
  if (su->state_dim < 1 || su->state_dim > 4096)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": create: state dimension %u outside "
                        "[1, 4096]", su->state_dim);
  int64_t max_states = su->settings ? tt_config_get_int(su->settings, "maxStates", 0) : 0;
  tt_predictor *p = calloc(1, sizeof *p);
  if (!p) return tt_set_error(TT_ERR_OUT_OF_MEMORY, NN_NAME ": out of memory");
  p->target = su->target;
  p->params = tt_space_count(su->target);
  p->dim = su->state_dim;
  p->max_states = max_states;
  p->state_space = tt__strdup(su->state_space ? su->state_space : "");
  p->signature = ttpm_space_signature(su->target);
  int bad = !p->state_space || !p->signature;
  if (su->state_names && !bad) {
    p->names = calloc(p->dim, sizeof *p->names);
    bad = !p->names;
    for (uint32_t i = 0; !bad && i < p->dim; i++) {
      const char *name = su->state_names[i] ? su->state_names[i] : "";  /* unnamed: "" */
      bad = !(p->names[i] = tt__strdup(name));
    }
  }
  if (bad) {
    nn_destroy(p);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, NN_NAME ": out of memory");
  }
  *out = p;
  return TT_OK;
}

static tt_status nn_create(const tt_space *target, uint32_t state_dim, const tt_config *settings,
                           uint64_t seed, tt_predictor **out) {
  tt_predictor_setup su = {.struct_size = sizeof su, .target = target, .state_dim = state_dim,
                           .settings = settings, .seed = seed};
  return nn_create_ex(&su, out);
}

/* Squared Euclidean distance. */
static double nn_dist2(const double *a, const double *b, uint32_t n) {
  double d = 0;
  for (uint32_t i = 0; i < n; i++) d += (a[i] - b[i]) * (a[i] - b[i]);
  return d;
}

/* Index of the nearest stored state (first on ties), or SIZE_MAX when empty. */
static size_t nn_nearest(const tt_predictor *p, const double *state, double *dist2) {
  size_t best = SIZE_MAX;
  double bd = INFINITY;
  for (size_t i = 0; i < p->n; i++) {
    double d = nn_dist2(p->entries[i].state, state, p->dim);
    if (d < bd) {
      bd = d;
      best = i;
    }
  }
  if (dist2) *dist2 = bd;
  return best;
}

/* Index of an entry whose state equals `state` exactly, or SIZE_MAX. */
static size_t nn_find(const tt_predictor *p, const double *state) {
  for (size_t i = 0; i < p->n; i++) {
    uint32_t k = 0;
    while (k < p->dim && p->entries[i].state[k] == state[k]) k++;
    if (k == p->dim) return i;
  }
  return SIZE_MAX;
}

static double nn_mean(const nn_cfg *c) { return c->sum / (double)c->count; }

static void nn_update_best(nn_entry *e) {
  size_t b = 0;
  for (size_t k = 1; k < e->ncfg; k++)
    if (nn_mean(&e->cfgs[k]) < nn_mean(&e->cfgs[b])) b = k;
  e->best = b;
}

/* Adds one validated observation; TT_OK or out of memory (nothing changed then). */
static tt_status nn_add(tt_predictor *p, const double *state, const double *values, double cost) {
  size_t i = nn_find(p, state);
  if (i == SIZE_MAX && p->max_states > 0 && p->n >= (size_t)p->max_states)
    i = nn_nearest(p, state, NULL);
  if (i == SIZE_MAX) {
    if (p->n == p->cap) {
      size_t cap = p->cap ? 2 * p->cap : 64;
      nn_entry *e = realloc(p->entries, cap * sizeof *e);
      if (!e) return tt_set_error(TT_ERR_OUT_OF_MEMORY, NN_NAME ": out of memory");
      p->entries = e;
      p->cap = cap;
    }
    nn_entry *e = &p->entries[p->n];
    memset(e, 0, sizeof *e);
    e->state = malloc(p->dim * sizeof(double));
    if (!e->state) return tt_set_error(TT_ERR_OUT_OF_MEMORY, NN_NAME ": out of memory");
    memcpy(e->state, state, p->dim * sizeof(double));
    i = p->n++;
  }
  nn_entry *e = &p->entries[i];
  size_t k = 0;
  while (k < e->ncfg && memcmp(e->cfgs[k].values, values, p->params * sizeof(double))) k++;
  if (k == e->ncfg) {
    if (e->ncfg == e->cap) {
      size_t cap = e->cap ? 2 * e->cap : 8;
      nn_cfg *c = realloc(e->cfgs, cap * sizeof *c);
      if (!c) return tt_set_error(TT_ERR_OUT_OF_MEMORY, NN_NAME ": out of memory");
      e->cfgs = c;
      e->cap = cap;
    }
    double *v = malloc((p->params ? p->params : 1) * sizeof(double));
    if (!v) return tt_set_error(TT_ERR_OUT_OF_MEMORY, NN_NAME ": out of memory");
    memcpy(v, values, p->params * sizeof(double));
    e->cfgs[k] = (nn_cfg){v, 0.0, 0};
    e->ncfg++;
  }
  e->cfgs[k].sum += cost;
  e->cfgs[k].count++;
  nn_update_best(e);
  p->observations++;
  return TT_OK;
}

/* Checks one sample; 1 = learn it, 0 = skip (infeasible), or an error status < 0. */
static int nn_check_sample(const tt_predictor *p, const double *state, const tt_config *config,
                           double cost) {
  if (!state || !config)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": observe: NULL state or configuration");
  if (tt_config_space(config) != p->target &&
      tt_space_count(tt_config_space(config)) != p->params)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": observe: the configuration is not of "
                        "the target space");
  for (uint32_t i = 0; i < p->dim; i++)
    if (!isfinite(state[i]))
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": observe: state value %u is not "
                          "finite", i);
  if (cost >= TT_COST_INFEASIBLE) return 0;
  if (!(cost > 0) || !isfinite(cost))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": observe: cost %g is not a finite "
                        "positive number", cost);
  return 1;
}

static tt_status nn_observe_ex(tt_predictor *p, const tt_predictor_sample *s, size_t count,
                               uint32_t flags) {
  (void)flags; /* a table learns the same from a data set and from a stream */
  if (!p || (!s && count)) return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": observe: NULL argument");
  for (size_t i = 0; i < count; i++) {
    if (s[i].struct_size < offsetof(tt_predictor_sample, cost) + sizeof s[i].cost)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": observe: sample %zu is too short", i);
    int ok = nn_check_sample(p, s[i].state, s[i].config, s[i].cost);
    if (ok < 0) return (tt_status)ok;
  }
  double *v = malloc((p->params ? p->params : 1) * sizeof(double));
  if (!v) return tt_set_error(TT_ERR_OUT_OF_MEMORY, NN_NAME ": out of memory");
  for (size_t i = 0; i < count; i++) {
    if (s[i].cost >= TT_COST_INFEASIBLE) continue;
    ttpm_config_values(s[i].config, v);
    tt_status st = nn_add(p, s[i].state, v, s[i].cost);
    if (st != TT_OK) {
      free(v);
      return st;
    }
  }
  free(v);
  return TT_OK;
}

static tt_status nn_observe(tt_predictor *p, const double *state, const tt_config *config,
                            double cost) {
  tt_predictor_sample s = {.struct_size = sizeof s, .state = state, .config = config,
                           .cost = cost, .default_cost = NAN};
  return nn_observe_ex(p, &s, 1, TT_PREDICTOR_ONLINE);
}

static tt_status nn_predict_ex(const tt_predictor *p, const tt_predictor_query *q, tt_config *out,
                               tt_predictor_result *res) {
  if (!p || !q || !q->state || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": predict: NULL argument");
  if (!p->n) return tt_set_error(TT_ERR_NO_DATA, NN_NAME ": predict: the table is empty (nothing observed)");
  double d2;
  size_t i = nn_nearest(p, q->state, &d2);
  if (i == SIZE_MAX)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": predict: the state is not finite");
  const nn_entry *e = &p->entries[i];
  char why[256];
  if (ttpm_config_from_values(out, e->cfgs[e->best].values, why, sizeof why))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": predict: %s", why);
  if (res && res->struct_size >= offsetof(tt_predictor_result, candidates) + sizeof res->candidates) {
    res->expected_cost = nn_mean(&e->cfgs[e->best]);
    res->value = NAN;
    res->distance = sqrt(d2);
    res->candidates = p->n;
  }
  return TT_OK;
}

static tt_status nn_predict(const tt_predictor *p, const double *state, tt_config *out,
                            double *expected_cost) {
  tt_predictor_query q = {.struct_size = sizeof q, .state = state, .default_cost = NAN};
  tt_predictor_result r = {.struct_size = sizeof r};
  tt_status st = nn_predict_ex(p, &q, out, &r);
  if (expected_cost) *expected_cost = st == TT_OK ? r.expected_cost : NAN;
  return st;
}

static tt_status nn_estimate(const tt_predictor *p, const tt_predictor_query *q,
                             const tt_config *config, double *cost) {
  if (!p || !q || !q->state || !config || !cost)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": estimate: NULL argument");
  *cost = NAN;
  size_t i = nn_nearest(p, q->state, NULL);
  if (i == SIZE_MAX) return TT_OK;
  double *v = malloc((p->params ? p->params : 1) * sizeof(double));
  if (!v) return tt_set_error(TT_ERR_OUT_OF_MEMORY, NN_NAME ": out of memory");
  ttpm_config_values(config, v);
  const nn_entry *e = &p->entries[i];
  for (size_t k = 0; k < e->ncfg; k++)
    if (!memcmp(e->cfgs[k].values, v, p->params * sizeof(double))) *cost = nn_mean(&e->cfgs[k]);
  free(v);
  return TT_OK;
}

static tt_status nn_info(const tt_predictor *p, tt_predictor_info *out) {
  if (!p || !out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": info: NULL argument");
  uint64_t bytes = sizeof *p + p->cap * sizeof(nn_entry);
  for (size_t i = 0; i < p->n; i++) {
    bytes += p->dim * sizeof(double) + p->entries[i].cap * sizeof(nn_cfg);
    bytes += p->entries[i].ncfg * p->params * sizeof(double);
  }
  if (out->struct_size >= offsetof(tt_predictor_info, format_version) + sizeof out->format_version) {
    out->memory_bytes = bytes;
    out->entries = p->n;
    out->observations = p->observations;
    out->format_version = NN_FORMAT;
  }
  return TT_OK;
}

/* ---- files ---- */

static char *nn_settings_json(const tt_predictor *p) {
  tt_config *c = tt_config_create(nn_settings);
  if (!c) return NULL;
  tt_config_set_number(c, (size_t)tt_space_find(nn_settings, "maxStates"), (double)p->max_states);
  char *j = tt_config_to_json(c);
  tt_config_destroy(c);
  return j;
}

static tt_status nn_save(const tt_predictor *p, const char *path) {
  if (!p || !path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": save: NULL argument");
  char *settings = nn_settings_json(p);
  ttpm_header h = {.kind = NN_NAME, .plugin_version = NN_VERSION, .state_space = p->state_space,
                   .state_dim = p->dim, .state_names = p->names, .target = p->signature,
                   .settings = settings};
  ttpm_writer w = {0};
  ttpm_put_header(&w, &h);
  ttpm_put_u64(&w, p->params);
  ttpm_put_u64(&w, p->observations);
  ttpm_put_u64(&w, p->n);
  for (size_t i = 0; i < p->n; i++) {
    const nn_entry *e = &p->entries[i];
    ttpm_put_f64s(&w, e->state, p->dim);
    ttpm_put_u64(&w, e->ncfg);
    for (size_t k = 0; k < e->ncfg; k++) {
      ttpm_put_f64s(&w, e->cfgs[k].values, p->params);
      ttpm_put_f64(&w, e->cfgs[k].sum);
      ttpm_put_u64(&w, e->cfgs[k].count);
    }
  }
  tt_status st = settings ? ttpm_save(NN_NAME, path, NN_FORMAT, &w)
                          : tt_set_error(TT_ERR_OUT_OF_MEMORY, NN_NAME ": out of memory");
  tt_free(settings);
  free(w.data);
  return st;
}

/* Checks the file's header against the model it is loaded into (kind, state space,
 * target); 0 or -1 with a message naming both sides. */
static int nn_check_header(const tt_predictor *p, const ttpm_header *h, const char *path) {
  char diff[400];
  if (strcmp(h->kind, NN_NAME)) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": model %s was written by %s %s, not by "
                 NN_NAME " (load it with --plugin %s)", path, h->kind, h->plugin_version, h->kind);
    return -1;
  }
  if (h->state_dim != p->dim || strcmp(h->state_space, p->state_space)) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": model %s is for states \"%s\" of %u values, "
                 "but this predictor gets states \"%s\" of %u values", path, h->state_space,
                 h->state_dim, p->state_space, p->dim);
    return -1;
  }
  if (strcmp(h->target, p->signature)) {
    ttpm_signature_diff(h->target, p->signature, diff, sizeof diff);
    tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": model %s predicts configurations of another "
                 "parameter space: the file's %s; this one's %s (first difference: %s)", path,
                 h->target, p->signature, diff);
    return -1;
  }
  return 0;
}

static tt_status nn_load(tt_predictor *p, const char *path) {
  if (!p || !path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, NN_NAME ": load: NULL argument");
  unsigned char *data;
  size_t len;
  uint32_t version;
  tt_status st = ttpm_load(NN_NAME, NN_VERSION, path, NN_FORMAT, &data, &len, &version);
  if (st != TT_OK) return st;
  ttpm_reader r = {.data = data, .len = len, .path = path};
  ttpm_header h;
  if (ttpm_get_header(&r, &h)) {
    st = tt_set_error(TT_ERR_PARSE, NN_NAME ": model %s", r.err);
    free(data);
    return st;
  }
  if (nn_check_header(p, &h, path)) {
    ttpm_header_free(&h);
    free(data);
    return TT_ERR_INVALID_ARGUMENT;
  }
  /* into a fresh model: on any error the loaded-into one is left as it was */
  tt_predictor tmp = *p;
  tmp.entries = NULL;
  tmp.n = tmp.cap = 0;
  tmp.observations = 0;
  tmp.max_states = 0; /* no merging while the stored table is rebuilt */
  int64_t max_states = 0;
  tt_config *s = tt_config_create(nn_settings);
  if (!s || tt_config_from_json(s, h.settings, path) != TT_OK)
    ttpm_fail(&r, "settings: %s", s ? tt_last_error() : "out of memory");
  else
    max_states = tt_config_get_int(s, "maxStates", 0);
  tt_config_destroy(s);
  uint64_t params = ttpm_get_u64(&r, "the parameter count");
  if (!r.err[0] && params != p->params)
    ttpm_fail(&r, "%llu parameters per configuration, the target space has %zu",
              (unsigned long long)params, p->params);
  uint64_t obs = ttpm_get_u64(&r, "the observation count");
  size_t per_state = p->dim * 8 + 8;
  uint64_t n = ttpm_get_count(&r, UINT32_MAX, per_state, "states");
  double *v = malloc((p->params ? p->params : 1) * sizeof(double));
  double *state = malloc(p->dim * sizeof(double));
  if (!v || !state) ttpm_fail(&r, "out of memory");
  char why[256];
  tt_config *check = tt_config_create(p->target);
  for (uint64_t i = 0; !r.err[0] && i < n; i++) {
    ttpm_get_f64s(&r, state, p->dim, "a state");
    for (uint32_t k = 0; !r.err[0] && k < p->dim; k++)
      if (!isfinite(state[k])) ttpm_fail(&r, "state %llu has a non-finite value", (unsigned long long)i);
    if (!r.err[0] && nn_find(&tmp, state) != SIZE_MAX)
      ttpm_fail(&r, "state %llu is stored twice", (unsigned long long)i);
    uint64_t ncfg = ttpm_get_count(&r, UINT32_MAX, p->params * 8 + 16, "configurations");
    if (!r.err[0] && ncfg == 0) ttpm_fail(&r, "state %llu has no configuration", (unsigned long long)i);
    for (uint64_t k = 0; !r.err[0] && k < ncfg; k++) {
      ttpm_get_f64s(&r, v, p->params, "a configuration");
      double sum = ttpm_get_f64(&r, "a cost sum");
      uint64_t count = ttpm_get_u64(&r, "a cost count");
      if (r.err[0]) break;
      if (!check || ttpm_config_from_values(check, v, why, sizeof why)) {
        ttpm_fail(&r, "state %llu, configuration %llu: %s", (unsigned long long)i,
                  (unsigned long long)k, check ? why : "out of memory");
        break;
      }
      if (!(sum > 0) || !isfinite(sum) || count == 0) {
        ttpm_fail(&r, "state %llu, configuration %llu: cost sum %g over %llu measurements is not "
                  "a positive finite mean", (unsigned long long)i, (unsigned long long)k, sum,
                  (unsigned long long)count);
        break;
      }
      /* rebuild exactly: one add with the whole sum, then the count */
      if (nn_add(&tmp, state, v, sum) != TT_OK) {
        ttpm_fail(&r, "out of memory");
        break;
      }
      nn_entry *e = &tmp.entries[tmp.n - 1];
      size_t j = e->ncfg - 1;
      if (memcmp(e->state, state, p->dim * sizeof(double)) || e->cfgs[j].count != 1) {
        ttpm_fail(&r, "state %llu: configuration %llu is stored twice", (unsigned long long)i,
                  (unsigned long long)k);
        break;
      }
      e->cfgs[j].count = count;
      nn_update_best(e);
    }
  }
  if (!r.err[0] && r.pos != r.len) ttpm_fail(&r, "%zu bytes after the last state", r.len - r.pos);
  tt_config_destroy(check);
  free(v);
  free(state);
  ttpm_header_free(&h);
  free(data);
  if (r.err[0]) {
    nn_clear(&tmp);
    return tt_set_error(TT_ERR_PARSE, NN_NAME ": model %s", r.err);
  }
  tmp.observations = obs;
  tmp.max_states = max_states;
  nn_clear(p);
  *p = tmp;
  return TT_OK;
}

/* ---- plugin ---- */

static const tt_predictor_iface nn_iface = {
  .struct_size = sizeof(tt_predictor_iface),
  .space = nn_space,
  .create = nn_create,
  .observe = nn_observe,
  .predict = nn_predict,
  .save = nn_save,
  .load = nn_load,
  .destroy = nn_destroy,
  .create_ex = nn_create_ex,
  .observe_ex = nn_observe_ex,
  .predict_ex = nn_predict_ex,
  .info = nn_info,
  .estimate = nn_estimate,
};

static tt_status nn_init(const tt_host *host) {
  (void)host;
  nn_settings = tt_space_create(NN_NAME, NN_VERSION);
  if (!nn_settings ||
      tt_space_add_int(nn_settings, "maxStates", 0, INT64_C(1000000000), 0,
                       "largest number of stored states (0: unbounded); once full, a new state "
                       "is merged into its nearest stored state") < 0) {
    tt_space_destroy(nn_settings);
    nn_settings = NULL;
    return tt_set_error(TT_ERR_INTERNAL, NN_NAME ": cannot build the settings space");
  }
  return TT_OK;
}

static void nn_deinit(void) {
  tt_space_destroy(nn_settings);
  nn_settings = NULL;
}

static const void *nn_get_interface(const char *id) {
  return strcmp(id, TT_PREDICTOR_INTERFACE_ID) == 0 ? &nn_iface : NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
  .struct_size = sizeof(tt_plugin),
  .abi_major = TT_ABI_MAJOR,
  .abi_minor = TT_ABI_MINOR,
  .kind = TT_KIND_PREDICTOR,
  .name = NN_NAME,
  .version = NN_VERSION,
  .description = "nearest neighbour: the best configuration of the nearest stored state "
                 "(thesis 3.3.2)",
  .init = nn_init,
  .deinit = nn_deinit,
  .get_interface = nn_get_interface,
};
