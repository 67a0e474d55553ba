/* host: the --stats run record (JSON), for scripts, benchmarks and the tuning tools. */
#include "host.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* Adds the configuration of one plugin as a JSON object, or null. */
static void tt__add_config(cJSON *parent, const char *name, const tt_config *config) {
  if (!config) {
    cJSON_AddItemToObject(parent, name, cJSON_CreateObject());
    return;
  }
  char *json = tt_config_to_json(config);
  cJSON *obj = tt__json_parse_exact(json);
  tt_free(json);
  cJSON_AddItemToObject(parent, name, obj ? obj : cJSON_CreateNull());
}

/* Adds a configuration given as JSON text (null if absent or unparsable). */
static void tt__add_json(cJSON *parent, const char *name, const char *json) {
  cJSON *obj = tt__json_parse_exact(json);
  cJSON_AddItemToObject(parent, name, obj ? obj : cJSON_CreateNull());
}

/* The "tuning" object: what the tuning or exploration phase measured and chose. */
static void tt__add_tuning(cJSON *root, const tt__tuning *t) {
  static const char *status_names[] = {"ok", "infeasible", "failed"};
  const tt_tuning *session = t->session;
  tt_tuning_stats st = {.struct_size = sizeof st};
  tt_tuning_get_stats(session, &st);
  const tt_objective *objective = tt_tuning_objective(session);
  double default_cost = TT_COST_INFEASIBLE, best_cost = TT_COST_INFEASIBLE;
  tt_tuning_default_cost(session, &default_cost);
  tt_tuning_best(session, NULL, &best_cost);
  const char *default_json = tt_tuning_default_json(session);
  const char *best_json = tt_tuning_best_json(session);
  cJSON *o = cJSON_AddObjectToObject(root, "tuning");
  cJSON_AddStringToObject(o, "mode", t->mode);
  cJSON_AddStringToObject(o, "plugin", t->plugin ? t->plugin : "");
  cJSON_AddStringToObject(o, "plugin_version", t->plugin_version ? t->plugin_version : "");
  if (t->tuner) cJSON_AddStringToObject(o, "tuner", t->tuner);
  else cJSON_AddNullToObject(o, "tuner");
  cJSON_AddStringToObject(o, "objective", objective ? objective->spec : "");
  cJSON_AddNumberToObject(o, "requested", t->requested);
  cJSON_AddNumberToObject(o, "iterations", st.iterations);
  cJSON_AddNumberToObject(o, "measured", st.measured);
  cJSON_AddNumberToObject(o, "cached", st.cached);
  cJSON_AddNumberToObject(o, "infeasible", st.infeasible);
  cJSON_AddNumberToObject(o, "failed", st.failed);
  cJSON_AddBoolToObject(o, "converged", st.converged);
  cJSON_AddBoolToObject(o, "interrupted", t->interrupted);
  cJSON_AddNumberToObject(o, "default_cost", default_cost);
  tt__add_json(o, "default_config", default_json);
  cJSON_AddNumberToObject(o, "best_cost", best_cost);
  tt__add_json(o, "best_config", best_json);
  cJSON_AddStringToObject(
      o, "best_from",
      !best_json || !default_json || !strcmp(best_json, default_json) ? "default" : t->mode);
  /* what the final passes used: the best, or the default when --verify rejected the best */
  static const char *verdict_names[] = {"unverified", "confirmed", "rejected", "default"};
  const char *reason = NULL;
  tt_tuning_verdict verdict = tt_tuning_get_verdict(session, &reason);
  const char *kept_json = tt_tuning_kept_json(session);
  tt__add_json(o, "kept_config", kept_json);
  cJSON_AddStringToObject(
      o, "kept", kept_json && best_json && strcmp(kept_json, best_json) ? "default" : "best");
  cJSON_AddStringToObject(o, "verdict",
                          verdict >= 0 && verdict <= 3 ? verdict_names[verdict] : "unverified");
  if (reason) cJSON_AddStringToObject(o, "kept_reason", reason);
  else cJSON_AddNullToObject(o, "kept_reason");
  cJSON_AddNumberToObject(o, "tuning_ms", t->ms);
  if (t->db_path[0]) cJSON_AddStringToObject(o, "db", t->db_path);
  else cJSON_AddNullToObject(o, "db");
  cJSON_AddNumberToObject(o, "db_unrecorded", st.unrecorded);
  if (t->verify_json) tt__add_json(o, "verify", t->verify_json);
  /* costs[i] and history[i] are iteration i; the default is separate (default_cost) */
  cJSON *costs = cJSON_AddArrayToObject(o, "costs");
  cJSON *hist = cJSON_AddArrayToObject(o, "history");
  for (size_t i = 0; i < tt_tuning_sample_count(session); i++) {
    const tt_tuning_sample *s = tt_tuning_sample_at(session, i);
    if (s->iteration < 0) continue;
    cJSON_AddItemToArray(costs, cJSON_CreateNumber(s->cost));
    cJSON *h = cJSON_CreateObject();
    cJSON_AddNumberToObject(h, "iteration", s->iteration);
    cJSON_AddNumberToObject(h, "cost", s->cost);
    cJSON_AddNumberToObject(h, "build_ms", s->build_ms);
    cJSON_AddNumberToObject(h, "render_ms", s->render_ms);
    cJSON_AddStringToObject(h, "status",
                            s->status >= 0 && s->status <= 2 ? status_names[s->status] : "unknown");
    cJSON_AddBoolToObject(h, "cached", s->cached);
    tt__add_json(h, "config", s->config);
    cJSON_AddItemToArray(hist, h);
  }
}

