/* host: command-line parsing over the option table (option_table.c), then the checks that
 * involve several options. Every error names the option and what was expected. */
#include "host.h"
#include "option_table.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Prints the unknown-option error, with the closest known option when one is close. */
static int tt__unknown_option(const char *arg) {
  const char *eq = arg[0] == '-' && arg[1] == '-' ? strchr(arg, '=') : NULL;
  char name[256];
  snprintf(name, sizeof name, "%.*s", eq ? (int)(eq - arg) : (int)strlen(arg), arg);
  const char *near = tt__option_suggest(name);
  if (near) tt__say("unknown option \"%s\"; did you mean %s? (try --help)\n", name, near);
  else tt__say("unknown option \"%s\" (try --help)\n", name);
  return -1;
}

/* 1 when `arg` reads as a word (a --help topic), not an option or a file name. */
static int tt__is_word(const char *arg) { return arg[0] && arg[0] != '-' && !strpbrk(arg, "./"); }

/* Reads the option at argv[*i] and its value (attached with '=' or the next argument). */
static int tt__read_option(int argc, char **argv, int *i, tt__host_options *opt) {
  const char *a = argv[*i], *value;
  const tt__option *o = tt__option_of_arg(a, &value);
  if (!o) return tt__unknown_option(a);
  if (o->arg == TT__ARG_NONE && value) {
    tt__say("%.*s takes no value, got \"%s\"\n", (int)(value - 1 - a), a, a);
    return -1;
  }
  if (o->arg == TT__ARG_TOPIC && !value && *i + 1 < argc && tt__is_word(argv[*i + 1]))
    value = argv[++*i]; /* --help TOPIC; not a scene file */
  if (o->arg == TT__ARG_ONE && !value) {
    if (*i + 1 >= argc) {
      tt__say("%s: missing value\n", a);
      return -1;
    }
    value = argv[++*i];
  }
  return o->set(o, value, opt);
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
  tt__say("--out %s: a frame pattern needs exactly one %%d, %%4d or %%04d "
          "(the frame number; %%%% for a literal %%)\n",
          out);
  return -1;
}

/* --frames A:B as two frame numbers (tunetrace/limits.h); 0 when it is not that (or A > B). */
static int tt__frames_range(const char *v, uint32_t *f0, uint32_t *f1) {
  uint64_t a, b;
  if (tt_limit_parse_span(TT_LIMIT_FRAME, v, &a, &b) != TT_OK) return 0;
  *f0 = (uint32_t)a;
  *f1 = (uint32_t)b;
  return 1;
}

/* --out DIR/frame_%04d.exr: the frames of a sequence (--frames A:B or --sequence) go there. */
static int tt__use_out_pattern(tt__host_options *opt) {
  const char *v = opt->frames_arg;
  uint32_t f0 = 0, f1 = 0;
  if (opt->out_dir) {
    tt__say("--out %s (a frame pattern) and --out-dir exclude each other\n", opt->out);
    return -1;
  }
  if (v && opt->sequence) {
    tt__say("--frames and --sequence exclude each other\n");
    return -1;
  }
  if (v && !tt__frames_range(v, &f0, &f1)) {
    tt__say("--frames: expected A:B with A <= B (frames A..B of the camera path, "
            "written to --out %s), got \"%s\"\n",
            opt->out, v);
    return -1;
  }
  if (v) {
    opt->sequence = 1;
    opt->seq_first = f0;
    opt->seq_last = f1;
  }
  if (!opt->sequence) {
    tt__say("--out %s is a frame pattern: give the frames with --frames A:B (or "
            "--sequence N)\n",
            opt->out);
    return -1;
  }
  return 0;
}

/* The pattern's other rules: no --camera-index, an .exr name; then it replaces --out. */
static int tt__check_out_pattern(tt__host_options *opt) {
  if (opt->camera_index_set) {
    tt__say("--camera-index and a frame pattern in --out exclude each other\n");
    return -1;
  }
  const char *dot = strrchr(opt->out, '.');
  if (!dot || strcmp(dot, ".exr")) {
    tt__say("--out %s: expected a file pattern ending in .exr\n", opt->out);
    return -1;
  }
  opt->seq_pattern = opt->out;
  opt->out = NULL;
  return 0;
}

/* --frames A:B without a pattern: the same frames (A..B at --fps), each a full still render. */
static int tt__use_still_frames(tt__host_options *opt) {
  uint32_t f0 = 0, f1 = 0;
  if (!tt__frames_range(opt->frames_arg, &f0, &f1)) {
    tt__say("--frames: expected A:B with A <= B (frames A..B of the camera path "
            "at --fps, both included), got \"%s\"\n",
            opt->frames_arg);
    return -1;
  }
  opt->frames = 1;
  opt->frames_first = f0;
  opt->frames_last = f1;
  return 0;
}

/* Options that only sequences take. */
static int tt__check_sequence_only(const tt__host_options *opt) {
  if (!opt->sequence && opt->reference_only) {
    tt__say("--supersample applies to sequences: give --frames A:B with --out "
            "DIR/frame_%%04d.exr, or --sequence\n");
    return -1;
  }
  if (!opt->sequence && (opt->aov_mask & TT__AOV_PREVDEPTH)) {
    tt__say("--aov prevdepth applies to sequences (it needs the previous frame's "
            "camera): give --frames A:B with --out DIR/frame_%%04d.exr, or --sequence\n");
    return -1;
  }
  if (!opt->sequence && (opt->reference_scale || (opt->out_dir && !opt->hybrid))) {
    tt__say("--reference-scale and --out-dir apply to --sequence (--out-dir also "
            "to --hybrid)\n");
    return -1;
  }
  if (opt->reference_only && opt->post) {
    tt__say("--supersample writes the reference frames: no --post filter (render "
            "the filtered frames in a separate run)\n");
    return -1;
  }
  return 0;
}

