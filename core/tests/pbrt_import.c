/* pbrt-v4 importer: golden checks on the fixtures in tests/data/pbrt (every supported
 * directive, Include/Import, ObjectInstance, PLY variants, handedness and fov rules). */
#include <tunetrace/camera.h>
#include <tunetrace/scene.h>

#include "tt_test.h"

#define TT_PI 3.14159265358979323846

static char g_dir[4096];

/* Loads tests/data/pbrt/<name>; NULL (with a failed check) on error. */
static tt_scene *load(const char *name) {
  char path[4352];
  snprintf(path, sizeof path, "%s/%s", g_dir, name);
  tt_scene *s = NULL;
  tt_status st = tt_scene_load(path, &s);
  CHECK_MSG(st == TT_OK && s, "%s: %s", name, tt_last_error());
  return st == TT_OK ? s : NULL;
}

/* Material by name, or NULL. */
static const tt_material *mat(const tt_scene *s, const char *name) {
  for (uint32_t i = 0; i < tt_scene_material_count(s); i++)
    if (strcmp(tt_scene_material(s, i)->name, name) == 0) return tt_scene_material(s, i);
  CHECK_MSG(0, "no material named %s", name);
  return NULL;
}

/* The index-th mesh with this name (instances share names), or NULL. */
static const tt_mesh *mesh(const tt_scene *s, const char *name, int index) {
  for (uint32_t i = 0; i < tt_scene_mesh_count(s); i++)
    if (strcmp(tt_scene_mesh(s, i)->name, name) == 0 && index-- == 0) return tt_scene_mesh(s, i);
  CHECK_MSG(0, "no mesh named %s", name);
  return NULL;
}

