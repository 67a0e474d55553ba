/* The predictors' state space: raw scene indicators (scene_indicators.c) mapped to [0, 1]
 * with the thesis' bounds (indicators.h has the table and the camera choice). */
#include <tunetrace/indicators.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Upper bound and log unit (0: linear only) per indicator, in tt_scene_indicator_name order.
 * Camera coordinates (3..8) are symmetric and depend on the camera mode; see tt__camera_bound. */
static const struct {
  double hi;
  double log_unit;
} tt__bound[TT_SCENE_INDICATOR_COUNT] = {
    {1e5, 1.0},    /* meshes */
    {1e7, 1.0},    /* triangles */
    {1e5, 1.0},    /* lights */
    {0, 0},        /* camera_x */
    {0, 0},        /* camera_y */
    {0, 0},        /* camera_z */
    {0, 0},        /* target_x */
    {0, 0},        /* target_y */
    {0, 0},        /* target_z */
    {180.0, 0},    /* fov_y, degrees */
    {1.0, 0},      /* diffuse_ratio */
    {1e5, 1.0},    /* extent, world units */
    {10.0, 0},     /* total_area / extent^2 */
    {10.0, 1e-6},  /* light_area / extent^2 */
    {10.0, 1e-6},  /* area_per_mesh */
    {1e-2, 1e-12}, /* mean_var_tri_size */
    {1e-2, 1e-24}, /* var_var_tri_size (a variance of variances: squared units) */
};

enum { TT__EXTENT = 11 };

static int tt__is_camera(uint32_t i) { return i >= 3 && i <= 8; }

static double tt__camera_bound(tt_indicator_camera c) {
  return c == TT_INDICATOR_CAMERA_TABLE ? 10.0 : c == TT_INDICATOR_CAMERA_TEXT ? 1e4 : 1.0;
}

void tt_indicator_norm_init(tt_indicator_norm *n) {
  if (!n) return;
  memset(n, 0, sizeof *n);
  n->struct_size = sizeof *n;
  n->camera = TT_INDICATOR_CAMERA_EXTENT;
  n->scale = TT_INDICATOR_LINEAR;
}

/* A copy of `n` with defaults for what an older (shorter) struct lacks, or the defaults. */
static tt_indicator_norm tt__norm(const tt_indicator_norm *n) {
  tt_indicator_norm d;
  tt_indicator_norm_init(&d);
  if (n && TT_HAS_FIELD(tt_indicator_norm, n, camera)) d.camera = n->camera;
  if (n && TT_HAS_FIELD(tt_indicator_norm, n, scale)) d.scale = n->scale;
  return d;
}

tt_status tt_indicator_bounds(const tt_indicator_norm *n_, uint32_t index, double *lo, double *hi,
                              double *log_unit) {
  if (index >= TT_SCENE_INDICATOR_COUNT)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_indicator_bounds: index %u out of range "
                        "(%d indicators)",
                        index, TT_SCENE_INDICATOR_COUNT);
  tt_indicator_norm n = tt__norm(n_);
  double l = 0, h = tt__bound[index].hi, u = 0;
  if (tt__is_camera(index)) {
    h = tt__camera_bound(n.camera);
    l = -h;
  } else if (n.scale == TT_INDICATOR_LOG) {
    u = tt__bound[index].log_unit;
  }
  if (lo) *lo = l;
  if (hi) *hi = h;
  if (log_unit) *log_unit = u;
  return TT_OK;
}

