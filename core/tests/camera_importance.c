/* The pinhole's importance (camera.h) as the bidirectional integrators use it: W_e cos
 * integrates to 1 over the sphere of directions and so does the direction density; the
 * density is that of tt_camera_generate_ray at uniform film positions (the share of the
 * sphere's integral over a region of the film equals the region's share of the film);
 * the film position W_e reports is the one the ray was generated through; nothing behind
 * the camera or outside the film. */
#include <tunetrace/camera.h>
#include <tt_util/rng.h>

#include "tt_test.h"

/* Uniform direction on the sphere from two uniforms. */
static void sphere_dir(double u1, double u2, float d[3]) {
  double z = 1.0 - 2.0 * u1, r = sqrt(fmax(0.0, 1.0 - z * z)), phi = 2.0 * M_PI * u2;
  d[0] = (float)(r * cos(phi));
  d[1] = (float)(r * sin(phi));
  d[2] = (float)z;
}

static void check_camera(float fov, uint32_t w, uint32_t h, const float target[3]) {
  tt_camera c;
  memset(&c, 0, sizeof c);
  c.struct_size = sizeof c;
  c.position[0] = 0.5f;
  c.position[1] = -1.0f;
  c.position[2] = 2.0f;
  memcpy(c.target, target, sizeof c.target);
  c.up[1] = 1.0f;
  c.fov_y = fov;
  c.width = w;
  c.height = h;
  tt_camera_frame fr;
  CHECK(tt_camera_frame_init(&fr, &c) == TT_OK);
  const float A = tt_camera_film_area(&fr);
  CHECK_NEAR(A, 4.0 * pow(tan(fov * M_PI / 360.0), 2) * w / h, 1e-4 * A);

  /* Integrals over the sphere (Monte Carlo, uniform directions): W_e cos and the density
   * integrate to 1; over the region x < W/3, y < H/2 of the film, to 1/6. */
  const int N = 4000000;
  double s_we = 0, s_we2 = 0, s_pdf = 0, s_region = 0;
  tt__pcg32 rng;
  tt__pcg32_seed(&rng, 42, 7);
  for (int i = 0; i < N; ++i) {
    float d[3], fx = -1, fy = -1;
    sphere_dir(tt__pcg32_double(&rng), tt__pcg32_double(&rng), d);
    float we = tt_camera_importance(&fr, d, &fx, &fy);
    float pdf = tt_camera_pdf_dir(&fr, d);
    double cosv = d[0] * fr.forward[0] + d[1] * fr.forward[1] + d[2] * fr.forward[2];
    double v = we * cosv * 4.0 * M_PI;
    s_we += v;
    s_we2 += v * v;
    s_pdf += pdf * 4.0 * M_PI;
    if (we > 0 && fx < w / 3.0f && fy < h / 2.0f) s_region += pdf * 4.0 * M_PI;
    CHECK(we >= 0 && pdf >= 0);
    if (we > 0) CHECK(fx >= 0 && fx < w && fy >= 0 && fy < h);
  }
  double mean = s_we / N, se = sqrt((s_we2 / N - mean * mean) / N);
  printf("fov %g %ux%u: int We cos = %.5f (se %.5f), int pdf = %.5f, region %.5f (1/6 = %.5f)\n",
         fov, w, h, mean, se, s_pdf / N, s_region / N, 1.0 / 6.0);
  CHECK_MSG(fabs(mean - 1.0) < 4.0 * se && se < 0.01, "int We cos = %g se %g", mean, se);
  CHECK_MSG(fabs(s_pdf / N - 1.0) < 4.0 * se, "int pdf = %g", s_pdf / N);
  CHECK_MSG(fabs(s_region / N - 1.0 / 6.0) < 4.0 * se, "region %g", s_region / N);

  /* Round trip: W_e of a generated ray reports its film position; W_e / pdf = 1 / cos. */
  for (int i = 0; i < 1000; ++i) {
    float fx = (float)(tt__pcg32_double(&rng) * w), fy = (float)(tt__pcg32_double(&rng) * h), gx,
          gy;
    tt_ray r;
    tt_camera_generate_ray(&fr, fx, fy, &r);
    float we = tt_camera_importance(&fr, r.dir, &gx, &gy);
    CHECK(we > 0);
    CHECK_NEAR(gx, fx, 2e-3 * w);
    CHECK_NEAR(gy, fy, 2e-3 * h);
    double cosv = r.dir[0] * fr.forward[0] + r.dir[1] * fr.forward[1] + r.dir[2] * fr.forward[2];
    CHECK_NEAR(we / tt_camera_pdf_dir(&fr, r.dir), 1.0 / cosv, 1e-4 / cosv);
  }
  /* Behind the camera, and just outside the film. */
  float back[3] = {-fr.forward[0], -fr.forward[1], -fr.forward[2]};
  CHECK(tt_camera_importance(&fr, back, NULL, NULL) == 0.0f &&
        tt_camera_pdf_dir(&fr, back) == 0.0f);
  tt_ray r;
  tt_camera_generate_ray(&fr, -0.01f * w, 0.5f * h, &r);
  CHECK(tt_camera_importance(&fr, r.dir, NULL, NULL) == 0.0f &&
        tt_camera_pdf_dir(&fr, r.dir) == 0.0f);
  tt_camera_generate_ray(&fr, 0.5f * w, 1.01f * h, &r);
  CHECK(tt_camera_importance(&fr, r.dir, NULL, NULL) == 0.0f);
}

int main(void) {
  const float t1[3] = {0.0f, 0.0f, -3.0f}, t2[3] = {2.0f, 1.0f, 0.5f};
  check_camera(45.0f, 64, 32, t1);
  check_camera(100.0f, 24, 48, t2);
  check_camera(10.0f, 7, 5, t1);
  return tt_test_finish("camera_importance");
}
