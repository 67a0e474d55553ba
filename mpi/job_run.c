/* tunetrace-mpi: one job run by this rank (see job_run.h). */
#include "job_run.h"
#include "frames.h"

#include <tunetrace/file.h>
#include <tunetrace/tunedb.h>
#include <tunetrace/tunetrace.h>

#include <cjson/cJSON.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int tt_mpi_run_start(tt_mpi_run *r, const tt_mpi_opts *o, const char *scratch,
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
  tt_mpi_running_child = r->child.pid;
  return rc;
}

/* A frame range's result: its frames moved into the sequence's folder, its manifest in
 * the note. 0, or -1 (message in r->err). */
static int tt__note_frames(tt_mpi_run *r, cJSON *o) {
  char *manifest = NULL;
  if (tt_mpi_frames_finish(r->job, r->dir, &manifest, r->err, sizeof r->err)) return -1;
  cJSON_AddItemToObject(o, "manifest", cJSON_Parse(manifest));
  free(manifest);
  return 0;
}

/* A tuning job's result: its --stats record in the note, and its database closed cleanly
 * (WAL checkpointed into the one file that travels). 0, or -1 (message in r->err). */
static int tt__note_tuning(tt_mpi_run *r, cJSON *o) {
  char *text = NULL;
  size_t size = 0;
  if (tt_file_read(r->stats, "stats", 0, &text, &size) == TT_OK) {
    cJSON *st = cJSON_Parse(text);
    if (st) cJSON_AddItemToObject(o, "stats", st);
    tt_free(text);
  }
  tt_tunedb *db = NULL;
  int rc = 0;
  if (tt_tunedb_open(r->db, &db) != TT_OK) {
    snprintf(r->err, sizeof r->err, "%s", tt_last_error());
    rc = -1;
  }
  tt_tunedb_close(db);
  return rc;
}

char *tt_mpi_run_note(tt_mpi_run *r, int rank, int *ok) {
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
  if (*ok && (r->job->kind == TT_MPI_FRAMES ? tt__note_frames(r, o) : tt__note_tuning(r, o)))
    *ok = 0;
  if (!*ok) {
    char tail[1500];
    tt_mpi_file_tail(r->log, tail, sizeof tail);
    cJSON_AddStringToObject(o, "error", r->err[0] ? r->err : tail);
  }
  char *s = cJSON_PrintUnformatted(o);
  cJSON_Delete(o);
  return s;
}

unsigned char *tt_mpi_run_pack(const tt_mpi_run *r, int ok, const char *note, int *len) {
  char *db = NULL;
  size_t dbn = 0;
  if (ok && r->job->kind != TT_MPI_FRAMES &&
      tt_file_read(r->db, "job database", 0, &db, &dbn) != TT_OK) {
    ok = 0;
    dbn = 0;
  }
  tt_mpi_result_head h = {r->index,        ok ? 0 : (r->child.exit_code ? r->child.exit_code : 1),
                          (int64_t)dbn,    (int64_t)strlen(note),
                          r->child.wall_s, r->child.cpu_s};
  size_t total = sizeof h + dbn + strlen(note);
  unsigned char *m = malloc(total);
  memcpy(m, &h, sizeof h);
  if (dbn) memcpy(m + sizeof h, db, dbn);
  memcpy(m + sizeof h + dbn, note, strlen(note));
  tt_free(db);
  *len = (int)total;
  return m;
}
