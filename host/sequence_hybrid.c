/* host --hybrid --sequence A:B: hybrid online autotuning (thesis 3.3, Fig. 3.15) along an
 * animated sequence, inside the one process that renders it.
 *
 * The sequence is cut into windows of --tune-window frames (default 8; 1 makes every frame
 * a state). A window is a state: the scene posed at its first frame, the indicators of that
 * frame's geometry, the frame in the camera and context. Per state the library's hybrid
 * tuner (tunetrace/hybrid.h) draws explore or exploit through a tuning target whose one
 * measurement is the window played with a configuration: its first frame's accel update a
 * build from scratch with it, the other frames updated as it says (refit, rebuild every N
 * frames) -- except a state's first play of the configuration already running, which goes
 * on updating the running structure as the frames would without tuning (so per-frame states
 * of an unchanged configuration keep refitting) -- the cost the mean per-frame update +
 * render ms (--objective build+render,
 * default; render or build alone). Exploring searches --iterations K configurations, each
 * replaying the window (the overhead the hybrid loop exists to remove); exploiting plays the
 * model's one configuration once. Every play writes the window's frames; the window is
 * played again only when the state's final configuration (the best found) was not the last
 * one played, so the frames on disk are always those of the final configuration, and the
 * manifest says per frame which state, mode and configuration ran.
 *
 * Indicators are computed afresh per state (tt_session_tuning_state): their cost is
 * recorded per state (--stats "state_ms") and is one pass over the triangles, small against
 * the window's frames it is paid once for. */
#include "hybrid_shared.h"
#include "sequence_internal.h"
#include "tune.h"

#include <tt_util/strings.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct tt__sh_totals {
  uint32_t states, explored, exploited, fallbacks, plays, frames_played, cached;
  double sum_frames_cost; /* sum over states of the written frames' mean cost */
} tt__sh_totals;

struct tt__seq_hybrid {
  tt_tuning_plan plan; /* the accel: its space and searched parameters */
  const tt_predictor_iface *pi;
  tt_predictor *model;
  const char *predictor_name, *tuner_name, *objective;
  tt_objective obj;
  tt_tunedb *db;
  tt_hybrid *hy;
  tt_indicator_norm norm;
  double epsilon;
  uint32_t K, window;
  const char *clock;      /* ",\"clock\":\"cpu\"" or "" */
  char *context, *camera; /* the first state's, for the warm start's filter */
  cJSON *warm, *states;
  /* the current window: frames f0..f1, the configuration applied and the one last played */
  uint32_t f0, f1;
  tt_config *pending, *played;
  int has_played; /* the window was played in this state (the database may answer all) */
  int running;    /* the accel runs `played`, updated up to frame run_end */
  uint32_t run_end;
  int continued;  /* the last play continued the running structure (no first-frame build) */
  uint32_t plays; /* plays of the current state */
  double play_update, play_render; /* the last play's mean per-frame ms */
  /* the last play's manifest entries (committed once the state is done) */
  FILE *wm;
  char *wbuf;
  size_t wlen;
  long *entry; /* 2 per frame: start and end offset in wbuf */
  double state_ms;
  tt__sh_totals tot;
  int interrupted;
};

/* The searched parameters and the objective (tt__seq_accel_plan); prints, exit code. */
static int tt__sh_plan(tt__seq *s, struct tt__seq_hybrid *h) {
  return tt__seq_accel_plan(s, "--hybrid --sequence", &h->plan, &h->objective, &h->obj);
}

/* What --hybrid --sequence does not take; prints, exit code. */
static int tt__sh_check(tt__seq *s) {
  const tt__host_options *opt = s->opt;
  if (!s->animated) {
    tt__say("--hybrid --sequence: %s does not move (no animated object): its states would "
            "all be one; run --hybrid without --sequence over its camera path\n",
            opt->scene);
    return TT_EXIT_USAGE;
  }
  if (s->post) {
    tt__say("--hybrid --sequence: the post-filter %s would see replayed frames (a search "
            "plays a window once per configuration) in its history: run it over the written "
            "frames in a separate run\n",
            s->post_name);
    return TT_EXIT_USAGE;
  }
  if (opt->explore || opt->verify || opt->reference) {
    tt__say("--hybrid --sequence: %s does not apply (each window is a state, searched "
            "with --iterations K or predicted)\n",
            opt->explore  ? "--explore"
            : opt->verify ? "--verify"
                          : "--reference");
    return TT_EXIT_USAGE;
  }
  return TT_EXIT_OK;
}

