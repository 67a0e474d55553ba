/* Shared helpers for the tuner_nm tests: load the plugin through the loader and drive a
 * tuner with ask/tell over an analytic cost function. */
#ifndef TUNER_NM_COMMON_H
#define TUNER_NM_COMMON_H

#include "tt_test.h"

#include <tunetrace/loader.h>
#include <tunetrace/tuner.h>

#include <stdarg.h>
#include <stdint.h>

/* Cost function over a configuration; `user` is the test's context. */
typedef double (*tnm_cost_fn)(const tt_config *cfg, void *user);

/* Outcome of one tuning run. */
typedef struct tnm_run {
  int evaluations;  /* measurements fed back */
  int done;         /* next() returned TT_DONE */
  double best_cost; /* from best() */
  int to_target;    /* first evaluation count at which `reached` held (-1: never) */
} tnm_run;

static tt_registry *tnm_reg;

/* Loads tuner_nm and returns its interface (skips the test if the loader cannot find it). */
static const tt_tuner_iface *tnm_load(void) {
  tnm_reg = tt_registry_create(tt_default_host());
  tt_loaded_plugin *p = NULL;
  if (!tnm_reg || tt_registry_load(tnm_reg, "tuner_nm", &p) != TT_OK) {
    fprintf(stderr, "cannot load tuner_nm: %s\n", tt_last_error());
    exit(1);
  }
  return (const tt_tuner_iface *)tt_loaded_plugin_iface(p);
}

/* Settings config of the tuner with `text` pairs applied ("name", "value", ..., NULL). */
static tt_config *tnm_settings(const tt_tuner_iface *nm, ...) {
  tt_config *s = tt_config_create(nm->space());
  va_list ap;
  va_start(ap, nm);
  for (const char *k; (k = va_arg(ap, const char *));) {
    const char *v = va_arg(ap, const char *);
    if (tt_config_set_string(s, k, v) != TT_OK)
      fprintf(stderr, "setting %s: %s\n", k, tt_last_error());
  }
  va_end(ap);
  return s;
}

/* Runs up to `budget` evaluations; `reached(cfg, user)` marks the target, `visit` (may be
 * NULL) sees every proposal; `best_out` (may be NULL) receives best(). */
static tnm_run tnm_drive(const tt_tuner_iface *nm, const tt_space *space, const tt_config *settings,
                         uint64_t seed, tnm_cost_fn cost, int (*reached)(const tt_config *, void *),
                         void (*visit)(const tt_config *, void *), void *user, int budget,
                         tt_config *best_out) {
  tnm_run r = {0, 0, INFINITY, -1};
  tt_tuner *t = NULL;
  if (nm->create(space, settings, seed, &t) != TT_OK) {
    fprintf(stderr, "create: %s\n", tt_last_error());
    return r;
  }
  tt_config *c = tt_config_create(space);
  while (r.evaluations < budget) {
    tt_status st = nm->next(t, c);
    if (st == TT_DONE) {
      r.done = 1;
      break;
    }
    if (st != TT_OK) break;
    if (visit) visit(c, user);
    double f = cost(c, user);
    nm->feedback(t, f);
    r.evaluations++;
    if (r.to_target < 0 && reached && reached(c, user)) r.to_target = r.evaluations;
  }
  nm->best(t, c, &r.best_cost);
  if (best_out) tt_config_copy(best_out, c);
  nm->destroy(t);
  tt_config_destroy(c);
  return r;
}

#endif
