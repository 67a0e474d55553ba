/* Pinhole camera: validation, orientation (right-handed, film y down), ray/projection round
 * trip, field of view, and the Halton(2,3) jitter sequence. */
#include <tunetrace/camera.h>

#include "tt_test.h"

static tt_camera make_camera(float fov, uint32_t w, uint32_t h) {
  tt_camera c;
  memset(&c, 0, sizeof c);
  c.struct_size = sizeof c;
  c.position[0] = 1.0f;
  c.position[1] = 2.0f;
  c.position[2] = 3.0f;
  c.target[0] = 1.0f;
  c.target[1] = 2.0f;
  c.target[2] = -7.0f; /* looks down -z */
  c.up[1] = 1.0f;
  c.fov_y = fov;
  c.width = w;
  c.height = h;
  return c;
}

int main(void) {
  tt_camera_frame fr;
  tt_camera c = make_camera(60.0f, 64, 32);
  CHECK(tt_camera_frame_init(&fr, &c) == TT_OK);
  CHECK_NEAR(fr.forward[2], -1.0, 1e-6);
  CHECK_NEAR(fr.right[0], 1.0, 1e-6); /* right-handed: forward x up = +x */
  CHECK_NEAR(fr.up[1], 1.0, 1e-6);
  CHECK_NEAR(fr.aspect, 2.0, 1e-6);
  CHECK_NEAR(fr.tan_half_fov_y, tan(M_PI / 6.0), 1e-6);

  /* Errors. */
  tt_camera bad = c;
  bad.target[2] = bad.position[2];
  CHECK(tt_camera_frame_init(&fr, &bad) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "target");
  bad = c;
  bad.up[1] = 0.0f;
  bad.up[2] = 1.0f;
  CHECK(tt_camera_frame_init(&fr, &bad) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "parallel");
  bad = c;
  bad.fov_y = 180.0f;
  CHECK(tt_camera_frame_init(&fr, &bad) == TT_ERR_INVALID_ARGUMENT);
  bad = c;
  bad.fov_y = 0.0f;
  CHECK(tt_camera_frame_init(&fr, &bad) == TT_ERR_INVALID_ARGUMENT);
  bad = c;
  bad.height = 0;
  CHECK(tt_camera_frame_init(&fr, &bad) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), "resolution");
  CHECK(tt_camera_frame_init(&fr, &c) == TT_OK);

  /* Centre of the film looks along forward; right/top of the film go +x/+y. */
  tt_ray r;
  tt_camera_generate_ray(&fr, 32.0f, 16.0f, &r);
  CHECK_NEAR(r.dir[2], -1.0, 1e-6);
  CHECK_NEAR(r.org[0], 1.0, 0);
  CHECK_NEAR(r.org[1], 2.0, 0);
  CHECK_NEAR(r.org[2], 3.0, 0);
  CHECK(r.tnear == 0.0f && isinf(r.tfar));
  tt_camera_generate_ray(&fr, 60.0f, 2.0f, &r);
  CHECK(r.dir[0] > 0.0f && r.dir[1] > 0.0f);
  /* Top edge centre: angle to forward is fov/2. */
  tt_camera_generate_ray(&fr, 32.0f, 0.0f, &r);
  CHECK_NEAR(acos(-r.dir[2]) * 180.0 / M_PI, 30.0, 1e-4);
  CHECK_NEAR(r.dir[0] * r.dir[0] + r.dir[1] * r.dir[1] + r.dir[2] * r.dir[2], 1.0, 1e-6);
  /* Left edge centre: horizontal half-angle atan(aspect * tan(fov/2)). */
  tt_camera_generate_ray(&fr, 0.0f, 16.0f, &r);
  CHECK_NEAR(atan2(-r.dir[0], -r.dir[2]), atan(2.0 * tan(M_PI / 6.0)), 1e-5);

  /* Round trip: generate -> point at distance t -> project gives the film position back,
   * depth = t * cos(angle to forward). */
  int bad_rt = 0;
  for (int i = 0; i < 200; ++i) {
    float fx = (float)(i * 37 % 640) / 10.0f, fy = (float)(i * 53 % 320) / 10.0f;
    tt_camera_generate_ray(&fr, fx, fy, &r);
    float t = 0.5f + (float)i * 0.1f;
    float p[3] = {r.org[0] + t * r.dir[0], r.org[1] + t * r.dir[1], r.org[2] + t * r.dir[2]};
    float gx, gy, depth;
    CHECK(tt_camera_project(&fr, p, &gx, &gy, &depth));
    bad_rt += fabsf(gx - fx) > 1e-3f || fabsf(gy - fy) > 1e-3f ||
              fabsf(depth - t * -r.dir[2]) > 1e-4f * t;
  }
  CHECK(bad_rt == 0);
  float behind[3] = {1.0f, 2.0f, 4.0f}, gx, gy;
  CHECK(tt_camera_project(&fr, behind, &gx, &gy, NULL) == 0);
  float ahead[3] = {1.5f, 2.0f, 0.0f}, depth;
  CHECK(tt_camera_project(&fr, ahead, NULL, NULL, &depth) == 1);
  CHECK_NEAR(depth, 3.0, 1e-6);

  /* Halton(2,3) jitter: index 0 is Halton index 1 = (1/2, 1/3). */
  float o[2];
  tt_jitter_halton23(0, o);
  CHECK_NEAR(o[0], 0.0, 1e-7);
  CHECK_NEAR(o[1], 1.0 / 3.0 - 0.5, 1e-7);
  tt_jitter_halton23(1, o);
  CHECK_NEAR(o[0], -0.25, 1e-7);
  CHECK_NEAR(o[1], 2.0 / 3.0 - 0.5, 1e-7);
  tt_jitter_halton23(2, o);
  CHECK_NEAR(o[0], 0.25, 1e-7);
  CHECK_NEAR(o[1], 1.0 / 9.0 - 0.5, 1e-7);
  tt_jitter_halton23(7, o); /* Halton index 8: 1/16, 8 = 22_3 -> 2/3 + 2/9 */
  CHECK_NEAR(o[0], 1.0 / 16.0 - 0.5, 1e-7);
  CHECK_NEAR(o[1], 8.0 / 9.0 - 0.5, 1e-7);
  int out_of_range = 0;
  double mean[2] = {0, 0};
  for (uint32_t i = 0; i < 4096; ++i) {
    tt_jitter_halton23(i, o);
    out_of_range += !(o[0] >= -0.5f && o[0] < 0.5f && o[1] >= -0.5f && o[1] < 0.5f);
    mean[0] += o[0];
    mean[1] += o[1];
  }
  CHECK(out_of_range == 0);
  CHECK_NEAR(mean[0] / 4096, 0.0, 1e-3);
  CHECK_NEAR(mean[1] / 4096, 0.0, 1e-3);
  tt_jitter_halton23(0x7ffffffeu, o);
  CHECK(o[0] >= -0.5f && o[0] < 0.5f && o[1] >= -0.5f && o[1] < 0.5f);
  return tt_test_finish("camera_basic");
}
