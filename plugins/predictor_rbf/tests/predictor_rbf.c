/* predictor_rbf (thesis 3.3.2) through the plugin ABI:
 *  - argmax: a model whose Q is one feature centred on a known (state, action) answers that
 *    action (NOM values exactly, INT/FLOAT within the coordinate search's last step);
 *  - learning: trained offline on samples of a synthetic cost with a known optimum per state,
 *    the predicted configuration costs within a few percent of the optimum, with the right
 *    nominal values, for inverse and relative rewards;
 *  - relative reward skips samples without a default cost; predict is deterministic and the
 *    candidates are counted; model files round-trip bit-exactly, bad files are refused;
 *  - the pool argmax (cached action distances) is the exact argmax over the pool's entries,
 *    after slots were replaced and after a load;
 *  - the default argmax (bounded, rbf_argmax.h) answers bit for bit what the reference loop
 *    answers, on full-size argmaxes, trained and loaded. */
#include "../../predictor_common/model_file.h"
#include "predictor_util.h"

#include <stdlib.h>
#include <tt_util/rng.h>

static const tt_predictor_iface *P, *NN;
static tt_space *target;

static double uni(uint64_t *x) { return tt__u64_to_unit(tt__splitmix64(x)); }

/* Synthetic cost: the optimum of state (s0, s1) is leaf-unit = s0, cost-unit = s1, quality
 * index 1, fast false; every step away costs more. */
static double synth_cost(const double *s, const tt_config *c) {
  double u[4];
  tt_config_to_unit(c, u);
  double q = tt_config_get(c, 2).index != 1 ? 0.6 : 0.0;
  double f = tt_config_get(c, 3).index ? 0.4 : 0.0;
  return 10.0 *
         (1.0 + 2.0 * (u[0] - s[0]) * (u[0] - s[0]) + 2.0 * (u[1] - s[1]) * (u[1] - s[1]) + q + f);
}

/* Writes a one-feature model file whose Q is maximal at (state, enc(best)). */
static void write_bump(const char *path, const tt_predictor *like, const double *state,
                       const tt_config *best, double width) {
  (void)like;
  char *sig = tt__pm_space_signature(target);
  tt_config *set = tt_config_create(P->space());
  tt_config_set_string(set, "features", "1");
  char wb[32];
  snprintf(wb, sizeof wb, "%g", width);
  tt_config_set_string(set, "width", wb);
  tt_config_set_string(set, "lhsCandidates", "256"); /* an empty pool: the argmax searches */
  tt_config_set_string(set, "reward", "inverse");    /* Q = 1 / cost */
  tt_config_set_string(set, "refine", "3");
  char *settings = tt_config_to_json(set);
  tt__pm_header h = {.kind = "predictor_rbf",
                     .plugin_version = "0.1.0",
                     .state_space = "synthetic",
                     .state_dim = 2,
                     .target = sig,
                     .settings = settings};
  tt__pm_writer w = {0};
  tt__pm_put_header(&w, &h);
  tt__pm_put_u64(&w, 7); /* seed */
  tt__pm_put_u64(&w, tt_space_count(target));
  uint32_t m = 1 + 1 + 3 + 1; /* leaf, cost, quality one-hot, fast */
  tt__pm_put_u64(&w, m);
  tt__pm_put_u64(&w, 1); /* features */
  tt__pm_put_u64(&w, 0); /* updates */
  tt__pm_put_u64(&w, 1); /* observations */
  double enc[8], u[4];
  tt_config_to_unit(best, u);
  enc[0] = u[0];
  enc[1] = u[1];
  for (int k = 0; k < 3; k++) enc[2 + k] = tt_config_get(best, 2).index == k;
  enc[5] = tt_config_get(best, 3).index;
  tt__pm_put_f64s(&w, state, 2);
  tt__pm_put_f64s(&w, enc, m);
  tt__pm_put_f64(&w, 1.0); /* theta */
  tt__pm_put_u64(&w, 0);   /* pool */
  CHECK(tt__pm_save("test", path, 1, &w) == TT_OK);
  free(w.data);
  free(sig);
  tt_free(settings);
  tt_config_destroy(set);
}

