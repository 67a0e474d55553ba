/* tunetrace: a render session — the scene, the loaded plugins with one configuration each,
 * the accel built over the scene, the integrator and the film, as one library object.
 *
 * This is what the `host` program renders, tunes and records sequences through, and what
 * the Python API (python/tunetrace) wraps, so that any application renders a scene the way
 * host does without reimplementing plugin set-up:
 *
 *     tt_session *s;  tt_session_create(NULL, &s);
 *     tt_session_load_scene(s, "scenes/cornell-box/scene.json");
 *     tt_session_load_plugin(s, "integrator_pt", NULL);
 *     tt_session_set(s, "integrator_pt", "maxDepth", "8");
 *     tt_session_start(s, TT_AOV_NORMAL | TT_AOV_ALBEDO);   // accel, integrator, film
 *     for (int i = 0; i < 16; i++) tt_session_render_pass(s, 1, NULL);
 *     tt_film_resolve(tt_session_film(s), rgb);
 *     tt_session_destroy(s);
 *
 * Two phases. Set-up: load the scene, load plugins, set parameters (tt_session_set), in any
 * order; every loaded plugin gets a configuration of its space (the defaults; an integrator's
 * maxDepth is the scene's render.maxDepth unless set explicitly). tt_session_start then loads
 * the default accel (accel_embree) and integrator (integrator_pt) for kinds not loaded,
 * checks every configuration, builds the accel, creates the integrator and a film of the
 * camera's size. Rendering: passes accumulate into the film progressively; the accel can be
 * rebuilt and the integrator reconfigured between passes (tuning).
 *
 * Errors: every fallible function returns a tt_status and records a message that names what
 * failed (tt_last_error, and the error callback of tt_set_error_callback).
 * Ownership: the session owns the scene, the plugins (its registry), the configurations, the
 * accel, the integrator and the film; pointers it returns stay valid until the session is
 * destroyed unless a function says otherwise.
 * Threads: a session is used by one thread at a time; sessions on different threads may
 * run at once (they share the loaded plugins' process-wide state, see plugin.h, and the
 * default host's worker pool, whose jobs run one after another). A session's passes run in
 * parallel on the host's worker pool.
 */
#ifndef TUNETRACE_SESSION_H
#define TUNETRACE_SESSION_H

#include <tunetrace/accel.h>
#include <tunetrace/common.h>
#include <tunetrace/film.h>
#include <tunetrace/host.h>
#include <tunetrace/integrator.h>
#include <tunetrace/loader.h>
#include <tunetrace/params.h>
#include <tunetrace/scene.h>
#include <tunetrace/tuning.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tt_session tt_session; /* opaque session handle */

/* ---- set-up ---------------------------------------------------------------------- */

/* Creates an empty session whose plugins receive `host` (NULL: tt_default_host(); it must
 * outlive the session). Plugins are searched in the folders added with
 * tt_session_add_plugin_dir, then $TT_PLUGIN_PATH, then the installed plugin folder.
 * `*out` is owned by the caller: free with tt_session_destroy. */
TT_API tt_status tt_session_create(const tt_host *host, tt_session **out);

/* Destroys the film, integrator, accel, configurations, plugins (deinit) and scene (NULL is
 * ignored). */
TT_API void tt_session_destroy(tt_session *s);

/* Appends a folder to the plugin search list (before $TT_PLUGIN_PATH). */
TT_API tt_status tt_session_add_plugin_dir(tt_session *s, const char *dir);

/* Loads a scene file (tt_scene_load) as the session's scene, replacing none: one scene per
 * session (TT_ERR_INVALID_ARGUMENT on a second). Errors are tt_scene_load's, naming the file,
 * the field and what was expected. */
TT_API tt_status tt_session_load_scene(tt_session *s, const char *path);
/* tt_session_load_scene with tt_scene_load_flags (TT_SCENE_LOAD_STRICT: pbrt-v4 input is
 * read as strictly as pbrt-v4 reads it). */
TT_API tt_status tt_session_load_scene_ex(tt_session *s, const char *path, uint32_t flags);

/* The session's scene (NULL before one is loaded). The camera and the resolution may be
 * changed (tt_scene_set_camera, tt_scene_set_resolution) until tt_session_start. */
