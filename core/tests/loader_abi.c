/* Loader ABI tests: each fixture plugin (tests/fixtures) is accepted or rejected exactly as
 * loader.h specifies, with messages that name the file and both versions; init/deinit run
 * only when they should; nothing stays mapped after a rejection; resolution by name, the
 * NAME/NAME.so layout, TT_PLUGIN_PATH, listing and probing.
 *
 * argv: the fixture .so paths (meson passes the build targets). */
#include <tunetrace/loader.h>
#include <tunetrace/post.h>
#include <tunetrace/sampler.h>
#include <tunetrace/tuner.h>

#include "tt_test.h"

#include <dlfcn.h>
#include <elf.h>
#include <stdarg.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static int g_argc;
static char **g_argv;
static char g_log[16384]; /* everything fixtures logged, one line per message */

/* Test host log: appends to g_log so checks can see which init/deinit calls happened. */
static void test_log(tt_log_level level, const char *plugin, const char *fmt, ...) {
  size_t n = strlen(g_log);
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(g_log + n, sizeof g_log - n, fmt, ap);
  va_end(ap);
  n = strlen(g_log);
  if (n + 1 < sizeof g_log) {
    g_log[n] = '\n';
    g_log[n + 1] = '\0';
  }
}

static tt_host g_host = {
    .struct_size = sizeof(tt_host),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .host_name = "loader_abi test",
    .host_version = "0",
    .log = test_log,
};

/* Number of log lines equal to `line`. */
static int log_count(const char *line) {
  int count = 0;
  size_t len = strlen(line);
  for (const char *p = g_log; (p = strstr(p, line)); p += len)
    if ((p == g_log || p[-1] == '\n') && p[len] == '\n') count++;
  return count;
}

/* Path of fixture NAME.so from argv; aborts the test if meson did not pass it. */
static const char *fixture(const char *name) {
  for (int i = 1; i < g_argc; i++) {
    const char *base = strrchr(g_argv[i], '/');
    base = base ? base + 1 : g_argv[i];
    size_t n = strlen(name);
    if (strncmp(base, name, n) == 0 && strcmp(base + n, ".so") == 0) return g_argv[i];
  }
  fprintf(stderr, "fixture %s not passed on the command line\n", name);
  exit(1);
}

/* True if the object at `path` is still mapped in this process. */
static int is_mapped(const char *path) {
  void *h = dlopen(path, RTLD_NOW | RTLD_NOLOAD);
  if (h) dlclose(h);
  return h != NULL;
}

/* Copies at most `limit` bytes (0 = all) of src to dst. */
static void copy_file(const char *src, const char *dst, long limit) {
  FILE *in = fopen(src, "rb"), *out = fopen(dst, "wb");
  if (!in || !out) {
    fprintf(stderr, "cannot copy %s to %s\n", src, dst);
    exit(1);
  }
  long total = 0;
  int c;
  while ((limit == 0 || total < limit) && (c = fgetc(in)) != EOF) {
    fputc(c, out);
    total++;
  }
  fclose(in);
  fclose(out);
}

/* Writes `text` to `path`. */
static void write_file(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  if (!f) exit(1);
  fputs(text, f);
  fclose(f);
}

/* Loads `name` into a fresh registry, expecting rejection; checks the message names the file
 * and contains `needle`, that nothing is registered and the object is unmapped. */
static void expect_reject(const char *name, const char *needle, int probe_rejects) {
  const char *path = fixture(name);
  tt_registry *reg = tt_registry_create(&g_host);
  tt_loaded_plugin *p = (tt_loaded_plugin *)1;
  tt_clear_error();
  tt_status st = tt_registry_load(reg, path, &p);
  CHECK_MSG(st == TT_ERR_ABI, "%s: status %d", name, (int)st);
  CHECK(p == NULL);
  CHECK(tt_registry_count(reg) == 0);
  CHECK_CONTAINS(tt_last_error(), path);
  CHECK_CONTAINS(tt_last_error(), needle);
  CHECK_MSG(!is_mapped(path), "%s still mapped after rejection", name);
  /* probe applies the same entry-table checks (interface checks need init) */
  tt_plugin copy;
  CHECK((tt_registry_probe(reg, path, &copy) != TT_OK) == probe_rejects);
  tt_registry_destroy(reg);
}

