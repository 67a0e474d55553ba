/* libFuzzer: the tuning database reader on a corrupt or foreign SQLite file: open (schema
 * check, WAL), count, lookup, a full read of every row and the CSV export. */
#include <tunetrace/tunedb.h>

#include "fuzz_util.h"

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
  const char *path = fuzz_write("in.db", data, size);
  char wal[700], shm[700], csv[700];
  snprintf(wal, sizeof wal, "%s-wal", path);
  snprintf(shm, sizeof shm, "%s-shm", path);
  snprintf(csv, sizeof csv, "%s/out.csv", fuzz_dir());
  unlink(wal);
  unlink(shm);
  tt_tunedb *db = NULL;
  if (tt_tunedb_open(path, &db) == TT_OK) {
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
  unlink(wal);
  unlink(shm);
  return 0;
}
