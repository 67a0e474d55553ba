/* host --resume FILE: the tuning session (samples, counters, the tuner's save_state) is saved
 * after every sample and continued when FILE exists. With a timing-free objective (PSSMLT
 * towards its acceptance target, as tools/check_bit_identical uses) the trajectory is a
 * function of the seed: a run stopped after 6 iterations and resumed to 14 proposes exactly
 * what one uninterrupted 14-iteration run proposes, and a killed run resumed completes.
 * A state of another search is refused naming the file, which is left as it is. */
#include <tunetrace/tunetrace.h>

#include <cjson/cJSON.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "host_util.h"
#include "json_util.h"
#include "tt_test.h"

extern char **environ;

static char dir[] = "/tmp/tt_tune_resumeXXXXXX";
static char out[1 << 17];

/* The configurations of the stats file's tuning history, joined. */
static char *history(const char *stats) {
  cJSON *root = read_json(stats);
  cJSON *h = root ? cJSON_GetObjectItem(cJSON_GetObjectItem(root, "tuning"), "history") : NULL;
  size_t cap = 1 << 16, len = 0;
  char *buf = malloc(cap);
  buf[0] = 0;
  for (int i = 0; i < cJSON_GetArraySize(h); i++) {
    char *c = cJSON_PrintUnformatted(cJSON_GetObjectItem(cJSON_GetArrayItem(h, i), "config"));
    size_t n = strlen(c);
    if (len + n + 2 > cap) buf = realloc(buf, cap = 2 * cap + n);
    memcpy(buf + len, c, n);
    len += n;
    buf[len++] = '\n';
    buf[len] = 0;
    free(c);
  }
  cJSON_Delete(root);
  return buf;
}

int main(void) {
  if (!mkdtemp(dir)) return 1;
  const char *scene = source_path("scenes/cornell-box/scene.json");
  const char *common = "--quiet --plugin integrator_pssmlt --plugin tuner_nm --res 12x12 --spp 1 "
                       "--threads 1 --no-db --set integrator_pssmlt.bootstrapSamples=2000";
  char args[8192], full[512], part[512], state[512], img[512];
  snprintf(full, sizeof full, "%s/full.json", dir);
  snprintf(part, sizeof part, "%s/part.json", dir);
  snprintf(state, sizeof state, "%s/state.json", dir);
  snprintf(img, sizeof img, "%s/i.exr", dir);

  snprintf(args, sizeof args, "%s --iterations 14 --stats '%s' --out '%s' '%s'", common, full, img,
           scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  char *ref = history(full);
  CHECK(strlen(ref) > 0);

  snprintf(args, sizeof args, "%s --iterations 6 --resume '%s' --stats '%s' --out '%s' '%s'",
           common, state, part, img, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  struct stat st;
  CHECK(stat(state, &st) == 0 && st.st_size > 0);
  snprintf(args, sizeof args,
           "--quiet --plugin integrator_pssmlt --plugin tuner_nm --res 12x12 "
           "--spp 1 --threads 1 --no-db --set integrator_pssmlt.bootstrapSamples=2000 "
           "--iterations 14 --resume '%s' --stats '%s' --out '%s' '%s'",
           state, part, img, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  char *got = history(part);
  CHECK_MSG(!strcmp(ref, got), "resumed trajectory differs:\n%s\nvs\n%s", got, ref);
  cJSON *root = read_json(part);
  cJSON *t = root ? cJSON_GetObjectItem(root, "tuning") : NULL;
  CHECK(t && num(t, "iterations") == 14);
  cJSON_Delete(root);
  free(got);

  /* a run killed mid-way continues from its last sample and completes */
  char state2[512];
  snprintf(state2, sizeof state2, "%s/state2.json", dir);
  snprintf(args, sizeof args, "%s/full2.json", dir);
  char *argv[] = {(char *)host_path(),
                  "--quiet",
                  "--plugin",
                  "integrator_pssmlt",
                  "--plugin",
                  "tuner_nm",
                  "--res",
                  "12x12",
                  "--spp",
                  "1",
                  "--threads",
                  "1",
                  "--no-db",
                  "--set",
                  "integrator_pssmlt.bootstrapSamples=2000",
                  "--iterations",
                  "400",
                  "--resume",
                  state2,
                  "--out",
                  img,
                  (char *)scene,
                  NULL};
  pid_t pid;
  CHECK(posix_spawn(&pid, host_path(), NULL, NULL, argv, environ) == 0);
  for (int i = 0; i < 400 && stat(state2, &st) != 0; i++) {
    struct timespec ts = {0, 25000000};
    nanosleep(&ts, NULL);
  }
  struct timespec ts = {0, 300000000};
  nanosleep(&ts, NULL);
  kill(pid, SIGKILL);
  int status;
  waitpid(pid, &status, 0);
  CHECK(stat(state2, &st) == 0 && st.st_size > 0);
  char stats2[512];
  snprintf(stats2, sizeof stats2, "%s/resumed2.json", dir);
  snprintf(args, sizeof args, "%s --iterations 20 --resume '%s' --stats '%s' --out '%s' '%s'",
           common, state2, stats2, img, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  root = read_json(stats2);
  t = root ? cJSON_GetObjectItem(root, "tuning") : NULL;
  CHECK(t && num(t, "iterations") >= 20); /* the killed run may have done more than 20 */
  cJSON_Delete(root);

  /* another search's state: refused, exit 2, the file left as it is */
  snprintf(args, sizeof args,
           "%s --iterations 4 --objective metric:acceptance:max --resume '%s' "
           "--out '%s' '%s'",
           common, state, img, scene);
  long before = stat(state, &st) == 0 ? st.st_size : -1;
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, state);
  CHECK_CONTAINS(out, "objective");
  CHECK(stat(state, &st) == 0 && st.st_size == before);
  FILE *f = fopen(state, "w");
  fputs("{\"not\": \"a state\"}", f);
  fclose(f);
  snprintf(args, sizeof args, "%s --iterations 4 --resume '%s' --out '%s' '%s'", common, state, img,
           scene);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, "not a tuning session state");
  /* nothing after the saved state is read: text appended to it, or behind a NUL byte */
  size_t sn = 0;
  char *saved = tt_test_read_file(state2, &sn);
  CHECK(saved && sn > 0);
  for (int k = 0; saved && k < 2; k++) {
    f = fopen(state, "wb");
    fwrite(saved, 1, sn, f);
    fwrite(k ? "\0{}" : "\n{}", 1, 3, f);
    fclose(f);
    CHECK(run_host(args, out, sizeof out) == 2);
    CHECK_CONTAINS(out, state);
    CHECK_CONTAINS(out, k ? "a NUL byte at offset" : "unexpected text after the state");
  }
  free(saved);

  free(ref);
  snprintf(args, sizeof args, "rm -rf '%s'", dir);
  if (system(args)) {}
  return tt_test_finish("tune_resume");
}
