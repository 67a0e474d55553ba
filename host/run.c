/* host: the jobs — list plugins, describe a plugin, render a scene. */
#include "session.h"
#include "tune.h"

#include <cjson/cJSON.h>
#include <libgen.h>
#include <limits.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- --list-plugins ---- */

typedef struct tt__list_ctx {
  tt_registry *reg;
  int found, rejected;
} tt__list_ctx;

static void tt__list_one(void *user, const char *path) {
  tt__list_ctx *ctx = user;
  tt_plugin e;
  if (tt_registry_probe(ctx->reg, path, &e) == TT_OK) {
    printf("%-22s %-10s %-8s %s\n    %s\n", e.name, tt_plugin_kind_name(e.kind), e.version, path,
           e.description ? e.description : "");
    ctx->found++;
  } else {
    printf("%-22s %-10s %-8s %s\n    rejected: %s\n", "?", "-", "-", path, tt_last_error());
    ctx->rejected++;
  }
}

int tt__run_list_plugins(const tt__host_options *opt) {
  tt_registry *reg = tt__make_registry(opt, tt__host_services(opt->quiet));
  if (!reg) return TT_EXIT_FAILURE;
  tt__list_ctx ctx = {reg, 0, 0};
  printf("%-22s %-10s %-8s %s\n", "NAME", "KIND", "VERSION", "PATH");
  tt_registry_list_files(reg, tt__list_one, &ctx);
  if (!opt->quiet)
    tt__say("%d plugin(s), %d rejected; search path: %s\n", ctx.found, ctx.rejected,
            tt_registry_search_path(reg));
  tt_registry_destroy(reg);
  /* everything is listed first; a rejected file is then a plugin error like --plugin's */
  return ctx.rejected ? TT_EXIT_PLUGIN : TT_EXIT_OK;
}

/* ---- --describe ---- */

/* The JSON of one plugin's space and options (NULL after printing what failed); `*rc` gets
 * the exit code of a failure. */
static cJSON *tt__describe_one(tt_registry *reg, const char *name, int *rc) {
  tt_loaded_plugin *p = NULL;
  if (tt_registry_load(reg, name, &p) != TT_OK) {
    tt__say("--describe \"%s\": %s\n", name, tt_last_error());
    *rc = TT_EXIT_PLUGIN;
    return NULL;
  }
  const tt_plugin *e = tt_loaded_plugin_entry(p);
  const tt_space *space = tt_loaded_plugin_space(p);
  char *json = space ? tt_space_to_json(space) : NULL;
  cJSON *root = json ? cJSON_Parse(json) : cJSON_CreateObject();
  tt_free(json);
  if (!root) {
    tt__say("--describe %s: %s\n", e->name, space ? tt_last_error() : "out of memory");
    *rc = TT_EXIT_FAILURE;
    return NULL;
  }
  if (!space) {
    cJSON_AddStringToObject(root, "plugin", e->name);
    cJSON_AddStringToObject(root, "version", e->version);
    cJSON_AddItemToObject(root, "parameters", cJSON_CreateArray());
    cJSON_AddItemToObject(root, "constraints", cJSON_CreateArray());
  }
  /* options (tt.options/1): set with --set NAME.KEY=VALUE like parameters, never tuned */
  cJSON *opts = cJSON_AddArrayToObject(root, "options");
  const tt_options_iface *oi = tt_session_plugin_options(p);
  for (uint32_t i = 0; oi && i < oi->count(); i++) {
    const tt_option_info *info = oi->info(i);
    if (!info || !info->key) continue;
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "name", info->key);
    cJSON_AddStringToObject(o, "description", info->description ? info->description : "");
    const char *v = oi->get(info->key);
    cJSON_AddStringToObject(o, "value", v ? v : "");
    cJSON_AddItemToArray(opts, o);
  }
  return root;
}

int tt__run_describe(const tt__host_options *opt) {
  /* one NAME: its object; several: an array of them in order (every failure reported).
   * A registry per name: two plugins of one kind cannot share one. */
  int rc = TT_EXIT_OK;
  cJSON *all = cJSON_CreateArray();
  for (int k = 0; k < opt->describe_count; k++) {
    tt_registry *reg = tt__make_registry(opt, tt__host_services(1));
    if (!reg) {
      rc = TT_EXIT_FAILURE;
      break;
    }
    cJSON *one = tt__describe_one(reg, opt->describe[k], &rc);
    if (one) cJSON_AddItemToArray(all, one);
    tt_registry_destroy(reg);
  }
  if (rc == TT_EXIT_OK) {
    cJSON *root = opt->describe_count == 1 ? cJSON_GetArrayItem(all, 0) : all;
    char *out = cJSON_Print(root);
    if (out) printf("%s\n", out);
    free(out);
  }
  cJSON_Delete(all);
  return rc;
}

