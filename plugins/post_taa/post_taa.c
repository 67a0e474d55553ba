/* post_taa: temporal anti-aliasing post-filter (kind TT_KIND_POST, "tt.post/1").
 *
 * Modes: "vctaa" (variance-clipping TAA, taa_vctaa.c), "network" (the thesis' kernel-
 * prediction network, taa_net.c) and "none" (passthrough, to render the raw input through
 * the same pipeline). See README.md for parameters and the weights file format. */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <tunetrace/options.h>
#include <tunetrace/plugin.h>
#include <tunetrace/post.h>

#include "taa_internal.h"

#ifndef TT__TAA_SOURCE_DIR
#  define TT__TAA_SOURCE_DIR "."
#endif

enum { TT__TAA_MODE_VCTAA = 0, TT__TAA_MODE_NETWORK = 1, TT__TAA_MODE_NONE = 2 };

static const tt_host *g_host;
static tt_space *g_space;
static char g_weights_option[4096]; /* option "weights" ("" = not set) */

struct tt_post {
  uint32_t width, height;
  int mode;
  tt__vctaa_params vc_params;
  uint32_t channels;       /* shipped network variant (6, the default, or 12) */
  char weights_path[4096]; /* file the loaded model came from ("" = none) */
  tt__vctaa_filter vc;
  tt__net_model net;
  tt__net_state net_state;
  int net_loaded;
};

/* The host, or libtunetrace's default services when used without init(). */
static const tt_host *tt__taa_host(void) { return g_host ? g_host : tt_default_host(); }

/* Builds the parameter space once (init). */
static tt_status tt__taa_build_space(void) {
  static const char *const modes[] = {"vctaa", "network", "none"};
  static const int64_t channels[] = {12, 6};
  static const char *const resolves[] = {"tonemapped", "linear"};
  tt_space *s = tt_space_create(TT__TAA_NAME, TT__TAA_VERSION);
  if (!s) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__TAA_NAME ": cannot create the space");
  int ok = 1;
  ok &= tt_space_add_nom_string(s, "mode", modes, 3, 0,
                                "vctaa: variance-clipping TAA; network: kernel-prediction "
                                "network (thesis 5.4); none: passthrough") >= 0;
  ok &= tt_space_add_float(s, "blend", 0.01, 1.0, 0.1, 0,
                           "vctaa: weight of the current frame in the running average") >= 0;
  ok &= tt_space_add_float(s, "gamma", 0.25, 4.0, 1.0, 0,
                           "vctaa: variance box half-size in standard deviations") >= 0;
  ok &= tt_space_add_nom_bool(s, "catmullRom", 1,
                              "vctaa: Catmull-Rom history fetch (false: bilinear)") >= 0;
  /* default index 1 (6 channels): the validation rule (tools/taa/select_val.py) chose it; the
   * order of the values stays, so configurations written before keep their meaning */
  ok &= tt_space_add_nom_int(s, "channels", channels, 2, 1,
                             "network: shipped model variant (body channels; 6 is the "
                             "default, chosen on validation sequences); the option "
                             "weights (--set post_taa.weights=FILE) or the "
                             "TT_POST_TAA_WEIGHTS environment variable names another file") >= 0;
  /* appended in 0.2.0 */
  ok &= tt_space_add_nom_string(s, "resolve", resolves, 2, 0,
                                "vctaa: tonemapped (the thesis' baseline; darkens noisy "
                                "input) or linear (energy-preserving)") >= 0;
  if (!ok) {
    tt_space_destroy(s);
    return tt_set_error(TT_ERR_INTERNAL, TT__TAA_NAME ": building the parameter space failed");
  }
  g_space = s;
  return TT_OK;
}

/* Space accessor for the interface. */
static const tt_space *tt__taa_space(void) { return g_space; }

/* Finds the weights file: option "weights", else $TT_POST_TAA_WEIGHTS, else the shipped file
 * next to the plugin, else in the source tree (uninstalled builds). */
static void tt__taa_weights_path(uint32_t channels, char *out, size_t size) {
  if (g_weights_option[0]) {
    snprintf(out, size, "%s", g_weights_option);
    return;
  }
  const char *env = getenv("TT_POST_TAA_WEIGHTS");
  if (env && *env) {
    snprintf(out, size, "%s", env);
    return;
  }
  char name[64];
  snprintf(name, sizeof name, "post_taa_c%u.ttw", channels);
  Dl_info info;
  if (dladdr((const void *)&g_host, &info) && info.dli_fname) {
    const char *slash = strrchr(info.dli_fname, '/');
    if (slash) {
      snprintf(out, size, "%.*s/%s", (int)(slash - info.dli_fname), info.dli_fname, name);
      if (access(out, F_OK) == 0) return; /* read (and checked) by tt_file_read */
    }
  }
  snprintf(out, size, "%s/%s", TT__TAA_SOURCE_DIR, name);
}

