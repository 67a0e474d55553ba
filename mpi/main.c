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
 * depend on which rank ran what, or in which order. */
#include "child.h"
#include "frames.h"
#include "jobs.h"

#include <tunetrace/file.h>
#include <tunetrace/tunedb.h>
#include <tunetrace/tunetrace.h>

#include <cjson/cJSON.h>
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
#define TT_MPI_BUILD_DIR ""
#endif
#ifndef TT_MPI_BUILD_HOST
#define TT_MPI_BUILD_HOST ""
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

enum { TAG_JOB = 1, TAG_RESULT = 2, TAG_ALIVE = 3 };
enum { EXIT_OK = 0, EXIT_FAILED = 1, EXIT_USAGE = 2, EXIT_INTERRUPTED = 130 };

/* The fixed head of a result message; the payload (the job's database file, or nothing)
 * and the note text (JSON) follow it. */
typedef struct tt_mpi_result_head {
  int64_t job;
  int64_t exit_code;
  int64_t payload;     /* bytes of the database file that follow (0: none) */
  int64_t note;        /* bytes of the note that follow */
  double wall_s, cpu_s;
} tt_mpi_result_head;

typedef struct tt_mpi_opts {
  const char *jobs, *db, *host, *scratch;
  int list, check;
  long max_jobs;
  double liveness;   /* seconds of silence after which a peer is taken as dead */
  double heartbeat;  /* seconds between heartbeats (liveness / 10, within 0.1..5) */
} tt_mpi_opts;

static volatile sig_atomic_t g_stop;
static volatile pid_t g_child;

static void tt__on_signal(int sig) {
  g_stop = 1;
  tt_mpi_child_kill(g_child, sig == SIGINT ? SIGINT : SIGTERM);
}

