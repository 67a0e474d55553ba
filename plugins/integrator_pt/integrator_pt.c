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

#define TT__PT_NAME "integrator_pt"
#define TT__PT_VERSION "0.1.0"
#define TT__PT_MAX_STATE 256
#define TT__PT_BH_RADIUS 1.5f
#define TT__PT_BH_TABLE 512
/* Paths in flight per thread in wavefront mode: one stream call traces up to this many
 * rays. A 32x32 tile at 1 spp is one wave. */
#define TT__PT_WAVE 1024

static const tt_host *g_host;
static tt_space *g_space;
/* Blackman-Harris 1D CDF over [-radius, radius], TT__PT_BH_TABLE bins (built at init). */
static float g_bh_cdf[TT__PT_BH_TABLE + 1];

typedef struct tt__pt_settings {
  tt_path_options path;
  const tt_sampler_iface *sampler;
  int filter_bh;
  int wavefront;
  uint32_t tile_size;
} tt__pt_settings;

struct tt_integrator {
  const tt_scene *scene;
  tt_path_tracer *pt;
  tt__pt_settings settings;
};

/* ---- parameters ---- */

/* The host, or libtunetrace's default services when the plugin is used without init(). */
static const tt_host *tt__pt_host(void) { return g_host ? g_host : tt_default_host(); }

/* Builds the parameter space once (init). */
static tt_status tt__pt_build_space(void) {
  static const char *const heuristics[] = {"power", "balance"};
  static const char *const samplers[] = {"independent", "halton", "sobol"};
  static const char *const filters[] = {"box", "blackman-harris"};
  tt_space *s = tt_space_create(TT__PT_NAME, TT__PT_VERSION);
  if (!s)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__PT_NAME ": cannot create the parameter space");
  int ok = 1;
  ok &= tt_space_add_int(s, "maxDepth", 0, 64, 3, "maximum number of bounces (0: emission only)") >=
        0;
  ok &= tt_space_add_int(s, "rrDepth", 0, 64, 3,
                         "bounce from which Russian roulette may end paths") >= 0;
  ok &= tt_space_add_nom_bool(
            s, "mis", 1, "combine light and BSDF sampling with MIS (false: light sampling only)") >=
        0;
  ok &= tt_space_add_nom_string(s, "heuristic", heuristics, 2, 0, "MIS heuristic") >= 0;
  /* sobol by default: the least CPU time to equal error on every scene measured
     (tools/charts/sampler_choice.py, the README's "Default sampler") */
  ok &= tt_space_add_nom_string(s, "sampler", samplers, 3, 2, "primary-sample generator") >= 0;
  ok &= tt_space_add_nom_string(
            s, "filter", filters, 2, 0,
            "pixel filter, importance-sampled (blackman-harris: radius 1.5 px)") >= 0;
  ok &= tt_space_add_int(s, "tileSize", 4, 256, 32,
                         "side of the square tiles handed to worker threads") >= 0;
  ok &= tt_space_add_nom_bool(
            s, "wavefront", 1,
            "trace each tile's rays bounce by bounce as streams (intersect_stream / "
            "occluded_stream); false: one path at a time with intersect1 / "
            "occluded1. Same image either way") >= 0;
  if (!ok) {
    tt_space_destroy(s);
    return tt_set_error(TT_ERR_INTERNAL, TT__PT_NAME ": building the parameter space failed");
  }
  g_space = s;
  return TT_OK;
}

/* Blackman-Harris window on [-r, r]. */
static double tt__pt_bh(double x) {
  double t = x / (2.0 * TT__PT_BH_RADIUS) + 0.5;
  return 0.35875 - 0.48829 * cos(2.0 * M_PI * t) + 0.14128 * cos(4.0 * M_PI * t) -
         0.01168 * cos(6.0 * M_PI * t);
}

