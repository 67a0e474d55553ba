/* host: the tuning phase (thesis Fig. 3.2 / 3.14) and random exploration, as option mapping
 * and logging over the library's tuning session (tunetrace/tuning.h).
 *
 * The host chooses the target plugin and the objective from the options (or the
 * integrator's tuning hint), opens the tuning database, describes the state (camera,
 * context, indicators) and lets the tuning session run the loop through the render session's
 * tuning target (tunetrace/session.h: apply a configuration, render one measurement pass into
 * the film; the tuning passes accumulate into the image). The tuning session answers what
 * the database knows, measures the rest, and keeps the best; --verify N then measures
 * default and best side by side, so the gain is reported from one run.
 */
#include "tune.h"

#include <tt_util/hash.h>
#include <tt_util/strings.h>

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Everything one tuning phase works with. */
typedef struct tt__tune_ctx {
  tt__session *s;
  const tt__host_options *opt;
  tt__tuning *t;
  tt_loaded_plugin *target;
  size_t target_index; /* registry index of the target (its configs[] slot) */
  uint32_t target_kind;
  const tt_space *space; /* the target's full space: what is measured and checked */
  tt_space *subset;      /* the searched parameters, or NULL to search all of space */
  const char *objective_spec;
  tt_objective objective;
  tt_tunedb *db;
  uint32_t spp;
  int want_pass;              /* the pass's own image (--objective rrmse, --tune-pass-images) */
  double *ref_lum;            /* --reference as luminance, 1 per pixel */
  char ref_hash[17];          /* FNV-1a 64 of the reference's luminance (database context) */
  int explore;                /* --explore N: random configurations, no tuner */
  tt_loaded_plugin *tuner_p;  /* the tuner (NULL, or unused, with --explore) */
  tt_tuning_target target_cb; /* the render session as the tuning target */
  tt_tuning_verification v;   /* --verify's result (rounds 0: not run) */
} tt__tune_ctx;

void tt__tuning_free(tt__tuning *t) {
  if (!t) return;
  tt_tuning_destroy(t->session);
  tt_tunedb_close(t->db);
  free(t->ref_lum);
  free(t->verify_json);
  free(t);
}

/* Registry index of a loaded plugin (its configs[] slot). */
static size_t tt__index_of(const tt__session *s, const tt_loaded_plugin *p) {
  return (size_t)tt_session_plugin_index(s->lib, tt_loaded_plugin_entry(p)->name);
}

/* --resume FILE: the session's state after this sample, written atomically (tunetrace/
 * file.h: a kill during the write keeps the previous state). */
static void tt__save_resume(tt__tune_ctx *c) {
  const char *path = c->opt->resume;
  char *json = NULL;
  if (tt_tuning_save_state(c->t->session, &json) != TT_OK) {
    c->s->host->log(TT_LOG_WARN, NULL, "tuning: --resume %s: %s", path, tt_last_error());
    return;
  }
  if (tt_file_write_atomic(path, json, strlen(json)) != TT_OK)
    c->s->host->log(TT_LOG_WARN, NULL, "tuning: --resume: %s", tt_last_error());
  free(json);
}

/* --resume FILE: continue the session saved there, if any; prints and returns an exit code. */
static int tt__load_resume(tt__tune_ctx *c) {
  const char *path = c->opt->resume;
  if (access(path, F_OK) != 0) return TT_EXIT_OK; /* a first run */
  char *text = NULL;
  size_t n = 0;
  int ok = tt_file_read(path, "resume file", 0, &text, &n) == TT_OK;
  tt_status st = !ok ? TT_ERR_IO
                 : strlen(text) != n /* text after a NUL would not be read: refused */
                     ? tt_set_error(TT_ERR_PARSE, "%s: a NUL byte at offset %zu (a state is text)",
                                    path, strlen(text))
                     : tt_tuning_load_state(c->t->session, text, path);
  tt_free(text);
  if (st != TT_OK) {
    tt__say("--resume %s: %s (the file is left as it is; remove it to start "
            "afresh)\n",
            path, tt_last_error());
    return TT_EXIT_USAGE;
  }
  c->s->host->log(TT_LOG_INFO, NULL, "tuning: resumed from %s", path);
  return TT_EXIT_OK;
}

