/* host: tuning along an animated sequence (--sequence A:B with a tuner, or --explore N).
 *
 * The frames are the measurements, rendered once each inside the one process that writes
 * the sequence: the search (tunetrace/tuning.h, ask/tell) is asked for a configuration of
 * the accel at the start of a window of --tune-window frames; the configuration takes over
 * at the window's first frame -- that frame's accel update is a build from scratch with it
 * (tt_session_set_time_config), unless it is the configuration already running -- and the
 * following frames update as it says (refit, or rebuild every N frames). The measurement is
 * the window's mean per-frame update ms ("build" of the objective) and render ms, so a refit
 * schedule pays for the rebuild it starts from and for the refitted tree's slower frames.
 * Each window is a state of its own: the scene posed at the window's first frame (its
 * indicators computed from that frame's geometry), the sequence time and frame in the
 * state's camera and context, so the database keeps per-frame records and answers only
 * what was measured at the same frame. Once the search is done the best configuration runs
 * the remaining frames. The manifest says per frame which window and configuration ran. */
#include "sequence_internal.h"
#include "hybrid_shared.h"
#include "tune.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TT__SEQ_TUNE_WINDOW 8u /* default frames per measurement */

struct tt__seq_tune {
  tt_loaded_plugin *target; /* the accel */
  size_t index;             /* its registry index */
  tt_tuning_plan plan;      /* its space and searched parameters */
  const char *objective;
  tt_tunedb *db;
  tt_tuning *tuning;
  tt_config *asked;   /* the configuration of the current window */
  tt_config *running; /* the configuration the accel runs with */
  const char *mode;   /* "tune" or "explore" */
  uint32_t window, in_window, windows, measured;
  int measuring; /* the current window measures `asked` for the search */
  int searching; /* the search has not said it is done */
  double sum_update, sum_render;
  char *note; /* the manifest members of the window's frames */
};

/* The accel's plan along a sequence, shared by --tune / --explore and --hybrid: --tune may name
 * only the accel (the frames measure its update + render), the searched parameters are
 * --tune-params or all its tunable ones (the update method included: the scene moves), and
 * the objective is the frames' times (render, build = the update, or both; default both).
 * `job` names the caller in messages. Prints, exit code. */
int tt__seq_accel_plan(tt__seq *s, const char *job, tt_tuning_plan *plan, const char **objective,
                       tt_objective *obj) {
  const tt__host_options *opt = s->opt;
  const char *accel = tt_loaded_plugin_entry(s->ses.accel_p)->name;
  if (opt->tune && strcmp(opt->tune, accel)) {
    tt__say("--tune %s: %s tunes the accel (%s), whose per-frame update + render the frames "
            "measure\n",
            opt->tune, job, accel);
    return TT_EXIT_USAGE;
  }
  const char *names[256];
  size_t n = 0;
  char buf[4096];
  if (opt->tune_params) {
    snprintf(buf, sizeof buf, "%s", opt->tune_params);
    for (char *tok = strtok(buf, ","); tok && n < 256; tok = strtok(NULL, ",")) names[n++] = tok;
  }
  plan->struct_size = sizeof *plan;
  if (tt_session_tuning_plan(s->ses.lib, accel, opt->tune_params ? names : NULL, n, plan) !=
      TT_OK) {
    tt__say("%s: %s\n", job, tt_last_error());
    return TT_EXIT_USAGE;
  }
  *objective = opt->objective ? opt->objective : "build+render";
  if (tt__parse_objective("--objective", *objective, obj)) return TT_EXIT_USAGE;
  if (obj->kind == TT_OBJECTIVE_RENDER || obj->kind == TT_OBJECTIVE_BUILD ||
      obj->kind == TT_OBJECTIVE_TOTAL)
    return TT_EXIT_OK;
  tt__say("--objective %s: along a sequence a measurement is frames' times: render, build "
          "(the per-frame accel update) or build+render (default)\n",
          *objective);
  return TT_EXIT_USAGE;
}

/* The target: the accel, its searched parameters and the objective (tt__seq_accel_plan). */
static int tt__seq_tune_plan(tt__seq *s, struct tt__seq_tune *t) {
  tt_objective obj;
  int rc = tt__seq_accel_plan(s, "tuning along a sequence", &t->plan, &t->objective, &obj);
  if (rc != TT_EXIT_OK) return rc;
  t->target = t->plan.target;
  t->index = t->plan.target_index;
  return TT_EXIT_OK;
}

