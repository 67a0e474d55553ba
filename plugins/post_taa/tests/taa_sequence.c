/* host --sequence end to end: a camera sliding sideways at constant speed in front of a
 * plane gives motion vectors of exactly speed * focal / distance pixels (and depth =
 * distance = the prevdepth AOV, the depth in the previous camera); a camera moving
 * straight at the plane gives prevdepth = depth + the distance moved per frame; the manifest walks the Halton jitter cycle; the reference and the post_taa
 * output are written; bad options are usage errors. The frame-pattern interface
 * (--frames A:B --out DIR/frame_%04d.exr --aov, --supersample K, --plugin post_taa,
 * post_taa.weights=FILE) writes exactly the same pixels as --sequence. */
#include "tt_test.h"

#include "host_util.h"

#include <tunetrace/camera.h>
#include <tunetrace/image.h>

#include <unistd.h>

/* A wall at z = 0 seen from z = 5; keys every second, 2.4 units apart (constant velocity
 * through the middle segments). */
static const char *k_scene =
    "{\"version\": 1,\n"
    " \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0], \"fov\": 45,\n"
    "   \"resolution\": [64, 48], \"path\": [\n"
    "   {\"time\": 0, \"position\": [0, 0, 5], \"target\": [0, 0, 0]},\n"
    "   {\"time\": 1, \"position\": [2.4, 0, 5], \"target\": [2.4, 0, 0]},\n"
    "   {\"time\": 2, \"position\": [4.8, 0, 5], \"target\": [4.8, 0, 0]},\n"
    "   {\"time\": 3, \"position\": [7.2, 0, 5], \"target\": [7.2, 0, 0]}]},\n"
    " \"render\": {\"spp\": 1, \"maxDepth\": 1},\n"
    " \"materials\": {\"w\": {\"albedo\": 0.6}, \"b\": {\"albedo\": 0.05}},\n"
    " \"meshes\": [\n"
    "  {\"material\": \"w\", \"positions\": [[-50, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, "
    "0]],\n"
    "   \"indices\": [[0, 1, 2], [0, 2, 3]]},\n"
    "  {\"material\": \"b\", \"positions\": [[0, -0.3, 0.01], [0.05, -0.3, 0.01], [0.6, 0.4, "
    "0.01]]}],\n"
    " \"lights\": [{\"type\": \"distant\", \"direction\": [0, 0, -1], \"irradiance\": 2}]}\n";

/* The same wall approached head-on: z from 5 to 4 in one second. */
static const char *k_dolly =
    "{\"version\": 1,\n"
    " \"camera\": {\"position\": [0, 0, 5], \"target\": [0, 0, 0], \"fov\": 45,\n"
    "   \"resolution\": [32, 24], \"path\": [\n"
    "   {\"time\": 0, \"position\": [0, 0, 5], \"target\": [0, 0, 0]},\n"
    "   {\"time\": 1, \"position\": [0, 0, 4], \"target\": [0, 0, -1]}]},\n"
    " \"render\": {\"spp\": 1, \"maxDepth\": 1},\n"
    " \"materials\": {\"w\": {\"albedo\": 0.6}},\n"
    " \"meshes\": [\n"
    "  {\"material\": \"w\", \"positions\": [[-50, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, "
    "0]],\n"
    "   \"indices\": [[0, 1, 2], [0, 2, 3]]}],\n"
    " \"lights\": [{\"type\": \"distant\", \"direction\": [0, 0, -1], \"irradiance\": 2}]}\n";

/* Largest |a - b| over two EXRs of the same shape; -1 if either is unreadable or the
 * shapes differ. */
