/* Shared by the libFuzzer harnesses of tests/fuzz: a scratch file per process for the
 * readers that take a path (pbrt, mesh files, the tuning database), on tmpfs when there is
 * one. Header-only; each harness defines LLVMFuzzerTestOneInput. */
#ifndef TT_FUZZ_UTIL_H
#define TT_FUZZ_UTIL_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* A folder of this process's own: $TT_FUZZ_TMP, else /dev/shm, else /tmp. */
static inline const char *fuzz_dir(void) {
  static char dir[512];
  if (dir[0]) return dir;
  const char *base = getenv("TT_FUZZ_TMP");
  struct stat st;
  if (!base || !*base) base = stat("/dev/shm", &st) == 0 ? "/dev/shm" : "/tmp";
  snprintf(dir, sizeof dir, "%s/tt_fuzz_%ld", base, (long)getpid());
  mkdir(dir, 0700);
  return dir;
}

/* Writes `data` to <fuzz_dir>/<name> and returns its path (static buffer per call site
 * slot: 4 in rotation). */
static inline const char *fuzz_write(const char *name, const uint8_t *data, size_t size) {
  static char paths[4][640];
  static int slot;
  char *p = paths[slot++ & 3];
  snprintf(p, sizeof paths[0], "%s/%s", fuzz_dir(), name);
  FILE *f = fopen(p, "wb");
  if (!f) abort(); /* the harness's own environment is broken: stop loudly */
  if (size && fwrite(data, 1, size, f) != size) abort();
  if (fclose(f) != 0) abort();
  return p;
}

/* A NUL-terminated copy of the input (free it). */
static inline char *fuzz_text(const uint8_t *data, size_t size) {
  char *t = malloc(size + 1);
  if (!t) abort();
  memcpy(t, data, size);
  t[size] = '\0';
  return t;
}

#endif
