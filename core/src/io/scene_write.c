/* scene.json v1 writer (format: scenes/README.md): writes a loaded, flattened scene so that
 * tt_scene_load reads back the same meshes, materials, lights, camera and settings. Meshes
 * go to binary little-endian PLY files in meshes/ next to the JSON (read back through
 * assimp, core/src/io/mesh_import.c); textures and environment images are referenced by
 * absolute path. Used by `host --convert`. */
#include "scene/scene_internal.h"
#include "plugin/log.h"

#include <tunetrace/file.h>

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define TT__PI 3.14159265358979323846

/* Writer state: the output stream, the file named in messages and warnings. */
typedef struct tt__wctx {
  FILE *f;
  const char *path;
} tt__wctx;

/* Warns through the log host (values clamped to the loader's ranges, dropped lights). */
static void tt__wwarn(const tt__wctx *w, const char *what, const char *why) {
  tt__log(TT_LOG_WARN, "%s: %s: %s", w->path, what, why);
}

/* Writes a JSON string literal with the escapes JSON requires. */
static void tt__wstr(FILE *f, const char *s) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p; p++) {
    if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
    else if (*p == '\n') fputs("\\n", f);
    else if (*p == '\t') fputs("\\t", f);
    else if (*p < 0x20) fprintf(f, "\\u%04x", *p);
    else fputc(*p, f);
  }
  fputc('"', f);
}

/* A float printed with 9 significant digits reads back as the same float. */
static void tt__wnum(FILE *f, float v) { fprintf(f, "%.9g", isfinite(v) ? (double)v : 0.0); }

/* "[a, b, c]" of n floats. */
static void tt__wvec(FILE *f, const float *v, int n) {
  fputc('[', f);
  for (int i = 0; i < n; i++) {
    if (i) fputs(", ", f);
    tt__wnum(f, v[i]);
  }
  fputc(']', f);
}

/* A number clamped to [lo, hi] (warning when clamped); clamped values are written with
 * 17 digits so a double bound such as pi/2 stays inside the loader's range. */
static void tt__wclamped(const tt__wctx *w, const char *what, float v, double lo, double hi) {
  double d = isfinite(v) ? (double)v : lo;
  if (d < lo || d > hi || !isfinite(v)) {
    tt__wwarn(w, what, "value outside the scene.json range, clamped");
    fprintf(w->f, "%.17g", d < lo ? lo : hi);
  } else {
    tt__wnum(w->f, v);
  }
}

/* "[a, b, c]" with each component clamped as in tt__wclamped. */
static void tt__wvec_clamped(const tt__wctx *w, const char *what, const float *v, int n, double lo,
                             double hi) {
  fputc('[', w->f);
  for (int i = 0; i < n; i++) {
    if (i) fputs(", ", w->f);
    tt__wclamped(w, what, v[i], lo, hi);
  }
  fputc(']', w->f);
}

/* Absolute form of an asset path (realpath when the file exists, else unchanged). */
static char *tt__wabs(const char *path) {
  char *real = realpath(path, NULL);
  return real ? real : tt__strdup(path);
}

/* ---- PLY ------------------------------------------------------------------------------- */

/* Appends a 32-bit value little-endian regardless of the host byte order. */
static void tt__put_u32(unsigned char *b, uint32_t v) {
  b[0] = (unsigned char)(v & 0xff);
  b[1] = (unsigned char)((v >> 8) & 0xff);
  b[2] = (unsigned char)((v >> 16) & 0xff);
  b[3] = (unsigned char)((v >> 24) & 0xff);
}

/* Float bits little-endian. */
static void tt__put_f32(unsigned char *b, float v) {
  uint32_t u;
  memcpy(&u, &v, sizeof u);
  tt__put_u32(b, u);
}

/* Writes one mesh as binary little-endian PLY: positions, normals and uvs when present,
 * triangles as uchar-counted uint lists. Each vertex starts with a uchar "guard" byte 'T':
 * assimp 5.2 skips whitespace after end_header, so a first float whose low byte is e.g.
 * 0x0a would shift (and crash) the whole binary body; readers ignore the extra property. */
