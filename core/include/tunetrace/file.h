/* tunetrace: files — whole-file reads that refuse what is not a regular file, and atomic
 * writes (temporary file in the same folder, fsync, rename).
 *
 * Every reader and writer of libtunetrace, the host and the shipped plugins goes through
 * these, so that a FIFO or /dev/zero named as an input is an error rather than a hang or an
 * out-of-memory, and so that a kill, a full disk or a crash during a write leaves either the
 * previous file or the complete new one, never a truncated file under the final name.
 * Plugins may use them for their own files (weights, models, state).
 *
 * Errors are TT_ERR_IO (or TT_ERR_OUT_OF_MEMORY) with a message naming the file and the
 * operating system's reason. All functions are thread-safe (distinct files).
 */
#ifndef TUNETRACE_FILE_H
#define TUNETRACE_FILE_H

#include <tunetrace/common.h>

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Default size limit of tt_file_read when max_bytes is 0: 4 GiB. */
#define TT_FILE_READ_DEFAULT_MAX ((size_t)4 << 30)

/* Reads the regular file `path` whole into a NUL-terminated buffer (free with tt_free);
 * *size excludes the NUL. Directories, FIFOs, devices and sockets are refused without
 * blocking, and so are files larger than `max_bytes` (0: TT_FILE_READ_DEFAULT_MAX). `what`
 * names the file's role in messages ("scene file", "PLY file"); NULL means "file". */
TT_API tt_status tt_file_read(const char *path, const char *what, size_t max_bytes, char **data,
                              size_t *size);

/* TT_OK if `path` is a regular file (or a link to one), TT_ERR_IO with the reason (missing,
 * a directory, a FIFO, a device) otherwise. `what` as for tt_file_read. Never blocks. */
TT_API tt_status tt_file_check_regular(const char *path, const char *what);

/* 1 if `a` and `b` name the same file: the same device and inode when both exist (hard and
 * symbolic links included), else, when neither exists yet, the same real folder and name;
 * 0 otherwise. */
TT_API int tt_file_same(const char *a, const char *b);

/* TT_ERR_INVALID_ARGUMENT, with a message naming both files and their roles ("stats file",
 * "scene file"), if writing `output` would replace `input` (tt_file_same); TT_OK otherwise.
 * Programs call it before any work for every pair of an output and an input. */
TT_API tt_status tt_file_check_not_input(const char *output, const char *output_what,
                                         const char *input, const char *input_what);

/* Checks before a long computation that `path` can be written atomically later: it is not
 * a directory or another non-regular file, and a file can be created in its folder (one is
 * created and removed). The message names the path and the OS reason. */
TT_API tt_status tt_file_check_writable(const char *path);

/* Writes `size` bytes to `path` atomically (tt_atomic_file_open, fwrite, commit). */
TT_API tt_status tt_file_write_atomic(const char *path, const void *data, size_t size);

/* An output being written: a temporary file beside its final path. */
typedef struct tt_atomic_file tt_atomic_file;

/* Creates a temporary file in the folder of `path` (".NAME.tmp-NNNNNN", the first free
 * number), with the permissions `path` already has, else 0666 minus the umask, and holds a
 * lock on it until commit or abort. Temporaries of the same output left by writers that are
 * gone (a kill: the lock is free) and not modified for a minute are removed; a live
 * writer's never are. `*out` is owned by the caller: end it with tt_atomic_file_commit or
 * tt_atomic_file_abort. */
TT_API tt_status tt_atomic_file_open(const char *path, tt_atomic_file **out);

/* The stream to write the content to (owned by `file`; do not fclose it). */
TT_API FILE *tt_atomic_file_stream(tt_atomic_file *file);

/* Flushes, checks that every write succeeded (a full disk or a write error anywhere
 * fails here, even if the writer ignored it), fsyncs, renames the temporary file over
 * `path` and fsyncs the folder. On failure the temporary file is removed and `path` is
 * unchanged. Frees `file` in both cases. */
TT_API tt_status tt_atomic_file_commit(tt_atomic_file *file);

/* Removes the temporary file and frees `file`; `path` is unchanged. NULL is ignored. */
TT_API void tt_atomic_file_abort(tt_atomic_file *file);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_FILE_H */
