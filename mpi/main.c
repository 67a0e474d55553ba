/* tunetrace-mpi: runs a job list (tuning searches, explorations, frame ranges of sequences)
 * across MPI ranks, every result in ONE tuning database and one folder per sequence.
 *
 *   mpirun -np 4 --bind-to core tunetrace-mpi --jobs jobs.json --db tuning.db
 *
 * Every rank runs jobs, one at a time, each as a host process (the program users run, with
 * the job's arguments); a rank that finishes asks rank 0 for the next job (dynamic
 * distribution in list order). A tuning or exploration job measures into a fresh database
 * file of its own in the rank's scratch folder (node-local); the rank sends the file to
 * rank 0, which alone writes the merged database: tt_tunedb_merge copies the job's rows and
 * records its tag in one transaction, so a job is in the database whole or not at all and
 * never twice. A rerun of the same command skips every tag already merged: a killed run
 * (a rank dying ends an Open MPI 4 run: mpirun tears every rank down) loses only the jobs in
 * flight. Why one writer and not per-rank files merged at the end: nothing is lost or left
 * half-merged when a run is killed, a rerun resumes from the one file, and one SQLite writer
 * sustains far more rows per second than the ranks produce (docs/mpi.md, bench mpi_scaling).
 * Jobs see no rows of other jobs (each starts from an empty database), so the results do not
 * depend on which rank ran what, or in which order.
 *
 * This file reads the command line and the job list (every rank checks it), then rank 0
 * coordinates (coordinator.c) and every other rank works (worker.c); a job is run by
 * job_run.c, the messages between them are protocol.h's. */
#include "child.h"
#include "coordinator.h"
#include "worker.h"

#include <tunetrace/file.h>
#include <tunetrace/tunetrace.h>

#include <mpi.h>

#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef TT_MPI_BUILD_DIR
#  define TT_MPI_BUILD_DIR ""
#endif
#ifndef TT_MPI_BUILD_HOST
#  define TT_MPI_BUILD_HOST ""
#endif
#define TT_MPI_INSTALLED_HOST "tunetrace"

/* The host program jobs run by default: in the build tree (this program runs from the build
 * tree's mpi/ folder) the build tree's host; installed, the `tunetrace` installed beside this
 * program (PREFIX/bin), found relative to itself so a --destdir staging copy or a moved
 * prefix runs its own. An installed copy never runs the tree it was built in. */
static const char *tt__default_host(void) {
  static char host[4200];
  char exe[4096], dir[4096];
  if (!realpath("/proc/self/exe", exe)) return TT_MPI_INSTALLED_HOST;
  char *slash = strrchr(exe, '/');
  if (!slash) return TT_MPI_INSTALLED_HOST;
  *slash = '\0';
  if (TT_MPI_BUILD_DIR[0] && realpath(TT_MPI_BUILD_DIR, dir) && !strcmp(exe, dir))
    return TT_MPI_BUILD_HOST;
  snprintf(host, sizeof host, "%s/%s", exe, TT_MPI_INSTALLED_HOST);
  return host;
}

static void tt__on_signal(int sig) {
  tt_mpi_stop = 1;
  tt_mpi_child_kill(tt_mpi_running_child, sig == SIGINT ? SIGINT : SIGTERM);
}

static int tt__usage(int rank, const char *msg) {
  if (rank == 0) {
    if (msg) fprintf(stderr, "tunetrace-mpi: %s\n", msg);
    fprintf(stderr,
            "usage: mpirun [--enable-recovery] -np N tunetrace-mpi --jobs FILE --db DB "
            "[--host PATH] [--scratch DIR] [--max-jobs N] [--liveness S] [--list | --check]\n"
            "  --jobs FILE   the job list (JSON; mpi/README.md)\n"
            "  --db DB       the merged tuning database (created; rank 0 writes it)\n"
            "  --host PATH   the host program the jobs run (default %s)\n"
            "  --scratch DIR node-local folder for the jobs' own databases (default $TMPDIR "
            "or /tmp)\n"
            "  --max-jobs N  hand out at most N new jobs, then stop (a rerun continues)\n"
            "  --liveness S  a rank silent for S seconds is taken as dead (default 60): its "
            "job is lost,\n"
            "                the others go on (needs mpirun --enable-recovery; else Open MPI "
            "ends the run)\n"
            "  --list        print every job as done or todo and exit\n"
            "  --check       print the jobs still todo; exit 0 when none is, 1 otherwise (the "
            "exit status\n"
            "                of mpirun --enable-recovery is 0 whatever the ranks return)\n",
            tt__default_host());
  }
  return EXIT_USAGE;
}

