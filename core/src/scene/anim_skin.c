/* Skins of animated meshes (scene/anim.h): the joints, inverse bind matrices and per-vertex
 * influences a loader hands over are checked (joints that exist, finite affine matrices,
 * weights that sum to 1) and copied with the weights normalised, so posing never meets a
 * missing joint or a vertex that shrinks toward the origin. */
#include "scene/anim.h"
#include "scene/scene_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Exporters quantise weights (8-bit normalised: 4 weights off by up to 0.5/255 each), so
 * a sum within 1% of 1 is a rounding of 1 and anything further is a broken file. */
#define TT__SKIN_WEIGHT_TOLERANCE 0.01

tt_status tt__mesh_anim_set_skin(tt_scene *s, tt__mesh_anim *m, uint32_t joints,
                                 const int32_t *joint_node, const char *const *joint_name,
                                 const double *inverse_bind, uint32_t influences,
                                 const uint32_t *joint_index, const float *joint_weight,
                                 const char *where) {
  const tt__scene_anim *a = s->anim;
  const uint32_t nodes = a ? a->node_count : 0;
  const uint32_t nv = s->meshes[m->mesh].vertex_count;
  if (joints == 0 || influences == 0)
    return tt_set_error(TT_ERR_PARSE, "%s: a skin needs at least one joint and one influence",
                        where);
  for (uint32_t j = 0; j < joints; j++) {
    if (joint_node[j] < 0 || (uint32_t)joint_node[j] >= nodes)
      return tt_set_error(TT_ERR_PARSE,
                          "%s: joint %u%s%s%s refers to a missing node (expected one of the %u "
                          "nodes of the file)",
                          where, j, joint_name ? " \"" : "", joint_name ? joint_name[j] : "",
                          joint_name ? "\"" : "", nodes);
    const double *ib = inverse_bind + 16 * (size_t)j;
    for (int e = 0; e < 16; e++)
      if (!isfinite(ib[e]))
        return tt_set_error(TT_ERR_PARSE,
                            "%s: inverse bind matrix of joint %u%s%s%s: element %d is %g "
                            "(expected finite numbers)",
                            where, j, joint_name ? " \"" : "", joint_name ? joint_name[j] : "",
                            joint_name ? "\"" : "", e, ib[e]);
    if (ib[12] != 0.0 || ib[13] != 0.0 || ib[14] != 0.0 || ib[15] != 1.0)
      return tt_set_error(TT_ERR_PARSE,
                          "%s: inverse bind matrix of joint %u%s%s%s: expected an affine matrix "
                          "(last row 0 0 0 1), got %g %g %g %g",
                          where, j, joint_name ? " \"" : "", joint_name ? joint_name[j] : "",
                          joint_name ? "\"" : "", ib[12], ib[13], ib[14], ib[15]);
  }
  for (uint32_t v = 0; v < nv; v++) {
    double sum = 0;
    for (uint32_t k = 0; k < influences; k++) {
      const size_t at = (size_t)v * influences + k;
      const float w = joint_weight[at];
      if (!isfinite(w) || w < 0)
        return tt_set_error(TT_ERR_PARSE,
                            "%s: vertex %u: joint weight %u is %g (expected a finite weight >= 0)",
                            where, v, k, w);
      if (w > 0 && joint_index[at] >= joints)
        return tt_set_error(TT_ERR_PARSE,
                            "%s: vertex %u: influence %u names joint %u, but the skin has %u "
                            "joints (a skin referencing a missing joint)",
                            where, v, k, joint_index[at], joints);
      sum += w;
    }
    if (!(fabs(sum - 1.0) <= TT__SKIN_WEIGHT_TOLERANCE))
      return tt_set_error(TT_ERR_PARSE,
                          "%s: vertex %u: joint weights sum to %.6g (expected 1 within %g: every "
                          "vertex of a skinned mesh needs normalised weights, and each of its "
                          "joint indices must name a joint of the skin)",
                          where, v, sum, TT__SKIN_WEIGHT_TOLERANCE);
  }
  const size_t ni = (size_t)nv * influences;
  m->joint_node = malloc(sizeof(int32_t) * joints);
  m->inverse_bind = malloc(sizeof(double) * 16 * joints);
  m->joint_index = malloc(sizeof(uint32_t) * (ni ? ni : 1));
  m->joint_weight = malloc(sizeof(float) * (ni ? ni : 1));
  if (!m->joint_node || !m->inverse_bind || !m->joint_index || !m->joint_weight)
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", where);
  memcpy(m->joint_node, joint_node, sizeof(int32_t) * joints);
  memcpy(m->inverse_bind, inverse_bind, sizeof(double) * 16 * joints);
  for (uint32_t v = 0; v < nv; v++) {
    double sum = 0;
    for (uint32_t k = 0; k < influences; k++) sum += joint_weight[(size_t)v * influences + k];
    for (uint32_t k = 0; k < influences; k++) {
      const size_t at = (size_t)v * influences + k;
      const float w = (float)(joint_weight[at] / sum);
      m->joint_weight[at] = w;
      m->joint_index[at] = w > 0 ? joint_index[at] : 0;
    }
  }
  m->joints = joints;
  m->influences = influences;
  return TT_OK;
}
