/* Render sessions that live side by side (tunetrace/session.h over the real plugins):
 * closing one session never disturbs another, whatever the order, and sessions on several
 * threads at once render what one session alone renders.
 *
 *  - two sessions alive: both render; closing either first leaves the other rendering,
 *    rebuilding its accel and rejecting a bad value with a readable message (before the
 *    plugins' state was per registry, closing one session freed accel_embree's device and
 *    space under the other: "build before init", freed names in error messages);
 *  - re-assignment in a loop (Python's `s = tt.Session(...)` creates the new session before
 *    the old one is freed), with a tuning run on each, the case that crashed;
 *  - a session per thread: four threads each create, tune, render and destroy sessions at
 *    once; each image equals, bit for bit, the one rendered by a session alone, and each
 *    thread's error message is its own (tt_last_error is per thread).
 * Built into the sanitizer build too (tools/test_sanitized.sh): ASan sees every free.
 *
 * Environment: TT_SOURCE_ROOT, TT_PLUGIN_PATH (tests/meson.build). */
#include <tunetrace/tunetrace.h>

#include "tt_test.h"

#include <pthread.h>
#include <unistd.h>

#define W 16
#define H 12
#define SPP 3

static char g_scene[4096];

/* A started session over the Cornell box at W x H with seed 7, or NULL (message printed). */
static tt_session *open_session(void) {
  tt_session *s = NULL;
  if (tt_session_create(NULL, &s) != TT_OK) return NULL;
  if (tt_session_load_scene(s, g_scene) != TT_OK ||
      tt_scene_set_resolution(tt_session_scene(s), W, H) != TT_OK ||
      tt_session_load_plugin(s, "accel_embree", NULL) != TT_OK ||
      tt_session_load_plugin(s, "integrator_pt", NULL) != TT_OK ||
      tt_session_load_plugin(s, "tuner_nm", NULL) != TT_OK) {
    fprintf(stderr, "open_session: %s\n", tt_last_error());
    tt_session_destroy(s);
    return NULL;
  }
  tt_session_set_seed(s, 7);
  return s;
}

/* Renders `spp` passes (starting the session first if needed) and resolves the film into
 * `rgb` (W*H*3, may be NULL). Returns the first failure's status. */
static tt_status render(tt_session *s, uint32_t spp, float *rgb) {
  tt_status st = tt_session_started(s) ? TT_OK : tt_session_start(s, 0);
  for (uint32_t i = 0; st == TT_OK && i < spp; i++) st = tt_session_render_pass(s, 1, NULL);
  if (st == TT_OK && rgb) tt_film_resolve(tt_session_film(s), rgb);
  return st;
}

/* A few tuner_nm iterations over accel_embree's space, as the Python API and the host run
 * them; leaves the best configuration applied. */
static tt_status tune(tt_session *s, uint32_t iterations) {
  tt_status st = tt_session_started(s) ? TT_OK : tt_session_start(s, 0);
  if (st != TT_OK) return st;
  int idx = tt_session_plugin_index(s, "accel_embree");
  int tidx = tt_session_plugin_index(s, "tuner_nm");
  tt_registry *reg = tt_session_registry(s);
  tt_loaded_plugin *target = tt_registry_get(reg, (size_t)idx);
  tt_loaded_plugin *tuner = tt_registry_get(reg, (size_t)tidx);
  tt_tuning_target tt;
  st = tt_session_tuning_target(s, (size_t)idx, 0, &tt);
  if (st != TT_OK) return st;
  tt_tuning_desc d;
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.space = tt_loaded_plugin_space(target);
  d.start = tt_session_config_at(s, (size_t)idx);
  d.objective = "render";
  d.tuner = tt_loaded_plugin_iface(tuner);
  d.tuner_settings = tt_session_config_at(s, (size_t)tidx);
  d.tuner_name = "tuner_nm";
  d.seed = 3;
  d.iterations = iterations;
  d.spp = 1;
  d.plugin = tt_loaded_plugin_entry(target)->name;
  d.plugin_version = tt_loaded_plugin_entry(target)->version;
  d.width = W;
  d.height = H;
  tt_tuning *t = NULL;
  st = tt_tuning_create(&d, &t);
  if (st == TT_OK) st = tt_tuning_run(t, &tt);
  if (st == TT_OK) st = tt_tuning_apply_best(t, &tt, NULL);
  tt_tuning_destroy(t);
  return st;
}

/* Sets accel_embree.quality to 7 (outside {1, 2, 3}) and checks the message names the
 * parameter and the allowed values: read from the plugin's space, which must be live. */
static void check_rejects_bad_value(tt_session *s, const char *when) {
  tt_status st = tt_session_set(s, "accel_embree", "quality", "7");
  CHECK_MSG(st == TT_ERR_INVALID_ARGUMENT, "%s: status %d", when, (int)st);
  CHECK_MSG(strstr(tt_last_error(), "accel_embree.quality: \"7\" is not one of 1, 2, 3"),
            "%s: message \"%s\"", when, tt_last_error());
}

