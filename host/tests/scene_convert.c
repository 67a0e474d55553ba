/* tt_scene_write_json round trips (host --convert): a pbrt fixture, the Cornell box and an
 * inline scene with a camera path and every explicit light type are written as scene.json
 * + PLY meshes, reloaded, and compared with the scene they came from. */
#include <tunetrace/tunetrace.h>

#include "tt_test.h"

#include <stdint.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static char tmp_root[] = "/tmp/tt_scene_convert_XXXXXX";

/* Relative difference scaled by the scene's size, for bounds. */
static double rel_err(float a, float b, double scale) {
  return fabs((double)a - (double)b) / scale;
}

/* Compares every field the converter promises to keep. */
static void compare(const tt_scene *a, const tt_scene *b, const char *what) {
  fprintf(stderr, "comparing %s\n", what);
  CHECK(tt_scene_mesh_count(a) == tt_scene_mesh_count(b));
  CHECK(tt_scene_triangle_count(a) == tt_scene_triangle_count(b));
  float alo[3], ahi[3], blo[3], bhi[3];
  tt_scene_bounds(a, alo, ahi);
  tt_scene_bounds(b, blo, bhi);
  double diag = 0;
  for (int i = 0; i < 3; i++) diag += ((double)ahi[i] - alo[i]) * ((double)ahi[i] - alo[i]);
  diag = sqrt(diag) > 0 ? sqrt(diag) : 1;
  for (int i = 0; i < 3; i++) {
    CHECK_MSG(rel_err(alo[i], blo[i], diag) <= 1e-5, "lo[%d] %g vs %g", i, alo[i], blo[i]);
    CHECK_MSG(rel_err(ahi[i], bhi[i], diag) <= 1e-5, "hi[%d] %g vs %g", i, ahi[i], bhi[i]);
  }
  uint32_t nm = tt_scene_mesh_count(a) < tt_scene_mesh_count(b) ? tt_scene_mesh_count(a)
                                                                : tt_scene_mesh_count(b);
  for (uint32_t i = 0; i < nm; i++) {
    const tt_mesh *ma = tt_scene_mesh(a, i), *mb = tt_scene_mesh(b, i);
    CHECK_MSG(ma->triangle_count == mb->triangle_count, "mesh %u: %u vs %u triangles", i,
              ma->triangle_count, mb->triangle_count);
    CHECK_MSG(strcmp(ma->name, mb->name) == 0, "mesh %u: \"%s\" vs \"%s\"", i, ma->name, mb->name);
    CHECK(ma->material == mb->material);
    CHECK(ma->light == mb->light);
    CHECK((ma->normals != NULL) == (mb->normals != NULL));
    CHECK((ma->uvs != NULL) == (mb->uvs != NULL));
    /* the first triangle's corners, found by position in the reloaded mesh (assimp may
     * reorder or merge vertices), carry the same normal and uv */
    for (int c = 0; c < 3 && ma->triangle_count; c++) {
      uint32_t va = ma->indices[c];
      int found = 0;
      for (uint32_t v = 0; v < mb->vertex_count && !found; v++) {
        if (memcmp(ma->positions + 3 * (size_t)va, mb->positions + 3 * (size_t)v,
                   3 * sizeof(float)) != 0)
          continue;
        if (ma->normals && mb->normals &&
            memcmp(ma->normals + 3 * (size_t)va, mb->normals + 3 * (size_t)v, 3 * sizeof(float)) !=
                0)
          continue;
        if (ma->uvs && mb->uvs &&
            memcmp(ma->uvs + 2 * (size_t)va, mb->uvs + 2 * (size_t)v, 2 * sizeof(float)) != 0)
          continue;
        found = 1;
      }
      CHECK_MSG(found, "mesh %u corner %d not found with the same position/normal/uv", i, c);
    }
  }
  CHECK(tt_scene_material_count(a) == tt_scene_material_count(b));
  for (uint32_t i = 0; i < tt_scene_material_count(a) && i < tt_scene_material_count(b); i++) {
    const tt_material *ma = tt_scene_material(a, i), *mb = tt_scene_material(b, i);
    CHECK_MSG(ma->type == mb->type, "material %u (%s): type %d vs %d", i, ma->name, ma->type,
              mb->type);
    CHECK_MSG(memcmp(ma->albedo, mb->albedo, sizeof ma->albedo) == 0, "material %u (%s) albedo", i,
              ma->name);
    CHECK_MSG(memcmp(ma->emission, mb->emission, sizeof ma->emission) == 0,
              "material %u (%s) emission", i, ma->name);
    CHECK(memcmp(ma->alpha, mb->alpha, sizeof ma->alpha) == 0);
    CHECK(memcmp(ma->eta, mb->eta, sizeof ma->eta) == 0);
    CHECK(memcmp(ma->k, mb->k, sizeof ma->k) == 0);
    CHECK(memcmp(ma->specular, mb->specular, sizeof ma->specular) == 0);
    CHECK(ma->ior == mb->ior && ma->roughness == mb->roughness && ma->two_sided == mb->two_sided);
    CHECK((ma->albedo_texture >= 0) == (mb->albedo_texture >= 0));
    if (ma->albedo_texture >= 0 && mb->albedo_texture >= 0) {
      /* textures are written by absolute path (the loader shares them by path) */
      char *ra = realpath(tt_scene_texture(a, (uint32_t)ma->albedo_texture)->path, NULL);
      char *rb = realpath(tt_scene_texture(b, (uint32_t)mb->albedo_texture)->path, NULL);
      CHECK(ra && rb && strcmp(ra, rb) == 0);
      free(ra);
      free(rb);
    }
  }
  CHECK(tt_scene_light_count(a) == tt_scene_light_count(b));
  for (uint32_t i = 0; i < tt_scene_light_count(a) && i < tt_scene_light_count(b); i++) {
    const tt_light *la = tt_scene_light(a, i), *lb = tt_scene_light(b, i);
    CHECK_MSG(la->type == lb->type, "light %u: type %d vs %d", i, la->type, lb->type);
    CHECK(memcmp(la->radiance, lb->radiance, sizeof la->radiance) == 0);
    CHECK(memcmp(la->position, lb->position, sizeof la->position) == 0);
    for (int k = 0; k < 3; k++) CHECK_NEAR(la->direction[k], lb->direction[k], 1e-6);
    CHECK_NEAR(la->cos_inner, lb->cos_inner, 1e-6);
    CHECK_NEAR(la->cos_outer, lb->cos_outer, 1e-6);
    CHECK(la->mesh == lb->mesh);
    CHECK_NEAR(la->area, lb->area, 1e-5 * (la->area > 1 ? la->area : 1));
    CHECK((la->image != NULL) == (lb->image != NULL));
  }
  const tt_camera *ca = tt_scene_camera(a), *cb = tt_scene_camera(b);
  CHECK(memcmp(ca->position, cb->position, sizeof ca->position) == 0);
  CHECK(memcmp(ca->target, cb->target, sizeof ca->target) == 0);
  CHECK(memcmp(ca->up, cb->up, sizeof ca->up) == 0);
  CHECK(ca->fov_y == cb->fov_y);
  CHECK(ca->width == cb->width && ca->height == cb->height);
  CHECK(ca->key_count == cb->key_count);
  for (uint32_t i = 0; i < ca->key_count && i < cb->key_count; i++)
    CHECK(memcmp(&ca->keys[i], &cb->keys[i], sizeof ca->keys[i]) == 0);
  const tt_render_settings *sa = tt_scene_settings(a), *sb = tt_scene_settings(b);
  CHECK(sa->spp == sb->spp && sa->max_depth == sb->max_depth && sa->seed == sb->seed);
  CHECK(sa->time_budget_s == sb->time_budget_s);
}

