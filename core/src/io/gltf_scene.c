/* glTF 2.0 files as animated scenes, through assimp (io/assimp_read.h): the node hierarchy
 * becomes scene/anim.h's nodes, the file's first animation their keyframed TRS channels and
 * the morph target weights, skins become CPU-skinned meshes (scene/anim_skin.c), the first
 * perspective camera the still camera and, when its node moves, the camera path, punctual
 * lights (KHR_lights_punctual) lights at their start pose. assimp
 * 5.2.5 drops what glTF says about interpolation, so the file's JSON is read too: each
 * sampler's STEP / LINEAR / CUBICSPLINE and the cameras' vertical field of view. Every error
 * names the file and the glTF field. */
#include "io/assimp_read.h"
#include "io/io_internal.h"
#include "plugin/log.h"
#include "scene/anim.h"

#include <tunetrace/file.h>

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cjson/cJSON.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TT__PI 3.14159265358979323846
/* Camera path keys per interval between the camera node's animation keys: the path is a
 * Catmull-Rom spline through samples of the node's exact pose. */
#define TT__CAM_SUBSTEPS 8
#define TT__CAM_MAX_KEYS 20000

typedef struct tt__gltf {
  const char *file;
  tt_scene *scene;
  const struct aiScene *sc;
  cJSON *json;                  /* the file's glTF JSON */
  const struct aiNode **ainode; /* per anim node: the assimp node */
  uint32_t nodes;
  uint8_t *moves;  /* per anim node: it or an ancestor has animated channels */
  uint32_t *mat;   /* per assimp material: the scene material */
  int anim_index;  /* the animation played, -1 without */
  int has_emitter; /* a material emits */
} tt__gltf;

/* ---- the glTF JSON ---------------------------------------------------------------------- */

