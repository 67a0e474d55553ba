/* Format dispatch: tt_scene_load picks the loader by file-name suffix. */
#include "io/io_internal.h"

#include <tunetrace/scene.h>

/* Reads the file and hands it to the JSON loader with its directory as the asset base. */
tt_status tt_scene_load(const char *path, tt_scene **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_scene_load: out is NULL");
  *out = NULL;
  if (!path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_scene_load: path is NULL");
  if (tt__has_ext(path, ".pbrt")) return tt__scene_load_pbrt(path, out);
  if (!tt__has_ext(path, ".json"))
    return tt_set_error(TT_ERR_UNSUPPORTED, "%s: unsupported scene format (expected .json or .pbrt)", path);
  return tt__scene_load_json_file(path, 0, out);
}
