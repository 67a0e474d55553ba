/* "Did you mean": edit distance between names and the closest plausible candidate
 * (tunetrace/suggest.h). Names are short (options, plugins, parameters), so a full
 * distance matrix on the stack is cheap. */
#include <tunetrace/suggest.h>

#include <string.h>

#define TT__SUGGEST_MAX 255 /* longer names are compared on their first 255 characters */

unsigned tt_edit_distance(const char *a, const char *b) {
  if (!a || !b) return TT__SUGGEST_MAX;
  size_t n = strlen(a), m = strlen(b);
  if (n > TT__SUGGEST_MAX) n = TT__SUGGEST_MAX;
  if (m > TT__SUGGEST_MAX) m = TT__SUGGEST_MAX;
  /* three rows of the optimal-string-alignment recurrence: i-2, i-1 and i */
  unsigned rows[3][TT__SUGGEST_MAX + 1];
  for (size_t j = 0; j <= m; j++) rows[1][j] = (unsigned)j;
  for (size_t i = 1; i <= n; i++) {
    unsigned *cur = rows[(i + 1) % 3], *prev = rows[i % 3], *prev2 = rows[(i + 2) % 3];
    cur[0] = (unsigned)i;
    for (size_t j = 1; j <= m; j++) {
      unsigned cost = a[i - 1] == b[j - 1] ? 0u : 1u;
      unsigned d = prev[j] + 1;                           /* deletion */
      if (cur[j - 1] + 1 < d) d = cur[j - 1] + 1;         /* insertion */
      if (prev[j - 1] + cost < d) d = prev[j - 1] + cost; /* substitution */
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] && prev2[j - 2] + 1 < d)
        d = prev2[j - 2] + 1; /* transposition */
      cur[j] = d;
    }
  }
  unsigned d = rows[(n + 1) % 3][m];
  return d > TT__SUGGEST_MAX ? TT__SUGGEST_MAX : d;
}

const char *tt_suggest(const char *word, const char *const *candidates, size_t count) {
  if (!word || !*word || !candidates) return NULL;
  size_t wl = strlen(word);
  const char *best = NULL, *prefix = NULL;
  unsigned best_d = TT__SUGGEST_MAX;
  size_t prefixes = 0;
  for (size_t k = 0; k < count; k++) {
    const char *c = candidates[k];
    if (!c) continue;
    if (!strcmp(c, word)) return NULL; /* not a typo: the caller failed for another reason */
    size_t cl = strlen(c), longer = cl > wl ? cl : wl;
    unsigned limit = longer <= 5 ? 1u : longer / 3 < 2 ? (unsigned)(longer / 3) : 2u;
    /* the distance is at least the difference in length: a name longer or shorter than the
     * candidate by more than the limit cannot be its typo, and its distance matrix (up to
     * 255 x 255 cells, most of the parameter fuzzer's time on long unknown names) is not
     * needed */
    size_t gap = cl > wl ? cl - wl : wl - cl;
    if (gap <= limit) {
      unsigned d = tt_edit_distance(word, c);
      if (d <= limit && d < best_d) best = c, best_d = d;
    }
    if (wl >= 3 && cl > wl && !strncmp(c, word, wl)) prefix = c, prefixes++;
  }
  if (best) return best;
  return prefixes == 1 ? prefix : NULL;
}
