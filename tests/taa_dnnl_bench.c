/* post_taa: the network's convolutions (body layers + kernel layer, thesis shapes) with
 * oneDNN's f32 convolution primitive, for comparison with taa_bench's hand-vectorised C.
 * Built only when libdnnl is installed (suite bench). Single-threaded by default
 * (DNNL/OMP thread count from OMP_NUM_THREADS); reports wall and process CPU ms. */
#include "tt_test.h"

#include <oneapi/dnnl/dnnl.h>
#include <time.h>

/* Process CPU time in ms. */
static double cpu_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* Wall time in ms. */
static double wall_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

#define OK(x) do { dnnl_status_t s_ = (x); if (s_ != dnnl_success) { fprintf(stderr, "%s: %d\n", #x, (int)s_); exit(1); } } while (0)

/* Times one conv (NHWC src/dst, any weights layout chosen by oneDNN), returns best CPU ms. */
static double time_conv(dnnl_engine_t eng, dnnl_stream_t st, int w, int h, int ic, int oc,
                        int k, double *wall) {
  dnnl_dims_t sd = {1, ic, h, w}, dd = {1, oc, h, w}, wd = {oc, ic, k, k}, bd = {oc};
  dnnl_dims_t strides = {1, 1}, pad = {k / 2, k / 2};
  dnnl_memory_desc_t smd, dmd, wmd_any, bmd, wmd_user;
  OK(dnnl_memory_desc_init_by_tag(&smd, 4, sd, dnnl_f32, dnnl_nhwc));
  OK(dnnl_memory_desc_init_by_tag(&dmd, 4, dd, dnnl_f32, dnnl_nhwc));
  OK(dnnl_memory_desc_init_by_tag(&wmd_any, 4, wd, dnnl_f32, dnnl_format_tag_any));
  OK(dnnl_memory_desc_init_by_tag(&wmd_user, 4, wd, dnnl_f32, dnnl_oihw));
  OK(dnnl_memory_desc_init_by_tag(&bmd, 1, bd, dnnl_f32, dnnl_x));
  dnnl_convolution_desc_t cd;
  OK(dnnl_convolution_forward_desc_init(&cd, dnnl_forward_inference, dnnl_convolution_direct,
                                        &smd, &wmd_any, &bmd, &dmd, strides, pad, pad));
  dnnl_primitive_desc_t pd;
  OK(dnnl_primitive_desc_create(&pd, &cd, NULL, eng, NULL));
  const dnnl_memory_desc_t *wq = dnnl_primitive_desc_query_md(pd, dnnl_query_weights_md, 0);
  dnnl_memory_t sm, dm, wm, bm;
  OK(dnnl_memory_create(&sm, &smd, eng, DNNL_MEMORY_ALLOCATE));
  OK(dnnl_memory_create(&dm, &dmd, eng, DNNL_MEMORY_ALLOCATE));
  OK(dnnl_memory_create(&wm, wq, eng, DNNL_MEMORY_ALLOCATE));
  OK(dnnl_memory_create(&bm, &bmd, eng, DNNL_MEMORY_ALLOCATE));
  (void)wmd_user;
  float *sp;
  OK(dnnl_memory_get_data_handle(sm, (void **)&sp));
  for (long i = 0; i < (long)w * h * ic; i++) sp[i] = (float)(i % 17) * 0.1f;
  dnnl_primitive_t prim;
  OK(dnnl_primitive_create(&prim, pd));
  dnnl_exec_arg_t args[4] = {{DNNL_ARG_SRC, sm}, {DNNL_ARG_WEIGHTS, wm}, {DNNL_ARG_BIAS, bm},
                             {DNNL_ARG_DST, dm}};
  double best = 1e30, best_wall = 1e30;
  for (int r = 0; r < 6; r++) {
    double c0 = cpu_ms(), w0 = wall_ms();
    OK(dnnl_primitive_execute(prim, st, 4, args));
    OK(dnnl_stream_wait(st));
    double c = cpu_ms() - c0, ww = wall_ms() - w0;
    if (r && c < best) best = c;
    if (r && ww < best_wall) best_wall = ww;
  }
  *wall = best_wall;
  dnnl_primitive_destroy(prim);
  dnnl_primitive_desc_destroy(pd);
  dnnl_memory_destroy(sm), dnnl_memory_destroy(dm), dnnl_memory_destroy(wm), dnnl_memory_destroy(bm);
  return best;
}

int main(void) {
  dnnl_engine_t eng;
  dnnl_stream_t st;
  OK(dnnl_engine_create(&eng, dnnl_cpu, 0));
  OK(dnnl_stream_create(&st, eng, dnnl_stream_default_flags));
  int sizes[2][2] = {{640, 480}, {1920, 1080}};
  for (int s = 0; s < 2; s++)
    for (int width = 12; width >= 6; width -= 6) {
      int w = sizes[s][0], h = sizes[s][1];
      double wl[4], c[4];
      c[0] = time_conv(eng, st, w, h, 14, width, 3, &wl[0]);
      c[1] = time_conv(eng, st, w, h, width, width, 3, &wl[1]);
      c[2] = time_conv(eng, st, w, h, width, width, 5, &wl[2]);
      c[3] = time_conv(eng, st, w, h, width, 50, 5, &wl[3]);
      printf("oneDNN %dx%d W=%d: CPU ms body %.1f + %.1f + %.1f, kernel layer %.1f; total "
             "%.1f CPU ms (%.1f wall)\n", w, h, width, c[0], c[1], c[2], c[3],
             c[0] + c[1] + c[2] + c[3], wl[0] + wl[1] + wl[2] + wl[3]);
    }
  dnnl_stream_destroy(st);
  dnnl_engine_destroy(eng);
  return tt_test_finish("taa_dnnl_bench");
}
