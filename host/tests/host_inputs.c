/* What host reads and writes, as a careless or hostile user would give it:
 *  - inputs that are not regular files (--reference /dev/zero, a FIFO, /dev/urandom;
 *    --warm-start and --db a FIFO) are refused at once naming the file and what it is,
 *    never a hang (each run is killed after 60 s, which fails the check);
 *  - an output that resolves to an input (--stats or --convert --out onto the scene, --out
 *    through a link onto --reference, the default output onto --reference, frames or hybrid
 *    states over an input, two outputs on one file) is refused before any work, exit 2,
 *    naming both, and the input keeps its bytes; --model read and saved is not a conflict;
 *  - --warm-start reads a database without changing a byte: another program's SQLite file
 *    and PRAGMA user_version=-1 are refused by name, rows that are not rows of the schema
 *    (text cost, indicators not JSON) are skipped in one warning while the others are learnt;
 *  - --db on a damaged file (PRAGMA quick_check) is refused. */
#include <tunetrace/tunetrace.h>

#include <cjson/cJSON.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "host_util.h"
#include "tt_test.h"

static char g_dir[] = "/tmp/tt_host_inputs_XXXXXX";
static char g_out[65536];

static const char *path_of(const char *name) {
  static char p[32][600];
  static int k;
  k = (k + 1) % 32;
  snprintf(p[k], sizeof p[k], "%s/%s", g_dir, name);
  return p[k];
}

static char *slurp(const char *path, size_t *n) {
  char *d = NULL;
  return tt_file_read(path, NULL, 0, &d, n) == TT_OK ? d : NULL;
}

static int same_bytes(const char *path, const char *data, size_t n) {
  size_t m = 0;
  char *now = slurp(path, &m);
  int same = now && data && m == n && !memcmp(now, data, n);
  tt_free(now);
  return same;
}

/* Runs host with `args` (60 s at most); checks the exit code and that the output names
 * every needle (NULL-terminated). */
static void expect(int want_rc, const char *args, const char *const *needles) {
  int rc = run_host_timeout(60, args, g_out, sizeof g_out);
  CHECK_MSG(rc != 137, "HUNG (killed after 60 s): host %s", args);
  CHECK_MSG(rc == want_rc, "exit %d, expected %d: host %s\n%s", rc, want_rc, args, g_out);
  for (; needles && *needles; needles++) CHECK_CONTAINS(g_out, *needles);
}

static int sql(const char *path, const char *text) {
  sqlite3 *db = NULL;
  int rc = sqlite3_open(path, &db) == SQLITE_OK ? sqlite3_exec(db, text, NULL, NULL, NULL) : -1;
  sqlite3_close(db);
  return rc == SQLITE_OK;
}

static const char *common =
    "--quiet --res 24x24 --spp 1 --threads 1 --tune-params quality,branchingFactor,maxDepth,"
    "maxLeafSize,travcost --set tuner_nm.reevaluate=0 --set accel_embree.backend=custom";

