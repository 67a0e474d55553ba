/* host: command-line parsing. Every error names the option and what was expected. */
#include "host.h"

#include <tunetrace/suggest.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* The --help text; also the list of options that "did you mean" suggests from. */
static const char tt__usage[] =
    "usage: host [options] [--plugin NAME]... scene.json\n"
    "\n"
    "Renders a scene with swappable plugins (defaults: accel_embree, integrator_pt).\n"
    "\n"
    "Plugins:\n"
    "  --plugin NAME|PATH     load a plugin by name (NAME.so on the search path) or by path\n"
    "  --plugin-path DIR      add DIR to the plugin search path (before $TT_PLUGIN_PATH)\n"
    "  --set PLUGIN.PARAM=V   set a parameter of a loaded plugin, e.g.\n"
    "                         --set accel_embree.quality=3 --set integrator_pt.maxDepth=8\n"
    "  --list-plugins         list the plugins found on the search path (exit 3 if any\n"
    "                         file there was rejected)\n"
    "  --describe NAME        print the plugin's parameter space as JSON on stdout (given\n"
    "                         several times: a JSON array of the spaces, in order)\n"
    "\n"
    "Rendering:\n"
    "  --spp N                samples per pixel (default: the scene's render.spp)\n"
    "  --strict               pbrt-v4 scenes as strictly as pbrt-v4 reads them: an unknown\n"
    "                         directive or parameter (\"WorldBgin\", \"rgb reflectanse\") is\n"
    "                         an error naming file:line, not a warning (exit 4)\n"
    "  --time SECONDS         time budget: stop after the pass that exceeds it\n"
    "  --res WxH              override the scene's resolution\n"
    "  --seed N               random seed (default: the scene's render.seed)\n"
    "  --threads N            worker threads (default: all CPUs)\n"
    "\n"
    "Tuning (thesis Fig. 3.2; see host/README.md):\n"
    "  --plugin TUNER         loading a tuner (e.g. tuner_nm) turns tuning on: before the\n"
    "                         final passes the host measures the target's default\n"
    "                         configuration, then asks the tuner for --iterations\n"
    "                         configurations, measuring each with one pass, and renders\n"
    "                         the remaining spp with the best one\n"
    "  --tune PLUGIN          the loaded plugin whose space is tuned (accel, integrator or\n"
    "                         post). Default: the integrator if it serves a tuning hint\n"
    "                         (tt.tuning_hint/1), else the accel\n"
    "  --objective SPEC       what is minimised per measurement:\n"
    "                           render         render ms of the pass (default)\n"
    "                           build          accel build ms (accel targets)\n"
    "                           build+render   both (accel targets; alias: total)\n"
    "                           metric:NAME    an integrator metric of the pass, minimised;\n"
    "                           metric:NAME:max            ... maximised\n"
    "                           metric:NAME:target=X       ... |value - X| minimised,\n"
    "                                          e.g. metric:acceptance:target=0.234\n"
    "                           rrmse          rRMSE of the pass's own image (luminance)\n"
    "                                          against --reference; any integrator\n"
    "  --reference FILE.exr   the reference image of --objective rrmse (same resolution\n"
    "                         as the render)\n"
    "  --tune-pass-images DIR write each measured tuning pass's own image (not the\n"
    "                         accumulated film) to DIR/pass_default.exr, pass_NNNN.exr\n"
    "  --tune-params A,B,...  search only these parameters of the target; the others keep\n"
    "                         their configured values (default: the tuning hint's list,\n"
    "                         e.g. PSSMLT's a_i and sigma_i, else all)\n"
    "  --iterations N         configurations to ask the tuner for (default 50)\n"
    "  --tune-spp N           samples per pixel of one measurement pass (default 1)\n"
    "  --explore N            measure N random configurations of the target's space (no\n"
    "                         tuner needed), for the analysis tools in tools/tuning/\n"
    "  --verify N             after tuning, measure the default and the best configuration\n"
    "                         side by side, alternating, N rounds of one pass each; the\n"
    "                         median ratios go to the log and to --stats (tuning.verify)\n"
    "  --db PATH              tuning database (SQLite; default\n"
    "                         $XDG_DATA_HOME/tunetrace/tuning.db, else\n"
    "                         ~/.local/share/tunetrace/tuning.db). A configuration already\n"
    "                         measured in the same state on this machine is not measured\n"
    "                         again: its stored cost is fed to the tuner\n"
    "  --no-db                no database: measure everything, record nothing\n"
    "  --resume FILE          save the tuning session (its samples and the tuner's state) to\n"
    "                         FILE after every sample; when FILE exists, continue from it\n"
    "                         (kill a long tuning run, run the same command again)\n"
    "  --clock wall|cpu       what build and render times measure: wall time (default) or\n"
    "                         the process's CPU time, which other processes running on the\n"
    "                         same cores do not inflate (use it with --threads 1 on a\n"
    "                         shared machine); tuning rows record the clock in `context`\n"
    "\n"
    "Sequences (temporal filters, see tools/taa/README.md):\n"
    "  --sequence N|A:B       render frames 0..N-1 (or A..B) of the scene's camera path at\n"
    "                         --fps (default 24), each with one Halton(2,3) sub-pixel\n"
    "                         jitter of a cycle of 8 for all its samples; writes\n"
    "                         color/depth/motion/prevdepth_NNNN.exr and manifest.json to\n"
    "                         --out-dir\n"
    "  --out-dir DIR          folder of the sequence (created if missing)\n"
    "  --reference-scale K    also render each frame at K x K the resolution and write the\n"
    "                         Blackman-Harris-downsampled reference_NNNN.exr\n"
    "  --post NAME            run the post-filter NAME (e.g. post_taa) over the frames in\n"
    "                         order and write post_NNNN.exr; --set NAME.mode=network ...\n"
    "  --fps F                frames per second along the camera path (default 24)\n"
    "  --frames A:B --out DIR/frame_%04d.exr\n"
    "                         the same as a sequence of frames A..B, each written to the\n"
    "                         pattern (manifest.json in DIR); beside it: --aov depth,motion\n"
    "                         -> frame_NNNN.depth.exr / .motion.exr (.normal, .albedo too);\n"
    "                         --supersample K writes\n"
    "                         the K x K-supersampled reference as the frame instead; a\n"
    "                         post-filter (--plugin post_taa --set post_taa.mode=network)\n"
    "                         writes the filtered frame, the rendered one as frame_NNNN.raw.exr\n"
    "  --aov LIST             per-frame AOVs: depth, normal, albedo, motion, prevdepth (the\n"
    "                         depth of each pixel's surface point in the previous frame's\n"
    "                         camera, for disocclusion tests; sequences only); default:\n"
    "                         depth, motion and prevdepth with --out-dir, none with an --out\n"
    "                         pattern\n"
    "  --supersample K        write only the reference (K x K the resolution, Blackman-Harris)\n"
    "  --png                  also write a display-referred PNG preview of every frame (of\n"
    "                         the frame the pattern names: filtered, or the reference with\n"
    "                         --supersample) beside its EXR, listed in the manifest as \"png\"\n"
    "                         (a still always gets its PNG)\n"
    "  --set NAME.KEY=VALUE   also sets a plugin's options (not tuned; host --describe NAME),\n"
    "                         e.g. --set post_taa.weights=FILE.ttw\n"
    "\n"
    "Camera path samples (benchmark views, scenes/README.md):\n"
    "  --camera-index I       render sample I (0..99) of the scene's camera path: the pose\n"
    "                         at t = I/99 of the path's time range (no path: still camera)\n"
    "  --frames A:B           render frames A..B (both included) of the camera path at\n"
    "                         --fps (frame f is the pose at t = f / fps, as in sequences),\n"
    "                         each a full render, to <out stem>_NNNN.exr/.png (default\n"
    "                         stem: <scene folder>); with an --out pattern they are the\n"
    "                         jittered frames of a sequence (above)\n"
    "\n"
    "Output:\n"
    "  --out, -o FILE.exr     linear EXR; a display-referred PNG is written next to it\n"
    "                         (default: <scene folder>.exr in the current directory)\n"
    "  --aov LIST             also write AOVs as layers of the EXR: depth (depth.Z), normal\n"
    "                         (normal.X/Y/Z), albedo (albedo.R/G/B), motion (motion.X/Y)\n"
    "  --stats FILE.json      machine-readable record of the run\n"
    "  --convert              write the loaded scene (scene.json or .pbrt) as scene.json v1\n"
    "                         to --out FILE.json, meshes as PLY in meshes/ next to it; no render\n"
    "  --indicators           print the scene's indicators (thesis Table 3.2) for its still\n"
    "                         camera or --camera-index I as JSON: raw, normalised to [0,1]\n"
    "                         (the predictors' state), bounds, what was clamped, compute ms\n"
    "  --indicator-norm SPEC  normalisation of the indicators: camera=extent|table|text,\n"
    "                         scale=linear|log (default camera=extent,scale=linear)\n"
    "  --quiet, -q            no progress bar and no progress messages; warnings and errors\n"
    "                         are still printed\n"
    "  --help, -h             this text\n"
    "  --version              the version and the plugin ABI\n"
    "\n"
    "An option's value may also be attached with '=': --spp=64, --out=box.exr.\n"
    "\n"
    "Hybrid tuning (thesis 3.3; host/README.md):\n"
    "  --hybrid               over the camera path (--camera-index A:B: samples A..B, both\n"
    "                         included; default all 100):\n"
    "                         per state, explore (the tuner, --iterations K, default 40)\n"
    "                         with probability --epsilon, else exploit (one configuration\n"
    "                         the predictor plugin predicts, built once); every cost goes\n"
    "                         to the database and the model. --plugin predictor_nn (default)\n"
    "                         | predictor_rbf | predictor_static, --plugin tuner_nm (default)\n"
    "  --epsilon E            probability of exploring a state, in [0, 1] (default 0.1)\n"
    "  --model FILE           the model: loaded when FILE exists, saved there at the end\n"
    "  --warm-start DB        teach the model every usable row of a tuning database first\n"
    "                         (other scenes, earlier runs; same objective, clock, spp, threads)\n"
    "  --predict              print the model's prediction per state as JSON; render nothing\n"
    "  --states FILE.json     --predict for these states ([{\"id\": ..., \"indicators\":\n"
    "                         {name: raw value, ...}}, ...]) instead of the path samples\n"
    "  --measure FILE.json    measure the accel configurations of FILE (a JSON array; the\n"
    "                         first should be the default) side by side: --rounds R (3)\n"
    "                         rounds, order alternating, medians and ratios to the first as\n"
    "                         JSON on stdout (--camera-index I, --objective, --tune-spp)\n"
    "\n"
    "Environment: TT_PLUGIN_PATH (':'-separated plugin folders), OCIO (OpenColorIO config\n"
    "for the PNG display transform; built-in sRGB when unset).\n"
    "\n"
    "Exit codes: 0 success, 1 runtime failure, 2 usage error, 3 plugin load failure,\n"
    "4 scene error, 5 output not written, 130 interrupted (partial image written).\n"
    "SIGINT/SIGTERM finish the current pass and write what was rendered so far; a second\n"
    "signal exits at once.\n";

