/* Scene loading: the Cornell box, OBJ import with transforms, camera paths, scene ids,
 * light types and the Table 3.2 indicators. */
#include <tunetrace/scene.h>

#include "tt_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char g_root[1024];

/* Builds "<TT_SOURCE_ROOT>/<rel>" so the test runs from any build directory. */
static const char *src_path(const char *rel, char *buf, size_t n) {
  snprintf(buf, n, "%s/%s", g_root, rel);
  return buf;
}

/* Loads JSON text from memory, reporting the error if it fails. */
static tt_scene *load_text(const char *json, const char *base) {
  tt_scene *s = NULL;
  tt_status st = tt_scene_load_json(json, strlen(json), "inline.json", base, &s);
  CHECK_MSG(st == TT_OK, "load failed: %s", tt_last_error());
  return s;
}

static const tt_mesh *find_mesh(const tt_scene *s, const char *name) {
  for (uint32_t i = 0; i < tt_scene_mesh_count(s); i++)
    if (strcmp(tt_scene_mesh(s, i)->name, name) == 0) return tt_scene_mesh(s, i);
  return NULL;
}

static void test_cornell(void) {
  char path[1200];
  tt_scene *s = NULL;
  tt_status st = tt_scene_load(src_path("scenes/cornell-box/scene.json", path, sizeof path), &s);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (!s) return;
  CHECK(strcmp(tt_scene_source(s), path) == 0);
  CHECK(tt_scene_mesh_count(s) == 8);
  CHECK(tt_scene_triangle_count(s) == 32);
  CHECK(tt_scene_material_count(s) == 4);
  CHECK(tt_scene_texture_count(s) == 0);
  CHECK(tt_scene_mesh(s, 8) == NULL);
  CHECK(tt_scene_material(s, 4) == NULL);

  float lo[3], hi[3];
  tt_scene_bounds(s, lo, hi);
  CHECK_NEAR(lo[0], 0.0, 1e-4);
  CHECK_NEAR(lo[1], 0.0, 1e-4);
  CHECK_NEAR(lo[2], 0.0, 1e-4);
  CHECK_NEAR(hi[0], 556.0, 1e-3);
  CHECK_NEAR(hi[1], 548.8, 1e-3);
  CHECK_NEAR(hi[2], 559.2, 1e-3);

  /* exactly one light: the ceiling quad, 130 x 105 mm, emission (17, 12, 4) */
  CHECK(tt_scene_light_count(s) == 1);
  const tt_light *l = tt_scene_light(s, 0);
  CHECK(l && l->type == TT_LIGHT_AREA);
  const tt_mesh *lm = find_mesh(s, "light");
  CHECK(lm != NULL);
  if (l && lm) {
    CHECK(tt_scene_mesh(s, l->mesh) == lm);
    CHECK(lm->light == 0);
    CHECK_NEAR(l->area, 130.0 * 105.0, 0.5);
    CHECK_NEAR(l->radiance[0], 17.0, 1e-6);
    CHECK_NEAR(l->radiance[1], 12.0, 1e-6);
    CHECK_NEAR(l->radiance[2], 4.0, 1e-6);
    /* the emitter faces down into the box */
    const float *p = lm->positions;
    const uint32_t *ix = lm->indices;
    float e1[3], e2[3];
    for (int a = 0; a < 3; a++) {
      e1[a] = p[3 * ix[1] + a] - p[3 * ix[0] + a];
      e2[a] = p[3 * ix[2] + a] - p[3 * ix[0] + a];
    }
    CHECK(e1[2] * e2[0] - e1[0] * e2[2] < 0);
  }
  for (uint32_t i = 0; i < tt_scene_mesh_count(s); i++) {
    const tt_mesh *m = tt_scene_mesh(s, i);
    CHECK(m->struct_size == sizeof(tt_mesh));
    if (m != lm) CHECK(m->light == -1);
    CHECK(m->normals == NULL && m->uvs == NULL);
  }

  /* materials in file order, classic reflectances */
  const tt_material *red = tt_scene_material(s, 1);
  CHECK(red && strcmp(red->name, "red") == 0 && red->type == TT_MATERIAL_DIFFUSE);
  if (red) {
    CHECK_NEAR(red->albedo[0], 0.63, 1e-6);
    CHECK_NEAR(red->albedo[1], 0.065, 1e-6);
    CHECK_NEAR(red->albedo[2], 0.05, 1e-6);
    CHECK(red->albedo_texture == -1);
    CHECK(red->emission[0] == 0 && red->emission[1] == 0 && red->emission[2] == 0);
  }
  const tt_material *white = tt_scene_material(s, find_mesh(s, "tall_block")->material);
  CHECK(strcmp(white->name, "white") == 0);
  CHECK_NEAR(white->albedo[1], 0.73, 1e-6);
  CHECK(strcmp(tt_scene_material(s, find_mesh(s, "left_wall")->material)->name, "red") == 0);
  CHECK(strcmp(tt_scene_material(s, find_mesh(s, "right_wall")->material)->name, "green") == 0);

  const tt_camera *c = tt_scene_camera(s);
  CHECK_NEAR(c->position[0], 278.0, 1e-4);
  CHECK_NEAR(c->position[1], 273.0, 1e-4);
  CHECK_NEAR(c->position[2], -800.0, 1e-4);
  CHECK_NEAR(c->target[2], 0.0, 1e-4);
  CHECK_NEAR(c->up[1], 1.0, 1e-6);
  CHECK_NEAR(c->fov_y, 39.3077, 1e-4);
  CHECK(c->width == 256 && c->height == 256);
  CHECK(c->key_count == 0);

  const tt_render_settings *rs = tt_scene_settings(s);
  CHECK(rs->spp == 16 && rs->max_depth == 3 && rs->seed == 1 && rs->time_budget_s == 0.0);

  /* resolution override */
  CHECK(tt_scene_set_resolution(s, 64, 32) == TT_OK);
  CHECK(c->width == 64 && c->height == 32);
  CHECK(tt_scene_set_resolution(s, 0, 32) == TT_ERR_INVALID_ARGUMENT);
  CHECK(c->width == 64);

  /* indicators (thesis Table 3.2) */
  double ind[TT_SCENE_INDICATOR_COUNT];
  tt_scene_indicators(s, ind);
  for (int i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) CHECK_MSG(isfinite(ind[i]), "indicator %d", i);
  CHECK(strcmp(tt_scene_indicator_name(0), "meshes") == 0);
  CHECK(strcmp(tt_scene_indicator_name(1), "triangles") == 0);
  CHECK(strcmp(tt_scene_indicator_name(16), "var_var_tri_size") == 0);
  CHECK(tt_scene_indicator_name(17) == NULL);
  for (uint32_t i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) {
    const char *n = tt_scene_indicator_name(i);
    CHECK(n && n[0]);
    for (const char *q = n; q && *q; q++) CHECK((*q >= 'a' && *q <= 'z') || *q == '_');
    for (uint32_t j = 0; j < i; j++) CHECK(strcmp(n, tt_scene_indicator_name(j)) != 0);
  }
  double d = sqrt(556.0 * 556.0 + 548.8 * 548.8 + 559.2 * 559.2);
  CHECK_NEAR(ind[0], 8, 0);
  CHECK_NEAR(ind[1], 32, 0);
  CHECK_NEAR(ind[2], 1, 0);
  CHECK_NEAR(ind[3], 278, 1e-4);
  CHECK_NEAR(ind[5], -800, 1e-4);
  CHECK_NEAR(ind[8], 0, 1e-4);
  CHECK_NEAR(ind[9], 39.3077, 1e-4);
  CHECK_NEAR(ind[10], 1.0, 1e-12); /* all diffuse */
  CHECK_NEAR(ind[11], d, 1e-2);
  CHECK_NEAR(ind[13], 13650.0 / (d * d), 1e-6);
  /* sum of the 32 triangle areas (1934345.708 mm^2, computed independently) / D^2 */
  CHECK_NEAR(ind[12], 1934345.708 / (d * d), 1e-6);
  CHECK_NEAR(ind[14], ind[12] / 8, 1e-12);
  CHECK(ind[15] >= 0 && ind[15] < 1e-2);
  CHECK(ind[16] >= 0 && ind[16] < 1e-2);
  /* the light's two triangles have equal area, so its VarTriSize is ~0 and the mean stays
   * below the largest mesh variance; the walls' two triangles differ slightly */
  CHECK(ind[15] > 0);
  tt_scene_destroy(s);
}

