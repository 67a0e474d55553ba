/* host: output folders and names. A folder named in --out, --stats or a frame pattern that does not
 * exist yet is created before anything renders (mkdir -p), so a render is never lost to a
 * missing folder at the end, and one that cannot be created is reported before the render. */
#include "host.h"

#include <errno.h>
#include <libgen.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int tt__ensure_dir(const char *dir) {
  char tmp[4096];
  if (snprintf(tmp, sizeof tmp, "%s", dir) >= (int)sizeof tmp) {
    errno = ENAMETOOLONG;
    return -1;
  }
  for (char *p = tmp + 1; *p; p++) {
    if (*p != '/') continue;
    *p = 0;
    if (mkdir(tmp, 0777) != 0 && errno != EEXIST) return -1;
    *p = '/';
  }
  if (mkdir(tmp, 0777) != 0 && errno != EEXIST) return -1;
  struct stat st;
  if (stat(tmp, &st) != 0) return -1;
  if (!S_ISDIR(st.st_mode)) {
    errno = ENOTDIR;
    return -1;
  }
  return 0;
}

int tt__ensure_parent_dir(const char *option, const char *path) {
  const char *slash = strrchr(path, '/');
  if (!slash || slash == path) return TT_EXIT_OK; /* the current folder, or / */
  char dir[4096];
  snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
  if (tt__ensure_dir(dir) == 0) return TT_EXIT_OK;
  tt__say("%s %s: cannot create the folder %s: %s\n", option, path, dir, strerror(errno));
  return TT_EXIT_OUTPUT;
}

/* Default output: <scene folder>.exr for ".../NAME/scene.json", else <file stem>.exr. The
 * folder's name comes from the resolved path, so "scene.json" run from its own folder (or
 * "./scene.json", "../NAME/scene.json") is named after the folder too, never "..exr". */
void tt__default_out(const char *scene, char *buf, size_t n) {
  char tmp[4096];
  snprintf(tmp, sizeof tmp, "%s", scene);
  char *base = basename(tmp);
  if (!strcmp(base, "scene.json")) {
    char resolved[PATH_MAX], tmp2[4096];
    snprintf(tmp2, sizeof tmp2, "%s", realpath(scene, resolved) ? resolved : scene);
    char *dir = dirname(tmp2);
    char tmp3[4096];
    snprintf(tmp3, sizeof tmp3, "%s", dir);
    const char *name = basename(tmp3);
    /* "/scene.json" or an unresolvable "./scene.json": no folder name to use */
    if (!strcmp(name, "/") || !strcmp(name, ".") || !strcmp(name, "..")) name = "scene";
    snprintf(buf, n, "%s.exr", name);
  } else {
    char *dot = strrchr(base, '.');
    if (dot && dot != base) *dot = 0;
    snprintf(buf, n, "%s.exr", base);
  }
}
