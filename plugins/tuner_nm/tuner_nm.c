/* tuner_nm: intermodal Nelder-Mead tuner (thesis 2.8.2 and 3.1.3), "tt.tuner/1".
 *
 * INT and FLOAT parameters (and NOM parameters beyond the combination cap) are searched by
 * a Nelder-Mead simplex in the unit cube; every combination of the remaining NOM values
 * ("arm") keeps its own simplex, which is resumed where it was left whenever the scheduler
 * comes back to that combination. See README.md for the design choices. */
#include "tuner_nm_internal.h"

#include <tunetrace/plugin.h>
#include <tt_util/hash.h>
#include <tt_util/rng.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const tt_host *tt__nm_host;
static tt_space *tt__nm_space;

/* ---- random numbers ---- */

/* SplitMix64 (<tt_util/rng.h>): one 64-bit word of state, trivially saved and restored.
 * Returns [0, 1). */
double tt__nm_rand(uint64_t *state) { return tt__u64_to_unit(tt__splitmix64(state)); }

/* ---- measurement cache ---- */

/* Hash of a key (FNV-1a 64 of its bytes, <tt_util/hash.h>), folded so the table's mask
 * sees the high bits too; -0.0 is normalised by the caller so equal values hash equally. */
static uint64_t tt__nm_hash(const double *key, size_t P) {
  uint64_t h = tt__fnv1a64(TT__FNV1A64_OFFSET, key, P * sizeof *key);
  return h ^ (h >> 29);
}

int32_t tt__nm_cache_find(const tt__nm_cache *c, size_t P, const double *key) {
  if (!c->table_size) return -1;
  size_t mask = c->table_size - 1;
  for (size_t s = (size_t)tt__nm_hash(key, P) & mask;; s = (s + 1) & mask) {
    int32_t id = c->table[s];
    if (id < 0) return -1;
    if (!memcmp(&c->keys[(size_t)id * P], key, P * sizeof(double))) return id;
  }
}

/* Rebuilds the open-addressing table at twice the size (load factor stays <= 1/2). */
static tt_status tt__nm_cache_rehash(tt__nm_cache *c, size_t P, size_t size) {
  int32_t *tab = malloc(size * sizeof *tab);
  if (!tab) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: out of memory (cache)");
  for (size_t i = 0; i < size; i++) tab[i] = -1;
  for (size_t id = 0; id < c->count; id++) {
    size_t s = (size_t)tt__nm_hash(&c->keys[id * P], P) & (size - 1);
    while (tab[s] >= 0) s = (s + 1) & (size - 1);
    tab[s] = (int32_t)id;
  }
  free(c->table);
  c->table = tab;
  c->table_size = size;
  return TT_OK;
}

tt_status tt__nm_cache_insert(tt__nm_cache *c, size_t P, const double *key, double sum, int64_t n,
                              int32_t *out_id) {
  if (c->count == c->cap) {
    size_t cap = c->cap ? c->cap * 2 : 64;
    double *keys = realloc(c->keys, cap * (P ? P : 1) * sizeof(double));
    if (keys) c->keys = keys;
    double *sums = keys ? realloc(c->sum, cap * sizeof(double)) : NULL;
    if (sums) c->sum = sums;
    int64_t *ns = sums ? realloc(c->n, cap * sizeof(int64_t)) : NULL;
    if (!ns) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: out of memory (cache)");
    c->n = ns;
    c->cap = cap;
  }
  if ((c->count + 1) * 2 > c->table_size) {
    tt_status st = tt__nm_cache_rehash(c, P, c->table_size ? c->table_size * 2 : 128);
    if (st != TT_OK) return st;
  }
  size_t id = c->count++;
  memcpy(&c->keys[id * P], key, P * sizeof(double));
  c->sum[id] = sum;
  c->n[id] = n;
  size_t s = (size_t)tt__nm_hash(key, P) & (c->table_size - 1);
  while (c->table[s] >= 0) s = (s + 1) & (c->table_size - 1);
  c->table[s] = (int32_t)id;
  *out_id = (int32_t)id;
  return TT_OK;
}

/* Frees the cache arrays. */
static void tt__nm_cache_free(tt__nm_cache *c) {
  free(c->keys);
  free(c->sum);
  free(c->n);
  free(c->table);
  memset(c, 0, sizeof *c);
}

