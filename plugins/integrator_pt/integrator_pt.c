/* integrator_pt: progressive unidirectional path tracer (kind TT_KIND_INTEGRATOR).
 *
 * Each render_pass adds ctx->spp samples to every pixel. Work is split into square tiles
 * handed to host->parallel_for; the random numbers of a sample depend only on (seed, pixel,
 * sample index, dimension), never on the tile order or the thread, so an image is
 * bit-identical for a fixed seed whatever the thread count. Paths come from the shared core
 * path sampler (tunetrace/path.h); see README.md for parameters and dimension layout. */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include <tunetrace/camera.h>
#include <tunetrace/integrator.h>
#include <tunetrace/path.h>
#include <tunetrace/plugin.h>

#define PT_NAME "integrator_pt"
#define PT_VERSION "0.1.0"
#define PT_MAX_STATE 256
#define PT_BH_RADIUS 1.5f
#define PT_BH_TABLE 512

static const tt_host *g_host;
static tt_space *g_space;
/* Blackman-Harris 1D CDF over [-radius, radius], PT_BH_TABLE bins (built at init). */
static float g_bh_cdf[PT_BH_TABLE + 1];

typedef struct pt_settings {
  tt_path_options path;
  const tt_sampler_iface *sampler;
  int filter_bh;
  uint32_t tile_size;
} pt_settings;

struct tt_integrator {
  const tt_scene *scene;
  tt_path_tracer *pt;
  pt_settings settings;
};

/* ---- parameters ---- */

/* The host, or libtunetrace's default services when the plugin is used without init(). */
static const tt_host *pt_host(void) { return g_host ? g_host : tt_default_host(); }

/* Builds the parameter space once (init). */
static tt_status pt_build_space(void) {
  static const char *const heuristics[] = {"power", "balance"};
  static const char *const samplers[] = {"independent", "halton", "sobol"};
  static const char *const filters[] = {"box", "blackman-harris"};
  tt_space *s = tt_space_create(PT_NAME, PT_VERSION);
  if (!s) return tt_set_error(TT_ERR_OUT_OF_MEMORY, PT_NAME ": cannot create the parameter space");
  int ok = 1;
  ok &= tt_space_add_int(s, "maxDepth", 0, 64, 3, "maximum number of bounces (0: emission only)") >= 0;
  ok &= tt_space_add_int(s, "rrDepth", 0, 64, 3, "bounce from which Russian roulette may end paths") >= 0;
  ok &= tt_space_add_nom_bool(s, "mis", 1, "combine light and BSDF sampling with MIS (false: light sampling only)") >= 0;
  ok &= tt_space_add_nom_string(s, "heuristic", heuristics, 2, 0, "MIS heuristic") >= 0;
  ok &= tt_space_add_nom_string(s, "sampler", samplers, 3, 0, "primary-sample generator") >= 0;
  ok &= tt_space_add_nom_string(s, "filter", filters, 2, 0,
                                "pixel filter, importance-sampled (blackman-harris: radius 1.5 px)") >= 0;
  ok &= tt_space_add_int(s, "tileSize", 4, 256, 32, "side of the square tiles handed to worker threads") >= 0;
  if (!ok) {
    tt_space_destroy(s);
    return tt_set_error(TT_ERR_INTERNAL, PT_NAME ": building the parameter space failed");
  }
  g_space = s;
  return TT_OK;
}

/* Blackman-Harris window on [-r, r]. */
static double pt_bh(double x) {
  double t = x / (2.0 * PT_BH_RADIUS) + 0.5;
  return 0.35875 - 0.48829 * cos(2.0 * M_PI * t) + 0.14128 * cos(4.0 * M_PI * t) -
         0.01168 * cos(6.0 * M_PI * t);
}

/* Tabulates the filter CDF (midpoint rule per bin; the window is positive). */
static void pt_build_bh_table(void) {
  double acc = 0.0, sum[PT_BH_TABLE + 1];
  sum[0] = 0.0;
  for (int i = 0; i < PT_BH_TABLE; ++i) {
    double x = -PT_BH_RADIUS + (i + 0.5) * (2.0 * PT_BH_RADIUS / PT_BH_TABLE);
    acc += pt_bh(x);
    sum[i + 1] = acc;
  }
  for (int i = 0; i <= PT_BH_TABLE; ++i) g_bh_cdf[i] = (float)(sum[i] / acc);
  g_bh_cdf[PT_BH_TABLE] = 1.0f;
}

