/* accel_embree custom backend: configuration-space fuzz. 300 random configurations (every
 * parameter drawn uniformly, or at an end of its range one time in four; small maxDepth and
 * extreme leaf sizes are common) over two scenes. Each must either build and answer a few
 * hundred rays like the brute-force reference, or be refused with TT_ERR_INFEASIBLE and a
 * message naming what to change. Never a crash, never another status. The space's check
 * function must agree: what it calls infeasible, build refuses. */
/* Only RAYS_PER_CONFIG rays are checked per configuration: a smaller reference set. */
#define NRAYS 1500
#define CAM 16
#include "accel_embree_check.h"

#include <time.h>

#define CONFIGS 300
#define RAYS_PER_CONFIG 300

/* Draws a value for parameter `i` of `space` into `c`. */
static void draw(ae_rng *rng, const tt_space *space, tt_config *c, size_t i) {
  const char *name = tt_space_name(space, i);
  if (strcmp(name, "backend") == 0) {
    CHECK(tt_config_set_string(c, "backend", "custom") == TT_OK);
    return;
  }
  if (tt_space_type(space, i) == TT_PARAM_NOM) {
    size_t k = ae_next(rng) % tt_space_nom_count(space, i);
    CHECK(tt_config_set_index(c, i, k) == TT_OK);
    return;
  }
  double lo = tt_space_min(space, i), hi = tt_space_max(space, i), v;
  uint64_t pick = ae_next(rng) % 8;
  if (pick == 0) v = lo;
  else if (pick == 1) v = hi;
  else v = ae_uniform(rng, lo, hi);
  if (tt_space_type(space, i) == TT_PARAM_INT) v = floor(v + 0.5);
  if (v > hi) v = hi;
  CHECK_MSG(tt_config_set_number(c, i, v) == TT_OK, "%s = %g", name, v);
}

int main(void) {
  ae_plugin pl = ae_load(NULL);
  const tt_accel_iface *A = pl.accel;
  const tt_space *space = A->space();

  /* Scene 0: 3,100 random triangles (deep trees with small leaves); scene 1: 12,000
   * (where small maxDepth values really bite). */
  static const uint32_t tris0[3] = {1500, 1000, 600}, tris1[2] = {7000, 5000};
  tt_scene *scenes[2] = {ae_random_scene(0xf022, 3, tris0), ae_random_scene(0xf023, 2, tris1)};
  rayset rs[2] = {make_rayset(scenes[0], 77), make_rayset(scenes[1], 78)};

  ae_rng rng = {0xc0ffee1234ull};
  int built = 0, infeasible = 0, repaired = 0, check_infeasible = 0;
  for (int n = 0; n < CONFIGS; n++) {
    tt_config *c = tt_config_create(space);
    for (size_t i = 0; i < tt_space_count(space); i++) draw(&rng, space, c, i);
    /* counters on one config in 8 (a different kernel), compact rarely (native fallback) */
    CHECK(tt_config_set_string(c, "counters", ae_next(&rng) % 8 ? "false" : "true") == TT_OK);
    CHECK(tt_config_set_string(c, "compact", ae_next(&rng) % 16 ? "false" : "true") == TT_OK);
    char *json = tt_config_to_json(c);
    tt_config *checked = tt_config_clone(c);
    char why[256] = "";
    tt_check_result cr = tt_space_check(space, checked, why, sizeof why);
    check_infeasible += cr == TT_CHECK_INFEASIBLE;
    const int sc = n % 2;
    double t0 = (double)clock() / CLOCKS_PER_SEC;
    tt_accel_build_stats st;
    long wrong = check_config(A, c, &rs[sc], json, RAYS_PER_CONFIG, &st);
    if (wrong >= 0) {
      built++;
      repaired += st.repaired != 0;
      CHECK_MSG(wrong == 0, "config %d %s: %ld wrong answers", n, json, wrong);
      CHECK_MSG(cr != TT_CHECK_INFEASIBLE,
                "config %d %s: check says infeasible (%s) but it "
                "built",
                n, json, why);
      CHECK_MSG((cr == TT_CHECK_REPAIRED) == (st.repaired != 0),
                "config %d %s: check %d vs stats.repaired %d", n, json, (int)cr, st.repaired);
    } else {
      tt_status s = ae_last_build_status;
      const char *msg = tt_last_error();
      infeasible++;
      CHECK_MSG(s == TT_ERR_INFEASIBLE, "config %d %s: status %d: %s", n, json, (int)s, msg);
      CHECK_MSG(msg && (strstr(msg, "maxDepth") || strstr(msg, "infeasible")),
                "config %d %s: unhelpful message: %s", n, json, msg ? msg : "(null)");
    }
    double dt = (double)clock() / CLOCKS_PER_SEC - t0;
    if (dt > 0.5) printf("slow (%.2f s): %s\n", dt, json);
    tt_free(json);
    tt_config_destroy(checked);
    tt_config_destroy(c);
  }
  printf("fuzz: %d configurations: %d built and checked (%d repaired), %d refused as "
         "infeasible (check function: %d)\n",
         CONFIGS, built, repaired, infeasible, check_infeasible);
  /* the draw must exercise both outcomes */
  CHECK(built > CONFIGS / 3 && infeasible > 0);

  for (int k = 0; k < 2; k++) {
    free(rs[k].rays), free(rs[k].ref);
    tt_scene_destroy(scenes[k]);
  }
  tt_registry_destroy(pl.reg);
  return tt_test_finish("accel_embree_fuzz");
}
