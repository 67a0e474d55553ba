/* pbrt-v4 importer: parameter lists ("type name" [values]), their typed lookups with
 * messages naming the directive and the parameter, and colour values that may be spectra or
 * textures. */
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

/* ---- parameter lists ------------------------------------------------------------------- */

/* Frees a parameter list's contents. */
void tt__plist_free(tt__plist *pl) {
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
  static const char *const nums[] = {"integer", "float",  "point2",    "vector2", "point3",
                                     "vector3", "normal", "normal3",   "point",   "vector",
                                     "color",   "rgb",    "blackbody", NULL};
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
      else
        return tt__perr(t->file, t->line, "parameter \"%s %s\": expected true or false, got %s",
                        p->type, p->name, tt__desc(t, d, sizeof d));
    } else if (!tt__num(t, &v)) {
      return tt__perr(t->file, t->line, "parameter \"%s %s\": bad number %s", p->type, p->name,
                      tt__desc(t, d, sizeof d));
    } else if (!numeric && !is_spec) {
      return tt__perr(t->file, t->line, "parameter \"%s %s\": expected a quoted string, got %s",
                      p->type, p->name, tt__desc(t, d, sizeof d));
    }
    if (p->nstr)
      return tt__perr(t->file, t->line, "parameter \"%s %s\": mixes strings and numbers", p->type,
                      p->name);
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
      else
        return tt__perr(t->file, t->line, "parameter \"%s %s\": expected true or false, got %s",
                        p->type, p->name, tt__desc(t, d, sizeof d));
      size_t cap = p->nnum;
      if ((cap & (cap - 1)) == 0) {
        double *n = realloc(p->num, (cap ? 2 * cap : 1) * sizeof *n);
        if (!n) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
        p->num = n;
      }
      p->num[p->nnum++] = v;
      return TT_OK;
    }
    if (numeric)
      return tt__perr(t->file, t->line, "parameter \"%s %s\": expected numbers, got the string %s",
                      p->type, p->name, tt__desc(t, d, sizeof d));
    if (p->nnum)
      return tt__perr(t->file, t->line, "parameter \"%s %s\": mixes strings and numbers", p->type,
                      p->name);
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
  return tt__perr(t->file, t->line, "parameter \"%s %s\": unexpected %s", p->type, p->name,
                  tt__desc(t, d, sizeof d));
}

/* Reads "type name" value pairs until the next token is not a string. */
tt_status tt__params(tt__pp *P, tt__plist *pl) {
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
      return tt__perr(decl.file, decl.line, "bad parameter declaration %s (expected \"type name\")",
                      tt__desc(&decl, d, sizeof d));
    int numeric;
    if (!tt__ptype(w0, &numeric))
      return tt__perr(decl.file, decl.line, "parameter \"%s %s\": unknown parameter type \"%s\"",
                      w0, w1, w0);
    strcpy(p->type, w0);
    strcpy(p->name, w1);
    if ((st = tt__next(P, &t)) != TT_OK) return st;
    if (t.kind == TK_LBRACK) {
      tt__tok open = t;
      for (;;) {
        if ((st = tt__next(P, &t)) != TT_OK) return st;
        if (t.kind == TK_RBRACK) break;
        if (t.kind == TK_EOF || t.file != open.file)
          return tt__perr(open.file, open.line, "unterminated '[' array of parameter \"%s %s\"",
                          p->type, p->name);
        if (t.kind == TK_LBRACK)
          return tt__perr(t.file, t.line, "parameter \"%s %s\": nested '['", p->type, p->name);
        if ((st = tt__pvalue(p, &t)) != TT_OK) return st;
      }
    } else if (t.kind == TK_STRING ||
               (t.kind == TK_WORD &&
                (tt__is(&t, "true") || tt__is(&t, "false") || tt__num(&t, &(double){0})))) {
      if ((st = tt__pvalue(p, &t)) != TT_OK) return st;
    } else {
      return tt__perr(decl.file, decl.line, "parameter \"%s %s\" has no value (got %s)", p->type,
                      p->name, tt__desc(&t, d, sizeof d));
    }
    if (p->nnum == 0 && p->nstr == 0)
      return tt__perr(decl.file, decl.line, "parameter \"%s %s\" has an empty value", p->type,
                      p->name);
  }
}

/* Last parameter with this name (pbrt lets later ones win); marks it used and remembers
 * the name as one the importer reads (for "did you mean"). */
tt__pparam *tt__find(tt__plist *pl, const char *name) {
  size_t len = strlen(name);
  int known = 0;
  for (unsigned k = 0; k < pl->nasked && !known; k++) known = !strcmp(pl->asked[k], name);
  if (!known && len < sizeof pl->asked[0] && pl->nasked < sizeof pl->asked / sizeof pl->asked[0])
    memcpy(pl->asked[pl->nasked++], name, len + 1);
  for (size_t i = pl->n; i-- > 0;)
    if (strcmp(pl->p[i].name, name) == 0) {
      for (size_t k = 0; k < pl->n; k++)
        if (strcmp(pl->p[k].name, name) == 0) pl->p[k].used = 1;
      return &pl->p[i];
    }
  return NULL;
}

/* Every parameter nobody read: pbrt-v4 rejects unused parameters, so under --strict an
 * error; a name close to one the importer read is a likely typo and gets "did you mean". */
