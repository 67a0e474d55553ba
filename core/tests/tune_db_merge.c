/* Tuning database for distributed runs: a schema-1 file is upgraded to 2 when opened (its
 * rows kept, host and rank NULL); every new row names its host, MPI rows their rank; a row of
 * a caller built before schema 2 (smaller struct_size) stores no rank; tt_tunedb_merge copies
 * a file's rows once per tag (a second merge copies nothing), keeps or sets the rank, reads
 * schema-1 files, and a merge that fails half-way leaves neither rows nor tag. */
#include <tunetrace/tunetrace.h>

#include <sqlite3.h>
#include <stddef.h>
#include <stdlib.h>
#include <unistd.h>

#include "tt_test.h"
#include "tt_test_sqlite.h"

static tt_tunedb_row make_row(const char *config, double cost, const char *run_id) {
  tt_tunedb_row r;
  memset(&r, 0, sizeof r);
  r.struct_size = sizeof r;
  r.scene_id = "s1";
  r.scene = "scene.json";
  r.camera = "{\"path_index\":3}";
  r.context = "{\"spp\":1}";
  r.plugin = "accel_embree";
  r.plugin_version = "1.0";
  r.config = config;
  r.objective = "render";
  r.render_ms = r.cost = cost;
  r.status = TT_TUNEDB_OK;
  r.mode = "explore";
  r.run_id = run_id;
  return r;
}

static int query1(const char *path, const char *sql, char *buf, size_t n) {
  return tt_test_query1(path, sql, buf, n, "NULL");
}

static int count_rows(void *user, const tt_tunedb_row *r) {
  (void)r;
  ++*(int *)user;
  return 0;
}

static int64_t count_sql(const char *path, const char *sql) {
  char buf[64];
  return query1(path, sql, buf, sizeof buf) ? atoll(buf) : -1;
}

/* A schema-1 file (as builds before host and rank wrote it) with `n` rows; `bad`: a table
 * without NOT NULL whose last row has no cost (a merge of it must fail and copy nothing). */
static int write_v1(const char *path, int n, int bad) {
  sqlite3 *raw = NULL;
  char sql[4096];
  int ok = sqlite3_open(path, &raw) == SQLITE_OK;
  snprintf(sql, sizeof sql,
           "PRAGMA journal_mode=WAL;"
           "CREATE TABLE samples (id INTEGER PRIMARY KEY, scene_id TEXT %s, scene TEXT,"
           " camera TEXT NOT NULL, context TEXT NOT NULL, indicators TEXT, plugin TEXT NOT NULL,"
           " plugin_version TEXT NOT NULL, config TEXT NOT NULL, objective TEXT NOT NULL,"
           " build_ms REAL NOT NULL, render_ms REAL NOT NULL, cost REAL %s,"
           " status INTEGER NOT NULL, mode TEXT, iteration INTEGER, run_id TEXT, tuner TEXT,"
           " metrics TEXT, machine TEXT NOT NULL, cpu TEXT NOT NULL, timestamp TEXT NOT NULL);"
           "PRAGMA user_version=1;",
           bad ? "" : "NOT NULL", bad ? "" : "NOT NULL");
  ok = ok && sqlite3_exec(raw, sql, NULL, NULL, NULL) == SQLITE_OK;
  for (int i = 0; i < n && ok; i++) {
    snprintf(sql, sizeof sql,
             "INSERT INTO samples VALUES (NULL, 's1', 'scene.json', '{\"path_index\":3}', "
             "'{\"spp\":1}', NULL, 'accel_embree', '1.0', '{\"a\":%d}', 'render', 0, 2, %s, 0, "
             "'explore', %d, 'old', NULL, NULL, 'm', 'c', '2020-01-01T00:00:00.000Z');",
             i, bad && i == n - 1 ? "NULL" : "2", i);
    ok = sqlite3_exec(raw, sql, NULL, NULL, NULL) == SQLITE_OK;
  }
  sqlite3_close(raw);
  return ok;
}

