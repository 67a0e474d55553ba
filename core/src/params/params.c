/* Parameter spaces (tt_space) and configurations (tt_config): building, reading, setting
 * values with strict validation, and the unit-cube mapping used by tuners. */
#include "params/params_internal.h"

#include <tunetrace/params.h>
#include <tunetrace/suggest.h>

#include <ctype.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Largest INT bound magnitude: 2^53, the last integer range exact in a double. */
#define TT__INT_LIMIT ((int64_t)1 << 53)

/* One parameter. INT uses imin/imax/idef, FLOAT fmin/fmax/fdef/log, NOM the value list. */
typedef struct tt__param {
  char *name;
  char *description;
  tt_param_type type;
  int64_t imin, imax, idef;
  double fmin, fmax, fdef;
  int log;
  tt_value_kind nom_kind; /* TT_VALUE_INT, TT_VALUE_BOOL or TT_VALUE_STRING */
  size_t nom_count;
  int64_t *nom_ints;  /* NOM int and bool values (bool: 0, 1) */
  char **nom_strings; /* NOM string values */
  size_t nom_def;
  int untunable;   /* tt_space_set_tunable(..., 0): tuners leave it alone */
  int motion_only; /* tt_space_set_motion_only: acts only while the scene moves */
  size_t ncond;    /* tt_space_add_condition: acts only while all hold */
  struct tt__cond {
    size_t parent;          /* a NOM parameter of the same space */
    unsigned char *allowed; /* one flag per possible value of the parent */
  } * conds;
} tt__param;

struct tt_space {
  char *plugin;
  char *version;
  tt__param *params;
  size_t count, cap;
  char **constraints;
  size_t constraint_count;
  tt_check_fn check;
  void *check_user;
  /* Set by the first tt_config_create: configs size their value arrays from `count`, so
   * adding parameters afterwards would corrupt them. Atomic because configs may be
   * created from several threads on a published space. */
  atomic_int frozen;
};

struct tt_config {
  const tt_space *space;
  tt_value *values; /* one per parameter, in space order */
};

tt_status tt__prefix_error(tt_status status, const char *prefix) {
  /* Copy first: tt_set_error formats into the very buffer tt_last_error points to. */
  char msg[2048];
  snprintf(msg, sizeof msg, "%s", tt_last_error());
  return tt_set_error(status, "%s%s", prefix, msg);
}

/* ---- building ---- */

tt_space *tt_space_create(const char *plugin_name, const char *plugin_version) {
  tt_space *s = calloc(1, sizeof *s);
  if (!s) {
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_space_create: out of memory");
    return NULL;
  }
  s->plugin = tt__strdup(plugin_name ? plugin_name : "");
  s->version = tt__strdup(plugin_version ? plugin_version : "");
  atomic_init(&s->frozen, 0);
  if (!s->plugin || !s->version) {
    tt_space_destroy(s);
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_space_create: out of memory");
    return NULL;
  }
  return s;
}

/* Frees what a parameter owns (not the struct itself, which lives in the array). */
static void tt__param_free(tt__param *p) {
  for (size_t k = 0; k < p->ncond; k++) free(p->conds[k].allowed);
  free(p->conds);
  free(p->name);
  free(p->description);
  free(p->nom_ints);
  if (p->nom_strings) {
    for (size_t k = 0; k < p->nom_count; k++) free(p->nom_strings[k]);
    free(p->nom_strings);
  }
}

void tt_space_destroy(tt_space *space) {
  if (!space) return;
  for (size_t i = 0; i < space->count; i++) tt__param_free(&space->params[i]);
  free(space->params);
  for (size_t k = 0; k < space->constraint_count; k++) free(space->constraints[k]);
  free(space->constraints);
  free(space->plugin);
  free(space->version);
  free(space);
}

/* Common checks for every add_*: space usable, name valid and unique. 0 or -1. */
static int tt__check_new_name(tt_space *space, const char *name, const char *fn) {
  if (!space) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: space is NULL", fn);
    return -1;
  }
  if (atomic_load_explicit(&space->frozen, memory_order_relaxed)) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "%s: %s: cannot add parameter \"%s\": configurations already exist "
                 "(a space is immutable once published)",
                 fn, space->plugin, name ? name : "(null)");
    return -1;
  }
  if (!name || !name[0] || strchr(name, '=')) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "%s: %s: parameter name \"%s\" is invalid (expected a non-empty name "
                 "without '=')",
                 fn, space->plugin, name ? name : "(null)");
    return -1;
  }
  if (tt_space_find(space, name) >= 0) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "%s: %s: duplicate parameter name \"%s\" (names must be unique)", fn,
                 space->plugin, name);
    return -1;
  }
  return 0;
}

/* Appends `p` (taking ownership of its allocations) and returns its index, or -1. */
static int tt__push_param(tt_space *space, tt__param *p, const char *description) {
  p->description = tt__strdup(description ? description : "");
  if (!p->name || !p->description) goto oom;
  if (space->count == space->cap) {
    size_t cap = space->cap ? space->cap * 2 : 8;
    tt__param *np = realloc(space->params, cap * sizeof *np);
    if (!np) goto oom;
    space->params = np;
    space->cap = cap;
  }
  space->params[space->count] = *p;
  return (int)space->count++;
oom:
  tt__param_free(p);
  tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory adding a parameter", space->plugin);
  return -1;
}

int tt_space_add_int(tt_space *space, const char *name, int64_t min, int64_t max, int64_t def,
                     const char *description) {
  if (tt__check_new_name(space, name, "tt_space_add_int") < 0) return -1;
  /* Beyond 2^53 values stop being exact as doubles, which tt_config_set_number,
   * tt_value.f, tt_space_min/max and JSON all rely on. */
  if (min < -TT__INT_LIMIT || max > TT__INT_LIMIT) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_int: %s.%s: range [%" PRId64 ", %" PRId64
                 "] exceeds +-2^53 (expected bounds exactly representable as doubles)",
                 space->plugin, name, min, max);
    return -1;
  }
  if (min > max) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_int: %s.%s: min %" PRId64 " is greater than max %" PRId64
                 " (expected min <= max)",
                 space->plugin, name, min, max);
    return -1;
  }
  if (def < min || def > max) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_int: %s.%s: default %" PRId64 " is outside [%" PRId64 ", %" PRId64
                 "]",
                 space->plugin, name, def, min, max);
    return -1;
  }
  tt__param p = {0};
  p.type = TT_PARAM_INT;
  p.name = tt__strdup(name);
  p.imin = min;
  p.imax = max;
  p.idef = def;
  return tt__push_param(space, &p, description);
}

