/* scenes_info: loads scenes (scene.json or .pbrt) and prints one JSON object per scene with
 * what the benchmark table of scenes/README.md lists: triangles, meshes, lights (by type),
 * materials, bounds and their diagonal, the still camera (after import, in tunetrace's world
 * coordinates), the camera path's key count and the load time. tools/scenes/camera_path.py
 * reads it to place camera paths in imported pbrt scenes.
 *
 *   scenes_info SCENE...        exit 0 when every scene loaded, 4 otherwise
 */
#include <tunetrace/tunetrace.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <tt_util/clock.h>

static void vec(const char *name, const float *v, int comma) {
  printf("\"%s\": [%.9g, %.9g, %.9g]%s", name, v[0], v[1], v[2], comma ? ", " : "");
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: scenes_info SCENE...\n");
    return 2;
  }
  int rc = 0;
  for (int a = 1; a < argc; a++) {
    tt_scene *s = NULL;
    double t0 = tt__wall_ms();
    if (tt_scene_load(argv[a], &s) != TT_OK) {
      fprintf(stderr, "scenes_info: %s\n", tt_last_error());
      rc = 4;
      continue;
    }
    double load_ms = tt__wall_ms() - t0;
    float lo[3], hi[3];
    tt_scene_bounds(s, lo, hi);
    double d =
        sqrt((double)(hi[0] - lo[0]) * (hi[0] - lo[0]) + (double)(hi[1] - lo[1]) * (hi[1] - lo[1]) +
             (double)(hi[2] - lo[2]) * (hi[2] - lo[2]));
    uint32_t counts[8] = {0};
    for (uint32_t i = 0; i < tt_scene_light_count(s); i++) {
      uint32_t t = (uint32_t)tt_scene_light(s, i)->type;
      if (t < 8) counts[t]++;
    }
    const tt_camera *c = tt_scene_camera(s);
    printf("{\"scene\": \"%s\", \"triangles\": %llu, \"meshes\": %u, \"materials\": %u, "
           "\"textures\": %u, \"lights\": %u, ",
           argv[a], (unsigned long long)tt_scene_triangle_count(s), tt_scene_mesh_count(s),
           tt_scene_material_count(s), tt_scene_texture_count(s), tt_scene_light_count(s));
    printf("\"light_types\": {\"area\": %u, \"environment\": %u, \"point\": %u, \"spot\": %u, "
           "\"distant\": %u}, ",
           counts[TT_LIGHT_AREA], counts[TT_LIGHT_ENV_CONSTANT] + counts[TT_LIGHT_ENV_IMAGE],
           counts[TT_LIGHT_POINT], counts[TT_LIGHT_SPOT], counts[TT_LIGHT_DISTANT]);
    printf("\"bounds\": [[%.9g, %.9g, %.9g], [%.9g, %.9g, %.9g]], \"diagonal\": %.9g, ", lo[0],
           lo[1], lo[2], hi[0], hi[1], hi[2], d);
    printf("\"camera\": {");
    vec("position", c->position, 1);
    vec("target", c->target, 1);
    vec("up", c->up, 1);
    printf("\"fov\": %.9g, \"resolution\": [%u, %u], \"path_keys\": %u}, ", c->fov_y, c->width,
           c->height, c->key_count);
    printf("\"load_ms\": %.1f}\n", load_ms);
    fflush(stdout);
    tt_scene_destroy(s);
  }
  return rc;
}
