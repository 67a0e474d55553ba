/* scene.json "stress": {"cylinder": ...} adds the thesis' rotating thin cylinder: it is
 * sized and centred by the scene's bounds, and at every time its vertices are where the
 * rotation about the axis by the angle linear in time puts them (checked analytically,
 * with Rodrigues' formula, across several keys of a long turn and clamped outside the
 * time range); its time range defaults to the camera path's; it works over an imported
 * scene; bad input is refused naming the file and field. */
#include <tunetrace/scene.h>

#include "tt_test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define PI 3.14159265358979323846

static tt_scene *load(const char *json, const char *base) {
  tt_scene *s = NULL;
  tt_status st = tt_scene_load_json(json, strlen(json), "stress.json", base, &s);
  if (st != TT_OK) fprintf(stderr, "load failed: %s\n", tt_last_error());
  return s;
}

/* A triangle spanning [0, 4] x [0, 3] x {0}: diagonal 5, centre (2, 1.5, 0). */
#define HEAD(camera)                                                                               \
  "{\"version\": 1, \"camera\": " camera ", \"materials\": {\"w\": {}},"                           \
  " \"meshes\": [{\"material\": \"w\", \"positions\": [[0,0,0],[4,0,0],[0,3,0]]}], "
#define STILL "{\"position\": [2, 1.5, 10], \"target\": [2, 1.5, 0]}"

/* Rodrigues: v rotated by deg about the unit axis a. */
static void rotate(const double a[3], double deg, const double v[3], double o[3]) {
  double th = deg * PI / 180, c = cos(th), s = sin(th);
  double d = a[0] * v[0] + a[1] * v[1] + a[2] * v[2];
  double x[3] = {a[1] * v[2] - a[2] * v[1], a[2] * v[0] - a[0] * v[2], a[0] * v[1] - a[1] * v[0]};
  for (int k = 0; k < 3; k++) o[k] = v[k] * c + x[k] * s + a[k] * d * (1 - c);
}

/* The cylinder's rest vertex i (ring i of `seg` at the -x end, ring i - seg at the +x end). */
static void rest_vertex(double length, double radius, uint32_t seg, uint32_t i, double p[3]) {
  uint32_t k = i % seg;
  double a = 2 * PI * k / seg;
  p[0] = i < seg ? -length / 2 : length / 2;
  p[1] = radius * cos(a);
  p[2] = radius * sin(a);
}

/* Checks every vertex of `pos` (a mesh's positions or previous positions) against
 * centre + R(axis, deg) * rest. */
static void check_vertices(const float *pos, const double axis[3], double deg, double length,
                           double radius, uint32_t seg, const double centre[3], double t) {
  double worst = 0;
  for (uint32_t i = 0; i < 2 * seg; i++) {
    double p[3], q[3];
    rest_vertex(length, radius, seg, i, p);
    rotate(axis, deg, p, q);
    for (int k = 0; k < 3; k++) worst = fmax(worst, fabs(pos[3 * i + k] - (centre[k] + q[k])));
  }
  CHECK_MSG(worst < 2e-5 * length, "t = %g (%g degrees): a vertex is %g from its analytic place", t,
            deg, worst);
}

static void check_cylinder(const tt_mesh *m, const double axis[3], double deg, double length,
                           double radius, uint32_t seg, const double centre[3], double t) {
  check_vertices(m->positions, axis, deg, length, radius, seg, centre, t);
}

