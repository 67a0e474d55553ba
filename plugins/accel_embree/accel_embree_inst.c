/* accel_embree: updateMethod=instances, the two-level update of an animated scene (native
 * backend).
 *
 * Every rigid mesh (tt_mesh.motion TT_MESH_RIGID) gets a BVH of its own, built once over its
 * object-space positions with the tuned quality and flags, and enters the top-level scene as
 * an Embree instance (RTC_GEOMETRY_TYPE_INSTANCE) whose transform is the mesh's
 * object-to-world matrix. The still meshes share one more BVH, built once, and the deforming
 * meshes one Embree dynamic scene in which each has its own BVH refitted on commit
 * (RTC_BUILD_QUALITY_REFIT, as updateMethod=refit); both enter the top level as instances
 * with the identity transform. An update sets the moved instances' transforms, refits the
 * deforming meshes that changed, and rebuilds the top level only: its BVH is over a handful
 * of instance boxes, not over triangles.
 *
 * Embree intersects an instance's triangles in its object space (the ray is transformed),
 * so t, u and v of a hit on a rigid mesh are those of the world-space triangle up to
 * rounding, and Embree reports its normal in object space: the hit's normal is brought back
 * here with the cofactor matrix of the transform (cross(A a, A b) = cof(A) cross(a, b)), the
 * unnormalised normal a flat build reports for the world-space triangle, up to rounding.
 * Hits on still and deforming meshes (identity instances) are the flat build's. */
#include "accel_embree.h"

#include <embree3/rtcore.h>

#include <stdlib.h>
#include <string.h>

/* What an instance of the top level holds. */
typedef enum tt__embree_inst_kind {
  TT__EMBREE_INST_STILL = 0,  /* every still mesh, identity */
  TT__EMBREE_INST_DEFORM = 1, /* every deforming mesh, identity, refitted per update */
  TT__EMBREE_INST_RIGID = 2   /* one rigid mesh, placed by its transform */
} tt__embree_inst_kind;

typedef struct tt__embree_inst_obj {
  int kind;          /* a tt__embree_inst_kind */
  uint32_t mesh;     /* TT__EMBREE_INST_RIGID: the mesh's index */
  RTCScene sub;      /* the instanced scene (owned) */
  RTCGeometry inst;  /* the instance geometry in the top level (the top level owns it) */
  uint64_t revision; /* rigid: the mesh revision its transform comes from */
  float cof[9];      /* rigid: row-major cofactor matrix of the transform's linear part */
} tt__embree_inst_obj;

struct tt__embree_inst {
  const tt_scene *scene;
  RTCScene top;
  uint32_t count; /* instances; instance i has instID i */
  tt__embree_inst_obj *obj;
  /* deforming meshes: each one's Embree vertex buffer (NULL for others) and revision */
  float **vbuf;
  uint64_t *vrev;
  uint32_t deform; /* index of the deforming instance, or UINT32_MAX */
};

/* Rigid meshes need their object-space positions; one without them deforms for us. */
static int tt__embree_inst_rigid(const tt_mesh *m) {
  return TT_HAS_FIELD(tt_mesh, m, object_positions) && m->motion == TT_MESH_RIGID &&
         m->object_positions;
}

/* Cofactor matrix of the 3x3 linear part of a row-major 3x4 transform: columns a1 x a2,
 * a2 x a0, a0 x a1 of A's columns a0, a1, a2, computed in double. */
static void tt__embree_inst_cofactor(const float x[12], float cof[9]) {
  double a[3][3];
  for (int r = 0; r < 3; r++)
    for (int c = 0; c < 3; c++) a[c][r] = x[4 * r + c]; /* a[c] = column c */
  for (int c = 0; c < 3; c++) {
    const double *p = a[(c + 1) % 3], *q = a[(c + 2) % 3];
    cof[0 * 3 + c] = (float)(p[1] * q[2] - p[2] * q[1]);
    cof[1 * 3 + c] = (float)(p[2] * q[0] - p[0] * q[2]);
    cof[2 * 3 + c] = (float)(p[0] * q[1] - p[1] * q[0]);
  }
}

