/* libFuzzer: tuner_nm's saved search state (tt.tuner/1 load_state, the JSON a tuning run
 * resumes from), on a space with integer, log-float, nominal and boolean parameters; a state
 * that loads must then propose, take feedback and save again. The plugin's sources are
 * compiled in; it is initialised through its own entry table. */
#include <tunetrace/plugin.h>
#include <tunetrace/tuner.h>

#include "fuzz_util.h"

extern const tt_plugin tt_plugin_entry;

static const tt_tuner_iface *g_ti;
static tt_space *g_space;

static void setup(void) {
  if (g_ti) return;
  if (tt_plugin_entry.init(tt_default_host()) != TT_OK) abort();
  g_ti = tt_plugin_entry.get_interface(TT_TUNER_INTERFACE_ID);
  if (!g_ti) abort();
  g_space = tt_space_create("target", "1");
  static const int64_t bf[] = {2, 4, 8};
  tt_space_add_int(g_space, "quality", 0, 3, 1, "");
  tt_space_add_nom_int(g_space, "branchingFactor", bf, 3, 2, "");
  tt_space_add_float(g_space, "travcost", 0.1, 10, 1, 1, "");
  tt_space_add_float(g_space, "x", -1, 1, 0, 0, "");
  tt_space_add_nom_bool(g_space, "compact", 0, "");
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  setup();
  char *text = fuzz_text(data, size);
  tt_tuner *t = NULL;
  if (g_ti->create(g_space, NULL, 7, &t) != TT_OK) abort();
  if (g_ti->load_state(t, text) == TT_OK) {
    tt_config *c = tt_config_create(g_space);
    for (int i = 0; i < 4; i++) {
      tt_status st = g_ti->next(t, c);
      if (st == TT_DONE) break;
      if (st != TT_OK) break;
      if (g_ti->feedback(t, 1.0 + i) != TT_OK) break;
    }
    double cost;
    g_ti->best(t, c, &cost);
    char *saved = NULL;
    if (g_ti->save_state(t, &saved) == TT_OK) {
      tt_tuner *t2 = NULL;
      if (g_ti->create(g_space, NULL, 7, &t2) != TT_OK) abort();
      if (g_ti->load_state(t2, saved) != TT_OK) abort(); /* its own state must load */
      g_ti->destroy(t2);
      tt_free(saved);
    }
    tt_config_destroy(c);
  }
  g_ti->destroy(t);
  free(text);
  return 0;
}
