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
  const char *sets[TT_HOST_MAX_LIST]; /* "plugin.param=value" */
  int set_count;
  const char *scene;
  const char *out;                        /* NULL: <scene folder>.exr in the current directory */
  const char *stats;                      /* NULL: no stats file */
  const char *describe[TT_HOST_MAX_LIST]; /* --describe NAME, in order */
  int describe_count;
  uint32_t spp;       /* 0: the scene's render.spp */
  double time_budget; /* seconds; 0: none */
  uint64_t seed;
  int seed_set;
  uint32_t threads;       /* 0: all CPUs */
  uint32_t width, height; /* 0: the scene's resolution */
  int list_plugins;
  int quiet;
  int png;    /* --png: a PNG preview of every sequence frame */
  int strict; /* --strict: pbrt input as strictly as pbrt-v4 reads it */
  /* tuning (tune.c) */
  const char *tune;        /* --tune PLUGIN; NULL: automatic when a tuner is loaded */
  const char *objective;   /* --objective SPEC; NULL: the target's natural objective */
  const char *tune_params; /* --tune-params A,B,...: search only these; NULL: the hint's or all */
  uint32_t iterations;     /* --iterations N; 0: TT_HOST_DEFAULT_ITERATIONS */
  uint32_t tune_spp;       /* --tune-spp N: spp per measurement; 0: 1 */
  uint32_t tune_window;    /* --tune-window N: frames per measurement along a sequence; 0: 8 */
  uint32_t explore;        /* --explore N: random configurations instead of a tuner */
  uint32_t verify;         /* --verify N: default vs best side by side, N rounds */
  const char *db;          /* --db PATH; NULL: tt_tunedb_default_path() */
  int no_db;               /* --no-db */
  int clock_cpu;           /* --clock cpu: every timing is the process's CPU time */
  const char *reference;   /* --reference FILE: the image --objective rrmse compares with */
  const char *tune_pass_images; /* --tune-pass-images DIR: each measurement's own pass image */
  int help;                     /* --help, -h, --help-all */
  const char *help_topic;       /* --help TOPIC; "all" for --help-all; NULL: the short help */
  int version;
  /* sequence rendering (sequence.c) */
  int sequence;                 /* --sequence given */
  uint32_t seq_first, seq_last; /* frames rendered, inclusive */
  const char *out_dir;          /* --out-dir DIR */
  double fps;                   /* --fps F; 0: 24 */
  uint32_t reference_scale;     /* --reference-scale K; 0: no reference */
  const char *post;             /* --post NAME: post-filter applied to each frame */
  const char *seq_pattern;      /* --out DIR/NAME_%04d.exr: frame file pattern (sequence) */
  int aov_set;                  /* --aov given */
  uint32_t aov_mask;            /* TT__AOV_* bits: EXR layers of a still, files of a sequence */
  int reference_only;           /* --supersample K: the frames are the reference */
  /* camera path samples (run.c): sample I of TT_HOST_PATH_SAMPLES at t = I/(N-1) of the
   * path's time range */
  int camera_index_set;       /* --camera-index given */
  uint32_t camera_index;      /* --camera-index I (or A of A:B), in [0, TT_HOST_PATH_SAMPLES) */
  uint32_t camera_index_last; /* B of --camera-index A:B (--hybrid, --predict); I otherwise */
  int camera_index_range;     /* --camera-index A:B given (a range: --hybrid and --predict) */
  const char *frames_arg;     /* --frames text (checked once --out is known) */
  int frames;                 /* --frames A:B without an --out pattern: frames A..B (at --fps,
                             * both included), each a full render to <out stem>_NNNN.exr */
  uint32_t frames_first, frames_last;
  int camera_time_set; /* one frame of --frames: the camera at t = camera_time */
  double camera_time;
  int convert; /* --convert: write the loaded scene as scene.json to --out */
  /* the run itself, for the --stats benchmark record */
  int argc; /* the command line as given */
  char **argv;
  int64_t started_ns; /* wall-clock (Unix) time the options were read, in ns */
  int indicators;     /* --indicators: print the scene's indicators as JSON */
  /* hybrid tuning (hybrid.c) */
  int hybrid;       /* --hybrid: eps-greedy search/prediction over the camera path */
  int predict_only; /* --predict: print the model's predictions, render nothing */
  double epsilon;   /* --epsilon E in [0, 1] */
  int epsilon_set;
  const char *model; /* --model FILE: loaded if it exists, saved at the end */
  const char *warm_start[TT_HOST_MAX_LIST]; /* --warm-start DB ... */
  int warm_start_count;
  const char *states;         /* --states FILE.json: --predict for these states, not the path */
  const char *measure;        /* --measure FILE.json: configurations measured side by side */
  uint32_t rounds;            /* --rounds R (--measure); 0: 3 */
  const char *resume;         /* --resume FILE: the tuning session's state, saved per sample */
  const char *indicator_norm; /* --indicator-norm SPEC (tt_indicator_norm_parse); NULL: default */
} tt__host_options;