/* tt_tuning_desc.on_sample: writes the pass image of a measurement to --tune-pass-images (a
 * warning on failure) and saves the session for --resume. */
static void tt__on_sample(void *user, const tt_tuning_sample *sample) {
  tt__tune_ctx *c = user;
  if (c->opt->resume && c->t->session) tt__save_resume(c);
  const char *dir = c->opt->tune_pass_images;
  if (!dir || !sample->image || sample->cached || sample->status != TT_TUNEDB_OK) return;
  char path[4200], it[32], cs[64];
  if (sample->iteration < 0) snprintf(path, sizeof path, "%s/pass_default.exr", dir);
  else snprintf(path, sizeof path, "%s/pass_%04d.exr", dir, sample->iteration);
  snprintf(it, sizeof it, "%d", sample->iteration);
  snprintf(cs, sizeof cs, "%.17g", sample->cost);
  tt_image_meta meta[3] = {{"tunetrace:iteration", it},
                           {"tunetrace:objective", c->objective.spec},
                           {"tunetrace:cost", cs}};
  if (tt_image_write_exr(path, c->s->camera->width, c->s->camera->height, 3, sample->image, NULL,
                         meta, 3) != TT_OK)
    c->s->host->log(TT_LOG_WARN, NULL, "tuning: --tune-pass-images: %s", tt_last_error());
}

/* ---- option mapping ---- */

/* Reads --reference as luminance (RGB[A] -> Rec. 709 luminance, one channel as is) and
 * checks its size against the render's; prints and returns TT_EXIT_USAGE on a problem. */
static int tt__load_reference(tt__tune_ctx *c) {
  const char *path = c->opt->reference;
  uint32_t w = 0, h = 0, ch = 0, W = c->s->camera->width, H = c->s->camera->height;
  float *px = NULL;
  if (tt_image_read(path, &w, &h, &ch, &px) != TT_OK) {
    tt__say("--reference %s: cannot read the image: %s\n", path, tt_last_error());
    return TT_EXIT_USAGE;
  }
  if (w != W || h != H) {
    tt__say("--reference %s: the reference is %ux%u but the render is %ux%u; "
            "--objective rrmse compares pixel by pixel (render the reference with --res %ux%u)\n",
            path, w, h, W, H, W, H);
    tt_free(px);
    return TT_EXIT_USAGE;
  }
  if (ch != 1 && ch < 3) {
    tt__say("--reference %s: expected 1 (luminance) or 3-4 (RGB[A]) channels, "
            "got %u\n",
            path, ch);
    tt_free(px);
    return TT_EXIT_USAGE;
  }
  size_t n = (size_t)w * h;
  c->ref_lum = malloc(n * sizeof *c->ref_lum);
  if (!c->ref_lum) {
    tt_free(px);
    tt__say("tuning: out of memory\n");
    return TT_EXIT_FAILURE;
  }
  tt_luminance(px, ch, n, c->ref_lum);
  tt_free(px);
  uint64_t hash = TT__FNV1A64_OFFSET;
  for (size_t i = 0; i < n; i++) {
    if (!isfinite(c->ref_lum[i])) {
      tt__say("--reference %s: pixel (%zu, %zu) is not finite\n", path, i % w, i / w);
      return TT_EXIT_USAGE;
    }
    hash = tt__fnv1a64(hash, &c->ref_lum[i], sizeof c->ref_lum[i]);
  }
  snprintf(c->ref_hash, sizeof c->ref_hash, "%016llx", (unsigned long long)hash);
  return TT_EXIT_OK;
}

