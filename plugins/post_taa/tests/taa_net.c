/* post_taa network inference (white-box: compiles the plugin's sources in):
 * - the SIMD path equals the plain scalar reference on random weights (every shape variant:
 *   12/6 channels, hidden 0/5/8, 2..4 layers, jitter sets on/off);
 * - the shipped weights reproduce the PyTorch golden outputs (tests/data/taa) to 1e-4;
 * - weights file errors (bad magic, wrong version, truncated, corrupted, bad shapes) give
 *   messages naming the file and the problem;
 * - Catmull-Rom reprojection against an analytic shift;
 * - the result does not depend on the thread count or the band split: 1, 2 and 3 threads
 *   and forced band heights give bit-identical outputs and states (memcmp);
 * - all of it for both kernel-layer algorithms of the fast path (Winograd F(2x2, 5x5) and
 *   direct), the vs-reference checks also on forced AVX2 and on the portable kernels;
 * - the kernels run are the best the CPU has, whichever compiler built them, and the
 *   AVX-512 kernels give the same bits as the AVX2 ones. */
#include "tt_test.h"

#include "taa_internal.h"

#include <stdint.h>

#include <tunetrace/camera.h>
#include <tt_util/hash.h>

/* The fast path's 5x5-layer algorithms (tt__net_state.winograd). */
static const char *wino_name(int wino) {
  return wino == 2 ? "winograd-4x4" : wino == 1 ? "winograd-2x2" : "direct";
}

/* ---- a tiny weights writer (the format of README.md) ---- */

typedef struct buf {
  unsigned char *p;
  size_t n, cap;
} buf;

/* Appends bytes. */
static void put(buf *b, const void *d, size_t n) {
  if (b->n + n > b->cap) {
    b->cap = (b->n + n) * 2;
    b->p = realloc(b->p, b->cap);
  }
  memcpy(b->p + b->n, d, n);
  b->n += n;
}
static void put_u32(buf *b, uint32_t v) { put(b, &v, 4); } /* tests run on LE hosts */
static void put_f32(buf *b, float v) { put(b, &v, 4); }

static uint32_t rng_state = 12345;
/* Uniform in [-1, 1) (xorshift). */
static float rnd(void) {
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 17;
  rng_state ^= rng_state << 5;
  return (float)(rng_state >> 8) / 8388608.0f - 1.0f;
}

/* Model shape for the writer. */
typedef struct shape {
  uint32_t width, hidden, body, ks[4], sets_body[4], sets_k, sets_h;
  uint32_t flags; /* TT__NET_FLAG_* (0: a version-1 file) */
} shape;

/* Serialises a random model of `s`; layer weights ~ U(-1,1) * scale. */
static buf write_model(const shape *s) {
  buf b = {0};
  uint32_t layers = s->body + 1 + (s->hidden ? 1 : 0);
  uint32_t in = 9 + s->hidden + ((s->flags & TT__NET_FLAG_REJECT) ? 1u : 0u);
  put(&b, "TTAANET\0", 8);
  put_u32(&b, s->flags ? 2 : 1);
  put_u32(&b, 48 + 24 * layers);
  put_u32(&b, in);
  put_u32(&b, s->width);
  put_u32(&b, s->hidden);
  put_u32(&b, 5);
  put_u32(&b, 8);
  put_u32(&b, layers);
  put_f32(&b, 0.125f);
  put_u32(&b, s->flags);
  uint32_t rec[8][6];
  uint32_t cin = in;
  for (uint32_t i = 0; i < s->body; i++) {
    uint32_t r[6] = {1, cin, s->width, s->ks[i], s->sets_body[i], 1};
    memcpy(rec[i], r, sizeof r);
    cin = s->width;
  }
  uint32_t rk[6] = {2, s->width, 50, 5, s->sets_k, 2};
  memcpy(rec[s->body], rk, sizeof rk);
  if (s->hidden) {
    uint32_t rh[6] = {3, s->width, s->hidden, 1, s->sets_h, 0};
    memcpy(rec[s->body + 1], rh, sizeof rh);
  }
  for (uint32_t i = 0; i < layers; i++)
    for (int k = 0; k < 6; k++) put_u32(&b, rec[i][k]);
  size_t start = b.n;
  for (uint32_t i = 0; i < layers; i++) {
    uint32_t *r = rec[i];
    size_t nw = (size_t)r[4] * r[2] * r[1] * r[3] * r[3], nb = (size_t)r[4] * r[2];
    float scale = 1.2f / sqrtf((float)(r[1] * r[3] * r[3]));
    for (size_t k = 0; k < nw; k++) put_f32(&b, rnd() * scale);
    for (size_t k = 0; k < nb; k++) put_f32(&b, 0.1f * rnd());
  }
  put_u32(&b, tt__fnv1a32(b.p + start, b.n - start));
  return b;
}

/* Random frame inputs. */
static void random_frame(uint32_t w, uint32_t h, float *color, float *depth, float *motion) {
  for (size_t i = 0; i < (size_t)w * h; i++) {
    for (int c = 0; c < 3; c++) color[3 * i + c] = 1.0f + rnd();
    depth[i] = 5.0f + 4.0f * rnd();
    motion[2 * i] = 2.5f * rnd();
    motion[2 * i + 1] = 2.5f * rnd();
  }
}

/* SIMD path == scalar reference for one shape over 3 frames; `wino`: the fast path's kernel
 * layer by Winograd F(2x2, 5x5) (1) or direct (0). */
