/* host: the online tuning loop (thesis Fig. 3.2 / 3.14) and random exploration.
 *
 * Each measurement applies a configuration to the target plugin (accel: destroy + build;
 * integrator and post: configure), renders one pass into the film and turns what it
 * measured into a cost. The tuning database (tunedb.h) answers configurations already
 * measured in the same state on this machine by an earlier run, so no (state,
 * configuration) pair is measured twice across runs (thesis 3.3); every measurement is
 * committed as soon as it is taken. Within one run, a configuration the tuner proposes
 * again after it was measured in this run is measured again: that is a tuner re-measuring
 * its incumbent against noise (tuner_nm's reevaluate), and a database answer would feed it
 * the same number back and make the noise invisible.
 *
 * --verify N then measures the default and the best configuration side by side, N
 * alternating rounds, so the gain is reported from one run and one process.
 */
#include "host.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <errno.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* Everything one tuning phase works with. */
typedef struct tt__tune_ctx {
  tt__render_state *rs;
  tt__tuning *t;
  tt_loaded_plugin *target;
  size_t target_index;          /* registry index of the target (its configs[] slot) */
  uint32_t target_kind;
  const tt_space *space;        /* the target's full space: what is measured and checked */
  tt_space *subset;             /* the searched parameters, or NULL to search all of space */
  const tt_post_iface *pi;
  tt_post *post;
  float *post_in, *post_out;
  tt_tunedb *db;
  tt_tunedb_row key;            /* state part of every row */
  char *camera_json, *context_json;
  char run_id[64];
  char *applied;                /* config JSON the target currently runs with */
  uint32_t spp;
  /* the pass's own image (--objective rrmse, --tune-pass-images): the film's accumulators
   * before the pass, and the image the pass alone added */
  int want_pass;
  float *snap;                  /* sum_rgb (3), sum_weight (1), splat_rgb (3) per pixel */
  double snap_scale;
  float *pass_rgb;              /* 3 per pixel */
  double *ref_lum;              /* --reference as luminance, 1 per pixel */
  char ref_hash[17];            /* FNV-1a 64 of the reference's luminance (database context) */
} tt__tune_ctx;

/* strdup that reports failure through NULL only (callers treat NULL as "no text"). */
static char *tt__dup(const char *s) {
  if (!s) return NULL;
  char *d = malloc(strlen(s) + 1);
  if (d) strcpy(d, s);
  return d;
}

/* Registry index of a loaded plugin. */
static size_t tt__index_of(tt_registry *reg, const tt_loaded_plugin *p) {
  for (size_t i = 0; i < tt_registry_count(reg); i++)
    if (tt_registry_get(reg, i) == p) return i;
  return (size_t)-1;
}

/* Comma-separated names of the loaded plugins, for error messages. */
static void tt__names(tt_registry *reg, char *buf, size_t n) {
  buf[0] = 0;
  for (size_t i = 0; i < tt_registry_count(reg); i++) {
    size_t len = strlen(buf);
    snprintf(buf + len, n - len, "%s%s", i ? ", " : "",
             tt_loaded_plugin_entry(tt_registry_get(reg, i))->name);
  }
}

/* Non-zero if the plugin publishes a space with at least one parameter. */
static int tt__tunable(const tt_loaded_plugin *p) {
  const tt_space *s = p ? tt_loaded_plugin_space(p) : NULL;
  return s && tt_space_count(s) > 0;
}

/* The plugin's tuning hint (tt.tuning_hint/1), or NULL. */
static const tt_tuning_hint *tt__hint(const tt_loaded_plugin *p) {
  const tt_tuning_hint *h = p ? tt_loaded_plugin_get(p, TT_TUNING_HINT_ID) : NULL;
  if (!h || h->struct_size < sizeof(uint32_t) + sizeof(const char *) || !h->objective)
    return NULL;
  return h;
}

void tt__tuning_free(tt__tuning *t) {
  if (!t) return;
  free(t->verify_json);
  for (size_t i = 0; i < t->count; i++) free(t->samples[i].config);
  free(t->samples);
  free(t->default_config);
  free(t->best_config);
  free(t);
}

/* Appends a sample (taking ownership of `config`); 0 or -1 when out of memory. */
static int tt__push_sample(tt__tuning *t, const tt__tune_sample *s) {
  if (t->count == t->cap) {
    size_t cap = t->cap ? 2 * t->cap : 64;
    tt__tune_sample *n = realloc(t->samples, cap * sizeof *n);
    if (!n) return -1;
    t->samples = n;
    t->cap = cap;
  }
  t->samples[t->count++] = *s;
  return 0;
}

/* JSON of the view: the part of the state the camera contributes. A sample of the scene's
 * camera path (--camera-index I) also records "path_index": I, so that a row says which
 * camera of the path it belongs to (the baseline generator's job is one such sample). */
static char *tt__camera_json(const tt_camera *c, const tt__host_options *opt) {
  char buf[1024], index[48] = "";
  if (opt->camera_index_set) snprintf(index, sizeof index, ",\"path_index\":%u", opt->camera_index);
  snprintf(buf, sizeof buf,
           "{\"position\":[%.9g,%.9g,%.9g],\"target\":[%.9g,%.9g,%.9g],\"up\":[%.9g,%.9g,%.9g],"
           "\"fov_y\":%.9g,\"resolution\":[%u,%u]%s}",
           c->position[0], c->position[1], c->position[2], c->target[0], c->target[1],
           c->target[2], c->up[0], c->up[1], c->up[2], c->fov_y, c->width, c->height, index);
  return tt__dup(buf);
}

/* JSON of everything else that shapes the cost: samples per measurement, threads, and the
 * other rendering plugins with their configurations (an accel's render time depends on the
 * integrator's maxDepth, an integrator's on the accel). Tuners are left out: they choose
 * configurations, they do not change what a configuration costs. */
