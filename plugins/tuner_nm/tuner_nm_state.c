/* tuner_nm: save_state/load_state as JSON. The state holds everything next() depends on
 * (RNG word, every arm's simplex and trial points, the measurement cache with its sums and
 * counts, the outstanding proposal), so a tuner that loads it proposes exactly what the
 * saving tuner would have. Doubles are written as raw %.17g numbers: cJSON's own printer
 * accepts %.15g when it reads back within an epsilon, which is not bit-exact. */
#include "tuner_nm_internal.h"

#include <cjson/cJSON.h>

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TT__NM_FORMAT 1

/* Adds a 64-bit word as a hex string: JSON numbers are doubles and would lose bits. */
static void tt__nm_add_u64(cJSON *obj, const char *name, uint64_t v) {
  char buf[32];
  snprintf(buf, sizeof buf, "%016" PRIx64, v);
  cJSON_AddStringToObject(obj, name, buf);
}

/* A number item that reads back bit-exactly (17 significant digits, strtod on parse). */
static cJSON *tt__nm_exact(double v) {
  char buf[40];
  if (!isfinite(v)) v = v < 0 ? -TT_COST_INFEASIBLE : TT_COST_INFEASIBLE; /* not in JSON */
  snprintf(buf, sizeof buf, "%.17g", v);
  return cJSON_CreateRaw(buf);
}

/* Adds member `name` as an exact number. */
static void tt__nm_add_exact(cJSON *obj, const char *name, double v) {
  cJSON_AddItemToObject(obj, name, tt__nm_exact(v));
}

/* Adds an array of doubles. */
static cJSON *tt__nm_doubles(const double *v, size_t n) {
  cJSON *arr = cJSON_CreateArray();
  for (size_t i = 0; arr && i < n; i++) cJSON_AddItemToArray(arr, tt__nm_exact(v[i]));
  return arr;
}

/* Serialises the settings so a load can name the one that differs. */
static cJSON *tt__nm_settings_json(const tt__nm_settings *s) {
  cJSON *o = cJSON_CreateObject();
  tt__nm_add_exact(o, "reflection", s->reflection);
  tt__nm_add_exact(o, "expansion", s->expansion);
  tt__nm_add_exact(o, "contraction", s->contraction);
  tt__nm_add_exact(o, "shrink", s->shrink);
  tt__nm_add_exact(o, "init", s->init);
  tt__nm_add_exact(o, "initSize", s->init_size);
  tt__nm_add_exact(o, "tolerance", s->tolerance);
  tt__nm_add_exact(o, "reevaluate", (double)s->reevaluate);
  tt__nm_add_exact(o, "maxEvaluations", (double)s->max_evaluations);
  tt__nm_add_exact(o, "epsilon", s->epsilon);
  tt__nm_add_exact(o, "restarts", (double)s->restarts);
  return o;
}

