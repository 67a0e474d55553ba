/* post_taa kernels: the head of the network per row chunk (README.md, "How the fast path
 * works", 4): softmax of the kernel layer's 50 logits (polynomial exp), the colour mix of
 * eq. 5.3 over the input planes' tonemapped colour and reprojected output, the 1x1 hidden
 * layer, the next state and the linear output; 8 pixels per vector, 16 in the AVX-512
 * copy. Compiled once per instruction set (taa_kernel.h). */
#include "taa_kernel.h"

/* 8 lanes of three vectors interleaved into 24 floats r0 g0 b0 r1 g1 b1 ... (the linear
 * output's pixel order). */
TT__NET_AI void tt__net_store_rgb8(float *dst, tt__net_v8f r, tt__net_v8f g, tt__net_v8f b) {
  tt__net_v8f rg0 = TT__NET_WINO_SHUF8(r, g, 0, 8, 0, 1, 9, 0, 2, 10);
  tt__net_v8f rg1 = TT__NET_WINO_SHUF8(r, g, 0, 3, 11, 0, 4, 12, 0, 5);
  tt__net_v8f rg2 = TT__NET_WINO_SHUF8(r, g, 13, 0, 6, 14, 0, 7, 15, 0);
  tt__net_vstore(dst, TT__NET_WINO_SHUF8(rg0, b, 0, 1, 8, 3, 4, 9, 6, 7));
  tt__net_vstore(dst + 8, TT__NET_WINO_SHUF8(rg1, b, 10, 1, 2, 11, 4, 5, 12, 7));
  tt__net_vstore(dst + 16, TT__NET_WINO_SHUF8(rg2, b, 0, 13, 2, 3, 14, 5, 6, 15));
}

/* The 8 channel vectors v of 8 pixels to dst in pixel-major order (8 floats per pixel). */
TT__NET_AI void tt__net_store_t8x8(float *dst, const tt__net_v8f v[8]) {
  tt__net_v8f t[8];
  tt__net_t8x8(v, t);
#pragma GCC unroll 8
  for (int l = 0; l < 8; l++) tt__net_vstore(dst + 8 * l, t[l]);
}

/* `hidden`: the model's hidden channels, a constant in the dispatch's common cases (the
 * hidden layer's sums then stay in registers). */
