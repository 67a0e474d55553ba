/* glTF 2.0 animation through assimp (io/gltf_scene.c), checked against values computed here
 * from the files' own numbers, never from the loader's: simple_skin (glTF-Sample-Models,
 * Debian's assimp-testmodels) skinned by hand at a time between two rotation keys;
 * AnimatedMorphCube's morph weights read from its .bin and applied by hand; small files
 * written here for STEP and CUBICSPLINE channels, an animated camera, a scene.json that
 * imports a glTF, and bad input (keys out of order, NaN in a transform, mismatched morph
 * target sizes, a skin naming a missing joint, weights that do not sum to 1, a NaN inverse
 * bind matrix): each refused with a message naming the file and the field. */
#include <tunetrace/tunetrace.h>

#include "tt_test.h"

#include <cjson/cJSON.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define MODELS "/usr/share/assimp/models/glTF2"
#define PI 3.14159265358979323846

static char tmpdir[] = "/tmp/tt_gltf_anim_XXXXXX";

/* ---- writing small glTF files ------------------------------------------------------------- */

static void b64(const unsigned char *in, size_t n, char *out) {
  static const char t[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  size_t o = 0;
  for (size_t i = 0; i < n; i += 3) {
    uint32_t v = (uint32_t)in[i] << 16 | (i + 1 < n ? (uint32_t)in[i + 1] << 8 : 0) |
                 (i + 2 < n ? in[i + 2] : 0);
    out[o++] = t[v >> 18 & 63];
    out[o++] = t[v >> 12 & 63];
    out[o++] = i + 1 < n ? t[v >> 6 & 63] : '=';
    out[o++] = i + 2 < n ? t[v & 63] : '=';
  }
  out[o] = '\0';
}

/* Writes dir/name with `json`'s "@BUFFER@" replaced by one buffer holding `data` as a data
 * URI; returns the path (static storage, one at a time). */
static const char *write_gltf(const char *name, const char *json, const void *data, size_t n) {
  static char path[512];
  snprintf(path, sizeof path, "%s/%s", tmpdir, name);
  char *enc = malloc(4 * (n / 3 + 2) + 1);
  char *buf = malloc(strlen(json) + 4 * (n / 3 + 2) + 200);
  if (!enc || !buf) TEST_FAIL("out of memory");
  b64(data, n, enc);
  const char *at = strstr(json, "@BUFFER@");
  if (!at) TEST_FAIL("no @BUFFER@ in a test file");
  sprintf(buf, "%.*s{\"uri\": \"data:application/octet-stream;base64,%s\", \"byteLength\": %zu}%s",
          (int)(at - json), json, enc, n, at + 8);
  FILE *f = fopen(path, "w");
  if (!f || fputs(buf, f) < 0 || fclose(f) != 0) TEST_FAIL("cannot write %s", path);
  free(enc);
  free(buf);
  return path;
}

static const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};

/* A triangle on node "mover" whose `path` channel has `n` keys (`dim` floats each, 3x that
 * for CUBICSPLINE) with `interp`. Buffer: positions, times, values. */
static const char *write_channel(const char *name, const char *interp, const char *path,
                                 const float *times, unsigned n, const float *values,
                                 unsigned nvalues, int dim) {
  unsigned char data[4096];
  memcpy(data, tri, 36);
  memcpy(data + 36, times, 4 * n);
  memcpy(data + 36 + 4 * n, values, 4 * nvalues);
  char json[4096];
  snprintf(json, sizeof json,
           "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}],\n"
           " \"nodes\": [{\"name\": \"mover\", \"mesh\": 0}],\n"
           " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],\n"
           " \"buffers\": [@BUFFER@],\n"
           " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"
           "   {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": %u},\n"
           "   {\"buffer\": 0, \"byteOffset\": %u, \"byteLength\": %u}],\n"
           " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": "
           "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
           "   {\"bufferView\": 1, \"componentType\": 5126, \"count\": %u, \"type\": \"SCALAR\"},\n"
           "   {\"bufferView\": 2, \"componentType\": 5126, \"count\": %u, \"type\": \"%s\"}],\n"
           " \"animations\": [{\"name\": \"move\", \"channels\": [{\"sampler\": 0, \"target\": "
           "{\"node\": 0, \"path\": \"%s\"}}],\n"
           "   \"samplers\": [{\"input\": 1, \"output\": 2, \"interpolation\": \"%s\"}]}]}\n",
           4 * n, 36 + 4 * n, 4 * nvalues, n, nvalues / dim, dim == 4 ? "VEC4" : "VEC3", path,
           interp);
  return write_gltf(name, json, data, 36 + 4 * n + 4 * nvalues);
}

