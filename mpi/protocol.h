/* tunetrace-mpi: what rank 0 (coordinator.c) and the workers (worker.c) share — the
 * driver's options, the messages between them, the exit codes and the signal state.
 *
 * Messages: a worker sends TAG_RESULT (a result head, then its job's database bytes and the
 * note; the first request of a worker carries a head with job -1), rank 0 answers TAG_JOB
 * (a job index, or a REPLY_* at the end of the run); both send TAG_ALIVE heartbeats.
 * Liveness: Open MPI 4 has no ULFM, so a peer's death is not reported to MPI calls (a send
 * to a dead rank over shared memory just succeeds). Under `mpirun --enable-recovery` the
 * other ranks keep running when one dies, so each side watches the other: a worker sends
 * rank 0 a heartbeat while its job runs, rank 0 sends one to every worker it waits for, and
 * a peer silent for --liveness seconds is taken as dead. Every wait is a non-blocking test,
 * so no rank ever blocks on a dead peer. */
#ifndef TT_MPI_PROTOCOL_H
#define TT_MPI_PROTOCOL_H

#include <signal.h>
#include <stdint.h>
#include <sys/types.h>

enum { TAG_JOB = 1, TAG_RESULT = 2, TAG_ALIVE = 3 };
enum { EXIT_OK = 0, EXIT_FAILED = 1, EXIT_USAGE = 2, EXIT_INTERRUPTED = 130 };

/* The reply to a worker's request: a job index >= 0, or the end of the run. Rank 0 answers
 * a request it has no job for only when the whole run is over, so that every rank knows
 * whether a rank was lost: Open MPI 4.1's MPI_Finalize is a PMIx fence over every process
 * of the run and hangs, more often than not, when one of them died; then the survivors exit
 * without it (under --enable-recovery mpirun accepts that). */
enum { REPLY_FINALIZE = -1, REPLY_EXIT = -2 };

/* The fixed head of a result message; the payload (the job's database file, or nothing)
 * and the note text (JSON) follow it. */
typedef struct tt_mpi_result_head {
  int64_t job;
  int64_t exit_code;
  int64_t payload; /* bytes of the database file that follow (0: none) */
  int64_t note;    /* bytes of the note that follow */
  double wall_s, cpu_s;
} tt_mpi_result_head;

/* The command line of tunetrace-mpi. */
typedef struct tt_mpi_opts {
  const char *jobs, *db, *host, *scratch;
  int list, check;
  long max_jobs;
  double liveness;  /* seconds of silence after which a peer is taken as dead */
  double heartbeat; /* seconds between heartbeats (liveness / 10, within 0.1..5) */
} tt_mpi_opts;

/* SIGINT/SIGTERM arrived: no new job is handed out (main.c's handler sets it). */
extern volatile sig_atomic_t tt_mpi_stop;
/* The host process this rank runs (0: none), stopped by the signal handler. */
extern volatile pid_t tt_mpi_running_child;
/* A rank was lost: end without MPI_Finalize (see REPLY_EXIT). */
extern int tt_mpi_skip_finalize;

/* Sends a heartbeat to rank `to` (not waited for). */
void tt_mpi_send_alive(int to);

#endif /* TT_MPI_PROTOCOL_H */
