/* host: SIGINT/SIGTERM. The first asks for a clean stop (the current pass finishes, outputs
 * are written); the second exits at once, except while the final outputs are written, when
 * it waits for the writes (atomic anyway) and the host exits 130 right after them.
 * A first signal before any pass is done (the scene loading, the accel building, the first
 * pass cut short) still ends with an image: run.c then completes one pass with the stop held
 * back (tt_default_host_hold_stop), during which a second signal exits at once. */
#include "host.h"

#include <signal.h>
#include <string.h>
#include <unistd.h>

static volatile sig_atomic_t tt__signals;
static volatile sig_atomic_t tt__writing_outputs;
static char tt__stop_msg[160]; /* set before the handlers are installed, read in them */
static size_t tt__stop_len;

static void tt__on_signal(int sig) {
  if (tt__signals++) {
    if (tt__writing_outputs) return;
    _exit(128 + sig);
  }
  tt_default_host_request_stop();
  ssize_t ignored = write(2, tt__stop_msg, tt__stop_len);
  (void)ignored;
}

void tt__install_signals(const char *unit) {
  int n =
      snprintf(tt__stop_msg, sizeof tt__stop_msg,
               "\n%s: interrupted: finishing the current %s (again to abort)\n", tt__prog(), unit);
  tt__stop_len = n > 0 && (size_t)n < sizeof tt__stop_msg ? (size_t)n : 0;
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = tt__on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
}

void tt__outputs_begin(void) { tt__writing_outputs = 1; }

void tt__outputs_end(void) {
  tt__writing_outputs = 0;
  if (tt__signals > 1) _exit(TT_EXIT_INTERRUPTED); /* the deferred second signal */
}
