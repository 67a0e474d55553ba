/* Tuning database: schema and WAL mode, record/lookup round trip (means over repeated
 * measurements, failures never answer, every key field matters), iteration, CSV export,
 * refusing a newer schema, the default path rules. */
#include <tunetrace/tunetrace.h>

#include <sqlite3.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include "tt_test.h"
#include "tt_test_sqlite.h"

/* A complete row with fixed key fields. */
static tt_tunedb_row make_row(const char *config, double cost, int status) {
  tt_tunedb_row r;
  memset(&r, 0, sizeof r);
  r.struct_size = sizeof r;
  r.scene_id = "abc123";
  r.scene = "scenes/x/scene.json";
  r.camera = "{\"position\":[0,1,2],\"resolution\":[32,32]}";
  r.context = "{\"spp\":1,\"threads\":2}";
  r.has_indicators = 1;
  for (int i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) r.indicators[i] = 0.1 * i + 1.0 / 3.0;
  r.plugin = "accel_embree";
  r.plugin_version = "0.1.0";
  r.config = config;
  r.objective = "render";
  r.build_ms = 1.25;
  r.render_ms = cost;
  r.cost = cost;
  r.status = status;
  r.mode = "tune";
  r.iteration = 3;
  r.run_id = "run-1";
  r.tuner = "tuner_nm";
  r.metrics = "{\"rays_per_s\":12345}";
  return r;
}

static int query1(const char *path, const char *sql, char *buf, size_t n) {
  return tt_test_query1(path, sql, buf, n, "");
}

typedef struct walk {
  int rows;
  int complete;
  int exact;
} walk;

/* Checks each row read back against what make_row wrote. */
static int on_row(void *user, const tt_tunedb_row *r) {
  walk *w = user;
  w->rows++;
  if (r->scene_id && r->camera && r->context && r->plugin && r->plugin_version && r->config &&
      r->objective && r->machine && r->cpu && r->timestamp && r->has_indicators)
    w->complete++;
  if (r->has_indicators && r->indicators[5] == 0.1 * 5 + 1.0 / 3.0 && r->build_ms == 1.25 &&
      r->iteration == 3 && r->tuner && !strcmp(r->tuner, "tuner_nm"))
    w->exact++;
  return 0;
}

