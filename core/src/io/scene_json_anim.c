/* scene.json mesh animation (scenes/README.md, "Animation"): "animation" keys of a rigid
 * transform (translate, rotate as Euler angles, axis-angle or quaternion, scale) and
 * "morph" targets with keyframed weights, read into scene/anim.h's tracks. Every error
 * names the file, the JSON path and what was expected. */
#include "io/io_internal.h"
#include "io/scene_json_internal.h"
#include "scene/anim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TT__PI 3.14159265358979323846

/* "linear" (default), "cubic" or "step" under obj.interpolation. */
static tt_status tt__jinterp(const tt__jctx *c, const cJSON *obj, const char *prefix,
                             tt__interp *out) {
  const char *name = NULL;
  tt_status st = tt__jstr(c, obj, "interpolation", prefix, 0, &name);
  if (st != TT_OK) return st;
  *out = TT__INTERP_LINEAR;
  if (!name || strcmp(name, "linear") == 0) return TT_OK;
  if (strcmp(name, "cubic") == 0) *out = TT__INTERP_CUBIC;
  else if (strcmp(name, "step") == 0) *out = TT__INTERP_STEP;
  else {
    char path[600];
    tt__jkey(path, sizeof path, prefix, "interpolation");
    return tt__jfail(c, TT_ERR_PARSE, path,
                     "expected \"linear\", \"cubic\" or \"step\", got \"%s\"", name);
  }
  return TT_OK;
}

/* The "keys" array of `obj`: non-empty, objects with strictly increasing "time". */
static tt_status tt__jkeys(const tt__jctx *c, const cJSON *obj, const char *prefix,
                           const cJSON **keys, const char *const *known) {
  char path[600], kp[640], got[128];
  tt__jkey(path, sizeof path, prefix, "keys");
  const cJSON *k = cJSON_GetObjectItemCaseSensitive(obj, "keys");
  if (!k)
    return tt__jfail(c, TT_ERR_PARSE, path,
                     "missing required field (expected a non-empty array of keys)");
  if (!cJSON_IsArray(k) || !k->child)
    return tt__jfail(c, TT_ERR_PARSE, path, "expected a non-empty array of keys, got %s",
                     tt__jdesc(k, got, sizeof got));
  double prev = 0;
  unsigned i = 0;
  for (const cJSON *e = k->child; e; e = e->next, i++) {
    tt__jidx(kp, sizeof kp, path, i);
    tt_status st = tt__jobject(c, e, kp);
    if (st != TT_OK) return st;
    tt__jcheck_keys(c, e, kp, known);
    double t;
    if ((st = tt__jnum(c, e, "time", kp, 1, &tt__any, &t)) != TT_OK) return st;
    if (i > 0 && !(t > prev)) {
      char tp[680];
      tt__jkey(tp, sizeof tp, kp, "time");
      return tt__jfail(
          c, TT_ERR_PARSE, tp,
          "keys out of order: expected a time greater than the previous key's (%g), got %g", prev,
          t);
    }
    prev = t;
  }
  *keys = k;
  return TT_OK;
}

/* Quaternion (x, y, z, w) of a "rotate" value: Euler angles [x, y, z] in degrees (about X,
 * then Y, then Z, as a static transform), {"axis", "angle"} or {"quaternion": [x, y, z, w]}. */
