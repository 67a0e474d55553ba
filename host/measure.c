/* host --measure FILE.json: N configurations of the accel measured side by side, in rounds
 * of one pass each (every configuration applied, i.e. rebuilt, and rendered once per round),
 * the order alternating between rounds (forward in even rounds, backward in odd ones) so that
 * a drift in machine speed hits every configuration alike; medians per configuration and
 * their ratios to the first one (put the default first). The side-by-side form of
 * tt_tuning_verify for more than two configurations: tools/hybrid/evaluate.py compares the
 * default, the search's best, the best static and the predicted configurations with it.
 * Costs are the objective's (build+render, render, build) through the host's clock
 * (--clock cpu for CPU time); nothing is written to the tuning database.
 *
 * FILE.json: an array of configuration objects of the accel (partial ones are put into its
 * configured values, as --set would). Output (stdout): JSON with per configuration its
 * canonical JSON, status, per-round build/render/cost and the medians. */
#include "session.h"

#include <tt_util/stats.h>

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The --measure job: the host session, the configurations and what every round measured.
 * tt__measure_close frees what it holds at any stage. */
typedef struct tt__measure_job {
  const tt__host_options *opt;
  tt__session s;
  tt_objective obj;
  tt_config **cfgs; /* the configurations of FILE, in its order */
  size_t n;
  int *ok; /* per configuration: feasible and measured without failure */
  uint32_t rounds, spp, done_rounds;
  double *m; /* rounds x n x {build, render, cost} */
} tt__measure_job;

/* Reads the configurations of FILE into `cfgs` (clones of `base`); prints and returns an
 * exit code. */
static int tt__measure_read(const char *path, const tt_config *base, tt_config ***cfgs,
                            size_t *count) {
  cJSON *root = NULL;
  if (tt__json_read("--measure", path, "configurations file", &root)) return TT_EXIT_USAGE;
  if (!cJSON_IsArray(root) || cJSON_GetArraySize(root) < 1) {
    tt__say("--measure %s: expected a JSON array of configuration objects\n", path);
    cJSON_Delete(root);
    return TT_EXIT_USAGE;
  }
  size_t k = (size_t)cJSON_GetArraySize(root);
  *cfgs = calloc(k, sizeof **cfgs);
  *count = k;
  for (size_t i = 0; i < k; i++) {
    cJSON *item = cJSON_GetArrayItem(root, (int)i);
    /* exact numbers: the configuration measured is the one the file names, to the last bit */
    if (cJSON_IsObject(item)) tt__json_exact(item);
    char *json = cJSON_IsObject(item) ? cJSON_PrintUnformatted(item) : NULL;
    char where[4200];
    snprintf(where, sizeof where, "%s[%zu]", path, i);
    (*cfgs)[i] = tt_config_clone(base);
    if (!json || !(*cfgs)[i] || tt_config_from_json((*cfgs)[i], json, where) != TT_OK) {
      tt__say("--measure %s\n", json ? tt_last_error() : "expected an object");
      cJSON_free(json);
      cJSON_Delete(root);
      return TT_EXIT_USAGE;
    }
    cJSON_free(json);
  }
  cJSON_Delete(root);
  return TT_EXIT_OK;
}

/* The objective: a time (render, build or build+render); prints and returns an exit code. */
static int tt__measure_objective(tt__measure_job *j) {
  const char *spec = j->opt->objective ? j->opt->objective : "render";
  if (tt__parse_objective("--objective", spec, &j->obj)) return TT_EXIT_USAGE;
  tt_objective_kind k = j->obj.kind;
  if (k != TT_OBJECTIVE_RENDER && k != TT_OBJECTIVE_TOTAL && k != TT_OBJECTIVE_BUILD) {
    tt__say("--measure: --objective %s: expected render, build or build+render\n", spec);
    return TT_EXIT_USAGE;
  }
  return TT_EXIT_OK;
}

/* Create: the session, the objective, the configurations (an infeasible one is reported,
 * not measured), the accel, integrator and film, and one warm-up pass (page faults, lazy
 * set-up). Prints what failed; an exit code. */
static int tt__measure_create(tt__measure_job *j, const tt__host_options *opt) {
  memset(j, 0, sizeof *j);
  j->opt = opt;
  int rc = tt__session_open(&j->s, opt);
  if (rc == TT_EXIT_OK) rc = tt__measure_objective(j);
  if (rc != TT_EXIT_OK) return rc;
  size_t ai = (size_t)tt_session_plugin_index(j->s.lib, tt_loaded_plugin_entry(j->s.accel_p)->name);
  const tt_space *space = tt_loaded_plugin_space(j->s.accel_p);
  rc = tt__measure_read(opt->measure, j->s.configs[ai], &j->cfgs, &j->n);
  if (rc != TT_EXIT_OK) return rc;
  j->rounds = opt->rounds ? opt->rounds : 3;
  j->spp = opt->tune_spp ? opt->tune_spp : 1;
  j->m = calloc((size_t)j->rounds * j->n * 3, sizeof *j->m);
  j->ok = calloc(j->n, sizeof *j->ok);
  if (!j->m || !j->ok) return TT_EXIT_FAILURE;
  char why[512];
  for (size_t i = 0; i < j->n; i++)
    j->ok[i] = tt_space_check(space, j->cfgs[i], why, sizeof why) != TT_CHECK_INFEASIBLE;
  rc = tt__session_start(&j->s, 0);
  if (rc != TT_EXIT_OK) return rc;
  tt_pass_stats ps;
  double ms;
  tt__session_render_pass(&j->s, 1, &ps, &ms);
  return TT_EXIT_OK;
}