/* Version strings as the loader prints them. */
static char host_abi[64];

/* The good fixture loads, serves its interface and space, and is deinit'ed and unmapped. */
static void test_good(void) {
  const char *path = fixture("fixture_good");
  tt_registry *reg = tt_registry_create(&g_host);
  g_log[0] = '\0';
  tt_loaded_plugin *p = NULL;
  tt_status st = tt_registry_load(reg, path, &p);
  CHECK_MSG(st == TT_OK, "%s", tt_last_error());
  CHECK(p != NULL);
  CHECK(tt_registry_count(reg) == 1);
  CHECK(tt_registry_get(reg, 0) == p);
  CHECK(tt_registry_get(reg, 1) == NULL);
  CHECK(tt_registry_find_kind(reg, TT_KIND_TUNER) == p);
  CHECK(tt_registry_find_kind(reg, TT_KIND_ACCEL) == NULL);
  CHECK(tt_registry_find_name(reg, "fixture_good") == p);
  CHECK(tt_registry_find_name(reg, "fixture_other") == NULL);
  CHECK(strcmp(tt_loaded_plugin_path(p), path) == 0);
  const tt_plugin *e = tt_loaded_plugin_entry(p);
  CHECK(e && strcmp(e->name, "fixture_good") == 0 && e->kind == TT_KIND_TUNER);
  const tt_tuner_iface *ti = tt_loaded_plugin_iface(p);
  CHECK(ti && ti->struct_size == sizeof(tt_tuner_iface));
  const void *sentinel = tt_loaded_plugin_get(p, "fixture.sentinel/1");
  CHECK(sentinel != NULL);
  CHECK((const void *)tt_loaded_plugin_space(p) == sentinel);
  CHECK(tt_loaded_plugin_get(p, "tt.nothing/1") == NULL);
  CHECK(log_count("init fixture_good") == 1);
  CHECK(log_count("deinit fixture_good") == 0);
  CHECK(is_mapped(path));
  tt_registry_destroy(reg);
  CHECK(log_count("deinit fixture_good") == 1);
  CHECK_MSG(!is_mapped(path), "fixture_good still mapped after tt_registry_destroy");
}

/* Every broken fixture is rejected with the specified message. */
static void test_rejections(void) {
  char both[128];
  g_log[0] = '\0';
  snprintf(both, sizeof both, "plugin ABI 2.%d, %s", TT_ABI_MINOR, host_abi);
  expect_reject("fixture_wrong_major", both, 1);
  expect_reject("fixture_wrong_major", "version mismatch", 1);
  expect_reject("fixture_no_entry", "no symbol \"tt_plugin_entry\"", 1);
  expect_reject("fixture_wrong_kind", "unknown plugin kind 42", 1);
  expect_reject("fixture_short_table", "shorter than", 1);
  expect_reject("fixture_short_table", host_abi, 1);
  /* None of those may reach init. */
  CHECK_MSG(strstr(g_log, "init ") == NULL, "init was called: %s", g_log);

  expect_reject("fixture_no_iface", "does not provide interface \"tt.tuner/1\"", 0);
  CHECK(log_count("init fixture_no_iface") == 1);   /* load ran init; probe did not */
  CHECK(log_count("deinit fixture_no_iface") == 1); /* undone before unloading */

  expect_reject("fixture_short_iface", "\"tt.tuner/1\" table is", 0);
  CHECK(log_count("deinit fixture_short_iface") == log_count("init fixture_short_iface"));

  /* NULL required functions: rejected naming every missing one, deinit'ed, unmapped (the
   * host would otherwise call through NULL) */
  expect_reject("fixture_null_tuner", "has no feedback, destroy (NULL", 0);
  CHECK(log_count("deinit fixture_null_tuner") == 1);
  expect_reject("fixture_null_post", "\"tt.post/1\" has no process (NULL", 0);
  expect_reject("fixture_null_sampler", "\"tt.sampler/1\" has no name (NULL", 0);

  /* init failure passes the plugin's own reason on; deinit is not called after a failed
   * init. The status is the plugin's. */
  const char *path = fixture("fixture_init_fails");
  tt_registry *reg = tt_registry_create(&g_host);
  CHECK(tt_registry_load(reg, path, NULL) == TT_ERR_UNSUPPORTED);
  CHECK_CONTAINS(tt_last_error(), path);
  CHECK_CONTAINS(tt_last_error(), "init failed");
  CHECK_CONTAINS(tt_last_error(), "no frobnicator on this machine");
  CHECK(log_count("init fixture_init_fails") == 1);
  CHECK(log_count("deinit fixture_init_fails") == 0);
  CHECK(tt_registry_count(reg) == 0);
  CHECK(!is_mapped(path));
  tt_registry_destroy(reg);
}

