/* tunetrace-mpi: one job's host process. Started with fork/exec (no shell), its output into
 * a log file, killed with its rank (PR_SET_PDEATHSIG: mpirun tearing a run down leaves no
 * orphan rendering on). */
#ifndef TT_MPI_CHILD_H
#define TT_MPI_CHILD_H

#include <sys/types.h>

typedef struct tt_mpi_child {
  pid_t pid; /* 0: none running */
  int pidfd; /* readable when the child ends (pidfd_open); -1 where unsupported */
  double t0; /* start (monotonic seconds) */
  double wall_s, cpu_s;
  int exit_code; /* exit status, 128 + signal if killed, -1 if it could not start */
} tt_mpi_child;

/* Monotonic seconds. */
double tt_mpi_now(void);

/* Starts argv[0] with argv, stdout and stderr into `log`. 0, or -1 (message in err). */
int tt_mpi_child_start(tt_mpi_child *c, char **argv, const char *log, char *err, size_t n);

/* Waits for the child (block != 0) or checks it; 1 when it has ended (exit_code, wall_s,
 * cpu_s filled, pid 0), 0 while it runs. */
int tt_mpi_child_poll(tt_mpi_child *c, int block);

/* Waits up to `timeout_s` seconds for the child to end, waking at once when it does (poll
 * on its pidfd; 2 ms steps where pidfds are missing); then as tt_mpi_child_poll(c, 0). */
int tt_mpi_child_wait(tt_mpi_child *c, double timeout_s);

/* Sends `sig` to a running child. Async-signal-safe on the pid it is given. */
void tt_mpi_child_kill(pid_t pid, int sig);

/* The last `max` bytes of the file `path` (a job's log) into buf. */
void tt_mpi_file_tail(const char *path, char *buf, size_t max);

/* Removes the files in the folder `dir` (it holds files only: a rank's scratch folder, a
 * frame range's work folder) and the folder. */
void tt_mpi_remove_folder(const char *dir);

#endif /* TT_MPI_CHILD_H */