/* Two sessions alive; `close_older_first`: close the older one first, else the newer. */
static void test_two_alive(int close_older_first, const float *ref) {
  const char *when = close_older_first ? "older closed first" : "newer closed first";
  tt_session *a = open_session(), *b = open_session();
  CHECK(a && b);
  if (!a || !b) {
    tt_session_destroy(a);
    tt_session_destroy(b);
    return;
  }
  float img[W * H * 3];
  CHECK_MSG(render(a, SPP, img) == TT_OK, "%s: %s", when, tt_last_error());
  CHECK_MSG(render(b, SPP, img) == TT_OK, "%s: %s", when, tt_last_error());
  tt_session *gone = close_older_first ? a : b, *kept = close_older_first ? b : a;
  tt_session_destroy(gone);
  /* the survivor rebuilds its accel (a new structure from the plugin's device), renders
   * on and still has the plugin's space behind its configurations */
  CHECK_MSG(tt_session_rebuild_accel(kept, NULL, NULL) == TT_OK, "%s: rebuild: %s", when,
            tt_last_error());
  tt_session_reset(kept);
  CHECK_MSG(render(kept, SPP, img) == TT_OK, "%s: render: %s", when, tt_last_error());
  CHECK_MSG(!memcmp(img, ref, sizeof img),
            "%s: the survivor's image differs from a lone "
            "session's",
            when);
  check_rejects_bad_value(kept, when);
  tt_session_destroy(kept);
}

/* `s = Session(...)` in a loop: the new session exists before the old one is freed. */
static void test_reassign_loop(const float *ref) {
  tt_session *s = open_session();
  CHECK(s != NULL);
  for (int i = 0; s && i < 6; i++) {
    CHECK_MSG(tune(s, 2) == TT_OK, "round %d: tune: %s", i, tt_last_error());
    tt_session *next = open_session();
    CHECK(next != NULL);
    tt_session_destroy(s);
    s = next;
    if (!s) break;
    check_rejects_bad_value(s, "after re-assignment");
    float img[W * H * 3];
    CHECK_MSG(render(s, SPP, img) == TT_OK, "round %d: render: %s", i, tt_last_error());
    CHECK_MSG(!memcmp(img, ref, sizeof img), "round %d: image differs from a lone session's", i);
  }
  tt_session_destroy(s);
}

/* ---- a session per thread ---- */

typedef struct worker {
  int id;
  const float *ref;
  int rounds_ok, images_equal, own_message;
  char error[512];
} worker;

static void *worker_main(void *arg) {
  worker *w = arg;
  for (int round = 0; round < 3; round++) {
    tt_session *s = open_session();
    if (!s) {
      snprintf(w->error, sizeof w->error, "open: %s", tt_last_error());
      return NULL;
    }
    float img[W * H * 3];
    if (render(s, SPP, img) != TT_OK) {
      snprintf(w->error, sizeof w->error, "render: %s", tt_last_error());
      tt_session_destroy(s);
      return NULL;
    }
    w->images_equal += !memcmp(img, w->ref, sizeof img);
    /* this thread's error, read again after the other threads set theirs meanwhile */
    char key[32];
    snprintf(key, sizeof key, "noSuchParam%d", w->id);
    tt_session_set(s, "integrator_pt", key, "1");
    char mine[2048];
    snprintf(mine, sizeof mine, "%s", tt_last_error());
    usleep(20000);
    w->own_message += strstr(mine, key) != NULL && !strcmp(tt_last_error(), mine);
    if (tune(s, 2) != TT_OK) {
      snprintf(w->error, sizeof w->error, "tune: %s", tt_last_error());
      tt_session_destroy(s);
      return NULL;
    }
    tt_session_destroy(s);
    w->rounds_ok++;
  }
  return NULL;
}

static void test_session_per_thread(const float *ref) {
  enum { N = 4 };
  pthread_t th[N];
  worker w[N];
  memset(w, 0, sizeof w);
  for (int i = 0; i < N; i++) {
    w[i].id = i;
    w[i].ref = ref;
    CHECK(pthread_create(&th[i], NULL, worker_main, &w[i]) == 0);
  }
  for (int i = 0; i < N; i++) pthread_join(th[i], NULL);
  for (int i = 0; i < N; i++) {
    CHECK_MSG(w[i].rounds_ok == 3, "thread %d: %d of 3 rounds (%s)", i, w[i].rounds_ok, w[i].error);
    CHECK_MSG(w[i].images_equal == w[i].rounds_ok,
              "thread %d: %d of %d images equal a lone "
              "session's",
              i, w[i].images_equal, w[i].rounds_ok);
    CHECK_MSG(w[i].own_message == w[i].rounds_ok,
              "thread %d: its own error message in %d of "
              "%d rounds",
              i, w[i].own_message, w[i].rounds_ok);
  }
}

int main(void) {
  const char *src = getenv("TT_SOURCE_ROOT");
  if (!src) TEST_SKIP("TT_SOURCE_ROOT is not set (run through meson test)");
  snprintf(g_scene, sizeof g_scene, "%s/scenes/cornell-box/scene.json", src);
  tt_default_host_set_log_level(TT_LOG_WARN);

  /* the reference: one session alone */
  float ref[W * H * 3];
  tt_session *s = open_session();
  if (!s) return 1;
  CHECK_MSG(render(s, SPP, ref) == TT_OK, "%s", tt_last_error());
  tt_session_destroy(s);
  double sum = 0;
  for (size_t i = 0; i < sizeof ref / sizeof ref[0]; i++) sum += ref[i];
  CHECK_MSG(sum > 0.01 * W * H, "the reference image is not black (sum %g)", sum);

  test_two_alive(1, ref);
  test_two_alive(0, ref);
  test_reassign_loop(ref);
  test_session_per_thread(ref);
  return tt_test_finish("session_lifetime");
}
