/* predictor_static: the best static configuration, as a predictor plugin written the way a
 * third party writes one (only <tunetrace/...> headers and libtunetrace, built with
 * pkg-config: see Makefile and README.md).
 *
 * It ignores the state in its answer: it predicts the one configuration that was best over
 * all states it saw, which is the baseline a per-state model has to beat ("always use the
 * best static configuration"). A configuration's score is the geometric mean, over the
 * states where it was observed, of cost / the state's default cost (its typical speed-up),
 * so cheap and expensive states weigh alike; samples without a default cost are scored by
 * their cost relative to the first cost seen in that state. Only configurations observed in
 * at least `minShare` of the states compete (one lucky state does not make a configuration
 * "static"); if none qualifies, the most widely observed ones do.
 *
 * Uses the ABI 1.1 table (create_ex, observe_ex, predict_ex, info, estimate); a host of ABI
 * 1.0 still gets the 1.0 functions. Model files: a small text format, versioned and
 * checksummed, written to a temporary file and renamed (static_save).
 */
#define _POSIX_C_SOURCE 200809L /* open_memstream */
#include <tunetrace/file.h>
#include <tunetrace/plugin.h>
#include <tunetrace/predictor.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PS_NAME "predictor_static"
#define PS_VERSION "1.0.0"
#define PS_FORMAT 1

static tt_space *ps_settings;

typedef struct ps_config {
  double *values;        /* per parameter: INT/FLOAT value, NOM index */
  double log_ratio_sum;  /* sum over states of log(cost / reference cost of the state) */
  uint64_t states;       /* states it was observed in */
  uint64_t last_state;   /* index + 1 of the last state it was scored in */
} ps_config;

typedef struct ps_state {
  double *x;             /* the state */
  double reference;      /* default cost, else the first cost seen */
} ps_state;

struct tt_predictor {
  const tt_space *target;
  size_t params;
  uint32_t dim;
  char *state_space;
  double min_share;
  ps_config *cfgs;
  size_t ncfg, cap;
  ps_state *states;
  size_t nstates, scap;
  uint64_t observations;
};

static const tt_space *ps_space(void) { return ps_settings; }

static void ps_clear(tt_predictor *p);

static void ps_destroy(tt_predictor *p) {
  if (!p) return;
  ps_clear(p);
  free(p->state_space);
  free(p);
}

static tt_status ps_create_ex(const tt_predictor_setup *su, tt_predictor **out) {
  if (!out || !su || !su->target || su->state_dim < 1)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": create: bad arguments");
  *out = NULL;
  tt_predictor *p = calloc(1, sizeof *p);
  const char *ss = su->state_space ? su->state_space : "";
  if (p) p->state_space = malloc(strlen(ss) + 1);
  if (!p || !p->state_space) {
    ps_destroy(p);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, PS_NAME ": out of memory");
  }
  strcpy(p->state_space, ss);
  p->target = su->target;
  p->params = tt_space_count(su->target);
  p->dim = su->state_dim;
  p->min_share = su->settings ? tt_config_get_float(su->settings, "minShare", 0.5) : 0.5;
  *out = p;
  return TT_OK;
}

static tt_status ps_create(const tt_space *target, uint32_t dim, const tt_config *settings,
                           uint64_t seed, tt_predictor **out) {
  tt_predictor_setup su = {.struct_size = sizeof su, .target = target, .state_dim = dim,
                           .settings = settings, .seed = seed};
  return ps_create_ex(&su, out);
}

/* Per-parameter values of a configuration (exact: FLOAT values, NOM indices). */
static void ps_values(const tt_predictor *p, const tt_config *c, double *v) {
  for (size_t i = 0; i < p->params; i++) {
    tt_value x = tt_config_get(c, i);
    v[i] = tt_space_type(p->target, i) == TT_PARAM_NOM ? (double)x.index : x.f;
  }
}

