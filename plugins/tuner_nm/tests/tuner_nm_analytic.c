/* tuner_nm on analytic functions: sphere (2 and 6 dims), Rosenbrock (2 to 4 dims), a mixed
 * INT/NOM/FLOAT function with a nominal trap, a folded-NOM space beyond the combination cap,
 * and a noisy sphere. Evaluation budgets and tolerances are the figures quoted in
 * plugins/tuner_nm/README.md; every run prints its evaluations-to-target. */
#include "tuner_nm_common.h"

#include <math.h>
#include <string.h>
#include <tt_util/rng.h>

typedef struct fn_ctx {
  int dims;
  double opt[8];
  double tol;   /* max-norm distance that counts as "reached" */
  double noise; /* standard deviation of additive Gaussian noise */
  uint64_t rng;
} fn_ctx;

/* Test-side uniform in (0, 1] (SplitMix64), independent of the tuner's generator. */
static double urand(uint64_t *s) { return tt__u64_to_unit(tt__splitmix64(s)) + 0x1p-53; }

/* Max-norm distance of the FLOAT parameters x0.. to the optimum. */
static double dist(const tt_config *c, const fn_ctx *f) {
  double m = 0.0;
  for (int i = 0; i < f->dims; i++) {
    double e = fabs(tt_config_get(c, (size_t)i).f - f->opt[i]);
    if (e > m) m = e;
  }
  return m;
}

static int reached(const tt_config *c, void *user) {
  fn_ctx *f = user;
  return dist(c, f) <= f->tol;
}

static double sphere(const tt_config *c, void *user) {
  fn_ctx *f = user;
  double s = 0.0;
  for (int i = 0; i < f->dims; i++) {
    double e = tt_config_get(c, (size_t)i).f - f->opt[i];
    s += e * e;
  }
  if (f->noise > 0.0) {
    double u1 = urand(&f->rng), u2 = urand(&f->rng);
    s += f->noise * sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
  }
  return s;
}

static double rosenbrock(const tt_config *c, void *user) {
  fn_ctx *f = user;
  double s = 0.0;
  for (int i = 0; i + 1 < f->dims; i++) {
    double x = tt_config_get(c, (size_t)i).f, y = tt_config_get(c, (size_t)i + 1).f;
    s += 100.0 * (y - x * x) * (y - x * x) + (1.0 - x) * (1.0 - x);
  }
  return s;
}

/* Space of `dims` FLOATs x0.. in [lo, hi] with default `def`. */
static tt_space *float_space(int dims, double lo, double hi, double def) {
  tt_space *s = tt_space_create("analytic", "1.0");
  char name[16];
  for (int i = 0; i < dims; i++) {
    snprintf(name, sizeof name, "x%d", i);
    tt_space_add_float(s, name, lo, hi, def, 0, NULL);
  }
  return s;
}

/* Sphere in 2 and 6 dims, optimum off-centre; default settings but a tighter tolerance so
 * that the simplex keeps contracting below 1e-2. */
static void test_sphere(const tt_tuner_iface *nm) {
  static const int dims[2] = {2, 6};
  static const int budget[2] = {60, 350};
  tt_config *set = tnm_settings(nm, "tolerance", "1e-6", NULL);
  for (int k = 0; k < 2; k++) {
    fn_ctx f = {.dims = dims[k], .tol = 1e-2};
    for (int i = 0; i < f.dims; i++) f.opt[i] = -2.0 + 0.9 * i;
    tt_space *s = float_space(f.dims, -5.0, 5.0, 0.0);
    tt_config *b = tt_config_create(s);
    for (uint64_t seed = 1; seed <= 5; seed++) {
      tnm_run r = tnm_drive(nm, s, set, seed, sphere, reached, NULL, &f, 5000, b);
      printf("sphere %dD seed %d: within 1e-2 after %d evaluations (%d total, %s)\n", f.dims,
             (int)seed, r.to_target, r.evaluations, r.done ? "done" : "budget");
      CHECK_MSG(r.to_target > 0 && r.to_target <= budget[k], "%dD seed %d: %d > %d", f.dims,
                (int)seed, r.to_target, budget[k]);
      CHECK(dist(b, &f) <= 1e-2);
    }
    tt_config_destroy(b);
    tt_space_destroy(s);
  }
  tt_config_destroy(set);
}

