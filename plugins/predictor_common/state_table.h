/* The table of observed states that the predictor plugins share: per distinct state, every
 * distinct configuration observed there with the sum and count of its costs, and the
 * state's best configuration (lowest mean cost; ties: the one observed first), the rule the
 * host uses to keep its best (a configuration re-measured against noise is judged by its
 * mean, so one lucky pass does not win).
 *
 * predictor_nn answers with the best of the nearest state; predictor_rbf takes the states'
 * bests as its argmax's candidate actions (poolSource=states). States are compared as given
 * (the caller normalises them), configurations as tt__pm_config_values rows, bit for bit.
 *
 * Not thread-safe: one table is used by one thread at a time (the predictor's contract).
 */
#ifndef TT_PREDICTOR_STATE_TABLE_H
#define TT_PREDICTOR_STATE_TABLE_H

#include "model_file.h"

#include <stddef.h>
#include <stdint.h>

/* One configuration of a state: its values (tt__pm_config_values) and its costs. */
typedef struct tt__pm_table_cfg {
  double *values;
  double sum;
  uint64_t count;
} tt__pm_table_cfg;

typedef struct tt__pm_table_entry {
  double *state; /* dim values */
  tt__pm_table_cfg *cfgs;
  size_t ncfg, cap;
  size_t best; /* index of the lowest mean cost */
} tt__pm_table_entry;

typedef struct tt__pm_table {
  uint32_t dim;       /* state values */
  size_t params;      /* values per configuration */
  int64_t max_states; /* 0: unbounded; else a new state beyond it joins its nearest state */
  tt__pm_table_entry *entries;
  size_t n, cap;
} tt__pm_table;

/* An empty table (allocates nothing). */
void tt__pm_table_init(tt__pm_table *t, uint32_t dim, size_t params, int64_t max_states);
/* Frees every entry; the table is empty afterwards (dim, params, max_states kept). */
void tt__pm_table_clear(tt__pm_table *t);

/* Mean cost of a configuration. */
static inline double tt__pm_table_mean(const tt__pm_table_cfg *c) {
  return c->sum / (double)c->count;
}
/* The best configuration of entry i. */
static inline const tt__pm_table_cfg *tt__pm_table_best(const tt__pm_table *t, size_t i) {
  return &t->entries[i].cfgs[t->entries[i].best];
}

/* Index of the nearest stored state by Euclidean distance (first on ties; its squared
 * distance in *dist2 when not NULL), or SIZE_MAX when the table is empty. */
size_t tt__pm_table_nearest(const tt__pm_table *t, const double *state, double *dist2);
/* Index of the entry whose state equals `state` exactly, or SIZE_MAX. */
size_t tt__pm_table_find(const tt__pm_table *t, const double *state);
/* Index of `values` among entry i's configurations, or SIZE_MAX. */
size_t tt__pm_table_find_cfg(const tt__pm_table *t, size_t i, const double *values);

/* Adds one observation (a finite positive cost; the caller checks it). Returns the index of
 * the entry it joined, or SIZE_MAX when out of memory (the table unchanged then but for a
 * new empty entry's state). *best_changed (when not NULL) is set to 1 if the entry is new or
 * its best configuration is now another one, else left as it was, so a caller can collect
 * over a batch whether anything derived from the states' bests must be recomputed. */
size_t tt__pm_table_add(tt__pm_table *t, const double *state, const double *values, double cost,
                        int *best_changed);

/* Heap bytes the table holds (what info() reports). */
uint64_t tt__pm_table_bytes(const tt__pm_table *t);

/* Model-file form: u64 state count, then per state its values, u64 configuration count, and
 * per configuration its values, f64 cost sum and u64 count. */
void tt__pm_table_put(tt__pm_writer *w, const tt__pm_table *t);
/* Reads that form into the empty table t (max_states is not applied while reading), checking
 * every state (finite, not stored twice), configuration (valid in `target`, not stored twice)
 * and mean (positive, finite); 0, or -1 with r->err set (t then holds what was read: clear
 * it). */
int tt__pm_table_get(tt__pm_reader *r, tt__pm_table *t, const tt_space *target);

#endif /* TT_PREDICTOR_STATE_TABLE_H */
