/* Scenes: construction helpers shared by the loaders, the content hash, accessors, camera
 * path evaluation. Format dispatch (tt_scene_load) is in io/scene_load.c. */
#include "scene/anim.h"
#include "scene/scene_internal.h"
#include "util/files.h"

#include <tt_util/hash.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- construction ---------------------------------------------------------------------- */

/* A still camera that sees something sensible even if a loader sets nothing. */
tt_scene *tt__scene_new(const char *source) {
  tt_scene *s = calloc(1, sizeof *s);
  if (!s) return NULL;
  s->source = tt__strdup(source ? source : "(memory)");
  if (!s->source) {
    free(s);
    return NULL;
  }
  s->camera.struct_size = sizeof s->camera;
  s->camera.position[2] = 1.0f;
  s->camera.up[1] = 1.0f;
  s->camera.fov_y = 45.0f;
  s->camera.width = 256;
  s->camera.height = 256;
  s->settings.struct_size = sizeof s->settings;
  s->settings.spp = 16;
  s->settings.max_depth = 3;
  s->settings.seed = 1;
  s->settings.time_budget_s = 0.0;
  return s;
}

/* Doubling growth keeps appends amortised O(1) for scenes with many meshes. */
void *tt__scene_push(void **items, uint32_t *count, uint32_t *cap, size_t size) {
  if (*count == UINT32_MAX) return NULL;
  if (*count == *cap) {
    uint32_t ncap = *cap ? (*cap > UINT32_MAX / 2 ? UINT32_MAX : *cap * 2) : 8;
    void *n = realloc(*items, (size_t)ncap * size);
    if (!n) return NULL;
    *items = n;
    *cap = ncap;
  }
  char *slot = (char *)*items + (size_t)(*count)++ * size;
  memset(slot, 0, size);
  return slot;
}

/* Releases everything a mesh_data owns so error paths can call it unconditionally. */
void tt__mesh_data_free(tt__mesh_data *d) {
  if (!d) return;
  free(d->name);
  free(d->positions);
  free(d->normals);
  free(d->uvs);
  free(d->indices);
  memset(d, 0, sizeof *d);
}

/* Ownership moves into the scene so loaders never copy large arrays. */
tt_status tt__scene_add_mesh(tt_scene *scene, tt__mesh_data *d, uint32_t material) {
  tt_mesh *m =
      tt__scene_push((void **)&scene->meshes, &scene->mesh_count, &scene->mesh_cap, sizeof *m);
  if (!m) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", scene->source);
  m->struct_size = sizeof *m;
  m->name = d->name;
  m->vertex_count = d->vertex_count;
  m->triangle_count = d->triangle_count;
  m->positions = d->positions;
  m->normals = d->normals;
  m->uvs = d->uvs;
  m->indices = d->indices;
  m->material = material;
  m->light = -1;
  m->motion = TT_MESH_STATIC;
  m->prev_positions = m->positions;
  m->transform[0] = m->transform[5] = m->transform[10] = 1.0f;
  memset(d, 0, sizeof *d);
  return TT_OK;
}

/* Half the cross product length, in double so that mm-scale scenes keep precision. */
double tt__triangle_area(const float *p, const uint32_t *idx, uint32_t t) {
  const float *a = p + 3 * (size_t)idx[3 * (size_t)t];
  const float *b = p + 3 * (size_t)idx[3 * (size_t)t + 1];
  const float *c = p + 3 * (size_t)idx[3 * (size_t)t + 2];
  double e1[3] = {b[0] - (double)a[0], b[1] - (double)a[1], b[2] - (double)a[2]};
  double e2[3] = {c[0] - (double)a[0], c[1] - (double)a[1], c[2] - (double)a[2]};
  double x = e1[1] * e2[2] - e1[2] * e2[1];
  double y = e1[2] * e2[0] - e1[0] * e2[2];
  double z = e1[0] * e2[1] - e1[1] * e2[0];
  return 0.5 * sqrt(x * x + y * y + z * z);
}

/* Sum of triangle areas; used for area lights and indicators. */
double tt__mesh_area(const tt_mesh *m) {
  double a = 0.0;
  for (uint32_t t = 0; t < m->triangle_count; t++)
    a += tt__triangle_area(m->positions, m->indices, t);
  return a;
}