static void test_default_cylinder(void) {
  tt_scene *s = load(HEAD(STILL) "\"stress\": {\"cylinder\": {\"time\": [0, 2]}}}", NULL);
  CHECK(s != NULL);
  if (!s) return;
  CHECK(tt_scene_animated(s));
  CHECK(tt_scene_mesh_count(s) == 2);
  const tt_mesh *m = tt_scene_mesh(s, 1);
  CHECK(strcmp(m->name, "stress_cylinder") == 0);
  CHECK(m->motion == TT_MESH_RIGID && tt_scene_mesh(s, 0)->motion == TT_MESH_STATIC);
  CHECK(m->vertex_count == 16 && m->triangle_count == 16);
  const tt_material *mat = tt_scene_material(s, m->material);
  CHECK(strcmp(mat->name, "stress_cylinder") == 0 && mat->albedo[0] == 0.8f);
  double t0, t1;
  tt_scene_time_range(s, &t0, &t1);
  CHECK(t0 == 0 && t1 == 2 && tt_scene_time(s) == 0);
  /* half the diagonal long, 0.002 of that in radius, about +z from 0 to 180 degrees */
  const double z[3] = {0, 0, 1}, c[3] = {2, 1.5, 0}, len = 2.5, r = 0.002 * 2.5;
  const double times[] = {0.0, 0.3, 1.0, 1.7, 2.0};
  for (size_t i = 0; i < sizeof times / sizeof times[0]; i++) {
    CHECK(tt_scene_set_time(s, times[i], times[i] - 0.1) == TT_OK);
    check_cylinder(m, z, 90.0 * times[i], len, r, 8, c, times[i]);
    /* one frame earlier (motion vectors): the angle 0.1 s before, clamped at the start */
    check_vertices(m->prev_positions, z, 90.0 * fmax(times[i] - 0.1, 0.0), len, r, 8, c,
                   times[i] - 0.1);
  }
  /* clamped after the end: the last angle */
  CHECK(tt_scene_set_time(s, 3.0, 2.9) == TT_OK);
  check_cylinder(m, z, 180.0, len, r, 8, c, 3.0);
  /* the rigid transform times the object positions is the pose */
  for (uint32_t v = 0; v < m->vertex_count; v++)
    for (int row = 0; row < 3; row++) {
      const float *o = m->object_positions + 3 * v, *T = m->transform + 4 * row;
      CHECK_NEAR(T[0] * o[0] + T[1] * o[1] + T[2] * o[2] + T[3], m->positions[3 * v + row], 1e-5);
    }
  tt_scene_destroy(s);
}

static void test_long_turn(void) {
  /* about (1, 1, 0) from 30 to 300 degrees (7 keys), longer and fatter, 5 segments, time
   * from the camera path (1 .. 4) */
  tt_scene *s = load(
      HEAD("{\"position\": [2, 1.5, 10], \"target\": [2, 1.5, 0], \"path\": ["
           "{\"time\": 1, \"position\": [2, 1.5, 10], \"target\": [2, 1.5, 0]},"
           "{\"time\": 4, \"position\": [2, 1.5, 12], \"target\": [2, 1.5, 0]}]}") "\"stress\": "
                                                                                   "{\"cylinder\": "
                                                                                   "{\"axis\": [1, "
                                                                                   "1, 0], "
                                                                                   "\"from\": 30, "
                                                                                   "\"to\": 300, "
                                                                                   "\"length\": "
                                                                                   "1.2, "
                                                                                   "\"radius\": "
                                                                                   "0.05, "
                                                                                   "\"segments\": "
                                                                                   "5, \"center\": "
                                                                                   "[1, 2, 3]}}}",
      NULL);
  CHECK(s != NULL);
  if (!s) return;
  const tt_mesh *m = tt_scene_mesh(s, 1);
  CHECK(m->vertex_count == 10 && m->triangle_count == 10);
  double t0, t1;
  tt_scene_time_range(s, &t0, &t1);
  CHECK(t0 == 1 && t1 == 4);
  const double h = sqrt(0.5), axis[3] = {h, h, 0}, c[3] = {1, 2, 3}, len = 6, r = 0.3;
  for (double t = 0.5; t <= 4.6; t += 0.37) {
    CHECK(tt_scene_set_time(s, t, t) == TT_OK);
    double u = t < 1 ? 0 : t > 4 ? 1 : (t - 1) / 3;
    check_cylinder(m, axis, 30 + 270 * u, len, r, 5, c, t);
  }
  tt_scene_destroy(s);
}

