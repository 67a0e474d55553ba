/* integrator_pssmlt's chain core (plugins/integrator_pssmlt/pssmlt_chain.c), compiled into
 * the test: the normal quantile, the truncated normal's sampler against its pdf (chi-square)
 * and against a brute-force numerical density, eq. 4.7 (the symmetric case reduces to the
 * classic ratio), the bin edges of eq. 4.2-4.3, and detailed balance of the whole chain with
 * per-state sigma on a toy target whose marginals are known: chains started exactly in the
 * target must still be in it after 40 steps (chi-square), for the one-by-one and the
 * composite catch-up and for classic mode; dropping the Hastings factor must fail. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pssmlt_chain.h"
#include "tt_test.h"

#define PI 3.14159265358979323846

/* Standard normal CDF. */
static double phi_cdf(double x) { return 0.5 * erfc(-x / sqrt(2.0)); }

/* Chi-square statistic of observed counts against expected probabilities. */
static double chi2(const double *obs, const double *prob, int k, double n) {
  double s = 0.0;
  for (int i = 0; i < k; ++i) {
    double e = prob[i] * n;
    s += (obs[i] - e) * (obs[i] - e) / e;
  }
  return s;
}

/* A generous but sharp bound: dof + 5 sqrt(2 dof) (false alarm < 1e-5). */
static double chi2_bound(int dof) { return dof + 5.0 * sqrt(2.0 * dof); }

/* ---- truncated normal ---- */

/* CDF of N(0, sigma) truncated to [-0.5, 0.5], straight from erf. */
static double tn_cdf(double sigma, double x) {
  double lo = phi_cdf(-0.5 / sigma), hi = phi_cdf(0.5 / sigma);
  return (phi_cdf(x / sigma) - lo) / (hi - lo);
}

static void test_quantile(void) {
  double worst = 0.0;
  const double ps[] = {1e-300, 1e-100, 1e-20, 1e-9, 1e-4, 0.01, 0.02425,
                       0.1,    0.3,    0.5,   0.7,  0.9,  0.99, 1 - 1e-9};
  for (size_t i = 0; i < sizeof ps / sizeof ps[0]; ++i) {
    double x = tt__mlt_normal_quantile(ps[i]);
    /* compare in the nearer tail: 1 - p is exact for p >= 0.5 */
    double back = ps[i] < 0.5 ? phi_cdf(x) : phi_cdf(-x);
    double ref = ps[i] < 0.5 ? ps[i] : 1.0 - ps[i];
    double rel = fabs(back - ref) / ref;
    if (rel > worst) worst = rel;
  }
  printf("normal quantile: worst relative round-trip error %.2e\n", worst);
  CHECK(worst < 1e-8);
  CHECK(tt__mlt_normal_quantile(0.5) == 0.0);
}

