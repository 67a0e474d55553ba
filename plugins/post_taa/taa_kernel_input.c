/* post_taa kernels: the input planes of a frame (stage 1; README.md, "How the fast path
 * works", 1), by rows: tonemap, motion, depth, the Catmull-Rom reprojection of the previous
 * state (one 8-float vector per tap when the state has 8 channels), the rejection test and
 * input channel, into planes (per row, each channel's columns in turn) with zero rows
 * above/below and zero columns left/right of the image. With AVX2, 8 pixels at a time for
 * states of 3 and 8 channels. Compiled once per instruction set (taa_kernel.h). */
#include "taa_kernel.h"

/* Catmull-Rom fetch of an 8-channel image (one vector per tap); same weights and order as
 * tt__taa_sample_catmull_rom. */
TT__NET_AI tt__net_v8f tt__net_fast_cr8(const float *img, uint32_t width, uint32_t height, float fx,
                                        float fy) {
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
  tt__net_v8f acc = tt__net_vsplat(0.0f);
  for (int j = 0; j < 4; j++) {
    int yy = y0 + j;
    yy = yy < 0 ? 0 : (yy >= h ? h - 1 : yy);
    const float *row = img + (size_t)yy * width * 8;
    for (int i = 0; i < 4; i++) acc += tt__net_vload(row + (size_t)xi[i] * 8) * (wx[i] * wy[j]);
  }
  return acc;
}

