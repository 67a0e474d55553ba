/* tunetrace: the tuning database on SQLite (see tunedb.h for the model). */
#include <tunetrace/tunedb.h>

#include <tunetrace/file.h>

#include "plugin/log.h"
#include "util/files.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

struct tt_tunedb {
  sqlite3 *sql;
  sqlite3_stmt *insert; /* NULL when read-only */
  sqlite3_stmt *lookup;
  char *path;
  int read_only;     /* tt_tunedb_open_readonly */
  int version;       /* the file's schema version (1 is read as 2 with NULL host, rank) */
  uint64_t bad_rows; /* rows the last tt_tunedb_foreach skipped */
};

/* Fields of a caller's row beyond the ones its struct_size covers read as absent (rows of
 * callers built before schema 2; a struct_size of 0 is taken as the first layout). */
#define TT__ROW_HAS(row, field) TT_HAS_FIELD(tt_tunedb_row, row, field)

/* Version 1 schema. Indicators are a JSON object so the row stays one table when
 * TT_SCENE_INDICATOR_COUNT grows; the CSV export spreads them into columns. */
static const char tt__schema_v1[] = "CREATE TABLE IF NOT EXISTS samples ("
                                    " id INTEGER PRIMARY KEY,"
                                    " scene_id TEXT NOT NULL,"
                                    " scene TEXT,"
                                    " camera TEXT NOT NULL,"
                                    " context TEXT NOT NULL,"
                                    " indicators TEXT,"
                                    " plugin TEXT NOT NULL,"
                                    " plugin_version TEXT NOT NULL,"
                                    " config TEXT NOT NULL,"
                                    " objective TEXT NOT NULL,"
                                    " build_ms REAL NOT NULL,"
                                    " render_ms REAL NOT NULL,"
                                    " cost REAL NOT NULL,"
                                    " status INTEGER NOT NULL,"
                                    " mode TEXT,"
                                    " iteration INTEGER,"
                                    " run_id TEXT,"
                                    " tuner TEXT,"
                                    " metrics TEXT,"
                                    " machine TEXT NOT NULL,"
                                    " cpu TEXT NOT NULL,"
                                    " timestamp TEXT NOT NULL);"
                                    "CREATE INDEX IF NOT EXISTS samples_key ON samples"
                                    " (scene_id, plugin, plugin_version, objective, config);";

/* Version 2: who measured (host name; MPI rank of tunetrace-mpi runs, else NULL) and the
 * tags merged into the file (tt_tunedb_merge: one row per tag, in the rows' transaction). */
static const char tt__schema_v2[] =
    "ALTER TABLE samples ADD COLUMN host TEXT;"
    "ALTER TABLE samples ADD COLUMN rank INTEGER;"
    "CREATE TABLE IF NOT EXISTS merges ("
    " tag TEXT PRIMARY KEY,"      /* the caller's name of what was merged (e.g. a job id) */
    " rows INTEGER NOT NULL,"     /* rows copied */
    " source TEXT,"               /* the file they came from */
    " note TEXT,"                 /* free text (a job's JSON) */
    " timestamp TEXT NOT NULL);"; /* ISO 8601 UTC */

static const char tt__columns[] =
    "id, scene_id, scene, camera, context, indicators, plugin, plugin_version, config,"
    " objective, build_ms, render_ms, cost, status, mode, iteration, run_id, tuner, metrics,"
    " machine, cpu, timestamp, host, rank";

static const char tt__lookup_sql[] =
    "SELECT avg(cost), count(*) FROM samples WHERE scene_id = ?1 AND"
    " camera = ?2 AND context = ?3 AND plugin = ?4 AND plugin_version = ?5"
    " AND config = ?6 AND objective = ?7 AND machine = ?8 AND cpu = ?9"
    " AND status IN (0, 1) AND typeof(cost) IN ('real', 'integer')";

/* Records an SQLite failure with the database path and SQLite's own message. */
static tt_status tt__sql_error(const tt_tunedb *db, sqlite3 *sql, const char *what) {
  return tt_set_error(TT_ERR_IO, "tuning database %s: %s: %s", db && db->path ? db->path : "?",
                      what, sql ? sqlite3_errmsg(sql) : "out of memory");
}

/* Trims trailing whitespace in place. */
static void tt__rstrip(char *s) {
  size_t n = strlen(s);
  while (n && (s[n - 1] == '\n' || s[n - 1] == ' ' || s[n - 1] == '\t')) s[--n] = 0;
}

const char *tt_tunedb_machine_id(void) {
  static char id[256];
  if (id[0]) return id;
  FILE *f = fopen("/etc/machine-id", "r");
  if (f) {
    if (!fgets(id, sizeof id, f)) id[0] = 0;
    fclose(f);
    tt__rstrip(id);
  }
  /* containers often lack /etc/machine-id: the host name is the next stable name */
  if (!id[0] && gethostname(id, sizeof id - 1) != 0) id[0] = 0;
  if (!id[0]) snprintf(id, sizeof id, "unknown");
  return id;
}

const char *tt_tunedb_host_name(void) {
  static char name[256];
  if (name[0]) return name;
  if (gethostname(name, sizeof name - 1) != 0 || !name[0]) snprintf(name, sizeof name, "unknown");
  return name;
}

const char *tt_tunedb_cpu_model(void) {
  static char model[256];
  if (model[0]) return model;
  FILE *f = fopen("/proc/cpuinfo", "r");
  char line[512];
  while (f && fgets(line, sizeof line, f)) {
    if (strncmp(line, "model name", 10) != 0) continue;
    const char *colon = strchr(line, ':');
    if (!colon) continue;
    colon++;
    while (*colon == ' ' || *colon == '\t') colon++;
    snprintf(model, sizeof model, "%s", colon);
    tt__rstrip(model);
    break;
  }
  if (f) fclose(f);
  if (!model[0]) snprintf(model, sizeof model, "unknown");
  return model;
}

char *tt_tunedb_default_path(void) {
  const char *xdg = getenv("XDG_DATA_HOME");
  const char *home = getenv("HOME");
  char buf[4096];
  /* XDG says a relative $XDG_DATA_HOME is invalid and must be ignored */
  if (xdg && xdg[0] == '/') snprintf(buf, sizeof buf, "%s/tunetrace/tuning.db", xdg);
  else if (home && home[0]) snprintf(buf, sizeof buf, "%s/.local/share/tunetrace/tuning.db", home);
  else return NULL;
  char *out = malloc(strlen(buf) + 1);
  if (out) strcpy(out, buf);
  return out;
}

