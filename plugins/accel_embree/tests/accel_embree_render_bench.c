/* accel_embree end-to-end bench (suite 'bench'): whole path-traced renders, not the kernel.
 *
 * What a user runs: the host's render loop (integrator_pt, progressive passes of 1 spp,
 * the host's default thread pool), here in one process so that the scene is loaded once
 * and every configuration's structure is built once, then rendered side by side. Per
 * scene (living-room, bmw-m6, staircase, bathroom, killeroos from ../shared/scenes, and
 * the procedural voxel world of tools/scenes/generate.py, generated once into a cache
 * folder), per thread count (1, 2) and integrator_pt maxDepth (3, 8): `runs` rounds, each
 * rendering every configuration once (the order rotates between rounds, so drift in the
 * machine's load hits every configuration alike); the figure of a render is the CPU time
 * of the rendering threads (each chunk of host->parallel_for timed with the thread's CPU
 * clock: time spent preempted by other jobs on this shared machine is not counted) summed
 * over its passes, and its wall time. Tables give medians (and min, spread), ratios to native
 * default (the median over rounds of the ratio within a round, so drift cancels; CPU
 * time), build ms, memory, and end with geometric means over the scenes and the goals of
 * issue 16 marked met / not met (printed, never asserted: figures depend on the machine).
 * Each render is also split into traversal (CPU time inside the accel's stream calls, by
 * kind: camera rays, other closest hits, shadow rays) and the rest (shading, sampling, the
 * integrator), with the same paired ratios to native, and the summary says what share of
 * native's render traversal is and how much faster than native's it would have to be for a
 * render 1.10x native's (so a kernel figure can be read as a render figure).
 *
 *   meson test -C build --suite bench accel_embree_render_bench -v
 *   TT_PLUGIN_PATH=build/plugins TT_SOURCE_ROOT=. build/plugins/accel_embree/tests/accel_embree_render_bench \
 *       [runs] [scene filter, e.g. "living,bmw"] [configuration filter]
 * Environment: TT_BENCH_RES (WxH, default 320x240), TT_BENCH_SPP (8), TT_BENCH_THREADS
 * ("1,2"), TT_BENCH_DEPTHS ("3,8"), TT_BENCH_CONFIGS (extra "label=settings;..." rows,
 * settings as "name=value,..."), TT_BENCH_PT (integrator_pt settings, e.g. "wavefront=false"),
 * TT_SHARED_SCENES, TT_BENCH_VOXEL_DIR (cache of the voxel
 * world, default /tmp/tt_bench_voxel_world).
 *
 * Fails only if a plugin cannot load, a build or a pass fails, or two configurations'
 * images disagree beyond noise (they trace the same paths: same seed, same samples). */
#include <tunetrace/film.h>
#include <tunetrace/integrator.h>
#include <tunetrace/loader.h>
#include <tunetrace/tunetrace.h>

#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "bench_util.h"
#include "tt_test.h"

#define MAX_CFG 16
#define MAX_RUNS 15
#define MAX_SCENES 8
#define MAX_MODES 8 /* (threads, depth) pairs */

/* ---- a host whose parallel_for times every chunk with the thread's CPU clock ---- */

static tt_host g_host;
static _Atomic long long g_chunk_cpu_ns;
static tt_parallel_fn g_inner_fn;
static void *g_inner_ctx;

static long long thread_cpu_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return (long long)ts.tv_sec * 1000000000ll + ts.tv_nsec;
}

static void timed_chunk(void *ctx, uint64_t begin, uint64_t end, uint32_t thread_index) {
  (void)ctx;
  long long c0 = thread_cpu_ns();
  g_inner_fn(g_inner_ctx, begin, end, thread_index);
  atomic_fetch_add_explicit(&g_chunk_cpu_ns, thread_cpu_ns() - c0, memory_order_relaxed);
}

/* The default host's pool, each chunk timed (parallel_for is main-thread only and not
 * reentrant, so one global slot for the wrapped function is enough). */
static tt_status timed_parallel_for(uint64_t count, uint64_t grain, tt_parallel_fn fn, void *ctx) {
  g_inner_fn = fn;
  g_inner_ctx = ctx;
  return tt_default_host()->parallel_for(count, grain, timed_chunk, NULL);
}

/* ---- an accel table whose queries time themselves, to split a render into traversal and
 * the rest (shading, sampling, the integrator) ----
 *
 * The integrator calls the accel through ctx.accel_iface, so the bench hands it a copy of
 * the plugin's table whose query entries forward to the plugin's and add the calling
 * thread's CPU time to a counter. Streams (what integrator_pt's wavefront calls: up to 1024
 * rays per call, ~0.1 ms) are timed per call, which costs two clock reads per call (well
 * under 1% of a call); single-ray calls are counted but not timed (a clock read per ray
 * would cost as much as the ray), so a render that makes them shows them in the "1-ray"
 * column and its traversal figure leaves them out. */
