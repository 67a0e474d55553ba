/* scene.json animation: rigid keys (translate, rotate, scale; linear, slerp, cubic, step)
 * and morph targets evaluate to the poses they describe, previous positions follow the
 * previous time, the time range joins the camera path's, the id sees the motion, and every
 * kind of bad input is refused with a message naming the file and the field. */
#include <tunetrace/scene.h>

#include "tt_test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define PI 3.14159265358979323846

static tt_scene *load(const char *json) {
  tt_scene *s = NULL;
  tt_status st = tt_scene_load_json(json, strlen(json), "anim.json", NULL, &s);
  if (st != TT_OK) fprintf(stderr, "load failed: %s\n", tt_last_error());
  return s;
}

#define HEAD                                                                                       \
  "{\"version\": 1, \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0]},"                 \
  " \"materials\": {\"w\": {}}, \"meshes\": ["
#define TRI "\"material\": \"w\", \"positions\": [[1,0,0],[0,1,0],[0,0,1]]"

/* translate linear from (0,0,0) at t=0 to (2,4,6) at t=2; rotate about y 0 -> 90 degrees
 * (slerp); scale 1 -> 3 */
static void test_rigid_linear(void) {
  tt_scene *s =
      load(HEAD "{\"name\": \"a\", " TRI ", \"animation\": {\"keys\": ["
                "{\"time\": 0, \"translate\": [0,0,0], \"rotate\": [0,0,0], \"scale\": 1},"
                "{\"time\": 2, \"translate\": [2,4,6], \"rotate\": {\"axis\": [0,1,0], \"angle\": "
                "90}, \"scale\": 3}]}},"
                "{\"name\": \"still\", " TRI "}]}");
  CHECK(s != NULL);
  if (!s) return;
  CHECK(tt_scene_animated(s));
  const tt_mesh *m = tt_scene_mesh(s, 0), *still = tt_scene_mesh(s, 1);
  CHECK(m->struct_size >= sizeof(tt_mesh));
  CHECK(m->motion == TT_MESH_RIGID && still->motion == TT_MESH_STATIC);
  CHECK(still->prev_positions == still->positions && still->object_positions == NULL);
  double t0, t1;
  tt_scene_time_range(s, &t0, &t1);
  CHECK(t0 == 0 && t1 == 2 && tt_scene_time(s) == 0);
  /* at t=0 the rest pose */
  CHECK_NEAR(m->positions[0], 1, 1e-6);
  CHECK_NEAR(m->positions[4], 1, 1e-6);
  CHECK(tt_scene_set_time(s, 1.0, 0.0) == TT_OK);
  /* t=1: translate (1,2,3), rotation 45 degrees about y, scale 2: vertex (1,0,0) ->
   * 2 * (cos45, 0, -sin45) + (1,2,3) */
  double c45 = cos(PI / 4);
  CHECK_NEAR(m->positions[0], 1 + 2 * c45, 1e-5);
  CHECK_NEAR(m->positions[1], 2, 1e-5);
  CHECK_NEAR(m->positions[2], 3 - 2 * c45, 1e-5);
  /* (0,1,0) -> (1, 4, 3) */
  CHECK_NEAR(m->positions[3], 1, 1e-5);
  CHECK_NEAR(m->positions[4], 4, 1e-5);
  CHECK_NEAR(m->positions[5], 3, 1e-5);
  /* the previous pose is t = 0's, the transform times the object positions is the pose */
  CHECK_NEAR(m->prev_positions[0], 1, 1e-6);
  CHECK_NEAR(m->prev_positions[4], 1, 1e-6);
  for (uint32_t v = 0; v < 3; v++)
    for (int r = 0; r < 3; r++) {
      const float *o = m->object_positions + 3 * v, *T = m->transform + 4 * r;
      CHECK_NEAR(T[0] * o[0] + T[1] * o[1] + T[2] * o[2] + T[3], m->positions[3 * v + r], 1e-5);
    }
  /* bounds follow the pose */
  float lo[3], hi[3];
  tt_scene_bounds(s, lo, hi);
  CHECK_NEAR(hi[1], 4, 1e-5);
  /* after the last key: clamped */
  CHECK(tt_scene_set_time(s, 5.0, 1.0) == TT_OK);
  CHECK_NEAR(m->positions[3], 2, 1e-5);
  CHECK_NEAR(m->positions[4], 4 + 3, 1e-5);
  CHECK_NEAR(m->prev_positions[4], 4, 1e-5);
  uint64_t rev = m->revision;
  CHECK(tt_scene_set_time(s, 1.0, 1.0) == TT_OK);
  CHECK(m->revision != rev);
  CHECK(memcmp(m->positions, m->prev_positions, 9 * sizeof(float)) == 0);
  /* non-finite times are refused */
  CHECK(tt_scene_set_time(s, NAN, 0) == TT_ERR_INVALID_ARGUMENT);
  tt_scene_destroy(s);
}

