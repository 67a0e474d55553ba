/* integrator_bdpt: progressive bidirectional path tracer (kind TT_KIND_INTEGRATOR) over the
 * core's bidirectional path sampler (tunetrace/bdpt.h).
 *
 * Each render_pass adds ctx->spp samples to every pixel: per sample a camera subpath through
 * the pixel and a light subpath, and every connection (s, t) of at most maxDepth bounces,
 * MIS-weighted. Connections with t >= 2 belong to the pixel; light tracing (t = 1) lands
 * anywhere on the film and is splatted. Work is split into square tiles; the random numbers
 * of a sample depend only on (seed, pixel, sample index, dimension), and each tile records
 * its splats in order and the tiles' records are summed in tile order after the pass, so an
 * image is bit-identical for a fixed seed whatever the thread count. See README.md. */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <tunetrace/bdpt.h>
#include <tunetrace/camera.h>
#include <tunetrace/image.h>
#include <tunetrace/integrator.h>
#include <tunetrace/plugin.h>

#define TT__BD_NAME "integrator_bdpt"
#define TT__BD_VERSION "0.1.0"
#define TT__BD_MAX_STATE 256
#define TT__BD_STREAMS 3
/* Splat records kept before a sub-pass is merged: a pass of many samples per pixel runs as
 * sub-passes so that the records of one stay within ~64 MiB. */
#define TT__BD_MAX_SPLATS (1u << 22)

static const tt_host *g_host;
static tt_space *g_space;

typedef struct tt__bd_settings {
  tt_bdpt_options bdpt;
  const tt_sampler_iface *sampler;
  uint32_t tile_size;
} tt__bd_settings;

/* One light-tracing splat: where, and (for the strategy images) which strategy. */
typedef struct tt__bd_splat {
  uint32_t pixel;
  uint16_t strategy;
  float L[3];
  float unweighted[3];
} tt__bd_splat;

/* A tile's splats, in the order its samples produced them. */
typedef struct tt__bd_splats {
  tt__bd_splat *v;
  size_t n, cap;
} tt__bd_splats;

struct tt_integrator {
  const tt_scene *scene;
  tt_path_tracer *pt;
  tt__bd_settings settings;
  /* light-tracing splats of the film (reset with a fresh film) */
  uint64_t light_paths; /* light subpaths traced into this film */
  double *splat_sum;    /* 3 per pixel, this pass */
  size_t pixels;
  /* strategy images (TT_BDPT_STRATEGIES): per strategy and pixel, sums of weighted and
   * unweighted contributions (camera strategies) and of splats (t = 1) */
  char *strategy_path;
  uint32_t strategies; /* count for settings.bdpt.max_depth */
  uint32_t strategy_depth;
  double *strategy_sum;    /* strategies * pixels * 6 */
  uint64_t camera_samples; /* samples per pixel in the film */
  int warned_dark;         /* "no light reached the camera" said once */
};

/* ---- parameters ---- */

static const tt_host *tt__bd_host(void) { return g_host ? g_host : tt_default_host(); }

static tt_status tt__bd_build_space(void) {
  static const char *const heuristics[] = {"power", "balance"};
  static const char *const samplers[] = {"independent", "halton", "sobol"};
  tt_space *s = tt_space_create(TT__BD_NAME, TT__BD_VERSION);
  if (!s)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__BD_NAME ": cannot create the parameter space");
  int ok = 1;
  ok &= tt_space_add_int(s, "maxDepth", 0, 64, 5,
                         "maximum number of bounces of a connected path (0: emission only), as "
                         "integrator_pt's") >= 0;
  ok &= tt_space_add_int(s, "rrDepth", 0, 64, 3,
                         "bounce from which Russian roulette may end a subpath") >= 0;
  ok &= tt_space_add_nom_string(s, "heuristic", heuristics, 2, 0,
                                "MIS heuristic over the strategies of a path length") >= 0;
  /* sobol by default: less CPU time to equal error than independent on three of five scenes
     (1.36-1.68x), a tie on the other two (tools/charts/sampler_choice.py --integrator
     integrator_bdpt; the README's "Default sampler") */
  ok &= tt_space_add_nom_string(s, "sampler", samplers, 3, 2,
                                "primary-sample generator (the camera, light and connection "
                                "streams interleaved)") >= 0;
  ok &= tt_space_add_int(s, "tileSize", 4, 256, 32,
                         "side of the square tiles handed to worker threads") >= 0;
  if (!ok) {
    tt_space_destroy(s);
    return tt_set_error(TT_ERR_INTERNAL, TT__BD_NAME ": building the parameter space failed");
  }
  g_space = s;
  return TT_OK;
}