/* An ABI 1.0 plugin (minor 0, the tuner table without set_context) loads; the host sees
 * that the 1.1 function is absent. */
static void test_abi10(void) {
  tt_registry *reg = tt_registry_create(&g_host);
  tt_loaded_plugin *p = NULL;
  CHECK_MSG(tt_registry_load(reg, fixture("fixture_abi10"), &p) == TT_OK, "%s", tt_last_error());
  const tt_tuner_iface *t = p ? tt_loaded_plugin_iface(p) : NULL;
  CHECK(t && t->struct_size == TT_TUNER_IFACE_SIZE_1_0 && !TT_TUNER_HAS(t, set_context));
  CHECK(p && tt_loaded_plugin_entry(p)->abi_minor == 0);
  tt_registry_destroy(reg);
}

/* Test log_str: appends "plugin: message" lines, like test_log. */
static char g_str_log[8192];
static void test_log_str(tt_log_level level, const char *plugin, const char *message) {
  (void)level;
  size_t n = strlen(g_str_log);
  snprintf(g_str_log + n, sizeof g_str_log - n, "%s: %s\n", plugin ? plugin : "-", message);
}

/* log_str (ABI 1.2): a host table with only the finished-string log (log NULL: what a
 * ctypes or Rust host can give) and an older table that ends before log_str both receive
 * a plugin's messages; a plugin older than ABI 1.2, which calls host->log itself, is
 * refused by the log_str-only host, naming what it lacks; tt_host_log hands over a
 * message longer than its stack buffer whole. */
static void test_log_str_hosts(void) {
  tt_host str_only = g_host;
  str_only.host_name = "log_str only";
  str_only.log = NULL;
  str_only.log_str = test_log_str;
  g_log[0] = g_str_log[0] = '\0';
  tt_registry *reg = tt_registry_create(&str_only);
  CHECK_MSG(tt_registry_load(reg, fixture("fixture_good"), NULL) == TT_OK, "%s", tt_last_error());
  tt_registry_destroy(reg);
  CHECK_CONTAINS(g_str_log, "fixture_good: init fixture_good\nfixture_good: deinit fixture_good\n");
  CHECK(g_log[0] == '\0');

  tt_host old = g_host; /* as built before ABI 1.2: log_str past its struct_size is not read */
  old.struct_size = offsetof(tt_host, log_str);
  old.log_str = test_log_str;
  g_log[0] = g_str_log[0] = '\0';
  reg = tt_registry_create(&old);
  CHECK_MSG(tt_registry_load(reg, fixture("fixture_good"), NULL) == TT_OK, "%s", tt_last_error());
  tt_registry_destroy(reg);
  CHECK(log_count("init fixture_good") == 1 && log_count("deinit fixture_good") == 1);
  CHECK(g_str_log[0] == '\0');

  g_str_log[0] = '\0';
  reg = tt_registry_create(&str_only);
  CHECK(tt_registry_load(reg, fixture("fixture_abi10"), NULL) == TT_ERR_ABI);
  CHECK_CONTAINS(tt_last_error(), "fixture_abi10.so: plugin ABI 1.0 calls the host's variadic log");
  CHECK_CONTAINS(tt_last_error(), "\"log_str only\"");
  CHECK(g_str_log[0] == '\0'); /* refused before init */
  CHECK_MSG(!is_mapped(fixture("fixture_abi10")), "fixture_abi10 still mapped after the refusal");
  tt_registry_destroy(reg);

  /* a real plugin through a log_str-only host with the default services (accel_embree
   * needs a clock): its init says which kernels it runs */
  tt_host services = *tt_default_host();
  services.log = NULL;
  services.log_str = test_log_str;
  g_str_log[0] = '\0';
  reg = tt_registry_create(&services);
  CHECK_MSG(tt_registry_load(reg, "accel_embree", NULL) == TT_OK, "%s", tt_last_error());
  tt_registry_destroy(reg);
  CHECK_CONTAINS(g_str_log, "accel_embree: custom backend kernels: ");

  char big[3000];
  memset(big, 'x', sizeof big - 1);
  big[sizeof big - 1] = '\0';
  g_str_log[0] = '\0';
  tt_host_log(&str_only, TT_LOG_WARN, "p", "%s!", big);
  CHECK(strlen(g_str_log) == 3 + sizeof big - 1 + 2 && g_str_log[3 + sizeof big - 1] == '!');
  g_log[0] = '\0';
  tt_host_log(&old, TT_LOG_WARN, "p", "%d %s", 42, "done");
  CHECK(log_count("42 done") == 1);
}

