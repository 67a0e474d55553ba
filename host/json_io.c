/* host: the JSON files the jobs read (--measure, --states) and the JSON they print on stdout
 * (--measure, --predict). */
#include "host.h"

#include <cjson/cJSON.h>
#include <stdio.h>

int tt__json_read(const char *option, const char *path, const char *what, cJSON **root) {
  char *text = NULL;
  size_t n = 0;
  *root = NULL;
  if (tt_file_read(path, what, 0, &text, &n) != TT_OK) {
    tt__say("%s %s\n", option, tt_last_error());
    return -1;
  }
  *root = cJSON_Parse(text);
  tt_free(text);
  return 0;
}

int tt__json_print(cJSON *root) {
  char *text = cJSON_Print(root);
  cJSON_Delete(root);
  int rc = !text || puts(text) < 0 || fflush(stdout) ? TT_EXIT_OUTPUT : TT_EXIT_OK;
  cJSON_free(text);
  return rc;
}
