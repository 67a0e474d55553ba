/* Helpers for the predictor tests: loading a predictor plugin, a small mixed target space,
 * and the model-file checks both plugins must pass (bit-exact round trip; another space, a
 * truncated, corrupt or newer file, another model kind: a clear error and the model left as
 * it was). */
#ifndef TT_PREDICTOR_UTIL_H
#define TT_PREDICTOR_UTIL_H

#include <tunetrace/loader.h>
#include <tunetrace/predictor.h>

#include "tt_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <tt_util/hash.h>
#include <tt_util/rng.h>

static void pu_quiet(tt_log_level level, const char *plugin, const char *fmt, ...) {
  (void)level, (void)plugin, (void)fmt;
}
static const tt_host pu_host = {.struct_size = sizeof(tt_host),
                                .abi_major = TT_ABI_MAJOR,
                                .abi_minor = TT_ABI_MINOR,
                                .host_name = "predictor test",
                                .host_version = "0",
                                .log = pu_quiet};

/* Loads a predictor by name from TT_PLUGIN_PATH; exits the test if it cannot. */
static const tt_predictor_iface *pu_load(tt_registry **reg, const char *name) {
  *reg = tt_registry_create(&pu_host);
  tt_loaded_plugin *p = NULL;
  if (tt_registry_load(*reg, name, &p) != TT_OK) {
    fprintf(stderr, "FAIL: cannot load %s: %s\n", name, tt_last_error());
    exit(1);
  }
  const tt_predictor_iface *pi = tt_loaded_plugin_iface(p);
  CHECK(TT_PREDICTOR_HAS(pi, create_ex) && TT_PREDICTOR_HAS(pi, observe_ex) &&
        TT_PREDICTOR_HAS(pi, predict_ex) && TT_PREDICTOR_HAS(pi, info) &&
        TT_PREDICTOR_HAS(pi, estimate));
  return pi;
}

/* Target: an INT, a log FLOAT, a 3-valued NOM, a bool (the shapes of accel_embree's space). */
static tt_space *pu_target(const char *name) {
  tt_space *s = tt_space_create(name, "1.0.0");
  static const int64_t q[] = {1, 2, 3};
  tt_space_add_int(s, "leaf", 1, 32, 8, "int");
  tt_space_add_float(s, "cost", 0.1, 10.0, 1.0, 1, "log float");
  tt_space_add_nom_int(s, "quality", q, 3, 1, "nom");
  tt_space_add_nom_bool(s, "fast", 0, "bool");
  return s;
}

static tt_config *pu_config(const tt_space *s, int64_t leaf, double cost, int q_index, int fast) {
  tt_config *c = tt_config_create(s);
  tt_config_set_number(c, 0, (double)leaf);
  tt_config_set_number(c, 1, cost);
  tt_config_set_index(c, 2, (size_t)q_index);
  tt_config_set_index(c, 3, (size_t)fast);
  return c;
}

static tt_predictor *pu_create(const tt_predictor_iface *pi, const tt_space *target, uint32_t dim,
                               const char *state_space, const tt_config *settings, uint64_t seed) {
  tt_predictor_setup su = {.struct_size = sizeof su,
                           .target = target,
                           .state_dim = dim,
                           .state_space = state_space,
                           .settings = settings,
                           .seed = seed};
  tt_predictor *p = NULL;
  CHECK_MSG(pi->create_ex(&su, &p) == TT_OK, "%s", tt_last_error());
  return p;
}

/* The bytes of a model file (free()), their count in *n; -1 when it cannot be read. */
static unsigned char *pu_read(const char *path, long *n) {
  size_t len = 0;
  unsigned char *b = (unsigned char *)tt_test_read_file(path, &len);
  *n = b ? (long)len : -1;
  return b;
}

static void pu_write(const char *path, const unsigned char *b, long n) {
  FILE *f = fopen(path, "wb");
  if (f) {
    fwrite(b, 1, (size_t)n, f);
    fclose(f);
  }
}

/* FNV-1a 64 of the model container (to forge a valid checksum on an edited file). */
static inline uint64_t pu_fnv(const unsigned char *p, size_t n) {
  return tt__fnv1a64(TT__FNV1A64_OFFSET, p, n);
}
static inline void pu_reseal(unsigned char *b, long n) {
  uint64_t h = pu_fnv(b, (size_t)n - 8);
  for (int i = 0; i < 8; i++) b[n - 8 + i] = (unsigned char)(h >> (8 * i));
}

