/* Malformed scenes: each case checks the status code and that the message names the file,
 * the JSON path and what was expected; then truncations and byte flips of the Cornell box
 * must fail cleanly (or load) without crashing. */
#include <tunetrace/scene.h>

#include "tt_test.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char g_root[1024];

/* A valid scene the cases below break one field at a time. Placeholders: @CAM@, @MAT@,
 * @MESH@ are substituted by each case. */
#define CAM_OK "{\"position\": [0, 0, 5], \"target\": [0, 0, 0], \"fov\": 45}"
#define MAT_OK                                                                                     \
  "{\"white\": {\"type\": \"diffuse\", \"albedo\": [0.7, 0.7, 0.7]}, \"red\": {\"albedo\": [0.6, " \
  "0.1, 0.1]}}"
#define MESH_OK                                                                                    \
  "[{\"name\": \"tri\", \"material\": \"white\", \"positions\": [[0,0,0],[1,0,0],[0,1,0]], "       \
  "\"indices\": [[0, 1, 2]]}]"
#define SCENE(cam, mat, mesh)                                                                      \
  "{\"version\": 1, \"camera\": " cam ", \"materials\": " mat ", \"meshes\": " mesh "}"

typedef struct error_case {
  const char *json;
  tt_status status;
  const char *expect;  /* substring of tt_last_error() */
  const char *expect2; /* optional second substring */
} error_case;

