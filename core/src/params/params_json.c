/* JSON form of parameter spaces (thesis Fig. 3.1 plus descriptions and constraints) and of
 * configurations ({"name": value, ...}), with errors that name the input, the JSON path and
 * what was expected. */
#include "params/params_internal.h"
#include "util/json_error.h"

#include <tunetrace/params.h>

#include <cjson/cJSON.h>

#include <inttypes.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Parses `json`, reporting syntax errors with line and column; NULL on error. */
static cJSON *tt__parse(const char *json, const char *source) {
  if (!json) {
    tt__json_error(TT_ERR_PARSE, source, NULL, "no JSON text (NULL)");
    return NULL;
  }
  const char *end = NULL;
  cJSON *root = cJSON_ParseWithOpts(json, &end, 1);
  if (!root) {
    const char *at = end ? end : json;
    unsigned line, col;
    tt__json_line_col(json, (size_t)(at - json), &line, &col);
    tt__json_error(TT_ERR_PARSE, source, NULL,
                   "invalid JSON at line %u, column %u (near \"%.20s\")", line, col, at);
  }
  return root;
}

/* Reads member `key` of `obj` as an exact integer into *out; path names obj. */
static int tt__get_int(const cJSON *obj, const char *key, const char *path, const char *source,
                       int64_t *out) {
  char p[256], got[128];
  snprintf(p, sizeof p, "%s.%s", path, key);
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!v) return tt__json_error(TT_ERR_PARSE, source, p, "missing (expected an integer)"), -1;
  double d = v->valuedouble;
  if (!cJSON_IsNumber(v) || !isfinite(d) || d != floor(d))
    return tt__json_error(TT_ERR_PARSE, source, p, "expected an integer, got %s",
                          tt__json_describe(v, TT__JSON_PARAMS, got, sizeof got)),
           -1;
  /* INT bounds are limited to +-2^53 (see tt_space_add_int); say so here, because
   * larger JSON integers have already been rounded by the parser. */
  if (fabs(d) > 0x1p53)
    return tt__json_error(TT_ERR_PARSE, source, p, "expected an integer within +-2^53, got %s",
                          tt__json_describe(v, TT__JSON_PARAMS, got, sizeof got)),
           -1;
  *out = (int64_t)d;
  return 0;
}

/* Reads member `key` of `obj` as a finite number into *out. */
static int tt__get_double(const cJSON *obj, const char *key, const char *path, const char *source,
                          double *out) {
  char p[256], got[128];
  snprintf(p, sizeof p, "%s.%s", path, key);
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!v) return tt__json_error(TT_ERR_PARSE, source, p, "missing (expected a number)"), -1;
  if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble))
    return tt__json_error(TT_ERR_PARSE, source, p, "expected a number, got %s",
                          tt__json_describe(v, TT__JSON_PARAMS, got, sizeof got)),
           -1;
  *out = v->valuedouble;
  return 0;
}

/* Kind of a possibleValues element: TT_VALUE_INT/BOOL/STRING, or 0 if none of those. */
static tt_value_kind tt__nom_kind_of(const cJSON *v) {
  if (cJSON_IsBool(v)) return TT_VALUE_BOOL;
  if (cJSON_IsString(v)) return TT_VALUE_STRING;
  if (cJSON_IsNumber(v)) {
    double d = v->valuedouble;
    if (isfinite(d) && d == floor(d) && d >= -0x1p63 && d < 0x1p63) return TT_VALUE_INT;
  }
  return (tt_value_kind)0;
}

/* Name of a NOM value kind, with article, for messages. */
static const char *tt__kind_name(tt_value_kind k) {
  switch (k) {
  case TT_VALUE_INT: return "an integer";
  case TT_VALUE_BOOL: return "a boolean";
  case TT_VALUE_STRING: return "a string";
  default: return "a number";
  }
}

