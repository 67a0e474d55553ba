/* A frame of an animated glTF renders bit for bit the image of a still scene with every
 * vertex placed where the animation puts it at that frame's time (fixed seed): the glTF
 * posed with tt_scene_set_time is written as a plain scene.json (tt_scene_write_json) and
 * rendered in a second session; a session started at time 0 and moved to the frame with
 * tt_session_set_time (accel_embree rebuilding or refitting the deformed mesh) renders the
 * same image. gltf_anim checks the posed vertices themselves against values computed by
 * hand. Files: simple_skin (skinning) and AnimatedMorphCube (morph targets) from
 * assimp-testmodels. */
#include <tunetrace/tunetrace.h>

#include "anim_frame.h"
#include "host_util.h"
#include "tt_test.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

#define MODELS "/usr/share/assimp/models/glTF2"

/* 4 1-spp passes of `path` at time t (anim_frame.h); `update` (accel_embree's updateMethod,
 * or NULL): the session starts at time 0 and is moved to t before it renders. */
static float *render_at(const char *path, double t, int animated, const char *write_to,
                        const char *update, uint32_t *w, uint32_t *h) {
  const char *const sets[] = {"updateMethod", update, NULL};
  anim_frame f = {.t = t, .animated = animated, .write_to = write_to, .sets = update ? sets : NULL};
  return anim_render_frame(path, &f, w, h);
}

static void check_file(const char *scene, const char *still, const double times[2]) {
  float *frames[2] = {NULL, NULL};
  size_t n = 0;
  for (int k = 0; k < 2; k++) {
    uint32_t w = 0, h = 0, w2 = 0, h2 = 0;
    float *anim = render_at(scene, times[k], 1, still, NULL, &w, &h);
    float *ref = render_at(still, times[k], 0, NULL, NULL, &w2, &h2);
    CHECK(anim && ref && w == w2 && h == h2);
    if (anim && ref && w == w2 && h == h2) {
      n = (size_t)3 * w * h;
      /* lit, and not one flat colour (the object is seen against the sky) */
      size_t lit = 0, other = 0;
      for (size_t i = 0; i < n; i++) {
        lit += anim[i] > 0.0f;
        other += fabsf(anim[i] - anim[0]) > 0.05f * anim[0];
      }
      CHECK_MSG(lit > n / 2 && other > n / 20, "%s: %zu of %zu values lit, %zu unlike the corner",
                scene, lit, n, other);
      size_t d = anim_values_differ(anim, ref, n);
      CHECK_MSG(d == 0, "%s t = %g: %zu of %zu values differ from the still scene placed there",
                scene, times[k], d, n);
      static const char *const updates[] = {"rebuild", "refit"};
      for (int u = 0; u < 2; u++) {
        uint32_t w3 = 0, h3 = 0;
        float *moved = render_at(scene, times[k], 1, NULL, updates[u], &w3, &h3);
        CHECK(moved && w3 == w && h3 == h);
        size_t md = moved && w3 == w && h3 == h ? anim_values_differ(moved, ref, n) : n;
        CHECK_MSG(md == 0, "%s t = %g, %s: %zu of %zu values differ from the still scene", scene,
                  times[k], updates[u], md, n);
        free(moved);
      }
    }
    frames[k] = anim;
    free(ref);
  }
  if (frames[0] && frames[1]) {
    size_t moved = anim_values_differ(frames[0], frames[1], n);
    CHECK_MSG(moved > n / 50, "%s: only %zu of %zu values changed between t = %g and %g", scene,
              moved, n, times[0], times[1]);
    printf("%s: frames at %g s and %g s differ in %zu of %zu values, each equal to its still\n",
           scene, times[0], times[1], moved, n);
  }
  free(frames[0]);
  free(frames[1]);
}

/* host renders the glTF as a sequence: one frame per 1/fps second of its animation, the
 * accel updated at every frame (the manifest's "update"). */
static void check_host_sequence(const char *tmp) {
  char args[1024], out[8192], path[600];
  snprintf(args, sizeof args, "--sequence 0:5 --spp 1 --out-dir '%s/seq' '%s'", tmp,
           MODELS "/simple_skin/simple_skin.gltf");
  int rc = run_host(args, out, sizeof out);
  CHECK_MSG(rc == 0, "host %s: exit %d: %s", args, rc, out);
  snprintf(path, sizeof path, "%s/seq/manifest.json", tmp);
  char *m = NULL;
  size_t len = 0;
  if (tt_file_read(path, "manifest", 0, &m, &len) != TT_OK) {
    CHECK_MSG(0, "no manifest: %s", tt_last_error());
    return;
  }
  unsigned updates = 0;
  for (const char *p = m; (p = strstr(p, "\"update_ms\"")); p++) updates++;
  CHECK_MSG(updates == 6, "6 frames with an accel update, got %u", updates);
  CHECK_CONTAINS(m, "\"time\": 0.208333"); /* frame 5 at 24 fps */
  tt_free(m);
}

int main(void) {
  char tmp[] = "/tmp/tt_gltf_anim_render_XXXXXX", still[4200];
  if (!mkdtemp(tmp)) TEST_FAIL("cannot create a temporary folder in /tmp");
  snprintf(still, sizeof still, "%s/still.json", tmp);
  const double skin_t[2] = {0.3, 2.7}, morph_t[2] = {0.9, 2.05};
  check_file(MODELS "/simple_skin/simple_skin.gltf", still, skin_t);
  check_file(MODELS "/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf", still,
             morph_t);
  (void)source_path;
  check_host_sequence(tmp);
  char cmd[4400];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmp);
  return tt_test_finish("gltf_anim_render");
}
