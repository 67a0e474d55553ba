/* post_taa: internal declarations shared by the plugin's files and its white-box tests.
 * Nothing here is exported from post_taa.so (hidden visibility). */
#ifndef TT_POST_TAA_INTERNAL_H
#define TT_POST_TAA_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include <tunetrace/common.h>
#include <tunetrace/host.h>

#define TT__TAA_NAME "post_taa"
#define TT__TAA_VERSION "0.2.0"

/* ---- shared image helpers (taa_image.c) ---- */

/* Row-parallel loop: the host's pool when available, a plain loop otherwise. */
typedef void (*tt__taa_rows_fn)(void *ctx, uint32_t y0, uint32_t y1);
void tt__taa_parallel_rows(const tt_host *host, uint32_t height, tt__taa_rows_fn fn, void *ctx);

/* Reinhard-max tonemap c / (1 + max(c)) and its inverse (the resolve runs in [0, 1)). */
void tt__taa_tonemap(const float in[3], float out[3]);
void tt__taa_untonemap(const float in[3], float out[3]);

/* fmaxf / fminf as inline compares (libm's are calls at -O2: IEEE NaN rules); same results
 * as fmaxf / fminf when at most one argument is NaN. */
static inline float tt__taa_fmax(float a, float b) { return (a > b || b != b) ? a : b; }
static inline float tt__taa_fmin(float a, float b) { return (a < b || b != b) ? a : b; }

/* Inline bodies of tt__taa_tonemap / tt__taa_untonemap for the per-pixel loops. */
static inline void tt__taa_tonemap_inl(const float in[3], float out[3]) {
  float m = tt__taa_fmax(tt__taa_fmax(in[0], in[1]), tt__taa_fmax(in[2], 0.0f));
  float s = 1.0f / (1.0f + m);
  for (int c = 0; c < 3; c++) out[c] = tt__taa_fmax(in[c], 0.0f) * s;
}
static inline void tt__taa_untonemap_inl(const float in[3], float out[3]) {
  /* Keep max below 1 so bright pixels stay finite after the inverse. */
  float m =
      tt__taa_fmin(tt__taa_fmax(tt__taa_fmax(in[0], in[1]), tt__taa_fmax(in[2], 0.0f)), 0.999f);
  float s = 1.0f / (1.0f - m);
  for (int c = 0; c < 3; c++) out[c] = tt__taa_fmax(in[c], 0.0f) * s;
}

/* Process CPU time in ms, all threads (stage timings that survive a loaded machine). */
double tt__taa_cpu_ms(void);

/* Catmull-Rom weights of the 4 taps for fractional offset f of the second tap (Karis 2014);
 * shared by every history fetch so that all paths weight taps identically. */
static inline void tt__taa_cr_weights(float f, float w[4]) {
  w[0] = f * (-0.5f + f * (1.0f - 0.5f * f));
  w[1] = 1.0f + f * f * (-2.5f + 1.5f * f);
  w[2] = f * (0.5f + f * (2.0f - 1.5f * f));
  w[3] = f * f * (-0.5f + 0.5f * f);
}

/* Samples `channels`-channel image `img` (width x height, interleaved) at continuous
 * position (fx, fy) (pixel centres at i + 0.5) with the separable 4x4 Catmull-Rom kernel,
 * clamping taps to the edge. Writes `channels` floats into `out`. */
void tt__taa_sample_catmull_rom(const float *img, uint32_t width, uint32_t height,
                                uint32_t channels, float fx, float fy, float *out);
/* Same with bilinear interpolation. */
void tt__taa_sample_bilinear(const float *img, uint32_t width, uint32_t height, uint32_t channels,
                             float fx, float fy, float *out);

/* ---- variance-clipping TAA (taa_vctaa.c) ---- */

typedef struct tt__vctaa_params {
  float blend;     /* weight of the current frame in the exponential average */
  float gamma;     /* variance box half-size in standard deviations */
  int catmull_rom; /* history fetch: 1 Catmull-Rom, 0 bilinear */
  int linear;      /* resolve in linear colour (energy-preserving) instead of tonemapped */
} tt__vctaa_params;

typedef struct tt__vctaa_filter {
  uint32_t width, height;
  float *history; /* tonemapped RGB of the previous output */
  float *scratch; /* next history */
  float *ycocg;   /* the new frame, tonemapped, in YCoCg */
  int valid;      /* history holds a frame */
  int linear;     /* the history's space (tt__vctaa_params.linear when it was written) */
} tt__vctaa_filter;