/* Writes `s` to <tmp>/<sub>/scene.json, reloads and compares. */
static void round_trip(tt_scene *s, const char *sub) {
  char dir[256], path[320];
  snprintf(dir, sizeof dir, "%s/%s", tmp_root, sub);
  CHECK(mkdir(dir, 0777) == 0);
  snprintf(path, sizeof path, "%s/scene.json", dir);
  tt_status st = tt_scene_write_json(s, path);
  CHECK_MSG(st == TT_OK, "write %s: %s", path, tt_last_error());
  if (st != TT_OK) return;
  tt_scene *r = NULL;
  st = tt_scene_load(path, &r);
  CHECK_MSG(st == TT_OK, "reload %s: %s", path, tt_last_error());
  if (st == TT_OK) compare(s, r, sub);
  tt_scene_destroy(r);
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  if (!root) root = ".";
  if (!mkdtemp(tmp_root)) TEST_FAIL("cannot create a temporary folder in /tmp");
  char path[512];

  /* a pbrt fixture: textures, every light type, spheres, uvs and normals */
  snprintf(path, sizeof path, "%s/tests/data/pbrt/basic.pbrt", root);
  tt_scene *s = NULL;
  tt_status st = tt_scene_load(path, &s);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (st == TT_OK) round_trip(s, "pbrt");
  tt_scene_destroy(s);

  /* the Cornell box: 8 meshes, one area light */
  snprintf(path, sizeof path, "%s/scenes/cornell-box/scene.json", root);
  s = NULL;
  st = tt_scene_load(path, &s);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (st == TT_OK) {
    CHECK(tt_scene_mesh_count(s) == 8);
    round_trip(s, "cornell");
  }
  tt_scene_destroy(s);

  /* inline: camera path, spot/point/distant/environment lights, settings, odd names */
  static const char json[] =
      "{\"version\": 1,"
      " \"camera\": {\"position\": [0, 1, 5], \"target\": [0, 1, 0], \"fov\": 33.3, "
      "\"resolution\": [64, 48],"
      "   \"path\": [{\"time\": 0}, {\"time\": 0.5, \"position\": [1, 2, 5]}, {\"time\": 1.25, "
      "\"fov\": 50}]},"
      " \"render\": {\"spp\": 7, \"maxDepth\": 9, \"seed\": 123456789, \"timeBudget\": 2.5},"
      " \"materials\": {\"a \\\"quoted\\\" name\": {\"type\": \"plastic\", \"albedo\": [0.1, 0.2, "
      "0.3], \"alpha\": [0.2, 0.05]},"
      "   \"lamp\": {\"emission\": [3, 2, 1], \"twoSided\": true},"
      "   \"metal\": {\"type\": \"conductor\", \"eta\": [0.2, 0.3, 0.4], \"k\": [3, 2, 1]}},"
      " \"meshes\": [{\"name\": \"tri/one two\", \"material\": \"a \\\"quoted\\\" name\","
      "     \"positions\": [0,0,0, 1,0,0, 0,1,0], \"normals\": [0,0,1, 0,0,1, 0,0,1], \"uvs\": "
      "[0,0, 1,0, 0,1]},"
      "   {\"material\": \"lamp\", \"positions\": [0,3,0, 1,3,0, 0,3,1, 1,3,1], \"indices\": "
      "[0,2,1, 1,2,3]},"
      "   {\"material\": \"metal\", \"positions\": [[-2,0,0],[-1,0,0],[-2,1,0.5]]},"
      /* the first float's low byte is 0x0a: assimp skips whitespace after end_header, which
       * the writer's per-vertex guard byte defends against (staircase.pbrt has such a mesh) */
      "   {\"material\": \"metal\", \"positions\": "
      "[[-0.345382988,2,0],[-0.345382988,3,0],[-0.345382988,2,1]]}],"
      " \"lights\": [{\"type\": \"spot\", \"position\": [0, 4, 0], \"target\": [0, 0, 0], "
      "\"intensity\": 5,"
      "   \"angle\": 35, \"innerAngle\": 20}, {\"type\": \"point\", \"position\": [1, 2, 3], "
      "\"intensity\": [1, 2, 3]},"
      "   {\"type\": \"distant\", \"direction\": [0.3, -1, 0.2], \"irradiance\": 2},"
      "   {\"type\": \"environment\", \"radiance\": [0.1, 0.2, 0.3]}]}";
  s = NULL;
  st = tt_scene_load_json(json, sizeof json - 1, "inline", NULL, &s);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (st == TT_OK) {
    CHECK(tt_scene_camera(s)->key_count == 3);
    round_trip(s, "inline");
    char ply[512];
    snprintf(ply, sizeof ply, "%s/inline/meshes/0_tri_one_two.ply", tmp_root);
    CHECK_MSG(access(ply, R_OK) == 0, "%s missing", ply);
    /* an unwritable destination fails with the file named */
    snprintf(path, sizeof path, "%s/no/such/dir/scene.json", tmp_root);
    st = tt_scene_write_json(s, path);
    CHECK(st == TT_ERR_IO);
    CHECK_CONTAINS(tt_last_error(), path);
  }
  tt_scene_destroy(s);

  /* host --convert: the Cornell box to a .json, reloaded; --out must end in .json */
  const char *build = getenv("TT_BUILD_ROOT");
  char cmd[1400];
  if (build) {
    snprintf(
        cmd, sizeof cmd,
        "'%s/host/host' --quiet --convert '%s/scenes/cornell-box/scene.json' --out '%s/cli.json'",
        build, root, tmp_root);
    CHECK_MSG(system(cmd) == 0, "%s", cmd);
    snprintf(path, sizeof path, "%s/cli.json", tmp_root);
    s = NULL;
    st = tt_scene_load(path, &s);
    CHECK_MSG(st == TT_OK, "%s", tt_last_error());
    if (st == TT_OK) CHECK(tt_scene_triangle_count(s) == 32 && tt_scene_mesh_count(s) == 8);
    tt_scene_destroy(s);
    snprintf(cmd, sizeof cmd,
             "'%s/host/host' --quiet --convert '%s/scenes/cornell-box/scene.json' --out '%s/x.exr' "
             "2>/dev/null",
             build, root, tmp_root);
    int rc = system(cmd);
    CHECK(rc != -1 && WIFEXITED(rc) && WEXITSTATUS(rc) == 2);
  }

  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_root);
  if (tt_test_failures == 0 && system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmp_root);
  return tt_test_finish("scene_convert");
}