/* A triangle skinned to joints "j0" (node 1) and "j1" (node 2, child of j0): `joints` is the
 * skin's joint list, `ji` 4 joint indices and `w` 4 weights per vertex, `ibm` two
 * matrices (column-major, as glTF stores them). */
static const char *write_skin(const char *name, const char *joints, const unsigned char ji[12],
                              const float w[12], const float ibm[32]) {
  unsigned char data[256];
  memcpy(data, tri, 36);
  memcpy(data + 36, ji, 12);
  memcpy(data + 48, w, 48);
  memcpy(data + 96, ibm, 128);
  char json[4096];
  snprintf(json, sizeof json,
           "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0, 1]}],\n"
           " \"nodes\": [{\"name\": \"skinned\", \"mesh\": 0, \"skin\": 0},\n"
           "   {\"name\": \"j0\", \"children\": [2]}, {\"name\": \"j1\", \"translation\": [0, 1, "
           "0]}],\n"
           " \"skins\": [{\"joints\": %s, \"inverseBindMatrices\": 3}],\n"
           " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"JOINTS_0\": 1, "
           "\"WEIGHTS_0\": 2}}]}],\n"
           " \"buffers\": [@BUFFER@],\n"
           " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"
           "   {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 12},\n"
           "   {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 48},\n"
           "   {\"buffer\": 0, \"byteOffset\": 96, \"byteLength\": 128}],\n"
           " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": "
           "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
           "   {\"bufferView\": 1, \"componentType\": 5121, \"count\": 3, \"type\": \"VEC4\"},\n"
           "   {\"bufferView\": 2, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC4\"},\n"
           "   {\"bufferView\": 3, \"componentType\": 5126, \"count\": 2, \"type\": \"MAT4\"}]}\n",
           joints);
  return write_gltf(name, json, data, 224);
}

