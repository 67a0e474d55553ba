/* post_taa, mode vctaa, through the plugin loader: convergence toward the jitter-averaged
 * image on a static scene, tracking a moving pattern with exact motion vectors without
 * ghost trails, reset_history / reset(), passthrough mode and argument errors. Images are
 * analytic (sampled at the jittered pixel positions), so no renderer is involved. */
#include "tt_test.h"

#include <tunetrace/camera.h>
#include <tunetrace/loader.h>
#include <tunetrace/post.h>

#define W 64
#define H 48

static const tt_post_iface *g_post;
static const tt_space *g_space;

/* Thin slanted lines (under-resolved, so a single sample per pixel aliases). */
static float pattern_lines(float x, float y) {
  float u = x * 0.9f + y * 0.35f;
  float f = u - 3.7f * floorf(u / 3.7f);
  return f < 0.8f ? 1.0f : 0.02f;
}

/* A bright square of side 12 whose top-left corner is at (cx, cy), on a dark ground. */
static float g_cx, g_cy;
static float pattern_square(float x, float y) {
  return (x >= g_cx && x < g_cx + 12.0f && y >= g_cy && y < g_cy + 12.0f) ? 4.0f : 0.05f;
}

/* Renders `fn` with one sample per pixel at the given jitter (grey RGB). */
static void render(float (*fn)(float, float), const float jitter[2], float *rgb) {
  for (int y = 0; y < H; y++)
    for (int x = 0; x < W; x++) {
      float v = fn(x + 0.5f + jitter[0], y + 0.5f + jitter[1]);
      for (int c = 0; c < 3; c++) rgb[3 * (y * W + x) + c] = v;
    }
}

/* Tonemapped value, the space the resolve averages in. */
static float tm(float v) { return v / (1.0f + v); }

/* RMSE in tonemapped space between an output and a reference (both linear grey RGB). */
static double rmse_tm(const float *a, const float *b, int border) {
  double s = 0.0;
  int n = 0;
  for (int y = border; y < H - border; y++)
    for (int x = border; x < W - border; x++) {
      double d = tm(a[3 * (y * W + x)]) - tm(b[3 * (y * W + x)]);
      s += d * d;
      n++;
    }
  return sqrt(s / n);
}

/* Creates a filter with `pairs` ("name", "value", ..., NULL) applied. */
static tt_post *make(const char *k1, const char *v1) {
  tt_config *c = tt_config_create(g_space);
  if (k1) CHECK_MSG(tt_config_set_string(c, k1, v1) == TT_OK, "%s", tt_last_error());
  tt_post *p = NULL;
  CHECK_MSG(g_post->create(W, H, c, &p) == TT_OK, "%s", tt_last_error());
  tt_config_destroy(c);
  return p;
}

/* Static scene: error against the jitter-averaged image falls over the frames. */
static void test_static_convergence(void) {
  static float color[W * H * 3], out[W * H * 3], ref[W * H * 3], tmp[W * H * 3];
  memset(ref, 0, sizeof ref);
  for (uint32_t j = 0; j < 8; j++) {
    float jit[2];
    tt_jitter_halton23(j, jit);
    render(pattern_lines, jit, tmp);
    for (int i = 0; i < W * H * 3; i++) ref[i] += tm(tmp[i]) / 8.0f;
  }
  for (int i = 0; i < W * H * 3; i++) ref[i] = ref[i] / (1.0f - ref[i]); /* back to linear */
  tt_post *p = make(NULL, NULL);
  double err[33];
  for (uint32_t k = 0; k <= 32; k++) {
    tt_post_frame f = {.struct_size = sizeof f,
                       .width = W,
                       .height = H,
                       .color = color,
                       .frame_index = k,
                       .jitter_index = k % 8};
    tt_jitter_halton23(k % 8, f.jitter);
    render(pattern_lines, f.jitter, color);
    CHECK(g_post->process(p, &f, out) == TT_OK);
    err[k] = rmse_tm(out, ref, 1);
  }
  printf("static: rmse vs jitter average: frame 0 %.4f, 4 %.4f, 8 %.4f, 16 %.4f, 32 %.4f\n", err[0],
         err[4], err[8], err[16], err[32]);
  CHECK(err[8] < err[0]);
  CHECK(err[16] < err[0] * 0.75);
  CHECK(err[32] < err[0] * 0.75);
  /* Averages over a jitter cycle fall too (single frames wobble with the jitter). */
  double a = 0, b = 0;
  for (int k = 1; k <= 8; k++) a += err[k];
  for (int k = 25; k <= 32; k++) b += err[k];
  CHECK(b < a);
  g_post->destroy(p);
}

