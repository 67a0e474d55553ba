/* accel_embree custom backend: correctness against the brute-force reference.
 *
 * - every quality x branchingFactor x robust, each with several leaf sizes / maxDepth /
 *   sahBlockSize / cost settings, on random rays (mixed [tnear, tfar]) and a camera grid:
 *   closest t, ids, barycentrics, ng, tfar shortening; occlusion; both stream calls;
 * - the default kernels are AVX-512 where the CPU has it; the same (quick matrix plus
 *   watertightness) for the AVX2 and SSE4.1 kernels (TT_ACCEL_EMBREE_ISA=avx2 / sse41,
 *   plugin reloaded);
 * - the rotating thin cylinder of thesis 3.2.3 under every quality;
 * - the voxel monument's camera ray that an 8-ray packet answered unlike intersect1;
 * - watertightness of robust=true on a closed mesh (rays through shared vertices/edges);
 * - build statistics, counters, compact -> native fallback, degenerate inputs. */
#include "accel_embree_check.h"

#include <stdarg.h>

/* Host whose log keeps INFO and WARN lines (to see the compact fallback note). */
static tt_host g_host;
static char g_last_info[512];

/* Records INFO messages; prints WARN and ERROR for diagnosis. */
static void test_log(tt_log_level level, const char *plugin, const char *fmt, ...) {
  char msg[512];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  if (level == TT_LOG_INFO) snprintf(g_last_info, sizeof g_last_info, "%s", msg);
  if (level >= TT_LOG_WARN) fprintf(stderr, "[log %d %s] %s\n", (int)level, plugin, msg);
}

/* Leaf / depth / block / cost variants crossed with every quality x bf x robust. */
static const char *const g_variants[] = {
    "", /* Embree defaults: leaves up to 32, maxDepth 32 */
    "minLeafSize=1,maxLeafSize=1,maxDepth=64",
    "minLeafSize=4,maxLeafSize=8,sahBlockSize=4,maxDepth=20",
    "minLeafSize=3,maxLeafSize=17,sahBlockSize=8,travcost=5,intcost=0.5,maxDepth=48",
    "minLeafSize=32,maxLeafSize=32,travcost=10,intcost=0.1,static=true",
};
#define NVAR (sizeof g_variants / sizeof g_variants[0])

/* The full matrix on one ray set; `quick` runs only the first two variants. */
static void run_matrix(const tt_accel_iface *A, const rayset *rs, int quick, const char *tag) {
  int built = 0;
  for (int q = 1; q <= 3; q++)
    for (int bf = 2; bf <= 8; bf *= 2)
      for (int robust = 0; robust <= 1; robust++)
        for (size_t v = 0; v < (quick ? 2 : NVAR); v++) {
          tt_config *c = tt_config_create(A->space());
          char base[128], name[256];
          snprintf(base, sizeof base, "backend=custom,quality=%d,branchingFactor=%d,robust=%s", q,
                   bf, robust ? "true" : "false");
          set_all(c, base);
          set_all(c, g_variants[v]);
          snprintf(name, sizeof name, "%s %s,%s", tag, base, g_variants[v]);
          tt_accel_build_stats st;
          long wrong = check_config(A, c, rs, name, 0, &st);
          CHECK_MSG(wrong >= 0, "build [%s]: %s", name, tt_last_error());
          CHECK_MSG(wrong <= 0, "[%s]: %ld wrong answers", name, wrong);
          if (wrong >= 0) {
            built++;
            CHECK_MSG(st.nodes > 0 && st.leaves > 0 && st.sah_cost > 0 && st.max_depth >= 2 &&
                          st.max_depth <= (uint32_t)tt_config_get_int(c, "maxDepth", 0) &&
                          st.memory_bytes > 0 && st.build_ms >= 0,
                      "[%s]: stats nodes %llu leaves %llu sah %g depth %u mem %llu", name,
                      (unsigned long long)st.nodes, (unsigned long long)st.leaves, st.sah_cost,
                      st.max_depth, (unsigned long long)st.memory_bytes);
          }
          tt_config_destroy(c);
        }
  printf("%s: %d configurations built and checked\n", tag, built);
}

