/* accel_embree bench (suite 'bench'): backend native versus backend custom, single thread
 * and all threads.
 *
 * Scenes: the Cornell box (scenes/cornell-box), a ~500k-triangle procedural bumpy sphere,
 * and, when ../shared/scenes is present, the Stanford bunny and the voxel monument (OBJ
 * files loaded through a scene.json "file" mesh, camera aimed at the bounds) and the pbrt
 * scenes living-room, bmw-m6 and staircase (loaded with tt_scene_load, traced from the
 * scene's own camera at 512x512). Rays: primary rays of a 512x512 pinhole camera
 * (coherent) and diffuse-bounce rays from the primary hits (incoherent; cosine directions
 * around the normal). For each configuration: build ms (median of `runs`, Embree's thread
 * pool), and single-thread Mrays/s of intersect1 and occluded1 (median of `runs` passes
 * over all rays, CPU time of the tracing thread). For native default, custom default and
 * the best custom configuration also intersect1 on all threads (the same rays split in
 * chunks over one pthread per CPU; wall time, median of `runs` passes). Ends with the
 * custom/native ratios that decide the default backend, as geometric means over scenes.
 *
 *   meson test -C BUILD --suite bench accel_embree_bench -v
 *   (or BUILD/plugins/accel_embree/tests/accel_embree_bench [runs] with TT_PLUGIN_PATH=BUILD/plugins)
 *
 * Fails only if the plugin cannot load or build, or custom and native disagree on more
 * than 1 ray in 10^4 (edge round-off). Figures depend on the machine. */
#include "accel_embree_common.h"

#include <tunetrace/camera.h>

#include <pthread.h>
#include <stdatomic.h>
#include <time.h>
#include <unistd.h>

#define W 512
#define H 512
#define NRAYS ((size_t)W * H)

/* CPU seconds of this thread: ray rates are single-threaded, and CPU time keeps them
 * meaningful on a shared, loaded machine (time spent preempted is not counted). */
static double cpu_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Wall-clock seconds (all-threads rates). */
static double wall_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Median of n values (sorts them). */
static double median(double *v, int n) {
  for (int i = 1; i < n; i++)
    for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
      double t = v[j];
      v[j] = v[j - 1];
      v[j - 1] = t;
    }
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* A bumpy sphere: (rings x segments) quads split in two, radius modulated so that the
 * surface is not trivially convex. 500 x 500 gives 499,000 triangles. */
