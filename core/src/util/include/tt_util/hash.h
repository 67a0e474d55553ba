/* tunetrace internal: FNV-1a, written once for the scene id, the tuning database's
 * reference fingerprint, tuner_nm's measurement cache (64-bit) and the checksum of
 * post_taa's weight files (32-bit). Include as <tt_util/hash.h>
 * (tunetrace_util_dep; see rng.h). Header-only, pure, thread-safe. */
#ifndef TT_UTIL_HASH_H
#define TT_UTIL_HASH_H

#include <stddef.h>
#include <stdint.h>

/* FNV-1a 64 offset basis: the hash of no bytes, where a chain of tt__fnv1a64 starts. */
#define TT__FNV1A64_OFFSET 0xcbf29ce484222325ull

/* Continues the FNV-1a 64 hash `h` over `n` bytes: simple, and stable across platforms
 * with the same byte layout. */
static inline uint64_t tt__fnv1a64(uint64_t h, const void *data, size_t n) {
  const unsigned char *p = (const unsigned char *)data;
  for (size_t i = 0; i < n; i++) {
    h ^= p[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

/* FNV-1a 32 of `n` bytes (offset basis 2166136261, prime 16777619): the checksum of
 * post_taa's weight files. */
static inline uint32_t tt__fnv1a32(const void *data, size_t n) {
  const unsigned char *p = (const unsigned char *)data;
  uint32_t h = 2166136261u;
  for (size_t i = 0; i < n; i++) {
    h ^= p[i];
    h *= 16777619u;
  }
  return h;
}

#endif /* TT_UTIL_HASH_H */
