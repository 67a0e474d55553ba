/* The exact argmax over candidates through approximate bounds (rbf_argmax.h). */
#include "rbf_argmax.h"

#include <math.h>

tt__rbf_kernels tt__rbf_kernels_pick(void) {
#ifdef TT__RBF_HAVE_AVX2
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    return *tt__rbf_kernels_avx2();
#endif
  return *tt__rbf_kernels_base();
}

size_t tt__rbf_argmax_work(uint32_t features, size_t n) {
  /* e (F), qa and tol (2n), the survivors' indices (n), theta and ds as floats (2 x F8) */
  return (size_t)features + 3 * n + tt__rbf_f8(features) + 1;
}

void tt__rbf_action_part_float(uint32_t features, const double *da, float *daf) {
  uint32_t i = 0;
  for (; i < features; i++) daf[i] = (float)da[i];
  for (; i < tt__rbf_f8(features); i++) daf[i] = 0.0f;
}

double tt__rbf_fine_tol(uint32_t features, double qabs, double theta_abs) {
  return (1e-11 + 4.0 * (double)features * 0x1p-53) * qabs + 1e-300 * theta_abs +
         (2.0 * features + 16.0) * 0x1p-1021;
}

double tt__rbf_coarse_tol(uint32_t features, double qabs, double qx, double theta_abs) {
  return (2e-6 + 1.2e-7 * ((double)features / 8.0 + 4.0)) * qabs + 5e-7 * qx + 1e-37 * theta_abs +
         (3.0 * features + 16.0) * 0x1p-125;
}

size_t tt__rbf_argmax_reference(const tt__rbf_model *r, const double *ds, const double *const *da,
                                size_t n, double *best_q) {
  size_t bi = 0;
  double b = -INFINITY;
  for (size_t k = 0; k < n; k++) {
    double q = tt__rbf_q_parts(r, ds, da[k]);
    if (q > b) b = q, bi = k;
  }
  *best_q = b;
  return bi;
}

size_t tt__rbf_argmax_bounded(const tt__rbf_model *r, const double *ds, const double *const *da,
                              const float *const *daf, size_t n, const tt__rbf_kernels *kernels,
                              double *work, double *best_q, tt__rbf_argmax_stats *stats) {
  tt__rbf_kernels kk = kernels ? *kernels : tt__rbf_kernels_pick();
  uint32_t f = r->features;
  double *e = work, *qa = work + f, *tol = qa + n;
  size_t *live = (size_t *)(tol + n);
  uint32_t f8 = tt__rbf_f8(f);
  float *thf = (float *)(live + n), *dsf = thf + f8;
  double tabs = 0;
  for (uint32_t i = 0; i < f; i++) tabs += fabs(r->theta[i]);
  int finite = isfinite(tabs);
  size_t nlive = 0;
  /* level 1, single precision: only where its bound is valid (theta and every sum within
   * the float range, the float sums' error bound below 1e-4) */
  int coarse = finite && kk.coarse && daf && f <= 8192 && tabs < 1e34;
  if (coarse) {
    tt__rbf_action_part_float(f, r->theta, thf); /* the same conversion and padding */
    tt__rbf_action_part_float(f, ds, dsf);
    double lower = -INFINITY;
    for (size_t k = 0; k < n && coarse; k++) {
      double qabs, qx;
      kk.coarse(thf, dsf, daf[k], f8, (float)-r->width, &qa[k], &qabs, &qx);
      tol[k] = tt__rbf_coarse_tol(f, qabs, qx, tabs);
      coarse = isfinite(qa[k]) && isfinite(tol[k]);
      if (qa[k] - tol[k] > lower) lower = qa[k] - tol[k];
    }
    for (size_t k = 0; k < n && coarse; k++)
      if (qa[k] + tol[k] >= lower) live[nlive++] = k; /* else Q_k < lower <= the best Q */
  }
  if (!coarse)
    for (nlive = 0; nlive < n; nlive++) live[nlive] = nlive;
  /* level 2, the polynomial kernel, on what level 1 kept */
  double lower = -INFINITY;
  for (size_t j = 0; j < nlive && finite; j++) {
    size_t k = live[j];
    double qabs;
    kk.fine(r->theta, ds, da[k], f, -r->width, e, &qa[k], &qabs);
    tol[k] = tt__rbf_fine_tol(f, qabs, tabs);
    finite = isfinite(qa[k]) && isfinite(tol[k]);
    if (qa[k] - tol[k] > lower) lower = qa[k] - tol[k];
  }
  /* level 3, tt__rbf_q_parts itself, in candidate order (live is increasing) */
  size_t bi = 0, exact = 0;
  double b = -INFINITY;
  for (size_t j = 0; j < nlive && finite; j++) {
    size_t k = live[j];
    if (!(qa[k] + tol[k] >= lower)) continue;
    double q = tt__rbf_q_parts(r, ds, da[k]);
    exact++;
    if (q > b) b = q, bi = k;
  }
  if (!finite || !isfinite(b)) {
    if (stats) stats->fine = 0, stats->exact = n;
    return tt__rbf_argmax_reference(r, ds, da, n, best_q);
  }
  if (stats) stats->fine = nlive, stats->exact = exact;
  *best_q = b;
  return bi;
}
