/* post_taa: the fast path of the kernel-prediction network (the computation of taa_net.c's
 * reference loops, reordered for speed), its driver. Per frame:
 *
 * 1. Input planes, by rows on the host's pool (the kernels' input_rows): tonemap, motion,
 *    depth, the rejection test and the Catmull-Rom reprojection of the previous state into
 *    planes (per row, each channel's columns in turn) with zero rows above/below and zero
 *    columns left/right of the image; then the history reset of models that have it.
 * 2. Network, softmax, colour mix, hidden layer and outputs by row bands
 *    (taa_fast_bands.c).
 *
 * The arithmetic is in the SIMD kernels (taa_kernel_*.c), which meson compiles once per
 * instruction set (generic, AVX2+FMA, AVX-512 F+VL; gcc and clang alike); the weights are
 * repacked for them at load (taa_fast_pack.c). tt__net_fast_kernels below is the only place
 * that chooses a copy: the best the CPU has, per frame; TT_POST_TAA_ISA=avx2|generic forces
 * a lower one. The AVX2 and AVX-512 copies give the same bits; every output is computed by
 * the same operations in the same order whatever the band split or thread count
 * (plugins/post_taa/tests/taa_net.c checks both).
 *
 * On AVX2 / AVX-512 the 5x5 layers run as Winograd F(4x4, 5x5) (the kernel layer, 5x5 body
 * layers after the first) or F(2x2, 5x5); the transforms add rounding of ~1e-7 relative
 * (tests/taa_net.c). TT_POST_TAA_WINOGRAD=0 (read at state init, tt__net_state.winograd)
 * selects the direct convolutions; the portable copy has only those. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "taa_fast.h"

/* Rows a body layer's output must extend beyond a band (what the later layers read). */
static uint32_t tt__net_fast_halo_after(const tt__net_model *m, uint32_t l) {
  uint32_t h = m->kernel.ksize / 2;
  for (uint32_t k = l + 1; k < m->body_count; k++) h += m->body[k].ksize / 2;
  return h;
}

tt_status tt__net_fast_init(tt__net_state *s, const tt__net_model *m) {
  s->halo = tt__net_fast_halo_after(m, 0) + m->body[0].ksize / 2;
  if (s->halo < 2) s->halo = 2;    /* the colour mix reads 2 rows around */
  s->vw = (s->width + 31u) & ~31u; /* F(4x4, 5x5) groups: 8 tiles of 4 columns */
  s->rs = s->vw + 2 * TT__NET_COL_OFF;
  /* Rows of all channels side by side: the first layer reads one contiguous stream per
   * row (the hardware prefetcher follows it) instead of one short stream per channel. */
  s->inp_cs = s->rs;
  s->inp_ys = (size_t)m->in_channels * s->rs;
  s->inp = tt__net_fz_alloc((size_t)(s->height + 2 * s->halo) * s->inp_ys);
  const char *wg = getenv("TT_POST_TAA_WINOGRAD");
  s->winograd = wg && (wg[0] == '0' || wg[0] == '1') ? wg[0] - '0' : 2;
  const char *pf = getenv("TT_POST_TAA_PREFETCH");
  s->prefetch = !(pf && pf[0] == '0');
  if (!s->inp)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY,
                        TT__TAA_NAME ": out of memory for %ux%u "
                                     "network planes",
                        s->width, s->height);
  return TT_OK;
}

void tt__net_fast_free(tt__net_state *s) {
  free(s->inp);
  free(s->scratch);
  s->inp = NULL;
  s->scratch = NULL;
  s->scratch_threads = 0;
  s->scratch_bytes = 0;
}

const tt__net_kernels *tt__net_fast_kernels(void) {
#if TT__NET_X86_KERNELS
  const char *force = getenv("TT_POST_TAA_ISA");
  __builtin_cpu_init();
  int has_v3 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  int has_v4 = has_v3 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  if (force && !strcmp(force, "generic")) return tt__net_kernels_generic();
  if (force && !strcmp(force, "avx2"))
    return has_v3 ? tt__net_kernels_avx2() : tt__net_kernels_generic();
  return has_v4   ? tt__net_kernels_avx512()
         : has_v3 ? tt__net_kernels_avx2()
                  : tt__net_kernels_generic();
#else
  return tt__net_kernels_generic();
#endif
}