static void test_tn_histogram(void) {
  const double sigmas[] = {0.01, 0.1, 0.3, 1.0};
  tt__mlt_rng rng;
  tt__mlt_rng_seed(&rng, 7, 1);
  enum { K = 50, N = 200000 };
  for (int s = 0; s < 4; ++s) {
    double sg = sigmas[s], edges[K + 1], obs[K], prob[K];
    /* equal-probability bins from the erf CDF by bisection (independent of the sampler) */
    edges[0] = -0.5;
    edges[K] = 0.5;
    for (int k = 1; k < K; ++k) {
      double lo = -0.5, hi = 0.5;
      for (int it = 0; it < 100; ++it) {
        double mid = 0.5 * (lo + hi);
        if (tn_cdf(sg, mid) < (double)k / K) lo = mid;
        else hi = mid;
      }
      edges[k] = 0.5 * (lo + hi);
    }
    for (int k = 0; k < K; ++k) {
      obs[k] = 0;
      prob[k] = tn_cdf(sg, edges[k + 1]) - tn_cdf(sg, edges[k]);
    }
    int outside = 0;
    for (int i = 0; i < N; ++i) {
      double x = tt__mlt_tn_sample(sg, tt__mlt_rng_unit(&rng));
      outside += !(x >= -0.5 && x <= 0.5);
      int lo = 0, hi = K;
      while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (x >= edges[mid]) lo = mid;
        else hi = mid;
      }
      obs[lo]++;
    }
    double c = chi2(obs, prob, K, N);
    printf("truncated normal sigma %.2f: chi2 %.1f (dof %d, bound %.1f)\n", sg, c, K - 1,
           chi2_bound(K - 1));
    CHECK_MSG(c < chi2_bound(K - 1), "sigma %g chi2 %g", sg, c);
    CHECK(outside == 0);
    /* The density is the derivative of the sampler's inverse CDF. */
    double worst = 0.0;
    for (double xi = 0.05; xi < 0.96; xi += 0.05) {
      double h = 1e-6, x0 = tt__mlt_tn_sample(sg, xi - h), x1 = tt__mlt_tn_sample(sg, xi + h);
      double num = 2.0 * h / (x1 - x0), ana = tt__mlt_tn_pdf(sg, tt__mlt_tn_sample(sg, xi));
      double rel = fabs(num - ana) / ana;
      if (rel > worst) worst = rel;
    }
    CHECK_MSG(worst < 1e-4, "sigma %g: pdf vs sampler derivative %.2e", sg, worst);
  }
  /* Extremes stay in the support and are finite. */
  CHECK(tt__mlt_tn_sample(0.01, 0.0) == -0.5);
  CHECK(fabs(tt__mlt_tn_sample(0.01, 0x1.fffffffffffffp-1)) <= 0.5);
  CHECK(tt__mlt_tn_sample(0.2, 0.5) == 0.0);
}

/* Brute force: the truncated normal density normalised by Simpson integration. */
static double brute_density(double sigma, double d) {
  enum { N = 20000 };
  double acc = 0.0;
  for (int i = 0; i <= N; ++i) {
    double x = -0.5 + (double)i / N, w = (i == 0 || i == N) ? 1 : (i & 1) ? 4 : 2;
    acc += w * exp(-0.5 * x * x / (sigma * sigma));
  }
  acc /= 3.0 * N;
  return exp(-0.5 * d * d / (sigma * sigma)) / acc;
}

static void test_ratio(void) {
  /* symmetric case: the sigma factor is exactly 1, the classic ratio C(y)/C(x) remains */
  const double ds[] = {-0.5, -0.21, -0.003, 0.0, 0.07, 0.4999};
  const double ss[] = {1e-4, 0.01, 0.07, 0.3};
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 4; ++j)
      for (double n = 1; n <= 16; n *= 4)
        CHECK(tt__mlt_tn_log_ratio(ds[i], ss[j], ss[j], n) == 0.0);
  /* non-symmetric case against brute-force transition densities T(p->c) / T(c->p) */
  double worst = 0.0;
  const double pairs[][2] = {{0.01, 0.3}, {0.3, 0.01}, {0.05, 0.2}, {0.2, 0.8}, {0.1, 0.1001}};
  for (int p = 0; p < 5; ++p)
    for (int i = 0; i < 6; ++i) {
      double sc = pairs[p][0], sp = pairs[p][1], d = ds[i] * 0.3;
      double brute = log(brute_density(sp, d)) - log(brute_density(sc, d));
      double got = tt__mlt_tn_log_ratio(d, sc, sp, 1.0);
      double exact_pdf = log(tt__mlt_tn_pdf(sp, d) / tt__mlt_tn_pdf(sc, d));
      worst = fmax(worst, fabs(got - brute));
      CHECK_NEAR(got, exact_pdf, 1e-9 * fmax(1.0, fabs(got)));
      /* n_s steps modelled as one truncated normal of sigma*sqrt(n_s) (the thesis' form) */
      double b3 = log(brute_density(sp * sqrt(3.0), d)) - log(brute_density(sc * sqrt(3.0), d));
      CHECK_NEAR(tt__mlt_tn_log_ratio(d, sc, sp, 3.0), b3, 1e-6 * fmax(1.0, fabs(b3)));
    }
  printf("eq. 4.7 vs brute-force densities: worst |log ratio difference| %.2e\n", worst);
  CHECK(worst < 1e-6);
}