/* A new scene with the tuned flags (`dynamic` adds RTC_SCENE_FLAG_DYNAMIC). */
static RTCScene tt__embree_inst_scene(const tt__embree_settings *st, int quality, int dynamic) {
  RTCScene s = rtcNewScene(tt__embree_device());
  if (!s) return NULL;
  int flags = RTC_SCENE_FLAG_NONE;
  if (!st->is_static || dynamic) flags |= RTC_SCENE_FLAG_DYNAMIC;
  if (st->compact) flags |= RTC_SCENE_FLAG_COMPACT;
  if (st->robust) flags |= RTC_SCENE_FLAG_ROBUST;
  rtcSetSceneFlags(s, (enum RTCSceneFlags)flags);
  rtcSetSceneBuildQuality(s, (enum RTCBuildQuality)quality);
  return s;
}

void tt__embree_inst_free(tt__embree_inst *in) {
  if (!in) return;
  if (in->top) rtcReleaseScene(in->top); /* releases the instance geometries */
  for (uint32_t i = 0; in->obj && i < in->count; i++)
    if (in->obj[i].sub) rtcReleaseScene(in->obj[i].sub);
  free(in->obj);
  free(in->vbuf);
  free(in->vrev);
  free(in);
}

/* Adds instance `i` of `sub` (committed) to the top level. */
static tt_status tt__embree_inst_add(tt__embree_inst *in, uint32_t i, const float xfm[12]) {
  RTCGeometry g = rtcNewGeometry(tt__embree_device(), RTC_GEOMETRY_TYPE_INSTANCE);
  if (!g) return tt__embree_status("rtcNewGeometry (instance)");
  rtcSetGeometryInstancedScene(g, in->obj[i].sub);
  rtcSetGeometryTimeStepCount(g, 1);
  rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, xfm);
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(in->top, g, i);
  rtcReleaseGeometry(g);
  in->obj[i].inst = g; /* alive as long as the top level holds it */
  return tt__embree_status("attaching an instance");
}

tt_status tt__embree_inst_build(const tt_scene *scene, const tt__embree_settings *st, int quality,
                                tt__embree_inst **out, RTCScene *top) {
  static const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  *out = NULL;
  *top = NULL;
  const uint32_t meshes = tt_scene_mesh_count(scene);
  tt__embree_inst *in = calloc(1, sizeof *in);
  if (!in) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "accel_embree: out of memory");
  in->scene = scene;
  in->deform = UINT32_MAX;
  in->obj = calloc((size_t)meshes + 2, sizeof *in->obj);
  in->vbuf = calloc(meshes, sizeof *in->vbuf);
  in->vrev = calloc(meshes, sizeof *in->vrev);
  in->top = tt__embree_inst_scene(st, quality, 0);
  tt_status s = TT_OK;
  if (!in->obj || !in->vbuf || !in->vrev)
    s = tt_set_error(TT_ERR_OUT_OF_MEMORY, "accel_embree: out of memory");
  else if (!in->top) s = tt__embree_status("rtcNewScene (instances, top level)");
  /* The still meshes, then the deforming ones, each group one instance (if it has any). */
  for (int kind = TT__EMBREE_INST_STILL; s == TT_OK && kind <= TT__EMBREE_INST_DEFORM; kind++) {
    RTCScene sub = NULL;
    for (uint32_t i = 0; s == TT_OK && i < meshes; i++) {
      const tt_mesh *m = tt_scene_mesh(scene, i);
      if (m->triangle_count == 0 || tt__embree_inst_rigid(m)) continue;
      const int deforms = tt__embree_mesh_moves(m);
      if (deforms != (kind == TT__EMBREE_INST_DEFORM)) continue;
      if (!sub) {
        sub = tt__embree_inst_scene(st, quality, deforms);
        if (!sub) {
          s = tt__embree_status("rtcNewScene (instances)");
          break;
        }
        in->obj[in->count].kind = kind;
        in->obj[in->count].sub = sub;
        in->count++;
      }
      s = tt__embree_attach_mesh(sub, m, m->positions, i,
                                 deforms ? RTC_BUILD_QUALITY_REFIT : quality,
                                 deforms ? &in->vbuf[i] : NULL);
      in->vrev[i] = m->revision;
    }
    if (s == TT_OK && sub) {
      rtcCommitScene(sub);
      s = tt__embree_status("rtcCommitScene (instanced meshes)");
      if (kind == TT__EMBREE_INST_DEFORM) in->deform = in->count - 1;
      if (s == TT_OK) s = tt__embree_inst_add(in, in->count - 1, identity);
    }
  }
  /* One instance per rigid mesh, over its object-space positions. */
  for (uint32_t i = 0; s == TT_OK && i < meshes; i++) {
    const tt_mesh *m = tt_scene_mesh(scene, i);
    if (m->triangle_count == 0 || !tt__embree_inst_rigid(m)) continue;
    tt__embree_inst_obj *o = &in->obj[in->count];
    o->kind = TT__EMBREE_INST_RIGID;
    o->mesh = i;
    o->revision = m->revision;
    tt__embree_inst_cofactor(m->transform, o->cof);
    o->sub = tt__embree_inst_scene(st, quality, 0);
    if (!o->sub) {
      s = tt__embree_status("rtcNewScene (instance)");
      break;
    }
    in->count++;
    s = tt__embree_attach_mesh(o->sub, m, m->object_positions, i, quality, NULL);
    if (s != TT_OK) break;
    rtcCommitScene(o->sub);
    s = tt__embree_status("rtcCommitScene (instance)");
    if (s == TT_OK) s = tt__embree_inst_add(in, in->count - 1, m->transform);
  }
  if (s == TT_OK) {
    rtcCommitScene(in->top);
    s = tt__embree_status("rtcCommitScene (instances, top level)");
  }
  if (s != TT_OK) {
    tt__embree_inst_free(in);
    return s;
  }
  *out = in;
  *top = in->top;
  return TT_OK;
}

