/* post_taa: declarations shared by the fast path's files (README.md, "How the fast path
 * works"): the driver taa_net_fast.c, the weight packing taa_fast_pack.c, the band
 * scheduler taa_fast_bands.c and the SIMD kernels taa_kernel_*.c, which meson compiles once
 * per instruction set. Each copy of the kernels exports one table (tt__net_kernels_<isa>);
 * the driver picks one per frame (tt__net_fast_kernels), nothing else calls an ISA by name. */
#ifndef TT_POST_TAA_FAST_H
#define TT_POST_TAA_FAST_H

#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "taa_internal.h"

#define TT__NET_CHUNK 64u     /* columns of one kernel-layer chunk (multiple of 16) */
#define TT__NET_WINO_POS 36u  /* F(2x2, 5x5): positions of the 6x6 transformed tile */
#define TT__NET_WINO4_POS 64u /* F(4x4, 5x5): positions of the 8x8 transformed tile */

/* 64-byte aligned zeroed floats (freed with free). */
static inline float *tt__net_fz_alloc(size_t count) {
  size_t bytes = (count * sizeof(float) + 63) & ~(size_t)63;
  float *p = aligned_alloc(64, bytes ? bytes : 64);
  if (p) memset(p, 0, bytes ? bytes : 64);
  return p;
}

/* Monotonic wall clock in ns (the stage timings). */
static inline double tt__net_now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1e9 + ts.tv_nsec;
}

/* One convolution over n columns of one output row. rowp[ky] points at channel 0 of the
 * input row y + ky - r, whose column x0 + i is at rowp[ky][TT__NET_COL_OFF + x0 + i] (x0 in the input
 * row's own coordinates, TT__NET_COL_OFF = TT__NET_COL_OFF); channel c adds c * cs. Output channel oc
 * of column i goes to dst[oc * dcs + i]; ReLU when `relu`. */
typedef struct tt__net_conv_args {
  const float *rowp[5];
  size_t cs;
  uint32_t in, ksize, oblk, nob, out;
  const float *w, *b; /* this set's packed weights and biases */
  uint32_t x0, n;
  float *dst;
  size_t dcs;
  int relu;
  size_t pf; /* AVX-512 code: floats from an input row to the row the next output row adds
               * (the first layer, reading the full-frame input planes), prefetched into L2
               * while this row computes; 0: none (ring rows are cache resident) */
} tt__net_conv_args;

/* Winograd F(2x2, 5x5): two output rows p, p + 1 (p even: tiles sit on absolute even rows
 * and columns, whatever the band or column tile) of columns x0 .. x0 + n (n a multiple of
 * 16, x0 even, in the input rows' own coordinates as in tt__net_conv_args). rowp[i]: input
 * row p - 2 + i (i < 6); the zero padding is the input rows' zero rows and columns. Output
 * channel oc of row p + r, column i goes to dst[r][oc * dcs + i] (bias added, ReLU when
 * `relu`). */
typedef struct tt__net_wino_args {
  const float *rowp[6];
  size_t cs;
  uint32_t in, nob, out;
  const float *u, *b; /* this set's transformed weights [block][36][in][O] and biases */
  uint32_t x0, n;
  float *dst[2]; /* output rows p, p + 1: channel oc, column i at dst[r][oc * dcs + i] */
  size_t dcs;
  int relu;
  float *vbuf, *mbuf; /* scratch: 36 * in * 16 and 2 * 36 * O * 16 floats */
} tt__net_wino_args;

/* Winograd F(4x4, 5x5): four output rows p .. p + 3 (p a multiple of 4: tiles sit on
 * absolute rows and columns that are multiples of 4, whatever the band or column tile) of
 * columns x0 .. x0 + n (n a multiple of 32, x0 a multiple of 4, in the input rows' own
 * coordinates as in tt__net_conv_args). rowp[i]: input row p - 2 + i (i < 8). Output
 * channel oc of row p + r, column i goes to dst[r][oc * dcs + i] (bias added, ReLU when
 * `relu`). */