/* A triangle with one morph target whose POSITION accessor has `count` entries. */
static const char *write_morph(const char *name, unsigned count) {
  unsigned char data[256];
  memcpy(data, tri, 36);
  const float d[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  memcpy(data + 36, d, 36);
  char json[4096];
  snprintf(json, sizeof json,
           "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}],\n"
           " \"nodes\": [{\"name\": \"morphing\", \"mesh\": 0}],\n"
           " \"meshes\": [{\"name\": \"m\", \"weights\": [0.5], \"primitives\": [{\"attributes\": "
           "{\"POSITION\": 0}, \"targets\": [{\"POSITION\": 1}]}]}],\n"
           " \"buffers\": [@BUFFER@],\n"
           " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"
           "   {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 36}],\n"
           " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": "
           "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
           "   {\"bufferView\": 1, \"componentType\": 5126, \"count\": %u, \"type\": \"VEC3\"}]}\n",
           count);
  return write_gltf(name, json, data, 72);
}

/* Loads `path`, which must fail with a message containing each of the NULL-terminated
 * `needles` and the file's name. */
static void expect_error(const char *path, const char *const *needles) {
  tt_scene *s = NULL;
  tt_status st = tt_scene_load(path, &s);
  CHECK_MSG(st != TT_OK && s == NULL, "%s loaded, expected an error", path);
  if (st == TT_OK) {
    tt_scene_destroy(s);
    return;
  }
  const char *msg = tt_last_error();
  printf("refused as expected: %s\n", msg);
  const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
  CHECK_MSG(strstr(msg, base) != NULL, "the message names the file %s: %s", base, msg);
  for (size_t i = 0; needles[i]; i++)
    CHECK_MSG(strstr(msg, needles[i]) != NULL, "expected \"%s\" in: %s", needles[i], msg);
}

static tt_scene *load(const char *path) {
  tt_scene *s = NULL;
  if (tt_scene_load(path, &s) != TT_OK) {
    CHECK_MSG(0, "%s: %s", path, tt_last_error());
    return NULL;
  }
  return s;
}

/* ---- simple_skin, skinned by hand ----------------------------------------------------------- */

/* glTF-Sample-Models' simple_skin: a 1 x 2 strip of 10 vertices, joint 0 (node 1, at
 * (0, 1, 0)) and joint 1 (node 2, its child) rotating about Z by its keys; both inverse bind
 * matrices translate by (-0.5, -1, 0); weights (1 - k/4, k/4) for the vertex rows k = 0..4.
 * At t = 0.75 s, half way between the keys at 0.5 s (z = 0.383, w = 0.924) and 1.0 s (z = w
 * = 0.707), slerp turns joint 1 by the mean of the two keys' angles. */
static void test_simple_skin(void) {
  tt_scene *s = load(MODELS "/simple_skin/simple_skin.gltf");
  if (!s) return;
  CHECK(tt_scene_animated(s));
  double t0, t1;
  tt_scene_time_range(s, &t0, &t1);
  CHECK_NEAR(t0, 0.0, 1e-9);
  CHECK_NEAR(t1, 5.5, 1e-5);
  CHECK(tt_scene_mesh_count(s) == 1);
  const tt_mesh *m = tt_scene_mesh(s, 0);
  CHECK(m->vertex_count == 10 && m->triangle_count == 8);
  CHECK(m->motion == TT_MESH_DEFORMING);
  const double t = 0.75;
  CHECK_MSG(tt_scene_set_time(s, t, 0.5) == TT_OK, "%s", tt_last_error());
  const double a1 = 2 * atan2(0.383f, 0.924f), a2 = 2 * atan2(0.707f, 0.707f);
  const double a = 0.5 * (a1 + a2), c = cos(a), sn = sin(a);
  double worst = 0;
  for (uint32_t v = 0; v < 10; v++) {
    const double x = v % 2, y = 0.5 * (v / 2), w1 = 0.25 * (v / 2), w0 = 1 - w1;
    const double bx = x - 0.5, by = y - 1.0; /* inverse bind */
    /* joint 0: T(0,1,0); joint 1: T(0,1,0) R(a) */
    const double p0[2] = {bx, by + 1}, p1[2] = {c * bx - sn * by, sn * bx + c * by + 1};
    const double ex = w0 * p0[0] + w1 * p1[0], ey = w0 * p0[1] + w1 * p1[1];
    const float *p = m->positions + 3 * v;
    double e = fabs(p[0] - ex) + fabs(p[1] - ey) + fabs(p[2]);
    if (e > worst) worst = e;
    CHECK_MSG(e < 2e-6, "vertex %u at t = %g: (%g, %g, %g), by hand (%g, %g, 0)", v, t, p[0], p[1],
              p[2], ex, ey);
  }
  /* the previous frame's positions are those of t = 0.5 (key 1: joint 1 at a1) */
  const float *q = m->prev_positions + 3 * 9; /* vertex 9: (1, 2), joint 1 only */
  CHECK_NEAR(q[0], cos(a1) * 0.5 - sin(a1) * 1.0, 2e-6);
  CHECK_NEAR(q[1], sin(a1) * 0.5 + cos(a1) * 1.0 + 1.0, 2e-6);
  printf("simple_skin: t = %g s, largest |skinned - by hand| %.3g\n", t, worst);
  tt_scene_destroy(s);
}

/* ---- AnimatedMorphCube, morphed by hand ---------------------------------------------------- */

/* Reads float accessor `i` of the cube's .bin (tightly packed, as that file stores them). */
static float *accessor(const cJSON *root, const unsigned char *bin, size_t binlen, int i,
                       unsigned *count, unsigned comps) {
  const cJSON *acc = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "accessors"), i);
  const cJSON *bv = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "bufferViews"),
                                       cJSON_GetObjectItem(acc, "bufferView")->valueint);
  const cJSON *bo = cJSON_GetObjectItem(bv, "byteOffset"),
              *ao = cJSON_GetObjectItem(acc, "byteOffset");
  size_t off = (bo ? (size_t)bo->valuedouble : 0) + (ao ? (size_t)ao->valuedouble : 0);
  *count = (unsigned)cJSON_GetObjectItem(acc, "count")->valuedouble;
  size_t n = (size_t)*count * comps;
  if (off + 4 * n > binlen) TEST_FAIL("accessor %d lies outside the .bin", i);
  float *out = malloc(4 * n);
  memcpy(out, bin + off, 4 * n);
  return out;
}

