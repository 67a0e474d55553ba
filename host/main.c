/* host: command-line entry point. Parses options and dispatches to the requested job. */
#include "host.h"
#include "sequence.h"

#include <stdio.h>

int main(int argc, char **argv) {
  tt__host_options opt;
  int rc = tt__parse_options(argc, argv, &opt);
  if (rc != TT_EXIT_OK) return rc;
  if (opt.help) {
    tt__print_help(stdout, opt.help_topic);
    return TT_EXIT_OK;
  }
  if (opt.version) {
    printf("tunetrace host %s (plugin ABI %d.%d)\n", tt_version(), TT_ABI_MAJOR, TT_ABI_MINOR);
    return TT_EXIT_OK;
  }
  if (opt.list_plugins) return tt__run_list_plugins(&opt);
  if (opt.describe_count) return tt__run_describe(&opt);
  if (!opt.scene) {
    tt__say("no scene given (try --help)\n");
    return TT_EXIT_USAGE;
  }
  if ((rc = tt__check_outputs(&opt)) != TT_EXIT_OK) return rc; /* no output replaces an input */
  if (opt.convert) return tt__run_convert(&opt);
  if (opt.indicators) return tt__run_indicators(&opt);
  if (opt.hybrid && opt.sequence) return tt__run_sequence(&opt); /* along the sequence */
  if (opt.hybrid || opt.predict_only) return tt__run_hybrid(&opt);
  if (opt.measure) return tt__run_measure(&opt);
  if (opt.sequence) return tt__run_sequence(&opt);
  return tt__run_render(&opt);
}