static tt_status tt__jrotation(const tt__jctx *c, const cJSON *rot, const char *path, float q[4]) {
  char sub[700], got[128];
  tt_status st;
  if (cJSON_IsArray(rot)) {
    float a[3];
    if ((st = tt__jvec_item(c, rot, path, 3, &tt__any, 0, a)) != TT_OK) return st;
    double h[3], cs[3], sn[3];
    for (int i = 0; i < 3; i++) {
      h[i] = a[i] * TT__PI / 360.0;
      cs[i] = cos(h[i]);
      sn[i] = sin(h[i]);
    }
    /* q = qz * qy * qx */
    q[0] = (float)(sn[0] * cs[1] * cs[2] - cs[0] * sn[1] * sn[2]);
    q[1] = (float)(cs[0] * sn[1] * cs[2] + sn[0] * cs[1] * sn[2]);
    q[2] = (float)(cs[0] * cs[1] * sn[2] - sn[0] * sn[1] * cs[2]);
    q[3] = (float)(cs[0] * cs[1] * cs[2] + sn[0] * sn[1] * sn[2]);
    return TT_OK;
  }
  if (!cJSON_IsObject(rot))
    return tt__jfail(
        c, TT_ERR_PARSE, path,
        "expected Euler angles [x, y, z] in degrees, {\"axis\": [x, y, z], \"angle\": degrees} "
        "or {\"quaternion\": [x, y, z, w]}, got %s",
        tt__jdesc(rot, got, sizeof got));
  static const char *const known[] = {"axis", "angle", "quaternion", NULL};
  tt__jcheck_keys(c, rot, path, known);
  if (cJSON_GetObjectItemCaseSensitive(rot, "quaternion")) {
    if ((st = tt__jvec(c, rot, "quaternion", path, 1, 4, &tt__any, 0, q)) != TT_OK) return st;
    double l =
        sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3]);
    if (!(l > 1e-12)) {
      tt__jkey(sub, sizeof sub, path, "quaternion");
      return tt__jfail(c, TT_ERR_PARSE, sub, "expected a non-zero quaternion [x, y, z, w]");
    }
    for (int i = 0; i < 4; i++) q[i] = (float)(q[i] / l);
    return TT_OK;
  }
  float axis[3];
  double angle;
  if ((st = tt__jvec(c, rot, "axis", path, 1, 3, &tt__any, 0, axis)) != TT_OK) return st;
  if ((st = tt__jnum(c, rot, "angle", path, 1, &tt__any, &angle)) != TT_OK) return st;
  double l = tt__len3(axis);
  if (!(l > 0)) {
    tt__jkey(sub, sizeof sub, path, "axis");
    return tt__jfail(c, TT_ERR_PARSE, sub, "expected a non-zero axis");
  }
  double h = angle * TT__PI / 360.0, s = sin(h) / l;
  q[0] = (float)(axis[0] * s);
  q[1] = (float)(axis[1] * s);
  q[2] = (float)(axis[2] * s);
  q[3] = (float)cos(h);
  return TT_OK;
}

static const char *const tt__anim_key_fields[] = {"time", "translate", "rotate", "scale", NULL};

/* One channel ("translate", "rotate" or "scale") of the rigid keys: the keys that give it. */
static tt_status tt__jchannel(const tt__jctx *c, const cJSON *keys, const char *kpath,
                              const char *field, tt__interp interp, tt__track *t) {
  uint32_t n = 0;
  for (const cJSON *e = keys->child; e; e = e->next)
    n += cJSON_GetObjectItemCaseSensitive(e, field) != NULL;
  int rot = strcmp(field, "rotate") == 0, scale = strcmp(field, "scale") == 0;
  t->rotation = rot;
  if (n == 0) return TT_OK;
  if (tt__track_alloc(t, n, rot ? 4 : 3, interp) != TT_OK)
    return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, kpath, "out of memory");
  t->rotation = rot;
  uint32_t j = 0;
  unsigned i = 0;
  char kp[640], fp[700];
  for (const cJSON *e = keys->child; e; e = e->next, i++) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(e, field);
    if (!v) continue;
    tt__jidx(kp, sizeof kp, kpath, i);
    tt__jkey(fp, sizeof fp, kp, field);
    t->times[j] = cJSON_GetObjectItemCaseSensitive(e, "time")->valuedouble;
    float *out = t->values + (size_t)j * t->dim;
    tt_status st =
        rot ? tt__jrotation(c, v, fp, out) : tt__jvec_item(c, v, fp, 3, &tt__any, scale, out);
    if (st != TT_OK) return st;
    if (scale) {
      /* a sign change between keys would pass through a flat (singular) mesh */
      const float *first = t->values;
      for (int k = 0; k < 3; k++)
        if (out[k] == 0.0f || (out[k] < 0) != (first[k] < 0))
          return tt__jfail(
              c, TT_ERR_PARSE, fp,
              "expected non-zero factors with the signs of the first scale key (%g %g %g), got "
              "%g %g %g (a sign change between keys makes the mesh flat on the way)",
              first[0], first[1], first[2], out[0], out[1], out[2]);
    }
    j++;
  }
  if (interp == TT__INTERP_CUBIC) tt__track_catmull_rom(t);
  else tt__track_align_rotations(t);
  return TT_OK;
}

