/* tunetrace-mpi: rank 0 — the one writer of the merged database and the job queue. It hands
 * out jobs in list order to the workers that ask, runs jobs itself between merges, merges
 * every result (tt_tunedb_merge: a job's rows and its tag in one transaction), writes a
 * sequence's manifest when its last range is done, and watches the workers' heartbeats. */
#ifndef TT_MPI_COORDINATOR_H
#define TT_MPI_COORDINATOR_H

#include "jobs.h"
#include "protocol.h"

#include <tunetrace/tunedb.h>

#include <stddef.h>

typedef struct tt_mpi_coord {
  const tt_mpi_opts *o;
  const tt_mpi_jobs *jobs;
  tt_tunedb *db;
  unsigned char *done;  /* per job: merged (before or in this run) */
  unsigned char *given; /* per job: handed out in this run */
  size_t next;          /* first job maybe not handed out */
  long handed, todo, finished, failed, lost;
  double t0;
  char scratch[4200];
} tt_mpi_coord;

/* Opens the merged database --db and finds which jobs it holds (`c` zeroed first). 0, or -1
 * after printing what failed. */
int tt_mpi_coord_open(tt_mpi_coord *c, const tt_mpi_opts *o, const tt_mpi_jobs *jobs);

/* --list / --check, or the run over `size` ranks (rank 0's own jobs in `scratch`) and its
 * summary; the exit code of rank 0. */
int tt_mpi_coord_run(tt_mpi_coord *c, int size, const char *scratch);

/* Closes the database and frees what `c` holds (a zeroed `c` too). */
void tt_mpi_coord_close(tt_mpi_coord *c);

#endif /* TT_MPI_COORDINATOR_H */