static const tt_accel_iface *g_real;
static tt_accel_iface g_timed;
static _Atomic long long g_hit_ns;  /* closest-hit streams */
static _Atomic long long g_cam_ns;  /* of those, the streams from one origin (camera) */
static _Atomic long long g_occl_ns; /* occlusion streams */
static _Atomic long long g_single_calls;

static void timed_intersect1(const tt_accel *a, tt_ray *ray, tt_hit *hit) {
  atomic_fetch_add_explicit(&g_single_calls, 1, memory_order_relaxed);
  g_real->intersect1(a, ray, hit);
}
static int timed_occluded1(const tt_accel *a, const tt_ray *ray) {
  atomic_fetch_add_explicit(&g_single_calls, 1, memory_order_relaxed);
  return g_real->occluded1(a, ray);
}
static void timed_intersect_stream(const tt_accel *a, tt_ray *rays, tt_hit *hits, size_t n) {
  /* camera streams share one origin; the first and last rays stand for the stream (bounce
   * streams start at n different surface points) */
  const int camera = n > 1 && !memcmp(rays[0].org, rays[n - 1].org, sizeof rays[0].org);
  long long c0 = thread_cpu_ns();
  g_real->intersect_stream(a, rays, hits, n);
  long long dt = thread_cpu_ns() - c0;
  atomic_fetch_add_explicit(&g_hit_ns, dt, memory_order_relaxed);
  if (camera) atomic_fetch_add_explicit(&g_cam_ns, dt, memory_order_relaxed);
}
static void timed_occluded_stream(const tt_accel *a, const tt_ray *rays, uint8_t *occ, size_t n) {
  long long c0 = thread_cpu_ns();
  g_real->occluded_stream(a, rays, occ, n);
  atomic_fetch_add_explicit(&g_occl_ns, thread_cpu_ns() - c0, memory_order_relaxed);
}

/* The timed copy of `real` (kept for the whole run). */
static const tt_accel_iface *timed_accel(const tt_accel_iface *real) {
  g_real = real;
  g_timed = *real;
  g_timed.intersect1 = timed_intersect1;
  g_timed.occluded1 = timed_occluded1;
  g_timed.intersect_stream = timed_intersect_stream;
  g_timed.occluded_stream = timed_occluded_stream;
  return &g_timed;
}

/* ---- configurations ---- */

typedef struct bench_cfg {
  char label[48];
  char settings[200]; /* "name=value,..." over accel_embree's defaults; "pt.name=value"
                        * sets integrator_pt's */
} bench_cfg;

static const bench_cfg g_builtin[] = {
    {"native default", "backend=native"},
    {"custom default (bf2)", "backend=custom"},
    {"custom bf4 blk4 leaf8", "backend=custom,branchingFactor=4,sahBlockSize=4,maxLeafSize=8"},
    {"custom bf8 blk4 leaf8", "backend=custom,branchingFactor=8,sahBlockSize=4,maxLeafSize=8"},
    /* Embree's own scene arguments (BVH8Triangle4SceneBuilderSAH): native's tree exactly,
     * so against native default this row compares the traversal kernels alone */
    {"custom as native", "backend=custom,branchingFactor=8,sahBlockSize=4,minLeafSize=4,"
                         "maxLeafSize=32"},
    /* Embree's best tree for rendering (spatial splits, static scene): how much any tree
     * can give over native default, i.e. the ceiling of render-time tuning from it */
    {"native q3 static", "backend=native,quality=3,static=true"},
};
static bench_cfg g_cfgs[MAX_CFG];
static int g_ncfg;

/* Applies "name=value,..." to `c`; 0 on an unknown name or bad value. */
static int apply(tt_config *c, const char *settings) {
  char buf[256];
  snprintf(buf, sizeof buf, "%s", settings);
  for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
    char *eq = strchr(tok, '=');
    if (!eq) continue;
    *eq = '\0';
    if (tt_config_set_string(c, tok, eq + 1) != TT_OK) {
      fprintf(stderr, "config: %s=%s: %s\n", tok, eq + 1, tt_last_error());
      return 0;
    }
  }
  return 1;
}

/* Splits a row's "name=value,..." into accel_embree's settings and integrator_pt's (those
 * written "pt.name=value"). Both buffers hold `size` bytes. */
static void split_settings(const char *settings, char *accel, char *pt, size_t size) {
  char buf[256];
  snprintf(buf, sizeof buf, "%s", settings);
  accel[0] = pt[0] = '\0';
  for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
    char *dst = strncmp(tok, "pt.", 3) == 0 ? pt : accel;
    const char *t = dst == pt ? tok + 3 : tok;
    size_t len = strlen(dst);
    snprintf(dst + len, size - len, "%s%s", len ? "," : "", t);
  }
}