static void test_obj_transform(void) {
  char path[1200];
  tt_scene *s = NULL;
  tt_status st =
      tt_scene_load(src_path("tests/data/scenes/obj-transform.json", path, sizeof path), &s);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (!s) return;
  CHECK(tt_scene_mesh_count(s) == 1);
  CHECK(tt_scene_triangle_count(s) == 12);
  const tt_mesh *m = tt_scene_mesh(s, 0);
  CHECK(strcmp(m->name, "cube") == 0);
  CHECK(m->vertex_count >= 8);
  for (uint32_t i = 0; i < 3 * m->triangle_count; i++) CHECK(m->indices[i] < m->vertex_count);
  float lo[3], hi[3];
  tt_scene_bounds(s, lo, hi);
  CHECK_NEAR(lo[0], 8.0, 1e-5);
  CHECK_NEAR(hi[0], 10.0, 1e-5);
  CHECK_NEAR(lo[1], 0.0, 1e-5);
  CHECK_NEAR(hi[1], 2.0, 1e-5);
  CHECK_NEAR(lo[2], 0.0, 1e-5);
  CHECK_NEAR(hi[2], 2.0, 1e-5);
  /* scale 2: the cube's area is 6 * 4 */
  double area = 0;
  for (uint32_t t = 0; t < m->triangle_count; t++) {
    const float *a = m->positions + 3 * m->indices[3 * t],
                *b = m->positions + 3 * m->indices[3 * t + 1],
                *c = m->positions + 3 * m->indices[3 * t + 2];
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
           e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2],
           z = e1[0] * e2[1] - e1[1] * e2[0];
    area += 0.5 * sqrt(x * x + y * y + z * z);
  }
  CHECK_NEAR(area, 24.0, 1e-4);
  CHECK(tt_scene_light_count(s) == 0);
  CHECK(tt_scene_camera(s)->width == 64 && tt_scene_camera(s)->height == 48);
  tt_scene_destroy(s);

  /* split mode: one mesh per OBJ group, named after it, placed by a row-major matrix */
  st = tt_scene_load(src_path("tests/data/scenes/obj-split.json", path, sizeof path), &s);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (!s) return;
  CHECK(tt_scene_mesh_count(s) == 2);
  CHECK(tt_scene_triangle_count(s) == 12);
  for (uint32_t i = 0; i < tt_scene_mesh_count(s); i++)
    CHECK(strncmp(tt_scene_mesh(s, i)->name, "cube/", 5) == 0);
  tt_scene_bounds(s, lo, hi);
  CHECK_NEAR(lo[2], -5.0, 1e-5);
  CHECK_NEAR(hi[2], -4.0, 1e-5);
  CHECK_NEAR(hi[0], 1.0, 1e-5);
  tt_scene_destroy(s);
}

