/* Indicator normalisation (tunetrace/indicators.h): every normalised value lies in [0, 1]
 * whatever the input, the thesis' bounds map onto 0 and 1, the camera modes and the log scale
 * do what the header says, ids parse back, and `host --indicators` prints the same numbers. */
#include "host_util.h"
#include "tt_test.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <tunetrace/tunetrace.h>
#include <tt_util/rng.h>

enum { N = TT_SCENE_INDICATOR_COUNT };

static uint64_t rng = 0x1234567u;
static double uniform(void) { return tt__u64_to_unit(tt__splitmix64(&rng)); }

/* Index of indicator `name`. */
static int idx(const char *name) {
  for (uint32_t i = 0; i < N; i++)
    if (!strcmp(tt_scene_indicator_name(i), name)) return (int)i;
  return -1;
}

static void bounds_respected(void) {
  tt_indicator_norm n;
  for (int mode = 0; mode < 6; mode++) {
    tt_indicator_norm_init(&n);
    n.camera = (tt_indicator_camera)(mode % 3);
    n.scale = (tt_indicator_scale)(mode / 3);
    for (int trial = 0; trial < 20000; trial++) {
      double raw[N], out[N];
      for (int i = 0; i < N; i++) {
        /* any magnitude and sign, some non-finite values */
        double e = uniform() * 80 - 40, s = uniform() < 0.3 ? -1 : 1;
        raw[i] = s * pow(10.0, e);
        if (uniform() < 0.01) raw[i] = uniform() < 0.5 ? NAN : INFINITY;
        if (uniform() < 0.05) raw[i] = 0;
      }
      tt_indicators_normalize(&n, raw, out);
      for (int i = 0; i < N; i++)
        CHECK_MSG(out[i] >= 0.0 && out[i] <= 1.0, "mode %d %s=%g -> %g", mode,
                  tt_scene_indicator_name(i), raw[i], out[i]);
    }
  }
}

static void known_values(void) {
  tt_indicator_norm n;
  tt_indicator_norm_init(&n);
  CHECK(n.camera == TT_INDICATOR_CAMERA_EXTENT && n.scale == TT_INDICATOR_LINEAR);
  double raw[N] = {0}, out[N];
  raw[idx("triangles")] = 1e7;
  raw[idx("meshes")] = 5e4;
  raw[idx("lights")] = 2e5; /* above the bound: clamped */
  raw[idx("fov_y")] = 45;
  raw[idx("diffuse_ratio")] = 0.25;
  raw[idx("extent")] = 20;
  raw[idx("camera_x")] = 20;  /* = extent: 1 */
  raw[idx("camera_y")] = -10; /* = -extent/2: 0.25 */
  raw[idx("target_z")] = -30; /* below -extent: clamped */
  raw[idx("total_area")] = 5;
  raw[idx("mean_var_tri_size")] = 1e-2;
  uint32_t clamped = tt_indicators_normalize(&n, raw, out);
  CHECK(clamped == 2);
  CHECK_NEAR(out[idx("triangles")], 1.0, 1e-15);
  CHECK_NEAR(out[idx("meshes")], 0.5, 1e-15);
  CHECK_NEAR(out[idx("lights")], 1.0, 0);
  CHECK_NEAR(out[idx("fov_y")], 0.25, 1e-15);
  CHECK_NEAR(out[idx("diffuse_ratio")], 0.25, 1e-15);
  CHECK_NEAR(out[idx("extent")], 20 / 1e5, 1e-15);
  CHECK_NEAR(out[idx("camera_x")], 1.0, 1e-15);
  CHECK_NEAR(out[idx("camera_y")], 0.25, 1e-15);
  CHECK_NEAR(out[idx("camera_z")], 0.5, 1e-15);
  CHECK_NEAR(out[idx("target_z")], 0.0, 0);
  CHECK_NEAR(out[idx("total_area")], 0.5, 1e-15);
  CHECK_NEAR(out[idx("mean_var_tri_size")], 1.0, 1e-15);

  /* the thesis' two camera bounds */
  n.camera = TT_INDICATOR_CAMERA_TABLE;
  tt_indicators_normalize(&n, raw, out);
  CHECK_NEAR(out[idx("camera_x")], 1.0, 0); /* 20 > 10: clamped */
  CHECK_NEAR(out[idx("camera_y")], 0.0, 0);
  n.camera = TT_INDICATOR_CAMERA_TEXT;
  tt_indicators_normalize(&n, raw, out);
  CHECK_NEAR(out[idx("camera_x")], 0.5 + 0.5 * 20 / 1e4, 1e-15);
  double lo, hi, unit;
  CHECK(tt_indicator_bounds(&n, idx("camera_z"), &lo, &hi, &unit) == TT_OK && lo == -1e4 &&
        hi == 1e4 && unit == 0);
  CHECK(tt_indicator_bounds(&n, N, &lo, &hi, &unit) == TT_ERR_INVALID_ARGUMENT);

  /* log scale: log10(1 + x / unit) / log10(1 + bound / unit) on the decade-spanning ones */
  n.scale = TT_INDICATOR_LOG;
  double r2[N] = {0};
  r2[idx("triangles")] = 9;             /* log10(10) / log10(1e7 + 1) */
  r2[idx("extent")] = 99999;            /* 1 - tiny */
  r2[idx("mean_var_tri_size")] = 9e-12; /* log10(10) / log10(1 + 1e10) */
  r2[idx("total_area")] = 5;            /* stays linear */
  tt_indicators_normalize(&n, r2, out);
  CHECK_NEAR(out[idx("triangles")], 1.0 / log10(1e7 + 1), 1e-12);
  CHECK_NEAR(out[idx("extent")], log10(1e5) / log10(1e5 + 1), 1e-12);
  CHECK_NEAR(out[idx("mean_var_tri_size")], 1.0 / log10(1 + 1e10), 1e-12);
  CHECK_NEAR(out[idx("total_area")], 0.5, 1e-15);
  CHECK(tt_indicator_bounds(&n, idx("fov_y"), &lo, &hi, &unit) == TT_OK && unit == 0);
  CHECK(tt_indicator_bounds(&n, idx("var_var_tri_size"), &lo, &hi, &unit) == TT_OK &&
        unit == 1e-24 && hi == 1e-2);
  /* monotone in every indicator */
  for (int i = 0; i < N; i++) {
    double a[N] = {0}, b[N] = {0}, ua[N], ub[N];
    a[11] = b[11] = 50;
    double lo2, hi2;
    tt_indicator_bounds(&n, (uint32_t)i, &lo2, &hi2, NULL);
    a[i] = lo2 + 0.1 * (hi2 - lo2);
    b[i] = lo2 + 0.2 * (hi2 - lo2);
    tt_indicators_normalize(&n, a, ua);
    tt_indicators_normalize(&n, b, ub);
    CHECK_MSG(ua[i] < ub[i], "%s not increasing", tt_scene_indicator_name((uint32_t)i));
  }
  /* in place */
  double same[N];
  memcpy(same, r2, sizeof same);
  tt_indicators_normalize(&n, same, same);
  tt_indicators_normalize(&n, r2, out);
  CHECK(!memcmp(same, out, sizeof out));
}

