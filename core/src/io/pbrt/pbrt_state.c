/* pbrt-v4 importer: matrices, the graphics state (AttributeBegin/End, the CTM), the world
 * setup (camera pose and world mirror, see below), Camera and the rendering options.
 *
 * Handedness: pbrt's camera space is left-handed (+x right, +y up, +z forward), while
 * tunetrace's camera puts `right = forward x up`. When the scene's camera transform keeps
 * pbrt's handedness, the whole world is mirrored (x -> -x) so that what pbrt shows on the
 * right of the image is on the right here too; files that already flip with `Scale -1 1 1`
 * are left alone. */
#include "io/pbrt/pbrt_internal.h"
#include "plugin/log.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---- matrices (row-major, column vectors: p' = M p, as pbrt) ---------------------------- */

/* Identity matrix. */
void tt__ident(double m[16]) {
  memset(m, 0, 16 * sizeof *m);
  m[0] = m[5] = m[10] = m[15] = 1.0;
}

/* Gauss-Jordan inverse with partial pivoting; 0 when singular. */
int tt__inverse(const double m[16], double inv[16]) {
  double a[4][8];
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 8; j++) a[i][j] = j < 4 ? m[4 * i + j] : (j - 4 == i);
  for (int c = 0; c < 4; c++) {
    int piv = c;
    for (int r = c + 1; r < 4; r++)
      if (fabs(a[r][c]) > fabs(a[piv][c])) piv = r;
    if (!(fabs(a[piv][c]) > 1e-300)) return 0;
    if (piv != c)
      for (int j = 0; j < 8; j++) {
        double t = a[c][j];
        a[c][j] = a[piv][j];
        a[piv][j] = t;
      }
    double d = a[c][c];
    for (int j = 0; j < 8; j++) a[c][j] /= d;
    for (int r = 0; r < 4; r++)
      if (r != c) {
        double f = a[r][c];
        for (int j = 0; j < 8; j++) a[r][j] -= f * a[c][j];
      }
  }
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) inv[4 * i + j] = a[i][j + 4];
  for (int i = 0; i < 16; i++)
    if (!isfinite(inv[i])) return 0;
  return 1;
}

/* Applies M to a point. */
void tt__xform_point(const double m[16], const double p[3], double o[3]) {
  double w = m[12] * p[0] + m[13] * p[1] + m[14] * p[2] + m[15];
  for (int r = 0; r < 3; r++)
    o[r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
  if (w != 1.0 && w != 0.0)
    for (int r = 0; r < 3; r++) o[r] /= w;
}

/* Applies M's linear part to a direction. */
void tt__xform_vec(const double m[16], const double v[3], double o[3]) {
  for (int r = 0; r < 3; r++) o[r] = m[4 * r] * v[0] + m[4 * r + 1] * v[1] + m[4 * r + 2] * v[2];
}

/* Normalises in place; 0 for a zero or non-finite vector. */
int tt__norm(double v[3]) {
  double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(l > 0) || !isfinite(l)) return 0;
  for (int i = 0; i < 3; i++) v[i] /= l;
  return 1;
}

/* a x b. */
void tt__cross(const double a[3], const double b[3], double o[3]) {
  o[0] = a[1] * b[2] - a[2] * b[1];
  o[1] = a[2] * b[0] - a[0] * b[2];
  o[2] = a[0] * b[1] - a[1] * b[0];
}

/* ---- graphics state -------------------------------------------------------------------- */

/* Replaces the active CTMs (Transform, Identity). */
void tt__ctm_set(tt__pp *P, const double m[16]) {
  if (P->gs.active & TT__ACTIVE_START) memcpy(P->gs.ctm, m, sizeof P->gs.ctm);
  if (P->gs.active & TT__ACTIVE_END) memcpy(P->gs.ctm_end, m, sizeof P->gs.ctm_end);
}

/* Post-multiplies the active CTMs, as every pbrt transform directive does. */
void tt__concat(tt__pp *P, const double m[16]) {
  if (P->gs.active & TT__ACTIVE_START) tt__mat4_mul(P->gs.ctm, P->gs.ctm, m);
  if (P->gs.active & TT__ACTIVE_END) tt__mat4_mul(P->gs.ctm_end, P->gs.ctm_end, m);
}

