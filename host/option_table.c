/* host: the command-line options, one row each (option_table.h). A new option is one row
 * here (and its member in tt__host_options); --help, the parser, "did you mean" and
 * tunetrace-mpi follow. */
#include "option_table.h"

#include "host.h"
#include "option_setters.h"

#include <tunetrace/suggest.h>

#include <stddef.h>
#include <stdio.h>
#include <string.h>

#define TT__AT(member) offsetof(tt__host_options, member)

/* tt__set_list finds a list's count right after its array. */
#define TT__LIST(list, count)                                                                      \
  _Static_assert(offsetof(tt__host_options, count) ==                                              \
                     offsetof(tt__host_options, list) + sizeof((tt__host_options){0}.list),        \
                 #count " must follow " #list)
TT__LIST(plugins, plugin_count);
TT__LIST(plugin_paths, plugin_path_count);
TT__LIST(sets, set_count);
TT__LIST(describe, describe_count);
TT__LIST(warm_start, warm_start_count);

static const tt__option tt__table[] = {
    /* --- plugins --- */
    {"--plugin", NULL, TT__ARG_ONE, "NAME|PATH", tt__set_list, TT__AT(plugins), 0,
     TT__TOPIC_PLUGINS, TT__TASK_RENDER, 0,
     "load a plugin by name (NAME.so on the search path) or by path\n"
     "(a tuner such as tuner_nm turns tuning on: --help tune)"},
    {"--plugin-path", NULL, TT__ARG_ONE, "DIR", tt__set_list, TT__AT(plugin_paths), 0,
     TT__TOPIC_PLUGINS, 0, 0, "add DIR to the plugin search path (before $TT_PLUGIN_PATH)"},
    {"--set", NULL, TT__ARG_ONE, "PLUGIN.PARAM=V", tt__set_plugin_param, TT__AT(sets), 0,
     TT__TOPIC_PLUGINS, TT__TASK_RENDER, 0,
     "set a plugin's parameter: --set integrator_pt.maxDepth=8\n"
     "(--set accel_embree.quality=3), or one of its options, which are\n"
     "never tuned (--set post_taa.weights=FILE.ttw); --describe NAME\n"
     "lists both"},
    {"--list-plugins", NULL, TT__ARG_NONE, NULL, tt__set_flag, TT__AT(list_plugins), 0,
     TT__TOPIC_PLUGINS, 0, 0,
     "list the plugins found on the search path (exit 3 if any\n"
     "file there was rejected)"},
    {"--describe", NULL, TT__ARG_ONE, "NAME", tt__set_list, TT__AT(describe), 0, TT__TOPIC_PLUGINS,
     0, 0,
     "print the plugin's parameter space as JSON on stdout (given\n"
     "several times: a JSON array of the spaces, in order)"},

    /* --- rendering --- */
    {"--spp", NULL, TT__ARG_ONE, "N", tt__set_u32, TT__AT(spp), TT_LIMIT_SPP, TT__TOPIC_RENDER,
     TT__TASK_RENDER, 0, "samples per pixel (default: the scene's render.spp)"},
    {"--time", NULL, TT__ARG_ONE, "SECONDS", tt__set_real, TT__AT(time_budget), TT_LIMIT_TIME,
     TT__TOPIC_RENDER, TT__TASK_RENDER, 0, "time budget: stop after the pass that exceeds it"},
    {"--res", NULL, TT__ARG_ONE, "WxH", tt__set_res, 0, TT_LIMIT_WIDTH, TT__TOPIC_RENDER,
     TT__TASK_RENDER, 0, "override the scene's resolution"},
    {"--seed", NULL, TT__ARG_ONE, "N", tt__set_seed, TT__AT(seed), TT_LIMIT_SEED, TT__TOPIC_RENDER,
     0, TT__MPI_EXPLORE, "random seed (default: the scene's render.seed)"},
    {"--threads", NULL, TT__ARG_ONE, "N", tt__set_u32, TT__AT(threads), TT_LIMIT_THREADS,
     TT__TOPIC_RENDER, 0, 0, "worker threads (default: all CPUs)"},
    {"--strict", NULL, TT__ARG_NONE, NULL, tt__set_flag, TT__AT(strict), 0, TT__TOPIC_RENDER, 0, 0,
     "read pbrt-v4 scenes as strictly as pbrt-v4 does: an unknown\n"
     "directive or parameter (\"WorldBgin\", \"rgb reflectanse\") is\n"
     "an error naming file:line, not a warning (exit 4)"},

    /* --- tuning --- */
    {"--tune", NULL, TT__ARG_ONE, "PLUGIN", tt__set_text, TT__AT(tune), 0, TT__TOPIC_TUNE,
     TT__TASK_TUNE, 0,
     "the plugin whose parameters are tuned (accel, integrator, post)\n"
     "(default: the integrator if it serves a tuning hint\n"
     "(tt.tuning_hint/1), else the accel)"},
    {"--objective", NULL, TT__ARG_ONE, "SPEC", tt__set_objective, 0, 0, TT__TOPIC_TUNE,
     TT__TASK_TUNE, TT__MPI_TUNE | TT__MPI_EXPLORE,
     "what tuning minimises (default: render), SPEC one of:\n"
     "  render         render ms of the pass\n"
     "  build          accel build ms (accel targets)\n"
     "  build+render   both (accel targets; alias: total)\n"
     "  metric:NAME    an integrator metric of the pass, minimised;\n"
     "  metric:NAME:max            ... maximised\n"
     "  metric:NAME:target=X       ... |value - X| minimised, e.g.\n"
     "                 metric:small_step_acceptance:target=0.234\n"
     "  rrmse          rRMSE of the pass's own image (luminance)\n"
     "                 against --reference; any integrator"},
    {"--iterations", NULL, TT__ARG_ONE, "N", tt__set_u32, TT__AT(iterations), TT_LIMIT_ITERATIONS,
     TT__TOPIC_TUNE, TT__TASK_TUNE, TT__MPI_EXPLORE,
     "configurations to ask the tuner for (default 50)\n"
     "(per searched state of --hybrid: default 40)"},
    {"--verify", NULL, TT__ARG_ONE, "N", tt__set_u32, TT__AT(verify), TT_LIMIT_VERIFY,
     TT__TOPIC_TUNE, TT__TASK_TUNE, 0,
     "then measure default and best side by side, N rounds each\n"
     "(alternating, one pass per round); the median ratios go to the\n"
     "log and to --stats (tuning.verify)"},
    {"--db", NULL, TT__ARG_ONE, "PATH", tt__set_text, TT__AT(db), 0, TT__TOPIC_TUNE, TT__TASK_TUNE,
     TT__MPI_ALL,
     "the tuning database, SQLite (default: the user's, below)\n"
     "($XDG_DATA_HOME/tunetrace/tuning.db, else\n"
     "~/.local/share/tunetrace/tuning.db). A configuration already\n"
     "measured in the same state on this machine is not measured\n"
     "again: its stored cost is fed to the tuner"},
    {"--no-db", NULL, TT__ARG_NONE, NULL, tt__set_flag, TT__AT(no_db), 0, TT__TOPIC_TUNE,
     TT__TASK_TUNE, TT__MPI_ALL, "no database: measure everything, record nothing"},
    {"--tune-params", NULL, TT__ARG_ONE, "A,B,...", tt__set_tune_params, 0, 0, TT__TOPIC_TUNE, 0, 0,
     "search only these parameters of the target; the others keep\n"
     "their configured values (default: the tuning hint's list,\n"
     "e.g. PSSMLT's a_i and sigma_i, else all)"},
    {"--tune-spp", NULL, TT__ARG_ONE, "N", tt__set_u32, TT__AT(tune_spp), TT_LIMIT_TUNE_SPP,
     TT__TOPIC_TUNE, 0, 0, "samples per pixel of one measurement pass (default 1)"},
    /* the range of --tune-spp, 1..65536, bounds a window of frames as well */
    {"--tune-window", NULL, TT__ARG_ONE, "N", tt__set_u32, TT__AT(tune_window), TT_LIMIT_TUNE_SPP,
     TT__TOPIC_TUNE, 0, 0,
     "tuning along an animated sequence: frames per measurement\n"
     "(default 8); each configuration runs N consecutive frames and\n"
     "costs their mean accel update + render ms, so a refit\n"
     "schedule is measured with the rebuild it starts from"},
    {"--explore", NULL, TT__ARG_ONE, "N", tt__set_u32, TT__AT(explore), TT_LIMIT_EXPLORE,
     TT__TOPIC_TUNE, 0, TT__MPI_TUNE | TT__MPI_EXPLORE,
     "measure N random configurations of the target's space (no\n"
     "tuner needed), for the analysis tools in tools/tuning/"},
    {"--reference", NULL, TT__ARG_ONE, "FILE.exr", tt__set_text, TT__AT(reference), 0,
     TT__TOPIC_TUNE, 0, 0,
     "the reference image of --objective rrmse (same resolution\n"
     "as the render)"},
    {"--tune-pass-images", NULL, TT__ARG_ONE, "DIR", tt__set_text, TT__AT(tune_pass_images), 0,
     TT__TOPIC_TUNE, 0, 0,
     "write each measured tuning pass's own image (not the\n"
     "accumulated film) to DIR/pass_default.exr, pass_NNNN.exr"},
    {"--resume", NULL, TT__ARG_ONE, "FILE", tt__set_text, TT__AT(resume), 0, TT__TOPIC_TUNE, 0,
     TT__MPI_ALL,
     "save the tuning session (its samples and the tuner's state) to\n"
     "FILE after every sample; when FILE exists, continue from it\n"
     "(kill a long tuning run, run the same command again)"},
    {"--clock", NULL, TT__ARG_ONE, "wall|cpu", tt__set_clock, 0, 0, TT__TOPIC_TUNE, 0, 0,
     "what build and render times measure: wall time (default) or\n"
     "the process's CPU time, which other processes running on the\n"
     "same cores do not inflate (use it with --threads 1 on a\n"
     "shared machine); tuning rows record the clock in `context`"},

    /* --- hybrid tuning --- */
    {"--hybrid", NULL, TT__ARG_NONE, NULL, tt__set_flag, TT__AT(hybrid), 0, TT__TOPIC_HYBRID,
     TT__TASK_HYBRID, TT__MPI_ALL,
     "tune along the camera path: search or predict per state\n"
     "(the tuner or the predictor plugin). States: the path samples of\n"
     "--camera-index A:B (both included; default all 100). A state is\n"
     "searched with probability --epsilon (--iterations K, default\n"
     "40), else its configuration is predicted and built once; every\n"
     "cost goes to the database and the model. With --sequence A:B\n"
     "over an animated scene: along the sequence, each window of\n"
     "--tune-window frames a state. --plugin predictor_nn\n"
     "(default) | predictor_rbf | predictor_static, --plugin tuner_nm\n"
     "(default)"},
    {"--epsilon", NULL, TT__ARG_ONE, "E", tt__set_epsilon, TT__AT(epsilon), TT_LIMIT_EPSILON,
     TT__TOPIC_HYBRID, TT__TASK_HYBRID, 0,
     "probability of searching a state, in [0, 1] (default 0.1)"},
    {"--model", NULL, TT__ARG_ONE, "FILE", tt__set_text, TT__AT(model), 0, TT__TOPIC_HYBRID,
     TT__TASK_HYBRID, 0, "the model: loaded when FILE exists, saved there at the end"},
    {"--warm-start", NULL, TT__ARG_ONE, "DB", tt__set_list, TT__AT(warm_start), 0, TT__TOPIC_HYBRID,
     TT__TASK_HYBRID, 0,
     "first teach the model the rows of a tuning database\n"
     "(other scenes, earlier runs: every row measured with the same\n"
     "objective, clock, spp and threads)"},
    {"--predict", NULL, TT__ARG_NONE, NULL, tt__set_flag, TT__AT(predict_only), 0, TT__TOPIC_HYBRID,
     TT__TASK_HYBRID, 0, "print the model's prediction per state as JSON; render nothing"},
    {"--states", NULL, TT__ARG_ONE, "FILE.json", tt__set_text, TT__AT(states), 0, TT__TOPIC_HYBRID,
     0, 0,
     "--predict for these states ([{\"id\": ..., \"indicators\":\n"
     "{name: raw value, ...}}, ...]) instead of the path samples"},

    /* --- sequences --- */
    {"--sequence", NULL, TT__ARG_ONE, "N|A:B", tt__set_sequence, 0, TT_LIMIT_FRAME,
     TT__TOPIC_SEQUENCE, TT__TASK_SEQUENCE, TT__MPI_ALL,
     "render frames 0..N-1 (or A..B) of the camera path into --out-dir\n"
     "at --fps (default 24), each with one Halton(2,3) sub-pixel\n"
     "jitter of a cycle of 8 for all its samples; writes\n"
     "color/depth/motion/prevdepth_NNNN.exr and manifest.json"},
    {"--out-dir", NULL, TT__ARG_ONE, "DIR", tt__set_text, TT__AT(out_dir), 0, TT__TOPIC_SEQUENCE,
     TT__TASK_SEQUENCE, TT__MPI_ALL,
     "folder of the sequence (created if missing; also --hybrid's)"},
    {"--post", NULL, TT__ARG_ONE, "NAME", tt__set_text, TT__AT(post), 0, TT__TOPIC_SEQUENCE,
     TT__TASK_SEQUENCE, TT__MPI_FRAMES,
     "run the post-filter NAME (e.g. post_taa) over the frames in\n"
     "order and write post_NNNN.exr; --set NAME.mode=network ..."},
    {"--fps", NULL, TT__ARG_ONE, "F", tt__set_real, TT__AT(fps), TT_LIMIT_FPS, TT__TOPIC_SEQUENCE,
     0, 0, "frames per second along the camera path (default 24)"},
    {"--reference-scale", NULL, TT__ARG_ONE, "K", tt__set_u32, TT__AT(reference_scale),
     TT_LIMIT_REFERENCE_SCALE, TT__TOPIC_SEQUENCE, 0, 0,
     "also render each frame at K x K the resolution and write the\n"
     "Blackman-Harris-downsampled reference_NNNN.exr"},
    {"--supersample", NULL, TT__ARG_ONE, "K", tt__set_supersample, TT__AT(reference_scale),
     TT_LIMIT_REFERENCE_SCALE, TT__TOPIC_SEQUENCE, 0, 0,
     "write only the reference (K x K the resolution, Blackman-Harris)\n"
     "as the frames of --frames A:B --out DIR/frame_%04d.exr"},
    {"--png", NULL, TT__ARG_NONE, NULL, tt__set_flag, TT__AT(png), 0, TT__TOPIC_SEQUENCE, 0, 0,
     "also write a PNG preview of every frame beside its EXR (of\n"
     "the frame the pattern names: filtered, or the reference with\n"
     "--supersample), listed in the manifest as \"png\" (a still\n"
     "always gets its PNG)"},

    /* --- camera path samples and frames --- */
    {"--frames", NULL, TT__ARG_ONE, "A:B", tt__set_text, TT__AT(frames_arg), 0, TT__TOPIC_CAMERA,
     TT__TASK_SEQUENCE, TT__MPI_ALL,
     "frames A..B (both included) of the camera path at --fps\n"
     "(frame f is the pose at t = f / fps, as in sequences). Each is a\n"
     "full render to <out stem>_NNNN.exr/.png (default stem: <scene\n"
     "folder>); with --out DIR/frame_%04d.exr they are the jittered\n"
     "frames of a sequence, written to the pattern (manifest.json in\n"
     "DIR): --supersample K writes the K x K-supersampled reference\n"
     "as the frame instead; a post-filter (--plugin post_taa --set\n"
     "post_taa.mode=network) writes the filtered frame, the rendered\n"
     "one as frame_NNNN.raw.exr"},
    {"--camera-index", NULL, TT__ARG_ONE, "I", tt__set_camera_index, 0, TT_LIMIT_CAMERA_INDEX,
     TT__TOPIC_CAMERA, 0, TT__MPI_ALL,
     "render sample I (0..99) of the scene's camera path: the pose\n"
     "at t = I/99 of the path's time range (no path: still camera);\n"
     "A:B with --hybrid and --predict: samples A..B, both included"},

    /* --- output --- */
    {"--out", "-o", TT__ARG_ONE, "FILE.exr", tt__set_out, 0, 0, TT__TOPIC_OUTPUT, TT__TASK_RENDER,
     TT__MPI_ALL,
     "the image: linear EXR, with a display-referred PNG beside it\n"
     "(default: <scene folder>.exr in the current directory)"},
    {"--aov", NULL, TT__ARG_ONE, "LIST", tt__set_aov, 0, 0, TT__TOPIC_OUTPUT, TT__TASK_SEQUENCE, 0,
     "the AOVs to write: depth, normal, albedo, motion, prevdepth, none\n"
     "A still writes them as layers of its EXR: depth (depth.Z),\n"
     "normal (normal.X/Y/Z), albedo (albedo.R/G/B), motion\n"
     "(motion.X/Y); a sequence one file per frame and AOV\n"
     "(depth_NNNN.exr in --out-dir, frame_NNNN.depth.exr beside an\n"
     "--out pattern). prevdepth (sequences only): the depth of each\n"
     "pixel's surface point in the previous frame's camera, for\n"
     "disocclusion tests. Default: depth, motion and prevdepth with\n"
     "--out-dir, else none"},
    {"--stats", NULL, TT__ARG_ONE, "FILE.json", tt__set_stats, 0, 0, TT__TOPIC_OUTPUT, 0,
     TT__MPI_ALL, "machine-readable record of the run"},
    {"--quiet", "-q", TT__ARG_NONE, NULL, tt__set_flag, TT__AT(quiet), 0, TT__TOPIC_OUTPUT,
     TT__TASK_RENDER, 0, "no progress bar or progress messages (warnings, errors stay)"},
    {"--help", "-h", TT__ARG_TOPIC, "[TOPIC]", tt__set_help, 0, 0, TT__TOPIC_OUTPUT, TT__TASK_MORE,
     0, "the options by task; with a TOPIC, all of that topic's options"},
    {"--help-all", NULL, TT__ARG_NONE, NULL, tt__set_help, 0, 0, TT__TOPIC_OUTPUT, TT__TASK_MORE, 0,
     "every option, the environment and the exit codes"},
    {"--version", NULL, TT__ARG_NONE, NULL, tt__set_flag, TT__AT(version), 0, TT__TOPIC_OUTPUT,
     TT__TASK_MORE, 0, "the version and the plugin ABI"},

    /* --- scene tools and measurements --- */
    {"--convert", NULL, TT__ARG_NONE, NULL, tt__set_flag, TT__AT(convert), 0, TT__TOPIC_TOOLS, 0, 0,
     "write the loaded scene (scene.json or .pbrt) as scene.json v1\n"
     "to --out FILE.json, meshes as PLY in meshes/ next to it; no render"},
    {"--indicators", NULL, TT__ARG_NONE, NULL, tt__set_flag, TT__AT(indicators), 0, TT__TOPIC_TOOLS,
     0, 0,
     "print the scene's indicators (thesis Table 3.2) as JSON\n"
     "for its still camera or --camera-index I: raw, normalised to\n"
     "[0,1] (the predictors' state), bounds, what was clamped, ms"},
    {"--indicator-norm", NULL, TT__ARG_ONE, "SPEC", tt__set_indicator_norm, 0, 0, TT__TOPIC_TOOLS,
     0, 0,
     "normalisation of the indicators: camera=extent|table|text,\n"
     "scale=linear|log (default camera=extent,scale=linear)"},
    {"--measure", NULL, TT__ARG_ONE, "FILE.json", tt__set_text, TT__AT(measure), 0, TT__TOPIC_TOOLS,
     0, 0,
     "measure the accel configurations of FILE (a JSON array; the\n"
     "first should be the default) side by side: --rounds R\n"
     "rounds, order alternating, medians and ratios to the first as\n"
     "JSON on stdout (--camera-index I, --objective, --tune-spp)"},
    {"--rounds", NULL, TT__ARG_ONE, "R", tt__set_u32, TT__AT(rounds), TT_LIMIT_ROUNDS,
     TT__TOPIC_TOOLS, 0, 0, "rounds of --measure (default 3)"},
};

#define TT__ROWS (sizeof tt__table / sizeof tt__table[0])

/* Other renderers' spellings of our options, suggested for "did you mean". */
static const struct {
  const char *theirs, *ours;
} tt__foreign[] = {
    {"--outfile", "--out"},      /* pbrt-v4 */
    {"--nthreads", "--threads"}, /* pbrt-v4 */
};

const tt__option *tt__options(size_t *count) {
  *count = TT__ROWS;
  return tt__table;
}

const tt__option *tt__option_find(const char *name) {
  for (size_t k = 0; k < TT__ROWS; k++) {
    const tt__option *o = &tt__table[k];
    if (!strcmp(name, o->name) || (o->alias && !strcmp(name, o->alias))) return o;
  }
  return NULL;
}

const tt__option *tt__option_of_arg(const char *arg, const char **value) {
  const char *eq = arg[0] == '-' && arg[1] == '-' ? strchr(arg, '=') : NULL;
  *value = eq ? eq + 1 : NULL;
  if (!eq) return tt__option_find(arg);
  char name[64];
  if ((size_t)(eq - arg) >= sizeof name) return NULL;
  memcpy(name, arg, (size_t)(eq - arg));
  name[eq - arg] = '\0';
  return tt__option_find(name);
}

const char *tt__option_suggest(const char *name) {
  for (size_t k = 0; k < sizeof tt__foreign / sizeof tt__foreign[0]; k++)
    if (!strcmp(name, tt__foreign[k].theirs)) return tt__foreign[k].ours;
  const char *names[TT__ROWS];
  for (size_t k = 0; k < TT__ROWS; k++) names[k] = tt__table[k].name;
  return tt_suggest(name, names, TT__ROWS);
}

static const struct {
  const char *name, *title, *intro;
} tt__topics[TT__TOPIC_COUNT] = {
    [TT__TOPIC_RENDER] = {"render", "Rendering", ""},
    [TT__TOPIC_PLUGINS] = {"plugins", "Plugins", ""},
    [TT__TOPIC_OUTPUT] = {"output", "Output", ""},
    [TT__TOPIC_TUNE] =
        {"tune", "Tuning; thesis Fig. 3.2, host/README.md",
         "  Loading a tuner (--plugin tuner_nm) turns tuning on: before the final passes the\n"
         "  host measures the target's default configuration, then asks the tuner for\n"
         "  --iterations configurations, measuring each with one pass, and renders the\n"
         "  remaining spp with the best one.\n"},
    [TT__TOPIC_HYBRID] = {"hybrid", "Hybrid tuning; thesis 3.3, host/README.md", ""},
    [TT__TOPIC_SEQUENCE] = {"sequence", "Sequences for temporal filters; tools/taa/README.md", ""},
    [TT__TOPIC_CAMERA] = {"camera", "Camera path samples and frames; scenes/README.md", ""},
    [TT__TOPIC_TOOLS] = {"tools", "Scene tools and measurements", ""},
};

int tt__topic_find(const char *name) {
  for (int t = 0; name && t < TT__TOPIC_COUNT; t++)
    if (!strcmp(name, tt__topics[t].name)) return t;
  return -1;
}

const char *tt__topic_name(tt__topic topic) { return tt__topics[topic].name; }

const char *tt__topic_list(void) {
  static char list[256];
  if (!list[0])
    for (int t = 0; t < TT__TOPIC_COUNT; t++)
      snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", t ? ", " : "",
               tt__topics[t].name);
  return list;
}

const char *tt__topic_suggest(const char *name) {
  const char *names[TT__TOPIC_COUNT];
  for (int t = 0; t < TT__TOPIC_COUNT; t++) names[t] = tt__topics[t].name;
  return tt_suggest(name, names, TT__TOPIC_COUNT);
}

const char *tt__topic_title(tt__topic topic) { return tt__topics[topic].title; }

const char *tt__topic_intro(tt__topic topic) { return tt__topics[topic].intro; }
