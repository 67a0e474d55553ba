/* host: the session every job renders through (session.c), over the library's render
 * session (tunetrace/session.h): options become library calls, failures become messages and
 * exit codes, and the run record (--stats) mirrors the library's statistics. Render (run.c),
 * tuning (tune.c) and sequences (sequence.c) set it up the same way; none of them calls back
 * into another's file. */
#ifndef TT_HOST_SESSION_H
#define TT_HOST_SESSION_H

#include "host.h"

typedef struct tt__session {
  const tt__host_options *opt;
  const tt_host *host;
  tt_session *lib; /* owns the scene, plugins, configurations, accel, film */
  /* views into lib, valid after tt__session_open (film: after tt__session_start) */
  tt_scene *scene;
  const tt_camera *camera; /* the scene's camera (after --camera-index) */
  tt_registry *reg;
  tt_config *configs[TT_HOST_MAX_LIST]; /* per loaded plugin, registry order, may be NULL */
  tt_loaded_plugin *accel_p, *integ_p;
  tt_film *film;
  tt__run_record rec; /* what the passes and builds measured, for --stats */
} tt__session;

/* Opens a session: host services and --threads, the scene (--res, --camera-index), every
 * --plugin/--post and the default accel and integrator, one configuration per plugin
 * (defaults, scene settings, --set), checked. Prints what failed and returns a TT_EXIT_*
 * code; close the session in any case. */
int tt__session_open(tt__session *s, const tt__host_options *opt);

/* Builds the accel over the scene, creates the integrator and a film of the camera's size
 * with `aovs` (TT_AOV_* bits). Prints what failed; TT_EXIT_OK or TT_EXIT_FAILURE. */
int tt__session_start(tt__session *s, uint32_t aovs);

/* Renders one pass of `spp` samples per pixel into the film and accounts it in the run
 * record; `ps` receives the pass statistics and `*ms` its wall time. */
tt_status tt__session_render_pass(tt__session *s, uint32_t spp, tt_pass_stats *ps, double *ms);

/* Copies the library session's statistics (passes, spp, times, build) into the run record:
 * after anything that rendered or built through the library directly (tuning). */
void tt__session_sync(tt__session *s);

/* Comma-separated names of the loaded plugins, for messages. */
void tt__session_plugin_names(const tt__session *s, char *buf, size_t n);

/* Frees everything the session holds (a zeroed or half-opened session too). */
void tt__session_close(tt__session *s);

/* Creates a registry with the command line's --plugin-path folders. */
tt_registry *tt__make_registry(const tt__host_options *opt, const tt_host *host);

#endif