/* Whether scene `name` passes the scene filter: NULL, or a comma-separated list of which
 * one item is a substring of the name ("living,bmw" runs a two-scene subset). */
static int scene_wanted(const char *name, const char *filter) {
  if (!filter || !filter[0]) return 1;
  char buf[256];
  snprintf(buf, sizeof buf, "%s", filter);
  for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save))
    if (strstr(name, tok)) return 1;
  return 0;
}

/* Built-in rows (filtered by label), then TT_BENCH_CONFIGS "label=settings;...". */
static void init_configs(const char *filter) {
  for (size_t i = 0; i < sizeof g_builtin / sizeof g_builtin[0]; i++)
    if (i == 0 || !filter || strstr(g_builtin[i].label, filter)) g_cfgs[g_ncfg++] = g_builtin[i];
  const char *extra = getenv("TT_BENCH_CONFIGS");
  if (!extra) return;
  char buf[2048];
  snprintf(buf, sizeof buf, "%s", extra);
  char *save = NULL;
  for (char *tok = strtok_r(buf, ";", &save); tok && g_ncfg < MAX_CFG;
       tok = strtok_r(NULL, ";", &save)) {
    char *eq = strchr(tok, '=');
    if (!eq) continue;
    *eq = '\0';
    snprintf(g_cfgs[g_ncfg].label, sizeof g_cfgs[g_ncfg].label, "%s", tok);
    snprintf(g_cfgs[g_ncfg].settings, sizeof g_cfgs[g_ncfg].settings, "%s", eq + 1);
    g_ncfg++;
  }
}

/* ---- modes (threads x maxDepth) ---- */

typedef struct mode {
  int threads, depth;
} mode;
static mode g_modes[MAX_MODES];
static int g_nmodes;

static int parse_list(const char *text, int *out, int max) {
  int n = 0;
  char buf[128];
  snprintf(buf, sizeof buf, "%s", text);
  for (char *tok = strtok(buf, ","); tok && n < max; tok = strtok(NULL, ","))
    if (atoi(tok) > 0 || strcmp(tok, "0") == 0) out[n++] = atoi(tok);
  return n;
}

/* ---- per-scene results, for the summary ---- */

typedef struct scene_result {
  char name[32];
  uint64_t triangles;
  int have[MAX_CFG];
  double cpu[MAX_MODES][MAX_CFG];        /* median CPU ms */
  double wall[MAX_MODES][MAX_CFG];       /* median wall ms */
  double ratio[MAX_MODES][MAX_CFG];      /* median over rounds of native CPU ms / this CPU ms */
  double trav[MAX_MODES][MAX_CFG];       /* median CPU ms in the accel's streams */
  double trav_ratio[MAX_MODES][MAX_CFG]; /* median over rounds of native's / this one's */
  double rest_ratio[MAX_MODES][MAX_CFG]; /* the same for the rest of the render */
  double mib[MAX_CFG];
} scene_result;
static scene_result g_res[MAX_SCENES];
static int g_nres;

/* ---- one scene ---- */

typedef struct plugins {
  const tt_accel_iface *A;
  const tt_accel_iface *Aq; /* A's copy whose queries time themselves (timed_accel) */
  const tt_integrator_iface *I;
} plugins;

static int g_runs, g_spp, g_w, g_h;

/* The figures of one render (ms are CPU ms of the rendering threads). */
typedef struct render_fig {
  double cpu, wall; /* the whole render; wall: wall-clock ms */
  double trav;      /* in the accel's streams (closest hit + occlusion) */
  double occl, cam; /* of trav: occlusion streams; camera (one-origin) streams */
  uint64_t rays;
  long long singles; /* single-ray calls (counted, not timed) */
} render_fig;

