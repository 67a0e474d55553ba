/* "Did you mean" (tunetrace/suggest.h): edit distances of known pairs, the suggestions the
 * host and the loaders print for typical typos, and tt_suggest against a reference that
 * computes the distance to every candidate (tt_suggest skips candidates whose length alone
 * rules them out, suggest.c): the same answer on 20,000 random words, long ones included. */
#include <tunetrace/suggest.h>

#include <tt_util/rng.h>

#include "tt_test.h"

/* tt_suggest as documented, without the length shortcut */
static const char *reference(const char *word, const char *const *cand, size_t count) {
  if (!word || !*word || !cand) return NULL;
  size_t wl = strlen(word);
  const char *best = NULL, *prefix = NULL;
  unsigned best_d = 255;
  size_t prefixes = 0;
  for (size_t k = 0; k < count; k++) {
    const char *c = cand[k];
    if (!c) continue;
    if (!strcmp(c, word)) return NULL;
    size_t cl = strlen(c), longer = cl > wl ? cl : wl;
    unsigned limit = longer <= 5 ? 1u : longer / 3 < 2 ? (unsigned)(longer / 3) : 2u;
    unsigned d = tt_edit_distance(word, c);
    if (d <= limit && d < best_d) best = c, best_d = d;
    if (wl >= 3 && cl > wl && !strncmp(c, word, wl)) prefix = c, prefixes++;
  }
  if (best) return best;
  return prefixes == 1 ? prefix : NULL;
}

int main(void) {
  CHECK(tt_edit_distance("", "") == 0);
  CHECK(tt_edit_distance("abc", "") == 3);
  CHECK(tt_edit_distance("kitten", "sitting") == 3);
  CHECK(tt_edit_distance("travcost", "trvacost") == 1); /* adjacent transposition */
  CHECK(tt_edit_distance("spp", "SPP") == 3);           /* case-sensitive */

  static const char *const names[] = {
      "quality", "branchingFactor", "minLeaf", "maxLeaf", "travcost", "intcost",
      "compact", "backend",         "spp",     NULL,      "threads",  "a",
      "ab"};
  const size_t n = sizeof names / sizeof names[0];
  CHECK(tt_suggest("qualty", names, n) && !strcmp(tt_suggest("qualty", names, n), "quality"));
  CHECK(tt_suggest("branchingfactor", names, n) &&
        !strcmp(tt_suggest("branchingfactor", names, n), "branchingFactor"));
  CHECK(tt_suggest("minleaf", names, n) && !strcmp(tt_suggest("minleaf", names, n), "minLeaf"));
  CHECK(tt_suggest("thread", names, n) && !strcmp(tt_suggest("thread", names, n), "threads"));
  CHECK(tt_suggest("quality", names, n) == NULL); /* a candidate itself */
  CHECK(tt_suggest("completelydifferent", names, n) == NULL);
  CHECK(tt_suggest("", names, n) == NULL);

  /* random words over a small alphabet (so near misses happen), 0-300 characters */
  char word[301];
  uint64_t st = 13;
  size_t agree = 0, suggested = 0;
  const int trials = 20000;
  for (int t = 0; t < trials; t++) {
    uint64_t r = tt__splitmix64(&st);
    size_t len;
    if (t % 4 == 0) len = (size_t)(r % 301); /* long ones too */
    else len = (size_t)(r % 18);
    if (t % 2 && len > 0) { /* a candidate with an edit or two */
      const char *c = names[r % n] ? names[r % n] : "spp";
      snprintf(word, sizeof word, "%s", c);
      size_t cl = strlen(word);
      for (int e = 0; e < 1 + (int)((r >> 20) % 3) && cl; e++) {
        size_t at = (size_t)((tt__splitmix64(&st)) % cl);
        word[at] = "abcelqtx"[tt__splitmix64(&st) % 8];
      }
      if ((r >> 30) & 1 && cl + 1 < sizeof word) word[cl] = 's', word[cl + 1] = '\0';
    } else {
      for (size_t i = 0; i < len; i++) word[i] = "abcelnqrst"[tt__splitmix64(&st) % 10];
      word[len] = '\0';
    }
    const char *got = tt_suggest(word, names, n), *want = reference(word, names, n);
    agree += got == want;
    suggested += want != NULL;
    if (got != want)
      fprintf(stderr, "\"%s\": tt_suggest %s, reference %s\n", word, got ? got : "NULL",
              want ? want : "NULL");
  }
  CHECK_MSG(agree == (size_t)trials, "%zu of %d random words agree", agree, trials);
  CHECK_MSG(suggested > 1000, "only %zu words had a suggestion: the test misses near typos",
            suggested);
  return tt_test_finish("suggest");
}
