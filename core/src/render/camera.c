/* tunetrace: pinhole camera (camera.h). Right-handed: right = forward x up, so a camera
 * looking down -z with +y up has +x to its right; film y grows downwards. */
#include <tunetrace/camera.h>

#include <math.h>

/* Length of a 3-vector in double, so nearly-degenerate inputs are judged accurately. */
static double tt__len3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

TT_API tt_status tt_camera_frame_init(tt_camera_frame *frame, const tt_camera *camera) {
  if (!frame || !camera)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "camera: frame or camera is NULL");
  if (camera->width == 0 || camera->height == 0)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "camera: resolution %ux%u has a zero side",
                        camera->width, camera->height);
  if (!(camera->fov_y > 0.0f && camera->fov_y < 180.0f))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "camera: fov %g degrees is outside (0, 180)",
                        (double)camera->fov_y);
  double f[3], up[3], r[3], u[3];
  for (int i = 0; i < 3; ++i) {
    f[i] = (double)camera->target[i] - (double)camera->position[i];
    up[i] = camera->up[i];
  }
  double fl = tt__len3(f), ul = tt__len3(up);
  if (!(fl > 0.0) || !isfinite(fl))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "camera: position equals target");
  if (!(ul > 0.0) || !isfinite(ul))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "camera: up vector is zero");
  for (int i = 0; i < 3; ++i) f[i] /= fl;
  r[0] = f[1] * up[2] - f[2] * up[1];
  r[1] = f[2] * up[0] - f[0] * up[2];
  r[2] = f[0] * up[1] - f[1] * up[0];
  double rl = tt__len3(r);
  if (!(rl > 1e-6 * ul))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "camera: up vector is parallel to the view direction");
  for (int i = 0; i < 3; ++i) r[i] /= rl;
  u[0] = r[1] * f[2] - r[2] * f[1];
  u[1] = r[2] * f[0] - r[0] * f[2];
  u[2] = r[0] * f[1] - r[1] * f[0];
  for (int i = 0; i < 3; ++i) {
    frame->origin[i] = camera->position[i];
    frame->forward[i] = (float)f[i];
    frame->right[i] = (float)r[i];
    frame->up[i] = (float)u[i];
  }
  frame->tan_half_fov_y = (float)tan(0.5 * (double)camera->fov_y * M_PI / 180.0);
  frame->aspect = (float)camera->width / (float)camera->height;
  frame->width = camera->width;
  frame->height = camera->height;
  return TT_OK;
}

TT_API void tt_camera_generate_ray(const tt_camera_frame *frame, float fx, float fy, tt_ray *ray) {
  /* Screen-plane coordinates at distance 1 along forward. */
  float sx = (2.0f * fx / (float)frame->width - 1.0f) * frame->tan_half_fov_y * frame->aspect;
  float sy = (1.0f - 2.0f * fy / (float)frame->height) * frame->tan_half_fov_y;
  float d[3], len2 = 0.0f;
  for (int i = 0; i < 3; ++i) {
    d[i] = frame->forward[i] + sx * frame->right[i] + sy * frame->up[i];
    len2 += d[i] * d[i];
  }
  float inv = 1.0f / sqrtf(len2);
  for (int i = 0; i < 3; ++i) {
    ray->org[i] = frame->origin[i];
    ray->dir[i] = d[i] * inv;
  }
  ray->tnear = 0.0f;
  ray->tfar = INFINITY;
}

TT_API int tt_camera_project(const tt_camera_frame *frame, const float p[3], float *fx, float *fy,
                             float *depth) {
  float d[3] = {p[0] - frame->origin[0], p[1] - frame->origin[1], p[2] - frame->origin[2]};
  float z = d[0] * frame->forward[0] + d[1] * frame->forward[1] + d[2] * frame->forward[2];
  if (!(z > 0.0f)) return 0;
  float x = (d[0] * frame->right[0] + d[1] * frame->right[1] + d[2] * frame->right[2]) / z;
  float y = (d[0] * frame->up[0] + d[1] * frame->up[1] + d[2] * frame->up[2]) / z;
  if (fx) *fx = (x / (frame->tan_half_fov_y * frame->aspect) + 1.0f) * 0.5f * (float)frame->width;
  if (fy) *fy = (1.0f - y / frame->tan_half_fov_y) * 0.5f * (float)frame->height;
  if (depth) *depth = z;
  return 1;
}

TT_API float tt_camera_film_area(const tt_camera_frame *frame) {
  float t = frame->tan_half_fov_y;
  return 4.0f * t * t * frame->aspect;
}

/* cos(theta) of `dir` with the view axis and its film position; 0 outside the film. */
static float tt__camera_cos_on_film(const tt_camera_frame *frame, const float dir[3], float *fx,
                                    float *fy) {
  float c = dir[0] * frame->forward[0] + dir[1] * frame->forward[1] + dir[2] * frame->forward[2];
  if (!(c > 0.0f)) return 0.0f;
  float x = (dir[0] * frame->right[0] + dir[1] * frame->right[1] + dir[2] * frame->right[2]) / c;
  float y = (dir[0] * frame->up[0] + dir[1] * frame->up[1] + dir[2] * frame->up[2]) / c;
  float px = (x / (frame->tan_half_fov_y * frame->aspect) + 1.0f) * 0.5f * (float)frame->width;
  float py = (1.0f - y / frame->tan_half_fov_y) * 0.5f * (float)frame->height;
  if (!(px >= 0.0f && px < (float)frame->width && py >= 0.0f && py < (float)frame->height))
    return 0.0f;
  if (fx) *fx = px;
  if (fy) *fy = py;
  return c;
}

TT_API float tt_camera_importance(const tt_camera_frame *frame, const float dir[3], float *fx,
                                  float *fy) {
  float c = tt__camera_cos_on_film(frame, dir, fx, fy);
  if (!(c > 0.0f)) return 0.0f;
  float c2 = c * c;
  return 1.0f / (tt_camera_film_area(frame) * c2 * c2);
}

TT_API float tt_camera_pdf_dir(const tt_camera_frame *frame, const float dir[3]) {
  float c = tt__camera_cos_on_film(frame, dir, NULL, NULL);
  if (!(c > 0.0f)) return 0.0f;
  return 1.0f / (tt_camera_film_area(frame) * c * c * c);
}

/* Radical inverse of n in an integer base (exact enough for jitter offsets). */
static float tt__radical_inverse(uint32_t n, uint32_t base) {
  double inv = 1.0 / base, f = inv, r = 0.0;
  while (n) {
    r += (double)(n % base) * f;
    n /= base;
    f *= inv;
  }
  return (float)r;
}

TT_API void tt_jitter_halton23(uint32_t index, float offset[2]) {
  uint32_t n = (index & 0x7fffffffu) + 1u; /* index 0 uses Halton index 1 */
  offset[0] = tt__radical_inverse(n, 2) - 0.5f;
  offset[1] = tt__radical_inverse(n, 3) - 0.5f;
  /* Float rounding of values just below 1 must not produce +0.5. */
  for (int i = 0; i < 2; ++i)
    if (offset[i] >= 0.5f) offset[i] = nextafterf(0.5f, 0.0f);
}
