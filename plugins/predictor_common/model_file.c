/* Model files of the predictor plugins: see model_file.h for the layout. */
#include "model_file.h"

#include <tunetrace/file.h>

#include <tt_util/hash.h>

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- writer ---- */

static void tt__pm_put(tt__pm_writer *w, const void *p, size_t n) {
  if (w->failed) return;
  if (w->len + n > w->cap) {
    size_t cap = w->cap ? w->cap : 4096;
    while (cap < w->len + n) cap *= 2;
    unsigned char *d = realloc(w->data, cap);
    if (!d) {
      w->failed = 1;
      return;
    }
    w->data = d;
    w->cap = cap;
  }
  memcpy(w->data + w->len, p, n);
  w->len += n;
}

void tt__pm_put_u32(tt__pm_writer *w, uint32_t v) {
  unsigned char b[4];
  for (int i = 0; i < 4; i++) b[i] = (unsigned char)(v >> (8 * i));
  tt__pm_put(w, b, 4);
}

void tt__pm_put_u64(tt__pm_writer *w, uint64_t v) {
  unsigned char b[8];
  for (int i = 0; i < 8; i++) b[i] = (unsigned char)(v >> (8 * i));
  tt__pm_put(w, b, 8);
}

void tt__pm_put_f64(tt__pm_writer *w, double v) {
  uint64_t u;
  memcpy(&u, &v, 8);
  tt__pm_put_u64(w, u);
}

void tt__pm_put_f64s(tt__pm_writer *w, const double *v, size_t n) {
  for (size_t i = 0; i < n; i++) tt__pm_put_f64(w, v[i]);
}

void tt__pm_put_str(tt__pm_writer *w, const char *s) {
  size_t n = s ? strlen(s) : 0;
  tt__pm_put_u32(w, (uint32_t)n);
  if (n) tt__pm_put(w, s, n);
}

/* ---- reader ---- */

void tt__pm_fail(tt__pm_reader *r, const char *fmt, ...) {
  if (r->err[0]) return;
  char msg[400];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  snprintf(r->err, sizeof r->err, "%s: %s (payload offset %zu)", r->path, msg, r->pos);
}

static const unsigned char *tt__pm_take(tt__pm_reader *r, size_t n, const char *what) {
  if (r->err[0]) return NULL;
  if (r->len - r->pos < n) {
    tt__pm_fail(r, "file cut short: %s needs %zu bytes, %zu left", what, n, r->len - r->pos);
    return NULL;
  }
  const unsigned char *p = r->data + r->pos;
  r->pos += n;
  return p;
}

uint32_t tt__pm_get_u32(tt__pm_reader *r, const char *what) {
  const unsigned char *b = tt__pm_take(r, 4, what);
  uint32_t v = 0;
  for (int i = 0; b && i < 4; i++) v |= (uint32_t)b[i] << (8 * i);
  return v;
}

uint64_t tt__pm_get_u64(tt__pm_reader *r, const char *what) {
  const unsigned char *b = tt__pm_take(r, 8, what);
  uint64_t v = 0;
  for (int i = 0; b && i < 8; i++) v |= (uint64_t)b[i] << (8 * i);
  return v;
}

double tt__pm_get_f64(tt__pm_reader *r, const char *what) {
  uint64_t u = tt__pm_get_u64(r, what);
  double v;
  memcpy(&v, &u, 8);
  return v;
}

void tt__pm_get_f64s(tt__pm_reader *r, double *v, size_t n, const char *what) {
  for (size_t i = 0; i < n; i++) v[i] = tt__pm_get_f64(r, what);
}

uint64_t tt__pm_get_count(tt__pm_reader *r, uint64_t max, size_t elem, const char *what) {
  uint64_t n = tt__pm_get_u64(r, what);
  if (r->err[0]) return 0;
  if (n > max) {
    tt__pm_fail(r, "%s is %llu, more than the %llu this format allows", what, (unsigned long long)n,
                (unsigned long long)max);
    return 0;
  }
  if (elem && n > (r->len - r->pos) / elem) {
    tt__pm_fail(r, "file cut short: %llu %s need %llu bytes, %zu left", (unsigned long long)n, what,
                (unsigned long long)(n * elem), r->len - r->pos);
    return 0;
  }
  return n;
}

