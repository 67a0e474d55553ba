/* scene.json "stress" (scenes/README.md, "Stress options"): the build-stability stress
 * case of thesis 3.2.3 as an option of any scene. "cylinder" adds a long, thin, open
 * cylinder (long sliver triangles, the hardest input of a SAH builder with spatial splits)
 * centred on the scene's bounds that turns about an axis over a time range, so the scene
 * becomes an animated sequence with the cylinder sweeping through its geometry. The
 * cylinder is an ordinary rigid animated mesh (scene/anim.h): its rest pose lies along +x
 * in its own frame, one node turns it (slerp between keys at most 45 degrees apart, so its
 * angle is exactly linear in time) and places it at the centre. */
#include "io/io_internal.h"
#include "io/scene_json_internal.h"
#include "scene/anim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TT__PI 3.14159265358979323846
#define TT__STRESS_KEY_DEG 45.0 /* slerp is exact only well inside 180 degrees per key */

/* What "stress.cylinder" asks for, defaults filled in. */
typedef struct tt__jcyl {
  float axis[3];      /* unit */
  double from, to;    /* degrees */
  double t0, t1;      /* seconds */
  double length_frac; /* of the bounds' diagonal */
  double radius_frac; /* of the length */
  double segments;
  float center[3];
  int has_center;
  const char *material; /* NULL: a new diffuse "stress_cylinder" */
} tt__jcyl;

/* Bounds of every mesh loaded so far (their load-time positions); 0 without meshes. */
static int tt__jbounds(const tt_scene *s, double lo[3], double hi[3]) {
  int any = 0;
  for (int a = 0; a < 3; a++) lo[a] = INFINITY, hi[a] = -INFINITY;
  for (uint32_t i = 0; i < s->mesh_count; i++) {
    const tt_mesh *m = &s->meshes[i];
    for (size_t v = 0; v < m->vertex_count; v++, any = 1)
      for (int a = 0; a < 3; a++) {
        double x = m->positions[3 * v + a];
        if (x < lo[a]) lo[a] = x;
        if (x > hi[a]) hi[a] = x;
      }
  }
  return any;
}

/* Reads "stress.cylinder" into *o (path `cp`). */
static tt_status tt__jcyl_read(const tt__jctx *c, const cJSON *cy, const char *cp, tt__jcyl *o) {
  memset(o, 0, sizeof *o);
  tt_status st = tt__jobject(c, cy, cp);
  if (st != TT_OK) return st;
  static const char *const known[] = {"axis",   "from",     "to",     "time",     "length",
                                      "radius", "segments", "center", "material", NULL};
  tt__jcheck_keys(c, cy, cp, known);
  char path[600];
  o->axis[0] = 0.0f, o->axis[1] = 0.0f, o->axis[2] = 1.0f;
  if ((st = tt__jvec(c, cy, "axis", cp, 0, 3, &tt__any, 0, o->axis)) != TT_OK) return st;
  double l = tt__len3(o->axis);
  if (!(l > 0) || !isfinite(l)) {
    tt__jkey(path, sizeof path, cp, "axis");
    return tt__jfail(c, TT_ERR_PARSE, path, "expected a non-zero rotation axis [x, y, z]");
  }
  for (int a = 0; a < 3; a++) o->axis[a] = (float)(o->axis[a] / l);
  o->from = 0.0, o->to = 180.0;
  static const tt__range deg_r = {-36000.0, 36000.0, 0};
  if ((st = tt__jnum(c, cy, "from", cp, 0, &deg_r, &o->from)) != TT_OK) return st;
  if ((st = tt__jnum(c, cy, "to", cp, 0, &deg_r, &o->to)) != TT_OK) return st;
  /* the sequence: the camera path's range, else one second */
  const tt_camera *cam = tt_scene_camera(c->scene);
  const int path_given = cam->key_count >= 2;
  o->t0 = path_given ? cam->keys[0].time : 0.0;
  o->t1 = path_given ? cam->keys[cam->key_count - 1].time : 1.0;
  const cJSON *tm = cJSON_GetObjectItemCaseSensitive(cy, "time");
  if (tm) {
    float t[2];
    tt__jkey(path, sizeof path, cp, "time");
    if ((st = tt__jvec_item(c, tm, path, 2, &tt__any, 0, t)) != TT_OK) return st;
    if (!(t[1] > t[0]))
      return tt__jfail(c, TT_ERR_PARSE, path,
                       "expected [start, end] seconds with end > start, got [%g, %g]", t[0], t[1]);
    if (path_given && (t[0] < o->t0 || t[1] > o->t1))
      return tt__jfail(c, TT_ERR_PARSE, path,
                       "the cylinder turns from time %g to %g: longer than the sequence (the "
                       "camera path runs from %g to %g); extend camera.path or narrow the time",
                       t[0], t[1], o->t0, o->t1);
    o->t0 = t[0], o->t1 = t[1];
  }
  o->length_frac = 0.5, o->radius_frac = 0.002, o->segments = 8;
  static const tt__range pos_r = {0.0, 1e6, TT__LO_OPEN}, seg_r = {3, 1024, TT__INT};
  if ((st = tt__jnum(c, cy, "length", cp, 0, &pos_r, &o->length_frac)) != TT_OK) return st;
  if ((st = tt__jnum(c, cy, "radius", cp, 0, &pos_r, &o->radius_frac)) != TT_OK) return st;
  if ((st = tt__jnum(c, cy, "segments", cp, 0, &seg_r, &o->segments)) != TT_OK) return st;
  o->has_center = cJSON_GetObjectItemCaseSensitive(cy, "center") != NULL;
  if ((st = tt__jvec(c, cy, "center", cp, 0, 3, &tt__any, 0, o->center)) != TT_OK) return st;
  if ((st = tt__jstr(c, cy, "material", cp, 0, &o->material)) != TT_OK) return st;
  return TT_OK;
}

