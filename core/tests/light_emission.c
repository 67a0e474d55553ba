/* Emission sampling of every light type for the bidirectional methods (white-box:
 * lights.c and light_emission.c compiled in). Known integrals:
 *  - the light-tracing estimate of emitted power, E[Le cos / (pmf pdf_pos pdf_dir)], equals
 *    the closed form (area pi Le A, two-sided 2 pi Le A; point 4 pi I; spot 2 pi I times the
 *    falloff's integral; distant E pi R^2; environments pi R^2 times the radiance's integral
 *    over the sphere), so the densities are those of the sampler;
 *  - tt__lights_pdf_emission gives each sample's densities back, and its direction density
 *    integrates to 1 over the sphere;
 *  - the s = 1 light point, E[Li max(cos, 0) / (pmf pdf)], gives the irradiance of a
 *    receiver in closed form (square light above it: the form factor; point: I cos / d^2;
 *    constant environment: pi L).
 * Every estimate within 4 standard errors. */
#include <stdlib.h>
#include <unistd.h>

#include <tunetrace/image.h>
#include <tt_util/rng.h>

#include "render/bsdf_internal.h"
#include "render/lights_internal.h"
#include "tt_test.h"

static double corner_ff(double x, double y) {
  double a = x / sqrt(1 + x * x) * atan(y / sqrt(1 + x * x));
  double b = y / sqrt(1 + y * y) * atan(x / sqrt(1 + y * y));
  return (a + b) / (2.0 * M_PI);
}

static tt__pcg32 g_rng;
static float U(void) { return (float)tt__pcg32_double(&g_rng); }

/* Mean and standard error accumulator. */
typedef struct acc {
  double s, s2;
  long n;
} acc;
static void acc_add(acc *a, double v) {
  a->s += v;
  a->s2 += v * v;
  a->n++;
}
static double acc_mean(const acc *a) { return a->s / a->n; }
static double acc_se(const acc *a) {
  double m = acc_mean(a);
  return sqrt(fmax(0.0, a->s2 / a->n - m * m) / a->n);
}
static void check_est(const char *what, const acc *a, double expected) {
  double m = acc_mean(a), se = acc_se(a);
  printf("%-34s %.6g (se %.3g), expected %.6g\n", what, m, se, expected);
  CHECK_MSG(fabs(m - expected) <= 4.0 * se + 1e-6 * fabs(expected), "%s: %g vs %g (se %g)", what, m,
            expected, se);
}

static const char *FLOOR =
    "{\"name\":\"floor\",\"material\":\"grey\",\"positions\":[-2,0,-2, 2,0,-2, 2,0,2, -2,0,2],"
    "\"indices\":[0,2,1, 0,3,2]}";

/* Loads a scene with `lights_json` (a "lights" array or ""), `extra_mesh` (a mesh or "") and
 * the floor; builds the lights. */
static int load(const char *lights_json, const char *extra_mesh, const char *extra_mat,
                tt_scene **scene, tt__lights *ls) {
  static char json[8192];
  snprintf(json, sizeof json,
           "{\"version\":1,\"camera\":{\"position\":[0,1,5],\"target\":[0,0,0],\"up\":[0,1,0],"
           "\"fov\":40,"
           "\"resolution\":[8,8]},\"materials\":{\"grey\":{\"type\":\"diffuse\",\"albedo\":0.5}%s},"
           "\"meshes\":[%s%s%s]%s%s}",
           extra_mat, FLOOR, *extra_mesh ? "," : "", extra_mesh, *lights_json ? "," : "",
           lights_json);
  if (tt_scene_load_json(json, strlen(json), "test", NULL, scene) != TT_OK) {
    fprintf(stderr, "scene: %s\n", tt_last_error());
    return 0;
  }
  if (tt__lights_init(ls, *scene) != TT_OK) {
    fprintf(stderr, "lights: %s\n", tt_last_error());
    tt_scene_destroy(*scene);
    return 0;
  }
  return 1;
}

