/* tunetrace: services the host passes to every plugin (logging, memory, clock, threads,
 * progress, interruption). One versioned table, like CLAP's clap_host or SQLite's
 * sqlite3_api_routines: fields are only ever appended; a plugin must check
 * `host->struct_size >= offsetof(tt_host, field) + sizeof(host->field)` (TT_HOST_HAS, the
 * rule of TT_HAS_FIELD in common.h) before using a field newer than the ABI minor it was
 * built for.
 *
 * Lifetime: the table and everything reachable from it are owned by the host and stay valid
 * from the plugin's init() until after its deinit().
 */
#ifndef TUNETRACE_HOST_H
#define TUNETRACE_HOST_H

#include <tunetrace/common.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Body of a parallel loop: processes indices [begin, end) on worker `thread_index`
 * (0 <= thread_index < thread_count()). */
typedef void (*tt_parallel_fn)(void *ctx, uint64_t begin, uint64_t end, uint32_t thread_index);

typedef struct tt_host {
  uint32_t struct_size;  /* sizeof(tt_host) as the host was built: the table's version */
  uint16_t abi_major;    /* TT_ABI_MAJOR of the host */
  uint16_t abi_minor;    /* TT_ABI_MINOR of the host */
  const char *host_name; /* "tunetrace host" or the embedding application's name */
  const char *host_version;

  /* Logs one message with a severity; `plugin` names the sender. Thread-safe. Kept for
   * plugins older than ABI 1.2, which call it directly; since ABI 1.2 a host may leave it
   * NULL when it sets log_str (the loader then refuses plugins older than 1.2, naming it),
   * and plugins log through tt_host_log, which uses log_str when the table has it. */
  void (*log)(tt_log_level level, const char *plugin, const char *fmt, ...) TT_PRINTF(3, 4);

  /* Allocates `size` bytes aligned to `align` (a power of two, at most 4096); NULL on
   * failure. Memory is owned by the caller and released with free_mem. Thread-safe. */
  void *(*alloc)(size_t size, size_t align);
  /* Releases memory from alloc (NULL is ignored). Thread-safe. */
  void (*free_mem)(void *ptr);

  /* Monotonic clock in nanoseconds (CLOCK_MONOTONIC); for timing only. Thread-safe. */
  uint64_t (*clock_ns)(void);

  /* Number of worker threads parallel_for uses (>= 1), as set by --threads. Thread-safe. */
  uint32_t (*thread_count)(void);

  /* Runs fn over [0, count) split into chunks of `grain` indices (0 = automatic) on the
   * host's worker pool and returns when all chunks are done. Chunks are handed out
   * dynamically, so which thread gets which chunk is not deterministic: code that must be
   * deterministic derives its random numbers from the index, never from thread_index.
   * Returns TT_ERR_INTERRUPTED if an interrupt arrived (chunks not yet started are skipped).
   * Main thread only; not reentrant (fn must not call parallel_for). */
  tt_status (*parallel_for)(uint64_t count, uint64_t grain, tt_parallel_fn fn, void *ctx);

  /* Reports progress of a long task in [0, 1]; `task` is a short label. Thread-safe,
   * cheap: the host rate-limits drawing. */
  void (*progress)(const char *task, double fraction);

  /* Non-zero once the user asked to stop (SIGINT/SIGTERM): finish the current unit of work
   * (a pass, a tuning step), leave results consistent and return. Thread-safe. */
  int (*should_stop)(void);

  /* Looks up an optional host extension by versioned id ("tt.host.xxx/1"); NULL if the host
   * has none. Thread-safe. No extensions are defined in ABI 1.0. */
  const void *(*get_extension)(const char *id);

  /* ---- fields below are ABI 1.2 and later; check with TT_HOST_HAS ---- */

  /* Logs one finished message (no format, no varargs, like CLAP's clap_host_log): what a
   * host written with ctypes, cffi or Rust can provide, which the variadic log is not.
   * `plugin` names the sender (NULL: the library itself); `message` is one line without
   * its newline, owned by the caller and valid only during the call. Thread-safe: plugins
   * call it from worker threads, concurrently. */
  void (*log_str)(tt_log_level level, const char *plugin, const char *message);
} tt_host;

/* True if the host table provides `field` (it may be older than the plugin). */
#define TT_HOST_HAS(host, field) (TT_HAS_FIELD(tt_host, host, field) && (host)->field)

/* Logs one message through `host` (NULL: tt_default_host()): formats it, then hands the
 * finished string to host->log_str when the table has it (TT_HOST_HAS), else to the
 * variadic host->log as "%s"; nothing when the host has neither. A copy of
 * tt_default_host() whose log was replaced and whose log_str was not counts as having only
 * that log (the way applications customised the log before ABI 1.2). What plugins and the
 * library call instead of host->log, so that both kinds of host receive their messages.
 * Any length (longer messages are formatted on the heap). Thread-safe when the host's log
 * is. */
TT_API void tt_host_log(const tt_host *host, tt_log_level level, const char *plugin,
                        const char *fmt, ...) TT_PRINTF(4, 5);

/* The host table libtunetrace's default implementation provides (stderr logging, pthread
 * pool, no progress drawing). Used by tests and by applications that embed libtunetrace
 * without a UI; an application that copies it to replace services sets log_str with log
 * (or leaves both: tt_default_host_set_log_callback takes finished messages). Valid for the life of the process. Thread-safe; its parallel_for may also
 * be called from several threads at once (one render session per thread): their jobs share
 * the one pool and run one after another. */
TT_API const tt_host *tt_default_host(void);

/* Sets the worker count of tt_default_host's pool (0 = number of CPUs). Main thread only,
 * not while a parallel_for runs. */
TT_API tt_status tt_default_host_set_threads(uint32_t threads);

/* Requests a stop on tt_default_host (should_stop() becomes non-zero). Async-signal-safe. */
TT_API void tt_default_host_request_stop(void);

/* Holds a requested stop back while `hold` is non-zero: should_stop() reads 0 and
 * parallel_for runs every chunk; releasing it lets a stop requested meanwhile through. For
 * the work a program must finish even when asked to stop (host: the one pass an interrupted
 * render completes when none was done, so that it has an image to write). Main thread,
 * not while a parallel_for runs. */
TT_API void tt_default_host_hold_stop(int hold);

/* Sets the minimum level tt_default_host's log prints (default TT_LOG_INFO). */
TT_API void tt_default_host_set_log_level(tt_log_level level);

/* Receives one finished log message: `plugin` is the plugin's name, or NULL for the
 * library's own messages. */
typedef void (*tt_log_fn)(void *user, tt_log_level level, const char *plugin, const char *message);

/* Sends tt_default_host's log (plugins' messages and the library's own) to `fn` instead of
 * stderr; NULL prints to stderr again. Levels below tt_default_host_set_log_level are
 * dropped before. For applications and bindings that route messages into their own
 * logging (the Python package: the `tunetrace` logger), and whose callbacks cannot be
 * variadic like tt_host.log. `fn` may be called from any thread, concurrently. */
TT_API void tt_default_host_set_log_callback(tt_log_fn fn, void *user);

/* Routes libtunetrace's own messages (the scene loaders' warnings: unknown keys, pbrt
 * features approximated or skipped, values clamped on write; a display config that falls
 * back) to host->log, so an application's quiet mode and progress display treat them like
 * its other messages. NULL (the default) sends them to tt_default_host(), which prints
 * "tunetrace: warning: ..." on stderr. `host` must outlive its use. Not thread-safe: call
 * at start-up, before loading scenes. */
TT_API void tt_set_log_host(const tt_host *host);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_HOST_H */
