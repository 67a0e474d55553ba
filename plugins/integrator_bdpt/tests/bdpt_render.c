/* integrator_bdpt end to end (plugin loader, brute-force accel, film):
 *  - the parameter space and its defaults;
 *  - unbiasedness against the path sampler driven by independent samples on scenes the path
 *    tracer can sample: a diffuse box, a glossy floor with a mirror (delta vertices), smooth
 *    shading normals, an open scene under an environment with rough glass (vertices at
 *    infinity, transmission, importance transport), point, spot and distant lights (delta
 *    lights): per-region means within 5 combined standard errors (BDPT's from the spread over
 *    seeds), the image mean within 1% + noise, and per-pixel errors consistent with noise
 *    (mean z^2 near 1);
 *  - the strategy images (TT_BDPT_STRATEGIES): the weighted layers sum to the image, and on
 *    a scene where every strategy is valid each strategy's unweighted image of a path length
 *    estimates the same thing (their weights sum to 1);
 *  - a caustic the path tracer cannot render: a spot light through a smooth glass slab onto
 *    a diffuse floor; the path tracer's floor under the slab is black, BDPT's carries the
 *    transmitted light (Fresnel: about (1 - R)^2 of the unobstructed irradiance);
 *  - determinism for 1 and 2 threads; maxDepth 0; AOVs;
 *  - bad input: no light, and lights (area, spot, point) inside a closed cube that nothing in
 *    view can see (black, no NaN), degenerate triangles (also as a light), a stop request. */
#include <stdlib.h>
#include <unistd.h>

#include <tunetrace/film.h>
#include <tunetrace/host.h>
#include <tunetrace/image.h>
#include <tunetrace/integrator.h>
#include <tunetrace/loader.h>
#include <tunetrace/params.h>

#include "caustic_scenes.h"
#include "path_common.h"
#include "tt_test.h"

#define W 16
#define H 16
#define RUNS 8
#define REG 4
#define NREG ((W / REG) * (H / REG) + 1)

#define HEAD                                                                                       \
  "{\"version\":1,\"camera\":{\"position\":[0,0,3.6],\"target\":[0,0,0],\"up\":[0,1,0],\"fov\":"   \
  "40,"                                                                                            \
  "\"resolution\":[16,16]},\"materials\":{"                                                        \
  "\"white\":{\"type\":\"diffuse\",\"albedo\":[0.7,0.7,0.7]},"                                     \
  "\"red\":{\"type\":\"diffuse\",\"albedo\":[0.7,0.1,0.1]},"                                       \
  "\"green\":{\"type\":\"diffuse\",\"albedo\":[0.1,0.7,0.1]},"                                     \
  "\"glossy\":{\"type\":\"plastic\",\"albedo\":[0.3,0.3,0.5],\"alpha\":0.08,\"ior\":1.5},"         \
  "\"metal\":{\"type\":\"conductor\",\"alpha\":0.2},"                                              \
  "\"mirror\":{\"type\":\"mirror\"},"                                                              \
  "\"rough\":{\"type\":\"dielectric\",\"alpha\":0.15,\"ior\":1.5},"                                \
  "\"glass\":{\"type\":\"dielectric\",\"ior\":1.5},"                                               \
  "\"light\":{\"type\":\"diffuse\",\"albedo\":[0,0,0],\"emission\":[12,12,10]}},"
#define WALLS                                                                                      \
  "{\"name\":\"ceiling\",\"material\":\"white\",\"positions\":[-1,1,-1, 1,1,-1, 1,1,1, "           \
  "-1,1,1],\"indices\":[0,1,2, 0,2,3]},"                                                           \
  "{\"name\":\"back\",\"material\":\"white\",\"positions\":[-1,-1,-1, 1,-1,-1, 1,1,-1, "           \
  "-1,1,-1],\"indices\":[0,1,2, 0,2,3]},"                                                          \
  "{\"name\":\"left\",\"material\":\"red\",\"positions\":[-1,-1,-1, -1,1,-1, -1,1,1, "             \
  "-1,-1,1],\"indices\":[0,1,2, 0,2,3]},"                                                          \
  "{\"name\":\"right\",\"material\":\"green\",\"positions\":[1,-1,-1, 1,1,-1, 1,1,1, "             \
  "1,-1,1],\"indices\":[0,1,2, 0,2,3]}"