/* glTF 2.0 as JSON with an embedded buffer and as GLB: one triangle (0,0,0) (2,0,0) (0,1,0)
 * of area 1, placed by its node's translation to z = 3, named by its mesh in split mode
 * (tests/data/scenes/tri.gltf and tri.glb hold the same asset). */
static void test_gltf(void) {
  char base[1200];
  src_path("tests/data/scenes", base, sizeof base);
  static const char *const files[] = {"tri.gltf", "tri.glb"};
  for (int i = 0; i < 2; i++) {
    char json[512];
    snprintf(json, sizeof json,
             "{\"version\": 1, \"camera\": {\"position\": [0, 0, 10], \"target\": [0, 0, 0]},"
             " \"materials\": {\"m\": {}}, \"meshes\": [{\"name\": \"g\", \"material\": \"m\","
             " \"file\": \"%s\", \"split\": true}]}",
             files[i]);
    tt_scene *s = load_text(json, base);
    if (!s) continue;
    CHECK_MSG(tt_scene_triangle_count(s) == 1, "%s", files[i]);
    CHECK(tt_scene_mesh_count(s) == 1);
    CHECK_MSG(strcmp(tt_scene_mesh(s, 0)->name, "g/tri") == 0, "%s: %s", files[i],
              tt_scene_mesh(s, 0)->name);
    float lo[3], hi[3];
    tt_scene_bounds(s, lo, hi);
    CHECK_NEAR(lo[0], 0.0, 1e-6);
    CHECK_NEAR(hi[0], 2.0, 1e-6);
    CHECK_NEAR(hi[1], 1.0, 1e-6);
    CHECK_NEAR(lo[2], 3.0, 1e-6);
    CHECK_NEAR(hi[2], 3.0, 1e-6);
    tt_scene_destroy(s);
  }
}

