/* tunetrace: predictor plugins (kind TT_KIND_PREDICTOR, interface "tt.predictor/1").
 *
 * A predictor learns, from observed (state, configuration, cost) triples, which
 * configuration of a target parameter space to use in a state. The state is the vector of
 * scene indicators of thesis Table 3.2 normalised to [0, 1] (tunetrace/indicators.h,
 * TT_SCENE_INDICATOR_COUNT values) or any fixed-length vector the caller chooses. Models:
 * nearest neighbour (predictor_nn), RBF features with Greedy-GQ (predictor_rbf), thesis 3.3.2.
 *
 * ABI 1.0 has create/observe/predict/save/load. ABI 1.1 appends create_ex (the state space
 * is named, so model files can refuse states of another space), observe_ex (batches, the
 * state's default cost for relative rewards, offline vs online learning), predict_ex (the
 * query's default cost, what the answer is based on), info (model size: the "no model
 * bigger than a scene needs" sweep) and estimate (the model's cost of a given configuration).
 * A host checks TT_PREDICTOR_HAS before calling a 1.1 function and falls back to the 1.0 ones.
 *
 * Ownership: the caller owns every pointer it passes and every object create returns; the
 * plugin copies what it keeps (states, configurations, strings). Threads: one thread at a
 * time per predictor object, except that predict, predict_ex, info and estimate on an object
 * nobody modifies concurrently may run on several threads at once; distinct objects are
 * independent.
 */
#ifndef TUNETRACE_PREDICTOR_H
#define TUNETRACE_PREDICTOR_H

#include <tunetrace/params.h>
#include <tunetrace/tuner.h> /* TT_COST_INFEASIBLE */