static int tt__usage(int rank, const char *msg) {
  if (rank == 0) {
    if (msg) fprintf(stderr, "tunetrace-mpi: %s\n", msg);
    fprintf(stderr, "usage: mpirun [--enable-recovery] -np N tunetrace-mpi --jobs FILE --db DB "
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

/* This rank's job run: the host process, then what it made, as a result message. */
typedef struct tt_mpi_run {
  const tt_mpi_job *job;
  long index;
  tt_mpi_child child;
  char db[4200], stats[4200], log[4200], dir[4200];
  char err[2048];
} tt_mpi_run;

static int tt__run_start(tt_mpi_run *r, const tt_mpi_opts *o, const char *scratch,
                         const tt_mpi_jobs *jobs, long index) {
  memset(r, 0, sizeof *r);
  r->job = &jobs->jobs[index];
  r->index = index;
  snprintf(r->db, sizeof r->db, "%s/job.db", scratch);
  snprintf(r->stats, sizeof r->stats, "%s/job.stats.json", scratch);
  snprintf(r->log, sizeof r->log, "%s/job.log", scratch);
  const char *sfx[] = {"", "-wal", "-shm"};
  for (int i = 0; i < 3; i++) {
    char p[4300];
    snprintf(p, sizeof p, "%s%s", r->db, sfx[i]);
    unlink(p);
  }
  unlink(r->stats);
  if (r->job->kind == TT_MPI_FRAMES &&
      tt_mpi_frames_prepare(r->job, r->dir, sizeof r->dir, r->err, sizeof r->err)) {
    r->child.exit_code = -1;
    return -1;
  }
  char **argv = tt_mpi_job_argv(r->job, o->host, r->db, r->stats, r->dir);
  int rc = argv ? tt_mpi_child_start(&r->child, argv, r->log, r->err, sizeof r->err) : -1;
  tt_mpi_argv_free(argv);
  if (rc) r->child.exit_code = -1;
  g_child = r->child.pid;
  return rc;
}

/* After the host process ended: the note (JSON) and, for a tuning job, the path of its
 * database. Moves a frame range into its folder. */
static char *tt__run_note(tt_mpi_run *r, int rank, int *ok) {
  cJSON *o = cJSON_CreateObject();
  char *job = tt_mpi_job_json(r->job);
  cJSON_AddItemToObject(o, "job", cJSON_Parse(job));
  free(job);
  cJSON_AddNumberToObject(o, "rank", rank);
  cJSON_AddStringToObject(o, "host", tt_tunedb_host_name());
  cJSON_AddNumberToObject(o, "exit", r->child.exit_code);
  cJSON_AddNumberToObject(o, "wall_s", r->child.wall_s);
  cJSON_AddNumberToObject(o, "cpu_s", r->child.cpu_s);
  double load[1] = {0};
  if (getloadavg(load, 1) == 1) cJSON_AddNumberToObject(o, "load1", load[0]);
  *ok = r->child.exit_code == 0;
  if (*ok && r->job->kind == TT_MPI_FRAMES) {
    char *manifest = NULL;
    if (tt_mpi_frames_finish(r->job, r->dir, &manifest, r->err, sizeof r->err)) {
      *ok = 0;
    } else {
      cJSON_AddItemToObject(o, "manifest", cJSON_Parse(manifest));
      free(manifest);
    }
  } else if (*ok) {
    char *text = NULL;
    size_t size = 0;
    if (tt_file_read(r->stats, "stats", 0, &text, &size) == TT_OK) {
      cJSON *st = cJSON_Parse(text);
      if (st) cJSON_AddItemToObject(o, "stats", st);
      tt_free(text);
    }
    /* the database closed cleanly (WAL checkpointed into the one file that travels) */
    tt_tunedb *db = NULL;
    if (tt_tunedb_open(r->db, &db) != TT_OK) {
      snprintf(r->err, sizeof r->err, "%s", tt_last_error());
      *ok = 0;
    }
    tt_tunedb_close(db);
  }
  if (!*ok) {
    char tail[1500];
    tt_mpi_file_tail(r->log, tail, sizeof tail);
    cJSON_AddStringToObject(o, "error", r->err[0] ? r->err : tail);
  }
  char *s = cJSON_PrintUnformatted(o);
  cJSON_Delete(o);
  return s;
}

/* ---- rank 0: the merged database and the job queue ---- */

typedef struct tt_mpi_coord {
  const tt_mpi_opts *o;
  const tt_mpi_jobs *jobs;
  tt_tunedb *db;
  unsigned char *done;   /* per job: merged (before or in this run) */
  unsigned char *given;  /* per job: handed out in this run */
  size_t next;           /* first job maybe not handed out */
  long handed, todo, finished, failed, lost;
  double t0;
  char scratch[4200];
} tt_mpi_coord;

static long tt__next_job(tt_mpi_coord *c) {
  if (g_stop || (c->o->max_jobs && c->handed >= c->o->max_jobs)) return -1;
  while (c->next < c->jobs->count && (c->done[c->next] || c->given[c->next])) c->next++;
  if (c->next >= c->jobs->count) return -1;
  c->given[c->next] = 1;
  c->handed++;
  return (long)c->next;
}

/* Writes a sequence's manifest when the last of its ranges is done. */
static void tt__maybe_sequence(tt_mpi_coord *c, size_t k) {
  const tt_mpi_job *j = &c->jobs->jobs[k];
  if (j->kind != TT_MPI_FRAMES) return;
  size_t first = c->jobs->count;
  for (size_t i = 0; i < c->jobs->count; i++) {
    const tt_mpi_job *o = &c->jobs->jobs[i];
    if (o->kind != TT_MPI_FRAMES || strcmp(o->sequence, j->sequence)) continue;
    if (!c->done[i]) return;
    if (first == c->jobs->count) first = i;
  }
  char err[2048];
  if (tt_mpi_sequence_write(c->jobs, first, err, sizeof err)) {
    fprintf(stderr, "tunetrace-mpi: sequence %s: %s\n", j->out_dir, err);
    c->failed++;
  } else {
    fprintf(stderr, "tunetrace-mpi: sequence %s complete (%s/manifest.json)\n", j->out_dir,
            j->out_dir);
  }
}

/* Merges one finished job (its database file at `path`, or none) and reports it. */
static void tt__merge(tt_mpi_coord *c, long k, int rank, int ok, const char *path,
                      const char *note, double wall_s) {
  const tt_mpi_job *j = &c->jobs->jobs[k];
  c->finished++;
  uint64_t rows = 0;
  int already = 0;
  if (ok && tt_tunedb_merge(c->db, j->kind == TT_MPI_FRAMES ? NULL : path, j->tag, rank, note,
                            &rows, &already) != TT_OK) {
    fprintf(stderr, "tunetrace-mpi: merging job %s from rank %d: %s\n", j->tag, rank,
            tt_last_error());
    ok = 0;
  }
  if (ok) {
    c->done[k] = 1;
  } else {
    c->failed++;
    cJSON *n = cJSON_Parse(note);
    const cJSON *e = n ? cJSON_GetObjectItemCaseSensitive(n, "error") : NULL;
    const cJSON *x = n ? cJSON_GetObjectItemCaseSensitive(n, "exit") : NULL;
    fprintf(stderr, "tunetrace-mpi: job %s (jobs[%zu]) FAILED on rank %d (exit %d):\n%s\n",
            j->tag, j->item, rank, cJSON_IsNumber(x) ? (int)x->valuedouble : -1,
            cJSON_IsString(e) ? e->valuestring : "");
    cJSON_Delete(n);
  }
  double el = tt_mpi_now() - c->t0;
  long left = c->todo - c->finished;
  char what[96] = "";
  if (ok && j->kind != TT_MPI_FRAMES)
    snprintf(what, sizeof what, ", %llu rows%s", (unsigned long long)rows,
             already ? " (merged before: none copied)" : "");
  fprintf(stderr, "[%ld/%ld] %s %s on rank %d, %.1f s%s; elapsed %.1f min, eta %.1f min\n",
          c->finished, c->todo, j->tag, ok ? "ok" : "FAILED", rank, wall_s, what, el / 60,
          c->finished ? el / c->finished * (left > 0 ? left : 0) / 60 : 0.0);
  if (ok) tt__maybe_sequence(c, (size_t)k);
}

/* A result message from `rank`: merges it. */
static void tt__receive(tt_mpi_coord *c, int rank, const unsigned char *msg, int len) {
  tt_mpi_result_head h;
  if ((size_t)len < sizeof h) return;
  memcpy(&h, msg, sizeof h);
  const unsigned char *payload = msg + sizeof h;
  char *note = malloc((size_t)h.note + 1);
  memcpy(note, payload + h.payload, (size_t)h.note);
  note[h.note] = 0;
  char path[4300] = "";
  int ok = h.exit_code == 0;
  if (ok && h.payload > 0) {
    snprintf(path, sizeof path, "%s/from-rank%d.db", c->scratch, rank);
    if (tt_file_write_atomic(path, payload, (size_t)h.payload) != TT_OK) {
      fprintf(stderr, "tunetrace-mpi: %s\n", tt_last_error());
      ok = 0;
    }
  }
  tt__merge(c, (long)h.job, rank, ok, path, note, h.wall_s);
  if (path[0]) unlink(path);
  free(note);
}

/* A job's result as one message (head, database bytes, note). */
static unsigned char *tt__pack(const tt_mpi_run *r, int ok, const char *note, int *len) {
  char *db = NULL;
  size_t dbn = 0;
  if (ok && r->job->kind != TT_MPI_FRAMES &&
      tt_file_read(r->db, "job database", 0, &db, &dbn) != TT_OK) {
    ok = 0;
    dbn = 0;
  }
  tt_mpi_result_head h = {r->index, ok ? 0 : (r->child.exit_code ? r->child.exit_code : 1),
                          (int64_t)dbn, (int64_t)strlen(note), r->child.wall_s, r->child.cpu_s};
  size_t total = sizeof h + dbn + strlen(note);
  unsigned char *m = malloc(total);
  memcpy(m, &h, sizeof h);
  if (dbn) memcpy(m + sizeof h, db, dbn);
  memcpy(m + sizeof h + dbn, note, strlen(note));
  tt_free(db);
  *len = (int)total;
  return m;
}

/* ---- liveness: how rank 0 and the workers notice that the other side died ----
 * Open MPI 4 has no ULFM: a peer's death is not reported to MPI calls (a send to a dead
 * rank over shared memory just succeeds). Under `mpirun --enable-recovery` the other ranks
 * keep running when one dies, so each side watches the other: a worker sends rank 0 a
 * heartbeat while its job runs, rank 0 sends one to every worker it waits for, and a peer
 * silent for --liveness seconds is taken as dead. Every wait is a non-blocking test, so no
 * rank ever blocks on a dead peer. */
static const int64_t g_alive = 0;  /* a heartbeat's body (buffer of requests freed at once) */

/* The reply to a worker's request: a job index >= 0, or the end of the run. Rank 0 answers
 * a request it has no job for only when the whole run is over, so that every rank knows
 * whether a rank was lost: Open MPI 4.1's MPI_Finalize is a PMIx fence over every process
 * of the run and hangs, more often than not, when one of them died; then the survivors exit
 * without it (under --enable-recovery mpirun accepts that). */
enum { REPLY_FINALIZE = -1, REPLY_EXIT = -2 };
static int g_skip_finalize;  /* a rank was lost: end without MPI_Finalize */

static void tt__send_alive(int to) {
  MPI_Request q;
  MPI_Isend(&g_alive, 1, MPI_INT64_T, to, TAG_ALIVE, MPI_COMM_WORLD, &q);
  MPI_Request_free(&q);
}

/* rank 0's view of a worker */
enum { PEER_WORKING, PEER_WAITING, PEER_LOST };  /* WAITING: asked, no job left for it */
typedef struct tt_mpi_peer {
  int state;
  double seen;          /* the last message from it (monotonic s) */
  long job;             /* the job it runs (-1: none) */
  int job_lost;         /* its job was counted lost */
  MPI_Request recv;     /* a result being received (MPI_REQUEST_NULL: none) */
  unsigned char *buf;
  int len;
  int64_t reply;        /* the job number last sent to it (the buffer of that send) */
} tt_mpi_peer;

static void tt__reply(tt_mpi_peer *p, int rank, int64_t v) {
  p->reply = v;
  MPI_Request q;
  MPI_Isend(&p->reply, 1, MPI_INT64_T, rank, TAG_JOB, MPI_COMM_WORLD, &q);
  MPI_Request_free(&q);
}

/* A worker's result (or first request) has arrived: merges it, hands out the next job. */
static void tt__peer_result(tt_mpi_coord *c, tt_mpi_peer *p, int rank, int *active) {
  int was_lost = p->state == PEER_LOST;
  if (was_lost) {
    fprintf(stderr, "tunetrace-mpi: rank %d answered again after being taken as lost; its "
            "result is taken, and it gets no new job\n", rank);
    if (p->job_lost) {
      c->finished--;
      c->lost--;
    }
  }
  if (p->len >= (int)sizeof(tt_mpi_result_head)) {
    tt_mpi_result_head h;
    memcpy(&h, p->buf, sizeof h);
    if (h.job >= 0) {
      if (g_stop && h.exit_code != 0) c->finished++;  /* interrupted: redone by a rerun */
      else tt__receive(c, rank, p->buf, p->len);
    }
  }
  free(p->buf);
  p->buf = NULL;
  p->job_lost = 0;
  int64_t next = was_lost ? -1 : tt__next_job(c);
  p->job = (long)next;
  if (next < 0) {  /* answered when the run is over (tt__coordinate) */
    if (!was_lost) (*active)--;
    p->state = PEER_WAITING;
    return;
  }
  tt__reply(p, rank, next);
}

static int tt__coordinate(tt_mpi_coord *c, int size, const char *scratch) {
  int active = size - 1;         /* workers not yet told to stop, nor lost */
  tt_mpi_peer *peers = calloc((size_t)size, sizeof *peers);
  double now = tt_mpi_now(), last_alive = now;
  for (int r = 1; r < size; r++) {
    peers[r].seen = now;
    peers[r].job = -1;
    peers[r].recv = MPI_REQUEST_NULL;
  }
  tt_mpi_run own;
  int own_running = 0;
  for (;;) {
    int progressed = 0;
    if (!own_running) {
      long k = tt__next_job(c);
      if (k >= 0) {
        if (tt__run_start(&own, c->o, scratch, c->jobs, k) == 0) {
          own_running = 1;
        } else {
          char *note = tt__run_note(&own, 0, &(int){0});
          tt__merge(c, k, 0, 0, NULL, note, 0);
          free(note);
        }
        progressed = 1;
      } else if (active == 0) {
        /* the end: every rank still here asked for a job lately (a waiting rank that died
         * must not be told to finalize), then all of them are told how to end */
        int fresh = 1;
        for (int r = 1; r < size; r++)
          if (peers[r].state == PEER_WAITING && now - peers[r].seen > 3 * c->o->heartbeat)
            fresh = 0;
        if (fresh) break;
      }
    }
    if (own_running && tt_mpi_child_poll(&own.child, 0)) {
      g_child = 0;
      int ok = 0;
      char *note = tt__run_note(&own, 0, &ok);
      if (g_stop && !ok) c->finished++;  /* interrupted: not a failure, redone by a rerun */
      else tt__merge(c, own.index, 0, ok, own.db, note, own.child.wall_s);
      free(note);
      own_running = 0;
      progressed = 1;
    }
    now = tt_mpi_now();
    /* messages: heartbeats, and results (received without blocking: a sender that dies
     * half-way must not hang rank 0) */
    for (int m = 0; m < 256; m++) {
      int flag = 0;
      MPI_Message msg;
      MPI_Status st;
      MPI_Improbe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &msg, &st);
      if (!flag) break;
      tt_mpi_peer *p = &peers[st.MPI_SOURCE];
      p->seen = now;
      int len = 0;
      MPI_Get_count(&st, MPI_BYTE, &len);
      if (st.MPI_TAG == TAG_RESULT && p->recv == MPI_REQUEST_NULL) {
        p->buf = malloc(len > 0 ? (size_t)len : 1);
        p->len = len;
        MPI_Imrecv(p->buf, len, MPI_BYTE, &msg, &p->recv);
      } else {  /* a heartbeat (or a message out of turn): read and dropped */
        unsigned char *junk = malloc(len > 0 ? (size_t)len : 1);
        MPI_Mrecv(junk, len, MPI_BYTE, &msg, MPI_STATUS_IGNORE);
        free(junk);
      }
      progressed = 1;
    }
    for (int r = 1; r < size; r++) {
      tt_mpi_peer *p = &peers[r];
      int done = 0;
      if (p->recv != MPI_REQUEST_NULL) MPI_Test(&p->recv, &done, MPI_STATUS_IGNORE);
      if (done) {
        p->seen = now;
        tt__peer_result(c, p, r, &active);
        progressed = 1;
      } else if (p->state != PEER_LOST && now - p->seen > c->o->liveness) {
        if (p->state == PEER_WORKING) active--;
        p->state = PEER_LOST;
        if (p->job >= 0) {
          const tt_mpi_job *j = &c->jobs->jobs[p->job];
          fprintf(stderr, "tunetrace-mpi: rank %d silent for %.0f s: taken as dead; its job "
                  "%s (jobs[%zu]) is lost (the same command redoes it), the other ranks go "
                  "on\n", r, now - p->seen, j->tag, j->item);
          p->job_lost = 1;
          c->finished++;
          c->lost++;
        } else {
          fprintf(stderr, "tunetrace-mpi: rank %d silent for %.0f s: taken as dead (it held "
                  "no job)\n", r, now - p->seen);
        }
        progressed = 1;
      }
    }
    if (now - last_alive >= c->o->heartbeat) {
      for (int r = 1; r < size; r++)
        if (peers[r].state != PEER_LOST) tt__send_alive(r);
      last_alive = now;
    }
    if (!progressed) usleep(2000);
  }
  int lost = 0;
  for (int r = 1; r < size; r++) lost |= peers[r].state == PEER_LOST;
  g_skip_finalize = lost;
  for (int r = 1; r < size; r++)
    if (peers[r].state == PEER_WAITING) tt__reply(&peers[r], r, lost ? REPLY_EXIT : REPLY_FINALIZE);
  if (lost)
    fprintf(stderr, "tunetrace-mpi: a rank was lost: the ranks end without MPI_Finalize (Open "
            "MPI 4.1's would wait for the dead one)\n");
  /* receives still open belong to lost ranks: their buffers stay with MPI */
  free(peers);
  return g_stop ? EXIT_INTERRUPTED : (c->failed || c->lost) ? EXIT_FAILED : EXIT_OK;
}

/* A worker: drains rank 0's heartbeats; 0 while rank 0 has been heard from within
 * --liveness seconds, -1 once it has been silent longer (taken as dead). */
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

/* A worker: completes request q (a send to rank 0 or a receive from it) without blocking on
 * a dead rank 0, sending heartbeats meanwhile (rank 0 may hold a request until the run
 * ends). 0 when done, -1 when rank 0 fell silent first. */
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
      tt__send_alive(0);
      last = tt_mpi_now();
    }
    usleep(1000);
  }
}

