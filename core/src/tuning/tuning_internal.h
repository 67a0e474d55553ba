/* Tuning internals shared by the session (tuning.c) and the objectives (objective.c). Not
 * part of the public ABI. */
#ifndef TT_TUNING_INTERNAL_H
#define TT_TUNING_INTERNAL_H

#include <tunetrace/tuning.h>

#include <stddef.h>

/* The objective's cost of one successful measurement. TT_ERR_NO_DATA (with a message)
 * when the pass did not publish the objective's metric, or an rrmse objective has no
 * image or reference; `ref` holds `pixels` reference luminances. */
tt_status tt__objective_cost(const tt_objective *o, const tt_tuning_measurement *m,
                             const double *ref, size_t pixels, double *cost);

#endif /* TT_TUNING_INTERNAL_H */