/* mkdir -p of the directory holding `path`, so the default location works first time. */
static void tt__make_parent_dirs(const char *path) {
  char buf[4096];
  snprintf(buf, sizeof buf, "%s", path);
  char *slash = strrchr(buf, '/');
  if (!slash || slash == buf) return;
  *slash = 0;
  for (char *p = buf + 1; *p; p++) {
    if (*p != '/') continue;
    *p = 0;
    mkdir(buf, 0755);
    *p = '/';
  }
  mkdir(buf, 0755);
}

/* Runs SQL without results; 0 on success. */
static int tt__exec(tt_tunedb *db, const char *sql, const char *what) {
  char *msg = NULL;
  if (sqlite3_exec(db->sql, sql, NULL, NULL, &msg) == SQLITE_OK) return 0;
  tt_set_error(TT_ERR_IO, "tuning database %s: %s: %s", db->path, what,
               msg ? msg : sqlite3_errmsg(db->sql));
  sqlite3_free(msg);
  return -1;
}

/* Reads PRAGMA user_version into *version. A negative version is a value, not an error:
 * tt__check_schema refuses it by name. */
static tt_status tt__user_version(tt_tunedb *db, int *version) {
  sqlite3_stmt *st = NULL;
  int ok = sqlite3_prepare_v2(db->sql, "PRAGMA user_version", -1, &st, NULL) == SQLITE_OK &&
           sqlite3_step(st) == SQLITE_ROW;
  if (ok) *version = sqlite3_column_int(st, 0);
  sqlite3_finalize(st);
  if (ok) return TT_OK;
  if (sqlite3_errcode(db->sql) == SQLITE_NOTADB)
    return tt_set_error(TT_ERR_IO, "tuning database %s: not an SQLite database (%s)", db->path,
                        sqlite3_errmsg(db->sql));
  return tt__sql_error(db, db->sql, "reading the schema version");
}

/* The columns of table samples every schema version has (tt__columns without id, and
 * without host and rank, which version 2 added). */
static const char *const tt__required_columns[] = {
    "scene_id",  "scene",     "camera",   "context",   "indicators", "plugin", "plugin_version",
    "config",    "objective", "build_ms", "render_ms", "cost",       "status", "mode",
    "iteration", "run_id",    "tuner",    "metrics",   "machine",    "cpu",    "timestamp"};
#define TT__NREQUIRED (sizeof tt__required_columns / sizeof tt__required_columns[0])

/* Appends `name` to the comma-separated list `buf` ("..." once it is full). */
static void tt__list_add(char *buf, size_t n, const char *name) {
  size_t len = strlen(buf);
  if (len + strlen(name) + 8 >= n) {
    if (len + 6 < n && (len < 3 || strcmp(buf + len - 3, "..."))) strcat(buf, ", ...");
    return;
  }
  if (len) strcat(buf, ", ");
  strcat(buf, name);
}

/* The names of the file's tables (`tables`, comma-separated) and whether it has `samples`. */
static tt_status tt__tables(tt_tunedb *db, char *tables, size_t n, int *has_samples) {
  sqlite3_stmt *st = NULL;
  *has_samples = 0;
  tables[0] = '\0';
  if (sqlite3_prepare_v2(db->sql,
                         "SELECT name FROM sqlite_master WHERE type = 'table' AND "
                         "name NOT LIKE 'sqlite\\_%' ESCAPE '\\' ORDER BY name",
                         -1, &st, NULL) != SQLITE_OK)
    return tt__sql_error(db, db->sql, "reading the schema");
  int rc;
  while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
    const char *name = (const char *)sqlite3_column_text(st, 0);
    if (!name) continue;
    tt__list_add(tables, n, name);
    if (!strcmp(name, "samples")) *has_samples = 1;
  }
  sqlite3_finalize(st);
  return rc == SQLITE_DONE ? TT_OK : tt__sql_error(db, db->sql, "reading the schema");
}

/* The columns of table samples a schema `version` needs that the file lacks, in `missing`
 * (empty when none). */
static tt_status tt__missing_columns(tt_tunedb *db, int version, char *missing, size_t n) {
  int have[TT__NREQUIRED] = {0}, has_host = 0, has_rank = 0;
  missing[0] = '\0';
  sqlite3_stmt *st = NULL;
  if (sqlite3_prepare_v2(db->sql, "SELECT name FROM pragma_table_info('samples')", -1, &st, NULL) !=
      SQLITE_OK)
    return tt__sql_error(db, db->sql, "reading the columns of table samples");
  int rc;
  while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
    const char *name = (const char *)sqlite3_column_text(st, 0);
    if (!name) continue;
    for (size_t i = 0; i < TT__NREQUIRED; i++)
      if (!strcmp(name, tt__required_columns[i])) have[i] = 1;
    has_host |= !strcmp(name, "host");
    has_rank |= !strcmp(name, "rank");
  }
  sqlite3_finalize(st);
  if (rc != SQLITE_DONE) return tt__sql_error(db, db->sql, "reading the columns of table samples");
  for (size_t i = 0; i < TT__NREQUIRED; i++)
    if (!have[i]) tt__list_add(missing, n, tt__required_columns[i]);
  if (version >= 2 && !has_host) tt__list_add(missing, n, "host");
  if (version >= 2 && !has_rank) tt__list_add(missing, n, "rank");
  return TT_OK;
}

/* Checks that the file is a tunetrace tuning database this build reads, before anything is
 * written to it: its schema version (PRAGMA user_version) and, for an existing schema, the
 * table samples with the columns of that version. A file of version 0 is new only when it
 * holds no table: another program's SQLite file is refused, naming its tables, and never
 * given ours. Sets db->version. */
