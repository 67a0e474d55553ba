/* The bidirectional path sampler's multiple-importance weights (white-box: bdpt.c and the
 * render sources compiled in). For every connection (s, t) with s, t >= 2 or s = 0 that
 * contributes, the path it built is split again into every strategy (s', t') that could have
 * produced it, each split's subpaths getting the densities their random walks would have
 * given them; the weights of all splits must sum to 1 (power and balance heuristics), and
 * the split equal to the connection must reproduce the weight the connection reported (to
 * 1e-3: the test shrinks the ray offsets, which otherwise make a subpath's stored densities,
 * of its sampled directions, differ from those of the vertex positions by ~1e-4 / distance).
 * Scenes: a closed box (one-sided area light, diffuse, plastic, rough metal, a rough glass
 * block, smooth shading normals) where every strategy is valid; an open floor under an
 * environment with a rough glass block (vertices at infinity, transmission, importance
 * transport); the same with a point light (a delta light: s' = 0 excluded). */
#include <stdlib.h>

#include "path_common.h"
#include "render/bdpt_internal.h"
#include "tt_test.h"

#define MAXV 8

/* Interleaved streams over one independent sample: dim -> 3 dim + stream. */
typedef struct stream {
  pt_sampler_src *src;
  uint32_t k;
} stream;
static float stream_get(void *self, uint32_t dim) {
  stream *s = self;
  return pt_src_get(s->src, 3 * dim + s->k);
}

typedef struct full_path {
  uint32_t k;
  tt__bvertex v[MAXV];    /* v[0] on the light (as a light vertex) ... v[k-1] the camera */
  tt__bvertex light_surf; /* v[0] as a surface of the camera subpath (s' = 0) */
  float A[MAXV], B[MAXV]; /* densities of each vertex from the light side / camera side */
} full_path;

/* The light vertex of an emissive surface vertex and vice versa. */
static void as_light(const tt_path_tracer *pt, const tt__bvertex *surf, tt__bvertex *out) {
  *out = *surf;
  if (surf->kind != TT__BV_SURFACE) return;
  (void)pt;
  out->kind = TT__BV_LIGHT;
  out->delta = 0;
}
static void as_surface(const tt_path_tracer *pt, const tt__bvertex *l, tt__bvertex *out) {
  *out = *l;
  if (l->kind != TT__BV_LIGHT || l->infinite) return;
  const tt__light *light = &pt->lights.lights[l->light];
  out->kind = TT__BV_SURFACE;
  out->mesh = light->mesh;
  out->bsdf = pt->bsdfs[tt_scene_mesh(pt->scene, light->mesh)->material];
  memcpy(out->ns, out->ng, sizeof out->ns);
  tt__frame_from(&out->frame, out->ns, out->ng);
}

static void densities(const tt_path_tracer *pt, const tt_camera_frame *fr, full_path *f) {
  uint32_t k = f->k;
  for (uint32_t m = 0; m < k; ++m) {
    if (m == 0) f->A[m] = tt__bv_pdf_light_origin(pt, &f->v[0], &f->v[1]);
    else f->A[m] = tt__bv_pdf(pt, fr, &f->v[m - 1], m >= 2 ? &f->v[m - 2] : NULL, &f->v[m]);
    if (m == k - 1) f->B[m] = 0.0f;
    else f->B[m] = tt__bv_pdf(pt, fr, &f->v[m + 1], m + 2 <= k - 1 ? &f->v[m + 2] : NULL, &f->v[m]);
  }
}

/* Weight of split (s, t) of the full path. */
static float split_weight(const tt_path_tracer *pt, const tt_camera_frame *fr, tt_mis_heuristic h,
                          const full_path *f, uint32_t s) {
  uint32_t k = f->k, t = k - s;
  tt__bvertex L[MAXV], C[MAXV], sampled;
  for (uint32_t i = 0; i < s; ++i) {
    L[i] = f->v[i];
    L[i].pdf_fwd = f->A[i];
    L[i].pdf_rev = f->B[i];
  }
  for (uint32_t j = 0; j < t; ++j) {
    uint32_t m = k - 1 - j;
    C[j] = m == 0 ? f->light_surf : f->v[m];
    C[j].pdf_fwd = f->B[m];
    C[j].pdf_rev = f->A[m];
  }
  if (s == 1) sampled = L[0];
  if (t == 1) sampled = C[0];
  return tt__bdpt_mis_weight(pt, fr, h, L, C, (s == 1 || t == 1) ? &sampled : NULL, s, t);
}