static tt_scene *bumpy_sphere(uint32_t rings, uint32_t segs) {
  uint32_t vc = (rings + 1) * (segs + 1), tc = 2 * rings * segs;
  float *pos = malloc(sizeof(float) * 3 * vc);
  uint32_t *idx = malloc(sizeof(uint32_t) * 3 * tc);
  const double pi = 3.14159265358979323846;
  for (uint32_t i = 0; i <= rings; i++)
    for (uint32_t j = 0; j <= segs; j++) {
      double th = pi * i / rings, ph = 2 * pi * j / segs;
      double rad = 1.0 + 0.08 * sin(7 * th) * cos(9 * ph) + 0.03 * sin(31 * th + 17 * ph);
      float *p = pos + 3 * (i * (segs + 1) + j);
      p[0] = (float)(rad * sin(th) * cos(ph));
      p[1] = (float)(rad * cos(th));
      p[2] = (float)(rad * sin(th) * sin(ph));
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
  ae_scene_mesh(&buf, 1, "bumpy_sphere", pos, vc, idx, tc);
  free(pos);
  free(idx);
  return ae_scene_end(&buf, "bumpy sphere");
}

/* Loads an OBJ through a scene.json "file" mesh, then aims the camera at its bounds from
 * the front-left-above. NULL (skipped) when the file is absent or does not load. */
static tt_scene *obj_scene(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fclose(f);
  char json[4600];
  snprintf(json, sizeof json,
           "{\"version\":1,\"camera\":{\"position\":[0,0,5],\"target\":[0,0,0],\"up\":[0,1,0],"
           "\"fov\":40,\"resolution\":[%d,%d]},\"materials\":{\"m\":{\"type\":\"diffuse\","
           "\"albedo\":[0.5,0.5,0.5]}},\"meshes\":[{\"name\":\"obj\",\"material\":\"m\","
           "\"file\":\"%s\"}]}",
           W, H, path);
  tt_scene *s = NULL;
  if (tt_scene_load_json(json, strlen(json), path, NULL, &s) != TT_OK) {
    printf("note: %s does not load (%s): skipped\n", path, tt_last_error());
    return NULL;
  }
  float lo[3], hi[3], c[3], ext = 0.0f;
  tt_scene_bounds(s, lo, hi);
  for (int k = 0; k < 3; k++) {
    c[k] = 0.5f * (lo[k] + hi[k]);
    if (hi[k] - lo[k] > ext) ext = hi[k] - lo[k];
  }
  tt_camera cam = *tt_scene_camera(s);
  cam.position[0] = c[0] - 0.8f * ext, cam.position[1] = c[1] + 0.6f * ext;
  cam.position[2] = c[2] + 1.4f * ext;
  memcpy(cam.target, c, sizeof c);
  cam.key_count = 0;
  cam.keys = NULL;
  tt_scene_set_camera(s, &cam);
  return s;
}

/* Loads a pbrt scene with core's loader (its own camera is used for primary rays). NULL
 * (skipped) when the file is absent or does not load. */
static tt_scene *pbrt_scene(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fclose(f);
  tt_scene *s = NULL;
  fflush(stdout); /* the loader's warnings go to stderr: keep them between tables */
  double t0 = wall_s();
  if (tt_scene_load(path, &s) != TT_OK) {
    printf("note: %s does not load (%s): skipped\n", path, tt_last_error());
    return NULL;
  }
  printf("note: %s loaded in %.1f s\n", path, wall_s() - t0);
  return s;
}

/* Primary rays through pixel centres of the scene camera at W x H. */
static void primary_rays(tt_scene *scene, tt_ray *rays) {
  CHECK(tt_scene_set_resolution(scene, W, H) == TT_OK);
  tt_camera_frame fr;
  CHECK(tt_camera_frame_init(&fr, tt_scene_camera(scene)) == TT_OK);
  for (size_t y = 0; y < H; y++)
    for (size_t x = 0; x < W; x++)
      tt_camera_generate_ray(&fr, (float)x + 0.5f, (float)y + 0.5f, &rays[y * W + x]);
}

/* Diffuse-bounce rays: from each primary hit, a cosine-distributed direction around the
 * normal facing the camera; a missed primary gives a random ray through the scene box. */
static void bounce_rays(const tt_scene *scene, const tt_ray *prim, const tt_hit *hits,
                        tt_ray *out) {
  ae_rng rng = {0x9e3779b97f4a7c15ull};
  float lo[3], hi[3];
  tt_scene_bounds(scene, lo, hi);
  double diag = 0.0;
  for (int k = 0; k < 3; k++) diag += (double)(hi[k] - lo[k]) * (hi[k] - lo[k]);
  diag = sqrt(diag);
  for (size_t i = 0; i < NRAYS; i++) {
    tt_ray *r = &out[i];
    const tt_hit *h = &hits[i];
    double n[3], d[3];
    if (h->geom_id != TT_INVALID_ID) {
      double len = sqrt((double)h->ng[0] * h->ng[0] + (double)h->ng[1] * h->ng[1] +
                        (double)h->ng[2] * h->ng[2]);
      double dot = 0.0;
      for (int k = 0; k < 3; k++) {
        n[k] = len > 0 ? h->ng[k] / len : (k == 2);
        dot += n[k] * prim[i].dir[k];
      }
      if (dot > 0)
        for (int k = 0; k < 3; k++) n[k] = -n[k];
      /* cosine sample: uniform point on the unit sphere added to the normal */
      double s[3], l2;
      do {
        for (int k = 0; k < 3; k++) s[k] = ae_uniform(&rng, -1, 1);
        l2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
      } while (l2 > 1.0 || l2 < 1e-6);
      double dl = 0;
      for (int k = 0; k < 3; k++) {
        d[k] = n[k] + s[k] / sqrt(l2);
        dl += d[k] * d[k];
      }
      dl = sqrt(dl) + 1e-30;
      for (int k = 0; k < 3; k++) {
        r->org[k] = (float)(prim[i].org[k] + (double)h->t * prim[i].dir[k] + 1e-4 * diag * n[k]);
        r->dir[k] = (float)(d[k] / dl);
      }
    } else {
      for (int k = 0; k < 3; k++) {
        r->org[k] = (float)ae_uniform(&rng, lo[k], hi[k]);
        d[k] = ae_uniform(&rng, -1, 1);
      }
      for (int k = 0; k < 3; k++) r->dir[k] = (float)d[k];
    }
    r->tnear = 0.0f;
    r->tfar = INFINITY;
  }
}

/* One configuration of the table. */
typedef struct bench_cfg {
  const char *label;
  const char *settings; /* "name=value,..." applied over the defaults */
} bench_cfg;

static const bench_cfg g_cfgs[] = {
    {"native default", "backend=native"},
    {"native static", "backend=native,static=true"},
    {"custom default (bf2)", "backend=custom"},
    {"custom bf4", "backend=custom,branchingFactor=4"},
    {"custom bf8", "backend=custom,branchingFactor=8"},
    {"custom bf4 blk4 leaf8", "backend=custom,branchingFactor=4,sahBlockSize=4,maxLeafSize=8"},
    {"custom bf8 blk4 leaf8", "backend=custom,branchingFactor=8,sahBlockSize=4,maxLeafSize=8"},
    {"custom bf8 blk4 leaf8 q3",
     "backend=custom,quality=3,branchingFactor=8,sahBlockSize=4,maxLeafSize=8"},
    {"custom bf8 blk4 leaf16", "backend=custom,branchingFactor=8,sahBlockSize=4,maxLeafSize=16"},
    {"custom bf8 blk4 t2",
     "backend=custom,branchingFactor=8,sahBlockSize=4,maxLeafSize=8,travcost=2"},
    {"custom bf4 robust", "backend=custom,branchingFactor=4,robust=true"},
    /* Embree's own scene arguments (BVH8Triangle4SceneBuilderSAH): native's tree exactly,
     * so this row against native default compares the kernels alone */
    {"custom as native",
     "backend=custom,branchingFactor=8,sahBlockSize=4,minLeafSize=4,maxLeafSize=32"},
};
#define NCFG (sizeof g_cfgs / sizeof g_cfgs[0])

/* Applies "name=value,..." to `c`. */
static void apply(tt_config *c, const char *settings) {
  char buf[256];
  snprintf(buf, sizeof buf, "%s", settings);
  for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
    char *eq = strchr(tok, '=');
    if (!eq) continue;
    *eq = '\0';
    tt_status s = tt_config_set_string(c, tok, eq + 1);
    CHECK_MSG(s == TT_OK, "set %s=%s: %s", tok, eq + 1, tt_last_error());
  }
}

