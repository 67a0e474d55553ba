/* pbrt-v4 importer on the real scenes in ../shared/scenes (skipped when absent): every
 * scene loads, has at least the triangles shared/scenes/README.md counts (PLY/OBJ faces;
 * tessellated spheres/disks, Loop subdivision and repeated PLY references add to them),
 * a light and finite bounds. Prints the import time of each. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime, dup2, mkdir */
#include <tunetrace/scene.h>

#include "tt_test.h"

#include <sys/stat.h>
#include <time.h>

typedef struct real_scene {
  const char *file;
  uint64_t min_triangles;
} real_scene;

/* README counts per folder; cornell-box-pbrt's 164 is the sum of its variants' inline
 * meshes (checked below), so each variant gets its own inline count. */
static const real_scene k_scenes[] = {
    {"cornell-box-pbrt/cornell-box.pbrt", 32},
    {"cornell-box-pbrt/cornell-box-silver.pbrt", 32},
    {"cornell-box-pbrt/cornell-box-specular.pbrt", 22},
    {"cornell-box-pbrt/cornell-box-environment-map.pbrt", 2},
    {"cornell-box-pbrt/cornell-box-volume.pbrt", 32},
    {"cornell-box-pbrt/cornell-box-specular-volume.pbrt", 22},
    {"cornell-box-pbrt/smallpt.pbrt", 10},
    {"cornell-box-pbrt/volumetric-caustic.pbrt", 12},
    {"veach-mis/veach-mis.pbrt", 12},
    {"veach-mis/veach-mis-colorized.pbrt", 12},
    {"killeroos/killeroo-simple.pbrt", 16660},
    {"killeroos/killeroo-gold.pbrt", 16660},
    {"killeroos/killeroo-coated-gold.pbrt", 16660},
    {"killeroos/killeroo-moving.pbrt", 16660},
    {"caustic-glass/caustic-glass-v4.pbrt", 88066},
    {"veach-ajar/veach-ajar.pbrt", 130592},
    {"living-room/living-room.pbrt", 143163},
    {"staircase/staircase.pbrt", 262661},
    {"bathroom/bathroom.pbrt", 592186},
    {"bmw-m6/bmw-m6.pbrt", 792746},
};

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  char dir[4096];
  snprintf(dir, sizeof dir, "%s/../shared/scenes", root ? root : ".");
  struct stat sb;
  if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode)) TEST_SKIP("%s not found", dir);
  uint64_t cornell_inline = 0;
  for (size_t i = 0; i < sizeof k_scenes / sizeof k_scenes[0]; i++) {
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, k_scenes[i].file);
    if (stat(path, &sb) != 0) {
      CHECK_MSG(0, "%s is missing", path);
      continue;
    }
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    tt_scene *s = NULL;
    tt_status st = tt_scene_load(path, &s);
    clock_gettime(CLOCK_MONOTONIC, &b);
    double ms = (double)(b.tv_sec - a.tv_sec) * 1e3 + (double)(b.tv_nsec - a.tv_nsec) / 1e6;
    CHECK_MSG(st == TT_OK && s, "%s: %s", k_scenes[i].file, tt_last_error());
    if (!s) continue;
    uint64_t tris = tt_scene_triangle_count(s);
    float lo[3], hi[3];
    tt_scene_bounds(s, lo, hi);
    const tt_camera *c = tt_scene_camera(s);
    printf("%-52s %8.1f ms %9llu triangles %5u meshes %3u materials %3u lights %ux%u\n", k_scenes[i].file, ms,
           (unsigned long long)tris, tt_scene_mesh_count(s), tt_scene_material_count(s), tt_scene_light_count(s),
           c->width, c->height);
    CHECK_MSG(tris >= k_scenes[i].min_triangles, "%s: %llu triangles < %llu", k_scenes[i].file,
              (unsigned long long)tris, (unsigned long long)k_scenes[i].min_triangles);
    if (strncmp(k_scenes[i].file, "cornell-box-pbrt/", 17) == 0) cornell_inline += k_scenes[i].min_triangles;
    CHECK_MSG(tt_scene_light_count(s) > 0, "%s: no lights", k_scenes[i].file);
    for (int k = 0; k < 3; k++) CHECK(isfinite(lo[k]) && isfinite(hi[k]) && lo[k] <= hi[k]);
    CHECK(c->width > 0 && c->height > 0 && c->fov_y > 0 && c->fov_y < 180);
    for (uint32_t m = 0; m < tt_scene_material_count(s); m++) {
      const tt_material *mt = tt_scene_material(s, m);
      for (int k = 0; k < 3; k++) CHECK(isfinite(mt->albedo[k]) && isfinite(mt->eta[k]) && isfinite(mt->emission[k]));
    }
    tt_scene_destroy(s);
  }
  CHECK(cornell_inline == 164);
  return tt_test_finish("pbrt_real");
}
