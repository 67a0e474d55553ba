/* pbrt-v4 importer: Shape (triangle meshes, PLY files, spheres, disks, bilinear patches,
 * Loop subdivision surfaces) into world-space tt_meshes, and ObjectBegin/ObjectInstance. */
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
#include <sys/stat.h>

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
    const float *a = d->positions + 3 * (size_t)ix[0], *b = d->positions + 3 * (size_t)ix[1],
                *c = d->positions + 3 * (size_t)ix[2];
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
           e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]}, ng[3];
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
static tt_status tt__pfloats(const tt__tok *at, tt__pparam *p, size_t arity, float **out,
                             size_t *count) {
  if (!p->num || p->nnum % arity)
    return tt__perr(at->file, at->line,
                    "parameter \"%s %s\": expected a multiple of %zu numbers, got %zu", p->type,
                    p->name, arity, p->nnum);
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
  if (nv == 0 || nv > UINT32_MAX / 4)
    return tt__perr(at->file, at->line, "mesh \"P\" holds %zu vertices", nv);
  for (size_t i = 0; i < 3 * nv; i++)
    if (!isfinite(d->positions[i]))
      return tt__perr(at->file, at->line, "mesh \"P\" has a non-finite value");
  d->vertex_count = (uint32_t)nv;
  tt__pparam *N = tt__find(pl, "N");
  if (N) {
    if ((st = tt__pfloats(at, N, 3, &d->normals, &nn)) != TT_OK) return st;
    if (nn != nv)
      return tt__perr(at->file, at->line, "mesh has %zu normals for %zu vertices", nn, nv);
  }
  tt__pparam *UV = tt__find(pl, "uv");
  if (!UV) UV = tt__find(pl, "st");
  if (UV) {
    if ((st = tt__pfloats(at, UV, 2, &d->uvs, &nuv)) != TT_OK) return st;
    if (nuv != nv)
      return tt__perr(at->file, at->line, "mesh has %zu uvs for %zu vertices", nuv, nv);
  }
  tt__pparam *I = tt__find(pl, "indices");
  size_t ni;
  const double *src = NULL;
  if (I) {
    if (strcmp(I->type, "integer") != 0 || !I->num)
      return tt__perr(at->file, at->line, "mesh \"indices\" must be integers");
    ni = I->nnum;
    src = I->num;
  } else {
    if ((size_t)per != nv)
      return tt__perr(at->file, at->line,
                      "mesh without \"integer indices\" needs exactly %d vertices, got %zu", per,
                      nv);
    ni = (size_t)per;
  }
  if (ni == 0 || ni % (size_t)per)
    return tt__perr(at->file, at->line, "mesh \"indices\" holds %zu values, not a multiple of %d",
                    ni, per);
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
      o[0] = q[0];
      o[1] = q[1];
      o[2] = q[2];
    } else {
      /* pbrt bilinear patch: v00 v10 v01 v11 -> (00,10,11), (00,11,01): normal dpdu x dpdv */
      o[0] = q[0];
      o[1] = q[1];
      o[2] = q[3];
      o[3] = q[0];
      o[4] = q[3];
      o[5] = q[2];
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
  tt__motion mo;
  memset(&mo, 0, sizeof mo);
  int animated = 0;
  if (P->cur_obj >= 0) {
    if (emissive) {
      tt__pwarn(P, at->file, at->line, "AreaLightSource",
                "area lights inside ObjectBegin are not supported by pbrt-v4 (emission ignored)");
      emissive = 0;
    }
    if (tt__ctm_animated(P))
      tt__pwarn(P, at->file, at->line, "ActiveTransform",
                "an animated transform inside ObjectBegin is not supported by pbrt-v4 (the "
                "start-time transform is used; animate the ObjectInstance instead)");
    memcpy(m, P->gs.ctm, sizeof m);
  } else if (tt__ctm_animated(P)) {
    /* the mesh is placed in its own frame now and moved by its node at every time */
    double m1[16];
    tt__world_matrix(P, P->gs.ctm, m);
    tt__world_matrix(P, P->gs.ctm_end, m1);
    if ((st = tt__motion_split(P, at, "Shape", m, m1, &mo)) != TT_OK) return st;
    memcpy(m, mo.pre, sizeof m);
    animated = 1;
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
  const uint32_t index = P->scene->mesh_count;
  if ((st = tt__scene_add_mesh(P->scene, d, (uint32_t)mat)) != TT_OK) return st;
  return animated ? tt__motion_attach(P, index, &mo) : TT_OK;
}

/* Shape directive: builds object-space triangles for the supported shape types. */
tt_status tt__shape(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl) {
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
    tt__pwarn(P, at->file, at->line, "alpha",
              "%s: alpha (cut-out) textures are not supported (ignored)", what);
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
      if (levels > 6)
        tt__pwarn(P, at->file, at->line, "levels", "loopsubdiv levels %g clamped to 6", levels);
      for (int i = 0; i < lv && st == TT_OK; i++) st = tt__pbrt_loop_subdivide(&d);
      if (st != TT_OK) st = tt__perr(at->file, at->line, "loopsubdiv: %s", tt_last_error());
    }
  } else if (strcmp(type, "plymesh") == 0) {
    const char *fn = NULL;
    if ((st = tt__gets(at, pl, "filename", &fn)) != TT_OK) return st;
    if (!fn) return tt__perr(at->file, at->line, "plymesh without \"string filename\"");
    tt__pparam *disp = tt__find(pl, "displacement");
    if (disp)
      tt__pwarn(P, at->file, at->line, "displacement",
                "%s: displacement is not supported (ignored)", what);
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
    if (!(r > 0))
      return tt__perr(at->file, at->line, "%s: radius must be positive, got %g", what, r);
    if ((st = tt__getf(P, at, pl, "phimax", &phimax)) != TT_OK) return st;
    if (phimax < 360)
      tt__pwarn(P, at->file, at->line, "phimax",
                "%s: partial shapes (phimax) are tessellated whole", what);
    if (type[0] == 's') {
      if ((st = tt__getf(P, at, pl, "zmin", &zmin)) != TT_OK) return st;
      if ((st = tt__getf(P, at, pl, "zmax", &zmax)) != TT_OK) return st;
      if (zmin > -r || zmax < r)
        tt__pwarn(P, at->file, at->line, "zmin",
                  "%s: clipped spheres (zmin/zmax) are tessellated whole", what);
      st = tt__pbrt_sphere(r, &d);
    } else {
      if ((st = tt__getf(P, at, pl, "height", &h)) != TT_OK) return st;
      if ((st = tt__getf(P, at, pl, "innerradius", &ri)) != TT_OK) return st;
      st = tt__pbrt_disk(r, ri, h, &d);
    }
  } else {
    static const char *const known[] = {"cylinder", "cone",  "paraboloid",  "hyperboloid",
                                        "curve",    "nurbs", "heightfield", NULL};
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
    tt__pwarn(P, at->file, at->line, "interface",
              "%s with material \"interface\" has no surface (skipped)", what);
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
  if (!d->positions || !d->indices || (s->normals && !d->normals) || (s->uvs && !d->uvs) ||
      (s->name && !d->name)) {
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
tt_status tt__instance(tt__pp *P, const tt__tok *at, const char *name) {
  if (P->cur_obj >= 0)
    return tt__perr(at->file, at->line, "ObjectInstance \"%s\" inside ObjectBegin", name);
  tt__object *o = NULL;
  for (size_t i = P->nobj; i-- > 0;)
    if (strcmp(P->obj[i].name, name) == 0) {
      o = &P->obj[i];
      break;
    }
  if (!o) return tt__perr(at->file, at->line, "ObjectInstance: no object named \"%s\"", name);
  double m[16];
  tt__world_matrix(P, P->gs.ctm, m);
  /* an animated instance: every copy moves as one rigid body (pbrt-v4's animated
   * renderFromInstance) */
  tt__motion mo;
  memset(&mo, 0, sizeof mo);
  const int animated = tt__ctm_animated(P);
  if (animated) {
    double m1[16];
    tt__world_matrix(P, P->gs.ctm_end, m1);
    tt_status st = tt__motion_split(P, at, "ObjectInstance", m, m1, &mo);
    if (st != TT_OK) return st;
    memcpy(m, mo.pre, sizeof m);
  }
  for (size_t i = 0; i < o->n; i++) {
    tt__mesh_data d;
    if (!tt__mesh_copy(&o->m[i].d, &d)) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
    if (tt__mesh_data_transform(&d, m) != TT_OK) {
      tt__mesh_data_free(&d);
      return tt__perr(at->file, at->line,
                      "ObjectInstance \"%s\": transform is singular or not affine", name);
    }
    const uint32_t index = P->scene->mesh_count;
    tt_status st = tt__scene_add_mesh(P->scene, &d, (uint32_t)o->m[i].mat);
    tt__mesh_data_free(&d);
    if (st == TT_OK && animated) st = tt__motion_attach(P, index, &mo);
    if (st != TT_OK) return st;
  }
  return TT_OK;
}