/* An option that takes a value (argv[*i + 1]): 1 when read, -1 with the message in msg when
 * it is missing or wrong, 0 when argv[*i] is no such option. */
static int tt__parse_value(tt_mpi_opts *o, int argc, char **argv, int *i, char *msg, size_t n) {
  const char *a = argv[*i];
  const char **val = !strcmp(a, "--jobs")      ? &o->jobs
                     : !strcmp(a, "--db")      ? &o->db
                     : !strcmp(a, "--host")    ? &o->host
                     : !strcmp(a, "--scratch") ? &o->scratch
                                               : NULL;
  if (!val && strcmp(a, "--max-jobs") && strcmp(a, "--liveness")) return 0;
  if (*i + 1 >= argc) {
    snprintf(msg, n, "%s needs a value", a);
    return -1;
  }
  const char *v = argv[++*i];
  char *end = NULL;
  if (val) {
    *val = v;
  } else if (!strcmp(a, "--liveness")) {
    o->liveness = strtod(v, &end);
    if (!*v || *end || !(o->liveness >= 1 && o->liveness <= 86400)) {
      snprintf(msg, n, "--liveness: expected seconds in 1..86400, got \"%s\"", v);
      return -1;
    }
  } else {
    o->max_jobs = strtol(v, &end, 10);
    if (!*v || *end || o->max_jobs < 1) {
      snprintf(msg, n, "--max-jobs: expected a count >= 1, got \"%s\"", v);
      return -1;
    }
  }
  return 1;
}

/* Reads the command line into `o`: -1 to go on, else the exit code (--help printed: 0; a
 * bad command line printed with the usage: EXIT_USAGE). */
static int tt__parse_args(int argc, char **argv, int rank, tt_mpi_opts *o) {
  *o = (tt_mpi_opts){NULL, NULL, tt__default_host(), NULL, 0, 0, 0, 60, 0};
  const char *tmp = getenv("TMPDIR");
  o->scratch = tmp && tmp[0] ? tmp : "/tmp";
  char msg[8192] = "";
  for (int i = 1; i < argc && !msg[0]; i++) {
    const char *a = argv[i];
    int v = tt__parse_value(o, argc, argv, &i, msg, sizeof msg);
    if (v != 0) continue;
    if (!strcmp(a, "--list")) {
      o->list = 1;
    } else if (!strcmp(a, "--check")) {
      o->check = 1;
    } else if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      tt__usage(rank, NULL);
      return EXIT_OK;
    } else {
      snprintf(msg, sizeof msg, "unknown argument \"%s\"", a);
    }
  }
  if (!msg[0] && (!o->jobs || !o->db))
    snprintf(msg, sizeof msg, "--jobs FILE and --db DB are required");
  if (!msg[0] && o->list && o->check)
    snprintf(msg, sizeof msg, "--list and --check: give one of them");
  o->heartbeat = o->liveness / 10 < 0.1 ? 0.1 : o->liveness / 10 > 5 ? 5 : o->liveness / 10;
  return msg[0] ? tt__usage(rank, msg) : -1;
}

/* Rank 0: the job list's text (malloc'ed by tt_file_read) and its length, or -1 after
 * printing why it cannot run (the file, or the --host program). */
