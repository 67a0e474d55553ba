/* pbrt-v4 importer internals, split as pbrt-v4 splits its parser and scene builder:
 *   pbrt_import.c      the entry point tt__scene_load_pbrt (pbrt.h): the directive loop
 *   pbrt_lexer.c       the include stack, tokens, messages
 *   pbrt_params.c      parameter lists ("type name" [values]) and their typed lookups
 *   pbrt_directives.c  the {name, handler} table: one function per directive
 *   pbrt_state.c       graphics state, transforms, world setup, camera, options
 *   pbrt_materials.c   materials and textures
 *   pbrt_geometry.c    shapes and object instances
 *   pbrt_lights.c      light sources and area lights
 *   pbrt_shapes.c      the PLY reader and analytic shape tessellation
 *   pbrt_spectrum.c    spectrum-to-RGB approximations
 * Not part of the public ABI; the mapping is documented in scenes/README.md, "Importing
 * pbrt-v4 scenes". */
#ifndef TT_PBRT_INTERNAL_H
#define TT_PBRT_INTERNAL_H

#include <tunetrace/suggest.h>
#include "io/pbrt/pbrt.h"
#include "scene/scene_internal.h"
#include "util/files.h"
#include "util/mat4.h"

#include <stddef.h>
#include <stdint.h>

/* ---- shapes (pbrt_shapes.c) ------------------------------------------------------------ */

/* Reads an ASCII or binary PLY file (".ply.gz" too when built with zlib) into triangles;
 * polygons are fanned. `where` ("file:line") prefixes error messages. */
tt_status tt__pbrt_read_ply(const char *path, const char *where, tt__mesh_data *out);

/* Tessellates pbrt's sphere (object space, outward normals, uv = (phi/2pi, theta/pi)). */
tt_status tt__pbrt_sphere(double radius, tt__mesh_data *out);

/* Tessellates pbrt's disk at height z with an optional inner radius; normal +z. */
tt_status tt__pbrt_disk(double radius, double inner, double height, tt__mesh_data *out);

/* One level of Loop subdivision of a closed or open triangle mesh (positions only; uvs and
 * normals are dropped, as pbrt's loopsubdiv computes its own). */
tt_status tt__pbrt_loop_subdivide(tt__mesh_data *mesh);

/* ---- spectra (pbrt_spectrum.c) --------------------------------------------------------- */

/* How a spectrum is turned into RGB: reflectance-like values keep a flat spectrum at 1,
 * illuminants are normalised to luminance 1 (pbrt-v4 divides light spectra by their
 * photometric power). */
typedef enum tt__spectrum_use { TT__SPEC_UNBOUNDED = 0, TT__SPEC_ILLUMINANT = 1 } tt__spectrum_use;

/* Named pbrt-v4 spectra: metal-<X>-eta/k, glass-<X> (a flat IOR), stdillum-*, illum-*.
 * Returns 1 and writes rgb when known, else 0. */
int tt__pbrt_named_spectrum(const char *name, float rgb[3]);

/* RGB of a piecewise-linear spectrum given as (lambda nm, value) pairs. */
void tt__pbrt_sampled_spectrum(const double *pairs, size_t pair_count, tt__spectrum_use use,
                               float rgb[3]);

/* RGB of a blackbody at `kelvin`, normalised to luminance 1 (pbrt-v4's "blackbody"). */
void tt__pbrt_blackbody(double kelvin, float rgb[3]);

/* ---- parser state (shared by the importer's files) ------------------------------- */

#define TT__PI 3.14159265358979323846
#define TT__MAX_INCLUDE_DEPTH 64
#define TT__MAX_WARNINGS 200
#define TT__MAT_INTERFACE (-2)

/* One source file: its text stays alive until the load ends (tokens point into it). */
typedef struct tt__pfile {
  char *path; /* as named (resolved against the includer) */
  char *dir;  /* directory for relative paths inside it */
  char *text;
  size_t len, pos;
  int line;
  struct tt__pfile *parent; /* includer while open */
  struct tt__pfile *next;   /* list of all files, for freeing */
} tt__pfile;

enum { TK_EOF, TK_WORD, TK_STRING, TK_LBRACK, TK_RBRACK };

typedef struct tt__tok {
  int kind;
  const char *s; /* WORD: the word; STRING: the raw content between the quotes */
  size_t n;
  const tt__pfile *file;
  int line;
} tt__tok;

