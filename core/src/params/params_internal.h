/* Internal helpers shared by params.c and params_json.c: things the JSON code needs that
 * the public reader API does not expose (version, constraint texts, value formatting). */
#ifndef TT_PARAMS_INTERNAL_H
#define TT_PARAMS_INTERNAL_H

#include <tunetrace/params.h>
#include <tt_util/strings.h> /* tt__strdup */

#include <stddef.h>

/* Plugin version string given to tt_space_create ("" if none). */
const char *tt__space_version(const tt_space *space);
/* Number of constraint descriptions added with tt_space_add_constraint_text. */
size_t tt__space_constraint_count(const tt_space *space);
/* Constraint description `k`, or NULL when out of range. */
const char *tt__space_constraint(const tt_space *space, size_t k);
/* Kind of the possible values of NOM parameter `index` (TT_VALUE_INT/BOOL/STRING). */
tt_value_kind tt__space_nom_kind(const tt_space *space, size_t index);
/* Exact bounds of INT parameter `index`; 0 (and *min, *max untouched) if not INT. */
int tt__space_int_range(const tt_space *space, size_t index, int64_t *min, int64_t *max);
/* Writes what to tell about an unknown parameter `name` of `space` into buf: 'did you mean
 * "X"? ' when a name is close (tt_suggest), then "known: a, b, c" (all names of the space). */
void tt__space_unknown_hint(const tt_space *space, const char *name, char *buf, size_t n);
/* Copies tt_last_error() and re-records it with `prefix` in front (e.g. "file.json: "),
 * so lower-level messages gain the input's name; returns `status`. */
tt_status tt__prefix_error(tt_status status, const char *prefix);

#endif /* TT_PARAMS_INTERNAL_H */