/* Index of JSON value `v` among possibleValues `pv` (same kind), or -1. */
static int tt__nom_find(const cJSON *pv, const cJSON *v) {
  tt_value_kind kind = tt__nom_kind_of(cJSON_GetArrayItem(pv, 0));
  if (tt__nom_kind_of(v) != kind) return -1;
  int k = 0;
  for (const cJSON *e = pv->child; e; e = e->next, k++) {
    if (kind == TT_VALUE_STRING && strcmp(e->valuestring, v->valuestring) == 0) return k;
    if (kind == TT_VALUE_BOOL && cJSON_IsTrue(e) == cJSON_IsTrue(v)) return k;
    if (kind == TT_VALUE_INT && e->valuedouble == v->valuedouble) return k;
  }
  return -1;
}

/* Parses parameters[i] and adds it to `space`; 0 or -1 (error recorded). */
static int tt__parse_param(tt_space *space, const cJSON *item, int i, const char *source) {
  char path[64], p[128], got[128];
  snprintf(path, sizeof path, "parameters[%d]", i);
  if (!cJSON_IsObject(item))
    return tt__json_error(TT_ERR_PARSE, source, path, "expected a parameter object, got %s",
                          tt__json_describe(item, TT__JSON_PARAMS, got, sizeof got)),
           -1;

  const cJSON *name = cJSON_GetObjectItemCaseSensitive(item, "name");
  snprintf(p, sizeof p, "%s.name", path);
  if (!cJSON_IsString(name) || !name->valuestring[0])
    return tt__json_error(TT_ERR_PARSE, source, p, "expected a non-empty string, got %s",
                          tt__json_describe(name, TT__JSON_PARAMS, got, sizeof got)),
           -1;
  int prev = tt_space_find(space, name->valuestring);
  if (prev >= 0)
    return tt__json_error(TT_ERR_PARSE, source, p,
                          "duplicate name \"%s\" (already used by parameters[%d])",
                          name->valuestring, prev),
           -1;

  const cJSON *desc = cJSON_GetObjectItemCaseSensitive(item, "description");
  snprintf(p, sizeof p, "%s.description", path);
  if (desc && !cJSON_IsString(desc))
    return tt__json_error(TT_ERR_PARSE, source, p, "expected a string, got %s",
                          tt__json_describe(desc, TT__JSON_PARAMS, got, sizeof got)),
           -1;
  const char *description = desc ? desc->valuestring : "";

  const cJSON *type = cJSON_GetObjectItemCaseSensitive(item, "type");
  snprintf(p, sizeof p, "%s.type", path);
  if (!type)
    return tt__json_error(TT_ERR_PARSE, source, p,
                          "missing (expected \"INT\", \"FLOAT\" or \"NOM\")"),
           -1;
  if (!cJSON_IsString(type))
    return tt__json_error(TT_ERR_PARSE, source, p, "expected \"INT\", \"FLOAT\" or \"NOM\", got %s",
                          tt__json_describe(type, TT__JSON_PARAMS, got, sizeof got)),
           -1;
  const char *t = type->valuestring;
  int is_int = strcmp(t, "INT") == 0, is_float = strcmp(t, "FLOAT") == 0,
      is_nom = strcmp(t, "NOM") == 0;
  if (!is_int && !is_float && !is_nom)
    return tt__json_error(TT_ERR_PARSE, source, p,
                          "unknown type \"%s\" (expected \"INT\", \"FLOAT\" or \"NOM\"; a "
                          "boolean is a NOM with possibleValues [false, true])",
                          t),
           -1;

  const cJSON *logj = cJSON_GetObjectItemCaseSensitive(item, "log");
  snprintf(p, sizeof p, "%s.log", path);
  if (logj && !cJSON_IsBool(logj))
    return tt__json_error(TT_ERR_PARSE, source, p, "expected true or false, got %s",
                          tt__json_describe(logj, TT__JSON_PARAMS, got, sizeof got)),
           -1;
  int log = cJSON_IsTrue(logj);
  if (log && !is_float)
    return tt__json_error(TT_ERR_PARSE, source, p,
                          "only FLOAT parameters may be log-scaled (type is %s)", t),
           -1;

  int r;
  if (is_int) {
    int64_t mn, mx, def;
    if (tt__get_int(item, "min", path, source, &mn) ||
        tt__get_int(item, "max", path, source, &mx) ||
        tt__get_int(item, "value", path, source, &def))
      return -1;
    if (mn > mx) {
      snprintf(p, sizeof p, "%s.max", path);
      return tt__json_error(TT_ERR_PARSE, source, p,
                            "%" PRId64 " is less than min %" PRId64 " (expected min <= max)", mx,
                            mn),
             -1;
    }
    if (def < mn || def > mx) {
      snprintf(p, sizeof p, "%s.value", path);
      return tt__json_error(TT_ERR_PARSE, source, p,
                            "default %" PRId64 " is outside [%" PRId64 ", %" PRId64 "]", def, mn,
                            mx),
             -1;
    }
    r = tt_space_add_int(space, name->valuestring, mn, mx, def, description);
  } else if (is_float) {
    double mn, mx, def;
    if (tt__get_double(item, "min", path, source, &mn) ||
        tt__get_double(item, "max", path, source, &mx) ||
        tt__get_double(item, "value", path, source, &def))
      return -1;
    if (mn > mx) {
      snprintf(p, sizeof p, "%s.max", path);
      return tt__json_error(TT_ERR_PARSE, source, p, "%g is less than min %g (expected min <= max)",
                            mx, mn),
             -1;
    }
    if (def < mn || def > mx) {
      snprintf(p, sizeof p, "%s.value", path);
      return tt__json_error(TT_ERR_PARSE, source, p, "default %g is outside [%g, %g]", def, mn, mx),
             -1;
    }
    if (log && mn <= 0.0) {
      snprintf(p, sizeof p, "%s.log", path);
      return tt__json_error(TT_ERR_PARSE, source, p, "log scale needs min > 0, got min %g", mn), -1;
    }
    r = tt_space_add_float(space, name->valuestring, mn, mx, def, log, description);
  } else {
    const cJSON *pv = cJSON_GetObjectItemCaseSensitive(item, "possibleValues");
    snprintf(p, sizeof p, "%s.possibleValues", path);
    if (!pv)
      return tt__json_error(TT_ERR_PARSE, source, p, "missing (expected a non-empty array)"), -1;
    if (!cJSON_IsArray(pv))
      return tt__json_error(TT_ERR_PARSE, source, p, "expected a non-empty array, got %s",
                            tt__json_describe(pv, TT__JSON_PARAMS, got, sizeof got)),
             -1;
    int count = cJSON_GetArraySize(pv);
    if (count == 0)
      return tt__json_error(TT_ERR_PARSE, source, p,
                            "empty (expected at least one possible value)"),
             -1;
    tt_value_kind kind = tt__nom_kind_of(pv->child);
    int k = 0;
    for (const cJSON *e = pv->child; e; e = e->next, k++) {
      snprintf(p, sizeof p, "%s.possibleValues[%d]", path, k);
      tt_value_kind ek = tt__nom_kind_of(e);
      if (!ek)
        return tt__json_error(TT_ERR_PARSE, source, p,
                              "expected an integer, boolean or string, got %s",
                              tt__json_describe(e, TT__JSON_PARAMS, got, sizeof got)),
               -1;
      if (ek != kind)
        return tt__json_error(TT_ERR_PARSE, source, p,
                              "mixed value kinds (possibleValues[0] is %s, this is %s; "
                              "expected all integers, all booleans or all strings)",
                              tt__kind_name(kind), tt__kind_name(ek)),
               -1;
      for (const cJSON *f = pv->child; f != e; f = f->next)
        if ((kind == TT_VALUE_STRING && strcmp(f->valuestring, e->valuestring) == 0) ||
            (kind == TT_VALUE_INT && f->valuedouble == e->valuedouble) ||
            (kind == TT_VALUE_BOOL && cJSON_IsTrue(f) == cJSON_IsTrue(e)))
          return tt__json_error(TT_ERR_PARSE, source, p,
                                "duplicate value %s (expected distinct values)",
                                tt__json_describe(e, TT__JSON_PARAMS, got, sizeof got)),
                 -1;
    }
    snprintf(p, sizeof p, "%s.possibleValues", path);
    if (kind == TT_VALUE_BOOL && (count != 2 || cJSON_IsTrue(pv->child)))
      return tt__json_error(TT_ERR_PARSE, source, p,
                            "boolean possible values must be [false, true]"),
             -1;

    const cJSON *val = cJSON_GetObjectItemCaseSensitive(item, "value");
    snprintf(p, sizeof p, "%s.value", path);
    if (!val)
      return tt__json_error(TT_ERR_PARSE, source, p,
                            "missing (expected the default, one of possibleValues)"),
             -1;
    int def = tt__nom_find(pv, val);
    if (def < 0)
      return tt__json_error(TT_ERR_PARSE, source, p, "default %s is not one of possibleValues",
                            tt__json_describe(val, TT__JSON_PARAMS, got, sizeof got)),
             -1;

    if (kind == TT_VALUE_BOOL) {
      r = tt_space_add_nom_bool(space, name->valuestring, def, description);
    } else if (kind == TT_VALUE_INT) {
      int64_t *vals = malloc((size_t)count * sizeof *vals);
      if (!vals) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", source), -1;
      k = 0;
      for (const cJSON *e = pv->child; e; e = e->next) vals[k++] = (int64_t)e->valuedouble;
      r = tt_space_add_nom_int(space, name->valuestring, vals, (size_t)count, (size_t)def,
                               description);
      free(vals);
    } else {
      const char **vals = malloc((size_t)count * sizeof *vals);
      if (!vals) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", source), -1;
      k = 0;
      for (const cJSON *e = pv->child; e; e = e->next) vals[k++] = e->valuestring;
      r = tt_space_add_nom_string(space, name->valuestring, vals, (size_t)count, (size_t)def,
                                  description);
      free(vals);
    }
  }
  if (r < 0) {
    /* Everything add_* checks was checked above; this keeps any remaining message. */
    char pre[160];
    snprintf(pre, sizeof pre, "%s: %s: ", source, path);
    tt__prefix_error(TT_ERR_PARSE, pre);
    return -1;
  }
  return 0;
}