static void argmax_of_a_known_q(const char *dir) {
  char path[4200];
  snprintf(path, sizeof path, "%s/bump.ttpm", dir);
  tt_config *set = tt_config_create(P->space());
  tt_config_set_string(set, "features", "1");
  tt_config_set_string(set, "lhsCandidates", "256");
  tt_config_set_string(set, "refine", "3");
  tt_config_set_string(set, "reward", "inverse");
  for (int trial = 0; trial < 6; trial++) {
    double s[2] = {0.1 + 0.15 * trial, 0.9 - 0.13 * trial};
    tt_config *best = pu_config(target, 3 + 5 * trial, 0.2 + 1.5 * trial, trial % 3, trial % 2);
    write_bump(path, NULL, s, best, 2.0);
    tt_config_set_string(set, "width", "2");
    tt_predictor *p = pu_create(P, target, 2, "synthetic", set, 1);
    CHECK_MSG(P->load(p, path) == TT_OK, "%s", tt_last_error());
    tt_config *out = tt_config_create(target);
    tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = NAN};
    tt_predictor_result r = {.struct_size = sizeof r};
    CHECK(P->predict_ex(p, &q, out, &r) == TT_OK);
    double ub[4], uo[4];
    tt_config_to_unit(best, ub);
    tt_config_to_unit(out, uo);
    CHECK_MSG(tt_config_get(out, 2).index == trial % 3 && tt_config_get(out, 3).index == trial % 2,
              "trial %d: nominal values %d %d", trial, tt_config_get(out, 2).index,
              tt_config_get(out, 3).index);
    /* the last coordinate step is 1/32 of the unit range; INT rounding adds 1/62 */
    CHECK_MSG(fabs(uo[0] - ub[0]) <= 1.0 / 32 + 1.0 / 62 + 1e-9 &&
                  fabs(uo[1] - ub[1]) <= 1.0 / 32 + 1e-9,
              "trial %d: leaf %g vs %g, cost %g vs %g", trial, uo[0], ub[0], uo[1], ub[1]);
    CHECK(r.value > 0.9 && r.value <= 1.0 && r.candidates > 256);
    CHECK_NEAR(r.expected_cost, 1.0 / r.value, 1e-12); /* inverse reward: cost = 1/Q */
    tt_config_destroy(out);
    tt_config_destroy(best);
    P->destroy(p);
  }
  tt_config_destroy(set);
}

/* Trains on n samples of the synthetic cost and returns the mean relative excess cost of
 * the predictions over 40 test states (0 = always optimal); wrong nominal values counted. */
