/* Reading a tuning database changes nothing in it, and what is not one is refused by name:
 * tt_tunedb_open_readonly leaves the file byte for byte (no WAL switch, no schema upgrade,
 * no tables added), reads a schema-1 file as it is and refuses to record or merge; another
 * program's SQLite file, a negative or newer schema version, a table samples without the
 * schema's columns and a damaged file (PRAGMA quick_check) are refused by both openers,
 * the file left as it was; rows that are not rows of the schema (text costs, indicators
 * that are not JSON, unknown statuses) are skipped, counted (tt_tunedb_bad_rows) and named
 * in one warning, and never answer a lookup. */
#include <tunetrace/tunetrace.h>

#include <sqlite3.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "tt_test.h"
#include "tt_test_sqlite.h"

static char g_dir[] = "/tmp/tt_tune_db_readXXXXXX";
static int g_warnings;
static char g_last[2048];

static void capture_log(tt_log_level level, const char *plugin, const char *fmt, ...) {
  (void)plugin;
  if (level != TT_LOG_WARN) return;
  g_warnings++;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(g_last, sizeof g_last, fmt, ap);
  va_end(ap);
}

/* DIR/name; each call its own buffer (the test names fewer than 32 files). */
static const char *path_of(const char *name) {
  static char p[32][600];
  static int k;
  k = (k + 1) % 32;
  snprintf(p[k], sizeof p[k], "%s/%s", g_dir, name);
  return p[k];
}

/* Runs SQL on a file directly (another program's writes). */
static int sql(const char *path, const char *text) {
  sqlite3 *db = NULL;
  int rc = sqlite3_open(path, &db) == SQLITE_OK ? sqlite3_exec(db, text, NULL, NULL, NULL) : -1;
  sqlite3_close(db);
  return rc == SQLITE_OK;
}

static char *slurp(const char *path, size_t *n) {
  char *d = NULL;
  return tt_file_read(path, NULL, 0, &d, n) == TT_OK ? d : NULL;
}

/* 1 if `path` holds exactly `data` (n bytes). */
static int unchanged(const char *path, const char *data, size_t n) {
  size_t m = 0;
  char *now = slurp(path, &m);
  int same = now && data && m == n && !memcmp(now, data, n);
  tt_free(now);
  return same;
}

static tt_tunedb_row make_row(const char *config, double cost) {
  tt_tunedb_row r;
  memset(&r, 0, sizeof r);
  r.struct_size = sizeof r;
  r.scene_id = "abc123";
  r.camera = "{\"i\":1}";
  r.context = "{\"spp\":1}";
  r.has_indicators = 1;
  for (int i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) r.indicators[i] = 0.5 + i;
  r.plugin = "accel_embree";
  r.plugin_version = "0.1.0";
  r.config = config;
  r.objective = "render";
  r.render_ms = cost;
  r.cost = cost;
  r.status = TT_TUNEDB_OK;
  r.mode = "tune";
  return r;
}

static int count_rows(void *user, const tt_tunedb_row *r) {
  int *n = user;
  (*n)++;
  CHECK(r->scene_id && r->config && r->has_indicators && r->indicators[2] == 2.5);
  return 0;
}

/* Both openers refuse `path` with TT_ERR_UNSUPPORTED (or `io` TT_ERR_IO), the message naming
 * the file and `what`; the file keeps its bytes. */
static void refused_by_both(const char *path, const char *what, int io) {
  size_t n = 0;
  char *before = slurp(path, &n);
  tt_tunedb *db = NULL;
  tt_status want = io ? TT_ERR_IO : TT_ERR_UNSUPPORTED;
  tt_status st = tt_tunedb_open_readonly(path, &db);
  CHECK_MSG(st == want && !db, "%s read-only: %d %s", path, (int)st, tt_last_error());
  CHECK_CONTAINS(tt_last_error(), path);
  CHECK_CONTAINS(tt_last_error(), what);
  tt_tunedb_close(db);
  db = NULL;
  st = tt_tunedb_open(path, &db);
  CHECK_MSG(st == want && !db, "%s read-write: %d %s", path, (int)st, tt_last_error());
  CHECK_CONTAINS(tt_last_error(), path);
  CHECK_CONTAINS(tt_last_error(), what);
  tt_tunedb_close(db);
  CHECK_MSG(unchanged(path, before, n), "%s was changed", path);
  tt_free(before);
}

