/* pbrt-v4 animated transforms (ActiveTransform StartTime/EndTime/All, TransformTimes): a
 * shape whose start- and end-time transforms differ moves between them over TransformTimes
 * (linear translation, slerp rotation, linear axis-aligned scale, clamped outside), a still
 * is the start pose, and the pose at any time equals a static file placed by the transform
 * pbrt interpolates to (written by hand, compared vertex by vertex). Mirrors, a constant
 * scale that is not axis-aligned, ObjectInstance and TransformEnd/AttributeEnd keep both
 * transforms. Bad input (end before start, NaN, no time span, shear in motion, a mirror at
 * one end only, an unknown ActiveTransform) is refused naming the file and line, and so is a
 * scene.json wrapper whose camera path is shorter than the pbrt animation it imports. An
 * animated Camera becomes a camera path with pbrt's interpolated poses. Every
 * pbrt file is written by the test into a temporary folder. */
#include <tunetrace/scene.h>

#include "tt_test.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

static char g_dir[64];

#define HEAD "LookAt 0 -10 2  0 0 0  0 0 1\nCamera \"perspective\" \"float fov\" [40]\nWorldBegin\n"
#define TRI                                                                                        \
  "Shape \"trianglemesh\" \"point3 P\" [1 0 0  0 1 0  0 0 1  2 1 1] \"integer indices\" "          \
  "[0 1 2  1 3 2]\n"

/* Writes `text` to DIR/name and loads it; NULL when the load fails (message in *err). */
static tt_scene *load_text(const char *name, const char *text, char *err, size_t n) {
  char path[256];
  snprintf(path, sizeof path, "%s/%s", g_dir, name);
  FILE *f = fopen(path, "w");
  if (!f) return NULL;
  fputs(text, f);
  fclose(f);
  tt_scene *s = NULL;
  if (tt_scene_load(path, &s) != TT_OK) {
    if (err) snprintf(err, n, "%s", tt_last_error());
    return NULL;
  }
  return s;
}

static tt_scene *load_ok(const char *name, const char *text) {
  char err[1024] = "";
  tt_scene *s = load_text(name, text, err, sizeof err);
  CHECK_MSG(s != NULL, "%s: %s", name, err);
  return s;
}

/* Every vertex of every mesh of `a` (posed) equals `b`'s to `tol`; returns the largest
 * difference. */
static double max_diff(const tt_scene *a, const tt_scene *b) {
  double d = 0;
  CHECK(tt_scene_mesh_count(a) == tt_scene_mesh_count(b));
  for (uint32_t i = 0; i < tt_scene_mesh_count(a) && i < tt_scene_mesh_count(b); i++) {
    const tt_mesh *ma = tt_scene_mesh(a, i), *mb = tt_scene_mesh(b, i);
    CHECK(ma->vertex_count == mb->vertex_count && ma->triangle_count == mb->triangle_count);
    if (ma->vertex_count != mb->vertex_count) return INFINITY;
    for (size_t k = 0; k < 3 * (size_t)ma->vertex_count; k++)
      d = fmax(d, fabs((double)ma->positions[k] - mb->positions[k]));
    /* same winding: the triangles' indices agree */
    CHECK(memcmp(ma->indices, mb->indices, 12 * (size_t)ma->triangle_count) == 0);
  }
  return d;
}

/* anim at time t equals the static file `body` (the transform pbrt interpolates to). */
static void check_pose(const char *what, tt_scene *anim, double t, const char *body) {
  char text[2048];
  snprintf(text, sizeof text, HEAD "%s", body);
  tt_scene *ref = load_ok("ref.pbrt", text);
  CHECK_MSG(tt_scene_set_time(anim, t, t) == TT_OK, "%s", tt_last_error());
  if (ref) {
    double d = max_diff(anim, ref);
    CHECK_MSG(d < 2e-5, "%s at t = %g: vertices differ from the static placement by %g", what, t,
              d);
  }
  tt_scene_destroy(ref);
}

