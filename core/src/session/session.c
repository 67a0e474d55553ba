/* The render session (tunetrace/session.h): scene, plugins and their configurations, accel,
 * integrator, film; progressive passes and their statistics. */
#include "session/session_internal.h"

#include <tunetrace/suggest.h>
#include <tt_util/strings.h>

#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

tt_status tt__session_error(tt_status status, const char *fmt, ...) {
  char cause[2048], prefix[1024];
  snprintf(cause, sizeof cause, "%s", tt_last_error());
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(prefix, sizeof prefix, fmt, ap);
  va_end(ap);
  return tt_set_error(status, "%s%s", prefix, cause);
}

/* ---- set-up ---- */

tt_status tt_session_create(const tt_host *host, tt_session **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_create: out is NULL");
  *out = NULL;
  tt_session *s = calloc(1, sizeof *s);
  if (!s) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory creating a session");
  s->host = host ? host : tt_default_host();
  s->reg = tt_registry_create(s->host);
  if (!s->reg) {
    free(s);
    return TT_ERR_OUT_OF_MEMORY;
  }
  s->stats.struct_size = sizeof s->stats;
  s->stats.build.struct_size = sizeof s->stats.build;
  *out = s;
  return TT_OK;
}

void tt_session_destroy(tt_session *s) {
  if (!s) return;
  if (s->post) s->pi->destroy(s->post);
  free(s->post_in);
  free(s->post_out);
  free(s->snap);
  free(s->pass_rgb);
  free(s->state_camera);
  free(s->state_context);
  tt_film_destroy(s->film);
  if (s->integrator) s->ii->destroy(s->integrator);
  if (s->accel) s->ai->destroy(s->accel);
  for (size_t i = 0; i < s->config_cap; i++)
    if (s->configs[i]) tt_config_destroy(s->configs[i]);
  free(s->configs);
  free(s->depth_set);
  for (size_t i = 0; i < s->setting_count; i++) {
    free(s->settings[i].key);
    free(s->settings[i].value);
  }
  free(s->settings);
  tt_registry_destroy(s->reg);
  tt_scene_destroy(s->scene);
  free(s);
}

tt_status tt_session_add_plugin_dir(tt_session *s, const char *dir) {
  if (!s || !dir) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_add_plugin_dir: NULL");
  return tt_registry_add_dir(s->reg, dir);
}

/* Sets the scene's render.maxDepth as the default depth of an integrator's configuration
 * (unless maxDepth was set explicitly). A depth beyond the integrator's range (pbrt's
 * maxdepth 65 of living-room, range [0, 64]) is clamped to it with a warning: falling back to
 * the plugin's default depth would render a far darker image than the scene asks for. */
static void tt__apply_scene_depth(tt_session *s, size_t i) {
  tt_loaded_plugin *p = tt_registry_get(s->reg, i);
  tt_config *cfg = s->configs[i];
  if (!s->scene || !cfg || s->depth_set[i] || tt_loaded_plugin_entry(p)->kind != TT_KIND_INTEGRATOR)
    return;
  const tt_space *space = tt_config_space(cfg);
  int d = tt_space_find(space, "maxDepth");
  if (d < 0) return;
  double want = tt_scene_settings(s->scene)->max_depth, lo = tt_space_min(space, (size_t)d),
         hi = tt_space_max(space, (size_t)d);
  double depth = want < lo ? lo : want > hi ? hi : want;
  const char *name = tt_loaded_plugin_entry(p)->name;
  if (depth != want)
    tt_host_log(s->host, TT_LOG_WARN, NULL,
                "%s: the scene asks for maxDepth %g (render.maxDepth, "
                "pbrt's maxdepth); the plugin supports [%g, %g]: clamped to %g",
                name, want, lo, hi, depth);
  if (tt_config_set_number(cfg, (size_t)d, depth) != TT_OK)
    tt_host_log(s->host, TT_LOG_WARN, NULL, "%s: render.maxDepth of the scene: %s", name,
                tt_last_error());
}

