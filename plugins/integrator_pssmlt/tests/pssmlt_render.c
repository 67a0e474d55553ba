/* integrator_pssmlt end to end (plugin loader, brute-force accel, film): the parameter space
 * and tuning hint, statistics, unbiasedness against the path sampler driven by independent
 * samples (a diffuse box and one with a glossy floor and a mirror, classic and sigma-binned,
 * in both modes — PSSMLT over the path tracer and multiplexed MLT over the bidirectional
 * sampler: whole-image and per-region means within noise bands measured over independent
 * seeds), determinism for 1 and 2 threads (both modes), configure() between passes keeping
 * the chains (a mode change restarts), an all-black scene rendering black (b = 0), the
 * caustic under a glass slab that mmlt renders and pssmlt cannot, point and spot lights only
 * (mmlt, against the path sampler), a light nothing in view can see (b = 0, black), degenerate
 * triangles (finite image), and a stop request. */
#include <stdlib.h>

#include <tunetrace/film.h>
#include <tunetrace/host.h>
#include <tunetrace/integrator.h>
#include <tunetrace/loader.h>
#include <tunetrace/params.h>
#include <tunetrace/tunedb.h>

#include "caustic_scenes.h"
#include "path_common.h"
#include "tt_test.h"

#define W 16
#define H 16
#ifndef RUNS
#  define RUNS 8
#endif
#ifndef MPP
#  define MPP 48
#endif
#define REG 4                            /* regions of REG x REG pixels */
#define NREG ((W / REG) * (H / REG) + 1) /* + the whole image */

#define BOX_SIDES                                                                                  \
  "{\"name\":\"ceiling\",\"material\":\"white\",\"positions\":[-1,1,-1, 1,1,-1, 1,1,1, "           \
  "-1,1,1],\"indices\":[0,1,2, 0,2,3]},"                                                           \
  "{\"name\":\"back\",\"material\":\"white\",\"positions\":[-1,-1,-1, 1,-1,-1, 1,1,-1, "           \
  "-1,1,-1],\"indices\":[0,1,2, 0,2,3]},"                                                          \
  "{\"name\":\"left\",\"material\":\"red\",\"positions\":[-1,-1,-1, -1,1,-1, -1,1,1, "             \
  "-1,-1,1],\"indices\":[0,1,2, 0,2,3]},"                                                          \
  "{\"name\":\"right\",\"material\":\"green\",\"positions\":[1,-1,-1, 1,1,-1, 1,1,1, "             \
  "1,-1,1],\"indices\":[0,1,2, 0,2,3]}"

#define BOX_LAMP                                                                                   \
  "{\"name\":\"light\",\"material\":\"light\",\"positions\":[-0.3,0.98,-0.3, 0.3,0.98,-0.3, "      \
  "0.3,0.98,0.3, -0.3,0.98,0.3],\"indices\":[0,1,2, 0,2,3]}"
#define BOX_WALLS BOX_SIDES "," BOX_LAMP

#define BOX_HEAD                                                                                   \
  "{\"version\":1,\"camera\":{\"position\":[0,0,3.6],\"target\":[0,0,0],\"up\":[0,1,0],\"fov\":"   \
  "40,"                                                                                            \
  "\"resolution\":[16,16]},\"materials\":{"                                                        \
  "\"white\":{\"type\":\"diffuse\",\"albedo\":[0.7,0.7,0.7]},"                                     \
  "\"red\":{\"type\":\"diffuse\",\"albedo\":[0.7,0.1,0.1]},"                                       \
  "\"green\":{\"type\":\"diffuse\",\"albedo\":[0.1,0.7,0.1]},"                                     \
  "\"glossy\":{\"type\":\"plastic\",\"albedo\":[0.3,0.3,0.5],\"alpha\":0.08,\"ior\":1.5},"         \
  "\"mirror\":{\"type\":\"mirror\"},"                                                              \
  "\"light\":{\"type\":\"diffuse\",\"albedo\":[0,0,0],\"emission\":[12,12,10],\"twoSided\":true}}" \
  ","

