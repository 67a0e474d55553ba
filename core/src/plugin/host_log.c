/* tt_host_log: one call that reaches either kind of host log (host.h). A host of ABI 1.2
 * may provide only log_str (a finished string: what a ctypes, cffi or Rust host can
 * implement), an older one only the variadic log; plugins and the library call this and
 * never choose themselves. */
#include <tunetrace/host.h>

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

void tt_host_log(const tt_host *host, tt_log_level level, const char *plugin, const char *fmt,
                 ...) {
  const tt_host *def = tt_default_host();
  if (!host) host = def;
  /* A copy of the default host whose log was replaced but not its log_str (the way to
   * customise it before ABI 1.2: `h = *tt_default_host(); h.log = mine;`) means its log. */
  int copied = host != def && host->log_str == def->log_str && host->log && host->log != def->log;
  int has_str = TT_HOST_HAS(host, log_str) && !copied;
  if (!has_str && !host->log) return;
  char buf[2048], *msg = buf;
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  if (n < 0) return;             /* an invalid format: nothing sensible to say */
  if ((size_t)n >= sizeof buf) { /* too long for the stack: the whole message, on the heap */
    char *big = malloc((size_t)n + 1);
    if (big) {
      va_start(ap, fmt);
      vsnprintf(big, (size_t)n + 1, fmt, ap);
      va_end(ap);
      msg = big;
    } /* else: the truncated message rather than none */
  }
  if (has_str) host->log_str(level, plugin, msg);
  else host->log(level, plugin, "%s", msg);
  if (msg != buf) free(msg);
}