/* A newer minor with longer tables loads; the host sees its own prefix. */
static void test_newer_minor(void) {
  const char *path = fixture("fixture_newer_minor");
  tt_registry *reg = tt_registry_create(&g_host);
  tt_loaded_plugin *p = NULL;
  CHECK_MSG(tt_registry_load(reg, path, &p) == TT_OK, "%s", tt_last_error());
  const tt_plugin *e = tt_loaded_plugin_entry(p);
  CHECK(e && e->abi_minor == 99 && e->struct_size > sizeof(tt_plugin));
  const tt_tuner_iface *ti = tt_loaded_plugin_iface(p);
  CHECK(ti && ti->struct_size > sizeof(tt_tuner_iface));
  CHECK((const void *)tt_loaded_plugin_space(p) == tt_loaded_plugin_get(p, "fixture.sentinel/1"));
  tt_plugin copy;
  CHECK(tt_registry_probe(reg, path, &copy) == TT_OK);
  CHECK(copy.abi_minor == 99 && copy.struct_size == sizeof(tt_plugin));
  tt_registry_destroy(reg);
}

/* Runs load and probe of `path` in a child, so that a SIGBUS fails a check instead of the
 * whole test. Returns 0 loaded, 2 rejected with the file named, 3 rejected without it,
 * 128+N killed by signal N. */
static int child_load(const char *path) {
  fflush(NULL);
  pid_t pid = fork();
  if (pid == 0) {
    tt_registry *reg = tt_registry_create(&g_host);
    int lrc = tt_registry_load(reg, path, NULL);
    if (lrc != TT_OK && !strstr(tt_last_error(), path)) _exit(3);
    tt_plugin copy;
    int prc = tt_registry_probe(reg, path, &copy);
    if (prc != TT_OK && !strstr(tt_last_error(), path)) _exit(3);
    tt_registry_destroy(reg);
    _exit(lrc == TT_OK ? 0 : 2);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status);
}

/* Writes the first `n` bytes of `b` to `path`. */
static void write_prefix(const char *path, const unsigned char *b, long n) {
  FILE *f = fopen(path, "wb");
  if (!f || fwrite(b, 1, (size_t)n, f) != (size_t)n) exit(1);
  fclose(f);
}

/* Plugins cut short inside a PT_LOAD segment (which dlopen maps past EOF and then faults
 * on with SIGBUS, exit 135 before the fix) are rejected by load and by probe with the file
 * named; cut anywhere else they are rejected or load, never crash. */
static void test_truncated(const char *tmp) {
  size_t n = 0;
  unsigned char *b = (unsigned char *)tt_test_read_file(fixture("fixture_good"), &n);
  if (!b || n == 0) exit(1); /* the fixture is built with the test */
  long size = (long)n;
  const Elf64_Ehdr *eh = (const Elf64_Ehdr *)b;
  CHECK(size > (long)sizeof *eh && memcmp(eh->e_ident, ELFMAG, SELFMAG) == 0);
  char path[512];
  snprintf(path, sizeof path, "%s/truncated_segment.so", tmp);
  int inside = 0;
  for (unsigned i = 0; i < eh->e_phnum; i++) {
    const Elf64_Phdr *ph = (const Elf64_Phdr *)(b + eh->e_phoff + (size_t)i * sizeof *ph);
    if (ph->p_type != PT_LOAD || ph->p_filesz < 2 || ph->p_offset == 0) continue;
    long cuts[2] = {(long)(ph->p_offset + ph->p_filesz / 2),
                    (long)(ph->p_offset + ph->p_filesz - 1)};
    for (int k = 0; k < 2; k++) {
      write_prefix(path, b, cuts[k]);
      int rc = child_load(path);
      CHECK_MSG(rc == 2, "cut at byte %ld of %ld (inside PT_LOAD %u): result %d", cuts[k], size, i,
                rc);
      inside++;
    }
  }
  CHECK(inside >= 4);
  for (int k = 1; k < 32; k++) {
    long cut = size * k / 32;
    write_prefix(path, b, cut);
    int rc = child_load(path);
    CHECK_MSG(rc == 0 || rc == 2, "cut at byte %ld of %ld: result %d", cut, size, rc);
  }
  unlink(path);
  free(b);
}