static tt_status tt__check_schema(tt_tunedb *db) {
  int version = 0;
  tt_status st = tt__user_version(db, &version);
  if (st != TT_OK) return st;
  if (version < 0)
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "tuning database %s: schema version %d (PRAGMA "
                        "user_version) is not a tunetrace tuning database's (1..%d)",
                        db->path, version, TT_TUNEDB_SCHEMA_VERSION);
  if (version > TT_TUNEDB_SCHEMA_VERSION)
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "tuning database %s: schema version %d is newer "
                        "than this build reads (%d)",
                        db->path, version, TT_TUNEDB_SCHEMA_VERSION);
  char tables[512], missing[512];
  int has_samples;
  if ((st = tt__tables(db, tables, sizeof tables, &has_samples)) != TT_OK) return st;
  if (version == 0 && tables[0])
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "tuning database %s: not a tunetrace tuning "
                        "database (schema version 0 and the tables %s): left as it is",
                        db->path, tables);
  if (version > 0 && !has_samples)
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "tuning database %s: not a tunetrace tuning "
                        "database (schema version %d without the table samples; tables: %s)",
                        db->path, version, tables[0] ? tables : "none");
  if (version > 0) {
    if ((st = tt__missing_columns(db, version, missing, sizeof missing)) != TT_OK) return st;
    if (missing[0])
      return tt_set_error(TT_ERR_UNSUPPORTED,
                          "tuning database %s: not a tunetrace tuning "
                          "database (its table samples lacks the columns %s of schema "
                          "version %d)",
                          db->path, missing, version);
  }
  db->version = version;
  return TT_OK;
}

/* PRAGMA quick_check: a damaged file is refused before it is read or written. */
static tt_status tt__quick_check(tt_tunedb *db) {
  sqlite3_stmt *st = NULL;
  if (sqlite3_prepare_v2(db->sql, "PRAGMA quick_check(1)", -1, &st, NULL) != SQLITE_OK)
    return tt__sql_error(db, db->sql, "checking the file (PRAGMA quick_check)");
  int rc = sqlite3_step(st);
  const char *r = rc == SQLITE_ROW ? (const char *)sqlite3_column_text(st, 0) : NULL;
  tt_status status = TT_OK;
  if (rc != SQLITE_ROW)
    status = tt__sql_error(db, db->sql, "checking the file (PRAGMA quick_check)");
  else if (!r || strcmp(r, "ok")) {
    /* SQLite's report on one line, without its "*** in database main ***" heading */
    char what[512];
    snprintf(what, sizeof what, "%s", r ? r : "no answer");
    const char *head = "*** in database main ***\n";
    char *w = !strncmp(what, head, strlen(head)) ? what + strlen(head) : what;
    for (char *p = w; *p; p++)
      if (*p == '\n') *p = ';';
    status = tt_set_error(TT_ERR_IO,
                          "tuning database %s: the file is damaged (PRAGMA "
                          "quick_check: %s); restore it from a copy, or give another file",
                          db->path, w);
  }
  sqlite3_finalize(st);
  return status;
}

/* Creates the schema or upgrades an older one, in one transaction that re-reads the version
 * (two processes opening a new or old file at once: the second finds the work done). */
static tt_status tt__upgrade(tt_tunedb *db) {
  if (tt__exec(db, "BEGIN IMMEDIATE", "upgrading the schema")) return TT_ERR_IO;
  /* another process may have created or upgraded the file since it was checked */
  tt_status st = tt__check_schema(db);
  if (st != TT_OK) return st;
  int version = db->version;
  if (version < 1 && tt__exec(db, tt__schema_v1, "creating the schema")) return TT_ERR_IO;
  if (version < 2 && tt__exec(db, tt__schema_v2, "upgrading the schema to version 2"))
    return TT_ERR_IO;
  if (version < TT_TUNEDB_SCHEMA_VERSION) {
    char sql[64];
    snprintf(sql, sizeof sql, "PRAGMA user_version=%d", TT_TUNEDB_SCHEMA_VERSION);
    if (tt__exec(db, sql, "upgrading the schema")) return TT_ERR_IO;
  }
  if (tt__exec(db, "COMMIT", "upgrading the schema")) return TT_ERR_IO;
  db->version = TT_TUNEDB_SCHEMA_VERSION;
  return TT_OK;
}

void tt_tunedb_close(tt_tunedb *db) {
  if (!db) return;
  sqlite3_finalize(db->insert);
  sqlite3_finalize(db->lookup);
  sqlite3_close(db->sql);
  free(db->path);
  free(db);
}

/* A handle for `path` with its path copied; NULL with the error set. */
static tt_tunedb *tt__tunedb_new(const char *path) {
  tt_tunedb *db = calloc(1, sizeof *db);
  if (db) db->path = malloc(strlen(path) + 1);
  if (!db || !db->path) {
    free(db);
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_tunedb_open: out of memory");
    return NULL;
  }
  strcpy(db->path, path);
  return db;
}

/* An existing file must be a regular file (a FIFO would block SQLite's first read). 1 if
 * it exists, 0 if not, -1 with the error set. */
static int tt__db_file(const char *path, int must_exist) {
  struct stat st;
  char why[256];
  int fd = tt__open_regular_fd(path, &st, why, sizeof why);
  if (fd >= 0) {
    close(fd);
    return 1;
  }
  if (errno == ENOENT && !must_exist && lstat(path, &st) != 0) return 0;
  tt_set_error(TT_ERR_IO, "tuning database %s: cannot open: %s", path, why);
  return -1;
}

/* Prepares the statements a handle uses (the insert only when writable). */
static int tt__prepare(tt_tunedb *db) {
  char sql[1024];
  snprintf(sql, sizeof sql,
           "INSERT INTO samples (%s) VALUES (NULL, ?, ?, ?, ?, ?, ?, ?, ?, ?,"
           " ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
           tt__columns);
  if ((!db->read_only && sqlite3_prepare_v2(db->sql, sql, -1, &db->insert, NULL) != SQLITE_OK) ||
      sqlite3_prepare_v2(db->sql, tt__lookup_sql, -1, &db->lookup, NULL) != SQLITE_OK) {
    tt__sql_error(db, db->sql, "preparing statements");
    return -1;
  }
  return 0;
}

