/* scene.json "import": a small scene.json wrapping a pbrt (or another scene.json) file.
 * The wrapped scene must give exactly the pbrt scene's meshes, materials, lights, camera and
 * settings (same scene id); the JSON's camera/render override them, its materials, meshes
 * and lights are appended (area lights stay last, in mesh order); errors name the file, the
 * field and the imported file (missing file, wrong format, nested import / cycles, a parse
 * error inside the imported file). Fixtures: tests/data/pbrt/{basic,handed}.pbrt and
 * wrap-basic.json; error cases write small files into the build tree. */
#include <tunetrace/scene.h>

#include "tt_test.h"

#include <errno.h>
#include <sys/stat.h>

static char g_data[4096]; /* tests/data/pbrt */
static char g_tmp[4096];  /* scratch folder in the build tree */

/* Loads a file; NULL (and a failed check) on error. */
static tt_scene *load(const char *path) {
  tt_scene *s = NULL;
  tt_status st = tt_scene_load(path, &s);
  CHECK_MSG(st == TT_OK && s, "%s: %s", path, tt_last_error());
  return st == TT_OK ? s : NULL;
}

/* Loads JSON text as if it were a file in `dir` named `name`. */
static tt_status load_text(const char *text, const char *dir, const char *name, tt_scene **out) {
  char src[4352];
  snprintf(src, sizeof src, "%s/%s", dir, name);
  return tt_scene_load_json(text, strlen(text), src, dir, out);
}

/* Writes a scratch file; returns its path (static buffer rotated over 4 calls). */
static const char *write_tmp(const char *name, const char *text) {
  static char path[4][4352];
  static int k;
  k = (k + 1) % 4;
  snprintf(path[k], sizeof path[k], "%s/%s", g_tmp, name);
  FILE *f = fopen(path[k], "wb");
  CHECK_MSG(f != NULL, "cannot write %s", path[k]);
  if (f) {
    fputs(text, f);
    fclose(f);
  }
  return path[k];
}

static int same_floats(const float *a, const float *b, size_t n) {
  if (!a || !b) return a == b;
  return memcmp(a, b, n * sizeof *a) == 0;
}

/* Everything the renderer sees must be identical: meshes (bit for bit), materials,
 * textures, lights, bounds, id, camera and settings. */