int tt_space_add_float(tt_space *space, const char *name, double min, double max, double def,
                       int log, const char *description) {
  if (tt__check_new_name(space, name, "tt_space_add_float") < 0) return -1;
  if (!isfinite(min) || !isfinite(max) || !isfinite(def)) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_float: %s.%s: min %g, max %g and default %g must be finite",
                 space->plugin, name, min, max, def);
    return -1;
  }
  if (min > max) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_float: %s.%s: min %g is greater than max %g (expected "
                 "min <= max)",
                 space->plugin, name, min, max);
    return -1;
  }
  if (def < min || def > max) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_float: %s.%s: default %g is outside [%g, %g]", space->plugin, name,
                 def, min, max);
    return -1;
  }
  if (log && min <= 0.0) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_float: %s.%s: log scale needs min > 0, got min %g", space->plugin,
                 name, min);
    return -1;
  }
  tt__param p = {0};
  p.type = TT_PARAM_FLOAT;
  p.name = tt__strdup(name);
  p.fmin = min;
  p.fmax = max;
  p.fdef = def;
  p.log = log ? 1 : 0;
  return tt__push_param(space, &p, description);
}

int tt_space_add_nom_int(tt_space *space, const char *name, const int64_t *values, size_t count,
                         size_t def_index, const char *description) {
  if (tt__check_new_name(space, name, "tt_space_add_nom_int") < 0) return -1;
  if (!values || count == 0) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_nom_int: %s.%s: possible values are empty (expected at "
                 "least one)",
                 space->plugin, name);
    return -1;
  }
  if (def_index >= count) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_nom_int: %s.%s: default index %zu is outside [0, %zu]",
                 space->plugin, name, def_index, count - 1);
    return -1;
  }
  /* Duplicates would make setting by value ambiguous and skew the unit-cube bins; values
   * beyond 2^53 could not be matched exactly by tt_config_set_number. */
  for (size_t a = 0; a < count; a++) {
    if (values[a] < -TT__INT_LIMIT || values[a] > TT__INT_LIMIT) {
      tt_set_error(TT_ERR_INVALID_ARGUMENT,
                   "tt_space_add_nom_int: %s.%s: possible value %" PRId64
                   " exceeds +-2^53 (expected values exactly representable as doubles)",
                   space->plugin, name, values[a]);
      return -1;
    }
    for (size_t b = a + 1; b < count; b++)
      if (values[a] == values[b]) {
        tt_set_error(TT_ERR_INVALID_ARGUMENT,
                     "tt_space_add_nom_int: %s.%s: possible value %" PRId64
                     " appears twice (expected distinct values)",
                     space->plugin, name, values[a]);
        return -1;
      }
  }
  tt__param p = {0};
  p.type = TT_PARAM_NOM;
  p.nom_kind = TT_VALUE_INT;
  p.name = tt__strdup(name);
  p.nom_count = count;
  p.nom_def = def_index;
  p.nom_ints = malloc(count * sizeof *p.nom_ints);
  if (!p.nom_ints) {
    tt__param_free(&p);
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory adding a parameter", space->plugin);
    return -1;
  }
  memcpy(p.nom_ints, values, count * sizeof *values);
  return tt__push_param(space, &p, description);
}

int tt_space_add_nom_bool(tt_space *space, const char *name, int def, const char *description) {
  if (tt__check_new_name(space, name, "tt_space_add_nom_bool") < 0) return -1;
  tt__param p = {0};
  p.type = TT_PARAM_NOM;
  p.nom_kind = TT_VALUE_BOOL;
  p.name = tt__strdup(name);
  p.nom_count = 2;
  p.nom_def = def ? 1 : 0;
  p.nom_ints = malloc(2 * sizeof *p.nom_ints);
  if (!p.nom_ints) {
    tt__param_free(&p);
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory adding a parameter", space->plugin);
    return -1;
  }
  p.nom_ints[0] = 0;
  p.nom_ints[1] = 1;
  return tt__push_param(space, &p, description);
}

int tt_space_add_nom_string(tt_space *space, const char *name, const char *const *values,
                            size_t count, size_t def_index, const char *description) {
  if (tt__check_new_name(space, name, "tt_space_add_nom_string") < 0) return -1;
  if (!values || count == 0) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_nom_string: %s.%s: possible values are empty (expected at "
                 "least one)",
                 space->plugin, name);
    return -1;
  }
  if (def_index >= count) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_space_add_nom_string: %s.%s: default index %zu is outside [0, %zu]",
                 space->plugin, name, def_index, count - 1);
    return -1;
  }
  for (size_t a = 0; a < count; a++) {
    if (!values[a]) {
      tt_set_error(TT_ERR_INVALID_ARGUMENT,
                   "tt_space_add_nom_string: %s.%s: possible value %zu is NULL", space->plugin,
                   name, a);
      return -1;
    }
    for (size_t b = 0; b < a; b++)
      if (strcmp(values[a], values[b]) == 0) {
        tt_set_error(TT_ERR_INVALID_ARGUMENT,
                     "tt_space_add_nom_string: %s.%s: possible value \"%s\" appears twice "
                     "(expected distinct values)",
                     space->plugin, name, values[a]);
        return -1;
      }
  }
  tt__param p = {0};
  p.type = TT_PARAM_NOM;
  p.nom_kind = TT_VALUE_STRING;
  p.name = tt__strdup(name);
  p.nom_def = def_index;
  p.nom_strings = calloc(count, sizeof *p.nom_strings);
  int ok = p.nom_strings != NULL;
  if (ok) {
    p.nom_count = count; /* set only now: tt__param_free walks nom_count entries */
    for (size_t k = 0; k < count; k++) ok = ok && (p.nom_strings[k] = tt__strdup(values[k]));
  }
  if (!ok) {
    tt__param_free(&p);
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory adding a parameter", space->plugin);
    return -1;
  }
  return tt__push_param(space, &p, description);
}

