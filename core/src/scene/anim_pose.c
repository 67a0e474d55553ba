/* Posing an animated scene (scene/anim.h): node world matrices from their keyframed TRS,
 * then every animated mesh's positions and normals (rigid placement, morph targets,
 * skinning on the CPU), the previous frame's positions for motion vectors, bounds and area
 * light areas. The public entry points are tt_scene_set_time and friends (scene.h). */
#include "scene/anim.h"
#include "scene/scene_internal.h"

#include <tt_util/hash.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double tt__id16[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

/* ---- building ---------------------------------------------------------------------- */

static tt__scene_anim *tt__anim_get(tt_scene *s) {
  if (!s->anim) s->anim = calloc(1, sizeof *s->anim);
  return s->anim;
}

tt_status tt__scene_anim_add_node(tt_scene *s, int32_t parent, uint32_t *index) {
  tt__scene_anim *a = tt__anim_get(s);
  if (!a) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", s->source);
  tt__anim_node *n = tt__scene_push((void **)&a->nodes, &a->node_count, &a->node_cap, sizeof *n);
  if (!n) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", s->source);
  n->parent = parent;
  memcpy(n->rest, tt__id16, sizeof tt__id16);
  n->r[3] = 1.0f;
  n->s[0] = n->s[1] = n->s[2] = 1.0f;
  n->rot.rotation = 1;
  *index = a->node_count - 1;
  return TT_OK;
}

tt__anim_node *tt__scene_anim_node(tt_scene *s, uint32_t index) {
  return s->anim && index < s->anim->node_count ? &s->anim->nodes[index] : NULL;
}

tt_status tt__scene_anim_add_mesh(tt_scene *s, uint32_t mesh, tt__mesh_anim **out) {
  *out = NULL;
  tt__scene_anim *a = tt__anim_get(s);
  if (!a || mesh >= s->mesh_count)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", s->source);
  tt__mesh_anim *m = tt__scene_push((void **)&a->meshes, &a->mesh_count, &a->mesh_cap, sizeof *m);
  if (!m) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", s->source);
  const tt_mesh *v = &s->meshes[mesh];
  size_t n = 3 * (size_t)v->vertex_count;
  m->mesh = mesh;
  m->node = -1;
  memcpy(m->post, tt__id16, sizeof tt__id16);
  m->weights.dim = 0;
  m->rest_pos = malloc(sizeof(float) * (n ? n : 1));
  m->prev = malloc(sizeof(float) * (n ? n : 1));
  if (v->normals) m->rest_nrm = malloc(sizeof(float) * (n ? n : 1));
  if (!m->rest_pos || !m->prev || (v->normals && !m->rest_nrm))
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", s->source);
  memcpy(m->rest_pos, v->positions, sizeof(float) * n);
  memcpy(m->prev, v->positions, sizeof(float) * n);
  if (v->normals) memcpy(m->rest_nrm, v->normals, sizeof(float) * n);
  *out = m;
  return TT_OK;
}

void tt__scene_anim_free(tt__scene_anim *a) {
  if (!a) return;
  for (uint32_t i = 0; i < a->node_count; i++) {
    tt__track_free(&a->nodes[i].tr);
    tt__track_free(&a->nodes[i].rot);
    tt__track_free(&a->nodes[i].sc);
  }
  for (uint32_t i = 0; i < a->mesh_count; i++) {
    tt__mesh_anim *m = &a->meshes[i];
    free(m->rest_pos);
    free(m->rest_nrm);
    free(m->dpos);
    free(m->dnrm);
    free(m->weights0);
    tt__track_free(&m->weights);
    free(m->joint_node);
    free(m->inverse_bind);
    free(m->joint_index);
    free(m->joint_weight);
    free(m->joint_mat);
    free(m->morph_w);
    free(m->prev);
  }
  free(a->nodes);
  free(a->meshes);
  free(a);
}

/* ---- time range ---------------------------------------------------------------------- */

static void tt__range_track(const tt__track *t, double *lo, double *hi, int *any) {
  if (t->count == 0) return;
  if (!*any || t->times[0] < *lo) *lo = t->times[0];
  if (!*any || t->times[t->count - 1] > *hi) *hi = t->times[t->count - 1];
  *any = 1;
}

