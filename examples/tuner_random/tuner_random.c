/* tuner_random: a random-search tuner plugin for tunetrace, written as a third party would
 * write one (only <tunetrace/...> headers and libtunetrace, built with pkg-config).
 *
 * Search: the first `samples` proposals form one Latin hypercube over the target space's
 * unit cube (every parameter's range is cut into `samples` strata and each stratum is hit
 * exactly once), which covers the space evenly with few measurements; afterwards, or with
 * lhs=false from the start, proposals are uniform random points. Every proposal is mapped
 * to a configuration with tt_config_from_unit, canonicalised (parameters marked not tunable
 * or inactive keep their defaults: tunetrace/params.h) and passed through tt_space_check: a
 * repaired configuration is proposed as repaired, an infeasible one is re-drawn (up to 100
 * draws).
 *
 * Determinism: all randomness comes from xoshiro256** seeded from the create() seed, so a
 * seed and a cost sequence give the same proposals on every machine; save_state stores the
 * generator state, the iteration, the outstanding proposal and the best point, so that a
 * resumed tuner continues exactly where the saved one stopped.
 */
#include <tunetrace/plugin.h>
#include <tunetrace/tuner.h>

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TR_NAME "tuner_random"
#define TR_VERSION "1.0.0"
#define TR_STATE_FORMAT 1
#define TR_MAX_DRAWS 100
#define TR_DEFAULT_SAMPLES 16

static const tt_host *tr_host; /* valid between init and deinit */
static tt_space *tr_settings;  /* the tuner's own settings space */

struct tt_tuner {
  const tt_space *target;
  size_t dim; /* parameters in the target space */
  uint64_t seed;
  int64_t samples;           /* size of the Latin hypercube */
  int lhs;                   /* 0: uniform random from the start */
  uint64_t rng[4];           /* xoshiro256** state for every draw after create */
  uint32_t *cells;           /* samples x dim stratum indices of the hypercube */
  double *design;            /* samples x dim first-choice points inside those strata */
  uint64_t iteration;        /* proposals that received feedback */
  int pending;               /* a proposal awaits feedback */
  double *pending_unit;      /* the drawn point behind the outstanding proposal */
  tt_config *pending_config; /* that point after tt_space_check (what next() returned) */
  int has_best;
  double best_cost;
  double *best_unit; /* the drawn point behind the best configuration */
  tt_config *best_config;
  double *scratch; /* dim doubles for drawing */
};

/* ---- random numbers ---- */