void tt__print_usage(FILE *out) { fputs(tt__usage, out); }

/* Every long option named in the --help text, for "did you mean" (filled once). */
static size_t tt__known_options(const char **names, size_t cap) {
  static char words[256][32];
  static size_t count;
  if (!count) {
    for (const char *p = tt__usage; (p = strstr(p, "--")) && count < 256;) {
      const char *q = p + 2;
      while ((*q >= 'a' && *q <= 'z') || (*q >= '0' && *q <= '9') || *q == '-') q++;
      size_t len = (size_t)(q - p);
      if (len > 3 && len < sizeof words[0] && p[2] != '-') {
        char w[32];
        snprintf(w, sizeof w, "%.*s", (int)len, p);
        size_t k = 0;
        while (k < count && strcmp(words[k], w)) k++;
        if (k == count) snprintf(words[count++], sizeof words[0], "%s", w);
      }
      p = q;
    }
  }
  size_t n = count < cap ? count : cap;
  for (size_t k = 0; k < n; k++) names[k] = words[k];
  return n;
}

/* Options that take no value: "--NAME=VALUE" is split into "--NAME" "VALUE" for all the
 * others. */
static int tt__is_flag(const char *name) {
  static const char *const flags[] = {"--help", "--version", "--quiet", "--list-plugins",
                                      "--convert", "--no-db", "--strict", "--png"};
  for (size_t k = 0; k < sizeof flags / sizeof flags[0]; k++)
    if (!strcmp(name, flags[k])) return 1;
  return 0;
}

