/* PLY meshes (ASCII, binary little and big endian, .ply.gz with zlib) read into triangles:
 * the one reader of the pbrt importer's plymesh shapes and of scene.json mesh files (which
 * assimp read before; fuzzing found it crashing and hanging on corrupt PLYs, #13). Every
 * read is bounds-checked against one buffer: a truncated or corrupt file is an error naming
 * it, never a crash; polygons are fanned; one vertex element, sized from its own count. */
#include "io/ply/ply.h"

#include <tunetrace/file.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#ifdef TT_HAVE_ZLIB
#  include <zlib.h>
#endif

/* ---- file reading ---------------------------------------------------------------------- */

/* Whole file into memory, gunzipping ".gz" when zlib is available. Only regular files are
 * read (a FIFO would block, /dev/zero never end), and at most TT_FILE_READ_DEFAULT_MAX bytes,
 * decompressed or not. */
static tt_status tt__read_all(const char *path, const char *where, unsigned char **out,
                              size_t *len) {
  *out = NULL;
  *len = 0;
  size_t n = strlen(path);
  int gz = n > 3 && strcasecmp(path + n - 3, ".gz") == 0;
  size_t cap = 0, used = 0;
  unsigned char *buf = NULL;
  if (gz) {
#ifdef TT_HAVE_ZLIB
    if (tt_file_check_regular(path, "PLY file") != TT_OK) {
      char msg[1024];
      snprintf(msg, sizeof msg, "%s", tt_last_error());
      return tt_set_error(TT_ERR_IO, "%s: %s", where, msg);
    }
    gzFile f = gzopen(path, "rb");
    if (!f)
      return tt_set_error(TT_ERR_IO, "%s: cannot open PLY file \"%s\": %s", where, path,
                          strerror(errno));
    for (;;) {
      if (used + 65536 > cap) {
        if (cap >= TT_FILE_READ_DEFAULT_MAX) {
          free(buf);
          gzclose(f);
          return tt_set_error(TT_ERR_IO, "%s: \"%s\": PLY file decompresses to more than %zu bytes",
                              where, path, (size_t)TT_FILE_READ_DEFAULT_MAX);
        }
        size_t ncap = cap ? cap * 2 : 1 << 20;
        unsigned char *nb = realloc(buf, ncap);
        if (!nb) {
          free(buf);
          gzclose(f);
          return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory reading \"%s\"", where,
                              path);
        }
        buf = nb;
        cap = ncap;
      }
      int got = gzread(f, buf + used, (unsigned)(cap - used));
      if (got < 0) {
        free(buf);
        gzclose(f);
        return tt_set_error(TT_ERR_IO, "%s: \"%s\": corrupt gzip stream", where, path);
      }
      if (got == 0) break;
      used += (size_t)got;
    }
    gzclose(f);
    *out = buf;
    *len = used;
    return TT_OK;
#else
    return tt_set_error(TT_ERR_UNSUPPORTED, "%s: \"%s\": this build has no zlib for .ply.gz files",
                        where, path);
#endif
  }
  /* plain files: the shared reader (regular files only, size-capped), message prefixed */
  char *text = NULL;
  tt_status st = tt_file_read(path, "PLY file", 0, &text, len);
  if (st != TT_OK) {
    char msg[1024];
    snprintf(msg, sizeof msg, "%s", tt_last_error());
    return tt_set_error(st, "%s: %s", where, msg);
  }
  *out = (unsigned char *)text;
  return st;
}

/* ---- PLY ------------------------------------------------------------------------------- */

enum { TT__PLY_ASCII, TT__PLY_LE, TT__PLY_BE };
enum {
  TT__P_NONE = 0,
  TT__P_I8,
  TT__P_U8,
  TT__P_I16,
  TT__P_U16,
  TT__P_I32,
  TT__P_U32,
  TT__P_F32,
  TT__P_F64
};

typedef struct tt__ply_prop {
  char name[32];
  int type;       /* scalar type, or the item type of a list */
  int count_type; /* list count type, TT__P_NONE for scalars */
} tt__ply_prop;

typedef struct tt__ply_elem {
  char name[32];
  uint64_t count;
  tt__ply_prop props[32];
  int prop_count;
} tt__ply_elem;