TT_API tt_scene *tt_session_scene(tt_session *s);

/* Sets the camera to the pose of the scene's camera path at time `t` (seconds) and, for the
 * motion AOV, the previous frame to the pose at `t - frame_interval` (a scene without a path
 * keeps its still camera: motion is zero). After tt_session_start too, between passes (the
 * hybrid loop's states): the film keeps its size (a path camera of another resolution is
 * TT_ERR_INVALID_ARGUMENT) and keeps what it holds (tt_session_reset for a new view). */
TT_API tt_status tt_session_set_camera_time(tt_session *s, double t, double frame_interval);

/* The camera the session renders (the scene's, after tt_session_set_camera_time); NULL
 * without a scene. */
TT_API const tt_camera *tt_session_camera(const tt_session *s);

/* Moves the session to time `t` of an animated scene: the meshes are posed at `t` with
 * their previous positions at `t - frame_interval` (tt_scene_set_time, for object motion
 * vectors), the camera as tt_session_set_camera_time, and once started the accel is brought
 * up to date -- the accel plugin's update (refit or rebuild, as its configuration says), or
 * destroy + build for a plugin without one -- and the integrator is created again when an
 * area light moved (its light distribution depends on the triangles). `stats` (may be
 * NULL): what the update did (update_ms, rebuilt, ...); zeroed for a still scene, which
 * only moves its camera. The film keeps what it holds (tt_session_reset for a new frame).
 * On an update failure no accel is left: render calls fail until a rebuild succeeds. */
TT_API tt_status tt_session_set_time(tt_session *s, double t, double frame_interval,
                                     tt_accel_update_stats *stats);

/* tt_session_set_time with a configuration change at this frame: once started, the accel
 * is built from scratch with `accel_config` (of the accel's space) over the new pose instead
 * of updated -- the frame's update is that build (stats->rebuilt, update_ms), and later
 * updates follow the new configuration's update method. NULL: tt_session_set_time. The
 * session's own configuration of the accel is left as it is (tt_session_configure_plugin
 * or the tuning target change it). A still scene only moves its camera: call
 * tt_session_apply to change its accel's configuration. Used by tuning along a sequence,
 * where each measured configuration takes over at a frame. */
TT_API tt_status tt_session_set_time_config(tt_session *s, double t, double frame_interval,
                                            const tt_config *accel_config,
                                            tt_accel_update_stats *stats);

/* Loads a plugin by name (searched) or path and gives it a configuration of its space.
 * `*out` (may be NULL) points to it, owned by the session. Errors are the loader's (missing
 * file, ABI, second plugin of a kind, ...). Before tt_session_start. */
TT_API tt_status tt_session_load_plugin(tt_session *s, const char *name_or_path,
                                        tt_loaded_plugin **out);

/* Name of the plugin tt_session_start loads for `kind` when none is loaded (accel:
 * "accel_embree", integrator: "integrator_pt"), or NULL for kinds without a default. */
TT_API const char *tt_session_default_plugin(uint32_t kind);

/* Loads the default plugin of every kind that has one and is not loaded yet (what
 * tt_session_start does first). On failure the message names the kind and the plugin. */
TT_API tt_status tt_session_load_defaults(tt_session *s);

/* The session's plugin registry (count, iteration, lookup by name or kind). */
TT_API tt_registry *tt_session_registry(tt_session *s);

/* Registry index of a loaded plugin called `name`, or -1. */
TT_API int tt_session_plugin_index(const tt_session *s, const char *name);

/* The configuration of the plugin at registry `index` (NULL: out of range, or the plugin
 * publishes no space). Owned by the session; changes apply at tt_session_start, or through
 * tt_session_apply afterwards. */
TT_API tt_config *tt_session_config_at(tt_session *s, size_t index);

/* The configuration of the loaded plugin called `plugin`, or NULL. */
TT_API tt_config *tt_session_config(tt_session *s, const char *plugin);

/* Sets `key` of the loaded plugin `plugin` to `value` (text, as in host's --set
 * PLUGIN.KEY=VALUE): a parameter of its space, else an option of its tt.options/1 table
 * (files, names: not tuned). TT_ERR_INVALID_ARGUMENT when no such plugin is loaded (the
 * message lists the loaded ones) or the key is neither (it lists the options); the
 * parameter's own error for a bad value. */
