/* accel_embree updateMethod=instances: the two-level structure (each rigid mesh an Embree
 * instance of its own BVH, only the top level rebuilt per update) answers as a flat tree built
 * from scratch over the same world positions. An animated scene of random triangles -- 48
 * rigid meshes that turn, move and scale, a mesh deforming through a morph target, a still
 * mesh -- is moved through four times; after each, the accel built at time 0 and updated
 * with updateMethod=instances is compared with a fresh flat build (updateMethod=rebuild) on
 * 2^18 random rays (2^20 in all per configuration):
 *   - a hit on a still or deforming mesh (identity instances: Embree intersects the world
 *     triangle) has the flat build's t, u, v and normal bit for bit;
 *   - a hit on a rigid mesh is the same triangle, equal up to the rounding of intersecting
 *     in object space: its hit point within 1e-6 (t + the scene's diagonal) of the flat
 *     hit's plane, its barycentric point no farther from the flat one than their t differ
 *     plus 1e-5 (t + the diagonal), its unnormalised normal within 1e-3 relative (the measured maxima are
 *     printed: a grazing ray moves t and u, v far more than the plane moves);
 *   - another triangle, or a hit against a miss, only where the two candidates lie within
 *     that rounding of each other or where one of them was hit within 1e-3 (barycentric) of
 *     its edge (the other test missed it by a rounding): at most 1 ray in 10^4;
 *   - the accel left at time 0 disagrees on many rays (the update did something).
 * The stream query answers as the single-ray one (the normal fix applies to both), the
 * update statistics say "not rebuilt", refitInterval rebuilds on schedule, and a scene
 * without rigid meshes answers bit for bit as the flat build. */
#include "accel_embree_common.h"

#include <math.h>

#define RAYS (1u << 18) /* per time; four times: 2^20 rays per configuration */
#define RIGID 48

/* The animated scene: `rigid` rigid meshes (each its own path), a morphing and a still one. */
static tt_scene *anim_scene(int rigid) {
  ae_rng rng = {0x1257a9ce5eedull};
  ae_buf b = {0};
  ae_scene_begin(&b);
  const double c1[3] = {0.5, 0.2, 0}, c2[3] = {0, -0.5, 0.3};
  ae_mesh_json(&b, &rng, 1, "cloth", 3000, c1, 0.5, NULL, 1);
  ae_mesh_json(&b, &rng, 0, "still", 3000, c2, 0.7, NULL, 0);
  for (int i = 0; i < rigid; i++) {
    double c[3], ax[3], tr[3];
    for (int k = 0; k < 3; k++) {
      c[k] = ae_uniform(&rng, -0.9, 0.9);
      ax[k] = ae_uniform(&rng, -1, 1);
      tr[k] = ae_uniform(&rng, -0.4, 0.4);
    }
    char name[32], anim[512];
    snprintf(name, sizeof name, "rigid%d", i);
    snprintf(anim, sizeof anim,
             "\"animation\":{\"keys\":[{\"time\":0,\"rotate\":[0,0,0],\"translate\":[0,0,0],"
             "\"scale\":1},{\"time\":1,\"rotate\":{\"axis\":[%.4f,%.4f,%.4f],\"angle\":%.1f},"
             "\"translate\":[%.4f,%.4f,%.4f],\"scale\":%.3f},{\"time\":2,\"rotate\":{\"axis\":"
             "[%.4f,%.4f,%.4f],\"angle\":%.1f},\"translate\":[%.4f,%.4f,%.4f],\"scale\":[%.3f,"
             "%.3f,%.3f]}]}",
             ax[0], ax[1] + 1.5, ax[2], ae_uniform(&rng, 30, 150), tr[0], tr[1], tr[2],
             ae_uniform(&rng, 0.6, 1.4), ax[0], ax[1] + 1.5, ax[2], ae_uniform(&rng, 160, 300),
             -tr[1], tr[2], tr[0], ae_uniform(&rng, 0.6, 1.4), ae_uniform(&rng, 0.6, 1.4),
             ae_uniform(&rng, 0.6, 1.4));
    ae_mesh_json(&b, &rng, 0, name, 200 + (uint32_t)(ae_next(&rng) % 400), c, 0.15, anim, 0);
  }
  return ae_scene_end(&b, "accel_embree instances scene");
}

/* |a - b| / |b| of two normals (vectors). */
static double rel3(const float a[3], const float b[3]) {
  double d = 0, n = 0;
  for (int k = 0; k < 3; k++) {
    d += ((double)a[k] - b[k]) * ((double)a[k] - b[k]);
    n += (double)b[k] * b[k];
  }
  return sqrt(d / fmax(n, 1e-60));
}