tt_status tt__vctaa_init(tt__vctaa_filter *v, uint32_t width, uint32_t height);
void tt__vctaa_free(tt__vctaa_filter *v);
/* Filters one frame. `motion` may be NULL (static camera). */
void tt__vctaa_process(tt__vctaa_filter *v, const tt_host *host, const tt__vctaa_params *p,
                       const float *color, const float *motion, float *out_rgb);

/* ---- history rejection (taa_reject.c) ---- */

/* Relative depth tolerance of the disocclusion test (tools/taa/rejection.py: TOL). */
#define TT__TAA_REJECT_TOL 0.01f
/* Bits of the rejection mask plane. */
#define TT__TAA_REJECT_RAW 1u /* disoccluded or off-screen: the network's rejection input */
#define TT__TAA_REJECT_RESET                                                                       \
  2u                          /* off-screen, or disoccluded in a region holding a 3 x 3
                                  * square: the history is replaced by the new frame */
#define TT__TAA_REJECT_FAR 4u /* disoccluded (before the opening) */
#define TT__TAA_REJECT_OFF 8u /* off-screen */

/* The per-pixel tests of pixel (x, y) (README.md, "History rejection"): RAW | OFF when the
 * history position q = (x, y) + 0.5 + jitter + motion lies outside the previous frame
 * (also for NaN motion), RAW | FAR when the prevdepth z' exceeds the largest previous depth
 * at the 2 x 2 samples around q by more than the tolerance (sky, depth <= 0 or NaN, counts
 * as infinitely far), else 0. `dprev` NULL: only the off-screen test. Shared by every path
 * so that they agree bit for bit. */
static inline __attribute__((always_inline)) uint8_t
tt__taa_reject_test(const float *dprev, uint32_t w, uint32_t h, float pjx, float pjy, float zp,
                    uint32_t x, uint32_t y, float mx, float my, float jx, float jy) {
  float qx = ((float)x + 0.5f + jx) + mx, qy = ((float)y + 0.5f + jy) + my;
  if (!(qx >= 0.0f && qx < (float)w && qy >= 0.0f && qy < (float)h))
    return TT__TAA_REJECT_RAW | TT__TAA_REJECT_OFF;
  if (!dprev) return 0;
  float ux = (qx - 0.5f) - pjx, uy = (qy - 0.5f) - pjy;
  int ix = (int)__builtin_floorf(ux), iy = (int)__builtin_floorf(uy);
  int x0 = ix < 0 ? 0 : ix >= (int)w ? (int)w - 1 : ix;
  int x1 = ix + 1 < 0 ? 0 : ix + 1 >= (int)w ? (int)w - 1 : ix + 1;
  int y0 = iy < 0 ? 0 : iy >= (int)h ? (int)h - 1 : iy;
  int y1 = iy + 1 < 0 ? 0 : iy + 1 >= (int)h ? (int)h - 1 : iy + 1;
  const float *r0 = dprev + (size_t)y0 * w, *r1 = dprev + (size_t)y1 * w;
  float d[4] = {r0[x0], r0[x1], r1[x0], r1[x1]};
  float hi = -__builtin_inff();
  int sky = 0;
  for (int k = 0; k < 4; k++) {
    if (d[k] > 0.0f) hi = d[k] > hi ? d[k] : hi;
    else sky = 1;
  }
  if (!sky && (!(zp > 0.0f) || zp > hi * (1.0f + TT__TAA_REJECT_TOL)))
    return TT__TAA_REJECT_RAW | TT__TAA_REJECT_FAR;
  return 0;
}

/* Per-pixel rejection of the reprojected history: the tests above into `mask` (width x
 * height; `dprev` or `zprev` NULL: only the off-screen test; `motion` NULL: zero motion),
 * then tt__taa_reject_open. `tmp`: width * height bytes of scratch. Rows run on the host's
 * pool; deterministic. */
void tt__taa_reject_masks(const tt_host *host, uint32_t width, uint32_t height, const float *dprev,
                          const float jitter_prev[2], const float *zprev, const float *motion,
                          const float jitter[2], uint8_t *mask, uint8_t *tmp);
/* Adds TT__TAA_REJECT_RESET = OFF, or FAR opened by 3 x 3 (erosion then dilation, edge
 * pixels replicated), to a plane of test bits. `tmp`: width * height bytes. */