/* ---- render ---- */

/* The EXR's pixels: RGB, then every AOV plane of the film as a named layer, in the channel
 * names external denoisers and compositors read (depth.Z, normal.X/Y/Z, albedo.R/G/B,
 * motion.X/Y). Returns the channel count; `names` receives them (static strings). */
static uint32_t tt__exr_layers(const tt_film *film, const float *rgb, float *out,
                               const char **names) {
  static const struct {
    tt_aov aov;
    const char *names[3];
  } layers[] = {
      {TT_AOV_DEPTH, {"depth.Z"}},
      {TT_AOV_NORMAL, {"normal.X", "normal.Y", "normal.Z"}},
      {TT_AOV_ALBEDO, {"albedo.R", "albedo.G", "albedo.B"}},
      {TT_AOV_MOTION, {"motion.X", "motion.Y"}},
  };
  size_t n = (size_t)tt_film_width(film) * tt_film_height(film);
  uint32_t ch = 3;
  names[0] = "R", names[1] = "G", names[2] = "B";
  for (size_t l = 0; l < sizeof layers / sizeof layers[0]; l++) {
    if (!(tt_film_aov_mask(film) & layers[l].aov)) continue;
    for (uint32_t c = 0; c < tt_aov_channels(layers[l].aov); c++)
      names[ch + c] = layers[l].names[c];
    ch += tt_aov_channels(layers[l].aov);
  }
  for (size_t i = 0; i < n; i++) {
    float *px = out + i * ch;
    memcpy(px, rgb + 3 * i, 3 * sizeof(float));
    uint32_t c = 3;
    for (size_t l = 0; l < sizeof layers / sizeof layers[0]; l++) {
      const float *plane = tt_film_aov_const(film, layers[l].aov);
      if (!plane) continue;
      uint32_t k = tt_aov_channels(layers[l].aov);
      memcpy(px + c, plane + i * k, k * sizeof(float));
      c += k;
    }
  }
  return ch;
}

/* Writes EXR (RGB and the requested AOVs as layers) + PNG with the run's metadata. */
static int tt__write_images(tt__run_record *rec, tt_film *film, char *exr, char *png) {
  uint32_t w = tt_film_width(film), h = tt_film_height(film);
  float *rgb = malloc((size_t)w * h * 3 * sizeof(float));
  float *layers = tt_film_aov_mask(film) ? malloc((size_t)w * h * 12 * sizeof(float)) : NULL;
  if (!rgb || (tt_film_aov_mask(film) && !layers)) {
    tt__say("out of memory resolving the image\n");
    free(rgb);
    free(layers);
    return TT_EXIT_OUTPUT;
  }
  tt_film_resolve(film, rgb);
  const char *names[12];
  uint32_t channels = layers ? tt__exr_layers(film, rgb, layers, names) : 3;
  char spp[32], seed[32], ms[32], threads[32], plugins[512] = "";
  snprintf(spp, sizeof spp, "%u", rec->spp);
  snprintf(seed, sizeof seed, "%llu", (unsigned long long)rec->seed);
  snprintf(ms, sizeof ms, "%.3f", rec->render_ms);
  snprintf(threads, sizeof threads, "%u", rec->threads);
  for (size_t i = 0; i < tt_registry_count(rec->reg); i++) {
    const tt_plugin *e = tt_loaded_plugin_entry(tt_registry_get(rec->reg, i));
    size_t len = strlen(plugins);
    snprintf(plugins + len, sizeof plugins - len, "%s%s %s", i ? ", " : "", e->name, e->version);
  }
  tt_image_meta meta[] = {
      {"spp", spp},
      {"seed", seed},
      {"render_ms", ms},
      {"threads", threads},
      {"plugins", plugins},
      {"scene", tt_scene_source(rec->scene)},
      {"software", "tunetrace " TT_VERSION_STRING},
      /* what the AOV layers hold (film.h), for whoever reads them without our docs */
      {"tunetrace:aovs", "depth: view-axis distance; normal: world-space shading normal; "
                         "albedo: reflectance; motion: pixels to the previous frame; each the "
                         "mean over the pixel's samples of the first hit"},
  };
  size_t nmeta = sizeof meta / sizeof meta[0] - (layers ? 0 : 1);
  int rc = TT_EXIT_OK;
  if (tt_image_write_exr(exr, w, h, channels, layers ? layers : rgb, layers ? names : NULL, meta,
                         nmeta) != TT_OK) {
    tt__say("cannot write %s: %s\n", exr, tt_last_error());
    rc = TT_EXIT_OUTPUT;
  }
  if (tt_image_write_png_display(png, w, h, rgb, 0.0f, meta, nmeta) != TT_OK) {
    tt__say("cannot write %s: %s\n", png, tt_last_error());
    rc = TT_EXIT_OUTPUT;
  }
  free(rgb);
  free(layers);
  return rc;
}

