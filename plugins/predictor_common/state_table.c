/* The predictors' table of observed states (state_table.h). */
#include "state_table.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void tt__pm_table_init(tt__pm_table *t, uint32_t dim, size_t params, int64_t max_states) {
  memset(t, 0, sizeof *t);
  t->dim = dim;
  t->params = params;
  t->max_states = max_states;
}

void tt__pm_table_clear(tt__pm_table *t) {
  for (size_t i = 0; i < t->n; i++) {
    for (size_t k = 0; k < t->entries[i].ncfg; k++) free(t->entries[i].cfgs[k].values);
    free(t->entries[i].cfgs);
    free(t->entries[i].state);
  }
  free(t->entries);
  t->entries = NULL;
  t->n = t->cap = 0;
}

static double tt__pm_dist2(const double *a, const double *b, uint32_t n) {
  double d = 0;
  for (uint32_t i = 0; i < n; i++) d += (a[i] - b[i]) * (a[i] - b[i]);
  return d;
}

size_t tt__pm_table_nearest(const tt__pm_table *t, const double *state, double *dist2) {
  size_t best = SIZE_MAX;
  double bd = INFINITY;
  for (size_t i = 0; i < t->n; i++) {
    double d = tt__pm_dist2(t->entries[i].state, state, t->dim);
    if (d < bd) {
      bd = d;
      best = i;
    }
  }
  if (dist2) *dist2 = bd;
  return best;
}

size_t tt__pm_table_find(const tt__pm_table *t, const double *state) {
  for (size_t i = 0; i < t->n; i++) {
    uint32_t k = 0;
    while (k < t->dim && t->entries[i].state[k] == state[k]) k++;
    if (k == t->dim) return i;
  }
  return SIZE_MAX;
}

size_t tt__pm_table_find_cfg(const tt__pm_table *t, size_t i, const double *values) {
  const tt__pm_table_entry *e = &t->entries[i];
  for (size_t k = 0; k < e->ncfg; k++)
    if (!memcmp(e->cfgs[k].values, values, t->params * sizeof(double))) return k;
  return SIZE_MAX;
}

static void tt__pm_update_best(tt__pm_table_entry *e) {
  size_t b = 0;
  for (size_t k = 1; k < e->ncfg; k++)
    if (tt__pm_table_mean(&e->cfgs[k]) < tt__pm_table_mean(&e->cfgs[b])) b = k;
  e->best = b;
}

/* Room for one more item in `items` (*cap items of `elem` bytes, n of them used): the array
 * itself, or when full a copy with twice the capacity (`first` for an empty one) and *cap
 * updated. NULL when out of memory (the old array is kept and still owned by the caller). */
static void *tt__pm_reserve(void *items, size_t *cap, size_t n, size_t elem, size_t first) {
  if (n < *cap) return items;
  size_t c = *cap ? 2 * *cap : first;
  void *p = realloc(items, c * elem);
  if (p) *cap = c;
  return p;
}

size_t tt__pm_table_add(tt__pm_table *t, const double *state, const double *values, double cost,
                        int *best_changed) {
  size_t i = tt__pm_table_find(t, state);
  if (i == SIZE_MAX && t->max_states > 0 && t->n >= (size_t)t->max_states)
    i = tt__pm_table_nearest(t, state, NULL);
  if (i == SIZE_MAX) {
    tt__pm_table_entry *grown = tt__pm_reserve(t->entries, &t->cap, t->n, sizeof *grown, 64);
    if (!grown) return SIZE_MAX;
    t->entries = grown;
    tt__pm_table_entry *e = &t->entries[t->n];
    memset(e, 0, sizeof *e);
    e->state = malloc((t->dim ? t->dim : 1) * sizeof(double));
    if (!e->state) return SIZE_MAX;
    memcpy(e->state, state, t->dim * sizeof(double));
    i = t->n++;
  }
  tt__pm_table_entry *e = &t->entries[i];
  int fresh = e->ncfg == 0;
  size_t best = e->best;
  size_t k = tt__pm_table_find_cfg(t, i, values);
  if (k == SIZE_MAX) {
    tt__pm_table_cfg *grown = tt__pm_reserve(e->cfgs, &e->cap, e->ncfg, sizeof *grown, 8);
    if (!grown) return SIZE_MAX;
    e->cfgs = grown;
    double *v = malloc((t->params ? t->params : 1) * sizeof(double));
    if (!v) return SIZE_MAX;
    memcpy(v, values, t->params * sizeof(double));
    k = e->ncfg++;
    e->cfgs[k] = (tt__pm_table_cfg){v, 0.0, 0};
  }
  e->cfgs[k].sum += cost;
  e->cfgs[k].count++;
  tt__pm_update_best(e);
  if (best_changed && (fresh || e->best != best)) *best_changed = 1;
  return i;
}