static tt_status tt__write_ply(const tt_mesh *m, const char *file, const char *json_path) {
  tt_atomic_file *af;
  if (tt_atomic_file_open(file, &af) != TT_OK) {
    char why[1024];
    snprintf(why, sizeof why, "%s", tt_last_error());
    return tt_set_error(TT_ERR_IO, "%s: cannot write mesh file \"%s\": %s", json_path, file, why);
  }
  FILE *f = tt_atomic_file_stream(af);
  fprintf(f, "ply\nformat binary_little_endian 1.0\ncomment written by tunetrace\n");
  fprintf(f,
          "element vertex %u\nproperty uchar guard\nproperty float x\nproperty float y\nproperty "
          "float z\n",
          m->vertex_count);
  if (m->normals) fprintf(f, "property float nx\nproperty float ny\nproperty float nz\n");
  if (m->uvs) fprintf(f, "property float u\nproperty float v\n");
  fprintf(f, "element face %u\nproperty list uchar uint vertex_indices\nend_header\n",
          m->triangle_count);
  unsigned char buf[40];
  for (uint32_t v = 0; v < m->vertex_count; v++) {
    size_t n = 1;
    buf[0] = 'T';
    for (int a = 0; a < 3; a++, n += 4) tt__put_f32(buf + n, m->positions[3 * (size_t)v + a]);
    if (m->normals)
      for (int a = 0; a < 3; a++, n += 4) tt__put_f32(buf + n, m->normals[3 * (size_t)v + a]);
    if (m->uvs)
      for (int a = 0; a < 2; a++, n += 4) tt__put_f32(buf + n, m->uvs[2 * (size_t)v + a]);
    fwrite(buf, 1, n, f);
  }
  for (uint32_t t = 0; t < m->triangle_count; t++) {
    buf[0] = 3;
    for (int c = 0; c < 3; c++) tt__put_u32(buf + 1 + 4 * c, m->indices[3 * (size_t)t + c]);
    fwrite(buf, 1, 13, f);
  }
  if (tt_atomic_file_commit(af) != TT_OK) {
    char why[1024];
    snprintf(why, sizeof why, "%s", tt_last_error());
    return tt_set_error(TT_ERR_IO, "%s: error writing mesh file \"%s\": %s", json_path, file, why);
  }
  return TT_OK;
}

/* File name for mesh i: "meshes/<index>_<name>.ply" with anything but [A-Za-z0-9-] made '_'. */
static void tt__mesh_file_name(char *buf, size_t n, uint32_t i, const char *name) {
  int w = snprintf(buf, n, "meshes/%u_", i);
  size_t at = w > 0 ? (size_t)w : 0;
  for (const char *p = name ? name : ""; *p && at + 5 < n && at < 80; p++) {
    char c = *p;
    int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-';
    buf[at++] = ok ? c : '_';
  }
  buf[at] = '\0';
  strcat(buf, ".ply");
}

/* ---- sections -------------------------------------------------------------------------- */

/* The still camera and its path keys. */
static void tt__wcamera(const tt__wctx *w, const tt_camera *c) {
  FILE *f = w->f;
  fputs("  \"camera\": {\n    \"position\": ", f);
  tt__wvec(f, c->position, 3);
  fputs(",\n    \"target\": ", f);
  tt__wvec(f, c->target, 3);
  fputs(",\n    \"up\": ", f);
  tt__wvec(f, c->up, 3);
  fputs(",\n    \"fov\": ", f);
  tt__wnum(f, c->fov_y);
  fprintf(f, ",\n    \"resolution\": [%u, %u]", c->width, c->height);
  if (c->key_count && c->keys) {
    fputs(",\n    \"path\": [", f);
    for (uint32_t i = 0; i < c->key_count; i++) {
      const tt_camera_key *k = &c->keys[i];
      fputs(i ? ",\n      {\"time\": " : "\n      {\"time\": ", f);
      tt__wnum(f, k->time);
      fputs(", \"position\": ", f);
      tt__wvec(f, k->position, 3);
      fputs(", \"target\": ", f);
      tt__wvec(f, k->target, 3);
      fputs(", \"up\": ", f);
      tt__wvec(f, k->up, 3);
      fputs(", \"fov\": ", f);
      tt__wnum(f, k->fov_y);
      fputc('}', f);
    }
    fputs("\n    ]", f);
  }
  fputs("\n  },\n", f);
}