/* 3x3 determinant of the upper-left block of a row-major 4x4 matrix. */
static double tt__det3(const double m[16]) {
  return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
         m[2] * (m[4] * m[9] - m[5] * m[8]);
}

/* Flattening at load time means plugins never see transforms; normals need the inverse
 * transpose so that non-uniform scales keep them perpendicular to the surface. */
tt_status tt__mesh_data_transform(tt__mesh_data *d, const double m[16]) {
  if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0) return TT_ERR_INVALID_ARGUMENT;
  double det = tt__det3(m);
  if (!isfinite(det) || fabs(det) < 1e-300) return TT_ERR_INVALID_ARGUMENT;
  for (uint32_t v = 0; v < d->vertex_count; v++) {
    float *p = d->positions + 3 * (size_t)v;
    double x = p[0], y = p[1], z = p[2];
    for (int r = 0; r < 3; r++)
      p[r] = (float)(m[4 * r] * x + m[4 * r + 1] * y + m[4 * r + 2] * z + m[4 * r + 3]);
  }
  if (d->normals) {
    /* inverse transpose of A = cofactor matrix / det; the 1/det only scales, and its sign
     * is handled by keeping the cofactor sign consistent with det. */
    double c[9] = {
        m[5] * m[10] - m[6] * m[9], m[6] * m[8] - m[4] * m[10], m[4] * m[9] - m[5] * m[8],
        m[2] * m[9] - m[1] * m[10], m[0] * m[10] - m[2] * m[8], m[1] * m[8] - m[0] * m[9],
        m[1] * m[6] - m[2] * m[5],  m[2] * m[4] - m[0] * m[6],  m[0] * m[5] - m[1] * m[4]};
    double sgn = det < 0 ? -1.0 : 1.0;
    for (uint32_t v = 0; v < d->vertex_count; v++) {
      float *n = d->normals + 3 * (size_t)v;
      double x = n[0], y = n[1], z = n[2], o[3];
      for (int r = 0; r < 3; r++) o[r] = sgn * (c[3 * r] * x + c[3 * r + 1] * y + c[3 * r + 2] * z);
      double len = sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
      if (len > 0)
        for (int r = 0; r < 3; r++) n[r] = (float)(o[r] / len);
    }
  }
  if (det < 0) {
    /* a mirror flips the geometric normal (v1-v0)x(v2-v0); swapping two indices restores
     * agreement with the shading normals and keeps one-sided emitters facing the same way */
    for (uint32_t t = 0; t < d->triangle_count; t++) {
      uint32_t tmp = d->indices[3 * (size_t)t + 1];
      d->indices[3 * (size_t)t + 1] = d->indices[3 * (size_t)t + 2];
      d->indices[3 * (size_t)t + 2] = tmp;
    }
  }
  return TT_OK;
}

/* ---- content hash ---------------------------------------------------------------------- */

/* Hashes a string with its terminator so "ab","c" differs from "a","bc". */
static uint64_t tt__fnv_str(uint64_t h, const char *s) {
  return s ? tt__fnv1a64(h, s, strlen(s) + 1) : tt__fnv1a64(h, "", 1);
}

/* Hashes a float array with -0 folded to +0 so equal values hash equally. */
static uint64_t tt__fnv_floats(uint64_t h, const float *f, size_t n) {
  for (size_t i = 0; i < n; i++) {
    float v = f[i] == 0.0f ? 0.0f : f[i];
    h = tt__fnv1a64(h, &v, sizeof v);
  }
  return h;
}

/* Digest of a file's bytes, so that a texture or environment image counts by its content,
 * not by where the scene was found: the same scene in another checkout (another absolute
 * path) keeps its id. A file that cannot be read (a texture listed missing, replaced by a
 * constant) counts by its base name. */
static uint64_t tt__fnv_file(uint64_t h, const char *path) {
  char why[160];
  FILE *f = path && tt__file_regular_reason(path, why, sizeof why) == 0 ? fopen(path, "rb") : NULL;
  if (!f) {
    const char *base = path ? strrchr(path, '/') : NULL;
    h = tt__fnv1a64(h, "missing:", 8);
    return tt__fnv_str(h, base ? base + 1 : path);
  }
  unsigned char buf[1 << 16];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, f)) > 0) h = tt__fnv1a64(h, buf, n);
  fclose(f);
  return h;
}