tt_status tt_session_load_scene(tt_session *s, const char *path) {
  return tt_session_load_scene_ex(s, path, TT_SCENE_LOAD_DEFAULT);
}

tt_status tt_session_load_scene_ex(tt_session *s, const char *path, uint32_t flags) {
  if (!s || !path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_load_scene: NULL");
  if (s->scene)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "%s: the session already has a scene (%s); "
                        "one scene per session",
                        path, tt_scene_source(s->scene));
  tt_status st = tt_scene_load_ex(path, flags, &s->scene);
  if (st != TT_OK) {
    s->scene = NULL;
    return st;
  }
  if (!s->seed_set) s->stats.seed = tt_scene_settings(s->scene)->seed;
  for (size_t i = 0; i < tt_registry_count(s->reg); i++) tt__apply_scene_depth(s, i);
  return TT_OK;
}

tt_scene *tt_session_scene(tt_session *s) { return s ? s->scene : NULL; }

const tt_camera *tt_session_camera(const tt_session *s) {
  return s && s->scene ? tt_scene_camera(s->scene) : NULL;
}

tt_status tt_session_set_camera_time(tt_session *s, double t, double frame_interval) {
  if (!s || !s->scene) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "camera time: no scene loaded");
  const tt_camera *c0 = tt_scene_camera(s->scene);
  if (c0->key_count == 0) {
    /* a still camera: no motion, unless objects move (the previous frame is the same view) */
    s->has_prev = tt_scene_animated(s->scene) && frame_interval > 0;
    if (s->has_prev) s->prev_camera = *c0;
    return TT_OK;
  }
  tt_camera cam;
  tt_scene_camera_at(s->scene, t, &cam);
  /* a started session moves along the path (the hybrid loop's states), but its film keeps
   * its size */
  if (s->started && s->film &&
      (cam.width != tt_film_width(s->film) || cam.height != tt_film_height(s->film)))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "camera time: the path's camera at %g s is "
                        "%ux%u, the started session's film %ux%u",
                        t, cam.width, cam.height, tt_film_width(s->film), tt_film_height(s->film));
  tt_scene_camera_at(s->scene, t - frame_interval, &s->prev_camera);
  s->prev_camera.width = cam.width;
  s->prev_camera.height = cam.height;
  s->has_prev = frame_interval > 0;
  tt_scene_set_camera(s->scene, &cam);
  return TT_OK;
}

/* Non-zero when an area light's mesh moves: the path tracer's light distribution (areas,
 * triangle CDFs) was computed from the positions at create. */
static int tt__lights_move(const tt_scene *scene) {
  for (uint32_t i = 0; i < tt_scene_mesh_count(scene); i++) {
    const tt_mesh *m = tt_scene_mesh(scene, i);
    if (m->light >= 0 && m->motion != TT_MESH_STATIC) return 1;
  }
  return 0;
}

/* Brings the started session's accel up to date after the scene moved. */
static tt_status tt__update_accel(tt_session *s, const tt_config *config,
                                  tt_accel_update_stats *out) {
  tt_accel_update_stats u;
  memset(&u, 0, sizeof u);
  u.struct_size = sizeof u;
  tt_status st;
  if (!config && s->accel && TT_HAS_FIELD(tt_accel_iface, s->ai, update) && s->ai->update) {
    st = s->ai->update(s->accel, &u);
    if (st != TT_OK) {
      s->ai->destroy(s->accel);
      s->accel = NULL;
      return tt__session_error(st, "%s: update failed: ", tt_loaded_plugin_entry(s->accel_p)->name);
    }
  } else { /* a new configuration, an ABI 1.1 accel, or one left without a structure: build
            * from scratch */
    double ms = 0;
    uint64_t t0 = s->host->clock_ns();
    st = tt_session_rebuild_accel(s, config, &ms);
    if (st != TT_OK) return st;
    u.update_ms = (s->host->clock_ns() - t0) * 1e-6;
    u.rebuilt = 1;
    u.sah_cost = s->stats.build.sah_cost;
  }
  if (out && out->struct_size > sizeof out->struct_size) {
    uint32_t size = out->struct_size;
    memcpy(out, &u, size < sizeof u ? size : sizeof u);
    out->struct_size = size;
  }
  return TT_OK;
}

