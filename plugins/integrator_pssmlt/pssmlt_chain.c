/* integrator_pssmlt: the primary-sample-space Markov chain (see pssmlt_chain.h, README.md). */
#include "pssmlt_chain.h"

#include <string.h>

#define TT__MLT_SQRT2 1.41421356237309504880
#define TT__MLT_SQRT2PI 2.50662827463100050242
#define TT__MLT_PI 3.14159265358979323846
/* Relative error below which a composite or uniform shortcut counts as exact (README). */
#define TT__MLT_EXACT_EPS 1e-17

/* ---- random numbers ---- */

/* Seeds PCG32 with a state and a stream (as pcg32_srandom_r), both hashed. */
void tt__mlt_rng_seed(tt__mlt_rng *rng, uint64_t seed, uint64_t stream) {
  tt__pcg32_seed(rng, tt__mix64(seed), tt__mix64(stream ^ 0xda3e39cb94b95bdbull));
}

/* ---- the normal and truncated normal ---- */

/* Acklam's rational approximation, |relative error| < 1.2e-9 in the central region (the
 * resulting distribution error is far below anything a render or a chi-square test can
 * see); in the tails, where the rational form is weaker, one Halley step on erfc (cubic:
 * to full precision). The central refinement is skipped for speed: it tripled the cost of
 * a small step (150 ns -> 50 ns measured). */
