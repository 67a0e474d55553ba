/* End to end: progress of long work (#30). A render asking for 16777216 spp (hours): piped
 * to a log, the progress says "ETA ?" until the first pass has ended, then the estimate once
 * ("about N h; --spp or --time to shorten"), then a line every 10 s (not only per 10%,
 * which would leave the log silent for hours); SIGINT still ends it with the image. On a
 * terminal (script(1) gives it one) the bar shows "ETA ?" before the first pass too. */
#include <sys/stat.h>
#include <unistd.h>

#include "host_util.h"
#include "tt_test.h"

/* Runs COMMAND with stdout+stderr in `out`; returns the exit code. */
static int run(const char *command, char *out, size_t n) {
  FILE *p = popen(command, "r");
  if (!p) return -1;
  size_t len = 0, r;
  while (len + 1 < n && (r = fread(out + len, 1, n - 1 - len, p)) > 0) len += r;
  out[len] = 0;
  int status = pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/* The largest "elapsed Xs" of the "render:" progress lines (-1: none). */
static double last_elapsed(const char *out) {
  double best = -1;
  for (const char *p = out; (p = strstr(p, "\nrender: ")); p++) {
    const char *e = strstr(p, "elapsed "), *nl = strchr(p + 1, '\n');
    double s;
    if (e && (!nl || e < nl) && sscanf(e, "elapsed %lfs", &s) == 1 && s > best) best = s;
  }
  return best;
}

int main(void) {
  static char out[1 << 16];
  char cmd[6000], exr[4200];
  const char *scene = source_path("scenes/cornell-box/scene.json");
  char dir[] = "/tmp/tt_host_progressXXXXXX";
  if (!mkdtemp(dir)) return 1;
  snprintf(exr, sizeof exr, "%s/long.exr", dir);

  /* a log: SIGINT after 15 s. --foreground: without it GNU timeout sends the signal to the
   * host and then to its whole process group, so the host may see two SIGINTs, and a
   * second one aborts without an image by design (a race lost under load). */
  snprintf(cmd, sizeof cmd,
           "timeout --foreground --preserve-status -s INT 15 '%s' --threads 1 --spp "
           "16777216 --res 32x32 --out '%s' '%s' 2>&1",
           host_path(), exr, scene);
  CHECK(run(cmd, out, sizeof out) == 130);
  CHECK_CONTAINS(out, "\nrender:   0.0%  elapsed 0.0s  ETA ?\n");
  CHECK_CONTAINS(out, "info: render: about ");
  CHECK_CONTAINS(out, " h; --spp or --time to shorten\n");
  const char *said = strstr(out, "info: render: about ");
  CHECK(!said || !strstr(said + 1, "info: render: about ")); /* once */
  double last = last_elapsed(out);
  CHECK_MSG(last >= 10.0 && last < 15.0, "the last progress line is at %.1f s:\n%s", last, out);
  struct stat st;
  CHECK_MSG(stat(exr, &st) == 0 && st.st_size > 0, "no image after SIGINT:\n%s", out);

  /* a terminal: the bar says "ETA ?" before the first pass; a short render says no
   * estimate */
  snprintf(cmd, sizeof cmd,
           "script -qec \"'%s' --spp 16777216 --res 32x32 --time 1 --out "
           "'%s' '%s'\" /dev/null 2>&1",
           host_path(), exr, scene);
  CHECK(run(cmd, out, sizeof out) == 0);
  CHECK_CONTAINS(out, "\033[Krender [..............................]   0.0%  elapsed 0.0s  ETA ?");
  CHECK(!strstr(out, "about "));

  /* --quiet: no progress at all */
  snprintf(cmd, sizeof cmd, "--quiet --spp 4 --res 8x8 --out '%s' '%s'", exr, scene);
  CHECK(run_host(cmd, out, sizeof out) == 0);
  CHECK_MSG(!strstr(out, "render") && !strstr(out, "ETA"), "%s", out);

  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  CHECK(system(cmd) == 0);
  return tt_test_finish("host_progress");
}
