/* Benchmark (suite 'bench', prints figures): albedo textures loaded directly (bilinear
 * lookups into a linear float array, the default) against OpenImageIO's TextureSystem
 * (TT_TEXTURES=oiio: shared cache, automip, bilinear) on a textured Cornell box: the
 * original scene with every wall and block textured by a 1024^2 sRGB PNG repeated every
 * 100 mm. Same paths (same seed) in both modes through accel_embree (the brute-force accel
 * if it cannot be loaded), one thread, timed in process CPU seconds (the machine may be
 * shared); prints samples per CPU second, the cost difference per sample, and the two
 * images' means (which must agree: both read the same texels).
 *   meson test -C build-pt --suite bench path_texture_bench -v
 * Optional argument: the directory to leave textured.json and its texture in (for host runs). */
#include <cjson/cJSON.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include <tunetrace/host.h>
#include <tunetrace/image.h>
#include <tunetrace/loader.h>

#include <tunetrace/camera.h>

#include <tt_util/clock.h>

#include "path_common.h"
#include "tt_test.h"

/* CPU seconds of this process (single-threaded rendering; steadier than wall time on a
 * busy machine). */
static double now_s(void) { return tt__process_cpu_ms() * 1e-3; }

/* Writes a 1024^2 colourful noise-over-checker PNG (display-encoded, i.e. sRGB). */
static int write_texture(const char *path) {
  const uint32_t n = 1024;
  float *px = malloc(sizeof(float) * 3 * n * n);
  if (!px) return 0;
  uint32_t s = 12345;
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      s = s * 1664525u + 1013904223u;
      float chk = ((x / 64 + y / 64) & 1) ? 0.8f : 0.3f, noise = (float)(s >> 8) / 16777216.0f;
      px[3 * (y * n + x) + 0] = chk * (0.7f + 0.3f * noise);
      px[3 * (y * n + x) + 1] = chk * (float)x / n;
      px[3 * (y * n + x) + 2] = chk * (float)y / n;
    }
  tt_status st = tt_image_write_png_display(path, n, n, px, 0.0f, NULL, 0);
  free(px);
  return st == TT_OK;
}

/* The Cornell box with uvs (the two largest extents of each mesh / 100 mm) and textured
 * diffuse materials; returns malloc'd JSON. */
static char *textured_cornell(const char *scene_path, const char *texture) {
  char *src = tt_test_read_file(scene_path, NULL);
  cJSON *root = src ? cJSON_Parse(src) : NULL;
  free(src);
  if (!root) return NULL;
  cJSON *mats = cJSON_GetObjectItem(root, "materials"), *m;
  cJSON_ArrayForEach(m, mats) {
    if (!cJSON_GetObjectItem(m, "emission")) cJSON_AddStringToObject(m, "texture", texture);
  }
  cJSON *mesh;
  cJSON_ArrayForEach(mesh, cJSON_GetObjectItem(root, "meshes")) {
    cJSON *pos = cJSON_GetObjectItem(mesh, "positions"), *p;
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    cJSON_ArrayForEach(p, pos) for (int i = 0; i < 3; ++i) {
      float v = (float)cJSON_GetArrayItem(p, i)->valuedouble;
      lo[i] = fminf(lo[i], v);
      hi[i] = fmaxf(hi[i], v);
    }
    int small = 0; /* drop the axis of least extent */
    for (int i = 1; i < 3; ++i)
      if (hi[i] - lo[i] < hi[small] - lo[small]) small = i;
    int a = (small + 1) % 3, b = (small + 2) % 3;
    cJSON *uvs = cJSON_AddArrayToObject(mesh, "uvs");
    cJSON_ArrayForEach(p, pos) {
      cJSON_AddItemToArray(uvs, cJSON_CreateNumber(cJSON_GetArrayItem(p, a)->valuedouble / 100.0));
      cJSON_AddItemToArray(uvs, cJSON_CreateNumber(cJSON_GetArrayItem(p, b)->valuedouble / 100.0));
    }
  }
  char *out = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  return out;
}

/* Renders `spp` samples per pixel of the scene's camera at 128^2; returns samples/s and
 * the mean radiance (green channel) in *mean. */