/* Non-ELF and truncated files are rejected with the file named. */
static void test_bad_files(const char *tmp) {
  char bogus[512], trunc[512], missing[512];
  snprintf(bogus, sizeof bogus, "%s/bogus.so", tmp);
  snprintf(trunc, sizeof trunc, "%s/truncated.so", tmp);
  snprintf(missing, sizeof missing, "%s/missing.so", tmp);
  write_file(bogus, "not an elf\n");
  copy_file(fixture("fixture_good"), trunc, 100);
  tt_registry *reg = tt_registry_create(&g_host);
  CHECK(tt_registry_load(reg, bogus, NULL) != TT_OK);
  CHECK_CONTAINS(tt_last_error(), bogus);
  CHECK(tt_registry_load(reg, trunc, NULL) != TT_OK);
  CHECK_CONTAINS(tt_last_error(), trunc);
  CHECK(tt_registry_load(reg, missing, NULL) == TT_ERR_IO);
  CHECK_CONTAINS(tt_last_error(), missing);
  CHECK(tt_registry_load(reg, tmp, NULL) != TT_OK); /* a directory given as a path */
  CHECK_CONTAINS(tt_last_error(), tmp);
  CHECK(tt_registry_count(reg) == 0);
  tt_registry_destroy(reg);
}

/* One plugin per kind (but post), one per name; rejected before init. */
static void test_duplicates(void) {
  const char *good = fixture("fixture_good");
  tt_registry *reg = tt_registry_create(&g_host);
  g_log[0] = '\0';
  CHECK(tt_registry_load(reg, good, NULL) == TT_OK);
  CHECK(tt_registry_load(reg, fixture("fixture_newer_minor"), NULL) == TT_ERR_ABI);
  char want[1024];
  snprintf(want, sizeof want, "a second tuner plugin: fixture_good is already loaded from %s",
           good);
  CHECK_CONTAINS(tt_last_error(), want);
  CHECK_CONTAINS(tt_last_error(), fixture("fixture_newer_minor"));
  CHECK(log_count("init fixture_newer_minor") == 0);
  /* The same file again: rejected without a second init or any deinit of the live one. */
  CHECK(tt_registry_load(reg, good, NULL) == TT_ERR_ABI);
  CHECK(log_count("init fixture_good") == 1);
  CHECK(log_count("deinit fixture_good") == 0);
  CHECK(tt_registry_count(reg) == 1);
  CHECK(is_mapped(good));

  /* Post plugins may stack; but not twice the same name. */
  CHECK_MSG(tt_registry_load(reg, fixture("fixture_post_a"), NULL) == TT_OK, "%s", tt_last_error());
  CHECK_MSG(tt_registry_load(reg, fixture("fixture_post_b"), NULL) == TT_OK, "%s", tt_last_error());
  CHECK(tt_registry_load(reg, fixture("fixture_post_a"), NULL) == TT_ERR_ABI);
  CHECK_CONTAINS(tt_last_error(), "a plugin named \"fixture_post_a\" is already loaded from");
  CHECK(log_count("init fixture_post_a") == 1);
  CHECK(tt_registry_count(reg) == 3);
  CHECK(tt_registry_find_kind(reg, TT_KIND_POST) == tt_registry_get(reg, 1));

  /* Sampler: space() is the third member, not the second. */
  tt_loaded_plugin *s = NULL;
  CHECK(tt_registry_load(reg, fixture("fixture_sampler"), &s) == TT_OK);
  CHECK(s &&
        (const void *)tt_loaded_plugin_space(s) == tt_loaded_plugin_get(s, "fixture.sentinel/1"));
  tt_registry_destroy(reg);
  /* Reverse load order: the sampler (last) is deinit'ed before the tuner (first). */
  const char *ds = strstr(g_log, "deinit fixture_sampler"),
             *dg = strstr(g_log, "deinit fixture_good");
  CHECK(ds && dg && ds < dg);
}