static double learn_synthetic(const char *reward, int n, int *wrong_nom, tt_predictor **keep) {
  tt_config *set = tt_config_create(P->space());
  tt_config_set_string(set, "reward", reward);
  /* the argmax over the whole space (the samples are uniform, none near an optimum) */
  tt_config_set_string(set, "lhsCandidates", "256");
  tt_config_set_string(set, "refine", "3");
  tt_config_set_string(set, "features", "200");
  tt_config_set_string(set, "width", "3");
  tt_config_set_string(set, "epochs", "40");
  tt_config_set_string(set, "alpha", "0.3");
  tt_config_set_string(set, "decay", "20000");
  tt_predictor *p = pu_create(P, target, 2, "synthetic", set, 3);
  tt_predictor_sample *samples = calloc((size_t)n, sizeof *samples);
  double(*states)[2] = calloc((size_t)n, sizeof *states);
  tt_config **cfgs = calloc((size_t)n, sizeof *cfgs);
  tt_config *def = tt_config_create(target);
  uint64_t x = 11;
  for (int i = 0; i < n; i++) {
    states[i][0] = uni(&x);
    states[i][1] = uni(&x);
    double u[4] = {uni(&x), uni(&x), uni(&x), uni(&x)};
    cfgs[i] = tt_config_create(target);
    tt_config_from_unit(cfgs[i], u);
    samples[i] = (tt_predictor_sample){.struct_size = sizeof samples[i],
                                       .state = states[i],
                                       .config = cfgs[i],
                                       .cost = synth_cost(states[i], cfgs[i]),
                                       .default_cost = synth_cost(states[i], def)};
  }
  CHECK_MSG(P->observe_ex(p, samples, (size_t)n, TT_PREDICTOR_OFFLINE) == TT_OK, "%s",
            tt_last_error());
  double excess = 0;
  *wrong_nom = 0;
  tt_config *out = tt_config_create(target);
  for (int t = 0; t < 40; t++) {
    double s[2] = {0.15 + 0.7 * uni(&x), 0.15 + 0.7 * uni(&x)};
    tt_predictor_query q = {
        .struct_size = sizeof q, .state = s, .default_cost = synth_cost(s, def)};
    tt_predictor_result r = {.struct_size = sizeof r};
    CHECK(P->predict_ex(p, &q, out, &r) == TT_OK);
    double c = synth_cost(s, out);
    excess += c / 10.0 - 1.0; /* the optimum costs 10 */
    *wrong_nom += tt_config_get(out, 2).index != 1 || tt_config_get(out, 3).index != 0;
  }
  excess /= 40;
  for (int i = 0; i < n; i++) tt_config_destroy(cfgs[i]);
  free(cfgs);
  free(states);
  free(samples);
  tt_config_destroy(out);
  tt_config_destroy(def);
  tt_config_destroy(set);
  if (keep) *keep = p;
  else P->destroy(p);
  return excess;
}

/* The default argmax (the pool alone) answers a configuration it observed, or the default:
 * with either pool source. */
static void pool_only_answers_observed(const char *source) {
  tt_config *set = tt_config_create(P->space());
  tt_config_set_string(set, "reward", "inverse"); /* the samples have no default cost */
  tt_config_set_string(set, "poolSource", source);
  tt_predictor *p = pu_create(P, target, 2, "synthetic", set, 5);
  tt_config_destroy(set);
  enum { N = 60 };
  tt_config *cfgs[N];
  double states[N][2];
  uint64_t x = 23;
  for (int i = 0; i < N; i++) {
    states[i][0] = uni(&x);
    states[i][1] = uni(&x);
    double u[4] = {uni(&x), uni(&x), uni(&x), uni(&x)};
    cfgs[i] = tt_config_create(target);
    tt_config_from_unit(cfgs[i], u);
    tt_predictor_sample smp = {.struct_size = sizeof smp,
                               .state = states[i],
                               .config = cfgs[i],
                               .cost = synth_cost(states[i], cfgs[i]),
                               .default_cost = NAN};
    CHECK(P->observe_ex(p, &smp, 1, TT_PREDICTOR_OFFLINE) == TT_OK);
  }
  tt_config *def = tt_config_create(target), *out = tt_config_create(target);
  char *dj = tt_config_to_json(def);
  for (int t = 0; t < 10; t++) {
    double s[2] = {uni(&x), uni(&x)};
    tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = NAN};
    tt_predictor_result r = {.struct_size = sizeof r};
    CHECK(P->predict_ex(p, &q, out, &r) == TT_OK);
    CHECK(r.candidates <= N + 1); /* the pool and the default, nothing else */
    char *oj = tt_config_to_json(out);
    int seen = !strcmp(oj, dj);
    for (int i = 0; i < N && !seen; i++) {
      char *cj = tt_config_to_json(cfgs[i]);
      seen = !strcmp(oj, cj);
      tt_free(cj);
    }
    CHECK_MSG(seen, "state %d: %s was never observed", t, oj);
    tt_free(oj);
  }
  tt_free(dj);
  for (int i = 0; i < N; i++) tt_config_destroy(cfgs[i]);
  tt_config_destroy(def);
  tt_config_destroy(out);
  P->destroy(p);
}

