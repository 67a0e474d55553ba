/* tunetrace: parameter spaces and configurations, shared by tuners, predictors and every
 * tunable plugin.
 *
 * A space is the JSON of thesis Fig. 3.1, extended with descriptions and constraints:
 *
 *   { "plugin": "accel_embree", "version": "1.0.0",
 *     "parameters": [
 *       { "name": "quality", "type": "NOM", "possibleValues": [1, 2, 3], "value": 2,
 *         "description": "1 Morton, 2 binned SAH, 3 SAH with spatial splits" },
 *       { "name": "maxDepth", "type": "INT", "min": 4, "max": 64, "value": 32 },
 *       { "name": "intcost", "type": "FLOAT", "min": 0.1, "max": 10.0, "value": 1.0 } ],
 *     "constraints": [ { "description": "branchingFactor^(maxDepth-1)*maxLeafSize >= N" } ] }
 *
 * "value" is the default. NOM values may be integers, booleans or strings, all of one kind
 * within a parameter. FLOAT parameters may be flagged "log": true (tuners then search
 * log(value)). Constraints are described in text for people and enforced by the space's
 * check function (tt_space_set_check), which may repair a configuration or reject it.
 *
 * A configuration (tt_config) holds one value per parameter of its space, in the space's
 * order. Spaces are immutable once published (a plugin builds its space once, at init, and
 * the space lives until deinit); configurations are small values owned by whoever created
 * them. No function here is thread-safe on the same object unless it says so; reading a
 * published space from many threads is safe.
 */
#ifndef TUNETRACE_PARAMS_H
#define TUNETRACE_PARAMS_H

#include <tunetrace/common.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tt_space tt_space;   /* opaque parameter space */
typedef struct tt_config tt_config; /* opaque configuration (values for one space) */

typedef enum tt_param_type {
  TT_PARAM_INT = 1,   /* integer in [min, max] */
  TT_PARAM_FLOAT = 2, /* real in [min, max] */
  TT_PARAM_NOM = 3    /* one of a list of possible values (no order assumed) */
} tt_param_type;

typedef enum tt_value_kind {
  TT_VALUE_INT = 1,
  TT_VALUE_FLOAT = 2,
  TT_VALUE_BOOL = 3,
  TT_VALUE_STRING = 4
} tt_value_kind;

/* One parameter value. For NOM parameters `index` is the position in possibleValues and
 * the typed field holds the value itself. Strings point into the space (never free). */
typedef struct tt_value {
  tt_value_kind kind;
  int32_t index; /* NOM: index into possibleValues; -1 for INT/FLOAT */
  int64_t i;     /* TT_VALUE_INT, TT_VALUE_BOOL (0/1) */
  double f;      /* TT_VALUE_FLOAT; also set (converted) for INT and BOOL */
  const char *s; /* TT_VALUE_STRING */
} tt_value;

/* Result of a constraint check. */
typedef enum tt_check_result {
  TT_CHECK_OK = 0,        /* feasible as is */
  TT_CHECK_REPAIRED = 1,  /* infeasible; `config` was changed into a feasible one */
  TT_CHECK_INFEASIBLE = 2 /* infeasible and not repairable; the plugin will reject it */
} tt_check_result;

/* Constraint check: may modify `config` to repair it; writes a one-line reason into `why`
 * (size `why_size`) unless the result is TT_CHECK_OK. Must be thread-safe and pure. */
typedef tt_check_result (*tt_check_fn)(const tt_space *space, tt_config *config, char *why,
                                       size_t why_size, void *user);

/* ---- building a space (plugin side, at init) ---- */

/* Creates an empty space owned by the caller (free with tt_space_destroy). */
TT_API tt_space *tt_space_create(const char *plugin_name, const char *plugin_version);
/* Destroys a space; configurations made from it must be destroyed first. */
TT_API void tt_space_destroy(tt_space *space);
/* Adds an INT parameter; returns its index or -1 (bad range, duplicate name). */
TT_API int tt_space_add_int(tt_space *space, const char *name, int64_t min, int64_t max,
                            int64_t def, const char *description);
/* Adds a FLOAT parameter (log != 0: tuners search in log space; requires min > 0). */
TT_API int tt_space_add_float(tt_space *space, const char *name, double min, double max, double def,
                              int log, const char *description);
/* Adds a NOM parameter with integer possible values; def_index selects the default. */
TT_API int tt_space_add_nom_int(tt_space *space, const char *name, const int64_t *values,
                                size_t count, size_t def_index, const char *description);
/* Adds a NOM parameter with possible values [false, true]. */
TT_API int tt_space_add_nom_bool(tt_space *space, const char *name, int def,
                                 const char *description);