tt_status tt_tunedb_open(const char *path, tt_tunedb **out) {
  if (!path || !*path || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tunedb_open: path and out are required");
  *out = NULL;
  int exists = tt__db_file(path, 0);
  if (exists < 0) return TT_ERR_IO;
  tt_tunedb *db = tt__tunedb_new(path);
  if (!db) return TT_ERR_OUT_OF_MEMORY;
  if (!exists) tt__make_parent_dirs(path);
  if (sqlite3_open_v2(path, &db->sql, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, NULL) !=
      SQLITE_OK) {
    tt__sql_error(db, db->sql, "cannot open");
    tt_tunedb_close(db);
    return TT_ERR_IO;
  }
  /* several hosts may tune into one file: wait for a writer instead of failing. A write
   * holds the lock for one small insert, but on a loaded machine a checkpoint can take
   * seconds: a minute before "database is locked" (host/tests/tune_concurrency.py). */
  sqlite3_busy_timeout(db->sql, 60000);
  /* nothing is written before the file is known to be ours (or empty) and undamaged */
  tt_status st = tt__check_schema(db);
  if (st == TT_OK && exists) st = tt__quick_check(db);
  if (st != TT_OK) {
    tt_tunedb_close(db);
    return st;
  }
  /* WAL: readers never block the loop; synchronous=NORMAL keeps every commit across a
   * process kill (only a power loss can drop the last transactions) */
  if (tt__exec(db, "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;", "enabling WAL")) {
    tt_tunedb_close(db);
    return TT_ERR_IO;
  }
  if (db->version < TT_TUNEDB_SCHEMA_VERSION && (st = tt__upgrade(db)) != TT_OK) {
    char why[1024];
    snprintf(why, sizeof why, "%s", tt_last_error());
    sqlite3_exec(db->sql, "ROLLBACK", NULL, NULL, NULL);
    tt_tunedb_close(db);
    return tt_set_error(st, "%s", why);
  }
  if (tt__prepare(db)) {
    tt_tunedb_close(db);
    return TT_ERR_IO;
  }
  *out = db;
  return TT_OK;
}

tt_status tt_tunedb_open_readonly(const char *path, tt_tunedb **out) {
  if (!path || !*path || !out)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_tunedb_open_readonly: path and out are required");
  *out = NULL;
  if (tt__db_file(path, 1) < 0) return TT_ERR_IO;
  tt_tunedb *db = tt__tunedb_new(path);
  if (!db) return TT_ERR_OUT_OF_MEMORY;
  db->read_only = 1;
  if (sqlite3_open_v2(path, &db->sql, SQLITE_OPEN_READONLY, NULL) != SQLITE_OK) {
    tt__sql_error(db, db->sql, "cannot open");
    tt_tunedb_close(db);
    return TT_ERR_IO;
  }
  sqlite3_busy_timeout(db->sql, 60000);
  tt_status st = tt__check_schema(db);
  if (st == TT_OK) st = tt__quick_check(db);
  if (st != TT_OK) {
    tt_tunedb_close(db);
    return st;
  }
  if (db->version == 0) {
    tt_tunedb_close(db);
    return tt_set_error(TT_ERR_UNSUPPORTED,
                        "tuning database %s: empty (no schema, no rows): "
                        "not a tunetrace tuning database yet",
                        path);
  }
  if (tt__prepare(db)) {
    tt_tunedb_close(db);
    return TT_ERR_IO;
  }
  *out = db;
  return TT_OK;
}

int tt_tunedb_read_only(const tt_tunedb *db) { return db ? db->read_only : 0; }

uint64_t tt_tunedb_bad_rows(const tt_tunedb *db) { return db ? db->bad_rows : 0; }

const char *tt_tunedb_path(const tt_tunedb *db) { return db ? db->path : NULL; }

/* Binds a string or NULL. */
static void tt__bind_text(sqlite3_stmt *st, int i, const char *s) {
  if (s) sqlite3_bind_text(st, i, s, -1, SQLITE_TRANSIENT);
  else sqlite3_bind_null(st, i);
}

/* Indicators as a JSON object {"meshes": 3, ...}; NULL if the row has none. */
static char *tt__indicators_json(const tt_tunedb_row *row) {
  if (!row->has_indicators) return NULL;
  size_t cap = 64 + TT_SCENE_INDICATOR_COUNT * 64;
  char *s = malloc(cap);
  if (!s) return NULL;
  size_t n = 0;
  s[n++] = '{';
  for (uint32_t i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) {
    double v = row->indicators[i];
    /* JSON has no NaN/Inf: an undefined indicator (e.g. variance of one mesh) is null */
    if (isfinite(v))
      n += snprintf(s + n, cap - n, "%s\"%s\":%.17g", i ? "," : "", tt_scene_indicator_name(i), v);
    else n += snprintf(s + n, cap - n, "%s\"%s\":null", i ? "," : "", tt_scene_indicator_name(i));
  }
  snprintf(s + n, cap - n, "}");
  return s;
}

/* Current UTC time as ISO 8601 with milliseconds. */
static void tt__now_iso(char *buf, size_t n) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  struct tm tm;
  gmtime_r(&ts.tv_sec, &tm);
  char base[32];
  strftime(base, sizeof base, "%Y-%m-%dT%H:%M:%S", &tm);
  snprintf(buf, n, "%s.%03ldZ", base, ts.tv_nsec / 1000000L);
}

/* `row` as the caller built it, with the fields of schema 2 its struct_size does not cover
 * absent and the machine, cpu, host and timestamp (`now`) of this process where NULL. */
static tt_tunedb_row tt__complete_row(const tt_tunedb_row *row, const char *now) {
  tt_tunedb_row r;
  memset(&r, 0, sizeof r);
  memcpy(&r, row, offsetof(tt_tunedb_row, host));
  r.struct_size = sizeof r;
  if (TT__ROW_HAS(row, host)) r.host = row->host;
  if (TT__ROW_HAS(row, rank)) {
    r.has_rank = row->has_rank;
    r.rank = row->rank;
  }
  if (!r.machine) r.machine = tt_tunedb_machine_id();
  if (!r.cpu) r.cpu = tt_tunedb_cpu_model();
  if (!r.host) r.host = tt_tunedb_host_name();
  if (!r.timestamp) r.timestamp = now;
  return r;
}

