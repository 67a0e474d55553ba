/* pbrt-v4 scene importer, entry point: reads directive after directive (pbrt_directives.c)
 * into a flattened tt_scene (world-space triangle meshes, tt_material, lights, camera,
 * resolution). The subset covers the shared test scenes; everything else warns once per
 * (file:line, name) and is skipped or approximated. The mapping and its approximations are
 * documented in scenes/README.md, "Importing pbrt-v4 scenes"; the files of the importer
 * are listed in pbrt_internal.h. */
#include "io/pbrt/pbrt_internal.h"
#include "plugin/log.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* The flags of the tt_scene_load_ex call running on this thread (pbrt.h): set by
 * tt_scene_load_ex (io/scene_load.c), defined here, in the layer that reads them. */
_Thread_local uint32_t tt__scene_load_flags;

/* ---- entry point ----------------------------------------------------------------------- */

/* Frees the parser's own state (never the scene). */
static void tt__pp_free(tt__pp *P) {
  for (tt__pfile *f = P->files; f;) {
    tt__pfile *n = f->next;
    free(f->path);
    free(f->dir);
    free(f->text);
    free(f);
    f = n;
  }
  for (size_t i = 0; i < P->nwarned; i++) free(P->warned[i]);
  free(P->warned);
  free(P->stack);
  for (size_t i = 0; i < P->nnmat; i++) free(P->nmat[i].name);
  free(P->nmat);
  for (size_t i = 0; i < P->nntex; i++) {
    free(P->ntex[i].name);
    free(P->ntex[i].image);
  }
  free(P->ntex);
  for (size_t i = 0; i < P->ncs; i++) free(P->cs[i].name);
  free(P->cs);
  for (size_t i = 0; i < P->nobj; i++) {
    for (size_t k = 0; k < P->obj[i].n; k++) tt__mesh_data_free(&P->obj[i].m[k].d);
    free(P->obj[i].m);
    free(P->obj[i].name);
  }
  free(P->obj);
  free(P->der);
}

/* pbrt's fov spans the shorter image side (or the screen window's height). */
static void tt__finish_camera(tt__pp *P) {
  tt_camera *c = &P->scene->camera;
  c->width = (uint32_t)P->xres;
  c->height = (uint32_t)P->yres;
  double aspect = P->frame_aspect > 0 ? P->frame_aspect : (double)P->xres / (double)P->yres;
  double t = tan(0.5 * P->fov * TT__PI / 180.0);
  double half_h = P->has_sw ? 0.5 * (P->sw[3] - P->sw[2]) : (aspect > 1 ? 1.0 : 1.0 / aspect);
  double fy = 2.0 * atan(t * half_h) * 180.0 / TT__PI;
  if (fy < 1e-3) fy = 1e-3;
  if (fy > 179.9) fy = 179.9;
  c->fov_y = (float)fy;
}

tt_status tt__scene_load_pbrt(const char *path, tt_scene **out) {
  if (!out) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_scene_load: out is NULL");
  *out = NULL;
  tt__pp P;
  memset(&P, 0, sizeof P);
  P.scene = tt__scene_new(path);
  if (!P.scene) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
  /* pbrt-v4 defaults: 16 samples per pixel, path depth 5, 1280x720, fov 90 */
  P.scene->settings.spp = 16;
  P.scene->settings.max_depth = 5;
  P.xres = 1280;
  P.yres = 720;
  P.fov = 90;
  P.cur_obj = -1;
  P.default_mat = -1;
  P.gs.mat = -1;
  P.strict = (tt__scene_load_flags & TT_SCENE_LOAD_STRICT) != 0;
  tt__ident(P.gs.ctm);
  tt__ident(P.gs.ctm_end);
  P.gs.active = TT__ACTIVE_ALL;
  P.gs.t_start = 0.0; /* pbrt-v4's TransformTimes default */
  P.gs.t_end = 1.0;
  tt_status st = tt__push_file(&P, path, NULL, 0);
  int done = 0;
  while (st == TT_OK && !done) st = tt__directive(&P, &done);
  if (st == TT_OK) st = tt__pstrict_result(&P);
  if (st == TT_OK && P.cur_obj >= 0)
    st = tt__perr(P.files, P.files ? P.files->line : 0, "ObjectBegin \"%s\" is never closed",
                  P.obj[P.cur_obj].name);
  if (st == TT_OK) {
    if (!P.in_world && P.scene->mesh_count == 0)
      tt__pwarn(&P, P.files, 0, "WorldBegin", "no WorldBegin: the file describes no world");
    tt__world_setup(&P);
    tt__finish_camera(&P);
    st = tt__motion_camera(&P);
    if (st == TT_OK) st = tt__scene_finish(P.scene);
  }
  if (P.suppressed) tt__log(TT_LOG_WARN, "%s: %u more warnings suppressed", path, P.suppressed);
  tt__pp_free(&P);
  if (st != TT_OK) {
    tt_scene_destroy(P.scene);
    return st;
  }
  *out = P.scene;
  return TT_OK;
}