static double render(const pt_fixture *f, uint32_t spp, double *mean) {
  const uint32_t w = 128, h = 128;
  tt_camera cam = *tt_scene_camera(f->scene);
  cam.width = w;
  cam.height = h;
  tt_camera_frame cs;
  if (tt_camera_frame_init(&cs, &cam) != TT_OK) return 0.0;
  pt_sampler_src src;
  memset(&src, 0, sizeof src);
  src.iface = tt_builtin_sampler("independent");
  src.iface->create(NULL, 1, &src.sampler);
  tt_sample_source source = {pt_src_get, NULL, &src};
  tt_path_options o;
  tt_path_options_default(&o);
  double sum = 0.0, t0 = now_s();
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      for (uint32_t i = 0; i < spp; ++i) {
        src.iface->start(src.sampler, src.state, x, y, i);
        float fx = (float)x + src.iface->get(src.sampler, src.state, 0);
        float fy = (float)y + src.iface->get(src.sampler, src.state, 1);
        tt_ray ray;
        tt_camera_generate_ray(&cs, fx, fy, &ray);
        tt_path_result r;
        tt_path_trace(f->pt, &f->tracer, &o, &ray, &source, &r);
        sum += r.L[1];
      }
  double secs = now_s() - t0;
  src.iface->destroy(src.sampler);
  *mean = sum / ((double)w * h * spp);
  return (double)w * h * spp / secs;
}

int main(int argc, char **argv) {
  const char *root = getenv("TT_SOURCE_ROOT");
  char scene_path[4096], dir[] = "/tmp/tt_texbench_XXXXXX", tex[4200], json_path[4200];
  snprintf(scene_path, sizeof scene_path, "%s/scenes/cornell-box/scene.json", root ? root : ".");
  const char *outdir = argc > 1 ? argv[1] : NULL;
  if (!outdir && !mkdtemp(dir)) TEST_FAIL("cannot create a temporary folder in /tmp");
  if (!outdir) outdir = dir;
  snprintf(tex, sizeof tex, "%s/texture.png", outdir);
  snprintf(json_path, sizeof json_path, "%s/textured.json", outdir);
  CHECK(write_texture(tex));
  char *json = textured_cornell(scene_path, tex);
  CHECK(json != NULL);
  if (!json) return tt_test_finish("path_texture_bench");
  FILE *jf = fopen(json_path, "w");
  if (jf) {
    fputs(json, jf);
    fclose(jf);
  }

  /* accel_embree through the loader, so that traversal does not dilute texture costs. */
  const tt_accel_iface *embree = NULL;
  tt_registry *reg = NULL;
  const char *pdir = getenv("TT_PLUGIN_PATH");
  if (pdir) {
    char ppath[4096];
    snprintf(ppath, sizeof ppath, "%s/accel_embree/accel_embree.so", pdir);
    reg = tt_registry_create(tt_default_host());
    tt_loaded_plugin *lp = NULL;
    if (reg && tt_registry_load(reg, ppath, &lp) == TT_OK && lp)
      embree = tt_loaded_plugin_iface(lp);
  }
  const char *modes[2] = {"direct", "oiio"};
  double sps[2] = {0, 0}, mean[2] = {0, 0};
  const uint32_t spp = 16;
  for (int rep = 0; rep < 2; ++rep) /* twice, alternating, against a busy machine */
    for (int m = 0; m < 2; ++m) {
      setenv("TT_TEXTURES", modes[m], 1);
      pt_fixture f;
      CHECK(pt_fixture_load(&f, json));
      if (!f.pt) continue;
      tt_accel *ea = NULL;
      if (embree && embree->build(f.scene, NULL, &ea, NULL) == TT_OK) {
        f.tracer.iface = embree;
        f.tracer.accel = ea;
      }
      double mu = 0.0, s = render(&f, spp, &mu);
      if (s > sps[m]) sps[m] = s; /* best of the two */
      mean[m] = mu;
      if (ea) {
        embree->destroy(ea);
        f.tracer.iface = tt_test_brute_accel();
        f.tracer.accel = f.accel;
      }
      pt_fixture_free(&f);
    }
  if (reg) tt_registry_destroy(reg);
  unsetenv("TT_TEXTURES");
  /* Lookups per sample: one per textured hit, at most maxDepth + 1 = 4 (every surface but
   * the light is textured); the cost difference per sample bounds the per-lookup cost. */
  double per_sample_ns = (1.0 / sps[1] - 1.0 / sps[0]) * 1e9;
  printf("textured Cornell box, 128x128, %u spp, maxDepth 3, 1 thread, %s accel, per CPU second:\n",
         spp, embree ? "embree" : "brute-force");
  printf("  direct loading : %9.0f samples/s  mean G %.5f\n", sps[0], mean[0]);
  printf("  OIIO texsys    : %9.0f samples/s  mean G %.5f\n", sps[1], mean[1]);
  printf("  OIIO / direct  : %.3fx  (+%.0f ns per sample)\n", sps[1] / sps[0], per_sample_ns);
  /* Both modes must render the same picture (bilinear of the same texels; OIIO filters the
   * sRGB-encoded values, direct the decoded ones, hence a loose tolerance). */
  CHECK_MSG(fabs(mean[1] - mean[0]) <= 0.02 * mean[0], "means differ: %.5f vs %.5f", mean[0],
            mean[1]);
  free(json);
  if (outdir == dir) {
    unlink(tex);
    unlink(json_path);
    rmdir(dir);
  }
  return tt_test_finish("path_texture_bench");
}