static const error_case g_cases[] = {
    /* 1. JSON syntax error with line:column */
    {"{\n  \"version\": 1,\n  \"camera\": {\"position\": [0, 0 5]}\n}", TT_ERR_PARSE,
     "bad.json:3:", "JSON syntax error"},
    /* 2. out-of-range number, the example from the format documentation */
    {SCENE("{\"position\": [0, 0, 5], \"target\": [0, 0, 0], \"fov\": 200}", MAT_OK, MESH_OK),
     TT_ERR_PARSE, "bad.json: camera.fov: expected a number in (0, 180), got 200", NULL},
    /* 3. unknown material, listing the known ones */
    {SCENE(CAM_OK, MAT_OK,
           "[{\"material\": \"white\", \"positions\": [0,0,0, 1,0,0, 0,1,0]},"
           " {\"material\": \"gold\", \"positions\": [0,0,0, 1,0,0, 0,1,0]}]"),
     TT_ERR_PARSE, "bad.json: meshes[1].material: unknown material \"gold\" (known: white, red)",
     NULL},
    /* 4. missing required field */
    {"{\"camera\": " CAM_OK ", \"materials\": " MAT_OK ", \"meshes\": " MESH_OK "}", TT_ERR_PARSE,
     "bad.json: version: missing required field", NULL},
    /* 5. unsupported version */
    {"{\"version\": 2, \"camera\": " CAM_OK ", \"materials\": " MAT_OK ", \"meshes\": " MESH_OK "}",
     TT_ERR_UNSUPPORTED, "bad.json: version: unsupported version 2 (expected 1)", NULL},
    {"{\"version\": \"1\", \"camera\": " CAM_OK ", \"materials\": " MAT_OK ", \"meshes\": " MESH_OK
     "}",
     TT_ERR_PARSE, "bad.json: version: expected the number 1, got a string \"1\"", NULL},
    /* 6. wrong type */
    {SCENE("{\"position\": \"origin\", \"target\": [0, 0, 0]}", MAT_OK, MESH_OK), TT_ERR_PARSE,
     "bad.json: camera.position: expected an array of 3 numbers, got a string \"origin\"", NULL},
    /* 7. wrong array length */
    {SCENE(CAM_OK, "{\"white\": {\"albedo\": [0.5, 0.5]}}", MESH_OK), TT_ERR_PARSE,
     "bad.json: materials.white.albedo: expected an array of 3 numbers",
     "got an array of 2 elements"},
    /* 8. index out of range */
    {SCENE(CAM_OK, MAT_OK,
           "[{\"material\": \"white\", \"positions\": [[0,0,0],[1,0,0],[0,1,0]], \"indices\": [[0, "
           "1, 2], [2, 1, 7]]}]"),
     TT_ERR_PARSE,
     "bad.json: meshes[0].indices[1][2]: index 7 out of range (the mesh has 3 vertices)", NULL},
    /* 9. non-finite number (1e999 overflows to inf) */
    {SCENE(CAM_OK, MAT_OK, "[{\"material\": \"white\", \"positions\": [0,0,0, 1e999,0,0, 0,1,0]}]"),
     TT_ERR_PARSE, "bad.json: meshes[0].positions[3]: expected a finite number, got inf", NULL},
    /* 10. zero area */
    {SCENE(CAM_OK, MAT_OK,
           "[{\"name\": \"flat\", \"material\": \"white\", \"positions\": "
           "[[0,0,0],[1,1,1],[2,2,2]]}]"),
     TT_ERR_PARSE, "bad.json: meshes[0]: mesh \"flat\" has zero area", NULL},
    /* 11. empty mesh list */
    {SCENE(CAM_OK, MAT_OK, "[]"), TT_ERR_PARSE,
     "bad.json: meshes: expected a non-empty array of meshes", NULL},
    /* 12. unknown material type */
    {SCENE(CAM_OK, "{\"white\": {\"type\": \"metal\"}}", MESH_OK), TT_ERR_PARSE,
     "bad.json: materials.white.type: unknown material type \"metal\" (expected diffuse, conductor",
     NULL},
    /* 13. missing section */
    {"{\"version\": 1, \"materials\": " MAT_OK ", \"meshes\": " MESH_OK "}", TT_ERR_PARSE,
     "bad.json: camera: missing required field (expected an object)", NULL},
    /* 14. not an object at the top */
    {"[1, 2, 3]", TT_ERR_PARSE, "bad.json: expected a JSON object at the top level, got an array",
     NULL},
    /* 15. truncated input */
    {"{\"version\": 1, \"camera\": {", TT_ERR_PARSE, "bad.json:1:", "unexpected end of input"},
    /* 16. empty input */
    {"", TT_ERR_PARSE, "bad.json:1:1: JSON syntax error", NULL},
    /* 17. degenerate camera */
    {SCENE("{\"position\": [0, 0, 5], \"target\": [0, 0, 0], \"up\": [0, 0, 1]}", MAT_OK, MESH_OK),
     TT_ERR_PARSE, "bad.json: camera.up: expected a vector not parallel to the view direction",
     NULL},
    {SCENE("{\"position\": [1, 2, 3], \"target\": [1, 2, 3]}", MAT_OK, MESH_OK), TT_ERR_PARSE,
     "bad.json: camera.target: expected a point different from camera.position", NULL},
    /* 18. indices not whole triangles */
    {SCENE(CAM_OK, MAT_OK,
           "[{\"material\": \"white\", \"positions\": [[0,0,0],[1,0,0],[0,1,0]], \"indices\": [0, "
           "1, 2, 0]}]"),
     TT_ERR_PARSE, "bad.json: meshes[0].indices: expected a multiple of 3 indices", NULL},
    /* 19. non-integer index */
    {SCENE(CAM_OK, MAT_OK,
           "[{\"material\": \"white\", \"positions\": [[0,0,0],[1,0,0],[0,1,0]], \"indices\": [0, "
           "1.5, 2]}]"),
     TT_ERR_PARSE,
     "bad.json: meshes[0].indices[1]: expected an integer in [0, 4.29497e+09], got 1.5", NULL},
    /* 20. camera path times must increase */
    {SCENE("{\"position\": [0, 0, 5], \"target\": [0, 0, 0], \"path\": [{\"time\": 1}, {\"time\": "
           "1}]}",
           MAT_OK, MESH_OK),
     TT_ERR_PARSE,
     "bad.json: camera.path[1].time: expected a time greater than the previous key's (1), got 1",
     NULL},
    /* 21. unknown light type */
    {"{\"version\": 1, \"camera\": " CAM_OK ", \"materials\": " MAT_OK ", \"meshes\": " MESH_OK
     ", \"lights\": [{\"type\": \"area\"}]}",
     TT_ERR_PARSE, "bad.json: lights[0].type: unknown light type \"area\"",
     "materials with emission"},
    /* 22. non-affine matrix and singular scale */
    {SCENE(CAM_OK, MAT_OK,
           "[{\"material\": \"white\", \"positions\": [0,0,0, 1,0,0, 0,1,0], \"matrix\": [1,0,0,0, "
           "0,1,0,0, 0,0,1,0, 0,0,1,1]}]"),
     TT_ERR_PARSE, "bad.json: meshes[0].matrix: expected an affine matrix (last row 0 0 0 1)",
     NULL},
    {SCENE(CAM_OK, MAT_OK,
           "[{\"material\": \"white\", \"positions\": [0,0,0, 1,0,0, 0,1,0], \"transform\": "
           "{\"scale\": [1, 0, 1]}}]"),
     TT_ERR_PARSE, "bad.json: meshes[0].transform.scale: expected non-zero scale factors", NULL},
    /* 23. resolution must be integers >= 1 */
    {SCENE("{\"position\": [0, 0, 5], \"target\": [0, 0, 0], \"resolution\": [640, 0]}", MAT_OK,
           MESH_OK),
     TT_ERR_PARSE, "bad.json: camera.resolution[1]: expected an integer in [1, 65536], got 0",
     NULL},
    /* 24. negative emission, wrong bool type, missing material */
    {SCENE(CAM_OK, "{\"l\": {\"emission\": [1, -1, 1]}}", MESH_OK), TT_ERR_PARSE,
     "bad.json: materials.l.emission[1]: expected a number in [0, inf), got -1", NULL},
    {SCENE(CAM_OK, "{\"white\": {\"twoSided\": 1}}", MESH_OK), TT_ERR_PARSE,
     "bad.json: materials.white.twoSided: expected true or false, got 1", NULL},
    {SCENE(CAM_OK, MAT_OK, "[{\"positions\": [0,0,0, 1,0,0, 0,1,0]}]"), TT_ERR_PARSE,
     "bad.json: meshes[0].material: missing required field (expected a string)", NULL},
    /* 25. both file and inline positions, or neither */
    {SCENE(
         CAM_OK, MAT_OK,
         "[{\"material\": \"white\", \"file\": \"a.obj\", \"positions\": [0,0,0, 1,0,0, 0,1,0]}]"),
     TT_ERR_PARSE, "bad.json: meshes[0]: expected either \"file\" or \"positions\", not both",
     NULL},
    {SCENE(CAM_OK, MAT_OK, "[{\"material\": \"white\"}]"), TT_ERR_PARSE,
     "bad.json: meshes[0].positions: missing required field (expected inline positions or a "
     "\"file\")",
     NULL},
    /* 26. normals count must match the vertices */
    {SCENE(CAM_OK, MAT_OK,
           "[{\"material\": \"white\", \"positions\": [0,0,0, 1,0,0, 0,1,0], \"normals\": "
           "[[0,0,1]]}]"),
     TT_ERR_PARSE, "bad.json: meshes[0].normals: expected 3 normals (one per vertex), got 1", NULL},
    /* 27. positions not a multiple of 3 */
    {SCENE(CAM_OK, MAT_OK, "[{\"material\": \"white\", \"positions\": [0,0,0, 1,0]}]"),
     TT_ERR_PARSE,
     "bad.json: meshes[0].positions: expected a multiple of 3 numbers (flat positions), got 5",
     NULL},
    /* 28. (#13) coordinates no renderer can trace: the camera at z = 1e19 aborted in Embree
     * (ray.valid() assertion), geometry at 1e30 or 1e38 vanished silently */
    {SCENE("{\"position\": [0, 0, 1e19], \"target\": [0, 0, 0]}", MAT_OK, MESH_OK), TT_ERR_PARSE,
     "bad.json: camera position (0, 0, 1e+19) is beyond the coordinate limit of +-1e18", NULL},
    {SCENE("{\"position\": [0, 0, 5], \"target\": [-3e18, 0, 0]}", MAT_OK, MESH_OK), TT_ERR_PARSE,
     "bad.json: camera target", "beyond the coordinate limit"},
    {SCENE(
         CAM_OK, MAT_OK,
         "[{\"name\": \"far\", \"material\": \"white\", \"positions\": [0,0,0, 1e30,0,0, 0,1,0]}]"),
     TT_ERR_PARSE,
     "bad.json: mesh 0 \"far\": vertex 1 at (1e+30, 0, 0) is beyond the coordinate limit", NULL},
    {SCENE(CAM_OK, MAT_OK, "[{\"material\": \"white\", \"positions\": [0,0,-1e38, 1,0,0, 0,1,0]}]"),
     TT_ERR_PARSE, "vertex 0 at (0, 0, -1e+38) is beyond the coordinate limit", NULL},
    {"{\"version\": 1, \"camera\": " CAM_OK ", \"materials\": " MAT_OK ", \"meshes\": " MESH_OK ","
     " \"lights\": [{\"type\": \"point\", \"position\": [5e18, 0, 0], \"intensity\": [1, 1, 1]}]}",
     TT_ERR_PARSE, "bad.json: light 0 at (5e+18, 0, 0) is beyond the coordinate limit", NULL},
};

