/* Files: whole-file reads that refuse non-regular files (tunetrace/file.h) and file-name
 * suffix tests, shared by every loader of the library and by the plugins. */
#include "util/files.h"

#include <tunetrace/file.h>

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* Case-insensitive suffix test for format dispatch. */
int tt__has_ext(const char *path, const char *ext) {
  size_t n = strlen(path), e = strlen(ext);
  return n >= e && strcasecmp(path + n - e, ext) == 0;
}

/* What a non-regular file is, for messages. */
const char *tt__file_kind(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

/* Opens `path` read-only without blocking (a FIFO would block open() until a writer comes)
 * and checks it is a regular file; returns the fd, or -1 with the error set. */
static int tt__open_regular(const char *path, const char *what, struct stat *st) {
  if (!path || !*path) {
    tt_set_error(TT_ERR_IO, "cannot open %s: empty path", what);
    return -1;
  }
  int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) {
    tt_set_error(TT_ERR_IO, "%s: cannot open %s: %s", path, what, strerror(errno));
    return -1;
  }
  if (fstat(fd, st) != 0) {
    tt_set_error(TT_ERR_IO, "%s: cannot open %s: %s", path, what, strerror(errno));
    close(fd);
    return -1;
  }
  if (!S_ISREG(st->st_mode)) {
    tt_set_error(TT_ERR_IO, "%s: cannot open %s: %s, not a regular file", path, what,
                 tt__file_kind(st->st_mode));
    close(fd);
    return -1;
  }
  return fd;
}

int tt__file_regular_reason(const char *path, char *why, size_t n) {
  if (!path || !*path) {
    snprintf(why, n, "empty path");
    return -1;
  }
  struct stat st;
  int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0 || fstat(fd, &st) != 0) {
    snprintf(why, n, "%s", strerror(errno));
    if (fd >= 0) close(fd);
    return -1;
  }
  close(fd);
  if (S_ISREG(st.st_mode)) return 0;
  snprintf(why, n, "%s, not a regular file", tt__file_kind(st.st_mode));
  return -1;
}

tt_status tt_file_check_regular(const char *path, const char *what) {
  char why[256];
  if (tt__file_regular_reason(path, why, sizeof why) == 0) return TT_OK;
  return tt_set_error(TT_ERR_IO, "%s: cannot open %s: %s", path && *path ? path : "(empty path)",
                      what ? what : "file", why);
}

tt_status tt_file_read(const char *path, const char *what, size_t max_bytes, char **data,
                       size_t *size) {
  if (!data || !size) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_file_read: NULL output");
  *data = NULL;
  *size = 0;
  if (!what) what = "file";
  if (max_bytes == 0) max_bytes = TT_FILE_READ_DEFAULT_MAX;
  struct stat st;
  int fd = tt__open_regular(path, what, &st);
  if (fd < 0) return TT_ERR_IO;
  if ((uint64_t)st.st_size > (uint64_t)max_bytes) {
    close(fd);
    return tt_set_error(TT_ERR_IO, "%s: %s is %llu bytes, more than the %llu-byte limit", path,
                        what, (unsigned long long)st.st_size, (unsigned long long)max_bytes);
  }
  /* the size is a hint (the file may change while read); the limit holds regardless */
  size_t cap = (size_t)st.st_size + 1, len = 0;
  char *buf = malloc(cap + 1);
  if (!buf) {
    close(fd);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory reading %s (%llu bytes)", path,
                        what, (unsigned long long)st.st_size);
  }
  for (;;) {
    if (len == cap) {
      if (cap > max_bytes) {
        free(buf);
        close(fd);
        return tt_set_error(TT_ERR_IO, "%s: %s grew past the %llu-byte limit while read", path,
                            what, (unsigned long long)max_bytes);
      }
      size_t ncap = cap * 2 > max_bytes + 1 ? max_bytes + 1 : cap * 2;
      char *n = realloc(buf, ncap + 1);
      if (!n) {
        free(buf);
        close(fd);
        return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory reading %s", path, what);
      }
      buf = n;
      cap = ncap;
    }
    ssize_t got = read(fd, buf + len, cap - len);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      int e = errno;
      free(buf);
      close(fd);
      return tt_set_error(TT_ERR_IO, "%s: read error in %s: %s", path, what, strerror(e));
    }
    if (got == 0) break;
    len += (size_t)got;
  }
  close(fd);
  buf[len] = '\0';
  *data = buf;
  *size = len;
  return TT_OK;
}

tt_status tt__read_file(const char *path, char **out, size_t *out_len) {
  return tt_file_read(path, "scene file", 0, out, out_len);
}