/* The state's index, adding it (with its reference cost) if new; SIZE_MAX when out of memory. */
static size_t ps_state_index(tt_predictor *p, const double *x, double reference) {
  for (size_t i = 0; i < p->nstates; i++)
    if (!memcmp(p->states[i].x, x, p->dim * sizeof(double))) return i;
  if (p->nstates == p->scap) {
    size_t cap = p->scap ? 2 * p->scap : 64;
    ps_state *s = realloc(p->states, cap * sizeof *s);
    if (!s) return SIZE_MAX;
    p->states = s;
    p->scap = cap;
  }
  double *c = malloc(p->dim * sizeof(double));
  if (!c) return SIZE_MAX;
  memcpy(c, x, p->dim * sizeof(double));
  p->states[p->nstates] = (ps_state){c, reference};
  return p->nstates++;
}

static size_t ps_config_index(tt_predictor *p, const double *v) {
  for (size_t i = 0; i < p->ncfg; i++)
    if (!memcmp(p->cfgs[i].values, v, p->params * sizeof(double))) return i;
  if (p->ncfg == p->cap) {
    size_t cap = p->cap ? 2 * p->cap : 64;
    ps_config *c = realloc(p->cfgs, cap * sizeof *c);
    if (!c) return SIZE_MAX;
    p->cfgs = c;
    p->cap = cap;
  }
  double *copy = malloc((p->params ? p->params : 1) * sizeof(double));
  if (!copy) return SIZE_MAX;
  memcpy(copy, v, p->params * sizeof(double));
  p->cfgs[p->ncfg] = (ps_config){copy, 0.0, 0, 0};
  return p->ncfg++;
}

static tt_status ps_observe_ex(tt_predictor *p, const tt_predictor_sample *s, size_t n,
                               uint32_t flags) {
  (void)flags;
  if (!p || (n && !s)) return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": observe: NULL");
  double v[256];
  if (p->params > 256) return tt_set_error(TT_ERR_UNSUPPORTED, PS_NAME ": more than 256 parameters");
  for (size_t k = 0; k < n; k++) {
    double cost = s[k].cost;
    if (!s[k].state || !s[k].config || isnan(cost) || !(cost > 0))
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": observe: sample %zu: no state, no "
                          "configuration or a cost that is not positive", k);
    if (cost >= TT_COST_INFEASIBLE) continue;  /* never a static answer */
    double def = s[k].default_cost;
    size_t si = ps_state_index(p, s[k].state, def > 0 && isfinite(def) ? def : cost);
    ps_values(p, s[k].config, v);
    size_t ci = si == SIZE_MAX ? SIZE_MAX : ps_config_index(p, v);
    if (ci == SIZE_MAX) return tt_set_error(TT_ERR_OUT_OF_MEMORY, PS_NAME ": out of memory");
    ps_config *c = &p->cfgs[ci];
    c->log_ratio_sum += log(cost / p->states[si].reference);
    if (c->last_state != si + 1) c->states++;  /* repeats in one state count once */
    c->last_state = si + 1;
    p->observations++;
  }
  return TT_OK;
}

static tt_status ps_observe(tt_predictor *p, const double *state, const tt_config *config,
                            double cost) {
  tt_predictor_sample s = {.struct_size = sizeof s, .state = state, .config = config,
                           .cost = cost, .default_cost = NAN};
  return ps_observe_ex(p, &s, 1, TT_PREDICTOR_ONLINE);
}

/* Index of the static answer: the lowest mean log ratio among configurations observed in
 * at least minShare of the states (or, if none, in the most states). */
static size_t ps_best(const tt_predictor *p, double *mean_log) {
  uint64_t most = 0;
  for (size_t i = 0; i < p->ncfg; i++)
    if (p->cfgs[i].states > most) most = p->cfgs[i].states;
  double need = p->min_share * (double)p->nstates;
  size_t best = SIZE_MAX;
  double bm = INFINITY;
  for (size_t i = 0; i < p->ncfg; i++) {
    const ps_config *c = &p->cfgs[i];
    if ((double)c->states < need && c->states < most) continue;
    double m = c->log_ratio_sum / (double)c->states;
    if (m < bm) bm = m, best = i;
  }
  if (mean_log) *mean_log = bm;
  return best;
}

