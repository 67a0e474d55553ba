/* scene.json v1 loader (format: scenes/README.md). Every error names the source, the JSON
 * path of the offending value and what was expected; unknown keys only warn, so files
 * written for a newer minor revision still load. A top-level "import" wraps another scene
 * file (.pbrt or a scene.json without an import of its own): its meshes, materials, lights,
 * camera and settings are loaded first, then this file's camera/render override them and
 * its materials/meshes/lights are appended. */
#include "io/io_internal.h"
#include "io/scene_json_internal.h"
#include "plugin/log.h"
#include "util/json_error.h"

#include <tunetrace/file.h>

#include <cjson/cJSON.h>

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define TT__PI 3.14159265358979323846

const tt__range tt__any = {-INFINITY, INFINITY, TT__LO_OPEN | TT__HI_OPEN};
const tt__range tt__nonneg = {0.0, INFINITY, TT__HI_OPEN};
static const tt__range tt__unit = {0.0, 1.0, 0};

/* ---- messages -------------------------------------------------------------------------- */

/* Warnings go to the log host (tt_set_log_host): the scene still loads, but typos should not
 * pass silently. */
void tt__jwarn(const tt__jctx *c, const char *path, const char *fmt, ...) {
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  tt__log(TT_LOG_WARN, "%s: %s: %s", c->src, path, msg);
}

/* "camera" + "fov" -> "camera.fov"; an empty prefix yields the key alone. */
void tt__jkey(char *buf, size_t n, const char *prefix, const char *key) {
  /* testing the result tells GCC that truncating an absurdly deep path is acceptable */
  int w =
      (prefix && prefix[0]) ? snprintf(buf, n, "%s.%s", prefix, key) : snprintf(buf, n, "%s", key);
  if (w < 0) buf[0] = '\0';
}

/* "meshes" + 2 -> "meshes[2]". */
void tt__jidx(char *buf, size_t n, const char *prefix, unsigned i) {
  if (snprintf(buf, n, "%s[%u]", prefix, i) < 0) buf[0] = '\0';
}

/* Describes a JSON value for "got ..." so the user sees what was actually there. */
const char *tt__jdesc(const cJSON *it, char *buf, size_t n) {
  return tt__json_describe(it, TT__JSON_SCENE, buf, n);
}

/* Formats a range as "(0, 180)" / "[1, 65536]" / "[0, inf)". */
static const char *tt__jrange_str(const tt__range *r, char *buf, size_t n) {
  snprintf(buf, n, "%c%g, %g%c", (r->flags & TT__LO_OPEN) ? '(' : '[', r->lo, r->hi,
           (r->flags & TT__HI_OPEN) ? ')' : ']');
  return buf;
}

/* Warns about keys outside `known`; keys starting with '_' are comments and stay silent. */
void tt__jcheck_keys(const tt__jctx *c, const cJSON *obj, const char *prefix,
                     const char *const *known) {
  for (const cJSON *it = obj ? obj->child : NULL; it; it = it->next) {
    if (!it->string || it->string[0] == '_') continue;
    int ok = 0;
    for (const char *const *k = known; *k && !ok; k++) ok = strcmp(*k, it->string) == 0;
    if (!ok) {
      char path[512];
      tt__jkey(path, sizeof path, prefix, it->string);
      tt__jwarn(c, path, "unknown key (ignored)");
    }
  }
}

/* ---- typed getters --------------------------------------------------------------------- */

/* Checks a number against a range; non-finite values (1e999 parses as inf) are rejected. */
tt_status tt__jnum_item(const tt__jctx *c, const cJSON *it, const char *path, const tt__range *r,
                        double *out) {
  char got[128], rs[96];
  int integer = (r->flags & TT__INT) != 0;
  if (!cJSON_IsNumber(it))
    return tt__jfail(c, TT_ERR_PARSE, path, "expected %s, got %s",
                     integer ? "an integer" : "a number", tt__jdesc(it, got, sizeof got));
  double v = it->valuedouble;
  if (!isfinite(v)) return tt__jfail(c, TT_ERR_PARSE, path, "expected a finite number, got %g", v);
  int lo_ok = (r->flags & TT__LO_OPEN) ? v > r->lo : v >= r->lo;
  int hi_ok = (r->flags & TT__HI_OPEN) ? v < r->hi : v <= r->hi;
  if (!lo_ok || !hi_ok || (integer && v != floor(v)))
    return tt__jfail(c, TT_ERR_PARSE, path, "expected %s in %s, got %g",
                     integer ? "an integer" : "a number", tt__jrange_str(r, rs, sizeof rs), v);
  *out = v;
  return TT_OK;
}

/* Optional/required number under `key`; leaves *out alone when absent and optional. */
tt_status tt__jnum(const tt__jctx *c, const cJSON *obj, const char *key, const char *prefix,
                   int required, const tt__range *r, double *out) {
  char path[512];
  tt__jkey(path, sizeof path, prefix, key);
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) {
    if (!required) return TT_OK;
    return tt__jfail(c, TT_ERR_PARSE, path, "missing required field (expected a number)");
  }
  return tt__jnum_item(c, it, path, r, out);
}

/* An array of exactly n numbers; with allow_scalar a single number fills all n. */
tt_status tt__jvec_item(const tt__jctx *c, const cJSON *it, const char *path, int n,
                        const tt__range *r, int allow_scalar, float *out) {
  char got[128], sub[560];
  double v;
  if (allow_scalar && cJSON_IsNumber(it)) {
    tt_status st = tt__jnum_item(c, it, path, r, &v);
    if (st != TT_OK) return st;
    for (int i = 0; i < n; i++) out[i] = (float)v;
    return TT_OK;
  }
  if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != n)
    return tt__jfail(c, TT_ERR_PARSE, path, "expected an array of %d numbers%s, got %s", n,
                     allow_scalar ? " (or one number)" : "", tt__jdesc(it, got, sizeof got));
  int i = 0;
  for (const cJSON *e = it->child; e; e = e->next, i++) {
    tt__jidx(sub, sizeof sub, path, (unsigned)i);
    tt_status st = tt__jnum_item(c, e, sub, r, &v);
    if (st != TT_OK) return st;
    out[i] = (float)v;
  }
  return TT_OK;
}

/* Optional/required n-vector under `key`. */
tt_status tt__jvec(const tt__jctx *c, const cJSON *obj, const char *key, const char *prefix,
                   int required, int n, const tt__range *r, int allow_scalar, float *out) {
  char path[512];
  tt__jkey(path, sizeof path, prefix, key);
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) {
    if (!required) return TT_OK;
    return tt__jfail(c, TT_ERR_PARSE, path,
                     "missing required field (expected an array of %d numbers)", n);
  }
  return tt__jvec_item(c, it, path, n, r, allow_scalar, out);
}

/* Optional/required non-empty string under `key`; *out points into the JSON tree. */
tt_status tt__jstr(const tt__jctx *c, const cJSON *obj, const char *key, const char *prefix,
                   int required, const char **out) {
  char path[512], got[128];
  tt__jkey(path, sizeof path, prefix, key);
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) {
    if (!required) return TT_OK;
    return tt__jfail(c, TT_ERR_PARSE, path, "missing required field (expected a string)");
  }
  if (!cJSON_IsString(it) || !it->valuestring[0])
    return tt__jfail(c, TT_ERR_PARSE, path, "expected a non-empty string, got %s",
                     tt__jdesc(it, got, sizeof got));
  *out = it->valuestring;
  return TT_OK;
}

