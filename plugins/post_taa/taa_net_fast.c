/* post_taa: the fast path of the kernel-prediction network (the computation of taa_net.c's
 * reference loops, reordered for speed).
 *
 * 1. Input planes, by rows: tonemap, motion, depth and the Catmull-Rom reprojection of the
 *    previous state (one 8-float vector per tap when the state has 8 channels) into planes
 *    (per row, each channel's columns in turn) with zero rows above/below and zero columns
 *    left/right of the image.
 * 2. Network, by row bands on the host's pool: each band streams its rows through all
 *    layers; a body layer keeps only the K rows its consumer reads, in a ring buffer per
 *    thread (cache resident), so nothing but the input planes and the outputs touches the
 *    full frame. A band recomputes the halo rows it shares with its neighbours (about 2
 *    rows of work per band). Per row, the kernel layer's 50 logits of 64-column chunks go
 *    to a small scratch buffer and the softmax, colour mix (eq. 5.3), hidden layer, state
 *    and linear output follow at once on the same chunk.
 *
 * Convolutions vectorise over pixels: 8 or 16 (AVX2: 8-lane vectors) or 16 or 32 (AVX-512:
 * 16-lane vectors, whose FMA peak is twice the 8-lane one on this machine) neighbouring
 * output pixels times a block of 6 to 12 output channels accumulate in registers; each
 * weight is a broadcast operand, each input vector serves the whole block. Every output
 * channel and pixel is computed by the same operations in the same order whatever the band
 * split or thread count, so results do not depend on the number of threads (bit-identical;
 * plugins/post_taa/tests/taa_net.c checks it). The instruction set is chosen at run time (AVX-512VL, AVX2+FMA,
 * or the portable vector-extension code); TT_POST_TAA_ISA=avx2|generic forces a lower one.
 *
 * On AVX2 / AVX-512 the 5x5 layers with output blocks of 10 or 12 (the kernel layer, and
 * 12-channel body layers after the first) run as Winograd F(2x2, 5x5): 2x2 output tiles at
 * absolute even rows and columns, so those layers produce rows in pairs (a band starting or
 * ending on an odd row computes the whole pair and keeps its row; rings hold one row more).
 * 36 instead of 100 multiplies per 2x2 outputs and input channel; the transforms add
 * rounding of ~1e-7 relative (plugins/post_taa/tests/taa_net.c). TT_POST_TAA_WINOGRAD=0 (read at state init,
 * tt__net_state.winograd) selects the direct convolutions; the portable path has only those. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "taa_internal.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#  include <immintrin.h>
#endif

#pragma GCC diagnostic ignored "-Wpsabi"  /* v8f helpers are always inlined */
typedef float v8f __attribute__((vector_size(32)));
typedef float v8fu __attribute__((vector_size(32), aligned(4)));
typedef int32_t v8i __attribute__((vector_size(32)));

#define AI static inline __attribute__((always_inline))
#define COL TT__NET_COL_OFF
#define CHUNK 64u  /* columns of one kernel-layer chunk (multiple of 16) */

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#  define FAST_X86 1
#  define TGT_V4 __attribute__((target("avx2,fma,avx512f,avx512vl")))
#  define TGT_V3 __attribute__((target("avx2,fma")))
#else
#  define FAST_X86 0
#  define TGT_V4
#  define TGT_V3
#endif

/* 64-byte aligned zeroed floats. */
static float *fz_alloc(size_t count) {
  size_t bytes = (count * sizeof(float) + 63) & ~(size_t)63;
  float *p = aligned_alloc(64, bytes ? bytes : 64);
  if (p) memset(p, 0, bytes ? bytes : 64);
  return p;
}

/* ---- weights ---- */

/* Winograd F(2x2, 5x5) (Lavin & Gray 2016) with the interpolation points 0, 1, -1, 2, -2
 * and infinity: a 2x2 output tile of a 5x5 correlation is Y = A^T [U . V] A with the 6x6
 * input tile d, V = B^T d B, and U = G g G^T per weight filter g; summed over input
 * channels, the elementwise products become 36 small matrix products (out x in times
 * in x tiles): 36 multiplies per 2x2 outputs and input channel instead of 100. B^T and A^T
 * hold small integers (exact in float); the fractions sit in G, applied once per weight
 * set in double. */
#define WINO_POS 36u
static const double wino_g[6][5] = {
    {1.0 / 4, 0, 0, 0, 0},
    {1.0 / 6, 1.0 / 6, 1.0 / 6, 1.0 / 6, 1.0 / 6},
    {1.0 / 6, -1.0 / 6, 1.0 / 6, -1.0 / 6, 1.0 / 6},
    {1.0 / 24, 1.0 / 12, 1.0 / 6, 1.0 / 3, 2.0 / 3},
    {1.0 / 24, -1.0 / 12, 1.0 / 6, -1.0 / 3, 2.0 / 3},
    {0, 0, 0, 0, 1}};

/* U = G g G^T of every (set, output, input) filter into l->wino, laid out
 * [set][block][36][in][oblk] (`uper` floats per set). */
static void wino_weights(tt__net_layer *l, size_t uper) {
  const uint32_t O = l->oblk, I = l->in;
  for (uint32_t s = 0; s < l->sets; s++)
    for (uint32_t oc = 0; oc < l->out; oc++)
      for (uint32_t c = 0; c < I; c++) {
        const float *g = l->w + (((size_t)s * l->out + oc) * I + c) * 25;
        double t[6][5], u[6][6];
        for (int i = 0; i < 6; i++)
          for (int k = 0; k < 5; k++) {
            double a = 0;
            for (int j = 0; j < 5; j++) a += wino_g[i][j] * g[j * 5 + k];
            t[i][k] = a;
          }
        for (int i = 0; i < 6; i++)
          for (int j = 0; j < 6; j++) {
            double a = 0;
            for (int k = 0; k < 5; k++) a += t[i][k] * wino_g[j][k];
            u[i][j] = a;
          }
        uint32_t b = oc / O, o = oc % O;
        float *dst = l->wino + s * uper + (size_t)b * WINO_POS * I * O;
        for (int p = 0; p < 36; p++) dst[((size_t)p * I + c) * O + o] = (float)u[p / 6][p % 6];
      }
}

/* Winograd F(4x4, 5x5) with the points 0, 1, -1, 2, -2, 1/2, -1/2 and infinity: a 4x4
 * output tile of a 5x5 correlation is Y = A^T [U . V] A with the 8x8 input tile d,
 * V = B^T d B, U = G g G^T: 64 multiplies per 16 outputs and input channel (4 per output,
 * against 9 for F(2x2, 5x5) and 25 direct). B^T (the same as F(6x6, 3x3)'s) and A^T hold
 * small dyadic fractions, exact in float; G is applied once per weight set in double. */
#define WINO4_POS 64u
static const double wino4_g[8][5] = {
    {-1, 0, 0, 0, 0},
    {-2.0 / 9, -2.0 / 9, -2.0 / 9, -2.0 / 9, -2.0 / 9},
    {-2.0 / 9, 2.0 / 9, -2.0 / 9, 2.0 / 9, -2.0 / 9},
    {1.0 / 90, 1.0 / 45, 2.0 / 45, 4.0 / 45, 8.0 / 45},
    {1.0 / 90, -1.0 / 45, 2.0 / 45, -4.0 / 45, 8.0 / 45},
    {32.0 / 45, 16.0 / 45, 8.0 / 45, 4.0 / 45, 2.0 / 45},
    {32.0 / 45, -16.0 / 45, 8.0 / 45, -4.0 / 45, 2.0 / 45},
    {0, 0, 0, 0, 1}};

/* U = G g G^T of every (set, output, input) filter into l->wino4, laid out
 * [set][block][64][in][oblk] (`uper` floats per set). */
static void wino4_weights(tt__net_layer *l, size_t uper) {
  const uint32_t O = l->oblk, I = l->in;
  for (uint32_t s = 0; s < l->sets; s++)
    for (uint32_t oc = 0; oc < l->out; oc++)
      for (uint32_t c = 0; c < I; c++) {
        const float *g = l->w + (((size_t)s * l->out + oc) * I + c) * 25;
        double t[8][5], u[8][8];
        for (int i = 0; i < 8; i++)
          for (int k = 0; k < 5; k++) {
            double a = 0;
            for (int j = 0; j < 5; j++) a += wino4_g[i][j] * g[j * 5 + k];
            t[i][k] = a;
          }
        for (int i = 0; i < 8; i++)
          for (int j = 0; j < 8; j++) {
            double a = 0;
            for (int k = 0; k < 5; k++) a += t[i][k] * wino4_g[j][k];
            u[i][j] = a;
          }
        uint32_t b = oc / O, o = oc % O;
        float *dst = l->wino4 + s * uper + (size_t)b * WINO4_POS * I * O;
        for (int p = 0; p < 64; p++) dst[((size_t)p * I + c) * O + o] = (float)u[p / 8][p % 8];
      }
}

tt_status tt__net_fast_pack(tt__net_layer *l) {
  uint32_t o = l->out;
  l->oblk = o % 12 == 0 ? 12 : o % 10 == 0 ? 10 : o % 8 == 0 ? 8 : o <= 6 ? 6 : 8;
  l->nob = (o + l->oblk - 1) / l->oblk;
  size_t kk = (size_t)l->ksize * l->ksize, per = (size_t)o * l->in * kk;
  size_t qper = (size_t)l->nob * l->oblk * l->in * kk;
  /* 5x5 layers (the kernel layer, body layers) also get Winograd weights, in the same
   * block; used for output blocks of 10 or 12 (not the first layer, which reads the input
   * planes). */
  int wino = l->ksize == 5 && (l->oblk == 10 || l->oblk == 12);
  size_t uper = wino ? (size_t)l->nob * WINO_POS * l->in * l->oblk : 0;
  /* F(4x4, 5x5) for 5x5 layers with output blocks of 6, 10 or 12 (the kernel layer, body
   * layers after the first) */
  int wino4 = l->ksize == 5 && (l->oblk == 6 || l->oblk == 10 || l->oblk == 12);
  size_t u4per = wino4 ? (size_t)l->nob * WINO4_POS * l->in * l->oblk : 0;
  l->wq = fz_alloc(qper * l->sets + (uper + u4per) * l->sets);
  l->bq = fz_alloc((size_t)l->nob * l->oblk * l->sets);
  l->wino = l->wino4 = NULL;
  if (!l->wq || !l->bq)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__TAA_NAME ": out of memory for weights");
  if (wino) {
    l->wino = l->wq + qper * l->sets;
    wino_weights(l, uper);
  }
  if (wino4) {
    l->wino4 = l->wq + (qper + uper) * l->sets;
    wino4_weights(l, u4per);
  }
  for (uint32_t s = 0; s < l->sets; s++)
    for (uint32_t oc = 0; oc < o; oc++) {
      uint32_t b = oc / l->oblk, j = oc % l->oblk;
      l->bq[(size_t)s * l->nob * l->oblk + oc] = l->b[(size_t)s * o + oc];
      for (uint32_t c = 0; c < l->in; c++)
        for (size_t t = 0; t < kk; t++)
          l->wq[s * qper + (((size_t)b * l->in + c) * kk + t) * l->oblk + j] =
              l->w[s * per + ((size_t)oc * l->in + c) * kk + t];
    }
  return TT_OK;
}

/* ---- state ---- */

/* Rows a body layer's output must extend beyond a band (what the later layers read). */
static uint32_t fast_halo_after(const tt__net_model *m, uint32_t l) {
  uint32_t h = m->kernel.ksize / 2;
  for (uint32_t k = l + 1; k < m->body_count; k++) h += m->body[k].ksize / 2;
  return h;
}

tt_status tt__net_fast_init(tt__net_state *s, const tt__net_model *m) {
  s->halo = fast_halo_after(m, 0) + m->body[0].ksize / 2;
  if (s->halo < 2) s->halo = 2;  /* the colour mix reads 2 rows around */
  s->vw = (s->width + 31u) & ~31u;  /* F(4x4, 5x5) groups: 8 tiles of 4 columns */
  s->rs = s->vw + 2 * COL;
  /* Rows of all channels side by side: the first layer reads one contiguous stream per
   * row (the hardware prefetcher follows it) instead of one short stream per channel. */
  s->inp_cs = s->rs;
  s->inp_ys = (size_t)m->in_channels * s->rs;
  s->inp = fz_alloc((size_t)(s->height + 2 * s->halo) * s->inp_ys);
  const char *wg = getenv("TT_POST_TAA_WINOGRAD");
  s->winograd = wg && (wg[0] == '0' || wg[0] == '1') ? wg[0] - '0' : 2;
  const char *pf = getenv("TT_POST_TAA_PREFETCH");
  s->prefetch = !(pf && pf[0] == '0');
  if (!s->inp)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__TAA_NAME ": out of memory for %ux%u "
                        "network planes", s->width, s->height);
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

/* ---- SIMD building blocks ---- */

AI v8f vsplat(float f) { return (v8f){f, f, f, f, f, f, f, f}; }

AI v8f vsel(v8i mask, v8f a, v8f b) {
  v8i ai, bi;
  memcpy(&ai, &a, sizeof ai);
  memcpy(&bi, &b, sizeof bi);
  ai = (ai & mask) | (bi & ~mask);
  memcpy(&a, &ai, sizeof a);
  return a;
}

AI v8f vmax(v8f a, v8f b) { return vsel(a > b, a, b); }
AI v8f vmin(v8f a, v8f b) { return vsel(a < b, a, b); }
AI v8f vload(const float *p) { return *(const v8fu *)p; }
AI void vstore(float *p, v8f v) { *(v8fu *)p = v; }

/* exp(x) for x <= 0: 2^n * p(r), degree-6 polynomial (rel. error ~2e-7). */
AI v8f vexp_neg(v8f x) {
  x = vmax(x, vsplat(-87.0f));
  v8f t = x * 1.44269504088896341f;
  v8f n = (t + 12582912.0f) - 12582912.0f;
  v8f r = x - n * 0.693145751953125f - n * 1.428606765330187045e-06f;
  v8f p = r * (1.0f / 720.0f) + 1.0f / 120.0f;
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  v8i e = (__builtin_convertvector(n, v8i) + 127) << 23;
  v8f scale;
  memcpy(&scale, &e, sizeof scale);
  return p * scale;
}

/* ---- convolution rows ---- */

/* One convolution over n columns of one output row. rowp[ky] points at channel 0 of the
 * input row y + ky - r, whose column x0 + i is at rowp[ky][COL + x0 + i] (x0 in the input
 * row's own coordinates); channel c adds c * cs. Output channel oc of column i goes to
 * dst[oc * dcs + i]; ReLU when `relu`. */
typedef struct conv_a {
  const float *rowp[5];
  size_t cs;
  uint32_t in, ksize, oblk, nob, out;
  const float *w, *b;  /* this set's packed weights and biases */
  uint32_t x0, n;
  float *dst;
  size_t dcs;
  int relu;
  size_t pf;  /* AVX-512 code: floats from an input row to the row the next output row adds
               * (the first layer, reading the full-frame input planes), prefetched into L2
               * while this row computes; 0: none (ring rows are cache resident) */
} conv_a;

