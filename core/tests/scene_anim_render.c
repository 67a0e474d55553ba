/* A frame of an animated scene renders bit for bit the image of a still scene with every
 * object placed where the animation puts it at that frame's time (fixed seed): the scene
 * posed with tt_scene_set_time is written as a plain scene.json (tt_scene_write_json) and
 * rendered in a second session. Scene: scenes/animated-cornell (rigid keys with slerp and
 * cubic paths, a morph target, a moving area light whose area changes). */
#define _DEFAULT_SOURCE /* mkdtemp */
#include <tunetrace/tunetrace.h>

#include "tt_test.h"

#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

#define FPS 24.0

/* Renders `passes` 1-spp passes of `path` at time t (camera and meshes) into a new buffer;
 * `write_to` (if set) receives the posed scene as scene.json. */
static float *render_at(const char *path, double t, int pose, const char *write_to, uint32_t *w, uint32_t *h) {
  tt_session *s = NULL;
  float *rgb = NULL;
  if (tt_session_create(NULL, &s) != TT_OK || tt_session_load_scene(s, path) != TT_OK) {
    fprintf(stderr, "%s: %s\n", path, tt_last_error());
    tt_session_destroy(s);
    return NULL;
  }
  tt_scene *scene = tt_session_scene(s);
  CHECK(tt_scene_animated(scene) == pose);
  if (pose) CHECK_MSG(tt_scene_set_time(scene, t, t - 1.0 / FPS) == TT_OK, "%s", tt_last_error());
  CHECK(tt_session_set_camera_time(s, t, 1.0 / FPS) == TT_OK);
  if (write_to) CHECK_MSG(tt_scene_write_json(scene, write_to) == TT_OK, "%s", tt_last_error());
  if (tt_session_start(s, 0) == TT_OK) {
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

int main(void) {
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
    float *anim = render_at(scene, times[k], 1, still, &w, &h);
    float *ref = render_at(still, times[k], 0, NULL, &w2, &h2);
    CHECK(anim && ref && w == w2 && h == h2);
    if (anim && ref && w == w2 && h == h2) {
      n = (size_t)3 * w * h;
      size_t diff = 0;
      for (size_t i = 0; i < n; i++) diff += memcmp(&anim[i], &ref[i], sizeof(float)) != 0;
      CHECK_MSG(diff == 0, "t = %g: %zu of %zu values differ from the still scene placed at that time", times[k], diff, n);
    }
    if (k == 0) {
      first = anim;
      anim = NULL;
    } else if (first && anim) {
      /* the frames differ: the objects moved */
      size_t moved = 0;
      for (size_t i = 0; i < n; i++) moved += first[i] != anim[i];
      CHECK_MSG(moved > n / 20, "only %zu of %zu values changed between t = 0.35 and t = 1.3", moved, n);
    }
    free(anim);
    free(ref);
  }
  free(first);
  char cmd[4400];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmp);
  return tt_test_finish("scene_anim_render");
}
