/* libFuzzer: the PLY reader (io/ply) on a buffer, as pbrt plymesh shapes and scene.json
 * mesh files reach it. Oracle: every index of a loaded mesh is a vertex of it. */
#include "io/ply/ply.h"

#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  tt__mesh_data m;
  memset(&m, 0, sizeof m);
  if (tt__ply_parse(data, size, "fuzz.ply", "fuzz", &m) == TT_OK) {
    if (!m.positions || !m.indices) abort();
    for (size_t k = 0; k < 3 * (size_t)m.triangle_count; k++)
      if (m.indices[k] >= m.vertex_count) abort();
  }
  tt__mesh_data_free(&m);
  return 0;
}