/* "tunable": false and "activeWhen": {"PARENT": [values...], ...} of parameters[i]. */
static int tt__parse_marking(tt_space *space, const cJSON *item, int i, const char *source) {
  char path[64], p[256], got[128];
  snprintf(path, sizeof path, "parameters[%d]", i);
  const cJSON *tun = cJSON_GetObjectItemCaseSensitive(item, "tunable");
  if (tun) {
    snprintf(p, sizeof p, "%s.tunable", path);
    if (!cJSON_IsBool(tun))
      return tt__json_error(TT_ERR_PARSE, source, p, "expected true or false, got %s",
                            tt__json_describe(tun, TT__JSON_PARAMS, got, sizeof got)),
             -1;
    tt_space_set_tunable(space, (size_t)i, cJSON_IsTrue(tun));
  }
  const cJSON *mo = cJSON_GetObjectItemCaseSensitive(item, "motionOnly");
  if (mo) {
    snprintf(p, sizeof p, "%s.motionOnly", path);
    if (!cJSON_IsBool(mo))
      return tt__json_error(TT_ERR_PARSE, source, p, "expected true or false, got %s",
                            tt__json_describe(mo, TT__JSON_PARAMS, got, sizeof got)),
             -1;
    tt_space_set_motion_only(space, (size_t)i, cJSON_IsTrue(mo));
  }
  const cJSON *when = cJSON_GetObjectItemCaseSensitive(item, "activeWhen");
  if (!when) return 0;
  snprintf(p, sizeof p, "%s.activeWhen", path);
  if (!cJSON_IsObject(when))
    return tt__json_error(TT_ERR_PARSE, source, p, "expected {\"PARAMETER\": [values...]}, got %s",
                          tt__json_describe(when, TT__JSON_PARAMS, got, sizeof got)),
           -1;
  for (const cJSON *c = when->child; c; c = c->next) {
    snprintf(p, sizeof p, "%s.activeWhen.%s", path, c->string);
    if (!cJSON_IsArray(c) || !c->child)
      return tt__json_error(TT_ERR_PARSE, source, p,
                            "expected a non-empty array of the parameter's values, "
                            "got %s",
                            tt__json_describe(c, TT__JSON_PARAMS, got, sizeof got)),
             -1;
    char texts[64][64];
    const char *vals[64];
    size_t n = 0;
    for (const cJSON *v = c->child; v && n < 64; v = v->next, n++) {
      if (cJSON_IsString(v)) snprintf(texts[n], sizeof texts[n], "%s", v->valuestring);
      else if (cJSON_IsBool(v))
        snprintf(texts[n], sizeof texts[n], "%s", cJSON_IsTrue(v) ? "true" : "false");
      else if (cJSON_IsNumber(v) && v->valuedouble == (double)(long long)v->valuedouble)
        snprintf(texts[n], sizeof texts[n], "%lld", (long long)v->valuedouble);
      else
        return tt__json_error(TT_ERR_PARSE, source, p,
                              "expected possible values (strings, booleans or "
                              "integers), got %s",
                              tt__json_describe(v, TT__JSON_PARAMS, got, sizeof got)),
               -1;
      vals[n] = texts[n];
    }
    if (tt_space_add_condition(space, (size_t)i, c->string, vals, n) != TT_OK) {
      char pre[300];
      snprintf(pre, sizeof pre, "%s: %s: ", source, p);
      tt__prefix_error(TT_ERR_PARSE, pre);
      return -1;
    }
  }
  return 0;
}