/* Two registries that load one file share it: init once for the first, deinit once after
 * the last, whichever is destroyed first; a registry with another host table is refused
 * while the plugin is live (the plugin keeps the table init gave it). */
static void test_shared_across_registries(void) {
  const char *good = fixture("fixture_good");
  for (int older_first = 0; older_first < 2; older_first++) {
    g_log[0] = '\0';
    tt_registry *a = tt_registry_create(&g_host), *b = tt_registry_create(&g_host);
    CHECK_MSG(tt_registry_load(a, good, NULL) == TT_OK, "%s", tt_last_error());
    CHECK_MSG(tt_registry_load(b, good, NULL) == TT_OK, "%s", tt_last_error());
    CHECK_MSG(log_count("init fixture_good") == 1, "init ran %d times for two registries",
              log_count("init fixture_good"));
    tt_registry_destroy(older_first ? a : b);
    CHECK_MSG(log_count("deinit fixture_good") == 0, "deinit ran while a registry holds it");
    CHECK(is_mapped(good));
    tt_registry *c = tt_registry_create(&g_host); /* a third one meanwhile */
    CHECK(tt_registry_load(c, good, NULL) == TT_OK);
    tt_registry_destroy(c);
    CHECK(log_count("init fixture_good") == 1 && log_count("deinit fixture_good") == 0);
    tt_registry_destroy(older_first ? b : a);
    CHECK_MSG(log_count("deinit fixture_good") == 1, "deinit ran %d times after the last",
              log_count("deinit fixture_good"));
    CHECK(!is_mapped(good));
  }
  tt_host other = g_host;
  other.host_name = "another host";
  tt_registry *a = tt_registry_create(&g_host), *b = tt_registry_create(&other);
  CHECK(tt_registry_load(a, good, NULL) == TT_OK);
  CHECK(tt_registry_load(b, good, NULL) == TT_ERR_ABI);
  CHECK_CONTAINS(tt_last_error(), good);
  CHECK_CONTAINS(tt_last_error(),
                 "already initialised in this process for host \"loader_abi test\"");
  tt_registry_destroy(a);
  CHECK(tt_registry_load(b, good, NULL) == TT_OK); /* once the first one is gone */
  tt_registry_destroy(b);
}

