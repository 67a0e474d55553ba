/* Closed-form direct lighting of a Lambertian receiver, L = albedo / pi * E:
 *  1. under a uniform environment of radiance Le, E = pi * Le, so L = albedo * Le;
 *  2. under a parallel square light of radiance Le centred above the point, E = pi * Le * F
 *     with F the form factor of a differential area to a parallel rectangle (four corner
 *     rectangles, F_c = 1/(2 pi) [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + (X <-> Y)]).
 * Every light strategy must match within 3 standard errors; a light seen from its back
 * (one-sided) gives nothing, and the camera ray is aimed exactly at the analysed point. */
#include <stdlib.h>
#include <unistd.h>

#include <tunetrace/image.h>

#include "path_common.h"
#include "tt_test.h"

static double corner_ff(double x, double y) {
  double a = x / sqrt(1 + x * x) * atan(y / sqrt(1 + x * x));
  double b = y / sqrt(1 + y * y) * atan(x / sqrt(1 + y * y));
  return (a + b) / (2.0 * M_PI);
}

static void check3(const char *what, const pt_estimate *e, const double expected[3]) {
  for (int c = 0; c < 3; ++c)
    CHECK_MSG(fabs(e->mean[c] - expected[c]) <= 3.0 * e->se[c] + 1e-5 * expected[c],
              "%s ch %d: %.5f expected %.5f (se %.5f)", what, c, e->mean[c], expected[c], e->se[c]);
}

static const char *PLANE =
    "{\"name\":\"floor\",\"material\":\"floor\",\"positions\":[-4,0,-4, 4,0,-4, 4,0,4, -4,0,4],"
    "\"indices\":[0,2,1, 0,3,2]}";

