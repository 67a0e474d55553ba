/* accel_embree correctness: for every quality x branchingFactor x compact x robust x static
 * configuration, closest hits, occlusion and both stream calls must agree with a
 * brute-force double-precision Moller-Trumbore reference over 20k random rays (with mixed
 * [tnear, tfar] intervals) on a scene of three random-triangle meshes. */
#include "accel_embree_common.h"

#define NRAYS 20000
#define CAM_W 64
#define CAM_H 64

/* Tolerances: t relative (float vs double), barycentrics absolute. */
#define T_REL 1e-4
#define UV_ABS 2e-4
/* Absolute floor for t: float round-off of origins (|org| <= 1.5) dominates near t = 0. */
#define T_ABS 2e-6

/* Counts of rays outside the reference's confident set, for the final sanity bound. */
static size_t g_ambiguous;

/* Checks one Embree hit against the reference; `what` names the call for messages. */
static void check_hit(const tt_scene *scene, const tt_ray *ray, const tt_ray *after,
                      const tt_hit *h, const ae_ref *ref, const char *what, size_t i,
                      const char *cfg) {
  if (ref->ambiguous) {
    /* Round-off may pick another answer, but a reported hit must still be a real
     * (edge-grown) intersection inside the interval. */
    if (h->geom_id == TT_INVALID_ID) return;
    CHECK_MSG(h->geom_id < tt_scene_mesh_count(scene), "%s ray %zu [%s]", what, i, cfg);
    if (h->geom_id >= tt_scene_mesh_count(scene)) return;
    const tt_mesh *m = tt_scene_mesh(scene, h->geom_id);
    CHECK_MSG(h->prim_id < m->triangle_count, "%s ray %zu [%s]", what, i, cfg);
    if (h->prim_id >= m->triangle_count) return;
    const float *p0, *p1, *p2;
    double t, u, v;
    ae_tri(m, h->prim_id, &p0, &p1, &p2);
    int ok = ae_mt(ray, p0, p1, p2, 10 * AE_EPS, &t, &u, &v);
    CHECK_MSG(ok && fabs(t - h->t) <= 1e-3 * fabs(t) + 1e-6,
              "%s ray %zu [%s]: reported triangle %u/%u not hit at t=%g", what, i, cfg, h->geom_id,
              h->prim_id, (double)h->t);
    return;
  }
  if (ref->geom == TT_INVALID_ID) {
    CHECK_MSG(h->geom_id == TT_INVALID_ID && h->prim_id == TT_INVALID_ID,
              "%s ray %zu [%s]: reference misses, Embree hit %u/%u t=%g", what, i, cfg, h->geom_id,
              h->prim_id, (double)h->t);
    CHECK_MSG(after->tfar == ray->tfar || (isnan(after->tfar) && isnan(ray->tfar)),
              "%s ray %zu [%s]: tfar changed on a miss", what, i, cfg);
    return;
  }
  CHECK_MSG(h->geom_id == ref->geom && h->prim_id == ref->prim,
            "%s ray %zu [%s]: hit %u/%u, reference %u/%u (t %g vs %g)", what, i, cfg, h->geom_id,
            h->prim_id, ref->geom, ref->prim, (double)h->t, ref->t);
  if (h->geom_id != ref->geom || h->prim_id != ref->prim) return;
  CHECK_MSG(fabs(h->t - ref->t) <= T_REL * ref->t + T_ABS, "%s ray %zu [%s]: t %.9g vs %.9g", what,
            i, cfg, (double)h->t, ref->t);
  CHECK_MSG(fabs(h->u - ref->u) <= UV_ABS && fabs(h->v - ref->v) <= UV_ABS,
            "%s ray %zu [%s]: uv (%g,%g) vs (%g,%g)", what, i, cfg, (double)h->u, (double)h->v,
            ref->u, ref->v);
  CHECK_MSG(after->tfar == h->t, "%s ray %zu [%s]: tfar %g not shortened to t %g", what, i, cfg,
            (double)after->tfar, (double)h->t);
  /* ng must be cross(v1-v0, v2-v0): same direction and length. */
  const float *p0, *p1, *p2;
  ae_tri(tt_scene_mesh(scene, ref->geom), ref->prim, &p0, &p1, &p2);
  double e1[3], e2[3], n[3];
  for (int k = 0; k < 3; k++) e1[k] = (double)p1[k] - p0[k], e2[k] = (double)p2[k] - p0[k];
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  double err = 0;
  for (int k = 0; k < 3; k++) err += (h->ng[k] - n[k]) * (h->ng[k] - n[k]);
  CHECK_MSG(sqrt(err) <= 1e-3 * len, "%s ray %zu [%s]: ng (%g,%g,%g) vs (%g,%g,%g)", what, i, cfg,
            (double)h->ng[0], (double)h->ng[1], (double)h->ng[2], n[0], n[1], n[2]);
}