static void test_edges(void) {
  const double a[6] = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  double e[TT__MLT_SLOTS];
  tt__mlt_edges(a, 5, e);
  double s = 0.1 + 0.2 + 0.3 + 0.4 + 0.5 + 0.6;
  CHECK(e[0] == 0.0);
  CHECK_NEAR(e[1], 0.1 / s, 1e-15);
  CHECK_NEAR(e[2], (0.1 + 0.2) / s, 1e-15);
  CHECK_NEAR(e[3], (0.1 + 0.2 + 0.3) / s, 1e-15);
  CHECK_NEAR(e[4], (0.1 + 0.2 + 0.3 + 0.4) / s, 1e-15);
  CHECK(e[5] == 1.0);
  tt__mlt_kernel k;
  const double sig[5] = {0.001, 0.002, 0.003, 0.004, 0.005};
  tt__mlt_kernel_init(&k, 0.01, 0.3, 1, 5, 4.0 * PI, a, sig);
  CHECK(tt__mlt_bin_of_theta(&k, 0.0) == 1);
  CHECK(tt__mlt_bin_of_theta(&k, e[1]) == 2); /* [A_{i-1}, A_i): left-closed */
  CHECK(tt__mlt_bin_of_theta(&k, nextafter(e[1], 0.0)) == 1);
  CHECK(tt__mlt_bin_of_theta(&k, e[4]) == 5);
  CHECK(tt__mlt_bin_of_theta(&k, 0.999) == 5);
  CHECK(tt__mlt_bin_of_theta(&k, 7.0) == 5); /* Theta >= 1 is clamped into the last bin */
  CHECK(tt__mlt_slot(&k, 0.0f) == 5);        /* delta lobe: Theta = inf */
  CHECK(tt__mlt_slot(&k, -1.0f) == 0);       /* nothing reported: the default sigma */
  /* Theta = 1 / (4 pi pdf): a Lambertian pdf cos/pi at cos = 1 gives Theta = 1/4 */
  CHECK_NEAR(tt__mlt_theta(&k, 1.0 / PI), 0.25, 1e-15);
  CHECK(k.slot_sigma[3] == 0.003 && k.slot_sigma[0] == 0.01);
  const double zero[9] = {0};
  tt__mlt_edges(zero, 4, e); /* all weights zero: equal widths */
  CHECK(e[1] == 0.25 && e[2] == 0.5 && e[3] == 0.75 && e[4] == 1.0);
  /* Catch-up shortcuts exist where they are exact and only there. */
  CHECK(isinf(k.composite_max_n) || k.composite_max_n > 1e100);
  tt__mlt_kernel_init(&k, 0.2, 0.3, 1, 5, 4.0 * PI, a, sig);
  CHECK(k.composite_max_n < 1.0);
  CHECK(k.uniform_n > 20 && k.uniform_n < 1000);
}

/* ---- detailed balance on a toy target ---- */

static double g(double u) { return 0.3 + u * u; }
static double G(double u) { return (0.3 * u + u * u * u / 3.0) / (0.3 + 1.0 / 3.0); }
static double q(double u) { return u < 0.5 ? 1.5 : 0.5; }

/* The toy "path": dims 8-9 (a BSDF direction pair) with a pdf that flips the sigma bin at
 * u8 = 0.5; dim 20 read only when u8 > 0.5 (density 2u); dims 16-17 (a second pair, pdf
 * depending on u16) read only when u9 > 0.7 (u16 density q, u17 uniform). The marginal of
 * (u8, u9) is proportional to g(u8) g(u9). */
