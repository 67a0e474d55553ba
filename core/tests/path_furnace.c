/* Furnace tests of the path sampler (thesis 2.5.4):
 *  1. inside a closed box of albedo a that emits radiance 1 everywhere, a path of at most D
 *     bounces sees L = sum_{k=0..D} a^k exactly (every surface is both light and reflector);
 *  2. a convex diffuse box of albedo a under a constant environment of radiance 1 reflects
 *     exactly a (no interreflection), and the environment is seen as 1;
 *  3. the same box under an image environment: a constant-valued image gives the constant
 *     environment's result, and an image that is black below the horizon and brighter on
 *     the -x side gives each face its closed-form irradiance (top 2a, +x a/2, -x 3a/2).
 * Every strategy (MIS power/balance, light only, BSDF only), sampler and Russian roulette
 * must agree with the closed form within 3 standard errors. */
#include <stdlib.h>
#include <unistd.h>

#include <tunetrace/image.h>

#include "path_common.h"
#include "tt_test.h"

/* Appends JSON for the 12 triangles of the box [-1,1]^3; `inward` picks the winding. */
static void box_mesh_json(char *buf, size_t size, const char *name, const char *material,
                          int inward) {
  float pos[24][3];
  uint32_t idx[12][3];
  int nv = 0, nt = 0;
  for (int axis = 0; axis < 3; ++axis) {
    for (int s = -1; s <= 1; s += 2) {
      int u = (axis + 1) % 3, v = (axis + 2) % 3;
      float q[4][3];
      const int cu[4] = {-1, 1, 1, -1}, cv[4] = {-1, -1, 1, 1};
      for (int k = 0; k < 4; ++k) {
        q[k][axis] = (float)s;
        q[k][u] = (float)cu[k];
        q[k][v] = (float)cv[k];
      }
      /* (q1-q0) x (q2-q0) points along +axis for this corner order; flip as required. */
      float want = inward ? (float)-s : (float)s;
      int flip = want < 0.0f;
      for (int k = 0; k < 4; ++k) memcpy(pos[nv + k], q[k], sizeof q[k]);
      uint32_t a = (uint32_t)nv, b = a + 1, c = a + 2, d = a + 3;
      if (!flip) {
        idx[nt][0] = a;
        idx[nt][1] = b;
        idx[nt][2] = c;
        idx[nt + 1][0] = a;
        idx[nt + 1][1] = c;
        idx[nt + 1][2] = d;
      } else {
        idx[nt][0] = a;
        idx[nt][1] = c;
        idx[nt][2] = b;
        idx[nt + 1][0] = a;
        idx[nt + 1][1] = d;
        idx[nt + 1][2] = c;
      }
      nv += 4;
      nt += 2;
    }
  }
  size_t n = strlen(buf);
  n += (size_t)snprintf(buf + n, size - n, "{\"name\":\"%s\",\"material\":\"%s\",\"positions\":[",
                        name, material);
  for (int i = 0; i < nv; ++i)
    n += (size_t)snprintf(buf + n, size - n, "%s%g,%g,%g", i ? "," : "", pos[i][0], pos[i][1],
                          pos[i][2]);
  n += (size_t)snprintf(buf + n, size - n, "],\"indices\":[");
  for (int i = 0; i < nt; ++i)
    n += (size_t)snprintf(buf + n, size - n, "%s%u,%u,%u", i ? "," : "", idx[i][0], idx[i][1],
                          idx[i][2]);
  snprintf(buf + n, size - n, "]}");
}

static const char *CAMERA = "\"camera\":{\"position\":[0,0,0.5],\"target\":[0,0,0],\"up\":[0,1,0],"
                            "\"fov\":45,\"resolution\":[8,8]}";