tt_space *tt_space_from_json(const char *json, const char *source) {
  if (!source) source = "(space JSON)";
  cJSON *root = tt__parse(json, source);
  if (!root) return NULL;
  char got[128];
  tt_space *space = NULL;
  if (!cJSON_IsObject(root)) {
    tt__json_error(TT_ERR_PARSE, source, NULL, "expected a JSON object at the top level, got %s",
                   tt__json_describe(root, TT__JSON_PARAMS, got, sizeof got));
    goto fail;
  }
  const cJSON *plugin = cJSON_GetObjectItemCaseSensitive(root, "plugin");
  if (!cJSON_IsString(plugin)) {
    tt__json_error(TT_ERR_PARSE, source, "plugin", "expected the plugin name as a string, got %s",
                   tt__json_describe(plugin, TT__JSON_PARAMS, got, sizeof got));
    goto fail;
  }
  const cJSON *version = cJSON_GetObjectItemCaseSensitive(root, "version");
  if (version && !cJSON_IsString(version)) {
    tt__json_error(TT_ERR_PARSE, source, "version", "expected a version string, got %s",
                   tt__json_describe(version, TT__JSON_PARAMS, got, sizeof got));
    goto fail;
  }
  const cJSON *params = cJSON_GetObjectItemCaseSensitive(root, "parameters");
  if (!cJSON_IsArray(params)) {
    tt__json_error(TT_ERR_PARSE, source, "parameters",
                   "expected an array of parameter objects, got %s",
                   tt__json_describe(params, TT__JSON_PARAMS, got, sizeof got));
    goto fail;
  }
  const cJSON *cons = cJSON_GetObjectItemCaseSensitive(root, "constraints");
  if (cons && !cJSON_IsArray(cons)) {
    tt__json_error(TT_ERR_PARSE, source, "constraints",
                   "expected an array of {\"description\": ...}, got %s",
                   tt__json_describe(cons, TT__JSON_PARAMS, got, sizeof got));
    goto fail;
  }
  space = tt_space_create(plugin->valuestring, version ? version->valuestring : "");
  if (!space) goto fail;
  int i = 0;
  for (const cJSON *item = params->child; item; item = item->next, i++)
    if (tt__parse_param(space, item, i, source) < 0) goto fail;
  /* conditions once every parameter exists: a parent may come after its child */
  i = 0;
  for (const cJSON *item = params->child; item; item = item->next, i++)
    if (tt__parse_marking(space, item, i, source) < 0) goto fail;
  i = 0;
  for (const cJSON *c = cons ? cons->child : NULL; c; c = c->next, i++) {
    const cJSON *d = cJSON_IsObject(c) ? cJSON_GetObjectItemCaseSensitive(c, "description") : c;
    if (!cJSON_IsString(d)) {
      char p[64];
      snprintf(p, sizeof p, "constraints[%d]", i);
      tt__json_error(TT_ERR_PARSE, source, p, "expected {\"description\": \"...\"}, got %s",
                     tt__json_describe(c, TT__JSON_PARAMS, got, sizeof got));
      goto fail;
    }
    tt_space_add_constraint_text(space, d->valuestring);
  }
  cJSON_Delete(root);
  return space;
fail:
  tt_space_destroy(space);
  cJSON_Delete(root);
  return NULL;
}

