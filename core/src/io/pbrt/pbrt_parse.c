/* pbrt-v4 scene importer: tokenizer, parameter lists, graphics state and the mapping of
 * pbrt's directives onto a flattened tt_scene (world-space triangle meshes, tt_material,
 * lights, camera, resolution). The subset covers the shared test scenes; everything else
 * warns once per (file:line, name) and is skipped or approximated. The mapping and its
 * approximations are documented in scenes/README.md, "Importing pbrt-v4 scenes".
 *
 * Handedness: pbrt's camera space is left-handed (+x right, +y up, +z forward), while
 * tunetrace's camera puts `right = forward x up`. When the scene's camera transform keeps
 * pbrt's handedness, the whole world is mirrored (x -> -x) so that what pbrt shows on the
 * right of the image is on the right here too; files that already flip with `Scale -1 1 1`
 * are left alone. */
#define _XOPEN_SOURCE 700 /* realpath */
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
#include <sys/stat.h>

#define TT__PI 3.14159265358979323846
#define TT__MAX_INCLUDE_DEPTH 64
#define TT__MAX_WARNINGS 200
#define TT__MAT_INTERFACE (-2)

/* ---- types ----------------------------------------------------------------------------- */

/* One source file: its text stays alive until the load ends (tokens point into it). */
typedef struct tt__pfile {
  char *path;               /* as named (resolved against the includer) */
  char *dir;                /* directory for relative paths inside it */
  char *text;
  size_t len, pos;
  int line;
  struct tt__pfile *parent; /* includer while open */
  struct tt__pfile *next;   /* list of all files, for freeing */
} tt__pfile;

enum { TK_EOF, TK_WORD, TK_STRING, TK_LBRACK, TK_RBRACK };

typedef struct tt__tok {
  int kind;
  const char *s; /* WORD: the word; STRING: the raw content between the quotes */
  size_t n;
  const tt__pfile *file;
  int line;
} tt__tok;

/* One "type name" [values] parameter; values are copied so tokens can go. */
typedef struct tt__pparam {
  char type[24];
  char name[64];
  double *num;
  size_t nnum;
  char **str;
  size_t nstr;
  int used;
} tt__pparam;

typedef struct tt__plist {
  tt__pparam *p;
  size_t n, cap;
} tt__plist;

/* A colour parameter's value: rgb times an optional image texture (scene index). */
typedef struct tt__texval {
  float rgb[3];
  int32_t tex;
} tt__texval;

/* A named pbrt texture, resolved to a constant or to one image at definition time. */
typedef struct tt__ntex {
  char *name;
  int is_float;
  float rgb[3];
  char *image;   /* resolved image path (NULL: constant) */
  int srgb;
} tt__ntex;

typedef struct tt__named_mat {
  char *name;
  int32_t mat;  /* scene material index or TT__MAT_INTERFACE */
} tt__named_mat;

typedef struct tt__coordsys {
  char *name;
  double m[16];
} tt__coordsys;

/* A shape recorded inside ObjectBegin/End, already in world space of the definition. */
typedef struct tt__objmesh {
  tt__mesh_data d;
  int32_t mat;
} tt__objmesh;

typedef struct tt__object {
  char *name;
  tt__objmesh *m;
  size_t n, cap;
} tt__object;

/* An emissive copy of a material, shared by all shapes with the same area light. */
typedef struct tt__derived {
  int32_t base;
  float L[3];
  int two_sided;
  int32_t mat;
} tt__derived;

/* What AttributeBegin saves. */
typedef struct tt__gstate {
  double ctm[16];
  int reverse;
  int32_t mat;        /* -1: pbrt's default diffuse (created on first use) */
  int area;           /* an AreaLightSource is active */
  float L[3];
  int two_sided;
  int kind;           /* 'A' attribute, 'T' transform, 'O' object: which End closes it */
  const tt__pfile *file;
  int line;
} tt__gstate;

typedef struct tt__pp {
  tt_scene *scene;
  tt__pfile *cur;          /* innermost open file */
  tt__pfile *files;        /* every file read */
  int depth;
  tt__tok peek;
  int has_peek;
  char **warned;
  size_t nwarned, capwarned;
  unsigned warnings, suppressed;
  tt__gstate gs;
  tt__gstate *stack;
  size_t nstack, capstack;
  tt__named_mat *nmat;
  size_t nnmat, capnmat;
  tt__ntex *ntex;
  size_t nntex, capntex;
  tt__coordsys *cs;
  size_t ncs, capcs;
  tt__object *obj;
  size_t nobj, capobj;
  int cur_obj;             /* index of the object being defined, or -1 */
  tt__derived *der;
  size_t nder, capder;
  int32_t default_mat;
  int world_ready;         /* camera and mirror are fixed */
  int in_world;
  double W[16];            /* world mirror applied to everything */
  int has_camera;
  double cam_ctm[16];      /* pbrt cameraFromWorld */
  double fov;
  double sw[4];
  int has_sw;
  double frame_aspect;     /* 0: from the resolution */
  long xres, yres;
  int env_seen;
  int end_only;            /* ActiveTransform EndTime: transforms are ignored */
} tt__pp;

/* ---- messages -------------------------------------------------------------------------- */

/* "file:line: message" as a TT_ERR_PARSE error. */
static tt_status tt__perr(const tt__pfile *f, int line, const char *fmt, ...) TT_PRINTF(3, 4);
static tt_status tt__perr(const tt__pfile *f, int line, const char *fmt, ...) {
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return tt_set_error(TT_ERR_PARSE, "%s:%d: %s", f ? f->path : "(pbrt)", line, msg);
}

/* One warning per (file:line, key) through the log host, so a shape included twice warns
 * once. */
static void tt__pwarn(tt__pp *P, const tt__pfile *f, int line, const char *key, const char *fmt, ...)
    TT_PRINTF(5, 6);
static void tt__pwarn(tt__pp *P, const tt__pfile *f, int line, const char *key, const char *fmt, ...) {
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
static char *tt__join(const char *dir, const char *rel, size_t rel_len) {
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
static int tt__exists(const char *path) { return tt_file_check_regular(path, NULL) == TT_OK; }

/* Generic growth for the parser's arrays. */
static void *tt__grow(void *items, size_t *cap, size_t need, size_t size) {
  if (need <= *cap) return items;
  size_t nc = *cap ? *cap : 8;
  while (nc < need) nc *= 2;
  void *n = realloc(items, nc * size);
  if (n) *cap = nc;
  return n;
}

/* ---- matrices (row-major, column vectors: p' = M p, as pbrt) ---------------------------- */


/* Identity matrix. */
static void tt__ident(double m[16]) {
  memset(m, 0, 16 * sizeof *m);
  m[0] = m[5] = m[10] = m[15] = 1.0;
}

/* Gauss-Jordan inverse with partial pivoting; 0 when singular. */
static int tt__inverse(const double m[16], double inv[16]) {
  double a[4][8];
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 8; j++) a[i][j] = j < 4 ? m[4 * i + j] : (j - 4 == i);
  for (int c = 0; c < 4; c++) {
    int piv = c;
    for (int r = c + 1; r < 4; r++)
      if (fabs(a[r][c]) > fabs(a[piv][c])) piv = r;
    if (!(fabs(a[piv][c]) > 1e-300)) return 0;
    if (piv != c)
      for (int j = 0; j < 8; j++) {
        double t = a[c][j];
        a[c][j] = a[piv][j];
        a[piv][j] = t;
      }
    double d = a[c][c];
    for (int j = 0; j < 8; j++) a[c][j] /= d;
    for (int r = 0; r < 4; r++)
      if (r != c) {
        double f = a[r][c];
        for (int j = 0; j < 8; j++) a[r][j] -= f * a[c][j];
      }
  }
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) inv[4 * i + j] = a[i][j + 4];
  for (int i = 0; i < 16; i++)
    if (!isfinite(inv[i])) return 0;
  return 1;
}

/* Applies M to a point. */
static void tt__xform_point(const double m[16], const double p[3], double o[3]) {
  double w = m[12] * p[0] + m[13] * p[1] + m[14] * p[2] + m[15];
  for (int r = 0; r < 3; r++) o[r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
  if (w != 1.0 && w != 0.0)
    for (int r = 0; r < 3; r++) o[r] /= w;
}

/* Applies M's linear part to a direction. */
static void tt__xform_vec(const double m[16], const double v[3], double o[3]) {
  for (int r = 0; r < 3; r++) o[r] = m[4 * r] * v[0] + m[4 * r + 1] * v[1] + m[4 * r + 2] * v[2];
}

/* Normalises in place; 0 for a zero or non-finite vector. */
static int tt__norm(double v[3]) {
  double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(l > 0) || !isfinite(l)) return 0;
  for (int i = 0; i < 3; i++) v[i] /= l;
  return 1;
}

/* a x b. */
static void tt__cross(const double a[3], const double b[3], double o[3]) {
  o[0] = a[1] * b[2] - a[2] * b[1];
  o[1] = a[2] * b[0] - a[0] * b[2];
  o[2] = a[0] * b[1] - a[1] * b[0];
}

/* ---- tokenizer ------------------------------------------------------------------------- */

/* Opens a file onto the include stack (parent = current file). */
static tt_status tt__push_file(tt__pp *P, const char *path, const tt__pfile *from, int from_line) {
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
      while (i < n && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r' || s[i] == '\n' || s[i] == '\f' || s[i] == '\v')) {
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
    if (c == '\0' || (unsigned char)c < 0x20) return tt__perr(f, f->line, "unexpected control character (byte 0x%02x)", (unsigned char)c);
    size_t j = i;
    while (j < n && !(s[j] == ' ' || s[j] == '\t' || s[j] == '\r' || s[j] == '\n' || s[j] == '\f' ||
                      s[j] == '\v' || s[j] == '[' || s[j] == ']' || s[j] == '"' || s[j] == '#' || s[j] == '\0'))
      j++;
    t->kind = TK_WORD;
    t->s = s + i;
    t->n = j - i;
    f->pos = j;
    return TT_OK;
  }
}

/* Next token, honouring one token of lookahead. */
static tt_status tt__next(tt__pp *P, tt__tok *t) {
  if (P->has_peek) {
    *t = P->peek;
    P->has_peek = 0;
    return TT_OK;
  }
  return tt__lex(P, t);
}

/* Looks at the next token without consuming it. */
static tt_status tt__peek(tt__pp *P, tt__tok *t) {
  if (!P->has_peek) {
    tt_status st = tt__lex(P, &P->peek);
    if (st != TT_OK) return st;
    P->has_peek = 1;
  }
  *t = P->peek;
  return TT_OK;
}