/* Chooses the target plugin, its searched parameters and the objective from the options
 * (the library's tuning plan: --tune or the integrator's hint or the accel, the hint's
 * setup under the user's --set, --tune-params or the hint's list); prints and returns
 * TT_EXIT_USAGE on a bad choice. */
static int tt__choose(tt__tune_ctx *c) {
  const tt__host_options *opt = c->opt;
  const char *names[256];
  size_t n = 0;
  char buf[4096];
  if (opt->tune_params) {
    snprintf(buf, sizeof buf, "%s", opt->tune_params);
    for (char *tok = strtok(buf, ","); tok && n < 256; tok = strtok(NULL, ",")) names[n++] = tok;
  }
  tt_tuning_plan plan = {.struct_size = sizeof plan};
  if (tt_session_tuning_plan(c->s->lib, opt->tune, opt->tune_params ? names : NULL, n, &plan) !=
      TT_OK) {
    tt__say("tuning: %s\n", tt_last_error());
    return TT_EXIT_USAGE;
  }
  c->target = plan.target;
  c->target_index = plan.target_index;
  c->target_kind = tt_loaded_plugin_entry(c->target)->kind;
  c->space = plan.space;
  c->subset = plan.search; /* freed with the phase */
  c->objective_spec = opt->objective ? opt->objective : plan.objective;
  if (tt__parse_objective(opt->objective ? "--objective" : "tuning hint", c->objective_spec,
                          &c->objective))
    return TT_EXIT_USAGE;
  if ((c->objective.kind == TT_OBJECTIVE_BUILD || c->objective.kind == TT_OBJECTIVE_TOTAL) &&
      c->target_kind != TT_KIND_ACCEL) {
    tt__say("--objective %s: only an accel target builds anything; %s is "
            "of kind %s (use render or metric:NAME)\n",
            c->objective_spec, tt_loaded_plugin_entry(c->target)->name,
            tt_plugin_kind_name(c->target_kind));
    return TT_EXIT_USAGE;
  }
  if (c->objective.kind == TT_OBJECTIVE_RRMSE) {
    int r = tt__load_reference(c);
    if (r != TT_EXIT_OK) return r;
  }
  const char *dir = opt->tune_pass_images;
  if (dir && mkdir(dir, 0777) != 0 && errno != EEXIST) {
    tt__say("--tune-pass-images %s: cannot create the folder: %s\n", dir, strerror(errno));
    return TT_EXIT_USAGE;
  }
  c->want_pass = c->objective.kind == TT_OBJECTIVE_RRMSE || dir;
  return TT_EXIT_OK;
}

int tt__tune_open_db(const tt__host_options *opt, const tt_host *host, tt_tunedb **db) {
  *db = NULL;
  if (opt->no_db) return TT_EXIT_OK;
  char *path = opt->db ? tt__strdup(opt->db) : tt_tunedb_default_path();
  if (!path) {
    host->log(TT_LOG_WARN, NULL,
              "tuning: no $XDG_DATA_HOME or $HOME: tuning without "
              "a database (use --db PATH)");
    return TT_EXIT_OK;
  }
  if (tt_tunedb_open(path, db) != TT_OK) {
    if (opt->db) {
      tt__say("--db: %s\n", tt_last_error());
      free(path);
      return TT_EXIT_FAILURE;
    }
    host->log(TT_LOG_WARN, NULL, "tuning: %s; tuning without a database", tt_last_error());
    *db = NULL;
  }
  free(path);
  return TT_EXIT_OK;
}

/* The state of every measurement of this phase (the database key besides the config): the
 * library's camera and context, plus what only the host knows — which camera of the path
 * (--camera-index), the clock (CPU-time costs never answer wall-time lookups, nor the other
 * way round) and the reference of an rRMSE cost (it means something only against it). */
