/* tunetrace: common definitions shared by every public header.
 *
 * Versioning: TT_VERSION_* is the library release; TT_ABI_MAJOR/MINOR is the plugin ABI.
 * A plugin built for ABI major M loads into a host of major M only; a plugin with a newer
 * minor loads too (the host reads only the table prefix it knows, through struct_size).
 *
 * Errors: every fallible function returns a tt_status. The message that goes with a failure
 * is stored per thread (tt_last_error) and also passed to the error callback installed with
 * tt_set_error_callback, like Embree's rtcSetDeviceErrorFunction.
 */
#ifndef TUNETRACE_COMMON_H
#define TUNETRACE_COMMON_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_VERSION_MAJOR 0
#define TT_VERSION_MINOR 1
#define TT_VERSION_PATCH 0
#define TT_VERSION_STRING "0.1.0"

/* Plugin ABI version. Bump MAJOR for any incompatible change, MINOR for appended fields. */
#define TT_ABI_MAJOR 1
#define TT_ABI_MINOR 2

#if defined(_WIN32)
#  define TT_EXPORT __declspec(dllexport)
#else
#  define TT_EXPORT __attribute__((visibility("default")))
#endif

/* TT_API marks functions exported by libtunetrace. */
#ifdef TT_BUILDING_CORE
#  define TT_API TT_EXPORT
#else
#  define TT_API
#endif

#if defined(__GNUC__)
#  define TT_PRINTF(fmt, args) __attribute__((format(printf, fmt, args)))
#else
#  define TT_PRINTF(fmt, args)
#endif

/* True when a versioned table or struct whose first field is `struct_size` is long enough
 * to hold `field`: offsetof(field) + sizeof(field) <= struct_size. The one rule for reading
 * an append-only table another party filled (a plugin's interface, a hint, a descriptor):
 * a field past its struct_size was not there when that party was built. Needs <stddef.h>. */
#define TT_HAS_FIELD(type, ptr, field)                                                             \
  ((ptr)->struct_size >= offsetof(type, field) + sizeof(((const type *)0)->field))

/* Status codes. Zero is success; negative values are errors; positive values are
 * non-error outcomes that a caller may want to distinguish. Values never change. */
typedef enum tt_status {
  TT_OK = 0,
  TT_DONE = 1,     /* iteration finished (e.g. a tuner that has converged) */
  TT_REPAIRED = 2, /* a configuration was infeasible and has been repaired */
  TT_ERR_INVALID_ARGUMENT = -1,
  TT_ERR_OUT_OF_MEMORY = -2,
  TT_ERR_IO = -3,          /* a file could not be read or written */
  TT_ERR_PARSE = -4,       /* malformed input (scene, JSON, image, weights) */
  TT_ERR_UNSUPPORTED = -5, /* a feature this build or plugin does not provide */
  TT_ERR_INFEASIBLE = -6,  /* a configuration violates a constraint and cannot be repaired */
  TT_ERR_ABI = -7,         /* plugin ABI mismatch */
  TT_ERR_NO_DATA = -8,     /* e.g. a predictor asked before it observed anything */
  TT_ERR_INTERRUPTED = -9, /* the user asked to stop */
  TT_ERR_INTERNAL = -10,   /* a bug: please report */
  TT_ERR_NUMERIC = -11     /* NaN/Inf or another numerical failure */
} tt_status;

/* Severity of log and error messages. */
typedef enum tt_log_level {
  TT_LOG_DEBUG = 0,
  TT_LOG_INFO = 1,
  TT_LOG_WARN = 2,
  TT_LOG_ERROR = 3
} tt_log_level;

/* Returns a static English name for a status code ("invalid argument", ...). Thread-safe. */
TT_API const char *tt_status_string(tt_status status);

/* Returns the identifier of a status code as this header spells it ("TT_ERR_NO_DATA"), or
 * NULL for a value that is no tt_status: bindings (the Python package) take the codes from
 * the library by name instead of copying the numbers. Thread-safe. */
TT_API const char *tt_status_name(tt_status status);

/* Records an error message for the calling thread and forwards it to the error callback;
 * returns `status` so that `return tt_set_error(TT_ERR_PARSE, "...")` reads naturally.
 * Thread-safe. Plugins call this too: they link against libtunetrace. */
TT_API tt_status tt_set_error(tt_status status, const char *fmt, ...) TT_PRINTF(2, 3);

/* Returns the last message recorded by tt_set_error on this thread ("" if none). Each
 * thread has its own: another thread's errors never change it. The pointer stays valid
 * until the next tt_set_error or tt_clear_error on the same thread. Thread-safe. */
TT_API const char *tt_last_error(void);

/* Clears the calling thread's last error message. Thread-safe. */
TT_API void tt_clear_error(void);

/* Error callback: receives every message passed to tt_set_error, from any thread. */
typedef void (*tt_error_fn)(void *user, tt_status status, const char *message);

/* Installs the process-wide error callback (NULL removes it). Not thread-safe: call at
 * start-up, before plugins run. */
TT_API void tt_set_error_callback(tt_error_fn fn, void *user);

/* Frees memory that a libtunetrace function documented as "free with tt_free" returned. */
TT_API void tt_free(void *ptr);

/* Library version string, e.g. "0.1.0". */
TT_API const char *tt_version(void);

/* The git commit libtunetrace was built from (`git describe --always --dirty`, e.g.
 * "398b3df" or "398b3df-dirty"), or "unknown" when it was not built from a git checkout.
 * For benchmark records: a figure is reproducible only with the code that measured it. */
TT_API const char *tt_build_commit(void);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_COMMON_H */