static void run_scene(const char *name, const char *json, int delta_light, uint32_t samples) {
  pt_fixture fx;
  CHECK(pt_fixture_load(&fx, json));
  if (!fx.pt) return;
  tt_camera_frame fr;
  CHECK(tt_camera_frame_init(&fr, tt_scene_camera(fx.scene)) == TT_OK);
  tt_bdpt_paths *paths;
  CHECK(tt_bdpt_paths_create(4, &paths) == TT_OK);
  pt_sampler_src src;
  memset(&src, 0, sizeof src);
  src.iface = tt_builtin_sampler("independent");
  src.iface->create(NULL, 99, &src.sampler);
  stream cs = {&src, 0}, ls = {&src, 1}, ks = {&src, 2};
  tt_sample_source cam = {stream_get, NULL, &cs}, lig = {stream_get, NULL, &ls},
                   con = {stream_get, NULL, &ks};
  const tt_mis_heuristic hs[2] = {TT_MIS_POWER, TT_MIS_BALANCE};
  uint32_t checked = 0, bad_sum = 0, bad_self = 0, by_len[MAXV] = {0};
  double worst = 0.0;
  float worst_self = 0.0f;
  for (uint32_t i = 0; i < samples; ++i) {
    tt_bdpt_options o;
    tt_bdpt_options_default(&o);
    o.max_depth = 4;
    o.heuristic = hs[i & 1];
    src.iface->start(src.sampler, src.state, i % 7, i / 7, i);
    float fxp = pt_src_get(&src, 0) * fr.width, fyp = pt_src_get(&src, 3) * fr.height;
    uint32_t nc =
        tt_bdpt_camera_subpath(fx.pt, &fx.tracer, &o, &fr, fxp, fyp, &cam, o.max_depth + 2, paths);
    uint32_t nl = tt_bdpt_light_subpath(fx.pt, &fx.tracer, &o, &lig, o.max_depth + 1, paths);
    for (uint32_t t = 2; t <= nc; ++t)
      for (uint32_t s = 0; s <= nl; ++s) {
        if (s == 1 || s + t - 2 > o.max_depth) continue;
        tt_bdpt_contribution c;
        if (!tt_bdpt_connect(fx.pt, &fx.tracer, &o, &fr, paths, s, t, &con, 0, &c)) continue;
        full_path f;
        memset(&f, 0, sizeof f);
        f.k = s + t;
        for (uint32_t a = 0; a < s; ++a) f.v[a] = paths->light[a];
        for (uint32_t b = 0; b < t; ++b) f.v[s + b] = paths->camera[t - 1 - b];
        if (s == 0) {
          f.light_surf = f.v[0];
          as_light(fx.pt, &f.light_surf, &f.v[0]);
        } else {
          as_surface(fx.pt, &f.v[0], &f.light_surf);
        }
        densities(fx.pt, &fr, &f);
        double sum = 0.0;
        for (uint32_t s2 = 0; s2 < f.k; ++s2) {
          if (s2 == 0 && delta_light) continue;
          if (s2 == 1 && f.k - s2 == 1) continue; /* (1, 1): not a strategy */
          float w = split_weight(fx.pt, &fr, o.heuristic, &f, s2);
          if (s2 == s && fabsf(w - c.weight) > worst_self) worst_self = fabsf(w - c.weight);
          if (s2 == s && fabsf(w - c.weight) > 1e-3f) {
            if (bad_self < 5)
              fprintf(stderr, "%s: (s, t) = (%u, %u): split weight %.6f, connection %.6f\n", name,
                      s, t, w, c.weight);
            bad_self++;
          }
          if (getenv("MIS_DEBUG")) fprintf(stderr, "  k=%u s'=%u w=%.6f\n", f.k, s2, w);
          sum += w;
        }
        checked++;
        by_len[f.k]++;
        double err = fabs(sum - 1.0);
        if (err > worst) worst = err;
        if (err > 2e-3) {
          if (bad_sum < 5)
            fprintf(stderr, "%s: (s, t) = (%u, %u): weights sum to %.6f\n", name, s, t, sum);
          bad_sum++;
        }
      }
  }
  printf("%s: %u paths checked (lengths 2-6: %u %u %u %u %u), worst |sum - 1| = %.2e, worst "
         "|split - connection| = %.2e\n",
         name, checked, by_len[2], by_len[3], by_len[4], by_len[5], by_len[6], worst, worst_self);
  CHECK_MSG(checked > samples / 4, "%s: only %u contributing connections", name, checked);
  CHECK_MSG(by_len[5] + by_len[6] > 0, "%s: no long path was checked", name);
  CHECK_MSG(bad_sum == 0, "%s: %u paths whose strategy weights do not sum to 1", name, bad_sum);
  CHECK_MSG(bad_self == 0, "%s: %u connections whose weight the split does not reproduce", name,
            bad_self);
  src.iface->destroy(src.sampler);
  tt_bdpt_paths_destroy(paths);
  pt_fixture_free(&fx);
}

