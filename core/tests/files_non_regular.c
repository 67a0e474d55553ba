/* Every input the library reads is refused at once when it is not a regular file: images
 * (tt_image_read, tt_image_read_meta: OpenImageIO would block on a FIFO and read /dev/zero
 * forever), tuning databases (SQLite would block on a FIFO), a merged database, and files a
 * mesh names inside it (an OBJ's mtllib read by assimp). The message names the file and what
 * it is. A hang fails the test through alarm() with the step that hung, never the suite. */
#include <tunetrace/tunetrace.h>

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "tt_test.h"

static const char *volatile g_step = "start";

static void on_alarm(int sig) {
  (void)sig;
  static const char msg[] = "files_non_regular: HUNG (no answer in 60 s) at: ";
  (void)!write(2, msg, sizeof msg - 1);
  (void)!write(2, (const char *)g_step, strlen((const char *)g_step));
  (void)!write(2, "\n", 1);
  _exit(1);
}

/* st is TT_ERR_IO and the message names `path` and `kind` ("a FIFO", ...). */
static void refused(tt_status st, const char *path, const char *kind) {
  CHECK_MSG(st == TT_ERR_IO, "%s: status %d (%s)", g_step, (int)st, tt_last_error());
  CHECK_CONTAINS(tt_last_error(), path);
  CHECK_CONTAINS(tt_last_error(), kind);
}

int main(void) {
  signal(SIGALRM, on_alarm);
  char dir[] = "/tmp/tt_files_non_regularXXXXXX";
  if (!mkdtemp(dir)) return 1;
  char fifo[512], obj[512], mtl[512], scene[512], db[512];
  snprintf(fifo, sizeof fifo, "%s/image.exr", dir);
  CHECK(mkfifo(fifo, 0600) == 0);

  struct {
    const char *path, *kind;
  } bad[] = {{fifo, "a FIFO"},
             {"/dev/zero", "a character device"},
             {"/dev/urandom", "a character device"},
             {dir, "a directory"}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    uint32_t w, h, c;
    float *px = NULL;
    char value[64];
    alarm(60);
    g_step = "tt_image_read";
    refused(tt_image_read(bad[i].path, &w, &h, &c, &px), bad[i].path, bad[i].kind);
    CHECK(px == NULL);
    g_step = "tt_image_read_meta";
    refused(tt_image_read_meta(bad[i].path, "software", value, sizeof value), bad[i].path,
            bad[i].kind);
    tt_tunedb *t = NULL;
    g_step = "tt_tunedb_open";
    refused(tt_tunedb_open(bad[i].path, &t), bad[i].path, bad[i].kind);
    CHECK(t == NULL);
    g_step = "tt_tunedb_open_readonly";
    refused(tt_tunedb_open_readonly(bad[i].path, &t), bad[i].path, bad[i].kind);
    CHECK(t == NULL);
    alarm(0);
  }

  /* a database merging a FIFO: refused before SQLite's ATTACH opens it */
  snprintf(db, sizeof db, "%s/merged.db", dir);
  tt_tunedb *t = NULL;
  CHECK(tt_tunedb_open(db, &t) == TT_OK);
  if (t) {
    alarm(60);
    g_step = "tt_tunedb_merge of a FIFO";
    refused(tt_tunedb_merge(t, fifo, "job", -1, NULL, NULL, NULL), fifo, "a FIFO");
    alarm(0);
    tt_tunedb_close(t);
  }

  /* an OBJ whose material library is a FIFO: assimp is told it does not exist (the mesh loads
   * with its default material) instead of blocking in fopen */
  snprintf(obj, sizeof obj, "%s/tri.obj", dir);
  snprintf(mtl, sizeof mtl, "%s/tri.mtl", dir);
  CHECK(mkfifo(mtl, 0600) == 0);
  FILE *f = fopen(obj, "w");
  if (f) {
    fputs("mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n", f);
    fclose(f);
  }
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  f = fopen(scene, "w");
  if (f) {
    fputs("{\"version\": 1, \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0], "
          "\"fov\": 45}, \"materials\": {\"white\": {\"albedo\": [0.7, 0.7, 0.7]}}, "
          "\"meshes\": [{\"material\": \"white\", \"file\": \"tri.obj\"}]}\n",
          f);
    fclose(f);
  }
  tt_scene *s = NULL;
  alarm(60);
  g_step = "tt_scene_load of an OBJ whose mtllib is a FIFO";
  tt_status st = tt_scene_load(scene, &s);
  alarm(0);
  CHECK_MSG(st == TT_OK && s && tt_scene_triangle_count(s) == 1, "status %d: %s", (int)st,
            tt_last_error());
  tt_scene_destroy(s);

  unlink(fifo);
  unlink(mtl);
  unlink(obj);
  unlink(scene);
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  (void)!system(cmd);
  return tt_test_finish("files_non_regular");
}
