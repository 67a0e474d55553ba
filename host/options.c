/* host: command-line parsing. Every error names the option and what was expected. */
#include "host.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void tt__print_usage(FILE *out) {
  fputs(
    "usage: host [options] [--plugin NAME]... scene.json\n"
    "\n"
    "Renders a scene with swappable plugins (defaults: accel_embree, integrator_pt).\n"
    "\n"
    "Plugins:\n"
    "  --plugin NAME|PATH     load a plugin by name (NAME.so on the search path) or by path\n"
    "  --plugin-path DIR      add DIR to the plugin search path (before $TT_PLUGIN_PATH)\n"
    "  --set PLUGIN.PARAM=V   set a parameter of a loaded plugin, e.g.\n"
    "                         --set accel_embree.quality=3 --set integrator_pt.maxDepth=8\n"
    "  --list-plugins         list the plugins found on the search path\n"
    "  --describe NAME        print the plugin's parameter space as JSON on stdout\n"
    "\n"
    "Rendering:\n"
    "  --spp N                samples per pixel (default: the scene's render.spp)\n"
    "  --time SECONDS         time budget: stop after the pass that exceeds it\n"
    "  --res WxH              override the scene's resolution\n"
    "  --seed N               random seed (default: the scene's render.seed)\n"
    "  --threads N            worker threads (default: all CPUs)\n"
    "\n"
    "Output:\n"
    "  --out FILE.exr         linear EXR; a display-referred PNG is written next to it\n"
    "                         (default: <scene folder>.exr in the current directory)\n"
    "  --stats FILE.json      machine-readable record of the run\n"
    "  --quiet                no progress bar, warnings and errors only\n"
    "  --help, --version\n"
    "\n"
    "Environment: TT_PLUGIN_PATH (':'-separated plugin folders), OCIO (OpenColorIO config\n"
    "for the PNG display transform; built-in sRGB when unset).\n"
    "\n"
    "Exit codes: 0 success, 1 runtime failure, 2 usage error, 3 plugin load failure,\n"
    "4 scene error, 5 output not written, 130 interrupted (partial image written).\n"
    "SIGINT/SIGTERM finish the current pass and write what was rendered so far; a second\n"
    "signal exits at once.\n",
    out);
}

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

/* Returns the value of an option that takes one, or NULL (and prints) if missing. */
static const char *tt__arg(int argc, char **argv, int *i) {
  if (*i + 1 >= argc) {
    fprintf(stderr, "host: %s: missing value\n", argv[*i]);
    return NULL;
  }
  return argv[++*i];
}

/* Appends to a bounded list. */
static int tt__push(const char **list, int *count, const char *opt, const char *value) {
  if (*count >= TT_HOST_MAX_LIST) {
    fprintf(stderr, "host: %s: at most %d times\n", opt, TT_HOST_MAX_LIST);
    return -1;
  }
  list[(*count)++] = value;
  return 0;
}

int tt__parse_options(int argc, char **argv, tt__host_options *opt) {
  memset(opt, 0, sizeof *opt);
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    const char *v;
    uint64_t n;
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      opt->help = 1;
    } else if (!strcmp(a, "--version")) {
      opt->version = 1;
    } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
      opt->quiet = 1;
    } else if (!strcmp(a, "--list-plugins")) {
      opt->list_plugins = 1;
    } else if (!strcmp(a, "--plugin")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__push(opt->plugins, &opt->plugin_count, a, v))
        return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--plugin-path")) {
      if (!(v = tt__arg(argc, argv, &i)) ||
          tt__push(opt->plugin_paths, &opt->plugin_path_count, a, v))
        return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--set")) {
      if (!(v = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      const char *dot = strchr(v, '.'), *eq = strchr(v, '=');
      if (!dot || !eq || dot > eq || dot == v || eq == dot + 1) {
        fprintf(stderr, "host: --set: expected PLUGIN.PARAM=VALUE, got \"%s\"\n", v);
        return TT_EXIT_USAGE;
      }
      if (tt__push(opt->sets, &opt->set_count, a, v)) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--describe")) {
      if (!(opt->describe = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--out") || !strcmp(a, "-o")) {
      if (!(opt->out = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      const char *dot = strrchr(opt->out, '.');
      if (!dot || strcmp(dot, ".exr") != 0) {
        fprintf(stderr, "host: --out: expected a file name ending in .exr, got \"%s\"\n",
                opt->out);
        return TT_EXIT_USAGE;
      }
    } else if (!strcmp(a, "--stats")) {
      if (!(opt->stats = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--spp")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_u64(a, v, 1, 1u << 24, &n))
        return TT_EXIT_USAGE;
      opt->spp = (uint32_t)n;
    } else if (!strcmp(a, "--threads")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_u64(a, v, 1, 1024, &n))
        return TT_EXIT_USAGE;
      opt->threads = (uint32_t)n;
    } else if (!strcmp(a, "--seed")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_u64(a, v, 0, UINT64_MAX, &n))
        return TT_EXIT_USAGE;
      opt->seed = n;
      opt->seed_set = 1;
    } else if (!strcmp(a, "--time")) {
      if (!(v = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      char *end = NULL;
      double t = strtod(v, &end);
      if (!*v || *end || !(t > 0) || t > 1e7) {
        fprintf(stderr, "host: --time: expected seconds > 0, got \"%s\"\n", v);
        return TT_EXIT_USAGE;
      }
      opt->time_budget = t;
    } else if (!strcmp(a, "--res")) {
      if (!(v = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      unsigned w = 0, h = 0;
      char tail = 0;
      if (sscanf(v, "%ux%u%c", &w, &h, &tail) != 2 || w == 0 || h == 0 || w > 65536 ||
          h > 65536) {
        fprintf(stderr, "host: --res: expected WIDTHxHEIGHT (1..65536 each), got \"%s\"\n", v);
        return TT_EXIT_USAGE;
      }
      opt->width = w;
      opt->height = h;
    } else if (a[0] == '-' && a[1] != '\0') {
      fprintf(stderr, "host: unknown option \"%s\" (try --help)\n", a);
      return TT_EXIT_USAGE;
    } else {
      if (opt->scene) {
        fprintf(stderr, "host: more than one scene given (\"%s\" and \"%s\")\n", opt->scene, a);
        return TT_EXIT_USAGE;
      }
      opt->scene = a;
    }
  }
  return TT_EXIT_OK;
}
