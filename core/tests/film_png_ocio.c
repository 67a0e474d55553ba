/* PNG through the OCIO display transform: sRGB encoding values, exposure, clipping, the
 * $OCIO fallback and a user $OCIO config. The display transform is cached per process, so
 * the $OCIO cases run in re-executed children. */
#include <tunetrace/image.h>

#include <sys/wait.h>
#include <unistd.h>

#include "tt_test.h"

static char tmpdir[] = "/tmp/tt_film_png_XXXXXX";

/* The sRGB encoding function (IEC 61966-2-1), for expected values. */
static double srgb_oetf(double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

/* Reads an 8-bit RGB PNG back as integer codes 0..255 (OIIO gives code / 255). */
static int read_codes(const char *path, uint32_t w, uint32_t h, int *codes) {
  uint32_t rw, rh, rc;
  float *px = NULL;
  tt_status st = tt_image_read(path, &rw, &rh, &rc, &px);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (st != TT_OK) return 0;
  CHECK(rw == w && rh == h && rc == 3);
  int ok = rw == w && rh == h && rc == 3;
  if (ok)
    for (size_t i = 0; i < (size_t)w * h * 3; i++) codes[i] = (int)lrintf(px[i] * 255.0f);
  tt_free(px);
  return ok;
}

#define RAMP_W 64
#define RAMP_H 2

/* Ramp from 0 to 1.5 (so the top clips), plus pinned values: 0, 0.18, 1, 4, linear segment. */
static void make_ramp(float *rgb) {
  for (int y = 0; y < RAMP_H; y++)
    for (int x = 0; x < RAMP_W; x++)
      for (int c = 0; c < 3; c++)
        rgb[3 * (y * RAMP_W + x) + c] = 1.5f * (float)x / (RAMP_W - 1) * (c == 1 ? 0.5f : 1.0f);
  const float pinned[] = {0.0f, 0.18f, 1.0f, 4.0f, 0.002f, -0.5f, NAN, INFINITY};
  for (size_t i = 0; i < sizeof pinned / sizeof pinned[0]; i++)
    for (int c = 0; c < 3; c++) rgb[3 * (RAMP_W + i) + c] = pinned[i];
}

/* Expected code for an input: NaN and negatives encode as 0, +Inf clips to 255. */
static int expected_code(float v, float exposure) {
  if (isnan(v)) return 0;
  return (int)lround(255.0 * srgb_oetf((double)v * exp2(exposure)));
}

static void test_ramp(void) {
  float rgb[RAMP_W * RAMP_H * 3];
  make_ramp(rgb);
  char path[256];
  snprintf(path, sizeof path, "%s/ramp.png", tmpdir);
  tt_status st = tt_image_write_png_display(path, RAMP_W, RAMP_H, rgb, 0.0f, NULL, 0);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  int codes[RAMP_W * RAMP_H * 3];
  if (!read_codes(path, RAMP_W, RAMP_H, codes)) return;
  int bad = 0, differs_from_linear = 0;
  for (int i = 0; i < RAMP_W * RAMP_H * 3; i++) {
    int want = expected_code(rgb[i], 0.0f);
    if (abs(codes[i] - want) > 1) {
      if (bad++ < 5) fprintf(stderr, "  [%d] in %.6g: got %d want %d\n", i, rgb[i], codes[i], want);
    }
    float lin = isnan(rgb[i]) ? 0.0f : fminf(fmaxf(rgb[i], 0.0f), 1.0f);
    if (abs(codes[i] - (int)lrintf(lin * 255.0f)) > 10) differs_from_linear++;
  }
  CHECK_MSG(bad == 0, "%d codes off by more than 1", bad);
  /* the transform really ran: mid-tones are far from a plain linear quantisation */
  CHECK_MSG(differs_from_linear > RAMP_W, "only %d codes differ from linear*255",
            differs_from_linear);
  const int *pin = codes + 3 * RAMP_W;
  CHECK(pin[0] == 0);                                       /* 0 -> 0 */
  CHECK_MSG(abs(pin[3] - 118) <= 1, "0.18 -> %d", pin[3]);  /* 0.18 -> 118 */
  CHECK(pin[6] == 255);                                     /* 1 -> 255 */
  CHECK(pin[9] == 255);                                     /* 4 clips */
  CHECK_MSG(abs(pin[12] - 7) <= 1, "0.002 -> %d", pin[12]); /* linear segment: 12.92*0.002 */
  CHECK(pin[15] == 0);                                      /* negative -> 0 */
  CHECK(pin[18] == 0);                                      /* NaN -> 0 */
  CHECK(pin[21] == 255);                                    /* +Inf clips */
  /* the in-place transform gives the same values as the file */
  float copy[RAMP_W * RAMP_H * 3];
  memcpy(copy, rgb, sizeof copy);
  CHECK(tt_image_display_transform(copy, RAMP_W * RAMP_H, 0.0f) == TT_OK);
  int mismatch = 0, in_range = 1;
  for (int i = 0; i < RAMP_W * RAMP_H * 3; i++) {
    mismatch += (int)lrintf(copy[i] * 255.0f) != codes[i];
    in_range &= copy[i] >= 0.0f && copy[i] <= 1.0f;
  }
  CHECK(mismatch == 0);
  CHECK(in_range);
  unlink(path);
}

/* Exposure +1 on L is the same image as exposure 0 on 2L (doubling is exact in float). */
static void test_exposure(void) {
  float rgb[RAMP_W * RAMP_H * 3], doubled[RAMP_W * RAMP_H * 3];
  make_ramp(rgb);
  for (int i = 0; i < RAMP_W * RAMP_H * 3; i++) doubled[i] = 2.0f * rgb[i];
  char a[256], b[256];
  snprintf(a, sizeof a, "%s/exp1.png", tmpdir);
  snprintf(b, sizeof b, "%s/doubled.png", tmpdir);
  CHECK(tt_image_write_png_display(a, RAMP_W, RAMP_H, rgb, 1.0f, NULL, 0) == TT_OK);
  CHECK(tt_image_write_png_display(b, RAMP_W, RAMP_H, doubled, 0.0f, NULL, 0) == TT_OK);
  int ca[RAMP_W * RAMP_H * 3], cb[RAMP_W * RAMP_H * 3];
  if (read_codes(a, RAMP_W, RAMP_H, ca) && read_codes(b, RAMP_W, RAMP_H, cb)) {
    CHECK(memcmp(ca, cb, sizeof ca) == 0);
    int brighter = 0;
    for (int i = 0; i < RAMP_W * 3; i++) {
      CHECK(abs(ca[i] - expected_code(rgb[i], 1.0f)) <= 1);
      brighter += ca[i] > expected_code(rgb[i], 0.0f) + 5;
    }
    CHECK(brighter > RAMP_W / 2); /* exposure did something */
  }
  unlink(a);
  unlink(b);
}

/* PNG text chunks round trip; bad paths report the path. */
static void test_png_meta_and_errors(void) {
  char path[256];
  snprintf(path, sizeof path, "%s/meta.png", tmpdir);
  const float px[2 * 2 * 3] = {0.5f, 0.5f, 0.5f};
  const tt_image_meta meta[] = {{"spp", "64"}, {"Software", "tunetrace 0.1.0"}};
  CHECK(tt_image_write_png_display(path, 2, 2, px, 0.0f, meta, 2) == TT_OK);
  char value[128];
  tt_status st = tt_image_read_meta(path, "spp", value, sizeof value);
  CHECK_MSG(st == TT_OK && strcmp(value, "64") == 0, "spp: %s", tt_last_error());
  st = tt_image_read_meta(path, "Software", value, sizeof value);
  CHECK_MSG(st == TT_OK && strcmp(value, "tunetrace 0.1.0") == 0, "Software: %s", value);
  unlink(path);
  st = tt_image_write_png_display("/nonexistent_dir_tt/a.png", 2, 2, px, 0.0f, NULL, 0);
  CHECK(st == TT_ERR_IO);
  CHECK_CONTAINS(tt_last_error(), "/nonexistent_dir_tt/a.png");
}

/* Re-executes this test as `self --child <mode>` with $OCIO = `ocio` and stderr captured in
 * `log`; returns the child's exit status (0 = its checks passed). A fresh exec rather than
 * a bare fork: OCIO caches its config per process, and libraries with helper threads
 * (log4cplus, pulled in by OIIO) hang in their exit handlers in a forked child. */
static int run_child(const char *self, const char *mode, const char *ocio, const char *log) {
  fflush(stdout);
  fflush(stderr);
  pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    if (!freopen(log, "w", stderr)) _exit(3);
    setenv("OCIO", ocio, 1);
    execl(self, self, "--child", mode, (char *)NULL);
    _exit(4);
  }
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/* The text of a file, valid until the next call ("" on failure). */
static const char *slurp(const char *path) {
  static char *text;
  free(text);
  text = tt_test_read_file(path, NULL);
  return text ? text : "";
}

/* Child body: a bogus $OCIO falls back to the built-in sRGB transform. */
static void child_bogus(void) {
  const char *name = tt_image_display_name();
  CHECK_CONTAINS(name, "built-in sRGB");
  float v[3] = {0.18f, 0.18f, 0.18f};
  CHECK(tt_image_display_transform(v, 1, 0.0f) == TT_OK);
  CHECK_NEAR(v[0] * 255.0f, 255.0 * srgb_oetf(0.18), 0.5);
}

/* Child body: a user config (encoding x^(1/2)) is honoured, with its display and view. */
static void child_user_config(void) {
  const char *name = tt_image_display_name();
  CHECK_CONTAINS(name, "TestDisplay/Sqrt");
  float v[3] = {0.25f, 0.04f, 0.0f};
  CHECK(tt_image_display_transform(v, 1, 0.0f) == TT_OK);
  CHECK_NEAR(v[0], 0.5, 1e-3);
  CHECK_NEAR(v[1], 0.2, 1e-3);
  CHECK_NEAR(v[2], 0.0, 1e-6);
}

static void test_ocio_env(const char *self) {
  char log[256];
  snprintf(log, sizeof log, "%s/child.log", tmpdir);
  int rc = run_child(self, "bogus", "/nonexistent_dir_tt/config.ocio", log);
  const char *text = slurp(log);
  CHECK_MSG(rc == 0, "bogus-$OCIO child failed (%d):\n%s", rc, text);
  CHECK_CONTAINS(text, "warning");
  CHECK_CONTAINS(text, "/nonexistent_dir_tt/config.ocio");

  char cfg[256];
  snprintf(cfg, sizeof cfg, "%s/test.ocio", tmpdir);
  FILE *f = fopen(cfg, "w");
  CHECK(f != NULL);
  if (!f) return;
  fputs(
      "ocio_profile_version: 2\n"
      "roles:\n"
      "  default: lin\n"
      "  scene_linear: lin\n"
      "displays:\n"
      "  TestDisplay:\n"
      "    - !<View> {name: Sqrt, colorspace: sqrt}\n"
      "colorspaces:\n"
      "  - !<ColorSpace>\n"
      "    name: lin\n"
      "  - !<ColorSpace>\n"
      "    name: sqrt\n"
      "    from_scene_reference: !<ExponentTransform> {value: [2, 2, 2, 1], direction: inverse}\n",
      f);
  fclose(f);
  rc = run_child(self, "user", cfg, log);
  text = slurp(log);
  CHECK_MSG(rc == 0, "user-$OCIO child failed (%d):\n%s", rc, text);
  unlink(cfg);
  unlink(log);
}

int main(int argc, char **argv) {
  if (argc == 3 && strcmp(argv[1], "--child") == 0) {
    if (strcmp(argv[2], "bogus") == 0) child_bogus();
    else if (strcmp(argv[2], "user") == 0) child_user_config();
    else CHECK(!"unknown child mode");
    return tt_test_finish(argv[2]) ? 1 : 0;
  }
  if (!mkdtemp(tmpdir)) TEST_FAIL("cannot create a temporary folder in /tmp");
  /* /proc/self/exe: argv[0] may be relative to a directory meson changed away from */
  test_ocio_env("/proc/self/exe");
  unsetenv("OCIO"); /* the developer's own config must not change expected values */
  CHECK_CONTAINS(tt_image_display_name(), "built-in sRGB (sRGB/Standard)");
  test_ramp();
  test_exposure();
  test_png_meta_and_errors();
  rmdir(tmpdir);
  return tt_test_finish("film_png_ocio");
}