void tt_space_add_constraint_text(tt_space *space, const char *description) {
  if (!space || !description) return;
  char **nc = realloc(space->constraints, (space->constraint_count + 1) * sizeof *nc);
  if (!nc) return;
  space->constraints = nc;
  char *d = tt__strdup(description);
  if (d) space->constraints[space->constraint_count++] = d;
}

void tt_space_set_check(tt_space *space, tt_check_fn fn, void *user) {
  if (!space) return;
  space->check = fn;
  space->check_user = user;
}

/* ---- reading ---- */

/* Parameter `index`, or NULL when the space is NULL or the index out of range. */
static const tt__param *tt__param_at(const tt_space *space, size_t index) {
  return (space && index < space->count) ? &space->params[index] : NULL;
}

const char *tt_space_plugin(const tt_space *space) { return space ? space->plugin : NULL; }
const char *tt__space_version(const tt_space *space) { return space ? space->version : NULL; }
size_t tt__space_constraint_count(const tt_space *space) {
  return space ? space->constraint_count : 0;
}
const char *tt__space_constraint(const tt_space *space, size_t k) {
  return (space && k < space->constraint_count) ? space->constraints[k] : NULL;
}
tt_value_kind tt__space_nom_kind(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  return (p && p->type == TT_PARAM_NOM) ? p->nom_kind : (tt_value_kind)0;
}

int tt__space_int_range(const tt_space *space, size_t index, int64_t *min, int64_t *max) {
  const tt__param *p = tt__param_at(space, index);
  if (!p || p->type != TT_PARAM_INT) return 0;
  *min = p->imin;
  *max = p->imax;
  return 1;
}

size_t tt_space_count(const tt_space *space) { return space ? space->count : 0; }

void tt__space_unknown_hint(const tt_space *space, const char *name, char *buf, size_t n) {
  if (!n) return;
  buf[0] = '\0';
  if (!space) return;
  const char *names[256];
  size_t count = space->count < 256 ? space->count : 256;
  for (size_t i = 0; i < count; i++) names[i] = space->params[i].name;
  const char *near = tt_suggest(name, names, count);
  if (near) snprintf(buf, n, "did you mean \"%s\"? ", near);
  size_t used = strlen(buf);
  const char *sep = "known: ";
  for (size_t i = 0; i < space->count && used + 1 < n; i++, sep = ", ") {
    snprintf(buf + used, n - used, "%s%s", sep, space->params[i].name);
    used += strlen(buf + used);
  }
  if (!space->count && used + 1 < n) snprintf(buf + used, n - used, "known: none");
}

int tt_space_find(const tt_space *space, const char *name) {
  if (!space || !name) return -1;
  for (size_t i = 0; i < space->count; i++)
    if (strcmp(space->params[i].name, name) == 0) return (int)i;
  return -1;
}

const char *tt_space_name(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  return p ? p->name : NULL;
}

tt_param_type tt_space_type(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  return p ? p->type : (tt_param_type)0;
}

const char *tt_space_description(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  return p ? p->description : NULL;
}

double tt_space_min(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  if (!p) return 0.0;
  switch (p->type) {
  case TT_PARAM_INT: return (double)p->imin;
  case TT_PARAM_FLOAT: return p->fmin;
  default: return 0.0;
  }
}

double tt_space_max(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  if (!p) return 0.0;
  switch (p->type) {
  case TT_PARAM_INT: return (double)p->imax;
  case TT_PARAM_FLOAT: return p->fmax;
  default: return (double)p->nom_count - 1.0;
  }
}

int tt_space_is_log(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  return p ? p->log : 0;
}

size_t tt_space_nom_count(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  return (p && p->type == TT_PARAM_NOM) ? p->nom_count : 0;
}

/* Builds the tt_value for possible value `k` of NOM parameter `p` (k < nom_count). */
static tt_value tt__nom_value(const tt__param *p, size_t k) {
  tt_value v = {0};
  v.kind = p->nom_kind;
  v.index = (int32_t)k;
  if (p->nom_kind == TT_VALUE_STRING) {
    v.s = p->nom_strings[k];
  } else {
    v.i = p->nom_ints[k];
    v.f = (double)v.i;
  }
  return v;
}

tt_value tt_space_nom_value(const tt_space *space, size_t index, size_t k) {
  const tt__param *p = tt__param_at(space, index);
  if (!p || p->type != TT_PARAM_NOM || k >= p->nom_count) {
    tt_value none = {0};
    none.index = -1;
    return none;
  }
  return tt__nom_value(p, k);
}

/* Value of INT parameter `p` holding `i`. */
static tt_value tt__int_value(int64_t i) {
  tt_value v = {0};
  v.kind = TT_VALUE_INT;
  v.index = -1;
  v.i = i;
  v.f = (double)i;
  return v;
}

/* Value of a FLOAT parameter holding `f`. */
static tt_value tt__float_value(double f) {
  tt_value v = {0};
  v.kind = TT_VALUE_FLOAT;
  v.index = -1;
  v.f = f;
  return v;
}

/* Default value of parameter `p`. */
static tt_value tt__param_default(const tt__param *p) {
  switch (p->type) {
  case TT_PARAM_INT: return tt__int_value(p->idef);
  case TT_PARAM_FLOAT: return tt__float_value(p->fdef);
  default: return tt__nom_value(p, p->nom_def);
  }
}

tt_value tt_space_default(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  if (!p) {
    tt_value none = {0};
    none.index = -1;
    return none;
  }
  return tt__param_default(p);
}

tt_check_result tt_space_check(const tt_space *space, tt_config *config, char *why,
                               size_t why_size) {
  if (why && why_size) why[0] = '\0';
  if (!space || !space->check) return TT_CHECK_OK;
  if (!config || config->space != space) {
    /* A config of another space cannot be judged; calling the check on it would read
     * the wrong parameters. */
    if (why && why_size)
      snprintf(why, why_size, "configuration does not belong to space %s", space->plugin);
    return TT_CHECK_INFEASIBLE;
  }
  /* Always give the check a buffer, so plugins need not test `why` for NULL. */
  char local[512];
  char *buf = (why && why_size) ? why : local;
  size_t size = (why && why_size) ? why_size : sizeof local;
  buf[0] = '\0';
  tt_check_result r = space->check(space, config, buf, size, space->check_user);
  if (r != TT_CHECK_OK && buf[0] == '\0')
    snprintf(buf, size, "%s: constraint violated", space->plugin);
  return r;
}

