/* accel_embree update(): a refitted tree answers as a tree built from scratch over the same
 * positions. An animated scene of random triangles (a mesh turning and moving rigidly, a
 * mesh deforming through a morph target, a still mesh) is moved through several times;
 * after each, the accel built at time 0 and updated with updateMethod=refit (native: Embree
 * RTC_BUILD_QUALITY_REFIT on a dynamic scene; custom BVH2/4/8: boxes refitted bottom-up)
 * must return on 2^20 random rays in all the same closest t (bit for bit) and the same
 * (mesh, triangle) as a fresh build of the same configuration, except where two triangles
 * lie at exactly that t (a tie either tree may break its own way; counted, and rare). The
 * accel left at time 0 is traced too: it must disagree on many rays, so a refit that did
 * nothing would fail. The update schedule (refitInterval, refitSahGrowth, rebuild) is
 * checked through update()'s statistics. */
#include "accel_embree_common.h"

#include <math.h>

#define RAYS (1u << 18) /* per time; four times: 2^20 rays per configuration */

/* The animated scene. */
static tt_scene *anim_scene(void) {
  ae_rng rng = {0x5eed0f2e1f17ull};
  ae_buf b = {0};
  ae_scene_begin(&b);
  const double c0[3] = {-0.4, 0, 0}, c1[3] = {0.5, 0.2, 0}, c2[3] = {0, -0.5, 0.3};
  ae_mesh_json(
      &b, &rng, 1, "spinner", 6000, c0, 0.5,
      "\"animation\":{\"keys\":[{\"time\":0,\"rotate\":[0,0,0],\"translate\":[0,0,0]},"
      "{\"time\":1,\"rotate\":{\"axis\":[0.3,1,0.2],\"angle\":120},\"translate\":[0.3,0.1,0]},"
      "{\"time\":2,\"rotate\":{\"axis\":[0.3,1,0.2],\"angle\":230},\"translate\":[0.6,-0.2,0.1]}]}",
      0);
  ae_mesh_json(&b, &rng, 0, "cloth", 5000, c1, 0.5, NULL, 1);
  ae_mesh_json(&b, &rng, 0, "still", 4000, c2, 0.7, NULL, 0);
  return ae_scene_end(&b, "accel_embree refit scene");
}

