/* tunetrace-mpi: reading, checking and expanding the job list (see jobs.h). */
#include "jobs.h"

#include "option_table.h"

#include <tunetrace/file.h>
#include <tunetrace/tunetrace.h>

#include <tt_util/hash.h>
#include <tt_util/strings.h>

#include <cjson/cJSON.h>

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TT_MPI_CAMERAS 100 /* the host's path samples (--camera-index 0..99) */

typedef struct tt__ctx {
  const char *source;
  char *err;
  size_t n;
  tt_mpi_jobs *out;
  size_t cap;
  size_t *index;    /* open-addressing set of the jobs' tags: job index + 1, 0 = empty */
  size_t index_cap; /* a power of two, at least twice the job count */
} tt__ctx;

static int tt__fail(tt__ctx *c, size_t item, const char *key, const char *fmt, ...) {
  char what[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(what, sizeof what, fmt, ap);
  va_end(ap);
  if (item == (size_t)-1)
    snprintf(c->err, c->n, "%s: %s%s%s", c->source, key ? key : "", key ? ": " : "", what);
  else
    snprintf(c->err, c->n, "%s: jobs[%zu]%s%s: %s", c->source, item, key ? "." : "", key ? key : "",
             what);
  return -1;
}

static void tt__job_free(tt_mpi_job *j) {
  free(j->tag);
  free(j->scene);
  free(j->objective);
  free(j->out_dir);
  free(j->sequence);
  for (size_t i = 0; i < j->nargs; i++) free(j->args[i]);
  free(j->args);
}

void tt_mpi_jobs_free(tt_mpi_jobs *jobs) {
  if (!jobs) return;
  for (size_t i = 0; i < jobs->count; i++) tt__job_free(&jobs->jobs[i]);
  free(jobs->jobs);
  free(jobs->source);
  memset(jobs, 0, sizeof *jobs);
}

/* Appends a string array (checked) to args; -1 on a bad item. */
static int tt__add_args(tt__ctx *c, size_t item, const char *key, const cJSON *arr, char ***args,
                        size_t *n) {
  if (!arr) return 0;
  if (!cJSON_IsArray(arr))
    return tt__fail(c, item, key, "expected an array of host arguments (strings)");
  size_t k = 0;
  for (const cJSON *a = arr->child; a; a = a->next, k++) {
    if (!cJSON_IsString(a)) return tt__fail(c, item, key, "[%zu]: expected a string", k);
    char **grown = realloc(*args, (*n + 1) * sizeof **args);
    if (!grown) return tt__fail(c, item, key, "out of memory");
    *args = grown;
    (*args)[(*n)++] = tt__strdup(a->valuestring);
  }
  return 0;
}

/* The TT__MPI_* bit of a job kind, and its name. */
static unsigned tt__kind_bit(tt_mpi_kind kind) {
  return kind == TT_MPI_TUNE      ? TT__MPI_TUNE
         : kind == TT_MPI_EXPLORE ? TT__MPI_EXPLORE
                                  : TT__MPI_FRAMES;
}

static const char *tt__kind_name(tt_mpi_kind kind) {
  return kind == TT_MPI_TUNE ? "tune" : kind == TT_MPI_EXPLORE ? "explore" : "frames";
}

/* -1 if an argument is an option the driver sets for this kind (the host's option table
 * says which; "--out=x.exr" and "-o" are --out). */
static int tt__check_owned(tt__ctx *c, size_t item, tt_mpi_kind kind, char **args, size_t n) {
  for (size_t i = 0; i < n; i++) {
    const char *value;
    const tt__option *o = tt__option_of_arg(args[i], &value);
    if (!o) continue;
    int as_named = !strcmp(args[i], o->name);
    if (o->mpi & tt__kind_bit(kind))
      return tt__fail(c, item, "args", "%s%s%s%s is set by tunetrace-mpi for a %s job (%s)",
                      o->name, as_named ? "" : " (\"", as_named ? "" : args[i],
                      as_named ? "" : "\")", tt__kind_name(kind),
                      !strcmp(o->name, "--post")
                          ? "a post-filter's history would cross the frame ranges; render "
                            "the frames, then filter the whole sequence"
                          : "use the job's own keys");
    if (o->arg == TT__ARG_ONE && !value) i++; /* its value is not an option */
  }
  return 0;
}

/* 1 if `v` is a number that is an integer in lo..hi. The range is checked on the double
 * before any cast: 1e300, -1e300 or NaN never reach (long), whose result would be undefined. */
static int tt__int_in(const cJSON *v, long lo, long hi) {
  if (!cJSON_IsNumber(v)) return 0;
  double d = v->valuedouble;
  if (!(d >= (double)lo && d <= (double)hi)) return 0; /* NaN fails both */
  return d == (double)(long)d;
}

/* Reads an integer list key (`one` or `many`), into vals; -1 on error, else the count (0:
 * neither given). */
static int tt__int_list(tt__ctx *c, size_t item, const cJSON *o, const char *one, const char *many,
                        long lo, long hi, long *vals, int max) {
  const cJSON *a = cJSON_GetObjectItemCaseSensitive(o, one);
  const cJSON *b = strcmp(one, many) ? cJSON_GetObjectItemCaseSensitive(o, many) : NULL;
  if (a && b) return tt__fail(c, item, many, "give either %s or %s", one, many);
  if (a) {
    if (!tt__int_in(a, lo, hi))
      return tt__fail(c, item, one, "expected an integer in %ld..%ld", lo, hi);
    vals[0] = (long)a->valuedouble;
    return 1;
  }
  if (!b) return 0;
  if (!cJSON_IsArray(b) || !b->child)
    return tt__fail(c, item, many, "expected a non-empty array of integers in %ld..%ld", lo, hi);
  int k = 0;
  for (const cJSON *v = b->child; v; v = v->next, k++) {
    if (k >= max) return tt__fail(c, item, many, "more than %d values", max);
    if (!tt__int_in(v, lo, hi))
      return tt__fail(c, item, many, "[%d]: expected an integer in %ld..%ld", k, lo, hi);
    vals[k] = (long)v->valuedouble;
  }
  return k;
}

static int tt__str_list(tt__ctx *c, size_t item, const cJSON *o, const char *one, const char *many,
                        const char **vals, int max) {
  const cJSON *a = cJSON_GetObjectItemCaseSensitive(o, one);
  const cJSON *b = cJSON_GetObjectItemCaseSensitive(o, many);
  if (a && b) return tt__fail(c, item, many, "give either %s or %s", one, many);
  if (a) {
    if (!cJSON_IsString(a) || !a->valuestring[0])
      return tt__fail(c, item, one, "expected a non-empty string");
    vals[0] = a->valuestring;
    return 1;
  }
  if (!b) return 0;
  if (!cJSON_IsArray(b) || !b->child)
    return tt__fail(c, item, many, "expected a non-empty array of strings");
  int k = 0;
  for (const cJSON *v = b->child; v; v = v->next, k++) {
    if (k >= max) return tt__fail(c, item, many, "more than %d values", max);
    if (!cJSON_IsString(v) || !v->valuestring[0])
      return tt__fail(c, item, many, "[%d]: expected a non-empty string", k);
    vals[k] = v->valuestring;
  }
  return k;
}

/* 16 hex digits of the FNV-1a of the arguments (NUL-separated). */
static void tt__args_hash(char **args, size_t n, char out[17]) {
  uint64_t h = TT__FNV1A64_OFFSET;
  for (size_t i = 0; i < n; i++) h = tt__fnv1a64(h, args[i], strlen(args[i]) + 1);
  snprintf(out, 17, "%016llx", (unsigned long long)h);
}

/* The slot of `tag` in the tag set: where it is, or the empty slot where it goes. */
static size_t tt__slot(const tt__ctx *c, const char *tag) {
  size_t mask = c->index_cap - 1;
  size_t i = (size_t)tt__fnv1a64(TT__FNV1A64_OFFSET, tag, strlen(tag)) & mask;
  while (c->index[i] && strcmp(c->out->jobs[c->index[i] - 1].tag, tag)) i = (i + 1) & mask;
  return i;
}

/* Grows the tag set to hold `count` jobs at half load at most; -1 when out of memory. */
static int tt__index_reserve(tt__ctx *c, size_t count) {
  if (count * 2 <= c->index_cap) return 0;
  size_t cap = c->index_cap ? c->index_cap : 64;
  while (cap < count * 2) cap *= 2;
  size_t *old = c->index, old_cap = c->index_cap;
  c->index = calloc(cap, sizeof *c->index);
  if (!c->index) {
    c->index = old;
    return -1;
  }
  c->index_cap = cap;
  for (size_t i = 0; i < old_cap; i++)
    if (old[i]) c->index[tt__slot(c, c->out->jobs[old[i] - 1].tag)] = old[i];
  free(old);
  return 0;
}

/* -1 (with the message) if `more` jobs would take the list past TT_MPI_MAX_JOBS; checked
 * before an item is expanded, so that no range is ever walked further than the bound. */
static int tt__check_count(tt__ctx *c, size_t item, const char *key, uint64_t more,
                           const char *how) {
  uint64_t total = (uint64_t)c->out->count + more;
  if (total <= TT_MPI_MAX_JOBS) return 0;
  return tt__fail(c, item, key,
                  "%s makes %llu jobs (%llu with the items before it); a job "
                  "list holds at most %d: cut it into several lists%s",
                  how, (unsigned long long)more, (unsigned long long)total, TT_MPI_MAX_JOBS,
                  key && !strcmp(key, "range") ? ", or give a larger chunk" : "");
}

/* Appends one job (takes a copy of args). Repeated tags are found in the tag set: the
 * expansion is linear in the number of jobs. */
static int tt__push(tt__ctx *c, size_t item, const tt_mpi_job *proto, char **args, size_t n,
                    const char *tag) {
  tt_mpi_jobs *o = c->out;
  if (tt__index_reserve(c, o->count + 1)) return tt__fail(c, item, NULL, "out of memory");
  size_t slot = tt__slot(c, tag);
  if (c->index[slot]) {
    const tt_mpi_job *same = &o->jobs[c->index[slot] - 1];
    return tt__fail(c, item, NULL, "repeats a job of jobs[%zu] (%s)", same->item, tag);
  }
  if (o->count == c->cap) {
    size_t cap = c->cap ? c->cap * 2 : 16;
    tt_mpi_job *g = realloc(o->jobs, cap * sizeof *g);
    if (!g) return tt__fail(c, item, NULL, "out of memory");
    o->jobs = g;
    c->cap = cap;
  }
  tt_mpi_job *j = &o->jobs[o->count];
  *j = *proto;
  j->tag = tt__strdup(tag);
  j->scene = tt__strdup(proto->scene);
  j->objective = proto->objective ? tt__strdup(proto->objective) : NULL;
  j->out_dir = proto->out_dir ? tt__strdup(proto->out_dir) : NULL;
  j->sequence = proto->sequence ? tt__strdup(proto->sequence) : NULL;
  j->args = n ? malloc(n * sizeof *j->args) : NULL;
  j->nargs = n;
  int oom = !j->tag || !j->scene || (proto->objective && !j->objective) ||
            (proto->out_dir && !j->out_dir) || (proto->sequence && !j->sequence) || (n && !j->args);
  for (size_t i = 0; j->args && i < n; i++) oom |= !(j->args[i] = tt__strdup(args[i]));
  j->item = item;
  if (oom) {
    if (!j->args) j->nargs = 0;
    tt__job_free(j);
    return tt__fail(c, item, NULL, "out of memory");
  }
  o->count++;
  c->index[slot] = o->count;
  return 0;
}

/* Parses a frame number of a "range": decimal digits only, at most 4294967295 (the host's
 * frame numbers are 32-bit); *end is set after it. 0, or -1. */
static int tt__frame_number(const char *s, uint32_t *out, const char **end) {
  uint64_t v = 0;
  const char *p = s;
  if (*p < '0' || *p > '9') return -1;
  for (; *p >= '0' && *p <= '9'; p++) {
    v = v * 10 + (uint64_t)(*p - '0');
    if (v > UINT32_MAX) return -1;
  }
  *out = (uint32_t)v;
  *end = p;
  return 0;
}

static int tt__item(tt__ctx *c, size_t item, const cJSON *o, char **common, size_t ncommon) {
  static const char *const keys[] = {"kind",       "scene",   "camera", "cameras", "objective",
                                     "objectives", "samples", "seed",   "seeds",   "range",
                                     "chunk",      "out_dir", "args",   NULL};
  if (!cJSON_IsObject(o)) return tt__fail(c, item, NULL, "expected an object");
  for (const cJSON *k = o->child; k; k = k->next) {
    int known = 0;
    for (const char *const *p = keys; *p; p++) known |= !strcmp(k->string, *p);
    if (!known)
      return tt__fail(c, item, k->string,
                      "unknown key (known: kind, scene, camera(s), "
                      "objective(s), samples, seed(s), range, chunk, out_dir, args)");
  }
  const cJSON *kind = cJSON_GetObjectItemCaseSensitive(o, "kind");
  tt_mpi_job proto;
  memset(&proto, 0, sizeof proto);
  proto.camera = -1;
  if (!cJSON_IsString(kind) ||
      (strcmp(kind->valuestring, "tune") && strcmp(kind->valuestring, "explore") &&
       strcmp(kind->valuestring, "frames")))
    return tt__fail(c, item, "kind", "expected \"tune\", \"explore\" or \"frames\"");
  proto.kind = !strcmp(kind->valuestring, "tune")      ? TT_MPI_TUNE
               : !strcmp(kind->valuestring, "explore") ? TT_MPI_EXPLORE
                                                       : TT_MPI_FRAMES;
  const cJSON *scene = cJSON_GetObjectItemCaseSensitive(o, "scene");
  if (!cJSON_IsString(scene) || !scene->valuestring[0])
    return tt__fail(c, item, "scene", "expected the path of a scene file");
  if (tt_file_check_regular(scene->valuestring, "scene file") != TT_OK)
    return tt__fail(c, item, "scene", "%s", tt_last_error());
  proto.scene = scene->valuestring;
  char **args = NULL;
  size_t nargs = 0;
  int rc = -1;
  for (size_t i = 0; i < ncommon; i++) {
    char **g = realloc(args, (nargs + 1) * sizeof *args);
    if (!g) goto done;
    args = g;
    args[nargs++] = tt__strdup(common[i]);
  }
  if (tt__add_args(c, item, "args", cJSON_GetObjectItemCaseSensitive(o, "args"), &args, &nargs) ||
      tt__check_owned(c, item, proto.kind, args, nargs))
    goto done;
  char hash[17], tag[8192];
  tt__args_hash(args, nargs, hash);
  long cams[TT_MPI_CAMERAS], seeds[1024];
  const char *objs[16];
  if (proto.kind == TT_MPI_FRAMES) {
    for (const char *const *k =
             (const char *const[]){"camera", "cameras", "objective", "objectives", "samples",
                                   "seed", "seeds", NULL};
         *k; k++)
      if (cJSON_GetObjectItemCaseSensitive(o, *k)) {
        tt__fail(c, item, *k, "not a key of a frames job (range, chunk, out_dir, args)");
        goto done;
      }
    const cJSON *range = cJSON_GetObjectItemCaseSensitive(o, "range");
    uint32_t a = 0, b = 0;
    const char *p = cJSON_IsString(range) ? range->valuestring : "";
    if (!cJSON_IsString(range) || tt__frame_number(p, &a, &p) || *p++ != ':' ||
        tt__frame_number(p, &b, &p) || *p || a > b) {
      tt__fail(c, item, "range",
               "expected frames \"A:B\" with A <= B (A..B inclusive, "
               "integers in 0..4294967295), got %s",
               cJSON_IsString(range) ? range->valuestring : "no string");
      goto done;
    }
    long chunk[1] = {0};
    int nc = tt__int_list(c, item, o, "chunk", "chunk", 1, 1000000, chunk, 1);
    if (nc < 0) goto done;
    if (nc == 0) chunk[0] = 8;
    const cJSON *dir = cJSON_GetObjectItemCaseSensitive(o, "out_dir");
    if (!cJSON_IsString(dir) || !dir->valuestring[0]) {
      tt__fail(c, item, "out_dir", "expected the sequence's output folder (one for all ranks)");
      goto done;
    }
    for (size_t i = 0; i < c->out->count; i++)
      if (c->out->jobs[i].kind == TT_MPI_FRAMES &&
          !strcmp(c->out->jobs[i].out_dir, dir->valuestring)) {
        tt__fail(c, item, "out_dir",
                 "%s is the folder of jobs[%zu] too (one sequence per "
                 "folder: each has one manifest)",
                 dir->valuestring, c->out->jobs[i].item);
        goto done;
      }
    char seq[8192];
    snprintf(seq, sizeof seq, "sequence:%s:%u-%u:%s", dir->valuestring, a, b, hash);
    proto.out_dir = dir->valuestring;
    proto.sequence = seq;
    char how[128];
    snprintf(how, sizeof how, "%s in chunks of %ld", range->valuestring, chunk[0]);
    if (tt__check_count(c, item, "range", ((uint64_t)b - a) / (uint64_t)chunk[0] + 1, how))
      goto done;
    for (uint64_t f = a; f <= b; f += (uint64_t)chunk[0]) {
      proto.first = (uint32_t)f;
      proto.last = (uint32_t)(f + (uint64_t)chunk[0] - 1 < b ? f + (uint64_t)chunk[0] - 1 : b);
      snprintf(tag, sizeof tag, "frames:%s:%u-%u:%s", dir->valuestring, proto.first, proto.last,
               hash);
      if (tt__push(c, item, &proto, args, nargs, tag)) goto done;
    }
    rc = 0;
    goto done;
  }
  for (const char *const *k = (const char *const[]){"range", "chunk", "out_dir", NULL}; *k; k++)
    if (cJSON_GetObjectItemCaseSensitive(o, *k)) {
      tt__fail(c, item, *k, "a key of frames jobs only");
      goto done;
    }
  int ncam =
      tt__int_list(c, item, o, "camera", "cameras", 0, TT_MPI_CAMERAS - 1, cams, TT_MPI_CAMERAS);
  if (ncam < 0) goto done;
  if (ncam == 0) {
    tt__fail(c, item, "camera", "expected camera (0..99, the scene's path sample) or cameras");
    goto done;
  }
  int nobj = tt__str_list(c, item, o, "objective", "objectives", objs, 16);
  if (nobj < 0) goto done;
  for (int i = 0; i < nobj; i++) {
    tt_objective ob;
    if (tt_objective_parse(objs[i], &ob) != TT_OK) {
      tt__fail(c, item,
               nobj == 1 && cJSON_GetObjectItemCaseSensitive(o, "objective") ? "objective"
                                                                             : "objectives",
               "%s", tt_last_error());
      goto done;
    }
  }
  if (nobj == 0) objs[nobj++] = NULL;
  int nseed = 1;
  seeds[0] = 0;
  if (proto.kind == TT_MPI_EXPLORE) {
    long samples[1];
    int ns = tt__int_list(c, item, o, "samples", "samples", 1, 1000000, samples, 1);
    if (ns < 0) goto done;
    if (ns == 0) {
      tt__fail(c, item, "samples", "expected the number of random configurations (>= 1)");
      goto done;
    }
    proto.samples = (uint32_t)samples[0];
    nseed = tt__int_list(c, item, o, "seed", "seeds", 0, 2147483647L, seeds, 1024);
    if (nseed < 0) goto done;
    proto.has_seed = nseed > 0;
    if (nseed == 0) nseed = 1;
  } else {
    for (const char *const *k = (const char *const[]){"samples", "seed", "seeds", NULL}; *k; k++)
      if (cJSON_GetObjectItemCaseSensitive(o, *k)) {
        tt__fail(c, item, *k, "a key of explore jobs only (a tune job's seed goes in args)");
        goto done;
      }
  }
  char how[128];
  snprintf(how, sizeof how, "%d camera%s x %d objective%s x %d seed%s", ncam, ncam == 1 ? "" : "s",
           nobj, nobj == 1 ? "" : "s", nseed, nseed == 1 ? "" : "s");
  if (tt__check_count(c, item, NULL, (uint64_t)ncam * (uint64_t)nobj * (uint64_t)nseed, how))
    goto done;
  for (int ci = 0; ci < ncam; ci++)
    for (int oi = 0; oi < nobj; oi++)
      for (int si = 0; si < nseed; si++) {
        proto.camera = (int)cams[ci];
        proto.objective = (char *)objs[oi];
        proto.seed = (uint64_t)seeds[si];
        if (proto.kind == TT_MPI_TUNE)
          snprintf(tag, sizeof tag, "tune:%s:%d:%s:%s", proto.scene, proto.camera,
                   objs[oi] ? objs[oi] : "default", hash);
        else
          snprintf(tag, sizeof tag, "explore:%s:%d:%s:%u:%s%llu:%s", proto.scene, proto.camera,
                   objs[oi] ? objs[oi] : "default", proto.samples, proto.has_seed ? "seed" : "",
                   (unsigned long long)proto.seed, hash);
        if (tt__push(c, item, &proto, args, nargs, tag)) goto done;
      }
  rc = 0;
done:
  for (size_t i = 0; i < nargs; i++) free(args[i]);
  free(args);
  return rc;
}

int tt_mpi_jobs_parse(const char *text, const char *source, tt_mpi_jobs *out, char *err, size_t n) {
  memset(out, 0, sizeof *out);
  tt__ctx c = {source, err, n, out, 0, NULL, 0};
  const char *end = NULL;
  cJSON *root = cJSON_ParseWithOpts(text, &end, 1);
  if (!root) {
    size_t at = end ? (size_t)(end - text) : 0, line = 1, col = 1;
    for (size_t i = 0; i < at && text[i]; i++) {
      if (text[i] == '\n') {
        line++;
        col = 1;
      } else col++;
    }
    tt__fail(&c, (size_t)-1, NULL, "not valid JSON (line %zu, column %zu)", line, col);
    return -1;
  }
  int rc = -1;
  char **common = NULL;
  size_t ncommon = 0;
  if (!cJSON_IsObject(root)) {
    tt__fail(&c, (size_t)-1, NULL, "expected an object {\"host_args\": [...], \"jobs\": [...]}");
    goto done;
  }
  for (const cJSON *k = root->child; k; k = k->next)
    if (strcmp(k->string, "jobs") && strcmp(k->string, "host_args")) {
      tt__fail(&c, (size_t)-1, k->string, "unknown key (known: host_args, jobs)");
      goto done;
    }
  if (tt__add_args(&c, (size_t)-1, "host_args", cJSON_GetObjectItemCaseSensitive(root, "host_args"),
                   &common, &ncommon))
    goto done;
  const cJSON *jobs = cJSON_GetObjectItemCaseSensitive(root, "jobs");
  if (!cJSON_IsArray(jobs) || !jobs->child) {
    tt__fail(&c, (size_t)-1, "jobs", "expected a non-empty array of jobs");
    goto done;
  }
  size_t i = 0;
  for (const cJSON *j = jobs->child; j; j = j->next, i++)
    if (tt__item(&c, i, j, common, ncommon)) goto done;
  out->source = tt__strdup(source);
  rc = 0;
done:
  for (size_t k = 0; k < ncommon; k++) free(common[k]);
  free(common);
  free(c.index);
  cJSON_Delete(root);
  if (rc) tt_mpi_jobs_free(out);
  return rc;
}

char **tt_mpi_job_argv(const tt_mpi_job *job, const char *host, const char *db, const char *stats,
                       const char *dir) {
  size_t cap = job->nargs + 24, n = 0;
  char **v = calloc(cap, sizeof *v);
  if (!v) return NULL;
  char num[64];
#define TT__ADD(s) (v[n++] = tt__strdup(s))
  TT__ADD(host);
  TT__ADD("--quiet");
  for (size_t i = 0; i < job->nargs; i++) TT__ADD(job->args[i]);
  if (job->kind == TT_MPI_FRAMES) {
    snprintf(num, sizeof num, "%u:%u", job->first, job->last);
    TT__ADD("--sequence");
    TT__ADD(num);
    TT__ADD("--out-dir");
    TT__ADD(dir);
  } else {
    snprintf(num, sizeof num, "%d", job->camera);
    TT__ADD("--camera-index");
    TT__ADD(num);
    if (job->objective) {
      TT__ADD("--objective");
      TT__ADD(job->objective);
    }
    if (job->kind == TT_MPI_EXPLORE) {
      snprintf(num, sizeof num, "%u", job->samples);
      TT__ADD("--explore");
      TT__ADD(num);
      if (job->has_seed) {
        snprintf(num, sizeof num, "%llu", (unsigned long long)job->seed);
        TT__ADD("--seed");
        TT__ADD(num);
      }
    }
    TT__ADD("--db");
    TT__ADD(db);
    TT__ADD("--stats");
    TT__ADD(stats);
    /* the image of a tuning run's last pass: of no use to the set, kept out of the way */
    char img[4200];
    snprintf(img, sizeof img, "%s.exr", stats);
    TT__ADD("--out");
    TT__ADD(img);
  }
  TT__ADD(job->scene);
#undef TT__ADD
  v[n] = NULL;
  return v;
}

void tt_mpi_argv_free(char **argv) {
  if (!argv) return;
  for (char **p = argv; *p; p++) free(*p);
  free(argv);
}

char *tt_mpi_job_json(const tt_mpi_job *job) {
  cJSON *o = cJSON_CreateObject();
  static const char *const kinds[] = {"tune", "explore", "frames"};
  cJSON_AddStringToObject(o, "kind", kinds[job->kind]);
  cJSON_AddStringToObject(o, "tag", job->tag);
  cJSON_AddStringToObject(o, "scene", job->scene);
  if (job->kind == TT_MPI_FRAMES) {
    char r[64];
    snprintf(r, sizeof r, "%u:%u", job->first, job->last);
    cJSON_AddStringToObject(o, "range", r);
    cJSON_AddStringToObject(o, "out_dir", job->out_dir);
    cJSON_AddStringToObject(o, "sequence", job->sequence);
  } else {
    cJSON_AddNumberToObject(o, "camera", job->camera);
    if (job->objective) cJSON_AddStringToObject(o, "objective", job->objective);
    if (job->kind == TT_MPI_EXPLORE) {
      cJSON_AddNumberToObject(o, "samples", job->samples);
      if (job->has_seed) cJSON_AddNumberToObject(o, "seed", (double)job->seed);
    }
  }
  cJSON *args = cJSON_AddArrayToObject(o, "args");
  for (size_t i = 0; i < job->nargs; i++)
    cJSON_AddItemToArray(args, cJSON_CreateString(job->args[i]));
  char *s = cJSON_PrintUnformatted(o);
  cJSON_Delete(o);
  return s;
}