/* Optional boolean under `key`. */
tt_status tt__jbool(const tt__jctx *c, const cJSON *obj, const char *key, const char *prefix,
                    int *out) {
  char path[512], got[128];
  tt__jkey(path, sizeof path, prefix, key);
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!it) return TT_OK;
  if (!cJSON_IsBool(it))
    return tt__jfail(c, TT_ERR_PARSE, path, "expected true or false, got %s",
                     tt__jdesc(it, got, sizeof got));
  *out = cJSON_IsTrue(it) ? 1 : 0;
  return TT_OK;
}

/* Objects are required where a section exists; a clear message beats a silent default. */
tt_status tt__jobject(const tt__jctx *c, const cJSON *it, const char *path) {
  char got[128];
  if (!cJSON_IsObject(it))
    return tt__jfail(c, TT_ERR_PARSE, path, "expected an object, got %s",
                     tt__jdesc(it, got, sizeof got));
  return TT_OK;
}

/* Absolute paths stay; relative ones are joined to the scene file's directory. */
static char *tt__resolve(const tt__jctx *c, const char *rel) {
  if (rel[0] == '/' || !c->base || !c->base[0]) return tt__strdup(rel);
  size_t n = strlen(c->base) + strlen(rel) + 2;
  char *p = malloc(n);
  if (!p) return NULL;
  size_t bl = strlen(c->base);
  snprintf(p, n, "%s%s%s", c->base, c->base[bl - 1] == '/' ? "" : "/", rel);
  return p;
}

/* Readability probe for optional assets (textures, environment images): a regular file
 * (a FIFO or a device would hang or flood the image reader). */
static int tt__file_exists(const char *path) { return tt_file_check_regular(path, NULL) == TT_OK; }

/* 3-vector helpers for camera checks. */
double tt__len3(const float v[3]) {
  return sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
}

/* ---- render & camera ------------------------------------------------------------------- */

/* Render settings; absent fields keep the defaults from tt__scene_new. */
static tt_status tt__jrender(const tt__jctx *c, const cJSON *root) {
  const cJSON *r = cJSON_GetObjectItemCaseSensitive(root, "render");
  if (!r) return TT_OK;
  tt_status st = tt__jobject(c, r, "render");
  if (st != TT_OK) return st;
  static const char *const known[] = {"spp", "maxDepth", "seed", "timeBudget", NULL};
  tt__jcheck_keys(c, r, "render", known);
  tt_render_settings *s = &c->scene->settings;
  double v;
  static const tt__range spp_r = {1, 1 << 24, TT__INT}, depth_r = {0, 1024, TT__INT},
                         seed_r = {0, 9007199254740992.0, TT__INT};
  v = s->spp;
  if ((st = tt__jnum(c, r, "spp", "render", 0, &spp_r, &v)) != TT_OK) return st;
  s->spp = (uint32_t)v;
  v = s->max_depth;
  if ((st = tt__jnum(c, r, "maxDepth", "render", 0, &depth_r, &v)) != TT_OK) return st;
  s->max_depth = (uint32_t)v;
  v = (double)s->seed;
  if ((st = tt__jnum(c, r, "seed", "render", 0, &seed_r, &v)) != TT_OK) return st;
  s->seed = (uint64_t)v;
  v = s->time_budget_s;
  if ((st = tt__jnum(c, r, "timeBudget", "render", 0, &tt__nonneg, &v)) != TT_OK) return st;
  s->time_budget_s = v;
  return TT_OK;
}

/* A pose must define a view direction and an up vector not parallel to it, or the camera
 * basis is undefined. */
static tt_status tt__jcheck_pose(const tt__jctx *c, const char *prefix, const float pos[3],
                                 const float tgt[3], const float up[3]) {
  char path[512];
  float d[3] = {tgt[0] - pos[0], tgt[1] - pos[1], tgt[2] - pos[2]};
  double dl = tt__len3(d), ul = tt__len3(up);
  if (!(dl > 0)) {
    tt__jkey(path, sizeof path, prefix, "target");
    return tt__jfail(c, TT_ERR_PARSE, path, "expected a point different from %s.position", prefix);
  }
  tt__jkey(path, sizeof path, prefix, "up");
  if (!(ul > 0)) return tt__jfail(c, TT_ERR_PARSE, path, "expected a non-zero vector");
  float x[3] = {d[1] * up[2] - d[2] * up[1], d[2] * up[0] - d[0] * up[2],
                d[0] * up[1] - d[1] * up[0]};
  if (tt__len3(x) <= 1e-6 * dl * ul)
    return tt__jfail(c, TT_ERR_PARSE, path, "expected a vector not parallel to the view direction");
  return TT_OK;
}

/* Still camera plus the optional keyframed path. With an imported scene every field is
 * optional and overrides the imported camera; a path replaces the imported one. */
static tt_status tt__jcamera(const tt__jctx *c, const cJSON *root, int imported) {
  const cJSON *cam = cJSON_GetObjectItemCaseSensitive(root, "camera");
  if (!cam && imported) return TT_OK;
  if (!cam)
    return tt__jfail(c, TT_ERR_PARSE, "camera", "missing required field (expected an object)");
  tt_status st = tt__jobject(c, cam, "camera");
  if (st != TT_OK) return st;
  static const char *const known[] = {"position",   "target", "up", "fov",
                                      "resolution", "path",   NULL};
  tt__jcheck_keys(c, cam, "camera", known);
  static const tt__range fov_r = {0, 180, TT__LO_OPEN | TT__HI_OPEN};
  static const tt__range res_r = {1, 65536, TT__INT};
  tt_camera *k = &c->scene->camera;
  double v;
  int req = !imported;
  if ((st = tt__jvec(c, cam, "position", "camera", req, 3, &tt__any, 0, k->position)) != TT_OK)
    return st;
  if ((st = tt__jvec(c, cam, "target", "camera", req, 3, &tt__any, 0, k->target)) != TT_OK)
    return st;
  if ((st = tt__jvec(c, cam, "up", "camera", 0, 3, &tt__any, 0, k->up)) != TT_OK) return st;
  v = k->fov_y;
  if ((st = tt__jnum(c, cam, "fov", "camera", 0, &fov_r, &v)) != TT_OK) return st;
  k->fov_y = (float)v;
  float res[2] = {(float)k->width, (float)k->height};
  if ((st = tt__jvec(c, cam, "resolution", "camera", 0, 2, &res_r, 0, res)) != TT_OK) return st;
  k->width = (uint32_t)res[0];
  k->height = (uint32_t)res[1];
  if ((st = tt__jcheck_pose(c, "camera", k->position, k->target, k->up)) != TT_OK) return st;

  const cJSON *path = cJSON_GetObjectItemCaseSensitive(cam, "path");
  if (!path) return TT_OK;
  char got[128];
  if (!cJSON_IsArray(path))
    return tt__jfail(c, TT_ERR_PARSE, "camera.path", "expected an array of keys, got %s",
                     tt__jdesc(path, got, sizeof got));
  int n = cJSON_GetArraySize(path);
  /* a path in this file replaces an imported one (an empty array removes it) */
  free(c->scene->keys);
  c->scene->keys = NULL;
  k->key_count = 0;
  k->keys = NULL;
  if (n == 0) return TT_OK;
  c->scene->keys = calloc((size_t)n, sizeof *c->scene->keys);
  if (!c->scene->keys) return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, "camera.path", "out of memory");
  static const char *const kknown[] = {"time", "position", "target", "up", "fov", NULL};
  unsigned i = 0;
  for (const cJSON *e = path->child; e; e = e->next, i++) {
    char kp[512], tp[560];
    tt__jidx(kp, sizeof kp, "camera.path", i);
    if ((st = tt__jobject(c, e, kp)) != TT_OK) return st;
    tt__jcheck_keys(c, e, kp, kknown);
    tt_camera_key *key = &c->scene->keys[i];
    memcpy(key->position, k->position, sizeof key->position);
    memcpy(key->target, k->target, sizeof key->target);
    memcpy(key->up, k->up, sizeof key->up);
    key->fov_y = k->fov_y;
    if ((st = tt__jnum(c, e, "time", kp, 1, &tt__any, &v)) != TT_OK) return st;
    key->time = (float)v;
    if (i > 0 && !(key->time > key[-1].time)) {
      tt__jkey(tp, sizeof tp, kp, "time");
      return tt__jfail(c, TT_ERR_PARSE, tp,
                       "expected a time greater than the previous key's (%g), got %g", key[-1].time,
                       v);
    }
    if ((st = tt__jvec(c, e, "position", kp, 0, 3, &tt__any, 0, key->position)) != TT_OK) return st;
    if ((st = tt__jvec(c, e, "target", kp, 0, 3, &tt__any, 0, key->target)) != TT_OK) return st;
    if ((st = tt__jvec(c, e, "up", kp, 0, 3, &tt__any, 0, key->up)) != TT_OK) return st;
    v = key->fov_y;
    if ((st = tt__jnum(c, e, "fov", kp, 0, &fov_r, &v)) != TT_OK) return st;
    key->fov_y = (float)v;
    if ((st = tt__jcheck_pose(c, kp, key->position, key->target, key->up)) != TT_OK) return st;
  }
  k->key_count = (uint32_t)n;
  k->keys = c->scene->keys;
  return TT_OK;
}

