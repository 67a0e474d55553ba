/* Atomic outputs (tunetrace/file.h): content goes to a temporary file in the folder of the
 * final path, is flushed and fsync()ed, then rename()d over the final path and the folder
 * fsync()ed. rename within one folder is atomic on POSIX file systems, so a reader, a kill
 * or a crash sees the old file or the complete new one. Writes go through a stdio stream
 * whose backend (fopencookie) records the first failing write(2) with its errno, so a full
 * disk is reported at commit even when the code that wrote (OpenImageIO's PNG writer, for
 * one) ignored the error.
 *
 * Temporaries are numbered: ".NAME.tmp-000000", "-000001", ... (six hex digits), each writer
 * taking the first free number with O_EXCL, so the temporaries of an output are found by
 * probing a few names, without reading the folder (a sequence writes thousands of files
 * into one). A writer holds an exclusive flock on its temporary until commit or abort; the
 * kernel drops it when the writer dies. The next write of the same output removes that
 * output's temporaries whose lock is free and which were not modified for
 * TT__STALE_TEMP_AGE_S seconds: a killed write leaves its temporary at most until then, and
 * a concurrent writer's temporary (locked) is never touched. */
#include "util/files.h"

#include <tunetrace/file.h>
#include <tt_util/strings.h>

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

struct tt_atomic_file {
  FILE *stream; /* fopencookie stream over fd */
  int fd;
  int error;  /* first errno of a failed write, 0 if none */
  int direct; /* 1: writing straight into a device or FIFO (nothing to rename) */
  char *path; /* final path (a symlink's target, so the link survives) */
  char *tmp;  /* temporary path, NULL when direct */
};

/* stdio backend: full writes with EINTR retries; the first error is kept for commit. */
static ssize_t tt__cookie_write(void *cookie, const char *buf, size_t n) {
  tt_atomic_file *f = cookie;
  size_t done = 0;
  while (done < n) {
    ssize_t w = write(f->fd, buf + done, n - done);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      if (!f->error) f->error = w < 0 ? errno : EIO;
      return done ? (ssize_t)done : -1;
    }
    done += (size_t)w;
  }
  return (ssize_t)done;
}

/* Writers that seek (OpenEXR rewrites its offset table) need seek on the stream too. */
static int tt__cookie_seek(void *cookie, off64_t *pos, int whence) {
  tt_atomic_file *f = cookie;
  off_t r = lseek(f->fd, (off_t)*pos, whence);
  if (r < 0) return -1;
  *pos = (off64_t)r;
  return 0;
}

/* The fd is closed by commit/abort, which need its result. */
static int tt__cookie_close(void *cookie) {
  (void)cookie;
  return 0;
}

/* The folder of `path` ("." for a bare name) as a new string. */
static char *tt__dirname(const char *path) {
  const char *slash = strrchr(path, '/');
  if (!slash) return tt__strdup(".");
  if (slash == path) return tt__strdup("/");
  size_t n = (size_t)(slash - path);
  char *d = malloc(n + 1);
  if (d) {
    memcpy(d, path, n);
    d[n] = '\0';
  }
  return d;
}

/* fsync of a folder, so the rename itself survives a power loss; file systems that cannot
 * sync a directory (EINVAL) are not an error. */
static int tt__sync_dir(const char *dir) {
  int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return errno;
  int e = fsync(fd) == 0 || errno == EINVAL || errno == EROFS ? 0 : errno;
  close(fd);
  return e;
}

/* Temporaries per output: numbers a writer tries, and free numbers in a row after which the
 * probe for stale ones stops (numbers freed by finished writers leave gaps). */
#define TT__TEMP_SLOTS 4096
#define TT__TEMP_PROBE_GAP 8

/* ".NAME.tmp-NNNNNN" (slot `slot` in hex) of the output `path`, in its folder, into `t`. */
static void tt__temp_name(const char *path, unsigned slot, char *t, size_t n) {
  const char *slash = strrchr(path, '/');
  size_t dir_len = slash ? (size_t)(slash - path + 1) : 0;
  snprintf(t, n, "%.*s.%s.tmp-%06x", (int)dir_len, path, path + dir_len, slot);
}