/* Rosenbrock in 2-4 dims on [-2,2]^d from x = 0: the curved valley is the classic hard case
 * for Nelder-Mead; restarts keep it from stalling. */
static void test_rosenbrock(const tt_tuner_iface *nm) {
  static const double tol[3] = {1e-2, 2e-2, 5e-2};
  static const int budget[3] = {200, 300, 450};
  tt_config *set = tnm_settings(nm, "tolerance", "1e-7", "restarts", "6", NULL);
  for (int d = 2; d <= 4; d++) {
    fn_ctx f = {.dims = d, .tol = tol[d - 2]};
    for (int i = 0; i < d; i++) f.opt[i] = 1.0;
    tt_space *s = float_space(d, -2.0, 2.0, 0.0);
    tt_config *b = tt_config_create(s);
    for (uint64_t seed = 1; seed <= 3; seed++) {
      tnm_run r = tnm_drive(nm, s, set, seed, rosenbrock, reached, NULL, &f, 20000, b);
      printf("rosenbrock %dD seed %d: within %g after %d evaluations (%d total, best %.3g)\n", d,
             (int)seed, f.tol, r.to_target, r.evaluations, r.best_cost);
      CHECK_MSG(r.to_target > 0 && r.to_target <= budget[d - 2], "%dD seed %d: %d > %d", d,
                (int)seed, r.to_target, budget[d - 2]);
    }
    tt_config_destroy(b);
    tt_space_destroy(s);
  }
  tt_config_destroy(set);
}

/* BVH-like mixed space: leaf size INT [1,32], branching NOM {2,4,8}, a FLOAT cost weight.
 * Every branching has its own optimum; the default branching (2) and its neighbour (8)
 * are traps, the global optimum is branching 4, leaf 11, weight 0.7. */
static double mixed(const tt_config *c, void *user) {
  (void)user;
  static const double base[3] = {0.30, 0.10, 0.15}, L[3] = {20, 11, 5}, F[3] = {0.2, 0.7, 0.4};
  int b = tt_config_get(c, 1).index;
  double leaf = (double)tt_config_get(c, 0).i, w = tt_config_get(c, 2).f;
  return base[b] + 0.02 * (leaf - L[b]) * (leaf - L[b]) + (w - F[b]) * (w - F[b]);
}

static int mixed_reached(const tt_config *c, void *user) {
  (void)user;
  return tt_config_get(c, 0).i == 11 && tt_config_get(c, 1).index == 1 &&
         fabs(tt_config_get(c, 2).f - 0.7) <= 1e-2;
}

static void test_mixed(const tt_tuner_iface *nm) {
  tt_space *s = tt_space_create("mixed", "1.0");
  static const int64_t br[3] = {2, 4, 8};
  tt_space_add_int(s, "leafSize", 1, 32, 8, NULL);
  tt_space_add_nom_int(s, "branching", br, 3, 0, NULL);
  tt_space_add_float(s, "weight", 0.0, 1.0, 0.5, 0, NULL);
  tt_config *b = tt_config_create(s);
  tt_config *set = tnm_settings(nm, "tolerance", "1e-5", NULL);
  for (uint64_t seed = 1; seed <= 8; seed++) {
    tnm_run r = tnm_drive(nm, s, set, seed, mixed, mixed_reached, NULL, NULL, 400, b);
    printf("mixed seed %d: global optimum after %d evaluations (%d total, %s, best %.6g)\n",
           (int)seed, r.to_target, r.evaluations, r.done ? "done" : "budget", r.best_cost);
    CHECK_MSG(r.to_target > 0 && r.to_target <= 150, "seed %d: %d", (int)seed, r.to_target);
    CHECK(tt_config_get(b, 0).i == 11);
    CHECK(tt_config_get_int(b, "branching", 0) == 4);
    CHECK_NEAR(tt_config_get(b, 2).f, 0.7, 1e-2);
  }
  tt_config_destroy(set);
  tt_config_destroy(b);
  tt_space_destroy(s);
}

/* accel_embree-like: 18 arms (NOM 3 x NOM 3 x bool, as quality x branchingFactor x static)
 * over 2 INTs and 4 FLOATs. Every arm is a bowl base[arm] + squared distance (in unit
 * coordinates) to its own optimum; base >= 0.15 except arm 13 (0.0), whose optimum is off
 * the default so that its probe at the default's coordinates ranks it mid-field. */