static void check_fast_vs_reference(const shape *s, const char *label, int wino) {
  const uint32_t w = 23, h = 17;
  buf b = write_model(s);
  tt__net_model m;
  tt_status st = tt__net_parse(b.p, b.n, label, &m);
  CHECK_MSG(st == TT_OK, "%s: %s", label, tt_last_error());
  free(b.p);
  if (st != TT_OK) return;
  tt__net_state fast, ref;
  CHECK(tt__net_state_init(&fast, &m, w, h) == TT_OK);
  CHECK(tt__net_state_init(&ref, &m, w, h) == TT_OK);
  ref.reference = 1;
  fast.winograd = wino;
  size_t n = (size_t)w * h;
  float *color = malloc(n * 3 * 4), *depth = malloc(n * 4), *motion = malloc(n * 2 * 4);
  float *o1 = malloc(n * 3 * 4), *o2 = malloc(n * 3 * 4), *zprev = malloc(n * 4);
  double worst = 0.0, worst_state = 0.0;
  for (uint32_t f = 0; f < 3; f++) {
    random_frame(w, h, color, depth, motion);
    for (size_t i = 0; i < n; i++) zprev[i] = 5.0f + 4.0f * rnd(); /* some rejected */
    tt__net_frame fr = {.color = color,
                        .depth = depth,
                        .motion = motion,
                        .prev_depth = zprev,
                        .jitter_index = 5 + f};
    tt_jitter_halton23(fr.jitter_index, fr.jitter);
    tt__net_process_frame(&fast, &m, tt_default_host(), &fr, o1);
    tt__net_process_frame(&ref, &m, tt_default_host(), &fr, o2);
    if (m.flags & TT__NET_FLAG_REJECT) {
      /* the fast path's inline (vectorised) tests == the reference path's masks, bit for bit */
      uint32_t differ = 0, rejected = 0;
      /* (without the reset flag the fast path does not compute the RESET bit) */
      uint8_t bits = (m.flags & TT__NET_FLAG_RESET) ? 0xff : (uint8_t)~TT__TAA_REJECT_RESET;
      for (size_t i = 0; i < n; i++) {
        differ += (fast.reject[i] & bits) != (ref.reject[i] & bits);
        rejected += (ref.reject[i] & TT__TAA_REJECT_RAW) != 0;
      }
      CHECK_MSG(differ == 0, "%s frame %u: rejection masks differ in %u pixels", label, f, differ);
      if (f == 2) printf("%s: rejection masks equal (%u of %zu rejected)\n", label, rejected, n);
    }
    for (size_t i = 0; i < n * 3; i++) worst = fmax(worst, fabs(o1[i] - o2[i]) / (1 + fabs(o2[i])));
    for (size_t i = 0; i < n * fast.state_ch; i++)
      worst_state = fmax(worst_state, fabs(fast.state[i] - ref.state[i]));
  }
  printf("%s (%s, %s): fast vs reference: state %.2e, output %.2e\n", label, wino_name(wino),
         tt__net_fast_isa(), worst_state, worst);
  CHECK_MSG(worst_state < 1e-4, "%s: state differs by %g", label, worst_state);
  CHECK_MSG(worst < 1e-3, "%s: output differs by %g", label, worst);
  free(color), free(depth), free(motion), free(o1), free(o2), free(zprev);
  tt__net_state_free(&fast);
  tt__net_state_free(&ref);
  tt__net_free(&m);
}

static void test_fast_vs_reference(void) {
  shape thesis12 = {12, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, 0};
  shape thesis6 = {6, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, 0};
  shape no_hidden = {12, 0, 3, {3, 3, 5}, {1, 1, 1}, 1, 1, 0};
  shape hidden8_all = {12, 8, 3, {3, 3, 5}, {8, 8, 8}, 8, 8, 0};
  shape two = {12, 3, 1, {3}, {8}, 8, 1, 0};
  shape wide = {40, 5, 2, {3, 5}, {1, 8}, 8, 1, 0};
  shape reject6 = {6, 0, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, TT__NET_FLAG_REJECT};
  shape reset12 = {12, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 8, TT__NET_FLAG_REJECT | TT__NET_FLAG_RESET};
  /* Both kernel-layer algorithms, on the best instruction set (AVX-512: 16-lane code), on
   * forced AVX2 (8 lanes) and on the portable code (direct convolutions only); on other
   * machines the runs take the paths they have. */
  const char *isa0 = getenv("TT_POST_TAA_ISA");
  char *saved = isa0 ? strdup(isa0) : NULL;
  for (int pass = 0; pass < 3; pass++) {
    if (pass) setenv("TT_POST_TAA_ISA", pass == 1 ? "avx2" : "generic", 1);
    for (int wino = 2; wino >= 0; wino--) {
      check_fast_vs_reference(&thesis12, "thesis-12", wino);
      check_fast_vs_reference(&thesis6, "thesis-6", wino);
      check_fast_vs_reference(&no_hidden, "hidden-0", wino);
      check_fast_vs_reference(&hidden8_all, "hidden-8-all-sets", wino);
      check_fast_vs_reference(&two, "2-layers", wino);
      check_fast_vs_reference(&wide, "width-40", wino);
      check_fast_vs_reference(&reject6, "rejection-input-6", wino);
      check_fast_vs_reference(&reset12, "rejection-reset-12", wino);
    }
  }
  if (saved) setenv("TT_POST_TAA_ISA", saved, 1);
  else unsetenv("TT_POST_TAA_ISA");
  free(saved);
}

/* Sets TT_POST_TAA_ISA (NULL: unsets it). */
static void set_isa(const char *isa) {
  if (isa) setenv("TT_POST_TAA_ISA", isa, 1);
  else unsetenv("TT_POST_TAA_ISA");
}