/* PLY type name to code (both the classic and the sized spellings). */
static int tt__ply_type(const char *s) {
  static const struct {
    const char *n;
    int t;
  } map[] = {
      {"char", TT__P_I8},   {"int8", TT__P_I8},     {"uchar", TT__P_U8},   {"uint8", TT__P_U8},
      {"short", TT__P_I16}, {"int16", TT__P_I16},   {"ushort", TT__P_U16}, {"uint16", TT__P_U16},
      {"int", TT__P_I32},   {"int32", TT__P_I32},   {"uint", TT__P_U32},   {"uint32", TT__P_U32},
      {"float", TT__P_F32}, {"float32", TT__P_F32}, {"double", TT__P_F64}, {"float64", TT__P_F64}};
  for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
    if (strcmp(s, map[i].n) == 0) return map[i].t;
  return TT__P_NONE;
}

/* Byte size of a scalar type. */
static size_t tt__ply_size(int t) {
  switch (t) {
  case TT__P_I8:
  case TT__P_U8: return 1;
  case TT__P_I16:
  case TT__P_U16: return 2;
  case TT__P_I32:
  case TT__P_U32:
  case TT__P_F32: return 4;
  case TT__P_F64: return 8;
  default: return 0;
  }
}

/* Cursor over the body: binary or ASCII, with an end that is never passed. */
typedef struct tt__ply_cur {
  const unsigned char *p, *end;
  int format;
} tt__ply_cur;

/* Reads one scalar as double; 0 at end of data or on a malformed ASCII number. */
static int tt__ply_scalar(tt__ply_cur *c, int t, double *v) {
  if (c->format == TT__PLY_ASCII) {
    while (c->p < c->end && (*c->p == ' ' || *c->p == '\t' || *c->p == '\r' || *c->p == '\n'))
      c->p++;
    if (c->p >= c->end) return 0;
    char tmp[64];
    size_t k = 0;
    while (c->p < c->end && k + 1 < sizeof tmp &&
           !(*c->p == ' ' || *c->p == '\t' || *c->p == '\r' || *c->p == '\n'))
      tmp[k++] = (char)*c->p++;
    tmp[k] = '\0';
    char *e;
    *v = strtod(tmp, &e);
    return e != tmp && *e == '\0';
  }
  size_t n = tt__ply_size(t);
  if (n == 0 || (size_t)(c->end - c->p) < n) return 0;
  unsigned char b[8];
  memcpy(b, c->p, n);
  c->p += n;
  if (c->format == TT__PLY_BE)
    for (size_t i = 0; i < n / 2; i++) {
      unsigned char x = b[i];
      b[i] = b[n - 1 - i];
      b[n - 1 - i] = x;
    }
  switch (t) {
  case TT__P_I8: {
    int8_t x;
    memcpy(&x, b, 1);
    *v = x;
    break;
  }
  case TT__P_U8: *v = b[0]; break;
  case TT__P_I16: {
    int16_t x;
    memcpy(&x, b, 2);
    *v = x;
    break;
  }
  case TT__P_U16: {
    uint16_t x;
    memcpy(&x, b, 2);
    *v = x;
    break;
  }
  case TT__P_I32: {
    int32_t x;
    memcpy(&x, b, 4);
    *v = x;
    break;
  }
  case TT__P_U32: {
    uint32_t x;
    memcpy(&x, b, 4);
    *v = x;
    break;
  }
  case TT__P_F32: {
    float x;
    memcpy(&x, b, 4);
    *v = x;
    break;
  }
  case TT__P_F64: {
    double x;
    memcpy(&x, b, 8);
    *v = x;
    break;
  }
  default: return 0;
  }
  return 1;
}

/* Vertex attribute slots filled from PLY properties. */
enum { TT__A_X, TT__A_Y, TT__A_Z, TT__A_NX, TT__A_NY, TT__A_NZ, TT__A_U, TT__A_V, TT__A_COUNT };

/* Maps a vertex property name to an attribute slot, or -1. */
static int tt__ply_attr(const char *n) {
  static const struct {
    const char *n;
    int a;
  } map[] = {{"x", TT__A_X},         {"y", TT__A_Y},         {"z", TT__A_Z},
             {"nx", TT__A_NX},       {"ny", TT__A_NY},       {"nz", TT__A_NZ},
             {"u", TT__A_U},         {"v", TT__A_V},         {"s", TT__A_U},
             {"t", TT__A_V},         {"texture_u", TT__A_U}, {"texture_v", TT__A_V},
             {"texture_s", TT__A_U}, {"texture_t", TT__A_V}};
  for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
    if (strcmp(n, map[i].n) == 0) return map[i].a;
  return -1;
}

