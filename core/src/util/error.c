/* Error codes, the per-thread last-error message and the process-wide error callback. */
#include <tunetrace/common.h>

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#define TT__ERROR_MAX 2048

static _Thread_local char tt__last_error[TT__ERROR_MAX];
static tt_error_fn tt__error_fn;
static void *tt__error_user;

const char *tt_status_string(tt_status status) {
  switch (status) {
    case TT_OK: return "ok";
    case TT_DONE: return "done";
    case TT_REPAIRED: return "repaired";
    case TT_ERR_INVALID_ARGUMENT: return "invalid argument";
    case TT_ERR_OUT_OF_MEMORY: return "out of memory";
    case TT_ERR_IO: return "I/O error";
    case TT_ERR_PARSE: return "parse error";
    case TT_ERR_UNSUPPORTED: return "unsupported";
    case TT_ERR_INFEASIBLE: return "infeasible configuration";
    case TT_ERR_ABI: return "plugin ABI mismatch";
    case TT_ERR_NO_DATA: return "no data";
    case TT_ERR_INTERRUPTED: return "interrupted";
    case TT_ERR_INTERNAL: return "internal error";
    case TT_ERR_NUMERIC: return "numerical error";
  }
  return "unknown status";
}

tt_status tt_set_error(tt_status status, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(tt__last_error, sizeof tt__last_error, fmt, ap);
  va_end(ap);
  if (tt__error_fn) tt__error_fn(tt__error_user, status, tt__last_error);
  return status;
}

const char *tt_last_error(void) { return tt__last_error; }

void tt_clear_error(void) { tt__last_error[0] = '\0'; }

void tt_set_error_callback(tt_error_fn fn, void *user) {
  tt__error_fn = fn;
  tt__error_user = user;
}

void tt_free(void *ptr) { free(ptr); }

const char *tt_version(void) { return TT_VERSION_STRING; }
