/* An output never replaces an input: tt_file_same (the same device and inode, or the same
 * real folder and name for files not written yet) and tt_file_check_not_input, and the
 * library's own writers that have an input at hand: tt_scene_write_json onto the scene file
 * it was loaded from, tt_tunedb_export_csv onto its database, tt_tunedb_merge of a database
 * into itself. Each refusal names both files and leaves the input byte for byte. */
#include <tunetrace/tunetrace.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "tt_test.h"

static char *slurp(const char *path, size_t *n) {
  char *data = NULL;
  if (tt_file_read(path, NULL, 0, &data, n) != TT_OK) return NULL;
  return data;
}

int main(void) {
  char dir[] = "/tmp/tt_files_sameXXXXXX";
  if (!mkdtemp(dir)) return 1;
  char a[512], b[512], lnk[512], hard[512], dotted[512], sub[512], up[512], miss1[512], miss2[512],
      cwd[4096];
  snprintf(a, sizeof a, "%s/a.json", dir);
  snprintf(b, sizeof b, "%s/b.json", dir);
  snprintf(lnk, sizeof lnk, "%s/link.json", dir);
  snprintf(hard, sizeof hard, "%s/hard.json", dir);
  snprintf(dotted, sizeof dotted, "%s/./a.json", dir);
  snprintf(sub, sizeof sub, "%s/sub", dir);
  snprintf(up, sizeof up, "%s/sub/../a.json", dir);
  snprintf(miss1, sizeof miss1, "%s/new.exr", dir);
  snprintf(miss2, sizeof miss2, "%s/sub/../new.exr", dir);
  CHECK(tt_file_write_atomic(a, "{}", 2) == TT_OK);
  CHECK(tt_file_write_atomic(b, "{}", 2) == TT_OK);
  CHECK(symlink("a.json", lnk) == 0);
  CHECK(link(a, hard) == 0);
  CHECK(mkdir(sub, 0777) == 0);

  /* the same file under every name; different files, equal content, are not */
  CHECK(tt_file_same(a, a) == 1);
  CHECK(tt_file_same(a, lnk) == 1);
  CHECK(tt_file_same(hard, a) == 1);
  CHECK(tt_file_same(dotted, a) == 1);
  CHECK(tt_file_same(up, a) == 1);
  CHECK(tt_file_same(a, b) == 0);
  CHECK(tt_file_same(a, miss1) == 0);
  /* outputs not written yet: the same real folder and name */
  CHECK(tt_file_same(miss1, miss2) == 1);
  CHECK(tt_file_same(miss1, b) == 0);
  CHECK(getcwd(cwd, sizeof cwd) != NULL);
  CHECK(chdir(dir) == 0);
  CHECK(tt_file_same("a.json", a) == 1);
  CHECK(tt_file_same("new.exr", miss1) == 1);
  CHECK(tt_file_same("./sub/../new.exr", miss2) == 1);
  CHECK(chdir(cwd) == 0);
  CHECK(tt_file_same(NULL, a) == 0 && tt_file_same("", "") == 0);

  CHECK(tt_file_check_not_input(b, "stats file", a, "scene file") == TT_OK);
  CHECK(tt_file_check_not_input(lnk, "stats file", a, "scene file") == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), lnk);
  CHECK_CONTAINS(tt_last_error(), a);
  CHECK_CONTAINS(tt_last_error(), "stats file would replace the scene file");

  /* tt_scene_write_json onto the file the scene came from: refused, the file as it was */
  char scene[512];
  snprintf(scene, sizeof scene, "%s/box.json", dir);
  size_t n0 = 0, n1 = 0;
  const char *src = getenv("TT_SOURCE_ROOT");
  char box[4096];
  snprintf(box, sizeof box, "%s/scenes/cornell-box/scene.json", src ? src : ".");
  char *orig = slurp(box, &n0);
  CHECK(orig != NULL);
  if (orig) CHECK(tt_file_write_atomic(scene, orig, n0) == TT_OK);
  tt_scene *s = NULL;
  CHECK(tt_scene_load(scene, &s) == TT_OK);
  if (s) {
    CHECK(tt_scene_write_json(s, scene) == TT_ERR_INVALID_ARGUMENT);
    CHECK_CONTAINS(tt_last_error(), scene);
    CHECK_CONTAINS(tt_last_error(), "converted scene would replace");
    char other[600];
    snprintf(other, sizeof other, "%s/sub/../box.json", dir);
    CHECK(tt_scene_write_json(s, other) == TT_ERR_INVALID_ARGUMENT);
    tt_scene_destroy(s);
  }
  char *now = slurp(scene, &n1);
  CHECK(orig && now && n0 == n1 && !memcmp(orig, now, n0));
  tt_free(now);
  tt_free(orig);

  /* a database's CSV export onto the database, and a merge of a database into itself */
  char db[512], dblink[512];
  snprintf(db, sizeof db, "%s/t.db", dir);
  snprintf(dblink, sizeof dblink, "%s/t-link.db", dir);
  tt_tunedb *t = NULL;
  CHECK(tt_tunedb_open(db, &t) == TT_OK);
  CHECK(symlink("t.db", dblink) == 0);
  if (t) {
    CHECK(tt_tunedb_export_csv(t, dblink) == TT_ERR_INVALID_ARGUMENT);
    CHECK_CONTAINS(tt_last_error(), "CSV export would replace the tuning database");
    CHECK(tt_tunedb_merge(t, dblink, "self", -1, NULL, NULL, NULL) == TT_ERR_INVALID_ARGUMENT);
    CHECK_CONTAINS(tt_last_error(), "is the database merged into");
    uint64_t rows = 1;
    CHECK(tt_tunedb_count(t, NULL, &rows) == TT_OK && rows == 0);
    tt_tunedb_close(t);
  }
  tt_tunedb *again = NULL;
  CHECK(tt_tunedb_open_readonly(db, &again) == TT_OK); /* still a database */
  tt_tunedb_close(again);

  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  (void)!system(cmd);
  return tt_test_finish("files_same");
}