static tt_status ps_predict_ex(const tt_predictor *p, const tt_predictor_query *q, tt_config *out,
                               tt_predictor_result *res) {
  if (!p || !q || !out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": predict: NULL");
  double m;
  size_t b = ps_best(p, &m);
  if (b == SIZE_MAX) return tt_set_error(TT_ERR_NO_DATA, PS_NAME ": predict: nothing observed");
  for (size_t i = 0; i < p->params; i++) {
    tt_status st = tt_space_type(p->target, i) == TT_PARAM_NOM
                       ? tt_config_set_index(out, i, (size_t)p->cfgs[b].values[i])
                       : tt_config_set_number(out, i, p->cfgs[b].values[i]);
    if (st != TT_OK) return st;
  }
  if (res && res->struct_size >= offsetof(tt_predictor_result, candidates) + sizeof res->candidates) {
    res->value = exp(-m);  /* the typical speed-up over the reference */
    res->expected_cost = q->default_cost > 0 ? q->default_cost * exp(m) : NAN;
    res->distance = NAN;
    res->candidates = p->ncfg;
  }
  return TT_OK;
}

static tt_status ps_predict(const tt_predictor *p, const double *state, tt_config *out,
                            double *expected_cost) {
  tt_predictor_query q = {.struct_size = sizeof q, .state = state, .default_cost = NAN};
  if (expected_cost) *expected_cost = NAN;
  return ps_predict_ex(p, &q, out, NULL);
}

static tt_status ps_estimate(const tt_predictor *p, const tt_predictor_query *q,
                             const tt_config *config, double *cost) {
  if (!p || !q || !config || !cost) return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": estimate: NULL");
  double v[256];
  *cost = NAN;
  if (p->params > 256) return TT_OK;
  ps_values(p, config, v);
  for (size_t i = 0; i < p->ncfg; i++)
    if (!memcmp(p->cfgs[i].values, v, p->params * sizeof(double)) && q->default_cost > 0)
      *cost = q->default_cost * exp(p->cfgs[i].log_ratio_sum / (double)p->cfgs[i].states);
  return TT_OK;
}

static tt_status ps_info(const tt_predictor *p, tt_predictor_info *out) {
  if (!p || !out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": info: NULL");
  if (out->struct_size < offsetof(tt_predictor_info, format_version) + sizeof out->format_version)
    return TT_OK;
  out->memory_bytes = sizeof *p + p->cap * (sizeof(ps_config) + p->params * sizeof(double)) +
                      p->scap * sizeof(ps_state) + p->nstates * p->dim * sizeof(double);
  out->entries = p->ncfg;
  out->observations = p->observations;
  out->format_version = PS_FORMAT;
  return TT_OK;
}

/* ---- files: "predictor_static FORMAT\n" then lines, then "checksum HEX\n" over all before ---- */

static uint64_t ps_fnv(const char *s, size_t n) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < n; i++) h = (h ^ (unsigned char)s[i]) * 0x100000001b3ull;
  return h;
}

