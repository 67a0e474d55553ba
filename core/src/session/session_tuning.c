/* The session as a tuning target (tunetrace/session.h): apply a configuration, render one
 * measurement pass into the film and separate the image that pass alone rendered; and the
 * state (camera, context, indicators) the measurements are recorded under. */
#include "session/session_internal.h"

#include <tunetrace/tuning_hint.h>

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Copies the film's accumulators before a measurement pass. */
static void tt__snapshot(tt_session *s) {
  tt_film *f = s->film;
  size_t n = (size_t)tt_film_width(f) * tt_film_height(f);
  memcpy(s->snap, tt_film_sum_rgb(f), 3 * n * sizeof(float));
  memcpy(s->snap + 3 * n, tt_film_sum_weight(f), n * sizeof(float));
  memcpy(s->snap + 4 * n, tt_film_splat_rgb(f), 3 * n * sizeof(float));
  s->snap_scale = tt_film_splat_scale(f);
}

/* The image the last pass alone renders (s->pass_rgb), from the accumulators before
 * (s->snap) and after it. The tuning passes still accumulate into the film; this only
 * separates the pass's share:
 *  - per-pixel samples: (sum_wL after - before) / (sum_w after - before);
 *  - splats (film.h: resolved = splat * scale, scale = c / N for N units so far, as
 *    PSSMLT's b * pixels / mutations): the pass's splats times c / (N_after - N_before),
 *    i.e. 1 / (1/scale_after - 1/scale_before). An unchanged scale means splats that add
 *    up: the pass's splats times that scale. A film without splats before the pass, or a
 *    scale that grew (the integrator restarted its estimate and cleared the splats), leaves
 *    the splat buffer to this pass alone: splats after times scale after. */
static void tt__pass_image(tt_session *s) {
  tt_film *f = s->film;
  size_t n = (size_t)tt_film_width(f) * tt_film_height(f);
  const float *sr = tt_film_sum_rgb(f), *sw = tt_film_sum_weight(f), *sp = tt_film_splat_rgb(f);
  const float *br = s->snap, *bw = s->snap + 3 * n, *bp = s->snap + 4 * n;
  double ka = tt_film_splat_scale(f), kb = s->snap_scale;
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
      s->pass_rgb[j] = (float)v;
    }
  }
}

/* Runs the post-filter target over the film as it is; its wall ms, or a negative value on
 * failure. */
static double tt__run_post(tt_session *s) {
  const tt_camera *cam = tt_scene_camera(s->scene);
  tt_film_resolve(s->film, s->post_in);
  tt_post_frame f;
  memset(&f, 0, sizeof f);
  f.struct_size = sizeof f;
  f.width = cam->width;
  f.height = cam->height;
  f.color = s->post_in;
  f.frame_index = s->pass;
  uint64_t t0 = s->host->clock_ns();
  tt_status st = s->pi->process(s->post, &f, s->post_out);
  double ms = (s->host->clock_ns() - t0) * 1e-6;
  return st == TT_OK ? ms : -1.0;
}

/* tt_tuning_target.apply */
static tt_status tt__target_apply(void *user, const tt_config *cfg, double *build_ms) {
  tt_session *s = user;
  return tt_session_apply(s, s->target_index, cfg, build_ms);
}

/* tt_tuning_target.render: one pass into the film (+ the filter of a post target), keeping
 * the pass's own image when one is wanted. `m` NULL: a warm-up pass. */
static tt_status tt__target_render(void *user, uint32_t spp, tt_tuning_measurement *m) {
  tt_session *s = user;
  s->ps.struct_size = sizeof s->ps;
  if (!m) return tt_session_render_pass(s, spp, &s->ps);
  if (s->want_images) tt__snapshot(s);
  tt_status st = tt_session_render_pass(s, spp, &s->ps);
  m->render_ms = s->ps.time_ms;
  m->pass = &s->ps;
  if (st != TT_OK) return st;
  if (s->want_images) {
    tt__pass_image(s);
    m->image = s->pass_rgb;
  }
  if (s->target_kind == TT_KIND_POST) {
    double pms = tt__run_post(s);
    if (pms < 0) return tt__session_error(TT_ERR_INTERNAL, "post-filter target: ");
    m->render_ms += pms;
  }
  return TT_OK;
}