static uint32_t tt__le32(const unsigned char *b) {
  return b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* The JSON of a .gltf, or the JSON chunk of a .glb (tt__gltf_check has checked the chunk
 * lies inside the file). */
static tt_status tt__gltf_json(const char *file, cJSON **out) {
  char *text = NULL;
  size_t len = 0;
  *out = NULL;
  tt_status st = tt_file_read(file, "glTF file", 0, &text, &len);
  if (st != TT_OK) return st;
  const char *json = text;
  size_t n = len;
  if (len >= 20 && memcmp(text, "glTF", 4) == 0) {
    uint32_t clen = tt__le32((const unsigned char *)text + 12);
    json = text + 20;
    n = clen <= len - 20 ? clen : len - 20;
  } else if (len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) {
    json += 3;
    n -= 3;
  }
  cJSON *root = cJSON_ParseWithLength(json, n);
  tt_free(text);
  if (!root || !cJSON_IsObject(root)) {
    cJSON_Delete(root);
    return tt_set_error(TT_ERR_PARSE, "%s: expected a glTF JSON object", file);
  }
  *out = root;
  return TT_OK;
}

static const cJSON *tt__jat(const cJSON *o, const char *key, int index) {
  const cJSON *a = cJSON_GetObjectItemCaseSensitive(o, key);
  return cJSON_IsArray(a) && index >= 0 ? cJSON_GetArrayItem(a, index) : NULL;
}

/* glTF JSON node `i`'s name as assimp 5.2.5 names its node (the name, else "nodes[i]"). */
static void tt__jnode_name(const cJSON *root, int i, char *out, size_t n) {
  const cJSON *nd = tt__jat(root, "nodes", i);
  const cJSON *nm = nd ? cJSON_GetObjectItemCaseSensitive(nd, "name") : NULL;
  if (cJSON_IsString(nm) && nm->valuestring[0]) snprintf(out, n, "%s", nm->valuestring);
  else snprintf(out, n, "nodes[%d]", i);
}

/* The interpolation the animation's sampler gives channel `path` of the node named `name`
 * ("translation", "rotation", "scale", "weights"); LINEAR when not found. *cubic_seen is set
 * for CUBICSPLINE. */
static tt__interp tt__jinterp(const tt__gltf *g, const char *name, const char *path) {
  const cJSON *anim = tt__jat(g->json, "animations", g->anim_index);
  const cJSON *chs = anim ? cJSON_GetObjectItemCaseSensitive(anim, "channels") : NULL;
  for (const cJSON *c = cJSON_IsArray(chs) ? chs->child : NULL; c; c = c->next) {
    const cJSON *tg = cJSON_GetObjectItemCaseSensitive(c, "target");
    const cJSON *nd = tg ? cJSON_GetObjectItemCaseSensitive(tg, "node") : NULL;
    const cJSON *pa = tg ? cJSON_GetObjectItemCaseSensitive(tg, "path") : NULL;
    const cJSON *sm = cJSON_GetObjectItemCaseSensitive(c, "sampler");
    if (!cJSON_IsNumber(nd) || !cJSON_IsString(pa) || !cJSON_IsNumber(sm)) continue;
    char nn[256];
    tt__jnode_name(g->json, nd->valueint, nn, sizeof nn);
    if (strcmp(nn, name) != 0 || strcmp(pa->valuestring, path) != 0) continue;
    const cJSON *s = tt__jat(anim, "samplers", sm->valueint);
    const cJSON *ip = s ? cJSON_GetObjectItemCaseSensitive(s, "interpolation") : NULL;
    if (!cJSON_IsString(ip) || strcmp(ip->valuestring, "LINEAR") == 0) return TT__INTERP_LINEAR;
    if (strcmp(ip->valuestring, "STEP") == 0) return TT__INTERP_STEP;
    if (strcmp(ip->valuestring, "CUBICSPLINE") == 0) return TT__INTERP_CUBIC;
    return TT__INTERP_LINEAR;
  }
  return TT__INTERP_LINEAR;
}

/* The element count of accessor `i`, or -1. */
static long tt__jaccessor_count(const cJSON *root, const cJSON *index) {
  if (!cJSON_IsNumber(index)) return -1;
  const cJSON *acc = tt__jat(root, "accessors", index->valueint);
  const cJSON *c = acc ? cJSON_GetObjectItemCaseSensitive(acc, "count") : NULL;
  return cJSON_IsNumber(c) && c->valuedouble >= 0 ? (long)c->valuedouble : -1;
}

/* What assimp 5.2.5 passes over with a log line or an exception that does not name the
 * field: checked on the JSON first. Morph targets and skin attributes with another vertex
 * count than their primitive (assimp drops such a target silently), skins naming nodes
 * that do not exist, samplers whose output does not match their input. */
static tt_status tt__gltf_json_check(const char *file, const cJSON *root) {
  const cJSON *nodes = cJSON_GetObjectItemCaseSensitive(root, "nodes");
  const int nn = cJSON_IsArray(nodes) ? cJSON_GetArraySize(nodes) : 0;
  const cJSON *skins = cJSON_GetObjectItemCaseSensitive(root, "skins");
  int si = 0;
  for (const cJSON *sk = cJSON_IsArray(skins) ? skins->child : NULL; sk; sk = sk->next, si++) {
    const cJSON *js = cJSON_GetObjectItemCaseSensitive(sk, "joints");
    int ji = 0;
    for (const cJSON *j = cJSON_IsArray(js) ? js->child : NULL; j; j = j->next, ji++)
      if (!cJSON_IsNumber(j) || j->valuedouble < 0 || j->valuedouble >= nn)
        return tt_set_error(TT_ERR_PARSE,
                            "%s: skins[%d].joints[%d]: a skin referencing a missing joint: "
                            "expected a node index below %d, got %g",
                            file, si, ji, nn, cJSON_IsNumber(j) ? j->valuedouble : -1.0);
    const long ib =
        tt__jaccessor_count(root, cJSON_GetObjectItemCaseSensitive(sk, "inverseBindMatrices"));
    if (ib >= 0 && cJSON_IsArray(js) && ib < cJSON_GetArraySize(js))
      return tt_set_error(TT_ERR_PARSE,
                          "%s: skins[%d].inverseBindMatrices: expected %d matrices (one per "
                          "joint), got %ld",
                          file, si, cJSON_GetArraySize(js), ib);
  }
  const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(root, "meshes");
  int mi = 0;
  for (const cJSON *m = cJSON_IsArray(meshes) ? meshes->child : NULL; m; m = m->next, mi++) {
    const cJSON *prims = cJSON_GetObjectItemCaseSensitive(m, "primitives");
    int pi = 0;
    for (const cJSON *p = cJSON_IsArray(prims) ? prims->child : NULL; p; p = p->next, pi++) {
      const cJSON *at = cJSON_GetObjectItemCaseSensitive(p, "attributes");
      const long nv =
          tt__jaccessor_count(root, at ? cJSON_GetObjectItemCaseSensitive(at, "POSITION") : NULL);
      if (nv < 0) continue;
      for (const cJSON *a = at ? at->child : NULL; a; a = a->next) {
        if (strncmp(a->string, "JOINTS_", 7) != 0 && strncmp(a->string, "WEIGHTS_", 8) != 0)
          continue;
        const long c = tt__jaccessor_count(root, a);
        if (c >= 0 && c != nv)
          return tt_set_error(TT_ERR_PARSE,
                              "%s: meshes[%d].primitives[%d].attributes.%s: expected %ld values "
                              "(one per vertex), got %ld",
                              file, mi, pi, a->string, nv, c);
      }
      const cJSON *tg = cJSON_GetObjectItemCaseSensitive(p, "targets");
      int ti = 0;
      for (const cJSON *t = cJSON_IsArray(tg) ? tg->child : NULL; t; t = t->next, ti++)
        for (const cJSON *a = t->child; a; a = a->next) {
          const long c = tt__jaccessor_count(root, a);
          if (c >= 0 && c != nv)
            return tt_set_error(TT_ERR_PARSE,
                                "%s: meshes[%d].primitives[%d].targets[%d].%s: mismatched morph "
                                "target size: expected %ld values (one per vertex of the "
                                "primitive), got %ld",
                                file, mi, pi, ti, a->string, nv, c);
        }
    }
  }
  const cJSON *anims = cJSON_GetObjectItemCaseSensitive(root, "animations");
  int ai = 0;
  for (const cJSON *an = cJSON_IsArray(anims) ? anims->child : NULL; an; an = an->next, ai++) {
    const cJSON *ss = cJSON_GetObjectItemCaseSensitive(an, "samplers");
    const cJSON *chs = cJSON_GetObjectItemCaseSensitive(an, "channels");
    for (const cJSON *c = cJSON_IsArray(chs) ? chs->child : NULL; c; c = c->next) {
      const cJSON *tg = cJSON_GetObjectItemCaseSensitive(c, "target");
      const cJSON *pa = tg ? cJSON_GetObjectItemCaseSensitive(tg, "path") : NULL;
      const cJSON *sm = cJSON_GetObjectItemCaseSensitive(c, "sampler");
      const cJSON *s = cJSON_IsNumber(sm) ? cJSON_GetArrayItem(ss, sm->valueint) : NULL;
      if (!s || !cJSON_IsString(pa) || strcmp(pa->valuestring, "weights") == 0) continue;
      const long in = tt__jaccessor_count(root, cJSON_GetObjectItemCaseSensitive(s, "input"));
      const long out = tt__jaccessor_count(root, cJSON_GetObjectItemCaseSensitive(s, "output"));
      const cJSON *ip = cJSON_GetObjectItemCaseSensitive(s, "interpolation");
      const long per = cJSON_IsString(ip) && !strcmp(ip->valuestring, "CUBICSPLINE") ? 3 : 1;
      if (in >= 0 && out >= 0 && out != per * in)
        return tt_set_error(TT_ERR_PARSE,
                            "%s: animations[%d].samplers[%d].output: expected %ld values (%s%ld "
                            "keys of the input), got %ld",
                            file, ai, sm->valueint, per * in,
                            per == 3 ? "3 per key, CUBICSPLINE: " : "", in, out);
    }
  }
  return TT_OK;
}

/* ---- nodes -------------------------------------------------------------------------------- */

static void tt__aimat(const struct aiMatrix4x4 *t, double m[16]) {
  const double v[16] = {t->a1, t->a2, t->a3, t->a4, t->b1, t->b2, t->b3, t->b4,
                        t->c1, t->c2, t->c3, t->c4, t->d1, t->d2, t->d3, t->d4};
  memcpy(m, v, sizeof v);
}

/* One anim node per assimp node, parents first (depth-first). */
static tt_status tt__gltf_nodes(tt__gltf *g, const struct aiNode *n, int32_t parent, int depth) {
  if (!n) return TT_OK;
  if (depth > 256)
    return tt_set_error(TT_ERR_PARSE, "%s: nodes: the hierarchy is deeper than 256 levels",
                        g->file);
  uint32_t index;
  tt_status st = tt__scene_anim_add_node(g->scene, parent, &index);
  if (st != TT_OK) return st;
  const struct aiNode **grown = realloc(g->ainode, sizeof *grown * (index + 1));
  if (!grown) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
  g->ainode = grown;
  g->ainode[index] = n;
  g->nodes = index + 1;
  tt__anim_node *an = tt__scene_anim_node(g->scene, index);
  tt__aimat(&n->mTransformation, an->rest);
  for (int e = 0; e < 16; e++)
    if (!isfinite(an->rest[e]))
      return tt_set_error(TT_ERR_PARSE,
                          "%s: node \"%s\": transform element %d is %g (expected finite numbers)",
                          g->file, n->mName.data, e, an->rest[e]);
  if (an->rest[12] != 0 || an->rest[13] != 0 || an->rest[14] != 0 || an->rest[15] != 1)
    return tt_set_error(TT_ERR_PARSE,
                        "%s: node \"%s\": expected an affine matrix (last row 0 0 0 1)", g->file,
                        n->mName.data);
  /* the values of channels the animation leaves alone (glTF: the node's own TRS) */
  struct aiVector3D sc, pos;
  struct aiQuaternion q;
  aiDecomposeMatrix(&n->mTransformation, &sc, &q, &pos);
  an->t[0] = pos.x, an->t[1] = pos.y, an->t[2] = pos.z;
  an->r[0] = q.x, an->r[1] = q.y, an->r[2] = q.z, an->r[3] = q.w;
  an->s[0] = sc.x, an->s[1] = sc.y, an->s[2] = sc.z;
  for (unsigned c = 0; c < n->mNumChildren; c++)
    if ((st = tt__gltf_nodes(g, n->mChildren[c], (int32_t)index, depth + 1)) != TT_OK) return st;
  return TT_OK;
}

/* The anim node named `name`: -1 when none, -2 when several nodes share the name (assimp
 * matches channels and joints to nodes by name, so such a reference is ambiguous). */
static int32_t tt__gltf_find(const tt__gltf *g, const char *name) {
  int32_t found = -1;
  for (uint32_t i = 0; i < g->nodes; i++)
    if (strcmp(g->ainode[i]->mName.data, name) == 0) {
      if (found >= 0) return -2;
      found = (int32_t)i;
    }
  return found;
}

static tt_status tt__gltf_node_ref(const tt__gltf *g, const char *name, const char *what,
                                   int32_t *out) {
  *out = tt__gltf_find(g, name);
  if (*out == -2)
    return tt_set_error(TT_ERR_PARSE,
                        "%s: %s names node \"%s\", which several nodes are called (animated nodes "
                        "and joints need unique names)",
                        g->file, what, name);
  if (*out < 0)
    return tt_set_error(TT_ERR_PARSE, "%s: %s names node \"%s\", which does not exist", g->file,
                        what, name);
  return TT_OK;
}

/* ---- animation channels ------------------------------------------------------------------- */

/* Key times in seconds, strictly increasing and finite. */
static tt_status tt__gltf_time(const tt__gltf *g, const char *what, uint32_t k, double ticks,
                               double tps, double prev, double *out) {
  double t = ticks / tps;
  if (!isfinite(t))
    return tt_set_error(TT_ERR_PARSE, "%s: %s: key %u: time is %g (expected a finite time)",
                        g->file, what, k, t);
  if (k > 0 && !(t > prev))
    return tt_set_error(TT_ERR_PARSE,
                        "%s: %s: keyframes out of order: key %u at %g s is not after key %u at "
                        "%g s (expected strictly increasing sampler input times)",
                        g->file, what, k, t, k - 1, prev);
  *out = t;
  return TT_OK;
}

static tt_status tt__gltf_finite(const tt__gltf *g, const char *what, uint32_t k, const float *v,
                                 int dim) {
  for (int i = 0; i < dim; i++)
    if (!isfinite(v[i]))
      return tt_set_error(TT_ERR_PARSE,
                          "%s: %s: key %u: component %d is %g (expected finite numbers: NaN in a "
                          "transform)",
                          g->file, what, k, i, v[i]);
  return TT_OK;
}

/* assimp 5.2.5 keeps CUBICSPLINE's values but drops its tangents: the track gets
 * Catmull-Rom tangents instead, said once per file. */
static void tt__gltf_cubic_note(const tt__gltf *g, int *said) {
  if (*said) return;
  *said = 1;
  tt__log(TT_LOG_WARN,
          "%s: CUBICSPLINE animation: assimp does not pass the file's tangents on, so the keys "
          "are joined by Catmull-Rom tangents (the curve passes through every key)",
          g->file);
}

static tt_status tt__gltf_vec_track(const tt__gltf *g, const struct aiVectorKey *keys, unsigned n,
                                    double tps, tt__interp interp, const char *what, tt__track *t) {
  if (n == 0) return TT_OK;
  if (tt__track_alloc(t, n, 3, interp) != TT_OK)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
  for (unsigned k = 0; k < n; k++) {
    float *v = t->values + 3 * (size_t)k;
    v[0] = keys[k].mValue.x, v[1] = keys[k].mValue.y, v[2] = keys[k].mValue.z;
    tt_status st =
        tt__gltf_time(g, what, k, keys[k].mTime, tps, k ? t->times[k - 1] : 0, &t->times[k]);
    if (st == TT_OK) st = tt__gltf_finite(g, what, k, v, 3);
    if (st != TT_OK) return st;
  }
  if (interp == TT__INTERP_CUBIC) tt__track_catmull_rom(t);
  return TT_OK;
}

static tt_status tt__gltf_rot_track(const tt__gltf *g, const struct aiQuatKey *keys, unsigned n,
                                    double tps, tt__interp interp, const char *what, tt__track *t) {
  if (n == 0) return TT_OK;
  if (tt__track_alloc(t, n, 4, interp) != TT_OK)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
  t->rotation = 1;
  for (unsigned k = 0; k < n; k++) {
    float *v = t->values + 4 * (size_t)k;
    v[0] = keys[k].mValue.x, v[1] = keys[k].mValue.y, v[2] = keys[k].mValue.z;
    v[3] = keys[k].mValue.w;
    tt_status st =
        tt__gltf_time(g, what, k, keys[k].mTime, tps, k ? t->times[k - 1] : 0, &t->times[k]);
    if (st == TT_OK) st = tt__gltf_finite(g, what, k, v, 4);
    if (st != TT_OK) return st;
    double l =
        sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2] + (double)v[3] * v[3]);
    if (!(l > 1e-6))
      return tt_set_error(TT_ERR_PARSE, "%s: %s: key %u: expected a unit quaternion, got length %g",
                          g->file, what, k, l);
    for (int i = 0; i < 4; i++) v[i] = (float)(v[i] / l);
  }
  if (interp == TT__INTERP_CUBIC) tt__track_catmull_rom(t);
  else tt__track_align_rotations(t);
  return TT_OK;
}

