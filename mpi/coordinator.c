/* tunetrace-mpi: rank 0 (see coordinator.h). */
#include "coordinator.h"
#include "frames.h"
#include "job_run.h"

#include <tunetrace/file.h>
#include <tunetrace/tunetrace.h>

#include <cjson/cJSON.h>
#include <mpi.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The next job to hand out, in list order; -1 when none is left, on a stop request, or once
 * --max-jobs were handed out. */
static long tt__next_job(tt_mpi_coord *c) {
  if (tt_mpi_stop || (c->o->max_jobs && c->handed >= c->o->max_jobs)) return -1;
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
static void tt__merge(tt_mpi_coord *c, long k, int rank, int ok, const char *path, const char *note,
                      double wall_s) {
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
    fprintf(stderr, "tunetrace-mpi: job %s (jobs[%zu]) FAILED on rank %d (exit %d):\n%s\n", j->tag,
            j->item, rank, cJSON_IsNumber(x) ? (int)x->valuedouble : -1,
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

/* rank 0's view of a worker */
enum { PEER_WORKING, PEER_WAITING, PEER_LOST }; /* WAITING: asked, no job left for it */
typedef struct tt_mpi_peer {
  int state;
  double seen;      /* the last message from it (monotonic s) */
  long job;         /* the job it runs (-1: none) */
  int job_lost;     /* its job was counted lost */
  MPI_Request recv; /* a result being received (MPI_REQUEST_NULL: none) */
  unsigned char *buf;
  int len;
  int64_t reply; /* the job number last sent to it (the buffer of that send) */
} tt_mpi_peer;

/* What rank 0 keeps while the run goes on. */
typedef struct tt__loop {
  tt_mpi_coord *c;
  int size;
  const char *scratch;
  tt_mpi_peer *peers; /* per rank (0 unused) */
  int active;         /* workers not yet told to stop, nor lost */
  tt_mpi_run own;     /* rank 0's own job */
  int own_running;
  double now, last_alive;
} tt__loop;

static void tt__reply(tt_mpi_peer *p, int rank, int64_t v) {
  p->reply = v;
  MPI_Request q;
  MPI_Isend(&p->reply, 1, MPI_INT64_T, rank, TAG_JOB, MPI_COMM_WORLD, &q);
  MPI_Request_free(&q);
}

/* A worker's result (or first request) has arrived: merges it, hands out the next job. */
static void tt__peer_result(tt__loop *l, int rank) {
  tt_mpi_coord *c = l->c;
  tt_mpi_peer *p = &l->peers[rank];
  int was_lost = p->state == PEER_LOST;
  if (was_lost) {
    fprintf(stderr,
            "tunetrace-mpi: rank %d answered again after being taken as lost; its "
            "result is taken, and it gets no new job\n",
            rank);
    if (p->job_lost) {
      c->finished--;
      c->lost--;
    }
  }
  if (p->len >= (int)sizeof(tt_mpi_result_head)) {
    tt_mpi_result_head h;
    memcpy(&h, p->buf, sizeof h);
    if (h.job >= 0) {
      if (tt_mpi_stop && h.exit_code != 0) c->finished++; /* interrupted: redone by a rerun */
      else tt__receive(c, rank, p->buf, p->len);
    }
  }
  free(p->buf);
  p->buf = NULL;
  p->job_lost = 0;
  int64_t next = was_lost ? -1 : tt__next_job(c);
  p->job = (long)next;
  if (next < 0) { /* answered when the run is over (tt__coordinate) */
    if (!was_lost) l->active--;
    p->state = PEER_WAITING;
    return;
  }
  tt__reply(p, rank, next);
}

/* Rank 0's own job: when none runs, starts the next one (a job that cannot start is merged
 * as failed). With no job left and every worker done, `*end` when each waiting rank asked
 * lately (a waiting rank that died must not be told to finalize). Returns 1 on progress. */
static int tt__own_start(tt__loop *l, int *end) {
  tt_mpi_coord *c = l->c;
  if (l->own_running) return 0;
  long k = tt__next_job(c);
  if (k < 0) {
    if (l->active != 0) return 0;
    int fresh = 1;
    for (int r = 1; r < l->size; r++)
      if (l->peers[r].state == PEER_WAITING && l->now - l->peers[r].seen > 3 * c->o->heartbeat)
        fresh = 0;
    *end = fresh;
    return 0;
  }
  if (tt_mpi_run_start(&l->own, c->o, l->scratch, c->jobs, k) == 0) {
    l->own_running = 1;
  } else {
    char *note = tt_mpi_run_note(&l->own, 0, &(int){0});
    tt__merge(c, k, 0, 0, NULL, note, 0);
    free(note);
  }
  return 1;
}

/* Rank 0's own job, when its process has ended: merged (an interrupted one is not a
 * failure: a rerun redoes it). Returns 1 on progress. */
static int tt__own_poll(tt__loop *l) {
  if (!l->own_running || !tt_mpi_child_poll(&l->own.child, 0)) return 0;
  tt_mpi_running_child = 0;
  int ok = 0;
  char *note = tt_mpi_run_note(&l->own, 0, &ok);
  if (tt_mpi_stop && !ok) l->c->finished++;
  else tt__merge(l->c, l->own.index, 0, ok, l->own.db, note, l->own.child.wall_s);
  free(note);
  l->own_running = 0;
  return 1;
}

/* Messages: heartbeats, and results (received without blocking: a sender that dies half-way
 * must not hang rank 0). Returns 1 on progress. */
static int tt__receive_messages(tt__loop *l) {
  int progressed = 0;
  for (int m = 0; m < 256; m++) {
    int flag = 0;
    MPI_Message msg;
    MPI_Status st;
    MPI_Improbe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &msg, &st);
    if (!flag) break;
    tt_mpi_peer *p = &l->peers[st.MPI_SOURCE];
    p->seen = l->now;
    int len = 0;
    MPI_Get_count(&st, MPI_BYTE, &len);
    if (st.MPI_TAG == TAG_RESULT && p->recv == MPI_REQUEST_NULL) {
      p->buf = malloc(len > 0 ? (size_t)len : 1);
      p->len = len;
      MPI_Imrecv(p->buf, len, MPI_BYTE, &msg, &p->recv);
    } else { /* a heartbeat (or a message out of turn): read and dropped */
      unsigned char *junk = malloc(len > 0 ? (size_t)len : 1);
      MPI_Mrecv(junk, len, MPI_BYTE, &msg, MPI_STATUS_IGNORE);
      free(junk);
    }
    progressed = 1;
  }
  return progressed;
}

/* A worker silent for --liveness seconds is taken as dead; its job is lost (a rerun redoes
 * it) and the others go on. */
static void tt__peer_silent(tt__loop *l, int r) {
  tt_mpi_coord *c = l->c;
  tt_mpi_peer *p = &l->peers[r];
  if (p->state == PEER_WORKING) l->active--;
  p->state = PEER_LOST;
  if (p->job >= 0) {
    const tt_mpi_job *j = &c->jobs->jobs[p->job];
    fprintf(stderr,
            "tunetrace-mpi: rank %d silent for %.0f s: taken as dead; its job "
            "%s (jobs[%zu]) is lost (the same command redoes it), the other ranks go "
            "on\n",
            r, l->now - p->seen, j->tag, j->item);
    p->job_lost = 1;
    c->finished++;
    c->lost++;
  } else {
    fprintf(stderr,
            "tunetrace-mpi: rank %d silent for %.0f s: taken as dead (it held "
            "no job)\n",
            r, l->now - p->seen);
  }
}

/* Every worker: a result received in full is merged (and the worker gets its next job), a
 * worker silent too long is taken as dead. Returns 1 on progress. */
static int tt__check_peers(tt__loop *l) {
  int progressed = 0;
  for (int r = 1; r < l->size; r++) {
    tt_mpi_peer *p = &l->peers[r];
    int done = 0;
    if (p->recv != MPI_REQUEST_NULL) MPI_Test(&p->recv, &done, MPI_STATUS_IGNORE);
    if (done) {
      p->seen = l->now;
      tt__peer_result(l, r);
      progressed = 1;
    } else if (p->state != PEER_LOST && l->now - p->seen > l->c->o->liveness) {
      tt__peer_silent(l, r);
      progressed = 1;
    }
  }
  return progressed;
}

/* A heartbeat to every worker not lost, every --liveness / 10 seconds. */
static void tt__heartbeats(tt__loop *l) {
  if (l->now - l->last_alive < l->c->o->heartbeat) return;
  for (int r = 1; r < l->size; r++)
    if (l->peers[r].state != PEER_LOST) tt_mpi_send_alive(r);
  l->last_alive = l->now;
}

/* The end of the run: every waiting rank is told how to end (without MPI_Finalize when a
 * rank was lost). Returns rank 0's exit code. */
static int tt__loop_end(tt__loop *l) {
  tt_mpi_coord *c = l->c;
  int lost = 0;
  for (int r = 1; r < l->size; r++) lost |= l->peers[r].state == PEER_LOST;
  tt_mpi_skip_finalize = lost;
  for (int r = 1; r < l->size; r++)
    if (l->peers[r].state == PEER_WAITING)
      tt__reply(&l->peers[r], r, lost ? REPLY_EXIT : REPLY_FINALIZE);
  if (lost)
    fprintf(stderr, "tunetrace-mpi: a rank was lost: the ranks end without MPI_Finalize (Open "
                    "MPI 4.1's would wait for the dead one)\n");
  /* receives still open belong to lost ranks: their buffers stay with MPI */
  free(l->peers);
  return tt_mpi_stop ? EXIT_INTERRUPTED : (c->failed || c->lost) ? EXIT_FAILED : EXIT_OK;
}

/* The run: rank 0's own jobs, the workers' results and requests, heartbeats, until no job is
 * left and every worker has asked for one. */
static int tt__coordinate(tt_mpi_coord *c, int size, const char *scratch) {
  tt__loop l = {.c = c, .size = size, .scratch = scratch, .active = size - 1};
  l.peers = calloc((size_t)size, sizeof *l.peers);
  l.now = l.last_alive = tt_mpi_now();
  for (int r = 1; r < size; r++) {
    l.peers[r].seen = l.now;
    l.peers[r].job = -1;
    l.peers[r].recv = MPI_REQUEST_NULL;
  }
  for (;;) {
    int end = 0;
    int progressed = tt__own_start(&l, &end);
    if (end) break;
    progressed |= tt__own_poll(&l);
    l.now = tt_mpi_now();
    progressed |= tt__receive_messages(&l);
    progressed |= tt__check_peers(&l);
    tt__heartbeats(&l);
    if (!progressed) usleep(2000);
  }
  return tt__loop_end(&l);
}

int tt_mpi_coord_open(tt_mpi_coord *c, const tt_mpi_opts *o, const tt_mpi_jobs *jobs) {
  memset(c, 0, sizeof *c);
  c->o = o;
  c->jobs = jobs;
  if (tt_tunedb_open(o->db, &c->db) != TT_OK) {
    fprintf(stderr, "tunetrace-mpi: --db: %s\n", tt_last_error());
    return -1;
  }
  c->done = calloc(jobs->count, 1);
  c->given = calloc(jobs->count, 1);
  for (size_t i = 0; i < jobs->count; i++) {
    int m = 0;
    if (tt_tunedb_merged(c->db, jobs->jobs[i].tag, &m) != TT_OK) {
      fprintf(stderr, "tunetrace-mpi: --db: %s\n", tt_last_error());
      return -1;
    }
    c->done[i] = (unsigned char)m;
    c->todo += !m;
  }
  return 0;
}

/* --list (every job, done or todo) or --check (the jobs todo; 1 while there are any). */
static int tt__list(const tt_mpi_coord *c) {
  const tt_mpi_jobs *jobs = c->jobs;
  for (size_t i = 0; i < jobs->count; i++)
    if (c->o->list || !c->done[i])
      printf("%s %s\n", c->done[i] ? "done" : "todo", jobs->jobs[i].tag);
  if (!c->o->check) return EXIT_OK;
  fprintf(stderr, "tunetrace-mpi: %s: %zu of %zu jobs of %s done\n", c->o->db,
          jobs->count - (size_t)c->todo, jobs->count, c->o->jobs);
  return c->todo ? EXIT_FAILED : EXIT_OK;
}

/* Without mpirun --enable-recovery a dying rank ends the whole run: said at the start. */
static void tt__recovery_note(int size) {
  const char *rec = getenv("OMPI_MCA_orte_enable_recovery");
  if (size > 1 && getenv("OMPI_COMM_WORLD_SIZE") &&
      !(rec && (!strcmp(rec, "1") || !strcmp(rec, "true"))))
    fprintf(stderr, "tunetrace-mpi: note: mpirun without --enable-recovery: a rank that "
                    "dies ends the whole run (Open MPI stops every rank; their jobs in flight are "
                    "lost); with it, only the dead rank's job is lost\n");
}

/* Sequences finished by earlier runs whose manifest is missing get it now. */
static void tt__old_sequences(tt_mpi_coord *c) {
  const tt_mpi_jobs *jobs = c->jobs;
  for (size_t i = 0; i < jobs->count; i++)
    if (jobs->jobs[i].kind == TT_MPI_FRAMES && c->done[i] && !c->given[i]) {
      char m[4300];
      snprintf(m, sizeof m, "%s/manifest.json", jobs->jobs[i].out_dir);
      if (access(m, F_OK) != 0) tt__maybe_sequence(c, i);
    }
}

int tt_mpi_coord_run(tt_mpi_coord *c, int size, const char *scratch) {
  const tt_mpi_opts *o = c->o;
  const tt_mpi_jobs *jobs = c->jobs;
  if (o->list || o->check) return tt__list(c);
  fprintf(stderr,
          "tunetrace-mpi: %zu jobs in %s, %zu already in %s, %ld to run on %d "
          "rank%s\n",
          jobs->count, o->jobs, jobs->count - (size_t)c->todo, o->db, c->todo, size,
          size == 1 ? "" : "s");
  snprintf(c->scratch, sizeof c->scratch, "%s", scratch);
  c->t0 = tt_mpi_now();
  tt__recovery_note(size);
  if (o->max_jobs && o->max_jobs < c->todo) c->todo = o->max_jobs;
  int rc = tt__coordinate(c, size, scratch);
  tt__old_sequences(c);
  long left = 0;
  for (size_t i = 0; i < jobs->count; i++) left += !c->done[i];
  fprintf(stderr,
          "tunetrace-mpi: %s: %zu of %zu jobs done, %ld failed and %ld lost with "
          "their rank in this run%s\n",
          o->db, jobs->count - (size_t)left, jobs->count, c->failed, c->lost,
          left ? " (run the same command again to continue)" : "");
  return rc == EXIT_OK && left && !o->max_jobs ? EXIT_FAILED : rc;
}

void tt_mpi_coord_close(tt_mpi_coord *c) {
  tt_tunedb_close(c->db);
  free(c->done);
  free(c->given);
}