/* SplitMix64: expands a 64-bit seed into well-mixed generator state. */
static uint64_t tr_splitmix(uint64_t *x) {
  uint64_t z = (*x += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/* Seeds xoshiro256** from `seed` and a stream tag, so the hypercube and the later draws
 * use independent streams. */
static void tr_seed(uint64_t s[4], uint64_t seed, uint64_t stream) {
  uint64_t x = seed ^ (stream * 0xd1b54a32d192ed03ull);
  for (int i = 0; i < 4; i++) s[i] = tr_splitmix(&x);
}

/* Rotate left, for xoshiro. */
static uint64_t tr_rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

/* xoshiro256**: small, fast, and its whole state fits in the saved JSON. */
static uint64_t tr_next_u64(uint64_t s[4]) {
  uint64_t result = tr_rotl(s[1] * 5, 7) * 9, t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = tr_rotl(s[3], 45);
  return result;
}

/* Uniform double in [0, 1) with 53 random bits. */
static double tr_uniform(uint64_t s[4]) { return (double)(tr_next_u64(s) >> 11) * 0x1.0p-53; }

/* Uniform integer in [0, n) without modulo bias (rejection sampling). */
static uint32_t tr_below(uint64_t s[4], uint32_t n) {
  uint64_t limit = UINT64_MAX - UINT64_MAX % n;
  uint64_t x;
  do x = tr_next_u64(s);
  while (x >= limit);
  return (uint32_t)(x % n);
}

/* ---- settings space ---- */

/* The settings space published through space(); NULL before init. */
static const tt_space *tr_space(void) { return tr_settings; }

/* Reads an integer setting, falling back to the default when settings are NULL. */
static int64_t tr_setting(const tt_config *settings, const char *name, int64_t def) {
  return settings ? tt_config_get_int(settings, name, def) : def;
}

/* ---- the tuner ---- */

static void tr_destroy(tt_tuner *t);

/* Builds the Latin hypercube: per dimension a random permutation of the strata, plus a
 * random offset inside each stratum. Depends only on the seed, so load_state can rely on a
 * tuner created with the same seed having the same design. */
static void tr_build_design(tt_tuner *t) {
  uint64_t s[4];
  tr_seed(s, t->seed, 1);
  uint32_t n = (uint32_t)t->samples;
  for (size_t j = 0; j < t->dim; j++) {
    for (uint32_t k = 0; k < n; k++) t->cells[k * t->dim + j] = k;
    for (uint32_t k = n - 1; k > 0; k--) { /* Fisher-Yates */
      uint32_t r = tr_below(s, k + 1), tmp = t->cells[k * t->dim + j];
      t->cells[k * t->dim + j] = t->cells[r * t->dim + j];
      t->cells[r * t->dim + j] = tmp;
    }
    for (uint32_t k = 0; k < n; k++)
      t->design[k * t->dim + j] = (t->cells[k * t->dim + j] + tr_uniform(s)) / n;
  }
}

/* Creates a tuner; see tt_tuner_iface.create. */
static tt_status tr_create(const tt_space *target, const tt_config *settings, uint64_t seed,
                           tt_tuner **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, TR_NAME ": create: out is NULL");
  *out = NULL;
  if (!target) return tt_set_error(TT_ERR_INVALID_ARGUMENT, TR_NAME ": create: no target space");
  int64_t samples = tr_setting(settings, "samples", TR_DEFAULT_SAMPLES);
  if (samples < 1 || samples > 4096)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TR_NAME ": samples must be in [1, 4096], got %lld",
                        (long long)samples);
  tt_tuner *t = calloc(1, sizeof *t);
  if (!t) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TR_NAME ": out of memory");
  t->target = target;
  t->dim = tt_space_count(target);
  t->seed = seed;
  t->samples = samples;
  t->lhs = tr_setting(settings, "lhs", 1) != 0;
  size_t d = t->dim ? t->dim : 1; /* keep allocations non-empty for a 0-parameter space */
  t->cells = malloc((size_t)samples * d * sizeof *t->cells);
  t->design = malloc((size_t)samples * d * sizeof *t->design);
  t->pending_unit = calloc(d, sizeof(double));
  t->best_unit = calloc(d, sizeof(double));
  t->scratch = calloc(d, sizeof(double));
  t->pending_config = tt_config_create(target);
  t->best_config = tt_config_create(target);
  if (!t->cells || !t->design || !t->pending_unit || !t->best_unit || !t->scratch ||
      !t->pending_config || !t->best_config) {
    tr_destroy(t);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TR_NAME ": out of memory for %zu parameters", t->dim);
  }
  tr_build_design(t);
  tr_seed(t->rng, seed, 2);
  *out = t;
  return TT_OK;
}

/* Maps a drawn unit point to the configuration it proposes: from_unit, then what the space
 * marks (tunetrace/params.h): parameters not tunable, or inactive under the point's own
 * values, go back to their defaults (tt_config_canonicalize; the session passes the
 * configured values as defaults), then the space's check. Deterministic, so a saved point
 * always gives back the same configuration. */
static tt_check_result tr_realize(const tt_tuner *t, const double *unit, tt_config *cfg, char *why,
                                  size_t why_size) {
  tt_config_from_unit(cfg, unit);
  tt_config_canonicalize(cfg, NULL);
  return tt_space_check(t->target, cfg, why, why_size);
}

/* Draws attempt `attempt` of proposal number `it` into t->scratch. During the hypercube,
 * the first attempt is the design point and re-draws stay inside its strata for half the
 * attempts (to keep the stratification); everything else is uniform over the cube. */