static void test_imported(const char *root) {
  char base[4096], json[8192];
  snprintf(base, sizeof base, "%s/scenes/cornell-box", root);
  snprintf(json, sizeof json,
           "{\"version\": 1, \"import\": \"scene.json\", \"stress\": {\"cylinder\": {}}}");
  tt_scene *s = load(json, base), *plain = NULL;
  char path[4200];
  snprintf(path, sizeof path, "%s/scene.json", base);
  CHECK(tt_scene_load(path, &plain) == TT_OK);
  CHECK(s != NULL);
  if (!s || !plain) {
    tt_scene_destroy(s);
    tt_scene_destroy(plain);
    return;
  }
  uint32_t n = tt_scene_mesh_count(plain);
  CHECK(tt_scene_mesh_count(s) == n + 1);
  float lo[3], hi[3];
  tt_scene_bounds(plain, lo, hi);
  double diag = 0, c[3];
  for (int k = 0; k < 3; k++) {
    diag += (double)(hi[k] - lo[k]) * (hi[k] - lo[k]);
    c[k] = (lo[k] + hi[k]) / 2.0;
  }
  diag = sqrt(diag);
  const tt_mesh *m = tt_scene_mesh(s, n);
  const double z[3] = {0, 0, 1};
  double t0, t1;
  tt_scene_time_range(s, &t0, &t1); /* the cornell box's camera path, or 0 .. 1 */
  CHECK(t1 > t0);
  double t = t0 + 0.25 * (t1 - t0);
  CHECK(tt_scene_set_time(s, t, t) == TT_OK);
  check_cylinder(m, z, 45.0, diag / 2, 0.002 * diag / 2, 8, c, t);
  /* the scene's own meshes are untouched */
  for (uint32_t i = 0; i < n; i++)
    CHECK(memcmp(tt_scene_mesh(s, i)->positions, tt_scene_mesh(plain, i)->positions,
                 12 * (size_t)tt_scene_mesh(plain, i)->vertex_count) == 0);
  tt_scene_destroy(s);
  tt_scene_destroy(plain);
}

typedef struct bad_case {
  const char *stress, *expect;
} bad_case;

static void test_bad_input(void) {
  static const bad_case cases[] = {
      {"{\"cylinder\": {\"time\": [2, 1]}}",
       "stress.json: stress.cylinder.time: expected [start, end] seconds with end > start, got "
       "[2, 1]"},
      {"{\"cylinder\": {\"axis\": [0, 0, 0]}}",
       "stress.json: stress.cylinder.axis: expected a non-zero rotation axis"},
      {"{\"cylinder\": {\"segments\": 2}}", "stress.json: stress.cylinder.segments:"},
      {"{\"cylinder\": {\"segments\": 8.5}}", "stress.json: stress.cylinder.segments:"},
      {"{\"cylinder\": {\"from\": 1e999}}",
       "stress.json: stress.cylinder.from: expected a finite number"},
      {"{\"cylinder\": {\"radius\": 0}}", "stress.json: stress.cylinder.radius:"},
      {"{\"cylinder\": {\"material\": \"nope\"}}",
       "stress.json: stress.cylinder.material: unknown material \"nope\""},
      {"{\"cylinder\": {\"time\": [0, 9]}}",
       "stress.json: stress.cylinder.time: the cylinder turns from time 0 to 9: longer than the "
       "sequence (the camera path runs from 0 to 2)"},
      {"{\"cylinder\": 3}", "stress.json: stress.cylinder: expected an object"},
      {"[1]", "stress.json: stress: expected an object"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char json[2048];
    snprintf(json, sizeof json,
             HEAD("{\"position\": [2, 1.5, 10], \"target\": [2, 1.5, 0], \"path\": ["
                  "{\"time\": 0, \"position\": [2, 1.5, 10], \"target\": [2, 1.5, 0]},"
                  "{\"time\": 2, \"position\": [2, 1.5, 12], \"target\": [2, 1.5, 0]}]}") "\"stress"
                                                                                          "\": %s}",
             cases[i].stress);
    tt_scene *s = NULL;
    CHECK_MSG(tt_scene_load_json(json, strlen(json), "stress.json", NULL, &s) != TT_OK,
              "case %zu loaded", i);
    tt_scene_destroy(s);
    CHECK_CONTAINS(tt_last_error(), cases[i].expect);
  }
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  test_default_cylinder();
  test_long_turn();
  test_imported(root ? root : "..");
  test_bad_input();
  return tt_test_finish("scene_stress");
}