/* Tabulates the filter CDF (midpoint rule per bin; the window is positive). */
static void tt__pt_build_bh_table(void) {
  double acc = 0.0, sum[TT__PT_BH_TABLE + 1];
  sum[0] = 0.0;
  for (int i = 0; i < TT__PT_BH_TABLE; ++i) {
    double x = -TT__PT_BH_RADIUS + (i + 0.5) * (2.0 * TT__PT_BH_RADIUS / TT__PT_BH_TABLE);
    acc += tt__pt_bh(x);
    sum[i + 1] = acc;
  }
  for (int i = 0; i <= TT__PT_BH_TABLE; ++i) g_bh_cdf[i] = (float)(sum[i] / acc);
  g_bh_cdf[TT__PT_BH_TABLE] = 1.0f;
}

/* Inverts the tabulated CDF: offset in [-r, r] distributed as the filter. */
static float tt__pt_bh_sample(float u) {
  int lo = 0, hi = TT__PT_BH_TABLE;
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (g_bh_cdf[mid] <= u) lo = mid;
    else hi = mid;
  }
  float w = g_bh_cdf[lo + 1] - g_bh_cdf[lo];
  float f = w > 0.0f ? (u - g_bh_cdf[lo]) / w : 0.5f;
  return -TT__PT_BH_RADIUS + ((float)lo + f) * (2.0f * TT__PT_BH_RADIUS / TT__PT_BH_TABLE);
}

/* Reads a configuration (NULL = defaults) into settings. */
static tt_status tt__pt_read_config(const tt_config *config, tt__pt_settings *out) {
  tt_config *defaults = NULL;
  if (!config) {
    if (!g_space) return tt_set_error(TT_ERR_INTERNAL, TT__PT_NAME ": used before init()");
    defaults = tt_config_create(g_space);
    if (!defaults) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__PT_NAME ": out of memory");
    config = defaults;
  }
  tt_status st = TT_OK;
  tt_path_options_default(&out->path);
  out->path.max_depth = (uint32_t)tt_config_get_int(config, "maxDepth", 3);
  out->path.result_size = sizeof(tt_path_result); /* with prev_position: object motion */
  out->path.rr_depth = (uint32_t)tt_config_get_int(config, "rrDepth", 3);
  int mis = (int)tt_config_get_int(config, "mis", 1);
  const char *h = tt_config_get_string(config, "heuristic");
  const char *s = tt_config_get_string(config, "sampler");
  const char *f = tt_config_get_string(config, "filter");
  out->path.strategy = TT_STRATEGY_MIS;
  out->path.heuristic = !mis                               ? TT_MIS_NONE
                        : (h && strcmp(h, "balance") == 0) ? TT_MIS_BALANCE
                                                           : TT_MIS_POWER;
  out->sampler = tt_builtin_sampler(s ? s : "sobol");
  if (!out->sampler)
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__PT_NAME ": unknown sampler '%s'", s ? s : "");
  out->filter_bh = f && strcmp(f, "blackman-harris") == 0;
  out->wavefront = (int)tt_config_get_int(config, "wavefront", 1) != 0;
  int64_t ts = tt_config_get_int(config, "tileSize", 32);
  out->tile_size = (uint32_t)(ts < 4 ? 4 : ts > 256 ? 256 : ts);
  if (out->path.max_depth > 64) out->path.max_depth = 64;
  tt_config_destroy(defaults);
  return st;
}

/* ---- interface ---- */

static const tt_space *tt__pt_space(void) { return g_space; }

static tt_status tt__pt_create(const tt_scene *scene, const tt_config *config,
                               tt_integrator **out) {
  if (!scene || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__PT_NAME ": scene or out is NULL");
  *out = NULL;
  tt_integrator *it = calloc(1, sizeof *it);
  if (!it) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__PT_NAME ": out of memory");
  it->scene = scene;
  tt_status st = tt__pt_read_config(config, &it->settings);
  if (st == TT_OK) st = tt_path_tracer_create(scene, &it->pt);
  if (st != TT_OK) {
    free(it);
    return st;
  }
  *out = it;
  return TT_OK;
}