char *tt__pm_get_str(tt__pm_reader *r, size_t max, const char *what) {
  uint32_t n = tt__pm_get_u32(r, what);
  if (r->err[0]) return NULL;
  if (n > max) {
    tt__pm_fail(r, "%s is %u bytes long, more than %zu", what, n, max);
    return NULL;
  }
  const unsigned char *p = tt__pm_take(r, n, what);
  if (!p) return NULL;
  if (memchr(p, 0, n)) {
    tt__pm_fail(r, "%s contains a NUL byte", what);
    return NULL;
  }
  char *s = malloc((size_t)n + 1);
  if (!s) {
    tt__pm_fail(r, "out of memory reading %s", what);
    return NULL;
  }
  memcpy(s, p, n);
  s[n] = 0;
  return s;
}

/* ---- common header ---- */

#define TT__PM_MAX_TEXT (1u << 20)
#define TT__PM_MAX_STATE_DIM 4096u

void tt__pm_header_free(tt__pm_header *h) {
  if (!h) return;
  free(h->kind);
  free(h->plugin_version);
  free(h->state_space);
  if (h->state_names)
    for (uint32_t i = 0; i < h->state_dim; i++) free(h->state_names[i]);
  free(h->state_names);
  free(h->target);
  free(h->settings);
  memset(h, 0, sizeof *h);
}

void tt__pm_put_header(tt__pm_writer *w, const tt__pm_header *h) {
  tt__pm_put_str(w, h->kind);
  tt__pm_put_str(w, h->plugin_version);
  tt__pm_put_str(w, h->state_space);
  tt__pm_put_u32(w, h->state_dim);
  tt__pm_put_u32(w, h->state_names ? 1u : 0u);
  for (uint32_t i = 0; h->state_names && i < h->state_dim; i++)
    tt__pm_put_str(w, h->state_names[i]);
  tt__pm_put_str(w, h->target);
  tt__pm_put_str(w, h->settings);
}

int tt__pm_get_header(tt__pm_reader *r, tt__pm_header *h) {
  memset(h, 0, sizeof *h);
  h->kind = tt__pm_get_str(r, 256, "the model kind");
  h->plugin_version = tt__pm_get_str(r, 256, "the plugin version");
  h->state_space = tt__pm_get_str(r, TT__PM_MAX_TEXT, "the state space");
  h->state_dim = tt__pm_get_u32(r, "the state dimension");
  if (!r->err[0] && (h->state_dim < 1 || h->state_dim > TT__PM_MAX_STATE_DIM))
    tt__pm_fail(r, "state dimension %u outside [1, %u]", h->state_dim, TT__PM_MAX_STATE_DIM);
  uint32_t names = tt__pm_get_u32(r, "the state-names flag");
  if (!r->err[0] && names > 1) tt__pm_fail(r, "state-names flag %u is neither 0 nor 1", names);
  if (!r->err[0] && names) {
    h->state_names = calloc(h->state_dim, sizeof *h->state_names);
    if (!h->state_names) tt__pm_fail(r, "out of memory");
    for (uint32_t i = 0; !r->err[0] && i < h->state_dim; i++)
      h->state_names[i] = tt__pm_get_str(r, 256, "a state name");
  }
  h->target = tt__pm_get_str(r, TT__PM_MAX_TEXT, "the target space");
  h->settings = tt__pm_get_str(r, TT__PM_MAX_TEXT, "the settings");
  if (r->err[0]) {
    tt__pm_header_free(h);
    return -1;
  }
  return 0;
}

/* ---- spaces and configurations ---- */

/* Appends printf output to a malloc'ed string; returns it (NULL on failure, freeing). */
static char *tt__pm_cat(char *s, size_t *len, size_t *cap, const char *fmt, ...) {
  if (!s) return NULL;
  for (;;) {
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(s + *len, *cap - *len, fmt, ap);
    va_end(ap);
    if (n < 0) {
      free(s);
      return NULL;
    }
    if ((size_t)n < *cap - *len) {
      *len += (size_t)n;
      return s;
    }
    size_t cap2 = *cap * 2 + (size_t)n;
    char *t = realloc(s, cap2);
    if (!t) {
      free(s);
      return NULL;
    }
    s = t;
    *cap = cap2;
  }
}