static tt_status tt__bd_read_config(const tt_config *config, tt__bd_settings *out) {
  tt_config *defaults = NULL;
  if (!config) {
    if (!g_space) return tt_set_error(TT_ERR_INTERNAL, TT__BD_NAME ": used before init()");
    defaults = tt_config_create(g_space);
    if (!defaults) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__BD_NAME ": out of memory");
    config = defaults;
  }
  tt_status st = TT_OK;
  tt_bdpt_options_default(&out->bdpt);
  int64_t d = tt_config_get_int(config, "maxDepth", 5),
          rr = tt_config_get_int(config, "rrDepth", 3);
  out->bdpt.max_depth = (uint32_t)(d < 0 ? 0 : d > 64 ? 64 : d);
  out->bdpt.rr_depth = (uint32_t)(rr < 0 ? 0 : rr > 64 ? 64 : rr);
  const char *h = tt_config_get_string(config, "heuristic");
  out->bdpt.heuristic = h && strcmp(h, "balance") == 0 ? TT_MIS_BALANCE : TT_MIS_POWER;
  const char *s = tt_config_get_string(config, "sampler");
  out->sampler = tt_builtin_sampler(s ? s : "sobol");
  if (!out->sampler)
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__BD_NAME ": unknown sampler '%s'", s ? s : "");
  int64_t ts = tt_config_get_int(config, "tileSize", 32);
  out->tile_size = (uint32_t)(ts < 4 ? 4 : ts > 256 ? 256 : ts);
  tt_config_destroy(defaults);
  return st;
}

/* ---- strategies: index of (s, t) among those of paths up to depth d ---- */

/* Strategies of depth k are (s, t) with s + t = k + 2, t >= 1, except (1, 1): s = 0..k+1. */
static uint32_t tt__bd_strategy_count(uint32_t max_depth) {
  uint32_t n = 0;
  for (uint32_t k = 0; k <= max_depth; ++k) n += k + 2 - (k == 0 ? 1 : 0);
  return n;
}

static uint32_t tt__bd_strategy_index(uint32_t s, uint32_t t) {
  uint32_t k = s + t - 2, idx = 0;
  for (uint32_t j = 0; j < k; ++j) idx += j + 2 - (j == 0 ? 1 : 0);
  return idx + (k == 0 ? 0 : s);
}

/* ---- interface ---- */

static const tt_space *tt__bd_space(void) { return g_space; }

static tt_status tt__bd_create(const tt_scene *scene, const tt_config *config,
                               tt_integrator **out) {
  if (!scene || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__BD_NAME ": scene or out is NULL");
  *out = NULL;
  tt_integrator *it = calloc(1, sizeof *it);
  if (!it) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__BD_NAME ": out of memory");
  it->scene = scene;
  tt_status st = tt__bd_read_config(config, &it->settings);
  if (st == TT_OK) st = tt_path_tracer_create(scene, &it->pt);
  if (st != TT_OK) {
    free(it);
    return st;
  }
  const char *dump = getenv("TT_BDPT_STRATEGIES");
  if (dump && *dump) {
    it->strategy_path = malloc(strlen(dump) + 1);
    if (it->strategy_path) strcpy(it->strategy_path, dump);
  }
  if (tt_scene_light_count(scene) == 0)
    tt_host_log(tt__bd_host(), TT_LOG_WARN, TT__BD_NAME,
                "the scene has no light (no emissive material, no light "
                "source): the image is black");
  *out = it;
  return TT_OK;
}

static tt_status tt__bd_configure(tt_integrator *it, const tt_config *config) {
  tt__bd_settings s;
  tt_status st = tt__bd_read_config(config, &s);
  if (st == TT_OK) it->settings = s;
  return st;
}

static void tt__bd_reset(tt_integrator *it) {
  if (!it) return;
  it->light_paths = 0;
  it->camera_samples = 0;
  if (it->strategy_sum)
    memset(it->strategy_sum, 0, (size_t)it->strategies * it->pixels * 6 * sizeof(double));
}