/* Pushes the graphics state for AttributeBegin / TransformBegin / ObjectBegin. */
tt_status tt__push(tt__pp *P, int kind, const tt__tok *at) {
  P->stack = tt__grow(P->stack, &P->capstack, P->nstack + 1, sizeof *P->stack);
  if (!P->stack) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  P->stack[P->nstack] = P->gs;
  P->stack[P->nstack].kind = kind;
  P->stack[P->nstack].file = at->file;
  P->stack[P->nstack].line = at->line;
  P->nstack++;
  return TT_OK;
}

/* Pops for the matching End; TransformEnd restores only the CTM. */
void tt__pop(tt__pp *P, int kind, const tt__tok *at) {
  static const char *const names[] = {"AttributeEnd", "TransformEnd", "ObjectEnd"};
  const char *nm = names[kind == 'A' ? 0 : kind == 'T' ? 1 : 2];
  if (P->nstack == 0) {
    tt__pwarn(P, at->file, at->line, nm, "unmatched %s (ignored)", nm);
    return;
  }
  tt__gstate *top = &P->stack[P->nstack - 1];
  if (top->kind != kind)
    tt__pwarn(P, at->file, at->line, nm, "%s closes the block opened at %s:%d by a different Begin",
              nm, top->file ? top->file->path : "?", top->line);
  if (kind == 'T') {
    memcpy(P->gs.ctm, top->ctm, sizeof P->gs.ctm);
    memcpy(P->gs.ctm_end, top->ctm_end, sizeof P->gs.ctm_end);
  } else {
    P->gs = *top;
  }
  P->nstack--;
}

/* Fixes the camera pose and the world mirror (at WorldBegin, or at the first world item
 * of a file that has none). */
void tt__world_setup(tt__pp *P) {
  if (P->world_ready) return;
  P->world_ready = 1;
  tt__ident(P->W);
  double C[16];
  if (!P->has_camera || !tt__inverse(P->cam_ctm, C)) tt__ident(C);
  double o[3] = {0, 0, 0}, z[3] = {0, 0, 1}, y[3] = {0, 1, 0}, x[3] = {1, 0, 0};
  double pos[3], f[3], up[3], right[3], r2[3];
  tt__xform_point(C, o, pos);
  tt__xform_vec(C, z, f);
  tt__xform_vec(C, y, up);
  tt__xform_vec(C, x, right);
  if (!tt__norm(f)) f[0] = 0, f[1] = 0, f[2] = 1;
  if (!tt__norm(up)) up[0] = 0, up[1] = 1, up[2] = 0;
  /* tunetrace's right is forward x up; mirror the world when pbrt's +x disagrees */
  tt__cross(f, up, r2);
  if (r2[0] * right[0] + r2[1] * right[1] + r2[2] * right[2] < 0) {
    P->W[0] = -1.0;
    pos[0] = -pos[0];
    f[0] = -f[0];
    up[0] = -up[0];
  }
  tt_camera *c = &P->scene->camera;
  for (int i = 0; i < 3; i++) {
    c->position[i] = (float)pos[i];
    c->target[i] = (float)(pos[i] + f[i]);
    c->up[i] = (float)up[i];
  }
}

/* The world matrix of a shape: mirror * CTM. */
void tt__world_matrix(tt__pp *P, const double ctm[16], double m[16]) {
  tt__world_setup(P);
  tt__mat4_mul(m, P->W, ctm);
}

/* ---- camera and options ---------------------------------------------------------------- */