static void check_same_scene(const tt_scene *a, const tt_scene *b, const char *what) {
  CHECK_MSG(tt_scene_mesh_count(a) == tt_scene_mesh_count(b), "%s: meshes %u vs %u", what,
            tt_scene_mesh_count(a), tt_scene_mesh_count(b));
  CHECK_MSG(tt_scene_triangle_count(a) == tt_scene_triangle_count(b), "%s: triangles", what);
  CHECK_MSG(tt_scene_material_count(a) == tt_scene_material_count(b), "%s: materials", what);
  CHECK_MSG(tt_scene_texture_count(a) == tt_scene_texture_count(b), "%s: textures", what);
  CHECK_MSG(tt_scene_light_count(a) == tt_scene_light_count(b), "%s: lights %u vs %u", what,
            tt_scene_light_count(a), tt_scene_light_count(b));
  CHECK_MSG(strcmp(tt_scene_id(a), tt_scene_id(b)) == 0, "%s: id %s vs %s", what, tt_scene_id(a),
            tt_scene_id(b));
  for (uint32_t i = 0; i < tt_scene_mesh_count(a) && i < tt_scene_mesh_count(b); i++) {
    const tt_mesh *x = tt_scene_mesh(a, i), *y = tt_scene_mesh(b, i);
    CHECK_MSG(strcmp(x->name, y->name) == 0 && x->vertex_count == y->vertex_count &&
                  x->triangle_count == y->triangle_count && x->material == y->material &&
                  x->light == y->light,
              "%s: mesh %u (%s)", what, i, x->name);
    if (x->vertex_count != y->vertex_count || x->triangle_count != y->triangle_count) continue;
    CHECK_MSG(
        same_floats(x->positions, y->positions, 3 * (size_t)x->vertex_count) &&
            same_floats(x->normals, y->normals, 3 * (size_t)x->vertex_count) &&
            same_floats(x->uvs, y->uvs, 2 * (size_t)x->vertex_count) &&
            memcmp(x->indices, y->indices, 3 * (size_t)x->triangle_count * sizeof *x->indices) == 0,
        "%s: mesh %u (%s) arrays differ", what, i, x->name);
  }
  for (uint32_t i = 0; i < tt_scene_material_count(a) && i < tt_scene_material_count(b); i++) {
    const tt_material *x = tt_scene_material(a, i), *y = tt_scene_material(b, i);
    CHECK_MSG(strcmp(x->name, y->name) == 0 && x->type == y->type &&
                  same_floats(x->albedo, y->albedo, 3) &&
                  same_floats(x->emission, y->emission, 3) &&
                  x->albedo_texture == y->albedo_texture,
              "%s: material %u (%s)", what, i, x->name);
  }
  for (uint32_t i = 0; i < tt_scene_light_count(a) && i < tt_scene_light_count(b); i++) {
    const tt_light *x = tt_scene_light(a, i), *y = tt_scene_light(b, i);
    CHECK_MSG(x->type == y->type && x->mesh == y->mesh && x->area == y->area &&
                  same_floats(x->radiance, y->radiance, 3) &&
                  same_floats(x->position, y->position, 3) &&
                  same_floats(x->direction, y->direction, 3),
              "%s: light %u", what, i);
  }
  float alo[3], ahi[3], blo[3], bhi[3];
  tt_scene_bounds(a, alo, ahi);
  tt_scene_bounds(b, blo, bhi);
  CHECK_MSG(same_floats(alo, blo, 3) && same_floats(ahi, bhi, 3), "%s: bounds", what);
  const tt_camera *ca = tt_scene_camera(a), *cb = tt_scene_camera(b);
  CHECK_MSG(same_floats(ca->position, cb->position, 3) && same_floats(ca->target, cb->target, 3) &&
                same_floats(ca->up, cb->up, 3) && ca->fov_y == cb->fov_y &&
                ca->width == cb->width && ca->height == cb->height &&
                ca->key_count == cb->key_count,
            "%s: camera", what);
  const tt_render_settings *sa = tt_scene_settings(a), *sb = tt_scene_settings(b);
  CHECK_MSG(sa->spp == sb->spp && sa->max_depth == sb->max_depth && sa->seed == sb->seed,
            "%s: settings", what);
}

/* A bare wrapper gives exactly the pbrt scene (mirrored or not), from memory and from a file. */
static void test_identity(void) {
  static const char *const files[] = {"basic.pbrt", "handed.pbrt"};
  for (int f = 0; f < 2; f++) {
    char path[4352], json[8192];
    snprintf(path, sizeof path, "%s/%s", g_data, files[f]);
    tt_scene *p = load(path);
    snprintf(json, sizeof json, "{\"version\": 1, \"import\": \"%s\"}", files[f]);
    tt_scene *w = NULL;
    tt_status st = load_text(json, g_data, "wrap.json", &w);
    CHECK_MSG(st == TT_OK, "%s", tt_last_error());
    if (p && w) {
      check_same_scene(p, w, files[f]);
      CHECK_CONTAINS(tt_scene_source(w), "wrap.json"); /* messages name the wrapper */
    }
    /* an absolute import path and a file in another folder give the same scene */
    snprintf(json, sizeof json,
             "{\"version\": 1, \"import\": \"%s\", \"meshes\": [], \"lights\": []}", path);
    tt_scene *w2 = load(write_tmp("abs.json", json));
    if (p && w2) check_same_scene(p, w2, "absolute import");
    tt_scene_destroy(w2);
    tt_scene_destroy(w);
    tt_scene_destroy(p);
  }
}

