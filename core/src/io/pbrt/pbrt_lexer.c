/* pbrt-v4 importer: the include stack, the tokenizer and the messages (errors as
 * "file:line: ...", warnings once per location through the log host). */
#include "io/pbrt/pbrt_internal.h"
#include "plugin/log.h"

#include <tunetrace/file.h>

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---- messages -------------------------------------------------------------------------- */

/* "file:line: message" as a TT_ERR_PARSE error. */
tt_status tt__perr(const tt__pfile *f, int line, const char *fmt, ...) TT_PRINTF(3, 4);
tt_status tt__perr(const tt__pfile *f, int line, const char *fmt, ...) {
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return tt_set_error(TT_ERR_PARSE, "%s:%d: %s", f ? f->path : "(pbrt)", line, msg);
}

/* One warning per (file:line, key) through the log host, so a shape included twice warns
 * once. */
void tt__pwarn(tt__pp *P, const tt__pfile *f, int line, const char *key, const char *fmt, ...)
    TT_PRINTF(5, 6);
void tt__pstrict(tt__pp *P, const tt__pfile *f, int line, const char *key, const char *fmt, ...) {
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (!P->strict) {
    tt__pwarn(P, f, line, key, "%s (skipped; host --strict refuses it, as pbrt-v4 does)", msg);
    return;
  }
  if (!P->strict_errors++)
    snprintf(P->strict_first, sizeof P->strict_first, "%s:%d: %s", f ? f->path : "(pbrt)", line,
             msg);
  tt__log(TT_LOG_ERROR, "%s:%d: %s", f ? f->path : "(pbrt)", line, msg);
}

tt_status tt__pstrict_result(const tt__pp *P) {
  if (!P->strict_errors) return TT_OK;
  if (P->strict_errors == 1) return tt_set_error(TT_ERR_PARSE, "%s (strict)", P->strict_first);
  return tt_set_error(TT_ERR_PARSE, "%s (strict; and %u more error%s, logged above)",
                      P->strict_first, P->strict_errors - 1, P->strict_errors == 2 ? "" : "s");
}

void tt__pwarn(tt__pp *P, const tt__pfile *f, int line, const char *key, const char *fmt, ...) {
  char id[1200];
  snprintf(id, sizeof id, "%s:%d:%s", f ? f->path : "", line, key ? key : "");
  for (size_t i = 0; i < P->nwarned; i++)
    if (strcmp(P->warned[i], id) == 0) return;
  if (P->nwarned == P->capwarned) {
    size_t nc = P->capwarned ? 2 * P->capwarned : 64;
    char **n = realloc(P->warned, nc * sizeof *n);
    if (!n) return;
    P->warned = n;
    P->capwarned = nc;
  }
  char *dup = tt__strdup(id);
  if (!dup) return;
  P->warned[P->nwarned++] = dup;
  if (P->warnings >= TT__MAX_WARNINGS) {
    P->suppressed++;
    return;
  }
  P->warnings++;
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  tt__log(TT_LOG_WARN, "%s:%d: %s", f ? f->path : "(pbrt)", line, msg);
}

/* ---- small helpers --------------------------------------------------------------------- */

/* Joins a relative path to a directory; absolute paths pass through. */
char *tt__join(const char *dir, const char *rel, size_t rel_len) {
  size_t dl = (rel_len && rel[0] == '/') || !dir ? 0 : strlen(dir);
  char *r = malloc(dl + 1 + rel_len + 1);
  if (!r) return NULL;
  size_t k = 0;
  if (dl) {
    memcpy(r, dir, dl);
    k = dl;
    if (r[k - 1] != '/') r[k++] = '/';
  }
  memcpy(r + k, rel, rel_len);
  r[k + rel_len] = '\0';
  return r;
}

/* Directory part of a path ("." for a bare name). */
static char *tt__dirname(const char *path) {
  char *d = tt__strdup(path);
  if (!d) return NULL;
  char *slash = strrchr(d, '/');
  if (slash == d) slash[1] = '\0';
  else if (slash) *slash = '\0';
  else strcpy(d, ".");
  return d;
}

/* True when the path names a readable regular file (a FIFO is not probed by opening it
 * blocking, and is not one). */
int tt__exists(const char *path) { return tt_file_check_regular(path, NULL) == TT_OK; }

