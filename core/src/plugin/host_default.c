/* The default host services: stderr logging, aligned allocation, a monotonic clock and a
 * persistent pthread pool for parallel_for. The host program wraps this table (it replaces
 * log and progress to draw a progress bar); tests and embedding applications use it as is. */
#include <tunetrace/host.h>

#include "plugin/log.h"

#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* ---- logging ---- */

static atomic_int tt__log_min = TT_LOG_INFO;
static pthread_mutex_t tt__log_lock = PTHREAD_MUTEX_INITIALIZER;

static const char *tt__level_name(tt_log_level level) {
  switch (level) {
  case TT_LOG_DEBUG: return "debug";
  case TT_LOG_INFO: return "info";
  case TT_LOG_WARN: return "warning";
  case TT_LOG_ERROR: return "error";
  }
  return "log";
}

/* tt_default_host_set_log_callback's function and its argument (under tt__log_lock). */
static tt_log_fn tt__log_fn;
static void *tt__log_user;

void tt_default_host_set_log_callback(tt_log_fn fn, void *user) {
  pthread_mutex_lock(&tt__log_lock);
  tt__log_fn = fn;
  tt__log_user = user;
  pthread_mutex_unlock(&tt__log_lock);
}

/* Prints "tunetrace: [plugin] level: message" as one write so lines never interleave, or
 * hands the finished message to the log callback. The table's log_str. */
static void tt__default_log_str(tt_log_level level, const char *plugin, const char *msg) {
  if ((int)level < atomic_load(&tt__log_min)) return;
  pthread_mutex_lock(&tt__log_lock);
  tt_log_fn fn = tt__log_fn;
  void *user = tt__log_user;
  if (fn) { /* called outside the lock: the callback may take its own */
    pthread_mutex_unlock(&tt__log_lock);
    fn(user, level, plugin, msg);
    return;
  }
  fprintf(stderr, "tunetrace: %s%s%s%s: %s\n", plugin ? "[" : "", plugin ? plugin : "",
          plugin ? "] " : "", tt__level_name(level), msg);
  pthread_mutex_unlock(&tt__log_lock);
}

/* The table's variadic log (plugins older than ABI 1.2): formats, then as log_str. */
static void tt__default_log(tt_log_level level, const char *plugin, const char *fmt, ...) {
  if ((int)level < atomic_load(&tt__log_min)) return;
  char msg[2048];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  tt__default_log_str(level, plugin, msg);
}

void tt_default_host_set_log_level(tt_log_level level) { atomic_store(&tt__log_min, (int)level); }

/* Where the library's own messages go (tt_set_log_host); NULL: the default host. */
static const tt_host *tt__log_host;

void tt_set_log_host(const tt_host *host) { tt__log_host = host; }

void tt__log(tt_log_level level, const char *fmt, ...) {
  char msg[2048];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  const tt_host *h =
      tt__log_host && (TT_HOST_HAS(tt__log_host, log_str) || TT_HOST_HAS(tt__log_host, log))
          ? tt__log_host
          : tt_default_host();
  tt_host_log(h, level, NULL, "%s", msg);
}

/* ---- memory and clock ---- */

static void *tt__default_alloc(size_t size, size_t align) {
  if (align == 0 || (align & (align - 1)) || align > 4096) return NULL;
  if (align < sizeof(void *)) align = sizeof(void *);
  void *p = NULL;
  if (posix_memalign(&p, align, size ? size : 1) != 0) return NULL;
  return p;
}

static void tt__default_free(void *ptr) { free(ptr); }

static uint64_t tt__default_clock_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
}

/* ---- stop request ---- */

static volatile sig_atomic_t tt__stop_requested;
/* tt_default_host_hold_stop; read by the pool's workers too */
static atomic_int tt__stop_held;

void tt_default_host_request_stop(void) { tt__stop_requested = 1; }

void tt_default_host_hold_stop(int hold) { atomic_store(&tt__stop_held, hold != 0); }

/* a requested stop, unless it is held back */
static int tt__stop_now(void) { return tt__stop_requested != 0 && !atomic_load(&tt__stop_held); }

static int tt__default_should_stop(void) { return tt__stop_now(); }

/* ---- thread pool ---- */

/* One job at a time: the main thread publishes it under the lock, bumps `generation`,
 * works on chunks itself as thread 0, and waits until every worker has left the job. */