TT__NET_AI void tt__net_mix_rows_t(const tt__net_mix_args *a, const uint32_t hidden) {
  const tt__net_state *s = a->s;
  const uint32_t hin = a->m->hid.in, sc = s->state_ch;
  const size_t rs = s->inp_ys, cs = s->inp_cs;
  for (uint32_t xl = 0; xl < a->n; xl += 8) {
    uint32_t x = a->x0 + xl;
    if (x >= s->width) break;
    float *lg = a->lg + xl;
    /* Max in 5 independent chains (the same value as one chain: max is exact). */
    tt__net_v8f m5[5];
#pragma GCC unroll 5
    for (int k = 0; k < 5; k++) m5[k] = tt__net_vload(lg + k * TT__NET_CHUNK);
#pragma GCC unroll 9
    for (int k = 5; k < 50; k += 5)
#pragma GCC unroll 5
      for (int j = 0; j < 5; j++)
        m5[j] = tt__net_vmax(m5[j], tt__net_vload(lg + (k + j) * TT__NET_CHUNK));
    tt__net_v8f mx =
        tt__net_vmax(tt__net_vmax(tt__net_vmax(m5[0], m5[1]), tt__net_vmax(m5[2], m5[3])), m5[4]);
    /* The softmax weights computed where the mix uses them (no store and reload of the 50
     * exponentials); the two kernels' sums in separate chains. */
    tt__net_v8f sa = tt__net_vsplat(0.0f), sb = tt__net_vsplat(0.0f);
    tt__net_v8f o[3] = {tt__net_vsplat(0.0f), tt__net_vsplat(0.0f), tt__net_vsplat(0.0f)};
    const float *row = s->inp + (size_t)(a->y - 2 + s->halo) * rs + TT__NET_COL_OFF + x - 2;
    for (uint32_t ty = 0; ty < 5; ty++, row += rs) {
      const float *lt = lg + ty * 5 * TT__NET_CHUNK;
#pragma GCC unroll 5
      for (uint32_t tx = 0; tx < 5; tx++) {
        tt__net_v8f ka = tt__net_vexp_neg(tt__net_vload(lt + tx * TT__NET_CHUNK) - mx);
        tt__net_v8f kb = tt__net_vexp_neg(tt__net_vload(lt + (25 + tx) * TT__NET_CHUNK) - mx);
        sa += ka;
        sb += kb;
#pragma GCC unroll 3
        for (int c = 0; c < 3; c++)
          o[c] +=
              ka * tt__net_vload(row + c * cs + tx) + kb * tt__net_vload(row + (6 + c) * cs + tx);
      }
    }
    tt__net_v8f sum = sa + sb;
    tt__net_v8f inv = tt__net_vsplat(1.0f) / sum;
    tt__net_v8f st[16];
#pragma GCC unroll 3
    for (int c = 0; c < 3; c++) st[c] = o[c] = o[c] * inv;
    /* Hidden layer (1x1): each input vector loaded once for all outputs; every output's
     * sum runs over the inputs in order. */
    const float *hp = a->hrow + (int)(TT__NET_COL_OFF + x) - a->hx;
#pragma GCC unroll 8
    for (uint32_t k = 0; k < hidden; k++) st[3 + k] = tt__net_vsplat(a->hb[k]);
    for (uint32_t c = 0; c < hin; c++) {
      tt__net_v8f xin = tt__net_vload(hp + c * a->hcs);
#pragma GCC unroll 8
      for (uint32_t k = 0; k < hidden; k++) st[3 + k] += xin * a->hw[k * hin + c];
    }
    /* Linear output: the inverse tonemap of taa_image.c on 8 lanes. */
    tt__net_v8f z = tt__net_vsplat(0.0f);
    tt__net_v8f mm = tt__net_vmin(tt__net_vmax(tt__net_vmax(o[0], o[1]), tt__net_vmax(o[2], z)),
                                  tt__net_vsplat(0.999f));
    tt__net_v8f scale = tt__net_vsplat(1.0f) / (tt__net_vsplat(1.0f) - mm);
    tt__net_v8f lin[3];
    for (int c = 0; c < 3; c++) lin[c] = tt__net_vmax(o[c], z) * scale;
    uint32_t lanes = s->width - x < 8 ? s->width - x : 8;
    size_t i = (size_t)a->y * s->width + x;
    float *ns = s->next_state + i * sc, *out = a->out_rgb + i * 3;
    if (lanes == 8) {
      tt__net_store_rgb8(out, lin[0], lin[1], lin[2]);
      if (hidden == 5) { /* 8 state channels */
        tt__net_store_t8x8(ns, st);
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

TT__NET_AI void tt__net_mix_dispatch(const tt__net_mix_args *a) {
  switch (a->m->hidden) {
  case 0: tt__net_mix_rows_t(a, 0); break;
  case 5: tt__net_mix_rows_t(a, 5); break;
  default: tt__net_mix_rows_t(a, a->m->hidden); break;
  }
}

#if TT__NET_HAVE_AVX512
/* ---- the colour mix on 16-lane vectors (AVX-512) ---- */

/* tt__net_v16f copies of tt__net_vmax / tt__net_vmin / tt__net_vexp_neg: the same operations per lane (MAXPS / MINPS are
 * tt__net_vsel(a > b, a, b) / tt__net_vsel(a < b, a, b), NaN included), so the same results bit for bit. */
TT__NET_AI tt__net_v16f tt__net_vmax16(tt__net_v16f a, tt__net_v16f b) {
  return (tt__net_v16f)_mm512_max_ps((__m512)a, (__m512)b);
}
TT__NET_AI tt__net_v16f tt__net_vmin16(tt__net_v16f a, tt__net_v16f b) {
  return (tt__net_v16f)_mm512_min_ps((__m512)a, (__m512)b);
}
TT__NET_AI tt__net_v16f tt__net_vload16(const float *p) { return *(const tt__net_v16fu *)p; }
TT__NET_AI tt__net_v16f tt__net_vsplat16(float f) { return (tt__net_v16f)_mm512_set1_ps(f); }
TT__NET_AI tt__net_v16f tt__net_vexp_neg16(tt__net_v16f x) {
  x = tt__net_vmax16(x, tt__net_vsplat16(-87.0f));
  tt__net_v16f t = x * 1.44269504088896341f;
  tt__net_v16f n = (t + 12582912.0f) - 12582912.0f;
  tt__net_v16f r = x - n * 0.693145751953125f - n * 1.428606765330187045e-06f;
  tt__net_v16f p = r * (1.0f / 720.0f) + 1.0f / 120.0f;
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  tt__net_v16i e = (__builtin_convertvector(n, tt__net_v16i) + 127) << 23;
  tt__net_v16f scale;
  memcpy(&scale, &e, sizeof scale);
  return p * scale;
}

/* tt__net_mix_rows_t on 16 pixels per step: the same steps; the stores go out as two 8-pixel
 * halves by the 8-lane helpers. */
TT__NET_AI void tt__net_mix_rows16_t(const tt__net_mix_args *a, const uint32_t hidden) {
  const tt__net_state *s = a->s;
  const uint32_t hin = a->m->hid.in, sc = s->state_ch;
  const size_t rs = s->inp_ys, cs = s->inp_cs;
  for (uint32_t xl = 0; xl < a->n; xl += 16) {
    uint32_t x = a->x0 + xl;
    if (x >= s->width) break;
    float *lg = a->lg + xl;
    tt__net_v16f m5[5];
#  pragma GCC unroll 5
    for (int k = 0; k < 5; k++) m5[k] = tt__net_vload16(lg + k * TT__NET_CHUNK);
#  pragma GCC unroll 9
    for (int k = 5; k < 50; k += 5)
#  pragma GCC unroll 5
      for (int j = 0; j < 5; j++)
        m5[j] = tt__net_vmax16(m5[j], tt__net_vload16(lg + (k + j) * TT__NET_CHUNK));
    tt__net_v16f mx = tt__net_vmax16(
        tt__net_vmax16(tt__net_vmax16(m5[0], m5[1]), tt__net_vmax16(m5[2], m5[3])), m5[4]);
    tt__net_v16f sa = tt__net_vsplat16(0.0f), sb = tt__net_vsplat16(0.0f);
    tt__net_v16f o[3] = {tt__net_vsplat16(0.0f), tt__net_vsplat16(0.0f), tt__net_vsplat16(0.0f)};
    const float *row = s->inp + (size_t)(a->y - 2 + s->halo) * rs + TT__NET_COL_OFF + x - 2;
    for (uint32_t ty = 0; ty < 5; ty++, row += rs) {
      const float *lt = lg + ty * 5 * TT__NET_CHUNK;
#  pragma GCC unroll 5
      for (uint32_t tx = 0; tx < 5; tx++) {
        tt__net_v16f ka = tt__net_vexp_neg16(tt__net_vload16(lt + tx * TT__NET_CHUNK) - mx);
        tt__net_v16f kb = tt__net_vexp_neg16(tt__net_vload16(lt + (25 + tx) * TT__NET_CHUNK) - mx);
        sa += ka;
        sb += kb;
#  pragma GCC unroll 3
        for (int c = 0; c < 3; c++)
          o[c] += ka * tt__net_vload16(row + c * cs + tx) +
                  kb * tt__net_vload16(row + (6 + c) * cs + tx);
      }
    }
    tt__net_v16f sum = sa + sb;
    tt__net_v16f inv = tt__net_vsplat16(1.0f) / sum;
    tt__net_v16f st[16];
#  pragma GCC unroll 3
    for (int c = 0; c < 3; c++) st[c] = o[c] = o[c] * inv;
    const float *hp = a->hrow + (int)(TT__NET_COL_OFF + x) - a->hx;
#  pragma GCC unroll 8
    for (uint32_t k = 0; k < hidden; k++) st[3 + k] = tt__net_vsplat16(a->hb[k]);
    for (uint32_t c = 0; c < hin; c++) {
      tt__net_v16f xin = tt__net_vload16(hp + c * a->hcs);
#  pragma GCC unroll 8
      for (uint32_t k = 0; k < hidden; k++) st[3 + k] += xin * a->hw[k * hin + c];
    }
    tt__net_v16f z = tt__net_vsplat16(0.0f);
    tt__net_v16f mm =
        tt__net_vmin16(tt__net_vmax16(tt__net_vmax16(o[0], o[1]), tt__net_vmax16(o[2], z)),
                       tt__net_vsplat16(0.999f));
    tt__net_v16f scale = tt__net_vsplat16(1.0f) / (tt__net_vsplat16(1.0f) - mm);
    tt__net_v16f lin[3];
    for (int c = 0; c < 3; c++) lin[c] = tt__net_vmax16(o[c], z) * scale;
    uint32_t lanes = s->width - x < 16 ? s->width - x : 16;
    size_t i = (size_t)a->y * s->width + x;
    float *ns = s->next_state + i * sc, *out = a->out_rgb + i * 3;
    if (lanes == 16) {
      tt__net_v8f l8[3][2];
      for (int c = 0; c < 3; c++) memcpy(l8[c], &lin[c], sizeof lin[c]);
      tt__net_store_rgb8(out, l8[0][0], l8[1][0], l8[2][0]);
      tt__net_store_rgb8(out + 24, l8[0][1], l8[1][1], l8[2][1]);
      if (hidden == 5) { /* 8 state channels */
        tt__net_v8f s8[2][8];
        for (int c = 0; c < 8; c++) {
          tt__net_v8f h[2];
          memcpy(h, &st[c], sizeof h);
          s8[0][c] = h[0], s8[1][c] = h[1];
        }
        tt__net_store_t8x8(ns, s8[0]);
        tt__net_store_t8x8(ns + 64, s8[1]);
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

TT__NET_AI void tt__net_mix16_dispatch(const tt__net_mix_args *a) {
  switch (a->m->hidden) {
  case 0: tt__net_mix_rows16_t(a, 0); break;
  case 5: tt__net_mix_rows16_t(a, 5); break;
  default: tt__net_mix_rows16_t(a, a->m->hidden); break;
  }
}
#endif

void TT__NET_K(mix)(const tt__net_mix_args *a) {
#if TT__NET_HAVE_AVX512
  tt__net_mix16_dispatch(a);
#else
  tt__net_mix_dispatch(a);
#endif
}
