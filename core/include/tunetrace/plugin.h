/* tunetrace: the plugin entry point (ABI v1).
 *
 * Every plugin is a shared object exporting one data symbol, `tt_plugin_entry`, of type
 * tt_plugin (compare CLAP's clap_entry). The host dlopen()s the file, checks the table head
 * (struct_size, ABI major/minor, kind), calls init() once with its services, then asks
 * get_interface() for the versioned interface of the plugin's kind, e.g. "tt.accel/1".
 *
 *   TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
 *     .struct_size = sizeof(tt_plugin), .abi_major = TT_ABI_MAJOR, .abi_minor = TT_ABI_MINOR,
 *     .kind = TT_KIND_TUNER, .name = "tuner_random", .version = "1.0.0",
 *     .description = "...", .init = my_init, .deinit = my_deinit,
 *     .get_interface = my_get_interface };
 *
 * Compatibility rules:
 * - abi_major must equal the host's TT_ABI_MAJOR, or the plugin is rejected.
 * - A newer abi_minor loads: tables only grow at the end, and the host reads only the
 *   prefix it knows (struct_size tells how long the plugin's table is). An older minor
 *   loads too; the host checks struct_size before touching a field newer than that minor
 *   (TT_HAS_FIELD in common.h: offsetof(field) + sizeof(field) <= struct_size, the one rule
 *   for every versioned table either side reads).
 * - An interface that changes incompatibly gets a new id ("tt.accel/2"); the old id may
 *   still be served alongside it.
 * - Every function of a kind's interface table (and the sampler's name) is required: the
 *   host rejects a table with a NULL one, naming it, rather than call through it.
 * - The file itself is checked before dlopen: an ELF shared object of the host's class
 *   whose segments all lie inside the file (a truncated copy is rejected, not mapped).
 *
 * Lifetime: a plugin file is initialised once per process. Registries (render sessions) that
 * load the same file share it: init runs when the first one loads it, deinit when the last
 * one unloads it, so static state set up in init serves every session. One host table per
 * plugin at a time: a registry with another host table is refused while the plugin is live.
 *
 * Threads: init and deinit run serialized (under the loader's lock, on the thread that loads
 * or unloads); get_interface on the thread that loads the plugin.
 */
#ifndef TUNETRACE_PLUGIN_H
#define TUNETRACE_PLUGIN_H

#include <tunetrace/common.h>
#include <tunetrace/host.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The six plugin kinds. Values never change; new kinds are appended. */
typedef enum tt_plugin_kind {
  TT_KIND_ACCEL = 1,      /* acceleration structure: "tt.accel/1" (accel.h) */
  TT_KIND_INTEGRATOR = 2, /* light transport: "tt.integrator/1" (integrator.h) */
  TT_KIND_TUNER = 3,      /* search over a parameter space: "tt.tuner/1" (tuner.h) */
  TT_KIND_PREDICTOR = 4,  /* state -> configuration model: "tt.predictor/1" (predictor.h) */
  TT_KIND_POST = 5,       /* per-frame image filter with temporal state: "tt.post/1" (post.h) */
  TT_KIND_SAMPLER = 6     /* primary-sample generator: "tt.sampler/1" (sampler.h) */
} tt_plugin_kind;

#define TT_KIND_COUNT 6

/* Name of the symbol every plugin exports. */
#define TT_PLUGIN_ENTRY_SYMBOL "tt_plugin_entry"

/* Export marker for the entry symbol (plugins build with hidden visibility). */
#ifdef __cplusplus
#  define TT_PLUGIN_EXPORT extern "C" TT_EXPORT
#else
#  define TT_PLUGIN_EXPORT TT_EXPORT
#endif

typedef struct tt_plugin {
  uint32_t struct_size;    /* sizeof(tt_plugin) as the plugin was built */
  uint16_t abi_major;      /* TT_ABI_MAJOR the plugin was built against */
  uint16_t abi_minor;      /* TT_ABI_MINOR the plugin was built against */
  uint32_t kind;           /* a tt_plugin_kind */
  const char *name;        /* unique short name, [a-z0-9_]+, e.g. "accel_embree" */
  const char *version;     /* the plugin's own semantic version, e.g. "1.2.0" */
  const char *description; /* one line for --list-plugins */

  /* Called once after the file is loaded by its first registry, before anything else
   * (see Lifetime above). `host` stays valid until deinit
   * returns; keep the pointer. Return TT_OK, or an error (with tt_set_error) to refuse
   * loading, e.g. when a required host field or CPU feature is missing. May be NULL. */
  tt_status (*init)(const tt_host *host);

  /* Called once before the last registry holding the file unloads it; every object the
   * plugin created has been destroyed. May be NULL. */
  void (*deinit)(void);

  /* Returns the interface table for a versioned id, or NULL if the plugin does not serve
   * it. Tables are static, owned by the plugin, valid until deinit. A plugin of kind K
   * must serve K's interface (see tt_plugin_kind); it may serve more (capabilities). */
  const void *(*get_interface)(const char *id);

  /* ---- appended in later ABI minors: check struct_size ---- */
} tt_plugin;

/* Interface id every plugin of `kind` must serve ("tt.accel/1", ...); NULL if unknown. */
TT_API const char *tt_plugin_kind_interface(uint32_t kind);
/* Short name of a kind ("accel", "integrator", ...); "unknown" if out of range. */
TT_API const char *tt_plugin_kind_name(uint32_t kind);
/* Kind from its short name; 0 if unknown. */
TT_API uint32_t tt_plugin_kind_from_name(const char *name);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_PLUGIN_H */