static char *tt__context_json(tt__tune_ctx *c) {
  tt__render_state *rs = c->rs;
  cJSON *root = cJSON_CreateObject();
  cJSON_AddNumberToObject(root, "spp", c->spp);
  cJSON_AddNumberToObject(root, "threads", rs->rec->threads);
  /* CPU-time costs never answer wall-time lookups, nor the other way round */
  if (rs->opt->clock_cpu) cJSON_AddStringToObject(root, "clock", "cpu");
  cJSON *plugins = cJSON_AddObjectToObject(root, "plugins");
  for (size_t i = 0; i < tt_registry_count(rs->reg); i++) {
    const tt_plugin *e = tt_loaded_plugin_entry(tt_registry_get(rs->reg, i));
    if (i == c->target_index || e->kind == TT_KIND_TUNER || e->kind == TT_KIND_PREDICTOR)
      continue;
    cJSON *p = cJSON_AddObjectToObject(plugins, e->name);
    cJSON_AddStringToObject(p, "version", e->version);
    char *cfg = rs->configs[i] ? tt_config_to_json(rs->configs[i]) : NULL;
    cJSON *obj = cfg ? cJSON_Parse(cfg) : NULL;
    tt_free(cfg);
    cJSON_AddItemToObject(p, "config", obj ? obj : cJSON_CreateObject());
  }
  if (c->ref_lum) {  /* an rRMSE cost means something only against the same reference */
    cJSON *r = cJSON_AddObjectToObject(root, "reference");
    cJSON_AddStringToObject(r, "file", rs->opt->reference);
    cJSON_AddStringToObject(r, "fnv1a64", c->ref_hash);
  }
  char *text = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  char *out = tt__dup(text);
  cJSON_free(text);
  return out;
}

/* JSON object of a pass's metrics, or NULL when it has none. */
static char *tt__metrics_json(const tt_pass_stats *ps) {
  if (!ps->metric_count) return NULL;
  cJSON *root = cJSON_CreateObject();
  for (uint32_t m = 0; m < ps->metric_count && m < TT_MAX_METRICS; m++)
    if (ps->metrics[m].name && isfinite(ps->metrics[m].value))
      cJSON_AddNumberToObject(root, ps->metrics[m].name, ps->metrics[m].value);
  char *text = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  char *out = tt__dup(text);
  cJSON_free(text);
  return out;
}

/* Applies `cfg` to the target; TT_OK or the plugin's error. `build_ms` gets the accel's
 * build time (0 for other kinds). Unless `force`, a configuration the target already runs
 * with is not applied again; a measurement always forces, so that a re-measured accel is
 * rebuilt and its build time is measured like any other candidate's. */
static tt_status tt__apply(tt__tune_ctx *c, const tt_config *cfg, const char *json,
                           double *build_ms, int force) {
  tt__render_state *rs = c->rs;
  tt_status st = TT_OK;
  *build_ms = 0;
  if (!force && c->applied && !strcmp(c->applied, json) &&
      (c->target_kind != TT_KIND_ACCEL || rs->accel))
    return TT_OK;
  if (c->target_kind == TT_KIND_ACCEL) {
    /* the loop of Fig. 3.2: a new configuration means a new structure */
    rs->ai->destroy(rs->accel);
    rs->accel = NULL;
    tt_accel_build_stats bs;
    memset(&bs, 0, sizeof bs);
    bs.struct_size = sizeof bs;
    uint64_t b0 = rs->host->clock_ns();
    st = rs->ai->build(rs->scene, cfg, &rs->accel, &bs);
    double wall = (rs->host->clock_ns() - b0) * 1e-6;
    *build_ms = bs.build_ms > 0 ? bs.build_ms : wall;
    if (st == TT_OK) {
      rs->rec->build = bs;
      rs->rec->build_ms = *build_ms;
    } else {
      rs->accel = NULL;
    }
  } else if (c->target_kind == TT_KIND_INTEGRATOR) {
    st = rs->ii->configure(rs->integrator, cfg);
  } else if (c->target_kind == TT_KIND_POST) {
    if (!c->post) st = c->pi->create(rs->camera->width, rs->camera->height, cfg, &c->post);
    else st = c->pi->configure(c->post, cfg);
  }
  free(c->applied);
  c->applied = st == TT_OK ? tt__dup(json) : NULL;
  return st;
}

/* Runs a post filter on the film as it is; its wall ms, or a negative value on failure. */
static double tt__run_post(tt__tune_ctx *c, uint32_t frame_index) {
  tt__render_state *rs = c->rs;
  uint32_t w = rs->camera->width, h = rs->camera->height;
  tt_film_resolve(rs->film, c->post_in);
  tt_post_frame f;
  memset(&f, 0, sizeof f);
  f.struct_size = sizeof f;
  f.width = w;
  f.height = h;
  f.color = c->post_in;
  f.frame_index = frame_index;
  uint64_t t0 = rs->host->clock_ns();
  tt_status st = c->pi->process(c->post, &f, c->post_out);
  double ms = (rs->host->clock_ns() - t0) * 1e-6;
  return st == TT_OK ? ms : -1.0;
}

/* Luminance weights of tools/pssmlt (Rec. 709). */
static double tt__lum(const float *rgb) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

/* Reads --reference as luminance (RGB[A] -> Rec. 709 luminance, one channel as is) and
 * checks its size against the render's; prints and returns TT_EXIT_USAGE on a problem. */
static int tt__load_reference(tt__tune_ctx *c) {
  const char *path = c->rs->opt->reference;
  uint32_t w = 0, h = 0, ch = 0, W = c->rs->camera->width, H = c->rs->camera->height;
  float *px = NULL;
  if (tt_image_read(path, &w, &h, &ch, &px) != TT_OK) {
    fprintf(stderr, "host: --reference %s: cannot read the image: %s\n", path, tt_last_error());
    return TT_EXIT_USAGE;
  }
  if (w != W || h != H) {
    fprintf(stderr, "host: --reference %s: the reference is %ux%u but the render is %ux%u; "
            "--objective rrmse compares pixel by pixel (render the reference with --res %ux%u)\n",
            path, w, h, W, H, W, H);
    tt_free(px);
    return TT_EXIT_USAGE;
  }
  if (ch != 1 && ch < 3) {
    fprintf(stderr, "host: --reference %s: expected 1 (luminance) or 3-4 (RGB[A]) channels, "
            "got %u\n", path, ch);
    tt_free(px);
    return TT_EXIT_USAGE;
  }
  size_t n = (size_t)w * h;
  c->ref_lum = malloc(n * sizeof *c->ref_lum);
  if (!c->ref_lum) {
    tt_free(px);
    fprintf(stderr, "host: tuning: out of memory\n");
    return TT_EXIT_FAILURE;
  }
  uint64_t hash = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < n; i++) {
    double v = ch == 1 ? px[i] : tt__lum(px + i * ch);
    if (!isfinite(v)) {
      fprintf(stderr, "host: --reference %s: pixel (%zu, %zu) is not finite\n", path, i % w,
              i / w);
      tt_free(px);
      return TT_EXIT_USAGE;
    }
    c->ref_lum[i] = v;
    const unsigned char *b = (const unsigned char *)&c->ref_lum[i];
    for (size_t k = 0; k < sizeof c->ref_lum[i]; k++) hash = (hash ^ b[k]) * 0x100000001b3ull;
  }
  snprintf(c->ref_hash, sizeof c->ref_hash, "%016llx", (unsigned long long)hash);
  tt_free(px);
  return TT_EXIT_OK;
}