/* ---- configurations ---- */

tt_config *tt_config_create(const tt_space *space) {
  if (!space) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_config_create: space is NULL");
    return NULL;
  }
  tt_config *c = calloc(1, sizeof *c);
  if (c) c->values = calloc(space->count ? space->count : 1, sizeof *c->values);
  if (!c || !c->values) {
    free(c);
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "tt_config_create: %s: out of memory", space->plugin);
    return NULL;
  }
  c->space = space;
  /* The space object is never const in storage (tt_space_create mallocs it); only the
   * atomic flag is written, which keeps concurrent creation race-free. */
  atomic_store_explicit(&((tt_space *)space)->frozen, 1, memory_order_relaxed);
  for (size_t i = 0; i < space->count; i++) c->values[i] = tt__param_default(&space->params[i]);
  return c;
}

void tt_config_destroy(tt_config *config) {
  if (!config) return;
  free(config->values);
  free(config);
}

void tt_config_copy(tt_config *dst, const tt_config *src) {
  if (!dst || !src || dst == src) return;
  if (dst->space != src->space) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT,
                 "tt_config_copy: configurations belong to different spaces (%s, %s)",
                 dst->space->plugin, src->space->plugin);
    return;
  }
  memcpy(dst->values, src->values, src->space->count * sizeof *dst->values);
}

tt_config *tt_config_clone(const tt_config *config) {
  if (!config) return NULL;
  tt_config *c = tt_config_create(config->space);
  if (c) tt_config_copy(c, config);
  return c;
}

const tt_space *tt_config_space(const tt_config *config) { return config ? config->space : NULL; }

int tt_config_equal(const tt_config *a, const tt_config *b) {
  if (!a || !b) return a == b;
  if (a->space != b->space) return 0;
  for (size_t i = 0; i < a->space->count; i++) {
    const tt__param *p = &a->space->params[i];
    const tt_value *va = &a->values[i], *vb = &b->values[i];
    switch (p->type) {
    case TT_PARAM_INT:
      if (va->i != vb->i) return 0;
      break;
    case TT_PARAM_FLOAT:
      if (va->f != vb->f) return 0;
      break;
    default:
      if (va->index != vb->index) return 0;
      break;
    }
  }
  return 1;
}

tt_value tt_config_get(const tt_config *config, size_t index) {
  if (!config || index >= config->space->count) {
    tt_value none = {0};
    none.index = -1;
    return none;
  }
  return config->values[index];
}

/* Stored value of parameter `name`, or NULL when the name is unknown. */
static const tt_value *tt__get_by_name(const tt_config *config, const char *name) {
  if (!config) return NULL;
  int i = tt_space_find(config->space, name);
  return i < 0 ? NULL : &config->values[i];
}

int64_t tt_config_get_int(const tt_config *config, const char *name, int64_t fallback) {
  const tt_value *v = tt__get_by_name(config, name);
  if (!v) return fallback;
  switch (v->kind) {
  case TT_VALUE_INT:
  case TT_VALUE_BOOL: return v->i;
  case TT_VALUE_FLOAT: return (int64_t)llround(v->f); /* nearest, not truncation */
  case TT_VALUE_STRING: return v->index;
  }
  return fallback;
}

double tt_config_get_float(const tt_config *config, const char *name, double fallback) {
  const tt_value *v = tt__get_by_name(config, name);
  if (!v) return fallback;
  switch (v->kind) {
  case TT_VALUE_INT:
  case TT_VALUE_BOOL: return (double)v->i;
  case TT_VALUE_FLOAT: return v->f;
  case TT_VALUE_STRING: return (double)v->index;
  }
  return fallback;
}

const char *tt_config_get_string(const tt_config *config, const char *name) {
  const tt_value *v = tt__get_by_name(config, name);
  return (v && v->kind == TT_VALUE_STRING) ? v->s : NULL;
}

/* Writes "a, b, c" (NOM possible values; strings quoted) into buf. */
static void tt__format_nom_values(const tt__param *p, char *buf, size_t size) {
  size_t used = 0;
  buf[0] = '\0';
  for (size_t k = 0; k < p->nom_count && used < size; k++) {
    const char *sep = k ? ", " : "";
    int n;
    if (p->nom_kind == TT_VALUE_STRING)
      n = snprintf(buf + used, size - used, "%s\"%s\"", sep, p->nom_strings[k]);
    else if (p->nom_kind == TT_VALUE_BOOL)
      n = snprintf(buf + used, size - used, "%s%s", sep, p->nom_ints[k] ? "true" : "false");
    else n = snprintf(buf + used, size - used, "%s%" PRId64, sep, p->nom_ints[k]);
    if (n < 0) break;
    used += (size_t)n;
  }
}

/* Writes "[min, max]" for an INT or FLOAT parameter into buf. */
static void tt__format_range(const tt__param *p, char *buf, size_t size) {
  if (p->type == TT_PARAM_INT) snprintf(buf, size, "[%" PRId64 ", %" PRId64 "]", p->imin, p->imax);
  else snprintf(buf, size, "[%.17g, %.17g]", p->fmin, p->fmax);
  /* %.17g is exact but noisy for values like 0.1; use %g when it round-trips. */
  if (p->type == TT_PARAM_FLOAT) {
    char a[64], b[64];
    snprintf(a, sizeof a, "%g", p->fmin);
    snprintf(b, sizeof b, "%g", p->fmax);
    if (strtod(a, NULL) == p->fmin && strtod(b, NULL) == p->fmax)
      snprintf(buf, size, "[%s, %s]", a, b);
  }
}

/* Sets parameter `index` to the number `value`; `shown` is how the value is named in
 * errors (the user's text, or NULL to print the number). */
/* The value as tt__set_number's errors show it: the caller's text in quotes, else %g when
 * it reads back exactly (or is not finite), else %.17g. */
