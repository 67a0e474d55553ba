/* post_taa: the fast path's weights, repacked once per model at load (tt__net_fast_pack):
 * per output block for the direct convolutions, and the Winograd transforms U = G g G^T of
 * the 5x5 layers (F(2x2, 5x5) and F(4x4, 5x5), taa_kernel_wino.c), computed in double. */
#include "taa_fast.h"

/* Winograd F(2x2, 5x5) (Lavin & Gray 2016) with the interpolation points 0, 1, -1, 2, -2
 * and infinity: a 2x2 output tile of a 5x5 correlation is Y = A^T [U . V] A with the 6x6
 * input tile d, V = B^T d B, and U = G g G^T per weight filter g; summed over input
 * channels, the elementwise products become 36 small matrix products (out x in times
 * in x tiles): 36 multiplies per 2x2 outputs and input channel instead of 100. B^T and A^T
 * hold small integers (exact in float); the fractions sit in G, applied once per weight
 * set in double. */
static const double tt__net_wino_g[6][5] = {{1.0 / 4, 0, 0, 0, 0},
                                            {1.0 / 6, 1.0 / 6, 1.0 / 6, 1.0 / 6, 1.0 / 6},
                                            {1.0 / 6, -1.0 / 6, 1.0 / 6, -1.0 / 6, 1.0 / 6},
                                            {1.0 / 24, 1.0 / 12, 1.0 / 6, 1.0 / 3, 2.0 / 3},
                                            {1.0 / 24, -1.0 / 12, 1.0 / 6, -1.0 / 3, 2.0 / 3},
                                            {0, 0, 0, 0, 1}};

/* U = G g G^T of every (set, output, input) filter into l->wino, laid out
 * [set][block][36][in][oblk] (`uper` floats per set). */
static void tt__net_wino_weights(tt__net_layer *l, size_t uper) {
  const uint32_t O = l->oblk, I = l->in;
  for (uint32_t s = 0; s < l->sets; s++)
    for (uint32_t oc = 0; oc < l->out; oc++)
      for (uint32_t c = 0; c < I; c++) {
        const float *g = l->w + (((size_t)s * l->out + oc) * I + c) * 25;
        double t[6][5], u[6][6];
        for (int i = 0; i < 6; i++)
          for (int k = 0; k < 5; k++) {
            double a = 0;
            for (int j = 0; j < 5; j++) a += tt__net_wino_g[i][j] * g[j * 5 + k];
            t[i][k] = a;
          }
        for (int i = 0; i < 6; i++)
          for (int j = 0; j < 6; j++) {
            double a = 0;
            for (int k = 0; k < 5; k++) a += t[i][k] * tt__net_wino_g[j][k];
            u[i][j] = a;
          }
        uint32_t b = oc / O, o = oc % O;
        float *dst = l->wino + s * uper + (size_t)b * TT__NET_WINO_POS * I * O;
        for (int p = 0; p < 36; p++) dst[((size_t)p * I + c) * O + o] = (float)u[p / 6][p % 6];
      }
}

/* Winograd F(4x4, 5x5) with the points 0, 1, -1, 2, -2, 1/2, -1/2 and infinity: a 4x4
 * output tile of a 5x5 correlation is Y = A^T [U . V] A with the 8x8 input tile d,
 * V = B^T d B, U = G g G^T: 64 multiplies per 16 outputs and input channel (4 per output,
 * against 9 for F(2x2, 5x5) and 25 direct). B^T (the same as F(6x6, 3x3)'s) and A^T hold
 * small dyadic fractions, exact in float; G is applied once per weight set in double. */
static const double tt__net_wino4_g[8][5] = {{-1, 0, 0, 0, 0},
                                             {-2.0 / 9, -2.0 / 9, -2.0 / 9, -2.0 / 9, -2.0 / 9},
                                             {-2.0 / 9, 2.0 / 9, -2.0 / 9, 2.0 / 9, -2.0 / 9},
                                             {1.0 / 90, 1.0 / 45, 2.0 / 45, 4.0 / 45, 8.0 / 45},
                                             {1.0 / 90, -1.0 / 45, 2.0 / 45, -4.0 / 45, 8.0 / 45},
                                             {32.0 / 45, 16.0 / 45, 8.0 / 45, 4.0 / 45, 2.0 / 45},
                                             {32.0 / 45, -16.0 / 45, 8.0 / 45, -4.0 / 45, 2.0 / 45},
                                             {0, 0, 0, 0, 1}};

/* U = G g G^T of every (set, output, input) filter into l->wino4, laid out
 * [set][block][64][in][oblk] (`uper` floats per set). */
static void tt__net_wino4_weights(tt__net_layer *l, size_t uper) {
  const uint32_t O = l->oblk, I = l->in;
  for (uint32_t s = 0; s < l->sets; s++)
    for (uint32_t oc = 0; oc < l->out; oc++)
      for (uint32_t c = 0; c < I; c++) {
        const float *g = l->w + (((size_t)s * l->out + oc) * I + c) * 25;
        double t[8][5], u[8][8];
        for (int i = 0; i < 8; i++)
          for (int k = 0; k < 5; k++) {
            double a = 0;
            for (int j = 0; j < 5; j++) a += tt__net_wino4_g[i][j] * g[j * 5 + k];
            t[i][k] = a;
          }
        for (int i = 0; i < 8; i++)
          for (int j = 0; j < 8; j++) {
            double a = 0;
            for (int k = 0; k < 5; k++) a += t[i][k] * tt__net_wino4_g[j][k];
            u[i][j] = a;
          }
        uint32_t b = oc / O, o = oc % O;
        float *dst = l->wino4 + s * uper + (size_t)b * TT__NET_WINO4_POS * I * O;
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
  size_t uper = wino ? (size_t)l->nob * TT__NET_WINO_POS * l->in * l->oblk : 0;
  /* F(4x4, 5x5) for 5x5 layers with output blocks of 6, 10 or 12 (the kernel layer, body
   * layers after the first) */
  int wino4 = l->ksize == 5 && (l->oblk == 6 || l->oblk == 10 || l->oblk == 12);
  size_t u4per = wino4 ? (size_t)l->nob * TT__NET_WINO4_POS * l->in * l->oblk : 0;
  l->wq = tt__net_fz_alloc(qper * l->sets + (uper + u4per) * l->sets);
  l->bq = tt__net_fz_alloc((size_t)l->nob * l->oblk * l->sets);
  l->wino = l->wino4 = NULL;
  if (!l->wq || !l->bq)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__TAA_NAME ": out of memory for weights");
  if (wino) {
    l->wino = l->wq + qper * l->sets;
    tt__net_wino_weights(l, uper);
  }
  if (wino4) {
    l->wino4 = l->wq + (qper + uper) * l->sets;
    tt__net_wino4_weights(l, u4per);
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