/* Refit against fresh builds along the animation for one configuration. */
static void check_refit(const tt_accel_iface *ai, const char *label, const char *const *kv) {
  tt_scene *scene = anim_scene();
  CHECK(tt_scene_animated(scene));
  tt_config *cfg = ae_config_of(ai, kv);
  tt_accel *acc = NULL, *stale = NULL;
  CHECK_MSG(ai->build(scene, cfg, &acc, NULL) == TT_OK, "%s: %s", label, tt_last_error());
  CHECK_MSG(ai->build(scene, cfg, &stale, NULL) == TT_OK, "%s: %s", label, tt_last_error());
  tt_ray *rays = malloc(sizeof *rays * RAYS);
  tt_hit *a = malloc(sizeof *a * RAYS), *f = malloc(sizeof *f * RAYS),
         *s = malloc(sizeof *s * RAYS);
  const double times[] = {0.3, 0.9, 1.6, 2.0};
  size_t total = 0, hits = 0, t_diff = 0, ties = 0, stale_diff = 0;
  for (int k = 0; k < 4 && acc; k++) {
    CHECK(tt_scene_set_time(scene, times[k], times[k] - 1.0 / 24) == TT_OK);
    tt_accel_update_stats us = {.struct_size = sizeof us};
    CHECK_MSG(ai->update(acc, &us) == TT_OK, "%s: update: %s", label, tt_last_error());
    CHECK_MSG(us.rebuilt == 0 && us.since_rebuild == (uint32_t)k + 1,
              "%s: update %d: rebuilt %d, "
              "%u since the build",
              label, k + 1, us.rebuilt, us.since_rebuild);
    tt_accel *fresh = NULL;
    CHECK_MSG(ai->build(scene, cfg, &fresh, NULL) == TT_OK, "%s: %s", label, tt_last_error());
    if (!fresh) break;
    ae_rays_in(scene, 1000u + (uint64_t)k, rays, RAYS);
    ae_trace(ai, acc, rays, a, RAYS);
    ae_trace(ai, fresh, rays, f, RAYS);
    ae_trace(ai, stale, rays, s, RAYS);
    for (size_t i = 0; i < RAYS; i++) {
      total++;
      hits += f[i].geom_id != TT_INVALID_ID;
      if (memcmp(&a[i].t, &f[i].t, sizeof(float)) != 0) {
        if (t_diff++ < 5)
          fprintf(stderr, "%s t=%g ray %zu: refit t %.9g (%u,%u), fresh t %.9g (%u,%u)\n", label,
                  times[k], i, (double)a[i].t, a[i].geom_id, a[i].prim_id, (double)f[i].t,
                  f[i].geom_id, f[i].prim_id);
      } else if (a[i].geom_id != f[i].geom_id || a[i].prim_id != f[i].prim_id) {
        ties++;
      }
      stale_diff += memcmp(&s[i].t, &f[i].t, sizeof(float)) != 0;
    }
    ai->destroy(fresh);
  }
  printf("%s: %zu rays, %zu hits, %zu t differ, %zu ties broken otherwise, a tree left at t=0 "
         "differs on %zu\n",
         label, total, hits, t_diff, ties, stale_diff);
  CHECK_MSG(total == 4 * RAYS && hits > total / 4, "%s: %zu hits of %zu rays", label, hits, total);
  CHECK_MSG(t_diff == 0, "%s: %zu of %zu rays hit at another t than a fresh build", label, t_diff,
            total);
  CHECK_MSG(ties <= total / 10000, "%s: %zu same-t hits on other triangles", label, ties);
  CHECK_MSG(stale_diff > total / 50, "%s: the scene hardly moved (%zu rays differ at t=0)", label,
            stale_diff);
  free(rays);
  free(a);
  free(f);
  free(s);
  ai->destroy(acc);
  ai->destroy(stale);
  tt_config_destroy(cfg);
  tt_scene_destroy(scene);
}

/* update()'s schedule: rebuild every time, refit with a rebuild every 3rd update, and a
 * growth limit so low that every refit asks for a rebuild (custom). */
static void check_schedule(const tt_accel_iface *ai) {
  static const struct {
    const char *label;
    const char *kv[9];
    int rebuilt[6];
  } cases[] = {
      {"rebuild", {"updateMethod", "rebuild", NULL}, {1, 1, 1, 1, 1, 1}},
      {"native refit every 3",
       {"updateMethod", "refit", "refitInterval", "3", NULL},
       {0, 0, 1, 0, 0, 1}},
      {"custom refit every 3",
       {"backend", "custom", "updateMethod", "refit", "refitInterval", "3", NULL},
       {0, 0, 1, 0, 0, 1}},
      {"custom growth",
       {"backend", "custom", "updateMethod", "refit", "refitSahGrowth", "0.01", NULL},
       {1, 1, 1, 1, 1, 1}},
      {"custom refit", {"backend", "custom", "updateMethod", "refit", NULL}, {0, 0, 0, 0, 0, 0}},
      /* native: the growth estimate of accel_embree_growth.c (before it, native ignored the
       * factor and never rebuilt) */
      {"native growth",
       {"updateMethod", "refit", "refitSahGrowth", "0.01", NULL},
       {1, 1, 1, 1, 1, 1}},
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    tt_scene *scene = anim_scene();
    tt_config *cfg = ae_config_of(ai, cases[c].kv);
    tt_accel *acc = NULL;
    CHECK_MSG(ai->build(scene, cfg, &acc, NULL) == TT_OK, "%s: %s", cases[c].label,
              tt_last_error());
    for (int k = 0; acc && k < 6; k++) {
      double t = 0.3 * (k + 1);
      CHECK(tt_scene_set_time(scene, t, t - 1.0 / 24) == TT_OK);
      tt_accel_update_stats us = {.struct_size = sizeof us};
      CHECK(ai->update(acc, &us) == TT_OK);
      CHECK_MSG(us.rebuilt == cases[c].rebuilt[k], "%s: update %d: rebuilt %d, expected %d",
                cases[c].label, k + 1, us.rebuilt, cases[c].rebuilt[k]);
      CHECK(us.update_ms >= 0.0);
      /* the custom tree reports its SAH cost; a refit's can only be judged against the build */
      if (!strcmp(cases[c].label, "custom refit"))
        CHECK_MSG(us.sah_cost > 0 && us.sah_growth > 0.5, "%s: sah %g, growth %g", cases[c].label,
                  us.sah_cost, us.sah_growth);
    }
    ai->destroy(acc);
    tt_config_destroy(cfg);
    tt_scene_destroy(scene);
  }
  /* a short stats struct (an older caller) is filled up to its size only */
  tt_scene *scene = anim_scene();
  tt_accel *acc = NULL;
  CHECK(ai->build(scene, NULL, &acc, NULL) == TT_OK);
  struct {
    tt_accel_update_stats s;
    uint32_t guard;
  } small;
  memset(&small, 0xAB, sizeof small);
  small.s.struct_size = (uint32_t)offsetof(tt_accel_update_stats, rebuilt);
  CHECK(tt_scene_set_time(scene, 1.0, 0.9) == TT_OK);
  CHECK(acc && ai->update(acc, &small.s) == TT_OK);
  CHECK(small.s.struct_size == offsetof(tt_accel_update_stats, rebuilt));
  CHECK(small.s.rebuilt == (int32_t)0xABABABAB && small.guard == 0xABABABABu);
  ai->destroy(acc);
  tt_scene_destroy(scene);
}