/* Predictions of `p` for `count` pseudo-random states, as configuration JSON joined. */
static inline char *pu_predictions(const tt_predictor_iface *pi, const tt_predictor *p,
                                   const tt_space *target, uint32_t dim, int count) {
  size_t cap = 1 << 16, len = 0;
  char *out = malloc(cap);
  out[0] = 0;
  uint64_t x = 99;
  double *state = malloc(dim * sizeof(double));
  tt_config *c = tt_config_create(target);
  for (int k = 0; k < count; k++) {
    for (uint32_t i = 0; i < dim; i++) {
      state[i] = tt__u64_to_unit(tt__splitmix64(&x));
    }
    tt_predictor_query q = {.struct_size = sizeof q, .state = state, .default_cost = 10.0};
    tt_predictor_result r = {.struct_size = sizeof r};
    if (pi->predict_ex(p, &q, c, &r) != TT_OK) break;
    char *j = tt_config_to_json(c);
    size_t need = strlen(j) + 64;
    if (len + need >= cap) out = realloc(out, cap = 2 * cap + need);
    len += (size_t)snprintf(out + len, cap - len, "%s %.17g %.17g;", j, r.expected_cost, r.value);
    tt_free(j);
  }
  free(state);
  tt_config_destroy(c);
  return out;
}

/* The model-file properties: `p` (trained) saved to dir/model.ttpm; `other` is a predictor
 * plugin of another kind (its file must be refused by pi); pi reads format versions 1 to
 * `max_version`. */