void tt__scene_anim_range(const tt_scene *s, double *t0, double *t1) {
  double lo = 0, hi = 0;
  int any = 0;
  const tt__scene_anim *a = s->anim;
  for (uint32_t i = 0; a && i < a->node_count; i++) {
    tt__range_track(&a->nodes[i].tr, &lo, &hi, &any);
    tt__range_track(&a->nodes[i].rot, &lo, &hi, &any);
    tt__range_track(&a->nodes[i].sc, &lo, &hi, &any);
  }
  for (uint32_t i = 0; a && i < a->mesh_count; i++)
    tt__range_track(&a->meshes[i].weights, &lo, &hi, &any);
  *t0 = lo;
  *t1 = hi;
}

/* ---- matrices -------------------------------------------------------------------------- */

/* Row-major T * R(q) * S. */
static void tt__trs(const float t[3], const float q[4], const float s[3], double m[16]) {
  double x = q[0], y = q[1], z = q[2], w = q[3];
  double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
                 2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                 2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++) m[4 * i + j] = r[3 * i + j] * s[j];
    m[4 * i + 3] = t[i];
  }
  m[12] = m[13] = m[14] = 0.0;
  m[15] = 1.0;
}

/* r = a * b for affine row-major matrices (r may alias either). */
static void tt__mul(double r[16], const double a[16], const double b[16]) {
  double t[16];
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) {
      double acc = 0;
      for (int k = 0; k < 4; k++) acc += a[4 * i + k] * b[4 * k + j];
      t[4 * i + j] = acc;
    }
  memcpy(r, t, sizeof t);
}

/* World matrices of every node at `time` (parents come first). */
static void tt__pose_nodes(tt__scene_anim *a, double time) {
  for (uint32_t i = 0; i < a->node_count; i++) {
    tt__anim_node *n = &a->nodes[i];
    double local[16];
    if (n->tr.count || n->rot.count || n->sc.count) {
      float t[3], r[4], s[3];
      memcpy(t, n->t, sizeof t);
      memcpy(r, n->r, sizeof r);
      memcpy(s, n->s, sizeof s);
      tt__track_eval(&n->tr, time, t);
      tt__track_eval(&n->rot, time, r);
      tt__track_eval(&n->sc, time, s);
      tt__trs(t, r, s, local);
    } else {
      memcpy(local, n->rest, sizeof local);
    }
    if (n->parent >= 0 && (uint32_t)n->parent < i)
      tt__mul(n->world, a->nodes[n->parent].world, local);
    else memcpy(n->world, local, sizeof local);
  }
}

void tt__scene_anim_pose_nodes(tt_scene *s, double time) {
  if (s->anim) tt__pose_nodes(s->anim, time);
}

/* Cofactor matrix of the upper 3x3 (the inverse transpose times det) and the determinant. */
static double tt__cofactor(const double *m, double c[9]) {
  c[0] = m[5] * m[10] - m[6] * m[9];
  c[1] = m[6] * m[8] - m[4] * m[10];
  c[2] = m[4] * m[9] - m[5] * m[8];
  c[3] = m[2] * m[9] - m[1] * m[10];
  c[4] = m[0] * m[10] - m[2] * m[8];
  c[5] = m[1] * m[8] - m[0] * m[9];
  c[6] = m[1] * m[6] - m[2] * m[5];
  c[7] = m[2] * m[4] - m[0] * m[6];
  c[8] = m[0] * m[5] - m[1] * m[4];
  return m[0] * c[0] + m[1] * c[1] + m[2] * c[2];
}

/* Writes p' = m * p (affine) and, when n is given, n' = normalise(cofactor(m) * n * sign). */
static void tt__xform(const double m[16], const double p[3], const double *n, float *po,
                      float *no) {
  for (int r = 0; r < 3; r++)
    po[r] = (float)(m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3]);
  if (!n || !no) return;
  double c[9], o[3];
  double det = tt__cofactor(m, c), sgn = det < 0 ? -1.0 : 1.0;
  for (int r = 0; r < 3; r++)
    o[r] = sgn * (c[3 * r] * n[0] + c[3 * r + 1] * n[1] + c[3 * r + 2] * n[2]);
  double len = sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
  if (len > 0 && isfinite(len))
    for (int r = 0; r < 3; r++) no[r] = (float)(o[r] / len);
  else no[0] = 0.0f, no[1] = 0.0f, no[2] = 1.0f;
}

/* ---- one mesh ---------------------------------------------------------------------------- */

/* The placement of a mesh without a skin: post * world(node). */
static void tt__mesh_matrix(const tt__scene_anim *a, const tt__mesh_anim *m, double out[16]) {
  if (m->node >= 0 && (uint32_t)m->node < a->node_count)
    memcpy(out, a->nodes[m->node].world, sizeof(double) * 16);
  else memcpy(out, tt__id16, sizeof tt__id16);
  if (m->has_post) tt__mul(out, m->post, out);
}