/* Checks |mean - expected| <= 3 se (+ float rounding) for every channel. */
static void check_estimate(const char *what, const pt_estimate *e, double expected) {
  for (int c = 0; c < 3; ++c) {
    double tol = 3.0 * e->se[c] + 1e-5 * expected;
    CHECK_MSG(fabs(e->mean[c] - expected) <= tol,
              "%s: channel %d mean %.5f expected %.5f (se %.5f)", what, c, e->mean[c], expected,
              e->se[c]);
  }
  CHECK_MSG(e->nonfinite == 0, "%s: %llu non-finite samples", what,
            (unsigned long long)e->nonfinite);
}

/* Pools estimates over several ray directions from the box centre. */
static void estimate_dirs(const pt_fixture *f, const tt_path_options *o, const char *sampler,
                          uint32_t n, pt_estimate *out) {
  static const float dirs[4][3] = {
      {0.3f, 0.2f, 1.0f}, {-1.0f, 0.1f, 0.2f}, {0.2f, -1.0f, -0.4f}, {0.5f, 0.5f, -0.7f}};
  double m[3] = {0, 0, 0}, v[3] = {0, 0, 0};
  memset(out, 0, sizeof *out);
  for (int d = 0; d < 4; ++d) {
    const float org[3] = {0.1f, -0.2f, 0.05f};
    float to[3] = {org[0] + dirs[d][0], org[1] + dirs[d][1], org[2] + dirs[d][2]};
    tt_ray ray;
    pt_ray_towards(&ray, org, to);
    pt_estimate e;
    pt_estimate_ray(f, o, &ray, n, (uint32_t)d, 7, sampler, &e);
    for (int c = 0; c < 3; ++c) {
      m[c] += e.mean[c] / 4.0;
      v[c] += e.se[c] * e.se[c] / 16.0;
    }
    out->rays += e.rays;
    out->nonfinite += e.nonfinite;
    if (e.max_dim > out->max_dim) out->max_dim = e.max_dim;
  }
  for (int c = 0; c < 3; ++c) {
    out->mean[c] = m[c];
    out->se[c] = sqrt(v[c]);
  }
}

/* Sum of a^k for k = 0..d. */
static double geometric(double a, uint32_t d) {
  double s = 0.0, p = 1.0;
  for (uint32_t k = 0; k <= d; ++k, p *= a) s += p;
  return s;
}