tt_status tt__nm_save(const tt_tuner *t, char **json) {
  if (!t || !json) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: save_state: NULL");
  *json = NULL;
  size_t P = t->P, n = t->n;
  cJSON *root = cJSON_CreateObject();
  if (!root) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: save_state: out of memory");
  cJSON_AddStringToObject(root, "tuner", "tuner_nm");
  cJSON_AddNumberToObject(root, "format", TT__NM_FORMAT);
  cJSON_AddStringToObject(root, "target", tt_space_plugin(t->target));
  cJSON_AddNumberToObject(root, "parameters", (double)P);
  cJSON_AddNumberToObject(root, "dimensions", (double)n);
  cJSON_AddNumberToObject(root, "arms", (double)t->n_arms);
  cJSON_AddItemToObject(root, "settings", tt__nm_settings_json(&t->set));
  tt__nm_add_u64(root, "seed", t->seed);
  tt__nm_add_u64(root, "rng", t->rng);
  cJSON_AddNumberToObject(root, "evaluations", (double)t->evaluations);
  cJSON_AddNumberToObject(root, "deterministic", t->deterministic);
  cJSON_AddNumberToObject(root, "roundRobin", (double)t->rr);
  cJSON_AddItemToObject(root, "probePoint", tt__nm_doubles(t->probe_pt, n));
  /* set_context's effects (the default's cost is in the cache) */
  cJSON_AddBoolToObject(root, "probe", t->probe);
  tt__nm_add_u64(root, "budget", t->budget);
  cJSON_AddBoolToObject(root, "contextSet", t->context_set);

  if (t->out_arm >= 0) {
    cJSON *o = cJSON_AddObjectToObject(root, "outstanding");
    cJSON_AddNumberToObject(o, "arm", t->out_arm);
    cJSON_AddNumberToObject(o, "reeval", t->out_reeval);
    cJSON_AddNumberToObject(o, "reevalId", t->reeval_id);
    double *key = malloc((P + 1) * sizeof *key);
    if (key) {
      /* The key, not a config JSON: it restores FLOAT values bit-exactly. */
      for (size_t i = 0; i < P; i++) {
        tt_value v = tt_config_get(t->proposal, i);
        tt_param_type ty = tt_space_type(t->target, i);
        key[i] = ty == TT_PARAM_INT ? (double)v.i : ty == TT_PARAM_FLOAT ? v.f : v.index;
      }
      cJSON_AddItemToObject(o, "key", tt__nm_doubles(key, P));
      free(key);
    }
  } else {
    cJSON_AddNullToObject(root, "outstanding");
  }

  cJSON *cache = cJSON_AddObjectToObject(root, "cache");
  cJSON *keys = cJSON_AddArrayToObject(cache, "keys");
  for (size_t i = 0; i < t->cache.count; i++)
    cJSON_AddItemToArray(keys, tt__nm_doubles(&t->cache.keys[i * P], P));
  cJSON_AddItemToObject(cache, "sum", tt__nm_doubles(t->cache.sum, t->cache.count));
  cJSON *cn = cJSON_AddArrayToObject(cache, "n");
  for (size_t i = 0; i < t->cache.count; i++)
    cJSON_AddItemToArray(cn, cJSON_CreateNumber((double)t->cache.n[i]));

  cJSON *arms = cJSON_AddArrayToObject(root, "armStates");
  for (size_t ai = 0; ai < t->n_arms; ai++) {
    const tt__nm_arm *a = &t->arms[ai];
    cJSON *o = cJSON_CreateObject();
    cJSON_AddItemToArray(arms, o);
    cJSON_AddNumberToObject(o, "phase", a->phase);
    cJSON_AddNumberToObject(o, "pend", a->pend);
    cJSON_AddNumberToObject(o, "k", a->k);
    cJSON_AddNumberToObject(o, "iter", (double)a->iter);
    cJSON_AddNumberToObject(o, "reevalIter", (double)a->reeval_iter);
    cJSON_AddNumberToObject(o, "restarts", (double)a->restarts);
    tt__nm_add_exact(o, "size", a->size);
    cJSON_AddNumberToObject(o, "evals", (double)a->evals);
    if (isnan(a->init_spread)) cJSON_AddNullToObject(o, "initSpread");
    else tt__nm_add_exact(o, "initSpread", a->init_spread);
    cJSON_AddItemToObject(o, "x", tt__nm_doubles(a->x, (n + 4) * n));
    cJSON *ids = cJSON_AddArrayToObject(o, "id");
    for (size_t i = 0; i < n + 4; i++) cJSON_AddItemToArray(ids, cJSON_CreateNumber(a->id[i]));
  }

  char *text = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  if (!text) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: save_state: out of memory");
  /* Callers free with tt_free (libc free in libtunetrace); hand over a malloc'd copy. */
  size_t len = strlen(text) + 1;
  *json = malloc(len);
  if (*json) memcpy(*json, text, len);
  cJSON_free(text);
  if (!*json) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: save_state: out of memory");
  return TT_OK;
}

/* Reads member `name` as a number into *v; 0 if absent or not a number. */
static int tt__nm_num(const cJSON *o, const char *name, double *v) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(o, name);
  if (!cJSON_IsNumber(it)) return 0;
  *v = it->valuedouble;
  return 1;
}

/* 1 if a count read from a state is an integer in [lo, 2^53]: it then converts to int64_t
 * exactly; a larger value (whose cast is undefined beyond INT64_MAX: 1e91 evaluations, found
 * by fuzz_tuning_state) or a fraction is a corrupt file. */
static int tt__nm_count_ok(double v, double lo) { /* lo: 0, 1, or -1 for "none" */
  return v >= lo && v <= 9007199254740992.0 && v == floor(v);
}

/* Reads a hex 64-bit word; 0 on failure. */
static int tt__nm_u64(const cJSON *o, const char *name, uint64_t *v) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(o, name);
  if (!cJSON_IsString(it)) return 0;
  char *end;
  unsigned long long x = strtoull(it->valuestring, &end, 16);
  if (*end || end == it->valuestring) return 0;
  *v = (uint64_t)x;
  return 1;
}