static double image_diff(const char *a, const char *b) {
  uint32_t w1, h1, c1, w2, h2, c2;
  float *p1 = NULL, *p2 = NULL;
  double worst = -1;
  if (tt_image_read(a, &w1, &h1, &c1, &p1) == TT_OK &&
      tt_image_read(b, &w2, &h2, &c2, &p2) == TT_OK && w1 == w2 && h1 == h2 && c1 == c2) {
    worst = 0;
    for (size_t i = 0; i < (size_t)w1 * h1 * c1; i++) worst = fmax(worst, fabs(p1[i] - p2[i]));
  }
  tt_free(p1);
  tt_free(p2);
  return worst;
}

/* Largest |prevdepth - depth - offset| of frame `f` of the --out-dir sequence in `dir`, or
 * -1 when a file is missing or the shapes differ. */
static double prev_depth_offset_error(const char *dir, int f, double offset) {
  char a[512], b[512];
  snprintf(a, sizeof a, "%s/depth_%04d.exr", dir, f);
  snprintf(b, sizeof b, "%s/prevdepth_%04d.exr", dir, f);
  uint32_t w1, h1, c1, w2, h2, c2;
  float *d = NULL, *p = NULL;
  double worst = -1;
  if (tt_image_read(a, &w1, &h1, &c1, &d) == TT_OK &&
      tt_image_read(b, &w2, &h2, &c2, &p) == TT_OK && w1 == w2 && h1 == h2 && c1 == 1 && c2 == 1) {
    worst = 0;
    for (size_t i = 0; i < (size_t)w1 * h1; i++) worst = fmax(worst, fabs(p[i] - d[i] - offset));
  }
  tt_free(d);
  tt_free(p);
  return worst;
}

/* Checks that DIR_A/A and DIR_B/B hold the same pixels. */
static void check_same(const char *dir_a, const char *a, const char *dir_b, const char *b) {
  char pa[512], pb[512];
  snprintf(pa, sizeof pa, "%s/%s", dir_a, a);
  snprintf(pb, sizeof pb, "%s/%s", dir_b, b);
  double d = image_diff(pa, pb);
  CHECK_MSG(d == 0, "%s vs %s: difference %g", pa, pb, d);
}