#define LAMP                                                                                       \
  "{\"name\":\"light\",\"material\":\"light\",\"positions\":[-0.3,0.98,-0.3, 0.3,0.98,-0.3, "      \
  "0.3,0.98,0.3, -0.3,0.98,0.3],\"indices\":[0,1,2, 0,2,3]}"
#define FLOOR(mat)                                                                                 \
  "{\"name\":\"floor\",\"material\":\"" mat                                                        \
  "\",\"positions\":[-1,-1,-1, 1,-1,-1, 1,-1,1, -1,-1,1],\"indices\":[0,1,2, 0,2,3]}"
#define BLOCK(mat)                                                                                 \
  "{\"name\":\"block\",\"material\":\"" mat                                                        \
  "\",\"positions\":[-0.5,-1,-0.3, 0.1,-1,-0.3, 0.1,-0.3,-0.3, -0.5,-0.3,-0.3,"                    \
  " -0.5,-1,0.3, 0.1,-1,0.3, 0.1,-0.3,0.3, -0.5,-0.3,0.3],\"indices\":[0,2,1, 0,3,2, 4,5,6, "      \
  "4,6,7, 0,1,5, 0,5,4,"                                                                           \
  " 3,6,2, 3,7,6, 0,4,7, 0,7,3, 1,2,6, 1,6,5]}"

static const char *DIFFUSE = HEAD "\"meshes\":[" FLOOR("white") "," WALLS "," LAMP "]}";
static const char *GLOSSY = HEAD "\"meshes\":[" FLOOR(
    "glossy") ","
              "{\"name\":\"panel\",\"material\":\"mirror\",\"positions\":[-0.9,-1,-0.2, "
              "-0.3,-1,-0.9, -0.3,0.3,-0.9, -0.9,0.3,-0.2],\"indices\":[0,1,2, 0,2,3]}," WALLS
              "," LAMP "]}";
static const char *NORMALS =
    HEAD "\"meshes\":[" FLOOR("metal") "," WALLS "," LAMP ","
                                       "{\"name\":\"bent\",\"material\":\"white\",\"positions\":[-"
                                       "0.6,-1,0.2, 0.4,-1,-0.5, 0.4,0.2,-0.5, -0.6,0.2,0.2],"
                                       "\"indices\":[0,1,2, 0,2,3],\"normals\":[0.5,0.3,0.8, "
                                       "0.7,-0.2,0.6, 0.8,0.1,0.5, 0.4,0.4,0.8]}]}";
static const char *ENV =
    HEAD "\"meshes\":["
         "{\"name\":\"ground\",\"material\":\"white\",\"positions\":[-4,-1,-4, 4,-1,-4, 4,-1,4, "
         "-4,-1,4],\"indices\":[0,2,1, 0,3,2]}," BLOCK(
             "rough") "],\"lights\":[{\"type\":\"environment\",\"radiance\":[0.4,0.5,0.7]}]}";
static const char *DELTA = HEAD "\"meshes\":[" FLOOR("glossy") "," WALLS "," BLOCK(
    "white") "],\"lights\":["
             "{\"type\":\"point\",\"position\":[0.4,0.6,0.3],\"intensity\":[1.5,1.5,1.2]},"
             "{\"type\":\"spot\",\"position\":[-0.6,0.9,0.6],\"target\":[0,-1,-0.5],\"intensity\":["
             "4,3,3],\"angle\":35}]}";
static const char *DISTANT =
    HEAD "\"meshes\":["
         "{\"name\":\"ground\",\"material\":\"white\",\"positions\":[-4,-1,-4, 4,-1,-4, 4,-1,4, "
         "-4,-1,4],\"indices\":[0,2,1, 0,3,2]}," BLOCK(
             "metal") "],\"lights\":[{\"type\":\"distant\",\"direction\":[0.3,-1,-0.4],"
                      "\"irradiance\":[2,2,2]}]}";
static const char *BLACK = HEAD "\"meshes\":[" FLOOR("white") "," WALLS "]}";
/* A light inside a closed cube, the camera outside: no path from the light reaches the camera,
 * whichever side builds it (light tracing included). */
