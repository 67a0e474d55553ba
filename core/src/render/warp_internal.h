/* tunetrace internal: warps of the unit square used by the BSDFs and the lights (pbrt-v4's
 * sampling.h, Shirley-Chiu's concentric map). Written once so that a material's cosine lobe
 * and an emitter's cosine-weighted directions are the same mapping of the same samples. */
#ifndef TT_WARP_INTERNAL_H
#define TT_WARP_INTERNAL_H

#include <math.h>

/* Concentric map of the unit square onto the unit disk (Shirley-Chiu): (x, y) with
 * x^2 + y^2 <= 1, area-preserving up to a constant. */
static inline void tt__concentric_disk(float u1, float u2, float *x, float *y) {
  const float pi = 3.14159265358979324f;
  float a = 2.0f * u1 - 1.0f, b = 2.0f * u2 - 1.0f, r, phi;
  if (a == 0.0f && b == 0.0f) {
    *x = *y = 0.0f;
    return;
  }
  if (fabsf(a) > fabsf(b)) {
    r = a;
    phi = (pi / 4.0f) * (b / a);
  } else {
    r = b;
    phi = (pi / 2.0f) - (pi / 4.0f) * (a / b);
  }
  *x = r * cosf(phi);
  *y = r * sinf(phi);
}

/* Cosine-weighted direction of the hemisphere z >= 0 (the disk lifted, Malley's method);
 * its density is cos(theta) / pi. */
static inline void tt__cosine_hemisphere(float u1, float u2, float out[3]) {
  tt__concentric_disk(u1, u2, &out[0], &out[1]);
  out[2] = sqrtf(fmaxf(0.0f, 1.0f - out[0] * out[0] - out[1] * out[1]));
}

#endif /* TT_WARP_INTERNAL_H */
