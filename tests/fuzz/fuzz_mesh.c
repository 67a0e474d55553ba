/* libFuzzer: scene.json mesh files through tt__mesh_import, the path of a "file" entry:
 * the first byte picks the format by its low two bits (OBJ, glTF JSON, GLB through assimp,
 * PLY through io/ply) and split or merged parts by bit 2; the rest is the file, under the
 * name of that format (content of another format must be refused, never guessed from).
 * Oracle: indices within each part. */
#include "io/io_internal.h"

#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1) return 0;
  static const char *const names[4] = {"in.obj", "in.gltf", "in.ply", "in.glb"};
  const char *path = fuzz_write(names[data[0] & 3], data + 1, size - 1);
  tt__mesh_data *parts = NULL;
  uint32_t count = 0;
  if (tt__mesh_import(path, "m", (data[0] >> 2) & 1, "fuzz", &parts, &count) == TT_OK) {
    for (uint32_t i = 0; i < count; i++) {
      for (size_t k = 0; k < 3 * (size_t)parts[i].triangle_count; k++)
        if (parts[i].indices[k] >= parts[i].vertex_count) abort();
      tt__mesh_data_free(&parts[i]);
    }
    free(parts);
  } else if (parts || count) {
    abort();
  }
  return 0;
}