char *tt__pm_space_signature(const tt_space *space) {
  size_t len = 0, cap = 256;
  char *s = malloc(cap);
  if (!s) return NULL;
  s[0] = 0;
  s = tt__pm_cat(s, &len, &cap, "%s:", tt_space_plugin(space) ? tt_space_plugin(space) : "");
  for (size_t i = 0; s && i < tt_space_count(space); i++) {
    const char *name = tt_space_name(space, i);
    switch (tt_space_type(space, i)) {
    case TT_PARAM_INT:
      s = tt__pm_cat(s, &len, &cap, "%s %s INT[%.17g,%.17g]", i ? ";" : "", name,
                     tt_space_min(space, i), tt_space_max(space, i));
      break;
    case TT_PARAM_FLOAT:
      s = tt__pm_cat(s, &len, &cap, "%s %s FLOAT[%.17g,%.17g]%s", i ? ";" : "", name,
                     tt_space_min(space, i), tt_space_max(space, i),
                     tt_space_is_log(space, i) ? " log" : "");
      break;
    case TT_PARAM_NOM: {
      s = tt__pm_cat(s, &len, &cap, "%s %s NOM{", i ? ";" : "", name);
      for (size_t k = 0; s && k < tt_space_nom_count(space, i); k++) {
        tt_value v = tt_space_nom_value(space, i, k);
        const char *sep = k ? "," : "";
        if (v.kind == TT_VALUE_STRING) s = tt__pm_cat(s, &len, &cap, "%s%s", sep, v.s);
        else if (v.kind == TT_VALUE_BOOL)
          s = tt__pm_cat(s, &len, &cap, "%s%s", sep, v.i ? "true" : "false");
        else if (v.kind == TT_VALUE_INT)
          s = tt__pm_cat(s, &len, &cap, "%s%lld", sep, (long long)v.i);
        else s = tt__pm_cat(s, &len, &cap, "%s%.17g", sep, v.f);
      }
      s = tt__pm_cat(s, &len, &cap, "}");
      break;
    }
    }
  }
  return s;
}

void tt__pm_signature_diff(const char *a, const char *b, char *buf, size_t n) {
  /* compare parameter by parameter (';'-separated) */
  const char *pa = a, *pb = b;
  for (;;) {
    size_t la = strcspn(pa, ";"), lb = strcspn(pb, ";");
    if (la != lb || strncmp(pa, pb, la)) {
      snprintf(buf, n, "\"%.*s\" vs \"%.*s\"", (int)(la < 120 ? la : 120), pa,
               (int)(lb < 120 ? lb : 120), pb);
      return;
    }
    if (!pa[la] || !pb[lb]) {
      snprintf(buf, n, "%s",
               !pa[la] && !pb[lb] ? "(same)"
               : !pa[la]          ? "the file's space has "
                                    "fewer parameters"
                                  : "the file's space has more parameters");
      return;
    }
    pa += la + 1;
    pb += lb + 1;
  }
}

void tt__pm_config_values(const tt_config *c, double *out) {
  const tt_space *s = tt_config_space(c);
  for (size_t i = 0; i < tt_space_count(s); i++) {
    tt_value v = tt_config_get(c, i);
    out[i] = tt_space_type(s, i) == TT_PARAM_NOM ? (double)v.index : v.f;
  }
}

int tt__pm_config_from_values(tt_config *c, const double *v, char *why, size_t n) {
  const tt_space *s = tt_config_space(c);
  for (size_t i = 0; i < tt_space_count(s); i++) {
    tt_status st;
    if (tt_space_type(s, i) == TT_PARAM_NOM) {
      if (!(v[i] >= 0) || v[i] >= (double)tt_space_nom_count(s, i) || v[i] != floor(v[i])) {
        snprintf(why, n, "parameter %s: possible-value index %.17g out of range [0, %zu)",
                 tt_space_name(s, i), v[i], tt_space_nom_count(s, i));
        return -1;
      }
      st = tt_config_set_index(c, i, (size_t)v[i]);
    } else {
      st = tt_config_set_number(c, i, v[i]);
    }
    if (st != TT_OK) {
      snprintf(why, n, "parameter %s: value %.17g: %s", tt_space_name(s, i), v[i], tt_last_error());
      return -1;
    }
  }
  return 0;
}

/* ---- files ---- */

tt_status tt__pm_save(const char *who, const char *path, uint32_t version, const tt__pm_writer *w) {
  if (w->failed)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory writing model %s", who, path);
  size_t total = TT__PM_HEADER_BYTES + w->len + 8;
  unsigned char *buf = malloc(total);
  if (!buf)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory writing model %s", who, path);
  memcpy(buf, TT__PM_MAGIC, 8);
  for (int i = 0; i < 4; i++) buf[8 + i] = (unsigned char)(version >> (8 * i));
  memset(buf + 12, 0, 4);
  for (int i = 0; i < 8; i++) buf[16 + i] = (unsigned char)((uint64_t)w->len >> (8 * i));
  if (w->len) memcpy(buf + TT__PM_HEADER_BYTES, w->data, w->len);
  uint64_t h = tt__fnv1a64(TT__FNV1A64_OFFSET, buf, TT__PM_HEADER_BYTES + w->len);
  for (int i = 0; i < 8; i++) buf[TT__PM_HEADER_BYTES + w->len + i] = (unsigned char)(h >> (8 * i));
  /* a temporary file renamed over the target: a failed save leaves an existing model */
  tt_status st = tt_file_write_atomic(path, buf, total);
  free(buf);
  if (st != TT_OK)
    return tt_set_error(st, "%s: cannot write model %s: %s (an existing file was left as it was)",
                        who, path, tt_last_error());
  return TT_OK;
}

