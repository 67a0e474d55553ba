/* tunetrace internal: integer hashing, SplitMix64 and the PCG32 generator, written once for
 * the library (built-in samplers, the tuning loop), the in-tree plugins (PSSMLT's chains,
 * tuner_nm's stream) and the tests, which include it as <tt_util/rng.h> through
 * tunetrace_util_dep (not installed: a third-party plugin carries its own, like
 * examples/tuner_random). Header-only (static inline): every function is pure or works on
 * caller-owned state, so all are thread-safe and allocation-free. */
#ifndef TT_UTIL_RNG_H
#define TT_UTIL_RNG_H

#include <stdint.h>

/* SplitMix64 finaliser: a bijective 64-bit mixer with full avalanche. */
static inline uint64_t tt__mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/* SplitMix64 (Steele, Lea, Flood 2014): the next value of the stream `*state`. Seeds
 * other generators and draws the tuning loop's random exploration. */
static inline uint64_t tt__splitmix64(uint64_t *state) {
  return tt__mix64(*state += 0x9e3779b97f4a7c15ull);
}

/* Hashes two 64-bit words; order matters (hash(a,b) != hash(b,a) in general). */
static inline uint64_t tt__hash2(uint64_t a, uint64_t b) {
  return tt__mix64(tt__mix64(a + 0x9e3779b97f4a7c15ull) ^ (b + 0x632be59bd9b4e019ull));
}

/* Hashes three words, order-sensitive. */
static inline uint64_t tt__hash3(uint64_t a, uint64_t b, uint64_t c) {
  return tt__mix64(tt__hash2(a, b) ^ (c + 0xd1b54a32d192ed03ull));
}

/* Hashes four words (pixel x, pixel y, sample index, seed-like values). */
static inline uint64_t tt__hash4(uint64_t a, uint64_t b, uint64_t c, uint64_t d) {
  return tt__hash2(tt__hash2(a, b), tt__hash2(c, d));
}

/* 32-bit mixer (Wellons' lowbias32) for per-digit and per-dimension seeds. */
static inline uint32_t tt__mix32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

/* Maps 32 random bits to [0, 1) with 24-bit resolution, so 1.0f is never produced. */
static inline float tt__u32_to_unit(uint32_t x) { return (float)(x >> 8) * 0x1p-24f; }

/* Maps 64 random bits to [0, 1) with 53-bit resolution (a double's mantissa). */
static inline double tt__u64_to_unit(uint64_t x) { return (double)(x >> 11) * 0x1p-53; }

/* Largest float below 1: clamp target for values computed in double. */
#define TT__ONE_MINUS_EPS 0x1.fffffep-1f

/* PCG32 (O'Neill 2014, XSH-RR 64/32). */
typedef struct tt__pcg32 {
  uint64_t state;
  uint64_t inc; /* odd */
} tt__pcg32;

#define TT__PCG32_MULT 6364136223846793005ull

/* Seeds a generator with a start state and a stream selector (as pcg32_srandom_r). */
static inline void tt__pcg32_seed(tt__pcg32 *rng, uint64_t initstate, uint64_t initseq) {
  rng->state = 0u;
  rng->inc = (initseq << 1u) | 1u;
  rng->state = rng->state * TT__PCG32_MULT + rng->inc;
  rng->state += initstate;
  rng->state = rng->state * TT__PCG32_MULT + rng->inc;
}

/* Next 32 random bits. */
static inline uint32_t tt__pcg32_next(tt__pcg32 *rng) {
  uint64_t old = rng->state;
  rng->state = old * TT__PCG32_MULT + rng->inc;
  uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
  uint32_t rot = (uint32_t)(old >> 59u);
  return (xorshifted >> rot) | (xorshifted << ((-rot) & 31u));
}

/* Uniform float in [0, 1). */
static inline float tt__pcg32_float(tt__pcg32 *rng) { return tt__u32_to_unit(tt__pcg32_next(rng)); }

/* Uniform double in [0, 1) with 53 random bits, from two draws (the first the high word). */
static inline double tt__pcg32_double(tt__pcg32 *rng) {
  uint64_t hi = tt__pcg32_next(rng), lo = tt__pcg32_next(rng);
  return tt__u64_to_unit((hi << 32) | lo);
}

/* Jumps `delta` steps ahead in O(log delta) (Brown 1994), so dimension d of a sample can be
 * read without drawing dimensions 0..d-1 first. */
static inline void tt__pcg32_advance(tt__pcg32 *rng, uint64_t delta) {
  uint64_t cur_mult = TT__PCG32_MULT, cur_plus = rng->inc;
  uint64_t acc_mult = 1u, acc_plus = 0u;
  while (delta > 0) {
    if (delta & 1u) {
      acc_mult *= cur_mult;
      acc_plus = acc_plus * cur_mult + cur_plus;
    }
    cur_plus = (cur_mult + 1u) * cur_plus;
    cur_mult *= cur_mult;
    delta >>= 1u;
  }
  rng->state = acc_mult * rng->state + acc_plus;
}

/* Reverses the bits of a 32-bit word (radical inverse in base 2). */
static inline uint32_t tt__reverse_bits32(uint32_t x) {
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
  x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
  return (x >> 16) | (x << 16);
}

#endif /* TT_UTIL_RNG_H */