/* Channels are independent: a key may give only some fields. Cubic hits every key and
 * follows the camera path's Catmull-Rom spline; step holds the earlier key. */
static void test_channels_cubic_step(void) {
  tt_scene *s = load(
      HEAD "{" TRI ", \"animation\": {\"interpolation\": \"cubic\", \"keys\": ["
           "{\"time\": 0, \"translate\": [0,0,0]}, {\"time\": 1, \"translate\": [1,0,0]},"
           "{\"time\": 2, \"rotate\": {\"quaternion\": [0,0,0,2]}},"
           "{\"time\": 3, \"translate\": [3,3,0]}]}},"
           "{" TRI ", \"animation\": {\"interpolation\": \"step\", \"keys\": ["
           "{\"time\": 0, \"translate\": [0,0,0]}, {\"time\": 1, \"translate\": [5,0,0]}]}}]}");
  CHECK(s != NULL);
  if (!s) return;
  const tt_mesh *a = tt_scene_mesh(s, 0), *b = tt_scene_mesh(s, 1);
  CHECK(tt_scene_set_time(s, 1.0, 0.0) == TT_OK);
  CHECK_NEAR(a->positions[0], 2, 1e-6); /* key hit exactly: (1,0,0) + (1,0,0) */
  CHECK_NEAR(b->positions[0], 6, 1e-6);
  CHECK(tt_scene_set_time(s, 0.5, 0.0) == TT_OK);
  CHECK_NEAR(b->positions[0], 1, 1e-6); /* step: still the first key */
  /* Hermite on keys t = 0, 1, 3 (x = 0, 1, 3): tangents (per second) m0 = 1, m1 = 3/3 = 1;
   * at t = 0.5: h00*0 + h10*1*1 + h01*1 + h11*1*1 = 0.125 + 0.5 - 0.125 = 0.5 */
  CHECK_NEAR(a->positions[0], 1.5, 1e-6);
  tt_scene_destroy(s);
}

/* Morph: position = rest + sum w_i (target_i - rest); weights keyframed. */
static void test_morph(void) {
  tt_scene *s = load(
      HEAD
      "{" TRI ", \"transform\": {\"translate\": [10, 0, 0]}, \"morph\": {"
      "\"targets\": [{\"positions\": [[2,0,0],[0,1,0],[0,0,1]]}, {\"positions\": "
      "[[1,0,0],[0,3,0],[0,0,1]]}],"
      "\"keys\": [{\"time\": 0, \"weights\": [0, 0]}, {\"time\": 1, \"weights\": [1, 0.5]}]}}]}");
  CHECK(s != NULL);
  if (!s) return;
  const tt_mesh *m = tt_scene_mesh(s, 0);
  CHECK(m->motion == TT_MESH_DEFORMING && m->object_positions == NULL);
  CHECK_NEAR(m->positions[0], 11, 1e-6);
  CHECK(tt_scene_set_time(s, 1.0, 0.5) == TT_OK);
  CHECK_NEAR(m->positions[0], 12, 1e-5); /* target 0 fully: x 1 -> 2, placed at +10 */
  CHECK_NEAR(m->positions[4], 2, 1e-5);  /* target 1 half: y 1 -> 2 */
  CHECK_NEAR(m->prev_positions[0], 11.5, 1e-5);
  CHECK_NEAR(m->prev_positions[4], 1.5, 1e-5);
  tt_scene_destroy(s);
}