AI void conv_rows_t(const conv_a *a, const int K, const int O, const int P) {
  const uint32_t I = a->in, r = (uint32_t)K / 2;
  for (uint32_t ob = 0; ob < a->nob; ob++) {
    const float *wb = a->w + (size_t)ob * I * K * K * O;
    const float *bb = a->b + (size_t)ob * O;
    for (uint32_t xl = 0; xl < a->n; xl += 8u * P) {
      v8f acc[12][2];
#pragma GCC unroll 12
      for (int o = 0; o < O; o++)
#pragma GCC unroll 2
        for (int j = 0; j < P; j++) acc[o][j] = vsplat(bb[o]);
      const float *wp = wb;
      size_t col = COL + a->x0 + xl - r;
      for (uint32_t c = 0; c < I; c++) {
#pragma GCC unroll 5
        for (int ky = 0; ky < K; ky++) {
          const float *p = a->rowp[ky] + c * a->cs + col;
#pragma GCC unroll 5
          for (int kx = 0; kx < K; kx++) {
            v8f in[2];
#pragma GCC unroll 2
            for (int j = 0; j < P; j++) in[j] = vload(p + kx + 8 * j);
#pragma GCC unroll 12
            for (int o = 0; o < O; o++) {
              float wv = wp[o];
#pragma GCC unroll 2
              for (int j = 0; j < P; j++) acc[o][j] += in[j] * wv;
            }
            wp += O;
          }
        }
      }
#pragma GCC unroll 12
      for (int o = 0; o < O; o++) {
        uint32_t oc = ob * O + (uint32_t)o;
        if (oc >= a->out) break;
        float *d = a->dst + oc * a->dcs + xl;
#pragma GCC unroll 2
        for (int j = 0; j < P; j++) {
          v8f v = acc[o][j];
          if (a->relu) v = vsel(v > vsplat(0.0f), v, vsplat(0.0f));
          vstore(d + 8 * j, v);
        }
      }
    }
  }
}

/* Dispatch on (output block, kernel size) to constant-folded loops; `wide`: 32 vector
 * registers (AVX-512VL), so 16 pixels per block. */
#define CONV_CASE(O_, K_) \
  case (O_) * 8 + (K_): conv_rows_t(a, K_, O_, wide ? 2 : ((O_) <= 6 ? 2 : 1)); break;
AI void conv_rows_dispatch(const conv_a *a, const int wide) {
  switch (a->oblk * 8 + a->ksize) {
    CONV_CASE(6, 1) CONV_CASE(6, 3) CONV_CASE(6, 5)
    CONV_CASE(8, 1) CONV_CASE(8, 3) CONV_CASE(8, 5)
    CONV_CASE(10, 1) CONV_CASE(10, 3) CONV_CASE(10, 5)
    CONV_CASE(12, 1) CONV_CASE(12, 3) CONV_CASE(12, 5)
    default: break;
  }
}

#if FAST_X86
/* conv_rows_t on 16-lane vectors (AVX-512): 16 or 32 output pixels per block, the same
 * multiply-adds per pixel in the same order as the 8-lane code (bit-identical results). */
typedef float v16f __attribute__((vector_size(64)));
typedef float v16fu __attribute__((vector_size(64), aligned(4)));
/* One block of 16 P output pixels from column xl, output block ob. */
TGT_V4 AI void conv16_block(const conv_a *a, uint32_t ob, uint32_t xl, const int K,
                            const int O, const int P) {
  const uint32_t I = a->in, r = (uint32_t)K / 2;
  const float *wp = a->w + (size_t)ob * I * K * K * O;
  const float *bb = a->b + (size_t)ob * O;
  v16f acc[12][2];
#pragma GCC unroll 12
  for (int o = 0; o < O; o++)
#pragma GCC unroll 2
    for (int j = 0; j < P; j++) acc[o][j] = (v16f)_mm512_set1_ps(bb[o]);
  size_t col = COL + a->x0 + xl - r;
  for (uint32_t c = 0; c < I; c++) {
    if (a->pf) {
      const float *q = a->rowp[K - 1] + c * a->cs + col + a->pf;
#pragma GCC unroll 3
      for (int k = 0; k < P + 1; k++) _mm_prefetch((const char *)(q + 16 * k), _MM_HINT_T1);
    }
#pragma GCC unroll 5
    for (int ky = 0; ky < K; ky++) {
      const float *q = a->rowp[ky] + c * a->cs + col;
#pragma GCC unroll 5
      for (int kx = 0; kx < K; kx++) {
        v16f in[2];
#pragma GCC unroll 2
        for (int j = 0; j < P; j++) in[j] = *(const v16fu *)(q + kx + 16 * j);
#pragma GCC unroll 12
        for (int o = 0; o < O; o++) {
          float wv = wp[o];
#pragma GCC unroll 2
          for (int j = 0; j < P; j++) acc[o][j] += in[j] * wv;
        }
        wp += O;
      }
    }
  }
#pragma GCC unroll 12
  for (int o = 0; o < O; o++) {
    uint32_t oc = ob * O + (uint32_t)o;
    if (oc >= a->out) break;
    float *d = a->dst + oc * a->dcs + xl;
#pragma GCC unroll 2
    for (int j = 0; j < P; j++) {
      v16f v = acc[o][j];
      if (a->relu) v = (v16f)_mm512_max_ps((__m512)v, _mm512_setzero_ps());  /* NaN -> 0 */
      *(v16fu *)(d + 16 * j) = v;
    }
  }
}

/* 32 pixels per block while more than 16 remain, then 16 (n rounded up to 16, as the
 * 8-lane code's blocks of 16 round it). */
TGT_V4 AI void conv_rows16_t(const conv_a *a, const int K, const int O) {
  for (uint32_t ob = 0; ob < a->nob; ob++)
    for (uint32_t xl = 0; xl < a->n;) {
      if (a->n - xl > 16) conv16_block(a, ob, xl, K, O, 2), xl += 32;
      else conv16_block(a, ob, xl, K, O, 1), xl += 16;
    }
}

#define CONV16_CASE(O_, K_) case (O_) * 8 + (K_): conv_rows16_t(a, K_, O_); break;
TGT_V4 AI void conv_rows16_dispatch(const conv_a *a) {
  switch (a->oblk * 8 + a->ksize) {
    CONV16_CASE(6, 1) CONV16_CASE(6, 3) CONV16_CASE(6, 5)
    CONV16_CASE(8, 1) CONV16_CASE(8, 3) CONV16_CASE(8, 5)
    CONV16_CASE(10, 1) CONV16_CASE(10, 3) CONV16_CASE(10, 5)
    CONV16_CASE(12, 1) CONV16_CASE(12, 3) CONV16_CASE(12, 5)
    default: break;
  }
}
#endif

/* ---- Winograd F(2x2, 5x5) for the kernel layer and 5x5 body layers ---- */

/* Two output rows p, p + 1 (p even: tiles sit on absolute even rows and columns, whatever
 * the band or column tile) of columns x0 .. x0 + n (n a multiple of 16, x0 even, in the
 * input rows' own coordinates as in conv_a). rowp[i]: input row p - 2 + i (i < 6); the
 * zero padding is the input rows' zero rows and columns. Output channel oc of row p + r,
 * column i goes to dst[r][oc * dcs + i] (bias added, ReLU when `relu`). Tiles are
 * vectorised: 8 tiles (16 columns) per vector, P vectors per group; per group the input
 * transform fills V[36][in][8P], then per block of O outputs the 36 products
 * M[pos][O][8P] = U[pos][O][in] x V[pos][in][8P] and the output transform. Every tile's
 * arithmetic is the same whatever lane or group it is in, so results do not depend on the
 * band or tile split. */
typedef struct wino_a {
  const float *rowp[6];
  size_t cs;
  uint32_t in, nob, out;
  const float *u, *b;   /* this set's transformed weights [block][36][in][O] and biases */
  uint32_t x0, n;
  float *dst[2];        /* output rows p, p + 1: channel oc, column i at dst[r][oc * dcs + i] */
  size_t dcs;
  int relu;
  float *vbuf, *mbuf;   /* scratch: 36 * in * 16 and 2 * 36 * O * 16 floats */
} wino_a;

/* A constant shuffle of the 16 lanes a:b into 8: GCC spells it __builtin_shuffle, clang
 * (the sanitizer and fuzzing builds) __builtin_shufflevector; same code either way. */
#if defined(__clang__)
#  define WINO_SHUF8(a, b, ...) __builtin_shufflevector(a, b, __VA_ARGS__)
#else
#  define WINO_SHUF8(a, b, ...) __builtin_shuffle(a, b, (v8i){__VA_ARGS__})
#endif

/* Even lanes of the 16 floats a:b (stride-2 gather of 8 tiles' column). */
AI v8f wino_even(v8f a, v8f b) { return WINO_SHUF8(a, b, 0, 2, 4, 6, 8, 10, 12, 14); }

/* B^T of one 6-vector (rows of B^T: 4 0 -5 0 1 0 / 0 4 4 -1 -1 0 / 0 -4 4 1 -1 0 /
 * 0 -2 -1 2 1 0 / 0 2 -1 -2 1 0 / 0 4 0 -5 0 1). */
AI void wino_bt(const v8f d[6], v8f v[6]) {
  v8f s12 = d[1] + d[2], s34 = d[3] + d[4], a21 = d[2] - d[1], a34 = d[3] - d[4];
  v8f a31 = d[3] - d[1], a42 = d[4] - d[2];
  v[0] = d[0] * 4.0f - d[2] * 5.0f + d[4];
  v[1] = s12 * 4.0f - s34;
  v[2] = a21 * 4.0f + a34;
  v[3] = a31 * 2.0f + a42;
  v[4] = a42 - a31 * 2.0f;
  v[5] = d[1] * 4.0f - d[3] * 5.0f + d[5];
}

/* A^T of one 6-vector: m0 + m1 + m2 + m3 + m4, m1 - m2 + 2 (m3 - m4) + m5. */
AI void wino_at(const v8f m[6], v8f *y0, v8f *y1) {
  *y0 = (m[0] + m[1]) + (m[2] + m[3]) + m[4];
  *y1 = (m[1] - m[2]) + (m[3] - m[4]) * 2.0f + m[5];
}

/* One group of 8P tiles (16P columns from xl). */
AI void wino_group_t(const wino_a *a, uint32_t xl, const int O, const int P) {
  const uint32_t I = a->in;
  const int T = 8 * P;
  float *V = a->vbuf, *M = a->mbuf;
  for (uint32_t c = 0; c < I; c++) {
#pragma GCC unroll 2
    for (int j = 0; j < P; j++) {
      v8f e[6][6];
#pragma GCC unroll 6
      for (int i = 0; i < 6; i++) {
        const float *q = a->rowp[i] + c * a->cs + COL + a->x0 + xl + 16 * j - 2;
        v8f d[6];
#pragma GCC unroll 3
        for (int k = 0; k < 6; k += 2) {
          v8f lo = vload(q + k), hi = vload(q + k + 8), lo1 = vload(q + k + 1),
              hi1 = vload(q + k + 9);
          d[k] = wino_even(lo, hi);
          d[k + 1] = wino_even(lo1, hi1);
        }
        wino_bt(d, e[i]);  /* along the row: e[i][s] */
      }
#pragma GCC unroll 6
      for (int s2 = 0; s2 < 6; s2++) {
        v8f col[6], v[6];
#pragma GCC unroll 6
        for (int i = 0; i < 6; i++) col[i] = e[i][s2];
        wino_bt(col, v);  /* along the column: V[r][s2] */
#pragma GCC unroll 6
        for (int r = 0; r < 6; r++) vstore(V + ((size_t)(r * 6 + s2) * I + c) * T + 8 * j, v[r]);
      }
    }
  }
  /* Block ob's 36 products go to one half of M while the output transforms of block
   * ob - 1 (one output channel and vector after each product) read the other: their adds
   * and loads overlap the products' multiply-adds. */
  for (uint32_t ob = 0; ob <= a->nob; ob++) {
    float *Mc = M + (size_t)(ob & 1) * WINO_POS * O * T;
    float *Mp = M + (size_t)(~ob & 1) * WINO_POS * O * T;
    const float *u = a->u + (size_t)(ob < a->nob ? ob : 0) * WINO_POS * I * O;
    for (uint32_t pos = 0; pos < WINO_POS; pos++) {
      if (ob < a->nob) {
        v8f acc[12][2];
#pragma GCC unroll 12
        for (int o = 0; o < O; o++)
#pragma GCC unroll 2
          for (int j = 0; j < P; j++) acc[o][j] = vsplat(0.0f);
        const float *vp = V + (size_t)pos * I * T;
        for (uint32_t c = 0; c < I; c++) {
          v8f in[2];
#pragma GCC unroll 2
          for (int j = 0; j < P; j++) in[j] = vload(vp + 8 * j);
#pragma GCC unroll 12
          for (int o = 0; o < O; o++) {
            float wv = u[o];
#pragma GCC unroll 2
            for (int j = 0; j < P; j++) acc[o][j] += in[j] * wv;
          }
          u += O;
          vp += T;
        }
#pragma GCC unroll 12
        for (int o = 0; o < O; o++)
#pragma GCC unroll 2
          for (int j = 0; j < P; j++) vstore(Mc + ((size_t)pos * O + o) * T + 8 * j, acc[o][j]);
      }
      if (ob == 0 || pos >= (uint32_t)(O * P)) continue;
      int o = (int)pos / P, j = (int)pos % P;
      uint32_t oc = (ob - 1) * O + (uint32_t)o;
      if (oc >= a->out) continue;
      v8f bias = vsplat(a->b[oc]);
      v8f r0[6], r1[6];
#pragma GCC unroll 6
      for (int i = 0; i < 6; i++) {
        v8f m[6];
#pragma GCC unroll 6
        for (int k = 0; k < 6; k++) m[k] = vload(Mp + ((size_t)(i * 6 + k) * O + o) * T + 8 * j);
        wino_at(m, &r0[i], &r1[i]);  /* along the row: output columns 0, 1 */
      }
      v8f y00, y10, y01, y11;
      wino_at(r0, &y00, &y10);  /* along the column: output rows 0, 1 */
      wino_at(r1, &y01, &y11);
      y00 += bias, y01 += bias, y10 += bias, y11 += bias;
      if (a->relu) {
        v8f z = vsplat(0.0f);
        y00 = vsel(y00 > z, y00, z), y01 = vsel(y01 > z, y01, z);
        y10 = vsel(y10 > z, y10, z), y11 = vsel(y11 > z, y11, z);
      }
      /* Tile t's columns 2t, 2t + 1: interleave the column-0 and column-1 vectors. */
      float *d0 = a->dst[0] + oc * a->dcs + xl + 16 * j;
      float *d1 = a->dst[1] + oc * a->dcs + xl + 16 * j;
      vstore(d0, WINO_SHUF8(y00, y01, 0, 8, 1, 9, 2, 10, 3, 11));
      vstore(d0 + 8, WINO_SHUF8(y00, y01, 4, 12, 5, 13, 6, 14, 7, 15));
      vstore(d1, WINO_SHUF8(y10, y11, 0, 8, 1, 9, 2, 10, 3, 11));
      vstore(d1 + 8, WINO_SHUF8(y10, y11, 4, 12, 5, 13, 6, 14, 7, 15));
    }
  }
}

/* All groups of a chunk: 16 tiles per group with 32 registers (`wide`), else 8. Output
 * blocks of 10 (the kernel layer's 50 outputs) or 12 (12-channel body layers). */
#define WINO_CASE(O_) \
  case O_: \
    for (uint32_t xl = 0; xl < a->n;) { \
      if (wide && a->n - xl >= 32) wino_group_t(a, xl, O_, 2), xl += 32; \
      else wino_group_t(a, xl, O_, 1), xl += 16; \
    } \
    break;
AI void wino_dispatch(const wino_a *a, uint32_t oblk, const int wide) {
  switch (oblk) {
    WINO_CASE(10)
    WINO_CASE(12)
    default: break;
  }
}

