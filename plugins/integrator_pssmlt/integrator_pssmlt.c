/* integrator_pssmlt: Metropolis light transport in primary sample space, with the thesis'
 * sigma-binning and truncated-normal small steps (chapter 4). Kind TT_KIND_INTEGRATOR. Two
 * modes: pssmlt, Kelemen et al. 2002's PSSMLT over the core path sampler (chain mechanics
 * after pbrt-v4's MLTSampler); mmlt, multiplexed MLT (Hachisuka et al. 2014) over the core's
 * bidirectional path sampler with pbrt-v3 MLTIntegrator's structure (three sample streams,
 * one connection strategy per state, a path depth per chain, a bootstrap per depth).
 *
 * The first pass bootstraps (N independent paths give b = mean luminance and the chain
 * starts, drawn in proportion to the luminance); every pass then advances all chains by
 * spp * mutationsPerPixel * pixels mutations in total, splatting expected values. Chains
 * are independent, each with its own random stream, and splats go to a fixed-point buffer
 * with integer atomics, so a seed gives the same image bit for bit whatever the thread
 * count. The chain mechanics live in pssmlt_chain.c; README.md has the derivations. */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <tunetrace/bdpt.h>
#include <tunetrace/camera.h>
#include <tunetrace/file.h>
#include <tunetrace/integrator.h>
#include <tunetrace/path.h>
#include <tunetrace/plugin.h>
#include <tunetrace/tuning_hint.h>

#include "pssmlt_chain.h"

#define TT__MLT_NAME "integrator_pssmlt"
#define TT__MLT_VERSION "0.1.0"
/* Fixed-point scale of the splat accumulator: 2^28 keeps 3.7e-9 resolution for splat
 * values that are at most 1/0.0722 (a pure blue path), with 2^35 of headroom per pass. */
#define TT__MLT_FIXED_SCALE 268435456.0
#define TT__MLT_STOP_CHECK 256
#define TT__MLT_PI 3.14159265358979323846

static const tt_host *g_host;
static tt_space *g_space;

typedef struct tt__mlt_settings {
  int mmlt; /* multiplexed MLT over the bidirectional sampler (else PSSMLT over PT) */
  uint32_t max_depth;
  double large_step, sigma, alpha;
  int binning, bins;
  double a[TT__MLT_MAX_BINS + 1], bin_sigma[TT__MLT_MAX_BINS];
  uint32_t mpp;
  uint64_t bootstrap;
  uint32_t chains;
} tt__mlt_settings;

struct tt_integrator {
  const tt_scene *scene;
  tt_path_tracer *pt;
  tt__mlt_settings set;
  tt_path_options opts;
  tt_bdpt_options bopts; /* mmlt */
  tt__mlt_kernel kernel;
  /* chains (valid when ready) */
  int ready;
  int black; /* ready, but the bootstrap found no light: b = 0, no chains run */
  uint32_t nchains, dims, width, height;
  tt__mlt_chain *chains;
  uint8_t *chain_depth; /* mmlt: each chain's path depth (bounces) */
  unsigned char *chain_mem;
  double b;
  uint64_t seed;
  uint64_t mutations_total;
  /* fixed-point splat accumulator, 3 per pixel, flushed into the film after every pass */
  _Atomic int64_t *acc;
  size_t acc_pixels;
  /* Theta histogram for the dump (TT_PSSMLT_THETA_DUMP) */
  char *theta_dump;
  uint64_t theta_hist[TT__MLT_THETA_BINS + 1];
};

/* ---- parameters ---- */

/* The host, or libtunetrace's default services when the plugin is used without init(). */
static const tt_host *tt__mlt_host(void) { return g_host ? g_host : tt_default_host(); }

/* Builds the parameter space once (init). */
static tt_status tt__mlt_build_space(void) {
  tt_space *s = tt_space_create(TT__MLT_NAME, TT__MLT_VERSION);
  if (!s)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__MLT_NAME ": cannot create the parameter space");
  int ok = 1;
  char name[32], desc[160];
  static const char *const modes[] = {"pssmlt", "mmlt"};
  ok &= tt_space_add_nom_string(
            s, "mode", modes, 2, 0,
            "pssmlt: Kelemen PSSMLT over the path tracer; mmlt: multiplexed MLT "
            "(Hachisuka 2014, pbrt-v3's MLTIntegrator) over the bidirectional path "
            "sampler, one connection strategy per state and a path depth per chain; "
            "changing it restarts the estimate") >= 0;
  ok &= tt_space_add_int(s, "maxDepth", 0, 64, 5,
                         "maximum number of bounces (pbrt-v4 MLT default 5); "
                         "changing it between passes restarts the estimate") >= 0;
  ok &= tt_space_add_float(s, "largeStepProbability", 0.0, 1.0, 0.3, 0,
                           "probability of a large (independent uniform) step") >= 0;
  ok &= tt_space_add_float(s, "sigma", 1e-4, 0.3, 0.01, 1,
                           "small-step standard deviation: every dimension in classic mode, the "
                           "non-direction dimensions with binning") >= 0;
  ok &= tt_space_add_nom_bool(s, "binning", 0,
                              "sigma-binning by Theta = 1/(alpha pdf) with truncated-"
                              "normal steps (thesis 4.4-4.6); false: classic wrapped normal") >= 0;
  ok &= tt_space_add_int(s, "bins", 5, TT__MLT_MAX_BINS, 7, "number M of sigma bins") >= 0;
  ok &= tt_space_add_float(s, "alpha", 0.1, 1000.0, 4.0 * TT__MLT_PI, 1,
                           "Theta = 1/(alpha * pdf) spread (thesis: 4 pi)") >= 0;
  for (int i = 1; i <= TT__MLT_MAX_BINS + 1; ++i) {
    snprintf(name, sizeof name, "a%d", i);
    snprintf(desc, sizeof desc,
             "bin edge weight a_%d: A_i = (a_1+..+a_i)/(a_1+..+a_{M+1}) (eq. 4.2-4.3); "
             "used when %d <= M+1",
             i, i);
    ok &= tt_space_add_float(s, name, 0.0, 1.0, 0.5, 0, desc) >= 0;
  }
  for (int i = 1; i <= TT__MLT_MAX_BINS; ++i) {
    snprintf(name, sizeof name, "sigma%d", i);
    snprintf(desc, sizeof desc, "small-step sigma of Theta bin %d (used when %d <= M)", i, i);
    ok &= tt_space_add_float(s, name, 1e-4, 0.3, 0.01, 1, desc) >= 0;
  }
  ok &= tt_space_add_int(s, "mutationsPerPixel", 1, 64, 1,
                         "mutations per pixel per pass and per --spp unit") >= 0;
  ok &= tt_space_add_int(s, "bootstrapSamples", 1000, 1000000, 100000,
                         "bootstrap paths for b and the chain starts, per path depth in mmlt "
                         "(restarts when changed)") >= 0;
  ok &= tt_space_add_int(s, "chains", 1, 100000, 1000,
                         "independent Markov chains (restarts when changed)") >= 0;
  tt_space_add_constraint_text(
      s, "only a_1..a_{bins+1} and sigma1..sigma{bins} are used, and only with binning");
  if (!ok) {
    tt_space_destroy(s);
    return tt_set_error(TT_ERR_INTERNAL, TT__MLT_NAME ": building the parameter space failed");
  }
  g_space = s;
  return TT_OK;
}

