/* Files: internal helpers beside the public tunetrace/file.h (files.c, atomic_file.c).
 * Internal to libtunetrace. */
#ifndef TT_UTIL_FILES_H
#define TT_UTIL_FILES_H

#include <tunetrace/common.h>

#include <stddef.h>
#include <sys/stat.h>
#include <sys/types.h>

/* Case-insensitive file-name suffix test (".pbrt", ".json"). */
int tt__has_ext(const char *path, const char *ext);

/* tt_file_read of a scene file (what = "scene file", default limit); errors name the file. */
tt_status tt__read_file(const char *path, char **out, size_t *len);

/* The one check of every input the library, the host and the plugins read: opens `path`
 * read-only without blocking (a FIFO, a device, a socket or a directory is refused at once,
 * before anything reads it) and returns a blocking descriptor of the regular file with its
 * stat in *st; or -1 with the reason in `why` ("No such file or directory", "a FIFO, not a
 * regular file") and errno set. tt_file_read, tt_file_check_regular and the functions
 * below are built on it. */
int tt__open_regular_fd(const char *path, struct stat *st, char *why, size_t n);

/* 0 if `path` is a regular file; else -1 and the reason in `why` ("No such file or
 * directory", "a FIFO, not a regular file"), for loaders that word their own message. Never
 * blocks. */
int tt__file_regular_reason(const char *path, char *why, size_t n);

/* "a directory", "a FIFO", ... for a st_mode that is not a regular file. */
const char *tt__file_kind(mode_t mode);

#endif /* TT_UTIL_FILES_H */