tt_status tt_session_set_time(tt_session *s, double t, double frame_interval,
                              tt_accel_update_stats *stats) {
  return tt_session_set_time_config(s, t, frame_interval, NULL, stats);
}

tt_status tt_session_set_time_config(tt_session *s, double t, double frame_interval,
                                     const tt_config *accel_config, tt_accel_update_stats *stats) {
  if (stats && stats->struct_size > sizeof stats->struct_size) {
    uint32_t size = stats->struct_size;
    memset(stats, 0, size < sizeof *stats ? size : sizeof *stats);
    stats->struct_size = size;
  }
  if (!s || !s->scene) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "set time: no scene loaded");
  if (!isfinite(t) || !isfinite(frame_interval) || frame_interval < 0)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "set time: t = %g and frame interval %g "
                        "must be finite (the interval >= 0)",
                        t, frame_interval);
  tt_status st = tt_session_set_camera_time(s, t, frame_interval);
  if (st != TT_OK || !tt_scene_animated(s->scene)) return st;
  if ((st = tt_scene_set_time(s->scene, t, t - frame_interval)) != TT_OK) return st;
  if (!s->started) return TT_OK; /* tt_session_start builds over this pose */
  if ((st = tt__update_accel(s, accel_config, stats)) != TT_OK) return st;
  if (tt__lights_move(s->scene)) {
    s->ii->destroy(s->integrator);
    s->integrator = NULL;
    const tt_config *icfg = tt_session_config(s, tt_loaded_plugin_entry(s->integ_p)->name);
    st = s->ii->create(s->scene, icfg, &s->integrator);
    if (st != TT_OK) {
      s->integrator = NULL;
      return tt__session_error(st, "%s: ", tt_loaded_plugin_entry(s->integ_p)->name);
    }
  }
  return TT_OK;
}

/* Grows the per-plugin arrays to `n` slots (zeroed). */
static int tt__grow(tt_session *s, size_t n) {
  if (n <= s->config_cap) return 0;
  size_t cap = s->config_cap ? s->config_cap * 2 : 8;
  while (cap < n) cap *= 2;
  tt_config **c = realloc(s->configs, cap * sizeof *c);
  if (!c) return -1;
  s->configs = c;
  unsigned char *d = realloc(s->depth_set, cap);
  if (!d) return -1;
  s->depth_set = d;
  memset(s->configs + s->config_cap, 0, (cap - s->config_cap) * sizeof *c);
  memset(s->depth_set + s->config_cap, 0, cap - s->config_cap);
  s->config_cap = cap;
  return 0;
}

tt_status tt_session_load_plugin(tt_session *s, const char *name_or_path, tt_loaded_plugin **out) {
  if (out) *out = NULL;
  if (!s || !name_or_path)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_load_plugin: NULL");
  if (s->started)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "plugin \"%s\": load plugins before the "
                        "session starts",
                        name_or_path);
  if (tt__grow(s, tt_registry_count(s->reg) + 1))
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory loading a plugin");
  tt_loaded_plugin *p = NULL;
  tt_status st = tt_registry_load(s->reg, name_or_path, &p);
  if (st != TT_OK) return st;
  size_t i = tt_registry_count(s->reg) - 1;
  const tt_space *space = tt_loaded_plugin_space(p);
  if (space && !(s->configs[i] = tt_config_create(space)))
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory for a configuration");
  tt__apply_scene_depth(s, i);
  if (out) *out = p;
  return TT_OK;
}

const char *tt_session_default_plugin(uint32_t kind) {
  switch (kind) {
  case TT_KIND_ACCEL: return "accel_embree";
  case TT_KIND_INTEGRATOR: return "integrator_pt";
  }
  return NULL;
}