static tt_status tt__pt_configure(tt_integrator *it, const tt_config *config) {
  tt__pt_settings s;
  tt_status st = tt__pt_read_config(config, &s);
  if (st == TT_OK) it->settings = s;
  return st;
}

static void tt__pt_reset(tt_integrator *it) { (void)it; /* stateless between passes */ }

static void tt__pt_destroy(tt_integrator *it) {
  if (!it) return;
  tt_path_tracer_destroy(it->pt);
  free(it);
}

/* Everything the tile workers share during one pass. */
typedef struct tt__pt_job {
  const tt_integrator *it;
  const tt_render_ctx *ctx;
  const tt_sampler *sampler;
  tt_camera_frame frame, prev_frame;
  int has_prev;
  tt_tracer tracer;
  uint32_t tiles_x, tile_size, width, height;
  uint32_t aovs;              /* the film's AOV planes (tt_path_write_aovs fills them) */
  struct tt__pt_wave **waves; /* wavefront mode: per-thread scratch, made on first use */
  uint32_t wave_count;
  atomic_uint_fast64_t rays, samples, nonfinite;
  atomic_int interrupted;
  atomic_int failed; /* a wave's scratch could not be allocated */
} tt__pt_job;

/* Sample source over the sampler's per-thread state. */
typedef struct tt__pt_source {
  const tt_sampler_iface *iface;
  const tt_sampler *sampler;
  void *state;
} tt__pt_source;

static float tt__pt_source_get(void *self, uint32_t dim) {
  tt__pt_source *s = self;
  return s->iface->get(s->sampler, s->state, dim);
}

/* Starts sample `s` of pixel (px, py) in sampler `state`: the film position (fx, fy) from
 * dimensions 0-1 (or the fixed jitter) and the camera ray through it. */
static void tt__pt_camera_sample(const tt__pt_job *job, void *state, uint32_t px, uint32_t py,
                                 uint32_t s, float *fx, float *fy, tt_ray *ray) {
  const tt_render_ctx *ctx = job->ctx;
  const tt__pt_settings *set = &job->it->settings;
  set->sampler->start(job->sampler, state, px, py, ctx->sample_offset + s);
  float jx, jy;
  if (ctx->fixed_jitter) {
    jx = ctx->jitter[0];
    jy = ctx->jitter[1];
  } else {
    float u0 = set->sampler->get(job->sampler, state, TT_PATH_DIM_FILM);
    float u1 = set->sampler->get(job->sampler, state, TT_PATH_DIM_FILM + 1);
    if (set->filter_bh) {
      jx = tt__pt_bh_sample(u0);
      jy = tt__pt_bh_sample(u1);
    } else {
      jx = u0 - 0.5f;
      jy = u1 - 0.5f;
    }
  }
  *fx = (float)px + 0.5f + jx;
  *fy = (float)py + 0.5f + jy;
  tt_camera_generate_ray(&job->frame, *fx, *fy, ray);
}

/* Wavefront scratch of one thread: up to TT__PT_WAVE paths of a tile, each with its path state
 * and sampler state, and the compacted ray/hit arrays the stream calls take. */
typedef struct tt__pt_wave {
  size_t state_stride, sampler_stride;
  unsigned char *states;   /* TT__PT_WAVE path states */
  unsigned char *samplers; /* TT__PT_WAVE sampler states */
  float (*film_pos)[2];    /* per path: fx, fy */
  tt_path_result *results;
  tt_ray *rays, *next_rays, *shadows;
  tt_hit *hits;
  uint8_t *occluded;
  uint32_t *active, *next_active, *shadow_of;
  void *block;
} tt__pt_wave;

static size_t tt__pt_align16(size_t n) { return (n + 15) & ~(size_t)15; }
static size_t tt__pt_align64(size_t n) { return (n + 63) & ~(size_t)63; }

