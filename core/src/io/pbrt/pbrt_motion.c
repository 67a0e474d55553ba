/* pbrt-v4 importer: animated transforms (ActiveTransform StartTime/EndTime/All,
 * TransformTimes). pbrt keeps two CTMs, one at the start and one at the end time, and
 * interpolates a shape's placement between them as AnimatedTransform does: each end is
 * decomposed as M = T R S (polar decomposition), T is interpolated linearly, R by slerp
 * along the shorter arc, S linearly; before the start and after the end the placement is
 * clamped. pbrt uses this for motion blur within the shutter; tunetrace plays it as
 * animation over the sequence's time axis (frame f at f / fps), so a shape moves from its
 * start-time placement at TransformTimes' start to its end-time placement at the end, and
 * a still renders the start time. The motion becomes one node of scene/anim.h with a
 * translate, a rotate and (when the scale is axis-aligned) a scale track; a constant
 * scale that is not axis-aligned, and a mirror, are applied to the mesh once, in its own
 * frame. A scale that is not axis-aligned and changes between the ends (a shear in
 * motion) is refused: tunetrace's tracks hold an axis-aligned scale only. */
#include "io/pbrt/pbrt_internal.h"
#include "scene/anim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int tt__ctm_animated(const tt__pp *P) {
  /* by value: -0 and 0 (one transform's rounding, not motion) are the same */
  for (int i = 0; i < 16; i++)
    if (P->gs.ctm[i] != P->gs.ctm_end[i]) return 1;
  return 0;
}

/* 3x3 helpers on the upper-left block of a row-major 4x4 (a[3 * r + c]). */
static double tt__det3(const double a[9]) {
  return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
         a[2] * (a[3] * a[7] - a[4] * a[6]);
}

/* Inverse transpose of a 3x3 with determinant det (non-zero). */
static void tt__inv_t3(const double a[9], double det, double o[9]) {
  o[0] = (a[4] * a[8] - a[5] * a[7]) / det;
  o[1] = (a[5] * a[6] - a[3] * a[8]) / det;
  o[2] = (a[3] * a[7] - a[4] * a[6]) / det;
  o[3] = (a[2] * a[7] - a[1] * a[8]) / det;
  o[4] = (a[0] * a[8] - a[2] * a[6]) / det;
  o[5] = (a[1] * a[6] - a[0] * a[7]) / det;
  o[6] = (a[1] * a[5] - a[2] * a[4]) / det;
  o[7] = (a[2] * a[3] - a[0] * a[5]) / det;
  o[8] = (a[0] * a[4] - a[1] * a[3]) / det;
}

/* Polar decomposition A = R P of a 3x3 with positive determinant (R a rotation, P
 * symmetric positive definite), by pbrt's iteration R <- (R + R^-T) / 2. */
static void tt__polar(const double a[9], double r[9], double p[9]) {
  memcpy(r, a, 9 * sizeof *a);
  for (int it = 0; it < 100; it++) {
    double it3[9], next[9], diff = 0;
    tt__inv_t3(r, tt__det3(r), it3);
    for (int i = 0; i < 9; i++) {
      next[i] = 0.5 * (r[i] + it3[i]);
      diff = fmax(diff, fabs(next[i] - r[i]));
    }
    memcpy(r, next, sizeof next);
    if (diff < 1e-14) break;
  }
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double v = 0;
      for (int k = 0; k < 3; k++) v += r[3 * k + i] * a[3 * k + j]; /* R^T A */
      p[3 * i + j] = v;
    }
  for (int i = 0; i < 3; i++)
    for (int j = i + 1; j < 3; j++)
      p[3 * i + j] = p[3 * j + i] = 0.5 * (p[3 * i + j] + p[3 * j + i]);
}

/* Unit quaternion (x, y, z, w) of a rotation matrix. */
static void tt__quat_of(const double r[9], float q[4]) {
  double x, y, z, w, tr = r[0] + r[4] + r[8];
  if (tr > 0) {
    double s = sqrt(tr + 1.0) * 2;
    w = s / 4, x = (r[7] - r[5]) / s, y = (r[2] - r[6]) / s, z = (r[3] - r[1]) / s;
  } else if (r[0] > r[4] && r[0] > r[8]) {
    double s = sqrt(1.0 + r[0] - r[4] - r[8]) * 2;
    w = (r[7] - r[5]) / s, x = s / 4, y = (r[1] + r[3]) / s, z = (r[2] + r[6]) / s;
  } else if (r[4] > r[8]) {
    double s = sqrt(1.0 + r[4] - r[0] - r[8]) * 2;
    w = (r[2] - r[6]) / s, x = (r[1] + r[3]) / s, y = s / 4, z = (r[5] + r[7]) / s;
  } else {
    double s = sqrt(1.0 + r[8] - r[0] - r[4]) * 2;
    w = (r[3] - r[1]) / s, x = (r[2] + r[6]) / s, y = (r[5] + r[7]) / s, z = s / 4;
  }
  double l = sqrt(x * x + y * y + z * z + w * w);
  q[0] = (float)(x / l), q[1] = (float)(y / l), q[2] = (float)(z / l), q[3] = (float)(w / l);
}