/* A post-filter works on the frames of a sequence (temporal history, motion vectors); a
 * still render would write the image unfiltered, so loading one for a still is a usage
 * error, unless the filter is the tuning target (--tune NAME measures it on the film). */
static int tt__check_still_post(const tt__session *s) {
  for (size_t i = 0; i < tt_registry_count(s->reg); i++) {
    const tt_plugin *e = tt_loaded_plugin_entry(tt_registry_get(s->reg, i));
    if (e->kind != TT_KIND_POST || (s->opt->tune && !strcmp(s->opt->tune, e->name))) continue;
    tt__say("%s %s: a post-filter runs over the frames of a sequence, and this "
            "is a still render, which it would leave unfiltered; render frames with --frames "
            "A:B --out DIR/frame_%%04d.exr (or --sequence N --out-dir DIR), or tune the filter "
            "with --tune %s\n",
            s->opt->post && strstr(s->opt->post, e->name) ? "--post" : "--plugin", e->name,
            e->name);
    return TT_EXIT_USAGE;
  }
  return TT_EXIT_OK;
}

/* --frames A:B: one full render per frame f = A..B (the camera at t = f / fps, the frames of
 * a sequence), <stem>_NNNN.exr (and <stats stem>_NNNN.json); the scene is reloaded for each
 * frame. */
static int tt__render_frames(const tt__host_options *opt) {
  char stem[4096], name[4200], stats[4200];
  if (opt->out) snprintf(stem, sizeof stem, "%.*s", (int)(strlen(opt->out) - 4), opt->out);
  else {
    tt__default_out(opt->scene, stem, sizeof stem);
    stem[strlen(stem) - 4] = 0;
  }
  double fps = opt->fps > 0 ? opt->fps : 24.0;
  for (uint32_t f = opt->frames_first; f <= opt->frames_last; f++) {
    tt__host_options one = *opt;
    one.frames = 0;
    one.camera_time_set = 1;
    one.camera_time = f / fps;
    snprintf(name, sizeof name, "%s_%04u.exr", stem, f);
    one.out = name;
    if (opt->stats) {
      const char *dot = strrchr(opt->stats, '.');
      int len = dot && !strcmp(dot, ".json") ? (int)(dot - opt->stats) : (int)strlen(opt->stats);
      snprintf(stats, sizeof stats, "%.*s_%04u.json", len, opt->stats, f);
      one.stats = stats;
    }
    int frc = tt__run_render(&one);
    if (frc != TT_EXIT_OK) return frc;
  }
  return TT_EXIT_OK;
}

/* A still render: the host session, the tuning phase's record, the output files and the
 * limits of the progressive passes. tt__render_close frees what it holds at any stage. */
typedef struct tt__render_job {
  const tt__host_options *opt;
  tt__session s;
  tt__tuning *tuning; /* NULL when nothing was tuned or explored */
  char exr[4096], png[4096];
  uint32_t target_spp; /* UINT32_MAX: until the time budget */
  double budget_s;     /* 0: no time budget */
  uint64_t t0;         /* the time budget counts from the tuning phase's start */
} tt__render_job;

/* The output files: named, then checked before the render (not found unwritable after it). */
static int tt__render_outputs(tt__render_job *j) {
  const tt__host_options *opt = j->opt;
  if (opt->out) snprintf(j->exr, sizeof j->exr, "%s", opt->out);
  else tt__default_out(opt->scene, j->exr, sizeof j->exr);
  snprintf(j->png, sizeof j->png, "%.*s.png", (int)(strlen(j->exr) - 4), j->exr);
  const char *outputs[3] = {j->exr, j->png, opt->stats};
  for (int i = 0; i < 3; i++)
    if (outputs[i] && tt_file_check_writable(outputs[i]) != TT_OK) {
      tt__say("%s%s\n", i == 2 ? "--stats: " : "", tt_last_error());
      return TT_EXIT_OUTPUT;
    }
  return TT_EXIT_OK;
}

