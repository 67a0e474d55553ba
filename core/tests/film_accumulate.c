/* Film accumulators: weighted means, splat scale, dropped non-finite values, concurrent
 * splats and AOV planes. */
#include <tunetrace/film.h>

#include <pthread.h>

#include "tt_test.h"

/* Weighted samples resolve to sum(w L) / sum(w); untouched pixels resolve to 0. */
static void test_weighted_average(void) {
  tt_film *film = tt_film_create(4, 3, 0);
  CHECK(film != NULL);
  if (!film) return;
  CHECK(tt_film_width(film) == 4 && tt_film_height(film) == 3);
  const float a[3] = {1.0f, 2.0f, 3.0f}, b[3] = {5.0f, 0.0f, -1.0f};
  tt_film_add_sample(film, 2, 1, a, 1.0f);
  tt_film_add_sample(film, 2, 1, b, 3.0f);
  tt_film_add_sample(film, 3, 2, a, 0.5f);
  float out[4 * 3 * 3];
  memset(out, 0xff, sizeof out); /* NaN pattern: every pixel must be written */
  tt_film_resolve(film, out);
  const float *p = out + 3 * (1 * 4 + 2);
  CHECK_NEAR(p[0], (1.0 + 15.0) / 4.0, 1e-6);
  CHECK_NEAR(p[1], 2.0 / 4.0, 1e-6);
  CHECK_NEAR(p[2], (3.0 - 3.0) / 4.0, 1e-6);
  const float *q = out + 3 * (2 * 4 + 3);
  CHECK_NEAR(q[0], 1.0, 1e-6);
  CHECK_NEAR(q[1], 2.0, 1e-6);
  CHECK_NEAR(q[2], 3.0, 1e-6);
  CHECK(out[0] == 0.0f && out[1] == 0.0f && out[2] == 0.0f); /* sum_w == 0 */
  CHECK_NEAR(tt_film_sum_weight(film)[1 * 4 + 2], 4.0, 0);
  CHECK_NEAR(tt_film_sum_rgb(film)[3 * (1 * 4 + 2)], 16.0, 0);
  CHECK(tt_film_dropped(film) == 0);

  /* clear resets sums and the splat scale */
  tt_film_set_splat_scale(film, 0.25);
  tt_film_clear(film);
  CHECK(tt_film_splat_scale(film) == 1.0);
  tt_film_resolve(film, out);
  int all_zero = 1;
  for (size_t i = 0; i < sizeof out / sizeof out[0]; i++) all_zero &= out[i] == 0.0f;
  CHECK(all_zero);
  tt_film_destroy(film);
}

/* Splats land in pixel (floor fx, floor fy) and are scaled at resolve, on top of samples. */
static void test_splat_scale(void) {
  tt_film *film = tt_film_create(3, 2, 0);
  CHECK(film != NULL);
  if (!film) return;
  const float s[3] = {2.0f, 4.0f, 8.0f};
  tt_film_splat(film, 1.99f, 0.01f, s); /* pixel (1, 0) */
  tt_film_splat(film, 1.0f, 0.99f, s);  /* pixel (1, 0) */
  tt_film_splat(film, 0.5f, 1.5f, s);   /* pixel (0, 1) */
  const float one[3] = {1.0f, 1.0f, 1.0f};
  tt_film_add_sample(film, 0, 1, one, 2.0f);
  CHECK(tt_film_splat_rgb(film)[3 * 1 + 2] == 16.0f);
  tt_film_set_splat_scale(film, 0.5);
  CHECK(tt_film_splat_scale(film) == 0.5);
  float out[3 * 2 * 3];
  tt_film_resolve(film, out);
  CHECK_NEAR(out[3 * 1 + 0], 2.0, 0); /* 2 splats * 2 * 0.5 */
  CHECK_NEAR(out[3 * 1 + 1], 4.0, 0);
  CHECK_NEAR(out[3 * 1 + 2], 8.0, 0);
  CHECK_NEAR(out[3 * 3 + 0], 1.0 + 1.0, 0); /* sample mean 1 + splat 2 * 0.5 */
  CHECK_NEAR(out[3 * 3 + 2], 1.0 + 4.0, 0);
  CHECK(out[0] == 0.0f && out[3 * 2] == 0.0f && out[3 * 4] == 0.0f && out[3 * 5] == 0.0f);
  CHECK(tt_film_dropped(film) == 0);
  tt_film_destroy(film);
}