/* poolSource = states: the candidates are the observed states' best configurations by mean
 * cost (a lucky single sample does not make a configuration best), those best in most
 * states first, and the default; online observations update them; a saved model keeps its
 * state table, so a loaded copy goes on learning exactly as the original. */
static void state_pool(const char *dir) {
  tt_config *set = tt_config_create(P->space());
  tt_config_set_string(set, "poolSource", "states");
  tt_config_set_string(set, "reward", "inverse"); /* the samples have no default cost */
  tt_predictor *p = pu_create(P, target, 2, "synthetic", set, 3);
  tt_config *a = pu_config(target, 4, 0.5, 0, 1), *b = pu_config(target, 20, 3.0, 2, 0);
  tt_config *c = pu_config(target, 30, 6.0, 1, 1), *def = tt_config_create(target);
  double st[4][2] = {{0.1, 0.2}, {0.8, 0.3}, {0.4, 0.9}, {0.6, 0.6}};
  /* state 0: A 10, B 12, C 15; state 1: A 9, B 11, C 30; state 2: A 14, B 10 and 11, C 5
   * and 20 (C's single 5 is the lowest cost seen, its mean 12.5 loses to B's 10.5) */
  struct {
    int s;
    tt_config *cfg;
    double cost;
  } obs[] = {{0, a, 10}, {0, b, 12}, {0, c, 15}, {1, a, 9},  {1, b, 11}, {1, c, 30},
             {2, a, 14}, {2, b, 10}, {2, c, 5},  {2, b, 11}, {2, c, 20}};
  enum { NO = sizeof obs / sizeof obs[0] };
  tt_predictor_sample smp[NO];
  for (int i = 0; i < NO; i++)
    smp[i] = (tt_predictor_sample){.struct_size = sizeof smp[i],
                                   .state = st[obs[i].s],
                                   .config = obs[i].cfg,
                                   .cost = obs[i].cost,
                                   .default_cost = NAN};
  CHECK(P->observe_ex(p, smp, NO, TT_PREDICTOR_OFFLINE) == TT_OK);
  char *aj = tt_config_to_json(a), *bj = tt_config_to_json(b), *cj = tt_config_to_json(c);
  char *dj = tt_config_to_json(def);
  tt_config *out = tt_config_create(target);
  uint64_t x = 77;
  for (int t = 0; t < 20; t++) {
    double s[2] = {uni(&x), uni(&x)};
    tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = NAN};
    tt_predictor_result r = {.struct_size = sizeof r};
    CHECK(P->predict_ex(p, &q, out, &r) == TT_OK);
    CHECK_MSG(r.candidates == 3,
              "%llu candidates: the pool must be A and B (the states' "
              "bests) and the default",
              (unsigned long long)r.candidates);
    char *oj = tt_config_to_json(out);
    CHECK_MSG(!strcmp(oj, aj) || !strcmp(oj, bj) || !strcmp(oj, dj), "answer %s is no state's best",
              oj);
    /* the answer is the argmax of estimate() over the three candidates */
    double ca, cb, cd, co;
    CHECK(P->estimate(p, &q, a, &ca) == TT_OK && P->estimate(p, &q, b, &cb) == TT_OK &&
          P->estimate(p, &q, def, &cd) == TT_OK && P->estimate(p, &q, out, &co) == TT_OK);
    CHECK_MSG(co <= ca * (1 + 1e-12) && co <= cb * (1 + 1e-12) && co <= cd * (1 + 1e-12),
              "answer's expected cost %g, A %g, B %g, default %g", co, ca, cb, cd);
    tt_free(oj);
  }
  /* saved and loaded: the same answers; both learn one more state (C best there) alike */
  char path[4200];
  snprintf(path, sizeof path, "%s/states.ttpm", dir);
  CHECK_MSG(P->save(p, path) == TT_OK, "%s", tt_last_error());
  tt_predictor *l = pu_create(P, target, 2, "synthetic", set, 99);
  CHECK_MSG(P->load(l, path) == TT_OK, "%s", tt_last_error());
  char *pa = pu_predictions(P, p, target, 2, 100), *pb = pu_predictions(P, l, target, 2, 100);
  CHECK(!strcmp(pa, pb));
  free(pa);
  free(pb);
  tt_predictor_sample more = {
      .struct_size = sizeof more, .state = st[3], .config = c, .cost = 2, .default_cost = NAN};
  CHECK(P->observe(p, st[3], c, 2.0) == TT_OK);
  CHECK(P->observe_ex(l, &more, 1, TT_PREDICTOR_ONLINE) == TT_OK);
  pa = pu_predictions(P, p, target, 2, 100);
  pb = pu_predictions(P, l, target, 2, 100);
  CHECK_MSG(!strcmp(pa, pb), "the loaded model learnt differently: its state table was not kept");
  free(pa);
  free(pb);
  tt_predictor_query q = {.struct_size = sizeof q, .state = st[3], .default_cost = NAN};
  tt_predictor_result r = {.struct_size = sizeof r};
  CHECK(P->predict_ex(p, &q, out, &r) == TT_OK);
  CHECK_MSG(r.candidates == 4, "%llu candidates after C became a state's best",
            (unsigned long long)r.candidates);
  /* the file properties of a states model (cut short, corrupt, other spaces, newer format) */
  pu_check_files(P, p, target, 2, "synthetic", dir, NN, set, 2);
  tt_free(aj);
  tt_free(bj);
  tt_free(cj);
  tt_free(dj);
  tt_config_destroy(a);
  tt_config_destroy(b);
  tt_config_destroy(c);
  tt_config_destroy(def);
  tt_config_destroy(out);
  tt_config_destroy(set);
  P->destroy(p);
  P->destroy(l);
}

