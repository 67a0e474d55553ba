/* pbrt-v4 importer on the real scenes in ../shared/scenes (skipped when absent): every
 * scene loads, has at least the triangles shared/scenes/README.md counts (PLY/OBJ faces;
 * tessellated spheres/disks, Loop subdivision and repeated PLY references add to them),
 * a light and finite bounds. Prints the import time of each.
 * Then the committed wrappers scenes/<name>/scene.json (which import these files and carry
 * the camera paths): each loads with the pbrt file's geometry (same scene id), has a path
 * whose samples 0, 50 and 99 are finite and distinct, and `host --camera-index` renders
 * those samples at 16x16, 1 spp without NaN and not all black. */
#include <tunetrace/image.h>
#include <tunetrace/scene.h>

#include "host_util.h"
#include "tt_test.h"

#include <sys/stat.h>
#include <time.h>

typedef struct real_scene {
  const char *file;
  uint64_t min_triangles;
} real_scene;

/* README counts per folder; cornell-box-pbrt's 164 is the sum of its variants' inline
 * meshes (checked below), so each variant gets its own inline count. */
static const real_scene k_scenes[] = {
    {"cornell-box-pbrt/cornell-box.pbrt", 32},
    {"cornell-box-pbrt/cornell-box-silver.pbrt", 32},
    {"cornell-box-pbrt/cornell-box-specular.pbrt", 22},
    {"cornell-box-pbrt/cornell-box-environment-map.pbrt", 2},
    {"cornell-box-pbrt/cornell-box-volume.pbrt", 32},
    {"cornell-box-pbrt/cornell-box-specular-volume.pbrt", 22},
    {"cornell-box-pbrt/smallpt.pbrt", 10},
    {"cornell-box-pbrt/volumetric-caustic.pbrt", 12},
    {"veach-mis/veach-mis.pbrt", 12},
    {"veach-mis/veach-mis-colorized.pbrt", 12},
    {"killeroos/killeroo-simple.pbrt", 16660},
    {"killeroos/killeroo-gold.pbrt", 16660},
    {"killeroos/killeroo-coated-gold.pbrt", 16660},
    {"killeroos/killeroo-moving.pbrt", 16660},
    {"caustic-glass/caustic-glass-v4.pbrt", 88066},
    {"veach-ajar/veach-ajar.pbrt", 130592},
    {"living-room/living-room.pbrt", 143163},
    {"staircase/staircase.pbrt", 262661},
    {"bathroom/bathroom.pbrt", 592186},
    {"bmw-m6/bmw-m6.pbrt", 792746},
};

/* scenes/<name>/scene.json -> the pbrt file it wraps (relative to ../shared/scenes). */
typedef struct wrapper {
  const char *name, *pbrt;
} wrapper;

static const wrapper k_wrappers[] = {
    {"veach-mis", "veach-mis/veach-mis.pbrt"},
    {"killeroos", "killeroos/killeroo-simple.pbrt"},
    {"caustic-glass", "caustic-glass/caustic-glass-v4.pbrt"},
    {"living-room", "living-room/living-room.pbrt"},
    {"veach-ajar", "veach-ajar/veach-ajar.pbrt"},
    {"staircase", "staircase/staircase.pbrt"},
    {"bathroom", "bathroom/bathroom.pbrt"},
    {"bmw-m6", "bmw-m6/bmw-m6.pbrt"},
};

/* Pose of path sample i of 100, as host --camera-index computes it. */
static void path_sample(const tt_scene *s, unsigned i, tt_camera *out) {
  const tt_camera *c = tt_scene_camera(s);
  double t0 = c->keys[0].time, t1 = c->keys[c->key_count - 1].time;
  tt_scene_camera_at(s, t0 + (t1 - t0) * i / 99.0, out);
}

