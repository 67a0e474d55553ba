/* host: no output replaces an input. Before any job starts, main.c hands the parsed options
 * to tt__check_outputs, which collects every file the job reads (the scene, --reference,
 * --warm-start, --states, --measure, --model and --resume when they exist, plugins given by
 * path) and every file it writes (--out or the default <scene>.exr and the PNG beside it,
 * --stats, --db, --model, --resume, the converted scene, the frames of --frames, --sequence
 * and --hybrid --out-dir, --tune-pass-images, a sequence's manifest.json), and refuses any
 * output that resolves to an input (tt_file_same: the same device and inode, or the same
 * real path), or to another output, naming both. `host --stats scene.json scene.json` is
 * refused before the scene is even loaded, so nothing is ever lost to a slip of the hand.
 *
 * Files an option both reads and writes are not a conflict: --model (loaded, then saved)
 * and --resume (the state read back, then saved per sample), and --db read by --warm-start
 * while measurements are recorded into it (the database only grows). */
#include "host.h"

#include <libgen.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#define TT__IO_MAX (2 * TT_HOST_MAX_LIST + 16)
#define TT__IO_MAX_FORMATS 20
#define TT__IO_PATH 4400 /* a path, a folder or a file-name format */

/* One file read or written, with the option that names it. */
typedef struct tt__io_file {
  const char *option; /* "--stats", "the scene file", ... (messages, exemptions) */
  char path[TT__IO_PATH];
} tt__io_file;

/* Numbered files a job writes into one folder: file names printf(format, (int)n) for n in
 * first..last (frames of a sequence, pass images, hybrid states). */
typedef struct tt__io_frames {
  const char *option;
  char dir[TT__IO_PATH];
  char formats[TT__IO_MAX_FORMATS][TT__IO_PATH];
  int count;
  uint32_t first, last;
} tt__io_frames;

typedef struct tt__io {
  tt__io_file in[TT__IO_MAX], out[TT__IO_MAX];
  int nin, nout;
  tt__io_frames frames[4];
  int nframes;
} tt__io;

static void tt__io_add(tt__io_file *list, int *n, const char *option, const char *path) {
  size_t len = path ? strlen(path) : 0;
  if (!len || len >= sizeof list[0].path || *n >= TT__IO_MAX) return; /* longer than PATH_MAX */
  list[*n].option = option;
  memcpy(list[*n].path, path, len + 1);
  (*n)++;
}

/* `text` with every '%' doubled, so it can be part of a printf format. */
static void tt__io_escape(const char *text, char *out, size_t n) {
  size_t k = 0;
  for (; *text && k + 2 < n; text++) {
    if (*text == '%') out[k++] = '%';
    out[k++] = *text;
  }
  out[k] = '\0';
}

/* A numbered set of files: `dir` + names from `formats` (NULL-terminated). */
static tt__io_frames *tt__io_frames_add(tt__io *io, const char *option, const char *dir,
                                        uint32_t first, uint32_t last) {
  if (io->nframes >= (int)(sizeof io->frames / sizeof io->frames[0])) return NULL;
  tt__io_frames *f = &io->frames[io->nframes++];
  memset(f, 0, sizeof *f);
  f->option = option;
  snprintf(f->dir, sizeof f->dir, "%s", dir && *dir ? dir : ".");
  f->first = first;
  f->last = last;
  return f;
}

/* Adds the name format a + b (b may be ""); one too long for a path is no name we write. */
static void tt__io_format2(tt__io_frames *f, const char *a, const char *b) {
  if (!f || f->count >= TT__IO_MAX_FORMATS || strlen(a) + strlen(b) >= TT__IO_PATH) return;
  strcpy(f->formats[f->count], a);
  strcat(f->formats[f->count++], b);
}

static void tt__io_format(tt__io_frames *f, const char *format) { tt__io_format2(f, format, ""); }

