/* tunetrace-mpi: one job run by this rank (rank 0 runs jobs too) — its host process, then
 * what it made: the note rank 0 merges with the job's tag and, for a worker, the result
 * message. */
#ifndef TT_MPI_JOB_RUN_H
#define TT_MPI_JOB_RUN_H

#include "child.h"
#include "jobs.h"
#include "protocol.h"

typedef struct tt_mpi_run {
  const tt_mpi_job *job;
  long index;
  tt_mpi_child child;
  char db[4200], stats[4200], log[4200], dir[4200];
  char err[2048];
} tt_mpi_run;

/* Starts job `index` of `jobs` as a host process, its database, stats and log in the rank's
 * `scratch` folder (a frame range renders into its own work folder). 0, or -1 when it could
 * not start (child.exit_code -1, the reason in err). */
int tt_mpi_run_start(tt_mpi_run *r, const tt_mpi_opts *o, const char *scratch,
                     const tt_mpi_jobs *jobs, long index);

/* After the host process ended: the note (JSON, malloc) and whether the job succeeded
 * (`*ok`). Moves a frame range into its folder; checks that a tuning job's database closed
 * cleanly. */
char *tt_mpi_run_note(tt_mpi_run *r, int rank, int *ok);

/* The job's result as one message (head, database bytes, note; malloc), `*len` bytes. */
unsigned char *tt_mpi_run_pack(const tt_mpi_run *r, int ok, const char *note, int *len);

#endif /* TT_MPI_JOB_RUN_H */
