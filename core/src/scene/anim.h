/* Scene animation (internal): keyframe tracks, the node hierarchy that places rigid meshes,
 * and the per-mesh animation (rigid placement, morph targets, skinning) that
 * tt_scene_set_time poses. Loaders (scene.json, glTF through assimp, pbrt-v4) fill it
 * through the builders below; tt__scene_finish poses the scene at the start of its time
 * range. Not part of the public ABI. */
#ifndef TT_SCENE_ANIM_H
#define TT_SCENE_ANIM_H

#include <tunetrace/scene.h>

#include <stdint.h>

/* How values between two keys are found. */
typedef enum tt__interp {
  TT__INTERP_STEP = 0,   /* the earlier key's value */
  TT__INTERP_LINEAR = 1, /* linear; rotations: slerp along the shorter arc */
  TT__INTERP_CUBIC = 2   /* cubic Hermite with per-key tangents (normalised for rotations) */
} tt__interp;

/* Keyframed values of `dim` floats. A track with count 0 is absent. Before the first key
 * and after the last one the value is clamped (the first / last key's). */
typedef struct tt__track {
  uint32_t count, dim;
  tt__interp interp;
  int rotation;            /* values are unit quaternions (x, y, z, w) */
  double *times;           /* count, strictly increasing */
  float *values;           /* count * dim */
  float *in_tan, *out_tan; /* CUBIC: count * dim each, value change per second; else NULL */
} tt__track;

/* Allocates a track of `count` keys of `dim` floats (tangents too for CUBIC); NULL arrays
 * on failure (returns TT_ERR_OUT_OF_MEMORY without a message). */
tt_status tt__track_alloc(tt__track *t, uint32_t count, uint32_t dim, tt__interp interp);
/* Frees the arrays and zeroes the track. */
void tt__track_free(tt__track *t);
/* Fills the CUBIC tangents of `t` as Catmull-Rom tangents scaled to non-uniform key spacing
 * (the camera path's spline): in = out = (v[k+1] - v[k-1]) / (t[k+1] - t[k-1]), one-sided
 * at the ends. Rotations are first made to lie in one hemisphere key to key. */
void tt__track_catmull_rom(tt__track *t);
/* Makes consecutive quaternions of a rotation track lie in one hemisphere (q and -q are one
 * rotation; slerp and the spline then take the shorter way). */
void tt__track_align_rotations(tt__track *t);
/* The track's value at time `time` into out[dim]. */
void tt__track_eval(const tt__track *t, double time, float *out);

/* A node of the placement hierarchy: local = T * R * S of its (animated) channels, or
 * `rest` when it has no track; world = parent's world * local. */
typedef struct tt__anim_node {
  int32_t parent;         /* index of an earlier node, or -1 */
  double rest[16];        /* row-major local matrix when no channel is animated */
  float t[3], r[4], s[3]; /* values of absent channels of an animated node */
  tt__track tr, rot, sc;  /* translate (3), rotate (4: x, y, z, w), scale (3) */
  double world[16];       /* scratch: the world matrix at the time being posed */
} tt__anim_node;

/* How one scene mesh moves. Its world positions at time t are
 *   skin: sum over influences w * (world(joint) * inverse_bind) * p,  else  world(node) * p
 * with p = rest + sum_i weight_i(t) * target_delta_i (morph), then `post` applied. */
typedef struct tt__mesh_anim {
  uint32_t mesh;   /* index of the scene mesh */
  int32_t node;    /* node placing the mesh (-1: identity) */
  double post[16]; /* applied after node / skin (the scene.json entry's placement of a
                             file) */
  int has_post;
  float *rest_pos; /* 3 * vertex_count */
  float *rest_nrm; /* 3 * vertex_count or NULL (mesh without normals) */
  /* morph targets */
  uint32_t targets;
  float *dpos, *dnrm; /* targets * 3 * vertex_count position / normal offsets (dnrm may
                             be NULL) */
  float *weights0;    /* targets: weights when `weights` has no keys */
  tt__track weights;  /* dim = targets */
  /* skin */
  uint32_t joints;
  int32_t *joint_node;   /* joints */
  double *inverse_bind;  /* joints * 16 */
  uint32_t influences;   /* per vertex */
  uint32_t *joint_index; /* vertex_count * influences */
  float *joint_weight;   /* vertex_count * influences (normalised at load) */
  /* scratch */
  double *joint_mat; /* joints * 16 */
  float *morph_w;    /* targets */
  /* positions at the previous frame (tt_mesh.prev_positions) */
  float *prev;
  int det_negative; /* the placement mirrors at load time (winding already swapped) */
} tt__mesh_anim;

/* Everything that moves in a scene. */
typedef struct tt__scene_anim {
  tt__anim_node *nodes;
  uint32_t node_count, node_cap;
  tt__mesh_anim *meshes;
  uint32_t mesh_count, mesh_cap;
  double time; /* the time the scene is posed at */
} tt__scene_anim;

/* Frees the scene's animation (NULL is ignored). */
void tt__scene_anim_free(tt__scene_anim *a);

/* Appends a node with an identity rest matrix and no tracks; its index in *index. */
tt_status tt__scene_anim_add_node(tt_scene *scene, int32_t parent, uint32_t *index);
/* The node at `index` (valid until the next add). */
tt__anim_node *tt__scene_anim_node(tt_scene *scene, uint32_t index);
/* Makes scene mesh `mesh` animated (its current positions and normals become the rest pose)
 * and returns its record to fill (node, morph, skin); valid until the next call. */
tt_status tt__scene_anim_add_mesh(tt_scene *scene, uint32_t mesh, tt__mesh_anim **out);

/* Time range [t0, t1] covered by the animation's keys (0, 0 without any). */
void tt__scene_anim_range(const tt_scene *scene, double *t0, double *t1);

/* Folds the animation (nodes, tracks, mesh records) into the scene id's hash `h`. */
uint64_t tt__scene_anim_hash(const tt_scene *scene, uint64_t h);

/* Poses every animated mesh at `time` (positions, normals, rigid transforms); called by
 * tt__scene_finish and tt_scene_set_time. TT_ERR_INVALID_ARGUMENT with a message naming the
 * mesh when a pose is non-finite or beyond TT_SCENE_COORD_LIMIT. */
tt_status tt__scene_anim_pose(tt_scene *scene, double time);

/* Sets the skin of mesh record `m` (anim_skin.c): `joints` joints, each the node
 * joint_node[j] (named joint_name[j] in messages when given) with its row-major inverse bind
 * matrix inverse_bind[16 j]; `influences` (joint_index, joint_weight) pairs per vertex.
 * TT_ERR_PARSE naming `where` when a joint is a missing node, a matrix is not finite and
 * affine, or a vertex's weights are negative, name a missing joint or do not sum to 1 within
 * 1%; the weights are stored normalised. */
tt_status tt__mesh_anim_set_skin(tt_scene *scene, tt__mesh_anim *m, uint32_t joints,
                                 const int32_t *joint_node, const char *const *joint_name,
                                 const double *inverse_bind, uint32_t influences,
                                 const uint32_t *joint_index, const float *joint_weight,
                                 const char *where);

/* Computes every node's world matrix at `time` into tt__anim_node.world (a loader placing
 * what follows a node, e.g. a glTF camera, without posing the meshes). */
void tt__scene_anim_pose_nodes(tt_scene *scene, double time);

#endif /* TT_SCENE_ANIM_H */
