/* Mesh files flattened to triangle arrays: PLY through the library's own reader (io/ply),
 * OBJ, glTF and whatever else assimp reads through assimp, each file only as the format its
 * extension names (io/assimp_read.h). Materials in the file are ignored: the scene.json
 * entry chooses the material. */
#include "io/assimp_read.h"
#include "io/io_internal.h"
#include "io/ply/ply.h"
#include "util/json_error.h"

#include <tunetrace/file.h>

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cjson/cJSON.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One placement of an assimp mesh by the node hierarchy. */
typedef struct tt__ai_instance {
  unsigned mesh;
  double m[16];     /* row-major node-to-file-root matrix */
  const char *name; /* mesh name, else node name, may be "" */
} tt__ai_instance;

typedef struct tt__ai_list {
  tt__ai_instance *items;
  uint32_t count, cap;
} tt__ai_list;

/* Counts usable triangles (assimp keeps points and lines as separate primitives). */
static uint32_t tt__ai_triangles(const struct aiMesh *m) {
  uint32_t n = 0;
  for (unsigned f = 0; f < m->mNumFaces; f++) n += m->mFaces[f].mNumIndices == 3;
  return n;
}

/* Walks the node tree accumulating transforms, so glTF/FBX node placements survive and
 * each placed mesh stays a separate part for split mode. Depth is bounded against cyclic
 * or absurd files. */
static int tt__ai_collect(const struct aiScene *sc, const struct aiNode *node,
                          const double parent[16], int depth, tt__ai_list *list) {
  if (!node || depth > 256) return 1;
  const struct aiMatrix4x4 *t = &node->mTransformation;
  double local[16] = {t->a1, t->a2, t->a3, t->a4, t->b1, t->b2, t->b3, t->b4,
                      t->c1, t->c2, t->c3, t->c4, t->d1, t->d2, t->d3, t->d4};
  double m[16];
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) {
      double s = 0;
      for (int k = 0; k < 4; k++) s += parent[4 * i + k] * local[4 * k + j];
      m[4 * i + j] = s;
    }
  for (unsigned i = 0; i < node->mNumMeshes; i++) {
    unsigned mi = node->mMeshes[i];
    if (mi >= sc->mNumMeshes || tt__ai_triangles(sc->mMeshes[mi]) == 0) continue;
    tt__ai_instance *inst =
        tt__scene_push((void **)&list->items, &list->count, &list->cap, sizeof *inst);
    if (!inst) return 0;
    inst->mesh = mi;
    memcpy(inst->m, m, sizeof m);
    inst->name = sc->mMeshes[mi]->mName.length ? sc->mMeshes[mi]->mName.data : node->mName.data;
  }
  for (unsigned c = 0; c < node->mNumChildren; c++)
    if (!tt__ai_collect(sc, node->mChildren[c], m, depth + 1, list)) return 0;
  return 1;
}