static void tt__bd_destroy(tt_integrator *it) {
  if (!it) return;
  tt_path_tracer_destroy(it->pt);
  free(it->splat_sum);
  free(it->strategy_sum);
  free(it->strategy_path);
  free(it);
}

/* Everything the tile workers share during one sub-pass. */
typedef struct tt__bd_job {
  tt_integrator *it;
  const tt_render_ctx *ctx;
  const tt_sampler *sampler;
  tt_camera_frame frame, prev_frame;
  int has_prev;
  tt_tracer tracer;
  uint32_t tiles_x, tile_size, width, height;
  uint32_t aovs;
  uint32_t spp_first, spp_count; /* the sub-pass: samples [first, first + count) of the pass */
  tt_bdpt_paths **paths;         /* per thread, made on first use */
  uint32_t threads;
  tt__bd_splats *splats; /* per tile */
  atomic_uint_fast64_t rays, samples, nonfinite, splat_count, contributions;
  atomic_int interrupted, failed;
} tt__bd_job;

/* One stream of the sampler's sample: dimension d of stream k is the sampler's 3 d + k. */
typedef struct tt__bd_stream {
  const tt_sampler_iface *iface;
  const tt_sampler *sampler;
  void *state;
  uint32_t k;
} tt__bd_stream;

static float tt__bd_stream_get(void *self, uint32_t dim) {
  tt__bd_stream *s = self;
  return s->iface->get(s->sampler, s->state, TT__BD_STREAMS * dim + s->k);
}

static int tt__bd_push(tt__bd_splats *l, const tt__bd_splat *s) {
  if (l->n == l->cap) {
    size_t ncap = l->cap ? 2 * l->cap : 1024;
    tt__bd_splat *nv = realloc(l->v, ncap * sizeof *nv);
    if (!nv) return 0;
    l->v = nv;
    l->cap = ncap;
  }
  l->v[l->n++] = *s;
  return 1;
}