/* ---- Winograd F(4x4, 5x5) for the kernel layer ---- */

/* Four output rows p .. p + 3 (p a multiple of 4: tiles sit on absolute rows and columns
 * that are multiples of 4, whatever the band or column tile) of columns x0 .. x0 + n (n a
 * multiple of 32, x0 a multiple of 4, in the input rows' own coordinates as in conv_a).
 * rowp[i]: input row p - 2 + i (i < 8). Output channel oc of row p + r, column i goes to
 * dst[r][oc * dcs + i] (bias added; no activation: the kernel layer's logits). 8 tiles (32
 * columns) per vector; their lanes hold tiles 0 2 4 6 1 3 5 7, the order a 4 x 4
 * transpose inside each 128-bit half gives, undone by the same transpose at the output.
 * Per group: the input transform fills V[64][in][8]; per block of O outputs the 64
 * products M[pos][O][8] = U[pos][O][in] x V[pos][in][8], then the output transform. Every
 * tile's arithmetic is the same whatever lane or group it is in. */
typedef struct wino4_a {
  const float *rowp[8];
  size_t cs;
  uint32_t in, nob, out;
  const float *u, *b;   /* this set's transformed weights [block][64][in][O] and biases */
  uint32_t x0, n;
  float *dst[4];
  size_t dcs;
  int relu;
  float *vbuf, *mbuf, *ebuf;  /* scratch: 64 * in * 16, 64 * O * 16 and 64 * 16 floats */
} wino4_a;

#if FAST_X86
/* 4 x 4 transpose inside each 128-bit half of (r0, r1, r2, r3). */
#define WINO4_T4(r0, r1, r2, r3)                                              \
  do {                                                                         \
    __m256 t0_ = _mm256_unpacklo_ps(r0, r1), t1_ = _mm256_unpackhi_ps(r0, r1); \
    __m256 t2_ = _mm256_unpacklo_ps(r2, r3), t3_ = _mm256_unpackhi_ps(r2, r3); \
    r0 = _mm256_shuffle_ps(t0_, t2_, 0x44);                                    \
    r1 = _mm256_shuffle_ps(t0_, t2_, 0xEE);                                    \
    r2 = _mm256_shuffle_ps(t1_, t3_, 0x44);                                    \
    r3 = _mm256_shuffle_ps(t1_, t3_, 0xEE);                                    \
  } while (0)

/* B^T of one 8-vector (rows: -1 0 21/4 0 -21/4 0 1 0 / 0 1 1 -17/4 -17/4 1 1 0 /
 * 0 -1 1 17/4 -17/4 -1 1 0 / 0 1/2 1/4 -5/2 -5/4 2 1 0 / 0 -1/2 1/4 5/2 -5/4 -2 1 0 /
 * 0 2 4 -5/2 -5 1/2 1 0 / 0 -2 4 5/2 -5 -1/2 1 0 / 0 -1 0 21/4 0 -21/4 0 1), the even and
 * odd halves of each +-pair computed once. */
TGT_V3 AI void wino4_bt(const __m256 d[8], __m256 v[8]) {
  const __m256 c21 = _mm256_set1_ps(5.25f), c17 = _mm256_set1_ps(4.25f);
  v[0] = _mm256_add_ps(_mm256_sub_ps(d[6], d[0]), _mm256_mul_ps(_mm256_sub_ps(d[2], d[4]), c21));
  v[7] = _mm256_add_ps(_mm256_sub_ps(d[7], d[1]), _mm256_mul_ps(_mm256_sub_ps(d[3], d[5]), c21));
  __m256 e1 = _mm256_fnmadd_ps(d[4], c17, _mm256_add_ps(d[2], d[6]));
  __m256 o1 = _mm256_fnmadd_ps(d[3], c17, _mm256_add_ps(d[1], d[5]));
  v[1] = _mm256_add_ps(e1, o1);
  v[2] = _mm256_sub_ps(e1, o1);
  __m256 e2 = _mm256_fmadd_ps(d[2], _mm256_set1_ps(0.25f),
                              _mm256_fnmadd_ps(d[4], _mm256_set1_ps(1.25f), d[6]));
  __m256 o2 = _mm256_fmadd_ps(d[1], _mm256_set1_ps(0.5f),
                              _mm256_fmadd_ps(d[5], _mm256_set1_ps(2.0f),
                                              _mm256_mul_ps(d[3], _mm256_set1_ps(-2.5f))));
  v[3] = _mm256_add_ps(e2, o2);
  v[4] = _mm256_sub_ps(e2, o2);
  __m256 e3 = _mm256_fmadd_ps(d[2], _mm256_set1_ps(4.0f),
                              _mm256_fnmadd_ps(d[4], _mm256_set1_ps(5.0f), d[6]));
  __m256 o3 = _mm256_fmadd_ps(d[1], _mm256_set1_ps(2.0f),
                              _mm256_fmadd_ps(d[5], _mm256_set1_ps(0.5f),
                                              _mm256_mul_ps(d[3], _mm256_set1_ps(-2.5f))));
  v[5] = _mm256_add_ps(e3, o3);
  v[6] = _mm256_sub_ps(e3, o3);
}

/* A^T of one 8-vector (rows 1 1 1 1 1 1 1 0 / 0 1 -1 2 -2 1/2 -1/2 0 / 0 1 1 4 4 1/4 1/4 0 /
 * 0 1 -1 8 -8 1/8 -1/8 1). */
TGT_V3 AI void wino4_at(const __m256 m[8], __m256 y[4]) {
  __m256 s1 = _mm256_add_ps(m[1], m[2]), d1 = _mm256_sub_ps(m[1], m[2]);
  __m256 s2 = _mm256_add_ps(m[3], m[4]), d2 = _mm256_sub_ps(m[3], m[4]);
  __m256 s3 = _mm256_add_ps(m[5], m[6]), d3 = _mm256_sub_ps(m[5], m[6]);
  y[0] = _mm256_add_ps(_mm256_add_ps(m[0], s1), _mm256_add_ps(s2, s3));
  y[1] = _mm256_fmadd_ps(d3, _mm256_set1_ps(0.5f), _mm256_fmadd_ps(d2, _mm256_set1_ps(2.0f), d1));
  y[2] = _mm256_fmadd_ps(s3, _mm256_set1_ps(0.25f), _mm256_fmadd_ps(s2, _mm256_set1_ps(4.0f), s1));
  y[3] = _mm256_add_ps(_mm256_fmadd_ps(d3, _mm256_set1_ps(0.125f),
                                       _mm256_fmadd_ps(d2, _mm256_set1_ps(8.0f), d1)), m[7]);
}

/* One group of 8P tiles (32P columns from xl), O outputs per block; P = 2 (16 tiles)
 * needs the 32 vector registers of AVX-512VL for its 2 O accumulators. */
TGT_V3 AI void wino4_group_t(const wino4_a *a, uint32_t xl, const int O, const int P) {
  const uint32_t I = a->in;
  const int T = 8 * P;
  float *V = a->vbuf, *M = a->mbuf, *E = a->ebuf;
  /* lane shifts by one tile in the 0 2 4 6 1 3 5 7 order: the tile before / after */
  const __m256i prev = _mm256_setr_epi32(0, 4, 5, 6, 0, 1, 2, 3);
  const __m256i next = _mm256_setr_epi32(4, 5, 6, 7, 1, 2, 3, 0);
  for (uint32_t c = 0; c < I; c++)
#pragma GCC unroll 2
    for (int j = 0; j < P; j++) {
#pragma GCC unroll 8
      for (int i = 0; i < 8; i++) {
        const float *q = a->rowp[i] + c * a->cs + COL + a->x0 + xl + 32 * j;
        __m256 r0 = _mm256_loadu_ps(q), r1 = _mm256_loadu_ps(q + 8),
               r2 = _mm256_loadu_ps(q + 16), r3 = _mm256_loadu_ps(q + 24);
        WINO4_T4(r0, r1, r2, r3);  /* rk: column 4t + k of tile t */
        __m256 d[8];
        d[0] = _mm256_blend_ps(_mm256_permutevar8x32_ps(r2, prev), _mm256_broadcast_ss(q - 2), 1);
        d[1] = _mm256_blend_ps(_mm256_permutevar8x32_ps(r3, prev), _mm256_broadcast_ss(q - 1), 1);
        d[2] = r0, d[3] = r1, d[4] = r2, d[5] = r3;
        d[6] = _mm256_blend_ps(_mm256_permutevar8x32_ps(r0, next), _mm256_broadcast_ss(q + 32), 0x80);
        d[7] = _mm256_blend_ps(_mm256_permutevar8x32_ps(r1, next), _mm256_broadcast_ss(q + 33), 0x80);
        __m256 e[8];
        wino4_bt(d, e);  /* along the row: E[i][s] */
#pragma GCC unroll 8
        for (int s2 = 0; s2 < 8; s2++) _mm256_store_ps(E + (i * 8 + s2) * 8, e[s2]);
      }
#pragma GCC unroll 8
      for (int s2 = 0; s2 < 8; s2++) {
        __m256 col[8], v[8];
#pragma GCC unroll 8
        for (int i = 0; i < 8; i++) col[i] = _mm256_load_ps(E + (i * 8 + s2) * 8);
        wino4_bt(col, v);  /* along the column: V[r][s2] */
#pragma GCC unroll 8
        for (int r = 0; r < 8; r++)
          _mm256_store_ps(V + ((size_t)(r * 8 + s2) * I + c) * T + 8 * j, v[r]);
      }
    }
  for (uint32_t ob = 0; ob < a->nob; ob++) {
    const float *u = a->u + (size_t)ob * WINO4_POS * I * O;
    for (uint32_t pos = 0; pos < WINO4_POS; pos++) {
      __m256 acc[12][2];
#pragma GCC unroll 12
      for (int o = 0; o < O; o++)
#pragma GCC unroll 2
        for (int j = 0; j < P; j++) acc[o][j] = _mm256_setzero_ps();
      const float *vp = V + (size_t)pos * I * T;
      for (uint32_t c = 0; c < I; c++) {
        __m256 in[2];
#pragma GCC unroll 2
        for (int j = 0; j < P; j++) in[j] = _mm256_load_ps(vp + 8 * j);
#pragma GCC unroll 12
        for (int o = 0; o < O; o++) {
          __m256 wv = _mm256_broadcast_ss(u + o);
#pragma GCC unroll 2
          for (int j = 0; j < P; j++) acc[o][j] = _mm256_fmadd_ps(in[j], wv, acc[o][j]);
        }
        u += O;
        vp += T;
      }
#pragma GCC unroll 12
      for (int o = 0; o < O; o++)
#pragma GCC unroll 2
        for (int j = 0; j < P; j++) _mm256_store_ps(M + ((size_t)pos * O + o) * T + 8 * j, acc[o][j]);
    }
    for (int o = 0; o < O; o++) {
      uint32_t oc = ob * (uint32_t)O + (uint32_t)o;
      if (oc >= a->out) break;
      __m256 bias = _mm256_broadcast_ss(a->b + oc);
#pragma GCC unroll 2
      for (int j = 0; j < P; j++) {
        __m256 t[8][4];
#pragma GCC unroll 8
        for (int i = 0; i < 8; i++) {
          __m256 m8[8];
#pragma GCC unroll 8
          for (int k = 0; k < 8; k++)
            m8[k] = _mm256_load_ps(M + ((size_t)(i * 8 + k) * O + o) * T + 8 * j);
          wino4_at(m8, t[i]);  /* along the row: tile columns 0..3 */
        }
        __m256 y[4][4];  /* [row][column] */
#pragma GCC unroll 4
        for (int k = 0; k < 4; k++) {
          __m256 col[8], yy[4];
#pragma GCC unroll 8
          for (int i = 0; i < 8; i++) col[i] = t[i][k];
          wino4_at(col, yy);  /* along the column: output rows 0..3 */
#pragma GCC unroll 4
          for (int r = 0; r < 4; r++) {
            y[r][k] = _mm256_add_ps(yy[r], bias);
            if (a->relu) y[r][k] = _mm256_max_ps(y[r][k], _mm256_setzero_ps());
          }
        }
#pragma GCC unroll 4
        for (int r = 0; r < 4; r++) {
          WINO4_T4(y[r][0], y[r][1], y[r][2], y[r][3]);  /* back to column order */
          float *d = a->dst[r] + oc * a->dcs + xl + 32 * j;
          for (int k = 0; k < 4; k++) _mm256_storeu_ps(d + 8 * k, y[r][k]);
        }
      }
    }
  }
}

/* All groups of a chunk; output blocks of 10 (the kernel layer's 50 outputs), 12 or 6
 * (12- and 6-channel body layers). */
#define WINO4_CASE(O_) \
  case O_: \
    for (uint32_t xl = 0; xl < a->n;) { \
      if (wide && a->n - xl >= 64) wino4_group_t(a, xl, O_, 2), xl += 64; \
      else wino4_group_t(a, xl, O_, 1), xl += 32; \
    } \
    break;
TGT_V3 AI void wino4_dispatch(const wino4_a *a, uint32_t oblk, const int wide) {
  switch (oblk) {
    WINO4_CASE(6)
    WINO4_CASE(10)
    WINO4_CASE(12)
    default: break;
  }
}

/* ---- F(4x4, 5x5) on 16-lane (AVX-512) vectors ---- */

/* With AVX-512 the same tiles run 16 per vector (64 columns): twice the FMAs per
 * instruction of the 8-lane code above (this machine's zmm peak is twice its ymm one). The
 * lanes hold tiles 0 4 8 12 1 5 9 13 2 6 10 14 3 7 11 15 (the 4 x 4 transpose inside each
 * 128-bit quarter of 4 vectors), undone at the output. Every step mirrors the 8-lane
 * code's operation for operation (same expressions, so the same contractions and
 * roundings): a tile's results do not depend on which of the two codes ran it, so column
 * tiles and chunk tails that mix them stay bit-identical. */
#define WINO4_T4_16(r0, r1, r2, r3)                                           \
  do {                                                                         \
    __m512 t0_ = _mm512_unpacklo_ps(r0, r1), t1_ = _mm512_unpackhi_ps(r0, r1); \
    __m512 t2_ = _mm512_unpacklo_ps(r2, r3), t3_ = _mm512_unpackhi_ps(r2, r3); \
    r0 = _mm512_shuffle_ps(t0_, t2_, 0x44);                                    \
    r1 = _mm512_shuffle_ps(t0_, t2_, 0xEE);                                    \
    r2 = _mm512_shuffle_ps(t1_, t3_, 0x44);                                    \
    r3 = _mm512_shuffle_ps(t1_, t3_, 0xEE);                                    \
  } while (0)