static void closed_box_tests(void) {
  static char json[16384];
  const double albedo = 0.8;
  snprintf(json, sizeof json,
           "{\"version\":1,%s,\"materials\":{\"glow\":{\"type\":\"diffuse\",\"albedo\":[%g,%g,%g],"
           "\"emission\":[1,1,1]}},\"meshes\":[",
           CAMERA, albedo, albedo, albedo);
  box_mesh_json(json, sizeof json, "box", "glow", 1);
  strcat(json, "]}");
  pt_fixture f;
  CHECK(pt_fixture_load(&f, json));
  if (!f.pt) return;

  struct {
    tt_light_strategy s;
    tt_mis_heuristic h;
    const char *name;
  } strategies[] = {
      {TT_STRATEGY_MIS, TT_MIS_POWER, "mis-power"},
      {TT_STRATEGY_MIS, TT_MIS_BALANCE, "mis-balance"},
      {TT_STRATEGY_LIGHT, TT_MIS_POWER, "light-only"},
      {TT_STRATEGY_MIS, TT_MIS_NONE, "mis-none"},
      {TT_STRATEGY_BSDF, TT_MIS_POWER, "bsdf-only"},
  };
  const uint32_t depth = 8;
  for (size_t i = 0; i < sizeof strategies / sizeof strategies[0]; ++i) {
    tt_path_options o;
    tt_path_options_default(&o);
    o.max_depth = depth;
    o.rr_depth = depth;
    o.strategy = strategies[i].s;
    o.heuristic = strategies[i].h;
    pt_estimate e;
    estimate_dirs(&f, &o, "independent", 3000, &e);
    printf("closed box %-12s L = %.4f +- %.4f (expected %.4f)\n", strategies[i].name, e.mean[0],
           e.se[0], geometric(albedo, depth));
    check_estimate(strategies[i].name, &e, geometric(albedo, depth));
    CHECK(e.max_dim <= TT_PATH_DIM_COUNT(depth));
    CHECK(e.rays > 0);
  }
  /* Samplers and Russian roulette. */
  const char *samplers[] = {"halton", "sobol"};
  for (int s = 0; s < 2; ++s) {
    tt_path_options o;
    tt_path_options_default(&o);
    o.max_depth = depth;
    o.rr_depth = depth;
    pt_estimate e;
    estimate_dirs(&f, &o, samplers[s], 2048, &e);
    printf("closed box sampler %-7s L = %.4f +- %.4f\n", samplers[s], e.mean[0], e.se[0]);
    check_estimate(samplers[s], &e, geometric(albedo, depth));
  }
  {
    tt_path_options o;
    tt_path_options_default(&o);
    o.max_depth = 20;
    o.rr_depth = 1;
    pt_estimate e;
    estimate_dirs(&f, &o, "independent", 3000, &e);
    printf("closed box RR from 1, depth 20: L = %.4f +- %.4f (expected %.4f)\n", e.mean[0], e.se[0],
           geometric(albedo, 20));
    check_estimate("russian roulette", &e, geometric(albedo, 20));
    /* Roulette must actually shorten paths: fewer rays than 2 per bounce for all 20. */
    CHECK(e.rays < 4ull * 3000 * 2 * 21 / 2);
  }
  {
    /* Depth 0 sees emission only; depth 1 adds exactly one bounce. */
    tt_path_options o;
    tt_path_options_default(&o);
    o.max_depth = 0;
    pt_estimate e;
    estimate_dirs(&f, &o, "independent", 64, &e);
    CHECK_NEAR(e.mean[0], 1.0, 1e-6);
    CHECK_NEAR(e.se[0], 0.0, 1e-6);
    CHECK(e.max_dim == 0);
  }
  {
    /* report_pdf: cosine sampling of a Lambertian reports pdf cos/pi, whose mean is 2/(3 pi). */
    tt_path_options o;
    tt_path_options_default(&o);
    o.max_depth = 1;
    pt_sampler_src src;
    memset(&src, 0, sizeof src);
    src.iface = tt_builtin_sampler("independent");
    src.iface->create(NULL, 3, &src.sampler);
    tt_sample_source source = {pt_src_get, pt_src_report, &src};
    const float org[3] = {0, 0, 0}, to[3] = {0.2f, 0.1f, 1.0f};
    tt_ray ray;
    pt_ray_towards(&ray, org, to);
    for (uint32_t i = 0; i < 20000; ++i) {
      src.iface->start(src.sampler, src.state, 0, 0, i);
      tt_path_result r;
      tt_path_trace(f.pt, &f.tracer, &o, &ray, &source, &r);
      CHECK(r.hit && r.bounces == 1 && r.rays >= 2);
      if (i == 0) {
        CHECK_NEAR(r.albedo[1], albedo, 1e-6);
        CHECK(r.normal[2] < -0.99f); /* the z = +1 wall, normal towards the viewer */
        CHECK_NEAR(r.distance, 1.0 / ray.dir[2], 1e-4);
      }
    }
    CHECK(src.pdf_reports == 20000);
    double mean_pdf = src.pdf_sum / src.pdf_reports;
    /* var(cos/pi) = (1/2 - 4/9)/pi^2; 5 standard errors. */
    double se = sqrt((0.5 - 4.0 / 9.0) / (M_PI * M_PI) / 20000.0);
    CHECK_NEAR(mean_pdf, 2.0 / (3.0 * M_PI), 5 * se);
    src.iface->destroy(src.sampler);
  }
  pt_fixture_free(&f);

  /* Outward winding: seen from inside every wall is a back face, so one-sided emission
   * gives L = 0 (nothing else emits); twoSided restores the series. */
  for (int two = 0; two < 2; ++two) {
    snprintf(
        json, sizeof json,
        "{\"version\":1,%s,\"materials\":{\"glow\":{\"type\":\"diffuse\",\"albedo\":[%g,%g,%g],"
        "\"emission\":[1,1,1],\"twoSided\":%s}},\"meshes\":[",
        CAMERA, albedo, albedo, albedo, two ? "true" : "false");
    box_mesh_json(json, sizeof json, "box", "glow", 0);
    strcat(json, "]}");
    CHECK(pt_fixture_load(&f, json));
    if (!f.pt) return;
    tt_path_options o;
    tt_path_options_default(&o);
    o.max_depth = 4;
    o.rr_depth = 4;
    pt_estimate e;
    estimate_dirs(&f, &o, "independent", 1000, &e);
    printf("outward box, twoSided=%d: L = %.4f +- %.4f\n", two, e.mean[0], e.se[0]);
    check_estimate(two ? "two-sided" : "one-sided back faces", &e,
                   two ? geometric(albedo, 4) : 0.0);
    pt_fixture_free(&f);
  }
}