static void test_translate_rotate(void) {
  /* start: identity; end: translate (2, 4, 6) and rotate 90 about y; TransformTimes 0 1 */
  tt_scene *s =
      load_ok("tr.pbrt", HEAD "AttributeBegin\n"
                              "ActiveTransform EndTime\nTranslate 2 4 6\nRotate 90 0 1 0\n"
                              "ActiveTransform All\n" TRI "AttributeEnd\n" TRI);
  if (!s) return;
  CHECK(tt_scene_animated(s));
  CHECK(tt_scene_mesh(s, 0)->motion == TT_MESH_RIGID);
  CHECK(tt_scene_mesh(s, 1)->motion == TT_MESH_STATIC); /* AttributeEnd restored both CTMs */
  double t0, t1;
  tt_scene_time_range(s, &t0, &t1);
  CHECK(t0 == 0 && t1 == 1 && tt_scene_time(s) == 0);
  /* the still is the start pose */
  check_pose("start", s, 0.0, TRI TRI);
  check_pose("middle", s, 0.5,
             "AttributeBegin\nTranslate 1 2 3\nRotate 45 0 1 0\n" TRI "AttributeEnd\n" TRI);
  check_pose("quarter", s, 0.25,
             "AttributeBegin\nTranslate 0.5 1 1.5\nRotate 22.5 0 1 0\n" TRI "AttributeEnd\n" TRI);
  check_pose("end", s, 1.0,
             "AttributeBegin\nTranslate 2 4 6\nRotate 90 0 1 0\n" TRI "AttributeEnd\n" TRI);
  check_pose("after the end (clamped)", s, 7.0,
             "AttributeBegin\nTranslate 2 4 6\nRotate 90 0 1 0\n" TRI "AttributeEnd\n" TRI);
  /* the motion is real: the middle pose is not the start pose */
  CHECK(tt_scene_set_time(s, 0.5, 0.0) == TT_OK);
  CHECK(fabs(tt_scene_mesh(s, 0)->positions[2] - tt_scene_mesh(s, 0)->prev_positions[2]) > 0.5);
  tt_scene_destroy(s);
}

static void test_times_scale_mirror(void) {
  /* TransformTimes 2 4; a shared rotation, scale 1 -> 3 at the end, under a mirror */
  tt_scene *s = load_ok("ts.pbrt", "TransformTimes 2 4\n" HEAD
                                   "Scale -1 1 1\nRotate 30 0 0 1\nActiveTransform EndTime\n"
                                   "Scale 3 3 3\nTranslate 0 0 2\nActiveTransform All\n" TRI);
  if (!s) return;
  double t0, t1;
  tt_scene_time_range(s, &t0, &t1);
  CHECK(t0 == 2 && t1 == 4 && tt_scene_time(s) == 2);
  check_pose("before the start (clamped)", s, 0.0, "Scale -1 1 1\nRotate 30 0 0 1\n" TRI);
  /* at t = 3 pbrt interpolates T, R, S of the ends: T = (0, 0, 3) (half of 3 * 2), S = 2 */
  check_pose("middle", s, 3.0, "Translate 0 0 3\nScale -1 1 1\nRotate 30 0 0 1\nScale 2 2 2\n" TRI);
  check_pose("end", s, 4.0, "Scale -1 1 1\nRotate 30 0 0 1\nScale 3 3 3\nTranslate 0 0 2\n" TRI);
  tt_scene_destroy(s);
  /* a constant scale that is not axis-aligned (along axes turned 30 degrees about z) under
   * a rotation that is animated: the scale is kept exactly, the rotation interpolated */
  s = load_ok("na.pbrt", HEAD "ActiveTransform EndTime\nRotate 60 1 0 0\nActiveTransform All\n"
                              "Rotate -30 0 0 1\nScale 1 3 1\nRotate 30 0 0 1\n" TRI);
  if (s) {
    check_pose("non-axis scale, start", s, 0.0,
               "Rotate -30 0 0 1\nScale 1 3 1\nRotate 30 0 0 1\n" TRI);
    check_pose("non-axis scale, middle", s, 0.5,
               "Rotate 30 1 0 0\nRotate -30 0 0 1\nScale 1 3 1\nRotate 30 0 0 1\n" TRI);
    check_pose("non-axis scale, end", s, 1.0,
               "Rotate 60 1 0 0\nRotate -30 0 0 1\nScale 1 3 1\nRotate 30 0 0 1\n" TRI);
  }
  tt_scene_destroy(s);
}

static void test_instance_and_blocks(void) {
  /* an animated ObjectInstance moves every copy; TransformBegin/End restore both CTMs;
   * CoordinateSystem / CoordSysTransform keep both */
  tt_scene *s = load_ok("in.pbrt", HEAD
                        "ObjectBegin \"o\"\n" TRI TRI "ObjectEnd\n"
                        "AttributeBegin\nActiveTransform StartTime\nTranslate -1 0 0\n"
                        "ActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n"
                        "CoordinateSystem \"moving\"\nObjectInstance \"o\"\nAttributeEnd\n"
                        "TransformBegin\nActiveTransform EndTime\nTranslate 0 5 0\nTransformEnd\n"
                        "ActiveTransform All\n" TRI "CoordSysTransform \"moving\"\n" TRI);
  if (!s) return;
  CHECK(tt_scene_mesh_count(s) == 4);
  if (tt_scene_mesh_count(s) == 4) {
    CHECK(tt_scene_mesh(s, 0)->motion == TT_MESH_RIGID);
    CHECK(tt_scene_mesh(s, 1)->motion == TT_MESH_RIGID);
    CHECK(tt_scene_mesh(s, 2)->motion == TT_MESH_STATIC);
    CHECK(tt_scene_mesh(s, 3)->motion == TT_MESH_RIGID);
  }
  check_pose("instance middle", s, 0.5, TRI TRI TRI TRI);
  check_pose("instance end", s, 1.0,
             "Translate 1 0 0\n" TRI TRI "Translate -1 0 0\n" TRI "Translate 1 0 0\n" TRI);
  tt_scene_destroy(s);
}