static const char *ENCLOSED =
    HEAD "\"meshes\":["
         "{\"name\":\"cube\",\"material\":\"white\",\"positions\":[-0.5,-0.5,-0.5, 0.5,-0.5,-0.5, "
         "0.5,0.5,-0.5, -0.5,0.5,-0.5,"
         " -0.5,-0.5,0.5, 0.5,-0.5,0.5, 0.5,0.5,0.5, -0.5,0.5,0.5],\"indices\":[0,2,1, 0,3,2, "
         "4,5,6, 4,6,7, 0,1,5, 0,5,4,"
         " 3,6,2, 3,7,6, 0,4,7, 0,7,3, 1,2,6, 1,6,5]},"
         "{\"name\":\"light\",\"material\":\"light\",\"positions\":[-0.2,0.3,-0.2, 0.2,0.3,-0.2, "
         "0.2,0.3,0.2, -0.2,0.3,0.2],\"indices\":[0,1,2, 0,2,3]}],"
         "\"lights\":[{\"type\":\"spot\",\"position\":[0,-0.3,0],\"target\":[0,-1,0.2],"
         "\"intensity\":[4,4,4],\"angle\":50},"
         "{\"type\":\"point\",\"position\":[0.2,0,0.1],\"intensity\":[2,2,2]}]}";
/* Degenerate triangles: a zero-area floor triangle, a collinear light triangle. */
static const char *DEGENERATE = HEAD "\"meshes\":[" FLOOR(
    "white") "," WALLS ","
             "{\"name\":\"flat\",\"material\":\"white\",\"positions\":[0,0,0, 0,0,0, 0.5,0.5,0, "
             "0.5,-0.5,0],\"indices\":[0,1,2, 0,2,3]},"
             "{\"name\":\"light\",\"material\":\"light\",\"positions\":[-0.3,0.98,-0.3, "
             "0.3,0.98,-0.3, 0.3,0.98,0.3, -0.3,0.98,0.3, 0,0.98,0],"
             "\"indices\":[0,1,2, 0,2,3, 0,4,2]}]}";
/* Warnings the plugin logged (tt_default_host's log callback). */
static char g_warnings[4096];
static void capture_log(void *user, tt_log_level level, const char *plugin, const char *message) {
  (void)user;
  if (level < TT_LOG_WARN || strlen(g_warnings) + strlen(message) + 2 > sizeof g_warnings) return;
  strcat(g_warnings, plugin ? plugin : "-");
  strcat(g_warnings, ": ");
  strcat(g_warnings, message);
  strcat(g_warnings, "\n");
}

typedef struct setup {
  const tt_integrator_iface *it;
  const tt_space *space;
  pt_fixture fx;
} setup;

/* One integrator, `passes` passes of `spp` into a fresh film (AOV planes `aovs`). */
static tt_status render(const setup *s, const char *config, int passes, uint32_t spp, uint64_t seed,
                        uint32_t aovs, tt_film **film_out, tt_pass_stats *stats) {
  tt_config *cfg = tt_config_create(s->space);
  if (config) CHECK(tt_config_from_json(cfg, config, "test") == TT_OK);
  tt_integrator *it = NULL;
  tt_status st = s->it->create(s->fx.scene, cfg, &it);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  tt_config_destroy(cfg);
  if (st != TT_OK) return st;
  const tt_camera *cam = tt_scene_camera(s->fx.scene);
  tt_film *film = tt_film_create(cam->width, cam->height, aovs);
  tt_render_ctx ctx;
  memset(&ctx, 0, sizeof ctx);
  ctx.struct_size = sizeof ctx;
  ctx.scene = s->fx.scene;
  ctx.accel_iface = s->fx.tracer.iface;
  ctx.accel = s->fx.accel;
  ctx.film = film;
  ctx.camera = cam;
  ctx.seed = seed;
  ctx.spp = spp;
  for (int p = 0; p < passes && st == TT_OK; ++p) {
    ctx.pass_index = (uint32_t)p;
    ctx.sample_offset = (uint64_t)p * spp;
    if (stats) {
      memset(&stats[p], 0, sizeof stats[p]);
      stats[p].struct_size = sizeof stats[p];
    }
    st = s->it->render_pass(it, &ctx, stats ? &stats[p] : NULL);
  }
  s->it->destroy(it);
  *film_out = film;
  return st;
}

