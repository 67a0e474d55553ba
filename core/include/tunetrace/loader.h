/* tunetrace: finding, loading and validating plugins (host side).
 *
 * A registry dlopen()s plugins with RTLD_NOW | RTLD_LOCAL, checks their entry table and
 * required interface, calls init() with the host services, and keeps them loaded until the
 * registry is destroyed. A plugin file is initialised once per process: registries that
 * load the same file share it (init for the first, deinit after the last; plugin.h). Plugins are named either by path (anything containing '/' or
 * ending in ".so") or by name, searched as NAME.so in: directories added with
 * tt_registry_add_dir (in order), then $TT_PLUGIN_PATH (':'-separated), then the installed
 * plugin folder: tunetrace-1/ beside the libtunetrace file in use (so a relocated or
 * --destdir install finds its own plugins), then the one configured at build time
 * (`pkg-config --variable=plugindir tunetrace`). No build tree is searched: programs run
 * from one (the uninstalled host, the build tree's Python package) add its folder.
 *
 * Every rejection is reported through tt_set_error with the file, and for version
 * mismatches both versions ("plugin ABI 2.0, host ABI 1.0"). Rejections:
 *   - the file is missing, not a shared object, or cannot be loaded (dlerror text);
 *   - no `tt_plugin_entry` symbol;
 *   - struct_size smaller than the ABI 1.0 table;
 *   - abi_major different from the host's;
 *   - unknown kind;
 *   - init() failed;
 *   - the plugin is live in another registry with a different host table;
 *   - get_interface() does not serve the kind's interface, or the interface table is
 *     shorter than its ABI 1.0 size;
 *   - a second plugin of a kind that allows one (all kinds but post);
 *   - a second plugin with the same name.
 *
 * Threads: one registry is used by one thread at a time; different registries may load
 * and unload plugins on different threads.
 */
#ifndef TUNETRACE_LOADER_H
#define TUNETRACE_LOADER_H

#include <tunetrace/params.h> /* tt_space, used by tt_loaded_plugin_space */
#include <tunetrace/plugin.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tt_registry tt_registry;
typedef struct tt_loaded_plugin tt_loaded_plugin;

/* Creates an empty registry whose plugins receive `host` (which must outlive it). */
TT_API tt_registry *tt_registry_create(const tt_host *host);
/* Unloads every plugin in reverse load order, calling deinit() of each one no other
 * registry holds. */
TT_API void tt_registry_destroy(tt_registry *reg);
/* Appends a directory to the search list. */
TT_API tt_status tt_registry_add_dir(tt_registry *reg, const char *dir);
/* Directories searched, in order, joined with ':' (for messages). Valid until the next
 * change to the registry. */
TT_API const char *tt_registry_search_path(tt_registry *reg);
/* Resolves `name_or_path` to a file path (caller frees with tt_free), or NULL with a
 * message listing the directories searched. */
TT_API char *tt_registry_resolve(tt_registry *reg, const char *name_or_path);

/* Loads and validates one plugin; on success `*out` (may be NULL) points to it (owned by
 * the registry). On failure nothing stays loaded. */
TT_API tt_status tt_registry_load(tt_registry *reg, const char *name_or_path,
                                  tt_loaded_plugin **out);

/* Probes a plugin file without keeping it: validates as tt_registry_load would, but never
 * calls init(). For --list-plugins. `entry_copy` receives name/kind/version pointers valid
 * until the next probe. */
TT_API tt_status tt_registry_probe(tt_registry *reg, const char *path, tt_plugin *entry_copy);

TT_API size_t tt_registry_count(const tt_registry *reg);
TT_API tt_loaded_plugin *tt_registry_get(const tt_registry *reg, size_t index);
/* First loaded plugin of `kind`, or NULL. */
TT_API tt_loaded_plugin *tt_registry_find_kind(const tt_registry *reg, uint32_t kind);
/* Loaded plugin called `name`, or NULL. */
TT_API tt_loaded_plugin *tt_registry_find_name(const tt_registry *reg, const char *name);

/* The plugin's entry table (as exported by it). */
TT_API const tt_plugin *tt_loaded_plugin_entry(const tt_loaded_plugin *p);
/* The resolved file path. */
TT_API const char *tt_loaded_plugin_path(const tt_loaded_plugin *p);
/* The plugin's kind interface table, already validated (cast to tt_accel_iface etc.). */
TT_API const void *tt_loaded_plugin_iface(const tt_loaded_plugin *p);
/* Optional capability lookup by id through the plugin's get_interface; NULL if absent. */
TT_API const void *tt_loaded_plugin_get(const tt_loaded_plugin *p, const char *id);
/* The parameter space the plugin's kind interface publishes (NULL if none). */
TT_API const tt_space *tt_loaded_plugin_space(const tt_loaded_plugin *p);

/* Lists NAME.so files in every search directory (first occurrence of a name wins), calling
 * fn for each path. */
TT_API void tt_registry_list_files(tt_registry *reg, void (*fn)(void *user, const char *path),
                                   void *user);

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_LOADER_H */