/* The pool argmax with its cached action distances (pool_da) answers the exact argmax over
 * what the pool must hold: with poolSize 16 and 60 distinct observed configurations (so slots
 * are replaced), the 16 highest rewards (lowest costs) and the default. estimate() is the
 * reference Q (tt__rbf_q, every distance summed afresh); the answer must be one of those 17 and
 * within 1e-12 of their lowest expected cost. A stale cached distance (a replaced slot, a
 * loaded file) moves Q far more than that. */
static void pool_argmax_is_exact(const char *dir) {
  tt_config *set = tt_config_create(P->space());
  tt_config_set_string(set, "poolSize", "16");
  tt_config_set_string(set, "poolSource", "rewards");
  tt_config_set_string(set, "reward", "inverse");
  tt_predictor *p = pu_create(P, target, 2, "synthetic", set, 8);
  enum { N = 60, K = 16 };
  tt_config *cfgs[N + 1];
  double cost[N];
  uint64_t x = 41;
  for (int i = 0; i < N; i++) {
    double st[2] = {uni(&x), uni(&x)}, u[4] = {uni(&x), uni(&x), uni(&x), uni(&x)};
    cfgs[i] = tt_config_create(target);
    tt_config_from_unit(cfgs[i], u);
    cost[i] = synth_cost(st, cfgs[i]);
    tt_predictor_sample smp = {.struct_size = sizeof smp,
                               .state = st,
                               .config = cfgs[i],
                               .cost = cost[i],
                               .default_cost = NAN};
    CHECK(P->observe_ex(p, &smp, 1, i % 2 ? TT_PREDICTOR_ONLINE : TT_PREDICTOR_OFFLINE) == TT_OK);
  }
  /* the K lowest costs, and the default */
  int in[N + 1] = {0};
  for (int k = 0; k < K; k++) {
    int b = -1;
    for (int i = 0; i < N; i++)
      if (!in[i] && (b < 0 || cost[i] < cost[b])) b = i;
    in[b] = 1;
  }
  cfgs[N] = tt_config_create(target);
  in[N] = 1;
  char path[4200];
  snprintf(path, sizeof path, "%s/pool.ttpm", dir);
  CHECK_MSG(P->save(p, path) == TT_OK, "%s", tt_last_error());
  tt_predictor *loaded = pu_create(P, target, 2, "synthetic", set, 99);
  CHECK_MSG(P->load(loaded, path) == TT_OK, "%s", tt_last_error());
  /* a pool reward that no observation gives (NaN, 0, negative; the last 8 payload bytes,
   * resealed): refused naming it (a NaN reward was never replaced, silently) */
  {
    long n;
    unsigned char *bytes = pu_read(path, &n);
    static const double rewards[] = {NAN, 0.0, -1.0};
    char bad[4300];
    snprintf(bad, sizeof bad, "%s/bad-reward.ttpm", dir);
    for (int i = 0; bytes && i < 3; i++) {
      uint64_t u;
      memcpy(&u, &rewards[i], 8);
      for (int k = 0; k < 8; k++) bytes[n - 16 + k] = (unsigned char)(u >> (8 * k));
      pu_reseal(bytes, n);
      pu_write(bad, bytes, n);
      tt_predictor *z = pu_create(P, target, 2, "synthetic", set, 1);
      CHECK(P->load(z, bad) == TT_ERR_PARSE);
      CHECK_CONTAINS(tt_last_error(), bad);
      CHECK_CONTAINS(tt_last_error(), "pool reward 15");
      P->destroy(z);
    }
    free(bytes);
  }
  tt_config *out = tt_config_create(target);
  for (int t = 0; t < 20; t++) {
    double s[2] = {uni(&x), uni(&x)};
    tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = NAN};
    for (int which = 0; which < 2; which++) {
      tt_predictor *m = which ? loaded : p;
      tt_predictor_result r = {.struct_size = sizeof r};
      CHECK(P->predict_ex(m, &q, out, &r) == TT_OK);
      CHECK(r.candidates == K + 1);
      double best = INFINITY, got = NAN;
      char *oj = tt_config_to_json(out);
      for (int i = 0; i <= N; i++) {
        if (!in[i]) continue;
        double ec;
        CHECK(P->estimate(m, &q, cfgs[i], &ec) == TT_OK);
        if (ec < best) best = ec;
        char *cj = tt_config_to_json(cfgs[i]);
        if (!strcmp(cj, oj)) got = ec;
        tt_free(cj);
      }
      CHECK_MSG(isfinite(got), "state %d: %s is not in the pool", t, oj);
      CHECK_MSG(got <= best * (1 + 1e-12),
                "state %d (%s): expected cost %.17g, the pool's best "
                "%.17g",
                t, which ? "loaded" : "trained", got, best);
      CHECK_NEAR(r.expected_cost, got, 1e-12 * got);
      tt_free(oj);
    }
  }
  for (int i = 0; i <= N; i++) tt_config_destroy(cfgs[i]);
  tt_config_destroy(out);
  tt_config_destroy(set);
  P->destroy(p);
  P->destroy(loaded);
}

