/* host: the tuning phase (tune.c): maps the command line's tuning options onto a library
 * tuning session (tunetrace/tuning.h) over the host session, and logs what it found. */
#ifndef TT_HOST_TUNE_H
#define TT_HOST_TUNE_H

#include "session.h"

/* Runs the tuning (or exploration) phase when the options ask for one; its passes render
 * into the session's film, and it leaves the best configuration applied to the target.
 * Returns TT_EXIT_OK, TT_EXIT_USAGE (bad target or objective), TT_EXIT_OUTPUT (measurements
 * the database could not record) or TT_EXIT_FAILURE; `*out` is NULL when no tuning was
 * requested (free it with tt__tuning_free). */
int tt__tune_phase(tt__session *s, tt__tuning **out);

/* Checks the tuning options against what is loaded: a tuning option without a tuner or
 * --explore N, or --explore with --iterations, is a usage error (printed). */
int tt__tune_check(const tt__host_options *opt, const tt_loaded_plugin *tuner_p);

/* Opens the tuning database (--db, the default path, or none with --no-db: *db NULL);
 * prints what failed and returns an exit code. */
int tt__tune_open_db(const tt__host_options *opt, const tt_host *host, tt_tunedb **db);

#endif
