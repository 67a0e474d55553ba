/* A frame of an animated scene renders bit for bit the image of a still scene with every
 * object placed where the animation puts it at that frame's time (fixed seed): the scene
 * posed with tt_scene_set_time is written as a plain scene.json (tt_scene_write_json) and
 * rendered in a second session. The same frame rendered by a session that started at time
 * 0 and was moved there with tt_session_set_time (the accel updated by accel_embree's
 * rebuild, or refitted by its native or custom backend; the integrator made again for the
 * moved light) is the same image bit for bit too, and so is the frame of an accel plugin of
 * ABI 1.1 (no update: the session builds it again; argv[1], tests/fixtures). With
 * updateMethod=instances (rigid meshes intersected in object space) the image is the same up
 * to rounding: relative RMSE <= 1e-6, no value off by more than 1e-4. Scene: scenes/animated-cornell (rigid
 * keys with slerp and cubic paths, a morph target, a moving area light whose area
 * changes). */
#include <tunetrace/tunetrace.h>

#include "anim_frame.h"
#include "tt_test.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

#define FPS ANIM_FRAME_FPS

/* 4 1-spp passes of `path` at time t (anim_frame.h); `sets`: accel_embree settings the
 * session starts with at time 0 before it moves to t, or NULL: posed before it starts. */
static float *render_at(const char *path, double t, int pose, const char *write_to,
                        const char *const *sets, uint32_t *w, uint32_t *h) {
  anim_frame f = {.t = t, .animated = pose, .write_to = write_to, .sets = sets};
  return anim_render_frame(path, &f, w, h);
}

/* The frame at t with the ABI 1.1 fixture accel `plugin`: posed before the session starts
 * (move = 0), or started at time 0 and moved with tt_session_set_time (move = 1). */
static float *render_fixture(const char *path, const char *plugin, double t, int move, uint32_t *w,
                             uint32_t *h) {
  tt_session *s = NULL;
  float *rgb = NULL;
  if (tt_session_create(NULL, &s) != TT_OK || tt_session_load_scene(s, path) != TT_OK ||
      tt_session_load_plugin(s, plugin, NULL) != TT_OK) {
    fprintf(stderr, "%s, %s: %s\n", path, plugin, tt_last_error());
    tt_session_destroy(s);
    return NULL;
  }
  CHECK(tt_session_set_time(s, move ? 0.0 : t, 1.0 / FPS, NULL) == TT_OK);
  if (tt_session_start(s, 0) == TT_OK) {
    CHECK(!strcmp(tt_loaded_plugin_entry(tt_session_accel_plugin(s))->name, "fixture_accel_abi11"));
    if (move) {
      tt_accel_update_stats us = {.struct_size = sizeof us};
      CHECK_MSG(tt_session_set_time(s, t, 1.0 / FPS, &us) == TT_OK, "%s", tt_last_error());
      CHECK_MSG(us.rebuilt == 1, "an ABI 1.1 accel is built again (rebuilt %d)", us.rebuilt);
    }
    for (int i = 0; i < 4; i++) CHECK(tt_session_render_pass(s, 1, NULL) == TT_OK);
    tt_film *film = tt_session_film(s);
    *w = tt_film_width(film);
    *h = tt_film_height(film);
    rgb = malloc(sizeof(float) * 3 * *w * *h);
    if (rgb) tt_film_resolve(film, rgb);
  } else {
    fprintf(stderr, "start: %s\n", tt_last_error());
  }
  tt_session_destroy(s);
  return rgb;
}