/* Poses one mesh at the time the nodes were posed at. */
static void tt__pose_mesh(tt_scene *s, tt__scene_anim *a, tt__mesh_anim *m, double time) {
  tt_mesh *v = &s->meshes[m->mesh];
  float *pos = (float *)v->positions, *nrm = (float *)v->normals;
  const uint32_t nv = v->vertex_count;
  if (m->targets) {
    memcpy(m->morph_w, m->weights0, sizeof(float) * m->targets);
    tt__track_eval(&m->weights, time, m->morph_w);
  }
  double M[16];
  tt__mesh_matrix(a, m, M);
  for (uint32_t j = 0; j < m->joints; j++) {
    const int32_t node = m->joint_node[j];
    const double *w = node >= 0 && (uint32_t)node < a->node_count ? a->nodes[node].world : tt__id16;
    tt__mul(m->joint_mat + 16 * (size_t)j, w, m->inverse_bind + 16 * (size_t)j);
    if (m->has_post) tt__mul(m->joint_mat + 16 * (size_t)j, m->post, m->joint_mat + 16 * (size_t)j);
  }
  for (uint32_t i = 0; i < nv; i++) {
    double p[3], n[3];
    for (int k = 0; k < 3; k++) {
      p[k] = m->rest_pos[3 * (size_t)i + k];
      n[k] = m->rest_nrm ? m->rest_nrm[3 * (size_t)i + k] : 0.0;
    }
    for (uint32_t t = 0; t < m->targets; t++) {
      const double w = m->morph_w[t];
      if (w == 0.0) continue;
      const size_t o = ((size_t)t * nv + i) * 3;
      for (int k = 0; k < 3; k++) {
        p[k] += w * m->dpos[o + k];
        if (m->dnrm && m->rest_nrm) n[k] += w * m->dnrm[o + k];
      }
    }
    const double *X = M;
    double blend[16];
    if (m->joints) {
      memset(blend, 0, sizeof blend);
      for (uint32_t k = 0; k < m->influences; k++) {
        const size_t at = (size_t)i * m->influences + k;
        const float w = m->joint_weight[at];
        if (w == 0.0f) continue;
        const double *J = m->joint_mat + 16 * (size_t)m->joint_index[at];
        for (int e = 0; e < 12; e++) blend[e] += w * J[e];
      }
      blend[15] = 1.0;
      X = blend;
    }
    tt__xform(X, p, m->rest_nrm ? n : NULL, pos + 3 * (size_t)i, nrm ? nrm + 3 * (size_t)i : NULL);
  }
  if (v->motion == TT_MESH_RIGID)
    for (int e = 0; e < 12; e++) v->transform[e] = (float)M[e];
  v->revision++;
}

/* The first vertex of a mesh that is not finite or lies beyond the coordinate limit. */
static long tt__bad_vertex(const tt_mesh *v) {
  for (size_t i = 0; i < 3 * (size_t)v->vertex_count; i++)
    if (!(fabsf(v->positions[i]) <= (float)TT_SCENE_COORD_LIMIT)) return (long)(i / 3);
  return -1;
}

tt_status tt__scene_anim_pose(tt_scene *s, double time) {
  tt__scene_anim *a = s->anim;
  if (!a) return TT_OK;
  tt__pose_nodes(a, time);
  for (uint32_t i = 0; i < a->mesh_count; i++) {
    tt__mesh_anim *m = &a->meshes[i];
    tt__pose_mesh(s, a, m, time);
    const tt_mesh *v = &s->meshes[m->mesh];
    long bad = tt__bad_vertex(v);
    if (bad >= 0) {
      const float *p = v->positions + 3 * (size_t)bad;
      return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                          "%s: mesh %u \"%s\" at time %g: vertex %ld at (%g, %g, %g) is not finite "
                          "or beyond the coordinate limit of +-1e18 (check its animation)",
                          s->source, m->mesh, v->name ? v->name : "", time, bad, p[0], p[1], p[2]);
    }
    if (v->light >= 0 && (uint32_t)v->light < s->light_count)
      s->lights[v->light].area = (float)tt__mesh_area(v);
  }
  a->time = time;
  return TT_OK;
}

/* ---- public API -------------------------------------------------------------------------- */

int tt_scene_animated(const tt_scene *s) { return s && s->anim && s->anim->mesh_count > 0; }