tt_status tt_session_tuning_target(tt_session *s, size_t index, int want_images,
                                   tt_tuning_target *out) {
  if (!s || !out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_tuning_target: NULL");
  if (!s->started)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "the session has not started (tt_session_start)");
  if (index >= tt_registry_count(s->reg))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuning target: no plugin at index %zu", index);
  const tt_plugin *e = tt_loaded_plugin_entry(tt_registry_get(s->reg, index));
  if (e->kind != TT_KIND_ACCEL && e->kind != TT_KIND_INTEGRATOR && e->kind != TT_KIND_POST)
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "%s: a %s plugin cannot be a tuning target (only "
                        "accel, integrator and post plugins)",
                        e->name, tt_plugin_kind_name(e->kind));
  size_t px = (size_t)tt_film_width(s->film) * tt_film_height(s->film);
  if (want_images && !s->snap) {
    s->snap = malloc(7 * px * sizeof(float));
    s->pass_rgb = malloc(3 * px * sizeof(float));
  }
  if (e->kind == TT_KIND_POST && !s->post_in) {
    s->post_in = malloc(3 * px * sizeof(float));
    s->post_out = malloc(3 * px * sizeof(float));
  }
  if ((want_images && (!s->snap || !s->pass_rgb)) ||
      (e->kind == TT_KIND_POST && (!s->post_in || !s->post_out)))
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuning target: out of memory for %zu pixels", px);
  if (e->kind == TT_KIND_POST) s->pi = tt_loaded_plugin_iface(tt_registry_get(s->reg, index));
  s->target_index = index;
  s->target_kind = e->kind;
  s->want_images = want_images;
  memset(out, 0, sizeof *out);
  out->struct_size = sizeof *out;
  out->user = s;
  out->apply = tt__target_apply;
  out->render = tt__target_render;
  return TT_OK;
}

/* ---- the tuning plan ---- */

/* Non-zero if the plugin publishes a space with at least one parameter. */
static int tt__tunable(const tt_loaded_plugin *p) {
  const tt_space *space = p ? tt_loaded_plugin_space(p) : NULL;
  return space && tt_space_count(space) > 0;
}

/* The tunable parameters of `space` that act on a still scene (not motion-only) into
 * `names` (at most `cap`); 0 when that is all of the tunable ones (no subset needed) or more
 * than `cap`. */
static size_t tt__still_params(const tt_space *space, const char **names, size_t cap) {
  size_t n = 0, tunable = 0;
  for (size_t i = 0; i < tt_space_count(space); i++) {
    if (!tt_space_is_tunable(space, i)) continue;
    tunable++;
    if (tt_space_is_motion_only(space, i)) continue;
    if (n == cap) return 0;
    names[n++] = tt_space_name(space, i);
  }
  return n < tunable ? n : 0;
}

/* The plugin's tuning hint (tt.tuning_hint/1) when it names an objective, else NULL. */
static const tt_tuning_hint *tt__hint(const tt_loaded_plugin *p) {
  const tt_tuning_hint *h = p ? tt_loaded_plugin_get(p, TT_TUNING_HINT_ID) : NULL;
  return h && TT_HAS_FIELD(tt_tuning_hint, h, objective) && h->objective ? h : NULL;
}

/* Chooses the target: the plugin named `name`, or an integrator with a hint and a space,
 * else the accel. */
static tt_status tt__plan_target(tt_session *s, const char *name, tt_loaded_plugin **out) {
  *out = NULL;
  if (!name) {
    tt_loaded_plugin *integ = tt_session_integrator_plugin(s), *accel = tt_session_accel_plugin(s);
    if (tt__hint(integ) && tt__tunable(integ)) *out = integ;
    else if (tt__tunable(accel)) *out = accel;
    else
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          "neither the integrator nor the accel "
                          "publishes tunable parameters; name the plugin to tune");
    return TT_OK;
  }
  tt_loaded_plugin *p = tt_registry_find_name(s->reg, name);
  if (!p) {
    char names[1024] = "";
    for (size_t i = 0; i < tt_registry_count(s->reg); i++) {
      size_t len = strlen(names);
      snprintf(names + len, sizeof names - len, "%s%s", i ? ", " : "",
               tt_loaded_plugin_entry(tt_registry_get(s->reg, i))->name);
    }
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "no loaded plugin is called \"%s\" (loaded: "
                        "%s)",
                        name, names);
  }
  uint32_t kind = tt_loaded_plugin_entry(p)->kind;
  if (kind != TT_KIND_ACCEL && kind != TT_KIND_INTEGRATOR && kind != TT_KIND_POST)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "%s: a %s plugin cannot be tuned (only accel, "
                        "integrator and post plugins)",
                        name, tt_plugin_kind_name(kind));
  if (!tt__tunable(p))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "%s: the plugin publishes no tunable "
                        "parameters",
                        name);
  *out = p;
  return TT_OK;
}