/* A mesh of `tc` small random triangles in a cube of side 2 whose morph target moves every
 * triangle, unchanged, by up to 0.2 along each axis: much the same distribution of
 * triangles, but a tree grouped at the start no longer groups neighbours. */
static tt_scene *scatter_scene(uint32_t tc) {
  ae_rng rng = {0x5ca77e4ull};
  ae_buf b = {0};
  ae_scene_begin(&b);
  const uint32_t vc = 3 * tc;
  float *pos = malloc(sizeof(float) * 6 * vc);
  for (uint32_t t = 0; t < tc; t++) {
    double m[3], to[3], size = ae_uniform(&rng, 0.02, 0.05);
    for (int k = 0; k < 3; k++) {
      m[k] = ae_uniform(&rng, -1, 1);
      to[k] = m[k] + ae_uniform(&rng, -0.2, 0.2);
    }
    for (int v = 0; v < 3; v++)
      for (int k = 0; k < 3; k++) {
        const double d = size * ae_uniform(&rng, -0.5, 0.5);
        pos[3 * (3 * t + v) + k] = (float)(m[k] + d);
        pos[3 * vc + 3 * (3 * t + v) + k] = (float)(to[k] + d);
      }
  }
  ae_printf(&b, "{\"name\":\"scatter\",\"material\":\"m\",\"positions\":[");
  for (uint32_t i = 0; i < 3 * vc; i++) ae_printf(&b, "%s%.9g", i ? "," : "", (double)pos[i]);
  ae_printf(&b, "],\"indices\":[");
  for (uint32_t i = 0; i < vc; i++) ae_printf(&b, "%s%u", i ? "," : "", i);
  ae_printf(&b, "],\"morph\":{\"targets\":[{\"positions\":[");
  for (uint32_t i = 0; i < 3 * vc; i++)
    ae_printf(&b, "%s%.9g", i ? "," : "", (double)pos[3 * vc + i]);
  ae_printf(&b, "]}],\"keys\":[{\"time\":0,\"weights\":[0]},{\"time\":2,\"weights\":[1]}]}}");
  free(pos);
  return ae_scene_end(&b, "accel_embree scatter scene");
}

/* The native SAH-growth estimate measures what refit loses: it stays at 1 where a refitted
 * tree is as good as a fresh one (a rigid mesh translated and scaled uniformly), grows where
 * neighbours drift apart (scatter_scene: 1.58), and a factor below that growth rebuilds,
 * after which the growth is 1 again. */