/* The kernels the fast path runs are the best the CPU has, whichever compiler built them
 * (the sanitizer build is clang's: its AVX2 / AVX-512 code must run there too), and
 * TT_POST_TAA_ISA=avx2|generic caps the choice. */
static void test_isa_dispatch(void) {
  int v3 = 0, v4 = 0;
#if defined(__x86_64__)
  __builtin_cpu_init();
  v3 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  v4 = v3 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
#endif
  const char *isa0 = getenv("TT_POST_TAA_ISA");
  char *saved = isa0 ? strdup(isa0) : NULL;
  const struct {
    const char *force, *want;
  } cases[] = {{NULL, v4   ? "avx512"
                      : v3 ? "avx2"
                           : "generic"},
               {"avx2", v3 ? "avx2" : "generic"},
               {"generic", "generic"}};
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
    set_isa(cases[k].force);
    const char *got = tt__net_fast_isa();
    printf("fast path kernels, TT_POST_TAA_ISA=%s: %s (expected %s)\n",
           cases[k].force ? cases[k].force : "(unset)", got, cases[k].want);
    CHECK_MSG(strcmp(got, cases[k].want) == 0, "TT_POST_TAA_ISA=%s: kernels %s, expected %s",
              cases[k].force ? cases[k].force : "(unset)", got, cases[k].want);
  }
  set_isa(saved);
  free(saved);
}

/* The AVX-512 kernels give the same bits as the AVX2 ones (the 16-lane code repeats the
 * 8-lane code's operations per lane in the same order): outputs and states of 2 frames of
 * one shape (a fresh start, then one with history and rejection tests), compared with
 * memcmp. 150 x 21: two 64-column chunks and a tail of 22, so the AVX-512 code's 16- and
 * 8-lane groups both run; two bands on 2 threads. */
static void check_isa_bits(const shape *s, const char *label, int wino) {
  const uint32_t w = 150, h = 21;
  buf b = write_model(s);
  tt__net_model m;
  tt_status st = tt__net_parse(b.p, b.n, label, &m);
  CHECK_MSG(st == TT_OK, "%s: %s", label, tt_last_error());
  free(b.p);
  if (st != TT_OK) return;
  tt__net_state best, avx2;
  CHECK(tt__net_state_init(&best, &m, w, h) == TT_OK);
  CHECK(tt__net_state_init(&avx2, &m, w, h) == TT_OK);
  best.winograd = avx2.winograd = wino;
  size_t n = (size_t)w * h;
  float *color = malloc(n * 3 * 4), *depth = malloc(n * 4), *motion = malloc(n * 2 * 4);
  float *o1 = malloc(n * 3 * 4), *o2 = malloc(n * 3 * 4), *zprev = malloc(n * 4);
  uint32_t differ = 0;
  const char *isa_best = "", *isa_avx2 = "";
  for (uint32_t f = 0; f < 2; f++) {
    random_frame(w, h, color, depth, motion);
    for (size_t i = 0; i < n; i++) zprev[i] = 5.0f + 4.0f * rnd();
    tt__net_frame fr = {.color = color,
                        .depth = depth,
                        .motion = motion,
                        .prev_depth = zprev,
                        .jitter_index = 3 + f};
    tt_jitter_halton23(fr.jitter_index, fr.jitter);
    set_isa(NULL);
    isa_best = tt__net_fast_isa();
    tt__net_process_frame(&best, &m, tt_default_host(), &fr, o1);
    set_isa("avx2");
    isa_avx2 = tt__net_fast_isa();
    tt__net_process_frame(&avx2, &m, tt_default_host(), &fr, o2);
    differ += memcmp(o1, o2, n * 3 * 4) != 0;
    differ += memcmp(best.state, avx2.state, n * best.state_ch * 4) != 0;
  }
  printf("%s (%s): %s vs %s: %s\n", label, wino_name(wino), isa_best, isa_avx2,
         differ ? "DIFFERENT" : "bit-identical");
  CHECK_MSG(differ == 0, "%s (%s): %s and %s results differ", label, wino_name(wino), isa_best,
            isa_avx2);
  free(color), free(depth), free(motion), free(o1), free(o2), free(zprev);
  tt__net_state_free(&best);
  tt__net_state_free(&avx2);
  tt__net_free(&m);
}

static void test_isa_bits(void) {
  shape thesis12 = {12, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, 0};
  shape thesis6 = {6, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, 0};
  shape no_hidden = {12, 0, 3, {3, 3, 5}, {1, 1, 1}, 1, 1, 0};
  shape hidden8_all = {12, 8, 3, {3, 3, 5}, {8, 8, 8}, 8, 8, 0};
  shape two = {12, 3, 1, {3}, {8}, 8, 1, 0};
  shape wide = {40, 5, 2, {3, 5}, {1, 8}, 8, 1, 0};
  shape reject6 = {6, 0, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, TT__NET_FLAG_REJECT};
  shape reset12 = {12, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 8, TT__NET_FLAG_REJECT | TT__NET_FLAG_RESET};
  const char *isa0 = getenv("TT_POST_TAA_ISA");
  char *saved = isa0 ? strdup(isa0) : NULL;
  for (int wino = 2; wino >= 0; wino--) {
    check_isa_bits(&thesis12, "thesis-12", wino);
    check_isa_bits(&thesis6, "thesis-6", wino);
    check_isa_bits(&no_hidden, "hidden-0", wino);
    check_isa_bits(&hidden8_all, "hidden-8-all-sets", wino);
    check_isa_bits(&two, "2-layers", wino);
    check_isa_bits(&wide, "width-40", wino);
    check_isa_bits(&reject6, "rejection-input-6", wino);
    check_isa_bits(&reset12, "rejection-reset-12", wino);
  }
  set_isa(saved);
  free(saved);
}