/* Single-thread Mrays/s of intersect1 over `n` rays: median of `runs` passes. */
static double rate_isect(const tt_accel_iface *A, const tt_accel *acc, const tt_ray *rays,
                         tt_ray *work, tt_hit *hits, int runs) {
  double v[16];
  for (int k = 0; k < runs; k++) {
    memcpy(work, rays, NRAYS * sizeof *rays);
    double t0 = cpu_s();
    for (size_t i = 0; i < NRAYS; i++) A->intersect1(acc, &work[i], &hits[i]);
    v[k] = (double)NRAYS / (cpu_s() - t0) * 1e-6;
  }
  return median(v, runs);
}

/* Single-thread Mrays/s of occluded1: median of `runs` passes. */
static double rate_occl(const tt_accel_iface *A, const tt_accel *acc, const tt_ray *rays,
                        uint8_t *occ, int runs) {
  double v[16];
  for (int k = 0; k < runs; k++) {
    double t0 = cpu_s();
    for (size_t i = 0; i < NRAYS; i++) occ[i] = (uint8_t)A->occluded1(acc, &rays[i]);
    v[k] = (double)NRAYS / (cpu_s() - t0) * 1e-6;
  }
  return median(v, runs);
}

/* Stream chunk: rays per intersect_stream / occluded_stream call (a 32x32 tile's worth, as
 * integrator_pt's wavefront passes them). */
#define STREAM_CHUNK 1024

/* Single-thread Mrays/s of intersect_stream in chunks of STREAM_CHUNK: median of `runs`. */
static double rate_isect_stream(const tt_accel_iface *A, const tt_accel *acc, const tt_ray *rays,
                                tt_ray *work, tt_hit *hits, int runs) {
  double v[16];
  for (int k = 0; k < runs; k++) {
    memcpy(work, rays, NRAYS * sizeof *rays);
    double t0 = cpu_s();
    for (size_t i = 0; i < NRAYS; i += STREAM_CHUNK)
      A->intersect_stream(acc, &work[i], &hits[i],
                          NRAYS - i < STREAM_CHUNK ? NRAYS - i : STREAM_CHUNK);
    v[k] = (double)NRAYS / (cpu_s() - t0) * 1e-6;
  }
  return median(v, runs);
}

