/* integrator_pssmlt internals: the Markov chain over primary-sample space (Kelemen et al.
 * 2002, pbrt-v4 MLTSampler) with the thesis' sigma-binning (4.4) and truncated-normal small
 * steps (4.5-4.6). Compiled into the plugin and into the tests (names are tt__, nothing is
 * exported from the plugin). See README.md for the derivation of what is exact.
 *
 * A chain's state is the infinite vector x of primary samples; only the dimensions a path
 * reads are ever materialised. One iteration: tt__mlt_chain_propose, then the path reads
 * the proposal through tt__mlt_chain_source (get / report_pdf), then the caller computes the
 * acceptance (tt__mlt_chain_log_T_ratio gives the Hastings factor) and calls accept or
 * reject. No allocation after tt__mlt_chain_init: every array lives in caller memory.
 * A chain is used by one thread at a time. */
#ifndef TT_PSSMLT_CHAIN_H
#define TT_PSSMLT_CHAIN_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include <tunetrace/path.h>
#include <tt_util/rng.h>

#define TT__MLT_MAX_BINS 8
#define TT__MLT_SLOTS (TT__MLT_MAX_BINS + 1)

/* PCG32 (O'Neill 2014, XSH-RR 64/32), one per chain: the shared generator of
 * <tt_util/rng.h>, seeded the PSSMLT way (seed and stream hashed, tt__mlt_rng_seed). */
typedef tt__pcg32 tt__mlt_rng;

void tt__mlt_rng_seed(tt__mlt_rng *rng, uint64_t seed, uint64_t stream);
/* Uniform double in [0, 1) with 53 random bits: the truncated normal's tails need more
 * than 24. */
static inline double tt__mlt_rng_unit(tt__mlt_rng *rng) { return tt__pcg32_double(rng); }

/* ---- the mutation kernel (derived from a configuration) ---- */

typedef struct tt__mlt_kernel {
  double sigma;                /* non-direction dims; every dim in classic mode */
  double large_step;           /* probability of a large step */
  int binning;                 /* sigma-binning + truncated normal (thesis 4.4-4.6) */
  int bins;                    /* M */
  double alpha;                /* Theta = 1 / (alpha * pdf) */
  double edges[TT__MLT_SLOTS]; /* A_0 = 0 < A_1 .. A_{M-1} < A_M = 1 (eq. 4.2-4.3) */
  /* per sigma slot (0 = `sigma`, i = bin i): sigma, log(sigma * Z), 1/sigma^2, Phi(-0.5/sigma)
   * and Z = 1 - 2 Phi(-0.5/sigma), the truncated normal's mass on [-0.5, 0.5] */
  double slot_sigma[TT__MLT_SLOTS], slot_lognorm[TT__MLT_SLOTS], slot_invvar[TT__MLT_SLOTS];
  double slot_tail[TT__MLT_SLOTS], slot_mass[TT__MLT_SLOTS];
  /* catch-up: up to this many pending steps of `sigma` are merged into one wrapped normal
   * of sigma*sqrt(n) (exact to double precision, README); beyond, applied one by one */
  double composite_max_n;
  /* pending steps beyond which the wrapped sum is uniform to double precision (README) */
  double uniform_n;
  int no_hastings; /* tests only: drop the sigma factor (to show the test bites) */
} tt__mlt_kernel;

/* Bin edges A_0..A_M from a_1..a_{M+1} (eq. 4.2-4.3): A_i = (a_1 + .. + a_i) / S for
 * i < M, S = a_1 + .. + a_{M+1}; S = 0 falls back to equal widths. */
void tt__mlt_edges(const double *a, int bins, double *edges);

/* Fills a kernel. `a` has bins+1 entries, `bin_sigma` bins entries. */
void tt__mlt_kernel_init(tt__mlt_kernel *k, double sigma, double large_step, int binning, int bins,
                         double alpha, const double *a, const double *bin_sigma);

/* Theta of a solid-angle pdf (0 for a delta lobe gives +inf). */
static inline double tt__mlt_theta(const tt__mlt_kernel *k, double pdf) {
  return pdf > 0.0 ? 1.0 / (k->alpha * pdf) : INFINITY;
}

/* Bin 1..M of Theta: [A_{i-1}, A_i); Theta >= 1 (and +inf) goes to bin M. */
int tt__mlt_bin_of_theta(const tt__mlt_kernel *k, double theta);

/* Sigma slot of a dimension whose state reported `pdf` (< 0: none reported -> slot 0). */
static inline int tt__mlt_slot(const tt__mlt_kernel *k, float pdf) {
  return (k->binning && pdf >= 0.0f) ? tt__mlt_bin_of_theta(k, tt__mlt_theta(k, pdf)) : 0;
}

/* ---- the truncated normal on [-0.5, 0.5] (eq. 2.20-2.22, 4.8-4.10) ---- */

