/* JSON helpers for tests that read the host's --stats records. */
#ifndef TT_JSON_UTIL_H
#define TT_JSON_UTIL_H

#include "tt_test.h"

#include <cjson/cJSON.h>

/* Reads and parses a JSON file (NULL when it cannot be read or parsed). */
static cJSON *read_json(const char *path) {
  char *text = tt_test_read_file(path, NULL);
  cJSON *root = text ? cJSON_Parse(text) : NULL;
  free(text);
  return root;
}

/* Number member `key` of `o` (NaN if absent). */
static inline double num(const cJSON *o, const char *key) {
  return cJSON_GetNumberValue(cJSON_GetObjectItem(o, key));
}

#endif