/* Moving square: with exact motion the output follows it and no trail stays behind;
 * returns the last frame's RMSE against the supersampled reference. */
static double run_moving(int use_motion, double *ghost_out, double *raw_out) {
  static float color[W * H * 3], out[W * H * 3], ref[W * H * 3], motion[W * H * 2];
  const float vx = 1.3f, vy = 0.4f;
  for (int i = 0; i < W * H; i++) {
    motion[2 * i] = -vx; /* from this frame back to the previous one */
    motion[2 * i + 1] = -vy;
  }
  tt_post *p = make(NULL, NULL);
  double worst_ghost = 0.0, last_err = 0.0, raw_err = 0.0;
  for (uint32_t k = 0; k < 24; k++) {
    g_cx = 6.0f + vx * k;
    g_cy = 10.0f + vy * k;
    tt_post_frame f = {.struct_size = sizeof f,
                       .width = W,
                       .height = H,
                       .color = color,
                       .motion = use_motion ? motion : NULL,
                       .frame_index = k,
                       .jitter_index = k % 8};
    tt_jitter_halton23(k % 8, f.jitter);
    render(pattern_square, f.jitter, color);
    CHECK(g_post->process(p, &f, out) == TT_OK);
    /* Ghosting: pixels more than 2 px from the square now, where it was earlier. */
    for (int y = 0; y < H; y++)
      for (int x = 0; x < W; x++) {
        float px = x + 0.5f, py = y + 0.5f;
        int near = px > g_cx - 2 && px < g_cx + 14 && py > g_cy - 2 && py < g_cy + 14;
        if (near || x < 2 || y < 2) continue;
        double d = tm(out[3 * (y * W + x)]) - tm(0.05f);
        if (d > worst_ghost) worst_ghost = d;
      }
    if (k == 23) {
      /* Reference: 8x8 stratified box average per pixel. */
      for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
          double s = 0;
          for (int sy = 0; sy < 8; sy++)
            for (int sx = 0; sx < 8; sx++)
              s += tm(pattern_square(x + (sx + 0.5f) / 8, y + (sy + 0.5f) / 8));
          s /= 64;
          for (int c = 0; c < 3; c++) ref[3 * (y * W + x) + c] = (float)(s / (1 - s));
        }
      last_err = rmse_tm(out, ref, 1);
      raw_err = rmse_tm(color, ref, 1);
    }
  }
  g_post->destroy(p);
  *ghost_out = worst_ghost;
  *raw_out = raw_err;
  return last_err;
}

static void test_moving_no_ghost(void) {
  double ghost, raw, ghost0, raw0;
  double err = run_moving(1, &ghost, &raw);
  double err0 = run_moving(0, &ghost0, &raw0);
  printf("moving: with motion: worst ghost %.4f (tonemapped), rmse %.4f (raw input %.4f); "
         "motion ignored: ghost %.4f, rmse %.4f\n",
         ghost, err, raw, ghost0, err0);
  CHECK(ghost < 0.05);
  CHECK(err < raw * 1.5);
  CHECK(err < err0);
}

/* reset_history and reset() drop the history: the next output is the new frame. */
static void test_reset(void) {
  static float a[W * H * 3], b[W * H * 3], out[W * H * 3];
  float zero[2] = {0, 0};
  render(pattern_lines, zero, a);
  g_cx = 20;
  g_cy = 20;
  render(pattern_square, zero, b);
  for (int pass = 0; pass < 2; pass++) {
    tt_post *p = make(NULL, NULL);
    tt_post_frame f = {.struct_size = sizeof f, .width = W, .height = H, .color = a};
    for (int k = 0; k < 5; k++) CHECK(g_post->process(p, &f, out) == TT_OK);
    f.color = b;
    if (pass == 0) f.reset_history = 1;
    else g_post->reset(p);
    CHECK(g_post->process(p, &f, out) == TT_OK);
    double worst = 0;
    for (int i = 0; i < W * H * 3; i++) worst = fmax(worst, fabs(out[i] - b[i]) / (1 + b[i]));
    CHECK_MSG(worst < 1e-4, "pass %d: output differs from the new frame by %g", pass, worst);
    /* Without a reset the old history leaks into the blend. */
    f.color = a;
    f.reset_history = 0;
    CHECK(g_post->process(p, &f, out) == TT_OK);
    worst = 0;
    for (int i = 0; i < W * H * 3; i++) worst = fmax(worst, fabs(out[i] - a[i]));
    CHECK(worst > 1e-3);
    g_post->destroy(p);
  }
}

