/* tunetrace: the online tuning loop (thesis Fig. 3.2 and 3.14) as a library object.
 *
 * A tuning session searches the parameter space of one plugin (the target: an accel, an
 * integrator, a post-filter, or anything with a tt_space) for the configuration with the
 * lowest cost under an objective (render ms, build ms, build+render, an integrator metric,
 * rRMSE against a reference). The session owns the search: the default configuration is
 * measured first, then a tuner plugin (tt.tuner/1) proposes configurations, or, without a
 * tuner, uniform random draws explore the space. Every sample is recorded in the tuning
 * database when one is given (tunedb.h), and a configuration the database already holds
 * for the same state on this machine is answered from it, not measured again (thesis 3.3);
 * a configuration measured earlier in the same session is measured again (a tuner
 * re-measuring its incumbent against noise).
 *
 * A tuner of ABI 1.1 (tuner.h) gets set_context before its first proposal: the state's
 * indicators normalised as the predictors see them (tunetrace/indicators.h), the default's
 * cost and the iteration budget.
 *
 * Two ways to drive it:
 *  - ask/tell: tt_tuning_next gives the next configuration that needs a measurement, the
 *    caller applies it, renders, and reports what it measured with tt_tuning_report;
 *  - library-driven: tt_tuning_run does the whole loop through a tt_tuning_target whose
 *    callbacks apply a configuration and render one pass.
 * Then tt_tuning_best gives the winner, tt_tuning_verify measures default and best side by
 * side (alternating rounds, medians of per-round ratios) and keeps the default when the best
 * was not faster, tt_tuning_apply_best leaves the target running the kept configuration.
 *
 * Ownership: the session copies what it keeps from the descriptor (configurations, state,
 * strings); the space, the tuner table, the database and the reference image are borrowed
 * and must outlive it. Strings and samples it returns are owned by the session and valid
 * until it is destroyed (sample pointers: until the next call that adds a sample).
 * Threads: a session is used by one thread at a time; the target callbacks are called on
 * that thread.
 *
 * Extending (append-only, like every public table): new descriptor fields go at the end of
 * tt_tuning_desc (the library reads only what desc->struct_size covers); new per-sample
 * fields at the end of tt_tuning_sample; new functions below the last one. Planned: a state
 * change (new camera or indicator vector) that restarts or continues the search per state,
 * and prediction (tt.predictor/1) fed from the samples, for the hybrid loop of thesis 3.3.
 */
#ifndef TUNETRACE_TUNING_H
#define TUNETRACE_TUNING_H

#include <tunetrace/common.h>
#include <tunetrace/host.h>
#include <tunetrace/integrator.h>
#include <tunetrace/params.h>
#include <tunetrace/scene.h>
#include <tunetrace/tunedb.h>
#include <tunetrace/tuner.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- objectives -------------------------------------------------------------------- */

/* What one measurement minimises. */
typedef enum tt_objective_kind {
  TT_OBJECTIVE_RENDER = 1, /* render ms of the measurement pass */
  TT_OBJECTIVE_BUILD = 2,  /* build ms of applying the configuration (accel targets) */
  TT_OBJECTIVE_TOTAL = 3,  /* build + render ms */
  TT_OBJECTIVE_METRIC = 4, /* a metric the integrator's pass publishes (tt_pass_stats) */
  TT_OBJECTIVE_RRMSE = 5   /* rRMSE of the pass's own image against a reference */
} tt_objective_kind;

/* How a metric becomes a cost. */
typedef enum tt_objective_goal {
  TT_OBJECTIVE_MIN = 0,   /* cost = value */
  TT_OBJECTIVE_MAX = 1,   /* cost = -value */
  TT_OBJECTIVE_TARGET = 2 /* cost = |value - target| */
} tt_objective_goal;

typedef struct tt_objective {
  tt_objective_kind kind;
  tt_objective_goal goal; /* metric objectives */
  double target;          /* TT_OBJECTIVE_TARGET */
  char metric[64];        /* metric name (metric objectives) */
  char spec[192];         /* canonical spec: the database's objective column */
} tt_objective;