/* Power estimate, density consistency and the direction density's integral. */
static void check_emission(const char *name, const tt__lights *ls, double power, int delta_dir) {
  const int N = 400000;
  acc a = {0};
  int bad_pdf = 0, produced = 0;
  for (int i = 0; i < N; ++i) {
    tt__emission e;
    if (!tt__lights_sample_emission(ls, U(), U(), U(), U(), U(), &e)) {
      acc_add(&a, 0.0);
      continue;
    }
    produced++;
    const tt__light *l = &ls->lights[e.light];
    double c = l->type == TT_LIGHT_AREA ? fabs(tt__dot3(e.n, e.dir)) : 1.0;
    acc_add(&a, e.Le[0] * c / (e.pmf * e.pdf_pos * e.pdf_dir));
    float pp, pd;
    tt__lights_pdf_emission(ls, e.light, e.n, e.dir, &pp, &pd);
    if (fabsf(pp - e.pdf_pos) > 1e-4f * e.pdf_pos) bad_pdf++;
    if (!delta_dir && fabsf(pd - e.pdf_dir) > 1e-3f * e.pdf_dir) bad_pdf++;
    CHECK(fabsf(tt__dot3(e.dir, e.dir) - 1.0f) < 1e-4f);
  }
  char what[96];
  snprintf(what, sizeof what, "%s: power", name);
  check_est(what, &a, power);
  CHECK_MSG(bad_pdf == 0,
            "%s: %d samples whose densities tt__lights_pdf_emission does not give back", name,
            bad_pdf);
  CHECK_MSG(produced > N / 2, "%s: only %d of %d emissions", name, produced, N);
  if (delta_dir) return;
  /* The direction density integrates to 1 over the sphere (uniform directions). */
  acc d = {0};
  tt__emission e;
  while (!tt__lights_sample_emission(ls, U(), U(), U(), U(), U(), &e)) {}
  for (int i = 0; i < N; ++i) {
    double z = 1.0 - 2.0 * U(), r = sqrt(fmax(0.0, 1.0 - z * z)), phi = 2.0 * M_PI * U();
    float w[3] = {(float)(r * cos(phi)), (float)(r * sin(phi)), (float)z}, pp, pd;
    tt__lights_pdf_emission(ls, e.light, e.n, w, &pp, &pd);
    acc_add(&d, pd * 4.0 * M_PI);
  }
  snprintf(what, sizeof what, "%s: int pdf_dir", name);
  check_est(what, &d, 1.0);
}

/* Irradiance at `p` (normal +y) from the s = 1 light points. */
static void check_irradiance(const char *name, const tt__lights *ls, const float p[3],
                             double expected) {
  const int N = 400000;
  acc a = {0};
  for (int i = 0; i < N; ++i) {
    tt__light_point lp;
    if (!tt__lights_sample_point(ls, p, U(), U(), U(), &lp)) {
      acc_add(&a, 0.0);
      continue;
    }
    acc_add(&a, lp.Li[0] * fmax(0.0, lp.wi[1]) / (lp.pmf * lp.pdf));
  }
  char what[96];
  snprintf(what, sizeof what, "%s: irradiance", name);
  check_est(what, &a, expected);
}