/* wino4_bt on 16 lanes. */
TGT_V4 AI void wino4_bt16(const __m512 d[8], __m512 v[8]) {
  const __m512 c21 = _mm512_set1_ps(5.25f), c17 = _mm512_set1_ps(4.25f);
  v[0] = _mm512_add_ps(_mm512_sub_ps(d[6], d[0]), _mm512_mul_ps(_mm512_sub_ps(d[2], d[4]), c21));
  v[7] = _mm512_add_ps(_mm512_sub_ps(d[7], d[1]), _mm512_mul_ps(_mm512_sub_ps(d[3], d[5]), c21));
  __m512 e1 = _mm512_fnmadd_ps(d[4], c17, _mm512_add_ps(d[2], d[6]));
  __m512 o1 = _mm512_fnmadd_ps(d[3], c17, _mm512_add_ps(d[1], d[5]));
  v[1] = _mm512_add_ps(e1, o1);
  v[2] = _mm512_sub_ps(e1, o1);
  __m512 e2 = _mm512_fmadd_ps(d[2], _mm512_set1_ps(0.25f),
                              _mm512_fnmadd_ps(d[4], _mm512_set1_ps(1.25f), d[6]));
  __m512 o2 = _mm512_fmadd_ps(d[1], _mm512_set1_ps(0.5f),
                              _mm512_fmadd_ps(d[5], _mm512_set1_ps(2.0f),
                                              _mm512_mul_ps(d[3], _mm512_set1_ps(-2.5f))));
  v[3] = _mm512_add_ps(e2, o2);
  v[4] = _mm512_sub_ps(e2, o2);
  __m512 e3 = _mm512_fmadd_ps(d[2], _mm512_set1_ps(4.0f),
                              _mm512_fnmadd_ps(d[4], _mm512_set1_ps(5.0f), d[6]));
  __m512 o3 = _mm512_fmadd_ps(d[1], _mm512_set1_ps(2.0f),
                              _mm512_fmadd_ps(d[5], _mm512_set1_ps(0.5f),
                                              _mm512_mul_ps(d[3], _mm512_set1_ps(-2.5f))));
  v[5] = _mm512_add_ps(e3, o3);
  v[6] = _mm512_sub_ps(e3, o3);
}

/* wino4_at on 16 lanes. */
TGT_V4 AI void wino4_at16(const __m512 m[8], __m512 y[4]) {
  __m512 s1 = _mm512_add_ps(m[1], m[2]), d1 = _mm512_sub_ps(m[1], m[2]);
  __m512 s2 = _mm512_add_ps(m[3], m[4]), d2 = _mm512_sub_ps(m[3], m[4]);
  __m512 s3 = _mm512_add_ps(m[5], m[6]), d3 = _mm512_sub_ps(m[5], m[6]);
  y[0] = _mm512_add_ps(_mm512_add_ps(m[0], s1), _mm512_add_ps(s2, s3));
  y[1] = _mm512_fmadd_ps(d3, _mm512_set1_ps(0.5f), _mm512_fmadd_ps(d2, _mm512_set1_ps(2.0f), d1));
  y[2] = _mm512_fmadd_ps(s3, _mm512_set1_ps(0.25f), _mm512_fmadd_ps(s2, _mm512_set1_ps(4.0f), s1));
  y[3] = _mm512_add_ps(_mm512_fmadd_ps(d3, _mm512_set1_ps(0.125f),
                                       _mm512_fmadd_ps(d2, _mm512_set1_ps(8.0f), d1)), m[7]);
}

/* One group of 16 tiles (64 columns from xl), O outputs per block: wino4_group_t's steps
 * with T = 16 lanes. */
TGT_V4 AI void wino4_group16_t(const wino4_a *a, uint32_t xl, const int O) {
  const uint32_t I = a->in;
  float *V = a->vbuf, *M = a->mbuf, *E = a->ebuf;
  /* lane shifts by one tile in the lane order above: the tile before / after */
  const __m512i prev = _mm512_setr_epi32(0, 12, 13, 14, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11);
  const __m512i next = _mm512_setr_epi32(4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 1, 2, 3, 0);
  for (uint32_t c = 0; c < I; c++) {
#pragma GCC unroll 8
    for (int i = 0; i < 8; i++) {
      const float *q = a->rowp[i] + c * a->cs + COL + a->x0 + xl;
      __m512 r0 = _mm512_loadu_ps(q), r1 = _mm512_loadu_ps(q + 16),
             r2 = _mm512_loadu_ps(q + 32), r3 = _mm512_loadu_ps(q + 48);
      WINO4_T4_16(r0, r1, r2, r3);  /* rk: column 4t + k of tile t */
      __m512 d[8];
      d[0] = _mm512_mask_blend_ps(0x0001, _mm512_permutexvar_ps(prev, r2), _mm512_set1_ps(q[-2]));
      d[1] = _mm512_mask_blend_ps(0x0001, _mm512_permutexvar_ps(prev, r3), _mm512_set1_ps(q[-1]));
      d[2] = r0, d[3] = r1, d[4] = r2, d[5] = r3;
      d[6] = _mm512_mask_blend_ps(0x8000, _mm512_permutexvar_ps(next, r0), _mm512_set1_ps(q[64]));
      d[7] = _mm512_mask_blend_ps(0x8000, _mm512_permutexvar_ps(next, r1), _mm512_set1_ps(q[65]));
      __m512 e[8];
      wino4_bt16(d, e);  /* along the row: E[i][s] */
#pragma GCC unroll 8
      for (int s2 = 0; s2 < 8; s2++) _mm512_store_ps(E + (i * 8 + s2) * 16, e[s2]);
    }
#pragma GCC unroll 8
    for (int s2 = 0; s2 < 8; s2++) {
      __m512 col[8], v[8];
#pragma GCC unroll 8
      for (int i = 0; i < 8; i++) col[i] = _mm512_load_ps(E + (i * 8 + s2) * 16);
      wino4_bt16(col, v);  /* along the column: V[r][s2] */
#pragma GCC unroll 8
      for (int r = 0; r < 8; r++) _mm512_store_ps(V + ((size_t)(r * 8 + s2) * I + c) * 16, v[r]);
    }
  }
  for (uint32_t ob = 0; ob < a->nob; ob++) {
    const float *u = a->u + (size_t)ob * WINO4_POS * I * O;
    for (uint32_t pos = 0; pos < WINO4_POS; pos++) {
      __m512 acc[12];
#pragma GCC unroll 12
      for (int o = 0; o < O; o++) acc[o] = _mm512_setzero_ps();
      const float *vp = V + (size_t)pos * I * 16;
      for (uint32_t c = 0; c < I; c++) {
        __m512 in = _mm512_load_ps(vp);
#pragma GCC unroll 12
        for (int o = 0; o < O; o++) acc[o] = _mm512_fmadd_ps(in, _mm512_set1_ps(u[o]), acc[o]);
        u += O;
        vp += 16;
      }
#pragma GCC unroll 12
      for (int o = 0; o < O; o++) _mm512_store_ps(M + ((size_t)pos * O + o) * 16, acc[o]);
    }
    for (int o = 0; o < O; o++) {
      uint32_t oc = ob * (uint32_t)O + (uint32_t)o;
      if (oc >= a->out) break;
      __m512 bias = _mm512_set1_ps(a->b[oc]);
      __m512 t[8][4];
#pragma GCC unroll 8
      for (int i = 0; i < 8; i++) {
        __m512 m8[8];
#pragma GCC unroll 8
        for (int k = 0; k < 8; k++) m8[k] = _mm512_load_ps(M + ((size_t)(i * 8 + k) * O + o) * 16);
        wino4_at16(m8, t[i]);  /* along the row: tile columns 0..3 */
      }
      __m512 y[4][4];  /* [row][column] */
#pragma GCC unroll 4
      for (int k = 0; k < 4; k++) {
        __m512 col[8], yy[4];
#pragma GCC unroll 8
        for (int i = 0; i < 8; i++) col[i] = t[i][k];
        wino4_at16(col, yy);  /* along the column: output rows 0..3 */
#pragma GCC unroll 4
        for (int r = 0; r < 4; r++) {
          y[r][k] = _mm512_add_ps(yy[r], bias);
          if (a->relu) y[r][k] = _mm512_max_ps(y[r][k], _mm512_setzero_ps());
        }
      }
#pragma GCC unroll 4
      for (int r = 0; r < 4; r++) {
        WINO4_T4_16(y[r][0], y[r][1], y[r][2], y[r][3]);  /* back to column order */
        float *d = a->dst[r] + oc * a->dcs + xl;
        for (int k = 0; k < 4; k++) _mm512_storeu_ps(d + 16 * k, y[r][k]);
      }
    }
  }
}

/* All groups of a chunk on AVX-512: 64 columns per 16-lane group, a 32-column tail by the
 * 8-lane code. */
#define WINO4_CASE16(O_) \
  case O_: \
    for (uint32_t xl = 0; xl < a->n;) { \
      if (a->n - xl >= 64) wino4_group16_t(a, xl, O_), xl += 64; \
      else wino4_group_t(a, xl, O_, 1), xl += 32; \
    } \
    break;
TGT_V4 AI void wino4_dispatch16(const wino4_a *a, uint32_t oblk) {
  switch (oblk) {
    WINO4_CASE16(6)
    WINO4_CASE16(10)
    WINO4_CASE16(12)
    default: break;
  }
}
#endif

/* ---- softmax + colour mix + hidden layer + outputs ---- */

typedef struct mix_a {
  const tt__net_state *s;
  const tt__net_model *m;
  float *lg;            /* logits [50][CHUNK] of columns x0.. (overwritten) */
  uint32_t x0, n, y;
  const float *hrow;    /* last body layer, row y: channel c at hrow[c * hcs + COL + x - hx] */
  size_t hcs;
  int hx;               /* first column of the tile's ring rows */
  const float *hw, *hb; /* hidden layer weights [out][in] and biases of this set */
  float *out_rgb;
} mix_a;

/* 8 lanes of three vectors interleaved into 24 floats r0 g0 b0 r1 g1 b1 ... (the linear
 * output's pixel order). */
AI void store_rgb8(float *dst, v8f r, v8f g, v8f b) {
  v8f rg0 = WINO_SHUF8(r, g, 0, 8, 0, 1, 9, 0, 2, 10);
  v8f rg1 = WINO_SHUF8(r, g, 0, 3, 11, 0, 4, 12, 0, 5);
  v8f rg2 = WINO_SHUF8(r, g, 13, 0, 6, 14, 0, 7, 15, 0);
  vstore(dst, WINO_SHUF8(rg0, b, 0, 1, 8, 3, 4, 9, 6, 7));
  vstore(dst + 8, WINO_SHUF8(rg1, b, 10, 1, 2, 11, 4, 5, 12, 7));
  vstore(dst + 16, WINO_SHUF8(rg2, b, 0, 13, 2, 3, 14, 5, 6, 15));
}

/* 8 x 8 transpose: t[l][c] = v[c][l] (channel vectors of 8 pixels <-> the pixels' 8
 * channels). */
AI void t8x8(const v8f v[8], v8f t[8]) {
  v8f a[8], b[8];
#pragma GCC unroll 4
  for (int k = 0; k < 8; k += 2) {  /* a[k]: lanes 0 1 | 4 5 of rows k, k + 1 interleaved */
    a[k] = WINO_SHUF8(v[k], v[k + 1], 0, 8, 1, 9, 4, 12, 5, 13);
    a[k + 1] = WINO_SHUF8(v[k], v[k + 1], 2, 10, 3, 11, 6, 14, 7, 15);
  }
#pragma GCC unroll 2
  for (int k = 0; k < 8; k += 4)  /* b[k + i]: lanes (0 2 1 3)[i] | + 4 of rows k..k + 3 */
#pragma GCC unroll 2
    for (int j = 0; j < 2; j++) {
      b[k + j] = WINO_SHUF8(a[k + j], a[k + j + 2], 0, 1, 8, 9, 4, 5, 12, 13);
      b[k + j + 2] = WINO_SHUF8(a[k + j], a[k + j + 2], 2, 3, 10, 11, 6, 7, 14, 15);
    }
  static const int lane[4] = {0, 2, 1, 3};
#pragma GCC unroll 4
  for (int k = 0; k < 4; k++) {
    t[lane[k]] = WINO_SHUF8(b[k], b[k + 4], 0, 1, 2, 3, 8, 9, 10, 11);
    t[lane[k] + 4] = WINO_SHUF8(b[k], b[k + 4], 4, 5, 6, 7, 12, 13, 14, 15);
  }
}

/* The 8 channel vectors v of 8 pixels to dst in pixel-major order (8 floats per pixel). */
AI void store_t8x8(float *dst, const v8f v[8]) {
  v8f t[8];
  t8x8(v, t);
#pragma GCC unroll 8
  for (int l = 0; l < 8; l++) vstore(dst + 8 * l, t[l]);
}

/* `hidden`: the model's hidden channels, a constant in the dispatch's common cases (the
 * hidden layer's sums then stay in registers). */
AI void mix_rows_t(const mix_a *a, const uint32_t hidden) {
  const tt__net_state *s = a->s;
  const uint32_t hin = a->m->hid.in, sc = s->state_ch;
  const size_t rs = s->inp_ys, cs = s->inp_cs;
  for (uint32_t xl = 0; xl < a->n; xl += 8) {
    uint32_t x = a->x0 + xl;
    if (x >= s->width) break;
    float *lg = a->lg + xl;
    /* Max in 5 independent chains (the same value as one chain: max is exact). */
    v8f m5[5];
#pragma GCC unroll 5
    for (int k = 0; k < 5; k++) m5[k] = vload(lg + k * CHUNK);
#pragma GCC unroll 9
    for (int k = 5; k < 50; k += 5)
#pragma GCC unroll 5
      for (int j = 0; j < 5; j++) m5[j] = vmax(m5[j], vload(lg + (k + j) * CHUNK));
    v8f mx = vmax(vmax(vmax(m5[0], m5[1]), vmax(m5[2], m5[3])), m5[4]);
    /* The softmax weights computed where the mix uses them (no store and reload of the 50
     * exponentials); the two kernels' sums in separate chains. */
    v8f sa = vsplat(0.0f), sb = vsplat(0.0f);
    v8f o[3] = {vsplat(0.0f), vsplat(0.0f), vsplat(0.0f)};
    const float *row = s->inp + (size_t)(a->y - 2 + s->halo) * rs + COL + x - 2;
    for (uint32_t ty = 0; ty < 5; ty++, row += rs) {
      const float *lt = lg + ty * 5 * CHUNK;
#pragma GCC unroll 5
      for (uint32_t tx = 0; tx < 5; tx++) {
        v8f ka = vexp_neg(vload(lt + tx * CHUNK) - mx);
        v8f kb = vexp_neg(vload(lt + (25 + tx) * CHUNK) - mx);
        sa += ka;
        sb += kb;
#pragma GCC unroll 3
        for (int c = 0; c < 3; c++)
          o[c] += ka * vload(row + c * cs + tx) + kb * vload(row + (6 + c) * cs + tx);
      }
    }
    v8f sum = sa + sb;
    v8f inv = vsplat(1.0f) / sum;
    v8f st[16];
#pragma GCC unroll 3
    for (int c = 0; c < 3; c++) st[c] = o[c] = o[c] * inv;
    /* Hidden layer (1x1): each input vector loaded once for all outputs; every output's
     * sum runs over the inputs in order. */
    const float *hp = a->hrow + (int)(COL + x) - a->hx;
#pragma GCC unroll 8
    for (uint32_t k = 0; k < hidden; k++) st[3 + k] = vsplat(a->hb[k]);
    for (uint32_t c = 0; c < hin; c++) {
      v8f xin = vload(hp + c * a->hcs);
#pragma GCC unroll 8
      for (uint32_t k = 0; k < hidden; k++) st[3 + k] += xin * a->hw[k * hin + c];
    }
    /* Linear output: the inverse tonemap of taa_image.c on 8 lanes. */
    v8f z = vsplat(0.0f);
    v8f mm = vmin(vmax(vmax(o[0], o[1]), vmax(o[2], z)), vsplat(0.999f));
    v8f scale = vsplat(1.0f) / (vsplat(1.0f) - mm);
    v8f lin[3];
    for (int c = 0; c < 3; c++) lin[c] = vmax(o[c], z) * scale;
    uint32_t lanes = s->width - x < 8 ? s->width - x : 8;
    size_t i = (size_t)a->y * s->width + x;
    float *ns = s->next_state + i * sc, *out = a->out_rgb + i * 3;
    if (lanes == 8) {
      store_rgb8(out, lin[0], lin[1], lin[2]);
      if (hidden == 5) {  /* 8 state channels */
        store_t8x8(ns, st);
        continue;
      }
    } else {
      for (uint32_t l = 0; l < lanes; l++)
        for (int c = 0; c < 3; c++) out[l * 3 + c] = lin[c][l];
    }
    for (uint32_t l = 0; l < lanes; l++)
      for (uint32_t c = 0; c < sc; c++) ns[l * sc + c] = st[c][l];
  }
}

