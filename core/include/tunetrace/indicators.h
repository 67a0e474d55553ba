/* tunetrace: the predictors' state space — scene indicators normalised to [0, 1] (thesis
 * 3.3.2: "we need to normalize parameters and indicators to a comparable scale").
 *
 * tt_scene_indicators (scene.h) computes the 17 raw indicators of Table 3.2. A distance-based
 * model (nearest neighbour, RBF features) needs them on one scale, so each one is mapped to
 * [0, 1] by a fixed bound; values outside the bound are clamped (the count is returned).
 *
 * Bounds (thesis Table 3.2 and the text of 3.3.2): meshes, lights 1e5; triangles 1e7;
 * extent 1e5; total area, light area, area per mesh 10; fov 180 degrees; diffuse ratio 1;
 * mean and variance of VarTriSize 1e-2. The camera position and target have two bounds in
 * the thesis, +-10 (the table) and 1e4 (the text), so the camera is a choice:
 *   TT_INDICATOR_CAMERA_EXTENT  u = (1 + x / extent) / 2, the scene's own scale (default;
 *                               see tools/hybrid/README.md for the measurement behind it)
 *   TT_INDICATOR_CAMERA_TABLE   u = (1 + x / 10) / 2
 *   TT_INDICATOR_CAMERA_TEXT    u = (1 + x / 1e4) / 2
 * Where a bound spans decades above a natural unit (counts from 1, the extent from 1 world
 * unit, light area and area per mesh from 1e-6, the VarTriSize statistics from 1e-12 and
 * 1e-24) the log scale maps u = log10(1 + x / unit) / log10(1 + bound / unit) instead.
 *
 * A normalisation is named by an id string ("tt.indicators/1 camera=extent scale=linear"):
 * model files record it, so a model is never queried with states of another space.
 *
 * Threads: every function here is pure and thread-safe.
 */
#ifndef TUNETRACE_INDICATORS_H
#define TUNETRACE_INDICATORS_H

#include <tunetrace/scene.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Version of the indicator state space (the "tt.indicators/N" of the id). */
#define TT_INDICATOR_SPACE_VERSION 1

typedef enum tt_indicator_camera {
  TT_INDICATOR_CAMERA_EXTENT = 0, /* +- the scene's extent (bounding-box diagonal) */
  TT_INDICATOR_CAMERA_TABLE = 1,  /* +- 10 world units (thesis Table 3.2) */
  TT_INDICATOR_CAMERA_TEXT = 2    /* +- 1e4 world units (thesis 3.3.2 text) */
} tt_indicator_camera;

typedef enum tt_indicator_scale {
  TT_INDICATOR_LINEAR = 0, /* u = x / bound for every indicator */
  TT_INDICATOR_LOG = 1     /* log10 scale for the indicators that span decades */
} tt_indicator_scale;

typedef struct tt_indicator_norm {
  uint32_t struct_size; /* sizeof(tt_indicator_norm) */
  tt_indicator_camera camera;
  tt_indicator_scale scale;
} tt_indicator_norm;

/* Fills `n` with the default normalisation. */
TT_API void tt_indicator_norm_init(tt_indicator_norm *n);

/* Bound of indicator `index` under `n`: raw values in [lo, hi] map onto [0, 1]; `*log`
 * (may be NULL) is set to the log unit when the indicator is on a log scale, else 0.
 * The camera bounds of TT_INDICATOR_CAMERA_EXTENT are given for extent 1 (multiply by the
 * state's extent). TT_ERR_INVALID_ARGUMENT for an index out of range. */
TT_API tt_status tt_indicator_bounds(const tt_indicator_norm *n, uint32_t index, double *lo,
                                     double *hi, double *log_unit);

/* Maps the raw indicators `raw` (tt_scene_indicators) to [0, 1] into `out` (may be `raw`).
 * Non-finite values map to 0. Returns how many values were outside their bound (clamped). */
TT_API uint32_t tt_indicators_normalize(const tt_indicator_norm *n,
                                        const double raw[TT_SCENE_INDICATOR_COUNT],
                                        double out[TT_SCENE_INDICATOR_COUNT]);

/* Writes the id of the normalisation, e.g. "tt.indicators/1 camera=extent scale=linear",
 * into `buf` (64 bytes are enough); returns buf. */
TT_API const char *tt_indicator_norm_id(const tt_indicator_norm *n, char *buf, size_t size);

/* Parses "camera=extent|table|text" and "scale=linear|log" items separated by ',' or ' '
 * (an id as written by tt_indicator_norm_id parses too; unset items keep the defaults).
 * Errors name the item and the accepted values. */
TT_API tt_status tt_indicator_norm_parse(const char *text, tt_indicator_norm *out);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_INDICATORS_H */