/* One allocation for all of a wave's arrays; NULL on failure. */
static tt__pt_wave *tt__pt_wave_create(size_t sampler_state) {
  tt__pt_wave *w = calloc(1, sizeof *w);
  if (!w) return NULL;
  w->state_stride = tt__pt_align16(tt_path_state_size());
  w->sampler_stride = tt__pt_align16(sampler_state ? sampler_state : 1);
  const size_t n = TT__PT_WAVE;
  size_t sizes[] = {n * w->state_stride,
                    n * w->sampler_stride,
                    n * sizeof *w->film_pos,
                    n * sizeof *w->results,
                    n * sizeof(tt_ray),
                    n * sizeof(tt_ray),
                    n * sizeof(tt_ray),
                    n * sizeof(tt_hit),
                    n,
                    n * 4,
                    n * 4,
                    n * 4};
  size_t total = 0;
  for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) total += tt__pt_align64(sizes[i]);
  unsigned char *p = aligned_alloc(64, total);
  if (!p) {
    free(w);
    return NULL;
  }
  w->block = p;
  void **dst[] = {(void **)&w->states,  (void **)&w->samplers,    (void **)&w->film_pos,
                  (void **)&w->results, (void **)&w->rays,        (void **)&w->next_rays,
                  (void **)&w->shadows, (void **)&w->hits,        (void **)&w->occluded,
                  (void **)&w->active,  (void **)&w->next_active, (void **)&w->shadow_of};
  for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
    *dst[i] = p;
    p += tt__pt_align64(sizes[i]); /* each array on its own cache lines */
  }
  return w;
}

static void tt__pt_wave_destroy(tt__pt_wave *w) {
  if (!w) return;
  free(w->block);
  free(w);
}

/* Shading a hit reads its triangle from the scene: the indices, then the positions,
 * normals and uvs of its three vertices, scattered lines that mostly miss the cache (in a
 * profile of a living-room render, the loads of the indices and the first vertex were a
 * third of tt_path_hit's time). With all hits of a wave known, they are prefetched ahead:
 * the indices TT__PT_PF_INDICES hits ahead, the vertex data (whose indices are in cache by
 * then) TT__PT_PF_VERTICES hits ahead. */
#define TT__PT_PF_INDICES 16
#define TT__PT_PF_VERTICES 8

static void tt__pt_prefetch_indices(const tt_scene *scene, const tt_hit *h) {
  if (h->geom_id == TT_INVALID_ID) return;
  const tt_mesh *m = tt_scene_mesh(scene, h->geom_id);
  __builtin_prefetch(m->indices + 3 * (size_t)h->prim_id);
}

static void tt__pt_prefetch_vertices(const tt_scene *scene, const tt_hit *h) {
  if (h->geom_id == TT_INVALID_ID) return;
  const tt_mesh *m = tt_scene_mesh(scene, h->geom_id);
  const uint32_t *idx = m->indices + 3 * (size_t)h->prim_id;
  for (int k = 0; k < 3; k++) {
    const size_t v = idx[k];
    __builtin_prefetch(m->positions + 3 * v);
    if (m->normals) __builtin_prefetch(m->normals + 3 * v);
    if (m->uvs) __builtin_prefetch(m->uvs + 2 * v);
  }
}

/* Renders paths [first, first + count) of a tile, path k being sample k % spp of pixel
 * k / spp in row-major order within the tile, as waves: all camera rays with one
 * intersect_stream call, then per bounce the shading of every hit, one occluded_stream
 * call for the shadow rays and one intersect_stream call for the continuations. Results
 * go to the film in path order, so the image is the scalar loop's, bit for bit. */
