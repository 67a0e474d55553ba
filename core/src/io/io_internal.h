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

/* A .gltf must be a JSON object, a .glb a GLB container whose chunks lie inside it
 * (mesh_import.c); checked before assimp reads the file. Other extensions pass. */
tt_status tt__gltf_check(const char *file, const char *where);

/* Loads a glTF 2.0 file (.gltf, .glb) as a scene with its node hierarchy, animation (node
 * TRS channels, morph target weights), skins, materials and camera (gltf_scene.c).
 * `imported`: the scene is wrapped by a scene.json "import", which brings its own lights;
 * a file loaded on its own without lights or emitters gets a dim sky and a sun. */
tt_status tt__scene_load_gltf(const char *path, int imported, tt_scene **out);

/* Reads and loads a scene.json file with its own directory as the asset base; depth 0 for
 * the scene being loaded, 1 for a scene.json imported by it (scene_json.c). */
tt_status tt__scene_load_json_file(const char *path, int depth, tt_scene **out);

#endif /* TT_IO_INTERNAL_H */
