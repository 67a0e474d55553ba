/* Outputs are atomic and failures are reported (issue #13, defects 5, 6, 11): a write that
 * fails half-way (a file-size limit standing in for a full disk) leaves the previous EXR,
 * PNG and --stats byte for byte and exits 5; a PNG cut short by the disk is an error, not
 * "wrote X.png" with exit 0; a successful write replaces the file by rename (new inode, no
 * temporary left); an unwritable --stats is found before rendering, with the OS reason; a
 * tuning database on a full disk warns once and exits 5. */
#include <tunetrace/file.h>
#include <tunetrace/image.h>

#include "host_util.h"
#include "tt_test.h"

#include <dirent.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static char g_tmp[] = "/tmp/tt_host_outputs_XXXXXX";

/* Runs the host with argv, optionally under a file-size limit of `fsize` bytes (SIGXFSZ
 * ignored, so writes past it fail with EFBIG like a full disk's ENOSPC); returns the exit
 * code or 128+signal; stderr goes to `err`. */
static int run_limited(char *const argv[], long fsize, char *err, size_t n) {
  char log[256];
  snprintf(log, sizeof log, "%s/stderr.txt", g_tmp);
  fflush(NULL);
  pid_t pid = fork();
  if (pid == 0) {
    FILE *e = freopen(log, "w", stderr);
    (void)e;
    if (fsize > 0) {
      signal(SIGXFSZ, SIG_IGN);
      struct rlimit rl = {(rlim_t)fsize, (rlim_t)fsize};
      setrlimit(RLIMIT_FSIZE, &rl);
    }
    execv(host_path(), argv);
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  FILE *f = fopen(log, "rb");
  size_t got = f ? fread(err, 1, n - 1, f) : 0;
  err[got] = '\0';
  if (f) fclose(f);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/* The whole content of a file (malloc'ed), NULL if missing. */
static char *slurp(const char *path, size_t *n) {
  char *data = NULL;
  if (tt_file_read(path, NULL, 0, &data, n) != TT_OK) return NULL;
  return data;
}

/* Files in g_tmp whose name contains ".tmp-" (leftover temporaries). */
static int temporaries(void) {
  DIR *d = opendir(g_tmp);
  int count = 0;
  struct dirent *de;
  while (d && (de = readdir(d)))
    if (strstr(de->d_name, ".tmp-")) count++;
  if (d) closedir(d);
  return count;
}

static ino_t inode(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 ? st.st_ino : 0;
}

/* Host renders: a failure half-way keeps the old outputs; success replaces them. */
static void test_host(void) {
  char exr[256], png[256], stats[256], err[1 << 16];
  snprintf(exr, sizeof exr, "%s/box.exr", g_tmp);
  snprintf(png, sizeof png, "%s/box.png", g_tmp);
  snprintf(stats, sizeof stats, "%s/box.json", g_tmp);
  const char *scene = source_path("scenes/cornell-box/scene.json");
  char *good[] = {(char *)host_path(),
                  "--quiet",
                  "--spp",
                  "2",
                  "--res",
                  "96x96",
                  "--seed",
                  "1",
                  "--out",
                  exr,
                  "--stats",
                  stats,
                  (char *)scene,
                  NULL};
  CHECK(run_limited(good, 0, err, sizeof err) == 0);
  size_t n_exr, n_png, n_stats;
  char *old_exr = slurp(exr, &n_exr), *old_png = slurp(png, &n_png),
       *old_stats = slurp(stats, &n_stats);
  CHECK(old_exr && old_png && old_stats);
  CHECK(temporaries() == 0);
  ino_t ino = inode(exr);

  /* 1: every output is bigger than 1 KiB: all three writes fail half-way */
  char *more[] = {(char *)host_path(),
                  "--quiet",
                  "--spp",
                  "3",
                  "--res",
                  "96x96",
                  "--seed",
                  "7",
                  "--out",
                  exr,
                  "--stats",
                  stats,
                  (char *)scene,
                  NULL};
  CHECK(run_limited(more, 1024, err, sizeof err) == 5);
  CHECK_CONTAINS(err, exr);
  CHECK_CONTAINS(err, png);
  CHECK_CONTAINS(err, "File too large");
  CHECK_CONTAINS(err, "the previous file, if any, is unchanged");
  size_t n;
  char *now = slurp(exr, &n);
  CHECK_MSG(now && n == n_exr && !memcmp(now, old_exr, n), "the previous EXR was lost or changed");
  free(now);
  now = slurp(png, &n);
  CHECK_MSG(now && n == n_png && !memcmp(now, old_png, n), "the previous PNG was lost or changed");
  free(now);
  now = slurp(stats, &n);
  CHECK_MSG(now && n == n_stats && !memcmp(now, old_stats, n), "the previous stats were lost");
  free(now);
  CHECK(temporaries() == 0);

  /* 2: a limit between the PNG and the EXR sizes: the EXR fails, the PNG is written */
  long mid = (long)(n_png + (n_exr - n_png) / 2);
  CHECK(n_png < n_exr);
  CHECK(run_limited(more, mid, err, sizeof err) == 5);
  CHECK_CONTAINS(err, exr);
  now = slurp(exr, &n);
  CHECK(now && n == n_exr && !memcmp(now, old_exr, n));
  free(now);

  /* 3: success replaces by rename: a new inode, no temporaries */
  CHECK(run_limited(more, 0, err, sizeof err) == 0);
  CHECK(inode(exr) != ino);
  now = slurp(exr, &n);
  CHECK(now && (n != n_exr || memcmp(now, old_exr, n)));
  free(now);
  CHECK(temporaries() == 0);
  uint32_t w = 0, h = 0, c = 0;
  float *px = NULL;
  CHECK(tt_image_read(exr, &w, &h, &c, &px) == TT_OK && w == 96 && h == 96);
  tt_free(px);

  /* 4: an unwritable --stats fails before rendering, with the OS reason (exit 5). A missing
   * folder is created (#17 defect 4); one that cannot be, because a file is in the way, is
   * the unwritable case */
  char bad[300], in_the_way[300];
  snprintf(in_the_way, sizeof in_the_way, "%s/a_file", g_tmp);
  FILE *blocker = fopen(in_the_way, "w");
  CHECK(blocker && fclose(blocker) == 0);
  snprintf(bad, sizeof bad, "%s/a_file/dir/run.json", g_tmp);
  char *unwritable[] = {(char *)host_path(), "--spp", "1",           "--res", "8x8", "--out", exr,
                        "--stats",           bad,     (char *)scene, NULL};
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  CHECK(run_limited(unwritable, 0, err, sizeof err) == 5);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  CHECK_CONTAINS(err, bad);
  CHECK_CONTAINS(err, "Not a directory");
  CHECK_MSG(strstr(err, "render:") == NULL && strstr(err, "triangles") == NULL,
            "the scene was loaded or rendered before the check: %s", err);
  char args[512];
  snprintf(args, sizeof args, "--stats '' '%s'", scene);
  CHECK(run_host(args, err, sizeof err) == 2);
  CHECK_CONTAINS(err, "--stats: expected a file name, got an empty string");
  char *dir[] = {(char *)host_path(), "--stats", g_tmp, (char *)scene, NULL};
  CHECK(run_limited(dir, 0, err, sizeof err) == 5);
  CHECK_CONTAINS(err, "is a directory");
  free(old_exr);
  free(old_png);
  free(old_stats);
}

/* Occurrences of `needle` in `s`. */
static int count_of(const char *s, const char *needle) {
  int n = 0;
  for (const char *p = s; (p = strstr(p, needle)); p += strlen(needle)) n++;
  return n;
}

/* A tuning run whose database fills the disk half-way: one warning with the reason (not
 * one per measurement), an error with the count, the image still written, exit 5 (was 0). */
static void test_db_full(void) {
  char db[256], exr[256], err[1 << 16];
  snprintf(db, sizeof db, "%s/full.db", g_tmp);
  snprintf(exr, sizeof exr, "%s/tuned.exr", g_tmp);
  char *argv[] = {(char *)host_path(),
                  "--plugin",
                  "tuner_nm",
                  "--iterations",
                  "30",
                  "--spp",
                  "1",
                  "--res",
                  "8x8",
                  "--db",
                  db,
                  "--out",
                  exr,
                  (char *)source_path("scenes/cornell-box/scene.json"),
                  NULL};
  /* 48 KiB: the schema and a few rows fit, the WAL of 30 commits does not; the 8x8 image
   * does */
  CHECK(run_limited(argv, 48 * 1024, err, sizeof err) == 5);
  CHECK_MSG(count_of(err, "recording a measurement") == 1, "%d warnings: %s",
            count_of(err, "recording a measurement"), err);
  CHECK_CONTAINS(err, "later failures are counted, not repeated");
  CHECK_CONTAINS(err, "measurements could not be recorded in the database");
  CHECK_CONTAINS(err, db);
  CHECK_CONTAINS(err, "host: wrote");
  uint32_t w = 0, h = 0, c = 0;
  float *px = NULL;
  CHECK(tt_image_read(exr, &w, &h, &c, &px) == TT_OK && w == 8 && h == 8);
  tt_free(px);
}

/* PSSMLT on a valid scene with no light writes a black image and exits 0, as PT does (it
 * exited 1 with no image). */
static void test_black_pssmlt(void) {
  char scene[256], exr[256], err[1 << 16];
  snprintf(scene, sizeof scene, "%s/black.json", g_tmp);
  snprintf(exr, sizeof exr, "%s/black.exr", g_tmp);
  static const char json[] =
      "{\"version\": 1, \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0], "
      "\"resolution\": [16, 16]}, \"materials\": {\"w\": {\"albedo\": [0.5, 0.5, 0.5]}}, "
      "\"meshes\": [{\"material\": \"w\", \"positions\": [-1,-1,0, 1,-1,0, 1,1,0]}]}";
  CHECK(tt_file_write_atomic(scene, json, sizeof json - 1) == TT_OK);
  const char *integrators[2] = {"integrator_pt", "integrator_pssmlt"};
  for (int i = 0; i < 2; i++) {
    char *argv[] = {(char *)host_path(),
                    "--plugin",
                    (char *)integrators[i],
                    "--spp",
                    "2",
                    "--out",
                    exr,
                    scene,
                    NULL};
    int rc = run_limited(argv, 0, err, sizeof err);
    CHECK_MSG(rc == 0, "%s: exit %d: %s", integrators[i], rc, err);
    uint32_t w = 0, h = 0, c = 0;
    float *px = NULL;
    CHECK(tt_image_read(exr, &w, &h, &c, &px) == TT_OK && w == 16 && h == 16);
    int nz = 0;
    for (size_t k = 0; px && k < (size_t)w * h * c; k++) nz += !(px[k] == 0.0f);
    CHECK_MSG(nz == 0, "%s: %d non-black values", integrators[i], nz);
    tt_free(px);
    unlink(exr);
  }
  CHECK_CONTAINS(err, "the image is black");
}

/* The library's PNG writer under a full disk: an error naming the file (OIIO's PNG writer
 * ignores the failed fwrite, so this returned TT_OK with a truncated file before). */
static void test_png_full(void) {
  char path[256];
  snprintf(path, sizeof path, "%s/noise.png", g_tmp);
  enum { W = 256, H = 256 };
  static float rgb[W * H * 3];
  uint32_t s = 12345;
  for (size_t i = 0; i < sizeof rgb / sizeof rgb[0]; i++) {
    s = s * 1664525u + 1013904223u;
    rgb[i] = (float)(s >> 8) / 16777216.0f; /* noise: the PNG stays large */
  }
  fflush(NULL);
  pid_t pid = fork();
  if (pid == 0) {
    signal(SIGXFSZ, SIG_IGN);
    struct rlimit rl = {4096, 4096};
    setrlimit(RLIMIT_FSIZE, &rl);
    tt_status st = tt_image_write_png_display(path, W, H, rgb, 0.0f, NULL, 0);
    _exit(st == TT_ERR_IO && strstr(tt_last_error(), path) &&
                  strstr(tt_last_error(), "File too large")
              ? 0
              : 1);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 0,
            "a PNG write past the file-size limit was not reported");
  struct stat st;
  CHECK_MSG(stat(path, &st) != 0, "a truncated PNG was left at %s", path);
  CHECK(temporaries() == 0);
  /* and without the limit it is written and reads back */
  CHECK(tt_image_write_png_display(path, W, H, rgb, 0.0f, NULL, 0) == TT_OK);
  uint32_t w, h, c;
  float *px = NULL;
  CHECK(tt_image_read(path, &w, &h, &c, &px) == TT_OK && w == W && h == H);
  tt_free(px);
}

/* The shared helpers themselves: non-regular files refused at once, atomic replacement. */
static void test_helpers(void) {
  char *data = NULL;
  size_t n = 0;
  CHECK(tt_file_read("/dev/zero", "test file", 0, &data, &n) == TT_ERR_IO && !data);
  CHECK_CONTAINS(tt_last_error(), "/dev/zero: cannot open test file: a character device");
  CHECK(tt_file_read(g_tmp, NULL, 0, &data, &n) == TT_ERR_IO);
  CHECK_CONTAINS(tt_last_error(), "a directory");
  char fifo[256], path[256];
  snprintf(fifo, sizeof fifo, "%s/fifo", g_tmp);
  CHECK(mkfifo(fifo, 0644) == 0);
  alarm(20); /* a blocking open would hang here */
  CHECK(tt_file_read(fifo, NULL, 0, &data, &n) == TT_ERR_IO);
  CHECK_CONTAINS(tt_last_error(), "a FIFO");
  alarm(0);
  unlink(fifo);
  snprintf(path, sizeof path, "%s/limited.txt", g_tmp);
  CHECK(tt_file_write_atomic(path, "0123456789", 10) == TT_OK);
  CHECK(tt_file_read(path, NULL, 9, &data, &n) == TT_ERR_IO);
  CHECK_CONTAINS(tt_last_error(), "more than the 9-byte limit");
  CHECK(tt_file_read(path, NULL, 10, &data, &n) == TT_OK && n == 10 && !strcmp(data, "0123456789"));
  tt_free(data);
  /* permissions of the replaced file are kept */
  CHECK(chmod(path, 0640) == 0);
  CHECK(tt_file_write_atomic(path, "abc", 3) == TT_OK);
  struct stat st;
  CHECK(stat(path, &st) == 0 && (st.st_mode & 0777) == 0640 && st.st_size == 3);
  /* an aborted write leaves the old content and no temporary */
  tt_atomic_file *f;
  CHECK(tt_atomic_file_open(path, &f) == TT_OK);
  fputs("partial", tt_atomic_file_stream(f));
  tt_atomic_file_abort(f);
  CHECK(tt_file_read(path, NULL, 0, &data, &n) == TT_OK && n == 3 && !strcmp(data, "abc"));
  tt_free(data);
  CHECK(temporaries() == 0);
  /* /dev/null is written into, not replaced */
  CHECK(tt_file_write_atomic("/dev/null", "x", 1) == TT_OK);
  CHECK(stat("/dev/null", &st) == 0 && S_ISCHR(st.st_mode));
  unlink(path);
}

/* Width and height from a PNG's IHDR (0 if the file is not a PNG). */
static void png_size(const char *path, uint32_t *w, uint32_t *h) {
  size_t n = 0;
  unsigned char *d = (unsigned char *)slurp(path, &n);
  *w = *h = 0;
  if (d && n >= 24 && !memcmp(d, "\x89PNG\r\n\x1a\n", 8) && !memcmp(d + 12, "IHDR", 4)) {
    *w = (uint32_t)d[16] << 24 | (uint32_t)d[17] << 16 | (uint32_t)d[18] << 8 | d[19];
    *h = (uint32_t)d[20] << 24 | (uint32_t)d[21] << 16 | (uint32_t)d[22] << 8 | d[23];
  }
  free(d);
}

/* #17 defect 16: --png writes a PNG preview of every sequence frame (the frame the pattern
 * names), listed in the manifest; without it a sequence writes EXR only, as before. */
static void test_sequence_png(void) {
  char pattern[256], err[1 << 16], path[300];
  snprintf(pattern, sizeof pattern, "%s/seq/f_%%04d.exr", g_tmp);
  char *argv[] = {(char *)host_path(),
                  "--quiet",
                  "--res",
                  "12x8",
                  "--spp",
                  "1",
                  "--frames",
                  "2:4",
                  "--png",
                  "--out",
                  pattern,
                  (char *)source_path("scenes/cornell-box/path.json"),
                  NULL};
  int rc = run_limited(argv, 0, err, sizeof err);
  CHECK_MSG(rc == 0, "exit %d: %s", rc, err);
  for (int f = 2; f <= 4; f++) {
    uint32_t w, h;
    snprintf(path, sizeof path, "%s/seq/f_%04d.png", g_tmp, f);
    png_size(path, &w, &h);
    CHECK_MSG(w == 12 && h == 8, "%s: %ux%u", path, w, h);
  }
  snprintf(path, sizeof path, "%s/seq/f_0005.png", g_tmp);
  CHECK(access(path, F_OK) != 0); /* frames 2..4 inclusive */
  snprintf(path, sizeof path, "%s/seq/manifest.json", g_tmp);
  char *m = slurp(path, &(size_t){0});
  CHECK_CONTAINS(m, "\"png\": \"f_0003.png\"");
  free(m);
  /* no --png: no previews */
  snprintf(pattern, sizeof pattern, "%s/seq2/f_%%04d.exr", g_tmp);
  argv[8] = "--quiet";
  rc = run_limited(argv, 0, err, sizeof err);
  CHECK_MSG(rc == 0, "exit %d: %s", rc, err);
  snprintf(path, sizeof path, "%s/seq2/f_0003.exr", g_tmp);
  CHECK(access(path, F_OK) == 0);
  snprintf(path, sizeof path, "%s/seq2/f_0003.png", g_tmp);
  CHECK(access(path, F_OK) != 0);
}

int main(void) {
  if (!mkdtemp(g_tmp)) return 1;
  test_helpers();
  test_png_full();
  test_host();
  test_db_full();
  test_black_pssmlt();
  test_sequence_png();
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_tmp);
  if (system(cmd) != 0) fprintf(stderr, "cannot remove %s\n", g_tmp);
  return tt_test_finish("host_outputs");
}