static int tt__make_state(tt__tune_ctx *c, tt_tuning_state *state) {
  char camera[64] = "", context[4600] = "{";
  if (c->opt->camera_index_set)
    snprintf(camera, sizeof camera, "{\"path_index\":%u}", c->opt->camera_index);
  if (c->opt->clock_cpu) strcat(context, "\"clock\":\"cpu\"");
  if (c->ref_lum) {
    size_t len = strlen(context);
    cJSON *file = cJSON_CreateString(c->opt->reference);
    char *quoted = cJSON_PrintUnformatted(file);
    cJSON_Delete(file);
    snprintf(context + len, sizeof context - len,
             "%s\"reference\":{\"file\":%s,\"fnv1a64\":\"%s\"}", len > 1 ? "," : "",
             quoted ? quoted : "\"\"", c->ref_hash);
    cJSON_free(quoted);
  }
  strcat(context, "}");
  if (tt_session_tuning_state(c->s->lib, c->target_index, c->spp, camera[0] ? camera : NULL,
                              context, c->db != NULL, state) != TT_OK) {
    tt__say("tuning: %s\n", tt_last_error());
    return -1;
  }
  return 0;
}

/* --verify's result as the JSON object of --stats (malloc). */
static char *tt__verify_json(const tt_tuning_verification *v) {
  cJSON *root = cJSON_CreateObject();
  cJSON_AddNumberToObject(root, "rounds", v->rounds);
  cJSON_AddNumberToObject(root, "spp", v->spp);
  static const char *who_name[2] = {"default", "best"};
  static const char *field[3] = {"build_ms", "render_ms", "cost"};
  for (int who = 0; who < 2; who++) {
    cJSON *o = cJSON_AddObjectToObject(root, who_name[who]);
    for (int f = 0; f < 3; f++) {
      cJSON *arr = cJSON_AddArrayToObject(o, field[f]);
      for (uint32_t r = 0; r < v->rounds; r++)
        cJSON_AddItemToArray(arr, cJSON_CreateNumber(v->rounds_ms[((size_t)r * 2 + who) * 3 + f]));
    }
    cJSON_AddNumberToObject(o, "median_build_ms", v->median_build_ms[who]);
    cJSON_AddNumberToObject(o, "median_render_ms", v->median_render_ms[who]);
    cJSON_AddNumberToObject(o, "median_total_ms", v->median_total_ms[who]);
    cJSON_AddNumberToObject(o, "median_cost", v->median_cost[who]);
  }
  static const char *ratio_name[3] = {"render_ratio", "total_ratio", "cost_ratio"};
  const double ratio[3] = {v->render_ratio, v->total_ratio, v->cost_ratio};
  for (int q = 0; q < 3; q++) {
    if (isfinite(ratio[q])) cJSON_AddNumberToObject(root, ratio_name[q], ratio[q]);
    else cJSON_AddNullToObject(root, ratio_name[q]);
  }
  char *text = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  char *out = tt__strdup(text);
  cJSON_free(text);
  return out;
}

/* Logs what the phase found. The gain over the default is quoted from --verify (`v`, NULL
 * when not run): the tuning-time costs are single passes taken minutes apart and the best
 * is the luckiest of many, so their ratio overstates the gain (Cornell box, 3 seeds: 5-21%
 * printed, 3.5% verified); without --verify it is marked as unverified. */
