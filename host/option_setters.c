/* host: the setters of the option table. Every error names the option and what was
 * expected. */
#include "option_setters.h"

#include "host.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The member of `opt` at the row's field offset. */
#define TT__FIELD(type, o, opt) ((type *)(void *)((char *)(opt) + (o)->field))

/* Parses an unsigned integer in [lo, hi] for option `name`. */
static int tt__parse_u64(const char *name, const char *text, uint64_t lo, uint64_t hi,
                         uint64_t *out) {
  char *end = NULL;
  errno = 0;
  if (!text || !*text || *text == '-') goto bad;
  unsigned long long v = strtoull(text, &end, 10);
  if (errno || *end || v < lo || v > hi) goto bad;
  *out = v;
  return 0;
bad:
  fprintf(stderr, "host: %s: expected an integer in [%llu, %llu], got \"%s\"\n", name,
          (unsigned long long)lo, (unsigned long long)hi, text ? text : "");
  return -1;
}

/* A real number of the whole text `v` (no trailing characters), or NAN. */
static double tt__real(const char *v) {
  char *end = NULL;
  double x = strtod(v, &end);
  return *v && !*end ? x : NAN;
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
    fprintf(stderr, "host: %s: at most %d times\n", o->name, TT_HOST_MAX_LIST);
    return -1;
  }
  list[(*count)++] = v;
  return 0;
}

int tt__set_u32(const tt__option *o, const char *v, tt__host_options *opt) {
  uint64_t n;
  if (tt__parse_u64(o->name, v, o->lo, o->hi, &n)) return -1;
  *TT__FIELD(uint32_t, o, opt) = (uint32_t)n;
  return 0;
}

int tt__set_plugin_param(const tt__option *o, const char *v, tt__host_options *opt) {
  const char *dot = strchr(v, '.'), *eq = strchr(v, '=');
  if (!dot || !eq || dot > eq || dot == v || eq == dot + 1) {
    fprintf(stderr, "host: --set: expected PLUGIN.PARAM=VALUE, got \"%s\"\n", v);
    return -1;
  }
  return tt__set_list(o, v, opt);
}

int tt__set_seed(const tt__option *o, const char *v, tt__host_options *opt) {
  if (tt__parse_u64(o->name, v, 0, UINT64_MAX, &opt->seed)) return -1;
  opt->seed_set = 1;
  return 0;
}

int tt__set_time(const tt__option *o, const char *v, tt__host_options *opt) {
  double t = tt__real(v);
  if (!(t > 0) || t > 1e7) {
    fprintf(stderr, "host: %s: expected seconds > 0, got \"%s\"\n", o->name, v);
    return -1;
  }
  opt->time_budget = t;
  return 0;
}

int tt__set_res(const tt__option *o, const char *v, tt__host_options *opt) {
  unsigned w = 0, h = 0;
  char tail = 0;
  if (sscanf(v, "%ux%u%c", &w, &h, &tail) != 2 || w == 0 || h == 0 || w > 65536 ||
      h > 65536) {
    fprintf(stderr, "host: %s: expected WIDTHxHEIGHT (1..65536 each), got \"%s\"\n", o->name, v);
    return -1;
  }
  opt->width = w;
  opt->height = h;
  return 0;
}

int tt__set_epsilon(const tt__option *o, const char *v, tt__host_options *opt) {
  double e = tt__real(v);
  if (!(e >= 0.0 && e <= 1.0)) {
    fprintf(stderr, "host: %s: expected the probability of exploring a state, a number in "
            "[0, 1], got \"%s\"\n", o->name, v);
    return -1;
  }
  opt->epsilon = e;
  opt->epsilon_set = 1;
  return 0;
}

int tt__set_fps(const tt__option *o, const char *v, tt__host_options *opt) {
  double fps = tt__real(v);
  if (!(fps > 0) || fps > 1000) {
    fprintf(stderr, "host: %s: expected frames per second in (0, 1000], got \"%s\"\n", o->name,
            v);
    return -1;
  }
  opt->fps = fps;
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
    fprintf(stderr, "host: %s: expected NAME[,NAME...], got \"%s\"\n", o->name, v);
    return -1;
  }
  opt->tune_params = v;
  return 0;
}