/* The hint's starting values (PSSMLT: binning on), then the user's settings on top. */
static tt_status tt__plan_setup(tt_session *s, size_t index, const tt_tuning_hint *hint) {
  if (!hint || !TT_HAS_FIELD(tt_tuning_hint, hint, setup) || !hint->setup) return TT_OK;
  tt_config *cfg = s->configs[index];
  const char *name = tt_loaded_plugin_entry(tt_registry_get(s->reg, index))->name;
  if (tt_config_from_json(cfg, hint->setup, "tuning hint setup") != TT_OK)
    return tt__session_error(TT_ERR_PARSE, "%s: ", name);
  for (size_t k = 0; k < s->setting_count; k++) {
    const struct tt__session_setting *set = &s->settings[k];
    /* options are no parameters: the setup does not touch them. The values were
     * validated when they were set. */
    if (set->index == index && tt_space_find(tt_config_space(cfg), set->key) >= 0)
      tt_config_set_string(cfg, set->key, set->value);
  }
  return TT_OK;
}

tt_status tt_session_tuning_plan(tt_session *s, const char *target, const char *const *params,
                                 size_t count, tt_tuning_plan *out) {
  if (!s || !out || !TT_HAS_FIELD(tt_tuning_plan, out, objective))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_session_tuning_plan: NULL or short plan");
  uint32_t size = out->struct_size;
  memset(out, 0, size);
  out->struct_size = size;
  tt_loaded_plugin *p;
  tt_status st = tt__plan_target(s, target, &p);
  if (st != TT_OK) return st;
  const tt_tuning_hint *hint = tt__hint(p);
  size_t index = (size_t)tt_session_plugin_index(s, tt_loaded_plugin_entry(p)->name);
  if ((st = tt__plan_setup(s, index, hint)) != TT_OK) return st;
  const tt_space *space = tt_loaded_plugin_space(p);
  const char *const *names = params;
  size_t n = params ? count : 0;
  int from_hint = !params && hint && TT_HAS_FIELD(tt_tuning_hint, hint, tunable) && hint->tunable;
  if (from_hint) {
    names = hint->tunable;
    while (names[n]) n++;
  }
  const char *still[256];
  if (!n && !tt_scene_animated(s->scene) && (n = tt__still_params(space, still, 256)) > 0) {
    names = still; /* a still scene: the parameters that act only while it moves are left out */
    char left[512] = "";
    for (size_t i = 0, used = 0; i < tt_space_count(space) && used < sizeof left; i++)
      if (tt_space_is_tunable(space, i) && tt_space_is_motion_only(space, i)) {
        int w = snprintf(left + used, sizeof left - used, "%s%s", used ? ", " : "",
                         tt_space_name(space, i));
        if (w > 0) used += (size_t)w;
      }
    tt_host_log(s->host, TT_LOG_INFO, NULL,
                "tuning %s: not searched: %s (they act only while the scene moves, and %s is "
                "still; tune along an animated sequence, or name them to search them anyway)",
                tt_loaded_plugin_entry(p)->name, left, tt_scene_source(s->scene));
  }
  tt_space *search = NULL;
  if (n && !(search = tt_space_subset(space, names, n, s->configs[index])))
    return tt__session_error(TT_ERR_INVALID_ARGUMENT, "%s: %s: ", tt_loaded_plugin_entry(p)->name,
                             from_hint ? "the tuning hint's parameters" : "searched parameters");
  out->target_index = index;
  out->target = p;
  out->space = space;
  out->search = search;
  out->objective = hint ? hint->objective : "render";
  return TT_OK;
}

void tt_tuning_plan_release(tt_tuning_plan *plan) {
  if (!plan || !TT_HAS_FIELD(tt_tuning_plan, plan, search)) return;
  tt_space_destroy(plan->search);
  plan->search = NULL;
}

/* Adds every member of the JSON object `extra` (NULL: none) to `obj`; TT_ERR_PARSE naming
 * `what` when it is no object. */