/* "animation": the rigid keys as one node's channels. */
static tt_status tt__jrigid(const tt__jctx *c, const cJSON *a, const char *ap, uint32_t *node_out) {
  tt_status st = tt__jobject(c, a, ap);
  if (st != TT_OK) return st;
  static const char *const known[] = {"interpolation", "keys", NULL};
  tt__jcheck_keys(c, a, ap, known);
  tt__interp interp;
  if ((st = tt__jinterp(c, a, ap, &interp)) != TT_OK) return st;
  const cJSON *keys = NULL;
  if ((st = tt__jkeys(c, a, ap, &keys, tt__anim_key_fields)) != TT_OK) return st;
  char kpath[600];
  tt__jkey(kpath, sizeof kpath, ap, "keys");
  unsigned i = 0;
  for (const cJSON *e = keys->child; e; e = e->next, i++)
    if (!cJSON_GetObjectItemCaseSensitive(e, "translate") &&
        !cJSON_GetObjectItemCaseSensitive(e, "rotate") &&
        !cJSON_GetObjectItemCaseSensitive(e, "scale")) {
      char kp[640];
      tt__jidx(kp, sizeof kp, kpath, i);
      return tt__jfail(c, TT_ERR_PARSE, kp,
                       "expected at least one of \"translate\", \"rotate\", \"scale\"");
    }
  uint32_t node;
  if ((st = tt__scene_anim_add_node(c->scene, -1, &node)) != TT_OK) return st;
  tt__anim_node *n = tt__scene_anim_node(c->scene, node);
  if ((st = tt__jchannel(c, keys, kpath, "translate", interp, &n->tr)) != TT_OK) return st;
  if ((st = tt__jchannel(c, keys, kpath, "rotate", interp, &n->rot)) != TT_OK) return st;
  if ((st = tt__jchannel(c, keys, kpath, "scale", interp, &n->sc)) != TT_OK) return st;
  *node_out = node;
  return TT_OK;
}

tt_status tt__janim_check(const tt__jctx *c, const cJSON *e, const char *mp, uint32_t parts) {
  const cJSON *morph = cJSON_GetObjectItemCaseSensitive(e, "morph");
  if (morph && parts != 1) {
    char path[600];
    tt__jkey(path, sizeof path, mp, "morph");
    return tt__jfail(
        c, TT_ERR_PARSE, path,
        "morph targets need exactly one mesh, but \"split\" made %u (morph one part per entry)",
        parts);
  }
  return TT_OK;
}

/* "morph": targets (absolute positions, optional normals, in the entry's object space) and
 * keyframed weights, as offsets from the mesh's rest pose. */