/* Reads a configuration into the filter (no state changes). */
static void tt__taa_read_config(tt_post *p, const tt_config *c) {
  const char *mode = c ? tt_config_get_string(c, "mode") : NULL;
  p->mode = !mode || !strcmp(mode, "vctaa") ? TT__TAA_MODE_VCTAA
            : !strcmp(mode, "network")      ? TT__TAA_MODE_NETWORK
                                            : TT__TAA_MODE_NONE;
  p->vc_params.blend = c ? (float)tt_config_get_float(c, "blend", 0.1) : 0.1f;
  p->vc_params.gamma = c ? (float)tt_config_get_float(c, "gamma", 1.0) : 1.0f;
  p->vc_params.catmull_rom = c ? (int)tt_config_get_int(c, "catmullRom", 1) : 1;
  const char *res = c ? tt_config_get_string(c, "resolve") : NULL;
  p->vc_params.linear = res && !strcmp(res, "linear");
  p->channels = c ? (uint32_t)tt_config_get_int(c, "channels", 6) : 6;
}

/* Loads the network (if the mode needs it and the file changed) and sizes its state. */
static tt_status tt__taa_prepare_network(tt_post *p) {
  char path[sizeof p->weights_path];
  tt__taa_weights_path(p->channels, path, sizeof path);
  if (p->net_loaded && !strcmp(path, p->weights_path)) return TT_OK;
  tt__net_model m;
  tt_status st = tt__net_load(path, &m);
  if (st != TT_OK) return st;
  tt__net_state s;
  st = tt__net_state_init(&s, &m, p->width, p->height);
  if (st != TT_OK) {
    tt__net_free(&m);
    return st;
  }
  if (p->net_loaded) {
    tt__net_state_free(&p->net_state);
    tt__net_free(&p->net);
  }
  p->net = m;
  p->net_state = s;
  p->net_loaded = 1;
  snprintf(p->weights_path, sizeof p->weights_path, "%s", path);
  tt_host_log(tt__taa_host(), TT_LOG_DEBUG, TT__TAA_NAME,
              "network weights %s: width %u, hidden %u, %u "
              "body layers",
              path, m.width, m.hidden, m.body_count);
  return TT_OK;
}

/* Destroys a filter (NULL ignored). */
static void tt__taa_destroy(tt_post *p) {
  if (!p) return;
  tt__vctaa_free(&p->vc);
  if (p->net_loaded) {
    tt__net_state_free(&p->net_state);
    tt__net_free(&p->net);
  }
  free(p);
}

/* Creates a filter; loads the network now so a bad weights file fails early. */
static tt_status tt__taa_create(uint32_t width, uint32_t height, const tt_config *config,
                                tt_post **out) {
  *out = NULL;
  if (width == 0 || height == 0)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__TAA_NAME ": frame size %ux%u", width, height);
  tt_post *p = calloc(1, sizeof *p);
  if (!p) return tt_set_error(TT_ERR_OUT_OF_MEMORY, TT__TAA_NAME ": out of memory");
  p->width = width;
  p->height = height;
  tt__taa_read_config(p, config);
  tt_status st = tt__vctaa_init(&p->vc, width, height);
  if (st == TT_OK && p->mode == TT__TAA_MODE_NETWORK) st = tt__taa_prepare_network(p);
  if (st != TT_OK) {
    tt__taa_destroy(p);
    return st;
  }
  *out = p;
  return TT_OK;
}

/* Drops the history of both filters. */
static void tt__taa_reset(tt_post *p) {
  if (!p) return;
  p->vc.valid = 0;
  if (p->net_loaded) p->net_state.valid = 0;
}

/* Applies new parameters; switching mode starts the new filter without history. */
static tt_status tt__taa_configure(tt_post *p, const tt_config *config) {
  int old_mode = p->mode;
  uint32_t old_channels = p->channels;
  tt__taa_read_config(p, config);
  if (p->mode == TT__TAA_MODE_NETWORK) {
    tt_status st = tt__taa_prepare_network(p);
    if (st != TT_OK) {
      p->mode = old_mode;
      p->channels = old_channels;
      return st;
    }
  }
  if (p->mode != old_mode) tt__taa_reset(p);
  return TT_OK;
}