/* Renders one image (g_spp passes of 1 spp, as the host does) into `film`. */
static render_fig render_once(const plugins *P, tt_integrator *it, const tt_scene *scene,
                              const tt_accel *acc, tt_film *film) {
  tt_film_clear(film);
  atomic_store(&g_chunk_cpu_ns, 0);
  atomic_store(&g_hit_ns, 0);
  atomic_store(&g_cam_ns, 0);
  atomic_store(&g_occl_ns, 0);
  atomic_store(&g_single_calls, 0);
  uint64_t r = 0;
  double w0 = bench_wall_ms();
  for (int p = 0; p < g_spp; p++) {
    tt_render_ctx ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.struct_size = sizeof ctx;
    ctx.scene = scene;
    ctx.accel_iface = P->Aq;
    ctx.accel = acc;
    ctx.film = film;
    ctx.camera = tt_scene_camera(scene);
    ctx.seed = 1;
    ctx.pass_index = (uint32_t)p;
    ctx.spp = 1;
    ctx.sample_offset = (uint64_t)p;
    tt_pass_stats ps;
    memset(&ps, 0, sizeof ps);
    ps.struct_size = sizeof ps;
    tt_status s = P->I->render_pass(it, &ctx, &ps);
    CHECK_MSG(s == TT_OK, "render_pass: %s", tt_last_error());
    r += ps.rays;
  }
  render_fig f;
  f.wall = bench_wall_ms() - w0;
  f.cpu = 1e-6 * (double)atomic_load(&g_chunk_cpu_ns);
  f.occl = 1e-6 * (double)atomic_load(&g_occl_ns);
  f.cam = 1e-6 * (double)atomic_load(&g_cam_ns);
  f.trav = 1e-6 * (double)atomic_load(&g_hit_ns) + f.occl;
  f.rays = r;
  f.singles = atomic_load(&g_single_calls);
  return f;
}

/* Mean of the film's resolved RGB (for the same-image check). */
static double film_mean(const tt_film *film) {
  size_t n = (size_t)tt_film_width(film) * tt_film_height(film);
  float *rgb = malloc(3 * n * sizeof *rgb);
  if (!rgb) return 0.0;
  tt_film_resolve(film, rgb);
  double s = 0.0;
  for (size_t i = 0; i < 3 * n; i++) s += isfinite(rgb[i]) ? rgb[i] : 0.0;
  free(rgb);
  return s / (double)(3 * n);
}