void tt__taa_reject_open(uint32_t width, uint32_t height, uint8_t *mask, uint8_t *tmp);

/* ---- the kernel-prediction network (taa_net.c) ---- */

#define TT__NET_MAGIC "TTAANET\0"
#define TT__NET_VERSION 2u     /* newest version read (1: no input flags) */
#define TT__NET_FLAG_REJECT 1u /* input flag: the rejection input channel (last) */
#define TT__NET_FLAG_RESET 2u  /* input flag: history reset (needs FLAG_REJECT) */
#define TT__NET_JITTER_SETS 8u
#define TT__NET_MAX_LAYERS 8u
#define TT__NET_MAX_CH 64u
#define TT__NET_MIX_K 5u /* colour-mix kernel side */
#define TT__NET_MIX_TAPS (TT__NET_MIX_K * TT__NET_MIX_K)
#define TT__NET_BORDER 2u /* zero border of padded planes */

/* One convolution: weights in the file's PyTorch layout [set][out][in][k][k] + bias
 * [set][out] (the reference path and the hidden layer use them as they are), repacked at
 * load for the fast path's convolutions. */
typedef struct tt__net_layer {
  uint32_t in, out, ksize, sets, activation; /* activation: 0 none, 1 ReLU, 2 softmax */
  float *w;                                  /* original layout, sets * out * in * k * k */
  float *b;                                  /* sets * out */
  /* Pixel-vector path (taa_fast_pack.c, taa_kernel_*.c): outputs in blocks of `oblk`, weights
   * [set][block][in][k][k][oblk] (zero for padded outputs), biases [set][nob * oblk]. */
  uint32_t oblk, nob;
  float *wq;
  float *bq;
  /* Winograd F(2x2, 5x5) weights U = G g G^T of a 5x5 softmax (kernel) layer, per set
   * [block][36 positions][in][oblk] (zero for padded outputs); NULL for other layers. They
   * live in the tail of the `wq` allocation (freed with it). */
  float *wino;
  /* Winograd F(4x4, 5x5) weights of the kernel layer (softmax, 5x5, blocks of 10): per set
   * [block][64 positions][in][oblk], also in the tail of `wq`; NULL for other layers. */
  float *wino4;
} tt__net_layer;

/* A loaded model: body layers (ReLU), then the kernel layer (softmax over 2 * 25 taps) and
 * the 1x1 hidden-state layer, both reading the last body layer. */
typedef struct tt__net_model {
  uint32_t in_channels; /* 6 + 3 + hidden (+ 1 with the rejection input) */
  uint32_t flags;       /* TT__NET_FLAG_* (file version 2; 0 for version 1) */
  uint32_t width;       /* body channels (12 or 6) */
  uint32_t hidden;      /* hidden-state channels (0..8) */
  float motion_scale;   /* motion input = pixels * motion_scale */
  uint32_t body_count;  /* body layers (1..TT__NET_MAX_LAYERS - 2) */
  tt__net_layer body[TT__NET_MAX_LAYERS];
  tt__net_layer kernel; /* -> 50 channels */
  tt__net_layer hid;    /* -> hidden channels (absent when hidden == 0) */
} tt__net_model;

/* Loads a weights file; errors name the file and what is wrong (magic, version, shape,
 * truncation, checksum). */
tt_status tt__net_load(const char *path, tt__net_model *m);
/* Parses a weights file from memory (`source` names it in messages). */
tt_status tt__net_parse(const void *data, size_t size, const char *source, tt__net_model *m);
void tt__net_free(tt__net_model *m);

