/* host: the setters of the option table (option_table.c): each reads one option's value into
 * tt__host_options, or prints what was expected and returns -1. */
#ifndef TT_HOST_OPTION_SETTERS_H
#define TT_HOST_OPTION_SETTERS_H

#include "option_table.h"

/* Generic, through tt__option.field: an int set to 1, a string, an entry of a bounded list
 * (the list's count follows its array), a number within tt__option.limit (uint32_t or
 * double). */
int tt__set_flag(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_text(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_list(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_u32(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_real(const tt__option *o, const char *v, struct tt__host_options *opt);

/* One option each (named after it). */
int tt__set_plugin_param(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_seed(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_res(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_epsilon(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_objective(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_tune_params(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_clock(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_sequence(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_camera_index(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_aov(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_supersample(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_indicator_norm(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_out(const tt__option *o, const char *v, struct tt__host_options *opt);
/* --help [TOPIC] and --help-all (topic "all"). */
int tt__set_help(const tt__option *o, const char *v, struct tt__host_options *opt);
int tt__set_stats(const tt__option *o, const char *v, struct tt__host_options *opt);

#endif