/* Loads each case from memory and checks status, message, and that no scene leaks out. */
static void test_cases(void) {
  for (size_t i = 0; i < sizeof g_cases / sizeof g_cases[0]; i++) {
    const error_case *c = &g_cases[i];
    tt_scene *s = (tt_scene *)&g_cases; /* must be reset to NULL */
    tt_clear_error();
    tt_status st = tt_scene_load_json(c->json, strlen(c->json), "bad.json", NULL, &s);
    CHECK_MSG(st == c->status, "case %zu: status %d (%s), expected %d", i + 1, (int)st,
              tt_last_error(), (int)c->status);
    CHECK_MSG(s == NULL, "case %zu: scene returned on error", i + 1);
    CHECK_CONTAINS(tt_last_error(), c->expect);
    if (c->expect2) CHECK_CONTAINS(tt_last_error(), c->expect2);
    if (st == TT_OK) tt_scene_destroy(s);
  }
}

/* Errors that involve files: missing mesh file, unreadable mesh, syntax error position in
 * a real file, unsupported extension, missing scene. */
static void test_files(void) {
  char path[1200];
  tt_scene *s = NULL;
  tt_status st;

  snprintf(path, sizeof path, "%s/tests/data/scenes/missing-file.json", g_root);
  st = tt_scene_load(path, &s);
  CHECK(st == TT_ERR_IO && s == NULL);
  CHECK_CONTAINS(tt_last_error(), "missing-file.json: meshes[0].file: cannot open mesh file");
  CHECK_CONTAINS(tt_last_error(), "tests/data/scenes/models/nothere.obj"); /* resolved path */

  snprintf(path, sizeof path, "%s/tests/data/scenes/garbage-file.json", g_root);
  st = tt_scene_load(path, &s);
  CHECK(st == TT_ERR_PARSE && s == NULL);
  CHECK_CONTAINS(tt_last_error(), "garbage-file.json: meshes[0].file:");
  CHECK_CONTAINS(tt_last_error(), "garbage.obj");

  snprintf(path, sizeof path, "%s/tests/data/scenes/syntax-error.json", g_root);
  st = tt_scene_load(path, &s);
  CHECK(st == TT_ERR_PARSE && s == NULL);
  CHECK_CONTAINS(tt_last_error(), "syntax-error.json:5:"); /* the missing comma is on line 5 */
  CHECK_CONTAINS(tt_last_error(), "JSON syntax error");

  st = tt_scene_load("scenes/x.obj", &s);
  CHECK(st == TT_ERR_UNSUPPORTED && s == NULL);
  CHECK_CONTAINS(tt_last_error(),
                 "scenes/x.obj: unsupported scene format (expected .json, .pbrt, .gltf or .glb)");

  st = tt_scene_load("/nonexistent/dir/scene.json", &s);
  CHECK(st == TT_ERR_IO && s == NULL);
  CHECK_CONTAINS(tt_last_error(), "/nonexistent/dir/scene.json: cannot open scene file");

  /* (#13) a device as mesh file or import: refused at once, naming it (assimp read
   * /dev/zero until memory ran out; a FIFO blocked forever) */
  static const char dev_mesh[] = "{\"version\": 1, \"camera\": " CAM_OK ", \"materials\": "
                                 "{\"w\": {}}, \"meshes\": "
                                 "[{\"material\": \"w\", \"file\": \"/dev/zero\"}]}";
  st = tt_scene_load_json(dev_mesh, sizeof dev_mesh - 1, "dev.json", NULL, &s);
  CHECK(st == TT_ERR_IO && s == NULL);
  CHECK_CONTAINS(tt_last_error(), "dev.json: meshes[0].file: cannot open mesh file \"/dev/zero\": "
                                  "a character device, not a regular file");
  static const char dev_import[] = "{\"version\": 1, \"import\": \"/dev/null.pbrt\"}";
  st = tt_scene_load_json(dev_import, sizeof dev_import - 1, "imp.json", NULL, &s);
  CHECK(st == TT_ERR_IO && s == NULL);
  CHECK_CONTAINS(tt_last_error(), "imp.json: import: cannot open scene file \"/dev/null.pbrt\"");

  /* (#13 defect 10) PLYs found by fuzzing assimp 5.2.5 (SIGSEGV, an ai_assert abort, an
   * endless loop on a header cut short) as mesh files: our reader loads or rejects them
   * with the file named, at once */
  static const char *const assimp_killers[] = {"assimp-segv.ply", "assimp-abort.ply",
                                               "assimp-hang.ply",
                                               /* rows without properties counted one by one
                                                * (a hang found by fuzz_ply) */
                                               "empty-elements.ply"};
  char base[1200];
  snprintf(base, sizeof base, "%s/tests/data/scenes", g_root);
  alarm(60);
  for (int i = 0; i < 4; i++) {
    char json[512];
    int n = snprintf(json, sizeof json,
                     "{\"version\": 1, \"camera\": " CAM_OK ", \"materials\": "
                     "{\"w\": {}}, \"meshes\": [{\"material\": \"w\", \"file\": \"%s\"}]}",
                     assimp_killers[i]);
    st = tt_scene_load_json(json, (size_t)n, "ply.json", base, &s);
    if (i == 3) CHECK_MSG(st == TT_OK, "%s", tt_last_error()); /* a valid file */
    if (st == TT_OK) {
      CHECK(tt_scene_mesh_count(s) == 1);
      tt_scene_destroy(s);
      s = NULL;
    } else {
      CHECK(s == NULL);
      CHECK_CONTAINS(tt_last_error(), "ply.json: meshes[0].file");
      CHECK_CONTAINS(tt_last_error(), assimp_killers[i]);
    }
  }
  alarm(0);

  CHECK(tt_scene_load(NULL, &s) == TT_ERR_INVALID_ARGUMENT);
  CHECK(tt_scene_load_json("{}", 2, "x", NULL, NULL) == TT_ERR_INVALID_ARGUMENT);
  /* an embedded NUL would silently truncate the document */
  CHECK(tt_scene_load_json("{\"version\": 1}\0xx", 17, "nul.json", NULL, &s) == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(), "nul.json:1:15: JSON syntax error: unexpected NUL byte");
  /* the accessors tolerate NULL */
  CHECK(tt_scene_mesh_count(NULL) == 0 && tt_scene_id(NULL) == NULL);
  tt_scene_destroy(NULL);
}