typedef struct bad_case {
  const char *text, *expect;
} bad_case;

static void test_bad_input(void) {
  static const bad_case cases[] = {
      {"TransformTimes 1 0\n" HEAD TRI,
       "bad.pbrt:1: TransformTimes: the end time 0 is before the start time 1"},
      {"TransformTimes nan 1\n" HEAD TRI, "bad.pbrt:1: TransformTimes: expected 2 numbers, got"},
      {"TransformTimes 0 inf\n" HEAD TRI, "bad.pbrt:1: TransformTimes: expected 2 numbers, got"},
      {"TransformTimes 1 1\n" HEAD "ActiveTransform EndTime\nTranslate 1 0 0\n" TRI,
       "bad.pbrt:7: Shape: the transform is animated (ActiveTransform) but TransformTimes gives "
       "no time span (start 1, end 1)"},
      {HEAD "Scale 1 3 1\nRotate 30 0 0 1\nActiveTransform EndTime\nScale 2 1 1\n" TRI,
       "bad.pbrt:8: Shape: the animated transform changes a scale that is not axis-aligned"},
      {HEAD "ActiveTransform EndTime\nScale -1 1 1\n" TRI,
       "bad.pbrt:6: Shape: the animated transform mirrors at one end only"},
      {HEAD "ActiveTransform EndTime\nScale 0 1 1\n" TRI,
       "bad.pbrt:6: Shape: the end-time transform is singular"},
      {HEAD "ActiveTransform Later\n" TRI,
       "bad.pbrt:4: ActiveTransform: expected StartTime, EndTime or All, got"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char err[1024] = "";
    tt_scene *s = load_text("bad.pbrt", cases[i].text, err, sizeof err);
    CHECK_MSG(s == NULL, "case %zu loaded", i);
    tt_scene_destroy(s);
    CHECK_CONTAINS(err, cases[i].expect);
  }
}

/* Unit direction from a camera's position to its target. */
static void cam_dir(const tt_camera *c, double f[3]) {
  double l = 0;
  for (int k = 0; k < 3; k++) {
    f[k] = (double)c->target[k] - c->position[k];
    l += f[k] * f[k];
  }
  for (int k = 0; k < 3; k++) f[k] /= sqrt(l);
}

/* An animated Camera (its CTM turned 40 degrees about z at the end) becomes a camera path
 * over TransformTimes: the ends are the cameras of the static files with the start and end
 * transforms, the middle has pbrt's linearly interpolated position and the direction turned
 * halfway (slerp), and a still renders the start. */
static void test_camera(void) {
  const char *cam = "Camera \"perspective\" \"float fov\" [40]\nWorldBegin\n" TRI;
  char text[1024];
  snprintf(text, sizeof text,
           "TransformTimes 1 3\nLookAt 0 -10 2  0 0 0  0 0 1\nActiveTransform EndTime\n"
           "Rotate 40 0 0 1\nActiveTransform All\n%s",
           cam);
  tt_scene *s = load_ok("cam.pbrt", text);
  snprintf(text, sizeof text, "LookAt 0 -10 2  0 0 0  0 0 1\n%s", cam);
  tt_scene *a = load_ok("cam0.pbrt", text);
  snprintf(text, sizeof text, "LookAt 0 -10 2  0 0 0  0 0 1\nRotate 40 0 0 1\n%s", cam);
  tt_scene *b = load_ok("cam1.pbrt", text);
  if (s && a && b) {
    const tt_camera *c = tt_scene_camera(s), *c0 = tt_scene_camera(a), *c1 = tt_scene_camera(b);
    CHECK_MSG(c->key_count >= 9, "%u keys for a 40-degree turn", c->key_count);
    double t0, t1;
    tt_scene_time_range(s, &t0, &t1);
    CHECK(t0 == 1 && t1 == 3);
    CHECK(!tt_scene_animated(s)); /* no moving mesh: only the camera moves */
    tt_camera at0, at1, mid;
    tt_scene_camera_at(s, 1.0, &at0);
    tt_scene_camera_at(s, 3.0, &at1);
    tt_scene_camera_at(s, 2.0, &mid);
    double f[3], g[3], h[3], e[3];
    for (int k = 0; k < 3; k++) {
      CHECK_NEAR(c->position[k], c0->position[k], 1e-5); /* the still is the start */
      CHECK_NEAR(at0.position[k], c0->position[k], 1e-5);
      CHECK_NEAR(at1.position[k], c1->position[k], 1e-4);
      CHECK_NEAR(mid.position[k], 0.5 * (c0->position[k] + c1->position[k]), 1e-4);
    }
    cam_dir(&at1, f);
    cam_dir(c1, g);
    CHECK_NEAR(f[0] * g[0] + f[1] * g[1] + f[2] * g[2], 1.0, 1e-9);
    /* halfway: the start direction turned about z by half the angle between the ends */
    cam_dir(c0, g);
    cam_dir(c1, h);
    double a0 = atan2(g[1], g[0]), a1 = atan2(h[1], h[0]), am = 0.5 * (a0 + a1);
    double r = sqrt(1 - g[2] * g[2]);
    e[0] = r * cos(am), e[1] = r * sin(am), e[2] = g[2];
    CHECK_NEAR(fabs(a1 - a0) * 180 / 3.14159265358979, 40.0, 1e-3);
    cam_dir(&mid, f);
    double ang = acos(fmin(1.0, f[0] * e[0] + f[1] * e[1] + f[2] * e[2])) * 180 / 3.14159265358979;
    CHECK_MSG(ang < 0.05, "the middle camera looks %g degrees away from the slerp direction", ang);
    /* between two keys (u = 0.5625): the path's spline stays within 0.05 degrees too */
    tt_camera between;
    tt_scene_camera_at(s, 2.125, &between);
    am = a0 + 0.5625 * (a1 - a0);
    e[0] = r * cos(am), e[1] = r * sin(am), e[2] = g[2];
    cam_dir(&between, f);
    ang = acos(fmin(1.0, f[0] * e[0] + f[1] * e[1] + f[2] * e[2])) * 180 / 3.14159265358979;
    fprintf(stderr, "camera between keys: %.4g degrees from the slerp direction\n", ang);
    CHECK_MSG(ang < 0.05, "between keys the camera looks %g degrees away from the slerp", ang);
  }
  tt_scene_destroy(s);
  tt_scene_destroy(a);
  tt_scene_destroy(b);
}

/* A scene.json wrapper's camera path is the sequence: an imported pbrt animation beyond it
 * is refused naming "import", one inside it loads. */
static void test_wrapper_range(void) {
  char pbrt[256], json[256];
  snprintf(pbrt, sizeof pbrt, "%s/w.pbrt", g_dir);
  snprintf(json, sizeof json, "%s/w.json", g_dir);
  FILE *f = fopen(pbrt, "w");
  CHECK(f != NULL);
  if (!f) return;
  fputs("TransformTimes 0 1\n" HEAD "ActiveTransform EndTime\nTranslate 1 0 0\n" TRI, f);
  fclose(f);
  static const char *const ends[] = {"0.5", "1"};
  for (int k = 0; k < 2; k++) {
    f = fopen(json, "w");
    CHECK(f != NULL);
    if (!f) return;
    fprintf(f,
            "{\"version\": 1, \"import\": \"w.pbrt\", \"camera\": {\"path\": ["
            "{\"time\": 0, \"position\": [0, -10, 2], \"target\": [0, 0, 0]},"
            "{\"time\": %s, \"position\": [0, -11, 2], \"target\": [0, 0, 0]}]}}\n",
            ends[k]);
    fclose(f);
    tt_scene *s = NULL;
    tt_status st = tt_scene_load(json, &s);
    if (k == 0) {
      CHECK(st != TT_OK);
      CHECK_CONTAINS(tt_last_error(),
                     "w.json: import: the imported scene's animation runs from time 0 to 1: "
                     "longer than the sequence (this file's camera path runs from 0 to 0.5)");
    } else {
      CHECK_MSG(st == TT_OK && s && tt_scene_animated(s), "%s", tt_last_error());
    }
    tt_scene_destroy(s);
  }
  unlink(json);
  unlink(pbrt);
}

int main(void) {
  snprintf(g_dir, sizeof g_dir, "/tmp/tt_pbrt_motion_XXXXXX");
  if (!mkdtemp(g_dir)) TEST_FAIL("cannot create a temporary folder in /tmp");
  test_translate_rotate();
  test_times_scale_mirror();
  test_instance_and_blocks();
  test_bad_input();
  test_wrapper_range();
  test_camera();
  const char *names[] = {"tr", "ts", "na", "in", "ref", "bad", "cam", "cam0", "cam1"};
  char path[256];
  for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
    snprintf(path, sizeof path, "%s/%s.pbrt", g_dir, names[i]);
    unlink(path);
  }
  rmdir(g_dir);
  return tt_test_finish("pbrt_motion");
}
