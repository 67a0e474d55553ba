/* host: the jobs — list plugins, describe a plugin, render a scene. */
#include "host.h"

#include <cjson/cJSON.h>
#include <libgen.h>
#include <stddef.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- signals: the first SIGINT/SIGTERM asks for a clean stop, the second exits ---- */

static volatile sig_atomic_t tt__signals;

static void tt__on_signal(int sig) {
  if (tt__signals++) _exit(128 + sig);
  tt_default_host_request_stop();
  static const char msg[] = "\nhost: interrupted: finishing the current pass (again to abort)\n";
  ssize_t ignored = write(2, msg, sizeof msg - 1);
  (void)ignored;
}

static void tt__install_signals(void) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = tt__on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
}

/* ---- plugins ---- */

/* Creates a registry with the command line's search directories. */
tt_registry *tt__make_registry(const tt__host_options *opt, const tt_host *host) {
  tt_registry *reg = tt_registry_create(host);
  if (!reg) return NULL;
  for (int i = 0; i < opt->plugin_path_count; i++) tt_registry_add_dir(reg, opt->plugin_paths[i]);
  return reg;
}

int tt__load_plugins(tt_registry *reg, const tt__host_options *opt) {
  int failures = 0;
  for (int i = 0; i < opt->plugin_count; i++) {
    if (tt_registry_load(reg, opt->plugins[i], NULL) != TT_OK) {
      fprintf(stderr, "host: plugin \"%s\": %s\n", opt->plugins[i], tt_last_error());
      failures++;
    }
  }
  if (opt->post && !tt_registry_find_name(reg, opt->post) &&
      tt_registry_load(reg, opt->post, NULL) != TT_OK) {
    fprintf(stderr, "host: --post \"%s\": %s\n", opt->post, tt_last_error());
    failures++;
  }
  if (failures) return failures;
  static const struct { uint32_t kind; const char *name; } defaults[] = {
    {TT_KIND_ACCEL, "accel_embree"},
    {TT_KIND_INTEGRATOR, "integrator_pt"},
  };
  for (size_t i = 0; i < sizeof defaults / sizeof defaults[0]; i++) {
    if (tt_registry_find_kind(reg, defaults[i].kind)) continue;
    if (tt_registry_load(reg, defaults[i].name, NULL) != TT_OK) {
      fprintf(stderr, "host: default %s plugin \"%s\": %s\n",
              tt_plugin_kind_name(defaults[i].kind), defaults[i].name, tt_last_error());
      failures++;
    }
  }
  return failures;
}

/* Comma-separated names of the loaded plugins (for messages). */
static void tt__loaded_names(tt_registry *reg, char *buf, size_t n) {
  buf[0] = 0;
  for (size_t i = 0; i < tt_registry_count(reg); i++) {
    const tt_plugin *e = tt_loaded_plugin_entry(tt_registry_get(reg, i));
    size_t len = strlen(buf);
    snprintf(buf + len, n - len, "%s%s", i ? ", " : "", e->name);
  }
}

const tt_options_iface *tt__plugin_options(const tt_loaded_plugin *p) {
  const tt_options_iface *oi = tt_loaded_plugin_get(p, TT_OPTIONS_INTERFACE_ID);
  /* tables older than the fields we call are ignored (struct_size rule of the ABI) */
  if (!oi || oi->struct_size < offsetof(tt_options_iface, get) + sizeof oi->get || !oi->count ||
      !oi->info || !oi->set || !oi->get)
    return NULL;
  return oi;
}

