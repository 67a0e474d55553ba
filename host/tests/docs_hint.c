/* host/README.md says which objective PSSMLT's tuning hint serves, and gives it as an example
 * of tuning an integrator towards a metric: both must be the hint the plugin serves, and the
 * metric one the plugin publishes (a user copying the README's command must get the hint's
 * objective, not an error or another metric). */
#include <tunetrace/loader.h>
#include <tunetrace/tuning_hint.h>

#include "tt_test.h"

#include <stdlib.h>

int main(void) {
  tt_registry *reg = tt_registry_create(tt_default_host());
  tt_loaded_plugin *p = NULL;
  if (!reg || tt_registry_load(reg, "integrator_pssmlt", &p) != TT_OK) {
    fprintf(stderr, "cannot load integrator_pssmlt: %s\n", tt_last_error());
    return 1;
  }
  const tt_tuning_hint *hint = tt_loaded_plugin_get(p, TT_TUNING_HINT_ID);
  CHECK(hint && hint->objective);
  char path[4200];
  const char *root = getenv("TT_SOURCE_ROOT");
  snprintf(path, sizeof path, "%s/host/README.md", root ? root : ".");
  FILE *f = fopen(path, "r");
  CHECK_MSG(f != NULL, "cannot read %s", path);
  static char text[1 << 20];
  size_t n = f ? fread(text, 1, sizeof text - 1, f) : 0;
  text[n] = 0;
  if (f) fclose(f);
  if (hint && hint->objective) {
    char claim[256], example[256];
    snprintf(claim, sizeof claim, "PSSMLT serves\n`\"%s\"`", hint->objective);
    snprintf(example, sizeof example, "--tune integrator_pssmlt \\\n     --objective %s ",
             hint->objective);
    CHECK_MSG(strstr(text, claim) || strstr(text, claim + 14),
              "%s does not say PSSMLT "
              "serves \"%s\"",
              path, hint->objective);
    CHECK_MSG(strstr(text, example),
              "%s: the PSSMLT example does not tune towards the hint "
              "%s",
              path, hint->objective);
    /* every metric objective the README gives PSSMLT names one of its hint's kind: the
     * README must not name a metric spelling the plugin does not serve as its hint */
    CHECK_MSG(!strstr(text, "metric:acceptance:target=0.234"),
              "%s still names "
              "metric:acceptance:target=0.234 (the hint is %s)",
              path, hint->objective);
  }
  tt_registry_destroy(reg);
  return tt_test_finish("docs_hint");
}