static void environment_tests(void) {
  static char json[16384];
  const double albedo = 0.6;
  snprintf(
      json, sizeof json,
      "{\"version\":1,%s,\"materials\":{\"grey\":{\"type\":\"diffuse\",\"albedo\":[%g,%g,%g]}},"
      "\"lights\":[{\"type\":\"environment\",\"radiance\":[1,1,1]}],\"meshes\":[",
      CAMERA, albedo, albedo, albedo);
  box_mesh_json(json, sizeof json, "box", "grey", 0);
  strcat(json, "]}");
  pt_fixture f;
  CHECK(pt_fixture_load(&f, json));
  if (!f.pt) return;
  const float eye[3] = {3.0f, 2.0f, 4.0f};
  const float targets[3][3] = {{0.0f, 0.0f, 0.0f}, {0.5f, -0.3f, 0.2f}, {-0.9f, 0.8f, 0.9f}};
  tt_light_strategy strategies[3] = {TT_STRATEGY_MIS, TT_STRATEGY_LIGHT, TT_STRATEGY_BSDF};
  for (int s = 0; s < 3; ++s) {
    for (int t = 0; t < 3; ++t) {
      tt_path_options o;
      tt_path_options_default(&o);
      o.max_depth = 5;
      o.strategy = strategies[s];
      tt_ray ray;
      pt_ray_towards(&ray, eye, targets[t]);
      pt_estimate e;
      pt_estimate_ray(&f, &o, &ray, 2000, (uint32_t)t, 11, "independent", &e);
      char what[64];
      snprintf(what, sizeof what, "env furnace strategy %d target %d", s, t);
      check_estimate(what, &e, albedo);
      if (s == 1 && t == 0)
        printf("env furnace (light only): L = %.4f +- %.4f (expected %.2f)\n", e.mean[0], e.se[0],
               albedo);
    }
  }
  /* A miss sees the environment exactly. */
  tt_path_options o;
  tt_path_options_default(&o);
  const float away[3] = {10.0f, 2.0f, 4.0f};
  tt_ray ray;
  pt_ray_towards(&ray, eye, away);
  pt_estimate e;
  pt_estimate_ray(&f, &o, &ray, 16, 0, 1, "independent", &e);
  CHECK_NEAR(e.mean[0], 1.0, 1e-6);
  CHECK_NEAR(e.se[0], 0.0, 1e-6);
  pt_fixture_free(&f);
}

/* Writes a W x H lat-long EXR: `constant` > 0 fills it; otherwise rows above the horizon
 * hold 3 for d.x < 0 (columns u < 1/2) and 1 for d.x > 0, rows below hold 0. */