static tt_status tt__add_members(cJSON *obj, const char *extra, const char *what) {
  if (!extra) return TT_OK;
  cJSON *e = cJSON_Parse(extra);
  if (!e || !cJSON_IsObject(e)) {
    cJSON_Delete(e);
    return tt_set_error(TT_ERR_PARSE, "tuning state: %s: expected a JSON object, got \"%.80s\"",
                        what, extra);
  }
  while (e->child) {
    cJSON *item = cJSON_DetachItemViaPointer(e, e->child);
    cJSON_AddItemToObject(obj, item->string, item);
  }
  cJSON_Delete(e);
  return TT_OK;
}

/* Prints `root` compactly into a malloc'd string (the session's), deleting `root`. */
static char *tt__print(cJSON *root) {
  char *text = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  if (!text) return NULL;
  char *out = malloc(strlen(text) + 1);
  if (out) strcpy(out, text);
  cJSON_free(text);
  return out;
}

/* %.9g of a float, as the tuning database has always stored camera numbers. */
static cJSON *tt__num(double v) {
  char buf[32];
  snprintf(buf, sizeof buf, "%.9g", v);
  return cJSON_CreateRaw(buf);
}

tt_status tt_session_tuning_state(tt_session *s, size_t index, uint32_t spp,
                                  const char *camera_extra, const char *context_extra,
                                  int indicators, tt_tuning_state *out) {
  if (!s || !out || !s->scene)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuning state: no scene loaded");
  if (index >= tt_registry_count(s->reg))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tuning state: no plugin at index %zu", index);
  const tt_camera *c = tt_scene_camera(s->scene);
  /* the view: the part of the state the camera contributes */
  cJSON *cam = cJSON_CreateObject();
  const float *vec[3] = {c->position, c->target, c->up};
  static const char *const vec_name[3] = {"position", "target", "up"};
  for (int v = 0; v < 3; v++) {
    cJSON *a = cJSON_AddArrayToObject(cam, vec_name[v]);
    for (int k = 0; k < 3; k++) cJSON_AddItemToArray(a, tt__num(vec[v][k]));
  }
  cJSON_AddItemToObject(cam, "fov_y", tt__num(c->fov_y));
  cJSON *res = cJSON_AddArrayToObject(cam, "resolution");
  cJSON_AddItemToArray(res, cJSON_CreateNumber(c->width));
  cJSON_AddItemToArray(res, cJSON_CreateNumber(c->height));
  /* everything else that shapes the cost: samples per measurement, threads, and the other
   * rendering plugins with their configurations (an accel's render time depends on the
   * integrator's maxDepth, an integrator's on the accel). Tuners and predictors are left
   * out: they choose configurations, they do not change what one costs. */
  cJSON *ctx = cJSON_CreateObject();
  cJSON_AddNumberToObject(ctx, "spp", spp ? spp : 1);
  cJSON_AddNumberToObject(ctx, "threads", s->host->thread_count());
  cJSON *plugins = cJSON_AddObjectToObject(ctx, "plugins");
  for (size_t i = 0; i < tt_registry_count(s->reg); i++) {
    const tt_plugin *e = tt_loaded_plugin_entry(tt_registry_get(s->reg, i));
    if (i == index || e->kind == TT_KIND_TUNER || e->kind == TT_KIND_PREDICTOR) continue;
    cJSON *p = cJSON_AddObjectToObject(plugins, e->name);
    cJSON_AddStringToObject(p, "version", e->version);
    char *cfg = s->configs[i] ? tt_config_to_json(s->configs[i]) : NULL;
    cJSON *obj = cfg ? cJSON_Parse(cfg) : NULL;
    tt_free(cfg);
    cJSON_AddItemToObject(p, "config", obj ? obj : cJSON_CreateObject());
  }
  tt_status st = tt__add_members(cam, camera_extra, "camera_extra");
  if (st == TT_OK) st = tt__add_members(ctx, context_extra, "context_extra");
  if (st != TT_OK) {
    cJSON_Delete(cam);
    cJSON_Delete(ctx);
    return st;
  }
  free(s->state_camera);
  free(s->state_context);
  s->state_camera = tt__print(cam);
  s->state_context = tt__print(ctx);
  if (!s->state_camera || !s->state_context)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "tuning state: out of memory");
  memset(out, 0, sizeof *out);
  out->struct_size = sizeof *out;
  out->scene_id = tt_scene_id(s->scene);
  out->scene = tt_scene_source(s->scene);
  out->camera = s->state_camera;
  out->context = s->state_context;
  if (indicators) {
    tt_scene_indicators(s->scene, out->indicators);
    out->has_indicators = 1;
  }
  return TT_OK;
}