static void bench_scene(const plugins *P, const char *name, tt_scene *scene) {
  if (g_nres >= MAX_SCENES) return;
  scene_result *res = &g_res[g_nres++];
  memset(res, 0, sizeof *res);
  snprintf(res->name, sizeof res->name, "%s", name);
  res->triangles = tt_scene_triangle_count(scene);
  CHECK(tt_scene_set_resolution(scene, (uint32_t)g_w, (uint32_t)g_h) == TT_OK);
  tt_film *film = tt_film_create((uint32_t)g_w, (uint32_t)g_h, 0);
  CHECK(film != NULL);
  if (!film) return;

  /* Build every configuration once (kept for the whole scene). */
  tt_accel *acc[MAX_CFG] = {0};
  tt_accel_build_stats bs[MAX_CFG];
  const tt_space *space = P->A->space();
  printf("\n%s: %llu triangles, %dx%d, %d spp (passes of 1 spp), %d rounds\n", name,
         (unsigned long long)res->triangles, g_w, g_h, g_spp, g_runs);
  fflush(stdout);
  for (int c = 0; c < g_ncfg; c++) {
    tt_config *cfg = tt_config_create(space);
    memset(&bs[c], 0, sizeof bs[c]);
    bs[c].struct_size = sizeof bs[c];
    char accel_part[256], pt_part[256];
    split_settings(g_cfgs[c].settings, accel_part, pt_part, sizeof pt_part);
    if (cfg && apply(cfg, accel_part)) {
      tt_status s = P->A->build(scene, cfg, &acc[c], &bs[c]);
      CHECK_MSG(s == TT_OK, "%s [%s]: build: %s", name, g_cfgs[c].label, tt_last_error());
      if (s != TT_OK) acc[c] = NULL;
    }
    tt_config_destroy(cfg);
    res->have[c] = acc[c] != NULL;
    res->mib[c] = (double)bs[c].memory_bytes / (1024.0 * 1024.0);
  }

  for (int m = 0; m < g_nmodes; m++) {
    const mode *md = &g_modes[m];
    CHECK(tt_default_host_set_threads((uint32_t)md->threads) == TT_OK);
    /* One integrator per row: its "pt." settings over maxDepth and TT_BENCH_PT. */
    tt_integrator *it[MAX_CFG] = {0};
    for (int c = 0; c < g_ncfg; c++) {
      if (!acc[c]) continue;
      tt_config *ic = tt_config_create(P->I->space());
      char set[512], accel_part[256], pt_part[256];
      const char *pt_extra = getenv("TT_BENCH_PT");
      split_settings(g_cfgs[c].settings, accel_part, pt_part, sizeof pt_part);
      snprintf(set, sizeof set, "maxDepth=%d%s%s%s%s", md->depth, pt_extra ? "," : "",
               pt_extra ? pt_extra : "", pt_part[0] ? "," : "", pt_part);
      CHECK(ic && apply(ic, set));
      tt_status s = P->I->create(scene, ic, &it[c]);
      tt_config_destroy(ic);
      CHECK_MSG(s == TT_OK, "integrator_pt create: %s", tt_last_error());
      if (s != TT_OK) it[c] = NULL;
    }
    /* per round, as columns for bench_median */
    double cpu[MAX_CFG][MAX_RUNS], wall[MAX_CFG][MAX_RUNS], trav[MAX_CFG][MAX_RUNS];
    double occl[MAX_CFG][MAX_RUNS], cam[MAX_CFG][MAX_RUNS];
    double mean[MAX_CFG];
    render_fig warm[MAX_CFG]; /* rays and single-ray calls (the same every round) */
    memset(mean, 0, sizeof mean);
    memset(warm, 0, sizeof warm);
    /* Warm-up: one render of each, not counted (first touch of the tree's pages). */
    for (int c = 0; c < g_ncfg; c++)
      if (acc[c] && it[c]) {
        warm[c] = render_once(P, it[c], scene, acc[c], film);
        mean[c] = film_mean(film);
      }
    for (int r = 0; r < g_runs; r++)
      for (int k = 0; k < g_ncfg; k++) {
        int c = (k + r) % g_ncfg; /* rotate the order */
        if (!acc[c] || !it[c]) continue;
        const render_fig f = render_once(P, it[c], scene, acc[c], film);
        cpu[c][r] = f.cpu, wall[c][r] = f.wall, trav[c][r] = f.trav;
        occl[c][r] = f.occl, cam[c][r] = f.cam;
      }
    for (int c = 0; c < g_ncfg; c++) P->I->destroy(it[c]);
    printf("  threads %d, maxDepth %d: %.2f Mrays per image\n", md->threads, md->depth,
           1e-6 * (double)warm[0].rays);
    printf("  %-28s %9s %9s %7s %9s %7s | %10s %9s %7s | %8s %6s %9s %9s %6s | %6s %6s %6s\n",
           "configuration", "CPU ms", "min", "spread", "wall ms", "on-CPU", "vs native",
           "(of mins)", "rays", "trav ms", "share", "trav/nat", "rest/nat", "1-ray", "camera",
           "bounce", "shadow");
    for (int c = 0; c < g_ncfg; c++) {
      if (!acc[c] || !it[c]) {
        printf("  %-28s (build failed)\n", g_cfgs[c].label);
        continue;
      }
      res->cpu[m][c] = bench_median(cpu[c], g_runs);
      res->wall[m][c] = bench_median(wall[c], g_runs);
      double mn = cpu[c][0], mx = cpu[c][0], q[MAX_RUNS], qt[MAX_RUNS], qr[MAX_RUNS];
      for (int r = 0; r < g_runs; r++) {
        mn = cpu[c][r] < mn ? cpu[c][r] : mn, mx = cpu[c][r] > mx ? cpu[c][r] : mx;
        /* paired: native's render and this one's in the same round (drift cancels) */
        q[r] = acc[0] && cpu[c][r] > 0 ? cpu[0][r] / cpu[c][r] : 0.0;
        qt[r] = acc[0] && trav[c][r] > 0 ? trav[0][r] / trav[c][r] : 0.0;
        double rest0 = cpu[0][r] - trav[0][r], rest = cpu[c][r] - trav[c][r];
        qr[r] = acc[0] && rest > 0 ? rest0 / rest : 0.0;
      }
      res->trav[m][c] = bench_median(trav[c], g_runs);
      double occl_ms = bench_median(occl[c], g_runs), cam_ms = bench_median(cam[c], g_runs);
      res->trav_ratio[m][c] = bench_median(qt, g_runs);
      res->rest_ratio[m][c] = bench_median(qr, g_runs);
      double mn0 = cpu[0][0];
      for (int r = 0; r < g_runs; r++) mn0 = cpu[0][r] < mn0 ? cpu[0][r] : mn0;
      res->ratio[m][c] = bench_median(q, g_runs);
      double share = res->cpu[m][c] / (res->wall[m][c] * md->threads);
      printf("  %-28s %9.1f %9.1f %6.1f%% %9.1f %6.0f%% | %9.3fx %8.3fx %+6.2f%% | %8.1f %5.0f%% "
             "%8.3fx %8.3fx %6lld | %6.1f %6.1f %6.1f\n",
             g_cfgs[c].label, res->cpu[m][c], mn, 100.0 * (mx - mn) / res->cpu[m][c],
             res->wall[m][c], 100.0 * share, res->ratio[m][c], mn0 / mn,
             warm[0].rays
                 ? 100.0 * ((double)warm[c].rays - (double)warm[0].rays) / (double)warm[0].rays
                 : 0.0,
             res->trav[m][c], 100.0 * res->trav[m][c] / res->cpu[m][c], res->trav_ratio[m][c],
             res->rest_ratio[m][c], warm[c].singles, cam_ms, res->trav[m][c] - occl_ms - cam_ms,
             occl_ms);
      /* Same seed, same samples: the images may differ only where a hit differs by
       * round-off (a handful of paths). */
      if (acc[0] && mean[0] > 0)
        CHECK_MSG(fabs(mean[c] - mean[0]) <= 0.01 * mean[0], "%s [%s]: image mean %g vs %g", name,
                  g_cfgs[c].label, mean[c], mean[0]);
    }
    fflush(stdout);
  }
  printf("  %-28s %10s %8s %8s %6s\n", "configuration", "build ms", "MiB", "nodes", "depth");
  for (int c = 0; c < g_ncfg; c++)
    if (acc[c])
      printf("  %-28s %10.1f %8.2f %8llu %6u\n", g_cfgs[c].label, bs[c].build_ms, res->mib[c],
             (unsigned long long)bs[c].nodes, bs[c].max_depth);
  for (int c = 0; c < g_ncfg; c++) P->A->destroy(acc[c]);
  tt_film_destroy(film);
}