/* ---- materials ------------------------------------------------------------------------- */

/* Textures are shared by resolved path; a missing file falls back to the constant albedo
 * with a warning, as the shared scenes' MISSING_FILES convention asks. */
static tt_status tt__jtexture(const tt__jctx *c, const char *path, const char *rel, int32_t *out) {
  *out = -1;
  char *full = tt__resolve(c, rel);
  if (!full) return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, path, "out of memory");
  if (!tt__file_exists(full)) {
    tt__jwarn(c, path, "texture \"%s\" not found, using the constant albedo", full);
    free(full);
    return TT_OK;
  }
  tt_scene *s = c->scene;
  for (uint32_t i = 0; i < s->texture_count; i++)
    if (strcmp(s->textures[i].path, full) == 0) {
      free(full);
      *out = (int32_t)i;
      return TT_OK;
    }
  tt_texture *t =
      tt__scene_push((void **)&s->textures, &s->texture_count, &s->texture_cap, sizeof *t);
  if (!t) {
    free(full);
    return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, path, "out of memory");
  }
  t->struct_size = sizeof *t;
  t->path = full;
  /* HDR formats store linear values; 8-bit formats are sRGB by convention */
  size_t n = strlen(full);
  t->srgb = !((n >= 4 && (strcmp(full + n - 4, ".exr") == 0 || strcmp(full + n - 4, ".hdr") == 0 ||
                          strcmp(full + n - 4, ".pfm") == 0)));
  *out = (int32_t)(s->texture_count - 1);
  return TT_OK;
}

/* One material; type-specific defaults are chosen before the fields override them. */
static tt_status tt__jmaterial(const tt__jctx *c, const cJSON *e, const char *mp, tt_material *m) {
  tt_status st;
  char path[512], got[128];
  if ((st = tt__jobject(c, e, mp)) != TT_OK) return st;
  static const char *const known[] = {"type", "albedo", "texture",  "roughness", "alpha",    "eta",
                                      "k",    "ior",    "specular", "emission",  "twoSided", NULL};
  tt__jcheck_keys(c, e, mp, known);
  const char *type = "diffuse";
  if ((st = tt__jstr(c, e, "type", mp, 0, &type)) != TT_OK) return st;
  static const char *const names[] = {"diffuse", "conductor", "dielectric", "mirror", "plastic"};
  static const tt_material_type types[] = {TT_MATERIAL_DIFFUSE, TT_MATERIAL_CONDUCTOR,
                                           TT_MATERIAL_DIELECTRIC, TT_MATERIAL_MIRROR,
                                           TT_MATERIAL_PLASTIC};
  m->type = 0;
  for (int i = 0; i < 5; i++)
    if (strcmp(type, names[i]) == 0) m->type = types[i];
  if (!m->type) {
    tt__jkey(path, sizeof path, mp, "type");
    return tt__jfail(
        c, TT_ERR_PARSE, path,
        "unknown material type \"%s\" (expected diffuse, conductor, dielectric, mirror or plastic)",
        type);
  }
  m->struct_size = sizeof *m;
  for (int i = 0; i < 3; i++) {
    m->albedo[i] = 0.5f;
    m->specular[i] = 1.0f;
  }
  m->albedo_texture = -1;
  /* gold, the usual conductor default (pbrt-v4's metal) */
  static const float au_eta[3] = {0.143f, 0.374f, 1.442f}, au_k[3] = {3.983f, 2.385f, 1.603f};
  memcpy(m->eta, au_eta, sizeof m->eta);
  memcpy(m->k, au_k, sizeof m->k);
  m->ior = 1.5f;
  float a = (m->type == TT_MATERIAL_CONDUCTOR || m->type == TT_MATERIAL_PLASTIC) ? 0.1f : 0.0f;
  m->alpha[0] = m->alpha[1] = a;
  static const tt__range rough_r = {0, TT__PI / 2, 0},
                         pos_r = {0, INFINITY, TT__LO_OPEN | TT__HI_OPEN};
  double v;
  if ((st = tt__jvec(c, e, "albedo", mp, 0, 3, &tt__unit, 1, m->albedo)) != TT_OK) return st;
  const char *tex = NULL;
  if ((st = tt__jstr(c, e, "texture", mp, 0, &tex)) != TT_OK) return st;
  if (tex) {
    tt__jkey(path, sizeof path, mp, "texture");
    if ((st = tt__jtexture(c, path, tex, &m->albedo_texture)) != TT_OK) return st;
  }
  v = m->roughness;
  if ((st = tt__jnum(c, e, "roughness", mp, 0, &rough_r, &v)) != TT_OK) return st;
  m->roughness = (float)v;
  const cJSON *al = cJSON_GetObjectItemCaseSensitive(e, "alpha");
  if (al) {
    tt__jkey(path, sizeof path, mp, "alpha");
    if (cJSON_IsArray(al) || cJSON_IsNumber(al)) {
      if ((st = tt__jvec_item(c, al, path, 2, &tt__unit, 1, m->alpha)) != TT_OK) return st;
    } else {
      return tt__jfail(c, TT_ERR_PARSE, path, "expected a number or an array [ax, ay], got %s",
                       tt__jdesc(al, got, sizeof got));
    }
  }
  if ((st = tt__jvec(c, e, "eta", mp, 0, 3, &pos_r, 0, m->eta)) != TT_OK) return st;
  if ((st = tt__jvec(c, e, "k", mp, 0, 3, &tt__nonneg, 0, m->k)) != TT_OK) return st;
  v = m->ior;
  if ((st = tt__jnum(c, e, "ior", mp, 0, &pos_r, &v)) != TT_OK) return st;
  m->ior = (float)v;
  if ((st = tt__jvec(c, e, "specular", mp, 0, 3, &tt__unit, 1, m->specular)) != TT_OK) return st;
  if ((st = tt__jvec(c, e, "emission", mp, 0, 3, &tt__nonneg, 1, m->emission)) != TT_OK) return st;
  if ((st = tt__jbool(c, e, "twoSided", mp, &m->two_sided)) != TT_OK) return st;
  return TT_OK;
}

