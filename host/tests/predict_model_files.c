/* End to end: host --predict and --hybrid with a crafted predictor_static model (--model M).
 * A model the host saved is changed the way a hostile or careless user would: text appended
 * after its checksum line (after a whole model, or where its configuration list should be),
 * a possible-value index of 1e300, a state count of 1e30 (resealed, so the checksum passes). Each is refused before any work, exit 2, with a message naming
 * the file and what was expected; the file is left as it was. (Before: exit 139, or exit 0
 * with "quality" silently 1.) */
#include <sys/stat.h>

#include "host_util.h"
#include "tt_test.h"

#include <tt_util/hash.h>

static char dir[] = "/tmp/tt_predict_modelXXXXXX";
static char out[1 << 17];

static const char *common =
    "--quiet --res 8x8 --spp 1 --threads 1 --tune-params quality,maxLeafSize";

/* `text` sealed with predictor_static's checksum line (FNV-1a 64 of the text before it),
 * then `tail`, written to `path`. */
static void write_sealed(const char *path, const char *text, const char *tail) {
  FILE *f = fopen(path, "wb");
  CHECK(f != NULL);
  if (!f) return;
  fprintf(f, "%schecksum %016llx\n%s", text,
          (unsigned long long)tt__fnv1a64(TT__FNV1A64_OFFSET, text, strlen(text)), tail);
  fclose(f);
}

/* The model text without its checksum line, with field `field` of the first configuration
 * line (the line after "configs ") replaced by `value` (field < 0: unchanged). malloc'ed. */
static char *edited(const char *model, int field, const char *value) {
  size_t n = strlen(model);
  char *t = malloc(n + 64);
  const char *ck = strstr(model, "\nchecksum ");
  CHECK(ck != NULL);
  size_t body = ck ? (size_t)(ck + 1 - model) : n;
  memcpy(t, model, body);
  t[body] = '\0';
  if (field < 0) return t;
  char *line = strstr(t, "\nconfigs ");
  CHECK(line != NULL);
  if (!line) return t;
  line = strchr(line + 1, '\n') + 1; /* the first configuration */
  char *f = line;
  for (int i = 0; i < field; i++) f = strchr(f, ' ') + 1;
  size_t old = strcspn(f, " \n");
  memmove(f + strlen(value), f + old, strlen(f + old) + 1);
  memcpy(f, value, strlen(value));
  return t;
}

/* `host MODE --model path` exits 2 naming the file and `what`; the file is unchanged. */
static void refused(const char *mode, const char *scene, const char *path, const char *what) {
  struct stat a, b;
  CHECK(stat(path, &a) == 0);
  char args[8192];
  snprintf(args, sizeof args,
           "%s %s --plugin predictor_static --no-db --camera-index 0:1 "
           "--model '%s' '%s'",
           common, mode, path, scene);
  int rc = run_host(args, out, sizeof out);
  CHECK_MSG(rc == 2, "%s with %s: exit %d, expected 2: %s", mode, path, rc, out);
  CHECK_CONTAINS(out, path);
  CHECK_CONTAINS(out, what);
  CHECK(stat(path, &b) == 0 && a.st_size == b.st_size && a.st_mtime == b.st_mtime);
}

int main(void) {
  if (!mkdtemp(dir)) return 1;
  char scene[4200], db[512], model[512], bad[512], args[8192];
  snprintf(scene, sizeof scene, "%s", source_path("scenes/cornell-box/path.json"));
  snprintf(db, sizeof db, "%s/search.db", dir);
  snprintf(model, sizeof model, "%s/static.txt", dir);

  /* a real model: a short search's rows, learnt by predictor_static and saved by the host */
  snprintf(args, sizeof args,
           "%s --plugin tuner_nm --iterations 4 --camera-index 0 --db '%s' "
           "--out '%s/t.exr' '%s'",
           common, db, dir, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  snprintf(args, sizeof args,
           "%s --predict --plugin predictor_static --camera-index 0:1 "
           "--warm-start '%s' --model '%s' '%s'",
           common, db, model, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  size_t n = 0;
  char *text = tt_test_read_file(model, &n);
  CHECK(text && strstr(text, "predictor_static 1\n") == text);
  if (!text) return tt_test_finish("predict_model_files");
  /* it loads back and answers */
  snprintf(args, sizeof args,
           "%s --predict --plugin predictor_static --camera-index 0:1 "
           "--model '%s' '%s'",
           common, model, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  CHECK_CONTAINS(out, "\"quality\"");

  /* text appended after the checksum line, without a newline */
  snprintf(bad, sizeof bad, "%s/appended.txt", dir);
  char *t = edited(text, -1, NULL);
  write_sealed(bad, t, "configs 1 0");
  free(t);
  refused("--predict", scene, bad, "11 bytes after its checksum line");
  refused("--hybrid", scene, bad, "11 bytes after its checksum line");

  /* the configuration list only in text appended after the checksum line: the sealed text
   * ends after the states (the crash: the old reader searched on past the checksum and fed
   * strtod a NULL line) */
  snprintf(bad, sizeof bad, "%s/configs-after.txt", dir);
  t = edited(text, -1, NULL);
  char *cut = strstr(t, "\nconfigs ");
  CHECK(cut != NULL);
  if (cut) cut[1] = '\0';
  write_sealed(bad, t, "configs 1 0");
  free(t);
  refused("--predict", scene, bad, "11 bytes after its checksum line");
  refused("--hybrid", scene, bad, "11 bytes after its checksum line");

  /* quality (a NOM parameter, stored as its possible-value index) 1e300 */
  snprintf(bad, sizeof bad, "%s/quality.txt", dir);
  t = edited(text, 0, "1e300");
  write_sealed(bad, t, "");
  free(t);
  refused("--predict", scene, bad, "accel_embree.quality: possible-value index");
  refused("--hybrid", scene, bad, "accel_embree.quality: possible-value index");

  /* a configuration seen in 1e30 states (fields: quality, maxLeafSize, log-ratio sum,
   * states, last state) */
  snprintf(bad, sizeof bad, "%s/states.txt", dir);
  t = edited(text, 3, "1e30");
  write_sealed(bad, t, "");
  free(t);
  refused("--predict", scene, bad, "the number of states it was seen in");

  free(text);
  snprintf(args, sizeof args, "rm -rf '%s'", dir);
  if (system(args)) {}
  return tt_test_finish("predict_model_files");
}