static uint64_t tt__id_meshes(uint64_t h, const tt_scene *s) {
  h = tt__fnv1a64(h, &s->mesh_count, sizeof s->mesh_count);
  for (uint32_t i = 0; i < s->mesh_count; i++) {
    const tt_mesh *m = &s->meshes[i];
    uint32_t hdr[5] = {m->vertex_count, m->triangle_count, m->material, m->normals != NULL,
                       m->uvs != NULL};
    h = tt__fnv1a64(h, hdr, sizeof hdr);
    h = tt__fnv_floats(h, m->positions, 3 * (size_t)m->vertex_count);
    if (m->normals) h = tt__fnv_floats(h, m->normals, 3 * (size_t)m->vertex_count);
    if (m->uvs) h = tt__fnv_floats(h, m->uvs, 2 * (size_t)m->vertex_count);
    h = tt__fnv1a64(h, m->indices, 3 * (size_t)m->triangle_count * sizeof *m->indices);
  }
  return h;
}

static uint64_t tt__id_materials(uint64_t h, const tt_scene *s) {
  h = tt__fnv1a64(h, &s->material_count, sizeof s->material_count);
  for (uint32_t i = 0; i < s->material_count; i++) {
    const tt_material *m = &s->materials[i];
    int32_t ints[3] = {(int32_t)m->type, m->albedo_texture, m->two_sided};
    h = tt__fnv1a64(h, ints, sizeof ints);
    h = tt__fnv_floats(h, m->albedo, 3);
    h = tt__fnv_floats(h, &m->roughness, 1);
    h = tt__fnv_floats(h, m->alpha, 2);
    h = tt__fnv_floats(h, m->eta, 3);
    h = tt__fnv_floats(h, m->k, 3);
    h = tt__fnv_floats(h, &m->ior, 1);
    h = tt__fnv_floats(h, m->specular, 3);
    h = tt__fnv_floats(h, m->emission, 3);
  }
  return h;
}

/* `digest` holds tt__fnv_file of each texture (read once for the id and its part). */
static uint64_t tt__id_textures(uint64_t h, const tt_scene *s, const uint64_t *digest) {
  for (uint32_t i = 0; i < s->texture_count; i++) {
    h = tt__fnv1a64(h, &digest[i], sizeof digest[i]);
    h = tt__fnv1a64(h, &s->textures[i].srgb, sizeof s->textures[i].srgb);
  }
  return h;
}

/* `digest` holds tt__fnv_file of each light's image (0 for a light without one). */
static uint64_t tt__id_lights(uint64_t h, const tt_scene *s, const uint64_t *digest) {
  for (uint32_t i = 0; i < s->light_count; i++) {
    const tt_light *l = &s->lights[i];
    if (l->type == TT_LIGHT_AREA) continue; /* implied by mesh + material */
    int32_t t = (int32_t)l->type;
    h = tt__fnv1a64(h, &t, sizeof t);
    h = tt__fnv_floats(h, l->radiance, 3);
    h = tt__fnv_floats(h, l->position, 3);
    h = tt__fnv_floats(h, l->direction, 3);
    h = tt__fnv_floats(h, &l->cos_inner, 1);
    h = tt__fnv_floats(h, &l->cos_outer, 1);
    if (l->image) {
      h = tt__fnv1a64(h, &digest[i], sizeof digest[i]);
    } else {
      h = tt__fnv_str(h, NULL);
    }
  }
  return h;
}

/* The id covers what determines rendering cost and result apart from the camera (which
 * the tuner treats as state): geometry, materials (not their names), textures and
 * environment images (by content) and the explicit lights. Names, file locations and the
 * camera are left out on purpose. Each part also gets an id of its own, so a changed id can
 * be explained (tt_scene_id_part). */
