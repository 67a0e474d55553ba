/* The render session's state (tunetrace/session.h), shared by session.c (set-up, rendering)
 * and session_tuning.c (the tuning target and state). */
#ifndef TT_SESSION_INTERNAL_H
#define TT_SESSION_INTERNAL_H

#include <tunetrace/options.h>
#include <tunetrace/post.h>
#include <tunetrace/session.h>

struct tt_session {
  const tt_host *host;
  tt_registry *reg;
  tt_scene *scene;
  tt_camera prev_camera; /* the previous frame's pose for TT_AOV_MOTION */
  int has_prev;
  /* per loaded plugin, registry order */
  tt_config **configs;      /* NULL where the plugin publishes no space */
  unsigned char *depth_set; /* maxDepth set with tt_session_set: the scene's does not apply */
  size_t config_cap;
  /* every value tt_session_set accepted, in order: the user's settings, which a tuning
   * plan puts back on top of a tuning hint's setup (session_tuning.c) */
  struct tt__session_setting {
    size_t index; /* registry index of the plugin */
    char *key, *value;
  } * settings;
  size_t setting_count, setting_cap;
  tt_loaded_plugin *accel_p, *integ_p;
  const tt_accel_iface *ai;
  const tt_integrator_iface *ii;
  tt_accel *accel;
  tt_integrator *integrator;
  tt_film *film;
  int started;
  int seed_set;
  uint32_t pass; /* passes in the film since the last reset */
  tt_session_stats stats;
  /* the tuning target (session_tuning.c) */
  size_t target_index;
  uint32_t target_kind;
  int want_images;
  const tt_post_iface *pi;
  tt_post *post;
  float *post_in, *post_out;
  float *snap; /* film accumulators before a measurement pass */
  double snap_scale;
  float *pass_rgb; /* the image a measurement pass alone rendered */
  tt_pass_stats ps;
  char *state_camera, *state_context;
};

/* Records `fmt` followed by the current error message as the new error (the message is
 * copied first: tt_set_error may not read the buffer it writes). Returns `status`. */
tt_status tt__session_error(tt_status status, const char *fmt, ...) TT_PRINTF(2, 3);

#endif