/* What a benchmark record needs besides the figures: when, on what, with which code and
 * command. The load average is read when the record is written (its 1-minute value covers
 * the end of the run): on a shared machine it says how much the timings can be trusted. */
void tt__add_scene_ids(cJSON *root, const tt_scene *scene) {
  cJSON_AddStringToObject(root, "scene_id", tt_scene_id(scene));
  cJSON *parts = cJSON_AddObjectToObject(root, "scene_id_parts");
  for (int p = 0; p < TT_SCENE_PART_COUNT; p++)
    cJSON_AddStringToObject(parts, tt_scene_part_name((tt_scene_part)p),
                            tt_scene_id_part(scene, (tt_scene_part)p));
}

static void tt__add_provenance(cJSON *root, const tt__run_record *rec) {
  cJSON_AddStringToObject(root, "tunetrace_commit", tt_build_commit());
  const tt__host_options *opt = rec->opt;
  char stamp[64] = "";
  if (opt && opt->started_ns) {
    time_t secs = (time_t)(opt->started_ns / 1000000000);
    struct tm tm;
    if (gmtime_r(&secs, &tm))
      snprintf(stamp, sizeof stamp, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
               tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
               (int)(opt->started_ns / 1000000 % 1000));
  }
  cJSON_AddStringToObject(root, "timestamp", stamp);
  cJSON *cmd = cJSON_AddArrayToObject(root, "command_line");
  for (int i = 0; opt && i < opt->argc; i++)
    cJSON_AddItemToArray(cmd, cJSON_CreateString(opt->argv[i]));
  char cwd[4096];
  if (getcwd(cwd, sizeof cwd)) cJSON_AddStringToObject(root, "working_directory", cwd);
  cJSON *m = cJSON_AddObjectToObject(root, "machine");
  cJSON_AddStringToObject(m, "cpu", tt_tunedb_cpu_model());
  cJSON_AddNumberToObject(m, "cores", (double)sysconf(_SC_NPROCESSORS_ONLN));
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0)
    cJSON_AddNumberToObject(m, "cores_available", CPU_COUNT(&set));
  cJSON_AddStringToObject(m, "machine_id", tt_tunedb_machine_id());
  char name[256] = "";
  if (gethostname(name, sizeof name - 1) == 0) cJSON_AddStringToObject(m, "hostname", name);
  double load[3];
  if (getloadavg(load, 3) == 3) {
    cJSON *la = cJSON_AddArrayToObject(m, "load_average");
    for (int i = 0; i < 3; i++) cJSON_AddItemToArray(la, cJSON_CreateNumber(load[i]));
  }
}