/* The animation's node channels onto the anim nodes. */
static tt_status tt__gltf_channels(tt__gltf *g, const struct aiAnimation *an, int *cubic_said) {
  const double tps = an->mTicksPerSecond > 0 ? an->mTicksPerSecond : 1000.0;
  for (unsigned c = 0; c < an->mNumChannels; c++) {
    const struct aiNodeAnim *ch = an->mChannels[c];
    char what[512];
    snprintf(what, sizeof what, "animations[%d] \"%.200s\", channel of node \"%.200s\"",
             g->anim_index, an->mName.data, ch->mNodeName.data);
    int32_t node;
    tt_status st = tt__gltf_node_ref(g, ch->mNodeName.data, what, &node);
    if (st != TT_OK) return st;
    tt__anim_node *n = tt__scene_anim_node(g->scene, (uint32_t)node);
    const char *name = ch->mNodeName.data;
    tt__interp it = tt__jinterp(g, name, "translation"), ir = tt__jinterp(g, name, "rotation"),
               is = tt__jinterp(g, name, "scale");
    if (it == TT__INTERP_CUBIC || ir == TT__INTERP_CUBIC || is == TT__INTERP_CUBIC)
      tt__gltf_cubic_note(g, cubic_said);
    char w2[600];
    snprintf(w2, sizeof w2, "%s: translation", what);
    if ((st = tt__gltf_vec_track(g, ch->mPositionKeys, ch->mNumPositionKeys, tps, it, w2,
                                 &n->tr)) != TT_OK)
      return st;
    snprintf(w2, sizeof w2, "%s: rotation", what);
    if ((st = tt__gltf_rot_track(g, ch->mRotationKeys, ch->mNumRotationKeys, tps, ir, w2,
                                 &n->rot)) != TT_OK)
      return st;
    snprintf(w2, sizeof w2, "%s: scale", what);
    if ((st = tt__gltf_vec_track(g, ch->mScalingKeys, ch->mNumScalingKeys, tps, is, w2, &n->sc)) !=
        TT_OK)
      return st;
  }
  /* morph weight keys: their order checked here, before assimp's validation would refuse
   * them without naming the field */
  for (unsigned c = 0; c < an->mNumMorphMeshChannels; c++) {
    const struct aiMeshMorphAnim *ch = an->mMorphMeshChannels[c];
    char what[512];
    snprintf(what, sizeof what, "animations[%d] \"%.200s\", weights of node \"%.200s\"",
             g->anim_index, an->mName.data, ch->mName.data);
    double prev = 0;
    for (unsigned k = 0; k < ch->mNumKeys; k++) {
      tt_status st = tt__gltf_time(g, what, k, ch->mKeys[k].mTime, tps, prev, &prev);
      if (st != TT_OK) return st;
    }
  }
  /* which nodes move: their own channels or an ancestor's (parents come first) */
  for (uint32_t i = 0; i < g->nodes; i++) {
    const tt__anim_node *n = tt__scene_anim_node(g->scene, i);
    g->moves[i] = (n->tr.count > 1 || n->rot.count > 1 || n->sc.count > 1) ||
                  (n->parent >= 0 && g->moves[n->parent]);
  }
  return TT_OK;
}