static const char *DIFFUSE =
    BOX_HEAD "\"meshes\":["
             "{\"name\":\"floor\",\"material\":\"white\",\"positions\":[-1,-1,-1, 1,-1,-1, 1,-1,1, "
             "-1,-1,1],\"indices\":[0,1,2, 0,2,3]}," BOX_WALLS "]}";
static const char *GLOSSY = BOX_HEAD
    "\"meshes\":["
    "{\"name\":\"floor\",\"material\":\"glossy\",\"positions\":[-1,-1,-1, 1,-1,-1, 1,-1,1, "
    "-1,-1,1],\"indices\":[0,1,2, 0,2,3]},"
    "{\"name\":\"panel\",\"material\":\"mirror\",\"positions\":[-0.9,-1,-0.2, -0.3,-1,-0.9, "
    "-0.3,0.3,-0.9, -0.9,0.3,-0.2],\"indices\":[0,1,2, 0,2,3]}," BOX_WALLS "]}";
static const char *BLACK =
    "{\"version\":1,\"camera\":{\"position\":[0,0,3],\"target\":[0,0,0],\"up\":[0,1,0],\"fov\":40,"
    "\"resolution\":[16,16]},\"materials\":{\"grey\":{\"type\":\"diffuse\"}},\"meshes\":["
    "{\"name\":\"q\",\"material\":\"grey\",\"positions\":[-1,-1,0, 1,-1,0, 1,1,0, "
    "-1,1,0],\"indices\":[0,1,2, 0,2,3]}]}";

/* A point and a spot light, no area light: only light tracing and next-event connections
 * reach them (no strategy with s = 0). */
static const char *DELTA =
    BOX_HEAD "\"meshes\":["
             "{\"name\":\"floor\",\"material\":\"glossy\",\"positions\":[-1,-1,-1, 1,-1,-1, "
             "1,-1,1, -1,-1,1],\"indices\":[0,1,2, 0,2,3]}," BOX_SIDES "],\"lights\":["
             "{\"type\":\"point\",\"position\":[0.4,0.6,0.3],\"intensity\":[1.5,1.5,1.2]},"
             "{\"type\":\"spot\",\"position\":[-0.6,0.9,0.6],\"target\":[0,-1,-0.5],\"intensity\":["
             "4,3,3],\"angle\":35}]}";
/* A light inside a closed grey cube, the camera outside: a light exists, none of it reaches
 * the camera (every bootstrap path, camera or light side, has zero contribution). */
static const char *ENCLOSED =
    BOX_HEAD "\"meshes\":["
             "{\"name\":\"cube\",\"material\":\"white\",\"positions\":[-0.5,-0.5,-0.5, "
             "0.5,-0.5,-0.5, 0.5,0.5,-0.5, -0.5,0.5,-0.5,"
             " -0.5,-0.5,0.5, 0.5,-0.5,0.5, 0.5,0.5,0.5, -0.5,0.5,0.5],\"indices\":[0,2,1, 0,3,2, "
             "4,5,6, 4,6,7, 0,1,5, 0,5,4,"
             " 3,6,2, 3,7,6, 0,4,7, 0,7,3, 1,2,6, 1,6,5]},"
             "{\"name\":\"inner\",\"material\":\"light\",\"positions\":[-0.2,0,-0.2, 0.2,0,-0.2, "
             "0.2,0,0.2, -0.2,0,0.2],\"indices\":[0,1,2, 0,2,3]}]}";
/* Degenerate triangles beside real ones (a mesh of nothing but degenerate triangles is a
 * load error, tested in core/tests/scene_errors.c): a zero-area triangle in view, a
 * collinear triangle in the light. */
static const char *DEGENERATE =
    BOX_HEAD "\"meshes\":["
             "{\"name\":\"floor\",\"material\":\"white\",\"positions\":[-1,-1,-1, 1,-1,-1, 1,-1,1, "
             "-1,-1,1],\"indices\":[0,1,2, 0,2,3]}," BOX_SIDES ","
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