/* One "type name" [values] parameter; values are copied so tokens can go. */
typedef struct tt__pparam {
  char type[24];
  char name[64];
  double *num;
  size_t nnum;
  char **str;
  size_t nstr;
  int used;
} tt__pparam;

typedef struct tt__plist {
  tt__pparam *p;
  size_t n, cap;
  /* names the importer asked for (tt__find), for "did you mean" about the others */
  char asked[48][40];
  unsigned nasked;
} tt__plist;

/* A colour parameter's value: rgb times an optional image texture (scene index). */
typedef struct tt__texval {
  float rgb[3];
  int32_t tex;
} tt__texval;

/* A named pbrt texture, resolved to a constant or to one image at definition time. */
typedef struct tt__ntex {
  char *name;
  int is_float;
  float rgb[3];
  char *image; /* resolved image path (NULL: constant) */
  int srgb;
} tt__ntex;

typedef struct tt__named_mat {
  char *name;
  int32_t mat; /* scene material index or TT__MAT_INTERFACE */
} tt__named_mat;

typedef struct tt__coordsys {
  char *name;
  double m[16], m_end[16]; /* the CTM at the start and at the end time */
} tt__coordsys;

/* A shape recorded inside ObjectBegin/End, already in world space of the definition. */
typedef struct tt__objmesh {
  tt__mesh_data d;
  int32_t mat;
} tt__objmesh;

typedef struct tt__object {
  char *name;
  tt__objmesh *m;
  size_t n, cap;
} tt__object;

/* An emissive copy of a material, shared by all shapes with the same area light. */
typedef struct tt__derived {
  int32_t base;
  float L[3];
  int two_sided;
  int32_t mat;
} tt__derived;

/* What AttributeBegin saves. */
typedef struct tt__gstate {
  double ctm[16];
  double ctm_end[16];    /* the CTM at the end time (ActiveTransform); == ctm: not animated */
  unsigned active;       /* TT__ACTIVE_* bits: which CTMs the transform directives change */
  double t_start, t_end; /* TransformTimes (default 0, 1) */
  int reverse;
  int32_t mat; /* -1: pbrt's default diffuse (created on first use) */
  int area;    /* an AreaLightSource is active */
  float L[3];
  int two_sided;
  int kind; /* 'A' attribute, 'T' transform, 'O' object: which End closes it */
  const tt__pfile *file;
  int line;
} tt__gstate;

typedef struct tt__pp {
  tt_scene *scene;
  tt__pfile *cur;   /* innermost open file */
  tt__pfile *files; /* every file read */
  int depth;
  tt__tok peek;
  int has_peek;
  char **warned;
  size_t nwarned, capwarned;
  unsigned warnings, suppressed;
  int strict;              /* TT_SCENE_LOAD_STRICT: unknown input is an error */
  unsigned strict_errors;  /* such errors seen (each logged) */
  char strict_first[1100]; /* "file:line: message" of the first */
  tt__gstate gs;
  tt__gstate *stack;
  size_t nstack, capstack;
  tt__named_mat *nmat;
  size_t nnmat, capnmat;
  tt__ntex *ntex;
  size_t nntex, capntex;
  tt__coordsys *cs;
  size_t ncs, capcs;
  tt__object *obj;
  size_t nobj, capobj;
  int cur_obj; /* index of the object being defined, or -1 */
  tt__derived *der;
  size_t nder, capder;
  int32_t default_mat;
  int world_ready; /* camera and mirror are fixed */
  int in_world;
  double W[16]; /* world mirror applied to everything */
  int has_camera;
  double cam_ctm[16];               /* pbrt cameraFromWorld */
  double cam_ctm_end[16];           /* ... at the end time (cam_animated) */
  int cam_animated;                 /* the Camera's CTM was animated (ActiveTransform) */
  double cam_t0, cam_t1;            /* its TransformTimes */
  const struct tt__pfile *cam_file; /* where the Camera directive is, for messages */
  int cam_line;
  double fov;
  double sw[4];
  int has_sw;
  double frame_aspect; /* 0: from the resolution */
  long xres, yres;
  int env_seen;
} tt__pp;

/* ---- lexer: files, tokens, messages (pbrt_lexer.c) ------------------------------- */

/* "file:line: message" as a TT_ERR_PARSE error. */
tt_status tt__perr(const tt__pfile *f, int line, const char *fmt, ...) TT_PRINTF(3, 4);

/* One warning per (file:line, key) through the log host, so a shape included twice warns
 * once. */