tt_status tt_tunedb_record(tt_tunedb *db, tt_tunedb_row *caller_row) {
  tt_tunedb_row *row = caller_row;
  if (!db || !row || !row->scene_id || !row->plugin || !row->plugin_version || !row->config ||
      !row->objective)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_tunedb_record: scene_id, plugin, "
                        "plugin_version, config and objective are required");
  if (!isfinite(row->cost) || !isfinite(row->build_ms) || !isfinite(row->render_ms))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tunedb_record: cost and times must be "
                                                 "finite (use TT_COST_INFEASIBLE for failures)");
  if (db->read_only)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tuning database %s: opened read-only: "
                        "nothing can be recorded",
                        db->path);
  char now[64];
  tt__now_iso(now, sizeof now);
  tt_tunedb_row full = tt__complete_row(row, now);
  row = &full;
  char *ind = tt__indicators_json(row);
  sqlite3_stmt *st = db->insert;
  sqlite3_reset(st);
  sqlite3_clear_bindings(st);
  int i = 1;
  tt__bind_text(st, i++, row->scene_id);
  tt__bind_text(st, i++, row->scene);
  tt__bind_text(st, i++, row->camera ? row->camera : "{}");
  tt__bind_text(st, i++, row->context ? row->context : "{}");
  tt__bind_text(st, i++, ind);
  tt__bind_text(st, i++, row->plugin);
  tt__bind_text(st, i++, row->plugin_version);
  tt__bind_text(st, i++, row->config);
  tt__bind_text(st, i++, row->objective);
  sqlite3_bind_double(st, i++, row->build_ms);
  sqlite3_bind_double(st, i++, row->render_ms);
  sqlite3_bind_double(st, i++, row->cost);
  sqlite3_bind_int(st, i++, row->status);
  tt__bind_text(st, i++, row->mode);
  sqlite3_bind_int(st, i++, row->iteration);
  tt__bind_text(st, i++, row->run_id);
  tt__bind_text(st, i++, row->tuner);
  tt__bind_text(st, i++, row->metrics);
  tt__bind_text(st, i++, row->machine);
  tt__bind_text(st, i++, row->cpu);
  tt__bind_text(st, i++, row->timestamp);
  tt__bind_text(st, i++, row->host);
  if (row->has_rank) sqlite3_bind_int(st, i++, row->rank);
  else sqlite3_bind_null(st, i++);
  /* autocommit: the insert is its own transaction, durable when step returns */
  int rc = sqlite3_step(st);
  free(ind);
  sqlite3_reset(st);
  if (rc != SQLITE_DONE) return tt__sql_error(db, db->sql, "recording a measurement");
  caller_row->id = sqlite3_last_insert_rowid(db->sql);
  return TT_OK;
}

tt_status tt_tunedb_lookup(tt_tunedb *db, const tt_tunedb_row *key, double *cost, uint32_t *count) {
  if (!db || !key || !key->scene_id || !key->plugin || !key->plugin_version || !key->config ||
      !key->objective)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_tunedb_lookup: scene_id, plugin, "
                        "plugin_version, config and objective are required");
  sqlite3_stmt *st = db->lookup;
  sqlite3_reset(st);
  sqlite3_clear_bindings(st);
  tt__bind_text(st, 1, key->scene_id);
  tt__bind_text(st, 2, key->camera ? key->camera : "{}");
  tt__bind_text(st, 3, key->context ? key->context : "{}");
  tt__bind_text(st, 4, key->plugin);
  tt__bind_text(st, 5, key->plugin_version);
  tt__bind_text(st, 6, key->config);
  tt__bind_text(st, 7, key->objective);
  tt__bind_text(st, 8, key->machine ? key->machine : tt_tunedb_machine_id());
  tt__bind_text(st, 9, key->cpu ? key->cpu : tt_tunedb_cpu_model());
  int rc = sqlite3_step(st);
  if (rc != SQLITE_ROW) {
    sqlite3_reset(st);
    return tt__sql_error(db, db->sql, "looking up a configuration");
  }
  int64_t n = sqlite3_column_int64(st, 1);
  double mean = sqlite3_column_double(st, 0);
  sqlite3_reset(st);
  if (n <= 0) return TT_ERR_NO_DATA;
  if (cost) *cost = mean;
  if (count) *count = (uint32_t)n;
  return TT_OK;
}

/* What an SQLite value is, for messages. */
static const char *tt__type_name(int type) {
  switch (type) {
  case SQLITE_INTEGER: return "an integer";
  case SQLITE_FLOAT: return "a real";
  case SQLITE_TEXT: return "text";
  case SQLITE_BLOB: return "a blob";
  default: return "NULL";
  }
}

/* Parses the indicators column (the JSON object tt__indicators_json writes) into out[]: every
 * indicator a number, null or absent (NaN: unknown, or one added after the row was written).
 * 0, or -1 with the reason in `why`. */
static int tt__indicators_parse(const char *json, double *out, char *why, size_t n) {
  cJSON *o = cJSON_Parse(json);
  if (!cJSON_IsObject(o)) {
    snprintf(why, n, "indicators is not a JSON object");
    cJSON_Delete(o);
    return -1;
  }
  int rc = 0;
  for (uint32_t i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, tt_scene_indicator_name(i));
    if (cJSON_IsNumber(v)) {
      out[i] = v->valuedouble;
    } else if (!v || cJSON_IsNull(v)) {
      out[i] = NAN;
    } else {
      snprintf(why, n, "indicators.%s is not a number", tt_scene_indicator_name(i));
      rc = -1;
      break;
    }
  }
  cJSON_Delete(o);
  return rc;
}

/* The columns of tt__columns, in order, and what each must hold. */
enum { TT__TEXT, TT__TEXT_OR_NULL, TT__NUMBER, TT__INT, TT__INT_OR_NULL, TT__ID, TT__JSON };
static const struct {
  const char *name;
  int kind;
} tt__column_kinds[] = {{"id", TT__ID},
                        {"scene_id", TT__TEXT},
                        {"scene", TT__TEXT_OR_NULL},
                        {"camera", TT__TEXT},
                        {"context", TT__TEXT},
                        {"indicators", TT__JSON},
                        {"plugin", TT__TEXT},
                        {"plugin_version", TT__TEXT},
                        {"config", TT__TEXT},
                        {"objective", TT__TEXT},
                        {"build_ms", TT__NUMBER},
                        {"render_ms", TT__NUMBER},
                        {"cost", TT__NUMBER},
                        {"status", TT__INT},
                        {"mode", TT__TEXT_OR_NULL},
                        {"iteration", TT__INT_OR_NULL},
                        {"run_id", TT__TEXT_OR_NULL},
                        {"tuner", TT__TEXT_OR_NULL},
                        {"metrics", TT__TEXT_OR_NULL},
                        {"machine", TT__TEXT},
                        {"cpu", TT__TEXT},
                        {"timestamp", TT__TEXT},
                        {"host", TT__TEXT_OR_NULL},
                        {"rank", TT__INT_OR_NULL}};
#define TT__NCOLUMNS (sizeof tt__column_kinds / sizeof tt__column_kinds[0])

/* Checks the current result row of a SELECT of tt__columns against the schema (types, a
 * finite cost and times, a known status, 32-bit integers, the indicators' JSON): 0, or -1
 * with what is wrong in `why`. Rows another program wrote into the file may be anything. */
