/* JSON error reporting shared by the JSON readers (params/params_json.c, io/scene_json.c):
 * one message shape "<source>: <JSON path>: <what was expected>, got <what was there>", the
 * description of a value, and the line and column of a syntax error. Internal to
 * libtunetrace. */
#ifndef TT_UTIL_JSON_ERROR_H
#define TT_UTIL_JSON_ERROR_H

#include <tunetrace/common.h>

#include <cjson/cJSON.h>

#include <stddef.h>

/* Records "<source>: <path>: <message>" (just "<source>: <message>" when `path` is NULL or
 * empty) as the last error; returns `status`. */
tt_status tt__json_error(tt_status status, const char *source, const char *path, const char *fmt,
                         ...) TT_PRINTF(4, 5);

/* How a value is described after "got": the two readers' wordings, which their users'
 * scripts and tests already match. */
typedef enum tt__json_style {
  TT__JSON_PARAMS = 0, /* the number 1.5, a string ("x"), an array */
  TT__JSON_SCENE = 1   /* 1.5, a string "x", an array of 3 elements */
} tt__json_style;

/* Describes `item` (NULL: "nothing") into `buf`; returns `buf`. */
const char *tt__json_describe(const cJSON *item, tt__json_style style, char *buf, size_t n);

/* Line and column (1-based, counted in bytes) of offset `at` in `text`. */
void tt__json_line_col(const char *text, size_t at, unsigned *line, unsigned *col);

#endif /* TT_UTIL_JSON_ERROR_H */