static inline void pu_check_files(const tt_predictor_iface *pi, tt_predictor *p,
                                  const tt_space *target, uint32_t dim, const char *state_space,
                                  const char *dir, const tt_predictor_iface *other,
                                  const tt_config *settings, unsigned max_version) {
  char path[4200], path2[4200], bad[4200];
  snprintf(path, sizeof path, "%s/model.ttpm", dir);
  snprintf(path2, sizeof path2, "%s/model2.ttpm", dir);
  snprintf(bad, sizeof bad, "%s/bad.ttpm", dir);
  CHECK_MSG(pi->save(p, path) == TT_OK, "%s", tt_last_error());
  char *before = pu_predictions(pi, p, target, dim, 300);

  /* round trip: a fresh model loaded from the file predicts the same bits, saves the same bytes */
  tt_predictor *q = pu_create(pi, target, dim, state_space, settings, 4242);
  CHECK_MSG(pi->load(q, path) == TT_OK, "%s", tt_last_error());
  char *after = pu_predictions(pi, q, target, dim, 300);
  CHECK_MSG(!strcmp(before, after), "predictions differ after load");
  CHECK(pi->save(q, path2) == TT_OK);
  long n1, n2;
  unsigned char *b1 = pu_read(path, &n1), *b2 = pu_read(path2, &n2);
  CHECK_MSG(n1 > 0 && n1 == n2 && !memcmp(b1, b2, (size_t)n1), "second save differs (%ld vs %ld)",
            n1, n2);
  tt_predictor_info i1 = {.struct_size = sizeof i1}, i2 = {.struct_size = sizeof i2};
  pi->info(p, &i1);
  pi->info(q, &i2);
  CHECK(i1.entries == i2.entries && i1.observations == i2.observations && i1.format_version >= 1);
  free(b2);

  /* every truncation is refused, naming the file, and leaves q as it was */
  for (long cut = 0; cut < n1; cut += (cut < 64 ? 1 : 1 + n1 / 97)) {
    pu_write(bad, b1, cut);
    tt_status st = pi->load(q, bad);
    CHECK_MSG(st != TT_OK, "a file cut at %ld of %ld bytes loaded", cut, n1);
    CHECK_CONTAINS(tt_last_error(), bad);
  }
  /* a flipped byte anywhere: the checksum */
  for (long at = 0; at < n1; at += 1 + n1 / 61) {
    unsigned char *c = malloc((size_t)n1);
    memcpy(c, b1, (size_t)n1);
    c[at] ^= 0x5a;
    pu_write(bad, c, n1);
    CHECK_MSG(pi->load(q, bad) != TT_OK, "a byte flipped at %ld loaded", at);
    CHECK_CONTAINS(tt_last_error(), bad);
    if (at >= 24 && at < n1 - 8) CHECK_CONTAINS(tt_last_error(), "corrupt");
    free(c);
  }
  /* a newer format version (with a valid checksum): refused naming both versions */
  {
    unsigned char *c = malloc((size_t)n1);
    memcpy(c, b1, (size_t)n1);
    c[8] = 77;
    pu_reseal(c, n1);
    pu_write(bad, c, n1);
    CHECK(pi->load(q, bad) == TT_ERR_UNSUPPORTED);
    CHECK_CONTAINS(tt_last_error(), "format version 77");
    char range[64];
    snprintf(range, sizeof range, "versions 1 to %u", max_version);
    CHECK_CONTAINS(tt_last_error(), range);
    CHECK_CONTAINS(tt_last_error(), "newer");
    free(c);
  }
  /* nothing after the sealed bytes is read: bytes appended to the file (as they are, or
   * counted in the header's payload length and resealed, so the checksum passes) */
  {
    static const char tail[] = "configs 1 0";
    long m = n1 + (long)sizeof tail - 1;
    unsigned char *c = malloc((size_t)m);
    memcpy(c, b1, (size_t)n1);
    memcpy(c + n1, tail, sizeof tail - 1);
    pu_write(bad, c, m);
    CHECK(pi->load(q, bad) == TT_ERR_PARSE);
    CHECK_CONTAINS(tt_last_error(), bad);
    CHECK_CONTAINS(tt_last_error(), "padded");
    /* inside the payload: the payload grows by the tail, the checksum moves behind it */
    memcpy(c, b1, (size_t)n1 - 8);
    memcpy(c + n1 - 8, tail, sizeof tail - 1);
    uint64_t len = 0;
    for (int i = 0; i < 8; i++) len |= (uint64_t)c[16 + i] << (8 * i);
    len += sizeof tail - 1;
    for (int i = 0; i < 8; i++) c[16 + i] = (unsigned char)(len >> (8 * i));
    pu_reseal(c, m);
    pu_write(bad, c, m);
    CHECK(pi->load(q, bad) == TT_ERR_PARSE);
    CHECK_CONTAINS(tt_last_error(), bad);
    CHECK_CONTAINS(tt_last_error(), "11 bytes after the");
    free(c);
  }
  /* valid checksum but a garbage payload (every payload byte flipped in turn, resealed):
   * refused or, where the byte is e.g. a cost bit, loaded; never a crash */
  for (long at = 24; at < n1 - 8; at += 1 + n1 / 200) {
    unsigned char *c = malloc((size_t)n1);
    memcpy(c, b1, (size_t)n1);
    c[at] ^= 0xff;
    pu_reseal(c, n1);
    pu_write(bad, c, n1);
    tt_predictor *z = pu_create(pi, target, dim, state_space, settings, 1);
    if (pi->load(z, bad) != TT_OK) CHECK_CONTAINS(tt_last_error(), bad);
    pi->destroy(z);
    free(c);
  }
  char *still = pu_predictions(pi, q, target, dim, 300);
  CHECK_MSG(!strcmp(before, still), "a refused load changed the model");
  free(still);

  /* another parameter space: the message shows both spaces */
  tt_space *t2 = tt_space_create(tt_space_plugin(target), "1.0.0");
  tt_space_add_int(t2, "leaf", 1, 64, 8, "int (another range)");
  tt_space_add_float(t2, "cost", 0.1, 10.0, 1.0, 1, "log float");
  static const int64_t qv[] = {1, 2, 3};
  tt_space_add_nom_int(t2, "quality", qv, 3, 1, "nom");
  tt_space_add_nom_bool(t2, "fast", 0, "bool");
  tt_predictor *w = pu_create(pi, t2, dim, state_space, NULL, 1);
  CHECK(pi->load(w, path) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), path);
  CHECK_CONTAINS(tt_last_error(), "another parameter space");
  CHECK_CONTAINS(tt_last_error(), "leaf INT[1,32]");
  CHECK_CONTAINS(tt_last_error(), "leaf INT[1,64]");
  pi->destroy(w);
  tt_space_destroy(t2);
  /* another state space, another state dimension */
  w = pu_create(pi, target, dim, "tt.indicators/1 camera=text scale=log", NULL, 1);
  CHECK(pi->load(w, path) == TT_ERR_INVALID_ARGUMENT);
  CHECK_CONTAINS(tt_last_error(), state_space);
  CHECK_CONTAINS(tt_last_error(), "camera=text scale=log");
  pi->destroy(w);
  w = pu_create(pi, target, dim + 1, state_space, NULL, 1);
  CHECK(pi->load(w, path) == TT_ERR_INVALID_ARGUMENT);
  pi->destroy(w);
  /* another model kind */
  if (other) {
    tt_predictor *o = pu_create(other, target, dim, state_space, NULL, 1);
    CHECK(other->load(o, path) == TT_ERR_INVALID_ARGUMENT);
    CHECK_CONTAINS(tt_last_error(), "was written by");
    other->destroy(o);
  }
  /* not a model; a missing file; a folder */
  pu_write(bad, (const unsigned char *)"{\"json\": true}", 14);
  CHECK(pi->load(q, bad) == TT_ERR_PARSE);
  CHECK_CONTAINS(tt_last_error(), "not a tunetrace predictor model");
  snprintf(bad, sizeof bad, "%s/missing.ttpm", dir);
  CHECK(pi->load(q, bad) == TT_ERR_IO);
  CHECK(pi->load(q, dir) == TT_ERR_IO);
  /* a failed save (no such folder) reports the file */
  snprintf(bad, sizeof bad, "%s/no/such/dir/m.ttpm", dir);
  CHECK(pi->save(q, bad) == TT_ERR_IO);
  CHECK_CONTAINS(tt_last_error(), bad);
  /* saving over an existing model replaces it atomically: no temporary file is left */
  CHECK(pi->save(q, path2) == TT_OK);
  char cmd[4400];
  snprintf(cmd, sizeof cmd, "ls -a '%s' | grep -c tmp >/dev/null", dir);
  CHECK(system(cmd) != 0);
  free(b1);
  free(before);
  free(after);
  pi->destroy(q);
}

#endif
