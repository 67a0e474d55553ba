/* tunetrace: the tuning hint extension (id "tt.tuning_hint/1"), an optional capability.
 *
 * A plugin may serve TT_TUNING_HINT_ID through get_interface to tell hosts which objective
 * tuning its space should minimise by default, in the host's --objective syntax (e.g.
 * PSSMLT: "metric:small_step_acceptance:target=0.234"). A host that tunes without an
 * explicit target prefers an integrator that serves a hint. */
#ifndef TUNETRACE_TUNING_HINT_H
#define TUNETRACE_TUNING_HINT_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_TUNING_HINT_ID "tt.tuning_hint/1"

typedef struct tt_tuning_hint {
  uint32_t struct_size;  /* sizeof(tt_tuning_hint) as the plugin was built */
  const char *objective; /* default objective spec, static string */
  /* NULL-terminated names of the parameters a default tuning run searches (the others stay
   * at their configured values), or NULL for all. PSSMLT lists its a_i and sigma_i: the
   * thesis tunes those, while chains or bootstrap size would only change the cost of a
   * measurement. --tune-params overrides it. */
  const char *const *tunable;
  /* JSON object of parameter values a tuning run of this plugin starts from, e.g.
   * {"binning": true} for PSSMLT; the user's --set values win. NULL: none. */
  const char *setup;
} tt_tuning_hint;

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_TUNING_HINT_H */
