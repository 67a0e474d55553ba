/* JSON helpers for tests that read the host's --stats records. */
#ifndef TT_JSON_UTIL_H
#define TT_JSON_UTIL_H

#include <cjson/cJSON.h>
#include <stdio.h>

/* Reads and parses a JSON file of up to 4 MiB (NULL on failure). Not reentrant. */
static cJSON *read_json(const char *path) {
  static char text[1 << 22];
  FILE *f = fopen(path, "r");
  if (!f) return NULL;
  size_t len = fread(text, 1, sizeof text - 1, f);
  text[len] = 0;
  fclose(f);
  return cJSON_Parse(text);
}

/* Number member `key` of `o` (NaN if absent). */
static inline double num(const cJSON *o, const char *key) {
  return cJSON_GetNumberValue(cJSON_GetObjectItem(o, key));
}

#endif