/* Copies a string token's content, resolving \" \\ \n \t escapes. */
static char *tt__tokstr(const tt__tok *t) {
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
static int tt__is(const tt__tok *t, const char *w) {
  size_t n = strlen(w);
  return t->kind == TK_WORD && t->n == n && memcmp(t->s, w, n) == 0;
}

/* Parses a WORD as a finite number; 0 when it is not one. */
static int tt__num(const tt__tok *t, double *v) {
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
static const char *tt__desc(const tt__tok *t, char *buf, size_t n) {
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
static tt_status tt__arg_str(tt__pp *P, const tt__tok *dir, const char *what, char **out) {
  tt__tok t;
  char d[64];
  tt_status st = tt__next(P, &t);
  if (st != TT_OK) return st;
  if (t.kind != TK_STRING)
    return tt__perr(t.file ? t.file : dir->file, t.file ? t.line : dir->line, "%.*s: expected %s (a quoted string), got %s",
                    (int)dir->n, dir->s, what, tt__desc(&t, d, sizeof d));
  *out = tt__tokstr(&t);
  if (!*out) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  return TT_OK;
}

/* Reads n numbers, optionally inside [ ] (Transform, ConcatTransform accept both). */
static tt_status tt__arg_nums(tt__pp *P, const tt__tok *dir, int n, double *v) {
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
      return tt__perr(t.file ? t.file : dir->file, t.file ? t.line : dir->line, "%.*s: expected ']' after %d numbers, got %s",
                      (int)dir->n, dir->s, n, tt__desc(&t, d, sizeof d));
  }
  return TT_OK;
}

/* ---- parameter lists ------------------------------------------------------------------- */

/* Frees a parameter list's contents. */
static void tt__plist_free(tt__plist *pl) {
  for (size_t i = 0; i < pl->n; i++) {
    free(pl->p[i].num);
    for (size_t k = 0; k < pl->p[i].nstr; k++) free(pl->p[i].str[k]);
    free(pl->p[i].str);
  }
  free(pl->p);
  memset(pl, 0, sizeof *pl);
}

/* Type names pbrt-v4 accepts, and whether their values are numbers. */
static int tt__ptype(const char *t, int *numeric) {
  static const char *const nums[] = {"integer", "float", "point2", "vector2", "point3", "vector3", "normal",
                                     "normal3", "point", "vector", "color", "rgb", "blackbody", NULL};
  static const char *const strs[] = {"string", "texture", "bool", "spectrum", NULL};
  for (int i = 0; nums[i]; i++)
    if (strcmp(t, nums[i]) == 0) return *numeric = 1, 1;
  for (int i = 0; strs[i]; i++)
    if (strcmp(t, strs[i]) == 0) return *numeric = 0, 1;
  return 0;
}

/* Appends one value token to a parameter, checking it against the declared type. */
static tt_status tt__pvalue(tt__pparam *p, const tt__tok *t) {
  char d[64];
  int is_bool = strcmp(p->type, "bool") == 0, is_spec = strcmp(p->type, "spectrum") == 0;
  int numeric = 0;
  tt__ptype(p->type, &numeric);
  if (t->kind == TK_WORD) {
    double v;
    if (is_bool) {
      if (tt__is(t, "true")) v = 1;
      else if (tt__is(t, "false")) v = 0;
      else return tt__perr(t->file, t->line, "parameter \"%s %s\": expected true or false, got %s", p->type, p->name, tt__desc(t, d, sizeof d));
    } else if (!tt__num(t, &v)) {
      return tt__perr(t->file, t->line, "parameter \"%s %s\": bad number %s", p->type, p->name, tt__desc(t, d, sizeof d));
    } else if (!numeric && !is_spec) {
      return tt__perr(t->file, t->line, "parameter \"%s %s\": expected a quoted string, got %s", p->type, p->name, tt__desc(t, d, sizeof d));
    }
    if (p->nstr) return tt__perr(t->file, t->line, "parameter \"%s %s\": mixes strings and numbers", p->type, p->name);
    size_t cap = p->nnum; /* grow by doubling, tracked implicitly: power-of-two sizes */
    if ((cap & (cap - 1)) == 0) {
      double *n = realloc(p->num, (cap ? 2 * cap : 1) * sizeof *n);
      if (!n) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
      p->num = n;
    }
    p->num[p->nnum++] = v;
    return TT_OK;
  }
  if (t->kind == TK_STRING) {
    if (is_bool) {
      double v;
      if (t->n == 4 && memcmp(t->s, "true", 4) == 0) v = 1;
      else if (t->n == 5 && memcmp(t->s, "false", 5) == 0) v = 0;
      else return tt__perr(t->file, t->line, "parameter \"%s %s\": expected true or false, got %s", p->type, p->name, tt__desc(t, d, sizeof d));
      size_t cap = p->nnum;
      if ((cap & (cap - 1)) == 0) {
        double *n = realloc(p->num, (cap ? 2 * cap : 1) * sizeof *n);
        if (!n) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
        p->num = n;
      }
      p->num[p->nnum++] = v;
      return TT_OK;
    }
    if (numeric) return tt__perr(t->file, t->line, "parameter \"%s %s\": expected numbers, got the string %s", p->type, p->name, tt__desc(t, d, sizeof d));
    if (p->nnum) return tt__perr(t->file, t->line, "parameter \"%s %s\": mixes strings and numbers", p->type, p->name);
    size_t cap = p->nstr;
    if ((cap & (cap - 1)) == 0) {
      char **n = realloc(p->str, (cap ? 2 * cap : 1) * sizeof *n);
      if (!n) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
      p->str = n;
    }
    char *s = tt__tokstr(t);
    if (!s) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    p->str[p->nstr++] = s;
    return TT_OK;
  }
  return tt__perr(t->file, t->line, "parameter \"%s %s\": unexpected %s", p->type, p->name, tt__desc(t, d, sizeof d));
}

/* Reads "type name" value pairs until the next token is not a string. */
static tt_status tt__params(tt__pp *P, tt__plist *pl) {
  tt_status st;
  tt__tok t;
  char d[64];
  for (;;) {
    if ((st = tt__peek(P, &t)) != TT_OK) return st;
    if (t.kind != TK_STRING) return TT_OK;
    tt__next(P, &t);
    tt__tok decl = t;
    pl->p = tt__grow(pl->p, &pl->cap, pl->n + 1, sizeof *pl->p);
    if (!pl->p) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    tt__pparam *p = &pl->p[pl->n++];
    memset(p, 0, sizeof *p);
    /* "type name": exactly two words */
    char buf[128];
    size_t n = decl.n < sizeof buf - 1 ? decl.n : sizeof buf - 1;
    memcpy(buf, decl.s, n);
    buf[n] = '\0';
    char w0[64] = "", w1[80] = "", w2[8] = "";
    int nw = sscanf(buf, "%63s %79s %7s", w0, w1, w2);
    if (nw != 2 || strlen(w0) >= sizeof p->type || strlen(w1) >= sizeof p->name)
      return tt__perr(decl.file, decl.line, "bad parameter declaration %s (expected \"type name\")", tt__desc(&decl, d, sizeof d));
    int numeric;
    if (!tt__ptype(w0, &numeric))
      return tt__perr(decl.file, decl.line, "parameter \"%s %s\": unknown parameter type \"%s\"", w0, w1, w0);
    strcpy(p->type, w0);
    strcpy(p->name, w1);
    if ((st = tt__next(P, &t)) != TT_OK) return st;
    if (t.kind == TK_LBRACK) {
      tt__tok open = t;
      for (;;) {
        if ((st = tt__next(P, &t)) != TT_OK) return st;
        if (t.kind == TK_RBRACK) break;
        if (t.kind == TK_EOF || t.file != open.file)
          return tt__perr(open.file, open.line, "unterminated '[' array of parameter \"%s %s\"", p->type, p->name);
        if (t.kind == TK_LBRACK) return tt__perr(t.file, t.line, "parameter \"%s %s\": nested '['", p->type, p->name);
        if ((st = tt__pvalue(p, &t)) != TT_OK) return st;
      }
    } else if (t.kind == TK_STRING || (t.kind == TK_WORD && (tt__is(&t, "true") || tt__is(&t, "false") || tt__num(&t, &(double){0})))) {
      if ((st = tt__pvalue(p, &t)) != TT_OK) return st;
    } else {
      return tt__perr(decl.file, decl.line, "parameter \"%s %s\" has no value (got %s)", p->type, p->name,
                      tt__desc(&t, d, sizeof d));
    }
    if (p->nnum == 0 && p->nstr == 0)
      return tt__perr(decl.file, decl.line, "parameter \"%s %s\" has an empty value", p->type, p->name);
  }
}

/* Last parameter with this name (pbrt lets later ones win); marks it used. */
static tt__pparam *tt__find(tt__plist *pl, const char *name) {
  for (size_t i = pl->n; i-- > 0;)
    if (strcmp(pl->p[i].name, name) == 0) {
      for (size_t k = 0; k < pl->n; k++)
        if (strcmp(pl->p[k].name, name) == 0) pl->p[k].used = 1;
      return &pl->p[i];
    }
  return NULL;
}

/* Warns about every parameter nobody read. */
static void tt__unused(tt__pp *P, const tt__tok *at, const char *what, tt__plist *pl) {
  for (size_t i = 0; i < pl->n; i++)
    if (!pl->p[i].used)
      tt__pwarn(P, at->file, at->line, pl->p[i].name, "%s: parameter \"%s %s\" is not supported (ignored)", what,
                pl->p[i].type, pl->p[i].name);
}

/* A single float (or integer); textures are not supported for scalars. */
static tt_status tt__getf(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *name, double *v) {
  tt__pparam *p = tt__find(pl, name);
  if (!p) return TT_OK;
  if (strcmp(p->type, "texture") == 0) {
    tt__pwarn(P, at->file, at->line, name, "textured \"%s\" is not supported; using the default %g", name, *v);
    return TT_OK;
  }
  if (strcmp(p->type, "float") != 0 && strcmp(p->type, "integer") != 0)
    return tt__perr(at->file, at->line, "parameter \"%s %s\": expected a float", p->type, p->name);
  *v = p->num[0];
  return TT_OK;
}

/* A bool parameter. */
static tt_status tt__getb(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *name, int *v) {
  (void)P;
  tt__pparam *p = tt__find(pl, name);
  if (!p) return TT_OK;
  if (strcmp(p->type, "bool") != 0)
    return tt__perr(at->file, at->line, "parameter \"%s %s\": expected a bool", p->type, p->name);
  *v = p->num[0] != 0;
  return TT_OK;
}

/* A string parameter (NULL stays when absent); the pointer lives in the list. */
static tt_status tt__gets(const tt__tok *at, tt__plist *pl, const char *name, const char **v) {
  tt__pparam *p = tt__find(pl, name);
  if (!p) return TT_OK;
  if (strcmp(p->type, "string") != 0 || !p->nstr)
    return tt__perr(at->file, at->line, "parameter \"%s %s\": expected a string", p->type, p->name);
  *v = p->str[0];
  return TT_OK;
}

/* A point/vector of 3 numbers. */
static tt_status tt__get3(const tt__tok *at, tt__plist *pl, const char *name, double v[3]) {
  tt__pparam *p = tt__find(pl, name);
  if (!p) return TT_OK;
  if (!p->num || p->nnum != 3)
    return tt__perr(at->file, at->line, "parameter \"%s %s\": expected 3 numbers, got %zu", p->type, p->name, p->nnum);
  for (int i = 0; i < 3; i++) v[i] = p->num[i];
  return TT_OK;
}

/* Reads a .spd file of "lambda value" pairs ('#' comments). */
static tt_status tt__read_spd(tt__pp *P, const tt__tok *at, const char *path, double **pairs, size_t *n) {
  *pairs = NULL;
  *n = 0;
  char *text;
  size_t len;
  /* regular files only, at most 16 MiB: a FIFO would block, /dev/zero never end */
  if (tt_file_read(path, "spectrum file", (size_t)16 << 20, &text, &len) != TT_OK) {
    tt__pwarn(P, at->file, at->line, path, "%s", tt_last_error());
    return TT_ERR_IO;
  }
  size_t cap = 0, cnt = 0;
  double *v = NULL;
  for (char *line = text; line && *line;) {
    char *nl = strchr(line, '\n');
    if (nl) *nl = '\0';
    char *h = strchr(line, '#');
    if (h) *h = '\0';
    char *s = line, *e;
    for (;;) {
      double x = strtod(s, &e);
      if (e == s) break;
      double *nv = tt__grow(v, &cap, cnt + 1, sizeof *v);
      if (!nv) {
        free(v);
        tt_free(text);
        return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
      }
      v = nv;
      v[cnt++] = x;
      s = e;
    }
    line = nl ? nl + 1 : NULL;
  }
  tt_free(text);
  if (cnt < 2 || cnt % 2) {
    free(v);
    tt__pwarn(P, at->file, at->line, path, "spectrum file \"%s\" does not hold (lambda, value) pairs", path);
    return TT_ERR_PARSE;
  }
  *pairs = v;
  *n = cnt / 2;
  return TT_OK;
}

/* Resolves a texture name to its value; unknown names warn and keep the default. */
static const tt__ntex *tt__lookup_tex(tt__pp *P, const char *name, int is_float) {
  const tt__ntex *any = NULL;
  for (size_t i = P->nntex; i-- > 0;)
    if (strcmp(P->ntex[i].name, name) == 0) {
      if (P->ntex[i].is_float == is_float) return &P->ntex[i];
      if (!any) any = &P->ntex[i];
    }
  return any;
}

/* Adds (or finds) an image texture in the scene. */
static tt_status tt__scene_texture(tt__pp *P, const char *path, int srgb, int32_t *out) {
  tt_scene *s = P->scene;
  for (uint32_t i = 0; i < s->texture_count; i++)
    if (strcmp(s->textures[i].path, path) == 0 && s->textures[i].srgb == srgb) {
      *out = (int32_t)i;
      return TT_OK;
    }
  tt_texture *t = tt__scene_push((void **)&s->textures, &s->texture_count, &s->texture_cap, sizeof *t);
  if (!t) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  t->struct_size = sizeof *t;
  t->path = tt__strdup(path);
  t->srgb = srgb;
  if (!t->path) {
    s->texture_count--;
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  }
  *out = (int32_t)(s->texture_count - 1);
  return TT_OK;
}

/* A colour-like parameter: rgb, spectrum (named, inline pairs or .spd file), blackbody,
 * float (grey) or texture. `found` reports whether it was given. */
static tt_status tt__getc(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *name, tt__spectrum_use use,
                          int allow_tex, tt__texval *v, int *found) {
  tt__pparam *p = tt__find(pl, name);
  if (found) *found = p != NULL;
  if (!p) return TT_OK;
  const char *ty = p->type;
  if (strcmp(ty, "rgb") == 0 || strcmp(ty, "color") == 0) {
    if (p->nnum != 3) return tt__perr(at->file, at->line, "parameter \"%s %s\": expected 3 numbers, got %zu", ty, p->name, p->nnum);
    for (int i = 0; i < 3; i++) {
      if (p->num[i] < 0) return tt__perr(at->file, at->line, "parameter \"%s %s\": negative component %g", ty, p->name, p->num[i]);
      v->rgb[i] = (float)p->num[i];
    }
    v->tex = -1;
    return TT_OK;
  }
  if (strcmp(ty, "float") == 0) {
    v->rgb[0] = v->rgb[1] = v->rgb[2] = (float)p->num[0];
    v->tex = -1;
    return TT_OK;
  }
  if (strcmp(ty, "blackbody") == 0) {
    tt__pbrt_blackbody(p->num[0], v->rgb);
    v->tex = -1;
    return TT_OK;
  }
  if (strcmp(ty, "spectrum") == 0) {
    if (p->nstr) {
      if (tt__pbrt_named_spectrum(p->str[0], v->rgb)) {
        v->tex = -1;
        return TT_OK;
      }
      char *path = tt__join(at->file->dir, p->str[0], strlen(p->str[0]));
      if (!path) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
      double *pairs;
      size_t n;
      tt_status st = tt__read_spd(P, at, path, &pairs, &n);
      free(path);
      if (st == TT_ERR_OUT_OF_MEMORY) return st;
      if (st != TT_OK) {
        tt__pwarn(P, at->file, at->line, p->name, "spectrum \"%s\" for \"%s\" is unknown; using the default", p->str[0], p->name);
        return TT_OK;
      }
      tt__pbrt_sampled_spectrum(pairs, n, use, v->rgb);
      free(pairs);
      v->tex = -1;
      return TT_OK;
    }
    if (p->nnum == 1) {
      v->rgb[0] = v->rgb[1] = v->rgb[2] = (float)p->num[0];
    } else {
      if (p->nnum % 2) return tt__perr(at->file, at->line, "parameter \"spectrum %s\": expected (lambda, value) pairs, got %zu numbers", p->name, p->nnum);
      tt__pbrt_sampled_spectrum(p->num, p->nnum / 2, use, v->rgb);
    }
    v->tex = -1;
    return TT_OK;
  }
  if (strcmp(ty, "texture") == 0) {
    if (!allow_tex) {
      tt__pwarn(P, at->file, at->line, p->name, "textured \"%s\" is not supported here; using the default", p->name);
      return TT_OK;
    }
    const tt__ntex *t = tt__lookup_tex(P, p->str[0], 0);
    if (!t) {
      tt__pwarn(P, at->file, at->line, p->name, "texture \"%s\" is not defined; using the default for \"%s\"", p->str[0], p->name);
      return TT_OK;
    }
    memcpy(v->rgb, t->rgb, sizeof v->rgb);
    v->tex = -1;
    if (t->image) return tt__scene_texture(P, t->image, t->srgb, &v->tex);
    return TT_OK;
  }
  return tt__perr(at->file, at->line, "parameter \"%s %s\": expected a colour (rgb, spectrum, blackbody or texture)", ty, p->name);
}

/* ---- graphics state -------------------------------------------------------------------- */

/* Post-multiplies the CTM, as every pbrt transform directive does. */
static void tt__concat(tt__pp *P, const double m[16]) { tt__mat4_mul(P->gs.ctm, P->gs.ctm, m); }

/* Pushes the graphics state for AttributeBegin / TransformBegin / ObjectBegin. */
static tt_status tt__push(tt__pp *P, int kind, const tt__tok *at) {
  P->stack = tt__grow(P->stack, &P->capstack, P->nstack + 1, sizeof *P->stack);
  if (!P->stack) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  P->stack[P->nstack] = P->gs;
  P->stack[P->nstack].kind = kind;
  P->stack[P->nstack].file = at->file;
  P->stack[P->nstack].line = at->line;
  P->nstack++;
  return TT_OK;
}

/* Pops for the matching End; TransformEnd restores only the CTM. */
static void tt__pop(tt__pp *P, int kind, const tt__tok *at) {
  static const char *const names[] = {"AttributeEnd", "TransformEnd", "ObjectEnd"};
  const char *nm = names[kind == 'A' ? 0 : kind == 'T' ? 1 : 2];
  if (P->nstack == 0) {
    tt__pwarn(P, at->file, at->line, nm, "unmatched %s (ignored)", nm);
    return;
  }
  tt__gstate *top = &P->stack[P->nstack - 1];
  if (top->kind != kind)
    tt__pwarn(P, at->file, at->line, nm, "%s closes the block opened at %s:%d by a different Begin", nm,
              top->file ? top->file->path : "?", top->line);
  if (kind == 'T') memcpy(P->gs.ctm, top->ctm, sizeof P->gs.ctm);
  else P->gs = *top;
  P->nstack--;
}

/* Fixes the camera pose and the world mirror (at WorldBegin, or at the first world item
 * of a file that has none). */
static void tt__world_setup(tt__pp *P) {
  if (P->world_ready) return;
  P->world_ready = 1;
  tt__ident(P->W);
  double C[16];
  if (!P->has_camera || !tt__inverse(P->cam_ctm, C)) tt__ident(C);
  double o[3] = {0, 0, 0}, z[3] = {0, 0, 1}, y[3] = {0, 1, 0}, x[3] = {1, 0, 0};
  double pos[3], f[3], up[3], right[3], r2[3];
  tt__xform_point(C, o, pos);
  tt__xform_vec(C, z, f);
  tt__xform_vec(C, y, up);
  tt__xform_vec(C, x, right);
  if (!tt__norm(f)) f[0] = 0, f[1] = 0, f[2] = 1;
  if (!tt__norm(up)) up[0] = 0, up[1] = 1, up[2] = 0;
  /* tunetrace's right is forward x up; mirror the world when pbrt's +x disagrees */
  tt__cross(f, up, r2);
  if (r2[0] * right[0] + r2[1] * right[1] + r2[2] * right[2] < 0) {
    P->W[0] = -1.0;
    pos[0] = -pos[0];
    f[0] = -f[0];
    up[0] = -up[0];
  }
  tt_camera *c = &P->scene->camera;
  for (int i = 0; i < 3; i++) {
    c->position[i] = (float)pos[i];
    c->target[i] = (float)(pos[i] + f[i]);
    c->up[i] = (float)up[i];
  }
}

/* The world matrix of a shape: mirror * CTM. */
static void tt__world_matrix(tt__pp *P, const double ctm[16], double m[16]) {
  tt__world_setup(P);
  tt__mat4_mul(m, P->W, ctm);
}

/* ---- materials ------------------------------------------------------------------------- */

/* pbrt-v4's roughness -> GGX alpha (TrowbridgeReitz::RoughnessToAlpha is sqrt). */
static float tt__alpha(double r, int remap) {
  if (!(r > 0)) return 0.0f;
  double a = remap ? sqrt(r) : r;
  return (float)(a > 1.0 ? 1.0 : a);
}

/* Reads roughness / uroughness / vroughness (with a prefix for coated materials). */
static tt_status tt__rough(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *prefix, int remap, float alpha[2]) {
  char n0[64], nu[64], nv[64];
  snprintf(n0, sizeof n0, "%sroughness", prefix);
  snprintf(nu, sizeof nu, "%suroughness", prefix);
  snprintf(nv, sizeof nv, "%svroughness", prefix);
  double r = 0, u, v;
  tt_status st;
  if ((st = tt__getf(P, at, pl, n0, &r)) != TT_OK) return st;
  u = v = r;
  if ((st = tt__getf(P, at, pl, nu, &u)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, nv, &v)) != TT_OK) return st;
  alpha[0] = tt__alpha(u, remap);
  alpha[1] = tt__alpha(v, remap);
  return TT_OK;
}

/* Material eta: a float or a spectrum (named glass or sampled: averaged to one IOR). */
static tt_status tt__ior(tt__pp *P, const tt__tok *at, tt__plist *pl, float *ior) {
  tt__texval v = {{*ior, *ior, *ior}, -1};
  int found;
  tt_status st = tt__getc(P, at, pl, "eta", TT__SPEC_UNBOUNDED, 0, &v, &found);
  if (st != TT_OK) return st;
  if (found) {
    float e = (v.rgb[0] + v.rgb[1] + v.rgb[2]) / 3.0f;
    if (!(e > 0)) return tt__perr(at->file, at->line, "dielectric eta must be positive, got %g", (double)e);
    *ior = e;
  }
  return TT_OK;
}

/* Conductor eta/k (or pbrt-v4's artist-friendly "reflectance"). */
static tt_status tt__metal(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *prefix, tt_material *m) {
  char ne[64], nk[64], nr[64];
  snprintf(ne, sizeof ne, "%seta", prefix);
  snprintf(nk, sizeof nk, "%sk", prefix);
  snprintf(nr, sizeof nr, "%sreflectance", prefix);
  tt__texval e = {{0.200438f, 0.924033f, 1.10221f}, -1}, k = {{3.91295f, 2.45285f, 2.14219f}, -1}, r;
  int fr;
  tt_status st;
  if ((st = tt__getc(P, at, pl, ne, TT__SPEC_UNBOUNDED, 0, &e, NULL)) != TT_OK) return st;
  if ((st = tt__getc(P, at, pl, nk, TT__SPEC_UNBOUNDED, 0, &k, NULL)) != TT_OK) return st;
  if ((st = tt__getc(P, at, pl, nr, TT__SPEC_UNBOUNDED, 0, &r, &fr)) != TT_OK) return st;
  if (fr) {
    /* pbrt-v4: eta = 1, k = 2 sqrt(r) / sqrt(1 - r) */
    for (int i = 0; i < 3; i++) {
      double rr = r.rgb[i] < 0 ? 0 : r.rgb[i] > 0.9999 ? 0.9999 : r.rgb[i];
      e.rgb[i] = 1.0f;
      k.rgb[i] = (float)(2 * sqrt(rr) / sqrt(1 - rr));
    }
  }
  for (int i = 0; i < 3; i++) {
    m->eta[i] = e.rgb[i] > 1e-3f ? e.rgb[i] : 1e-3f;
    m->k[i] = k.rgb[i] > 0 ? k.rgb[i] : 0.0f;
  }
  return TT_OK;
}

/* Creates a tt_material from a pbrt material type and its parameters; *out is the scene
 * index, or TT__MAT_INTERFACE for "interface" (no surface). */
static tt_status tt__make_material(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl, const char *name,
                                   int32_t *out) {
  tt_status st;
  char what[160];
  snprintf(what, sizeof what, "Material \"%s\"", type);
  /* parameters that only steer pbrt's own sampling: nothing to map, nothing to warn */
  static const char *const quiet[] = {"remaproughness", "maxdepth", "nsamples", "g", "thickness", "regularize", NULL};
  int remap = 1;
  if ((st = tt__getb(P, at, pl, "remaproughness", &remap)) != TT_OK) return st;
  for (int i = 0; quiet[i]; i++) tt__find(pl, quiet[i]);
  if (strcmp(type, "interface") == 0 || strcmp(type, "none") == 0 || strcmp(type, "") == 0) {
    *out = TT__MAT_INTERFACE;
    tt__unused(P, at, what, pl);
    return TT_OK;
  }
  if (strcmp(type, "mix") == 0) {
    tt__pparam *mp = tt__find(pl, "materials");
    if (!mp || strcmp(mp->type, "string") != 0 || mp->nstr != 2)
      return tt__perr(at->file, at->line, "mix material needs \"string materials\" with two names");
    double amount = 0.5;
    if ((st = tt__getf(P, at, pl, "amount", &amount)) != TT_OK) return st;
    /* pbrt-v4 picks materials[1] with probability `amount`: keep the dominant one */
    const char *pick = amount <= 0.5 ? mp->str[0] : mp->str[1];
    tt__pwarn(P, at->file, at->line, "mix", "mix material approximated by its dominant component \"%s\"", pick);
    for (size_t i = P->nnmat; i-- > 0;)
      if (strcmp(P->nmat[i].name, pick) == 0) {
        *out = P->nmat[i].mat;
        tt__unused(P, at, what, pl);
        return TT_OK;
      }
    return tt__perr(at->file, at->line, "mix material: named material \"%s\" is not defined", pick);
  }
  tt_scene *s = P->scene;
  tt_material m;
  memset(&m, 0, sizeof m);
  m.struct_size = sizeof m;
  m.albedo[0] = m.albedo[1] = m.albedo[2] = 0.5f;
  m.albedo_texture = -1;
  m.specular[0] = m.specular[1] = m.specular[2] = 1.0f;
  m.ior = 1.5f;
  static const float cu_eta[3] = {0.200438f, 0.924033f, 1.10221f}, cu_k[3] = {3.91295f, 2.45285f, 2.14219f};
  memcpy(m.eta, cu_eta, sizeof m.eta);
  memcpy(m.k, cu_k, sizeof m.k);
  tt__texval refl = {{0.5f, 0.5f, 0.5f}, -1};
  if (strcmp(type, "diffuse") == 0 || strcmp(type, "diffusetransmission") == 0) {
    m.type = TT_MATERIAL_DIFFUSE;
    if (type[7] == 't') {
      refl.rgb[0] = refl.rgb[1] = refl.rgb[2] = 0.25f;
      tt__pwarn(P, at->file, at->line, "diffusetransmission", "diffusetransmission approximated by diffuse reflection (transmission dropped)");
      tt__find(pl, "transmittance");
      double sc = 1;
      if ((st = tt__getf(P, at, pl, "scale", &sc)) != TT_OK) return st;
      if ((st = tt__getc(P, at, pl, "reflectance", TT__SPEC_UNBOUNDED, 1, &refl, NULL)) != TT_OK) return st;
      for (int i = 0; i < 3; i++) refl.rgb[i] *= (float)sc;
    } else if ((st = tt__getc(P, at, pl, "reflectance", TT__SPEC_UNBOUNDED, 1, &refl, NULL)) != TT_OK) {
      return st;
    }
  } else if (strcmp(type, "coateddiffuse") == 0) {
    m.type = TT_MATERIAL_PLASTIC;
    if ((st = tt__getc(P, at, pl, "reflectance", TT__SPEC_UNBOUNDED, 1, &refl, NULL)) != TT_OK) return st;
    if ((st = tt__rough(P, at, pl, "", remap, m.alpha)) != TT_OK) return st;
    if ((st = tt__ior(P, at, pl, &m.ior)) != TT_OK) return st;
    tt__find(pl, "albedo");
  } else if (strcmp(type, "conductor") == 0) {
    m.type = TT_MATERIAL_CONDUCTOR;
    if ((st = tt__metal(P, at, pl, "", &m)) != TT_OK) return st;
    if ((st = tt__rough(P, at, pl, "", remap, m.alpha)) != TT_OK) return st;
  } else if (strcmp(type, "coatedconductor") == 0) {
    m.type = TT_MATERIAL_CONDUCTOR;
    tt__pwarn(P, at->file, at->line, "coatedconductor",
              "coatedconductor approximated by its conductor base (the clear coat is dropped)");
    if ((st = tt__metal(P, at, pl, "conductor.", &m)) != TT_OK) return st;
    float a1[2], a2[2];
    if ((st = tt__rough(P, at, pl, "interface.", remap, a1)) != TT_OK) return st;
    if ((st = tt__rough(P, at, pl, "conductor.", remap, a2)) != TT_OK) return st;
    for (int i = 0; i < 2; i++) m.alpha[i] = a1[i] > a2[i] ? a1[i] : a2[i];
    tt__find(pl, "interface.eta");
    tt__find(pl, "albedo");
  } else if (strcmp(type, "dielectric") == 0 || strcmp(type, "thindielectric") == 0) {
    m.type = TT_MATERIAL_DIELECTRIC;
    if ((st = tt__ior(P, at, pl, &m.ior)) != TT_OK) return st;
    /* dielectric: roughness -> GGX alpha exactly as for conductor (rough glass, Walter 2007).
     * thindielectric has no roughness in pbrt-v4 and stays smooth (alpha 0). */
    if (type[0] == 't')
      tt__pwarn(P, at->file, at->line, "thindielectric", "thindielectric approximated by a solid dielectric");
    else if ((st = tt__rough(P, at, pl, "", remap, m.alpha)) != TT_OK)
      return st;
  } else {
    static const char *const known[] = {"hair", "measured", "subsurface", "coatedconductor", NULL};
    int pbrt_known = 0;
    for (int i = 0; known[i]; i++) pbrt_known |= strcmp(type, known[i]) == 0;
    if (!pbrt_known) return tt__perr(at->file, at->line, "unknown material type \"%s\"", type);
    tt__pwarn(P, at->file, at->line, type, "material \"%s\" is not supported; using diffuse grey", type);
    m.type = TT_MATERIAL_DIFFUSE;
    for (size_t i = 0; i < pl->n; i++) pl->p[i].used = 1;
  }
  for (int i = 0; i < 3; i++) m.albedo[i] = refl.rgb[i] > 1.0f ? 1.0f : refl.rgb[i];
  m.albedo_texture = refl.tex;
  tt__unused(P, at, what, pl);
  char nm[512];
  if (name) snprintf(nm, sizeof nm, "%s", name);
  else {
    const char *base = strrchr(at->file->path, '/');
    snprintf(nm, sizeof nm, "%s@%s:%d", type, base ? base + 1 : at->file->path, at->line);
  }
  m.name = tt__strdup(nm);
  if (!m.name) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  tt_material *slot = tt__scene_push((void **)&s->materials, &s->material_count, &s->material_cap, sizeof *slot);
  if (!slot) {
    free((void *)m.name);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  }
  *slot = m;
  *out = (int32_t)(s->material_count - 1);
  return TT_OK;
}

/* The material a shape gets: the current one (pbrt's default diffuse if none) with the
 * active area light's emission folded into a derived copy. */
static tt_status tt__shape_material(tt__pp *P, int emissive, int32_t *out) {
  int32_t base = P->gs.mat;
  if (base < 0) {
    if (P->default_mat < 0) {
      tt__plist empty = {0};
      tt__tok at = {TK_WORD, "", 0, P->files, 0};
      tt_status st = tt__make_material(P, &at, "diffuse", &empty, "pbrt-default-diffuse", &P->default_mat);
      if (st != TT_OK) return st;
    }
    base = P->default_mat;
  }
  if (!emissive) {
    *out = base;
    return TT_OK;
  }
  for (size_t i = 0; i < P->nder; i++) {
    const tt__derived *d = &P->der[i];
    if (d->base == base && d->two_sided == P->gs.two_sided && memcmp(d->L, P->gs.L, sizeof d->L) == 0) {
      *out = d->mat;
      return TT_OK;
    }
  }
  tt_scene *s = P->scene;
  tt_material m = s->materials[base];
  char nm[600];
  snprintf(nm, sizeof nm, "%s+light%zu", m.name ? m.name : "material", P->nder);
  m.name = tt__strdup(nm);
  if (!m.name) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  memcpy(m.emission, P->gs.L, sizeof m.emission);
  m.two_sided = P->gs.two_sided;
  tt_material *slot = tt__scene_push((void **)&s->materials, &s->material_count, &s->material_cap, sizeof *slot);
  P->der = tt__grow(P->der, &P->capder, P->nder + 1, sizeof *P->der);
  if (!slot || !P->der) {
    free((void *)m.name);
    if (slot) s->material_count--;
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  }
  *slot = m;
  tt__derived *d = &P->der[P->nder++];
  d->base = base;
  memcpy(d->L, P->gs.L, sizeof d->L);
  d->two_sided = P->gs.two_sided;
  d->mat = *out = (int32_t)(s->material_count - 1);
  return TT_OK;
}

/* ---- shapes ---------------------------------------------------------------------------- */

/* Swaps two indices of every triangle (flips the geometric normal). */
static void tt__flip(tt__mesh_data *d) {
  for (uint32_t t = 0; t < d->triangle_count; t++) {
    uint32_t x = d->indices[3 * (size_t)t + 1];
    d->indices[3 * (size_t)t + 1] = d->indices[3 * (size_t)t + 2];
    d->indices[3 * (size_t)t + 2] = x;
  }
}

/* pbrt turns a triangle's geometric normal towards its shading normals; emitters only
 * shine on the geometric side here, so the winding is made to agree. */
static void tt__face_forward(tt__mesh_data *d) {
  if (!d->normals) return;
  for (uint32_t t = 0; t < d->triangle_count; t++) {
    uint32_t *ix = d->indices + 3 * (size_t)t;
    const float *a = d->positions + 3 * (size_t)ix[0], *b = d->positions + 3 * (size_t)ix[1], *c = d->positions + 3 * (size_t)ix[2];
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]}, ng[3];
    tt__cross(e1, e2, ng);
    double dot = 0;
    for (int k = 0; k < 3; k++)
      for (int j = 0; j < 3; j++) dot += ng[j] * d->normals[3 * (size_t)ix[k] + j];
    if (dot < 0) {
      uint32_t x = ix[1];
      ix[1] = ix[2];
      ix[2] = x;
    }
  }
}

