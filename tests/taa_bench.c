/* post_taa timings (suite bench): ms per frame at 640x480 and 1920x1080 for the network's
 * reprojection+input, convolutions and fused kernel layer+colour mix (thesis Table 5.2),
 * the scalar reference path, and VCTAA; FLOPs per pixel from the layer shapes (Table 5.1)
 * and the reached GFLOP/s. Uses the shipped 12- and 6-channel weights. Threads: $TT_THREADS
 * (default 2, the goal's budget). Both wall time and process CPU time are printed: on a
 * shared machine the CPU time (one thread: TT_THREADS=1) is the figure that survives load. */
#include "tt_test.h"

#include "taa_internal.h"

#include <time.h>

/* Wall clock in ms. */
static double now_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* CPU time of the whole process (all threads) in ms. */
static double cpu_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* FLOPs per pixel of one layer (2 K^2 I O + O, one weight set). */
static double layer_flops(const tt__net_layer *l) {
  return 2.0 * l->ksize * l->ksize * l->in * l->out + l->out;
}

/* Times the network at w x h (median-ish: best of `reps` after a warm-up). */
static void bench_net(const char *weights, uint32_t w, uint32_t h, int reps) {
  tt__net_model m;
  if (tt__net_load(weights, &m) != TT_OK) {
    fprintf(stderr, "%s\n", tt_last_error());
    tt_test_failures++;
    return;
  }
  double flops = layer_flops(&m.kernel) + (m.hidden ? layer_flops(&m.hid) : 0);
  for (uint32_t i = 0; i < m.body_count; i++) flops += layer_flops(&m.body[i]);
  size_t n = (size_t)w * h;
  float *color = malloc(n * 12), *depth = malloc(n * 4), *motion = malloc(n * 8), *out = malloc(n * 12);
  for (size_t i = 0; i < n; i++) {
    color[3 * i] = color[3 * i + 1] = color[3 * i + 2] = (float)(i % 97) / 50.0f;
    depth[i] = 1.0f + (float)(i % 13);
    motion[2 * i] = 0.7f;
    motion[2 * i + 1] = -0.3f;
  }
  tt__net_state s;
  CHECK(tt__net_state_init(&s, &m, w, h) == TT_OK);
  double best[4] = {1e30, 1e30, 1e30, 1e30}, best_cpu = 1e30, cpu_parts[3] = {0, 0, 0};
  for (int r = 0; r <= reps; r++) {
    double t0 = now_ms(), c0 = cpu_ms();
    tt__net_process(&s, &m, tt_default_host(), color, depth, motion, (uint32_t)r, out);
    double t = now_ms() - t0, c = cpu_ms() - c0;
    if (r == 0) continue;  /* warm-up */
    if (c < best_cpu) {
      best_cpu = c;
      cpu_parts[0] = s.cpu_reproject;
      cpu_parts[1] = s.cpu_network;
      cpu_parts[2] = s.cpu_mix;
    }
    if (t < best[0]) {
      best[0] = t;
      best[1] = s.ms_reproject;
      best[2] = s.ms_network;
      best[3] = s.ms_mix;
    }
  }
  double gflops = flops * n / (best[2] + best[3]) * 1e-6;
  printf("network %s %ux%u: wall %.1f ms (reprojection+input %.1f, body convs %.1f, "
         "kernel+mix+hidden %.1f), CPU %.1f ms; %.0f FLOP/px, %.1f GFLOP/s (wall) / %.1f "
         "GFLOP/s per CPU-second\n", strrchr(weights, '/') + 1, w, h, best[0], best[1],
         best[2], best[3], best_cpu, flops, gflops, flops * n / best_cpu * 1e-6);
  printf("network %s %ux%u: CPU ms: reprojection+input %.1f, body convs %.1f, "
         "kernel+softmax+mix+hidden %.1f\n", strrchr(weights, '/') + 1, w, h, cpu_parts[0],
         cpu_parts[1], cpu_parts[2]);
  if (w == 640) {
    s.reference = 1;
    s.valid = 0;
    double t0 = now_ms();
    tt__net_process(&s, &m, tt_default_host(), color, depth, motion, 0, out);
    printf("network %s %ux%u: scalar reference path %.1f ms\n", strrchr(weights, '/') + 1, w, h,
           now_ms() - t0);
  }
  tt__net_state_free(&s);
  tt__net_free(&m);
  free(color), free(depth), free(motion), free(out);
}

/* Times VCTAA at w x h. */
static void bench_vctaa(uint32_t w, uint32_t h, int reps) {
  size_t n = (size_t)w * h;
  float *color = malloc(n * 12), *motion = malloc(n * 8), *out = malloc(n * 12);
  for (size_t i = 0; i < n; i++) {
    color[3 * i] = color[3 * i + 1] = color[3 * i + 2] = (float)(i % 97) / 50.0f;
    motion[2 * i] = 0.7f;
    motion[2 * i + 1] = -0.3f;
  }
  tt__vctaa v;
  CHECK(tt__vctaa_init(&v, w, h) == TT_OK);
  tt__vctaa_params p = {0.1f, 1.0f, 1};
  double best = 1e30, best_cpu = 1e30;
  for (int r = 0; r <= reps; r++) {
    double t0 = now_ms(), c0 = cpu_ms();
    tt__vctaa_process(&v, tt_default_host(), &p, color, motion, out);
    double t = now_ms() - t0, c = cpu_ms() - c0;
    if (r && t < best) best = t;
    if (r && c < best_cpu) best_cpu = c;
  }
  printf("vctaa %ux%u: wall %.1f ms, CPU %.1f ms\n", w, h, best, best_cpu);
  tt__vctaa_free(&v);
  free(color), free(motion), free(out);
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  const char *th = getenv("TT_THREADS");
  uint32_t threads = th ? (uint32_t)atoi(th) : 2;
  tt_default_host_set_threads(threads);
  printf("threads: %u\n", threads);
  char w12[1024], w6[1024];
  snprintf(w12, sizeof w12, "%s/plugins/post_taa/post_taa_c12.ttw", root ? root : ".");
  snprintf(w6, sizeof w6, "%s/plugins/post_taa/post_taa_c6.ttw", root ? root : ".");
  bench_vctaa(640, 480, 5);
  bench_vctaa(1920, 1080, 3);
  bench_net(w12, 640, 480, 5);
  bench_net(w6, 640, 480, 5);
  bench_net(w12, 1920, 1080, 2);
  bench_net(w6, 1920, 1080, 2);
  return tt_test_finish("taa_bench");
}
