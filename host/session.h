/* host: the session every job renders through (session.c): the scene, the plugin registry
 * with one configuration per loaded plugin, the accel built over the scene, the integrator,
 * the film, and the run record its passes account into. Render (run.c), tuning (tune.c)
 * and sequences (sequence.c) set it up the same way; none of them calls back into another's
 * file. */
#ifndef TT_HOST_SESSION_H
#define TT_HOST_SESSION_H

#include "host.h"

typedef struct tt__session {
  const tt__host_options *opt;
  const tt_host *host;
  tt_scene *scene;
  const tt_camera *camera;      /* the scene's camera (after --camera-index) */
  tt_registry *reg;
  tt_config *configs[TT_HOST_MAX_LIST];  /* per loaded plugin, registry order, may be NULL */
  tt_loaded_plugin *accel_p, *integ_p;
  const tt_accel_iface *ai;
  const tt_integrator_iface *ii;
  tt_accel *accel;
  tt_integrator *integrator;
  tt_film *film;
  uint32_t pass;                /* passes rendered into the film */
  tt__run_record rec;           /* what the passes and builds measured, for --stats */
} tt__session;

/* Opens a session: host services and --threads, the scene (--res, --camera-index), the
 * registry with every --plugin/--post and the default accel and integrator, one
 * configuration per plugin (defaults, scene settings, --set). Prints what failed and
 * returns a TT_EXIT_* code; close the session in any case. */
int tt__session_open(tt__session *s, const tt__host_options *opt);

/* Builds the accel over the scene, creates the integrator and a film of the camera's size
 * with `aovs` (TT_AOV_* bits). Prints what failed; TT_EXIT_OK or TT_EXIT_FAILURE. */
int tt__session_start(tt__session *s, uint32_t aovs);

/* Renders one pass of `spp` samples per pixel into the film and accounts it in the run
 * record; `ps` receives the pass statistics and `*ms` its wall time. */
tt_status tt__session_render_pass(tt__session *s, uint32_t spp, tt_pass_stats *ps, double *ms);

/* Rebuilds the accel with `cfg` (the old structure is destroyed first); `*build_ms` is the
 * build time the accel reports, else the wall time. On success the build statistics go to
 * the run record. */
tt_status tt__session_rebuild_accel(tt__session *s, const tt_config *cfg, double *build_ms);

/* Registry index of a loaded plugin ((size_t)-1 if not loaded) and its configuration. */
size_t tt__session_index_of(const tt__session *s, const tt_loaded_plugin *p);
tt_config *tt__session_config_of(tt__session *s, const tt_loaded_plugin *p);

/* Comma-separated names of the loaded plugins, for messages. */
void tt__session_plugin_names(const tt__session *s, char *buf, size_t n);

/* Frees everything the session holds (a zeroed or half-opened session too). */
void tt__session_close(tt__session *s);

/* Creates a registry with the command line's --plugin-path folders. */
tt_registry *tt__make_registry(const tt__host_options *opt, const tt_host *host);

/* The plugin's tt.options/1 table (settings outside the tuned space), or NULL when it serves
 * none or an older table than the fields the host calls. */
const tt_options_iface *tt__plugin_options(const tt_loaded_plugin *p);

#endif