/* A thin cylinder (radius 0.005, length 2) of `segs` x `rings` quads, rotated by `angle`
 * about (1,1,0)/sqrt2: long thin triangles whose boxes overlap badly (thesis 3.2.3). */
static tt_scene *thin_cylinder(double angle) {
  const uint32_t segs = 24, rings = 40, vc = segs * (rings + 1), tc = 2 * segs * rings;
  float *pos = malloc(sizeof(float) * 3 * vc);
  uint32_t *idx = malloc(sizeof(uint32_t) * 3 * tc);
  const double pi = 3.14159265358979323846, c = cos(angle), s = sin(angle);
  const double ax[3] = {0.70710678, 0.70710678, 0.0};
  for (uint32_t r = 0; r <= rings; r++)
    for (uint32_t k = 0; k < segs; k++) {
      double p[3] = {0.005 * cos(2 * pi * k / segs), 0.005 * sin(2 * pi * k / segs),
                     -1.0 + 2.0 * r / rings};
      /* Rodrigues rotation */
      double d = ax[0] * p[0] + ax[1] * p[1] + ax[2] * p[2];
      double cr[3] = {ax[1] * p[2] - ax[2] * p[1], ax[2] * p[0] - ax[0] * p[2],
                      ax[0] * p[1] - ax[1] * p[0]};
      for (int j = 0; j < 3; j++)
        pos[3 * (r * segs + k) + j] = (float)(p[j] * c + cr[j] * s + ax[j] * d * (1 - c));
    }
  uint32_t *q = idx;
  for (uint32_t r = 0; r < rings; r++)
    for (uint32_t k = 0; k < segs; k++) {
      uint32_t a = r * segs + k, b = r * segs + (k + 1) % segs, c2 = a + segs, d2 = b + segs;
      *q++ = a, *q++ = b, *q++ = d2;
      *q++ = a, *q++ = d2, *q++ = c2;
    }
  ae_buf buf = {0};
  ae_scene_begin(&buf);
  ae_scene_mesh(&buf, 1, "cylinder", pos, vc, idx, tc);
  free(pos);
  free(idx);
  return ae_scene_end(&buf, "thin cylinder");
}

/* Rays aimed at the cylinder's axis from random points around it. */
static rayset cylinder_rays(const tt_scene *scene, uint64_t seed) {
  /* slivers 0.0013 wide, 0.05 long: barycentrics good to ~1e-3 in float */
  rayset rs = {scene, 4000, malloc(4000 * sizeof(tt_ray)), malloc(4000 * sizeof(ae_ref)), 5e-3};
  ae_rng rng = {seed};
  const tt_mesh *m = tt_scene_mesh(scene, 0);
  for (size_t i = 0; i < rs.n; i++) {
    const float *t = m->positions + 3 * (ae_next(&rng) % m->vertex_count);
    tt_ray *r = &rs.rays[i];
    for (int k = 0; k < 3; k++) {
      r->org[k] = (float)ae_uniform(&rng, -1.5, 1.5);
      r->dir[k] = (float)(t[k] + ae_uniform(&rng, -0.004, 0.004)) - r->org[k];
    }
    r->tnear = 0.0f;
    r->tfar = INFINITY;
    rs.ref[i] = ae_brute(scene, r);
  }
  return rs;
}

/* Thesis 3.2.3: the rotating thin cylinder builds and traces under every quality. */
static void test_cylinder(const tt_accel_iface *A) {
  for (int step = 0; step < 4; step++) {
    tt_scene *s = thin_cylinder(step * 0.4);
    rayset rs = cylinder_rays(s, 99 + (uint64_t)step);
    size_t hits = 0;
    for (size_t i = 0; i < rs.n; i++) hits += rs.ref[i].geom != TT_INVALID_ID;
    CHECK(hits > rs.n / 4);
    for (int q = 1; q <= 3; q++)
      for (int bf = 2; bf <= 8; bf *= 4) {
        tt_config *c = tt_config_create(A->space());
        char name[128];
        snprintf(name, sizeof name, "backend=custom,quality=%d,branchingFactor=%d", q, bf);
        set_all(c, name);
        long wrong = check_config(A, c, &rs, name, 0, NULL);
        CHECK_MSG(wrong == 0, "cylinder angle %d [%s]: %ld wrong (%s)", step, name, wrong,
                  wrong < 0 ? tt_last_error() : "");
        tt_config_destroy(c);
      }
    free(rs.rays), free(rs.ref);
    tt_scene_destroy(s);
  }
}