/* Copies a numeric array parameter into floats, checking its arity. */
static tt_status tt__pfloats(const tt__tok *at, tt__pparam *p, size_t arity, float **out, size_t *count) {
  if (!p->num || p->nnum % arity)
    return tt__perr(at->file, at->line, "parameter \"%s %s\": expected a multiple of %zu numbers, got %zu", p->type, p->name,
                    arity, p->nnum);
  *out = malloc((p->nnum ? p->nnum : 1) * sizeof **out);
  if (!*out) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  for (size_t i = 0; i < p->nnum; i++) (*out)[i] = (float)p->num[i];
  *count = p->nnum / arity;
  return TT_OK;
}

/* trianglemesh / bilinearmesh / loopsubdiv from inline arrays. `per` is 3 for triangles
 * and 4 for bilinear patches (split into two triangles). */
static tt_status tt__inline_mesh(const tt__tok *at, tt__plist *pl, int per, tt__mesh_data *d) {
  tt_status st;
  size_t nv = 0, nn = 0, nuv = 0;
  tt__pparam *P3 = tt__find(pl, "P");
  if (!P3) return tt__perr(at->file, at->line, "mesh without \"point3 P\"");
  if ((st = tt__pfloats(at, P3, 3, &d->positions, &nv)) != TT_OK) return st;
  if (nv == 0 || nv > UINT32_MAX / 4) return tt__perr(at->file, at->line, "mesh \"P\" holds %zu vertices", nv);
  for (size_t i = 0; i < 3 * nv; i++)
    if (!isfinite(d->positions[i])) return tt__perr(at->file, at->line, "mesh \"P\" has a non-finite value");
  d->vertex_count = (uint32_t)nv;
  tt__pparam *N = tt__find(pl, "N");
  if (N) {
    if ((st = tt__pfloats(at, N, 3, &d->normals, &nn)) != TT_OK) return st;
    if (nn != nv) return tt__perr(at->file, at->line, "mesh has %zu normals for %zu vertices", nn, nv);
  }
  tt__pparam *UV = tt__find(pl, "uv");
  if (!UV) UV = tt__find(pl, "st");
  if (UV) {
    if ((st = tt__pfloats(at, UV, 2, &d->uvs, &nuv)) != TT_OK) return st;
    if (nuv != nv) return tt__perr(at->file, at->line, "mesh has %zu uvs for %zu vertices", nuv, nv);
  }
  tt__pparam *I = tt__find(pl, "indices");
  size_t ni;
  const double *src = NULL;
  if (I) {
    if (strcmp(I->type, "integer") != 0 || !I->num) return tt__perr(at->file, at->line, "mesh \"indices\" must be integers");
    ni = I->nnum;
    src = I->num;
  } else {
    if ((size_t)per != nv) return tt__perr(at->file, at->line, "mesh without \"integer indices\" needs exactly %d vertices, got %zu", per, nv);
    ni = (size_t)per;
  }
  if (ni == 0 || ni % (size_t)per)
    return tt__perr(at->file, at->line, "mesh \"indices\" holds %zu values, not a multiple of %d", ni, per);
  size_t prims = ni / (size_t)per, nt = per == 4 ? 2 * prims : prims;
  if (nt > UINT32_MAX / 3) return tt__perr(at->file, at->line, "mesh is too large");
  d->indices = malloc(3 * nt * sizeof *d->indices);
  if (!d->indices) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  uint32_t q[4];
  for (size_t p = 0; p < prims; p++) {
    for (int k = 0; k < per; k++) {
      double v = src ? src[p * (size_t)per + (size_t)k] : (double)k;
      if (!(v >= 0) || v >= (double)nv || v != floor(v))
        return tt__perr(at->file, at->line, "mesh index %g is out of range (%zu vertices)", v, nv);
      q[k] = (uint32_t)v;
    }
    uint32_t *o = d->indices + 3 * (per == 4 ? 2 * p : p);
    if (per == 3) {
      o[0] = q[0]; o[1] = q[1]; o[2] = q[2];
    } else {
      /* pbrt bilinear patch: v00 v10 v01 v11 -> (00,10,11), (00,11,01): normal dpdu x dpdv */
      o[0] = q[0]; o[1] = q[1]; o[2] = q[3];
      o[3] = q[0]; o[4] = q[3]; o[5] = q[2];
    }
  }
  d->triangle_count = (uint32_t)nt;
  return TT_OK;
}