static tt_status ps_save(const tt_predictor *p, const char *path) {
  if (!p || !path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": save: NULL");
  char *text = NULL;
  size_t len = 0;
  FILE *m = open_memstream(&text, &len);
  if (!m) return tt_set_error(TT_ERR_OUT_OF_MEMORY, PS_NAME ": out of memory");
  fprintf(m, PS_NAME " %d\nstate_space %s\ndim %u\nparams %zu %s\nminShare %.17g\n", PS_FORMAT,
          p->state_space, p->dim, p->params, tt_space_plugin(p->target), p->min_share);
  fprintf(m, "states %zu\n", p->nstates);
  for (size_t i = 0; i < p->nstates; i++) {
    for (uint32_t k = 0; k < p->dim; k++) fprintf(m, "%a ", p->states[i].x[k]);
    fprintf(m, "%a\n", p->states[i].reference);
  }
  fprintf(m, "configs %zu %llu\n", p->ncfg, (unsigned long long)p->observations);
  for (size_t i = 0; i < p->ncfg; i++) {
    for (size_t k = 0; k < p->params; k++) fprintf(m, "%a ", p->cfgs[i].values[k]);
    fprintf(m, "%a %llu %llu\n", p->cfgs[i].log_ratio_sum, (unsigned long long)p->cfgs[i].states,
            (unsigned long long)p->cfgs[i].last_state);
  }
  fprintf(m, "checksum %016llx\n", 0ull);  /* placeholder, filled in below */
  fclose(m);
  if (!text) return tt_set_error(TT_ERR_OUT_OF_MEMORY, PS_NAME ": out of memory");
  /* the checksum covers everything before its line */
  size_t body = len - strlen("checksum 0000000000000000\n");
  snprintf(text + body, len - body + 1, "checksum %016llx\n", (unsigned long long)ps_fnv(text, body));
  /* libtunetrace's atomic write (<tunetrace/file.h>): a temporary file renamed over `path`,
   * so a failed save never destroys the previous model */
  tt_status st = tt_file_write_atomic(path, text, len);
  free(text);
  if (st != TT_OK) return tt_set_error(st, PS_NAME ": cannot write model %s: %s", path, tt_last_error());
  return TT_OK;
}

/* Reads one number ("%a" or decimal) at *s and advances; -1 if there is none. */
static int ps_num(char **s, double *v) {
  char *end;
  *v = strtod(*s, &end);
  if (end == *s) return -1;
  *s = end;
  return 0;
}

/* Frees the lists of a model (not the struct). */
static void ps_clear(tt_predictor *p) {
  for (size_t i = 0; i < p->ncfg; i++) free(p->cfgs[i].values);
  for (size_t i = 0; i < p->nstates; i++) free(p->states[i].x);
  free(p->cfgs);
  free(p->states);
  p->cfgs = NULL;
  p->states = NULL;
  p->ncfg = p->cap = p->nstates = p->scap = 0;
}