/* Copies one placed assimp mesh into a mesh_data in file-root space. */
static tt_status tt__ai_part(const struct aiScene *sc, const tt__ai_instance *inst,
                             const char *where, tt__mesh_data *out) {
  const struct aiMesh *m = sc->mMeshes[inst->mesh];
  uint32_t nv = m->mNumVertices, nt = tt__ai_triangles(m);
  memset(out, 0, sizeof *out);
  if (nt > UINT32_MAX / 3) return tt_set_error(TT_ERR_UNSUPPORTED, "%s: mesh too large", where);
  out->vertex_count = nv;
  out->triangle_count = nt;
  out->positions = malloc(3 * sizeof(float) * (nv ? nv : 1));
  out->indices = malloc(3 * sizeof(uint32_t) * (nt ? nt : 1));
  if (m->mNormals) out->normals = malloc(3 * sizeof(float) * (nv ? nv : 1));
  if (m->mTextureCoords[0]) out->uvs = malloc(2 * sizeof(float) * (nv ? nv : 1));
  if (!out->positions || !out->indices || (m->mNormals && !out->normals) ||
      (m->mTextureCoords[0] && !out->uvs)) {
    tt__mesh_data_free(out);
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
  }
  for (uint32_t v = 0; v < nv; v++) {
    float *p = out->positions + 3 * (size_t)v;
    p[0] = m->mVertices[v].x;
    p[1] = m->mVertices[v].y;
    p[2] = m->mVertices[v].z;
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
      tt__mesh_data_free(out);
      return tt_set_error(TT_ERR_PARSE, "%s: non-finite vertex position", where);
    }
    if (out->normals) {
      float *n = out->normals + 3 * (size_t)v;
      double x = m->mNormals[v].x, y = m->mNormals[v].y, z = m->mNormals[v].z;
      double len = sqrt(x * x + y * y + z * z);
      /* files sometimes carry zero normals; a fixed unit vector is safer than NaN */
      if (!(len > 0) || !isfinite(len)) x = 0, y = 0, z = 1, len = 1;
      n[0] = (float)(x / len);
      n[1] = (float)(y / len);
      n[2] = (float)(z / len);
    }
    if (out->uvs) {
      out->uvs[2 * (size_t)v] = m->mTextureCoords[0][v].x;
      out->uvs[2 * (size_t)v + 1] = m->mTextureCoords[0][v].y;
    }
  }
  uint32_t t = 0;
  for (unsigned f = 0; f < m->mNumFaces; f++) {
    const struct aiFace *face = &m->mFaces[f];
    if (face->mNumIndices != 3) continue;
    for (int c = 0; c < 3; c++) {
      if (face->mIndices[c] >= nv) {
        tt__mesh_data_free(out);
        return tt_set_error(TT_ERR_PARSE, "%s: face index out of range", where);
      }
      out->indices[3 * (size_t)t + c] = face->mIndices[c];
    }
    t++;
  }
  static const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  if (memcmp(inst->m, id, sizeof id) != 0 && tt__mesh_data_transform(out, inst->m) != TT_OK) {
    tt__mesh_data_free(out);
    return tt_set_error(TT_ERR_PARSE, "%s: node transform is singular or not affine", where);
  }
  return TT_OK;
}

/* Concatenates parts into one; normals/uvs survive only if every part has them, since a
 * partial attribute array would be meaningless. Frees the parts. */
static tt_status tt__ai_merge(tt__mesh_data *parts, uint32_t count, const char *where,
                              tt__mesh_data *out) {
  uint64_t nv = 0, nt = 0;
  int has_n = 1, has_uv = 1;
  for (uint32_t i = 0; i < count; i++) {
    nv += parts[i].vertex_count;
    nt += parts[i].triangle_count;
    has_n &= parts[i].normals != NULL;
    has_uv &= parts[i].uvs != NULL;
  }
  memset(out, 0, sizeof *out);
  tt_status st = TT_OK;
  if (nv > UINT32_MAX || nt > UINT32_MAX / 3) {
    st = tt_set_error(TT_ERR_UNSUPPORTED, "%s: mesh too large (%llu vertices)", where,
                      (unsigned long long)nv);
    goto done;
  }
  out->vertex_count = (uint32_t)nv;
  out->triangle_count = (uint32_t)nt;
  out->positions = malloc(3 * sizeof(float) * (nv ? nv : 1));
  out->indices = malloc(3 * sizeof(uint32_t) * (nt ? nt : 1));
  if (has_n) out->normals = malloc(3 * sizeof(float) * (nv ? nv : 1));
  if (has_uv) out->uvs = malloc(2 * sizeof(float) * (nv ? nv : 1));
  if (!out->positions || !out->indices || (has_n && !out->normals) || (has_uv && !out->uvs)) {
    tt__mesh_data_free(out);
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
    goto done;
  }
  size_t v0 = 0, t0 = 0;
  for (uint32_t i = 0; i < count; i++) {
    const tt__mesh_data *p = &parts[i];
    memcpy(out->positions + 3 * v0, p->positions, 3 * sizeof(float) * p->vertex_count);
    if (has_n) memcpy(out->normals + 3 * v0, p->normals, 3 * sizeof(float) * p->vertex_count);
    if (has_uv) memcpy(out->uvs + 2 * v0, p->uvs, 2 * sizeof(float) * p->vertex_count);
    for (size_t k = 0; k < 3 * (size_t)p->triangle_count; k++)
      out->indices[3 * t0 + k] = (uint32_t)v0 + p->indices[k];
    v0 += p->vertex_count;
    t0 += p->triangle_count;
  }
done:
  for (uint32_t i = 0; i < count; i++) tt__mesh_data_free(&parts[i]);
  return st;
}