TT_API tt_status tt_session_set(tt_session *s, const char *plugin, const char *key,
                                const char *value);

/* Checks every configuration against its space's constraints: a repaired one is logged as a
 * warning through the host and kept repaired; TT_ERR_INFEASIBLE names the first plugin that
 * cannot be repaired and why. */
TT_API tt_status tt_session_check(tt_session *s);

/* The plugin's tt.options/1 table, or NULL when it serves none or one older than the
 * fields the session calls. */
TT_API const tt_options_iface *tt_session_plugin_options(const tt_loaded_plugin *p);

/* ---- rendering ------------------------------------------------------------------- */

/* Loads the default plugins, checks the configurations (tt_session_check), builds the accel
 * over the scene, creates the integrator and a black film of the camera's size with the AOV
 * planes in `aov_mask` (TT_AOV_* bits). Once per session; a scene is required. */
TT_API tt_status tt_session_start(tt_session *s, uint32_t aov_mask);

/* Non-zero once tt_session_start succeeded. */
TT_API int tt_session_started(const tt_session *s);

/* The accel and integrator plugins the session renders with (NULL before start unless
 * loaded), their interface tables, and the objects (NULL before start). */
TT_API tt_loaded_plugin *tt_session_accel_plugin(const tt_session *s);
TT_API tt_loaded_plugin *tt_session_integrator_plugin(const tt_session *s);
TT_API tt_accel *tt_session_accel(const tt_session *s);
TT_API tt_integrator *tt_session_integrator(const tt_session *s);

/* The session's film (NULL before start). */
TT_API tt_film *tt_session_film(tt_session *s);

/* Renders one progressive pass of `spp` samples per pixel (0: 1) into the film, continuing
 * the sample sequence of the passes before, and accounts it in the session's statistics.
 * `stats` (may be NULL) receives the pass statistics, its time_ms the pass's wall time on
 * the host's clock. TT_ERR_INTERRUPTED when host->should_stop() cut the pass short (what was
 * rendered is in the film; the pass is not counted). */
TT_API tt_status tt_session_render_pass(tt_session *s, uint32_t spp, tt_pass_stats *stats);

/* Fills `ctx` for a pass of the session's scene and accel into the session's film with its
 * camera, seed and sample offset (what tt_session_render_pass renders next); a caller may
 * then change film, camera, prev_camera, seed, spp, jitter (a sequence frame, a supersampled
 * reference) and render it with tt_session_render_ctx. */
TT_API void tt_session_init_ctx(tt_session *s, tt_render_ctx *ctx);

/* Renders `ctx` with the session's integrator, after setting its scene and accel to the
 * session's (the film may be any of the camera's size). Nothing is accounted: a pass
 * outside the progressive image. */
TT_API tt_status tt_session_render_ctx(tt_session *s, const tt_render_ctx *ctx,
                                       tt_pass_stats *stats);

/* Clears the film and the integrator's accumulated state and restarts the sample sequence
 * (the statistics keep counting). */
TT_API void tt_session_reset(tt_session *s);

/* Rebuilds the accel with `config` (NULL: the session's accel configuration); the old
 * structure is destroyed first, so on failure no accel is left (rebuild again to render).
 * `*build_ms` (may be NULL): the build time the accel reports, else the wall time. */
TT_API tt_status tt_session_rebuild_accel(tt_session *s, const tt_config *config, double *build_ms);

/* Applies `config` (of the plugin's space) to the plugin at registry `index` after start:
 * accel: rebuild; integrator: configure (its accumulated state survives); post: configure
 * the session's post-filter instance of tuning targets. `*build_ms` (may be NULL) is the
 * build time, 0 when nothing was built. The session's configuration is not changed. */
TT_API tt_status tt_session_apply(tt_session *s, size_t index, const tt_config *config,
                                  double *build_ms);

