/* tunetrace internal: string helpers written once for the library, the host and the
 * in-tree plugins. Include as <tt_util/strings.h> (tunetrace_util_dep; see rng.h). */
#ifndef TT_UTIL_STRINGS_H
#define TT_UTIL_STRINGS_H

#include <stdlib.h>
#include <string.h>

/* A malloc'ed copy of `s` (free with free()); NULL when `s` is NULL or out of memory. */
static inline char *tt__strdup(const char *s) {
  if (!s) return NULL;
  size_t n = strlen(s) + 1;
  char *d = (char *)malloc(n);
  if (d) memcpy(d, s, n);
  return d;
}

#endif /* TT_UTIL_STRINGS_H */