/* ---- materials ------------------------------------------------------------------------------ */

/* glTF's base colour as a diffuse albedo and its emissive colour as emission; names unique. */
static tt_status tt__gltf_materials(tt__gltf *g) {
  tt_scene *s = g->scene;
  const unsigned n = g->sc->mNumMaterials;
  g->mat = calloc(n ? n : 1, sizeof *g->mat);
  if (!g->mat) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
  for (unsigned i = 0; i <= n; i++) {
    const struct aiMaterial *am = i < n ? g->sc->mMaterials[i] : NULL;
    tt_material m;
    memset(&m, 0, sizeof m);
    m.struct_size = sizeof m;
    m.type = TT_MATERIAL_DIFFUSE;
    m.albedo_texture = -1;
    m.albedo[0] = m.albedo[1] = m.albedo[2] = 0.8f;
    m.ior = 1.5f;
    m.specular[0] = m.specular[1] = m.specular[2] = 1.0f;
    /* scene.json's conductor defaults, so a written scene reads back the same material */
    static const float au_eta[3] = {0.143f, 0.374f, 1.442f}, au_k[3] = {3.983f, 2.385f, 1.603f};
    memcpy(m.eta, au_eta, sizeof m.eta);
    memcpy(m.k, au_k, sizeof m.k);
    char name[300];
    if (am) {
      struct aiColor4D c;
      if (aiGetMaterialColor(am, "$clr.base", 0, 0, &c) == aiReturn_SUCCESS ||
          aiGetMaterialColor(am, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS) {
        m.albedo[0] = c.r, m.albedo[1] = c.g, m.albedo[2] = c.b;
      }
      if (aiGetMaterialColor(am, AI_MATKEY_COLOR_EMISSIVE, &c) == aiReturn_SUCCESS) {
        m.emission[0] = c.r, m.emission[1] = c.g, m.emission[2] = c.b;
      }
      for (int k = 0; k < 3; k++) {
        if (!(m.albedo[k] >= 0)) m.albedo[k] = 0;
        if (m.albedo[k] > 1) m.albedo[k] = 1;
        if (!(m.emission[k] >= 0) || !isfinite(m.emission[k])) m.emission[k] = 0;
      }
      g->has_emitter |= m.emission[0] > 0 || m.emission[1] > 0 || m.emission[2] > 0;
      struct aiString an;
      if (aiGetMaterialString(am, AI_MATKEY_NAME, &an) == aiReturn_SUCCESS && an.length)
        snprintf(name, sizeof name, "%.250s", an.data);
      else snprintf(name, sizeof name, "materials[%u]", i);
    } else {
      snprintf(name, sizeof name, "gltf-default"); /* for meshes without a material */
    }
    for (uint32_t k = 0; k < s->material_count; k++)
      if (strcmp(s->materials[k].name, name) == 0) {
        size_t l = strlen(name);
        snprintf(name + (l < 280 ? l : 280), 20, "#%u", i);
        break;
      }
    tt_material *slot =
        tt__scene_push((void **)&s->materials, &s->material_count, &s->material_cap, sizeof *slot);
    if (!slot) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
    m.name = tt__strdup(name);
    *slot = m;
    if (!m.name) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
    if (i < n) g->mat[i] = s->material_count - 1;
  }
  return TT_OK;
}

/* ---- meshes --------------------------------------------------------------------------------- */

static uint32_t tt__ai_tris(const struct aiMesh *m) {
  uint32_t n = 0;
  for (unsigned f = 0; f < m->mNumFaces; f++) n += m->mFaces[f].mNumIndices == 3;
  return n;
}

/* The mesh's triangles in its own space (vertices as the file stores them). */
static tt_status tt__gltf_mesh_data(const tt__gltf *g, const struct aiMesh *m, const char *what,
                                    tt__mesh_data *d) {
  const uint32_t nv = m->mNumVertices, nt = tt__ai_tris(m);
  memset(d, 0, sizeof *d);
  d->vertex_count = nv;
  d->triangle_count = nt;
  d->positions = malloc(3 * sizeof(float) * (nv ? nv : 1));
  d->indices = malloc(3 * sizeof(uint32_t) * (nt ? nt : 1));
  if (m->mNormals) d->normals = malloc(3 * sizeof(float) * (nv ? nv : 1));
  if (m->mTextureCoords[0]) d->uvs = malloc(2 * sizeof(float) * (nv ? nv : 1));
  if (!d->positions || !d->indices || (m->mNormals && !d->normals) ||
      (m->mTextureCoords[0] && !d->uvs))
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
  for (uint32_t v = 0; v < nv; v++) {
    float *p = d->positions + 3 * (size_t)v;
    p[0] = m->mVertices[v].x, p[1] = m->mVertices[v].y, p[2] = m->mVertices[v].z;
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
      return tt_set_error(TT_ERR_PARSE,
                          "%s: %s: POSITION of vertex %u is (%g, %g, %g) (expected finite numbers)",
                          g->file, what, v, p[0], p[1], p[2]);
    if (d->normals) {
      double x = m->mNormals[v].x, y = m->mNormals[v].y, z = m->mNormals[v].z;
      double len = sqrt(x * x + y * y + z * z);
      if (!(len > 0) || !isfinite(len)) x = 0, y = 0, z = 1, len = 1;
      float *o = d->normals + 3 * (size_t)v;
      o[0] = (float)(x / len), o[1] = (float)(y / len), o[2] = (float)(z / len);
    }
    if (d->uvs) {
      d->uvs[2 * (size_t)v] = m->mTextureCoords[0][v].x;
      d->uvs[2 * (size_t)v + 1] = m->mTextureCoords[0][v].y;
    }
  }
  uint32_t t = 0;
  for (unsigned f = 0; f < m->mNumFaces; f++) {
    const struct aiFace *face = &m->mFaces[f];
    if (face->mNumIndices != 3) continue;
    for (int c = 0; c < 3; c++) {
      if (face->mIndices[c] >= nv)
        return tt_set_error(TT_ERR_PARSE, "%s: %s: face %u: index %u out of range (%u vertices)",
                            g->file, what, f, face->mIndices[c], nv);
      d->indices[3 * (size_t)t + c] = face->mIndices[c];
    }
    t++;
  }
  return TT_OK;
}

/* Morph targets (assimp's aiAnimMesh: absolute positions and normals) as offsets from the
 * rest pose, and the weights' track from the animation's channel of the mesh's node. */
static tt_status tt__gltf_morph(tt__gltf *g, const struct aiMesh *m, tt__mesh_anim *ma,
                                const char *node_name, const char *what, int *cubic_said) {
  const uint32_t nv = m->mNumVertices, nt = m->mNumAnimMeshes;
  ma->targets = nt;
  ma->dpos = calloc((size_t)nt * nv * 3 + 1, sizeof(float));
  ma->weights0 = calloc(nt, sizeof(float));
  if (ma->rest_nrm) ma->dnrm = calloc((size_t)nt * nv * 3 + 1, sizeof(float));
  if (!ma->dpos || !ma->weights0 || (ma->rest_nrm && !ma->dnrm))
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
  for (uint32_t t = 0; t < nt; t++) {
    const struct aiAnimMesh *am = m->mAnimMeshes[t];
    if (am->mNumVertices != nv || !am->mVertices)
      return tt_set_error(TT_ERR_PARSE,
                          "%s: %s: morph target %u: mismatched morph target size: expected %u "
                          "POSITION values (one per vertex), got %u",
                          g->file, what, t, nv, am->mVertices ? am->mNumVertices : 0);
    ma->weights0[t] = am->mWeight;
    if (!isfinite(am->mWeight))
      return tt_set_error(TT_ERR_PARSE, "%s: %s: weights[%u] is %g (expected a finite weight)",
                          g->file, what, t, am->mWeight);
    for (uint32_t v = 0; v < nv; v++) {
      const float p[3] = {am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z};
      float *o = ma->dpos + ((size_t)t * nv + v) * 3;
      for (int k = 0; k < 3; k++) {
        o[k] = p[k] - ma->rest_pos[3 * (size_t)v + k];
        if (!isfinite(o[k]))
          return tt_set_error(TT_ERR_PARSE,
                              "%s: %s: morph target %u: POSITION of vertex %u is not finite",
                              g->file, what, t, v);
      }
      if (ma->dnrm && am->mNormals) {
        const float n[3] = {am->mNormals[v].x, am->mNormals[v].y, am->mNormals[v].z};
        float *on = ma->dnrm + ((size_t)t * nv + v) * 3;
        for (int k = 0; k < 3; k++)
          on[k] = isfinite(n[k]) ? n[k] - ma->rest_nrm[3 * (size_t)v + k] : 0.0f;
      }
    }
  }
  const struct aiAnimation *an = g->anim_index >= 0 ? g->sc->mAnimations[g->anim_index] : NULL;
  for (unsigned c = 0; an && c < an->mNumMorphMeshChannels; c++) {
    const struct aiMeshMorphAnim *ch = an->mMorphMeshChannels[c];
    if (strcmp(ch->mName.data, node_name) != 0 || ch->mNumKeys == 0) continue;
    char w2[600];
    snprintf(w2, sizeof w2, "animations[%d] \"%.200s\", weights of node \"%.200s\"", g->anim_index,
             an->mName.data, node_name);
    const double tps = an->mTicksPerSecond > 0 ? an->mTicksPerSecond : 1000.0;
    tt__interp ip = tt__jinterp(g, node_name, "weights");
    if (ip == TT__INTERP_CUBIC) tt__gltf_cubic_note(g, cubic_said);
    if (tt__track_alloc(&ma->weights, ch->mNumKeys, nt, ip) != TT_OK)
      return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
    for (unsigned k = 0; k < ch->mNumKeys; k++) {
      const struct aiMeshMorphKey *key = &ch->mKeys[k];
      if (key->mNumValuesAndWeights != nt)
        return tt_set_error(TT_ERR_PARSE,
                            "%s: %s: key %u: mismatched morph target size: %u weights, but the "
                            "mesh %s has %u morph targets",
                            g->file, w2, k, key->mNumValuesAndWeights, what, nt);
      tt_status st = tt__gltf_time(g, w2, k, key->mTime, tps, k ? ma->weights.times[k - 1] : 0,
                                   &ma->weights.times[k]);
      if (st != TT_OK) return st;
      float *v = ma->weights.values + (size_t)k * nt;
      for (uint32_t j = 0; j < nt; j++) {
        if (key->mValues[j] >= nt)
          return tt_set_error(TT_ERR_PARSE, "%s: %s: key %u names morph target %u of %u", g->file,
                              w2, k, key->mValues[j], nt);
        v[key->mValues[j]] = (float)key->mWeights[j];
      }
      if ((st = tt__gltf_finite(g, w2, k, v, (int)nt)) != TT_OK) return st;
    }
    if (ip == TT__INTERP_CUBIC) tt__track_catmull_rom(&ma->weights);
    break;
  }
  return TT_OK;
}

/* assimp's bones (one per joint: the joint node's name, the inverse bind matrix, the
 * vertices it moves) as a skin: per vertex as many influences as the busiest vertex has. */
static tt_status tt__gltf_skin(tt__gltf *g, const struct aiMesh *m, tt__mesh_anim *ma,
                               const char *what) {
  const uint32_t nv = m->mNumVertices, nj = m->mNumBones;
  tt_status st = TT_OK;
  uint32_t *count = calloc(nv ? nv : 1, sizeof *count);
  int32_t *jn = calloc(nj, sizeof *jn);
  const char **names = calloc(nj, sizeof *names);
  double *ib = calloc((size_t)16 * nj, sizeof *ib);
  uint32_t *idx = NULL;
  float *w = NULL;
  char where[600];
  snprintf(where, sizeof where, "%s: %s skin", g->file, what);
  if (!count || !jn || !names || !ib) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
    goto done;
  }
  uint32_t inf = 1;
  for (uint32_t j = 0; j < nj; j++) {
    const struct aiBone *b = m->mBones[j];
    names[j] = b->mName.data;
    jn[j] = tt__gltf_find(g, b->mName.data);
    if (jn[j] == -2) {
      st = tt_set_error(TT_ERR_PARSE,
                        "%s: joint %u names node \"%s\", which several nodes are called (joints "
                        "need unique names)",
                        where, j, b->mName.data);
      goto done;
    }
    tt__aimat(&b->mOffsetMatrix, ib + 16 * (size_t)j);
    for (unsigned k = 0; k < b->mNumWeights; k++) {
      const struct aiVertexWeight *vw = &b->mWeights[k];
      if (vw->mVertexId >= nv) {
        st = tt_set_error(TT_ERR_PARSE, "%s: joint %u moves vertex %u of %u", where, j,
                          vw->mVertexId, nv);
        goto done;
      }
      if (vw->mWeight != 0.0f && ++count[vw->mVertexId] > inf) inf = count[vw->mVertexId];
    }
  }
  idx = calloc((size_t)nv * inf + 1, sizeof *idx);
  w = calloc((size_t)nv * inf + 1, sizeof *w);
  if (!idx || !w) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
    goto done;
  }
  memset(count, 0, sizeof *count * (nv ? nv : 1));
  for (uint32_t j = 0; j < nj; j++) {
    const struct aiBone *b = m->mBones[j];
    for (unsigned k = 0; k < b->mNumWeights; k++) {
      const struct aiVertexWeight *vw = &b->mWeights[k];
      if (vw->mWeight == 0.0f) continue;
      const size_t at = (size_t)vw->mVertexId * inf + count[vw->mVertexId]++;
      idx[at] = j;
      w[at] = vw->mWeight;
    }
  }
  st = tt__mesh_anim_set_skin(g->scene, ma, nj, jn, names, ib, inf, idx, w, where);