/* Renders the sub-pass's samples of tiles [begin, end). */
static void tt__bd_tile_fn(void *vctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  tt__bd_job *job = vctx;
  tt_integrator *it = job->it;
  const tt_render_ctx *ctx = job->ctx;
  const tt__bd_settings *set = &it->settings;
  const tt_bdpt_options *o = &set->bdpt;
  const tt_host *host = tt__bd_host();
  if (thread_index >= job->threads) {
    atomic_store(&job->failed, 1);
    return;
  }
  if (!job->paths[thread_index] &&
      tt_bdpt_paths_create(o->max_depth, &job->paths[thread_index]) != TT_OK) {
    atomic_store(&job->failed, 1);
    return;
  }
  tt_bdpt_paths *paths = job->paths[thread_index];
  _Alignas(16) unsigned char state[TT__BD_MAX_STATE];
  tt__bd_stream cs = {set->sampler, job->sampler, state, 0},
                ls = {set->sampler, job->sampler, state, 1},
                ks = {set->sampler, job->sampler, state, 2};
  tt_sample_source cam = {tt__bd_stream_get, NULL, &cs}, lig = {tt__bd_stream_get, NULL, &ls},
                   con = {tt__bd_stream_get, NULL, &ks};
  double *strat = it->strategy_sum;
  const size_t pixels = it->pixels;
  uint64_t rays = 0, samples = 0, nonfinite = 0, splat_count = 0, contributions = 0;
  for (uint64_t tile = begin; tile < end; ++tile) {
    if (host->should_stop && host->should_stop()) {
      atomic_store(&job->interrupted, 1);
      break;
    }
    tt__bd_splats *list = &job->splats[tile];
    uint32_t x0 = (uint32_t)(tile % job->tiles_x) * job->tile_size;
    uint32_t y0 = (uint32_t)(tile / job->tiles_x) * job->tile_size;
    uint32_t x1 = x0 + job->tile_size < job->width ? x0 + job->tile_size : job->width;
    uint32_t y1 = y0 + job->tile_size < job->height ? y0 + job->tile_size : job->height;
    for (uint32_t py = y0; py < y1; ++py)
      for (uint32_t px = x0; px < x1; ++px)
        for (uint32_t s = job->spp_first; s < job->spp_first + job->spp_count; ++s) {
          uint64_t index = ctx->sample_offset + s;
          set->sampler->start(job->sampler, state, px, py, index);
          float jx, jy;
          if (ctx->fixed_jitter) {
            jx = ctx->jitter[0];
            jy = ctx->jitter[1];
          } else {
            jx = tt__bd_stream_get(&cs, TT_BDPT_CAMERA_DIM_FILM) - 0.5f;
            jy = tt__bd_stream_get(&cs, TT_BDPT_CAMERA_DIM_FILM + 1) - 0.5f;
          }
          float fx = (float)px + 0.5f + jx, fy = (float)py + 0.5f + jy;
          uint32_t nc = tt_bdpt_camera_subpath(it->pt, &job->tracer, o, &job->frame, fx, fy, &cam,
                                               o->max_depth + 2, paths);
          uint32_t nl =
              tt_bdpt_light_subpath(it->pt, &job->tracer, o, &lig, o->max_depth + 1, paths);
          float L[3] = {0.0f, 0.0f, 0.0f};
          size_t pix = (size_t)py * job->width + px;
          for (uint32_t t = 1; t <= nc; ++t)
            for (uint32_t sl = 0; sl <= nl; ++sl) {
              if ((sl == 1 && t == 1) || sl + t < 2 || sl + t - 2 > o->max_depth) continue;
              tt_bdpt_contribution c;
              int got = tt_bdpt_connect(it->pt, &job->tracer, o, &job->frame, paths, sl, t, &con,
                                        TT_BDPT_CONNECT_DIMS * t, &c);
              nonfinite += c.nonfinite ? 1u : 0u;
              if (!got) continue;
              contributions++;
              uint32_t si = tt__bd_strategy_index(sl, t);
              if (t == 1) {
                uint32_t sx = (uint32_t)c.fx, sy = (uint32_t)c.fy;
                if (sx >= job->width) sx = job->width - 1;
                if (sy >= job->height) sy = job->height - 1;
                tt__bd_splat sp = {sy * job->width + sx,
                                   (uint16_t)si,
                                   {c.L[0], c.L[1], c.L[2]},
                                   {c.unweighted[0], c.unweighted[1], c.unweighted[2]}};
                if (!tt__bd_push(list, &sp)) atomic_store(&job->failed, 1);
                splat_count++;
              } else {
                for (int i = 0; i < 3; ++i) L[i] += c.L[i];
                if (strat) {
                  double *d = strat + ((size_t)si * pixels + pix) * 6;
                  for (int i = 0; i < 3; ++i) {
                    d[i] += c.L[i];
                    d[3 + i] += c.unweighted[i];
                  }
                }
              }
            }
          tt_film_add_sample(ctx->film, px, py, L, 1.0f);
          rays += tt_bdpt_rays(paths);
          samples++;
          if (job->aovs) {
            tt_path_result r;
            tt_bdpt_first_hit_ex(paths, &r, sizeof r);
            tt_ray ray;
            tt_camera_generate_ray(&job->frame, fx, fy, &ray);
            tt_path_write_aovs_ex(ctx->film, px, py, &job->frame,
                                  job->has_prev ? &job->prev_frame : NULL, fx, fy, &ray, &r,
                                  r.prev_position, index + 1);
          }
        }
  }
  atomic_fetch_add(&job->rays, rays);
  atomic_fetch_add(&job->samples, samples);
  atomic_fetch_add(&job->nonfinite, nonfinite);
  atomic_fetch_add(&job->splat_count, splat_count);
  atomic_fetch_add(&job->contributions, contributions);
}

/* Sums the tiles' splat records in tile order (the same additions whatever thread rendered
 * which tile) and empties them. */
static void tt__bd_merge_splats(tt__bd_job *job, uint64_t tiles) {
  tt_integrator *it = job->it;
  double *strat = it->strategy_sum;
  for (uint64_t t = 0; t < tiles; ++t) {
    tt__bd_splats *l = &job->splats[t];
    for (size_t i = 0; i < l->n; ++i) {
      const tt__bd_splat *s = &l->v[i];
      double *d = it->splat_sum + 3 * (size_t)s->pixel;
      for (int c = 0; c < 3; ++c) d[c] += s->L[c];
      if (strat) {
        double *e = strat + ((size_t)s->strategy * it->pixels + s->pixel) * 6;
        for (int c = 0; c < 3; ++c) {
          e[c] += s->L[c];
          e[3 + c] += s->unweighted[c];
        }
      }
    }
    l->n = 0;
  }
}

