/* host: progress bar with ETA on a TTY, a line every 10 s otherwise, the estimate of long
 * work said once its first step has ended, and a log that does not tear the bar. Progress
 * and log are passed to plugins through the host services table. */
#include "host.h"

#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static pthread_mutex_t tt__lock = PTHREAD_MUTEX_INITIALIZER;
static int tt__quiet;
static int tt__tty;
static int tt__bar_visible; /* a partial bar line is on screen */
static char tt__task[64];
static uint64_t tt__task_start_ns;
static uint64_t tt__last_draw_ns; /* the bar's last redraw, or the last logged line */
static int tt__estimated;         /* the task's estimate was said (after its first step) */
static tt_host tt__host;

#define TT__LOG_EVERY_NS 10000000000ull /* not a terminal: one progress line per 10 s */
#define TT__LONG_WORK_S 60.0            /* an estimate at least this long is said once */

static uint64_t tt__now(void) { return tt_default_host()->clock_ns(); }
static void tt__host_log(tt_log_level level, const char *plugin, const char *fmt, ...);

/* Formats seconds as "12.3s", "4m05s" or "1h02m"; "?" while unknown. */
static void tt__fmt_time(double s, char *buf, size_t n) {
  if (s < 0 || s != s) snprintf(buf, n, "?");
  else if (s < 60) snprintf(buf, n, "%.1fs", s);
  else if (s < 3600) snprintf(buf, n, "%dm%02ds", (int)(s / 60), (int)s % 60);
  else snprintf(buf, n, "%dh%02dm", (int)(s / 3600), (int)(s / 60) % 60);
}

/* How a user shortens each task, said with a long estimate. */
static const char *tt__shorten(const char *task) {
  static const struct {
    const char *task, *how;
  } hints[] = {
      {"render", "--spp or --time to shorten"},
      {"tuning", "--iterations to shorten"},
      {"explore", "a smaller --explore N to shorten"},
      {"hybrid", "--camera-index A:B or --iterations to shorten"},
      {"sequence", "fewer frames or --spp to shorten"},
  };
  for (size_t k = 0; k < sizeof hints / sizeof hints[0]; k++)
    if (!strcmp(task, hints[k].task)) return hints[k].how;
  return NULL;
}

/* Says a long task's estimate once, when its first step has ended: "render: about 48 h;
 * --spp or --time to shorten". Called without the lock (the log takes it). */
static void tt__say_estimate(const char *task, double eta) {
  const char *how = tt__shorten(task);
  double unit = eta >= 7200 ? 3600 : eta >= 120 ? 60 : 1;
  tt__host_log(TT_LOG_INFO, NULL, "%s: about %.0f %s%s%s", task, eta / unit,
               unit == 3600 ? "h"
               : unit == 60 ? "min"
                            : "s",
               how ? "; " : "", how ? how : "");
}

/* Starts the progress of a new task (under the lock). */
static void tt__begin_task(const char *task, uint64_t now) {
  snprintf(tt__task, sizeof tt__task, "%s", task);
  tt__task_start_ns = now;
  tt__last_draw_ns = 0;
  tt__estimated = 0;
}

/* The bar on a terminal, at most 10 redraws a second and always at 100%. */
static void tt__draw_bar(double fraction, const char *el, const char *et, uint64_t now) {
  if (fraction < 1 && tt__last_draw_ns && now - tt__last_draw_ns < 100000000ull) return;
  tt__last_draw_ns = now;
  char bar[31];
  int fill = (int)(fraction * 30 + 0.5);
  for (int i = 0; i < 30; i++) bar[i] = i < fill ? '#' : '.';
  bar[30] = 0;
  fprintf(stderr, "\r\033[K%s [%s] %5.1f%%  elapsed %s  ETA %s", tt__task, bar, fraction * 100, el,
          et);
  tt__bar_visible = 1;
}

/* A line in a log (not a terminal): the first, then one per 10 s, and the last. */
static void tt__log_line(double fraction, const char *el, const char *et, uint64_t now) {
  if (tt__last_draw_ns && fraction < 1 && now - tt__last_draw_ns < TT__LOG_EVERY_NS) return;
  tt__last_draw_ns = now;
  fprintf(stderr, "%s: %5.1f%%  elapsed %s  ETA %s\n", tt__task, fraction * 100, el, et);
}

void tt__progress_update(const char *task, double fraction) {
  if (tt__quiet) return;
  fraction = fraction < 0 ? 0 : fraction > 1 ? 1 : fraction;
  pthread_mutex_lock(&tt__lock);
  uint64_t now = tt__now();
  if (strncmp(task, tt__task, sizeof tt__task - 1) != 0) tt__begin_task(task, now);
  double elapsed = (now - tt__task_start_ns) * 1e-9;
  double eta = fraction > 0 ? elapsed * (1 - fraction) / fraction : -1; /* "?" until then */
  int say = fraction > 0 && !tt__estimated && eta >= TT__LONG_WORK_S;
  tt__estimated |= fraction > 0;
  char el[32], et[32];
  tt__fmt_time(elapsed, el, sizeof el);
  tt__fmt_time(eta, et, sizeof et);
  if (tt__tty) tt__draw_bar(fraction, el, et, now);
  else tt__log_line(fraction, el, et, now);
  fflush(stderr);
  pthread_mutex_unlock(&tt__lock);
  if (say) tt__say_estimate(task, eta);
}

void tt__progress_finish(void) {
  pthread_mutex_lock(&tt__lock);
  if (tt__bar_visible) fputc('\n', stderr);
  tt__bar_visible = 0;
  tt__task[0] = 0;
  pthread_mutex_unlock(&tt__lock);
}

/* Log for plugins and the host (the table's log_str): clears a partial bar line first. */
static void tt__host_log_str(tt_log_level level, const char *plugin, const char *msg) {
  if (level < TT_LOG_WARN && tt__quiet) return;
  if (level == TT_LOG_DEBUG && !getenv("TT_DEBUG")) return;
  static const char *names[] = {"debug", "info", "warning", "error"};
  pthread_mutex_lock(&tt__lock);
  if (tt__bar_visible) {
    fputs("\r\033[K", stderr);
    tt__bar_visible = 0;
    tt__last_draw_ns = 0;
  }
  tt__say("%s%s%s%s: %s\n", plugin ? "[" : "", plugin ? plugin : "", plugin ? "] " : "",
          names[level <= TT_LOG_ERROR ? level : TT_LOG_ERROR], msg);
  pthread_mutex_unlock(&tt__lock);
}

/* The table's variadic log (plugins older than ABI 1.2, the host's own messages). */
static void tt__host_log(tt_log_level level, const char *plugin, const char *fmt, ...) {
  if (level < TT_LOG_WARN && tt__quiet) return;
  if (level == TT_LOG_DEBUG && !getenv("TT_DEBUG")) return;
  char msg[2048];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  tt__host_log_str(level, plugin, msg);
}

/* CPU time of the whole process (all its threads), in ns: the clock of --clock cpu. */
static uint64_t tt__cpu_clock_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
}

void tt__host_use_cpu_clock(void) { tt__host.clock_ns = tt__cpu_clock_ns; }

const tt_host *tt__host_services(int quiet) {
  tt__quiet = quiet;
  tt__tty = isatty(2);
  tt__host = *tt_default_host();
  tt__host.host_name = "tunetrace host";
  tt__host.log = tt__host_log;
  tt__host.log_str = tt__host_log_str;
  tt__host.progress = tt__progress_update;
  return &tt__host;
}
