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
#define _POSIX_C_SOURCE 200809L
#include "session.h"

#include <tt_util/stats.h>

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Reads the configurations of FILE into `cfgs` (clones of `base`); prints and returns an
 * exit code. */
static int tt__measure_read(const char *path, const tt_config *base, tt_config ***cfgs,
                            size_t *count) {
  char *text = NULL;
  size_t size = 0;
  if (tt_file_read(path, "configurations file", 0, &text, &size) != TT_OK) {
    tt__say("--measure %s\n", tt_last_error());
    return TT_EXIT_USAGE;
  }
  cJSON *root = cJSON_Parse(text);
  tt_free(text);
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

int tt__run_measure(const tt__host_options *opt) {
  tt__install_signals("round");
  tt__session s;
  tt_config **cfgs = NULL;
  size_t n = 0;
  double *m = NULL;  /* rounds x n x {build, render, cost} */
  int *ok = NULL;
  int rc = tt__session_open(&s, opt);
  if (rc != TT_EXIT_OK) goto done;
  tt_objective obj;
  const char *spec = opt->objective ? opt->objective : "render";
  if (tt__parse_objective("--objective", spec, &obj)) {
    rc = TT_EXIT_USAGE;
    goto done;
  }
  if (obj.kind != TT_OBJECTIVE_RENDER && obj.kind != TT_OBJECTIVE_TOTAL && obj.kind != TT_OBJECTIVE_BUILD) {
    tt__say("--measure: --objective %s: expected render, build or build+render\n", spec);
    rc = TT_EXIT_USAGE;
    goto done;
  }
  size_t ai = (size_t)tt_session_plugin_index(s.lib, tt_loaded_plugin_entry(s.accel_p)->name);
  const tt_space *space = tt_loaded_plugin_space(s.accel_p);
  rc = tt__measure_read(opt->measure, s.configs[ai], &cfgs, &n);
  if (rc != TT_EXIT_OK) goto done;
  uint32_t rounds = opt->rounds ? opt->rounds : 3, spp = opt->tune_spp ? opt->tune_spp : 1;
  m = calloc((size_t)rounds * n * 3, sizeof *m);
  ok = calloc(n, sizeof *ok);
  if (!m || !ok) {
    rc = TT_EXIT_FAILURE;
    goto done;
  }
  char why[512];
  for (size_t i = 0; i < n; i++) {
    tt_check_result c = tt_space_check(space, cfgs[i], why, sizeof why);
    ok[i] = c != TT_CHECK_INFEASIBLE;
  }
  rc = tt__session_start(&s, 0);
  if (rc != TT_EXIT_OK) goto done;
  tt_pass_stats ps;
  double ms;
  tt__session_render_pass(&s, 1, &ps, &ms);  /* warm-up: page faults, lazy set-up */
  uint32_t done_rounds = 0;
  for (uint32_t r = 0; r < rounds && !s.host->should_stop(); r++) {
    for (size_t k = 0; k < n; k++) {
      size_t i = r % 2 ? n - 1 - k : k;
      if (!ok[i]) continue;
      double build_ms = 0, render_ms = 0;
      if (tt_session_rebuild_accel(s.lib, cfgs[i], &build_ms) != TT_OK ||
          tt__session_render_pass(&s, spp, &ps, &render_ms) != TT_OK) {
        if (s.host->should_stop()) break;
        ok[i] = 0;
        s.host->log(TT_LOG_WARN, NULL, "measure: configuration %zu failed: %s", i, tt_last_error());
        continue;
      }
      double *x = &m[((size_t)r * n + i) * 3];
      x[0] = build_ms;
      x[1] = render_ms;
      x[2] = obj.kind == TT_OBJECTIVE_RENDER ? render_ms
             : obj.kind == TT_OBJECTIVE_BUILD ? build_ms : build_ms + render_ms;
    }
    if (!s.host->should_stop()) done_rounds++;
  }
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "scene", opt->scene);
  cJSON_AddStringToObject(root, "scene_id", tt_scene_id(s.scene));
  if (opt->camera_index_set) cJSON_AddNumberToObject(root, "camera_index", opt->camera_index);
  cJSON_AddStringToObject(root, "objective", obj.spec);
  cJSON_AddStringToObject(root, "clock", opt->clock_cpu ? "cpu" : "wall");
  cJSON_AddNumberToObject(root, "rounds", done_rounds);
  cJSON_AddNumberToObject(root, "spp", spp);
  cJSON *arr = cJSON_AddArrayToObject(root, "configs");
  double *tmp = malloc((rounds ? rounds : 1) * sizeof *tmp);
  double first = NAN;
  for (size_t i = 0; i < n && tmp; i++) {
    cJSON *o = cJSON_CreateObject();
    char *j = tt_config_to_json(cfgs[i]);
    cJSON *cj = j ? cJSON_Parse(j) : NULL;
    tt_free(j);
    cJSON_AddItemToObject(o, "config", cj ? cj : cJSON_CreateNull());
    cJSON_AddStringToObject(o, "status", ok[i] ? "ok" : "infeasible or failed");
    static const char *names[3] = {"build_ms", "render_ms", "cost"};
    double med[3] = {NAN, NAN, NAN};
    for (int f = 0; f < 3; f++) {
      cJSON *a = cJSON_AddArrayToObject(o, names[f]);
      for (uint32_t r = 0; ok[i] && r < done_rounds; r++) {
        tmp[r] = m[((size_t)r * n + i) * 3 + f];
        cJSON_AddItemToArray(a, cJSON_CreateNumber(tmp[r]));
      }
      if (ok[i]) med[f] = tt__median(tmp, done_rounds);
    }
    if (i == 0) first = med[2];
    cJSON_AddNumberToObject(o, "median_build_ms", isfinite(med[0]) ? med[0] : -1);
    cJSON_AddNumberToObject(o, "median_render_ms", isfinite(med[1]) ? med[1] : -1);
    if (isfinite(med[2])) cJSON_AddNumberToObject(o, "median_cost", med[2]);
    else cJSON_AddNullToObject(o, "median_cost");
    /* the median of per-round ratios to the first configuration: robust to drift */
    uint32_t nr = 0;
    for (uint32_t r = 0; ok[i] && ok[0] && r < done_rounds; r++) {
      double a = m[((size_t)r * n + i) * 3 + 2], b = m[((size_t)r * n + 0) * 3 + 2];
      if (b > 0) tmp[nr++] = a / b;
    }
    if (nr) cJSON_AddNumberToObject(o, "ratio_to_first", tt__median(tmp, nr));
    else cJSON_AddNullToObject(o, "ratio_to_first");
    cJSON_AddItemToArray(arr, o);
  }
  (void)first;
  free(tmp);
  char *text = cJSON_Print(root);
  cJSON_Delete(root);
  if (!text || puts(text) < 0 || fflush(stdout)) rc = TT_EXIT_OUTPUT;
  cJSON_free(text);
  if (rc == TT_EXIT_OK && s.host->should_stop()) rc = TT_EXIT_INTERRUPTED;

done:
  for (size_t i = 0; cfgs && i < n; i++) tt_config_destroy(cfgs[i]);
  free(cfgs);
  free(m);
  free(ok);
  tt__session_close(&s);
  return rc;
}