/* wrap-basic.json: overrides and appended parts. */
static void test_override_append(void) {
  char path[4352];
  snprintf(path, sizeof path, "%s/basic.pbrt", g_data);
  tt_scene *p = load(path);
  snprintf(path, sizeof path, "%s/wrap-basic.json", g_data);
  tt_scene *w = load(path);
  if (!p || !w) {
    tt_scene_destroy(p);
    tt_scene_destroy(w);
    return;
  }
  const tt_camera *cp = tt_scene_camera(p), *cw = tt_scene_camera(w);
  /* overridden: position, fov, resolution; kept: target and up of the pbrt camera */
  CHECK_NEAR(cw->position[0], 0, 0);
  CHECK_NEAR(cw->position[1], 2, 0);
  CHECK_NEAR(cw->position[2], -12, 0);
  for (int k = 0; k < 3; k++) {
    CHECK(cw->target[k] == cp->target[k]);
    CHECK(cw->up[k] == cp->up[k]);
  }
  CHECK_NEAR(cw->fov_y, 30, 1e-6);
  CHECK(cw->width == 64 && cw->height == 32);
  /* the path: keys default to the (overridden) still camera */
  CHECK(cw->key_count == 3 && cw->keys != NULL);
  if (cw->key_count == 3) {
    CHECK(cw->keys[0].position[2] == -12.0f && cw->keys[0].fov_y == 30.0f);
    CHECK(cw->keys[1].position[0] == 4.0f && cw->keys[1].target[2] == cp->target[2]);
    CHECK(cw->keys[2].fov_y == 50.0f && cw->keys[2].target[2] == 5.0f);
    tt_camera at;
    tt_scene_camera_at(w, 3.0, &at);
    CHECK(at.position[0] == 4.0f && at.position[1] == 3.0f && at.position[2] == 0.0f);
    tt_scene_camera_at(w, 2.0, &at);
    CHECK(isfinite(at.position[0]) && at.position[0] > 3.0f);
  }
  /* render: spp and maxDepth overridden, seed kept */
  CHECK(tt_scene_settings(w)->spp == 4 && tt_scene_settings(w)->max_depth == 2);
  CHECK(tt_scene_settings(w)->seed == tt_scene_settings(p)->seed);
  /* appended: one material, two meshes; one explicit light before the area lights */
  uint32_t pm = tt_scene_mesh_count(p), pl = tt_scene_light_count(p);
  CHECK(tt_scene_material_count(w) == tt_scene_material_count(p) + 1);
  CHECK(tt_scene_mesh_count(w) == pm + 2);
  CHECK(tt_scene_triangle_count(w) == tt_scene_triangle_count(p) + 2);
  CHECK(tt_scene_light_count(w) == pl + 2);
  uint32_t explicit_p = 0;
  for (uint32_t i = 0; i < pl; i++) explicit_p += tt_scene_light(p, i)->type != TT_LIGHT_AREA;
  const tt_light *added = tt_scene_light(w, explicit_p);
  CHECK(added && added->type == TT_LIGHT_POINT && added->position[1] == 6.0f);
  for (uint32_t i = 0; i < explicit_p; i++)
    CHECK(tt_scene_light(w, i)->type == tt_scene_light(p, i)->type);
  for (uint32_t i = explicit_p + 1; i < tt_scene_light_count(w); i++)
    CHECK(tt_scene_light(w, i)->type == TT_LIGHT_AREA);
  const tt_light *last = tt_scene_light(w, tt_scene_light_count(w) - 1);
  CHECK(last && last->mesh == pm + 1 && last->radiance[0] == 2.0f);
  const tt_mesh *extra = tt_scene_mesh(w, pm);
  CHECK(extra && strcmp(extra->name, "extra") == 0 &&
        strcmp(tt_scene_material(w, extra->material)->name, "red") == 0); /* an imported material */
  CHECK(tt_scene_mesh(w, pm + 1)->light == (int32_t)tt_scene_light_count(w) - 1);
  /* the imported meshes are untouched and keep their area lights */
  for (uint32_t i = 0; i < pm; i++) {
    const tt_mesh *a = tt_scene_mesh(p, i), *b = tt_scene_mesh(w, i);
    CHECK(a->triangle_count == b->triangle_count &&
          same_floats(a->positions, b->positions, 3 * (size_t)a->vertex_count));
    CHECK((a->light >= 0) == (b->light >= 0));
  }
  CHECK(strcmp(tt_scene_id(w), tt_scene_id(p)) != 0); /* geometry was added */
  tt_scene_destroy(w);
  tt_scene_destroy(p);
}