/* The materials object, in file order (indices follow it). */
static tt_status tt__jmaterials(const tt__jctx *c, const cJSON *root, int imported) {
  const cJSON *mats = cJSON_GetObjectItemCaseSensitive(root, "materials");
  if (!mats && imported) return TT_OK;
  if (!mats)
    return tt__jfail(c, TT_ERR_PARSE, "materials",
                     "missing required field (expected an object of named materials)");
  tt_status st = tt__jobject(c, mats, "materials");
  if (st != TT_OK) return st;
  tt_scene *s = c->scene;
  for (const cJSON *e = mats->child; e; e = e->next) {
    char mp[512];
    tt__jkey(mp, sizeof mp, "materials", e->string);
    if (e->string[0] == '_') continue; /* comment entries */
    for (uint32_t i = 0; i < s->material_count; i++)
      if (strcmp(s->materials[i].name, e->string) == 0)
        return tt__jfail(c, TT_ERR_PARSE, mp, "duplicate material name%s",
                         imported ? " (names of the imported scene count too)" : "");
    tt_material m;
    memset(&m, 0, sizeof m);
    if ((st = tt__jmaterial(c, e, mp, &m)) != TT_OK) return st;
    tt_material *slot =
        tt__scene_push((void **)&s->materials, &s->material_count, &s->material_cap, sizeof *slot);
    if (!slot) return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, mp, "out of memory");
    m.name = tt__strdup(e->string);
    *slot = m;
    if (!m.name) return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, mp, "out of memory");
  }
  if (s->material_count == 0)
    return tt__jfail(c, TT_ERR_PARSE, "materials", "expected at least one material");
  return TT_OK;
}

/* ---- meshes ---------------------------------------------------------------------------- */

/* Rotation about a unit axis by `deg` degrees (Rodrigues). */
void tt__mat_rot(double r[16], double x, double y, double z, double deg) {
  double a = deg * TT__PI / 180.0, cs = cos(a), sn = sin(a), t = 1 - cs;
  double m[16] = {t * x * x + cs,
                  t * x * y - sn * z,
                  t * x * z + sn * y,
                  0,
                  t * x * y + sn * z,
                  t * y * y + cs,
                  t * y * z - sn * x,
                  0,
                  t * x * z - sn * y,
                  t * y * z + sn * x,
                  t * z * z + cs,
                  0,
                  0,
                  0,
                  0,
                  1};
  memcpy(r, m, sizeof m);
}

/* Builds the mesh's object-to-world matrix from "transform" (T * R * S) or "matrix";
 * *has is 0 when the mesh has neither. */
static tt_status tt__jtransform(const tt__jctx *c, const cJSON *e, const char *mp, double m[16],
                                int *has) {
  static const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  memcpy(m, id, sizeof id);
  *has = 0;
  const cJSON *tr = cJSON_GetObjectItemCaseSensitive(e, "transform");
  const cJSON *mx = cJSON_GetObjectItemCaseSensitive(e, "matrix");
  char path[512], sub[560], got[128];
  tt_status st;
  if (tr && mx)
    return tt__jfail(c, TT_ERR_PARSE, mp, "expected either \"transform\" or \"matrix\", not both");
  if (mx) {
    tt__jkey(path, sizeof path, mp, "matrix");
    int n = cJSON_GetArraySize(mx);
    if (!cJSON_IsArray(mx) || (n != 16 && n != 4))
      return tt__jfail(c, TT_ERR_PARSE, path,
                       "expected 16 numbers or 4 rows of 4 (row-major), got %s",
                       tt__jdesc(mx, got, sizeof got));
    if (n == 16) {
      float f[16];
      if ((st = tt__jvec_item(c, mx, path, 16, &tt__any, 0, f)) != TT_OK) return st;
      for (int i = 0; i < 16; i++) m[i] = f[i];
    } else {
      int r = 0;
      for (const cJSON *row = mx->child; row; row = row->next, r++) {
        float f[4];
        tt__jidx(sub, sizeof sub, path, (unsigned)r);
        if ((st = tt__jvec_item(c, row, sub, 4, &tt__any, 0, f)) != TT_OK) return st;
        for (int i = 0; i < 4; i++) m[4 * r + i] = f[i];
      }
    }
    if (m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1)
      return tt__jfail(c, TT_ERR_PARSE, path,
                       "expected an affine matrix (last row 0 0 0 1), got last row %g %g %g %g",
                       m[12], m[13], m[14], m[15]);
    *has = 1;
    return TT_OK;
  }
  if (!tr) return TT_OK;
  tt__jkey(path, sizeof path, mp, "transform");
  if ((st = tt__jobject(c, tr, path)) != TT_OK) return st;
  static const char *const known[] = {"translate", "rotate", "scale", NULL};
  tt__jcheck_keys(c, tr, path, known);
  float t[3] = {0, 0, 0}, s[3] = {1, 1, 1};
  if ((st = tt__jvec(c, tr, "translate", path, 0, 3, &tt__any, 0, t)) != TT_OK) return st;
  if ((st = tt__jvec(c, tr, "scale", path, 0, 3, &tt__any, 1, s)) != TT_OK) return st;
  if (s[0] == 0 || s[1] == 0 || s[2] == 0) {
    tt__jkey(sub, sizeof sub, path, "scale");
    return tt__jfail(c, TT_ERR_PARSE, sub, "expected non-zero scale factors, got %g %g %g", s[0],
                     s[1], s[2]);
  }
  double R[16];
  memcpy(R, id, sizeof id);
  const cJSON *rot = cJSON_GetObjectItemCaseSensitive(tr, "rotate");
  tt__jkey(sub, sizeof sub, path, "rotate");
  if (cJSON_IsArray(rot)) {
    /* Euler angles in degrees, applied about X, then Y, then Z: R = Rz * Ry * Rx */
    float ang[3];
    if ((st = tt__jvec_item(c, rot, sub, 3, &tt__any, 0, ang)) != TT_OK) return st;
    double rx[16], ry[16], rz[16];
    tt__mat_rot(rx, 1, 0, 0, ang[0]);
    tt__mat_rot(ry, 0, 1, 0, ang[1]);
    tt__mat_rot(rz, 0, 0, 1, ang[2]);
    tt__mat4_mul(R, ry, rx);
    tt__mat4_mul(R, rz, R);
  } else if (cJSON_IsObject(rot)) {
    static const char *const rknown[] = {"axis", "angle", NULL};
    tt__jcheck_keys(c, rot, sub, rknown);
    float axis[3];
    double angle;
    if ((st = tt__jvec(c, rot, "axis", sub, 1, 3, &tt__any, 0, axis)) != TT_OK) return st;
    if ((st = tt__jnum(c, rot, "angle", sub, 1, &tt__any, &angle)) != TT_OK) return st;
    double l = tt__len3(axis);
    if (!(l > 0)) {
      char ap[600];
      tt__jkey(ap, sizeof ap, sub, "axis");
      return tt__jfail(c, TT_ERR_PARSE, ap, "expected a non-zero axis");
    }
    tt__mat_rot(R, axis[0] / l, axis[1] / l, axis[2] / l, angle);
  } else if (rot) {
    return tt__jfail(c, TT_ERR_PARSE, sub,
                     "expected Euler angles [x, y, z] in degrees or {\"axis\": [x, y, z], "
                     "\"angle\": degrees}, got %s",
                     tt__jdesc(rot, got, sizeof got));
  }
  double S[16] = {s[0], 0, 0, 0, 0, s[1], 0, 0, 0, 0, s[2], 0, 0, 0, 0, 1};
  double T[16] = {1, 0, 0, t[0], 0, 1, 0, t[1], 0, 0, 1, t[2], 0, 0, 0, 1};
  tt__mat4_mul(m, R, S);
  tt__mat4_mul(m, T, m);
  *has = 1;
  return TT_OK;
}