/* Resolution by name through added dirs, TT_PLUGIN_PATH and the NAME/NAME.so layout. */
static void test_resolution(const char *tmp) {
  char dir[512], want[1024], nested_dir[512], nested[1024], sub[600];
  snprintf(dir, sizeof dir, "%s", fixture("fixture_good"));
  *strrchr(dir, '/') = '\0';

  setenv("TT_PLUGIN_PATH", "/nonexistent-tt-env", 1);
  tt_registry *reg = tt_registry_create(&g_host);
  CHECK(tt_registry_resolve(reg, "fixture_good") == NULL);
  CHECK(tt_registry_add_dir(reg, "/nonexistent-tt-added") == TT_OK);
  CHECK(tt_registry_add_dir(reg, dir) == TT_OK);
  const char *sp = tt_registry_search_path(reg);
  const char *a = strstr(sp, "/nonexistent-tt-added"), *b = strstr(sp, dir),
             *c = strstr(sp, "/nonexistent-tt-env");
  CHECK_MSG(a && b && c && a < b && b < c, "search path order: %s", sp);
  char *r = tt_registry_resolve(reg, "fixture_good");
  snprintf(want, sizeof want, "%s/fixture_good.so", dir);
  CHECK_MSG(r && strcmp(r, want) == 0, "resolved %s", r ? r : "(null)");
  tt_free(r);
  tt_loaded_plugin *p = NULL;
  CHECK(tt_registry_load(reg, "fixture_good", &p) == TT_OK);
  CHECK(p && strcmp(tt_loaded_plugin_path(p), want) == 0);
  tt_registry_destroy(reg);

  /* Through $TT_PLUGIN_PATH only (empty components ignored). */
  char env[1200];
  snprintf(env, sizeof env, "/nonexistent-tt-1::%s", dir);
  setenv("TT_PLUGIN_PATH", env, 1);
  reg = tt_registry_create(&g_host);
  r = tt_registry_resolve(reg, "fixture_post_a");
  snprintf(want, sizeof want, "%s/fixture_post_a.so", dir);
  CHECK_MSG(r && strcmp(r, want) == 0, "resolved %s: %s", r ? r : "(null)", tt_last_error());
  tt_free(r);
  CHECK(tt_registry_load(reg, "fixture_post_a", NULL) == TT_OK);
  tt_registry_destroy(reg);

  /* NAME/NAME.so (the build tree's layout); NAME.so wins in the same directory. */
  snprintf(nested_dir, sizeof nested_dir, "%s/plugins", tmp);
  snprintf(sub, sizeof sub, "%s/fixture_sampler", nested_dir);
  mkdir(nested_dir, 0755);
  mkdir(sub, 0755);
  snprintf(nested, sizeof nested, "%s/fixture_sampler.so", sub);
  copy_file(fixture("fixture_sampler"), nested, 0);
  setenv("TT_PLUGIN_PATH", "", 1);
  reg = tt_registry_create(&g_host);
  tt_registry_add_dir(reg, nested_dir);
  tt_registry_add_dir(reg, dir);
  r = tt_registry_resolve(reg, "fixture_sampler");
  CHECK_MSG(r && strcmp(r, nested) == 0, "resolved %s", r ? r : "(null)");
  tt_free(r);
  CHECK(tt_registry_load(reg, "fixture_sampler", &p) == TT_OK);
  CHECK(p && strcmp(tt_loaded_plugin_entry(p)->name, "fixture_sampler") == 0);
  tt_registry_destroy(reg);

  /* Missing: the message names the plugin and every directory searched. */
  setenv("TT_PLUGIN_PATH", "/nonexistent-tt-env-x:/nonexistent-tt-env-y", 1);
  reg = tt_registry_create(&g_host);
  tt_registry_add_dir(reg, "/nonexistent-tt-added-x");
  CHECK(tt_registry_resolve(reg, "no_such_plugin") == NULL);
  CHECK(tt_registry_load(reg, "no_such_plugin", NULL) != TT_OK);
  const char *msg = tt_last_error();
  CHECK_CONTAINS(msg, "\"no_such_plugin\" not found");
  CHECK_CONTAINS(msg, "no_such_plugin.so");
  CHECK_CONTAINS(msg, "/nonexistent-tt-added-x:/nonexistent-tt-env-x:/nonexistent-tt-env-y");
  CHECK_CONTAINS(msg, tt_registry_search_path(reg));
  tt_registry_destroy(reg);
}

static char listed[8192];
/* list_files callback: collects paths one per line. */
static void collect(void *user, const char *path) {
  (void)user;
  strncat(listed, path, sizeof listed - strlen(listed) - 2);
  strcat(listed, "\n");
}

