/* Checks shared by the accel_embree custom-backend tests: a ray set with brute-force
 * references, per-hit comparison, and "build this configuration and check every query".
 * Header-only (static functions), like accel_embree_common.h. */
#ifndef TT_ACCEL_EMBREE_CHECK_H
#define TT_ACCEL_EMBREE_CHECK_H

#include "accel_embree_common.h"

#ifndef NRAYS
#  define NRAYS 6000
#endif
#ifndef CAM
#  define CAM 48
#endif

#define T_REL 1e-4
#define UV_ABS 2e-4
#define T_ABS 2e-6

/* A checked scene: rays and their reference answers. */
typedef struct rayset {
  const tt_scene *scene;
  size_t n;
  tt_ray *rays;
  ae_ref *ref;
  double uv_abs; /* barycentric tolerance (0: UV_ABS); ill-conditioned sliver triangles
                   * need more: float u, v err by ~ulp * length / width */
} rayset;

/* Rays (random + camera grid) and references for `scene`. */
static inline rayset make_rayset(const tt_scene *scene, uint64_t seed) {
  rayset rs = {scene, NRAYS + CAM * CAM, NULL, NULL, UV_ABS};
  rs.rays = malloc(rs.n * sizeof *rs.rays);
  rs.ref = malloc(rs.n * sizeof *rs.ref);
  ae_random_rays(seed, rs.rays, NRAYS);
  ae_camera_rays(rs.rays + NRAYS, CAM, CAM);
  size_t hits = 0, amb = 0;
  for (size_t i = 0; i < rs.n; i++) {
    rs.ref[i] = ae_brute(scene, &rs.rays[i]);
    hits += rs.ref[i].geom != TT_INVALID_ID;
    amb += rs.ref[i].ambiguous;
  }
  printf("rayset: %zu rays, %zu hits, %zu ambiguous\n", rs.n, hits, amb);
  CHECK(hits > rs.n / 10 && amb < rs.n / 50);
  return rs;
}

/* Compares one hit with the reference; returns 1 if it is wrong (and reports it). */
static inline int check_hit(const rayset *rs, size_t i, const tt_ray *after, const tt_hit *h,
                            const char *what, const char *cfg) {
  const ae_ref *ref = &rs->ref[i];
  const tt_ray *ray = &rs->rays[i];
  const double uv_abs = rs->uv_abs > 0 ? rs->uv_abs : UV_ABS;
  int bad = 0;
  if (ref->ambiguous) {
    if (h->geom_id == TT_INVALID_ID) return 0;
    if (h->geom_id >= tt_scene_mesh_count(rs->scene) ||
        h->prim_id >= tt_scene_mesh(rs->scene, h->geom_id)->triangle_count) {
      CHECK_MSG(0, "%s ray %zu [%s]: ids %u/%u out of range", what, i, cfg, h->geom_id, h->prim_id);
      return 1;
    }
    const float *p0, *p1, *p2;
    double t, u, v;
    ae_tri(tt_scene_mesh(rs->scene, h->geom_id), h->prim_id, &p0, &p1, &p2);
    int ok =
        ae_mt(ray, p0, p1, p2, 10 * AE_EPS, &t, &u, &v) && fabs(t - h->t) <= 1e-3 * fabs(t) + 1e-6;
    CHECK_MSG(ok, "%s ray %zu [%s]: reported %u/%u not hit at t=%g", what, i, cfg, h->geom_id,
              h->prim_id, (double)h->t);
    return !ok;
  }
  if (ref->geom == TT_INVALID_ID) {
    bad = h->geom_id != TT_INVALID_ID || after->tfar != ray->tfar;
    CHECK_MSG(!bad, "%s ray %zu [%s]: reference misses, got %u/%u t=%g", what, i, cfg, h->geom_id,
              h->prim_id, (double)h->t);
    return bad;
  }
  bad = h->geom_id != ref->geom || h->prim_id != ref->prim;
  CHECK_MSG(!bad, "%s ray %zu [%s]: hit %u/%u, reference %u/%u (t %g vs %g)", what, i, cfg,
            h->geom_id, h->prim_id, ref->geom, ref->prim, (double)h->t, ref->t);
  if (bad) return 1;
  bad = fabs(h->t - ref->t) > T_REL * ref->t + T_ABS || fabs(h->u - ref->u) > uv_abs ||
        fabs(h->v - ref->v) > uv_abs || after->tfar != h->t;
  CHECK_MSG(!bad, "%s ray %zu [%s]: t %.9g/%.9g uv (%g,%g)/(%g,%g) tfar %g", what, i, cfg,
            (double)h->t, ref->t, (double)h->u, (double)h->v, ref->u, ref->v, (double)after->tfar);
  const float *p0, *p1, *p2;
  ae_tri(tt_scene_mesh(rs->scene, ref->geom), ref->prim, &p0, &p1, &p2);
  double e1[3], e2[3], n[3], err = 0, len;
  for (int k = 0; k < 3; k++) e1[k] = (double)p1[k] - p0[k], e2[k] = (double)p2[k] - p0[k];
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int k = 0; k < 3; k++) err += (h->ng[k] - n[k]) * (h->ng[k] - n[k]);
  CHECK_MSG(sqrt(err) <= 1e-3 * len, "%s ray %zu [%s]: ng", what, i, cfg);
  return bad || sqrt(err) > 1e-3 * len;
}