done:
  free(count);
  free(jn);
  free(names);
  free(ib);
  free(idx);
  free(w);
  return st;
}

/* Every triangle mesh of every node: still ones placed once, moving ones posed per frame. */
static tt_status tt__gltf_meshes(tt__gltf *g, int *cubic_said) {
  tt_scene *s = g->scene;
  for (uint32_t i = 0; i < g->nodes; i++) {
    const struct aiNode *n = g->ainode[i];
    for (unsigned k = 0; k < n->mNumMeshes; k++) {
      const unsigned mi = n->mMeshes[k];
      if (mi >= g->sc->mNumMeshes) continue;
      const struct aiMesh *m = g->sc->mMeshes[mi];
      if (tt__ai_tris(m) == 0) continue;
      char what[400];
      snprintf(what, sizeof what, "mesh \"%.150s\" of node \"%.150s\"", m->mName.data,
               n->mName.data);
      tt__mesh_data d;
      tt_status st = tt__gltf_mesh_data(g, m, what, &d);
      if (st == TT_OK) {
        char name[600];
        snprintf(name, sizeof name, "%.250s/%.250s", n->mName.data,
                 m->mName.length ? m->mName.data : "mesh");
        if (!(d.name = tt__strdup(name)))
          st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
      }
      const int skinned = m->mNumBones > 0, morph = m->mNumAnimMeshes > 0;
      const tt__anim_node *an = tt__scene_anim_node(s, i);
      if (st == TT_OK && !skinned && !morph && !g->moves[i]) {
        /* never moves: placed once at its node's rest world matrix */
        static const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        if (memcmp(an->world, id, sizeof id) != 0 &&
            tt__mesh_data_transform(&d, an->world) != TT_OK)
          st = tt_set_error(TT_ERR_PARSE,
                            "%s: %s: the node's world matrix is singular (a zero scale?)", g->file,
                            what);
      }
      const uint32_t mat = m->mMaterialIndex < g->sc->mNumMaterials ? g->mat[m->mMaterialIndex]
                                                                    : s->material_count - 1;
      if (st == TT_OK) st = tt__scene_add_mesh(s, &d, mat);
      tt__mesh_data_free(&d);
      if (st != TT_OK) return st;
      if (!skinned && !morph && !g->moves[i]) continue;
      tt__mesh_anim *ma = NULL;
      if ((st = tt__scene_anim_add_mesh(s, s->mesh_count - 1, &ma)) != TT_OK) return st;
      /* glTF: a skinned mesh is placed by its joints alone, not by its node */
      ma->node = skinned ? -1 : (int32_t)i;
      if (morph && (st = tt__gltf_morph(g, m, ma, n->mName.data, what, cubic_said)) != TT_OK)
        return st;
      if (skinned && (st = tt__gltf_skin(g, m, ma, what)) != TT_OK) return st;
    }
  }
  return TT_OK;
}