/* Transforms, assigns the material and adds one shape to the scene (or to the object
 * being defined). */
static tt_status tt__emit_shape(tt__pp *P, const tt__tok *at, tt__mesh_data *d) {
  tt_status st;
  int emissive = P->gs.area && (P->gs.L[0] > 0 || P->gs.L[1] > 0 || P->gs.L[2] > 0);
  double m[16];
  if (P->cur_obj >= 0) {
    if (emissive) {
      tt__pwarn(P, at->file, at->line, "AreaLightSource", "area lights inside ObjectBegin are not supported by pbrt-v4 (emission ignored)");
      emissive = 0;
    }
    memcpy(m, P->gs.ctm, sizeof m);
  } else {
    tt__world_matrix(P, P->gs.ctm, m);
  }
  if (tt__mesh_data_transform(d, m) != TT_OK)
    return tt__perr(at->file, at->line, "shape transform is singular or not affine");
  int32_t mat = 0;
  if ((st = tt__shape_material(P, emissive, &mat)) != TT_OK) return st;
  if (emissive) tt__face_forward(d);
  if (P->cur_obj >= 0) {
    tt__object *o = &P->obj[P->cur_obj];
    o->m = tt__grow(o->m, &o->cap, o->n + 1, sizeof *o->m);
    if (!o->m) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    o->m[o->n].d = *d;
    o->m[o->n].mat = mat;
    o->n++;
    memset(d, 0, sizeof *d);
    return TT_OK;
  }
  return tt__scene_add_mesh(P->scene, d, (uint32_t)mat);
}

