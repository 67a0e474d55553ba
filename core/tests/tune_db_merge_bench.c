/* Bench (prints figures, asserts only correctness): how many rows per second one SQLite
 * writer merges, the rate rank 0 of tunetrace-mpi sustains. A job file of ROWS rows (a
 * baseline search: default + 40 iterations) is merged JOBS times under distinct tags into
 * one database, against recording the same rows one by one (one transaction each, what a
 * single host process does). Interleaved rounds, medians. */
#include <tunetrace/tunetrace.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "tt_test.h"

#define ROWS 41
#define JOBS 100
#define ROUNDS 5

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int cmp_d(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static void fill(tt_tunedb_row *r, int i, char *config, size_t n) {
  memset(r, 0, sizeof *r);
  r->struct_size = sizeof *r;
  r->scene_id = "bench-scene";
  r->scene = "scenes/bmw-m6/scene.json";
  r->camera = "{\"path_index\":17,\"position\":[1,2,3],\"target\":[0,0,0],\"fov_y\":40}";
  r->context = "{\"spp\":1,\"threads\":1,\"clock\":\"cpu\",\"integrator_pt\":{\"max_depth\":8}}";
  r->plugin = "accel_embree";
  r->plugin_version = "1.2.0";
  snprintf(config, n,
           "{\"quality\":\"high\",\"branchingFactor\":%d,\"maxDepth\":%d,"
           "\"sahBlockSize\":4,\"minLeafSize\":1,\"maxLeafSize\":8,\"travcost\":1.5,"
           "\"intcost\":%d.25,\"static\":true,\"compact\":false,\"robust\":false}",
           4 + i % 5, 20 + i, i);
  r->config = config;
  r->objective = "build+render";
  r->build_ms = 50 + i;
  r->render_ms = 30 + i;
  r->cost = 80 + 2 * i;
  r->status = TT_TUNEDB_OK;
  r->mode = i ? "tune" : "default";
  r->iteration = i - 1;
  r->run_id = "bench";
  r->tuner = "tuner_nm";
  r->has_indicators = 1;
  for (int k = 0; k < TT_SCENE_INDICATOR_COUNT; k++) r->indicators[k] = k * 1.5;
}

int main(void) {
  char dir[] = "/tmp/tt_merge_benchXXXXXX";
  if (!mkdtemp(dir)) return 1;
  char src[4200], dst[4200], one[4200], tag[64], config[512];
  snprintf(src, sizeof src, "%s/job.db", dir);
  tt_tunedb *s = NULL;
  CHECK(tt_tunedb_open(src, &s) == TT_OK);
  if (!s) return tt_test_finish("tune_db_merge_bench");
  for (int i = 0; i < ROWS; i++) {
    tt_tunedb_row r;
    fill(&r, i, config, sizeof config);
    CHECK(tt_tunedb_record(s, &r) == TT_OK);
  }
  tt_tunedb_close(s);
  double merge_s[ROUNDS], record_s[ROUNDS];
  for (int round = 0; round < ROUNDS; round++) {
    /* merges: JOBS files of ROWS rows, one transaction each (rows + tag) */
    snprintf(dst, sizeof dst, "%s/merged%d.db", dir, round);
    tt_tunedb *d = NULL;
    CHECK(tt_tunedb_open(dst, &d) == TT_OK);
    double t0 = now_s();
    for (int j = 0; j < JOBS && d; j++) {
      snprintf(tag, sizeof tag, "job-%d", j);
      uint64_t rows = 0;
      CHECK(tt_tunedb_merge(d, src, tag, j % 64, NULL, &rows, NULL) == TT_OK && rows == ROWS);
    }
    merge_s[round] = now_s() - t0;
    uint64_t count = 0;
    CHECK(d && tt_tunedb_count(d, NULL, &count) == TT_OK && count == (uint64_t)ROWS * JOBS);
    tt_tunedb_close(d);
    /* the same rows recorded one by one */
    snprintf(one, sizeof one, "%s/record%d.db", dir, round);
    CHECK(tt_tunedb_open(one, &d) == TT_OK);
    t0 = now_s();
    for (int j = 0; j < JOBS && d; j++)
      for (int i = 0; i < ROWS; i++) {
        tt_tunedb_row r;
        fill(&r, i, config, sizeof config);
        CHECK(tt_tunedb_record(d, &r) == TT_OK);
      }
    record_s[round] = now_s() - t0;
    tt_tunedb_close(d);
    unlink(dst);
    unlink(one);
  }
  double m[ROUNDS], r[ROUNDS];
  memcpy(m, merge_s, sizeof m);
  memcpy(r, record_s, sizeof r);
  qsort(m, ROUNDS, sizeof *m, cmp_d);
  qsort(r, ROUNDS, sizeof *r, cmp_d);
  double load[1] = {0};
  if (getloadavg(load, 1) != 1) load[0] = -1;
  printf("BENCH tune_db_merge: %d jobs x %d rows, %d interleaved rounds, load %.1f\n", JOBS, ROWS,
         ROUNDS, load[0]);
  printf("  merge (one transaction per job): median %.3f s = %.0f rows/s, %.0f jobs/s\n",
         m[ROUNDS / 2], ROWS * JOBS / m[ROUNDS / 2], JOBS / m[ROUNDS / 2]);
  printf("  record (one transaction per row): median %.3f s = %.0f rows/s\n", r[ROUNDS / 2],
         ROWS * JOBS / r[ROUNDS / 2]);
  printf("  ratio record/merge time: %.2f\n", r[ROUNDS / 2] / m[ROUNDS / 2]);
  char cmd[4300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (system(cmd) != 0) {}
  return tt_test_finish("tune_db_merge_bench");
}