const char *tt__net_fast_isa(void) { return tt__net_fast_kernels()->name; }

/* History reset (models with TT__NET_FLAG_RESET): after the reprojection pass wrote the
 * test bits, the opening marks RESET and the reprojected state of those pixels becomes the
 * fresh-start state (tonemapped colour, hidden 0), as the reference path fetches it. */
static void tt__net_fast_reject_reset(tt__net_state *s, const tt__net_model *m) {
  size_t n = (size_t)s->width * s->height, cs = s->inp_cs;
  tt__taa_reject_open(s->width, s->height, s->reject, s->reject + n);
  for (uint32_t y = 0; y < s->height; y++) {
    const uint8_t *r = s->reject + (size_t)y * s->width;
    float *base = s->inp + (size_t)(y + s->halo) * s->inp_ys + TT__NET_COL_OFF;
    for (uint32_t x = 0; x < s->width; x++) {
      if (!(r[x] & TT__TAA_REJECT_RESET)) continue;
      for (uint32_t c = 0; c < 3; c++) base[(6 + c) * cs + x] = base[c * cs + x];
      for (uint32_t c = 0; c < m->hidden; c++) base[(9 + c) * cs + x] = 0.0f;
    }
  }
}

void tt__net_fast_process(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                          const tt__net_frame *f, float *out_rgb) {
  const float *color = f->color, *depth = f->depth;
  const tt__net_kernels *k = tt__net_fast_kernels();
  double w0 = tt__net_now_ns() * 1e-6, c0 = tt__taa_cpu_ms();
  tt__net_input_job ij = {.s = s,
                          .m = m,
                          .color = color,
                          .depth = depth,
                          .motion = f->motion,
                          .reject = (m->flags & TT__NET_FLAG_REJECT) ? s->reject : NULL,
                          .dprev = s->have_prev_depth && f->prev_depth ? s->prev_depth : NULL,
                          .zprev = f->prev_depth,
                          .jx = f->jitter[0],
                          .jy = f->jitter[1],
                          .pjx = s->prev_jitter[0],
                          .pjy = s->prev_jitter[1]};
  float dmax = 0.0f;
  if (depth)
    for (size_t i = 0; i < (size_t)s->width * s->height; i++)
      if (depth[i] > dmax && isfinite(depth[i])) dmax = depth[i];
  ij.depth_scale = dmax > 0.0f ? 1.0f / dmax : 0.0f;
  tt__taa_parallel_rows(host, s->height, k->input_rows, &ij);
  if ((m->flags & TT__NET_FLAG_RESET) && s->valid) tt__net_fast_reject_reset(s, m);
  double w1 = tt__net_now_ns() * 1e-6, c1 = tt__taa_cpu_ms();

  tt__net_band_times bt;
  if (tt__net_fast_bands(s, m, host, k, f->jitter_index % TT__NET_JITTER_SETS, out_rgb, &bt) !=
      TT_OK) {
    /* Out of memory for a few MB of scratch: leave the frame as the input. */
    memcpy(out_rgb, color, (size_t)s->width * s->height * 3 * sizeof(float));
    return;
  }
  double w2 = tt__net_now_ns() * 1e-6, c2 = tt__taa_cpu_ms();

  double tot = bt.body_ns + bt.kernel_ns + bt.mix_ns, fmix = tot > 0 ? bt.mix_ns / tot : 0;
  s->ms_body = bt.body_ns * 1e-6;
  s->ms_kernel = bt.kernel_ns * 1e-6;
  s->ms_reproject = w1 - w0;
  s->ms_network = (w2 - w1) * (1 - fmix);
  s->ms_mix = (w2 - w1) * fmix;
  s->cpu_reproject = c1 - c0;
  s->cpu_network = (c2 - c1) * (1 - fmix);
  s->cpu_mix = (c2 - c1) * fmix;
  float *t = s->state;
  s->state = s->next_state;
  s->next_state = t;
  s->valid = 1;
}