AI void mix_dispatch(const mix_a *a) {
  switch (a->m->hidden) {
    case 0: mix_rows_t(a, 0); break;
    case 5: mix_rows_t(a, 5); break;
    default: mix_rows_t(a, a->m->hidden); break;
  }
}

#if FAST_X86
/* ---- the colour mix on 16-lane vectors (AVX-512) ---- */

/* v16f copies of vmax / vmin / vexp_neg: the same operations per lane (MAXPS / MINPS are
 * vsel(a > b, a, b) / vsel(a < b, a, b), NaN included), so the same results bit for bit. */
typedef int32_t v16i __attribute__((vector_size(64)));
TGT_V4 AI v16f vmax16(v16f a, v16f b) { return (v16f)_mm512_max_ps((__m512)a, (__m512)b); }
TGT_V4 AI v16f vmin16(v16f a, v16f b) { return (v16f)_mm512_min_ps((__m512)a, (__m512)b); }
TGT_V4 AI v16f vload16(const float *p) { return *(const v16fu *)p; }
TGT_V4 AI v16f vsplat16(float f) { return (v16f)_mm512_set1_ps(f); }
TGT_V4 AI v16f vexp_neg16(v16f x) {
  x = vmax16(x, vsplat16(-87.0f));
  v16f t = x * 1.44269504088896341f;
  v16f n = (t + 12582912.0f) - 12582912.0f;
  v16f r = x - n * 0.693145751953125f - n * 1.428606765330187045e-06f;
  v16f p = r * (1.0f / 720.0f) + 1.0f / 120.0f;
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  v16i e = (__builtin_convertvector(n, v16i) + 127) << 23;
  v16f scale;
  memcpy(&scale, &e, sizeof scale);
  return p * scale;
}

/* mix_rows_t on 16 pixels per step: the same steps; the stores go out as two 8-pixel
 * halves by the 8-lane helpers. */
TGT_V4 AI void mix_rows16_t(const mix_a *a, const uint32_t hidden) {
  const tt__net_state *s = a->s;
  const uint32_t hin = a->m->hid.in, sc = s->state_ch;
  const size_t rs = s->inp_ys, cs = s->inp_cs;
  for (uint32_t xl = 0; xl < a->n; xl += 16) {
    uint32_t x = a->x0 + xl;
    if (x >= s->width) break;
    float *lg = a->lg + xl;
    v16f m5[5];
#pragma GCC unroll 5
    for (int k = 0; k < 5; k++) m5[k] = vload16(lg + k * CHUNK);
#pragma GCC unroll 9
    for (int k = 5; k < 50; k += 5)
#pragma GCC unroll 5
      for (int j = 0; j < 5; j++) m5[j] = vmax16(m5[j], vload16(lg + (k + j) * CHUNK));
    v16f mx = vmax16(vmax16(vmax16(m5[0], m5[1]), vmax16(m5[2], m5[3])), m5[4]);
    v16f sa = vsplat16(0.0f), sb = vsplat16(0.0f);
    v16f o[3] = {vsplat16(0.0f), vsplat16(0.0f), vsplat16(0.0f)};
    const float *row = s->inp + (size_t)(a->y - 2 + s->halo) * rs + COL + x - 2;
    for (uint32_t ty = 0; ty < 5; ty++, row += rs) {
      const float *lt = lg + ty * 5 * CHUNK;
#pragma GCC unroll 5
      for (uint32_t tx = 0; tx < 5; tx++) {
        v16f ka = vexp_neg16(vload16(lt + tx * CHUNK) - mx);
        v16f kb = vexp_neg16(vload16(lt + (25 + tx) * CHUNK) - mx);
        sa += ka;
        sb += kb;
#pragma GCC unroll 3
        for (int c = 0; c < 3; c++)
          o[c] += ka * vload16(row + c * cs + tx) + kb * vload16(row + (6 + c) * cs + tx);
      }
    }
    v16f sum = sa + sb;
    v16f inv = vsplat16(1.0f) / sum;
    v16f st[16];
#pragma GCC unroll 3
    for (int c = 0; c < 3; c++) st[c] = o[c] = o[c] * inv;
    const float *hp = a->hrow + (int)(COL + x) - a->hx;
#pragma GCC unroll 8
    for (uint32_t k = 0; k < hidden; k++) st[3 + k] = vsplat16(a->hb[k]);
    for (uint32_t c = 0; c < hin; c++) {
      v16f xin = vload16(hp + c * a->hcs);
#pragma GCC unroll 8
      for (uint32_t k = 0; k < hidden; k++) st[3 + k] += xin * a->hw[k * hin + c];
    }
    v16f z = vsplat16(0.0f);
    v16f mm = vmin16(vmax16(vmax16(o[0], o[1]), vmax16(o[2], z)), vsplat16(0.999f));
    v16f scale = vsplat16(1.0f) / (vsplat16(1.0f) - mm);
    v16f lin[3];
    for (int c = 0; c < 3; c++) lin[c] = vmax16(o[c], z) * scale;
    uint32_t lanes = s->width - x < 16 ? s->width - x : 16;
    size_t i = (size_t)a->y * s->width + x;
    float *ns = s->next_state + i * sc, *out = a->out_rgb + i * 3;
    if (lanes == 16) {
      v8f l8[3][2];
      for (int c = 0; c < 3; c++) memcpy(l8[c], &lin[c], sizeof lin[c]);
      store_rgb8(out, l8[0][0], l8[1][0], l8[2][0]);
      store_rgb8(out + 24, l8[0][1], l8[1][1], l8[2][1]);
      if (hidden == 5) {  /* 8 state channels */
        v8f s8[2][8];
        for (int c = 0; c < 8; c++) {
          v8f h[2];
          memcpy(h, &st[c], sizeof h);
          s8[0][c] = h[0], s8[1][c] = h[1];
        }
        store_t8x8(ns, s8[0]);
        store_t8x8(ns + 64, s8[1]);
        continue;
      }
    } else {
      for (uint32_t l = 0; l < lanes; l++)
        for (int c = 0; c < 3; c++) out[l * 3 + c] = lin[c][l];
    }
    for (uint32_t l = 0; l < lanes; l++)
      for (uint32_t c = 0; c < sc; c++) ns[l * sc + c] = st[c][l];
  }
}

TGT_V4 AI void mix16_dispatch(const mix_a *a) {
  switch (a->m->hidden) {
    case 0: mix_rows16_t(a, 0); break;
    case 5: mix_rows16_t(a, 5); break;
    default: mix_rows16_t(a, a->m->hidden); break;
  }
}
#endif

/* ---- per-ISA entry points ---- */

typedef struct fast_isa {
  const char *name;
  void (*conv)(const conv_a *);
  void (*mix)(const mix_a *);
  void (*wino)(const wino_a *, uint32_t oblk);  /* NULL: direct kernel layer only */
  void (*wino4)(const wino4_a *, uint32_t oblk); /* NULL: no F(4x4, 5x5) */
} fast_isa;

#if FAST_X86
TGT_V4 static void conv_v4(const conv_a *a) { conv_rows16_dispatch(a); }
TGT_V4 static void mix_v4(const mix_a *a) { mix16_dispatch(a); }
TGT_V4 static void wino_v4(const wino_a *a, uint32_t oblk) { wino_dispatch(a, oblk, 1); }
TGT_V4 static void wino4_v4(const wino4_a *a, uint32_t oblk) { wino4_dispatch16(a, oblk); }
TGT_V3 static void conv_v3(const conv_a *a) { conv_rows_dispatch(a, 0); }
TGT_V3 static void mix_v3(const mix_a *a) { mix_dispatch(a); }
TGT_V3 static void wino_v3(const wino_a *a, uint32_t oblk) { wino_dispatch(a, oblk, 0); }
TGT_V3 static void wino4_v3(const wino4_a *a, uint32_t oblk) { wino4_dispatch(a, oblk, 0); }
#endif
static void conv_generic(const conv_a *a) { conv_rows_dispatch(a, 0); }
static void mix_generic(const mix_a *a) { mix_dispatch(a); }

static const fast_isa *fast_pick(void) {
  static const fast_isa generic = {"generic", conv_generic, mix_generic, NULL, NULL};
#if FAST_X86
  static const fast_isa v4 = {"avx512", conv_v4, mix_v4, wino_v4, wino4_v4},
                        v3 = {"avx2", conv_v3, mix_v3, wino_v3, wino4_v3};
  const char *force = getenv("TT_POST_TAA_ISA");
  __builtin_cpu_init();
  int has_v3 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  int has_v4 = has_v3 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  if (force && !strcmp(force, "generic")) return &generic;
  if (force && !strcmp(force, "avx2")) return has_v3 ? &v3 : &generic;
  return has_v4 ? &v4 : has_v3 ? &v3 : &generic;
#else
  return &generic;
#endif
}

const char *tt__net_fast_isa(void) { return fast_pick()->name; }

/* ---- stage 1: input planes ---- */

typedef struct in_job {
  tt__net_state *s;
  const tt__net_model *m;
  const float *color, *depth, *motion;
  uint8_t *reject;          /* rejection mask (written here), or NULL (no rejection input) */
  const float *dprev, *zprev;  /* previous depth and prevdepth for the tests, or NULL */
  float jx, jy, pjx, pjy;
  float depth_scale;
} in_job;

/* Catmull-Rom fetch of an 8-channel image (one vector per tap); same weights and order as
 * tt__taa_sample_catmull_rom. */
AI v8f fast_cr8(const float *img, uint32_t width, uint32_t height, float fx, float fy) {
  float ux = fx - 0.5f, uy = fy - 0.5f;
  float bx = floorf(ux), by = floorf(uy);
  float wx[4], wy[4];
  tt__taa_cr_weights(ux - bx, wx);
  tt__taa_cr_weights(uy - by, wy);
  int x0 = (int)bx - 1, y0 = (int)by - 1, w = (int)width, h = (int)height;
  int xi[4];
  for (int i = 0; i < 4; i++) {
    int v = x0 + i;
    xi[i] = v < 0 ? 0 : (v >= w ? w - 1 : v);
  }
  v8f acc = vsplat(0.0f);
  for (int j = 0; j < 4; j++) {
    int yy = y0 + j;
    yy = yy < 0 ? 0 : (yy >= h ? h - 1 : yy);
    const float *row = img + (size_t)yy * width * 8;
    for (int i = 0; i < 4; i++) acc += vload(row + (size_t)xi[i] * 8) * (wx[i] * wy[j]);
  }
  return acc;
}

/* The same for C channels known at compile time (scalar taps, unrolled; C = 3 + hidden). */
AI void fast_crc(const float *img, uint32_t width, uint32_t height, float fx, float fy,
                 const int C, float *out) {
  float ux = fx - 0.5f, uy = fy - 0.5f;
  float bx = floorf(ux), by = floorf(uy);
  float wx[4], wy[4];
  tt__taa_cr_weights(ux - bx, wx);
  tt__taa_cr_weights(uy - by, wy);
  int x0 = (int)bx - 1, y0 = (int)by - 1, w = (int)width, h = (int)height;
  int xi[4];
  for (int i = 0; i < 4; i++) {
    int v = x0 + i;
    xi[i] = v < 0 ? 0 : (v >= w ? w - 1 : v);
  }
  float acc[11];
#pragma GCC unroll 11
  for (int c = 0; c < C; c++) acc[c] = 0.0f;
#pragma GCC unroll 4
  for (int j = 0; j < 4; j++) {
    int yy = y0 + j;
    yy = yy < 0 ? 0 : (yy >= h ? h - 1 : yy);
    const float *row = img + (size_t)yy * width * C;
#pragma GCC unroll 4
    for (int i = 0; i < 4; i++) {
      const float *p = row + (size_t)xi[i] * C;
      float wt = wx[i] * wy[j];
#pragma GCC unroll 11
      for (int c = 0; c < C; c++) acc[c] += wt * p[c];
    }
  }
#pragma GCC unroll 11
  for (int c = 0; c < C; c++) out[c] = acc[c];
}

/* Input planes of pixel (x, y): tonemap, motion, depth, the reprojected state (the new
 * frame and hidden 0 on a fresh start), the rejection test (its bits into job->reject)
 * and input channel. `base`: channel 0 of the row in the planes. */
AI void input_pixel(const in_job *job, uint32_t x, uint32_t y, float *base) {
  tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  uint32_t w = s->width, sc = s->state_ch, nch = 6 + sc;
  size_t cs = s->inp_cs, i = (size_t)y * w + x;
  float fb[16];
  float t[3];
  tt__taa_tonemap_inl(job->color + 3 * i, t);
  float mx = job->motion ? job->motion[2 * i] : 0.0f;
  float my = job->motion ? job->motion[2 * i + 1] : 0.0f;
  uint8_t rj = 0;
  if (job->reject) {
    /* RAW (the input channel) needs only this pixel; RESET (the opening) is added and
     * applied after the pass (fast_reject_reset) */
    rj = !s->valid ? (uint8_t)(TT__TAA_REJECT_RAW | TT__TAA_REJECT_RESET)
                   : tt__taa_reject_test(job->dprev, w, s->height, job->pjx, job->pjy,
                                         job->zprev ? job->zprev[i] : 0.0f, x, y, mx, my,
                                         job->jx, job->jy);
    job->reject[i] = rj;
  }
  if (s->valid) {
    /* Motion points from this frame back to the previous one (film.h). */
    float fx = (float)x + 0.5f + mx, fy = (float)y + 0.5f + my;
    switch (sc) {
      case 8: {
        v8f v = fast_cr8(s->state, w, s->height, fx, fy);
        memcpy(fb, &v, sizeof v);
        break;
      }
      case 3: fast_crc(s->state, w, s->height, fx, fy, 3, fb); break;
      case 4: fast_crc(s->state, w, s->height, fx, fy, 4, fb); break;
      case 6: fast_crc(s->state, w, s->height, fx, fy, 6, fb); break;
      default: tt__taa_sample_catmull_rom(s->state, w, s->height, sc, fx, fy, fb); break;
    }
  } else {
    memset(fb, 0, sizeof fb);
    memcpy(fb, t, sizeof t);
  }
  float v[6 + 16 + 1];
  v[0] = t[0];
  v[1] = t[1];
  v[2] = t[2];
  v[3] = mx * m->motion_scale;
  v[4] = my * m->motion_scale;
  v[5] = job->depth ? job->depth[i] * job->depth_scale : 0.0f;
  memcpy(v + 6, fb, sc * sizeof(float));
  if (job->reject) v[nch] = (rj & TT__TAA_REJECT_RAW) ? 1.0f : 0.0f;
  uint32_t nin = nch + (job->reject ? 1u : 0u);
  for (uint32_t c = 0; c < nin; c++) base[c * cs + x] = v[c];
}

AI void input_rows_t(const in_job *job, uint32_t y0, uint32_t y1) {
  const tt__net_state *s = job->s;
  for (uint32_t y = y0; y < y1; y++) {
    float *base = s->inp + (size_t)(y + s->halo) * s->inp_ys + COL;
    for (uint32_t x = 0; x < s->width; x++) input_pixel(job, x, y, base);
  }
}