/* Generic growth for the parser's arrays. */
void *tt__grow(void *items, size_t *cap, size_t need, size_t size) {
  if (need <= *cap) return items;
  size_t nc = *cap ? *cap : 8;
  while (nc < need) nc *= 2;
  void *n = realloc(items, nc * size);
  if (n) *cap = nc;
  return n;
}

/* ---- tokenizer ------------------------------------------------------------------------- */

/* Opens a file onto the include stack (parent = current file). */
tt_status tt__push_file(tt__pp *P, const char *path, const tt__pfile *from, int from_line) {
  char *buf = NULL;
  size_t len = 0;
  tt_status rst = tt__read_file(path, &buf, &len);
  if (rst != TT_OK) {
    /* inside an Include, name the including file and line instead */
    if (from && rst == TT_ERR_IO) {
      char msg[1024];
      snprintf(msg, sizeof msg, "%s", tt_last_error());
      return tt__perr(from, from_line, "cannot open included file \"%s\" (%s)", path, msg);
    }
    return rst;
  }
  tt__pfile *pf = calloc(1, sizeof *pf);
  if (!pf) {
    free(buf);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
  }
  pf->path = tt__strdup(path);
  pf->dir = tt__dirname(path);
  pf->text = buf;
  pf->len = len;
  pf->line = 1;
  if (!pf->path || !pf->dir) {
    free(pf->path);
    free(pf->dir);
    free(buf);
    free(pf);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
  }
  pf->parent = P->cur;
  pf->next = P->files;
  P->files = pf;
  P->cur = pf;
  P->depth++;
  return TT_OK;
}

/* Reads the next token, leaving finished include files for their includer. */
static tt_status tt__lex(tt__pp *P, tt__tok *t) {
  for (;;) {
    tt__pfile *f = P->cur;
    memset(t, 0, sizeof *t);
    if (!f) {
      t->kind = TK_EOF;
      return TT_OK;
    }
    const char *s = f->text;
    size_t i = f->pos, n = f->len;
    for (;;) {
      while (i < n && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r' || s[i] == '\n' ||
                       s[i] == '\f' || s[i] == '\v')) {
        if (s[i] == '\n') f->line++;
        i++;
      }
      if (i < n && s[i] == '#') {
        while (i < n && s[i] != '\n') i++;
        continue;
      }
      break;
    }
    f->pos = i;
    if (i >= n) {
      if (!f->parent) {
        t->kind = TK_EOF;
        t->file = f;
        t->line = f->line;
        return TT_OK;
      }
      P->cur = f->parent;
      P->depth--;
      continue;
    }
    t->file = f;
    t->line = f->line;
    char c = s[i];
    if (c == '[' || c == ']') {
      t->kind = c == '[' ? TK_LBRACK : TK_RBRACK;
      t->s = s + i;
      t->n = 1;
      f->pos = i + 1;
      return TT_OK;
    }
    if (c == '"') {
      size_t j = i + 1;
      while (j < n && s[j] != '"') {
        if (s[j] == '\n' || s[j] == '\0') return tt__perr(f, f->line, "unterminated string");
        if (s[j] == '\\' && j + 1 < n && s[j + 1] != '\n') j++;
        j++;
      }
      if (j >= n) return tt__perr(f, f->line, "unterminated string at end of file");
      t->kind = TK_STRING;
      t->s = s + i + 1;
      t->n = j - i - 1;
      f->pos = j + 1;
      return TT_OK;
    }
    if (c == '\0' || (unsigned char)c < 0x20)
      return tt__perr(f, f->line, "unexpected control character (byte 0x%02x)", (unsigned char)c);
    size_t j = i;
    while (j < n && !(s[j] == ' ' || s[j] == '\t' || s[j] == '\r' || s[j] == '\n' || s[j] == '\f' ||
                      s[j] == '\v' || s[j] == '[' || s[j] == ']' || s[j] == '"' || s[j] == '#' ||
                      s[j] == '\0'))
      j++;
    t->kind = TK_WORD;
    t->s = s + i;
    t->n = j - i;
    f->pos = j;
    return TT_OK;
  }
}

/* Next token, honouring one token of lookahead. */
tt_status tt__next(tt__pp *P, tt__tok *t) {
  if (P->has_peek) {
    *t = P->peek;
    P->has_peek = 0;
    return TT_OK;
  }
  return tt__lex(P, t);
}

