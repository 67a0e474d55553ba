/* tunetrace: scenes. A scene is loaded from scene.json (see scenes/README.md), flattened to
 * world-space triangle meshes, and is immutable afterwards except for the camera and the
 * resolution, which the host may override before rendering. Plugins receive it as const
 * and read it through the views below; views point into the scene and stay valid until
 * tt_scene_destroy. Reading a scene is thread-safe.
 *
 * View structs begin with struct_size so fields can be appended; a reader built against an
 * older header simply ignores the tail.
 */
#ifndef TUNETRACE_SCENE_H
#define TUNETRACE_SCENE_H

#include <tunetrace/common.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tt_scene tt_scene;

/* A triangle mesh in world space. */
typedef struct tt_mesh {
  uint32_t struct_size;
  const char *name; /* from the scene file ("mesh[3]" if unnamed) */
  uint32_t vertex_count;
  uint32_t triangle_count;
  const float *positions;  /* 3 * vertex_count floats, world space */
  const float *normals;    /* 3 * vertex_count unit normals, or NULL (use the face normal) */
  const float *uvs;        /* 2 * vertex_count, or NULL */
  const uint32_t *indices; /* 3 * triangle_count vertex indices */
  uint32_t material;       /* index into the scene's materials */
  int32_t light;           /* index of the area light this mesh emits as, or -1 */
  /* ---- appended (ABI 1.2): animation; read only when struct_size covers them ---- */
  uint32_t motion;               /* a tt_mesh_motion: how tt_scene_set_time changes the mesh */
  const float *prev_positions;   /* 3 * vertex_count: world positions at the previous frame's
                                    time (tt_scene_set_time); == positions when static */
  const float *object_positions; /* TT_MESH_RIGID: 3 * vertex_count in object space; else
                                    NULL */
  float transform[12];           /* TT_MESH_RIGID: row-major 3x4 object-to-world matrix at the
                                 current time (positions are it times object_positions,
                                 computed in double and rounded); identity otherwise */
  uint64_t revision;             /* changes whenever tt_scene_set_time rewrites the positions */
} tt_mesh;

/* How a mesh moves over the scene's time (tt_mesh.motion). */
typedef enum tt_mesh_motion {
  TT_MESH_STATIC = 0,   /* never changes */
  TT_MESH_RIGID = 1,    /* placed by a keyframed transform: positions = transform *
                                 object_positions */
  TT_MESH_DEFORMING = 2 /* vertices move independently (morph targets, skinning) */
} tt_mesh_motion;

typedef enum tt_material_type {
  TT_MATERIAL_DIFFUSE = 1,    /* Lambert, or Oren-Nayar when roughness > 0 */
  TT_MATERIAL_CONDUCTOR = 2,  /* anisotropic GGX microfacet metal (eta, k) */
  TT_MATERIAL_DIELECTRIC = 3, /* smooth glass with Fresnel (rough when alpha > 0) */
  TT_MATERIAL_MIRROR = 4,     /* ideal specular reflector, tinted by `specular` */
  TT_MATERIAL_PLASTIC = 5     /* diffuse base under a GGX dielectric coat (glossy) */
} tt_material_type;

typedef struct tt_material {
  uint32_t struct_size;
  const char *name;
  tt_material_type type;
  float albedo[3];        /* diffuse reflectance (linear RGB), DIFFUSE and PLASTIC base */
  int32_t albedo_texture; /* index of an image texture modulating albedo, or -1 */
  float roughness;        /* Oren-Nayar sigma in radians (DIFFUSE) */
  float alpha[2];         /* GGX alpha_x, alpha_y (CONDUCTOR, PLASTIC, rough DIELECTRIC) */
  float eta[3];           /* CONDUCTOR: real part of the IOR per channel */
  float k[3];             /* CONDUCTOR: imaginary part (absorption) per channel */
  float ior;              /* DIELECTRIC / PLASTIC coat: index of refraction */
  float specular[3];      /* tint of specular reflection/transmission */
  float emission[3];      /* emitted radiance; non-zero makes every mesh using it a light */
  int32_t two_sided;      /* emission from both sides when non-zero */
} tt_material;

typedef struct tt_texture {
  uint32_t struct_size;
  const char *path; /* resolved path of the image file */
  int32_t srgb;     /* non-zero: the file holds sRGB-encoded colour */
} tt_texture;

typedef enum tt_light_type {
  TT_LIGHT_AREA = 1,         /* an emissive mesh (radiance from its material) */
  TT_LIGHT_ENV_CONSTANT = 2, /* uniform environment of radiance `radiance` */
  TT_LIGHT_ENV_IMAGE = 3,    /* lat-long environment image `image` scaled by `radiance` */
  TT_LIGHT_POINT = 4,
  TT_LIGHT_SPOT = 5,
  TT_LIGHT_DISTANT = 6
} tt_light_type;