/* Writes the strategy images: per (s, t) the weighted and unweighted contribution as layers
 * "sS_tT.weighted.{R,G,B}" and "sS_tT.unweighted.{R,G,B}" of one EXR (pbrt-v3's
 * visualizestrategies); camera strategies as means per sample, light tracing scaled like
 * the film's splats. The weighted layers sum to the image. */
static void tt__bd_write_strategies(tt_integrator *it, uint32_t w, uint32_t h) {
  const uint32_t n = it->strategies, ch = 6 * n, d = it->strategy_depth;
  const size_t pixels = (size_t)w * h;
  float *img = malloc(pixels * ch * sizeof(float));
  char **names = calloc(ch, sizeof(char *));
  char *name_mem = malloc((size_t)ch * 40);
  if (!img || !names || !name_mem) {
    tt_host_log(tt__bd_host(), TT_LOG_WARN, TT__BD_NAME,
                "cannot write the strategy images: out of memory");
    free(img);
    free(names);
    free(name_mem);
    return;
  }
  static const char rgb[3] = {'R', 'G', 'B'};
  double cam_scale = it->camera_samples ? 1.0 / (double)it->camera_samples : 0.0;
  double lt_scale = it->light_paths ? (double)pixels / (double)it->light_paths : 0.0;
  for (uint32_t k = 0; k <= d; ++k)
    for (uint32_t s = 0; s <= k + 1; ++s) {
      uint32_t t = k + 2 - s;
      if (s == 1 && t == 1) continue;
      uint32_t si = tt__bd_strategy_index(s, t);
      for (uint32_t c = 0; c < 6; ++c) {
        char *nm = name_mem + (size_t)(6 * si + c) * 40;
        snprintf(nm, 40, "s%u_t%u.%s.%c", s, t, c < 3 ? "weighted" : "unweighted", rgb[c % 3]);
        names[6 * si + c] = nm;
      }
      double scale = t == 1 ? lt_scale : cam_scale;
      for (size_t p = 0; p < pixels; ++p)
        for (uint32_t c = 0; c < 6; ++c)
          img[p * ch + 6 * si + c] =
              (float)(it->strategy_sum[((size_t)si * pixels + p) * 6 + c] * scale);
    }
  char depth[16];
  snprintf(depth, sizeof depth, "%u", d);
  tt_image_meta meta[2] = {{"tunetrace:integrator", TT__BD_NAME}, {"tunetrace:maxDepth", depth}};
  if (tt_image_write_exr(it->strategy_path, w, h, ch, img, (const char *const *)names, meta, 2) !=
      TT_OK)
    tt_host_log(tt__bd_host(), TT_LOG_WARN, TT__BD_NAME, "cannot write the strategy images: %s",
                tt_last_error());
  free(img);
  free(names);
  free(name_mem);
}