void tt_scene_time_range(const tt_scene *s, double *t0, double *t1) {
  double lo = 0, hi = 0;
  if (s) tt__scene_time_range(s, &lo, &hi);
  if (t0) *t0 = lo;
  if (t1) *t1 = hi;
}

double tt_scene_time(const tt_scene *s) {
  return s && s->anim ? s->anim->time : s ? s->start_time : 0.0;
}

tt_status tt_scene_set_time(tt_scene *s, double t, double t_prev) {
  if (!s) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_scene_set_time: scene is NULL");
  if (!isfinite(t) || !isfinite(t_prev))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "tt_scene_set_time: times must be finite (got %g, %g)", t, t_prev);
  tt__scene_anim *a = s->anim;
  if (!a || a->mesh_count == 0) return TT_OK;
  const double good = a->time;
  tt_status st = TT_OK;
  if (t_prev != a->time) st = tt__scene_anim_pose(s, t_prev);
  for (uint32_t i = 0; i < a->mesh_count && st == TT_OK; i++) {
    const tt_mesh *v = &s->meshes[a->meshes[i].mesh];
    memcpy(a->meshes[i].prev, v->positions, sizeof(float) * 3 * (size_t)v->vertex_count);
  }
  if (st == TT_OK && t != a->time) st = tt__scene_anim_pose(s, t);
  if (st != TT_OK) {
    /* back to the last pose that worked, with no motion: never a half-posed scene */
    char msg[1024];
    snprintf(msg, sizeof msg, "%s", tt_last_error());
    if (tt__scene_anim_pose(s, good) == TT_OK)
      for (uint32_t i = 0; i < a->mesh_count; i++) {
        const tt_mesh *v = &s->meshes[a->meshes[i].mesh];
        memcpy(a->meshes[i].prev, v->positions, sizeof(float) * 3 * (size_t)v->vertex_count);
      }
    tt_set_error(st, "%s", msg);
  }
  tt__scene_update_bounds(s);
  return st;
}

/* ---- content hash -------------------------------------------------------------------------- */

static uint64_t tt__hash_track(uint64_t h, const tt__track *t) {
  uint32_t hdr[3] = {t->count, t->dim, (uint32_t)t->interp};
  h = tt__fnv1a64(h, hdr, sizeof hdr);
  if (!t->count) return h;
  h = tt__fnv1a64(h, t->times, sizeof(double) * t->count);
  h = tt__fnv1a64(h, t->values, sizeof(float) * t->count * t->dim);
  if (t->in_tan) h = tt__fnv1a64(h, t->in_tan, sizeof(float) * t->count * t->dim);
  if (t->out_tan) h = tt__fnv1a64(h, t->out_tan, sizeof(float) * t->count * t->dim);
  return h;
}

/* Two scenes with the same start pose but different motion get different ids. */
uint64_t tt__scene_anim_hash(const tt_scene *s, uint64_t h) {
  const tt__scene_anim *a = s->anim;
  if (!a || a->mesh_count == 0) return h;
  h = tt__fnv1a64(h, "anim", 4);
  for (uint32_t i = 0; i < a->node_count; i++) {
    const tt__anim_node *n = &a->nodes[i];
    h = tt__fnv1a64(h, &n->parent, sizeof n->parent);
    h = tt__fnv1a64(h, n->rest, sizeof n->rest);
    h = tt__hash_track(tt__hash_track(tt__hash_track(h, &n->tr), &n->rot), &n->sc);
  }
  for (uint32_t i = 0; i < a->mesh_count; i++) {
    const tt__mesh_anim *m = &a->meshes[i];
    const size_t nv = s->meshes[m->mesh].vertex_count;
    uint32_t hdr[5] = {m->mesh, (uint32_t)m->node, m->targets, m->joints, m->influences};
    h = tt__fnv1a64(h, hdr, sizeof hdr);
    h = tt__fnv1a64(h, m->rest_pos, sizeof(float) * 3 * nv);
    if (m->targets) h = tt__fnv1a64(h, m->dpos, sizeof(float) * 3 * nv * m->targets);
    h = tt__hash_track(h, &m->weights);
    if (m->joints) {
      h = tt__fnv1a64(h, m->joint_node, sizeof(int32_t) * m->joints);
      h = tt__fnv1a64(h, m->inverse_bind, sizeof(double) * 16 * m->joints);
      h = tt__fnv1a64(h, m->joint_index, sizeof(uint32_t) * nv * m->influences);
      h = tt__fnv1a64(h, m->joint_weight, sizeof(float) * nv * m->influences);
    }
  }
  return h;
}
