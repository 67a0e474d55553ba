/* host: the command-line options, one table. The parser, --help, the "did you mean"
 * suggestions and tunetrace-mpi's list of the options its driver sets are all made from it. */
#ifndef TT_HOST_OPTION_TABLE_H
#define TT_HOST_OPTION_TABLE_H

#include <tunetrace/limits.h>

#include <stddef.h>
#include <stdint.h>

struct tt__host_options;
struct tt__option;

/* What follows an option on the command line. */
typedef enum tt__arg_kind {
  TT__ARG_NONE = 0, /* a flag: --quiet ("--quiet=x" is refused) */
  TT__ARG_ONE = 1,  /* one value: "--spp 64" or "--spp=64" */
  TT__ARG_TOPIC = 2 /* an optional --help topic: "--help tune", "--help=tune" or none */
} tt__arg_kind;

/* The sections of --help-all, in its order; "--help TOPIC" prints one. */
typedef enum tt__topic {
  TT__TOPIC_RENDER,
  TT__TOPIC_PLUGINS,
  TT__TOPIC_OUTPUT,
  TT__TOPIC_TUNE,
  TT__TOPIC_HYBRID,
  TT__TOPIC_SEQUENCE,
  TT__TOPIC_CAMERA,
  TT__TOPIC_TOOLS,
  TT__TOPIC_COUNT
} tt__topic;

/* The sections of the short --help, one per task (an option may be in several). */
enum {
  TT__TASK_RENDER = 1,
  TT__TASK_TUNE = 2,
  TT__TASK_HYBRID = 4,
  TT__TASK_SEQUENCE = 8,
  TT__TASK_MORE = 16 /* the short help's last lines: --help itself, --version */
};

/* tunetrace-mpi jobs whose driver sets an option itself (a job's args may not). */
enum {
  TT__MPI_TUNE = 1,
  TT__MPI_EXPLORE = 2,
  TT__MPI_FRAMES = 4,
  TT__MPI_ALL = TT__MPI_TUNE | TT__MPI_EXPLORE | TT__MPI_FRAMES
};

/* Stores `value` (NULL for a flag) of option `o` in `opt`; on a bad value prints one message
 * naming the option and what was expected, and returns -1. */
typedef int (*tt__option_set)(const struct tt__option *o, const char *value,
                              struct tt__host_options *opt);

typedef struct tt__option {
  const char *name;  /* "--spp" */
  const char *alias; /* the short form ("-o"), or NULL */
  tt__arg_kind arg;
  const char *value; /* the value's placeholder in --help ("N", "FILE.exr") */
  tt__option_set set;
  size_t field;   /* offsetof the tt__host_options member the generic setters write */
  tt_limit limit; /* the range of a number (tunetrace/limits.h) */
  tt__topic topic;
  unsigned tasks;   /* TT__TASK_*: the short --help's sections that list it */
  unsigned mpi;     /* TT__MPI_* */
  const char *help; /* lines of --help, '\n'-separated; the first one stands alone (the
                          * short --help shows only it) */
} tt__option;

/* The table, `*count` rows. */
const tt__option *tt__options(size_t *count);
/* The row of option `name` ("--spp" or its alias "-o"), or NULL. */
const tt__option *tt__option_find(const char *name);
/* The row of command-line argument `arg`, with "--NAME=VALUE" looked up by NAME; `*value`
 * is then VALUE (else NULL). NULL when `arg` is not an option of the table. */
const tt__option *tt__option_of_arg(const char *arg, const char **value);
/* The topic named `name` ("tune"), or -1. */
int tt__topic_find(const char *name);
/* The name of a topic ("tune"). */
const char *tt__topic_name(tt__topic topic);
/* The topic names, ", "-separated, and the closest to a mistyped `name` (or NULL). */
const char *tt__topic_list(void);
const char *tt__topic_suggest(const char *name);
/* The title of a --help section ("Tuning; thesis Fig. 3.2, ...": what follows ';' says where
 * to read more). */
const char *tt__topic_title(tt__topic topic);
/* Text printed under a section's title before its options ("" when none). */
const char *tt__topic_intro(tt__topic topic);
/* The closest option name to a mistyped `name` (edit distance, or another renderer's
 * spelling of it), or NULL. */
const char *tt__option_suggest(const char *name);

#endif