/* Writes `n` bytes of `data` to DIR/NAME; returns 0 on success. */
static int put_file(const char *dir, const char *name, const void *data, size_t n) {
  char path[1400];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "wb");
  if (!f) return -1;
  size_t w = fwrite(data, 1, n, f);
  return fclose(f) == 0 && w == n ? 0 : -1;
}

/* Reads DIR/NAME whole into buf (at most n bytes); returns its size, or 0. */
static size_t get_file(const char *dir, const char *name, char *buf, size_t n) {
  char path[1400];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "rb");
  if (!f) return 0;
  size_t r = fread(buf, 1, n, f);
  fclose(f);
  return r;
}

/* Loads a one-mesh scene whose "file" is NAME in DIR; expects `status` and both substrings
 * (NULL: none) in the message, which must name the entry and the file. */
static void mesh_file_fails(const char *dir, const char *name, tt_status status, const char *expect,
                            const char *expect2) {
  char json[512];
  int n = snprintf(json, sizeof json,
                   "{\"version\": 1, \"camera\": " CAM_OK ", \"materials\": "
                   "{\"w\": {}}, \"meshes\": [{\"material\": \"w\", \"file\": \"%s\"}]}",
                   name);
  tt_scene *s = NULL;
  tt_status st = tt_scene_load_json(json, (size_t)n, "mesh.json", dir, &s);
  CHECK_MSG(st == status && s == NULL, "%s: status %d: %s", name, (int)st, tt_last_error());
  if (s) tt_scene_destroy(s);
  CHECK_CONTAINS(tt_last_error(), "mesh.json: meshes[0].file");
  CHECK_CONTAINS(tt_last_error(), name);
  if (expect) CHECK_CONTAINS(tt_last_error(), expect);
  if (expect2) CHECK_CONTAINS(tt_last_error(), expect2);
}