/* Largest off-diagonal magnitude relative to the largest diagonal one. */
static double tt__offdiag(const double p[9]) {
  double d = fmax(fabs(p[0]), fmax(fabs(p[4]), fabs(p[8])));
  double o = fmax(fabs(p[1]), fmax(fabs(p[2]), fabs(p[5])));
  return d > 0 ? o / d : INFINITY;
}

/* tt__motion_split with explicit times and place. */
static tt_status tt__motion_split_at(const tt__pfile *file, int line, const char *what, double t0,
                                     double t1, const double m0[16], const double m1[16],
                                     tt__motion *mo) {
  memset(mo, 0, sizeof *mo);
  if (!(t1 > t0))
    return tt__perr(file, line,
                    "%s: the transform is animated (ActiveTransform) but TransformTimes gives no "
                    "time span (start %g, end %g): expected end > start",
                    what, t0, t1);
  const double *m[2] = {m0, m1};
  double a[2][9], det[2];
  for (int e = 0; e < 2; e++) {
    if (m[e][12] != 0 || m[e][13] != 0 || m[e][14] != 0 || m[e][15] != 1)
      return tt__perr(file, line, "%s: the %s-time transform is not affine", what,
                      e ? "end" : "start");
    for (int r = 0; r < 3; r++)
      for (int c = 0; c < 3; c++) a[e][3 * r + c] = m[e][4 * r + c];
    det[e] = tt__det3(a[e]);
    if (!(det[e] != 0) || !isfinite(det[e]))
      return tt__perr(file, line, "%s: the %s-time transform is singular", what,
                      e ? "end" : "start");
  }
  if ((det[0] < 0) != (det[1] < 0))
    return tt__perr(file, line,
                    "%s: the animated transform mirrors at one end only (the start- and "
                    "end-time transforms' determinants have opposite signs, so the shape would "
                    "turn inside out on the way)",
                    what);
  /* a mirror F = diag(-1, 1, 1) is taken out first: M F then has a positive determinant */
  const int mirror = det[0] < 0;
  double r[2][9], p[2][9];
  for (int e = 0; e < 2; e++) {
    if (mirror)
      for (int row = 0; row < 3; row++) a[e][3 * row] = -a[e][3 * row];
    tt__polar(a[e], r[e], p[e]);
    tt__quat_of(r[e], mo->q[e]);
    for (int k = 0; k < 3; k++) mo->t[e][k] = (float)m[e][4 * k + 3];
  }
  double pre[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (tt__offdiag(p[0]) < 1e-7 && tt__offdiag(p[1]) < 1e-7) {
    mo->has_scale = 1;
    for (int e = 0; e < 2; e++)
      for (int k = 0; k < 3; k++) mo->s[e][k] = (float)p[e][4 * k];
  } else {
    double dmax = 0, pmax = 0;
    for (int i = 0; i < 9; i++) {
      dmax = fmax(dmax, fabs(p[0][i] - p[1][i]));
      pmax = fmax(pmax, fabs(p[0][i]));
    }
    if (dmax > 1e-7 * pmax)
      return tt__perr(file, line,
                      "%s: the animated transform changes a scale that is not axis-aligned (a "
                      "shear) between the start and end times; tunetrace animates translation, "
                      "rotation and axis-aligned scale (keep such a scale the same at both ends)",
                      what);
    memcpy(pre, p[0], sizeof pre);
  }
  /* B = pre * F, applied to the mesh once, in its own frame */
  tt__ident(mo->pre);
  for (int row = 0; row < 3; row++)
    for (int c = 0; c < 3; c++)
      mo->pre[4 * row + c] = pre[3 * row + c] * (mirror && c == 0 ? -1 : 1);
  return TT_OK;
}

tt_status tt__motion_split(const tt__pp *P, const tt__tok *at, const char *what,
                           const double m0[16], const double m1[16], tt__motion *mo) {
  return tt__motion_split_at(at->file, at->line, what, P->gs.t_start, P->gs.t_end, m0, m1, mo);
}

tt_status tt__motion_attach(tt__pp *P, uint32_t mesh, const tt__motion *mo) {
  tt_scene *s = P->scene;
  uint32_t node;
  tt_status st = tt__scene_anim_add_node(s, -1, &node);
  if (st != TT_OK) return st;
  tt__anim_node *n = tt__scene_anim_node(s, node);
  const double times[2] = {P->gs.t_start, P->gs.t_end};
  if (tt__track_alloc(&n->tr, 2, 3, TT__INTERP_LINEAR) != TT_OK ||
      tt__track_alloc(&n->rot, 2, 4, TT__INTERP_LINEAR) != TT_OK ||
      (mo->has_scale && tt__track_alloc(&n->sc, 2, 3, TT__INTERP_LINEAR) != TT_OK))
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  n->rot.rotation = 1;
  for (int e = 0; e < 2; e++) {
    n->tr.times[e] = n->rot.times[e] = times[e];
    memcpy(n->tr.values + 3 * e, mo->t[e], sizeof mo->t[e]);
    memcpy(n->rot.values + 4 * e, mo->q[e], sizeof mo->q[e]);
    if (mo->has_scale) {
      n->sc.times[e] = times[e];
      memcpy(n->sc.values + 3 * e, mo->s[e], sizeof mo->s[e]);
    }
  }
  tt__track_align_rotations(&n->rot); /* pbrt: the shorter way */
  tt__mesh_anim *ma = NULL;
  if ((st = tt__scene_anim_add_mesh(s, mesh, &ma)) != TT_OK) return st;
  ma->node = (int32_t)node;
  return TT_OK;
}

/* ---- an animated camera ------------------------------------------------------------------ */

/* Slerp of unit quaternions along the shorter arc (as pbrt's AnimatedTransform). */
static void tt__qslerp(const float a[4], const float b[4], double u, double o[4]) {
  double d = 0, sb = 1;
  for (int i = 0; i < 4; i++) d += (double)a[i] * b[i];
  if (d < 0) d = -d, sb = -1;
  double wa = 1 - u, wb = u;
  if (d < 0.9995) {
    double th = acos(d), s = sin(th);
    wa = sin((1 - u) * th) / s;
    wb = sin(u * th) / s;
  }
  double l = 0;
  for (int i = 0; i < 4; i++) {
    o[i] = wa * a[i] + wb * sb * b[i];
    l += o[i] * o[i];
  }
  l = sqrt(l);
  for (int i = 0; i < 4; i++) o[i] /= l;
}

/* Row-major 3x3 of a unit quaternion (x, y, z, w). */
static void tt__qmat(const double q[4], double r[9]) {
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  r[0] = 1 - 2 * (y * y + z * z), r[1] = 2 * (x * y - z * w), r[2] = 2 * (x * z + y * w);
  r[3] = 2 * (x * y + z * w), r[4] = 1 - 2 * (x * x + z * z), r[5] = 2 * (y * z - x * w);
  r[6] = 2 * (x * z - y * w), r[7] = 2 * (y * z + x * w), r[8] = 1 - 2 * (x * x + y * y);
}

tt_status tt__motion_camera(tt__pp *P) {
  if (!P->cam_animated) return TT_OK;
  double c0[16], c1[16];
  if (!tt__inverse(P->cam_ctm, c0) || !tt__inverse(P->cam_ctm_end, c1))
    return tt__perr(P->cam_file, P->cam_line, "Camera: the current transform is singular");
  /* pbrt interpolates worldFromCamera */
  tt__motion mo;
  tt_status st =
      tt__motion_split_at(P->cam_file, P->cam_line, "Camera", P->cam_t0, P->cam_t1, c0, c1, &mo);
  if (st != TT_OK) return st;
  double d = 0;
  for (int i = 0; i < 4; i++) d += (double)mo.q[0][i] * mo.q[1][i];
  const double turn = 2 * acos(fmin(1.0, fabs(d))) * 180 / 3.14159265358979323846;
  uint32_t n = (uint32_t)ceil(turn / 5.0);
  if (n < 1) n = 1;
  tt_scene *s = P->scene;
  tt_camera *cam = &s->camera;
  free(s->keys);
  s->keys = calloc(n + 1, sizeof *s->keys);
  cam->keys = s->keys;
  cam->key_count = 0;
  if (!s->keys) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory");
  const double sx = P->W[0]; /* the world mirror fixed by the start camera */
  for (uint32_t k = 0; k <= n; k++) {
    const double u = (double)k / n;
    double q[4], r[9], m[9], pos[3], f[3], up[3];
    tt__qslerp(mo.q[0], mo.q[1], u, q);
    tt__qmat(q, r);
    double sc[3] = {1, 1, 1};
    for (int i = 0; mo.has_scale && i < 3; i++) sc[i] = (1 - u) * mo.s[0][i] + u * mo.s[1][i];
    /* M = R S pre (3x3): the camera's +z and +y in the world; its origin is the translation */
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) {
        double v = 0;
        for (int l = 0; l < 3; l++) v += r[3 * i + l] * sc[l] * mo.pre[4 * l + j];
        m[3 * i + j] = v;
      }
    for (int i = 0; i < 3; i++) {
      pos[i] = (1 - u) * mo.t[0][i] + u * mo.t[1][i];
      f[i] = m[3 * i + 2];
      up[i] = m[3 * i + 1];
    }
    if (!tt__norm(f) || !tt__norm(up))
      return tt__perr(P->cam_file, P->cam_line, "Camera: a degenerate animated camera transform");
    pos[0] *= sx, f[0] *= sx, up[0] *= sx;
    tt_camera_key *key = &s->keys[k];
    key->time = (float)(P->cam_t0 + (P->cam_t1 - P->cam_t0) * u);
    for (int i = 0; i < 3; i++) {
      key->position[i] = (float)pos[i];
      key->target[i] = (float)(pos[i] + f[i]);
      key->up[i] = (float)up[i];
    }
    key->fov_y = cam->fov_y;
  }
  cam->key_count = n + 1;
  return TT_OK;
}