/* Reads a vertex attribute given either flat ([x,y,z,x,y,z...]) or nested ([[x,y,z],...]);
 * *count receives the number of tuples. */
tt_status tt__jtuples(const tt__jctx *c, const cJSON *arr, const char *path, int dim,
                      const char *what, float **out, uint32_t *count) {
  char got[128], sub[560];
  *out = NULL;
  *count = 0;
  if (!cJSON_IsArray(arr) || !arr->child)
    return tt__jfail(c, TT_ERR_PARSE, path, "expected a non-empty array of %s, got %s", what,
                     tt__jdesc(arr, got, sizeof got));
  int nested = cJSON_IsArray(arr->child);
  size_t n = (size_t)cJSON_GetArraySize(arr);
  size_t tuples = nested ? n : n / dim;
  if (!nested && n % (size_t)dim != 0)
    return tt__jfail(c, TT_ERR_PARSE, path, "expected a multiple of %d numbers (flat %s), got %zu",
                     dim, what, n);
  if (tuples > UINT32_MAX) return tt__jfail(c, TT_ERR_UNSUPPORTED, path, "too many %s", what);
  float *f = malloc(sizeof(float) * dim * tuples);
  if (!f) return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, path, "out of memory");
  size_t i = 0;
  tt_status st = TT_OK;
  for (const cJSON *e = arr->child; e && st == TT_OK; e = e->next, i++) {
    tt__jidx(sub, sizeof sub, path, (unsigned)i);
    if (nested) {
      st = tt__jvec_item(c, e, sub, dim, &tt__any, 0, f + (size_t)dim * i);
    } else {
      double v;
      st = tt__jnum_item(c, e, sub, &tt__any, &v);
      f[i] = (float)v;
    }
  }
  if (st != TT_OK) {
    free(f);
    return st;
  }
  *out = f;
  *count = (uint32_t)tuples;
  return TT_OK;
}

/* Inline geometry; indices are range-checked here because everything downstream trusts
 * them. */
static tt_status tt__jinline(const tt__jctx *c, const cJSON *e, const char *mp, tt__mesh_data *d) {
  char path[512], sub[560], sub2[600], got[128];
  tt_status st;
  tt__jkey(path, sizeof path, mp, "positions");
  if ((st = tt__jtuples(c, cJSON_GetObjectItemCaseSensitive(e, "positions"), path, 3, "positions",
                        &d->positions, &d->vertex_count)) != TT_OK)
    return st;
  uint32_t nv = d->vertex_count;
  const cJSON *idx = cJSON_GetObjectItemCaseSensitive(e, "indices");
  tt__jkey(path, sizeof path, mp, "indices");
  if (!idx) {
    if (nv % 3 != 0)
      return tt__jfail(
          c, TT_ERR_PARSE, path,
          "missing required field (without indices the %u positions must form whole triangles)",
          nv);
    d->triangle_count = nv / 3;
    d->indices = malloc(sizeof(uint32_t) * nv);
    if (!d->indices) return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, path, "out of memory");
    for (uint32_t i = 0; i < nv; i++) d->indices[i] = i;
  } else {
    if (!cJSON_IsArray(idx) || !idx->child)
      return tt__jfail(c, TT_ERR_PARSE, path,
                       "expected a non-empty array of vertex indices, got %s",
                       tt__jdesc(idx, got, sizeof got));
    int nested = cJSON_IsArray(idx->child);
    size_t n = (size_t)cJSON_GetArraySize(idx) * (nested ? 3 : 1);
    if (n % 3 != 0)
      return tt__jfail(c, TT_ERR_PARSE, path,
                       "expected a multiple of 3 indices (whole triangles), got %zu", n);
    if (n / 3 > UINT32_MAX) return tt__jfail(c, TT_ERR_UNSUPPORTED, path, "too many triangles");
    d->triangle_count = (uint32_t)(n / 3);
    d->indices = malloc(sizeof(uint32_t) * n);
    if (!d->indices) return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, path, "out of memory");
    static const tt__range idx_r = {0, 4294967295.0, TT__INT};
    size_t k = 0;
    unsigned i = 0;
    for (const cJSON *it = idx->child; it; it = it->next, i++) {
      tt__jidx(sub, sizeof sub, path, i);
      const cJSON *vals[3] = {it, NULL, NULL};
      int cnt = 1;
      if (nested) {
        if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 3)
          return tt__jfail(c, TT_ERR_PARSE, sub, "expected an array of 3 vertex indices, got %s",
                           tt__jdesc(it, got, sizeof got));
        cnt = 3;
        vals[0] = it->child;
        vals[1] = vals[0]->next;
        vals[2] = vals[1]->next;
      }
      for (int j = 0; j < cnt; j++) {
        if (nested) tt__jidx(sub2, sizeof sub2, sub, (unsigned)j);
        else snprintf(sub2, sizeof sub2, "%s", sub);
        double v;
        if ((st = tt__jnum_item(c, vals[j], sub2, &idx_r, &v)) != TT_OK) return st;
        if (v >= nv)
          return tt__jfail(c, TT_ERR_PARSE, sub2,
                           "index %.0f out of range (the mesh has %u vertices)", v, nv);
        d->indices[k++] = (uint32_t)v;
      }
    }
  }
  const cJSON *nrm = cJSON_GetObjectItemCaseSensitive(e, "normals");
  if (nrm) {
    uint32_t cnt;
    tt__jkey(path, sizeof path, mp, "normals");
    if ((st = tt__jtuples(c, nrm, path, 3, "normals", &d->normals, &cnt)) != TT_OK) return st;
    if (cnt != nv)
      return tt__jfail(c, TT_ERR_PARSE, path, "expected %u normals (one per vertex), got %u", nv,
                       cnt);
    for (uint32_t v = 0; v < nv; v++) {
      float *n = d->normals + 3 * (size_t)v;
      double l = tt__len3(n);
      if (!(l > 0)) {
        tt__jidx(sub, sizeof sub, path, v);
        return tt__jfail(c, TT_ERR_PARSE, sub, "expected a non-zero normal");
      }
      for (int j = 0; j < 3; j++) n[j] = (float)(n[j] / l);
    }
  }
  const cJSON *uv = cJSON_GetObjectItemCaseSensitive(e, "uvs");
  if (uv) {
    uint32_t cnt;
    tt__jkey(path, sizeof path, mp, "uvs");
    if ((st = tt__jtuples(c, uv, path, 2, "uvs", &d->uvs, &cnt)) != TT_OK) return st;
    if (cnt != nv)
      return tt__jfail(c, TT_ERR_PARSE, path, "expected %u uvs (one per vertex), got %u", nv, cnt);
  }
  return TT_OK;
}

