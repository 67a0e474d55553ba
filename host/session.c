/* host: the session (session.h) — options mapped onto the library's render session. */
#include "session.h"

#include <limits.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef TT_HOST_BUILD_DIR
#  define TT_HOST_BUILD_DIR ""
#endif
#ifndef TT_BUILD_PLUGIN_DIR
#  define TT_BUILD_PLUGIN_DIR ""
#endif

/* Non-zero when this program runs from the build tree's host/ folder (not installed): only
 * then are the build tree's plugins searched, after $TT_PLUGIN_PATH. An installed copy never
 * looks into the tree it was built in. */
static int tt__uninstalled(void) {
  char exe[4096], dir[4096];
  if (!TT_HOST_BUILD_DIR[0] || !realpath("/proc/self/exe", exe) ||
      !realpath(TT_HOST_BUILD_DIR, dir))
    return 0;
  char *slash = strrchr(exe, '/');
  if (!slash) return 0;
  *slash = '\0';
  return !strcmp(exe, dir);
}

/* The plugin folders in search order before the library's installed ones: --plugin-path,
 * $TT_PLUGIN_PATH (the library searches it too; naming it here keeps it before the build
 * tree), and the build tree's plugins for the uninstalled program. */
static int tt__plugin_dirs(const tt__host_options *opt, const char **dirs, int max) {
  static char env[8192];
  int n = 0;
  for (int i = 0; i < opt->plugin_path_count && n < max; i++) dirs[n++] = opt->plugin_paths[i];
  snprintf(env, sizeof env, "%s", getenv("TT_PLUGIN_PATH") ? getenv("TT_PLUGIN_PATH") : "");
  for (char *p = env, *colon; p && *p && n < max; p = colon ? colon + 1 : NULL) {
    colon = strchr(p, ':');
    if (colon) *colon = '\0';
    if (*p) dirs[n++] = p;
  }
  if (n < max && tt__uninstalled()) dirs[n++] = TT_BUILD_PLUGIN_DIR;
  return n;
}

tt_registry *tt__make_registry(const tt__host_options *opt, const tt_host *host) {
  tt_registry *reg = tt_registry_create(host);
  if (!reg) return NULL;
  const char *dirs[2 * TT_HOST_MAX_LIST];
  int n = tt__plugin_dirs(opt, dirs, 2 * TT_HOST_MAX_LIST);
  for (int i = 0; i < n; i++) tt_registry_add_dir(reg, dirs[i]);
  return reg;
}

/* Loads every --plugin and --post, reporting each failure, then the default accel and
 * integrator for kinds not named. Returns the number of failures. */