/* Single-thread Mrays/s of occluded_stream in chunks of STREAM_CHUNK: median of `runs`. */
static double rate_occl_stream(const tt_accel_iface *A, const tt_accel *acc, const tt_ray *rays,
                               uint8_t *occ, int runs) {
  double v[16];
  for (int k = 0; k < runs; k++) {
    double t0 = cpu_s();
    for (size_t i = 0; i < NRAYS; i += STREAM_CHUNK)
      A->occluded_stream(acc, &rays[i], &occ[i],
                         NRAYS - i < STREAM_CHUNK ? NRAYS - i : STREAM_CHUNK);
    v[k] = (double)NRAYS / (cpu_s() - t0) * 1e-6;
  }
  return median(v, runs);
}

/* ---- all threads: the same ray set split in chunks over one pthread per CPU ---- */

static int g_threads = 1;

#define MT_CHUNK 1024

typedef struct mt_job {
  const tt_accel_iface *A;
  const tt_accel *acc;
  tt_ray *work;
  tt_hit *hits;
  atomic_size_t next;
  _Atomic long long cpu_ns; /* CPU time of all worker threads, summed */
} mt_job;

static void *mt_worker(void *arg) {
  mt_job *j = arg;
  double c0 = cpu_s();
  for (;;) {
    size_t b = atomic_fetch_add_explicit(&j->next, MT_CHUNK, memory_order_relaxed);
    if (b >= NRAYS) break;
    size_t e = b + MT_CHUNK < NRAYS ? b + MT_CHUNK : NRAYS;
    for (size_t i = b; i < e; i++) j->A->intersect1(j->acc, &j->work[i], &j->hits[i]);
  }
  atomic_fetch_add(&j->cpu_ns, (long long)((cpu_s() - c0) * 1e9));
  return NULL;
}

/* All-threads Mrays/s of intersect1 (wall time, thread start and join included): median
 * of `runs` passes. `share` gets the median fraction of threads x wall time the threads
 * were on a CPU (below 1: other load on the machine took the rest). */
static double rate_isect_mt(const tt_accel_iface *A, const tt_accel *acc, const tt_ray *rays,
                            tt_ray *work, tt_hit *hits, int runs, double *share) {
  double v[16], sh[16];
  pthread_t th[64];
  for (int k = 0; k < runs; k++) {
    memcpy(work, rays, NRAYS * sizeof *rays);
    mt_job j = {.A = A, .acc = acc, .work = work, .hits = hits};
    atomic_init(&j.next, 0);
    atomic_init(&j.cpu_ns, 0);
    double t0 = wall_s();
    int started = 0;
    for (int t = 1; t < g_threads; t++)
      if (pthread_create(&th[started], NULL, mt_worker, &j) == 0) started++;
    mt_worker(&j);
    for (int t = 0; t < started; t++) pthread_join(th[t], NULL);
    double w = wall_s() - t0;
    v[k] = (double)NRAYS / w * 1e-6;
    sh[k] = 1e-9 * (double)atomic_load(&j.cpu_ns) / (w * (started + 1));
  }
  *share = median(sh, runs);
  return median(v, runs);
}

/* The configurations also measured on all threads, and the one the README calls best. */
#define BEST_LABEL "custom bf8 blk4 leaf8"
static int all_threads_cfg(const char *label) {
  return !strcmp(label, "native default") || !strcmp(label, "custom default (bf2)") ||
         !strcmp(label, BEST_LABEL);
}

/* Configuration-label filter (argv[3]); native default always runs (reference). */
static const char *g_cfg_filter;

/* Log of the custom-default / native-default ratios, for a geometric mean over scenes. */
static double g_log_ratio_sum[2];
static int g_ratio_n;

/* Per configuration: log of its ratio to native default (prim, bounce, occl-p, occl-b,
 * all-threads prim, all-threads bounce) summed over scenes, and the scene count. */
static double g_cfg_log[16][6];
static double g_cfg_slog[16][4]; /* the same for the stream rates (vs native's streams) */
static int g_cfg_n[16], g_cfg_mt_n[16];
static int g_scene_n;