/* NaN/Inf values and out-of-film positions are dropped and counted; the image stays finite. */
static void test_non_finite(void) {
  tt_film *film = tt_film_create(2, 2, 0);
  CHECK(film != NULL);
  if (!film) return;
  const float good[3] = {1.0f, 1.0f, 1.0f};
  const float nan3[3] = {1.0f, NAN, 1.0f};
  const float inf3[3] = {INFINITY, 0.0f, 0.0f};
  tt_film_add_sample(film, 0, 0, good, 1.0f);
  tt_film_add_sample(film, 0, 0, nan3, 1.0f);
  tt_film_add_sample(film, 0, 0, inf3, 1.0f);
  tt_film_add_sample(film, 0, 0, good, NAN);
  tt_film_add_sample(film, 0, 0, good, INFINITY);
  tt_film_add_sample(film, 2, 0, good, 1.0f); /* outside */
  tt_film_splat(film, 1.0f, 1.0f, nan3);
  tt_film_splat(film, 1.0f, 1.0f, inf3);
  tt_film_splat(film, NAN, 1.0f, good);
  tt_film_splat(film, 1.0f, INFINITY, good);
  tt_film_splat(film, -0.5f, 1.0f, good); /* floor would be -1: outside */
  tt_film_splat(film, 2.0f, 1.0f, good);  /* x == width: outside */
  CHECK_MSG(tt_film_dropped(film) == 11, "dropped = %llu",
            (unsigned long long)tt_film_dropped(film));
  float out[2 * 2 * 3];
  tt_film_resolve(film, out);
  int finite = 1;
  for (int i = 0; i < 12; i++) finite &= isfinite(out[i]) != 0;
  CHECK(finite);
  CHECK(out[0] == 1.0f && out[1] == 1.0f && out[2] == 1.0f);
  CHECK(out[9] == 0.0f && out[10] == 0.0f && out[11] == 0.0f);
  tt_film_clear(film);
  CHECK(tt_film_dropped(film) == 0);
  tt_film_destroy(film);
}

#define SPLAT_THREADS 8
#define SPLATS_PER_THREAD 200000

typedef struct splat_job {
  tt_film *film;
  int id;
} splat_job;

/* Every thread hammers the same few pixels so that CAS retries really happen; also drops
 * one NaN splat per 1000 so the counter is exercised concurrently. */
static void *splat_worker(void *arg) {
  splat_job *job = arg;
  const float v[3] = {1.0f, 2.0f, (float)job->id};
  const float bad[3] = {NAN, 0.0f, 0.0f};
  for (int i = 0; i < SPLATS_PER_THREAD; i++) {
    float fx = (float)(i % 2) + 0.5f;
    tt_film_splat(job->film, fx, 0.25f, v);
    if (i % 1000 == 0) tt_film_splat(job->film, fx, 0.25f, bad);
  }
  return NULL;
}

