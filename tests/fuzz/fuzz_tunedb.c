/* libFuzzer: the tuning database reader on a corrupt or foreign SQLite file: open (schema
 * check, WAL), count, lookup, a full read of every row and the CSV export.
 *
 * The file is an in-memory database: SQLite's memdb VFS under a shared name (a
 * "file:/NAME?vfs=memdb" URI, every connection of the process sees the same bytes), filled
 * through the VFS's own write. On a file in tmpfs each input cost open, WAL and shared-memory
 * files, unlinks and an fsync'd CSV, 45% of the time in the kernel (~100 executions/s at
 * load 14); the reader's SQL and checks are the same either way. Only SQLite's WAL file
 * handling, which the input does not reach (it is the main file alone), is left out. */
#include <tunetrace/tunedb.h>

#include "fuzz_util.h"

#include <fcntl.h>
#include <sqlite3.h>

static const char g_uri[] = "file:/tt_fuzz_tunedb?vfs=memdb";
static int g_cwd = -1;

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc, (void)argv;
  /* URI file names for every connection, the reader's too (it opens without SQLITE_OPEN_URI) */
  if (sqlite3_config(SQLITE_CONFIG_URI, 1) != SQLITE_OK) abort();
  g_cwd = open(".", O_RDONLY | O_DIRECTORY);
  if (g_cwd < 0) abort();
  return 0;
}

/* Opens the shared in-memory database holding `data`; the returned connection keeps it
 * alive until it is closed (the last connection frees it). */
static sqlite3 *memdb_hold(const uint8_t *data, size_t size) {
  sqlite3 *h = NULL;
  sqlite3_file *f = NULL;
  if (sqlite3_open_v2(g_uri, &h, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_URI,
                      NULL) != SQLITE_OK ||
      sqlite3_file_control(h, "main", SQLITE_FCNTL_FILE_POINTER, &f) != SQLITE_OK || !f ||
      f->pMethods->xTruncate(f, 0) != SQLITE_OK ||
      (size && f->pMethods->xWrite(f, data, (int)size, 0) != SQLITE_OK))
    abort(); /* the harness's own set-up failed: stop loudly */
  return h;
}

static int visit(void *user, const tt_tunedb_row *row) {
  (void)user;
  /* read every field a reader uses */
  volatile size_t n = 0;
  if (row->scene_id) n += strlen(row->scene_id);
  if (row->config) n += strlen(row->config);
  if (row->plugin) n += strlen(row->plugin);
  (void)n;
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size > (1u << 30)) return 0;
  char csv[700];
  snprintf(csv, sizeof csv, "%s/out.csv", fuzz_dir());
  sqlite3 *hold = memdb_hold(data, size);
  tt_tunedb *db = NULL;
  /* tt_tunedb_open creates the parent folders of its path, here "file:": in the scratch
   * folder, not wherever the fuzzer runs */
  if (chdir(fuzz_dir()) != 0) abort();
  tt_status st = tt_tunedb_open(g_uri, &db);
  if (fchdir(g_cwd) != 0) abort();
  if (st == TT_OK) {
    uint64_t count = 0;
    tt_tunedb_count(db, NULL, &count);
    tt_tunedb_count(db, "accel_embree", &count);
    tt_tunedb_row key;
    memset(&key, 0, sizeof key);
    key.struct_size = sizeof key;
    key.scene_id = "0000000000000000";
    key.plugin = "accel_embree";
    key.plugin_version = "0.1.0";
    key.config = "{}";
    key.objective = "render";
    double cost;
    uint32_t n;
    tt_tunedb_lookup(db, &key, &cost, &n);
    tt_tunedb_foreach(db, NULL, visit, NULL);
    tt_tunedb_export_csv(db, csv);
    tt_tunedb_close(db);
  } else if (db) {
    abort();
  }
  sqlite3_close(hold);
  return 0;
}