double tt__nm_point_cost(const tt_tuner *t, int32_t id) {
  /* Internally rejected points rank below every measured one, even a measured
   * TT_COST_INFEASIBLE: that is the "worse than the worst seen" penalty. */
  if (id < 0) return INFINITY;
  return t->cache.sum[id] / (double)t->cache.n[id];
}

/* Key of a configuration: INT value, FLOAT value, NOM index, one double each. */
static void tt__nm_key(const tt_tuner *t, const tt_config *cfg, double *key) {
  for (size_t i = 0; i < t->P; i++) {
    tt_value v = tt_config_get(cfg, i);
    tt_param_type ty = tt_space_type(t->target, i);
    double k = ty == TT_PARAM_INT ? (double)v.i : ty == TT_PARAM_FLOAT ? v.f : (double)v.index;
    key[i] = k == 0.0 ? 0.0 : k; /* -0.0 and 0.0 are the same configuration */
  }
}

void tt__nm_config_from_key(tt_tuner *t, tt_config *cfg, const double *key) {
  for (size_t i = 0; i < t->P; i++) {
    if (tt_space_type(t->target, i) == TT_PARAM_NOM) tt_config_set_index(cfg, i, (size_t)key[i]);
    else tt_config_set_number(cfg, i, key[i]);
  }
}

/* ---- settings ---- */

static const char *const tt__nm_init_names[] = {"lhs", "uniform", "normal"};

/* Rejects settings for which Nelder-Mead is not a descent method. */
static tt_check_result tt__nm_settings_check(const tt_space *space, tt_config *cfg, char *why,
                                             size_t why_size, void *user) {
  (void)space, (void)user;
  double r = tt_config_get_float(cfg, "reflection", 1.0);
  double e = tt_config_get_float(cfg, "expansion", 2.0);
  if (!(e > r) || !(e > 1.0)) {
    snprintf(why, why_size, "expansion (%g) must exceed reflection (%g) and 1", e, r);
    return TT_CHECK_INFEASIBLE;
  }
  return TT_CHECK_OK;
}

/* Builds the tuner's own space (published by space()). */
static tt_space *tt__nm_build_space(void) {
  tt_space *s = tt_space_create("tuner_nm", "0.1.0");
  if (!s) return NULL;
  int ok = 1;
  ok &= tt_space_add_float(s, "reflection", 0.1, 4.0, 1.0, 0,
                           "Nelder-Mead reflection coefficient alpha") >= 0;
  ok &= tt_space_add_float(s, "expansion", 1.0, 8.0, 2.0, 0,
                           "expansion coefficient gamma (> reflection)") >= 0;
  ok &=
      tt_space_add_float(s, "contraction", 0.05, 0.95, 0.5, 0, "contraction coefficient rho") >= 0;
  ok &= tt_space_add_float(s, "shrink", 0.05, 0.95, 0.5, 0, "shrink coefficient sigma") >= 0;
  ok &= tt_space_add_nom_string(s, "init", tt__nm_init_names, 3, 0,
                                "initial simplex: Latin hypercube, uniform or centred "
                                "normal around the default configuration") >= 0;
  ok &= tt_space_add_float(s, "initSize", 0.01, 1.0, 0.35, 0,
                           "initial simplex spread in unit space (Active Harmony's "
                           "init percent)") >= 0;
  ok &= tt_space_add_float(s, "tolerance", 1e-9, 0.5, 1e-3, 1,
                           "simplex diameter (unit space) at which a simplex has "
                           "converged and restarts or stops") >= 0;
  ok &= tt_space_add_int(s, "reevaluate", 0, 1000, 1,
                         "re-measure the incumbent every K iterations and average "
                         "(noisy costs); 0 = never") >= 0;
  ok &= tt_space_add_int(s, "maxEvaluations", 0, INT64_C(1000000000000), 0,
                         "stop after this many measurements; 0 = unbounded") >= 0;
  ok &= tt_space_add_float(s, "epsilon", 0.0, 1.0, 0.1, 0,
                           "probability of advancing a random nominal combination "
                           "instead of the best one") >= 0;
  ok &= tt_space_add_int(s, "restarts", 0, 50, 2,
                         "restarts from the best vertex with a halved simplex after "
                         "convergence, before a combination is finished") >= 0;
  tt_space_add_constraint_text(s, "expansion > reflection and expansion > 1");
  tt_space_set_check(s, tt__nm_settings_check, NULL);
  if (!ok) {
    tt_space_destroy(s);
    return NULL;
  }
  return s;
}