/* Splits `path` into its folder ("." for a bare name) and its name. */
static void tt__io_split(const char *path, char *dir, size_t nd, char *name, size_t nn) {
  const char *slash = strrchr(path, '/');
  if (!slash) {
    snprintf(dir, nd, ".");
    snprintf(name, nn, "%s", path);
  } else {
    snprintf(dir, nd, "%.*s", slash == path ? 1 : (int)(slash - path), path);
    snprintf(name, nn, "%s", slash + 1);
  }
}

/* The frames of a sequence with the frame pattern `pattern` (DIR/NAME_%04d.exr): the frame,
 * and beside it the other files of a frame (NAME_0007.depth.exr, ...) and its PNG. */
static void tt__io_sequence_pattern(tt__io *io, const tt__host_options *opt) {
  char dir[TT__IO_PATH], name[TT__IO_PATH];
  tt__io_split(opt->seq_pattern, dir, sizeof dir, name, sizeof name);
  tt__io_frames *f = tt__io_frames_add(io, "--out", dir, opt->seq_first, opt->seq_last);
  if (!f) return;
  tt__io_format(f, name);
  static const char *const suffix[] = {".raw.exr",       ".depth.exr",     ".motion.exr",
                                       ".reference.exr", ".post.exr",      ".normal.exr",
                                       ".albedo.exr",    ".prevdepth.exr", ".png"};
  size_t len = strlen(name);
  if (len > 4) name[len - 4] = '\0'; /* the pattern ends in .exr */
  for (size_t i = 0; i < sizeof suffix / sizeof suffix[0]; i++) tt__io_format2(f, name, suffix[i]);
}

/* The frames of an --out-dir sequence (color_0007.exr, depth_0007.exr, ..., and PNGs). */
static void tt__io_sequence_dir(tt__io *io, const tt__host_options *opt) {
  tt__io_frames *f =
      tt__io_frames_add(io, "--out-dir", opt->out_dir, opt->seq_first, opt->seq_last);
  static const char *const names[] = {"color", "depth",  "motion", "reference",
                                      "post",  "normal", "albedo", "prevdepth"};
  for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
    tt__io_format2(f, names[i], "_%04d.exr");
    tt__io_format2(f, names[i], "_%04d.png");
  }
}

/* --frames A:B without a pattern: STEM_NNNN.exr and .png, and STATS_NNNN.json. */
static void tt__io_still_frames(tt__io *io, const tt__host_options *opt, const char *exr) {
  char dir[TT__IO_PATH], name[TT__IO_PATH], esc[TT__IO_PATH];
  tt__io_split(exr, dir, sizeof dir, name, sizeof name);
  size_t len = strlen(name);
  if (len > 4) name[len - 4] = '\0'; /* the .exr */
  tt__io_escape(name, esc, sizeof esc);
  tt__io_frames *f = tt__io_frames_add(io, opt->out ? "--out" : "the default output", dir,
                                       opt->frames_first, opt->frames_last);
  tt__io_format2(f, esc, "_%04d.exr");
  tt__io_format2(f, esc, "_%04d.png");
  if (!opt->stats) return;
  tt__io_split(opt->stats, dir, sizeof dir, name, sizeof name);
  const char *dot = strrchr(name, '.');
  if (dot && !strcmp(dot, ".json")) name[dot - name] = '\0';
  tt__io_escape(name, esc, sizeof esc);
  f = tt__io_frames_add(io, "--stats", dir, opt->frames_first, opt->frames_last);
  tt__io_format2(f, esc, "_%04d.json");
}