#if FAST_X86
/* 8 pixels x .. x + 7 of row y at once (AVX2 gathers), for a state of SC = 3 (hidden 0) or
 * 8 (hidden 5) channels: the same steps as input_pixel. The Catmull-Rom weights may round
 * differently from the scalar code in the last bit (a pixel always takes the same path,
 * whatever the threads); the rejection test uses the same float operations as
 * tt__taa_reject_test, bit for bit. */
TGT_V3 static inline __attribute__((always_inline)) void input8_t(const in_job *job,
                                                                  uint32_t x, uint32_t y,
                                                                  float *base, const int SC) {
  const tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  const int w = (int)s->width, h = (int)s->height;
  const size_t cs = s->inp_cs, i = (size_t)y * (size_t)w + x;
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), half = _mm256_set1_ps(0.5f);
  const __m256i i3 = _mm256_mullo_epi32(lane, _mm256_set1_epi32(3));
  const __m256i i2 = _mm256_add_epi32(lane, lane);
  const float *cp = job->color + 3 * i;
  __m256 c[3];
  for (int k = 0; k < 3; k++) c[k] = _mm256_i32gather_ps(cp + k, i3, 4);
  __m256 mxm = _mm256_max_ps(_mm256_max_ps(c[0], c[1]), _mm256_max_ps(c[2], zero));
  __m256 sc = _mm256_div_ps(one, _mm256_add_ps(one, mxm));
  __m256 t[3];
  for (int k = 0; k < 3; k++) t[k] = _mm256_mul_ps(_mm256_max_ps(c[k], zero), sc);
  __m256 mx = zero, my = zero;
  if (job->motion) {
    mx = _mm256_i32gather_ps(job->motion + 2 * i, i2, 4);
    my = _mm256_i32gather_ps(job->motion + 2 * i + 1, i2, 4);
  }
  __m256 dep = job->depth ? _mm256_mul_ps(_mm256_loadu_ps(job->depth + i),
                                          _mm256_set1_ps(job->depth_scale))
                          : zero;
  const __m256 xf = _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32((int)x), lane));
  const __m256 yf = _mm256_set1_ps((float)y);
  __m256 raw = zero;
  if (job->reject) {
    if (!s->valid) {
      memset(job->reject + i, TT__TAA_REJECT_RAW | TT__TAA_REJECT_RESET, 8);
      raw = one;
    } else {
      __m256 qx = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(xf, half), _mm256_set1_ps(job->jx)), mx);
      __m256 qy = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(yf, half), _mm256_set1_ps(job->jy)), my);
      __m256 in = _mm256_and_ps(
          _mm256_and_ps(_mm256_cmp_ps(qx, zero, _CMP_GE_OQ),
                        _mm256_cmp_ps(qx, _mm256_set1_ps((float)w), _CMP_LT_OQ)),
          _mm256_and_ps(_mm256_cmp_ps(qy, zero, _CMP_GE_OQ),
                        _mm256_cmp_ps(qy, _mm256_set1_ps((float)h), _CMP_LT_OQ)));
      __m256 far = zero;
      if (job->dprev) {
        __m256 ux = _mm256_sub_ps(_mm256_sub_ps(qx, half), _mm256_set1_ps(job->pjx));
        __m256 uy = _mm256_sub_ps(_mm256_sub_ps(qy, half), _mm256_set1_ps(job->pjy));
        /* off-screen lanes: any index (clamped below), their result is dropped */
        ux = _mm256_and_ps(ux, in), uy = _mm256_and_ps(uy, in);
        __m256i ix = _mm256_cvttps_epi32(_mm256_floor_ps(ux));
        __m256i iy = _mm256_cvttps_epi32(_mm256_floor_ps(uy));
        const __m256i z = _mm256_setzero_si256(), wm = _mm256_set1_epi32(w - 1),
                      hm = _mm256_set1_epi32(h - 1), o1 = _mm256_set1_epi32(1);
        __m256i x0 = _mm256_min_epi32(_mm256_max_epi32(ix, z), wm);
        __m256i x1 = _mm256_min_epi32(_mm256_max_epi32(_mm256_add_epi32(ix, o1), z), wm);
        __m256i y0 = _mm256_mullo_epi32(_mm256_min_epi32(_mm256_max_epi32(iy, z), hm),
                                        _mm256_set1_epi32(w));
        __m256i y1 = _mm256_mullo_epi32(
            _mm256_min_epi32(_mm256_max_epi32(_mm256_add_epi32(iy, o1), z), hm),
            _mm256_set1_epi32(w));
        __m256 d[4] = {_mm256_i32gather_ps(job->dprev, _mm256_add_epi32(y0, x0), 4),
                       _mm256_i32gather_ps(job->dprev, _mm256_add_epi32(y0, x1), 4),
                       _mm256_i32gather_ps(job->dprev, _mm256_add_epi32(y1, x0), 4),
                       _mm256_i32gather_ps(job->dprev, _mm256_add_epi32(y1, x1), 4)};
        __m256 hi = _mm256_set1_ps(-__builtin_inff()), sky = zero;
        for (int k = 0; k < 4; k++) {
          __m256 pos = _mm256_cmp_ps(d[k], zero, _CMP_GT_OQ);
          hi = _mm256_blendv_ps(hi, _mm256_max_ps(d[k], hi), pos);
          sky = _mm256_or_ps(sky, _mm256_xor_ps(pos, _mm256_castsi256_ps(_mm256_set1_epi32(-1))));
        }
        __m256 zp = job->zprev ? _mm256_loadu_ps(job->zprev + i) : zero;
        __m256 thr = _mm256_mul_ps(hi, _mm256_set1_ps(1.0f + TT__TAA_REJECT_TOL));
        __m256 test = _mm256_or_ps(_mm256_cmp_ps(zp, zero, _CMP_NGT_UQ),
                                   _mm256_cmp_ps(zp, thr, _CMP_GT_OQ));
        far = _mm256_and_ps(_mm256_andnot_ps(sky, test), in);
      }
      int offm = ~_mm256_movemask_ps(in) & 0xff, farm = _mm256_movemask_ps(far);
      for (int l = 0; l < 8; l++)
        job->reject[i + (size_t)l] =
            (uint8_t)((offm >> l) & 1 ? TT__TAA_REJECT_RAW | TT__TAA_REJECT_OFF
                      : (farm >> l) & 1 ? TT__TAA_REJECT_RAW | TT__TAA_REJECT_FAR : 0u);
      raw = _mm256_and_ps(_mm256_or_ps(_mm256_xor_ps(in, _mm256_castsi256_ps(_mm256_set1_epi32(-1))), far), one);
    }
  }
  __m256 fb[8] = {t[0], t[1], t[2], zero, zero, zero, zero, zero};
  if (s->valid) {
    __m256 ux = _mm256_sub_ps(_mm256_add_ps(_mm256_add_ps(xf, half), mx), half);
    __m256 uy = _mm256_sub_ps(_mm256_add_ps(_mm256_add_ps(yf, half), my), half);
    __m256 bx = _mm256_floor_ps(ux), by = _mm256_floor_ps(uy);
    __m256 fxr = _mm256_sub_ps(ux, bx), fyr = _mm256_sub_ps(uy, by);
    __m256 wx[4], wy[4];
    for (int a = 0; a < 2; a++) {
      __m256 f = a ? fyr : fxr, *o = a ? wy : wx;
      o[0] = _mm256_mul_ps(f, _mm256_fmadd_ps(f, _mm256_fnmadd_ps(half, f, one), _mm256_set1_ps(-0.5f)));
      o[1] = _mm256_fmadd_ps(_mm256_mul_ps(f, f), _mm256_fmadd_ps(_mm256_set1_ps(1.5f), f, _mm256_set1_ps(-2.5f)), one);
      o[2] = _mm256_mul_ps(f, _mm256_fmadd_ps(f, _mm256_fnmadd_ps(_mm256_set1_ps(1.5f), f, _mm256_set1_ps(2.0f)), half));
      o[3] = _mm256_mul_ps(_mm256_mul_ps(f, f), _mm256_fmadd_ps(half, f, _mm256_set1_ps(-0.5f)));
    }
    /* Per pixel: rows of taps weighted by wx, then the rows by wy. bx, by: floors of
     * finite positions (huge motion still gives clamped taps). */
    const __m256i z = _mm256_setzero_si256(), wm = _mm256_set1_epi32(w - 1),
                  hm = _mm256_set1_epi32(h - 1);
    __m256i bxi = _mm256_cvttps_epi32(bx), byi = _mm256_cvttps_epi32(by);
    int xi[4][8], yo[4][8];
    float wxs[4][8], wys[4][8];
    for (int k = 0; k < 4; k++) {
      __m256i o = _mm256_set1_epi32(k - 1);
      _mm256_storeu_si256((__m256i *)xi[k], _mm256_mullo_epi32(
          _mm256_min_epi32(_mm256_max_epi32(_mm256_add_epi32(bxi, o), z), wm), _mm256_set1_epi32(SC)));
      _mm256_storeu_si256((__m256i *)yo[k], _mm256_mullo_epi32(
          _mm256_min_epi32(_mm256_max_epi32(_mm256_add_epi32(byi, o), z), hm), _mm256_set1_epi32(SC * w)));
      _mm256_storeu_ps(wxs[k], wx[k]);
      _mm256_storeu_ps(wys[k], wy[k]);
    }
    if (SC == 8) {
      /* one 8-float vector per tap (all state channels), then the 8 x 8 transpose */
      v8f px[8];
      for (int l = 0; l < 8; l++) {
        __m256 acc = _mm256_setzero_ps();
        for (int j = 0; j < 4; j++) {
          const float *row = s->state + yo[j][l];
          __m256 r = _mm256_mul_ps(_mm256_loadu_ps(row + xi[0][l]), _mm256_set1_ps(wxs[0][l]));
          r = _mm256_fmadd_ps(_mm256_loadu_ps(row + xi[1][l]), _mm256_set1_ps(wxs[1][l]), r);
          r = _mm256_fmadd_ps(_mm256_loadu_ps(row + xi[2][l]), _mm256_set1_ps(wxs[2][l]), r);
          r = _mm256_fmadd_ps(_mm256_loadu_ps(row + xi[3][l]), _mm256_set1_ps(wxs[3][l]), r);
          acc = _mm256_fmadd_ps(r, _mm256_set1_ps(wys[j][l]), acc);
        }
        px[l] = acc;
      }
      v8f ch[8];
      t8x8(px, ch);
      for (int k = 0; k < 8; k++) fb[k] = ch[k];
    } else {
      /* each tap's 3 channels as one 4-float load (the 4th, the next pixel's red, is
       * unused) */
      __m128 px[8];
      for (int l = 0; l < 8; l++) {
        __m128 acc = _mm_setzero_ps();
        for (int j = 0; j < 4; j++) {
          const float *row = s->state + yo[j][l];
          __m128 r = _mm_mul_ps(_mm_loadu_ps(row + xi[0][l]), _mm_set1_ps(wxs[0][l]));
          r = _mm_fmadd_ps(_mm_loadu_ps(row + xi[1][l]), _mm_set1_ps(wxs[1][l]), r);
          r = _mm_fmadd_ps(_mm_loadu_ps(row + xi[2][l]), _mm_set1_ps(wxs[2][l]), r);
          r = _mm_fmadd_ps(_mm_loadu_ps(row + xi[3][l]), _mm_set1_ps(wxs[3][l]), r);
          acc = _mm_fmadd_ps(r, _mm_set1_ps(wys[j][l]), acc);
        }
        px[l] = acc;
      }
      /* [r g b -] of pixels l and l + 4 in the two halves, then a 4 x 4 transpose per half */
      __m256 q0 = _mm256_set_m128(px[4], px[0]), q1 = _mm256_set_m128(px[5], px[1]),
             q2 = _mm256_set_m128(px[6], px[2]), q3 = _mm256_set_m128(px[7], px[3]);
      __m256 t0 = _mm256_unpacklo_ps(q0, q1), t1 = _mm256_unpackhi_ps(q0, q1);
      __m256 t2 = _mm256_unpacklo_ps(q2, q3), t3 = _mm256_unpackhi_ps(q2, q3);
      fb[0] = _mm256_shuffle_ps(t0, t2, 0x44);
      fb[1] = _mm256_shuffle_ps(t0, t2, 0xEE);
      fb[2] = _mm256_shuffle_ps(t1, t3, 0x44);
    }
  }
  const __m256 ms = _mm256_set1_ps(m->motion_scale);
  __m256 v[6] = {t[0], t[1], t[2], _mm256_mul_ps(mx, ms), _mm256_mul_ps(my, ms), dep};
  for (int k = 0; k < 6; k++) _mm256_storeu_ps(base + (size_t)k * cs + x, v[k]);
  for (int k = 0; k < SC; k++) _mm256_storeu_ps(base + (size_t)(6 + k) * cs + x, fb[k]);
  if (job->reject) _mm256_storeu_ps(base + (size_t)(6 + SC) * cs + x, raw);
}

/* Rows with a 3- or 8-channel state: groups of 8 pixels by AVX2, the rest pixel by pixel. */
TGT_V3 AI void input_rows8_t(const in_job *job, uint32_t y0, uint32_t y1, const int SC) {
  const tt__net_state *s = job->s;
  for (uint32_t y = y0; y < y1; y++) {
    float *base = s->inp + (size_t)(y + s->halo) * s->inp_ys + COL;
    uint32_t x = 0;
    for (; x + 8 <= s->width; x += 8) input8_t(job, x, y, base, SC);
    for (; x < s->width; x++) input_pixel(job, x, y, base);
  }
}
TGT_V3 static void input_rows_sc3_v3(void *ctx, uint32_t y0, uint32_t y1) {
  input_rows8_t(ctx, y0, y1, 3);
}
TGT_V3 static void input_rows_sc8_v3(void *ctx, uint32_t y0, uint32_t y1) {
  input_rows8_t(ctx, y0, y1, 8);
}

TGT_V3 static void input_rows_v3(void *ctx, uint32_t y0, uint32_t y1) {
  input_rows_t(ctx, y0, y1);
}
#endif
static void input_rows_generic(void *ctx, uint32_t y0, uint32_t y1) {
  input_rows_t(ctx, y0, y1);
}

/* History reset (models with TT__NET_FLAG_RESET): after the reprojection pass wrote the
 * test bits, the opening marks RESET and the reprojected state of those pixels becomes the
 * fresh-start state (tonemapped colour, hidden 0), as the reference path fetches it. */
static void fast_reject_reset(tt__net_state *s, const tt__net_model *m) {
  size_t n = (size_t)s->width * s->height, cs = s->inp_cs;
  tt__taa_reject_open(s->width, s->height, s->reject, s->reject + n);
  for (uint32_t y = 0; y < s->height; y++) {
    const uint8_t *r = s->reject + (size_t)y * s->width;
    float *base = s->inp + (size_t)(y + s->halo) * s->inp_ys + COL;
    for (uint32_t x = 0; x < s->width; x++) {
      if (!(r[x] & TT__TAA_REJECT_RESET)) continue;
      for (uint32_t c = 0; c < 3; c++) base[(6 + c) * cs + x] = base[c * cs + x];
      for (uint32_t c = 0; c < m->hidden; c++) base[(9 + c) * cs + x] = 0.0f;
    }
  }
}

/* ---- stage 2: bands ---- */