const tt_space *tt__nm_settings_space(void) { return tt__nm_space; }

void tt__nm_settings_read(const tt_config *cfg, tt__nm_settings *s) {
  s->reflection = 1.0;
  s->expansion = 2.0;
  s->contraction = 0.5;
  s->shrink = 0.5;
  s->init = TT__NM_INIT_LHS;
  s->init_size = 0.35;
  s->tolerance = 1e-3;
  s->reevaluate = 1;
  s->max_evaluations = 0;
  s->epsilon = 0.1;
  s->restarts = 2;
  if (!cfg) return;
  /* By name, so a settings config of a JSON copy of space() works as well. */
  s->reflection = tt_config_get_float(cfg, "reflection", s->reflection);
  s->expansion = tt_config_get_float(cfg, "expansion", s->expansion);
  s->contraction = tt_config_get_float(cfg, "contraction", s->contraction);
  s->shrink = tt_config_get_float(cfg, "shrink", s->shrink);
  const char *init = tt_config_get_string(cfg, "init");
  if (init)
    for (int i = 0; i < 3; i++)
      if (!strcmp(init, tt__nm_init_names[i])) s->init = i;
  s->init_size = tt_config_get_float(cfg, "initSize", s->init_size);
  s->tolerance = tt_config_get_float(cfg, "tolerance", s->tolerance);
  s->reevaluate = tt_config_get_int(cfg, "reevaluate", s->reevaluate);
  s->max_evaluations = tt_config_get_int(cfg, "maxEvaluations", s->max_evaluations);
  s->epsilon = tt_config_get_float(cfg, "epsilon", s->epsilon);
  s->restarts = tt_config_get_int(cfg, "restarts", s->restarts);
}

/* ---- tuner ---- */

static void tt__nm_destroy(tt_tuner *t);

/* Draws the probe point: one point, uniformly in a box of side initSize/4 around the
 * default (shifted inside [0,1]), at which every arm is probed: the arms are compared at the
 * same INT/FLOAT values near the default, and the default itself, which the caller measures
 * anyway, is not proposed again. */
static void tt__nm_draw_probe(tt_tuner *t) {
  double sz = TT__NM_PROBE_BOX * (t->set.init_size > 1.0 ? 1.0 : t->set.init_size);
  for (size_t d = 0; d < t->n; d++) {
    double l = t->center[d] - 0.5 * sz;
    if (l > 1.0 - sz) l = 1.0 - sz;
    if (l < 0.0) l = 0.0;
    t->probe_pt[d] = l + sz * tt__nm_rand(&t->rng);
  }
}

