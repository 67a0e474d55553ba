/* Plugin registry: finds plugin files, dlopen()s them, validates their ABI and keeps them
 * loaded until the registry is destroyed (see loader.h for the rules). */
#include <tunetrace/loader.h>
#include <tunetrace/suggest.h>

#include "plugin/elf_check.h"

#include <tt_util/strings.h>

#include <tunetrace/accel.h>
#include <tunetrace/integrator.h>
#include <tunetrace/post.h>
#include <tunetrace/predictor.h>
#include <tunetrace/sampler.h>
#include <tunetrace/tuner.h>

#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#ifndef TT_INSTALL_PLUGIN_DIR
#  define TT_INSTALL_PLUGIN_DIR ""
#endif
#ifndef TT_PLUGIN_SUBDIR
#  define TT_PLUGIN_SUBDIR "tunetrace-1"
#endif

/* The ABI 1.0 entry table ends with get_interface; anything shorter cannot be used. */
#define TT__ENTRY_MIN_SIZE (offsetof(tt_plugin, get_interface) + sizeof(void *))

struct tt_loaded_plugin {
  void *handle;              /* dlopen handle */
  const tt_plugin *entry;    /* the plugin's own table (lives in the mapped object) */
  char *path;                /* resolved file path */
  const void *iface;         /* validated kind interface */
};

/* A growable list of owned strings; used for search directories and listings. */
typedef struct tt__strlist {
  char **v;
  size_t n, cap;
} tt__strlist;

struct tt_registry {
  const tt_host *host;
  tt__strlist dirs;               /* added with tt_registry_add_dir, in order */
  char *search_path;              /* cache behind tt_registry_search_path */
  tt_loaded_plugin **plugins;     /* in load order */
  size_t count, cap;
  char *probe_name, *probe_version, *probe_description;  /* tt_registry_probe copies */
};

/* Joins a directory and a relative name with one '/'. */
static char *tt__join(const char *dir, const char *name) {
  size_t a = strlen(dir), b = strlen(name);
  char *p = malloc(a + b + 2);
  if (!p) return NULL;
  memcpy(p, dir, a);
  size_t o = a;
  if (a > 0 && dir[a - 1] != '/') p[o++] = '/';
  memcpy(p + o, name, b + 1);
  return p;
}

/* Appends a copy of `s` unless it is empty or already present (dirs repeat in practice:
 * TT_PLUGIN_PATH often names the build directory too). */
static int tt__strlist_push_unique(tt__strlist *l, const char *s, size_t len) {
  if (len == 0) return 0;
  for (size_t i = 0; i < l->n; i++)
    if (strlen(l->v[i]) == len && memcmp(l->v[i], s, len) == 0) return 0;
  if (l->n == l->cap) {
    size_t cap = l->cap ? l->cap * 2 : 8;
    char **v = realloc(l->v, cap * sizeof *v);
    if (!v) return -1;
    l->v = v;
    l->cap = cap;
  }
  char *c = malloc(len + 1);
  if (!c) return -1;
  memcpy(c, s, len);
  c[len] = '\0';
  l->v[l->n++] = c;
  return 0;
}

/* Frees every string and the array. */
static void tt__strlist_free(tt__strlist *l) {
  for (size_t i = 0; i < l->n; i++) free(l->v[i]);
  free(l->v);
  l->v = NULL;
  l->n = l->cap = 0;
}

/* The installed plugin folder as this copy of the library sees it: TT_PLUGIN_SUBDIR beside
 * the library file itself (a --destdir staging copy or a moved prefix finds its own plugins),
 * or "" when that folder does not exist (the build tree's library). */
static const char *tt__relocated_plugin_dir(void) {
  static char dir[4096 + sizeof TT_PLUGIN_SUBDIR + 1];
  static int done;
  if (done) return dir;
  done = 1;
  Dl_info info;
  char real[4096];
  if (!dladdr((void *)&tt_registry_create, &info) || !info.dli_fname ||
      !realpath(info.dli_fname, real))
    return dir;
  char *slash = strrchr(real, '/');
  if (!slash) return dir;
  *slash = '\0';
  snprintf(dir, sizeof dir, "%s/%s", real, TT_PLUGIN_SUBDIR);
  struct stat st;
  if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) dir[0] = '\0';
  return dir;
}

