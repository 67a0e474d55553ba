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
/* open_memstream; its Makefile, unlike meson, sets no _GNU_SOURCE */
#define _POSIX_C_SOURCE 200809L
#include <tunetrace/file.h>
#include <tunetrace/plugin.h>
#include <tunetrace/predictor.h>

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PS_NAME "predictor_static"
#define PS_VERSION "1.0.0"
#define PS_FORMAT 1

static tt_space *ps_settings;

typedef struct ps_config {
  double *values;       /* per parameter: INT/FLOAT value, NOM index */
  double log_ratio_sum; /* sum over states of log(cost / reference cost of the state) */
  uint64_t states;      /* states it was observed in */
  uint64_t last_state;  /* index + 1 of the last state it was scored in */
} ps_config;

typedef struct ps_state {
  double *x;        /* the state */
  double reference; /* default cost, else the first cost seen */
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
  const char *ss = su->state_space ? su->state_space : "";
  if (strchr(ss, '\n')) /* it is one line of the model file */
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": create: the state space holds a "
                                                         "newline");
  tt_predictor *p = calloc(1, sizeof *p);
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
  tt_predictor_setup su = {.struct_size = sizeof su,
                           .target = target,
                           .state_dim = dim,
                           .settings = settings,
                           .seed = seed};
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
  if (p->params > 256)
    return tt_set_error(TT_ERR_UNSUPPORTED, PS_NAME ": more than 256 parameters");
  /* the whole batch is checked first: a bad sample leaves the model unchanged */
  for (size_t k = 0; k < n; k++) {
    double cost = s[k].cost;
    if (!s[k].state || !s[k].config || isnan(cost) || !(cost > 0))
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          PS_NAME ": observe: sample %zu: no state, no "
                                  "configuration or a cost that is not positive",
                          k);
    if (tt_space_count(tt_config_space(s[k].config)) != p->params)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          PS_NAME ": observe: sample %zu: the "
                                  "configuration is not of the target space",
                          k);
    for (uint32_t i = 0; i < p->dim; i++) /* the model file holds finite states only */
      if (!isfinite(s[k].state[i]))
        return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                            PS_NAME ": observe: sample %zu: state "
                                    "value %u is not finite",
                            k, i);
  }
  for (size_t k = 0; k < n; k++) {
    double cost = s[k].cost;
    if (cost >= TT_COST_INFEASIBLE) continue; /* never a static answer */
    double def = s[k].default_cost;
    size_t si = ps_state_index(p, s[k].state, def > 0 && isfinite(def) ? def : cost);
    ps_values(p, s[k].config, v);
    size_t ci = si == SIZE_MAX ? SIZE_MAX : ps_config_index(p, v);
    if (ci == SIZE_MAX) return tt_set_error(TT_ERR_OUT_OF_MEMORY, PS_NAME ": out of memory");
    ps_config *c = &p->cfgs[ci];
    /* (the difference of the logs stays finite where the ratio of two extreme costs would
     * not, and the model file holds finite sums only) */
    c->log_ratio_sum += log(cost) - log(p->states[si].reference);
    if (c->last_state != si + 1) c->states++; /* repeats in one state count once */
    c->last_state = si + 1;
    p->observations++;
  }
  return TT_OK;
}

static tt_status ps_observe(tt_predictor *p, const double *state, const tt_config *config,
                            double cost) {
  tt_predictor_sample s = {
      .struct_size = sizeof s, .state = state, .config = config, .cost = cost, .default_cost = NAN};
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
    double v = p->cfgs[b].values[i]; /* checked by observe and load; cast only when in range */
    int nom = tt_space_type(p->target, i) == TT_PARAM_NOM;
    if (nom && !(v >= 0 && v < (double)tt_space_nom_count(p->target, i)))
      return tt_set_error(TT_ERR_INTERNAL,
                          PS_NAME ": predict: possible-value index %g of %s "
                                  "out of range",
                          v, tt_space_name(p->target, i));
    tt_status st = nom ? tt_config_set_index(out, i, (size_t)v) : tt_config_set_number(out, i, v);
    if (st != TT_OK) return st;
  }
  if (res && TT_HAS_FIELD(tt_predictor_result, res, candidates)) {
    res->value = exp(-m); /* the typical speed-up over the reference */
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
  if (!p || !q || !config || !cost)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": estimate: NULL");
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
  if (!TT_HAS_FIELD(tt_predictor_info, out, format_version)) return TT_OK;
  out->memory_bytes = sizeof *p + p->cap * (sizeof(ps_config) + p->params * sizeof(double)) +
                      p->scap * sizeof(ps_state) + p->nstates * p->dim * sizeof(double);
  out->entries = p->ncfg;
  out->observations = p->observations;
  out->format_version = PS_FORMAT;
  return TT_OK;
}

