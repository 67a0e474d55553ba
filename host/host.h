/* host: the tunetrace command-line program. Internal declarations shared by its files. */
#ifndef TT_HOST_HOST_H
#define TT_HOST_HOST_H

#include <tunetrace/tunetrace.h>

#include <stdio.h>

/* Exit codes (documented in README.md and --help). */
enum {
  TT_EXIT_OK = 0,
  TT_EXIT_FAILURE = 1,      /* rendering or another runtime step failed */
  TT_EXIT_USAGE = 2,        /* bad command line */
  TT_EXIT_PLUGIN = 3,       /* one or more plugins could not be loaded */
  TT_EXIT_SCENE = 4,        /* the scene could not be loaded */
  TT_EXIT_OUTPUT = 5,       /* an output file could not be written */
  TT_EXIT_INTERRUPTED = 130 /* SIGINT/SIGTERM: partial results were written */
};

#define TT_HOST_MAX_LIST 64

typedef struct tt__host_options {
  const char *plugins[TT_HOST_MAX_LIST];
  int plugin_count;
  const char *plugin_paths[TT_HOST_MAX_LIST];
  int plugin_path_count;
  const char *sets[TT_HOST_MAX_LIST];     /* "plugin.param=value" */
  int set_count;
  const char *scene;
  const char *out;          /* NULL: <scene folder>.exr in the current directory */
  const char *stats;        /* NULL: no stats file */
  const char *describe;     /* --describe NAME */
  uint32_t spp;             /* 0: the scene's render.spp */
  double time_budget;       /* seconds; 0: none */
  uint64_t seed;
  int seed_set;
  uint32_t threads;         /* 0: all CPUs */
  uint32_t width, height;   /* 0: the scene's resolution */
  int list_plugins;
  int quiet;
  /* tuning (tune.c) */
  const char *tune;         /* --tune PLUGIN; NULL: automatic when a tuner is loaded */
  const char *objective;    /* --objective SPEC; NULL: the target's natural objective */
  const char *tune_params;  /* --tune-params A,B,...: search only these; NULL: the hint's or all */
  uint32_t iterations;      /* --iterations N; 0: TT_HOST_DEFAULT_ITERATIONS */
  uint32_t tune_spp;        /* --tune-spp N: spp per measurement; 0: 1 */
  uint32_t explore;         /* --explore N: random configurations instead of a tuner */
  uint32_t verify;          /* --verify N: default vs best side by side, N rounds */
  const char *db;           /* --db PATH; NULL: tt_tunedb_default_path() */
  int no_db;                /* --no-db */
  int clock_cpu;            /* --clock cpu: every timing is the process's CPU time */
  const char *reference;    /* --reference FILE: the image --objective rrmse compares with */
  const char *tune_pass_images; /* --tune-pass-images DIR: each measurement's own pass image */
  int help;
  int version;
  /* sequence rendering (sequence.c) */
  int sequence;             /* --sequence given */
  uint32_t seq_first, seq_last;  /* frames rendered, inclusive */
  const char *out_dir;      /* --out-dir DIR */
  double fps;               /* --fps F; 0: 24 */
  uint32_t reference_scale; /* --reference-scale K; 0: no reference */
  const char *post;         /* --post NAME: post-filter applied to each frame */
  const char *seq_pattern;  /* --out DIR/NAME_%04d.exr: frame file pattern (sequence) */
  int aov_set;              /* --aov given */
  uint32_t aov_mask;        /* TT__SEQ_AOV_* bits written per frame */
  int reference_only;       /* --supersample K: the frames are the reference */
  /* camera path samples (run.c): sample I of TT_HOST_PATH_SAMPLES at t = I/(N-1) of the
   * path's time range */
  int camera_index_set;     /* --camera-index given */
  uint32_t camera_index;    /* --camera-index I, in [0, TT_HOST_PATH_SAMPLES) */
  const char *frames_arg;   /* --frames text (meaning depends on --out, checked at the end) */
  int frames;               /* --frames A:B given: samples A..B-1 to <out stem>_NNNN.exr */
  uint32_t frames_first, frames_end;
  int convert;              /* --convert: write the loaded scene as scene.json to --out */
} tt__host_options;

/* Runs --convert: loads the scene and writes it as scene.json v1 + PLY meshes (convert.c). */
int tt__run_convert(const tt__host_options *opt);

#define TT_HOST_PATH_SAMPLES 100

/* Per-frame AOVs of a sequence (--aov). */
#define TT__SEQ_AOV_DEPTH 1u
#define TT__SEQ_AOV_MOTION 2u

#define TT_HOST_DEFAULT_ITERATIONS 50

/* What a tuning measurement minimises (--objective). */
typedef enum tt__objective_kind {
  TT_OBJ_RENDER = 1,        /* wall ms of the measurement pass(es) */
  TT_OBJ_BUILD = 2,         /* accel build ms */
  TT_OBJ_TOTAL = 3,         /* build + render ms */
  TT_OBJ_METRIC = 4,        /* an integrator metric of the pass */
  TT_OBJ_RRMSE = 5          /* rRMSE of the pass's own image against --reference */
} tt__objective_kind;

typedef enum tt__metric_goal {
  TT_GOAL_MIN = 0,          /* cost = value */
  TT_GOAL_MAX = 1,          /* cost = -value */
  TT_GOAL_TARGET = 2        /* cost = |value - target| */
} tt__metric_goal;

typedef struct tt__objective {
  tt__objective_kind kind;
  char metric[64];
  tt__metric_goal goal;
  double target;
  char spec[192];           /* canonical spec, the database's objective column */
} tt__objective;