/* Context of the threaded query check. */
typedef struct par_ctx {
  const tt_accel_iface *A;
  const tt_accel *acc;
  const tt_ray *rays;
  tt_ray *work;
  tt_hit *hits;
} par_ctx;

/* parallel_for body: odd chunks use intersect1, even chunks the stream call, so both run
 * concurrently on one accel. */
static void par_body(void *user, uint64_t begin, uint64_t end, uint32_t thread) {
  (void)thread;
  par_ctx *c = user;
  memcpy(c->work + begin, c->rays + begin, (size_t)(end - begin) * sizeof *c->rays);
  if ((begin / 100) % 2)
    for (uint64_t i = begin; i < end; i++) c->A->intersect1(c->acc, &c->work[i], &c->hits[i]);
  else c->A->intersect_stream(c->acc, c->work + begin, c->hits + begin, (size_t)(end - begin));
}

int main(void) {
  ae_plugin pl = ae_load(NULL);
  const tt_accel_iface *A = pl.accel;
  CHECK(A->struct_size >= sizeof(tt_accel_iface));
  const tt_space *space = A->space();

  static const uint32_t tris[3] = {1500, 1000, 600};
  tt_scene *scene = ae_random_scene(0x5eed1234abcdull, 3, tris);
  CHECK(tt_scene_triangle_count(scene) == 3100);

  /* Rays: NRAYS random + a coherent camera grid (exercises the coherent stream mode). */
  const size_t n = NRAYS + CAM_W * CAM_H;
  tt_ray *rays = malloc(n * sizeof *rays), *work = malloc(n * sizeof *rays);
  tt_hit *hits = malloc(n * sizeof *hits), *shits = malloc(n * sizeof *shits);
  ae_ref *ref = malloc(n * sizeof *ref);
  uint8_t *occ = malloc(n), *socc = malloc(n);
  ae_random_rays(42, rays, NRAYS);
  ae_camera_rays(rays + NRAYS, CAM_W, CAM_H);

  size_t ref_hits = 0;
  for (size_t i = 0; i < n; i++) {
    ref[i] = ae_brute(scene, &rays[i]);
    ref_hits += ref[i].geom != TT_INVALID_ID;
    g_ambiguous += ref[i].ambiguous;
  }
  printf("reference: %zu rays, %zu hits, %zu ambiguous\n", n, ref_hits, g_ambiguous);
  /* The scene must exercise both outcomes, and the tolerance band must stay narrow. */
  CHECK(ref_hits > n / 5 && ref_hits < n - n / 10);
  CHECK(g_ambiguous < n / 100);

  int combos = 0;
  tt_config *cfg = tt_config_create(space);
  for (int q = 1; q <= 3; q++)
    for (int bf = 2; bf <= 8; bf *= 2)
      for (int flags = 0; flags < 8; flags++) {
        int compact = flags & 1, robust = (flags >> 1) & 1, stat = (flags >> 2) & 1;
        char name[96];
        snprintf(name, sizeof name, "quality=%d bf=%d compact=%d robust=%d static=%d", q, bf,
                 compact, robust, stat);
        CHECK(tt_config_set_number(cfg, (size_t)tt_space_find(space, "quality"), q) == TT_OK);
        CHECK(tt_config_set_number(cfg, (size_t)tt_space_find(space, "branchingFactor"), bf) ==
              TT_OK);
        CHECK(tt_config_set_string(cfg, "compact", compact ? "true" : "false") == TT_OK);
        CHECK(tt_config_set_string(cfg, "robust", robust ? "true" : "false") == TT_OK);
        CHECK(tt_config_set_string(cfg, "static", stat ? "true" : "false") == TT_OK);
        /* this test covers backend native; accel_embree_custom covers custom */
        CHECK(tt_config_set_string(cfg, "backend", "native") == TT_OK);

        tt_accel *acc = NULL;
        tt_accel_build_stats st;
        memset(&st, 0, sizeof st);
        st.struct_size = sizeof st;
        tt_status s = A->build(scene, cfg, &acc, &st);
        CHECK_MSG(s == TT_OK && acc, "build [%s]: %s", name, tt_last_error());
        if (s != TT_OK || !acc) continue;
        combos++;
        CHECK(st.struct_size == sizeof st);
        CHECK(st.build_ms >= 0.0 && st.build_ms < 10000.0);
        /* The structure holds at least the copied vertices (36 bytes per triangle here). */
        CHECK_MSG(st.memory_bytes >= 3100ull * 36, "[%s] memory_bytes %llu", name,
                  (unsigned long long)st.memory_bytes);
        CHECK(st.repaired == 0);

        /* intersect1 + occluded1 */
        for (size_t i = 0; i < n; i++) {
          work[i] = rays[i];
          A->intersect1(acc, &work[i], &hits[i]);
          check_hit(scene, &rays[i], &work[i], &hits[i], &ref[i], "intersect1", i, name);
          occ[i] = (uint8_t)A->occluded1(acc, &rays[i]);
          if (!ref[i].ambiguous)
            CHECK_MSG(occ[i] == (ref[i].geom != TT_INVALID_ID), "occluded1 ray %zu [%s]", i, name);
        }
        /* streams: same answers as the single-ray calls (odd count: a partial chunk) */
        memcpy(work, rays, n * sizeof *rays);
        A->intersect_stream(acc, work, shits, n);
        A->occluded_stream(acc, rays, socc, n);
        size_t stream_diff = 0;
        for (size_t i = 0; i < n; i++) {
          check_hit(scene, &rays[i], &work[i], &shits[i], &ref[i], "intersect_stream", i, name);
          int same = shits[i].geom_id == hits[i].geom_id && shits[i].prim_id == hits[i].prim_id &&
                     (hits[i].geom_id == TT_INVALID_ID
                          ? isinf(shits[i].t) && work[i].tfar == rays[i].tfar
                          : fabsf(shits[i].t - hits[i].t) <= 1e-5f * fabsf(hits[i].t) + 1e-7f);
          if (!ref[i].ambiguous) CHECK_MSG(same, "stream vs single ray %zu [%s]", i, name);
          stream_diff += !same;
          if (!ref[i].ambiguous)
            CHECK_MSG(socc[i] == occ[i], "occluded_stream ray %zu [%s]", i, name);
        }
        CHECK(stream_diff <= g_ambiguous);
        A->intersect_stream(acc, work, shits, 0); /* empty stream: a no-op */

        /* counters are not available in the native backend */
        tt_accel_counters c = {.struct_size = sizeof c};
        CHECK(A->counters(acc, &c, 1) == TT_ERR_UNSUPPORTED);
        A->destroy(acc);
        if (tt_test_failures > 50) break; /* enough to diagnose */
      }
  CHECK(combos == 3 * 3 * 8);
  printf("configurations checked: %d\n", combos);

  /* Interval semantics on confident hits: tfar just short of the hit misses it; tnear
   * just past it finds the next surface (as the reference says), never the same one. */
  tt_accel *acc = NULL;
  CHECK(A->build(scene, NULL, &acc, NULL) == TT_OK);
  size_t tested = 0;
  for (size_t i = 0; i < NRAYS && acc && tested < 500; i++) {
    if (ref[i].ambiguous || ref[i].geom == TT_INVALID_ID) continue;
    tt_ray r = rays[i];
    r.tfar = (float)(ref[i].t * 0.999);
    if (r.tfar <= r.tnear) continue;
    ae_ref rr = ae_brute(scene, &r);
    if (rr.ambiguous) continue;
    tt_hit h;
    tt_ray w = r;
    A->intersect1(acc, &w, &h);
    CHECK(rr.geom == TT_INVALID_ID); /* ref[i] was the closest */
    CHECK_MSG(h.geom_id == TT_INVALID_ID, "short tfar ray %zu still hits", i);
    CHECK(!A->occluded1(acc, &r));
    r = rays[i];
    r.tnear = (float)(ref[i].t * 1.001);
    rr = ae_brute(scene, &r);
    if (rr.ambiguous) continue;
    w = r;
    A->intersect1(acc, &w, &h);
    check_hit(scene, &r, &w, &h, &rr, "tnear past first hit", i, "defaults");
    CHECK(!(h.geom_id == ref[i].geom && h.prim_id == ref[i].prim));
    tested++;
  }
  CHECK(tested >= 100);

  /* Queries are thread-safe: 4 threads mixing intersect1 and streams on one accel give the
   * serial answers (streams up to edge round-off). */
  if (acc) {
    for (size_t i = 0; i < n; i++) {
      work[i] = rays[i];
      A->intersect1(acc, &work[i], &hits[i]);
    }
    tt_ray *pwork = malloc(n * sizeof *pwork);
    tt_hit *phits = malloc(n * sizeof *phits);
    CHECK(tt_default_host_set_threads(4) == TT_OK);
    par_ctx pc = {A, acc, rays, pwork, phits};
    CHECK(tt_default_host()->parallel_for(n, 100, par_body, &pc) == TT_OK);
    size_t diff = 0;
    for (size_t i = 0; i < n; i++)
      diff += phits[i].geom_id != hits[i].geom_id || phits[i].prim_id != hits[i].prim_id ||
              (hits[i].geom_id != TT_INVALID_ID && phits[i].t != hits[i].t);
    CHECK_MSG(diff <= g_ambiguous, "%zu rays differ between threaded and serial queries", diff);
    free(pwork), free(phits);
  }
  A->destroy(acc);
  A->destroy(NULL); /* documented no-op */

  tt_config_destroy(cfg);
  free(rays), free(work), free(hits), free(shits), free(ref), free(occ), free(socc);
  tt_scene_destroy(scene);
  tt_registry_destroy(pl.reg);
  return tt_test_finish("accel_embree_correctness");
}