static void tr_draw(tt_tuner *t, uint64_t it, int attempt) {
  int in_design = t->lhs && it < (uint64_t)t->samples;
  for (size_t j = 0; j < t->dim; j++) {
    if (in_design && attempt == 0) {
      t->scratch[j] = t->design[it * t->dim + j];
    } else if (in_design && attempt < TR_MAX_DRAWS / 2) {
      t->scratch[j] = (t->cells[it * t->dim + j] + tr_uniform(t->rng)) / (double)t->samples;
    } else {
      t->scratch[j] = tr_uniform(t->rng);
    }
  }
}

/* Proposes the next configuration; see tt_tuner_iface.next. */
static tt_status tr_next(tt_tuner *t, tt_config *out) {
  if (!t || !out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, TR_NAME ": next: NULL argument");
  if (!t->pending) {
    char why[256] = "";
    int found = 0;
    for (int attempt = 0; attempt < TR_MAX_DRAWS && !found; attempt++) {
      tr_draw(t, t->iteration, attempt);
      why[0] = '\0';
      found = tr_realize(t, t->scratch, t->pending_config, why, sizeof why) != TT_CHECK_INFEASIBLE;
    }
    if (!found)
      return tt_set_error(TT_ERR_INFEASIBLE,
                          TR_NAME ": no feasible configuration of %s in %d draws (last: %s)",
                          tt_space_plugin(t->target), TR_MAX_DRAWS, why);
    memcpy(t->pending_unit, t->scratch, t->dim * sizeof(double));
    t->pending = 1;
  }
  tt_config_copy(out, t->pending_config);
  return TT_OK;
}

/* Records the cost of the outstanding proposal; see tt_tuner_iface.feedback. */
static tt_status tr_feedback(tt_tuner *t, double cost) {
  if (!t) return tt_set_error(TT_ERR_INVALID_ARGUMENT, TR_NAME ": feedback: NULL tuner");
  if (!t->pending)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TR_NAME ": feedback without an outstanding proposal");
  if (cost != cost) return tt_set_error(TT_ERR_INVALID_ARGUMENT, TR_NAME ": feedback: cost is NaN");
  if (!t->has_best || cost < t->best_cost) {
    t->has_best = 1;
    t->best_cost = cost;
    memcpy(t->best_unit, t->pending_unit, t->dim * sizeof(double));
    tt_config_copy(t->best_config, t->pending_config);
  }
  t->pending = 0;
  t->iteration++;
  return TT_OK;
}

/* Best configuration so far; see tt_tuner_iface.best. */
static tt_status tr_best(const tt_tuner *t, tt_config *out, double *cost) {
  if (!t) return tt_set_error(TT_ERR_INVALID_ARGUMENT, TR_NAME ": best: NULL tuner");
  if (!t->has_best) return tt_set_error(TT_ERR_NO_DATA, TR_NAME ": no configuration measured yet");
  if (out) tt_config_copy(out, t->best_config);
  if (cost) *cost = t->best_cost;
  return TT_OK;
}

/* ---- state as JSON ---- */

/* A growable output buffer for save_state. */
typedef struct tr_buf {
  char *s;
  size_t n, cap;
  int failed;
} tr_buf;

/* Appends printf-formatted text; remembers an allocation failure for the caller. */
static void tr_printf(tr_buf *b, const char *fmt, ...) TT_PRINTF(2, 3);
static void tr_printf(tr_buf *b, const char *fmt, ...) {
  if (b->failed) return;
  for (;;) {
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(b->s + b->n, b->cap - b->n, fmt, ap);
    va_end(ap);
    if (k < 0) {
      b->failed = 1;
      return;
    }
    if ((size_t)k < b->cap - b->n) {
      b->n += (size_t)k;
      return;
    }
    size_t cap = (b->cap + (size_t)k + 1) * 2;
    char *s = realloc(b->s, cap);
    if (!s) {
      b->failed = 1;
      return;
    }
    b->s = s;
    b->cap = cap;
  }
}

/* Writes a unit vector; %.17g round-trips every double exactly. */
static void tr_print_vec(tr_buf *b, const double *v, size_t n) {
  tr_printf(b, "[");
  for (size_t j = 0; j < n; j++) tr_printf(b, "%s%.17g", j ? ", " : "", v[j]);
  tr_printf(b, "]");
}