/* Adds a NOM parameter with string possible values (copied). */
TT_API int tt_space_add_nom_string(tt_space *space, const char *name, const char *const *values,
                                   size_t count, size_t def_index, const char *description);
/* Adds a human-readable constraint description (published in the JSON). */
TT_API void tt_space_add_constraint_text(tt_space *space, const char *description);
/* Installs the constraint check used by tt_space_check (one per space). */
TT_API void tt_space_set_check(tt_space *space, tt_check_fn fn, void *user);

/* ---- reading a space ---- */

TT_API const char *tt_space_plugin(const tt_space *space);
TT_API size_t tt_space_count(const tt_space *space);
/* Index of the parameter called `name`, or -1. */
TT_API int tt_space_find(const tt_space *space, const char *name);
TT_API const char *tt_space_name(const tt_space *space, size_t index);
TT_API tt_param_type tt_space_type(const tt_space *space, size_t index);
TT_API const char *tt_space_description(const tt_space *space, size_t index);
/* INT/FLOAT bounds (as doubles); NOM: 0 and count-1. */
TT_API double tt_space_min(const tt_space *space, size_t index);
TT_API double tt_space_max(const tt_space *space, size_t index);
TT_API int tt_space_is_log(const tt_space *space, size_t index);
/* NOM: number of possible values (0 for INT/FLOAT). */
TT_API size_t tt_space_nom_count(const tt_space *space, size_t index);
/* NOM: possible value `k` (0 <= k < nom_count). */
TT_API tt_value tt_space_nom_value(const tt_space *space, size_t index, size_t k);
/* Default value of parameter `index`. */
TT_API tt_value tt_space_default(const tt_space *space, size_t index);

/* Serialises the space as Fig. 3.1 JSON (pretty-printed). Free with tt_free. */
TT_API char *tt_space_to_json(const tt_space *space);
/* Parses a space from JSON (as written by tt_space_to_json; no check function). `source`
 * names the input in error messages. NULL on error (see tt_last_error). */
TT_API tt_space *tt_space_from_json(const char *json, const char *source);

/* Runs the space's constraint check on `config` (TT_CHECK_OK when no check is installed).
 * Thread-safe for distinct configs. */
TT_API tt_check_result tt_space_check(const tt_space *space, tt_config *config, char *why,
                                      size_t why_size);

/* ---- configurations ---- */

/* Creates a configuration holding the space's defaults. Free with tt_config_destroy. */
TT_API tt_config *tt_config_create(const tt_space *space);
TT_API void tt_config_destroy(tt_config *config);
/* Copies values of `src` into `dst` (same space). */
TT_API void tt_config_copy(tt_config *dst, const tt_config *src);
TT_API tt_config *tt_config_clone(const tt_config *config);
TT_API const tt_space *tt_config_space(const tt_config *config);
/* Non-zero if both hold the same values. */
TT_API int tt_config_equal(const tt_config *a, const tt_config *b);

/* Value of parameter `index`. */
TT_API tt_value tt_config_get(const tt_config *config, size_t index);
/* Convenience readers by name; return `fallback` if the name is unknown. NOM values are
 * converted (bool -> 0/1; string -> its index). */
TT_API int64_t tt_config_get_int(const tt_config *config, const char *name, int64_t fallback);
TT_API double tt_config_get_float(const tt_config *config, const char *name, double fallback);
/* NOM string value by name, or NULL. */
TT_API const char *tt_config_get_string(const tt_config *config, const char *name);

/* Sets INT, FLOAT or NOM by a numeric value. Out of range is TT_ERR_INVALID_ARGUMENT (no
 * silent clamping); INT must be integral; NOM must equal one of possibleValues. */
TT_API tt_status tt_config_set_number(tt_config *config, size_t index, double value);
/* Sets a NOM parameter by possible-value index. */
TT_API tt_status tt_config_set_index(tt_config *config, size_t index, size_t nom_index);
/* Parses `text` ("4", "0.5", "true", "native") for parameter `name`, as --set does. Errors
 * name the parameter, the text and what was expected. */
TT_API tt_status tt_config_set_string(tt_config *config, const char *name, const char *text);

/* Maps a configuration to the unit cube: INT/FLOAT to [0,1] (log-scaled if flagged), NOM
 * to (index + 0.5) / count. `out` has tt_space_count entries. */
TT_API void tt_config_to_unit(const tt_config *config, double *out);
/* Inverse of tt_config_to_unit: clamps to [0,1], rounds INT to nearest, NOM to the bin. */
TT_API void tt_config_from_unit(tt_config *config, const double *unit);

