/* post_taa timings (suite bench; thesis Table 5.2): ms per frame at 640x480 and 1920x1080
 * for 1 and 2 threads, split into reprojection (tonemap + Catmull-Rom of the previous state
 * into the input planes), network (body layers + kernel layer) and colour mix (softmax,
 * eq. 5.3, hidden layer, outputs), for the 12- and 6-channel shipped weights and VCTAA
 * (one fused pass: no split). Every figure is the median of >= 5 frames after a warm-up,
 * both wall time and process CPU time (on a shared machine the CPU time is the figure that
 * survives load; wall = CPU / threads only on an idle machine).
 *
 * FLOPs per pixel come from the layer shapes (2 K^2 I O + O per layer, one weight set;
 * softmax, mix and reprojection not counted). The FLOP peak is measured: a loop of
 * independent 8-wide FMAs (AVX2) gives this core's FLOP/s per CPU-second, i.e. 2 FMA units
 * x 8 floats x 2 flops x the effective clock, which is printed as the clock it implies.
 *
 * Each network row is measured twice, alternating frames in one process: D = all layers by
 * direct convolution, W = the kernel layer and 12-channel 5x5 body layers by Winograd
 * F(2x2, 5x5) (fewer multiplies; its GFLOP/s are "effective": the direct convolution's FLOP
 * count over the time taken).
 *
 * Environment: TT_BENCH_THREADS="1 2" (thread counts), TT_BENCH_QUICK=1 (640x480 only),
 * TT_POST_TAA_ISA=avx2|generic (force a lower instruction set; generic has no Winograd). */
#include "tt_test.h"

#include "taa_internal.h"

#include "bench_util.h"

/* FLOPs per pixel of one layer (2 K^2 I O + O, one weight set). */
static double layer_flops(const tt__net_layer *l) {
  return 2.0 * l->ksize * l->ksize * l->in * l->out + l->out;
}

typedef float v8f __attribute__((vector_size(32)));

/* 12 independent chains of 8-wide FMAs (2 FMA units x 4 cycles latency need >= 8). */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target("avx2,fma"), noinline))
#endif
static void fma_loop(v8f *a, long n) {
  v8f r[12], b, c;
  for (int i = 0; i < 8; i++) b[i] = 1.0000001f, c[i] = 1e-7f;
  for (int i = 0; i < 12; i++) r[i] = a[i];
  for (long k = 0; k < n; k++) {
#pragma GCC unroll 12
    for (int i = 0; i < 12; i++) r[i] = r[i] * b + c;
  }
  for (int i = 0; i < 12; i++) a[i] = r[i];
}

/* This core's AVX2 FMA peak in GFLOP/s per CPU-second (best of 5 runs of ~0.1 s). */
static double measure_peak(void) {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) return 0.0;
  v8f a[12];
  for (int i = 0; i < 12; i++)
    for (int l = 0; l < 8; l++) a[i][l] = (float)(i + l);
  double best = 0.0;
  long n = 5000000;
  for (int r = 0; r < 5; r++) {
    double c0 = bench_cpu_ms();
    fma_loop(a, n);
    double c = bench_cpu_ms() - c0;
    double g = (double)n * 12 * 16 / (c * 1e-3) * 1e-9;
    if (g > best) best = g;
  }
  volatile float sink = a[3][2];
  (void)sink;
  return best;
#else
  return 0.0;
#endif
}

static double g_peak;  /* GFLOP/s per core */
static char g_notes[8192];  /* per-part lines printed after the table */
static char g_summary[4096];  /* direct vs Winograd, side by side */

typedef struct frame_in {
  uint32_t w, h;
  float *color, *depth, *motion, *out;
} frame_in;

/* A moving synthetic frame: edges and gradients, motion of a slow pan. */
static frame_in make_frame(uint32_t w, uint32_t h) {
  frame_in f = {w, h, NULL, NULL, NULL, NULL};
  size_t n = (size_t)w * h;
  f.color = malloc(n * 12), f.depth = malloc(n * 4), f.motion = malloc(n * 8);
  f.out = malloc(n * 12);
  for (size_t i = 0; i < n; i++) {
    uint32_t x = (uint32_t)(i % w), y = (uint32_t)(i / w);
    f.color[3 * i] = (float)(i % 97) / 50.0f;
    f.color[3 * i + 1] = ((x / 7 + y / 5) % 2) ? 1.5f : 0.1f;
    f.color[3 * i + 2] = (float)y / (float)h;
    f.depth[i] = 1.0f + (float)(i % 13);
    f.motion[2 * i] = 0.7f;
    f.motion[2 * i + 1] = -0.3f;
  }
  return f;
}

