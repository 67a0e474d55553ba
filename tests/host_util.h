/* Helpers for end-to-end tests that run the host program. */
#ifndef TT_HOST_UTIL_H
#define TT_HOST_UTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

/* Path of the built host program. */
static const char *host_path(void) {
  static char path[4096];
  const char *root = getenv("TT_BUILD_ROOT");
  snprintf(path, sizeof path, "%s/host/host", root ? root : ".");
  return path;
}

/* Runs `host ARGS` with stdout+stderr captured into `out` (size n), killed (SIGKILL) after
 * `seconds` if that is > 0; returns the exit code (or 128+signal: 137 when killed). */
static int run_host_timeout(int seconds, const char *args, char *out, size_t n) {
  char cmd[8192];
  if (seconds > 0)
    snprintf(cmd, sizeof cmd, "timeout -s KILL %d '%s' %s 2>&1", seconds, host_path(), args);
  else snprintf(cmd, sizeof cmd, "'%s' %s 2>&1", host_path(), args);
  FILE *p = popen(cmd, "r");
  if (!p) return -1;
  size_t len = 0;
  if (out && n) {
    out[0] = 0;
    size_t r;
    while (len + 1 < n && (r = fread(out + len, 1, n - 1 - len, p)) > 0) len += r;
    out[len] = 0;
  }
  char sink[4096];
  while (fread(sink, 1, sizeof sink, p) > 0) {}
  int status = pclose(p);
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

/* Runs `host ARGS` as run_host_timeout without a time limit. */
static int run_host(const char *args, char *out, size_t n) {
  return run_host_timeout(0, args, out, n);
}

/* Path of a file in the source tree. */
static const char *source_path(const char *rel) {
  static char path[4][4096];
  static int k;
  const char *root = getenv("TT_SOURCE_ROOT");
  k = (k + 1) % 4;
  snprintf(path[k], sizeof path[k], "%s/%s", root ? root : ".", rel);
  return path[k];
}

#endif