double tt__mlt_normal_quantile(double p) {
  if (!(p > 0.0)) return -INFINITY;
  if (!(p < 1.0)) return INFINITY;
  if (p > 0.5) return -tt__mlt_normal_quantile(1.0 - p); /* 1 - p is exact for p >= 0.5 */
  static const double a[6] = {-3.969683028665376e+01, 2.209460984245205e+02,
                              -2.759285104469687e+02, 1.383577518672690e+02,
                              -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[5] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                              6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[6] = {-7.784894002430293e-03, -3.223964580411365e-01,
                              -2.400758277161838e+00, -2.549732539343734e+00,
                              4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[4] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                              3.754408661907416e+00};
  if (p >= 0.02425) {
    double q = p - 0.5, r = q * q;
    return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
           (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  }
  double q = sqrt(-2.0 * log(p));
  double x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
             ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  /* (Phi(x) - p) / phi(x) as (Phi(x)/p - 1) exp(log p + x^2/2 + log sqrt(2 pi)): neither
   * factor overflows in the far tail (p down to 1e-300). */
  double u = (0.5 * erfc(-x / TT__MLT_SQRT2) / p - 1.0) *
             exp(log(p) + 0.91893853320467274178 + 0.5 * x * x);
  x = x - u / (1.0 + 0.5 * x * u);
  return x;
}

/* Eq. 4.10 with a = -0.5, b = 0.5, rewritten around the nearer tail so that no 1 - (1 - eps)
 * cancellation occurs: for xi < 1/2, p = Phi(-c) + xi Z with c = 0.5/sigma, Z = 1 - 2 Phi(-c),
 * and X = sigma Phi^-1(p); the upper half mirrors it (the density is symmetric). */
static double tt__mlt_tn_sample_pre(double sigma, double tail, double mass, double xi) {
  double u = xi < 0.5 ? xi : 1.0 - xi;
  double x = sigma * tt__mlt_normal_quantile(tail + u * mass);
  if (xi >= 0.5) x = -x;
  return x < -0.5 ? -0.5 : x > 0.5 ? 0.5 : x;
}

/* Public form for the tests: computes the normalisation on the fly. */
double tt__mlt_tn_sample(double sigma, double xi) {
  double c = 0.5 / sigma;
  return tt__mlt_tn_sample_pre(sigma, 0.5 * erfc(c / TT__MLT_SQRT2), erf(c / TT__MLT_SQRT2), xi);
}

/* phi(d / sigma) / (sigma Z) on [-0.5, 0.5] (eq. 2.11). */
double tt__mlt_tn_pdf(double sigma, double d) {
  if (!(fabs(d) <= 0.5)) return 0.0;
  double z = erf(0.5 / (TT__MLT_SQRT2 * sigma));
  return exp(-0.5 * d * d / (sigma * sigma)) / (sigma * TT__MLT_SQRT2PI * z);
}

/* log of eq. 4.7 (the D terms read as erf(0.5 / (sqrt(2 n_s) sigma)) differences). */
double tt__mlt_tn_log_ratio(double delta, double sigma_c, double sigma_p, double n_s) {
  double sc = sigma_c * sqrt(n_s), sp = sigma_p * sqrt(n_s);
  double dc = erf(0.5 / (TT__MLT_SQRT2 * sc)), dp = erf(0.5 / (TT__MLT_SQRT2 * sp));
  return log(sc * dc) - log(sp * dp) + 0.5 * delta * delta * (1.0 / (sc * sc) - 1.0 / (sp * sp));
}

/* ---- kernel ---- */

/* Eq. 4.2-4.3. */
void tt__mlt_edges(const double *a, int bins, double *edges) {
  double s = 0.0;
  for (int j = 0; j <= bins; ++j) s += a[j] > 0.0 ? a[j] : 0.0;
  edges[0] = 0.0;
  double prefix = 0.0;
  for (int i = 1; i < bins; ++i) {
    prefix += a[i - 1] > 0.0 ? a[i - 1] : 0.0;
    edges[i] = s > 0.0 ? prefix / s : (double)i / bins;
  }
  edges[bins] = 1.0;
}

/* Linear scan: M <= 8 edges, cheaper than a search. */
int tt__mlt_bin_of_theta(const tt__mlt_kernel *k, double theta) {
  for (int i = 1; i < k->bins; ++i)
    if (theta < k->edges[i]) return i;
  return k->bins;
}

/* Largest |Fourier coefficient| c_m (m = 1..64) of one small step on the circle: after n
 * pending steps the wrapped sum deviates from uniform by at most 2 sum_m |c_m|^n. */
static double tt__mlt_step_rho(const tt__mlt_kernel *k) {
  double s = k->sigma;
  if (!k->binning || k->slot_tail[0] < 1e-20) /* wrapped normal, or truncation invisible */
    return exp(-2.0 * TT__MLT_PI * TT__MLT_PI * s * s);
  enum { N = 4096 };
  double rho = 0.0;
  for (int m = 1; m <= 64; ++m) {
    double acc = 0.0;
    for (int i = 0; i <= N; ++i) { /* Simpson on [-0.5, 0.5] */
      double d = -0.5 + (double)i / N;
      double w = (i == 0 || i == N) ? 1.0 : (i & 1) ? 4.0 : 2.0;
      acc += w * exp(-0.5 * d * d / (s * s)) * cos(2.0 * TT__MLT_PI * m * d);
    }
    double cm = fabs(acc / (3.0 * N) / (s * TT__MLT_SQRT2PI * k->slot_mass[0]));
    if (cm > rho) rho = cm;
  }
  return rho;
}

/* Derives the kernel's per-slot constants. */
void tt__mlt_kernel_init(tt__mlt_kernel *k, double sigma, double large_step, int binning, int bins,
                         double alpha, const double *a, const double *bin_sigma) {
  memset(k, 0, sizeof *k);
  if (bins < 1) bins = 1;
  if (bins > TT__MLT_MAX_BINS) bins = TT__MLT_MAX_BINS;
  k->sigma = sigma;
  k->large_step = large_step;
  k->binning = binning;
  k->bins = bins;
  k->alpha = alpha > 0.0 ? alpha : 4.0 * TT__MLT_PI;
  tt__mlt_edges(a, bins, k->edges);
  for (int s = 0; s < TT__MLT_SLOTS; ++s) {
    double sg = s == 0 ? sigma : s <= bins ? bin_sigma[s - 1] : sigma;
    double c = 0.5 / sg;
    k->slot_sigma[s] = sg;
    k->slot_tail[s] = 0.5 * erfc(c / TT__MLT_SQRT2);
    k->slot_mass[s] = erf(c / TT__MLT_SQRT2);
    k->slot_lognorm[s] = log(sg * k->slot_mass[s]);
    k->slot_invvar[s] = 1.0 / (sg * sg);
  }
  double out = 2.0 * k->slot_tail[0];
  k->composite_max_n = !binning || out <= 0.0 ? INFINITY : TT__MLT_EXACT_EPS / out;
  double rho = tt__mlt_step_rho(k);
  k->uniform_n = rho < 1.0 ? log(TT__MLT_EXACT_EPS / 128.0) / log(rho) : INFINITY;
}

/* ---- chain ---- */

/* x mod 1 in [0, 1) (x - floor(x) can round to 1 for tiny negative x). */
static inline double tt__mlt_wrap(double x) {
  x -= floor(x);
  return x >= 1.0 ? 0.0 : x;
}

/* Small-step offset from slot `s`: truncated normal (binning) or plain normal (classic). */
static inline double tt__mlt_step(tt__mlt_chain *c, int s) {
  const tt__mlt_kernel *k = c->k;
  double xi = tt__mlt_rng_unit(&c->rng);
  if (k->binning)
    return tt__mlt_tn_sample_pre(k->slot_sigma[s], k->slot_tail[s], k->slot_mass[s], xi);
  return k->slot_sigma[s] * tt__mlt_normal_quantile(xi > 0.0 ? xi : 0x1p-60);
}

/* Brings a dimension to the current state: a dim untouched since the last accepted large
 * step is uniform; otherwise the n pending steps (all of `sigma`, README) are applied. */
static void tt__mlt_realise(tt__mlt_chain *c, tt__mlt_dim *d) {
  const tt__mlt_kernel *k = c->k;
  if (d->mod >= c->t) return;
  if (d->mod < c->t_large) {
    d->value = tt__mlt_rng_unit(&c->rng);
  } else {
    double n = (double)(c->t - d->mod);
    if (n >= k->uniform_n) {
      d->value = tt__mlt_rng_unit(&c->rng);
    } else if (n <= k->composite_max_n) {
      double xi = tt__mlt_rng_unit(&c->rng);
      d->value = tt__mlt_wrap(d->value + k->sigma * sqrt(n) *
                                             tt__mlt_normal_quantile(xi > 0.0 ? xi : 0x1p-60));
    } else {
      for (int64_t i = 0; i < c->t - d->mod; ++i)
        d->value = tt__mlt_wrap(d->value + tt__mlt_step(c, 0));
    }
  }
  d->mod = c->t;
}

size_t tt__mlt_chain_bytes(uint32_t dims) {
  size_t b = (size_t)dims * sizeof(tt__mlt_dim) + 3 * (size_t)dims * sizeof(uint32_t);
  return (b + 7) & ~(size_t)7;
}

void tt__mlt_chain_init(tt__mlt_chain *c, void *mem, uint32_t dims, const tt__mlt_kernel *k) {
  memset(c, 0, sizeof *c);
  memset(mem, 0, tt__mlt_chain_bytes(dims));
  c->k = k;
  c->dims = dims;
  c->pair_stride = 1;
  c->d = mem;
  c->touched = (uint32_t *)(c->d + dims);
  c->cur_binned = c->touched + dims;
  c->new_binned = c->cur_binned + dims;
  for (uint32_t i = 0; i < dims; ++i) c->d[i].pdf = c->d[i].pdf_new = -1.0f;
}

void tt__mlt_chain_start(tt__mlt_chain *c, uint64_t seed, uint64_t index, uint64_t chain_index) {
  c->replay = 1;
  c->replay_seed = seed;
  c->replay_index = index;
  tt__mlt_rng_seed(&c->rng, seed, 0x6d6c74ull ^ (chain_index * 0x9e3779b97f4a7c15ull));
}

void tt__mlt_chain_propose(tt__mlt_chain *c) {
  c->iter++;
  c->n_touched = 0;
  c->n_new = 0;
  c->large = c->replay || tt__mlt_rng_unit(&c->rng) < c->k->large_step;
}

/* get(): the proposal's value of `dim`, mutated from the current state on first use. */
static float tt__mlt_chain_get(void *self, uint32_t dim) {
  tt__mlt_chain *c = self;
  if (dim >= c->dims) return 0.5f; /* beyond TT_PATH_DIM_COUNT(maxDepth): not reached */
  tt__mlt_dim *d = &c->d[dim];
  if (d->stamp != c->iter) {
    d->stamp = c->iter;
    c->touched[c->n_touched++] = dim;
    d->pdf_new = -1.0f;
    if (c->replay) {
      d->backup = d->value;
      d->mod_backup = d->mod;
      d->value = tt__mlt_bootstrap_value(c->replay_seed, c->replay_index, dim);
    } else if (c->large) { /* no need to realise: a rejection restores the pending form */
      d->backup = d->value;
      d->mod_backup = d->mod;
      d->value = tt__mlt_rng_unit(&c->rng);
    } else {
      tt__mlt_realise(c, d);
      d->backup = d->value;
      d->mod_backup = d->mod;
      d->delta = tt__mlt_step(c, tt__mlt_slot(c->k, d->pdf));
      d->value = tt__mlt_wrap(d->value + d->delta);
    }
  }
  float f = (float)d->value;
  return f < 1.0f ? f : 0x1.fffffep-1f;
}

/* report_pdf(): remembers the proposal's direction pdf for both dims of the pair, and feeds
 * the Theta histogram. Tracked in classic mode too, so that a switch to binning between
 * passes knows the current state's sigmas. */
static void tt__mlt_chain_report(void *self, uint32_t dim, float pdf) {
  tt__mlt_chain *c = self;
  if (c->theta_hist) {
    double th = tt__mlt_theta(c->k, pdf);
    int b = th < 1.0 ? (int)(th * TT__MLT_THETA_BINS) : TT__MLT_THETA_BINS;
    c->theta_hist[b < 0 ? 0 : b]++;
  }
  if (!(pdf >= 0.0f) || !isfinite(pdf) || dim + c->pair_stride >= c->dims) return;
  for (uint32_t j = dim; j <= dim + c->pair_stride; j += c->pair_stride) {
    if (c->d[j].stamp != c->iter) continue; /* not read (cannot happen in path.c) */
    if (c->d[j].pdf_new < 0.0f) c->new_binned[c->n_new++] = j;
    c->d[j].pdf_new = pdf;
  }
}

tt_sample_source tt__mlt_chain_source(tt__mlt_chain *c) {
  tt_sample_source s = {tt__mlt_chain_get, tt__mlt_chain_report, c};
  return s;
}

/* One dimension's log[t_sp(delta) / t_sc(delta)]. */
static inline double tt__mlt_slot_term(const tt__mlt_kernel *k, double delta, int sc, int sp) {
  return k->slot_lognorm[sc] - k->slot_lognorm[sp] +
         0.5 * delta * delta * (k->slot_invvar[sc] - k->slot_invvar[sp]);
}

double tt__mlt_chain_log_T_ratio(tt__mlt_chain *c) {
  const tt__mlt_kernel *k = c->k;
  if (c->large || c->replay || !k->binning) return 0.0;
  double lr = 0.0;
  for (uint32_t i = 0; i < c->n_touched; ++i) {
    const tt__mlt_dim *d = &c->d[c->touched[i]];
    int sc = tt__mlt_slot(k, d->pdf), sp = tt__mlt_slot(k, d->pdf_new);
    if (sc != sp) lr += tt__mlt_slot_term(k, d->delta, sc, sp);
  }
  /* Dims the current state uses with a binned sigma but the proposal never read still move
   * in the full-state chain, from sigma(x) to the default sigma of y: draw them now. */
  for (uint32_t i = 0; i < c->n_cur; ++i) {
    tt__mlt_dim *d = &c->d[c->cur_binned[i]];
    if (d->stamp == c->iter) continue;
    int sc = tt__mlt_slot(k, d->pdf);
    if (sc == 0) continue; /* same sigma both ways: stays a lazy pending step */
    d->delta = tt__mlt_step(c, sc);
    d->eager = c->iter;
    lr += tt__mlt_slot_term(k, d->delta, sc, 0);
  }
  return k->no_hastings ? 0.0 : lr;
}

void tt__mlt_chain_accept(tt__mlt_chain *c) {
  c->t++;
  if (c->large) c->t_large = c->t;
  for (uint32_t i = 0; i < c->n_cur; ++i) { /* the old state's binned dims */
    tt__mlt_dim *d = &c->d[c->cur_binned[i]];
    if (d->stamp == c->iter) continue;
    if (!c->large && d->eager == c->iter) {
      d->value = tt__mlt_wrap(d->value + d->delta);
      d->mod = c->t;
    }
    d->pdf = -1.0f;
  }
  for (uint32_t i = 0; i < c->n_touched; ++i) {
    tt__mlt_dim *d = &c->d[c->touched[i]];
    d->mod = c->t;
    d->pdf = d->pdf_new;
  }
  uint32_t *tmp = c->cur_binned;
  c->cur_binned = c->new_binned;
  c->new_binned = tmp;
  c->n_cur = c->n_new;
  c->replay = 0;
}

void tt__mlt_chain_reject(tt__mlt_chain *c) {
  for (uint32_t i = 0; i < c->n_touched; ++i) {
    tt__mlt_dim *d = &c->d[c->touched[i]];
    d->value = d->backup;
    d->mod = d->mod_backup;
  }
  c->replay = 0;
}

double tt__mlt_chain_value(tt__mlt_chain *c, uint32_t dim) {
  if (dim >= c->dims) return 0.5;
  tt__mlt_realise(c, &c->d[dim]);
  return c->d[dim].value;
}

void tt__mlt_chain_flush(tt__mlt_chain *c) {
  for (uint32_t i = 0; i < c->dims; ++i) tt__mlt_realise(c, &c->d[i]);
}