/* Copies the film's accumulators before a measurement pass. */
static void tt__snapshot(tt__tune_ctx *c) {
  tt_film *f = c->rs->film;
  size_t n = (size_t)tt_film_width(f) * tt_film_height(f);
  memcpy(c->snap, tt_film_sum_rgb(f), 3 * n * sizeof(float));
  memcpy(c->snap + 3 * n, tt_film_sum_weight(f), n * sizeof(float));
  memcpy(c->snap + 4 * n, tt_film_splat_rgb(f), 3 * n * sizeof(float));
  c->snap_scale = tt_film_splat_scale(f);
}

/* The image the last pass alone renders (c->pass_rgb), from the accumulators before
 * (c->snap) and after it. The tuning passes still accumulate into the film; this only
 * separates the pass's share:
 *  - per-pixel samples: (sum_wL after - before) / (sum_w after - before);
 *  - splats (film.h: resolved = splat * scale, scale = c / N for N units so far, as
 *    PSSMLT's b * pixels / mutations): the pass's splats times c / (N_after - N_before),
 *    i.e. 1 / (1/scale_after - 1/scale_before). An unchanged scale means splats that add
 *    up: the pass's splats times that scale. A film without splats before the pass, or a
 *    scale that grew (the integrator restarted its estimate and cleared the splats), leaves
 *    the splat buffer to this pass alone: splats after times scale after. */
static void tt__pass_image(tt__tune_ctx *c) {
  tt_film *f = c->rs->film;
  size_t n = (size_t)tt_film_width(f) * tt_film_height(f);
  const float *sr = tt_film_sum_rgb(f), *sw = tt_film_sum_weight(f), *sp = tt_film_splat_rgb(f);
  const float *br = c->snap, *bw = c->snap + 3 * n, *bp = c->snap + 4 * n;
  double ka = tt_film_splat_scale(f), kb = c->snap_scale;
  int splats_before = 0;
  for (size_t i = 0; i < 3 * n && !splats_before; i++) splats_before = bp[i] != 0.0f;
  double inv = 1.0 / ka - 1.0 / kb;
  int fresh = !splats_before || (ka != kb && (!(inv > 0) || !isfinite(inv)));
  double k = fresh || ka == kb ? ka : 1.0 / inv;
  for (size_t i = 0; i < n; i++) {
    double dw = (double)sw[i] - bw[i];
    for (int ch = 0; ch < 3; ch++) {
      size_t j = 3 * i + ch;
      double v = dw > 0 ? ((double)sr[j] - br[j]) / dw : 0.0;
      v += (fresh ? (double)sp[j] : (double)sp[j] - bp[j]) * k;
      c->pass_rgb[j] = (float)v;
    }
  }
}

/* rRMSE of the pass image against the reference, over luminance, as tools/pssmlt:
 * sqrt(mean((I - R)^2 / (R^2 + 1e-3))). */
static double tt__rrmse(const tt__tune_ctx *c) {
  size_t n = (size_t)c->rs->camera->width * c->rs->camera->height;
  double sum = 0;
  for (size_t i = 0; i < n; i++) {
    double I = tt__lum(c->pass_rgb + 3 * i), R = c->ref_lum[i];
    sum += (I - R) * (I - R) / (R * R + 1e-3);
  }
  return sqrt(sum / (double)n);
}

/* Renders one measurement pass (+ the post filter of a post target), keeping the pass's own
 * image in c->pass_rgb when one is wanted. */
static tt_status tt__measure_pass(tt__tune_ctx *c, tt_pass_stats *ps, double *render_ms) {
  tt__render_state *rs = c->rs;
  if (c->want_pass) tt__snapshot(c);
  tt_status st = tt__render_pass(rs, c->spp, ps, render_ms);
  if (st != TT_OK) return st;
  if (c->want_pass) tt__pass_image(c);
  if (c->target_kind == TT_KIND_POST) {
    double pms = tt__run_post(c, rs->pass);
    if (pms < 0) return TT_ERR_INTERNAL;
    *render_ms += pms;
  }
  return TT_OK;
}

/* Writes the pass image of a measurement to --tune-pass-images (a warning on failure). */
static void tt__write_pass_image(tt__tune_ctx *c, int iteration, double cost) {
  const char *dir = c->rs->opt->tune_pass_images;
  if (!dir) return;
  char path[4200], it[32], cs[64];
  if (iteration < 0) snprintf(path, sizeof path, "%s/pass_default.exr", dir);
  else snprintf(path, sizeof path, "%s/pass_%04d.exr", dir, iteration);
  snprintf(it, sizeof it, "%d", iteration);
  snprintf(cs, sizeof cs, "%.17g", cost);
  tt_image_meta meta[3] = {{"tunetrace:iteration", it},
                           {"tunetrace:objective", c->t->objective.spec},
                           {"tunetrace:cost", cs}};
  if (tt_image_write_exr(path, c->rs->camera->width, c->rs->camera->height, 3, c->pass_rgb,
                         NULL, meta, 3) != TT_OK)
    c->rs->host->log(TT_LOG_WARN, NULL, "tuning: --tune-pass-images: %s", tt_last_error());
}

/* The objective's cost of one pass; -1 (with a message) if the metric is not published. */
static int tt__cost(const tt__tune_ctx *c, double build_ms, double render_ms,
                    const tt_pass_stats *ps, double *cost, char *why, size_t why_n) {
  const tt__objective *o = &c->t->objective;
  switch (o->kind) {
    case TT_OBJ_RENDER: *cost = render_ms; return 0;
    case TT_OBJ_BUILD: *cost = build_ms; return 0;
    case TT_OBJ_TOTAL: *cost = build_ms + render_ms; return 0;
    case TT_OBJ_RRMSE: *cost = tt__rrmse(c); return 0;
    case TT_OBJ_METRIC: break;
  }
  char names[512] = "";
  for (uint32_t m = 0; m < ps->metric_count && m < TT_MAX_METRICS; m++) {
    const char *name = ps->metrics[m].name;
    if (!name) continue;
    if (!strcmp(name, o->metric)) {
      double v = ps->metrics[m].value;
      if (!isfinite(v)) break;
      *cost = o->goal == TT_GOAL_MAX ? -v : o->goal == TT_GOAL_TARGET ? fabs(v - o->target) : v;
      return 0;
    }
    size_t len = strlen(names);
    snprintf(names + len, sizeof names - len, "%s%s", len ? ", " : "", name);
  }
  snprintf(why, why_n, "the integrator's pass published no finite metric \"%s\" (it has: %s)",
           o->metric, names[0] ? names : "none");
  return -1;
}

