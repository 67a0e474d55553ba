/* End to end: --objective rrmse (host/README.md). The cost of a tuning measurement is the
 * rRMSE of that pass's own image (not the accumulated film) against --reference:
 *  - every cost in the run record equals the rRMSE computed here from the pass image the
 *    host wrote with --tune-pass-images (path tracer tuning its accel, and PSSMLT);
 *  - the pass image is the pass's own: the path tracer's default-measurement pass equals
 *    2 x (plain 2-spp render) - (plain 1-spp render) of the same seed;
 *  - the database records objective "rrmse" with the reference in the context;
 *  - a reference of another size, a missing reference and a reference without rrmse are
 *    usage errors (exit 2) naming the file and both sizes;
 *  - tuning PSSMLT on the Cornell box with the rrmse objective completes. */
#include <tunetrace/tunetrace.h>

#include <cjson/cJSON.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <unistd.h>

#include "host_util.h"
#include "json_util.h"
#include "tt_test.h"

static char dir[] = "/tmp/tt_tune_rrmseXXXXXX";
static char scene_path[4200];

/* Reads an image as luminance (Rec. 709, as tools/pssmlt); NULL on failure. */
static double *read_lum(const char *path, uint32_t *w, uint32_t *h) {
  uint32_t ch = 0;
  float *px = NULL;
  if (tt_image_read(path, w, h, &ch, &px) != TT_OK || ch < 3) {
    tt_free(px);
    return NULL;
  }
  size_t n = (size_t)*w * *h;
  double *lum = malloc(n * sizeof *lum);
  for (size_t i = 0; lum && i < n; i++)
    lum[i] = 0.2126 * px[i * ch] + 0.7152 * px[i * ch + 1] + 0.0722 * px[i * ch + 2];
  tt_free(px);
  return lum;
}

/* sqrt(mean((I - R)^2 / (R^2 + 1e-3))), computed independently of the host. */
static double rrmse(const double *I, const double *R, size_t n) {
  double s = 0;
  for (size_t i = 0; i < n; i++) s += (I[i] - R[i]) * (I[i] - R[i]) / (R[i] * R[i] + 1e-3);
  return sqrt(s / (double)n);
}

/* Checks every measured cost of `stats` against the pass images in `passes`, whose
 * reference is `ref` (n pixels). Returns the number of costs checked. */
static int check_costs(const char *stats, const char *passes, const double *ref, size_t n) {
  cJSON *root = read_json(stats);
  CHECK_MSG(root != NULL, "%s unreadable", stats);
  if (!root) return 0;
  cJSON *t = cJSON_GetObjectItem(root, "tuning");
  CHECK(t && !strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(t, "objective")), "rrmse"));
  int checked = 0;
  cJSON *hist = cJSON_GetObjectItem(t, "history");
  for (int i = -1; t && i < cJSON_GetArraySize(hist); i++) {
    char path[4400];
    double cost;
    if (i < 0) {
      snprintf(path, sizeof path, "%s/pass_default.exr", passes);
      cost = num(t, "default_cost");
    } else {
      cJSON *h = cJSON_GetArrayItem(hist, i);
      if (strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(h, "status")), "ok")) continue;
      snprintf(path, sizeof path, "%s/pass_%04d.exr", passes, (int)num(h, "iteration"));
      cost = num(h, "cost");
    }
    uint32_t w = 0, hgt = 0;
    double *img = read_lum(path, &w, &hgt);
    CHECK_MSG(img != NULL && (size_t)w * hgt == n, "pass image %s", path);
    if (img && (size_t)w * hgt == n) {
      double e = rrmse(img, ref, n);
      CHECK_MSG(cost > 0 && fabs(cost - e) <= 1e-9 * e, "%s: cost %.17g, from the image %.17g",
                path, cost, e);
      checked++;
    }
    free(img);
  }
  cJSON_Delete(root);
  return checked;
}