/* Camera rays alone form a stream from one origin, which backend custom traces in packets
 * (its AVX2 / AVX-512 kernels). Against intersect1 / occluded1 on the same rays: the same
 * occlusion answers; the same hits, bit for bit (ties at equal distance go to the smaller
 * ids in both kernels, whatever the order of visit); and every hit is right by the
 * reference. Some rays get other [tnear, tfar]
 * intervals, some a non-finite direction or origin, and the stream is cut at odd lengths
 * (packets with empty lanes, and fewer rays than a packet) to exercise the lane masks. */
static inline long check_one_origin_streams(const tt_accel_iface *A, const tt_accel *acc,
                                            const rayset *rs, size_t n, const char *name) {
  if (n <= NRAYS) return 0;
  const size_t m = n - NRAYS;
  const tt_ray *cam = rs->rays + NRAYS;
  tt_ray *r = malloc(m * sizeof *r), *w1 = malloc(m * sizeof *w1), *w2 = malloc(m * sizeof *w2);
  tt_hit *h1 = malloc(m * sizeof *h1), *h2 = malloc(m * sizeof *h2);
  uint8_t *o2 = malloc(m);
  long wrong = 0;
  for (int variant = 0; variant < 2; variant++) {
    memcpy(r, cam, m * sizeof *r);
    if (variant == 1)
      for (size_t i = 0; i < m; i++) {
        if (i % 5 == 1) r[i].tnear = 3.0f + 0.001f * (float)(i % 17);
        if (i % 7 == 2) r[i].tfar = 3.5f + 0.01f * (float)(i % 13);
        if (i % 11 == 3) r[i].tfar = r[i].tnear - 1.0f; /* empty interval */
        if (i % 97 == 4) r[i].dir[1] = NAN;
        if (i % 89 == 5) r[i].dir[0] = INFINITY;
      }
    memcpy(w1, r, m * sizeof *r);
    memcpy(w2, r, m * sizeof *r);
    for (size_t i = 0; i < m; i++) A->intersect1(acc, &w1[i], &h1[i]);
    /* odd pieces: a long run, a 1-ray and a 2-ray call, the rest */
    size_t cuts[] = {0, m / 2 + 3, m / 2 + 4, m / 2 + 6, m};
    for (int c = 0; c < 4; c++) {
      A->intersect_stream(acc, w2 + cuts[c], h2 + cuts[c], cuts[c + 1] - cuts[c]);
      A->occluded_stream(acc, r + cuts[c], o2 + cuts[c], cuts[c + 1] - cuts[c]);
    }
    size_t ties = 0;
    for (size_t i = 0; i < m; i++) {
      const int miss1 = h1[i].geom_id == TT_INVALID_ID, miss2 = h2[i].geom_id == TT_INVALID_ID;
      int bad = miss1 != miss2 || (!miss1 && fabsf(h1[i].t - h2[i].t) > 4e-7f * fabsf(h1[i].t)) ||
                (!miss2 && w2[i].tfar != h2[i].t) || (miss2 && w2[i].tfar != r[i].tfar);
      int same_tri = h1[i].geom_id == h2[i].geom_id && h1[i].prim_id == h2[i].prim_id;
      if (!bad && !miss1 && !same_tri) ties++;
      if (!bad && !miss1 && same_tri)
        bad = h1[i].t != h2[i].t || h1[i].u != h2[i].u || h1[i].v != h2[i].v ||
              memcmp(h1[i].ng, h2[i].ng, sizeof h1[i].ng) != 0;
      CHECK_MSG(!bad,
                "one-origin stream ray %zu (variant %d) [%s]: %u/%u t=%.9g vs intersect1 "
                "%u/%u t=%.9g",
                i, variant, name, h2[i].geom_id, h2[i].prim_id, (double)h2[i].t, h1[i].geom_id,
                h1[i].prim_id, (double)h1[i].t);
      wrong += bad;
      if (variant == 0)
        wrong += check_hit(rs, NRAYS + i, &w2[i], &h2[i], "one-origin stream", name);
      int o1 = A->occluded1(acc, &r[i]);
      CHECK_MSG(o1 == o2[i], "one-origin occluded_stream ray %zu (variant %d) [%s]: %d vs %d", i,
                variant, name, o2[i], o1);
      wrong += o1 != o2[i];
    }
    /* exact ties go to the smaller ids in both kernels: the same triangle */
    CHECK_MSG(ties == 0, "[%s]: %zu of %zu one-origin rays hit another triangle at a tie", name,
              ties, m);
  }
  free(r), free(w1), free(w2), free(h1), free(h2), free(o2);
  return wrong;
}