/* A closed bumpy sphere; rays from inside toward vertices and edge midpoints must all hit
 * with robust=true (watertight). Non-robust misses are only reported. */
static void test_watertight(const tt_accel_iface *A) {
  const uint32_t rings = 60, segs = 80;
  uint32_t vc = (rings + 1) * (segs + 1), tc = 2 * rings * segs;
  float *pos = malloc(sizeof(float) * 3 * vc);
  uint32_t *idx = malloc(sizeof(uint32_t) * 3 * tc);
  const double pi = 3.14159265358979323846;
  for (uint32_t i = 0; i <= rings; i++)
    for (uint32_t j = 0; j <= segs; j++) {
      double th = pi * i / rings, ph = 2 * pi * (j % segs) / segs;
      double rad = 1.0 + 0.05 * sin(5 * th) * cos(7 * ph);
      float *p = pos + 3 * (i * (segs + 1) + j);
      p[0] = (float)(rad * sin(th) * cos(ph));
      p[1] = (float)(rad * cos(th));
      p[2] = (float)(rad * sin(th) * sin(ph));
    }
  /* poles and the seam: share exact vertex positions so the mesh is closed */
  for (uint32_t i = 0; i <= rings; i++)
    memcpy(pos + 3 * (i * (segs + 1) + segs), pos + 3 * (i * (segs + 1)), 3 * sizeof(float));
  for (uint32_t j = 0; j <= segs; j++) {
    memcpy(pos + 3 * j, pos, 3 * sizeof(float));
    memcpy(pos + 3 * (rings * (segs + 1) + j), pos + 3 * (rings * (segs + 1)), 3 * sizeof(float));
  }
  uint32_t *q = idx;
  for (uint32_t i = 0; i < rings; i++)
    for (uint32_t j = 0; j < segs; j++) {
      uint32_t a = i * (segs + 1) + j, b = a + 1, c = a + segs + 1, d = c + 1;
      *q++ = a, *q++ = c, *q++ = b;
      *q++ = b, *q++ = c, *q++ = d;
    }
  ae_buf buf = {0};
  ae_scene_begin(&buf);
  ae_scene_mesh(&buf, 1, "closed", pos, vc, idx, tc);
  tt_scene *s = ae_scene_end(&buf, "closed sphere");
  const tt_mesh *m = tt_scene_mesh(s, 0);
  /* targets: every vertex and the midpoint of every triangle's first edge */
  size_t n = m->vertex_count + m->triangle_count;
  tt_ray *rays = malloc(n * sizeof *rays);
  const float org[3] = {0.013f, -0.021f, 0.007f};
  for (size_t i = 0; i < n; i++) {
    float t[3];
    if (i < m->vertex_count) {
      memcpy(t, m->positions + 3 * i, sizeof t);
    } else {
      const uint32_t *tri = m->indices + 3 * (i - m->vertex_count);
      for (int k = 0; k < 3; k++)
        t[k] = 0.5f * (m->positions[3 * tri[0] + k] + m->positions[3 * tri[1] + k]);
    }
    for (int k = 0; k < 3; k++) rays[i].org[k] = org[k], rays[i].dir[k] = t[k] - org[k];
    rays[i].tnear = 0.0f;
    rays[i].tfar = INFINITY;
  }
  for (int robust = 1; robust >= 0; robust--)
    for (int bf = 2; bf <= 8; bf *= 2) {
      tt_config *c = tt_config_create(A->space());
      char name[128];
      snprintf(name, sizeof name, "backend=custom,branchingFactor=%d,robust=%s", bf,
               robust ? "true" : "false");
      set_all(c, name);
      tt_accel *acc = NULL;
      CHECK(A->build(s, c, &acc, NULL) == TT_OK);
      size_t miss = 0, occ_miss = 0;
      for (size_t i = 0; acc && i < n; i++) {
        tt_ray r = rays[i];
        tt_hit h;
        A->intersect1(acc, &r, &h);
        miss += h.geom_id == TT_INVALID_ID;
        occ_miss += !A->occluded1(acc, &rays[i]);
      }
      printf("watertight [%s]: %zu of %zu rays through vertices/edges missed (%zu occlusion)\n",
             name, miss, n, occ_miss);
      if (robust) CHECK_MSG(miss == 0 && occ_miss == 0, "robust [%s] leaks", name);
      A->destroy(acc);
      tt_config_destroy(c);
    }
  free(rays), free(pos), free(idx);
  tt_scene_destroy(s);
}