static void test_inline_transform_normals(void) {
  /* a unit right triangle in the xy plane with +z normals, scaled non-uniformly and
   * rotated; shading normals must stay perpendicular to the surface */
  const char *json =
      "{\"version\": 1, \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0]},"
      " \"materials\": {\"m\": {}},"
      " \"meshes\": [{\"material\": \"m\", \"positions\": [0,0,0, 1,0,0, 0,1,1],"
      "   \"normals\": [[0,-0.7071,0.7071],[0,-0.7071,0.7071],[0,-0.7071,0.7071]],"
      "   \"uvs\": [[0,0],[1,0],[0,1]],"
      "   \"transform\": {\"scale\": [3, 1, 0.5], \"rotate\": [0, 0, 30], \"translate\": [1, 2, "
      "3]}},"
      "  {\"material\": \"m\", \"positions\": [0,0,0, 1,0,0, 0,1,0],"
      "   \"matrix\": [-1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1], \"normals\": [0,0,1, 0,0,1, 0,0,1]}]}";
  tt_scene *s = load_text(json, NULL);
  if (!s) return;
  const tt_mesh *m = tt_scene_mesh(s, 0);
  CHECK(strcmp(m->name, "mesh[0]") == 0);
  CHECK(m->normals != NULL && m->uvs != NULL);
  CHECK_NEAR(m->uvs[2], 1.0, 0);
  const float *p = m->positions;
  float e1[3] = {p[3] - p[0], p[4] - p[1], p[5] - p[2]},
        e2[3] = {p[6] - p[0], p[7] - p[1], p[8] - p[2]};
  float gn[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                 e1[0] * e2[1] - e1[1] * e2[0]};
  for (int v = 0; v < 3; v++) {
    const float *n = m->normals + 3 * v;
    CHECK_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-5);
    CHECK_NEAR(n[0] * e1[0] + n[1] * e1[1] + n[2] * e1[2], 0.0, 1e-4);
    CHECK_NEAR(n[0] * e2[0] + n[1] * e2[1] + n[2] * e2[2], 0.0, 1e-4);
    CHECK(n[0] * gn[0] + n[1] * gn[1] + n[2] * gn[2] > 0); /* same side as the face */
  }
  CHECK_NEAR(p[0], 1.0, 1e-6); /* vertex 0 is the origin, only translated */
  CHECK_NEAR(p[1], 2.0, 1e-6);
  CHECK_NEAR(p[2], 3.0, 1e-6);
  /* the mirroring matrix flips the winding so the face normal still agrees with +z */
  const tt_mesh *r = tt_scene_mesh(s, 1);
  const float *q = r->positions;
  const uint32_t *ix = r->indices;
  float f1[3], f2[3];
  for (int a = 0; a < 3; a++) {
    f1[a] = q[3 * ix[1] + a] - q[3 * ix[0] + a];
    f2[a] = q[3 * ix[2] + a] - q[3 * ix[0] + a];
  }
  CHECK(f1[0] * f2[1] - f1[1] * f2[0] > 0);
  CHECK_NEAR(r->normals[2], 1.0, 1e-6);
  CHECK_NEAR(q[3 * 1], -1.0, 1e-6);
  tt_scene_destroy(s);
}