/* Looks at the next token without consuming it. */
tt_status tt__peek(tt__pp *P, tt__tok *t) {
  if (!P->has_peek) {
    tt_status st = tt__lex(P, &P->peek);
    if (st != TT_OK) return st;
    P->has_peek = 1;
  }
  *t = P->peek;
  return TT_OK;
}

/* Copies a string token's content, resolving \" \\ \n \t escapes. */
char *tt__tokstr(const tt__tok *t) {
  char *r = malloc(t->n + 1);
  if (!r) return NULL;
  size_t k = 0;
  for (size_t i = 0; i < t->n; i++) {
    char c = t->s[i];
    if (c == '\\' && i + 1 < t->n) {
      c = t->s[++i];
      if (c == 'n') c = '\n';
      else if (c == 't') c = '\t';
    }
    r[k++] = c;
  }
  r[k] = '\0';
  return r;
}

/* Token equals a literal word. */
int tt__is(const tt__tok *t, const char *w) {
  size_t n = strlen(w);
  return t->kind == TK_WORD && t->n == n && memcmp(t->s, w, n) == 0;
}

/* Parses a WORD as a finite number; 0 when it is not one. */
int tt__num(const tt__tok *t, double *v) {
  char buf[80];
  if (t->kind != TK_WORD || t->n == 0 || t->n >= sizeof buf) return 0;
  memcpy(buf, t->s, t->n);
  buf[t->n] = '\0';
  char *e;
  *v = strtod(buf, &e);
  if (e != buf + t->n || !isfinite(*v)) return 0;
  /* strtod also reads "nan"/"inf"/hex; pbrt numbers start with a digit, sign or dot */
  char c = buf[0];
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
}

/* Short description of a token for messages. */
const char *tt__desc(const tt__tok *t, char *buf, size_t n) {
  switch (t->kind) {
  case TK_EOF: snprintf(buf, n, "end of file"); break;
  case TK_LBRACK: snprintf(buf, n, "'['"); break;
  case TK_RBRACK: snprintf(buf, n, "']'"); break;
  case TK_STRING: snprintf(buf, n, "\"%.*s\"", (int)(t->n > 40 ? 40 : t->n), t->s); break;
  default: snprintf(buf, n, "'%.*s'", (int)(t->n > 40 ? 40 : t->n), t->s); break;
  }
  return buf;
}

/* Reads one quoted string argument of a directive. */
tt_status tt__arg_str(tt__pp *P, const tt__tok *dir, const char *what, char **out) {
  tt__tok t;
  char d[64];
  tt_status st = tt__next(P, &t);
  if (st != TT_OK) return st;
  if (t.kind != TK_STRING)
    return tt__perr(t.file ? t.file : dir->file, t.file ? t.line : dir->line,
                    "%.*s: expected %s (a quoted string), got %s", (int)dir->n, dir->s, what,
                    tt__desc(&t, d, sizeof d));
  *out = tt__tokstr(&t);
  if (!*out) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  return TT_OK;
}

/* Reads n numbers, optionally inside [ ] (Transform, ConcatTransform accept both). */
tt_status tt__arg_nums(tt__pp *P, const tt__tok *dir, int n, double *v) {
  tt__tok t;
  char d[64];
  tt_status st = tt__peek(P, &t);
  if (st != TT_OK) return st;
  int br = t.kind == TK_LBRACK;
  if (br) tt__next(P, &t);
  for (int i = 0; i < n; i++) {
    if ((st = tt__next(P, &t)) != TT_OK) return st;
    if (!tt__num(&t, &v[i]))
      return tt__perr(t.file ? t.file : dir->file, t.file ? t.line : dir->line,
                      "%.*s: expected %d numbers, got %s as number %d", (int)dir->n, dir->s, n,
                      tt__desc(&t, d, sizeof d), i + 1);
  }
  if (br) {
    if ((st = tt__next(P, &t)) != TT_OK) return st;
    if (t.kind != TK_RBRACK)
      return tt__perr(t.file ? t.file : dir->file, t.file ? t.line : dir->line,
                      "%.*s: expected ']' after %d numbers, got %s", (int)dir->n, dir->s, n,
                      tt__desc(&t, d, sizeof d));
  }
  return TT_OK;
}
