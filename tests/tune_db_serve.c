/* Tuning database for distributed runs: a schema-1 file is upgraded to 2 when opened (its
 * rows kept, host and rank NULL); every new row names its host, MPI rows their rank; a row of
 * a caller built before schema 2 (smaller struct_size) stores no rank; lookups restricted to
 * a view (snapshot id, or the run's own rows); a handle over a backend forwards complete
 * rows and keys (machine, cpu, host, timestamp filled in on the measuring side) and refuses
 * what only a file can do. */
#include <tunetrace/tunetrace.h>

#include <sqlite3.h>
#include <stddef.h>
#include <stdlib.h>
#include <unistd.h>

#include "tt_test.h"

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
  sqlite3 *db = NULL;
  sqlite3_stmt *st = NULL;
  int ok = 0;
  buf[0] = 0;
  if (sqlite3_open_v2(path, &db, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
      sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW) {
    const unsigned char *t = sqlite3_column_text(st, 0);
    snprintf(buf, n, "%s", t ? (const char *)t : "NULL");
    ok = 1;
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
  return ok;
}

/* A backend that keeps what it was given. */
typedef struct served {
  int records, lookups, closed;
  char machine[256], cpu[256], host[256], timestamp[64], key_machine[256];
  int has_rank, rank;
} served;

static tt_status served_record(void *user, const tt_tunedb_row *row, int64_t *id) {
  served *s = user;
  s->records++;
  snprintf(s->machine, sizeof s->machine, "%s", row->machine ? row->machine : "NULL");
  snprintf(s->cpu, sizeof s->cpu, "%s", row->cpu ? row->cpu : "NULL");
  snprintf(s->host, sizeof s->host, "%s", row->host ? row->host : "NULL");
  snprintf(s->timestamp, sizeof s->timestamp, "%s", row->timestamp ? row->timestamp : "NULL");
  s->has_rank = row->has_rank;
  s->rank = row->rank;
  *id = 1000 + s->records;
  return TT_OK;
}

static tt_status served_lookup(void *user, const tt_tunedb_row *key, double *cost,
                               uint32_t *count) {
  served *s = user;
  s->lookups++;
  snprintf(s->key_machine, sizeof s->key_machine, "%s", key->machine ? key->machine : "NULL");
  if (strcmp(key->config, "{\"a\":1}")) return TT_ERR_NO_DATA;
  if (cost) *cost = 7.5;
  if (count) *count = 2;
  return TT_OK;
}

static void served_close(void *user) { ((served *)user)->closed++; }

static int count_rows(void *user, const tt_tunedb_row *r) {
  (void)r;
  ++*(int *)user;
  return 0;
}

int main(void) {
  char dir[] = "/tmp/tt_tune_db_serveXXXXXX";
  if (!mkdtemp(dir)) return 1;
  char path[4200], buf[4096];
  snprintf(path, sizeof path, "%s/v1.db", dir);

  /* a file of schema 1, as builds before host and rank wrote it */
  sqlite3 *raw = NULL;
  CHECK(sqlite3_open(path, &raw) == SQLITE_OK);
  CHECK(sqlite3_exec(raw,
    "PRAGMA journal_mode=WAL;"
    "CREATE TABLE samples (id INTEGER PRIMARY KEY, scene_id TEXT NOT NULL, scene TEXT,"
    " camera TEXT NOT NULL, context TEXT NOT NULL, indicators TEXT, plugin TEXT NOT NULL,"
    " plugin_version TEXT NOT NULL, config TEXT NOT NULL, objective TEXT NOT NULL,"
    " build_ms REAL NOT NULL, render_ms REAL NOT NULL, cost REAL NOT NULL,"
    " status INTEGER NOT NULL, mode TEXT, iteration INTEGER, run_id TEXT, tuner TEXT,"
    " metrics TEXT, machine TEXT NOT NULL, cpu TEXT NOT NULL, timestamp TEXT NOT NULL);"
    "INSERT INTO samples VALUES (NULL, 's1', 'scene.json', '{\"path_index\":3}', '{\"spp\":1}',"
    " NULL, 'accel_embree', '1.0', '{\"a\":1}', 'render', 0, 2, 2, 0, 'explore', 0, 'old',"
    " NULL, NULL, 'm', 'c', '2020-01-01T00:00:00.000Z');"
    "PRAGMA user_version=1;", NULL, NULL, NULL) == SQLITE_OK);
  sqlite3_close(raw);

  tt_tunedb *db = NULL;
  CHECK(tt_tunedb_open(path, &db) == TT_OK);
  if (!db) return tt_test_finish("tune_db_serve");
  CHECK(query1(path, "PRAGMA user_version", buf, sizeof buf) && atoi(buf) == 2);
  CHECK(query1(path, "SELECT count(*) FROM samples", buf, sizeof buf) && !strcmp(buf, "1"));
  CHECK(query1(path, "SELECT coalesce(host, 'NULL') || ':' || coalesce(rank, 'NULL') FROM samples",
               buf, sizeof buf) && !strcmp(buf, "NULL:NULL"));
  int64_t snap = -1;
  CHECK(tt_tunedb_last_id(db, &snap) == TT_OK && snap == 1);

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
  snprintf(sql, sizeof sql, "SELECT host || ':' || coalesce(rank, 'NULL') FROM samples WHERE id = %lld",
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

  /* views: the snapshot (the old row only) plus the run's own rows */
  tt_tunedb_row key = make_row("{\"a\":3}", 0, NULL);
  key.machine = mpi.machine;
  double cost = 0;
  uint32_t n = 0;
  CHECK(tt_tunedb_lookup(db, &key, &cost, &n) == TT_OK && cost == 4.0 && n == 1);
  tt_tunedb_view v;
  memset(&v, 0, sizeof v);
  v.struct_size = sizeof v;
  v.max_id = snap;
  CHECK(tt_tunedb_lookup_view(db, &v, &key, &cost, &n) == TT_ERR_NO_DATA);
  v.run_id = "run-a";
  CHECK(tt_tunedb_lookup_view(db, &v, &key, &cost, &n) == TT_ERR_NO_DATA);
  v.run_id = "run-b";
  CHECK(tt_tunedb_lookup_view(db, &v, &key, &cost, &n) == TT_OK && cost == 4.0 && n == 1);
  /* the old row (machine 'm', cpu 'c') is in the snapshot */
  tt_tunedb_row okey = make_row("{\"a\":1}", 0, NULL);
  okey.machine = "m";
  okey.cpu = "c";
  v.run_id = NULL;
  CHECK(tt_tunedb_lookup_view(db, &v, &okey, &cost, &n) == TT_OK && cost == 2.0 && n == 1);
  v.max_id = 0;
  CHECK(tt_tunedb_lookup_view(db, &v, &okey, &cost, &n) == TT_ERR_NO_DATA);
  CHECK(tt_tunedb_lookup_view(db, NULL, &okey, &cost, &n) == TT_OK);  /* NULL: every row */
  tt_tunedb_close(db);

  /* a backend: rows arrive complete, keys name this machine, files-only calls refused */
  served s;
  memset(&s, 0, sizeof s);
  tt_tunedb_backend b;
  memset(&b, 0, sizeof b);
  b.struct_size = sizeof b;
  b.user = &s;
  b.record = served_record;
  b.lookup = served_lookup;
  b.close = served_close;
  tt_tunedb *remote = NULL;
  CHECK(tt_tunedb_open_backend(&b, "rank 0: /x/tuning.db", &remote) == TT_OK);
  CHECK(remote && !strcmp(tt_tunedb_path(remote), "rank 0: /x/tuning.db"));
  tt_tunedb_row r = make_row("{\"a\":1}", 2.5, "job-1");
  r.has_rank = 1;
  r.rank = 3;
  CHECK(tt_tunedb_record(remote, &r) == TT_OK && r.id == 1001);
  CHECK(s.records == 1 && !strcmp(s.machine, tt_tunedb_machine_id()) &&
        !strcmp(s.cpu, tt_tunedb_cpu_model()) && !strcmp(s.host, tt_tunedb_host_name()));
  CHECK(strlen(s.timestamp) == 24 && s.timestamp[23] == 'Z');
  CHECK(s.has_rank && s.rank == 3);
  CHECK(tt_tunedb_lookup(remote, &r, &cost, &n) == TT_OK && cost == 7.5 && n == 2);
  CHECK(!strcmp(s.key_machine, tt_tunedb_machine_id()));
  tt_tunedb_row miss = make_row("{\"a\":9}", 0, NULL);
  CHECK(tt_tunedb_lookup(remote, &miss, &cost, &n) == TT_ERR_NO_DATA);
  uint64_t cnt = 0;
  CHECK(tt_tunedb_count(remote, NULL, &cnt) == TT_ERR_UNSUPPORTED);
  CHECK_CONTAINS(tt_last_error(), "served by another process");
  CHECK(tt_tunedb_foreach(remote, NULL, count_rows, &rows) == TT_ERR_UNSUPPORTED);
  CHECK(tt_tunedb_last_id(remote, &snap) == TT_ERR_UNSUPPORTED);
  tt_tunedb_close(remote);
  CHECK(s.closed == 1);
  b.lookup = NULL;
  CHECK(tt_tunedb_open_backend(&b, "x", &remote) == TT_ERR_INVALID_ARGUMENT);

  snprintf(buf, sizeof buf, "rm -rf '%s'", dir);
  if (system(buf) != 0) {}
  return tt_test_finish("tune_db_serve");
}