/* Shape directive: builds object-space triangles for the supported shape types. */
static tt_status tt__shape(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl) {
  tt_status st = TT_OK;
  tt__mesh_data d;
  memset(&d, 0, sizeof d);
  char what[160], nm[512];
  snprintf(what, sizeof what, "Shape \"%s\"", type);
  const char *base = strrchr(at->file->path, '/');
  snprintf(nm, sizeof nm, "%s@%s:%d", type, base ? base + 1 : at->file->path, at->line);
  int analytic = 0;
  tt__find(pl, "emissionfilename");
  if (tt__find(pl, "alpha"))
    tt__pwarn(P, at->file, at->line, "alpha", "%s: alpha (cut-out) textures are not supported (ignored)", what);
  if (strcmp(type, "trianglemesh") == 0) {
    tt__find(pl, "S");
    tt__find(pl, "faceIndices");
    st = tt__inline_mesh(at, pl, 3, &d);
  } else if (strcmp(type, "bilinearmesh") == 0) {
    tt__find(pl, "faceIndices");
    st = tt__inline_mesh(at, pl, 4, &d);
  } else if (strcmp(type, "loopsubdiv") == 0) {
    double levels = 3;
    if ((st = tt__getf(P, at, pl, "levels", &levels)) == TT_OK) st = tt__inline_mesh(at, pl, 3, &d);
    if (st == TT_OK) {
      free(d.normals);
      free(d.uvs);
      d.normals = NULL;
      d.uvs = NULL;
      int lv = levels < 0 ? 0 : levels > 6 ? 6 : (int)levels;
      if (levels > 6) tt__pwarn(P, at->file, at->line, "levels", "loopsubdiv levels %g clamped to 6", levels);
      for (int i = 0; i < lv && st == TT_OK; i++) st = tt__pbrt_loop_subdivide(&d);
      if (st != TT_OK) st = tt__perr(at->file, at->line, "loopsubdiv: %s", tt_last_error());
    }
  } else if (strcmp(type, "plymesh") == 0) {
    const char *fn = NULL;
    if ((st = tt__gets(at, pl, "filename", &fn)) != TT_OK) return st;
    if (!fn) return tt__perr(at->file, at->line, "plymesh without \"string filename\"");
    tt__pparam *disp = tt__find(pl, "displacement");
    if (disp) tt__pwarn(P, at->file, at->line, "displacement", "%s: displacement is not supported (ignored)", what);
    tt__find(pl, "edgelength");
    char *path = tt__join(at->file->dir, fn, strlen(fn));
    if (!path) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    struct stat sb;
    if (stat(path, &sb) != 0 && errno == ENOENT) {
      /* like a missing texture (the shared scenes' MISSING_FILES convention): warn, skip */
      tt__pwarn(P, at->file, at->line, "filename", "%s: PLY file \"%s\" not found (shape skipped)",
                what, path);
      free(path);
      return TT_OK;
    }
    char where[600];
    snprintf(where, sizeof where, "%s:%d", at->file->path, at->line);
    st = tt__pbrt_read_ply(path, where, &d);
    free(path);
    if (st == TT_OK) snprintf(nm, sizeof nm, "%s", fn);
  } else if (strcmp(type, "sphere") == 0 || strcmp(type, "disk") == 0) {
    double r = 1, zmin = -1e30, zmax = 1e30, phimax = 360, h = 0, ri = 0;
    analytic = 1;
    if ((st = tt__getf(P, at, pl, "radius", &r)) != TT_OK) return st;
    if (!(r > 0)) return tt__perr(at->file, at->line, "%s: radius must be positive, got %g", what, r);
    if ((st = tt__getf(P, at, pl, "phimax", &phimax)) != TT_OK) return st;
    if (phimax < 360) tt__pwarn(P, at->file, at->line, "phimax", "%s: partial shapes (phimax) are tessellated whole", what);
    if (type[0] == 's') {
      if ((st = tt__getf(P, at, pl, "zmin", &zmin)) != TT_OK) return st;
      if ((st = tt__getf(P, at, pl, "zmax", &zmax)) != TT_OK) return st;
      if (zmin > -r || zmax < r) tt__pwarn(P, at->file, at->line, "zmin", "%s: clipped spheres (zmin/zmax) are tessellated whole", what);
      st = tt__pbrt_sphere(r, &d);
    } else {
      if ((st = tt__getf(P, at, pl, "height", &h)) != TT_OK) return st;
      if ((st = tt__getf(P, at, pl, "innerradius", &ri)) != TT_OK) return st;
      st = tt__pbrt_disk(r, ri, h, &d);
    }
  } else {
    static const char *const known[] = {"cylinder", "cone", "paraboloid", "hyperboloid", "curve", "nurbs", "heightfield", NULL};
    for (int i = 0; known[i]; i++)
      if (strcmp(type, known[i]) == 0) {
        tt__pwarn(P, at->file, at->line, type, "shape \"%s\" is not supported (skipped)", type);
        return TT_OK;
      }
    return tt__perr(at->file, at->line, "unknown shape type \"%s\"", type);
  }
  if (st != TT_OK) {
    tt__mesh_data_free(&d);
    return st;
  }
  tt__unused(P, at, what, pl);
  if (P->gs.mat == TT__MAT_INTERFACE) {
    /* "interface" marks a medium boundary with no surface: nothing to render */
    tt__pwarn(P, at->file, at->line, "interface", "%s with material \"interface\" has no surface (skipped)", what);
    tt__mesh_data_free(&d);
    return TT_OK;
  }
  if (d.triangle_count == 0) {
    tt__mesh_data_free(&d);
    return TT_OK;
  }
  /* ReverseOrientation flips the normal of analytic shapes and of meshes without normals;
   * meshes with normals follow them (pbrt face-forwards to the shading normal) */
  if (P->gs.reverse && (analytic || !d.normals)) {
    tt__flip(&d);
    if (d.normals)
      for (size_t i = 0; i < 3 * (size_t)d.vertex_count; i++) d.normals[i] = -d.normals[i];
  }
  d.name = tt__strdup(nm);
  if (!d.name) {
    tt__mesh_data_free(&d);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  }
  st = tt__emit_shape(P, at, &d);
  tt__mesh_data_free(&d);
  return st;
}

/* Deep copy of a mesh_data (instances are flattened into independent meshes). */
static int tt__mesh_copy(const tt__mesh_data *s, tt__mesh_data *d) {
  memset(d, 0, sizeof *d);
  d->vertex_count = s->vertex_count;
  d->triangle_count = s->triangle_count;
  d->name = tt__strdup(s->name);
  d->positions = malloc(3 * (size_t)s->vertex_count * sizeof(float) + 1);
  d->indices = malloc(3 * (size_t)s->triangle_count * sizeof(uint32_t) + 1);
  if (s->normals) d->normals = malloc(3 * (size_t)s->vertex_count * sizeof(float) + 1);
  if (s->uvs) d->uvs = malloc(2 * (size_t)s->vertex_count * sizeof(float) + 1);
  if (!d->positions || !d->indices || (s->normals && !d->normals) || (s->uvs && !d->uvs) || (s->name && !d->name)) {
    tt__mesh_data_free(d);
    return 0;
  }
  memcpy(d->positions, s->positions, 3 * (size_t)s->vertex_count * sizeof(float));
  memcpy(d->indices, s->indices, 3 * (size_t)s->triangle_count * sizeof(uint32_t));
  if (s->normals) memcpy(d->normals, s->normals, 3 * (size_t)s->vertex_count * sizeof(float));
  if (s->uvs) memcpy(d->uvs, s->uvs, 2 * (size_t)s->vertex_count * sizeof(float));
  return 1;
}

/* ObjectInstance: copies the object's meshes through the current CTM. */
static tt_status tt__instance(tt__pp *P, const tt__tok *at, const char *name) {
  if (P->cur_obj >= 0) return tt__perr(at->file, at->line, "ObjectInstance \"%s\" inside ObjectBegin", name);
  tt__object *o = NULL;
  for (size_t i = P->nobj; i-- > 0;)
    if (strcmp(P->obj[i].name, name) == 0) {
      o = &P->obj[i];
      break;
    }
  if (!o) return tt__perr(at->file, at->line, "ObjectInstance: no object named \"%s\"", name);
  double m[16];
  tt__world_matrix(P, P->gs.ctm, m);
  for (size_t i = 0; i < o->n; i++) {
    tt__mesh_data d;
    if (!tt__mesh_copy(&o->m[i].d, &d)) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    if (tt__mesh_data_transform(&d, m) != TT_OK) {
      tt__mesh_data_free(&d);
      return tt__perr(at->file, at->line, "ObjectInstance \"%s\": transform is singular or not affine", name);
    }
    tt_status st = tt__scene_add_mesh(P->scene, &d, (uint32_t)o->m[i].mat);
    tt__mesh_data_free(&d);
    if (st != TT_OK) return st;
  }
  return TT_OK;
}

/* ---- textures -------------------------------------------------------------------------- */

