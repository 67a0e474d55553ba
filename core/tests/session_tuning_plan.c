/* The tuning plan (tt_session_tuning_plan, tunetrace/session.h): the one place that decides
 * what host --tune and Python's Session.tune search.
 *
 *  - no target named: integrator_pt has no hint, so the accel, objective "render", every
 *    parameter searched but, on a still scene, the motion-only ones (the accel's update
 *    method: nothing moves to tell its values apart); on an animated scene all, and named
 *    parameters as named; integrator_pssmlt serves a hint, so it is the target with the
 *    hint's objective and tunable list (its a_i and sigma_i), binning on from the setup;
 *  - a post plugin with a hint (tests/fixtures: fixture_hint): the setup {"a": 3, "c": 2}
 *    applies, a value the user set with tt_session_set wins over it, only the hint's "b" is
 *    searched; names given by the caller replace the hint's list;
 *  - a hint whose struct_size ends before `objective` (12 bytes; host/tune.c once accepted
 *    it: the rule is offsetof + sizeof = 16) is ignored: objective "render", all searched;
 *  - errors name the plugin: not loaded (with the loaded ones), a kind that cannot be
 *    tuned, a parameter that does not exist.
 *
 * argv: the fixture plugins fixture_hint.so and fixture_hint_short.so.
 * Environment: TT_SOURCE_ROOT, TT_PLUGIN_PATH (tests/meson.build). */
#include <tunetrace/tunetrace.h>

#include "tt_test.h"

static char g_scene[4096], g_anim_scene[4096];

/* A session over the Cornell box at 8x8 with the named plugins loaded, started. */
static tt_session *open_session(const char *const *plugins, size_t n) {
  tt_session *s = NULL;
  CHECK(tt_session_create(NULL, &s) == TT_OK);
  CHECK_MSG(tt_session_load_scene(s, g_scene) == TT_OK, "%s", tt_last_error());
  tt_scene_set_resolution(tt_session_scene(s), 8, 8);
  for (size_t i = 0; i < n; i++)
    CHECK_MSG(tt_session_load_plugin(s, plugins[i], NULL) == TT_OK, "%s: %s", plugins[i],
              tt_last_error());
  return s;
}

/* The configured value of integer/bool parameter `name` of `plugin` (-1: none). */
static double value_of(tt_session *s, const char *plugin, const char *name) {
  tt_config *c = tt_session_config(s, plugin);
  return c ? (double)tt_config_get_int(c, name, -1) : -1;
}

static void test_defaults(void) {
  tt_session *s = open_session(NULL, 0);
  CHECK_MSG(tt_session_start(s, 0) == TT_OK, "%s", tt_last_error());
  tt_tuning_plan plan = {.struct_size = sizeof plan};
  CHECK_MSG(tt_session_tuning_plan(s, NULL, NULL, 0, &plan) == TT_OK, "%s", tt_last_error());
  CHECK(plan.target == tt_session_accel_plugin(s) && !strcmp(plan.objective, "render"));
  CHECK((int)plan.target_index == tt_session_plugin_index(s, "accel_embree"));
  /* a still scene: every tunable parameter but the motion-only ones (the accel's update
   * method and schedule) is searched */
  const tt_space *full = plan.space;
  CHECK(plan.space == tt_loaded_plugin_space(plan.target));
  size_t tunable = 0, motion = 0;
  for (size_t i = 0; i < tt_space_count(full); i++) {
    tunable += tt_space_is_tunable(full, i) != 0;
    motion += tt_space_is_tunable(full, i) && tt_space_is_motion_only(full, i);
  }
  CHECK_MSG(motion >= 3 && plan.search && tt_space_count(plan.search) == tunable - motion,
            "still scene: searched %zu of %zu tunable (%zu motion-only)",
            plan.search ? tt_space_count(plan.search) : 0, tunable, motion);
  CHECK(plan.search && tt_space_find(plan.search, "updateMethod") < 0 &&
        tt_space_find(plan.search, "quality") >= 0);
  tt_tuning_plan_release(&plan);
  tt_tuning_plan_release(&plan); /* twice: a released plan is empty */
  /* named parameters are searched as named, motion-only or not */
  const char *named[] = {"updateMethod", "quality"};
  CHECK(tt_session_tuning_plan(s, NULL, named, 2, &plan) == TT_OK);
  CHECK(plan.search && tt_space_count(plan.search) == 2 &&
        tt_space_find(plan.search, "updateMethod") >= 0);
  tt_tuning_plan_release(&plan);
  tt_session_destroy(s);

  /* an animated scene: everything tunable is searched, the update method included */
  s = NULL;
  CHECK(tt_session_create(NULL, &s) == TT_OK);
  CHECK_MSG(tt_session_load_scene(s, g_anim_scene) == TT_OK, "%s", tt_last_error());
  tt_scene_set_resolution(tt_session_scene(s), 8, 8);
  CHECK_MSG(tt_session_start(s, 0) == TT_OK, "%s", tt_last_error());
  CHECK(tt_scene_animated(tt_session_scene(s)));
  CHECK(tt_session_tuning_plan(s, NULL, NULL, 0, &plan) == TT_OK);
  CHECK(plan.search == NULL && plan.target == tt_session_accel_plugin(s));
  tt_tuning_plan_release(&plan);
  tt_session_destroy(s);

  /* PSSMLT's hint: target, objective, its list, binning on; the user's set wins */
  const char *mlt[] = {"integrator_pssmlt"};
  s = open_session(mlt, 1);
  CHECK(tt_session_set(s, "integrator_pssmlt", "binning", "false") == TT_OK);
  CHECK_MSG(tt_session_start(s, 0) == TT_OK, "%s", tt_last_error());
  CHECK(tt_session_tuning_plan(s, NULL, NULL, 0, &plan) == TT_OK);
  CHECK(plan.target == tt_session_integrator_plugin(s));
  const tt_tuning_hint *hint = tt_loaded_plugin_get(plan.target, TT_TUNING_HINT_ID);
  CHECK(hint && plan.objective == hint->objective);
  size_t listed = 0;
  while (hint && hint->tunable[listed]) listed++;
  CHECK_MSG(plan.search && tt_space_count(plan.search) == listed, "searched %zu of the hint's %zu",
            plan.search ? tt_space_count(plan.search) : 0, listed);
  CHECK_MSG(value_of(s, "integrator_pssmlt", "binning") == 0, "the user's binning=false wins "
                                                              "over the hint's setup");
  tt_tuning_plan_release(&plan);
  tt_session_destroy(s);
  s = open_session(mlt, 1); /* without a user value the hint's setup applies */
  CHECK(tt_session_start(s, 0) == TT_OK);
  CHECK(tt_session_tuning_plan(s, NULL, NULL, 0, &plan) == TT_OK);
  CHECK(value_of(s, "integrator_pssmlt", "binning") == 1);
  tt_tuning_plan_release(&plan);
  tt_session_destroy(s);
}