/* The state of the window starting at frame f: the camera and the scene posed at the
 * frame's time (the play poses them again, identically), the frame in the camera and
 * context, the indicators of the frame's geometry. */
static int tt__sh_state(tt__seq *s, uint32_t f, tt_tuning_state *state) {
  struct tt__seq_hybrid *h = s->hybrid;
  double time = f / s->fps;
  char camera[96], context[320];
  snprintf(camera, sizeof camera, "{\"sequence_time\":%.9g}", time);
  snprintf(context, sizeof context,
           "{\"measure\":\"%s\"%s,\"sequence\":{\"frame\":%u,\"fps\":%.9g,\"window\":%u}}",
           TT__SEQ_MEASURE, h->clock, f, s->fps, h->window);
  uint64_t t0 = s->ses.host->clock_ns();
  if (tt_session_set_camera_time(s->ses.lib, time, 1.0 / s->fps) != TT_OK ||
      tt_scene_set_time(s->ses.scene, time, time - 1.0 / s->fps) != TT_OK ||
      tt_session_tuning_state(s->ses.lib, h->plan.target_index, s->spp, camera, context, 1,
                              state) != TT_OK) {
    tt__say("--hybrid: frame %u: the state: %s\n", f, tt_last_error());
    return TT_EXIT_FAILURE;
  }
  h->state_ms = (s->ses.host->clock_ns() - t0) * 1e-6;
  return TT_EXIT_OK;
}

/* Plays the window f0..f1 with h->pending: the first frame built from scratch with it, the
 * others updated as it says; each frame written, its manifest entry kept in h->wbuf until
 * the state is done. An exit code (a failed play leaves nothing in the manifest). */
static int tt__sh_play(tt__seq *s) {
  struct tt__seq_hybrid *h = s->hybrid;
  if (h->wm) fclose(h->wm);
  free(h->wbuf);
  h->wbuf = NULL;
  h->wlen = 0;
  h->wm = open_memstream(&h->wbuf, &h->wlen);
  if (!h->wm) {
    tt__say("--hybrid: out of memory\n");
    return TT_EXIT_FAILURE;
  }
  /* a state's first play of the configuration already running continues its structure, as
   * the frames would run without tuning (a refit schedule goes on); every other play starts
   * from scratch at the window's first frame */
  h->continued = h->plays == 0 && h->running && h->run_end + 1 == h->f0 &&
                 tt_config_equal(h->played, h->pending);
  tt_config_copy(h->played, h->pending);
  h->has_played = 1;
  h->plays++;
  h->running = 0;
  s->switch_config = h->continued ? NULL : h->played;
  FILE *manifest = s->manifest;
  s->manifest = h->wm;
  s->defer_commit = 1;
  double upd = 0, ren = 0;
  int rc = TT_EXIT_OK;
  for (uint32_t f = h->f0; f <= h->f1 && rc == TT_EXIT_OK; f++) {
    fflush(h->wm);
    h->entry[2 * (f - h->f0)] = ftell(h->wm);
    rc = s->step(s, f);
    fflush(h->wm);
    h->entry[2 * (f - h->f0) + 1] = ftell(h->wm);
    upd += s->update_ms;
    ren += s->render_ms;
  }
  s->manifest = manifest;
  s->defer_commit = 0;
  s->switch_config = NULL;
  uint32_t n = h->f1 - h->f0 + 1;
  h->play_update = upd / n;
  h->play_render = ren / n;
  h->tot.plays++;
  h->tot.frames_played += n;
  if (rc != TT_EXIT_OK) { /* the failed play is not in the manifest (the search goes on) */
    s->entry_open = 0;
    tt_default_host_hold_stop(0);
    return rc;
  }
  h->running = 1;
  h->run_end = h->f1;
  return rc;
}

/* The tuning target: applying a configuration keeps it; a measurement plays the window with
 * it (the cost: mean per-frame update as build_ms, mean render as render_ms). */
static tt_status tt__sh_apply(void *user, const tt_config *cfg, double *build_ms) {
  tt__seq *s = user;
  tt_config_copy(s->hybrid->pending, cfg);
  *build_ms = 0; /* the build is the first frame's update, measured by the play */
  return TT_OK;
}