/* One integrator, `passes` passes of `spp` into a fresh film; configs[p] (may be NULL) is
 * applied before pass p (p = 0: at create). */
static tt_status render(const setup *s, const char *const *configs, int passes, uint32_t spp,
                        uint64_t seed, tt_film **film_out, tt_pass_stats *stats) {
  tt_config *cfg = tt_config_create(s->space);
  if (configs && configs[0]) CHECK(tt_config_from_json(cfg, configs[0], "test") == TT_OK);
  tt_integrator *it = NULL;
  tt_status st = s->it->create(s->fx.scene, cfg, &it);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (st != TT_OK) {
    tt_config_destroy(cfg);
    return st;
  }
  tt_film *film = tt_film_create(W, H, 0);
  tt_render_ctx ctx;
  memset(&ctx, 0, sizeof ctx);
  ctx.struct_size = sizeof ctx;
  ctx.scene = s->fx.scene;
  ctx.accel_iface = s->fx.tracer.iface;
  ctx.accel = s->fx.accel;
  ctx.film = film;
  ctx.camera = tt_scene_camera(s->fx.scene);
  ctx.seed = seed;
  ctx.spp = spp;
  for (int p = 0; p < passes && st == TT_OK; ++p) {
    if (p > 0 && configs && configs[p]) {
      CHECK(tt_config_from_json(cfg, configs[p], "test") == TT_OK);
      CHECK(s->it->configure(it, cfg) == TT_OK);
    }
    ctx.pass_index = (uint32_t)p;
    ctx.sample_offset = (uint64_t)p * spp;
    if (stats) {
      memset(&stats[p], 0, sizeof stats[p]);
      stats[p].struct_size = sizeof stats[p];
    }
    st = s->it->render_pass(it, &ctx, stats ? &stats[p] : NULL);
  }
  tt_config_destroy(cfg);
  s->it->destroy(it);
  *film_out = film;
  return st;
}

/* Value of metric `name`, NaN if absent. */
static double metric(const tt_pass_stats *ps, const char *name) {
  for (uint32_t m = 0; m < ps->metric_count; ++m)
    if (!strcmp(ps->metrics[m].name, name)) return ps->metrics[m].value;
  return NAN;
}

/* Luminance per region (REG x REG blocks, then the whole image) of a resolved film. */
static void region_means(const tt_film *film, double *out) {
  static float rgb[3 * W * H];
  tt_film_resolve(film, rgb);
  for (int r = 0; r < NREG; ++r) out[r] = 0.0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const float *c = rgb + 3 * (y * W + x);
      double l = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
      out[(y / REG) * (W / REG) + x / REG] += l / (REG * REG);
      out[NREG - 1] += l / (W * H);
    }
}

/* Reference: the same path sampler with independent samples, `spp` per pixel; region means
 * and their standard errors (pixels' sample means treated as independent). */
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
  double s1[NREG] = {0}, s2[NREG] = {0};
  double n[NREG] = {0};
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      int r = (y / REG) * (W / REG) + x / REG;
      for (uint32_t i = 0; i < spp; ++i) {
        src.iface->start(src.sampler, src.state, (uint32_t)x, (uint32_t)y, i);
        float fx = x + src.iface->get(src.sampler, src.state, 0);
        float fy = y + src.iface->get(src.sampler, src.state, 1);
        tt_ray ray;
        tt_camera_generate_ray(&frame, fx, fy, &ray);
        tt_path_result pr;
        tt_path_trace(s->fx.pt, &s->fx.tracer, &o, &ray, &source, &pr);
        double l = 0.2126 * pr.L[0] + 0.7152 * pr.L[1] + 0.0722 * pr.L[2];
        s1[r] += l;
        s2[r] += l * l;
        n[r]++;
        s1[NREG - 1] += l;
        s2[NREG - 1] += l * l;
        n[NREG - 1]++;
      }
    }
  for (int r = 0; r < NREG; ++r) {
    mean[r] = s1[r] / n[r];
    se[r] = sqrt(fmax(0.0, s2[r] / n[r] - mean[r] * mean[r]) / (n[r] - 1));
  }
  src.iface->destroy(src.sampler);
}

