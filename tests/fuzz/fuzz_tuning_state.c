/* libFuzzer: a tuning session's saved state (tt_tuning_load_state: the file host --resume
 * reads, with tuner_nm's state inside), for a session over a space with integer, log-float,
 * nominal and boolean parameters. A state that loads must then go on (ask/tell with a
 * synthetic cost), save, and load into a fresh session again. tuner_nm's sources are
 * compiled in and initialised through its own entry table.
 *
 * Seeds: with TT_FUZZ_WRITE_SEEDS=DIR set, the harness saves the states of sessions stopped
 * after 0, 3 and 25 measurements into DIR and exits (how corpus/tuning_state was made). */
#include <tunetrace/host.h>
#include <tunetrace/plugin.h>
#include <tunetrace/tuner.h>
#include <tunetrace/tuning.h>

#include "fuzz_util.h"

#include <math.h>

extern const tt_plugin tt_plugin_entry;

static const tt_tuner_iface *g_ti;
static tt_space *g_space;

static void quiet(tt_log_level level, const char *plugin, const char *fmt, ...) {
  (void)level, (void)plugin, (void)fmt;
}
/* the library's default host (clock, allocator, threads) with a quiet log */
static tt_host g_host;

static tt_tuning *create(void) {
  tt_tuning_desc d;
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.host = &g_host;
  d.space = g_space;
  d.tuner = g_ti;
  d.tuner_name = "tuner_nm";
  d.seed = 7;
  d.iterations = 30;
  d.spp = 1;
  d.plugin = "target";
  d.plugin_version = "1.0.0";
  d.run_id = "fuzz";
  tt_tuning *t = NULL;
  if (tt_tuning_create(&d, &t) != TT_OK || !t) abort();
  return t;
}

/* `steps` ask/tell rounds with a cost that depends on the configuration; 0 when done. */
static int advance(tt_tuning *t, int steps) {
  tt_config *c = tt_config_create(g_space);
  int done = 0;
  for (int i = 0; i < steps; i++) {
    if (tt_tuning_next(t, c) != TT_OK) {
      done = 1;
      break;
    }
    double x = tt_config_get_float(c, "x", 0), tc = tt_config_get_float(c, "travcost", 1);
    tt_tuning_measurement m = {
        .struct_size = sizeof m, .status = TT_OK, .render_ms = 10.0 + x * x + fabs(log(tc))};
    if (tt_tuning_report(t, &m, NULL) != TT_OK) abort();
  }
  tt_config_destroy(c);
  return done;
}

static void write_seeds(const char *dir) {
  static const int steps[3] = {0, 3, 25};
  for (int k = 0; k < 3; k++) {
    tt_tuning *t = create();
    advance(t, steps[k]);
    char *json = NULL;
    if (tt_tuning_save_state(t, &json) != TT_OK) abort();
    char name[64];
    snprintf(name, sizeof name, "state_%d.json", steps[k]);
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f || fputs(json, f) < 0 || fclose(f) != 0) abort();
    free(json);
    tt_tuning_destroy(t);
  }
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc, (void)argv;
  g_host = *tt_default_host();
  g_host.log = quiet;
  if (tt_plugin_entry.init(&g_host) != TT_OK) abort();
  g_ti = tt_plugin_entry.get_interface(TT_TUNER_INTERFACE_ID);
  if (!g_ti) abort();
  g_space = tt_space_create("target", "1.0.0");
  static const int64_t bf[] = {2, 4, 8};
  tt_space_add_int(g_space, "quality", 0, 3, 1, "");
  tt_space_add_nom_int(g_space, "branchingFactor", bf, 3, 2, "");
  tt_space_add_float(g_space, "travcost", 0.1, 10, 1, 1, "");
  tt_space_add_float(g_space, "x", -1, 1, 0, 0, "");
  tt_space_add_nom_bool(g_space, "compact", 0, "");
  const char *seeds = getenv("TT_FUZZ_WRITE_SEEDS");
  if (seeds && *seeds) {
    write_seeds(seeds);
    exit(0);
  }
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = fuzz_text(data, size);
  tt_tuning *t = create();
  if (tt_tuning_load_state(t, text, "fuzz.json") == TT_OK) {
    advance(t, 3);
    tt_config *best = tt_config_create(g_space);
    double cost;
    tt_tuning_best(t, best, &cost);
    tt_config_destroy(best);
    char *json = NULL;
    if (tt_tuning_save_state(t, &json) == TT_OK) {
      tt_tuning *t2 = create();
      if (tt_tuning_load_state(t2, json, "its own state") != TT_OK) {
        fprintf(stderr, "its own saved state does not load: %s\n", tt_last_error());
        abort();
      }
      tt_tuning_destroy(t2);
      free(json);
    }
  }
  tt_tuning_destroy(t);
  free(text);
  return 0;
}
