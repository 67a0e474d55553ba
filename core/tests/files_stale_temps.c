/* A killed write leaves its temporary ".NAME.tmp-NNNNNN"; the next write of the same output
 * removes it (its writer is gone: its lock is free, and it is older than a minute), and
 * never a file that is not one of ours: a temporary a live writer holds (even an old one),
 * a fresh unlocked one (a writer between create and lock), another output's temporaries,
 * names that only look alike. The live writer then commits as if nothing happened, and a
 * stale temporary past a gap of freed numbers is found too. */
#include <tunetrace/tunetrace.h>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "tt_test.h"

static char g_dir[] = "/tmp/tt_files_stale_tempsXXXXXX";

/* Creates DIR/name with `text`, modified `age` seconds ago. */
static void make(const char *name, const char *text, int age) {
  char path[600];
  snprintf(path, sizeof path, "%s/%s", g_dir, name);
  FILE *f = fopen(path, "w");
  CHECK(f != NULL);
  if (!f) return;
  fputs(text, f);
  fclose(f);
  struct timespec t[2];
  clock_gettime(CLOCK_REALTIME, &t[0]);
  t[0].tv_sec -= age;
  t[1] = t[0];
  CHECK(utimensat(AT_FDCWD, path, t, 0) == 0);
}

static int exists(const char *name) {
  char path[600];
  snprintf(path, sizeof path, "%s/%s", g_dir, name);
  struct stat st;
  return lstat(path, &st) == 0;
}

/* The temporaries of `base` in the folder (names starting ".BASE.tmp-"), and the first. */
static int temps_of(const char *base, char *first, size_t n) {
  char prefix[256];
  snprintf(prefix, sizeof prefix, ".%s.tmp-", base);
  DIR *d = opendir(g_dir);
  int count = 0;
  struct dirent *e;
  while (d && (e = readdir(d)))
    if (!strncmp(e->d_name, prefix, strlen(prefix))) {
      if (!count++ && first) snprintf(first, n, "%s", e->d_name);
    }
  if (d) closedir(d);
  return count;
}

static void age_file(const char *name, int age) {
  char path[600];
  snprintf(path, sizeof path, "%s/%s", g_dir, name);
  struct timespec t[2];
  clock_gettime(CLOCK_REALTIME, &t[0]);
  t[0].tv_sec -= age;
  t[1] = t[0];
  CHECK(utimensat(AT_FDCWD, path, t, 0) == 0);
}

int main(void) {
  if (!mkdtemp(g_dir)) return 1;
  char out[600], text[64];
  snprintf(out, sizeof out, "%s/frame.exr", g_dir);

  /* a write killed after it created its temporary (SIGKILL: no cleanup runs) */
  pid_t pid = fork();
  if (pid == 0) {
    tt_atomic_file *f;
    if (tt_atomic_file_open(out, &f) != TT_OK) _exit(3);
    fputs("half a frame", tt_atomic_file_stream(f));
    fflush(tt_atomic_file_stream(f));
    raise(SIGKILL);
    _exit(4);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  char killed[256] = "";
  CHECK(temps_of("frame.exr", killed, sizeof killed) == 1);

  /* a live writer of the same output: its open leaves the killed write's temporary (fresh) */
  tt_atomic_file *live = NULL;
  CHECK(tt_atomic_file_open(out, &live) == TT_OK);
  fputs("the live writer", tt_atomic_file_stream(live));
  fflush(tt_atomic_file_stream(live));
  CHECK(exists(killed));
  char live_name[256] = "";
  DIR *d = opendir(g_dir);
  struct dirent *e;
  while (d && (e = readdir(d)))
    if (!strncmp(e->d_name, ".frame.exr.tmp-", 15) && strcmp(e->d_name, killed))
      snprintf(live_name, sizeof live_name, "%s", e->d_name);
  if (d) closedir(d);
  CHECK(live_name[0] != '\0');
  /* both made an hour old: only the lock tells them apart */
  age_file(killed, 3600);
  if (live_name[0]) age_file(live_name, 3600);

  /* look-alikes that are not ours, old and unlocked: they stay */
  make(".frame.exr.tmp-12345", "5 digits", 3600);
  make(".frame.exr.tmp-1234567", "7 digits", 3600);
  make(".frame.exr.tmp-ABCDEF", "upper case", 3600);
  make(".frame.exr.tmp-abcdef.bak", "suffix", 3600);
  make(".other.exr.tmp-abcdef", "another output's", 3600);
  make("frame.exr.tmp-abcdef", "no dot", 3600);
  /* ours but fresh and unlocked (a writer between its create and its lock): stays */
  make(".frame.exr.tmp-000002", "fresh", 0);

  /* the next write of the output */
  CHECK(tt_file_write_atomic(out, "frame 2", 7) == TT_OK);
  CHECK_MSG(!exists(killed), "the killed write's temporary %s is still there", killed);
  CHECK(exists(".frame.exr.tmp-12345") && exists(".frame.exr.tmp-1234567") &&
        exists(".frame.exr.tmp-ABCDEF") && exists(".frame.exr.tmp-abcdef.bak") &&
        exists(".other.exr.tmp-abcdef") && exists("frame.exr.tmp-abcdef"));
  CHECK(exists(".frame.exr.tmp-000002"));
  CHECK_MSG(live_name[0] && exists(live_name), "the live writer's temporary %s was removed",
            live_name);
  size_t n = 0;
  char *data = NULL;
  CHECK(tt_file_read(out, NULL, 0, &data, &n) == TT_OK && n == 7 && !memcmp(data, "frame 2", 7));
  tt_free(data);

  /* the live writer commits its content over the output */
  CHECK(tt_atomic_file_commit(live) == TT_OK);
  CHECK(tt_file_read(out, NULL, 0, &data, &n) == TT_OK && n == 15 &&
        !memcmp(data, "the live writer", 15));
  tt_free(data);
  CHECK(!exists(live_name));

  /* the fresh one, once old, goes with the next write; the look-alikes stay */
  age_file(".frame.exr.tmp-000002", 120);
  CHECK(tt_file_write_atomic(out, "frame 3", 7) == TT_OK);
  CHECK(!exists(".frame.exr.tmp-000002"));
  CHECK(temps_of("frame.exr", NULL, 0) == 4); /* 12345, 1234567, ABCDEF, abcdef.bak */
  snprintf(text, sizeof text, "%d", temps_of("other.exr", NULL, 0));
  CHECK_MSG(!strcmp(text, "1"), "another output's temporaries: %s", text);

  /* numbers freed by finished writers leave gaps: a stale one past a few is still found */
  make(".frame.exr.tmp-000005", "stale past a gap", 3600);
  CHECK(tt_file_write_atomic(out, "frame 4", 7) == TT_OK);
  CHECK(!exists(".frame.exr.tmp-000005"));
  CHECK(temps_of("frame.exr", NULL, 0) == 4);

  char cmd[700];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
  (void)!system(cmd);
  return tt_test_finish("files_stale_temps");
}