/* Runs every configuration on one scene and prints its table. */
static void bench_scene(const tt_accel_iface *A, const char *name, tt_scene *scene, int runs) {
  tt_ray *prim = malloc(NRAYS * sizeof *prim), *bounce = malloc(NRAYS * sizeof *bounce),
         *work = malloc(NRAYS * sizeof *work);
  tt_hit *hits = malloc(NRAYS * sizeof *hits), *ref_hits = malloc(NRAYS * sizeof *ref_hits);
  uint8_t *occ = malloc(NRAYS);
  primary_rays(scene, prim);
  printf("\n%s: %llu triangles, %zu primary + %zu diffuse-bounce rays, %d runs (medians)\n", name,
         (unsigned long long)tt_scene_triangle_count(scene), NRAYS, NRAYS, runs);
  printf("%-24s %9s %8s %7s %7s %8s | %8s %8s | %8s %8s\n", "configuration", "build ms", "MiB",
         "nodes", "depth", "SAH", "prim", "bounce", "occl-p", "occl-b");
  const tt_space *space = A->space();
  double native_rate[2] = {0, 0}, native_all[4] = {0, 0, 0, 0}, native_mt[2] = {0, 0};
  double native_stream[4] = {0, 0, 0, 0};
  g_scene_n++;
  for (size_t ci = 0; ci < NCFG; ci++) {
    if (ci > 0 && g_cfg_filter && !strstr(g_cfgs[ci].label, g_cfg_filter)) continue;
    tt_config *c = tt_config_create(space);
    apply(c, g_cfgs[ci].settings);
    double bms[16];
    tt_accel_build_stats st = {.struct_size = sizeof st};
    tt_accel *acc = NULL;
    for (int k = 0; k < runs; k++) {
      if (acc) A->destroy(acc);
      acc = NULL;
      memset(&st, 0, sizeof st);
      st.struct_size = sizeof st;
      tt_status s = A->build(scene, c, &acc, &st);
      CHECK_MSG(s == TT_OK, "%s build [%s]: %s", name, g_cfgs[ci].label, tt_last_error());
      if (s != TT_OK) break;
      bms[k] = st.build_ms;
    }
    tt_config_destroy(c);
    if (!acc) continue;
    if (ci == 0) {
      /* Bounce rays come from native's primary hits, so every backend traces the same. */
      memcpy(work, prim, NRAYS * sizeof *prim);
      for (size_t i = 0; i < NRAYS; i++) A->intersect1(acc, &work[i], &ref_hits[i]);
      bounce_rays(scene, prim, ref_hits, bounce);
    }
    double rp = rate_isect(A, acc, prim, work, hits, runs);
    tt_hit *prim_hits = malloc(NRAYS * sizeof *prim_hits);
    memcpy(prim_hits, hits, NRAYS * sizeof *hits);
    size_t differ = 0;
    for (size_t i = 0; i < NRAYS; i++)
      differ +=
          (hits[i].geom_id != ref_hits[i].geom_id) || (hits[i].prim_id != ref_hits[i].prim_id);
    double rb = rate_isect(A, acc, bounce, work, hits, runs);
    double op = rate_occl(A, acc, prim, occ, runs);
    double ob = rate_occl(A, acc, bounce, occ, runs);
    printf("%-24s %9.2f %8.2f %7llu %7u %8.2f | %8.2f %8.2f | %8.2f %8.2f\n", g_cfgs[ci].label,
           median(bms, runs), (double)st.memory_bytes / (1024.0 * 1024.0),
           (unsigned long long)st.nodes, st.max_depth, st.sah_cost, rp, rb, op, ob);
    /* Streams (chunks of STREAM_CHUNK): rates, and the same answers as the single-ray calls
     * (exactly for backend custom, whose stream kernels run the single-ray arithmetic). */
    {
      tt_hit *sh = malloc(NRAYS * sizeof *sh);
      uint8_t *so = malloc(NRAYS), *o1 = malloc(NRAYS);
      double sp = rate_isect_stream(A, acc, prim, work, sh, runs);
      size_t sdiff = 0, sties = 0;
      for (size_t i = 0; i < NRAYS; i++) {
        int d = sh[i].geom_id != prim_hits[i].geom_id || sh[i].prim_id != prim_hits[i].prim_id ||
                (sh[i].geom_id != TT_INVALID_ID && sh[i].t != prim_hits[i].t);
        /* a different triangle at a distance within rounding: a tie the order decides */
        int tie = d && sh[i].geom_id != TT_INVALID_ID && prim_hits[i].geom_id != TT_INVALID_ID &&
                  fabsf(sh[i].t - prim_hits[i].t) <= 1e-5f * fabsf(prim_hits[i].t);
        sdiff += d && !tie;
        sties += tie;
      }
      double sb = rate_isect_stream(A, acc, bounce, work, sh, runs);
      double sop = rate_occl_stream(A, acc, prim, so, runs);
      for (size_t i = 0; i < NRAYS; i++) o1[i] = (uint8_t)A->occluded1(acc, &prim[i]);
      size_t odiff = 0;
      for (size_t i = 0; i < NRAYS; i++) odiff += so[i] != o1[i];
      double sob = rate_occl_stream(A, acc, bounce, so, runs);
      printf("%-24s   streams of %d: %8.2f %8.2f | %8.2f %8.2f   (x single: %.2f %.2f | %.2f "
             "%.2f)\n",
             "", STREAM_CHUNK, sp, sb, sop, sob, sp / rp, sb / rb, sop / op, sob / ob);
      int custom = strstr(g_cfgs[ci].settings, "backend=custom") != NULL;
      /* custom: exactly (ties go to the smaller ids whatever the order of visit) */
      CHECK_MSG(sdiff <= (custom ? 0 : NRAYS / 10000) && odiff <= (custom ? 0 : NRAYS / 10000) &&
                    sties <= (custom ? 0 : NRAYS / 10000),
                "%s [%s]: streams differ from single rays on %zu hits (%zu of them ties), %zu "
                "occlusions",
                name, g_cfgs[ci].label, sdiff + sties, sties, odiff);
      double sall[4] = {sp, sb, sop, sob};
      if (ci == 0) memcpy(native_stream, sall, sizeof sall);
      else if (native_stream[0] > 0 && ci < 16) {
        for (int k = 0; k < 4; k++) g_cfg_slog[ci][k] += log(sall[k] / native_stream[k]);
      }
      free(sh), free(so), free(o1);
    }
    free(prim_hits);
    CHECK_MSG(differ <= NRAYS / 10000, "%s [%s]: %zu primary hits differ from native", name,
              g_cfgs[ci].label, differ);
    double mp = 0, mb = 0;
    if (all_threads_cfg(g_cfgs[ci].label)) {
      double shp, shb;
      mp = rate_isect_mt(A, acc, prim, work, hits, runs, &shp);
      size_t mt_differ = 0;
      for (size_t i = 0; i < NRAYS; i++)
        mt_differ +=
            (hits[i].geom_id != ref_hits[i].geom_id) || (hits[i].prim_id != ref_hits[i].prim_id);
      CHECK_MSG(mt_differ <= NRAYS / 10000, "%s [%s]: %zu all-threads primary hits differ", name,
                g_cfgs[ci].label, mt_differ);
      mb = rate_isect_mt(A, acc, bounce, work, hits, runs, &shb);
      printf("%-24s   all %d threads (wall): primary %.2f, bounce %.2f Mrays/s (threads on "
             "a CPU %.0f%% / %.0f%% of the time)\n",
             "", g_threads, mp, mb, 100 * shp, 100 * shb);
    }
    double all[4] = {rp, rb, op, ob};
    if (ci == 0) {
      native_rate[0] = rp, native_rate[1] = rb;
      memcpy(native_all, all, sizeof all);
      native_mt[0] = mp, native_mt[1] = mb;
    } else if (native_all[0] > 0 && ci < 16) {
      for (int k = 0; k < 4; k++) g_cfg_log[ci][k] += log(all[k] / native_all[k]);
      g_cfg_n[ci]++;
      if (mp > 0 && native_mt[0] > 0) {
        g_cfg_log[ci][4] += log(mp / native_mt[0]);
        g_cfg_log[ci][5] += log(mb / native_mt[1]);
        g_cfg_mt_n[ci]++;
      }
    }
    if (strcmp(g_cfgs[ci].label, "custom default (bf2)") == 0 && native_rate[0] > 0) {
      printf("%-24s custom default / native default: primary %.2fx, bounce %.2fx\n", "",
             rp / native_rate[0], rb / native_rate[1]);
      g_log_ratio_sum[0] += log(rp / native_rate[0]);
      g_log_ratio_sum[1] += log(rb / native_rate[1]);
      g_ratio_n++;
    }
    if (mp > 0 && ci > 0 && native_mt[0] > 0)
      printf("%-24s   all threads, / native default: primary %.2fx, bounce %.2fx\n", "",
             mp / native_mt[0], mb / native_mt[1]);
    A->destroy(acc);
    if (strstr(g_cfgs[ci].settings, "backend=custom")) {
      /* Work per ray, from the counters (a separate build: counting slows the kernels). */
      tt_config *cc = tt_config_create(space);
      apply(cc, g_cfgs[ci].settings);
      apply(cc, "counters=true");
      acc = NULL;
      if (A->build(scene, cc, &acc, NULL) == TT_OK) {
        double per[2][2];
        for (int set = 0; set < 2; set++) {
          memcpy(work, set ? bounce : prim, NRAYS * sizeof *work);
          for (size_t i = 0; i < NRAYS; i++) A->intersect1(acc, &work[i], &hits[i]);
          tt_accel_counters cnt = {.struct_size = sizeof cnt};
          CHECK(A->counters(acc, &cnt, 1) == TT_OK && cnt.rays == NRAYS);
          per[set][0] = (double)cnt.nodes_visited / (double)NRAYS;
          per[set][1] = (double)cnt.triangles_tested / (double)NRAYS;
        }
        printf("%-24s   per ray: primary %.1f nodes %.1f triangles, bounce %.1f nodes %.1f "
               "triangles\n",
               "", per[0][0], per[0][1], per[1][0], per[1][1]);
        for (int set = 0; set < 2; set++) {
          const tt_ray *rs = set ? bounce : prim;
          for (size_t i = 0; i < NRAYS; i++) occ[i] = (uint8_t)A->occluded1(acc, &rs[i]);
          tt_accel_counters cnt = {.struct_size = sizeof cnt};
          CHECK(A->counters(acc, &cnt, 1) == TT_OK && cnt.rays == NRAYS);
          per[set][0] = (double)cnt.nodes_visited / (double)NRAYS;
          per[set][1] = (double)cnt.triangles_tested / (double)NRAYS;
        }
        printf("%-24s   per occlusion ray: primary %.1f nodes %.1f triangles, bounce %.1f nodes "
               "%.1f triangles\n",
               "", per[0][0], per[0][1], per[1][0], per[1][1]);
        A->destroy(acc);
      }
      tt_config_destroy(cc);
    }
  }
  free(prim), free(bounce), free(work), free(hits), free(ref_hits), free(occ);
}