static void free_frame(frame_in *f) {
  free(f->color), free(f->depth), free(f->motion), free(f->out);
}

/* Two Table 5.2 rows of the network, the 5x5 layers (kernel layer; 12-channel 5x5 body
 * layers) by direct convolution (D) and by Winograd F(2x2, 5x5) (W)
 * (tt__net_state.winograd; TT_POST_TAA_WINOGRAD=0 selects direct in the plugin): two states
 * run alternately frame by frame in this process (the order swapped every frame), so both
 * see the same machine load; medians over `reps` frames each. */
static void bench_net(const char *weights, const char *label, uint32_t w, uint32_t h,
                      uint32_t threads, int reps) {
  tt__net_model m;
  if (tt__net_load(weights, &m) != TT_OK) {
    fprintf(stderr, "%s\n", tt_last_error());
    tt_test_failures++;
    return;
  }
  double flops = layer_flops(&m.kernel) + (m.hidden ? layer_flops(&m.hid) : 0);
  double body_flops = 0;
  for (uint32_t i = 0; i < m.body_count; i++) body_flops += layer_flops(&m.body[i]);
  flops += body_flops;
  frame_in f = make_frame(w, h);
  tt__net_state st[2];
  double wall[2][64], cpu[2][64], wr[2][64], wn[2][64], wm[2][64], cr[2][64], cn[2][64],
      cm[2][64], tb[2][64], tk[2][64];
  for (int md = 0; md < 2; md++) {
    CHECK(tt__net_state_init(&st[md], &m, w, h) == TT_OK);
    st[md].winograd = md;
  }
  for (int r = 0; r <= reps; r++) {
    for (int q = 0; q < 2; q++) {
      int md = (r + q) % 2;
      tt__net_state *s = &st[md];
      double t0 = bench_wall_ms(), c0 = bench_cpu_ms();
      tt__net_process(s, &m, tt_default_host(), f.color, f.depth, f.motion, (uint32_t)r, f.out);
      double t = bench_wall_ms() - t0, c = bench_cpu_ms() - c0;
      if (r == 0) continue;  /* warm-up (first frame has no history) */
      int k = r - 1;
      wall[md][k] = t, cpu[md][k] = c;
      wr[md][k] = s->ms_reproject, wn[md][k] = s->ms_network, wm[md][k] = s->ms_mix;
      cr[md][k] = s->cpu_reproject, cn[md][k] = s->cpu_network, cm[md][k] = s->cpu_mix;
      tb[md][k] = s->ms_body, tk[md][k] = s->ms_kernel;
    }
  }
  double px = (double)w * h, mcpu[2], mwall[2], mker[2];
  for (int md = 0; md < 2; md++) {
    char lab[64];
    snprintf(lab, sizeof lab, "%s %s", label, md ? "W" : "D");
    double mc = bench_median(cpu[md], reps);
    double gf = flops * px / (bench_median(cn[md], reps) * 1e-3) * 1e-9;
    printf("| %-12s | %4ux%-4u | %u | %6.1f | %6.1f | %6.1f | %6.1f | %6.1f | %5.1f / %5.1f / "
           "%5.1f | %5.1f | %3.0f%% |\n", lab, w, h, threads, bench_median(wr[md], reps),
           bench_median(wn[md], reps), bench_median(wm[md], reps), bench_median(wall[md], reps), mc,
           bench_median(cr[md], reps), bench_median(cn[md], reps), bench_median(cm[md], reps), gf,
           g_peak > 0 ? 100.0 * gf / g_peak : 0.0);
    /* Body layers vs kernel layer: the network CPU time split by the threads' own timers. */
    double bb = bench_median(tb[md], reps), kk = bench_median(tk[md], reps);
    double sh = bb + kk > 0 ? bb / (bb + kk) : 0;
    double cb = bench_median(cn[md], reps) * sh, ck = bench_median(cn[md], reps) * (1 - sh);
    snprintf(g_notes + strlen(g_notes), sizeof g_notes - strlen(g_notes),
             "%s %ux%u T=%u %s: body layers %.1f CPU ms (%.1f GFLOP/s%s), kernel layer %.1f "
             "CPU ms (%.1f GFLOP/s%s); %.0f FLOP/px (direct convolution)\n", label, w, h,
             threads, md ? "W" : "D", cb, body_flops * px / (cb * 1e-3) * 1e-9,
             md && m.body_count > 1 && m.body[m.body_count - 1].wino ? " effective" : "", ck,
             layer_flops(&m.kernel) * px / (ck * 1e-3) * 1e-9, md ? " effective" : "", flops);
    mcpu[md] = mc, mwall[md] = bench_median(wall[md], reps), mker[md] = ck;
  }
  snprintf(g_summary + strlen(g_summary), sizeof g_summary - strlen(g_summary),
           "| %-10s | %4ux%-4u | %u | %7.1f | %7.1f | %5.2fx | %7.1f | %7.1f | %6.1f | %6.1f |\n",
           label, w, h, threads, mcpu[0], mcpu[1], mcpu[0] / mcpu[1], mwall[0], mwall[1],
           mker[0], mker[1]);
  for (int md = 0; md < 2; md++) tt__net_state_free(&st[md]);
  tt__net_free(&m);
  free_frame(&f);
}

