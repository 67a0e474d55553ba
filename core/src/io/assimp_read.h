/* assimp, restricted to the readers that claim the file's extension. Internal to
 * libtunetrace (io/).
 *
 * Why: when none of the readers that claim an extension accepts the content (two claim
 * .gltf and .glb, the glTF 1 and glTF 2 readers), assimp 5.2.5's Importer::ReadFile guesses
 * the format from the content and runs whichever of its ~60 parsers recognises it. A PLY
 * named .gltf thus reached assimp's PLY parser, which spins forever on a corrupt header
 * (found by fuzz_mesh), although tunetrace reads PLY with its own reader. Here every other
 * reader is unregistered before the import, so a file is parsed only as the format its
 * name says, or refused. */
#ifndef TT_IO_ASSIMP_READ_H
#define TT_IO_ASSIMP_READ_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

struct aiScene;
typedef struct tt__assimp tt__assimp;

typedef enum tt__assimp_result {
  TT__ASSIMP_OK = 0,
  TT__ASSIMP_UNKNOWN_EXTENSION, /* no assimp reader claims the file's extension */
  TT__ASSIMP_FAILED,            /* the readers refused or failed: the reason is in `why` */
  TT__ASSIMP_OUT_OF_MEMORY,
} tt__assimp_result;

/* Imports `file` with the post-processing `flags` (aiProcess_*) using only the readers that
 * claim its extension. On TT__ASSIMP_OK *scene is owned by *handle (free both with
 * tt__assimp_free); otherwise both are NULL and `why` (n bytes) holds assimp's reason.
 * Thread-safe: each call has its own importer and error text. */
tt__assimp_result tt__assimp_read(const char *file, unsigned flags, tt__assimp **handle,
                                  const struct aiScene **scene, char *why, size_t n);

/* Runs assimp's data-structure validation (aiProcess_ValidateDataStructure) on an import,
 * after the caller has checked what it words better itself (key order); TT__ASSIMP_FAILED
 * with the reason in `why` when the scene is inconsistent (the import is then unusable:
 * free it). */
tt__assimp_result tt__assimp_validate(tt__assimp *handle, char *why, size_t n);

/* Frees an import and its scene. NULL is ignored. */
void tt__assimp_free(tt__assimp *handle);

#ifdef __cplusplus
}
#endif

#endif /* TT_IO_ASSIMP_READ_H */