void tt__pwarn(tt__pp *P, const tt__pfile *f, int line, const char *key, const char *fmt, ...)
    TT_PRINTF(5, 6);

/* Input pbrt-v4 itself rejects (an unknown directive or parameter): with P->strict an
 * error (logged; the load fails with the first, tt__pstrict_result), else a warning as
 * tt__pwarn that says --strict would refuse it. */
void tt__pstrict(tt__pp *P, const tt__pfile *f, int line, const char *key, const char *fmt, ...)
    TT_PRINTF(5, 6);

/* TT_OK, or TT_ERR_PARSE with the first strict error (and how many more were logged). */
tt_status tt__pstrict_result(const tt__pp *P);

/* Joins a relative path to a directory; absolute paths pass through. */
char *tt__join(const char *dir, const char *rel, size_t rel_len);

/* True when the path names a readable regular file (a FIFO is not probed by opening it
 * blocking, and is not one). */
int tt__exists(const char *path);

/* Generic growth for the parser's arrays. */
void *tt__grow(void *items, size_t *cap, size_t need, size_t size);

/* Opens a file onto the include stack (parent = current file). */
tt_status tt__push_file(tt__pp *P, const char *path, const tt__pfile *from, int from_line);

/* Next token, honouring one token of lookahead. */
tt_status tt__next(tt__pp *P, tt__tok *t);

/* Looks at the next token without consuming it. */
tt_status tt__peek(tt__pp *P, tt__tok *t);

/* Copies a string token's content, resolving \" \\ \n \t escapes. */
char *tt__tokstr(const tt__tok *t);

/* Token equals a literal word. */
int tt__is(const tt__tok *t, const char *w);

/* Parses a WORD as a finite number; 0 when it is not one. */
int tt__num(const tt__tok *t, double *v);

/* Short description of a token for messages. */
const char *tt__desc(const tt__tok *t, char *buf, size_t n);

/* Reads one quoted string argument of a directive. */
tt_status tt__arg_str(tt__pp *P, const tt__tok *dir, const char *what, char **out);

/* Reads n numbers, optionally inside [ ] (Transform, ConcatTransform accept both). */
tt_status tt__arg_nums(tt__pp *P, const tt__tok *dir, int n, double *v);

/* ---- parameter lists (pbrt_params.c) --------------------------------------------- */

/* Frees a parameter list's contents. */
void tt__plist_free(tt__plist *pl);

/* Reads "type name" value pairs until the next token is not a string. */
tt_status tt__params(tt__pp *P, tt__plist *pl);

/* Last parameter with this name (pbrt lets later ones win); marks it used. */
tt__pparam *tt__find(tt__plist *pl, const char *name);

/* Warns about every parameter nobody read. */
void tt__unused(tt__pp *P, const tt__tok *at, const char *what, tt__plist *pl);

/* A single float (or integer); textures are not supported for scalars. */
tt_status tt__getf(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *name, double *v);

/* A bool parameter. */
tt_status tt__getb(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *name, int *v);

/* A string parameter (NULL stays when absent); the pointer lives in the list. */
tt_status tt__gets(const tt__tok *at, tt__plist *pl, const char *name, const char **v);

/* A point/vector of 3 numbers. */
tt_status tt__get3(const tt__tok *at, tt__plist *pl, const char *name, double v[3]);

/* Resolves a texture name to its value; unknown names warn and keep the default. */
const tt__ntex *tt__lookup_tex(tt__pp *P, const char *name, int is_float);

/* A colour-like parameter: rgb, spectrum (named, inline pairs or .spd file), blackbody,
 * float (grey) or texture. `found` reports whether it was given. */
tt_status tt__getc(tt__pp *P, const tt__tok *at, tt__plist *pl, const char *name,
                   tt__spectrum_use use, int allow_tex, tt__texval *v, int *found);

/* ---- graphics state, transforms, camera, options (pbrt_state.c) ------------------ */

/* Identity matrix. */
void tt__ident(double m[16]);

/* Gauss-Jordan inverse with partial pivoting; 0 when singular. */
int tt__inverse(const double m[16], double inv[16]);

/* Applies M to a point. */
void tt__xform_point(const double m[16], const double p[3], double o[3]);

/* Applies M's linear part to a direction. */
void tt__xform_vec(const double m[16], const double v[3], double o[3]);

/* Normalises in place; 0 for a zero or non-finite vector. */
int tt__norm(double v[3]);