static void many_opt(int arm, double *o) {
  if (arm == 13) {
    static const double g[6] = {16, 20, 0.25, 0.75, 0.3, 0.7};
    memcpy(o, g, sizeof g);
    return;
  }
  o[0] = 2 + (arm * 5) % 29;
  o[1] = 10 + (arm * 11) % 50;
  for (int d = 0; d < 4; d++) {
    double v = (arm + 1) * (d + 1) * 0.6180339887498949;
    o[2 + d] = 0.25 + 0.5 * (v - floor(v));
  }
}

static double many_base(int arm) {
  double v = (arm + 3) * 0.7548776662466927;
  return arm == 13 ? 0.0 : 0.15 + 0.3 * (v - floor(v));
}

static double many(const tt_config *c, void *user) {
  (void)user;
  int arm =
      (int)(tt_config_get(c, 0).index * 6 + tt_config_get(c, 1).index * 2 + tt_config_get(c, 2).i);
  double o[6], span[6] = {31, 56, 1, 1, 1, 1}, s = many_base(arm);
  many_opt(arm, o);
  for (int d = 0; d < 6; d++) {
    tt_value v = tt_config_get(c, (size_t)d + 3);
    double x = d < 2 ? (double)v.i : v.f, e = (x - o[d]) / span[d];
    s += e * e;
  }
  return s;
}

static int many_reached(const tt_config *c, void *user) { return many(c, user) <= 0.01; }

static void test_many_arms(const tt_tuner_iface *nm) {
  tt_space *s = tt_space_create("many", "1.0");
  static const int64_t q[3] = {1, 2, 3}, br[3] = {4, 8, 16};
  tt_space_add_nom_int(s, "quality", q, 3, 1, NULL);
  tt_space_add_nom_int(s, "branching", br, 3, 0, NULL);
  tt_space_add_nom_bool(s, "static", 0, NULL);
  tt_space_add_int(s, "leaf", 1, 32, 8, NULL);
  tt_space_add_int(s, "depth", 8, 64, 32, NULL);
  char name[8];
  for (int d = 0; d < 4; d++) {
    snprintf(name, sizeof name, "x%d", d);
    tt_space_add_float(s, name, 0.0, 1.0, 0.5, 0, NULL);
  }
  int to[8];
  double at120[8];
  for (uint64_t seed = 1; seed <= 8; seed++) {
    tnm_run r = tnm_drive(nm, s, NULL, seed, many, many_reached, NULL, NULL, 1000, NULL);
    tnm_run r120 = tnm_drive(nm, s, NULL, seed, many, NULL, NULL, NULL, 120, NULL);
    to[seed - 1] = r.to_target > 0 ? r.to_target : 1001;
    at120[seed - 1] = r120.best_cost;
    printf("18 arms seed %d: within 0.01 of the optimum after %d evaluations; best after 120: "
           "%.4f\n",
           (int)seed, r.to_target, r120.best_cost);
    CHECK_MSG(r.to_target > 0 && r.to_target <= 700, "seed %d: %d", (int)seed, r.to_target);
    CHECK_MSG(r120.best_cost < 0.2, "seed %d: best after 120 is %g", (int)seed, r120.best_cost);
  }
  /* Medians over the 8 seeds (the tuner without the probe phase: 176 and 0.19). */
  for (int i = 1; i < 8; i++)
    for (int j = i; j > 0 && to[j] < to[j - 1]; j--) {
      int x = to[j];
      to[j] = to[j - 1];
      to[j - 1] = x;
    }
  for (int i = 1; i < 8; i++)
    for (int j = i; j > 0 && at120[j] < at120[j - 1]; j--) {
      double x = at120[j];
      at120[j] = at120[j - 1];
      at120[j - 1] = x;
    }
  double med_to = 0.5 * (to[3] + to[4]), med_b = 0.5 * (at120[3] + at120[4]);
  printf("18 arms: median %.1f evaluations to target, median best after 120: %.4f\n", med_to,
         med_b);
  CHECK_MSG(med_to <= 150, "median evaluations to target %g", med_to);
  CHECK_MSG(med_b <= 0.02, "median best after 120 %g", med_b);
  tt_space_destroy(s);
}