/* Resolves the sequence options once all are read: --frames means frames of a sequence when
 * --out is a pattern (DIR/frame_%04d.exr), else frames rendered as stills. */
static int tt__check_sequence_options(tt__host_options *opt) {
  int pattern = opt->out ? tt__out_pattern(opt->out) : 0;
  if (pattern < 0) return -1;
  if (pattern && (tt__use_out_pattern(opt) || tt__check_out_pattern(opt))) return -1;
  if (!pattern && opt->frames_arg && tt__use_still_frames(opt)) return -1;
  if (tt__check_sequence_only(opt)) return -1;
  if (opt->sequence && !opt->aov_set) /* --out-dir sequences: depth, motion, prevdepth */
    opt->aov_mask = opt->seq_pattern ? 0 : TT__AOV_DEPTH | TT__AOV_MOTION | TT__AOV_PREVDEPTH;
  return 0;
}

/* --objective rrmse and --reference go together. */
static int tt__check_reference(const tt__host_options *opt) {
  tt_objective obj;
  int rrmse = opt->objective && !tt__parse_objective("--objective", opt->objective, &obj) &&
              obj.kind == TT_OBJECTIVE_RRMSE;
  if (rrmse && !opt->reference) {
    tt__say("--objective rrmse needs --reference FILE.exr (an image of the same "
            "scene and resolution, e.g. a high-spp integrator_pt render)\n");
    return -1;
  }
  if (opt->reference && !rrmse) {
    tt__say("--reference %s: only --objective rrmse uses a reference\n", opt->reference);
    return -1;
  }
  return 0;
}

/* Options that exclude each other. */
static int tt__check_exclusions(const tt__host_options *opt) {
  if (opt->db && opt->no_db) {
    tt__say("--db and --no-db exclude each other\n");
    return -1;
  }
  if ((opt->frames || opt->camera_index_set) && opt->sequence) {
    tt__say("--camera-index/--frames and --sequence exclude each other\n");
    return -1;
  }
  return 0;
}

/* --camera-index (A:B), --frames and the states of --hybrid / --predict. */
static int tt__check_path_states(const tt__host_options *opt) {
  if ((opt->hybrid || opt->predict_only) && opt->frames_arg) {
    tt__say("--%s: the states are camera path samples (of %d over the path's "
            "time range): give them with --camera-index A:B (samples A..B, both included); "
            "--frames A:B means frames at --fps\n",
            opt->hybrid ? "hybrid" : "predict", TT_HOST_PATH_SAMPLES);
    return -1;
  }
  if (opt->camera_index_range && !opt->hybrid && !opt->predict_only) {
    tt__say("--camera-index A:B (a range of path samples) applies to --hybrid "
            "and --predict; render one sample with --camera-index I, or frames with "
            "--frames A:B\n");
    return -1;
  }
  if (opt->frames && opt->camera_index_set) {
    tt__say("--camera-index and --frames exclude each other\n");
    return -1;
  }
  return 0;
}

/* --out FILE.json goes with --convert, and --convert needs it. */
static int tt__check_convert(const tt__host_options *opt) {
  const char *odot = opt->out ? strrchr(opt->out, '.') : NULL;
  int out_json = odot && strcmp(odot, ".json") == 0;
  if (opt->convert && !out_json) {
    tt__say("--convert: expected --out FILE.json (the scene.json to write)\n");
    return -1;
  }
  if (!opt->convert && out_json) {
    tt__say("--out: expected a file name ending in .exr, got \"%s\" (.json only "
            "with --convert)\n",
            opt->out);
    return -1;
  }
  return 0;
}

/* The checks that involve several options, once all are read. */
static int tt__check_combinations(tt__host_options *opt) {
  if (tt__check_reference(opt) || tt__check_sequence_options(opt) || tt__check_exclusions(opt) ||
      tt__check_path_states(opt) || tt__check_convert(opt))
    return -1;
  return 0;
}

int tt__parse_options(int argc, char **argv, tt__host_options *opt) {
  memset(opt, 0, sizeof *opt);
  tt__set_prog(argc > 0 ? argv[0] : NULL);
  opt->argc = argc;
  opt->argv = argv;
  struct timespec now;
  clock_gettime(CLOCK_REALTIME, &now);
  opt->started_ns = (int64_t)now.tv_sec * 1000000000 + now.tv_nsec;
  /* the options point into argv, which lives as long as the process */
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (a[0] == '-' && a[1] != '\0') {
      if (tt__read_option(argc, argv, &i, opt)) return TT_EXIT_USAGE;
    } else if (opt->scene) {
      tt__say("more than one scene given (\"%s\" and \"%s\")\n", opt->scene, a);
      return TT_EXIT_USAGE;
    } else {
      opt->scene = a;
    }
  }
  return tt__check_combinations(opt) ? TT_EXIT_USAGE : TT_EXIT_OK;
}

int tt__parse_objective(const char *opt, const char *text, tt_objective *out) {
  if (tt_objective_parse(text, out) == TT_OK) return 0;
  tt__say("%s: %s\n", opt, tt_last_error());
  return -1;
}