/* ---- camera --------------------------------------------------------------------------------- */

/* The pose of a glTF camera (looking down its node's -Z, up +Y) from the node's world
 * matrix. */
static void tt__cam_pose(const double w[16], float pos[3], float target[3], float up[3]) {
  for (int r = 0; r < 3; r++) {
    pos[r] = (float)w[4 * r + 3];
    target[r] = (float)(w[4 * r + 3] - w[4 * r + 2]);
    up[r] = (float)w[4 * r + 1];
  }
}

static void tt__add_times(const tt__track *t, double *times, uint32_t *n, uint32_t cap) {
  for (uint32_t k = 0; k < t->count && *n < cap; k++) times[(*n)++] = t->times[k];
}

static int tt__cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

/* The first perspective camera of the file: the still camera at the start time and, when
 * its node moves, the camera path sampled from the node's pose. Returns 0 without one. */
static tt_status tt__gltf_camera(tt__gltf *g, int *found) {
  *found = 0;
  tt_scene *s = g->scene;
  const cJSON *nodes = cJSON_GetObjectItemCaseSensitive(g->json, "nodes");
  int jnode = -1;
  const cJSON *persp = NULL;
  /* in assimp's node order (the scene's hierarchy, depth first) */
  for (uint32_t i = 0; i < g->nodes && jnode < 0; i++) {
    unsigned idx = 0;
    for (const cJSON *nd = cJSON_IsArray(nodes) ? nodes->child : NULL; nd; nd = nd->next, idx++) {
      const cJSON *cam = cJSON_GetObjectItemCaseSensitive(nd, "camera");
      if (!cJSON_IsNumber(cam)) continue;
      char nn[256];
      tt__jnode_name(g->json, (int)idx, nn, sizeof nn);
      if (strcmp(nn, g->ainode[i]->mName.data) != 0) continue;
      const cJSON *c = tt__jat(g->json, "cameras", cam->valueint);
      const cJSON *ty = c ? cJSON_GetObjectItemCaseSensitive(c, "type") : NULL;
      if (!cJSON_IsString(ty) || strcmp(ty->valuestring, "perspective") != 0) continue;
      persp = cJSON_GetObjectItemCaseSensitive(c, "perspective");
      jnode = (int)i;
      break;
    }
  }
  if (jnode < 0) return TT_OK;
  *found = 1;
  const cJSON *yf = persp ? cJSON_GetObjectItemCaseSensitive(persp, "yfov") : NULL;
  const cJSON *ar = persp ? cJSON_GetObjectItemCaseSensitive(persp, "aspectRatio") : NULL;
  double yfov = cJSON_IsNumber(yf) ? yf->valuedouble : -1;
  if (!(yfov > 0 && yfov < TT__PI))
    return tt_set_error(TT_ERR_PARSE,
                        "%s: camera of node \"%s\": perspective.yfov: expected radians in (0, pi), "
                        "got %g",
                        g->file, g->ainode[jnode]->mName.data, yfov);
  s->camera.fov_y = (float)(yfov * 180.0 / TT__PI);
  if (cJSON_IsNumber(ar) && ar->valuedouble > 0 && isfinite(ar->valuedouble)) {
    double h = s->camera.width / ar->valuedouble;
    s->camera.height = (uint32_t)(h < 1 ? 1 : h > 65536 ? 65536 : h + 0.5);
  }
  double t0, t1;
  tt__scene_anim_range(s, &t0, &t1);
  tt__scene_anim_pose_nodes(s, t0);
  tt__cam_pose(tt__scene_anim_node(s, (uint32_t)jnode)->world, s->camera.position, s->camera.target,
               s->camera.up);
  if (!g->moves[jnode]) return TT_OK;
  /* every key time of the node and its ancestors, with TT__CAM_SUBSTEPS between */
  uint32_t n = 0;
  double *times = malloc(sizeof(double) * TT__CAM_MAX_KEYS);
  if (!times) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
  for (int32_t i = jnode; i >= 0; i = tt__scene_anim_node(s, (uint32_t)i)->parent) {
    const tt__anim_node *an = tt__scene_anim_node(s, (uint32_t)i);
    tt__add_times(&an->tr, times, &n, TT__CAM_MAX_KEYS / TT__CAM_SUBSTEPS);
    tt__add_times(&an->rot, times, &n, TT__CAM_MAX_KEYS / TT__CAM_SUBSTEPS);
    tt__add_times(&an->sc, times, &n, TT__CAM_MAX_KEYS / TT__CAM_SUBSTEPS);
  }
  qsort(times, n, sizeof *times, tt__cmp_double);
  uint32_t u = 0;
  for (uint32_t k = 0; k < n; k++)
    if (u == 0 || times[k] > times[u - 1]) times[u++] = times[k];
  n = u;
  uint32_t total = n ? (n - 1) * TT__CAM_SUBSTEPS + 1 : 0;
  tt_camera_key *keys = calloc(total ? total : 1, sizeof *keys);
  if (!keys) {
    free(times);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
  }
  uint32_t w = 0;
  for (uint32_t k = 0; k < n; k++)
    for (uint32_t j = 0; j < (k + 1 < n ? TT__CAM_SUBSTEPS : 1u); j++) {
      double t = k + 1 < n ? times[k] + (times[k + 1] - times[k]) * j / TT__CAM_SUBSTEPS : times[k];
      if (w > 0 && !((float)t > keys[w - 1].time)) continue; /* float times stay increasing */
      tt__scene_anim_pose_nodes(s, t);
      tt_camera_key *key = &keys[w++];
      key->time = (float)t;
      tt__cam_pose(tt__scene_anim_node(s, (uint32_t)jnode)->world, key->position, key->target,
                   key->up);
      key->fov_y = s->camera.fov_y;
    }
  free(times);
  free(s->keys);
  s->keys = keys;
  s->camera.key_count = w;
  s->camera.keys = keys;
  return TT_OK;
}