/* Winograd vs direct 5x5 layers on frames with odd sizes (tiles cut by the image edge on
 * the right and bottom), several column chunks, and tiny frames (one row or column): both
 * close to each other. */
static void winograd_vs_direct(const tt__net_model *mp, uint32_t w, uint32_t h, int level) {
  tt__net_state sw, sd;
  CHECK(tt__net_state_init(&sw, mp, w, h) == TT_OK);
  CHECK(tt__net_state_init(&sd, mp, w, h) == TT_OK);
  sw.winograd = level;
  sd.winograd = 0;
  size_t n = (size_t)w * h;
  float *color = malloc(n * 3 * 4), *depth = malloc(n * 4), *motion = malloc(n * 2 * 4);
  float *o1 = malloc(n * 3 * 4), *o2 = malloc(n * 3 * 4);
  double worst = 0.0, worst_state = 0.0;
  for (uint32_t f = 0; f < 4; f++) {
    random_frame(w, h, color, depth, motion);
    tt__net_process(&sw, mp, tt_default_host(), color, depth, motion, f, o1);
    tt__net_process(&sd, mp, tt_default_host(), color, depth, motion, f, o2);
    for (size_t i = 0; i < n * 3; i++) worst = fmax(worst, fabs(o1[i] - o2[i]) / (1 + fabs(o2[i])));
    for (size_t i = 0; i < n * sw.state_ch; i++)
      worst_state = fmax(worst_state, fabs(sw.state[i] - sd.state[i]));
  }
  printf("%s vs direct (%s, %ux%u, 4 frames): state %.2e, output %.2e\n", wino_name(level),
         tt__net_fast_isa(), w, h, worst_state, worst);
  CHECK_MSG(worst_state < 1e-4, "winograd vs direct %ux%u: state differs by %g", w, h, worst_state);
  CHECK_MSG(worst < 1e-3, "winograd vs direct %ux%u: output differs by %g", w, h, worst);
  free(color), free(depth), free(motion), free(o1), free(o2);
  tt__net_state_free(&sw);
  tt__net_state_free(&sd);
}

static void test_winograd_vs_direct(void) {
  shape thesis12 = {12, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, 0};
  buf b = write_model(&thesis12);
  tt__net_model m;
  CHECK_MSG(tt__net_parse(b.p, b.n, "wino", &m) == TT_OK, "%s", tt_last_error());
  free(b.p);
  const uint32_t sizes[][2] = {{157, 45}, {1, 1}, {3, 2}, {17, 1}, {2, 5}, {33, 3}};
  for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++)
    for (int level = 2; level >= 1; level--)
      winograd_vs_direct(&m, sizes[k][0], sizes[k][1], level);
  tt__net_free(&m);
}

/* Runs 4 frames of a random 12-channel model at w x h with `threads` threads and bands of
 * `band_rows` rows (0: automatic); returns the outputs and final state (caller frees). */
static void run_threads(const tt__net_model *m, uint32_t w, uint32_t h, uint32_t threads,
                        uint32_t band_rows, uint32_t tile_cols, int wino, float **out,
                        float **state) {
  float *zprev = malloc((size_t)w * h * 4);
  tt_default_host_set_threads(threads);
  tt__net_state s;
  CHECK(tt__net_state_init(&s, m, w, h) == TT_OK);
  s.winograd = wino;
  s.band_rows = band_rows;
  s.tile_cols = tile_cols;
  size_t n = (size_t)w * h;
  float *color = malloc(n * 3 * 4), *depth = malloc(n * 4), *motion = malloc(n * 2 * 4);
  *out = malloc(n * 3 * 4 * 4);
  rng_state = 777;
  for (uint32_t f = 0; f < 4; f++) {
    random_frame(w, h, color, depth, motion);
    for (size_t i = 0; i < n; i++) zprev[i] = 5.0f + 4.0f * rnd();
    tt__net_frame fr = {
        .color = color, .depth = depth, .motion = motion, .prev_depth = zprev, .jitter_index = f};
    tt_jitter_halton23(f, fr.jitter);
    tt__net_process_frame(&s, m, tt_default_host(), &fr, *out + f * n * 3);
  }
  *state = malloc(n * 8 * 4);
  memset(*state, 0, n * 8 * 4);
  memcpy(*state, s.state, n * s.state_ch * 4);
  free(color), free(depth), free(motion), free(zprev);
  tt__net_state_free(&s);
}

/* 1 vs 2 vs 3 threads and several band splits: bit-identical (each pixel is computed by the
 * same operations whatever band it falls in; halo rows are recomputed identically). */