static void test_camera_path(void) {
  const char *json =
      "{\"version\": 1,"
      " \"camera\": {\"position\": [0, 0, 10], \"target\": [0, 0, 0], \"fov\": 50, \"resolution\": "
      "[32, 16],"
      "  \"path\": [{\"time\": 0, \"position\": [0, 0, 10], \"fov\": 40},"
      "            {\"time\": 1, \"position\": [10, 0, 0], \"target\": [1, 0, 0], \"up\": [0, 2, "
      "0], \"fov\": 60},"
      "            {\"time\": 3, \"position\": [0, 5, -10], \"up\": [1, 1, 0]},"
      "            {\"time\": 4, \"position\": [-10, 0, 0], \"fov\": 30}]},"
      " \"materials\": {\"m\": {}},"
      " \"meshes\": [{\"material\": \"m\", \"positions\": [[-1,-1,0],[1,-1,0],[0,1,0]]}]}";
  tt_scene *s = load_text(json, NULL);
  if (!s) return;
  const tt_camera *still = tt_scene_camera(s);
  CHECK(still->key_count == 4 && still->keys != NULL);
  const tt_camera_key *k = still->keys;
  CHECK_NEAR(k[1].up[1], 2.0, 0);  /* keys are stored as given */
  CHECK_NEAR(k[2].fov_y, 50.0, 0); /* missing fields inherit the still camera */
  tt_camera c;
  for (int i = 0; i < 4; i++) {
    tt_scene_camera_at(s, k[i].time, &c);
    double ul = sqrt((double)k[i].up[0] * k[i].up[0] + (double)k[i].up[1] * k[i].up[1] +
                     (double)k[i].up[2] * k[i].up[2]);
    for (int a = 0; a < 3; a++) {
      CHECK_NEAR(c.position[a], k[i].position[a], 1e-6);
      CHECK_NEAR(c.target[a], k[i].target[a], 1e-6);
      CHECK_NEAR(c.up[a], k[i].up[a] / ul, 1e-6);
    }
    CHECK_NEAR(c.fov_y, k[i].fov_y, 1e-6);
    CHECK(c.width == 32 && c.height == 16);
  }
  /* clamped at both ends */
  tt_scene_camera_at(s, -5.0, &c);
  CHECK_NEAR(c.position[2], 10.0, 1e-6);
  CHECK_NEAR(c.fov_y, 40.0, 1e-6);
  tt_scene_camera_at(s, 99.0, &c);
  CHECK_NEAR(c.position[0], -10.0, 1e-6);
  CHECK_NEAR(c.fov_y, 30.0, 1e-6);
  /* between keys: continuous, unit up, fov between neighbours for a monotone stretch */
  tt_scene_camera_at(s, 0.5, &c);
  CHECK(c.position[0] > 0 && c.position[0] < 10);
  CHECK(c.fov_y > 40 && c.fov_y < 60);
  CHECK_NEAR(c.up[0] * c.up[0] + c.up[1] * c.up[1] + c.up[2] * c.up[2], 1.0, 1e-5);
  tt_camera a, b;
  tt_scene_camera_at(s, 1.0 - 1e-4, &a);
  tt_scene_camera_at(s, 1.0 + 1e-4, &b);
  CHECK_NEAR(a.position[0], b.position[0], 1e-2);
  CHECK_NEAR(a.position[2], b.position[2], 1e-2);

  /* set_camera replaces the still pose only */
  tt_camera pose = *still;
  pose.position[0] = 3.0f;
  pose.fov_y = 20.0f;
  pose.width = 999;
  tt_scene_set_camera(s, &pose);
  CHECK_NEAR(tt_scene_camera(s)->position[0], 3.0, 0);
  CHECK_NEAR(tt_scene_camera(s)->fov_y, 20.0, 0);
  CHECK(tt_scene_camera(s)->width == 32);
  tt_scene_destroy(s);

  /* no path: camera_at returns the still camera at any time */
  s = load_text("{\"version\": 1, \"camera\": {\"position\": [1, 2, 3], \"target\": [0, 0, 0]},"
                " \"materials\": {\"m\": {}}, \"meshes\": [{\"material\": \"m\", \"positions\": "
                "[0,0,0, 1,0,0, 0,1,0]}]}",
                NULL);
  if (!s) return;
  tt_scene_camera_at(s, 12.5, &c);
  CHECK_NEAR(c.position[1], 2.0, 0);
  CHECK_NEAR(c.fov_y, 45.0, 0); /* default fov */
  CHECK(c.width == 256 && c.height == 256);
  const tt_render_settings *rs = tt_scene_settings(s);
  CHECK(rs->spp == 16 && rs->max_depth == 3 && rs->seed == 1);
  tt_scene_destroy(s);
}