static void tt__shown_number(double value, const char *shown, char *num, size_t n) {
  if (shown) {
    snprintf(num, n, "\"%s\"", shown);
    return;
  }
  snprintf(num, n, "%g", value);
  if (strtod(num, NULL) != value && isfinite(value)) snprintf(num, n, "%.17g", value);
}

/* Sets parameter `index` to the number `value` (`shown`: how the caller wrote it, for the
 * messages; NULL: the number). The messages are formatted only on error: this is every
 * predictor's and tuner's way of setting a configuration, and formatting them up front (two
 * snprintf, a strtod and the range) cost about 1 us per parameter on every call. */
static tt_status tt__set_number(tt_config *config, size_t index, double value, const char *shown) {
  const tt_space *s = config->space;
  const tt__param *p = &s->params[index];
  char num[64], what[1024];
  switch (p->type) {
  case TT_PARAM_INT:
    if (!isfinite(value) || value != floor(value)) {
      tt__shown_number(value, shown, num, sizeof num);
      tt__format_range(p, what, sizeof what);
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: %s is not an integer in %s", s->plugin,
                          p->name, num, what);
    }
    /* Compare as doubles first so the int64 conversion below cannot overflow (2^63
       * itself is not representable), then exactly as integers. */
    if (value < (double)p->imin || value > (double)p->imax || value >= 0x1p63 ||
        (int64_t)value < p->imin || (int64_t)value > p->imax) {
      tt__shown_number(value, shown, num, sizeof num);
      tt__format_range(p, what, sizeof what);
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: %s is out of range %s", s->plugin,
                          p->name, num, what);
    }
    config->values[index] = tt__int_value((int64_t)value);
    return TT_OK;
  case TT_PARAM_FLOAT:
    if (!isfinite(value)) {
      tt__shown_number(value, shown, num, sizeof num);
      tt__format_range(p, what, sizeof what);
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: %s is not a finite number in %s",
                          s->plugin, p->name, num, what);
    }
    if (value < p->fmin || value > p->fmax) {
      tt__shown_number(value, shown, num, sizeof num);
      tt__format_range(p, what, sizeof what);
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: %s is out of range %s", s->plugin,
                          p->name, num, what);
    }
    config->values[index] = tt__float_value(value);
    return TT_OK;
  default:
    if (p->nom_kind != TT_VALUE_STRING)
      for (size_t k = 0; k < p->nom_count; k++)
        if ((double)p->nom_ints[k] == value) {
          config->values[index] = tt__nom_value(p, k);
          return TT_OK;
        }
    tt__shown_number(value, shown, num, sizeof num);
    tt__format_nom_values(p, what, sizeof what);
    if (p->nom_kind == TT_VALUE_STRING)
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          "%s.%s: %s is not one of %s (a string parameter; set it by "
                          "name or by index)",
                          s->plugin, p->name, num, what);
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: %s is not one of %s", s->plugin, p->name,
                        num, what);
  }
}

tt_status tt_config_set_number(tt_config *config, size_t index, double value) {
  if (!config) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_config_set_number: config is NULL");
  if (index >= config->space->count)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_config_set_number: %s: parameter index %zu is out of range "
                        "(the space has %zu parameters)",
                        config->space->plugin, index, config->space->count);
  return tt__set_number(config, index, value, NULL);
}

tt_status tt_config_set_index(tt_config *config, size_t index, size_t nom_index) {
  if (!config) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_config_set_index: config is NULL");
  const tt_space *s = config->space;
  if (index >= s->count)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_config_set_index: %s: parameter index %zu is out of range "
                        "(the space has %zu parameters)",
                        s->plugin, index, s->count);
  const tt__param *p = &s->params[index];
  if (p->type != TT_PARAM_NOM)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_config_set_index: %s.%s is not a NOM parameter (use "
                        "tt_config_set_number)",
                        s->plugin, p->name);
  if (nom_index >= p->nom_count)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_config_set_index: %s.%s: index %zu is out of range [0, %zu]", s->plugin,
                        p->name, nom_index, p->nom_count - 1);
  config->values[index] = tt__nom_value(p, nom_index);
  return TT_OK;
}

/* Parses all of `t` (already trimmed) as a number; 0 on success. */
static int tt__parse_number(const char *t, double *out) {
  if (!t[0]) return -1;
  char *end;
  errno = 0;
  /* strtoll first: exact for integers beyond 2^53, where strtod would round. */
  long long ll = strtoll(t, &end, 10);
  if (*end == '\0' && errno == 0) {
    *out = (double)ll;
    return 0;
  }
  errno = 0;
  double d = strtod(t, &end);
  if (*end != '\0' || end == t) return -1;
  *out = d;
  return 0;
}

tt_status tt_config_set_string(tt_config *config, const char *name, const char *text) {
  if (!config) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_config_set_string: config is NULL");
  const tt_space *s = config->space;
  int idx = tt_space_find(s, name);
  if (idx < 0) {
    char hint[1024];
    tt__space_unknown_hint(s, name, hint, sizeof hint);
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: unknown parameter \"%s\" (%s)", s->plugin,
                        name ? name : "(null)", hint);
  }
  const tt__param *p = &s->params[idx];
  if (!text)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: value text is NULL", s->plugin, p->name);
  /* Trim surrounding blanks: "--set a= 4" and shell quoting easily add them. */
  char buf[512];
  while (isspace((unsigned char)*text)) text++;
  size_t n = strlen(text);
  while (n && isspace((unsigned char)text[n - 1])) n--;
  if (n >= sizeof buf)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: value text is too long (%zu chars)",
                        s->plugin, p->name, n);
  memcpy(buf, text, n);
  buf[n] = '\0';

  char what[1024];
  if (p->type == TT_PARAM_NOM && p->nom_kind == TT_VALUE_STRING) {
    for (size_t k = 0; k < p->nom_count; k++)
      if (strcmp(p->nom_strings[k], buf) == 0) {
        config->values[idx] = tt__nom_value(p, k);
        return TT_OK;
      }
    tt__format_nom_values(p, what, sizeof what);
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: \"%s\" is not one of %s", s->plugin,
                        p->name, buf, what);
  }
  if (p->type == TT_PARAM_NOM && p->nom_kind == TT_VALUE_BOOL) {
    /* "1"/"0" are accepted too, matching tt_config_set_number on a bool. */
    int b = -1;
    if (strcmp(buf, "true") == 0 || strcmp(buf, "1") == 0) b = 1;
    if (strcmp(buf, "false") == 0 || strcmp(buf, "0") == 0) b = 0;
    if (b < 0) {
      tt__format_nom_values(p, what, sizeof what);
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: \"%s\" is not one of %s", s->plugin,
                          p->name, buf, what);
    }
    config->values[idx] = tt__nom_value(p, (size_t)b);
    return TT_OK;
  }
  double v;
  if (tt__parse_number(buf, &v) != 0) {
    if (p->type == TT_PARAM_NOM) {
      tt__format_nom_values(p, what, sizeof what);
      return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: \"%s\" is not one of %s", s->plugin,
                          p->name, buf, what);
    }
    tt__format_range(p, what, sizeof what);
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s.%s: \"%s\" is not %s in %s", s->plugin,
                        p->name, buf, p->type == TT_PARAM_INT ? "an integer" : "a number", what);
  }
  return tt__set_number(config, (size_t)idx, v, buf);
}

