/* tunetrace-mpi: a worker rank (every rank but 0) — asks rank 0 for a job, runs it as a host
 * process, sends the result, and so on until rank 0 says the run is over; it stops by itself
 * when rank 0 falls silent for --liveness seconds. */
#ifndef TT_MPI_WORKER_H
#define TT_MPI_WORKER_H

#include "jobs.h"
#include "protocol.h"

/* Runs the worker loop of `rank` with its `scratch` folder; the rank's exit code. */
int tt_mpi_work(const tt_mpi_opts *o, const tt_mpi_jobs *jobs, int rank, const char *scratch);

#endif /* TT_MPI_WORKER_H */