/* Reads a configuration (NULL = defaults) into settings. */
static tt_status tt__mlt_read_config(const tt_config *config, tt__mlt_settings *out) {
  tt_config *defaults = NULL;
  if (!config) {
    if (!g_space) return tt_set_error(TT_ERR_INTERNAL, TT__MLT_NAME ": used before init()");
    defaults = tt_config_create(g_space);
    if (!defaults) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__MLT_NAME ": out of memory");
    config = defaults;
  }
  char name[32];
  memset(out, 0, sizeof *out);
  const char *mode = tt_config_get_string(config, "mode");
  out->mmlt = mode && strcmp(mode, "mmlt") == 0;
  out->max_depth = (uint32_t)tt_config_get_int(config, "maxDepth", 5);
  out->large_step = tt_config_get_float(config, "largeStepProbability", 0.3);
  out->sigma = tt_config_get_float(config, "sigma", 0.01);
  out->binning = (int)tt_config_get_int(config, "binning", 0);
  out->bins = (int)tt_config_get_int(config, "bins", 7);
  out->alpha = tt_config_get_float(config, "alpha", 4.0 * TT__MLT_PI);
  for (int i = 0; i <= TT__MLT_MAX_BINS; ++i) {
    snprintf(name, sizeof name, "a%d", i + 1);
    out->a[i] = tt_config_get_float(config, name, 0.5);
  }
  for (int i = 0; i < TT__MLT_MAX_BINS; ++i) {
    snprintf(name, sizeof name, "sigma%d", i + 1);
    out->bin_sigma[i] = tt_config_get_float(config, name, 0.01);
  }
  out->mpp = (uint32_t)tt_config_get_int(config, "mutationsPerPixel", 1);
  out->bootstrap = (uint64_t)tt_config_get_int(config, "bootstrapSamples", 100000);
  out->chains = (uint32_t)tt_config_get_int(config, "chains", 1000);
  tt_config_destroy(defaults);
  tt_status st = TT_OK;
  if (out->max_depth > 64 || out->bins < 1 || out->bins > TT__MLT_MAX_BINS || out->mpp < 1 ||
      out->bootstrap < 1 || out->chains < 1 || !(out->sigma > 0.0) || !(out->large_step >= 0.0) ||
      !(out->large_step <= 1.0) || !(out->alpha > 0.0))
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__MLT_NAME ": configuration out of range");
  for (int i = 0; i < TT__MLT_MAX_BINS && st == TT_OK; ++i)
    if (!(out->bin_sigma[i] > 0.0) || !(out->a[i] >= 0.0))
      st = tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__MLT_NAME ": sigma%d/a%d out of range", i + 1,
                        i + 1);
  return st;
}

/* Path options and mutation kernel from settings (Russian roulette off: MLT explores depth
 * through the chain, and a roulette dimension would only add discontinuities). */
static void tt__mlt_apply(tt_integrator *it, const tt__mlt_settings *s) {
  it->set = *s;
  tt_path_options_default(&it->opts);
  it->opts.max_depth = s->max_depth;
  it->opts.rr_depth = s->max_depth;
  it->opts.result_size = sizeof(tt_path_result); /* with prev_position: object motion */
  tt_bdpt_options_default(&it->bopts);
  it->bopts.max_depth = s->max_depth;
  it->bopts.rr_depth = 64; /* off, as in pssmlt mode: the chain picks the depth */
  tt__mlt_kernel_init(&it->kernel, s->sigma, s->large_step, s->binning, s->bins, s->alpha, s->a,
                      s->bin_sigma);
}

/* ---- interface ---- */

static const tt_space *tt__mlt_space(void) { return g_space; }

static tt_status tt__mlt_create(const tt_scene *scene, const tt_config *config,
                                tt_integrator **out) {
  if (!scene || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__MLT_NAME ": scene or out is NULL");
  *out = NULL;
  tt__mlt_settings s;
  tt_status st = tt__mlt_read_config(config, &s);
  if (st != TT_OK) return st;
  tt_integrator *it = calloc(1, sizeof *it);
  if (!it) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__MLT_NAME ": out of memory");
  it->scene = scene;
  tt__mlt_apply(it, &s);
  const char *dump = getenv("TT_PSSMLT_THETA_DUMP");
  if (dump && *dump) {
    it->theta_dump = malloc(strlen(dump) + 1);
    if (it->theta_dump) strcpy(it->theta_dump, dump);
  }
  st = tt_path_tracer_create(scene, &it->pt);
  if (st != TT_OK) {
    free(it->theta_dump);
    free(it);
    return st;
  }
  *out = it;
  return TT_OK;
}

