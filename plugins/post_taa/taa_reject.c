/* post_taa: history rejection for the network (README.md, "History rejection").
 *
 * Pixel p of the frame sees a point that sat at q = p + 0.5 + jitter + motion in the
 * previous frame (film coordinates: the host's motion vectors run from the jittered sample
 * position back to the previous camera). The previous frame sampled its pixel i at
 * i + 0.5 + jitter_prev, so the 2 x 2 pixels i0 = floor(q - 0.5 - jitter_prev), i0 + 1 per
 * axis are the samples around q, and for a plane (1/z affine on the film) the depth at q
 * lies within their range. With z' the prevdepth AOV (the depth the point had in the
 * previous camera), the history is disoccluded when z' > max(those 4 depths) * (1 + TOL):
 * the previous frame saw only nearer surfaces there, an occluder (sky, depth 0, is
 * infinitely far: never nearer). The opposite mismatch cannot happen to a visible point of
 * a static scene; it is thin geometry aliasing between jitter positions, and that history
 * is what TAA accumulates, so it is kept.
 *   RAW   = off-screen (q outside the previous frame) or disoccluded: the network's input
 *   RESET = off-screen, or disoccluded in a region that holds a 3 x 3 square (3 x 3 opening,
 *           edge pixels replicated): one- or two-pixel flags on aliasing thin geometry
 *           keep their history
 * tools/taa/rejection.py computes the same masks with the same float operations (training
 * data, golden fixture). */
#include <math.h>
#include <string.h>

#include "taa_internal.h"

#define FAR 4u    /* scratch bit: disoccluded (before the opening) */
#define OFF 8u    /* scratch bit: off-screen */

typedef struct reject_job {
  uint32_t w, h;
  const float *dprev, *zprev, *motion;
  float jx, jy, pjx, pjy;
  uint8_t *mask, *a, *b;  /* output; scratch: FAR | OFF bits, eroded FAR */
} reject_job;

/* Pass 1: the per-pixel tests into a (FAR, OFF bits). */
static void reject_test_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const reject_job *j = ctx;
  const uint32_t w = j->w, h = j->h;
  for (uint32_t y = y0; y < y1; y++)
    for (uint32_t x = 0; x < w; x++) {
      size_t i = (size_t)y * w + x;
      float mx = j->motion ? j->motion[2 * i] : 0.0f, my = j->motion ? j->motion[2 * i + 1] : 0.0f;
      float qx = ((float)x + 0.5f + j->jx) + mx, qy = ((float)y + 0.5f + j->jy) + my;
      if (!(qx >= 0.0f && qx < (float)w && qy >= 0.0f && qy < (float)h)) {
        j->a[i] = OFF;  /* also NaN motion */
        continue;
      }
      uint8_t bits = 0;
      if (j->dprev && j->zprev) {
        int ix = (int)floorf((qx - 0.5f) - j->pjx), iy = (int)floorf((qy - 0.5f) - j->pjy);
        float hi = -INFINITY;
        int sky = 0;
        for (int dy = 0; dy < 2; dy++)
          for (int dx = 0; dx < 2; dx++) {
            int tx = ix + dx, ty = iy + dy;
            tx = tx < 0 ? 0 : tx >= (int)w ? (int)w - 1 : tx;
            ty = ty < 0 ? 0 : ty >= (int)h ? (int)h - 1 : ty;
            float d = j->dprev[(size_t)ty * w + (size_t)tx];
            if (d > 0.0f) hi = d > hi ? d : hi;
            else sky = 1;  /* sky (or a non-finite depth): farther than anything */
          }
        float z = j->zprev[i];
        if (!sky && (!(z > 0.0f) || z > hi * (1.0f + TT__TAA_REJECT_TOL))) bits = FAR;
      }
      j->a[i] = bits;
    }
}

/* Pass 2: 3 x 3 erosion of FAR into b (edge pixels replicated). */
static void reject_erode_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const reject_job *j = ctx;
  const int w = (int)j->w, h = (int)j->h;
  for (int y = (int)y0; y < (int)y1; y++)
    for (int x = 0; x < w; x++) {
      uint8_t all = 1;
      for (int dy = -1; dy <= 1 && all; dy++)
        for (int dx = -1; dx <= 1; dx++) {
          int tx = x + dx < 0 ? 0 : x + dx >= w ? w - 1 : x + dx;
          int ty = y + dy < 0 ? 0 : y + dy >= h ? h - 1 : y + dy;
          if (!(j->a[(size_t)ty * w + tx] & FAR)) {
            all = 0;
            break;
          }
        }
      j->b[(size_t)y * w + x] = all;
    }
}

/* Pass 3: dilation of b, and the output bits. */
static void reject_out_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const reject_job *j = ctx;
  const int w = (int)j->w, h = (int)j->h;
  for (int y = (int)y0; y < (int)y1; y++)
    for (int x = 0; x < w; x++) {
      size_t i = (size_t)y * w + x;
      uint8_t any = 0;
      for (int dy = -1; dy <= 1 && !any; dy++)
        for (int dx = -1; dx <= 1; dx++) {
          int tx = x + dx < 0 ? 0 : x + dx >= w ? w - 1 : x + dx;
          int ty = y + dy < 0 ? 0 : y + dy >= h ? h - 1 : y + dy;
          if (j->b[(size_t)ty * w + tx]) {
            any = 1;
            break;
          }
        }
      uint8_t a = j->a[i];
      j->mask[i] = (uint8_t)(((a & (FAR | OFF)) ? TT__TAA_REJECT_RAW : 0u) |
                             ((any || (a & OFF)) ? TT__TAA_REJECT_RESET : 0u));
    }
}

void tt__taa_reject_masks(const tt_host *host, uint32_t width, uint32_t height,
                          const float *dprev, const float jitter_prev[2], const float *zprev,
                          const float *motion, const float jitter[2], uint8_t *mask,
                          uint8_t *tmp) {
  size_t n = (size_t)width * height;
  reject_job j = {.w = width, .h = height, .dprev = dprev, .zprev = zprev, .motion = motion,
                  .jx = jitter[0], .jy = jitter[1], .pjx = jitter_prev[0],
                  .pjy = jitter_prev[1], .mask = mask, .a = tmp, .b = tmp + n};
  tt__taa_parallel_rows(host, height, reject_test_rows, &j);
  tt__taa_parallel_rows(host, height, reject_erode_rows, &j);
  tt__taa_parallel_rows(host, height, reject_out_rows, &j);
}