/* Counters on/off, compact fallback, stats prefix. */
static void test_counters_and_fallback(const tt_accel_iface *A, const rayset *rs) {
  tt_config *c = tt_config_create(A->space());
  set_all(c, "backend=custom,branchingFactor=4,counters=true");
  tt_accel *acc = NULL;
  CHECK(A->build(rs->scene, c, &acc, NULL) == TT_OK && acc);
  tt_ray *w = malloc(rs->n * sizeof *w);
  tt_hit *h = malloc(rs->n * sizeof *h);
  memcpy(w, rs->rays, rs->n * sizeof *w);
  A->intersect_stream(acc, w, h, rs->n);
  size_t occluded = 0;
  for (size_t i = 0; i < 100; i++) occluded += (size_t)A->occluded1(acc, &rs->rays[i]);
  /* occlusion streams walk the tree in groups of rays: still one count per ray, and the
   * same work per ray as occluded1 (a ray visits the same nodes in the same order, up to
   * its first hit) */
  uint8_t *occ = malloc(rs->n);
  tt_accel_counters c1 = {.struct_size = sizeof c1}, c2 = {.struct_size = sizeof c2};
  CHECK(A->counters(acc, &c1, 1) == TT_OK);
  for (size_t i = 0; i < rs->n; i++) occ[i] = (uint8_t)A->occluded1(acc, &rs->rays[i]);
  CHECK(A->counters(acc, &c1, 1) == TT_OK && c1.rays == rs->n);
  A->occluded_stream(acc, rs->rays, occ, rs->n);
  CHECK(A->counters(acc, &c2, 0) == TT_OK && c2.rays == rs->n);
  CHECK_MSG(c2.nodes_visited == c1.nodes_visited && c2.triangles_tested == c1.triangles_tested,
            "occlusion work: stream %llu nodes %llu triangles, single %llu / %llu",
            (unsigned long long)c2.nodes_visited, (unsigned long long)c2.triangles_tested,
            (unsigned long long)c1.nodes_visited, (unsigned long long)c1.triangles_tested);
  free(occ);
  A->intersect_stream(acc, w, h, rs->n);
  for (size_t i = 0; i < 100; i++) occluded += (size_t)A->occluded1(acc, &rs->rays[i]);
  tt_accel_counters cnt = {.struct_size = sizeof cnt};
  CHECK(A->counters(acc, &cnt, 1) == TT_OK);
  CHECK(cnt.rays == rs->n + rs->n + 100);
  CHECK(cnt.nodes_visited > rs->n && cnt.triangles_tested > 0);
  printf("counters: %llu rays, %.2f nodes and %.2f triangles per ray\n",
         (unsigned long long)cnt.rays, (double)cnt.nodes_visited / (double)cnt.rays,
         (double)cnt.triangles_tested / (double)cnt.rays);
  CHECK(A->counters(acc, &cnt, 0) == TT_OK && cnt.rays == 0 && cnt.nodes_visited == 0);
  A->destroy(acc);
  (void)occluded;

  /* counters off: unsupported, with a message that says how to turn them on */
  set_all(c, "counters=false");
  CHECK(A->build(rs->scene, c, &acc, NULL) == TT_OK);
  CHECK(A->counters(acc, &cnt, 0) == TT_ERR_UNSUPPORTED);
  CHECK_CONTAINS(tt_last_error(), "counters=true");
  A->destroy(acc);

  /* compact: built by backend native (no counters there), with an INFO note */
  g_last_info[0] = '\0';
  set_all(c, "compact=true,counters=true");
  tt_accel_build_stats st = {.struct_size = sizeof st};
  CHECK(A->build(rs->scene, c, &acc, &st) == TT_OK);
  CHECK(st.nodes == 0); /* native reports no node counts */
  CHECK(A->counters(acc, &cnt, 0) == TT_ERR_UNSUPPORTED);
  CHECK_CONTAINS(tt_last_error(), "native");
  CHECK_CONTAINS(g_last_info, "falls back to native");
  tt_ray r = rs->rays[NRAYS + CAM * CAM / 2];
  tt_hit hh;
  A->intersect1(acc, &r, &hh);
  CHECK(hh.geom_id == rs->ref[NRAYS + CAM * CAM / 2].geom ||
        rs->ref[NRAYS + CAM * CAM / 2].ambiguous);
  A->destroy(acc);
  tt_config_destroy(c);
  free(w), free(h);
}