typedef struct band_job {
  tt__net_state *s;
  const tt__net_model *m;
  const fast_isa *isa;
  uint32_t set, band_rows, bands;
  uint32_t tile_cols, tiles, margin;  /* column tiles: output columns per tile, count, and
                                       * the extra columns each side the body layers cover */
  uint32_t lw, rrs;                   /* ring row: columns computed, stride */
  float *out_rgb;
  size_t ring_off[TT__NET_MAX_LAYERS], logits_off;
  int wino;                           /* tt__net_state.winograd this frame (0 on the
                                       * portable path): 5x5 body layers after the first in
                                       * row pairs (1) or quads (2) */
  int kwino;                          /* kernel layer by Winograd: 2 F(2x2, 5x5) rows in
                                       * even pairs, 4 F(4x4, 5x5) rows in quads; 0 direct */
  size_t vbuf_off, mbuf_off, ebuf_off; /* Winograd scratch */
} band_job;

/* Per-thread scratch header: accumulated ns of the stage's parts. */
typedef struct band_times {
  double body_ns, kernel_ns, mix_ns;
} band_times;
#define SCRATCH_HEADER 64u

/* One band's ring buffers and progress. */
typedef struct band_ctx {
  const band_job *job;
  unsigned char *scr;
  band_times *tm;
  float *ring[TT__NET_MAX_LAYERS];
  uint32_t rlen[TT__NET_MAX_LAYERS];
  int next[TT__NET_MAX_LAYERS];
  int bx;             /* image column of ring column 0 */
  uint32_t tx0, tx1;  /* the tile's output columns */
} band_ctx;

static double fast_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1e9 + ts.tv_nsec;
}

/* Ring slot of row y (y may be negative). */
static inline float *ring_row(const band_ctx *b, uint32_t l, int y) {
  int R = (int)b->rlen[l];
  int k = ((y % R) + R) % R;
  return b->ring[l] + (size_t)k * b->job->rrs;
}

/* Body layer l can run as Winograd row pairs (5x5 with transformed weights, reading a
 * ring: not the first layer). */
static inline int body_wino_ok(const tt__net_model *m, uint32_t l) {
  return l >= 1 && l < m->body_count && m->body[l].wino != NULL;
}

/* The same for F(4x4, 5x5) row quads. */
static inline int body_wino4_ok(const tt__net_model *m, uint32_t l) {
  return l >= 1 && l < m->body_count && m->body[l].wino4 != NULL;
}

/* Rows body layer l (or, l == body_count, the kernel layer) produces at once with the
 * most capable algorithm: 4 (F(4x4, 5x5)), 2 (F(2x2, 5x5)) or 1. */
static uint32_t max_step(const tt__net_model *m, uint32_t l) {
  if (l >= m->body_count) return m->kernel.wino4 ? 4u : m->kernel.wino ? 2u : 1u;
  return body_wino4_ok(m, l) ? 4u : body_wino_ok(m, l) ? 2u : 1u;
}

/* Rows in the ring of body layer l: what its consumer reads (the next body layer's or the
 * kernel layer's kernel size), one more when Winograd row pairs write or read it. The same
 * for both algorithms, so switching between frames keeps the scratch layout. */
static uint32_t ring_len(const tt__net_model *m, uint32_t l) {
  int last = l + 1 >= m->body_count;
  uint32_t k = last ? m->kernel.ksize : m->body[l + 1].ksize;
  (void)last;
  /* the consumer's step S_c reads k + S_c - 1 rows; this layer, producing S_l rows at a
   * time, may be up to S_l - 1 rows ahead */
  return k + (max_step(m, l + 1) - 1u) + (max_step(m, l) - 1u);
}

/* Layer index of a set: the jitter set for 8-set layers. */
static inline uint32_t set_of(const tt__net_layer *l, uint32_t set) {
  return l->sets > 1 ? set : 0;
}

/* Input row pointers of layer l (0: the input planes; else the previous ring) for output
 * row y; returns the channel stride. *col0: image column of the rows' column 0. */
static size_t layer_rows(const band_ctx *b, uint32_t l, uint32_t ksize, int y,
                         const float **rowp, int *col0) {
  const tt__net_state *s = b->job->s;
  int r = (int)ksize / 2;
  if (l == 0) {
    for (int ky = 0; ky < (int)ksize; ky++)
      rowp[ky] = s->inp + (size_t)(y + ky - r + (int)s->halo) * s->inp_ys;
    *col0 = 0;
    return s->inp_cs;
  }
  for (int ky = 0; ky < (int)ksize; ky++) rowp[ky] = ring_row(b, l - 1, y + ky - r);
  *col0 = b->bx;
  return (size_t)b->rlen[l - 1] * b->job->rrs;
}

/* Image columns [*xs, *xe) of the band's ring rows [bx, bx + lw); the rest is zero padding
 * (left of the image, right of it) and must read as 0 in the next layer. */
static void band_image_cols(const band_ctx *b, int *xs, int *xe) {
  int bx = b->bx, lw = (int)b->job->lw, vw = (int)b->job->s->vw;
  *xs = bx > 0 ? bx : 0;
  *xe = bx + lw < vw ? bx + lw : vw;
}

/* Zeroes the padding columns of one ring row (`out` channels `dcs` apart), given xs of
 * band_image_cols. */
static void zero_pad_cols(const band_ctx *b, float *dst, size_t dcs, uint32_t out, int xs) {
  int bx = b->bx, lw = (int)b->job->lw, w = (int)b->job->s->width;
  int zr = w > xs ? w : xs;  /* first column right of the image */
  for (uint32_t c = 0; c < out; c++) {
    float *d = dst + c * dcs + COL;
    if (xs > bx) memset(d, 0, (size_t)(xs - bx) * sizeof(float));
    if (zr < bx + lw) memset(d + (zr - bx), 0, (size_t)(bx + lw - zr) * sizeof(float));
  }
}

/* Computes row y of body layer l into its ring (zeros outside the image). */
static void body_row(band_ctx *b, uint32_t l, int y) {
  const band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_layer *ly = &job->m->body[l];
  float *dst = ring_row(b, l, y);
  size_t rrs = job->rrs, dcs = (size_t)b->rlen[l] * rrs;
  if (y < 0 || y >= (int)s->height) {
    for (uint32_t c = 0; c < ly->out; c++) memset(dst + c * dcs, 0, rrs * sizeof(float));
    return;
  }
  double t0 = fast_ns();
  conv_a a;
  int col0;
  a.cs = layer_rows(b, l, ly->ksize, y, a.rowp, &col0);
  a.in = ly->in;
  a.ksize = ly->ksize;
  a.oblk = ly->oblk;
  a.nob = ly->nob;
  a.out = ly->out;
  uint32_t st = set_of(ly, job->set);
  a.w = ly->wq + (size_t)st * ly->nob * ly->oblk * ly->in * ly->ksize * ly->ksize;
  a.b = ly->bq + (size_t)st * ly->nob * ly->oblk;
  a.dcs = dcs;
  a.relu = 1;
  a.pf = l == 0 && s->prefetch ? s->inp_ys : 0;
  int xs, xe;
  band_image_cols(b, &xs, &xe);
  for (int x0 = xs; x0 < xe; x0 += (int)CHUNK) {
    a.x0 = (uint32_t)(x0 - col0);
    a.n = xe - x0 < (int)CHUNK ? (uint32_t)(xe - x0) : CHUNK;
    a.dst = dst + COL + (x0 - b->bx);
    job->isa->conv(&a);
  }
  zero_pad_cols(b, dst, dcs, ly->out, xs);
  b->tm->body_ns += fast_ns() - t0;
}

/* Rows q, q + 1 (q even) of 5x5 body layer l >= 1 by Winograd into its ring (zeros
 * outside the image). */
static void body_pair(band_ctx *b, uint32_t l, int q) {
  const band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_layer *ly = &job->m->body[l];
  size_t rrs = job->rrs, dcs = (size_t)b->rlen[l] * rrs;
  float *dst[2] = {ring_row(b, l, q), ring_row(b, l, q + 1)};
  int h = (int)s->height, inside[2] = {q >= 0 && q < h, q + 1 >= 0 && q + 1 < h};
  if (inside[0] || inside[1]) {
    double t0 = fast_ns();
    wino_a a;
    for (int i = 0; i < 6; i++) a.rowp[i] = ring_row(b, l - 1, q - 2 + i);
    a.cs = (size_t)b->rlen[l - 1] * rrs;
    a.in = ly->in;
    a.nob = ly->nob;
    a.out = ly->out;
    uint32_t st = set_of(ly, job->set);
    a.u = ly->wino + (size_t)st * ly->nob * WINO_POS * ly->in * ly->oblk;
    a.b = ly->bq + (size_t)st * ly->nob * ly->oblk;
    a.dcs = dcs;
    a.relu = 1;
    a.vbuf = (float *)(b->scr + job->vbuf_off);
    a.mbuf = (float *)(b->scr + job->mbuf_off);
    int bx = b->bx, xs, xe;
    band_image_cols(b, &xs, &xe);
    for (int x0 = xs; x0 < xe; x0 += (int)CHUNK) {
      a.x0 = (uint32_t)(x0 - bx);
      a.n = xe - x0 < (int)CHUNK ? (uint32_t)(xe - x0) : CHUNK;
      a.dst[0] = dst[0] + COL + (x0 - bx);
      a.dst[1] = dst[1] + COL + (x0 - bx);
      job->isa->wino(&a, ly->oblk);
    }
    for (int r = 0; r < 2; r++) zero_pad_cols(b, dst[r], dcs, ly->out, xs);
    b->tm->body_ns += fast_ns() - t0;
  }
  for (int r = 0; r < 2; r++)
    if (!inside[r])
      for (uint32_t c = 0; c < ly->out; c++) memset(dst[r] + c * dcs, 0, rrs * sizeof(float));
}

#if FAST_X86
/* Rows q .. q + 3 (q a multiple of 4) of 5x5 body layer l >= 1 by F(4x4, 5x5) into its
 * ring (zeros outside the image). */
static void body_quad(band_ctx *b, uint32_t l, int q) {
  const band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_layer *ly = &job->m->body[l];
  size_t rrs = job->rrs, dcs = (size_t)b->rlen[l] * rrs;
  float *dst[4];
  int h = (int)s->height, inside[4], any = 0;
  for (int r = 0; r < 4; r++) {
    dst[r] = ring_row(b, l, q + r);
    inside[r] = q + r >= 0 && q + r < h;
    any |= inside[r];
  }
  if (any) {
    double t0 = fast_ns();
    wino4_a a;
    for (int i = 0; i < 8; i++) a.rowp[i] = ring_row(b, l - 1, q - 2 + i);
    a.cs = (size_t)b->rlen[l - 1] * rrs;
    a.in = ly->in;
    a.nob = ly->nob;
    a.out = ly->out;
    uint32_t st = set_of(ly, job->set);
    a.u = ly->wino4 + (size_t)st * ly->nob * WINO4_POS * ly->in * ly->oblk;
    a.b = ly->bq + (size_t)st * ly->nob * ly->oblk;
    a.dcs = dcs;
    a.relu = 1;
    a.vbuf = (float *)(b->scr + job->vbuf_off);
    a.mbuf = (float *)(b->scr + job->mbuf_off);
    a.ebuf = (float *)(b->scr + job->ebuf_off);
    int bx = b->bx, xs, xe;
    band_image_cols(b, &xs, &xe);
    for (int x0 = xs; x0 < xe; x0 += (int)CHUNK) {
      a.x0 = (uint32_t)(x0 - bx);
      a.n = xe - x0 < (int)CHUNK ? (uint32_t)(xe - x0) : CHUNK;
      for (int r = 0; r < 4; r++) a.dst[r] = dst[r] + COL + (x0 - bx);
      job->isa->wino4(&a, ly->oblk);
    }
    for (int r = 0; r < 4; r++) zero_pad_cols(b, dst[r], dcs, ly->out, xs);
    b->tm->body_ns += fast_ns() - t0;
  }
  for (int r = 0; r < 4; r++)
    if (!inside[r])
      for (uint32_t c = 0; c < ly->out; c++) memset(dst[r] + c * dcs, 0, rrs * sizeof(float));
}
#endif

/* Rows body layer l computes at once this frame: 4 (F(4x4, 5x5)), 2 (F(2x2, 5x5)) or 1. */
static inline int body_step(const band_job *job, uint32_t l) {
  if (job->wino >= 2 && job->isa->wino4 && body_wino4_ok(job->m, l)) return 4;
  return job->wino && body_wino_ok(job->m, l) ? 2 : 1;
}

/* Makes body layer l hold rows up to y (computing the inputs first). */
static void ensure_rows(band_ctx *b, uint32_t l, int y) {
  int step = body_step(b->job, l);
  while (b->next[l] <= y) {
    int yy = b->next[l];
    if (l > 0) ensure_rows(b, l - 1, yy + step - 1 + (int)b->job->m->body[l].ksize / 2);
#if FAST_X86
    if (step == 4) body_quad(b, l, yy);
    else
#endif
    if (step == 2) body_pair(b, l, yy);
    else body_row(b, l, yy);
    b->next[l] += step;
  }
}

/* The colour-mix arguments shared by every row of a band (the hidden layer's weight set,
 * the ring of the last body layer, the output image). */
static void mix_setup(const band_ctx *b, mix_a *mx) {
  const band_job *job = b->job;
  const tt__net_model *m = job->m;
  uint32_t last = m->body_count - 1;
  mx->s = job->s;
  mx->m = m;
  mx->hcs = (size_t)b->rlen[last] * job->rrs;
  mx->hx = b->bx;
  uint32_t hs = set_of(&m->hid, job->set);
  mx->hw = m->hidden ? m->hid.w + (size_t)hs * m->hid.out * m->hid.in : NULL;
  mx->hb = m->hidden ? m->hid.b + (size_t)hs * m->hid.out : NULL;
  mx->out_rgb = job->out_rgb;
}

/* Kernel layer, softmax, colour mix, hidden layer and outputs of row y. */
static void head_row(band_ctx *b, int y) {
  const band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  const tt__net_layer *kl = &m->kernel;
  uint32_t last = m->body_count - 1;
  conv_a a;
  int col0;
  a.cs = layer_rows(b, m->body_count, kl->ksize, y, a.rowp, &col0);
  a.in = kl->in;
  a.ksize = kl->ksize;
  a.oblk = kl->oblk;
  a.nob = kl->nob;
  a.out = kl->out;
  uint32_t ks = set_of(kl, job->set);
  a.w = kl->wq + (size_t)ks * kl->nob * kl->oblk * kl->in * kl->ksize * kl->ksize;
  a.b = kl->bq + (size_t)ks * kl->nob * kl->oblk;
  a.dcs = CHUNK;
  a.relu = 0;
  a.pf = 0;
  a.dst = (float *)(b->scr + job->logits_off);
  mix_a mx;
  mix_setup(b, &mx);
  mx.lg = a.dst;
  mx.y = (uint32_t)y;
  mx.hrow = ring_row(b, last, y);
  for (uint32_t x0 = b->tx0; x0 < b->tx1 && x0 < s->width; x0 += CHUNK) {
    a.x0 = (uint32_t)((int)x0 - col0);
    mx.x0 = x0;
    a.n = mx.n = b->tx1 - x0 < CHUNK ? b->tx1 - x0 : CHUNK;
    double t0 = fast_ns();
    job->isa->conv(&a);
    double t1 = fast_ns();
    job->isa->mix(&mx);
    b->tm->kernel_ns += t1 - t0;
    b->tm->mix_ns += fast_ns() - t1;
  }
}