/* Parses an objective spec: render, build, build+render (also "total", "render+build"),
 * rrmse, metric:NAME, metric:NAME:min, metric:NAME:max, metric:NAME:target=X. The message
 * of TT_ERR_PARSE quotes the spec and says what was expected. Thread-safe. */
TT_API tt_status tt_objective_parse(const char *spec, tt_objective *out);

/* rRMSE of an RGB image against a reference luminance image, over Rec. 709 luminance:
 * sqrt(mean((L - R)^2 / (R^2 + 1e-3))). The one definition of rRMSE in tunetrace (the
 * tuning objective; tools/common/images.py mirrors it). Thread-safe. */
TT_API double tt_rrmse(const float *rgb, const double *reference_luminance, size_t pixel_count);

/* Rec. 709 luminance of `pixel_count` pixels of `channels` channels (1: the value itself,
 * 3 or more: 0.2126 R + 0.7152 G + 0.0722 B) into `out`. Thread-safe. */
TT_API void tt_luminance(const float *pixels, uint32_t channels, size_t pixel_count, double *out);

/* ---- the session ------------------------------------------------------------------- */

typedef struct tt_tuning tt_tuning; /* opaque session handle */

/* The state a measurement is taken in: the database key besides the target and its
 * configuration. Strings are copied by the session. */
typedef struct tt_tuning_state {
  uint32_t struct_size;   /* sizeof(tt_tuning_state) */
  const char *scene_id;   /* tt_scene_id (required with a database) */
  const char *scene;      /* scene file, for people */
  const char *camera;     /* JSON of the view (position, target, up, fov_y, resolution) */
  const char *context;    /* JSON of what else shapes the cost (spp, threads, the other
                               plugins and their configurations, the reference) */
  int32_t has_indicators; /* non-zero: indicators[] is set (thesis Table 3.2) */
  double indicators[TT_SCENE_INDICATOR_COUNT];
} tt_tuning_state;

/* One sample of the session: the default configuration (iteration -1) or a proposal. */
typedef struct tt_tuning_sample {
  uint32_t struct_size; /* sizeof(tt_tuning_sample) as the library was built */
  int32_t iteration;    /* -1: the default configuration; else 0, 1, ... */
  const char *config;   /* canonical JSON of the full configuration */
  double cost;          /* TT_COST_INFEASIBLE unless status is TT_TUNEDB_OK */
  double build_ms, render_ms;
  int32_t status;     /* tt_tunedb_status: OK, INFEASIBLE (constraints), FAILED */
  int32_t cached;     /* non-zero: answered by the database, not measured */
  const float *image; /* the measurement pass's own image (width x height RGB) when
                               the objective or the caller asked for one, else NULL; valid
                               during on_sample only */
} tt_tuning_sample;

/* What the caller measured for one configuration (tt_tuning_report, target->render). */
typedef struct tt_tuning_measurement {
  uint32_t struct_size;      /* sizeof(tt_tuning_measurement) */
  tt_status status;          /* TT_OK; TT_ERR_INTERRUPTED: the user asked to stop (nothing is
                               recorded); any other error: a failed measurement */
  double build_ms;           /* build time of applying the configuration (0: none) */
  double render_ms;          /* wall ms of the measurement pass */
  const tt_pass_stats *pass; /* the pass's metrics (metric objectives), or NULL */
  const float *image;        /* the pass's own image, width x height RGB (rrmse), or NULL */
} tt_tuning_measurement;

/* Callbacks through which tt_tuning_run, tt_tuning_verify and tt_tuning_apply_best act on
 * the target. Both are called on the session's thread. */
typedef struct tt_tuning_target {
  uint32_t struct_size; /* sizeof(tt_tuning_target) */
  void *user;
  /* Applies `config` (of the session's space) to the target (an accel is rebuilt, an
   * integrator reconfigured); `*build_ms` receives the build time (0 when nothing is
   * built). TT_OK or the plugin's error (the configuration counts as failed). */
  tt_status (*apply)(void *user, const tt_config *config, double *build_ms);
  /* Renders one pass of `spp` samples per pixel with the applied configuration and fills
   * m->render_ms, m->pass and (when the session wants images) m->image. `m` is NULL for a
   * warm-up pass (desc->warmup_passes): render, measure nothing. TT_OK,
   * TT_ERR_INTERRUPTED when the user asked to stop, or the failure. */
  tt_status (*render)(void *user, uint32_t spp, tt_tuning_measurement *m);
} tt_tuning_target;