static tt_status tt__scene_compute_id(tt_scene *s) {
  uint64_t *digest = malloc(((size_t)s->texture_count + s->light_count + 1) * sizeof *digest);
  if (!digest) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "scene id: out of memory");
  uint64_t *tex = digest, *img = digest + s->texture_count;
  for (uint32_t i = 0; i < s->texture_count; i++)
    tex[i] = tt__fnv_file(TT__FNV1A64_OFFSET, s->textures[i].path);
  for (uint32_t i = 0; i < s->light_count; i++)
    img[i] = s->lights[i].image ? tt__fnv_file(TT__FNV1A64_OFFSET, s->lights[i].image) : 0;
  /* the id chains the parts (in the order of the first scene ids, which stay valid for
   * scenes without images); the animation (keyframes, morph targets) counts as geometry */
  uint64_t meshes = tt__id_meshes(TT__FNV1A64_OFFSET, s);
  uint64_t part[TT_SCENE_PART_COUNT] = {
      tt__scene_anim_hash(s, meshes), tt__id_materials(TT__FNV1A64_OFFSET, s),
      tt__id_textures(TT__FNV1A64_OFFSET, s, tex), tt__id_lights(TT__FNV1A64_OFFSET, s, img)};
  uint64_t h = tt__id_lights(tt__id_textures(tt__id_materials(meshes, s), s, tex), s, img);
  h = tt__scene_anim_hash(s, h);
  free(digest);
  snprintf(s->id, sizeof s->id, "%016llx", (unsigned long long)h);
  for (int p = 0; p < TT_SCENE_PART_COUNT; p++)
    snprintf(s->part_id[p], sizeof s->part_id[p], "%016llx", (unsigned long long)part[p]);
  return TT_OK;
}

/* Index of the first of n 3-vectors with a coordinate beyond TT_SCENE_COORD_LIMIT (or not
 * finite), or -1. */
static long tt__far_vec(const float *v, size_t n) {
  for (size_t i = 0; i < n; i++)
    for (int a = 0; a < 3; a++)
      if (!(fabsf(v[3 * i + a]) <= (float)TT_SCENE_COORD_LIMIT)) return (long)i;
  return -1;
}

/* Positions no renderer can trace are rejected at load, naming what holds them: Embree
 * asserts on a ray origin beyond ~1.8e18 (SIGABRT with the camera at z = 1e19) and drops
 * triangles beyond it (geometry at 1e30 vanished silently). */
static tt_status tt__scene_check_range(const tt_scene *s) {
  const char *why = "beyond the coordinate limit of +-1e18 (rays are traced up to ~1.8e18: "
                    "rescale the scene)";
  const tt_camera *c = &s->camera;
  const float *cam[3] = {c->position, c->target, c->up};
  static const char *const cam_names[3] = {"position", "target", "up"};
  for (int k = 0; k < 3; k++)
    if (tt__far_vec(cam[k], 1) >= 0)
      return tt_set_error(TT_ERR_PARSE, "%s: camera %s (%g, %g, %g) is %s", s->source, cam_names[k],
                          cam[k][0], cam[k][1], cam[k][2], why);
  for (uint32_t i = 0; i < c->key_count; i++) {
    const tt_camera_key *key = &s->keys[i];
    if (tt__far_vec(key->position, 1) >= 0 || tt__far_vec(key->target, 1) >= 0)
      return tt_set_error(TT_ERR_PARSE,
                          "%s: camera path key %u (time %g): position (%g, %g, %g) "
                          "or target (%g, %g, %g) is %s",
                          s->source, i, key->time, key->position[0], key->position[1],
                          key->position[2], key->target[0], key->target[1], key->target[2], why);
  }
  for (uint32_t i = 0; i < s->light_count; i++) {
    const tt_light *l = &s->lights[i];
    if ((l->type == TT_LIGHT_POINT || l->type == TT_LIGHT_SPOT) && tt__far_vec(l->position, 1) >= 0)
      return tt_set_error(TT_ERR_PARSE, "%s: light %u at (%g, %g, %g) is %s", s->source, i,
                          l->position[0], l->position[1], l->position[2], why);
  }
  for (uint32_t i = 0; i < s->mesh_count; i++) {
    const tt_mesh *m = &s->meshes[i];
    long v = tt__far_vec(m->positions, m->vertex_count);
    if (v >= 0) {
      const float *p = m->positions + 3 * (size_t)v;
      return tt_set_error(TT_ERR_PARSE, "%s: mesh %u \"%s\": vertex %ld at (%g, %g, %g) is %s",
                          s->source, i, m->name ? m->name : "", v, p[0], p[1], p[2], why);
    }
  }
  return TT_OK;
}