/* Serialises the search state; see tt_tuner_iface.save_state. 64-bit integers are written
 * as hex strings because JSON readers commonly hold numbers as doubles. */
static tt_status tr_save_state(const tt_tuner *t, char **json) {
  if (!t || !json)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TR_NAME ": save_state: NULL argument");
  *json = NULL;
  tr_buf b = {0};
  b.cap = 256;
  b.s = malloc(b.cap);
  if (!b.s) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TR_NAME ": out of memory");
  tr_printf(&b, "{\n  \"tuner\": \"%s\",\n  \"format\": %d,\n", TR_NAME, TR_STATE_FORMAT);
  tr_printf(&b, "  \"seed\": \"%016llx\",\n  \"dim\": %zu,\n  \"samples\": %lld,\n",
            (unsigned long long)t->seed, t->dim, (long long)t->samples);
  tr_printf(&b, "  \"lhs\": %s,\n  \"iteration\": %llu,\n", t->lhs ? "true" : "false",
            (unsigned long long)t->iteration);
  tr_printf(&b, "  \"rng\": [\"%016llx\", \"%016llx\", \"%016llx\", \"%016llx\"],\n",
            (unsigned long long)t->rng[0], (unsigned long long)t->rng[1],
            (unsigned long long)t->rng[2], (unsigned long long)t->rng[3]);
  tr_printf(&b, "  \"pending\": ");
  if (t->pending) tr_print_vec(&b, t->pending_unit, t->dim);
  else tr_printf(&b, "null");
  tr_printf(&b, ",\n  \"best_cost\": ");
  if (t->has_best) tr_printf(&b, "%.17g", t->best_cost);
  else tr_printf(&b, "null");
  tr_printf(&b, ",\n  \"best\": ");
  if (t->has_best) tr_print_vec(&b, t->best_unit, t->dim);
  else tr_printf(&b, "null");
  tr_printf(&b, "\n}\n");
  if (b.failed) {
    free(b.s);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TR_NAME ": out of memory writing state");
  }
  /* Callers release the text with tt_free, which is free(). */
  *json = b.s;
  return TT_OK;
}

/* Skips JSON whitespace. */
static const char *tr_ws(const char *p) {
  while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') p++;
  return p;
}

/* Finds the value of top-level `"key":` in our own flat state format, or NULL. */
static const char *tr_key(const char *json, const char *key) {
  size_t n = strlen(key);
  for (const char *p = json; (p = strchr(p, '"')); p++) {
    if (strncmp(p + 1, key, n) == 0 && p[n + 1] == '"') {
      const char *q = tr_ws(p + n + 2);
      if (*q == ':') return tr_ws(q + 1);
    }
  }
  return NULL;
}

/* Parses "hex" as a 64-bit value. */
static int tr_parse_hex(const char *p, uint64_t *out, const char **end) {
  if (*p != '"') return 0;
  char *e;
  *out = strtoull(p + 1, &e, 16);
  if (e == p + 1 || *e != '"') return 0;
  if (end) *end = e + 1;
  return 1;
}

/* Parses a JSON number. */
static int tr_parse_num(const char *p, double *out, const char **end) {
  char *e;
  *out = strtod(p, &e);
  if (e == p) return 0;
  if (end) *end = e;
  return 1;
}

/* Parses a JSON array of exactly `n` numbers into v. */
static int tr_parse_vec(const char *p, double *v, size_t n) {
  if (*p != '[') return 0;
  p = tr_ws(p + 1);
  for (size_t j = 0; j < n; j++) {
    if (j) {
      if (*p != ',') return 0;
      p = tr_ws(p + 1);
    }
    if (!tr_parse_num(p, &v[j], &p)) return 0;
    p = tr_ws(p);
  }
  return *p == ']';
}

/* True if the value at p is JSON null. */
static int tr_is_null(const char *p) { return p && strncmp(p, "null", 4) == 0; }

/* Restores a state written by tr_save_state; see tt_tuner_iface.load_state. Everything is
 * parsed into locals first so that a bad state leaves the tuner untouched. */