static void test_scene_id(void) {
  char path[1200];
  src_path("scenes/cornell-box/scene.json", path, sizeof path);
  tt_scene *a = NULL, *b = NULL, *c = NULL;
  CHECK(tt_scene_load(path, &a) == TT_OK);
  CHECK(tt_scene_load(path, &b) == TT_OK);
  size_t len;
  char *text = tt_test_read_file(path, &len);
  CHECK(text != NULL);
  if (!a || !b || !text) goto done;
  CHECK(strlen(tt_scene_id(a)) == 16);
  CHECK(strspn(tt_scene_id(a), "0123456789abcdef") == 16);
  CHECK(strcmp(tt_scene_id(a), tt_scene_id(b)) == 0);
  /* the id is about content, not where it was loaded from */
  CHECK(tt_scene_load_json(text, len, "elsewhere.json", NULL, &c) == TT_OK);
  if (c) CHECK(strcmp(tt_scene_id(a), tt_scene_id(c)) == 0);
  tt_scene_destroy(c);
  c = NULL;
  /* one changed albedo changes the id */
  char *at = strstr(text, "0.73, 0.73, 0.73");
  CHECK(at != NULL);
  if (at) {
    memcpy(at, "0.74", 4);
    CHECK(tt_scene_load_json(text, len, path, NULL, &c) == TT_OK);
    if (c) CHECK(strcmp(tt_scene_id(a), tt_scene_id(c)) != 0);
    /* the camera is state, not content: moving it keeps the id */
    tt_camera cam = *tt_scene_camera(a);
    cam.position[0] += 10;
    tt_scene_set_camera(a, &cam);
    CHECK(strcmp(tt_scene_id(a), tt_scene_id(b)) == 0);
  }
done:
  free(text);
  tt_scene_destroy(a);
  tt_scene_destroy(b);
  tt_scene_destroy(c);
}

/* Writes `n` bytes to dir/name; 0 on success. */
static int put_file(const char *dir, const char *name, const void *data, size_t n) {
  char path[1200];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "wb");
  if (!f) return -1;
  size_t w = fwrite(data, 1, n, f);
  return fclose(f) == 0 && w == n ? 0 : -1;
}

/* A textured scene loaded from two folders (another checkout, another absolute path) has one
 * id: textures count by content. Each change moves only its own part of the id. */