/* Inverts the tabulated CDF: offset in [-r, r] distributed as the filter. */
static float pt_bh_sample(float u) {
  int lo = 0, hi = PT_BH_TABLE;
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (g_bh_cdf[mid] <= u) lo = mid; else hi = mid;
  }
  float w = g_bh_cdf[lo + 1] - g_bh_cdf[lo];
  float f = w > 0.0f ? (u - g_bh_cdf[lo]) / w : 0.5f;
  return -PT_BH_RADIUS + ((float)lo + f) * (2.0f * PT_BH_RADIUS / PT_BH_TABLE);
}

/* Reads a configuration (NULL = defaults) into settings. */
static tt_status pt_read_config(const tt_config *config, pt_settings *out) {
  tt_config *defaults = NULL;
  if (!config) {
    if (!g_space) return tt_set_error(TT_ERR_INTERNAL, PT_NAME ": used before init()");
    defaults = tt_config_create(g_space);
    if (!defaults) return tt_set_error(TT_ERR_OUT_OF_MEMORY, PT_NAME ": out of memory");
    config = defaults;
  }
  tt_status st = TT_OK;
  tt_path_options_default(&out->path);
  out->path.max_depth = (uint32_t)tt_config_get_int(config, "maxDepth", 3);
  out->path.rr_depth = (uint32_t)tt_config_get_int(config, "rrDepth", 3);
  int mis = (int)tt_config_get_int(config, "mis", 1);
  const char *h = tt_config_get_string(config, "heuristic");
  const char *s = tt_config_get_string(config, "sampler");
  const char *f = tt_config_get_string(config, "filter");
  out->path.strategy = TT_STRATEGY_MIS;
  out->path.heuristic = !mis ? TT_MIS_NONE
                        : (h && strcmp(h, "balance") == 0) ? TT_MIS_BALANCE : TT_MIS_POWER;
  out->sampler = tt_builtin_sampler(s ? s : "independent");
  if (!out->sampler)
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT, PT_NAME ": unknown sampler '%s'", s ? s : "");
  out->filter_bh = f && strcmp(f, "blackman-harris") == 0;
  int64_t ts = tt_config_get_int(config, "tileSize", 32);
  out->tile_size = (uint32_t)(ts < 4 ? 4 : ts > 256 ? 256 : ts);
  if (out->path.max_depth > 64) out->path.max_depth = 64;
  tt_config_destroy(defaults);
  return st;
}

/* ---- interface ---- */

static const tt_space *pt_space(void) { return g_space; }

static tt_status pt_create(const tt_scene *scene, const tt_config *config, tt_integrator **out) {
  if (!scene || !out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, PT_NAME ": scene or out is NULL");
  *out = NULL;
  tt_integrator *it = calloc(1, sizeof *it);
  if (!it) return tt_set_error(TT_ERR_OUT_OF_MEMORY, PT_NAME ": out of memory");
  it->scene = scene;
  tt_status st = pt_read_config(config, &it->settings);
  if (st == TT_OK) st = tt_path_tracer_create(scene, &it->pt);
  if (st != TT_OK) {
    free(it);
    return st;
  }
  *out = it;
  return TT_OK;
}

static tt_status pt_configure(tt_integrator *it, const tt_config *config) {
  pt_settings s;
  tt_status st = pt_read_config(config, &s);
  if (st == TT_OK) it->settings = s;
  return st;
}

static void pt_reset(tt_integrator *it) { (void)it; /* stateless between passes */ }

static void pt_destroy(tt_integrator *it) {
  if (!it) return;
  tt_path_tracer_destroy(it->pt);
  free(it);
}

/* Everything the tile workers share during one pass. */
typedef struct pt_job {
  const tt_integrator *it;
  const tt_render_ctx *ctx;
  const tt_sampler *sampler;
  tt_camera_frame frame, prev_frame;
  int has_prev;
  tt_tracer tracer;
  uint32_t tiles_x, tile_size, width, height;
  uint32_t aovs;                  /* the film's AOV planes (tt_path_write_aovs fills them) */
  atomic_uint_fast64_t rays, samples, nonfinite;
  atomic_int interrupted;
} pt_job;

