/* libFuzzer: scene.json from memory (tt_scene_load_json), then what a renderer asks of a
 * loaded scene (bounds, camera path, poses of an animated scene, indicators, resolution
 * override). Mesh files it names
 * resolve against an empty scratch folder. */
#include <tunetrace/scene.h>

#include "fuzz_util.h"

#include <math.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  tt_scene *s = NULL;
  if (tt_scene_load_json((const char *)data, size, "fuzz.json", fuzz_dir(), &s) != TT_OK) {
    if (s) abort(); /* an error must not hand out a scene */
    return 0;
  }
  float lo[3], hi[3];
  tt_scene_bounds(s, lo, hi);
  for (int a = 0; a < 3; a++)
    if (!isfinite(lo[a]) || !isfinite(hi[a]) || lo[a] > hi[a]) abort();
  for (uint32_t i = 0; i < tt_scene_mesh_count(s); i++) {
    const tt_mesh *m = tt_scene_mesh(s, i);
    for (size_t k = 0; k < 3 * (size_t)m->triangle_count; k++)
      if (m->indices[k] >= m->vertex_count) abort();
  }
  /* an animated scene posed across its time range stays finite (a failed pose keeps the
   * last good one) */
  if (tt_scene_animated(s)) {
    double t0, t1;
    tt_scene_time_range(s, &t0, &t1);
    for (int k = 0; k <= 4; k++) {
      double t = t0 + (t1 - t0) * k / 3.0 - 0.5;
      tt_scene_set_time(s, t, t - 0.04);
      tt_scene_bounds(s, lo, hi);
      for (int a = 0; a < 3; a++)
        if (!isfinite(lo[a]) || !isfinite(hi[a]) || lo[a] > hi[a]) abort();
      for (uint32_t i = 0; i < tt_scene_mesh_count(s); i++) {
        const tt_mesh *m = tt_scene_mesh(s, i);
        for (size_t v = 0; v < 3 * (size_t)m->vertex_count; v++)
          if (!isfinite(m->positions[v]) || !isfinite(m->prev_positions[v])) abort();
      }
    }
  }
  const tt_camera *c = tt_scene_camera(s);
  tt_camera at;
  for (int k = 0; k <= 4; k++) tt_scene_camera_at(s, c->key_count ? c->keys[0].time + k : 0, &at);
  double ind[TT_SCENE_INDICATOR_COUNT];
  tt_scene_indicators(s, ind);
  tt_scene_set_resolution(s, 7, 5);
  tt_scene_destroy(s);
  return 0;
}