static void test_scene_id_location(void) {
  static const char scene[] =
      "{\"version\": 1, \"camera\": {\"position\": [0, 0, 3], \"target\": [0, 0, 0]},"
      " \"materials\": {\"m\": {\"albedo\": [0.5, 0.5, 0.5], \"texture\": \"tex.ppm\"}},"
      " \"meshes\": [{\"material\": \"m\", \"positions\": [0,0,0, 1,0,0, 0,1,0],"
      " \"uvs\": [0,0, 1,0, 0,1]}]}";
  static const char tex_a[] = "P3\n2 1\n255\n255 0 0 0 255 0\n";
  static const char tex_b[] = "P3\n2 1\n255\n255 0 0 0 0 255\n";
  char d1[] = "/tmp/tt_scene_id_XXXXXX", d2[] = "/tmp/tt_scene_id_XXXXXX", p1[1200], p2[1200];
  CHECK(mkdtemp(d1) != NULL && mkdtemp(d2) != NULL);
  CHECK(put_file(d1, "scene.json", scene, strlen(scene)) == 0);
  CHECK(put_file(d1, "tex.ppm", tex_a, strlen(tex_a)) == 0);
  CHECK(put_file(d2, "scene.json", scene, strlen(scene)) == 0);
  CHECK(put_file(d2, "tex.ppm", tex_a, strlen(tex_a)) == 0);
  snprintf(p1, sizeof p1, "%s/scene.json", d1);
  snprintf(p2, sizeof p2, "%s/scene.json", d2);
  tt_scene *a = NULL, *b = NULL;
  CHECK(tt_scene_load(p1, &a) == TT_OK);
  CHECK(tt_scene_load(p2, &b) == TT_OK);
  if (a && b) {
    CHECK(tt_scene_texture_count(a) == 1);
    CHECK_MSG(strcmp(tt_scene_id(a), tt_scene_id(b)) == 0, "same scene in two folders: %s vs %s",
              tt_scene_id(a), tt_scene_id(b));
    for (int p = 0; p < TT_SCENE_PART_COUNT; p++)
      CHECK(strcmp(tt_scene_id_part(a, (tt_scene_part)p), tt_scene_id_part(b, (tt_scene_part)p)) ==
            0);
  }
  tt_scene_destroy(b);
  b = NULL;
  /* another texture image: the id and the textures part change, nothing else */
  CHECK(put_file(d2, "tex.ppm", tex_b, strlen(tex_b)) == 0);
  CHECK(tt_scene_load(p2, &b) == TT_OK);
  if (a && b) {
    CHECK(strcmp(tt_scene_id(a), tt_scene_id(b)) != 0);
    for (int p = 0; p < TT_SCENE_PART_COUNT; p++) {
      int same =
          strcmp(tt_scene_id_part(a, (tt_scene_part)p), tt_scene_id_part(b, (tt_scene_part)p)) == 0;
      CHECK_MSG(same == (p != TT_SCENE_PART_TEXTURES), "part %s",
                tt_scene_part_name((tt_scene_part)p));
    }
  }
  CHECK(tt_scene_id_part(a, TT_SCENE_PART_COUNT) == NULL);
  CHECK(tt_scene_part_name(TT_SCENE_PART_COUNT) == NULL);
  CHECK(strcmp(tt_scene_part_name(TT_SCENE_PART_GEOMETRY), "geometry") == 0);
  tt_scene_destroy(a);
  tt_scene_destroy(b);
  char path[1200];
  const char *dirs[2] = {d1, d2};
  for (int i = 0; i < 2; i++) {
    snprintf(path, sizeof path, "%s/scene.json", dirs[i]);
    remove(path);
    snprintf(path, sizeof path, "%s/tex.ppm", dirs[i]);
    remove(path);
    remove(dirs[i]);
  }
}

