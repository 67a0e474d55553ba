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

#define CHECK(cond)                                                                    \
  do {                                                                                 \
    tt_test_checks++;                                                                  \
    if (!(cond)) {                                                                     \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);         \
      tt_test_failures++;                                                              \
    }                                                                                  \
  } while (0)

#define CHECK_MSG(cond, ...)                                                           \
  do {                                                                                 \
    tt_test_checks++;                                                                  \
    if (!(cond)) {                                                                     \
      fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond);         \
      fprintf(stderr, __VA_ARGS__);                                                    \
      fputc('\n', stderr);                                                             \
      tt_test_failures++;                                                              \
    }                                                                                  \
  } while (0)

/* |a - b| <= tol */
#define CHECK_NEAR(a, b, tol)                                                          \
  do {                                                                                 \
    double tt__a = (double)(a), tt__b = (double)(b), tt__t = (double)(tol);            \
    tt_test_checks++;                                                                  \
    if (!(fabs(tt__a - tt__b) <= tt__t)) {                                             \
      fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.9g, %s = %.9g, tol %.3g\n",    \
              __FILE__, __LINE__, #a, tt__a, #b, tt__b, tt__t);                        \
      tt_test_failures++;                                                              \
    }                                                                                  \
  } while (0)

/* strstr(haystack, needle) != NULL, printing both on failure */
#define CHECK_CONTAINS(haystack, needle)                                               \
  do {                                                                                 \
    const char *tt__h = (haystack), *tt__n = (needle);                                 \
    tt_test_checks++;                                                                  \
    if (!tt__h || !strstr(tt__h, tt__n)) {                                             \
      fprintf(stderr, "%s:%d: expected \"%s\" in \"%s\"\n", __FILE__, __LINE__, tt__n, \
              tt__h ? tt__h : "(null)");                                               \
      tt_test_failures++;                                                              \
    }                                                                                  \
  } while (0)

#define TEST_SKIP(...)                                                                 \
  do {                                                                                 \
    fprintf(stderr, "SKIP: " __VA_ARGS__);                                             \
    fputc('\n', stderr);                                                               \
    exit(77);                                                                          \
  } while (0)

/* Prints a summary and returns the process exit code. */
static inline int tt_test_finish(const char *name) {
  printf("%s: %d checks, %d failed\n", name, tt_test_checks, tt_test_failures);
  return tt_test_failures ? 1 : 0;
}

#endif