/* Index of material `name`, or of a new diffuse one (albedo 0.8) when name is NULL. */
static tt_status tt__jcyl_material(const tt__jctx *c, const char *cp, const char *name,
                                   uint32_t *out) {
  tt_scene *s = c->scene;
  char path[600];
  if (name) {
    for (uint32_t i = 0; i < s->material_count; i++)
      if (strcmp(s->materials[i].name, name) == 0) {
        *out = i;
        return TT_OK;
      }
    tt__jkey(path, sizeof path, cp, "material");
    return tt__jfail(c, TT_ERR_PARSE, path, "unknown material \"%s\"", name);
  }
  char mname[80] = "stress_cylinder";
  for (int taken = 1; taken;) {
    taken = 0;
    for (uint32_t i = 0; i < s->material_count && !taken; i++)
      taken = strcmp(s->materials[i].name, mname) == 0;
    if (taken && strlen(mname) + 2 < sizeof mname) strcat(mname, "_");
    else if (taken) return tt__jfail(c, TT_ERR_PARSE, cp, "no free material name");
  }
  tt_material m;
  memset(&m, 0, sizeof m);
  m.struct_size = sizeof m;
  m.type = TT_MATERIAL_DIFFUSE;
  for (int i = 0; i < 3; i++) m.albedo[i] = 0.8f, m.specular[i] = 1.0f;
  m.albedo_texture = -1;
  m.ior = 1.5f;
  /* the scene.json defaults of the fields a diffuse material does not use (tt__jmaterial) */
  static const float au_eta[3] = {0.143f, 0.374f, 1.442f}, au_k[3] = {3.983f, 2.385f, 1.603f};
  memcpy(m.eta, au_eta, sizeof m.eta);
  memcpy(m.k, au_k, sizeof m.k);
  char *owned = tt__strdup(mname);
  tt_material *slot = owned ? tt__scene_push((void **)&s->materials, &s->material_count,
                                             &s->material_cap, sizeof *slot)
                            : NULL;
  if (!slot) {
    free(owned);
    return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, cp, "out of memory");
  }
  m.name = owned;
  *slot = m;
  *out = s->material_count - 1;
  return TT_OK;
}

/* The open cylinder along +x centred at the origin: `seg` quads, outward normals. */
static tt_status tt__jcyl_mesh(double length, double radius, uint32_t seg, tt__mesh_data *d) {
  memset(d, 0, sizeof *d);
  d->vertex_count = 2 * seg;
  d->triangle_count = 2 * seg;
  d->name = tt__strdup("stress_cylinder");
  d->positions = malloc(sizeof(float) * 3 * d->vertex_count);
  d->normals = malloc(sizeof(float) * 3 * d->vertex_count);
  d->indices = malloc(sizeof(uint32_t) * 3 * d->triangle_count);
  if (!d->name || !d->positions || !d->normals || !d->indices) return TT_ERR_OUT_OF_MEMORY;
  for (uint32_t i = 0; i < seg; i++) {
    const double a = 2.0 * TT__PI * i / seg, cy = cos(a), sz = sin(a);
    for (uint32_t end = 0; end < 2; end++) {
      float *p = d->positions + 3 * (size_t)(end * seg + i);
      float *n = d->normals + 3 * (size_t)(end * seg + i);
      p[0] = (float)(end ? length / 2 : -length / 2);
      p[1] = (float)(radius * cy);
      p[2] = (float)(radius * sz);
      n[0] = 0.0f, n[1] = (float)cy, n[2] = (float)sz;
    }
    const uint32_t j = (i + 1) % seg;
    const uint32_t tri[6] = {i, j, seg + j, i, seg + j, seg + i};
    memcpy(d->indices + 6 * (size_t)i, tri, sizeof tri);
  }
  return TT_OK;
}