static int bits_equal(const tt_hit *a, const tt_hit *b) {
  return !memcmp(&a->t, &b->t, sizeof a->t) && !memcmp(&a->u, &b->u, sizeof a->u) &&
         !memcmp(&a->v, &b->v, sizeof a->v) && !memcmp(a->ng, b->ng, sizeof a->ng) &&
         a->geom_id == b->geom_id && a->prim_id == b->prim_id;
}

/* Instances against fresh flat builds along the animation for one configuration (key,
 * value pairs without updateMethod). `rigid`: rigid meshes in the scene (0: every hit must
 * be bit for bit the flat build's). */
static void check_instances(const tt_accel_iface *ai, const char *label, const char *const *kv,
                            int rigid) {
  tt_scene *scene = anim_scene(rigid);
  CHECK(tt_scene_animated(scene));
  const char *ikv[16], *fkv[16];
  size_t n = 0;
  for (; kv[n]; n++) ikv[n] = fkv[n] = kv[n];
  ikv[n] = fkv[n] = "updateMethod";
  ikv[n + 1] = "instances";
  fkv[n + 1] = "rebuild";
  ikv[n + 2] = fkv[n + 2] = NULL;
  tt_config *icfg = ae_config_of(ai, ikv), *fcfg = ae_config_of(ai, fkv);
  tt_accel *acc = NULL, *stale = NULL;
  CHECK_MSG(ai->build(scene, icfg, &acc, NULL) == TT_OK, "%s: %s", label, tt_last_error());
  CHECK_MSG(ai->build(scene, icfg, &stale, NULL) == TT_OK, "%s: %s", label, tt_last_error());
  tt_ray *rays = malloc(sizeof *rays * RAYS);
  tt_hit *a = malloc(sizeof *a * RAYS), *f = malloc(sizeof *f * RAYS),
         *s = malloc(sizeof *s * RAYS), *st = malloc(sizeof *st * RAYS);
  const double times[] = {0.3, 0.9, 1.6, 2.0};
  size_t total = 0, hits = 0, rigid_hits = 0, exact_bad = 0, close_bad = 0, other = 0,
         stale_diff = 0, stream_diff = 0;
  double max_t = 0, max_uv = 0, max_ng = 0;
  const uint32_t fixed = 2; /* meshes 0 and 1: the deforming and the still one */
  for (int k = 0; k < 4 && acc && stale; k++) {
    CHECK(tt_scene_set_time(scene, times[k], times[k] - 1.0 / 24) == TT_OK);
    tt_accel_update_stats us = {.struct_size = sizeof us};
    CHECK_MSG(ai->update(acc, &us) == TT_OK, "%s: update: %s", label, tt_last_error());
    CHECK_MSG(us.rebuilt == 0 && us.since_rebuild == (uint32_t)k + 1,
              "%s: update %d: rebuilt %d, %u since the build", label, k + 1, us.rebuilt,
              us.since_rebuild);
    float lo[3], hi[3];
    tt_scene_bounds(scene, lo, hi);
    const double extent =
        sqrt(((double)hi[0] - lo[0]) * (hi[0] - lo[0]) + ((double)hi[1] - lo[1]) * (hi[1] - lo[1]) +
             ((double)hi[2] - lo[2]) * (hi[2] - lo[2]));
    tt_accel *fresh = NULL;
    CHECK_MSG(ai->build(scene, fcfg, &fresh, NULL) == TT_OK, "%s: %s", label, tt_last_error());
    if (!fresh) break;
    ae_rays_in(scene, 7000u + (uint64_t)k, rays, RAYS);
    ae_trace(ai, acc, rays, a, RAYS);
    ae_trace(ai, fresh, rays, f, RAYS);
    ae_trace(ai, stale, rays, s, RAYS);
    tt_ray *sr = malloc(sizeof *sr * RAYS);
    memcpy(sr, rays, sizeof *sr * RAYS);
    ai->intersect_stream(acc, sr, st, RAYS);
    for (size_t i = 0; i < RAYS; i++) {
      total++;
      stream_diff += !bits_equal(&st[i], &a[i]);
      stale_diff += memcmp(&s[i].t, &f[i].t, sizeof(float)) != 0;
      const int ah = a[i].geom_id != TT_INVALID_ID, fh = f[i].geom_id != TT_INVALID_ID;
      hits += fh;
      if (!ah && !fh) continue;
      if (ah && fh && a[i].geom_id == f[i].geom_id && a[i].prim_id == f[i].prim_id) {
        if (f[i].geom_id < fixed) {
          if (!bits_equal(&a[i], &f[i]) && exact_bad++ < 5)
            fprintf(stderr, "%s t=%g ray %zu mesh %u: t %.9g / %.9g, ng %g %g %g / %g %g %g\n",
                    label, times[k], i, f[i].geom_id, (double)a[i].t, (double)f[i].t,
                    (double)a[i].ng[0], (double)a[i].ng[1], (double)a[i].ng[2], (double)f[i].ng[0],
                    (double)f[i].ng[1], (double)f[i].ng[2]);
          continue;
        }
        rigid_hits++;
        /* Well-conditioned measures of the difference (a grazing ray moves t and the
         * barycentrics a lot for a tiny move of the plane): the distance of the instanced
         * hit point from the flat hit's plane, and the distance between the two hits'
         * barycentric points on the world triangle beyond their distance along the ray. */
        const tt_mesh *m = tt_scene_mesh(scene, f[i].geom_id);
        const uint32_t *ix = m->indices + 3 * (size_t)f[i].prim_id;
        const float *p0 = m->positions + 3 * ix[0], *p1 = m->positions + 3 * ix[1],
                    *p2 = m->positions + 3 * ix[2];
        double nl = sqrt((double)f[i].ng[0] * f[i].ng[0] + (double)f[i].ng[1] * f[i].ng[1] +
                         (double)f[i].ng[2] * f[i].ng[2]),
               cosd = 0, dpt = 0;
        const double dtv = (double)a[i].t - f[i].t;
        for (int c = 0; c < 3; c++) {
          cosd += f[i].ng[c] / nl * rays[i].dir[c];
          double pa = (1.0 - a[i].u - a[i].v) * p0[c] + a[i].u * p1[c] + a[i].v * p2[c];
          double pf = (1.0 - f[i].u - f[i].v) * p0[c] + f[i].u * p1[c] + f[i].v * p2[c];
          dpt += (pa - pf) * (pa - pf);
        }
        const double scale = f[i].t + extent;
        double plane = fabs(dtv * cosd) / scale, along = fmax(0.0, sqrt(dpt) - fabs(dtv)) / scale,
               dn = rel3(a[i].ng, f[i].ng);
        max_t = fmax(max_t, plane);
        max_uv = fmax(max_uv, along);
        max_ng = fmax(max_ng, dn);
        if ((plane > 1e-6 || along > 1e-5 || dn > 1e-3) && close_bad++ < 5)
          fprintf(stderr, "%s t=%g ray %zu mesh %u: t %.9g / %.9g, uv %g %g / %g %g, ng rel %g\n",
                  label, times[k], i, f[i].geom_id, (double)a[i].t, (double)f[i].t, (double)a[i].u,
                  (double)a[i].v, (double)f[i].u, (double)f[i].v, dn);
        continue;
      }
      /* another triangle or a hit against a miss: a near tie of the two candidates, or a
       * ray through the edge of the triangle one of them hit (the other missed it by a
       * rounding and found what lies behind) */
      other++;
      const int tie = ah && fh && fabs((double)a[i].t - f[i].t) / (f[i].t + extent) <= 1e-5;
      const int edge = (ah && fmin(fmin(a[i].u, a[i].v), 1.0f - a[i].u - a[i].v) <= 1e-3f) ||
                       (fh && fmin(fmin(f[i].u, f[i].v), 1.0f - f[i].u - f[i].v) <= 1e-3f);
      if (!tie && !edge && close_bad++ < 5)
        fprintf(
            stderr,
            "%s t=%g ray %zu: instances (%u,%u) t %.9g uv %g %g, flat (%u,%u) t %.9g uv %g %g\n",
            label, times[k], i, a[i].geom_id, a[i].prim_id, (double)a[i].t, (double)a[i].u,
            (double)a[i].v, f[i].geom_id, f[i].prim_id, (double)f[i].t, (double)f[i].u,
            (double)f[i].v);
    }
    free(sr);
    ai->destroy(fresh);
  }
  printf("%s: %zu rays, %zu hits (%zu on rigid meshes; largest differences, relative to t + "
         "the scene's diagonal: %.3g off the plane, %.3g between the barycentric points, "
         "normal %.3g relative), %zu on another triangle or missed, a tree left at t=0 differs on "
         "%zu\n",
         label, total, hits, rigid_hits, max_t, max_uv, max_ng, other, stale_diff);
  CHECK_MSG(total == 4 * RAYS && hits > total / 4, "%s: %zu hits of %zu rays", label, hits, total);
  CHECK_MSG(rigid ? rigid_hits > total / 20 : rigid_hits == 0, "%s: %zu hits on rigid meshes",
            label, rigid_hits);
  CHECK_MSG(exact_bad == 0, "%s: %zu hits on identity instances differ from the flat build", label,
            exact_bad);
  CHECK_MSG(close_bad == 0, "%s: %zu hits beyond the rounding of an object-space test", label,
            close_bad);
  CHECK_MSG(rigid ? other <= total / 10000 : other <= total / 100000,
            "%s: %zu rays hit another triangle", label, other);
  CHECK_MSG(stale_diff > total / 50, "%s: the scene hardly moved (%zu rays differ at t=0)", label,
            stale_diff);
  CHECK_MSG(stream_diff == 0, "%s: the stream query differs from intersect1 on %zu rays", label,
            stream_diff);
  free(rays);
  free(a);
  free(f);
  free(s);
  free(st);
  ai->destroy(acc);
  ai->destroy(stale);
  tt_config_destroy(icfg);
  tt_config_destroy(fcfg);
  tt_scene_destroy(scene);
}