static tt_status tr_load_state(tt_tuner *t, const char *json) {
  if (!t || !json)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TR_NAME ": load_state: NULL argument");
  const char *p = tr_key(json, "tuner");
  if (!p || strncmp(p, "\"" TR_NAME "\"", sizeof(TR_NAME) + 1) != 0)
    return tt_set_error(TT_ERR_PARSE,
                        TR_NAME ": load_state: not a " TR_NAME
                                " state (\"tuner\" is missing or names another tuner)");
  double num;
  if (!(p = tr_key(json, "format")) || !tr_parse_num(p, &num, NULL) || num != TR_STATE_FORMAT)
    return tt_set_error(TT_ERR_PARSE, TR_NAME ": load_state: state format is not %d",
                        TR_STATE_FORMAT);
  uint64_t seed;
  if (!(p = tr_key(json, "seed")) || !tr_parse_hex(p, &seed, NULL))
    return tt_set_error(TT_ERR_PARSE, TR_NAME ": load_state: missing or malformed \"seed\"");
  if (seed != t->seed)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TR_NAME
                        ": load_state: state was saved with seed %llu, this tuner has seed %llu",
                        (unsigned long long)seed, (unsigned long long)t->seed);
  if (!(p = tr_key(json, "dim")) || !tr_parse_num(p, &num, NULL))
    return tt_set_error(TT_ERR_PARSE, TR_NAME ": load_state: missing \"dim\"");
  if (num != (double)t->dim)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TR_NAME ": load_state: state has %g parameters, target space %s has %zu",
                        num, tt_space_plugin(t->target), t->dim);
  if (!(p = tr_key(json, "samples")) || !tr_parse_num(p, &num, NULL))
    return tt_set_error(TT_ERR_PARSE, TR_NAME ": load_state: missing \"samples\"");
  if (num != (double)t->samples)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TR_NAME ": load_state: state has samples %g, this tuner has samples %lld",
                        num, (long long)t->samples);
  if (!(p = tr_key(json, "lhs")) || (strncmp(p, "true", 4) != 0 && strncmp(p, "false", 5) != 0))
    return tt_set_error(TT_ERR_PARSE, TR_NAME ": load_state: missing \"lhs\"");
  if ((*p == 't') != t->lhs)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TR_NAME ": load_state: state has lhs %s, this tuner has lhs %s",
                        *p == 't' ? "true" : "false", t->lhs ? "true" : "false");
  if (!(p = tr_key(json, "iteration")) || !tr_parse_num(p, &num, NULL) || num < 0)
    return tt_set_error(TT_ERR_PARSE, TR_NAME ": load_state: missing or malformed \"iteration\"");
  uint64_t iteration = strtoull(p, NULL, 10);
  uint64_t rng[4];
  if (!(p = tr_key(json, "rng")) || *p != '[')
    return tt_set_error(TT_ERR_PARSE, TR_NAME ": load_state: missing \"rng\"");
  p = tr_ws(p + 1);
  for (int i = 0; i < 4; i++) {
    if (i) {
      if (*p != ',')
        return tt_set_error(TT_ERR_PARSE, TR_NAME ": load_state: \"rng\" needs 4 values");
      p = tr_ws(p + 1);
    }
    if (!tr_parse_hex(p, &rng[i], &p))
      return tt_set_error(TT_ERR_PARSE, TR_NAME ": load_state: \"rng\" needs 4 hex strings");
    p = tr_ws(p);
  }
  size_t d = t->dim ? t->dim : 1;
  double *pending = calloc(d, sizeof(double)), *best = calloc(d, sizeof(double));
  tt_config *pending_cfg = tt_config_create(t->target), *best_cfg = tt_config_create(t->target);
  tt_status st = TT_OK;
  int has_pending = 0, has_best = 0;
  double best_cost = 0;
  char why[256];
  if (!pending || !best || !pending_cfg || !best_cfg) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, TR_NAME ": out of memory");
    goto done;
  }
  p = tr_key(json, "pending");
  if (p && !tr_is_null(p)) {
    if (!tr_parse_vec(p, pending, t->dim)) {
      st = tt_set_error(TT_ERR_PARSE, TR_NAME ": load_state: \"pending\" is not %zu numbers",
                        t->dim);
      goto done;
    }
    if (tr_realize(t, pending, pending_cfg, why, sizeof why) == TT_CHECK_INFEASIBLE) {
      st = tt_set_error(TT_ERR_INFEASIBLE, TR_NAME ": load_state: pending point infeasible: %s",
                        why);
      goto done;
    }
    has_pending = 1;
  }
  p = tr_key(json, "best");
  if (p && !tr_is_null(p)) {
    const char *c = tr_key(json, "best_cost");
    if (!c || !tr_parse_num(c, &best_cost, NULL) || !tr_parse_vec(p, best, t->dim)) {
      st = tt_set_error(TT_ERR_PARSE,
                        TR_NAME ": load_state: \"best\" needs %zu numbers and \"best_cost\"",
                        t->dim);
      goto done;
    }
    if (tr_realize(t, best, best_cfg, why, sizeof why) == TT_CHECK_INFEASIBLE) {
      st = tt_set_error(TT_ERR_INFEASIBLE, TR_NAME ": load_state: best point infeasible: %s", why);
      goto done;
    }
    has_best = 1;
  }
  /* Everything parsed: commit. */
  memcpy(t->rng, rng, sizeof rng);
  t->iteration = iteration;
  t->pending = has_pending;
  if (has_pending) {
    memcpy(t->pending_unit, pending, t->dim * sizeof(double));
    tt_config_copy(t->pending_config, pending_cfg);
  }
  t->has_best = has_best;
  if (has_best) {
    t->best_cost = best_cost;
    memcpy(t->best_unit, best, t->dim * sizeof(double));
    tt_config_copy(t->best_config, best_cfg);
  }
