/* libFuzzer: post_taa's weights file (.ttw) parser, then one 8x6 frame through both
 * inference paths (the fast banded one and the scalar reference) when the file loads, so a
 * shape that passes the parser but not the convolutions is found too. */
#include "taa_internal.h"

#include "fuzz_util.h"

#include <tunetrace/host.h>
#include <tt_util/hash.h>

/* The file ends with an FNV-1a checksum of the payload (after header_bytes, the u32 at 12):
 * recomputed here on the mutated input so the fuzzer reaches the shapes and weights behind
 * it (a mismatch is one comparison the parser makes and the unit tests cover). */
static uint8_t *fix_checksum(const uint8_t *data, size_t size) {
  uint8_t *c = malloc(size ? size : 1);
  if (!c) abort();
  memcpy(c, data, size);
  if (size < 20) return c;
  uint32_t hb =
      (uint32_t)c[12] | (uint32_t)c[13] << 8 | (uint32_t)c[14] << 16 | (uint32_t)c[15] << 24;
  if (hb > size - 4) return c;
  uint32_t h = tt__fnv1a32(c + hb, size - 4 - hb);
  for (int k = 0; k < 4; k++) c[size - 4 + k] = (uint8_t)(h >> (8 * k));
  return c;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  tt__net_model m;
  uint8_t *fixed = fix_checksum(data, size);
  tt_status st = tt__net_parse(fixed, size, "fuzz.ttw", &m);
  free(fixed);
  if (st != TT_OK) return 0;
  enum { W = 8, H = 6 };
  static float color[W * H * 3], depth[W * H], motion[W * H * 2], out[W * H * 3];
  for (int i = 0; i < W * H * 3; i++) color[i] = (float)(i % 7) * 0.25f;
  for (int i = 0; i < W * H * 2; i++) motion[i] = (float)(i % 5) - 2.0f;
  for (int ref = 0; ref < 2; ref++) {
    tt__net_state s;
    if (tt__net_state_init(&s, &m, W, H) != TT_OK) continue;
    s.reference = ref;
    for (uint32_t f = 0; f < 2; f++)
      tt__net_process(&s, &m, tt_default_host(), color, depth, motion, f, out);
    tt__net_state_free(&s);
  }
  tt__net_free(&m);
  return 0;
}