/* Filters one frame. */
static tt_status tt__taa_process(tt_post *p, const tt_post_frame *f, float *out_rgb) {
  if (!p || !f || !out_rgb || !f->color)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, TT__TAA_NAME ": process: NULL argument");
  if (f->width != p->width || f->height != p->height)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__TAA_NAME ": frame is %ux%u, the filter "
                                     "was created for %ux%u",
                        f->width, f->height, p->width, p->height);
  if (f->reset_history) tt__taa_reset(p);
  switch (p->mode) {
  case TT__TAA_MODE_VCTAA:
    tt__vctaa_process(&p->vc, tt__taa_host(), &p->vc_params, f->color, f->motion, out_rgb);
    break;
  case TT__TAA_MODE_NETWORK: {
    tt__net_frame nf = {.color = f->color,
                        .depth = f->depth,
                        .motion = f->motion,
                        .prev_depth = TT_POST_FRAME_HAS(f, prev_depth) ? f->prev_depth : NULL,
                        .jitter_index = f->jitter_index,
                        .jitter = {f->jitter[0], f->jitter[1]}};
    tt__net_process_frame(&p->net_state, &p->net, tt__taa_host(), &nf, out_rgb);
  } break;
  default: memcpy(out_rgb, f->color, sizeof(float) * 3 * p->width * p->height); break;
  }
  return TT_OK;
}

static const tt_post_iface g_iface = {
    .struct_size = sizeof(tt_post_iface),
    .space = tt__taa_space,
    .create = tt__taa_create,
    .configure = tt__taa_configure,
    .process = tt__taa_process,
    .reset = tt__taa_reset,
    .destroy = tt__taa_destroy,
};

/* ---- options (tt.options/1): settings that are not tuned ---- */

static const tt_option_info g_options[] = {
    {"weights", "network: weights file (.ttw, README.md) used instead of the shipped "
                "post_taa_c<channels>.ttw; \"\" = the shipped file"},
};

/* Number of options. */
static uint32_t tt__taa_option_count(void) { return 1; }

/* Option `i`, or NULL. */
static const tt_option_info *tt__taa_option_info(uint32_t i) {
  return i < 1 ? &g_options[i] : NULL;
}

/* Sets an option; the weights file is checked when a network filter is created. */
static tt_status tt__taa_option_set(const char *key, const char *value) {
  if (!key || strcmp(key, "weights"))
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__TAA_NAME ": no option \"%s\" (options: "
                                     "weights)",
                        key ? key : "(null)");
  if (!value || strlen(value) >= sizeof g_weights_option)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        TT__TAA_NAME ": option weights: expected a "
                                     "file name shorter than %zu bytes",
                        sizeof g_weights_option);
  snprintf(g_weights_option, sizeof g_weights_option, "%s", value);
  return TT_OK;
}

/* Current value of an option. */
static const char *tt__taa_option_get(const char *key) {
  return key && !strcmp(key, "weights") ? g_weights_option : NULL;
}

static const tt_options_iface g_options_iface = {
    .struct_size = sizeof(tt_options_iface),
    .count = tt__taa_option_count,
    .info = tt__taa_option_info,
    .set = tt__taa_option_set,
    .get = tt__taa_option_get,
};

/* Keeps the host table and builds the space. */
static tt_status tt__taa_init(const tt_host *host) {
  g_host = host;
  return g_space ? TT_OK : tt__taa_build_space();
}

/* Releases the space. */
static void tt__taa_deinit(void) {
  tt_space_destroy(g_space);
  g_space = NULL;
  g_host = NULL;
  g_weights_option[0] = 0;
}

/* Serves "tt.post/1" and "tt.options/1". */
static const void *tt__taa_get_interface(const char *id) {
  if (!id) return NULL;
  if (!strcmp(id, TT_POST_INTERFACE_ID)) return &g_iface;
  if (!strcmp(id, TT_OPTIONS_INTERFACE_ID)) return &g_options_iface;
  return NULL;
}

TT_PLUGIN_EXPORT const tt_plugin tt_plugin_entry = {
    .struct_size = sizeof(tt_plugin),
    .abi_major = TT_ABI_MAJOR,
    .abi_minor = TT_ABI_MINOR,
    .kind = TT_KIND_POST,
    .name = TT__TAA_NAME,
    .version = TT__TAA_VERSION,
    .description = "temporal anti-aliasing: variance-clipping TAA and the thesis' "
                   "kernel-prediction network",
    .init = tt__taa_init,
    .deinit = tt__taa_deinit,
    .get_interface = tt__taa_get_interface,
};