int main(void) {
  static char json[4096];
  const float eye[3] = {3.0f, 0.5f, 0.4f}, target[3] = {0.0f, 0.0f, 0.0f};
  tt_ray ray;
  pt_ray_towards(&ray, eye, target);
  const tt_light_strategy strategies[3] = {TT_STRATEGY_MIS, TT_STRATEGY_LIGHT, TT_STRATEGY_BSDF};
  const char *names[3] = {"mis", "light", "bsdf"};

  /* 1. Uniform environment. */
  snprintf(
      json, sizeof json,
      "{\"version\":1,\"camera\":{\"position\":[3,0.5,0.4],\"target\":[0,0,0],\"up\":[0,1,0],"
      "\"fov\":30,\"resolution\":[4,4]},\"materials\":{\"floor\":{\"type\":\"diffuse\","
      "\"albedo\":[0.5,0.7,0.9]}},\"lights\":[{\"type\":\"environment\",\"radiance\":[0.5,1,2]}],"
      "\"meshes\":[%s]}",
      PLANE);
  pt_fixture f;
  CHECK(pt_fixture_load(&f, json));
  if (f.pt) {
    const double expected[3] = {0.5 * 0.5, 0.7 * 1.0, 0.9 * 2.0};
    for (int s = 0; s < 3; ++s) {
      tt_path_options o;
      tt_path_options_default(&o);
      o.max_depth = 1;
      o.strategy = strategies[s];
      pt_estimate e;
      pt_estimate_ray(&f, &o, &ray, 20000, 1, 5, "independent", &e);
      printf("environment, %-5s: L = %.4f %.4f %.4f (se %.4f), expected %.4f %.4f %.4f\n", names[s],
             e.mean[0], e.mean[1], e.mean[2], e.se[2], expected[0], expected[1], expected[2]);
      check3(names[s], &e, expected);
    }
    pt_fixture_free(&f);
  }

  /* 2. Square light of half side 0.5 at height 1, facing down (one-sided). */
  const double half = 0.5, height = 1.0, Le = 4.0;
  double F = 4.0 * corner_ff(half / height, half / height);
  for (int flip = 0; flip < 2; ++flip) {
    /* flip = 1 winds the light upwards: one-sided, the receiver sees only its back. */
    snprintf(
        json, sizeof json,
        "{\"version\":1,\"camera\":{\"position\":[3,0.5,0.4],\"target\":[0,0,0],\"up\":[0,1,0],"
        "\"fov\":30,\"resolution\":[4,4]},\"materials\":{\"floor\":{\"type\":\"diffuse\","
        "\"albedo\":[0.5,0.7,0.9]},\"lamp\":{\"type\":\"diffuse\",\"albedo\":[0,0,0],"
        "\"emission\":[%g,%g,%g]}},\"meshes\":[%s,{\"name\":\"lamp\",\"material\":\"lamp\","
        "\"positions\":[%g,%g,%g, %g,%g,%g, %g,%g,%g, %g,%g,%g],\"indices\":[%s]}]}",
        Le, Le, Le, PLANE, -half, height, -half, half, height, -half, half, height, half, -half,
        height, half, flip ? "0,2,1, 0,3,2" : "0,1,2, 0,2,3");
    CHECK(pt_fixture_load(&f, json));
    if (!f.pt) continue;
    const double expected[3] = {flip ? 0.0 : 0.5 * Le * F, flip ? 0.0 : 0.7 * Le * F,
                                flip ? 0.0 : 0.9 * Le * F};
    for (int s = 0; s < 3; ++s) {
      for (uint32_t depth = 1; depth <= 3; depth += 2) {
        tt_path_options o;
        tt_path_options_default(&o);
        o.max_depth = depth;
        o.strategy = strategies[s];
        pt_estimate e;
        pt_estimate_ray(&f, &o, &ray, 20000, 2 + depth, 9, "independent", &e);
        if (depth == 1)
          printf("square light%s, %-5s: L = %.4f (se %.4f), expected %.4f (F = %.5f)\n",
                 flip ? " (back)" : "", names[s], e.mean[0], e.se[0], expected[0], F);
        char what[64];
        snprintf(what, sizeof what, "square light flip %d %s depth %u", flip, names[s], depth);
        check3(what, &e, expected);
        CHECK(e.nonfinite == 0);
      }
    }
    /* The sobol sampler converges to the same value with a smaller error. */
    if (!flip) {
      tt_path_options o;
      tt_path_options_default(&o);
      o.max_depth = 1;
      pt_estimate es, ei;
      pt_estimate_ray(&f, &o, &ray, 4096, 3, 9, "sobol", &es);
      pt_estimate_ray(&f, &o, &ray, 4096, 3, 9, "independent", &ei);
      printf("square light, 4096 spp: |err| sobol %.2e independent %.2e\n",
             fabs(es.mean[0] - expected[0]), fabs(ei.mean[0] - expected[0]));
      check3("sobol", &es, expected);
    }
    pt_fixture_free(&f);
  }
  /* 3. An albedo texture (2x1 EXR: left texel, right texel) modulates the environment-lit
   * plane: points at the texel centres (u = 0.25, 0.75) reflect albedo * texel * Le. */
  {
    char dir[] = "/tmp/tt_path_tex_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char file[256];
    snprintf(file, sizeof file, "%s/tex.exr", dir);
    const float texels[6] = {1.0f, 0.5f, 0.25f, 0.2f, 0.4f, 0.8f};
    CHECK(tt_image_write_exr(file, 2, 1, 3, texels, NULL, NULL, 0) == TT_OK);
    snprintf(
        json, sizeof json,
        "{\"version\":1,\"camera\":{\"position\":[3,0.5,0.4],\"target\":[0,0,0],\"up\":[0,1,0],"
        "\"fov\":30,\"resolution\":[4,4]},\"materials\":{\"floor\":{\"type\":\"diffuse\","
        "\"albedo\":[0.8,0.8,0.8],\"texture\":\"tex.exr\"}},\"lights\":[{\"type\":\"environment\","
        "\"radiance\":[1,1,1]}],\"meshes\":[{\"name\":\"floor\",\"material\":\"floor\","
        "\"positions\":[-4,0,-4, 4,0,-4, 4,0,4, -4,0,4],\"uvs\":[0,0, 1,0, 1,1, 0,1],"
        "\"indices\":[0,2,1, 0,3,2]}]}");
    tt_scene *sc = NULL;
    tt_status lst = tt_scene_load_json(json, strlen(json), "textured", dir, &sc);
    CHECK_MSG(lst == TT_OK, "%s", tt_last_error());
    if (sc) {
      CHECK(tt_scene_texture_count(sc) == 1);
      tt_scene_destroy(sc);
    }
    CHECK(pt_fixture_load_dir(&f, json, dir));
    if (f.pt) {
      for (int side = 0; side < 2; ++side) {
        const float tgt[3] = {side ? 2.0f : -2.0f, 0.0f, 0.3f};
        const float from[3] = {tgt[0] + 1.0f, 2.0f, 1.0f};
        tt_ray r2;
        pt_ray_towards(&r2, from, tgt);
        tt_path_options o;
        tt_path_options_default(&o);
        o.max_depth = 1;
        pt_estimate e;
        pt_estimate_ray(&f, &o, &r2, 256, 40 + side, 3, "independent", &e);
        const double expected[3] = {0.8 * texels[3 * side], 0.8 * texels[3 * side + 1],
                                    0.8 * texels[3 * side + 2]};
        printf("textured plane, %s texel: L = %.4f %.4f %.4f, expected %.4f %.4f %.4f\n",
               side ? "right" : "left", e.mean[0], e.mean[1], e.mean[2], expected[0], expected[1],
               expected[2]);
        for (int c = 0; c < 3; ++c) CHECK_NEAR(e.mean[c], expected[c], 1e-4);
      }
      pt_fixture_free(&f);
    }
    unlink(file);
    rmdir(dir);
  }
  return tt_test_finish("path_irradiance");
}