static void test_morph_cube(void) {
  const char *dir = MODELS "/glTF-Sample-Models/AnimatedMorphCube-glTF/";
  char path[512], bpath[512];
  snprintf(path, sizeof path, "%sAnimatedMorphCube.gltf", dir);
  snprintf(bpath, sizeof bpath, "%sAnimatedMorphCube.bin", dir);
  char *text = NULL, *bin = NULL;
  size_t tlen = 0, blen = 0;
  if (tt_file_read(path, "glTF", 0, &text, &tlen) != TT_OK ||
      tt_file_read(bpath, "bin", 0, &bin, &blen) != TT_OK)
    TEST_FAIL("cannot read %s (install assimp-testmodels: tools/bootstrap.sh)", path);
  cJSON *root = cJSON_ParseWithLength(text, tlen);
  CHECK(root != NULL);
  unsigned nb, nt0, nt1, nk, nw;
  float *base = accessor(root, (unsigned char *)bin, blen, 2, &nb, 3);
  float *d0 = accessor(root, (unsigned char *)bin, blen, 4, &nt0, 3);
  float *d1 = accessor(root, (unsigned char *)bin, blen, 7, &nt1, 3);
  float *kt = accessor(root, (unsigned char *)bin, blen, 10, &nk, 1);
  float *kw = accessor(root, (unsigned char *)bin, blen, 11, &nw, 1);
  CHECK(nb == 24 && nt0 == 24 && nt1 == 24 && nk == 127 && nw == 254);
  tt_scene *s = load(path);
  if (s && nk == 127) {
    CHECK(tt_scene_animated(s));
    const tt_mesh *m = tt_scene_mesh(s, 0);
    CHECK(m->vertex_count == 24 && m->motion == TT_MESH_DEFORMING);
    /* node: rotation (0, 0.7071067, -0.7071068, 0), scale 100 */
    const double qx = 0, qy = 0.7071067, qz = -0.7071068, qw = 0;
    const double R[9] = {
        1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw),     2 * (qx * qz + qy * qw),
        2 * (qx * qy + qz * qw),     1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw),
        2 * (qx * qz - qy * qw),     2 * (qy * qz + qx * qw),     1 - 2 * (qx * qx + qy * qy)};
    const double times[] = {0.9, 2.05, 3.3};
    double worst = 0, moved = 0;
    for (int k = 0; k < 3; k++) {
      const double t = times[k];
      CHECK(tt_scene_set_time(s, t, t - 1.0 / 24) == TT_OK);
      unsigned j = 0;
      while (j + 2 < nk && kt[j + 1] <= t) j++;
      const double u = (t - kt[j]) / ((double)kt[j + 1] - kt[j]);
      const double w0 = (1 - u) * kw[2 * j] + u * kw[2 * j + 2];
      const double w1 = (1 - u) * kw[2 * j + 1] + u * kw[2 * j + 3];
      for (unsigned v = 0; v < 24; v++) {
        double p[3], e = 0;
        for (int c = 0; c < 3; c++)
          p[c] = base[3 * v + c] + w0 * d0[3 * v + c] + w1 * d1[3 * v + c];
        for (int r = 0; r < 3; r++) {
          double x = 100 * (R[3 * r] * p[0] + R[3 * r + 1] * p[1] + R[3 * r + 2] * p[2]);
          e += fabs(m->positions[3 * v + r] - x);
          moved += fabs(m->positions[3 * v + r] - m->prev_positions[3 * v + r]);
        }
        if (e > worst) worst = e;
        CHECK_MSG(e < 2e-5, "t = %g vertex %u: off by %g from the weights (%g, %g) applied by hand",
                  t, v, e, w0, w1);
      }
    }
    CHECK_MSG(moved > 0.1, "the cube's vertices moved by %g in all between frames", moved);
    printf("AnimatedMorphCube: largest |morphed - by hand| %.3g (cube of size 2)\n", worst);
    tt_scene_destroy(s);
  }
  free(base), free(d0), free(d1), free(kt), free(kw);
  cJSON_Delete(root);
  tt_free(text);
  tt_free(bin);
}

