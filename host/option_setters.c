/* host: the setters of the option table. Every error names the option and what was
 * expected. */
#include "option_setters.h"

#include "host.h"

#include <stdio.h>
#include <string.h>

/* The member of `opt` at the row's field offset. */
#define TT__FIELD(type, o, opt) ((type *)(void *)((char *)(opt) + (o)->field))

/* Prints the library's message for option `o` (tunetrace/limits.h); returns -1. */
static int tt__bad_value(const tt__option *o) {
  tt__say("%s: %s\n", o->name, tt_last_error());
  return -1;
}

/* The integer `v` within the row's limit. */
static int tt__uint(const tt__option *o, const char *v, uint64_t *out) {
  return tt_limit_parse_uint(o->limit, v, out) == TT_OK ? 0 : tt__bad_value(o);
}

int tt__set_flag(const tt__option *o, const char *v, tt__host_options *opt) {
  (void)v;
  *TT__FIELD(int, o, opt) = 1;
  return 0;
}

int tt__set_text(const tt__option *o, const char *v, tt__host_options *opt) {
  *TT__FIELD(const char *, o, opt) = v;
  return 0;
}

int tt__set_list(const tt__option *o, const char *v, tt__host_options *opt) {
  const char **list = TT__FIELD(const char *, o, opt);
  int *count = (int *)(void *)(list + TT_HOST_MAX_LIST);
  if (*count >= TT_HOST_MAX_LIST) {
    tt__say("%s: at most %d times\n", o->name, TT_HOST_MAX_LIST);
    return -1;
  }
  list[(*count)++] = v;
  return 0;
}

int tt__set_u32(const tt__option *o, const char *v, tt__host_options *opt) {
  uint64_t n;
  if (tt__uint(o, v, &n)) return -1;
  *TT__FIELD(uint32_t, o, opt) = (uint32_t)n;
  return 0;
}

int tt__set_real(const tt__option *o, const char *v, tt__host_options *opt) {
  if (tt_limit_parse_real(o->limit, v, TT__FIELD(double, o, opt)) != TT_OK) return tt__bad_value(o);
  return 0;
}

int tt__set_plugin_param(const tt__option *o, const char *v, tt__host_options *opt) {
  const char *dot = strchr(v, '.'), *eq = strchr(v, '=');
  if (!dot || !eq || dot > eq || dot == v || eq == dot + 1) {
    tt__say("--set: expected PLUGIN.PARAM=VALUE, got \"%s\"\n", v);
    return -1;
  }
  return tt__set_list(o, v, opt);
}

int tt__set_seed(const tt__option *o, const char *v, tt__host_options *opt) {
  if (tt__uint(o, v, &opt->seed)) return -1;
  opt->seed_set = 1;
  return 0;
}

int tt__set_res(const tt__option *o, const char *v, tt__host_options *opt) {
  if (tt_limit_parse_resolution(v, &opt->width, &opt->height) != TT_OK) return tt__bad_value(o);
  return 0;
}

int tt__set_epsilon(const tt__option *o, const char *v, tt__host_options *opt) {
  if (tt__set_real(o, v, opt)) return -1;
  opt->epsilon_set = 1;
  return 0;
}

int tt__set_objective(const tt__option *o, const char *v, tt__host_options *opt) {
  tt_objective obj;
  if (tt__parse_objective(o->name, v, &obj)) return -1;
  opt->objective = v;
  return 0;
}

int tt__set_tune_params(const tt__option *o, const char *v, tt__host_options *opt) {
  if (!v[0] || strstr(v, ",,") || v[0] == ',' || v[strlen(v) - 1] == ',') {
    tt__say("%s: expected NAME[,NAME...], got \"%s\"\n", o->name, v);
    return -1;
  }
  opt->tune_params = v;
  return 0;
}

int tt__set_clock(const tt__option *o, const char *v, tt__host_options *opt) {
  if (strcmp(v, "cpu") && strcmp(v, "wall")) {
    tt__say("%s: expected wall or cpu, got \"%s\"\n", o->name, v);
    return -1;
  }
  opt->clock_cpu = !strcmp(v, "cpu");
  return 0;
}

/* "N" renders frames 0..N-1, "A:B" frames A..B inclusive (sequence.c). */
int tt__set_sequence(const tt__option *o, const char *v, tt__host_options *opt) {
  uint64_t f0 = 0, f1 = 0, n = 0;
  int range = strchr(v, ':') != NULL;
  int ok = range ? tt_limit_parse_span(o->limit, v, &f0, &f1) == TT_OK
                 : tt_limit_parse_uint(o->limit, v, &n) == TT_OK && n >= 1;
  if (!ok) {
    tt__say("%s: expected a frame count N >= 1 or a range A:B with A <= B (frame "
            "numbers up to %u), got \"%s\"\n",
            o->name, UINT32_MAX - 1, v);
    return -1;
  }
  opt->seq_first = (uint32_t)f0;
  opt->seq_last = (uint32_t)(range ? f1 : n - 1);
  opt->sequence = 1;
  return 0;
}

