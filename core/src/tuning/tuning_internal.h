/* Tuning internals shared by the session (tuning.c), the objectives (objective.c) and the
 * hybrid loop (hybrid.c). Not part of the public ABI. */
#ifndef TT_TUNING_INTERNAL_H
#define TT_TUNING_INTERNAL_H

#include <tunetrace/tuning.h>

#include <stddef.h>

/* The objective's cost of one successful measurement. TT_ERR_NO_DATA (with a message)
 * when the pass did not publish the objective's metric, or an rrmse objective has no
 * image or reference; `ref` holds `pixels` reference luminances. */
tt_status tt__objective_cost(const tt_objective *o, const tt_tuning_measurement *m,
                             const double *ref, size_t pixels, double *cost);

/* Writes a run id unique to this process and moment, "<prefix><ns since epoch, hex>-<pid>",
 * into buf (n >= 64): the database's run_id when the caller names none. */
void tt__default_run_id(char *buf, size_t n, const char *prefix);

/* tt_tuning_create; `quiet` non-zero leaves out what is said once per run (the parameters
 * not searched, the summary of database answers and re-measurements): the hybrid loop runs a
 * session per state and says those once itself. */
tt_status tt__tuning_create(const tt_tuning_desc *d, int quiet, tt_tuning **out);

/* The parameters the session does not search (not tunable, or unable to act), as a list
 * for people, or NULL when every parameter is searched. */
const char *tt__tuning_dropped(const tt_tuning *t);

#endif /* TT_TUNING_INTERNAL_H */