/* The default argmax (no refinement: tt__rbf_argmax_bounded, Q approximated with bounds and
 * evaluated exactly only where they cannot decide) answers exactly what the reference loop
 * answers (tt__rbf_q_parts for every candidate, taken with refine 1 and refineStarts 0, which
 * computes every Q and refines nothing): the same configuration and the same bits of Q, on
 * full-size argmaxes (a pool of up to 256 with slots replaced, 200 LHS points, the default),
 * for a trained model and the same model loaded from its file. */
static void bounded_argmax_matches_reference(const char *dir) {
  tt_config *fast = tt_config_create(P->space()), *ref = tt_config_create(P->space());
  tt_config_set_string(fast, "lhsCandidates", "200");
  tt_config_set_string(ref, "lhsCandidates", "200");
  tt_config_set_string(fast, "reward", "inverse"); /* its samples have no default cost */
  tt_config_set_string(ref, "reward", "inverse");
  tt_config_set_string(ref, "refine", "1");
  tt_config_set_string(ref, "refineStarts", "0");
  tt_predictor *a = pu_create(P, target, 2, "synthetic", fast, 5);
  tt_predictor *b = pu_create(P, target, 2, "synthetic", ref, 5);
  uint64_t x = 77;
  tt_config *c = tt_config_create(target);
  for (int i = 0; i < 400; i++) {
    double st[2] = {uni(&x), uni(&x)}, u[4] = {uni(&x), uni(&x), uni(&x), uni(&x)};
    tt_config_from_unit(c, u);
    tt_predictor_sample smp = {.struct_size = sizeof smp,
                               .state = st,
                               .config = c,
                               .cost = synth_cost(st, c),
                               .default_cost = NAN};
    uint32_t fl = i % 3 ? TT_PREDICTOR_ONLINE : TT_PREDICTOR_OFFLINE;
    CHECK(P->observe_ex(a, &smp, 1, fl) == TT_OK && P->observe_ex(b, &smp, 1, fl) == TT_OK);
  }
  char path[4200];
  snprintf(path, sizeof path, "%s/bounded.ttpm", dir);
  CHECK_MSG(P->save(a, path) == TT_OK, "%s", tt_last_error());
  tt_predictor *loaded = pu_create(P, target, 2, "synthetic", fast, 99);
  CHECK_MSG(P->load(loaded, path) == TT_OK, "%s", tt_last_error());
  tt_config *oa = tt_config_create(target), *ob = tt_config_create(target);
  int differ = 0;
  for (int t = 0; t < 200; t++) {
    double s[2] = {uni(&x), uni(&x)};
    tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = NAN};
    tt_predictor_result rb = {.struct_size = sizeof rb};
    CHECK(P->predict_ex(b, &q, ob, &rb) == TT_OK);
    char *jb = tt_config_to_json(ob);
    for (int which = 0; which < 2; which++) {
      tt_predictor_result ra = {.struct_size = sizeof ra};
      CHECK(P->predict_ex(which ? loaded : a, &q, oa, &ra) == TT_OK);
      char *ja = tt_config_to_json(oa);
      int same = !strcmp(ja, jb) && !memcmp(&ra.value, &rb.value, sizeof ra.value) &&
                 ra.candidates == rb.candidates;
      if (!same && differ++ < 3)
        fprintf(stderr, "state %d (%s): %s Q %.17g, reference %s Q %.17g\n", t,
                which ? "loaded" : "trained", ja, ra.value, jb, rb.value);
      tt_free(ja);
    }
    CHECK(rb.candidates > 200); /* the pool, the LHS points that passed the check, the default */
    tt_free(jb);
  }
  CHECK_MSG(differ == 0, "%d of 400 predictions differ from the reference loop's", differ);
  tt_config_destroy(c);
  tt_config_destroy(oa);
  tt_config_destroy(ob);
  tt_config_destroy(fast);
  tt_config_destroy(ref);
  P->destroy(a);
  P->destroy(b);
  P->destroy(loaded);
}