static void ids(void) {
  char id[96];
  for (int mode = 0; mode < 6; mode++) {
    tt_indicator_norm n, m;
    tt_indicator_norm_init(&n);
    n.camera = (tt_indicator_camera)(mode % 3);
    n.scale = (tt_indicator_scale)(mode / 3);
    tt_indicator_norm_id(&n, id, sizeof id);
    CHECK_MSG(tt_indicator_norm_parse(id, &m) == TT_OK && m.camera == n.camera &&
                  m.scale == n.scale,
              "%s", id);
  }
  tt_indicator_norm m;
  CHECK(tt_indicator_norm_parse("scale=log", &m) == TT_OK && m.scale == TT_INDICATOR_LOG &&
        m.camera == TT_INDICATOR_CAMERA_EXTENT);
  CHECK(tt_indicator_norm_parse("camera=text, scale=linear", &m) == TT_OK &&
        m.camera == TT_INDICATOR_CAMERA_TEXT);
  CHECK(tt_indicator_norm_parse("camera=far", &m) == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(), "expected extent, table or text");
  CHECK(tt_indicator_norm_parse("scale=cubic", &m) == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(), "expected linear or log");
  CHECK(tt_indicator_norm_parse("tt.indicators/2 camera=text", &m) == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(), "tt.indicators/1");
  CHECK(tt_indicator_norm_parse("colour=red", &m) == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(), "unknown item \"colour=red\"");
}

/* host --indicators prints what the library computes for the same view. */
static void host_json(void) {
  static char out[1 << 16];
  const char *scene = source_path("scenes/cornell-box/path.json");
  char args[4400];
  snprintf(args, sizeof args, "--indicators --camera-index 30 --indicator-norm scale=log '%s'",
           scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  cJSON *root = cJSON_Parse(strchr(out, '{'));
  CHECK(root != NULL);
  if (!root) return;
  tt_scene *s = NULL;
  CHECK(tt_scene_load(scene, &s) == TT_OK);
  const tt_camera *c0 = tt_scene_camera(s);
  tt_camera cam;
  double t = c0->keys[0].time + (c0->keys[c0->key_count - 1].time - c0->keys[0].time) * 30 / 99.0;
  tt_scene_camera_at(s, t, &cam);
  tt_scene_set_camera(s, &cam);
  double raw[N], unit[N];
  tt_scene_indicators(s, raw);
  tt_indicator_norm n;
  tt_indicator_norm_parse("scale=log", &n);
  tt_indicators_normalize(&n, raw, unit);
  cJSON *r = cJSON_GetObjectItem(root, "raw"), *u = cJSON_GetObjectItem(root, "normalized");
  for (uint32_t i = 0; i < N; i++) {
    const char *name = tt_scene_indicator_name(i);
    CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(r, name)), raw[i],
               1e-12 * (1 + fabs(raw[i])));
    CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(u, name)), unit[i], 1e-12);
  }
  CHECK(!strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(root, "normalization")),
                "tt.indicators/1 camera=extent scale=log"));
  CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(root, "camera_index")) == 30);
  CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(root, "compute_ms")) >= 0);
  CHECK(cJSON_IsArray(cJSON_GetObjectItem(root, "clamped")));
  cJSON_Delete(root);
  tt_scene_destroy(s);
  snprintf(args, sizeof args, "--indicators --indicator-norm camera=near '%s'", scene);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--indicator-norm");
}

int main(void) {
  bounds_respected();
  known_values();
  ids();
  host_json();
  return tt_test_finish("indicators_norm");
}
