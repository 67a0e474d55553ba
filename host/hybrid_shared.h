/* host: what the hybrid loop over a camera path (hybrid.c) and along an animated sequence
 * (sequence_hybrid.c) share: the model, the warm start, the --stats record of a state. */
#ifndef TT_HOST_HYBRID_SHARED_H
#define TT_HOST_HYBRID_SHARED_H

#include "session.h"

#include <cjson/cJSON.h>
#include <tunetrace/hybrid.h>

/* What a still's measurement and a sequence's share no cost with: rows whose context says
 * another "measure" (a sequence's "mean per-frame accel update + render"; a still's has
 * none) are never learnt by a warm start, nor another clock, spp, thread count or
 * resolution. */
extern const char *const tt__hyb_context_keys[];
extern const char *const tt__hyb_camera_keys[];

/* The measure a sequence's states record in their context (sequence_tune.c,
 * sequence_hybrid.c): one measurement = a window of frames, each an accel update and a
 * render. */
#define TT__SEQ_MEASURE "mean per-frame accel update + render"
/* Frames per state along a sequence without --tune-window (as tuning along it). */
#define TT__SEQ_HYBRID_WINDOW 8u

/* Creates the model of predictor `pp` over `target` (the searched parameters) for states
 * in the space `norm` names; loads `model_path` when that file exists. Prints what failed;
 * an exit code. */
int tt__hyb_model_create(tt_session *lib, const tt_host *host, tt_loaded_plugin *pp,
                         const tt_space *target, const tt_indicator_norm *norm, uint64_t seed,
                         const char *model_path, const tt_predictor_iface **pi,
                         tt_predictor **model);

/* Every --warm-start file exists (checked before the scene loads); prints, exit code. */
int tt__hyb_warm_files(const tt__host_options *opt);

/* What a warm start compares rows with, and names in its log. */
typedef struct tt__hyb_warm_args {
  const tt_host *host;
  const tt__host_options *opt; /* --warm-start files */
  const char *predictor_name, *accel_name, *objective;
  const char *context, *camera; /* this run's state (the filter's expected values) */
} tt__hyb_warm_args;

/* Teaches `hy`'s model every usable row of each --warm-start database, logging what was
 * learnt and why rows were left out; `*out` receives the --stats record of it (owned by
 * the caller, also on failure). Prints what failed; an exit code. */
int tt__hyb_warm_all(const tt__hyb_warm_args *a, tt_hybrid *hy, cJSON **out);

/* The --stats record of one state: its report, `where` (e.g. "path_index") = `index`, the
 * state's total ms and the passes it rendered. */
cJSON *tt__hyb_state_json(const tt_hybrid_report *r, const char *where, uint32_t index,
                          double total_ms, uint32_t passes);

/* Writes `root` to `path` atomically; prints a failure (--stats), TT_EXIT_OUTPUT. */
int tt__hyb_write_json(const char *path, cJSON *root);

#endif