/* Sample source over the sampler's per-thread state. */
typedef struct pt_source {
  const tt_sampler_iface *iface;
  const tt_sampler *sampler;
  void *state;
} pt_source;

static float pt_source_get(void *self, uint32_t dim) {
  pt_source *s = self;
  return s->iface->get(s->sampler, s->state, dim);
}

/* Renders tiles [begin, end); a tile is skipped whole when a stop was requested. */
static void pt_tile_fn(void *vctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  pt_job *job = vctx;
  const tt_render_ctx *ctx = job->ctx;
  const pt_settings *set = &job->it->settings;
  const tt_host *host = pt_host();
  _Alignas(16) unsigned char state[PT_MAX_STATE];
  pt_source src = {set->sampler, job->sampler, state};
  tt_sample_source source = {pt_source_get, NULL, &src};
  uint64_t rays = 0, samples = 0, nonfinite = 0;
  for (uint64_t tile = begin; tile < end; ++tile) {
    if (host->should_stop && host->should_stop()) {
      atomic_store(&job->interrupted, 1);
      break;
    }
    uint32_t x0 = (uint32_t)(tile % job->tiles_x) * job->tile_size;
    uint32_t y0 = (uint32_t)(tile / job->tiles_x) * job->tile_size;
    uint32_t x1 = x0 + job->tile_size < job->width ? x0 + job->tile_size : job->width;
    uint32_t y1 = y0 + job->tile_size < job->height ? y0 + job->tile_size : job->height;
    for (uint32_t py = y0; py < y1; ++py) {
      for (uint32_t px = x0; px < x1; ++px) {
        for (uint32_t s = 0; s < ctx->spp; ++s) {
          set->sampler->start(job->sampler, state, px, py, ctx->sample_offset + s);
          float jx, jy;
          if (ctx->fixed_jitter) {
            jx = ctx->jitter[0];
            jy = ctx->jitter[1];
          } else {
            float u0 = set->sampler->get(job->sampler, state, TT_PATH_DIM_FILM);
            float u1 = set->sampler->get(job->sampler, state, TT_PATH_DIM_FILM + 1);
            if (set->filter_bh) {
              jx = pt_bh_sample(u0);
              jy = pt_bh_sample(u1);
            } else {
              jx = u0 - 0.5f;
              jy = u1 - 0.5f;
            }
          }
          float fx = (float)px + 0.5f + jx, fy = (float)py + 0.5f + jy;
          tt_ray ray;
          tt_camera_generate_ray(&job->frame, fx, fy, &ray);
          tt_path_result r;
          tt_path_trace(job->it->pt, &job->tracer, &set->path, &ray, &source, &r);
          tt_film_add_sample(ctx->film, px, py, r.L, 1.0f);
          rays += r.rays;
          samples++;
          nonfinite += r.nonfinite ? 1u : 0u;
          if (job->aovs)
            tt_path_write_aovs(ctx->film, px, py, &job->frame,
                               job->has_prev ? &job->prev_frame : NULL, fx, fy, &ray, &r,
                               ctx->sample_offset + s + 1);
        }
      }
    }
  }
  atomic_fetch_add(&job->rays, rays);
  atomic_fetch_add(&job->samples, samples);
  atomic_fetch_add(&job->nonfinite, nonfinite);
}