#define HEAD(res)                                                                                  \
  "{\"version\":1,\"camera\":{\"position\":[0,0,3.4],\"target\":[0,0,0],\"up\":[0,1,0],\"fov\":"   \
  "45,"                                                                                            \
  "\"resolution\":[" res "]},\"materials\":{"                                                      \
  "\"white\":{\"type\":\"diffuse\",\"albedo\":[0.7,0.7,0.7]},"                                     \
  "\"red\":{\"type\":\"diffuse\",\"albedo\":[0.7,0.1,0.1]},"                                       \
  "\"metal\":{\"type\":\"conductor\",\"alpha\":0.3},"                                              \
  "\"glossy\":{\"type\":\"plastic\",\"albedo\":[0.3,0.3,0.5],\"alpha\":0.15,\"ior\":1.5},"         \
  "\"glass\":{\"type\":\"dielectric\",\"alpha\":0.2,\"ior\":1.4},"                                 \
  "\"light\":{\"type\":\"diffuse\",\"albedo\":[0,0,0],\"emission\":[8,8,7]}},"
#define BLOCK                                                                                      \
  "{\"name\":\"block\",\"material\":\"glass\",\"positions\":[-0.4,-1,-0.3, 0.2,-1,-0.3, "          \
  "0.2,-0.2,-0.3, -0.4,-0.2,-0.3,"                                                                 \
  " -0.4,-1,0.3, 0.2,-1,0.3, 0.2,-0.2,0.3, -0.4,-0.2,0.3],\"indices\":[0,2,1, 0,3,2, 4,5,6, "      \
  "4,6,7, 0,1,5, 0,5,4,"                                                                           \
  " 3,6,2, 3,7,6, 0,4,7, 0,7,3, 1,2,6, 1,6,5]}"

int main(void) {
  static const char *BOX =
      HEAD("16,16") "\"meshes\":["
                    "{\"name\":\"floor\",\"material\":\"glossy\",\"positions\":[-1,-1,-1, 1,-1,-1, "
                    "1,-1,1, -1,-1,1],\"indices\":[0,2,1, 0,3,2]},"
                    "{\"name\":\"ceiling\",\"material\":\"white\",\"positions\":[-1,1,-1, 1,1,-1, "
                    "1,1,1, -1,1,1],\"indices\":[0,1,2, 0,2,3]},"
                    "{\"name\":\"back\",\"material\":\"metal\",\"positions\":[-1,-1,-1, 1,-1,-1, "
                    "1,1,-1, -1,1,-1],\"indices\":[0,1,2, 0,2,3]},"
                    "{\"name\":\"left\",\"material\":\"red\",\"positions\":[-1,-1,-1, -1,1,-1, "
                    "-1,1,1, -1,-1,1],\"indices\":[0,1,2, 0,2,3],"
                    " \"normals\":[0.9,0.3,0.3, 0.95,-0.2,0.1, 1,0,0, 0.9,0.1,-0.4]},"
                    "{\"name\":\"right\",\"material\":\"white\",\"positions\":[1,-1,-1, 1,1,-1, "
                    "1,1,1, 1,-1,1],\"indices\":[0,1,2, 0,2,3]},"
                    "{\"name\":\"front\",\"material\":\"white\",\"positions\":[-1,-1,3.5, "
                    "1,-1,3.5, 1,1,3.5, -1,1,3.5],\"indices\":[0,2,1, 0,3,2]},"
                    "{\"name\":\"lamp\",\"material\":\"light\",\"positions\":[-0.3,0.98,-0.3, "
                    "0.3,0.98,-0.3, 0.3,0.98,0.3, -0.3,0.98,0.3],\"indices\":[0,1,2, 0,2,3]}," BLOCK
                    "]}";
  static const char *OPEN_ENV =
      HEAD("16,16") "\"meshes\":["
                    "{\"name\":\"floor\",\"material\":\"white\",\"positions\":[-3,-1,-3, 3,-1,-3, "
                    "3,-1,3, -3,-1,3],\"indices\":[0,2,1, 0,3,2]}," BLOCK
                    "],\"lights\":[{\"type\":\"environment\",\"radiance\":[0.5,0.6,0.8]}]}";
  static const char *OPEN_POINT =
      HEAD("16,16") "\"meshes\":["
                    "{\"name\":\"back\",\"material\":\"white\",\"positions\":[-3,-1,-1.5, "
                    "3,-1,-1.5, 3,3,-1.5, -3,3,-1.5],\"indices\":[0,1,2, 0,2,3]},"
                    "{\"name\":\"floor\",\"material\":\"glossy\",\"positions\":[-3,-1,-3, 3,-1,-3, "
                    "3,-1,3, -3,-1,3],\"indices\":[0,2,1, 0,3,2]}," BLOCK
                    "],\"lights\":[{\"type\":\"point\",\"position\":[0.5,1.5,0.5],\"intensity\":[5,"
                    "5,5]}]}";
  run_scene("closed box", BOX, 0, 3000);
  run_scene("environment", OPEN_ENV, 0, 3000);
  run_scene("point light", OPEN_POINT, 1, 3000);
  return tt_test_finish("bdpt_mis");
}
