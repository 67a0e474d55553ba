/* Keyframe tracks (scene/anim.h): step, linear (slerp for rotations) and cubic Hermite
 * interpolation as glTF 2.0 defines them, so files from glTF and scene.json keys evaluate
 * alike. */
#include "scene/anim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

tt_status tt__track_alloc(tt__track *t, uint32_t count, uint32_t dim, tt__interp interp) {
  memset(t, 0, sizeof *t);
  t->count = count;
  t->dim = dim;
  t->interp = interp;
  size_t n = (size_t)count * dim;
  t->times = malloc(sizeof(double) * (count ? count : 1));
  t->values = malloc(sizeof(float) * (n ? n : 1));
  if (interp == TT__INTERP_CUBIC) {
    t->in_tan = calloc(n ? n : 1, sizeof(float));
    t->out_tan = calloc(n ? n : 1, sizeof(float));
  }
  if (!t->times || !t->values || (interp == TT__INTERP_CUBIC && (!t->in_tan || !t->out_tan))) {
    tt__track_free(t);
    return TT_ERR_OUT_OF_MEMORY;
  }
  return TT_OK;
}

void tt__track_free(tt__track *t) {
  if (!t) return;
  free(t->times);
  free(t->values);
  free(t->in_tan);
  free(t->out_tan);
  memset(t, 0, sizeof *t);
}

void tt__track_align_rotations(tt__track *t) {
  if (!t->rotation || t->dim != 4) return;
  for (uint32_t k = 1; k < t->count; k++) {
    float *a = t->values + 4 * (size_t)(k - 1), *b = t->values + 4 * (size_t)k;
    double d =
        (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2] + (double)a[3] * b[3];
    if (d < 0)
      for (int i = 0; i < 4; i++) b[i] = -b[i];
  }
}

/* The camera path's tangents (scene.c, tt__hermite), per second instead of per segment. */
void tt__track_catmull_rom(tt__track *t) {
  if (t->interp != TT__INTERP_CUBIC || !t->in_tan) return;
  tt__track_align_rotations(t);
  const uint32_t n = t->count, d = t->dim;
  for (uint32_t k = 0; k < n; k++) {
    uint32_t a = k > 0 ? k - 1 : k, b = k + 1 < n ? k + 1 : k;
    double dt = t->times[b] - t->times[a];
    for (uint32_t i = 0; i < d; i++) {
      double m =
          dt > 0 ? ((double)t->values[(size_t)b * d + i] - t->values[(size_t)a * d + i]) / dt : 0.0;
      t->in_tan[(size_t)k * d + i] = t->out_tan[(size_t)k * d + i] = (float)m;
    }
  }
}

/* Index k of the last key with times[k] <= time (0 <= k < count - 1 for an interior time). */
static uint32_t tt__track_find(const tt__track *t, double time) {
  uint32_t lo = 0, hi = t->count - 1; /* times[lo] <= time < times[hi] */
  while (hi - lo > 1) {
    uint32_t mid = lo + (hi - lo) / 2;
    if (t->times[mid] <= time) lo = mid;
    else hi = mid;
  }
  return lo;
}

/* Unit quaternion, or identity if it has no length. */
static void tt__quat_normalize(float *q) {
  double l =
      sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3]);
  if (!(l > 0) || !isfinite(l)) {
    q[0] = q[1] = q[2] = 0.0f;
    q[3] = 1.0f;
    return;
  }
  for (int i = 0; i < 4; i++) q[i] = (float)(q[i] / l);
}

/* Spherical interpolation along the shorter arc (glTF's LINEAR for rotations). */
static void tt__slerp(const float *a, const float *b, double s, float *out) {
  double d = (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2] + (double)a[3] * b[3];
  double sign = d < 0 ? -1.0 : 1.0;
  d *= sign;
  double wa, wb;
  if (d > 0.9995) { /* nearly parallel: lerp, normalised below */
    wa = 1.0 - s;
    wb = s;
  } else {
    double th = acos(d), st = sin(th);
    wa = sin((1.0 - s) * th) / st;
    wb = sin(s * th) / st;
  }
  for (int i = 0; i < 4; i++) out[i] = (float)(wa * a[i] + wb * sign * b[i]);
  tt__quat_normalize(out);
}

void tt__track_eval(const tt__track *t, double time, float *out) {
  const uint32_t d = t->dim;
  if (t->count == 0) return;
  if (t->count == 1 || !(time > t->times[0])) {
    memcpy(out, t->values, sizeof(float) * d);
    return;
  }
  if (time >= t->times[t->count - 1]) {
    memcpy(out, t->values + (size_t)(t->count - 1) * d, sizeof(float) * d);
    return;
  }
  uint32_t k = tt__track_find(t, time);
  const float *a = t->values + (size_t)k * d, *b = a + d;
  double dt = t->times[k + 1] - t->times[k], s = (time - t->times[k]) / dt;
  switch (t->interp) {
  case TT__INTERP_STEP: memcpy(out, a, sizeof(float) * d); return;
  case TT__INTERP_LINEAR:
    if (t->rotation && d == 4) {
      tt__slerp(a, b, s, out);
      return;
    }
    for (uint32_t i = 0; i < d; i++) out[i] = (float)((1.0 - s) * a[i] + s * (double)b[i]);
    return;
  case TT__INTERP_CUBIC: {
    const float *m0 = t->out_tan + (size_t)k * d, *m1 = t->in_tan + (size_t)(k + 1) * d;
    double s2 = s * s, s3 = s2 * s;
    double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    for (uint32_t i = 0; i < d; i++)
      out[i] = (float)(h00 * a[i] + h10 * dt * m0[i] + h01 * b[i] + h11 * dt * m1[i]);
    if (t->rotation && d == 4) tt__quat_normalize(out);
    return;
  }
  }
}
