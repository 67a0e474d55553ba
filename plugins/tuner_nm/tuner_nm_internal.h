/* tuner_nm internal: data structures shared by the driver (tuner_nm.c), the simplex state
 * machine (tuner_nm_simplex.c) and the JSON state (tuner_nm_state.c). Nothing here is
 * exported: the plugin builds with hidden visibility and exports only tt_plugin_entry. */
#ifndef TT_TUNER_NM_INTERNAL_H
#define TT_TUNER_NM_INTERNAL_H

#include <tunetrace/tuner.h>

#include <stddef.h>
#include <stdint.h>

/* At most this many nominal combinations get their own simplex (an "arm"); NOM parameters
 * that would push the product past it are folded into the simplex as unit-space bins. */
#define TT__NM_MAX_ARMS 32
/* A re-measured incumbent stops being re-measured once its mean has this many samples. */
#define TT__NM_REEVAL_CAP 8
/* Probe mode (see tt__nm_choose_arm) when building every arm's initial simplex up front,
 * arms x (n+1) measurements, would cost more than this (the host's default iteration
 * count). */
#define TT__NM_PROBE_ABOVE 50
/* Side of the box around the default in which the shared probe point is drawn, as a
 * fraction of initSize. */
#define TT__NM_PROBE_BOX 0.25
/* Candidate initial simplices drawn; the one with the largest volume is kept. */
#define TT__NM_INIT_TRIES 8
/* Internal steps (cache hits, infeasible points) one next() may take before giving up. */
#define TT__NM_MAX_INTERNAL_STEPS 1000000

enum { TT__NM_INIT_LHS = 0, TT__NM_INIT_UNIFORM = 1, TT__NM_INIT_NORMAL = 2 };

/* What an arm waits for: the result of its pending point `pend`. */
typedef enum tt__nm_phase {
  TT__NM_FRESH = 0,       /* simplex not generated yet */
  TT__NM_WAIT_INIT = 1,   /* vertex k of the initial (or restart) simplex */
  TT__NM_WAIT_REEVAL = 2, /* re-measurement of the arm's best vertex */
  TT__NM_WAIT_REFLECT = 3,
  TT__NM_WAIT_EXPAND = 4,
  TT__NM_WAIT_CONTRACT_OUT = 5,
  TT__NM_WAIT_CONTRACT_IN = 6,
  TT__NM_WAIT_SHRINK = 7, /* vertex k of a shrink */
  TT__NM_DONE = 8,        /* converged after the last restart */
  TT__NM_WAIT_PROBE = 9,  /* probe: vertex 0 at the shared probe point */
  TT__NM_PROBED = 10      /* probe measured; the simplex is built when the arm is chosen */
} tt__nm_phase;

typedef struct tt__nm_settings {
  double reflection, expansion, contraction, shrink;
  int init;
  double init_size, tolerance;
  int64_t reevaluate, max_evaluations, restarts;
  double epsilon;
} tt__nm_settings;

/* One nominal combination and its Nelder-Mead search. Points 0..n are the vertices (sorted
 * best first at the start of every iteration); n+1, n+2, n+3 hold the reflection, expansion
 * and contraction trials. A point's cost is the cache mean of `id`, or +inf when id < 0
 * (internally rejected as infeasible, never measured). */
typedef struct tt__nm_arm {
  int phase;           /* tt__nm_phase */
  int pend;            /* point whose result is awaited */
  int k;               /* vertex counter for WAIT_INIT and WAIT_SHRINK */
  int64_t iter;        /* completed Nelder-Mead iterations */
  int64_t reeval_iter; /* iteration at which the last re-measurement was made (-1: none) */
  int64_t restarts;    /* restarts made so far */
  double size;         /* current simplex spread (initSize, halved on each restart) */
  int64_t evals;       /* measurements made for this arm (reported in the state) */
  double init_spread;  /* cost spread (worst - best) of the first full simplex; NaN before */
  double *x;           /* (n + 4) * n unit coordinates */
  int32_t *id;         /* n + 4 cache ids */
} tt__nm_arm;

/* Cache of measured configurations: key = one double per target parameter (INT value,
 * FLOAT value, NOM index); cost = sum / count (the mean of its measurements). */
typedef struct tt__nm_cache {
  size_t count, cap;
  double *keys; /* count * P */
  double *sum;
  int64_t *n;
  int32_t *table;    /* open addressing, -1 = empty */
  size_t table_size; /* power of two */
} tt__nm_cache;

struct tt_tuner {
  const tt_space *target;
  tt__nm_settings set;
  uint64_t seed;
  uint64_t rng; /* SplitMix64 state */

  size_t P;          /* target parameter count */
  size_t n;          /* simplex dimensions */
  size_t *dim_param; /* n: target parameter index of each simplex dimension */
  size_t n_armnom;   /* NOM parameters enumerated as arms */
  size_t *armnom_param;
  size_t *armnom_count;
  size_t n_arms;
  tt__nm_arm *arms;
  double *center;     /* n: unit coordinates of the target's default configuration */
  double min_restart; /* smallest restart spread: two grid steps of the coarsest INT */

  tt__nm_cache cache;
  int64_t evaluations; /* measurements fed back */
  int deterministic;   /* 0 unknown, 1 repeated measurement was identical, -1 noisy */
  size_t rr;           /* round-robin cursor for the initialisation phase */
  int probe;           /* several arms and n > 0: probe every arm once, build on demand */
  double *probe_pt;    /* n: the probe's unit coordinates, the same for every arm */
  uint64_t budget;     /* set_context's iteration budget (0: unknown) */
  int context_set;     /* set_context was called */

  /* Outstanding proposal: arm index (-1 if none), whether it is a re-measurement (then
   * reeval_id is the cache id), and the configuration. */
  int out_arm;
  int out_reeval;
  int32_t reeval_id;
  tt_config *proposal;
  tt_config *work, *work2;
  double *unit; /* P scratch */
  double *key;  /* P scratch */
};

/* ---- tuner_nm.c ---- */
double tt__nm_rand(uint64_t *state);
double tt__nm_point_cost(const tt_tuner *t, int32_t id);
int32_t tt__nm_cache_find(const tt__nm_cache *c, size_t P, const double *key);
tt_status tt__nm_cache_insert(tt__nm_cache *c, size_t P, const double *key, double sum, int64_t n,
                              int32_t *out_id);
void tt__nm_config_from_key(tt_tuner *t, tt_config *cfg, const double *key);
const tt_space *tt__nm_settings_space(void);
void tt__nm_settings_read(const tt_config *cfg, tt__nm_settings *s);

/* ---- tuner_nm_simplex.c ---- */
void tt__nm_arm_generate(tt_tuner *t, tt__nm_arm *a, const double *center, double size,
                         int keep_best);
void tt__nm_arm_receive(tt_tuner *t, tt__nm_arm *a);
int tt__nm_arm_init_complete(const tt__nm_arm *a);
int tt__nm_arm_built(const tt__nm_arm *a);
double tt__nm_arm_spread(const tt_tuner *t, const tt__nm_arm *a);
double tt__nm_arm_best(const tt_tuner *t, const tt__nm_arm *a);
double tt__nm_arm_optimistic(const tt_tuner *t, const tt__nm_arm *a);
void tt__nm_lhs(tt_tuner *t, double *pts, size_t count, size_t n, const double *lo, double size);

/* ---- tuner_nm_state.c ---- */
tt_status tt__nm_save(const tt_tuner *t, char **json);
tt_status tt__nm_load(tt_tuner *t, const char *json);

#endif /* TT_TUNER_NM_INTERNAL_H */