/* ---- files ----
 * Text, one record a line, numbers as C99 hex floats ("%a": exact) or decimal integers:
 *   predictor_static 1
 *   state_space TEXT
 *   dim D
 *   params P PLUGIN
 *   minShare S
 *   states N            then N lines: the D state values and the state's reference cost
 *   configs C OBS       then C lines: the P values (FLOAT/INT value, NOM index), the sum of
 *                       log cost ratios, the states it was seen in, the last of them (1-based)
 *   checksum HEX        FNV-1a 64 of every byte before this line; the file's last line
 * A model file is input like any other: the reader checks the checksum first, then reads
 * only the text it covers, and range-checks every number against the model's own counts and
 * the target space before using it, so a crafted or damaged file is an error naming the file,
 * the line and what was expected, never a crash or a silently wrong answer. */

#define PS_CHECKSUM_LINE 26 /* "checksum " + 16 hex digits + "\n" */
#define PS_MAX_FILE ((size_t)1 << 26)

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
  fprintf(m, "checksum %016llx\n", 0ull); /* placeholder, filled in below */
  fclose(m);
  if (!text) return tt_set_error(TT_ERR_OUT_OF_MEMORY, PS_NAME ": out of memory");
  /* the checksum covers everything before its line */
  size_t body = len - PS_CHECKSUM_LINE;
  snprintf(text + body, len - body + 1, "checksum %016llx\n",
           (unsigned long long)ps_fnv(text, body));
  /* libtunetrace's atomic write (<tunetrace/file.h>): a temporary file renamed over `path`,
   * so a failed save never destroys the previous model */
  tt_status st = tt_file_write_atomic(path, text, len);
  free(text);
  if (st != TT_OK)
    return tt_set_error(st, PS_NAME ": cannot write model %s: %s", path, tt_last_error());
  return TT_OK;
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

/* The checksummed text of a model file, line by line. The first error is kept (in the
 * library's last error, and `failed`); later calls do nothing. */
typedef struct ps_reader {
  char *next;      /* the next line; the checksummed text ends with '\0' */
  const char *end; /* that '\0' */
  const char *path;
  unsigned line; /* number of the current line, 1-based */
  char item[64]; /* the state or configuration the line holds, "" for the others */
  int failed;
} ps_reader;