/* ---- interpolation modes, camera, scene.json import ---------------------------------------- */

static void test_interpolation(void) {
  const float times[3] = {0, 0.5f, 1};
  const float steps[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  tt_scene *s = load(write_channel("step.gltf", "STEP", "translation", times, 3, steps, 9, 3));
  if (s) {
    CHECK(tt_scene_mesh(s, 0)->motion == TT_MESH_RIGID);
    CHECK(tt_scene_set_time(s, 0.75, 0.7) == TT_OK);
    /* STEP holds key 1 (x = 1) until 1 s; LINEAR would be at 1.5 */
    CHECK_NEAR(tt_scene_mesh(s, 0)->positions[3], 2.0, 1e-6);
    CHECK(tt_scene_set_time(s, 1.0, 0.75) == TT_OK);
    CHECK_NEAR(tt_scene_mesh(s, 0)->positions[3], 3.0, 1e-6);
    tt_scene_destroy(s);
  }
  s = load(write_channel("linear.gltf", "LINEAR", "translation", times, 3, steps, 9, 3));
  if (s) {
    CHECK(tt_scene_set_time(s, 0.75, 0.7) == TT_OK);
    CHECK_NEAR(tt_scene_mesh(s, 0)->positions[3], 2.5, 1e-6);
    tt_scene_destroy(s);
  }
  /* CUBICSPLINE: (in-tangent, value, out-tangent) per key; the curve passes the values */
  float cub[27];
  for (int k = 0; k < 3; k++) {
    const float v[3] = {0, (float)(k * k), 0};
    for (int c = 0; c < 3; c++) {
      cub[9 * k + c] = 0.0f;
      cub[9 * k + 3 + c] = v[c];
      cub[9 * k + 6 + c] = 0.0f;
    }
  }
  s = load(write_channel("cubic.gltf", "CUBICSPLINE", "translation", times, 3, cub, 27, 3));
  if (s) {
    for (int k = 0; k < 3; k++) {
      CHECK(tt_scene_set_time(s, times[k], times[k]) == TT_OK);
      CHECK_NEAR(tt_scene_mesh(s, 0)->positions[1], (double)(k * k), 1e-6);
    }
    CHECK(tt_scene_set_time(s, 0.75, 0.7) == TT_OK);
    const double y = tt_scene_mesh(s, 0)->positions[1];
    CHECK_MSG(y > 1.0 && y < 4.0, "between keys 1 and 4: %g", y);
    tt_scene_destroy(s);
  }
  /* rotation LINEAR: slerp about Z from 0 to 90 degrees; at 0.25 s: 45 degrees */
  const float rt[2] = {0, 0.5f};
  const float q[8] = {0, 0, 0, 1, 0, 0, (float)sin(PI / 4), (float)cos(PI / 4)};
  s = load(write_channel("rot.gltf", "LINEAR", "rotation", rt, 2, q, 8, 4));
  if (s) {
    CHECK(tt_scene_set_time(s, 0.25, 0.2) == TT_OK);
    const float *p = tt_scene_mesh(s, 0)->positions + 3; /* (1, 0, 0) turned by 45 degrees */
    CHECK_NEAR(p[0], sqrt(0.5), 1e-6);
    CHECK_NEAR(p[1], sqrt(0.5), 1e-6);
    tt_scene_destroy(s);
  }
}

static void test_camera(void) {
  unsigned char data[128];
  const float times[2] = {0, 1}, pos[6] = {0, 0, 5, 2, 0, 5};
  memcpy(data, tri, 36);
  memcpy(data + 36, times, 8);
  memcpy(data + 44, pos, 24);
  const char *json =
      "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0, 1]}],\n"
      " \"nodes\": [{\"mesh\": 0}, {\"name\": \"cam\", \"camera\": 0, \"translation\": [0, 0, "
      "5]}],\n"
      " \"cameras\": [{\"type\": \"perspective\", \"perspective\": {\"yfov\": 0.8, "
      "\"aspectRatio\": 2.0, \"znear\": 0.1}}],\n"
      " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],\n"
      " \"buffers\": [@BUFFER@],\n"
      " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"
      "   {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 8},\n"
      "   {\"buffer\": 0, \"byteOffset\": 44, \"byteLength\": 24}],\n"
      " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": "
      "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
      "   {\"bufferView\": 1, \"componentType\": 5126, \"count\": 2, \"type\": \"SCALAR\"},\n"
      "   {\"bufferView\": 2, \"componentType\": 5126, \"count\": 2, \"type\": \"VEC3\"}],\n"
      " \"animations\": [{\"channels\": [{\"sampler\": 0, \"target\": {\"node\": 1, \"path\": "
      "\"translation\"}}], \"samplers\": [{\"input\": 1, \"output\": 2}]}]}\n";
  const char *path = write_gltf("camera.gltf", json, data, 68);
  /* the same as a GLB container: the JSON chunk (read for the camera and interpolation)
   * and the buffer as the BIN chunk */
  char glb[600];
  snprintf(glb, sizeof glb, "%s/camera.glb", tmpdir);
  {
    char text[4096];
    const char *at = strstr(json, "@BUFFER@");
    snprintf(text, sizeof text, "%.*s{\"byteLength\": 68}%s", (int)(at - json), json, at + 8);
    const uint32_t n = (uint32_t)strlen(text), padded = (n + 3) & ~3u;
    const uint32_t total = 12 + 8 + padded + 8 + 68;
    const uint32_t head[5] = {0x46546C67u, 2, total, padded, 0x4E4F534Au};
    const uint32_t bin[2] = {68, 0x004E4942u};
    FILE *f = fopen(glb, "wb");
    if (!f || fwrite(head, 4, 5, f) != 5 || fwrite(text, 1, n, f) != n ||
        fwrite("   ", 1, padded - n, f) != padded - n || fwrite(bin, 4, 2, f) != 2 ||
        fwrite(data, 1, 68, f) != 68 || fclose(f) != 0)
      TEST_FAIL("cannot write %s", glb);
  }
  tt_scene *g = load(glb);
  if (g) {
    tt_camera at;
    tt_scene_camera_at(g, 0.5, &at);
    CHECK_NEAR(at.position[0], 1.0, 1e-5);
    CHECK_NEAR(tt_scene_camera(g)->fov_y, 0.8 * 180 / PI, 1e-4);
    tt_scene_destroy(g);
  }
  tt_scene *s = load(path);
  if (!s) return;
  const tt_camera *c = tt_scene_camera(s);
  CHECK_NEAR(c->fov_y, 0.8 * 180 / PI, 1e-4);
  CHECK(c->width == 256 && c->height == 128);
  CHECK_MSG(c->key_count >= 2, "camera path: %u keys", c->key_count);
  CHECK_NEAR(c->position[2], 5.0, 1e-6);
  CHECK_NEAR(c->position[0], 0.0, 1e-6);
  const double ts[] = {0.25, 0.5, 0.9};
  for (int k = 0; k < 3; k++) {
    tt_camera at;
    tt_scene_camera_at(s, ts[k], &at);
    CHECK_NEAR(at.position[0], 2 * ts[k], 1e-5);
    CHECK_NEAR(at.position[2], 5.0, 1e-5);
    CHECK_NEAR(at.target[0], 2 * ts[k], 1e-5);
    CHECK_NEAR(at.target[2], 4.0, 1e-5); /* glTF cameras look down -Z */
    CHECK_NEAR(at.up[1], 1.0, 1e-6);
  }
  /* on its own the file gets a dim sky and a sun; imported, the scene.json lights it */
  CHECK(tt_scene_light_count(s) == 2 && tt_scene_light(s, 0)->type == TT_LIGHT_ENV_CONSTANT &&
        tt_scene_light(s, 1)->type == TT_LIGHT_DISTANT);
  tt_scene_destroy(s);
  char wrap[600];
  snprintf(wrap, sizeof wrap, "%s/wrap.json", tmpdir);
  FILE *f = fopen(wrap, "w");
  if (!f) TEST_FAIL("cannot write %s", wrap);
  fputs(
      "{\"version\": 1, \"import\": \"camera.gltf\", \"render\": {\"spp\": 2},\n"
      " \"lights\": [{\"type\": \"point\", \"position\": [0, 0, 3], \"intensity\": [5, 5, 5]}]}\n",
      f);
  fclose(f);
  s = load(wrap);
  if (s) {
    CHECK(tt_scene_light_count(s) == 1 && tt_scene_light(s, 0)->type == TT_LIGHT_POINT);
    CHECK(tt_scene_camera(s)->key_count >= 2);
    tt_scene_destroy(s);
  }
}

/* KHR_lights_punctual: a point light at its node's position, a spot light turned by its
 * node (looking down -Z, so down -Y after a -90 degree turn about X) and a directional one;
 * with lights of its own the file gets no default sky. */
static void test_lights(void) {
  const char *json =
      "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0, 1, 2, "
      "3]}],\n"
      " \"extensionsUsed\": [\"KHR_lights_punctual\"],\n"
      " \"extensions\": {\"KHR_lights_punctual\": {\"lights\": [\n"
      "   {\"type\": \"point\", \"color\": [1, 0.5, 0.25], \"intensity\": 8},\n"
      "   {\"type\": \"spot\", \"intensity\": 3, \"spot\": {\"innerConeAngle\": 0.2, "
      "\"outerConeAngle\": 0.5}},\n"
      "   {\"type\": \"directional\", \"intensity\": 2}]}},\n"
      " \"nodes\": [{\"mesh\": 0},\n"
      "   {\"name\": \"bulb\", \"translation\": [1, 2, 3], \"extensions\": "
      "{\"KHR_lights_punctual\": {\"light\": 0}}},\n"
      "   {\"name\": \"lamp\", \"translation\": [0, 4, 0], \"rotation\": [-0.70710678, 0, 0, "
      "0.70710678], \"extensions\": {\"KHR_lights_punctual\": {\"light\": 1}}},\n"
      "   {\"name\": \"sun\", \"extensions\": {\"KHR_lights_punctual\": {\"light\": 2}}}],\n"
      " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],\n"
      " \"buffers\": [@BUFFER@],\n"
      " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36}],\n"
      " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": "
      "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]}]}\n";
  tt_scene *s = load(write_gltf("lights.gltf", json, tri, 36));
  if (!s) return;
  CHECK_MSG(tt_scene_light_count(s) == 3, "%u lights", tt_scene_light_count(s));
  for (uint32_t i = 0; i < tt_scene_light_count(s) && tt_scene_light_count(s) == 3; i++) {
    const tt_light *l = tt_scene_light(s, i);
    if (l->type == TT_LIGHT_POINT) {
      CHECK_NEAR(l->position[0], 1, 1e-6);
      CHECK_NEAR(l->position[1], 2, 1e-6);
      CHECK_NEAR(l->position[2], 3, 1e-6);
      CHECK_NEAR(l->radiance[0], 8, 1e-5);
      CHECK_NEAR(l->radiance[2], 2, 1e-5);
    } else if (l->type == TT_LIGHT_SPOT) {
      CHECK_NEAR(l->position[1], 4, 1e-6);
      CHECK_NEAR(l->direction[1], -1, 1e-5);
      CHECK_NEAR(l->cos_outer, cos(0.5), 1e-6);
      CHECK_NEAR(l->cos_inner, cos(0.2), 1e-6);
      CHECK_NEAR(l->radiance[1], 3, 1e-5);
    } else {
      CHECK(l->type == TT_LIGHT_DISTANT);
      CHECK_NEAR(l->direction[2], -1, 1e-6);
      CHECK_NEAR(l->radiance[0], 2, 1e-5);
    }
  }
  tt_scene_destroy(s);
}

/* ---- bad input ------------------------------------------------------------------------------ */

static void test_bad_input(void) {
  const float times_bad[3] = {0, 1, 0.5f}, vals[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  expect_error(write_channel("order.gltf", "LINEAR", "translation", times_bad, 3, vals, 9, 3),
               (const char *const[]){"animations[0]", "\"mover\"", "translation",
                                     "keyframes out of order", NULL});
  const float times[3] = {0, 0.5f, 1};
  float nan_vals[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  nan_vals[4] = NAN;
  expect_error(write_channel("nan.gltf", "LINEAR", "translation", times, 3, nan_vals, 9, 3),
               (const char *const[]){"animations[0]", "translation", "key 1", "NaN", NULL});
  float nan_rot[8] = {0, 0, 0, 1, 0, 0, NAN, 1};
  expect_error(write_channel("nanrot.gltf", "LINEAR", "rotation", times, 2, nan_rot, 8, 4),
               (const char *const[]){"rotation", "key 1", "NaN", NULL});
  expect_error(write_morph("morph_size.gltf", 2),
               (const char *const[]){"meshes[0].primitives[0].targets[0].POSITION",
                                     "mismatched morph target size", "expected 3", "got 2", NULL});
  const unsigned char ji[12] = {0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0};
  const float w[12] = {1, 0, 0, 0, 0.5f, 0.5f, 0, 0, 1, 0, 0, 0};
  float ibm[32] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0,  0, 1,
                   1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1};
  tt_scene *ok = load(write_skin("skin_ok.gltf", "[1, 2]", ji, w, ibm));
  if (ok) {
    CHECK(tt_scene_mesh(ok, 0)->motion == TT_MESH_DEFORMING);
    tt_scene_destroy(ok);
  }
  const float wbad[12] = {1, 0, 0, 0, 0.5f, 0.2f, 0, 0, 1, 0, 0, 0};
  expect_error(write_skin("skin_weights.gltf", "[1, 2]", ji, wbad, ibm),
               (const char *const[]){"skin", "vertex 1", "sum to 0.7", NULL});
  const unsigned char jmiss[12] = {0, 1, 0, 0, 0, 3, 0, 0, 1, 0, 0, 0};
  expect_error(write_skin("skin_joint.gltf", "[1, 2]", jmiss, w, ibm),
               (const char *const[]){"vertex 1", "joint indices must name a joint", NULL});
  expect_error(write_skin("skin_node.gltf", "[1, 7]", ji, w, ibm),
               (const char *const[]){"skins[0].joints[1]", "missing joint", "got 7", NULL});
  ibm[13] = NAN;
  expect_error(write_skin("skin_nan.gltf", "[1, 2]", ji, w, ibm),
               (const char *const[]){"inverse bind matrix", "joint 0", NULL});
}

int main(void) {
  if (!mkdtemp(tmpdir)) TEST_FAIL("cannot create a temporary folder in /tmp");
  test_simple_skin();
  test_morph_cube();
  test_interpolation();
  test_camera();
  test_lights();
  test_bad_input();
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmpdir);
  return tt_test_finish("gltf_anim");
}