/* The library's tuning session over the accel, in the first frame's state (set per window). */
static int tt__seq_tune_session(tt__seq *s, struct tt__seq_tune *t, tt_loaded_plugin *tuner_p) {
  const tt__host_options *opt = s->opt;
  int explore = opt->explore > 0;
  const tt_plugin *e = tt_loaded_plugin_entry(t->target);
  tt_tuning_desc d = {.struct_size = sizeof d};
  d.host = s->ses.host;
  d.space = t->plan.space;
  d.start = s->ses.configs[t->index];
  d.search = t->plan.search;
  d.objective = t->objective;
  d.tuner = explore ? NULL : tt_loaded_plugin_iface(tuner_p);
  d.tuner_settings = explore ? NULL
                             : s->ses.configs[tt_session_plugin_index(
                                   s->ses.lib, tt_loaded_plugin_entry(tuner_p)->name)];
  d.tuner_name = explore ? NULL : tt_loaded_plugin_entry(tuner_p)->name;
  d.seed = s->seed;
  d.iterations = explore           ? opt->explore
                 : opt->iterations ? opt->iterations
                                   : TT_HOST_DEFAULT_ITERATIONS;
  d.spp = s->spp;
  d.plugin = e->name;
  d.plugin_version = e->version;
  d.db = t->db;
  if (tt_tuning_create(&d, &t->tuning) == TT_OK) return TT_EXIT_OK;
  tt__say("tuning: %s\n", tt_last_error());
  t->tuning = NULL;
  return TT_EXIT_FAILURE;
}

int tt__seq_tune_create(tt__seq *s) {
  const tt__host_options *opt = s->opt;
  tt_loaded_plugin *tuner_p = tt_registry_find_kind(s->ses.reg, TT_KIND_TUNER);
  int rc = tt__tune_check(opt, tuner_p);
  if (rc != TT_EXIT_OK || (!tuner_p && !opt->explore)) return rc;
  if (!s->animated) {
    tt__say("tuning along a sequence measures each frame's accel update + render, and %s "
            "does not move: tune a still with --tune (no --sequence), a camera path with "
            "--hybrid\n",
            opt->scene);
    return TT_EXIT_USAGE;
  }
  struct tt__seq_tune *t = s->tune = calloc(1, sizeof *t);
  if (!t) return TT_EXIT_FAILURE;
  t->mode = opt->explore ? "explore" : "tune";
  t->window = opt->tune_window ? opt->tune_window : TT__SEQ_TUNE_WINDOW;
  t->searching = 1;
  if ((rc = tt__seq_tune_plan(s, t)) != TT_EXIT_OK) return rc;
  if ((rc = tt__tune_open_db(opt, s->ses.host, &t->db)) != TT_EXIT_OK) return rc;
  t->asked = tt_config_clone(s->ses.configs[t->index]);
  t->running = tt_config_clone(s->ses.configs[t->index]);
  if (!t->asked || !t->running) return TT_EXIT_FAILURE;
  if ((rc = tt__seq_tune_session(s, t, tuner_p)) != TT_EXIT_OK) return rc;
  s->ses.host->log(TT_LOG_INFO, NULL,
                   "%s %s along the sequence: %u frames per measurement, objective %s "
                   "(per-frame accel update + render), database %s",
                   opt->explore ? "exploring" : "tuning", tt_loaded_plugin_entry(t->target)->name,
                   t->window, t->objective, t->db ? tt_tunedb_path(t->db) : "none");
  return TT_EXIT_OK;
}

/* The state of the window starting at frame f: the scene posed at the frame (the update
 * poses it again, identically), its indicators, the frame in the camera and context. */
static int tt__seq_tune_state(tt__seq *s, uint32_t f, tt_tuning_state *state) {
  struct tt__seq_tune *t = s->tune;
  double time = f / s->fps;
  char camera[96], context[256];
  snprintf(camera, sizeof camera, "{\"sequence_time\":%.9g}", time);
  snprintf(context, sizeof context,
           "{\"measure\":\"%s\",\"sequence\":{\"frame\":%u,\"fps\":%.9g,\"window\":%u}}",
           TT__SEQ_MEASURE, f, s->fps, t->window);
  if (tt_scene_set_time(s->ses.scene, time, time - 1.0 / s->fps) != TT_OK ||
      tt_session_tuning_state(s->ses.lib, t->index, s->spp, camera, context, 1, state) != TT_OK) {
    tt__say("frame %u: tuning state: %s\n", f, tt_last_error());
    return TT_EXIT_FAILURE;
  }
  return TT_EXIT_OK;
}

/* The manifest members of the window's frames: the window, whether it measures, and (its
 * first frame only) the configuration. */
static void tt__seq_tune_note(tt__seq *s, int first) {
  struct tt__seq_tune *t = s->tune;
  free(t->note);
  t->note = NULL;
  char *json = first ? tt_config_to_json(t->asked) : NULL;
  size_t n = 160 + (json ? strlen(json) : 0);
  t->note = malloc(n);
  if (t->note)
    snprintf(t->note, n, ", \"tune\": {\"window\": %u, \"mode\": \"%s\"%s%s}", t->windows,
             t->measuring ? t->mode : "best", json ? ", \"config\": " : "", json ? json : "");
  tt_free(json);
  s->frame_note = t->note;
}

