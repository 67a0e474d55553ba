/* Built-in samplers: values in [0, 1), purity (any dimension order, any thread gives the same
 * number), stratification of Owen-scrambled sequences, lower L2-star discrepancy than
 * independent sampling, and decorrelation between pixels. */
#include <tunetrace/sampler.h>

#include "tt_test.h"

static const char *NAMES[3] = {"independent", "halton", "sobol"};

typedef struct smp {
  const tt_sampler_iface *it;
  tt_sampler *s;
  _Alignas(16) unsigned char state[256];
} smp;

static void smp_open(smp *m, const char *name, uint64_t seed) {
  m->it = tt_builtin_sampler(name);
  CHECK(m->it != NULL);
  CHECK(m->it->create(NULL, seed, &m->s) == TT_OK);
  CHECK(m->it->state_size(m->s) <= sizeof m->state);
}

static float smp_get(smp *m, uint32_t px, uint32_t py, uint64_t index, uint32_t dim) {
  m->it->start(m->s, m->state, px, py, index);
  return m->it->get(m->s, m->state, dim);
}

/* Squared L2-star discrepancy of n 2D points (Warnock's formula). */
static double l2_star2(const double (*p)[2], int n) {
  double a = 0.0, b = 0.0;
  for (int i = 0; i < n; ++i) {
    a += (1.0 - p[i][0] * p[i][0]) * (1.0 - p[i][1] * p[i][1]) / 4.0;
    for (int j = 0; j < n; ++j)
      b += (1.0 - fmax(p[i][0], p[j][0])) * (1.0 - fmax(p[i][1], p[j][1]));
  }
  return 1.0 / 9.0 - 2.0 * a / n + b / ((double)n * n);
}

/* Mean squared L2-star discrepancy of the first 256 points of dims (d0, d1) over 8 pixels. */
static double mean_disc(smp *m, uint32_t d0, uint32_t d1) {
  static double pts[256][2];
  double sum = 0.0;
  for (uint32_t px = 0; px < 8; ++px) {
    for (int i = 0; i < 256; ++i) {
      pts[i][0] = smp_get(m, px, 3, (uint64_t)i, d0);
      pts[i][1] = smp_get(m, px, 3, (uint64_t)i, d1);
    }
    sum += l2_star2((const double(*)[2])pts, 256);
  }
  return sum / 8.0;
}

