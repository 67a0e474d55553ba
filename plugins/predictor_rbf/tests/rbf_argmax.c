/* The bounded argmax (plugins/predictor_rbf/rbf_argmax.c) answers exactly what the reference
 * loop of tt__rbf_q_parts answers: the same index and the same bits of Q, on random models with
 * every kernel this CPU runs (the baseline copy and, where the CPU has it, AVX2+FMA).
 *
 * The models cover what could break the bounds or the kernels: feature counts around the
 * kernels' 8-wide blocks (1, 7, 8, 9, 102, 300), widths 0.01-100, centres far outside the
 * unit cube (exponents below -708: the polynomial's clamp), theta of mixed sign over 30
 * decades, exact ties (repeated candidates: the first must win) and near-ties (candidates
 * 1e-15 apart, where the approximation cannot separate them and the exact values must).
 * Also: every kernel is within half its bound of tt__rbf_q_parts on every candidate (the fine
 * kernels within 1e-13 relative to sum |theta e|, the bound assumes 1e-11; a kernel that lost
 * its accuracy fails here before an argmax could), the argmax takes few candidates to the
 * fine level and one to tt__rbf_q_parts on distinct candidates (else it is no faster), and a
 * model whose sums overflow takes the reference loop and still agrees. */
#include "rbf_argmax.h"

#include "tt_test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <tt_util/rng.h>

static double uni(uint64_t *x) { return tt__u64_to_unit(tt__splitmix64(x)); }

typedef struct kernel {
  const char *name;
  tt__rbf_kernels k;
} kernel;

static int kernels(kernel *out) {
  int n = 0;
  const tt__rbf_kernels *base = tt__rbf_kernels_base();
  out[n++] = (kernel){"base", *base};
#ifdef TT__RBF_HAVE_AVX2
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    const tt__rbf_kernels *avx2 = tt__rbf_kernels_avx2();
    out[n++] = (kernel){"avx2", {NULL, avx2->fine}};
    out[n++] = (kernel){"coarse avx2 + avx2", *avx2};
    out[n++] = (kernel){"coarse avx2 + base", {avx2->coarse, base->fine}};
  }
#endif
  return n;
}

static size_t last_fine = SIZE_MAX; /* candidates the coarse level kept, last case */

/* One random model and candidate set; checks every kernel against the reference. Returns
 * the candidates evaluated exactly by the last kernel. */
static size_t one_case(uint64_t *x, uint32_t d, uint32_t m, uint32_t f, double width, double spread,
                       double theta_scale, size_t n, int ties) {
  tt__rbf_model r;
  CHECK(tt__rbf_model_init(&r, d, m, f, width, 0.1, 0, tt__splitmix64(x)) == 0);
  for (size_t i = 0; i < (size_t)f * r.dim; i++) r.centres[i] = 0.5 + spread * (r.centres[i] - 0.5);
  double tabs = 0;
  for (uint32_t i = 0; i < f; i++) {
    /* beyond 1e300: every theta that large, so that the sums overflow */
    r.theta[i] = theta_scale > 1e300 ? theta_scale
                                     : (uni(x) - 0.4) * theta_scale * pow(10.0, 4 * (uni(x) - 0.5));
    tabs += fabs(r.theta[i]);
  }
  double *state = malloc(d * sizeof(double)), *ds = malloc(f * sizeof(double));
  double *acts = malloc(n * m * sizeof(double)), *da = malloc(n * f * sizeof(double));
  const double **rows = malloc(n * sizeof *rows);
  double *work = malloc(tt__rbf_argmax_work(f, n) * sizeof(double));
  uint32_t f8 = tt__rbf_f8(f);
  float *thf = malloc(f8 * sizeof(float)), *dsf = malloc(f8 * sizeof(float));
  float *daf = malloc(n * f8 * sizeof(float));
  const float **frows = malloc(n * sizeof *frows);
  for (uint32_t k = 0; k < d; k++) state[k] = uni(x);
  tt__rbf_state_part(&r, state, ds);
  tt__rbf_action_part_float(f, r.theta, thf);
  tt__rbf_action_part_float(f, ds, dsf);
  for (size_t k = 0; k < n; k++) {
    for (uint32_t j = 0; j < m; j++)
      acts[k * m + j] = uni(x) < 0.3 ? (double)(uni(x) < 0.5) : uni(x);
    if (ties && k > 0 && uni(x) < 0.3) { /* a repeat of an earlier candidate, or 1e-15 from it */
      size_t src = (size_t)(uni(x) * (double)k);
      memcpy(acts + k * m, acts + src * m, m * sizeof(double));
      if (uni(x) < 0.5) acts[k * m] += 1e-15;
    }
    tt__rbf_action_part(&r, acts + k * m, da + k * f);
    tt__rbf_action_part_float(f, da + k * f, daf + k * f8);
    rows[k] = da + k * f;
    frows[k] = daf + k * f8;
  }
  double qref;
  size_t iref = tt__rbf_argmax_reference(&r, ds, rows, n, &qref);
  kernel ks[4];
  int nk = kernels(ks);
  size_t exact = 0;
  for (int kk = 0; kk < nk; kk++) {
    double q;
    tt__rbf_argmax_stats st;
    size_t i = tt__rbf_argmax_bounded(&r, ds, rows, frows, n, &ks[kk].k, work, &q, &st);
    CHECK_MSG(i == iref && memcmp(&q, &qref, sizeof q) == 0,
              "%s, f %u width %g spread %g theta %g n %zu: index %zu Q %.17g, reference %zu %.17g",
              ks[kk].name, f, width, spread, theta_scale, n, i, q, iref, qref);
    CHECK(st.exact >= 1 && st.exact <= n && st.fine <= n);
    if (ks[kk].k.coarse) last_fine = st.fine;
    exact = st.exact;
    /* each kernel's own accuracy, within half its bound */
    double e_scratch[300];
    for (size_t k = 0; k < n && f <= 300 && isfinite(tabs); k++) {
      double qa, qabs, qx, qe = tt__rbf_q_parts(&r, ds, rows[k]);
      if (ks[kk].k.coarse && tabs < 1e34) {
        ks[kk].k.coarse(thf, dsf, frows[k], f8, (float)-width, &qa, &qabs, &qx);
        double tol = tt__rbf_coarse_tol(f, qabs, qx, tabs);
        CHECK_MSG(fabs(qa - qe) <= 0.5 * tol,
                  "%s (coarse): f %u width %g spread %g theta %g "
                  "candidate %zu: %.9g vs %.17g, bound %g",
                  ks[kk].name, f, width, spread, theta_scale, k, qa, qe, tol);
      }
      ks[kk].k.fine(r.theta, ds, rows[k], f, -width, e_scratch, &qa, &qabs);
      /* exponents below -708: both below 3.4e-308 */
      CHECK_MSG(fabs(qa - qe) <= 1e-13 * qabs + 4e-308 * tabs,
                "%s: candidate %zu: %.17g vs %.17g (sum |theta e| %g)", ks[kk].name, k, qa, qe,
                qabs);
    }
  }
  free(state);
  free(ds);
  free(acts);
  free(da);
  free(rows);
  free(work);
  free(thf);
  free(dsf);
  free(daf);
  free(frows);
  tt__rbf_model_free(&r);
  return exact;
}

