/* The pbrt-v4 importer's entry point (pbrt_parse.c), called by format dispatch
 * (io/scene_load.c) and by scene.json's "import". Internal to libtunetrace. */
#ifndef TT_IO_PBRT_H
#define TT_IO_PBRT_H

#include <tunetrace/scene.h>

/* Loads a pbrt-v4 scene file (pbrt_parse.c; Include/Import relative to the including
 * file). Errors are TT_ERR_IO / TT_ERR_PARSE with "file:line: ..." messages; unsupported
 * features warn once per location through the log host (tt_set_log_host) and are
 * approximated or skipped. */
tt_status tt__scene_load_pbrt(const char *path, tt_scene **out);

/* tt_scene_load_flags of the tt_scene_load_ex call running on this thread (set by
 * tt_scene_load_ex in io/scene_load.c, defined in pbrt_import.c);
 * 0 outside one. */
extern _Thread_local uint32_t tt__scene_load_flags;

#endif /* TT_IO_PBRT_H */
