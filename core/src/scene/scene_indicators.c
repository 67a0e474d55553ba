/* Scene indicators of thesis Table 3.2 (section 3.3.1): the 17 numbers the tuners and
 * predictors use as the "state" of a scene.
 *
 * Normalisation, following the thesis: "we divide any surface-related value by the square
 * of the diagonal of the scene's bounding box". With D = |hi - lo| (the `extent` indicator,
 * world units) every area below is divided by D^2:
 *   total_area        = sum of all triangle areas / D^2
 *   light_area        = sum of the area lights' areas / D^2   (point/spot/distant/env: 0)
 *   area_per_mesh     = total_area / meshes
 *   VarTriSize[m]     = population variance over mesh m's triangles of (triangle area / D^2)
 *   mean_var_tri_size = mean of VarTriSize over meshes
 *   var_var_tri_size  = population variance of VarTriSize over meshes
 * Counts, the camera position/target (world units, the still camera) and the vertical fov
 * (degrees) are not normalised: the thesis normalises surface values only. D = 0 (a scene
 * without extent) is treated as D = 1 so nothing divides by zero.
 *
 * diffuse_ratio is the area-weighted mean over meshes of how diffuse the mesh's material
 * is: diffuse 1; mirror and dielectric 0 ("for transparent or mirror-like objects, it is
 * zero"); plastic lum(albedo) / (lum(albedo) + lum(specular)), the share of the diffuse
 * base in its reflectance; conductor min(1, sqrt(alpha_x * alpha_y)), since rough metal
 * scatters broadly and smooth metal is mirror-like. 0 for a scene without area.
 */
#include "scene/scene_internal.h"

#include <math.h>
#include <stdlib.h>

static const char *const tt__indicator_names[TT_SCENE_INDICATOR_COUNT] = {
    "meshes",          "triangles",  "lights",        "camera_x",
    "camera_y",        "camera_z",   "target_x",      "target_y",
    "target_z",        "fov_y",      "diffuse_ratio", "extent",
    "total_area",      "light_area", "area_per_mesh", "mean_var_tri_size",
    "var_var_tri_size"};

/* Short snake_case names, stable: tuning databases store them as column names. */
const char *tt_scene_indicator_name(uint32_t index) {
  return index < TT_SCENE_INDICATOR_COUNT ? tt__indicator_names[index] : NULL;
}

/* Rec. 709 luminance, to weigh colour channels as the eye (and the image metric) does. */
static double tt__lum(const float c[3]) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

/* How diffuse a material is, in [0, 1] (see the file comment). */
static double tt__diffuseness(const tt_material *m) {
  switch (m->type) {
  case TT_MATERIAL_DIFFUSE: return 1.0;
  case TT_MATERIAL_MIRROR:
  case TT_MATERIAL_DIELECTRIC: return 0.0;
  case TT_MATERIAL_PLASTIC: {
    double kd = tt__lum(m->albedo), ks = tt__lum(m->specular);
    return kd + ks > 0 ? kd / (kd + ks) : 0.0;
  }
  case TT_MATERIAL_CONDUCTOR: {
    double a = sqrt((double)m->alpha[0] * m->alpha[1]);
    return a < 1.0 ? a : 1.0;
  }
  }
  return 0.0;
}

/* Two passes per mesh (mean, then variance) keep the variance accurate for the tiny
 * normalised areas of finely tessellated meshes. */
void tt_scene_indicators(const tt_scene *s, double out[TT_SCENE_INDICATOR_COUNT]) {
  for (int i = 0; i < TT_SCENE_INDICATOR_COUNT; i++) out[i] = 0.0;
  if (!s) return;
  double d2 = 0.0;
  for (int a = 0; a < 3; a++) {
    double e = (double)s->hi[a] - s->lo[a];
    d2 += e * e;
  }
  double extent = sqrt(d2);
  double norm = d2 > 0 ? 1.0 / d2 : 1.0;

  double total = 0.0, diffuse = 0.0, light_area = 0.0;
  double vsum = 0.0, vsum2 = 0.0;
  for (uint32_t i = 0; i < s->mesh_count; i++) {
    const tt_mesh *m = &s->meshes[i];
    double sum = 0.0;
    for (uint32_t t = 0; t < m->triangle_count; t++)
      sum += tt__triangle_area(m->positions, m->indices, t) * norm;
    double mean = m->triangle_count ? sum / m->triangle_count : 0.0, var = 0.0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
      double dv = tt__triangle_area(m->positions, m->indices, t) * norm - mean;
      var += dv * dv;
    }
    if (m->triangle_count) var /= m->triangle_count;
    total += sum;
    diffuse += sum * tt__diffuseness(&s->materials[m->material]);
    vsum += var;
    vsum2 += var * var;
  }
  for (uint32_t i = 0; i < s->light_count; i++)
    if (s->lights[i].type == TT_LIGHT_AREA) light_area += s->lights[i].area * norm;
  double n = s->mesh_count;
  double vmean = n > 0 ? vsum / n : 0.0;
  double vvar = n > 0 ? vsum2 / n - vmean * vmean : 0.0;
  if (vvar < 0) vvar = 0; /* rounding in E[x^2] - E[x]^2 */

  out[0] = s->mesh_count;
  out[1] = (double)s->triangle_count;
  out[2] = s->light_count;
  for (int a = 0; a < 3; a++) {
    out[3 + a] = s->camera.position[a];
    out[6 + a] = s->camera.target[a];
  }
  out[9] = s->camera.fov_y;
  out[10] = total > 0 ? diffuse / total : 0.0;
  out[11] = extent;
  out[12] = total;
  out[13] = light_area;
  out[14] = n > 0 ? total / n : 0.0;
  out[15] = vmean;
  out[16] = vvar;
}