/* Reads an array of exactly `count` numbers into `out`; 0 on mismatch. */
static int tt__nm_read_doubles(const cJSON *arr, double *out, size_t count) {
  if (!cJSON_IsArray(arr) || (size_t)cJSON_GetArraySize(arr) != count) return 0;
  size_t i = 0;
  const cJSON *it;
  cJSON_ArrayForEach(it, arr) {
    if (!cJSON_IsNumber(it)) return 0;
    out[i++] = it->valuedouble;
  }
  return 1;
}

/* Checks a count recorded in the state against the tuner's own. */
static tt_status tt__nm_expect(const cJSON *root, const char *name, double want) {
  double v;
  if (!tt__nm_num(root, name, &v))
    return tt_set_error(TT_ERR_PARSE, "tuner_nm: load_state: missing \"%s\"", name);
  if (v != want)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tuner_nm: load_state: state has %s = %g, this tuner has %g", name, v,
                        want);
  return TT_OK;
}

/* The point an arm waits for agrees with its phase (tt__nm_arm_receive's invariants): a
 * state that breaks them loads, runs on and saves a state that no longer loads (WAIT_INIT
 * with k = n + 1 moves k to n + 2; found by tests/fuzz/fuzz_tuning_state). */
static int tt__nm_phase_consistent(int phase, int pend, int k, size_t n) {
  const int N = (int)n;
  switch (phase) {
  /* (n = 0: a restart keeping the best vertex waits for point 1) */
  case TT__NM_WAIT_INIT: return (k <= N || (N == 0 && k == 1)) && pend == k;
  case TT__NM_WAIT_SHRINK: return k >= 1 && k <= N && pend == k;
  case TT__NM_WAIT_REEVAL:
  case TT__NM_WAIT_PROBE: return pend == 0;
  case TT__NM_WAIT_REFLECT: return pend == N + 1;
  case TT__NM_WAIT_EXPAND: return pend == N + 2;
  case TT__NM_WAIT_CONTRACT_OUT:
  case TT__NM_WAIT_CONTRACT_IN: return pend == N + 3;
  default: return 1; /* FRESH, DONE, PROBED: nothing pending */
  }
}

/* Parses and validates the whole state into fresh arrays, then swaps them in, so a failed
 * load leaves the tuner untouched. */