uint64_t tt__pm_table_bytes(const tt__pm_table *t) {
  uint64_t bytes = t->cap * sizeof(tt__pm_table_entry);
  for (size_t i = 0; i < t->n; i++) {
    bytes += t->dim * sizeof(double) + t->entries[i].cap * sizeof(tt__pm_table_cfg);
    bytes += t->entries[i].ncfg * t->params * sizeof(double);
  }
  return bytes;
}

void tt__pm_table_put(tt__pm_writer *w, const tt__pm_table *t) {
  tt__pm_put_u64(w, t->n);
  for (size_t i = 0; i < t->n; i++) {
    const tt__pm_table_entry *e = &t->entries[i];
    tt__pm_put_f64s(w, e->state, t->dim);
    tt__pm_put_u64(w, e->ncfg);
    for (size_t k = 0; k < e->ncfg; k++) {
      tt__pm_put_f64s(w, e->cfgs[k].values, t->params);
      tt__pm_put_f64(w, e->cfgs[k].sum);
      tt__pm_put_u64(w, e->cfgs[k].count);
    }
  }
}

int tt__pm_table_get(tt__pm_reader *r, tt__pm_table *t, const tt_space *target) {
  int64_t max_states = t->max_states;
  t->max_states = 0; /* no merging while the stored table is rebuilt */
  size_t per_state = t->dim * 8 + 8;
  uint64_t n = tt__pm_get_count(r, UINT32_MAX, per_state, "states");
  double *v = malloc((t->params ? t->params : 1) * sizeof(double));
  double *state = malloc((t->dim ? t->dim : 1) * sizeof(double));
  tt_config *check = tt_config_create(target);
  if (!v || !state || !check) tt__pm_fail(r, "out of memory");
  char why[256];
  for (uint64_t i = 0; !r->err[0] && i < n; i++) {
    tt__pm_get_f64s(r, state, t->dim, "a state");
    for (uint32_t k = 0; !r->err[0] && k < t->dim; k++)
      if (!isfinite(state[k]))
        tt__pm_fail(r, "state %llu has a non-finite value", (unsigned long long)i);
    if (!r->err[0] && tt__pm_table_find(t, state) != SIZE_MAX)
      tt__pm_fail(r, "state %llu is stored twice", (unsigned long long)i);
    uint64_t ncfg = tt__pm_get_count(r, UINT32_MAX, t->params * 8 + 16, "configurations");
    if (!r->err[0] && ncfg == 0)
      tt__pm_fail(r, "state %llu has no configuration", (unsigned long long)i);
    for (uint64_t k = 0; !r->err[0] && k < ncfg; k++) {
      tt__pm_get_f64s(r, v, t->params, "a configuration");
      double sum = tt__pm_get_f64(r, "a cost sum");
      uint64_t count = tt__pm_get_u64(r, "a cost count");
      if (r->err[0]) break;
      if (tt__pm_config_from_values(check, v, why, sizeof why)) {
        tt__pm_fail(r, "state %llu, configuration %llu: %s", (unsigned long long)i,
                    (unsigned long long)k, why);
        break;
      }
      if (!(sum > 0) || !isfinite(sum) || count == 0) {
        tt__pm_fail(r,
                    "state %llu, configuration %llu: cost sum %g over %llu measurements is not "
                    "a positive finite mean",
                    (unsigned long long)i, (unsigned long long)k, sum, (unsigned long long)count);
        break;
      }
      /* rebuild exactly: one add with the whole sum, then the count */
      size_t e_i = tt__pm_table_add(t, state, v, sum, NULL);
      if (e_i == SIZE_MAX) {
        tt__pm_fail(r, "out of memory");
        break;
      }
      tt__pm_table_entry *e = &t->entries[e_i];
      size_t j = e->ncfg - 1;
      if (e_i != t->n - 1 || e->cfgs[j].count != 1) {
        tt__pm_fail(r, "state %llu: configuration %llu is stored twice", (unsigned long long)i,
                    (unsigned long long)k);
        break;
      }
      e->cfgs[j].count = count;
      tt__pm_update_best(e);
    }
  }
  tt_config_destroy(check);
  free(v);
  free(state);
  t->max_states = max_states;
  return r->err[0] ? -1 : 0;
}