/* The camera path and the animation share the time axis; the id sees the motion. */
static void test_range_and_id(void) {
  const char *a =
      "{\"version\": 1, \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0], \"path\": ["
      "{\"time\": -1}, {\"time\": 4}]}, \"materials\": {\"w\": {}}, \"meshes\": [{" TRI
      ", \"animation\": {\"keys\": [{\"time\": 0, \"translate\": [0,0,0]}, {\"time\": 3, "
      "\"translate\": [1,0,0]}]}}]}";
  const char *b =
      "{\"version\": 1, \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0], \"path\": ["
      "{\"time\": -1}, {\"time\": 4}]}, \"materials\": {\"w\": {}}, \"meshes\": [{" TRI
      ", \"animation\": {\"keys\": [{\"time\": 0, \"translate\": [0,0,0]}, {\"time\": 3, "
      "\"translate\": [2,0,0]}]}}]}";
  tt_scene *sa = load(a), *sb = load(b);
  CHECK(sa && sb);
  if (sa && sb) {
    double t0, t1;
    tt_scene_time_range(sa, &t0, &t1);
    CHECK(t0 == -1 && t1 == 4);
    CHECK(strcmp(tt_scene_id(sa), tt_scene_id(sb)) != 0);
  }
  tt_scene_destroy(sa);
  tt_scene_destroy(sb);
}

typedef struct bad_case {
  const char *meshes; /* the meshes array's content */
  const char *expect;
} bad_case;

