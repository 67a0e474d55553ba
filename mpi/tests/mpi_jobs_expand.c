/* The job list's expansion (mpi/jobs.c, no MPI needed): linear in the number of jobs (a
 * sequence of 100000 frames in chunks of 1 expands at once; it took a minute of CPU on every
 * rank), bounded (TT_MPI_MAX_JOBS: a list past it is refused before it is expanded, naming
 * the file and the item, so "range": "0:4294967295" is an error, not a run that never
 * ends), and every number range-checked before it is converted (1e300, -1e300 and a frame
 * past 4294967295 are errors naming the key, never undefined behaviour). A step that does
 * not finish fails through alarm() naming it. */
#include "../jobs.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "tt_test.h"

static const char *volatile g_step = "start";

static void on_alarm(int sig) {
  (void)sig;
  static const char msg[] = "mpi_jobs_expand: HUNG (no answer in 60 s) at: ";
  (void)!write(2, msg, sizeof msg - 1);
  (void)!write(2, (const char *)g_step, strlen((const char *)g_step));
  (void)!write(2, "\n", 1);
  _exit(1);
}

static char g_scene[4096];
static char g_err[4096];

/* Parses {"jobs": [ITEMS]} with the scene filled in for every %s. */
static int parse(const char *items, tt_mpi_jobs *jobs) {
  char text[8192];
  snprintf(text, sizeof text, items, g_scene, g_scene, g_scene);
  char list[9000];
  snprintf(list, sizeof list, "{\"jobs\": [%s]}", text);
  alarm(60);
  g_step = items;
  int rc = tt_mpi_jobs_parse(list, "jobs.json", jobs, g_err, sizeof g_err);
  alarm(0);
  return rc;
}

/* The list is refused with a message holding every needle. */
static void refused(const char *items, const char *const *needles) {
  tt_mpi_jobs jobs;
  int rc = parse(items, &jobs);
  CHECK_MSG(rc == -1, "accepted: %s", items);
  CHECK_MSG(jobs.count == 0 && jobs.jobs == NULL, "left %zu jobs", jobs.count);
  for (; *needles; needles++) CHECK_CONTAINS(g_err, *needles);
  if (rc == 0) tt_mpi_jobs_free(&jobs);
}

