/* Tests of animated scenes: one frame rendered at a time t, the way the frame-equality tests
 * (scene_anim_render, scene_stress_render, gltf_anim_render) all need it: either posed
 * before the session starts (tt_scene_set_time, the camera at t), or started at time 0 with
 * accel_embree settings and moved to t by tt_session_set_time (the accel updated as the
 * settings say). Fixed seed: the same frame renders the same values. */
#ifndef TT_TESTS_ANIM_FRAME_H
#define TT_TESTS_ANIM_FRAME_H

#include <tunetrace/tunetrace.h>

#include "tt_test.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define ANIM_FRAME_FPS 24.0

typedef struct anim_frame {
  double t;
  int animated;            /* what tt_scene_animated must say; animated scenes are posed at t */
  const char *write_to;    /* receives the posed scene as scene.json (or NULL) */
  const char *const *sets; /* accel_embree key, value pairs, NULL-terminated: the session
                               starts at time 0 with them and moves to t (or NULL) */
  int passes;              /* 1-spp passes (0: 4) */
  uint32_t width, height;  /* the film (0: the scene's) */
} anim_frame;

/* Whether the accel rebuilds when moved with these settings: every updateMethod but refit and
 * instances (which refit, or rebuild only the top level) does. */
static inline int anim_frame_rebuilds(const char *const *sets) {
  for (size_t i = 0; sets[i]; i += 2)
    if (!strcmp(sets[i], "updateMethod"))
      return strcmp(sets[i + 1], "refit") != 0 && strcmp(sets[i + 1], "instances") != 0;
  return 1;
}

/* The frame of `path` that `f` describes, a new width x height RGB buffer (NULL on failure,
 * which is reported). */
static inline float *anim_render_frame(const char *path, const anim_frame *f, uint32_t *w,
                                       uint32_t *h) {
  tt_session *s = NULL;
  float *rgb = NULL;
  if (tt_session_create(NULL, &s) != TT_OK || tt_session_load_scene(s, path) != TT_OK) {
    fprintf(stderr, "%s: %s\n", path, tt_last_error());
    tt_session_destroy(s);
    return NULL;
  }
  tt_scene *scene = tt_session_scene(s);
  CHECK_MSG(tt_scene_animated(scene) == f->animated, "%s: animated %d", path,
            tt_scene_animated(scene));
  if (f->width) CHECK(tt_scene_set_resolution(scene, f->width, f->height) == TT_OK);
  if (f->sets) {
    CHECK(tt_session_load_defaults(s) == TT_OK);
    for (size_t i = 0; f->sets[i]; i += 2)
      CHECK_MSG(tt_session_set(s, "accel_embree", f->sets[i], f->sets[i + 1]) == TT_OK, "%s",
                tt_last_error());
    CHECK(tt_session_set_time(s, 0.0, 1.0 / ANIM_FRAME_FPS, NULL) == TT_OK);
    CHECK(tt_session_start(s, 0) == TT_OK);
    tt_accel_update_stats us = {.struct_size = sizeof us};
    CHECK_MSG(tt_session_set_time(s, f->t, 1.0 / ANIM_FRAME_FPS, &us) == TT_OK, "%s",
              tt_last_error());
    if (f->animated)
      CHECK_MSG(us.rebuilt == anim_frame_rebuilds(f->sets), "%s: moved to t = %g: rebuilt %d", path,
                f->t, us.rebuilt);
  } else {
    if (f->animated)
      CHECK_MSG(tt_scene_set_time(scene, f->t, f->t - 1.0 / ANIM_FRAME_FPS) == TT_OK, "%s",
                tt_last_error());
    CHECK(tt_session_set_camera_time(s, f->t, 1.0 / ANIM_FRAME_FPS) == TT_OK);
  }
  if (f->write_to)
    CHECK_MSG(tt_scene_write_json(scene, f->write_to) == TT_OK, "%s", tt_last_error());
  if (tt_session_started(s) || tt_session_start(s, 0) == TT_OK) {
    for (int i = 0; i < (f->passes ? f->passes : 4); i++)
      CHECK(tt_session_render_pass(s, 1, NULL) == TT_OK);
    tt_film *film = tt_session_film(s);
    *w = tt_film_width(film);
    *h = tt_film_height(film);
    rgb = malloc(sizeof(float) * 3 * *w * *h);
    if (rgb) tt_film_resolve(film, rgb);
  } else {
    fprintf(stderr, "%s: start: %s\n", path, tt_last_error());
  }
  tt_session_destroy(s);
  return rgb;
}

/* How many of the n values of a and b differ in any bit. */
static inline size_t anim_values_differ(const float *a, const float *b, size_t n) {
  size_t d = 0;
  for (size_t i = 0; i < n; i++) d += memcmp(&a[i], &b[i], sizeof(float)) != 0;
  return d;
}

#endif /* TT_TESTS_ANIM_FRAME_H */