static void check_growth_estimate(const tt_accel_iface *ai) {
  ae_rng rng = {0x9e0e57ull};
  ae_buf b = {0};
  ae_scene_begin(&b);
  const double c[3] = {0, 0, 0};
  ae_mesh_json(&b, &rng, 1, "glider", 3000, c, 0.6,
               "\"animation\":{\"keys\":[{\"time\":0,\"translate\":[0,0,0],\"scale\":1},"
               "{\"time\":2,\"translate\":[0.9,-0.4,0.3],\"scale\":2.5}]}",
               0);
  tt_scene *rigid = ae_scene_end(&b, "accel_embree glider scene");
  static const char *const kv[] = {"updateMethod", "refit", "refitSahGrowth", "8", NULL};
  tt_config *cfg = ae_config_of(ai, kv);
  tt_accel *acc = NULL;
  CHECK_MSG(ai->build(rigid, cfg, &acc, NULL) == TT_OK, "glider: %s", tt_last_error());
  for (int k = 1; acc && k <= 4; k++) {
    CHECK(tt_scene_set_time(rigid, 0.5 * k, 0.5 * k - 0.1) == TT_OK);
    tt_accel_update_stats us = {.struct_size = sizeof us};
    CHECK(ai->update(acc, &us) == TT_OK);
    CHECK_MSG(!us.rebuilt && us.sah_cost > 1.0 && fabs(us.sah_growth - 1.0) < 1e-3,
              "glider t=%g: rebuilt %d, sah %g, growth %.6f (expected 1)", 0.5 * k, us.rebuilt,
              us.sah_cost, us.sah_growth);
  }
  ai->destroy(acc);
  tt_scene_destroy(rigid);

  for (int limit = 0; limit < 2; limit++) {
    tt_scene *scene = scatter_scene(4000);
    static const char *const loose[] = {"updateMethod", "refit", "refitSahGrowth", "8", NULL};
    static const char *const tight[] = {"updateMethod", "refit", "refitSahGrowth", "1.2", NULL};
    tt_config *c2 = ae_config_of(ai, limit ? tight : loose);
    acc = NULL;
    CHECK_MSG(ai->build(scene, c2, &acc, NULL) == TT_OK, "scatter: %s", tt_last_error());
    CHECK(tt_scene_set_time(scene, 2.0, 1.9) == TT_OK);
    tt_accel_update_stats us = {.struct_size = sizeof us};
    CHECK(acc && ai->update(acc, &us) == TT_OK);
    if (!limit)
      CHECK_MSG(!us.rebuilt && us.sah_growth > 1.3 && us.sah_growth < 8.0,
                "scatter, factor 8: rebuilt %d, growth %g (expected 1.3-8, refitted)", us.rebuilt,
                us.sah_growth);
    else
      CHECK_MSG(us.rebuilt && fabs(us.sah_growth - 1.0) < 1e-9,
                "scatter, factor 1.2: rebuilt %d, growth %g (expected a rebuild, growth 1)",
                us.rebuilt, us.sah_growth);
    ai->destroy(acc);
    tt_config_destroy(c2);
    tt_scene_destroy(scene);
  }
  tt_config_destroy(cfg);
}

int main(void) {
  ae_plugin p = ae_load(NULL);
  const tt_accel_iface *ai = p.accel;
  CHECK(TT_HAS_FIELD(tt_accel_iface, ai, update) && ai->update);
  static const char *const native[] = {"updateMethod", "refit", NULL};
  static const char *const native_robust[] = {"updateMethod", "refit", "robust", "true", NULL};
  static const char *const bvh2[] = {"backend", "custom", "branchingFactor", "2", "updateMethod",
                                     "refit",   NULL};
  static const char *const bvh4[] = {
      "backend", "custom", "branchingFactor", "4", "updateMethod", "refit", "maxLeafSize",
      "8",       NULL};
  static const char *const bvh8[] = {"backend",
                                     "custom",
                                     "branchingFactor",
                                     "8",
                                     "updateMethod",
                                     "refit",
                                     "quality",
                                     "3",
                                     "robust",
                                     "true",
                                     NULL};
  check_growth_estimate(ai);
  check_refit(ai, "native", native);
  check_refit(ai, "native robust", native_robust);
  check_refit(ai, "custom bvh2", bvh2);
  check_refit(ai, "custom bvh4", bvh4);
  check_refit(ai, "custom bvh8 spatial robust", bvh8);
  check_schedule(ai);
  tt_registry_destroy(p.reg);
  return tt_test_finish("accel_embree_refit");
}