/* Listing: NAME.so and NAME/NAME.so, first occurrence of a name wins; probe never inits. */
static void test_list_and_probe(const char *tmp) {
  char d1[512], d2[512], f1[1024], f2[1024], n1[1024], txt[1024];
  snprintf(d1, sizeof d1, "%s/list1", tmp);
  snprintf(d2, sizeof d2, "%s/list2", tmp);
  mkdir(d1, 0755);
  mkdir(d2, 0755);
  snprintf(f1, sizeof f1, "%s/fixture_good.so", d1);
  snprintf(f2, sizeof f2, "%s/fixture_good.so", d2);
  snprintf(txt, sizeof txt, "%s/notes.txt", d1);
  copy_file(fixture("fixture_good"), f1, 0);
  copy_file(fixture("fixture_good"), f2, 0);
  write_file(txt, "not a plugin\n");
  snprintf(n1, sizeof n1, "%s/fixture_post_b", d2);
  mkdir(n1, 0755);
  strcat(n1, "/fixture_post_b.so");
  copy_file(fixture("fixture_post_b"), n1, 0);

  setenv("TT_PLUGIN_PATH", d2, 1);
  tt_registry *reg = tt_registry_create(&g_host);
  tt_registry_add_dir(reg, d1);
  listed[0] = '\0';
  tt_registry_list_files(reg, collect, NULL);
  char line[1100];
  snprintf(line, sizeof line, "%s\n", f1);
  CHECK_CONTAINS(listed, line);
  snprintf(line, sizeof line, "%s\n", n1);
  CHECK_CONTAINS(listed, line);
  CHECK_MSG(strstr(listed, f2) == NULL, "shadowed %s listed:\n%s", f2, listed);
  CHECK(strstr(listed, "notes") == NULL);

  g_log[0] = '\0';
  tt_plugin copy;
  CHECK_MSG(tt_registry_probe(reg, n1, &copy) == TT_OK, "%s", tt_last_error());
  CHECK(strcmp(copy.name, "fixture_post_b") == 0 && copy.kind == TT_KIND_POST);
  CHECK(strcmp(copy.version, "0.0.1") == 0);
  CHECK(copy.init == NULL && copy.get_interface == NULL);
  CHECK(tt_registry_probe(reg, "fixture_good", &copy) == TT_OK); /* by name */
  CHECK(strcmp(copy.name, "fixture_good") == 0 && copy.kind == TT_KIND_TUNER);
  CHECK(g_log[0] == '\0'); /* no init, no deinit */
  CHECK(!is_mapped(f1));
  CHECK(tt_registry_count(reg) == 0);
  tt_registry_destroy(reg);
}

/* Kind names and interface ids. */
static void test_kinds(void) {
  CHECK(strcmp(tt_plugin_kind_interface(TT_KIND_ACCEL), "tt.accel/1") == 0);
  CHECK(strcmp(tt_plugin_kind_interface(TT_KIND_TUNER), TT_TUNER_INTERFACE_ID) == 0);
  CHECK(strcmp(tt_plugin_kind_interface(TT_KIND_SAMPLER), "tt.sampler/1") == 0);
  CHECK(tt_plugin_kind_interface(0) == NULL);
  CHECK(tt_plugin_kind_interface(42) == NULL);
  CHECK(strcmp(tt_plugin_kind_name(42), "unknown") == 0);
  for (uint32_t k = 1; k <= TT_KIND_COUNT; k++) {
    CHECK(tt_plugin_kind_from_name(tt_plugin_kind_name(k)) == k);
    char want[64];
    snprintf(want, sizeof want, "tt.%s/1", tt_plugin_kind_name(k));
    CHECK_MSG(strcmp(tt_plugin_kind_interface(k), want) == 0, "kind %u", (unsigned)k);
  }
  CHECK(tt_plugin_kind_from_name("bogus") == 0);
  CHECK(tt_plugin_kind_from_name(NULL) == 0);
}

/* Removes the scratch files this test created (known names only). */
static void cleanup(const char *tmp) {
  const char *files[] = {"bogus.so",
                         "truncated.so",
                         "plugins/fixture_sampler/fixture_sampler.so",
                         "plugins/fixture_sampler",
                         "plugins",
                         "list1/fixture_good.so",
                         "list1/notes.txt",
                         "list1",
                         "list2/fixture_good.so",
                         "list2/fixture_post_b/fixture_post_b.so",
                         "list2/fixture_post_b",
                         "list2"};
  char p[1024];
  for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
    snprintf(p, sizeof p, "%s/%s", tmp, files[i]);
    remove(p);
  }
  rmdir(tmp);
}

int main(int argc, char **argv) {
  g_argc = argc;
  g_argv = argv;
  snprintf(host_abi, sizeof host_abi, "host ABI %d.%d", TT_ABI_MAJOR, TT_ABI_MINOR);
  char tmp[] = "/tmp/tt_loader_abi_XXXXXX";
  if (!mkdtemp(tmp)) {
    perror("mkdtemp");
    return 1;
  }
  test_kinds();
  test_good();
  test_rejections();
  test_newer_minor();
  test_abi10();
  test_log_str_hosts();
  test_bad_files(tmp);
  test_truncated(tmp);
  test_duplicates();
  test_shared_across_registries();
  test_resolution(tmp);
  test_list_and_probe(tmp);
  cleanup(tmp);
  return tt_test_finish("loader_abi");
}