/* Camera: remembers the CTM (cameraFromWorld) and the field of view. */
tt_status tt__camera(tt__pp *P, const tt__tok *at, const char *type, tt__plist *pl) {
  tt_status st;
  if (strcmp(type, "perspective") != 0)
    tt__pwarn(P, at->file, at->line, type, "camera \"%s\" is approximated by a perspective camera",
              type);
  P->has_camera = 1;
  memcpy(P->cam_ctm, P->gs.ctm, sizeof P->cam_ctm);
  /* an animated camera becomes a camera path (tt__motion_camera, at the end of the file) */
  P->cam_animated = tt__ctm_animated(P);
  memcpy(P->cam_ctm_end, P->gs.ctm_end, sizeof P->cam_ctm_end);
  P->cam_t0 = P->gs.t_start;
  P->cam_t1 = P->gs.t_end;
  P->cam_file = at->file;
  P->cam_line = at->line;
  double fov = 90, lens = 0, fa = 0;
  if ((st = tt__getf(P, at, pl, "fov", &fov)) != TT_OK) return st;
  if (!(fov > 0 && fov < 180))
    return tt__perr(at->file, at->line, "Camera: fov %g is outside (0, 180)", fov);
  P->fov = fov;
  if ((st = tt__getf(P, at, pl, "lensradius", &lens)) != TT_OK) return st;
  tt__find(pl, "focaldistance");
  if (lens > 0)
    tt__pwarn(P, at->file, at->line, "lensradius",
              "Camera: depth of field (lensradius) is not supported (pinhole used)");
  if ((st = tt__getf(P, at, pl, "frameaspectratio", &fa)) != TT_OK) return st;
  P->frame_aspect = fa > 0 ? fa : 0;
  tt__pparam *sw = tt__find(pl, "screenwindow");
  if (sw) {
    if (!sw->num || sw->nnum != 4 || !(sw->num[1] > sw->num[0]) || !(sw->num[3] > sw->num[2]))
      return tt__perr(at->file, at->line,
                      "Camera: \"screenwindow\" needs 4 numbers x0 x1 y0 y1 with x0 < x1, y0 < y1");
    for (int i = 0; i < 4; i++) P->sw[i] = sw->num[i];
    P->has_sw = 1;
    if (fabs(sw->num[0] + sw->num[1]) > 1e-6 || fabs(sw->num[2] + sw->num[3]) > 1e-6)
      tt__pwarn(P, at->file, at->line, "screenwindow",
                "Camera: off-centre screenwindow is centred (only its height is used)");
  }
  tt__find(pl, "shutteropen");
  tt__find(pl, "shutterclose");
  tt__unused(P, at, "Camera", pl);
  /* the camera's own frame is a named coordinate system */
  double inv[16], inv_end[16];
  if (!tt__inverse(P->gs.ctm, inv) || !tt__inverse(P->gs.ctm_end, inv_end))
    return tt__perr(at->file, at->line, "Camera: the current transform is singular");
  for (size_t i = 0; i < P->ncs; i++)
    if (strcmp(P->cs[i].name, "camera") == 0) {
      memcpy(P->cs[i].m, inv, sizeof inv);
      memcpy(P->cs[i].m_end, inv_end, sizeof inv_end);
      return TT_OK;
    }
  P->cs = tt__grow(P->cs, &P->capcs, P->ncs + 1, sizeof *P->cs);
  if (!P->cs) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  P->cs[P->ncs].name = tt__strdup("camera");
  if (!P->cs[P->ncs].name) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  memcpy(P->cs[P->ncs].m, inv, sizeof inv);
  memcpy(P->cs[P->ncs].m_end, inv_end, sizeof inv_end);
  P->ncs++;
  return TT_OK;
}

/* Film / Sampler / Integrator: the few values tunetrace keeps; the rest is silent. */
tt_status tt__option(tt__pp *P, const tt__tok *at, const char *dir, tt__plist *pl) {
  tt_status st;
  if (strcmp(dir, "Film") == 0) {
    double x = (double)P->xres, y = (double)P->yres;
    if ((st = tt__getf(P, at, pl, "xresolution", &x)) != TT_OK) return st;
    if ((st = tt__getf(P, at, pl, "yresolution", &y)) != TT_OK) return st;
    if (!(x >= 1 && x <= 65536 && y >= 1 && y <= 65536))
      return tt__perr(at->file, at->line, "Film: resolution %gx%g is outside 1..65536", x, y);
    P->xres = (long)x;
    P->yres = (long)y;
    if (tt__find(pl, "cropwindow") || tt__find(pl, "pixelbounds"))
      tt__pwarn(P, at->file, at->line, "cropwindow",
                "Film: cropwindow/pixelbounds are not supported (full frame rendered)");
  } else if (strcmp(dir, "Sampler") == 0) {
    double spp = P->scene->settings.spp;
    if ((st = tt__getf(P, at, pl, "pixelsamples", &spp)) != TT_OK) return st;
    if (!(spp >= 1 && spp <= 16777216))
      return tt__perr(at->file, at->line, "Sampler: pixelsamples %g is out of range", spp);
    P->scene->settings.spp = (uint32_t)spp;
  } else if (strcmp(dir, "Integrator") == 0) {
    double md = P->scene->settings.max_depth;
    if ((st = tt__getf(P, at, pl, "maxdepth", &md)) != TT_OK) return st;
    if (!(md >= 0 && md <= 100000))
      return tt__perr(at->file, at->line, "Integrator: maxdepth %g is out of range", md);
    P->scene->settings.max_depth = (uint32_t)md;
  }
  return TT_OK;
}