/* The frame-pattern interface against the --sequence output in `seq` (frames 24..33). */
static void check_pattern_interface(const char *dir, const char *seq, const char *scene) {
  char args[2048], log[16384], a[512], b[512];
  /* rendered frames + AOVs */
  snprintf(args, sizeof args,
           "--quiet --threads 2 --frames 24:27 --out '%s/i/frame_%%04d.exr' "
           "--aov depth,motion,prevdepth --set integrator_pt.maxDepth=1 '%s'",
           dir, scene);
  int rc = run_host(args, log, sizeof log);
  CHECK_MSG(rc == 0, "host exited %d: %s", rc, log);
  snprintf(a, sizeof a, "%s/i", dir);
  check_same(a, "frame_0026.exr", seq, "color_0026.exr");
  check_same(a, "frame_0026.depth.exr", seq, "depth_0026.exr");
  check_same(a, "frame_0026.motion.exr", seq, "motion_0026.exr");
  check_same(a, "frame_0026.prevdepth.exr", seq, "prevdepth_0026.exr");
  snprintf(a, sizeof a, "%s/i/frame_0027.raw.exr", dir);
  CHECK_MSG(access(a, F_OK) != 0, "%s written without a post-filter", a);
  snprintf(a, sizeof a, "%s/i/manifest.json", dir);
  char *man = tt_test_read_file(a, NULL);
  CHECK(man && strstr(man, "\"color\": \"frame_0025.exr\", \"depth\": \"frame_0025.depth.exr\""));
  free(man);

  /* --supersample: the frames are the Blackman-Harris-downsampled reference */
  snprintf(args, sizeof args,
           "--quiet --threads 2 --frames 24:25 --out '%s/r/ref_%%d.exr' "
           "--supersample 2 --set integrator_pt.maxDepth=1 '%s'",
           dir, scene);
  rc = run_host(args, log, sizeof log);
  CHECK_MSG(rc == 0, "host exited %d: %s", rc, log);
  snprintf(a, sizeof a, "%s/r", dir);
  check_same(a, "ref_25.exr", seq, "reference_0025.exr");
  snprintf(a, sizeof a, "%s/r/ref_25.depth.exr", dir);
  CHECK_MSG(access(a, F_OK) != 0, "%s written without --aov", a);

  /* --plugin post_taa: the frame is the filtered one, the rendered frame beside it */
  snprintf(args, sizeof args,
           "--quiet --threads 2 --frames 24:27 --out '%s/p/f%%03d.exr' "
           "--plugin post_taa --set integrator_pt.maxDepth=1 '%s'",
           dir, scene);
  rc = run_host(args, log, sizeof log);
  CHECK_MSG(rc == 0, "host exited %d: %s", rc, log);
  snprintf(a, sizeof a, "%s/p", dir);
  check_same(a, "f027.exr", seq, "post_0027.exr");
  check_same(a, "f027.raw.exr", seq, "color_0027.exr");

  /* post_taa.weights=FILE (an option, not a tuned parameter) == the shipped 6-channel model,
   * which is the default network (no channels set: the validation rule chose it) */
  snprintf(args, sizeof args,
           "--quiet --threads 2 --frames 24:27 --out '%s/w6/f%%03d.exr' "
           "--plugin post_taa --set post_taa.mode=network "
           "--set integrator_pt.maxDepth=1 '%s'",
           dir, scene);
  CHECK(run_host(args, log, sizeof log) == 0);
  snprintf(args, sizeof args,
           "--quiet --threads 2 --frames 24:27 --out '%s/wf/f%%03d.exr' "
           "--plugin post_taa --set post_taa.mode=network --set 'post_taa.weights=%s' "
           "--set integrator_pt.maxDepth=1 '%s'",
           dir, source_path("plugins/post_taa/post_taa_c6.ttw"), scene);
  rc = run_host(args, log, sizeof log);
  CHECK_MSG(rc == 0, "host exited %d: %s", rc, log);
  snprintf(a, sizeof a, "%s/w6", dir);
  snprintf(b, sizeof b, "%s/wf", dir);
  check_same(a, "f027.exr", b, "f027.exr"); /* weights=post_taa_c6.ttw == the default */
  /* channels=12 picks the other shipped file: its pixels differ from the default's */
  snprintf(args, sizeof args,
           "--quiet --threads 2 --frames 24:27 --out '%s/w12/f%%03d.exr' "
           "--plugin post_taa --set post_taa.mode=network --set post_taa.channels=12 "
           "--set integrator_pt.maxDepth=1 '%s'",
           dir, scene);
  rc = run_host(args, log, sizeof log);
  CHECK_MSG(rc == 0, "host exited %d: %s", rc, log);
  snprintf(a, sizeof a, "%s/w6/f027.exr", dir);
  snprintf(b, sizeof b, "%s/w12/f027.exr", dir);
  CHECK_MSG(image_diff(a, b) > 1e-4, "channels=12 renders the default (6-channel) network");
  snprintf(a, sizeof a, "%s/w6/f027.exr", dir);
  snprintf(b, sizeof b, "%s/post_0027.exr", seq); /* VCTAA: the network must differ */
  CHECK(image_diff(a, b) > 1e-4);
  snprintf(args, sizeof args,
           "--frames 0:1 --out '%s/x/f%%d.exr' --plugin post_taa "
           "--set post_taa.mode=network --set post_taa.weights=%s/none.ttw '%s'",
           dir, dir, scene);
  CHECK(run_host(args, log, sizeof log) == 1);
  CHECK_CONTAINS(log, "none.ttw");
  /* a directory as the weights file: refused by name (it asked for ~LONG_MAX bytes, #13) */
  snprintf(args, sizeof args,
           "--frames 0:1 --out '%s/x/f%%d.exr' --plugin post_taa "
           "--set post_taa.mode=network --set 'post_taa.weights=%s' '%s'",
           dir, dir, scene);
  CHECK(run_host(args, log, sizeof log) == 1);
  CHECK_CONTAINS(log, "cannot open weights file: a directory, not a regular file");

  /* usage errors name the option */
  snprintf(args, sizeof args, "--frames 3:1 --out '%s/x/f%%d.exr' '%s'", dir, scene);
  CHECK(run_host(args, log, sizeof log) == 2);
  CHECK_CONTAINS(log, "--frames");
  snprintf(args, sizeof args, "--frames 0:1 --out '%s/x/f%%d_%%d.exr' '%s'", dir, scene);
  CHECK(run_host(args, log, sizeof log) == 2);
  CHECK_CONTAINS(log, "exactly one");
  snprintf(args, sizeof args, "--frames 0:1 --out '%s/x/f%%d.exr' --aov depth,shadow '%s'", dir,
           scene);
  CHECK(run_host(args, log, sizeof log) == 2);
  CHECK_CONTAINS(log, "shadow");
  CHECK_CONTAINS(log, "prevdepth");
  snprintf(args, sizeof args, "--out '%s/x/f%%d.exr' '%s'", dir, scene);
  CHECK(run_host(args, log, sizeof log) == 2);
  CHECK_CONTAINS(log, "--frames A:B");
  snprintf(args, sizeof args,
           "--frames 0:1 --out '%s/x/f%%d.exr' --plugin post_taa "
           "--set post_taa.weight=x '%s'",
           dir, scene);
  CHECK(run_host(args, log, sizeof log) == 2);
  CHECK_CONTAINS(log, "weight");
}

