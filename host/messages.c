/* host: the program's name in its messages and usage line: the name it was run as
 * ("tunetrace" installed, "host" in the build tree, whatever a link calls it). */
#include "host.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static const char *tt__name = "host";

void tt__set_prog(const char *argv0) {
  const char *slash = argv0 ? strrchr(argv0, '/') : NULL;
  const char *base = slash ? slash + 1 : argv0;
  if (base && *base) tt__name = base;
}

const char *tt__prog(void) { return tt__name; }

void tt__say(const char *fmt, ...) {
  char msg[4096];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  fprintf(stderr, "%s: %s", tt__name, msg);
}
