/* tunetrace: the tuning database (thesis 3.3) — every measured (state, configuration) pair.
 *
 * One SQLite file in WAL mode, so readers (analysis tools, predictors) never block the
 * tuning loop and a killed process leaves every committed row readable. Each call to
 * tt_tunedb_record is its own transaction: a finished measurement is durable at once.
 * The schema is versioned with PRAGMA user_version (TT_TUNEDB_SCHEMA_VERSION); a file
 * written by a newer schema is refused with a message naming both versions.
 *
 * A row holds the state (scene id, camera, measurement context, scene indicators), the
 * plugin (name + version) and its configuration (canonical compact JSON from
 * tt_config_to_json), the objective, the measured build/render times and cost, and where
 * and when it was measured (machine id, CPU model, UTC timestamp). The lookup key of
 * "the same measurement" is (scene_id, camera, context, plugin, plugin_version, config,
 * objective, machine, cpu): the tuning loop never measures a key the database already has.
 *
 * Default location: $XDG_DATA_HOME/tunetrace/tuning.db, else
 * ~/.local/share/tunetrace/tuning.db (tt_tunedb_default_path).
 *
 * Every row also names the host and, for a row of an MPI run (tunetrace-mpi), the rank that
 * measured it. Databases merge idempotently by tag (tt_tunedb_merge): how the rows of many
 * processes or machines end in one file without loss or duplicates.
 *
 * Threads: a tt_tunedb handle is used by one thread at a time; several processes may share
 * one file (SQLite locking, 60 s busy timeout).
 */
#ifndef TUNETRACE_TUNEDB_H
#define TUNETRACE_TUNEDB_H

#include <tunetrace/common.h>
#include <tunetrace/scene.h>
#include <tunetrace/tuning_hint.h> /* tt.tuning_hint/1 used to be declared here */