tt_status tt__embree_inst_update(tt__embree_inst *in) {
  const tt_scene *scene = in->scene;
  for (uint32_t k = 0; k < in->count; k++) {
    tt__embree_inst_obj *o = &in->obj[k];
    if (o->kind == TT__EMBREE_INST_RIGID) {
      const tt_mesh *m = tt_scene_mesh(scene, o->mesh);
      if (m->revision == o->revision) continue;
      rtcSetGeometryTransform(o->inst, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, m->transform);
      rtcCommitGeometry(o->inst);
      tt__embree_inst_cofactor(m->transform, o->cof);
      o->revision = m->revision;
    } else if (o->kind == TT__EMBREE_INST_DEFORM) {
      int changed = 0;
      const uint32_t meshes = tt_scene_mesh_count(scene);
      for (uint32_t i = 0; i < meshes; i++) {
        const tt_mesh *m = tt_scene_mesh(scene, i);
        if (!in->vbuf[i] || m->revision == in->vrev[i]) continue;
        memcpy(in->vbuf[i], m->positions, (size_t)m->vertex_count * 3 * sizeof(float));
        RTCGeometry g = rtcGetGeometry(o->sub, i);
        rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(g);
        in->vrev[i] = m->revision;
        changed = 1;
      }
      if (!changed) continue;
      rtcCommitScene(o->sub); /* refits the changed meshes' BVHs */
      tt_status s = tt__embree_status("rtcCommitScene (deforming meshes)");
      if (s != TT_OK) return s;
      rtcCommitGeometry(o->inst); /* its bounds changed: the top level must see it */
    }
  }
  rtcCommitScene(in->top);
  return tt__embree_status("rtcCommitScene (instances, top level)");
}

void tt__embree_inst_normal(const tt__embree_inst *in, uint32_t inst_id, float ng[3]) {
  if (inst_id >= in->count || in->obj[inst_id].kind != TT__EMBREE_INST_RIGID) return;
  const float *c = in->obj[inst_id].cof, n[3] = {ng[0], ng[1], ng[2]};
  for (int r = 0; r < 3; r++) ng[r] = c[3 * r] * n[0] + c[3 * r + 1] * n[1] + c[3 * r + 2] * n[2];
}

uint32_t tt__embree_inst_count(const tt__embree_inst *in) { return in ? in->count : 0; }
