/* libFuzzer: a predictor plugin's model file (tt.predictor/1 load, the file host --model and
 * --hybrid read), compiled once per plugin (fuzz_predictor_nn, fuzz_predictor_rbf,
 * fuzz_predictor_static: the plugin's sources are compiled in and initialised through its
 * own entry table). A model that loads must then answer predict_ex, estimate and info, save,
 * and load its own file again. The checksum is recomputed on the mutated input so the
 * fuzzer reaches what is behind it: the binary container's FNV-1a 64
 * (predictor_common/model_file.h), or the text format's last "checksum HEX" line
 * (predictor_static: FNV-1a 64 of the text before the line; the bytes after its 16 digits
 * are left, so text appended after a sealed model is tried too).
 *
 * Seeds: with TT_FUZZ_WRITE_SEEDS=DIR set, the harness trains small models (0, 1 and 40
 * observations) on its own target space, saves them into DIR and exits: that is how
 * corpus/predictor_nn, corpus/predictor_rbf and corpus/predictor_static were made. */
#include <tunetrace/host.h>
#include <tunetrace/plugin.h>
#include <tunetrace/predictor.h>
#include <tt_util/hash.h>

#include "fuzz_util.h"

#include <math.h>

extern const tt_plugin tt_plugin_entry;

static const tt_predictor_iface *g_pi;
static tt_space *g_target;
enum { DIM = 3 };

static void quiet(tt_log_level level, const char *plugin, const char *fmt, ...) {
  (void)level, (void)plugin, (void)fmt;
}
/* the library's default host (clock, allocator, threads) with a quiet log */
static tt_host g_host;

/* The predictor's settings: its defaults, but predictor_rbf's candidate set cut from 256
 * to 16 points (lhsCandidates), which the seed files record too: building 256 candidates at
 * every create and load was 40% of the harness's time, and the count changes no code path
 * the file reaches. */
static tt_config *g_settings;

static tt_predictor *create(void) {
  static const char *const names[DIM] = {"a", "b", "c"};
  tt_predictor_setup su = {.struct_size = sizeof su,
                           .target = g_target,
                           .state_dim = DIM,
                           .state_space = "fuzz/1",
                           .state_names = names,
                           .settings = g_settings,
                           .seed = 3};
  tt_predictor *p = NULL;
  if (g_pi->create_ex(&su, &p) != TT_OK || !p) abort();
  return p;
}