/* Creates the first free ".NAME.tmp-NNNNNN" beside `path` with O_EXCL (0666 minus the umask,
 * as a plain open would); returns the fd and sets *tmp, or -1 with errno set. */
static int tt__create_temp(const char *path, char **tmp) {
  size_t n = strlen(path) + 32;
  char *t = malloc(n);
  if (!t) {
    errno = ENOMEM;
    return -1;
  }
  for (unsigned slot = 0; slot < TT__TEMP_SLOTS; slot++) {
    tt__temp_name(path, slot, t, n);
    int fd = open(t, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      *tmp = t;
      return fd;
    }
    if (errno != EEXIST) break;
  }
  int e = errno;
  free(t);
  errno = e;
  return -1;
}

/* Age (seconds since the last modification) from which an unlocked temporary of an output is
 * abandoned: it covers the moment between a writer's create and its flock, and writers that
 * do not lock (older builds), which keep the file's time fresh while they write. */
#define TT__STALE_TEMP_AGE_S 60

/* Removes the abandoned temporaries of the output `path` (see the top of the file); `own` is
 * the temporary this writer just created. Best effort: anything unexpected leaves a file. */
static void tt__remove_stale_temps(const char *path, const char *own) {
  size_t n = strlen(path) + 32;
  char *t = malloc(n);
  if (!t) return;
  for (unsigned slot = 0, gap = 0; slot < TT__TEMP_SLOTS && gap < TT__TEMP_PROBE_GAP; slot++) {
    tt__temp_name(path, slot, t, n);
    if (own && !strcmp(t, own)) {
      gap = 0;
      continue;
    }
    int fd = open(t, O_RDONLY | O_NONBLOCK | O_NOFOLLOW | O_NOCTTY | O_CLOEXEC);
    if (fd < 0) {
      gap = errno == ENOENT ? gap + 1 : 0;
      continue;
    }
    gap = 0;
    struct stat held, now_st;
    /* a writer alive holds its exclusive lock: a shared one is refused at once; the name
     * must still be the file locked (not a new writer's, made since) */
    if (fstat(fd, &held) == 0 && S_ISREG(held.st_mode) && flock(fd, LOCK_SH | LOCK_NB) == 0 &&
        lstat(t, &now_st) == 0 && now_st.st_dev == held.st_dev && now_st.st_ino == held.st_ino &&
        time(NULL) - now_st.st_mtime >= TT__STALE_TEMP_AGE_S)
      (void)unlink(t);
    close(fd); /* drops the shared lock */
  }
  free(t);
}

tt_status tt_file_check_writable(const char *path) {
  if (!path || !*path) return tt_set_error(TT_ERR_IO, "cannot write to an empty path");
  struct stat st;
  if (stat(path, &st) == 0) {
    if (S_ISDIR(st.st_mode))
      return tt_set_error(TT_ERR_IO, "%s: cannot write: is a directory", path);
    if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) return TT_OK; /* written directly */
    if (!S_ISREG(st.st_mode))
      return tt_set_error(TT_ERR_IO, "%s: cannot write: %s", path, tt__file_kind(st.st_mode));
  }
  char *tmp = NULL;
  int fd = tt__create_temp(path, &tmp);
  if (fd < 0) {
    int e = errno;
    char *dir = tt__dirname(path);
    tt_status s = tt_set_error(TT_ERR_IO, "%s: cannot write: cannot create a file in %s: %s", path,
                               dir ? dir : "its folder", strerror(e));
    free(dir);
    return s;
  }
  close(fd);
  unlink(tmp);
  free(tmp);
  return TT_OK;
}