#ifdef __cplusplus
extern "C" {
#endif

#define TT_PREDICTOR_INTERFACE_ID "tt.predictor/1"

typedef struct tt_predictor tt_predictor; /* opaque, defined by the plugin */

/* ---- ABI 1.1 argument structs (each begins with its size; fields only appended) ---- */

/* What a model is created for (create_ex). */
typedef struct tt_predictor_setup {
  uint32_t struct_size;   /* sizeof(tt_predictor_setup) as the caller was built */
  const tt_space *target; /* configurations predicted; must outlive the model */
  uint32_t state_dim;     /* values per state (>= 1) */
  /* What a state vector means, e.g. tt_indicator_norm_id()'s "tt.indicators/1 camera=extent
   * scale=linear"; recorded in model files, and load() refuses a file of another state
   * space. NULL is "". */
  const char *state_space;
  const char *const *state_names; /* state_dim names recorded in model files, or NULL */
  const tt_config *settings;      /* the predictor's hyper-parameters (of space()), NULL =
                                    defaults */
  uint64_t seed;                  /* every random choice (RBF centres, candidates) from it */
} tt_predictor_setup;

/* One observation (observe_ex). */
typedef struct tt_predictor_sample {
  uint32_t struct_size;    /* sizeof(tt_predictor_sample) */
  const double *state;     /* state_dim values */
  const tt_config *config; /* a configuration of the target space */
  double cost;             /* measured cost (finite, > 0), or TT_COST_INFEASIBLE */
  double default_cost;     /* the state's default configuration's cost, or NAN */
} tt_predictor_sample;

/* observe_ex flags. */
#define TT_PREDICTOR_ONLINE 0u /* each sample once, in order: online learning */
#define TT_PREDICTOR_OFFLINE                                                                       \
  1u /* a data set (e.g. a tuning DB): the model may take several
                                    seeded passes in shuffled order (RBF: `epochs`) */
#define TT_PREDICTOR_EXPLOIT                                                                       \
  2u /* or'ed with either: the samples measure configurations the
                                    model itself chose (exploitation), not what a search found.
                                    They refine what the model knows of states it already
                                    holds, but must not become the answer for other states: a
                                    table model whose every exploited state became a stored
                                    state would answer the next state of a camera path with
                                    its own previous answer forever (thesis 3.3.5.1: the table
                                    maps states to what the searches found). Models older than
                                    this flag ignore it. */

/* A query (predict_ex, estimate). */
typedef struct tt_predictor_query {
  uint32_t struct_size; /* sizeof(tt_predictor_query) */
  const double *state;  /* state_dim values */
  double default_cost;  /* the state's default cost if known (turns a relative
                                    estimate into a cost), else NAN */
} tt_predictor_query;

/* What predict_ex says about its answer. Fields a model does not know are NAN / 0. */
typedef struct tt_predictor_result {
  uint32_t struct_size; /* sizeof(tt_predictor_result), set by the caller */
  double expected_cost; /* the model's cost estimate of the answer, NAN if none */
  double value;         /* the model's value of the answer (RBF: Q = theta.phi) */
  double distance;      /* NN: distance to the stored state answered from */
  uint64_t candidates;  /* configurations compared to find the answer */
} tt_predictor_result;

/* Size and shape of a model (info). */
typedef struct tt_predictor_info {
  uint32_t struct_size;    /* sizeof(tt_predictor_info), set by the caller */
  uint64_t memory_bytes;   /* heap bytes the model holds */
  uint64_t entries;        /* NN: stored states; RBF: features */
  uint64_t observations;   /* observations learnt from since create/load */
  uint32_t format_version; /* version of the model files save() writes */
} tt_predictor_info;

typedef struct tt_predictor_iface {
  uint32_t struct_size; /* sizeof(tt_predictor_iface) as the plugin was built */

  /* The predictor's own hyper-parameters (RBF widths, learning rates, ...), or NULL.
   * Owned by the plugin. Thread-safe. */
  const tt_space *(*space)(void);

  /* Creates an empty model over configurations of `target` (which must outlive it) for
   * states of `state_dim` values (state space ""). `*out` is owned by the caller: free with
   * destroy. */
  tt_status (*create)(const tt_space *target, uint32_t state_dim, const tt_config *settings,
                      uint64_t seed, tt_predictor **out);

  /* Adds one observation: in `state`, `config` measured `cost` (lower is better). */
  tt_status (*observe)(tt_predictor *p, const double *state, const tt_config *config, double cost);

  /* Writes the predicted best configuration for `state` into `out`; `expected_cost` (may
   * be NULL) receives the model's cost estimate (NAN if it has none). TT_ERR_NO_DATA if
   * nothing has been observed. */
  tt_status (*predict)(const tt_predictor *p, const double *state, tt_config *out,
                       double *expected_cost);

  /* Saves the model to a file (format owned by the plugin, versioned inside). The file is
   * written atomically: on failure an existing file at `path` is left as it was. */
  tt_status (*save)(const tt_predictor *p, const char *path);

  /* Replaces the model by one saved with save(); errors name the file and the mismatch
   * (another target or state space, another model kind, a newer format, a truncated or
   * corrupt file). On error the model is left unchanged. */
  tt_status (*load)(tt_predictor *p, const char *path);

  /* Destroys the model (NULL is ignored). */
  void (*destroy)(tt_predictor *p);

  /* ---- ABI 1.1: check with TT_PREDICTOR_HAS ---- */

  /* create with a named state space (see tt_predictor_setup). `*out` is owned by the
   * caller: free with destroy. */
  tt_status (*create_ex)(const tt_predictor_setup *setup, tt_predictor **out);

  /* Adds `count` observations; flags TT_PREDICTOR_ONLINE or TT_PREDICTOR_OFFLINE. Samples of
   * infeasible configurations (cost TT_COST_INFEASIBLE) are learnt as such or skipped, as the
   * model sees fit; a NaN or non-positive cost is TT_ERR_INVALID_ARGUMENT (nothing added). */
  tt_status (*observe_ex)(tt_predictor *p, const tt_predictor_sample *samples, size_t count,
                          uint32_t flags);

  /* predict with the query's default cost; `res` (may be NULL) says what the answer is
   * based on. TT_ERR_NO_DATA if nothing has been observed. */
  tt_status (*predict_ex)(const tt_predictor *p, const tt_predictor_query *q, tt_config *out,
                          tt_predictor_result *res);

  /* Writes the model's size into `out` (its struct_size set by the caller). */
  tt_status (*info)(const tt_predictor *p, tt_predictor_info *out);

  /* The model's cost estimate of `config` in the query's state (NAN if it has none, e.g. NN
   * for a configuration it never stored). */
  tt_status (*estimate)(const tt_predictor *p, const tt_predictor_query *q, const tt_config *config,
                        double *cost);
} tt_predictor_iface;

/* Bytes of the ABI 1.0 table: the shortest table a host accepts. */
#define TT_PREDICTOR_IFACE_SIZE_1_0 offsetof(tt_predictor_iface, create_ex)

/* True if the plugin's table provides `field` (it may be older than the host). */
#define TT_PREDICTOR_HAS(iface, field)                                                             \
  (TT_HAS_FIELD(tt_predictor_iface, iface, field) && (iface)->field)

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_PREDICTOR_H */
