/* tunetrace-mpi: a job's host process (see child.h). */
#include "child.h"

#include <tunetrace/file.h>

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <poll.h>
#include <sys/pidfd.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

double tt_mpi_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

int tt_mpi_child_start(tt_mpi_child *c, char **argv, const char *log, char *err, size_t n) {
  int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    snprintf(err, n, "cannot write the job log %s: %s", log, strerror(errno));
    return -1;
  }
  pid_t parent = getpid();
  pid_t pid = fork();
  if (pid < 0) {
    snprintf(err, n, "cannot start %s: %s", argv[0], strerror(errno));
    close(fd);
    return -1;
  }
  if (pid == 0) {
    /* the child: dies with its rank; the rank's signal dispositions are not inherited */
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    dup2(fd, STDOUT_FILENO);
    dup2(fd, STDERR_FILENO);
    int null = open("/dev/null", O_RDONLY);
    if (null >= 0) dup2(null, STDIN_FILENO);
    execv(argv[0], argv);
    dprintf(STDERR_FILENO, "tunetrace-mpi: cannot run %s: %s\n", argv[0], strerror(errno));
    _exit(127);
  }
  close(fd);
  c->pid = pid;
  c->pidfd = pidfd_open(pid, 0);
  c->t0 = tt_mpi_now();
  c->exit_code = -1;
  return 0;
}

int tt_mpi_child_poll(tt_mpi_child *c, int block) {
  if (!c->pid) return 1;
  int status = 0;
  struct rusage ru;
  pid_t r;
  do r = wait4(c->pid, &status, block ? 0 : WNOHANG, &ru);
  while (r < 0 && errno == EINTR);
  if (r == 0) return 0;
  c->wall_s = tt_mpi_now() - c->t0;
  if (r < 0) {
    c->exit_code = -1;
    c->cpu_s = 0;
  } else {
    c->exit_code = WIFEXITED(status)     ? WEXITSTATUS(status)
                   : WIFSIGNALED(status) ? 128 + WTERMSIG(status)
                                         : -1;
    c->cpu_s = ru.ru_utime.tv_sec + ru.ru_utime.tv_usec * 1e-6 + ru.ru_stime.tv_sec +
               ru.ru_stime.tv_usec * 1e-6;
  }
  c->pid = 0;
  if (c->pidfd >= 0) close(c->pidfd);
  c->pidfd = -1;
  return 1;
}

int tt_mpi_child_wait(tt_mpi_child *c, double timeout_s) {
  if (!c->pid) return 1;
  if (c->pidfd >= 0) {
    struct pollfd p = {c->pidfd, POLLIN, 0};
    poll(&p, 1, timeout_s > 0 ? (int)(timeout_s * 1000) : 0);
  } else {
    for (double t0 = tt_mpi_now(); tt_mpi_now() - t0 < timeout_s;) {
      if (tt_mpi_child_poll(c, 0)) return 1;
      usleep(2000);
    }
  }
  return tt_mpi_child_poll(c, 0);
}

void tt_mpi_child_kill(pid_t pid, int sig) {
  if (pid > 0) kill(pid, sig);
}

void tt_mpi_file_tail(const char *path, char *buf, size_t max) {
  buf[0] = 0;
  if (tt_file_check_regular(path, "log") != TT_OK) return; /* never block on a FIFO */
  FILE *f = fopen(path, "rb");
  if (!f) return;
  fseek(f, 0, SEEK_END);
  long size = ftell(f);
  long from = size > (long)max - 1 ? size - (long)max + 1 : 0;
  fseek(f, from, SEEK_SET);
  size_t got = fread(buf, 1, max - 1, f);
  buf[got] = 0;
  fclose(f);
}

void tt_mpi_remove_folder(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return;
  struct dirent *e;
  char path[8192];
  while ((e = readdir(d))) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
    unlink(path);
  }
  closedir(d);
  rmdir(dir);
}
