/* host: --help, made from the option table (option_table.c). */
#include "host.h"
#include "option_table.h"

#include <stdio.h>
#include <string.h>

#define TT__HELP_COLUMN 25  /* where the description of an option starts */

static const char tt__help_head[] =
    "usage: host [options] [--plugin NAME]... scene.json\n"
    "\n"
    "Renders a scene with swappable plugins (defaults: accel_embree, integrator_pt).\n";

static const char tt__help_foot[] =
    "An option's value may also be attached with '=': --spp=64, --out=box.exr.\n"
    "\n"
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

/* One option: its synopsis, then its help lines from TT__HELP_COLUMN. */
static void tt__print_option(FILE *out, const tt__option *o) {
  char syn[128];
  tt__option_synopsis(o, syn, sizeof syn);
  int pad = TT__HELP_COLUMN - 2 - (int)strlen(syn);
  if (pad < 1) fprintf(out, "  %s\n%*s", syn, TT__HELP_COLUMN, "");
  else fprintf(out, "  %s%*s", syn, pad, "");
  for (const char *p = o->help; *p;) {
    size_t len = strcspn(p, "\n");
    fprintf(out, "%.*s\n", (int)len, p);
    p += len;
    if (*p == '\n' && *++p) fprintf(out, "%*s", TT__HELP_COLUMN, "");
  }
}

/* A section: its title, its introduction, its options in table order. */
static void tt__print_topic(FILE *out, tt__topic topic) {
  size_t n;
  const tt__option *rows = tt__options(&n);
  fprintf(out, "%s:\n%s", tt__topic_title(topic), tt__topic_intro(topic));
  for (size_t k = 0; k < n; k++)
    if (rows[k].topic == topic) tt__print_option(out, &rows[k]);
  fputc('\n', out);
}

void tt__print_usage(FILE *out) {
  fprintf(out, "%s\n", tt__help_head);
  for (int t = 0; t < TT__TOPIC_COUNT; t++) tt__print_topic(out, (tt__topic)t);
  fputs(tt__help_foot, out);
}