static tt_status pt_render_pass(tt_integrator *it, const tt_render_ctx *ctx, tt_pass_stats *stats) {
  if (!it || !ctx || !ctx->film || !ctx->camera || !ctx->accel_iface || !ctx->accel)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, PT_NAME ": render_pass needs film, camera and accel");
  const tt_host *host = pt_host();
  uint64_t t0 = host->clock_ns ? host->clock_ns() : 0;
  pt_job *job = calloc(1, sizeof *job);
  if (!job) return tt_set_error(TT_ERR_OUT_OF_MEMORY, PT_NAME ": out of memory");
  job->it = it;
  job->ctx = ctx;
  tt_status st = tt_camera_frame_init(&job->frame, ctx->camera);
  if (st == TT_OK && (tt_film_width(ctx->film) != ctx->camera->width ||
                      tt_film_height(ctx->film) != ctx->camera->height))
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT, PT_NAME ": film %ux%u differs from camera %ux%u",
                      tt_film_width(ctx->film), tt_film_height(ctx->film), ctx->camera->width,
                      ctx->camera->height);
  if (st == TT_OK && ctx->prev_camera) {
    job->has_prev = tt_camera_frame_init(&job->prev_frame, ctx->prev_camera) == TT_OK;
    if (!job->has_prev) tt_clear_error();
  }
  const pt_settings *set = &it->settings;
  tt_sampler *sampler = NULL;
  if (st == TT_OK) st = set->sampler->create(NULL, ctx->seed, &sampler);
  if (st == TT_OK && set->sampler->state_size(sampler) > PT_MAX_STATE)
    st = tt_set_error(TT_ERR_UNSUPPORTED, PT_NAME ": sampler '%s' needs more than %d bytes of state",
                      set->sampler->name, PT_MAX_STATE);
  if (st != TT_OK) {
    if (sampler) set->sampler->destroy(sampler);
    free(job);
    return st;
  }
  job->sampler = sampler;
  job->tracer.iface = ctx->accel_iface;
  job->tracer.accel = ctx->accel;
  job->width = ctx->camera->width;
  job->height = ctx->camera->height;
  job->tile_size = set->tile_size;
  job->tiles_x = (job->width + job->tile_size - 1) / job->tile_size;
  uint32_t tiles_y = (job->height + job->tile_size - 1) / job->tile_size;
  job->aovs = tt_film_aov_mask(ctx->film);
  atomic_init(&job->rays, 0);
  atomic_init(&job->samples, 0);
  atomic_init(&job->nonfinite, 0);
  atomic_init(&job->interrupted, 0);

  tt_status pst = host->parallel_for((uint64_t)job->tiles_x * tiles_y, 1, pt_tile_fn, job);
  if (pst == TT_ERR_INTERRUPTED || atomic_load(&job->interrupted)) st = TT_ERR_INTERRUPTED;
  else if (pst != TT_OK) st = pst;

  uint64_t t1 = host->clock_ns ? host->clock_ns() : 0;
  if (stats) {
    tt_pass_stats local;
    memset(&local, 0, sizeof local);
    local.time_ms = (double)(t1 - t0) * 1e-6;
    local.rays = atomic_load(&job->rays);
    local.samples = atomic_load(&job->samples);
    local.nonfinite = atomic_load(&job->nonfinite);
    double secs = local.time_ms > 0.0 ? local.time_ms * 1e-3 : 0.0;
    local.metric_count = 2;
    local.metrics[0].name = "samples_per_s";
    local.metrics[0].value = secs > 0.0 ? (double)local.samples / secs : 0.0;
    local.metrics[1].name = "rays_per_s";
    local.metrics[1].value = secs > 0.0 ? (double)local.rays / secs : 0.0;
    size_t n = stats->struct_size < sizeof local ? stats->struct_size : sizeof local;
    local.struct_size = (uint32_t)n;
    memcpy(stats, &local, n);
  }
  set->sampler->destroy(sampler);
  free(job);
  if (st == TT_ERR_INTERRUPTED)
    return tt_set_error(TT_ERR_INTERRUPTED, PT_NAME ": pass interrupted (completed tiles are in the film)");
  return st;
}

static const tt_integrator_iface pt_iface = {
  .struct_size = sizeof(tt_integrator_iface),
  .space = pt_space,
  .create = pt_create,
  .configure = pt_configure,
  .render_pass = pt_render_pass,
  .reset = pt_reset,
  .destroy = pt_destroy,
};

static tt_status pt_init(const tt_host *host) {
  g_host = host;
  pt_build_bh_table();
  return g_space ? TT_OK : pt_build_space();
}

static void pt_deinit(void) {
  tt_space_destroy(g_space);
  g_space = NULL;
  g_host = NULL;
}

static const void *pt_get_interface(const char *id) {
  return id && strcmp(id, TT_INTEGRATOR_INTERFACE_ID) == 0 ? &pt_iface : NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
  .struct_size = sizeof(tt_plugin),
  .abi_major = TT_ABI_MAJOR,
  .abi_minor = TT_ABI_MINOR,
  .kind = TT_KIND_INTEGRATOR,
  .name = PT_NAME,
  .version = PT_VERSION,
  .description = "progressive path tracer: NEE + BSDF sampling with MIS, independent/Halton/Sobol samplers",
  .init = pt_init,
  .deinit = pt_deinit,
  .get_interface = pt_get_interface,
};