static tt_status tt__sh_render(void *user, uint32_t spp, tt_tuning_measurement *m) {
  (void)spp; /* the frames render --spp samples each, the context's spp */
  tt__seq *s = user;
  if (!m)
    return TT_OK; /* no warm-up: the first frame's build pays the set-up, as in a plain
                         * sequence */
  /* a stop asked for during a search ends it before the next replay; the state's frames
   * are then not committed (the manifest lists the states done) */
  if (s->ses.host->should_stop()) return TT_ERR_INTERRUPTED;
  if (tt__sh_play(s) != TT_EXIT_OK) {
    char msg[512];
    snprintf(msg, sizeof msg, "%s", tt_last_error());
    return tt_set_error(TT_ERR_UNSUPPORTED, "frames %u..%u could not be played: %s", s->hybrid->f0,
                        s->hybrid->f1, msg);
  }
  m->build_ms = s->hybrid->play_update;
  m->render_ms = s->hybrid->play_render;
  return TT_OK;
}

/* The manifest members of the state's frames: the state, its window, mode and configuration. */
static char *tt__sh_note(const struct tt__seq_hybrid *h, const tt_hybrid_report *r) {
  size_t n = 256 + (r->config ? strlen(r->config) : 4);
  char *note = malloc(n);
  if (note)
    snprintf(note, n,
             ", \"hybrid\": {\"state\": %u, \"window\": [%u, %u], \"mode\": \"%s\", "
             "\"fallback\": %s, \"plays\": %u, \"continued\": %s, \"config\": %s}",
             r->state_index, h->f0, h->f1, r->mode == TT_HYBRID_EXPLORE ? "explore" : "exploit",
             r->fallback ? "true" : "false", h->plays, h->continued ? "true" : "false",
             r->config ? r->config : "null");
  return note;
}

/* The state's frames into the manifest (each entry with the note), committed. */
static int tt__sh_commit(tt__seq *s, const tt_hybrid_report *r) {
  struct tt__seq_hybrid *h = s->hybrid;
  char *note = tt__sh_note(h, r);
  if (!note) {
    tt__say("--hybrid: out of memory\n");
    return TT_EXIT_FAILURE;
  }
  for (uint32_t f = h->f0; f <= h->f1; f++) {
    long a = h->entry[2 * (f - h->f0)], b = h->entry[2 * (f - h->f0) + 1];
    /* the entry ends with "}\n": the note goes before it */
    fwrite(h->wbuf + a, 1, (size_t)(b - a - 2), s->manifest);
    fprintf(s->manifest, "%s}\n", note);
  }
  free(note);
  int rc = s->commit_frames(s, h->f1 - h->f0 + 1);
  return rc;
}

/* Adds the state to the totals and --stats, and logs it. */
static void tt__sh_account(tt__seq *s, const tt_hybrid_report *r, double total_ms) {
  struct tt__seq_hybrid *h = s->hybrid;
  tt__sh_totals *t = &h->tot;
  double frames_cost = h->obj.kind == TT_OBJECTIVE_RENDER  ? h->play_render
                       : h->obj.kind == TT_OBJECTIVE_BUILD ? h->play_update
                                                           : h->play_update + h->play_render;
  t->states++;
  t->explored += r->mode == TT_HYBRID_EXPLORE;
  t->exploited += r->mode == TT_HYBRID_EXPLOIT;
  t->fallbacks += r->fallback != 0;
  t->cached += r->cached;
  t->sum_frames_cost += frames_cost;
  cJSON *o = tt__hyb_state_json(r, "first_frame", h->f0, total_ms, h->plays);
  cJSON_AddNumberToObject(o, "last_frame", h->f1);
  cJSON_AddNumberToObject(o, "plays", h->plays);
  cJSON_AddBoolToObject(o, "continued", h->continued);
  cJSON_AddNumberToObject(o, "frames_cost", frames_cost);
  cJSON_AddNumberToObject(o, "frames_update_ms", h->play_update);
  cJSON_AddNumberToObject(o, "frames_render_ms", h->play_render);
  cJSON_AddNumberToObject(o, "state_ms", h->state_ms);
  cJSON_AddItemToArray(h->states, o);
  if (s->opt->quiet) return;
  char exp[64] = "";
  if (isfinite(r->predicted_cost))
    snprintf(exp, sizeof exp, ", the model expected %.4g", r->predicted_cost);
  s->ses.host->log(TT_LOG_INFO, NULL,
                   "hybrid: state %u (frames %u..%u): %s%s, %u play%s, frames %.4g ms per "
                   "frame%s",
                   r->state_index, h->f0, h->f1,
                   r->mode == TT_HYBRID_EXPLORE ? "explore" : "exploit",
                   r->fallback ? " (the default: the model has no usable prediction)" : "",
                   h->plays, h->plays == 1 ? "" : "s", frames_cost, exp);
}