/* Emissive meshes become area lights here, after all meshes exist, so every loader gets
 * the same light list (explicit lights first, then area lights in mesh order). */
/* Camera path keys and animation keys share one time axis. */
void tt__scene_time_range(const tt_scene *s, double *t0, double *t1) {
  double lo, hi;
  tt__scene_anim_range(s, &lo, &hi);
  int any = s->anim && !(lo == 0 && hi == 0);
  if (s->camera.key_count) {
    double a = s->keys[0].time, b = s->keys[s->camera.key_count - 1].time;
    if (!any || a < lo) lo = a;
    if (!any || b > hi) hi = b;
  }
  *t0 = lo;
  *t1 = hi;
}

void tt__scene_update_bounds(tt_scene *s) {
  for (int a = 0; a < 3; a++) {
    s->lo[a] = INFINITY;
    s->hi[a] = -INFINITY;
  }
  for (uint32_t i = 0; i < s->mesh_count; i++) {
    const tt_mesh *m = &s->meshes[i];
    for (uint32_t v = 0; v < m->vertex_count; v++)
      for (int a = 0; a < 3; a++) {
        float x = m->positions[3 * (size_t)v + a];
        if (x < s->lo[a]) s->lo[a] = x;
        if (x > s->hi[a]) s->hi[a] = x;
      }
  }
  if (s->mesh_count == 0)
    for (int a = 0; a < 3; a++) s->lo[a] = s->hi[a] = 0.0f;
}

/* Animated meshes get their motion kind and previous-position arrays, and the scene its
 * start pose. */
static tt_status tt__scene_finish_anim(tt_scene *s) {
  tt__scene_anim *a = s->anim;
  if (!a) return TT_OK;
  for (uint32_t i = 0; i < a->mesh_count; i++) {
    tt__mesh_anim *ma = &a->meshes[i];
    tt_mesh *m = &s->meshes[ma->mesh];
    if (ma->targets || ma->joints) {
      m->motion = TT_MESH_DEFORMING;
    } else {
      m->motion = TT_MESH_RIGID;
      m->object_positions = ma->rest_pos;
    }
    m->prev_positions = ma->prev;
    if (ma->targets && !ma->morph_w) ma->morph_w = calloc(ma->targets, sizeof(float));
    if (ma->joints && !ma->joint_mat) ma->joint_mat = malloc(sizeof(double) * 16 * ma->joints);
    if ((ma->targets && !ma->morph_w) || (ma->joints && !ma->joint_mat))
      return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", s->source);
  }
  double t1;
  tt__scene_time_range(s, &s->start_time, &t1);
  a->time = NAN; /* nothing posed yet */
  tt_status st = tt__scene_anim_pose(s, s->start_time);
  if (st != TT_OK) return tt_set_error(TT_ERR_PARSE, "%s", tt_last_error());
  for (uint32_t i = 0; i < a->mesh_count; i++) {
    const tt_mesh *m = &s->meshes[a->meshes[i].mesh];
    memcpy(a->meshes[i].prev, m->positions, sizeof(float) * 3 * (size_t)m->vertex_count);
  }
  return TT_OK;
}

tt_status tt__scene_finish(tt_scene *s) {
  tt_status range = tt__scene_finish_anim(s);
  if (range == TT_OK) range = tt__scene_check_range(s);
  if (range != TT_OK) return range;
  for (uint32_t i = 0; i < s->mesh_count; i++) {
    tt_mesh *m = &s->meshes[i];
    const tt_material *mat = &s->materials[m->material];
    if (mat->emission[0] <= 0 && mat->emission[1] <= 0 && mat->emission[2] <= 0) continue;
    tt_light *l = tt__scene_push((void **)&s->lights, &s->light_count, &s->light_cap, sizeof *l);
    if (!l) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", s->source);
    l->struct_size = sizeof *l;
    l->type = TT_LIGHT_AREA;
    l->mesh = i;
    memcpy(l->radiance, mat->emission, sizeof l->radiance);
    l->area = (float)tt__mesh_area(m);
    m->light = (int32_t)(s->light_count - 1);
  }
  s->triangle_count = 0;
  for (uint32_t i = 0; i < s->mesh_count; i++) s->triangle_count += s->meshes[i].triangle_count;
  tt__scene_update_bounds(s);
  s->camera.keys = s->keys;
  return tt__scene_compute_id(s);
}