tt_status tt_session_load_defaults(tt_session *s) {
  if (!s) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_load_defaults: NULL");
  static const uint32_t kinds[] = {TT_KIND_ACCEL, TT_KIND_INTEGRATOR};
  tt_status first = TT_OK;
  char all[4096] = "";
  for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++) {
    if (tt_registry_find_kind(s->reg, kinds[k])) continue;
    const char *name = tt_session_default_plugin(kinds[k]);
    tt_status st = tt_session_load_plugin(s, name, NULL);
    if (st == TT_OK) continue;
    size_t len = strlen(all);
    snprintf(all + len, sizeof all - len, "%sdefault %s plugin \"%s\": %s", len ? "; " : "",
             tt_plugin_kind_name(kinds[k]), name, tt_last_error());
    if (first == TT_OK) first = st;
  }
  /* every failure in one message: the user fixes them all at once */
  return first == TT_OK ? TT_OK : tt_set_error(first, "%s", all);
}

tt_registry *tt_session_registry(tt_session *s) { return s ? s->reg : NULL; }

int tt_session_plugin_index(const tt_session *s, const char *name) {
  if (!s || !name) return -1;
  for (size_t i = 0; i < tt_registry_count(s->reg); i++)
    if (!strcmp(tt_loaded_plugin_entry(tt_registry_get(s->reg, i))->name, name)) return (int)i;
  return -1;
}

tt_config *tt_session_config_at(tt_session *s, size_t index) {
  return s && index < tt_registry_count(s->reg) ? s->configs[index] : NULL;
}

tt_config *tt_session_config(tt_session *s, const char *plugin) {
  int i = tt_session_plugin_index(s, plugin);
  return i < 0 ? NULL : s->configs[i];
}

const tt_options_iface *tt_session_plugin_options(const tt_loaded_plugin *p) {
  const tt_options_iface *oi = p ? tt_loaded_plugin_get(p, TT_OPTIONS_INTERFACE_ID) : NULL;
  /* tables older than the fields we call are ignored (struct_size rule of the ABI) */
  if (!oi || !TT_HAS_FIELD(tt_options_iface, oi, get) || !oi->count || !oi->info || !oi->set ||
      !oi->get)
    return NULL;
  return oi;
}

/* Comma-separated names of the loaded plugins, for messages. */
static void tt__plugin_names(const tt_session *s, char *buf, size_t n) {
  buf[0] = 0;
  for (size_t i = 0; i < tt_registry_count(s->reg); i++) {
    const tt_plugin *e = tt_loaded_plugin_entry(tt_registry_get(s->reg, i));
    size_t len = strlen(buf);
    snprintf(buf + len, n - len, "%s%s", i ? ", " : "", e->name);
  }
}

/* Records a value tt_session_set accepted (the tuning plan re-applies the user's settings);
 * TT_ERR_OUT_OF_MEMORY when it cannot. */
static tt_status tt__remember_setting(tt_session *s, size_t index, const char *key,
                                      const char *value) {
  if (s->setting_count == s->setting_cap) {
    size_t cap = s->setting_cap ? 2 * s->setting_cap : 16;
    struct tt__session_setting *v = realloc(s->settings, cap * sizeof *v);
    if (!v) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory recording a setting");
    s->settings = v;
    s->setting_cap = cap;
  }
  char *k = tt__strdup(key), *v = tt__strdup(value);
  if (!k || !v) {
    free(k);
    free(v);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory recording a setting");
  }
  s->settings[s->setting_count++] = (struct tt__session_setting){index, k, v};
  return TT_OK;
}

