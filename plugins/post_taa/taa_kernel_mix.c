/* post_taa kernels: the head of the network per row chunk (README.md, "How the fast path
 * works", 4): softmax of the kernel layer's 50 logits (polynomial exp), the colour mix of
 * eq. 5.3 over the input planes' tonemapped colour and reprojected output, the 1x1 hidden
 * layer, the next state and the linear output; 8 pixels per vector, 16 in the AVX-512
 * copy. Compiled once per instruction set (taa_kernel.h). */
#include "taa_kernel.h"

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

/* The 8 channel vectors v of 8 pixels to dst in pixel-major order (8 floats per pixel). */
AI void store_t8x8(float *dst, const v8f v[8]) {
  v8f t[8];
  t8x8(v, t);
#pragma GCC unroll 8
  for (int l = 0; l < 8; l++) vstore(dst + 8 * l, t[l]);
}

/* `hidden`: the model's hidden channels, a constant in the dispatch's common cases (the
 * hidden layer's sums then stay in registers). */
AI void mix_rows_t(const tt__net_mix_args *a, const uint32_t hidden) {
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
      if (hidden == 5) { /* 8 state channels */
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

AI void mix_dispatch(const tt__net_mix_args *a) {
  switch (a->m->hidden) {
  case 0: mix_rows_t(a, 0); break;
  case 5: mix_rows_t(a, 5); break;
  default: mix_rows_t(a, a->m->hidden); break;
  }
}

#if TT__NET_HAVE_AVX512
/* ---- the colour mix on 16-lane vectors (AVX-512) ---- */

/* v16f copies of vmax / vmin / vexp_neg: the same operations per lane (MAXPS / MINPS are
 * vsel(a > b, a, b) / vsel(a < b, a, b), NaN included), so the same results bit for bit. */
AI v16f vmax16(v16f a, v16f b) { return (v16f)_mm512_max_ps((__m512)a, (__m512)b); }
AI v16f vmin16(v16f a, v16f b) { return (v16f)_mm512_min_ps((__m512)a, (__m512)b); }
AI v16f vload16(const float *p) { return *(const v16fu *)p; }
AI v16f vsplat16(float f) { return (v16f)_mm512_set1_ps(f); }
AI v16f vexp_neg16(v16f x) {
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
AI void mix_rows16_t(const tt__net_mix_args *a, const uint32_t hidden) {
  const tt__net_state *s = a->s;
  const uint32_t hin = a->m->hid.in, sc = s->state_ch;
  const size_t rs = s->inp_ys, cs = s->inp_cs;
  for (uint32_t xl = 0; xl < a->n; xl += 16) {
    uint32_t x = a->x0 + xl;
    if (x >= s->width) break;
    float *lg = a->lg + xl;
    v16f m5[5];
#  pragma GCC unroll 5
    for (int k = 0; k < 5; k++) m5[k] = vload16(lg + k * CHUNK);
#  pragma GCC unroll 9
    for (int k = 5; k < 50; k += 5)
#  pragma GCC unroll 5
      for (int j = 0; j < 5; j++) m5[j] = vmax16(m5[j], vload16(lg + (k + j) * CHUNK));
    v16f mx = vmax16(vmax16(vmax16(m5[0], m5[1]), vmax16(m5[2], m5[3])), m5[4]);
    v16f sa = vsplat16(0.0f), sb = vsplat16(0.0f);
    v16f o[3] = {vsplat16(0.0f), vsplat16(0.0f), vsplat16(0.0f)};
    const float *row = s->inp + (size_t)(a->y - 2 + s->halo) * rs + COL + x - 2;
    for (uint32_t ty = 0; ty < 5; ty++, row += rs) {
      const float *lt = lg + ty * 5 * CHUNK;
#  pragma GCC unroll 5
      for (uint32_t tx = 0; tx < 5; tx++) {
        v16f ka = vexp_neg16(vload16(lt + tx * CHUNK) - mx);
        v16f kb = vexp_neg16(vload16(lt + (25 + tx) * CHUNK) - mx);
        sa += ka;
        sb += kb;
#  pragma GCC unroll 3
        for (int c = 0; c < 3; c++)
          o[c] += ka * vload16(row + c * cs + tx) + kb * vload16(row + (6 + c) * cs + tx);
      }
    }
    v16f sum = sa + sb;
    v16f inv = vsplat16(1.0f) / sum;
    v16f st[16];
#  pragma GCC unroll 3
    for (int c = 0; c < 3; c++) st[c] = o[c] = o[c] * inv;
    const float *hp = a->hrow + (int)(COL + x) - a->hx;
#  pragma GCC unroll 8
    for (uint32_t k = 0; k < hidden; k++) st[3 + k] = vsplat16(a->hb[k]);
    for (uint32_t c = 0; c < hin; c++) {
      v16f xin = vload16(hp + c * a->hcs);
#  pragma GCC unroll 8
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
      if (hidden == 5) { /* 8 state channels */
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

AI void mix16_dispatch(const tt__net_mix_args *a) {
  switch (a->m->hidden) {
  case 0: mix_rows16_t(a, 0); break;
  case 5: mix_rows16_t(a, 5); break;
  default: mix_rows16_t(a, a->m->hidden); break;
  }
}
#endif

void TT__NET_K(mix)(const tt__net_mix_args *a) {
#if TT__NET_HAVE_AVX512
  mix16_dispatch(a);
#else
  mix_dispatch(a);
#endif
}