tt_status tt__nm_load(tt_tuner *t, const char *json) {
  if (!t || !json) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: load_state: NULL");
  size_t P = t->P, n = t->n;
  const char *end = json;
  cJSON *root = cJSON_ParseWithOpts(json, &end, 0);
  if (!root) return tt_set_error(TT_ERR_PARSE, "tuner_nm: load_state: malformed JSON");
  end += strspn(end, " \t\r\n"); /* nothing may follow the state */
  if (*end) {
    cJSON_Delete(root);
    return tt_set_error(TT_ERR_PARSE,
                        "tuner_nm: load_state: unexpected text after the state, "
                        "at byte %zu",
                        (size_t)(end - json));
  }
  tt_status st = TT_OK;
  tt__nm_cache cache = {0};
  tt__nm_arm *arms = NULL;
  double *key = NULL, *probe = NULL;
  const cJSON *name = cJSON_GetObjectItemCaseSensitive(root, "tuner");
  if (!cJSON_IsString(name) || strcmp(name->valuestring, "tuner_nm")) {
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuner_nm: load_state: not a tuner_nm state");
    goto done;
  }
  if ((st = tt__nm_expect(root, "format", TT__NM_FORMAT)) != TT_OK) goto done;
  const cJSON *target = cJSON_GetObjectItemCaseSensitive(root, "target");
  if (!cJSON_IsString(target) || strcmp(target->valuestring, tt_space_plugin(t->target))) {
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT,
                      "tuner_nm: load_state: state is for target \"%s\", this tuner's is \"%s\"",
                      cJSON_IsString(target) ? target->valuestring : "?",
                      tt_space_plugin(t->target));
    goto done;
  }
  if ((st = tt__nm_expect(root, "parameters", (double)P)) != TT_OK ||
      (st = tt__nm_expect(root, "dimensions", (double)n)) != TT_OK ||
      (st = tt__nm_expect(root, "arms", (double)t->n_arms)) != TT_OK)
    goto done;
  {
    /* Settings must match: the saved simplex moves were made with them. */
    const cJSON *sj = cJSON_GetObjectItemCaseSensitive(root, "settings");
    cJSON *mine = tt__nm_settings_json(&t->set);
    const cJSON *it;
    cJSON_ArrayForEach(it, mine) {
      double v, own = strtod(it->valuestring, NULL); /* raw items keep their text */
      if (!tt__nm_num(sj, it->string, &v) || v != own) {
        st = tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          "tuner_nm: load_state: setting \"%s\" differs (state %g, tuner %g)",
                          it->string, tt__nm_num(sj, it->string, &v) ? v : NAN, own);
        break;
      }
    }
    cJSON_Delete(mine);
    if (st != TT_OK) goto done;
  }
  uint64_t rng;
  double evals, det, rr;
  if (!tt__nm_u64(root, "rng", &rng) || !tt__nm_num(root, "evaluations", &evals) ||
      !tt__nm_num(root, "deterministic", &det) || !tt__nm_num(root, "roundRobin", &rr) ||
      !tt__nm_count_ok(rr, 0) || rr >= (double)t->n_arms || !tt__nm_count_ok(evals, 0) ||
      (det != 0 && det != 1 && det != -1)) { /* unknown, identical, noisy */
    st = tt_set_error(TT_ERR_PARSE, "tuner_nm: load_state: bad rng/evaluations/roundRobin");
    goto done;
  }

  key = malloc((P + 1) * sizeof *key);
  if (!key) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: load_state: out of memory");
    goto done;
  }
  /* Cache: re-inserted in order, so ids stay what the arms refer to. */
  const cJSON *cj = cJSON_GetObjectItemCaseSensitive(root, "cache");
  const cJSON *keys = cJSON_GetObjectItemCaseSensitive(cj, "keys");
  const cJSON *sums = cJSON_GetObjectItemCaseSensitive(cj, "sum");
  const cJSON *ns = cJSON_GetObjectItemCaseSensitive(cj, "n");
  if (!cJSON_IsArray(keys) || !cJSON_IsArray(sums) || !cJSON_IsArray(ns) ||
      cJSON_GetArraySize(keys) != cJSON_GetArraySize(sums) ||
      cJSON_GetArraySize(keys) != cJSON_GetArraySize(ns)) {
    st = tt_set_error(TT_ERR_PARSE, "tuner_nm: load_state: bad \"cache\"");
    goto done;
  }
  {
    const cJSON *k = keys->child, *s = sums->child, *c = ns->child;
    for (; k && s && c; k = k->next, s = s->next, c = c->next) {
      int32_t id;
      if (!tt__nm_read_doubles(k, key, P) || !cJSON_IsNumber(s) || !cJSON_IsNumber(c) ||
          !tt__nm_count_ok(c->valuedouble, 1)) {
        st = tt_set_error(TT_ERR_PARSE, "tuner_nm: load_state: bad cache entry %zu", cache.count);
        goto done;
      }
      if ((st = tt__nm_cache_insert(&cache, P, key, s->valuedouble, (int64_t)c->valuedouble,
                                    &id)) != TT_OK)
        goto done;
    }
  }

  const cJSON *aj = cJSON_GetObjectItemCaseSensitive(root, "armStates");
  if (!cJSON_IsArray(aj) || (size_t)cJSON_GetArraySize(aj) != t->n_arms) {
    st = tt_set_error(TT_ERR_PARSE, "tuner_nm: load_state: bad \"armStates\"");
    goto done;
  }
  arms = calloc(t->n_arms, sizeof *arms);
  if (!arms) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuner_nm: load_state: out of memory");
    goto done;
  }
  {
    size_t ai = 0;
    const cJSON *o;
    double *ids = malloc((n + 4) * sizeof *ids);
    cJSON_ArrayForEach(o, aj) {
      tt__nm_arm *a = &arms[ai];
      a->x = calloc((n + 4) * (n ? n : 1), sizeof(double));
      a->id = malloc((n + 4) * sizeof(int32_t));
      double ph, pend, k, iter, ri, rs, size, ev;
      int ok = ids && a->x && a->id && tt__nm_num(o, "phase", &ph) &&
               tt__nm_num(o, "pend", &pend) && tt__nm_num(o, "k", &k) &&
               tt__nm_num(o, "iter", &iter) && tt__nm_num(o, "reevalIter", &ri) &&
               tt__nm_num(o, "restarts", &rs) && tt__nm_num(o, "size", &size) &&
               tt__nm_num(o, "evals", &ev) && tt__nm_count_ok(iter, 0) && tt__nm_count_ok(ri, -1) &&
               tt__nm_count_ok(rs, 0) && tt__nm_count_ok(ev, 0) &&
               tt__nm_read_doubles(cJSON_GetObjectItemCaseSensitive(o, "x"), a->x, (n + 4) * n) &&
               tt__nm_read_doubles(cJSON_GetObjectItemCaseSensitive(o, "id"), ids, n + 4) &&
               ph >= TT__NM_FRESH && ph <= TT__NM_PROBED && pend >= 0 && pend < (double)(n + 4) &&
               k >= 0 && k <= (double)(n + 1) && ph == (int)ph && pend == (int)pend &&
               k == (int)k && tt__nm_phase_consistent((int)ph, (int)pend, (int)k, n);
      for (size_t i = 0; ok && i < n + 4; i++) {
        if (ids[i] < -2 || ids[i] >= (double)cache.count) ok = 0;
        else a->id[i] = (int32_t)ids[i];
      }
      ai++;
      if (!ok) {
        free(ids);
        st = tt_set_error(TT_ERR_PARSE, "tuner_nm: load_state: bad arm state %zu", ai - 1);
        goto done;
      }
      a->phase = (int)ph;
      a->pend = (int)pend;
      a->k = (int)k;
      a->iter = (int64_t)iter;
      a->reeval_iter = (int64_t)ri;
      a->restarts = (int64_t)rs;
      a->size = size;
      a->evals = (int64_t)ev;
      /* initSpread: null or absent (older states) means "no full simplex yet". */
      double isp;
      a->init_spread = tt__nm_num(o, "initSpread", &isp) ? isp : NAN;
    }
    free(ids);
  }

  /* Outstanding proposal. */
  const cJSON *oj = cJSON_GetObjectItemCaseSensitive(root, "outstanding");
  int out_arm = -1, out_reeval = 0;
  int32_t reeval_id = 0;
  if (oj && !cJSON_IsNull(oj)) {
    double arm, re, rid;
    if (!tt__nm_num(oj, "arm", &arm) || !tt__nm_num(oj, "reeval", &re) ||
        !tt__nm_num(oj, "reevalId", &rid) || arm < 0 || arm >= (double)t->n_arms ||
        (re && (rid < 0 || rid >= (double)cache.count)) ||
        !tt__nm_read_doubles(cJSON_GetObjectItemCaseSensitive(oj, "key"), key, P)) {
      st = tt_set_error(TT_ERR_PARSE, "tuner_nm: load_state: bad \"outstanding\"");
      goto done;
    }
    out_arm = (int)arm;
    out_reeval = re != 0;
    reeval_id = (int32_t)rid;
    tt__nm_config_from_key(t, t->proposal, key);
  }

  /* Probe point (absent in older states: keep the one drawn at create). */
  const cJSON *pj = cJSON_GetObjectItemCaseSensitive(root, "probePoint");
  if (pj && n) {
    probe = malloc(n * sizeof *probe);
    if (!probe || !tt__nm_read_doubles(pj, probe, n)) {
      st = tt_set_error(TT_ERR_PARSE, "tuner_nm: load_state: bad \"probePoint\"");
      goto done;
    }
  }

  /* set_context's effects (absent in states of tuners before ABI 1.1: as created) */
  const cJSON *pr = cJSON_GetObjectItemCaseSensitive(root, "probe");
  const cJSON *cs = cJSON_GetObjectItemCaseSensitive(root, "contextSet");
  uint64_t budget = 0;
  if ((pr && !cJSON_IsBool(pr)) || (cs && !cJSON_IsBool(cs)) ||
      (cJSON_GetObjectItemCaseSensitive(root, "budget") && !tt__nm_u64(root, "budget", &budget))) {
    st = tt_set_error(TT_ERR_PARSE,
                      "tuner_nm: load_state: bad \"probe\", \"budget\" or \"contextSet\"");
    goto done;
  }

  /* Commit. */
  if (pr) t->probe = cJSON_IsTrue(pr);
  if (cs) t->context_set = cJSON_IsTrue(cs);
  t->budget = budget;
  if (probe) memcpy(t->probe_pt, probe, n * sizeof(double));
  for (size_t ai = 0; ai < t->n_arms; ai++) {
    free(t->arms[ai].x);
    free(t->arms[ai].id);
  }
  free(t->arms);
  t->arms = arms;
  arms = NULL;
  free(t->cache.keys);
  free(t->cache.sum);
  free(t->cache.n);
  free(t->cache.table);
  t->cache = cache;
  memset(&cache, 0, sizeof cache);
  t->rng = rng;
  t->evaluations = (int64_t)evals;
  t->deterministic = (int)det;
  t->rr = (size_t)rr;
  t->out_arm = out_arm;
  t->out_reeval = out_reeval;
  t->reeval_id = reeval_id;

done:
  if (arms)
    for (size_t ai = 0; ai < t->n_arms; ai++) {
      free(arms[ai].x);
      free(arms[ai].id);
    }
  free(arms);
  free(cache.keys);
  free(cache.sum);
  free(cache.n);
  free(cache.table);
  free(key);
  free(probe);
  cJSON_Delete(root);
  return st;
}