static tt_status tt__jmorph(const tt__jctx *c, const cJSON *mo, const char *mop, tt__mesh_anim *ma,
                            const double m[16], int has_tf) {
  tt_status st = tt__jobject(c, mo, mop);
  if (st != TT_OK) return st;
  static const char *const known[] = {"targets", "weights", "interpolation", "keys", NULL};
  tt__jcheck_keys(c, mo, mop, known);
  const tt_mesh *v = tt_scene_mesh(c->scene, ma->mesh);
  const uint32_t nv = v->vertex_count;
  char tp[600], ip[640], fp[700], got[128];
  tt__jkey(tp, sizeof tp, mop, "targets");
  const cJSON *targets = cJSON_GetObjectItemCaseSensitive(mo, "targets");
  if (!cJSON_IsArray(targets) || !targets->child)
    return tt__jfail(c, TT_ERR_PARSE, tp, "%s a non-empty array of targets%s%s",
                     targets ? "expected" : "missing required field (expected",
                     targets ? ", got " : ")", targets ? tt__jdesc(targets, got, sizeof got) : "");
  const uint32_t nt = (uint32_t)cJSON_GetArraySize(targets);
  ma->targets = nt;
  ma->dpos = calloc((size_t)nt * nv * 3, sizeof(float));
  ma->weights0 = calloc(nt, sizeof(float));
  if (v->normals) ma->dnrm = calloc((size_t)nt * nv * 3, sizeof(float));
  if (!ma->dpos || !ma->weights0 || (v->normals && !ma->dnrm))
    return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, mop, "out of memory");
  unsigned i = 0;
  for (const cJSON *t = targets->child; t; t = t->next, i++) {
    tt__jidx(ip, sizeof ip, tp, i);
    if ((st = tt__jobject(c, t, ip)) != TT_OK) return st;
    static const char *const tknown[] = {"positions", "normals", NULL};
    tt__jcheck_keys(c, t, ip, tknown);
    tt__mesh_data d;
    memset(&d, 0, sizeof d);
    uint32_t cnt = 0;
    tt__jkey(fp, sizeof fp, ip, "positions");
    if ((st = tt__jtuples(c, cJSON_GetObjectItemCaseSensitive(t, "positions"), fp, 3, "positions",
                          &d.positions, &cnt)) != TT_OK)
      return st;
    d.vertex_count = cnt;
    if (cnt != nv) {
      tt__mesh_data_free(&d);
      return tt__jfail(c, TT_ERR_PARSE, fp,
                       "mismatched morph target size: expected %u positions (one per vertex of the "
                       "mesh), got %u",
                       nv, cnt);
    }
    const cJSON *tn = cJSON_GetObjectItemCaseSensitive(t, "normals");
    if (tn) {
      tt__jkey(fp, sizeof fp, ip, "normals");
      if (!v->normals) {
        tt__mesh_data_free(&d);
        return tt__jfail(c, TT_ERR_PARSE, fp,
                         "the mesh has no normals, so its targets cannot have any");
      }
      if ((st = tt__jtuples(c, tn, fp, 3, "normals", &d.normals, &cnt)) != TT_OK) {
        tt__mesh_data_free(&d);
        return st;
      }
      if (cnt != nv) {
        tt__mesh_data_free(&d);
        return tt__jfail(c, TT_ERR_PARSE, fp,
                         "mismatched morph target size: expected %u normals (one per vertex of the "
                         "mesh), got %u",
                         nv, cnt);
      }
    }
    /* place the target as the base mesh was placed (normals by the inverse transpose) */
    if (has_tf && tt__mesh_data_transform(&d, m) != TT_OK) {
      tt__mesh_data_free(&d);
      return tt__jfail(c, TT_ERR_PARSE, ip, "transform is singular (determinant 0)");
    }
    for (size_t k = 0; k < 3 * (size_t)nv; k++) {
      ma->dpos[(size_t)i * nv * 3 + k] = d.positions[k] - ma->rest_pos[k];
      if (d.normals) ma->dnrm[(size_t)i * nv * 3 + k] = d.normals[k] - ma->rest_nrm[k];
    }
    tt__mesh_data_free(&d);
  }
  char wp[600];
  tt__jkey(wp, sizeof wp, mop, "weights");
  const cJSON *w0 = cJSON_GetObjectItemCaseSensitive(mo, "weights");
  if (w0) {
    if (!cJSON_IsArray(w0) || (uint32_t)cJSON_GetArraySize(w0) != nt)
      return tt__jfail(c, TT_ERR_PARSE, wp, "expected %u weights (one per target), got %s", nt,
                       tt__jdesc(w0, got, sizeof got));
    unsigned k = 0;
    for (const cJSON *x = w0->child; x; x = x->next, k++) {
      double val;
      tt__jidx(fp, sizeof fp, wp, k);
      if ((st = tt__jnum_item(c, x, fp, &tt__any, &val)) != TT_OK) return st;
      ma->weights0[k] = (float)val;
    }
  }
  if (!cJSON_GetObjectItemCaseSensitive(mo, "keys")) return TT_OK; /* fixed weights */
  tt__interp interp;
  if ((st = tt__jinterp(c, mo, mop, &interp)) != TT_OK) return st;
  static const char *const kknown[] = {"time", "weights", NULL};
  const cJSON *keys = NULL;
  if ((st = tt__jkeys(c, mo, mop, &keys, kknown)) != TT_OK) return st;
  char kpath[600], kp[640];
  tt__jkey(kpath, sizeof kpath, mop, "keys");
  if (tt__track_alloc(&ma->weights, (uint32_t)cJSON_GetArraySize(keys), nt, interp) != TT_OK)
    return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, kpath, "out of memory");
  i = 0;
  for (const cJSON *e = keys->child; e; e = e->next, i++) {
    tt__jidx(kp, sizeof kp, kpath, i);
    tt__jkey(fp, sizeof fp, kp, "weights");
    const cJSON *w = cJSON_GetObjectItemCaseSensitive(e, "weights");
    if (!w)
      return tt__jfail(c, TT_ERR_PARSE, fp,
                       "missing required field (expected %u weights, one per target)", nt);
    if (!cJSON_IsArray(w) || (uint32_t)cJSON_GetArraySize(w) != nt)
      return tt__jfail(c, TT_ERR_PARSE, fp, "expected %u weights (one per target), got %s", nt,
                       tt__jdesc(w, got, sizeof got));
    ma->weights.times[i] = cJSON_GetObjectItemCaseSensitive(e, "time")->valuedouble;
    unsigned k = 0;
    for (const cJSON *x = w->child; x; x = x->next, k++) {
      double val;
      char xp[720];
      tt__jidx(xp, sizeof xp, fp, k);
      if ((st = tt__jnum_item(c, x, xp, &tt__any, &val)) != TT_OK) return st;
      ma->weights.values[(size_t)i * nt + k] = (float)val;
    }
  }
  if (interp == TT__INTERP_CUBIC) tt__track_catmull_rom(&ma->weights);
  return TT_OK;
}