/* Clamps u to [0, 1]; NaN becomes 0 so that from_unit always yields a valid value. */
static double tt__clamp01(double u) {
  if (!(u >= 0.0)) return 0.0;
  return u > 1.0 ? 1.0 : u;
}

void tt_config_to_unit(const tt_config *config, double *out) {
  if (!config || !out) return;
  const tt_space *s = config->space;
  for (size_t i = 0; i < s->count; i++) {
    const tt__param *p = &s->params[i];
    const tt_value *v = &config->values[i];
    double u;
    if (p->type == TT_PARAM_INT) {
      /* Degenerate ranges map to the middle, like a one-value NOM. */
      u = p->imax > p->imin ? ((double)v->i - (double)p->imin) / ((double)p->imax - (double)p->imin)
                            : 0.5;
    } else if (p->type == TT_PARAM_FLOAT) {
      if (p->fmax <= p->fmin) u = 0.5;
      else if (p->log) u = (log(v->f) - log(p->fmin)) / (log(p->fmax) - log(p->fmin));
      else u = (v->f - p->fmin) / (p->fmax - p->fmin);
    } else {
      u = ((double)v->index + 0.5) / (double)p->nom_count;
    }
    out[i] = tt__clamp01(u);
  }
}

void tt_config_from_unit(tt_config *config, const double *unit) {
  if (!config || !unit) return;
  const tt_space *s = config->space;
  for (size_t i = 0; i < s->count; i++) {
    const tt__param *p = &s->params[i];
    double u = tt__clamp01(unit[i]);
    if (p->type == TT_PARAM_FLOAT && (u == 0.0 || u == 1.0)) {
      /* Faces map exactly to the bounds; exp(log(min)) need not give min back. */
      config->values[i] = tt__float_value(u == 0.0 ? p->fmin : p->fmax);
    } else if (p->type == TT_PARAM_INT) {
      double span = (double)p->imax - (double)p->imin;
      int64_t x = p->imin + (int64_t)llround(u * span);
      /* Large int64 spans lose precision in double; keep the result in range. */
      if (x < p->imin) x = p->imin;
      if (x > p->imax) x = p->imax;
      config->values[i] = tt__int_value(x);
    } else if (p->type == TT_PARAM_FLOAT) {
      double x;
      if (p->fmax <= p->fmin) x = p->fmin;
      else if (p->log) x = exp(log(p->fmin) + u * (log(p->fmax) - log(p->fmin)));
      else x = p->fmin + u * (p->fmax - p->fmin);
      /* Rounding in exp/log can step just outside the bounds. */
      if (x < p->fmin) x = p->fmin;
      if (x > p->fmax) x = p->fmax;
      config->values[i] = tt__float_value(x);
    } else {
      size_t k = (size_t)floor(u * (double)p->nom_count);
      if (k >= p->nom_count) k = p->nom_count - 1;
      config->values[i] = tt__nom_value(p, k);
    }
  }
}

/* ---- subsets (tuning a few parameters of a larger space) ---- */

/* Adds to `dst` a copy of parameter `i` of `src` whose default is `def`. */
static int tt__copy_param(tt_space *dst, const tt_space *src, size_t i, tt_value def) {
  const tt__param *p = tt__param_at(src, i);
  const char *desc = tt_space_description(src, i);
  switch (p->type) {
  case TT_PARAM_INT: {
    int64_t lo = 0, hi = 0;
    tt__space_int_range(src, i, &lo, &hi);
    return tt_space_add_int(dst, p->name, lo, hi, def.i, desc);
  }
  case TT_PARAM_FLOAT:
    return tt_space_add_float(dst, p->name, tt_space_min(src, i), tt_space_max(src, i), def.f,
                              tt_space_is_log(src, i), desc);
  case TT_PARAM_NOM: {
    size_t n = tt_space_nom_count(src, i);
    size_t d = def.index >= 0 ? (size_t)def.index : 0;
    if (p->nom_kind == TT_VALUE_BOOL) return tt_space_add_nom_bool(dst, p->name, (int)d, desc);
    if (p->nom_kind == TT_VALUE_STRING) {
      const char **vals = malloc(n * sizeof *vals);
      if (!vals) return -1;
      for (size_t k = 0; k < n; k++) vals[k] = tt_space_nom_value(src, i, k).s;
      int r = tt_space_add_nom_string(dst, p->name, vals, n, d, desc);
      free(vals);
      return r;
    }
    int64_t *vals = malloc(n * sizeof *vals);
    if (!vals) return -1;
    for (size_t k = 0; k < n; k++) vals[k] = tt_space_nom_value(src, i, k).i;
    int r = tt_space_add_nom_int(dst, p->name, vals, n, d, desc);
    free(vals);
    return r;
  }
  }
  return -1;
}

static tt_status tt__copy_marking(tt_space *sub, const tt_space *space, const char *const *names,
                                  size_t count, const tt_config *base);

