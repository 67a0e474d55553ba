/* pbrt-v4 spectra mapped to linear sRGB. tunetrace renders in RGB, so every spectrum is
 * projected once at load time: through the CIE 1931 matching functions (Wyman, Sloan and
 * Shirley's 2013 multi-lobe Gaussian fit) and the XYZ -> linear sRGB matrix. Tables of
 * named metals are the usual RGB fits of the measured data pbrt ships. */
#include "io/pbrt/pbrt_internal.h"

#include <math.h>
#include <string.h>

/* Piecewise Gaussian used by the CIE fit. */
static double tt__g(double x, double mu, double s1, double s2) {
  double t = (x - mu) / (x < mu ? s1 : s2);
  return exp(-0.5 * t * t);
}

/* CIE 1931 2-degree matching functions at wavelength l (nm), analytic fit. */
static void tt__cie(double l, double xyz[3]) {
  xyz[0] = 1.056 * tt__g(l, 599.8, 37.9, 31.0) + 0.362 * tt__g(l, 442.0, 16.0, 26.7) -
           0.065 * tt__g(l, 501.1, 20.4, 26.2);
  xyz[1] = 0.821 * tt__g(l, 568.8, 46.9, 40.5) + 0.286 * tt__g(l, 530.9, 16.3, 31.1);
  xyz[2] = 1.217 * tt__g(l, 437.0, 11.8, 36.0) + 0.681 * tt__g(l, 459.0, 26.0, 13.8);
}

/* XYZ to linear sRGB (D65). */
static void tt__xyz_to_rgb(const double xyz[3], double rgb[3]) {
  rgb[0] = 3.2404542 * xyz[0] - 1.5371385 * xyz[1] - 0.4985314 * xyz[2];
  rgb[1] = -0.9692660 * xyz[0] + 1.8760108 * xyz[1] + 0.0415560 * xyz[2];
  rgb[2] = 0.0556434 * xyz[0] - 0.2040259 * xyz[1] + 1.0572252 * xyz[2];
}

/* Linear interpolation in sorted (lambda, value) pairs, clamped at both ends. */
static double tt__interp(const double *p, size_t n, double l) {
  if (n == 0) return 0.0;
  if (l <= p[0]) return p[1];
  if (l >= p[2 * (n - 1)]) return p[2 * (n - 1) + 1];
  for (size_t i = 0; i + 1 < n; i++) {
    double l0 = p[2 * i], l1 = p[2 * i + 2];
    if (l >= l0 && l <= l1) {
      double t = l1 > l0 ? (l - l0) / (l1 - l0) : 0.0;
      return p[2 * i + 1] * (1 - t) + p[2 * i + 3] * t;
    }
  }
  return p[2 * (n - 1) + 1];
}

/* Integrates spectrum s(l) (callback) against the matching functions, 360..830 nm. */
static void tt__integrate(double (*s)(const void *, double), const void *ctx, double xyz[3]) {
  xyz[0] = xyz[1] = xyz[2] = 0.0;
  for (double l = 360.0; l <= 830.0; l += 1.0) {
    double c[3], v = s(ctx, l);
    tt__cie(l, c);
    for (int i = 0; i < 3; i++) xyz[i] += v * c[i];
  }
}

typedef struct tt__pairs {
  const double *p;
  size_t n;
} tt__pairs;

/* Spectrum callback for sampled pairs. */
static double tt__pairs_eval(const void *ctx, double l) {
  const tt__pairs *pp = ctx;
  return tt__interp(pp->p, pp->n, l);
}

/* Spectrum callback for a flat spectrum of 1. */
static double tt__one_eval(const void *ctx, double l) {
  (void)ctx;
  (void)l;
  return 1.0;
}

/* Spectrum callback for Planck's law at a temperature (kelvin in *ctx). */
static double tt__planck_eval(const void *ctx, double l) {
  double T = *(const double *)ctx;
  const double c = 299792458.0, h = 6.62606957e-34, kb = 1.3806488e-23;
  double m = l * 1e-9;
  return (2 * h * c * c) / (pow(m, 5) * (exp((h * c) / (m * kb * T)) - 1));
}

/* Illuminants keep their chromaticity and get luminance 1; reflectance-like spectra are
 * white-balanced so that a flat spectrum maps to exactly (v, v, v). */
