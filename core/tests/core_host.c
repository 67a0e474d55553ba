/* The default host services: parallel_for visits every index exactly once for any grain
 * and thread count, thread indices stay in range, stop requests interrupt, allocation
 * honours alignment, the clock is monotonic, and errors reach the callback. */
#include <tunetrace/tunetrace.h>

#include <stdatomic.h>

#include "tt_test.h"

typedef struct visit_ctx {
  atomic_int *hits;
  atomic_int bad_thread;
  uint32_t threads;
} visit_ctx;

static void visit(void *ctx_, uint64_t begin, uint64_t end, uint32_t thread_index) {
  visit_ctx *ctx = ctx_;
  if (thread_index >= ctx->threads) atomic_fetch_add(&ctx->bad_thread, 1);
  for (uint64_t i = begin; i < end; i++) atomic_fetch_add(&ctx->hits[i], 1);
}

static int error_calls;
static tt_status last_status;
static void on_error(void *user, tt_status status, const char *message) {
  (void)message;
  (*(int *)user)++;
  last_status = status;
}

static void count_calls(void *ctx, uint64_t begin, uint64_t end, uint32_t t) {
  (void)t;
  atomic_fetch_add((atomic_long *)ctx, (long)(end - begin));
}

/* tt_default_host_set_log_callback: what the callback received last. */
static struct {
  int calls;
  tt_log_level level;
  char plugin[64], message[256];
} g_logged;
static void on_log(void *user, tt_log_level level, const char *plugin, const char *message) {
  (void)user;
  g_logged.calls++;
  g_logged.level = level;
  snprintf(g_logged.plugin, sizeof g_logged.plugin, "%s", plugin ? plugin : "(null)");
  snprintf(g_logged.message, sizeof g_logged.message, "%s", message);
}

/* The log callback gets finished messages with their level and plugin, after the level
 * filter; NULL restores stderr. */
static void test_log_callback(const tt_host *host) {
  int marker;
  tt_default_host_set_log_callback(on_log, &marker);
  host->log(TT_LOG_WARN, "accel_embree", "%d of %s", 3, "four");
  CHECK(g_logged.calls == 1 && g_logged.level == TT_LOG_WARN);
  CHECK(!strcmp(g_logged.plugin, "accel_embree") && !strcmp(g_logged.message, "3 of four"));
  host->log(TT_LOG_DEBUG, NULL, "dropped below the level");
  CHECK(g_logged.calls == 1);
  tt_default_host_set_log_level(TT_LOG_DEBUG);
  host->log(TT_LOG_DEBUG, NULL, "kept");
  CHECK(g_logged.calls == 2 && !strcmp(g_logged.plugin, "(null)") &&
        !strcmp(g_logged.message, "kept") && g_logged.level == TT_LOG_DEBUG);
  tt_default_host_set_log_level(TT_LOG_INFO);
  /* log_str (ABI 1.2): the finished string, the same level filter and callback */
  CHECK(TT_HOST_HAS(host, log_str));
  host->log_str(TT_LOG_WARN, "post_taa", "100% as given, no format");
  CHECK(g_logged.calls == 3 && !strcmp(g_logged.plugin, "post_taa") &&
        !strcmp(g_logged.message, "100% as given, no format"));
  host->log_str(TT_LOG_DEBUG, NULL, "dropped below the level");
  tt_host_log(host, TT_LOG_INFO, "pt", "%u%%", 7u);
  CHECK(g_logged.calls == 4 && !strcmp(g_logged.message, "7%"));
  tt_default_host_set_log_callback(NULL, NULL);
  host->log(TT_LOG_INFO, NULL, "core_host: a line on stderr again");
  CHECK(g_logged.calls == 4);
}

