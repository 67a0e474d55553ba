/* The animated stress cases render, frame by frame, bit for bit the image of a still scene
 * with every object placed where the animation puts it at that frame's time (fixed seed):
 * the posed scene is written as a plain scene.json (tt_scene_write_json) and rendered in a
 * second session. Scenes: scenes/animated-stress (64 rigid bodies and a morphing cloth),
 * the Cornell box with the "stress" cylinder option, and a pbrt file with ActiveTransform /
 * TransformTimes (written by the test). The frames at two times differ (things moved), so
 * the equality is not that of two unchanged images. */
#include <tunetrace/tunetrace.h>

#include "anim_frame.h"
#include "tt_test.h"

#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

/* 2 passes of 1 spp of `path` at time t at 64 x 48, posed when `pose` (anim_frame.h);
 * `write_to` (if set) receives the posed scene. A new buffer of *n values, NULL on failure. */
static float *render_at(const char *path, double t, int pose, const char *write_to, size_t *n) {
  anim_frame f = {
      .t = t, .animated = pose, .write_to = write_to, .passes = 2, .width = 64, .height = 48};
  uint32_t w = 0, h = 0;
  float *rgb = anim_render_frame(path, &f, &w, &h);
  *n = (size_t)3 * w * h;
  return rgb;
}

/* Frames of `path` at t0 and t1 equal the still scenes placed at those times, and differ
 * from each other in more than `min_changed` values. */
static void check_scene(const char *path, const char *still, double t0, double t1,
                        size_t min_changed) {
  float *frames[2] = {NULL, NULL};
  size_t n[2] = {0, 0};
  const double ts[2] = {t0, t1};
  for (int k = 0; k < 2; k++) {
    size_t m = 0;
    frames[k] = render_at(path, ts[k], 1, still, &n[k]);
    float *ref = render_at(still, ts[k], 0, NULL, &m);
    CHECK_MSG(frames[k] && ref && n[k] == m, "%s at t = %g: no image", path, ts[k]);
    size_t diff = 0, lit = 0;
    for (size_t i = 0; frames[k] && ref && n[k] == m && i < m; i++) {
      if (memcmp(&frames[k][i], &ref[i], sizeof(float)) != 0 && diff < 4)
        fprintf(stderr, "%s t = %g: value %zu (pixel %zu): %.9g vs the still's %.9g\n", path, ts[k],
                i, i / 3, frames[k][i], ref[i]);
      diff += memcmp(&frames[k][i], &ref[i], sizeof(float)) != 0;
      lit += ref[i] > 0.0f;
    }
    CHECK_MSG(diff == 0 && lit > m / 10,
              "%s at t = %g: %zu of %zu values differ from the still scene placed at that time "
              "(%zu lit)",
              path, ts[k], diff, m, lit);
    free(ref);
  }
  if (frames[0] && frames[1] && n[0] == n[1]) {
    size_t moved = 0;
    for (size_t i = 0; i < n[0]; i++) moved += frames[0][i] != frames[1][i];
    CHECK_MSG(moved > min_changed, "%s: only %zu of %zu values changed between t = %g and %g", path,
              moved, n[0], t0, t1);
  }
  free(frames[0]);
  free(frames[1]);
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  if (!root) root = "..";
  char tmp[] = "/tmp/tt_scene_stress_render_XXXXXX", still[4200], path[4200], cyl[4200];
  if (!mkdtemp(tmp)) TEST_FAIL("cannot create a temporary folder in /tmp");
  snprintf(still, sizeof still, "%s/still.json", tmp);
  /* 64 rigid bodies + a morphing cloth, camera orbiting */
  snprintf(path, sizeof path, "%s/scenes/animated-stress/scene.json", root);
  check_scene(path, still, 1.25, 3.7, 3 * 64 * 48 / 10);
  /* the Cornell box with the rotating cylinder (a fat one, so that it covers pixels) */
  snprintf(cyl, sizeof cyl, "%s/cyl.json", tmp);
  FILE *f = fopen(cyl, "w");
  CHECK(f != NULL);
  if (f) {
    fprintf(f,
            "{\"version\": 1, \"import\": \"%s/scenes/cornell-box/scene.json\", "
            "\"camera\": {\"path\": []}, \"stress\": {\"cylinder\": {\"axis\": [0, 1, 0], "
            "\"radius\": 0.05, \"time\": [0, 2]}}}\n",
            root);
    fclose(f);
  }
  check_scene(cyl, still, 0.4, 1.1, 20);
  /* pbrt: a box and a quad moving with ActiveTransform over TransformTimes 0 2 (meshes
   * without shading normals: a posed normal re-normalised by the mesh importer of the
   * still scene can change in its last bit, which is the still's writing, not the pose) */
  snprintf(path, sizeof path, "%s/motion.pbrt", tmp);
  f = fopen(path, "w");
  CHECK(f != NULL);
  if (f) {
    fputs("TransformTimes 0 2\nLookAt 0 -8 3  0 0 0.5  0 0 1\nCamera \"perspective\" "
          "\"float fov\" [45]\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [0.8 0.8 0.8]\n"
          "Shape \"trianglemesh\" \"point3 P\" [-5 -5 0  5 -5 0  5 5 0  -5 5 0] "
          "\"integer indices\" [0 1 2  0 2 3]\n"
          "AttributeBegin\nActiveTransform StartTime\nTranslate -1.5 0 1\n"
          "ActiveTransform EndTime\nTranslate 1.5 0 1.5\nRotate 90 0 0 1\nScale 0.5 0.5 0.5\n"
          "ActiveTransform All\nShape \"trianglemesh\" \"point3 P\" [-1 -1 -1  1 -1 -1  1 1 -1  "
          "-1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1] \"integer indices\" [0 2 1  0 3 2  4 5 6  "
          "4 6 7  0 1 5  0 5 4  1 2 6  1 6 5  2 3 7  2 7 6  3 0 4  3 4 7]\n"
          "Shape \"trianglemesh\" \"point3 P\" [0 0 1  1 0 1  1 1 1  0 1 1] "
          "\"integer indices\" [0 1 2  0 2 3]\nAttributeEnd\n",
          f);
    fclose(f);
  }
  check_scene(path, still, 0.5, 1.5, 20);
  char cmd[4400];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmp);
  return tt_test_finish("scene_stress_render");
}