/* Creates a tuner; see tuner.h. */
static tt_status tt__nm_create(const tt_space *target, const tt_config *settings, uint64_t seed,
                               tt_tuner **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: create: out is NULL");
  *out = NULL;
  if (!target) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: create: no target");
  tt__nm_settings set;
  tt__nm_settings_read(settings, &set);
  if (settings) {
    char why[256];
    if (tt__nm_settings_check(NULL, (tt_config *)settings, why, sizeof why, NULL) != TT_CHECK_OK)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: settings: %s", why);
  }
  if (!(set.reflection > 0.0) || !(set.contraction > 0.0 && set.contraction < 1.0) ||
      !(set.shrink > 0.0 && set.shrink < 1.0) || !(set.init_size > 0.0) || !(set.tolerance > 0.0) ||
      set.reevaluate < 0 || set.max_evaluations < 0 ||
      !(set.epsilon >= 0.0 && set.epsilon <= 1.0) || set.restarts < 0)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: settings out of range");

  tt_tuner *t = calloc(1, sizeof *t);
  if (!t) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: out of memory");
  t->target = target;
  t->set = set;
  t->seed = seed;
  t->rng = seed;
  t->out_arm = -1;
  t->P = tt_space_count(target);
  size_t P = t->P;
  t->dim_param = calloc(P + 1, sizeof(size_t));
  t->armnom_param = calloc(P + 1, sizeof(size_t));
  t->armnom_count = calloc(P + 1, sizeof(size_t));
  t->unit = calloc(P + 1, sizeof(double));
  t->key = calloc(P + 1, sizeof(double));
  t->center = calloc(P + 1, sizeof(double));
  t->proposal = tt_config_create(target);
  t->work = tt_config_create(target);
  t->work2 = tt_config_create(target);
  if (!t->dim_param || !t->armnom_param || !t->armnom_count || !t->unit || !t->key || !t->center ||
      !t->proposal || !t->work || !t->work2) {
    tt__nm_destroy(t);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: out of memory");
  }
  /* NOM parameters become arms while the number of combinations stays within
   * TT__NM_MAX_ARMS; the rest join INT and FLOAT as simplex dimensions. Parents of
   * conditions (tunetrace/params.h: "activeWhen") come first, in space order, then the other
   * NOM parameters in space order: an arm then fixes whether its dependent parameters act,
   * and the proposals' canonicalisation (tt__nm_next) collapses its simplex onto the
   * parameters that do. Parameters marked not tunable are never searched: they keep their
   * default (the session passes the configured value as the default). */
  unsigned char *parent = calloc(P + 1, 1);
  if (!parent) {
    tt__nm_destroy(t);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: out of memory");
  }
  for (size_t i = 0; i < P; i++)
    for (size_t k = 0; k < tt_space_condition_count(target, i); k++) {
      int q = tt_space_condition_parent(target, i, k);
      if (q >= 0 && tt_space_is_tunable(target, (size_t)q)) parent[q] = 1;
    }
  size_t arms = 1;
  for (int pass = 0; pass < 2; pass++)
    for (size_t i = 0; i < P; i++) {
      size_t c = tt_space_nom_count(target, i);
      if (!tt_space_is_tunable(target, i) || parent[i] != (pass == 0)) continue;
      if (tt_space_type(target, i) == TT_PARAM_NOM && arms * c <= TT__NM_MAX_ARMS) {
        t->armnom_param[t->n_armnom] = i;
        t->armnom_count[t->n_armnom++] = c;
        arms *= c;
      } else {
        t->dim_param[t->n++] = i;
      }
    }
  free(parent);
  t->n_arms = arms;
  for (size_t d = 0; d < t->n; d++) {
    /* A restart simplex narrower than two grid steps of an INT (or folded NOM) dimension
     * rounds back to the point it restarts from and cannot leave it. */
    size_t p = t->dim_param[d];
    double span = tt_space_type(target, p) == TT_PARAM_INT
                      ? tt_space_max(target, p) - tt_space_min(target, p)
                  : tt_space_type(target, p) == TT_PARAM_NOM ? (double)tt_space_nom_count(target, p)
                                                             : 0.0;
    if (span > 0.0 && 2.0 / span > t->min_restart) t->min_restart = 2.0 / span;
  }
  if (t->min_restart > 1.0) t->min_restart = 1.0;
  tt_config_to_unit(t->proposal, t->unit); /* proposal holds the defaults here */
  for (size_t d = 0; d < t->n; d++) t->center[d] = t->unit[t->dim_param[d]];
  t->arms = calloc(arms, sizeof *t->arms);
  if (!t->arms) {
    tt__nm_destroy(t);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: out of memory");
  }
  for (size_t a = 0; a < arms; a++) {
    tt__nm_arm *arm = &t->arms[a];
    arm->x = calloc((t->n + 4) * (t->n ? t->n : 1), sizeof(double));
    arm->id = malloc((t->n + 4) * sizeof(int32_t));
    if (!arm->x || !arm->id) {
      tt__nm_destroy(t);
      return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: out of memory");
    }
    for (size_t i = 0; i < t->n + 4; i++) arm->id[i] = -2;
    arm->phase = TT__NM_FRESH;
    arm->reeval_iter = -1;
    arm->size = set.init_size;
    arm->init_spread = NAN;
  }
  t->probe = arms > 1 && t->n > 0 && (double)arms * (double)(t->n + 1) > TT__NM_PROBE_ABOVE;
  t->probe_pt = calloc(t->n + 1, sizeof(double));
  if (!t->probe_pt) {
    tt__nm_destroy(t);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: out of memory");
  }
  if (t->probe) tt__nm_draw_probe(t);
  *out = t;
  return TT_OK;
}

