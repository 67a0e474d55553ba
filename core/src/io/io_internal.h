/* Scene file loaders (io/): the entry points format dispatch (scene_load.c) and the
 * scene.json importer call, and the mesh importer. They build scenes through the builders
 * of scene/scene_internal.h. Not part of the public ABI. */
#ifndef TT_IO_INTERNAL_H
#define TT_IO_INTERNAL_H

#include "scene/scene_internal.h"
#include "util/files.h"
#include "util/mat4.h"
#include "io/pbrt/pbrt.h"

#include <stdint.h>

/* Loads every triangle of an OBJ/PLY/glTF/... file through assimp. With split == 0 all
 * sub-meshes are merged into one; otherwise one tt__mesh_data per sub-mesh, named
 * "<base_name>/<sub-mesh name or index>". `where` prefixes error messages (e.g.
 * "x.json: meshes[2].file"). On success *out holds *count entries (free each with
 * tt__mesh_data_free, then free(*out)). */
tt_status tt__mesh_import(const char *file, const char *base_name, int split, const char *where,
                          tt__mesh_data **out, uint32_t *count);

/* Reads and loads a scene.json file with its own directory as the asset base; depth 0 for
 * the scene being loaded, 1 for a scene.json imported by it (scene_json.c). */
tt_status tt__scene_load_json_file(const char *path, int depth, tt_scene **out);

#endif /* TT_IO_INTERNAL_H */