/* JSON number for an int64 written exactly (cJSON's doubles would round beyond 2^53). */
static cJSON *tt__json_int(int64_t v) {
  char buf[32];
  snprintf(buf, sizeof buf, "%" PRId64, v);
  return cJSON_CreateRaw(buf);
}

/* JSON number for a double written with the fewest digits that read back exactly: cJSON's
 * own printer accepts a 1-ulp difference, which would break configuration round trips. */
static cJSON *tt__json_double(double v) {
  char buf[64];
  for (int prec = 15; prec <= 17; prec++) {
    snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (strtod(buf, NULL) == v) break;
  }
  /* JSON needs '.', whatever LC_NUMERIC the host process selected. */
  const char *dp = localeconv()->decimal_point;
  if (dp && dp[0] && dp[0] != '.')
    for (char *c = buf; *c; c++)
      if (*c == dp[0]) *c = '.';
  return cJSON_CreateRaw(buf);
}

/* JSON form of a parameter value. */
static cJSON *tt__json_value(tt_value v) {
  switch (v.kind) {
  case TT_VALUE_INT: return tt__json_int(v.i);
  case TT_VALUE_FLOAT: return tt__json_double(v.f);
  case TT_VALUE_BOOL: return cJSON_CreateBool(v.i != 0);
  case TT_VALUE_STRING: return cJSON_CreateString(v.s);
  }
  return cJSON_CreateNull();
}

