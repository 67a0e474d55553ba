/* tunetrace-mpi: frame ranges of a sequence (see frames.h). */
#include "frames.h"

#include "child.h"

#include <tunetrace/file.h>
#include <tunetrace/tunetrace.h>

#include <cjson/cJSON.h>

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define TT__WORK ".tunetrace-mpi"

static int tt__mkdir(const char *path, char *err, size_t n) {
  if (mkdir(path, 0777) == 0 || errno == EEXIST) {
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) return 0;
    errno = ENOTDIR;
  }
  snprintf(err, n, "cannot create the folder %s: %s", path, strerror(errno));
  return -1;
}

/* mkdir -p */
static int tt__mkdirs(const char *path, char *err, size_t n) {
  char buf[4300];
  snprintf(buf, sizeof buf, "%s", path);
  for (char *p = buf + 1; *p; p++)
    if (*p == '/') {
      *p = 0;
      if (mkdir(buf, 0777) != 0 && errno != EEXIST) {
        snprintf(err, n, "cannot create the folder %s: %s", buf, strerror(errno));
        return -1;
      }
      *p = '/';
    }
  return tt__mkdir(buf, err, n);
}

static void tt__range_paths(const tt_mpi_job *job, char *dir, size_t dn, char *json, size_t jn) {
  if (dir) snprintf(dir, dn, "%s/" TT__WORK "/%u-%u", job->out_dir, job->first, job->last);
  if (json) snprintf(json, jn, "%s/" TT__WORK "/%u-%u.json", job->out_dir, job->first, job->last);
}

int tt_mpi_frames_prepare(const tt_mpi_job *job, char *dir, size_t dn, char *err, size_t n) {
  char work[4200];
  snprintf(work, sizeof work, "%s/" TT__WORK, job->out_dir);
  if (tt__mkdirs(work, err, n)) return -1;
  tt__range_paths(job, dir, dn, NULL, 0);
  tt_mpi_remove_folder(dir); /* what a killed run of this range left */
  return tt__mkdir(dir, err, n);
}

int tt_mpi_frames_finish(const tt_mpi_job *job, const char *dir, char **manifest, char *err,
                         size_t n) {
  char path[8192], dst[8192], json[4200];
  *manifest = NULL;
  snprintf(path, sizeof path, "%s/manifest.json", dir);
  size_t size = 0;
  char *text = NULL;
  if (tt_file_read(path, "sequence manifest", 0, &text, &size) != TT_OK) {
    snprintf(err, n, "%s", tt_last_error());
    return -1;
  }
  DIR *d = opendir(dir);
  if (!d) {
    snprintf(err, n, "cannot read the folder %s: %s", dir, strerror(errno));
    tt_free(text);
    return -1;
  }
  struct dirent *e;
  int rc = 0;
  while ((e = readdir(d)) && !rc) {
    if (e->d_name[0] == '.' || !strcmp(e->d_name, "manifest.json")) continue;
    snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
    snprintf(dst, sizeof dst, "%s/%s", job->out_dir, e->d_name);
    if (rename(path, dst) != 0) {
      snprintf(err, n, "cannot move %s to %s: %s", path, dst, strerror(errno));
      rc = -1;
    }
  }
  closedir(d);
  tt__range_paths(job, NULL, 0, json, sizeof json);
  if (!rc && tt_file_write_atomic(json, text, size) != TT_OK) {
    snprintf(err, n, "%s", tt_last_error());
    rc = -1;
  }
  if (!rc) {
    tt_mpi_remove_folder(dir);
    *manifest = malloc(size + 1);
    if (*manifest) memcpy(*manifest, text, size + 1);
  }
  tt_free(text);
  return rc;
}

int tt_mpi_sequence_write(const tt_mpi_jobs *jobs, size_t first, char *err, size_t n) {
  const tt_mpi_job *j0 = &jobs->jobs[first];
  cJSON *merged = NULL, *frames = NULL;
  int rc = 0;
  for (size_t i = first; i < jobs->count && !rc; i++) {
    const tt_mpi_job *j = &jobs->jobs[i];
    if (j->kind != TT_MPI_FRAMES || strcmp(j->sequence, j0->sequence)) continue;
    char json[4200];
    tt__range_paths(j, NULL, 0, json, sizeof json);
    char *text = NULL;
    size_t size = 0;
    if (tt_file_read(json, "range manifest", 0, &text, &size) != TT_OK) {
      snprintf(err, n, "%s", tt_last_error());
      rc = -1;
      break;
    }
    cJSON *m = cJSON_Parse(text);
    tt_free(text);
    cJSON *fr = m ? cJSON_DetachItemFromObjectCaseSensitive(m, "frames") : NULL;
    if (!cJSON_IsArray(fr)) {
      snprintf(err, n, "%s: expected a host sequence manifest with \"frames\"", json);
      cJSON_Delete(fr);
      cJSON_Delete(m);
      rc = -1;
      break;
    }
    if (!merged) {
      merged = m;
      frames = cJSON_AddArrayToObject(merged, "frames");
    } else {
      cJSON_Delete(m);
    }
    while (fr->child) {
      cJSON *f = cJSON_DetachItemViaPointer(fr, fr->child);
      const cJSON *idx = cJSON_GetObjectItemCaseSensitive(f, "index");
      cJSON_ReplaceItemInObjectCaseSensitive(
          f, "reset", cJSON_CreateBool(cJSON_IsNumber(idx) && idx->valuedouble == j0->first));
      cJSON_AddItemToArray(frames, f);
    }
    cJSON_Delete(fr);
  }
  if (!rc && merged) {
    char path[4200];
    snprintf(path, sizeof path, "%s/manifest.json", j0->out_dir);
    char *text = cJSON_Print(merged);
    size_t len = strlen(text);
    char *withnl = malloc(len + 2);
    memcpy(withnl, text, len);
    withnl[len] = '\n';
    withnl[len + 1] = 0;
    free(text);
    if (tt_file_write_atomic(path, withnl, len + 1) != TT_OK) {
      snprintf(err, n, "%s", tt_last_error());
      rc = -1;
    }
    free(withnl);
  }
  cJSON_Delete(merged);
  return rc;
}