static double toy(const tt_sample_source *s) {
  double u8 = s->get(s->self, 8), u9 = s->get(s->self, 9);
  if (s->report_pdf) s->report_pdf(s->self, 8, u8 < 0.5 ? 50.0f : 0.3f);
  double c = g(u8) * g(u9);
  if (u8 > 0.5) c *= 2.0 * s->get(s->self, 20);
  if (u9 > 0.7) {
    double u16 = s->get(s->self, 16);
    (void)s->get(s->self, 17);
    if (s->report_pdf) s->report_pdf(s->self, 16, u16 < 0.5 ? 2.0f : 0.02f);
    c *= q(u16);
  }
  return c;
}

typedef struct boot_src {
  uint64_t seed, index;
} boot_src;
static float boot_get(void *self, uint32_t dim) {
  boot_src *b = self;
  return (float)tt__mlt_bootstrap_value(b->seed, b->index, dim);
}

/* Runs `chains` chains started exactly in the target for `steps` steps; returns the worst
 * chi2 / bound ratio over the histograms (< 1 passes). */
static double run_toy(const tt__mlt_kernel *k, int chains, int steps, const char *label) {
  enum { D = 24, B8 = 8, B1 = 10 };
  unsigned char *mem = malloc(tt__mlt_chain_bytes(D));
  tt__mlt_rng pick;
  tt__mlt_rng_seed(&pick, 99, 5);
  double h89[B8 * B8] = {0}, h20a[B1] = {0}, h20b[B1] = {0}, h16[B1] = {0}, h17[B1] = {0};
  double n20a = 0, n20b = 0, n16 = 0;
  const uint64_t seed = 12345;
  const double cmax = g(1) * g(1) * 2.0 * 1.5;
  uint64_t accepted = 0, proposed = 0;
  for (int ci = 0; ci < chains; ++ci) {
    /* rejection sampling over bootstrap samples: an exact draw from the target */
    uint64_t idx = (uint64_t)ci << 20;
    for (;; ++idx) {
      boot_src b = {seed, idx};
      tt_sample_source s = {boot_get, NULL, &b};
      if (tt__mlt_rng_unit(&pick) * cmax < toy(&s)) break;
    }
    tt__mlt_chain c;
    tt__mlt_chain_init(&c, mem, D, k);
    tt__mlt_chain_start(&c, seed, idx, (uint64_t)ci);
    tt__mlt_chain_propose(&c);
    tt_sample_source src = tt__mlt_chain_source(&c);
    double cx = toy(&src);
    tt__mlt_chain_accept(&c);
    for (int it = 0; it < steps; ++it) {
      tt__mlt_chain_propose(&c);
      double cy = toy(&src);
      double lr = tt__mlt_chain_log_T_ratio(&c);
      double a = cy > 0 ? fmin(1.0, exp(log(cy) - log(cx) + lr)) : 0.0;
      proposed++;
      if (tt__mlt_rng_unit(&c.rng) < a) {
        tt__mlt_chain_accept(&c);
        cx = cy;
        accepted++;
      } else {
        tt__mlt_chain_reject(&c);
      }
    }
    double u8 = tt__mlt_chain_value(&c, 8), u9 = tt__mlt_chain_value(&c, 9);
    double u20 = tt__mlt_chain_value(&c, 20), u16 = tt__mlt_chain_value(&c, 16);
    double u17 = tt__mlt_chain_value(&c, 17);
    h89[(int)(u8 * B8) * B8 + (int)(u9 * B8)]++;
    if (u8 > 0.5) {
      h20a[(int)(u20 * B1)]++;
      n20a++;
    } else {
      h20b[(int)(u20 * B1)]++;
      n20b++;
    }
    if (u9 > 0.7) {
      h16[(int)(u16 * B1)]++;
      h17[(int)(u17 * B1)]++;
      n16++;
    }
  }
  free(mem);
  double p89[B8 * B8], p20a[B1], pu[B1], p16[B1];
  for (int i = 0; i < B8; ++i)
    for (int j = 0; j < B8; ++j)
      p89[i * B8 + j] =
          (G((i + 1.0) / B8) - G((double)i / B8)) * (G((j + 1.0) / B8) - G((double)j / B8));
  for (int i = 0; i < B1; ++i) {
    double lo = (double)i / B1, hi = (i + 1.0) / B1;
    p20a[i] = hi * hi - lo * lo;
    pu[i] = 1.0 / B1;
    p16[i] = 0.5 * (q(lo) + q(hi - 1e-12)) * (hi - lo); /* q is constant on each bin */
  }
  double c89 = chi2(h89, p89, B8 * B8, chains) / chi2_bound(B8 * B8 - 1);
  double c20a = chi2(h20a, p20a, B1, n20a) / chi2_bound(B1 - 1);
  double c20b = chi2(h20b, pu, B1, n20b) / chi2_bound(B1 - 1);
  double c16 = chi2(h16, p16, B1, n16) / chi2_bound(B1 - 1);
  double c17 = chi2(h17, pu, B1, n16) / chi2_bound(B1 - 1);
  printf("%s: acceptance %.3f; chi2/bound (u8,u9) %.2f, u20|u8>.5 %.2f, u20|u8<=.5 %.2f, "
         "u16|u9>.7 %.2f, u17|u9>.7 %.2f\n",
         label, (double)accepted / proposed, c89, c20a, c20b, c16, c17);
  double worst = fmax(fmax(c89, c20a), fmax(c20b, fmax(c16, c17)));
  return worst;
}