/* (#13) A mesh file is read only as the format its name says. A 132-byte corrupt PLY named
 * .gltf (found by fuzz_mesh) made assimp 5.2.5, once both glTF readers had refused it, guess
 * the format from the content and spin forever in its PLY parser; now a .gltf must be a JSON
 * object and a .glb a whole GLB container, and assimp runs only the readers of the file's
 * extension. Each case must fail at once (alarm) with what was expected. */
static void test_mesh_format_mismatch(void) {
  char data[1200], dir[] = "/tmp/tt_scene_errors_XXXXXX";
  snprintf(data, sizeof data, "%s/tests/data/scenes", g_root);
  alarm(60);
  mesh_file_fails(data, "ply-as-gltf.gltf", TT_ERR_PARSE,
                  "is not a glTF file: expected a JSON object, got a PLY file", NULL);
  CHECK(mkdtemp(dir) != NULL);
  static char ply[4096], glb[4096], gltf[4096];
  size_t nply = get_file(data, "ply-as-gltf.gltf", ply, sizeof ply);
  size_t nglb = get_file(data, "tri.glb", glb, sizeof glb);
  size_t ngltf = get_file(data, "tri.gltf", gltf, sizeof gltf);
  CHECK(nply == 132 && nglb > 100 && ngltf > 100);
  CHECK(put_file(dir, "ply.glb", ply, nply) == 0);
  mesh_file_fails(dir, "ply.glb", TT_ERR_PARSE,
                  "is not a GLB file: expected the 12-byte GLB header", "got a PLY file");
  CHECK(put_file(dir, "glb.gltf", glb, nglb) == 0);
  mesh_file_fails(dir, "glb.gltf", TT_ERR_PARSE,
                  "expected a JSON object, got a GLB (binary glTF) file", NULL);
  CHECK(put_file(dir, "json.glb", gltf, ngltf) == 0);
  mesh_file_fails(dir, "json.glb", TT_ERR_PARSE, "is not a GLB file", "got other bytes");
  CHECK(put_file(dir, "cut.glb", glb, 100) == 0);
  mesh_file_fails(dir, "cut.glb", TT_ERR_PARSE, "the GLB header declares",
                  "the file has 100 (cut short?)");
  /* (#13, found by fuzz_mesh in CI) a GLB whose JSON chunk declares ~4 GiB: assimp 5.2.5
   * allocated and zero-filled it before reading; now every chunk must fit the container */
  static char big[4096];
  memcpy(big, glb, nglb);
  big[12] = (char)0xF8, big[13] = 0x01, big[14] = (char)0xFF, big[15] = (char)0xFF;
  CHECK(put_file(dir, "chunk.glb", big, nglb) == 0);
  mesh_file_fails(dir, "chunk.glb", TT_ERR_PARSE,
                  "GLB chunk 0 at byte 12 declares 4294902264 bytes", "remain of the declared");
  memcpy(big, glb, nglb);
  big[16] = 'B'; /* the JSON chunk's type */
  CHECK(put_file(dir, "type.glb", big, nglb) == 0);
  mesh_file_fails(dir, "type.glb", TT_ERR_PARSE, "GLB chunk 0 must be the JSON chunk", NULL);
  CHECK(put_file(dir, "cut.gltf", gltf, 200) == 0);
  mesh_file_fails(dir, "cut.gltf", TT_ERR_PARSE,
                  "expected a JSON object, got a JSON syntax error at", NULL);
  CHECK(put_file(dir, "array.gltf", "[1, 2]", 6) == 0);
  mesh_file_fails(dir, "array.gltf", TT_ERR_PARSE,
                  "expected a JSON object, got an array of 2 elements", NULL);
  /* a JSON object that neither glTF reader accepts: refused by them, not handed on */
  static const char not_gltf[] =
      "{\"asset\": {\"version\": \"9.0\"}, \"x\": \"\nply\nformat ascii 1.0\n\"}";
  CHECK(put_file(dir, "v9.gltf", not_gltf, sizeof not_gltf - 1) == 0);
  mesh_file_fails(dir, "v9.gltf", TT_ERR_PARSE, "cannot import mesh file", NULL);
  /* content assimp would have recognised, under a name no reader claims */
  CHECK(put_file(dir, "tri.tt-unknown", gltf, ngltf) == 0);
  mesh_file_fails(dir, "tri.tt-unknown", TT_ERR_UNSUPPORTED,
                  "unknown mesh format (expected .ply, .obj, .gltf", NULL);
  alarm(0);
  static const char *const made[] = {"ply.glb",   "glb.gltf",      "json.glb", "cut.glb",
                                     "chunk.glb", "type.glb",      "cut.gltf", "array.gltf",
                                     "v9.gltf",   "tri.tt-unknown"};
  for (size_t i = 0; i < sizeof made / sizeof made[0]; i++) {
    char path[1400];
    snprintf(path, sizeof path, "%s/%s", dir, made[i]);
    unlink(path);
  }
  rmdir(dir);
}