static void tt__nm_destroy(tt_tuner *t) {
  if (!t) return;
  if (t->arms)
    for (size_t a = 0; a < t->n_arms; a++) {
      free(t->arms[a].x);
      free(t->arms[a].id);
    }
  free(t->arms);
  tt__nm_cache_free(&t->cache);
  free(t->dim_param);
  free(t->armnom_param);
  free(t->armnom_count);
  free(t->unit);
  free(t->key);
  free(t->center);
  free(t->probe_pt);
  tt_config_destroy(t->proposal);
  tt_config_destroy(t->work);
  tt_config_destroy(t->work2);
  free(t);
}

/* What a not yet built arm is credited with: the median cost spread of the first full
 * simplices built so far (0 before the first one). */
static double tt__nm_spread_credit(const tt_tuner *t) {
  double v[TT__NM_MAX_ARMS];
  size_t m = 0;
  for (size_t a = 0; a < t->n_arms && m < TT__NM_MAX_ARMS; a++)
    if (!isnan(t->arms[a].init_spread)) {
      double x = t->arms[a].init_spread;
      size_t j = m++;
      while (j > 0 && v[j - 1] > x) v[j] = v[j - 1], j--; /* insertion sort */
      v[j] = x;
    }
  if (!m) return 0.0;
  return m % 2 ? v[m / 2] : 0.5 * (v[m / 2 - 1] + v[m / 2]);
}

/* Picks the arm to advance.
 *
 * Several arms (probe mode): round-robin until every arm has measured its probe (vertex 0
 * at the shared probe point, t->probe_pt); then, with probability epsilon, a random live
 * arm, otherwise the arm with the lowest optimistic bound. A built arm's bound is its best
 * vertex minus the cost spread of its simplex (tt__nm_arm_optimistic); an arm that has no
 * full simplex yet is credited with the median spread of the first simplices of the arms
 * built so far. So simplices are built only for arms whose probe comes within that spread
 * of the incumbent, one after the other, instead of n+1 points for every arm up front.
 *
 * One arm, or no simplex dimension: round-robin until every arm has evaluated its initial
 * simplex, then the same bound. Plain greedy on the incumbent would polish the best arm
 * down to the tolerance while a close second, whose basin may be deeper, waits. */
static int tt__nm_choose_arm(tt_tuner *t) {
  size_t live = 0, A = t->n_arms;
  for (size_t a = 0; a < A; a++) live += t->arms[a].phase != TT__NM_DONE;
  if (!live) return -1;
  for (size_t j = 0; j < A; j++) {
    size_t a = (t->rr + j) % A;
    const tt__nm_arm *arm = &t->arms[a];
    if (t->probe ? arm->phase == TT__NM_FRESH || arm->phase == TT__NM_WAIT_PROBE
                 : arm->phase != TT__NM_DONE && !tt__nm_arm_init_complete(arm)) {
      t->rr = (a + 1) % A;
      return (int)a;
    }
  }
  if (live > 1 && tt__nm_rand(&t->rng) < t->set.epsilon) {
    size_t r = (size_t)(tt__nm_rand(&t->rng) * (double)live);
    for (size_t a = 0; a < A; a++)
      if (t->arms[a].phase != TT__NM_DONE && r-- == 0) return (int)a;
  }
  double credit = t->probe ? tt__nm_spread_credit(t) : 0.0;
  int best = -1;
  double bs = INFINITY;
  for (size_t a = 0; a < A; a++) {
    const tt__nm_arm *arm = &t->arms[a];
    if (arm->phase == TT__NM_DONE) continue;
    double s = t->probe && !tt__nm_arm_built(arm) ? tt__nm_arm_best(t, arm) - credit
                                                  : tt__nm_arm_optimistic(t, arm);
    if (best < 0 || s < bs) best = (int)a, bs = s;
  }
  return best;
}

/* Unit coordinates (simplex dimensions) of the best measured configuration, else the
 * default's: a newly built arm centres its simplex there, so what the other arms learnt
 * about the INT/FLOAT parameters carries over. */
static void tt__nm_incumbent_point(tt_tuner *t, double *x) {
  if (!t->cache.count) {
    memcpy(x, t->center, t->n * sizeof(double));
    return;
  }
  int32_t b = 0;
  for (size_t id = 1; id < t->cache.count; id++)
    if (tt__nm_point_cost(t, (int32_t)id) < tt__nm_point_cost(t, b)) b = (int32_t)id;
  tt__nm_config_from_key(t, t->work2, &t->cache.keys[(size_t)b * t->P]);
  tt_config_to_unit(t->work2, t->unit);
  for (size_t d = 0; d < t->n; d++) x[d] = t->unit[t->dim_param[d]];
}