/* I, or A:B (samples A..B, both included: the states of --hybrid and --predict). */
int tt__set_camera_index(const tt__option *o, const char *v, tt__host_options *opt) {
  uint64_t c0 = 0, c1 = 0;
  if (!strchr(v, ':')) {
    if (tt__uint(o, v, &c0)) return -1;
    c1 = c0;
  } else if (tt_limit_parse_span(o->limit, v, &c0, &c1) == TT_OK) {
    opt->camera_index_range = 1;
  } else {
    tt__say("%s: expected I or A:B with A <= B <= %d (path samples A..B, both "
            "included), got \"%s\"\n",
            o->name, TT_HOST_PATH_SAMPLES - 1, v);
    return -1;
  }
  opt->camera_index = (uint32_t)c0;
  opt->camera_index_last = (uint32_t)c1;
  opt->camera_index_set = 1;
  return 0;
}

/* The TT__AOV_* bit of the `len` characters at `name`, or 0. */
static uint32_t tt__aov_bit(const char *name, size_t len) {
  static const struct {
    const char *name;
    uint32_t bit;
  } aovs[] = {{"depth", TT__AOV_DEPTH},
              {"normal", TT__AOV_NORMAL},
              {"albedo", TT__AOV_ALBEDO},
              {"motion", TT__AOV_MOTION},
              {"prevdepth", TT__AOV_PREVDEPTH}};
  for (size_t k = 0; k < sizeof aovs / sizeof aovs[0]; k++)
    if (strlen(aovs[k].name) == len && !strncmp(name, aovs[k].name, len)) return aovs[k].bit;
  return 0;
}

/* "depth,normal,albedo,motion,prevdepth" as TT__AOV_* bits ("none" = no AOV). */
int tt__set_aov(const tt__option *o, const char *v, tt__host_options *opt) {
  opt->aov_mask = 0;
  opt->aov_set = 1;
  if (!strcmp(v, "none")) return 0;
  for (const char *p = v; *p;) {
    size_t len = strcspn(p, ",");
    uint32_t bit = tt__aov_bit(p, len);
    if (!bit) {
      tt__say("%s: expected a comma-separated list of depth, normal, albedo, "
              "motion, prevdepth (or none), got \"%.*s\" in \"%s\"\n",
              o->name, (int)len, p, v);
      return -1;
    }
    opt->aov_mask |= bit;
    p += len;
    if (*p == ',') p++;
  }
  return 0;
}

int tt__set_supersample(const tt__option *o, const char *v, tt__host_options *opt) {
  if (tt__set_u32(o, v, opt)) return -1;
  opt->reference_only = 1;
  return 0;
}

int tt__set_indicator_norm(const tt__option *o, const char *v, tt__host_options *opt) {
  tt_indicator_norm norm;
  if (tt_indicator_norm_parse(v, &norm) != TT_OK) {
    tt__say("%s: %s\n", o->name, tt_last_error());
    return -1;
  }
  opt->indicator_norm = v;
  return 0;
}

int tt__set_out(const tt__option *o, const char *v, tt__host_options *opt) {
  const char *dot = strrchr(v, '.');
  if (!dot || (strcmp(dot, ".exr") != 0 && strcmp(dot, ".json") != 0)) {
    tt__say("%s: expected a file name ending in .exr (.json with --convert), got "
            "\"%s\"\n",
            o->name, v);
    return -1;
  }
  opt->out = v;
  return 0;
}

int tt__set_stats(const tt__option *o, const char *v, tt__host_options *opt) {
  if (!*v) {
    tt__say("%s: expected a file name, got an empty string\n", o->name);
    return -1;
  }
  opt->stats = v;
  return 0;
}

int tt__set_help(const tt__option *o, const char *v, tt__host_options *opt) {
  opt->help = 1;
  opt->help_topic = !strcmp(o->name, "--help-all") ? "all" : v;
  if (!v || !strcmp(v, "all") || tt__topic_find(v) >= 0) return 0;
  const char *near = tt__topic_suggest(v);
  tt__say("%s: unknown topic \"%s\"%s%s%s; the topics: %s, all\n", o->name, v,
          near ? " (did you mean " : "", near ? near : "", near ? "?)" : "", tt__topic_list());
  return -1;
}