tt_space *tt_space_subset(const tt_space *space, const char *const *names, size_t count,
                          const tt_config *base) {
  if (!space || (count && !names))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_space_subset: no space or names"), NULL;
  if (base && tt_config_space(base) != space)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_space_subset: %s: the base configuration belongs to another space",
                        space->plugin),
           NULL;
  tt_space *sub = tt_space_create(space->plugin, space->version);
  if (!sub) return NULL;
  for (size_t k = 0; k < count; k++) {
    int i = tt_space_find(space, names[k]);
    if (i < 0) {
      char hint[1024];
      tt__space_unknown_hint(space, names[k], hint, sizeof hint);
      tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: no parameter \"%s\" to tune (%s)", space->plugin,
                   names[k], hint);
      tt_space_destroy(sub);
      return NULL;
    }
    tt_value def = base ? tt_config_get(base, (size_t)i) : tt_space_default(space, (size_t)i);
    if (tt__copy_param(sub, space, (size_t)i, def) < 0) {
      tt_space_destroy(sub);
      return NULL;
    }
  }
  for (size_t k = 0; k < tt__space_constraint_count(space); k++)
    tt_space_add_constraint_text(sub, tt__space_constraint(space, k));
  if (tt__copy_marking(sub, space, names, count, base) != TT_OK) {
    tt_space_destroy(sub);
    return NULL;
  }
  return sub;
}

int tt_config_assign(tt_config *dst, const tt_config *src) {
  if (!dst || !src) return -1;
  const tt_space *ds = tt_config_space(dst), *ss = tt_config_space(src);
  int copied = 0;
  for (size_t k = 0; k < tt_space_count(ss); k++) {
    int i = tt_space_find(ds, tt_space_name(ss, k));
    if (i < 0 || tt_space_type(ds, (size_t)i) != tt_space_type(ss, k)) continue;
    tt_value v = tt_config_get(src, k);
    tt_status st = v.index >= 0 ? tt_config_set_index(dst, (size_t)i, (size_t)v.index)
                                : tt_config_set_number(dst, (size_t)i,
                                                       v.kind == TT_VALUE_INT ? (double)v.i : v.f);
    if (st != TT_OK) return -1;
    copied++;
  }
  return copied;
}

/* ---- not tunable, active only under a condition ---- */

/* Refuses changes to a published space (configurations exist): they size and read it. */
static tt_status tt__check_mutable(const tt_space *space, size_t index, const char *fn) {
  if (!space) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: space is NULL", fn);
  if (index >= space->count)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "%s: %s: parameter index %zu is out of range "
                        "(the space has %zu parameters)",
                        fn, space->plugin, index, space->count);
  if (atomic_load_explicit(&space->frozen, memory_order_relaxed))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "%s: %s.%s: configurations already exist (a "
                        "space is immutable once published)",
                        fn, space->plugin, space->params[index].name);
  return TT_OK;
}

tt_status tt_space_set_tunable(tt_space *space, size_t index, int tunable) {
  tt_status st = tt__check_mutable(space, index, "tt_space_set_tunable");
  if (st != TT_OK) return st;
  space->params[index].untunable = !tunable;
  return TT_OK;
}

int tt_space_is_tunable(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  return p && !p->untunable;
}

tt_status tt_space_set_motion_only(tt_space *space, size_t index, int motion_only) {
  tt_status st = tt__check_mutable(space, index, "tt_space_set_motion_only");
  if (st != TT_OK) return st;
  space->params[index].motion_only = !!motion_only;
  return TT_OK;
}

int tt_space_is_motion_only(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  return p && p->motion_only;
}

/* Non-zero if `anc` is `index` or one of its ancestors through conditions. */
static int tt__is_ancestor(const tt_space *space, size_t anc, size_t index, unsigned depth) {
  if (anc == index) return 1;
  if (depth > space->count) return 1; /* a cycle already: refuse anything more */
  const tt__param *p = &space->params[index];
  for (size_t k = 0; k < p->ncond; k++)
    if (tt__is_ancestor(space, anc, p->conds[k].parent, depth + 1)) return 1;
  return 0;
}

/* Appends a condition with an `allowed` mask of the parent's possible values (copied). */
static tt_status tt__push_condition(tt_space *space, size_t index, size_t parent,
                                    const unsigned char *allowed) {
  tt__param *p = &space->params[index];
  size_t n = space->params[parent].nom_count;
  for (size_t k = 0; k < p->ncond; k++) /* a second condition on one parent: both hold */
    if (p->conds[k].parent == parent) {
      for (size_t v = 0; v < n; v++) p->conds[k].allowed[v] &= allowed[v];
      return TT_OK;
    }
  struct tt__cond *nc = realloc(p->conds, (p->ncond + 1) * sizeof *nc);
  if (!nc) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", space->plugin);
  p->conds = nc;
  unsigned char *mask = malloc(n);
  if (!mask) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", space->plugin);
  memcpy(mask, allowed, n);
  p->conds[p->ncond].parent = parent;
  p->conds[p->ncond].allowed = mask;
  p->ncond++;
  return TT_OK;
}

/* Possible-value index of `text` in NOM parameter `p` (as tt_config_set_string reads it), or
 * -1. */
static int tt__nom_index_of(const tt__param *p, const char *text) {
  for (size_t k = 0; k < p->nom_count; k++) {
    if (p->nom_kind == TT_VALUE_STRING) {
      if (!strcmp(p->nom_strings[k], text)) return (int)k;
    } else if (p->nom_kind == TT_VALUE_BOOL) {
      int b = !strcmp(text, "true") || !strcmp(text, "1")    ? 1
              : !strcmp(text, "false") || !strcmp(text, "0") ? 0
                                                             : -1;
      if (b >= 0 && p->nom_ints[k] == b) return (int)k;
    } else {
      char *end;
      errno = 0;
      long long v = strtoll(text, &end, 10);
      if (*text && !*end && !errno && p->nom_ints[k] == v) return (int)k;
    }
  }
  return -1;
}

