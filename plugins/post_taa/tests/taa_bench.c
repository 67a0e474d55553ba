/* post_taa timings (suite bench; thesis Table 5.2): ms per 640x480 (and 1920x1080) frame
 * of every network and VCTAA, the whole post-process as the plugin runs it: rejection masks
 * (networks with the rejection input), tonemap + Catmull-Rom reprojection into the input
 * planes, network (body + kernel layer), colour mix (softmax, eq. 5.3, hidden layer,
 * outputs). Variants are interleaved: every round runs one frame of each variant, the order
 * rotated per round, so all see the same machine load; each figure is the median over the
 * rounds after a warm-up round. Wall time and process CPU time (all threads); the stage
 * split is CPU ms from the threads' own timers.
 *
 * FLOPs per pixel come from the layer shapes (2 K^2 I O + O per layer, one weight set;
 * softmax, mix, masks and reprojection not counted); with Winograd 5x5 layers the GFLOP/s
 * are "effective" (direct-convolution FLOPs over the time taken). The FLOP peak is measured:
 * a loop of independent 8-wide FMAs gives this core's FLOP/s per CPU-second.
 *
 * Environment: TT_BENCH_WEIGHTS="label=FILE.ttw[@LEVEL],..." (default: every shipped
 * plugins/post_taa/post_taa_*.ttw; @0 direct convolutions, @1 Winograd F(2x2, 5x5), @2
 * the default: F(4x4, 5x5) kernel layer), TT_BENCH_DIRECT=1 (also the direct-convolution
 * rows of every file, label suffix D; the other rows use the plugin's default),
 * TT_BENCH_THREADS="1 2", TT_BENCH_QUICK=1 (640x480 only), TT_BENCH_ROUNDS (9),
 * TT_BENCH_BAND_ROWS / TT_BENCH_TILE_COLS (the fast path's band height and column tile
 * width, tt__net_state.band_rows / tile_cols; 0 or unset: the plugin's automatic choice),
 * TT_POST_TAA_ISA=avx2|generic. Besides the table it prints one line per row,
 *   BENCH label WxH threads wall_ms cpu_ms reject_cpu reproj_cpu network_cpu mix_cpu
 * which tools/taa/speed.py collects over several runs (medians of per-run medians).
 * TT_BENCH_DIGEST=1 adds, per row, "DIGEST label WxH threads HEX": FNV-1a 64 of every
 * frame's output (after the timer stops), so two builds, or two thread counts, can be
 * compared bit for bit on the bench's own frames (the same for the same rounds). */
#include "tt_test.h"

#include "taa_internal.h"

#include "bench_util.h"

#include <dirent.h>

#include <tt_util/hash.h>

#include <tunetrace/camera.h>

#define MAX_VARIANTS 16
#define MAX_ROUNDS 64

/* FLOPs per pixel of one layer (2 K^2 I O + O, one weight set). */
static double layer_flops(const tt__net_layer *l) {
  return 2.0 * l->ksize * l->ksize * l->in * l->out + l->out;
}

typedef float tt__net_v8f __attribute__((vector_size(32)));

/* 12 independent chains of 8-wide FMAs (2 FMA units x 4 cycles latency need >= 8); a
 * measurement of the machine, not a kernel, so gcc and clang both build it for AVX2+FMA. */
#if defined(__x86_64__)
__attribute__((target("avx2,fma"), noinline))
#endif
static void
fma_loop(tt__net_v8f *a, long n) {
  tt__net_v8f r[12], b, c;
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
#if defined(__x86_64__)
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) return 0.0;
  tt__net_v8f a[12];
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

typedef struct frame_in {
  uint32_t w, h;
  float *color, *depth, *motion, *zprev, *out;
} frame_in;

/* A moving synthetic frame: edges and gradients, motion of a slow pan, prevdepth = depth
 * (so the rejection test runs in full on every pixel). */
