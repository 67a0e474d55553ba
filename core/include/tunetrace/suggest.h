/* tunetrace: "did you mean" for names typed by people (options, plugins, parameters).
 *
 * The host and the library use it for every unknown name they report; plugins may use it
 * for their own settings. Thread-safe, no allocation.
 */
#ifndef TUNETRACE_SUGGEST_H
#define TUNETRACE_SUGGEST_H

#include <tunetrace/common.h>

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Edit distance (Damerau-Levenshtein with adjacent transpositions, case-sensitive) between
 * `a` and `b`; counts stop at 255 (longer names than that compare as 255). */
TT_API unsigned tt_edit_distance(const char *a, const char *b);

/* The candidate closest to `word` when it is a likely typo of it: edit distance at most
 * 2 and at most a third of the longer name (1 for names of up to 5 characters), or `word`
 * is a prefix of exactly one candidate of the closest ones. Ties go to the earlier
 * candidate. NULL when nothing is that close, or `word` itself is a candidate. NULL
 * entries of `candidates` are skipped. */
TT_API const char *tt_suggest(const char *word, const char *const *candidates, size_t count);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_SUGGEST_H */