/* a x b. */
void tt__cross(const double a[3], const double b[3], double o[3]);

#define TT__ACTIVE_START 1u
#define TT__ACTIVE_END 2u
#define TT__ACTIVE_ALL 3u

/* Replaces the active CTMs (Transform, Identity). */
void tt__ctm_set(tt__pp *P, const double m[16]);

/* Post-multiplies the CTM, as every pbrt transform directive does. */
void tt__concat(tt__pp *P, const double m[16]);

/* Pushes the graphics state for AttributeBegin / TransformBegin / ObjectBegin. */
tt_status tt__push(tt__pp *P, int kind, const tt__tok *at);

/* Pops for the matching End; TransformEnd restores only the CTM. */
void tt__pop(tt__pp *P, int kind, const tt__tok *at);

/* Fixes the camera pose and the world mirror (at WorldBegin, or at the first world item
 * of a file that has none). */
void tt__world_setup(tt__pp *P);

/* The world matrix of a shape: mirror * CTM. */
void tt__world_matrix(tt__pp *P, const double ctm[16], double m[16]);

/* Camera: remembers the CTM (cameraFromWorld) and the field of view. */
tt_status tt__camera(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl);

/* Film / Sampler / Integrator: the few values tunetrace keeps; the rest is silent. */
tt_status tt__option(tt__pp *P, const tt__tok *at, const char *dir, tt__plist *pl);

/* ---- materials and textures (pbrt_materials.c) ----------------------------------- */

/* Creates a tt_material from a pbrt material type and its parameters; *out is the scene
 * index, or TT__MAT_INTERFACE for "interface" (no surface). */
tt_status tt__make_material(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl,
                            const char *name, int32_t *out);

/* The material a shape gets: the current one (pbrt's default diffuse if none) with the
 * active area light's emission folded into a derived copy. */
tt_status tt__shape_material(tt__pp *P, int emissive, int32_t *out);

/* Texture directive: imagemap keeps its file; scale multiplies; others become constants. */
tt_status tt__texture(tt__pp *P, const tt__tok *at, const char *name, const char *kind,
                      const char *cls, tt__plist *pl);

/* ---- shapes and object instances (pbrt_geometry.c) ------------------------------- */

/* Shape directive: builds object-space triangles for the supported shape types. */
tt_status tt__shape(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl);

/* ObjectInstance: copies the object's meshes through the current CTM. */
tt_status tt__instance(tt__pp *P, const tt__tok *at, const char *name);

/* ---- lights (pbrt_lights.c) ------------------------------------------------------ */

/* LightSource: point, spot, distant and infinite map to tunetrace lights. */
tt_status tt__light(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl);

/* AreaLightSource "diffuse": emission for the shapes that follow in this attribute block. */
tt_status tt__area_light(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl);

/* ---- directives (pbrt_directives.c) ---------------------------------------------- */

/* Reads one directive and applies it. *done is set at the end of input. */
tt_status tt__directive(tt__pp *P, int *done);

/* ---- animated transforms (pbrt_motion.c) ---------------------------------------------- */

/* The start- and end-time CTMs differ. */
int tt__ctm_animated(const tt__pp *P);

/* An animated placement split for scene/anim.h: `pre` goes into the mesh once (its frame),
 * then translate t, rotate q and (has_scale) scale s at the start (index 0) and end time. */
typedef struct tt__motion {
  double pre[16];
  float t[2][3], q[2][4], s[2][3];
  int has_scale;
} tt__motion;

/* Decomposes the world matrices m0 (start) and m1 (end) of a shape (`what` at `at`, for
 * messages); an error names the file and line for a singular, non-affine, one-sided
 * mirroring or shearing motion, or TransformTimes without a span. */
tt_status tt__motion_split(const tt__pp *P, const tt__tok *at, const char *what,
                           const double m0[16], const double m1[16], tt__motion *mo);

/* Makes scene mesh `mesh` (already placed by mo->pre) move by `mo` over TransformTimes. */
tt_status tt__motion_attach(tt__pp *P, uint32_t mesh, const tt__motion *mo);

/* An animated Camera (P->cam_animated) becomes a camera path: keys over its TransformTimes,
 * at most 5 degrees of turn apart, each the camera pbrt's interpolated worldFromCamera gives
 * (under the world mirror of the start camera); called once the still camera is set. */
tt_status tt__motion_camera(tt__pp *P);

#endif /* TT_PBRT_INTERNAL_H */