typedef struct tt_light {
  uint32_t struct_size;
  tt_light_type type;
  uint32_t mesh;              /* AREA: index of the emitting mesh */
  float radiance[3];          /* AREA: emitted radiance; ENV: radiance or scale; POINT/SPOT:
                               intensity; DISTANT: irradiance */
  float position[3];          /* POINT, SPOT */
  float direction[3];         /* SPOT, DISTANT: direction the light travels */
  float cos_inner, cos_outer; /* SPOT falloff cone */
  const char *image;          /* ENV_IMAGE: resolved path */
  float area;                 /* AREA: total surface area (world units^2) */
} tt_light;

/* One camera pose; a camera path is a list of them (times in seconds, increasing). */
/* Largest |coordinate| of a vertex, camera position, target or path key and point or spot
 * light a scene may hold; loaders reject what lies beyond, naming it. Rays are traced up to
 * about 1.8e18 (Embree's limit); 1e18 leaves room for offsets and light directions. */
#define TT_SCENE_COORD_LIMIT 1e18

typedef struct tt_camera_key {
  float time;
  float position[3];
  float target[3];
  float up[3];
  float fov_y; /* vertical field of view in degrees */
} tt_camera_key;

typedef struct tt_camera {
  uint32_t struct_size;
  float position[3];
  float target[3];
  float up[3];
  float fov_y;            /* vertical field of view, degrees, in (0, 180) */
  uint32_t width, height; /* resolution in pixels */
  uint32_t key_count;     /* camera path keyframes (0: a still camera) */
  const tt_camera_key *keys;
} tt_camera;

/* Render settings stored in the scene (the host's options override them). */
typedef struct tt_render_settings {
  uint32_t struct_size;
  uint32_t spp;       /* samples per pixel for the final image */
  uint32_t max_depth; /* default path depth (bounces) for integrators */
  uint64_t seed;
  double time_budget_s; /* 0: no budget */
} tt_render_settings;

/* Loads a scene file (scene.json, .pbrt, or glTF 2.0 .gltf/.glb with its animation, chosen
 * by extension; a scene.json may "import" one pbrt/scene.json/glTF file and override its
 * camera and settings). On error returns
 * TT_ERR_IO / TT_ERR_PARSE and a message naming the file, the JSON path and what was
 * expected. `*out` is owned by the caller: free with tt_scene_destroy. Thread-safe. */
TT_API tt_status tt_scene_load(const char *path, tt_scene **out);

/* Flags of tt_scene_load_ex. */
typedef enum tt_scene_load_flags {
  TT_SCENE_LOAD_DEFAULT = 0,
  /* pbrt-v4 input as pbrt-v4 reads it: an unknown directive, or a parameter the importer
   * does not read (a misspelt "rgb reflectanse", a parameter of another material), is an
   * error naming file:line (with "did you mean" when a known name is close), not a warning
   * and a guess. Every such problem is logged; the load fails with the first. Features
   * the importer knows but approximates (media, displacement, ...) still only warn. Also
   * applies to pbrt files a scene.json imports. */
  TT_SCENE_LOAD_STRICT = 1u << 0
} tt_scene_load_flags;

/* tt_scene_load with `flags` (tt_scene_load_flags, or-ed). Thread-safe. */
TT_API tt_status tt_scene_load_ex(const char *path, uint32_t flags, tt_scene **out);

/* Loads scene JSON from memory; `source` names it in messages; relative asset paths are
 * resolved against `base_dir` (NULL = current directory). */
TT_API tt_status tt_scene_load_json(const char *json, size_t length, const char *source,
                                    const char *base_dir, tt_scene **out);

/* Destroys a scene (NULL is ignored). No plugin may still hold views into it. */
TT_API void tt_scene_destroy(tt_scene *scene);

/* Path (or source name) the scene was loaded from. */
TT_API const char *tt_scene_source(const tt_scene *scene);
/* Stable identifier of the scene content (16 hex digits: geometry, materials, textures and
 * environment images by content, lights; not names, file locations or the camera), used as
 * the scene key of tuning databases. The same scene loaded from another folder has the same
 * id. */
TT_API const char *tt_scene_id(const tt_scene *scene);

/* The parts of a scene that its id covers, each with an id of its own (tt_scene_id_part), so
 * that a changed id can say what changed. */
typedef enum tt_scene_part {
  TT_SCENE_PART_GEOMETRY = 0,  /* meshes: positions, normals, uvs, indices, material slots */
  TT_SCENE_PART_MATERIALS = 1, /* material parameters */
  TT_SCENE_PART_TEXTURES = 2,  /* texture images by content, and their colour space */
  TT_SCENE_PART_LIGHTS = 3,    /* lights other than emissive meshes, environment images */
  TT_SCENE_PART_COUNT = 4
} tt_scene_part;

