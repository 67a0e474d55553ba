/* post_taa: image helpers shared by VCTAA and the network: row-parallel loops, the
 * Reinhard-max tonemap, Catmull-Rom / bilinear history fetches and the CPU clock of the
 * stage timings. */
#include <math.h>
#include <time.h>

#include "taa_internal.h"

#include <tt_util/clock.h>

double tt__taa_cpu_ms(void) { return tt__process_cpu_ms(); }

typedef struct tt__taa_rows_job {
  tt__taa_rows_fn fn;
  void *ctx;
  uint32_t height;
} tt__taa_rows_job;

/* Adapts parallel_for's index ranges (rows) to the row callback. */
static void tt__taa_rows_body(void *ctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  (void)thread_index;
  const tt__taa_rows_job *job = ctx;
  job->fn(job->ctx, (uint32_t)begin, (uint32_t)end);
}

void tt__taa_parallel_rows(const tt_host *host, uint32_t height, tt__taa_rows_fn fn, void *ctx) {
  /* Small frames are not worth the pool's wake-up cost. */
  if (!host || !host->parallel_for || height < 16) {
    fn(ctx, 0, height);
    return;
  }
  tt__taa_rows_job job = {fn, ctx, height};
  /* Several bands per thread so dynamic scheduling evens out uneven rows. */
  uint64_t grain = height / (8u * (host->thread_count ? host->thread_count() : 1u));
  if (grain < 4) grain = 4;
  if (host->parallel_for(height, grain, tt__taa_rows_body, &job) != TT_OK) {
    /* Interrupted: finish serially so the frame stays consistent. */
    fn(ctx, 0, height);
  }
}

void tt__taa_tonemap(const float in[3], float out[3]) { tt__taa_tonemap_inl(in, out); }

void tt__taa_untonemap(const float in[3], float out[3]) { tt__taa_untonemap_inl(in, out); }

/* Clamps a tap index to [0, n - 1]. */
static inline int tt__taa_clampi(int i, int n) { return i < 0 ? 0 : (i >= n ? n - 1 : i); }

void tt__taa_sample_catmull_rom(const float *img, uint32_t width, uint32_t height,
                                uint32_t channels, float fx, float fy, float *out) {
  float ux = fx - 0.5f, uy = fy - 0.5f;
  float bx = floorf(ux), by = floorf(uy);
  float wx[4], wy[4];
  tt__taa_cr_weights(ux - bx, wx);
  tt__taa_cr_weights(uy - by, wy);
  int x0 = (int)bx - 1, y0 = (int)by - 1;
  int xi[4];
  for (int i = 0; i < 4; i++) xi[i] = tt__taa_clampi(x0 + i, (int)width);
  for (uint32_t c = 0; c < channels; c++) out[c] = 0.0f;
  for (int j = 0; j < 4; j++) {
    const float *row = img + (size_t)tt__taa_clampi(y0 + j, (int)height) * width * channels;
    for (int i = 0; i < 4; i++) {
      const float *p = row + (size_t)xi[i] * channels;
      float w = wx[i] * wy[j];
      for (uint32_t c = 0; c < channels; c++) out[c] += w * p[c];
    }
  }
}

void tt__taa_sample_bilinear(const float *img, uint32_t width, uint32_t height, uint32_t channels,
                             float fx, float fy, float *out) {
  float ux = fx - 0.5f, uy = fy - 0.5f;
  float bx = floorf(ux), by = floorf(uy);
  float tx = ux - bx, ty = uy - by;
  int x0 = tt__taa_clampi((int)bx, (int)width), x1 = tt__taa_clampi((int)bx + 1, (int)width);
  int y0 = tt__taa_clampi((int)by, (int)height), y1 = tt__taa_clampi((int)by + 1, (int)height);
  const float *p00 = img + ((size_t)y0 * width + x0) * channels;
  const float *p10 = img + ((size_t)y0 * width + x1) * channels;
  const float *p01 = img + ((size_t)y1 * width + x0) * channels;
  const float *p11 = img + ((size_t)y1 * width + x1) * channels;
  for (uint32_t c = 0; c < channels; c++) {
    float a = p00[c] + tx * (p10[c] - p00[c]);
    float b = p01[c] + tx * (p11[c] - p01[c]);
    out[c] = a + ty * (b - a);
  }
}