/* The passes' limits: --spp (else the scene's) and --time-budget (else the scene's); a time
 * budget alone renders until the budget, with --spp both limits apply. Logs the render. */
static void tt__render_limits(tt__render_job *j) {
  const tt__host_options *opt = j->opt;
  const tt_render_settings *settings = tt_scene_settings(j->s.scene);
  j->target_spp = opt->spp ? opt->spp : settings->spp;
  j->budget_s = opt->time_budget > 0 ? opt->time_budget : settings->time_budget_s;
  if (opt->time_budget > 0 && !opt->spp) j->target_spp = UINT32_MAX;
  if (opt->quiet) return;
  int until_budget = j->target_spp == UINT32_MAX;
  tt__say("%s: %llu triangles, %ux%u, %s%u spp, seed %llu, %u threads\n", opt->scene,
          (unsigned long long)tt_scene_triangle_count(j->s.scene), j->s.camera->width,
          j->s.camera->height, until_budget ? "time budget, up to " : "",
          until_budget ? 0 : j->target_spp, (unsigned long long)j->s.rec.seed, j->s.rec.threads);
}

/* Create: the outputs checked, the session opened (scene, plugins, configurations) and
 * started (accel, integrator, film). Prints what failed; an exit code. */
static int tt__render_create(tt__render_job *j, const tt__host_options *opt) {
  memset(j, 0, sizeof *j);
  j->opt = opt;
  int rc = tt__render_outputs(j);
  if (rc == TT_EXIT_OK) rc = tt__session_open(&j->s, opt);
  if (rc == TT_EXIT_OK) rc = tt__check_still_post(&j->s);
  if (rc != TT_EXIT_OK) return rc;
  tt_loaded_plugin *predictor = tt_registry_find_kind(j->s.reg, TT_KIND_PREDICTOR);
  if (predictor && !opt->quiet)
    j->s.host->log(TT_LOG_WARN, NULL,
                   "%s is loaded but not used: a predictor chooses the "
                   "configuration in the hybrid loop (--hybrid over the camera path, or "
                   "--predict)",
                   tt_loaded_plugin_entry(predictor)->name);
  tt__render_limits(j);
  return tt__session_start(&j->s, opt->aov_mask);
}

/* The tuning phase (when a tuner is loaded, or --tune/--explore): its passes go into the
 * film. Returns its exit code; the render goes on to write what it has unless that is a usage
 * error or the phase left no record. */
static int tt__render_tune(tt__render_job *j) {
  tt__run_record *rec = &j->s.rec;
  j->t0 = j->s.host->clock_ns();
  int rc = tt__tune_phase(&j->s, &j->tuning);
  rec->tuning = j->tuning;
  tt__session_sync(&j->s); /* the tuning passes and builds ran through the library */
  if (!j->tuning) return rc;
  if (j->tuning->interrupted) rec->interrupted = 1;
  /* the image holds the tuning passes; the database's answers rendered none, so their
   * samples are rendered here (with the kept configuration): with or without a database the
   * same command ends with at least as many samples */
  if (j->tuning->answered_spp && j->target_spp != UINT32_MAX) {
    uint64_t without_db = (uint64_t)rec->spp + j->tuning->answered_spp;
    if (without_db > j->target_spp)
      j->target_spp = without_db > UINT32_MAX - 1 ? UINT32_MAX - 1 : (uint32_t)without_db;
  }
  return rc;
}

/* One pass of 1 spp into the film. */
static tt_status tt__render_pass(tt__render_job *j) {
  tt_pass_stats ps;
  double ms = 0;
  return tt__session_render_pass(&j->s, 1, &ps, &ms);
}

/* Prints that a pass failed; TT_EXIT_FAILURE. */
static int tt__render_pass_failed(const tt__render_job *j) {
  tt__say("%s: pass %u failed: %s\n", tt_loaded_plugin_entry(j->s.integ_p)->name, j->s.rec.passes,
          tt_last_error());
  return TT_EXIT_FAILURE;
}

/* Step: one progressive pass, unless the target spp, the time budget or a stop request ends
 * the render (*more = 0; a stop marks the record interrupted). Returns an exit code. */