/* Winograd kernel layer of rows p, p + 1 (p even), then the head of those in [y0, y1). */
static void head_pair(band_ctx *b, int p, uint32_t y0, uint32_t y1) {
  const band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  const tt__net_layer *kl = &m->kernel;
  uint32_t last = m->body_count - 1;
  wino_a a;
  for (int i = 0; i < 6; i++) a.rowp[i] = ring_row(b, last, p - 2 + i);
  a.cs = (size_t)b->rlen[last] * job->rrs;
  int col0 = b->bx;
  a.in = kl->in;
  a.nob = kl->nob;
  a.out = kl->out;
  uint32_t ks = set_of(kl, job->set);
  a.u = kl->wino + (size_t)ks * kl->nob * WINO_POS * kl->in * kl->oblk;
  a.b = kl->bq + (size_t)ks * kl->nob * kl->oblk;
  float *lg = (float *)(b->scr + job->logits_off);
  size_t lgn = (size_t)kl->nob * kl->oblk * CHUNK;
  a.dst[0] = lg;
  a.dst[1] = lg + lgn;
  a.dcs = CHUNK;
  a.relu = 0;
  a.vbuf = (float *)(b->scr + job->vbuf_off);
  a.mbuf = (float *)(b->scr + job->mbuf_off);
  mix_a mx;
  mix_setup(b, &mx);
  for (uint32_t x0 = b->tx0; x0 < b->tx1 && x0 < s->width; x0 += CHUNK) {
    a.x0 = (uint32_t)((int)x0 - col0);
    mx.x0 = x0;
    a.n = mx.n = b->tx1 - x0 < CHUNK ? b->tx1 - x0 : CHUNK;
    double t0 = fast_ns();
    job->isa->wino(&a, kl->oblk);
    double t1 = fast_ns();
    for (int r = 0; r < 2; r++) {
      int y = p + r;
      if (y < (int)y0 || y >= (int)y1 || y >= (int)s->height) continue;
      mx.lg = a.dst[r];
      mx.y = (uint32_t)y;
      mx.hrow = ring_row(b, last, y);
      job->isa->mix(&mx);
    }
    b->tm->kernel_ns += t1 - t0;
    b->tm->mix_ns += fast_ns() - t1;
  }
}

#if FAST_X86
/* F(4x4, 5x5) kernel layer of rows p .. p + 3 (p a multiple of 4), then the head of those
 * in [y0, y1). */
static void head_quad(band_ctx *b, int p, uint32_t y0, uint32_t y1) {
  const band_job *job = b->job;
  const tt__net_state *s = job->s;
  const tt__net_model *m = job->m;
  const tt__net_layer *kl = &m->kernel;
  uint32_t last = m->body_count - 1;
  wino4_a a;
  for (int i = 0; i < 8; i++) a.rowp[i] = ring_row(b, last, p - 2 + i);
  a.cs = (size_t)b->rlen[last] * job->rrs;
  int col0 = b->bx;
  a.in = kl->in;
  a.nob = kl->nob;
  a.out = kl->out;
  uint32_t ks = set_of(kl, job->set);
  a.u = kl->wino4 + (size_t)ks * kl->nob * WINO4_POS * kl->in * kl->oblk;
  a.b = kl->bq + (size_t)ks * kl->nob * kl->oblk;
  float *lg = (float *)(b->scr + job->logits_off);
  size_t lgn = (size_t)kl->nob * kl->oblk * CHUNK;
  for (int r = 0; r < 4; r++) a.dst[r] = lg + r * lgn;
  a.dcs = CHUNK;
  a.relu = 0;
  a.vbuf = (float *)(b->scr + job->vbuf_off);
  a.mbuf = (float *)(b->scr + job->mbuf_off);
  a.ebuf = (float *)(b->scr + job->ebuf_off);
  mix_a mx;
  mix_setup(b, &mx);
  for (uint32_t x0 = b->tx0; x0 < b->tx1 && x0 < s->width; x0 += CHUNK) {
    a.x0 = (uint32_t)((int)x0 - col0);
    mx.x0 = x0;
    a.n = mx.n = b->tx1 - x0 < CHUNK ? b->tx1 - x0 : CHUNK;
    double t0 = fast_ns();
    job->isa->wino4(&a, kl->oblk);
    double t1 = fast_ns();
    for (int r = 0; r < 4; r++) {
      int y = p + r;
      if (y < (int)y0 || y >= (int)y1 || y >= (int)s->height) continue;
      mx.lg = a.dst[r];
      mx.y = (uint32_t)y;
      mx.hrow = ring_row(b, last, y);
      job->isa->mix(&mx);
    }
    b->tm->kernel_ns += t1 - t0;
    b->tm->mix_ns += fast_ns() - t1;
  }
}
#endif

/* Rows [y0, y1) of columns [tx0, tx1) through all layers. */
static void band_run(const band_job *job, uint32_t thread, uint32_t y0, uint32_t y1,
                     uint32_t tx0, uint32_t tx1) {
  band_ctx b;
  memset(&b, 0, sizeof b);
  b.job = job;
  b.tx0 = tx0;
  b.tx1 = tx1;
  b.bx = (int)tx0 - (int)job->margin;
  b.scr = (unsigned char *)job->s->scratch + (size_t)thread * job->s->scratch_bytes;
  b.tm = (band_times *)b.scr;
  const tt__net_model *m = job->m;
  int rk = (int)m->kernel.ksize / 2;
  /* First row of each layer, from the kernel layer back: the first row its consumer's
   * first step reads, rounded down to the layer's own step (pairs on even rows, quads on
   * multiples of 4). Every row a Winograd tile reads is then computed in this band: the
   * tile's transforms mix all of its input rows (exact only in exact arithmetic), so a
   * stale ring row would change its outputs in the last bits. */
  uint32_t ys = job->kwino == 4 ? y0 & ~3u : job->kwino ? y0 & ~1u : y0;
  int need = (int)ys - rk;
  for (uint32_t l = m->body_count; l-- > 0;) {
    b.ring[l] = (float *)(b.scr + job->ring_off[l]);
    b.rlen[l] = ring_len(m, l);
    int v = need & ~(body_step(job, l) - 1);
    b.next[l] = v;
    need = v - (int)m->body[l].ksize / 2;
  }
#if FAST_X86
  if (job->kwino == 4) {
    /* Row quads at absolute multiples of 4; a band starting or ending inside a quad
     * computes it whole and keeps its own rows. */
    for (int p = (int)(y0 & ~3u); p < (int)y1; p += 4) {
      ensure_rows(&b, m->body_count - 1, p + 3 + rk);
      head_quad(&b, p, y0, y1);
    }
    return;
  }
#endif
  if (job->kwino) {
    /* Row pairs at absolute even rows; a band starting or ending on an odd row computes
     * its first / last pair whole and keeps its own row. */
    for (int p = (int)(y0 & ~1u); p < (int)y1; p += 2) {
      ensure_rows(&b, m->body_count - 1, p + 1 + rk);
      head_pair(&b, p, y0, y1);
    }
    return;
  }
  for (int y = (int)y0; y < (int)y1; y++) {
    ensure_rows(&b, m->body_count - 1, y + rk);
    head_row(&b, y);
  }
}

static void band_body(void *ctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  const band_job *job = ctx;
  uint32_t h = job->s->height;
  if (thread_index >= job->s->scratch_threads) thread_index = 0;  /* not expected */
  for (uint64_t k = begin; k < end; k++) {
    uint32_t band = (uint32_t)(k / job->tiles), tile = (uint32_t)(k % job->tiles);
    uint32_t y0 = band * job->band_rows, y1 = y0 + job->band_rows;
    uint32_t x0 = tile * job->tile_cols, x1 = x0 + job->tile_cols;
    band_run(job, thread_index, y0, y1 < h ? y1 : h, x0, x1 < job->s->vw ? x1 : job->s->vw);
  }
}

/* Scratch layout for `threads` threads; (re)allocates when it grew. */
static tt_status fast_scratch(tt__net_state *s, const tt__net_model *m, band_job *job,
                              uint32_t threads) {
  /* Column tiles keep the ring buffers within ~512 KB (L2): a tile's body layers cover 16
   * more columns each side (>= the receptive field's 2..12), recomputed by both tiles. */
  size_t ring_ch = 0;
  for (uint32_t l = 0; l < m->body_count; l++) ring_ch += (size_t)m->body[l].out * ring_len(m, l);
  uint32_t cols = s->tile_cols;
  if (!cols) {
    size_t fit = (512u * 1024u) / (ring_ch * sizeof(float));
    cols = s->vw;
    if (fit < s->vw + 2 * COL) {
      uint32_t tiles = (uint32_t)((s->vw + fit - 1) / (fit > 128 ? fit - 64 : 64));
      cols = (s->vw + tiles - 1) / tiles;
    }
  }
  cols = (cols + 63) & ~63u;
  if (cols >= s->vw) cols = s->vw;
  job->tile_cols = cols;
  job->tiles = (s->vw + cols - 1) / cols;
  job->margin = job->tiles > 1 ? 16u : 0u;
  job->lw = cols + 2 * job->margin;
  job->rrs = job->lw + 2 * COL;
  size_t off = SCRATCH_HEADER;
  for (uint32_t l = 0; l < m->body_count; l++) {
    uint32_t R = ring_len(m, l);
    job->ring_off[l] = off;
    off += ((size_t)m->body[l].out * R * job->rrs * sizeof(float) + 63) & ~(size_t)63;
  }
  job->logits_off = off;
  off += 4 * (size_t)m->kernel.nob * m->kernel.oblk * CHUNK * sizeof(float);  /* 4 rows */
  /* Winograd scratch (every such layer reads W channels, blocks of <= 12 outputs). */
  job->vbuf_off = job->mbuf_off = job->ebuf_off = 0;
  int any = m->kernel.wino != NULL;
  for (uint32_t l = 0; l < m->body_count; l++) any |= body_wino_ok(m, l) | body_wino4_ok(m, l);
  if (any) {
    /* F(2x2, 5x5): V 36 x W x 16, M 2 x 36 x 12 x 16; F(4x4, 5x5): V 64 x W x 16, M 64 x
     * 12 x 16, E 64 x 16 (all offsets 64-byte aligned) */
    size_t v2 = (size_t)WINO_POS * m->width * 16, v4 = (size_t)WINO4_POS * m->width * 16;
    job->vbuf_off = off;
    off += ((v2 > v4 ? v2 : v4) * sizeof(float) + 63) & ~(size_t)63;
    job->mbuf_off = off;
    off += 2 * (size_t)WINO_POS * 12 * 16 * sizeof(float);  /* >= 64 x 12 x 16 */
    job->ebuf_off = off;
    off += (size_t)WINO4_POS * 16 * sizeof(float);
  }
  off = (off + 4095) & ~(size_t)4095;  /* threads' blocks on separate pages */
  if (s->scratch && s->scratch_threads >= threads && s->scratch_bytes == off) return TT_OK;
  free(s->scratch);
  s->scratch = aligned_alloc(4096, off * threads);
  if (!s->scratch) {
    s->scratch_threads = 0;
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__TAA_NAME ": out of memory for scratch");
  }
  /* Ring columns outside the image stay zero: only [COL, COL + vw) is ever written. */
  memset(s->scratch, 0, off * threads);
  s->scratch_threads = threads;
  s->scratch_bytes = off;
  return TT_OK;
}

void tt__net_fast_process(tt__net_state *s, const tt__net_model *m, const tt_host *host,
                          const tt__net_frame *f, float *out_rgb) {
  const float *color = f->color, *depth = f->depth;
  const uint32_t jitter_index = f->jitter_index;
  const fast_isa *isa = fast_pick();
  double w0 = fast_ns() * 1e-6, c0 = tt__taa_cpu_ms();
  in_job ij = {.s = s, .m = m, .color = color, .depth = depth, .motion = f->motion,
               .reject = (m->flags & TT__NET_FLAG_REJECT) ? s->reject : NULL,
               .dprev = s->have_prev_depth && f->prev_depth ? s->prev_depth : NULL,
               .zprev = f->prev_depth, .jx = f->jitter[0], .jy = f->jitter[1],
               .pjx = s->prev_jitter[0], .pjy = s->prev_jitter[1]};
  float dmax = 0.0f;
  if (depth)
    for (size_t i = 0; i < (size_t)s->width * s->height; i++)
      if (depth[i] > dmax && isfinite(depth[i])) dmax = depth[i];
  ij.depth_scale = dmax > 0.0f ? 1.0f / dmax : 0.0f;
#if FAST_X86
  tt__taa_rows_fn in_rows = input_rows_generic;
  if (strcmp(isa->name, "generic"))
    in_rows = s->state_ch == 3 ? input_rows_sc3_v3
              : s->state_ch == 8 ? input_rows_sc8_v3 : input_rows_v3;
  tt__taa_parallel_rows(host, s->height, in_rows, &ij);
#else
  tt__taa_parallel_rows(host, s->height, input_rows_generic, &ij);
#endif
  if ((m->flags & TT__NET_FLAG_RESET) && s->valid) fast_reject_reset(s, m);
  double w1 = fast_ns() * 1e-6, c1 = tt__taa_cpu_ms();

  int pool = host && host->parallel_for && s->height >= 16;
  uint32_t threads = pool && host->thread_count ? host->thread_count() : 1;
  if (threads < 1) threads = 1;
  band_job job = {.s = s, .m = m, .isa = isa, .set = jitter_index % TT__NET_JITTER_SETS,
                  .out_rgb = out_rgb};
  job.wino = isa->wino ? s->winograd : 0;
  job.kwino = !job.wino || !m->kernel.wino ? 0 : s->winograd >= 2 && m->kernel.wino4 && isa->wino4 ? 4 : 2;
  if (fast_scratch(s, m, &job, threads) != TT_OK) {
    /* Out of memory for a few MB of scratch: leave the frame as the input. */
    memcpy(out_rgb, color, (size_t)s->width * s->height * 3 * sizeof(float));
    return;
  }
  for (uint32_t t = 0; t < s->scratch_threads; t++)
    memset((unsigned char *)s->scratch + (size_t)t * s->scratch_bytes, 0, sizeof(band_times));
  /* Bands: about 4 per thread (dynamic scheduling evens out a loaded machine), at least 16
   * rows each (a band recomputes ~2 rows of halo work). The split does not change results. */
  uint32_t rows = s->band_rows;
  if (!rows) {
    rows = (s->height + 4 * threads - 1) / (4 * threads);
    if (rows < 16) rows = 16;
    if (job.wino) rows = (rows + 3) & ~3u;  /* whole Winograd row pairs / quads per band */
  }
  job.band_rows = rows;
  job.bands = (s->height + rows - 1) / rows;
  uint64_t items = (uint64_t)job.bands * job.tiles;
  if (!pool || threads == 1 || items == 1 ||
      host->parallel_for(items, 1, band_body, &job) != TT_OK)
    band_body(&job, 0, items, 0);  /* serial, or finishing an interrupted frame */
  double w2 = fast_ns() * 1e-6, c2 = tt__taa_cpu_ms();

  double body = 0, kern = 0, mix = 0;
  for (uint32_t t = 0; t < s->scratch_threads; t++) {
    const band_times *bt = (const band_times *)((unsigned char *)s->scratch +
                                                (size_t)t * s->scratch_bytes);
    body += bt->body_ns;
    kern += bt->kernel_ns;
    mix += bt->mix_ns;
  }
  double tot = body + kern + mix, fmix = tot > 0 ? mix / tot : 0;
  s->ms_body = body * 1e-6;
  s->ms_kernel = kern * 1e-6;
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