/* One state: the window f0..f1 (its state, the hybrid step, the final configuration played
 * when the last play was another, the frames committed). An exit code. */
static int tt__sh_window(tt__seq *s, uint32_t f0, uint32_t f1) {
  struct tt__seq_hybrid *h = s->hybrid;
  h->f0 = f0;
  h->f1 = f1;
  h->has_played = 0;
  h->plays = 0;
  tt_tuning_state state;
  int rc = tt__sh_state(s, f0, &state);
  if (rc != TT_EXIT_OK) return rc;
  tt_tuning_target target = {sizeof target, s, tt__sh_apply, tt__sh_render};
  tt_hybrid_report r = {.struct_size = sizeof r};
  uint64_t t0 = s->ses.host->clock_ns();
  tt_status st = tt_hybrid_step(h->hy, &state, &target, &r);
  if (st == TT_ERR_INTERRUPTED) {
    h->interrupted = 1;
    return TT_EXIT_INTERRUPTED;
  }
  if (st != TT_OK) {
    tt__say("--hybrid: frames %u..%u: %s\n", f0, f1, tt_last_error());
    return TT_EXIT_FAILURE;
  }
  /* the frames written are the final configuration's */
  if (!h->has_played || !tt_config_equal(h->played, h->pending)) {
    if ((rc = tt__sh_play(s)) != TT_EXIT_OK) return rc;
  }
  double total_ms = (s->ses.host->clock_ns() - t0) * 1e-6;
  tt__sh_account(s, &r, total_ms);
  return tt__sh_commit(s, &r);
}

/* The library's hybrid tuner over the accel, its model and warm start. */
static int tt__sh_tuner(tt__seq *s, struct tt__seq_hybrid *h) {
  const tt__host_options *opt = s->opt;
  tt_loaded_plugin *tp = tt_registry_find_kind(s->ses.reg, TT_KIND_TUNER);
  tt_loaded_plugin *pp = tt_registry_find_kind(s->ses.reg, TT_KIND_PREDICTOR);
  h->tuner_name = tt_loaded_plugin_entry(tp)->name;
  h->predictor_name = tt_loaded_plugin_entry(pp)->name;
  tt_indicator_norm_init(&h->norm);
  if (opt->indicator_norm) tt_indicator_norm_parse(opt->indicator_norm, &h->norm);
  const tt_space *target = h->plan.search ? h->plan.search : h->plan.space;
  int rc = tt__hyb_model_create(s->ses.lib, s->ses.host, pp, target, &h->norm, s->seed, opt->model,
                                &h->pi, &h->model);
  if (rc != TT_EXIT_OK) return rc;
  if ((rc = tt__tune_open_db(opt, s->ses.host, &h->db)) != TT_EXIT_OK) return rc;
  h->epsilon = opt->epsilon_set ? opt->epsilon : TT_HOST_DEFAULT_EPSILON;
  h->K = opt->iterations ? opt->iterations : TT_HOST_DEFAULT_HYBRID_ITERATIONS;
  const tt_plugin *ae = tt_loaded_plugin_entry(h->plan.target);
  tt_hybrid_desc d = {.struct_size = sizeof d};
  d.host = s->ses.host;
  d.space = h->plan.space;
  d.start = s->ses.configs[h->plan.target_index];
  d.search = h->plan.search;
  d.objective = h->objective;
  d.tuner = tt_loaded_plugin_iface(tp);
  d.tuner_settings = tt_session_config(s->ses.lib, h->tuner_name);
  d.tuner_name = h->tuner_name;
  d.predictor = h->pi;
  d.model = h->model;
  d.predictor_name = h->predictor_name;
  d.epsilon = h->epsilon;
  d.explore_iterations = h->K;
  d.spp = s->spp;
  d.warmup_passes = 0;
  d.seed = s->seed;
  d.plugin = ae->name;
  d.plugin_version = ae->version;
  d.db = h->db;
  d.norm = &h->norm;
  if (tt_hybrid_create(&d, &h->hy) != TT_OK) {
    tt__say("--hybrid: %s\n", tt_last_error());
    return TT_EXIT_FAILURE;
  }
  /* the warm start compares rows with the first state's context and camera */
  tt_tuning_state st0;
  if (tt__sh_state(s, s->opt->seq_first, &st0) != TT_EXIT_OK) return TT_EXIT_FAILURE;
  h->context = tt__strdup(st0.context);
  h->camera = tt__strdup(st0.camera);
  tt__hyb_warm_args a = {s->ses.host, opt,        h->predictor_name, ae->name,
                         h->obj.spec, h->context, h->camera};
  return tt__hyb_warm_all(&a, h->hy, &h->warm);
}

