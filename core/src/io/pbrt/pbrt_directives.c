/* pbrt-v4 importer: the directives. A {name, handler} table maps each directive to one
 * function that reads its arguments and applies it through the graphics state, materials,
 * geometry and lights files; unknown directives warn and are skipped with their arguments. */
#include "io/pbrt/pbrt_internal.h"
#include "plugin/log.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

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
    if (t.kind == TK_WORD && depth == 0 && !tt__num(&t, &v) && !tt__is(&t, "true") &&
        !tt__is(&t, "false"))
      return TT_OK;
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
      for (const tt__pfile *g = P->cur; g && n < TT__MAX_INCLUDE_DEPTH + 1; g = g->parent)
        stack[n++] = g;
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

/* ---- one function per directive ---------------------------------------------------------
 * Each reads its arguments after the directive token `at` and applies it; `name` is the
 * directive as written (for messages). The table below maps names to them. */

typedef tt_status (*tt__typed_fn)(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl);

/* The common shape "Directive "type" params...": reads both and calls fn. */
static tt_status tt__typed(tt__pp *P, const tt__tok *at, const char *what, tt__typed_fn fn) {
  char *type = NULL;
  tt__plist pl = {0};
  tt_status st = tt__arg_str(P, at, what, &type);
  if (st == TT_OK) st = tt__params(P, &pl);
  if (st == TT_OK) st = fn(P, at, type, &pl);
  free(type);
  tt__plist_free(&pl);
  return st;
}

static tt_status tt__d_attribute_begin(tt__pp *P, const tt__tok *at, const char *name) {
  return tt__push(P, name[0], at); /* 'A'ttributeBegin or 'T'ransformBegin */
}

static tt_status tt__d_attribute_end(tt__pp *P, const tt__tok *at, const char *name) {
  tt__pop(P, name[0], at);
  return TT_OK;
}

static tt_status tt__d_identity(tt__pp *P, const tt__tok *at, const char *name) {
  double m[16];
  tt__ident(m);
  tt__ctm_set(P, m);
  return TT_OK;
}

static tt_status tt__d_translate(tt__pp *P, const tt__tok *at, const char *name) {
  double v[3], m[16];
  tt_status st = tt__arg_nums(P, at, 3, v);
  if (st != TT_OK) return st;
  tt__ident(m);
  m[3] = v[0], m[7] = v[1], m[11] = v[2];
  tt__concat(P, m);
  return TT_OK;
}

static tt_status tt__d_scale(tt__pp *P, const tt__tok *at, const char *name) {
  double v[3], m[16];
  tt_status st = tt__arg_nums(P, at, 3, v);
  if (st != TT_OK) return st;
  tt__ident(m);
  m[0] = v[0], m[5] = v[1], m[10] = v[2];
  tt__concat(P, m);
  return TT_OK;
}

static tt_status tt__d_rotate(tt__pp *P, const tt__tok *at, const char *name) {
  double v[4], m[16];
  tt_status st = tt__arg_nums(P, at, 4, v);
  if (st != TT_OK) return st;
  double a[3] = {v[1], v[2], v[3]};
  if (!tt__norm(a)) return tt__perr(at->file, at->line, "Rotate: zero rotation axis");
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
  return TT_OK;
}

static tt_status tt__d_look_at(tt__pp *P, const tt__tok *at, const char *name) {
  double v[9];
  tt_status st = tt__arg_nums(P, at, 9, v);
  if (st != TT_OK) return st;
  double dir[3] = {v[3] - v[0], v[4] - v[1], v[5] - v[2]}, up[3] = {v[6], v[7], v[8]}, right[3],
         nu[3];
  if (!tt__norm(dir) || !tt__norm(up))
    return tt__perr(at->file, at->line, "LookAt: eye equals target or up is zero");
  tt__cross(up, dir, right);
  if (!tt__norm(right))
    return tt__perr(at->file, at->line, "LookAt: up vector is parallel to the view direction");
  tt__cross(dir, right, nu);
  double wfc[16] = {right[0], nu[0], dir[0], v[0], right[1], nu[1], dir[1], v[1],
                    right[2], nu[2], dir[2], v[2], 0,        0,     0,      1},
         cfw[16];
  if (!tt__inverse(wfc, cfw)) return tt__perr(at->file, at->line, "LookAt: degenerate frame");
  tt__concat(P, cfw);
  return TT_OK;
}

