/* End to end: render the default Cornell box through the host and check the image:
 * finite and non-negative, directly visible light pixels show the emitted radiance,
 * mean in physically sensible bounds, bit-identical pixels for a fixed seed whatever the
 * thread count, the run record's keys, PNG written, and SIGINT writing a partial image (of a still
 * and of a sequence). */
#include <tunetrace/tunetrace.h>

#include <cjson/cJSON.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "host_util.h"
#include "tt_test.h"

extern char **environ;

/* Reads an EXR; returns pixel count or 0. */
static size_t read_exr(const char *path, float **px, uint32_t *w, uint32_t *h) {
  uint32_t c = 0;
  if (tt_image_read(path, w, h, &c, px) != TT_OK) {
    fprintf(stderr, "read %s: %s\n", path, tt_last_error());
    return 0;
  }
  return c == 3 ? (size_t)*w * *h : 0;
}

/* Starts the host with argv, sends SIGINT once `trigger` appears on its stderr, and returns
 * its wait status (-1 if the trigger never came). */
static int interrupt_at(char *const argv[], const char *trigger) {
  int fds[2];
  if (pipe(fds) != 0) return -1;
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, fds[1], 2);
  posix_spawn_file_actions_addclose(&fa, fds[0]);
  pid_t pid;
  int spawned = posix_spawn(&pid, argv[0], &fa, NULL, argv, environ) == 0;
  posix_spawn_file_actions_destroy(&fa);
  close(fds[1]);
  if (!spawned) {
    close(fds[0]);
    return -1;
  }
  static char log[8192];
  size_t got = 0;
  ssize_t r;
  log[0] = '\0';
  while (got + 1 < sizeof log && (r = read(fds[0], log + got, sizeof log - 1 - got)) > 0) {
    got += (size_t)r;
    log[got] = '\0';
    if (strstr(log, trigger)) break;
  }
  int seen = strstr(log, trigger) != NULL;
  if (!seen) fprintf(stderr, "no \"%s\" before EOF: %s\n", trigger, log);
  kill(pid, SIGINT);
  char sink[4096];
  while (read(fds[0], sink, sizeof sink) > 0) {}
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  return seen ? status : -1;
}

/* The spp an EXR records (its "spp" or "tunetrace:spp" attribute), -1 if it does not read
 * back whole with `pixels` pixels. */
static long exr_spp(const char *path, size_t pixels) {
  float *px = NULL;
  uint32_t w = 0, h = 0;
  size_t n = read_exr(path, &px, &w, &h);
  tt_free(px);
  if (n != pixels) return -1;
  char meta[64] = "";
  if (tt_image_read_meta(path, "spp", meta, sizeof meta) != TT_OK)
    tt_image_read_meta(path, "tunetrace:spp", meta, sizeof meta);
  return strtol(meta, NULL, 10);
}

/* A JSON file parsed (NULL if unreadable or not JSON). */
static cJSON *read_json_file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  static char text[1 << 16];
  size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = '\0';
  return cJSON_Parse(text);
}