static void tt__pt_wave_run(tt__pt_job *job, tt__pt_wave *w, uint32_t x0, uint32_t y0, uint32_t tw,
                            uint64_t first, uint32_t count, uint64_t *rays, uint64_t *samples,
                            uint64_t *nonfinite) {
  const tt_render_ctx *ctx = job->ctx;
  const tt__pt_settings *set = &job->it->settings;
  const tt_accel_iface *A = job->tracer.iface;
  const tt_path_tracer *pt = job->it->pt;
  const uint32_t spp = ctx->spp;
#define TT__PT_STATE(k) ((tt_path_state *)(w->states + (size_t)(k)*w->state_stride))
#define TT__PT_SSTATE(k) ((void *)(w->samplers + (size_t)(k)*w->sampler_stride))
  uint32_t n = 0;
  for (uint32_t k = 0; k < count; k++) {
    uint64_t q = first + k;
    uint32_t px = x0 + (uint32_t)((q / spp) % tw), py = y0 + (uint32_t)((q / spp) / tw);
    tt_ray ray;
    tt__pt_camera_sample(job, TT__PT_SSTATE(k), px, py, (uint32_t)(q % spp), &w->film_pos[k][0],
                         &w->film_pos[k][1], &ray);
    if (tt_path_begin(pt, &set->path, &ray, TT__PT_STATE(k), &w->rays[n])) w->active[n++] = k;
  }
  while (n > 0) {
    for (uint32_t j = 0; j < n; j++) {
      w->hits[j].geom_id = TT_INVALID_ID;
      w->hits[j].prim_id = TT_INVALID_ID;
    }
    A->intersect_stream(job->tracer.accel, w->rays, w->hits, n);
    uint32_t next = 0, shadows = 0;
    for (uint32_t j = 0; j < n && j < TT__PT_PF_INDICES; j++)
      tt__pt_prefetch_indices(job->it->scene, &w->hits[j]);
    for (uint32_t j = 0; j < n; j++) {
      const uint32_t k = w->active[j];
      if (j + TT__PT_PF_INDICES < n)
        tt__pt_prefetch_indices(job->it->scene, &w->hits[j + TT__PT_PF_INDICES]);
      if (j + TT__PT_PF_VERTICES < n)
        tt__pt_prefetch_vertices(job->it->scene, &w->hits[j + TT__PT_PF_VERTICES]);
      tt__pt_source src = {set->sampler, job->sampler, TT__PT_SSTATE(k)};
      tt_sample_source source = {tt__pt_source_get, NULL, &src};
      int has_shadow = 0;
      if (tt_path_hit(pt, TT__PT_STATE(k), &w->rays[j], &w->hits[j], &source, &w->shadows[shadows],
                      &has_shadow, &w->next_rays[next]))
        w->next_active[next++] = k;
      if (has_shadow) w->shadow_of[shadows++] = k;
    }
    if (shadows > 0) {
      A->occluded_stream(job->tracer.accel, w->shadows, w->occluded, shadows);
      for (uint32_t j = 0; j < shadows; j++)
        tt_path_shadow(TT__PT_STATE(w->shadow_of[j]), w->occluded[j]);
    }
    tt_ray *tr = w->rays;
    w->rays = w->next_rays, w->next_rays = tr;
    uint32_t *ta = w->active;
    w->active = w->next_active, w->next_active = ta;
    n = next;
  }
  for (uint32_t k = 0; k < count; k++) {
    uint64_t q = first + k;
    uint32_t px = x0 + (uint32_t)((q / spp) % tw), py = y0 + (uint32_t)((q / spp) / tw);
    tt_path_result *r = &w->results[k];
    tt_path_finish(TT__PT_STATE(k), r);
    tt_film_add_sample(ctx->film, px, py, r->L, 1.0f);
    *rays += r->rays;
    (*samples)++;
    *nonfinite += r->nonfinite ? 1u : 0u;
    if (job->aovs) {
      tt_ray ray; /* the camera ray again (motion of a miss uses its direction) */
      tt_camera_generate_ray(&job->frame, w->film_pos[k][0], w->film_pos[k][1], &ray);
      tt_path_write_aovs_ex(ctx->film, px, py, &job->frame, job->has_prev ? &job->prev_frame : NULL,
                            w->film_pos[k][0], w->film_pos[k][1], &ray, r, r->prev_position,
                            ctx->sample_offset + q % spp + 1);
    }
  }
#undef TT__PT_STATE
#undef TT__PT_SSTATE
}