/* ---- scenes ---- */

static tt_scene *load_scene(const char *path) {
  struct stat sb;
  if (stat(path, &sb) != 0) {
    printf("note: %s not available: skipped\n", path);
    return NULL;
  }
  tt_scene *s = NULL;
  fflush(stdout); /* the loader's warnings go to stderr */
  double t0 = bench_wall_ms();
  if (tt_scene_load(path, &s) != TT_OK) {
    printf("note: %s does not load (%s): skipped\n", path, tt_last_error());
    return NULL;
  }
  printf("note: %s loaded in %.1f s\n", path, 1e-3 * (bench_wall_ms() - t0));
  return s;
}

/* The voxel world (generate.py voxel, default size: 1.27M triangles), generated once. */
static tt_scene *voxel_world(const char *root) {
  const char *dir = getenv("TT_BENCH_VOXEL_DIR");
  if (!dir) dir = "/tmp/tt_bench_voxel_world";
  char scene[4096], cmd[8192];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  struct stat sb;
  if (stat(scene, &sb) != 0) {
    snprintf(cmd, sizeof cmd, "'%s/tools/run' scenes.generate voxel '%s' >/dev/null", root, dir);
    printf("note: generating the voxel world into %s\n", dir);
    fflush(stdout);
    if (system(cmd) != 0) {
      printf("note: %s failed (python3-numpy missing?): voxel world skipped\n", cmd);
      return NULL;
    }
  }
  return load_scene(scene);
}

/* ---- summary ---- */

static double geomean_ratio(int m, int c, int *n_out, double *min_out) {
  double lg = 0.0, mn = INFINITY;
  int n = 0;
  for (int s = 0; s < g_nres; s++) {
    const scene_result *r = &g_res[s];
    if (!r->have[0] || !r->have[c] || r->ratio[m][c] <= 0) continue;
    double q = r->ratio[m][c];
    lg += log(q);
    if (q < mn) mn = q;
    n++;
  }
  *n_out = n;
  *min_out = mn;
  return n ? exp(lg / n) : 0.0;
}

/* Whether row c builds the custom backend (the goals' "best custom" is chosen among these). */
static int is_custom(int c) { return strstr(g_cfgs[c].settings, "backend=custom") != NULL; }