tt_status tt_space_add_condition(tt_space *space, size_t index, const char *parent,
                                 const char *const *values, size_t count) {
  tt_status st = tt__check_mutable(space, index, "tt_space_add_condition");
  if (st != TT_OK) return st;
  const char *child = space->params[index].name;
  int q = tt_space_find(space, parent);
  if (q < 0) {
    char hint[1024];
    tt__space_unknown_hint(space, parent, hint, sizeof hint);
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_space_add_condition: %s.%s: no parameter "
                        "\"%s\" to depend on (%s)",
                        space->plugin, child, parent ? parent : "(null)", hint);
  }
  const tt__param *pp = &space->params[q];
  if (pp->type != TT_PARAM_NOM)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_space_add_condition: %s.%s: the parent %s "
                        "is not a NOM parameter (conditions name possible values)",
                        space->plugin, child, pp->name);
  if (tt__is_ancestor(space, index, (size_t)q, 0))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_space_add_condition: %s.%s: depending on "
                        "%s would make the parameter its own ancestor",
                        space->plugin, child, pp->name);
  if (!values || !count)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_space_add_condition: %s.%s: no values of "
                        "%s given (expected at least one)",
                        space->plugin, child, pp->name);
  unsigned char *allowed = calloc(pp->nom_count, 1);
  if (!allowed) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", space->plugin);
  for (size_t k = 0; k < count; k++) {
    int v = values[k] ? tt__nom_index_of(pp, values[k]) : -1;
    if (v < 0) {
      char what[1024];
      tt__format_nom_values(pp, what, sizeof what);
      free(allowed);
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          "tt_space_add_condition: %s.%s: \"%s\" is "
                          "not a value of %s (expected one of %s)",
                          space->plugin, child, values[k] ? values[k] : "(null)", pp->name, what);
    }
    allowed[v] = 1;
  }
  st = tt__push_condition(space, index, (size_t)q, allowed);
  free(allowed);
  return st;
}

size_t tt_space_condition_count(const tt_space *space, size_t index) {
  const tt__param *p = tt__param_at(space, index);
  return p ? p->ncond : 0;
}

int tt_space_condition_parent(const tt_space *space, size_t index, size_t k) {
  const tt__param *p = tt__param_at(space, index);
  return p && k < p->ncond ? (int)p->conds[k].parent : -1;
}

int tt_space_condition_allows(const tt_space *space, size_t index, size_t k, size_t nom_index) {
  const tt__param *p = tt__param_at(space, index);
  if (!p || k >= p->ncond) return 0;
  const tt__param *pp = &space->params[p->conds[k].parent];
  return nom_index < pp->nom_count && p->conds[k].allowed[nom_index];
}

/* Active under the values of `c`: every condition holds and every parent is active. */
static int tt__active(const tt_config *c, size_t index, unsigned depth) {
  const tt__param *p = &c->space->params[index];
  if (depth > c->space->count) return 1; /* cycles are refused at add time */
  for (size_t k = 0; k < p->ncond; k++) {
    size_t q = p->conds[k].parent;
    int32_t v = c->values[q].index;
    if (v < 0 || (size_t)v >= c->space->params[q].nom_count || !p->conds[k].allowed[v]) return 0;
    if (!tt__active(c, q, depth + 1)) return 0;
  }
  return 1;
}

int tt_config_is_active(const tt_config *config, size_t index) {
  if (!config || index >= config->space->count) return 0;
  return tt__active(config, index, 0);
}

/* Same value of parameter `p` (as tt_config_equal compares). */
static int tt__same_value(const tt__param *p, const tt_value *a, const tt_value *b) {
  switch (p->type) {
  case TT_PARAM_INT: return a->i == b->i;
  case TT_PARAM_FLOAT: return a->f == b->f;
  default: return a->index == b->index;
  }
}

int tt_config_canonicalize(tt_config *config, const tt_config *base) {
  if (!config) return 0;
  const tt_space *s = config->space;
  if (base && base->space != s) base = NULL;
  int changed = 0;
  /* settings first: an inactive child of a reset setting is judged on the reset value */
  for (size_t i = 0; i < s->count; i++) {
    const tt__param *p = &s->params[i];
    if (!p->untunable) continue;
    tt_value v = base ? base->values[i] : tt__param_default(p);
    if (!tt__same_value(p, &config->values[i], &v)) config->values[i] = v, changed++;
  }
  /* then what the values leave inactive: judged all at once, before any is reset (a reset
   * parent is inactive itself, so its children stay inactive) */
  unsigned char local[256], *inactive = s->count <= sizeof local ? local : malloc(s->count);
  if (!inactive) return changed;
  for (size_t i = 0; i < s->count; i++)
    inactive[i] = s->params[i].ncond && !tt__active(config, i, 0);
  for (size_t i = 0; i < s->count; i++) {
    if (!inactive[i]) continue;
    const tt__param *p = &s->params[i];
    tt_value v = base ? base->values[i] : tt__param_default(p);
    if (!tt__same_value(p, &config->values[i], &v)) config->values[i] = v, changed++;
  }
  if (inactive != local) free(inactive);
  return changed;
}

/* A subset keeps what the full space says about its parameters: not tunable stays so; a
 * condition on a parameter of the subset is copied, one on a parameter left out is decided
 * by that parameter's fixed value in `base` (or its default): it holds, and is dropped, or
 * it fails, and the parameter can never act in the subset, so it is marked not tunable. */
static tt_status tt__copy_marking(tt_space *sub, const tt_space *space, const char *const *names,
                                  size_t count, const tt_config *base) {
  tt_config *fixed = NULL;
  tt_status st = TT_OK;
  for (size_t k = 0; k < count && st == TT_OK; k++) {
    size_t i = (size_t)tt_space_find(space, names[k]);
    const tt__param *p = &space->params[i];
    int never = p->untunable;
    for (size_t c = 0; c < p->ncond && st == TT_OK; c++) {
      size_t q = p->conds[c].parent;
      int qs = tt_space_find(sub, space->params[q].name);
      if (qs >= 0) {
        st = tt__push_condition(sub, k, (size_t)qs, p->conds[c].allowed);
        continue;
      }
      if (!fixed) {
        fixed = base ? tt_config_clone(base) : tt_config_create(space);
        if (!fixed) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", space->plugin);
      }
      if (fixed) {
        int32_t v = fixed->values[q].index;
        if (v < 0 || !p->conds[c].allowed[v] || !tt__active(fixed, q, 0)) never = 1;
      }
    }
    sub->params[k].untunable = never;
    sub->params[k].motion_only = p->motion_only;
  }
  tt_config_destroy(fixed);
  return st;
}