/* Per-sequence state and scratch planes of the network filter. */
typedef struct tt__net_state {
  uint32_t width, height;
  uint32_t state_ch; /* 3 + hidden */
  float *state;      /* previous [rgb_tonemapped, hidden], width x height x state_ch */
  float *next_state;
  float *planes[2];      /* reference path: padded HWC ping-pong planes (allocated on
                             * its first frame), and its tonemapped / reprojected rgb */
  uint32_t plane_stride; /* floats per padded pixel */
  float *tm;             /* padded tonemapped colour, 3 ch */
  float *reproj;         /* padded reprojected rgb of the previous output, 3 ch */
  int valid;
  int reference; /* use the plain scalar loops (tests) */
  /* Fast path (taa_net_fast.c): input planes [height + 2 halo][in_channels][rs],
   * column x at index x + TT__NET_COL_OFF, zero outside the image; per-thread band scratch
   * (ring buffers of the body layers and the kernel layer's logits). */
  float *inp;
  uint32_t rs, halo, vw; /* row stride, zero rows above/below, width rounded to 16 */
  size_t inp_cs;         /* channel stride of inp (= rs: a row's channels side by side) */
  size_t inp_ys;         /* row stride of inp (in_channels * rs) */
  void *scratch;         /* per-thread band scratch, scratch_threads * scratch_bytes */
  uint32_t scratch_threads;
  size_t scratch_bytes;
  uint32_t band_rows;                         /* rows per band (0: automatic) */
  uint32_t tile_cols;                         /* columns per tile, multiple of 64 (0: automatic) */
  double ms_reproject, ms_network, ms_mix;    /* wall ms of the last frame's passes */
  double cpu_reproject, cpu_network, cpu_mix; /* process CPU ms of the same passes */
  double ms_body, ms_kernel; /* fast path: the network's time in body layers and kernel
                               * layer, summed over threads (thread ms, not wall) */
  int winograd;              /* fast path (AVX2 / AVX-512), the 5x5 layers: 0 direct convolution;
                             * 1 Winograd F(2x2, 5x5) (kernel layer, 12-channel body layers);
                             * 2 (default) the kernel layer by F(4x4, 5x5), body layers as 1.
                             * Set at init from TT_POST_TAA_WINOGRAD (0, 1, 2), may be changed
                             * between frames */
  int prefetch;              /* fast path: software prefetch of the first layer's input rows
                             * (TT_POST_TAA_PREFETCH=0 turns it off, for A/B timings) */
  /* History rejection (models with TT__NET_FLAG_REJECT): the previous frame's depth and
   * jitter, and this frame's TT__TAA_REJECT_* mask (+ 2 planes of scratch). */
  float *prev_depth;
  int have_prev_depth;
  float prev_jitter[2];
  uint8_t *reject;  /* 2 * width * height bytes: the mask, then scratch */
  double ms_reject; /* wall ms of the last frame's rejection pass */
} tt__net_state;

/* One frame's inputs (as tt_post_frame; depth, motion and prev_depth may be NULL). */
typedef struct tt__net_frame {
  const float *color, *depth, *motion, *prev_depth;
  uint32_t jitter_index;
  float jitter[2]; /* sub-pixel offset of the frame's samples */
} tt__net_frame;

tt_status tt__net_state_init(tt__net_state *s, const tt__net_model *m, uint32_t width,
                             uint32_t height);
void tt__net_state_free(tt__net_state *s);
#define TT__NET_COL_OFF 8u /* zero columns left of x = 0 in the fast path's planes */

/* Fast path (taa_fast_pack.c): repacks a layer's weights for the pixel-vector convolutions. */
tt_status tt__net_fast_pack(tt__net_layer *l);
/* Allocates the fast path's planes; called by tt__net_state_init. */
tt_status tt__net_fast_init(tt__net_state *s, const tt__net_model *m);
void tt__net_fast_free(tt__net_state *s);
/* One frame on the fast path: input planes (tonemap + reprojection) by rows, then the
 * network, softmax, colour mix and hidden layer fused by row bands on the host's pool. */
void tt__net_fast_process(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                          const tt__net_frame *f, float *out_rgb);
/* The instruction set the fast path dispatches to: "avx512", "avx2" or "generic". */
const char *tt__net_fast_isa(void);

/* Filters one frame. Writes linear RGB, and the tonemapped result is kept in s->state.
 * Models with the rejection input first compute s->reject (taa_reject.c) from the previous
 * frame's depth and jitter kept in `s`. */
void tt__net_process_frame(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                           const tt__net_frame *f, float *out_rgb);
/* The same for a frame given by planes (`depth`, `motion` may be NULL: read as 0), without
 * prevdepth, jittered by tt_jitter_halton23(jitter_index). */
void tt__net_process(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                     const float *color, const float *depth, const float *motion,
                     uint32_t jitter_index, float *out_rgb);
/* Shared by both paths: the per-frame rejection pass (when the model has the input) and,
 * after the frame, keeping its depth and jitter for the next one. */
void tt__net_reject_begin(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                          const tt__net_frame *f);
void tt__net_reject_end(tt__net_state *s, const tt__net_model *m, const tt__net_frame *f);

#endif