/* Integer-valued splats below 2^24 sum exactly in float, so any lost update shows. */
static void test_concurrent_splats(void) {
  tt_film *film = tt_film_create(2, 1, 0);
  CHECK(film != NULL);
  if (!film) return;
  pthread_t threads[SPLAT_THREADS];
  splat_job jobs[SPLAT_THREADS];
  for (int t = 0; t < SPLAT_THREADS; t++) {
    jobs[t] = (splat_job){film, t};
    CHECK(pthread_create(&threads[t], NULL, splat_worker, &jobs[t]) == 0);
  }
  for (int t = 0; t < SPLAT_THREADS; t++) pthread_join(threads[t], NULL);
  const double per_pixel = SPLATS_PER_THREAD / 2.0 * SPLAT_THREADS; /* 800000 per pixel */
  double id_sum = 0;
  for (int t = 0; t < SPLAT_THREADS; t++) id_sum += t;
  const float *s = tt_film_splat_rgb(film);
  for (int p = 0; p < 2; p++) {
    CHECK_NEAR(s[3 * p + 0], per_pixel, 0);
    CHECK_NEAR(s[3 * p + 1], 2.0 * per_pixel, 0);
    CHECK_NEAR(s[3 * p + 2], id_sum * SPLATS_PER_THREAD / 2.0, 0);
  }
  CHECK(tt_film_dropped(film) == (uint64_t)SPLAT_THREADS * (SPLATS_PER_THREAD / 1000));
  tt_film_destroy(film);
}

/* AOV planes exist exactly for the mask bits, have the documented channel counts, start
 * zeroed and are cleared by tt_film_clear. */
static void test_aovs(void) {
  CHECK(tt_aov_channels(TT_AOV_DEPTH) == 1);
  CHECK(tt_aov_channels(TT_AOV_NORMAL) == 3);
  CHECK(tt_aov_channels(TT_AOV_ALBEDO) == 3);
  CHECK(tt_aov_channels(TT_AOV_MOTION) == 2);
  CHECK(tt_aov_channels((tt_aov)(TT_AOV_DEPTH | TT_AOV_NORMAL)) == 0);

  tt_film *film = tt_film_create(5, 3, TT_AOV_DEPTH | TT_AOV_MOTION);
  CHECK(film != NULL);
  if (!film) return;
  CHECK(tt_film_aov_mask(film) == (TT_AOV_DEPTH | TT_AOV_MOTION));
  float *depth = tt_film_aov(film, TT_AOV_DEPTH);
  float *motion = tt_film_aov(film, TT_AOV_MOTION);
  CHECK(depth != NULL && motion != NULL);
  CHECK(tt_film_aov(film, TT_AOV_NORMAL) == NULL);
  CHECK(tt_film_aov(film, TT_AOV_ALBEDO) == NULL);
  CHECK(tt_film_aov_const(film, TT_AOV_DEPTH) == depth);
  if (depth && motion) {
    int zero = 1;
    for (int i = 0; i < 15; i++) zero &= depth[i] == 0.0f;
    for (int i = 0; i < 30; i++) zero &= motion[i] == 0.0f;
    CHECK(zero);
    /* writing the last element of each plane must be in bounds (ASan/valgrind would tell) */
    depth[14] = 7.0f;
    motion[29] = -3.0f;
    CHECK(tt_film_aov_const(film, TT_AOV_MOTION)[29] == -3.0f);
    tt_film_clear(film);
    CHECK(depth[14] == 0.0f && motion[29] == 0.0f);
  }
  tt_film_destroy(film);

  tt_film *all = tt_film_create(2, 2, TT_AOV_DEPTH | TT_AOV_NORMAL | TT_AOV_ALBEDO | TT_AOV_MOTION);
  CHECK(all != NULL);
  if (all) {
    CHECK(tt_film_aov(all, TT_AOV_NORMAL) != NULL && tt_film_aov(all, TT_AOV_ALBEDO) != NULL);
    tt_film_destroy(all);
  }
}

/* Bad sizes and masks fail with a message. */
static void test_bad_create(void) {
  tt_clear_error();
  CHECK(tt_film_create(0, 4, 0) == NULL);
  CHECK_CONTAINS(tt_last_error(), "film");
  CHECK(tt_film_create(4, 4, 1u << 7) == NULL);
  CHECK_CONTAINS(tt_last_error(), "AOV");
  tt_film_destroy(NULL);
}

int main(void) {
  test_weighted_average();
  test_splat_scale();
  test_non_finite();
  test_concurrent_splats();
  test_aovs();
  test_bad_create();
  return tt_test_finish("film_accumulate");
}