/* Applies the mesh transform and rejects meshes that end up degenerate or non-finite. */
static tt_status tt__jfinish_mesh(const tt__jctx *c, const char *mp, tt__mesh_data *d,
                                  const double m[16], int has_tf, uint32_t material) {
  if (has_tf) {
    if (tt__mesh_data_transform(d, m) != TT_OK)
      return tt__jfail(c, TT_ERR_PARSE, mp, "transform is singular (determinant 0)");
    for (size_t i = 0; i < 3 * (size_t)d->vertex_count; i++)
      if (!isfinite(d->positions[i]))
        return tt__jfail(c, TT_ERR_PARSE, mp, "transform produces non-finite positions");
  }
  double area = 0;
  for (uint32_t t = 0; t < d->triangle_count; t++)
    area += tt__triangle_area(d->positions, d->indices, t);
  if (!(area > 0) || !isfinite(area))
    return tt__jfail(c, TT_ERR_PARSE, mp,
                     "mesh \"%s\" has zero area (every triangle is degenerate)",
                     d->name ? d->name : "");
  return tt__scene_add_mesh(c->scene, d, material);
}

/* Appends "name, name, ..." of the scene's materials, for "unknown material" messages. */
static void tt__known_materials(const tt_scene *s, char *buf, size_t n) {
  size_t at = 0;
  buf[0] = '\0';
  for (uint32_t i = 0; i < s->material_count && at + 1 < n; i++) {
    int w = snprintf(buf + at, n - at, "%s%s", i ? ", " : "", s->materials[i].name);
    if (w < 0) break;
    at += (size_t)w;
  }
}

/* One mesh entry: inline arrays or a file through assimp, then the transform. */
static tt_status tt__jmesh(const tt__jctx *c, const cJSON *e, unsigned index) {
  char mp[512], path[560], where[1200];
  tt_status st;
  tt__jidx(mp, sizeof mp, "meshes", index);
  if ((st = tt__jobject(c, e, mp)) != TT_OK) return st;
  static const char *const known[] = {"name",      "material", "positions", "indices",   "normals",
                                      "uvs",       "file",     "split",     "transform", "matrix",
                                      "animation", "morph",    NULL};
  tt__jcheck_keys(c, e, mp, known);
  tt_scene *s = c->scene;
  const char *name = NULL, *mat = NULL, *file = NULL;
  char defname[64];
  snprintf(defname, sizeof defname, "mesh[%u]", index);
  if ((st = tt__jstr(c, e, "name", mp, 0, &name)) != TT_OK) return st;
  if (!name) name = defname;
  if ((st = tt__jstr(c, e, "material", mp, 1, &mat)) != TT_OK) return st;
  uint32_t mi = UINT32_MAX;
  for (uint32_t i = 0; i < s->material_count; i++)
    if (strcmp(s->materials[i].name, mat) == 0) mi = i;
  if (mi == UINT32_MAX) {
    char list[600];
    tt__known_materials(s, list, sizeof list);
    tt__jkey(path, sizeof path, mp, "material");
    return tt__jfail(c, TT_ERR_PARSE, path, "unknown material \"%s\" (known: %s)", mat, list);
  }
  if ((st = tt__jstr(c, e, "file", mp, 0, &file)) != TT_OK) return st;
  const cJSON *pos = cJSON_GetObjectItemCaseSensitive(e, "positions");
  if (file && pos)
    return tt__jfail(c, TT_ERR_PARSE, mp, "expected either \"file\" or \"positions\", not both");
  if (!file && !pos) {
    tt__jkey(path, sizeof path, mp, "positions");
    return tt__jfail(c, TT_ERR_PARSE, path,
                     "missing required field (expected inline positions or a \"file\")");
  }
  double m[16];
  int has_tf = 0;
  if ((st = tt__jtransform(c, e, mp, m, &has_tf)) != TT_OK) return st;
  const uint32_t first = s->mesh_count;
  if (pos) {
    tt__mesh_data d;
    memset(&d, 0, sizeof d);
    st = tt__jinline(c, e, mp, &d);
    if (st == TT_OK) {
      d.name = tt__strdup(name);
      if (!d.name) st = tt__jfail(c, TT_ERR_OUT_OF_MEMORY, mp, "out of memory");
    }
    if (st == TT_OK) st = tt__jfinish_mesh(c, mp, &d, m, has_tf, mi);
    tt__mesh_data_free(&d);
    if (st == TT_OK) st = tt__janim_attach(c, e, mp, first, s->mesh_count - first, m, has_tf);
    return st;
  }
  int split = 0;
  if ((st = tt__jbool(c, e, "split", mp, &split)) != TT_OK) return st;
  if (cJSON_GetObjectItemCaseSensitive(e, "indices") ||
      cJSON_GetObjectItemCaseSensitive(e, "normals") || cJSON_GetObjectItemCaseSensitive(e, "uvs"))
    tt__jwarn(c, mp, "indices/normals/uvs are ignored for a mesh loaded from \"file\"");
  char *full = tt__resolve(c, file);
  if (!full) return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, mp, "out of memory");
  snprintf(where, sizeof where, "%s: %s.file", c->src, mp);
  tt__mesh_data *parts = NULL;
  uint32_t np = 0;
  st = tt__mesh_import(full, name, split, where, &parts, &np);
  free(full);
  if (st == TT_OK) st = tt__janim_check(c, e, mp, np);
  for (uint32_t i = 0; i < np; i++) {
    if (st == TT_OK) st = tt__jfinish_mesh(c, mp, &parts[i], m, has_tf, mi);
    tt__mesh_data_free(&parts[i]);
  }
  free(parts);
  if (st == TT_OK) st = tt__janim_attach(c, e, mp, first, s->mesh_count - first, m, has_tf);
  return st;
}

/* The non-empty meshes array. */
static tt_status tt__jmeshes(const tt__jctx *c, const cJSON *root, int imported) {
  const cJSON *ms = cJSON_GetObjectItemCaseSensitive(root, "meshes");
  char got[128];
  if (!ms && imported) return TT_OK;
  if (!ms)
    return tt__jfail(c, TT_ERR_PARSE, "meshes",
                     "missing required field (expected a non-empty array of meshes)");
  if (imported && !cJSON_IsArray(ms))
    return tt__jfail(c, TT_ERR_PARSE, "meshes", "expected an array of meshes, got %s",
                     tt__jdesc(ms, got, sizeof got));
  if (!cJSON_IsArray(ms) || (!ms->child && !imported))
    return tt__jfail(c, TT_ERR_PARSE, "meshes", "expected a non-empty array of meshes, got %s",
                     tt__jdesc(ms, got, sizeof got));
  unsigned i = 0;
  for (const cJSON *e = ms->child; e; e = e->next, i++) {
    tt_status st = tt__jmesh(c, e, i);
    if (st != TT_OK) return st;
  }
  return TT_OK;
}

/* ---- lights ---------------------------------------------------------------------------- */

/* Normalises a direction in place; 0 if it has no length. */
static int tt__normalize3(float v[3]) {
  double l = tt__len3(v);
  if (!(l > 0) || !isfinite(l)) return 0;
  for (int i = 0; i < 3; i++) v[i] = (float)(v[i] / l);
  return 1;
}