int main(void) {
  char dir[] = "/tmp/tt_tune_db_mergeXXXXXX";
  if (!mkdtemp(dir)) return 1;
  char path[4200], buf[4096];
  snprintf(path, sizeof path, "%s/v1.db", dir);

  CHECK(write_v1(path, 1, 0));

  tt_tunedb *db = NULL;
  CHECK(tt_tunedb_open(path, &db) == TT_OK);
  if (!db) return tt_test_finish("tune_db_merge");
  CHECK(query1(path, "PRAGMA user_version", buf, sizeof buf) && atoi(buf) == 2);
  CHECK(query1(path, "SELECT count(*) FROM samples", buf, sizeof buf) && !strcmp(buf, "1"));
  CHECK(query1(path, "SELECT coalesce(host, 'NULL') || ':' || coalesce(rank, 'NULL') FROM samples",
               buf, sizeof buf) &&
        !strcmp(buf, "NULL:NULL"));

  /* new rows: the host always, the rank when given */
  tt_tunedb_row plain = make_row("{\"a\":2}", 3.0, "run-a");
  CHECK(tt_tunedb_record(db, &plain) == TT_OK);
  tt_tunedb_row mpi = make_row("{\"a\":3}", 4.0, "run-b");
  mpi.host = "node17";
  mpi.has_rank = 1;
  mpi.rank = 5;
  CHECK(tt_tunedb_record(db, &mpi) == TT_OK);
  /* a caller built before schema 2: its struct ends before host, so has_rank is not read */
  tt_tunedb_row old = make_row("{\"a\":4}", 5.0, "run-b");
  old.has_rank = 1;
  old.rank = 9;
  old.struct_size = offsetof(tt_tunedb_row, host);
  CHECK(tt_tunedb_record(db, &old) == TT_OK);
  char sql[256];
  snprintf(sql, sizeof sql,
           "SELECT host || ':' || coalesce(rank, 'NULL') FROM samples WHERE id = %lld",
           (long long)plain.id);
  char want[300];
  snprintf(want, sizeof want, "%s:NULL", tt_tunedb_host_name());
  CHECK(query1(path, sql, buf, sizeof buf) && !strcmp(buf, want));
  snprintf(sql, sizeof sql, "SELECT host || ':' || rank FROM samples WHERE id = %lld",
           (long long)mpi.id);
  CHECK(query1(path, sql, buf, sizeof buf) && !strcmp(buf, "node17:5"));
  snprintf(sql, sizeof sql, "SELECT coalesce(rank, 'NULL') FROM samples WHERE id = %lld",
           (long long)old.id);
  CHECK(query1(path, sql, buf, sizeof buf) && !strcmp(buf, "NULL"));
  /* foreach reads them back */
  int rows = 0;
  CHECK(tt_tunedb_foreach(db, NULL, count_rows, &rows) == TT_OK && rows == 4);

  tt_tunedb_close(db);

  /* merges: one file (schema 2, its ranks kept or replaced) into another, once per tag */
  char dst[4200], src1[4200], bad[4200], none[4200];
  snprintf(dst, sizeof dst, "%s/merged.db", dir);
  snprintf(src1, sizeof src1, "%s/old.db", dir);
  snprintf(bad, sizeof bad, "%s/bad.db", dir);
  snprintf(none, sizeof none, "%s/missing.db", dir);
  CHECK(write_v1(src1, 3, 0));
  CHECK(write_v1(bad, 3, 1));
  tt_tunedb *m = NULL;
  CHECK(tt_tunedb_open(dst, &m) == TT_OK);
  if (!m) return tt_test_finish("tune_db_merge");
  uint64_t copied = 99;
  int already = -1, merged = -1;
  CHECK(tt_tunedb_merged(m, "job-a", &merged) == TT_OK && merged == 0);
  CHECK(tt_tunedb_merge(m, path, "job-a", -1, "{\"kind\":\"tune\"}", &copied, &already) == TT_OK);
  CHECK_MSG(copied == 4 && already == 0, "copied %llu already %d", (unsigned long long)copied,
            already);
  CHECK(tt_tunedb_merged(m, "job-a", &merged) == TT_OK && merged == 1);
  /* the same tag again: nothing copied, the file unchanged */
  CHECK(tt_tunedb_merge(m, path, "job-a", -1, NULL, &copied, &already) == TT_OK);
  CHECK(copied == 0 && already == 1);
  CHECK(count_sql(dst, "SELECT count(*) FROM samples") == 4);
  /* the rows as they were, host and rank included (the rank of the MPI row kept) */
  CHECK(count_sql(dst, "SELECT count(*) FROM samples WHERE host = 'node17' AND rank = 5") == 1);
  CHECK(count_sql(dst, "SELECT count(*) FROM samples WHERE rank IS NULL") == 3);
  CHECK(count_sql(dst, "SELECT count(*) FROM samples m JOIN (SELECT config, cost, timestamp"
                       " FROM samples) s USING (config, cost, timestamp)") == 4);
  /* a schema-1 file with a rank given: host NULL, rank set */
  CHECK(tt_tunedb_merge(m, src1, "job-b", 2, NULL, &copied, &already) == TT_OK && copied == 3);
  CHECK(count_sql(dst, "SELECT count(*) FROM samples WHERE rank = 2 AND host IS NULL") == 3);
  CHECK(count_sql(dst, "SELECT rows FROM merges WHERE tag = 'job-b'") == 3);
  /* a tag without rows (work that makes no rows, e.g. frames) */
  CHECK(tt_tunedb_merge(m, NULL, "frames-0-3", 1, NULL, &copied, &already) == TT_OK &&
        copied == 0 && already == 0);
  CHECK(tt_tunedb_merged(m, "frames-0-3", &merged) == TT_OK && merged == 1);
  /* a merge that fails half-way copies nothing and records no tag */
  CHECK(tt_tunedb_merge(m, bad, "job-c", 1, NULL, &copied, &already) == TT_ERR_IO);
  CHECK(count_sql(dst, "SELECT count(*) FROM samples") == 7);
  CHECK(tt_tunedb_merged(m, "job-c", &merged) == TT_OK && merged == 0);
  /* a missing source is an error naming it, and is not created */
  CHECK(tt_tunedb_merge(m, none, "job-d", 1, NULL, &copied, &already) == TT_ERR_IO);
  CHECK_CONTAINS(tt_last_error(), "missing.db");
  CHECK(access(none, F_OK) != 0);
  /* not a tuning database */
  char junk[4200];
  snprintf(junk, sizeof junk, "%s/junk.db", dir);
  sqlite3 *raw = NULL;
  CHECK(sqlite3_open(junk, &raw) == SQLITE_OK &&
        sqlite3_exec(raw, "CREATE TABLE t (x);", NULL, NULL, NULL) == SQLITE_OK);
  sqlite3_close(raw);
  CHECK(tt_tunedb_merge(m, junk, "job-e", 1, NULL, &copied, &already) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "is not a tuning database");
  CHECK(tt_tunedb_merge(m, src1, "", 1, NULL, &copied, &already) == TT_ERR_INVALID_ARGUMENT);
  /* the handle still works after failed merges */
  tt_tunedb_row after = make_row("{\"a\":7}", 1.0, "run-c");
  CHECK(tt_tunedb_record(m, &after) == TT_OK);
  CHECK(count_sql(dst, "SELECT count(*) FROM samples") == 8);
  CHECK(count_sql(dst, "SELECT count(*) FROM merges") == 3);
  tt_tunedb_close(m);

  snprintf(buf, sizeof buf, "rm -rf '%s'", dir);
  if (system(buf) != 0) {}
  return tt_test_finish("tune_db_merge");
}