/* Takes the program's name from argv[0] (its last path component; messages.c). */
void tt__set_prog(const char *argv0);
/* The name the program was run as: "tunetrace" installed, "host" in the build tree. */
const char *tt__prog(void);
/* Prints "NAME: " and the formatted text to stderr: how every message of the program
 * starts. */
void tt__say(const char *fmt, ...) TT_PRINTF(1, 2);

/* Creates `dir` and its missing parents (mkdir -p); 0, or -1 with errno (output_dir.c). */
int tt__ensure_dir(const char *dir);
/* Creates the folder of the output file `path` if missing, before a render; on failure
 * prints one message naming `option`, the path and the reason, and returns TT_EXIT_OUTPUT. */
int tt__ensure_parent_dir(const char *option, const char *path);
/* The still's default output <scene folder>.exr, or <file stem>.exr (output_dir.c). */
void tt__default_out(const char *scene, char *buf, size_t n);
/* Refuses, before any work, an output that would replace an input or another output,
 * naming both: TT_EXIT_USAGE after one message, else TT_EXIT_OK (io_check.c). */
int tt__check_outputs(const tt__host_options *opt);

/* Runs --convert: loads the scene and writes it as scene.json v1 + PLY meshes (convert.c). */
int tt__run_convert(const tt__host_options *opt);
/* Runs --indicators: prints raw and normalised indicators as JSON (indicators.c). */
int tt__run_indicators(const tt__host_options *opt);
/* SIGINT/SIGTERM finish the current `unit` ("pass", "frame", ...: named in the message;
 * tt_host.should_stop); a second one exits (signals.c). */
void tt__install_signals(const char *unit);
/* Brackets the writing of the final outputs: a second signal meanwhile waits for the writes,
 * and tt__outputs_end then exits 130 (signals.c). */
void tt__outputs_begin(void);
void tt__outputs_end(void);
/* Runs --hybrid / --predict over the scene's camera path (hybrid.c). */
int tt__run_hybrid(const tt__host_options *opt);
/* Runs --measure: configurations of the accel side by side (measure.c). */
int tt__run_measure(const tt__host_options *opt);

#define TT_HOST_DEFAULT_EPSILON 0.1
#define TT_HOST_DEFAULT_HYBRID_ITERATIONS 40

#define TT_HOST_PATH_SAMPLES 100

/* AOVs (--aov): the film's TT_AOV_* bits. A still writes them as layers of its EXR, a
 * sequence as one file per frame and AOV. */
#define TT__AOV_DEPTH ((uint32_t)TT_AOV_DEPTH)
#define TT__AOV_NORMAL ((uint32_t)TT_AOV_NORMAL)
#define TT__AOV_ALBEDO ((uint32_t)TT_AOV_ALBEDO)
#define TT__AOV_MOTION ((uint32_t)TT_AOV_MOTION)
/* Not a film AOV: the depth of each pixel's point in the previous camera, computed by the
 * host for sequences (--aov prevdepth, tt_post_frame.prev_depth). */
