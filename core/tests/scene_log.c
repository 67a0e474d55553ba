/* The scene loaders' warnings go through the log host (tt_set_log_host), not straight to
 * stderr: in-process they reach the application's tt_host.log with level TT_LOG_WARN and
 * the file and JSON path in the text; through the host program they come out as the
 * host's own "host: warning:" lines, also with --quiet (which hides only info). */
#include <tunetrace/host.h>
#include <tunetrace/scene.h>

#include "host_util.h"
#include "tt_test.h"

#include <stdarg.h>
#include <unistd.h>

static char g_last[2048];
static int g_warnings, g_others;

static void capture_log(tt_log_level level, const char *plugin, const char *fmt, ...) {
  (void)plugin;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(g_last, sizeof g_last, fmt, ap);
  va_end(ap);
  if (level == TT_LOG_WARN) g_warnings++;
  else g_others++;
}

int main(void) {
  static const char json[] =
      "{\"version\": 1, \"colour\": 3,\n"
      " \"camera\": {\"position\": [0.3, 0.3, 2], \"target\": [0.3, 0.3, 0], \"up\": [0, 1, 0],\n"
      "            \"fov\": 40, \"resolution\": [8, 8]},\n"
      " \"materials\": {\"m\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]}},\n"
      " \"meshes\": [{\"material\": \"m\", \"positions\": [0,0,0, 1,0,0, 0,1,0],\n"
      "              \"indices\": [0, 1, 2]}]}\n";
  tt_host h = *tt_default_host();
  h.log = capture_log;
  tt_set_log_host(&h);
  tt_scene *s = NULL;
  CHECK(tt_scene_load_json(json, sizeof json - 1, "warn.json", NULL, &s) == TT_OK);
  CHECK(g_warnings == 1 && g_others == 0);
  CHECK_CONTAINS(g_last, "warn.json");
  CHECK_CONTAINS(g_last, "colour");
  tt_scene_destroy(s);
  tt_set_log_host(NULL); /* back to the default host (stderr) */
  g_warnings = 0;
  CHECK(tt_scene_load_json(json, sizeof json - 1, "warn.json", NULL, &s) == TT_OK);
  CHECK(g_warnings == 0);
  tt_scene_destroy(s);

  /* through the host program: the host's log format, kept by --quiet */
  char path[] = "/tmp/tt_scene_log_XXXXXX.json";
  int fd = mkstemps(path, 5);
  CHECK(fd >= 0);
  CHECK(write(fd, json, sizeof json - 1) == (ssize_t)(sizeof json - 1));
  close(fd);
  char args[512], out[8192];
  (void)source_path;
  snprintf(args, sizeof args, "--quiet --spp 1 --res 8x8 --out /tmp/tt_scene_log.exr '%s'", path);
  CHECK(run_host(args, out, sizeof out) == 0);
  CHECK_CONTAINS(out, "host: warning: ");
  CHECK_CONTAINS(out, "colour");
  CHECK(strstr(out, "tunetrace: warning") == NULL);
  unlink(path);
  unlink("/tmp/tt_scene_log.exr");
  unlink("/tmp/tt_scene_log.png");
  return tt_test_finish("scene_log");
}