/* Drops the chains; the next pass bootstraps again. */
static void tt__mlt_drop_chains(tt_integrator *it) {
  free(it->chains);
  free(it->chain_mem);
  free(it->chain_depth);
  it->chains = NULL;
  it->chain_mem = NULL;
  it->chain_depth = NULL;
  it->ready = 0;
  it->black = 0;
  it->mutations_total = 0;
}

static tt_status tt__mlt_configure(tt_integrator *it, const tt_config *config) {
  tt__mlt_settings s;
  tt_status st = tt__mlt_read_config(config, &s);
  if (st != TT_OK) return st;
  int restart = s.max_depth != it->set.max_depth || s.bootstrap != it->set.bootstrap ||
                s.chains != it->set.chains || s.mmlt != it->set.mmlt;
  if (restart) {
    tt__mlt_drop_chains(it); /* another target function or start distribution */
  } else if (it->ready) {
    /* Pending steps were drawn under the old kernel: realise them before it changes. */
    for (uint32_t c = 0; c < it->nchains; ++c) tt__mlt_chain_flush(&it->chains[c]);
  }
  tt__mlt_apply(it, &s);
  return TT_OK;
}

static void tt__mlt_reset(tt_integrator *it) {
  if (it) tt__mlt_drop_chains(it);
}

static void tt__mlt_destroy(tt_integrator *it) {
  if (!it) return;
  tt__mlt_drop_chains(it);
  free((void *)it->acc);
  free(it->theta_dump);
  tt_path_tracer_destroy(it->pt);
  free(it);
}

/* Everything the workers share during one pass. */
typedef struct tt__mlt_job {
  tt_integrator *it;
  const tt_render_ctx *ctx;
  tt_camera_frame frame;
  tt_tracer tracer;
  uint32_t width, height;
  /* bootstrap */
  double *weights;
  uint64_t *starts;
  /* mutation quotas */
  uint64_t base, extra;
  /* mmlt: per-thread subpaths, made on first use */
  tt_bdpt_paths **paths;
  uint32_t threads;
  atomic_uint_fast64_t rays, mutations, nonfinite, small_prop, small_acc, large_prop, large_acc,
      vertices;
  atomic_uint_fast64_t theta[TT__MLT_THETA_BINS + 1];
  atomic_int interrupted, failed;
} tt__mlt_job;

/* One evaluated state: its contribution, where it lands, what it cost. */
typedef struct tt__mlt_sample {
  float L[3];
  float fx, fy;
  uint32_t rays;
  uint32_t vertices; /* surface vertices the state's path(s) traced */
  int32_t nonfinite;
} tt__mlt_sample;

/* Luminance (Rec. 709), the scalar contribution C. */
static inline double tt__mlt_lum(const float L[3]) {
  return 0.2126 * L[0] + 0.7152 * L[1] + 0.0722 * L[2];
}

/* Bootstrap sample source: counter-based uniforms, replayable by any chain. */
typedef struct tt__mlt_boot_src {
  uint64_t seed, index;
} tt__mlt_boot_src;

static float tt__mlt_boot_get(void *self, uint32_t dim) {
  const tt__mlt_boot_src *s = self;
  float f = (float)tt__mlt_bootstrap_value(s->seed, s->index, dim);
  return f < 1.0f ? f : 0x1.fffffep-1f;
}

/* Film position of primary samples (u0, u1): the whole film. */
static inline void tt__mlt_film_pos(const tt__mlt_job *job, float u0, float u1, float *fx,
                                    float *fy) {
  *fx = u0 * (float)job->width;
  *fy = u1 * (float)job->height;
}

/* Traces one path from primary samples read through `src` (pssmlt mode). */
static void tt__mlt_trace(const tt__mlt_job *job, const tt_sample_source *src, tt_path_result *r,
                          float *fx, float *fy) {
  float u0 = src->get(src->self, TT_PATH_DIM_FILM), u1 = src->get(src->self, TT_PATH_DIM_FILM + 1);
  tt__mlt_film_pos(job, u0, u1, fx, fy);
  tt_ray ray;
  tt_camera_generate_ray(&job->frame, *fx, *fy, &ray);
  tt_path_trace(job->it->pt, &job->tracer, &job->it->opts, &ray, src, r);
}

/* ---- multiplexed MLT (pbrt-v3 MLTIntegrator::L) ----
 * The state's primary samples are three interleaved streams (camera, light, connection:
 * stream k's dimension d is the chain's 3 d + k), so that a change of one subpath's length
 * never shifts another's dimensions. Connection-stream dim 0 chooses the strategy s of the
 * chain's depth (uniformly among depth + 2), its dims 1.. feed the connection. */
#define TT__MLT_STREAMS 3
#define TT__MLT_CONNECT_BASE 1

typedef struct tt__mlt_stream {
  const tt_sample_source *base;
  uint32_t k;
} tt__mlt_stream;

static float tt__mlt_stream_get(void *self, uint32_t dim) {
  const tt__mlt_stream *s = self;
  return s->base->get(s->base->self, TT__MLT_STREAMS * dim + s->k);
}

static void tt__mlt_stream_report(void *self, uint32_t dim, float pdf) {
  const tt__mlt_stream *s = self;
  if (s->base->report_pdf) s->base->report_pdf(s->base->self, TT__MLT_STREAMS * dim + s->k, pdf);
}

/* Dimensions of an mmlt state for paths up to `depth` bounces. */
static uint32_t tt__mlt_mmlt_dims(uint32_t depth) {
  uint32_t c = TT_BDPT_CAMERA_DIM_COUNT(depth), l = TT_BDPT_LIGHT_DIM_COUNT(depth);
  uint32_t k = TT__MLT_CONNECT_BASE + TT_BDPT_CONNECT_DIMS, m = c > l ? c : l;
  return TT__MLT_STREAMS * (m > k ? m : k);
}