static int tt__rank0_lost(int rank, const tt_mpi_opts *o) {
  g_skip_finalize = 1;
  fprintf(stderr, "tunetrace-mpi: rank %d: rank 0 silent for %.0f s: taken as dead; this rank "
          "stops (every job rank 0 merged is in the database: the same command completes "
          "the set)\n", rank, o->liveness);
  return EXIT_FAILED;
}

static int tt__work(const tt_mpi_opts *o, const tt_mpi_jobs *jobs, int rank,
                    const char *scratch) {
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
      g_skip_finalize = k == REPLY_EXIT;
      return EXIT_OK;
    }
    tt_mpi_run r;
    if (tt__run_start(&r, o, scratch, jobs, (long)k) == 0) {
      double last = tt_mpi_now();
      while (!tt_mpi_child_wait(&r.child, o->heartbeat)) {
        if (tt_mpi_now() - last >= o->heartbeat) {
          tt__send_alive(0);
          last = tt_mpi_now();
        }
        if (tt__rank0_alive(o, &seen)) {
          tt_mpi_child_kill(r.child.pid, SIGTERM);
          tt_mpi_child_poll(&r.child, 1);
          g_child = 0;
          return tt__rank0_lost(rank, o);
        }
      }
    }
    g_child = 0;
    int ok = 0;
    char *note = tt__run_note(&r, rank, &ok);
    int len = 0;
    unsigned char *m = tt__pack(&r, ok, note, &len);
    MPI_Isend(m, len, MPI_BYTE, 0, TAG_RESULT, MPI_COMM_WORLD, &q);
    int lost = tt__finish(o, &q, &seen);
    free(note);
    if (lost) return tt__rank0_lost(rank, o);  /* m stays with the request */
    free(m);
  }
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

  tt_mpi_opts o = {NULL, NULL, tt__default_host(), NULL, 0, 0, 0, 60, 0};
  const char *tmp = getenv("TMPDIR");
  o.scratch = tmp && tmp[0] ? tmp : "/tmp";
  int bad = 0;
  char msg[8192] = "";
  for (int i = 1; i < argc && !bad; i++) {
    const char *a = argv[i];
    const char **val = !strcmp(a, "--jobs") ? &o.jobs : !strcmp(a, "--db") ? &o.db
                       : !strcmp(a, "--host") ? &o.host : !strcmp(a, "--scratch") ? &o.scratch
                                                                                 : NULL;
    if (val || !strcmp(a, "--max-jobs") || !strcmp(a, "--liveness")) {
      if (i + 1 >= argc) {
        snprintf(msg, sizeof msg, "%s needs a value", a);
        bad = 1;
      } else if (val) {
        *val = argv[++i];
      } else if (!strcmp(a, "--liveness")) {
        char *end = NULL;
        o.liveness = strtod(argv[++i], &end);
        if (!*argv[i] || *end || !(o.liveness >= 1 && o.liveness <= 86400)) {
          snprintf(msg, sizeof msg, "--liveness: expected seconds in 1..86400, got \"%s\"",
                   argv[i]);
          bad = 1;
        }
      } else {
        char *end = NULL;
        o.max_jobs = strtol(argv[++i], &end, 10);
        if (!*argv[i] || *end || o.max_jobs < 1) {
          snprintf(msg, sizeof msg, "--max-jobs: expected a count >= 1, got \"%s\"", argv[i]);
          bad = 1;
        }
      }
    } else if (!strcmp(a, "--list")) {
      o.list = 1;
    } else if (!strcmp(a, "--check")) {
      o.check = 1;
    } else if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      tt__usage(rank, NULL);
      MPI_Finalize();
      return EXIT_OK;
    } else {
      snprintf(msg, sizeof msg, "unknown argument \"%s\"", a);
      bad = 1;
    }
  }
  if (!bad && (!o.jobs || !o.db)) {
    snprintf(msg, sizeof msg, "--jobs FILE and --db DB are required");
    bad = 1;
  }
  if (!bad && o.list && o.check) {
    snprintf(msg, sizeof msg, "--list and --check: give one of them");
    bad = 1;
  }
  o.heartbeat = o.liveness / 10 < 0.1 ? 0.1 : o.liveness / 10 > 5 ? 5 : o.liveness / 10;
  if (bad) {
    tt__usage(rank, msg);
    MPI_Finalize();
    return EXIT_USAGE;
  }

  /* rank 0 reads the list and sends it; every rank checks it (its scenes exist there too),
   * and nobody starts work unless every rank accepted it */
  char *text = NULL;
  size_t tn = 0;
  int64_t len = -1;
  if (rank == 0) {
    if (tt_file_read(o.jobs, "job list", 64u << 20, &text, &tn) == TT_OK) len = (int64_t)tn;
    else fprintf(stderr, "tunetrace-mpi: --jobs: %s\n", tt_last_error());
    if (len >= 0 && access(o.host, X_OK) != 0) {
      fprintf(stderr, "tunetrace-mpi: --host %s: not an executable (%s)\n", o.host,
              strerror(errno));
      len = -1;
    }
  }
  MPI_Bcast(&len, 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
  if (len < 0) {
    tt_free(text);
    MPI_Finalize();
    return EXIT_USAGE;
  }
  if (rank != 0) text = malloc((size_t)len + 1);
  MPI_Bcast(text, (int)len, MPI_CHAR, 0, MPI_COMM_WORLD);
  text[len] = 0;
  tt_mpi_jobs jobs;
  int parsed = tt_mpi_jobs_parse(text, o.jobs, &jobs, msg, sizeof msg) == 0;
  if (rank == 0) tt_free(text);
  else free(text);
  int parsed0 = parsed;  /* rank 0 names the problem; another rank only what rank 0 accepted */
  MPI_Bcast(&parsed0, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (!parsed && (rank == 0 || parsed0))
    fprintf(stderr, "tunetrace-mpi%s%.0d: %s\n", rank ? " rank " : "", rank, msg);
  int all = 0;
  MPI_Allreduce(&parsed, &all, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  if (!all) {
    if (parsed) tt_mpi_jobs_free(&jobs);
    MPI_Finalize();
    return EXIT_USAGE;
  }

  /* rank 0 opens the merged database and finds what is done */
  tt_mpi_coord c;
  memset(&c, 0, sizeof c);
  c.o = &o;
  c.jobs = &jobs;
  int opened = 1;
  if (rank == 0) {
    if (tt_tunedb_open(o.db, &c.db) != TT_OK) {
      fprintf(stderr, "tunetrace-mpi: --db: %s\n", tt_last_error());
      opened = 0;
    } else {
      c.done = calloc(jobs.count, 1);
      c.given = calloc(jobs.count, 1);
      for (size_t i = 0; i < jobs.count && opened; i++) {
        int m = 0;
        if (tt_tunedb_merged(c.db, jobs.jobs[i].tag, &m) != TT_OK) {
          fprintf(stderr, "tunetrace-mpi: --db: %s\n", tt_last_error());
          opened = 0;
        }
        c.done[i] = (unsigned char)m;
        c.todo += !m;
      }
    }
  }
  /* each rank's scratch folder (node-local: the jobs' own databases, logs) */
  char scratch[4200];
  snprintf(scratch, sizeof scratch, "%s/tunetrace-mpi-r%d-XXXXXX", o.scratch, rank);
  int have_scratch = mkdtemp(scratch) != NULL;
  if (!have_scratch)
    fprintf(stderr, "tunetrace-mpi: rank %d: --scratch %s: cannot create a folder: %s\n", rank,
            o.scratch, strerror(errno));
  int ready = opened && have_scratch, all_ready = 0;
  MPI_Allreduce(&ready, &all_ready, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  int rc = EXIT_USAGE;
  if (all_ready && (o.list || o.check)) {
    rc = EXIT_OK;
    if (rank == 0) {
      for (size_t i = 0; i < jobs.count; i++)
        if (o.list || !c.done[i])
          printf("%s %s\n", c.done[i] ? "done" : "todo", jobs.jobs[i].tag);
      if (o.check) {
        fprintf(stderr, "tunetrace-mpi: %s: %zu of %zu jobs of %s done\n", o.db,
                jobs.count - (size_t)c.todo, jobs.count, o.jobs);
        if (c.todo) rc = EXIT_FAILED;
      }
    }
  } else if (all_ready) {
    if (rank == 0) {
      fprintf(stderr, "tunetrace-mpi: %zu jobs in %s, %zu already in %s, %ld to run on %d "
              "rank%s\n", jobs.count, o.jobs, jobs.count - (size_t)c.todo, o.db, c.todo, size,
              size == 1 ? "" : "s");
      snprintf(c.scratch, sizeof c.scratch, "%s", scratch);
      c.t0 = tt_mpi_now();
      const char *rec = getenv("OMPI_MCA_orte_enable_recovery");
      if (size > 1 && getenv("OMPI_COMM_WORLD_SIZE") && !(rec && (!strcmp(rec, "1") ||
                                                           !strcmp(rec, "true"))))
        fprintf(stderr, "tunetrace-mpi: note: mpirun without --enable-recovery: a rank that "
                "dies ends the whole run (Open MPI stops every rank; their jobs in flight are "
                "lost); with it, only the dead rank's job is lost\n");
      if (o.max_jobs && o.max_jobs < c.todo) c.todo = o.max_jobs;
      rc = tt__coordinate(&c, size, scratch);
      /* sequences finished by earlier runs whose manifest is missing */
      for (size_t i = 0; i < jobs.count; i++)
        if (jobs.jobs[i].kind == TT_MPI_FRAMES && c.done[i] && !c.given[i]) {
          char m[4300];
          snprintf(m, sizeof m, "%s/manifest.json", jobs.jobs[i].out_dir);
          if (access(m, F_OK) != 0) tt__maybe_sequence(&c, i);
        }
      long left = 0;
      for (size_t i = 0; i < jobs.count; i++) left += !c.done[i];
      fprintf(stderr, "tunetrace-mpi: %s: %zu of %zu jobs done, %ld failed and %ld lost with "
              "their rank in this run%s\n",
              o.db, jobs.count - (size_t)left, jobs.count, c.failed, c.lost,
              left ? " (run the same command again to continue)" : "");
      if (rc == EXIT_OK && left && !o.max_jobs) rc = EXIT_FAILED;
    } else {
      rc = tt__work(&o, &jobs, rank, scratch);
    }
  }
  if (have_scratch) tt_mpi_remove_folder(scratch);
  tt_tunedb_close(c.db);
  free(c.done);
  free(c.given);
  tt_mpi_jobs_free(&jobs);
  if (g_skip_finalize) {  /* see REPLY_EXIT */
    fflush(NULL);
    _exit(rc);
  }
  MPI_Finalize();
  return rc;
}
