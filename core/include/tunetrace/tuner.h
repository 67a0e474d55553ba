/* tunetrace: tuner plugins (kind TT_KIND_TUNER, interface "tt.tuner/1").
 *
 * A tuner searches a parameter space (published by another plugin) for the configuration
 * with the lowest cost. Protocol (ask/tell): next() proposes a configuration; the caller
 * measures it and calls feedback() with its cost before the next call to next(); best()
 * returns the best configuration measured so far. Costs are minimised; an infeasible or
 * failed configuration is fed back as TT_COST_INFEASIBLE.
 *
 * Threads: a tuner object is used by one thread at a time; distinct tuners are independent.
 * The tuner never proposes a configuration outside its space: proposals pass
 * tt_space_check, repaired if the check repairs them.
 *
 * What a tuner may change (tunetrace/params.h, "not tunable" and "activeWhen"): never
 * search a parameter for which tt_space_is_tunable is 0, and pass every proposal through
 * tt_config_canonicalize(proposal, NULL) before the check, so proposals that differ only in
 * parameters that do nothing under their own values are one configuration. The tuning
 * session (tunetrace/tuning.h) gives the tuner a space without the parameters that are not
 * tunable, with the configured values as defaults, and canonicalises again; a tuner used
 * outside a session must do both itself.
 */
#ifndef TUNETRACE_TUNER_H
#define TUNETRACE_TUNER_H

#include <tunetrace/params.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_TUNER_INTERFACE_ID "tt.tuner/1"

/* Cost to report for an infeasible configuration or a failed measurement. */
#define TT_COST_INFEASIBLE 1e300

typedef struct tt_tuner tt_tuner; /* opaque, defined by the plugin */
struct tt_tuner_context;

typedef struct tt_tuner_iface {
  uint32_t struct_size; /* sizeof(tt_tuner_iface) as the plugin was built */

  /* The tuner's own settings (e.g. Nelder-Mead coefficients, initial simplex), or NULL if
   * it has none. Owned by the plugin. Thread-safe. */
  const tt_space *(*space)(void);

  /* Creates a tuner over `target` (which must outlive it) with its own `settings` (of
   * space(); NULL = defaults) and a seed; deterministic for a given seed and cost
   * sequence. `*out` is owned by the caller: free with destroy. */
  tt_status (*create)(const tt_space *target, const tt_config *settings, uint64_t seed,
                      tt_tuner **out);

  /* Writes the next configuration to measure into `out` (a config of `target`). Returns
   * TT_OK, or TT_DONE when the search has converged or is exhausted (then `out` holds the
   * best configuration). Calling next() twice without feedback() re-proposes the same one. */
  tt_status (*next)(tt_tuner *tuner, tt_config *out);

  /* Reports the measured cost of the last proposal (finite, or TT_COST_INFEASIBLE).
   * TT_ERR_INVALID_ARGUMENT if there is no outstanding proposal or the cost is NaN. */
  tt_status (*feedback)(tt_tuner *tuner, double cost);

  /* Best configuration measured so far and its cost; TT_ERR_NO_DATA before any feedback. */
  tt_status (*best)(const tt_tuner *tuner, tt_config *out, double *cost);

  /* Serialises the complete search state as JSON (free with tt_free) so that a later
   * load_state on a tuner created with the same target, settings and seed resumes exactly. */
  tt_status (*save_state)(const tt_tuner *tuner, char **json);

  /* Restores state written by save_state; errors name what did not match. */
  tt_status (*load_state)(tt_tuner *tuner, const char *json);

  /* Destroys the tuner (NULL is ignored). */
  void (*destroy)(tt_tuner *tuner);

  /* ---- ABI 1.1: check with TT_TUNER_HAS; a NULL slot means "not supported" ---- */

  /* Tells the tuner what the caller knows about the search (tt_tuner_context): the state it
   * tunes for, the default configuration's measured cost and the iteration budget. Called
   * after create and before the first next(), at most once; a tuner may ignore any field.
   * The context is copied. TT_ERR_INVALID_ARGUMENT for a malformed context (e.g. a state
   * pointer with state_dim 0). save_state records what the tuner keeps of it, so a resumed
   * tuner needs no second call. */
  tt_status (*set_context)(tt_tuner *tuner, const struct tt_tuner_context *context);
} tt_tuner_iface;

/* What a caller knows about a search (set_context). Fields are only appended. */
typedef struct tt_tuner_context {
  uint32_t struct_size;    /* sizeof(tt_tuner_context) as the caller was built */
  const double *state;     /* the state tuned for (e.g. normalised indicators), or NULL */
  uint32_t state_dim;      /* values in `state` (0 with NULL) */
  const char *state_space; /* what the state means (tt_indicator_norm_id), or NULL */
  /* Cost the caller measured for the target's default configuration (the configuration the
   * space's defaults describe) in this state, or NAN if it did not measure it. A tuner that
   * would propose the default may use this value instead (the host does not measure the
   * default twice). */
  double default_cost;
  /* Measurements the caller will ask for at most (its --iterations), 0 if unknown. A tuner
   * can size its initial design to it (tuner_nm: probe mode when building every arm's
   * simplex would not fit). */
  uint64_t budget;
} tt_tuner_context;

/* Bytes of the ABI 1.0 table: the shortest table a host accepts. */
#define TT_TUNER_IFACE_SIZE_1_0 offsetof(tt_tuner_iface, set_context)

/* True if the plugin's table provides `field` (it may be older than the host). */
#define TT_TUNER_HAS(iface, field) (TT_HAS_FIELD(tt_tuner_iface, iface, field) && (iface)->field)

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_TUNER_H */