/* What the session's passes and builds measured since it was created. */
typedef struct tt_session_stats {
  uint32_t struct_size;               /* sizeof(tt_session_stats) as the caller was built */
  uint32_t passes;                    /* progressive passes completed */
  uint32_t spp;                       /* samples per pixel in the film (since the last reset) */
  uint64_t total_spp;                 /* samples per pixel rendered, resets included */
  double render_ms;                   /* wall time of all passes, interrupted ones included */
  uint64_t rays, samples, nonfinite;  /* summed over passes */
  double build_ms;                    /* the last successful accel build */
  tt_accel_build_stats build;         /* statistics of the last successful build */
  tt_pass_stats last_pass;            /* the last completed pass (integrator metrics) */
  double metric_sums[TT_MAX_METRICS]; /* per metric slot, summed over completed passes */
  uint64_t seed;                      /* the seed of the passes (scene's render.seed unless set) */
} tt_session_stats;

/* Fills `out` up to out->struct_size. */
TT_API void tt_session_get_stats(const tt_session *s, tt_session_stats *out);

/* Sets the seed of the passes (default: the scene's render.seed). */
TT_API void tt_session_set_seed(tt_session *s, uint64_t seed);

/* ---- tuning (tunetrace/tuning.h) ------------------------------------------------- */

/* Fills `out` with callbacks through which a tuning session (tt_tuning_run, _verify,
 * _apply_best) measures the plugin at registry `index` in this session: apply rebuilds the
 * accel, configures the integrator, or creates/configures a post-filter instance; render
 * adds one pass to the film (the tuning passes accumulate into the image, as the thesis'
 * online loop) and, when `want_images` is non-zero, gives the image that pass alone
 * rendered (splats included). A post target's render also runs the filter over the film.
 * Valid until the session is destroyed or the next call. After tt_session_start. */
TT_API tt_status tt_session_tuning_target(tt_session *s, size_t index, int want_images,
                                          tt_tuning_target *out);

/* What a tuning run of the session searches (tt_session_tuning_plan). */
typedef struct tt_tuning_plan {
  uint32_t struct_size;     /* sizeof(tt_tuning_plan) as the caller was built */
  size_t target_index;      /* the target's registry index (tt_session_config_at) */
  tt_loaded_plugin *target; /* the plugin tuned */
  const tt_space *space;    /* its full space: what is measured and checked */
  tt_space *search;         /* the searched parameters (a tt_space_subset of `space` whose
                                  defaults are the configured values), or NULL: all of space.
                                  Owned by the plan: tt_tuning_plan_release */
  const char *objective;    /* the default objective: the target's tuning hint's
                                  (tuning_hint.h), else "render"; valid while the plugin is
                                  loaded */
} tt_tuning_plan;

/* Plans a tuning run the way host and the Python API run one: the target is the loaded
 * plugin named `target`, or with NULL an integrator that serves a tuning hint and has
 * tunable parameters (PSSMLT), else the accel (its parameters change speed, never the
 * image); it must be an accel, integrator or post plugin with a non-empty space. The
 * target's hint setup ({"binning": true}) is applied to its configuration and the values
 * set on it with tt_session_set are put back on top (the user's settings win). The searched
 * parameters are the `count` names of `params`, or with NULL the hint's tunable list, else
 * all. Errors name the plugin (and the parameter). Release the plan with
 * tt_tuning_plan_release. */
TT_API tt_status tt_session_tuning_plan(tt_session *s, const char *target,
                                        const char *const *params, size_t count,
                                        tt_tuning_plan *out);

/* Frees what the plan owns (its search space) and clears it; NULL or a cleared plan: no-op. */
TT_API void tt_tuning_plan_release(tt_tuning_plan *plan);

/* Fills `out` with the state the plugin at `index` is measured in: the scene id and file,
 * the camera (position, target, up, fov_y, resolution, then the members of `camera_extra`,
 * a JSON object text or NULL) and the context (spp per measurement, threads, every other
 * rendering plugin with its version and configuration, then the members of
 * `context_extra`) and the scene indicators (thesis Table 3.2) when `indicators` is
 * non-zero. Strings are owned by the session, valid until the next call. */
TT_API tt_status tt_session_tuning_state(tt_session *s, size_t index, uint32_t spp,
                                         const char *camera_extra, const char *context_extra,
                                         int indicators, tt_tuning_state *out);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_SESSION_H */