/* Writes arm `ai`'s pending point into t->work: NOM values of the arm, simplex
 * coordinates for the rest (tt_config_from_unit rounds INT to nearest). */
static void tt__nm_point_config(tt_tuner *t, size_t ai) {
  tt__nm_arm *a = &t->arms[ai];
  size_t rest = ai;
  for (size_t j = 0; j < t->n_armnom; j++) {
    size_t c = t->armnom_count[j];
    t->unit[t->armnom_param[j]] = ((double)(rest % c) + 0.5) / (double)c;
    rest /= c;
  }
  const double *x = &a->x[(size_t)a->pend * t->n];
  for (size_t d = 0; d < t->n; d++) t->unit[t->dim_param[d]] = x[d];
  tt_config_from_unit(t->work, t->unit);
}

/* Copies the best measured configuration to `out`; TT_ERR_NO_DATA if none. */
static tt_status tt__nm_best(const tt_tuner *t, tt_config *out, double *cost) {
  if (!t || !out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: best: NULL");
  if (tt_config_space(out) != t->target)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: best: config of another space");
  if (!t->cache.count) return tt_set_error(TT_ERR_NO_DATA, "tuner_nm: nothing measured yet");
  int32_t b = 0;
  for (size_t id = 1; id < t->cache.count; id++)
    if (tt__nm_point_cost(t, (int32_t)id) < tt__nm_point_cost(t, b)) b = (int32_t)id;
  tt__nm_config_from_key((tt_tuner *)t, out, &t->cache.keys[(size_t)b * t->P]);
  if (cost) *cost = tt__nm_point_cost(t, b);
  return TT_OK;
}

/* Ends the search: `out` gets the best configuration (the checked default if none). */
static tt_status tt__nm_finish(tt_tuner *t, tt_config *out) {
  if (t->cache.count) {
    tt__nm_best(t, out, NULL);
  } else {
    tt_config *def = tt_config_create(t->target);
    if (def) {
      tt_space_check(t->target, def, NULL, 0);
      tt_config_copy(out, def);
      tt_config_destroy(def);
    }
  }
  return TT_DONE;
}

/* Proposes the next configuration; see tuner.h. Points that are infeasible or already
 * measured are answered internally, so only new feasible configurations reach the caller. */
static tt_status tt__nm_next(tt_tuner *t, tt_config *out) {
  if (!t || !out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: next: NULL");
  if (tt_config_space(out) != t->target)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: next: config of another space");
  if (t->out_arm >= 0) {
    tt_config_copy(out, t->proposal);
    return TT_OK;
  }
  if (t->set.max_evaluations > 0 && t->evaluations >= t->set.max_evaluations)
    return tt__nm_finish(t, out);
  char why[256];
  for (long steps = 0; steps < TT__NM_MAX_INTERNAL_STEPS;) {
    int ai = tt__nm_choose_arm(t);
    if (ai < 0) return tt__nm_finish(t, out);
    tt__nm_arm *a = &t->arms[ai];
    int chosen = 1;
    while (a->phase != TT__NM_DONE && steps < TT__NM_MAX_INTERNAL_STEPS) {
      /* A probe answered internally (cache, infeasible): choose again, do not build. */
      if (a->phase == TT__NM_PROBED && !chosen) break;
      chosen = 0;
      if (a->phase == TT__NM_FRESH && t->probe) {
        /* Probe: one point per arm, the same INT/FLOAT coordinates for every arm. */
        memcpy(a->x, t->probe_pt, t->n * sizeof(double));
        for (size_t i = 0; i < t->n + 4; i++) a->id[i] = -2;
        a->phase = TT__NM_WAIT_PROBE;
        a->pend = 0;
        a->k = 0;
      } else if (a->phase == TT__NM_FRESH) {
        tt__nm_arm_generate(t, a, t->center, a->size, 0);
      } else if (a->phase == TT__NM_PROBED) {
        /* Build: the probe stays vertex 0; the other n vertices are a Latin hypercube of
         * side initSize around the incumbent's continuous coordinates. */
        double tmp[64], *c = t->n <= 64 ? tmp : malloc(t->n * sizeof *c);
        if (c) tt__nm_incumbent_point(t, c);
        tt__nm_arm_generate(t, a, c ? c : t->center, a->size, 1);
        if (c != tmp) free(c);
      }
      if (a->phase == TT__NM_WAIT_REEVAL) {
        t->reeval_id = a->id[0];
        tt__nm_config_from_key(t, t->proposal, &t->cache.keys[(size_t)t->reeval_id * t->P]);
        t->out_arm = ai;
        t->out_reeval = 1;
        tt_config_copy(out, t->proposal);
        return TT_OK;
      }
      tt__nm_point_config(t, (size_t)ai);
      tt_config_copy(t->work2, t->work);
      /* Parameters the point's own values leave inactive take their defaults: points that
       * differ only there are one configuration (one cache entry, measured once), and the
       * vertex moves there too, so each arm's simplex spans only what acts in it. */
      int canonical = tt_config_canonicalize(t->work, NULL) > 0;
      tt_check_result r = tt_space_check(t->target, t->work, why, sizeof why);
      if (r == TT_CHECK_REPAIRED || canonical) {
        /* Move the vertex to the repaired point, but only along the dimensions the repair
         * changed, so INT rounding does not snap the continuous simplex to the grid. */
        tt_config_to_unit(t->work, t->unit);
        double *x = &a->x[(size_t)a->pend * t->n];
        for (size_t d = 0; d < t->n; d++) {
          size_t p = t->dim_param[d];
          tt_value v1 = tt_config_get(t->work, p), v0 = tt_config_get(t->work2, p);
          tt_param_type ty = tt_space_type(t->target, p);
          int changed = ty == TT_PARAM_INT     ? v1.i != v0.i
                        : ty == TT_PARAM_FLOAT ? v1.f != v0.f
                                               : v1.index != v0.index;
          if (changed) x[d] = t->unit[p];
        }
        /* A repair must yield a feasible configuration; do not trust one that does not. */
        tt_config_copy(t->work2, t->work);
        if (r == TT_CHECK_REPAIRED &&
            tt_space_check(t->target, t->work2, why, sizeof why) != TT_CHECK_OK)
          r = TT_CHECK_INFEASIBLE;
      }
      steps++;
      if (r == TT_CHECK_INFEASIBLE) {
        a->id[a->pend] = -1;
        tt__nm_arm_receive(t, a);
        continue;
      }
      tt__nm_key(t, t->work, t->key);
      int32_t hit = tt__nm_cache_find(&t->cache, t->P, t->key);
      if (hit >= 0) {
        a->id[a->pend] = hit;
        tt__nm_arm_receive(t, a);
        continue;
      }
      tt_config_copy(t->proposal, t->work);
      t->out_arm = ai;
      t->out_reeval = 0;
      tt_config_copy(out, t->proposal);
      return TT_OK;
    }
  }
  /* Only reachable if the simplex keeps cycling through known points. */
  for (size_t a = 0; a < t->n_arms; a++) t->arms[a].phase = TT__NM_DONE;
  return tt__nm_finish(t, out);
}

/* Records the cost of the outstanding proposal; see tuner.h. */
static tt_status tt__nm_feedback(tt_tuner *t, double cost) {
  if (!t) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: feedback: NULL tuner");
  if (t->out_arm < 0)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: feedback without a proposal");
  if (isnan(cost) || cost == -INFINITY)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: feedback: cost is %g", cost);
  if (cost > TT_COST_INFEASIBLE) cost = TT_COST_INFEASIBLE; /* +inf: failed measurement */
  tt__nm_arm *a = &t->arms[t->out_arm];
  if (t->out_reeval) {
    int32_t id = t->reeval_id;
    /* The first repeated measurement tells whether costs are noisy at all: identical
     * results mean a deterministic cost, and re-measuring would only waste evaluations. */
    if (t->deterministic == 0 && t->cache.n[id] == 1)
      t->deterministic = cost == t->cache.sum[id] ? 1 : -1;
    t->cache.sum[id] += cost;
    t->cache.n[id]++;
  } else {
    int32_t id;
    tt__nm_key(t, t->proposal, t->key);
    tt_status st = tt__nm_cache_insert(&t->cache, t->P, t->key, cost, 1, &id);
    if (st != TT_OK) return st;
    a->id[a->pend] = id;
  }
  t->evaluations++;
  a->evals++;
  t->out_arm = -1;
  tt__nm_arm_receive(t, a);
  return TT_OK;
}

/* What the caller knows (tuner.h, ABI 1.1): the budget decides between building every
 * arm's simplex up front and probe mode (the fixed TT__NM_PROBE_ABOVE stands in for a budget
 * nobody told us); the default's measured cost goes into the cache, so a vertex that rounds
 * to the default configuration is answered without a measurement and the default competes
 * for best(). The state is not used by a pure search. */
static tt_status tt__nm_set_context(tt_tuner *t, const tt_tuner_context *ctx) {
  if (!t || !ctx) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: set_context: NULL");
  if (!TT_HAS_FIELD(tt_tuner_context, ctx, budget))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tuner_nm: set_context: context of %u bytes, "
                        "shorter than ABI 1.1's %zu",
                        ctx->struct_size, offsetof(tt_tuner_context, budget) + sizeof ctx->budget);
  if ((ctx->state == NULL) != (ctx->state_dim == 0))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tuner_nm: set_context: state %s with "
                        "state_dim %u",
                        ctx->state ? "given" : "NULL", ctx->state_dim);
  if (t->evaluations || t->out_arm >= 0 || t->cache.count || t->context_set)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: set_context: only once, before the "
                                                 "first next()");
  double dc = ctx->default_cost;
  if (!isnan(dc) && !(dc > 0))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tuner_nm: set_context: default cost %g is "
                        "neither NAN nor positive",
                        dc);
  if (ctx->budget > 0) {
    int probe =
        t->n_arms > 1 && t->n > 0 && (double)t->n_arms * (double)(t->n + 1) > (double)ctx->budget;
    if (probe && !t->probe) tt__nm_draw_probe(t);
    t->probe = probe;
    t->budget = ctx->budget;
  }
  if (!isnan(dc)) {
    tt_config *def = tt_config_create(t->target);
    if (!def) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: out of memory");
    int32_t id;
    tt__nm_key(t, def, t->key);
    tt_config_destroy(def);
    tt_status st = tt__nm_cache_insert(&t->cache, t->P, t->key,
                                       dc > TT_COST_INFEASIBLE ? TT_COST_INFEASIBLE : dc, 1, &id);
    if (st != TT_OK) return st;
  }
  t->context_set = 1;
  return TT_OK;
}

