/* Shared helpers of the path_* tests: load a scene from JSON, trace it through the
 * brute-force accel (no Embree), and estimate a camera ray's radiance with its standard
 * error from independent samples. */
#ifndef TT_TEST_PATH_COMMON_H
#define TT_TEST_PATH_COMMON_H

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <tunetrace/camera.h>
#include <tunetrace/path.h>
#include <tunetrace/sampler.h>

#include "support/brute_accel.h"

typedef struct pt_fixture {
  tt_scene *scene;
  tt_accel *accel;
  tt_path_tracer *pt;
  tt_tracer tracer;
} pt_fixture;

/* Loads `json` (assets relative to `dir`), builds the brute accel and the path tracer; 0 on
 * failure (message printed). */
static inline int pt_fixture_load_dir(pt_fixture *f, const char *json, const char *dir) {
  memset(f, 0, sizeof *f);
  tt_status st = tt_scene_load_json(json, strlen(json), "test", dir, &f->scene);
  if (st != TT_OK) {
    fprintf(stderr, "scene: %s\n", tt_last_error());
    return 0;
  }
  const tt_accel_iface *iface = tt_test_brute_accel();
  if (iface->build(f->scene, NULL, &f->accel, NULL) != TT_OK) return 0;
  f->tracer.iface = iface;
  f->tracer.accel = f->accel;
  st = tt_path_tracer_create(f->scene, &f->pt);
  if (st != TT_OK) {
    fprintf(stderr, "path tracer: %s\n", tt_last_error());
    return 0;
  }
  return 1;
}

static inline int pt_fixture_load(pt_fixture *f, const char *json) {
  return pt_fixture_load_dir(f, json, NULL);
}

static inline void pt_fixture_free(pt_fixture *f) {
  tt_path_tracer_destroy(f->pt);
  if (f->accel) f->tracer.iface->destroy(f->accel);
  tt_scene_destroy(f->scene);
  memset(f, 0, sizeof *f);
}

/* A built-in sampler positioned at one (pixel, index), as a tt_sample_source. */
typedef struct pt_sampler_src {
  const tt_sampler_iface *iface;
  tt_sampler *sampler;
  _Alignas(16) unsigned char state[256];
  double pdf_sum; /* sum of reported BSDF pdfs (report_pdf) */
  uint32_t pdf_reports;
} pt_sampler_src;

static inline float pt_src_get(void *self, uint32_t dim) {
  pt_sampler_src *s = self;
  return s->iface->get(s->sampler, s->state, dim);
}

static inline void pt_src_report(void *self, uint32_t dim, float pdf) {
  pt_sampler_src *s = self;
  (void)dim;
  s->pdf_sum += pdf;
  s->pdf_reports++;
}

/* Mean and standard error of n samples of the radiance along `ray`. Samples use pixel
 * (key, 0) of the named sampler with indices 0..n-1 and `seed`. */
typedef struct pt_estimate {
  double mean[3], se[3];
  uint64_t rays, nonfinite;
  uint32_t max_dim;
} pt_estimate;

static inline void pt_estimate_ray(const pt_fixture *f, const tt_path_options *o, const tt_ray *ray,
                                   uint32_t n, uint32_t key, uint64_t seed, const char *sampler,
                                   pt_estimate *e) {
  pt_sampler_src src;
  memset(&src, 0, sizeof src);
  src.iface = tt_builtin_sampler(sampler);
  src.iface->create(NULL, seed, &src.sampler);
  tt_sample_source source = {pt_src_get, pt_src_report, &src};
  double s1[3] = {0, 0, 0}, s2[3] = {0, 0, 0};
  memset(e, 0, sizeof *e);
  for (uint32_t i = 0; i < n; ++i) {
    src.iface->start(src.sampler, src.state, key, 0, i);
    tt_path_result r;
    tt_path_trace(f->pt, &f->tracer, o, ray, &source, &r);
    for (int c = 0; c < 3; ++c) {
      s1[c] += r.L[c];
      s2[c] += (double)r.L[c] * r.L[c];
    }
    e->rays += r.rays;
    e->nonfinite += r.nonfinite ? 1 : 0;
    if (r.max_dim > e->max_dim) e->max_dim = r.max_dim;
  }
  for (int c = 0; c < 3; ++c) {
    e->mean[c] = s1[c] / n;
    double var = (s2[c] / n - e->mean[c] * e->mean[c]) * n / (n > 1 ? n - 1 : 1);
    e->se[c] = sqrt(var > 0 ? var / n : 0);
  }
  src.iface->destroy(src.sampler);
}

/* A ray from `from` towards `to`. */
static inline void pt_ray_towards(tt_ray *r, const float from[3], const float to[3]) {
  float d[3] = {to[0] - from[0], to[1] - from[1], to[2] - from[2]};
  float l = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  for (int i = 0; i < 3; ++i) {
    r->org[i] = from[i];
    r->dir[i] = d[i] / l;
  }
  r->tnear = 0.0f;
  r->tfar = INFINITY;
}

#endif