/* Renders tiles [begin, end); a tile is skipped whole when a stop was requested. */
static void tt__pt_tile_fn(void *vctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  tt__pt_job *job = vctx;
  const tt_render_ctx *ctx = job->ctx;
  const tt__pt_settings *set = &job->it->settings;
  const tt_host *host = tt__pt_host();
  _Alignas(16) unsigned char state[TT__PT_MAX_STATE];
  tt__pt_source src = {set->sampler, job->sampler, state};
  tt_sample_source source = {tt__pt_source_get, NULL, &src};
  uint64_t rays = 0, samples = 0, nonfinite = 0;
  tt__pt_wave *wave = NULL;
  if (set->wavefront && thread_index < job->wave_count) {
    if (!job->waves[thread_index])
      job->waves[thread_index] = tt__pt_wave_create(set->sampler->state_size(job->sampler));
    wave = job->waves[thread_index];
    if (!wave) {
      atomic_store(&job->failed, 1);
      return;
    }
  }
  for (uint64_t tile = begin; tile < end; ++tile) {
    if (host->should_stop && host->should_stop()) {
      atomic_store(&job->interrupted, 1);
      break;
    }
    uint32_t x0 = (uint32_t)(tile % job->tiles_x) * job->tile_size;
    uint32_t y0 = (uint32_t)(tile / job->tiles_x) * job->tile_size;
    uint32_t x1 = x0 + job->tile_size < job->width ? x0 + job->tile_size : job->width;
    uint32_t y1 = y0 + job->tile_size < job->height ? y0 + job->tile_size : job->height;
    if (wave) {
      const uint64_t paths = (uint64_t)(x1 - x0) * (y1 - y0) * ctx->spp;
      for (uint64_t first = 0; first < paths; first += TT__PT_WAVE) {
        uint32_t count = (uint32_t)(paths - first < TT__PT_WAVE ? paths - first : TT__PT_WAVE);
        tt__pt_wave_run(job, wave, x0, y0, x1 - x0, first, count, &rays, &samples, &nonfinite);
      }
      continue;
    }
    for (uint32_t py = y0; py < y1; ++py) {
      for (uint32_t px = x0; px < x1; ++px) {
        for (uint32_t s = 0; s < ctx->spp; ++s) {
          float fx, fy;
          tt_ray ray;
          tt__pt_camera_sample(job, state, px, py, s, &fx, &fy, &ray);
          tt_path_result r;
          tt_path_trace(job->it->pt, &job->tracer, &set->path, &ray, &source, &r);
          tt_film_add_sample(ctx->film, px, py, r.L, 1.0f);
          rays += r.rays;
          samples++;
          nonfinite += r.nonfinite ? 1u : 0u;
          if (job->aovs)
            tt_path_write_aovs_ex(ctx->film, px, py, &job->frame,
                                  job->has_prev ? &job->prev_frame : NULL, fx, fy, &ray, &r,
                                  r.prev_position, ctx->sample_offset + s + 1);
        }
      }
    }
  }
  atomic_fetch_add(&job->rays, rays);
  atomic_fetch_add(&job->samples, samples);
  atomic_fetch_add(&job->nonfinite, nonfinite);
}