void tt__unused(tt__pp *P, const tt__tok *at, const char *what, tt__plist *pl) {
  const char *asked[sizeof pl->asked / sizeof pl->asked[0]];
  for (unsigned k = 0; k < pl->nasked; k++) asked[k] = pl->asked[k];
  for (size_t i = 0; i < pl->n; i++)
    if (!pl->p[i].used) {
      const char *near = tt_suggest(pl->p[i].name, asked, pl->nasked);
      if (near)
        tt__pstrict(P, at->file, at->line, pl->p[i].name,
                    "%s: unknown parameter \"%s %s\" "
                    "(did you mean \"%s\"?)",
                    what, pl->p[i].type, pl->p[i].name, near);
      else
        tt__pstrict(P, at->file, at->line, pl->p[i].name,
                    "%s: parameter \"%s %s\" is not "
                    "used by the importer",
                    what, pl->p[i].type, pl->p[i].name);
    }
}

/* A single float (or integer); textures are not supported for scalars. */
tt_status tt__getf(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *name, double *v) {
  tt__pparam *p = tt__find(pl, name);
  if (!p) return TT_OK;
  if (strcmp(p->type, "texture") == 0) {
    tt__pwarn(P, at->file, at->line, name, "textured \"%s\" is not supported; using the default %g",
              name, *v);
    return TT_OK;
  }
  if (strcmp(p->type, "float") != 0 && strcmp(p->type, "integer") != 0)
    return tt__perr(at->file, at->line, "parameter \"%s %s\": expected a float", p->type, p->name);
  *v = p->num[0];
  return TT_OK;
}

/* A bool parameter. */
tt_status tt__getb(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *name, int *v) {
  (void)P;
  tt__pparam *p = tt__find(pl, name);
  if (!p) return TT_OK;
  if (strcmp(p->type, "bool") != 0)
    return tt__perr(at->file, at->line, "parameter \"%s %s\": expected a bool", p->type, p->name);
  *v = p->num[0] != 0;
  return TT_OK;
}

/* A string parameter (NULL stays when absent); the pointer lives in the list. */
tt_status tt__gets(const tt__tok *at, tt__plist *pl, const char *name, const char **v) {
  tt__pparam *p = tt__find(pl, name);
  if (!p) return TT_OK;
  if (strcmp(p->type, "string") != 0 || !p->nstr)
    return tt__perr(at->file, at->line, "parameter \"%s %s\": expected a string", p->type, p->name);
  *v = p->str[0];
  return TT_OK;
}

/* A point/vector of 3 numbers. */
tt_status tt__get3(const tt__tok *at, tt__plist *pl, const char *name, double v[3]) {
  tt__pparam *p = tt__find(pl, name);
  if (!p) return TT_OK;
  if (!p->num || p->nnum != 3)
    return tt__perr(at->file, at->line, "parameter \"%s %s\": expected 3 numbers, got %zu", p->type,
                    p->name, p->nnum);
  for (int i = 0; i < 3; i++) v[i] = p->num[i];
  return TT_OK;
}

/* Reads a .spd file of "lambda value" pairs ('#' comments). */
static tt_status tt__read_spd(tt__pp *P, const tt__tok *at, const char *path, double **pairs,
                              size_t *n) {
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
    tt__pwarn(P, at->file, at->line, path,
              "spectrum file \"%s\" does not hold (lambda, value) pairs", path);
    return TT_ERR_PARSE;
  }
  *pairs = v;
  *n = cnt / 2;
  return TT_OK;
}

/* Resolves a texture name to its value; unknown names warn and keep the default. */
const tt__ntex *tt__lookup_tex(tt__pp *P, const char *name, int is_float) {
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
  tt_texture *t =
      tt__scene_push((void **)&s->textures, &s->texture_count, &s->texture_cap, sizeof *t);
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
tt_status tt__getc(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *name,
                   tt__spectrum_use use, int allow_tex, tt__texval *v, int *found) {
  tt__pparam *p = tt__find(pl, name);
  if (found) *found = p != NULL;
  if (!p) return TT_OK;
  const char *ty = p->type;
  if (strcmp(ty, "rgb") == 0 || strcmp(ty, "color") == 0) {
    if (p->nnum != 3)
      return tt__perr(at->file, at->line, "parameter \"%s %s\": expected 3 numbers, got %zu", ty,
                      p->name, p->nnum);
    for (int i = 0; i < 3; i++) {
      if (p->num[i] < 0)
        return tt__perr(at->file, at->line, "parameter \"%s %s\": negative component %g", ty,
                        p->name, p->num[i]);
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
        tt__pwarn(P, at->file, at->line, p->name,
                  "spectrum \"%s\" for \"%s\" is unknown; using the default", p->str[0], p->name);
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
      if (p->nnum % 2)
        return tt__perr(
            at->file, at->line,
            "parameter \"spectrum %s\": expected (lambda, value) pairs, got %zu numbers", p->name,
            p->nnum);
      tt__pbrt_sampled_spectrum(p->num, p->nnum / 2, use, v->rgb);
    }
    v->tex = -1;
    return TT_OK;
  }
  if (strcmp(ty, "texture") == 0) {
    if (!allow_tex) {
      tt__pwarn(P, at->file, at->line, p->name,
                "textured \"%s\" is not supported here; using the default", p->name);
      return TT_OK;
    }
    const tt__ntex *t = tt__lookup_tex(P, p->str[0], 0);
    if (!t) {
      tt__pwarn(P, at->file, at->line, p->name,
                "texture \"%s\" is not defined; using the default for \"%s\"", p->str[0], p->name);
      return TT_OK;
    }
    memcpy(v->rgb, t->rgb, sizeof v->rgb);
    v->tex = -1;
    if (t->image) return tt__scene_texture(P, t->image, t->srgb, &v->tex);
    return TT_OK;
  }
  return tt__perr(at->file, at->line,
                  "parameter \"%s %s\": expected a colour (rgb, spectrum, blackbody or texture)",
                  ty, p->name);
}