/* Degenerate inputs: one triangle; zero-area triangles; a NaN vertex (the scene loader
 * refuses it, which is the defined behaviour then: noted, not failed). */
static void test_degenerate(const tt_accel_iface *A) {
  static const float pos[] = {0,   0, 0, 1, 0, 0, 0, 1, 0,  /* a real triangle */
                              2,   2, 2, 2, 2, 2, 2, 2, 2,  /* a point */
                              0,   0, 1, 1, 1, 1, 2, 2, 1,  /* collinear */
                              NAN, 0, 0, 1, 0, 0, 0, 1, 0}; /* NaN vertex */
  static const uint32_t idx[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  for (int variant = 0; variant < 3; variant++) {
    ae_buf b = {0};
    ae_scene_begin(&b);
    if (variant == 0) ae_scene_mesh(&b, 1, "one", pos, 3, idx, 1);
    if (variant == 1) ae_scene_mesh(&b, 1, "mixed", pos, 9, idx, 3);
    if (variant == 2) ae_scene_mesh(&b, 1, "nan", pos + 27, 3, idx, 1);
    ae_printf(&b, "]}");
    tt_scene *s = NULL;
    if (tt_scene_load_json(b.p, b.len, "degenerate", NULL, &s) != TT_OK) {
      printf("note: loader refuses degenerate variant %d: %s\n", variant, tt_last_error());
      free(b.p);
      continue;
    }
    free(b.p);
    for (int q = 1; q <= 3; q++)
      for (int bf = 2; bf <= 8; bf *= 2)
        for (int robust = 0; robust <= 1; robust++) {
          tt_config *c = tt_config_create(A->space());
          char name[128];
          snprintf(name, sizeof name, "backend=custom,quality=%d,branchingFactor=%d,robust=%s", q,
                   bf, robust ? "true" : "false");
          set_all(c, name);
          tt_accel *acc = NULL;
          tt_accel_build_stats st = {.struct_size = sizeof st};
          tt_status bs = A->build(s, c, &acc, &st);
          CHECK_MSG(bs == TT_OK, "degenerate %d [%s]: %s", variant, name, tt_last_error());
          if (bs != TT_OK) {
            tt_config_destroy(c);
            continue;
          }
          tt_ray r = {{0.2f, 0.2f, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
          tt_hit h;
          A->intersect1(acc, &r, &h);
          if (variant == 2) {
            CHECK(h.geom_id == TT_INVALID_ID);
          } else {
            CHECK_MSG(h.geom_id == 0 && h.prim_id == 0 && fabsf(h.t - 1.0f) < 1e-6f,
                      "degenerate %d [%s]: hit %u/%u t %g", variant, name, h.geom_id, h.prim_id,
                      (double)h.t);
          }
          /* NaN / zero-direction rays: defined (miss), no crash */
          tt_ray bad = {{NAN, 0, 0}, 0.0f, {0, 0, -1}, INFINITY};
          A->intersect1(acc, &bad, &h);
          CHECK(h.geom_id == TT_INVALID_ID && A->occluded1(acc, &bad) == 0);
          tt_ray zero = {{0.2f, 0.2f, 1.0f}, 0.0f, {0, 0, 0}, INFINITY};
          A->intersect1(acc, &zero, &h);
          CHECK(h.geom_id == TT_INVALID_ID);
          tt_ray empty = {{0.2f, 0.2f, 1.0f}, 2.0f, {0, 0, -1}, 1.0f}; /* tnear > tfar */
          CHECK(A->occluded1(acc, &empty) == 0);
          A->destroy(acc);
          tt_config_destroy(c);
        }
    tt_scene_destroy(s);
  }
}

/* Infeasible maxDepth: rejected ahead with the smallest feasible value in the message. */
static void test_infeasible(const tt_accel_iface *A, const tt_scene *scene) {
  tt_config *c = tt_config_create(A->space());
  set_all(c, "backend=custom,branchingFactor=2,maxLeafSize=1,maxDepth=8");
  tt_accel *acc = (tt_accel *)c;
  CHECK(A->build(scene, c, &acc, NULL) == TT_ERR_INFEASIBLE && acc == NULL);
  CHECK_CONTAINS(tt_last_error(), "maxDepth 8 is too small");
  CHECK_CONTAINS(tt_last_error(), "maxDepth >= 13"); /* 2^12 * 1 >= 3100 */
  /* the message's value is feasible for the count bound (Embree may still refuse an
   * unbalanced tree, which is reported as infeasible too) */
  set_all(c, "maxDepth=13");
  tt_status s = A->build(scene, c, &acc, NULL);
  CHECK_MSG(s == TT_OK || s == TT_ERR_INFEASIBLE, "maxDepth 13: %s", tt_last_error());
  if (s == TT_OK) A->destroy(acc);
  else CHECK_CONTAINS(tt_last_error(), "maxDepth");
  /* native ignores maxDepth: the same configuration builds there */
  set_all(c, "backend=native,maxDepth=8");
  CHECK(A->build(scene, c, &acc, NULL) == TT_OK);
  A->destroy(acc);
  tt_config_destroy(c);
}

/* A camera ray of the voxel monument (kernel bench, 1 of 262,144) whose 8-ray packet answer
 * differed from intersect1: it passes 7e-6 below the edge y = 29 of the unit quad at z = 0,
 * whose leaf box it misses, and hits the ground y = 0 behind it. The packet's other rays
 * hit the quad, so the packet enters the quad's leaf first (the larger ground is the first
 * child, and the quad is nearer for those lanes); the ray has no hit yet, tfar = +inf, and
 * a lane that missed a box (entry +inf) counted as live there (+inf <= +inf), so its
 * triangle test ran and accepted the quad within rounding of the edge, at t = 0x1.503aaep+7
 * as on the monument. The quad and the ray are the monument's, bit for bit (the same
 * vertex order, hence the same precomputed edges). Every width, leaves of 1 and 2 and the
 * defaults: stream answers equal intersect1's exactly, and ray 0 never hits the quad. */
static void test_packet_missed_box(const tt_accel_iface *A) {
  static const float pos[] = {31, 29, 0,   32, 29, 0,   32, 30, 0,   31, 30, 0,    /* quad */
                              40, 0,  -20, 60, 0,  -40, 60, 0,  -20, 40, 0,  -40}; /* ground */
  static const uint32_t idx[] = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 7, 5};
  ae_buf buf = {0};
  ae_scene_begin(&buf);
  ae_scene_mesh(&buf, 1, "voxel faces", pos, 8, idx, 4);
  tt_scene *scene = ae_scene_end(&buf, "voxel monument ray 243996");
  enum { NR = 8 };
  tt_ray rays[NR];
  for (int i = 0; i < NR; i++) {
    tt_ray *r = &rays[i];
    r->org[0] = -40.0f, r->org[1] = 132.0f, r->org[2] = 112.0f;
    r->tnear = 0.0f;
    r->tfar = INFINITY;
    if (i == 0) { /* the monument's ray, exactly */
      r->dir[0] = 0x1.b36568p-2f, r->dir[1] = -0x1.39b0d8p-1f, r->dir[2] = -0x1.5519c4p-1f;
      continue;
    }
    /* the others through the quad's interior */
    const float target[3] = {31.1f + 0.11f * (float)i, 29.9f - 0.12f * (float)i, 0.0f};
    float len = 0.0f;
    for (int k = 0; k < 3; k++) r->dir[k] = target[k] - r->org[k], len += r->dir[k] * r->dir[k];
    for (int k = 0; k < 3; k++) r->dir[k] /= sqrtf(len);
  }
  ae_ref ref0 = ae_brute(scene, &rays[0]);
  CHECK_MSG(ref0.geom == 0 && ref0.prim >= 2,
            "monument ray: the reference hits %u/%u (expected the ground quad)", ref0.geom,
            ref0.prim);
  static const char *const cfgs[] = {"", "maxLeafSize=2", "minLeafSize=1,maxLeafSize=1"};
  for (int bf = 2; bf <= 8; bf *= 2)
    for (size_t v = 0; v < sizeof cfgs / sizeof cfgs[0]; v++) {
      char name[160];
      snprintf(name, sizeof name, "backend=custom,branchingFactor=%d,%s", bf, cfgs[v]);
      tt_config *c = tt_config_create(A->space());
      set_all(c, name);
      tt_accel *acc = NULL;
      tt_status s = A->build(scene, c, &acc, NULL);
      CHECK_MSG(s == TT_OK, "monument ray [%s]: build: %s", name, tt_last_error());
      tt_config_destroy(c);
      if (s != TT_OK) continue;
      tt_ray w1[NR], w2[NR];
      tt_hit h1[NR], h2[NR];
      uint8_t o2[NR];
      memcpy(w1, rays, sizeof rays);
      memcpy(w2, rays, sizeof rays);
      for (int i = 0; i < NR; i++) A->intersect1(acc, &w1[i], &h1[i]);
      A->intersect_stream(acc, w2, h2, NR);
      A->occluded_stream(acc, rays, o2, NR);
      for (int i = 0; i < NR; i++) {
        int same = h1[i].geom_id == h2[i].geom_id && h1[i].prim_id == h2[i].prim_id &&
                   memcmp(&h1[i].t, &h2[i].t, sizeof h1[i].t) == 0 && h1[i].u == h2[i].u &&
                   h1[i].v == h2[i].v && w1[i].tfar == w2[i].tfar;
        CHECK_MSG(same, "monument ray %d [%s]: stream %u/%u t=%a, intersect1 %u/%u t=%a", i, name,
                  h2[i].geom_id, h2[i].prim_id, (double)h2[i].t, h1[i].geom_id, h1[i].prim_id,
                  (double)h1[i].t);
        CHECK_MSG(o2[i] == (uint8_t)A->occluded1(acc, &rays[i]),
                  "monument ray %d [%s]: occluded_stream differs", i, name);
      }
      CHECK_MSG(h2[0].prim_id != 0 && h2[0].prim_id != 1,
                "monument ray [%s]: the stream hits the quad it passes below (t=%a)", name,
                (double)h2[0].t);
      A->destroy(acc);
    }
  tt_scene_destroy(scene);
}

int main(void) {
  g_host = *tt_default_host();
  g_host.log = test_log;
  ae_plugin pl = ae_load(&g_host);
  const tt_accel_iface *A = pl.accel;

  static const uint32_t tris[3] = {1500, 1000, 600};
  tt_scene *scene = ae_random_scene(0x5eed1234abcdull, 3, tris);
  rayset rs = make_rayset(scene, 4242);

  test_packet_missed_box(A);
  run_matrix(A, &rs, 0, "default ISA");
  test_cylinder(A);
  test_watertight(A);
  test_counters_and_fallback(A, &rs);
  test_degenerate(A);
  test_infeasible(A, scene);
  tt_registry_destroy(pl.reg);

  /* The AVX2 kernels (what a CPU without AVX-512 runs; the default ISA above is AVX-512
   * where the CPU has it): reload the plugin. */
  setenv("TT_ACCEL_EMBREE_ISA", "avx2", 1);
  pl = ae_load(&g_host);
  test_packet_missed_box(pl.accel);
  run_matrix(pl.accel, &rs, 1, "avx2");
  test_watertight(pl.accel);
  tt_registry_destroy(pl.reg);

  /* The SSE4.1 baseline kernels (what a CPU without AVX2 runs): reload the plugin. */
  setenv("TT_ACCEL_EMBREE_ISA", "sse41", 1);
  pl = ae_load(&g_host);
  run_matrix(pl.accel, &rs, 1, "sse41");
  test_watertight(pl.accel);
  tt_registry_destroy(pl.reg);
  unsetenv("TT_ACCEL_EMBREE_ISA");

  free(rs.rays), free(rs.ref);
  tt_scene_destroy(scene);
  return tt_test_finish("accel_embree_custom");
}