/* Energy: a static flat image under Monte Carlo-like noise (each pixel an independent
 * exponential sample of mean 1.5 every frame, a path tracer's heavy tail) whose true value
 * is known. The tonemapped resolve (the thesis' baseline) averages c / (1 + c), whose
 * inverse lies below the mean (Jensen): it comes out much darker whatever gamma.
 * resolve=linear removes that; what remains is the variance clip's bias (on skewed noise a
 * low neighbourhood mean comes with a narrow box, so clipping pulls the history down more
 * often than up), which falls as gamma widens the box: mean kept within 2% at gamma 4.
 * 64 frames of 64 x 48 pixels, frames 32.. averaged. */
static double energy_ratio(const char *resolve, const char *gamma) {
  static float color[W * H * 3], out[W * H * 3];
  tt_config *c = tt_config_create(g_space);
  CHECK(tt_config_set_string(c, "resolve", resolve) == TT_OK);
  CHECK(tt_config_set_string(c, "gamma", gamma) == TT_OK);
  tt_post *p = NULL;
  CHECK_MSG(g_post->create(W, H, c, &p) == TT_OK, "%s", tt_last_error());
  tt_config_destroy(c);
  if (!p) return 0;
  uint32_t rng = 2024;
  double sum = 0;
  int n = 0;
  for (uint32_t k = 0; k < 64; k++) {
    for (int i = 0; i < W * H; i++) {
      rng = rng * 1664525u + 1013904223u;
      float u = ((rng >> 8) + 0.5f) / 16777216.0f;
      float v = -1.5f * logf(u);
      for (int ch = 0; ch < 3; ch++) color[3 * i + ch] = v;
    }
    tt_post_frame f = {.struct_size = sizeof f,
                       .width = W,
                       .height = H,
                       .color = color,
                       .frame_index = k,
                       .jitter_index = k % 8};
    CHECK(g_post->process(p, &f, out) == TT_OK);
    if (k < 32) continue; /* converged history */
    for (int i = 0; i < W * H * 3; i++) sum += out[i];
    n += W * H * 3;
  }
  g_post->destroy(p);
  return sum / n / 1.5;
}

static void test_energy(void) {
  double t1 = energy_ratio("tonemapped", "1"), t4 = energy_ratio("tonemapped", "4");
  double l1 = energy_ratio("linear", "1"), l4 = energy_ratio("linear", "4");
  printf("energy: output mean / true mean: tonemapped resolve %.3f (gamma 1) %.3f (gamma 4), "
         "linear resolve %.3f (gamma 1) %.3f (gamma 4)\n",
         t1, t4, l1, l4);
  CHECK(t1 < 0.8 && t4 < 0.8);        /* the documented darkening of the baseline */
  CHECK(l1 > 0.85 && l1 > t1 + 0.15); /* linear: the clip's bias only */
  CHECK(fabs(l4 - 1.0) < 0.02);       /* energy kept */
}

/* Mode none copies; bad sizes and a missing weights file are clear errors. */
static void test_modes_and_errors(void) {
  static float a[W * H * 3], out[W * H * 3];
  float zero[2] = {0, 0};
  render(pattern_lines, zero, a);
  tt_post *p = make("mode", "none");
  tt_post_frame f = {.struct_size = sizeof f, .width = W, .height = H, .color = a};
  CHECK(g_post->process(p, &f, out) == TT_OK);
  CHECK(memcmp(out, a, sizeof a) == 0);
  f.width = W + 1;
  CHECK(g_post->process(p, &f, out) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "created for 64x48");
  g_post->destroy(p);
  setenv("TT_POST_TAA_WEIGHTS", "/nonexistent/taa.ttw", 1);
  tt_config *c = tt_config_create(g_space);
  CHECK(tt_config_set_string(c, "mode", "network") == TT_OK);
  p = NULL;
  CHECK(g_post->create(W, H, c, &p) == TT_ERR_IO);
  CHECK(p == NULL);
  CHECK_CONTAINS(tt_last_error(), "/nonexistent/taa.ttw");
  tt_config_destroy(c);
  unsetenv("TT_POST_TAA_WEIGHTS");
}