static int64_t tt__job_text(const tt_mpi_opts *o, char **text) {
  size_t tn = 0;
  if (tt_file_read(o->jobs, "job list", 64u << 20, text, &tn) != TT_OK) {
    fprintf(stderr, "tunetrace-mpi: --jobs: %s\n", tt_last_error());
    return -1;
  }
  if (access(o->host, X_OK) != 0) {
    fprintf(stderr, "tunetrace-mpi: --host %s: not an executable (%s)\n", o->host, strerror(errno));
    return -1;
  }
  return (int64_t)tn;
}

/* Rank 0 reads the list and sends it; every rank checks it (its scenes exist there too), and
 * nobody starts work unless every rank accepted it. 0, or -1 (printed). */
static int tt__read_jobs(const tt_mpi_opts *o, int rank, tt_mpi_jobs *jobs) {
  char *text = NULL, msg[8192] = "";
  int64_t len = rank == 0 ? tt__job_text(o, &text) : -1;
  MPI_Bcast(&len, 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
  if (len < 0) {
    tt_free(text);
    return -1;
  }
  if (rank != 0) text = malloc((size_t)len + 1);
  MPI_Bcast(text, (int)len, MPI_CHAR, 0, MPI_COMM_WORLD);
  text[len] = 0;
  int parsed = tt_mpi_jobs_parse(text, o->jobs, jobs, msg, sizeof msg) == 0;
  if (rank == 0) tt_free(text);
  else free(text);
  int parsed0 = parsed; /* rank 0 names the problem; another rank only what rank 0 accepted */
  MPI_Bcast(&parsed0, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (!parsed && (rank == 0 || parsed0))
    fprintf(stderr, "tunetrace-mpi%s%.0d: %s\n", rank ? " rank " : "", rank, msg);
  int all = 0;
  MPI_Allreduce(&parsed, &all, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  if (!all && parsed) tt_mpi_jobs_free(jobs);
  return all ? 0 : -1;
}

/* Each rank's scratch folder (node-local: the jobs' own databases, logs); 0, or -1 printed. */
static int tt__make_scratch(const tt_mpi_opts *o, int rank, char *scratch, size_t n) {
  snprintf(scratch, n, "%s/tunetrace-mpi-r%d-XXXXXX", o->scratch, rank);
  if (mkdtemp(scratch)) return 0;
  fprintf(stderr, "tunetrace-mpi: rank %d: --scratch %s: cannot create a folder: %s\n", rank,
          o->scratch, strerror(errno));
  return -1;
}

/* Ends the rank: without MPI_Finalize when a rank was lost (see REPLY_EXIT). */
static int tt__end(int rc) {
  if (tt_mpi_skip_finalize) {
    fflush(NULL);
    _exit(rc);
  }
  MPI_Finalize();
  return rc;
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = tt__on_signal;
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
  tt_mpi_opts o;
  tt_mpi_jobs jobs;
  int rc = tt__parse_args(argc, argv, rank, &o);
  if (rc < 0 && tt__read_jobs(&o, rank, &jobs)) rc = EXIT_USAGE;
  if (rc >= 0) {
    MPI_Finalize();
    return rc;
  }
  /* rank 0 opens the merged database and finds what is done */
  tt_mpi_coord c;
  memset(&c, 0, sizeof c);
  int opened = rank != 0 || tt_mpi_coord_open(&c, &o, &jobs) == 0;
  char scratch[4200];
  int have_scratch = tt__make_scratch(&o, rank, scratch, sizeof scratch) == 0;
  int ready = opened && have_scratch, all_ready = 0;
  MPI_Allreduce(&ready, &all_ready, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  rc = !all_ready          ? EXIT_USAGE
       : rank == 0         ? tt_mpi_coord_run(&c, size, scratch)
       : o.list || o.check ? EXIT_OK
                           : tt_mpi_work(&o, &jobs, rank, scratch);
  if (have_scratch) tt_mpi_remove_folder(scratch);
  tt_mpi_coord_close(&c);
  tt_mpi_jobs_free(&jobs);
  return tt__end(rc);
}