tt_status tt_session_set(tt_session *s, const char *plugin, const char *key, const char *value) {
  if (!s || !plugin || !key || !value)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_set: NULL argument");
  int idx = tt_session_plugin_index(s, plugin);
  if (idx < 0) {
    char names[1024];
    tt__plugin_names(s, names, sizeof names);
    const char *loaded[256];
    size_t nl = tt_registry_count(s->reg) < 256 ? tt_registry_count(s->reg) : 256;
    for (size_t i = 0; i < nl; i++)
      loaded[i] = tt_loaded_plugin_entry(tt_registry_get(s->reg, i))->name;
    const char *near = tt_suggest(plugin, loaded, nl);
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "no plugin \"%s\" is loaded (%s%s%sloaded: %s)",
                        plugin, near ? "did you mean \"" : "", near ? near : "", near ? "\"? " : "",
                        names);
  }
  tt_loaded_plugin *p = tt_registry_get(s->reg, (size_t)idx);
  tt_config *cfg = s->configs[idx];
  /* a key that is no parameter may be an option (tt.options/1: files, names) */
  const tt_options_iface *oi = tt_session_plugin_options(p);
  int is_param = cfg && tt_space_find(tt_config_space(cfg), key) >= 0;
  if (!is_param && oi && oi->get(key)) {
    tt_status st = oi->set(key, value);
    return st == TT_OK ? tt__remember_setting(s, (size_t)idx, key, value) : st;
  }
  if (!cfg)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "plugin \"%s\" has no parameters%s", plugin,
                        oi ? " and no such option" : "");
  if (tt_config_set_string(cfg, key, value) != TT_OK) {
    char hint[512] = "";
    for (uint32_t o = 0; oi && !is_param && o < oi->count(); o++) {
      const tt_option_info *info = oi->info(o);
      size_t len = strlen(hint);
      if (info && info->key)
        snprintf(hint + len, sizeof hint - len, "%s%s", o ? ", " : "; options: ", info->key);
    }
    char cause[2048];
    snprintf(cause, sizeof cause, "%s", tt_last_error());
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s%s", cause, hint);
  }
  if (!strcmp(key, "maxDepth")) s->depth_set[idx] = 1;
  return tt__remember_setting(s, (size_t)idx, key, value);
}

tt_status tt_session_check(tt_session *s) {
  if (!s) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_check: NULL");
  char all[4096] = "";
  for (size_t i = 0; i < tt_registry_count(s->reg); i++) {
    if (!s->configs[i]) continue;
    char why[512] = "";
    tt_check_result r =
        tt_space_check(tt_config_space(s->configs[i]), s->configs[i], why, sizeof why);
    const char *name = tt_loaded_plugin_entry(tt_registry_get(s->reg, i))->name;
    if (r == TT_CHECK_REPAIRED) {
      tt_host_log(s->host, TT_LOG_WARN, NULL, "%s: configuration repaired: %s", name, why);
    } else if (r == TT_CHECK_INFEASIBLE) {
      size_t len = strlen(all);
      snprintf(all + len, sizeof all - len, "%s%s: infeasible configuration: %s", len ? "; " : "",
               name, why);
    }
  }
  return all[0] ? tt_set_error(TT_ERR_INFEASIBLE, "%s", all) : TT_OK;
}

/* ---- rendering ---- */