static tt_status tt__nm_save_state(const tt_tuner *t, char **json) { return tt__nm_save(t, json); }

static tt_status tt__nm_load_state(tt_tuner *t, const char *json) { return tt__nm_load(t, json); }

/* The settings space, built at init. */
static const tt_space *tt__nm_space_fn(void) { return tt__nm_space; }

static const tt_tuner_iface tt__nm_iface = {
    .struct_size = sizeof(tt_tuner_iface),
    .space = tt__nm_space_fn,
    .create = tt__nm_create,
    .next = tt__nm_next,
    .feedback = tt__nm_feedback,
    .best = tt__nm_best,
    .save_state = tt__nm_save_state,
    .load_state = tt__nm_load_state,
    .destroy = tt__nm_destroy,
    .set_context = tt__nm_set_context,
};

/* Builds the settings space once per load. */
static tt_status tt__nm_init(const tt_host *host) {
  tt__nm_host = host;
  if (!tt__nm_space) tt__nm_space = tt__nm_build_space();
  if (!tt__nm_space) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: settings space");
  return TT_OK;
}

/* Frees the settings space; every tuner has been destroyed by now. */
static void tt__nm_deinit(void) {
  tt_space_destroy(tt__nm_space);
  tt__nm_space = NULL;
  tt__nm_host = NULL;
}

/* Serves "tt.tuner/1" only. */
static const void *tt__nm_get_interface(const char *id) {
  return id && !strcmp(id, TT_TUNER_INTERFACE_ID) ? &tt__nm_iface : NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
    .struct_size = sizeof(tt_plugin),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .kind = TT_KIND_TUNER,
    .name = "tuner_nm",
    .version = "0.1.0",
    .description = "intermodal Nelder-Mead tuner: one resumable simplex per nominal "
                   "combination, Latin hypercube start, incumbent re-measurement",
    .init = tt__nm_init,
    .deinit = tt__nm_deinit,
    .get_interface = tt__nm_get_interface,
};
