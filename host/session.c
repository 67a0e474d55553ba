/* host: the session (session.h) — scene, plugins, configurations, accel, integrator, film. */
#include "session.h"

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- plugins ---- */

tt_registry *tt__make_registry(const tt__host_options *opt, const tt_host *host) {
  tt_registry *reg = tt_registry_create(host);
  if (!reg) return NULL;
  for (int i = 0; i < opt->plugin_path_count; i++) tt_registry_add_dir(reg, opt->plugin_paths[i]);
  return reg;
}

/* Loads every --plugin and --post, reporting each failure, then the default accel and
 * integrator for kinds not named. Returns the number of failures. */
static int tt__load_plugins(tt_registry *reg, const tt__host_options *opt) {
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

void tt__session_plugin_names(const tt__session *s, char *buf, size_t n) {
  buf[0] = 0;
  for (size_t i = 0; i < tt_registry_count(s->reg); i++) {
    const tt_plugin *e = tt_loaded_plugin_entry(tt_registry_get(s->reg, i));
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

/* Builds one configuration per loaded plugin (registry order) from its defaults, the
 * scene's render settings (integrator maxDepth) and the --set options; reports every bad
 * --set and returns the number of errors. */
static int tt__build_configs(tt__session *s) {
  tt_registry *reg = s->reg;
  const tt__host_options *opt = s->opt;
  tt_config **configs = s->configs;
  int errors = 0;
  size_t count = tt_registry_count(reg);
  for (size_t i = 0; i < count; i++) {
    tt_loaded_plugin *p = tt_registry_get(reg, i);
    const tt_space *space = tt_loaded_plugin_space(p);
    configs[i] = space ? tt_config_create(space) : NULL;
    /* the scene's render.maxDepth is the integrator's default depth; --set overrides it */
    int d = space ? tt_space_find(space, "maxDepth") : -1;
    if (s->scene && d >= 0 && tt_loaded_plugin_entry(p)->kind == TT_KIND_INTEGRATOR &&
        tt_config_set_number(configs[i], (size_t)d, tt_scene_settings(s->scene)->max_depth) != TT_OK)
      fprintf(stderr, "host: warning: %s: render.maxDepth of the scene: %s\n",
              tt_loaded_plugin_entry(p)->name, tt_last_error());
  }
  for (int k = 0; k < opt->set_count; k++) {
    const char *arg = opt->sets[k];
    const char *dot = strchr(arg, '.'), *eq = strchr(arg, '=');
    char plugin[128], param[128];
    snprintf(plugin, sizeof plugin, "%.*s", (int)(dot - arg), arg);
    snprintf(param, sizeof param, "%.*s", (int)(eq - dot - 1), dot + 1);
    tt_loaded_plugin *p = tt_registry_find_name(reg, plugin);
    if (!p) {
      char names[512];
      tt__session_plugin_names(s, names, sizeof names);
      fprintf(stderr, "host: --set %s: no plugin \"%s\" is loaded (loaded: %s)\n", arg, plugin,
              names);
      errors++;
      continue;
    }
    size_t idx = tt__session_index_of(s, p);
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

size_t tt__session_index_of(const tt__session *s, const tt_loaded_plugin *p) {
  for (size_t i = 0; i < tt_registry_count(s->reg); i++)
    if (tt_registry_get(s->reg, i) == p) return i;
  return (size_t)-1;
}

tt_config *tt__session_config_of(tt__session *s, const tt_loaded_plugin *p) {
  size_t i = tt__session_index_of(s, p);
  return i == (size_t)-1 ? NULL : s->configs[i];
}

/* ---- the session ---- */

/* --camera-index I: the path sample I of TT_HOST_PATH_SAMPLES, t = first key + I/(N-1) of
 * the path's time range, becomes the scene's camera. */
static void tt__apply_camera_index(tt__session *s) {
  const tt__host_options *opt = s->opt;
  const tt_camera *c0 = tt_scene_camera(s->scene);
  double t = 0;
  if (c0->key_count > 0)
    t = c0->keys[0].time + (c0->keys[c0->key_count - 1].time - c0->keys[0].time) *
                               (double)opt->camera_index / (TT_HOST_PATH_SAMPLES - 1.0);
  else if (!opt->quiet)
    fprintf(stderr, "host: warning: --camera-index %u: the scene has no camera path; "
            "using its still camera\n", opt->camera_index);
  tt_camera cam;
  tt_scene_camera_at(s->scene, t, &cam);
  tt_scene_set_camera(s->scene, &cam);
}

int tt__session_open(tt__session *s, const tt__host_options *opt) {
  memset(s, 0, sizeof *s);
  s->opt = opt;
  s->host = tt__host_services(opt->quiet);
  if (opt->clock_cpu) tt__host_use_cpu_clock();
  if (opt->threads && tt_default_host_set_threads(opt->threads) != TT_OK) {
    fprintf(stderr, "host: --threads: %s\n", tt_last_error());
    return TT_EXIT_USAGE;
  }
  if (tt_scene_load(opt->scene, &s->scene) != TT_OK) {
    fprintf(stderr, "host: %s\n", tt_last_error());
    return TT_EXIT_SCENE;
  }
  if (opt->width && tt_scene_set_resolution(s->scene, opt->width, opt->height) != TT_OK) {
    fprintf(stderr, "host: --res: %s\n", tt_last_error());
    return TT_EXIT_USAGE;
  }
  if (opt->camera_index_set) tt__apply_camera_index(s);
  s->camera = tt_scene_camera(s->scene);
  s->reg = tt__make_registry(opt, s->host);
  if (!s->reg) return TT_EXIT_FAILURE;
  if (tt__load_plugins(s->reg, opt)) return TT_EXIT_PLUGIN;
  if (tt__build_configs(s)) return TT_EXIT_USAGE;
  s->accel_p = tt_registry_find_kind(s->reg, TT_KIND_ACCEL);
  s->integ_p = tt_registry_find_kind(s->reg, TT_KIND_INTEGRATOR);
  s->ai = tt_loaded_plugin_iface(s->accel_p);
  s->ii = tt_loaded_plugin_iface(s->integ_p);

  const tt_render_settings *settings = tt_scene_settings(s->scene);
  tt__run_record *rec = &s->rec;
  rec->opt = opt;
  rec->reg = s->reg;
  rec->scene = s->scene;
  for (size_t i = 0; i < tt_registry_count(s->reg); i++) rec->configs[i] = s->configs[i];
  rec->seed = opt->seed_set ? opt->seed : settings->seed;
  rec->threads = s->host->thread_count();
  rec->width = s->camera->width;
  rec->height = s->camera->height;
  rec->build.struct_size = sizeof rec->build;
  return TT_EXIT_OK;
}

int tt__session_start(tt__session *s, uint32_t aovs) {
  tt__run_record *rec = &s->rec;
  if (s->ai->build(s->scene, tt__session_config_of(s, s->accel_p), &s->accel, &rec->build) !=
      TT_OK) {
    s->accel = NULL;
    fprintf(stderr, "host: %s: build failed: %s\n", tt_loaded_plugin_entry(s->accel_p)->name,
            tt_last_error());
    return TT_EXIT_FAILURE;
  }
  rec->build_ms = rec->build.build_ms;
  if (s->ii->create(s->scene, tt__session_config_of(s, s->integ_p), &s->integrator) != TT_OK) {
    s->integrator = NULL;
    fprintf(stderr, "host: %s: %s\n", tt_loaded_plugin_entry(s->integ_p)->name, tt_last_error());
    return TT_EXIT_FAILURE;
  }
  s->film = tt_film_create(s->camera->width, s->camera->height, aovs);
  if (!s->film) {
    fprintf(stderr, "host: film: %s\n", tt_last_error());
    return TT_EXIT_FAILURE;
  }
  return TT_EXIT_OK;
}

tt_status tt__session_render_pass(tt__session *s, uint32_t spp, tt_pass_stats *ps, double *ms) {
  tt__run_record *rec = &s->rec;
  tt_render_ctx ctx;
  memset(&ctx, 0, sizeof ctx);
  ctx.struct_size = sizeof ctx;
  ctx.scene = s->scene;
  ctx.accel_iface = s->ai;
  ctx.accel = s->accel;
  ctx.film = s->film;
  ctx.camera = s->camera;
  ctx.seed = rec->seed;
  ctx.pass_index = s->pass;
  ctx.spp = spp;
  ctx.sample_offset = rec->spp;
  memset(ps, 0, sizeof *ps);
  ps->struct_size = sizeof *ps;
  uint64_t p0 = s->host->clock_ns();
  tt_status st = s->ii->render_pass(s->integrator, &ctx, ps);
  *ms = (s->host->clock_ns() - p0) * 1e-6;
  rec->render_ms += *ms;
  rec->rays += ps->rays;
  rec->samples += ps->samples;
  rec->nonfinite += ps->nonfinite;
  if (st != TT_OK) return st;
  s->pass++;
  rec->passes++;
  rec->spp += spp;
  rec->last_pass = *ps;
  for (uint32_t m = 0; m < ps->metric_count && m < TT_MAX_METRICS; m++)
    rec->metric_sums[m] += ps->metrics[m].value;
  return TT_OK;
}

tt_status tt__session_rebuild_accel(tt__session *s, const tt_config *cfg, double *build_ms) {
  /* the loop of Fig. 3.2: a new configuration means a new structure */
  s->ai->destroy(s->accel);
  s->accel = NULL;
  tt_accel_build_stats bs;
  memset(&bs, 0, sizeof bs);
  bs.struct_size = sizeof bs;
  uint64_t b0 = s->host->clock_ns();
  tt_status st = s->ai->build(s->scene, cfg, &s->accel, &bs);
  double wall = (s->host->clock_ns() - b0) * 1e-6;
  *build_ms = bs.build_ms > 0 ? bs.build_ms : wall;
  if (st == TT_OK) {
    s->rec.build = bs;
    s->rec.build_ms = *build_ms;
  } else {
    s->accel = NULL;
  }
  return st;
}

void tt__session_close(tt__session *s) {
  if (s->film) tt_film_destroy(s->film);
  if (s->integrator) s->ii->destroy(s->integrator);
  if (s->accel) s->ai->destroy(s->accel);
  for (int i = 0; i < TT_HOST_MAX_LIST; i++)
    if (s->configs[i]) tt_config_destroy(s->configs[i]);
  tt_registry_destroy(s->reg);
  tt_scene_destroy(s->scene);
  memset(s, 0, sizeof *s);
}