/* Prints `root` into a malloc'ed string (tt_free frees with free(), whatever cJSON's hooks
 * are) and deletes it. */
static char *tt__print(cJSON *root, int pretty) {
  char *text = pretty ? cJSON_Print(root) : cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  if (!text) {
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "JSON serialisation: out of memory");
    return NULL;
  }
  char *out = tt__strdup(text);
  cJSON_free(text);
  if (!out) tt_set_error(TT_ERR_OUT_OF_MEMORY, "JSON serialisation: out of memory");
  return out;
}

char *tt_space_to_json(const tt_space *space) {
  if (!space) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_space_to_json: space is NULL");
    return NULL;
  }
  cJSON *root = cJSON_CreateObject();
  cJSON *params = cJSON_CreateArray();
  int ok = root && params;
  if (ok) {
    cJSON_AddItemToObject(root, "plugin", cJSON_CreateString(tt_space_plugin(space)));
    cJSON_AddItemToObject(root, "version", cJSON_CreateString(tt__space_version(space)));
    cJSON_AddItemToObject(root, "parameters", params);
  } else {
    cJSON_Delete(params);
  }
  for (size_t i = 0; ok && i < tt_space_count(space); i++) {
    cJSON *p = cJSON_CreateObject();
    if (!p) {
      ok = 0;
      break;
    }
    cJSON_AddItemToArray(params, p);
    tt_param_type type = tt_space_type(space, i);
    cJSON_AddItemToObject(p, "name", cJSON_CreateString(tt_space_name(space, i)));
    cJSON_AddItemToObject(p, "type",
                          cJSON_CreateString(type == TT_PARAM_INT     ? "INT"
                                             : type == TT_PARAM_FLOAT ? "FLOAT"
                                                                      : "NOM"));
    if (type == TT_PARAM_INT) {
      /* Exact int64 bounds: tt_space_min/max are doubles and round beyond 2^53. */
      int64_t mn = 0, mx = 0;
      tt__space_int_range(space, i, &mn, &mx);
      cJSON_AddItemToObject(p, "min", tt__json_int(mn));
      cJSON_AddItemToObject(p, "max", tt__json_int(mx));
    } else if (type == TT_PARAM_FLOAT) {
      cJSON_AddItemToObject(p, "min", tt__json_double(tt_space_min(space, i)));
      cJSON_AddItemToObject(p, "max", tt__json_double(tt_space_max(space, i)));
    } else {
      cJSON *pv = cJSON_CreateArray();
      cJSON_AddItemToObject(p, "possibleValues", pv);
      for (size_t k = 0; pv && k < tt_space_nom_count(space, i); k++)
        cJSON_AddItemToArray(pv, tt__json_value(tt_space_nom_value(space, i, k)));
    }
    cJSON_AddItemToObject(p, "value", tt__json_value(tt_space_default(space, i)));
    const char *d = tt_space_description(space, i);
    if (d && d[0]) cJSON_AddItemToObject(p, "description", cJSON_CreateString(d));
    if (tt_space_is_log(space, i)) cJSON_AddItemToObject(p, "log", cJSON_CreateTrue());
    if (!tt_space_is_tunable(space, i)) cJSON_AddItemToObject(p, "tunable", cJSON_CreateFalse());
    if (tt_space_is_motion_only(space, i))
      cJSON_AddItemToObject(p, "motionOnly", cJSON_CreateTrue());
    size_t nc = tt_space_condition_count(space, i);
    cJSON *when = nc ? cJSON_CreateObject() : NULL;
    if (when) cJSON_AddItemToObject(p, "activeWhen", when);
    for (size_t k = 0; when && k < nc; k++) {
      size_t q = (size_t)tt_space_condition_parent(space, i, k);
      cJSON *vals = cJSON_CreateArray();
      if (!vals) break;
      cJSON_AddItemToObject(when, tt_space_name(space, q), vals);
      for (size_t v = 0; v < tt_space_nom_count(space, q); v++)
        if (tt_space_condition_allows(space, i, k, v))
          cJSON_AddItemToArray(vals, tt__json_value(tt_space_nom_value(space, q, v)));
    }
  }
  cJSON *cons = ok ? cJSON_CreateArray() : NULL;
  if (cons) {
    cJSON_AddItemToObject(root, "constraints", cons);
    for (size_t k = 0; k < tt__space_constraint_count(space); k++) {
      cJSON *c = cJSON_CreateObject();
      if (!c) break;
      cJSON_AddItemToObject(c, "description", cJSON_CreateString(tt__space_constraint(space, k)));
      cJSON_AddItemToArray(cons, c);
    }
  }
  if (!ok) {
    cJSON_Delete(root);
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_space_to_json: %s: out of memory",
                 tt_space_plugin(space));
    return NULL;
  }
  return tt__print(root, 1);
}