/* refitInterval with instances: a build from scratch every 3rd update; occlusion agrees with
 * the closest-hit query. */
static void check_schedule(const tt_accel_iface *ai) {
  tt_scene *scene = anim_scene(8);
  static const char *const kv[] = {"updateMethod", "instances", "refitInterval", "3", NULL};
  tt_config *cfg = ae_config_of(ai, kv);
  tt_accel *acc = NULL;
  CHECK_MSG(ai->build(scene, cfg, &acc, NULL) == TT_OK, "%s", tt_last_error());
  const int expect[6] = {0, 0, 1, 0, 0, 1};
  tt_ray *rays = malloc(sizeof *rays * 4096);
  for (int k = 0; acc && k < 6; k++) {
    double t = 0.3 * (k + 1);
    CHECK(tt_scene_set_time(scene, t, t - 1.0 / 24) == TT_OK);
    tt_accel_update_stats us = {.struct_size = sizeof us};
    CHECK(ai->update(acc, &us) == TT_OK);
    CHECK_MSG(us.rebuilt == expect[k], "instances every 3: update %d: rebuilt %d, expected %d",
              k + 1, us.rebuilt, expect[k]);
    ae_rays_in(scene, 99u + (uint64_t)k, rays, 4096);
    size_t mismatch = 0, hit = 0;
    for (size_t i = 0; i < 4096; i++) {
      tt_ray r = rays[i];
      tt_hit h;
      ai->intersect1(acc, &r, &h);
      hit += h.geom_id != TT_INVALID_ID;
      mismatch += ai->occluded1(acc, &rays[i]) != (h.geom_id != TT_INVALID_ID);
    }
    CHECK_MSG(mismatch == 0 && hit > 1000, "update %d: occluded1 disagrees on %zu of %zu hits",
              k + 1, mismatch, hit);
  }
  /* backend custom falls back to native instances: the same answers bit for bit */
  static const char *const ckv[] = {"updateMethod", "instances", "backend", "custom", NULL};
  static const char *const nkv[] = {"updateMethod", "instances", NULL};
  tt_config *ccfg = ae_config_of(ai, ckv), *ncfg = ae_config_of(ai, nkv);
  tt_accel *ca = NULL, *na = NULL;
  CHECK_MSG(ai->build(scene, ccfg, &ca, NULL) == TT_OK &&
                ai->build(scene, ncfg, &na, NULL) == TT_OK,
            "%s", tt_last_error());
  CHECK(tt_scene_set_time(scene, 0.7, 0.6) == TT_OK);
  tt_accel_update_stats us = {.struct_size = sizeof us};
  CHECK(ca && na && ai->update(ca, &us) == TT_OK && us.rebuilt == 0 &&
        ai->update(na, NULL) == TT_OK);
  ae_rays_in(scene, 4242u, rays, 4096);
  size_t differ = 0;
  for (size_t i = 0; ca && na && i < 4096; i++) {
    tt_ray r1 = rays[i], r2 = rays[i];
    tt_hit h1, h2;
    ai->intersect1(ca, &r1, &h1);
    ai->intersect1(na, &r2, &h2);
    differ += !bits_equal(&h1, &h2);
  }
  CHECK_MSG(differ == 0, "custom with instances differs from native instances on %zu rays", differ);
  ai->destroy(ca);
  ai->destroy(na);
  tt_config_destroy(ccfg);
  tt_config_destroy(ncfg);
  free(rays);
  ai->destroy(acc);
  tt_config_destroy(cfg);
  tt_scene_destroy(scene);
}

int main(void) {
  ae_plugin p = ae_load(NULL);
  const tt_accel_iface *ai = p.accel;
  CHECK(TT_HAS_FIELD(tt_accel_iface, ai, update) && ai->update);
  static const char *const native[] = {NULL};
  static const char *const robust[] = {"robust", "true", NULL};
  static const char *const high_static[] = {"quality", "3", "static", "true", NULL};
  check_instances(ai, "native", native, RIGID);
  check_instances(ai, "native robust", robust, RIGID);
  check_instances(ai, "native quality 3 static", high_static, RIGID);
  check_instances(ai, "no rigid meshes", native, 0);
  check_schedule(ai);
  tt_registry_destroy(p.reg);
  return tt_test_finish("accel_embree_instances");
}
