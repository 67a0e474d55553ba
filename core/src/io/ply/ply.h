/* PLY meshes (ply_read.c): the reader shared by the pbrt importer and scene.json mesh files.
 * Internal to libtunetrace. */
#ifndef TT_IO_PLY_H
#define TT_IO_PLY_H

#include "scene/scene_internal.h"

#include <stddef.h>

/* Reads an ASCII or binary PLY file (".ply.gz" too when built with zlib) into triangles;
 * polygons are fanned. Only regular files are read, at most TT_FILE_READ_DEFAULT_MAX bytes
 * (decompressed). `where` (e.g. "file:line", "x.json: meshes[2].file") prefixes error
 * messages. On failure `*out` is empty. */
tt_status tt__ply_read(const char *path, const char *where, tt__mesh_data *out);

/* Parses a PLY held in memory (`len` bytes, no terminator needed); `path` names it in
 * messages. The fuzz harness calls this directly. `*out` is filled only on success (its
 * arrays then belong to the caller: tt__mesh_data_free); on failure nothing is allocated. */
tt_status tt__ply_parse(const unsigned char *data, size_t len, const char *path, const char *where,
                        tt__mesh_data *out);

#endif /* TT_IO_PLY_H */
