/* tunetrace-mpi: the job list (a JSON file) and what one job runs. Independent of MPI: the
 * list is read, checked and expanded by rank 0 before any rank starts work, every item
 * named in errors (jobs[2].scene, jobs[0].frames). */
#ifndef TT_MPI_JOBS_H
#define TT_MPI_JOBS_H

#include <stddef.h>
#include <stdint.h>

/* The most jobs one list expands to (all items together): a list past it is refused before
 * it is expanded, naming the file and the item. 100000 jobs hold a sequence of 100000 frames
 * in chunks of 1; tunetrace-mpi --list of such a list peaks at 170 MB and 0.8 s of CPU. */
#define TT_MPI_MAX_JOBS 100000

typedef enum tt_mpi_kind {
  TT_MPI_TUNE = 0,    /* one tuning search: host --camera-index I --objective O ... --db */
  TT_MPI_EXPLORE = 1, /* host --explore N --seed S at one camera (random configurations) */
  TT_MPI_FRAMES = 2   /* frames A..B of a sequence: host --sequence A:B into out_dir */
} tt_mpi_kind;

/* One job: the unit a rank runs, merges and is skipped by a rerun (its tag). */
typedef struct tt_mpi_job {
  tt_mpi_kind kind;
  char *tag;        /* unique id: kind:scene:camera:objective|seed|range:hash of the args */
  char *scene;      /* scene file as given */
  int camera;       /* --camera-index, -1: none */
  char *objective;  /* tune/explore: --objective (NULL: host's default) */
  uint32_t samples; /* explore: --explore N */
  uint64_t seed;    /* explore: --seed; 0 with has_seed 0: host's */
  int has_seed;
  uint32_t first, last; /* frames: the range (inclusive) */
  char *out_dir;        /* frames: the sequence's folder (one for the whole sequence) */
  char *sequence;       /* frames: tag of the whole sequence (the manifest is per sequence) */
  char **args;          /* extra host arguments (the list's "host_args", then the job's) */
  size_t nargs;
  size_t item; /* index of the item of "jobs" it came from (messages) */
} tt_mpi_job;

typedef struct tt_mpi_jobs {
  tt_mpi_job *jobs;
  size_t count;
  char *source; /* the file's path (messages) */
} tt_mpi_jobs;

/* Parses the job list `text` (from `source`), checks every item (scene files exist, ranges
 * not empty, cameras 0..99, known keys, every number in its range before it is converted)
 * and expands it: "cameras" lists, "objectives" lists and frame ranges cut into "chunk"
 * frames, in time linear in the number of jobs, at most TT_MPI_MAX_JOBS. 0, or -1 with the
 * message in `err`. */
int tt_mpi_jobs_parse(const char *text, const char *source, tt_mpi_jobs *out, char *err, size_t n);

/* Frees what tt_mpi_jobs_parse allocated. */
void tt_mpi_jobs_free(tt_mpi_jobs *jobs);

/* The host argv of `job` (NULL-terminated, malloc'ed strings, free with tt_mpi_argv_free):
 * `host` first; `db` and `stats` are its tuning DB and --stats files (tune/explore), `dir`
 * the folder frames are rendered into (frames). */
char **tt_mpi_job_argv(const tt_mpi_job *job, const char *host, const char *db, const char *stats,
                       const char *dir);
void tt_mpi_argv_free(char **argv);

/* The job as a JSON object (kind, scene, camera, objective, samples, seed, frames, args):
 * the note the merged DB keeps with its tag. malloc'ed. */
char *tt_mpi_job_json(const tt_mpi_job *job);

#endif /* TT_MPI_JOBS_H */