tt_status tt__jstress(const tt__jctx *c, const cJSON *root) {
  const cJSON *stress = cJSON_GetObjectItemCaseSensitive(root, "stress");
  if (!stress) return TT_OK;
  tt_status st = tt__jobject(c, stress, "stress");
  if (st != TT_OK) return st;
  static const char *const known[] = {"cylinder", NULL};
  tt__jcheck_keys(c, stress, "stress", known);
  const cJSON *cy = cJSON_GetObjectItemCaseSensitive(stress, "cylinder");
  if (!cy) return TT_OK;
  const char *cp = "stress.cylinder";
  tt__jcyl o;
  if ((st = tt__jcyl_read(c, cy, cp, &o)) != TT_OK) return st;
  tt_scene *s = c->scene;
  double lo[3], hi[3];
  if (!tt__jbounds(s, lo, hi))
    return tt__jfail(c, TT_ERR_PARSE, cp,
                     "the cylinder is sized by the scene's bounds, but the scene has no geometry");
  const double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                           (hi[2] - lo[2]) * (hi[2] - lo[2]));
  const double length = o.length_frac * diag, radius = o.radius_frac * length;
  if (!(radius > 0) || !isfinite(length) || length > TT_SCENE_COORD_LIMIT)
    return tt__jfail(c, TT_ERR_PARSE, cp,
                     "the cylinder would be %g long and %g wide (the scene's bounds have diagonal "
                     "%g): expected a positive, finite size",
                     length, 2 * radius, diag);
  if (!o.has_center)
    for (int a = 0; a < 3; a++) o.center[a] = (float)((lo[a] + hi[a]) / 2);
  uint32_t mat = 0;
  if ((st = tt__jcyl_material(c, cp, o.material, &mat)) != TT_OK) return st;
  tt__mesh_data d;
  if (tt__jcyl_mesh(length, radius, (uint32_t)o.segments, &d) != TT_OK) {
    tt__mesh_data_free(&d);
    return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, cp, "out of memory");
  }
  const uint32_t mesh = s->mesh_count;
  st = tt__scene_add_mesh(s, &d, mat);
  tt__mesh_data_free(&d);
  if (st != TT_OK) return st;
  /* one node: translate to the centre, turn from `from` to `to` over [t0, t1] */
  uint32_t node;
  if ((st = tt__scene_anim_add_node(s, -1, &node)) != TT_OK) return st;
  tt__anim_node *n = tt__scene_anim_node(s, node);
  memcpy(n->t, o.center, sizeof n->t);
  const double span = o.to - o.from;
  uint32_t keys = (uint32_t)ceil(fabs(span) / TT__STRESS_KEY_DEG);
  if (keys < 1) keys = 1;
  if (tt__track_alloc(&n->rot, keys + 1, 4, TT__INTERP_LINEAR) != TT_OK)
    return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, cp, "out of memory");
  n->rot.rotation = 1;
  for (uint32_t k = 0; k <= keys; k++) {
    const double f = (double)k / keys, deg = o.from + span * f;
    const double h = deg * TT__PI / 360.0, sh = sin(h);
    n->rot.times[k] = k == keys ? o.t1 : o.t0 + (o.t1 - o.t0) * f;
    float *q = n->rot.values + 4 * (size_t)k;
    for (int a = 0; a < 3; a++) q[a] = (float)(o.axis[a] * sh);
    q[3] = (float)cos(h);
  }
  tt__track_align_rotations(&n->rot);
  tt__mesh_anim *ma = NULL;
  if ((st = tt__scene_anim_add_mesh(s, mesh, &ma)) != TT_OK) return st;
  ma->node = (int32_t)node;
  return TT_OK;
}