tt_status tt__janim_attach(const tt__jctx *c, const cJSON *e, const char *mp, uint32_t first,
                           uint32_t count, const double m[16], int has_tf) {
  const cJSON *anim = cJSON_GetObjectItemCaseSensitive(e, "animation");
  const cJSON *morph = cJSON_GetObjectItemCaseSensitive(e, "morph");
  if (!anim && !morph) return TT_OK;
  char ap[600];
  tt_status st;
  int32_t node = -1;
  if (anim) {
    uint32_t n = 0;
    tt__jkey(ap, sizeof ap, mp, "animation");
    if ((st = tt__jrigid(c, anim, ap, &n)) != TT_OK) return st;
    node = (int32_t)n;
  }
  for (uint32_t i = 0; i < count; i++) {
    tt__mesh_anim *ma = NULL;
    if ((st = tt__scene_anim_add_mesh(c->scene, first + i, &ma)) != TT_OK) return st;
    ma->node = node;
    if (morph) {
      tt__jkey(ap, sizeof ap, mp, "morph");
      if ((st = tt__jmorph(c, morph, ap, ma, m, has_tf)) != TT_OK) return st;
    }
  }
  return TT_OK;
}

/* Last time of a "keys" array (its keys are in order), or -inf. */
static double tt__keys_span(const cJSON *obj, double *first) {
  const cJSON *k = obj ? cJSON_GetObjectItemCaseSensitive(obj, "keys") : NULL;
  if (!cJSON_IsArray(k) || !k->child) return -INFINITY;
  const cJSON *t0 = cJSON_GetObjectItemCaseSensitive(k->child, "time");
  *first = cJSON_IsNumber(t0) ? t0->valuedouble : 0;
  const cJSON *last = k->child;
  while (last->next) last = last->next;
  const cJSON *t = cJSON_GetObjectItemCaseSensitive(last, "time");
  return cJSON_IsNumber(t) ? t->valuedouble : -INFINITY;
}

tt_status tt__janim_check_range(const tt__jctx *c, const cJSON *root) {
  const tt_camera *cam = tt_scene_camera(c->scene);
  if (cam->key_count < 2) return TT_OK; /* no sequence to exceed */
  const double lo = cam->keys[0].time, hi = cam->keys[cam->key_count - 1].time;
  const cJSON *ms = cJSON_GetObjectItemCaseSensitive(root, "meshes");
  unsigned i = 0;
  for (const cJSON *e = cJSON_IsArray(ms) ? ms->child : NULL; e; e = e->next, i++) {
    static const char *const which[] = {"animation", "morph"};
    for (int w = 0; w < 2; w++) {
      double first = 0, last = tt__keys_span(cJSON_GetObjectItemCaseSensitive(e, which[w]), &first);
      if (last == -INFINITY || (first >= lo && last <= hi)) continue;
      char path[600];
      snprintf(path, sizeof path, "meshes[%u].%s.keys", i, which[w]);
      return tt__jfail(
          c, TT_ERR_PARSE, path,
          "keys from time %g to %g: the animation is longer than the sequence (the camera path "
          "runs from %g to %g); extend camera.path or move the keys inside it",
          first, last, lo, hi);
    }
  }
  /* what this file does not key itself: an imported scene's animation (pbrt TransformTimes,
   * glTF channels, a scene.json's keys) under this file's camera path */
  double a0, a1;
  tt__scene_anim_range(c->scene, &a0, &a1);
  if (cJSON_GetObjectItemCaseSensitive(root, "import") && !(a0 == 0 && a1 == 0) &&
      (a0 < lo || a1 > hi))
    return tt__jfail(c, TT_ERR_PARSE, "import",
                     "the imported scene's animation runs from time %g to %g: longer than the "
                     "sequence (this file's camera path runs from %g to %g); extend camera.path "
                     "to cover it",
                     a0, a1, lo, hi);
  return TT_OK;
}
