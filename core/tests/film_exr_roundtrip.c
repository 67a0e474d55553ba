/* EXR round trip: awkward floats survive bit-exactly, metadata survives, errors name files. */
#include <tunetrace/image.h>

#include <stdint.h>
#include <unistd.h>

#include "tt_test.h"
#include <tt_util/rng.h>

static char tmpdir[] = "/tmp/tt_film_exr_XXXXXX";

/* SplitMix64: deterministic test data without libc rand's platform differences. */
static uint64_t rng_state = 1;
static uint32_t next_u32(void) { return (uint32_t)(tt__splitmix64(&rng_state) >> 32); }

/* A float from random bits, re-rolled while NaN (NaN payloads need not survive a round
 * trip and are not something the film ever writes). Covers denormals, huge values,
 * negatives and -0. */
static float random_float(void) {
  for (;;) {
    uint32_t bits = next_u32();
    float f;
    memcpy(&f, &bits, sizeof f);
    if (!isnan(f)) return f;
  }
}

/* Writes and reads back one image; checks shape and that the bytes are identical. */
static void roundtrip(uint32_t w, uint32_t h, uint32_t c) {
  size_t n = (size_t)w * h * c;
  float *px = malloc(n * sizeof(float));
  for (size_t i = 0; i < n; i++) px[i] = random_float();
  /* make sure the interesting classes are there regardless of the generator */
  const float special[] = {1.0e-45f, -1.0e-40f, 1.17e-38f, 3.0e38f, -3.4e38f, -0.0f,
                           0.0f,     INFINITY,  -INFINITY, 0.18f,   1.0f};
  for (size_t i = 0; i < sizeof special / sizeof special[0] && i < n; i++) px[i] = special[i];
  char path[256];
  snprintf(path, sizeof path, "%s/img_%ux%ux%u.exr", tmpdir, w, h, c);
  tt_status st = tt_image_write_exr(path, w, h, c, px, NULL, NULL, 0);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  uint32_t rw = 0, rh = 0, rc = 0;
  float *back = NULL;
  st = tt_image_read(path, &rw, &rh, &rc, &back);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  CHECK(rw == w && rh == h && rc == c);
  if (back && rw == w && rh == h && rc == c) {
    int same = memcmp(px, back, n * sizeof(float)) == 0;
    CHECK_MSG(same, "%ux%ux%u not bit-exact", w, h, c);
    if (!same)
      for (size_t i = 0; i < n; i++)
        if (memcmp(&px[i], &back[i], sizeof(float))) {
          fprintf(stderr, "  first difference at %zu: %.9g vs %.9g\n", i, px[i], back[i]);
          break;
        }
  }
  tt_free(back);
  free(px);
  unlink(path);
}

/* Bare keys come back by name (stored as tunetrace:key), namespaced keys as given. */
static void metadata(void) {
  char path[256];
  snprintf(path, sizeof path, "%s/meta.exr", tmpdir);
  const float px[2 * 2 * 3] = {0};
  const tt_image_meta meta[] = {
      {"spp", "1024"},
      {"seed", "18446744073709551615"},
      {"plugins", "accel.embree@1.0, integrator.path@0.3, sampler.sobol@1.0"},
      {"studio:shot", "sq010_sh020"},
  };
  tt_status st = tt_image_write_exr(path, 2, 2, 3, px, NULL, meta, 4);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  char value[256];
  for (int i = 0; i < 4; i++) {
    st = tt_image_read_meta(path, meta[i].key, value, sizeof value);
    CHECK_MSG(st == TT_OK, "%s: %s", meta[i].key, tt_last_error());
    CHECK_MSG(strcmp(value, meta[i].value) == 0, "%s = '%s'", meta[i].key, value);
  }
  /* the prefix is how it is stored in the file */
  st = tt_image_read_meta(path, "tunetrace:spp", value, sizeof value);
  CHECK(st == TT_OK && strcmp(value, "1024") == 0);
  st = tt_image_read_meta(path, "no_such_key", value, sizeof value);
  CHECK(st == TT_ERR_NO_DATA);
  CHECK_CONTAINS(tt_last_error(), "no_such_key");
  st = tt_image_read_meta(path, "plugins", value, 8); /* too small: error, not truncation */
  CHECK(st == TT_ERR_INVALID_ARGUMENT);
  unlink(path);
}

/* Custom channel names are written; a 1-channel default is "Y" and reads back as 1 channel. */
static void channels_and_errors(void) {
  char path[256];
  snprintf(path, sizeof path, "%s/depth.exr", tmpdir);
  const float depth[3 * 2] = {1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.5f};
  const char *names[] = {"Z"};
  CHECK(tt_image_write_exr(path, 3, 2, 1, depth, names, NULL, 0) == TT_OK);
  uint32_t w, h, c;
  float *back = NULL;
  CHECK(tt_image_read(path, &w, &h, &c, &back) == TT_OK);
  CHECK(w == 3 && h == 2 && c == 1);
  CHECK(back && memcmp(back, depth, sizeof depth) == 0);
  tt_free(back);
  unlink(path);

  /* unwritable directory: TT_ERR_IO and the message names the path */
  tt_status st = tt_image_write_exr("/nonexistent_dir_tt/x.exr", 3, 2, 1, depth, NULL, NULL, 0);
  CHECK(st == TT_ERR_IO);
  CHECK_CONTAINS(tt_last_error(), "/nonexistent_dir_tt/x.exr");
  back = NULL;
  st = tt_image_read("/nonexistent_dir_tt/y.exr", &w, &h, &c, &back);
  CHECK(st == TT_ERR_IO && back == NULL);
  CHECK_CONTAINS(tt_last_error(), "/nonexistent_dir_tt/y.exr");
  CHECK(tt_image_write_exr(path, 0, 2, 1, depth, NULL, NULL, 0) == TT_ERR_INVALID_ARGUMENT);
}

int main(void) {
  if (!mkdtemp(tmpdir)) TEST_FAIL("cannot create a temporary folder in /tmp");
  roundtrip(7, 5, 3);
  roundtrip(7, 5, 4);
  roundtrip(1, 1, 3);
  roundtrip(33, 17, 4);
  metadata();
  channels_and_errors();
  rmdir(tmpdir);
  return tt_test_finish("film_exr_roundtrip");
}