/* VCTAA: one fused pass (history fetch + variance clip + blend). */
static void bench_vctaa(uint32_t w, uint32_t h, uint32_t threads, int reps) {
  frame_in f = make_frame(w, h);
  tt__vctaa v;
  CHECK(tt__vctaa_init(&v, w, h) == TT_OK);
  tt__vctaa_params p = {0.1f, 1.0f, 1};
  double wall[64], cpu[64];
  for (int r = 0; r <= reps; r++) {
    double t0 = bench_wall_ms(), c0 = bench_cpu_ms();
    tt__vctaa_process(&v, tt_default_host(), &p, f.color, f.motion, f.out);
    double t = bench_wall_ms() - t0, c = bench_cpu_ms() - c0;
    if (r) wall[r - 1] = t, cpu[r - 1] = c;
  }
  printf("| %-12s | %4ux%-4u | %u | %6s | %6s | %6s | %6.1f | %6.1f | %21s | %5s | %4s |\n",
         "VCTAA", w, h, threads, "-", "-", "-", bench_median(wall, reps), bench_median(cpu, reps), "-", "-",
         "-");
  tt__vctaa_free(&v);
  free_frame(&f);
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  const char *tl = getenv("TT_BENCH_THREADS");
  int quick = getenv("TT_BENCH_QUICK") != NULL;
  char w12[1024], w6[1024];
  snprintf(w12, sizeof w12, "%s/plugins/post_taa/post_taa_c12.ttw", root ? root : ".");
  snprintf(w6, sizeof w6, "%s/plugins/post_taa/post_taa_c6.ttw", root ? root : ".");
  g_peak = measure_peak();
  printf("FLOP peak (measured, AVX2 FMA loop): %.1f GFLOP/s per core = 2 FMA units x 8 floats "
         "x 2 flops x %.2f GHz effective clock\n", g_peak, g_peak / 32.0);
  printf("network instruction set: %s\n", tt__net_fast_isa());
  printf("medians of >= 5 frames; wall ms split reprojection / network / mix; CPU ms = process "
         "CPU time (all threads); GFLOP/s = network FLOPs per network CPU-second, FLOPs of the "
         "direct convolutions for both D (direct) and W (Winograd F(2x2, 5x5) 5x5 layers: "
         "'effective' GFLOP/s, it does fewer multiplies); D and W frames alternate in one "
         "process\n\n");
  printf("| method       | size      | T | reproj | netw.  |  mix   | total  | CPU    | CPU reproj/netw/mix   | GF/s  | peak |\n");
  printf("|--------------|-----------|---|--------|--------|--------|--------|--------|-----------------------|-------|------|\n");
  unsigned th[4] = {1, 2, 0, 0};
  int nth = 2;
  if (tl) {
    nth = sscanf(tl, "%u %u %u %u", &th[0], &th[1], &th[2], &th[3]);
    if (nth < 1) nth = 1, th[0] = 2;
  }
  for (int sz = 0; sz < (quick ? 1 : 2); sz++) {
    uint32_t w = sz ? 1920 : 640, h = sz ? 1080 : 480;
    int reps = sz ? 5 : 7;
    for (int t = 0; t < nth; t++) {
      tt_default_host_set_threads(th[t]);
      bench_net(w12, "network-12", w, h, th[t], reps);
      bench_net(w6, "network-6", w, h, th[t], reps);
      bench_vctaa(w, h, th[t], reps);
    }
  }
  printf("\n%s", g_notes);
  printf("\ndirect (D) vs Winograd (W) 5x5 layers, same process, alternating frames "
         "(medians; CPU = process CPU ms per frame, wall = ms per frame; kern = kernel layer "
         "CPU ms):\n\n");
  printf("| network    | size      | T | CPU D   | CPU W   | D/W    | wall D  | wall W  | "
         "kern D | kern W |\n");
  printf("|------------|-----------|---|---------|---------|--------|---------|---------|"
         "--------|--------|\n%s", g_summary);
  return tt_test_finish("taa_bench");
}