int tt__build_configs(tt_registry *reg, const tt__host_options *opt, const tt_scene *scene,
                      tt_config **configs) {
  int errors = 0;
  size_t count = tt_registry_count(reg);
  for (size_t i = 0; i < count; i++) {
    tt_loaded_plugin *p = tt_registry_get(reg, i);
    const tt_space *space = tt_loaded_plugin_space(p);
    configs[i] = space ? tt_config_create(space) : NULL;
    /* the scene's render.maxDepth is the integrator's default depth; --set overrides it */
    int d = space ? tt_space_find(space, "maxDepth") : -1;
    if (scene && d >= 0 && tt_loaded_plugin_entry(p)->kind == TT_KIND_INTEGRATOR &&
        tt_config_set_number(configs[i], (size_t)d, tt_scene_settings(scene)->max_depth) != TT_OK)
      fprintf(stderr, "host: warning: %s: render.maxDepth of the scene: %s\n",
              tt_loaded_plugin_entry(p)->name, tt_last_error());
  }
  for (int s = 0; s < opt->set_count; s++) {
    const char *arg = opt->sets[s];
    const char *dot = strchr(arg, '.'), *eq = strchr(arg, '=');
    char plugin[128], param[128];
    snprintf(plugin, sizeof plugin, "%.*s", (int)(dot - arg), arg);
    snprintf(param, sizeof param, "%.*s", (int)(eq - dot - 1), dot + 1);
    tt_loaded_plugin *p = tt_registry_find_name(reg, plugin);
    if (!p) {
      char names[512];
      tt__loaded_names(reg, names, sizeof names);
      fprintf(stderr, "host: --set %s: no plugin \"%s\" is loaded (loaded: %s)\n", arg, plugin,
              names);
      errors++;
      continue;
    }
    size_t idx = 0;
    while (tt_registry_get(reg, idx) != p) idx++;
    /* a key that is no parameter may be an option (tt.options/1: files, names) */
    const tt_options_iface *oi = tt__plugin_options(p);
    int is_param = configs[idx] && tt_space_find(tt_config_space(configs[idx]), param) >= 0;
    if (!is_param && oi && oi->get(param)) {
      if (oi->set(param, eq + 1) != TT_OK) {
        fprintf(stderr, "host: --set %s: %s\n", arg, tt_last_error());
        errors++;
      }
      continue;
    }
    if (!configs[idx]) {
      fprintf(stderr, "host: --set %s: plugin \"%s\" has no parameters%s\n", arg, plugin,
              oi ? " and no such option" : "");
      errors++;
      continue;
    }
    if (tt_config_set_string(configs[idx], param, eq + 1) != TT_OK) {
      char hint[256] = "";
      for (uint32_t o = 0; oi && !is_param && o < oi->count(); o++) {
        const tt_option_info *info = oi->info(o);
        size_t len = strlen(hint);
        if (info && info->key)
          snprintf(hint + len, sizeof hint - len, "%s%s", o ? ", " : "; options: ", info->key);
      }
      fprintf(stderr, "host: --set %s: %s%s\n", arg, tt_last_error(), hint);
      errors++;
    }
  }
  for (size_t i = 0; i < count && !errors; i++) {
    if (!configs[i]) continue;
    char why[512] = "";
    tt_check_result r = tt_space_check(tt_config_space(configs[i]), configs[i], why, sizeof why);
    const char *name = tt_loaded_plugin_entry(tt_registry_get(reg, i))->name;
    if (r == TT_CHECK_REPAIRED) {
      fprintf(stderr, "host: warning: %s: configuration repaired: %s\n", name, why);
    } else if (r == TT_CHECK_INFEASIBLE) {
      fprintf(stderr, "host: %s: infeasible configuration: %s\n", name, why);
      errors++;
    }
  }
  return errors;
}

/* Config of the loaded plugin `p` (same index order as the registry). */
static const tt_config *tt__config_of(tt_registry *reg, tt_config **configs,
                                      const tt_loaded_plugin *p) {
  for (size_t i = 0; i < tt_registry_count(reg); i++)
    if (tt_registry_get(reg, i) == p) return configs[i];
  return NULL;
}

/* ---- --list-plugins ---- */

typedef struct tt__list_ctx {
  tt_registry *reg;
  int found, rejected;
} tt__list_ctx;