static void test_errors(void) {
  static const bad_case cases[] = {
      {"{" TRI ", \"animation\": {\"keys\": [{\"time\": 1, \"translate\": [0,0,0]}, {\"time\": "
       "0.5, \"translate\": [1,0,0]}]}}",
       "anim.json: meshes[0].animation.keys[1].time: keys out of order: expected a time greater "
       "than the previous key's (1), got 0.5"},
      {"{" TRI ", \"morph\": {\"targets\": [{\"positions\": [[0,0,0],[1,0,0]]}]}}",
       "anim.json: meshes[0].morph.targets[0].positions: mismatched morph target size: expected 3 "
       "positions"},
      {"{" TRI ", \"morph\": {\"targets\": [{\"positions\": [[0,0,0],[1,0,0],[0,1,0]]}], \"keys\": "
       "[{\"time\": 0, \"weights\": [1, 2]}]}}",
       "anim.json: meshes[0].morph.keys[0].weights: expected 1 weights (one per target)"},
      {"{" TRI
       ", \"animation\": {\"keys\": [{\"time\": 0, \"rotate\": {\"quaternion\": [0,0,0,0]}}]}}",
       "anim.json: meshes[0].animation.keys[0].rotate.quaternion: expected a non-zero quaternion"},
      {"{" TRI ", \"animation\": {\"keys\": [{\"time\": 0, \"translate\": [0,1e999,0]}]}}",
       "anim.json: meshes[0].animation.keys[0].translate[1]: expected a finite number, got inf"},
      {"{" TRI ", \"animation\": {\"keys\": [{\"time\": 0, \"scale\": 1}, {\"time\": 1, \"scale\": "
       "[1, -1, 1]}]}}",
       "anim.json: meshes[0].animation.keys[1].scale: expected non-zero factors with the signs of "
       "the first scale key"},
      {"{" TRI ", \"animation\": {\"keys\": [{\"time\": 0}]}}",
       "anim.json: meshes[0].animation.keys[0]: expected at least one of"},
      {"{" TRI
       ", \"animation\": {\"interpolation\": \"bezier\", \"keys\": [{\"time\": 0, \"scale\": 2}]}}",
       "anim.json: meshes[0].animation.interpolation: expected \"linear\", \"cubic\" or \"step\", "
       "got \"bezier\""},
      {"{" TRI ", \"animation\": {\"keys\": []}}",
       "anim.json: meshes[0].animation.keys: expected a non-empty array of keys"},
      {"{" TRI ", \"animation\": {\"keys\": [{\"translate\": [1,0,0]}]}}",
       "anim.json: meshes[0].animation.keys[0].time: missing required field"},
      {"{" TRI ", \"morph\": {\"targets\": []}}",
       "anim.json: meshes[0].morph.targets: expected a non-empty array of targets"},
      {"{" TRI ", \"morph\": {\"targets\": [{\"positions\": [[0,0,0],[1,0,0],[0,1,0]], "
       "\"normals\": [[0,0,1],[0,0,1],[0,0,1]]}]}}",
       "anim.json: meshes[0].morph.targets[0].normals: the mesh has no normals"},
      /* an animation that leaves the coordinate limit */
      {"{" TRI ", \"animation\": {\"keys\": [{\"time\": 0, \"scale\": 1e30}]}}",
       "is not finite or beyond the coordinate limit"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char json[4096];
    snprintf(json, sizeof json, HEAD "%s]}", cases[i].meshes);
    tt_scene *s = NULL;
    tt_status st = tt_scene_load_json(json, strlen(json), "anim.json", NULL, &s);
    CHECK_MSG(st == TT_ERR_PARSE && s == NULL, "case %zu: status %d", i, (int)st);
    CHECK_CONTAINS(tt_last_error(), cases[i].expect);
    tt_scene_destroy(s);
  }
  /* an animation longer than the sequence the camera path describes */
  const char *longer =
      "{\"version\": 1, \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0], \"path\": ["
      "{\"time\": 0}, {\"time\": 2}]}, \"materials\": {\"w\": {}}, \"meshes\": [{\"material\": "
      "\"w\", "
      "\"positions\": [[1,0,0],[0,1,0],[0,0,1]]}, {\"material\": \"w\", \"positions\": "
      "[[1,0,0],[0,1,0],[0,0,1]],"
      " \"animation\": {\"keys\": [{\"time\": 0, \"translate\": [0,0,0]}, {\"time\": 3, "
      "\"translate\": [1,0,0]}]}}]}";
  tt_scene *s = NULL;
  CHECK(tt_scene_load_json(longer, strlen(longer), "anim.json", NULL, &s) == TT_ERR_PARSE);
  CHECK_CONTAINS(
      tt_last_error(),
      "anim.json: meshes[1].animation.keys: keys from time 0 to 3: the animation is longer "
      "than the sequence (the camera path runs from 0 to 2)");
}

/* A pose beyond the coordinate limit is refused and leaves the last good pose. */
static void test_failed_pose(void) {
  tt_scene *s = load(
      HEAD "{\"name\": \"grow\", " TRI
           ", \"animation\": {\"interpolation\": \"step\", \"keys\": [{\"time\": 0, \"scale\": 1},"
           " {\"time\": 1, \"scale\": 1e30}]}}]}");
  CHECK(s != NULL);
  if (!s) return;
  const tt_mesh *m = tt_scene_mesh(s, 0);
  CHECK(tt_scene_set_time(s, 1e-6, 0) == TT_OK);
  float before[9];
  memcpy(before, m->positions, sizeof before);
  CHECK(tt_scene_set_time(s, 1.0, 0.5) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "mesh 0 \"grow\" at time");
  CHECK_CONTAINS(tt_last_error(), "beyond the coordinate limit");
  CHECK(memcmp(before, m->positions, sizeof before) == 0);
  CHECK(memcmp(m->prev_positions, m->positions, sizeof before) == 0);
  CHECK_NEAR(tt_scene_time(s), 1e-6, 1e-12);
  tt_scene_destroy(s);
}

int main(void) {
  test_failed_pose();
  test_rigid_linear();
  test_channels_cubic_step();
  test_morph();
  test_range_and_id();
  test_errors();
  return tt_test_finish("scene_anim");
}