#define TT__AOV_PREVDEPTH (1u << 16)

#define TT_HOST_DEFAULT_ITERATIONS 50

/* Parses an --objective spec (tt_objective_parse); on error prints a message naming `opt`
 * and returns -1. */
int tt__parse_objective(const char *opt, const char *text, tt_objective *out);

/* Parses argv; on error prints a message naming the option and returns TT_EXIT_USAGE. */
int tt__parse_options(int argc, char **argv, tt__host_options *opt);
/* Prints --help: the options by task (topic NULL), one topic's ("tune"), or all ("all"). */
void tt__print_help(FILE *out, const char *topic);

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

/* Runs --list-plugins, --describe or a render. */
int tt__run_list_plugins(const tt__host_options *opt);
int tt__run_describe(const tt__host_options *opt);
int tt__run_render(const tt__host_options *opt);

/* Everything the run record holds. */
typedef struct tt__run_record {
  const tt__host_options *opt;
  tt_registry *reg;
  const tt_scene *scene;
  const tt_config *configs[TT_HOST_MAX_LIST]; /* per loaded plugin, may be NULL */
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
  tt_pass_stats last_pass; /* integrator metrics of the last pass */
  double metric_sums[TT_MAX_METRICS];
  const char *out_exr;
  const char *out_png;
  const struct tt__tuning *tuning; /* NULL when nothing was tuned or explored */
} tt__run_record;

/* What the tuning phase (tune.c) leaves for the log and --stats: the library's session
 * with its samples, best configuration and counters, and what the host added around it. */
typedef struct tt__tuning {
  tt_tuning *session; /* NULL when the phase failed before the session existed */
  const char *mode;   /* "tune" or "explore" */
  const char *plugin, *plugin_version, *tuner;
  uint32_t requested;
  int interrupted;
  double ms;             /* wall time of the tuning phase */
  char db_path[4096];    /* "" with --no-db */
  char *verify_json;     /* --verify result (JSON object, malloc), or NULL */
  tt_tunedb *db;         /* the database the session records into, or NULL */
  double *ref_lum;       /* --reference as luminance (--objective rrmse), or NULL */
  uint32_t answered_spp; /* samples per pixel the database's answers did not render
                                   (answers x --tune-spp): the render phase renders them, so
                                   that the image is never worse than without a database */
} tt__tuning;

/* Frees the tuning record (NULL is ignored). */
void tt__tuning_free(tt__tuning *t);

/* Writes the --stats JSON file. */
tt_status tt__write_stats(const char *path, const tt__run_record *rec);

/* Reads the JSON file `path` (`what` names it in errors: "states file"): 0 with `*root` the
 * parsed document (NULL when the text is not JSON), or -1 after printing "NAME: OPTION
 * <why>" when the file cannot be read (json_io.c). */
struct cJSON;
int tt__json_read(const char *option, const char *path, const char *what, struct cJSON **root);
/* Prints `root` on stdout and deletes it; TT_EXIT_OK, or TT_EXIT_OUTPUT when stdout fails. */
int tt__json_print(struct cJSON *root);
/* Parses JSON the library wrote (a configuration) so that cJSON prints every number back as
 * the same double (NULL when text is NULL or unparsable): configurations one ulp apart stay
 * apart in what the host prints, as in the library and its database (json_io.c). */
struct cJSON *tt__json_parse_exact(const char *text);
/* Makes every number under `node` print back as the same double (json_io.c). */
void tt__json_exact(struct cJSON *node);

/* Adds "scene_id" and "scene_id_parts" (geometry, materials, textures, lights) to a JSON
 * record, so a changed scene id can be explained. */
void tt__add_scene_ids(struct cJSON *root, const tt_scene *scene);

#endif