static int tt__check_row(sqlite3_stmt *st, char *why, size_t n) {
  for (int i = 0; i < (int)TT__NCOLUMNS; i++) {
    int type = sqlite3_column_type(st, i), kind = tt__column_kinds[i].kind;
    const char *name = tt__column_kinds[i].name;
    int ok = 1;
    switch (kind) {
    case TT__ID: ok = type == SQLITE_INTEGER; break;
    case TT__TEXT: ok = type == SQLITE_TEXT; break;
    case TT__TEXT_OR_NULL: ok = type == SQLITE_TEXT || type == SQLITE_NULL; break;
    case TT__JSON: ok = type == SQLITE_TEXT || type == SQLITE_NULL; break;
    case TT__NUMBER: ok = type == SQLITE_INTEGER || type == SQLITE_FLOAT; break;
    case TT__INT: ok = type == SQLITE_INTEGER; break;
    case TT__INT_OR_NULL: ok = type == SQLITE_INTEGER || type == SQLITE_NULL; break;
    }
    if (!ok) {
      snprintf(why, n, "%s is %s, not %s", name, tt__type_name(type),
               kind == TT__NUMBER                                             ? "a number"
               : kind == TT__INT || kind == TT__INT_OR_NULL || kind == TT__ID ? "an integer"
               : kind == TT__JSON                                             ? "JSON text"
                                                                              : "text");
      return -1;
    }
    if (kind == TT__NUMBER && !isfinite(sqlite3_column_double(st, i))) {
      snprintf(why, n, "%s is not finite", name);
      return -1;
    }
    if ((kind == TT__INT || kind == TT__INT_OR_NULL) && type == SQLITE_INTEGER) {
      sqlite3_int64 v = sqlite3_column_int64(st, i);
      if (v < INT32_MIN || v > INT32_MAX) {
        snprintf(why, n, "%s %lld is out of the 32-bit range", name, (long long)v);
        return -1;
      }
      if (!strcmp(name, "status") && (v < TT_TUNEDB_OK || v > TT_TUNEDB_FAILED)) {
        snprintf(why, n, "status %lld is not 0 (ok), 1 (infeasible) or 2 (failed)", (long long)v);
        return -1;
      }
    }
  }
  return 0;
}

/* Fills `row` from the current result row of a SELECT of tt__columns, checked first
 * (tt__check_row): 0, or -1 with what is wrong in `why`. */
static int tt__read_row(sqlite3_stmt *st, tt_tunedb_row *row, char *why, size_t n) {
  memset(row, 0, sizeof *row);
  row->struct_size = sizeof *row;
  if (tt__check_row(st, why, n)) return -1;
  int i = 0;
  row->id = sqlite3_column_int64(st, i++);
  row->scene_id = (const char *)sqlite3_column_text(st, i++);
  row->scene = (const char *)sqlite3_column_text(st, i++);
  row->camera = (const char *)sqlite3_column_text(st, i++);
  row->context = (const char *)sqlite3_column_text(st, i++);
  const char *ind = (const char *)sqlite3_column_text(st, i++);
  if (ind && tt__indicators_parse(ind, row->indicators, why, n)) return -1;
  row->has_indicators = ind != NULL;
  row->plugin = (const char *)sqlite3_column_text(st, i++);
  row->plugin_version = (const char *)sqlite3_column_text(st, i++);
  row->config = (const char *)sqlite3_column_text(st, i++);
  row->objective = (const char *)sqlite3_column_text(st, i++);
  row->build_ms = sqlite3_column_double(st, i++);
  row->render_ms = sqlite3_column_double(st, i++);
  row->cost = sqlite3_column_double(st, i++);
  row->status = sqlite3_column_int(st, i++);
  row->mode = (const char *)sqlite3_column_text(st, i++);
  row->iteration = sqlite3_column_int(st, i++);
  row->run_id = (const char *)sqlite3_column_text(st, i++);
  row->tuner = (const char *)sqlite3_column_text(st, i++);
  row->metrics = (const char *)sqlite3_column_text(st, i++);
  row->machine = (const char *)sqlite3_column_text(st, i++);
  row->cpu = (const char *)sqlite3_column_text(st, i++);
  row->timestamp = (const char *)sqlite3_column_text(st, i++);
  row->host = (const char *)sqlite3_column_text(st, i++);
  row->has_rank = sqlite3_column_type(st, i) != SQLITE_NULL;
  row->rank = sqlite3_column_int(st, i++);
  return 0;
}

tt_status tt_tunedb_foreach(tt_tunedb *db, const char *plugin,
                            int (*fn)(void *user, const tt_tunedb_row *row), void *user) {
  if (!db || !fn) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tunedb_foreach: db and fn");
  db->bad_rows = 0;
  char sql[1024];
  /* a file of schema 1 opened read-only is not upgraded: its rows have no host and rank */
  snprintf(sql, sizeof sql, "SELECT %.*s%s FROM samples%s ORDER BY id",
           (int)(sizeof tt__columns - 1 - (db->version < 2 ? strlen(", host, rank") : 0)),
           tt__columns, db->version < 2 ? ", NULL, NULL" : "", plugin ? " WHERE plugin = ?1" : "");
  sqlite3_stmt *st = NULL;
  if (sqlite3_prepare_v2(db->sql, sql, -1, &st, NULL) != SQLITE_OK)
    return tt__sql_error(db, db->sql, "reading rows");
  if (plugin) tt__bind_text(st, 1, plugin);
  int rc;
  uint64_t bad = 0;
  long long first_bad = 0;
  char why[256], first_why[256] = "";
  while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
    tt_tunedb_row row;
    if (tt__read_row(st, &row, why, sizeof why)) {
      /* a row that is not one of the schema is skipped, never passed on as garbage */
      if (!bad++) {
        first_bad = sqlite3_column_int64(st, 0);
        snprintf(first_why, sizeof first_why, "%s", why);
      }
      continue;
    }
    if (fn(user, &row)) {
      rc = SQLITE_DONE;
      break;
    }
  }
  tt_status status = rc == SQLITE_DONE ? TT_OK : tt__sql_error(db, db->sql, "reading rows");
  sqlite3_finalize(st);
  db->bad_rows = bad;
  if (bad)
    tt__log(TT_LOG_WARN,
            "tuning database %s: %llu row%s skipped, not rows of its schema (the "
            "first, id %lld: %s)",
            db->path, (unsigned long long)bad, bad == 1 ? "" : "s", first_bad, first_why);
  return status;
}