static void tt__list_one(void *user, const char *path) {
  tt__list_ctx *ctx = user;
  tt_plugin e;
  if (tt_registry_probe(ctx->reg, path, &e) == TT_OK) {
    printf("%-22s %-10s %-8s %s\n    %s\n", e.name, tt_plugin_kind_name(e.kind), e.version,
           path, e.description ? e.description : "");
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
    fprintf(stderr, "host: %d plugin(s), %d rejected; search path: %s\n", ctx.found,
            ctx.rejected, tt_registry_search_path(reg));
  tt_registry_destroy(reg);
  /* everything is listed first; a rejected file is then a plugin error like --plugin's */
  return ctx.rejected ? TT_EXIT_PLUGIN : TT_EXIT_OK;
}

/* ---- --describe ---- */

int tt__run_describe(const tt__host_options *opt) {
  tt_registry *reg = tt__make_registry(opt, tt__host_services(1));
  if (!reg) return TT_EXIT_FAILURE;
  tt_loaded_plugin *p = NULL;
  if (tt_registry_load(reg, opt->describe, &p) != TT_OK) {
    fprintf(stderr, "host: --describe \"%s\": %s\n", opt->describe, tt_last_error());
    tt_registry_destroy(reg);
    return TT_EXIT_PLUGIN;
  }
  const tt_plugin *e = tt_loaded_plugin_entry(p);
  const tt_space *space = tt_loaded_plugin_space(p);
  char *json = space ? tt_space_to_json(space) : NULL;
  cJSON *root = json ? cJSON_Parse(json) : cJSON_CreateObject();
  tt_free(json);
  if (!root) {
    fprintf(stderr, "host: --describe %s: %s\n", e->name,
            space ? tt_last_error() : "out of memory");
    tt_registry_destroy(reg);
    return TT_EXIT_FAILURE;
  }
  if (!space) {
    cJSON_AddStringToObject(root, "plugin", e->name);
    cJSON_AddStringToObject(root, "version", e->version);
    cJSON_AddItemToObject(root, "parameters", cJSON_CreateArray());
    cJSON_AddItemToObject(root, "constraints", cJSON_CreateArray());
  }
  /* options (tt.options/1): set with --set NAME.KEY=VALUE like parameters, never tuned */
  cJSON *opts = cJSON_AddArrayToObject(root, "options");
  const tt_options_iface *oi = tt__plugin_options(p);
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
  char *out = cJSON_Print(root);
  cJSON_Delete(root);
  if (out) printf("%s\n", out);
  free(out);
  tt_registry_destroy(reg);
  return TT_EXIT_OK;
}

/* ---- render ---- */

tt_status tt__render_pass(tt__render_state *rs, uint32_t spp, tt_pass_stats *ps, double *ms) {
  tt__run_record *rec = rs->rec;
  tt_render_ctx ctx;
  memset(&ctx, 0, sizeof ctx);
  ctx.struct_size = sizeof ctx;
  ctx.scene = rs->scene;
  ctx.accel_iface = rs->ai;
  ctx.accel = rs->accel;
  ctx.film = rs->film;
  ctx.camera = rs->camera;
  ctx.seed = rec->seed;
  ctx.pass_index = rs->pass;
  ctx.spp = spp;
  ctx.sample_offset = rec->spp;
  memset(ps, 0, sizeof *ps);
  ps->struct_size = sizeof *ps;
  uint64_t p0 = rs->host->clock_ns();
  tt_status st = rs->ii->render_pass(rs->integrator, &ctx, ps);
  *ms = (rs->host->clock_ns() - p0) * 1e-6;
  rec->render_ms += *ms;
  rec->rays += ps->rays;
  rec->samples += ps->samples;
  rec->nonfinite += ps->nonfinite;
  if (st != TT_OK) return st;
  rs->pass++;
  rec->passes++;
  rec->spp += spp;
  rec->last_pass = *ps;
  for (uint32_t m = 0; m < ps->metric_count && m < TT_MAX_METRICS; m++)
    rec->metric_sums[m] += ps->metrics[m].value;
  return TT_OK;
}

/* Default output: <scene folder>.exr for ".../NAME/scene.json", else <file stem>.exr. */
static void tt__default_out(const char *scene, char *buf, size_t n) {
  char tmp[4096];
  snprintf(tmp, sizeof tmp, "%s", scene);
  char *base = basename(tmp);
  if (!strcmp(base, "scene.json")) {
    char tmp2[4096];
    snprintf(tmp2, sizeof tmp2, "%s", scene);
    char *dir = dirname(tmp2);
    char tmp3[4096];
    snprintf(tmp3, sizeof tmp3, "%s", dir);
    snprintf(buf, n, "%s.exr", basename(tmp3));
  } else {
    char *dot = strrchr(base, '.');
    if (dot) *dot = 0;
    snprintf(buf, n, "%s.exr", base);
  }
}

/* Writes EXR + PNG with the run's metadata. */
static int tt__write_images(tt__run_record *rec, tt_film *film, char *exr, char *png) {
  uint32_t w = tt_film_width(film), h = tt_film_height(film);
  float *rgb = malloc((size_t)w * h * 3 * sizeof(float));
  if (!rgb) {
    fprintf(stderr, "host: out of memory resolving the image\n");
    return TT_EXIT_OUTPUT;
  }
  tt_film_resolve(film, rgb);
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
    {"spp", spp}, {"seed", seed}, {"render_ms", ms}, {"threads", threads},
    {"plugins", plugins}, {"scene", tt_scene_source(rec->scene)},
    {"software", "tunetrace " TT_VERSION_STRING},
  };
  size_t nmeta = sizeof meta / sizeof meta[0];
  int rc = TT_EXIT_OK;
  if (tt_image_write_exr(exr, w, h, 3, rgb, NULL, meta, nmeta) != TT_OK) {
    fprintf(stderr, "host: cannot write %s: %s\n", exr, tt_last_error());
    rc = TT_EXIT_OUTPUT;
  }
  if (tt_image_write_png_display(png, w, h, rgb, 0.0f, meta, nmeta) != TT_OK) {
    fprintf(stderr, "host: cannot write %s: %s\n", png, tt_last_error());
    rc = TT_EXIT_OUTPUT;
  }
  free(rgb);
  return rc;
}