/* 16 hex digits of the content hash of one part of the scene; NULL for an unknown part. */
TT_API const char *tt_scene_id_part(const tt_scene *scene, tt_scene_part part);

/* The name of a part ("geometry", "materials", "textures", "lights"); NULL if unknown. */
TT_API const char *tt_scene_part_name(tt_scene_part part);

TT_API uint32_t tt_scene_mesh_count(const tt_scene *scene);
TT_API const tt_mesh *tt_scene_mesh(const tt_scene *scene, uint32_t index);
TT_API uint32_t tt_scene_material_count(const tt_scene *scene);
TT_API const tt_material *tt_scene_material(const tt_scene *scene, uint32_t index);
TT_API uint32_t tt_scene_texture_count(const tt_scene *scene);
TT_API const tt_texture *tt_scene_texture(const tt_scene *scene, uint32_t index);
TT_API uint32_t tt_scene_light_count(const tt_scene *scene);
TT_API const tt_light *tt_scene_light(const tt_scene *scene, uint32_t index);
/* Total number of triangles over all meshes. */
TT_API uint64_t tt_scene_triangle_count(const tt_scene *scene);
/* World-space bounding box of all geometry: lo[3], hi[3]. */
TT_API void tt_scene_bounds(const tt_scene *scene, float lo[3], float hi[3]);

TT_API const tt_camera *tt_scene_camera(const tt_scene *scene);
/* Camera pose at time t on the camera path (Catmull-Rom through the keys; the still camera
 * when there are no keys). Writes a full camera (resolution included) into `out`. */
TT_API void tt_scene_camera_at(const tt_scene *scene, double t, tt_camera *out);
/* Replaces the still camera pose (not thread-safe: only before rendering). */
TT_API void tt_scene_set_camera(tt_scene *scene, const tt_camera *camera);
/* Overrides the resolution (both > 0). Not thread-safe: only before rendering. */
TT_API tt_status tt_scene_set_resolution(tt_scene *scene, uint32_t width, uint32_t height);

TT_API const tt_render_settings *tt_scene_settings(const tt_scene *scene);

/* ---- animation (scenes/README.md, "Animation") --------------------------------------
 * A scene's meshes may move over time (keyframed rigid transforms, morph targets,
 * skinning); the time axis is the camera path's. A loaded scene is posed at the start of
 * its time range (a still renders that pose). */

/* Non-zero when any mesh of the scene moves (tt_mesh.motion != TT_MESH_STATIC). */
TT_API int tt_scene_animated(const tt_scene *scene);
/* Time range [t0, t1] of the scene: the keys of its camera path and of its animations
 * (0, 0 for a still scene). */
TT_API void tt_scene_time_range(const tt_scene *scene, double *t0, double *t1);
/* The time the meshes are posed at. */
TT_API double tt_scene_time(const tt_scene *scene);
/* Poses every animated mesh at time `t` (positions, normals and transforms rewritten in
 * place: views keep their pointers) and their prev_positions at `t_prev` (the previous
 * frame, for motion vectors); updates the bounds and the areas of moving area lights.
 * Keys are clamped outside their range. A still scene is left as it is. Not thread-safe:
 * only between renders, and an accel built over the scene must be updated or rebuilt
 * before the next query. TT_ERR_INVALID_ARGUMENT (naming the mesh) when a pose leaves the
 * coordinate limit. */
TT_API tt_status tt_scene_set_time(tt_scene *scene, double t, double t_prev);

/* Scene indicators of thesis Table 3.2 (the predictors' state vector). */
#define TT_SCENE_INDICATOR_COUNT 17
/* Name of indicator i ("meshes", "triangles", ..., "var_var_tri_size"). */
TT_API const char *tt_scene_indicator_name(uint32_t index);
/* Computes the TT_SCENE_INDICATOR_COUNT indicators for the scene and its current camera;
 * surface quantities are normalised by the scene extent as in thesis 3.3.1. */
TT_API void tt_scene_indicators(const tt_scene *scene, double out[TT_SCENE_INDICATOR_COUNT]);

/* Writes the loaded, flattened scene as scene.json v1 at `path`, with every mesh as a binary
 * little-endian PLY file meshes/<index>_<name>.ply next to it (folder created if missing);
 * tt_scene_load reads it back with the same meshes, materials, lights, camera and settings.
 * Textures and environment images are referenced by absolute path; area lights are implied
 * by emissive materials. Errors (TT_ERR_IO) name the file. */
TT_API tt_status tt_scene_write_json(const tt_scene *scene, const char *path);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_SCENE_H */