/* Everything a session is created from. Zero-initialise, set struct_size, fill in. */
typedef struct tt_tuning_desc {
  uint32_t struct_size;            /* sizeof(tt_tuning_desc) as the caller was built */
  const tt_host *host;             /* log, clock, progress, should_stop; NULL: tt_default_host() */
  const tt_space *space;           /* the target's full space (required; borrowed) */
  const tt_config *start;          /* the target's configured values: the default configuration,
                               measured first, and the value of every parameter not searched
                               (NULL: the space's defaults; copied) */
  const tt_space *search;          /* the searched parameters: a tt_space_subset of `space` with
                               the configured values as defaults (borrowed), or NULL: all */
  const char *objective;           /* objective spec (tt_objective_parse); NULL: "render" */
  const tt_tuner_iface *tuner;     /* the search; NULL: random exploration */
  const tt_config *tuner_settings; /* the tuner's own settings, or NULL for its defaults */
  const char *tuner_name;          /* for the log and the database (NULL: exploration) */
  uint64_t seed;                   /* the tuner's seed; exploration draws from it too */
  uint32_t iterations;             /* configurations to ask for after the default (>= 0) */
  uint32_t spp;                    /* samples per pixel of one measurement pass (0: 1) */
  uint32_t warmup_passes;          /* tt_tuning_run: unmeasured 1-spp passes before the default
                               (the first pass pays page faults and lazy set-up) */
  double time_budget_s;            /* > 0: stop asking for configurations after this long */
  const char *plugin;              /* the target's plugin name (log, database; required) */
  const char *plugin_version;
  tt_tunedb *db;                     /* the tuning database, or NULL (borrowed) */
  const tt_tuning_state *state;      /* the state of the measurements (NULL: unknown) */
  const char *run_id;                /* database run id (NULL: generated from time and pid) */
  uint32_t width, height;            /* size of the pass images (rrmse objective, want_images) */
  const double *reference_luminance; /* width x height (rrmse; borrowed) */
  int32_t want_images;               /* non-zero: ask the target for each pass's own image, given to
                               on_sample (the rrmse objective asks in any case) */
  /* Called after every sample is recorded (measured or answered by the database) and fed
   * to the tuner, e.g. to write the pass image, feed a model or save the session's state.
   * NULL: none. */
  void (*on_sample)(void *user, const tt_tuning_sample *sample);
  void *user; /* on_sample's first argument */
  /* ---- appended for the hybrid loop (tunetrace/hybrid.h) ---- */
  /* The database's mode column for every sample of this session (e.g. "exploit" for the
   * one configuration a model predicted); NULL: "default" for the default and "tune" /
   * "explore" for the proposals. */
  const char *mode;
} tt_tuning_desc;

/* Creates a session. TT_ERR_INVALID_ARGUMENT (a missing field), TT_ERR_PARSE (objective),
 * or the tuner's error from its create(). `*out` is owned by the caller: free with
 * tt_tuning_destroy. */
TT_API tt_status tt_tuning_create(const tt_tuning_desc *desc, tt_tuning **out);

/* Destroys the session and its tuner (NULL is ignored). */
TT_API void tt_tuning_destroy(tt_tuning *t);

/* Ask: writes the next configuration to measure into `out` (a config of the session's
 * space): the default first, then the proposals. Proposals the database answers or the
 * space's constraints reject are recorded (and fed to the tuner) without being returned.
 * TT_OK: measure `out` and call tt_tuning_report; TT_DONE: the iterations, the time budget
 * or the search (tuner convergence) are used up; TT_ERR_INTERRUPTED: host->should_stop();
 * other errors: the tuner failed (logged). Calling it again before a report returns the
 * same configuration. */
TT_API tt_status tt_tuning_next(tt_tuning *t, tt_config *out);

