/* host: the JSON files the jobs read (--measure, --states) and the JSON they print on stdout
 * (--measure, --predict). */
#include "host.h"

#include <cjson/cJSON.h>
#include <locale.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* Turns every number under `node` into raw text that reads back as the same double.
 * cJSON prints 15 significant digits whenever they read back within a relative DBL_EPSILON,
 * so two configurations one ulp apart (a tuner's arithmetic makes such pairs: distinct
 * configurations for the library and the database) would print as one, and a printed
 * configuration would not be the one measured. */
void tt__json_exact(cJSON *node) {
  for (cJSON *c = node ? node->child : NULL; c; c = c->next) {
    if (!cJSON_IsNumber(c)) {
      tt__json_exact(c);
      continue;
    }
    double v = c->valuedouble;
    if (!isfinite(v)) continue; /* cJSON writes null */
    char buf[64];
    for (int prec = 15; prec <= 17; prec++) {
      snprintf(buf, sizeof buf, "%.*g", prec, v);
      if (strtod(buf, NULL) == v) break;
    }
    /* JSON needs '.', whatever LC_NUMERIC the process selected */
    const char *dp = localeconv()->decimal_point;
    if (dp && dp[0] && dp[0] != '.')
      for (char *p = buf; *p; p++)
        if (*p == dp[0]) *p = '.';
    char *text = cJSON_malloc(strlen(buf) + 1);
    if (!text) continue; /* keeps cJSON's own form */
    strcpy(text, buf);
    if (c->valuestring) cJSON_free(c->valuestring);
    c->valuestring = text;
    c->type = cJSON_Raw | (c->type & cJSON_StringIsConst);
  }
}

cJSON *tt__json_parse_exact(const char *text) {
  cJSON *root = text ? cJSON_Parse(text) : NULL;
  tt__json_exact(root);
  return root;
}