/* No camera in the file: the start pose's bounds seen from +Z, filling the view. */
static void tt__gltf_frame(tt_scene *s) {
  float c[3], r = 0;
  for (int a = 0; a < 3; a++) {
    c[a] = 0.5f * (s->lo[a] + s->hi[a]);
    float h = 0.5f * (s->hi[a] - s->lo[a]);
    r += h * h;
  }
  r = sqrtf(r);
  if (!(r > 0)) r = 1;
  double d = r / sin(0.5 * s->camera.fov_y * TT__PI / 180.0);
  for (int a = 0; a < 3; a++) {
    s->camera.target[a] = c[a];
    s->camera.position[a] = c[a];
    s->camera.up[a] = a == 1;
  }
  s->camera.position[2] = (float)(c[2] + d);
}

/* ---- lights ---------------------------------------------------------------------------------- */

/* KHR_lights_punctual (assimp's aiLight: colour times intensity, the node's name) at their
 * nodes' start pose: point (intensity), spot (its cones) and directional (irradiance)
 * lights, shining down the node's -Z. tunetrace lights do not move: a light on a moving
 * node is said once. */
static tt_status tt__gltf_lights(tt__gltf *g) {
  tt_scene *s = g->scene;
  double t0, t1;
  tt__scene_anim_range(s, &t0, &t1);
  tt__scene_anim_pose_nodes(s, t0);
  for (unsigned i = 0; i < g->sc->mNumLights; i++) {
    const struct aiLight *al = g->sc->mLights[i];
    char what[400];
    snprintf(what, sizeof what, "light of node \"%.200s\"", al->mName.data);
    int32_t node;
    tt_status st = tt__gltf_node_ref(g, al->mName.data, what, &node);
    if (st != TT_OK) return st;
    const double *w = tt__scene_anim_node(s, (uint32_t)node)->world;
    tt_light l;
    memset(&l, 0, sizeof l);
    l.struct_size = sizeof l;
    const float rgb[3] = {al->mColorDiffuse.r, al->mColorDiffuse.g, al->mColorDiffuse.b};
    for (int k = 0; k < 3; k++) {
      if (!isfinite(rgb[k]) || rgb[k] < 0)
        return tt_set_error(TT_ERR_PARSE,
                            "%s: %s: color times intensity is (%g, %g, %g) (expected finite "
                            "values >= 0)",
                            g->file, what, rgb[0], rgb[1], rgb[2]);
      l.radiance[k] = rgb[k];
      l.position[k] = (float)w[4 * k + 3];
      l.direction[k] = (float)-w[4 * k + 2];
    }
    double len =
        sqrt((double)l.direction[0] * l.direction[0] + (double)l.direction[1] * l.direction[1] +
             (double)l.direction[2] * l.direction[2]);
    if (al->mType != aiLightSource_POINT && !(len > 0 && isfinite(len)))
      return tt_set_error(TT_ERR_PARSE,
                          "%s: %s: the node's matrix gives no direction (zero "
                          "scale?)",
                          g->file, what);
    for (int k = 0; k < 3 && len > 0; k++) l.direction[k] = (float)(l.direction[k] / len);
    if (al->mType == aiLightSource_POINT) l.type = TT_LIGHT_POINT;
    else if (al->mType == aiLightSource_DIRECTIONAL) l.type = TT_LIGHT_DISTANT;
    else if (al->mType == aiLightSource_SPOT) {
      l.type = TT_LIGHT_SPOT;
      double outer = al->mAngleOuterCone, inner = al->mAngleInnerCone;
      if (!(outer > 0 && outer <= TT__PI / 2) || !(inner >= 0 && inner <= outer))
        return tt_set_error(TT_ERR_PARSE,
                            "%s: %s: spot.innerConeAngle %g and outerConeAngle %g: expected 0 <= "
                            "inner <= outer <= pi/2",
                            g->file, what, inner, outer);
      l.cos_outer = (float)cos(outer);
      l.cos_inner = (float)cos(inner);
    } else {
      tt__log(TT_LOG_WARN, "%s: %s: unsupported light type (ignored)", g->file, what);
      continue;
    }
    if (g->moves[node])
      tt__log(TT_LOG_WARN,
              "%s: %s: the light stays where its node is at the start (%g s); "
              "lights do not move",
              g->file, what, t0);
    tt_light *slot =
        tt__scene_push((void **)&s->lights, &s->light_count, &s->light_cap, sizeof *slot);
    if (!slot) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", g->file);
    *slot = l;
  }
  return TT_OK;
}

