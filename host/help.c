/* host: --help, made from the option table (option_table.c): the short help lists the
 * options of each task (render, tune, hybrid, sequences), --help TOPIC one topic in full,
 * --help-all every topic, the environment and the exit codes. */
#include "host.h"
#include "option_table.h"

#include <stdio.h>
#include <string.h>

#define TT__HELP_COLUMN 25 /* where the description of an option starts */

/* The short help's sections: a task, with a command that does it (after the program's name). */
static const struct {
  unsigned task;
  const char *title, *example;
} tt__tasks[] = {
    {TT__TASK_RENDER, "Render", "--spp 64 -o box.exr scenes/cornell-box/scene.json"},
    {TT__TASK_TUNE, "Tune (load a tuner)", "--plugin tuner_nm --iterations 40 scene.json"},
    {TT__TASK_HYBRID, "Hybrid tuning along the camera path", "--hybrid --model m.ttpm scene.json"},
    {TT__TASK_SEQUENCE, "Sequences (frames for temporal filters)",
     "--sequence 0:47 --out-dir seq scene.json"},
};

static const char tt__help_notes[] =
    "An option's value may also be attached with '=': --spp=64, --out=box.exr.\n";

static const char tt__help_foot[] =
    "Environment: TT_PLUGIN_PATH (':'-separated plugin folders), OCIO (OpenColorIO config\n"
    "for the PNG display transform; built-in sRGB when unset).\n"
    "\n"
    "Exit codes: 0 success, 1 runtime failure, 2 usage error, 3 plugin load failure,\n"
    "4 scene error, 5 output not written, 130 interrupted (partial image written).\n"
    "SIGINT/SIGTERM finish the current pass and write what was rendered so far; a second\n"
    "signal exits at once.\n";

/* "--out, -o FILE.exr": the option as --help shows it. */
static void tt__option_synopsis(const tt__option *o, char *buf, size_t n) {
  snprintf(buf, n, "%s%s%s%s%s", o->name, o->alias ? ", " : "", o->alias ? o->alias : "",
           o->value ? " " : "", o->value ? o->value : "");
}

/* One option: its synopsis, then its help from TT__HELP_COLUMN (all lines, or the first). */
static void tt__print_option(FILE *out, const tt__option *o, int full) {
  char syn[128];
  tt__option_synopsis(o, syn, sizeof syn);
  int pad = TT__HELP_COLUMN - 2 - (int)strlen(syn);
  if (pad < 1) fprintf(out, "  %s\n%*s", syn, TT__HELP_COLUMN, "");
  else fprintf(out, "  %s%*s", syn, pad, "");
  for (const char *p = o->help; *p;) {
    size_t len = strcspn(p, "\n");
    fprintf(out, "%.*s\n", (int)len, p);
    p += len;
    if (!full) break;
    if (*p == '\n' && *++p) fprintf(out, "%*s", TT__HELP_COLUMN, "");
  }
}

/* A topic: its title, its introduction, its options in table order. */
static void tt__print_topic(FILE *out, tt__topic topic) {
  size_t n;
  const tt__option *rows = tt__options(&n);
  const char *title = tt__topic_title(topic), *see = strchr(title, ';');
  fprintf(out, "%.*s (--help %s%s):\n%s", see ? (int)(see - title) : (int)strlen(title), title,
          tt__topic_name(topic), see ? see : "", tt__topic_intro(topic));
  for (size_t k = 0; k < n; k++)
    if (rows[k].topic == topic) tt__print_option(out, &rows[k], 1);
}

/* The options of a task (TT__TASK_*), one line each. */
static void tt__print_task(FILE *out, unsigned task) {
  size_t n;
  const tt__option *rows = tt__options(&n);
  for (size_t k = 0; k < n; k++)
    if (rows[k].tasks & task) tt__print_option(out, &rows[k], 0);
}

static void tt__print_head(FILE *out) {
  fprintf(out,
          "usage: %s [options] [--plugin NAME]... scene.json|scene.pbrt|scene.gltf\n\n"
          "Renders a scene with swappable plugins (defaults: accel_embree, integrator_pt).\n\n",
          tt__prog());
}

/* The short help: the options by task, then where the rest is. */
static void tt__print_short(FILE *out) {
  tt__print_head(out);
  for (size_t t = 0; t < sizeof tt__tasks / sizeof tt__tasks[0]; t++) {
    fprintf(out, "%s:  %s %s\n", tt__tasks[t].title, tt__prog(), tt__tasks[t].example);
    tt__print_task(out, tt__tasks[t].task);
    fputc('\n', out);
  }
  tt__print_task(out, TT__TASK_MORE);
  fprintf(out, "\nTopics: %s.\n%s", tt__topic_list(), tt__help_notes);
  fputs("Exit codes: 0 success, 1 failure, 2 usage, 3 plugin, 4 scene, 5 output, 130 "
        "interrupted.\n",
        out);
}

void tt__print_help(FILE *out, const char *topic) {
  int t = topic ? tt__topic_find(topic) : -1;
  if (t >= 0) {
    tt__print_topic(out, (tt__topic)t);
    return;
  }
  if (!topic) {
    tt__print_short(out);
    return;
  }
  tt__print_head(out); /* "all" */
  for (int k = 0; k < TT__TOPIC_COUNT; k++) {
    tt__print_topic(out, (tt__topic)k);
    fputc('\n', out);
  }
  fprintf(out, "%s\n%s", tt__help_notes, tt__help_foot);
}