/* Appends triangle indices, growing the array geometrically. */
static int tt__push_tri(uint32_t **idx, uint32_t *count, size_t *cap, uint32_t a, uint32_t b,
                        uint32_t c) {
  if ((size_t)*count * 3 + 3 > *cap) {
    size_t ncap = *cap ? *cap * 2 : 3 * 1024;
    uint32_t *n = realloc(*idx, ncap * sizeof *n);
    if (!n) return 0;
    *idx = n;
    *cap = ncap;
  }
  if (*count == UINT32_MAX / 3) return 0;
  uint32_t *t = *idx + 3 * (size_t)*count;
  t[0] = a;
  t[1] = b;
  t[2] = c;
  (*count)++;
  return 1;
}

/* Parses the header, then the vertex and face elements; other elements are skipped. */
tt_status tt__ply_parse(const unsigned char *data, size_t len, const char *path, const char *where,
                        tt__mesh_data *out) {
  const unsigned char *p = data, *end = data + len;
  tt__ply_elem *elems = NULL;
  int elem_count = 0, format = -1;
  tt_status st = TT_OK;
  uint32_t *idx = NULL;
  size_t idx_cap = 0;
  uint32_t tri_count = 0;
  float *pos = NULL, *nrm = NULL, *uv = NULL;
  uint64_t nverts = 0;
  int have_vertex = 0;
#define TT__PLY_FAIL(...)                                                                          \
  do {                                                                                             \
    st = tt_set_error(TT_ERR_PARSE, __VA_ARGS__);                                                  \
    goto done;                                                                                     \
  } while (0)
  if (len < 4 || memcmp(p, "ply", 3) != 0 || (p[3] != '\n' && p[3] != '\r'))
    TT__PLY_FAIL("%s: \"%s\" is not a PLY file (no \"ply\" magic line)", where, path);
  /* header: line by line up to end_header */
  for (;;) {
    const unsigned char *nl = memchr(p, '\n', (size_t)(end - p));
    if (!nl) TT__PLY_FAIL("%s: \"%s\": PLY header has no end_header", where, path);
    char line[256];
    size_t n = (size_t)(nl - p);
    if (n >= sizeof line) n = sizeof line - 1;
    memcpy(line, p, n);
    line[n] = '\0';
    if (n && line[n - 1] == '\r') line[n - 1] = '\0';
    p = nl + 1;
    char w0[32] = "", w1[32] = "", w2[32] = "", w3[32] = "", w4[32] = "";
    int nw = sscanf(line, "%31s %31s %31s %31s %31s", w0, w1, w2, w3, w4);
    if (nw <= 0 || strcmp(w0, "comment") == 0 || strcmp(w0, "obj_info") == 0 ||
        strcmp(w0, "ply") == 0)
      continue;
    if (strcmp(w0, "end_header") == 0) break;
    if (strcmp(w0, "format") == 0) {
      if (strcmp(w1, "ascii") == 0) format = TT__PLY_ASCII;
      else if (strcmp(w1, "binary_little_endian") == 0) format = TT__PLY_LE;
      else if (strcmp(w1, "binary_big_endian") == 0) format = TT__PLY_BE;
      else TT__PLY_FAIL("%s: \"%s\": unknown PLY format \"%s\"", where, path, w1);
    } else if (strcmp(w0, "element") == 0) {
      char *e;
      double cnt = strtod(w2, &e);
      if (nw < 3 || e == w2 || *e || cnt < 0 || cnt > 4e9 || cnt != floor(cnt))
        TT__PLY_FAIL("%s: \"%s\": bad PLY element line \"%s\"", where, path, line);
      if (elem_count >= 64) TT__PLY_FAIL("%s: \"%s\": too many PLY elements", where, path);
      tt__ply_elem *ne = realloc(elems, (size_t)(elem_count + 1) * sizeof *ne);
      if (!ne) {
        st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
        goto done;
      }
      elems = ne;
      memset(&elems[elem_count], 0, sizeof elems[0]);
      snprintf(elems[elem_count].name, sizeof elems[0].name, "%s", w1);
      elems[elem_count].count = (uint64_t)cnt;
      elem_count++;
    } else if (strcmp(w0, "property") == 0) {
      if (elem_count == 0) TT__PLY_FAIL("%s: \"%s\": PLY property before any element", where, path);
      tt__ply_elem *el = &elems[elem_count - 1];
      if (el->prop_count >= 32) TT__PLY_FAIL("%s: \"%s\": too many PLY properties", where, path);
      tt__ply_prop *pr = &el->props[el->prop_count];
      memset(pr, 0, sizeof *pr);
      if (strcmp(w1, "list") == 0) {
        pr->count_type = tt__ply_type(w2);
        pr->type = tt__ply_type(w3);
        snprintf(pr->name, sizeof pr->name, "%s", w4);
        if (nw < 5 || !pr->count_type || !pr->type || pr->count_type == TT__P_F32 ||
            pr->count_type == TT__P_F64)
          TT__PLY_FAIL("%s: \"%s\": bad PLY list property \"%s\"", where, path, line);
      } else {
        pr->type = tt__ply_type(w1);
        snprintf(pr->name, sizeof pr->name, "%s", w2);
        if (nw < 3 || !pr->type)
          TT__PLY_FAIL("%s: \"%s\": bad PLY property \"%s\"", where, path, line);
      }
      el->prop_count++;
    } else {
      TT__PLY_FAIL("%s: \"%s\": unexpected PLY header line \"%s\"", where, path, line);
    }
  }
  if (format < 0) TT__PLY_FAIL("%s: \"%s\": PLY header has no format line", where, path);
  tt__ply_cur cur = {p, end, format};
  for (int e = 0; e < elem_count; e++) {
    tt__ply_elem *el = &elems[e];
    int is_vertex = strcmp(el->name, "vertex") == 0, is_face = strcmp(el->name, "face") == 0;
    if (is_vertex) {
      /* one vertex element only: faces index it, and its buffers are sized from its count
       * (a second one wrote its attributes past the first one's normals buffer) */
      if (have_vertex)
        TT__PLY_FAIL("%s: \"%s\": PLY file has a second \"element vertex\" (one is expected)",
                     where, path);
      if (el->count > UINT32_MAX / 3) TT__PLY_FAIL("%s: \"%s\": too many vertices", where, path);
      /* a count larger than the data left cannot be honest (every vertex takes at least one
       * byte, binary or ASCII): stop before allocating */
      if (el->count > (uint64_t)(end - cur.p))
        TT__PLY_FAIL("%s: \"%s\": truncated PLY file (vertex data)", where, path);
      int slot[32], have[TT__A_COUNT] = {0};
      for (int i = 0; i < el->prop_count; i++) {
        slot[i] = el->props[i].count_type ? -1 : tt__ply_attr(el->props[i].name);
        if (slot[i] >= 0) have[slot[i]] = 1;
      }
      if (!have[TT__A_X] || !have[TT__A_Y] || !have[TT__A_Z])
        TT__PLY_FAIL("%s: \"%s\": PLY vertex element lacks x, y or z", where, path);
      nverts = el->count;
      have_vertex = 1;
      size_t nv = (size_t)nverts ? (size_t)nverts : 1;
      pos = malloc(3 * nv * sizeof *pos);
      if (have[TT__A_NX] && have[TT__A_NY] && have[TT__A_NZ]) nrm = malloc(3 * nv * sizeof *nrm);
      if (have[TT__A_U] && have[TT__A_V]) uv = malloc(2 * nv * sizeof *uv);
      if (!pos || (have[TT__A_NX] && have[TT__A_NY] && have[TT__A_NZ] && !nrm) ||
          (have[TT__A_U] && have[TT__A_V] && !uv)) {
        st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory for %llu PLY vertices", where,
                          (unsigned long long)nverts);
        goto done;
      }
      for (uint64_t v = 0; v < nverts; v++) {
        double a[TT__A_COUNT] = {0};
        for (int i = 0; i < el->prop_count; i++) {
          const tt__ply_prop *pr = &el->props[i];
          double x;
          if (pr->count_type) {
            double cnt;
            if (!tt__ply_scalar(&cur, pr->count_type, &cnt) || cnt < 0)
              TT__PLY_FAIL("%s: \"%s\": truncated or corrupt PLY vertex %llu", where, path,
                           (unsigned long long)v);
            for (double k = 0; k < cnt; k++)
              if (!tt__ply_scalar(&cur, pr->type, &x))
                TT__PLY_FAIL("%s: \"%s\": truncated PLY vertex %llu", where, path,
                             (unsigned long long)v);
            continue;
          }
          if (!tt__ply_scalar(&cur, pr->type, &x))
            TT__PLY_FAIL("%s: \"%s\": truncated or corrupt PLY vertex %llu", where, path,
                         (unsigned long long)v);
          if (slot[i] >= 0) a[slot[i]] = x;
        }
        for (int k = 0; k < 3; k++) {
          if (!isfinite(a[TT__A_X + k]))
            TT__PLY_FAIL("%s: \"%s\": PLY vertex %llu is not finite", where, path,
                         (unsigned long long)v);
          pos[3 * v + (size_t)k] = (float)a[TT__A_X + k];
          if (nrm)
            nrm[3 * v + (size_t)k] = isfinite(a[TT__A_NX + k]) ? (float)a[TT__A_NX + k] : 0.0f;
        }
        if (uv) {
          uv[2 * v] = isfinite(a[TT__A_U]) ? (float)a[TT__A_U] : 0.0f;
          uv[2 * v + 1] = isfinite(a[TT__A_V]) ? (float)a[TT__A_V] : 0.0f;
        }
      }
      continue;
    }
    int list_prop = -1;
    if (is_face)
      for (int i = 0; i < el->prop_count; i++)
        if (el->props[i].count_type && (strcmp(el->props[i].name, "vertex_indices") == 0 ||
                                        strcmp(el->props[i].name, "vertex_index") == 0))
          list_prop = i;
    if (is_face && list_prop < 0)
      TT__PLY_FAIL("%s: \"%s\": PLY face element has no vertex_indices list", where, path);
    if (is_face && !have_vertex)
      TT__PLY_FAIL("%s: \"%s\": PLY faces come before the vertices", where, path);
    /* rows of an element without properties hold no bytes: nothing to read, and counting
     * through up to 2^64 of them one by one was a hang (found by tests/fuzz/fuzz_ply) */
    if (el->prop_count == 0) continue;
    for (uint64_t f = 0; f < el->count; f++) {
      for (int i = 0; i < el->prop_count; i++) {
        const tt__ply_prop *pr = &el->props[i];
        double x;
        if (!pr->count_type) {
          if (!tt__ply_scalar(&cur, pr->type, &x))
            TT__PLY_FAIL("%s: \"%s\": truncated or corrupt PLY %s %llu", where, path, el->name,
                         (unsigned long long)f);
          continue;
        }
        double cnt;
        if (!tt__ply_scalar(&cur, pr->count_type, &cnt) || cnt < 0 || cnt > 1e6)
          TT__PLY_FAIL("%s: \"%s\": truncated or corrupt PLY %s %llu", where, path, el->name,
                       (unsigned long long)f);
        uint32_t first = 0, prev = 0;
        for (uint32_t k = 0; k < (uint32_t)cnt; k++) {
          if (!tt__ply_scalar(&cur, pr->type, &x))
            TT__PLY_FAIL("%s: \"%s\": truncated PLY %s %llu", where, path, el->name,
                         (unsigned long long)f);
          if (i != list_prop) continue;
          if (!(x >= 0) || x >= (double)nverts)
            TT__PLY_FAIL("%s: \"%s\": PLY face %llu uses vertex %.0f (the file has %llu)", where,
                         path, (unsigned long long)f, x, (unsigned long long)nverts);
          uint32_t vi = (uint32_t)x;
          if (k == 0) first = vi;
          else if (k >= 2 && !tt__push_tri(&idx, &tri_count, &idx_cap, first, prev, vi)) {
            st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory for PLY faces", where);
            goto done;
          }
          prev = vi;
        }
      }
    }
  }
  if (!have_vertex) TT__PLY_FAIL("%s: \"%s\": PLY file has no vertex element", where, path);
  out->vertex_count = (uint32_t)nverts;
  out->triangle_count = tri_count;
  out->positions = pos;
  out->normals = nrm;
  out->uvs = uv;
  out->indices = idx ? idx : malloc(sizeof(uint32_t));
  pos = nrm = uv = NULL;
  idx = NULL;
  if (!out->indices) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
done:
#undef TT__PLY_FAIL
  free(elems);
  free(idx);
  free(pos);
  free(nrm);
  free(uv);
  return st;
}

/* File loading and parsing are separate so the parser sees one bounded buffer. */
tt_status tt__ply_read(const char *path, const char *where, tt__mesh_data *out) {
  memset(out, 0, sizeof *out);
  unsigned char *data;
  size_t len;
  tt_status st = tt__read_all(path, where, &data, &len);
  if (st != TT_OK) return st;
  st = tt__ply_parse(data, len, path, where, out);
  free(data);
  if (st != TT_OK) tt__mesh_data_free(out);
  return st;
}