done:
  free(pending);
  free(best);
  tt_config_destroy(pending_cfg);
  tt_config_destroy(best_cfg);
  return st;
}

/* Frees everything the tuner owns (NULL is ignored). */
static void tr_destroy(tt_tuner *t) {
  if (!t) return;
  free(t->cells);
  free(t->design);
  free(t->pending_unit);
  free(t->best_unit);
  free(t->scratch);
  tt_config_destroy(t->pending_config);
  tt_config_destroy(t->best_config);
  free(t);
}

static const tt_tuner_iface tr_iface = {
    .struct_size = sizeof(tt_tuner_iface),
    .space = tr_space,
    .create = tr_create,
    .next = tr_next,
    .feedback = tr_feedback,
    .best = tr_best,
    .save_state = tr_save_state,
    .load_state = tr_load_state,
    .destroy = tr_destroy,
};

/* ---- plugin entry ---- */

/* Builds the settings space once; it lives until deinit like every published space. */
static tt_status tr_init(const tt_host *host) {
  tr_host = host;
  tr_settings = tt_space_create(TR_NAME, TR_VERSION);
  if (!tr_settings)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TR_NAME ": cannot create settings space");
  if (tt_space_add_int(tr_settings, "samples", 1, 4096, TR_DEFAULT_SAMPLES,
                       "Latin hypercube size: the first proposals cover each parameter's range "
                       "in this many strata") < 0 ||
      tt_space_add_nom_bool(tr_settings, "lhs", 1,
                            "start with a Latin hypercube (false: uniform random only)") < 0) {
    tt_space_destroy(tr_settings);
    tr_settings = NULL;
    return tt_set_error(TT_ERR_INTERNAL, TR_NAME ": cannot build settings space");
  }
  return TT_OK;
}

/* Releases the settings space; the host has destroyed every tuner by now. */
static void tr_deinit(void) {
  tt_space_destroy(tr_settings);
  tr_settings = NULL;
  tr_host = NULL;
}

/* Serves "tt.tuner/1" only. */
static const void *tr_get_interface(const char *id) {
  return strcmp(id, TT_TUNER_INTERFACE_ID) == 0 ? &tr_iface : NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
    .struct_size = sizeof(tt_plugin),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .kind = TT_KIND_TUNER,
    .name = TR_NAME,
    .version = TR_VERSION,
    .description = "random search: a Latin hypercube, then uniform random points",
    .init = tr_init,
    .deinit = tr_deinit,
    .get_interface = tr_get_interface,
};