/* Step: round `r`, every configuration applied (rebuilt) and rendered once, forward in even
 * rounds and backward in odd ones; a configuration that fails is measured no more. */
static void tt__measure_round(tt__measure_job *j, uint32_t r) {
  const tt_host *host = j->s.host;
  size_t n = j->n;
  for (size_t k = 0; k < n; k++) {
    size_t i = r % 2 ? n - 1 - k : k;
    if (!j->ok[i]) continue;
    double build_ms = 0, render_ms = 0;
    tt_pass_stats ps;
    if (tt_session_rebuild_accel(j->s.lib, j->cfgs[i], &build_ms) != TT_OK ||
        tt__session_render_pass(&j->s, j->spp, &ps, &render_ms) != TT_OK) {
      if (host->should_stop()) break;
      j->ok[i] = 0;
      host->log(TT_LOG_WARN, NULL, "measure: configuration %zu failed: %s", i, tt_last_error());
      continue;
    }
    double *x = &j->m[((size_t)r * n + i) * 3];
    x[0] = build_ms;
    x[1] = render_ms;
    x[2] = j->obj.kind == TT_OBJECTIVE_RENDER  ? render_ms
           : j->obj.kind == TT_OBJECTIVE_BUILD ? build_ms
                                               : build_ms + render_ms;
  }
  if (!host->should_stop()) j->done_rounds++;
}

/* Configuration `i` as JSON: its canonical form, status, per-round figures, medians and the
 * median of its per-round cost ratios to the first configuration (robust to drift); `tmp`
 * holds a value per round. */
static cJSON *tt__measure_config_json(const tt__measure_job *j, size_t i, double *tmp) {
  static const char *names[3] = {"build_ms", "render_ms", "cost"};
  const double *m = j->m;
  size_t n = j->n;
  int ok = j->ok[i];
  cJSON *o = cJSON_CreateObject();
  char *js = tt_config_to_json(j->cfgs[i]);
  cJSON *cj = tt__json_parse_exact(js);
  tt_free(js);
  cJSON_AddItemToObject(o, "config", cj ? cj : cJSON_CreateNull());
  cJSON_AddStringToObject(o, "status", ok ? "ok" : "infeasible or failed");
  double med[3] = {NAN, NAN, NAN};
  for (int f = 0; f < 3; f++) {
    cJSON *a = cJSON_AddArrayToObject(o, names[f]);
    for (uint32_t r = 0; ok && r < j->done_rounds; r++) {
      tmp[r] = m[((size_t)r * n + i) * 3 + f];
      cJSON_AddItemToArray(a, cJSON_CreateNumber(tmp[r]));
    }
    if (ok) med[f] = tt__median(tmp, j->done_rounds);
  }
  cJSON_AddNumberToObject(o, "median_build_ms", isfinite(med[0]) ? med[0] : -1);
  cJSON_AddNumberToObject(o, "median_render_ms", isfinite(med[1]) ? med[1] : -1);
  if (isfinite(med[2])) cJSON_AddNumberToObject(o, "median_cost", med[2]);
  else cJSON_AddNullToObject(o, "median_cost");
  uint32_t nr = 0;
  for (uint32_t r = 0; ok && j->ok[0] && r < j->done_rounds; r++) {
    double a = m[((size_t)r * n + i) * 3 + 2], b = m[((size_t)r * n + 0) * 3 + 2];
    if (b > 0) tmp[nr++] = a / b;
  }
  if (nr) cJSON_AddNumberToObject(o, "ratio_to_first", tt__median(tmp, nr));
  else cJSON_AddNullToObject(o, "ratio_to_first");
  return o;
}

/* Finish: the result as JSON on stdout; TT_EXIT_INTERRUPTED when a stop cut the rounds. */
static int tt__measure_finish(tt__measure_job *j) {
  const tt__host_options *opt = j->opt;
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "scene", opt->scene);
  cJSON_AddStringToObject(root, "scene_id", tt_scene_id(j->s.scene));
  if (opt->camera_index_set) cJSON_AddNumberToObject(root, "camera_index", opt->camera_index);
  cJSON_AddStringToObject(root, "objective", j->obj.spec);
  cJSON_AddStringToObject(root, "clock", opt->clock_cpu ? "cpu" : "wall");
  cJSON_AddNumberToObject(root, "rounds", j->done_rounds);
  cJSON_AddNumberToObject(root, "spp", j->spp);
  cJSON *arr = cJSON_AddArrayToObject(root, "configs");
  double *tmp = malloc((j->rounds ? j->rounds : 1) * sizeof *tmp);
  for (size_t i = 0; i < j->n && tmp; i++)
    cJSON_AddItemToArray(arr, tt__measure_config_json(j, i, tmp));
  free(tmp);
  int rc = tt__json_print(root);
  return rc == TT_EXIT_OK && j->s.host->should_stop() ? TT_EXIT_INTERRUPTED : rc;
}

/* Frees what the job holds, at any stage. */
static void tt__measure_close(tt__measure_job *j) {
  for (size_t i = 0; j->cfgs && i < j->n; i++) tt_config_destroy(j->cfgs[i]);
  free(j->cfgs);
  free(j->m);
  free(j->ok);
  tt__session_close(&j->s);
}

int tt__run_measure(const tt__host_options *opt) {
  tt__install_signals("round");
  tt__measure_job j;
  int rc = tt__measure_create(&j, opt);
  if (rc == TT_EXIT_OK) {
    for (uint32_t r = 0; r < j.rounds && !j.s.host->should_stop(); r++) tt__measure_round(&j, r);
    rc = tt__measure_finish(&j);
  }
  tt__measure_close(&j);
  return rc;
}