/* Tell: reports the measurement of the configuration tt_tuning_next returned; computes its
 * cost (`*cost`, may be NULL), records it in the session and the database and feeds it to
 * the tuner. TT_ERR_NO_DATA: a metric objective whose metric the pass did not publish
 * (nothing is recorded: the objective cannot work); TT_ERR_INTERRUPTED when m->status says
 * so; TT_ERR_INVALID_ARGUMENT without an outstanding configuration. */
TT_API tt_status tt_tuning_report(tt_tuning *t, const tt_tuning_measurement *m, double *cost);

/* The whole loop through `target`: warm-up passes, the default, then up to `iterations`
 * proposals, each applied and rendered once. TT_OK when it ran to the end (budget, time or
 * convergence), TT_ERR_INTERRUPTED, TT_ERR_NO_DATA as tt_tuning_report, or a failure. */
TT_API tt_status tt_tuning_run(tt_tuning *t, const tt_tuning_target *target);

/* The best configuration so far: the lowest mean cost over all measurements of the same
 * configuration (the default included, failures left out), so that one lucky timing does
 * not beat a configuration measured several times; the default while nothing else is
 * known. `out` (may be NULL) is a config of the session's space; `cost` may be NULL.
 * TT_ERR_NO_DATA before the default was recorded. */
TT_API tt_status tt_tuning_best(const tt_tuning *t, tt_config *out, double *cost);

/* Canonical JSON of the best and of the default configuration (owned by the session). */
TT_API const char *tt_tuning_best_json(const tt_tuning *t);
TT_API const char *tt_tuning_default_json(const tt_tuning *t);

/* Cost of the default configuration (mean over its measurements); TT_ERR_NO_DATA before it
 * was recorded. */
TT_API tt_status tt_tuning_default_cost(const tt_tuning *t, double *cost);

/* Samples in the order they were recorded ([0] is the default once recorded). */
TT_API size_t tt_tuning_sample_count(const tt_tuning *t);
TT_API const tt_tuning_sample *tt_tuning_sample_at(const tt_tuning *t, size_t index);

/* Counters of a session. */
typedef struct tt_tuning_stats {
  uint32_t struct_size; /* sizeof(tt_tuning_stats) as the caller was built */
  uint32_t requested;   /* desc->iterations */
  uint32_t iterations;  /* proposals recorded after the default */
  uint32_t measured;    /* samples measured (infeasible and failed included) */
  uint32_t cached;      /* samples answered by the database */
  uint32_t infeasible, failed;
  int32_t converged;   /* the tuner reported convergence */
  int32_t interrupted; /* the user asked to stop */
  double tuning_ms;    /* wall ms of tt_tuning_run */
  uint32_t unrecorded; /* measurements the database failed to record (a full disk):
                             * one warning is logged, then they are only counted */
  uint32_t remeasured; /* proposals of a configuration already measured in this session
                               (a tuner re-evaluating its incumbent), measured again */
} tt_tuning_stats;

/* Fills `out` up to out->struct_size. */
TT_API void tt_tuning_get_stats(const tt_tuning *t, tt_tuning_stats *out);

/* "tune" (a tuner searches) or "explore" (random draws). */
TT_API const char *tt_tuning_mode(const tt_tuning *t);
/* The parsed objective. */
TT_API const tt_objective *tt_tuning_objective(const tt_tuning *t);

/* Result of tt_tuning_verify: index 0 is the default configuration, 1 the best. */
typedef struct tt_tuning_verification {
  uint32_t struct_size; /* sizeof(tt_tuning_verification) as the caller was built */
  uint32_t rounds;      /* rounds completed */
  uint32_t spp;         /* samples per pixel per pass */
  double median_build_ms[2], median_render_ms[2], median_total_ms[2], median_cost[2];
  double render_ratio;     /* median over rounds of render best/default (NAN if none) */
  double total_ratio;      /* ... of build+render */
  double cost_ratio;       /* ... of the objective's cost */
  const double *rounds_ms; /* rounds x 2 x {build_ms, render_ms, cost}, [r][who][k];
                               owned by the session, valid until the next verify */
  /* ---- appended: what the rounds decided (tt_tuning_verdict) ---- */
  int32_t verdict;        /* TT_TUNING_CONFIRMED, _REJECTED or _DEFAULT; _UNVERIFIED when no
                               round completed */
  uint32_t best_faster;   /* rounds in which the best's cost was lower than the default's */
  double cost_difference; /* median over rounds of cost best - default (NAN if none) */
  const char *reason;     /* one plain sentence saying which configuration is kept and why
                               (owned by the session, valid until the next verify) */
} tt_tuning_verification;