/* Seven booleans (128 combinations, over the 32-arm cap: five become arms, two are folded
 * into the simplex as bins) and one FLOAT: still finds the optimum. */
static double folded(const tt_config *c, void *user) {
  (void)user;
  double s = 0.0;
  for (size_t i = 0; i < 7; i++) s += (double)(tt_config_get(c, i).i != (int64_t)(i % 2)) * 0.5;
  double w = tt_config_get(c, 7).f;
  return s + (w - 0.3) * (w - 0.3);
}

static void test_folded(const tt_tuner_iface *nm) {
  tt_space *s = tt_space_create("folded", "1.0");
  char name[8];
  for (int i = 0; i < 7; i++) {
    snprintf(name, sizeof name, "b%d", i);
    tt_space_add_nom_bool(s, name, 0, NULL);
  }
  tt_space_add_float(s, "w", 0.0, 1.0, 0.5, 0, NULL);
  tt_config *b = tt_config_create(s);
  tnm_run r = tnm_drive(nm, s, NULL, 3, folded, NULL, NULL, NULL, 3000, b);
  printf("folded NOM: best %.6g after %d evaluations (%s)\n", r.best_cost, r.evaluations,
         r.done ? "done" : "budget");
  CHECK(r.best_cost < 1e-4);
  tt_config_destroy(b);
  tt_space_destroy(s);
}

/* Sphere with Gaussian noise: incumbent re-measurement (reevaluate = 1) against none. */
static void test_noisy(const tt_tuner_iface *nm) {
  tt_space *s = float_space(2, -5.0, 5.0, 0.0);
  tt_config *b = tt_config_create(s);
  const char *re[2] = {"1", "0"};
  double sum_dist[2] = {0, 0};
  for (int m = 0; m < 2; m++) {
    tt_config *set = tnm_settings(nm, "reevaluate", re[m], "tolerance", "1e-4", NULL);
    for (uint64_t seed = 1; seed <= 10; seed++) {
      fn_ctx f = {.dims = 2, .opt = {1.3, -0.7}, .tol = 0.1, .noise = 0.05, .rng = seed * 77};
      tnm_run r = tnm_drive(nm, s, set, seed, sphere, NULL, NULL, &f, 300, b);
      double d = dist(b, &f);
      sum_dist[m] += d;
      if (m == 0) CHECK_MSG(d <= 0.15, "seed %d: distance %g", (int)seed, d);
      (void)r;
    }
    tt_config_destroy(set);
  }
  printf("noisy sphere (sigma 0.05, 300 evaluations): mean distance %.4f with reevaluate=1, "
         "%.4f without\n",
         sum_dist[0] / 10, sum_dist[1] / 10);
  tt_config_destroy(b);
  tt_space_destroy(s);
}

/* The other initial simplices (uniform, centred normal) converge too. */
static void test_inits(const tt_tuner_iface *nm) {
  static const char *const inits[2] = {"uniform", "normal"};
  fn_ctx f = {.dims = 3, .opt = {1.3, -0.7, 2.2}, .tol = 1e-2};
  tt_space *s = float_space(3, -5.0, 5.0, 0.0);
  for (int k = 0; k < 2; k++) {
    tt_config *set = tnm_settings(nm, "init", inits[k], "tolerance", "1e-6", NULL);
    for (uint64_t seed = 1; seed <= 3; seed++) {
      tnm_run r = tnm_drive(nm, s, set, seed, sphere, reached, NULL, &f, 2000, NULL);
      printf("sphere 3D init %s seed %d: within 1e-2 after %d evaluations\n", inits[k], (int)seed,
             r.to_target);
      CHECK(r.to_target > 0 && r.to_target <= 200);
    }
    tt_config_destroy(set);
  }
  tt_space_destroy(s);
}

int main(void) {
  const tt_tuner_iface *nm = tnm_load();
  test_sphere(nm);
  test_rosenbrock(nm);
  test_mixed(nm);
  test_many_arms(nm);
  test_folded(nm);
  test_noisy(nm);
  test_inits(nm);
  tt_registry_destroy(tnm_reg);
  return tt_test_finish("tuner_nm_analytic");
}