static void tt__log_result(const tt__tune_ctx *c, const tt_tuning_verification *v) {
  const tt__tuning *t = c->t;
  tt_tuning_stats st = {.struct_size = sizeof st};
  tt_tuning_get_stats(t->session, &st);
  double best = TT_COST_INFEASIBLE, def = TT_COST_INFEASIBLE;
  tt_tuning_best(t->session, NULL, &best);
  tt_tuning_default_cost(t->session, &def);
  const char *best_json = tt_tuning_best_json(t->session);
  const char *from = !strcmp(best_json, tt_tuning_default_json(t->session)) ? "default" : t->mode;
  char gain[256] = "";
  if (v && v->rounds && isfinite(v->cost_ratio) && v->median_cost[0] > 0 && strcmp(from, "default"))
    snprintf(gain, sizeof gain, ": %.1f%% %s when verified (median of %u rounds side by side)",
             100.0 * fabs(1.0 - v->cost_ratio), v->cost_ratio < 1 ? "lower" : "higher", v->rounds);
  else if (def > 0 && def < TT_COST_INFEASIBLE && best < TT_COST_INFEASIBLE &&
           c->objective.kind != TT_OBJECTIVE_METRIC && strcmp(from, "default"))
    snprintf(gain, sizeof gain,
             ": %.1f%% %s in single tuning passes, unverified (the best of "
             "many noisy passes looks better than it is; --verify 5 measures both side by side)",
             100.0 * fabs(1.0 - best / def), best <= def ? "lower" : "higher");
  c->s->host->log(TT_LOG_INFO, NULL,
                  "tuning: best cost %.6g (%s), default %.6g%s, after %u "
                  "iterations (%u measured, %u from the database): %s",
                  best, from, def, gain, st.iterations, st.measured, st.cached, best_json);
}

int tt__tune_check(const tt__host_options *opt, const tt_loaded_plugin *tuner_p) {
  if (!tuner_p && !opt->explore) {
    if (!(opt->tune || opt->objective || opt->iterations || opt->tune_spp || opt->verify ||
          opt->tune_pass_images))
      return TT_EXIT_OK;
    tt__say("%s needs a tuner plugin (e.g. --plugin tuner_nm) or --explore N\n",
            opt->tune         ? "--tune"
            : opt->objective  ? "--objective"
            : opt->iterations ? "--iterations"
            : opt->tune_spp   ? "--tune-spp"
            : opt->verify     ? "--verify"
                              : "--tune-pass-images");
    return TT_EXIT_USAGE;
  }
  if (opt->explore && opt->iterations) {
    tt__say("--explore N and --iterations exclude each other (exploration "
            "measures N random configurations)\n");
    return TT_EXIT_USAGE;
  }
  return TT_EXIT_OK;
}

/* Says what the phase tunes, with what, and where it records. */
static void tt__tune_log_start(const tt__tune_ctx *c) {
  const tt__tuning *t = c->t;
  int explore = c->explore;
  if (explore && c->tuner_p && !c->opt->quiet)
    c->s->host->log(TT_LOG_INFO, NULL,
                    "tuning: --explore draws random configurations; the "
                    "tuner %s is not used",
                    tt_loaded_plugin_entry(c->tuner_p)->name);
  c->s->host->log(TT_LOG_INFO, NULL,
                  "%s %s %s%s%s, objective %s, %u %s, %u spp per "
                  "measurement, database %s",
                  explore ? "exploring" : "tuning", t->plugin, t->plugin_version,
                  explore ? "" : " with ", explore ? "" : t->tuner, c->objective.spec, t->requested,
                  explore ? "configurations" : "iterations", c->spp,
                  c->db ? tt_tunedb_path(c->db) : "none");
}

/* The library's tuning session over the target, in `state`: it searches c->subset (when
 * --tune-params or the hint narrows it); every candidate is the target's configured values
 * with the searched ones put in. Prints what failed. */
static int tt__tune_session(tt__tune_ctx *c, const tt_tuning_state *state) {
  tt__session *s = c->s;
  tt__tuning *t = c->t;
  int explore = c->explore;
  tt_tuning_desc d = {.struct_size = sizeof d};
  d.host = s->host;
  d.space = c->space;
  d.start = s->configs[c->target_index];
  d.search = c->subset;
  d.objective = c->objective_spec;
  d.tuner = explore ? NULL : tt_loaded_plugin_iface(c->tuner_p);
  d.tuner_settings = explore ? NULL : s->configs[tt__index_of(s, c->tuner_p)];
  d.tuner_name = t->tuner;
  d.seed = s->rec.seed;
  d.iterations = t->requested;
  d.spp = c->spp;
  d.warmup_passes = 1;
  d.time_budget_s = c->opt->time_budget;
  d.plugin = t->plugin;
  d.plugin_version = t->plugin_version;
  d.db = c->db;
  d.state = state;
  d.width = s->camera->width;
  d.height = s->camera->height;
  d.reference_luminance = c->ref_lum;
  d.want_images = c->want_pass;
  d.on_sample = tt__on_sample;
  d.user = c;
  if (tt_tuning_create(&d, &t->session) == TT_OK) return TT_EXIT_OK;
  tt__say("%s: %s\n", explore ? "tuning" : t->tuner, tt_last_error());
  t->session = NULL;
  return TT_EXIT_FAILURE;
}

