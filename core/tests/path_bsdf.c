/* BSDF unit tests (white-box, core/src/render/bsdf.c compiled in), for every material type:
 *  - directional albedo (integral of f cos over the sphere, estimated with the BSDF's own
 *    sampling) <= 1 for several incoming angles, and = albedo exactly for Lambert;
 *  - the albedo from uniform sphere sampling of eval() agrees with the importance-sampled
 *    one (eval, pdf and sample describe the same function);
 *  - reciprocity f(wo, wi) = f(wi, wo) for the non-delta BSDFs;
 *  - the pdf integrates to <= 1 over the sphere, and to the fraction of successful samples;
 *  - chi-square goodness of fit of sampled directions against the pdf on a theta/phi grid
 *    (as pbrt's and Mitsuba's BSDF tests), at a fixed seed;
 *  - delta lobes: mirror direction and weight; glass Fresnel split, Snell's law and TIR;
 *  - rough glass (GGX transmission, Walter 2007) from both sides: the same albedo, pdf and
 *    chi-square checks over the whole sphere, generalised reciprocity
 *    f(wo, wi) / eta_o^2 = f(wi, wo) / eta_i^2, and convergence to smooth glass as alpha -> 0;
 *  - adjoint (importance) sampling for light subpaths: the same direction and pdf as
 *    radiance sampling, f the adjoint f(wi, wo) for every BSDF, and glass that conserves
 *    importance exactly (R + T = 1, where radiance carries R + T / eta'^2) from both sides. */
#include <stdlib.h>

#include "../src/render/bsdf_internal.h"
#include <tt_util/rng.h>
#include "tt_test.h"

typedef struct named_material {
  const char *name;
  tt_material m;
} named_material;

static tt_material base_material(tt_material_type type) {
  tt_material m;
  memset(&m, 0, sizeof m);
  m.struct_size = sizeof m;
  m.name = "test";
  m.type = type;
  m.albedo_texture = -1;
  for (int i = 0; i < 3; ++i) m.specular[i] = 1.0f;
  m.ior = 1.5f;
  return m;
}

/* Uniform direction on the sphere. */
static void uniform_sphere(float u1, float u2, float w[3]) {
  float z = 1.0f - 2.0f * u1, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 2.0f * (float)M_PI * u2;
  w[0] = r * cosf(phi);
  w[1] = r * sinf(phi);
  w[2] = z;
}

static void dir_from_angles(float theta, float phi, float w[3]) {
  w[0] = sinf(theta) * cosf(phi);
  w[1] = sinf(theta) * sinf(phi);
  w[2] = cosf(theta);
}

/* Albedo by importance sampling (mean, se of f cos / pdf) and by uniform sphere sampling. */
static void albedo_estimates(const tt__bsdf *b, const float wo[3], int n, tt__pcg32 *rng,
                             double is_mean[3], double is_se[3], double us_mean[3], double us_se[3],
                             double *success) {
  double s1[3] = {0}, s2[3] = {0}, u1s[3] = {0}, u2s[3] = {0};
  int ok = 0;
  for (int i = 0; i < n; ++i) {
    tt__bsdf_result s;
    float ul = tt__pcg32_float(rng), a = tt__pcg32_float(rng), c = tt__pcg32_float(rng);
    if (tt__bsdf_sample(b, wo, ul, a, c, &s)) {
      ok++;
      for (int k = 0; k < 3; ++k) {
        double w = s.f[k] * fabsf(s.wi[2]) / s.pdf;
        s1[k] += w;
        s2[k] += w * w;
      }
    }
    float wi[3], f[3];
    uniform_sphere(tt__pcg32_float(rng), tt__pcg32_float(rng), wi);
    tt__bsdf_eval(b, wo, wi, f);
    for (int k = 0; k < 3; ++k) {
      double w = f[k] * fabsf(wi[2]) * 4.0 * M_PI;
      u1s[k] += w;
      u2s[k] += w * w;
    }
  }
  for (int k = 0; k < 3; ++k) {
    is_mean[k] = s1[k] / n;
    is_se[k] = sqrt(fmax(0.0, s2[k] / n - is_mean[k] * is_mean[k]) / n);
    us_mean[k] = u1s[k] / n;
    us_se[k] = sqrt(fmax(0.0, u2s[k] / n - us_mean[k] * us_mean[k]) / n);
  }
  *success = (double)ok / n;
}