char *tt_config_to_json(const tt_config *config) {
  if (!config) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_config_to_json: config is NULL");
    return NULL;
  }
  const tt_space *space = tt_config_space(config);
  cJSON *root = cJSON_CreateObject();
  if (!root) {
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_config_to_json: out of memory");
    return NULL;
  }
  for (size_t i = 0; i < tt_space_count(space); i++)
    cJSON_AddItemToObject(root, tt_space_name(space, i), tt__json_value(tt_config_get(config, i)));
  /* Compact: configurations are logged one per line by tuners and the host. */
  return tt__print(root, 0);
}

/* Sets parameter `idx` of `work` from JSON value `v`; 0 or -1 (error recorded). */
static int tt__config_set_json(tt_config *work, size_t idx, const cJSON *v, const char *source) {
  const tt_space *space = tt_config_space(work);
  const char *name = tt_space_name(space, idx);
  char path[256], got[128];
  snprintf(path, sizeof path, "%s.%s", tt_space_plugin(space), name);
  tt_param_type type = tt_space_type(space, idx);
  tt_value_kind kind = tt__space_nom_kind(space, idx);
  if (type == TT_PARAM_NOM && kind == TT_VALUE_BOOL) {
    if (!cJSON_IsBool(v))
      return tt__json_error(TT_ERR_PARSE, source, path, "expected true or false, got %s",
                            tt__json_describe(v, TT__JSON_PARAMS, got, sizeof got)),
             -1;
    tt_config_set_index(work, idx, cJSON_IsTrue(v) ? 1 : 0);
    return 0;
  }
  if (type == TT_PARAM_NOM && kind == TT_VALUE_STRING) {
    if (cJSON_IsString(v))
      for (size_t k = 0; k < tt_space_nom_count(space, idx); k++)
        if (strcmp(tt_space_nom_value(space, idx, k).s, v->valuestring) == 0) {
          tt_config_set_index(work, idx, k);
          return 0;
        }
    char list[512];
    size_t used = 0;
    list[0] = '\0';
    for (size_t k = 0; k < tt_space_nom_count(space, idx) && used < sizeof list; k++) {
      int n = snprintf(list + used, sizeof list - used, "%s\"%s\"", k ? ", " : "",
                       tt_space_nom_value(space, idx, k).s);
      if (n < 0) break;
      used += (size_t)n;
    }
    return tt__json_error(TT_ERR_PARSE, source, path, "expected one of %s, got %s", list,
                          tt__json_describe(v, TT__JSON_PARAMS, got, sizeof got)),
           -1;
  }
  if (!cJSON_IsNumber(v))
    return tt__json_error(TT_ERR_PARSE, source, path, "expected %s, got %s",
                          type == TT_PARAM_FLOAT ? "a number" : "an integer",
                          tt__json_describe(v, TT__JSON_PARAMS, got, sizeof got)),
           -1;
  if (tt_config_set_number(work, idx, v->valuedouble) != TT_OK) {
    char pre[160];
    snprintf(pre, sizeof pre, "%s: ", source);
    tt__prefix_error(TT_ERR_PARSE, pre);
    return -1;
  }
  return 0;
}