static int write_env(const char *path, uint32_t w, uint32_t h, float constant) {
  float *px = malloc(sizeof(float) * 3 * w * h);
  if (!px) return 0;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      for (int k = 0; k < 3; ++k)
        px[3 * (y * w + x) + k] =
            constant > 0.0f ? constant : (y < h / 2 ? (x < w / 2 ? 3.0f : 1.0f) : 0.0f);
  tt_status st = tt_image_write_exr(path, w, h, 3, px, NULL, NULL, 0);
  free(px);
  return st == TT_OK;
}

static void image_environment_tests(void) {
  char dir[] = "/tmp/tt_path_env_XXXXXX";
  if (!mkdtemp(dir)) {
    CHECK_MSG(0, "mkdtemp failed");
    return;
  }
  char flat[512], split[512];
  snprintf(flat, sizeof flat, "%s/flat.exr", dir);
  snprintf(split, sizeof split, "%s/split.exr", dir);
  CHECK(write_env(flat, 32, 16, 1.0f));
  CHECK(write_env(split, 64, 32, 0.0f));
  const double albedo = 0.6;
  const float scale[3] = {0.5f, 1.0f, 2.0f};
  static char json[16384];
  tt_light_strategy strategies[3] = {TT_STRATEGY_MIS, TT_STRATEGY_LIGHT, TT_STRATEGY_BSDF};
  const float eye[3] = {3.0f, 2.0f, 4.0f}, target[3] = {0.5f, -0.3f, 0.2f};
  tt_ray ray;
  pt_ray_towards(&ray, eye, target);

  /* 1. Constant image == constant environment (radiance used as the image's scale). */
  pt_estimate ref[3], img[3];
  for (int use_image = 0; use_image < 2; ++use_image) {
    char light[700];
    if (use_image)
      snprintf(light, sizeof light,
               "{\"type\":\"environment\",\"radiance\":[%g,%g,%g],\"image\":\"%s\"}", scale[0],
               scale[1], scale[2], flat);
    else
      snprintf(light, sizeof light, "{\"type\":\"environment\",\"radiance\":[%g,%g,%g]}", scale[0],
               scale[1], scale[2]);
    snprintf(json, sizeof json,
             "{\"version\":1,%s,\"materials\":{\"grey\":{\"type\":\"diffuse\",\"albedo\":%g}},"
             "\"lights\":[%s],\"meshes\":[",
             CAMERA, albedo, light);
    box_mesh_json(json, sizeof json, "box", "grey", 0);
    strcat(json, "]}");
    pt_fixture f;
    CHECK(pt_fixture_load(&f, json));
    if (!f.pt) return;
    CHECK(tt_scene_light(f.scene, 0)->type ==
          (use_image ? TT_LIGHT_ENV_IMAGE : TT_LIGHT_ENV_CONSTANT));
    for (int s = 0; s < 3; ++s) {
      tt_path_options o;
      tt_path_options_default(&o);
      o.max_depth = 5;
      o.strategy = strategies[s];
      pt_estimate *e = use_image ? &img[s] : &ref[s];
      pt_estimate_ray(&f, &o, &ray, 4000, 3, 21, "independent", e);
      for (int c = 0; c < 3; ++c) {
        double expect = albedo * scale[c];
        CHECK_MSG(fabs(e->mean[c] - expect) <= 3.0 * e->se[c] + 1e-5,
                  "%s env strategy %d ch %d: %.5f expected %.5f (se %.5f)",
                  use_image ? "image" : "constant", s, c, e->mean[c], expect, e->se[c]);
      }
      CHECK(e->nonfinite == 0);
    }
    /* A miss sees the environment (the scale times the image value). */
    const float away[3] = {10.0f, 2.0f, 4.0f};
    tt_ray miss;
    pt_ray_towards(&miss, eye, away);
    pt_estimate e;
    pt_estimate_ray(&f, NULL, &miss, 4, 0, 1, "independent", &e);
    for (int c = 0; c < 3; ++c) CHECK_NEAR(e.mean[c], scale[c], 1e-6);
    pt_fixture_free(&f);
  }
  for (int s = 0; s < 3; ++s) {
    double comb = sqrt(ref[s].se[1] * ref[s].se[1] + img[s].se[1] * img[s].se[1]);
    printf("constant env vs constant image, strategy %d: %.4f +- %.4f vs %.4f +- %.4f\n", s,
           ref[s].mean[1], ref[s].se[1], img[s].mean[1], img[s].se[1]);
    CHECK(fabs(ref[s].mean[1] - img[s].mean[1]) <= 4.0 * comb);
  }

  /* 2. Non-uniform image: each face's irradiance in closed form. */
  snprintf(json, sizeof json,
           "{\"version\":1,%s,\"materials\":{\"grey\":{\"type\":\"diffuse\",\"albedo\":%g}},"
           "\"lights\":[{\"type\":\"environment\",\"image\":\"%s\"}],\"meshes\":[",
           CAMERA, albedo, split);
  box_mesh_json(json, sizeof json, "box", "grey", 0);
  strcat(json, "]}");
  pt_fixture f;
  CHECK(pt_fixture_load(&f, json));
  if (!f.pt) return;
  static const struct {
    float from[3], to[3];
    double expect;
    const char *face;
  } faces[4] = {
      {{0.1f, 5.0f, 0.2f}, {0.2f, 0.0f, 0.3f}, 2.0, "top"},
      {{5.0f, 0.2f, 0.1f}, {0.0f, 0.1f, -0.2f}, 0.5, "+x"},
      {{-5.0f, 0.3f, 0.2f}, {0.0f, 0.0f, 0.0f}, 1.5, "-x"},
      {{0.2f, -5.0f, 0.1f}, {0.0f, 0.0f, 0.0f}, 0.0, "bottom"},
  };
  for (int i = 0; i < 4; ++i) {
    pt_ray_towards(&ray, faces[i].from, faces[i].to);
    for (int s = 0; s < 3; ++s) {
      tt_path_options o;
      tt_path_options_default(&o);
      o.max_depth = 3;
      o.strategy = strategies[s];
      pt_estimate e;
      pt_estimate_ray(&f, &o, &ray, 4000, (uint32_t)i, 5, "independent", &e);
      double expect = albedo * faces[i].expect;
      if (s == 0)
        printf("split image env, %-6s face (MIS): L = %.4f +- %.4f (expected %.4f)\n",
               faces[i].face, e.mean[0], e.se[0], expect);
      char what[64];
      snprintf(what, sizeof what, "split env %s face strategy %d", faces[i].face, s);
      check_estimate(what, &e, expect);
    }
  }
  /* Importance sampling by the image: light sampling alone has a lower error than BSDF
   * sampling alone on the -x face, whose sky is half bright, half dark. */
  {
    pt_ray_towards(&ray, faces[2].from, faces[2].to);
    tt_path_options o;
    tt_path_options_default(&o);
    o.max_depth = 1;
    pt_estimate el, eb;
    o.strategy = TT_STRATEGY_LIGHT;
    pt_estimate_ray(&f, &o, &ray, 4000, 9, 5, "independent", &el);
    o.strategy = TT_STRATEGY_BSDF;
    pt_estimate_ray(&f, &o, &ray, 4000, 9, 5, "independent", &eb);
    printf("split image env, -x face: se light-only %.5f, bsdf-only %.5f\n", el.se[0], eb.se[0]);
    CHECK(el.se[0] < eb.se[0]);
  }
  pt_fixture_free(&f);
  unlink(flat);
  unlink(split);
  rmdir(dir);
}

int main(void) {
  closed_box_tests();
  environment_tests();
  image_environment_tests();
  return tt_test_finish("path_furnace");
}