/* Create: the record, the target and objective, the database, the state, the library's
 * tuning session (continued from --resume) and its target over the render session. Prints
 * what failed; an exit code. */
static int tt__tune_create(tt__tune_ctx *c, tt__session *s, tt_loaded_plugin *tuner_p) {
  const tt__host_options *opt = s->opt;
  memset(c, 0, sizeof *c);
  c->s = s;
  c->opt = opt;
  c->tuner_p = tuner_p;
  c->explore = opt->explore > 0;
  c->spp = opt->tune_spp ? opt->tune_spp : 1;
  c->v.struct_size = sizeof c->v;
  tt__tuning *t = c->t = calloc(1, sizeof *t);
  if (!t) return TT_EXIT_FAILURE;
  int explore = c->explore;
  t->mode = explore ? "explore" : "tune";
  t->tuner = explore ? NULL : tt_loaded_plugin_entry(tuner_p)->name;
  t->requested = explore           ? opt->explore
                 : opt->iterations ? opt->iterations
                                   : TT_HOST_DEFAULT_ITERATIONS;
  int rc = tt__choose(c);
  if (rc == TT_EXIT_OK) rc = tt__tune_open_db(opt, s->host, &c->db);
  if (rc != TT_EXIT_OK) return rc;
  t->plugin = tt_loaded_plugin_entry(c->target)->name;
  t->plugin_version = tt_loaded_plugin_entry(c->target)->version;
  if (c->db) snprintf(t->db_path, sizeof t->db_path, "%s", tt_tunedb_path(c->db));
  tt_tuning_state state;
  if (tt__make_state(c, &state)) return TT_EXIT_FAILURE;
  tt__tune_log_start(c);
  if ((rc = tt__tune_session(c, &state)) != TT_EXIT_OK) return rc;
  if (opt->resume && (rc = tt__load_resume(c)) != TT_EXIT_OK) return rc;
  if (tt_session_tuning_target(s->lib, c->target_index, c->want_pass, &c->target_cb) != TT_OK) {
    tt__say("tuning: %s\n", tt_last_error());
    return TT_EXIT_FAILURE;
  }
  return TT_EXIT_OK;
}

/* Step: the library runs the search (or exploration); its passes render into the film. */
static int tt__tune_run(tt__tune_ctx *c) {
  tt__tuning *t = c->t;
  uint64_t t0 = c->s->host->clock_ns();
  tt_status st = tt_tuning_run(t->session, &c->target_cb);
  tt__progress_finish();
  t->ms = (c->s->host->clock_ns() - t0) * 1e-6;
  if (st == TT_ERR_NO_DATA) {
    tt__say("--objective %s: %s\n", c->objective.spec, tt_last_error());
    return TT_EXIT_USAGE;
  }
  t->interrupted = st == TT_ERR_INTERRUPTED;
  /* a cost the database answered rendered no pass into the image: the render phase makes
   * up for those, so an answer from the database never leaves the image with fewer samples
   * than the same command without one */
  for (size_t i = 0; i < tt_tuning_sample_count(t->session); i++) {
    const tt_tuning_sample *x = tt_tuning_sample_at(t->session, i);
    if (x->cached && x->status == TT_TUNEDB_OK) t->answered_spp += c->spp;
  }
  return st != TT_OK && st != TT_ERR_INTERRUPTED ? TT_EXIT_FAILURE : TT_EXIT_OK;
}

