/* host --convert: loads any scene tt_scene_load reads (scene.json, pbrt-v4) and writes it as
 * scene.json v1 with PLY meshes (tt_scene_write_json); nothing is rendered. */
#include "host.h"

#include <stdio.h>

/* Load, write, report; exit codes as for a render (4 scene error, 5 output not written). */
int tt__run_convert(const tt__host_options *opt) {
  tt_set_log_host(tt__host_services(opt->quiet)); /* loader and writer warnings */
  tt_scene *scene = NULL;
  if (tt_scene_load_ex(opt->scene, opt->strict ? TT_SCENE_LOAD_STRICT : TT_SCENE_LOAD_DEFAULT,
                       &scene) != TT_OK) {
    tt__say("%s\n", tt_last_error());
    return TT_EXIT_SCENE;
  }
  int rc = TT_EXIT_OK;
  if (tt_scene_write_json(scene, opt->out) != TT_OK) {
    tt__say("%s\n", tt_last_error());
    rc = TT_EXIT_OUTPUT;
  } else if (!opt->quiet) {
    tt__say("wrote %s (%u meshes, %llu triangles, %u materials, %u lights)\n", opt->out,
            tt_scene_mesh_count(scene), (unsigned long long)tt_scene_triangle_count(scene),
            tt_scene_material_count(scene), tt_scene_light_count(scene));
  }
  tt_scene_destroy(scene);
  return rc;
}