static void thread_invariance(const shape *sh, const char *label) {
  buf b = write_model(sh);
  tt__net_model m;
  CHECK_MSG(tt__net_parse(b.p, b.n, "threads", &m) == TT_OK, "%s", tt_last_error());
  free(b.p);
  const uint32_t w = 201, h = 67; /* not multiples of 8 or 16: column tails, uneven bands */
  size_t n = (size_t)w * h;
  /* Winograd: odd band heights start bands on odd rows (half a tile pair). */
  for (int wino = 2; wino >= 0; wino--) {
    float *o1, *s1;
    run_threads(&m, w, h, 1, 0, 0, wino, &o1, &s1);
    struct {
      uint32_t threads, rows, cols;
    } cases[] = {{2, 0, 0},   {3, 0, 0},  {2, 16, 0}, {2, 17, 64},
                 {1, 5, 128}, {2, 0, 64}, {3, 3, 64}, {2, 1, 0}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
      float *o2, *s2;
      run_threads(&m, w, h, cases[k].threads, cases[k].rows, cases[k].cols, wino, &o2, &s2);
      int same_out = memcmp(o1, o2, n * 3 * 4 * 4) == 0;
      int same_state = memcmp(s1, s2, n * 8 * 4) == 0;
      printf("%s %s: threads %u, band rows %u, tile columns %u vs 1 thread: %s\n", label,
             wino_name(wino), cases[k].threads, cases[k].rows, cases[k].cols,
             same_out && same_state ? "bit-identical" : "DIFFERENT");
      CHECK_MSG(same_out && same_state,
                "%s: threads %u band rows %u tile columns %u: results "
                "differ from 1 thread",
                wino_name(wino), cases[k].threads, cases[k].rows, cases[k].cols);
      free(o2), free(s2);
    }
    free(o1), free(s1);
  }
  tt__net_free(&m);
  tt_default_host_set_threads(2);
}

static void test_thread_invariance(void) {
  shape thesis12 = {12, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, 0};
  shape reset6 = {6, 0, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, TT__NET_FLAG_REJECT | TT__NET_FLAG_RESET};
  thread_invariance(&thesis12, "thesis-12");
  thread_invariance(&reset6, "hidden-0-rejection-6");
}

/* The shipped weights `name`.ttw reproduce the PyTorch outputs of
 * tools/taa/export_golden.py (tests/data/taa/golden_`name`.bin). */
static void test_golden(const char *root, const char *name) {
  char wpath[1024], gpath[1024];
  snprintf(wpath, sizeof wpath, "%s/plugins/post_taa/post_taa_%s.ttw", root, name);
  snprintf(gpath, sizeof gpath, "%s/tests/data/taa/golden_%s.bin", root, name);
  size_t wn = 0, gn = 0;
  unsigned char *wdata = (unsigned char *)tt_test_read_file(wpath, &wn),
                *g = (unsigned char *)tt_test_read_file(gpath, &gn);
  CHECK_MSG(wdata && g, "cannot read %s or %s", wpath, gpath);
  if (!wdata || !g) return;
  CHECK(gn > 28 && memcmp(g, "TTAAGLD2", 8) == 0);
  uint32_t hdr[5];
  memcpy(hdr, g + 8, sizeof hdr);
  CHECK_MSG(tt__fnv1a32(wdata, wn) == hdr[0],
            "golden fixture was made from other weights: rerun "
            "tools/taa/export_golden.py after changing %s",
            wpath);
  tt__net_model m;
  CHECK_MSG(tt__net_parse(wdata, wn, wpath, &m) == TT_OK, "%s", tt_last_error());
  uint32_t w = hdr[1], hh = hdr[2], frames = hdr[3], sc = hdr[4];
  CHECK(sc == 3 + m.hidden);
  size_t n = (size_t)w * hh;
  const unsigned char *p = g + 28;
  for (int wino = 2; wino >= 0; wino--) {
    p = g + 28;
    tt__net_state s;
    CHECK(tt__net_state_init(&s, &m, w, hh) == TT_OK);
    s.winograd = wino;
    float *out = malloc(n * 3 * 4);
    double worst_state = 0, worst_out = 0;
    for (uint32_t f = 0; f < frames; f++) {
      uint32_t jit, fresh;
      float jxy[2];
      memcpy(&jit, p, 4);
      memcpy(&fresh, p + 4, 4);
      memcpy(jxy, p + 8, 8);
      p += 16;
      const float *color = (const float *)p, *depth = color + n * 3, *motion = depth + n;
      const float *zprev = motion + n * 2, *want_state = zprev + n, *want_out = want_state + n * sc;
      p = (const unsigned char *)(want_out + n * 3);
      if (fresh) s.valid = 0;
      tt__net_frame fr = {.color = color,
                          .depth = depth,
                          .motion = motion,
                          .prev_depth = zprev,
                          .jitter_index = jit,
                          .jitter = {jxy[0], jxy[1]}};
      tt__net_process_frame(&s, &m, tt_default_host(), &fr, out);
      for (size_t i = 0; i < n * sc; i++)
        worst_state = fmax(worst_state, fabs(s.state[i] - want_state[i]));
      for (size_t i = 0; i < n * 3; i++)
        worst_out = fmax(worst_out, fabs(out[i] - want_out[i]) / (1 + fabs(want_out[i])));
    }
    CHECK((size_t)(p - g) == gn);
    printf("golden %s (%s, %s): %u frames %ux%u: state %.2e (tol 1e-4), linear output rel "
           "%.2e\n",
           name, wino_name(wino), tt__net_fast_isa(), frames, w, hh, worst_state, worst_out);
    CHECK(worst_state < 1e-4);
    CHECK(worst_out < 1e-3);
    free(out);
    tt__net_state_free(&s);
  }
  tt__net_free(&m);
  free(wdata);
  free(g);
}

/* Parsing `b` (modified) fails with `status` and a message containing `needle`. */
static void expect_error(const unsigned char *data, size_t n, tt_status status,
                         const char *needle) {
  tt__net_model m;
  tt_status st = tt__net_parse(data, n, "bad.ttw", &m);
  CHECK_MSG(st == status, "expected %d, got %d (%s)", status, st, tt_last_error());
  if (st == TT_OK) {
    tt__net_free(&m);
    return;
  }
  CHECK_CONTAINS(tt_last_error(), "bad.ttw");
  CHECK_CONTAINS(tt_last_error(), needle);
}