typedef struct tt__pool {
  pthread_t *threads;
  uint32_t worker_count; /* threads besides the caller */
  pthread_mutex_t lock;
  pthread_cond_t wake;
  pthread_cond_t done;
  uint64_t generation;
  uint32_t busy; /* workers still inside the current job */
  int quit;
  /* current job */
  tt_parallel_fn fn;
  void *ctx;
  uint64_t count, grain;
  atomic_uint_fast64_t next;
  atomic_int interrupted;
} tt__pool;

static tt__pool tt__the_pool;
static int tt__pool_started;
/* Held for a whole job: render sessions on several threads (a session per thread, as an
 * application or Python may use them) share the one pool, and their jobs run one after
 * another instead of overwriting each other's job description. */
static pthread_mutex_t tt__job_lock = PTHREAD_MUTEX_INITIALIZER;
/* thread_index + 1 on a thread that is running chunks of a job, else 0: a parallel_for
 * called from inside fn runs inline on that thread instead of waiting for the job it is
 * part of. */
static _Thread_local int tt__in_job;
static uint32_t tt__thread_setting; /* 0 = number of CPUs */

/* Claims and runs chunks until the job is exhausted or a stop is requested. */
static void tt__pool_run_chunks(tt__pool *pool, uint32_t thread_index) {
  for (;;) {
    if (tt__stop_now()) {
      atomic_store(&pool->interrupted, 1);
      return;
    }
    uint64_t begin = atomic_fetch_add(&pool->next, pool->grain);
    if (begin >= pool->count) return;
    uint64_t end = begin + pool->grain;
    if (end > pool->count) end = pool->count;
    tt__in_job = (int)thread_index + 1;
    pool->fn(pool->ctx, begin, end, thread_index);
    tt__in_job = 0;
  }
}

typedef struct tt__worker_arg {
  tt__pool *pool;
  uint32_t index;
} tt__worker_arg;

static tt__worker_arg tt__worker_args[1024];

static void *tt__worker_main(void *arg_) {
  tt__worker_arg *arg = arg_;
  tt__pool *pool = arg->pool;
  uint64_t seen = 0;
  pthread_mutex_lock(&pool->lock);
  for (;;) {
    while (!pool->quit && pool->generation == seen) pthread_cond_wait(&pool->wake, &pool->lock);
    if (pool->quit) break;
    seen = pool->generation;
    pthread_mutex_unlock(&pool->lock);
    tt__pool_run_chunks(pool, arg->index);
    pthread_mutex_lock(&pool->lock);
    if (--pool->busy == 0) pthread_cond_signal(&pool->done);
  }
  pthread_mutex_unlock(&pool->lock);
  return NULL;
}

/* The CPUs this process may run on: its affinity mask (mpirun --bind-to core, taskset, a
 * cgroup cpuset), else the online CPUs. */
static uint32_t tt__cpu_count(void) {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0)
    return (uint32_t)CPU_COUNT(&set);
  long n = sysconf(_SC_NPROCESSORS_ONLN);
  return n > 0 ? (uint32_t)n : 1u;
}

static uint32_t tt__default_thread_count(void) {
  uint32_t n = tt__thread_setting ? tt__thread_setting : tt__cpu_count();
  return n > 1024 ? 1024 : n;
}

/* Stops and joins the workers (if any). */
static void tt__pool_stop(void) {
  if (!tt__pool_started) return;
  tt__pool *pool = &tt__the_pool;
  pthread_mutex_lock(&pool->lock);
  pool->quit = 1;
  pthread_cond_broadcast(&pool->wake);
  pthread_mutex_unlock(&pool->lock);
  for (uint32_t i = 0; i < pool->worker_count; i++) pthread_join(pool->threads[i], NULL);
  free(pool->threads);
  pthread_mutex_destroy(&pool->lock);
  pthread_cond_destroy(&pool->wake);
  pthread_cond_destroy(&pool->done);
  memset(pool, 0, sizeof *pool);
  tt__pool_started = 0;
}

