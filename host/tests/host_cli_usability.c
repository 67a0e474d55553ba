/* End to end: the host's command line as a new user meets it (issue #17, defects 5-7, 10-13,
 * 18): "did you mean" for options, plugins and parameters, the unknown-parameter error
 * listing the known ones, --opt=value, the short options in --help, several --describe,
 * every problem reported when the scene is missing too, --quiet keeping warnings, a
 * post-filter refused on a still, the default output named after the scene's folder from
 * inside it, the film allocation message, pbrt's maxdepth 65 clamped to 64, and --frames
 * meaning the frames of the camera path at --fps with or without an --out pattern. */
#include <tunetrace/tunetrace.h>

#include <math.h>
#include <sys/stat.h>
#include <unistd.h>

#include "host_util.h"
#include "tt_test.h"

#if defined(__SANITIZE_ADDRESS__)
#  define TT_TEST_ASAN 1
#elif defined(__has_feature)
#  if __has_feature(address_sanitizer)
#    define TT_TEST_ASAN 1
#  endif
#endif
#ifndef TT_TEST_ASAN
#  define TT_TEST_ASAN 0
#endif

/* Runs `cd DIR && [PREFIX] host ARGS` with stdout+stderr in `out`; returns the exit code. */
static int run_in(const char *dir, const char *prefix, const char *args, char *out, size_t n) {
  char cmd[16384];
  snprintf(cmd, sizeof cmd, "cd '%s' && %s '%s' %s 2>&1", dir, prefix, host_path(), args);
  FILE *p = popen(cmd, "r");
  if (!p) return -1;
  size_t len = 0, r;
  out[0] = 0;
  while (len + 1 < n && (r = fread(out + len, 1, n - 1 - len, p)) > 0) len += r;
  out[len] = 0;
  int status = pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/* Number of (non-overlapping) occurrences of `needle` in `s`. */
static int count_of(const char *s, const char *needle) {
  int k = 0;
  for (const char *p = s; (p = strstr(p, needle)); p += strlen(needle)) k++;
  return k;
}

/* Mean absolute difference of two RGB EXRs of the same size (-1 if unreadable). */
static double exr_mad(const char *a, const char *b) {
  float *pa = NULL, *pb = NULL;
  uint32_t wa, ha, ca, wb, hb, cb;
  double d = -1;
  if (tt_image_read(a, &wa, &ha, &ca, &pa) == TT_OK &&
      tt_image_read(b, &wb, &hb, &cb, &pb) == TT_OK && wa == wb && ha == hb && ca == cb) {
    size_t n = (size_t)wa * ha * ca;
    d = 0;
    for (size_t i = 0; i < n; i++) d += fabs((double)pa[i] - pb[i]);
    d /= (double)n;
  }
  tt_free(pa);
  tt_free(pb);
  return d;
}

static int exists(const char *path) {
  struct stat st;
  return stat(path, &st) == 0;
}

/* Copies a file (small text files only). */
static int copy_file(const char *from, const char *to) {
  FILE *in = fopen(from, "rb"), *o = fopen(to, "wb");
  int ok = in && o;
  char buf[1 << 14];
  size_t r;
  while (ok && (r = fread(buf, 1, sizeof buf, in)) > 0) ok = fwrite(buf, 1, r, o) == r;
  if (in) fclose(in);
  if (o && fclose(o) != 0) ok = 0;
  return ok;
}

int main(void) {
  static char out[1 << 16];
  char args[16384], path[4400], path2[4400];
  const char *scene = source_path("scenes/cornell-box/scene.json");
  const char *with_path = source_path("scenes/cornell-box/path.json");
  char dir[] = "/tmp/tt_host_usabilityXXXXXX";
  if (!mkdtemp(dir)) return 1;

  /* 11: did you mean, for options, plugins, parameters and plugin names of --set */
  CHECK(run_host("--sp 4 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "unknown option \"--sp\"; did you mean --spp?");
  CHECK(run_host("--tune-sp 4 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "did you mean --tune-spp?");
  CHECK(run_host("--frobnicate x.json", out, sizeof out) == 2);
  CHECK(strstr(out, "did you mean") == NULL);
  /* other renderers' spellings: pbrt-v4's --outfile and --nthreads */
  CHECK(run_host("--outfile a.exr x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "unknown option \"--outfile\"; did you mean --out?");
  CHECK(run_host("--nthreads=2 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "unknown option \"--nthreads\"; did you mean --threads?");
  snprintf(args, sizeof args, "--plugin integrator_ptt --res 4x4 --spp 1 --out %s/a.exr '%s'", dir,
           scene);
  CHECK(run_host(args, out, sizeof out) == 3);
  CHECK_CONTAINS(out, "plugin \"integrator_ptt\" not found (did you mean \"integrator_pt\"?)");
  snprintf(args, sizeof args,
           "--set accel_embree.qualty=2 --set accel_embre.quality=2 "
           "--res 4x4 --spp 1 --out %s/a.exr '%s'",
           dir, scene);
  CHECK(run_host(args, out, sizeof out) == 2);
  /* the unknown-parameter error names the close one and lists the known ones */
  CHECK_CONTAINS(out, "unknown parameter \"qualty\" (did you mean \"quality\"? known: quality, "
                      "branchingFactor, maxDepth,");
  CHECK_CONTAINS(out, "robust, backend, counters, updateMethod, refitInterval, refitSahGrowth)");
  CHECK_CONTAINS(out, "no plugin \"accel_embre\" is loaded (did you mean \"accel_embree\"?");
  /* --opt=value */
  snprintf(args, sizeof args, "--quiet --spp=2 --res=4x4 --out=%s/eq.exr --stats=%s/eq.json '%s'",
           dir, dir, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  snprintf(path, sizeof path, "%s/eq.json", dir);
  char *stats = NULL;
  size_t size = 0;
  FILE *f = fopen(path, "rb");
  if (f) {
    static char buf[1 << 16];
    size = fread(buf, 1, sizeof buf - 1, f);
    buf[size] = 0;
    stats = buf;
    fclose(f);
  }
  CHECK_MSG(stats && strstr(stats, "\"spp\":\t2") && strstr(stats, "\"resolution\":\t[4, 4]"), "%s",
            stats ? stats : "no stats");
  CHECK(run_host("--quiet=yes x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--quiet takes no value");
  /* -o -q -h are in --help */
  CHECK(run_host("-h", out, sizeof out) == 0);
  CHECK_CONTAINS(out, "--out, -o FILE.exr");
  CHECK_CONTAINS(out, "--quiet, -q");
  CHECK_CONTAINS(out, "--help, -h");
  CHECK_CONTAINS(out, "--spp=64");
  /* (#30) --help is short, by task; --help TOPIC and --help-all have the rest, and every
   * option is listed once with one meaning (--aov, --set, --frames were each listed twice) */
  CHECK(run_host("--help", out, sizeof out) == 0);
  CHECK_MSG(count_of(out, "\n") <= 60, "--help is %d lines", count_of(out, "\n"));
  CHECK_CONTAINS(out, "Render:");
  CHECK_CONTAINS(out, "Tune (load a tuner):");
  CHECK_CONTAINS(out, "Hybrid tuning along the camera path:");
  CHECK_CONTAINS(out, "Sequences (frames for temporal filters):");
  CHECK_CONTAINS(out, "--help-all");
  CHECK(!strstr(out, "--tune-pass-images") && !strstr(out, "--indicator-norm"));
  CHECK(run_host("--help-all", out, sizeof out) == 0);
  const char *every[] = {"--aov",
                         "--set",
                         "--frames",
                         "--plugin",
                         "--spp",
                         "--tune-pass-images",
                         "--indicator-norm",
                         "--rounds",
                         "--supersample",
                         "--states",
                         "--clock"};
  for (size_t k = 0; k < sizeof every / sizeof every[0]; k++) {
    char line[64];
    snprintf(line, sizeof line, "\n  %s ", every[k]);
    CHECK_MSG(count_of(out, line) == 1, "--help-all lists %s %d times", every[k],
              count_of(out, line));
  }
  CHECK_CONTAINS(out, "Exit codes: 0 success");
  CHECK_CONTAINS(out, "Environment: TT_PLUGIN_PATH");
  CHECK(run_host("--help tune", out, sizeof out) == 0);
  CHECK_CONTAINS(out, "--tune-params A,B,...");
  CHECK_CONTAINS(out, "Loading a tuner (--plugin tuner_nm) turns tuning on");
  CHECK(!strstr(out, "--sequence"));
  CHECK(run_host("-h=sequence", out, sizeof out) == 2); /* -h takes no '=' */
  CHECK(run_host("--help=sequence", out, sizeof out) == 0);
  CHECK_CONTAINS(out, "--reference-scale K");
  CHECK(run_host("--help sequences", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--help: unknown topic \"sequences\" (did you mean sequence?)");
  CHECK(run_host("--help x.json", out, sizeof out) == 0); /* a scene, not a topic */
  CHECK_CONTAINS(out, "Render:");
  /* (#30) the program's name is the one it was run as (installed: tunetrace), in the usage
   * line and in every message */
  const char *as_tunetrace = "bash -c 'exec -a /usr/local/bin/tunetrace \"$0\" \"$@\"'";
  CHECK(run_in(dir, as_tunetrace, "--help", out, sizeof out) == 0);
  CHECK_CONTAINS(out, "usage: tunetrace [options]");
  CHECK_CONTAINS(out, "Render:  tunetrace --spp 64");
  CHECK(run_in(dir, as_tunetrace, "--frobnicate x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "tunetrace: unknown option \"--frobnicate\"");
  CHECK(run_in(dir, as_tunetrace, "--res 4x4 /nonexistent/scene.json", out, sizeof out) == 4);
  CHECK_CONTAINS(out, "tunetrace: /nonexistent/scene.json");
  CHECK(!strstr(out, "host:"));
  /* several --describe: an array of the spaces, in order */
  CHECK(run_host("--describe integrator_pt --describe accel_embree", out, sizeof out) == 0);
  CHECK(out[0] == '[');
  const char *pt = strstr(out, "\"plugin\":\t\"integrator_pt\"");
  const char *ae = strstr(out, "\"plugin\":\t\"accel_embree\"");
  CHECK_MSG(pt && ae && pt < ae, "%.400s", out);
  CHECK(run_host("--describe accel_embree --describe nothing_here", out, sizeof out) == 3);
  CHECK_CONTAINS(out, "nothing_here");

  /* 12: a missing scene and a missing plugin and a bad --set: all reported, exit 4 */
  CHECK(run_host("--plugin no_such_plugin /nonexistent/scene.json", out, sizeof out) == 4);
  CHECK_CONTAINS(out, "/nonexistent/scene.json");
  CHECK_CONTAINS(out, "no_such_plugin");
  CHECK(run_host("--set accel_embree.qualty=2 /nonexistent/scene.json", out, sizeof out) == 4);
  CHECK_CONTAINS(out, "/nonexistent/scene.json");
  CHECK_CONTAINS(out, "qualty");

  /* 13: --quiet keeps warnings (--camera-index on a scene without a camera path) */
  snprintf(args, sizeof args, "--quiet --camera-index 3 --res 4x4 --spp 1 --out %s/ci.exr '%s'",
           dir, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  CHECK_CONTAINS(out, "warning: --camera-index 3: the scene has no camera path");

  /* 6: a post-filter on a still is a usage error before anything renders */
  snprintf(args, sizeof args, "--plugin post_taa --res 4x4 --spp 1 --out %s/post.exr '%s'", dir,
           scene);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--plugin post_taa: a post-filter runs over the frames of a sequence");
  snprintf(path, sizeof path, "%s/post.exr", dir);
  CHECK(!exists(path));

  /* 10: run from the scene's folder, the output is named after that folder */
  char box[4000];
  snprintf(box, sizeof box, "%s/mybox", dir);
  CHECK(mkdir(box, 0777) == 0);
  snprintf(path, sizeof path, "%s/scene.json", box);
  CHECK(copy_file(scene, path));
  CHECK_MSG(run_in(box, "", "--quiet --res 4x4 --spp 1 scene.json", out, sizeof out) == 0, "%s",
            out);
  snprintf(path, sizeof path, "%s/mybox.exr", box);
  snprintf(path2, sizeof path2, "%s/mybox.png", box);
  CHECK(exists(path) && exists(path2));
  snprintf(path, sizeof path, "%s/..exr", box);
  CHECK(!exists(path));
  CHECK_MSG(run_in(box, "", "--quiet --res 4x4 --spp 1 ./scene.json", out, sizeof out) == 0, "%s",
            out);
  CHECK(!exists(path));

  /* 18: the film that cannot be allocated: its size in bytes, the prefix once (the address
   * space is capped so no machine can allocate the 112 GiB) */
  /* (not in the AddressSanitizer build: its shadow memory needs terabytes of address space,
   * so an instrumented host cannot start under ulimit -v) */
#if !TT_TEST_ASAN
  snprintf(args, sizeof args, "--res 65536x65536 --spp 1 --out %s/big.exr '%s'", dir, scene);
  CHECK(run_in(dir, "ulimit -v 8000000;", args, out, sizeof out) == 1);
  CHECK_CONTAINS(out, "film: cannot allocate a 65536x65536 film: 120259084288 bytes (112.0 GiB");
  CHECK(!strstr(out, "film: film:"));
#endif

  /* 4: a missing output folder is created before the render; one that cannot be (a file
   * in the way) fails at once, exit 5, the path named once, nothing rendered */
  snprintf(args, sizeof args,
           "--quiet --res 4x4 --spp 1 --out %s/new/sub/x.exr --stats "
           "%s/st/x.json '%s'",
           dir, dir, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  snprintf(path, sizeof path, "%s/new/sub/x.png", dir);
  snprintf(path2, sizeof path2, "%s/st/x.json", dir);
  CHECK(exists(path) && exists(path2));
  snprintf(args, sizeof args, "--res 64x64 --spp 64 --out %s/new/sub/x.png/y.exr '%s'", dir, scene);
  CHECK(run_host(args, out, sizeof out) == 5);
  snprintf(path, sizeof path, "%s/new/sub/x.png/y.exr", dir);
  CHECK_MSG(count_of(out, path) == 1 && !strstr(out, "spp, seed") && !strstr(out, "render"), "%s",
            out);
  CHECK_CONTAINS(out, "cannot create the folder");

  /* 7: pbrt's maxdepth 65 is clamped to integrator_pt's 64, with a warning */
  snprintf(path, sizeof path, "%s/deep.pbrt", dir);
  f = fopen(path, "w");
  if (f) {
    fputs("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [45]\n"
          "Film \"rgb\" \"integer xresolution\" [4] \"integer yresolution\" [4]\n"
          "Integrator \"volpath\" \"integer maxdepth\" [65]\nWorldBegin\n"
          "LightSource \"infinite\" \"rgb L\" [1 1 1]\nShape \"sphere\" \"float radius\" [1]\n",
          f);
    fclose(f);
  }
  snprintf(args, sizeof args, "--quiet --spp 1 --out %s/deep.exr --stats %s/deep.json '%s'", dir,
           dir, path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  CHECK_CONTAINS(out, "integrator_pt: the scene asks for maxDepth 65");
  CHECK_CONTAINS(out, "clamped to 64");
  snprintf(path, sizeof path, "%s/deep.json", dir);
  f = fopen(path, "rb");
  static char deep[1 << 16];
  size = f ? fread(deep, 1, sizeof deep - 1, f) : 0;
  deep[size] = 0;
  if (f) fclose(f);
  CHECK_MSG(strstr(deep, "\"maxDepth\":\t64"), "%.2000s", deep);

  /* 5: --frames A:B is frames A..B (both included) at --fps with or without a pattern: frame
   * 30 rendered as a still and as a sequence frame show the same pose */
  snprintf(args, sizeof args,
           "--quiet --threads 2 --res 24x24 --spp 16 --frames 30:31 --out "
           "%s/fr/still.exr '%s'",
           dir, with_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  snprintf(args, sizeof args,
           "--quiet --threads 2 --res 24x24 --spp 16 --frames 30:30 --out "
           "'%s/fr/seq/f%%04d.exr' '%s'",
           dir, with_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  snprintf(args, sizeof args,
           "--quiet --threads 2 --res 24x24 --spp 16 --frames 0:0 --out "
           "%s/fr/first.exr '%s'",
           dir, with_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  char s30[4300], s31[4300], q30[4300], s0[4300];
  snprintf(s30, sizeof s30, "%s/fr/still_0030.exr", dir);
  snprintf(s31, sizeof s31, "%s/fr/still_0031.exr", dir);
  snprintf(q30, sizeof q30, "%s/fr/seq/f0030.exr", dir);
  snprintf(s0, sizeof s0, "%s/fr/first_0000.exr", dir);
  CHECK(exists(s30) && exists(s31) && exists(q30) && exists(s0));
  snprintf(path, sizeof path, "%s/fr/still_0032.exr", dir);
  CHECK(!exists(path));
  double same = exr_mad(s30, q30), other = exr_mad(s30, s0);
  CHECK_MSG(same >= 0 && other > 0 && same < 0.25 * other,
            "frame 30 still vs sequence frame 30: %g; vs frame 0: %g", same, other);
  /* A <= B; one frame is fine */
  snprintf(args, sizeof args, "--frames 5:4 '%s'", with_path);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, "frames A..B of the camera path at --fps, both included");

  snprintf(args, sizeof args, "rm -rf '%s'", dir);
  CHECK(system(args) == 0);
  return tt_test_finish("host_cli_usability");
}