static void test_wrappers(const char *root, const char *shared) {
  const char *build = getenv("TT_BUILD_ROOT");
  char tmp[2048];
  snprintf(tmp, sizeof tmp, "%s/pbrt_real_tmp", build ? build : ".");
  mkdir(tmp, 0755);
  for (size_t w = 0; w < sizeof k_wrappers / sizeof k_wrappers[0]; w++) {
    const wrapper *k = &k_wrappers[w];
    char path[2048], pbrt[2048];
    snprintf(path, sizeof path, "%s/scenes/%s/scene.json", root, k->name);
    if (snprintf(pbrt, sizeof pbrt, "%s/%s", shared, k->pbrt) >= (int)sizeof pbrt) continue;
    tt_scene *s = NULL, *p = NULL;
    tt_status st = tt_scene_load(path, &s);
    CHECK_MSG(st == TT_OK && s, "%s: %s", path, tt_last_error());
    if (!s) continue;
    /* the wrapper imports the canonical path (texture paths, hence the id, follow it) */
    char *real = realpath(pbrt, NULL);
    st = tt_scene_load(real ? real : pbrt, &p);
    free(real);
    CHECK_MSG(st == TT_OK && p, "%s: %s", pbrt, tt_last_error());
    if (p) {
      CHECK_MSG(strcmp(tt_scene_id(s), tt_scene_id(p)) == 0, "%s: scene id differs from %s",
                k->name, k->pbrt);
      CHECK(tt_scene_triangle_count(s) == tt_scene_triangle_count(p));
      CHECK(tt_scene_light_count(s) == tt_scene_light_count(p));
    }
    const tt_camera *c = tt_scene_camera(s);
    CHECK_MSG(c->key_count >= 4, "%s: %u path keys", k->name, c->key_count);
    CHECK_MSG(tt_scene_settings(s)->max_depth <= 64, "%s: maxDepth %u above integrator_pt's 64",
              k->name, tt_scene_settings(s)->max_depth);
    if (c->key_count >= 2) {
      static const unsigned idx[3] = {0, 50, 99};
      tt_camera cam[3];
      for (int i = 0; i < 3; i++) {
        path_sample(s, idx[i], &cam[i]);
        for (int a = 0; a < 3; a++)
          CHECK_MSG(isfinite(cam[i].position[a]) && isfinite(cam[i].target[a]) &&
                        isfinite(cam[i].up[a]),
                    "%s: sample %u not finite", k->name, idx[i]);
        CHECK(cam[i].fov_y > 0 && cam[i].fov_y < 180);
      }
      /* three different places: the paths are not closed loops */
      for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++) {
          double dp = 0;
          for (int a = 0; a < 3; a++) dp += fabs((double)cam[i].position[a] - cam[j].position[a]);
          CHECK_MSG(dp > 0, "%s: samples %u and %u at the same position", k->name, idx[i], idx[j]);
        }
      for (int i = 0; i < 3; i++) {
        char out[2300], args[4000], log[4096];
        snprintf(out, sizeof out, "%s/%s_%u.exr", tmp, k->name, idx[i]);
        if (snprintf(args, sizeof args,
                     "--quiet --camera-index %u --res 16x16 --spp 1 --threads 2 --out '%s' '%s'",
                     idx[i], out, path) >= 3000) {
          CHECK_MSG(0, "%s: paths too long", k->name);
          continue;
        }
        int rc = run_host(args, log, sizeof log);
        CHECK_MSG(rc == 0, "%s: host %s: exit %d\n%s", k->name, args, rc, log);
        uint32_t iw = 0, ih = 0, ch = 0;
        float *px = NULL;
        if (rc != 0 || tt_image_read(out, &iw, &ih, &ch, &px) != TT_OK) {
          CHECK_MSG(0, "%s: cannot read %s: %s", k->name, out, tt_last_error());
          continue;
        }
        double sum = 0;
        size_t bad = 0;
        for (size_t q = 0; q < (size_t)iw * ih; q++)
          for (uint32_t a = 0; a < ch && a < 3; a++) {
            float v = px[q * ch + a];
            if (!isfinite(v)) bad++;
            else sum += v;
          }
        printf("%-14s sample %2u: position [%g %g %g], mean %.4g\n", k->name, idx[i],
               cam[i].position[0], cam[i].position[1], cam[i].position[2],
               sum / ((double)iw * ih * 3));
        CHECK(iw == 16 && ih == 16);
        CHECK_MSG(bad == 0, "%s: sample %u: %zu non-finite values", k->name, idx[i], bad);
        CHECK_MSG(sum > 0, "%s: sample %u renders all black", k->name, idx[i]);
        tt_free(px);
      }
    }
    tt_scene_destroy(p);
    tt_scene_destroy(s);
  }
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  char dir[4096];
  snprintf(dir, sizeof dir, "%s/../shared/scenes", root ? root : ".");
  struct stat sb;
  if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode)) TEST_SKIP("%s not found", dir);
  uint64_t cornell_inline = 0;
  for (size_t i = 0; i < sizeof k_scenes / sizeof k_scenes[0]; i++) {
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, k_scenes[i].file);
    if (stat(path, &sb) != 0) {
      CHECK_MSG(0, "%s is missing", path);
      continue;
    }
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    tt_scene *s = NULL;
    tt_status st = tt_scene_load(path, &s);
    clock_gettime(CLOCK_MONOTONIC, &b);
    double ms = (double)(b.tv_sec - a.tv_sec) * 1e3 + (double)(b.tv_nsec - a.tv_nsec) / 1e6;
    CHECK_MSG(st == TT_OK && s, "%s: %s", k_scenes[i].file, tt_last_error());
    if (!s) continue;
    uint64_t tris = tt_scene_triangle_count(s);
    float lo[3], hi[3];
    tt_scene_bounds(s, lo, hi);
    const tt_camera *c = tt_scene_camera(s);
    printf("%-52s %8.1f ms %9llu triangles %5u meshes %3u materials %3u lights %ux%u\n",
           k_scenes[i].file, ms, (unsigned long long)tris, tt_scene_mesh_count(s),
           tt_scene_material_count(s), tt_scene_light_count(s), c->width, c->height);
    CHECK_MSG(tris >= k_scenes[i].min_triangles, "%s: %llu triangles < %llu", k_scenes[i].file,
              (unsigned long long)tris, (unsigned long long)k_scenes[i].min_triangles);
    if (strncmp(k_scenes[i].file, "cornell-box-pbrt/", 17) == 0)
      cornell_inline += k_scenes[i].min_triangles;
    CHECK_MSG(tt_scene_light_count(s) > 0, "%s: no lights", k_scenes[i].file);
    for (int k = 0; k < 3; k++) CHECK(isfinite(lo[k]) && isfinite(hi[k]) && lo[k] <= hi[k]);
    CHECK(c->width > 0 && c->height > 0 && c->fov_y > 0 && c->fov_y < 180);
    for (uint32_t m = 0; m < tt_scene_material_count(s); m++) {
      const tt_material *mt = tt_scene_material(s, m);
      for (int k = 0; k < 3; k++)
        CHECK(isfinite(mt->albedo[k]) && isfinite(mt->eta[k]) && isfinite(mt->emission[k]));
    }
    tt_scene_destroy(s);
  }
  CHECK(cornell_inline == 164);
  test_wrappers(root ? root : ".", dir);
  (void)source_path;
  return tt_test_finish("pbrt_real");
}