/* Texture directive: imagemap keeps its file; scale multiplies; others become constants. */
static tt_status tt__texture(tt__pp *P, const tt__tok *at, const char *name, const char *kind, const char *cls,
                             tt__plist *pl) {
  tt_status st;
  int is_float = strcmp(kind, "float") == 0;
  if (!is_float && strcmp(kind, "spectrum") != 0 && strcmp(kind, "color") != 0)
    return tt__perr(at->file, at->line, "Texture \"%s\": type must be \"float\" or \"spectrum\", got \"%s\"", name, kind);
  tt__ntex t;
  memset(&t, 0, sizeof t);
  t.is_float = is_float;
  t.rgb[0] = t.rgb[1] = t.rgb[2] = 1.0f;
  char what[200];
  snprintf(what, sizeof what, "Texture \"%s\" (\"%s\")", name, cls);
  static const char *const quiet[] = {"filter", "maxanisotropy", "wrap", NULL};
  for (int i = 0; quiet[i]; i++) tt__find(pl, quiet[i]);
  double us = 1, vs = 1, ud = 0, vd = 0;
  const char *mapping = NULL;
  if ((st = tt__gets(at, pl, "mapping", &mapping)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, "uscale", &us)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, "vscale", &vs)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, "udelta", &ud)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, "vdelta", &vd)) != TT_OK) return st;
  if (us != 1 || vs != 1 || ud != 0 || vd != 0 || (mapping && strcmp(mapping, "uv") != 0))
    tt__pwarn(P, at->file, at->line, "mapping", "%s: texture mapping (uscale/vscale/udelta/vdelta/mapping) is not supported (plain uv used)", what);
  if (strcmp(cls, "imagemap") == 0) {
    const char *fn = NULL, *enc = NULL;
    double scale = 1;
    int invert = 0;
    if ((st = tt__gets(at, pl, "filename", &fn)) != TT_OK) return st;
    if ((st = tt__gets(at, pl, "encoding", &enc)) != TT_OK) return st;
    if ((st = tt__getf(P, at, pl, "scale", &scale)) != TT_OK) return st;
    if ((st = tt__getb(P, at, pl, "invert", &invert)) != TT_OK) return st;
    if (invert) tt__pwarn(P, at->file, at->line, "invert", "%s: \"invert\" is not supported (ignored)", what);
    if (!fn) return tt__perr(at->file, at->line, "%s: missing \"string filename\"", what);
    char *path = tt__join(at->file->dir, fn, strlen(fn));
    if (!path) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    t.rgb[0] = t.rgb[1] = t.rgb[2] = (float)scale;
    if (tt__exists(path)) {
      t.image = path;
      /* pbrt-v4: PNGs default to sRGB, every other format to linear */
      size_t n = strlen(path);
      t.srgb = enc ? strcasecmp(enc, "sRGB") == 0 : (n >= 4 && strcasecmp(path + n - 4, ".png") == 0);
      if (enc && strncmp(enc, "gamma", 5) == 0) t.srgb = 1;
    } else {
      tt__pwarn(P, at->file, at->line, "filename", "%s: image \"%s\" not found, using a constant 0.5", what, path);
      free(path);
      t.rgb[0] = t.rgb[1] = t.rgb[2] = (float)(0.5 * scale);
    }
  } else if (strcmp(cls, "constant") == 0) {
    tt__texval v = {{1, 1, 1}, -1};
    if ((st = tt__getc(P, at, pl, "value", TT__SPEC_UNBOUNDED, 0, &v, NULL)) != TT_OK) return st;
    memcpy(t.rgb, v.rgb, sizeof t.rgb);
  } else if (strcmp(cls, "scale") == 0) {
    /* tex * scale: either may be a texture; the first image found is kept */
    const char *names[2] = {"tex", "scale"};
    for (int k = 0; k < 2; k++) {
      tt__pparam *p = tt__find(pl, names[k]);
      if (!p) continue;
      float f[3] = {1, 1, 1};
      if (strcmp(p->type, "texture") == 0) {
        const tt__ntex *src = tt__lookup_tex(P, p->str[0], is_float);
        if (!src) {
          tt__pwarn(P, at->file, at->line, names[k], "%s: texture \"%s\" is not defined (1 used)", what, p->str[0]);
        } else {
          memcpy(f, src->rgb, sizeof f);
          if (src->image && !t.image) {
            t.image = tt__strdup(src->image);
            t.srgb = src->srgb;
            if (!t.image) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
          } else if (src->image) {
            tt__pwarn(P, at->file, at->line, names[k], "%s: product of two images; the second is averaged away", what);
          }
        }
      } else {
        tt__texval v = {{1, 1, 1}, -1};
        p->used = 0;
        if ((st = tt__getc(P, at, pl, names[k], TT__SPEC_UNBOUNDED, 0, &v, NULL)) != TT_OK) {
          free(t.image);
          return st;
        }
        memcpy(f, v.rgb, sizeof f);
      }
      for (int i = 0; i < 3; i++) t.rgb[i] *= f[i];
    }
  } else {
    /* checkerboard, mix, dots, fbm, ...: a constant average with a warning */
    float a[3] = {1, 1, 1}, b[3] = {0, 0, 0};
    const char *n1 = "tex1", *n2 = "tex2";
    if (strcmp(cls, "mix") == 0 || strcmp(cls, "directionmix") == 0) {
      a[0] = a[1] = a[2] = 0;
      b[0] = b[1] = b[2] = 1;
    }
    tt__pparam *ps[2] = {tt__find(pl, n1), tt__find(pl, n2)};
    float *dst[2] = {a, b};
    for (int k = 0; k < 2; k++) {
      if (!ps[k]) continue;
      if (strcmp(ps[k]->type, "texture") == 0) {
        const tt__ntex *src = tt__lookup_tex(P, ps[k]->str[0], is_float);
        if (src) memcpy(dst[k], src->rgb, 3 * sizeof(float));
      } else {
        tt__texval v = {{dst[k][0], dst[k][1], dst[k][2]}, -1};
        ps[k]->used = 0;
        if ((st = tt__getc(P, at, pl, k ? n2 : n1, TT__SPEC_UNBOUNDED, 0, &v, NULL)) != TT_OK) return st;
        memcpy(dst[k], v.rgb, 3 * sizeof(float));
      }
    }
    for (int i = 0; i < 3; i++) t.rgb[i] = 0.5f * (a[i] + b[i]);
    tt__pwarn(P, at->file, at->line, cls, "%s: procedural texture \"%s\" replaced by the constant %.3g %.3g %.3g", what, cls,
              (double)t.rgb[0], (double)t.rgb[1], (double)t.rgb[2]);
    for (size_t i = 0; i < pl->n; i++) pl->p[i].used = 1;
  }
  tt__unused(P, at, what, pl);
  t.name = tt__strdup(name);
  P->ntex = tt__grow(P->ntex, &P->capntex, P->nntex + 1, sizeof *P->ntex);
  if (!t.name || !P->ntex) {
    free(t.name);
    free(t.image);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  }
  P->ntex[P->nntex++] = t;
  return TT_OK;
}

/* ---- lights ---------------------------------------------------------------------------- */

/* Appends an explicit light to the scene. */
static tt_status tt__add_light(tt__pp *P, const tt_light *l) {
  tt_scene *s = P->scene;
  tt_light *slot = tt__scene_push((void **)&s->lights, &s->light_count, &s->light_cap, sizeof *slot);
  if (!slot) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  *slot = *l;
  return TT_OK;
}

/* LightSource: point, spot, distant and infinite map to tunetrace lights. */
static tt_status tt__light(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl) {
  tt_status st;
  tt_light l;
  memset(&l, 0, sizeof l);
  l.struct_size = sizeof l;
  char what[160];
  snprintf(what, sizeof what, "LightSource \"%s\"", type);
  double scale = 1, m[16];
  if ((st = tt__getf(P, at, pl, "scale", &scale)) != TT_OK) return st;
  if (tt__find(pl, "power") || tt__find(pl, "illuminance"))
    tt__pwarn(P, at->file, at->line, "power", "%s: photometric \"power\"/\"illuminance\" are not supported (scale used)", what);
  if (P->cur_obj >= 0) {
    tt__pwarn(P, at->file, at->line, "LightSource", "%s inside ObjectBegin is not supported (ignored)", what);
    return TT_OK;
  }
  tt__world_matrix(P, P->gs.ctm, m);
  tt__texval v = {{1, 1, 1}, -1};
  if (strcmp(type, "point") == 0 || strcmp(type, "spot") == 0) {
    double from[3] = {0, 0, 0}, to[3] = {0, 0, 1}, p[3], q[3];
    if ((st = tt__getc(P, at, pl, "I", TT__SPEC_ILLUMINANT, 0, &v, NULL)) != TT_OK) return st;
    if ((st = tt__get3(at, pl, "from", from)) != TT_OK) return st;
    tt__xform_point(m, from, p);
    for (int i = 0; i < 3; i++) {
      l.position[i] = (float)p[i];
      l.radiance[i] = (float)(v.rgb[i] * scale);
    }
    l.type = TT_LIGHT_POINT;
    if (type[0] == 's') {
      double cone = 30, delta = 5, dir[3];
      if ((st = tt__get3(at, pl, "to", to)) != TT_OK) return st;
      if ((st = tt__getf(P, at, pl, "coneangle", &cone)) != TT_OK) return st;
      if ((st = tt__getf(P, at, pl, "conedelta", &delta)) != TT_OK) return st;
      tt__xform_point(m, to, q);
      for (int i = 0; i < 3; i++) dir[i] = q[i] - p[i];
      if (!tt__norm(dir)) return tt__perr(at->file, at->line, "%s: \"from\" equals \"to\"", what);
      for (int i = 0; i < 3; i++) l.direction[i] = (float)dir[i];
      l.type = TT_LIGHT_SPOT;
      if (cone > 90) cone = 90;
      if (cone < 0) cone = 0;
      double inner = cone - delta < 0 ? 0 : cone - delta;
      l.cos_outer = (float)cos(cone * TT__PI / 180);
      l.cos_inner = (float)cos(inner * TT__PI / 180);
    }
  } else if (strcmp(type, "distant") == 0) {
    double from[3] = {0, 0, 0}, to[3] = {0, 0, 1}, w[3], dir[3];
    if ((st = tt__getc(P, at, pl, "L", TT__SPEC_ILLUMINANT, 0, &v, NULL)) != TT_OK) return st;
    if ((st = tt__get3(at, pl, "from", from)) != TT_OK) return st;
    if ((st = tt__get3(at, pl, "to", to)) != TT_OK) return st;
    for (int i = 0; i < 3; i++) w[i] = to[i] - from[i];
    tt__xform_vec(m, w, dir);
    if (!tt__norm(dir)) return tt__perr(at->file, at->line, "%s: \"from\" equals \"to\"", what);
    l.type = TT_LIGHT_DISTANT;
    for (int i = 0; i < 3; i++) {
      l.direction[i] = (float)dir[i];
      l.radiance[i] = (float)(v.rgb[i] * scale);
    }
  } else if (strcmp(type, "infinite") == 0) {
    const char *fn = NULL;
    int hasL;
    if ((st = tt__gets(at, pl, "filename", &fn)) != TT_OK) return st;
    if ((st = tt__getc(P, at, pl, "L", TT__SPEC_ILLUMINANT, 0, &v, &hasL)) != TT_OK) return st;
    tt__find(pl, "portal");
    l.type = TT_LIGHT_ENV_CONSTANT;
    for (int i = 0; i < 3; i++) l.radiance[i] = (float)(v.rgb[i] * scale);
    if (fn) {
      char *path = tt__join(at->file->dir, fn, strlen(fn));
      if (!path) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
      for (int i = 0; i < 3; i++) l.radiance[i] = (float)scale;
      if (tt__exists(path)) {
        l.type = TT_LIGHT_ENV_IMAGE;
        l.image = path;
        tt__pwarn(P, at->file, at->line, "filename",
                  "%s: pbrt-v4 maps \"%s\" with the equal-area octahedral mapping and the light's transform; "
                  "tunetrace reads it as lat-long, untransformed", what, fn);
      } else {
        tt__pwarn(P, at->file, at->line, "filename", "%s: environment image \"%s\" not found, using a constant environment of %g",
                  what, path, scale);
        free(path);
      }
    }
    if (P->env_seen) {
      tt__pwarn(P, at->file, at->line, "infinite", "only one environment light is supported; this one is ignored");
      free((void *)l.image);
      return TT_OK;
    }
    P->env_seen = 1;
  } else {
    static const char *const known[] = {"goniometric", "projection", NULL};
    for (int i = 0; known[i]; i++)
      if (strcmp(type, known[i]) == 0) {
        tt__pwarn(P, at->file, at->line, type, "light \"%s\" is not supported (skipped)", type);
        return TT_OK;
      }
    return tt__perr(at->file, at->line, "unknown light type \"%s\"", type);
  }
  tt__unused(P, at, what, pl);
  st = tt__add_light(P, &l);
  if (st != TT_OK) free((void *)l.image);
  return st;
}

/* AreaLightSource "diffuse": emission for the shapes that follow in this attribute block. */
static tt_status tt__area_light(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl) {
  tt_status st;
  if (strcmp(type, "diffuse") != 0) {
    tt__pwarn(P, at->file, at->line, type, "area light \"%s\" is not supported (ignored)", type);
    return TT_OK;
  }
  tt__texval v = {{1, 1, 1}, -1};
  double scale = 1;
  int two = 0;
  if ((st = tt__getc(P, at, pl, "L", TT__SPEC_ILLUMINANT, 0, &v, NULL)) != TT_OK) return st;
  if ((st = tt__getf(P, at, pl, "scale", &scale)) != TT_OK) return st;
  if ((st = tt__getb(P, at, pl, "twosided", &two)) != TT_OK) return st;
  if (tt__find(pl, "power")) tt__pwarn(P, at->file, at->line, "power", "AreaLightSource: \"power\" is not supported (scale used)");
  if (tt__find(pl, "filename")) tt__pwarn(P, at->file, at->line, "filename", "AreaLightSource: image emission is not supported (L used)");
  tt__unused(P, at, "AreaLightSource \"diffuse\"", pl);
  if (!(scale >= 0)) return tt__perr(at->file, at->line, "AreaLightSource: negative scale %g", scale);
  P->gs.area = 1;
  P->gs.two_sided = two;
  for (int i = 0; i < 3; i++) P->gs.L[i] = (float)(v.rgb[i] * scale);
  return TT_OK;
}