/* Starts thread_count()-1 workers; the calling thread is worker 0. */
static tt_status tt__pool_start(void) {
  tt__pool *pool = &tt__the_pool;
  memset(pool, 0, sizeof *pool);
  pthread_mutex_init(&pool->lock, NULL);
  pthread_cond_init(&pool->wake, NULL);
  pthread_cond_init(&pool->done, NULL);
  uint32_t n = tt__default_thread_count();
  pool->worker_count = n - 1;
  if (pool->worker_count) {
    pool->threads = calloc(pool->worker_count, sizeof *pool->threads);
    if (!pool->threads) return tt_set_error(TT_ERR_OUT_OF_MEMORY, "thread pool: out of memory");
  }
  for (uint32_t i = 0; i < pool->worker_count; i++) {
    tt__worker_args[i].pool = pool;
    tt__worker_args[i].index = i + 1;
    if (pthread_create(&pool->threads[i], NULL, tt__worker_main, &tt__worker_args[i]) != 0) {
      pool->worker_count = i;
      tt__pool_started = 1;
      tt__pool_stop();
      return tt_set_error(TT_ERR_INTERNAL, "thread pool: cannot start thread %u", i + 1);
    }
  }
  tt__pool_started = 1;
  return TT_OK;
}

static void tt__pool_atexit(void) { tt__pool_stop(); }

/* A parallel_for called from inside a job's fn: the whole range on the calling thread. */
static tt_status tt__run_inline(uint64_t count, tt_parallel_fn fn, void *ctx) {
  if (tt__stop_now()) return TT_ERR_INTERRUPTED;
  int outer = tt__in_job;
  fn(ctx, 0, count, (uint32_t)(outer - 1));
  tt__in_job = outer;
  return TT_OK;
}

static tt_status tt__default_parallel_for(uint64_t count, uint64_t grain, tt_parallel_fn fn,
                                          void *ctx) {
  if (!fn) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "parallel_for: no function");
  if (count == 0) return tt__stop_now() ? TT_ERR_INTERRUPTED : TT_OK;
  if (tt__in_job) return tt__run_inline(count, fn, ctx);
  pthread_mutex_lock(&tt__job_lock);
  if (!tt__pool_started) {
    tt_status st = tt__pool_start();
    if (st != TT_OK) {
      pthread_mutex_unlock(&tt__job_lock);
      return st;
    }
    static int registered;
    if (!registered) {
      atexit(tt__pool_atexit);
      registered = 1;
    }
  }
  tt__pool *pool = &tt__the_pool;
  uint32_t threads = pool->worker_count + 1;
  if (grain == 0) {
    /* ~8 chunks per thread balances load without much contention */
    grain = count / ((uint64_t)threads * 8);
    if (grain == 0) grain = 1;
  }
  pthread_mutex_lock(&pool->lock);
  pool->fn = fn;
  pool->ctx = ctx;
  pool->count = count;
  pool->grain = grain;
  atomic_store(&pool->next, 0);
  atomic_store(&pool->interrupted, 0);
  pool->busy = pool->worker_count;
  pool->generation++;
  pthread_cond_broadcast(&pool->wake);
  pthread_mutex_unlock(&pool->lock);

  tt__pool_run_chunks(pool, 0);

  pthread_mutex_lock(&pool->lock);
  while (pool->busy > 0) pthread_cond_wait(&pool->done, &pool->lock);
  pthread_mutex_unlock(&pool->lock);
  tt_status st = atomic_load(&pool->interrupted) ? TT_ERR_INTERRUPTED : TT_OK;
  pthread_mutex_unlock(&tt__job_lock);
  return st;
}

tt_status tt_default_host_set_threads(uint32_t threads) {
  if (threads > 1024)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "threads: at most 1024, got %u", threads);
  pthread_mutex_lock(&tt__job_lock); /* not in the middle of another thread's job */
  tt__pool_stop();
  tt__thread_setting = threads;
  pthread_mutex_unlock(&tt__job_lock);
  return TT_OK;
}

/* ---- progress (silent by default) and extensions ---- */

static void tt__default_progress(const char *task, double fraction) {
  (void)task;
  (void)fraction;
}

static const void *tt__default_get_extension(const char *id) {
  (void)id;
  return NULL;
}

static const tt_host tt__default_host = {
    .struct_size = sizeof(tt_host),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .host_name = "libtunetrace default host",
    .host_version = TT_VERSION_STRING,
    .log = tt__default_log,
    .alloc = tt__default_alloc,
    .free_mem = tt__default_free,
    .clock_ns = tt__default_clock_ns,
    .thread_count = tt__default_thread_count,
    .parallel_for = tt__default_parallel_for,
    .progress = tt__default_progress,
    .should_stop = tt__default_should_stop,
    .get_extension = tt__default_get_extension,
    .log_str = tt__default_log_str,
};

const tt_host *tt_default_host(void) { return &tt__default_host; }