/* ---- entry point ------------------------------------------------------------------------------ */

tt_status tt__scene_load_gltf(const char *path, int imported, tt_scene **out) {
  *out = NULL;
  char why[512];
  if (tt__file_regular_reason(path, why, sizeof why) != 0)
    return tt_set_error(TT_ERR_IO, "%s: cannot open glTF file: %s", path, why);
  tt_status st = tt__gltf_check(path, path);
  if (st != TT_OK) return st;
  tt__gltf g;
  memset(&g, 0, sizeof g);
  g.file = path;
  g.anim_index = -1;
  if ((st = tt__gltf_json(path, &g.json)) != TT_OK) return st;
  tt__assimp *ai = NULL;
  if ((st = tt__gltf_json_check(path, g.json)) != TT_OK) {
    cJSON_Delete(g.json);
    return st;
  }
  /* validated below, once the keys are checked with messages that name the channel */
  switch (tt__assimp_read(path, aiProcess_Triangulate, &ai, &g.sc, why, sizeof why)) {
  case TT__ASSIMP_OK: break;
  case TT__ASSIMP_OUT_OF_MEMORY:
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    break;
  default: st = tt_set_error(TT_ERR_PARSE, "%s: cannot import the glTF file: %s", path, why);
  }
  if (st != TT_OK) {
    cJSON_Delete(g.json);
    return st;
  }
  g.scene = tt__scene_new(path);
  if (!g.scene) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
  int cubic_said = 0, camera = 0;
  if (st == TT_OK) st = tt__gltf_nodes(&g, g.sc->mRootNode, -1, 0);
  if (st == TT_OK && !(g.moves = calloc(g.nodes ? g.nodes : 1, 1)))
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
  if (st == TT_OK && g.sc->mNumAnimations > 0) {
    g.anim_index = 0;
    if (g.sc->mNumAnimations > 1)
      tt__log(TT_LOG_WARN,
              "%s: plays animations[0] \"%s\"; the file's %u other animations are "
              "not played",
              path, g.sc->mAnimations[0]->mName.data, g.sc->mNumAnimations - 1);
    st = tt__gltf_channels(&g, g.sc->mAnimations[0], &cubic_said);
  }
  if (st == TT_OK) {
    switch (tt__assimp_validate(ai, why, sizeof why)) {
    case TT__ASSIMP_OK: break;
    case TT__ASSIMP_OUT_OF_MEMORY:
      st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
      break;
    default: st = tt_set_error(TT_ERR_PARSE, "%s: cannot import the glTF file: %s", path, why);
    }
  }
  if (st == TT_OK) {
    double t0, t1;
    tt__scene_anim_range(g.scene, &t0, &t1);
    tt__scene_anim_pose_nodes(g.scene, t0); /* rest world matrices for still meshes */
  }
  if (st == TT_OK) st = tt__gltf_materials(&g);
  if (st == TT_OK) st = tt__gltf_meshes(&g, &cubic_said);
  if (st == TT_OK && g.scene->mesh_count == 0)
    st = tt_set_error(TT_ERR_PARSE, "%s: meshes: the file contains no triangles", path);
  if (st == TT_OK) st = tt__gltf_camera(&g, &camera);
  if (st == TT_OK) st = tt__gltf_lights(&g);
  if (st == TT_OK && !imported && !g.has_emitter && g.scene->light_count == 0) {
    /* a file without lights would render black on its own: a dim white sky and a sun from
     * above and in front (+Y up, +Z toward the default view, as glTF), so shapes read even
     * with glTF's default white albedo, which a uniform sky alone turns into a white
     * furnace where nothing can be seen */
    tt_light *l = tt__scene_push((void **)&g.scene->lights, &g.scene->light_count,
                                 &g.scene->light_cap, sizeof *l);
    tt_light *sun = l ? tt__scene_push((void **)&g.scene->lights, &g.scene->light_count,
                                       &g.scene->light_cap, sizeof *sun)
                      : NULL;
    if (!l || !sun) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    else {
      l = &g.scene->lights[g.scene->light_count - 2];
      l->struct_size = sun->struct_size = sizeof *l;
      l->type = TT_LIGHT_ENV_CONSTANT;
      l->radiance[0] = l->radiance[1] = l->radiance[2] = 0.3f;
      sun->type = TT_LIGHT_DISTANT;
      const double d[3] = {-0.4, -0.8, -0.45}, n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      for (int k = 0; k < 3; k++) {
        sun->direction[k] = (float)(d[k] / n);
        sun->radiance[k] = 2.5f;
      }
    }
  }
  if (st == TT_OK) st = tt__scene_finish(g.scene);
  if (st == TT_OK && !camera) tt__gltf_frame(g.scene);
  free(g.ainode);
  free(g.moves);
  free(g.mat);
  cJSON_Delete(g.json);
  tt__assimp_free(ai);
  if (st != TT_OK) {
    tt_scene_destroy(g.scene);
    return st;
  }
  *out = g.scene;
  return TT_OK;
}