static void summary(void) {
  printf("\nratios to native default (render speed: median over rounds of native CPU ms / CPU ms "
         "of the same round), per scene and geometric mean\n");
  printf("%-28s %-8s", "configuration", "mode");
  for (int s = 0; s < g_nres; s++) printf(" %11.11s", g_res[s].name);
  printf(" %9s %7s\n", "geomean", "min");
  int best_c = -1;
  double best_score = 0.0;
  for (int c = 1; c < g_ncfg; c++) {
    double score = 0.0;
    for (int m = 0; m < g_nmodes; m++) {
      printf("%-28s t%d d%-4d", m == 0 ? g_cfgs[c].label : "", g_modes[m].threads,
             g_modes[m].depth);
      for (int s = 0; s < g_nres; s++) {
        const scene_result *r = &g_res[s];
        if (r->have[0] && r->have[c] && r->ratio[m][c] > 0) printf(" %10.3fx", r->ratio[m][c]);
        else printf(" %11s", "-");
      }
      int n;
      double mn, g = geomean_ratio(m, c, &n, &mn);
      printf(" %8.3fx %6.3fx\n", g, n ? mn : 0.0);
      score += log(g > 0 ? g : 1e-9);
    }
    if (c > 1 && is_custom(c) && (best_c < 0 || score > best_score)) best_c = c, best_score = score;
  }
  printf("\nmemory (MiB) / native default's\n");
  for (int c = 1; c < g_ncfg; c++) {
    printf("%-28s", g_cfgs[c].label);
    for (int s = 0; s < g_nres; s++)
      if (g_res[s].have[c] && g_res[s].mib[0] > 0)
        printf(" %10.2fx", g_res[s].mib[c] / g_res[s].mib[0]);
      else printf(" %11s", "-");
    printf("\n");
  }
  printf("\ntraversal speed / native default's (median over rounds of native's stream CPU ms "
         "/ this row's), and the same for the rest of the render\n");
  for (int c = 1; c < g_ncfg; c++)
    for (int m = 0; m < g_nmodes; m++) {
      printf("%-28s t%d d%-4d", m == 0 ? g_cfgs[c].label : "", g_modes[m].threads,
             g_modes[m].depth);
      for (int s = 0; s < g_nres; s++) {
        const scene_result *r = &g_res[s];
        if (r->have[0] && r->have[c] && r->trav_ratio[m][c] > 0)
          printf(" %5.3f %5.3f", r->trav_ratio[m][c], r->rest_ratio[m][c]);
        else printf(" %11s", "-");
      }
      printf("\n");
    }
  /* Where the render's time goes: native's traversal share, and what a render 1.10x
   * native's would ask of traversal if the rest (shading, sampling) stayed as fast. */
  printf("\ntraversal (the accel's streams) in native default's render, and the traversal "
         "speed (x native's) that a 1.10x render needs with the rest unchanged\n");
  for (int m = 0; m < g_nmodes; m++) {
    printf("%-28s t%d d%-4d", m == 0 ? "share / needed" : "", g_modes[m].threads, g_modes[m].depth);
    for (int s = 0; s < g_nres; s++) {
      const scene_result *r = &g_res[s];
      const double T = r->cpu[m][0], t = r->trav[m][0], cut = T - T / 1.10;
      if (!r->have[0] || T <= 0 || t <= 0) printf(" %11s", "-");
      else if (t <= cut) printf(" %4.0f%% never", 100.0 * t / T);
      else printf(" %4.0f%% %4.2fx", 100.0 * t / T, t / (t - cut));
    }
    printf("\n");
  }
  /* Issue 16's goals, printed (never asserted): each with its figure and met / NOT met. */
  printf("\ngoals (issue 16), CPU-time ratios to native default over %d scenes:\n", g_nres);
  int custom_default = -1;
  for (int c = 0; c < g_ncfg; c++)
    if (!strcmp(g_cfgs[c].label, "custom default (bf2)")) custom_default = c;
  if (best_c > 0) {
    /* "best" = the custom row with the highest geometric mean over all modes; picked on
     * the same rounds it is judged on, so with k candidate rows it is biased upwards by
     * about the noise of one row (see the spread column). */
    int all_met = 1;
    for (int m = 0; m < g_nmodes; m++) {
      int n;
      double mn, g = geomean_ratio(m, best_c, &n, &mn);
      all_met &= g >= 1.10 && mn >= 1.0;
      printf("  best custom (%s) t%d d%d: geomean %.3fx (goal >= 1.10: %s), min %.3fx "
             "(goal >= 1.0: %s)\n",
             g_cfgs[best_c].label, g_modes[m].threads, g_modes[m].depth, g,
             g >= 1.10 ? "met" : "NOT met", mn, mn >= 1.0 ? "met" : "NOT met");
    }
    printf("  => best custom >= 1.10x geomean, none below 1.0x, in every mode: %s\n",
           all_met ? "met" : "NOT met");
  }
  if (custom_default > 0) {
    int all_met = 1;
    for (int m = 0; m < g_nmodes; m++) {
      int n;
      double mn, g = geomean_ratio(m, custom_default, &n, &mn);
      all_met &= g >= 0.95;
      printf("  custom default t%d d%d: geomean %.3fx (goal >= 0.95: %s), min %.3fx\n",
             g_modes[m].threads, g_modes[m].depth, g, g >= 0.95 ? "met" : "NOT met", mn);
    }
    printf("  => custom default >= 0.95x in every mode: %s\n", all_met ? "met" : "NOT met");
  }
  /* Memory: every custom row against native default, scene by scene. */
  for (int c = 1; c < g_ncfg; c++) {
    if (!is_custom(c)) continue;
    double worst = 0.0;
    int n = 0;
    for (int s = 0; s < g_nres; s++)
      if (g_res[s].have[c] && g_res[s].mib[0] > 0) {
        double q = g_res[s].mib[c] / g_res[s].mib[0];
        worst = q > worst ? q : worst;
        n++;
      }
    if (n)
      printf("  memory of %s <= native on every scene: %s (largest %.2fx native)\n",
             g_cfgs[c].label, worst <= 1.0 ? "met" : "NOT met", worst);
  }
  printf("  verified render-time tuning gain >= 8%% median: not measured by this bench "
         "(tools/tuning/gains.py --verify; plugins/accel_embree/README.md)\n");
}