/* Transform replaces the CTM, ConcatTransform multiplies it. */
static tt_status tt__d_transform(tt__pp *P, const tt__tok *at, const char *name) {
  double v[16];
  tt_status st = tt__arg_nums(P, at, 16, v);
  if (st != TT_OK) return st;
  /* the 16 numbers are the matrix column by column */
  double m[16];
  for (int r = 0; r < 4; r++)
    for (int c = 0; c < 4; c++) m[4 * r + c] = v[4 * c + r];
  if (name[0] == 'T') tt__ctm_set(P, m);
  else tt__concat(P, m);
  return TT_OK;
}

/* Index of the named coordinate system, or P->ncs. */
static size_t tt__coordsys_find(const tt__pp *P, const char *cs) {
  size_t i;
  for (i = 0; i < P->ncs; i++)
    if (strcmp(P->cs[i].name, cs) == 0) break;
  return i;
}

static tt_status tt__d_coordinate_system(tt__pp *P, const tt__tok *at, const char *name) {
  char *cs = NULL;
  tt_status st = tt__arg_str(P, at, "a coordinate system name", &cs);
  if (st != TT_OK) return st;
  size_t i = tt__coordsys_find(P, cs);
  if (i == P->ncs) {
    P->cs = tt__grow(P->cs, &P->capcs, P->ncs + 1, sizeof *P->cs);
    if (!P->cs) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    else {
      P->cs[P->ncs].name = cs;
      cs = NULL;
      P->ncs++;
    }
  }
  if (st == TT_OK) {
    memcpy(P->cs[i].m, P->gs.ctm, sizeof P->gs.ctm);
    memcpy(P->cs[i].m_end, P->gs.ctm_end, sizeof P->gs.ctm_end);
  }
  free(cs);
  return st;
}

static tt_status tt__d_coord_sys_transform(tt__pp *P, const tt__tok *at, const char *name) {
  char *cs = NULL;
  tt_status st = tt__arg_str(P, at, "a coordinate system name", &cs);
  if (st != TT_OK) return st;
  size_t i = tt__coordsys_find(P, cs);
  if (i < P->ncs) { /* pbrt-v4: both CTMs, whatever ActiveTransform says */
    memcpy(P->gs.ctm, P->cs[i].m, sizeof P->gs.ctm);
    memcpy(P->gs.ctm_end, P->cs[i].m_end, sizeof P->gs.ctm_end);
  } else
    tt__pwarn(P, at->file, at->line, cs,
              "CoordSysTransform: no coordinate system named \"%s\" (ignored)", cs);
  free(cs);
  return st;
}

static tt_status tt__d_reverse_orientation(tt__pp *P, const tt__tok *at, const char *name) {
  P->gs.reverse = !P->gs.reverse;
  return TT_OK;
}

static tt_status tt__d_world_begin(tt__pp *P, const tt__tok *at, const char *name) {
  if (P->in_world) tt__pwarn(P, at->file, at->line, "WorldBegin", "second WorldBegin (ignored)");
  P->in_world = 1;
  tt__world_setup(P);
  tt__ident(P->gs.ctm);
  tt__ident(P->gs.ctm_end);
  P->cs = tt__grow(P->cs, &P->capcs, P->ncs + 1, sizeof *P->cs);
  if (!P->cs) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  if (!(P->cs[P->ncs].name = tt__strdup("world")))
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  tt__ident(P->cs[P->ncs].m);
  tt__ident(P->cs[P->ncs++].m_end);
  return TT_OK;
}

static tt_status tt__d_world_end(tt__pp *P, const tt__tok *at, const char *name) {
  return TT_OK; /* pbrt-v3 leftover: harmless */
}

static tt_status tt__d_camera(tt__pp *P, const tt__tok *at, const char *name) {
  return tt__typed(P, at, "a camera type", tt__camera);
}

/* Film, Sampler, Integrator, PixelFilter, Accelerator, ColorSpace: tt__option keeps what
 * tunetrace uses. */
static tt_status tt__d_option_block(tt__pp *P, const tt__tok *at, const char *name) {
  char *type = NULL;
  tt__plist pl = {0};
  tt_status st = tt__arg_str(P, at, "a type name", &type);
  if (st == TT_OK) st = tt__params(P, &pl);
  if (st == TT_OK) st = tt__option(P, at, name, &pl);
  free(type);
  tt__plist_free(&pl);
  return st;
}