/* Integral of the pdf over the sphere by a midpoint grid uniform in (theta, phi), weighted
 * by sin theta: unlike a grid uniform in cos theta it resolves the narrow transmission lobe
 * that rough glass sends to a pole at normal incidence. */
static double pdf_integral(const tt__bsdf *b, const float wo[3], int nth, int nphi) {
  double sum = 0.0;
  for (int i = 0; i < nth; ++i) {
    double th = M_PI * (i + 0.5) / nth, st = sin(th);
    float z = (float)cos(th), r = (float)st;
    for (int j = 0; j < nphi; ++j) {
      float phi = 2.0f * (float)M_PI * ((float)j + 0.5f) / (float)nphi;
      float wi[3] = {r * cosf(phi), r * sinf(phi), z};
      sum += tt__bsdf_pdf(b, wo, wi) * st;
    }
  }
  return sum * 2.0 * M_PI * M_PI / ((double)nth * nphi);
}

/* Upper tail probability of chi-square with k degrees of freedom (Wilson-Hilferty). */
static double chi2_pvalue(double x, int k) {
  double z = (pow(x / k, 1.0 / 3.0) - (1.0 - 2.0 / (9.0 * k))) / sqrt(2.0 / (9.0 * k));
  return 0.5 * erfc(z / sqrt(2.0));
}

#define TH_BINS 10
#define PH_BINS 20

/* Chi-square test of n sampled directions against the pdf on a theta x phi grid; expected
 * bin masses integrated with a 24x24 sub-grid uniform in (theta, phi), sin-weighted. */
static double chi2_test(const tt__bsdf *b, const float wo[3], int n, tt__pcg32 *rng, int *dof_out) {
  static double observed[TH_BINS * PH_BINS], expected[TH_BINS * PH_BINS];
  memset(observed, 0, sizeof observed);
  for (int i = 0; i < n; ++i) {
    tt__bsdf_result s;
    float ul = tt__pcg32_float(rng), a = tt__pcg32_float(rng), c = tt__pcg32_float(rng);
    if (!tt__bsdf_sample(b, wo, ul, a, c, &s)) continue;
    float z = fminf(1.0f, fmaxf(-1.0f, s.wi[2]));
    int ti = (int)(acosf(z) / (float)M_PI * TH_BINS);
    float phi = atan2f(s.wi[1], s.wi[0]);
    if (phi < 0.0f) phi += 2.0f * (float)M_PI;
    int pi = (int)(phi / (2.0f * (float)M_PI) * PH_BINS);
    if (ti >= TH_BINS) ti = TH_BINS - 1;
    if (pi >= PH_BINS) pi = PH_BINS - 1;
    observed[ti * PH_BINS + pi] += 1.0;
  }
  const int sub = 24;
  for (int ti = 0; ti < TH_BINS; ++ti) {
    double t0 = M_PI * ti / TH_BINS, t1 = M_PI * (ti + 1) / TH_BINS;
    for (int pi = 0; pi < PH_BINS; ++pi) {
      double p0 = 2.0 * M_PI * pi / PH_BINS, p1 = 2.0 * M_PI * (pi + 1) / PH_BINS, sum = 0.0;
      for (int a = 0; a < sub; ++a) {
        double th = t0 + (t1 - t0) * (a + 0.5) / sub, z = cos(th), r = sin(th);
        for (int c = 0; c < sub; ++c) {
          double phi = p0 + (p1 - p0) * (c + 0.5) / sub;
          float wi[3] = {(float)(r * cos(phi)), (float)(r * sin(phi)), (float)z};
          sum += tt__bsdf_pdf(b, wo, wi) * r;
        }
      }
      expected[ti * PH_BINS + pi] = sum * (t1 - t0) * (p1 - p0) / (sub * sub) * n;
    }
  }
  /* Pool bins expecting fewer than 5 samples. */
  double chi2 = 0.0, pool_o = 0.0, pool_e = 0.0;
  int dof = 0;
  for (int i = 0; i < TH_BINS * PH_BINS; ++i) {
    if (expected[i] < 5.0) {
      pool_o += observed[i];
      pool_e += expected[i];
      continue;
    }
    double d = observed[i] - expected[i];
    chi2 += d * d / expected[i];
    dof++;
  }
  if (pool_e > 0.0 || pool_o > 0.0) {
    double d = pool_o - pool_e;
    chi2 += d * d / fmax(pool_e, 1.0);
    dof++;
  }
  *dof_out = dof - 1;
  return chi2_pvalue(chi2, dof - 1 > 0 ? dof - 1 : 1);
}