/* Unit shading normals as assimp's path gives them: zero or non-finite ones become +z. */
static void tt__normalize_normals(tt__mesh_data *d) {
  for (uint32_t v = 0; d->normals && v < d->vertex_count; v++) {
    float *n = d->normals + 3 * (size_t)v;
    double x = n[0], y = n[1], z = n[2], len = sqrt(x * x + y * y + z * z);
    if (!(len > 0) || !isfinite(len)) x = 0, y = 0, z = 1, len = 1;
    n[0] = (float)(x / len);
    n[1] = (float)(y / len);
    n[2] = (float)(z / len);
  }
}

/* A PLY through the library's own reader (io/ply): one part named like assimp's. */
static tt_status tt__ply_import(const char *file, const char *base_name, int split,
                                const char *where, tt__mesh_data **out, uint32_t *count) {
  tt__mesh_data *one = calloc(1, sizeof *one);
  if (!one) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
  tt_status st = tt__ply_read(file, where, one);
  if (st == TT_OK && one->triangle_count == 0)
    st = tt_set_error(TT_ERR_PARSE, "%s: mesh file \"%s\" contains no triangles", where, file);
  if (st == TT_OK) {
    tt__normalize_normals(one);
    char name[512];
    if (split) snprintf(name, sizeof name, "%s/0", base_name);
    else snprintf(name, sizeof name, "%s", base_name);
    if (!(one->name = tt__strdup(name)))
      st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
  }
  if (st != TT_OK) {
    tt__mesh_data_free(one);
    free(one);
    return st;
  }
  *out = one;
  *count = 1;
  return TT_OK;
}

/* What a file's first bytes look like, for a message about content that does not match
 * its name; NULL if nothing is recognised. */
static const char *tt__mesh_sniff(const unsigned char *b, size_t n) {
  if (n >= 4 && memcmp(b, "glTF", 4) == 0) return "a GLB (binary glTF) file";
  if (n >= 4 && memcmp(b, "ply", 3) == 0 && (b[3] == '\n' || b[3] == '\r')) return "a PLY file";
  if (n >= 4 && memcmp(b, "\x89PNG", 4) == 0) return "a PNG image";
  if (n >= 4 && memcmp(b, "\x76\x2f\x31\x01", 4) == 0) return "an OpenEXR image";
  return NULL;
}