uint32_t tt_indicators_normalize(const tt_indicator_norm *n_,
                                 const double raw[TT_SCENE_INDICATOR_COUNT],
                                 double out[TT_SCENE_INDICATOR_COUNT]) {
  tt_indicator_norm n = tt__norm(n_);
  double extent = raw[TT__EXTENT];
  if (!(extent > 0) || !isfinite(extent)) extent = 1.0; /* as tt_scene_indicators: D = 0 -> 1 */
  uint32_t clamped = 0;
  double tmp[TT_SCENE_INDICATOR_COUNT];
  for (uint32_t i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) {
    double x = raw[i], lo, hi, unit, u;
    tt_indicator_bounds(&n, i, &lo, &hi, &unit);
    if (tt__is_camera(i) && n.camera == TT_INDICATOR_CAMERA_EXTENT) {
      lo *= extent;
      hi *= extent;
    }
    if (!isfinite(x)) {
      tmp[i] = 0.0;
      clamped++;
      continue;
    }
    if (unit > 0) u = x > 0 ? log10(1.0 + x / unit) / log10(1.0 + hi / unit) : 0.0;
    else u = (x - lo) / (hi - lo);
    if (u < 0.0 || u > 1.0) {
      clamped++;
      u = u < 0.0 ? 0.0 : 1.0;
    }
    tmp[i] = u;
  }
  memcpy(out, tmp, sizeof tmp);
  return clamped;
}

static const char *const tt__camera_names[] = {"extent", "table", "text"};
static const char *const tt__scale_names[] = {"linear", "log"};

const char *tt_indicator_norm_id(const tt_indicator_norm *n_, char *buf, size_t size) {
  tt_indicator_norm n = tt__norm(n_);
  unsigned c = (unsigned)n.camera < 3 ? (unsigned)n.camera : 0;
  unsigned s = (unsigned)n.scale < 2 ? (unsigned)n.scale : 0;
  snprintf(buf, size, "tt.indicators/%d camera=%s scale=%s", TT_INDICATOR_SPACE_VERSION,
           tt__camera_names[c], tt__scale_names[s]);
  return buf;
}

tt_status tt_indicator_norm_parse(const char *text, tt_indicator_norm *out) {
  tt_indicator_norm n;
  tt_indicator_norm_init(&n);
  if (!text) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "indicator normalisation: no text");
  const char *p = text;
  while (*p) {
    while (*p == ' ' || *p == ',') p++;
    if (!*p) break;
    size_t len = strcspn(p, " ,");
    char item[64];
    if (len >= sizeof item)
      return tt_set_error(TT_ERR_PARSE,
                          "indicator normalisation \"%s\": item \"%.*s...\" is too "
                          "long",
                          text, 20, p);
    memcpy(item, p, len);
    item[len] = 0;
    p += len;
    int v;
    if (!strncmp(item, "tt.indicators/", 14)) {
      if (sscanf(item + 14, "%d", &v) != 1 || v != TT_INDICATOR_SPACE_VERSION)
        return tt_set_error(TT_ERR_PARSE,
                            "indicator normalisation \"%s\": state space \"%s\" is "
                            "not this library's tt.indicators/%d",
                            text, item, TT_INDICATOR_SPACE_VERSION);
    } else if (!strncmp(item, "camera=", 7)) {
      for (v = 0; v < 3 && strcmp(item + 7, tt__camera_names[v]); v++) {}
      if (v == 3)
        return tt_set_error(TT_ERR_PARSE,
                            "indicator normalisation \"%s\": camera=\"%s\": expected "
                            "extent, table or text",
                            text, item + 7);
      n.camera = (tt_indicator_camera)v;
    } else if (!strncmp(item, "scale=", 6)) {
      for (v = 0; v < 2 && strcmp(item + 6, tt__scale_names[v]); v++) {}
      if (v == 2)
        return tt_set_error(TT_ERR_PARSE,
                            "indicator normalisation \"%s\": scale=\"%s\": expected "
                            "linear or log",
                            text, item + 6);
      n.scale = (tt_indicator_scale)v;
    } else {
      return tt_set_error(TT_ERR_PARSE,
                          "indicator normalisation \"%s\": unknown item \"%s\" "
                          "(expected camera=extent|table|text, scale=linear|log)",
                          text, item);
    }
  }
  if (out) *out = n;
  return TT_OK;
}