static void test_errors(void) {
  shape s = {6, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, 0};
  buf b = write_model(&s);
  unsigned char *c = malloc(b.n);
  memcpy(c, b.p, b.n);
  c[0] = 'X';
  expect_error(c, b.n, TT_ERR_PARSE, "bad magic");
  expect_error(c, 4, TT_ERR_PARSE, "bad magic");
  memcpy(c, b.p, b.n);
  c[8] = 3;
  expect_error(c, b.n, TT_ERR_UNSUPPORTED, "version 3 is not supported");
  memcpy(c, b.p, b.n);
  c[8] = 2;
  c[44] = 4; /* version 2 with an unknown input flag */
  expect_error(c, b.n, TT_ERR_UNSUPPORTED, "input flags 0x4");
  c[44] = 2; /* history reset without the rejection input */
  expect_error(c, b.n, TT_ERR_UNSUPPORTED, "input flags 0x2");
  c[44] = 1; /* the rejection input needs one more input channel */
  expect_error(c, b.n, TT_ERR_PARSE, "bad model shape");
  expect_error(b.p, b.n - 100, TT_ERR_PARSE, "truncated");
  expect_error(b.p, 30, TT_ERR_PARSE, "truncated header");
  expect_error(b.p, 60, TT_ERR_PARSE, "truncated layer table");
  memcpy(c, b.p, b.n);
  c[b.n - 50] ^= 0x40;
  expect_error(c, b.n, TT_ERR_PARSE, "checksum");
  memcpy(c, b.p, b.n);
  c[48 + 24 + 8] = 7; /* second body layer outputs 7 channels instead of 6 */
  expect_error(c, b.n, TT_ERR_PARSE, "layer 1 (body)");
  memcpy(c, b.p, b.n);
  c[16] = 20; /* in_channels != 9 + hidden */
  expect_error(c, b.n, TT_ERR_PARSE, "bad model shape");
  tt__net_model m;
  CHECK(tt__net_load("/nonexistent/w.ttw", &m) == TT_ERR_IO);
  CHECK_CONTAINS(tt_last_error(), "/nonexistent/w.ttw");
  expect_error(b.p, b.n, TT_OK, ""); /* the intact file parses */
  /* nothing after the checksum is read: bytes appended to a valid file are refused */
  unsigned char *longer = malloc(b.n + 11);
  memcpy(longer, b.p, b.n);
  memcpy(longer + b.n, "configs 1 0", 11);
  expect_error(longer, b.n + 11, TT_ERR_PARSE, "11 trailing bytes after the checksum");
  free(longer);
  free(c);
  free(b.p);
}

/* A model written by the writer parses back to exactly the written numbers: every record
 * field and every weight and bias of every set (byte offsets recomputed here from the
 * format table of README.md, independently of the reader). */
static void check_roundtrip(const shape *s, const char *label) {
  buf b = write_model(s);
  tt__net_model m;
  tt_status st = tt__net_parse(b.p, b.n, label, &m);
  CHECK_MSG(st == TT_OK, "%s: %s", label, tt_last_error());
  if (st != TT_OK) {
    free(b.p);
    return;
  }
  uint32_t layers = s->body + 1 + (s->hidden ? 1 : 0), bad = 0;
  CHECK(m.body_count == s->body && m.hidden == s->hidden && m.width == s->width &&
        m.flags == s->flags && m.in_channels == 9 + s->hidden + (s->flags & 1u));
  size_t off = 48 + 24 * (size_t)layers;
  for (uint32_t i = 0; i < layers; i++) {
    const tt__net_layer *l = i < s->body ? &m.body[i] : i == s->body ? &m.kernel : &m.hid;
    uint32_t rec[6];
    memcpy(rec, b.p + 48 + 24 * i, sizeof rec);
    CHECK_MSG(l->in == rec[1] && l->out == rec[2] && l->ksize == rec[3] && l->sets == rec[4] &&
                  l->activation == rec[5],
              "%s: layer %u record", label, i);
    size_t nw = (size_t)rec[4] * rec[2] * rec[1] * rec[3] * rec[3], nb = (size_t)rec[4] * rec[2];
    for (size_t k = 0; k < nw; k++) bad += memcmp(&l->w[k], b.p + off + 4 * k, 4) != 0;
    off += 4 * nw;
    for (size_t k = 0; k < nb; k++) bad += memcmp(&l->b[k], b.p + off + 4 * k, 4) != 0;
    off += 4 * nb;
  }
  CHECK(off + 4 == b.n);
  printf("round trip %s: %u layers, %zu payload bytes, %u values differ\n", label, layers,
         b.n - 48 - 24 * (size_t)layers - 4, bad);
  CHECK_MSG(bad == 0, "%s: %u weights differ after the round trip", label, bad);
  tt__net_free(&m);
  free(b.p);
}

static void test_roundtrip(void) {
  /* hidden 0 with 8 jitter sets in every layer (12 and 6 channels), and with the
   * rejection input + reset flags (a version-2 file) */
  shape h0_12 = {12, 0, 3, {3, 3, 5}, {8, 8, 8}, 8, 1, 0};
  shape h0_6 = {6, 0, 3, {3, 3, 5}, {8, 8, 8}, 8, 1, 0};
  shape h0_6r = {6, 0, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, TT__NET_FLAG_REJECT | TT__NET_FLAG_RESET};
  check_roundtrip(&h0_12, "hidden0-8sets-12");
  check_roundtrip(&h0_6, "hidden0-8sets-6");
  check_roundtrip(&h0_6r, "hidden0-rejection-6");
}