/* ---- public API ------------------------------------------------------------------------ */

/* Frees the heap copies behind the const views. */
void tt_scene_destroy(tt_scene *s) {
  if (!s) return;
  for (uint32_t i = 0; i < s->mesh_count; i++) {
    tt_mesh *m = &s->meshes[i];
    free((void *)m->name);
    free((void *)m->positions);
    free((void *)m->normals);
    free((void *)m->uvs);
    free((void *)m->indices);
  }
  for (uint32_t i = 0; i < s->material_count; i++) free((void *)s->materials[i].name);
  for (uint32_t i = 0; i < s->texture_count; i++) free((void *)s->textures[i].path);
  for (uint32_t i = 0; i < s->light_count; i++) free((void *)s->lights[i].image);
  free(s->meshes);
  free(s->materials);
  free(s->textures);
  free(s->lights);
  free(s->keys);
  free(s->source);
  tt__scene_anim_free(s->anim);
  free(s);
}

/* Accessors: NULL-safe and bounds-checked so a buggy plugin gets NULL instead of garbage. */
const char *tt_scene_source(const tt_scene *s) { return s ? s->source : NULL; }
/* See tt__scene_compute_id for what the id covers. */
const char *tt_scene_id(const tt_scene *s) { return s ? s->id : NULL; }

const char *tt_scene_part_name(tt_scene_part part) {
  static const char *const names[TT_SCENE_PART_COUNT] = {"geometry", "materials", "textures",
                                                         "lights"};
  return part >= 0 && part < TT_SCENE_PART_COUNT ? names[part] : NULL;
}

const char *tt_scene_id_part(const tt_scene *s, tt_scene_part part) {
  return s && part >= 0 && part < TT_SCENE_PART_COUNT ? s->part_id[part] : NULL;
}
/* Number of meshes. */
uint32_t tt_scene_mesh_count(const tt_scene *s) { return s ? s->mesh_count : 0; }
/* Mesh view, NULL when out of range. */
const tt_mesh *tt_scene_mesh(const tt_scene *s, uint32_t i) {
  return s && i < s->mesh_count ? &s->meshes[i] : NULL;
}
/* Number of materials. */
uint32_t tt_scene_material_count(const tt_scene *s) { return s ? s->material_count : 0; }
/* Material view, NULL when out of range. */
const tt_material *tt_scene_material(const tt_scene *s, uint32_t i) {
  return s && i < s->material_count ? &s->materials[i] : NULL;
}
/* Number of textures. */
uint32_t tt_scene_texture_count(const tt_scene *s) { return s ? s->texture_count : 0; }
/* Texture view, NULL when out of range. */
const tt_texture *tt_scene_texture(const tt_scene *s, uint32_t i) {
  return s && i < s->texture_count ? &s->textures[i] : NULL;
}
/* Number of lights, area lights included. */
uint32_t tt_scene_light_count(const tt_scene *s) { return s ? s->light_count : 0; }
/* Light view, NULL when out of range. */
const tt_light *tt_scene_light(const tt_scene *s, uint32_t i) {
  return s && i < s->light_count ? &s->lights[i] : NULL;
}
/* Precomputed in tt__scene_finish. */
uint64_t tt_scene_triangle_count(const tt_scene *s) { return s ? s->triangle_count : 0; }

/* Precomputed in tt__scene_finish. */
void tt_scene_bounds(const tt_scene *s, float lo[3], float hi[3]) {
  for (int a = 0; a < 3; a++) {
    if (lo) lo[a] = s ? s->lo[a] : 0.0f;
    if (hi) hi[a] = s ? s->hi[a] : 0.0f;
  }
}

/* The still camera (with the path keys attached). */
const tt_camera *tt_scene_camera(const tt_scene *s) { return s ? &s->camera : NULL; }