/* Mode network through the loaded plugin (the shipped 12- and 6-channel weights, the host's
 * thread pool): finite, non-negative, near the jitter-averaged image, and the same frames
 * after reset() reproduce the same outputs bit for bit. */
static void test_network_plugin(void) {
  static float color[W * H * 3], out[W * H * 3], first[W * H * 3], ref[W * H * 3], tmp[W * H * 3];
  memset(ref, 0, sizeof ref);
  for (uint32_t j = 0; j < 8; j++) {
    float jit[2];
    tt_jitter_halton23(j, jit);
    render(pattern_lines, jit, tmp);
    for (int i = 0; i < W * H * 3; i++) ref[i] += tm(tmp[i]) / 8.0f;
  }
  for (int i = 0; i < W * H * 3; i++) ref[i] = ref[i] / (1.0f - ref[i]);
  /* the space's default network is the 6-channel one (tools/taa/select_val.py's choice) */
  tt_config *d = tt_config_create(g_space);
  CHECK_MSG(tt_config_get_int(d, "channels", -1) == 6, "default channels %lld, want 6",
            (long long)tt_config_get_int(d, "channels", -1));
  tt_config_destroy(d);
  const char *channels[2] = {"12", "6"};
  for (int v = 0; v < 2; v++) {
    tt_config *c = tt_config_create(g_space);
    CHECK(tt_config_set_string(c, "mode", "network") == TT_OK);
    CHECK(tt_config_set_string(c, "channels", channels[v]) == TT_OK);
    tt_post *p = NULL;
    CHECK_MSG(g_post->create(W, H, c, &p) == TT_OK, "%s", tt_last_error());
    tt_config_destroy(c);
    if (!p) continue;
    for (int pass = 0; pass < 2; pass++) {
      int bad = 0;
      for (uint32_t fr = 0; fr < 12; fr++) {
        float jit[2];
        tt_jitter_halton23(fr % 8, jit);
        render(pattern_lines, jit, color);
        tt_post_frame f = {.struct_size = sizeof f,
                           .width = W,
                           .height = H,
                           .color = color,
                           .jitter_index = fr % 8};
        CHECK(g_post->process(p, &f, out) == TT_OK);
        for (int i = 0; i < W * H * 3; i++) bad += !(isfinite(out[i]) && out[i] >= 0.0f);
      }
      CHECK_MSG(bad == 0, "channels %s: %d non-finite or negative outputs", channels[v], bad);
      double e = rmse_tm(out, ref, 2);
      printf("network %s ch (plugin): RMSE to the jitter average %.4f (pass %d)\n", channels[v], e,
             pass);
      CHECK(e < 0.25);
      if (pass == 0) {
        memcpy(first, out, sizeof out);
        g_post->reset(p);
      } else {
        CHECK_MSG(memcmp(first, out, sizeof out) == 0, "channels %s: not reproducible",
                  channels[v]);
      }
    }
    g_post->destroy(p);
  }
}

int main(void) {
  tt_registry *reg = tt_registry_create(tt_default_host());
  tt_loaded_plugin *lp = NULL;
  if (!reg || tt_registry_load(reg, "post_taa", &lp) != TT_OK) {
    fprintf(stderr, "cannot load post_taa: %s\n", tt_last_error());
    return 1;
  }
  g_post = tt_loaded_plugin_iface(lp);
  g_space = g_post->space();
  CHECK(g_space && tt_space_find(g_space, "mode") >= 0 && tt_space_find(g_space, "blend") >= 0);
  test_static_convergence();
  test_moving_no_ghost();
  test_reset();
  test_energy();
  test_modes_and_errors();
  test_network_plugin();
  tt_registry_destroy(reg);
  return tt_test_finish("taa_vctaa");
}