int main(void) {
  named_material mats[12];
  int nm = 0;
  mats[nm].name = "lambert";
  mats[nm].m = base_material(TT_MATERIAL_DIFFUSE);
  mats[nm].m.albedo[0] = 0.8f;
  mats[nm].m.albedo[1] = 0.5f;
  mats[nm].m.albedo[2] = 1.0f;
  nm++;
  mats[nm].name = "oren-nayar";
  mats[nm].m = base_material(TT_MATERIAL_DIFFUSE);
  mats[nm].m.albedo[0] = mats[nm].m.albedo[1] = mats[nm].m.albedo[2] = 1.0f;
  mats[nm].m.roughness = 0.6f;
  nm++;
  mats[nm].name = "conductor-iso";
  mats[nm].m = base_material(TT_MATERIAL_CONDUCTOR);
  mats[nm].m.alpha[0] = mats[nm].m.alpha[1] = 0.3f;
  {
    const float eta[3] = {0.143f, 0.374f, 1.442f}, k[3] = {3.983f, 2.385f, 1.603f};
    memcpy(mats[nm].m.eta, eta, sizeof eta);
    memcpy(mats[nm].m.k, k, sizeof k);
  }
  nm++;
  mats[nm].name = "conductor-aniso";
  mats[nm].m = mats[nm - 1].m;
  mats[nm].m.alpha[0] = 0.08f;
  mats[nm].m.alpha[1] = 0.4f;
  nm++;
  mats[nm].name = "conductor-white"; /* k = 0, eta = huge: F ~ 1, tests G2's energy loss */
  mats[nm].m = base_material(TT_MATERIAL_CONDUCTOR);
  mats[nm].m.alpha[0] = mats[nm].m.alpha[1] = 0.8f;
  for (int i = 0; i < 3; ++i) {
    mats[nm].m.eta[i] = 1000.0f;
    mats[nm].m.k[i] = 0.0f;
  }
  nm++;
  mats[nm].name = "plastic";
  mats[nm].m = base_material(TT_MATERIAL_PLASTIC);
  mats[nm].m.albedo[0] = 1.0f;
  mats[nm].m.albedo[1] = 0.6f;
  mats[nm].m.albedo[2] = 0.2f;
  mats[nm].m.alpha[0] = mats[nm].m.alpha[1] = 0.2f;
  nm++;
  mats[nm].name = "plastic-sharp";
  mats[nm].m = mats[nm - 1].m;
  mats[nm].m.albedo[0] = mats[nm].m.albedo[1] = mats[nm].m.albedo[2] = 1.0f;
  mats[nm].m.alpha[0] = 0.05f;
  mats[nm].m.alpha[1] = 0.1f;
  nm++;
  mats[nm].name = "rough-glass";
  mats[nm].m = base_material(TT_MATERIAL_DIELECTRIC);
  mats[nm].m.alpha[0] = mats[nm].m.alpha[1] = 0.3f;
  mats[nm].m.ior = 1.5f;
  nm++;
  mats[nm].name = "rough-glass-aniso";
  mats[nm].m = mats[nm - 1].m;
  mats[nm].m.alpha[0] = 0.12f;
  mats[nm].m.alpha[1] = 0.35f;
  mats[nm].m.ior = 1.33f;
  mats[nm].m.specular[2] = 0.5f;
  nm++;

  tt__pcg32 rng;
  tt__pcg32_seed(&rng, 12345, 678);
  /* Glass is also seen from inside (theta > pi/2), beyond the critical angle for the last. */
  const float thetas[6] = {0.0f, 0.5f, 1.0f, 1.4f, (float)M_PI - 0.3f, (float)M_PI - 1.2f};

  for (int i = 0; i < nm; ++i) {
    tt__bsdf b;
    CHECK(tt__bsdf_init(&b, &mats[i].m) == TT_OK);
    CHECK(!b.delta);
    const int glass = mats[i].m.type == TT_MATERIAL_DIELECTRIC;
    for (int t = 0; t < (glass ? 6 : 4); ++t) {
      float wo[3];
      dir_from_angles(thetas[t], 0.3f, wo);
      /* Radiance entering a denser medium is concentrated by eta^2 (radiance transport). */
      const double bound = glass && wo[2] < 0.0f ? (double)mats[i].m.ior * mats[i].m.ior : 1.0;
      double is_m[3], is_se[3], us_m[3], us_se[3], success;
      albedo_estimates(&b, wo, 200000, &rng, is_m, is_se, us_m, us_se, &success);
      double integral = pdf_integral(&b, wo, 1000, 2000);
      printf("%-16s theta %.1f: albedo IS %.4f %.4f %.4f (se %.4f) uniform %.4f  int pdf %.4f  "
             "success %.4f\n",
             mats[i].name, thetas[t], is_m[0], is_m[1], is_m[2], is_se[0], us_m[0], integral,
             success);
      for (int k = 0; k < 3; ++k) {
        CHECK_MSG(is_m[k] <= bound + 3.0 * is_se[k] + 1e-4, "%s theta %.1f: albedo %.4f > %.2f",
                  mats[i].name, thetas[t], is_m[k], bound);
        double comb = sqrt(is_se[k] * is_se[k] + us_se[k] * us_se[k]);
        CHECK_MSG(fabs(is_m[k] - us_m[k]) <= 4.0 * comb + 1e-4,
                  "%s theta %.1f ch %d: sampled albedo %.4f vs uniform %.4f (se %.4f)",
                  mats[i].name, thetas[t], k, is_m[k], us_m[k], comb);
      }
      if (i == 0)
        for (int k = 0; k < 3; ++k) CHECK_NEAR(is_m[k], mats[0].m.albedo[k], 1e-4);
      /* pdf integrates to <= 1, and to the probability that sampling succeeds. */
      double se_s = sqrt(success * (1.0 - success) / 200000.0);
      CHECK_MSG(integral <= 1.0 + 2e-3, "%s: pdf integrates to %.4f", mats[i].name, integral);
      CHECK_MSG(fabs(integral - success) <= 4.0 * se_s + 3e-3,
                "%s theta %.1f: int pdf %.4f vs success %.4f", mats[i].name, thetas[t], integral,
                success);
      /* chi-square at a fixed seed: p must not be tiny. */
      int dof;
      double p = chi2_test(&b, wo, 100000, &rng, &dof);
      CHECK_MSG(p > 1e-4, "%s theta %.1f: chi-square p = %.3g (dof %d)", mats[i].name, thetas[t], p,
                dof);
    }
    if (glass) {
      /* Generalised reciprocity over random pairs on both sides (eta = 1 outside). */
      int bad = 0, nonzero = 0;
      const float eta = mats[i].m.ior;
      for (int j = 0; j < 4000; ++j) {
        float a[3], c[3], fa[3], fc[3];
        uniform_sphere(tt__pcg32_float(&rng), tt__pcg32_float(&rng), a);
        uniform_sphere(tt__pcg32_float(&rng), tt__pcg32_float(&rng), c);
        tt__bsdf_eval(&b, a, c, fa);
        tt__bsdf_eval(&b, c, a, fc);
        float ea = a[2] > 0.0f ? 1.0f : eta, ec = c[2] > 0.0f ? 1.0f : eta;
        for (int k = 0; k < 3; ++k) {
          float x = fa[k] / (ea * ea), y = fc[k] / (ec * ec);
          bad += fabsf(x - y) > 2e-4f * fmaxf(1.0f, fmaxf(x, y));
          nonzero += fa[k] > 0.0f && a[2] * c[2] < 0.0f;
        }
        /* pdf support equals f support */
        bad += (tt__bsdf_pdf(&b, a, c) > 0.0f) != (fa[0] > 0.0f);
      }
      CHECK_MSG(bad == 0, "%s: %d generalised reciprocity failures", mats[i].name, bad);
      CHECK_MSG(nonzero > 100, "%s: only %d transmitting pairs", mats[i].name, nonzero);
      continue;
    }
    /* Reciprocity and symmetry of the pdf's support. */
    int nonrecip = 0;
    for (int j = 0; j < 2000; ++j) {
      float a[3], c[3], fa[3], fc[3];
      uniform_sphere(tt__pcg32_float(&rng), tt__pcg32_float(&rng), a);
      uniform_sphere(tt__pcg32_float(&rng), tt__pcg32_float(&rng), c);
      a[2] = fabsf(a[2]);
      c[2] = fabsf(c[2]);
      tt__bsdf_eval(&b, a, c, fa);
      tt__bsdf_eval(&b, c, a, fc);
      for (int k = 0; k < 3; ++k)
        nonrecip += fabsf(fa[k] - fc[k]) > 1e-4f * fmaxf(1.0f, fabsf(fa[k]));
      /* two-sided: viewing from below mirrors the lobe */
      float am[3] = {a[0], a[1], -a[2]}, cm[3] = {c[0], c[1], -c[2]}, fm[3];
      tt__bsdf_eval(&b, am, cm, fm);
      for (int k = 0; k < 3; ++k)
        nonrecip += fabsf(fa[k] - fm[k]) > 1e-4f * fmaxf(1.0f, fabsf(fa[k]));
      /* opposite sides never reflect */
      tt__bsdf_eval(&b, a, cm, fm);
      nonrecip += fm[0] != 0.0f || tt__bsdf_pdf(&b, a, cm) != 0.0f;
    }
    CHECK_MSG(nonrecip == 0, "%s: %d reciprocity/side failures", mats[i].name, nonrecip);
  }

  /* Oren-Nayar loses energy relative to Lambert (albedo < 1 for an albedo-1 surface) and
   * backscatters: f(wo, wo) > f at the mirror direction for a grazing wo. */
  {
    tt__bsdf b;
    tt__bsdf_init(&b, &mats[1].m);
    float wo[3], back[3], fwd[3], f1[3], f2[3];
    dir_from_angles(1.2f, 0.0f, wo);
    dir_from_angles(1.2f, 0.0f, back);
    dir_from_angles(1.2f, (float)M_PI, fwd);
    tt__bsdf_eval(&b, wo, back, f1);
    tt__bsdf_eval(&b, wo, fwd, f2);
    CHECK(f1[0] > f2[0]);
    CHECK(f2[0] < 1.0f / (float)M_PI);
  }

  /* Mirror: exact reflection, weight = specular tint, delta. */
  {
    tt_material m = base_material(TT_MATERIAL_MIRROR);
    m.specular[1] = 0.5f;
    tt__bsdf b;
    CHECK(tt__bsdf_init(&b, &m) == TT_OK);
    CHECK(b.delta);
    float wo[3], f[3];
    dir_from_angles(0.7f, 1.0f, wo);
    tt__bsdf_result s;
    CHECK(tt__bsdf_sample(&b, wo, 0.3f, 0.4f, 0.5f, &s));
    CHECK(s.delta);
    CHECK_NEAR(s.wi[0], -wo[0], 1e-6);
    CHECK_NEAR(s.wi[1], -wo[1], 1e-6);
    CHECK_NEAR(s.wi[2], wo[2], 1e-6);
    CHECK_NEAR(s.f[0] * s.wi[2] / s.pdf, 1.0, 1e-5);
    CHECK_NEAR(s.f[1] * s.wi[2] / s.pdf, 0.5, 1e-5);
    tt__bsdf_eval(&b, wo, s.wi, f);
    CHECK(f[0] == 0.0f && tt__bsdf_pdf(&b, wo, s.wi) == 0.0f);
    /* from below (two-sided) */
    float wb[3] = {wo[0], wo[1], -wo[2]};
    CHECK(tt__bsdf_sample(&b, wb, 0.3f, 0.4f, 0.5f, &s));
    CHECK_NEAR(s.wi[2], -wo[2], 1e-6);
  }

  /* Smooth glass: reflection probability = Fresnel, Snell's law, expected weight
   * R + T / eta^2 from outside (radiance transport), total internal reflection inside. */
  {
    tt_material m = base_material(TT_MATERIAL_DIELECTRIC);
    m.ior = 1.5f;
    tt__bsdf b;
    CHECK(tt__bsdf_init(&b, &m) == TT_OK);
    CHECK(b.delta);
    float wo[3];
    dir_from_angles(0.9f, 0.2f, wo);
    float F = tt__fresnel_dielectric(wo[2], 1.5f);
    CHECK(F > 0.04f && F < 0.2f);
    CHECK_NEAR(tt__fresnel_dielectric(1.0f, 1.5f), 0.04, 1e-6);
    int refl = 0, n = 100000;
    double wsum = 0.0;
    for (int i = 0; i < n; ++i) {
      tt__bsdf_result s;
      CHECK(tt__bsdf_sample(&b, wo, tt__pcg32_float(&rng), 0.5f, 0.5f, &s));
      CHECK(s.delta);
      wsum += s.f[0] * fabsf(s.wi[2]) / s.pdf;
      if (s.wi[2] > 0.0f) {
        refl++;
      } else if (i < 50) {
        float sin_o = sqrtf(1.0f - wo[2] * wo[2]), sin_t = sqrtf(1.0f - s.wi[2] * s.wi[2]);
        CHECK_NEAR(sin_t, sin_o / 1.5f, 1e-5);                    /* Snell */
        CHECK_NEAR(s.wi[0] * wo[1] - s.wi[1] * wo[0], 0.0, 1e-6); /* plane of incidence */
        CHECK(s.wi[0] * wo[0] < 0.0f);
      }
    }
    double fr = (double)refl / n, se = sqrt(F * (1.0 - F) / n);
    CHECK_NEAR(fr, F, 4.0 * se);
    double expect = F + (1.0 - F) / (1.5 * 1.5);
    CHECK_NEAR(wsum / n, expect, 4.0 * se);
    CHECK(wsum / n <= 1.0);
    /* From inside beyond the critical angle (asin(1/1.5) = 0.73): always reflects, weight 1. */
    float wi_in[3];
    dir_from_angles((float)M_PI - 0.9f, 0.2f, wi_in);
    CHECK_NEAR(tt__fresnel_dielectric(wi_in[2], 1.5f), 1.0, 0);
    tt__bsdf_result s;
    CHECK(tt__bsdf_sample(&b, wi_in, 0.99f, 0.5f, 0.5f, &s));
    CHECK(s.wi[2] < 0.0f);
    CHECK_NEAR(s.f[0] * fabsf(s.wi[2]) / s.pdf, 1.0, 1e-5);
    /* From inside below the critical angle the transmitted weight is T * eta^2. */
    dir_from_angles((float)M_PI - 0.3f, 0.2f, wi_in);
    float Fi = tt__fresnel_dielectric(wi_in[2], 1.5f);
    CHECK(tt__bsdf_sample(&b, wi_in, 0.999f, 0.5f, 0.5f, &s));
    CHECK(s.wi[2] > 0.0f);
    CHECK_NEAR(s.f[0] * fabsf(s.wi[2]) / s.pdf, 1.5 * 1.5, 1e-4);
    CHECK_NEAR(s.pdf, 1.0 - Fi, 1e-6);
  }

  /* Smooth conductor (alpha 0) is a delta lobe with the Fresnel weight; rough glass is
   * refused with a message instead of rendering black. */
  {
    tt_material m = mats[2].m;
    m.alpha[0] = m.alpha[1] = 0.0f;
    tt__bsdf b;
    CHECK(tt__bsdf_init(&b, &m) == TT_OK);
    CHECK(b.delta);
    float wo[3];
    dir_from_angles(0.4f, 0.0f, wo);
    tt__bsdf_result s;
    CHECK(tt__bsdf_sample(&b, wo, 0.5f, 0.5f, 0.5f, &s));
    double w = s.f[0] * s.wi[2] / s.pdf;
    CHECK(w > 0.5 && w < 1.0); /* gold's red reflectance */
    tt_material bad = base_material((tt_material_type)42);
    CHECK(tt__bsdf_init(&b, &bad) == TT_ERR_UNSUPPORTED);
  }
  /* Rough glass: alpha below 1e-3 is the smooth (delta) BSDF; a nearly smooth rough glass
   * has the smooth glass's directional albedo R + T / eta^2 from outside, and splits energy
   * between the hemispheres by Fresnel. */
  {
    tt_material g = base_material(TT_MATERIAL_DIELECTRIC);
    g.alpha[0] = g.alpha[1] = 5e-4f;
    tt__bsdf b;
    CHECK(tt__bsdf_init(&b, &g) == TT_OK);
    CHECK(b.delta);
    g.alpha[0] = g.alpha[1] = 0.01f;
    CHECK(tt__bsdf_init(&b, &g) == TT_OK);
    CHECK(!b.delta);
    float wo[3];
    dir_from_angles(0.9f, 0.2f, wo);
    float F = tt__fresnel_dielectric(wo[2], 1.5f);
    double sum = 0.0, refl = 0.0;
    int n = 100000;
    for (int i = 0; i < n; ++i) {
      tt__bsdf_result s;
      if (!tt__bsdf_sample(&b, wo, tt__pcg32_float(&rng), tt__pcg32_float(&rng),
                           tt__pcg32_float(&rng), &s))
        continue;
      double w = s.f[0] * fabsf(s.wi[2]) / s.pdf;
      sum += w;
      if (s.wi[2] > 0.0f) refl += w;
    }
    double expect = F + (1.0 - F) / (1.5 * 1.5);
    printf("rough glass alpha 0.01: albedo %.4f (smooth %.4f), reflected %.4f (F %.4f)\n", sum / n,
           expect, refl / n, F);
    CHECK_NEAR(sum / n, expect, 0.01);
    CHECK_NEAR(refl / n, F, 0.01);
  }
  /* Adjoint sampling: same direction and pdf as radiance sampling, f* (wo, wi) = f(wi, wo);
   * smooth glass's importance throughput is R + T = 1 from either side. */
  {
    int bad = 0;
    for (int i = 0; i < nm; ++i) {
      tt__bsdf b;
      CHECK(tt__bsdf_init(&b, &mats[i].m) == TT_OK);
      for (int k = 0; k < 2000; ++k) {
        float wo[3], u[3] = {tt__pcg32_float(&rng), tt__pcg32_float(&rng), tt__pcg32_float(&rng)};
        uniform_sphere(tt__pcg32_float(&rng), tt__pcg32_float(&rng), wo);
        tt__bsdf_result r, a;
        int okr = tt__bsdf_sample(&b, wo, u[0], u[1], u[2], &r);
        int oka = tt__bsdf_sample_adjoint(&b, wo, u[0], u[1], u[2], &a);
        CHECK(okr == oka);
        if (!okr) continue;
        float fs[3];
        tt__bsdf_eval(&b, a.wi, wo, fs);
        for (int c = 0; c < 3; ++c)
          if (a.wi[c] != r.wi[c] || a.pdf != r.pdf ||
              fabsf(a.f[c] - fs[c]) > 1e-3f * fmaxf(fs[c], 1e-3f))
            bad++;
      }
    }
    CHECK_MSG(bad == 0, "%d adjoint samples differ from f(wi, wo) or from radiance sampling", bad);
    tt_material g = base_material(TT_MATERIAL_DIELECTRIC);
    g.ior = 1.6f;
    tt__bsdf b;
    CHECK(tt__bsdf_init(&b, &g) == TT_OK && b.delta);
    for (int side = 0; side < 2; ++side) {
      float wo[3];
      dir_from_angles(side ? (float)M_PI - 0.5f : 0.7f, 0.3f, wo);
      double imp = 0.0, rad = 0.0;
      int n = 20000;
      for (int k = 0; k < n; ++k) {
        tt__bsdf_result s;
        float ul = tt__pcg32_float(&rng);
        if (tt__bsdf_sample_adjoint(&b, wo, ul, 0.5f, 0.5f, &s))
          imp += s.f[0] * fabsf(s.wi[2]) / s.pdf;
        if (tt__bsdf_sample(&b, wo, ul, 0.5f, 0.5f, &s)) rad += s.f[0] * fabsf(s.wi[2]) / s.pdf;
      }
      float F = tt__fresnel_dielectric(wo[2], 1.6f), etap = side ? 1.0f / 1.6f : 1.6f;
      printf("smooth glass from %s: importance %.5f (1), radiance %.5f (R + T/eta'^2 = %.5f)\n",
             side ? "inside" : "outside", imp / n, rad / n, F + (1.0f - F) / (etap * etap));
      CHECK_NEAR(imp / n, 1.0, 1e-4);
      CHECK_NEAR(rad / n, F + (1.0 - F) / (etap * etap), 0.01);
    }
  }
  return tt_test_finish("path_bsdf");
}