static void test_materials_and_lights(void) {
  /* two unit quads of equal area: diffuse and mirror -> diffuse ratio 0.5 */
  const char *json =
      "{\"version\": 1, \"_note\": \"comment keys are ignored\","
      " \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0]},"
      " \"render\": {\"spp\": 4, \"maxDepth\": 7, \"seed\": 42, \"timeBudget\": 1.5},"
      " \"materials\": {"
      "   \"d\": {\"type\": \"diffuse\", \"albedo\": 0.25, \"roughness\": 0.3, \"texture\": "
      "\"no-such-texture.png\"},"
      "   \"s\": {\"type\": \"mirror\", \"specular\": [0.9, 0.8, 0.7]},"
      "   \"c\": {\"type\": \"conductor\", \"alpha\": [0.2, 0.05], \"eta\": [0.2, 0.9, 1.1], "
      "\"k\": [3.9, 2.4, 2.1]},"
      "   \"g\": {\"type\": \"dielectric\", \"ior\": 1.33},"
      "   \"p\": {\"type\": \"plastic\", \"alpha\": 0.3, \"twoSided\": true}},"
      " \"meshes\": [{\"material\": \"d\", \"positions\": [[0,0,0],[1,0,0],[1,1,0],[0,1,0]], "
      "\"indices\": [0,1,2, 0,2,3]},"
      "              {\"material\": \"s\", \"positions\": [[0,0,1],[1,0,1],[1,1,1],[0,1,1]], "
      "\"indices\": [[0,1,2],[0,2,3]]}],"
      " \"lights\": [{\"type\": \"environment\", \"radiance\": [0.1, 0.2, 0.3]},"
      "             {\"type\": \"point\", \"position\": [1, 2, 3], \"intensity\": 5},"
      "             {\"type\": \"spot\", \"position\": [0, 5, 0], \"target\": [0, 0, 0], "
      "\"intensity\": [1, 1, 1], \"angle\": 60, \"innerAngle\": 0},"
      "             {\"type\": \"distant\", \"direction\": [0, -2, 0], \"irradiance\": [3, 3, 3]},"
      "             {\"type\": \"environment\", \"_x\": 1, \"image\": \"sky.exr\"}]}";
  /* two environments are an error; drop the last one for the positive test */
  tt_scene *s = NULL;
  CHECK(tt_scene_load_json(json, strlen(json), "m.json", NULL, &s) == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(), "m.json: lights[4]: only one environment light");
  char *fixed = malloc(strlen(json) + 1);
  strcpy(fixed, json);
  char *cut = strstr(fixed, ",             {\"type\": \"environment\", \"_x\"");
  CHECK(cut != NULL);
  if (!cut) {
    free(fixed);
    return;
  }
  strcpy(cut, "]}");
  s = load_text(fixed, NULL);
  free(fixed);
  if (!s) return;
  const tt_render_settings *rs = tt_scene_settings(s);
  CHECK(rs->spp == 4 && rs->max_depth == 7 && rs->seed == 42);
  CHECK_NEAR(rs->time_budget_s, 1.5, 0);
  CHECK(tt_scene_material_count(s) == 5);
  const tt_material *d = tt_scene_material(s, 0);
  CHECK(d->type == TT_MATERIAL_DIFFUSE && d->albedo_texture == -1); /* missing texture: warning */
  CHECK_NEAR(d->albedo[2], 0.25, 1e-7);
  CHECK_NEAR(d->roughness, 0.3, 1e-7);
  const tt_material *c = tt_scene_material(s, 2);
  CHECK(c->type == TT_MATERIAL_CONDUCTOR);
  CHECK_NEAR(c->alpha[0], 0.2, 1e-7);
  CHECK_NEAR(c->alpha[1], 0.05, 1e-7);
  CHECK_NEAR(c->k[1], 2.4, 1e-6);
  CHECK(tt_scene_material(s, 3)->type == TT_MATERIAL_DIELECTRIC);
  CHECK_NEAR(tt_scene_material(s, 3)->ior, 1.33, 1e-6);
  CHECK_NEAR(tt_scene_material(s, 3)->alpha[0], 0.0, 0);
  const tt_material *p = tt_scene_material(s, 4);
  CHECK(p->type == TT_MATERIAL_PLASTIC && p->two_sided == 1);
  CHECK_NEAR(p->alpha[1], 0.3, 1e-7);
  CHECK(tt_scene_light_count(s) == 4);
  const tt_light *l = tt_scene_light(s, 0);
  CHECK(l->type == TT_LIGHT_ENV_CONSTANT);
  CHECK_NEAR(l->radiance[2], 0.3, 1e-7);
  l = tt_scene_light(s, 1);
  CHECK(l->type == TT_LIGHT_POINT);
  CHECK_NEAR(l->radiance[1], 5.0, 0);
  CHECK_NEAR(l->position[2], 3.0, 0);
  l = tt_scene_light(s, 2);
  CHECK(l->type == TT_LIGHT_SPOT);
  CHECK_NEAR(l->direction[1], -1.0, 1e-6);
  CHECK_NEAR(l->cos_outer, 0.5, 1e-6);
  CHECK_NEAR(l->cos_inner, 1.0, 1e-6);
  l = tt_scene_light(s, 3);
  CHECK(l->type == TT_LIGHT_DISTANT);
  CHECK_NEAR(l->direction[1], -1.0, 1e-6);
  double ind[TT_SCENE_INDICATOR_COUNT];
  tt_scene_indicators(s, ind);
  CHECK_NEAR(ind[10], 0.5, 1e-9);
  CHECK_NEAR(ind[2], 4, 0);
  CHECK_NEAR(ind[13], 0, 0); /* no area lights */
  /* D^2 = 1 + 1 + 1 = 3; total area 2 */
  CHECK_NEAR(ind[11], sqrt(3.0), 1e-6);
  CHECK_NEAR(ind[12], 2.0 / 3.0, 1e-6);
  CHECK_NEAR(ind[14], 1.0 / 3.0, 1e-6);
  CHECK_NEAR(ind[15], 0.0, 1e-12); /* equal triangles everywhere */
  tt_scene_destroy(s);
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  snprintf(g_root, sizeof g_root, "%s", root ? root : "..");
  test_cornell();
  test_obj_transform();
  test_gltf();
  test_inline_transform_normals();
  test_camera_path();
  test_scene_id();
  test_scene_id_location();
  test_materials_and_lights();
  return tt_test_finish("scene_load");
}