int main(void) {
  const tt_host *host = tt_default_host();
  test_log_callback(host);
  CHECK(host->struct_size == sizeof(tt_host));
  CHECK(host->abi_major == TT_ABI_MAJOR);

  enum { N = 100003 };
  static atomic_int hits[N];
  uint32_t thread_settings[] = {1, 2, 3, 8};
  uint64_t grains[] = {0, 1, 7, 1000, N + 5};
  for (size_t t = 0; t < 4; t++) {
    CHECK(tt_default_host_set_threads(thread_settings[t]) == TT_OK);
    CHECK(host->thread_count() == thread_settings[t]);
    for (size_t g = 0; g < 5; g++) {
      for (int i = 0; i < N; i++) atomic_store(&hits[i], 0);
      visit_ctx ctx = {hits, 0, host->thread_count()};
      CHECK(host->parallel_for(N, grains[g], visit, &ctx) == TT_OK);
      int wrong = 0;
      for (int i = 0; i < N; i++) wrong += atomic_load(&hits[i]) != 1;
      CHECK_MSG(wrong == 0, "threads %u grain %llu: %d indices not visited exactly once",
                thread_settings[t], (unsigned long long)grains[g], wrong);
      CHECK(atomic_load(&ctx.bad_thread) == 0);
    }
  }
  CHECK(tt_default_host_set_threads(2000) == TT_ERR_INVALID_ARGUMENT);
  CHECK(host->parallel_for(0, 0, visit, NULL) == TT_OK);
  CHECK(host->parallel_for(10, 0, NULL, NULL) == TT_ERR_INVALID_ARGUMENT);

  /* alignment */
  for (size_t align = 1; align <= 4096; align *= 2) {
    void *p = host->alloc(1000, align);
    CHECK(p != NULL && ((uintptr_t)p % align) == 0);
    host->free_mem(p);
  }
  CHECK(host->alloc(10, 3) == NULL);

  /* clock */
  uint64_t a = host->clock_ns(), b = host->clock_ns();
  CHECK(b >= a);

  /* errors: code returned, message stored per thread, callback called */
  tt_set_error_callback(on_error, &error_calls);
  CHECK(tt_set_error(TT_ERR_PARSE, "file.json: %s", "bad") == TT_ERR_PARSE);
  CHECK(strcmp(tt_last_error(), "file.json: bad") == 0);
  CHECK(error_calls == 1 && last_status == TT_ERR_PARSE);
  /* prefixing the previous message with itself as an argument (the message came out garbled:
   * vsnprintf into the buffer it read from, #13) */
  CHECK(tt_set_error(TT_ERR_PARSE, "%s: %s: %s", "resume.json", "tuner_nm", tt_last_error()) ==
        TT_ERR_PARSE);
  CHECK_MSG(strcmp(tt_last_error(), "resume.json: tuner_nm: file.json: bad") == 0, "%s",
            tt_last_error());
  tt_clear_error();
  CHECK(tt_last_error()[0] == 0);
  tt_set_error_callback(NULL, NULL);
  CHECK(strcmp(tt_status_string(TT_ERR_ABI), "plugin ABI mismatch") == 0);
  CHECK(strcmp(tt_status_string((tt_status)12345), "unknown status") == 0);
  /* identifiers for bindings: every code by its header name, nothing for other values */
  CHECK(strcmp(tt_status_name(TT_ERR_NO_DATA), "TT_ERR_NO_DATA") == 0);
  CHECK(strcmp(tt_status_name(TT_OK), "TT_OK") == 0);
  CHECK(strcmp(tt_status_name(TT_ERR_NUMERIC), "TT_ERR_NUMERIC") == 0);
  CHECK(tt_status_name((tt_status)12345) == NULL && tt_status_name((tt_status)-12) == NULL);

  /* stop request: should_stop turns on, parallel_for reports the interruption and skips */
  CHECK(host->should_stop() == 0);
  tt_default_host_request_stop();
  CHECK(host->should_stop() != 0);
  atomic_long calls = 0;
  CHECK(host->parallel_for(1000, 1, count_calls, &calls) == TT_ERR_INTERRUPTED);
  CHECK(atomic_load(&calls) == 0);
  /* held back (the host's one pass of an interrupted render with none done): no stop is
   * seen and every chunk runs; released, the stop requested meanwhile is back */
  tt_default_host_hold_stop(1);
  CHECK(host->should_stop() == 0);
  CHECK(host->parallel_for(1000, 1, count_calls, &calls) == TT_OK);
  CHECK(atomic_load(&calls) == 1000);
  tt_default_host_hold_stop(0);
  CHECK(host->should_stop() != 0);
  CHECK(host->parallel_for(1000, 1, count_calls, &calls) == TT_ERR_INTERRUPTED);

  return tt_test_finish("core_host");
}