/* Render settings, clamped to the loader's ranges. */
static void tt__wrender(const tt__wctx *w, const tt_render_settings *s) {
  uint32_t spp = s->spp < 1 ? 1 : s->spp > (1u << 24) ? (1u << 24) : s->spp;
  uint32_t depth = s->max_depth > 1024 ? 1024 : s->max_depth;
  uint64_t seed = s->seed;
  if (seed > (1ull << 53)) {
    tt__wwarn(w, "render.seed", "seed above 2^53, reduced modulo 2^53");
    seed %= (1ull << 53);
  }
  double budget = s->time_budget_s > 0 && isfinite(s->time_budget_s) ? s->time_budget_s : 0.0;
  fprintf(w->f,
          "  \"render\": {\"spp\": %u, \"maxDepth\": %u, \"seed\": %llu, \"timeBudget\": %.17g},\n",
          spp, depth, (unsigned long long)seed, budget);
}

/* Material keys must be unique, non-empty and not start with '_' (a comment to the
 * loader); others get "material<i>". Returns malloc'ed names, one per material. */
static char **tt__material_keys(const tt_scene *s) {
  char **keys = calloc(s->material_count ? s->material_count : 1, sizeof *keys);
  if (!keys) return NULL;
  for (uint32_t i = 0; i < s->material_count; i++) {
    const char *n = s->materials[i].name;
    int ok = n && n[0] && n[0] != '_';
    for (uint32_t j = 0; ok && j < i; j++) ok = strcmp(keys[j], n) != 0;
    char gen[64];
    if (!ok) {
      /* a generated name could itself collide with a later real name: add a counter */
      for (unsigned extra = 0;; extra++) {
        if (extra) snprintf(gen, sizeof gen, "material%u_%u", i, extra);
        else snprintf(gen, sizeof gen, "material%u", i);
        int clash = 0;
        for (uint32_t j = 0; j < s->material_count && !clash; j++)
          clash = (j < i ? keys[j] : s->materials[j].name) &&
                  strcmp(j < i ? keys[j] : s->materials[j].name, gen) == 0;
        if (!clash) break;
      }
      n = gen;
    }
    keys[i] = tt__strdup(n);
    if (!keys[i]) {
      for (uint32_t j = 0; j < i; j++) free(keys[j]);
      free(keys);
      return NULL;
    }
  }
  return keys;
}

/* All materials in index order, every field written so no default is relied upon. */
static tt_status tt__wmaterials(const tt__wctx *w, const tt_scene *s, char **keys) {
  static const char *const types[] = {"",           "diffuse", "conductor",
                                      "dielectric", "mirror",  "plastic"};
  FILE *f = w->f;
  fputs("  \"materials\": {", f);
  for (uint32_t i = 0; i < s->material_count; i++) {
    const tt_material *m = &s->materials[i];
    int t = (int)m->type;
    if (t < 1 || t > 5)
      return tt_set_error(TT_ERR_UNSUPPORTED, "%s: material \"%s\" has an unknown type %d", w->path,
                          keys[i], t);
    fputs(i ? ",\n    " : "\n    ", f);
    tt__wstr(f, keys[i]);
    fprintf(f, ": {\"type\": \"%s\", \"albedo\": ", types[t]);
    tt__wvec_clamped(w, "material albedo", m->albedo, 3, 0.0, 1.0);
    if (m->albedo_texture >= 0 && (uint32_t)m->albedo_texture < s->texture_count) {
      char *abs = tt__wabs(s->textures[m->albedo_texture].path);
      if (!abs) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", w->path);
      fputs(", \"texture\": ", f);
      tt__wstr(f, abs);
      free(abs);
    }
    fputs(",\n      \"roughness\": ", f);
    tt__wclamped(w, "material roughness", m->roughness, 0.0, TT__PI / 2);
    fputs(", \"alpha\": ", f);
    tt__wvec_clamped(w, "material alpha", m->alpha, 2, 0.0, 1.0);
    fputs(", \"eta\": ", f);
    tt__wvec_clamped(w, "material eta", m->eta, 3, 1e-30, 1e30);
    fputs(", \"k\": ", f);
    tt__wvec_clamped(w, "material k", m->k, 3, 0.0, 1e30);
    fputs(", \"ior\": ", f);
    tt__wclamped(w, "material ior", m->ior, 1e-30, 1e30);
    fputs(",\n      \"specular\": ", f);
    tt__wvec_clamped(w, "material specular", m->specular, 3, 0.0, 1.0);
    fputs(", \"emission\": ", f);
    tt__wvec_clamped(w, "material emission", m->emission, 3, 0.0, 1e30);
    fprintf(f, ", \"twoSided\": %s}", m->two_sided ? "true" : "false");
  }
  fputs("\n  },\n", f);
  return TT_OK;
}

