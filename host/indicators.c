/* host --indicators: the scene indicators of thesis Table 3.2 for one view, raw and
 * normalised to [0, 1] (tunetrace/indicators.h), as JSON on stdout. */
#include "session.h"

#include <tt_util/clock.h>
#include <tt_util/stats.h>

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

/* Each indicator raw, normalised and with the bounds of its normalisation (the camera-extent
 * ones scaled by the scene's extent); the names of those outside their bounds. */
static void tt__indicators_add(cJSON *root, const tt_indicator_norm *norm, const double *raw,
                               const double *unit) {
  cJSON *r = cJSON_AddObjectToObject(root, "raw");
  cJSON *u = cJSON_AddObjectToObject(root, "normalized");
  cJSON *b = cJSON_AddObjectToObject(root, "bounds");
  cJSON *c = cJSON_AddArrayToObject(root, "clamped");
  for (uint32_t i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) {
    const char *name = tt_scene_indicator_name(i);
    double lo, hi, log_unit;
    tt_indicator_bounds(norm, i, &lo, &hi, &log_unit);
    if (i >= 3 && i <= 8 && norm->camera == TT_INDICATOR_CAMERA_EXTENT) {
      double e = raw[11] > 0 ? raw[11] : 1.0;
      lo *= e;
      hi *= e;
    }
    cJSON_AddNumberToObject(r, name, raw[i]);
    cJSON_AddNumberToObject(u, name, unit[i]);
    cJSON *bi = cJSON_AddObjectToObject(b, name);
    cJSON_AddNumberToObject(bi, "lo", lo);
    cJSON_AddNumberToObject(bi, "hi", hi);
    if (log_unit > 0) cJSON_AddNumberToObject(bi, "log_unit", log_unit);
    if (raw[i] < lo || raw[i] > hi) cJSON_AddItemToArray(c, cJSON_CreateString(name));
  }
}

/* The view they describe: the camera's position, target and vertical field of view. */
static void tt__indicators_add_camera(cJSON *root, const tt_camera *cam) {
  cJSON *v = cJSON_AddObjectToObject(root, "camera");
  cJSON *pos = cJSON_AddArrayToObject(v, "position"), *tgt = cJSON_AddArrayToObject(v, "target");
  for (int a = 0; a < 3; a++) {
    cJSON_AddItemToArray(pos, cJSON_CreateNumber(cam->position[a]));
    cJSON_AddItemToArray(tgt, cJSON_CreateNumber(cam->target[a]));
  }
  cJSON_AddNumberToObject(v, "fov_y", cam->fov_y);
}

/* The indicators of the session's view as the JSON text printed (malloc, NULL when out of
 * memory), with the median CPU ms of 5 evaluations (one pass over all triangles; the camera
 * entries alone cost nothing). */
static char *tt__indicators_text(const tt__session *s, const tt_indicator_norm *norm) {
  const tt__host_options *opt = s->opt;
  double raw[TT_SCENE_INDICATOR_COUNT], unit[TT_SCENE_INDICATOR_COUNT], ms[5];
  for (int r = 0; r < 5; r++) {
    double t0 = tt__thread_cpu_ms();
    tt_scene_indicators(s->scene, raw);
    ms[r] = tt__thread_cpu_ms() - t0;
  }
  double compute_ms = tt__median(ms, 5);
  tt_indicators_normalize(norm, raw, unit);
  char id[96];
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "scene", opt->scene);
  tt__add_scene_ids(root, s->scene);
  if (opt->camera_index_set) cJSON_AddNumberToObject(root, "camera_index", opt->camera_index);
  else cJSON_AddNullToObject(root, "camera_index");
  cJSON_AddStringToObject(root, "normalization", tt_indicator_norm_id(norm, id, sizeof id));
  tt__indicators_add(root, norm, raw, unit);
  cJSON_AddNumberToObject(root, "triangles", (double)tt_scene_triangle_count(s->scene));
  cJSON_AddNumberToObject(root, "compute_ms", compute_ms);
  tt__indicators_add_camera(root, tt_scene_camera(s->scene));
  char *text = cJSON_Print(root);
  cJSON_Delete(root);
  return text;
}

int tt__run_indicators(const tt__host_options *opt) {
  tt_indicator_norm norm;
  tt_indicator_norm_init(&norm);
  if (opt->indicator_norm && tt_indicator_norm_parse(opt->indicator_norm, &norm) != TT_OK) {
    tt__say("--indicator-norm: %s\n", tt_last_error());
    return TT_EXIT_USAGE;
  }
  /* the session's scene set-up (--res, --camera-index); its plugins are not used */
  tt__session s;
  int rc = tt__session_open(&s, opt);
  char *text = rc == TT_EXIT_OK ? tt__indicators_text(&s, &norm) : NULL;
  tt__session_close(&s);
  if (rc != TT_EXIT_OK) return rc;
  if (!text) {
    tt__say("--indicators: out of memory\n");
    return TT_EXIT_FAILURE;
  }
  int ok = puts(text) >= 0 && fflush(stdout) == 0;
  cJSON_free(text);
  if (!ok) {
    tt__say("--indicators: cannot write to stdout\n");
    return TT_EXIT_OUTPUT;
  }
  return TT_EXIT_OK;
}