/* The effective search list: added dirs, $TT_PLUGIN_PATH, the installed plugin folder (beside
 * the library, then the configured one). The build tree's folder is not compiled in: the
 * uninstalled host and the build tree's Python package add it themselves, so an installed
 * library never loads a plugin from a build tree. Built on each use because the environment
 * may change between calls. */
static int tt__search_dirs(const tt_registry *reg, tt__strlist *out) {
  memset(out, 0, sizeof *out);
  for (size_t i = 0; i < reg->dirs.n; i++)
    if (tt__strlist_push_unique(out, reg->dirs.v[i], strlen(reg->dirs.v[i]))) goto oom;
  const char *env = getenv("TT_PLUGIN_PATH");
  while (env && *env) {
    const char *colon = strchr(env, ':');
    size_t len = colon ? (size_t)(colon - env) : strlen(env);
    if (tt__strlist_push_unique(out, env, len)) goto oom;
    env = colon ? colon + 1 : NULL;
  }
  const char *relocated = tt__relocated_plugin_dir();
  if (tt__strlist_push_unique(out, relocated, strlen(relocated))) goto oom;
  if (tt__strlist_push_unique(out, TT_INSTALL_PLUGIN_DIR, strlen(TT_INSTALL_PLUGIN_DIR)))
    goto oom;
  return 0;
oom:
  tt__strlist_free(out);
  return -1;
}

/* Joins the list with ':' for messages. */
static char *tt__strlist_join(const tt__strlist *l) {
  size_t len = 1;
  for (size_t i = 0; i < l->n; i++) len += strlen(l->v[i]) + 1;
  char *s = malloc(len);
  if (!s) return NULL;
  s[0] = '\0';
  size_t o = 0;
  for (size_t i = 0; i < l->n; i++) {
    size_t k = strlen(l->v[i]);
    if (i) s[o++] = ':';
    memcpy(s + o, l->v[i], k);
    o += k;
  }
  s[o] = '\0';
  return s;
}