/* Mean luminance of an image (NaN if unreadable). */
static double mean_lum(const char *path) {
  uint32_t w = 0, h = 0;
  double *l = read_lum(path, &w, &h), s = 0;
  if (!l) return NAN;
  for (size_t i = 0; i < (size_t)w * h; i++) s += l[i];
  free(l);
  return s / ((double)w * h);
}

int main(void) {
  static char out[1 << 16];
  char args[32768], ref[4300], stats[4300], passes[4300], db[4300];
  if (!mkdtemp(dir)) return 1;
  snprintf(scene_path, sizeof scene_path, "%s", source_path("scenes/cornell-box/scene.json"));
  char data_home[4300];
  snprintf(data_home, sizeof data_home, "%s/data", dir);
  setenv("XDG_DATA_HOME", data_home, 1); /* never touch the user's own database */

  /* the reference: a 24x24 path-traced render */
  snprintf(ref, sizeof ref, "%s/ref.exr", dir);
  snprintf(args, sizeof args,
           "--plugin integrator_pt --res 24x24 --spp 32 --seed 99 --threads 2 "
           "--quiet --out '%s' '%s'",
           ref, scene_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  uint32_t rw = 0, rh = 0;
  double *R = read_lum(ref, &rw, &rh);
  CHECK(R != NULL && rw == 24 && rh == 24);
  if (!R) return tt_test_finish("tune_rrmse");
  size_t n = (size_t)rw * rh;

  /* path tracer, tuning the accel for rrmse: costs = rRMSE of the written pass images */
  snprintf(stats, sizeof stats, "%s/pt.json", dir);
  snprintf(passes, sizeof passes, "%s/pt_passes", dir);
  snprintf(db, sizeof db, "%s/pt.db", dir);
  snprintf(args, sizeof args,
           "--plugin integrator_pt --plugin tuner_nm --tune accel_embree "
           "--objective rrmse --reference '%s' --iterations 4 --res 24x24 --spp 1 --seed 7 "
           "--threads 2 --db '%s' --tune-pass-images '%s' --out '%s/pt.exr' --stats '%s' '%s'",
           ref, db, passes, dir, stats, scene_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  CHECK_MSG(check_costs(stats, passes, R, n) == 5, "path tracer: not every cost checked");

  /* the pass image is the pass's own: warm-up = pass 0, default measurement = pass 1, and
   * the plain renders of the same seed hold p0 (1 spp) and (p0 + p1) / 2 (2 spp) */
  char p1[4400], p2[4400];
  snprintf(p1, sizeof p1, "%s/plain1.exr", dir);
  snprintf(p2, sizeof p2, "%s/plain2.exr", dir);
  snprintf(args, sizeof args,
           "--plugin integrator_pt --res 24x24 --spp 1 --seed 7 --threads 2 "
           "--quiet --out '%s' '%s'",
           p1, scene_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  snprintf(args, sizeof args,
           "--plugin integrator_pt --res 24x24 --spp 2 --seed 7 --threads 2 "
           "--quiet --out '%s' '%s'",
           p2, scene_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  {
    uint32_t w, h;
    char pd[4400];
    snprintf(pd, sizeof pd, "%s/pass_default.exr", passes);
    double *a = read_lum(p1, &w, &h), *b = read_lum(p2, &w, &h), *d = read_lum(pd, &w, &h);
    CHECK(a && b && d);
    double worst = 0, film = 0;
    for (size_t i = 0; a && b && d && i < n; i++) {
      double own = 2 * b[i] - a[i];
      double e = fabs(d[i] - own) / (fabs(own) + 1e-3);
      if (e > worst) worst = e;
      film += fabs(d[i] - b[i]);
    }
    CHECK_MSG(worst < 1e-4, "default pass image differs from 2*plain2 - plain1 by %g", worst);
    CHECK_MSG(film > 1e-3 * n * 1e-3, "the pass image looks like the accumulated film");
    free(a);
    free(b);
    free(d);
  }

  /* the database: objective rrmse, the reference in the context */
  {
    sqlite3 *s = NULL;
    sqlite3_stmt *st = NULL;
    long rows = -1, with_ref = -1;
    if (sqlite3_open_v2(db, &s, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
        sqlite3_prepare_v2(s,
                           "SELECT count(*), sum(context LIKE '%\"reference\"%fnv1a64%') "
                           "FROM samples WHERE objective = 'rrmse'",
                           -1, &st, NULL) == SQLITE_OK &&
        sqlite3_step(st) == SQLITE_ROW) {
      rows = sqlite3_column_int64(st, 0);
      with_ref = sqlite3_column_int64(st, 1);
    }
    sqlite3_finalize(st);
    sqlite3_close(s);
    CHECK_MSG(rows >= 1 && with_ref == rows, "%ld rrmse rows, %ld with the reference", rows,
              with_ref);
  }

  /* PSSMLT on the Cornell box, its hint's space, rrmse objective: completes, costs check */
  snprintf(stats, sizeof stats, "%s/mlt.json", dir);
  snprintf(passes, sizeof passes, "%s/mlt_passes", dir);
  snprintf(args, sizeof args,
           "--plugin integrator_pssmlt --plugin tuner_nm --objective rrmse "
           "--reference '%s' --iterations 6 --tune-spp 2 --res 24x24 --spp 2 --seed 3 "
           "--threads 2 --set integrator_pssmlt.bootstrapSamples=10000 --no-db "
           "--tune-pass-images '%s' --out '%s/mlt.exr' --stats '%s' '%s'",
           ref, passes, dir, stats, scene_path);
  CHECK_MSG(run_host(args, out, sizeof out) == 0, "%s", out);
  CHECK_MSG(check_costs(stats, passes, R, n) >= 2, "PSSMLT: costs not checked");
  {
    cJSON *root = read_json(stats);
    cJSON *t = root ? cJSON_GetObjectItem(root, "tuning") : NULL;
    CHECK(t &&
          !strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(t, "plugin")), "integrator_pssmlt"));
    CHECK(t && num(t, "iterations") == 6);
    CHECK(t && num(t, "best_cost") <= num(t, "default_cost"));
    cJSON_Delete(root);
    /* a PSSMLT pass image has mean luminance b like the film (splats of luminance 1) */
    char pd[4400], film[4400];
    snprintf(pd, sizeof pd, "%s/pass_default.exr", passes);
    snprintf(film, sizeof film, "%s/mlt.exr", dir);
    double mp = mean_lum(pd), mf = mean_lum(film);
    CHECK_MSG(fabs(mp - mf) <= 1e-3 * mf, "pass mean %g, film mean %g", mp, mf);
  }

  /* usage errors */
  snprintf(args, sizeof args,
           "--plugin integrator_pt --plugin tuner_nm --tune accel_embree "
           "--objective rrmse --reference '%s' --iterations 2 --res 16x12 --no-db --out "
           "'%s/bad.exr' '%s'",
           ref, dir, scene_path);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, ref);
  CHECK_CONTAINS(out, "24x24");
  CHECK_CONTAINS(out, "16x12");
  snprintf(args, sizeof args, "--plugin tuner_nm --objective rrmse --res 16x16 --no-db '%s'",
           scene_path);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, "--objective rrmse needs --reference");
  snprintf(args, sizeof args, "--plugin tuner_nm --reference '%s' --res 24x24 --no-db '%s'", ref,
           scene_path);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, "only --objective rrmse uses a reference");
  snprintf(args, sizeof args,
           "--plugin tuner_nm --tune accel_embree --objective rrmse "
           "--reference '%s/missing.exr' --res 24x24 --no-db '%s'",
           dir, scene_path);
  CHECK(run_host(args, out, sizeof out) == 2);
  CHECK_CONTAINS(out, "missing.exr");

  free(R);
  snprintf(args, sizeof args, "rm -rf '%s'", dir);
  if (system(args) != 0) {}
  return tt_test_finish("tune_rrmse");
}
