/* post_taa: variance-clipping TAA (Salvi 2016 on Karis 2014). Per pixel: fetch the
 * reprojected history, build the 3x3 neighbourhood's variance box in YCoCg (mean +- gamma
 * sigma), clip the history toward the box centre, and blend with the current pixel. By
 * default (the thesis' baseline) the whole resolve runs on tonemapped colour c / (1 + max c)
 * so that single bright samples do not dominate the average; the output is untonemapped.
 * That average of tonemapped samples is darker than the tonemapped average (the tonemap is
 * concave: Jensen), strongly so on Monte Carlo noise; `linear` resolves in linear colour
 * instead (energy-preserving: the running average of unbiased samples stays unbiased, up
 * to the clipping), at the price of fireflies that fade over ~1/blend frames. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "taa_internal.h"

tt_status tt__vctaa_init(tt__vctaa_filter *v, uint32_t width, uint32_t height) {
  memset(v, 0, sizeof *v);
  size_t n = (size_t)width * height * 3;
  v->width = width;
  v->height = height;
  v->history = calloc(n, sizeof(float));
  v->scratch = calloc(n, sizeof(float));
  v->ycocg = calloc(n, sizeof(float));
  if (!v->history || !v->scratch || !v->ycocg) {
    tt__vctaa_free(v);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__TAA_NAME ": out of memory for %ux%u history",
                        width, height);
  }
  return TT_OK;
}

void tt__vctaa_free(tt__vctaa_filter *v) {
  free(v->history);
  free(v->scratch);
  free(v->ycocg);
  v->history = v->scratch = v->ycocg = NULL;
  v->valid = 0;
}

/* RGB -> YCoCg (the luma/chroma space where an axis-aligned box fits colour clouds best). */
static inline void tt__vctaa_to_ycocg(const float c[3], float o[3]) {
  o[0] = 0.25f * c[0] + 0.5f * c[1] + 0.25f * c[2];
  o[1] = 0.5f * c[0] - 0.5f * c[2];
  o[2] = -0.25f * c[0] + 0.5f * c[1] - 0.25f * c[2];
}

/* YCoCg -> RGB. */
static inline void tt__vctaa_from_ycocg(const float o[3], float c[3]) {
  c[0] = o[0] + o[1] - o[2];
  c[1] = o[0] + o[2];
  c[2] = o[0] - o[1] - o[2];
}

typedef struct tt__vctaa_job {
  tt__vctaa_filter *v;
  const tt__vctaa_params *p;
  const float *color;
  const float *motion;
  float *out;
} tt__vctaa_job;

/* Tonemaps rows [y0, y1) of the new frame into YCoCg once (each is read 9 times). */
static void tt__vctaa_prepare_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const tt__vctaa_job *job = ctx;
  size_t w = job->v->width;
  for (size_t i = y0 * w; i < y1 * w; i++) {
    float t[3];
    if (job->p->linear)
      for (int c = 0; c < 3; c++) t[c] = tt__taa_fmax(job->color[3 * i + c], 0.0f);
    else tt__taa_tonemap_inl(job->color + 3 * i, t);
    tt__vctaa_to_ycocg(t, job->v->ycocg + 3 * i);
  }
}

/* tt__taa_sample_catmull_rom for 3 channels, inlined (same weights, taps and order). */
static inline void tt__vctaa_catmull_rom3(const float *img, int w, int h, float fx, float fy,
                                          float out[3]) {
  float ux = fx - 0.5f, uy = fy - 0.5f;
  float bx = floorf(ux), by = floorf(uy);
  float wx[4], wy[4];
  tt__taa_cr_weights(ux - bx, wx);
  tt__taa_cr_weights(uy - by, wy);
  int x0 = (int)bx - 1, y0 = (int)by - 1;
  int xi[4];
  for (int i = 0; i < 4; i++) {
    int v = x0 + i;
    xi[i] = 3 * (v < 0 ? 0 : (v >= w ? w - 1 : v));
  }
  float o0 = 0.0f, o1 = 0.0f, o2 = 0.0f;
  for (int j = 0; j < 4; j++) {
    int yy = y0 + j;
    const float *row = img + (size_t)(yy < 0 ? 0 : (yy >= h ? h - 1 : yy)) * w * 3;
    for (int i = 0; i < 4; i++) {
      const float *p = row + xi[i];
      float wt = wx[i] * wy[j];
      o0 += wt * p[0];
      o1 += wt * p[1];
      o2 += wt * p[2];
    }
  }
  out[0] = o0;
  out[1] = o1;
  out[2] = o2;
}

