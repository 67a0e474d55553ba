/* JSON error reporting (json_error.h). */
#include "util/json_error.h"

#include <stdarg.h>
#include <stdio.h>

tt_status tt__json_error(tt_status status, const char *source, const char *path, const char *fmt,
                         ...) {
  char msg[1536];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (path && path[0]) return tt_set_error(status, "%s: %s: %s", source, path, msg);
  return tt_set_error(status, "%s: %s", source, msg);
}

const char *tt__json_describe(const cJSON *it, tt__json_style style, char *buf, size_t n) {
  int scene = style == TT__JSON_SCENE;
  if (!it) snprintf(buf, n, "nothing");
  else if (cJSON_IsNumber(it) && scene) snprintf(buf, n, "%g", it->valuedouble);
  else if (cJSON_IsNumber(it)) snprintf(buf, n, "the number %.17g", it->valuedouble);
  else if (cJSON_IsString(it) && scene) snprintf(buf, n, "a string \"%.60s\"", it->valuestring);
  else if (cJSON_IsString(it)) snprintf(buf, n, "a string (\"%.64s\")", it->valuestring);
  else if (cJSON_IsTrue(it)) snprintf(buf, n, "true");
  else if (cJSON_IsFalse(it)) snprintf(buf, n, "false");
  else if (cJSON_IsNull(it)) snprintf(buf, n, "null");
  else if (cJSON_IsArray(it) && scene)
    snprintf(buf, n, "an array of %d elements", cJSON_GetArraySize(it));
  else if (cJSON_IsArray(it)) snprintf(buf, n, "an array");
  else if (cJSON_IsObject(it)) snprintf(buf, n, "an object");
  else snprintf(buf, n, scene ? "an invalid value" : "an unknown JSON value");
  return buf;
}

void tt__json_line_col(const char *text, size_t at, unsigned *line, unsigned *col) {
  *line = 1;
  *col = 1;
  for (size_t i = 0; i < at && text[i]; i++) {
    if (text[i] == '\n') {
      (*line)++;
      *col = 1;
    } else {
      (*col)++;
    }
  }
}