static void test_fixture_hints(const char *full, const char *short_) {
  const char *plugins[] = {full, short_};
  tt_session *s = open_session(plugins, 2);
  CHECK(tt_session_set(s, "fixture_hint", "a", "7") == TT_OK);
  CHECK_MSG(tt_session_start(s, 0) == TT_OK, "%s", tt_last_error());
  tt_tuning_plan plan = {.struct_size = sizeof plan};
  CHECK_MSG(tt_session_tuning_plan(s, "fixture_hint", NULL, 0, &plan) == TT_OK, "%s",
            tt_last_error());
  CHECK(!strcmp(plan.objective, "render"));
  CHECK(plan.search && tt_space_count(plan.search) == 1 && tt_space_find(plan.search, "b") == 0);
  CHECK_MSG(value_of(s, "fixture_hint", "a") == 7,
            "a = %g: the user's 7 wins over the "
            "setup's 3",
            value_of(s, "fixture_hint", "a"));
  CHECK_MSG(value_of(s, "fixture_hint", "c") == 2, "c = %g: the setup's 2",
            value_of(s, "fixture_hint", "c"));
  tt_tuning_plan_release(&plan);
  const char *mine[] = {"a", "c"};
  CHECK(tt_session_tuning_plan(s, "fixture_hint", mine, 2, &plan) == TT_OK);
  CHECK(plan.search && tt_space_count(plan.search) == 2 && tt_space_find(plan.search, "b") < 0);
  tt_tuning_plan_release(&plan);

  /* the short hint: 12 bytes hold struct_size and padding, not `objective` */
  CHECK_MSG(tt_session_tuning_plan(s, "fixture_hint_short", NULL, 0, &plan) == TT_OK, "%s",
            tt_last_error());
  CHECK_MSG(!strcmp(plan.objective, "render"), "objective %s read from a 12-byte hint",
            plan.objective);
  CHECK(plan.search == NULL);
  CHECK_MSG(value_of(s, "fixture_hint_short", "a") == 1, "the short hint's setup was applied");
  tt_tuning_plan_release(&plan);

  /* errors */
  CHECK(tt_session_tuning_plan(s, "nope", NULL, 0, &plan) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "no loaded plugin is called \"nope\" (loaded: fixture_hint, "
                                  "fixture_hint_short, accel_embree, integrator_pt)");
  tt_session_destroy(s);
  const char *with_tuner[] = {"tuner_nm"};
  s = open_session(with_tuner, 1);
  CHECK(tt_session_start(s, 0) == TT_OK);
  CHECK(tt_session_tuning_plan(s, "tuner_nm", NULL, 0, &plan) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "tuner_nm: a tuner plugin cannot be tuned");
  const char *bad[] = {"maxLeafSize", "nonsense"};
  CHECK(tt_session_tuning_plan(s, "accel_embree", bad, 2, &plan) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "accel_embree: searched parameters: ");
  CHECK_CONTAINS(tt_last_error(), "\"nonsense\"");
  CHECK(plan.search == NULL);
  tt_session_destroy(s);
}

int main(int argc, char **argv) {
  const char *src = getenv("TT_SOURCE_ROOT");
  if (!src || argc < 3) TEST_SKIP("run through meson test (TT_SOURCE_ROOT, fixture paths)");
  snprintf(g_scene, sizeof g_scene, "%s/scenes/cornell-box/scene.json", src);
  snprintf(g_anim_scene, sizeof g_anim_scene, "%s/scenes/animated-cornell/scene.json", src);
  tt_default_host_set_log_level(TT_LOG_WARN);
  test_defaults();
  test_fixture_hints(argv[1], argv[2]);
  return tt_test_finish("session_tuning_plan");
}