/* One explicit light (area lights come from emissive materials, not from here). */
static tt_status tt__jlight(const tt__jctx *c, const cJSON *e, unsigned index, int *env_seen) {
  char lp[512], path[560];
  tt_status st;
  tt__jidx(lp, sizeof lp, "lights", index);
  if ((st = tt__jobject(c, e, lp)) != TT_OK) return st;
  const char *type = NULL;
  if ((st = tt__jstr(c, e, "type", lp, 1, &type)) != TT_OK) return st;
  tt_light l;
  memset(&l, 0, sizeof l);
  l.struct_size = sizeof l;
  static const tt__range angle_r = {0, 90, TT__LO_OPEN}, inner_r = {0, 90, 0};
  if (strcmp(type, "environment") == 0) {
    static const char *const known[] = {"type", "radiance", "image", NULL};
    tt__jcheck_keys(c, e, lp, known);
    if (*env_seen)
      return tt__jfail(c, TT_ERR_PARSE, lp, "only one environment light is allowed%s",
                       *env_seen > 1 ? " (the imported scene has one)" : "");
    *env_seen = 1;
    l.type = TT_LIGHT_ENV_CONSTANT;
    l.radiance[0] = l.radiance[1] = l.radiance[2] = 1.0f;
    if ((st = tt__jvec(c, e, "radiance", lp, 0, 3, &tt__nonneg, 1, l.radiance)) != TT_OK) return st;
    const char *img = NULL;
    if ((st = tt__jstr(c, e, "image", lp, 0, &img)) != TT_OK) return st;
    if (img) {
      char *full = tt__resolve(c, img);
      if (!full) return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, lp, "out of memory");
      tt__jkey(path, sizeof path, lp, "image");
      if (tt__file_exists(full)) {
        l.type = TT_LIGHT_ENV_IMAGE;
        l.image = full;
      } else {
        tt__jwarn(c, path, "environment image \"%s\" not found, using a constant environment",
                  full);
        free(full);
      }
    }
  } else if (strcmp(type, "point") == 0 || strcmp(type, "spot") == 0) {
    int spot = type[0] == 's';
    static const char *const pknown[] = {"type", "position", "intensity", NULL};
    static const char *const sknown[] = {"type",   "position", "intensity",  "direction",
                                         "target", "angle",    "innerAngle", NULL};
    tt__jcheck_keys(c, e, lp, spot ? sknown : pknown);
    l.type = spot ? TT_LIGHT_SPOT : TT_LIGHT_POINT;
    if ((st = tt__jvec(c, e, "position", lp, 1, 3, &tt__any, 0, l.position)) != TT_OK) return st;
    if ((st = tt__jvec(c, e, "intensity", lp, 1, 3, &tt__nonneg, 1, l.radiance)) != TT_OK)
      return st;
    if (spot) {
      int has_dir = cJSON_GetObjectItemCaseSensitive(e, "direction") != NULL;
      int has_tgt = cJSON_GetObjectItemCaseSensitive(e, "target") != NULL;
      if (has_dir == has_tgt)
        return tt__jfail(c, TT_ERR_PARSE, lp,
                         "expected exactly one of \"direction\" or \"target\"");
      if (has_dir) {
        if ((st = tt__jvec(c, e, "direction", lp, 1, 3, &tt__any, 0, l.direction)) != TT_OK)
          return st;
        tt__jkey(path, sizeof path, lp, "direction");
      } else {
        float t[3];
        if ((st = tt__jvec(c, e, "target", lp, 1, 3, &tt__any, 0, t)) != TT_OK) return st;
        for (int i = 0; i < 3; i++) l.direction[i] = t[i] - l.position[i];
        tt__jkey(path, sizeof path, lp, "target");
      }
      if (!tt__normalize3(l.direction))
        return tt__jfail(c, TT_ERR_PARSE, path, "expected a non-zero direction");
      double outer = 30.0, inner;
      if ((st = tt__jnum(c, e, "angle", lp, 0, &angle_r, &outer)) != TT_OK) return st;
      inner = 0.75 * outer;
      if ((st = tt__jnum(c, e, "innerAngle", lp, 0, &inner_r, &inner)) != TT_OK) return st;
      if (inner > outer) {
        tt__jkey(path, sizeof path, lp, "innerAngle");
        return tt__jfail(c, TT_ERR_PARSE, path, "expected at most angle (%g), got %g", outer,
                         inner);
      }
      l.cos_outer = (float)cos(outer * TT__PI / 180.0);
      l.cos_inner = (float)cos(inner * TT__PI / 180.0);
    }
  } else if (strcmp(type, "distant") == 0) {
    static const char *const known[] = {"type", "direction", "irradiance", NULL};
    tt__jcheck_keys(c, e, lp, known);
    l.type = TT_LIGHT_DISTANT;
    if ((st = tt__jvec(c, e, "direction", lp, 1, 3, &tt__any, 0, l.direction)) != TT_OK) return st;
    if (!tt__normalize3(l.direction)) {
      tt__jkey(path, sizeof path, lp, "direction");
      return tt__jfail(c, TT_ERR_PARSE, path, "expected a non-zero direction");
    }
    if ((st = tt__jvec(c, e, "irradiance", lp, 1, 3, &tt__nonneg, 1, l.radiance)) != TT_OK)
      return st;
  } else {
    tt__jkey(path, sizeof path, lp, "type");
    return tt__jfail(c, TT_ERR_PARSE, path,
                     "unknown light type \"%s\" (expected environment, point, spot or distant; "
                     "area lights come from materials with emission)",
                     type);
  }
  tt_scene *s = c->scene;
  tt_light *slot =
      tt__scene_push((void **)&s->lights, &s->light_count, &s->light_cap, sizeof *slot);
  if (!slot) {
    free((void *)l.image);
    return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, lp, "out of memory");
  }
  *slot = l;
  return TT_OK;
}

/* The optional lights array. */
static tt_status tt__jlights(const tt__jctx *c, const cJSON *root) {
  const cJSON *ls = cJSON_GetObjectItemCaseSensitive(root, "lights");
  char got[128];
  if (!ls) return TT_OK;
  if (!cJSON_IsArray(ls))
    return tt__jfail(c, TT_ERR_PARSE, "lights", "expected an array of lights, got %s",
                     tt__jdesc(ls, got, sizeof got));
  int env = 0; /* 2: the imported scene's environment light */
  for (uint32_t i = 0; i < c->scene->light_count; i++)
    if (c->scene->lights[i].type == TT_LIGHT_ENV_CONSTANT ||
        c->scene->lights[i].type == TT_LIGHT_ENV_IMAGE)
      env = 2;
  unsigned i = 0;
  for (const cJSON *e = ls->child; e; e = e->next, i++) {
    tt_status st = tt__jlight(c, e, i, &env);
    if (st != TT_OK) return st;
  }
  return TT_OK;
}

/* ---- import ---------------------------------------------------------------------------- */

static tt_status tt__load_json(const char *json, size_t length, const char *source,
                               const char *base_dir, int depth, tt_scene **out);

/* Reads a scene.json file and loads it with its own directory as the asset base. */
tt_status tt__scene_load_json_file(const char *path, int depth, tt_scene **out) {
  char *buf = NULL;
  size_t len = 0;
  tt_status st = tt__read_file(path, &buf, &len);
  if (st != TT_OK) return st;
  char *dir = tt__strdup(path);
  if (!dir) {
    free(buf);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
  }
  char *slash = strrchr(dir, '/');
  if (slash == dir) slash[1] = '\0';
  else if (slash) *slash = '\0';
  else strcpy(dir, ".");
  st = tt__load_json(buf, len, path, dir, depth, out);
  free(dir);
  free(buf);
  return st;
}

/* Removes the area lights of an imported scene (they are implied by emissive materials and
 * recreated by tt__scene_finish once this file's meshes are appended), so the light order
 * stays "explicit lights, then area lights in mesh order". */
static void tt__strip_area_lights(tt_scene *s) {
  uint32_t w = 0;
  for (uint32_t i = 0; i < s->light_count; i++)
    if (s->lights[i].type != TT_LIGHT_AREA) s->lights[w++] = s->lights[i];
  s->light_count = w;
  for (uint32_t i = 0; i < s->mesh_count; i++) s->meshes[i].light = -1;
}