int main(void) {
  if (!mkdtemp(g_dir)) return 1;
  char args[16384], cmd[2048];
  char still[4096], path[4096];
  snprintf(still, sizeof still, "%s", source_path("scenes/cornell-box/scene.json"));
  snprintf(path, sizeof path, "%s", source_path("scenes/cornell-box/path.json"));
  const char *fifo = path_of("fifo.exr");
  CHECK(mkfifo(fifo, 0600) == 0);

  /* ---- inputs that are not regular files ---- */
  const char *devices[][2] = {{"/dev/zero", "a character device"},
                              {fifo, "a FIFO"},
                              {"/dev/urandom", "a character device"}};
  for (int i = 0; i < 3; i++) {
    snprintf(args, sizeof args,
             "--plugin integrator_pt --plugin tuner_nm --tune accel_embree "
             "--objective rrmse --reference '%s' --iterations 1 --res 8x8 --spp 1 --no-db "
             "--out '%s' '%s'",
             devices[i][0], path_of("rrmse.exr"), still);
    const char *n[] = {devices[i][0], devices[i][1], "not a regular file", NULL};
    int rc = run_host_timeout(60, args, g_out, sizeof g_out);
    CHECK_MSG(rc != 137, "HUNG (killed after 60 s): host %s", args);
    CHECK_MSG(rc != 0, "--reference %s accepted", devices[i][0]);
    for (const char *const *k = n; *k; k++) CHECK_CONTAINS(g_out, *k);
  }
  snprintf(args, sizeof args, "%s --hybrid --camera-index 0:1 --warm-start '%s' --no-db '%s'",
           common, fifo, path);
  expect(2, args, (const char *[]){fifo, "a FIFO", NULL});
  snprintf(args, sizeof args, "%s --plugin tuner_nm --iterations 1 --db '%s' --out '%s' '%s'",
           common, fifo, path_of("t.exr"), still);
  expect(1, args, (const char *[]){fifo, "a FIFO", NULL});

  /* ---- outputs that would replace an input: refused before any work ---- */
  const char *scene = path_of("box.json");
  size_t n_scene = 0;
  char *scene_bytes = slurp(still, &n_scene);
  CHECK(scene_bytes && tt_file_write_atomic(scene, scene_bytes, n_scene) == TT_OK);
  snprintf(args, sizeof args, "--res 8x8 --spp 1 --stats '%s' --out '%s' '%s'", scene,
           path_of("a.exr"), scene);
  expect(
      2, args,
      (const char *[]){"--stats", "would replace the scene file", scene, "before any work", NULL});
  snprintf(args, sizeof args, "--convert --out '%s' '%s'", scene, scene);
  expect(2, args, (const char *[]){"--out", "would replace the scene file", NULL});
  CHECK(symlink("box.json", path_of("link.json")) == 0);
  snprintf(args, sizeof args, "--convert --out '%s' '%s'", path_of("link.json"), scene);
  expect(2, args, (const char *[]){path_of("link.json"), scene, "(the same file)", NULL});
  CHECK_MSG(same_bytes(scene, scene_bytes, n_scene), "%s was changed", scene);
  CHECK(access(path_of("a.exr"), F_OK) != 0); /* nothing rendered */

  /* --out through a hard link onto --reference */
  const char *ref = path_of("ref.exr");
  snprintf(args, sizeof args, "--plugin integrator_pt --res 8x8 --spp 2 --out '%s' '%s'", ref,
           still);
  CHECK(run_host(args, g_out, sizeof g_out) == 0);
  size_t n_ref = 0;
  char *ref_bytes = slurp(ref, &n_ref);
  CHECK(link(ref, path_of("ref-hard.exr")) == 0);
  snprintf(args, sizeof args,
           "--plugin integrator_pt --plugin tuner_nm --tune accel_embree "
           "--objective rrmse --reference '%s' --iterations 1 --res 8x8 --no-db --out '%s' '%s'",
           ref, path_of("ref-hard.exr"), still);
  expect(2, args, (const char *[]){"--out", "would replace --reference", ref, NULL});
  /* the default output (<scene folder>.exr in the current folder) onto --reference */
  char cwd[4096];
  CHECK(getcwd(cwd, sizeof cwd) != NULL);
  CHECK(chdir(g_dir) == 0);
  snprintf(cmd, sizeof cmd, "cp '%s' cornell-box.exr", ref);
  CHECK(system(cmd) == 0);
  snprintf(args, sizeof args,
           "--plugin integrator_pt --plugin tuner_nm --tune accel_embree "
           "--objective rrmse --reference cornell-box.exr --iterations 1 --res 8x8 --no-db '%s'",
           still);
  expect(2, args, (const char *[]){"the default output cornell-box.exr", "--reference", NULL});
  CHECK(chdir(cwd) == 0);
  /* --frames 0:2 would write f_0001.exr, the reference */
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", ref, path_of("f_0001.exr"));
  CHECK(system(cmd) == 0);
  snprintf(args, sizeof args,
           "--plugin integrator_pt --plugin tuner_nm --tune accel_embree "
           "--objective rrmse --reference '%s' --iterations 1 --res 8x8 --no-db --frames 0:2 "
           "--out '%s' '%s'",
           path_of("f_0001.exr"), path_of("f.exr"), path);
  expect(2, args, (const char *[]){"would write", "f_0001.exr", "--reference", NULL});
  /* --hybrid --out-dir writes state_NNNN.exr: one of them is the --model */
  CHECK(mkdir(path_of("states"), 0777) == 0);
  CHECK(tt_file_write_atomic(path_of("states/state_0001.exr"), "model", 5) == TT_OK);
  snprintf(args, sizeof args,
           "%s --hybrid --camera-index 0:2 --no-db --out-dir '%s' --model '%s' "
           "'%s'",
           common, path_of("states"), path_of("states/state_0001.exr"), path);
  expect(2, args, (const char *[]){"--out-dir", "state_0001.exr", "--model", NULL});
  CHECK(same_bytes(path_of("states/state_0001.exr"), "model", 5));
  /* two outputs on one file */
  snprintf(args, sizeof args, "--res 8x8 --spp 1 --out '%s' --stats '%s' '%s'", path_of("x.exr"),
           path_of("x.exr"), still);
  expect(2, args, (const char *[]){"would replace the output --stats", NULL});
  CHECK(same_bytes(ref, ref_bytes, n_ref));
  tt_free(ref_bytes);

  /* ---- --warm-start reads; --db refuses a damaged file ---- */
  const char *good = path_of("good.db");
  snprintf(args, sizeof args,
           "%s --plugin tuner_nm --iterations 4 --camera-index 2 --db '%s' "
           "--out '%s' '%s'",
           common, good, path_of("t.exr"), path);
  expect(0, args, NULL);
  CHECK(sql(good, "PRAGMA journal_mode=DELETE")); /* one self-contained file to compare */
  const char *bad = path_of("bad.db");
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", good, bad);
  CHECK(system(cmd) == 0);
  const char *copy =
      "INSERT INTO samples SELECT NULL, scene_id, scene, camera, context, %s, plugin,"
      " plugin_version, config, objective, build_ms, render_ms, %s, status, mode, iteration,"
      " run_id, tuner, metrics, machine, cpu, timestamp, host, rank FROM samples WHERE id = 2";
  snprintf(cmd, sizeof cmd, copy, "'not json'", "cost");
  CHECK(sql(bad, cmd));
  snprintf(cmd, sizeof cmd, copy, "indicators", "'cheap'");
  CHECK(sql(bad, cmd));
  size_t n_bad = 0;
  char *bad_bytes = slurp(bad, &n_bad);
  snprintf(args, sizeof args,
           "%s --hybrid --epsilon 0 --camera-index 3:4 --warm-start '%s' "
           "--no-db --stats '%s' '%s'",
           common, bad, path_of("warm.json"), path);
  expect(0, args, (const char *[]){"2 rows skipped", bad, NULL});
  CHECK_MSG(same_bytes(bad, bad_bytes, n_bad), "--warm-start changed %s", bad);
  tt_free(bad_bytes);
  size_t n_stats = 0;
  char *stats = slurp(path_of("warm.json"), &n_stats);
  cJSON *root = stats ? cJSON_Parse(stats) : NULL;
  cJSON *warm =
      cJSON_GetArrayItem(cJSON_GetObjectItem(cJSON_GetObjectItem(root, "hybrid"), "warm_start"), 0);
  cJSON *rows = cJSON_GetObjectItem(warm, "rows");
  CHECK_MSG(cJSON_IsNumber(rows) && rows->valuedouble == 5, "%s",
            stats ? stats : "(no stats)"); /* the good rows */
  cJSON_Delete(root);
  tt_free(stats);

  const char *foreign = path_of("foreign.db");
  CHECK(sql(foreign, "CREATE TABLE photos (id INTEGER); INSERT INTO photos VALUES (1)"));
  size_t n_foreign = 0;
  char *foreign_bytes = slurp(foreign, &n_foreign);
  snprintf(args, sizeof args, "%s --hybrid --camera-index 0:1 --warm-start '%s' --no-db '%s'",
           common, foreign, path);
  expect(2, args, (const char *[]){foreign, "not a tunetrace tuning database", "photos", NULL});
  snprintf(args, sizeof args, "%s --plugin tuner_nm --iterations 1 --db '%s' --out '%s' '%s'",
           common, foreign, path_of("t.exr"), still);
  expect(1, args, (const char *[]){foreign, "not a tunetrace tuning database", NULL});
  CHECK_MSG(same_bytes(foreign, foreign_bytes, n_foreign), "%s was changed", foreign);
  tt_free(foreign_bytes);

  const char *negative = path_of("negative.db");
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", good, negative);
  CHECK(system(cmd) == 0);
  CHECK(sql(negative, "PRAGMA user_version=-1"));
  snprintf(args, sizeof args, "%s --hybrid --camera-index 0:1 --warm-start '%s' --no-db '%s'",
           common, negative, path);
  expect(2, args, (const char *[]){negative, "schema version -1", NULL});

  /* an index page overwritten: PRAGMA quick_check fails, --db refuses the file */
  const char *damaged = path_of("damaged.db");
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", good, damaged);
  CHECK(system(cmd) == 0);
  FILE *f = fopen(damaged, "r+b");
  sqlite3 *s3 = NULL;
  sqlite3_stmt *st = NULL;
  long page = 0, page_size = 0;
  if (sqlite3_open_v2(good, &s3, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
      sqlite3_prepare_v2(s3,
                         "SELECT rootpage, (SELECT page_size FROM pragma_page_size) FROM "
                         "sqlite_master WHERE name = 'samples_key'",
                         -1, &st, NULL) == SQLITE_OK &&
      sqlite3_step(st) == SQLITE_ROW) {
    page = sqlite3_column_int(st, 0);
    page_size = sqlite3_column_int(st, 1);
  }
  sqlite3_finalize(st);
  sqlite3_close(s3);
  CHECK(f && page > 1 && page_size > 0);
  if (f) {
    fseek(f, (page - 1) * page_size + 8, SEEK_SET);
    fwrite("\xff\xff\xff\xff", 1, 4, f);
    fclose(f);
  }
  snprintf(args, sizeof args, "%s --plugin tuner_nm --iterations 1 --db '%s' --out '%s' '%s'",
           common, damaged, path_of("t.exr"), still);
  expect(1, args, (const char *[]){damaged, "damaged (PRAGMA quick_check", NULL});

  tt_free(scene_bytes);
  unlink(fifo);
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
  (void)!system(cmd);
  return tt_test_finish("host_inputs");
}
