/* End to end: tuning a subset of a space. --tune-params searches only the named parameters
 * (every other value stays as configured); PSSMLT's tuning hint turns binning on and
 * searches only the a_i / sigma_i of the thesis; unknown names are usage errors. */
#include <cjson/cJSON.h>

#include "host_util.h"
#include "json_util.h"
#include "tt_test.h"

/* Checks that every history config equals `def` except in the names of `allowed`. */
static int changed_outside(cJSON *tuning, const char *const *allowed, size_t n_allowed,
                           int *changed_inside) {
  cJSON *def = cJSON_GetObjectItem(tuning, "default_config");
  cJSON *hist = cJSON_GetObjectItem(tuning, "history");
  int outside = 0;
  cJSON *h;
  cJSON_ArrayForEach(h, hist) {
    cJSON *cfg = cJSON_GetObjectItem(h, "config"), *v;
    cJSON_ArrayForEach(v, cfg) {
      int is_allowed = 0;
      for (size_t k = 0; k < n_allowed; k++) is_allowed |= !strcmp(v->string, allowed[k]);
      int same = cJSON_Compare(v, cJSON_GetObjectItem(def, v->string), 1);
      if (!same && !is_allowed) outside++;
      if (!same && is_allowed) (*changed_inside)++;
    }
  }
  return outside;
}

int main(void) {
  static char out[1 << 16];
  char args[8192], stats[256];
  char dir[] = "/tmp/tt_tune_subsetXXXXXX";
  if (!mkdtemp(dir)) return 1;
  const char *scene = source_path("scenes/cornell-box/scene.json");

  /* accel: with the default backend (native) maxLeafSize and intcost do nothing: refused,
   * naming them (#17 defect 9) */
  snprintf(stats, sizeof stats, "%s/a.json", dir);
  snprintf(args, sizeof args,
           "--quiet --no-db --res 24x24 --spp 1 --threads 1 --plugin tuner_nm "
           "--tune accel_embree --tune-params maxLeafSize,intcost --iterations 12 "
           "--stats %s --out %s/a.exr '%s'",
           stats, dir, scene);
  CHECK(run_host(args, out, sizeof out) != 0);
  CHECK_CONTAINS(out, "nothing to search: maxLeafSize, intcost are not tunable");
  /* accel, backend custom: only maxLeafSize and intcost move */
  snprintf(args, sizeof args,
           "--quiet --no-db --res 24x24 --spp 1 --threads 1 --plugin tuner_nm "
           "--tune accel_embree --tune-params maxLeafSize,intcost --iterations 12 "
           "--set accel_embree.backend=custom --set accel_embree.maxLeafSize=16 --stats %s "
           "--out %s/a.exr '%s'",
           stats, dir, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  cJSON *root = read_json(stats);
  CHECK(root != NULL);
  if (root) {
    cJSON *t = cJSON_GetObjectItem(root, "tuning");
    const char *allowed[] = {"maxLeafSize", "intcost"};
    int inside = 0;
    CHECK(changed_outside(t, allowed, 2, &inside) == 0);
    CHECK(inside > 0);
    /* the search started from the configured value, not the plugin default */
    cJSON *def = cJSON_GetObjectItem(t, "default_config");
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(def, "maxLeafSize")) == 16);
    cJSON_Delete(root);
  }

  /* PSSMLT's hint: binning on, only a_i / sigma_i / sigma searched, maxDepth kept */
  snprintf(stats, sizeof stats, "%s/b.json", dir);
  snprintf(args, sizeof args,
           "--quiet --no-db --res 24x24 --spp 2 --threads 1 "
           "--plugin integrator_pssmlt --plugin tuner_nm --iterations 6 "
           "--set integrator_pssmlt.bootstrapSamples=2000 --set integrator_pssmlt.chains=64 "
           "--stats %s --out %s/b.exr '%s'",
           stats, dir, scene);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  root = read_json(stats);
  CHECK(root != NULL);
  if (root) {
    cJSON *t = cJSON_GetObjectItem(root, "tuning");
    CHECK(!strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(t, "plugin")), "integrator_pssmlt"));
    const char *allowed[] = {"a1",     "a2",     "a3",     "a4",     "a5",     "a6",
                             "a7",     "a8",     "sigma1", "sigma2", "sigma3", "sigma4",
                             "sigma5", "sigma6", "sigma7", "sigma"};
    int inside = 0;
    CHECK(changed_outside(t, allowed, 16, &inside) == 0);
    CHECK(inside > 0);
    cJSON *def = cJSON_GetObjectItem(t, "default_config");
    CHECK(cJSON_IsTrue(cJSON_GetObjectItem(def, "binning")));
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(def, "chains")) == 64);
    cJSON_Delete(root);
  }

  /* errors */
  snprintf(args, sizeof args,
           "--quiet --no-db --plugin tuner_nm --tune accel_embree "
           "--tune-params maxLeafSize,nonsense '%s'",
           scene);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, "no parameter \"nonsense\"");
  CHECK(run_host("--tune-params a,,b x.json", out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--tune-params: expected NAME");

  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) {}
  return tt_test_finish("tune_subset");
}