static tt_status tt__bd_render_pass(tt_integrator *it, const tt_render_ctx *ctx,
                                    tt_pass_stats *stats) {
  if (!it || !ctx || !ctx->film || !ctx->camera || !ctx->accel_iface || !ctx->accel)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__BD_NAME ": render_pass needs film, camera and accel");
  const tt_host *host = tt__bd_host();
  uint64_t t0 = host->clock_ns ? host->clock_ns() : 0;
  const tt__bd_settings *set = &it->settings;
  tt__bd_job *job = calloc(1, sizeof *job);
  if (!job) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__BD_NAME ": out of memory");
  job->it = it;
  job->ctx = ctx;
  tt_status st = tt_camera_frame_init(&job->frame, ctx->camera);
  uint32_t w = tt_film_width(ctx->film), h = tt_film_height(ctx->film);
  if (st == TT_OK && (w != ctx->camera->width || h != ctx->camera->height))
    st = tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__BD_NAME ": film %ux%u differs from camera %ux%u",
                      w, h, ctx->camera->width, ctx->camera->height);
  if (st == TT_OK && ctx->prev_camera) {
    job->has_prev = tt_camera_frame_init(&job->prev_frame, ctx->prev_camera) == TT_OK;
    if (!job->has_prev) tt_clear_error();
  }
  const size_t pixels = (size_t)w * h;
  /* A fresh film (or another size) starts the light-tracing normalisation over. */
  if (st == TT_OK && (ctx->sample_offset == 0 || it->pixels != pixels)) {
    if (it->pixels != pixels) {
      free(it->splat_sum);
      free(it->strategy_sum);
      it->strategy_sum = NULL;
      it->splat_sum = calloc(3 * pixels, sizeof(double));
      it->pixels = it->splat_sum ? pixels : 0;
      if (!it->splat_sum)
        st = tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__BD_NAME ": out of memory for the splats");
    }
    tt__bd_reset(it);
  }
  if (st == TT_OK && it->strategy_path &&
      (!it->strategy_sum || it->strategy_depth != set->bdpt.max_depth)) {
    free(it->strategy_sum);
    it->strategy_depth = set->bdpt.max_depth;
    it->strategies = tt__bd_strategy_count(it->strategy_depth);
    it->strategy_sum = calloc((size_t)it->strategies * pixels * 6, sizeof(double));
    if (!it->strategy_sum) {
      tt_host_log(host, TT_LOG_WARN, TT__BD_NAME,
                  "no strategy images: out of memory for %u strategies", it->strategies);
      free(it->strategy_path);
      it->strategy_path = NULL;
    }
  }
  tt_sampler *sampler = NULL;
  if (st == TT_OK) st = set->sampler->create(NULL, ctx->seed, &sampler);
  if (st == TT_OK && set->sampler->state_size(sampler) > TT__BD_MAX_STATE)
    st = tt_set_error(TT_ERR_UNSUPPORTED,
                      TT__BD_NAME ": sampler '%s' needs more than %d bytes of state",
                      set->sampler->name, TT__BD_MAX_STATE);
  job->sampler = sampler;
  job->tracer.iface = ctx->accel_iface;
  job->tracer.accel = ctx->accel;
  job->width = w;
  job->height = h;
  job->tile_size = set->tile_size;
  job->tiles_x = (w + job->tile_size - 1) / job->tile_size;
  const uint64_t tiles = (uint64_t)job->tiles_x * ((h + job->tile_size - 1) / job->tile_size);
  job->aovs = tt_film_aov_mask(ctx->film);
  job->threads = host->thread_count ? host->thread_count() : 1;
  if (job->threads < 1) job->threads = 1;
  if (st == TT_OK) {
    job->paths = calloc(job->threads, sizeof *job->paths);
    job->splats = calloc(tiles, sizeof *job->splats);
    if (!job->paths || !job->splats)
      st = tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__BD_NAME ": out of memory");
  }
  atomic_init(&job->rays, 0);
  atomic_init(&job->samples, 0);
  atomic_init(&job->nonfinite, 0);
  atomic_init(&job->splat_count, 0);
  atomic_init(&job->contributions, 0);
  atomic_init(&job->interrupted, 0);
  atomic_init(&job->failed, 0);
  if (st == TT_OK) memset(it->splat_sum, 0, 3 * pixels * sizeof(double));
  /* Sub-passes of at most TT__BD_MAX_SPLATS possible splats (one per light vertex and sample). */
  uint64_t per_spp = (uint64_t)pixels * (set->bdpt.max_depth + 1);
  uint32_t chunk = (uint32_t)(per_spp >= TT__BD_MAX_SPLATS ? 1 : TT__BD_MAX_SPLATS / per_spp);
  uint64_t done_samples = 0;
  for (uint32_t first = 0; st == TT_OK && first < ctx->spp; first += chunk) {
    job->spp_first = first;
    job->spp_count = ctx->spp - first < chunk ? ctx->spp - first : chunk;
    uint64_t before = atomic_load(&job->samples);
    tt_status pst = host->parallel_for(tiles, 1, tt__bd_tile_fn, job);
    tt__bd_merge_splats(job, tiles);
    done_samples += atomic_load(&job->samples) - before;
    if (pst == TT_ERR_INTERRUPTED || atomic_load(&job->interrupted)) st = TT_ERR_INTERRUPTED;
    else if (pst != TT_OK) st = pst;
    if (st == TT_OK && atomic_load(&job->failed))
      st = tt_set_error(TT_ERR_OUT_OF_MEMORY,
                        TT__BD_NAME ": out of memory for the subpaths or the splats");
  }
  /* Light tracing: every sample traced one light subpath; the film's splats are their sum
   * times pixels / light subpaths (= 1 / spp when the passes were whole). */
  if (job->splats) {
    it->light_paths += done_samples;
    it->camera_samples += done_samples / (pixels ? pixels : 1);
    for (size_t p = 0; p < pixels; ++p) {
      const double *d = it->splat_sum + 3 * p;
      if (d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0) continue;
      float rgb[3] = {(float)d[0], (float)d[1], (float)d[2]};
      tt_film_splat(ctx->film, (float)(p % w) + 0.5f, (float)(p / w) + 0.5f, rgb);
    }
    if (it->light_paths > 0)
      tt_film_set_splat_scale(ctx->film, (double)pixels / (double)it->light_paths);
    if (it->strategy_path && it->strategy_sum && done_samples > 0)
      tt__bd_write_strategies(it, w, h);
  }
  /* Lights exist but no strategy of a whole pass reached the camera (lights enclosed, facing
   * away, or behind something only a specular chain crosses): say why the image is black. */
  if (st == TT_OK && done_samples > 0 && atomic_load(&job->contributions) == 0 &&
      !it->warned_dark && tt_scene_light_count(it->scene) > 0) {
    it->warned_dark = 1;
    tt_host_log(host, TT_LOG_WARN, TT__BD_NAME,
                "no light reached the camera in %llu samples: the image is "
                "black (are the lights enclosed, or facing away from everything in view?)",
                (unsigned long long)done_samples);
  }
  for (uint32_t i = 0; job->paths && i < job->threads; ++i) tt_bdpt_paths_destroy(job->paths[i]);
  for (uint64_t t = 0; job->splats && t < tiles; ++t) free(job->splats[t].v);
  free(job->paths);
  free(job->splats);

  uint64_t t1 = host->clock_ns ? host->clock_ns() : 0;
  if (stats) {
    tt_pass_stats local;
    memset(&local, 0, sizeof local);
    local.time_ms = (double)(t1 - t0) * 1e-6;
    local.rays = atomic_load(&job->rays);
    local.samples = atomic_load(&job->samples);
    local.nonfinite = atomic_load(&job->nonfinite);
    double secs = local.time_ms > 0.0 ? local.time_ms * 1e-3 : 0.0;
    const char *names[] = {"samples_per_s", "rays_per_s", "rays_per_sample", "splats_per_sample"};
    double n = local.samples ? (double)local.samples : 1.0;
    double values[] = {secs > 0.0 ? (double)local.samples / secs : 0.0,
                       secs > 0.0 ? (double)local.rays / secs : 0.0, (double)local.rays / n,
                       (double)atomic_load(&job->splat_count) / n};
    local.metric_count = 4;
    for (uint32_t m = 0; m < local.metric_count; ++m) {
      local.metrics[m].name = names[m];
      local.metrics[m].value = values[m];
    }
    size_t ns = stats->struct_size < sizeof local ? stats->struct_size : sizeof local;
    local.struct_size = (uint32_t)ns;
    memcpy(stats, &local, ns);
  }
  if (sampler) set->sampler->destroy(sampler);
  free(job);
  if (st == TT_ERR_INTERRUPTED)
    return tt_set_error(TT_ERR_INTERRUPTED,
                        TT__BD_NAME ": pass interrupted (completed tiles are in the film)");
  return st;
}