int main(void) {
  signal(SIGALRM, on_alarm);
  const char *root = getenv("TT_SOURCE_ROOT");
  snprintf(g_scene, sizeof g_scene, "%s/scenes/cornell-box/path.json", root ? root : ".");

  /* 100000 frames in chunks of 1: every one a job, in order */
  tt_mpi_jobs jobs;
  CHECK(parse("{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"0:99999\", \"chunk\": 1,"
              " \"out_dir\": \"seq\"}",
              &jobs) == 0);
  CHECK_MSG(jobs.count == TT_MPI_MAX_JOBS, "%zu jobs: %s", jobs.count, g_err);
  int ordered = 1;
  for (size_t i = 0; i < jobs.count; i++)
    ordered &= jobs.jobs[i].first == i && jobs.jobs[i].last == i && jobs.jobs[i].item == 0;
  CHECK(ordered);
  tt_mpi_jobs_free(&jobs);

  /* chunks that do not divide the range: the last one is short */
  CHECK(parse("{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"10:4294967295\","
              " \"chunk\": 1000000, \"out_dir\": \"far\"}",
              &jobs) == 0);
  CHECK_MSG(jobs.count == 4295, "%zu jobs: %s", jobs.count, g_err);
  if (jobs.count == 4295) {
    CHECK(jobs.jobs[0].first == 10 && jobs.jobs[0].last == 1000009);
    CHECK(jobs.jobs[4294].first == 4294000010u && jobs.jobs[4294].last == 4294967295u);
  }
  tt_mpi_jobs_free(&jobs);

  /* past the bound: refused before expansion, naming the file, the item, the count */
  refused("{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"0:100000\", \"chunk\": 1,"
          " \"out_dir\": \"seq\"}",
          (const char *[]){"jobs.json: jobs[0].range", "100001 jobs", "at most 100000",
                           "larger chunk", NULL});
  refused("{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"0:4294967295\","
          " \"out_dir\": \"seq\"}",
          (const char *[]){"jobs.json: jobs[0].range", "536870912 jobs", NULL});
  /* the bound counts the whole list: the second item takes it past */
  refused("{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"0:59999\", \"chunk\": 1,"
          " \"out_dir\": \"a\"}, {\"kind\": \"frames\", \"scene\": \"%s\","
          " \"range\": \"0:59999\", \"chunk\": 1, \"out_dir\": \"b\"}",
          (const char *[]){"jobs.json: jobs[1].range",
                           "60000 jobs (120000 with the items "
                           "before it)",
                           NULL});
  refused("{\"kind\": \"explore\", \"scene\": \"%s\", \"cameras\": [0, 1, 2, 3, 4, 5, 6, 7, 8,"
          " 9], \"samples\": 1, \"objectives\": [\"render\", \"build+render\"],"
          " \"seeds\": ["
          "0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24,25,"
          "26,27,28,29,30,31,32,33,34,35,36,37,38,39,40,41,42,43,44,45,46,47,48,49,50,51,52,53,"
          "54,55,56,57,58,59,60,61,62,63,64,65,66,67,68,69,70,71,72,73,74,75,76,77,78,79,80,81,"
          "82,83,84,85,86,87,88,89,90,91,92,93,94,95,96,97,98,99"
          "]}, "
          "{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"0:99999\", \"chunk\": 1,"
          " \"out_dir\": \"c\"}",
          (const char *[]){"jobs.json: jobs[1].range", "100000 jobs (102000 with the items", NULL});

  /* numbers out of range, refused before any cast */
  refused("{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"0:4294967296\","
          " \"out_dir\": \"seq\"}",
          (const char *[]){"jobs[0].range", "0..4294967295", NULL});
  refused("{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"0:99999999999999999999999\","
          " \"out_dir\": \"seq\"}",
          (const char *[]){"jobs[0].range", NULL});
  refused("{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"-1:3\", \"out_dir\": \"seq\"}",
          (const char *[]){"jobs[0].range", NULL});
  refused("{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"0:9\", \"chunk\": 1e300,"
          " \"out_dir\": \"seq\"}",
          (const char *[]){"jobs[0].chunk", "1..1000000", NULL});
  refused("{\"kind\": \"frames\", \"scene\": \"%s\", \"range\": \"0:9\", \"chunk\": -1e300,"
          " \"out_dir\": \"seq\"}",
          (const char *[]){"jobs[0].chunk", NULL});
  refused("{\"kind\": \"tune\", \"scene\": \"%s\", \"camera\": 1e300}",
          (const char *[]){"jobs[0].camera", "0..99", NULL});
  refused("{\"kind\": \"tune\", \"scene\": \"%s\", \"cameras\": [1, -1e300]}",
          (const char *[]){"jobs[0].cameras", "[1]", NULL});
  refused("{\"kind\": \"explore\", \"scene\": \"%s\", \"camera\": 1, \"samples\": 1e300}",
          (const char *[]){"jobs[0].samples", NULL});
  refused("{\"kind\": \"explore\", \"scene\": \"%s\", \"camera\": 1, \"samples\": 2,"
          " \"seeds\": [1, 9.5]}",
          (const char *[]){"jobs[0].seeds", "[1]", NULL});
  refused("{\"kind\": \"explore\", \"scene\": \"%s\", \"camera\": 1, \"samples\": 2,"
          " \"seed\": 1e19}",
          (const char *[]){"jobs[0].seed", NULL});

  /* a repeated job is still found (through the tag set), naming the first */
  refused("{\"kind\": \"tune\", \"scene\": \"%s\", \"cameras\": [3, 4]}, {\"kind\": \"tune\","
          " \"scene\": \"%s\", \"camera\": 4}",
          (const char *[]){"jobs[1]", "repeats a job of jobs[0]", NULL});
  CHECK(parse("{\"kind\": \"tune\", \"scene\": \"%s\", \"cameras\": [3, 4],"
              " \"objectives\": [\"render\", \"build+render\"]}",
              &jobs) == 0);
  CHECK(jobs.count == 4);
  tt_mpi_jobs_free(&jobs);
  return tt_test_finish("mpi_jobs_expand");
}