tt_status tt__write_stats(const char *path, const tt__run_record *rec) {
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "tunetrace", tt_version());
  tt__add_provenance(root, rec);
  cJSON_AddStringToObject(root, "scene", tt_scene_source(rec->scene));
  tt__add_scene_ids(root, rec->scene);
  cJSON *plugins = cJSON_AddObjectToObject(root, "plugins");
  cJSON *params = cJSON_AddObjectToObject(root, "params");
  for (size_t i = 0; i < tt_registry_count(rec->reg); i++) {
    const tt_loaded_plugin *p = tt_registry_get(rec->reg, i);
    const tt_plugin *e = tt_loaded_plugin_entry(p);
    cJSON *entry = cJSON_CreateObject();
    cJSON_AddStringToObject(entry, "name", e->name);
    cJSON_AddStringToObject(entry, "version", e->version);
    cJSON_AddStringToObject(entry, "path", tt_loaded_plugin_path(p));
    const char *kind = tt_plugin_kind_name(e->kind);
    /* kinds that allow several plugins (post) become arrays */
    if (e->kind == TT_KIND_POST) {
      cJSON *arr = cJSON_GetObjectItem(plugins, kind);
      if (!arr) arr = cJSON_AddArrayToObject(plugins, kind);
      cJSON_AddItemToArray(arr, entry);
    } else {
      cJSON_AddItemToObject(plugins, kind, entry);
    }
    tt__add_config(params, e->name, rec->configs[i]);
  }
  cJSON_AddNumberToObject(root, "build_ms", rec->build_ms);
  cJSON_AddNumberToObject(root, "render_ms", rec->render_ms);
  cJSON_AddNumberToObject(root, "passes", rec->passes);
  cJSON_AddNumberToObject(root, "spp", rec->spp);
  cJSON_AddNumberToObject(root, "rays", (double)rec->rays);
  cJSON_AddNumberToObject(root, "rays_per_s",
                          rec->render_ms > 0 ? rec->rays / (rec->render_ms * 1e-3) : 0.0);
  cJSON_AddNumberToObject(root, "samples", (double)rec->samples);
  cJSON_AddNumberToObject(root, "nonfinite", (double)rec->nonfinite);
  cJSON_AddNumberToObject(root, "triangles", (double)tt_scene_triangle_count(rec->scene));
  cJSON_AddNumberToObject(root, "seed", (double)rec->seed);
  cJSON_AddNumberToObject(root, "threads", rec->threads);
  cJSON_AddStringToObject(root, "clock", rec->opt && rec->opt->clock_cpu ? "cpu" : "wall");
  cJSON *res = cJSON_AddArrayToObject(root, "resolution");
  cJSON_AddItemToArray(res, cJSON_CreateNumber(rec->width));
  cJSON_AddItemToArray(res, cJSON_CreateNumber(rec->height));
  cJSON_AddBoolToObject(root, "interrupted", rec->interrupted);
  cJSON *accel = cJSON_AddObjectToObject(root, "accel");
  cJSON_AddNumberToObject(accel, "build_ms", rec->build.build_ms);
  cJSON_AddNumberToObject(accel, "memory_bytes", (double)rec->build.memory_bytes);
  cJSON_AddNumberToObject(accel, "nodes", (double)rec->build.nodes);
  cJSON_AddNumberToObject(accel, "leaves", (double)rec->build.leaves);
  cJSON_AddNumberToObject(accel, "sah_cost", rec->build.sah_cost);
  cJSON_AddBoolToObject(accel, "repaired", rec->build.repaired != 0);
  /* integrator metrics: mean over passes */
  cJSON *metrics = cJSON_AddObjectToObject(root, "metrics");
  for (uint32_t m = 0; m < rec->last_pass.metric_count && m < TT_MAX_METRICS; m++)
    if (rec->last_pass.metrics[m].name)
      cJSON_AddNumberToObject(metrics, rec->last_pass.metrics[m].name,
                              rec->passes ? rec->metric_sums[m] / rec->passes : 0.0);
  if (rec->tuning) tt__add_tuning(root, rec->tuning);
  cJSON *out = cJSON_AddObjectToObject(root, "output");
  if (rec->out_exr) cJSON_AddStringToObject(out, "exr", rec->out_exr);
  if (rec->out_png) cJSON_AddStringToObject(out, "png", rec->out_png);

  char *text = cJSON_Print(root);
  cJSON_Delete(root);
  if (!text) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
  /* atomic: a kill or a full disk leaves the previous record, never half of one */
  size_t n = strlen(text);
  text[n] = '\n'; /* cJSON_Print's buffer has room: replaces the terminator, written by size */
  tt_status st = tt_file_write_atomic(path, text, n + 1);
  free(text);
  return st;
}