/* ---- camera and options ---------------------------------------------------------------- */

/* Camera: remembers the CTM (cameraFromWorld) and the field of view. */
static tt_status tt__camera(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl) {
  tt_status st;
  if (strcmp(type, "perspective") != 0)
    tt__pwarn(P, at->file, at->line, type, "camera \"%s\" is approximated by a perspective camera", type);
  P->has_camera = 1;
  memcpy(P->cam_ctm, P->gs.ctm, sizeof P->cam_ctm);
  double fov = 90, lens = 0, fa = 0;
  if ((st = tt__getf(P, at, pl, "fov", &fov)) != TT_OK) return st;
  if (!(fov > 0 && fov < 180)) return tt__perr(at->file, at->line, "Camera: fov %g is outside (0, 180)", fov);
  P->fov = fov;
  if ((st = tt__getf(P, at, pl, "lensradius", &lens)) != TT_OK) return st;
  tt__find(pl, "focaldistance");
  if (lens > 0) tt__pwarn(P, at->file, at->line, "lensradius", "Camera: depth of field (lensradius) is not supported (pinhole used)");
  if ((st = tt__getf(P, at, pl, "frameaspectratio", &fa)) != TT_OK) return st;
  P->frame_aspect = fa > 0 ? fa : 0;
  tt__pparam *sw = tt__find(pl, "screenwindow");
  if (sw) {
    if (!sw->num || sw->nnum != 4 || !(sw->num[1] > sw->num[0]) || !(sw->num[3] > sw->num[2]))
      return tt__perr(at->file, at->line, "Camera: \"screenwindow\" needs 4 numbers x0 x1 y0 y1 with x0 < x1, y0 < y1");
    for (int i = 0; i < 4; i++) P->sw[i] = sw->num[i];
    P->has_sw = 1;
    if (fabs(sw->num[0] + sw->num[1]) > 1e-6 || fabs(sw->num[2] + sw->num[3]) > 1e-6)
      tt__pwarn(P, at->file, at->line, "screenwindow", "Camera: off-centre screenwindow is centred (only its height is used)");
  }
  tt__find(pl, "shutteropen");
  tt__find(pl, "shutterclose");
  tt__unused(P, at, "Camera", pl);
  /* the camera's own frame is a named coordinate system */
  double inv[16];
  if (!tt__inverse(P->gs.ctm, inv)) return tt__perr(at->file, at->line, "Camera: the current transform is singular");
  for (size_t i = 0; i < P->ncs; i++)
    if (strcmp(P->cs[i].name, "camera") == 0) {
      memcpy(P->cs[i].m, inv, sizeof inv);
      return TT_OK;
    }
  P->cs = tt__grow(P->cs, &P->capcs, P->ncs + 1, sizeof *P->cs);
  if (!P->cs) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  P->cs[P->ncs].name = tt__strdup("camera");
  if (!P->cs[P->ncs].name) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  memcpy(P->cs[P->ncs].m, inv, sizeof inv);
  P->ncs++;
  return TT_OK;
}

/* Film / Sampler / Integrator: the few values tunetrace keeps; the rest is silent. */
static tt_status tt__option(tt__pp *P, const tt__tok *at, const char *dir, tt__plist *pl) {
  tt_status st;
  if (strcmp(dir, "Film") == 0) {
    double x = (double)P->xres, y = (double)P->yres;
    if ((st = tt__getf(P, at, pl, "xresolution", &x)) != TT_OK) return st;
    if ((st = tt__getf(P, at, pl, "yresolution", &y)) != TT_OK) return st;
    if (!(x >= 1 && x <= 65536 && y >= 1 && y <= 65536))
      return tt__perr(at->file, at->line, "Film: resolution %gx%g is outside 1..65536", x, y);
    P->xres = (long)x;
    P->yres = (long)y;
    if (tt__find(pl, "cropwindow") || tt__find(pl, "pixelbounds"))
      tt__pwarn(P, at->file, at->line, "cropwindow", "Film: cropwindow/pixelbounds are not supported (full frame rendered)");
  } else if (strcmp(dir, "Sampler") == 0) {
    double spp = P->scene->settings.spp;
    if ((st = tt__getf(P, at, pl, "pixelsamples", &spp)) != TT_OK) return st;
    if (!(spp >= 1 && spp <= 16777216)) return tt__perr(at->file, at->line, "Sampler: pixelsamples %g is out of range", spp);
    P->scene->settings.spp = (uint32_t)spp;
  } else if (strcmp(dir, "Integrator") == 0) {
    double md = P->scene->settings.max_depth;
    if ((st = tt__getf(P, at, pl, "maxdepth", &md)) != TT_OK) return st;
    if (!(md >= 0 && md <= 100000)) return tt__perr(at->file, at->line, "Integrator: maxdepth %g is out of range", md);
    P->scene->settings.max_depth = (uint32_t)md;
  }
  return TT_OK;
}

/* ---- directives ------------------------------------------------------------------------ */

/* Skips the arguments of an unknown directive: everything up to the next bare word that is
 * not a number or a bool. */
static tt_status tt__skip_args(tt__pp *P) {
  tt__tok t;
  tt_status st;
  double v;
  int depth = 0;
  for (;;) {
    if ((st = tt__peek(P, &t)) != TT_OK) return st;
    if (t.kind == TK_EOF) return TT_OK;
    if (t.kind == TK_WORD && depth == 0 && !tt__num(&t, &v) && !tt__is(&t, "true") && !tt__is(&t, "false")) return TT_OK;
    if (t.kind == TK_LBRACK) depth++;
    if (t.kind == TK_RBRACK && depth > 0) depth--;
    tt__next(P, &t);
  }
}

/* Include / Import: the included file's tokens continue the stream. */
static tt_status tt__include(tt__pp *P, const tt__tok *at, const char *name) {
  char *path = tt__join(at->file->dir, name, strlen(name));
  if (!path) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  char *real = realpath(path, NULL);
  if (real) {
    for (const tt__pfile *f = P->cur; f; f = f->parent) {
      char *fr = realpath(f->path, NULL);
      int same = fr && strcmp(fr, real) == 0;
      free(fr);
      if (!same) continue;
      /* chain from the outermost file down to the repeated one */
      char chain[2048] = "";
      const tt__pfile *stack[TT__MAX_INCLUDE_DEPTH + 2];
      int n = 0;
      for (const tt__pfile *g = P->cur; g && n < TT__MAX_INCLUDE_DEPTH + 1; g = g->parent) stack[n++] = g;
      for (int i = n - 1; i >= 0; i--) {
        strncat(chain, stack[i]->path, sizeof chain - strlen(chain) - 1);
        strncat(chain, " -> ", sizeof chain - strlen(chain) - 1);
      }
      strncat(chain, path, sizeof chain - strlen(chain) - 1);
      tt_status st = tt__perr(at->file, at->line, "cyclic Include of \"%s\": %s", name, chain);
      free(real);
      free(path);
      return st;
    }
    free(real);
  }
  if (P->depth >= TT__MAX_INCLUDE_DEPTH) {
    free(path);
    return tt__perr(at->file, at->line, "Include nesting deeper than %d", TT__MAX_INCLUDE_DEPTH);
  }
  if (P->has_peek) return tt__perr(at->file, at->line, "internal: Include with a pending token");
  tt_status st = tt__push_file(P, path, at->file, at->line);
  free(path);
  return st;
}