/* Writes seed models with 0, 1 and 40 observations into `dir`. */
static void write_seeds(const char *dir) {
  uint64_t x = 12345;
  for (int k = 0; k < 3; k++) {
    static const int counts[3] = {0, 1, 40};
    tt_predictor *p = create();
    tt_config *c = tt_config_create(g_target);
    for (int i = 0; i < counts[k]; i++) {
      double u[4], s[DIM];
      for (int j = 0; j < 4; j++)
        u[j] = (double)((x = x * 6364136223846793005ull + 1) >> 11) * 0x1.0p-53;
      for (int j = 0; j < DIM; j++) s[j] = u[j];
      tt_config_from_unit(c, u);
      tt_predictor_sample sm = {.struct_size = sizeof sm,
                                .state = s,
                                .config = c,
                                .cost = 1.0 + u[0] + u[3],
                                .default_cost = 2.0};
      if (g_pi->observe_ex(p, &sm, 1, TT_PREDICTOR_ONLINE) != TT_OK) abort();
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/model_%d.bin", dir, counts[k]);
    if (g_pi->save(p, path) != TT_OK) abort();
    tt_config_destroy(c);
    g_pi->destroy(p);
  }
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc, (void)argv;
  g_host = *tt_default_host();
  g_host.log = quiet;
  if (tt_plugin_entry.init(&g_host) != TT_OK) abort();
  g_pi = tt_plugin_entry.get_interface(TT_PREDICTOR_INTERFACE_ID);
  if (!g_pi || !TT_PREDICTOR_HAS(g_pi, create_ex) || !TT_PREDICTOR_HAS(g_pi, estimate)) abort();
  /* the shapes of accel_embree's space: an INT, a log FLOAT, a NOM, a bool */
  g_target = tt_space_create("target", "1.0.0");
  static const int64_t q[] = {1, 2, 3};
  tt_space_add_int(g_target, "leaf", 1, 32, 8, "");
  tt_space_add_float(g_target, "cost", 0.1, 10.0, 1.0, 1, "");
  tt_space_add_nom_int(g_target, "quality", q, 3, 1, "");
  tt_space_add_nom_bool(g_target, "fast", 0, "");
  const tt_space *settings = g_pi->space ? g_pi->space() : NULL;
  if (settings) {
    g_settings = tt_config_create(settings);
    if (!g_settings) abort();
    int lhs = tt_space_find(settings, "lhsCandidates");
    if (lhs >= 0 && tt_config_set_number(g_settings, (size_t)lhs, 16) != TT_OK) abort();
  }
  const char *seeds = getenv("TT_FUZZ_WRITE_SEEDS");
  if (seeds && *seeds) {
    write_seeds(seeds);
    exit(0);
  }
  return 0;
}

static uint64_t get_u64(const uint8_t *p) {
  uint64_t v = 0;
  for (int k = 7; k >= 0; k--) v = v << 8 | p[k];
  return v;
}

/* predictor_static's text format: the last "\nchecksum " followed by 16 characters gets the
 * FNV-1a 64 of the bytes before its line, as lowercase hex. */
static void reseal_text(uint8_t *c, size_t size) {
  for (size_t i = size; i-- > 0;)
    if (c[i] == '\n' && size - i - 1 >= 9 + 16 && !memcmp(c + i + 1, "checksum ", 9)) {
      char hex[17];
      snprintf(hex, sizeof hex, "%016llx",
               (unsigned long long)tt__fnv1a64(TT__FNV1A64_OFFSET, c, i + 1));
      memcpy(c + i + 1 + 9, hex, 16);
      return;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  uint8_t *c = malloc(size ? size : 1);
  if (!c) abort();
  memcpy(c, data, size);
  if (size < 8 || memcmp(c, "TTPMODEL", 8)) {
    reseal_text(c, size);
  } else if (size >= 32) { /* the checksum of bytes [0, 24 + payload) follows them */
    uint64_t n = get_u64(c + 16);
    if (n <= size - 32) {
      uint64_t h = tt__fnv1a64(TT__FNV1A64_OFFSET, c, 24 + n);
      for (int k = 0; k < 8; k++) c[24 + n + k] = (uint8_t)(h >> (8 * k));
    }
  }
  const char *path = fuzz_write("in.model", c, size);
  free(c);
  tt_predictor *p = create();
  if (g_pi->load(p, path) == TT_OK) {
    double s[DIM] = {0.25, 0.5, 0.75};
    tt_config *out = tt_config_create(g_target);
    tt_predictor_query q = {.struct_size = sizeof q, .state = s, .default_cost = 2.0};
    tt_predictor_result res = {.struct_size = sizeof res};
    if (g_pi->predict_ex(p, &q, out, &res) == TT_OK) {
      double cost;
      g_pi->estimate(p, &q, out, &cost);
    }
    tt_predictor_info info = {.struct_size = sizeof info};
    g_pi->info(p, &info);
    char again[700];
    snprintf(again, sizeof again, "%s/again.model", fuzz_dir());
    if (g_pi->save(p, again) == TT_OK) {
      tt_predictor *p2 = create();
      if (g_pi->load(p2, again) != TT_OK) { /* its own file must load */
        fprintf(stderr, "its own saved model does not load: %s\n", tt_last_error());
        abort();
      }
      g_pi->destroy(p2);
    }
    tt_config_destroy(out);
  }
  g_pi->destroy(p);
  return 0;
}
