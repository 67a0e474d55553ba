/* Tuning objectives: the spec syntax, the cost of one measurement, and the one rRMSE. */
#include "tuning/tuning_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

tt_status tt_objective_parse(const char *text, tt_objective *out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_objective_parse: out is NULL");
  memset(out, 0, sizeof *out);
  if (!text) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_objective_parse: spec is NULL");
  if (!strcmp(text, "render")) {
    out->kind = TT_OBJECTIVE_RENDER;
  } else if (!strcmp(text, "build")) {
    out->kind = TT_OBJECTIVE_BUILD;
  } else if (!strcmp(text, "build+render") || !strcmp(text, "total") ||
             !strcmp(text, "render+build")) {
    out->kind = TT_OBJECTIVE_TOTAL;
  } else if (!strcmp(text, "rrmse")) {
    out->kind = TT_OBJECTIVE_RRMSE;
  } else if (!strncmp(text, "metric:", 7)) {
    const char *name = text + 7;
    const char *colon = strchr(name, ':');
    size_t len = colon ? (size_t)(colon - name) : strlen(name);
    if (len == 0 || len >= sizeof out->metric)
      return tt_set_error(TT_ERR_PARSE,
                          "\"%s\": expected metric:NAME[:min|:max|:target=X] "
                          "with a metric name of 1..63 characters",
                          text);
    out->kind = TT_OBJECTIVE_METRIC;
    memcpy(out->metric, name, len);
    out->goal = TT_OBJECTIVE_MIN;
    if (colon) {
      const char *g = colon + 1;
      char *end = NULL;
      if (!strcmp(g, "min")) {
        out->goal = TT_OBJECTIVE_MIN;
      } else if (!strcmp(g, "max")) {
        out->goal = TT_OBJECTIVE_MAX;
      } else if (!strncmp(g, "target=", 7) && g[7] &&
                 (out->target = strtod(g + 7, &end), *end == 0) && isfinite(out->target)) {
        out->goal = TT_OBJECTIVE_TARGET;
      } else {
        return tt_set_error(TT_ERR_PARSE,
                            "\"%s\": after the metric name expected :min, :max "
                            "or :target=NUMBER, got \":%s\"",
                            text, g);
      }
    }
  } else {
    return tt_set_error(TT_ERR_PARSE,
                        "unknown objective \"%s\" (expected render, build, "
                        "build+render, rrmse, metric:NAME, metric:NAME:max or "
                        "metric:NAME:target=X)",
                        text);
  }
  /* one spelling per objective, so the database matches "total" and "build+render" */
  switch (out->kind) {
  case TT_OBJECTIVE_RENDER: snprintf(out->spec, sizeof out->spec, "render"); break;
  case TT_OBJECTIVE_BUILD: snprintf(out->spec, sizeof out->spec, "build"); break;
  case TT_OBJECTIVE_TOTAL: snprintf(out->spec, sizeof out->spec, "build+render"); break;
  case TT_OBJECTIVE_RRMSE: snprintf(out->spec, sizeof out->spec, "rrmse"); break;
  case TT_OBJECTIVE_METRIC:
    if (out->goal == TT_OBJECTIVE_TARGET) {
      /* shortest text that reads back as the same double: 0.234, not 0.23400000000000001 */
      char num[32];
      for (int prec = 6; prec <= 17; prec++) {
        snprintf(num, sizeof num, "%.*g", prec, out->target);
        if (strtod(num, NULL) == out->target) break;
      }
      snprintf(out->spec, sizeof out->spec, "metric:%s:target=%s", out->metric, num);
    } else {
      snprintf(out->spec, sizeof out->spec, "metric:%s:%s", out->metric,
               out->goal == TT_OBJECTIVE_MAX ? "max" : "min");
    }
    break;
  }
  return TT_OK;
}

/* Luminance weights of Rec. 709. */
static double tt__lum(const float *rgb) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

void tt_luminance(const float *px, uint32_t channels, size_t n, double *out) {
  for (size_t i = 0; i < n; i++) out[i] = channels == 1 ? px[i] : tt__lum(px + i * channels);
}

double tt_rrmse(const float *rgb, const double *ref, size_t n) {
  double sum = 0;
  for (size_t i = 0; i < n; i++) {
    double I = tt__lum(rgb + 3 * i), R = ref[i];
    sum += (I - R) * (I - R) / (R * R + 1e-3);
  }
  return sqrt(sum / (double)n);
}

tt_status tt__objective_cost(const tt_objective *o, const tt_tuning_measurement *m,
                             const double *ref, size_t pixels, double *cost) {
  switch (o->kind) {
  case TT_OBJECTIVE_RENDER: *cost = m->render_ms; return TT_OK;
  case TT_OBJECTIVE_BUILD: *cost = m->build_ms; return TT_OK;
  case TT_OBJECTIVE_TOTAL: *cost = m->build_ms + m->render_ms; return TT_OK;
  case TT_OBJECTIVE_RRMSE:
    if (!m->image || !ref)
      return tt_set_error(TT_ERR_NO_DATA, "the rrmse objective needs the pass's image and a "
                                          "reference");
    *cost = tt_rrmse(m->image, ref, pixels);
    return TT_OK;
  case TT_OBJECTIVE_METRIC: break;
  }
  char names[512] = "";
  const tt_pass_stats *ps = m->pass;
  for (uint32_t k = 0; ps && k < ps->metric_count && k < TT_MAX_METRICS; k++) {
    const char *name = ps->metrics[k].name;
    if (!name) continue;
    if (!strcmp(name, o->metric)) {
      double v = ps->metrics[k].value;
      if (!isfinite(v)) break;
      *cost = o->goal == TT_OBJECTIVE_MAX      ? -v
              : o->goal == TT_OBJECTIVE_TARGET ? fabs(v - o->target)
                                               : v;
      return TT_OK;
    }
    size_t len = strlen(names);
    snprintf(names + len, sizeof names - len, "%s%s", len ? ", " : "", name);
  }
  return tt_set_error(TT_ERR_NO_DATA,
                      "the integrator's pass published no finite metric "
                      "\"%s\" (it has: %s)",
                      o->metric, names[0] ? names : "none");
}