int main(void) {
  static char out[1 << 16];
  char dir[] = "/tmp/tt_host_cornellXXXXXX";
  if (!mkdtemp(dir)) return 1;
  const char *scene_path = source_path("scenes/cornell-box/scene.json");
  char args[16384], a_exr[4200], b_exr[4200], c_exr[4200], stats[4200], png[4200];
  snprintf(a_exr, sizeof a_exr, "%s/a.exr", dir);
  snprintf(b_exr, sizeof b_exr, "%s/b.exr", dir);
  snprintf(c_exr, sizeof c_exr, "%s/c.exr", dir);
  snprintf(stats, sizeof stats, "%s/a.json", dir);
  snprintf(png, sizeof png, "%s/a.png", dir);

  snprintf(args, sizeof args,
           "--quiet --res 64x64 --spp 8 --seed 7 --threads 2 --out '%s' --stats '%s' '%s'", a_exr,
           stats, scene_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  snprintf(args, sizeof args, "--quiet --res 64x64 --spp 8 --seed 7 --threads 2 --out '%s' '%s'",
           b_exr, scene_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  snprintf(args, sizeof args, "--quiet --res 64x64 --spp 8 --seed 7 --threads 1 --out '%s' '%s'",
           c_exr, scene_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);

  float *a = NULL, *b = NULL, *c = NULL;
  uint32_t w = 0, h = 0;
  size_t n = read_exr(a_exr, &a, &w, &h);
  CHECK(n == 64 * 64);
  CHECK(read_exr(b_exr, &b, &w, &h) == n);
  CHECK(read_exr(c_exr, &c, &w, &h) == n);
  if (n && a && b && c) {
    CHECK_MSG(memcmp(a, b, n * 3 * sizeof(float)) == 0, "same seed and threads: pixels differ");
    CHECK_MSG(memcmp(a, c, n * 3 * sizeof(float)) == 0, "1 vs 2 threads: pixels differ");
    /* finite, non-negative, sensible mean; brightest pixels are the light itself */
    tt_scene *scene = NULL;
    CHECK(tt_scene_load(scene_path, &scene) == TT_OK);
    float le[3] = {0, 0, 0};
    for (uint32_t m = 0; scene && m < tt_scene_material_count(scene); m++) {
      const tt_material *mat = tt_scene_material(scene, m);
      if (mat->emission[0] + mat->emission[1] + mat->emission[2] > le[0] + le[1] + le[2])
        memcpy(le, mat->emission, sizeof le);
    }
    int bad = 0;
    double sum = 0, maxr = 0;
    size_t light_pixels = 0;
    for (size_t i = 0; i < n * 3; i++) {
      if (!isfinite(a[i]) || a[i] < 0) bad++;
      sum += a[i];
    }
    for (size_t i = 0; i < n; i++) {
      if (a[3 * i] > maxr) maxr = a[3 * i];
      /* a pixel on the light sees its emission plus the little light its own diffuse
       * albedo reflects back from the box below (a few percent) */
      if (a[3 * i] >= le[0] * (1 - 1e-5) && a[3 * i] <= 1.05 * le[0] &&
          a[3 * i + 1] >= le[1] * (1 - 1e-5) && a[3 * i + 1] <= 1.05 * le[1])
        light_pixels++;
    }
    double mean = sum / (n * 3);
    CHECK_MSG(bad == 0, "%d non-finite or negative values", bad);
    CHECK_MSG(mean > 0.05 && mean < 0.25 * (le[0] + le[1] + le[2]) / 3, "mean %g", mean);
    CHECK_MSG(light_pixels >= 4, "only %zu pixels see the emitted radiance", light_pixels);
    /* no pixel is much brighter than the light: nothing but the light emits */
    CHECK_MSG(maxr >= le[0] && maxr <= le[0] * 1.05, "max red %g vs emission %g", maxr, le[0]);
    tt_scene_destroy(scene);
  }
  tt_free(a);
  tt_free(b);
  tt_free(c);

  /* PNG written next to the EXR; EXR metadata carries spp and seed */
  struct stat st;
  CHECK(stat(png, &st) == 0 && st.st_size > 100);
  char meta[256];
  CHECK(tt_image_read_meta(a_exr, "spp", meta, sizeof meta) == TT_OK ||
        tt_image_read_meta(a_exr, "tunetrace:spp", meta, sizeof meta) == TT_OK);
  CHECK(strcmp(meta, "8") == 0);

  /* run record */
  FILE *f = fopen(stats, "r");
  CHECK(f != NULL);
  if (f) {
    static char text[1 << 16];
    size_t len = fread(text, 1, sizeof text - 1, f);
    text[len] = 0;
    fclose(f);
    cJSON *root = cJSON_Parse(text);
    CHECK(root != NULL);
    const char *keys[] = {"plugins", "params",     "build_ms",  "render_ms", "passes",  "spp",
                          "rays",    "rays_per_s", "triangles", "seed",      "threads", "metrics"};
    for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++)
      CHECK_MSG(cJSON_GetObjectItem(root, keys[k]) != NULL, "missing key %s", keys[k]);
    cJSON *accel = cJSON_GetObjectItem(cJSON_GetObjectItem(root, "plugins"), "accel");
    CHECK(accel &&
          !strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(accel, "name")), "accel_embree"));
    cJSON *ap = cJSON_GetObjectItem(cJSON_GetObjectItem(root, "params"), "accel_embree");
    CHECK(ap && cJSON_GetObjectItem(ap, "quality") && cJSON_GetObjectItem(ap, "robust"));
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(root, "spp")) == 8);
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(root, "seed")) == 7);
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(root, "rays")) >= 64 * 64 * 8);
    /* what a benchmark record needs (#17 defect 15): version and commit, when, the command
     * line, the CPU, its cores and the load */
    CHECK(!strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(root, "tunetrace")), tt_version()));
    const char *commit = cJSON_GetStringValue(cJSON_GetObjectItem(root, "tunetrace_commit"));
    CHECK_MSG(commit && !strcmp(commit, tt_build_commit()) && strlen(commit) >= 7, "commit %s",
              commit ? commit : "(none)");
    const char *stamp = cJSON_GetStringValue(cJSON_GetObjectItem(root, "timestamp"));
    int year = 0, mon = 0, day = 0, hh = -1, mm = -1, ss = -1;
    CHECK_MSG(stamp &&
                  sscanf(stamp, "%4d-%2d-%2dT%2d:%2d:%2d", &year, &mon, &day, &hh, &mm, &ss) == 6 &&
                  year >= 2024 && mon >= 1 && mon <= 12 && stamp[strlen(stamp) - 1] == 'Z',
              "timestamp %s", stamp ? stamp : "(none)");
    if (stamp) { /* the start of this very run: within a day of now */
      struct tm tm = {.tm_year = year - 1900,
                      .tm_mon = mon - 1,
                      .tm_mday = day,
                      .tm_hour = hh,
                      .tm_min = mm,
                      .tm_sec = ss};
      double age = difftime(time(NULL), timegm(&tm));
      CHECK_MSG(age >= -5 && age < 86400, "timestamp %s is %g s old", stamp, age);
    }
    cJSON *cmd = cJSON_GetObjectItem(root, "command_line");
    CHECK(cJSON_GetArraySize(cmd) == 15);
    CHECK(!strcmp(cJSON_GetStringValue(cJSON_GetArrayItem(cmd, 0)), host_path()));
    CHECK(!strcmp(cJSON_GetStringValue(cJSON_GetArrayItem(cmd, 14)), scene_path));
    CHECK(!strcmp(cJSON_GetStringValue(cJSON_GetArrayItem(cmd, 2)), "--res"));
    CHECK(!strcmp(cJSON_GetStringValue(cJSON_GetArrayItem(cmd, 3)), "64x64"));
    cJSON *m = cJSON_GetObjectItem(root, "machine");
    CHECK(!strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(m, "cpu")), tt_tunedb_cpu_model()));
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(m, "cores")) == sysconf(_SC_NPROCESSORS_ONLN));
    double avail = cJSON_GetNumberValue(cJSON_GetObjectItem(m, "cores_available"));
    CHECK(avail >= 1 && avail <= sysconf(_SC_NPROCESSORS_ONLN));
    CHECK(cJSON_GetArraySize(cJSON_GetObjectItem(m, "load_average")) == 3);
    cJSON_Delete(root);
  }

  /* SIGINT: the current pass finishes, the partial image is written, exit code 130 */
  char d_exr[4200];
  snprintf(d_exr, sizeof d_exr, "%s/d.exr", dir);
  char *argv[] = {(char *)host_path(), "--res", "64x64", "--spp", "1000000", "--out", d_exr,
                  (char *)scene_path,  NULL};
  /* the signal goes once the first pass is done (its "render:" progress line is out), not
   * after a fixed sleep: on a loaded machine the program may take seconds to start, and a
   * SIGINT before the handler is installed kills it */
  int status = interrupt_at(argv, "render:");
  CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 130, "status %d", status);
  long spp = exr_spp(d_exr, 64 * 64);
  CHECK_MSG(spp >= 1 && spp < 1000000, "interrupted render has %ld spp", spp);

  /* SIGINT before any pass is done (sent when the scene's summary line is out: the handlers
   * are installed, the accel is not built yet, and a 512x512 pass takes far longer than the
   * signal): exit 130 still comes with an image, one pass completed with the stop held back,
   * not "no pass completed: nothing to write" (#13, tools/crash_safety.py --part signal) */
  char e_exr[4200], e_stats[4200];
  snprintf(e_exr, sizeof e_exr, "%s/e.exr", dir);
  snprintf(e_stats, sizeof e_stats, "%s/e.json", dir);
  char *argv_e[] = {
      (char *)host_path(), "--res", "512x512",          "--spp", "1000000", "--out", e_exr,
      "--stats",           e_stats, (char *)scene_path, NULL};
  status = interrupt_at(argv_e, "triangles,");
  CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 130, "status %d", status);
  spp = exr_spp(e_exr, 512 * 512);
  CHECK_MSG(spp >= 1 && spp < 1000000,
            "render interrupted before its first pass: %ld spp "
            "in %s",
            spp, e_exr);
  cJSON *e_rec = read_json_file(e_stats);
  CHECK_MSG(e_rec && cJSON_IsTrue(cJSON_GetObjectItem(e_rec, "interrupted")) &&
                cJSON_GetNumberValue(cJSON_GetObjectItem(e_rec, "spp")) == spp,
            "the record of %s says interrupted with the image's spp", e_stats);
  cJSON_Delete(e_rec);

  /* (#13) a sequence: SIGINT once the first frame's progress line is out, and SIGINT while
   * frame 0 is set up (the "host: sequence" line): the frame being rendered finishes,
   * exit 130, and manifest.json lists every frame on disk, each whole, none "incomplete"
   * (the sequence mode had no handlers: SIGTERM killed it without its manifest) */
  const char *triggers[] = {"sequence:", "host: sequence"};
  for (int t = 0; t < 2; t++) {
    char pattern[4200], mpath[4200];
    snprintf(pattern, sizeof pattern, "%s/seq%d/f_%%04d.exr", dir, t);
    snprintf(mpath, sizeof mpath, "%s/seq%d/manifest.json", dir, t);
    char *argv_s[] = {(char *)host_path(),
                      "--res",
                      "96x96",
                      "--spp",
                      "4",
                      "--frames",
                      "0:100000",
                      "--out",
                      pattern,
                      (char *)scene_path,
                      NULL};
    status = interrupt_at(argv_s, triggers[t]);
    CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 130,
              "sequence, signal at \"%s\": status %d", triggers[t], status);
    cJSON *man = read_json_file(mpath);
    cJSON *frames = cJSON_GetObjectItem(man, "frames");
    int nf = cJSON_GetArraySize(frames);
    CHECK_MSG(cJSON_IsArray(frames) && nf >= 1 && nf < 100000, "%s lists %d frames", mpath, nf);
    for (int i = 0; i < nf; i++) {
      cJSON *fr = cJSON_GetArrayItem(frames, i);
      CHECK(cJSON_GetObjectItem(fr, "incomplete") == NULL);
      CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(fr, "index")) == i);
      char fpath[4300];
      snprintf(fpath, sizeof fpath, "%s/seq%d/%s", dir, t,
               cJSON_GetStringValue(cJSON_GetObjectItem(fr, "color")));
      float *px = NULL;
      uint32_t w = 0, h = 0;
      CHECK_MSG(read_exr(fpath, &px, &w, &h) == 96 * 96, "%s reads back whole", fpath);
      tt_free(px);
    }
    /* nothing on disk beyond what the manifest lists */
    char next[4300];
    snprintf(next, sizeof next, "%s/seq%d/f_%04d.exr", dir, t, nf);
    CHECK_MSG(access(next, F_OK) != 0, "%s exists but is not in the manifest", next);
    cJSON_Delete(man);
  }

  char cmd[4200];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) {}
  return tt_test_finish("host_cornell");
}