/* Status of the last build check_config ran. */
static tt_status ae_last_build_status;

/* Builds `cfg` and checks every query on `rs`; returns the number of wrong answers, or -1
 * if the build failed. `max_check` limits the rays (0: all). */
static inline long check_config(const tt_accel_iface *A, const tt_config *cfg, const rayset *rs,
                                const char *name, size_t max_check, tt_accel_build_stats *st_out) {
  tt_accel *acc = NULL;
  tt_accel_build_stats st;
  memset(&st, 0, sizeof st);
  st.struct_size = sizeof st;
  tt_status s = A->build(rs->scene, cfg, &acc, &st);
  ae_last_build_status = s;
  if (st_out) *st_out = st;
  if (s != TT_OK) return -1;
  size_t n = max_check && max_check < rs->n ? max_check : rs->n;
  tt_ray *w1 = malloc(n * sizeof *w1), *w2 = malloc(n * sizeof *w2);
  tt_hit *h1 = malloc(n * sizeof *h1), *h2 = malloc(n * sizeof *h2);
  uint8_t *occ = malloc(n);
  memcpy(w1, rs->rays, n * sizeof *w1);
  memcpy(w2, rs->rays, n * sizeof *w2);
  for (size_t i = 0; i < n; i++) A->intersect1(acc, &w1[i], &h1[i]);
  A->intersect_stream(acc, w2, h2, n);
  A->occluded_stream(acc, rs->rays, occ, n);
  long wrong = 0;
  for (size_t i = 0; i < n; i++) {
    wrong += check_hit(rs, i, &w1[i], &h1[i], "intersect1", name);
    /* the stream runs the same kernel: bit-identical answers */
    int same = h1[i].geom_id == h2[i].geom_id && h1[i].prim_id == h2[i].prim_id &&
               (h1[i].geom_id == TT_INVALID_ID || (h1[i].t == h2[i].t && h1[i].u == h2[i].u));
    CHECK_MSG(same, "stream ray %zu [%s] differs from intersect1", i, name);
    wrong += !same;
    if (!rs->ref[i].ambiguous) {
      int expect = rs->ref[i].geom != TT_INVALID_ID;
      int o1 = A->occluded1(acc, &rs->rays[i]);
      CHECK_MSG(o1 == expect && occ[i] == expect, "occluded ray %zu [%s]: %d/%d, expected %d", i,
                name, o1, occ[i], expect);
      wrong += o1 != expect || occ[i] != expect;
    }
  }
  wrong += check_one_origin_streams(A, acc, rs, n, name);
  free(w1), free(w2), free(h1), free(h2), free(occ);
  A->destroy(acc);
  return wrong;
}

/* Sets "name=value" pairs (comma-separated) on a configuration. */
static inline void set_all(tt_config *c, const char *settings) {
  char buf[512];
  snprintf(buf, sizeof buf, "%s", settings);
  for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
    char *eq = strchr(tok, '=');
    if (!eq) continue;
    *eq = '\0';
    tt_status s = tt_config_set_string(c, tok, eq + 1);
    CHECK_MSG(s == TT_OK, "set %s=%s: %s", tok, eq + 1, tt_last_error());
  }
}

#endif /* TT_ACCEL_EMBREE_CHECK_H */
