/* Plugin kinds: their short names and the interface id each kind must serve. */
#include <tunetrace/plugin.h>

#include <tunetrace/accel.h>
#include <tunetrace/integrator.h>
#include <tunetrace/post.h>
#include <tunetrace/predictor.h>
#include <tunetrace/sampler.h>
#include <tunetrace/tuner.h>

#include <string.h>

/* Indexed by kind value; slot 0 is unused because kinds start at 1 (0 means "unknown"). */
static const struct {
  const char *name;
  const char *iface;
} tt__kinds[TT_KIND_COUNT + 1] = {
    {NULL, NULL},
    {"accel", TT_ACCEL_INTERFACE_ID},
    {"integrator", TT_INTEGRATOR_INTERFACE_ID},
    {"tuner", TT_TUNER_INTERFACE_ID},
    {"predictor", TT_PREDICTOR_INTERFACE_ID},
    {"post", TT_POST_INTERFACE_ID},
    {"sampler", TT_SAMPLER_INTERFACE_ID},
};

/* Interface id of `kind`; NULL for values outside the enum so callers can reject them. */
const char *tt_plugin_kind_interface(uint32_t kind) {
  if (kind < 1 || kind > TT_KIND_COUNT) return NULL;
  return tt__kinds[kind].iface;
}

/* Short kind name; "unknown" keeps messages printable for bad values. */
const char *tt_plugin_kind_name(uint32_t kind) {
  if (kind < 1 || kind > TT_KIND_COUNT) return "unknown";
  return tt__kinds[kind].name;
}

/* Reverse of tt_plugin_kind_name, for command-line options such as --plugin-kind. */
uint32_t tt_plugin_kind_from_name(const char *name) {
  if (!name) return 0;
  for (uint32_t k = 1; k <= TT_KIND_COUNT; k++)
    if (strcmp(tt__kinds[k].name, name) == 0) return k;
  return 0;
}