/* Window start at frame f: the state, then the search's next configuration (or, once it is
 * done, the best); an exit code. */
static int tt__seq_tune_begin(tt__seq *s, uint32_t f) {
  struct tt__seq_tune *t = s->tune;
  t->measuring = 0;
  if (t->searching) {
    tt_tuning_state state;
    int rc = tt__seq_tune_state(s, f, &state);
    if (rc != TT_EXIT_OK) return rc;
    tt_status st = tt_tuning_set_state(t->tuning, &state);
    if (st == TT_OK) st = tt_tuning_next(t->tuning, t->asked);
    if (st == TT_ERR_INTERRUPTED) return TT_EXIT_INTERRUPTED;
    if (st != TT_OK && st != TT_DONE) {
      tt__say("frame %u: tuning: %s\n", f, tt_last_error());
      return TT_EXIT_FAILURE;
    }
    t->measuring = st == TT_OK;
    t->searching = st == TT_OK;
  }
  if (!t->measuring && tt_tuning_best(t->tuning, t->asked, NULL) != TT_OK) {
    tt__say("frame %u: tuning: %s\n", f, tt_last_error());
    return TT_EXIT_FAILURE;
  }
  t->windows++;
  t->in_window = 0;
  t->sum_update = t->sum_render = 0;
  if (!tt_config_equal(t->asked, t->running)) {
    tt_config_copy(t->running, t->asked);
    s->switch_config = t->running; /* the first frame's update builds with it */
  }
  return TT_EXIT_OK;
}

/* Window end: the mean per-frame update and render ms reported to the search. */
static int tt__seq_tune_end(tt__seq *s) {
  struct tt__seq_tune *t = s->tune;
  if (!t->measuring || !t->in_window) return TT_EXIT_OK;
  tt_tuning_measurement m = {.struct_size = sizeof m};
  m.status = TT_OK;
  m.build_ms = t->sum_update / t->in_window;
  m.render_ms = t->sum_render / t->in_window;
  t->measuring = 0;
  t->measured++;
  if (tt_tuning_report(t->tuning, &m, NULL) == TT_OK) return TT_EXIT_OK;
  tt__say("tuning: %s\n", tt_last_error());
  return TT_EXIT_FAILURE;
}

int tt__seq_tune_before(tt__seq *s, uint32_t f) {
  struct tt__seq_tune *t = s->tune;
  int rc = TT_EXIT_OK;
  if (t->in_window == 0 && (rc = tt__seq_tune_begin(s, f)) != TT_EXIT_OK) return rc;
  tt__seq_tune_note(s, t->in_window == 0);
  return TT_EXIT_OK;
}

int tt__seq_tune_after(tt__seq *s, uint32_t f) {
  struct tt__seq_tune *t = s->tune;
  s->frame_note = NULL;
  t->sum_update += s->update_ms;
  t->sum_render += s->render_ms;
  int rc = TT_EXIT_OK;
  if (++t->in_window == t->window || f == s->opt->seq_last) {
    rc = tt__seq_tune_end(s);
    t->in_window = 0;
  }
  return rc;
}

int tt__seq_tune_finish(tt__seq *s, int rc) {
  struct tt__seq_tune *t = s->tune;
  if (!t->tuning) return rc;
  tt_tuning_stats st = {.struct_size = sizeof st};
  tt_tuning_get_stats(t->tuning, &st);
  double best = NAN, def = NAN;
  tt_tuning_best(t->tuning, NULL, &best);
  tt_tuning_default_cost(t->tuning, &def);
  s->ses.host->log(TT_LOG_INFO, NULL,
                   "tuning along the sequence: %u windows of %u frames, %u measured (%u from "
                   "the database), search %s; best %.4g ms per frame, default %.4g: %s",
                   t->windows, t->window, st.measured, st.cached,
                   t->searching ? "cut short by the sequence's end" : "done", best, def,
                   tt_tuning_best_json(t->tuning));
  if (st.unrecorded) {
    s->ses.host->log(TT_LOG_ERROR, NULL,
                     "tuning: %u of %u measurements could not be recorded in the database %s",
                     st.unrecorded, st.measured, tt_tunedb_path(t->db));
    if (rc == TT_EXIT_OK) rc = TT_EXIT_OUTPUT;
  }
  return rc;
}

void tt__seq_tune_free(tt__seq *s) {
  struct tt__seq_tune *t = s->tune;
  if (!t) return;
  tt_tuning_destroy(t->tuning);
  tt_tuning_plan_release(&t->plan);
  tt_tunedb_close(t->db);
  tt_config_destroy(t->asked);
  tt_config_destroy(t->running);
  free(t->note);
  free(t);
  s->tune = NULL;
  s->frame_note = NULL;
}
