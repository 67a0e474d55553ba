/* Test helper over SQLite for the tests that read a tuning database directly. */
#ifndef TT_TEST_SQLITE_H
#define TT_TEST_SQLITE_H

#include <sqlite3.h>
#include <stdio.h>

/* Runs one SQL query returning a single cell, as text, into buf (`null_text` for SQL NULL);
 * the database is opened read-only. Returns 1 when a row came back, else 0 (buf empty). */
static inline int tt_test_query1(const char *path, const char *sql, char *buf, size_t n,
                                 const char *null_text) {
  sqlite3 *db = NULL;
  sqlite3_stmt *st = NULL;
  int ok = 0;
  buf[0] = 0;
  if (sqlite3_open_v2(path, &db, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
      sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW) {
    const unsigned char *t = sqlite3_column_text(st, 0);
    snprintf(buf, n, "%s", t ? (const char *)t : null_text);
    ok = 1;
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
  return ok;
}

#endif /* TT_TEST_SQLITE_H */