int tt__run_render(const tt__host_options *opt) {
  if (opt->frames) {
    /* --frames A:B: one full render per camera path sample, <stem>_NNNN.exr (and
     * <stats stem>_NNNN.json); the scene is reloaded for each sample */
    char stem[4096], name[4200], stats[4200];
    if (opt->out) snprintf(stem, sizeof stem, "%.*s", (int)(strlen(opt->out) - 4), opt->out);
    else {
      tt__default_out(opt->scene, stem, sizeof stem);
      stem[strlen(stem) - 4] = 0;
    }
    for (uint32_t f = opt->frames_first; f < opt->frames_end; f++) {
      tt__host_options one = *opt;
      one.frames = 0;
      one.camera_index_set = 1;
      one.camera_index = f;
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
  const tt_host *host = tt__host_services(opt->quiet);
  if (opt->clock_cpu) tt__host_use_cpu_clock();
  if (opt->threads && tt_default_host_set_threads(opt->threads) != TT_OK) {
    fprintf(stderr, "host: --threads: %s\n", tt_last_error());
    return TT_EXIT_USAGE;
  }
  tt__install_signals();

  tt_scene *scene = NULL;
  if (tt_scene_load(opt->scene, &scene) != TT_OK) {
    fprintf(stderr, "host: %s\n", tt_last_error());
    return TT_EXIT_SCENE;
  }
  if (opt->width && tt_scene_set_resolution(scene, opt->width, opt->height) != TT_OK) {
    fprintf(stderr, "host: --res: %s\n", tt_last_error());
    tt_scene_destroy(scene);
    return TT_EXIT_USAGE;
  }
  if (opt->camera_index_set) {
    /* path sample I of TT_HOST_PATH_SAMPLES: t = first key + I/(N-1) of the time range */
    const tt_camera *c0 = tt_scene_camera(scene);
    double t = 0;
    if (c0->key_count > 0)
      t = c0->keys[0].time + (c0->keys[c0->key_count - 1].time - c0->keys[0].time) *
                                 (double)opt->camera_index / (TT_HOST_PATH_SAMPLES - 1.0);
    else if (!opt->quiet)
      fprintf(stderr, "host: warning: --camera-index %u: the scene has no camera path; "
              "using its still camera\n", opt->camera_index);
    tt_camera cam;
    tt_scene_camera_at(scene, t, &cam);
    tt_scene_set_camera(scene, &cam);
  }

  int rc = TT_EXIT_OK;
  tt_registry *reg = tt__make_registry(opt, host);
  tt_config *configs[TT_HOST_MAX_LIST] = {0};
  tt_accel *accel = NULL;
  tt_integrator *integrator = NULL;
  tt_film *film = NULL;
  tt_loaded_plugin *accel_p = NULL, *integ_p = NULL;
  tt__tuning *tuning = NULL;
  const tt_accel_iface *ai = NULL;
  const tt_integrator_iface *ii = NULL;
  if (!reg) {
    tt_scene_destroy(scene);
    return TT_EXIT_FAILURE;
  }
  if (tt__load_plugins(reg, opt)) {
    rc = TT_EXIT_PLUGIN;
    goto done;
  }
  if (tt__build_configs(reg, opt, scene, configs)) {
    rc = TT_EXIT_USAGE;
    goto done;
  }

  accel_p = tt_registry_find_kind(reg, TT_KIND_ACCEL);
  integ_p = tt_registry_find_kind(reg, TT_KIND_INTEGRATOR);
  ai = tt_loaded_plugin_iface(accel_p);
  ii = tt_loaded_plugin_iface(integ_p);
  const tt_render_settings *settings = tt_scene_settings(scene);
  const tt_camera *camera = tt_scene_camera(scene);

  tt__run_record rec;
  memset(&rec, 0, sizeof rec);
  rec.opt = opt;
  rec.reg = reg;
  rec.scene = scene;
  for (size_t i = 0; i < tt_registry_count(reg); i++) rec.configs[i] = configs[i];
  rec.seed = opt->seed_set ? opt->seed : settings->seed;
  rec.threads = host->thread_count();
  rec.width = camera->width;
  rec.height = camera->height;
  uint32_t target_spp = opt->spp ? opt->spp : settings->spp;
  double budget_s = opt->time_budget > 0 ? opt->time_budget : settings->time_budget_s;
  /* a time budget alone renders until the budget; with --spp both limits apply */
  if (opt->time_budget > 0 && !opt->spp) target_spp = UINT32_MAX;

  if (!opt->quiet)
    fprintf(stderr, "host: %s: %llu triangles, %ux%u, %s%u spp, seed %llu, %u threads\n",
            opt->scene, (unsigned long long)tt_scene_triangle_count(scene), camera->width,
            camera->height, target_spp == UINT32_MAX ? "time budget, up to " : "",
            target_spp == UINT32_MAX ? 0 : target_spp, (unsigned long long)rec.seed,
            rec.threads);

  rec.build.struct_size = sizeof rec.build;
  if (ai->build(scene, tt__config_of(reg, configs, accel_p), &accel, &rec.build) != TT_OK) {
    fprintf(stderr, "host: %s: build failed: %s\n", tt_loaded_plugin_entry(accel_p)->name,
            tt_last_error());
    rc = TT_EXIT_FAILURE;
    goto done;
  }
  rec.build_ms = rec.build.build_ms;
  if (ii->create(scene, tt__config_of(reg, configs, integ_p), &integrator) != TT_OK) {
    fprintf(stderr, "host: %s: %s\n", tt_loaded_plugin_entry(integ_p)->name, tt_last_error());
    rc = TT_EXIT_FAILURE;
    goto done;
  }
  film = tt_film_create(camera->width, camera->height, 0);
  if (!film) {
    fprintf(stderr, "host: film: %s\n", tt_last_error());
    rc = TT_EXIT_FAILURE;
    goto done;
  }

  /* tuning phase (when a tuner is loaded, or --tune/--explore): its passes go into the film */
  tt__render_state rs;
  memset(&rs, 0, sizeof rs);
  rs.opt = opt;
  rs.host = host;
  rs.rec = &rec;
  rs.scene = scene;
  rs.camera = camera;
  rs.reg = reg;
  rs.configs = configs;
  rs.accel_p = accel_p;
  rs.integ_p = integ_p;
  rs.ai = ai;
  rs.ii = ii;
  rs.accel = accel;
  rs.integrator = integrator;
  rs.film = film;
  uint64_t t0 = host->clock_ns();
  int trc = tt__tune_phase(&rs, &tuning);
  accel = rs.accel;
  rec.tuning = tuning;
  if (trc != TT_EXIT_OK) {
    rc = trc;
    if (rc == TT_EXIT_USAGE || !tuning) goto done;
  }
  if (tuning && tuning->interrupted) rec.interrupted = 1;

  /* progressive passes of 1 spp each, until the target or the time budget */
  while (rc == TT_EXIT_OK && !rec.interrupted && rec.spp < target_spp) {
    double elapsed = (host->clock_ns() - t0) * 1e-9;
    if (budget_s > 0 && elapsed >= budget_s) break;
    if (host->should_stop()) {
      rec.interrupted = 1;
      break;
    }
    tt_pass_stats ps;
    double ms = 0;
    tt_status st = tt__render_pass(&rs, 1, &ps, &ms);
    if (st == TT_ERR_INTERRUPTED) {
      rec.interrupted = 1;
      break;
    }
    if (st != TT_OK) {
      fprintf(stderr, "host: %s: pass %u failed: %s\n", tt_loaded_plugin_entry(integ_p)->name,
              rs.pass, tt_last_error());
      rc = TT_EXIT_FAILURE;
      break;
    }
    double frac = target_spp == UINT32_MAX ? 0 : (double)rec.spp / target_spp;
    if (budget_s > 0) {
      double tf = (host->clock_ns() - t0) * 1e-9 / budget_s;
      if (tf > frac) frac = tf;
    }
    tt__progress_update("render", frac);
  }
  tt__progress_finish();
  if (rec.nonfinite && !opt->quiet)
    fprintf(stderr, "host: warning: %llu non-finite samples were dropped\n",
            (unsigned long long)rec.nonfinite);

  /* write what was rendered, even when interrupted or a later pass failed */
  char exr[4096], png[4096];
  if (opt->out) snprintf(exr, sizeof exr, "%s", opt->out);
  else tt__default_out(opt->scene, exr, sizeof exr);
  snprintf(png, sizeof png, "%.*s.png", (int)(strlen(exr) - 4), exr);
  rec.out_exr = exr;
  rec.out_png = png;
  if (rec.spp > 0) {
    int wrc = tt__write_images(&rec, film, exr, png);
    if (wrc != TT_EXIT_OK && rc == TT_EXIT_OK) rc = wrc;
    else if (!opt->quiet && wrc == TT_EXIT_OK)
      fprintf(stderr, "host: wrote %s and %s (%u spp, %.1f ms, %.2f Mrays/s)\n", exr, png,
              rec.spp, rec.render_ms,
              rec.render_ms > 0 ? rec.rays / (rec.render_ms * 1e3) : 0.0);
  } else {
    fprintf(stderr, "host: no pass completed: nothing to write\n");
  }
  if (opt->stats && tt__write_stats(opt->stats, &rec) != TT_OK) {
    fprintf(stderr, "host: cannot write %s: %s\n", opt->stats, tt_last_error());
    if (rc == TT_EXIT_OK) rc = TT_EXIT_OUTPUT;
  }
  if (rec.interrupted && rc == TT_EXIT_OK) rc = TT_EXIT_INTERRUPTED;

done:
  if (film) tt_film_destroy(film);
  if (integrator) ii->destroy(integrator);
  if (accel) ai->destroy(accel);
  for (int i = 0; i < TT_HOST_MAX_LIST; i++)
    if (configs[i]) tt_config_destroy(configs[i]);
  tt__tuning_free(tuning);
  tt_registry_destroy(reg);
  tt_scene_destroy(scene);
  return rc;
}
