/* scene.json reading shared by the loader's files (scene_json.c: the sections;
 * scene_json_anim.c: mesh animation): the loader context and the typed getters, each of
 * which reports "<source>: <json path>: <what was expected>, got ...". Internal to io/. */
#ifndef TT_IO_SCENE_JSON_INTERNAL_H
#define TT_IO_SCENE_JSON_INTERNAL_H

#include "scene/scene_internal.h"
#include "util/json_error.h"

#include <cjson/cJSON.h>

/* Loader state: where messages point and where relative assets are resolved. */
typedef struct tt__jctx {
  const char *src;
  const char *base; /* NULL: relative to the current directory */
  tt_scene *scene;
} tt__jctx;

/* Range of an accepted number; flags select open ends and integers. */
typedef struct tt__range {
  double lo, hi;
  unsigned flags;
} tt__range;
#define TT__LO_OPEN 1u
#define TT__HI_OPEN 2u
#define TT__INT 4u

extern const tt__range tt__any;    /* any finite number */
extern const tt__range tt__nonneg; /* [0, inf) */

/* One place formats "<source>: <path>: <message>" so all errors look alike
 * (util/json_error.c, shared with the parameter-space reader). */
#define tt__jfail(c, st, path, ...) tt__json_error((st), (c)->src, (path), __VA_ARGS__)

/* A warning through the log host: the scene still loads. */
void tt__jwarn(const tt__jctx *c, const char *path, const char *fmt, ...) TT_PRINTF(3, 4);
/* "camera" + "fov" -> "camera.fov". */
void tt__jkey(char *buf, size_t n, const char *prefix, const char *key);
/* "meshes" + 2 -> "meshes[2]". */
void tt__jidx(char *buf, size_t n, const char *prefix, unsigned i);
/* Describes a JSON value for "got ...". */
const char *tt__jdesc(const cJSON *it, char *buf, size_t n);
/* Warns about keys outside the NULL-terminated `known` (keys starting with '_' are
 * comments). */
void tt__jcheck_keys(const tt__jctx *c, const cJSON *obj, const char *prefix,
                     const char *const *known);
/* A finite number inside `r`. */
tt_status tt__jnum_item(const tt__jctx *c, const cJSON *it, const char *path, const tt__range *r,
                        double *out);
/* Optional/required number under `key`; *out untouched when absent and optional. */
tt_status tt__jnum(const tt__jctx *c, const cJSON *obj, const char *key, const char *prefix,
                   int required, const tt__range *r, double *out);
/* An array of exactly n numbers (one number fills all n with allow_scalar). */
tt_status tt__jvec_item(const tt__jctx *c, const cJSON *it, const char *path, int n,
                        const tt__range *r, int allow_scalar, float *out);
/* Optional/required n-vector under `key`. */
tt_status tt__jvec(const tt__jctx *c, const cJSON *obj, const char *key, const char *prefix,
                   int required, int n, const tt__range *r, int allow_scalar, float *out);
/* Optional/required non-empty string under `key` (points into the JSON tree). */
tt_status tt__jstr(const tt__jctx *c, const cJSON *obj, const char *key, const char *prefix,
                   int required, const char **out);
/* Optional boolean under `key`. */
tt_status tt__jbool(const tt__jctx *c, const cJSON *obj, const char *key, const char *prefix,
                    int *out);
/* TT_OK if `it` is an object. */
tt_status tt__jobject(const tt__jctx *c, const cJSON *it, const char *path);
/* Vertex attribute tuples given flat or nested; *count tuples into a malloc'ed *out. */
tt_status tt__jtuples(const tt__jctx *c, const cJSON *arr, const char *path, int dim,
                      const char *what, float **out, uint32_t *count);
/* Rotation about a unit axis by `deg` degrees (row-major 4x4). */
void tt__mat_rot(double r[16], double x, double y, double z, double deg);
/* Length of a 3-vector. */
double tt__len3(const float v[3]);

/* ---- mesh animation (scene_json_anim.c) ---- */

/* What a mesh entry's "animation" and "morph" hold, read before the mesh is added. */
typedef struct tt__janim {
  const cJSON *animation, *morph; /* NULL when absent */
} tt__janim;

/* Validates the shape of "animation" and "morph" of mesh entry `e` (path `mp`) that made
 * `parts` scene meshes (morph needs exactly one, of `vertex_count` vertices). */
tt_status tt__janim_check(const tt__jctx *c, const cJSON *e, const char *mp, uint32_t parts);

/* Attaches the entry's animation to the scene meshes [first, first + count) just added:
 * the rigid keys become one node placing them all, the morph targets (in the entry's
 * object space, placed by its static matrix m when has_tf) the mesh's targets. */
tt_status tt__janim_attach(const tt__jctx *c, const cJSON *e, const char *mp, uint32_t first,
                           uint32_t count, const double m[16], int has_tf);

/* Checks that every animation key lies inside the camera path's time range (the sequence
 * the scene describes), naming the first key beyond it, or "import" when the imported
 * scene's animation runs beyond it. */
tt_status tt__janim_check_range(const tt__jctx *c, const cJSON *root);

/* ---- stress options (scene_json_stress.c) ---- */

/* The top-level "stress" object: "cylinder" adds the thesis' rotating thin cylinder (sized
 * and centred by the meshes loaded so far) as a rigid animated mesh. */
tt_status tt__jstress(const tt__jctx *c, const cJSON *root);

#endif /* TT_IO_SCENE_JSON_INTERNAL_H */
