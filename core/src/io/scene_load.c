/* Format dispatch: tt_scene_load picks the loader by file-name suffix. */
#include "io/io_internal.h"

#include <tunetrace/scene.h>

/* tt__scene_load_flags (defined by the pbrt importer, the layer below, which reads it:
 * io/pbrt/pbrt.h) holds the flags of the tt_scene_load_ex call running on this thread, also
 * when a scene.json imports the pbrt file. */
tt_status tt_scene_load_ex(const char *path, uint32_t flags, tt_scene **out) {
  uint32_t saved = tt__scene_load_flags;
  tt__scene_load_flags = flags;
  tt_status st = tt_scene_load(path, out);
  tt__scene_load_flags = saved;
  return st;
}

/* Picks the loader by suffix: pbrt-v4, glTF 2.0 (through assimp), else scene.json. */
tt_status tt_scene_load(const char *path, tt_scene **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_scene_load: out is NULL");
  *out = NULL;
  if (!path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_scene_load: path is NULL");
  if (tt__has_ext(path, ".pbrt")) return tt__scene_load_pbrt(path, out);
  if (tt__has_ext(path, ".gltf") || tt__has_ext(path, ".glb"))
    return tt__scene_load_gltf(path, 0, out);
  if (!tt__has_ext(path, ".json"))
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "%s: unsupported scene format (expected .json, .pbrt, .gltf or .glb)",
                        path);
  return tt__scene_load_json_file(path, 0, out);
}
