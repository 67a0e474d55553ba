/* The exact argmax over candidates through approximate bounds (rbf_argmax.h). */
#include "rbf_argmax.h"

#include <math.h>

rbf_qbound_fn *rbf_qbound_pick(void) {
#ifdef RBF_HAVE_AVX2
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return rbf_qbound_avx2;
#endif
  return rbf_qbound_base;
}

size_t rbf_argmax_reference(const rbf_model *r, const double *ds, const double *const *da,
                            size_t n, double *best_q) {
  size_t bi = 0;
  double b = -INFINITY;
  for (size_t k = 0; k < n; k++) {
    double q = rbf_q_parts(r, ds, da[k]);
    if (q > b) b = q, bi = k;
  }
  *best_q = b;
  return bi;
}

size_t rbf_argmax_bounded(const rbf_model *r, const double *ds, const double *const *da,
                          size_t n, rbf_qbound_fn *fn, double *work, double *best_q,
                          size_t *exact) {
  if (!fn) fn = rbf_qbound_pick();
  uint32_t f = r->features;
  double *e = work, *qa = work + f, *tol = qa + n;
  double tabs = 0;
  for (uint32_t i = 0; i < f; i++) tabs += fabs(r->theta[i]);
  const double rel = 1e-11 + 4.0 * (double)f * 0x1p-53;
  const double floor_abs = 1e-300 * tabs + (2.0 * f + 16.0) * 0x1p-1021;
  double lower = -INFINITY;
  int finite = isfinite(tabs);
  for (size_t k = 0; k < n && finite; k++) {
    double qabs;
    fn(r->theta, ds, da[k], f, -r->width, e, &qa[k], &qabs);
    tol[k] = rel * qabs + floor_abs;
    finite = isfinite(qa[k]) && isfinite(tol[k]);
    if (qa[k] - tol[k] > lower) lower = qa[k] - tol[k];
  }
  size_t bi = 0, evaluated = 0;
  double b = -INFINITY;
  for (size_t k = 0; k < n && finite; k++) {
    if (!(qa[k] + tol[k] >= lower)) continue;  /* Q_k < lower <= the best Q */
    double q = rbf_q_parts(r, ds, da[k]);
    evaluated++;
    if (q > b) b = q, bi = k;
  }
  if (!finite || !isfinite(b)) {
    if (exact) *exact = n;
    return rbf_argmax_reference(r, ds, da, n, best_q);
  }
  if (exact) *exact = evaluated;
  *best_q = b;
  return bi;
}