static tt_status tt__pt_render_pass(tt_integrator *it, const tt_render_ctx *ctx,
                                    tt_pass_stats *stats) {
  if (!it || !ctx || !ctx->film || !ctx->camera || !ctx->accel_iface || !ctx->accel)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__PT_NAME ": render_pass needs film, camera and accel");
  const tt_host *host = tt__pt_host();
  uint64_t t0 = host->clock_ns ? host->clock_ns() : 0;
  tt__pt_job *job = calloc(1, sizeof *job);
  if (!job) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__PT_NAME ": out of memory");
  job->it = it;
  job->ctx = ctx;
  tt_status st = tt_camera_frame_init(&job->frame, ctx->camera);
  if (st == TT_OK && (tt_film_width(ctx->film) != ctx->camera->width ||
                      tt_film_height(ctx->film) != ctx->camera->height))
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__PT_NAME ": film %ux%u differs from camera %ux%u",
                      tt_film_width(ctx->film), tt_film_height(ctx->film), ctx->camera->width,
                      ctx->camera->height);
  if (st == TT_OK && ctx->prev_camera) {
    job->has_prev = tt_camera_frame_init(&job->prev_frame, ctx->prev_camera) == TT_OK;
    if (!job->has_prev) tt_clear_error();
  }
  const tt__pt_settings *set = &it->settings;
  tt_sampler *sampler = NULL;
  if (st == TT_OK) st = set->sampler->create(NULL, ctx->seed, &sampler);
  if (st == TT_OK && set->sampler->state_size(sampler) > TT__PT_MAX_STATE)
    st = tt_set_error(TT_ERR_UNSUPPORTED,
                      TT__PT_NAME ": sampler '%s' needs more than %d bytes of state",
                      set->sampler->name, TT__PT_MAX_STATE);
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
  atomic_init(&job->failed, 0);
  if (set->wavefront) {
    job->wave_count = host->thread_count ? host->thread_count() : 1;
    if (job->wave_count < 1) job->wave_count = 1;
    job->waves = calloc(job->wave_count, sizeof *job->waves);
    if (!job->waves) {
      set->sampler->destroy(sampler);
      free(job);
      return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__PT_NAME ": out of memory");
    }
  }

  tt_status pst = host->parallel_for((uint64_t)job->tiles_x * tiles_y, 1, tt__pt_tile_fn, job);
  if (pst == TT_ERR_INTERRUPTED || atomic_load(&job->interrupted)) st = TT_ERR_INTERRUPTED;
  else if (pst != TT_OK) st = pst;
  if (atomic_load(&job->failed) && st == TT_OK)
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__PT_NAME ": cannot allocate the wavefront buffers");
  for (uint32_t i = 0; i < job->wave_count; i++) tt__pt_wave_destroy(job->waves[i]);
  free(job->waves);

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
    return tt_set_error(TT_ERR_INTERRUPTED,
                        TT__PT_NAME ": pass interrupted (completed tiles are in the film)");
  return st;
}

static const tt_integrator_iface tt__pt_iface = {
    .struct_size = sizeof(tt_integrator_iface),
    .space = tt__pt_space,
    .create = tt__pt_create,
    .configure = tt__pt_configure,
    .render_pass = tt__pt_render_pass,
    .reset = tt__pt_reset,
    .destroy = tt__pt_destroy,
};

static tt_status tt__pt_init(const tt_host *host) {
  g_host = host;
  tt__pt_build_bh_table();
  return g_space ? TT_OK : tt__pt_build_space();
}

static void tt__pt_deinit(void) {
  tt_space_destroy(g_space);
  g_space = NULL;
  g_host = NULL;
}

static const void *tt__pt_get_interface(const char *id) {
  return id && strcmp(id, TT_INTEGRATOR_INTERFACE_ID) == 0 ? &tt__pt_iface : NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
    .struct_size = sizeof(tt_plugin),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .kind = TT_KIND_INTEGRATOR,
    .name = TT__PT_NAME,
    .version = TT__PT_VERSION,
    .description =
        "progressive path tracer: NEE + BSDF sampling with MIS, independent/Halton/Sobol samplers",
    .init = tt__pt_init,
    .deinit = tt__pt_deinit,
    .get_interface = tt__pt_get_interface,
};
