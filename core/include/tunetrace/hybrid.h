/* tunetrace: hybrid online autotuning (thesis 3.3, Fig. 3.15) as a library object.
 *
 * A renderer moves through states (the camera along a path, the scene changing). On every
 * state change the hybrid tuner chooses, eps-greedy: with probability epsilon it explores
 * (a search, thesis: Nelder-Mead, for K iterations in this state; every sample goes to the
 * tuning database and to the model), otherwise it exploits (the model predicts one
 * configuration, which is built once and kept until the next state change; its measured
 * cost is observed too). Exploitation is a one-step process: no iterations, one build.
 *
 * Each state is a tuning session of tunetrace/tuning.h over the same target callbacks, so
 * costs are measured exactly as the tuning loop measures them (one definition: the target's
 * build and render times through the host's clock, the session's objective), recorded in the
 * same database (the exploit's one sample with mode "exploit"), and answered from it when
 * the database already holds the state and configuration.
 *
 * The model is any predictor plugin (tt.predictor/1, ABI 1.1): predictor_nn, predictor_rbf,
 * predictor_static or a third party's. The caller creates it over the searched space (the
 * configurations the model predicts) for states of TT_SCENE_INDICATOR_COUNT values named
 * by the normalisation's id (tt_indicator_norm_id), and may warm-start it from a tuning
 * database (tt_hybrid_warm_start: other scenes, earlier runs).
 *
 * Ownership: the space, tuner and predictor tables, the model, the database are borrowed and
 * must outlive the object; strings it returns are owned by it. Threads: one thread at a
 * time; the target's callbacks run on that thread.
 */
#ifndef TUNETRACE_HYBRID_H
#define TUNETRACE_HYBRID_H

#include <tunetrace/indicators.h>
#include <tunetrace/predictor.h>
#include <tunetrace/tuning.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tt_hybrid tt_hybrid; /* opaque */

typedef enum tt_hybrid_mode {
  TT_HYBRID_EXPLORE = 1, /* a search of K iterations in this state */
  TT_HYBRID_EXPLOIT = 2  /* one predicted configuration, built once */
} tt_hybrid_mode;

/* Where a state's default cost (tt_hybrid_report.default_cost) comes from. An exploited state
 * does not measure the default (exploitation is one build), so its default cost is the
 * database's when an earlier run measured the default in this very state, else estimated. */
typedef enum tt_hybrid_cost_source {
  TT_HYBRID_COST_NONE = 0,     /* unknown (NAN) */
  TT_HYBRID_COST_MEASURED = 1, /* measured in this state by this run */
  TT_HYBRID_COST_DATABASE = 2, /* measured in this state by an earlier run (the database) */
  TT_HYBRID_COST_NEAREST = 3   /* estimated: the default's cost in the nearest state (by the
                                   normalised indicators) where it was measured, by this run or
                                   a warm start; default_distance says how near */
} tt_hybrid_cost_source;

/* Everything a hybrid tuner is created from. Zero-initialise, set struct_size, fill in. */
typedef struct tt_hybrid_desc {
  uint32_t struct_size;        /* sizeof(tt_hybrid_desc) as the caller was built */
  const tt_host *host;         /* NULL: tt_default_host() */
  const tt_space *space;       /* the target's full space (required) */
  const tt_config *start;      /* configured values: the default (NULL: space defaults) */
  const tt_space *search;      /* searched and predicted parameters (a tt_space_subset
                                      of space), NULL: all of space */
  const char *objective;       /* objective spec; NULL: "render" */
  const tt_tuner_iface *tuner; /* the exploration search (required) */
  const tt_config *tuner_settings;
  const char *tuner_name;
  const tt_predictor_iface *predictor; /* the model's table (ABI 1.1, required) */
  tt_predictor *model;                 /* created by the caller over `search` (required) */
  const char *predictor_name;
  double epsilon;                      /* probability of exploring a new state, in [0, 1] */
  uint32_t explore_iterations;         /* K >= 1: tuner iterations of an explored state */
  uint32_t spp;                        /* samples per pixel of one measurement pass (0: 1) */
  uint32_t warmup_passes;              /* unmeasured 1-spp passes before the first state */
  uint64_t seed;                       /* the eps-greedy draws; each state's tuner seed is
                                      derived from it and the state index */
  const char *plugin, *plugin_version; /* the target (database, log) */
  tt_tunedb *db;                       /* borrowed, or NULL */
  const char *run_id;                  /* NULL: generated */
  const tt_indicator_norm *norm;       /* the model's state space; NULL: the default */
  /* Non-zero: an exploited configuration's measured cost is not given to the model (the
   * thesis observes it; turning it off measures what the model learns from search alone). */
  int32_t no_exploit_feedback;
} tt_hybrid_desc;

/* What one state did (tt_hybrid_step). Strings are owned by the hybrid object and valid
 * until the next step. */
typedef struct tt_hybrid_report {
  uint32_t struct_size; /* sizeof(tt_hybrid_report), set by the caller */
  uint32_t state_index; /* 0, 1, ... in step order */
  tt_hybrid_mode mode;
  int32_t fallback;      /* exploit answered the default configuration: the model
                                      had no data, or its answer was infeasible */
  const char *config;    /* JSON of the configuration the state runs with */
  double cost;           /* its cost (explore: the best's mean over its samples;
                                      exploit: the one measurement, or the database's) */
  double predicted_cost; /* the model's expected cost of it (exploit), else NAN */
  double default_cost;   /* the default's cost in this state when known, else NAN */
  double search_cost;    /* explore: the sum of the costs of all samples (what the
                                      search paid), exploit: = cost */
  uint32_t samples;      /* samples recorded (measured or from the database) */
  uint32_t builds;       /* configurations applied through the target */
  uint32_t cached;       /* samples answered by the database */
  double predict_ms;     /* CPU ms of the model's predict call (exploit) */
  double state[TT_SCENE_INDICATOR_COUNT]; /* the normalised indicators */
  /* ---- appended ---- */
  int32_t default_source;  /* tt_hybrid_cost_source of default_cost */
  double default_distance; /* TT_HYBRID_COST_NEAREST: distance between the normalised
                                      states, else 0 (NAN when unknown) */
  uint32_t remeasured;     /* samples that measured again a configuration already
                                      measured in this state (the tuner against noise) */
} tt_hybrid_report;