static tt_status tt__d_option(tt__pp *P, const tt__tok *at, const char *name) {
  tt__plist pl = {0};
  tt_status st = tt__params(P, &pl);
  tt__plist_free(&pl);
  return st;
}

/* Material "type": the current material (a NULL name: not a named one). */
static tt_status tt__material_current(tt__pp *P, const tt__tok *at, const char *type,
                                      tt__plist *pl) {
  return tt__make_material(P, at, type, pl, NULL, &P->gs.mat);
}

static tt_status tt__d_material(tt__pp *P, const tt__tok *at, const char *name) {
  return tt__typed(P, at, "a material type", tt__material_current);
}

static tt_status tt__d_make_named_material(tt__pp *P, const tt__tok *at, const char *name) {
  char *mname = NULL;
  tt__plist pl = {0};
  tt_status st = tt__arg_str(P, at, "a material name", &mname);
  if (st == TT_OK) st = tt__params(P, &pl);
  const char *type = NULL;
  if (st == TT_OK) st = tt__gets(at, &pl, "type", &type);
  if (st == TT_OK) {
    int32_t mat;
    if (!type)
      st = tt__perr(at->file, at->line, "MakeNamedMaterial \"%s\": missing \"string type\"", mname);
    else if ((st = tt__make_material(P, at, type, &pl, mname, &mat)) == TT_OK) {
      P->nmat = tt__grow(P->nmat, &P->capnmat, P->nnmat + 1, sizeof *P->nmat);
      if (!P->nmat) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
      else {
        P->nmat[P->nnmat].name = mname;
        P->nmat[P->nnmat].mat = mat;
        P->nnmat++;
        mname = NULL;
      }
    }
  }
  free(mname);
  tt__plist_free(&pl);
  return st;
}

static tt_status tt__d_named_material(tt__pp *P, const tt__tok *at, const char *name) {
  char *mname = NULL;
  tt_status st = tt__arg_str(P, at, "a material name", &mname);
  if (st != TT_OK) return st;
  size_t i;
  for (i = P->nnmat; i-- > 0;)
    if (strcmp(P->nmat[i].name, mname) == 0) break;
  if (i == (size_t)-1)
    st = tt__perr(at->file, at->line, "NamedMaterial: no material named \"%s\"", mname);
  else P->gs.mat = P->nmat[i].mat;
  free(mname);
  return st;
}

static tt_status tt__d_texture(tt__pp *P, const tt__tok *at, const char *name) {
  char *tname = NULL, *kind = NULL, *cls = NULL;
  tt__plist pl = {0};
  tt_status st = tt__arg_str(P, at, "a texture name", &tname);
  if (st == TT_OK) st = tt__arg_str(P, at, "a texture type (\"float\" or \"spectrum\")", &kind);
  if (st == TT_OK) st = tt__arg_str(P, at, "a texture class", &cls);
  if (st == TT_OK) st = tt__params(P, &pl);
  if (st == TT_OK) st = tt__texture(P, at, tname, kind, cls, &pl);
  free(tname);
  free(kind);
  free(cls);
  tt__plist_free(&pl);
  return st;
}

static tt_status tt__d_shape(tt__pp *P, const tt__tok *at, const char *name) {
  return tt__typed(P, at, "a shape type", tt__shape);
}

static tt_status tt__d_light_source(tt__pp *P, const tt__tok *at, const char *name) {
  return tt__typed(P, at, "a light type", tt__light);
}

static tt_status tt__d_area_light_source(tt__pp *P, const tt__tok *at, const char *name) {
  return tt__typed(P, at, "an area light type", tt__area_light);
}

/* Include and Import (tunetrace reads both the same way). */
static tt_status tt__d_include(tt__pp *P, const tt__tok *at, const char *name) {
  char *file = NULL;
  tt_status st = tt__arg_str(P, at, "a file name", &file);
  if (st == TT_OK) st = tt__include(P, at, file);
  free(file);
  return st;
}

static tt_status tt__d_object_begin(tt__pp *P, const tt__tok *at, const char *name) {
  char *oname = NULL;
  tt_status st = tt__arg_str(P, at, "an object name", &oname);
  if (st != TT_OK) return st;
  if (P->cur_obj >= 0)
    st = tt__perr(at->file, at->line, "ObjectBegin \"%s\" inside another ObjectBegin", oname);
  else if ((st = tt__push(P, 'O', at)) == TT_OK) {
    P->obj = tt__grow(P->obj, &P->capobj, P->nobj + 1, sizeof *P->obj);
    if (!P->obj) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    else {
      memset(&P->obj[P->nobj], 0, sizeof P->obj[0]);
      P->obj[P->nobj].name = oname;
      oname = NULL;
      P->cur_obj = (int)P->nobj++;
    }
  }
  free(oname);
  return st;
}

