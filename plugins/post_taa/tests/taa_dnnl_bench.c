/* post_taa: the network's convolutions (body layers + kernel layer, thesis shapes) with
 * oneDNN's f32 convolution primitive (NHWC activations, weights in the layout oneDNN picks,
 * primitives created once per resolution; also with the activation layouts oneDNN prefers,
 * "blocked", conversions not timed), side by side in one process with the plugin's
 * hand-vectorised C (taa_net_fast.c) on the shipped weights. Built only when libdnnl is
 * installed (suite bench). Threads: OMP_NUM_THREADS for both (default 1). Reports medians
 * of 5 runs, process CPU ms and wall ms; the C figures are the network stage (body +
 * kernel layer; the split uses the threads' own timers), without reprojection and mix. */
#include "tt_test.h"

#include "taa_internal.h"

#include "bench_util.h"

#include <oneapi/dnnl/dnnl.h>

#define OK(x)                                                                                      \
  do {                                                                                             \
    dnnl_status_t s_ = (x);                                                                        \
    if (s_ != dnnl_success) {                                                                      \
      fprintf(stderr, "%s: %d\n", #x, (int)s_);                                                    \
      exit(1);                                                                                     \
    }                                                                                              \
  } while (0)

/* Times one conv (NHWC src/dst, or with `blocked` the activation layouts oneDNN prefers,
 * e.g. nChw16c; weights always in oneDNN's layout); returns the median CPU ms. */
static double time_conv(dnnl_engine_t eng, dnnl_stream_t st, int w, int h, int ic, int oc, int k,
                        int blocked, double *wall) {
  dnnl_dims_t sd = {1, ic, h, w}, dd = {1, oc, h, w}, wd = {oc, ic, k, k}, bd = {oc};
  dnnl_dims_t strides = {1, 1}, pad = {k / 2, k / 2};
  dnnl_memory_desc_t smd, dmd, wmd_any, bmd, wmd_user;
  dnnl_format_tag_t act = blocked ? dnnl_format_tag_any : dnnl_nhwc;
  OK(dnnl_memory_desc_init_by_tag(&smd, 4, sd, dnnl_f32, act));
  OK(dnnl_memory_desc_init_by_tag(&dmd, 4, dd, dnnl_f32, act));
  OK(dnnl_memory_desc_init_by_tag(&wmd_any, 4, wd, dnnl_f32, dnnl_format_tag_any));
  OK(dnnl_memory_desc_init_by_tag(&wmd_user, 4, wd, dnnl_f32, dnnl_oihw));
  OK(dnnl_memory_desc_init_by_tag(&bmd, 1, bd, dnnl_f32, dnnl_x));
  dnnl_convolution_desc_t cd;
  OK(dnnl_convolution_forward_desc_init(&cd, dnnl_forward_inference, dnnl_convolution_direct, &smd,
                                        &wmd_any, &bmd, &dmd, strides, pad, pad));
  dnnl_primitive_desc_t pd;
  OK(dnnl_primitive_desc_create(&pd, &cd, NULL, eng, NULL));
  const dnnl_memory_desc_t *wq = dnnl_primitive_desc_query_md(pd, dnnl_query_weights_md, 0);
  dnnl_memory_t sm, dm, wm, bm;
  OK(dnnl_memory_create(&sm, dnnl_primitive_desc_query_md(pd, dnnl_query_src_md, 0), eng,
                        DNNL_MEMORY_ALLOCATE));
  OK(dnnl_memory_create(&dm, dnnl_primitive_desc_query_md(pd, dnnl_query_dst_md, 0), eng,
                        DNNL_MEMORY_ALLOCATE));
  OK(dnnl_memory_create(&wm, wq, eng, DNNL_MEMORY_ALLOCATE));
  OK(dnnl_memory_create(&bm, &bmd, eng, DNNL_MEMORY_ALLOCATE));
  (void)wmd_user;
  float *sp;
  OK(dnnl_memory_get_data_handle(sm, (void **)&sp));
  size_t sbytes = dnnl_memory_desc_get_size(dnnl_primitive_desc_query_md(pd, dnnl_query_src_md, 0));
  for (size_t i = 0; i < sbytes / sizeof(float); i++) sp[i] = (float)(i % 17) * 0.1f;
  dnnl_primitive_t prim;
  OK(dnnl_primitive_create(&prim, pd));
  dnnl_exec_arg_t args[4] = {
      {DNNL_ARG_SRC, sm}, {DNNL_ARG_WEIGHTS, wm}, {DNNL_ARG_BIAS, bm}, {DNNL_ARG_DST, dm}};
  double cs[5], ws[5];
  for (int r = 0; r < 6; r++) {
    double c0 = bench_cpu_ms(), w0 = bench_wall_ms();
    OK(dnnl_primitive_execute(prim, st, 4, args));
    OK(dnnl_stream_wait(st));
    double c = bench_cpu_ms() - c0, ww = bench_wall_ms() - w0;
    if (r) cs[r - 1] = c, ws[r - 1] = ww;
  }
  double best = bench_median(cs, 5);
  *wall = bench_median(ws, 5);
  dnnl_primitive_destroy(prim);
  dnnl_primitive_desc_destroy(pd);
  dnnl_memory_destroy(sm), dnnl_memory_destroy(dm), dnnl_memory_destroy(wm),
      dnnl_memory_destroy(bm);
  return best;
}

/* The plugin's C path on the shipped weights: median network-stage CPU ms (body + kernel
 * layer) and wall ms, with the body / kernel split of the threads' timers. */
static void time_c(const char *root, int width, int w, int h, int threads) {
  char path[1024];
  snprintf(path, sizeof path, "%s/plugins/post_taa/post_taa_c%d.ttw", root, width);
  tt__net_model m;
  if (tt__net_load(path, &m) != TT_OK) {
    fprintf(stderr, "%s\n", tt_last_error());
    tt_test_failures++;
    return;
  }
  tt_default_host_set_threads((uint32_t)threads);
  size_t n = (size_t)w * h;
  float *color = malloc(n * 12), *depth = malloc(n * 4), *motion = malloc(n * 8);
  float *out = malloc(n * 12);
  for (size_t i = 0; i < n; i++) {
    color[3 * i] = color[3 * i + 1] = color[3 * i + 2] = (float)(i % 97) / 50.0f;
    depth[i] = 1.0f + (float)(i % 13);
    motion[2 * i] = 0.7f;
    motion[2 * i + 1] = -0.3f;
  }
  tt__net_state s;
  CHECK(tt__net_state_init(&s, &m, (uint32_t)w, (uint32_t)h) == TT_OK);
  double cn[5], wn[5], body[5], kern[5];
  for (int r = 0; r < 6; r++) {
    tt__net_process(&s, &m, tt_default_host(), color, depth, motion, (uint32_t)r, out);
    if (!r) continue;
    double share = s.ms_body + s.ms_kernel > 0 ? s.ms_body / (s.ms_body + s.ms_kernel) : 0;
    cn[r - 1] = s.cpu_network, wn[r - 1] = s.ms_network;
    body[r - 1] = s.cpu_network * share, kern[r - 1] = s.cpu_network * (1 - share);
  }
  printf("C (%s) %dx%d W=%d: CPU ms body %.1f, kernel layer %.1f; total %.1f CPU ms (%.1f "
         "wall), %d thread(s)\n",
         tt__net_fast_isa(), w, h, width, bench_median(body, 5), bench_median(kern, 5),
         bench_median(cn, 5), bench_median(wn, 5), threads);
  tt__net_state_free(&s);
  tt__net_free(&m);
  free(color), free(depth), free(motion), free(out);
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  const char *omp = getenv("OMP_NUM_THREADS");
  int threads = omp ? atoi(omp) : 1;
  if (threads < 1) threads = 1;
  if (!root) root = ".";
  dnnl_engine_t eng;
  dnnl_stream_t st;
  OK(dnnl_engine_create(&eng, dnnl_cpu, 0));
  OK(dnnl_stream_create(&st, eng, dnnl_stream_default_flags));
  int sizes[2][2] = {{640, 480}, {1920, 1080}};
  for (int s = 0; s < 2; s++)
    for (int width = 12; width >= 6; width -= 6) {
      int w = sizes[s][0], h = sizes[s][1];
      for (int blocked = 0; blocked < 2; blocked++) {
        double wl[4], c[4];
        c[0] = time_conv(eng, st, w, h, 14, width, 3, blocked, &wl[0]);
        c[1] = time_conv(eng, st, w, h, width, width, 3, blocked, &wl[1]);
        c[2] = time_conv(eng, st, w, h, width, width, 5, blocked, &wl[2]);
        c[3] = time_conv(eng, st, w, h, width, 50, 5, blocked, &wl[3]);
        printf("oneDNN %s %dx%d W=%d: CPU ms body %.1f (%.1f + %.1f + %.1f), kernel layer "
               "%.1f; total %.1f CPU ms (%.1f wall)\n",
               blocked ? "blocked" : "NHWC", w, h, width, c[0] + c[1] + c[2], c[0], c[1], c[2],
               c[3], c[0] + c[1] + c[2] + c[3], wl[0] + wl[1] + wl[2] + wl[3]);
      }
      time_c(root, width, w, h, threads);
    }
  dnnl_stream_destroy(st);
  dnnl_engine_destroy(eng);
  return tt_test_finish("taa_dnnl_bench");
}