/* PSSMLT over RUNS seeds against the reference: every region within 5 combined standard
 * errors (the MLT one from the spread over seeds), and the image mean within 1% + noise. */
static void check_unbiased(const setup *s, const char *label, const char *config, const double *ref,
                           const double *ref_se) {
  double m[RUNS][NREG];
  double acc_small = 0.0;
  for (int k = 0; k < RUNS; ++k) {
    tt_film *film = NULL;
    tt_pass_stats ps;
    const char *cfgs[1] = {config};
    CHECK(render(s, cfgs, 1, MPP, 1000 + 17 * k, &film, &ps) == TT_OK);
    region_means(film, m[k]);
    acc_small += metric(&ps, "small_step_acceptance") / RUNS;
    CHECK(ps.nonfinite == 0);
    tt_film_destroy(film);
  }
  double worst = 0.0;
  int worst_r = 0;
  double mean_img = 0.0, se_img = 0.0;
  for (int r = 0; r < NREG; ++r) {
    double mu = 0.0, var = 0.0;
    for (int k = 0; k < RUNS; ++k) mu += m[k][r] / RUNS;
    for (int k = 0; k < RUNS; ++k) var += (m[k][r] - mu) * (m[k][r] - mu) / (RUNS - 1);
    double se = sqrt(var / RUNS + ref_se[r] * ref_se[r]);
    double z = fabs(mu - ref[r]) / se;
    if (z > worst) {
      worst = z;
      worst_r = r;
    }
    if (r == NREG - 1) {
      mean_img = mu;
      se_img = se;
    }
    CHECK_MSG(z < 5.0, "%s region %d: pssmlt %.5f vs reference %.5f (combined se %.5f)", label, r,
              mu, ref[r], se);
  }
  printf("%s: image mean %.5f vs reference %.5f (%+.2f%%, se %.5f); worst region z = %.2f (region "
         "%d); "
         "small-step acceptance %.3f\n",
         label, mean_img, ref[NREG - 1], 100.0 * (mean_img / ref[NREG - 1] - 1.0), se_img, worst,
         worst_r, acc_small);
  CHECK(fabs(mean_img / ref[NREG - 1] - 1.0) < 0.01 + 3.0 * se_img / ref[NREG - 1]);
}