/* Every prefix of the Cornell box and a few thousand single-byte corruptions either load
 * or fail with a message; under ASan/valgrind this doubles as a memory-safety check. */
static void test_no_crash(void) {
  char path[1200];
  snprintf(path, sizeof path, "%s/scenes/cornell-box/scene.json", g_root);
  FILE *f = fopen(path, "rb");
  CHECK(f != NULL);
  if (!f) return;
  static char text[1 << 16];
  size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  CHECK(n > 1000);
  int failures_without_message = 0, loaded = 0;
  for (size_t len = 0; len < n; len += 7) {
    tt_scene *s = NULL;
    tt_clear_error();
    tt_status st = tt_scene_load_json(text, len, "cut.json", NULL, &s);
    if (st == TT_OK) {
      loaded++;
      tt_scene_destroy(s);
    } else if (!tt_last_error()[0] || s != NULL) {
      failures_without_message++;
    }
  }
  CHECK(loaded == 0); /* a cut document is never a complete scene */
  static const char junk[] = "\"{}[],:0-9eE.+ \n\\x\x80";
  uint32_t rng = 12345;
  for (int iter = 0; iter < 3000; iter++) {
    static char copy[1 << 16];
    memcpy(copy, text, n);
    for (int k = 0; k < 1 + iter % 3; k++) {
      rng = rng * 1664525u + 1013904223u;
      size_t at = (rng >> 8) % n;
      rng = rng * 1664525u + 1013904223u;
      copy[at] = junk[(rng >> 8) % (sizeof junk - 1)];
    }
    tt_scene *s = NULL;
    tt_clear_error();
    tt_status st = tt_scene_load_json(copy, n, "flip.json", NULL, &s);
    if (st == TT_OK) tt_scene_destroy(s);
    else if (!tt_last_error()[0] || s != NULL) failures_without_message++;
  }
  CHECK(failures_without_message == 0);
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  snprintf(g_root, sizeof g_root, "%s", root ? root : "..");
  test_cases();
  test_files();
  test_mesh_format_mismatch();
  test_no_crash();
  return tt_test_finish("scene_errors");
}
