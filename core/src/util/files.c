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

int tt__open_regular_fd(const char *path, struct stat *st, char *why, size_t n) {
  if (!path || !*path) {
    snprintf(why, n, "empty path");
    errno = ENOENT;
    return -1;
  }
  /* O_NONBLOCK: open() of a FIFO would block until a writer comes; O_NOCTTY: a terminal
   * named as an input must not become our controlling terminal */
  int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) {
    int e = errno;
    snprintf(why, n, "%s", strerror(e));
    errno = e;
    return -1;
  }
  if (fstat(fd, st) != 0) {
    int e = errno;
    snprintf(why, n, "%s", strerror(e));
    close(fd);
    errno = e;
    return -1;
  }
  if (!S_ISREG(st->st_mode)) {
    snprintf(why, n, "%s, not a regular file", tt__file_kind(st->st_mode));
    close(fd);
    errno = S_ISDIR(st->st_mode) ? EISDIR : EINVAL;
    return -1;
  }
  /* reads of a regular file never block; the descriptor reads as usual from here */
  int flags = fcntl(fd, F_GETFL);
  if (flags >= 0) (void)fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  return fd;
}

/* tt__open_regular_fd with the error set: "PATH: cannot open WHAT: REASON". */
static int tt__open_regular(const char *path, const char *what, struct stat *st) {
  char why[256];
  int fd = tt__open_regular_fd(path, st, why, sizeof why);
  if (fd < 0)
    tt_set_error(TT_ERR_IO, "%s: cannot open %s: %s", path && *path ? path : "(empty path)", what,
                 why);
  return fd;
}

int tt__file_regular_reason(const char *path, char *why, size_t n) {
  struct stat st;
  int fd = tt__open_regular_fd(path, &st, why, n);
  if (fd < 0) return -1;
  close(fd);
  return 0;
}

tt_status tt_file_check_regular(const char *path, const char *what) {
  struct stat st;
  int fd = tt__open_regular(path, what ? what : "file", &st);
  if (fd < 0) return TT_ERR_IO;
  close(fd);
  return TT_OK;
}

/* The real path of `path` when it exists, else of its folder joined with its name (an output
 * not written yet); NULL when neither resolves (malloc'ed). */
static char *tt__canonical(const char *path) {
  char *real = realpath(path, NULL);
  if (real) return real;
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  if (!*base || !strcmp(base, ".") || !strcmp(base, "..")) return NULL;
  char *dir;
  if (!slash) dir = realpath(".", NULL);
  else if (slash == path) dir = realpath("/", NULL);
  else {
    char *d = strndup(path, (size_t)(slash - path));
    dir = d ? realpath(d, NULL) : NULL;
    free(d);
  }
  if (!dir) return NULL;
  size_t n = strlen(dir) + strlen(base) + 2;
  char *out = malloc(n);
  if (out) snprintf(out, n, "%s%s%s", dir, strcmp(dir, "/") ? "/" : "", base);
  free(dir);
  return out;
}

int tt_file_same(const char *a, const char *b) {
  if (!a || !b || !*a || !*b) return 0;
  struct stat sa, sb;
  int ha = stat(a, &sa) == 0, hb = stat(b, &sb) == 0;
  if (ha && hb) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (ha != hb) return 0; /* one exists, the other not: two files */
  /* neither exists yet: the same real folder and name */
  char *ca = tt__canonical(a), *cb = tt__canonical(b);
  int same = ca && cb ? !strcmp(ca, cb) : !strcmp(a, b);
  free(ca);
  free(cb);
  return same;
}

tt_status tt_file_check_not_input(const char *output, const char *output_what, const char *input,
                                  const char *input_what) {
  if (!tt_file_same(output, input)) return TT_OK;
  if (!output_what) output_what = "output";
  if (!input_what) input_what = "input";
  if (!strcmp(output, input))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "%s: the %s would replace the %s (the same "
                        "file): give the %s another name",
                        output, output_what, input_what, output_what);
  return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                      "%s: the %s would replace the %s %s (the same "
                      "file): give the %s another name",
                      output, output_what, input_what, input, output_what);
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