static frame_in make_frame(uint32_t w, uint32_t h) {
  frame_in f = {w, h, NULL, NULL, NULL, NULL, NULL};
  size_t n = (size_t)w * h;
  f.color = malloc(n * 12), f.depth = malloc(n * 4), f.motion = malloc(n * 8);
  f.zprev = malloc(n * 4), f.out = malloc(n * 12);
  for (size_t i = 0; i < n; i++) {
    uint32_t x = (uint32_t)(i % w), y = (uint32_t)(i / w);
    f.color[3 * i] = (float)(i % 97) / 50.0f;
    f.color[3 * i + 1] = ((x / 7 + y / 5) % 2) ? 1.5f : 0.1f;
    f.color[3 * i + 2] = (float)y / (float)h;
    f.depth[i] = f.zprev[i] = 1.0f + (float)(i % 13);
    f.motion[2 * i] = 0.7f;
    f.motion[2 * i + 1] = -0.3f;
  }
  return f;
}

static void free_frame(frame_in *f) {
  free(f->color), free(f->depth), free(f->motion), free(f->zprev), free(f->out);
}

/* One row of the table: a network (with Winograd or direct 5x5 layers) or VCTAA. */
typedef struct variant {
  char label[64];
  int vctaa;
  int winograd; /* tt__net_state.winograd of this row (-1: the plugin's default) */
  tt__net_model m;
  tt__net_state s;
  tt__vctaa_filter v;
  double wall[MAX_ROUNDS], cpu[MAX_ROUNDS], rej[MAX_ROUNDS], rep[MAX_ROUNDS], net[MAX_ROUNDS],
      mix[MAX_ROUNDS], body[MAX_ROUNDS], kern[MAX_ROUNDS];
  uint64_t digest; /* TT_BENCH_DIGEST: FNV-1a 64 of all frames' outputs */
} variant;

static variant g_var[MAX_VARIANTS];
static int g_nvar;
static double g_peak;
static uint32_t g_band_rows, g_tile_cols; /* TT_BENCH_BAND_ROWS, TT_BENCH_TILE_COLS (0: auto) */
static int g_digest;                      /* TT_BENCH_DIGEST=1 */

/* Adds a network variant (file, 5x5-layer algorithm: -1 default, 0 direct, 1 Winograd
 * F(2x2, 5x5), 2 F(4x4, 5x5) kernel layer); 0 on failure (reported). */
static int add_network(const char *label, const char *path, int winograd) {
  if (g_nvar >= MAX_VARIANTS) return 0;
  variant *v = &g_var[g_nvar];
  memset(v, 0, sizeof *v);
  static const char *const suffix[] = {"", " D", " W2", " W4"};
  snprintf(v->label, sizeof v->label, "%s%s", label, suffix[winograd + 1]);
  if (tt__net_load(path, &v->m) != TT_OK) {
    fprintf(stderr, "%s\n", tt_last_error());
    tt_test_failures++;
    return 0;
  }
  v->winograd = winograd;
  g_nvar++;
  return 1;
}

/* The weights to time: TT_BENCH_WEIGHTS, else every shipped file. */
static void collect_networks(const char *root, int direct) {
  const char *env = getenv("TT_BENCH_WEIGHTS");
  char list[4096] = "";
  if (env && *env) {
    snprintf(list, sizeof list, "%s", env);
  } else {
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/plugins/post_taa", root);
    DIR *d = opendir(dir);
    char names[MAX_VARIANTS][256];
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d)) && n < MAX_VARIANTS;) {
      size_t len = strlen(e->d_name);
      if (len > 4 && !strcmp(e->d_name + len - 4, ".ttw"))
        snprintf(names[n++], 256, "%s", e->d_name);
    }
    if (d) closedir(d);
    qsort(names, (size_t)n, sizeof names[0], (int (*)(const void *, const void *))strcmp);
    for (int i = 0; i < n; i++) {
      char stem[256];
      snprintf(stem, sizeof stem, "%.*s", (int)(strlen(names[i]) - 4), names[i]);
      const char *lab = strncmp(stem, "post_taa_", 9) ? stem : stem + 9;
      snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s=%s/%s", i ? "," : "", lab,
               dir, names[i]);
    }
  }
  for (char *tok = strtok(list, ","); tok; tok = strtok(NULL, ",")) {
    char *eq = strchr(tok, '=');
    if (!eq) {
      fprintf(stderr, "TT_BENCH_WEIGHTS: expected label=file.ttw, got \"%s\"\n", tok);
      tt_test_failures++;
      continue;
    }
    *eq = 0;
    char *at = strchr(eq + 1, '@'); /* label=file.ttw@LEVEL: that algorithm only */
    if (at) {
      *at = 0;
      add_network(tok, eq + 1, atoi(at + 1) < 0 ? 0 : atoi(at + 1) > 2 ? 2 : atoi(at + 1));
      continue;
    }
    add_network(tok, eq + 1, -1);
    if (direct) add_network(tok, eq + 1, 0);
  }
}

