/* The library's own log (warnings of the scene loaders and writers): one call that goes to
 * the host set with tt_set_log_host, else to tt_default_host() (host_default.c). Internal to
 * libtunetrace. */
#ifndef TT_PLUGIN_LOG_H
#define TT_PLUGIN_LOG_H

#include <tunetrace/common.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Logs one message through the log host; thread-safe when the host's log is. */
void tt__log(tt_log_level level, const char *fmt, ...) TT_PRINTF(2, 3);

#ifdef __cplusplus
}
#endif

#endif /* TT_PLUGIN_LOG_H */