int main(void) {
  uint64_t x = 2026;
  static const uint32_t fs[] = {1, 7, 8, 9, 102, 300};
  static const double widths[] = {0.01, 1.0, 3.0, 100.0};
  static const double spreads[] = {1.0, 40.0};
  static const double scales[] = {1e-15, 1.0, 1e15};
  size_t distinct_cases = 0, distinct_exact = 0;
  for (size_t a = 0; a < sizeof fs / sizeof fs[0]; a++)
    for (size_t b = 0; b < sizeof widths / sizeof widths[0]; b++)
      for (size_t c = 0; c < sizeof spreads / sizeof spreads[0]; c++)
        for (size_t s = 0; s < sizeof scales / sizeof scales[0]; s++)
          for (int ties = 0; ties < 2; ties++) {
            size_t n = 1 + (size_t)(uni(&x) * 300);
            size_t ex = one_case(&x, 17, 16, fs[a], widths[b], spreads[c], scales[s], n, ties);
            if (!ties && spreads[c] == 1.0 && fs[a] >= 8) distinct_cases++, distinct_exact += ex;
          }
  /* the predictor's shape: 17 state values, 16 action coordinates, 102 features, 257 candidates */
  size_t shape_cases = 0, shape_fine = 0;
  for (int t = 0; t < 200; t++) {
    last_fine = SIZE_MAX;
    size_t ex = one_case(&x, 17, 16, 102, 1.0, 1.0, 1.0, 257, t % 2);
    if (t % 2 == 0) distinct_cases++, distinct_exact += ex;
    if (t % 2 == 0 && last_fine != SIZE_MAX) shape_cases++, shape_fine += last_fine;
  }
  printf("distinct candidates: %.2f evaluated exactly per argmax (%zu argmaxes)\n",
         (double)distinct_exact / (double)distinct_cases, distinct_cases);
  if (shape_cases) { /* the coarse level ran: it must leave few of the 257 to the fine one */
    printf("coarse level: %.2f of 257 candidates reach the fine level (%zu argmaxes)\n",
           (double)shape_fine / (double)shape_cases, shape_cases);
    CHECK_MSG(shape_fine <= 16 * shape_cases, "%zu in %zu argmaxes", shape_fine, shape_cases);
  }
  CHECK_MSG(distinct_exact <= 2 * distinct_cases, "%zu exact evaluations in %zu argmaxes",
            distinct_exact, distinct_cases);
  /* sums beyond the double range: the reference loop, the same answer */
  one_case(&x, 3, 4, 16, 1.0, 1.0, 1e308, 40, 0);
  return tt_test_finish("rbf_argmax");
}
