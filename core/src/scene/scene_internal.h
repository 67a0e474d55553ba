/* Internal scene representation shared by the scene loaders (io/: scene.json, pbrt-v4), the
 * mesh importer and the indicators, and the builders the loaders fill it with. Not part of
 * the public ABI. */
#ifndef TT_SCENE_INTERNAL_H
#define TT_SCENE_INTERNAL_H

#include <tunetrace/scene.h>
#include <tt_util/strings.h> /* tt__strdup */

#include <stddef.h>
#include <stdint.h>

/* Everything a scene owns. Mesh arrays, names and paths are heap copies owned here, freed by
 * tt_scene_destroy (the public views expose them as const). */
struct tt_scene {
  char *source;                          /* file path or source name given to the loader */
  char id[17];                           /* 16 hex digits of the content hash, NUL-terminated */
  char part_id[TT_SCENE_PART_COUNT][17]; /* the same of each part (tt_scene_id_part) */
  tt_mesh *meshes;
  uint32_t mesh_count, mesh_cap;
  tt_material *materials;
  uint32_t material_count, material_cap;
  tt_texture *textures;
  uint32_t texture_count, texture_cap;
  tt_light *lights;
  uint32_t light_count, light_cap;
  tt_camera camera; /* camera.keys points at `keys` */
  tt_camera_key *keys;
  tt_render_settings settings;
  float lo[3], hi[3]; /* world bounds, valid after tt__scene_finish */
  uint64_t triangle_count;
  struct tt__scene_anim *anim; /* moving meshes (scene/anim.h), NULL for a still scene */
  double start_time;           /* start of the time range: the pose after loading */
};

/* Geometry produced by the mesh importer or an inline definition, before it becomes a
 * tt_mesh. All arrays are malloc'ed; normals and uvs may be NULL. */
typedef struct tt__mesh_data {
  char *name;
  uint32_t vertex_count, triangle_count;
  float *positions;  /* 3 * vertex_count */
  float *normals;    /* 3 * vertex_count or NULL */
  float *uvs;        /* 2 * vertex_count or NULL */
  uint32_t *indices; /* 3 * triangle_count */
} tt__mesh_data;

/* Allocates an empty scene with the default camera and render settings; NULL when out of
 * memory. */
tt_scene *tt__scene_new(const char *source);

/* Appends one zeroed element of `size` bytes to a growable array; NULL when out of memory. */
void *tt__scene_push(void **items, uint32_t *count, uint32_t *cap, size_t size);

/* Frees the arrays and name of a mesh_data and zeroes it. */
void tt__mesh_data_free(tt__mesh_data *data);

/* Moves `data` into a new scene mesh using material `material`; on success `data` is
 * emptied. */
tt_status tt__scene_add_mesh(tt_scene *scene, tt__mesh_data *data, uint32_t material);

/* Area of triangle t of a mesh-like set of arrays. */
double tt__triangle_area(const float *positions, const uint32_t *indices, uint32_t t);

/* Total surface area of a mesh. */
double tt__mesh_area(const tt_mesh *mesh);

/* Applies a row-major 4x4 affine matrix to positions, normals (inverse transpose) and,
 * for mirroring matrices, the winding. TT_ERR_INVALID_ARGUMENT if the matrix is singular
 * or not affine (the caller words the message). */
tt_status tt__mesh_data_transform(tt__mesh_data *data, const double m[16]);

/* Time range of the camera path's keys and the animation's (0, 0 without either). */
void tt__scene_time_range(const tt_scene *scene, double *t0, double *t1);

/* Recomputes the world bounds from the meshes' current positions. */
void tt__scene_update_bounds(tt_scene *scene);

/* Completes a scene after loading: poses animated meshes at the start of the time range,
 * creates the area lights of emissive meshes, computes the bounds, the triangle count and
 * the id. */
tt_status tt__scene_finish(tt_scene *scene);

#endif /* TT_SCENE_INTERNAL_H */