/* The contribution of a state of a chain of path depth `depth` (times the number of
 * strategies, as the strategy is chosen uniformly). */
static void tt__mlt_trace_mmlt(const tt__mlt_job *job, tt_bdpt_paths *paths,
                               const tt_sample_source *src, uint32_t depth, tt__mlt_sample *out) {
  const tt_integrator *it = job->it;
  tt__mlt_stream cs = {src, 0}, ls = {src, 1}, ks = {src, 2};
  tt_sample_source cam = {tt__mlt_stream_get, tt__mlt_stream_report, &cs};
  tt_sample_source lig = {tt__mlt_stream_get, tt__mlt_stream_report, &ls};
  tt_sample_source con = {tt__mlt_stream_get, tt__mlt_stream_report, &ks};
  uint32_t n = depth == 0 ? 1 : depth + 2, s = 0, t = 2;
  if (depth > 0) {
    float u = con.get(con.self, 0);
    s = (uint32_t)(u * (float)n);
    if (s > n - 1) s = n - 1;
    t = n - s;
  }
  tt__mlt_film_pos(job, cam.get(cam.self, TT_BDPT_CAMERA_DIM_FILM),
                   cam.get(cam.self, TT_BDPT_CAMERA_DIM_FILM + 1), &out->fx, &out->fy);
  uint32_t nc = tt_bdpt_camera_subpath(it->pt, &job->tracer, &it->bopts, &job->frame, out->fx,
                                       out->fy, &cam, t, paths);
  uint32_t nl =
      nc == t ? tt_bdpt_light_subpath(it->pt, &job->tracer, &it->bopts, &lig, s, paths) : 0;
  out->vertices = (nc > 0 ? nc - 1 : 0) + (nl > 0 ? nl - 1 : 0);
  if (nc == t && nl == s) {
    tt_bdpt_contribution c;
    tt_bdpt_connect(it->pt, &job->tracer, &it->bopts, &job->frame, paths, s, t, &con,
                    TT__MLT_CONNECT_BASE, &c);
    for (int i = 0; i < 3; ++i) out->L[i] = c.L[i] * (float)n;
    out->nonfinite = c.nonfinite;
    if (t == 1) {
      out->fx = c.fx;
      out->fy = c.fy;
    }
  }
  out->rays = tt_bdpt_rays(paths);
}

/* Evaluates the state read through `src` in the integrator's mode (`depth`: the chain's, mmlt
 * only). Returns 0 when the thread's subpaths cannot be allocated. */
static int tt__mlt_eval(tt__mlt_job *job, uint32_t thread, const tt_sample_source *src,
                        uint32_t depth, tt__mlt_sample *out) {
  memset(out, 0, sizeof *out);
  if (!job->it->set.mmlt) {
    tt_path_result r;
    tt__mlt_trace(job, src, &r, &out->fx, &out->fy);
    memcpy(out->L, r.L, sizeof out->L);
    out->rays = r.rays;
    out->vertices = r.bounces;
    out->nonfinite = r.nonfinite;
    return 1;
  }
  if (thread >= job->threads) return 0;
  if (!job->paths[thread] &&
      tt_bdpt_paths_create(job->it->set.max_depth, &job->paths[thread]) != TT_OK)
    return 0;
  tt__mlt_trace_mmlt(job, job->paths[thread], src, depth, out);
  return 1;
}

/* Path depth of bootstrap sample i: pbrt-v3 cycles i through 0..maxDepth. */
static inline uint32_t tt__mlt_boot_depth(const tt_integrator *it, uint64_t i) {
  return it->set.mmlt ? (uint32_t)(i % (it->set.max_depth + 1)) : 0;
}

/* Bootstrap paths [begin, end): their luminance, 0 for non-finite or negative. */
static void tt__mlt_boot_fn(void *vctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  tt__mlt_job *job = vctx;
  tt__mlt_boot_src bs = {job->it->seed, 0};
  tt_sample_source src = {tt__mlt_boot_get, NULL, &bs};
  uint64_t rays = 0;
  for (uint64_t i = begin; i < end; ++i) {
    bs.index = i;
    tt__mlt_sample r;
    if (!tt__mlt_eval(job, thread_index, &src, tt__mlt_boot_depth(job->it, i), &r)) {
      atomic_store(&job->failed, 1);
      return;
    }
    double c = tt__mlt_lum(r.L);
    job->weights[i] = (isfinite(c) && c > 0.0 && !r.nonfinite) ? c : 0.0;
    rays += r.rays;
  }
  atomic_fetch_add(&job->rays, rays);
}

/* Chains [begin, end): replay their bootstrap start as a forced large step. */
static void tt__mlt_start_fn(void *vctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  tt__mlt_job *job = vctx;
  tt_integrator *it = job->it;
  for (uint64_t c = begin; c < end; ++c) {
    tt__mlt_chain *ch = &it->chains[c];
    tt__mlt_chain_init(ch, it->chain_mem + c * tt__mlt_chain_bytes(it->dims), it->dims,
                       &it->kernel);
    if (it->set.mmlt) ch->pair_stride = TT__MLT_STREAMS;
    tt__mlt_chain_start(ch, it->seed, job->starts[c], c);
    if (it->chain_depth) it->chain_depth[c] = (uint8_t)tt__mlt_boot_depth(it, job->starts[c]);
    tt__mlt_chain_propose(ch);
    tt_sample_source src = tt__mlt_chain_source(ch);
    tt__mlt_sample r;
    if (!tt__mlt_eval(job, thread_index, &src, it->chain_depth ? it->chain_depth[c] : 0, &r)) {
      atomic_store(&job->failed, 1);
      return;
    }
    tt__mlt_chain_accept(ch);
    memcpy(ch->L, r.L, sizeof ch->L);
    ch->fx = r.fx;
    ch->fy = r.fy;
    ch->C = tt__mlt_lum(r.L); /* = the bootstrap weight (> 0): the evaluation is deterministic */
  }
}

