/* MIS consistency (Veach 1997, fig. 9.2 style): a small bright and a large dim area light
 * above a floor that is glossy plastic on one half and rough metal on the other. Light
 * sampling only, BSDF sampling only and MIS (power and balance) estimate the same pixels;
 * every pair must agree within 4 combined standard errors, for direct lighting and for
 * three bounces. MIS must also have a lower error than the worse single strategy. */
#include "path_common.h"
#include "tt_test.h"

static const char *SCENE =
    "{\"version\":1,\"camera\":{\"position\":[0,1.2,4],\"target\":[0,0,0],\"up\":[0,1,0],"
    "\"fov\":40,\"resolution\":[8,8]},"
    "\"materials\":{"
    "\"glossy\":{\"type\":\"plastic\",\"albedo\":[0.3,0.4,0.5],\"alpha\":0.08,\"ior\":1.5},"
    "\"metal\":{\"type\":\"conductor\",\"alpha\":[0.15,0.3]},"
    "\"small\":{\"type\":\"diffuse\",\"albedo\":[0,0,0],\"emission\":[60,50,40]},"
    "\"large\":{\"type\":\"diffuse\",\"albedo\":[0.2,0.2,0.2],\"emission\":[1.5,1.5,2],"
    "\"twoSided\":true}},"
    "\"meshes\":["
    "{\"name\":\"left\",\"material\":\"glossy\",\"positions\":[-3,0,-3, 0,0,-3, 0,0,3, "
    "-3,0,3],\"indices\":[0,2,1, 0,3,2]},"
    "{\"name\":\"right\",\"material\":\"metal\",\"positions\":[0,0,-3, 3,0,-3, 3,0,3, "
    "0,0,3],\"indices\":[0,2,1, 0,3,2]},"
    "{\"name\":\"small\",\"material\":\"small\",\"positions\":[-1.1,1.5,-1.1, -0.9,1.5,-1.1, "
    "-0.9,1.5,-0.9, -1.1,1.5,-0.9],\"indices\":[0,1,2, 0,2,3]},"
    "{\"name\":\"large\",\"material\":\"large\",\"positions\":[0.4,1.8,-1.6, 1.6,1.8,-1.6, "
    "1.6,1.8,-0.4, 0.4,1.8,-0.4],\"indices\":[0,1,2, 0,2,3]}"
    "]}";

int main(void) {
  pt_fixture f;
  CHECK(pt_fixture_load(&f, SCENE));
  if (!f.pt) return tt_test_finish("path_mis");
  const float eye[3] = {0.0f, 1.2f, 4.0f};
  /* Points on both halves, some in the glossy reflection of a light. */
  const float targets[6][3] = {{-1.0f, 0, -0.3f}, {-0.6f, 0, 0.6f}, {-1.5f, 0, -1.8f},
                               {1.0f, 0, -0.4f},  {0.6f, 0, 0.5f},  {1.8f, 0, -2.0f}};
  struct {
    tt_light_strategy s;
    tt_mis_heuristic h;
    const char *name;
  } st[4] = {{TT_STRATEGY_LIGHT, TT_MIS_POWER, "light"},
             {TT_STRATEGY_BSDF, TT_MIS_POWER, "bsdf"},
             {TT_STRATEGY_MIS, TT_MIS_POWER, "power"},
             {TT_STRATEGY_MIS, TT_MIS_BALANCE, "balance"}};
  int mis_better = 0, cases = 0;
  for (uint32_t depth = 1; depth <= 3; depth += 2) {
    for (int t = 0; t < 6; ++t) {
      tt_ray ray;
      pt_ray_towards(&ray, eye, targets[t]);
      pt_estimate e[4];
      for (int s = 0; s < 4; ++s) {
        tt_path_options o;
        tt_path_options_default(&o);
        o.max_depth = depth;
        o.rr_depth = 2;
        o.strategy = st[s].s;
        o.heuristic = st[s].h;
        /* BSDF sampling finds the small light rarely: its error estimate needs many hits. */
        uint32_t n = st[s].s == TT_STRATEGY_BSDF ? 160000 : 24000;
        pt_estimate_ray(&f, &o, &ray, n, (uint32_t)(t * 16 + s), 21 + depth, "independent", &e[s]);
        CHECK(e[s].nonfinite == 0);
      }
      printf("depth %u point %d: light %.4f+-%.4f bsdf %.4f+-%.4f power %.4f+-%.4f balance "
             "%.4f+-%.4f\n",
             depth, t, e[0].mean[0], e[0].se[0], e[1].mean[0], e[1].se[0], e[2].mean[0], e[2].se[0],
             e[3].mean[0], e[3].se[0]);
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b)
          for (int c = 0; c < 3; ++c) {
            double comb = sqrt(e[a].se[c] * e[a].se[c] + e[b].se[c] * e[b].se[c]);
            CHECK_MSG(fabs(e[a].mean[c] - e[b].mean[c]) <= 4.0 * comb + 1e-6,
                      "depth %u point %d ch %d: %s %.5f vs %s %.5f (combined se %.5f)", depth, t, c,
                      st[a].name, e[a].mean[c], st[b].name, e[b].mean[c], comb);
          }
      CHECK(e[0].mean[0] > 0.0);
      double worst = fmax(e[0].se[0], e[1].se[0]);
      mis_better += e[2].se[0] < worst;
      cases++;
    }
  }
  printf("MIS (power) beat the worse single strategy in %d of %d cases\n", mis_better, cases);
  CHECK(mis_better == cases);
  pt_fixture_free(&f);
  return tt_test_finish("path_mis");
}