static void relative_reward(void) {
  tt_config *set = tt_config_create(P->space());
  tt_config_set_string(set, "reward", "relative");
  tt_predictor *p = pu_create(P, target, 2, "synthetic", set, 3);
  double s[2] = {0.5, 0.5};
  tt_config *c = pu_config(target, 4, 1.0, 1, 0);
  tt_predictor_sample x = {
      .struct_size = sizeof x, .state = s, .config = c, .cost = 5.0, .default_cost = NAN};
  CHECK(P->observe_ex(p, &x, 1, TT_PREDICTOR_ONLINE) == TT_OK);
  tt_predictor_info info = {.struct_size = sizeof info};
  P->info(p, &info);
  CHECK(info.observations == 0); /* no default cost: no relative reward */
  x.default_cost = 10.0;
  for (int k = 0; k < 400; k++) CHECK(P->observe_ex(p, &x, 1, TT_PREDICTOR_ONLINE) == TT_OK);
  P->info(p, &info);
  CHECK(info.observations == 400 && info.entries == 21); /* round(3.5 x (2 + 4)) */
  /* Q -> the speed-up 2; the expected cost needs the query's default cost */
  tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = 8.0};
  double ec;
  CHECK(P->estimate(p, &q, c, &ec) == TT_OK);
  CHECK_NEAR(ec, 4.0, 0.05);
  q.default_cost = NAN;
  CHECK(P->estimate(p, &q, c, &ec) == TT_OK && isnan(ec));
  x.cost = NAN;
  CHECK(P->observe_ex(p, &x, 1, TT_PREDICTOR_ONLINE) == TT_ERR_INVALID_ARGUMENT);
  tt_config_destroy(c);
  tt_config_destroy(set);
  P->destroy(p);
}