int main(int argc, char **argv) {
  g_runs = argc > 1 ? atoi(argv[1]) : 5;
  if (g_runs < 1 || g_runs > MAX_RUNS) g_runs = 5;
  const char *only = argc > 2 && argv[2][0] ? argv[2] : NULL;
  init_configs(argc > 3 ? argv[3] : NULL);
  const char *res = getenv("TT_BENCH_RES");
  g_w = 320, g_h = 240;
  if (res && sscanf(res, "%dx%d", &g_w, &g_h) != 2) g_w = 320, g_h = 240;
  g_spp = getenv("TT_BENCH_SPP") ? atoi(getenv("TT_BENCH_SPP")) : 8;
  if (g_spp < 1) g_spp = 8;
  int th[4], dp[4];
  int nt = parse_list(getenv("TT_BENCH_THREADS") ? getenv("TT_BENCH_THREADS") : "1,2", th, 4);
  int nd = parse_list(getenv("TT_BENCH_DEPTHS") ? getenv("TT_BENCH_DEPTHS") : "3,8", dp, 4);
  for (int i = 0; i < nt; i++)
    for (int j = 0; j < nd && g_nmodes < MAX_MODES; j++) g_modes[g_nmodes++] = (mode){th[i], dp[j]};

  const char *pdir = getenv("TT_PLUGIN_PATH");
  if (!pdir) TEST_SKIP("TT_PLUGIN_PATH is not set (run through meson test)");
  g_host = *tt_default_host();
  g_host.parallel_for = timed_parallel_for;
  tt_default_host_set_log_level(TT_LOG_WARN);
  tt_registry *reg = tt_registry_create(&g_host);
  char path[4096];
  tt_loaded_plugin *la = NULL, *li = NULL;
  snprintf(path, sizeof path, "%s/accel_embree/accel_embree.so", pdir);
  if (!reg || tt_registry_load(reg, path, &la) != TT_OK) {
    fprintf(stderr, "loading %s failed: %s\n", path, tt_last_error());
    return 1;
  }
  snprintf(path, sizeof path, "%s/integrator_pt/integrator_pt.so", pdir);
  if (tt_registry_load(reg, path, &li) != TT_OK) {
    fprintf(stderr, "loading %s failed: %s\n", path, tt_last_error());
    return 1;
  }
  plugins P = {tt_loaded_plugin_iface(la), NULL, tt_loaded_plugin_iface(li)};
  P.Aq = timed_accel(P.A);

  double load[3] = {0, 0, 0};
  if (getloadavg(load, 3) < 0) load[0] = load[1] = load[2] = -1;
  printf("accel_embree render bench: integrator_pt, %dx%d, %d spp, %d rounds (medians), "
         "configurations interleaved; figure = CPU ms of the rendering threads; load average "
         "at start %.2f %.2f %.2f on %ld CPUs\n",
         g_w, g_h, g_spp, g_runs, load[0], load[1], load[2], sysconf(_SC_NPROCESSORS_ONLN));

  const char *root = getenv("TT_SOURCE_ROOT");
  if (!root) root = ".";
  const char *shared = getenv("TT_SHARED_SCENES");
  char sdir[4000];
  if (shared) snprintf(sdir, sizeof sdir, "%s", shared);
  else snprintf(sdir, sizeof sdir, "%s/../shared/scenes", root);
  static const char *const scenes[][2] = {
      {"living-room", "living-room/living-room.pbrt"}, {"bmw-m6", "bmw-m6/bmw-m6.pbrt"},
      {"staircase", "staircase/staircase.pbrt"},       {"bathroom", "bathroom/bathroom.pbrt"},
      {"killeroos", "killeroos/killeroo-simple.pbrt"},
  };
  for (size_t i = 0; i < sizeof scenes / sizeof scenes[0]; i++) {
    if (!scene_wanted(scenes[i][0], only)) continue;
    snprintf(path, sizeof path, "%s/%s", sdir, scenes[i][1]);
    tt_scene *s = load_scene(path);
    if (!s) continue;
    bench_scene(&P, scenes[i][0], s);
    tt_scene_destroy(s);
  }
  if (scene_wanted("voxel-world", only)) {
    tt_scene *s = voxel_world(root);
    if (s) {
      bench_scene(&P, "voxel-world", s);
      tt_scene_destroy(s);
    }
  }
  if (getloadavg(load, 3) < 0) load[0] = load[1] = load[2] = -1;
  summary();
  printf("load average at the end: %.2f %.2f %.2f\n", load[0], load[1], load[2]);
  tt_registry_destroy(reg);
  return tt_test_finish("accel_embree_render_bench");
}