int main(void) {
  tt__pcg32_seed(&g_rng, 2024, 1);
  tt_scene *scene;
  tt__lights ls;
  const float recv[3] = {0.0f, 0.0f, 0.0f};

  /* Square light of side 1 at height 1, facing down; one- and two-sided. */
  for (int two = 0; two < 2; ++two) {
    char mat[256], mesh[512];
    snprintf(mat, sizeof mat,
             ",\"lamp\":{\"type\":\"diffuse\",\"albedo\":0,\"emission\":[3,3,3],\"twoSided\":%s}",
             two ? "true" : "false");
    snprintf(mesh, sizeof mesh,
             "{\"name\":\"lamp\",\"material\":\"lamp\",\"positions\":[-0.5,1,-0.5, 0.5,1,-0.5, "
             "0.5,1,0.5, -0.5,1,0.5],\"indices\":[0,1,2, 0,2,3]}");
    CHECK(load("", mesh, mat, &scene, &ls));
    check_emission(two ? "area two-sided" : "area one-sided", &ls,
                   (two ? 2.0 : 1.0) * M_PI * 3.0 * 1.0, 0);
    check_irradiance(two ? "area two-sided" : "area one-sided", &ls, recv,
                     M_PI * 3.0 * 4.0 * corner_ff(0.5, 0.5));
    tt__lights_free(&ls);
    tt_scene_destroy(scene);
  }
  /* Point light. */
  CHECK(load("\"lights\":[{\"type\":\"point\",\"position\":[0,2,0],\"intensity\":[5,5,5]}]", "", "",
             &scene, &ls));
  check_emission("point", &ls, 4.0 * M_PI * 5.0, 0);
  check_irradiance("point", &ls, recv, 5.0 / 4.0);
  tt__lights_free(&ls);
  tt_scene_destroy(scene);
  /* Spot light: cone 30 degrees, falloff from 20. */
  CHECK(load("\"lights\":[{\"type\":\"spot\",\"position\":[0,2,0],\"direction\":[0,-1,0],"
             "\"intensity\":[5,5,5],"
             "\"angle\":30,\"innerAngle\":20}]",
             "", "", &scene, &ls));
  {
    double ci = ls.lights[0].cos_inner, co = ls.lights[0].cos_outer;
    check_emission("spot", &ls, 2.0 * M_PI * 5.0 * ((1.0 - ci) + 0.5 * (ci - co)), 0);
    check_irradiance("spot", &ls, recv, 5.0 / 4.0);
  }
  tt__lights_free(&ls);
  tt_scene_destroy(scene);
  /* Distant light. */
  CHECK(load("\"lights\":[{\"type\":\"distant\",\"direction\":[0,-1,0],\"irradiance\":[2,2,2]}]",
             "", "", &scene, &ls));
  check_emission("distant", &ls, 2.0 * M_PI * ls.radius * ls.radius, 1);
  check_irradiance("distant", &ls, recv, 2.0);
  tt__lights_free(&ls);
  tt_scene_destroy(scene);
  /* Constant environment. */
  CHECK(load("\"lights\":[{\"type\":\"environment\",\"radiance\":[0.7,0.7,0.7]}]", "", "", &scene,
             &ls));
  check_emission("environment", &ls, 0.7 * 4.0 * M_PI * M_PI * ls.radius * ls.radius, 0);
  check_irradiance("environment", &ls, recv, M_PI * 0.7);
  tt__lights_free(&ls);
  tt_scene_destroy(scene);
  /* Image environment: 16 x 8 texels of varying radiance. */
  char dir[] = "/tmp/tt_light_emission_XXXXXX", path[256];
  CHECK(mkdtemp(dir) != NULL);
  snprintf(path, sizeof path, "%s/env.exr", dir);
  enum { EW = 16, EH = 8 };
  static float px[3 * EW * EH];
  double integral = 0.0; /* of the radiance over the sphere (nearest texel lookup) */
  for (int y = 0; y < EH; ++y)
    for (int x = 0; x < EW; ++x) {
      float v = (float)(0.1 + (x == 3 && y == 2 ? 20.0 : 0.0) + 0.3 * y + 0.05 * x);
      for (int c = 0; c < 3; ++c) px[3 * (y * EW + x) + c] = v;
      integral += v * (cos(M_PI * y / EH) - cos(M_PI * (y + 1) / EH)) * 2.0 * M_PI / EW;
    }
  CHECK(tt_image_write_exr(path, EW, EH, 3, px, NULL, NULL, 0) == TT_OK);
  char lj[512];
  snprintf(lj, sizeof lj, "\"lights\":[{\"type\":\"environment\",\"image\":\"%s\"}]", path);
  CHECK(load(lj, "", "", &scene, &ls));
  if (ls.env_rgb) {
    check_emission("image environment", &ls, integral * M_PI * ls.radius * ls.radius, 0);
    tt__lights_free(&ls);
  } else {
    CHECK_MSG(0, "the image environment was not loaded");
  }
  tt_scene_destroy(scene);
  unlink(path);
  rmdir(dir);
  return tt_test_finish("light_emission");
}