tt_status tt_tunedb_count(tt_tunedb *db, const char *plugin, uint64_t *count) {
  if (!db || !count) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tunedb_count: db, count");
  sqlite3_stmt *st = NULL;
  const char *sql =
      plugin ? "SELECT count(*) FROM samples WHERE plugin = ?1" : "SELECT count(*) FROM samples";
  if (sqlite3_prepare_v2(db->sql, sql, -1, &st, NULL) != SQLITE_OK)
    return tt__sql_error(db, db->sql, "counting rows");
  if (plugin) tt__bind_text(st, 1, plugin);
  tt_status status = TT_OK;
  if (sqlite3_step(st) == SQLITE_ROW) *count = (uint64_t)sqlite3_column_int64(st, 0);
  else status = tt__sql_error(db, db->sql, "counting rows");
  sqlite3_finalize(st);
  return status;
}

/* Writes one CSV field, quoted when it holds a comma, quote or line break (RFC 4180). */
static void tt__csv_text(FILE *f, const char *s) {
  if (!s) return;
  if (!strpbrk(s, ",\"\r\n")) {
    fputs(s, f);
    return;
  }
  fputc('"', f);
  for (; *s; s++) {
    if (*s == '"') fputc('"', f);
    fputc(*s, f);
  }
  fputc('"', f);
}

typedef struct tt__csv_ctx {
  FILE *f;
} tt__csv_ctx;

/* One CSV line per row; doubles with %.17g so the export round-trips. */
static int tt__csv_row(void *user, const tt_tunedb_row *r) {
  FILE *f = ((tt__csv_ctx *)user)->f;
  static const char *status_names[] = {"ok", "infeasible", "failed"};
  fprintf(f, "%lld,", (long long)r->id);
  const char *texts[] = {r->scene_id, r->scene,          r->camera, r->context,
                         r->plugin,   r->plugin_version, r->config, r->objective};
  for (size_t i = 0; i < sizeof texts / sizeof texts[0]; i++) {
    tt__csv_text(f, texts[i]);
    fputc(',', f);
  }
  fprintf(f, "%.17g,%.17g,%.17g,%s,", r->build_ms, r->render_ms, r->cost,
          r->status >= 0 && r->status <= 2 ? status_names[r->status] : "unknown");
  tt__csv_text(f, r->mode);
  fprintf(f, ",%d,", r->iteration);
  tt__csv_text(f, r->run_id);
  fputc(',', f);
  tt__csv_text(f, r->tuner);
  fputc(',', f);
  tt__csv_text(f, r->metrics);
  fputc(',', f);
  tt__csv_text(f, r->machine);
  fputc(',', f);
  tt__csv_text(f, r->cpu);
  fputc(',', f);
  tt__csv_text(f, r->timestamp);
  fputc(',', f);
  tt__csv_text(f, r->host);
  fputc(',', f);
  if (r->has_rank) fprintf(f, "%d", r->rank);
  for (uint32_t i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) {
    fputc(',', f);
    if (r->has_indicators && isfinite(r->indicators[i])) fprintf(f, "%.17g", r->indicators[i]);
  }
  fputc('\n', f);
  return 0;
}

tt_status tt_tunedb_export_csv(tt_tunedb *db, const char *path) {
  if (!db || !path) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tunedb_export_csv: db, path");
  if (tt_file_check_not_input(path, "CSV export", db->path, "tuning database") != TT_OK)
    return TT_ERR_INVALID_ARGUMENT;
  tt_atomic_file *af;
  if (tt_atomic_file_open(path, &af) != TT_OK) return TT_ERR_IO;
  FILE *f = tt_atomic_file_stream(af);
  fputs("id,scene_id,scene,camera,context,plugin,plugin_version,config,objective,build_ms,"
        "render_ms,cost,status,mode,iteration,run_id,tuner,metrics,machine,cpu,timestamp,host,rank",
        f);
  for (uint32_t i = 0; i < TT_SCENE_INDICATOR_COUNT; i++)
    fprintf(f, ",ind_%s", tt_scene_indicator_name(i));
  fputc('\n', f);
  tt__csv_ctx ctx = {f};
  tt_status st = tt_tunedb_foreach(db, NULL, tt__csv_row, &ctx);
  if (st != TT_OK) {
    char why[1024];
    snprintf(why, sizeof why, "%s", tt_last_error());
    tt_atomic_file_abort(af);
    return tt_set_error(st, "%s", why);
  }
  return tt_atomic_file_commit(af); /* the previous export stays if this one fails */
}

/* ---- merging (issue 18) ---- */

/* The samples columns (without id) in the order of tt__columns. */
static const char *const tt__merge_columns[] = {
    "scene_id",       "scene",  "camera",    "context",  "indicators", "plugin",
    "plugin_version", "config", "objective", "build_ms", "render_ms",  "cost",
    "status",         "mode",   "iteration", "run_id",   "tuner",      "metrics",
    "machine",        "cpu",    "timestamp", "host",     "rank"};

#define TT__MERGE_NCOL (sizeof tt__merge_columns / sizeof tt__merge_columns[0])

/* has[i] = 1 where the attached schema src's table samples has tt__merge_columns[i]; the
 * number of its columns (0: no table samples), -1 on error. One query for all. */
static int tt__src_columns(tt_tunedb *db, int has[TT__MERGE_NCOL]) {
  sqlite3_stmt *st = NULL;
  memset(has, 0, TT__MERGE_NCOL * sizeof *has);
  if (sqlite3_prepare_v2(db->sql, "SELECT name FROM pragma_table_info('samples', 'src')", -1, &st,
                         NULL) != SQLITE_OK)
    return -1;
  int n = 0, rc;
  while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
    const char *name = (const char *)sqlite3_column_text(st, 0);
    n++;
    for (size_t i = 0; name && i < TT__MERGE_NCOL; i++)
      if (!strcmp(name, tt__merge_columns[i])) has[i] = 1;
  }
  sqlite3_finalize(st);
  return rc == SQLITE_DONE ? n : -1;
}

