/* libFuzzer: the pbrt-v4 importer on one file (Include/Import of other names find nothing
 * in the scratch folder; of its own name, a cycle). */
#include <tunetrace/scene.h>

#include "fuzz_util.h"

#include <math.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_write("in.pbrt", data, size);
  tt_scene *s = NULL;
  if (tt_scene_load(path, &s) != TT_OK) {
    if (s) abort();
    return 0;
  }
  float lo[3], hi[3];
  tt_scene_bounds(s, lo, hi);
  for (int a = 0; a < 3; a++)
    if (!isfinite(lo[a]) || !isfinite(hi[a])) abort();
  for (uint32_t i = 0; i < tt_scene_mesh_count(s); i++) {
    const tt_mesh *m = tt_scene_mesh(s, i);
    for (size_t k = 0; k < 3 * (size_t)m->triangle_count; k++)
      if (m->indices[k] >= m->vertex_count) abort();
  }
  tt_scene_destroy(s);
  return 0;
}