int main(void) {
  char dir[] = "/tmp/tt_tune_dbXXXXXX";
  if (!mkdtemp(dir)) return 1;
  char path[4200], csv[4200], buf[4096];
  /* a missing parent directory is created, as the default location needs */
  snprintf(path, sizeof path, "%s/nested/deeper/tuning.db", dir);
  snprintf(csv, sizeof csv, "%s/export.csv", dir);

  tt_tunedb *db = NULL;
  CHECK(tt_tunedb_open(path, &db) == TT_OK);
  if (!db) return tt_test_finish("tune_db");
  CHECK(!strcmp(tt_tunedb_path(db), path));

  /* schema: WAL, versioned, the documented columns */
  CHECK(query1(path, "PRAGMA journal_mode", buf, sizeof buf));
  CHECK_MSG(!strcmp(buf, "wal"), "journal_mode %s", buf);
  CHECK(query1(path, "PRAGMA user_version", buf, sizeof buf));
  CHECK(atoi(buf) == TT_TUNEDB_SCHEMA_VERSION);
  const char *cols[] = {"scene_id",       "camera", "context",   "indicators", "plugin",
                        "plugin_version", "config", "objective", "build_ms",   "render_ms",
                        "cost",           "status", "machine",   "cpu",        "timestamp",
                        "host",           "rank"};
  for (size_t i = 0; i < sizeof cols / sizeof cols[0]; i++) {
    char sql[256];
    snprintf(sql, sizeof sql, "SELECT count(*) FROM pragma_table_info('samples') WHERE name='%s'",
             cols[i]);
    CHECK_MSG(query1(path, sql, buf, sizeof buf) && !strcmp(buf, "1"), "column %s", cols[i]);
  }

  /* record / lookup */
  tt_tunedb_row a = make_row("{\"quality\":2,\"intcost\":0.5}", 4.0, TT_TUNEDB_OK);
  CHECK(tt_tunedb_record(db, &a) == TT_OK);
  CHECK(a.id > 0);
  double cost = -1;
  uint32_t count = 0;
  CHECK(tt_tunedb_lookup(db, &a, &cost, &count) == TT_OK);
  CHECK(cost == 4.0 && count == 1);
  /* a second measurement of the same key: the lookup answers the mean */
  tt_tunedb_row a2 = make_row("{\"quality\":2,\"intcost\":0.5}", 6.0, TT_TUNEDB_OK);
  CHECK(tt_tunedb_record(db, &a2) == TT_OK);
  CHECK(a2.id > a.id);
  CHECK(tt_tunedb_lookup(db, &a, &cost, &count) == TT_OK);
  CHECK_NEAR(cost, 5.0, 1e-12);
  CHECK(count == 2);
  /* every key field separates: objective, camera, context, version, machine */
  tt_tunedb_row k = a;
  k.objective = "build+render";
  CHECK(tt_tunedb_lookup(db, &k, &cost, &count) == TT_ERR_NO_DATA);
  k = a;
  k.camera = "{\"position\":[0,1,3],\"resolution\":[32,32]}";
  CHECK(tt_tunedb_lookup(db, &k, &cost, &count) == TT_ERR_NO_DATA);
  k = a;
  k.context = "{\"spp\":4,\"threads\":2}";
  CHECK(tt_tunedb_lookup(db, &k, &cost, &count) == TT_ERR_NO_DATA);
  k = a;
  k.plugin_version = "0.2.0";
  CHECK(tt_tunedb_lookup(db, &k, &cost, &count) == TT_ERR_NO_DATA);
  k = a;
  k.machine = "another-machine";
  CHECK(tt_tunedb_lookup(db, &k, &cost, &count) == TT_ERR_NO_DATA);
  /* infeasible answers (constraints are deterministic); a failure does not (may be transient) */
  tt_tunedb_row inf = make_row("{\"quality\":3,\"intcost\":9}", 1e300, TT_TUNEDB_INFEASIBLE);
  CHECK(tt_tunedb_record(db, &inf) == TT_OK);
  CHECK(tt_tunedb_lookup(db, &inf, &cost, &count) == TT_OK && cost == 1e300);
  /* a config with a comma, a quote and a newline in a string: CSV must quote it */
  tt_tunedb_row fail = make_row("{\"name\":\"a,\\\"b\\\"\\nc\"}", 1e300, TT_TUNEDB_FAILED);
  CHECK(tt_tunedb_record(db, &fail) == TT_OK);
  CHECK(tt_tunedb_lookup(db, &fail, &cost, &count) == TT_ERR_NO_DATA);

  /* invalid rows are refused */
  tt_tunedb_row bad = make_row("{}", NAN, TT_TUNEDB_OK);
  CHECK(tt_tunedb_record(db, &bad) == TT_ERR_INVALID_ARGUMENT);
  bad = make_row("{}", 1.0, TT_TUNEDB_OK);
  bad.scene_id = NULL;
  CHECK(tt_tunedb_record(db, &bad) == TT_ERR_INVALID_ARGUMENT);

  /* iteration and counts */
  uint64_t n = 0;
  CHECK(tt_tunedb_count(db, NULL, &n) == TT_OK && n == 4);
  CHECK(tt_tunedb_count(db, "integrator_pt", &n) == TT_OK && n == 0);
  walk w = {0, 0, 0};
  CHECK(tt_tunedb_foreach(db, "accel_embree", on_row, &w) == TT_OK);
  CHECK(w.rows == 4 && w.complete == 4 && w.exact == 4);

  /* CSV: header + one line per row (the quoted newline continues a record) */
  CHECK(tt_tunedb_export_csv(db, csv) == TT_OK);
  FILE *f = fopen(csv, "r");
  CHECK(f != NULL);
  if (f) {
    static char text[1 << 16];
    size_t len = fread(text, 1, sizeof text - 1, f);
    text[len] = 0;
    fclose(f);
    int records = 0, quoted = 0, fields_first = 1;
    for (const char *p = text; *p; p++) {
      if (*p == '"') quoted = !quoted;
      else if (*p == '\n' && !quoted) records++;
      else if (*p == ',' && !quoted && records == 0) fields_first++;
    }
    CHECK_MSG(records == 5, "%d CSV records", records);
    CHECK(fields_first == 23 + TT_SCENE_INDICATOR_COUNT);
    CHECK_CONTAINS(text, "id,scene_id,scene,camera,context,plugin,");
    CHECK_CONTAINS(text, ",ind_meshes,");
    CHECK_CONTAINS(text, "\"{\"\"name\"\":\"\"a,");
    CHECK_CONTAINS(text, ",infeasible,");
    CHECK_CONTAINS(text, ",failed,");
  }

  /* reopening keeps the rows; a newer schema is refused, naming both versions */
  tt_tunedb_close(db);
  db = NULL;
  CHECK(tt_tunedb_open(path, &db) == TT_OK);
  CHECK(db && tt_tunedb_count(db, NULL, &n) == TT_OK && n == 4);
  tt_tunedb_close(db);
  sqlite3 *raw = NULL;
  CHECK(sqlite3_open(path, &raw) == SQLITE_OK);
  CHECK(sqlite3_exec(raw, "PRAGMA user_version=99", NULL, NULL, NULL) == SQLITE_OK);
  sqlite3_close(raw);
  db = NULL;
  CHECK(tt_tunedb_open(path, &db) == TT_ERR_UNSUPPORTED);
  CHECK(db == NULL);
  CHECK_CONTAINS(tt_last_error(), "99");

  /* default path: $XDG_DATA_HOME when absolute, else ~/.local/share */
  setenv("XDG_DATA_HOME", "/data/x", 1);
  char *p = tt_tunedb_default_path();
  CHECK(p && !strcmp(p, "/data/x/tunetrace/tuning.db"));
  tt_free(p);
  setenv("XDG_DATA_HOME", "relative/ignored", 1);
  setenv("HOME", "/home/someone", 1);
  p = tt_tunedb_default_path();
  CHECK(p && !strcmp(p, "/home/someone/.local/share/tunetrace/tuning.db"));
  tt_free(p);

  CHECK(tt_tunedb_machine_id()[0] != 0);
  CHECK(tt_tunedb_cpu_model()[0] != 0);

  snprintf(buf, sizeof buf, "rm -rf '%s'", dir);
  if (system(buf) != 0) {}
  return tt_test_finish("tune_db");
}