int main(int argc, char **argv) {
  const char *root = getenv("TT_SOURCE_ROOT");
  char scene[4096], tmp[] = "/tmp/tt_scene_anim_render_XXXXXX", still[4200];
  snprintf(scene, sizeof scene, "%s/scenes/animated-cornell/scene.json", root ? root : "..");
  if (!mkdtemp(tmp)) TEST_FAIL("cannot create a temporary folder in /tmp");
  snprintf(still, sizeof still, "%s/still.json", tmp);
  const double times[] = {0.35, 1.3};
  float *first = NULL;
  size_t n = 0;
  for (int k = 0; k < 2; k++) {
    uint32_t w = 0, h = 0, w2 = 0, h2 = 0;
    float *anim = render_at(scene, times[k], 1, still, NULL, &w, &h);
    float *ref = render_at(still, times[k], 0, NULL, NULL, &w2, &h2);
    CHECK(anim && ref && w == w2 && h == h2);
    if (anim && ref && w == w2 && h == h2) {
      n = (size_t)3 * w * h;
      size_t diff = anim_values_differ(anim, ref, n);
      CHECK_MSG(diff == 0,
                "t = %g: %zu of %zu values differ from the still scene placed at that time",
                times[k], diff, n);
      /* a session moved to the frame: the accel rebuilt or refitted, the same image */
      static const char *const updates[][5] = {
          {"updateMethod", "rebuild", NULL},
          {"updateMethod", "refit", NULL},
          {"updateMethod", "refit", "backend", "custom", NULL}};
      static const char *const custom[] = {"updateMethod", "rebuild", "backend", "custom", NULL};
      uint32_t w4 = 0, h4 = 0;
      float *ref_custom =
          render_at(still, times[k], 0, NULL, custom, &w4, &h4); /* its own traversal */
      CHECK(ref_custom && w4 == w && h4 == h);
      for (size_t u = 0; u < 3 && ref_custom; u++) {
        uint32_t w3 = 0, h3 = 0;
        float *moved = render_at(scene, times[k], 1, NULL, updates[u], &w3, &h3);
        CHECK(moved && w3 == w && h3 == h);
        const float *r = updates[u][2] ? ref_custom : ref;
        size_t mdiff = moved && w3 == w && h3 == h ? anim_values_differ(moved, r, n) : n;
        CHECK_MSG(moved && mdiff == 0,
                  "t = %g, %s %s: %zu of %zu values differ from the still scene", times[k],
                  updates[u][1], updates[u][2] ? "custom" : "native", mdiff, n);
        free(moved);
      }
      /* updateMethod=instances intersects a rigid mesh's triangles in its object space: the
       * same image up to rounding (a few ulps in a few percent of the values), not bit for
       * bit */
      static const char *const inst[] = {"updateMethod", "instances", NULL};
      uint32_t w5 = 0, h5 = 0;
      float *moved = render_at(scene, times[k], 1, NULL, inst, &w5, &h5);
      CHECK(moved && w5 == w && h5 == h);
      double err2 = 0, ref2 = 0, maxd = 0;
      size_t idiff = 0;
      for (size_t i = 0; moved && w5 == w && h5 == h && i < n; i++) {
        double d = fabs((double)moved[i] - ref[i]);
        err2 += d * d;
        ref2 += (double)ref[i] * ref[i];
        maxd = d > maxd ? d : maxd;
        idiff += d > 0;
      }
      fprintf(stderr,
              "t = %g, instances: %zu of %zu values differ, by at most %.3g; relative RMSE %.3g\n",
              times[k], idiff, n, maxd, sqrt(err2 / (ref2 > 0 ? ref2 : 1)));
      CHECK_MSG(moved && ref2 > 0 && sqrt(err2 / ref2) <= 1e-6 && maxd <= 1e-4 && idiff <= n / 4,
                "t = %g, instances: %zu of %zu values differ, by at most %g (relative RMSE %g)",
                times[k], idiff, n, maxd, sqrt(err2 / (ref2 > 0 ? ref2 : 1)));
      free(moved);
      free(ref_custom);
    }
    if (k == 0) {
      first = anim;
      anim = NULL;
    } else if (first && anim) {
      /* the frames differ: the objects moved */
      size_t moved = 0;
      for (size_t i = 0; i < n; i++) moved += first[i] != anim[i];
      CHECK_MSG(moved > n / 20, "only %zu of %zu values changed between t = 0.35 and t = 1.3",
                moved, n);
    }
    free(anim);
    free(ref);
  }
  free(first);
  if (argc > 1) { /* the ABI 1.1 fixture accel */
    uint32_t w = 0, h = 0, w2 = 0, h2 = 0;
    float *posed = render_fixture(scene, argv[1], 1.3, 0, &w, &h);
    float *moved = render_fixture(scene, argv[1], 1.3, 1, &w2, &h2);
    CHECK(posed && moved && w == w2 && h == h2);
    size_t diff = 0, lit = 0;
    for (size_t i = 0; posed && moved && w == w2 && h == h2 && i < (size_t)3 * w * h; i++) {
      diff += memcmp(&posed[i], &moved[i], sizeof(float)) != 0;
      lit += posed[i] > 0.0f;
    }
    CHECK_MSG(diff == 0 && lit > 0,
              "ABI 1.1 accel: %zu values differ between the moved and the posed session (%zu lit)",
              diff, lit);
    free(posed);
    free(moved);
  } else {
    CHECK_MSG(0, "usage: scene_anim_render FIXTURE_ACCEL.so (tests/fixtures)");
  }
  char cmd[4400];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmp);
  return tt_test_finish("scene_anim_render");
}