static tt_status tt__d_object_end(tt__pp *P, const tt__tok *at, const char *name) {
  if (P->cur_obj < 0) {
    tt__pwarn(P, at->file, at->line, "ObjectEnd", "ObjectEnd without ObjectBegin (ignored)");
    return TT_OK;
  }
  tt__pop(P, 'O', at);
  P->cur_obj = -1;
  return TT_OK;
}

static tt_status tt__d_object_instance(tt__pp *P, const tt__tok *at, const char *name) {
  char *oname = NULL;
  tt_status st = tt__arg_str(P, at, "an object name", &oname);
  if (st == TT_OK) st = tt__instance(P, at, oname);
  free(oname);
  return st;
}

/* MakeNamedMedium "name" params, MediumInterface "inside" ["outside"]: media are not
 * supported; the arguments are read and dropped. */
static tt_status tt__d_medium(tt__pp *P, const tt__tok *at, const char *name) {
  tt__pwarn(P, at->file, at->line, name, "%s: participating media are not supported (ignored)",
            name);
  char *mname = NULL;
  tt__plist pl = {0};
  tt_status st = tt__arg_str(P, at, "a name", &mname);
  if (st == TT_OK) {
    int interface = name[0] == 'M' && name[1] == 'e'; /* MediumInterface */
    tt__tok n2;
    if (interface && (st = tt__peek(P, &n2)) == TT_OK && n2.kind == TK_STRING) tt__next(P, &n2);
    if (st == TT_OK && !interface) st = tt__params(P, &pl);
  }
  free(mname);
  tt__plist_free(&pl);
  return st;
}

static tt_status tt__d_attribute(tt__pp *P, const tt__tok *at, const char *name) {
  tt__pwarn(P, at->file, at->line, name,
            "Attribute (default parameters) is not supported (ignored)");
  char *target = NULL;
  tt__plist pl = {0};
  tt_status st = tt__arg_str(P, at, "a target", &target);
  if (st == TT_OK) st = tt__params(P, &pl);
  free(target);
  tt__plist_free(&pl);
  return st;
}

/* ActiveTransform: which of the two CTMs (start time, end time) the transform directives
 * change from here on (pbrt_motion.c turns shapes whose CTMs differ into animation). */
static tt_status tt__d_active_transform(tt__pp *P, const tt__tok *at, const char *name) {
  tt__tok w;
  char d[64];
  tt_status st = tt__next(P, &w);
  if (st != TT_OK) return st;
  if (tt__is(&w, "StartTime")) P->gs.active = TT__ACTIVE_START;
  else if (tt__is(&w, "EndTime")) P->gs.active = TT__ACTIVE_END;
  else if (tt__is(&w, "All")) P->gs.active = TT__ACTIVE_ALL;
  else
    st = tt__perr(w.file, w.line, "ActiveTransform: expected StartTime, EndTime or All, got %s",
                  tt__desc(&w, d, sizeof d));
  return st;
}

/* TransformTimes start end: the times of the two CTMs (seconds on the sequence's axis). */
static tt_status tt__d_transform_times(tt__pp *P, const tt__tok *at, const char *name) {
  double v[2];
  tt_status st = tt__arg_nums(P, at, 2, v);
  if (st != TT_OK) return st;
  if (!(v[1] >= v[0]))
    return tt__perr(at->file, at->line,
                    "TransformTimes: the end time %g is before the start time %g (expected "
                    "start <= end)",
                    v[1], v[0]);
  if (fabs(v[0]) > 1e9 || fabs(v[1]) > 1e9)
    return tt__perr(at->file, at->line,
                    "TransformTimes: times %g, %g are beyond +-1e9 seconds (expected a "
                    "sequence's time range)",
                    v[0], v[1]);
  if (P->in_world)
    tt__pstrict(P, at->file, at->line, name,
                "TransformTimes inside the world block (pbrt-v4 accepts it only before "
                "WorldBegin); applied to the shapes that follow");
  P->gs.t_start = v[0];
  P->gs.t_end = v[1];
  return TT_OK;
}