/* Serialises as a JSON object {"name": value, ...}. Free with tt_free. */
TT_API char *tt_config_to_json(const tt_config *config);
/* Sets every parameter named in a JSON object; unknown names and bad values are errors
 * naming `source`, the parameter and what was expected. */
TT_API tt_status tt_config_from_json(tt_config *config, const char *json, const char *source);

/* ---- subsets: tuning some parameters of a larger space ---- */

/* Creates a space holding copies of the parameters `names` of `space` (same bounds, types
 * and possible values; constraint texts copied, no check function), with defaults taken
 * from `base` (a config of `space`; NULL = the space's defaults). Free with
 * tt_space_destroy. NULL and a message naming the unknown parameter on error. */
TT_API tt_space *tt_space_subset(const tt_space *space, const char *const *names, size_t count,
                                 const tt_config *base);

/* Copies into `dst` every parameter of `src` that `dst`'s space has under the same name
 * and type (e.g. a subset configuration back into the full one). Returns how many were
 * copied, or -1 if a value does not fit (nothing is rolled back). */
TT_API int tt_config_assign(tt_config *dst, const tt_config *src);

/* ---- what a tuner may change: settings that are not tunable, parameters that act only
 *      under a condition ----
 *
 * A parameter marked not tunable is a setting (instrumentation, a debug switch) that a
 * tuner leaves at its configured value; --set still sets it. A parameter with conditions
 * acts only while every condition holds: condition k says that the NOM parameter `parent`
 * takes one of a list of its possible values (accel_embree: maxLeafSize acts only with
 * backend "custom"); a parameter whose parent is inactive is inactive too. JSON (Fig. 3.1
 * extended): "tunable": false, "activeWhen": {"backend": ["custom"], "quality": [2, 3]};
 * both are absent when the parameter is tunable and unconditional.
 *
 * How a tuner honours them (tuner_nm, tuner_random and the host's --explore do):
 *  - never search a parameter that is not tunable;
 *  - treat a parameter inactive under a configuration's values as absent from it: call
 *    tt_config_canonicalize on every proposal, so configurations that differ only in
 *    parameters that do nothing are the same configuration, measured once;
 *  - optionally (tuner_nm) search the inactive parameters of a branch not at all, e.g. one
 *    simplex over the active parameters per value of the parent.
 * The marking is published with the space and must be set before the first configuration
 * of the space is created, like the parameters themselves. */

/* Marks parameter `index` as not tunable (tunable = 0) or tunable (the default). */
TT_API tt_status tt_space_set_tunable(tt_space *space, size_t index, int tunable);
/* Non-zero if tuners may change parameter `index` (0 for an index out of range). */
TT_API int tt_space_is_tunable(const tt_space *space, size_t index);
/* Marks parameter `index` as acting only while the scene moves (e.g. how an accel updates
 * itself between the frames of an animated scene; "motionOnly": true in the space's JSON).
 * Still tunable: tuning along an animated sequence searches it, while the tuning plan of a
 * still scene (tt_session_tuning_plan without named parameters) leaves it out, since no
 * measurement there could tell its values apart. */
TT_API tt_status tt_space_set_motion_only(tt_space *space, size_t index, int motion_only);
/* Non-zero if parameter `index` acts only while the scene moves (0 out of range). */
TT_API int tt_space_is_motion_only(const tt_space *space, size_t index);
/* Adds a condition to parameter `index`: it acts only while the NOM parameter `parent`
 * holds one of `values` (count >= 1, written as --set would: "custom", "2", "true"). A
 * parameter may not be its own ancestor. Errors name the parameter and the value. */
TT_API tt_status tt_space_add_condition(tt_space *space, size_t index, const char *parent,
                                        const char *const *values, size_t count);
/* Number of conditions of parameter `index`. */
TT_API size_t tt_space_condition_count(const tt_space *space, size_t index);
/* Index of the parent parameter of condition `k` of parameter `index`, or -1. */
TT_API int tt_space_condition_parent(const tt_space *space, size_t index, size_t k);
/* Non-zero if condition `k` of parameter `index` holds when its parent takes possible value
 * `nom_index`. */
TT_API int tt_space_condition_allows(const tt_space *space, size_t index, size_t k,
                                     size_t nom_index);
/* Non-zero if parameter `index` acts under the values of `config`: every condition holds
 * and every parent is active itself. Says nothing about tunable. */
TT_API int tt_config_is_active(const tt_config *config, size_t index);
/* Sets every parameter of `config` that is not tunable, or inactive under the
 * configuration's own values, to its value in `base` (a configuration of the same space,
 * e.g. the configured start; NULL: the space's defaults). Returns how many values changed.
 * Tuners call it on each proposal (see above). */
TT_API int tt_config_canonicalize(tt_config *config, const tt_config *base);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_PARAMS_H */
