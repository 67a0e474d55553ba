/* Minimal assertion helpers for tunetrace's C tests. Each test is one executable run by
 * meson; a failed CHECK prints file:line and the expression and makes main return 1.
 * Exit code 77 tells meson the test was skipped. */
#ifndef TT_TEST_H
#define TT_TEST_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int tt_test_failures = 0;
static int tt_test_checks = 0;

#define CHECK(cond)                                                                                \
  do {                                                                                             \
    tt_test_checks++;                                                                              \
    if (!(cond)) {                                                                                 \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);                     \
      tt_test_failures++;                                                                          \
    }                                                                                              \
  } while (0)

#define CHECK_MSG(cond, ...)                                                                       \
  do {                                                                                             \
    tt_test_checks++;                                                                              \
    if (!(cond)) {                                                                                 \
      fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond);                     \
      fprintf(stderr, __VA_ARGS__);                                                                \
      fputc('\n', stderr);                                                                         \
      tt_test_failures++;                                                                          \
    }                                                                                              \
  } while (0)

/* |a - b| <= tol */
#define CHECK_NEAR(a, b, tol)                                                                      \
  do {                                                                                             \
    double tt__a = (double)(a), tt__b = (double)(b), tt__t = (double)(tol);                        \
    tt_test_checks++;                                                                              \
    if (!(fabs(tt__a - tt__b) <= tt__t)) {                                                         \
      fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.9g, %s = %.9g, tol %.3g\n", __FILE__,      \
              __LINE__, #a, tt__a, #b, tt__b, tt__t);                                              \
      tt_test_failures++;                                                                          \
    }                                                                                              \
  } while (0)

/* strstr(haystack, needle) != NULL, printing both on failure */
#define CHECK_CONTAINS(haystack, needle)                                                           \
  do {                                                                                             \
    const char *tt__h = (haystack), *tt__n = (needle);                                             \
    tt_test_checks++;                                                                              \
    if (!tt__h || !strstr(tt__h, tt__n)) {                                                         \
      fprintf(stderr, "%s:%d: expected \"%s\" in \"%s\"\n", __FILE__, __LINE__, tt__n,             \
              tt__h ? tt__h : "(null)");                                                           \
      tt_test_failures++;                                                                          \
    }                                                                                              \
  } while (0)

/* Skips the test (exit 77) for a reason outside the code under test: data or a tool the
 * README's setup provides. tools/test.sh fails the suite on any skip when CI is set, so a
 * skip never hides a missing install step there. */
#define TEST_SKIP(...)                                                                             \
  do {                                                                                             \
    fprintf(stderr, "SKIP: " __VA_ARGS__);                                                         \
    fputc('\n', stderr);                                                                           \
    exit(77);                                                                                      \
  } while (0)

/* Fails the test at once (a set-up step that must work, such as a temporary folder). */
#define TEST_FAIL(...)                                                                             \
  do {                                                                                             \
    fprintf(stderr, "FAIL: " __VA_ARGS__);                                                         \
    fputc('\n', stderr);                                                                           \
    exit(1);                                                                                       \
  } while (0)

/* The whole content of `path` (malloc'ed and NUL-terminated: free it with free()), its
 * length in *len when len is not NULL; NULL when the file cannot be read. The tests' one
 * file reader (read in chunks, so pipes and files that grow work too). */
static inline char *tt_test_read_file(const char *path, size_t *len) {
  if (len) *len = 0;
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  char *buf = NULL;
  size_t n = 0, cap = 0;
  int oom = 0; /* out of memory with the buffer full: the file is not read whole */
  for (;;) {
    if (n + 1 >= cap) {
      size_t ncap = cap ? 2 * cap : 65536;
      char *nb = (char *)realloc(buf, ncap);
      if (!nb) {
        oom = 1;
        break;
      }
      buf = nb;
      cap = ncap;
    }
    size_t got = fread(buf + n, 1, cap - n - 1, f);
    n += got;
    if (got == 0) break;
  }
  int failed = oom || ferror(f) || !buf;
  fclose(f);
  if (failed) {
    free(buf);
    return NULL;
  }
  buf[n] = '\0';
  if (len) *len = n;
  return buf;
}

/* Prints a summary and returns the process exit code: failure when a check failed, and
 * when no check ran at all (a test that asserts nothing proves nothing: an early return, a
 * loop over an empty list). Every test's main ends with `return tt_test_finish(name);`. */
static inline int tt_test_finish(const char *name) {
  printf("%s: %d checks, %d failed\n", name, tt_test_checks, tt_test_failures);
  if (tt_test_checks == 0) {
    fprintf(stderr, "%s: no check ran: the test asserted nothing\n", name);
    return 1;
  }
  return tt_test_failures ? 1 : 0;
}

#endif
