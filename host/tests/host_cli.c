/* End to end: the host's command line — usage errors, plugin errors, --describe and
 * --list-plugins — each with its exit code and message. */
#include "host_util.h"
#include "tt_test.h"

#include <sys/stat.h>
#include <unistd.h>

int main(void) {
  static char out[1 << 16];
  char args[8192];
  const char *scene = source_path("scenes/cornell-box/scene.json");

  CHECK(run_host("--help", out, sizeof out) == 0);
  CHECK_CONTAINS(out, "--plugin");
  CHECK_CONTAINS(out, "Exit codes");

  CHECK(run_host("--version", out, sizeof out) == 0);
  CHECK_CONTAINS(out, "plugin ABI 1.2");

  CHECK(run_host("--frobnicate", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "unknown option \"--frobnicate\"");

  CHECK(run_host("--spp zero x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--spp: expected an integer");

  CHECK(run_host("--res 64by64 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--res: expected WIDTHxHEIGHT");
  /* numbers wider than 32 bits are refused, not wrapped (--res rendered 8x8 and 8x1, a
   * sequence of 4294967297 frames was one frame) */
  CHECK(run_host("--res 4294967304x8 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--res: expected WIDTHxHEIGHT (1..65536 each), got \"4294967304x8\"");
  CHECK(run_host("--res 8x4294967297 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--res: expected WIDTHxHEIGHT");
  CHECK(run_host("--sequence 4294967297 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--sequence: expected a frame count N >= 1");
  CHECK(run_host("--frames 4294967296:4294967297 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--frames: expected A:B with A <= B");
  CHECK(run_host("--camera-index 4294967296:4294967297 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--camera-index: expected I or A:B");
  CHECK(run_host("--spp 1099511627776 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--spp: expected an integer in [1, 16777216], got \"1099511627776\"");
  CHECK(run_host("--seed -1 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--seed: expected an integer in [0, 18446744073709551615], got \"-1\"");

  CHECK(run_host("--out image.png x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "ending in .exr");

  CHECK(run_host("--set quality=3 x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "expected PLUGIN.PARAM=VALUE");

  CHECK(run_host("", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "no scene given");

  /* scene errors: exit 4 with the file named */
  CHECK(run_host("/nonexistent/scene.json", out, sizeof out) == 4);
  CHECK_CONTAINS(out, "/nonexistent/scene.json");
  /* (#13) a corrupt PLY named .gltf (found by fuzz_mesh) spun forever inside assimp: exit 4
   * at once, saying what a .gltf must be (137 here means it hung and was killed) */
  snprintf(args, sizeof args, "'%s'", source_path("tests/data/scenes/ply-as-gltf.json"));
  CHECK(run_host_timeout(60, args, out, sizeof out) == 4);
  CHECK_CONTAINS(out, "ply-as-gltf.json: meshes[0].file: mesh file");
  CHECK_CONTAINS(out,
                 "ply-as-gltf.gltf\" is not a glTF file: expected a JSON object, got a PLY file");

  /* plugin errors: exit 3, every failure reported */
  snprintf(args, sizeof args, "--plugin no_such_plugin --plugin also_missing '%s'", scene);
  CHECK(run_host(args, out, sizeof out) == 3);
  CHECK_CONTAINS(out, "no_such_plugin");
  CHECK_CONTAINS(out, "also_missing");

  /* two plugins of one kind */
  snprintf(args, sizeof args, "--plugin accel_embree --plugin accel_embree '%s'", scene);
  CHECK(run_host(args, out, sizeof out) == 3);

  /* --set errors: unknown plugin, unknown parameter, bad value — all reported, exit 2 */
  snprintf(args, sizeof args,
           "--set accel_nope.quality=2 --set accel_embree.qualty=2 "
           "--set accel_embree.branchingFactor=3 --set integrator_pt.maxDepth=-4 '%s'",
           scene);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, "no plugin \"accel_nope\" is loaded");
  CHECK_CONTAINS(out, "qualty");
  CHECK_CONTAINS(out, "branchingFactor");
  CHECK_CONTAINS(out, "maxDepth");

  /* --describe prints the Table 3.1 space as JSON on stdout */
  CHECK(run_host("--describe accel_embree", out, sizeof out) == 0);
  const char *names[] = {"quality",     "branchingFactor", "maxDepth", "sahBlockSize",
                         "minLeafSize", "maxLeafSize",     "travcost", "intcost",
                         "static",      "compact",         "robust"};
  for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
    char quoted[64];
    snprintf(quoted, sizeof quoted, "\"%s\"", names[i]);
    CHECK_CONTAINS(out, quoted);
  }
  CHECK_CONTAINS(out, "\"possibleValues\"");
  CHECK(run_host("--describe integrator_pt", out, sizeof out) == 0);
  CHECK_CONTAINS(out, "\"maxDepth\"");
  CHECK(run_host("--describe nothing_here", out, sizeof out) == 3);
  /* options (tt.options/1) are listed apart from the tuned parameters */
  CHECK(run_host("--describe post_taa", out, sizeof out) == 0);
  CHECK_CONTAINS(out, "\"options\"");
  CHECK_CONTAINS(out, "\"weights\"");

  /* --list-plugins finds the built plugins */
  CHECK(run_host("--list-plugins", out, sizeof out) == 0);
  CHECK_CONTAINS(out, "accel_embree");
  CHECK_CONTAINS(out, "integrator_pt");

  /* a plugin cut short inside its code segment: exit 3 naming the file, for --plugin and
   * for a --plugin-path folder listed (dlopen faulted with SIGBUS, exit 135, before) */
  char tmp[] = "/tmp/tt_host_cli_XXXXXX";
  CHECK(mkdtemp(tmp) != NULL);
  char src[4096], cut[4200];
  snprintf(src, sizeof src, "%s/plugins/tuner_nm/tuner_nm.so", getenv("TT_BUILD_ROOT"));
  snprintf(cut, sizeof cut, "%s/tuner_nm.so", tmp);
  FILE *in = fopen(src, "rb"), *o = fopen(cut, "wb");
  CHECK(in && o);
  if (in && o) {
    static unsigned char buf[1 << 14]; /* the first 16 KiB: inside the code segment */
    size_t n = fread(buf, 1, sizeof buf, in);
    CHECK(n == sizeof buf && fwrite(buf, 1, n, o) == n);
  }
  if (in) fclose(in);
  if (o) fclose(o);
  snprintf(args, sizeof args, "--plugin '%s' --spp 1 --res 4x4 --out %s/x.exr '%s'", cut, tmp,
           scene);
  CHECK(run_host(args, out, sizeof out) == 3);
  CHECK_CONTAINS(out, cut);
  CHECK_CONTAINS(out, "truncated ELF file");
  snprintf(args, sizeof args, "--plugin-path '%s' --list-plugins", tmp);
  CHECK(run_host(args, out, sizeof out) == 3);
  CHECK_CONTAINS(out, "rejected: cannot load plugin");
  CHECK_CONTAINS(out, cut);
  CHECK_CONTAINS(out, "integrator_pt"); /* the good ones are still listed */
  unlink(cut);

  /* cut one byte short: every segment is there, the section headers are not (it loaded and
   * ran before: a half-copied plugin, #13) */
  in = fopen(src, "rb");
  o = fopen(cut, "wb");
  CHECK(in && o);
  if (in && o) {
    fseek(in, 0, SEEK_END);
    long size = ftell(in);
    fseek(in, 0, SEEK_SET);
    char *all = malloc((size_t)size);
    CHECK(all && fread(all, 1, (size_t)size, in) == (size_t)size);
    CHECK(fwrite(all, 1, (size_t)size - 1, o) == (size_t)size - 1);
    free(all);
  }
  if (in) fclose(in);
  if (o) fclose(o);
  snprintf(args, sizeof args, "--plugin '%s' --spp 1 --res 4x4 --out %s/x.exr '%s'", cut, tmp,
           scene);
  CHECK(run_host(args, out, sizeof out) == 3);
  CHECK_CONTAINS(out, cut);
  CHECK_CONTAINS(out, "truncated ELF file");
  CHECK_CONTAINS(out, "section");
  unlink(cut);

  /* NAME.so that is not a regular file in a --plugin-path folder: rejected by name in the
   * listing, as --plugin rejects it (it was skipped silently) */
  char fifo[4200];
  snprintf(fifo, sizeof fifo, "%s/fifo_plugin.so", tmp);
  CHECK(mkfifo(fifo, 0600) == 0);
  snprintf(args, sizeof args, "--plugin-path '%s' --list-plugins", tmp);
  CHECK(run_host(args, out, sizeof out) == 3);
  CHECK_CONTAINS(out, fifo);
  CHECK_CONTAINS(out, "not a regular file");
  CHECK_CONTAINS(out, "integrator_pt");
  unlink(fifo);

  /* a camera beyond Embree's range: exit 4 naming the field, with both backends (the native
   * one aborted on Embree's ray.valid() assertion, exit 134) */
  char far[4200];
  snprintf(far, sizeof far, "%s/far.json", tmp);
  FILE *fj = fopen(far, "w");
  CHECK(fj != NULL);
  if (fj) {
    fputs("{\"version\": 1, \"camera\": {\"position\": [0, 0, 1e19], \"target\": [0, 0, 0], "
          "\"resolution\": [8, 8]}, \"materials\": {\"w\": {\"albedo\": [0.5, 0.5, 0.5]}}, "
          "\"lights\": [{\"type\": \"point\", \"position\": [0, 5, 5], \"intensity\": [9, 9, 9]}], "
          "\"meshes\": [{\"material\": \"w\", \"positions\": [-1,-1,0, 1,-1,0, 1,1,0]}]}",
          fj);
    fclose(fj);
  }
  const char *backends[2] = {"native", "custom"};
  for (int b = 0; b < 2; b++) {
    snprintf(args, sizeof args, "--set accel_embree.backend=%s --spp 1 --out %s/far.exr '%s'",
             backends[b], tmp, far);
    CHECK(run_host(args, out, sizeof out) == 4);
    CHECK_CONTAINS(out, "far.json: camera position (0, 0, 1e+19) is beyond the coordinate limit");
  }
  unlink(far);
  rmdir(tmp);

  return tt_test_finish("host_cli");
}
