/* host: what sequence.c (the frame loop) and sequence_tune.c (tuning along it) share: the
 * sequence job and its per-frame step. */
#ifndef TT_HOST_SEQUENCE_INTERNAL_H
#define TT_HOST_SEQUENCE_INTERNAL_H

#include "sequence.h"

/* Everything one sequence run holds besides the session: the output names, the frame
 * buffers, the post-filter and the manifest. tt__seq_close frees it at any stage. */
typedef struct tt__seq {
  const tt__host_options *opt;
  tt__session ses; /* scene, plugins, configurations, accel, integrator, film */
  const tt_post_iface *pi;
  const tt_config *pcfg; /* the post-filter's configuration */
  tt_post *post;
  const char *post_name;
  uint64_t seed;
  uint32_t spp;
  char dir[4096];      /* output folder (--out-dir, or the folder of the --out pattern) */
  const char *pattern; /* file name part of the --out pattern, or NULL */
  uint32_t w, h, k;    /* frame size; k: --reference-scale (0: no reference) */
  double fps;
  int animated;     /* the scene moves: pose and accel update per frame */
  int render_frame; /* the jittered frame is rendered (not only the reference) */
  float *rgb, *ref_hi, *ref, *post_rgb, *motion, *prev_depth;
  tt_film *ref_film;
  FILE *manifest; /* memstream over mbuf: the manifest text so far */
  char *mbuf, mpath[4096 + 32];
  size_t mlen;
  int entry_open;       /* a frame's manifest entry is started but not closed */
  uint32_t done_frames; /* frames committed to the manifest */
  /* tuning along the sequence (sequence_tune.c), NULL without */
  struct tt__seq_tune *tune;
  const tt_config *switch_config; /* the next frame's update builds the accel with this
                                     configuration from scratch (NULL: updates as built) */
  const char *frame_note;         /* JSON members added to the next frame's manifest entry */
  double update_ms, render_ms;    /* what the last frame's update and render took */
  /* the hybrid loop along the sequence (sequence_hybrid.c), NULL without */
  struct tt__seq_hybrid *hybrid;
  int defer_commit; /* step leaves the manifest's commit to commit_frames */
  /* the frame loop's own steps, for sequence_hybrid.c (which sequence.c calls, never the
   * other way round): frame f (pose and accel update, render, outputs, its manifest entry,
   * the manifest committed unless defer_commit), and the manifest committed after `n`
   * deferred frames whose entries it now holds. Exit codes. */
  int (*step)(struct tt__seq *s, uint32_t f);
  int (*commit_frames)(struct tt__seq *s, uint32_t n);
} tt__seq;

/* One frame being rendered: its index, poses and jitter, what it has produced so far. */
typedef struct tt__seq_frame {
  uint32_t f, ji; /* frame index, index in the jitter cycle */
  float jit[2];
  tt_camera cam, prev; /* this frame's pose and the pose one frame interval earlier */
  const float *depth;  /* the film's depth AOV (NULL when the frame was not rendered) */
  double render_ms, ref_ms;
} tt__seq_frame;

/* Tuning along the sequence (sequence_tune.c): with a tuner loaded (or --explore N) over an
 * animated scene, the frames are the measurements. tt__seq_tune_create sets s->tune (left
 * NULL when nothing is tuned); around each frame's step, tt__seq_tune_before starts a window
 * when one is due (the search's next configuration in s->switch_config, the manifest note in
 * s->frame_note) and tt__seq_tune_after adds the frame's times (s->update_ms, s->render_ms)
 * and reports a finished window; tt__seq_tune_finish logs what was found; tt__seq_tune_free
 * releases it. Exit codes. (The frame loop calls these, never the other way round.) */
/* The accel's tuning plan and objective along a sequence (--tune, --tune-params, --objective
 * checked); `job` names the caller in messages. Prints, exit code. */
int tt__seq_accel_plan(tt__seq *s, const char *job, tt_tuning_plan *plan, const char **objective,
                       tt_objective *obj);
int tt__seq_tune_create(tt__seq *s);
int tt__seq_tune_before(tt__seq *s, uint32_t f);
int tt__seq_tune_after(tt__seq *s, uint32_t f);
int tt__seq_tune_finish(tt__seq *s, int rc);
void tt__seq_tune_free(tt__seq *s);

/* The hybrid loop along the sequence (sequence_hybrid.c), with --hybrid: each window of
 * --tune-window frames a state, explored (a search replaying the window) or exploited (the
 * model's configuration, played once). tt__seq_hybrid_create sets s->hybrid (or prints and
 * fails: a still scene, a post-filter); tt__seq_hybrid_run plays the frames (instead of the
 * frame loop); tt__seq_hybrid_finish logs, saves --model and writes --stats;
 * tt__seq_hybrid_free releases it. Exit codes. */
int tt__seq_hybrid_create(tt__seq *s);
int tt__seq_hybrid_run(tt__seq *s);
int tt__seq_hybrid_finish(tt__seq *s, int rc);
void tt__seq_hybrid_free(tt__seq *s);

#endif