/* Everything the job of `opt` reads and writes. */
static void tt__io_collect(tt__io *io, const tt__host_options *opt) {
  struct stat st;
  tt__io_add(io->in, &io->nin, "the scene file", opt->scene);
  tt__io_add(io->in, &io->nin, "--reference", opt->reference);
  for (int i = 0; i < opt->warm_start_count; i++)
    tt__io_add(io->in, &io->nin, "--warm-start", opt->warm_start[i]);
  tt__io_add(io->in, &io->nin, "--states", opt->states);
  tt__io_add(io->in, &io->nin, "--measure", opt->measure);
  if (opt->model && stat(opt->model, &st) == 0) tt__io_add(io->in, &io->nin, "--model", opt->model);
  if (opt->resume && stat(opt->resume, &st) == 0)
    tt__io_add(io->in, &io->nin, "--resume", opt->resume);
  for (int i = 0; i < opt->plugin_count; i++)
    if (strchr(opt->plugins[i], '/')) tt__io_add(io->in, &io->nin, "--plugin", opt->plugins[i]);

  if (!opt->frames) tt__io_add(io->out, &io->nout, "--stats", opt->stats);
  if (!opt->no_db) tt__io_add(io->out, &io->nout, "--db", opt->db);
  tt__io_add(io->out, &io->nout, "--model", opt->model);
  tt__io_add(io->out, &io->nout, "--resume", opt->resume);
  if (opt->tune_pass_images) {
    tt__io_add(io->out, &io->nout, "--tune-pass-images", opt->tune_pass_images);
    tt__io_frames *f =
        tt__io_frames_add(io, "--tune-pass-images", opt->tune_pass_images, 0, INT32_MAX);
    tt__io_format(f, "pass_%04d.exr");
    tt__io_format(f, "pass_default.exr");
  }
  if (opt->convert) {
    tt__io_add(io->out, &io->nout, "--out", opt->out);
    return;
  }
  if (opt->indicators || opt->measure) return;
  if (opt->hybrid || opt->predict_only) {
    if (opt->out_dir) {
      tt__io_add(io->out, &io->nout, "--out-dir", opt->out_dir);
      tt__io_frames *f =
          tt__io_frames_add(io, "--out-dir", opt->out_dir, 0, TT_HOST_PATH_SAMPLES - 1);
      tt__io_format(f, "state_%04d.exr");
    }
    return;
  }
  if (opt->sequence) {
    char manifest[TT__IO_PATH + 16];
    if (opt->seq_pattern) {
      char dir[TT__IO_PATH], name[TT__IO_PATH];
      tt__io_split(opt->seq_pattern, dir, sizeof dir, name, sizeof name);
      snprintf(manifest, sizeof manifest, "%s/manifest.json", dir);
      tt__io_sequence_pattern(io, opt);
    } else if (opt->out_dir) {
      tt__io_add(io->out, &io->nout, "--out-dir", opt->out_dir);
      snprintf(manifest, sizeof manifest, "%s/manifest.json", opt->out_dir);
      tt__io_sequence_dir(io, opt);
    } else {
      return;
    }
    tt__io_add(io->out, &io->nout, "the sequence's manifest", manifest);
    return;
  }
  /* a still (or --frames A:B of stills) */
  char exr[TT__IO_PATH], png[TT__IO_PATH];
  if (opt->out) snprintf(exr, sizeof exr, "%s", opt->out);
  else tt__default_out(opt->scene, exr, sizeof exr);
  if (opt->frames) {
    tt__io_still_frames(io, opt, exr);
    return;
  }
  size_t len = strlen(exr);
  snprintf(png, sizeof png, "%.*s.png", (int)(len > 4 ? len - 4 : len), exr);
  tt__io_add(io->out, &io->nout, opt->out ? "--out" : "the default output", exr);
  tt__io_add(io->out, &io->nout, opt->out ? "the PNG beside --out" : "the default PNG", png);
}

/* Files one option reads and writes by design (see the top of the file). */
static int tt__io_exempt(const tt__io_file *out, const tt__io_file *in) {
  if (!strcmp(out->option, in->option) &&
      (!strcmp(out->option, "--model") || !strcmp(out->option, "--resume")))
    return 1;
  return !strcmp(out->option, "--db") && !strcmp(in->option, "--warm-start");
}

/* 1 if the file `name` in a folder of `f` is one of its numbered files. Each run of digits
 * in the name is tried as the number n; the name must then be exactly printf(format, n). */