tt_status tt_session_start(tt_session *s, uint32_t aov_mask) {
  if (!s) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_start: NULL");
  if (s->started) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "the session has already started");
  if (!s->scene) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "no scene loaded: load one first");
  tt_status st = tt_session_load_defaults(s);
  if (st == TT_OK) st = tt_session_check(s);
  if (st != TT_OK) return st;
  s->accel_p = tt_registry_find_kind(s->reg, TT_KIND_ACCEL);
  s->integ_p = tt_registry_find_kind(s->reg, TT_KIND_INTEGRATOR);
  s->ai = tt_loaded_plugin_iface(s->accel_p);
  s->ii = tt_loaded_plugin_iface(s->integ_p);
  const tt_camera *cam = tt_scene_camera(s->scene);
  tt_accel_build_stats bs;
  memset(&bs, 0, sizeof bs);
  bs.struct_size = sizeof bs;
  const tt_config *acfg = tt_session_config(s, tt_loaded_plugin_entry(s->accel_p)->name);
  if (s->ai->build(s->scene, acfg, &s->accel, &bs) != TT_OK) {
    s->accel = NULL;
    return tt__session_error(TT_ERR_INTERNAL,
                             "%s: build failed: ", tt_loaded_plugin_entry(s->accel_p)->name);
  }
  s->stats.build = bs;
  s->stats.build_ms = bs.build_ms;
  const tt_config *icfg = tt_session_config(s, tt_loaded_plugin_entry(s->integ_p)->name);
  st = s->ii->create(s->scene, icfg, &s->integrator);
  if (st != TT_OK) {
    s->integrator = NULL;
    return tt__session_error(st, "%s: ", tt_loaded_plugin_entry(s->integ_p)->name);
  }
  s->film = tt_film_create(cam->width, cam->height, aov_mask);
  if (!s->film) return TT_ERR_OUT_OF_MEMORY; /* tt_film_create's message names the size */
  s->started = 1;
  return TT_OK;
}

int tt_session_started(const tt_session *s) { return s && s->started; }

tt_loaded_plugin *tt_session_accel_plugin(const tt_session *s) {
  return s ? (s->accel_p ? s->accel_p : tt_registry_find_kind(s->reg, TT_KIND_ACCEL)) : NULL;
}
tt_loaded_plugin *tt_session_integrator_plugin(const tt_session *s) {
  return s ? (s->integ_p ? s->integ_p : tt_registry_find_kind(s->reg, TT_KIND_INTEGRATOR)) : NULL;
}
tt_accel *tt_session_accel(const tt_session *s) { return s ? s->accel : NULL; }
tt_integrator *tt_session_integrator(const tt_session *s) { return s ? s->integrator : NULL; }
tt_film *tt_session_film(tt_session *s) { return s ? s->film : NULL; }

void tt_session_init_ctx(tt_session *s, tt_render_ctx *ctx) {
  memset(ctx, 0, sizeof *ctx);
  ctx->struct_size = sizeof *ctx;
  ctx->scene = s->scene;
  ctx->accel_iface = s->ai;
  ctx->accel = s->accel;
  ctx->film = s->film;
  ctx->camera = tt_scene_camera(s->scene);
  ctx->prev_camera = s->has_prev ? &s->prev_camera : NULL;
  ctx->seed = s->stats.seed;
  ctx->pass_index = s->pass;
  ctx->spp = 1;
  ctx->sample_offset = s->stats.spp;
}

/* Checks that the session can render (started, an accel built). */
static tt_status tt__can_render(const tt_session *s) {
  if (!s || !s->started)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "the session has not started (tt_session_start)");
  if (!s->accel)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: no accel structure (its last build failed)",
                        tt_loaded_plugin_entry(s->accel_p)->name);
  if (!s->integrator)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "%s: no integrator (creating it again after "
                        "the scene moved failed)",
                        tt_loaded_plugin_entry(s->integ_p)->name);
  return TT_OK;
}

tt_status tt_session_render_ctx(tt_session *s, const tt_render_ctx *ctx, tt_pass_stats *stats) {
  tt_status st = tt__can_render(s);
  if (st != TT_OK) return st;
  tt_render_ctx c = *ctx;
  c.struct_size = sizeof c;
  c.scene = s->scene;
  c.accel_iface = s->ai;
  c.accel = s->accel;
  return s->ii->render_pass(s->integrator, &c, stats);
}