/* The optional top-level "import": loads the wrapped scene into *out (NULL when absent).
 * Only one level: a scene.json that is imported may not import again, which also rules
 * out cycles. Errors name this file, the field and the imported file. */
static tt_status tt__jimport(const tt__jctx *c, const cJSON *root, int depth, tt_scene **out) {
  *out = NULL;
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(root, "import");
  if (!it) return TT_OK;
  const char *rel = NULL;
  tt_status st = tt__jstr(c, root, "import", "", 1, &rel);
  if (st != TT_OK) return st;
  if (depth > 0)
    return tt__jfail(c, TT_ERR_PARSE, "import",
                     "\"%s\" not loaded: this file is itself imported by a scene.json, and imports "
                     "cannot be nested (import the scene directly)",
                     rel);
  int pbrt = tt__has_ext(rel, ".pbrt"), json = tt__has_ext(rel, ".json");
  int gltf = tt__has_ext(rel, ".gltf") || tt__has_ext(rel, ".glb");
  if (!pbrt && !json && !gltf)
    return tt__jfail(c, TT_ERR_UNSUPPORTED, "import",
                     "unsupported scene format \"%s\" (expected .pbrt, .json, .gltf or .glb)", rel);
  char *full = tt__resolve(c, rel);
  if (!full) return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, "import", "out of memory");
  char why[256];
  if (tt__file_regular_reason(full, why, sizeof why) != 0) {
    st = tt__jfail(c, TT_ERR_IO, "import", "cannot open scene file \"%s\": %s", full, why);
    free(full);
    return st;
  }
  /* the canonical path makes the scene (its texture paths, hence tt_scene_id) independent of
   * how the wrapper was reached: scenes/x/../../../shared/... and /abs/shared/... agree */
  char *real = realpath(full, NULL);
  if (real) {
    free(full);
    full = real;
  }
  if (json) {
    /* a file importing itself would otherwise be reported as a nested import */
    char *a = realpath(full, NULL), *b = realpath(c->src, NULL);
    int self = a && b && strcmp(a, b) == 0;
    free(a);
    free(b);
    if (self) {
      st = tt__jfail(c, TT_ERR_PARSE, "import",
                     "\"%s\" is this file (a scene cannot import itself)", full);
      free(full);
      return st;
    }
  }
  tt_scene *s = NULL;
  st = pbrt   ? tt__scene_load_pbrt(full, &s)
       : gltf ? tt__scene_load_gltf(full, 1, &s)
              : tt__scene_load_json_file(full, depth + 1, &s);
  if (st != TT_OK) {
    /* keep the imported loader's message (file:line or JSON path) behind ours */
    char inner[1024];
    snprintf(inner, sizeof inner, "%s", tt_last_error());
    st = tt__jfail(c, st, "import", "%s", inner);
    free(full);
    return st;
  }
  free(full);
  char *src = tt__strdup(c->src);
  if (!src) {
    tt_scene_destroy(s);
    return tt__jfail(c, TT_ERR_OUT_OF_MEMORY, "import", "out of memory");
  }
  free(s->source);
  s->source = src;
  tt__strip_area_lights(s);
  *out = s;
  return TT_OK;
}

/* ---- entry point ----------------------------------------------------------------------- */

/* Parses, validates section by section, then finishes (area lights, bounds, id). */
tt_status tt_scene_load_json(const char *json, size_t length, const char *source,
                             const char *base_dir, tt_scene **out) {
  return tt__load_json(json, length, source, base_dir, 0, out);
}

/* depth: 0 for the scene being loaded, 1 for a scene.json imported by it. */
static tt_status tt__load_json(const char *json, size_t length, const char *source,
                               const char *base_dir, int depth, tt_scene **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_scene_load_json: out is NULL");
  *out = NULL;
  if (!source) source = "(memory)";
  if (!json) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "%s: no JSON text given", source);
  const char *nul = memchr(json, '\0', length);
  if (nul) {
    unsigned line, col;
    tt__json_line_col(json, (size_t)(nul - json), &line, &col);
    return tt_set_error(TT_ERR_PARSE, "%s:%u:%u: JSON syntax error: unexpected NUL byte", source,
                        line, col);
  }
  /* a private NUL-terminated copy lets cJSON insist that nothing follows the value */
  char *text = malloc(length + 1);
  if (!text) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", source);
  memcpy(text, json, length);
  text[length] = '\0';
  size_t skip = (length >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) ? 3 : 0; /* UTF-8 BOM */
  const char *end = NULL;
  cJSON *root = cJSON_ParseWithLengthOpts(text + skip, length - skip + 1, &end, 1);
  if (!root) {
    size_t at = end && end >= text + skip ? (size_t)(end - text) : length;
    if (at > length) at = length;
    unsigned line, col;
    tt__json_line_col(text, at, &line, &col);
    char near[24];
    size_t k = 0;
    for (size_t i = at; i < length && k + 1 < sizeof near && text[i] != '\n'; i++)
      near[k++] = text[i];
    near[k] = '\0';
    tt_status st =
        k ? tt_set_error(TT_ERR_PARSE, "%s:%u:%u: JSON syntax error near \"%s\"", source, line, col,
                         near)
          : tt_set_error(TT_ERR_PARSE, "%s:%u:%u: JSON syntax error (unexpected end of input)",
                         source, line, col);
    free(text);
    return st;
  }
  free(text);

  tt__jctx c = {source, base_dir, NULL};
  tt_status st = TT_OK;
  char got[128];
  if (!cJSON_IsObject(root)) {
    st = tt_set_error(TT_ERR_PARSE, "%s: expected a JSON object at the top level, got %s", source,
                      tt__jdesc(root, got, sizeof got));
    cJSON_Delete(root);
    return st;
  }
  static const char *const known[] = {"version", "import", "camera", "render", "materials",
                                      "meshes",  "lights", "stress", NULL};
  tt__jcheck_keys(&c, root, "", known);
  const cJSON *ver = cJSON_GetObjectItemCaseSensitive(root, "version");
  if (!ver) st = tt__jfail(&c, TT_ERR_PARSE, "version", "missing required field (expected 1)");
  else if (!cJSON_IsNumber(ver))
    st = tt__jfail(&c, TT_ERR_PARSE, "version", "expected the number 1, got %s",
                   tt__jdesc(ver, got, sizeof got));
  else if (ver->valuedouble != 1.0)
    st = tt__jfail(&c, TT_ERR_UNSUPPORTED, "version", "unsupported version %g (expected 1)",
                   ver->valuedouble);
  tt_scene *imported = NULL;
  if (st == TT_OK) st = tt__jimport(&c, root, depth, &imported);
  if (st != TT_OK) {
    cJSON_Delete(root);
    return st;
  }
  int imp = imported != NULL;
  c.scene = imp ? imported : tt__scene_new(source);
  if (!c.scene) {
    cJSON_Delete(root);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", source);
  }
  st = tt__jrender(&c, root);
  if (st == TT_OK) st = tt__jcamera(&c, root, imp);
  if (st == TT_OK) st = tt__jmaterials(&c, root, imp);
  if (st == TT_OK) st = tt__jmeshes(&c, root, imp);
  if (st == TT_OK) st = tt__jlights(&c, root);
  if (st == TT_OK) st = tt__janim_check_range(&c, root);
  if (st == TT_OK) st = tt__jstress(&c, root);
  if (st == TT_OK) st = tt__scene_finish(c.scene);
  cJSON_Delete(root);
  if (st != TT_OK) {
    tt_scene_destroy(c.scene);
    return st;
  }
  *out = c.scene;
  return TT_OK;
}