static int tt__io_frames_match(const tt__io_frames *f, const char *name) {
  for (const char *p = name; *p; p++) {
    if (*p < '0' || *p > '9' || (p > name && p[-1] >= '0' && p[-1] <= '9')) continue;
    uint64_t n = 0;
    for (const char *q = p; *q >= '0' && *q <= '9' && n <= UINT32_MAX; q++)
      n = n * 10 + (uint64_t)(*q - '0');
    if (n < f->first || n > f->last) continue;
    char buf[TT__IO_PATH];
    for (int i = 0; i < f->count; i++) {
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
      snprintf(buf, sizeof buf, f->formats[i], (int)n); /* one integer conversion each */
#pragma GCC diagnostic pop
      if (!strcmp(buf, name)) return 1;
    }
  }
  for (int i = 0; i < f->count; i++) /* a name without a number (pass_default.exr) */
    if (!strchr(f->formats[i], '%') && !strcmp(f->formats[i], name)) return 1;
  return 0;
}

/* 0 for an output written straight into a device or a FIFO (/dev/null, /dev/stdout): two
 * outputs may share one; 1 for a file (or a path not there yet), which one would replace. */
static int tt__io_replaceable(const char *path) {
  struct stat st;
  return stat(path, &st) != 0 || S_ISREG(st.st_mode) || S_ISDIR(st.st_mode);
}

/* The option a user changes to move an output (the PNG goes where --out goes). */
static const char *tt__io_option(const char *output) {
  if (!strncmp(output, "the default", 11) || !strcmp(output, "the PNG beside --out"))
    return "--out";
  if (!strcmp(output, "the sequence's manifest")) return "--out-dir (or the --out pattern)";
  return output;
}

/* One message naming both files; TT_EXIT_USAGE. */
static int tt__io_refuse(const char *out_option, const char *out_path, const char *in_option,
                         const char *in_path, int input) {
  tt__say("%s %s would replace %s%s %s (%s): refused before any work; give %s another "
          "path\n",
          out_option, out_path, input ? "" : "the output ", in_option, in_path,
          strcmp(out_path, in_path) ? "the same file" : "the same path", tt__io_option(out_option));
  return TT_EXIT_USAGE;
}

int tt__check_outputs(const tt__host_options *opt) {
  static tt__io io; /* large; the check runs once per process */
  memset(&io, 0, sizeof io);
  tt__io_collect(&io, opt);
  for (int o = 0; o < io.nout; o++) {
    for (int i = 0; i < io.nin; i++)
      if (!tt__io_exempt(&io.out[o], &io.in[i]) && tt_file_same(io.out[o].path, io.in[i].path))
        return tt__io_refuse(io.out[o].option, io.out[o].path, io.in[i].option, io.in[i].path, 1);
    for (int k = 0; k < o; k++)
      if (tt__io_replaceable(io.out[o].path) && tt_file_same(io.out[o].path, io.out[k].path))
        return tt__io_refuse(io.out[o].option, io.out[o].path, io.out[k].option, io.out[k].path, 0);
  }
  /* numbered outputs: an input in their folder with one of their names */
  for (int i = 0; i < io.nin; i++) {
    char dir[TT__IO_PATH], name[TT__IO_PATH];
    tt__io_split(io.in[i].path, dir, sizeof dir, name, sizeof name);
    for (int k = 0; k < io.nframes; k++) {
      const tt__io_frames *f = &io.frames[k];
      if (tt_file_same(dir, f->dir) && tt__io_frames_match(f, name)) {
        char what[TT__IO_PATH];
        snprintf(what, sizeof what, "%s (files numbered %u..%u in %s)", f->option, f->first,
                 f->last, f->dir);
        tt__say("%s would write %s, which is %s: refused before any work; give %s another "
                "folder or name\n",
                what, io.in[i].path, io.in[i].option, tt__io_option(f->option));
        return TT_EXIT_USAGE;
      }
    }
  }
  return TT_EXIT_OK;
}