tt_status tt_session_render_pass(tt_session *s, uint32_t spp, tt_pass_stats *stats) {
  tt_status st = tt__can_render(s);
  if (st != TT_OK) return st;
  tt_render_ctx ctx;
  tt_session_init_ctx(s, &ctx);
  ctx.spp = spp ? spp : 1;
  tt_pass_stats ps;
  memset(&ps, 0, sizeof ps);
  ps.struct_size = sizeof ps;
  uint64_t p0 = s->host->clock_ns();
  st = s->ii->render_pass(s->integrator, &ctx, &ps);
  double ms = (s->host->clock_ns() - p0) * 1e-6;
  ps.time_ms = ms;
  tt_session_stats *r = &s->stats;
  r->render_ms += ms;
  r->rays += ps.rays;
  r->samples += ps.samples;
  r->nonfinite += ps.nonfinite;
  if (stats) {
    size_t n = stats->struct_size < sizeof ps ? stats->struct_size : sizeof ps;
    memcpy(stats, &ps, n);
    stats->struct_size = (uint32_t)n;
  }
  if (st != TT_OK) return st;
  s->pass++;
  r->passes++;
  r->spp += ctx.spp;
  r->total_spp += ctx.spp;
  r->last_pass = ps;
  for (uint32_t m = 0; m < ps.metric_count && m < TT_MAX_METRICS; m++)
    r->metric_sums[m] += ps.metrics[m].value;
  return TT_OK;
}

void tt_session_reset(tt_session *s) {
  if (!s || !s->started) return;
  tt_film_clear(s->film);
  s->ii->reset(s->integrator);
  s->pass = 0;
  s->stats.spp = 0;
}

tt_status tt_session_rebuild_accel(tt_session *s, const tt_config *config, double *build_ms) {
  if (build_ms) *build_ms = 0;
  if (!s || !s->started)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "the session has not started (tt_session_start)");
  if (!config) config = tt_session_config(s, tt_loaded_plugin_entry(s->accel_p)->name);
  /* the loop of thesis Fig. 3.2: a new configuration means a new structure */
  s->ai->destroy(s->accel);
  s->accel = NULL;
  tt_accel_build_stats bs;
  memset(&bs, 0, sizeof bs);
  bs.struct_size = sizeof bs;
  uint64_t b0 = s->host->clock_ns();
  tt_status st = s->ai->build(s->scene, config, &s->accel, &bs);
  double wall = (s->host->clock_ns() - b0) * 1e-6;
  double ms = bs.build_ms > 0 ? bs.build_ms : wall;
  if (build_ms) *build_ms = ms;
  if (st == TT_OK) {
    s->stats.build = bs;
    s->stats.build_ms = ms;
  } else {
    s->accel = NULL;
  }
  return st;
}

tt_status tt_session_apply(tt_session *s, size_t index, const tt_config *config, double *build_ms) {
  if (build_ms) *build_ms = 0;
  if (!s || !s->started)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "the session has not started (tt_session_start)");
  if (index >= tt_registry_count(s->reg))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_apply: no plugin at index %zu", index);
  tt_loaded_plugin *p = tt_registry_get(s->reg, index);
  if (p == s->accel_p) return tt_session_rebuild_accel(s, config, build_ms);
  if (p == s->integ_p) return s->ii->configure(s->integrator, config);
  const tt_plugin *e = tt_loaded_plugin_entry(p);
  if (e->kind != TT_KIND_POST)
    return tt_set_error(TT_ERR_UNSUPPORTED, "%s: a %s plugin is not applied to a render", e->name,
                        tt_plugin_kind_name(e->kind));
  const tt_post_iface *pi = tt_loaded_plugin_iface(p);
  if (s->post && s->pi != pi) { /* a filter instance belongs to one plugin */
    s->pi->destroy(s->post);
    s->post = NULL;
  }
  s->pi = pi;
  const tt_camera *cam = tt_scene_camera(s->scene);
  if (!s->post) return pi->create(cam->width, cam->height, config, &s->post);
  return pi->configure(s->post, config);
}

void tt_session_get_stats(const tt_session *s, tt_session_stats *out) {
  if (!s || !out) return;
  size_t n = out->struct_size < sizeof s->stats ? out->struct_size : sizeof s->stats;
  memcpy(out, &s->stats, n);
  out->struct_size = (uint32_t)n;
}

void tt_session_set_seed(tt_session *s, uint64_t seed) {
  if (!s) return;
  s->stats.seed = seed;
  s->seed_set = 1;
}