/* The same for C channels known at compile time (scalar taps, unrolled; C = 3 + hidden). */
TT__NET_AI void tt__net_fast_crc(const float *img, uint32_t width, uint32_t height, float fx,
                                 float fy, const int C, float *out) {
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
TT__NET_AI void tt__net_input_pixel(const tt__net_input_job *job, uint32_t x, uint32_t y,
                                    float *base) {
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
     * applied after the pass (tt__net_fast_reject_reset) */
    rj = !s->valid ? (uint8_t)(TT__TAA_REJECT_RAW | TT__TAA_REJECT_RESET)
                   : tt__taa_reject_test(job->dprev, w, s->height, job->pjx, job->pjy,
                                         job->zprev ? job->zprev[i] : 0.0f, x, y, mx, my, job->jx,
                                         job->jy);
    job->reject[i] = rj;
  }
  if (s->valid) {
    /* Motion points from this frame back to the previous one (film.h). */
    float fx = (float)x + 0.5f + mx, fy = (float)y + 0.5f + my;
    switch (sc) {
    case 8: {
      tt__net_v8f v = tt__net_fast_cr8(s->state, w, s->height, fx, fy);
      memcpy(fb, &v, sizeof v);
      break;
    }
    case 3: tt__net_fast_crc(s->state, w, s->height, fx, fy, 3, fb); break;
    case 4: tt__net_fast_crc(s->state, w, s->height, fx, fy, 4, fb); break;
    case 6: tt__net_fast_crc(s->state, w, s->height, fx, fy, 6, fb); break;
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

TT__NET_AI void tt__net_input_rows_t(const tt__net_input_job *job, uint32_t y0, uint32_t y1) {
  const tt__net_state *s = job->s;
  for (uint32_t y = y0; y < y1; y++) {
    float *base = s->inp + (size_t)(y + s->halo) * s->inp_ys + TT__NET_COL_OFF;
    for (uint32_t x = 0; x < s->width; x++) tt__net_input_pixel(job, x, y, base);
  }
}

#if TT__NET_HAVE_AVX2
/* 8 pixels x .. x + 7 of row y at once (AVX2 gathers), for a state of SC = 3 (hidden 0) or
 * 8 (hidden 5) channels: the same steps as tt__net_input_pixel. The Catmull-Rom weights may round
 * differently from the scalar code in the last bit (a pixel always takes the same path,
 * whatever the threads); the rejection test uses the same float operations as
 * tt__taa_reject_test, bit for bit. */
TT__NET_AI void tt__net_input8_t(const tt__net_input_job *job, uint32_t x, uint32_t y, float *base,
                                 const int SC) {
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
  __m256 dep =
      job->depth ? _mm256_mul_ps(_mm256_loadu_ps(job->depth + i), _mm256_set1_ps(job->depth_scale))
                 : zero;
  const __m256 xf = _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32((int)x), lane));
  const __m256 yf = _mm256_set1_ps((float)y);
  __m256 raw = zero;
  if (job->reject) {
    if (!s->valid) {
      memset(job->reject + i, TT__TAA_REJECT_RAW | TT__TAA_REJECT_RESET, 8);
      raw = one;
    } else {
      __m256 qx =
          _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(xf, half), _mm256_set1_ps(job->jx)), mx);
      __m256 qy =
          _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(yf, half), _mm256_set1_ps(job->jy)), my);
      __m256 in =
          _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(qx, zero, _CMP_GE_OQ),
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
        __m256i y0 =
            _mm256_mullo_epi32(_mm256_min_epi32(_mm256_max_epi32(iy, z), hm), _mm256_set1_epi32(w));
        __m256i y1 =
            _mm256_mullo_epi32(_mm256_min_epi32(_mm256_max_epi32(_mm256_add_epi32(iy, o1), z), hm),
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
        __m256 test =
            _mm256_or_ps(_mm256_cmp_ps(zp, zero, _CMP_NGT_UQ), _mm256_cmp_ps(zp, thr, _CMP_GT_OQ));
        far = _mm256_and_ps(_mm256_andnot_ps(sky, test), in);
      }
      int offm = ~_mm256_movemask_ps(in) & 0xff, farm = _mm256_movemask_ps(far);
      for (int l = 0; l < 8; l++)
        job->reject[i + (size_t)l] =
            (uint8_t)((offm >> l) & 1   ? TT__TAA_REJECT_RAW | TT__TAA_REJECT_OFF
                      : (farm >> l) & 1 ? TT__TAA_REJECT_RAW | TT__TAA_REJECT_FAR
                                        : 0u);
      raw = _mm256_and_ps(
          _mm256_or_ps(_mm256_xor_ps(in, _mm256_castsi256_ps(_mm256_set1_epi32(-1))), far), one);
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
      o[0] = _mm256_mul_ps(
          f, _mm256_fmadd_ps(f, _mm256_fnmadd_ps(half, f, one), _mm256_set1_ps(-0.5f)));
      o[1] = _mm256_fmadd_ps(_mm256_mul_ps(f, f),
                             _mm256_fmadd_ps(_mm256_set1_ps(1.5f), f, _mm256_set1_ps(-2.5f)), one);
      o[2] = _mm256_mul_ps(
          f, _mm256_fmadd_ps(f, _mm256_fnmadd_ps(_mm256_set1_ps(1.5f), f, _mm256_set1_ps(2.0f)),
                             half));
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
      _mm256_storeu_si256(
          (__m256i *)xi[k],
          _mm256_mullo_epi32(_mm256_min_epi32(_mm256_max_epi32(_mm256_add_epi32(bxi, o), z), wm),
                             _mm256_set1_epi32(SC)));
      _mm256_storeu_si256(
          (__m256i *)yo[k],
          _mm256_mullo_epi32(_mm256_min_epi32(_mm256_max_epi32(_mm256_add_epi32(byi, o), z), hm),
                             _mm256_set1_epi32(SC * w)));
      _mm256_storeu_ps(wxs[k], wx[k]);
      _mm256_storeu_ps(wys[k], wy[k]);
    }
    if (SC == 8) {
      /* one 8-float vector per tap (all state channels), then the 8 x 8 transpose */
      tt__net_v8f px[8];
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
      tt__net_v8f ch[8];
      tt__net_t8x8(px, ch);
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
TT__NET_AI void tt__net_input_rows8_t(const tt__net_input_job *job, uint32_t y0, uint32_t y1,
                                      const int SC) {
  const tt__net_state *s = job->s;
  for (uint32_t y = y0; y < y1; y++) {
    float *base = s->inp + (size_t)(y + s->halo) * s->inp_ys + TT__NET_COL_OFF;
    uint32_t x = 0;
    for (; x + 8 <= s->width; x += 8) tt__net_input8_t(job, x, y, base, SC);
    for (; x < s->width; x++) tt__net_input_pixel(job, x, y, base);
  }
}
#endif

void TT__NET_K(input_rows)(void *ctx, uint32_t y0, uint32_t y1) {
  const tt__net_input_job *job = ctx;
#if TT__NET_HAVE_AVX2
  switch (job->s->state_ch) {
  case 3: tt__net_input_rows8_t(job, y0, y1, 3); return;
  case 8: tt__net_input_rows8_t(job, y0, y1, 8); return;
  default: break;
  }
#endif
  tt__net_input_rows_t(job, y0, y1);
}
