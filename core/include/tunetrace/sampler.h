/* tunetrace: primary-sample generators (kind TT_KIND_SAMPLER, interface "tt.sampler/1").
 *
 * A sampler maps (pixel, sample index, dimension) to a number in [0, 1). The path sampler
 * (path.h) consumes those numbers dimension by dimension, so swapping the sampler swaps
 * independent random numbers for low-discrepancy ones without touching the integrator.
 * Core ships three built-in samplers with the same interface (tt_builtin_sampler):
 * "independent" (PCG32), "halton" (scrambled, per pixel), "sobol" (Owen-scrambled).
 *
 * Threads: a sampler object is immutable after create; start() and get() are thread-safe
 * as long as each thread passes its own state buffer of state_size() bytes.
 */
#ifndef TUNETRACE_SAMPLER_H
#define TUNETRACE_SAMPLER_H

#include <tunetrace/params.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_SAMPLER_INTERFACE_ID "tt.sampler/1"

typedef struct tt_sampler tt_sampler; /* opaque, defined by the implementation */

typedef struct tt_sampler_iface {
  uint32_t struct_size; /* sizeof(tt_sampler_iface) as built */
  const char *name;     /* "independent", "halton", ... */

  /* The sampler's settings space, or NULL. Thread-safe. */
  const tt_space *(*space)(void);

  /* Creates a sampler with `settings` (NULL = defaults) and a global seed. `*out` is
   * owned by the caller: free with destroy. */
  tt_status (*create)(const tt_config *settings, uint64_t seed, tt_sampler **out);

  /* Bytes of per-thread state (at most 256, 16-byte aligned by the caller). */
  size_t (*state_size)(const tt_sampler *s);

  /* Positions `state` at sample `sample_index` of pixel (px, py). Thread-safe. */
  void (*start)(const tt_sampler *s, void *state, uint32_t px, uint32_t py, uint64_t sample_index);

  /* Returns dimension `dim` of the current sample, in [0, 1). Dimensions may be requested
   * in any order; the same (pixel, index, dim) always gives the same number. Thread-safe. */
  float (*get)(const tt_sampler *s, void *state, uint32_t dim);

  /* Destroys the sampler (NULL is ignored). */
  void (*destroy)(tt_sampler *s);

  /* ---- appended in later ABI minors: check struct_size ---- */
} tt_sampler_iface;

/* Built-in sampler by name ("independent", "halton", "sobol"), or NULL. Static table. */
TT_API const tt_sampler_iface *tt_builtin_sampler(const char *name);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_SAMPLER_H */