/* Cubic Hermite with Catmull-Rom tangents scaled to non-uniform key spacing, so uneven
 * timing does not make the camera overshoot; u = 0 returns p1 exactly. */
static double tt__hermite(double p0, double p1, double p2, double p3, double t0, double t1,
                          double t2, double t3, double u) {
  double dt = t2 - t1;
  double m1 = (t2 > t0) ? (p2 - p0) / (t2 - t0) * dt : 0.0;
  double m2 = (t3 > t1) ? (p3 - p1) / (t3 - t1) * dt : 0.0;
  double u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * p1 + (u3 - 2 * u2 + u) * m1 + (-2 * u3 + 3 * u2) * p2 +
         (u3 - u2) * m2;
}

/* Keys are clamped at both ends; up is re-normalised and fov kept inside (0, 180). */
void tt_scene_camera_at(const tt_scene *s, double t, tt_camera *out) {
  if (!s || !out) return;
  *out = s->camera;
  uint32_t n = s->camera.key_count;
  if (n == 0) return;
  const tt_camera_key *k = s->keys;
  const tt_camera_key *key = NULL;
  if (n == 1 || !(t > k[0].time)) key = &k[0];
  else if (t >= k[n - 1].time) key = &k[n - 1];
  if (key) {
    memcpy(out->position, key->position, sizeof out->position);
    memcpy(out->target, key->target, sizeof out->target);
    memcpy(out->up, key->up, sizeof out->up);
    out->fov_y = key->fov_y;
  } else {
    uint32_t i = 0;
    while (i + 2 < n && t >= k[i + 1].time) i++; /* k[i].time <= t < k[i+1].time */
    const tt_camera_key *a = &k[i > 0 ? i - 1 : i], *b = &k[i], *c = &k[i + 1];
    const tt_camera_key *d = &k[i + 2 < n ? i + 2 : i + 1];
    double u = (t - b->time) / ((double)c->time - b->time);
#define TT__INTERP(field, j)                                                                       \
  (float)tt__hermite(a->field[j], b->field[j], c->field[j], d->field[j], a->time, b->time,         \
                     c->time, d->time, u)
    for (int j = 0; j < 3; j++) {
      out->position[j] = TT__INTERP(position, j);
      out->target[j] = TT__INTERP(target, j);
      out->up[j] = TT__INTERP(up, j);
    }
#undef TT__INTERP
    out->fov_y = (float)tt__hermite(a->fov_y, b->fov_y, c->fov_y, d->fov_y, a->time, b->time,
                                    c->time, d->time, u);
  }
  double len = sqrt((double)out->up[0] * out->up[0] + (double)out->up[1] * out->up[1] +
                    (double)out->up[2] * out->up[2]);
  if (len > 0)
    for (int j = 0; j < 3; j++) out->up[j] = (float)(out->up[j] / len);
  if (out->fov_y < 1e-3f) out->fov_y = 1e-3f;
  if (out->fov_y > 179.999f) out->fov_y = 179.999f;
}

/* Pose only: resolution and the camera path stay the scene's own. */
void tt_scene_set_camera(tt_scene *s, const tt_camera *c) {
  if (!s || !c) return;
  memcpy(s->camera.position, c->position, sizeof s->camera.position);
  memcpy(s->camera.target, c->target, sizeof s->camera.target);
  memcpy(s->camera.up, c->up, sizeof s->camera.up);
  s->camera.fov_y = c->fov_y;
}

/* Both dimensions must be positive; the limit keeps width*height*4 floats addressable. */
tt_status tt_scene_set_resolution(tt_scene *s, uint32_t width, uint32_t height) {
  if (!s) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_scene_set_resolution: scene is NULL");
  if (width == 0 || height == 0 || width > 65536 || height > 65536)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_scene_set_resolution: expected 1..65536 x 1..65536, got %ux%u", width,
                        height);
  s->camera.width = width;
  s->camera.height = height;
  return TT_OK;
}

/* Render settings from the scene file (defaults spp 16, maxDepth 3, seed 1). */
const tt_render_settings *tt_scene_settings(const tt_scene *s) { return s ? &s->settings : NULL; }