static int tt__load_plugins(tt__session *s) {
  const tt__host_options *opt = s->opt;
  int failures = 0;
  for (int i = 0; i < opt->plugin_count; i++) {
    if (tt_session_load_plugin(s->lib, opt->plugins[i], NULL) != TT_OK) {
      tt__say("plugin \"%s\": %s\n", opt->plugins[i], tt_last_error());
      failures++;
    }
  }
  if (opt->post && !tt_registry_find_name(tt_session_registry(s->lib), opt->post) &&
      tt_session_load_plugin(s->lib, opt->post, NULL) != TT_OK) {
    tt__say("--post \"%s\": %s\n", opt->post, tt_last_error());
    failures++;
  }
  if (failures) return failures;
  if (tt_session_load_defaults(s->lib) != TT_OK) {
    tt__say("%s\n", tt_last_error());
    failures++;
  }
  /* the hybrid loop (--hybrid, --predict) also needs a search and a model: the thesis' */
  static const struct {
    uint32_t kind;
    const char *name;
  } hybrid[] = {{TT_KIND_TUNER, "tuner_nm"}, {TT_KIND_PREDICTOR, "predictor_nn"}};
  for (size_t i = 0; (opt->hybrid || opt->predict_only) && i < 2; i++) {
    if (tt_registry_find_kind(tt_session_registry(s->lib), hybrid[i].kind)) continue;
    if (tt_session_load_plugin(s->lib, hybrid[i].name, NULL) != TT_OK) {
      tt__say("default %s plugin \"%s\": %s\n", tt_plugin_kind_name(hybrid[i].kind), hybrid[i].name,
              tt_last_error());
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

/* Applies every --set PLUGIN.KEY=VALUE, reporting each bad one; returns the number of
 * errors. */
static int tt__apply_sets(tt__session *s) {
  const tt__host_options *opt = s->opt;
  int errors = 0;
  for (int k = 0; k < opt->set_count; k++) {
    const char *arg = opt->sets[k];
    const char *dot = strchr(arg, '.'), *eq = strchr(arg, '=');
    char plugin[128], param[128];
    snprintf(plugin, sizeof plugin, "%.*s", (int)(dot - arg), arg);
    snprintf(param, sizeof param, "%.*s", (int)(eq - dot - 1), dot + 1);
    if (tt_session_set(s->lib, plugin, param, eq + 1) != TT_OK) {
      tt__say("--set %s: %s\n", arg, tt_last_error());
      errors++;
    }
  }
  return errors;
}

/* --camera-index I: the path sample I of TT_HOST_PATH_SAMPLES, t = first key + I/(N-1) of
 * the scene's time range (camera path and animation), becomes the scene's time: the camera
 * and the moving meshes; a frame of --frames: the pose at its time (camera_time = f / fps,
 * as the frames of a sequence). The motion AOV's previous frame is one frame interval
 * (--fps, default 24) earlier. */
static int tt__apply_camera_index(tt__session *s) {
  const tt__host_options *opt = s->opt;
  const tt_camera *c0 = tt_scene_camera(s->scene);
  double t = opt->camera_time_set ? opt->camera_time : 0, t0, t1;
  const double dt = 1.0 / (opt->fps > 0 ? opt->fps : 24.0);
  tt_scene_time_range(s->scene, &t0, &t1);
  int timed = c0->key_count > 0 || tt_scene_animated(s->scene);
  if (timed && !opt->camera_time_set)
    t = t0 + (t1 - t0) * (double)opt->camera_index / (TT_HOST_PATH_SAMPLES - 1.0);
  if (tt_scene_animated(s->scene) && tt_scene_set_time(s->scene, t, t - dt) != TT_OK) {
    tt__say("%s\n", tt_last_error());
    return TT_EXIT_SCENE;
  }
  if (!timed && opt->camera_time_set) /* a warning: --quiet keeps it */
    tt__say("warning: --frames: the scene has no camera path; every frame "
            "uses its still camera\n");
  else if (!timed)
    tt__say("warning: --camera-index %u: the scene has no camera path; "
            "using its still camera\n",
            opt->camera_index);
  tt_session_set_camera_time(s->lib, t, dt);
  return TT_EXIT_OK;
}

void tt__session_sync(tt__session *s) {
  tt_session_stats st = {.struct_size = sizeof st};
  tt_session_get_stats(s->lib, &st);
  tt__run_record *rec = &s->rec;
  rec->build_ms = st.build_ms;
  rec->build = st.build;
  rec->render_ms = st.render_ms;
  rec->passes = st.passes;
  rec->spp = st.spp;
  rec->rays = st.rays;
  rec->samples = st.samples;
  rec->nonfinite = st.nonfinite;
  rec->last_pass = st.last_pass;
  memcpy(rec->metric_sums, st.metric_sums, sizeof rec->metric_sums);
}

/* Once the session is checked: the views into the library session (configurations, accel,
 * integrator) and the run record's fixed part (plugins, scene, seed, threads, size). */
static void tt__session_views(tt__session *s) {
  size_t count = tt_registry_count(s->reg);
  for (size_t i = 0; i < count && i < TT_HOST_MAX_LIST; i++)
    s->configs[i] = tt_session_config_at(s->lib, i);
  s->accel_p = tt_session_accel_plugin(s->lib);
  s->integ_p = tt_session_integrator_plugin(s->lib);
  tt_session_stats st = {.struct_size = sizeof st};
  tt_session_get_stats(s->lib, &st);
  tt__run_record *rec = &s->rec;
  rec->opt = s->opt;
  rec->reg = s->reg;
  rec->scene = s->scene;
  for (size_t i = 0; i < count && i < TT_HOST_MAX_LIST; i++) rec->configs[i] = s->configs[i];
  rec->seed = st.seed;
  rec->threads = s->host->thread_count();
  rec->width = s->camera->width;
  rec->height = s->camera->height;
  rec->build.struct_size = sizeof rec->build;
}

int tt__session_open(tt__session *s, const tt__host_options *opt) {
  memset(s, 0, sizeof *s);
  s->opt = opt;
  s->host = tt__host_services(opt->quiet);
  if (opt->clock_cpu) tt__host_use_cpu_clock();
  tt_set_log_host(s->host); /* loader warnings go through the host's log */
  if (opt->threads && tt_default_host_set_threads(opt->threads) != TT_OK) {
    tt__say("--threads: %s\n", tt_last_error());
    return TT_EXIT_USAGE;
  }
  if (tt_session_create(s->host, &s->lib) != TT_OK) {
    tt__say("%s\n", tt_last_error());
    return TT_EXIT_FAILURE;
  }
  const char *dirs[2 * TT_HOST_MAX_LIST];
  int ndirs = tt__plugin_dirs(opt, dirs, 2 * TT_HOST_MAX_LIST);
  for (int i = 0; i < ndirs; i++) tt_session_add_plugin_dir(s->lib, dirs[i]);
  s->reg = tt_session_registry(s->lib);
  /* every problem is reported before giving up: a scene that does not load still lets the
   * plugins and --set be checked; the exit code is the first problem's (scene 4, plugin 3,
   * --set 2) */
  int rc = TT_EXIT_OK;
  if (tt_session_load_scene_ex(s->lib, opt->scene,
                               opt->strict ? TT_SCENE_LOAD_STRICT : TT_SCENE_LOAD_DEFAULT) !=
      TT_OK) {
    tt__say("%s\n", tt_last_error());
    rc = TT_EXIT_SCENE;
  } else {
    s->scene = tt_session_scene(s->lib);
    if (opt->width && tt_scene_set_resolution(s->scene, opt->width, opt->height) != TT_OK) {
      tt__say("--res: %s\n", tt_last_error());
      return TT_EXIT_USAGE;
    }
    if ((opt->camera_index_set || opt->camera_time_set) &&
        (rc = tt__apply_camera_index(s)) != TT_EXIT_OK)
      return rc;
    s->camera = tt_session_camera(s->lib);
  }
  if (opt->seed_set) tt_session_set_seed(s->lib, opt->seed);
  if (tt__load_plugins(s)) return rc != TT_EXIT_OK ? rc : TT_EXIT_PLUGIN;
  if (tt__apply_sets(s) && rc == TT_EXIT_OK) rc = TT_EXIT_USAGE;
  if (rc != TT_EXIT_OK) return rc;
  if (tt_session_check(s->lib) != TT_OK) {
    tt__say("%s\n", tt_last_error());
    return TT_EXIT_USAGE;
  }
  tt__session_views(s);
  return TT_EXIT_OK;
}

int tt__session_start(tt__session *s, uint32_t aovs) {
  if (tt_session_start(s->lib, aovs) != TT_OK) {
    tt__say("%s\n", tt_last_error());
    return TT_EXIT_FAILURE;
  }
  s->film = tt_session_film(s->lib);
  tt__session_sync(s);
  return TT_EXIT_OK;
}

tt_status tt__session_render_pass(tt__session *s, uint32_t spp, tt_pass_stats *ps, double *ms) {
  memset(ps, 0, sizeof *ps);
  ps->struct_size = sizeof *ps;
  tt_status st = tt_session_render_pass(s->lib, spp, ps);
  *ms = ps->time_ms;
  tt__session_sync(s);
  return st;
}

void tt__session_close(tt__session *s) {
  tt_session_destroy(s->lib);
  memset(s, 0, sizeof *s);
}