static void test_detailed_balance(void) {
  const double a[6] = {0.5, 0.5, 0.5, 0.5, 0.5, 0.5}; /* edges 1/6 .. 4/6 */
  const double bs[5] = {0.3, 0.02, 0.05, 0.05,
                        0.15}; /* pdf 50 and 2 -> bin 1, 0.3 -> 2, 0.02 -> 5 */
  tt__mlt_kernel k;
  /* default sigma 0.1: pending steps are applied one by one (or are uniform) */
  tt__mlt_kernel_init(&k, 0.1, 0.1, 1, 5, 4.0 * PI, a, bs);
  CHECK(k.composite_max_n < 1.0);
  CHECK(run_toy(&k, 30000, 40, "binning, sigma 0.1 (one-by-one catch-up)") < 1.0);
  /* default sigma 0.02: pending steps merge into one wrapped normal */
  tt__mlt_kernel_init(&k, 0.02, 0.1, 1, 5, 4.0 * PI, a, bs);
  CHECK(k.composite_max_n > 1e6);
  CHECK(run_toy(&k, 30000, 40, "binning, sigma 0.02 (composite catch-up)") < 1.0);
  /* no large steps at all: only the small-step kernel keeps the target */
  tt__mlt_kernel_init(&k, 0.1, 0.0, 1, 5, 4.0 * PI, a, bs);
  CHECK(run_toy(&k, 30000, 40, "binning, no large steps") < 1.0);
  /* classic: wrapped normal, fixed sigma */
  tt__mlt_kernel_init(&k, 0.05, 0.3, 0, 5, 4.0 * PI, a, bs);
  CHECK(run_toy(&k, 30000, 40, "classic, sigma 0.05") < 1.0);
  /* the control: without the Hastings sigma factor the target is lost */
  tt__mlt_kernel_init(&k, 0.1, 0.0, 1, 5, 4.0 * PI, a, bs);
  k.no_hastings = 1;
  double bad = run_toy(&k, 30000, 40, "binning WITHOUT the sigma factor (must fail)");
  CHECK_MSG(bad > 3.0, "dropping the Hastings factor went unnoticed (%.2f)", bad);
}

int main(void) {
  test_quantile();
  test_tn_histogram();
  test_ratio();
  test_edges();
  test_detailed_balance();
  return tt_test_finish("pssmlt_chain");
}