static double metric(const tt_pass_stats *ps, const char *name) {
  for (uint32_t m = 0; m < ps->metric_count; ++m)
    if (!strcmp(ps->metrics[m].name, name)) return ps->metrics[m].value;
  return NAN;
}

static double lum(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

/* Per-pixel luminance of a resolved film. */
static void pixels_of(const tt_film *film, double *out) {
  static float rgb[3 * W * H];
  tt_film_resolve(film, rgb);
  for (int i = 0; i < W * H; ++i) out[i] = lum(rgb + 3 * i);
}

/* Reference: the path sampler with independent samples, `spp` per pixel, rr off; per-pixel
 * luminance means and standard errors. */
static void reference(const setup *s, uint32_t max_depth, uint32_t spp, double *mean, double *se) {
  tt_path_options o;
  tt_path_options_default(&o);
  o.max_depth = max_depth;
  o.rr_depth = max_depth;
  tt_camera_frame frame;
  CHECK(tt_camera_frame_init(&frame, tt_scene_camera(s->fx.scene)) == TT_OK);
  pt_sampler_src src;
  memset(&src, 0, sizeof src);
  src.iface = tt_builtin_sampler("independent");
  src.iface->create(NULL, 777, &src.sampler);
  tt_sample_source source = {pt_src_get, NULL, &src};
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      double s1 = 0, s2 = 0;
      for (uint32_t i = 0; i < spp; ++i) {
        src.iface->start(src.sampler, src.state, (uint32_t)x, (uint32_t)y, i);
        float fx = x + src.iface->get(src.sampler, src.state, 0);
        float fy = y + src.iface->get(src.sampler, src.state, 1);
        tt_ray ray;
        tt_camera_generate_ray(&frame, fx, fy, &ray);
        tt_path_result pr;
        tt_path_trace(s->fx.pt, &s->fx.tracer, &o, &ray, &source, &pr);
        double l = lum(pr.L);
        s1 += l;
        s2 += l * l;
      }
      mean[y * W + x] = s1 / spp;
      se[y * W + x] = sqrt(fmax(0.0, s2 / spp - (s1 / spp) * (s1 / spp)) / (spp - 1));
    }
  src.iface->destroy(src.sampler);
}

/* BDPT over RUNS seeds against the reference: regions within 5 combined standard errors,
 * the image mean within 1% + noise, per-pixel mean z^2 below 2 (1 expected). */