tt_status tt_config_from_json(tt_config *config, const char *json, const char *source) {
  if (!source) source = "(config JSON)";
  if (!config) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: config is NULL", source);
  cJSON *root = tt__parse(json, source);
  if (!root) return TT_ERR_PARSE;
  char got[128];
  tt_status st = TT_OK;
  /* Work on a clone so that a failure leaves `config` untouched. */
  tt_config *work = NULL;
  if (!cJSON_IsObject(root)) {
    st = tt__json_error(TT_ERR_PARSE, source, NULL,
                        "expected a JSON object {\"name\": value, ...}, got %s",
                        tt__json_describe(root, TT__JSON_PARAMS, got, sizeof got));
    goto done;
  }
  work = tt_config_clone(config);
  if (!work) {
    st = TT_ERR_OUT_OF_MEMORY;
    goto done;
  }
  const tt_space *space = tt_config_space(config);
  for (const cJSON *m = root->child; m; m = m->next) {
    for (const cJSON *e = root->child; e != m; e = e->next)
      if (strcmp(e->string, m->string) == 0) {
        st = tt__json_error(TT_ERR_PARSE, source, m->string,
                            "appears twice (expected each name once)");
        goto done;
      }
    int idx = tt_space_find(space, m->string);
    if (idx < 0) {
      char hint[1024];
      tt__space_unknown_hint(space, m->string, hint, sizeof hint);
      st = tt__json_error(TT_ERR_PARSE, source, NULL, "unknown parameter \"%s\" of %s (%s)",
                          m->string, tt_space_plugin(space), hint);
      goto done;
    }
    if (tt__config_set_json(work, (size_t)idx, m, source) < 0) {
      st = TT_ERR_PARSE;
      goto done;
    }
  }
  tt_config_copy(config, work);
done:
  tt_config_destroy(work);
  cJSON_Delete(root);
  return st;
}