int main(void) {
  char dir[] = "/tmp/taa_sequence_XXXXXX";
  if (!mkdtemp(dir)) TEST_FAIL("cannot create a temporary folder in /tmp");
  char scene[256], out[256], args[1024], log[16384], path[512];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  snprintf(out, sizeof out, "%s/seq", dir);
  FILE *f = fopen(scene, "w");
  fputs(k_scene, f);
  fclose(f);

  /* Frames 24..33 lie in the constant-speed segment: 0.1 units per frame. */
  snprintf(args, sizeof args,
           "--quiet --threads 2 --sequence 24:33 --out-dir '%s' "
           "--reference-scale 2 --set integrator_pt.maxDepth=1 --post post_taa '%s'",
           out, scene);
  int rc = run_host(args, log, sizeof log);
  CHECK_MSG(rc == 0, "host exited %d: %s", rc, log);

  /* Motion of the wall: the previous camera was 0.1 to the left, so points sat further
   * right: +0.1 * focal / 5 pixels in x, 0 in y. */
  double focal = 24.0 / tan(22.5 * M_PI / 180.0);
  double want = 0.1 * focal / 5.0;
  uint32_t w, h, c;
  float *px = NULL;
  snprintf(path, sizeof path, "%s/motion_0027.exr", out);
  CHECK_MSG(tt_image_read(path, &w, &h, &c, &px) == TT_OK, "%s", tt_last_error());
  if (px) {
    CHECK(w == 64 && h == 48 && c == 2);
    double worst = 0;
    for (size_t i = 0; i < (size_t)w * h; i++) {
      worst = fmax(worst, fabs(px[2 * i] - want));
      worst = fmax(worst, fabs(px[2 * i + 1]));
    }
    printf("motion: expected (%.4f, 0) px, worst deviation %.2e\n", want, worst);
    CHECK(worst < 5e-3);
    tt_free(px);
    px = NULL;
  }
  snprintf(path, sizeof path, "%s/depth_0027.exr", out);
  CHECK(tt_image_read(path, &w, &h, &c, &px) == TT_OK);
  if (px) {
    CHECK(c == 1);
    double worst = 0;
    for (size_t i = 0; i < (size_t)w * h; i++) worst = fmax(worst, fabs(px[i] - 5.0));
    CHECK_MSG(worst < 0.02, "depth deviates by %g", worst);
    tt_free(px);
    px = NULL;
  }
  /* Sliding parallel to the wall: every point had the same depth in the previous camera. */
  double slide = prev_depth_offset_error(out, 27, 0.0);
  printf("prevdepth, sideways slide: |prevdepth - depth| <= %.2e\n", slide);
  CHECK_MSG(slide >= 0 && slide < 1e-4, "prevdepth - depth deviates by %g", slide);
  const char *kinds[] = {"color", "reference", "post"};
  for (int k = 0; k < 3; k++) {
    snprintf(path, sizeof path, "%s/%s_0033.exr", out, kinds[k]);
    CHECK_MSG(access(path, R_OK) == 0, "missing %s", path);
  }
  snprintf(path, sizeof path, "%s/manifest.json", out);
  char *man = tt_test_read_file(path, NULL);
  CHECK(man != NULL);
  if (man) {
    CHECK_CONTAINS(man, "\"jitter_cycle\": 8");
    CHECK_CONTAINS(man, "\"post\": \"post_taa\"");
    /* Frame 24 starts the sequence (history reset) with jitter index 0; 29 has index 5. */
    CHECK_CONTAINS(man, "{\"index\": 24, \"time\": 1.000000, \"jitter_index\": 0, "
                        "\"jitter\": [0.000000, -0.166667], \"reset\": true");
    float j5[2];
    tt_jitter_halton23(5, j5);
    char want5[256];
    snprintf(want5, sizeof want5,
             "{\"index\": 29, \"time\": %.6f, \"jitter_index\": 5, "
             "\"jitter\": [%.6f, %.6f], \"reset\": false",
             29 / 24.0, j5[0], j5[1]);
    CHECK_CONTAINS(man, want5);
    free(man);
  }

  check_pattern_interface(dir, out, scene);

  /* Moving straight at the wall by 1/24 per frame: the previous camera saw every point
   * 1/24 further away. */
  char dolly[256], dout[256];
  snprintf(dolly, sizeof dolly, "%s/dolly.json", dir);
  snprintf(dout, sizeof dout, "%s/dolly", dir);
  f = fopen(dolly, "w");
  fputs(k_dolly, f);
  fclose(f);
  snprintf(args, sizeof args,
           "--quiet --threads 2 --sequence 4:6 --out-dir '%s' "
           "--set integrator_pt.maxDepth=1 '%s'",
           dout, dolly);
  rc = run_host(args, log, sizeof log);
  CHECK_MSG(rc == 0, "host exited %d: %s", rc, log);
  double dz = prev_depth_offset_error(dout, 5, 1.0 / 24.0);
  printf("prevdepth, dolly 1/24 per frame: |prevdepth - depth - 1/24| <= %.2e\n", dz);
  CHECK_MSG(dz >= 0 && dz < 1e-4, "prevdepth - depth - 1/24 deviates by %g", dz);

  /* Usage errors name the option. */
  snprintf(args, sizeof args, "--sequence 5:2 --out-dir '%s' '%s'", out, scene);
  CHECK(run_host(args, log, sizeof log) == 2);
  CHECK_CONTAINS(log, "--sequence");
  snprintf(args, sizeof args, "--sequence 3 '%s'", scene);
  CHECK(run_host(args, log, sizeof log) == 2);
  CHECK_CONTAINS(log, "--out-dir");
  snprintf(args, sizeof args, "--sequence 2 --out-dir '%s' --post integrator_pt '%s'", out, scene);
  CHECK(run_host(args, log, sizeof log) == 3);
  CHECK_CONTAINS(log, "not a post-filter");

  snprintf(args, sizeof args, "rm -rf '%s'", dir);
  if (system(args) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return tt_test_finish("taa_sequence");
}
