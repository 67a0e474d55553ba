/* Files: whole-file reads and file-name suffix tests (files.c). Internal to libtunetrace. */
#ifndef TT_UTIL_FILES_H
#define TT_UTIL_FILES_H

#include <tunetrace/common.h>

#include <stddef.h>

/* Case-insensitive file-name suffix test (".pbrt", ".json"). */
int tt__has_ext(const char *path, const char *ext);

/* Reads a whole file into a NUL-terminated malloc'ed buffer; errors name the file. */
tt_status tt__read_file(const char *path, char **out, size_t *len);

#endif /* TT_UTIL_FILES_H */