static int ps_fail(ps_reader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int ps_fail(ps_reader *r, const char *fmt, ...) {
  if (r->failed) return -1;
  char msg[512];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  tt_set_error(TT_ERR_PARSE, PS_NAME ": model %s, line %u: %s%s%s", r->path, r->line, r->item,
               r->item[0] ? ": " : "", msg);
  r->failed = 1;
  return -1;
}

/* The next line (NUL-terminated in place) if it begins with `key` and a space: what follows
 * them; NULL (an error) otherwise. `what` says what the line should hold. */
static char *ps_line(ps_reader *r, const char *key, const char *what) {
  if (r->failed) return NULL;
  r->line++;
  if (r->next >= r->end) {
    ps_fail(r, "the file ends before %s", what);
    return NULL;
  }
  char *s = r->next, *nl = strchr(s, '\n'); /* the text ends with '\n' (checked) */
  *nl = '\0';
  r->next = nl + 1;
  size_t k = strlen(key);
  if (k && (strncmp(s, key, k) || s[k] != ' ')) {
    ps_fail(r, "expected %s (\"%s ...\"), got \"%.60s\"", what, key, s);
    return NULL;
  }
  return s + (k ? k + 1 : 0);
}

/* One space-separated field at *s; advances past it and its separator. */
static char *ps_field(char **s) {
  char *f = *s;
  size_t n = strcspn(f, " ");
  *s = f + n + (f[n] == ' ');
  if (f[n]) f[n] = '\0';
  return f;
}

/* A decimal integer field in [lo, hi]. */
static int ps_u64(ps_reader *r, char **s, uint64_t lo, uint64_t hi, const char *what,
                  uint64_t *out) {
  if (r->failed) return -1;
  char *f = ps_field(s), *end;
  errno = 0;
  unsigned long long v = f[0] >= '0' && f[0] <= '9' ? strtoull(f, &end, 10) : 0;
  if (f[0] < '0' || f[0] > '9' || *end || errno == ERANGE || v < lo || v > hi)
    return ps_fail(r, "%s: expected an integer in [%llu, %llu], got \"%.40s\"", what,
                   (unsigned long long)lo, (unsigned long long)hi, f);
  *out = v;
  return 0;
}

/* A finite number field ("%a" or decimal) in [lo, hi]. */
static int ps_f64(ps_reader *r, char **s, double lo, double hi, const char *what, double *out) {
  if (r->failed) return -1;
  char *f = ps_field(s), *end;
  double v = strtod(f, &end);
  if (end == f || *end || !isfinite(v) || v < lo || v > hi) {
    if (lo == -DBL_MAX && hi == DBL_MAX)
      return ps_fail(r, "%s: expected a finite number, got \"%.40s\"", what, f);
    return ps_fail(r, "%s: expected a number in [%g, %g], got \"%.40s\"", what, lo, hi, f);
  }
  *out = v;
  return 0;
}

/* A finite number field that must be positive. */
static int ps_positive(ps_reader *r, char **s, const char *what, double *out) {
  if (ps_f64(r, s, -DBL_MAX, DBL_MAX, what, out)) return -1;
  if (!(*out > 0)) return ps_fail(r, "%s: expected a positive number, got %g", what, *out);
  return 0;
}

/* The end of a line: nothing may follow its last field. */
static int ps_eol(ps_reader *r, const char *s, const char *what) {
  if (r->failed) return -1;
  if (*s) return ps_fail(r, "unexpected \"%.40s\" after %s", s, what);
  return 0;
}

/* A value of parameter `i` of the target, as this predictor stores it (ps_values), checked
 * through the target space: an INT or FLOAT in its range, a NOM index below its count. */
static int ps_value(ps_reader *r, const tt_predictor *p, tt_config *scratch, size_t i, double v) {
  tt_status st;
  if (tt_space_type(p->target, i) == TT_PARAM_NOM) {
    size_t n = tt_space_nom_count(p->target, i);
    if (!(v >= 0) || v >= (double)n || v != floor(v))
      return ps_fail(r, "%s.%s: possible-value index %.17g is not an integer in [0, %zu)",
                     tt_space_plugin(p->target), tt_space_name(p->target, i), v, n);
    st = tt_config_set_index(scratch, i, (size_t)v);
  } else {
    st = tt_config_set_number(scratch, i, v); /* INT: an integer in range; FLOAT: in range */
  }
  if (st != TT_OK) {
    char why[400];
    snprintf(why, sizeof why, "%s", tt_last_error());
    return ps_fail(r, "%s", why);
  }
  return 0;
}

/* Rows of doubles compared bytewise (the way ps_state_index and ps_config_index find them),
 * sorted to find one stored twice in O(n log n): a crafted file of millions of rows must
 * not take hours. */
typedef struct ps_row {
  const double *x;
  size_t n, index;
} ps_row;

static int ps_row_cmp(const void *a, const void *b) {
  const ps_row *u = a, *v = b;
  int c = memcmp(u->x, v->x, u->n * sizeof(double));
  return c ? c : (u->index > v->index) - (u->index < v->index);
}

/* 0, or -1 with *first < *second the indices of two equal rows. */
static int ps_twice(ps_row *rows, size_t n, size_t *first, size_t *second) {
  if (n < 2) return 0;
  qsort(rows, n, sizeof *rows, ps_row_cmp);
  for (size_t i = 1; i < n; i++)
    if (!memcmp(rows[i - 1].x, rows[i].x, rows[i].n * sizeof(double))) {
      *first = rows[i - 1].index;
      *second = rows[i].index;
      return -1;
    }
  return 0;
}

/* Locates the checksum line and checks it. TT_OK and *body (the bytes it covers), or an
 * error: not a model, corrupt or cut short, or bytes after the checksum line. */
static tt_status ps_checksum(const char *text, size_t n, const char *path, size_t *body) {
  const char *nul = memchr(text, '\0', n);
  if (nul)
    return tt_set_error(TT_ERR_PARSE,
                        PS_NAME ": model %s holds a NUL byte at offset %zu (a "
                                "model is text)",
                        path, (size_t)(nul - text));
  /* the last "\nchecksum " line, wherever it is, to tell data after it from damage */
  const char *ck = NULL;
  for (size_t i = n; i-- > 0 && !ck;)
    if (text[i] == '\n' && n - i - 1 >= 9 && !memcmp(text + i + 1, "checksum ", 9))
      ck = text + i + 1;
  int digits = 0;
  uint64_t want = 0;
  for (; ck && digits < 16 && (size_t)(ck + 9 + digits - text) < n; digits++) {
    char c = ck[9 + digits];
    int d = c >= '0' && c <= '9'   ? c - '0'
            : c >= 'a' && c <= 'f' ? c - 'a' + 10
            : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                   : -1;
    if (d < 0) break;
    want = want << 4 | (uint64_t)d;
  }
  size_t covered = ck ? (size_t)(ck - text) : 0;
  if (!ck || digits != 16 || ps_fnv(text, covered) != want)
    return tt_set_error(TT_ERR_PARSE, PS_NAME ": model %s is truncated or corrupt (%s)", path,
                        !ck            ? "no \"checksum\" line"
                        : digits != 16 ? "the checksum line does not hold 16 hexadecimal digits"
                                       : "the checksum does not match the text before it");
  size_t line_end = covered + PS_CHECKSUM_LINE;
  if (line_end > n || text[line_end - 1] != '\n')
    return tt_set_error(TT_ERR_PARSE,
                        PS_NAME ": model %s: the checksum line is not "
                                "\"checksum\", 16 hexadecimal digits and a newline",
                        path);
  if (line_end != n)
    return tt_set_error(TT_ERR_PARSE,
                        PS_NAME ": model %s has %zu bytes after its checksum line "
                                "(a model ends there; was something appended to it?)",
                        path, n - line_end);
  *body = covered;
  return TT_OK;
}

/* Reads the checksummed text into q (fresh lists): the header lines are checked against p
 * (another state space, dimension or target: TT_ERR_INVALID_ARGUMENT), then the lists. */
static tt_status ps_parse(tt_predictor *p, tt_predictor *q, ps_reader *r) {
  uint64_t version = 0, dim = 0, params = 0, ns = 0, nc = 0, obs = 0;
  char *s = ps_line(r, PS_NAME, "the format line");
  if (s && ps_u64(r, &s, 0, UINT32_MAX, "the format version", &version) == 0 &&
      ps_eol(r, s, "the format version") == 0) {
    if (version > PS_FORMAT)
      return tt_set_error(TT_ERR_UNSUPPORTED,
                          PS_NAME ": model %s has format %llu; this " PS_NAME " " PS_VERSION
                                  " reads format %d",
                          r->path, (unsigned long long)version, PS_FORMAT);
    if (version < 1) ps_fail(r, "format version 0 does not exist (1 to %d)", PS_FORMAT);
  }
  const char *space = ps_line(r, "state_space", "the state space");
  s = ps_line(r, "dim", "the state dimension");
  if (s && !ps_u64(r, &s, 1, UINT32_MAX, "dim", &dim)) ps_eol(r, s, "dim");
  s = ps_line(r, "params", "the parameter count and target");
  const char *plugin = "";
  if (s && !ps_u64(r, &s, 0, SIZE_MAX, "params", &params)) plugin = s;
  if (!r->failed && (strcmp(space, p->state_space) || dim != p->dim || params != p->params ||
                     strcmp(plugin, tt_space_plugin(p->target))))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        PS_NAME ": model %s is for states \"%s\" "
                                "(%u values) and %llu parameters of %s; this predictor has \"%s\" "
                                "(%u) and %zu of %s",
                        r->path, space, (unsigned)dim, (unsigned long long)params, plugin,
                        p->state_space, p->dim, p->params, tt_space_plugin(p->target));
  s = ps_line(r, "minShare", "the minShare setting");
  if (s && !ps_f64(r, &s, 0.0, 1.0, "minShare", &q->min_share)) ps_eol(r, s, "minShare");
  /* every state line holds dim + 1 numbers of at least one character and a separator */
  s = ps_line(r, "states", "the state count");
  if (s && !ps_u64(r, &s, 0, (uint64_t)(r->end - r->next) / (2 * (p->dim + 1ull)),
                   "the state count (at most what the rest of the file can hold)", &ns))
    ps_eol(r, s, "the state count");
  double *x = r->failed ? NULL : malloc((p->dim + 1ull) * sizeof(double));
  double *v = r->failed ? NULL : malloc((p->params + 1) * sizeof(double));
  tt_config *scratch = r->failed ? NULL : tt_config_create(p->target);
  ps_row *rows = NULL;
  if (!r->failed && (!x || !v || !scratch)) ps_fail(r, "out of memory");
  if (!r->failed && ns) {
    q->states = malloc(ns * sizeof *q->states);
    rows = malloc(ns * sizeof *rows);
    if (!q->states || !rows) ps_fail(r, "out of memory");
    q->scap = ns;
  }
  unsigned first = r->line + 1; /* the line of state 0 */
  for (uint64_t i = 0; !r->failed && i < ns; i++) {
    snprintf(r->item, sizeof r->item, "state %llu", (unsigned long long)i);
    s = ps_line(r, "", "a state");
    for (uint32_t k = 0; k < p->dim; k++) ps_f64(r, &s, -DBL_MAX, DBL_MAX, "a state value", &x[k]);
    ps_positive(r, &s, "the state's reference cost", &x[p->dim]);
    ps_eol(r, s, "the state's reference cost");
    double *copy = r->failed ? NULL : malloc(p->dim * sizeof(double));
    if (!r->failed && !copy) ps_fail(r, "out of memory");
    if (r->failed) break;
    memcpy(copy, x, p->dim * sizeof(double));
    q->states[q->nstates++] = (ps_state){copy, x[p->dim]};
    rows[i] = (ps_row){copy, p->dim, i};
  }
  r->item[0] = '\0';
  size_t a, b;
  if (!r->failed && ps_twice(rows, ns, &a, &b)) {
    r->line = first + (unsigned)b;
    ps_fail(r, "state %zu is stored twice (states %zu and %zu are equal)", b, a, b);
  }
  free(rows);
  rows = NULL;
  /* every configuration line holds params + 3 fields */
  s = ps_line(r, "configs", "the configuration count and observation count");
  if (s &&
      !ps_u64(r, &s, 0, (uint64_t)(r->end - r->next) / (2 * (p->params + 3)),
              "the configuration count (at most what the rest of the file can hold)", &nc) &&
      !ps_u64(r, &s, 0, UINT64_MAX, "the observation count", &obs))
    ps_eol(r, s, "the observation count");
  if (!r->failed && nc) {
    q->cfgs = malloc(nc * sizeof *q->cfgs);
    rows = malloc(nc * sizeof *rows);
    if (!q->cfgs || !rows) ps_fail(r, "out of memory");
    q->cap = nc;
  }
  uint64_t seen = 0; /* sum of the configurations' state counts: at most one per observation */
  first = r->line + 1;
  for (uint64_t i = 0; !r->failed && i < nc; i++) {
    snprintf(r->item, sizeof r->item, "configuration %llu", (unsigned long long)i);
    s = ps_line(r, "", "a configuration");
    for (size_t k = 0; k < p->params && !r->failed; k++)
      if (!ps_f64(r, &s, -DBL_MAX, DBL_MAX, "a parameter value", &v[k]))
        ps_value(r, p, scratch, k, v[k]);
    double sum = 0;
    uint64_t states = 0, last = 0;
    ps_f64(r, &s, -DBL_MAX, DBL_MAX, "the sum of log cost ratios", &sum);
    /* invariants of every saved model: each observation adds to at most one configuration's
     * state count, and the last state is one of the states */
    ps_u64(r, &s, 1, obs - seen,
           "the number of states it was seen in (at most the "
           "observations the configurations before it leave)",
           &states);
    ps_u64(r, &s, 1, ns, "the last state it was seen in", &last);
    ps_eol(r, s, "the last state");
    double *copy = r->failed ? NULL : malloc((p->params ? p->params : 1) * sizeof(double));
    if (!r->failed && !copy) ps_fail(r, "out of memory");
    if (r->failed) break;
    seen += states;
    memcpy(copy, v, p->params * sizeof(double));
    q->cfgs[q->ncfg++] = (ps_config){copy, sum, states, last};
    rows[i] = (ps_row){copy, p->params, i};
  }
  r->item[0] = '\0';
  if (!r->failed && ps_twice(rows, nc, &a, &b)) {
    r->line = first + (unsigned)b;
    ps_fail(r, "configuration %zu is stored twice (configurations %zu and %zu are equal)", b, a, b);
  }
  if (!r->failed && r->next < r->end) {
    r->line++;
    ps_fail(r, "unexpected text after the configurations: \"%.40s\"", r->next);
  }
  free(rows);
  free(x);
  free(v);
  tt_config_destroy(scratch);
  q->observations = obs;
  return r->failed ? TT_ERR_PARSE : TT_OK;
}