/* Resolves rows [y0, y1). The 3x3 neighbourhood reads edge-clamped rows and columns. */
static void tt__vctaa_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const tt__vctaa_job *job = ctx;
  const tt__vctaa_filter *v = job->v;
  const tt__vctaa_params *p = job->p;
  uint32_t w = v->width, h = v->height;
  for (uint32_t y = y0; y < y1; y++) {
    const float *rows[3] = {v->ycocg + (size_t)(y ? y - 1 : 0) * w * 3,
                            v->ycocg + (size_t)y * w * 3,
                            v->ycocg + (size_t)(y + 1 < h ? y + 1 : h - 1) * w * 3};
    for (uint32_t x = 0; x < w; x++) {
      size_t i = (size_t)y * w + x;
      uint32_t xs[3] = {3 * (x ? x - 1 : 0), 3 * x, 3 * (x + 1 < w ? x + 1 : w - 1)};
      float cur[3], m1[3] = {0, 0, 0}, m2[3] = {0, 0, 0};
      for (int dy = 0; dy < 3; dy++)
        for (int dx = 0; dx < 3; dx++) {
          const float *s = rows[dy] + xs[dx];
          for (int c = 0; c < 3; c++) {
            m1[c] += s[c];
            m2[c] += s[c] * s[c];
          }
        }
      memcpy(cur, rows[1] + xs[1], sizeof cur);
      float res[3];
      float mx = job->motion ? job->motion[2 * i] : 0.0f;
      float my = job->motion ? job->motion[2 * i + 1] : 0.0f;
      /* Motion points from this frame back to the previous one (film.h). */
      float hx = (float)x + 0.5f + mx, hy = (float)y + 0.5f + my;
      if (!v->valid || !(hx >= 0.0f && hy >= 0.0f && hx <= (float)w && hy <= (float)h)) {
        /* Disocclusion by the frame border or no history: the current sample alone. */
        memcpy(res, cur, sizeof res);
      } else {
        float hist_rgb[3], hist[3];
        if (p->catmull_rom) tt__vctaa_catmull_rom3(v->history, (int)w, (int)h, hx, hy, hist_rgb);
        else tt__taa_sample_bilinear(v->history, w, h, 3, hx, hy, hist_rgb);
        tt__vctaa_to_ycocg(hist_rgb, hist);
        /* Clip toward the box centre along the line to the mean (not a per-axis clamp), so
         * the clipped colour stays on a plausible hue. */
        float scale = 0.0f, d[3];
        for (int c = 0; c < 3; c++) {
          float mean = m1[c] / 9.0f;
          float sigma = sqrtf(tt__taa_fmax(m2[c] / 9.0f - mean * mean, 0.0f));
          float ext = p->gamma * sigma + 1e-6f;
          d[c] = hist[c] - mean;
          float u = fabsf(d[c]) / ext;
          if (u > scale) scale = u;
          m1[c] = mean;
        }
        if (scale > 1.0f)
          for (int c = 0; c < 3; c++) hist[c] = m1[c] + d[c] / scale;
        for (int c = 0; c < 3; c++) res[c] = hist[c] + p->blend * (cur[c] - hist[c]);
      }
      float rgb[3];
      tt__vctaa_from_ycocg(res, rgb);
      if (p->linear) {
        for (int c = 0; c < 3; c++) rgb[c] = tt__taa_fmax(rgb[c], 0.0f);
        memcpy(v->scratch + 3 * i, rgb, sizeof rgb);
        memcpy(job->out + 3 * i, rgb, sizeof rgb);
        continue;
      }
      for (int c = 0; c < 3; c++) rgb[c] = tt__taa_fmin(tt__taa_fmax(rgb[c], 0.0f), 0.999f);
      memcpy(v->scratch + 3 * i, rgb, sizeof rgb);
      tt__taa_untonemap_inl(rgb, job->out + 3 * i);
    }
  }
}

void tt__vctaa_process(tt__vctaa_filter *v, const tt_host *host, const tt__vctaa_params *p,
                       const float *color, const float *motion, float *out_rgb) {
  tt__vctaa_job job = {v, p, color, motion, out_rgb};
  if (v->linear != p->linear) v->valid = 0; /* the history is in the other space */
  v->linear = p->linear;
  tt__taa_parallel_rows(host, v->height, tt__vctaa_prepare_rows, &job);
  tt__taa_parallel_rows(host, v->height, tt__vctaa_rows, &job);
  float *t = v->history;
  v->history = v->scratch;
  v->scratch = t;
  v->valid = 1;
}