static int tt__render_step(tt__render_job *j, int *more) {
  tt__run_record *rec = &j->s.rec;
  const tt_host *host = j->s.host;
  *more = 0;
  if (rec->interrupted || rec->spp >= j->target_spp) return TT_EXIT_OK;
  if (j->budget_s > 0 && (host->clock_ns() - j->t0) * 1e-9 >= j->budget_s) return TT_EXIT_OK;
  tt_status st = host->should_stop() ? TT_ERR_INTERRUPTED : tt__render_pass(j);
  if (st == TT_ERR_INTERRUPTED) {
    rec->interrupted = 1;
    return TT_EXIT_OK;
  }
  if (st != TT_OK) return tt__render_pass_failed(j);
  double frac = j->target_spp == UINT32_MAX ? 0 : (double)rec->spp / j->target_spp;
  if (j->budget_s > 0) {
    double tf = (host->clock_ns() - j->t0) * 1e-9 / j->budget_s;
    if (tf > frac) frac = tf;
  }
  tt__progress_update("render", frac);
  *more = 1;
  return TT_EXIT_OK;
}

/* A signal before any pass was done (the scene loading, the accel building, the first pass
 * cut short) would leave nothing to write while exit 130 promises the image rendered so far:
 * one pass is completed with the stop held back (a second signal still exits). */
static int tt__render_first_pass(tt__render_job *j) {
  if (!j->s.rec.interrupted || j->s.rec.spp != 0) return TT_EXIT_OK;
  tt_default_host_hold_stop(1);
  tt_status st = tt__render_pass(j);
  tt_default_host_hold_stop(0);
  return st == TT_OK ? TT_EXIT_OK : tt__render_pass_failed(j);
}

/* Finish: writes what was rendered (images, --stats), even when interrupted or a later pass
 * failed; a second signal during the writes waits for them (signals.c). Returns `rc`, or the
 * first output failure, or TT_EXIT_INTERRUPTED. */
static int tt__render_finish(tt__render_job *j, int rc) {
  tt__run_record *rec = &j->s.rec;
  tt__progress_finish();
  if (rec->nonfinite) /* a warning: --quiet keeps it */
    tt__say("warning: %llu non-finite samples were dropped\n", (unsigned long long)rec->nonfinite);
  tt__outputs_begin();
  rec->out_exr = j->exr;
  rec->out_png = j->png;
  if (rec->spp > 0) {
    int wrc = tt__write_images(rec, j->s.film, j->exr, j->png);
    if (wrc != TT_EXIT_OK && rc == TT_EXIT_OK) rc = wrc;
    else if (!j->opt->quiet && wrc == TT_EXIT_OK)
      tt__say("wrote %s and %s (%u spp, %.1f ms, %.2f Mrays/s)\n", j->exr, j->png, rec->spp,
              rec->render_ms, rec->render_ms > 0 ? rec->rays / (rec->render_ms * 1e3) : 0.0);
  } else {
    tt__say("no pass completed: nothing to write\n");
  }
  if (j->opt->stats && tt__write_stats(j->opt->stats, rec) != TT_OK) {
    tt__say("cannot write %s: %s\n", j->opt->stats, tt_last_error());
    if (rc == TT_EXIT_OK) rc = TT_EXIT_OUTPUT;
  }
  tt__outputs_end();
  return rec->interrupted && rc == TT_EXIT_OK ? TT_EXIT_INTERRUPTED : rc;
}

/* Frees what the job holds, at any stage. */
static void tt__render_close(tt__render_job *j) {
  tt__tuning_free(j->tuning);
  tt__session_close(&j->s);
}

int tt__run_render(const tt__host_options *opt) {
  tt__install_signals("pass");
  /* a missing output folder is created now, not found missing after the render */
  if (opt->out && tt__ensure_parent_dir("--out", opt->out) != TT_EXIT_OK) return TT_EXIT_OUTPUT;
  if (opt->stats && tt__ensure_parent_dir("--stats", opt->stats) != TT_EXIT_OK)
    return TT_EXIT_OUTPUT;
  if (opt->frames) return tt__render_frames(opt);
  tt__render_job j;
  int rc = tt__render_create(&j, opt);
  if (rc == TT_EXIT_OK) rc = tt__render_tune(&j);
  /* a failed tuning phase that left its record still writes the image and --stats */
  if (rc == TT_EXIT_OK || (rc != TT_EXIT_USAGE && j.tuning)) {
    tt__progress_update("render", 0); /* "ETA ?" until the first pass has ended */
    for (int more = 1; rc == TT_EXIT_OK && more;) rc = tt__render_step(&j, &more);
    if (rc == TT_EXIT_OK) rc = tt__render_first_pass(&j);
    rc = tt__render_finish(&j, rc);
  }
  tt__render_close(&j);
  return rc;
}