/* One level of scene.json import: the imported JSON's assets resolve against its own
 * folder, its camera path is kept unless the wrapper gives one. */
static void test_import_json(void) {
  char inner[8192];
  snprintf(inner, sizeof inner,
           "{\"version\": 1, \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0],"
           " \"path\": [{\"time\": 0}, {\"time\": 2, \"position\": [1, 0, 5]}]},"
           " \"render\": {\"spp\": 9},"
           " \"materials\": {\"m\": {\"albedo\": 0.3}},"
           " \"meshes\": [{\"material\": \"m\", \"file\": \"%s/ascii.ply\"}]}",
           g_data);
  const char *ip = write_tmp("inner.json", inner);
  tt_scene *direct = load(ip);
  tt_scene *w = NULL;
  tt_status st =
      load_text("{\"version\": 1, \"import\": \"inner.json\", \"render\": {\"seed\": 5}}", g_tmp,
                "outer.json", &w);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (direct && w) {
    CHECK(tt_scene_triangle_count(w) == tt_scene_triangle_count(direct));
    CHECK(tt_scene_camera(w)->key_count == 2);
    CHECK(tt_scene_settings(w)->spp == 9 && tt_scene_settings(w)->seed == 5);
    CHECK(strcmp(tt_scene_id(w), tt_scene_id(direct)) == 0);
  }
  tt_scene_destroy(w);
  w = NULL;
  /* an empty path in the wrapper removes the imported one */
  st = load_text("{\"version\": 1, \"import\": \"inner.json\", \"camera\": {\"path\": []}}", g_tmp,
                 "outer.json", &w);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (w) CHECK(tt_scene_camera(w)->key_count == 0);
  tt_scene_destroy(w);
  tt_scene_destroy(direct);
}

typedef struct err_case {
  const char *json;
  tt_status status;
  const char *expect, *expect2;
} err_case;