void tt__pbrt_sampled_spectrum(const double *pairs, size_t n, tt__spectrum_use use, float out[3]) {
  tt__pairs pp = {pairs, n};
  double xyz[3], rgb[3];
  tt__integrate(tt__pairs_eval, &pp, xyz);
  tt__xyz_to_rgb(xyz, rgb);
  if (use == TT__SPEC_ILLUMINANT) {
    double y = xyz[1] > 0 ? xyz[1] : 1.0;
    for (int i = 0; i < 3; i++) out[i] = (float)fmax(rgb[i] / y, 0.0);
    if (!(xyz[1] > 0)) out[0] = out[1] = out[2] = 0.0f;
  } else {
    double w[3], wxyz[3];
    tt__integrate(tt__one_eval, NULL, wxyz);
    tt__xyz_to_rgb(wxyz, w);
    /* eta and k are positive by nature; the matching functions' overlap may push a
     * channel slightly negative for steep spectra */
    for (int i = 0; i < 3; i++) out[i] = (float)fmax(rgb[i] / w[i], 1e-3);
  }
}

/* Planck spectrum projected and normalised to luminance 1. */
void tt__pbrt_blackbody(double kelvin, float out[3]) {
  if (!(kelvin > 0) || !isfinite(kelvin)) {
    out[0] = out[1] = out[2] = 0.0f;
    return;
  }
  double xyz[3], rgb[3];
  tt__integrate(tt__planck_eval, &kelvin, xyz);
  tt__xyz_to_rgb(xyz, rgb);
  for (int i = 0; i < 3; i++) out[i] = (float)fmax(xyz[1] > 0 ? rgb[i] / xyz[1] : 0.0, 0.0);
}

typedef struct tt__named {
  const char *name;
  float rgb[3];
} tt__named;

/* RGB fits of pbrt-v4's named spectra (metals: as used by Mitsuba/Tungsten; glasses: IOR
 * at the sodium d-line, flat). */
static const tt__named tt__named_spectra[] = {
    {"metal-Ag-eta", {0.155265f, 0.116723f, 0.138342f}},
    {"metal-Ag-k", {4.82835f, 3.12225f, 2.14696f}},
    {"metal-Al-eta", {1.65746f, 0.880369f, 0.521229f}},
    {"metal-Al-k", {9.22387f, 6.26952f, 4.837f}},
    {"metal-Au-eta", {0.143119f, 0.374957f, 1.44248f}},
    {"metal-Au-k", {3.98316f, 2.38572f, 1.60322f}},
    {"metal-Cu-eta", {0.200438f, 0.924033f, 1.10221f}},
    {"metal-Cu-k", {3.91295f, 2.45285f, 2.14219f}},
    {"metal-CuZn-eta", {0.444f, 0.527f, 1.094f}},
    {"metal-CuZn-k", {3.695f, 2.765f, 1.829f}},
    {"metal-MgO-eta", {1.7357f, 1.7357f, 1.7357f}},
    {"metal-MgO-k", {0.0f, 0.0f, 0.0f}},
    {"metal-TiO2-eta", {2.8717f, 2.6126f, 2.4557f}},
    {"metal-TiO2-k", {0.0f, 0.0f, 0.0f}},
    {"glass-BK7", {1.5168f, 1.5168f, 1.5168f}},
    {"glass-BAF10", {1.6700f, 1.6700f, 1.6700f}},
    {"glass-FK51A", {1.4866f, 1.4866f, 1.4866f}},
    {"glass-LASF9", {1.8503f, 1.8503f, 1.8503f}},
    {"glass-F5", {1.6034f, 1.6034f, 1.6034f}},
    {"glass-F10", {1.6200f, 1.6200f, 1.6200f}},
    {"glass-F11", {1.6209f, 1.6209f, 1.6209f}},
};

/* Standard illuminants become white of luminance 1 (the renderer works in sRGB/D65). */
int tt__pbrt_named_spectrum(const char *name, float rgb[3]) {
  if (!name) return 0;
  for (size_t i = 0; i < sizeof tt__named_spectra / sizeof tt__named_spectra[0]; i++)
    if (strcmp(name, tt__named_spectra[i].name) == 0) {
      memcpy(rgb, tt__named_spectra[i].rgb, 3 * sizeof(float));
      return 1;
    }
  if (strncmp(name, "stdillum-", 9) == 0 || strncmp(name, "illum-", 6) == 0) {
    rgb[0] = rgb[1] = rgb[2] = 1.0f;
    return 1;
  }
  return 0;
}