static void check_unbiased(const setup *s, const char *label, const char *config, uint32_t spp,
                           const double *ref, const double *ref_se) {
  static double px[RUNS][W * H];
  for (int k = 0; k < RUNS; ++k) {
    tt_film *film = NULL;
    tt_pass_stats ps;
    CHECK(render(s, config, 1, spp, 1000 + 17 * k, 0, &film, &ps) == TT_OK);
    CHECK(ps.nonfinite == 0);
    pixels_of(film, px[k]);
    tt_film_destroy(film);
  }
  double worst = 0.0, z2 = 0.0;
  int worst_r = 0, zn = 0;
  double img_mu = 0, img_var = 0, img_ref = 0, img_ref_var = 0;
  for (int r = 0; r < NREG; ++r) {
    double m[RUNS], rm = 0.0, rv = 0.0;
    int cnt = 0;
    for (int k = 0; k < RUNS; ++k) m[k] = 0.0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        if (r < NREG - 1 && (y / REG) * (W / REG) + x / REG != r) continue;
        for (int k = 0; k < RUNS; ++k) m[k] += px[k][y * W + x];
        rm += ref[y * W + x];
        rv += ref_se[y * W + x] * ref_se[y * W + x];
        cnt++;
      }
    double mu = 0.0, var = 0.0;
    for (int k = 0; k < RUNS; ++k) mu += m[k] / cnt / RUNS;
    for (int k = 0; k < RUNS; ++k) var += (m[k] / cnt - mu) * (m[k] / cnt - mu) / (RUNS - 1);
    rm /= cnt;
    rv /= (double)cnt * cnt;
    double se =
        sqrt(var / RUNS + rv) + 1e-6 * fabs(rm); /* floor: pixels that see only a constant */
    double z = se > 0 ? fabs(mu - rm) / se : (mu == rm ? 0.0 : INFINITY);
    if (z > worst) {
      worst = z;
      worst_r = r;
    }
    if (r == NREG - 1) {
      img_mu = mu;
      img_var = var / RUNS;
      img_ref = rm;
      img_ref_var = rv;
    }
    CHECK_MSG(z < 5.0, "%s region %d: bdpt %.5f vs reference %.5f (combined se %.5f)", label, r, mu,
              rm, se);
  }
  for (int i = 0; i < W * H; ++i) {
    double mu = 0, var = 0;
    for (int k = 0; k < RUNS; ++k) mu += px[k][i] / RUNS;
    for (int k = 0; k < RUNS; ++k) var += (px[k][i] - mu) * (px[k][i] - mu) / (RUNS - 1);
    double v = var / RUNS + ref_se[i] * ref_se[i];
    if (v > 1e-10 * ref[i] * ref[i]) {
      z2 += (mu - ref[i]) * (mu - ref[i]) / v;
      zn++;
    }
  }
  double se_img = sqrt(img_var + img_ref_var);
  printf("%-18s image mean %.5f vs path tracer %.5f (%+.2f%%, se %.5f); worst region z %.2f (%d); "
         "pixels: mean z^2 %.2f over %d\n",
         label, img_mu, img_ref, 100.0 * (img_mu / img_ref - 1.0), se_img, worst, worst_r,
         zn ? z2 / zn : 0.0, zn);
  CHECK(fabs(img_mu / img_ref - 1.0) < 0.01 + 3.0 * se_img / img_ref);
  CHECK_MSG(zn == 0 || z2 / zn < 2.0, "%s: per-pixel mean z^2 %.2f", label, z2 / zn);
}

static void unbiased_scene(setup *s, const char *label, const char *json, uint32_t depth,
                           uint32_t spp) {
  static double ref[W * H], se[W * H];
  CHECK(pt_fixture_load(&s->fx, json));
  if (!s->fx.pt) return;
  reference(s, depth, 2048, ref, se);
  char cfg[128];
  snprintf(cfg, sizeof cfg, "{\"maxDepth\": %u, \"rrDepth\": 2}", depth);
  check_unbiased(s, label, cfg, spp, ref, se);
  pt_fixture_free(&s->fx);
}

/* The strategy images over SEEDS renders of the diffuse box: the weighted layers sum to the
 * image; for each path length, every strategy's unweighted image mean agrees with next-event
 * estimation's (s = 1) within 5 standard errors from the spread over seeds, + 2%. */