/* All variants at w x h with `threads` threads, `rounds` interleaved rounds. */
static void bench_size(uint32_t w, uint32_t h, uint32_t threads, int rounds) {
  tt_default_host_set_threads(threads);
  frame_in f = make_frame(w, h);
  for (int i = 0; i < g_nvar; i++) {
    variant *v = &g_var[i];
    if (v->vctaa) {
      CHECK(tt__vctaa_init(&v->v, w, h) == TT_OK);
    } else {
      CHECK(tt__net_state_init(&v->s, &v->m, w, h) == TT_OK);
      if (v->winograd >= 0) v->s.winograd = v->winograd;
      v->s.band_rows = g_band_rows;
      v->s.tile_cols = g_tile_cols;
    }
    v->digest = TT__FNV1A64_OFFSET;
  }
  const tt__vctaa_params vp = {0.1f, 1.0f, 1, 0};
  for (int r = 0; r <= rounds; r++) {
    for (int q = 0; q < g_nvar; q++) {
      variant *v = &g_var[(q + r) % g_nvar];
      tt__net_frame fr = {.color = f.color,
                          .depth = f.depth,
                          .motion = f.motion,
                          .prev_depth = f.zprev,
                          .jitter_index = (uint32_t)r};
      tt_jitter_halton23((uint32_t)r, fr.jitter);
      double t0 = bench_wall_ms(), c0 = bench_cpu_ms();
      if (v->vctaa) tt__vctaa_process(&v->v, tt_default_host(), &vp, f.color, f.motion, f.out);
      else tt__net_process_frame(&v->s, &v->m, tt_default_host(), &fr, f.out);
      double t = bench_wall_ms() - t0, c = bench_cpu_ms() - c0;
      if (g_digest) v->digest = tt__fnv1a64(v->digest, f.out, (size_t)w * h * 3 * sizeof(float));
      if (r == 0) continue; /* warm-up (the first frame has no history) */
      int k = r - 1;
      v->wall[k] = t, v->cpu[k] = c;
      if (!v->vctaa) {
        /* the rejection pass is timed in wall ms inside; its CPU share ~ wall x threads */
        v->rej[k] = v->s.ms_reject;
        v->rep[k] = v->s.cpu_reproject, v->net[k] = v->s.cpu_network, v->mix[k] = v->s.cpu_mix;
        v->body[k] = v->s.ms_body, v->kern[k] = v->s.ms_kernel;
      }
    }
  }
  double px = (double)w * h;
  for (int i = 0; i < g_nvar; i++) {
    variant *v = &g_var[i];
    double wall = bench_median(v->wall, rounds), cpu = bench_median(v->cpu, rounds);
    if (v->vctaa) {
      printf("| %-16s | %4ux%-4u | %u | %7.1f | %7.1f | %25s | %6s | %23s |\n", v->label, w, h,
             threads, wall, cpu, "-", "-", "-");
      printf("BENCH %s %ux%u %u %.3f %.3f 0 0 0 0\n", v->label, w, h, threads, wall, cpu);
      if (g_digest)
        printf("DIGEST %s %ux%u %u %016llx\n", v->label, w, h, threads,
               (unsigned long long)v->digest);
      tt__vctaa_free(&v->v);
      continue;
    }
    const tt__net_model *m = &v->m;
    double flops = layer_flops(&m->kernel) + (m->hidden ? layer_flops(&m->hid) : 0), bf = 0;
    for (uint32_t l = 0; l < m->body_count; l++) bf += layer_flops(&m->body[l]);
    flops += bf;
    double rj = bench_median(v->rej, rounds), rp = bench_median(v->rep, rounds);
    double nt = bench_median(v->net, rounds), mx = bench_median(v->mix, rounds);
    double bb = bench_median(v->body, rounds), kk = bench_median(v->kern, rounds);
    double sh = bb + kk > 0 ? bb / (bb + kk) : 0;
    double gf = flops * px / (nt * 1e-3) * 1e-9;
    printf("| %-16s | %4ux%-4u | %u | %7.1f | %7.1f | %5.1f / %5.1f / %5.1f / %5.1f | %6.1f | "
           "%5.1f + %5.1f = %5.0f %3.0f%% |\n",
           v->label, w, h, threads, wall, cpu, rj, rp, nt, mx, flops, nt * sh, nt * (1 - sh), gf,
           g_peak > 0 ? 100.0 * gf / g_peak : 0.0);
    printf("BENCH %s %ux%u %u %.3f %.3f %.3f %.3f %.3f %.3f\n", v->label, w, h, threads, wall, cpu,
           rj, rp, nt, mx);
    if (g_digest)
      printf("DIGEST %s %ux%u %u %016llx\n", v->label, w, h, threads,
             (unsigned long long)v->digest);
    tt__net_state_free(&v->s);
  }
  free_frame(&f);
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  if (!root) root = ".";
  const char *tl = getenv("TT_BENCH_THREADS"), *rs = getenv("TT_BENCH_ROUNDS");
  int quick = getenv("TT_BENCH_QUICK") != NULL;
  const char *dr = getenv("TT_BENCH_DIRECT");
  int rounds = rs ? atoi(rs) : 9;
  if (rounds < 1) rounds = 1;
  if (rounds > MAX_ROUNDS) rounds = MAX_ROUNDS;
  collect_networks(root, dr && dr[0] == '1');
  const char *br = getenv("TT_BENCH_BAND_ROWS"), *tc = getenv("TT_BENCH_TILE_COLS");
  g_band_rows = br ? (uint32_t)atoi(br) : 0;
  g_tile_cols = tc ? (uint32_t)atoi(tc) : 0;
  const char *dg = getenv("TT_BENCH_DIGEST");
  g_digest = dg && dg[0] == '1';
  if (g_nvar < MAX_VARIANTS) {
    memset(&g_var[g_nvar], 0, sizeof g_var[0]);
    snprintf(g_var[g_nvar].label, sizeof g_var[0].label, "VCTAA");
    g_var[g_nvar++].vctaa = 1;
  }
  g_peak = measure_peak();
  printf("FLOP peak (measured, AVX2 FMA loop): %.1f GFLOP/s per core = 2 FMA units x 8 floats "
         "x 2 flops x %.2f GHz effective clock\n",
         g_peak, g_peak / 32.0);
  printf("network instruction set: %s; %d variants interleaved, medians of %d rounds after a "
         "warm-up round\n",
         tt__net_fast_isa(), g_nvar, rounds);
  printf("wall / CPU = ms per frame (CPU: process CPU time, all threads); stages: rejection "
         "masks (wall) / reprojection / network / mix (CPU ms); FLOP/px of the direct "
         "convolutions; body + kernel layer CPU ms = effective GFLOP/s and %% of the peak\n\n");
  printf("| variant          | size      | T | wall    | CPU     | rej / reproj / net / mix  | "
         "FLOP/px | body + kernel = GF/s peak |\n");
  printf("|------------------|-----------|---|---------|---------|---------------------------|-----"
         "---|---------------------------|\n");
  unsigned th[4] = {1, 2, 0, 0};
  int nth = 2;
  if (tl) {
    nth = sscanf(tl, "%u %u %u %u", &th[0], &th[1], &th[2], &th[3]);
    if (nth < 1) nth = 1, th[0] = 2;
  }
  for (int sz = 0; sz < (quick ? 1 : 2); sz++) {
    uint32_t w = sz ? 1920 : 640, h = sz ? 1080 : 480;
    for (int t = 0; t < nth; t++) bench_size(w, h, th[t], sz ? (rounds + 1) / 2 : rounds);
  }
  for (int i = 0; i < g_nvar; i++)
    if (!g_var[i].vctaa) tt__net_free(&g_var[i].m);
  return tt_test_finish("taa_bench");
}