int main(void) {
  if (!mkdtemp(g_dir)) return 1;
  tt_host h = *tt_default_host();
  h.log = capture_log;
  tt_set_log_host(&h);
  char buf[4096];

  /* a tuning database of 3 rows, closed (its WAL checkpointed into the file) */
  const char *good = path_of("good.db");
  tt_tunedb *db = NULL;
  CHECK(tt_tunedb_open(good, &db) == TT_OK);
  const char *configs[] = {"{\"q\":1}", "{\"q\":2}", "{\"q\":3}"};
  for (int i = 0; i < 3 && db; i++) {
    tt_tunedb_row r = make_row(configs[i], 10.0 + i);
    CHECK(tt_tunedb_record(db, &r) == TT_OK);
  }
  tt_tunedb_close(db);

  /* read-only: rows read, lookups answered, nothing written, record and merge refused */
  size_t n0 = 0;
  char *orig = slurp(good, &n0);
  CHECK(tt_tunedb_open_readonly(good, &db) == TT_OK);
  if (db) {
    CHECK(tt_tunedb_read_only(db));
    int rows = 0;
    CHECK(tt_tunedb_foreach(db, NULL, count_rows, &rows) == TT_OK && rows == 3);
    CHECK(tt_tunedb_bad_rows(db) == 0);
    tt_tunedb_row key = make_row(configs[1], 0);
    double cost = 0;
    CHECK(tt_tunedb_lookup(db, &key, &cost, NULL) == TT_OK && cost == 11.0);
    tt_tunedb_row r = make_row("{\"q\":9}", 1);
    CHECK(tt_tunedb_record(db, &r) == TT_ERR_INVALID_ARGUMENT);
    CHECK_CONTAINS(tt_last_error(), "read-only");
    CHECK(tt_tunedb_merge(db, NULL, "tag", -1, NULL, NULL, NULL) == TT_ERR_INVALID_ARGUMENT);
    tt_tunedb_close(db);
  }
  CHECK_MSG(unchanged(good, orig, n0), "a read-only open changed %s", good);
  tt_free(orig);

  /* a database in rollback-journal mode keeps it when read (the read-write open makes WAL) */
  const char *journal = path_of("journal.db");
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", good, journal);
  CHECK(system(cmd) == 0);
  CHECK(sql(journal, "PRAGMA journal_mode=DELETE"));
  CHECK(tt_tunedb_open_readonly(journal, &db) == TT_OK);
  tt_tunedb_close(db);
  CHECK(tt_test_query1(journal, "PRAGMA journal_mode", buf, sizeof buf, "") &&
        !strcmp(buf, "delete"));

  /* schema 1, read as it is: no upgrade, host and rank absent */
  const char *v1 = path_of("v1.db");
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", journal, v1);
  CHECK(system(cmd) == 0);
  CHECK(sql(v1, "DROP TABLE merges; ALTER TABLE samples DROP COLUMN host; "
                "ALTER TABLE samples DROP COLUMN rank; PRAGMA user_version=1"));
  size_t n1 = 0;
  char *v1_bytes = slurp(v1, &n1);
  CHECK(tt_tunedb_open_readonly(v1, &db) == TT_OK);
  if (db) {
    int rows = 0;
    CHECK(tt_tunedb_foreach(db, NULL, count_rows, &rows) == TT_OK && rows == 3);
    tt_tunedb_close(db);
  }
  CHECK(unchanged(v1, v1_bytes, n1));
  tt_free(v1_bytes);

  /* another program's SQLite file: refused, never given our tables */
  const char *foreign = path_of("foreign.db");
  CHECK(sql(foreign,
            "CREATE TABLE photos (id INTEGER, name TEXT); INSERT INTO photos VALUES (1, 'x')"));
  refused_by_both(foreign, "not a tunetrace tuning database", 0);
  CHECK_CONTAINS(tt_last_error(), "photos");
  CHECK(tt_test_query1(foreign, "SELECT group_concat(name) FROM sqlite_master", buf, sizeof buf,
                       "") &&
        !strcmp(buf, "photos"));

  /* schema versions this build does not read */
  const char *neg = path_of("negative.db");
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", journal, neg);
  CHECK(system(cmd) == 0);
  CHECK(sql(neg, "PRAGMA user_version=-1"));
  refused_by_both(neg, "schema version -1", 0);
  const char *newer = path_of("newer.db");
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", journal, newer);
  CHECK(system(cmd) == 0);
  CHECK(sql(newer, "PRAGMA user_version=3"));
  refused_by_both(newer, "schema version 3 is newer", 0);
  /* version 2 with a table samples of someone else's */
  const char *odd = path_of("odd.db");
  CHECK(sql(odd, "CREATE TABLE samples (id INTEGER, cost REAL); PRAGMA user_version=2"));
  refused_by_both(odd, "lacks the columns scene_id", 0);
  /* an empty file: nothing to read; the read-write open makes it a database */
  const char *empty = path_of("empty.db");
  CHECK(tt_file_write_atomic(empty, "", 0) == TT_OK);
  CHECK(tt_tunedb_open_readonly(empty, &db) == TT_ERR_UNSUPPORTED && !db);
  CHECK_CONTAINS(tt_last_error(), "empty");
  CHECK(tt_tunedb_open(empty, &db) == TT_OK);
  tt_tunedb_close(db);
  /* not SQLite at all */
  const char *text = path_of("text.db");
  CHECK(tt_file_write_atomic(text, "hello, this is not SQLite at all, not even close....", 52) ==
        TT_OK);
  refused_by_both(text, "not an SQLite database", 1);

  /* a damaged file: an index page overwritten (the schema still reads) */
  const char *damaged = path_of("damaged.db");
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", journal, damaged);
  CHECK(system(cmd) == 0);
  CHECK(tt_test_query1(damaged, "SELECT rootpage FROM sqlite_master WHERE name = 'samples_key'",
                       buf, sizeof buf, ""));
  long page = atol(buf);
  CHECK(tt_test_query1(damaged, "PRAGMA page_size", buf, sizeof buf, ""));
  long page_size = atol(buf);
  FILE *f = fopen(damaged, "r+b");
  CHECK(f && page > 1 && page_size > 0);
  if (f) {
    fseek(f, (page - 1) * page_size + 8, SEEK_SET);
    fwrite("\xff\xff\xff\xff", 1, 4, f);
    fclose(f);
  }
  refused_by_both(damaged, "damaged (PRAGMA quick_check", 1);

  /* rows that are not rows of the schema: skipped, counted, one warning */
  const char *bad = path_of("bad.db");
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", good, bad);
  CHECK(system(cmd) == 0);
  const char *copy =
      "INSERT INTO samples (scene_id, scene, camera, context, indicators, plugin, plugin_version,"
      " config, objective, build_ms, render_ms, cost, status, mode, iteration, run_id, tuner,"
      " metrics, machine, cpu, timestamp, host, rank) SELECT scene_id, scene, camera, context, %s,"
      " plugin, plugin_version, '{\"q\":%d}', objective, build_ms, render_ms, %s, %s, mode,"
      " iteration, run_id, tuner, metrics, machine, cpu, timestamp, host, rank FROM samples"
      " WHERE id = 1";
  struct {
    const char *indicators, *cost, *status;
  } rows[] = {{"'not json'", "cost", "status"},
              {"'{\"meshes\": \"many\"}'", "cost", "status"},
              {"indicators", "'cheap'", "status"},
              {"indicators", "cost", "7"},
              {"indicators", "cost", "'ok'"}};
  for (int i = 0; i < 5; i++) {
    snprintf(cmd, sizeof cmd, copy, rows[i].indicators, 100 + i, rows[i].cost, rows[i].status);
    CHECK_MSG(sql(bad, cmd), "%s", cmd);
  }
  g_warnings = 0;
  CHECK(tt_tunedb_open_readonly(bad, &db) == TT_OK);
  if (db) {
    int n = 0;
    CHECK(tt_tunedb_foreach(db, NULL, count_rows, &n) == TT_OK);
    CHECK_MSG(n == 3, "%d good rows read", n);
    CHECK(tt_tunedb_bad_rows(db) == 5);
    CHECK(g_warnings == 1);
    CHECK_CONTAINS(g_last, bad);
    CHECK_CONTAINS(g_last, "5 rows skipped");
    CHECK_CONTAINS(g_last, "indicators is not a JSON object");
    /* a text cost never answers a lookup (SQLite would read 'cheap' as 0) */
    tt_tunedb_row key = make_row("{\"q\":102}", 0);
    CHECK(tt_tunedb_lookup(db, &key, NULL, NULL) == TT_ERR_NO_DATA);
    /* the CSV export skips them too */
    CHECK(tt_tunedb_export_csv(db, path_of("bad.csv")) == TT_OK);
    CHECK(tt_tunedb_bad_rows(db) == 5);
    tt_tunedb_close(db);
  }

  tt_set_log_host(NULL);
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
  (void)!system(cmd);
  return tt_test_finish("tune_db_read");
}