int tt__set_clock(const tt__option *o, const char *v, tt__host_options *opt) {
  if (strcmp(v, "cpu") && strcmp(v, "wall")) {
    fprintf(stderr, "host: %s: expected wall or cpu, got \"%s\"\n", o->name, v);
    return -1;
  }
  opt->clock_cpu = !strcmp(v, "cpu");
  return 0;
}

/* "N" renders frames 0..N-1, "A:B" frames A..B inclusive (sequence.c). */
int tt__set_sequence(const tt__option *o, const char *v, tt__host_options *opt) {
  unsigned f0 = 0, f1 = 0;
  char extra;
  int digit = v[0] >= '0' && v[0] <= '9';
  if (digit && sscanf(v, "%u:%u%c", &f0, &f1, &extra) == 2 && f0 <= f1) {
    opt->seq_first = f0;
    opt->seq_last = f1;
  } else if (digit && sscanf(v, "%u%c", &f0, &extra) == 1 && f0 >= 1) {
    opt->seq_first = 0;
    opt->seq_last = f0 - 1;
  } else {
    fprintf(stderr, "host: %s: expected a frame count N >= 1 or a range A:B with A <= B, got "
            "\"%s\"\n", o->name, v);
    return -1;
  }
  opt->sequence = 1;
  return 0;
}

/* I, or A:B (samples A..B, both included: the states of --hybrid and --predict). */
int tt__set_camera_index(const tt__option *o, const char *v, tt__host_options *opt) {
  unsigned c0 = 0, c1 = 0;
  char extra;
  uint64_t n;
  if (strchr(v, ':')) {
    if (!(v[0] >= '0' && v[0] <= '9') || sscanf(v, "%u:%u%c", &c0, &c1, &extra) != 2 ||
        c0 > c1 || c1 >= TT_HOST_PATH_SAMPLES) {
      fprintf(stderr, "host: %s: expected I or A:B with A <= B <= %d (path samples A..B, both "
              "included), got \"%s\"\n", o->name, TT_HOST_PATH_SAMPLES - 1, v);
      return -1;
    }
    opt->camera_index_range = 1;
  } else {
    if (tt__parse_u64(o->name, v, 0, TT_HOST_PATH_SAMPLES - 1, &n)) return -1;
    c0 = c1 = (unsigned)n;
  }
  opt->camera_index = c0;
  opt->camera_index_last = c1;
  opt->camera_index_set = 1;
  return 0;
}

/* The TT__AOV_* bit of the `len` characters at `name`, or 0. */
static uint32_t tt__aov_bit(const char *name, size_t len) {
  static const struct { const char *name; uint32_t bit; } aovs[] = {
    {"depth", TT__AOV_DEPTH}, {"normal", TT__AOV_NORMAL}, {"albedo", TT__AOV_ALBEDO},
    {"motion", TT__AOV_MOTION}, {"prevdepth", TT__AOV_PREVDEPTH}};
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
      fprintf(stderr, "host: %s: expected a comma-separated list of depth, normal, albedo, "
              "motion, prevdepth (or none), got \"%.*s\" in \"%s\"\n", o->name, (int)len, p, v);
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
    fprintf(stderr, "host: %s: %s\n", o->name, tt_last_error());
    return -1;
  }
  opt->indicator_norm = v;
  return 0;
}

int tt__set_out(const tt__option *o, const char *v, tt__host_options *opt) {
  const char *dot = strrchr(v, '.');
  if (!dot || (strcmp(dot, ".exr") != 0 && strcmp(dot, ".json") != 0)) {
    fprintf(stderr, "host: %s: expected a file name ending in .exr (.json with --convert), got "
            "\"%s\"\n", o->name, v);
    return -1;
  }
  opt->out = v;
  return 0;
}

int tt__set_stats(const tt__option *o, const char *v, tt__host_options *opt) {
  if (!*v) {
    fprintf(stderr, "host: %s: expected a file name, got an empty string\n", o->name);
    return -1;
  }
  opt->stats = v;
  return 0;
}