#define SEEDS 4
static void check_strategies(setup *s) {
  char path[64];
  snprintf(path, sizeof path, "/tmp/tt_bdpt_strategies_%d.exr", (int)getpid());
  /* OpenEXR keeps channels sorted by name and OpenImageIO returns them layer by layer (layers
   * sorted by name, R, G, B within each): find each strategy layer's place in the file. */
  static char names[13 * 2][40];
  int order[13 * 6];
  {
    int n = 0;
    for (uint32_t k = 0; k <= 3; ++k)
      for (uint32_t s2 = 0; s2 <= k + 1; ++s2) {
        if (k == 0 && s2 == 1) continue;
        for (int wu = 0; wu < 2; ++wu)
          snprintf(names[n++], 40, "s%u_t%u.%s", s2, k + 2 - s2, wu ? "unweighted" : "weighted");
      }
    for (int i = 0; i < n; ++i) {
      int rank = 0;
      for (int j = 0; j < n; ++j) rank += strcmp(names[j], names[i]) < 0;
      for (int c3 = 0; c3 < 3; ++c3) order[6 * (i / 2) + 3 * (i % 2) + c3] = 3 * rank + c3;
    }
  }
  CHECK(pt_fixture_load(&s->fx, DIFFUSE));
  double mean[SEEDS][13];
  double worst = 0.0;
  for (int k = 0; k < SEEDS; ++k) {
    setenv("TT_BDPT_STRATEGIES", path, 1);
    tt_film *film = NULL;
    CHECK(render(s, "{\"maxDepth\": 3}", 2, 32, 50 + (uint64_t)k, 0, &film, NULL) == TT_OK);
    unsetenv("TT_BDPT_STRATEGIES");
    uint32_t w = 0, h = 0, c = 0;
    float *px = NULL;
    CHECK(tt_image_read(path, &w, &h, &c, &px) == TT_OK);
    /* strategies of depths 0..3: 1 + 3 + 4 + 5 = 13, 6 channels each */
    CHECK_MSG(w == W && h == H && c == 13 * 6, "%ux%u, %u channels", w, h, c);
    if (px && c == 13 * 6) {
      static float rgb[3 * W * H];
      tt_film_resolve(film, rgb);
      for (int i = 0; i < W * H; ++i)
        for (int ch = 0; ch < 3; ++ch) {
          double sum = 0.0;
          for (int st = 0; st < 13; ++st) sum += px[(size_t)i * c + order[6 * st + ch]];
          double e = fabs(sum - rgb[3 * i + ch]) / fmax(1e-3, fabs(rgb[3 * i + ch]));
          if (e > worst) worst = e;
        }
      for (int st = 0; st < 13; ++st) {
        mean[k][st] = 0.0;
        for (int i = 0; i < W * H; ++i) {
          const float *q = px + (size_t)i * c;
          float u[3] = {q[order[6 * st + 3]], q[order[6 * st + 4]], q[order[6 * st + 5]]};
          mean[k][st] += lum(u) / (W * H);
        }
      }
    }
    tt_free(px);
    tt_film_destroy(film);
    unlink(path);
  }
  printf("strategy images: weighted layers sum to the image within %.2e (relative)\n", worst);
  CHECK(worst < 1e-4);
  uint32_t base = 1; /* strategy index within depth k: s = 0..k+1 (depth 0: only s = 0) */
  for (uint32_t k = 1; k <= 3; ++k) {
    double mu[8], se[8];
    printf("depth %u, unweighted image means:", k);
    for (uint32_t s2 = 0; s2 <= k + 1; ++s2) {
      mu[s2] = se[s2] = 0.0;
      for (int q = 0; q < SEEDS; ++q) mu[s2] += mean[q][base + s2] / SEEDS;
      for (int q = 0; q < SEEDS; ++q)
        se[s2] += pow(mean[q][base + s2] - mu[s2], 2) / (SEEDS - 1) / SEEDS;
      se[s2] = sqrt(se[s2]);
      printf(" s%u_t%u %.4f (%.4f)", s2, k + 2 - s2, mu[s2], se[s2]);
    }
    printf("\n");
    for (uint32_t s2 = 0; s2 <= k + 1; ++s2)
      CHECK_MSG(fabs(mu[s2] - mu[1]) < 5.0 * sqrt(se[s2] * se[s2] + se[1] * se[1]) + 0.02 * mu[1],
                "depth %u: s%u mean %.4f vs s1 %.4f", k, s2, mu[s2], mu[1]);
    base += k + 2;
  }
  pt_fixture_free(&s->fx);
}

/* Mean luminance of the film's central 6x6 pixels (under the slab). */
static double centre_mean(const tt_film *film) {
  static float rgb[3 * W * H];
  tt_film_resolve(film, rgb);
  return tt_caustic_centre(rgb);
}