tt_status tt_atomic_file_open(const char *path, tt_atomic_file **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_atomic_file_open: NULL output");
  *out = NULL;
  if (!path || !*path) return tt_set_error(TT_ERR_IO, "cannot write to an empty path");
  tt_atomic_file *f = calloc(1, sizeof *f);
  if (!f) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
  f->fd = -1;
  /* a symlink stays a symlink: its target is what gets replaced */
  struct stat lst, st;
  char *real = NULL;
  if (lstat(path, &lst) == 0 && S_ISLNK(lst.st_mode)) real = realpath(path, NULL);
  f->path = real ? real : tt__strdup(path);
  int have = f->path && stat(f->path, &st) == 0;
  if (!f->path) goto oom;
  if (have && S_ISDIR(st.st_mode)) {
    tt_set_error(TT_ERR_IO, "%s: cannot write: is a directory", path);
    goto fail;
  }
  if (have && (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode))) {
    /* /dev/null, /dev/stdout, a pipe: nothing to replace, write straight into it */
    f->direct = 1;
    f->fd = open(f->path, O_WRONLY | O_CLOEXEC | O_NOCTTY);
  } else if (have && !S_ISREG(st.st_mode)) {
    tt_set_error(TT_ERR_IO, "%s: cannot write: %s", path, tt__file_kind(st.st_mode));
    goto fail;
  } else {
    f->fd = tt__create_temp(f->path, &f->tmp);
    if (f->fd >= 0) {
      /* held until commit or abort (or death): other writers of this output leave it alone */
      while (flock(f->fd, LOCK_EX) != 0 && errno == EINTR) {}
      /* keep the permissions of the file being replaced */
      if (have) (void)fchmod(f->fd, st.st_mode & 07777);
      tt__remove_stale_temps(f->path, f->tmp);
    }
  }
  if (f->fd < 0) {
    int e = errno;
    char *dir = tt__dirname(f->path);
    if (f->direct) tt_set_error(TT_ERR_IO, "%s: cannot write: %s", path, strerror(e));
    else
      tt_set_error(TT_ERR_IO, "%s: cannot write: cannot create a file in %s: %s", path,
                   dir ? dir : "its folder", strerror(e));
    free(dir);
    goto fail;
  }
  cookie_io_functions_t io = {NULL, tt__cookie_write, tt__cookie_seek, tt__cookie_close};
  f->stream = fopencookie(f, "w", io);
  if (!f->stream) goto oom;
  *out = f;
  return TT_OK;
oom:
  tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory opening an output", path);
fail:
  tt_atomic_file_abort(f);
  return TT_ERR_IO;
}

FILE *tt_atomic_file_stream(tt_atomic_file *file) { return file ? file->stream : NULL; }

/* Frees everything; removes the temporary file if it is still there. */
static void tt__atomic_free(tt_atomic_file *f, int unlink_tmp) {
  if (f->stream) fclose(f->stream);
  if (f->fd >= 0) close(f->fd);
  if (unlink_tmp && f->tmp) unlink(f->tmp);
  free(f->path);
  free(f->tmp);
  free(f);
}

void tt_atomic_file_abort(tt_atomic_file *file) {
  if (file) tt__atomic_free(file, 1);
}

tt_status tt_atomic_file_commit(tt_atomic_file *f) {
  if (!f) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_atomic_file_commit: NULL file");
  int e = fflush(f->stream) == 0 ? 0 : (f->error ? f->error : errno ? errno : EIO);
  if (!e && (f->error || ferror(f->stream))) e = f->error ? f->error : EIO;
  const char *step = "write failed";
  if (!e && !f->direct && fsync(f->fd) != 0) e = errno, step = "fsync failed";
  if (!e) {
    fclose(f->stream);
    f->stream = NULL;
    int fd = f->fd;
    f->fd = -1;
    if (close(fd) != 0 && !f->direct) e = errno, step = "close failed";
  }
  if (!e && !f->direct && rename(f->tmp, f->path) != 0) e = errno, step = "rename failed";
  if (e) {
    tt_status s = tt_set_error(TT_ERR_IO, "%s: %s: %s%s", f->path, step, strerror(e),
                               f->direct ? "" : " (the previous file, if any, is unchanged)");
    tt__atomic_free(f, 1);
    return s;
  }
  if (!f->direct) {
    char *dir = tt__dirname(f->path);
    if (dir) (void)tt__sync_dir(dir); /* the new content is in place either way */
    free(dir);
  }
  tt__atomic_free(f, 0);
  return TT_OK;
}

tt_status tt_file_write_atomic(const char *path, const void *data, size_t size) {
  tt_atomic_file *f;
  tt_status st = tt_atomic_file_open(path, &f);
  if (st != TT_OK) return st;
  if (size && fwrite(data, 1, size, f->stream) != size && !f->error) f->error = EIO;
  return tt_atomic_file_commit(f);
}