int main(int argc, char **argv) {
  int runs = argc > 1 ? atoi(argv[1]) : 5;
  const char *only = argc > 2 ? argv[2] : NULL; /* scene-name filter, for quick looks */
  g_cfg_filter = argc > 3 ? argv[3] : NULL;
  if (runs < 1 || runs > 16) runs = 5;
  long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
  g_threads = ncpu < 1 ? 1 : ncpu > 64 ? 64 : (int)ncpu;
  const char *tenv = getenv("TT_BENCH_THREADS");
  if (tenv && atoi(tenv) >= 1 && atoi(tenv) <= 64) g_threads = atoi(tenv);
  ae_plugin pl = ae_load(NULL);
  const tt_accel_iface *A = pl.accel;
  const char *root = getenv("TT_SOURCE_ROOT");
  char path[4096];

  printf("accel_embree bench: single-thread Mrays/s (intersect1 / occluded1, per CPU second "
         "of the tracing thread), build ms (wall, Embree's thread pool); medians of %d\n",
         runs);
  printf("all-threads rows: intersect1 on %d threads (pthreads, chunks of %d rays), Mrays/s "
         "per WALL second (shared machine: other load counts against them), medians of %d\n",
         g_threads, MT_CHUNK, runs);
  snprintf(path, sizeof path, "%s/scenes/cornell-box/scene.json", root ? root : ".");
  tt_scene *s = NULL;
  if (only && !strstr("Cornell box", only)) {
  } else if (tt_scene_load(path, &s) == TT_OK) {
    bench_scene(A, "Cornell box", s, runs);
    tt_scene_destroy(s);
  } else {
    printf("note: %s: %s (skipped)\n", path, tt_last_error());
  }
  if (!only || strstr("bumpy sphere", only)) {
    s = bumpy_sphere(500, 500);
    bench_scene(A, "bumpy sphere (procedural)", s, runs);
    tt_scene_destroy(s);
  }
  const char *shared = getenv("TT_SHARED_SCENES");
  char sdir[4000];
  snprintf(sdir, sizeof sdir, "%s", shared ? shared : "");
  if (!shared) snprintf(sdir, sizeof sdir, "%s/../shared/scenes", root ? root : ".");
  static const char *const objs[][2] = {
      {"Stanford bunny", "stanford-bunny/stanford-bunny.obj"},
      {"voxel monument", "voxel-monument/monu3.obj"},
  };
  for (size_t i = 0; i < sizeof objs / sizeof objs[0]; i++) {
    if (only && !strstr(objs[i][0], only)) continue;
    snprintf(path, sizeof path, "%s/%s", sdir, objs[i][1]);
    s = obj_scene(path);
    if (!s) {
      printf("note: %s not available: skipped\n", path);
      continue;
    }
    bench_scene(A, objs[i][0], s, runs);
    tt_scene_destroy(s);
  }
  static const char *const pbrts[][2] = {
      {"living room (pbrt)", "living-room/living-room.pbrt"},
      {"BMW M6 (pbrt)", "bmw-m6/bmw-m6.pbrt"},
      {"staircase (pbrt)", "staircase/staircase.pbrt"},
  };
  for (size_t i = 0; i < sizeof pbrts / sizeof pbrts[0]; i++) {
    if (only && !strstr(pbrts[i][0], only)) continue;
    snprintf(path, sizeof path, "%s/%s", sdir, pbrts[i][1]);
    s = pbrt_scene(path);
    if (!s) {
      printf("note: %s not available: skipped\n", path);
      continue;
    }
    bench_scene(A, pbrts[i][0], s, runs);
    tt_scene_destroy(s);
  }
  if (g_ratio_n)
    printf("\ncustom default / native default, geometric mean over %d scenes: primary %.2fx, "
           "bounce %.2fx\n",
           g_ratio_n, exp(g_log_ratio_sum[0] / g_ratio_n), exp(g_log_ratio_sum[1] / g_ratio_n));
  for (size_t ci = 1; ci < NCFG && ci < 16; ci++)
    if (!strcmp(g_cfgs[ci].label, "custom default (bf2)") && g_cfg_mt_n[ci])
      printf("custom default / native default, all %d threads (wall), geometric mean over %d "
             "scenes: primary %.2fx, bounce %.2fx\n",
             g_threads, g_cfg_mt_n[ci], exp(g_cfg_log[ci][4] / g_cfg_mt_n[ci]),
             exp(g_cfg_log[ci][5] / g_cfg_mt_n[ci]));
  printf("\nratios to native default, geometric means over the scenes measured (all threads: "
         "wall time, %d threads)\n",
         g_threads);
  printf("%-24s %7s %7s %7s %7s | %8s %8s\n", "configuration", "prim", "bounce", "occl-p", "occl-b",
         "all-prim", "all-bnc");
  for (size_t ci = 1; ci < NCFG && ci < 16; ci++) {
    if (!g_cfg_n[ci]) continue;
    double n = g_cfg_n[ci];
    printf("%-24s %6.2fx %6.2fx %6.2fx %6.2fx |", g_cfgs[ci].label, exp(g_cfg_log[ci][0] / n),
           exp(g_cfg_log[ci][1] / n), exp(g_cfg_log[ci][2] / n), exp(g_cfg_log[ci][3] / n));
    printf(" streams %5.2fx %5.2fx %5.2fx %5.2fx |", exp(g_cfg_slog[ci][0] / n),
           exp(g_cfg_slog[ci][1] / n), exp(g_cfg_slog[ci][2] / n), exp(g_cfg_slog[ci][3] / n));
    if (g_cfg_mt_n[ci])
      printf(" %7.2fx %7.2fx", exp(g_cfg_log[ci][4] / g_cfg_mt_n[ci]),
             exp(g_cfg_log[ci][5] / g_cfg_mt_n[ci]));
    printf("%s\n", g_cfg_n[ci] < g_scene_n ? "  (not on every scene)" : "");
  }
  tt_registry_destroy(pl.reg);
  return tt_test_finish("accel_embree_bench");
}