#ifdef __cplusplus
extern "C" {
#endif

/* Schema version stored in PRAGMA user_version. 2 added the columns host and rank and the
 * table merges (a file of version 1 is upgraded when opened, its rows kept). */
#define TT_TUNEDB_SCHEMA_VERSION 2

typedef struct tt_tunedb tt_tunedb; /* opaque database handle */

/* Outcome of one measurement. Only OK and INFEASIBLE rows answer lookups: a failure may be
 * transient (out of memory, a driver hiccup) and is measured again next time. */
typedef enum tt_tunedb_status {
  TT_TUNEDB_OK = 0,         /* measured; cost is finite */
  TT_TUNEDB_INFEASIBLE = 1, /* rejected by the space's constraints; cost TT_COST_INFEASIBLE */
  TT_TUNEDB_FAILED = 2      /* build or render failed; cost TT_COST_INFEASIBLE */
} tt_tunedb_status;

/* One row. Strings are borrowed: on record they are copied, in tt_tunedb_foreach they are
 * valid during the callback only. NULL strings are stored as NULL, except where noted. */
typedef struct tt_tunedb_row {
  uint32_t struct_size;   /* sizeof(tt_tunedb_row) */
  int64_t id;             /* rowid; written by tt_tunedb_record */
  const char *scene_id;   /* tt_scene_id (required) */
  const char *scene;      /* scene file, for people */
  const char *camera;     /* JSON of the view: position, target, up, fov_y, resolution */
  const char *context;    /* JSON of what else shapes the cost: spp per measurement,
                                threads, the other plugins and their configurations */
  int32_t has_indicators; /* non-zero: indicators[] is set */
  double indicators[TT_SCENE_INDICATOR_COUNT]; /* tt_scene_indicators, Table 3.2 */
  const char *plugin;                          /* tuned plugin's name (required) */
  const char *plugin_version;                  /* its version (required) */
  const char *config;                          /* canonical configuration JSON (required) */
  const char *objective; /* objective spec, e.g. "render", "build+render" (required) */
  double build_ms;       /* build time of this measurement (0 if nothing was built) */
  double render_ms;      /* render time of this measurement */
  double cost;           /* the objective's value; TT_COST_INFEASIBLE if not OK */
  int32_t status;        /* tt_tunedb_status */
  const char *mode;      /* "default", "tune", "explore" */
  int32_t iteration;     /* -1 for the default configuration, else 0, 1, ... */
  const char *run_id;    /* identifies one host run */
  const char *tuner;     /* tuner plugin name, NULL for exploration */
  const char *metrics;   /* JSON object of the integrator's pass metrics, or NULL */
  const char *machine;   /* NULL on record: tt_tunedb_machine_id() */
  const char *cpu;       /* NULL on record: tt_tunedb_cpu_model() */
  const char *timestamp; /* ISO 8601 UTC; NULL on record: now */
  /* ---- appended in schema 2; read on record only when struct_size covers them ---- */
  const char *host; /* host name of the machine that measured; NULL on record: this
                                one's (gethostname) */
  int32_t has_rank; /* non-zero: rank is set (a row of an MPI run, tunetrace-mpi) */
  int32_t rank;     /* MPI rank that measured; stored as NULL when has_rank is 0 */
} tt_tunedb_row;

/* Default database path (see above). Free with tt_free; NULL if neither $XDG_DATA_HOME
 * nor $HOME is set. */
TT_API char *tt_tunedb_default_path(void);

/* Opens for reading and writing (creating the file, its parent directory and the schema if
 * needed) the database at `path`. Before anything is written the file is checked: a FIFO,
 * a device or a folder, another program's SQLite file (schema version 0 with tables of its
 * own), a schema version this build does not read (newer, or negative) and a damaged file
 * (PRAGMA quick_check) are refused, naming the file and what it holds, and left as they
 * are. A file of an older schema is upgraded. `*out` is owned by the caller: free with
 * tt_tunedb_close. To read a database, use tt_tunedb_open_readonly. */
TT_API tt_status tt_tunedb_open(const char *path, tt_tunedb **out);
/* Closes the database (NULL is ignored). */
TT_API void tt_tunedb_close(tt_tunedb *db);
/* Path the database was opened with. */
TT_API const char *tt_tunedb_path(const tt_tunedb *db);

/* Inserts `row` and commits it; sets row->id. Required fields missing or a non-finite
 * cost are TT_ERR_INVALID_ARGUMENT. */
TT_API tt_status tt_tunedb_record(tt_tunedb *db, tt_tunedb_row *row);

/* Looks up the key fields of `key` (scene_id, camera, context, plugin, plugin_version,
 * config, objective, machine, cpu; NULL machine/cpu mean this machine). On a hit writes
 * the mean cost of the matching OK/INFEASIBLE rows into `*cost` and their number into
 * `*count` (either may be NULL) and returns TT_OK; TT_ERR_NO_DATA if there is none. */
TT_API tt_status tt_tunedb_lookup(tt_tunedb *db, const tt_tunedb_row *key, double *cost,
                                  uint32_t *count);

/* Calls fn for every row (of `plugin`, or all if NULL) in insertion order; a non-zero
 * return from fn stops the walk. A row that is not one of the schema (text where a number
 * belongs, a non-finite cost, an unknown status, indicators that are not a JSON object of
 * numbers) is skipped and counted: one warning through the library's log per walk names the
 * number and the first such row (tt_tunedb_bad_rows). */
TT_API tt_status tt_tunedb_foreach(tt_tunedb *db, const char *plugin,
                                   int (*fn)(void *user, const tt_tunedb_row *row), void *user);

/* Number of rows (of `plugin`, or all if NULL). */
TT_API tt_status tt_tunedb_count(tt_tunedb *db, const char *plugin, uint64_t *count);

/* Writes every row as CSV (RFC 4180 quoting, header line; the indicators as one column
 * each, named after tt_scene_indicator_name, empty when unknown). */
TT_API tt_status tt_tunedb_export_csv(tt_tunedb *db, const char *path);

/* This machine: /etc/machine-id (else the host name), and the CPU model from
 * /proc/cpuinfo ("unknown" if absent). Static strings. */
TT_API const char *tt_tunedb_machine_id(void);
TT_API const char *tt_tunedb_cpu_model(void);

/* ---- appended for distributed runs (tunetrace-mpi, issue 18) ---- */

/* This machine's host name (gethostname; "unknown" if none). Static string. */
TT_API const char *tt_tunedb_host_name(void);

/* Merges the rows of the tuning database file `source` into `db`, once per `tag`. In one
 * transaction: if `tag` is not in db's table `merges` yet, every row of `source` is copied
 * (new ids; the rank column set to `rank` where `rank >= 0`, else kept) and the tag is
 * recorded with the number of rows, `source` and `note` (free text, e.g. a job's JSON; may be
 * NULL). A tag merged before copies nothing and sets *already = 1, so merging a source twice,
 * or redoing a job whose rows already arrived, never duplicates a row; a crash leaves either
 * all of a tag's rows or none. `source` NULL records the tag alone (work without rows).
 * `source` may be of schema 1 (its rows get NULL host and rank). rows/already may be NULL. */
TT_API tt_status tt_tunedb_merge(tt_tunedb *db, const char *source, const char *tag, int32_t rank,
                                 const char *note, uint64_t *rows, int *already);

/* *merged = 1 if `tag` was merged into `db` (tt_tunedb_merge), else 0. */
TT_API tt_status tt_tunedb_merged(tt_tunedb *db, const char *tag, int *merged);

/* ---- appended: reading a database without writing to it ---- */

/* Opens the existing database at `path` read-only (SQLITE_OPEN_READONLY): nothing in the
 * file changes, not its journal mode, not its schema, so another program's file, a
 * read-only file or a baseline kept for comparison can be read. Refused, naming the file:
 * a missing or non-regular file, a file without tunetrace's schema (another program's
 * SQLite file, an empty one), a newer or negative schema version, a damaged file (PRAGMA
 * quick_check). A file of schema 1 is read as it is (host and rank NULL). The handle reads
 * (foreach, count, lookup, export); tt_tunedb_record and tt_tunedb_merge refuse it. */
TT_API tt_status tt_tunedb_open_readonly(const char *path, tt_tunedb **out);

/* Non-zero if `db` was opened with tt_tunedb_open_readonly. */
TT_API int tt_tunedb_read_only(const tt_tunedb *db);

/* Rows the last tt_tunedb_foreach (or tt_tunedb_export_csv) on `db` skipped because they
 * were not rows of the schema. */
TT_API uint64_t tt_tunedb_bad_rows(const tt_tunedb *db);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_TUNEDB_H */