tt_status tt_tunedb_merged(tt_tunedb *db, const char *tag, int *merged) {
  if (!db || !tag || !merged)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tunedb_merged: db, tag, merged");
  sqlite3_stmt *st = NULL;
  if (sqlite3_prepare_v2(db->sql, "SELECT count(*) FROM merges WHERE tag = ?1", -1, &st, NULL) !=
      SQLITE_OK)
    return tt__sql_error(db, db->sql, "reading the merged tags");
  tt__bind_text(st, 1, tag);
  int rc = sqlite3_step(st);
  *merged = rc == SQLITE_ROW && sqlite3_column_int(st, 0) > 0;
  sqlite3_finalize(st);
  return rc == SQLITE_ROW ? TT_OK : tt__sql_error(db, db->sql, "reading the merged tags");
}

/* The copy of tt_tunedb_merge inside its transaction; *rows = rows copied. */
static tt_status tt__merge_rows(tt_tunedb *db, const char *source, int32_t rank, uint64_t *rows) {
  int version = -1;
  sqlite3_stmt *st = NULL;
  if (sqlite3_prepare_v2(db->sql, "PRAGMA src.user_version", -1, &st, NULL) == SQLITE_OK &&
      sqlite3_step(st) == SQLITE_ROW)
    version = sqlite3_column_int(st, 0);
  sqlite3_finalize(st);
  int has[TT__MERGE_NCOL];
  int ncols = tt__src_columns(db, has);
  if (ncols < 0) return tt__sql_error(db, db->sql, "reading the columns of the merged file");
  int has_samples = ncols > 0 && has[7]; /* config */
  if (version < 1 || version > TT_TUNEDB_SCHEMA_VERSION || !has_samples)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_tunedb_merge: %s is not a tuning database "
                        "of schema 1..%d (user_version %d%s)",
                        source, TT_TUNEDB_SCHEMA_VERSION, version,
                        has_samples ? "" : ", no table samples");
  char sql[2048];
  size_t n = (size_t)snprintf(sql, sizeof sql, "INSERT INTO main.samples (");
  const size_t ncol = TT__MERGE_NCOL;
  for (size_t i = 0; i < ncol; i++)
    n += (size_t)snprintf(sql + n, sizeof sql - n, "%s%s", i ? ", " : "", tt__merge_columns[i]);
  n += (size_t)snprintf(sql + n, sizeof sql - n, ") SELECT ");
  for (size_t i = 0; i < ncol; i++) {
    const char *c = tt__merge_columns[i];
    const char *expr = !strcmp(c, "rank") && rank >= 0 ? "?1" : has[i] ? c : "NULL";
    n += (size_t)snprintf(sql + n, sizeof sql - n, "%s%s", i ? ", " : "", expr);
  }
  snprintf(sql + n, sizeof sql - n, " FROM src.samples ORDER BY id");
  if (sqlite3_prepare_v2(db->sql, sql, -1, &st, NULL) != SQLITE_OK)
    return tt__sql_error(db, db->sql, "preparing the merge");
  if (rank >= 0) sqlite3_bind_int(st, 1, rank);
  int rc = sqlite3_step(st);
  sqlite3_finalize(st);
  if (rc != SQLITE_DONE) return tt__sql_error(db, db->sql, "copying the merged rows");
  *rows = (uint64_t)sqlite3_changes(db->sql);
  return TT_OK;
}

tt_status tt_tunedb_merge(tt_tunedb *db, const char *source, const char *tag, int32_t rank,
                          const char *note, uint64_t *rows, int *already) {
  uint64_t copied = 0;
  if (rows) *rows = 0;
  if (already) *already = 0;
  if (!db || !tag || !tag[0])
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_tunedb_merge: db and a non-empty tag");
  if (db->read_only)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tuning database %s: opened read-only: "
                        "nothing can be merged into it",
                        db->path);
  if (source) {
    /* ATTACH would create a missing file and block on a FIFO */
    char why[256];
    if (tt__file_regular_reason(source, why, sizeof why) != 0)
      return tt_set_error(TT_ERR_IO, "tt_tunedb_merge: cannot read %s: %s", source, why);
    if (tt_file_same(source, db->path) == 1)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          "tt_tunedb_merge: %s is the database "
                          "merged into (%s)",
                          source, db->path);
  }
  if (source) {
    sqlite3_stmt *st = NULL;
    int rc = sqlite3_prepare_v2(db->sql, "ATTACH DATABASE ?1 AS src", -1, &st, NULL);
    if (rc == SQLITE_OK) {
      tt__bind_text(st, 1, source);
      rc = sqlite3_step(st) == SQLITE_DONE ? SQLITE_OK : SQLITE_ERROR;
    }
    sqlite3_finalize(st);
    if (rc != SQLITE_OK) return tt__sql_error(db, db->sql, "attaching the merged file");
  }
  tt_status status = TT_OK;
  int merged = 0;
  if (tt__exec(db, "BEGIN IMMEDIATE", "starting a merge")) {
    status = TT_ERR_IO;
  } else if ((status = tt_tunedb_merged(db, tag, &merged)) == TT_OK && !merged) {
    if (source) status = tt__merge_rows(db, source, rank, &copied);
    if (status == TT_OK) {
      char now[64];
      tt__now_iso(now, sizeof now);
      sqlite3_stmt *st = NULL;
      if (sqlite3_prepare_v2(db->sql,
                             "INSERT INTO merges (tag, rows, source, note, timestamp)"
                             " VALUES (?1, ?2, ?3, ?4, ?5)",
                             -1, &st, NULL) != SQLITE_OK) {
        status = tt__sql_error(db, db->sql, "recording a merge");
      } else {
        tt__bind_text(st, 1, tag);
        sqlite3_bind_int64(st, 2, (sqlite3_int64)copied);
        tt__bind_text(st, 3, source);
        tt__bind_text(st, 4, note);
        tt__bind_text(st, 5, now);
        if (sqlite3_step(st) != SQLITE_DONE)
          status = tt__sql_error(db, db->sql, "recording a merge");
        sqlite3_finalize(st);
      }
    }
  }
  if (status == TT_OK) {
    if (tt__exec(db, "COMMIT", "committing a merge")) status = TT_ERR_IO;
  }
  if (status != TT_OK) {
    char why[1024];
    snprintf(why, sizeof why, "%s", tt_last_error());
    sqlite3_exec(db->sql, "ROLLBACK", NULL, NULL, NULL);
    tt_set_error(status, "%s", why);
    copied = 0;
  }
  if (source) sqlite3_exec(db->sql, "DETACH DATABASE src", NULL, NULL, NULL);
  if (status == TT_OK) {
    if (rows) *rows = copied;
    if (already) *already = merged;
  }
  return status;
}