/* Outcome of one measurement. */
enum { TT__MEASURED = 0, TT__INTERRUPTED = 1, TT__BAD_METRIC = 2, TT__NO_MEMORY = 3 };

/* How many times `config` was really measured (not answered from the database) in this
 * run so far. */
static uint32_t tt__measured_in_run(const tt__tuning *t, const char *config) {
  uint32_t n = 0;
  for (size_t i = 0; i < t->count; i++)
    if (!t->samples[i].cached && !strcmp(t->samples[i].config, config)) n++;
  return n;
}

/* Measures `cfg` (or answers it from the database), records and appends the sample.
 * `*cost_out` gets the cost to feed back. The database answers only configurations this
 * run has not measured yet: a tuner that proposes a configuration again after measuring it
 * here wants a new sample (it re-measures its incumbent against noise), which is measured
 * and recorded as a new row. */
static int tt__measure(tt__tune_ctx *c, tt_config *cfg, int iteration, const char *mode,
                       double *cost_out) {
  tt__render_state *rs = c->rs;
  tt__tuning *t = c->t;
  tt__tune_sample s;
  memset(&s, 0, sizeof s);
  s.iteration = iteration;
  char *json = tt_config_to_json(cfg);
  s.config = tt__dup(json);
  tt_free(json);
  if (!s.config) return TT__NO_MEMORY;

  tt_tunedb_row row = c->key;
  row.config = s.config;
  double cached = 0;
  uint32_t times = 0, here = tt__measured_in_run(t, s.config);
  if (here)
    rs->host->log(TT_LOG_INFO, NULL, "tuning: iteration %d: measuring again a configuration "
                  "measured %u time%s in this run", iteration, here, here == 1 ? "" : "s");
  else if (c->db && tt_tunedb_lookup(c->db, &row, &cached, &times) == TT_OK) {
    s.cost = cached;
    s.cached = 1;
    s.status = cached >= TT_COST_INFEASIBLE ? TT_TUNEDB_INFEASIBLE : TT_TUNEDB_OK;
    t->cached++;
    if (s.status == TT_TUNEDB_INFEASIBLE) t->infeasible++;
    if (iteration < 0)
      rs->host->log(TT_LOG_INFO, NULL, "tuning: default configuration: cost %.6g from the "
                    "database (%u earlier measurement%s), not measured again", cached, times,
                    times == 1 ? "" : "s");
    else
      rs->host->log(TT_LOG_INFO, NULL, "tuning: iteration %d: cost %.6g from the database "
                    "(%u earlier measurement%s), not measured again", iteration, cached, times,
                    times == 1 ? "" : "s");
    *cost_out = cached;
    return tt__push_sample(t, &s) ? TT__NO_MEMORY : TT__MEASURED;
  }

  char why[512] = "";
  tt_pass_stats ps;
  memset(&ps, 0, sizeof ps);
  double build_ms = 0, render_ms = 0;
  tt_config *work = tt_config_clone(cfg);
  tt_check_result check = work ? tt_space_check(c->space, work, why, sizeof why) : TT_CHECK_OK;
  if (!work) {
    free(s.config);
    return TT__NO_MEMORY;
  }
  if (check == TT_CHECK_INFEASIBLE) {
    s.status = TT_TUNEDB_INFEASIBLE;
    rs->host->log(TT_LOG_INFO, NULL, "tuning: iteration %d: infeasible: %s", iteration, why);
  } else if (tt__apply(c, work, s.config, &build_ms, 1) != TT_OK) {
    s.status = TT_TUNEDB_FAILED;
    rs->host->log(TT_LOG_WARN, NULL, "tuning: iteration %d: %s rejected %s: %s", iteration,
                  t->plugin, s.config, tt_last_error());
  } else {
    tt_status st = tt__measure_pass(c, &ps, &render_ms);
    if (st == TT_ERR_INTERRUPTED) {
      tt_config_destroy(work);
      free(s.config);
      return TT__INTERRUPTED;
    }
    if (st != TT_OK) {
      s.status = TT_TUNEDB_FAILED;
      rs->host->log(TT_LOG_WARN, NULL, "tuning: iteration %d: the pass failed: %s", iteration,
                    tt_last_error());
    } else if (tt__cost(c, build_ms, render_ms, &ps, &s.cost, why, sizeof why)) {
      tt_config_destroy(work);
      free(s.config);
      fprintf(stderr, "host: --objective %s: %s\n", t->objective.spec, why);
      return TT__BAD_METRIC;
    } else {
      s.status = TT_TUNEDB_OK;
      if (c->want_pass) tt__write_pass_image(c, iteration, s.cost);
    }
  }
  tt_config_destroy(work);
  if (s.status != TT_TUNEDB_OK) s.cost = TT_COST_INFEASIBLE;
  if (s.status == TT_TUNEDB_INFEASIBLE) t->infeasible++;
  if (s.status == TT_TUNEDB_FAILED) t->failed++;
  s.build_ms = build_ms;
  s.render_ms = render_ms;
  t->measured++;

  if (c->db) {
    char *metrics = tt__metrics_json(&ps);
    row.build_ms = build_ms;
    row.render_ms = render_ms;
    row.cost = s.cost;
    row.status = s.status;
    row.mode = iteration < 0 ? "default" : mode;
    row.iteration = iteration;
    row.metrics = metrics;
    if (tt_tunedb_record(c->db, &row) != TT_OK)
      rs->host->log(TT_LOG_WARN, NULL, "tuning: %s", tt_last_error());
    free(metrics);
  }
  *cost_out = s.cost;
  return tt__push_sample(t, &s) ? TT__NO_MEMORY : TT__MEASURED;
}