int main(void) {
  tt_registry *reg = tt_registry_create(tt_default_host());
  tt_loaded_plugin *p = NULL;
  tt_status st = tt_registry_load(reg, "integrator_pssmlt", &p);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  if (st != TT_OK) return tt_test_finish("pssmlt_render");
  const tt_plugin *entry = tt_loaded_plugin_entry(p);
  CHECK(entry->kind == TT_KIND_INTEGRATOR);
  CHECK(strcmp(entry->name, "integrator_pssmlt") == 0);
  setup s;
  memset(&s, 0, sizeof s);
  s.it = tt_loaded_plugin_iface(p);
  s.space = s.it->space();
  CHECK(s.space != NULL);

  /* Parameter space: pbrt-v4's defaults in classic mode, the thesis' for binning. */
  const char *names[] = {"mode",
                         "maxDepth",
                         "largeStepProbability",
                         "sigma",
                         "binning",
                         "bins",
                         "alpha",
                         "a1",
                         "a9",
                         "sigma1",
                         "sigma8",
                         "mutationsPerPixel",
                         "bootstrapSamples",
                         "chains"};
  for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i)
    CHECK_MSG(tt_space_find(s.space, names[i]) >= 0, "missing %s", names[i]);
  tt_config *def = tt_config_create(s.space);
  CHECK(tt_config_get_float(def, "sigma", 0) == 0.01);
  CHECK(tt_config_get_float(def, "largeStepProbability", 0) == 0.3);
  CHECK(tt_config_get_int(def, "bootstrapSamples", 0) == 100000);
  CHECK(tt_config_get_int(def, "chains", 0) == 1000);
  CHECK(tt_config_get_int(def, "maxDepth", 0) == 5);
  CHECK(tt_config_get_int(def, "binning", 1) == 0);
  CHECK(strcmp(tt_config_get_string(def, "mode"), "pssmlt") == 0);
  CHECK_NEAR(tt_config_get_float(def, "alpha", 0), 4.0 * 3.14159265358979, 1e-9);
  int si = tt_space_find(s.space, "sigma3");
  CHECK(tt_space_min(s.space, (size_t)si) == 1e-4 && tt_space_max(s.space, (size_t)si) == 0.3);
  CHECK(tt_space_min(s.space, (size_t)tt_space_find(s.space, "bins")) == 5);
  CHECK(tt_space_max(s.space, (size_t)tt_space_find(s.space, "bins")) == 8);
  tt_config_destroy(def);
  const tt_tuning_hint *hint = tt_loaded_plugin_get(p, TT_TUNING_HINT_ID);
  CHECK(hint && strcmp(hint->objective, "metric:small_step_acceptance:target=0.234") == 0);

  CHECK(pt_fixture_load(&s.fx, DIFFUSE));
  const char *cls = "{\"bootstrapSamples\": 20000, \"chains\": 64}";
  const char *bin =
      "{\"bootstrapSamples\": 20000, \"chains\": 64, \"binning\": true, \"largeStepProbability\": "
      "0.1,"
      " \"sigma1\": 0.003, \"sigma2\": 0.01, \"sigma3\": 0.03, \"sigma4\": 0.06, \"sigma5\": 0.1,"
      " \"sigma6\": 0.2, \"sigma7\": 0.3}";

  /* Statistics of one pass. */
  {
    tt_film *film = NULL;
    tt_pass_stats ps;
    const char *cfgs[1] = {cls};
    CHECK(render(&s, cfgs, 1, 4, 1, &film, &ps) == TT_OK);
    CHECK(ps.samples == 4u * W * H);
    CHECK(metric(&ps, "mutations") == 4.0 * W * H);
    double acc = metric(&ps, "acceptance"), sm = metric(&ps, "small_step_acceptance");
    double lg = metric(&ps, "large_step_acceptance"), b = metric(&ps, "b");
    printf("classic pass: acceptance %.3f small %.3f large %.3f b %.5f, %.0f mutations/s, "
           "bootstrap %.1f ms\n",
           acc, sm, lg, b, metric(&ps, "mutations_per_s"), metric(&ps, "bootstrap_ms"));
    CHECK(acc > 0.0 && acc < 1.0 && sm > lg && lg > 0.0);
    CHECK(sm == metric(&ps, "acceptance_small"));
    CHECK(metric(&ps, "mutations_per_s") > 0.0 && b > 0.0);
    CHECK_NEAR(tt_film_splat_scale(film), b * W * H / (4.0 * W * H), 1e-12 * b);
    CHECK(ps.nonfinite == 0 && ps.rays > ps.samples);
    /* luminance of the splats sums to exactly one per mutation (expected values) */
    const float *sp = tt_film_splat_rgb(film);
    double lum = 0.0;
    for (int i = 0; i < W * H; ++i)
      lum += 0.2126 * sp[3 * i] + 0.7152 * sp[3 * i + 1] + 0.0722 * sp[3 * i + 2];
    CHECK_NEAR(lum, 4.0 * W * H, 1e-3 * W * H);
    tt_film_destroy(film);
  }

  const char *mm_cls = "{\"mode\": \"mmlt\", \"bootstrapSamples\": 5000, \"chains\": 64}";
  const char *mm_bin =
      "{\"mode\": \"mmlt\", \"bootstrapSamples\": 5000, \"chains\": 64, \"binning\": true,"
      " \"largeStepProbability\": 0.1, \"sigma1\": 0.003, \"sigma2\": 0.01, \"sigma3\": 0.03,"
      " \"sigma4\": 0.06, \"sigma5\": 0.1, \"sigma6\": 0.2, \"sigma7\": 0.3}";
  /* Statistics of an mmlt pass: six path depths bootstrapped (5000 each). */
  {
    tt_film *film = NULL;
    tt_pass_stats ps;
    const char *cfgs[1] = {mm_cls};
    CHECK(render(&s, cfgs, 1, 4, 1, &film, &ps) == TT_OK);
    CHECK(ps.samples == 4u * W * H && ps.nonfinite == 0);
    double sm = metric(&ps, "small_step_acceptance"), b = metric(&ps, "b");
    printf(
        "mmlt pass: small-step acceptance %.3f, b %.5f, %.1f rays and %.2f vertices per mutation\n",
        sm, b, metric(&ps, "rays_per_mutation"), metric(&ps, "mean_path_length"));
    CHECK(sm > 0.0 && sm < 1.0 && b > 0.0);
    CHECK(metric(&ps, "rays_per_mutation") > 1.0 && metric(&ps, "mean_path_length") > 1.0);
    const float *sp = tt_film_splat_rgb(film);
    double lum = 0.0;
    for (int i = 0; i < W * H; ++i)
      lum += 0.2126 * sp[3 * i] + 0.7152 * sp[3 * i + 1] + 0.0722 * sp[3 * i + 2];
    CHECK_NEAR(lum, 4.0 * W * H, 1e-3 * W * H);
    tt_film_destroy(film);
  }

  /* Determinism: 1 thread vs 2 threads, bit-identical splats (binning, both modes). */
  for (int mode = 0; mode < 2; ++mode) {
    tt_film *a = NULL, *b = NULL, *c = NULL;
    const char *cfgs[1] = {mode ? mm_bin : bin};
    CHECK(tt_default_host_set_threads(1) == TT_OK);
    CHECK(render(&s, cfgs, 1, 4, 5, &a, NULL) == TT_OK);
    CHECK(tt_default_host_set_threads(2) == TT_OK);
    CHECK(render(&s, cfgs, 1, 4, 5, &b, NULL) == TT_OK);
    CHECK(render(&s, cfgs, 1, 4, 6, &c, NULL) == TT_OK);
    CHECK(memcmp(tt_film_splat_rgb(a), tt_film_splat_rgb(b), 3 * sizeof(float) * W * H) == 0);
    CHECK(tt_film_splat_scale(a) == tt_film_splat_scale(b));
    CHECK(memcmp(tt_film_splat_rgb(a), tt_film_splat_rgb(c), 3 * sizeof(float) * W * H) != 0);
    tt_film_destroy(a);
    tt_film_destroy(b);
    tt_film_destroy(c);
  }

  /* configure() between passes keeps the chains (no second bootstrap, same b) and the film
   * keeps accumulating: the scale counts every mutation. */
  {
    tt_film *film = NULL;
    tt_pass_stats ps[3];
    const char *cfgs[3] = {cls, bin,
                           "{\"bootstrapSamples\": 20000, \"chains\": 64, \"sigma\": 0.05}"};
    CHECK(render(&s, cfgs, 3, 2, 9, &film, ps) == TT_OK);
    CHECK(metric(&ps[0], "bootstrap_ms") > 0.0);
    CHECK(metric(&ps[1], "bootstrap_ms") == 0.0 && metric(&ps[2], "bootstrap_ms") == 0.0);
    CHECK(metric(&ps[1], "b") == metric(&ps[0], "b"));
    CHECK_NEAR(tt_film_splat_scale(film), metric(&ps[0], "b") / 6.0, 1e-12);
    tt_film_destroy(film);
    /* maxDepth changes the target: a restart, with a new bootstrap */
    const char *cfgs2[2] = {cls, "{\"bootstrapSamples\": 20000, \"chains\": 64, \"maxDepth\": 2}"};
    CHECK(render(&s, cfgs2, 2, 2, 9, &film, ps) == TT_OK);
    CHECK(metric(&ps[1], "bootstrap_ms") > 0.0);
    CHECK(metric(&ps[1], "b") < metric(&ps[0], "b"));
    CHECK_NEAR(tt_film_splat_scale(film), metric(&ps[1], "b") / 2.0, 1e-12);
    tt_film_destroy(film);
    /* so does the mode */
    const char *cfgs3[2] = {cls, mm_cls};
    CHECK(render(&s, cfgs3, 2, 2, 9, &film, ps) == TT_OK);
    CHECK(metric(&ps[1], "bootstrap_ms") > 0.0);
    CHECK_NEAR(tt_film_splat_scale(film), metric(&ps[1], "b") / 2.0, 1e-12);
    tt_film_destroy(film);
  }

  /* Unbiasedness against the path sampler with independent samples. */
  {
    double ref[NREG], se[NREG];
    reference(&s, 5, 512, ref, se);
    check_unbiased(&s, "diffuse classic", cls, ref, se);
    check_unbiased(&s, "diffuse binning", bin, ref, se);
    check_unbiased(&s, "diffuse mmlt classic", mm_cls, ref, se);
    check_unbiased(&s, "diffuse mmlt binning", mm_bin, ref, se);
    pt_fixture_free(&s.fx);
    CHECK(pt_fixture_load(&s.fx, GLOSSY));
    reference(&s, 5, 512, ref, se);
    check_unbiased(&s, "glossy+mirror classic", cls, ref, se);
    check_unbiased(&s, "glossy+mirror binning", bin, ref, se);
    check_unbiased(&s, "glossy+mirror mmlt classic", mm_cls, ref, se);
    check_unbiased(&s, "glossy+mirror mmlt binning", mm_bin, ref, se);
    pt_fixture_free(&s.fx);
  }

  /* The caustic under a glass slab: mmlt renders it (about (1 - R)^2 of the open floor),
   * pssmlt (over the path tracer) leaves it black. */
  {
    double centre[3];
    const char *scenes[3] = {TT_CAUSTIC_OPEN, TT_CAUSTIC, TT_CAUSTIC};
    const char *modes[3] = {mm_cls, mm_cls, cls};
    for (int k = 0; k < 3; ++k) {
      CHECK(pt_fixture_load(&s.fx, scenes[k]));
      tt_film *film = NULL;
      const char *cfgs[1] = {modes[k]};
      CHECK(render(&s, cfgs, 1, 64, 3, &film, NULL) == TT_OK);
      static float rgb[3 * W * H];
      tt_film_resolve(film, rgb);
      centre[k] = tt_caustic_centre(rgb);
      tt_film_destroy(film);
      pt_fixture_free(&s.fx);
    }
    printf("caustic: floor under the slab %.4f (mmlt), %.4f (pssmlt); open floor %.4f (mmlt); "
           "ratio %.3f\n",
           centre[1], centre[2], centre[0], centre[1] / centre[0]);
    CHECK(centre[1] / centre[0] > 0.8 && centre[1] / centre[0] < 1.1);
    CHECK(centre[2] < 1e-6 * centre[0]);
  }

  /* A scene with no light: b = 0, passes succeed with a black image (as PT's), no NaN
   * (#13: this used to fail the pass, and the host wrote no image) */
  for (int mode = 0; mode < 2; ++mode) {
    CHECK(pt_fixture_load(&s.fx, BLACK));
    tt_film *film = NULL;
    tt_pass_stats ps[2];
    const char *cfgs[2] = {mode ? "{\"mode\": \"mmlt\", \"bootstrapSamples\": 1000}"
                                : "{\"bootstrapSamples\": 1000}",
                           NULL};
    CHECK(render(&s, cfgs, 2, 1, 1, &film, ps) == TT_OK);
    CHECK(metric(&ps[0], "b") == 0.0 && metric(&ps[1], "mutations") == 0.0);
    float *rgb = malloc(3 * sizeof(float) * W * H);
    tt_film_resolve(film, rgb);
    int nz = 0;
    for (int i = 0; i < 3 * W * H; ++i) nz += !(rgb[i] == 0.0f); /* NaN counts too */
    CHECK(nz == 0);
    free(rgb);
    tt_film_destroy(film);
    pt_fixture_free(&s.fx);
  }

  /* Delta lights (point + spot, no area light) in mmlt: light tracing and connections only,
   * unbiased against the path sampler. */
  {
    CHECK(pt_fixture_load(&s.fx, DELTA));
    double ref[NREG], se[NREG];
    reference(&s, 5, 512, ref, se);
    CHECK(ref[NREG - 1] > 0.0);
    check_unbiased(&s, "point + spot mmlt classic", mm_cls, ref, se);
    pt_fixture_free(&s.fx);
  }

  /* A light nothing in view can see (inside a closed cube): b = 0 and a black image in both
   * modes, no NaN, no hang; degenerate triangles (zero-area, a collinear emitter): a finite,
   * non-negative image with light in it. */
  for (int mode = 0; mode < 2; ++mode) {
    const char *cfgs[1] = {mode ? "{\"mode\": \"mmlt\", \"bootstrapSamples\": 5000, \"chains\": 64}"
                                : "{\"bootstrapSamples\": 5000, \"chains\": 64}"};
    float *rgb = malloc(3 * sizeof(float) * W * H);
    CHECK(pt_fixture_load(&s.fx, ENCLOSED));
    tt_film *film = NULL;
    tt_pass_stats ps;
    g_warnings[0] = '\0';
    tt_default_host_set_log_callback(capture_log, NULL);
    CHECK(render(&s, cfgs, 1, 2, 1, &film, &ps) == TT_OK);
    tt_default_host_set_log_callback(NULL, NULL);
    CHECK_MSG(strstr(g_warnings, "integrator_pssmlt: all ") &&
                  strstr(g_warnings, "have zero contribution"),
              "enclosed light, mode %d: no warning that the image is black; logged: %s", mode,
              g_warnings);
    CHECK(metric(&ps, "b") == 0.0 && ps.nonfinite == 0);
    tt_film_resolve(film, rgb);
    int nz = 0;
    for (int i = 0; i < 3 * W * H; ++i) nz += !(rgb[i] == 0.0f); /* NaN counts too */
    CHECK_MSG(nz == 0, "enclosed light, mode %d: %d non-zero channels", mode, nz);
    tt_film_destroy(film);
    pt_fixture_free(&s.fx);
    if (!pt_fixture_load(&s.fx, DEGENERATE)) {
      CHECK_MSG(0, "the degenerate-triangle scene does not load: %s", tt_last_error());
      free(rgb);
      break;
    }
    CHECK(render(&s, cfgs, 1, 4, 1, &film, &ps) == TT_OK);
    tt_film_resolve(film, rgb);
    int bad = 0;
    double sum = 0.0;
    for (int i = 0; i < 3 * W * H; ++i) {
      bad += !isfinite(rgb[i]) || rgb[i] < 0.0f;
      sum += rgb[i];
    }
    CHECK_MSG(bad == 0 && sum > 0.0 && ps.nonfinite == 0,
              "degenerate triangles, mode %d: %d bad channels, "
              "sum %g, %llu non-finite",
              mode, bad, sum, (unsigned long long)ps.nonfinite);
    tt_film_destroy(film);
    pt_fixture_free(&s.fx);
    free(rgb);
  }

  /* A stop request: the pass returns TT_ERR_INTERRUPTED with a consistent film. */
  {
    CHECK(pt_fixture_load(&s.fx, DIFFUSE));
    tt_default_host_request_stop();
    tt_film *film = NULL;
    tt_pass_stats ps;
    const char *cfgs[1] = {cls};
    CHECK(render(&s, cfgs, 1, 4, 1, &film, &ps) == TT_ERR_INTERRUPTED);
    CHECK(ps.samples < 4u * W * H);
    tt_film_destroy(film);
    pt_fixture_free(&s.fx);
  }

  tt_registry_destroy(reg);
  return tt_test_finish("pssmlt_render");
}