int main(int argc, char **argv) {
  (void)argc, (void)argv;
  char tmp[] = "/tmp/tt_prbf_XXXXXX";
  const char *dir = mkdtemp(tmp);
  tt_registry *reg, *reg2;
  P = pu_load(&reg, "predictor_rbf");
  NN = pu_load(&reg2, "predictor_nn");
  target = pu_target("target");

  tt_predictor *e = pu_create(P, target, 2, "synthetic", NULL, 1);
  double s0[2] = {0.5, 0.5};
  tt_config *out = tt_config_create(target);
  double ec;
  CHECK(P->predict(e, s0, out, &ec) == TT_ERR_NO_DATA);
  P->destroy(e);

  argmax_of_a_known_q(dir);
  pool_only_answers_observed("rewards");
  pool_only_answers_observed("states");
  state_pool(dir);
  pool_argmax_is_exact(dir);
  bounded_argmax_matches_reference(dir);
  relative_reward();

  int wrong;
  tt_predictor *trained = NULL;
  double ex = learn_synthetic("inverse", 3000, &wrong, &trained);
  printf("synthetic, inverse reward: mean excess cost %.4f, wrong nominal values %d/40\n", ex,
         wrong);
  CHECK_MSG(ex < 0.05 && wrong <= 2, "inverse: excess %g, wrong %d", ex, wrong);
  ex = learn_synthetic("relative", 3000, &wrong, NULL);
  printf("synthetic, relative reward: mean excess cost %.4f, wrong nominal values %d/40\n", ex,
         wrong);
  CHECK_MSG(ex < 0.05 && wrong <= 2, "relative: excess %g, wrong %d", ex, wrong);

  /* deterministic: the same seed and data give the same predictions */
  tt_predictor *again = NULL;
  learn_synthetic("inverse", 3000, &wrong, &again);
  char *a = pu_predictions(P, trained, target, 2, 50), *b = pu_predictions(P, again, target, 2, 50);
  CHECK(!strcmp(a, b));
  free(a);
  free(b);
  P->destroy(again);

  tt_config *set = tt_config_create(P->space());
  tt_config_set_string(set, "features", "200");
  tt_config_set_string(set, "width", "3");
  tt_config_set_string(set, "epochs", "40");
  tt_config_set_string(set, "alpha", "0.3");
  tt_config_set_string(set, "decay", "20000");
  tt_config_set_string(set, "lhsCandidates", "256");
  tt_config_set_string(set, "refine", "3");
  pu_check_files(P, trained, target, 2, "synthetic", dir, NN, set, 2);
  tt_config_destroy(set);

  P->destroy(trained);
  tt_config_destroy(out);
  tt_space_destroy(target);
  tt_registry_destroy(reg);
  tt_registry_destroy(reg2);
  char cmd[256];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
  if (system(cmd)) {}
  return tt_test_finish("predictor_rbf");
}
