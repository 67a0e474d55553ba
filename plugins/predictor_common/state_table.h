/* The table of observed states that the predictor plugins share: per distinct state, every
 * distinct configuration observed there with the sum and count of its costs, and the
 * state's best configuration (lowest mean cost; ties: the one observed first), the rule the
 * host uses to keep its best (a configuration re-measured against noise is judged by its
 * mean, so one lucky pass does not win).
 *
 * predictor_nn answers with the best of the nearest state; predictor_rbf takes the states'
 * bests as its argmax's candidate actions (poolSource=states). States are compared as given
 * (the caller normalises them), configurations as ttpm_config_values rows, bit for bit.
 *
 * Not thread-safe: one table is used by one thread at a time (the predictor's contract).
 */
#ifndef TT_PREDICTOR_STATE_TABLE_H
#define TT_PREDICTOR_STATE_TABLE_H

#include "model_file.h"

#include <stddef.h>
#include <stdint.h>

/* One configuration of a state: its values (ttpm_config_values) and its costs. */
typedef struct ttpm_table_cfg {
  double *values;
  double sum;
  uint64_t count;
} ttpm_table_cfg;

typedef struct ttpm_table_entry {
  double *state;       /* dim values */
  ttpm_table_cfg *cfgs;
  size_t ncfg, cap;
  size_t best;         /* index of the lowest mean cost */
} ttpm_table_entry;

typedef struct ttpm_table {
  uint32_t dim;        /* state values */
  size_t params;       /* values per configuration */
  int64_t max_states;  /* 0: unbounded; else a new state beyond it joins its nearest state */
  ttpm_table_entry *entries;
  size_t n, cap;
} ttpm_table;

/* An empty table (allocates nothing). */
void ttpm_table_init(ttpm_table *t, uint32_t dim, size_t params, int64_t max_states);
/* Frees every entry; the table is empty afterwards (dim, params, max_states kept). */
void ttpm_table_clear(ttpm_table *t);

/* Mean cost of a configuration. */
static inline double ttpm_table_mean(const ttpm_table_cfg *c) { return c->sum / (double)c->count; }
/* The best configuration of entry i. */
static inline const ttpm_table_cfg *ttpm_table_best(const ttpm_table *t, size_t i) {
  return &t->entries[i].cfgs[t->entries[i].best];
}

/* Index of the nearest stored state by Euclidean distance (first on ties; its squared
 * distance in *dist2 when not NULL), or SIZE_MAX when the table is empty. */
size_t ttpm_table_nearest(const ttpm_table *t, const double *state, double *dist2);
/* Index of the entry whose state equals `state` exactly, or SIZE_MAX. */
size_t ttpm_table_find(const ttpm_table *t, const double *state);
/* Index of `values` among entry i's configurations, or SIZE_MAX. */
size_t ttpm_table_find_cfg(const ttpm_table *t, size_t i, const double *values);

/* Adds one observation (a finite positive cost; the caller checks it). Returns the index of
 * the entry it joined, or SIZE_MAX when out of memory (the table unchanged then but for a
 * new empty entry's state). *best_changed (when not NULL) is set to 1 if the entry is new or
 * its best configuration is now another one, else left as it was, so a caller can collect
 * over a batch whether anything derived from the states' bests must be recomputed. */
size_t ttpm_table_add(ttpm_table *t, const double *state, const double *values, double cost,
                      int *best_changed);

/* Heap bytes the table holds (what info() reports). */
uint64_t ttpm_table_bytes(const ttpm_table *t);

/* Model-file form: u64 state count, then per state its values, u64 configuration count, and
 * per configuration its values, f64 cost sum and u64 count. */
void ttpm_table_put(ttpm_writer *w, const ttpm_table *t);
/* Reads that form into the empty table t (max_states is not applied while reading), checking
 * every state (finite, not stored twice), configuration (valid in `target`, not stored twice)
 * and mean (positive, finite); 0, or -1 with r->err set (t then holds what was read: clear
 * it). */
int ttpm_table_get(ttpm_reader *r, ttpm_table *t, const tt_space *target);

#endif /* TT_PREDICTOR_STATE_TABLE_H */