/* SplitMix64: the exploration's random stream (seeded from the run's seed). */
static uint64_t tt__splitmix(uint64_t *state) {
  uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/* Picks the best configuration: lowest mean cost over every measurement of the same
 * configuration (the default included), so one lucky timing cannot win over a config
 * measured several times, matching how tuner_nm averages re-measured incumbents. */
static void tt__pick_best(tt__tuning *t) {
  t->best_cost = TT_COST_INFEASIBLE;
  free(t->best_config);
  t->best_config = NULL;
  for (size_t i = 0; i < t->count; i++) {
    const char *cfg = t->samples[i].config;
    int seen = 0;
    for (size_t j = 0; j < i && !seen; j++) seen = !strcmp(t->samples[j].config, cfg);
    if (seen) continue;
    double sum = 0;
    uint32_t n = 0;
    for (size_t j = i; j < t->count; j++) {
      if (strcmp(t->samples[j].config, cfg) || t->samples[j].status == TT_TUNEDB_FAILED) continue;
      sum += t->samples[j].cost;
      n++;
    }
    if (!n) continue;
    double mean = sum / n;
    if (mean < t->best_cost || !t->best_config) {
      t->best_cost = mean;
      free(t->best_config);
      t->best_config = tt__dup(cfg);
    }
  }
  if (!t->best_config) {
    t->best_config = tt__dup(t->default_config);
    t->best_cost = t->default_cost;
  }
  t->best_from = t->best_config && t->default_config && !strcmp(t->best_config, t->default_config)
                     ? "default" : t->mode;
}

/* Median of n values (sorts them in place); NaN for n = 0. */
static int tt__cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}
static double tt__median(double *v, size_t n) {
  if (!n) return NAN;
  qsort(v, n, sizeof *v, tt__cmp_double);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* One verification measurement: applies `cfg` (rebuilding an accel) and renders one pass.
 * 0 on success, 1 when interrupted, -1 when the configuration fails. */
static int tt__verify_one(tt__tune_ctx *c, const tt_config *cfg, const char *json,
                          double out[3]) {
  tt__render_state *rs = c->rs;
  double build_ms = 0, render_ms = 0, cost = 0;
  char why[512];
  tt_pass_stats ps;
  memset(&ps, 0, sizeof ps);
  (void)rs;
  if (tt__apply(c, cfg, json, &build_ms, 1) != TT_OK) return -1;
  tt_status st = tt__measure_pass(c, &ps, &render_ms);
  if (st == TT_ERR_INTERRUPTED) return 1;
  if (st != TT_OK || tt__cost(c, build_ms, render_ms, &ps, &cost, why, sizeof why))
    return -1;
  out[0] = build_ms;
  out[1] = render_ms;
  out[2] = cost;
  return 0;
}

/* --verify N: the default and the best configuration measured side by side in N rounds of
 * one pass each, alternating the order (ABBA...) so that a drift in machine speed hits both
 * alike. The figures are per-round ratios best/default and their medians: the gain of the
 * tuned configuration taken in one run, not two tuning-time numbers measured minutes apart.
 * Nothing is recorded in the database (these are repeats, not new states). Returns 1 if
 * interrupted. */
static int tt__verify(tt__tune_ctx *c, uint32_t rounds) {
  tt__render_state *rs = c->rs;
  tt__tuning *t = c->t;
  tt_config *cfg[2] = {tt_config_create(c->space), tt_config_create(c->space)};
  const char *json[2] = {t->default_config, t->best_config};
  double *m = calloc((size_t)rounds * 6 + 3 * (size_t)rounds, sizeof *m);  /* [r][who][3] */
  cJSON *root = cJSON_CreateObject();
  int rc = 0;
  uint32_t done = 0;
  if (!cfg[0] || !cfg[1] || !m || !root || !json[0] || !json[1] ||
      tt_config_from_json(cfg[0], json[0], "default") != TT_OK ||
      tt_config_from_json(cfg[1], json[1], "best") != TT_OK) {
    rs->host->log(TT_LOG_ERROR, NULL, "tuning: --verify: cannot set up: %s", tt_last_error());
    goto out;
  }
  for (uint32_t r = 0; r < rounds && !rc; r++) {
    if (rs->host->should_stop()) {
      rc = 1;
      break;
    }
    for (int k = 0; k < 2 && !rc; k++) {
      int who = (r % 2) ? 1 - k : k;  /* 0 = default, 1 = best */
      int v = tt__verify_one(c, cfg[who], json[who], &m[((size_t)r * 2 + who) * 3]);
      if (v == 1) rc = 1;
      if (v < 0) {
        rs->host->log(TT_LOG_ERROR, NULL, "tuning: --verify: the %s configuration failed: %s",
                      who ? "best" : "default", tt_last_error());
        goto out;
      }
    }
    if (!rc) done++;
  }
  if (!done) goto out;
  double *tmp = &m[(size_t)rounds * 6];
  cJSON_AddNumberToObject(root, "rounds", done);
  cJSON_AddNumberToObject(root, "spp", c->spp);
  static const char *who_name[2] = {"default", "best"};
  static const char *field[3] = {"build_ms", "render_ms", "cost"};
  double med[2][4];
  for (int who = 0; who < 2; who++) {
    cJSON *o = cJSON_AddObjectToObject(root, who_name[who]);
    for (int f = 0; f < 4; f++) {
      cJSON *arr = f < 3 ? cJSON_AddArrayToObject(o, field[f]) : NULL;
      for (uint32_t r = 0; r < done; r++) {
        const double *x = &m[((size_t)r * 2 + who) * 3];
        tmp[r] = f < 3 ? x[f] : x[0] + x[1];
        if (arr) cJSON_AddItemToArray(arr, cJSON_CreateNumber(tmp[r]));
      }
      med[who][f] = tt__median(tmp, done);
    }
    cJSON_AddNumberToObject(o, "median_build_ms", med[who][0]);
    cJSON_AddNumberToObject(o, "median_render_ms", med[who][1]);
    cJSON_AddNumberToObject(o, "median_total_ms", med[who][3]);
    cJSON_AddNumberToObject(o, "median_cost", med[who][2]);
  }
  /* per-round ratios best/default: render, build+render, and the objective's cost */
  static const char *ratio_name[3] = {"render_ratio", "total_ratio", "cost_ratio"};
  double ratio[3];
  for (int q = 0; q < 3; q++) {
    uint32_t n = 0;
    for (uint32_t r = 0; r < done; r++) {
      const double *d = &m[((size_t)r * 2) * 3], *b = &m[((size_t)r * 2 + 1) * 3];
      double num = q == 0 ? b[1] : q == 1 ? b[0] + b[1] : b[2];
      double den = q == 0 ? d[1] : q == 1 ? d[0] + d[1] : d[2];
      if (den > 0 && isfinite(num / den)) tmp[n++] = num / den;
    }
    ratio[q] = tt__median(tmp, n);
    if (isfinite(ratio[q])) cJSON_AddNumberToObject(root, ratio_name[q], ratio[q]);
    else cJSON_AddNullToObject(root, ratio_name[q]);
  }
  char *text = cJSON_PrintUnformatted(root);
  free(t->verify_json);
  t->verify_json = tt__dup(text);
  cJSON_free(text);
  rs->host->log(TT_LOG_INFO, NULL, "tuning: verify, %u rounds side by side: render median "
                "%.4g ms (default) vs %.4g ms (best), ratio %.4f; build+render %.4g vs %.4g ms, "
                "ratio %.4f", done, med[0][1], med[1][1], ratio[0], med[0][3], med[1][3],
                ratio[1]);
out:
  cJSON_Delete(root);
  free(m);
  tt_config_destroy(cfg[0]);
  tt_config_destroy(cfg[1]);
  return rc;
}

/* Builds c->subset from --tune-params or the hint's tunable list (defaults = the target's
 * configured values); leaves it NULL when every parameter is searched. */
static int tt__make_subset(tt__tune_ctx *c, const tt_tuning_hint *hint) {
  const char *names[256];
  size_t n = 0;
  char buf[4096];
  const tt__host_options *opt = c->rs->opt;
  if (opt->tune_params) {
    snprintf(buf, sizeof buf, "%s", opt->tune_params);
    for (char *tok = strtok(buf, ","); tok && n < 256; tok = strtok(NULL, ",")) names[n++] = tok;
  } else if (hint && hint->struct_size >= offsetof(tt_tuning_hint, tunable) + sizeof(hint->tunable) &&
             hint->tunable) {
    for (; hint->tunable[n] && n < 256; n++) names[n] = hint->tunable[n];
  }
  /* the hint's starting values (PSSMLT: binning on), then the user's --set on top */
  if (hint && hint->struct_size >= offsetof(tt_tuning_hint, setup) + sizeof(hint->setup) &&
      hint->setup) {
    tt_config *cfg = c->rs->configs[c->target_index];
    const char *name = tt_loaded_plugin_entry(c->target)->name;
    size_t len = strlen(name);
    if (tt_config_from_json(cfg, hint->setup, "tuning hint setup") != TT_OK) {
      fprintf(stderr, "host: %s: %s\n", name, tt_last_error());
      return 1;
    }
    for (int k = 0; k < opt->set_count; k++)
      if (!strncmp(opt->sets[k], name, len) && opt->sets[k][len] == '.') {
        char param[128];
        const char *eq = strchr(opt->sets[k], '=');
        snprintf(param, sizeof param, "%.*s", (int)(eq - opt->sets[k] - len - 1),
                 opt->sets[k] + len + 1);
        tt_config_set_string(cfg, param, eq + 1); /* validated when the configs were built */
      }
  }
  if (n == 0) return 0;
  c->subset = tt_space_subset(c->space, names, n, c->rs->configs[c->target_index]);
  if (!c->subset) {
    fprintf(stderr, "host: %s: %s\n", opt->tune_params ? "--tune-params" : "tuning hint",
            tt_last_error());
    return 1;
  }
  return 0;
}

/* Chooses the target plugin and objective from the options; prints and returns
 * TT_EXIT_USAGE on a bad choice. */
static int tt__choose(tt__tune_ctx *c) {
  tt__render_state *rs = c->rs;
  const tt__host_options *opt = rs->opt;
  char names[1024];
  const tt_tuning_hint *hint = NULL;
  if (opt->tune) {
    c->target = tt_registry_find_name(rs->reg, opt->tune);
    if (!c->target) {
      tt__names(rs->reg, names, sizeof names);
      fprintf(stderr, "host: --tune %s: no loaded plugin is called \"%s\" (loaded: %s)\n",
              opt->tune, opt->tune, names);
      return TT_EXIT_USAGE;
    }
    uint32_t kind = tt_loaded_plugin_entry(c->target)->kind;
    if (kind != TT_KIND_ACCEL && kind != TT_KIND_INTEGRATOR && kind != TT_KIND_POST) {
      fprintf(stderr, "host: --tune %s: a %s plugin cannot be tuned by the host (only accel, "
              "integrator and post plugins)\n", opt->tune, tt_plugin_kind_name(kind));
      return TT_EXIT_USAGE;
    }
    if (!tt__tunable(c->target)) {
      fprintf(stderr, "host: --tune %s: the plugin publishes no tunable parameters\n", opt->tune);
      return TT_EXIT_USAGE;
    }
    hint = tt__hint(c->target);
  } else {
    /* an integrator that says how to tune it (PSSMLT) wins; otherwise the accel, whose
     * parameters change speed only, never the image (integrator_pt's maxDepth would) */
    hint = tt__hint(rs->integ_p);
    if (hint && tt__tunable(rs->integ_p)) c->target = rs->integ_p;
    else if (tt__tunable(rs->accel_p)) c->target = rs->accel_p, hint = NULL;
    else {
      fprintf(stderr, "host: tuning: neither the integrator nor the accel publishes tunable "
              "parameters; name a plugin with --tune\n");
      return TT_EXIT_USAGE;
    }
  }
  c->target_index = tt__index_of(rs->reg, c->target);
  c->target_kind = tt_loaded_plugin_entry(c->target)->kind;
  c->space = tt_loaded_plugin_space(c->target);
  if (tt__make_subset(c, hint)) return TT_EXIT_USAGE;
  const char *spec = opt->objective ? opt->objective : hint ? hint->objective : "render";
  if (tt__parse_objective(opt->objective ? "--objective" : "tuning hint", spec,
                          &c->t->objective))
    return TT_EXIT_USAGE;
  if ((c->t->objective.kind == TT_OBJ_BUILD || c->t->objective.kind == TT_OBJ_TOTAL) &&
      c->target_kind != TT_KIND_ACCEL) {
    fprintf(stderr, "host: --objective %s: only an accel target builds anything; %s is "
            "of kind %s (use render or metric:NAME)\n", spec, tt_loaded_plugin_entry(c->target)->name,
            tt_plugin_kind_name(c->target_kind));
    return TT_EXIT_USAGE;
  }
  if (c->t->objective.kind == TT_OBJ_RRMSE) {
    int r = tt__load_reference(c);
    if (r != TT_EXIT_OK) return r;
  }
  const char *dir = opt->tune_pass_images;
  if (dir && mkdir(dir, 0777) != 0 && errno != EEXIST) {
    fprintf(stderr, "host: --tune-pass-images %s: cannot create the folder: %s\n", dir,
            strerror(errno));
    return TT_EXIT_USAGE;
  }
  c->want_pass = c->t->objective.kind == TT_OBJ_RRMSE || dir;
  if (c->want_pass) {
    size_t px = (size_t)rs->camera->width * rs->camera->height;
    c->snap = malloc(7 * px * sizeof(float));
    c->pass_rgb = malloc(3 * px * sizeof(float));
    if (!c->snap || !c->pass_rgb) {
      fprintf(stderr, "host: tuning: out of memory\n");
      return TT_EXIT_FAILURE;
    }
  }
  if (c->target_kind == TT_KIND_POST) {
    c->pi = tt_loaded_plugin_iface(c->target);
    size_t px = (size_t)rs->camera->width * rs->camera->height * 3;
    c->post_in = malloc(px * sizeof(float));
    c->post_out = malloc(px * sizeof(float));
    if (!c->post_in || !c->post_out) {
      fprintf(stderr, "host: tuning: out of memory\n");
      return TT_EXIT_FAILURE;
    }
  }
  return TT_EXIT_OK;
}

/* Opens the database (--db, the default path, or none with --no-db). */
static int tt__open_db(tt__tune_ctx *c) {
  const tt__host_options *opt = c->rs->opt;
  if (opt->no_db) return TT_EXIT_OK;
  char *path = opt->db ? tt__dup(opt->db) : tt_tunedb_default_path();
  if (!path) {
    c->rs->host->log(TT_LOG_WARN, NULL, "tuning: no $XDG_DATA_HOME or $HOME: tuning without "
                     "a database (use --db PATH)");
    return TT_EXIT_OK;
  }
  if (tt_tunedb_open(path, &c->db) != TT_OK) {
    if (opt->db) {
      fprintf(stderr, "host: --db: %s\n", tt_last_error());
      free(path);
      return TT_EXIT_FAILURE;
    }
    c->rs->host->log(TT_LOG_WARN, NULL, "tuning: %s; tuning without a database",
                     tt_last_error());
    c->db = NULL;
  }
  free(path);
  return TT_EXIT_OK;
}

/* Fills the state part of the database key, shared by every row of the run. */
static int tt__make_key(tt__tune_ctx *c) {
  tt__render_state *rs = c->rs;
  const tt_plugin *e = tt_loaded_plugin_entry(c->target);
  c->camera_json = tt__camera_json(rs->camera, rs->opt);
  c->context_json = tt__context_json(c);
  if (!c->camera_json || !c->context_json) return -1;
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  snprintf(c->run_id, sizeof c->run_id, "%llx-%d",
           (unsigned long long)ts.tv_sec * 1000000000ull + (unsigned long long)ts.tv_nsec,
           (int)getpid());
  memset(&c->key, 0, sizeof c->key);
  c->key.struct_size = sizeof c->key;
  c->key.scene_id = tt_scene_id(rs->scene);
  c->key.scene = tt_scene_source(rs->scene);
  c->key.camera = c->camera_json;
  c->key.context = c->context_json;
  c->key.plugin = e->name;
  c->key.plugin_version = e->version;
  c->key.objective = c->t->objective.spec;
  c->key.run_id = c->run_id;
  c->key.tuner = c->t->tuner;
  if (c->db) {
    tt_scene_indicators(rs->scene, c->key.indicators);
    c->key.has_indicators = 1;
  }
  return 0;
}

/* Draws progress of the tuning phase. */
static void tt__tune_progress(const tt__tuning *t, uint32_t done) {
  tt__progress_update(!strcmp(t->mode, "explore") ? "explore" : "tuning",
                      t->requested ? (double)done / t->requested : 1.0);
}

int tt__tune_phase(tt__render_state *rs, tt__tuning **out) {
  const tt__host_options *opt = rs->opt;
  *out = NULL;
  tt_loaded_plugin *tuner_p = tt_registry_find_kind(rs->reg, TT_KIND_TUNER);
  int explore = opt->explore > 0;
  if (!tuner_p && !explore) {
    if (opt->tune || opt->objective || opt->iterations || opt->tune_spp || opt->verify ||
        opt->tune_pass_images) {
      fprintf(stderr, "host: %s needs a tuner plugin (e.g. --plugin tuner_nm) or --explore N\n",
              opt->tune ? "--tune" : opt->objective ? "--objective"
              : opt->iterations ? "--iterations" : opt->tune_spp ? "--tune-spp"
              : opt->verify ? "--verify" : "--tune-pass-images");
      return TT_EXIT_USAGE;
    }
    return TT_EXIT_OK;
  }
  if (explore && opt->iterations) {
    fprintf(stderr, "host: --explore N and --iterations exclude each other (exploration "
            "measures N random configurations)\n");
    return TT_EXIT_USAGE;
  }

  tt__tuning *t = calloc(1, sizeof *t);
  if (!t) return TT_EXIT_FAILURE;
  tt__tune_ctx c;
  memset(&c, 0, sizeof c);
  c.rs = rs;
  c.t = t;
  c.spp = opt->tune_spp ? opt->tune_spp : 1;
  t->mode = explore ? "explore" : "tune";
  t->tuner = explore ? NULL : tt_loaded_plugin_entry(tuner_p)->name;
  t->requested = explore ? opt->explore : opt->iterations ? opt->iterations
                                                          : TT_HOST_DEFAULT_ITERATIONS;
  int rc = tt__choose(&c);
  tt_tuner *tuner = NULL;
  tt_config *cand = NULL, *sub = NULL;
  const tt_tuner_iface *ti = NULL;
  if (rc == TT_EXIT_OK) rc = tt__open_db(&c);
  if (rc != TT_EXIT_OK) goto fail;
  const tt_plugin *te = tt_loaded_plugin_entry(c.target);
  t->plugin = te->name;
  t->plugin_version = te->version;
  t->db_path = c.db ? tt_tunedb_path(c.db) : NULL;
  if (tt__make_key(&c)) {
    rc = TT_EXIT_FAILURE;
    goto fail;
  }
  tt_config *current = rs->configs[c.target_index];
  char *json = tt_config_to_json(current);
  t->default_config = tt__dup(json);
  tt_free(json);
  /* c.applied stays NULL: the default is applied again like every candidate (an accel is
   * rebuilt), so its build time is measured and it pays the same cold-start costs */
  if (explore && tuner_p && !opt->quiet)
    rs->host->log(TT_LOG_INFO, NULL, "tuning: --explore draws random configurations; the "
                  "tuner %s is not used", tt_loaded_plugin_entry(tuner_p)->name);
  rs->host->log(TT_LOG_INFO, NULL, "%s %s %s%s%s, objective %s, %u %s, %u spp per "
                "measurement, database %s", explore ? "exploring" : "tuning", te->name,
                te->version, explore ? "" : " with ", explore ? "" : t->tuner,
                t->objective.spec, t->requested, explore ? "configurations" : "iterations",
                c.spp, c.db ? tt_tunedb_path(c.db) : "none");

  uint64_t t0 = rs->host->clock_ns();
  /* the tuner searches `search` (a subset when --tune-params or the hint narrows it);
   * every candidate is the current configuration with the searched values put in */
  const tt_space *search = c.subset ? c.subset : c.space;
  cand = tt_config_create(c.space);
  sub = tt_config_create(search);
  if (!cand || !sub) {
    rc = TT_EXIT_FAILURE;
    goto fail;
  }
  if (!explore) {
    ti = tt_loaded_plugin_iface(tuner_p);
    const tt_config *settings = rs->configs[tt__index_of(rs->reg, tuner_p)];
    if (ti->create(search, settings, rs->rec->seed, &tuner) != TT_OK) {
      fprintf(stderr, "host: %s: %s\n", t->tuner, tt_last_error());
      rc = TT_EXIT_FAILURE;
      goto fail;
    }
  }

  /* one unmeasured warm-up pass (it still goes into the image): the first pass pays for
   * page faults and lazy initialisation, which would make the default look slow */
  double cost = 0;
  tt_pass_stats warm;
  if (tt__render_pass(rs, 1, &warm, &cost) == TT_ERR_INTERRUPTED) t->interrupted = 1;

  /* the default configuration first: the baseline the tuned one is compared with */
  int m = t->interrupted ? TT__INTERRUPTED : tt__measure(&c, current, -1, t->mode, &cost);
  if (m == TT__BAD_METRIC) {
    rc = TT_EXIT_USAGE;
    goto fail;
  }
  if (m == TT__NO_MEMORY) {
    rc = TT_EXIT_FAILURE;
    goto fail;
  }
  t->interrupted = m == TT__INTERRUPTED;
  t->default_cost = t->count ? t->samples[0].cost : TT_COST_INFEASIBLE;
  tt__tune_progress(t, 0);

  uint64_t rng = rs->rec->seed ^ 0x7475756e65ull;
  size_t dims = tt_space_count(search);
  double *unit = calloc(dims ? dims : 1, sizeof *unit);
  for (uint32_t it = 0; it < t->requested && !t->interrupted && unit; it++) {
    if (rs->host->should_stop()) {
      t->interrupted = 1;
      break;
    }
    if (opt->time_budget > 0 && (rs->host->clock_ns() - t0) * 1e-9 >= opt->time_budget) break;
    if (explore) {
      for (size_t d = 0; d < dims; d++) unit[d] = (tt__splitmix(&rng) >> 11) * 0x1.0p-53;
      tt_config_from_unit(sub, unit);
      tt_config_copy(cand, current);
      tt_config_assign(cand, sub);
      char why[256];
      /* a repairable draw is measured as repaired; an infeasible one is recorded as such
       * (tt__measure checks again), since where the constraints bite is part of the map */
      tt_space_check(c.space, cand, why, sizeof why);
    } else {
      tt_status st = ti->next(tuner, sub);
      if (st == TT_DONE) {
        t->converged = 1;
        rs->host->log(TT_LOG_INFO, NULL, "tuning: %s reports convergence after %u iterations",
                      t->tuner, it);
        break;
      }
      if (st != TT_OK) {
        rs->host->log(TT_LOG_ERROR, NULL, "tuning: %s: next: %s", t->tuner, tt_last_error());
        rc = TT_EXIT_FAILURE;
        break;
      }
    }
    if (!explore) {
      tt_config_copy(cand, current);
      tt_config_assign(cand, sub);
    }
    m = tt__measure(&c, cand, (int)it, t->mode, &cost);
    if (m == TT__INTERRUPTED) {
      t->interrupted = 1;
      break;
    }
    if (m != TT__MEASURED) {
      rc = m == TT__BAD_METRIC ? TT_EXIT_USAGE : TT_EXIT_FAILURE;
      break;
    }
    if (!explore && ti->feedback(tuner, cost) != TT_OK) {
      rs->host->log(TT_LOG_ERROR, NULL, "tuning: %s: feedback: %s", t->tuner, tt_last_error());
      rc = TT_EXIT_FAILURE;
      break;
    }
    tt__tune_progress(t, it + 1);
  }
  free(unit);
  tt__progress_finish();
  t->ms = (rs->host->clock_ns() - t0) * 1e-6;

  /* keep the best: the rest of the image renders with it */
  tt__pick_best(t);
  if (opt->verify && !t->interrupted && rc == TT_EXIT_OK && tt__verify(&c, opt->verify))
    t->interrupted = 1;
  if (t->best_config && tt_config_from_json(current, t->best_config, "tuning") != TT_OK)
    rs->host->log(TT_LOG_ERROR, NULL, "tuning: cannot restore the best configuration: %s",
                  tt_last_error());
  if (!t->interrupted && rc == TT_EXIT_OK) {
    double build_ms = 0;
    if (tt__apply(&c, current, t->best_config, &build_ms, 0) != TT_OK) {
      fprintf(stderr, "host: tuning: %s rejected the best configuration: %s\n", t->plugin,
              tt_last_error());
      rc = TT_EXIT_FAILURE;
    }
  }
  uint32_t iters = t->count ? (uint32_t)t->count - 1 : 0;
  if (t->default_cost > 0 && t->default_cost < TT_COST_INFEASIBLE &&
      t->best_cost < TT_COST_INFEASIBLE && t->objective.kind != TT_OBJ_METRIC)
    rs->host->log(TT_LOG_INFO, NULL, "tuning: best cost %.6g (%s), default %.6g: %.1f%% lower, "
                  "after %u iterations (%u measured, %u from the database): %s", t->best_cost,
                  t->best_from, t->default_cost, 100.0 * (1.0 - t->best_cost / t->default_cost),
                  iters, t->measured, t->cached, t->best_config);
  else
    rs->host->log(TT_LOG_INFO, NULL, "tuning: best cost %.6g (%s), default %.6g, after %u "
                  "iterations (%u measured, %u from the database): %s", t->best_cost,
                  t->best_from, t->default_cost, iters, t->measured, t->cached,
                  t->best_config);

fail:
  if (tuner) ti->destroy(tuner);
  tt_config_destroy(cand);
  tt_config_destroy(sub);
  tt_space_destroy(c.subset);
  free(c.applied);
  free(c.camera_json);
  free(c.context_json);
  if (c.post) c.pi->destroy(c.post);
  free(c.post_in);
  free(c.post_out);
  free(c.snap);
  free(c.pass_rgb);
  free(c.ref_lum);
  /* the path is still shown in stats: keep a copy alive as long as the record */
  if (c.db) {
    static char db_path[4096];
    snprintf(db_path, sizeof db_path, "%s", tt_tunedb_path(c.db));
    t->db_path = db_path;
  }
  tt_tunedb_close(c.db);
  if (rc == TT_EXIT_USAGE) {
    tt__tuning_free(t);
    return rc;
  }
  *out = t;
  return rc;
}
