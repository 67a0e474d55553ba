/* tunetrace: plugin options outside the tuned parameter space (capability "tt.options/1").
 *
 * Parameters (params.h) are what a tuner may vary: numbers and nominal choices. Some settings
 * are not of that kind -- a file to read (post_taa's weights), a name, a folder -- and must
 * never be "tuned". A plugin with such settings serves this table from
 * get_interface(TT_OPTIONS_INTERFACE_ID), any kind of plugin may. The host applies
 * `--set NAME.KEY=VALUE` here when KEY is not a parameter of NAME's space.
 *
 * Options are per loaded plugin (process-wide): a value applies to the objects the plugin
 * creates after it was set. Strings passed in are copied; strings returned are owned by the
 * plugin.
 *
 * Threads: count() and info() are thread-safe; set() and get() are not: call them before
 * creating objects (the host does so while it parses the command line).
 */
#ifndef TUNETRACE_OPTIONS_H
#define TUNETRACE_OPTIONS_H

#include <tunetrace/common.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TT_OPTIONS_INTERFACE_ID "tt.options/1"

/* One option: its key ([A-Za-z0-9_]+) and a one-line description with the expected value. */
typedef struct tt_option_info {
  const char *key;
  const char *description;
} tt_option_info;

typedef struct tt_options_iface {
  uint32_t struct_size; /* sizeof(tt_options_iface) as the plugin was built */

  /* Number of options. Thread-safe. */
  uint32_t (*count)(void);

  /* Option `index` (< count()), static storage; NULL when out of range. Thread-safe. */
  const tt_option_info *(*info)(uint32_t index);

  /* Sets option `key` to `value` (copied). Returns TT_ERR_INVALID_ARGUMENT with a message
   * naming the key and what was expected for an unknown key or a bad value. Not
   * thread-safe. */
  tt_status (*set)(const char *key, const char *value);

  /* Current value of `key` ("" when unset, NULL for an unknown key); valid until the next
   * set(). Not thread-safe. */
  const char *(*get)(const char *key);

  /* ---- appended in later ABI minors: check struct_size ---- */
} tt_options_iface;

#ifdef __cplusplus
}
#endif

#endif /* TUNETRACE_OPTIONS_H */