/* What paired verification (tt_tuning_verify) decided about the search's best. */
typedef enum tt_tuning_verdict {
  TT_TUNING_UNVERIFIED = 0, /* not verified (or the best changed since): the best is kept */
  TT_TUNING_CONFIRMED = 1,  /* the best was faster than the default in the median round: kept */
  TT_TUNING_REJECTED = 2,   /* it was not (or it failed): the default is kept */
  TT_TUNING_DEFAULT = 3     /* the best is the default configuration itself */
} tt_tuning_verdict;

/* Measures the default and the best configuration side by side through `target`:
 * `rounds` rounds of one pass each, alternating the order (default first in even rounds),
 * so a drift in machine speed hits both alike. Nothing is recorded in the database (these
 * are repeats, not new states). Then decides: the best is kept only when its cost was lower
 * than the default's in the median round (median of the per-round differences < 0);
 * otherwise the session keeps the default (tt_tuning_kept_json, tt_tuning_apply_best): the
 * search's best is the luckiest of many noisy passes, and a configuration that is not faster
 * when measured side by side must not replace the default. The decision is logged as one
 * sentence and returned in out->verdict / out->reason. TT_OK, TT_ERR_INTERRUPTED (out holds
 * the rounds done, judged when there is at least one), or the failure of a configuration
 * (logged; a failing best is rejected). */
TT_API tt_status tt_tuning_verify(tt_tuning *t, const tt_tuning_target *target, uint32_t rounds,
                                  tt_tuning_verification *out);

/* Applies the kept configuration (tt_tuning_kept_json: the best, or the default when
 * verification rejected the best) through `target` unless the target already runs it (the
 * last configuration the session applied); `*build_ms` (may be NULL) gets the build time
 * (0 when nothing was applied). */
TT_API tt_status tt_tuning_apply_best(tt_tuning *t, const tt_tuning_target *target,
                                      double *build_ms);

/* Serialises the session between samples (not while a configuration is outstanding): its
 * samples, counters, the next iteration and the tuner's save_state, as JSON (free with
 * free()). A session created from the same descriptor and given it with
 * tt_tuning_load_state continues exactly where this one stopped (the host's --resume). */
TT_API tt_status tt_tuning_save_state(const tt_tuning *t, char **json);

/* Restores a state of tt_tuning_save_state into a fresh session (before its first next());
 * errors name `source` and what differs (another target, objective, tuner, state, default,
 * or a tuner state its tuner refuses); on error the session is left fresh. */
TT_API tt_status tt_tuning_load_state(tt_tuning *t, const char *json, const char *source);

/* The configuration the session keeps for the target after tuning (owned by the session):
 * the best, unless tt_tuning_verify rejected it, then the default. */
TT_API const char *tt_tuning_kept_json(const tt_tuning *t);

/* The verification's decision about the current best; `*reason` (may be NULL) gets its
 * sentence (NULL when unverified; owned by the session). */
TT_API tt_tuning_verdict tt_tuning_get_verdict(const tt_tuning *t, const char **reason);

/* Changes the state the next measurements are taken in (appended; tuning along a sequence:
 * each frame of an animated scene is a state, its geometry and camera another). Samples
 * asked for afterwards are looked up in and recorded to the database under `state` (copied);
 * the search goes on (the tuner keeps its course: a sequence's frames change gradually) and
 * the best is still the lowest mean over every sample of a configuration, whatever its
 * state. TT_ERR_INVALID_ARGUMENT while a configuration is outstanding (tt_tuning_next without
 * its report: a measurement belongs to the state it was asked for in), for a NULL or short
 * state, or one without scene_id in a session with a database. */
TT_API tt_status tt_tuning_set_state(tt_tuning *t, const tt_tuning_state *state);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_TUNING_H */
