/* pbrt-v4 importer: LightSource (point, spot, distant, infinite) and AreaLightSource. */
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

/* ---- lights ---------------------------------------------------------------------------- */

/* Appends an explicit light to the scene. */
static tt_status tt__add_light(tt__pp *P, const tt_light *l) {
  tt_scene *s = P->scene;
  tt_light *slot =
      tt__scene_push((void **)&s->lights, &s->light_count, &s->light_cap, sizeof *slot);
  if (!slot) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  *slot = *l;
  return TT_OK;
}

/* LightSource: point, spot, distant and infinite map to tunetrace lights. */
tt_status tt__light(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl) {
  tt_status st;
  tt_light l;
  memset(&l, 0, sizeof l);
  l.struct_size = sizeof l;
  char what[160];
  snprintf(what, sizeof what, "LightSource \"%s\"", type);
  double scale = 1, m[16];
  if ((st = tt__getf(P, at, pl, "scale", &scale)) != TT_OK) return st;
  if (tt__find(pl, "power") || tt__find(pl, "illuminance"))
    tt__pwarn(P, at->file, at->line, "power",
              "%s: photometric \"power\"/\"illuminance\" are not supported (scale used)", what);
  if (P->cur_obj >= 0) {
    tt__pwarn(P, at->file, at->line, "LightSource",
              "%s inside ObjectBegin is not supported (ignored)", what);
    return TT_OK;
  }
  if (tt__ctm_animated(P))
    tt__pwarn(P, at->file, at->line, "ActiveTransform",
              "%s: an animated light transform is not supported: the light stays at its "
              "start-time transform (an area light, a Shape with AreaLightSource, moves)",
              what);
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
                  "%s: pbrt-v4 maps \"%s\" with the equal-area octahedral mapping and the light's "
                  "transform; "
                  "tunetrace reads it as lat-long, untransformed",
                  what, fn);
      } else {
        tt__pwarn(P, at->file, at->line, "filename",
                  "%s: environment image \"%s\" not found, using a constant environment of %g",
                  what, path, scale);
        free(path);
      }
    }
    if (P->env_seen) {
      tt__pwarn(P, at->file, at->line, "infinite",
                "only one environment light is supported; this one is ignored");
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
tt_status tt__area_light(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl) {
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
  if (tt__find(pl, "power"))
    tt__pwarn(P, at->file, at->line, "power",
              "AreaLightSource: \"power\" is not supported (scale used)");
  if (tt__find(pl, "filename"))
    tt__pwarn(P, at->file, at->line, "filename",
              "AreaLightSource: image emission is not supported (L used)");
  tt__unused(P, at, "AreaLightSource \"diffuse\"", pl);
  if (!(scale >= 0))
    return tt__perr(at->file, at->line, "AreaLightSource: negative scale %g", scale);
  P->gs.area = 1;
  P->gs.two_sided = two;
  for (int i = 0; i < 3; i++) P->gs.L[i] = (float)(v.rgb[i] * scale);
  return TT_OK;
}