/* Geometric normal (unnormalised) of triangle t. */
static void tri_normal(const tt_mesh *m, uint32_t t, double n[3]) {
  const float *a = m->positions + 3 * m->indices[3 * t],
              *b = m->positions + 3 * m->indices[3 * t + 1],
              *c = m->positions + 3 * m->indices[3 * t + 2];
  double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
         e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

/* Mean vertex position of a mesh. */
static void centroid(const tt_mesh *m, double c[3]) {
  c[0] = c[1] = c[2] = 0;
  for (uint32_t v = 0; v < m->vertex_count; v++)
    for (int k = 0; k < 3; k++) c[k] += m->positions[3 * v + k] / (double)m->vertex_count;
}

static void test_basic(void) {
  tt_scene *s = load("basic.pbrt");
  if (!s) return;
  /* 2 light + 2 floor + 1 mix + 2208 sphere + 64 disk + 2 bilinear + 16 loop + 6 PLY
   * + 2 x 3 instanced + 1 imported + 1 alpha-textured; the interface triangle is skipped */
  CHECK(tt_scene_triangle_count(s) == 2309);
  CHECK(tt_scene_mesh_count(s) == 16);
  CHECK(tt_scene_light_count(s) == 6);
  float lo[3], hi[3];
  tt_scene_bounds(s, lo, hi);
  CHECK_NEAR(lo[0], -10, 1e-5);
  CHECK_NEAR(lo[1], -1, 1e-5);
  CHECK_NEAR(lo[2], -40, 1e-5);
  CHECK_NEAR(hi[0], 10, 1e-5);
  CHECK_NEAR(hi[1], 5, 1e-5);
  CHECK_NEAR(hi[2], 30, 1e-5);

  /* camera, film, sampler, integrator; `Scale -1 1 1` means no mirroring */
  const tt_camera *c = tt_scene_camera(s);
  CHECK(c->width == 200 && c->height == 100);
  CHECK_NEAR(c->fov_y, 40, 1e-4); /* screenwindow height 2 = the default */
  CHECK_NEAR(c->position[0], 0, 1e-6);
  CHECK_NEAR(c->position[1], 1, 1e-6);
  CHECK_NEAR(c->position[2], -10, 1e-6);
  CHECK_NEAR(c->target[2] - c->position[2], 1, 1e-6);
  CHECK_NEAR(c->up[1], 1, 1e-6);
  CHECK(tt_scene_settings(s)->spp == 8);
  CHECK(tt_scene_settings(s)->max_depth == 7);

  /* materials */
  const tt_material *m = mat(s, "red");
  if (m) {
    CHECK(m->type == TT_MATERIAL_DIFFUSE);
    CHECK_NEAR(m->albedo[0], 0.8, 1e-6);
    CHECK_NEAR(m->albedo[2], 0.1, 1e-6);
    CHECK(m->albedo_texture == -1);
  }
  if ((m = mat(s, "plastic"))) {
    CHECK(m->type == TT_MATERIAL_PLASTIC);
    CHECK_NEAR(m->albedo[1], 0.5, 1e-6); /* the "scale" texture's 0.5 */
    CHECK_NEAR(m->alpha[0], 0.2, 1e-6);  /* remapped: sqrt(0.04) */
    CHECK_NEAR(m->ior, 1.5, 1e-6);
    CHECK(m->albedo_texture >= 0);
    if (m->albedo_texture >= 0) {
      const tt_texture *t = tt_scene_texture(s, (uint32_t)m->albedo_texture);
      CHECK_CONTAINS(t->path, "checker.png");
      CHECK(t->srgb == 1); /* pbrt-v4: PNG defaults to sRGB */
    }
  }
  if ((m = mat(s, "linear"))) {
    CHECK(m->albedo_texture >= 0);
    if (m->albedo_texture >= 0) CHECK(tt_scene_texture(s, (uint32_t)m->albedo_texture)->srgb == 0);
  }
  CHECK(tt_scene_texture_count(s) == 2);
  if ((m = mat(s, "gold"))) {
    CHECK(m->type == TT_MATERIAL_CONDUCTOR);
    CHECK_NEAR(m->eta[0], 0.143119, 1e-5);
    CHECK_NEAR(m->k[2], 1.60322, 1e-5);
    CHECK_NEAR(m->alpha[0], 0.1, 1e-6);
    CHECK_NEAR(m->alpha[1], 0.3, 1e-6);
  }
  if ((m = mat(s, "rawrough"))) {
    CHECK_NEAR(m->alpha[0], 0.3, 1e-6); /* remaproughness false */
    CHECK_NEAR(m->eta[1], 0.9, 1e-6);
    CHECK_NEAR(m->k[0], 3.9, 1e-6);
  }
  if ((m = mat(s, "spd"))) {
    for (int i = 0; i < 3; i++) {
      CHECK_NEAR(m->eta[i], 2.0, 1e-3); /* flat .spd file */
      CHECK_NEAR(m->k[i], 1.0, 1e-3);   /* flat inline pairs */
    }
  }
  if ((m = mat(s, "glass"))) {
    CHECK(m->type == TT_MATERIAL_DIELECTRIC);
    CHECK_NEAR(m->ior, 1.5168, 1e-4);
  }
  if ((m = mat(s, "water"))) {
    CHECK(m->type == TT_MATERIAL_DIELECTRIC);
    CHECK_NEAR(m->ior, 1.33, 1e-6);
  }
  if ((m = mat(s, "leaf"))) {
    CHECK(m->type == TT_MATERIAL_DIFFUSE);
    CHECK_NEAR(m->albedo[1], 0.4, 1e-6);
  }
  if ((m = mat(s, "fallback"))) {
    CHECK(m->albedo_texture == -1);
    CHECK_NEAR(m->albedo[0], 0.5, 1e-6);
  }
  if ((m = mat(s, "checks"))) {
    CHECK(m->albedo_texture == -1);
    CHECK_NEAR(m->albedo[0], 0.5, 1e-6);
  }
  if ((m = mat(s, "coated"))) {
    CHECK(m->type == TT_MATERIAL_CONDUCTOR);
    CHECK_NEAR(m->eta[0], 0.155265, 1e-5);
    CHECK_NEAR(m->alpha[0], 0.2, 1e-6); /* max(sqrt(0.04), sqrt(0.01)) */
  }

  /* mix picks the dominant material; anonymous Material directives are named by line */
  const tt_mesh *me = mesh(s, "trianglemesh@basic.pbrt:68", 0);
  if (me) CHECK(strcmp(tt_scene_material(s, me->material)->name, "red") == 0);
  me = mesh(s, "sphere@basic.pbrt:75", 0);
  if (me) {
    const tt_material *sm = tt_scene_material(s, me->material);
    CHECK(sm->type == TT_MATERIAL_DIELECTRIC);
    CHECK_NEAR(sm->ior, 1.4, 1e-6);
    CHECK(me->triangle_count == 2208 && me->normals != NULL && me->uvs != NULL);
    int outward = 1;
    double ctr[3] = {3, 1, 0};
    for (uint32_t t = 0; t < me->triangle_count; t++) {
      double n[3];
      tri_normal(me, t, n);
      const float *a = me->positions + 3 * me->indices[3 * t];
      if (n[0] * (a[0] - ctr[0]) + n[1] * (a[1] - ctr[1]) + n[2] * (a[2] - ctr[2]) <= 0)
        outward = 0;
    }
    CHECK(outward);
    double cc[3];
    centroid(me, cc);
    CHECK_NEAR(cc[0], 3, 0.02);
    CHECK_NEAR(cc[1], 1, 1e-3); /* seam vertices are doubled */
  }
  /* disk: +z rotated to -y, then ReverseOrientation -> faces +y */
  if ((me = mesh(s, "disk@basic.pbrt:82", 0))) {
    double n[3];
    tri_normal(me, 0, n);
    CHECK(me->triangle_count == 64);
    CHECK(n[1] > 0 && fabs(n[0]) < 1e-6 && fabs(n[2]) < 1e-6);
  }
  if ((me = mesh(s, "bilinearmesh@basic.pbrt:87", 0))) {
    double n[3];
    tri_normal(me, 0, n);
    CHECK(me->triangle_count == 2 && n[2] > 0);
    CHECK_NEAR(me->positions[2], 5, 1e-6); /* TransformBegin's Translate */
  }
  if ((me = mesh(s, "loopsubdiv@basic.pbrt:92", 0))) {
    CHECK(me->triangle_count == 16 && me->vertex_count == 10 && me->normals != NULL);
    for (uint32_t v = 0; v < me->vertex_count * 3; v++)
      CHECK(me->positions[v] >= -1e-5 && me->positions[v] <= 2.0f);
  }
  /* the area light: emission = L * scale, one-sided, facing -y like pbrt's normal */
  int area = 0;
  for (uint32_t i = 0; i < tt_scene_light_count(s); i++) {
    const tt_light *l = tt_scene_light(s, i);
    switch (l->type) {
    case TT_LIGHT_AREA: {
      area++;
      CHECK_NEAR(l->radiance[0], 4, 1e-6);
      CHECK_NEAR(l->radiance[2], 12, 1e-6);
      CHECK_NEAR(l->area, 4, 1e-5);
      const tt_mesh *lm = tt_scene_mesh(s, l->mesh);
      const tt_material *em = tt_scene_material(s, lm->material);
      CHECK(em->two_sided == 0);
      CHECK(em->type == TT_MATERIAL_DIFFUSE && fabs(em->albedo[0] - 0.8) < 1e-6);
      double n[3];
      tri_normal(lm, 0, n);
      CHECK(n[1] < 0);
      break;
    }
    case TT_LIGHT_POINT:
      if (l->radiance[0] == 10) {
        CHECK_NEAR(l->position[0], 1, 1e-6);
        CHECK_NEAR(l->position[2], 3, 1e-6);
        CHECK_NEAR(l->radiance[2], 30, 1e-6);
      } else { /* CoordSysTransform "lamp" */
        CHECK_NEAR(l->position[1], 3, 1e-6);
        CHECK_NEAR(l->position[0], 0, 1e-6);
      }
      break;
    case TT_LIGHT_SPOT: {
      CHECK_NEAR(l->position[1], 5, 1e-6);
      CHECK_NEAR(l->direction[1], -1, 1e-6);
      CHECK_NEAR(l->cos_outer, cos(40 * TT_PI / 180), 1e-6);
      CHECK_NEAR(l->cos_inner, cos(30 * TT_PI / 180), 1e-6);
      /* blackbody normalised to luminance 1, times scale 2; 6500 K is near white */
      double y = 0.2126 * l->radiance[0] + 0.7152 * l->radiance[1] + 0.0722 * l->radiance[2];
      CHECK_NEAR(y, 2.0, 0.02);
      CHECK(fabs(l->radiance[0] - l->radiance[2]) < 0.3);
      break;
    }
    case TT_LIGHT_DISTANT: CHECK_NEAR(l->direction[1], -1, 1e-6); break;
    case TT_LIGHT_ENV_CONSTANT:
      CHECK_NEAR(l->radiance[0], 0.1, 1e-6);
      CHECK_NEAR(l->radiance[2], 0.3, 1e-6);
      break;
    default: CHECK_MSG(0, "unexpected light type %d", (int)l->type);
    }
  }
  CHECK(area == 1);

  /* PLY variants */
  if ((me = mesh(s, "quad_le.ply", 0))) {
    CHECK(me->vertex_count == 4 && me->triangle_count == 2 && !me->normals);
    CHECK_NEAR(me->positions[2], -5, 1e-6);
    CHECK(strcmp(tt_scene_material(s, me->material)->name, "water") == 0);
  }
  if ((me = mesh(s, "ascii.ply", 0))) {
    CHECK(me->vertex_count == 5 && me->triangle_count == 3 && me->normals && me->uvs);
    if (me->uvs) {
      CHECK_NEAR(me->uvs[8], 0.5, 1e-6);
      CHECK_NEAR(me->uvs[9], 1.5, 1e-6);
    }
  }
  if ((me = mesh(s, "tri_be.ply", 0))) {
    CHECK(me->vertex_count == 3 && me->triangle_count == 1);
    CHECK_NEAR(me->positions[3], 2, 1e-6);
    CHECK_NEAR(me->positions[5], -3, 1e-6);
  }
  /* ObjectInstance: two flattened copies of the included object */
  const tt_mesh *i0 = mesh(s, "trianglemesh@objects.pbrt:4", 0),
                *i1 = mesh(s, "trianglemesh@objects.pbrt:4", 1);
  if (i0 && i1) {
    CHECK_NEAR(i0->positions[2], 20, 1e-6);
    CHECK_NEAR(i1->positions[2], 30, 1e-6);
    CHECK(strcmp(tt_scene_material(s, i0->material)->name, "red") == 0);
  }
  CHECK(mesh(s, "../quad_le.ply", 1) != NULL);
  /* Import */
  if ((me = mesh(s, "trianglemesh@imported.pbrt:3", 0))) {
    CHECK_NEAR(me->positions[2], -40, 1e-6);
    CHECK(strcmp(tt_scene_material(s, me->material)->name, "checks") == 0);
  }
  tt_scene_destroy(s);
}

/* Rough dielectric: roughness / uroughness / vroughness -> alpha as for conductor. */
static void test_rough_glass(void) {
  tt_scene *s = load("rough-glass.pbrt");
  if (!s) return;
  const tt_material *m;
  if ((m = mat(s, "frosted"))) {
    CHECK(m->type == TT_MATERIAL_DIELECTRIC);
    CHECK_NEAR(m->ior, 1.5, 1e-6);
    CHECK_NEAR(m->alpha[0], 0.2, 1e-6);
    CHECK_NEAR(m->alpha[1], 0.2, 1e-6); /* remapped: sqrt(0.04) */
  }
  if ((m = mat(s, "aniso"))) {
    CHECK(m->type == TT_MATERIAL_DIELECTRIC);
    CHECK_NEAR(m->ior, 1.33, 1e-6);
    CHECK_NEAR(m->alpha[0], 0.1, 1e-6);
    CHECK_NEAR(m->alpha[1], 0.3, 1e-6);
  }
  if ((m = mat(s, "rawglass"))) {
    CHECK(m->type == TT_MATERIAL_DIELECTRIC);
    CHECK_NEAR(m->alpha[0], 0.3, 1e-6);
    CHECK_NEAR(m->alpha[1], 0.3, 1e-6); /* remaproughness false */
  }
  if ((m = mat(s, "clamped"))) {
    CHECK_NEAR(m->alpha[0], 1.0, 1e-6);
    CHECK_NEAR(m->alpha[1], 1.0, 1e-6);
  }
  if ((m = mat(s, "smooth"))) {
    CHECK(m->alpha[0] == 0.0f && m->alpha[1] == 0.0f);
  }
  if ((m = mat(s, "thin"))) {
    CHECK(m->type == TT_MATERIAL_DIELECTRIC);
    CHECK_NEAR(m->ior, 1.4, 1e-6);
    CHECK(m->alpha[0] == 0.0f && m->alpha[1] == 0.0f); /* thindielectric stays smooth */
  }
  tt_scene_destroy(s);
}

/* Projects the centroid of mesh i through the scene camera. */
static void project(const tt_scene *s, uint32_t i, float *fx, float *fy) {
  tt_camera_frame f;
  CHECK(tt_camera_frame_init(&f, tt_scene_camera(s)) == TT_OK);
  double c[3];
  centroid(tt_scene_mesh(s, i), c);
  float p[3] = {(float)c[0], (float)c[1], (float)c[2]}, depth;
  CHECK(tt_camera_project(&f, p, fx, fy, &depth));
}

static void test_handedness(void) {
  tt_scene *s = load("handed.pbrt");
  if (s) {
    float fx, fy;
    project(s, 0, &fx, &fy); /* world +x: pbrt's right */
    CHECK_MSG(fx > 60 && fabs(fy - 100) < 1, "fx %g fy %g", fx, fy);
    project(s, 1, &fx, &fy); /* world +y: the top */
    CHECK_MSG(fy < 90 && fabs(fx - 50) < 1, "fx %g fy %g", fx, fy);
    /* portrait 100x200 with fov 60 on the short (horizontal) side */
    CHECK_NEAR(tt_scene_camera(s)->fov_y, 2 * atan(tan(30 * TT_PI / 180) * 2) * 180 / TT_PI, 1e-3);
    /* pbrt's projection: x = tan(30) * 2 / 5 * 50 px per unit... the triangle at x = 2,
     * depth 5 lands at 50 + 50 * (2 / 5) / tan(30 deg) */
    project(s, 0, &fx, &fy);
    CHECK_NEAR(fx, 50 + 50 * 0.4 / tan(30 * TT_PI / 180), 0.05);
    tt_scene_destroy(s);
  }
  s = load("handed-flip.pbrt");
  if (s) {
    float fx, fy;
    project(s, 0, &fx, &fy); /* Scale -1 1 1: world +x is on pbrt's left */
    CHECK_MSG(fx < 100 && fabs(fy - 50) < 1, "fx %g fy %g", fx, fy);
    project(s, 1, &fx, &fy);
    CHECK(fy < 50);
    CHECK_NEAR(tt_scene_camera(s)->fov_y, 60, 1e-4); /* landscape: fov is vertical */
    float lo[3], hi[3];
    tt_scene_bounds(s, lo, hi);
    CHECK_NEAR(hi[0], 2.1, 1e-6); /* no mirroring needed */
    tt_scene_destroy(s);
  }
  s = load("transform.pbrt");
  if (s) {
    const tt_mesh *m = tt_scene_mesh(s, 0);
    /* Transform (translation in the last column), ConcatTransform scale 2; mirrored x */
    CHECK_NEAR(m->positions[3], -12, 1e-5);
    CHECK_NEAR(m->positions[4], 20, 1e-5);
    CHECK_NEAR(m->positions[7], 22, 1e-5);
    CHECK_NEAR(m->positions[8], 30, 1e-5);
    m = tt_scene_mesh(s, 1);
    CHECK_NEAR(m->positions[0], 0, 1e-6);
    CHECK_NEAR(m->positions[2], 0, 1e-6);                                          /* Identity */
    CHECK(tt_scene_camera(s)->width == 1280 && tt_scene_camera(s)->height == 720); /* defaults */
    CHECK_NEAR(tt_scene_camera(s)->fov_y, 90, 1e-4);
    tt_scene_destroy(s);
  }
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  snprintf(g_dir, sizeof g_dir, "%s/tests/data/pbrt", root ? root : ".");
  test_basic();
  test_handedness();
  test_rough_glass();
  return tt_test_finish("pbrt_import");
}