static tt_status ps_load(tt_predictor *p, const char *path) {
  if (!p || !path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": load: NULL");
  size_t n;
  char *text = NULL;  /* regular files only, at most 64 MiB (<tunetrace/file.h>) */
  if (tt_file_read(path, "model", (size_t)1 << 26, &text, &n) != TT_OK)
    return tt_set_error(TT_ERR_IO, PS_NAME ": cannot open model %s: %s", path, tt_last_error());
  int version = 0;
  if (sscanf(text, PS_NAME " %d", &version) != 1) {
    tt_free(text);
    return tt_set_error(TT_ERR_PARSE, PS_NAME ": %s is not a " PS_NAME " model", path);
  }
  char *ck = strstr(text, "\nchecksum ");
  unsigned long long want = 0;
  if (!ck || sscanf(ck + 10, "%16llx", &want) != 1 || ps_fnv(text, (size_t)(ck + 1 - text)) != want) {
    tt_free(text);
    return tt_set_error(TT_ERR_PARSE, PS_NAME ": model %s is truncated or corrupt (checksum)", path);
  }
  if (version > PS_FORMAT) {
    tt_free(text);
    return tt_set_error(TT_ERR_UNSUPPORTED, PS_NAME ": model %s has format %d; this " PS_NAME " "
                        PS_VERSION " reads format %d", path, version, PS_FORMAT);
  }
  char space[1024] = "", plugin[256] = "";
  char *s = strchr(text, '\n') + 1;
  if (!strncmp(s, "state_space ", 12)) {
    size_t l = strcspn(s + 12, "\n");
    snprintf(space, sizeof space, "%.*s", (int)l, s + 12);
    s += 12 + l + (s[12 + l] ? 1 : 0);
  }
  unsigned dim = 0;
  size_t params = 0;
  double ms = 0.5;
  int got = sscanf(s, "dim %u params %zu %255s minShare %lf", &dim, &params, plugin, &ms);
  if (got != 4 || strcmp(space, p->state_space) || dim != p->dim || params != p->params ||
      strcmp(plugin, tt_space_plugin(p->target))) {
    tt_status st = tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": model %s is for states \"%s\" "
                                "(%u values) and %zu parameters of %s; this predictor has \"%s\" "
                                "(%u) and %zu of %s", path, space, dim, params, plugin,
                                p->state_space, p->dim, p->params, tt_space_plugin(p->target));
    tt_free(text);
    return st;
  }
  tt_predictor q = *p;  /* the loaded model is built aside: p stays as it was on error */
  q.cfgs = NULL, q.states = NULL, q.ncfg = q.cap = q.nstates = q.scap = 0;
  q.min_share = ms;
  unsigned long long ns = 0, nc = 0, obs = 0;
  s = strstr(s, "\nstates ");
  int bad = !s || sscanf(s, "\nstates %llu", &ns) != 1 || dim > 4096 || params > 256;
  if (!bad) s = strchr(s + 1, '\n');
  double x[4096], v[256], ref, a, b, c;
  for (unsigned long long i = 0; !bad && i < ns; i++) {
    for (unsigned k = 0; k < dim && !bad; k++) bad = ps_num(&s, &x[k]);
    bad = bad || ps_num(&s, &ref) || !(ref > 0) || ps_state_index(&q, x, ref) != i;
  }
  char *cfgs = bad ? NULL : strstr(s, "configs ");
  bad = bad || !cfgs || sscanf(cfgs, "configs %llu %llu", &nc, &obs) != 2;
  if (!bad) s = strchr(cfgs, '\n');
  for (unsigned long long i = 0; !bad && i < nc; i++) {
    for (size_t k = 0; k < params && !bad; k++) bad = ps_num(&s, &v[k]);
    bad = bad || ps_num(&s, &a) || ps_num(&s, &b) || ps_num(&s, &c) || !(b >= 1) ||
          !isfinite(a) || ps_config_index(&q, v) != i;
    if (!bad) {
      q.cfgs[i].log_ratio_sum = a;
      q.cfgs[i].states = (uint64_t)b;
      q.cfgs[i].last_state = (uint64_t)c;
    }
  }
  tt_free(text);
  if (bad) {
    ps_clear(&q);
    return tt_set_error(TT_ERR_PARSE, PS_NAME ": model %s: malformed state or configuration list", path);
  }
  ps_clear(p);
  q.observations = obs;
  *p = q;
  return TT_OK;
}

static const tt_predictor_iface ps_iface = {
  .struct_size = sizeof(tt_predictor_iface),
  .space = ps_space, .create = ps_create, .observe = ps_observe, .predict = ps_predict,
  .save = ps_save, .load = ps_load, .destroy = ps_destroy,
  .create_ex = ps_create_ex, .observe_ex = ps_observe_ex, .predict_ex = ps_predict_ex,
  .info = ps_info, .estimate = ps_estimate,
};

static tt_status ps_init(const tt_host *host) {
  (void)host;
  ps_settings = tt_space_create(PS_NAME, PS_VERSION);
  if (!ps_settings || tt_space_add_float(ps_settings, "minShare", 0.0, 1.0, 0.5, 0,
                                         "share of the states a configuration must have been "
                                         "observed in to be the static answer") < 0) {
    tt_space_destroy(ps_settings);
    ps_settings = NULL;
    return tt_set_error(TT_ERR_INTERNAL, PS_NAME ": cannot build the settings space");
  }
  return TT_OK;
}

static void ps_deinit(void) {
  tt_space_destroy(ps_settings);
  ps_settings = NULL;
}

static const void *ps_get_interface(const char *id) {
  return strcmp(id, TT_PREDICTOR_INTERFACE_ID) == 0 ? &ps_iface : NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
  .struct_size = sizeof(tt_plugin),
  .abi_major = TT_ABI_MAJOR,
  .abi_minor = TT_ABI_MINOR,
  .kind = TT_KIND_PREDICTOR,
  .name = PS_NAME,
  .version = PS_VERSION,
  .description = "the best static configuration over all states seen (a baseline, and the "
                 "SDK's predictor example)",
  .init = ps_init,
  .deinit = ps_deinit,
  .get_interface = ps_get_interface,
};
