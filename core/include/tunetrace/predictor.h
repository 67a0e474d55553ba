/* tunetrace: predictor plugins (kind TT_KIND_PREDICTOR, interface "tt.predictor/1").
 *
 * A predictor learns, from observed (state, configuration, cost) triples, which
 * configuration of a target parameter space to use in a state. The state is the vector of
 * scene indicators of thesis Table 3.2 (tt_scene_indicators, TT_SCENE_INDICATOR_COUNT
 * values) or any fixed-length vector the caller chooses. Models: nearest neighbour,
 * RBF features with Greedy-GQ (thesis 3.3.2).
 *
 * Threads: one thread at a time per predictor object.
 */
#ifndef TUNETRACE_PREDICTOR_H
#define TUNETRACE_PREDICTOR_H

#include <tunetrace/params.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_PREDICTOR_INTERFACE_ID "tt.predictor/1"

typedef struct tt_predictor tt_predictor;  /* opaque, defined by the plugin */

typedef struct tt_predictor_iface {
  uint32_t struct_size;     /* sizeof(tt_predictor_iface) as the plugin was built */

  /* The predictor's own hyper-parameters (RBF widths, learning rates, ...), or NULL.
   * Owned by the plugin. Thread-safe. */
  const tt_space *(*space)(void);

  /* Creates an empty model over configurations of `target` (which must outlive it) for
   * states of `state_dim` values. `*out` is owned by the caller: free with destroy. */
  tt_status (*create)(const tt_space *target, uint32_t state_dim, const tt_config *settings,
                      uint64_t seed, tt_predictor **out);

  /* Adds one observation: in `state`, `config` measured `cost` (lower is better). */
  tt_status (*observe)(tt_predictor *p, const double *state, const tt_config *config,
                       double cost);

  /* Writes the predicted best configuration for `state` into `out`; `expected_cost` (may
   * be NULL) receives the model's cost estimate (NAN if it has none). TT_ERR_NO_DATA if
   * nothing has been observed. */
  tt_status (*predict)(const tt_predictor *p, const double *state, tt_config *out,
                       double *expected_cost);

  /* Saves the model to a file (format owned by the plugin, versioned inside). */
  tt_status (*save)(const tt_predictor *p, const char *path);

  /* Replaces the model by one saved with save(); errors name the file and the mismatch. */
  tt_status (*load)(tt_predictor *p, const char *path);

  /* Destroys the model (NULL is ignored). */
  void (*destroy)(tt_predictor *p);

  /* ---- appended in later ABI minors: check struct_size ---- */
} tt_predictor_iface;

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_PREDICTOR_H */