static const tt_integrator_iface tt__bd_iface = {
    .struct_size = sizeof(tt_integrator_iface),
    .space = tt__bd_space,
    .create = tt__bd_create,
    .configure = tt__bd_configure,
    .render_pass = tt__bd_render_pass,
    .reset = tt__bd_reset,
    .destroy = tt__bd_destroy,
};

static tt_status tt__bd_init(const tt_host *host) {
  g_host = host;
  return g_space ? TT_OK : tt__bd_build_space();
}

static void tt__bd_deinit(void) {
  tt_space_destroy(g_space);
  g_space = NULL;
  g_host = NULL;
}

static const void *tt__bd_get_interface(const char *id) {
  return id && strcmp(id, TT_INTEGRATOR_INTERFACE_ID) == 0 ? &tt__bd_iface : NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
    .struct_size = sizeof(tt_plugin),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .kind = TT_KIND_INTEGRATOR,
    .name = TT__BD_NAME,
    .version = TT__BD_VERSION,
    .description = "bidirectional path tracer: every connection strategy incl. light tracing, MIS "
                   "(power/balance), "
                   "Russian roulette, independent/Halton/Sobol samplers",
    .init = tt__bd_init,
    .deinit = tt__bd_deinit,
    .get_interface = tt__bd_get_interface,
};
