/* host: the --stats run record (JSON), for scripts, benchmarks and the tuning tools. */
#include "host.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>

/* Adds the configuration of one plugin as a JSON object, or null. */
static void tt__add_config(cJSON *parent, const char *name, const tt_config *config) {
  if (!config) {
    cJSON_AddItemToObject(parent, name, cJSON_CreateObject());
    return;
  }
  char *json = tt_config_to_json(config);
  cJSON *obj = json ? cJSON_Parse(json) : NULL;
  tt_free(json);
  cJSON_AddItemToObject(parent, name, obj ? obj : cJSON_CreateNull());
}

tt_status tt__write_stats(const char *path, const tt__run_record *rec) {
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "tunetrace", tt_version());
  cJSON_AddStringToObject(root, "scene", tt_scene_source(rec->scene));
  cJSON_AddStringToObject(root, "scene_id", tt_scene_id(rec->scene));
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
  cJSON *out = cJSON_AddObjectToObject(root, "output");
  if (rec->out_exr) cJSON_AddStringToObject(out, "exr", rec->out_exr);
  if (rec->out_png) cJSON_AddStringToObject(out, "png", rec->out_png);

  char *text = cJSON_Print(root);
  cJSON_Delete(root);
  if (!text) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
  FILE *f = fopen(path, "w");
  if (!f) {
    free(text);
    return tt_set_error(TT_ERR_IO, "%s: cannot open for writing", path);
  }
  int ok = fputs(text, f) >= 0 && fputc('\n', f) != EOF;
  ok = (fclose(f) == 0) && ok;
  free(text);
  return ok ? TT_OK : tt_set_error(TT_ERR_IO, "%s: write failed", path);
}