/* A synthetic disocclusion whose true history is known: a background plane at depth 10
 * and a square at depth 4 (x 12..23, y 8..19) that moves 6 pixels right between frame 0
 * and frame 1 (static camera, jitter 0: motion -6 on the square, 0 elsewhere; prevdepth =
 * each point's own depth). In frame 1 the pixels x 12..17, y 8..18 see background that
 * frame 0 never showed (the square covered it; y 19 has a background sample below): their
 * reprojected history is the square's red, not the truth. The mask must mark exactly that
 * rectangle (RAW and, being wider than 3 x 3, RESET); the reset model's input planes must
 * hold the new frame as the history there (its tonemapped colour, hidden 0) and the
 * rejection channel 1 there, 0 elsewhere; a model without the flags keeps the red history
 * (so the check can fail); the fast and reference paths agree. */
static void test_rejection_disocclusion(void) {
  enum { w = 48, h = 32 };
  const size_t n = (size_t)w * h;
  static float color0[w * h * 3], color1[w * h * 3], depth0[w * h], depth1[w * h],
      motion1[w * h * 2], zprev1[w * h], motion0[w * h * 2], out[w * h * 3];
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      size_t i = (size_t)y * w + x;
      int sq0 = x >= 12 && x < 24 && y >= 8 && y < 20, sq1 = x >= 18 && x < 30 && y >= 8 && y < 20;
      const float bg[3] = {0.1f, 0.2f, 0.6f + 0.004f * x}, red[3] = {0.9f, 0.05f, 0.05f};
      memcpy(color0 + 3 * i, sq0 ? red : bg, sizeof bg);
      memcpy(color1 + 3 * i, sq1 ? red : bg, sizeof bg);
      depth0[i] = sq0 ? 4.0f : 10.0f;
      depth1[i] = zprev1[i] = sq1 ? 4.0f : 10.0f;
      motion1[2 * i] = sq1 ? -6.0f : 0.0f;
      motion1[2 * i + 1] = 0.0f;
      motion0[2 * i] = motion0[2 * i + 1] = 0.0f;
    }
  /* the mask alone */
  static uint8_t mask[w * h], tmp[w * h];
  const float j0[2] = {0, 0};
  tt__taa_reject_masks(tt_default_host(), w, h, depth0, j0, zprev1, motion1, j0, mask, tmp);
  uint32_t wrong_raw = 0, wrong_reset = 0, marked = 0;
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      int want = x >= 12 && x < 18 && y >= 8 && y < 19;
      uint8_t k = mask[(size_t)y * w + x];
      wrong_raw += !!(k & TT__TAA_REJECT_RAW) != want;
      wrong_reset += !!(k & TT__TAA_REJECT_RESET) != want;
      marked += want;
    }
  printf("disocclusion: %u pixels disoccluded; mask differs from them in %u (raw) / %u "
         "(reset) pixels\n",
         marked, wrong_raw, wrong_reset);
  CHECK(wrong_raw == 0 && wrong_reset == 0);
  /* without prevdepth only the off-screen test runs: nothing is rejected here */
  tt__taa_reject_masks(tt_default_host(), w, h, depth0, j0, NULL, motion1, j0, mask, tmp);
  uint32_t any = 0;
  for (size_t i = 0; i < n; i++) any += mask[i] != 0;
  CHECK(any == 0);
  /* off-screen: the square's history 6 pixels left of x < 6 is outside the frame */
  for (size_t i = 0; i < n; i++) motion0[2 * i] = -6.0f;
  tt__taa_reject_masks(tt_default_host(), w, h, depth0, j0, NULL, motion0, j0, mask, tmp);
  uint32_t off_wrong = 0;
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++)
      off_wrong += ((mask[(size_t)y * w + x] & (TT__TAA_REJECT_RAW | TT__TAA_REJECT_RESET)) ==
                    (TT__TAA_REJECT_RAW | TT__TAA_REJECT_RESET)) != (x < 6) ||
                   (mask[(size_t)y * w + x] & TT__TAA_REJECT_FAR);
  CHECK_MSG(off_wrong == 0, "off-screen test wrong in %u pixels", off_wrong);
  for (size_t i = 0; i < n; i++) motion0[2 * i] = 0.0f;

  /* through the network: the history planes of frame 1 */
  shape reset = {12, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, TT__NET_FLAG_REJECT | TT__NET_FLAG_RESET};
  shape plain = {12, 5, 3, {3, 3, 5}, {1, 8, 8}, 8, 1, 0};
  for (int k = 0; k < 2; k++) {
    buf b = write_model(k ? &plain : &reset);
    tt__net_model m;
    CHECK_MSG(tt__net_parse(b.p, b.n, "disocclusion", &m) == TT_OK, "%s", tt_last_error());
    free(b.p);
    tt__net_state s, r;
    CHECK(tt__net_state_init(&s, &m, w, h) == TT_OK);
    CHECK(tt__net_state_init(&r, &m, w, h) == TT_OK);
    r.reference = 1;
    tt__net_frame f0 = {.color = color0,
                        .depth = depth0,
                        .motion = motion0,
                        .prev_depth = depth0,
                        .jitter_index = 0},
                  f1 = {.color = color1,
                        .depth = depth1,
                        .motion = motion1,
                        .prev_depth = zprev1,
                        .jitter_index = 1};
    static float out_ref[w * h * 3];
    tt__net_process_frame(&s, &m, tt_default_host(), &f0, out);
    tt__net_process_frame(&s, &m, tt_default_host(), &f1, out);
    tt__net_process_frame(&r, &m, tt_default_host(), &f0, out_ref);
    tt__net_process_frame(&r, &m, tt_default_host(), &f1, out_ref);
    double worst = 0;
    for (size_t i = 0; i < n * 3; i++)
      worst = fmax(worst, fabs(out[i] - out_ref[i]) / (1 + fabs(out_ref[i])));
    CHECK_MSG(worst < 1e-3, "fast vs reference: %g", worst);
    /* the fast path's input planes: channels 6..8 reprojected rgb, 9..13 hidden, 14 reject */
    uint32_t reset_ok = 0, red_hist = 0, flag_wrong = 0;
    for (int y = 8; y < 19; y++)
      for (int x = 12; x < 18; x++) {
        size_t i = (size_t)y * w + x, pi = (size_t)(y + s.halo) * s.inp_ys + TT__NET_COL_OFF + x;
        float t[3];
        tt__taa_tonemap(color1 + 3 * i, t);
        int same = 1;
        for (int c = 0; c < 3; c++) same &= s.inp[(6 + c) * s.inp_cs + pi] == t[c];
        for (int c = 0; c < 5; c++) same &= s.inp[(9 + c) * s.inp_cs + pi] == 0.0f;
        reset_ok += same;
        red_hist += s.inp[6 * s.inp_cs + pi] > 2.0f * s.inp[8 * s.inp_cs + pi];
      }
    if (!k)
      for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
          size_t pi = (size_t)(y + s.halo) * s.inp_ys + TT__NET_COL_OFF + x;
          int want = x >= 12 && x < 18 && y >= 8 && y < 19;
          flag_wrong += s.inp[14 * s.inp_cs + pi] != (want ? 1.0f : 0.0f);
        }
    printf("disocclusion, %s model: %u of 66 disoccluded pixels see the new frame as "
           "history, %u a red history; rejection input wrong in %u pixels\n",
           k ? "plain" : "reset", reset_ok, red_hist, flag_wrong);
    if (!k) CHECK(reset_ok == 66 && red_hist == 0 && flag_wrong == 0);
    else CHECK(red_hist >= 40); /* without rejection the square's red is the history */
    tt__net_state_free(&s);
    tt__net_state_free(&r);
    tt__net_free(&m);
  }
}