int tt__seq_hybrid_create(tt__seq *s) {
  const tt__host_options *opt = s->opt;
  int rc = tt__sh_check(s);
  if (rc != TT_EXIT_OK) return rc;
  struct tt__seq_hybrid *h = s->hybrid = calloc(1, sizeof *h);
  if (!h) return TT_EXIT_FAILURE;
  h->window = opt->tune_window ? opt->tune_window : TT__SEQ_HYBRID_WINDOW;
  h->clock = opt->clock_cpu ? ",\"clock\":\"cpu\"" : "";
  h->states = cJSON_CreateArray();
  h->entry = calloc(2 * (size_t)h->window, sizeof *h->entry);
  if (!h->states || !h->entry) return TT_EXIT_FAILURE;
  if ((rc = tt__sh_plan(s, h)) != TT_EXIT_OK || (rc = tt__sh_tuner(s, h)) != TT_EXIT_OK) return rc;
  h->pending = tt_config_clone(s->ses.configs[h->plan.target_index]);
  h->played = tt_config_clone(s->ses.configs[h->plan.target_index]);
  if (!h->pending || !h->played) return TT_EXIT_FAILURE;
  s->ses.host->log(TT_LOG_INFO, NULL,
                   "hybrid along the sequence: %u frames per state, epsilon %g, explore %s for "
                   "%u iterations, exploit %s, objective %s (mean per-frame accel update + "
                   "render), database %s",
                   h->window, h->epsilon, h->tuner_name, h->K, h->predictor_name, h->objective,
                   h->db ? tt_tunedb_path(h->db) : "none");
  return TT_EXIT_OK;
}

int tt__seq_hybrid_run(tt__seq *s) {
  const tt__host_options *opt = s->opt;
  struct tt__seq_hybrid *h = s->hybrid;
  int rc = TT_EXIT_OK;
  for (uint32_t f0 = opt->seq_first; f0 <= opt->seq_last && rc == TT_EXIT_OK; f0 += h->window) {
    if (f0 > opt->seq_first && s->ses.host->should_stop()) return TT_EXIT_INTERRUPTED;
    uint32_t f1 = opt->seq_last - f0 < h->window - 1 ? opt->seq_last : f0 + h->window - 1;
    rc = tt__sh_window(s, f0, f1);
    if (f1 == opt->seq_last) break; /* f0 + window may wrap at the top of the range */
  }
  return rc;
}

