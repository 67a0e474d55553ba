/* Files: whole-file reads and file-name suffix tests shared by the loaders. */
#include "util/files.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* Case-insensitive suffix test for format dispatch. */
int tt__has_ext(const char *path, const char *ext) {
  size_t n = strlen(path), e = strlen(ext);
  return n >= e && strcasecmp(path + n - e, ext) == 0;
}

/* Reads a whole file into a NUL-terminated malloc'ed buffer (shared by the JSON and pbrt
 * loaders). Errors name the file: "cannot open scene file", "read error". */
tt_status tt__read_file(const char *path, char **out, size_t *out_len) {
  *out = NULL;
  *out_len = 0;
  FILE *f = fopen(path, "rb");
  if (!f) return tt_set_error(TT_ERR_IO, "%s: cannot open scene file: %s", path, strerror(errno));
  char *buf = NULL;
  size_t len = 0, cap = 0;
  for (;;) {
    if (len + 4096 + 1 > cap) {
      size_t ncap = cap ? cap * 2 : 65536;
      char *n = realloc(buf, ncap);
      if (!n) {
        free(buf);
        fclose(f);
        return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory reading the file", path);
      }
      buf = n;
      cap = ncap;
    }
    size_t got = fread(buf + len, 1, cap - len - 1, f);
    len += got;
    if (got == 0) break;
  }
  int bad = ferror(f);
  fclose(f);
  if (bad) {
    free(buf);
    return tt_set_error(TT_ERR_IO, "%s: read error", path);
  }
  buf[len] = '\0';
  *out = buf;
  *out_len = len;
  return TT_OK;
}