/* Standard normal quantile, full double precision (Acklam + Halley refinement). */
double tt__mlt_normal_quantile(double p);
/* Offset in [-0.5, 0.5] from N(0, sigma) truncated to [-0.5, 0.5]; xi uniform in [0, 1). */
double tt__mlt_tn_sample(double sigma, double xi);
/* Density of that offset at d (0 outside [-0.5, 0.5]). */
double tt__mlt_tn_pdf(double sigma, double d);
/* log of eq. 4.7's sigma factor: log[T(p->c) / T(c->p)] for one dimension moved by `delta`
 * from a state with sigma_c to one with sigma_p, each the composite of n_s steps modelled as
 * one truncated normal of sigma*sqrt(n_s) (the thesis' form). The plugin uses n_s = 1
 * (README: the only exact case); larger n_s is kept for the tests. */
double tt__mlt_tn_log_ratio(double delta, double sigma_c, double sigma_p, double n_s);

/* ---- the chain ---- */

typedef struct tt__mlt_dim {
  double value;  /* value of the dim in the current state as of `mod` (or the proposal's) */
  double backup; /* the current state's while a proposal is out */
  double delta;  /* this iteration's small-step offset */
  int64_t mod;   /* accepted-move count at which `value` holds */
  int64_t mod_backup;
  uint64_t stamp; /* iteration that last touched the dim */
  uint64_t eager; /* iteration whose offset was drawn without the proposal reading it */
  float pdf;      /* BSDF pdf the current state reported for this dim, -1 if none */
  float pdf_new;  /* the proposal's */
} tt__mlt_dim;

typedef struct tt__mlt_chain {
  tt__mlt_rng rng;
  const tt__mlt_kernel *k;
  uint32_t dims;
  uint32_t pair_stride; /* a direction's second dim is its first + this (1; 3 for
                                       MMLT's interleaved streams) */
  tt__mlt_dim *d;
  uint32_t *touched, n_touched; /* dims the proposal read */
  uint32_t *cur_binned, n_cur;  /* dims with a reported pdf in the current state */
  uint32_t *new_binned, n_new;  /* dims with a reported pdf in the proposal */
  int64_t t;                    /* accepted moves */
  int64_t t_large;              /* t of the last accepted large step */
  uint64_t iter;                /* iterations, accepted or not */
  int large;                    /* current iteration is a large step */
  int replay;                   /* current iteration replays a bootstrap sample */
  uint64_t replay_seed, replay_index;
  /* the plugin's view of the current state */
  float L[3], fx, fy;
  double C;
  /* optional Theta histogram (counts per 1/TT__MLT_THETA_BINS, last = >= 1), or NULL */
  uint64_t *theta_hist;
} tt__mlt_chain;

#define TT__MLT_THETA_BINS 200

/* Bytes of caller memory a chain of `dims` dimensions needs (8-byte aligned). */
size_t tt__mlt_chain_bytes(uint32_t dims);
/* Lays the chain's arrays into `mem` (tt__mlt_chain_bytes(dims) bytes) and clears it. */
void tt__mlt_chain_init(tt__mlt_chain *c, void *mem, uint32_t dims, const tt__mlt_kernel *k);
/* Makes the next iteration a forced large step that replays bootstrap sample `index` of
 * `seed` (its primary samples are tt__mlt_bootstrap_value); the chain's own random numbers
 * then come from stream `chain_index`. The caller traces it and calls accept. */
void tt__mlt_chain_start(tt__mlt_chain *c, uint64_t seed, uint64_t index, uint64_t chain_index);
/* Primary sample `dim` of bootstrap sample `index`. */
static inline double tt__mlt_bootstrap_value(uint64_t seed, uint64_t index, uint32_t dim) {
  return tt__u64_to_unit(tt__hash3(seed, index, dim));
}

/* Starts an iteration: chooses small or large step. */
void tt__mlt_chain_propose(tt__mlt_chain *c);
/* The proposal as a sample source (get + report_pdf). */
tt_sample_source tt__mlt_chain_source(tt__mlt_chain *c);
/* log of the Hastings factor T(y->x)/T(x->y) of this iteration (0 for large steps and in
 * classic mode). Draws the offsets of the current state's binned dims that the proposal did
 * not read: call it once per small step before accept/reject. */
double tt__mlt_chain_log_T_ratio(tt__mlt_chain *c);
void tt__mlt_chain_accept(tt__mlt_chain *c);
void tt__mlt_chain_reject(tt__mlt_chain *c);
/* Value of `dim` in the current state, realising pending steps (tests, dumps). */
double tt__mlt_chain_value(tt__mlt_chain *c, uint32_t dim);
/* Realises every pending step with the kernel in force (before the kernel changes). */
void tt__mlt_chain_flush(tt__mlt_chain *c);

#endif