/* --verify N: default and best side by side (the library keeps the default unless the best
 * shows faster); the result goes to --stats and the log. */
static void tt__tune_verify(tt__tune_ctx *c) {
  tt__tuning *t = c->t;
  const tt_tuning_verification *v = &c->v;
  tt_status st = tt_tuning_verify(t->session, &c->target_cb, c->opt->verify, &c->v);
  if (st == TT_ERR_INTERRUPTED) t->interrupted = 1;
  if ((st != TT_OK && st != TT_ERR_INTERRUPTED) || !v->rounds) return;
  t->verify_json = tt__verify_json(v);
  c->s->host->log(TT_LOG_INFO, NULL,
                  "tuning: verify, %u rounds side by side: render median "
                  "%.4g ms (default) vs %.4g ms (best), ratio %.4f; build+render %.4g vs "
                  "%.4g ms, ratio %.4f",
                  v->rounds, v->median_render_ms[0], v->median_render_ms[1], v->render_ratio,
                  v->median_total_ms[0], v->median_total_ms[1], v->total_ratio);
}

/* Finish: --verify, then the kept configuration (the best, or the default when --verify
 * rejected the best) on the target, so the rest of the image renders with it; logs what was
 * found. Returns `rc`, or what failed first. */
static int tt__tune_finish(tt__tune_ctx *c, int rc) {
  tt__tuning *t = c->t;
  tt__session *s = c->s;
  if (c->opt->verify && !t->interrupted && rc == TT_EXIT_OK) tt__tune_verify(c);
  if (tt_config_from_json(s->configs[c->target_index], tt_tuning_kept_json(t->session), "tuning") !=
      TT_OK)
    s->host->log(TT_LOG_ERROR, NULL, "tuning: cannot restore the kept configuration: %s",
                 tt_last_error());
  if (!t->interrupted && rc == TT_EXIT_OK &&
      tt_tuning_apply_best(t->session, &c->target_cb, NULL) != TT_OK) {
    tt__say("tuning: %s rejected the best configuration: %s\n", t->plugin, tt_last_error());
    rc = TT_EXIT_FAILURE;
  }
  tt__log_result(c, &c->v);
  tt_tuning_stats ts = {.struct_size = sizeof ts};
  tt_tuning_get_stats(t->session, &ts);
  if (ts.unrecorded) {
    /* the image is still rendered and written; the exit status says records were lost */
    s->host->log(TT_LOG_ERROR, NULL,
                 "tuning: %u of %u measurements could not be recorded in "
                 "the database %s",
                 ts.unrecorded, ts.measured, t->db_path);
    if (rc == TT_EXIT_OK) rc = TT_EXIT_OUTPUT;
  }
  return rc;
}

/* Hands the record to the caller (`*out`), with the database and the reference the session
 * borrowed; a usage error leaves no record. Frees the rest of the phase. */
static int tt__tune_close(tt__tune_ctx *c, int rc, tt__tuning **out) {
  tt_space_destroy(c->subset);
  if (!c->t) return rc;
  tt__session_sync(c->s);
  c->t->db = c->db;
  c->t->ref_lum = c->ref_lum;
  if (rc == TT_EXIT_USAGE) tt__tuning_free(c->t);
  else *out = c->t;
  return rc;
}

int tt__tune_phase(tt__session *s, tt__tuning **out) {
  *out = NULL;
  tt_loaded_plugin *tuner_p = tt_registry_find_kind(s->reg, TT_KIND_TUNER);
  int rc = tt__tune_check(s->opt, tuner_p);
  if (rc != TT_EXIT_OK || (!tuner_p && !s->opt->explore)) return rc;
  tt__tune_ctx c;
  rc = tt__tune_create(&c, s, tuner_p);
  if (rc == TT_EXIT_OK) {
    rc = tt__tune_run(&c);
    if (rc != TT_EXIT_USAGE) rc = tt__tune_finish(&c, rc);
  }
  return tt__tune_close(&c, rc, out);
}
