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
 * The per-pixel test is tt__taa_reject_test (taa_internal.h), which the fast path also
 * runs inside its reprojection pass; tools/taa/rejection.py computes the same masks with
 * the same float operations (training data, golden fixture). */
#include <string.h>

#include "taa_internal.h"

typedef struct tt__taa_reject_job {
  uint32_t w, h;
  const float *dprev, *zprev, *motion;
  float jx, jy, pjx, pjy;
  uint8_t *mask;
} tt__taa_reject_job;

/* The per-pixel tests of rows [y0, y1). */
static void tt__taa_reject_test_rows(void *ctx, uint32_t y0, uint32_t y1) {
  const tt__taa_reject_job *j = ctx;
  for (uint32_t y = y0; y < y1; y++)
    for (uint32_t x = 0; x < j->w; x++) {
      size_t i = (size_t)y * j->w + x;
      float mx = j->motion ? j->motion[2 * i] : 0.0f, my = j->motion ? j->motion[2 * i + 1] : 0.0f;
      j->mask[i] = tt__taa_reject_test(j->zprev ? j->dprev : NULL, j->w, j->h, j->pjx, j->pjy,
                                       j->zprev ? j->zprev[i] : 0.0f, x, y, mx, my, j->jx, j->jy);
    }
}

void tt__taa_reject_open(uint32_t width, uint32_t height, uint8_t *mask, uint8_t *tmp) {
  const size_t w = width, h = height;
  /* Separable 3 x 3 erosion of FAR into tmp (bit 0), edge pixels replicated: rows, then
   * columns in place; then the dilation the same way into RESET. Byte loops (vectorised by
   * the compiler); a few hundred microseconds at 640 x 480. */
  for (size_t y = 0; y < h; y++) {
    const uint8_t *m = mask + y * w;
    uint8_t *t = tmp + y * w;
    for (size_t x = 0; x < w; x++) {
      size_t a = x ? x - 1 : 0, b = x + 1 < w ? x + 1 : w - 1;
      t[x] = (uint8_t)((m[a] & m[x] & m[b] & TT__TAA_REJECT_FAR) ? 1 : 0);
    }
  }
  for (int pass = 0; pass < 3; pass++) {
    /* pass 0: erosion down the columns (tmp -> bit 1 of tmp); pass 1: dilation along the
     * rows (bit 1 -> bit 2); pass 2: dilation down the columns (bit 2 -> RESET) */
    for (size_t y = 0; y < h; y++) {
      size_t ya = y ? y - 1 : 0, yb = y + 1 < h ? y + 1 : h - 1;
      uint8_t *t = tmp + y * w;
      if (pass == 0) {
        const uint8_t *ta = tmp + ya * w, *tb = tmp + yb * w;
        for (size_t x = 0; x < w; x++) t[x] |= (uint8_t)((ta[x] & t[x] & tb[x] & 1) << 1);
      } else if (pass == 1) {
        for (size_t x = 0; x < w; x++) {
          size_t a = x ? x - 1 : 0, b = x + 1 < w ? x + 1 : w - 1;
          t[x] |= (uint8_t)(((t[a] | t[x] | t[b]) & 2) << 1);
        }
      } else {
        const uint8_t *ta = tmp + ya * w, *tb = tmp + yb * w;
        uint8_t *m = mask + y * w;
        for (size_t x = 0; x < w; x++) {
          int d = ((ta[x] | t[x] | tb[x]) & 4) != 0;
          m[x] = (uint8_t)(m[x] | ((d || (m[x] & TT__TAA_REJECT_OFF)) ? TT__TAA_REJECT_RESET : 0u));
        }
      }
    }
  }
}

void tt__taa_reject_masks(const tt_host *host, uint32_t width, uint32_t height, const float *dprev,
                          const float jitter_prev[2], const float *zprev, const float *motion,
                          const float jitter[2], uint8_t *mask, uint8_t *tmp) {
  tt__taa_reject_job j = {.w = width,
                          .h = height,
                          .dprev = dprev,
                          .zprev = zprev,
                          .motion = motion,
                          .jx = jitter[0],
                          .jy = jitter[1],
                          .pjx = jitter_prev[0],
                          .pjy = jitter_prev[1],
                          .mask = mask};
  if (!dprev) j.zprev = NULL;
  tt__taa_parallel_rows(host, height, tt__taa_reject_test_rows, &j);
  tt__taa_reject_open(width, height, mask, tmp);
}