typedef struct tt__net_wino4_args {
  const float *rowp[8];
  size_t cs;
  uint32_t in, nob, out;
  const float *u, *b; /* this set's transformed weights [block][64][in][O] and biases */
  uint32_t x0, n;
  float *dst[4];
  size_t dcs;
  int relu;
  float *vbuf, *mbuf, *ebuf; /* scratch: 64 * in * 16, 64 * O * 16 and 64 * 16 floats */
} tt__net_wino4_args;

/* Softmax of the kernel layer's logits, colour mix (eq. 5.3), hidden layer (1x1) and the
 * outputs (state, linear rgb) of columns x0 .. x0 + n of row y. */
typedef struct tt__net_mix_args {
  const tt__net_state *s;
  const tt__net_model *m;
  float *lg; /* logits [50][TT__NET_CHUNK] of columns x0.. (overwritten) */
  uint32_t x0, n, y;
  const float
      *hrow; /* last body layer, row y: channel c at hrow[c * hcs + TT__NET_COL_OFF + x - hx] */
  size_t hcs;
  int hx;               /* first column of the tile's ring rows */
  const float *hw, *hb; /* hidden layer weights [out][in] and biases of this set */
  float *out_rgb;
} tt__net_mix_args;

/* The input planes of a frame (stage 1): tonemap, motion, depth, the reprojected state and
 * the rejection test of every pixel, by rows (tt__net_kernels.input_rows). */
typedef struct tt__net_input_job {
  tt__net_state *s;
  const tt__net_model *m;
  const float *color, *depth, *motion;
  uint8_t *reject;            /* rejection mask (written here), or NULL (no rejection input) */
  const float *dprev, *zprev; /* previous depth and prevdepth for the tests, or NULL */
  float jx, jy, pjx, pjy;
  float depth_scale;
} tt__net_input_job;

/* One instruction set's kernels. Every kernel computes each output with the same
 * operations in the same order whatever band, tile or chunk it is called for, so results do
 * not depend on the split (tests/taa_net.c). */
typedef struct tt__net_kernels {
  const char *name; /* "avx512", "avx2" or "generic" */
  /* Direct convolution of one row chunk (every layer shape of the format). */
  void (*conv)(const tt__net_conv_args *a);
  /* Softmax, colour mix, hidden layer and outputs of one row chunk. */
  void (*mix)(const tt__net_mix_args *a);
  /* F(2x2, 5x5) of output blocks of 10 or 12; NULL: direct convolutions only. */
  void (*wino)(const tt__net_wino_args *a, uint32_t oblk);
  /* F(4x4, 5x5) of output blocks of 6, 10 or 12; NULL: none. */
  void (*wino4)(const tt__net_wino4_args *a, uint32_t oblk);
  /* Input planes of rows [y0, y1); ctx is a tt__net_input_job. */
  tt__taa_rows_fn input_rows;
} tt__net_kernels;

/* The copies of the kernels (taa_kernel_table.c, one per instruction set; the x86 ones
 * exist only in builds for x86-64 and run only where the CPU has them). */
const tt__net_kernels *tt__net_kernels_generic(void);
const tt__net_kernels *tt__net_kernels_avx2(void);
const tt__net_kernels *tt__net_kernels_avx512(void);

/* The kernels this frame runs (taa_net_fast.c): the best the CPU has, capped by
 * TT_POST_TAA_ISA=avx2|generic. */
const tt__net_kernels *tt__net_fast_kernels(void);

/* Summed thread ns of the band stage's parts (taa_fast_bands.c). */
typedef struct tt__net_band_times {
  double body_ns, kernel_ns, mix_ns;
} tt__net_band_times;

/* Stage 2 (taa_fast_bands.c): the network, softmax, colour mix, hidden layer and outputs of
 * the frame whose input planes are in s->inp, by row bands x column tiles on the host's
 * pool, with weight set `set`; writes out_rgb and s->next_state, and the parts' thread
 * times into *times. TT_ERR_OUT_OF_MEMORY (nothing written) when the per-thread scratch
 * cannot be allocated. */
tt_status tt__net_fast_bands(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                             const tt__net_kernels *k, uint32_t set, float *out_rgb,
                             tt__net_band_times *times);

#endif