/* Creates a hybrid tuner. TT_ERR_INVALID_ARGUMENT names a missing or bad field (epsilon
 * outside [0, 1], K < 1, no tuner, a predictor table older than ABI 1.1). */
TT_API tt_status tt_hybrid_create(const tt_hybrid_desc *desc, tt_hybrid **out);
TT_API void tt_hybrid_destroy(tt_hybrid *h);

/* Which database rows a warm start learns from. Zero-initialise, set struct_size. */
typedef struct tt_hybrid_warm_filter {
  uint32_t struct_size; /* sizeof(tt_hybrid_warm_filter) */
  /* Keys of the rows' context JSON that must equal those of `context` (e.g. "clock", "spp",
   * "threads": costs measured with another clock or thread count do not compare); NULL
   * entries end the list. NULL list: no context check. */
  const char *const *context_keys;
  const char *context; /* the JSON those keys are compared with */
  /* Called per candidate row; non-zero keeps it (e.g. leave a validation camera out). */
  int (*keep)(void *user, const tt_tunedb_row *row);
  void *user;
  /* ---- appended ---- */
  /* Keys of the rows' camera JSON that must equal those of `camera` (e.g. "resolution":
   * render times at another resolution do not compare); NULL: no camera check. */
  const char *const *camera_keys;
  const char *camera;
} tt_hybrid_warm_filter;

/* Why a warm start learnt what it learnt (tt_hybrid_warm_start_ex). Zero-initialise, set
 * struct_size. Counts are rows of the target plugin, each counted under the first reason
 * that leaves it out, in this order; mismatches (rows otherwise usable) are counted per key,
 * so a row measured with another clock and another thread count counts under both. */
#define TT_HYBRID_WARM_MAX_KEYS 16
typedef struct tt_hybrid_warm_result {
  uint32_t struct_size;     /* sizeof(tt_hybrid_warm_result) */
  uint64_t rows;            /* rows learnt */
  uint64_t exploit_rows;    /* of which the model's own answers (mode "exploit") */
  uint64_t considered;      /* rows of the target plugin in the database */
  uint64_t other_objective; /* measured for another objective */
  uint64_t failed;          /* failed measurements (never learnt) */
  uint64_t no_indicators;   /* without indicators (not a state a model can learn) */
  uint64_t excluded;        /* left out by the filter's keep() */
  uint64_t other_context;   /* left out by a context or camera key (mismatch[] says
                                      which) */
  uint64_t other_space;     /* configurations this space cannot read (another plugin
                                      version with other parameters) */
  /* per key, the filter's context_keys then its camera_keys: rows whose value differs, and
   * the first such value as JSON ("(none)" when the row lacks the key); owned by the hybrid
   * object until the next warm start */
  uint32_t key_count;
  const char *key[TT_HYBRID_WARM_MAX_KEYS];
  uint64_t mismatch[TT_HYBRID_WARM_MAX_KEYS];
  const char *mismatch_value[TT_HYBRID_WARM_MAX_KEYS];
  const char *expected_value[TT_HYBRID_WARM_MAX_KEYS]; /* the filter's value ("(none)") */
} tt_hybrid_warm_result;

/* Teaches the model every usable row of `db` (the target plugin, the session's objective,
 * status OK or infeasible, indicators present, the filter): states normalised, configurations
 * narrowed to the searched parameters, each state's default cost (its "default" row) given
 * for relative rewards; one observe_ex(TT_PREDICTOR_OFFLINE) batch. `*rows` (may be NULL)
 * receives how many rows were learnt. Rows another space's configuration cannot be read
 * into (another plugin version with other parameters) are skipped and counted in `*skipped`. */
TT_API tt_status tt_hybrid_warm_start(tt_hybrid *h, tt_tunedb *db, const tt_hybrid_warm_filter *f,
                                      uint64_t *rows, uint64_t *skipped);

/* One state: draws explore/exploit, runs it through `target` (which is left running the
 * state's configuration: the best found, or the predicted one), observes the costs in the
 * model and fills `out` (may be NULL). `state` is the database state (scene id, camera,
 * context, raw indicators: required). TT_OK, TT_ERR_INTERRUPTED (host->should_stop), or a
 * failure (logged). */
TT_API tt_status tt_hybrid_step(tt_hybrid *h, const tt_tuning_state *state,
                                const tt_tuning_target *target, tt_hybrid_report *out);

/* tt_hybrid_warm_start, saying why rows were left out (`out`, may be NULL): a warm start
 * that learns nothing because every row was measured with another clock, thread count,
 * resolution or spp can then name the mismatch. Rows of mode "exploit" are learnt as the
 * model's own answers (TT_PREDICTOR_EXPLOIT), the others as search results. */
TT_API tt_status tt_hybrid_warm_start_ex(tt_hybrid *h, tt_tunedb *db,
                                         const tt_hybrid_warm_filter *f,
                                         tt_hybrid_warm_result *out);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_HYBRID_H */