/* Reads one directive and applies it. *done is set at the end of input. */
static tt_status tt__directive(tt__pp *P, int *done) {
  tt__tok t;
  char d[64];
  tt_status st = tt__next(P, &t);
  if (st != TT_OK) return st;
  if (t.kind == TK_EOF) {
    *done = 1;
    return TT_OK;
  }
  if (t.kind != TK_WORD) return tt__perr(t.file, t.line, "expected a directive, got %s", tt__desc(&t, d, sizeof d));
  char name[40];
  snprintf(name, sizeof name, "%.*s", (int)(t.n < 39 ? t.n : 39), t.s);
  double v[16];
  tt__plist pl = {0};
  char *a1 = NULL, *a2 = NULL, *a3 = NULL;
  st = TT_OK;
#define TT__IS(w) (strcmp(name, w) == 0 && t.n == strlen(w))
  int xform = TT__IS("Identity") || TT__IS("Translate") || TT__IS("Scale") || TT__IS("Rotate") || TT__IS("LookAt") ||
              TT__IS("Transform") || TT__IS("ConcatTransform") || TT__IS("CoordSysTransform");
  double saved[16];
  memcpy(saved, P->gs.ctm, sizeof saved);
  if (TT__IS("AttributeBegin") || TT__IS("TransformBegin")) {
    st = tt__push(P, name[0], &t);
  } else if (TT__IS("AttributeEnd") || TT__IS("TransformEnd")) {
    tt__pop(P, name[0], &t);
  } else if (TT__IS("Identity")) {
    tt__ident(P->gs.ctm);
  } else if (TT__IS("Translate")) {
    if ((st = tt__arg_nums(P, &t, 3, v)) == TT_OK) {
      double m[16];
      tt__ident(m);
      m[3] = v[0], m[7] = v[1], m[11] = v[2];
      tt__concat(P, m);
    }
  } else if (TT__IS("Scale")) {
    if ((st = tt__arg_nums(P, &t, 3, v)) == TT_OK) {
      double m[16];
      tt__ident(m);
      m[0] = v[0], m[5] = v[1], m[10] = v[2];
      tt__concat(P, m);
    }
  } else if (TT__IS("Rotate")) {
    if ((st = tt__arg_nums(P, &t, 4, v)) == TT_OK) {
      double a[3] = {v[1], v[2], v[3]}, m[16];
      if (!tt__norm(a)) {
        st = tt__perr(t.file, t.line, "Rotate: zero rotation axis");
      } else {
        double th = v[0] * TT__PI / 180, s = sin(th), c = cos(th);
        tt__ident(m);
        m[0] = a[0] * a[0] + (1 - a[0] * a[0]) * c;
        m[1] = a[0] * a[1] * (1 - c) - a[2] * s;
        m[2] = a[0] * a[2] * (1 - c) + a[1] * s;
        m[4] = a[0] * a[1] * (1 - c) + a[2] * s;
        m[5] = a[1] * a[1] + (1 - a[1] * a[1]) * c;
        m[6] = a[1] * a[2] * (1 - c) - a[0] * s;
        m[8] = a[0] * a[2] * (1 - c) - a[1] * s;
        m[9] = a[1] * a[2] * (1 - c) + a[0] * s;
        m[10] = a[2] * a[2] + (1 - a[2] * a[2]) * c;
        tt__concat(P, m);
      }
    }
  } else if (TT__IS("LookAt")) {
    if ((st = tt__arg_nums(P, &t, 9, v)) == TT_OK) {
      double dir[3] = {v[3] - v[0], v[4] - v[1], v[5] - v[2]}, up[3] = {v[6], v[7], v[8]}, right[3], nu[3];
      if (!tt__norm(dir) || !tt__norm(up)) {
        st = tt__perr(t.file, t.line, "LookAt: eye equals target or up is zero");
      } else {
        tt__cross(up, dir, right);
        if (!tt__norm(right)) {
          st = tt__perr(t.file, t.line, "LookAt: up vector is parallel to the view direction");
        } else {
          tt__cross(dir, right, nu);
          double wfc[16] = {right[0], nu[0], dir[0], v[0], right[1], nu[1], dir[1], v[1],
                            right[2], nu[2], dir[2], v[2], 0, 0, 0, 1}, cfw[16];
          if (!tt__inverse(wfc, cfw)) st = tt__perr(t.file, t.line, "LookAt: degenerate frame");
          else tt__concat(P, cfw);
        }
      }
    }
  } else if (TT__IS("Transform") || TT__IS("ConcatTransform")) {
    if ((st = tt__arg_nums(P, &t, 16, v)) == TT_OK) {
      /* the 16 numbers are the matrix column by column */
      double m[16];
      for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) m[4 * r + c] = v[4 * c + r];
      if (name[0] == 'T') memcpy(P->gs.ctm, m, sizeof m);
      else tt__concat(P, m);
    }
  } else if (TT__IS("CoordinateSystem") || TT__IS("CoordSysTransform")) {
    if ((st = tt__arg_str(P, &t, "a coordinate system name", &a1)) == TT_OK) {
      size_t i;
      for (i = 0; i < P->ncs; i++)
        if (strcmp(P->cs[i].name, a1) == 0) break;
      if (name[5] == 'i') { /* CoordinateSystem */
        if (i == P->ncs) {
          P->cs = tt__grow(P->cs, &P->capcs, P->ncs + 1, sizeof *P->cs);
          if (!P->cs) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
          else {
            P->cs[P->ncs].name = a1;
            a1 = NULL;
            P->ncs++;
          }
        }
        if (st == TT_OK) memcpy(P->cs[i].m, P->gs.ctm, sizeof P->gs.ctm);
      } else if (i < P->ncs) {
        memcpy(P->gs.ctm, P->cs[i].m, sizeof P->gs.ctm);
      } else {
        tt__pwarn(P, t.file, t.line, a1, "CoordSysTransform: no coordinate system named \"%s\" (ignored)", a1);
      }
    }
  } else if (TT__IS("ReverseOrientation")) {
    P->gs.reverse = !P->gs.reverse;
  } else if (TT__IS("WorldBegin")) {
    if (P->in_world) tt__pwarn(P, t.file, t.line, "WorldBegin", "second WorldBegin (ignored)");
    P->in_world = 1;
    tt__world_setup(P);
    tt__ident(P->gs.ctm);
    P->cs = tt__grow(P->cs, &P->capcs, P->ncs + 1, sizeof *P->cs);
    if (!P->cs) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    else if (!(P->cs[P->ncs].name = tt__strdup("world"))) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    else tt__ident(P->cs[P->ncs++].m);
  } else if (TT__IS("WorldEnd")) {
    /* pbrt-v3 leftover: harmless */
  } else if (TT__IS("Camera")) {
    if ((st = tt__arg_str(P, &t, "a camera type", &a1)) == TT_OK && (st = tt__params(P, &pl)) == TT_OK)
      st = tt__camera(P, &t, a1, &pl);
  } else if (TT__IS("Film") || TT__IS("Sampler") || TT__IS("Integrator") || TT__IS("PixelFilter") ||
             TT__IS("Accelerator") || TT__IS("ColorSpace")) {
    if ((st = tt__arg_str(P, &t, "a type name", &a1)) == TT_OK && (st = tt__params(P, &pl)) == TT_OK)
      st = tt__option(P, &t, name, &pl);
  } else if (TT__IS("Option")) {
    st = tt__params(P, &pl);
  } else if (TT__IS("Material")) {
    if ((st = tt__arg_str(P, &t, "a material type", &a1)) == TT_OK && (st = tt__params(P, &pl)) == TT_OK)
      st = tt__make_material(P, &t, a1, &pl, NULL, &P->gs.mat);
  } else if (TT__IS("MakeNamedMaterial")) {
    if ((st = tt__arg_str(P, &t, "a material name", &a1)) == TT_OK && (st = tt__params(P, &pl)) == TT_OK) {
      const char *type = NULL;
      if ((st = tt__gets(&t, &pl, "type", &type)) == TT_OK) {
        int32_t mat;
        if (!type) st = tt__perr(t.file, t.line, "MakeNamedMaterial \"%s\": missing \"string type\"", a1);
        else if ((st = tt__make_material(P, &t, type, &pl, a1, &mat)) == TT_OK) {
          P->nmat = tt__grow(P->nmat, &P->capnmat, P->nnmat + 1, sizeof *P->nmat);
          if (!P->nmat) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
          else {
            P->nmat[P->nnmat].name = a1;
            P->nmat[P->nnmat].mat = mat;
            P->nnmat++;
            a1 = NULL;
          }
        }
      }
    }
  } else if (TT__IS("NamedMaterial")) {
    if ((st = tt__arg_str(P, &t, "a material name", &a1)) == TT_OK) {
      size_t i;
      for (i = P->nnmat; i-- > 0;)
        if (strcmp(P->nmat[i].name, a1) == 0) break;
      if (i == (size_t)-1) st = tt__perr(t.file, t.line, "NamedMaterial: no material named \"%s\"", a1);
      else P->gs.mat = P->nmat[i].mat;
    }
  } else if (TT__IS("Texture")) {
    if ((st = tt__arg_str(P, &t, "a texture name", &a1)) == TT_OK &&
        (st = tt__arg_str(P, &t, "a texture type (\"float\" or \"spectrum\")", &a2)) == TT_OK &&
        (st = tt__arg_str(P, &t, "a texture class", &a3)) == TT_OK && (st = tt__params(P, &pl)) == TT_OK)
      st = tt__texture(P, &t, a1, a2, a3, &pl);
  } else if (TT__IS("Shape")) {
    if ((st = tt__arg_str(P, &t, "a shape type", &a1)) == TT_OK && (st = tt__params(P, &pl)) == TT_OK)
      st = tt__shape(P, &t, a1, &pl);
  } else if (TT__IS("LightSource")) {
    if ((st = tt__arg_str(P, &t, "a light type", &a1)) == TT_OK && (st = tt__params(P, &pl)) == TT_OK)
      st = tt__light(P, &t, a1, &pl);
  } else if (TT__IS("AreaLightSource")) {
    if ((st = tt__arg_str(P, &t, "an area light type", &a1)) == TT_OK && (st = tt__params(P, &pl)) == TT_OK)
      st = tt__area_light(P, &t, a1, &pl);
  } else if (TT__IS("Include") || TT__IS("Import")) {
    if ((st = tt__arg_str(P, &t, "a file name", &a1)) == TT_OK) st = tt__include(P, &t, a1);
  } else if (TT__IS("ObjectBegin")) {
    if ((st = tt__arg_str(P, &t, "an object name", &a1)) == TT_OK) {
      if (P->cur_obj >= 0) st = tt__perr(t.file, t.line, "ObjectBegin \"%s\" inside another ObjectBegin", a1);
      else if ((st = tt__push(P, 'O', &t)) == TT_OK) {
        P->obj = tt__grow(P->obj, &P->capobj, P->nobj + 1, sizeof *P->obj);
        if (!P->obj) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
        else {
          memset(&P->obj[P->nobj], 0, sizeof P->obj[0]);
          P->obj[P->nobj].name = a1;
          a1 = NULL;
          P->cur_obj = (int)P->nobj++;
        }
      }
    }
  } else if (TT__IS("ObjectEnd")) {
    if (P->cur_obj < 0) tt__pwarn(P, t.file, t.line, "ObjectEnd", "ObjectEnd without ObjectBegin (ignored)");
    else {
      tt__pop(P, 'O', &t);
      P->cur_obj = -1;
    }
  } else if (TT__IS("ObjectInstance")) {
    if ((st = tt__arg_str(P, &t, "an object name", &a1)) == TT_OK) st = tt__instance(P, &t, a1);
  } else if (TT__IS("MakeNamedMedium") || TT__IS("MediumInterface")) {
    tt__pwarn(P, t.file, t.line, name, "%s: participating media are not supported (ignored)", name);
    if ((st = tt__arg_str(P, &t, "a name", &a1)) == TT_OK) {
      tt__tok n2;
      if (TT__IS("MediumInterface") && (st = tt__peek(P, &n2)) == TT_OK && n2.kind == TK_STRING) tt__next(P, &n2);
      if (st == TT_OK && TT__IS("MakeNamedMedium")) st = tt__params(P, &pl);
    }
  } else if (TT__IS("Attribute")) {
    tt__pwarn(P, t.file, t.line, name, "Attribute (default parameters) is not supported (ignored)");
    if ((st = tt__arg_str(P, &t, "a target", &a1)) == TT_OK) st = tt__params(P, &pl);
  } else if (TT__IS("ActiveTransform")) {
    /* motion blur: the scene is frozen at the start time, so end-time transforms are
     * dropped */
    tt__tok w;
    if ((st = tt__next(P, &w)) == TT_OK) {
      if (tt__is(&w, "StartTime") || tt__is(&w, "All")) P->end_only = 0;
      else if (tt__is(&w, "EndTime")) {
        P->end_only = 1;
        tt__pwarn(P, t.file, t.line, name, "motion blur is not supported: end-time transforms are ignored");
      } else st = tt__perr(w.file, w.line, "ActiveTransform: expected StartTime, EndTime or All, got %s", tt__desc(&w, d, sizeof d));
    }
  } else if (TT__IS("TransformTimes")) {
    st = tt__arg_nums(P, &t, 2, v);
  } else {
    tt__pwarn(P, t.file, t.line, name, "unknown directive \"%s\" (skipped with its arguments)", name);
    st = tt__skip_args(P);
  }
#undef TT__IS
  if (xform && P->end_only) memcpy(P->gs.ctm, saved, sizeof saved);
  free(a1);
  free(a2);
  free(a3);
  tt__plist_free(&pl);
  return st;
}

/* ---- entry point ----------------------------------------------------------------------- */

/* Frees the parser's own state (never the scene). */
static void tt__pp_free(tt__pp *P) {
  for (tt__pfile *f = P->files; f;) {
    tt__pfile *n = f->next;
    free(f->path);
    free(f->dir);
    free(f->text);
    free(f);
    f = n;
  }
  for (size_t i = 0; i < P->nwarned; i++) free(P->warned[i]);
  free(P->warned);
  free(P->stack);
  for (size_t i = 0; i < P->nnmat; i++) free(P->nmat[i].name);
  free(P->nmat);
  for (size_t i = 0; i < P->nntex; i++) {
    free(P->ntex[i].name);
    free(P->ntex[i].image);
  }
  free(P->ntex);
  for (size_t i = 0; i < P->ncs; i++) free(P->cs[i].name);
  free(P->cs);
  for (size_t i = 0; i < P->nobj; i++) {
    for (size_t k = 0; k < P->obj[i].n; k++) tt__mesh_data_free(&P->obj[i].m[k].d);
    free(P->obj[i].m);
    free(P->obj[i].name);
  }
  free(P->obj);
  free(P->der);
}

/* pbrt's fov spans the shorter image side (or the screen window's height). */
static void tt__finish_camera(tt__pp *P) {
  tt_camera *c = &P->scene->camera;
  c->width = (uint32_t)P->xres;
  c->height = (uint32_t)P->yres;
  double aspect = P->frame_aspect > 0 ? P->frame_aspect : (double)P->xres / (double)P->yres;
  double t = tan(0.5 * P->fov * TT__PI / 180.0);
  double half_h = P->has_sw ? 0.5 * (P->sw[3] - P->sw[2]) : (aspect > 1 ? 1.0 : 1.0 / aspect);
  double fy = 2.0 * atan(t * half_h) * 180.0 / TT__PI;
  if (fy < 1e-3) fy = 1e-3;
  if (fy > 179.9) fy = 179.9;
  c->fov_y = (float)fy;
}

tt_status tt__scene_load_pbrt(const char *path, tt_scene **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_scene_load: out is NULL");
  *out = NULL;
  tt__pp P;
  memset(&P, 0, sizeof P);
  P.scene = tt__scene_new(path);
  if (!P.scene) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
  /* pbrt-v4 defaults: 16 samples per pixel, path depth 5, 1280x720, fov 90 */
  P.scene->settings.spp = 16;
  P.scene->settings.max_depth = 5;
  P.xres = 1280;
  P.yres = 720;
  P.fov = 90;
  P.cur_obj = -1;
  P.default_mat = -1;
  P.gs.mat = -1;
  tt__ident(P.gs.ctm);
  tt_status st = tt__push_file(&P, path, NULL, 0);
  int done = 0;
  while (st == TT_OK && !done) st = tt__directive(&P, &done);
  if (st == TT_OK && P.cur_obj >= 0)
    st = tt__perr(P.files, P.files ? P.files->line : 0, "ObjectBegin \"%s\" is never closed", P.obj[P.cur_obj].name);
  if (st == TT_OK) {
    if (!P.in_world && P.scene->mesh_count == 0)
      tt__pwarn(&P, P.files, 0, "WorldBegin", "no WorldBegin: the file describes no world");
    tt__world_setup(&P);
    tt__finish_camera(&P);
    st = tt__scene_finish(P.scene);
  }
  if (P.suppressed)
    tt__log(TT_LOG_WARN, "%s: %u more warnings suppressed", path, P.suppressed);
  tt__pp_free(&P);
  if (st != TT_OK) {
    tt_scene_destroy(P.scene);
    return st;
  }
  *out = P.scene;
  return TT_OK;
}