int main(void) {
  CHECK(tt_builtin_sampler("nope") == NULL);
  CHECK(tt_builtin_sampler(NULL) == NULL);
  smp m[3];
  for (int k = 0; k < 3; ++k) {
    smp_open(&m[k], NAMES[k], 42);
    CHECK(strcmp(m[k].it->name, NAMES[k]) == 0);
    CHECK(m[k].it->struct_size == sizeof(tt_sampler_iface));
  }

  for (int k = 0; k < 3; ++k) {
    /* Range, over dimensions inside and beyond the low-discrepancy tables. */
    int bad = 0;
    double sum = 0.0;
    long count = 0;
    for (uint32_t dim = 0; dim < 300; dim += 7)
      for (uint64_t i = 0; i < 200; ++i) {
        float u = smp_get(&m[k], 5, 9, i * 977u, dim);
        bad += !(u >= 0.0f && u < 1.0f);
        sum += u;
        count++;
      }
    CHECK_MSG(bad == 0, "%s: %d values outside [0,1)", NAMES[k], bad);
    CHECK_NEAR(sum / count, 0.5, 0.02);

    /* Purity: reversed dimension order and a restart give identical values. */
    float fwd[64], rev[64];
    m[k].it->start(m[k].s, m[k].state, 17, 4, 123);
    for (uint32_t d = 0; d < 64; ++d) fwd[d] = m[k].it->get(m[k].s, m[k].state, d * 5);
    m[k].it->start(m[k].s, m[k].state, 2, 2, 7); /* somewhere else in between */
    (void)m[k].it->get(m[k].s, m[k].state, 3);
    m[k].it->start(m[k].s, m[k].state, 17, 4, 123);
    for (int d = 63; d >= 0; --d) rev[d] = m[k].it->get(m[k].s, m[k].state, (uint32_t)d * 5);
    CHECK(memcmp(fwd, rev, sizeof fwd) == 0);

    /* A second sampler object with the same seed agrees; another seed does not. */
    smp same, other;
    smp_open(&same, NAMES[k], 42);
    smp_open(&other, NAMES[k], 43);
    int diff_same = 0, diff_other = 0;
    for (uint32_t d = 0; d < 32; ++d) {
      diff_same += smp_get(&same, 17, 4, 123, d) != fwd[0] * 0 + smp_get(&m[k], 17, 4, 123, d);
      diff_other += smp_get(&other, 17, 4, 123, d) != smp_get(&m[k], 17, 4, 123, d);
    }
    CHECK(diff_same == 0);
    CHECK(diff_other > 24);
    same.it->destroy(same.s);
    other.it->destroy(other.s);

    /* Pixels are decorrelated: over a 32x32 block, the value of a sample (fixed index and
     * dimension) in one pixel does not predict its right neighbour's, and pixels never
     * share values. (Two fixed pixels compared index by index do correlate for stratified
     * sequences, by design; what matters for images is the spatial structure.) */
    for (uint64_t idx = 0; idx < 40; idx += 13) {
      for (uint32_t dim = 0; dim < 12; dim += 5) {
        double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
        int equal = 0;
        for (uint32_t py = 0; py < 32; ++py)
          for (uint32_t px = 0; px < 32; ++px) {
            double x = smp_get(&m[k], px, py, idx, dim), y = smp_get(&m[k], px + 1, py, idx, dim);
            sx += x;
            sy += y;
            sxx += x * x;
            syy += y * y;
            sxy += x * y;
            equal += x == y;
          }
        double n = 1024.0;
        double r = (sxy / n - sx / n * sy / n) /
                   sqrt((sxx / n - sx * sx / n / n) * (syy / n - sy * sy / n / n));
        /* 1/sqrt(1024) = 0.031 standard deviation of r under independence */
        CHECK_MSG(fabs(r) < 0.13, "%s: neighbouring pixels correlate, index %u dim %u r = %.3f",
                  NAMES[k], (unsigned)idx, dim, r);
        CHECK_MSG(fabs(sx / n - 0.5) < 0.05, "%s: index %u dim %u mean over pixels %.3f", NAMES[k],
                  (unsigned)idx, dim, sx / n);
        CHECK_MSG(equal < 4, "%s: index %u dim %u: %d equal neighbours", NAMES[k], (unsigned)idx,
                  dim, equal);
      }
    }
  }

  /* Stratification: the first 256 values of a 1D projection put one point in each stratum
   * of width 1/256 (Sobol, any dimension in the table; Halton base 2). */
  for (uint32_t dim = 0; dim < 64; dim += 9) {
    int hits[256] = {0}, ok = 1;
    for (uint64_t i = 0; i < 256; ++i) hits[(int)(smp_get(&m[2], 6, 1, i, dim) * 256.0f)]++;
    for (int s = 0; s < 256; ++s) ok &= hits[s] == 1;
    CHECK_MSG(ok, "sobol dim %u is not stratified", dim);
  }
  {
    int hits[256] = {0}, ok = 1;
    for (uint64_t i = 0; i < 256; ++i) hits[(int)(smp_get(&m[1], 6, 1, i, 0) * 256.0f)]++;
    for (int s = 0; s < 256; ++s) ok &= hits[s] == 1;
    CHECK_MSG(ok, "halton dim 0 is not stratified");
    /* base 3, 243 = 3^5 points: one per stratum of width 1/243 */
    int h3[243] = {0};
    ok = 1;
    for (uint64_t i = 0; i < 243; ++i) h3[(int)(smp_get(&m[1], 6, 1, i, 1) * 243.0f)]++;
    for (int s = 0; s < 243; ++s) ok &= h3[s] == 1;
    CHECK_MSG(ok, "halton dim 1 is not stratified");
  }

  /* Low discrepancy: 2D L2-star discrepancy of 256 points per pixel. */
  const uint32_t pairs[3][2] = {{0, 1}, {8, 9}, {20, 21}};
  for (int p = 0; p < 3; ++p) {
    double di = mean_disc(&m[0], pairs[p][0], pairs[p][1]);
    double dh = mean_disc(&m[1], pairs[p][0], pairs[p][1]);
    double ds = mean_disc(&m[2], pairs[p][0], pairs[p][1]);
    printf("L2* discrepancy^2 dims (%u,%u): independent %.3g halton %.3g sobol %.3g\n", pairs[p][0],
           pairs[p][1], di, dh, ds);
    /* independent: E[D^2] = (1/4 - 1/9)/256 = 5.4e-4 */
    CHECK(di > 2e-4 && di < 1e-3);
    CHECK_MSG(dh < 0.5 * di, "halton dims (%u,%u) %.3g vs independent %.3g", pairs[p][0],
              pairs[p][1], dh, di);
    CHECK_MSG(ds < (p == 0 ? 0.1 : 0.5) * di, "sobol dims (%u,%u) %.3g vs independent %.3g",
              pairs[p][0], pairs[p][1], ds, di);
  }

  for (int k = 0; k < 3; ++k) m[k].it->destroy(m[k].s);
  return tt_test_finish("sampler_builtin");
}