int main(void) {
  tt_registry *reg = tt_registry_create(tt_default_host());
  tt_loaded_plugin *p = NULL;
  tt_status st = tt_registry_load(reg, "integrator_bdpt", &p);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (st != TT_OK) return tt_test_finish("bdpt_render");
  const tt_plugin *entry = tt_loaded_plugin_entry(p);
  CHECK(entry->kind == TT_KIND_INTEGRATOR && strcmp(entry->name, "integrator_bdpt") == 0);
  setup s;
  memset(&s, 0, sizeof s);
  s.it = tt_loaded_plugin_iface(p);
  s.space = s.it->space();
  tt_config *def = tt_config_create(s.space);
  CHECK(tt_config_get_int(def, "maxDepth", 0) == 5);
  CHECK(tt_config_get_int(def, "rrDepth", 0) == 3);
  CHECK(strcmp(tt_config_get_string(def, "heuristic"), "power") == 0);
  CHECK(strcmp(tt_config_get_string(def, "sampler"), "sobol") == 0);
  tt_config_destroy(def);

  /* Unbiasedness against the path tracer. */
  unbiased_scene(&s, "diffuse box", DIFFUSE, 4, 64);
  unbiased_scene(&s, "glossy + mirror", GLOSSY, 4, 64);
  unbiased_scene(&s, "shading normals", NORMALS, 3, 64);
  unbiased_scene(&s, "environment+glass", ENV, 4, 64);
  unbiased_scene(&s, "point + spot", DELTA, 3, 64);
  unbiased_scene(&s, "distant", DISTANT, 3, 64);

  /* Statistics, determinism across thread counts, a balance-heuristic render, AOVs. */
  CHECK(pt_fixture_load(&s.fx, GLOSSY));
  {
    tt_film *a = NULL, *b = NULL, *c = NULL;
    tt_pass_stats ps[2];
    CHECK(tt_default_host_set_threads(1) == TT_OK);
    CHECK(render(&s, "{\"tileSize\": 8}", 2, 2, 5, TT_AOV_NORMAL | TT_AOV_DEPTH, &a, ps) == TT_OK);
    CHECK(tt_default_host_set_threads(2) == TT_OK);
    CHECK(render(&s, "{\"tileSize\": 8}", 2, 2, 5, TT_AOV_NORMAL | TT_AOV_DEPTH, &b, NULL) ==
          TT_OK);
    CHECK(render(&s, "{\"tileSize\": 8}", 2, 2, 6, 0, &c, NULL) == TT_OK);
    CHECK(memcmp(tt_film_sum_rgb(a), tt_film_sum_rgb(b), 3 * sizeof(float) * W * H) == 0);
    CHECK(memcmp(tt_film_splat_rgb(a), tt_film_splat_rgb(b), 3 * sizeof(float) * W * H) == 0);
    CHECK(memcmp(tt_film_aov(a, TT_AOV_NORMAL), tt_film_aov(b, TT_AOV_NORMAL),
                 3 * sizeof(float) * W * H) == 0);
    CHECK(memcmp(tt_film_splat_rgb(a), tt_film_splat_rgb(c), 3 * sizeof(float) * W * H) != 0);
    CHECK_NEAR(tt_film_splat_scale(a), 1.0 / 4.0, 1e-12); /* 2 passes of 2 spp */
    CHECK(ps[0].samples == 2u * W * H && ps[0].rays > ps[0].samples && ps[0].nonfinite == 0);
    printf("glossy box: %.1f rays and %.2f splats per sample, %.0f samples/s\n",
           metric(&ps[0], "rays_per_sample"), metric(&ps[0], "splats_per_sample"),
           metric(&ps[0], "samples_per_s"));
    CHECK(metric(&ps[0], "splats_per_sample") > 0.1);
    const float *depth = tt_film_aov(a, TT_AOV_DEPTH);
    int hits = 0;
    for (int i = 0; i < W * H; ++i) hits += depth[i] > 2.0f && depth[i] < 5.0f;
    CHECK(hits > W * H / 2);
    tt_film_destroy(a);
    tt_film_destroy(b);
    tt_film_destroy(c);
  }
  /* maxDepth 0: directly visible emission only, as the path tracer's */
  {
    tt_film *f0 = NULL;
    CHECK(render(&s, "{\"maxDepth\": 0}", 1, 256, 1, 0, &f0, NULL) == TT_OK);
    static double a[W * H], ref[W * H], se[W * H];
    pixels_of(f0, a);
    reference(&s, 0, 256, ref, se);
    double sa = 0, sr = 0, v = 0;
    for (int i = 0; i < W * H; ++i) {
      sa += a[i];
      sr += ref[i];
      v += se[i] * se[i];
    }
    printf("maxDepth 0: image sum %.3f, path tracer %.3f (se %.3f)\n", sa, sr, sqrt(v));
    CHECK(sr > 0 && fabs(sa - sr) < 5.0 * sqrt(2.0 * v));
    tt_film_destroy(f0);
  }
  pt_fixture_free(&s.fx);

  /* Strategy images. */
  check_strategies(&s);

  /* The caustic: path tracer black under the slab, BDPT about (1 - R)^2 of the open floor. */
  {
    double open_ref[W * H], se[W * H], pt_px[W * H];
    CHECK(pt_fixture_load(&s.fx, TT_CAUSTIC_OPEN));
    tt_film *fo = NULL;
    CHECK(render(&s, "{\"maxDepth\": 4}", 1, 64, 3, 0, &fo, NULL) == TT_OK);
    double open = centre_mean(fo);
    reference(&s, 4, 64, open_ref, se);
    tt_film_destroy(fo);
    pt_fixture_free(&s.fx);
    CHECK(pt_fixture_load(&s.fx, TT_CAUSTIC));
    tt_film *fc = NULL;
    CHECK(render(&s, "{\"maxDepth\": 4}", 1, 256, 3, 0, &fc, NULL) == TT_OK);
    double caustic = centre_mean(fc);
    reference(&s, 4, 64, pt_px, se);
    double ptc = 0;
    for (int y = 5; y < 11; ++y)
      for (int x = 5; x < 11; ++x) ptc += pt_px[y * W + x] / 36.0;
    double R = pow((1.5 - 1.0) / (1.5 + 1.0), 2.0);
    printf("caustic: floor under the slab %.4f (BDPT), %.4f (path tracer); open floor %.4f; ratio "
           "%.3f "
           "((1 - R)^2 = %.3f)\n",
           caustic, ptc, open, caustic / open, (1 - R) * (1 - R));
    CHECK(ptc < 1e-6 * open);
    CHECK(caustic / open > 0.85 && caustic / open < 1.05);
    tt_film_destroy(fc);
    pt_fixture_free(&s.fx);
  }

  /* Bad input: no light (black, no NaN); degenerate triangles; a stop request. */
  {
    CHECK(pt_fixture_load(&s.fx, BLACK));
    tt_film *film = NULL;
    tt_pass_stats ps;
    CHECK(render(&s, NULL, 1, 2, 1, 0, &film, &ps) == TT_OK);
    static float rgb[3 * W * H];
    tt_film_resolve(film, rgb);
    int nz = 0;
    for (int i = 0; i < 3 * W * H; ++i) nz += !(rgb[i] == 0.0f);
    CHECK(nz == 0 && ps.nonfinite == 0);
    tt_film_destroy(film);
    pt_fixture_free(&s.fx);
    /* lights (area, spot, point) that nothing in view can see: black, every strategy tried */
    CHECK(pt_fixture_load(&s.fx, ENCLOSED));
    g_warnings[0] = '\0';
    tt_default_host_set_log_callback(capture_log, NULL);
    CHECK(render(&s, NULL, 1, 8, 1, 0, &film, &ps) == TT_OK);
    tt_default_host_set_log_callback(NULL, NULL);
    CHECK_MSG(strstr(g_warnings, "integrator_bdpt: no light reached the camera in 2048 samples") !=
                  NULL,
              "enclosed lights: no warning that the image is black; logged: %s", g_warnings);
    tt_film_resolve(film, rgb);
    nz = 0;
    for (int i = 0; i < 3 * W * H; ++i) nz += !(rgb[i] == 0.0f);
    CHECK_MSG(nz == 0 && ps.nonfinite == 0 && ps.rays > ps.samples,
              "enclosed lights: %d non-zero channels", nz);
    tt_film_destroy(film);
    pt_fixture_free(&s.fx);
    CHECK(pt_fixture_load(&s.fx, DEGENERATE));
    CHECK(render(&s, NULL, 1, 8, 1, 0, &film, &ps) == TT_OK);
    tt_film_resolve(film, rgb);
    int bad = 0;
    double m = 0;
    for (int i = 0; i < 3 * W * H; ++i) {
      bad += !isfinite(rgb[i]) || rgb[i] < 0.0f;
      m += rgb[i];
    }
    CHECK(bad == 0 && m > 0 && ps.nonfinite == 0);
    tt_film_destroy(film);
    tt_default_host_request_stop();
    CHECK(render(&s, NULL, 1, 4, 1, 0, &film, &ps) == TT_ERR_INTERRUPTED);
    CHECK(ps.samples < 4u * W * H);
    tt_film_destroy(film);
    pt_fixture_free(&s.fx);
  }
  tt_registry_destroy(reg);
  return tt_test_finish("bdpt_render");
}
