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
  int help;
  int version;
} tt__host_options;

/* Parses argv; on error prints a message naming the option and returns TT_EXIT_USAGE. */
int tt__parse_options(int argc, char **argv, tt__host_options *opt);
/* Prints --help. */
void tt__print_usage(FILE *out);

/* The host services table the program passes to plugins: the default host with a
 * progress-bar-aware log and a progress bar on stderr. */
const tt_host *tt__host_services(int quiet);
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
} tt__run_record;

/* Writes the --stats JSON file. */
tt_status tt__write_stats(const char *path, const tt__run_record *rec);

#endif
