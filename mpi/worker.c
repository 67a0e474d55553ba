/* tunetrace-mpi: a worker rank (see worker.h). */
#include "worker.h"
#include "job_run.h"

#include <mpi.h>

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

/* Drains rank 0's heartbeats; 0 while rank 0 has been heard from within --liveness seconds,
 * -1 once it has been silent longer (taken as dead). */
static int tt__rank0_alive(const tt_mpi_opts *o, double *seen) {
  double now = tt_mpi_now();
  for (;;) {
    int flag = 0;
    MPI_Status st;
    MPI_Iprobe(0, TAG_ALIVE, MPI_COMM_WORLD, &flag, &st);
    if (!flag) break;
    int64_t x;
    MPI_Recv(&x, 1, MPI_INT64_T, 0, TAG_ALIVE, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    *seen = now;
  }
  return now - *seen > o->liveness ? -1 : 0;
}

/* Completes request q (a send to rank 0 or a receive from it) without blocking on a dead
 * rank 0, sending heartbeats meanwhile (rank 0 may hold a request until the run ends). 0 when
 * done, -1 when rank 0 fell silent first. */
static int tt__finish(const tt_mpi_opts *o, MPI_Request *q, double *seen) {
  double last = tt_mpi_now();
  for (;;) {
    int done = 0;
    MPI_Test(q, &done, MPI_STATUS_IGNORE);
    if (done) {
      *seen = tt_mpi_now();
      return 0;
    }
    if (tt__rank0_alive(o, seen)) return -1;
    if (tt_mpi_now() - last >= o->heartbeat) {
      tt_mpi_send_alive(0);
      last = tt_mpi_now();
    }
    usleep(1000);
  }
}

static int tt__rank0_lost(int rank, const tt_mpi_opts *o) {
  tt_mpi_skip_finalize = 1;
  fprintf(stderr,
          "tunetrace-mpi: rank %d: rank 0 silent for %.0f s: taken as dead; this rank "
          "stops (every job rank 0 merged is in the database: the same command completes "
          "the set)\n",
          rank, o->liveness);
  return EXIT_FAILED;
}

/* Waits for the job's host process, sending rank 0 heartbeats; 0 when it ended, -1 when
 * rank 0 fell silent first (the process is stopped). */
static int tt__wait_job(const tt_mpi_opts *o, tt_mpi_run *r, double *seen) {
  double last = tt_mpi_now();
  while (!tt_mpi_child_wait(&r->child, o->heartbeat)) {
    if (tt_mpi_now() - last >= o->heartbeat) {
      tt_mpi_send_alive(0);
      last = tt_mpi_now();
    }
    if (tt__rank0_alive(o, seen)) {
      tt_mpi_child_kill(r->child.pid, SIGTERM);
      tt_mpi_child_poll(&r->child, 1);
      tt_mpi_running_child = 0;
      return -1;
    }
  }
  return 0;
}

/* Runs job `k` and sends its result; 0, or -1 when rank 0 fell silent. */
static int tt__do_job(const tt_mpi_opts *o, const tt_mpi_jobs *jobs, int rank, const char *scratch,
                      long k, double *seen) {
  tt_mpi_run r;
  if (tt_mpi_run_start(&r, o, scratch, jobs, k) == 0 && tt__wait_job(o, &r, seen)) return -1;
  tt_mpi_running_child = 0;
  int ok = 0;
  char *note = tt_mpi_run_note(&r, rank, &ok);
  int len = 0;
  unsigned char *m = tt_mpi_run_pack(&r, ok, note, &len);
  MPI_Request q;
  MPI_Isend(m, len, MPI_BYTE, 0, TAG_RESULT, MPI_COMM_WORLD, &q);
  int lost = tt__finish(o, &q, seen);
  free(note);
  if (lost) return -1; /* m stays with the request */
  free(m);
  return 0;
}

int tt_mpi_work(const tt_mpi_opts *o, const tt_mpi_jobs *jobs, int rank, const char *scratch) {
  double seen = tt_mpi_now();
  MPI_Request q;
  /* the first request carries no result */
  tt_mpi_result_head none = {-1, 0, 0, 0, 0, 0};
  MPI_Isend(&none, (int)sizeof none, MPI_BYTE, 0, TAG_RESULT, MPI_COMM_WORLD, &q);
  if (tt__finish(o, &q, &seen)) return tt__rank0_lost(rank, o);
  for (;;) {
    int64_t k = -1;
    MPI_Irecv(&k, 1, MPI_INT64_T, 0, TAG_JOB, MPI_COMM_WORLD, &q);
    if (tt__finish(o, &q, &seen)) return tt__rank0_lost(rank, o);
    if (k < 0) {
      tt_mpi_skip_finalize = k == REPLY_EXIT;
      return EXIT_OK;
    }
    if (tt__do_job(o, jobs, rank, scratch, (long)k, &seen)) return tt__rank0_lost(rank, o);
  }
}