/* Bootstraps b and the chains for the film of this pass. */
static tt_status tt__mlt_bootstrap(tt_integrator *it, tt__mlt_job *job) {
  const tt__mlt_settings *s = &it->set;
  /* mmlt: bootstrapSamples per path depth, sample i of depth i % (maxDepth + 1) (pbrt-v3) */
  const uint64_t depths = s->mmlt ? s->max_depth + 1 : 1;
  uint64_t n = s->bootstrap * depths;
  it->seed = job->ctx->seed;
  it->width = job->width;
  it->height = job->height;
  it->nchains = s->chains;
  it->dims = s->mmlt ? tt__mlt_mmlt_dims(s->max_depth) : TT_PATH_DIM_COUNT(s->max_depth);
  job->weights = malloc(n * sizeof(double));
  job->starts = malloc((size_t)it->nchains * sizeof(uint64_t));
  it->chains = calloc(it->nchains, sizeof(tt__mlt_chain));
  it->chain_mem = malloc((size_t)it->nchains * tt__mlt_chain_bytes(it->dims));
  if (s->mmlt) it->chain_depth = calloc(it->nchains, 1);
  tt_status st = TT_OK;
  if (!job->weights || !job->starts || !it->chains || !it->chain_mem ||
      (s->mmlt && !it->chain_depth)) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY,
                      TT__MLT_NAME ": out of memory for %llu bootstrap samples and %u chains",
                      (unsigned long long)n, it->nchains);
    goto done;
  }
  const tt_host *host = tt__mlt_host();
  st = host->parallel_for(n, 256, tt__mlt_boot_fn, job);
  if (st == TT_OK && atomic_load(&job->failed))
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY,
                      TT__MLT_NAME ": out of memory for the bidirectional subpaths");
  if (st != TT_OK) goto done;
  /* Serial prefix sum: deterministic b whatever the thread count. */
  double sum = 0.0;
  uint64_t nonzero = 0;
  for (uint64_t i = 0; i < n; ++i) {
    nonzero += job->weights[i] > 0.0;
    sum += job->weights[i];
    job->weights[i] = sum;
  }
  if (!(sum > 0.0)) {
    /* b = 0: the estimate of every pixel is 0, a black image like PT's, not a failure */
    it->b = 0.0;
    it->black = 1;
    it->ready = 1;
    it->mutations_total = 0;
    tt_host_log(host, TT_LOG_WARN, TT__MLT_NAME,
                "all %llu bootstrap paths have zero contribution: nothing "
                "in view is lit, the image is black (raise bootstrap if the lights are tiny)",
                (unsigned long long)n);
    goto done;
  }
  it->b = sum / (double)n * (double)depths; /* mmlt: the mean over depths of each depth's image */
  for (uint32_t c = 0; c < it->nchains; ++c) { /* starts in proportion to the weights */
    double u = tt__u64_to_unit(tt__hash3(it->seed, c, 0x7374617274ull)) * sum;
    uint64_t lo = 0, hi = n - 1;
    while (lo < hi) { /* first i with prefix[i] > u */
      uint64_t mid = lo + (hi - lo) / 2;
      if (job->weights[mid] > u) hi = mid;
      else lo = mid + 1;
    }
    job->starts[c] = lo;
  }
  st = host->parallel_for(it->nchains, 1, tt__mlt_start_fn, job);
  if (st == TT_OK && atomic_load(&job->failed))
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY,
                      TT__MLT_NAME ": out of memory for the bidirectional subpaths");
  if (st == TT_OK) {
    it->ready = 1;
    it->mutations_total = 0;
    tt_host_log(host, TT_LOG_INFO, TT__MLT_NAME,
                "bootstrap (%s): %llu paths (%llu non-zero), b = %.6g, %u chains",
                s->mmlt ? "mmlt" : "pssmlt", (unsigned long long)n, (unsigned long long)nonzero,
                it->b, it->nchains);
  }
done:
  free(job->weights);
  free(job->starts);
  job->weights = NULL;
  job->starts = NULL;
  if (!it->ready) tt__mlt_drop_chains(it);
  return st;
}

/* Adds w * L / C at pixel `pix` to the fixed-point accumulator (finite values only). */
static inline void tt__mlt_splat(tt__mlt_job *job, uint32_t pix, const float L[3], double C,
                                 double w) {
  double k = w / C * TT__MLT_FIXED_SCALE;
  _Atomic int64_t *acc = job->it->acc + 3 * (size_t)pix;
  for (int i = 0; i < 3; ++i) {
    double v = (double)L[i] * k;
    if (!(v > 0.0)) continue; /* also drops NaN */
    int64_t q = llrint(v);
    if (q) atomic_fetch_add_explicit(&acc[i], q, memory_order_relaxed);
  }
}

/* Pixel of a film position (positions come from [0, 1) samples). */
static inline uint32_t tt__mlt_pixel(const tt__mlt_job *job, float fx, float fy) {
  uint32_t x = (uint32_t)fx, y = (uint32_t)fy;
  if (x >= job->width) x = job->width - 1;
  if (y >= job->height) y = job->height - 1;
  return y * job->width + x;
}