/* Mesh entries referencing PLY files written into <dir>/meshes/. */
static tt_status tt__wmeshes(const tt__wctx *w, const tt_scene *s, char **keys, const char *dir) {
  FILE *f = w->f;
  size_t dl = strlen(dir);
  char *mdir = malloc(dl + 16);
  if (!mdir) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", w->path);
  snprintf(mdir, dl + 16, "%s/meshes", dir);
  if (mkdir(mdir, 0777) != 0 && errno != EEXIST) {
    tt_status st = tt_set_error(TT_ERR_IO, "%s: cannot create folder \"%s\": %s", w->path, mdir,
                                strerror(errno));
    free(mdir);
    return st;
  }
  free(mdir);
  fputs("  \"meshes\": [", f);
  int first = 1;
  for (uint32_t i = 0; i < s->mesh_count; i++) {
    const tt_mesh *m = &s->meshes[i];
    double area = m->triangle_count ? tt__mesh_area(m) : 0.0;
    if (!(area > 0) || !isfinite(area)) { /* the loader rejects such meshes */
      tt__wwarn(w, m->name ? m->name : "mesh",
                "mesh of zero area (all triangles degenerate) skipped");
      continue;
    }
    char rel[128];
    tt__mesh_file_name(rel, sizeof rel, i, m->name);
    char *full = malloc(dl + sizeof rel + 2);
    if (!full) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", w->path);
    snprintf(full, dl + sizeof rel + 2, "%s/%s", dir, rel);
    tt_status st = tt__write_ply(m, full, w->path);
    free(full);
    if (st != TT_OK) return st;
    fputs(first ? "\n    {" : ",\n    {", f);
    first = 0;
    if (m->name && m->name[0]) { /* the loader rejects "", and names unnamed meshes itself */
      fputs("\"name\": ", f);
      tt__wstr(f, m->name);
      fputs(", ", f);
    }
    fputs("\"material\": ", f);
    tt__wstr(f, keys[m->material < s->material_count ? m->material : 0]);
    fputs(", \"file\": ", f);
    tt__wstr(f, rel);
    fputc('}', f);
  }
  fputs("\n  ],\n", f);
  return TT_OK;
}