tt_status tt__pm_load(const char *who, const char *who_version, const char *path,
                      uint32_t max_version, unsigned char **payload, size_t *payload_len,
                      uint32_t *version) {
  *payload = NULL;
  *payload_len = 0;
  char *data = NULL;
  size_t size = 0;
  /* regular files only (a FIFO or /dev/zero is an error, not a hang), at most 16 GiB */
  if (tt_file_read(path, "model", (size_t)1 << 34, &data, &size) != TT_OK)
    return tt_set_error(TT_ERR_IO, "%s: cannot open model %s: %s", who, path, tt_last_error());
  unsigned char *buf = malloc(size ? size : 1);
  if (!buf) {
    tt_free(data);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory reading model %s", who, path);
  }
  memcpy(buf, data, size);
  tt_free(data);
  int rerr = 0;
  size_t got = size;
  tt_status rc = TT_OK;
  if (rerr || got != size) {
    rc = tt_set_error(TT_ERR_IO, "%s: cannot read model %s", who, path);
  } else if (size < TT__PM_HEADER_BYTES || memcmp(buf, TT__PM_MAGIC, 8)) {
    rc = tt_set_error(TT_ERR_PARSE, "%s: %s is not a tunetrace predictor model (%s)", who, path,
                      size < 8 ? "shorter than the 8-byte magic"
                               : "no \"TTPMODEL\" magic at the start");
  } else {
    uint32_t v = 0;
    uint64_t n = 0;
    for (int i = 0; i < 4; i++) v |= (uint32_t)buf[8 + i] << (8 * i);
    for (int i = 0; i < 8; i++) n |= (uint64_t)buf[16 + i] << (8 * i);
    /* a newer version: the model kind (the payload's first string, u32 length + bytes)
     * where it can be read, so that a file of another predictor is named as such */
    uint32_t kl = 0;
    if (v > max_version && size >= TT__PM_HEADER_BYTES + 4)
      for (int i = 0; i < 4; i++) kl |= (uint32_t)buf[TT__PM_HEADER_BYTES + i] << (8 * i);
    int other_kind = kl > 0 && kl < 256 && size >= TT__PM_HEADER_BYTES + 4 + (size_t)kl &&
                     (strlen(who) != kl || memcmp(buf + TT__PM_HEADER_BYTES + 4, who, kl)) &&
                     !memchr(buf + TT__PM_HEADER_BYTES + 4, 0, kl);
    if (other_kind) {
      rc = tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "%s: model %s was written by %.*s (format "
                        "version %u), not by %s (load it with --plugin %.*s)",
                        who, path, (int)kl, (const char *)buf + TT__PM_HEADER_BYTES + 4, v, who,
                        (int)kl, (const char *)buf + TT__PM_HEADER_BYTES + 4);
    } else if (v > max_version || v == 0) {
      rc = tt_set_error(TT_ERR_UNSUPPORTED,
                        "%s: model %s has format version %u; this %s %s reads "
                        "versions 1 to %u%s",
                        who, path, v, who, who_version, max_version,
                        v > max_version ? " (written by a newer plugin: update it)" : "");
    } else if (n > size || size - TT__PM_HEADER_BYTES - 8 < n ||
               size != TT__PM_HEADER_BYTES + n + 8) {
      rc = tt_set_error(TT_ERR_PARSE,
                        "%s: model %s is %zu bytes, but its header says %llu "
                        "(file cut short or padded)",
                        who, path, size, (unsigned long long)(TT__PM_HEADER_BYTES + n + 8));
    } else {
      uint64_t stored = 0;
      for (int i = 0; i < 8; i++) stored |= (uint64_t)buf[TT__PM_HEADER_BYTES + n + i] << (8 * i);
      uint64_t h = tt__fnv1a64(TT__FNV1A64_OFFSET, buf, TT__PM_HEADER_BYTES + (size_t)n);
      if (h != stored) {
        rc = tt_set_error(TT_ERR_PARSE,
                          "%s: model %s is corrupt (checksum %016llx, computed "
                          "%016llx)",
                          who, path, (unsigned long long)stored, (unsigned long long)h);
      } else {
        memmove(buf, buf + TT__PM_HEADER_BYTES, (size_t)n);
        *payload = buf;
        *payload_len = (size_t)n;
        *version = v;
        return TT_OK;
      }
    }
  }
  free(buf);
  return rc;
}