/* Runs the pass's mutations of chains [begin, end). */
static void tt__mlt_mutate_fn(void *vctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  tt__mlt_job *job = vctx;
  tt_integrator *it = job->it;
  const tt_host *host = tt__mlt_host();
  uint64_t rays = 0, done = 0, nonfinite = 0, sp = 0, sa = 0, lp = 0, la = 0, vertices = 0;
  uint64_t theta[TT__MLT_THETA_BINS + 1];
  int dump = it->theta_dump != NULL;
  if (dump) memset(theta, 0, sizeof theta);
  for (uint64_t c = begin; c < end && !atomic_load(&job->interrupted); ++c) {
    tt__mlt_chain *ch = &it->chains[c];
    ch->theta_hist = dump ? theta : NULL;
    uint64_t quota = job->base + (c < job->extra ? 1 : 0);
    tt_sample_source src = tt__mlt_chain_source(ch);
    const uint32_t depth = it->chain_depth ? it->chain_depth[c] : 0;
    for (uint64_t m = 0; m < quota; ++m) {
      if (m % TT__MLT_STOP_CHECK == 0 && host->should_stop && host->should_stop()) {
        atomic_store(&job->interrupted, 1);
        break;
      }
      tt__mlt_chain_propose(ch);
      tt__mlt_sample r;
      if (!tt__mlt_eval(job, thread_index, &src, depth, &r)) {
        tt__mlt_chain_reject(ch);
        atomic_store(&job->failed, 1);
        atomic_store(&job->interrupted, 1);
        break;
      }
      const float fx = r.fx, fy = r.fy;
      rays += r.rays;
      vertices += r.vertices;
      double cy = tt__mlt_lum(r.L);
      if (r.nonfinite || !isfinite(cy) || cy < 0.0) { /* never splatted, never accepted */
        nonfinite++;
        cy = 0.0;
      }
      double lr = tt__mlt_chain_log_T_ratio(ch);
      double a;
      if (!(cy > 0.0)) a = 0.0;
      else if (!(ch->C > 0.0)) a = 1.0;
      else {
        double la_ = log(cy) - log(ch->C) + lr;
        a = la_ >= 0.0 ? 1.0 : exp(la_);
      }
      /* Expected values: the proposal with weight a, the current state with 1 - a. */
      if (a > 0.0) tt__mlt_splat(job, tt__mlt_pixel(job, fx, fy), r.L, cy, a);
      if (a < 1.0 && ch->C > 0.0)
        tt__mlt_splat(job, tt__mlt_pixel(job, ch->fx, ch->fy), ch->L, ch->C, 1.0 - a);
      int large = ch->large;
      int accept = tt__mlt_rng_unit(&ch->rng) < a;
      if (large) {
        lp++;
        la += accept;
      } else {
        sp++;
        sa += accept;
      }
      if (accept) {
        tt__mlt_chain_accept(ch);
        memcpy(ch->L, r.L, sizeof ch->L);
        ch->C = cy;
        ch->fx = fx;
        ch->fy = fy;
      } else {
        tt__mlt_chain_reject(ch);
      }
      done++;
    }
    ch->theta_hist = NULL;
  }
  atomic_fetch_add(&job->rays, rays);
  atomic_fetch_add(&job->mutations, done);
  atomic_fetch_add(&job->vertices, vertices);
  atomic_fetch_add(&job->nonfinite, nonfinite);
  atomic_fetch_add(&job->small_prop, sp);
  atomic_fetch_add(&job->small_acc, sa);
  atomic_fetch_add(&job->large_prop, lp);
  atomic_fetch_add(&job->large_acc, la);
  if (dump)
    for (int i = 0; i <= TT__MLT_THETA_BINS; ++i)
      if (theta[i]) atomic_fetch_add(&job->theta[i], theta[i]);
}

/* Writes the Theta histogram (CSV with a comment header) for tools/pssmlt. */
static void tt__mlt_write_theta(const tt_integrator *it) {
  tt_atomic_file *af;
  if (tt_atomic_file_open(it->theta_dump, &af) != TT_OK) {
    tt_host_log(tt__mlt_host(), TT_LOG_WARN, TT__MLT_NAME, "cannot write the Theta dump: %s",
                tt_last_error());
    return;
  }
  FILE *f = tt_atomic_file_stream(af);
  fprintf(f, "# integrator_pssmlt Theta = 1/(alpha*pdf) histogram of proposed BSDF directions\n");
  fprintf(f, "# alpha=%.9g bins=%d binning=%d edges=", it->kernel.alpha, it->kernel.bins,
          it->kernel.binning);
  for (int i = 0; i <= it->kernel.bins; ++i)
    fprintf(f, "%s%.9g", i ? ";" : "", it->kernel.edges[i]);
  fprintf(f, "\ntheta_lo,theta_hi,count\n");
  for (int i = 0; i < TT__MLT_THETA_BINS; ++i)
    fprintf(f, "%.6f,%.6f,%llu\n", (double)i / TT__MLT_THETA_BINS,
            (double)(i + 1) / TT__MLT_THETA_BINS, (unsigned long long)it->theta_hist[i]);
  fprintf(f, "1.000000,inf,%llu\n", (unsigned long long)it->theta_hist[TT__MLT_THETA_BINS]);
  if (tt_atomic_file_commit(af) != TT_OK)
    tt_host_log(tt__mlt_host(), TT_LOG_WARN, TT__MLT_NAME, "cannot write the Theta dump: %s",
                tt_last_error());
}

/* The film's AOV planes: PSSMLT's paths land anywhere on the film, so the AOVs come from a
 * pass of their own, one first-hit ray per pixel per render pass (at the pass's Halton(2,3)
 * offset, or the frame's fixed jitter), folded into the running mean as the path tracer
 * does (tt_path_write_aovs): with N passes an AOV is the mean of N stratified samples. */
typedef struct tt__mlt_aov_job {
  tt__mlt_job *job;
  tt_path_options opts; /* max_depth 0: the first hit only, no light sampling */
  tt_camera_frame prev;
  int has_prev;
  float jitter[2];
  uint64_t n; /* this pass's AOV sample number since the film was cleared */
} tt__mlt_aov_job;