/* Explicit lights; area lights are implied by emissive materials and not written. */
static tt_status tt__wlights(const tt__wctx *w, const tt_scene *s) {
  FILE *f = w->f;
  int first = 1, env = 0;
  fputs("  \"lights\": [", f);
  for (uint32_t i = 0; i < s->light_count; i++) {
    const tt_light *l = &s->lights[i];
    if (l->type == TT_LIGHT_AREA) continue;
    if (l->type == TT_LIGHT_ENV_CONSTANT || l->type == TT_LIGHT_ENV_IMAGE) {
      if (env++) {
        tt__wwarn(w, "lights", "only one environment light is allowed, extra one dropped");
        continue;
      }
    }
    fputs(first ? "\n    {" : ",\n    {", f);
    first = 0;
    switch (l->type) {
    case TT_LIGHT_ENV_CONSTANT:
    case TT_LIGHT_ENV_IMAGE:
      fputs("\"type\": \"environment\", \"radiance\": ", f);
      tt__wvec_clamped(w, "environment radiance", l->radiance, 3, 0.0, 1e30);
      if (l->type == TT_LIGHT_ENV_IMAGE && l->image) {
        char *abs = tt__wabs(l->image);
        if (!abs) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", w->path);
        fputs(", \"image\": ", f);
        tt__wstr(f, abs);
        free(abs);
      }
      break;
    case TT_LIGHT_POINT:
    case TT_LIGHT_SPOT: {
      fprintf(f, "\"type\": \"%s\", \"position\": ", l->type == TT_LIGHT_POINT ? "point" : "spot");
      tt__wvec(f, l->position, 3);
      fputs(", \"intensity\": ", f);
      tt__wvec_clamped(w, "light intensity", l->radiance, 3, 0.0, 1e30);
      if (l->type == TT_LIGHT_SPOT) {
        double co = l->cos_outer > 1 ? 1 : l->cos_outer < -1 ? -1 : l->cos_outer;
        double ci = l->cos_inner > 1 ? 1 : l->cos_inner < -1 ? -1 : l->cos_inner;
        double outer = acos(co) * 180.0 / TT__PI, inner = acos(ci) * 180.0 / TT__PI;
        if (!(outer > 0) || outer > 90) {
          tt__wwarn(w, "spot light angle", "outside (0, 90] degrees, clamped");
          outer = outer > 90 ? 90 : 1e-6;
        }
        if (inner > outer) inner = outer;
        fputs(", \"direction\": ", f);
        tt__wvec(f, l->direction, 3);
        fprintf(f, ", \"angle\": %.17g, \"innerAngle\": %.17g", outer, inner);
      }
      break;
    }
    case TT_LIGHT_DISTANT:
      fputs("\"type\": \"distant\", \"direction\": ", f);
      tt__wvec(f, l->direction, 3);
      fputs(", \"irradiance\": ", f);
      tt__wvec_clamped(w, "light irradiance", l->radiance, 3, 0.0, 1e30);
      break;
    default:
      return tt_set_error(TT_ERR_UNSUPPORTED, "%s: light %u has an unknown type %d", w->path, i,
                          (int)l->type);
    }
    fputc('}', f);
  }
  fputs("\n  ]\n", f);
  return TT_OK;
}

/* ---- entry point ----------------------------------------------------------------------- */

/* Writes <path> and <dir of path>/meshes/<i>_<name>.ply, each atomically (tunetrace/file.h)
 * so a failed or killed write never leaves a truncated scene. */
tt_status tt_scene_write_json(const tt_scene *scene, const char *path) {
  if (!scene || !path || !path[0])
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_scene_write_json: %s is NULL or empty",
                        !scene ? "scene" : "path");
  /* converting a scene onto its own file would destroy the input */
  if (tt_scene_source(scene) &&
      tt_file_check_not_input(path, "converted scene", tt_scene_source(scene),
                              "scene file it was loaded from") != TT_OK)
    return TT_ERR_INVALID_ARGUMENT;
  const char *slash = strrchr(path, '/');
  size_t dl = slash ? (size_t)(slash - path) : 1;
  char *dir = malloc(dl + 2);
  char **keys = tt__material_keys(scene);
  tt_status st = TT_OK;
  FILE *f = NULL;
  tt_atomic_file *af = NULL;
  if (!dir || !keys) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    goto done;
  }
  if (slash) memcpy(dir, path, dl);
  else dir[0] = '.';
  if (slash && dl == 0) dir[dl++] = '/'; /* "/scene.json" */
  dir[dl] = '\0';
  if (tt_atomic_file_open(path, &af) != TT_OK) {
    st = TT_ERR_IO;
    goto done;
  }
  f = tt_atomic_file_stream(af);
  tt__wctx w = {f, path};
  fputs("{\n  \"version\": 1,\n  \"_comment\": ", f);
  char note[1200];
  snprintf(note, sizeof note, "converted by tunetrace from %s",
           tt_scene_source(scene) ? tt_scene_source(scene) : "(unknown)");
  tt__wstr(f, note);
  fputs(",\n", f);
  tt__wcamera(&w, tt_scene_camera(scene));
  tt__wrender(&w, tt_scene_settings(scene));
  if ((st = tt__wmaterials(&w, scene, keys)) != TT_OK) goto done;
  if ((st = tt__wmeshes(&w, scene, keys, dir)) != TT_OK) goto done;
  if ((st = tt__wlights(&w, scene)) != TT_OK) goto done;
  fputs("}\n", f);
  st = tt_atomic_file_commit(af); /* names the path and the OS reason on failure */
  af = NULL;
done:
  tt_atomic_file_abort(af);
  if (keys)
    for (uint32_t i = 0; i < scene->material_count; i++) free(keys[i]);
  free(keys);
  free(dir);
  return st;
}