/* True if `path` is an existing regular file (or a link to one). */
static int tt__is_file(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

/* True if `path` is a directory. */
static int tt__is_dir(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* True if `s` ends with `suffix`. */
static int tt__ends_with(const char *s, const char *suffix) {
  size_t a = strlen(s), b = strlen(suffix);
  return a >= b && strcmp(s + a - b, suffix) == 0;
}

/* A function (or string) slot of a kind's ABI 1.0 interface table that must not be NULL. */
typedef struct tt__required {
  size_t offset;
  const char *name;
} tt__required;

#define TT__REQ(type, field) {offsetof(type, field), #field}
static const tt__required tt__accel_required[] = {
  TT__REQ(tt_accel_iface, space), TT__REQ(tt_accel_iface, build),
  TT__REQ(tt_accel_iface, intersect1), TT__REQ(tt_accel_iface, occluded1),
  TT__REQ(tt_accel_iface, intersect_stream), TT__REQ(tt_accel_iface, occluded_stream),
  TT__REQ(tt_accel_iface, counters), TT__REQ(tt_accel_iface, destroy), {0, NULL}};
static const tt__required tt__integrator_required[] = {
  TT__REQ(tt_integrator_iface, space), TT__REQ(tt_integrator_iface, create),
  TT__REQ(tt_integrator_iface, configure), TT__REQ(tt_integrator_iface, render_pass),
  TT__REQ(tt_integrator_iface, reset), TT__REQ(tt_integrator_iface, destroy), {0, NULL}};
static const tt__required tt__tuner_required[] = {
  TT__REQ(tt_tuner_iface, space), TT__REQ(tt_tuner_iface, create),
  TT__REQ(tt_tuner_iface, next), TT__REQ(tt_tuner_iface, feedback),
  TT__REQ(tt_tuner_iface, best), TT__REQ(tt_tuner_iface, save_state),
  TT__REQ(tt_tuner_iface, load_state), TT__REQ(tt_tuner_iface, destroy), {0, NULL}};
static const tt__required tt__predictor_required[] = {
  TT__REQ(tt_predictor_iface, space), TT__REQ(tt_predictor_iface, create),
  TT__REQ(tt_predictor_iface, observe), TT__REQ(tt_predictor_iface, predict),
  TT__REQ(tt_predictor_iface, save), TT__REQ(tt_predictor_iface, load),
  TT__REQ(tt_predictor_iface, destroy), {0, NULL}};
static const tt__required tt__post_required[] = {
  TT__REQ(tt_post_iface, space), TT__REQ(tt_post_iface, create),
  TT__REQ(tt_post_iface, configure), TT__REQ(tt_post_iface, process),
  TT__REQ(tt_post_iface, reset), TT__REQ(tt_post_iface, destroy), {0, NULL}};
static const tt__required tt__sampler_required[] = {
  TT__REQ(tt_sampler_iface, name), TT__REQ(tt_sampler_iface, space),
  TT__REQ(tt_sampler_iface, create), TT__REQ(tt_sampler_iface, state_size),
  TT__REQ(tt_sampler_iface, start), TT__REQ(tt_sampler_iface, get),
  TT__REQ(tt_sampler_iface, destroy), {0, NULL}};
#undef TT__REQ

/* The slots the host may call through, per kind: every function of ABI 1.0 (the headers
 * say "all functions are required"), and the sampler's name. */
static const tt__required *tt__iface_required(uint32_t kind) {
  switch (kind) {
    case TT_KIND_ACCEL: return tt__accel_required;
    case TT_KIND_INTEGRATOR: return tt__integrator_required;
    case TT_KIND_TUNER: return tt__tuner_required;
    case TT_KIND_PREDICTOR: return tt__predictor_required;
    case TT_KIND_POST: return tt__post_required;
    case TT_KIND_SAMPLER: return tt__sampler_required;
  }
  return NULL;
}

/* Writes the comma-separated names of the NULL required slots of `iface` into `buf`
 * ("" when none is NULL). Pointer slots are read as bytes: function and data pointers have
 * one size on every platform the loader supports (POSIX dlsym relies on it too). */
static void tt__iface_missing(uint32_t kind, const void *iface, char *buf, size_t n) {
  buf[0] = '\0';
  size_t used = 0;
  for (const tt__required *r = tt__iface_required(kind); r && r->name; r++) {
    void *slot;
    memcpy(&slot, (const char *)iface + r->offset, sizeof slot);
    if (slot) continue;
    int w = snprintf(buf + used, n - used, "%s%s", used ? ", " : "", r->name);
    if (w < 0 || (size_t)w >= n - used) break;
    used += (size_t)w;
  }
}

/* Minimum interface table size per kind: the ABI 1.0 size (tables grown in 1.1 name it). */
static size_t tt__iface_min_size(uint32_t kind) {
  switch (kind) {
    case TT_KIND_ACCEL: return sizeof(tt_accel_iface);
    case TT_KIND_INTEGRATOR: return sizeof(tt_integrator_iface);
    case TT_KIND_TUNER: return TT_TUNER_IFACE_SIZE_1_0;
    case TT_KIND_PREDICTOR: return TT_PREDICTOR_IFACE_SIZE_1_0;
    case TT_KIND_POST: return sizeof(tt_post_iface);
    case TT_KIND_SAMPLER: return sizeof(tt_sampler_iface);
  }
  return 0;
}

tt_registry *tt_registry_create(const tt_host *host) {
  tt_registry *reg = calloc(1, sizeof *reg);
  if (!reg) {
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory creating a plugin registry");
    return NULL;
  }
  reg->host = host;
  return reg;
}

/* ---- plugins live once per process ----
 * dlopen of a file that is already loaded returns the same handle, so two registries (two
 * render sessions, two Python tt.Session objects) that load one plugin share its static
 * state: its space, its device, the host it keeps. init therefore runs when the first
 * registry loads the plugin and deinit when the last one unloads it; a plugin serves one
 * host table at a time. Before, each registry ran init and deinit on its own, so closing one
 * session freed the state the others still used (accel_embree: "build before init", freed
 * parameter names in error messages, a crash after tuning). One lock serializes init,
 * deinit and the counts: sessions may be created and closed on any thread. */
typedef struct tt__live {
  void *handle;              /* the dlopen handle the registries share */
  const tt_host *host;       /* the table init received */
  unsigned refs;             /* registries holding the plugin */
  struct tt__live *next;
} tt__live;

static pthread_mutex_t tt__live_lock = PTHREAD_MUTEX_INITIALIZER;
static tt__live *tt__live_list;

/* Registers one more user of the plugin behind `h`: the first one runs init with `host`.
 * Sets the error (naming `path`) and returns it when init fails, when out of memory, or
 * when the plugin already serves another host table. */
static tt_status tt__acquire(void *h, const tt_plugin *e, const tt_host *host, const char *path) {
  pthread_mutex_lock(&tt__live_lock);
  tt__live *l = tt__live_list;
  while (l && l->handle != h) l = l->next;
  tt_status st = TT_OK;
  if (l && l->host != host) {
    st = tt_set_error(TT_ERR_ABI, "plugin %s: already initialised in this process for host "
                      "\"%s\"; a plugin serves one host table at a time (load it with the same "
                      "tt_host, or destroy the other registries first)", path,
                      l->host && l->host->host_name ? l->host->host_name : "?");
  } else if (l) {
    l->refs++;
  } else if (!(l = calloc(1, sizeof *l))) {
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory loading plugin %s", path);
  } else {
    tt_status ist = TT_OK;
    if (e->init) {
      tt_clear_error();
      ist = e->init(host);
    }
    if (ist != TT_OK) {
      /* Copy the plugin's message first: tt_set_error formats into the same buffer. */
      char why[1024];
      const char *le = tt_last_error();
      snprintf(why, sizeof why, "%s", *le ? le : tt_status_string(ist));
      st = tt_set_error(ist < 0 ? ist : TT_ERR_ABI, "plugin %s: init failed: %s", path, why);
      free(l);
    } else {
      l->handle = h;
      l->host = host;
      l->refs = 1;
      l->next = tt__live_list;
      tt__live_list = l;
    }
  }
  pthread_mutex_unlock(&tt__live_lock);
  return st;
}

/* Drops one user of the plugin behind `h`: the last one runs deinit. */
static void tt__release(void *h, const tt_plugin *e) {
  pthread_mutex_lock(&tt__live_lock);
  tt__live **pl = &tt__live_list;
  while (*pl && (*pl)->handle != h) pl = &(*pl)->next;
  tt__live *l = *pl;
  if (l && --l->refs == 0) {
    *pl = l->next;
    free(l);
    if (e->deinit) e->deinit();
  }
  pthread_mutex_unlock(&tt__live_lock);
}

/* Unloads one plugin: deinit (when no other registry holds it) first, so it can release
 * what it owns while its code is still mapped. */
static void tt__unload(tt_loaded_plugin *p) {
  if (!p) return;
  if (p->entry) tt__release(p->handle, p->entry);
  if (p->handle) dlclose(p->handle);
  free(p->path);
  free(p);
}

void tt_registry_destroy(tt_registry *reg) {
  if (!reg) return;
  for (size_t i = reg->count; i-- > 0;) tt__unload(reg->plugins[i]);
  free(reg->plugins);
  tt__strlist_free(&reg->dirs);
  free(reg->search_path);
  free(reg->probe_name);
  free(reg->probe_version);
  free(reg->probe_description);
  free(reg);
}

tt_status tt_registry_add_dir(tt_registry *reg, const char *dir) {
  if (!reg || !dir || !*dir)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_registry_add_dir: empty directory");
  if (tt__strlist_push_unique(&reg->dirs, dir, strlen(dir)))
    return tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory adding plugin directory %s", dir);
  return TT_OK;
}

const char *tt_registry_search_path(tt_registry *reg) {
  if (!reg) return "";
  tt__strlist dirs;
  if (tt__search_dirs(reg, &dirs)) return reg->search_path ? reg->search_path : "";
  char *joined = tt__strlist_join(&dirs);
  tt__strlist_free(&dirs);
  if (!joined) return reg->search_path ? reg->search_path : "";
  /* Keep the previous pointer when nothing changed, so repeated calls stay valid. */
  if (reg->search_path && strcmp(reg->search_path, joined) == 0) {
    free(joined);
  } else {
    free(reg->search_path);
    reg->search_path = joined;
  }
  return reg->search_path;
}

/* ' (did you mean "NAME"?)' for a plugin not found (defined below tt__list_dir). */
static void tt__suggest_plugin(const tt__strlist *dirs, const char *name, char *buf, size_t n);

char *tt_registry_resolve(tt_registry *reg, const char *name_or_path) {
  if (!reg || !name_or_path || !*name_or_path) {
    tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_registry_resolve: empty plugin name");
    return NULL;
  }
  const char *s = name_or_path;
  if (strchr(s, '/') || tt__ends_with(s, ".so")) {
    struct stat st;
    const char *why = NULL;
    if (stat(s, &st) != 0) why = strerror(errno);
    else if (!S_ISREG(st.st_mode)) why = "not a regular file";
    if (why) {
      tt_set_error(TT_ERR_IO, "cannot load plugin %s: %s", s, why);
      return NULL;
    }
    /* A bare "x.so" would make dlopen search the library path instead of the cwd. */
    char *p = strchr(s, '/') ? tt__strdup(s) : tt__join(".", s);
    if (!p) tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory resolving plugin %s", s);
    return p;
  }
  tt__strlist dirs;
  if (tt__search_dirs(reg, &dirs)) {
    tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory resolving plugin %s", s);
    return NULL;
  }
  size_t n = strlen(s);
  char *flat = malloc(n + 4), *nested = malloc(2 * n + 5);
  char *found = NULL;
  if (flat && nested) {
    memcpy(flat, s, n);
    memcpy(flat + n, ".so", 4);
    memcpy(nested, s, n);
    nested[n] = '/';
    memcpy(nested + n + 1, flat, n + 4);
    for (size_t i = 0; i < dirs.n && !found; i++) {
      const char *cand[2] = {flat, nested};
      for (int k = 0; k < 2 && !found; k++) {
        char *p = tt__join(dirs.v[i], cand[k]);
        if (p && tt__is_file(p)) found = p;
        else free(p);
      }
    }
  }
  if (!found) {
    char *joined = tt__strlist_join(&dirs), near[160] = "";
    tt__suggest_plugin(&dirs, s, near, sizeof near);
    tt_set_error(TT_ERR_IO, "plugin \"%s\" not found%s: looked for %s.so and %s/%s.so in %s", s,
                 near, s, s, s, joined && *joined ? joined : "(no directories)");
    free(joined);
  }
  free(flat);
  free(nested);
  tt__strlist_free(&dirs);
  return found;
}

/* dlopen()s `path` and checks the entry table head: symbol, size, ABI major, kind, name.
 * On failure nothing stays open. Shared by load and probe so both reject alike. */
static tt_status tt__open_entry(const char *path, void **handle_out, const tt_plugin **entry_out) {
  *handle_out = NULL;
  *entry_out = NULL;
  /* a truncated file would make dlopen fault (SIGBUS) instead of failing */
  tt_status est = tt__elf_check_plugin(path);
  if (est != TT_OK) return est;
  dlerror();
  void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
  if (!h) {
    const char *why = dlerror();
    return tt_set_error(TT_ERR_ABI, "cannot load plugin %s: %s", path,
                        why ? why : "dlopen failed");
  }
  tt_status st = TT_OK;
  const tt_plugin *e = (const tt_plugin *)dlsym(h, TT_PLUGIN_ENTRY_SYMBOL);
  if (!e) {
    st = tt_set_error(TT_ERR_ABI, "plugin %s: no symbol \"%s\" (not a tunetrace plugin)", path,
                      TT_PLUGIN_ENTRY_SYMBOL);
  } else if (e->struct_size < TT__ENTRY_MIN_SIZE) {
    st = tt_set_error(TT_ERR_ABI,
                      "plugin %s: entry table is %u bytes, shorter than the %zu bytes of "
                      "ABI 1.0 (plugin ABI %u.%u, host ABI %d.%d)",
                      path, (unsigned)e->struct_size, (size_t)TT__ENTRY_MIN_SIZE,
                      (unsigned)e->abi_major, (unsigned)e->abi_minor, TT_ABI_MAJOR,
                      TT_ABI_MINOR);
  } else if (e->abi_major != TT_ABI_MAJOR) {
    st = tt_set_error(TT_ERR_ABI, "plugin %s: version mismatch: plugin ABI %u.%u, host ABI %d.%d",
                      path, (unsigned)e->abi_major, (unsigned)e->abi_minor, TT_ABI_MAJOR,
                      TT_ABI_MINOR);
  } else if (!tt_plugin_kind_interface(e->kind)) {
    st = tt_set_error(TT_ERR_ABI,
                      "plugin %s: unknown plugin kind %u (plugin ABI %u.%u, host ABI %d.%d "
                      "knows kinds 1 to %d)",
                      path, (unsigned)e->kind, (unsigned)e->abi_major, (unsigned)e->abi_minor,
                      TT_ABI_MAJOR, TT_ABI_MINOR, TT_KIND_COUNT);
  } else if (!e->name || !*e->name) {
    st = tt_set_error(TT_ERR_ABI, "plugin %s: entry table has no name", path);
  } else if (!e->get_interface) {
    st = tt_set_error(TT_ERR_ABI,
                      "plugin %s (%s): does not provide interface \"%s\" (get_interface is NULL)",
                      path, e->name, tt_plugin_kind_interface(e->kind));
  }
  if (st != TT_OK) {
    dlclose(h);
    return st;
  }
  *handle_out = h;
  *entry_out = e;
  return TT_OK;
}

tt_status tt_registry_load(tt_registry *reg, const char *name_or_path, tt_loaded_plugin **out) {
  if (out) *out = NULL;
  if (!reg) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_registry_load: no registry");
  if (!reg->host)
    return tt_set_error(TT_ERR_INVALID_ARGUMENT,
                        "cannot load plugin %s: the registry has no host services",
                        name_or_path ? name_or_path : "(null)");
  char *path = tt_registry_resolve(reg, name_or_path);
  if (!path) return TT_ERR_IO;  /* resolve set the message */

  void *h;
  const tt_plugin *e;
  tt_status st = tt__open_entry(path, &h, &e);
  if (st != TT_OK) {
    free(path);
    return st;
  }

  /* Duplicates are rejected before init: dlopen of an already-loaded file returns the same
   * handle, so init/deinit would run again on the live plugin's state. */
  for (size_t i = 0; i < reg->count; i++) {
    const tt_loaded_plugin *o = reg->plugins[i];
    if (e->kind != TT_KIND_POST && o->entry->kind == e->kind) {
      st = tt_set_error(TT_ERR_ABI, "plugin %s: a second %s plugin: %s is already loaded from %s",
                        path, tt_plugin_kind_name(e->kind), o->entry->name, o->path);
      break;
    }
    if (strcmp(o->entry->name, e->name) == 0) {
      st = tt_set_error(TT_ERR_ABI, "plugin %s: a plugin named \"%s\" is already loaded from %s",
                        path, e->name, o->path);
      break;
    }
  }
  if (st != TT_OK) {
    dlclose(h);
    free(path);
    return st;
  }

  st = tt__acquire(h, e, reg->host, path);
  if (st != TT_OK) {
    dlclose(h);
    free(path);
    return st;
  }

  const char *id = tt_plugin_kind_interface(e->kind);
  const void *iface = e->get_interface(id);
  size_t need = tt__iface_min_size(e->kind);
  if (!iface) {
    st = tt_set_error(TT_ERR_ABI, "plugin %s (%s): does not provide interface \"%s\" required of "
                      "a %s plugin", path, e->name, id, tt_plugin_kind_name(e->kind));
  } else if (*(const uint32_t *)iface < need) {
    st = tt_set_error(TT_ERR_ABI,
                      "plugin %s (%s): interface \"%s\" table is %u bytes, shorter than the %zu "
                      "bytes of ABI 1.0 (plugin ABI %u.%u, host ABI %d.%d)",
                      path, e->name, id, (unsigned)*(const uint32_t *)iface, need,
                      (unsigned)e->abi_major, (unsigned)e->abi_minor, TT_ABI_MAJOR, TT_ABI_MINOR);
  } else {
    /* the host calls through these without checking: a NULL one would be a SIGSEGV later */
    char missing[512];
    tt__iface_missing(e->kind, iface, missing, sizeof missing);
    if (missing[0])
      st = tt_set_error(TT_ERR_ABI, "plugin %s (%s): interface \"%s\" has no %s (NULL; every "
                        "function of a %s interface is required)", path, e->name, id, missing,
                        tt_plugin_kind_name(e->kind));
  }

  tt_loaded_plugin *p = NULL;
  if (st == TT_OK && reg->count == reg->cap) {
    size_t cap = reg->cap ? reg->cap * 2 : 8;
    tt_loaded_plugin **v = realloc(reg->plugins, cap * sizeof *v);
    if (!v) st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory loading plugin %s", path);
    else {
      reg->plugins = v;
      reg->cap = cap;
    }
  }
  if (st == TT_OK && !(p = calloc(1, sizeof *p)))
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory loading plugin %s", path);
  if (st != TT_OK) {
    tt__release(h, e);
    dlclose(h);
    free(path);
    return st;
  }
  p->handle = h;
  p->entry = e;
  p->path = path;
  p->iface = iface;
  reg->plugins[reg->count++] = p;
  if (out) *out = p;
  return TT_OK;
}

tt_status tt_registry_probe(tt_registry *reg, const char *path, tt_plugin *entry_copy) {
  if (!reg) return tt_set_error(TT_ERR_INVALID_ARGUMENT, "tt_registry_probe: no registry");
  char *resolved = tt_registry_resolve(reg, path);
  if (!resolved) return TT_ERR_IO;
  void *h;
  const tt_plugin *e;
  tt_status st = tt__open_entry(resolved, &h, &e);
  if (st != TT_OK) {
    free(resolved);
    return st;
  }
  /* get_interface may only be called after init, so the interface is not probed. The
   * strings are copied because the object is closed again right away. */
  char *name = tt__strdup(e->name);
  char *version = tt__strdup(e->version ? e->version : "");
  char *description = tt__strdup(e->description ? e->description : "");
  if (!name || !version || !description) {
    free(name);
    free(version);
    free(description);
    dlclose(h);
    st = tt_set_error(TT_ERR_OUT_OF_MEMORY, "out of memory probing plugin %s", resolved);
    free(resolved);
    return st;
  }
  if (entry_copy) {
    memset(entry_copy, 0, sizeof *entry_copy);
    entry_copy->struct_size = e->struct_size < sizeof(tt_plugin) ? e->struct_size
                                                                  : (uint32_t)sizeof(tt_plugin);
    entry_copy->abi_major = e->abi_major;
    entry_copy->abi_minor = e->abi_minor;
    entry_copy->kind = e->kind;
    entry_copy->name = name;
    entry_copy->version = version;
    entry_copy->description = description;
  }
  dlclose(h);
  free(reg->probe_name);
  free(reg->probe_version);
  free(reg->probe_description);
  reg->probe_name = name;
  reg->probe_version = version;
  reg->probe_description = description;
  free(resolved);
  return TT_OK;
}

size_t tt_registry_count(const tt_registry *reg) { return reg ? reg->count : 0; }

tt_loaded_plugin *tt_registry_get(const tt_registry *reg, size_t index) {
  return reg && index < reg->count ? reg->plugins[index] : NULL;
}

tt_loaded_plugin *tt_registry_find_kind(const tt_registry *reg, uint32_t kind) {
  for (size_t i = 0; reg && i < reg->count; i++)
    if (reg->plugins[i]->entry->kind == kind) return reg->plugins[i];
  return NULL;
}

tt_loaded_plugin *tt_registry_find_name(const tt_registry *reg, const char *name) {
  for (size_t i = 0; reg && name && i < reg->count; i++)
    if (strcmp(reg->plugins[i]->entry->name, name) == 0) return reg->plugins[i];
  return NULL;
}

const tt_plugin *tt_loaded_plugin_entry(const tt_loaded_plugin *p) { return p ? p->entry : NULL; }

const char *tt_loaded_plugin_path(const tt_loaded_plugin *p) { return p ? p->path : NULL; }

const void *tt_loaded_plugin_iface(const tt_loaded_plugin *p) { return p ? p->iface : NULL; }

const void *tt_loaded_plugin_get(const tt_loaded_plugin *p, const char *id) {
  return p && id ? p->entry->get_interface(id) : NULL;
}

const tt_space *tt_loaded_plugin_space(const tt_loaded_plugin *p) {
  if (!p) return NULL;
  /* Each kind's table is read through its own type: sampler has `name` before `space`. */
  const tt_space *(*fn)(void) = NULL;
  switch (p->entry->kind) {
    case TT_KIND_ACCEL: fn = ((const tt_accel_iface *)p->iface)->space; break;
    case TT_KIND_INTEGRATOR: fn = ((const tt_integrator_iface *)p->iface)->space; break;
    case TT_KIND_TUNER: fn = ((const tt_tuner_iface *)p->iface)->space; break;
    case TT_KIND_PREDICTOR: fn = ((const tt_predictor_iface *)p->iface)->space; break;
    case TT_KIND_POST: fn = ((const tt_post_iface *)p->iface)->space; break;
    case TT_KIND_SAMPLER: fn = ((const tt_sampler_iface *)p->iface)->space; break;
  }
  return fn ? fn() : NULL;
}

/* One plugin file found while listing a directory. */
typedef struct tt__listed {
  char *name;
  char *path;
  int nested;  /* 1 for NAME/NAME.so, which resolve tries after NAME.so */
} tt__listed;

/* Orders by name, NAME.so before NAME/NAME.so, matching resolution order. */
static int tt__listed_cmp(const void *a, const void *b) {
  const tt__listed *x = a, *y = b;
  int c = strcmp(x->name, y->name);
  return c ? c : x->nested - y->nested;
}

/* NAME of a file name NAME.so (`len` its length, > 3), malloc'ed; NULL without memory. */
static char *tt__so_stem(const char *fn, size_t len) {
  char *name = malloc(len - 2);
  if (name) {
    memcpy(name, fn, len - 3);
    name[len - 3] = '\0';
  }
  return name;
}

/* Collects NAME.so and NAME/NAME.so entries of one directory into `*items`; a NAME.so that
 * is not a regular file (nor a folder holding NAME.so.so) is collected too, to be rejected
 * by name. */
static size_t tt__list_dir(const char *dir, tt__listed **items) {
  *items = NULL;
  DIR *d = opendir(dir);
  if (!d) return 0;
  size_t n = 0, cap = 0;
  struct dirent *de;
  while ((de = readdir(d))) {
    const char *fn = de->d_name;
    if (fn[0] == '.') continue;
    char *path = NULL, *name = NULL;
    int nested = 0;
    char *full = tt__join(dir, fn);
    if (!full) break;
    size_t len = strlen(fn);
    if (len > 3 && tt__ends_with(fn, ".so") && tt__is_file(full)) {
      path = full;
      name = tt__so_stem(fn, len);
    } else if (tt__is_dir(full)) {
      char *so = malloc(len + 4);
      if (so) {
        memcpy(so, fn, len);
        memcpy(so + len, ".so", 4);
        char *inner = tt__join(full, so);
        if (inner && tt__is_file(inner)) {
          path = inner;
          name = tt__strdup(fn);
          nested = 1;
        } else {
          free(inner);
        }
        free(so);
      }
      if (!path && len > 3 && tt__ends_with(fn, ".so")) {  /* a folder named NAME.so */
        path = full;
        name = tt__so_stem(fn, len);
      } else {
        free(full);
      }
    } else if (len > 3 && tt__ends_with(fn, ".so")) {
      /* NAME.so that is not a regular file (a FIFO, a device, a dangling link): listed, so
       * the probe rejects it with the reason instead of the file silently not being there */
      path = full;
      name = tt__so_stem(fn, len);
    } else {
      free(full);
    }
    if (!path || !name) {
      free(path);
      free(name);
      continue;
    }
    if (n == cap) {
      size_t nc = cap ? cap * 2 : 16;
      tt__listed *v = realloc(*items, nc * sizeof *v);
      if (!v) {
        free(path);
        free(name);
        break;
      }
      *items = v;
      cap = nc;
    }
    (*items)[n].name = name;
    (*items)[n].path = path;
    (*items)[n].nested = nested;
    n++;
  }
  closedir(d);
  if (n) qsort(*items, n, sizeof **items, tt__listed_cmp);
  return n;
}

/* Writes ' (did you mean "NAME"?)' into buf when a plugin file in `dirs` has a name close
 * to `name` (tt_suggest), else "". */
static void tt__suggest_plugin(const tt__strlist *dirs, const char *name, char *buf, size_t n) {
  buf[0] = '\0';
  const char *names[256];
  tt__listed *all[64];
  size_t counts[64], count = 0, ndirs = dirs->n < 64 ? dirs->n : 64;
  for (size_t i = 0; i < ndirs; i++) {
    counts[i] = tt__list_dir(dirs->v[i], &all[i]);
    for (size_t k = 0; k < counts[i] && count < 256; k++) names[count++] = all[i][k].name;
  }
  const char *near = tt_suggest(name, names, count);
  if (near) snprintf(buf, n, " (did you mean \"%s\"?)", near);
  for (size_t i = 0; i < ndirs; i++) {
    for (size_t k = 0; k < counts[i]; k++) {
      free(all[i][k].name);
      free(all[i][k].path);
    }
    free(all[i]);
  }
}

void tt_registry_list_files(tt_registry *reg, void (*fn)(void *user, const char *path),
                            void *user) {
  if (!reg || !fn) return;
  tt__strlist dirs, seen = {0};
  if (tt__search_dirs(reg, &dirs)) return;
  for (size_t i = 0; i < dirs.n; i++) {
    tt__listed *items;
    size_t n = tt__list_dir(dirs.v[i], &items);
    for (size_t k = 0; k < n; k++) {
      size_t before = seen.n;
      /* push_unique only grows the list for a name not seen yet: first occurrence wins. */
      if (tt__strlist_push_unique(&seen, items[k].name, strlen(items[k].name)) == 0 &&
          seen.n > before)
        fn(user, items[k].path);
      free(items[k].name);
      free(items[k].path);
    }
    free(items);
  }
  tt__strlist_free(&seen);
  tt__strlist_free(&dirs);
}