/* The --stats record: the settings, the totals, every state. */
static cJSON *tt__sh_stats_json(tt__seq *s) {
  struct tt__seq_hybrid *h = s->hybrid;
  const tt__sh_totals *t = &h->tot;
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "scene", s->opt->scene);
  cJSON_AddStringToObject(root, "scene_id", tt_scene_id(s->ses.scene));
  cJSON_AddStringToObject(root, "clock", s->opt->clock_cpu ? "cpu" : "wall");
  cJSON_AddNumberToObject(root, "threads", s->ses.host->thread_count());
  cJSON_AddNumberToObject(root, "seed", (double)s->seed);
  cJSON *sj = cJSON_AddObjectToObject(root, "sequence");
  cJSON_AddNumberToObject(sj, "first", s->opt->seq_first);
  cJSON_AddNumberToObject(sj, "last", s->opt->seq_last);
  cJSON_AddNumberToObject(sj, "fps", s->fps);
  cJSON_AddNumberToObject(sj, "window", h->window);
  cJSON_AddNumberToObject(sj, "spp", s->spp);
  cJSON *hj = cJSON_AddObjectToObject(root, "hybrid");
  cJSON_AddStringToObject(hj, "predictor", h->predictor_name);
  cJSON_AddStringToObject(hj, "tuner", h->tuner_name);
  cJSON_AddNumberToObject(hj, "epsilon", h->epsilon);
  cJSON_AddNumberToObject(hj, "explore_iterations", h->K);
  cJSON_AddStringToObject(hj, "objective", h->obj.spec);
  cJSON_AddStringToObject(hj, "measure", TT__SEQ_MEASURE);
  char id[96];
  cJSON_AddStringToObject(hj, "state_space", tt_indicator_norm_id(&h->norm, id, sizeof id));
  if (s->opt->model) cJSON_AddStringToObject(hj, "model", s->opt->model);
  else cJSON_AddNullToObject(hj, "model");
  if (h->db) cJSON_AddStringToObject(hj, "db", tt_tunedb_path(h->db));
  else cJSON_AddNullToObject(hj, "db");
  cJSON_AddItemToObject(hj, "warm_start", h->warm ? h->warm : cJSON_CreateArray());
  h->warm = NULL;
  cJSON_AddNumberToObject(hj, "states_done", t->states);
  cJSON_AddNumberToObject(hj, "explored", t->explored);
  cJSON_AddNumberToObject(hj, "exploited", t->exploited);
  cJSON_AddNumberToObject(hj, "fallbacks", t->fallbacks);
  cJSON_AddNumberToObject(hj, "plays", t->plays);
  cJSON_AddNumberToObject(hj, "frames_played", t->frames_played);
  cJSON_AddNumberToObject(hj, "mean_frames_cost", t->states ? t->sum_frames_cost / t->states : 0.0);
  cJSON_AddBoolToObject(hj, "interrupted", h->interrupted);
  cJSON_AddItemToObject(hj, "states", h->states);
  h->states = NULL;
  return root;
}

int tt__seq_hybrid_finish(tt__seq *s, int rc) {
  struct tt__seq_hybrid *h = s->hybrid;
  if (!h || !h->hy || !h->tot.states) return rc; /* nothing ran: the failure said it */
  const tt__sh_totals *t = &h->tot;
  uint32_t written = t->states ? s->done_frames : 0;
  s->ses.host->log(TT_LOG_INFO, NULL,
                   "hybrid along the sequence: %u states (%u explored, %u exploited%s), %u "
                   "frames played for %u written; written frames %.4g ms per frame (mean over "
                   "states)",
                   t->states, t->explored, t->exploited,
                   t->fallbacks ? ", some with the default: no usable prediction" : "",
                   t->frames_played, written, t->states ? t->sum_frames_cost / t->states : 0.0);
  if (t->fallbacks)
    s->ses.host->log(TT_LOG_WARN, NULL,
                     "hybrid: %u of %u exploited states ran the default configuration: the "
                     "model had nothing to predict from (warm-start it with --warm-start DB, "
                     "or explore with --epsilon > 0)",
                     t->fallbacks, t->exploited);
  if (s->opt->model && rc == TT_EXIT_OK && h->pi->save(h->model, s->opt->model) != TT_OK) {
    tt__say("--model %s: %s\n", s->opt->model, tt_last_error());
    rc = TT_EXIT_OUTPUT;
  }
  if (s->opt->stats) {
    cJSON *root = tt__sh_stats_json(s);
    int wrc = tt__hyb_write_json(s->opt->stats, root);
    cJSON_Delete(root);
    if (wrc != TT_EXIT_OK && rc == TT_EXIT_OK) rc = wrc;
  }
  return rc;
}

void tt__seq_hybrid_free(tt__seq *s) {
  struct tt__seq_hybrid *h = s->hybrid;
  if (!h) return;
  tt_hybrid_destroy(h->hy);
  if (h->model) h->pi->destroy(h->model);
  tt_tunedb_close(h->db);
  tt_tuning_plan_release(&h->plan);
  tt_config_destroy(h->pending);
  tt_config_destroy(h->played);
  cJSON_Delete(h->warm);
  cJSON_Delete(h->states);
  free(h->context);
  free(h->camera);
  if (h->wm) fclose(h->wm);
  free(h->wbuf);
  free(h->entry);
  free(h);
  s->hybrid = NULL;
}