static void tt__mlt_aov_fn(void *vctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  tt__mlt_aov_job *a = vctx;
  tt__mlt_job *job = a->job;
  (void)thread_index;
  tt__mlt_boot_src bs = {job->it->seed, 0}; /* a depth-0 path draws no sample dimension */
  tt_sample_source src = {tt__mlt_boot_get, NULL, &bs};
  uint64_t rays = 0;
  for (uint64_t y = begin; y < end; ++y) {
    for (uint32_t x = 0; x < job->width; ++x) {
      float fx = (float)x + 0.5f + a->jitter[0], fy = (float)y + 0.5f + a->jitter[1];
      tt_ray ray;
      tt_camera_generate_ray(&job->frame, fx, fy, &ray);
      tt_path_result r;
      tt_path_trace(job->it->pt, &job->tracer, &a->opts, &ray, &src, &r);
      tt_path_write_aovs_ex(job->ctx->film, x, (uint32_t)y, &job->frame,
                            a->has_prev ? &a->prev : NULL, fx, fy, &ray, &r, r.prev_position, a->n);
      rays += r.rays;
    }
  }
  atomic_fetch_add(&job->rays, rays);
}

static tt_status tt__mlt_aovs(tt__mlt_job *job) {
  const tt_render_ctx *ctx = job->ctx;
  tt__mlt_aov_job a;
  memset(&a, 0, sizeof a);
  a.job = job;
  a.opts = job->it->opts;
  a.opts.max_depth = 0;
  a.has_prev = ctx->prev_camera && tt_camera_frame_init(&a.prev, ctx->prev_camera) == TT_OK;
  if (ctx->prev_camera && !a.has_prev) tt_clear_error();
  if (ctx->fixed_jitter) {
    a.jitter[0] = ctx->jitter[0];
    a.jitter[1] = ctx->jitter[1];
  } else {
    tt_jitter_halton23(ctx->pass_index, a.jitter);
  }
  a.n = ctx->sample_offset == 0 ? 1 : (uint64_t)ctx->pass_index + 1;
  return tt__mlt_host()->parallel_for(job->height, 1, tt__mlt_aov_fn, &a);
}

static tt_status tt__mlt_render_pass(tt_integrator *it, const tt_render_ctx *ctx,
                                     tt_pass_stats *stats) {
  if (!it || !ctx || !ctx->film || !ctx->camera || !ctx->accel_iface || !ctx->accel)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__MLT_NAME ": render_pass needs film, camera and accel");
  const tt_host *host = tt__mlt_host();
  uint64_t t0 = host->clock_ns();
  uint32_t w = tt_film_width(ctx->film), h = tt_film_height(ctx->film);
  if (w != ctx->camera->width || h != ctx->camera->height)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__MLT_NAME ": film %ux%u differs from camera %ux%u", w, h,
                        ctx->camera->width, ctx->camera->height);
  tt__mlt_job *job = calloc(1, sizeof *job);
  if (!job) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__MLT_NAME ": out of memory");
  job->it = it;
  job->ctx = ctx;
  job->width = w;
  job->height = h;
  job->tracer.iface = ctx->accel_iface;
  job->tracer.accel = ctx->accel;
  tt_status st = tt_camera_frame_init(&job->frame, ctx->camera);
  size_t pixels = (size_t)w * h;
  job->threads = host->thread_count ? host->thread_count() : 1;
  if (job->threads < 1) job->threads = 1;
  atomic_init(&job->failed, 0);
  if (st == TT_OK && it->set.mmlt) {
    job->paths = calloc(job->threads, sizeof *job->paths);
    if (!job->paths) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__MLT_NAME ": out of memory");
  }
  if (st == TT_OK && it->acc_pixels != pixels) { /* allocated once per film size */
    free((void *)it->acc);
    it->acc = calloc(3 * pixels, sizeof(int64_t));
    it->acc_pixels = it->acc ? pixels : 0;
    if (!it->acc)
      st = tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__MLT_NAME ": out of memory for the splat buffer");
  }
  if (st != TT_OK) {
    free(job->paths);
    free(job);
    return st;
  }

  /* A new target (first pass, reset, maxDepth/chains/bootstrap changed, other film size)
   * starts over; a film without earlier passes restarts the count but keeps the chains. */
  double boot_ms = 0.0;
  if (it->ready && (it->width != w || it->height != h)) tt__mlt_drop_chains(it);
  if (!it->ready) {
    uint64_t b0 = host->clock_ns();
    st = tt__mlt_bootstrap(it, job);
    boot_ms = (double)(host->clock_ns() - b0) * 1e-6;
    if (st == TT_OK && ctx->sample_offset > 0) /* the film holds an older estimate */
      memset(tt_film_splat_rgb(ctx->film), 0, 3 * pixels * sizeof(float));
  } else if (ctx->sample_offset == 0) {
    it->mutations_total = 0;
  }
  uint64_t boot_rays = atomic_load(&job->rays);

  if (st == TT_OK && !it->black) {
    uint64_t total = (uint64_t)ctx->spp * it->set.mpp * pixels;
    job->base = total / it->nchains;
    job->extra = total % it->nchains;
    tt_status pst = host->parallel_for(it->nchains, 1, tt__mlt_mutate_fn, job);
    if (atomic_load(&job->failed))
      st = tt_set_error(TT_ERR_OUT_OF_MEMORY,
                        TT__MLT_NAME ": out of memory for the bidirectional subpaths");
    else if (pst == TT_ERR_INTERRUPTED || atomic_load(&job->interrupted)) st = TT_ERR_INTERRUPTED;
    else if (pst != TT_OK) st = pst;
    /* Flush the pass into the film: one splat per pixel, so the order is irrelevant. */
    for (size_t p = 0; p < pixels; ++p) {
      _Atomic int64_t *q = it->acc + 3 * p;
      int64_t q0 = atomic_load(&q[0]), q1 = atomic_load(&q[1]), q2 = atomic_load(&q[2]);
      if (!(q0 | q1 | q2)) continue;
      float rgb[3] = {(float)(q0 / TT__MLT_FIXED_SCALE), (float)(q1 / TT__MLT_FIXED_SCALE),
                      (float)(q2 / TT__MLT_FIXED_SCALE)};
      tt_film_splat(ctx->film, (float)(p % w) + 0.5f, (float)(p / w) + 0.5f, rgb);
      atomic_store(&q[0], 0);
      atomic_store(&q[1], 0);
      atomic_store(&q[2], 0);
    }
    it->mutations_total += atomic_load(&job->mutations);
    if (it->mutations_total > 0)
      tt_film_set_splat_scale(ctx->film, it->b * (double)pixels / (double)it->mutations_total);
    if (it->theta_dump) {
      for (int i = 0; i <= TT__MLT_THETA_BINS; ++i)
        it->theta_hist[i] += atomic_load(&job->theta[i]);
      tt__mlt_write_theta(it);
    }
    if (st == TT_OK && tt_film_aov_mask(ctx->film)) st = tt__mlt_aovs(job);
  }

  uint64_t t1 = host->clock_ns();
  if (stats) {
    tt_pass_stats local;
    memset(&local, 0, sizeof local);
    local.time_ms = (double)(t1 - t0) * 1e-6;
    local.rays = atomic_load(&job->rays);
    local.samples = atomic_load(&job->mutations);
    local.nonfinite = atomic_load(&job->nonfinite);
    double mut_s = (local.time_ms - boot_ms) * 1e-3;
    uint64_t sp = atomic_load(&job->small_prop), sa = atomic_load(&job->small_acc);
    uint64_t lp = atomic_load(&job->large_prop), la = atomic_load(&job->large_acc);
    double small = sp ? (double)sa / sp : 0.0;
    double nm = local.samples ? (double)local.samples : 1.0;
    const char *names[] = {"acceptance",
                           "small_step_acceptance",
                           "acceptance_small",
                           "large_step_acceptance",
                           "mutations_per_s",
                           "mutations",
                           "b",
                           "rays_per_s",
                           "bootstrap_ms",
                           "rays_per_mutation",
                           "mean_path_length"};
    double values[] = {sp + lp ? (double)(sa + la) / (sp + lp) : 0.0,
                       small,
                       small,
                       lp ? (double)la / lp : 0.0,
                       mut_s > 0.0 ? (double)local.samples / mut_s : 0.0,
                       (double)local.samples,
                       it->b,
                       mut_s > 0.0 ? (double)(local.rays - boot_rays) / mut_s : 0.0,
                       boot_ms,
                       (double)(local.rays - boot_rays) / nm,
                       (double)atomic_load(&job->vertices) / nm};
    local.metric_count = (uint32_t)(sizeof values / sizeof values[0]);
    for (uint32_t m = 0; m < local.metric_count; ++m) {
      local.metrics[m].name = names[m];
      local.metrics[m].value = values[m];
    }
    size_t n = stats->struct_size < sizeof local ? stats->struct_size : sizeof local;
    local.struct_size = (uint32_t)n;
    memcpy(stats, &local, n);
  }
  for (uint32_t i = 0; job->paths && i < job->threads; ++i) tt_bdpt_paths_destroy(job->paths[i]);
  free(job->paths);
  free(job);
  if (st == TT_ERR_INTERRUPTED)
    return tt_set_error(TT_ERR_INTERRUPTED,
                        TT__MLT_NAME ": pass interrupted (mutations done are in the film)");
  return st;
}