static uint32_t tt__le32(const unsigned char *b) {
  return b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* Every chunk of a GLB 2 container (8-byte header: length, type) must lie inside the
 * declared length, the first one JSON. assimp 5.2.5 allocates and zero-fills a chunk's
 * declared length before it reads it: a 577-byte file declaring a 4 GiB JSON chunk made it
 * take 4 GiB (found by fuzz_mesh in CI). */
static tt_status tt__glb_chunks_check(FILE *f, const char *file, const char *where,
                                      uint32_t length) {
  uint64_t at = 12;
  for (unsigned i = 0; at < length; i++) {
    unsigned char c[8];
    if (length - at < 8 || fseek(f, (long)at, SEEK_SET) != 0 || fread(c, 1, 8, f) != 8)
      return tt_set_error(
          TT_ERR_PARSE,
          "%s: mesh file \"%s\": GLB chunk %u at byte %llu: expected an 8-byte chunk "
          "header inside the declared %u bytes",
          where, file, i, (unsigned long long)at, length);
    uint32_t clen = tt__le32(c), type = tt__le32(c + 4);
    if (i == 0 && type != 0x4E4F534Au) /* "JSON" */
      return tt_set_error(
          TT_ERR_PARSE,
          "%s: mesh file \"%s\": GLB chunk 0 must be the JSON chunk (type 0x4E4F534A), "
          "got type 0x%08X",
          where, file, type);
    if ((uint64_t)clen > length - at - 8)
      return tt_set_error(
          TT_ERR_PARSE,
          "%s: mesh file \"%s\": GLB chunk %u at byte %llu declares %u bytes, only %llu "
          "remain of the declared %u (corrupt or cut short?)",
          where, file, i, (unsigned long long)at, clen, (unsigned long long)(length - at - 8),
          length);
    at += 8 + (uint64_t)clen;
  }
  return TT_OK;
}

/* A .glb must start with the GLB header (magic "glTF", version, total length), hold the
 * length it declares, and its chunks (GLB 2) or its JSON content (GLB 1) must fit in it. */
static tt_status tt__glb_check(const char *file, const char *where) {
  FILE *f = fopen(file, "rb");
  if (!f)
    return tt_set_error(TT_ERR_IO, "%s: cannot open mesh file \"%s\": %s", where, file,
                        strerror(errno));
  unsigned char h[20];
  size_t got = fread(h, 1, sizeof h, f);
  long size = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
  uint32_t version = got >= 12 ? tt__le32(h + 4) : 0, length = got >= 12 ? tt__le32(h + 8) : 0;
  tt_status st = TT_OK;
  if (got < 12 || memcmp(h, "glTF", 4) != 0) {
    const char *looks = tt__mesh_sniff(h, got);
    st = tt_set_error(TT_ERR_PARSE,
                      "%s: mesh file \"%s\" is not a GLB file: expected the 12-byte GLB header "
                      "starting with \"glTF\", got %s",
                      where, file,
                      looks      ? looks
                      : got < 12 ? "a file shorter than that"
                                 : "other bytes");
  } else if (version != 1 && version != 2) {
    st = tt_set_error(TT_ERR_UNSUPPORTED, "%s: mesh file \"%s\": GLB version %u (expected 2, or 1)",
                      where, file, version);
  } else if (length < (version == 1 ? 20u : 12u) || size < 0 || (uint64_t)length > (uint64_t)size) {
    st = tt_set_error(TT_ERR_PARSE,
                      "%s: mesh file \"%s\": the GLB header declares %u bytes, the file has %ld "
                      "(cut short?)",
                      where, file, length, size);
  } else if (version == 2) {
    st = tt__glb_chunks_check(f, file, where, length);
  } else if (tt__le32(h + 12) > length - 20) {
    /* GLB 1: a 20-byte header whose content length (the JSON scene) follows the length */
    st =
        tt_set_error(TT_ERR_PARSE,
                     "%s: mesh file \"%s\": the GLB 1 header declares %u bytes of content, only %u "
                     "follow the header (corrupt or cut short?)",
                     where, file, tt__le32(h + 12), length - 20);
  }
  fclose(f);
  return st;
}

/* A .gltf must be a JSON object (glTF's top level); a .glb a GLB container. Checked before
 * assimp so that content of another format gets a message saying what was expected (the
 * glTF readers then check the rest). */
tt_status tt__gltf_check(const char *file, const char *where) {
  if (tt__has_ext(file, ".glb")) return tt__glb_check(file, where);
  if (!tt__has_ext(file, ".gltf")) return TT_OK;
  char *text = NULL;
  size_t len = 0;
  tt_status st = tt_file_read(file, "mesh file", 0, &text, &len);
  if (st != TT_OK) return tt_set_error(st, "%s: %s", where, tt_last_error());
  size_t skip = len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0; /* a UTF-8 BOM */
  const char *end = NULL;
  cJSON *root = cJSON_ParseWithLengthOpts(text + skip, len - skip, &end, 0);
  if (!root || !cJSON_IsObject(root)) {
    char got[96];
    const char *looks = tt__mesh_sniff((const unsigned char *)text, len);
    if (looks) {
      snprintf(got, sizeof got, "%s", looks);
    } else if (!root) {
      unsigned line, col;
      size_t at = end && end >= text + skip ? (size_t)(end - text) : skip;
      tt__json_line_col(text, at, &line, &col);
      snprintf(got, sizeof got, "a JSON syntax error at %u:%u", line, col);
    } else {
      tt__json_describe(root, TT__JSON_SCENE, got, sizeof got);
    }
    st = tt_set_error(TT_ERR_PARSE,
                      "%s: mesh file \"%s\" is not a glTF file: expected a JSON object, got %s",
                      where, file, got);
  }
  cJSON_Delete(root);
  tt_free(text);
  return st;
}

/* Imports, then builds one part per placed mesh and either returns them (split) or merges
 * them into one. PLY files go to the library's fuzzed reader; assimp reads the formats only
 * it reads (OBJ, glTF, FBX, ...), with its data-structure validation step on, and only with
 * the readers of the file's extension. */
tt_status tt__mesh_import(const char *file, const char *base_name, int split, const char *where,
                          tt__mesh_data **out, uint32_t *count) {
  *out = NULL;
  *count = 0;
  /* assimp would block on a FIFO and read /dev/zero forever: regular files only */
  char why[256];
  if (tt__file_regular_reason(file, why, sizeof why) != 0)
    return tt_set_error(TT_ERR_IO, "%s: cannot open mesh file \"%s\": %s", where, file, why);
  if (tt__has_ext(file, ".ply") || tt__has_ext(file, ".ply.gz"))
    return tt__ply_import(file, base_name, split, where, out, count);
  tt_status gst = tt__gltf_check(file, where);
  if (gst != TT_OK) return gst;
  /* ValidateDataStructure rejects out-of-range indices and inconsistent arrays that a
   * corrupt file makes assimp's importers produce, before we walk them */
  tt__assimp *ai = NULL;
  const struct aiScene *sc = NULL;
  char reason[512];
  switch (tt__assimp_read(file,
                          aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                              aiProcess_ValidateDataStructure,
                          &ai, &sc, reason, sizeof reason)) {
  case TT__ASSIMP_OK: break;
  case TT__ASSIMP_UNKNOWN_EXTENSION:
    return tt_set_error(
        TT_ERR_UNSUPPORTED,
        "%s: mesh file \"%s\": unknown mesh format (expected .ply, .obj, .gltf, .glb "
        "or another extension assimp reads, such as .fbx, .dae, .stl)",
        where, file);
  case TT__ASSIMP_OUT_OF_MEMORY:
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: mesh file \"%s\": out of memory", where, file);
  default:
    return tt_set_error(TT_ERR_PARSE, "%s: cannot import mesh file \"%s\": %s", where, file,
                        reason);
  }

  static const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  tt__ai_list list = {NULL, 0, 0};
  tt__mesh_data *parts = NULL;
  tt_status st = TT_OK;
  if (!tt__ai_collect(sc, sc->mRootNode, id, 0, &list)) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
    goto done;
  }
  if (list.count == 0) {
    st = tt_set_error(TT_ERR_PARSE, "%s: mesh file \"%s\" contains no triangles", where, file);
    goto done;
  }
  parts = calloc(list.count, sizeof *parts);
  if (!parts) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
    goto done;
  }
  for (uint32_t i = 0; i < list.count && st == TT_OK; i++) {
    st = tt__ai_part(sc, &list.items[i], where, &parts[i]);
    if (st == TT_OK && split) {
      char name[512];
      int w = list.items[i].name[0]
                  ? snprintf(name, sizeof name, "%s/%s", base_name, list.items[i].name)
                  : snprintf(name, sizeof name, "%s/%u", base_name, i);
      if (w < 0) name[0] = '\0';
      parts[i].name = tt__strdup(name);
      if (!parts[i].name) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
    }
  }
  if (st != TT_OK) {
    for (uint32_t i = 0; i < list.count; i++) tt__mesh_data_free(&parts[i]);
    free(parts);
    parts = NULL;
    goto done;
  }
  if (split) {
    *out = parts;
    *count = list.count;
    parts = NULL;
  } else {
    tt__mesh_data *one = calloc(1, sizeof *one);
    if (!one) {
      for (uint32_t i = 0; i < list.count; i++) tt__mesh_data_free(&parts[i]);
      st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
    } else if ((st = tt__ai_merge(parts, list.count, where, one)) == TT_OK &&
               !(one->name = tt__strdup(base_name))) {
      tt__mesh_data_free(one);
      st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
    }
    if (st == TT_OK) {
      *out = one;
      *count = 1;
    } else {
      free(one);
    }
  }
done:
  free(parts);
  free(list.items);
  tt__assimp_free(ai);
  return st;
}