/* Prints the unknown-option error, with the closest known option when one is close. */
static void tt__unknown_option(const char *a) {
  const char *names[256];
  size_t n = tt__known_options(names, 256);
  const char *near = tt_suggest(a, names, n);
  if (near)
    fprintf(stderr, "host: unknown option \"%s\"; did you mean %s? (try --help)\n", a, near);
  else
    fprintf(stderr, "host: unknown option \"%s\" (try --help)\n", a);
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

/* Parses --aov "depth,normal,albedo,motion,prevdepth" into TT__AOV_* bits ("none" = no AOV). */
static int tt__parse_aovs(const char *text, uint32_t *mask) {
  static const struct { const char *name; uint32_t bit; } aovs[] = {
    {"depth", TT__AOV_DEPTH}, {"normal", TT__AOV_NORMAL}, {"albedo", TT__AOV_ALBEDO},
    {"motion", TT__AOV_MOTION}, {"prevdepth", TT__AOV_PREVDEPTH}};
  *mask = 0;
  if (!strcmp(text, "none")) return 0;
  const char *p = text;
  while (*p) {
    size_t len = strcspn(p, ","), k = 0;
    while (k < sizeof aovs / sizeof aovs[0] &&
           (strlen(aovs[k].name) != len || strncmp(p, aovs[k].name, len)))
      k++;
    if (k < sizeof aovs / sizeof aovs[0]) {
      *mask |= aovs[k].bit;
    } else {
      fprintf(stderr, "host: --aov: expected a comma-separated list of depth, normal, albedo, "
              "motion, prevdepth (or none), got \"%.*s\" in \"%s\"\n", (int)len, p, text);
      return -1;
    }
    p += len;
    if (*p == ',') p++;
  }
  return 0;
}

/* 1 when `out` is a frame-number pattern: exactly one %d, %Nd or %0Nd (and %% escapes);
 * 0 when it has no '%'; -1 (and prints) when its '%' conversions are not that. */
static int tt__out_pattern(const char *out) {
  int convs = 0;
  for (const char *p = out; *p; p++) {
    if (*p != '%') continue;
    if (p[1] == '%') {
      p++;
      continue;
    }
    const char *q = p + 1;
    while (*q >= '0' && *q <= '9') q++;
    if (*q != 'd' || q - p > 4) convs = 99;
    else convs++;
    p = q;
  }
  if (convs == 0 && !strchr(out, '%')) return 0;
  if (convs == 1) return 1;
  fprintf(stderr, "host: --out %s: a frame pattern needs exactly one %%d, %%4d or %%04d "
          "(the frame number; %%%% for a literal %%)\n", out);
  return -1;
}

/* Checks and resolves the sequence options once all are read: --frames means frames of a
 * sequence when --out is a pattern (DIR/frame_%04d.exr), else camera path samples. */
static int tt__check_sequence_options(tt__host_options *opt) {
  int pattern = opt->out ? tt__out_pattern(opt->out) : 0;
  if (pattern < 0) return -1;
  const char *v = opt->frames_arg;
  unsigned f0 = 0, f1 = 0;
  char extra;
  int range = v && v[0] >= '0' && v[0] <= '9' && sscanf(v, "%u:%u%c", &f0, &f1, &extra) == 2;
  if (pattern) {
    if (opt->out_dir) {
      fprintf(stderr, "host: --out %s (a frame pattern) and --out-dir exclude each other\n",
              opt->out);
      return -1;
    }
    if (v && opt->sequence) {
      fprintf(stderr, "host: --frames and --sequence exclude each other\n");
      return -1;
    }
    if (v) {
      if (!range || f0 > f1) {
        fprintf(stderr, "host: --frames: expected A:B with A <= B (frames A..B of the "
                "camera path, written to --out %s), got \"%s\"\n", opt->out, v);
        return -1;
      }
      opt->sequence = 1;
      opt->seq_first = f0;
      opt->seq_last = f1;
    }
    if (!opt->sequence) {
      fprintf(stderr, "host: --out %s is a frame pattern: give the frames with --frames A:B "
              "(or --sequence N)\n", opt->out);
      return -1;
    }
    if (opt->camera_index_set) {
      fprintf(stderr, "host: --camera-index and a frame pattern in --out exclude each "
              "other\n");
      return -1;
    }
    const char *dot = strrchr(opt->out, '.');
    if (!dot || strcmp(dot, ".exr")) {
      fprintf(stderr, "host: --out %s: expected a file pattern ending in .exr\n", opt->out);
      return -1;
    }
    opt->seq_pattern = opt->out;
    opt->out = NULL;
  } else if (v) {
    /* the same frames as with a pattern (A..B at --fps), each a full still render */
    if (!range || f0 > f1) {
      fprintf(stderr, "host: --frames: expected A:B with A <= B (frames A..B of the camera "
              "path at --fps, both included), got \"%s\"\n", v);
      return -1;
    }
    opt->frames = 1;
    opt->frames_first = f0;
    opt->frames_last = f1;
  }
  if (!opt->sequence && opt->reference_only) {
    fprintf(stderr, "host: --supersample applies to sequences: give --frames A:B "
            "with --out DIR/frame_%%04d.exr, or --sequence\n");
    return -1;
  }
  if (!opt->sequence && (opt->aov_mask & TT__AOV_PREVDEPTH)) {
    fprintf(stderr, "host: --aov prevdepth applies to sequences (it needs the previous "
            "frame's camera): give --frames A:B with --out DIR/frame_%%04d.exr, or --sequence\n");
    return -1;
  }
  if (!opt->sequence && (opt->reference_scale || (opt->out_dir && !opt->hybrid))) {
    fprintf(stderr, "host: --reference-scale and --out-dir apply to --sequence (--out-dir also "
            "to --hybrid)\n");
    return -1;
  }
  if (opt->reference_only && opt->post) {
    fprintf(stderr, "host: --supersample writes the reference frames: no --post filter "
            "(render the filtered frames in a separate run)\n");
    return -1;
  }
  if (opt->sequence && !opt->aov_set)  /* --out-dir sequences: depth, motion, prevdepth */
    opt->aov_mask = opt->seq_pattern ? 0 : TT__AOV_DEPTH | TT__AOV_MOTION | TT__AOV_PREVDEPTH;
  return 0;
}

/* The split argv of tt__split_equals, kept for the process's lifetime: the options point
 * into it (held here, it is reachable, not a leak LeakSanitizer reports at exit). */
static char **tt__split_argv;

/* argv with every "--NAME=VALUE" of an option that takes a value split in two (the value
 * points into the original argument; the names are allocated once per process). */
static char **tt__split_equals(int argc, char **argv, int *out_argc) {
  char **v = calloc((size_t)argc * 2 + 1, sizeof *v);
  if (!v) return NULL;
  int n = 0;
  for (int i = 0; i < argc; i++) {
    const char *a = argv[i], *eq = a[0] == '-' && a[1] == '-' ? strchr(a, '=') : NULL;
    if (i == 0 || !eq) {
      v[n++] = argv[i];
      continue;
    }
    char *name = malloc((size_t)(eq - a) + 1);
    if (!name) {
      free(v);
      return NULL;
    }
    memcpy(name, a, (size_t)(eq - a));
    name[eq - a] = '\0';
    if (tt__is_flag(name)) {
      v[n++] = argv[i];  /* reported below: a flag takes no value */
      free(name);
      continue;
    }
    v[n++] = name;
    v[n++] = (char *)(eq + 1);
  }
  *out_argc = n;
  tt__split_argv = v;  /* the options point into it until the process ends */
  return v;
}

int tt__parse_options(int argc0, char **argv0, tt__host_options *opt) {
  memset(opt, 0, sizeof *opt);
  int argc = 0;
  char **argv = tt__split_equals(argc0, argv0, &argc);
  if (!argv) {
    fprintf(stderr, "host: out of memory reading the command line\n");
    return TT_EXIT_USAGE;
  }
  opt->argc = argc0;
  opt->argv = argv0;
  struct timespec now;
  clock_gettime(CLOCK_REALTIME, &now);
  opt->started_ns = (int64_t)now.tv_sec * 1000000000 + now.tv_nsec;
  /* argv lives as long as the options point into it: the whole process */
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    const char *v;
    uint64_t n;
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      opt->help = 1;
    } else if (!strcmp(a, "--version")) {
      opt->version = 1;
    } else if (!strcmp(a, "--png")) {
      opt->png = 1;
    } else if (!strcmp(a, "--strict")) {
      opt->strict = 1;
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
      if (!(v = tt__arg(argc, argv, &i)) || tt__push(opt->describe, &opt->describe_count, a, v))
        return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--convert")) {
      opt->convert = 1;
    } else if (!strcmp(a, "--indicators")) {
      opt->indicators = 1;
    } else if (!strcmp(a, "--hybrid")) {
      opt->hybrid = 1;
    } else if (!strcmp(a, "--predict")) {
      opt->predict_only = 1;
    } else if (!strcmp(a, "--epsilon")) {
      if (!(v = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      char *end = NULL;
      double e = strtod(v, &end);
      if (!*v || *end || !(e >= 0.0 && e <= 1.0)) {
        fprintf(stderr, "host: --epsilon: expected the probability of exploring a state, a "
                "number in [0, 1], got \"%s\"\n", v);
        return TT_EXIT_USAGE;
      }
      opt->epsilon = e;
      opt->epsilon_set = 1;
    } else if (!strcmp(a, "--states")) {
      if (!(opt->states = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--measure")) {
      if (!(opt->measure = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--rounds")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_u64(a, v, 1, 10000, &n))
        return TT_EXIT_USAGE;
      opt->rounds = (uint32_t)n;
    } else if (!strcmp(a, "--resume")) {
      if (!(opt->resume = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--model")) {
      if (!(opt->model = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--warm-start")) {
      if (!(v = tt__arg(argc, argv, &i)) ||
          tt__push(opt->warm_start, &opt->warm_start_count, a, v))
        return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--indicator-norm")) {
      tt_indicator_norm norm;
      if (!(opt->indicator_norm = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      if (tt_indicator_norm_parse(opt->indicator_norm, &norm) != TT_OK) {
        fprintf(stderr, "host: --indicator-norm: %s\n", tt_last_error());
        return TT_EXIT_USAGE;
      }
    } else if (!strcmp(a, "--out") || !strcmp(a, "-o")) {
      if (!(opt->out = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      const char *dot = strrchr(opt->out, '.');
      if (!dot || (strcmp(dot, ".exr") != 0 && strcmp(dot, ".json") != 0)) {
        fprintf(stderr, "host: --out: expected a file name ending in .exr (.json with --convert), "
                "got \"%s\"\n", opt->out);
        return TT_EXIT_USAGE;
      }
    } else if (!strcmp(a, "--stats")) {
      if (!(opt->stats = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      if (!*opt->stats) {
        fprintf(stderr, "host: --stats: expected a file name, got an empty string\n");
        return TT_EXIT_USAGE;
      }
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
    } else if (!strcmp(a, "--tune")) {
      if (!(opt->tune = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--objective")) {
      tt_objective obj;
      if (!(opt->objective = tt__arg(argc, argv, &i)) ||
          tt__parse_objective(a, opt->objective, &obj))
        return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--tune-params")) {
      if (!(opt->tune_params = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      if (!opt->tune_params[0] || strstr(opt->tune_params, ",,") ||
          opt->tune_params[0] == ',' || opt->tune_params[strlen(opt->tune_params) - 1] == ',') {
        fprintf(stderr, "host: --tune-params: expected NAME[,NAME...], got \"%s\"\n",
                opt->tune_params);
        return TT_EXIT_USAGE;
      }
    } else if (!strcmp(a, "--iterations")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_u64(a, v, 1, 1000000, &n))
        return TT_EXIT_USAGE;
      opt->iterations = (uint32_t)n;
    } else if (!strcmp(a, "--tune-spp")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_u64(a, v, 1, 1u << 16, &n))
        return TT_EXIT_USAGE;
      opt->tune_spp = (uint32_t)n;
    } else if (!strcmp(a, "--explore")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_u64(a, v, 1, 1000000, &n))
        return TT_EXIT_USAGE;
      opt->explore = (uint32_t)n;
    } else if (!strcmp(a, "--verify")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_u64(a, v, 1, 10000, &n))
        return TT_EXIT_USAGE;
      opt->verify = (uint32_t)n;
    } else if (!strcmp(a, "--db")) {
      if (!(opt->db = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--no-db")) {
      opt->no_db = 1;
    } else if (!strcmp(a, "--clock")) {
      if (!(v = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      if (!strcmp(v, "cpu")) opt->clock_cpu = 1;
      else if (!strcmp(v, "wall")) opt->clock_cpu = 0;
      else {
        fprintf(stderr, "host: --clock: expected wall or cpu, got \"%s\"\n", v);
        return TT_EXIT_USAGE;
      }
    } else if (!strcmp(a, "--reference")) {
      if (!(opt->reference = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--tune-pass-images")) {
      if (!(opt->tune_pass_images = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--sequence")) {
      /* "N" renders frames 0..N-1, "A:B" frames A..B inclusive (sequence.c). */
      unsigned f0 = 0, f1 = 0;
      char extra;
      if (!(v = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      if (v[0] >= '0' && v[0] <= '9' && sscanf(v, "%u:%u%c", &f0, &f1, &extra) == 2 && f0 <= f1) {
        opt->seq_first = f0;
        opt->seq_last = f1;
      } else if (v[0] >= '0' && v[0] <= '9' && sscanf(v, "%u%c", &f0, &extra) == 1 && f0 >= 1) {
        opt->seq_first = 0;
        opt->seq_last = f0 - 1;
      } else {
        fprintf(stderr, "host: --sequence: expected a frame count N >= 1 or a range A:B "
                "with A <= B, got \"%s\"\n", v);
        return TT_EXIT_USAGE;
      }
      opt->sequence = 1;
    } else if (!strcmp(a, "--out-dir")) {
      if (!(opt->out_dir = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--post")) {
      if (!(opt->post = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--reference-scale")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_u64(a, v, 1, 16, &n)) return TT_EXIT_USAGE;
      opt->reference_scale = (uint32_t)n;
    } else if (!strcmp(a, "--fps")) {
      if (!(v = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      char *end = NULL;
      double fps = strtod(v, &end);
      if (!*v || *end || !(fps > 0) || fps > 1000) {
        fprintf(stderr, "host: --fps: expected frames per second in (0, 1000], got \"%s\"\n", v);
        return TT_EXIT_USAGE;
      }
      opt->fps = fps;
    } else if (!strcmp(a, "--camera-index")) {
      /* I, or A:B (samples A..B, both included: the states of --hybrid and --predict) */
      if (!(v = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
      unsigned c0 = 0, c1 = 0;
      char extra;
      if (strchr(v, ':')) {
        if (!(v[0] >= '0' && v[0] <= '9') || sscanf(v, "%u:%u%c", &c0, &c1, &extra) != 2 ||
            c0 > c1 || c1 >= TT_HOST_PATH_SAMPLES) {
          fprintf(stderr, "host: --camera-index: expected I or A:B with A <= B <= %d (path "
                  "samples A..B, both included), got \"%s\"\n", TT_HOST_PATH_SAMPLES - 1, v);
          return TT_EXIT_USAGE;
        }
        opt->camera_index_range = 1;
      } else {
        if (tt__parse_u64(a, v, 0, TT_HOST_PATH_SAMPLES - 1, &n)) return TT_EXIT_USAGE;
        c0 = c1 = (unsigned)n;
      }
      opt->camera_index = c0;
      opt->camera_index_last = c1;
      opt->camera_index_set = 1;
    } else if (!strcmp(a, "--frames")) {
      if (!(opt->frames_arg = tt__arg(argc, argv, &i))) return TT_EXIT_USAGE;
    } else if (!strcmp(a, "--aov")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_aovs(v, &opt->aov_mask))
        return TT_EXIT_USAGE;
      opt->aov_set = 1;
    } else if (!strcmp(a, "--supersample")) {
      if (!(v = tt__arg(argc, argv, &i)) || tt__parse_u64(a, v, 1, 16, &n)) return TT_EXIT_USAGE;
      opt->reference_scale = (uint32_t)n;
      opt->reference_only = 1;
    } else if (a[0] == '-' && a[1] == '-' && strchr(a, '=')) {
      fprintf(stderr, "host: %.*s takes no value, got \"%s\"\n", (int)(strchr(a, '=') - a), a,
              a);
      return TT_EXIT_USAGE;
    } else if (a[0] == '-' && a[1] != '\0') {
      tt__unknown_option(a);
      return TT_EXIT_USAGE;
    } else {
      if (opt->scene) {
        fprintf(stderr, "host: more than one scene given (\"%s\" and \"%s\")\n", opt->scene, a);
        return TT_EXIT_USAGE;
      }
      opt->scene = a;
    }
  }
  {
    tt_objective obj;
    int rrmse = opt->objective && !tt__parse_objective("--objective", opt->objective, &obj) &&
                obj.kind == TT_OBJECTIVE_RRMSE;
    if (rrmse && !opt->reference) {
      fprintf(stderr, "host: --objective rrmse needs --reference FILE.exr (an image of the "
              "same scene and resolution, e.g. a high-spp integrator_pt render)\n");
      return TT_EXIT_USAGE;
    }
    if (opt->reference && !rrmse) {
      fprintf(stderr, "host: --reference %s: only --objective rrmse uses a reference\n",
              opt->reference);
      return TT_EXIT_USAGE;
    }
  }
  if (tt__check_sequence_options(opt)) return TT_EXIT_USAGE;
  if (opt->db && opt->no_db) {
    fprintf(stderr, "host: --db and --no-db exclude each other\n");
    return TT_EXIT_USAGE;
  }
  if ((opt->frames || opt->camera_index_set) && opt->sequence) {
    fprintf(stderr, "host: --camera-index/--frames and --sequence exclude each other\n");
    return TT_EXIT_USAGE;
  }
  if ((opt->hybrid || opt->predict_only) && opt->frames_arg) {
    fprintf(stderr, "host: --%s: the states are camera path samples (of %d over the path's "
            "time range): give them with --camera-index A:B (samples A..B, both included); "
            "--frames A:B means frames at --fps\n", opt->hybrid ? "hybrid" : "predict",
            TT_HOST_PATH_SAMPLES);
    return TT_EXIT_USAGE;
  }
  if (opt->camera_index_range && !opt->hybrid && !opt->predict_only) {
    fprintf(stderr, "host: --camera-index A:B (a range of path samples) applies to --hybrid "
            "and --predict; render one sample with --camera-index I, or frames with "
            "--frames A:B\n");
    return TT_EXIT_USAGE;
  }
  if (opt->frames && opt->camera_index_set) {
    fprintf(stderr, "host: --camera-index and --frames exclude each other\n");
    return TT_EXIT_USAGE;
  }
  const char *odot = opt->out ? strrchr(opt->out, '.') : NULL;
  int out_json = odot && strcmp(odot, ".json") == 0;
  if (opt->convert && !out_json) {
    fprintf(stderr, "host: --convert: expected --out FILE.json (the scene.json to write)\n");
    return TT_EXIT_USAGE;
  }
  if (!opt->convert && out_json) {
    fprintf(stderr, "host: --out: expected a file name ending in .exr, got \"%s\" (.json only "
            "with --convert)\n", opt->out);
    return TT_EXIT_USAGE;
  }
  return TT_EXIT_OK;
}

int tt__parse_objective(const char *opt, const char *text, tt_objective *out) {
  if (tt_objective_parse(text, out) == TT_OK) return 0;
  fprintf(stderr, "host: %s: %s\n", opt, tt_last_error());
  return -1;
}