static const tt_integrator_iface tt__mlt_iface = {
    .struct_size = sizeof(tt_integrator_iface),
    .space = tt__mlt_space,
    .create = tt__mlt_create,
    .configure = tt__mlt_configure,
    .render_pass = tt__mlt_render_pass,
    .reset = tt__mlt_reset,
    .destroy = tt__mlt_destroy,
};

/* Tells a tuning host what to minimise by default (thesis 4.4: small-step acceptance). */
/* What the thesis tunes (4.4): the bin edges a_1..a_{M+1} and sigmas sigma_1..sigma_M of the
 * default M = 7, plus the sigma of the non-direction dimensions, with binning on. Chains,
 * bootstrap size or depth would change the cost of a measurement, not the method. */
static const char *const tt__mlt_tunable[] = {
    "a1",     "a2",     "a3",     "a4",     "a5",     "a6",     "a7",    "a8", "sigma1",
    "sigma2", "sigma3", "sigma4", "sigma5", "sigma6", "sigma7", "sigma", NULL};

static const tt_tuning_hint tt__mlt_hint = {
    .struct_size = sizeof(tt_tuning_hint),
    .objective = "metric:small_step_acceptance:target=0.234",
    .tunable = tt__mlt_tunable,
    .setup = "{\"binning\": true, \"bins\": 7}",
};

static tt_status tt__mlt_init(const tt_host *host) {
  g_host = host;
  return g_space ? TT_OK : tt__mlt_build_space();
}

static void tt__mlt_deinit(void) {
  tt_space_destroy(g_space);
  g_space = NULL;
  g_host = NULL;
}

static const void *tt__mlt_get_interface(const char *id) {
  if (!id) return NULL;
  if (strcmp(id, TT_INTEGRATOR_INTERFACE_ID) == 0) return &tt__mlt_iface;
  if (strcmp(id, TT_TUNING_HINT_ID) == 0) return &tt__mlt_hint;
  return NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
    .struct_size = sizeof(tt_plugin),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .kind = TT_KIND_INTEGRATOR,
    .name = TT__MLT_NAME,
    .version = TT__MLT_VERSION,
    .description =
        "PSSMLT over the path tracer or multiplexed MLT over BDPT, with sigma-binning and "
        "truncated-normal steps (thesis ch. 4)",
    .init = tt__mlt_init,
    .deinit = tt__mlt_deinit,
    .get_interface = tt__mlt_get_interface,
};
