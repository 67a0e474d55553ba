/* End to end: host --hybrid over the Cornell box's camera path (24x24, one thread).
 *  - epsilon 1 is exactly search: with a fixed seed every state runs the tuning loop's own
 *    search (replayed here from a database filled by host --plugin tuner_nm --camera-index I,
 *    so the same proposals in the same order are answered, none measured);
 *  - epsilon 0 is exactly one build per state (after a warm start);
 *  - a warm start reads another scene's rows (NN answers their best configuration);
 *  - --model saves a model that --predict loads back; bad input exits 2, a bad model file is
 *    left as it is. */
#include <tunetrace/tunetrace.h>

#include <cjson/cJSON.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include "host_util.h"
#include "json_util.h"
#include "tt_test.h"

static char dir[] = "/tmp/tt_hybrid_loopXXXXXX";
static char out[1 << 18];

/* The configurations of the rows of one path sample, in insertion order, joined by '\n'. */
static char *row_configs(const char *db_path, int path_index, const char *extra) {
  sqlite3 *db = NULL;
  sqlite3_stmt *st = NULL;
  char sql[512];
  snprintf(sql, sizeof sql,
           "SELECT config FROM samples WHERE camera LIKE '%%\"path_index\":%d}'"
           " %s ORDER BY id",
           path_index, extra ? extra : "");
  size_t cap = 1 << 16, len = 0;
  char *buf = malloc(cap);
  buf[0] = 0;
  if (sqlite3_open_v2(db_path, &db, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
      sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK)
    while (sqlite3_step(st) == SQLITE_ROW) {
      const char *c = (const char *)sqlite3_column_text(st, 0);
      size_t n = strlen(c);
      if (len + n + 2 > cap) buf = realloc(buf, cap = 2 * cap + n);
      memcpy(buf + len, c, n);
      len += n;
      buf[len++] = '\n';
      buf[len] = 0;
    }
  sqlite3_finalize(st);
  sqlite3_close(db);
  return buf;
}

static long rows_where(const char *db_path, const char *where) {
  sqlite3 *db = NULL;
  sqlite3_stmt *st = NULL;
  char sql[512];
  long n = -1;
  snprintf(sql, sizeof sql, "SELECT count(*) FROM samples WHERE %s", where);
  if (sqlite3_open_v2(db_path, &db, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
      sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
    n = sqlite3_column_int64(st, 0);
  sqlite3_finalize(st);
  sqlite3_close(db);
  return n;
}

static const char *common =
    "--quiet --res 24x24 --spp 1 --threads 1 --tune-params quality,branchingFactor,maxDepth,"
    "maxLeafSize,travcost --set tuner_nm.reevaluate=0 --set accel_embree.backend=custom";

int main(void) {
  if (!mkdtemp(dir)) return 1;
  char scene[4200], other[4200], still[4200];
  snprintf(scene, sizeof scene, "%s", source_path("scenes/cornell-box/path.json"));
  snprintf(other, sizeof other, "%s",
           source_path("scenes/cornell-box-variants/specular-box/scene.json"));
  snprintf(still, sizeof still, "%s", source_path("scenes/cornell-box/scene.json"));
  char args[16384];
  char db[512], stats[512], model[512];
  snprintf(db, sizeof db, "%s/search.db", dir);

  /* the tuning loop's own search at path samples 2, 3, 4 */
  for (int i = 2; i <= 4; i++) {
    snprintf(args, sizeof args,
             "%s --plugin tuner_nm --iterations 6 --camera-index %d --db '%s' "
             "--out '%s/t.exr' '%s'",
             common, i, db, dir, scene);
    CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  }
  /* epsilon 1: the same searches, every proposal answered by the database */
  snprintf(stats, sizeof stats, "%s/eps1.json", dir);
  snprintf(args, sizeof args,
           "%s --hybrid --epsilon 1 --iterations 6 --camera-index 2:4 --db '%s' "
           "--stats '%s' '%s'",
           common, db, stats, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  cJSON *root = read_json(stats);
  cJSON *h = root ? cJSON_GetObjectItem(root, "hybrid") : NULL;
  cJSON *states = h ? cJSON_GetObjectItem(h, "states") : NULL;
  CHECK(cJSON_GetArraySize(states) == 3 && num(h, "explored") == 3 && num(h, "exploited") == 0);
  for (int k = 0; k < cJSON_GetArraySize(states); k++) {
    cJSON *s = cJSON_GetArrayItem(states, k);
    CHECK(!strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(s, "mode")), "explore"));
    CHECK_MSG(num(s, "samples") == 7 && num(s, "cached") == 7, "state %d: %g samples, %g cached", k,
              num(s, "samples"), num(s, "cached"));
  }
  cJSON_Delete(root);
  /* nothing new was measured: the database holds only the three searches */
  CHECK(rows_where(db, "1") == 3 * 7);
  for (int i = 2; i <= 4; i++) {
    char *a = row_configs(db, i, NULL);
    CHECK(strlen(a) > 0 && rows_where(db, "mode = 'exploit'") == 0);
    free(a);
  }

  /* epsilon 0 after a warm start: exactly one build per state, its cost observed */
  snprintf(stats, sizeof stats, "%s/eps0.json", dir);
  snprintf(model, sizeof model, "%s/nn.ttpm", dir);
  char db2[512];
  snprintf(db2, sizeof db2, "%s/exploit.db", dir);
  snprintf(args, sizeof args,
           "%s --hybrid --epsilon 0 --camera-index 10:15 --warm-start '%s' --db '%s' "
           "--model '%s' --stats '%s' --out-dir '%s/states' '%s'",
           common, db, db2, model, stats, dir, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  root = read_json(stats);
  h = root ? cJSON_GetObjectItem(root, "hybrid") : NULL;
  states = h ? cJSON_GetObjectItem(h, "states") : NULL;
  CHECK(cJSON_GetArraySize(states) == 6 && num(h, "builds") == 6 && num(h, "exploited") == 6);
  cJSON *warm = h ? cJSON_GetArrayItem(cJSON_GetObjectItem(h, "warm_start"), 0) : NULL;
  CHECK(warm && num(warm, "rows") == 3 * 7);
  for (int k = 0; k < cJSON_GetArraySize(states); k++) {
    cJSON *s = cJSON_GetArrayItem(states, k);
    CHECK(num(s, "builds") == 1 && num(s, "samples") == 1);
    CHECK(!cJSON_IsTrue(cJSON_GetObjectItem(s, "fallback")));
    CHECK(cJSON_IsNumber(cJSON_GetObjectItem(s, "predicted_cost")) && num(s, "predict_ms") >= 0);
    /* the default is not measured in an exploited state: its cost is that of the nearest
     * state where it was (the warm start's searches at path samples 2-4), and says so */
    CHECK(cJSON_IsNumber(cJSON_GetObjectItem(s, "default_cost")) && num(s, "default_cost") > 0);
    CHECK(!strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(s, "default_cost_from")),
                  "nearest state") &&
          num(s, "default_distance") > 0);
    /* --out-dir: each state's image and its preview */
    char png[600];
    snprintf(png, sizeof png, "%s/states/state_%04d.png", dir, 10 + k);
    struct stat ps;
    CHECK_MSG(stat(png, &ps) == 0 && ps.st_size > 0, "%s missing", png);
    png[strlen(png) - 3] = 0;
    strcat(png, "exr");
    CHECK_MSG(stat(png, &ps) == 0 && ps.st_size > 0, "%s missing", png);
  }
  cJSON_Delete(root);
  CHECK(rows_where(db2, "mode = 'exploit' AND iteration = -1") == 6);
  CHECK(rows_where(db2, "mode <> 'exploit'") == 0);
  struct stat st;
  CHECK(stat(model, &st) == 0 && st.st_size > 0);

  /* a warm start from rows measured otherwise learns nothing, and names why: every row was
   * measured with a wall clock, one thread, at 24x24 */
  snprintf(stats, sizeof stats, "%s/mismatch.json", dir);
  snprintf(
      args, sizeof args,
      "--quiet --res 16x16 --spp 1 --threads 2 --clock cpu --tune-params "
      "quality,branchingFactor,maxDepth,maxLeafSize,travcost --set accel_embree.backend=custom "
      "--hybrid --epsilon 0 --camera-index 10:10 --warm-start '%s' --no-db --stats '%s' '%s'",
      db, stats, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  CHECK_CONTAINS(out, "learnt 0 of the 21 rows");
  CHECK_CONTAINS(out, "21 measured with --clock wall (this run: --clock cpu)");
  CHECK_CONTAINS(out, "21 measured with --threads 1 (this run: --threads 2)");
  CHECK_CONTAINS(out, "21 measured with --res 24x24 (this run: --res 16x16)");
  root = read_json(stats);
  h = root ? cJSON_GetObjectItem(root, "hybrid") : NULL;
  warm = h ? cJSON_GetArrayItem(cJSON_GetObjectItem(h, "warm_start"), 0) : NULL;
  cJSON *mm = warm ? cJSON_GetObjectItem(warm, "mismatch") : NULL;
  CHECK(warm && num(warm, "rows") == 0 && num(warm, "skipped") == 21);
  CHECK(mm && num(cJSON_GetObjectItem(mm, "threads"), "rows") == 21 &&
        num(cJSON_GetObjectItem(mm, "threads"), "value") == 1 &&
        num(cJSON_GetObjectItem(mm, "threads"), "this_run") == 2);
  CHECK(mm && num(cJSON_GetObjectItem(mm, "resolution"), "rows") == 21 &&
        num(cJSON_GetObjectItem(mm, "spp"), "rows") == 0);
  cJSON_Delete(root);

  /* said once per run, not at every state: the parameters not searched, the re-measurements */
  snprintf(args, sizeof args,
           "--res 24x24 --spp 1 --threads 1 --set accel_embree.backend=custom "
           "--hybrid --epsilon 1 --iterations 12 --camera-index 2:4 --no-db '%s'",
           scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  {
    int n = 0;
    for (const char *p = strstr(out, "not searched"); p; p = strstr(p + 1, "not searched")) n++;
    CHECK_MSG(n == 1 && !strstr(out, "measuring again"), "%d 'not searched' lines:\n%s", n, out);
  }

  /* the saved model predicts for another scene's states without a database */
  snprintf(args, sizeof args,
           "--quiet --res 24x24 --tune-params quality,branchingFactor,maxDepth,"
           "maxLeafSize,travcost --predict --camera-index 0:3 --model '%s' '%s'",
           model, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  root = cJSON_Parse(strchr(out, '{'));
  CHECK(root && cJSON_GetArraySize(cJSON_GetObjectItem(root, "predictions")) == 4);
  /* the exploited states are not stored: the table holds what the searches found */
  CHECK(root && num(root, "observations") == 3 * 7);
  cJSON_Delete(root);

  /* a warm start reads another scene's rows: one stored state, so NN answers its best */
  char db3[512];
  snprintf(db3, sizeof db3, "%s/other.db", dir);
  snprintf(stats, sizeof stats, "%s/other.json", dir);
  snprintf(args, sizeof args,
           "%s --plugin tuner_nm --iterations 5 --camera-index 30 --db '%s' "
           "--stats '%s' --out '%s/o.exr' '%s'",
           common, db3, stats, dir, other);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  root = read_json(stats);
  cJSON *tj = root ? cJSON_GetObjectItem(root, "tuning") : NULL;
  char *best = tj ? cJSON_PrintUnformatted(cJSON_GetObjectItem(tj, "best_config")) : NULL;
  cJSON_Delete(root);
  snprintf(
      args, sizeof args,
      "--quiet --res 24x24 --threads 1 --spp 1 --tune-params quality,"
      "branchingFactor,maxDepth,maxLeafSize,travcost --set accel_embree.backend=custom --predict "
      "--camera-index 0:2 --warm-start '%s' "
      "'%s'",
      db3, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  root = cJSON_Parse(strchr(out, '{'));
  cJSON *preds = root ? cJSON_GetObjectItem(root, "predictions") : NULL;
  CHECK(cJSON_GetArraySize(preds) == 3);
  for (int k = 0; k < cJSON_GetArraySize(preds); k++) {
    char *c = cJSON_PrintUnformatted(cJSON_GetObjectItem(cJSON_GetArrayItem(preds, k), "config"));
    CHECK_MSG(best && c && !strcmp(c, best), "predicted %s, the other scene's best %s", c, best);
    free(c);
  }
  cJSON_Delete(root);
  free(best);

  /* bad input: usage errors (exit 2) naming the problem */
  char junk_scene[512];
  snprintf(junk_scene, sizeof junk_scene, "%s/junk.json", dir);
  FILE *js = fopen(junk_scene, "w");
  fputs("{\"version\": 1, \"camera\": ", js);
  fclose(js);
  struct {
    const char *args;
    const char *scene;
    const char *msg;
  } bad[] = {
      {"--hybrid", still, "has no camera path"},
      {"--hybrid --epsilon 1.5", scene, "--epsilon: expected"},
      {"--hybrid --epsilon -0.1", scene, "--epsilon: expected"},
      {"--hybrid --iterations 0", scene, "--iterations"},
      /* the states are path samples (--camera-index A:B); --frames means frames at --fps */
      {"--hybrid --frames 0:3", scene, "give them with --camera-index A:B"},
      {"--predict --frames 0:3", scene, "give them with --camera-index A:B"},
      {"--hybrid --camera-index 4:3", scene, "--camera-index: expected I or A:B"},
      {"--hybrid --camera-index 0:100", scene, "--camera-index: expected I or A:B"},
      {"--camera-index 0:3", scene, "applies to --hybrid and --predict"},
      {"--hybrid --objective metric:rays_per_s", scene, "for time"},
      {"--hybrid --warm-start /nonexistent/x.db", scene, "/nonexistent/x.db"},
      /* a missing warm start is named before the scene loads (this scene does not parse) */
      {"--hybrid --warm-start /nonexistent/x.db", junk_scene, "--warm-start /nonexistent/x.db"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    snprintf(args, sizeof args, "%s %s --no-db --res 8x8 '%s'", common, bad[i].args, bad[i].scene);
    int rc = run_host(args, out, sizeof out);
    CHECK_MSG(rc == 2, "%s: exit %d (%s)", bad[i].args, rc, out);
    CHECK_CONTAINS(out, bad[i].msg);
  }
  /* a model file that is not one: refused, exit 2, left as it was */
  char junk[512];
  snprintf(junk, sizeof junk, "%s/junk.ttpm", dir);
  FILE *f = fopen(junk, "w");
  fputs("not a model", f);
  fclose(f);
  snprintf(args, sizeof args, "%s --hybrid --no-db --camera-index 0:1 --model '%s' '%s'", common,
           junk, scene);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, junk);
  CHECK_CONTAINS(out, "left as it is");
  CHECK(stat(junk, &st) == 0 && st.st_size == 11);
  /* an NN model loaded into RBF: refused naming both */
  snprintf(args, sizeof args,
           "%s --hybrid --plugin predictor_rbf --no-db --camera-index 0:1 --model '%s' '%s'",
           common, model, scene);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, "written by predictor_nn");

  snprintf(args, sizeof args, "rm -rf '%s'", dir);
  if (system(args)) {}
  return tt_test_finish("hybrid_loop");
}