/* ---- the table ---------------------------------------------------------------------- */

typedef tt_status (*tt__directive_fn)(tt__pp *P, const tt__tok *at, const char *name);

/* One directive of the pbrt-v4 format; `transform`: it changes the active CTMs. */
typedef struct tt__directive_entry {
  const char *name;
  tt__directive_fn fn;
  int transform;
} tt__directive_entry;

static const tt__directive_entry tt__directives[] = {
    {"AttributeBegin", tt__d_attribute_begin, 0},
    {"TransformBegin", tt__d_attribute_begin, 0},
    {"AttributeEnd", tt__d_attribute_end, 0},
    {"TransformEnd", tt__d_attribute_end, 0},
    {"Identity", tt__d_identity, 1},
    {"Translate", tt__d_translate, 1},
    {"Scale", tt__d_scale, 1},
    {"Rotate", tt__d_rotate, 1},
    {"LookAt", tt__d_look_at, 1},
    {"Transform", tt__d_transform, 1},
    {"ConcatTransform", tt__d_transform, 1},
    {"CoordinateSystem", tt__d_coordinate_system, 0},
    {"CoordSysTransform", tt__d_coord_sys_transform, 1},
    {"ReverseOrientation", tt__d_reverse_orientation, 0},
    {"WorldBegin", tt__d_world_begin, 0},
    {"WorldEnd", tt__d_world_end, 0},
    {"Camera", tt__d_camera, 0},
    {"Film", tt__d_option_block, 0},
    {"Sampler", tt__d_option_block, 0},
    {"Integrator", tt__d_option_block, 0},
    {"PixelFilter", tt__d_option_block, 0},
    {"Accelerator", tt__d_option_block, 0},
    {"ColorSpace", tt__d_option_block, 0},
    {"Option", tt__d_option, 0},
    {"Material", tt__d_material, 0},
    {"MakeNamedMaterial", tt__d_make_named_material, 0},
    {"NamedMaterial", tt__d_named_material, 0},
    {"Texture", tt__d_texture, 0},
    {"Shape", tt__d_shape, 0},
    {"LightSource", tt__d_light_source, 0},
    {"AreaLightSource", tt__d_area_light_source, 0},
    {"Include", tt__d_include, 0},
    {"Import", tt__d_include, 0},
    {"ObjectBegin", tt__d_object_begin, 0},
    {"ObjectEnd", tt__d_object_end, 0},
    {"ObjectInstance", tt__d_object_instance, 0},
    {"MakeNamedMedium", tt__d_medium, 0},
    {"MediumInterface", tt__d_medium, 0},
    {"Attribute", tt__d_attribute, 0},
    {"ActiveTransform", tt__d_active_transform, 0},
    {"TransformTimes", tt__d_transform_times, 0},
};

/* The table entry of the word token `t`, or NULL. */
static const tt__directive_entry *tt__lookup_directive(const tt__tok *t) {
  for (size_t i = 0; i < sizeof tt__directives / sizeof tt__directives[0]; i++) {
    const char *n = tt__directives[i].name;
    if (t->n == strlen(n) && memcmp(t->s, n, t->n) == 0) return &tt__directives[i];
  }
  return NULL;
}

/* Reads one directive and applies it. *done is set at the end of input. */
tt_status tt__directive(tt__pp *P, int *done) {
  tt__tok t;
  char d[64];
  tt_status st = tt__next(P, &t);
  if (st != TT_OK) return st;
  if (t.kind == TK_EOF) {
    *done = 1;
    return TT_OK;
  }
  if (t.kind != TK_WORD)
    return tt__perr(t.file, t.line, "expected a directive, got %s", tt__desc(&t, d, sizeof d));
  char name[40];
  snprintf(name, sizeof name, "%.*s", (int)(t.n < 39 ? t.n : 39), t.s);
  const tt__directive_entry *e = tt__lookup_directive(&t);
  if (!e) {
    const char *names[sizeof tt__directives / sizeof tt__directives[0]];
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) names[i] = tt__directives[i].name;
    const char *near = tt_suggest(name, names, sizeof names / sizeof names[0]);
    tt__pstrict(P, t.file, t.line, name, "unknown directive \"%s\"%s%s%s", name,
                near ? " (did you mean \"" : "", near ? near : "", near ? "\"?)" : "");
    return tt__skip_args(P);
  }
  return e->fn(P, &t, name);
}