/* Each case is loaded as g_tmp/w.json; messages must name w.json, the field and the file. */
static void test_errors(void) {
  char basic[4352];
  snprintf(basic, sizeof basic, "%s/basic.pbrt", g_data);
  write_tmp("broken.pbrt", "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 "
                           "]\nShape \"frobnicate\"\n");
  write_tmp("nested.json", "{\"version\": 1, \"import\": \"broken.pbrt\"}");
  write_tmp("cycle-a.json", "{\"version\": 1, \"import\": \"cycle-b.json\"}");
  write_tmp("cycle-b.json", "{\"version\": 1, \"import\": \"cycle-a.json\"}");
  write_tmp("mesh.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  char c_basic_env[8192], c_basic_mat[8192], c_basic_fov[8192], c_basic_meshes[8192];
  snprintf(c_basic_env, sizeof c_basic_env,
           "{\"version\": 1, \"import\": \"%s\", \"lights\": [{\"type\": \"environment\"}]}",
           basic);
  snprintf(c_basic_mat, sizeof c_basic_mat,
           "{\"version\": 1, \"import\": \"%s\", \"materials\": {\"red\": {\"albedo\": 1}}}",
           basic);
  snprintf(c_basic_fov, sizeof c_basic_fov,
           "{\"version\": 1, \"import\": \"%s\", \"camera\": {\"fov\": 200}}", basic);
  snprintf(c_basic_meshes, sizeof c_basic_meshes,
           "{\"version\": 1, \"import\": \"%s\", \"meshes\": {\"a\": 1}}", basic);
  const err_case cases[] = {
      {"{\"version\": 1, \"import\": \"nothere.pbrt\"}", TT_ERR_IO,
       "w.json: import: cannot open scene file \"", "nothere.pbrt\": No such file or directory"},
      {"{\"version\": 1, \"import\": 3}", TT_ERR_PARSE,
       "w.json: import: expected a non-empty string, got 3", NULL},
      {"{\"version\": 1, \"import\": \"\"}", TT_ERR_PARSE,
       "w.json: import: expected a non-empty string", NULL},
      {"{\"version\": 1, \"import\": \"mesh.obj\"}", TT_ERR_UNSUPPORTED,
       "w.json: import: unsupported scene format \"mesh.obj\" (expected .pbrt, .json, .gltf or "
       ".glb)",
       NULL},
      /* a parse error inside the imported pbrt keeps its file:line */
      {"{\"version\": 1, \"import\": \"broken.pbrt\"}", TT_ERR_PARSE,
       "w.json: import: ", "broken.pbrt:3:"},
      /* nested import, cycles and self-import */
      {"{\"version\": 1, \"import\": \"nested.json\"}", TT_ERR_PARSE, "w.json: import: ",
       "nested.json: import: \"broken.pbrt\" not loaded: this file is itself imported"},
      {"{\"version\": 1, \"import\": \"cycle-a.json\"}", TT_ERR_PARSE,
       "w.json: import: ", "cycle-a.json: import: \"cycle-b.json\" not loaded"},
      {"{\"version\": 1, \"import\": \"w.json\"}", TT_ERR_PARSE, "w.json: import: \"",
       "w.json\" is this file (a scene cannot import itself)"},
      /* the JSON's own sections are still checked, with their JSON paths */
      {c_basic_env, TT_ERR_PARSE,
       "w.json: lights[0]: only one environment light is allowed (the imported scene has one)",
       NULL},
      {c_basic_mat, TT_ERR_PARSE,
       "w.json: materials.red: duplicate material name (names of the imported scene count too)",
       NULL},
      {c_basic_fov, TT_ERR_PARSE, "w.json: camera.fov: expected a number in (0, 180), got 200",
       NULL},
      {c_basic_meshes, TT_ERR_PARSE, "w.json: meshes: expected an array of meshes, got an object",
       NULL},
      /* without import, camera/materials/meshes stay required */
      {"{\"version\": 1}", TT_ERR_PARSE, "w.json: camera: missing required field", NULL},
      {"{\"version\": 1, \"import\": \"x.pbrt\", \"camera\": {\"position\": [0, 0, 0], \"target\": "
       "[0, 0, 0]}}",
       TT_ERR_IO, "w.json: import: cannot open scene file", NULL},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    const char *path = write_tmp("w.json", cases[i].json);
    tt_scene *s = NULL;
    tt_status st = tt_scene_load(path, &s);
    CHECK_MSG(st == cases[i].status, "case %zu: status %d (%s), expected %d", i, (int)st,
              tt_last_error(), (int)cases[i].status);
    CHECK(s == NULL);
    CHECK_CONTAINS(tt_last_error(), cases[i].expect);
    if (cases[i].expect2) CHECK_CONTAINS(tt_last_error(), cases[i].expect2);
    tt_scene_destroy(s);
  }
  /* a pose override that makes the imported camera degenerate is caught */
  char deg[8192];
  snprintf(deg, sizeof deg,
           "{\"version\": 1, \"import\": \"%s\", \"camera\": {\"position\": [0, 1, -9]}}", basic);
  tt_scene *s = NULL;
  tt_status st = tt_scene_load(write_tmp("w.json", deg), &s);
  CHECK(st == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(),
                 "w.json: camera.target: expected a point different from camera.position");
  tt_scene_destroy(s);
}

int main(void) {
  const char *src = getenv("TT_SOURCE_ROOT"), *build = getenv("TT_BUILD_ROOT");
  snprintf(g_data, sizeof g_data, "%s/tests/data/pbrt", src ? src : ".");
  snprintf(g_tmp, sizeof g_tmp, "%s/scene_import_tmp", build ? build : ".");
  if (mkdir(g_tmp, 0755) != 0 && errno != EEXIST) {
    fprintf(stderr, "cannot create %s\n", g_tmp);
    return 1;
  }
  test_identity();
  test_override_append();
  test_import_json();
  test_errors();
  return tt_test_finish("scene_import");
}