/* Catmull-Rom fetch vs an analytic shift: exact on quadratics, close on a smooth image. */
static void test_catmull_rom(void) {
  enum { w = 40, h = 30 };
  static float quad[w * h], smooth[w * h * 2];
  for (int y = 0; y < h; y++)
    for (int x = 0; x < w; x++) {
      float u = x + 0.5f, v = y + 0.5f;
      quad[y * w + x] = 0.3f + 0.02f * u - 0.01f * v + 0.0004f * u * u + 0.0003f * u * v;
      smooth[2 * (y * w + x)] = sinf(0.21f * u) * cosf(0.17f * v);
      smooth[2 * (y * w + x) + 1] = 0.5f + 0.5f * cosf(0.11f * u + 0.07f * v);
    }
  double wq = 0, ws = 0, wb = 0;
  for (int k = 0; k < 200; k++) {
    float fx = 4.0f + (w - 8) * (0.5f + 0.5f * rnd()), fy = 4.0f + (h - 8) * (0.5f + 0.5f * rnd());
    float q, s[2], bl[2];
    tt__taa_sample_catmull_rom(quad, w, h, 1, fx, fy, &q);
    wq = fmax(wq,
              fabs(q - (0.3f + 0.02f * fx - 0.01f * fy + 0.0004f * fx * fx + 0.0003f * fx * fy)));
    tt__taa_sample_catmull_rom(smooth, w, h, 2, fx, fy, s);
    tt__taa_sample_bilinear(smooth, w, h, 2, fx, fy, bl);
    float e0 = sinf(0.21f * fx) * cosf(0.17f * fy),
          e1 = 0.5f + 0.5f * cosf(0.11f * fx + 0.07f * fy);
    ws = fmax(ws, fmax(fabs(s[0] - e0), fabs(s[1] - e1)));
    wb = fmax(wb, fmax(fabs(bl[0] - e0), fabs(bl[1] - e1)));
  }
  printf("catmull-rom: quadratic error %.2e, smooth image %.2e (bilinear %.2e)\n", wq, ws, wb);
  CHECK(wq < 1e-4);
  CHECK(ws < 2e-3);
  CHECK(ws < 0.5 * wb);
  /* Whole-pixel shifts reproduce the pixels exactly. */
  float v;
  tt__taa_sample_catmull_rom(quad, w, h, 1, 7.5f + 3.0f, 5.5f - 2.0f, &v);
  CHECK_NEAR(v, quad[3 * w + 10], 1e-6);
}

int main(void) {
  const char *root = getenv("TT_SOURCE_ROOT");
  if (!root) root = ".";
  tt_default_host_set_threads(2);
  test_catmull_rom();
  test_errors();
  test_roundtrip();
  test_rejection_disocclusion();
  test_isa_dispatch();
  test_fast_vs_reference();
  test_isa_bits();
  test_winograd_vs_direct();
  test_thread_invariance();
  /* every shipped network (README.md: the default and the two thesis widths) */
  static const char *const shipped[] = {"c12", "c6"};
  for (size_t k = 0; k < sizeof shipped / sizeof shipped[0]; k++) test_golden(root, shipped[k]);
  return tt_test_finish("taa_net");
}