/* Parses an --objective spec; on error prints a message naming `opt` and returns -1. */
int tt__parse_objective(const char *opt, const char *text, tt__objective *out);

/* Parses argv; on error prints a message naming the option and returns TT_EXIT_USAGE. */
int tt__parse_options(int argc, char **argv, tt__host_options *opt);
/* Prints --help. */
void tt__print_usage(FILE *out);

/* The host services table the program passes to plugins: the default host with a
 * progress-bar-aware log and a progress bar on stderr. */
const tt_host *tt__host_services(int quiet);
/* Makes the services' clock_ns the process's CPU time (--clock cpu): every build and render
 * time that plugins and the tuning loop measure then excludes the time other processes ran
 * on our cores. */
void tt__host_use_cpu_clock(void);
/* Draws progress of the render: fraction in [0,1], with elapsed time and ETA. */
void tt__progress_update(const char *task, double fraction);
/* Ends the current progress line (newline on a TTY). */
void tt__progress_finish(void);

/* Creates a registry with the command line's --plugin-path folders. */
tt_registry *tt__make_registry(const tt__host_options *opt, const tt_host *host);
/* Loads every --plugin and --post, reporting each failure, then the default accel and
 * integrator for kinds not named. Returns the number of failures. */
int tt__load_plugins(tt_registry *reg, const tt__host_options *opt);
/* The plugin's tt.options/1 table (settings outside the tuned space), or NULL when it serves
 * none or an older table than the fields the host calls. */
const tt_options_iface *tt__plugin_options(const tt_loaded_plugin *p);

/* Builds one configuration per loaded plugin (registry order) from its defaults, the
 * scene's render settings (integrator maxDepth) and the --set options; reports every bad
 * --set and returns the number of errors. */
int tt__build_configs(tt_registry *reg, const tt__host_options *opt, const tt_scene *scene,
                      tt_config **configs);

/* Runs --list-plugins, --describe or a render. */
int tt__run_list_plugins(const tt__host_options *opt);
int tt__run_describe(const tt__host_options *opt);
int tt__run_render(const tt__host_options *opt);

/* Everything the run record holds. */
typedef struct tt__run_record {
  const tt__host_options *opt;
  tt_registry *reg;
  const tt_scene *scene;
  const tt_config *configs[TT_HOST_MAX_LIST];   /* per loaded plugin, may be NULL */
  double build_ms;
  double render_ms;
  uint32_t passes;
  uint32_t spp;
  uint64_t rays;
  uint64_t samples;
  uint64_t nonfinite;
  uint64_t seed;
  uint32_t threads;
  uint32_t width, height;
  int interrupted;
  tt_accel_build_stats build;
  tt_pass_stats last_pass;     /* integrator metrics of the last pass */
  double metric_sums[TT_MAX_METRICS];
  const char *out_exr;
  const char *out_png;
  const struct tt__tuning *tuning;  /* NULL when nothing was tuned or explored */
} tt__run_record;

/* The render state the passes and the tuning loop share (run.c). */
typedef struct tt__render_state {
  const tt__host_options *opt;
  const tt_host *host;
  tt__run_record *rec;
  tt_scene *scene;
  const tt_camera *camera;
  tt_registry *reg;
  tt_config **configs;          /* per loaded plugin, registry order */
  tt_loaded_plugin *accel_p, *integ_p;
  const tt_accel_iface *ai;
  const tt_integrator_iface *ii;
  tt_accel *accel;
  tt_integrator *integrator;
  tt_film *film;
  uint32_t pass;                /* passes rendered into the film */
} tt__render_state;

/* Renders one pass of `spp` samples per pixel into the film and accounts it in the run
 * record; `ps` receives the pass statistics and `*ms` its wall time. */
tt_status tt__render_pass(tt__render_state *rs, uint32_t spp, tt_pass_stats *ps, double *ms);

/* One measurement of the tuning loop. */
typedef struct tt__tune_sample {
  int iteration;                /* -1: the default configuration */
  char *config;                 /* canonical JSON (malloc) */
  double cost, build_ms, render_ms;
  int status;                   /* tt_tunedb_status */
  int cached;                   /* cost came from the database */
} tt__tune_sample;

/* Everything the tuning phase did, for the log and --stats. */
typedef struct tt__tuning {
  const char *mode;             /* "tune" or "explore" */
  const char *plugin, *plugin_version, *tuner;
  tt__objective objective;
  uint32_t requested;
  tt__tune_sample *samples;     /* [0] is the default configuration */
  size_t count, cap;
  uint32_t measured, cached, infeasible, failed;
  int converged, interrupted;
  double default_cost;
  char *default_config;
  double best_cost;
  char *best_config;
  const char *best_from;        /* "default", or the mode that found it */
  double ms;                    /* wall time of the tuning phase */
  const char *db_path;          /* NULL with --no-db */
  char *verify_json;            /* --verify result (JSON object, malloc), or NULL */
} tt__tuning;

/* Runs the tuning (or exploration) phase when the options ask for one; leaves the best
 * configuration applied to the target. Returns TT_EXIT_OK, TT_EXIT_USAGE (bad target or
 * objective) or TT_EXIT_FAILURE; `*out` is NULL when no tuning was requested. */
int tt__tune_phase(tt__render_state *rs, tt__tuning **out);
/* Frees the tuning record. */
void tt__tuning_free(tt__tuning *t);

/* Writes the --stats JSON file. */
tt_status tt__write_stats(const char *path, const tt__run_record *rec);

#endif