static tt_status ps_load(tt_predictor *p, const char *path) {
  if (!p || !path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, PS_NAME ": load: NULL");
  size_t n = 0, body = 0;
  char *text = NULL; /* regular files only, at most 64 MiB (<tunetrace/file.h>) */
  if (tt_file_read(path, "model", PS_MAX_FILE, &text, &n) != TT_OK)
    return tt_set_error(TT_ERR_IO, PS_NAME ": cannot open model %s: %s", path, tt_last_error());
  if (n < sizeof PS_NAME || memcmp(text, PS_NAME " ", sizeof PS_NAME)) {
    tt_free(text);
    return tt_set_error(TT_ERR_PARSE, PS_NAME ": %s is not a " PS_NAME " model", path);
  }
  tt_status st = ps_checksum(text, n, path, &body);
  if (st != TT_OK) {
    tt_free(text);
    return st;
  }
  text[body] = '\0'; /* nothing after the checksummed text is read */
  ps_reader r = {.next = text, .end = text + body, .path = path};
  tt_predictor q = *p; /* the loaded model is built aside: p stays as it was on error */
  q.cfgs = NULL, q.states = NULL, q.ncfg = q.cap = q.nstates = q.scap = 0;
  st = ps_parse(p, &q, &r);
  tt_free(text);
  if (st != TT_OK) {
    ps_clear(&q);
    return st;
  }
  ps_clear(p);
  *p = q;
  return TT_OK;
}

static const tt_predictor_iface ps_iface = {
    .struct_size = sizeof(tt_predictor_iface),
    .space = ps_space,
    .create = ps_create,
    .observe = ps_observe,
    .predict = ps_predict,
    .save = ps_save,
    .load = ps_load,
    .destroy = ps_destroy,
    .create_ex = ps_create_ex,
    .observe_ex = ps_observe_ex,
    .predict_ex = ps_predict_ex,
    .info = ps_info,
    .estimate = ps_estimate,
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
