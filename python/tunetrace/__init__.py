"""tunetrace from Python: render scenes through libtunetrace's plugins into numpy arrays,
tune plugin parameters online (thesis ch. 3) and read the tuning database.

    import tunetrace as tt
    s = tt.Session("scenes/cornell-box/scene.json", plugins=["integrator_pt"],
                   resolution=(128, 128), seed=7, aovs=["normal", "albedo"])
    s.set("integrator_pt.maxDepth", 8)
    rgb = s.render(spp=16)            # (128, 128, 3) float32, linear RGB
    normal = s.aov("normal")          # (128, 128, 3)
    t = s.tune("accel_embree", tuner="tuner_nm", iterations=20, db="tuning.db")
    print(t.best_config, t.best_cost, len(t.history))

Everything goes through the library's render session (tunetrace/session.h), so an image is
the one `host` renders for the same scene, plugins, parameters and seed. Errors raise
tunetrace.Error carrying the library's message (which names the file, the field and what
was expected), as a subclass that is also the built-in exception Python code catches for
it: a missing file is a FileNotFoundError, a bad value a ValueError, an unknown parameter a
KeyError, a wrong argument type a TypeError. See python/README.md for how the library is
found.
"""
import atexit
import contextlib
import ctypes
import json
import logging
import os
import warnings

import numpy as np

from . import _lib
from ._errors import (STATUS, ArgumentTypeError, Error, FileError, InfeasibleError,
                      InternalError, InvalidArgumentError, NoDataError, NotFoundError,
                      NumericError, OutOfMemoryError, ParseError, PluginError, StopRequested,
                      UnknownNameError, UnsupportedError, check as _check,
                      last_error_text as _last_error_text, make_error as _make_error)
from ._lib import lib, text

__all__ = ["Error", "InvalidArgumentError", "ParseError", "InfeasibleError", "NumericError",
           "UnknownNameError", "FileError", "NotFoundError", "OutOfMemoryError",
           "ArgumentTypeError", "PluginError", "UnsupportedError", "NoDataError",
           "StopRequested", "InternalError", "STATUS", "KINDS", "AOVS", "INDICATORS", "COST_INFEASIBLE",
           "Session", "Tuning", "TuningDB", "version", "library_path", "list_plugins",
           "describe", "read_image", "write_exr", "set_threads", "__version__"]

__version__ = text(lib.tt_version())
"""The version of the libtunetrace this package loaded (the package is versioned with it)."""

# ---- the library's messages through logging ----------------------------------------------
# The default host's log (plugins' messages and the library's own, e.g. a scene loader's
# warnings) goes to the logger "tunetrace" (a plugin's to "tunetrace.PLUGIN"), levels mapped;
# nothing is printed to stderr by the library. Messages below the logger's level are
# dropped in the library already: the threshold is taken when a session is created and at
# every render() and tune().
_log = logging.getLogger("tunetrace")
_LEVELS = {0: logging.DEBUG, 1: logging.INFO, 2: logging.WARNING, 3: logging.ERROR}


def _on_log(_user, level, plugin, message):
    logger = _log.getChild(plugin.decode(errors="replace")) if plugin else _log
    logger.log(_LEVELS.get(level, logging.ERROR), "%s", message.decode(errors="replace"))


_LOG_FN = _lib.LOG_FN(_on_log)  # kept alive: the library holds the pointer


def _sync_log_level():
    """Lets the library drop what the `tunetrace` logger would drop anyway."""
    eff = _log.getEffectiveLevel()
    lib.tt_default_host_set_log_level(next((k for k, v in sorted(_LEVELS.items())
                                            if v >= eff), 3))


lib.tt_default_host_set_log_callback(_LOG_FN, None)
_sync_log_level()
# messages from interpreter shutdown on (sessions freed late) go to stderr again
atexit.register(lib.tt_default_host_set_log_callback, _lib.LOG_FN(), None)


def _kinds():
    """{1: "accel", 2: "integrator", ...}: the plugin kinds as the library names them."""
    out, k = {}, 1
    while text(lib.tt_plugin_kind_name(k)) != "unknown":
        out[k] = text(lib.tt_plugin_kind_name(k))
        k += 1
    return out


KINDS = _kinds()
"""Plugin kind value -> name ("accel", "integrator", "tuner", ...), from the library."""
AOVS = {"depth": (1, 1), "normal": (2, 3), "albedo": (4, 3), "motion": (8, 2)}
"""AOV name -> (tt_aov bit, channels) (tunetrace/film.h)."""
COST_INFEASIBLE = 1e300
"""The cost of a configuration that could not be measured (TT_COST_INFEASIBLE, tuner.h)."""
_STATUS_NAMES = {0: "ok", 1: "infeasible", 2: "failed"}
INDICATORS = tuple(text(lib.tt_scene_indicator_name(k))
                   for k in range(_lib.TT_SCENE_INDICATOR_COUNT))
"""The names of the scene indicators (tt_scene_indicator_name), in the order of a
TuningDB row's "indicators" list: dict(zip(INDICATORS, row["indicators"]))."""
_ERR_NO_DATA, _ERR_INTERRUPTED = STATUS["TT_ERR_NO_DATA"], STATUS["TT_ERR_INTERRUPTED"]
_ERR_ARG = STATUS["TT_ERR_INVALID_ARGUMENT"]


def _refuse_nul(raw, text_, what):
    if b"\0" in raw:
        raise InvalidArgumentError(_ERR_ARG, f"{what}: {text_!r} contains a NUL character "
                                   "(the library would read it cut short there)")
    return raw


def _b(s, what="argument"):
    """A name or value as the library's char *: UTF-8; a NUL character is refused (C would
    silently cut the string there)."""
    if s is None:
        return None
    s = str(s)
    return _refuse_nul(s.encode(), s, what)


def _path(p, what="path"):
    """A path (str, bytes or os.PathLike) as the library's char *, encoded as the file system
    encodes it; a NUL character is refused (ValueError), as open() does."""
    if not isinstance(p, (str, bytes, os.PathLike)):
        raise ArgumentTypeError(_ERR_ARG, f"{what}: expected a path (str, bytes or "
                                f"os.PathLike), got {type(p).__name__}")
    p = os.fspath(p)
    return _refuse_nul(os.fsencode(p), p, what)


def _names(v, what):
    """A list of names from a list/tuple or one name: plugins="integrator_pt" is one plugin,
    not a sequence of letters."""
    if v is None:
        return []
    if isinstance(v, (str, bytes, os.PathLike)):
        return [v]
    try:
        return list(v)
    except TypeError:
        raise ArgumentTypeError(_ERR_ARG, f"{what}: expected a name or a list of names, got "
                                f"{type(v).__name__}") from None


def _integer(v, what):
    """An integer argument (int, numpy integer, anything with __index__); TypeError naming
    the argument for a str, float or other type. The range is checked by the library."""
    if isinstance(v, bool):
        raise ArgumentTypeError(_ERR_ARG, f"{what}: expected an integer, got bool {v!r}")
    try:
        return int(v.__index__())
    except AttributeError:
        raise ArgumentTypeError(_ERR_ARG, f"{what}: expected an integer, got "
                                f"{type(v).__name__} {v!r}") from None


def _number(v, what):
    """A real-number argument (int, float, numpy number); TypeError naming the argument for a
    str or other type."""
    if isinstance(v, (str, bytes, bool)) or not hasattr(v, "__float__"):
        raise ArgumentTypeError(_ERR_ARG, f"{what}: expected a number, got "
                                f"{type(v).__name__} {v!r}")
    return float(v)


def _limited(limit, value, what):
    """`value` as an integer within the library's limit `limit` (tunetrace/limits.h, which
    the host's options use too): out of range raises, never wraps."""
    digits = str(_integer(value, what))
    which, out = ctypes.c_int(), ctypes.c_uint64()
    _check(lib.tt_limit_find(_b(limit), ctypes.byref(which)), what)
    _check(lib.tt_limit_parse_uint(which, _b(digits), ctypes.byref(out)), what)
    return out.value


def _resolution(resolution):
    """(width, height) checked as the host checks --res WIDTHxHEIGHT (tunetrace/limits.h)."""
    try:
        w, h = resolution
    except (TypeError, ValueError):
        raise ArgumentTypeError(_ERR_ARG, "resolution: expected (width, height), got "
                                f"{resolution!r}") from None
    w, h = _integer(w, "resolution width"), _integer(h, "resolution height")
    out_w, out_h = ctypes.c_uint32(), ctypes.c_uint32()
    _check(lib.tt_limit_parse_resolution(_b(f"{w}x{h}"), ctypes.byref(out_w),
                                         ctypes.byref(out_h)), "resolution")
    return out_w.value, out_h.value


def _limited_real(limit, value, what):
    """`value` as a real number within the library's limit `limit` (tunetrace/limits.h)."""
    which, out = ctypes.c_int(), ctypes.c_double()
    _check(lib.tt_limit_find(_b(limit), ctypes.byref(which)), what)
    _check(lib.tt_limit_parse_real(which, _b(repr(_number(value, what))), ctypes.byref(out)),
           what)
    return out.value


def version():
    """The library's version string."""
    return text(lib.tt_version())


def library_path():
    """The libtunetrace file this package loaded."""
    return _lib.LIBRARY_PATH


def set_threads(n):
    """Worker threads of the library's default host (0: all CPUs). Before rendering."""
    n = _limited("threads", n, "threads") if n != 0 else 0
    _check(lib.tt_default_host_set_threads(n), "threads")


def _extra_plugin_dirs(plugin_path):
    """plugin_path, then $TT_PLUGIN_PATH, then (the build tree's package only) the build
    tree's plugins; the library then searches its installed plugin folder."""
    dirs = [os.fspath(d) for d in _names(plugin_path, "plugin_path")]
    build = getattr(_lib._paths, "BUILD_PLUGIN_DIR", None) if _lib._paths else None
    if build:  # after $TT_PLUGIN_PATH, as for the uninstalled host
        dirs += [d for d in os.environ.get("TT_PLUGIN_PATH", "").split(":") if d]
        dirs.append(build)
    return dirs


def _plugin_info(entry, path=None):
    e = entry.contents if hasattr(entry, "contents") else entry
    return {"name": text(e.name), "kind": KINDS.get(e.kind, str(e.kind)),
            "version": text(e.version), "description": text(e.description) or "",
            "path": path}


class _Handle:
    """An owned library object: close() (or a with block, or garbage collection) frees it
    once with the class's _free function; _p raises once it is closed."""
    _ptr = None
    _what = "object"

    @staticmethod
    def _free(ptr):
        raise NotImplementedError

    def close(self):
        if self._ptr:
            self._free(self._ptr)
            self._ptr = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()

    @property
    def _p(self):
        if not self._ptr:
            raise InvalidArgumentError(_ERR_ARG, f"the {self._what} is closed")
        return self._ptr


class _Registry(_Handle):
    """A registry for listing and describing plugins outside a session."""
    _what = "registry"
    _free = staticmethod(lambda p: lib.tt_registry_destroy(p))

    def __init__(self, plugin_path=None):
        self._ptr = lib.tt_registry_create(lib.tt_default_host())
        if not self._ptr:
            _check(STATUS["TT_ERR_OUT_OF_MEMORY"], "registry")
        for d in _extra_plugin_dirs(plugin_path):
            lib.tt_registry_add_dir(self._ptr, _path(d, "plugin_path"))


def list_plugins(plugin_path=None):
    """Every plugin file in the search path (first occurrence of a name wins), as dicts
    {name, kind, version, description, path}; a file the loader rejects has name None and
    its reason under "error"."""
    out = []
    with _Registry(plugin_path) as reg:
        def one(_user, path):
            entry = _lib.Plugin()
            if lib.tt_registry_probe(reg._p, path, ctypes.byref(entry)) == 0:
                out.append(_plugin_info(entry, path.decode()))
            else:
                out.append({"name": None, "path": path.decode(),
                            "error": text(lib.tt_last_error())})
        lib.tt_registry_list_files(reg._p, _lib.LIST_FN(one), None)
    return out


def _describe_loaded(p):
    """Space (parameters, constraints) and options of a loaded plugin, as host --describe."""
    entry = lib.tt_loaded_plugin_entry(p).contents
    space = lib.tt_loaded_plugin_space(p)
    d = json.loads(_lib.take_string(lib.tt_space_to_json(space))) if space else {
        "plugin": text(entry.name), "version": text(entry.version), "parameters": [],
        "constraints": []}
    d["kind"] = KINDS.get(entry.kind, str(entry.kind))
    d["options"] = []
    oi = lib.tt_session_plugin_options(p)
    if oi:
        oi = oi.contents
        for i in range(oi.count()):
            info = oi.info(i)
            if not info or not info.contents.key:
                continue
            key = info.contents.key
            d["options"].append({"name": text(key),
                                 "description": text(info.contents.description) or "",
                                 "value": text(oi.get(key)) or ""})
    return d


def describe(name, plugin_path=None):
    """The plugin's parameter space and options as a dict (host --describe NAME)."""
    with _Registry(plugin_path) as reg:
        p = ctypes.c_void_p()
        _check(lib.tt_registry_load(reg._p, _path(name, "plugin"), ctypes.byref(p)),
               f"plugin \"{name}\"")
        return _describe_loaded(p)


def read_image(path):
    """Reads an image (EXR, PNG, ... through OpenImageIO) as float32 (height, width,
    channels)."""
    w, h, c = ctypes.c_uint32(), ctypes.c_uint32(), ctypes.c_uint32()
    px = ctypes.POINTER(ctypes.c_float)()
    _check(lib.tt_image_read(_path(path, "read_image"), ctypes.byref(w), ctypes.byref(h),
                             ctypes.byref(c), ctypes.byref(px)), filename=path)
    try:
        n = w.value * h.value * c.value
        return np.ctypeslib.as_array(px, shape=(n,)).copy().reshape(h.value, w.value, c.value)
    finally:
        lib.tt_free(ctypes.cast(px, ctypes.c_void_p))


class _Meta(ctypes.Structure):  # tt_image_meta (image.h)
    _fields_ = [("key", ctypes.c_char_p), ("value", ctypes.c_char_p)]


def write_exr(path, pixels, channels=None, meta=None):
    """Writes float32 pixels (height, width[, channels]) to an OpenEXR file (32-bit float,
    bit-exact round trip) with channel names (default R,G,B[,A] or Y; layers as
    "normal.X", ...) and metadata (a dict of strings)."""
    a = np.ascontiguousarray(pixels, dtype=np.float32)
    if a.ndim == 2:
        a = a[:, :, None]
    h, w, c = a.shape
    names = None
    if channels is not None:
        if len(channels) != c:
            raise InvalidArgumentError(_ERR_ARG, f"write_exr {path}: {c} channels but "
                                       f"{len(channels)} names")
        names = (ctypes.c_char_p * c)(*[_b(n, "channel name") for n in channels])
    items = list((meta or {}).items())
    m = (_Meta * max(1, len(items)))(*[_Meta(_b(k, "meta key"), _b(v, "meta value"))
                                       for k, v in items])
    _check(lib.tt_image_write_exr(_path(path, "write_exr"), w, h, c,
                                  a.ctypes.data_as(ctypes.POINTER(ctypes.c_float)), names,
                                  ctypes.cast(m, ctypes.c_void_p), len(items)))


def _value_text(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


class Session(_Handle):
    """A render session: one scene, the loaded plugins with their configurations, the accel,
    the integrator and the film. Passes accumulate progressively; render() returns the image
    so far. Use from one thread; close() (or a with block) frees it."""

    def __init__(self, scene, plugins=(), params=None, resolution=None, seed=None,
                 aovs=(), plugin_path=None, camera_time=None, frame_interval=1.0 / 24):
        """Loads `scene` (scene.json or .pbrt) and the `plugins` (names or paths; one name
        alone is one plugin); `params` maps "plugin.param" to a value (a plugin not listed in
        `plugins` is loaded by name, as set() does); `resolution` (width, height) and `seed`
        override the scene's; `aovs` names the AOV planes to keep (depth, normal, albedo,
        motion); `camera_time` (seconds) picks the pose on the scene's camera path, with the
        motion AOV measured against the pose `frame_interval` earlier."""
        scene_b = _path(scene, "scene")
        plugins = _names(plugins, "plugins")
        aov_mask = self._aov_mask(aovs)
        if resolution is not None:
            w, h = _resolution(resolution)
        if seed is not None:
            seed = _limited("seed", seed, "seed")
        if camera_time is not None:
            camera_time = _number(camera_time, "camera_time")
            frame_interval = _number(frame_interval, "frame_interval")
        _sync_log_level()
        ptr = ctypes.c_void_p()
        _check(lib.tt_session_create(None, ctypes.byref(ptr)), "session")
        self._ptr = ptr
        self._aovs = aov_mask
        for d in _extra_plugin_dirs(plugin_path):
            _check(lib.tt_session_add_plugin_dir(self._ptr, _path(d, "plugin_path")))
        _check(lib.tt_session_load_scene(self._ptr, scene_b), filename=scene_b)
        if resolution is not None:
            _check(lib.tt_scene_set_resolution(lib.tt_session_scene(self._ptr), w, h),
                   "resolution")
        if camera_time is not None:
            _check(lib.tt_session_set_camera_time(self._ptr, camera_time, frame_interval),
                   "camera_time")
        if seed is not None:
            lib.tt_session_set_seed(self._ptr, seed)
        for p in plugins:
            self.load_plugin(p)
        for key, value in (params or {}).items():
            self.set(key, value)

    # close() frees the session: plugins are unloaded; arrays and Tuning results returned
    # before stay valid
    _what = "session"
    _free = staticmethod(lambda p: lib.tt_session_destroy(p))

    @staticmethod
    def _aov_mask(aovs):
        mask = 0
        for a in _names(aovs, "aovs"):
            if a not in AOVS:
                raise InvalidArgumentError(_ERR_ARG, f"AOV \"{a}\": expected one of "
                                           f"{', '.join(AOVS)}")
            mask |= AOVS[a][0]
        return mask

    # -- set-up --
    def load_plugin(self, name):
        """Loads a plugin by name or path; returns its description (name, kind, version)."""
        p = ctypes.c_void_p()
        _check(lib.tt_session_load_plugin(self._p, _path(name, "plugin"), ctypes.byref(p)),
               f"plugin \"{name}\"")
        return _plugin_info(lib.tt_loaded_plugin_entry(p), text(lib.tt_loaded_plugin_path(p)))

    @property
    def plugins(self):
        """The loaded plugins in load order (the defaults appear once the session started)."""
        reg = lib.tt_session_registry(self._p)
        out = []
        for i in range(lib.tt_registry_count(reg)):
            p = lib.tt_registry_get(reg, i)
            out.append(_plugin_info(lib.tt_loaded_plugin_entry(p), text(lib.tt_loaded_plugin_path(p))))
        return out

    def _loaded(self, name):
        p = lib.tt_registry_find_name(lib.tt_session_registry(self._p), _b(name, "plugin"))
        if not p:
            loaded = ", ".join(x["name"] for x in self.plugins)
            raise UnknownNameError(_ERR_ARG, f"no plugin \"{name}\" is loaded (loaded: "
                                   f"{loaded})")
        return p

    def _load_on_demand(self, name):
        """Loads plugin `name` for set() and tune() when the session has not started and no
        plugin of that name is loaded (the host loads its default accel and integrator the
        same way before --set); a name that is no plugin file is left to the caller's
        error."""
        if lib.tt_session_started(self._p) or lib.tt_registry_find_name(
                lib.tt_session_registry(self._p), _b(name, "plugin")):
            return
        try:
            self.load_plugin(name)
        except NotFoundError:
            pass

    def _knows_key(self, plugin, key):
        """True when `key` is a parameter or an option of the loaded plugin."""
        p = lib.tt_registry_find_name(lib.tt_session_registry(self._p), _b(plugin))
        if not p:
            return False
        space = lib.tt_loaded_plugin_space(p)
        if space and lib.tt_space_find(space, _b(key)) >= 0:
            return True
        oi = lib.tt_session_plugin_options(p)
        return bool(oi and oi.contents.get(_b(key)) is not None)

    def describe(self, name):
        """Space and options of a loaded plugin (as host --describe)."""
        return _describe_loaded(self._loaded(name))

    def set(self, key, value, value2=None):
        """Sets a parameter or option: set("plugin.param", v) or set("plugin", "param", v).
        A plugin that is not loaded yet is loaded by name while the session has not started.
        Raises UnknownNameError (a KeyError) for an unknown plugin or key and
        InvalidArgumentError (a ValueError) for a bad value, with the library's message."""
        if value2 is None:
            plugin, dot, param = str(key).partition(".")
            if not dot:
                raise InvalidArgumentError(_ERR_ARG, f"set({key!r}, ...): expected "
                                           "\"plugin.param\"")
        else:
            plugin, param, value = key, value, value2
        what = f"{plugin}.{param}={_value_text(value)}"
        raw = (_b(plugin, "plugin"), _b(param, "parameter"), _b(_value_text(value), what))
        self._load_on_demand(plugin)
        st = lib.tt_session_set(self._p, *raw)
        if st < 0:  # the message first: the look-ups below may record errors of their own
            msg = _last_error_text(st)
            raise _make_error(st, f"{what}: {msg}",
                              cls=None if self._knows_key(plugin, param) else UnknownNameError)

    def config(self, plugin):
        """The plugin's configuration as a dict (parameter -> value)."""
        cfg = lib.tt_session_config(self._p, _b(plugin))
        if not cfg:
            self._loaded(plugin)
            return {}
        return json.loads(_lib.take_string(lib.tt_config_to_json(cfg)))

    # -- rendering --
    def start(self, aovs=None):
        """Loads the default accel and integrator, checks the configurations, builds the accel
        and creates the film (render() does this on first use)."""
        if aovs is not None:
            self._aovs = self._aov_mask(aovs)
        if not lib.tt_session_started(self._p):
            _check(lib.tt_session_start(self._p, self._aovs))

    @property
    def resolution(self):
        """The image size (width, height) the session renders."""
        c = lib.tt_session_camera(self._p).contents
        return c.width, c.height

    def render(self, spp=1, pass_spp=1):
        """Renders `spp` more samples per pixel in passes of `pass_spp` (host renders passes
        of 1) and returns the accumulated image, float32 (height, width, 3)."""
        spp, pass_spp = _limited("spp", spp, "spp"), _limited("spp", pass_spp, "pass_spp")
        _sync_log_level()
        self.start()
        ps = _lib.PassStats(struct_size=ctypes.sizeof(_lib.PassStats))
        done = 0
        while done < spp:
            n = min(pass_spp, spp - done)
            _check(lib.tt_session_render_pass(self._p, n, ctypes.byref(ps)), "render")
            done += n
        return self.image()

    def image(self):
        """The film resolved to linear RGB, float32 (height, width, 3)."""
        film = self._film()
        w, h = lib.tt_film_width(film), lib.tt_film_height(film)
        out = np.empty((h, w, 3), dtype=np.float32)
        lib.tt_film_resolve(film, out.ctypes.data_as(ctypes.POINTER(ctypes.c_float)))
        return out

    def _film(self):
        film = lib.tt_session_film(self._p)
        if not film:
            raise InvalidArgumentError(_ERR_ARG, "the session has not rendered yet (call "
                                       "render() or start())")
        return film

    def aov(self, name):
        """An AOV plane of the last pass (first hit): depth (h, w), normal and albedo
        (h, w, 3), motion (h, w, 2) in pixels from this frame to the previous one."""
        if name not in AOVS:
            raise InvalidArgumentError(_ERR_ARG, f"AOV \"{name}\": expected one of "
                                       f"{', '.join(AOVS)}")
        film = self._film()
        bit, ch = AOVS[name]
        ptr = lib.tt_film_aov_const(film, bit)
        if not ptr:
            have = [a for a, (b, _) in AOVS.items() if lib.tt_film_aov_mask(film) & b]
            raise InvalidArgumentError(_ERR_ARG, f"AOV \"{name}\" was not requested (the "
                                       f"session keeps: {', '.join(have) or 'none'}; pass "
                                       "aovs=[...] to Session)")
        w, h = lib.tt_film_width(film), lib.tt_film_height(film)
        a = np.ctypeslib.as_array(ptr, shape=(w * h * ch,)).copy()
        return a.reshape(h, w) if ch == 1 else a.reshape(h, w, ch)

    def reset(self):
        """Clears the film and the integrator's state; the next render starts from 0 spp."""
        if lib.tt_session_started(self._p):
            lib.tt_session_reset(self._p)

    @property
    def stats(self):
        """What the passes and builds measured: passes, spp, render_ms, rays, samples,
        nonfinite, build_ms, seed, metrics (mean per pass)."""
        st = _lib.SessionStats(struct_size=ctypes.sizeof(_lib.SessionStats))
        lib.tt_session_get_stats(self._p, ctypes.byref(st))
        lp = st.last_pass
        metrics = {text(lp.metrics[m].name): st.metric_sums[m] / st.passes
                   for m in range(min(lp.metric_count, _lib.TT_MAX_METRICS))
                   if lp.metrics[m].name and st.passes}
        return {"passes": st.passes, "spp": st.spp, "render_ms": st.render_ms,
                "rays": st.rays, "samples": st.samples, "nonfinite": st.nonfinite,
                "build_ms": st.build_ms, "seed": st.seed, "metrics": metrics}

    # -- tuning --
    def tune(self, target=None, tuner=None, iterations=50, objective=None, params=None,
             spp=1, db=None, seed=None, warmup_passes=1, time_budget=0.0, verify=0):
        """Tunes the plugin `target` online (thesis Fig. 3.2): the default configuration is
        measured first, then the tuner plugin `tuner` (None: random exploration) proposes
        `iterations` configurations, each applied and rendered for one pass of `spp` (the
        passes accumulate into the image). The plan is the library's, as host's: `target`
        None: an integrator with a tuning hint (PSSMLT), else the accel; the hint's setup
        applies, the values set() put back on top; `objective` None: the hint's, else
        "render"; `params` (a name or a list): the parameters searched (None: the hint's
        list, else all). A target or tuner not loaded yet is loaded by name when the session
        has not started. `db`: a TuningDB or a path; None: the per-user database as host
        uses it ($XDG_DATA_HOME/tunetrace/tuning.db; one that cannot be opened is logged
        and tuning goes on without); False: none. Afterwards the target runs the best
        configuration. `verify` > 0 measures default and best side by side that many rounds.
        Returns a Tuning with the history."""
        iterations = _limited("iterations", iterations, "iterations")
        spp = _limited("tune_spp", spp, "spp")
        seed = None if seed is None else _limited("seed", seed, "seed")
        warmup_passes = _limited("warmup", warmup_passes, "warmup_passes")
        time_budget = _number(time_budget, "time_budget")
        time_budget = _limited_real("time", time_budget, "time_budget") if time_budget else 0.0
        verify = _limited("verify", verify, "verify") if verify else 0
        params = None if params is None else _names(params, "params")
        for name in (target, tuner):
            if name is not None:
                self._load_on_demand(name)
        _sync_log_level()
        self.start()
        tuner_p = None
        if tuner is not None:
            tuner_p = lib.tt_registry_find_name(lib.tt_session_registry(self._p),
                                                _b(tuner, "tuner"))
            if not tuner_p:
                raise UnknownNameError(_ERR_ARG, f"tuner \"{tuner}\" is not loaded, and the "
                                       "session has started: pass plugins=[\"{tuner}\", ...] "
                                       "to Session or tune before the first render")
        plan = _lib.TuningPlan(struct_size=ctypes.sizeof(_lib.TuningPlan))
        names = None
        if params is not None:
            names = (ctypes.c_char_p * max(1, len(params)))(
                *[_b(p, "tune(params)") for p in params])
        st = lib.tt_session_tuning_plan(self._p, _b(target, "tune(target)"), names,
                                        len(params or ()), ctypes.byref(plan))
        if st < 0:
            msg = _last_error_text(st)
            unknown = target is not None and not lib.tt_registry_find_name(
                lib.tt_session_registry(self._p), _b(target))
            raise _make_error(st, f"tune: {msg}", cls=UnknownNameError if unknown else None)
        try:
            entry = lib.tt_loaded_plugin_entry(plan.target).contents
            current = lib.tt_session_config_at(self._p, plan.target_index)
            if objective is None:
                objective = text(plan.objective)
            with self._tuning_db(db) as tdb:
                return self._run_tuning(plan.target_index, entry, plan.space, current,
                                        plan.search, objective, tuner_p, iterations, spp,
                                        tdb, seed, warmup_passes, time_budget, verify)
        finally:
            lib.tt_tuning_plan_release(ctypes.byref(plan))

    @staticmethod
    def _tuning_db(db):
        """The database of a tuning run as a context (None inside for no database): host's
        rule, see tune(). A database this opened is closed afterwards."""
        if db is False:
            return contextlib.nullcontext(None)
        if isinstance(db, TuningDB):
            if db.read_only:
                raise InvalidArgumentError(_ERR_ARG, f"tune: the tuning database {db.path} was "
                                           "opened read-only: TuningDB(path, write=True), or "
                                           "give the path")
            return contextlib.nullcontext(db)
        if db is not None:
            return TuningDB(db, write=True)
        path = _lib.take_string(lib.tt_tunedb_default_path())
        if path is None:
            _log.warning("tuning: no $XDG_DATA_HOME or $HOME: tuning without a database "
                         "(pass db=PATH)")
            return contextlib.nullcontext(None)
        try:
            return TuningDB(path, write=True)
        except Error as e:
            _log.warning("tuning: %s; tuning without a database", e)
            return contextlib.nullcontext(None)

    def _run_tuning(self, index, entry, space, current, subset, objective, tuner_p, iterations,
                    spp, db, seed, warmup_passes, time_budget, verify):
        state = _lib.TuningState()
        _check(lib.tt_session_tuning_state(self._p, index, spp, None, None, db is not None,
                                           ctypes.byref(state)), "tuning state")
        target = _lib.TuningTarget()
        want_images = objective.startswith("rrmse")
        _check(lib.tt_session_tuning_target(self._p, index, want_images, ctypes.byref(target)),
               "tuning target")
        w, h = self.resolution
        d = _lib.TuningDesc(struct_size=ctypes.sizeof(_lib.TuningDesc))
        d.host = lib.tt_default_host()
        d.space, d.start, d.search = space, current, subset
        d.objective = _b(objective)
        if tuner_p:
            d.tuner = lib.tt_loaded_plugin_iface(tuner_p)
            tentry = lib.tt_loaded_plugin_entry(tuner_p).contents
            d.tuner_settings = lib.tt_session_config_at(
                self._p, lib.tt_session_plugin_index(self._p, tentry.name))
            d.tuner_name = tentry.name
        d.seed = seed if seed is not None else self.stats["seed"]
        d.iterations, d.spp, d.warmup_passes = iterations, spp, warmup_passes
        d.time_budget_s = time_budget
        d.plugin, d.plugin_version = entry.name, entry.version
        d.db = db._ptr if db is not None else None
        d.state = ctypes.pointer(state)
        d.width, d.height = w, h
        t = ctypes.c_void_p()
        _check(lib.tt_tuning_create(ctypes.byref(d), ctypes.byref(t)), "tuning")
        try:
            return self._drive(t, target, current, objective, db, verify)
        finally:
            lib.tt_tuning_destroy(t)

    def _drive(self, t, target, current, objective, db, verify):
        verification = None
        st = lib.tt_tuning_run(t, ctypes.byref(target))
        if st == _ERR_NO_DATA:  # the objective's metric is not published
            _check(st, f"objective {objective}")
        interrupted = st == _ERR_INTERRUPTED
        if st < 0 and not interrupted:
            _check(st, "tuning")
        if verify and not interrupted:
            v = _lib.TuningVerification(struct_size=ctypes.sizeof(_lib.TuningVerification))
            vst = lib.tt_tuning_verify(t, ctypes.byref(target), verify, ctypes.byref(v))
            if vst < 0 and vst != _ERR_INTERRUPTED:
                _check(vst, "verify")
            verification = {
                "rounds": v.rounds, "render_ratio": v.render_ratio, "total_ratio": v.total_ratio,
                "cost_ratio": v.cost_ratio, "median_render_ms": list(v.median_render_ms),
                "median_total_ms": list(v.median_total_ms), "median_cost": list(v.median_cost),
                # the library keeps the default when the best was not faster side by side
                "kept": "best" if v.verdict != 2 else "default",
                "reason": text(v.reason) if v.reason else None}
        # keep the kept configuration (the best, or the default verification chose): the
        # rest of the image renders with it (as host does)
        _check(lib.tt_config_from_json(current, lib.tt_tuning_kept_json(t), b"tuning"), "best")
        if not interrupted:
            _check(lib.tt_tuning_apply_best(t, ctypes.byref(target), None), "apply best")
        tuning = Tuning(t, db)
        tuning.verification = verification
        if tuning.stats.get("unrecorded"):
            warnings.warn(f"tuning: {tuning.stats['unrecorded']} of {tuning.stats['measured']} "
                          f"measurements could not be recorded in the database {tuning.db_path}")
        return tuning


class Tuning:
    """The result of Session.tune, read from the library's tuning session once it finished:
    history (every sample in order: dicts {iteration (-1: the default), config (dict), cost,
    build_ms, render_ms, status ("ok", "infeasible", "failed"), cached (answered by the
    database)}), best_config / best_cost (lowest mean cost over repeats), default_config /
    default_cost, mode ("tune" or "explore"), stats (requested, iterations, measured,
    cached, infeasible, failed, converged, interrupted, tuning_ms, unrecorded: rows the
    database failed to record, a warning is issued), verification (with
    verify > 0), db_path."""

    def __init__(self, ptr, db):
        self.history = []
        for i in range(lib.tt_tuning_sample_count(ptr)):
            s = lib.tt_tuning_sample_at(ptr, i).contents
            self.history.append({
                "iteration": s.iteration, "config": json.loads(text(s.config)), "cost": s.cost,
                "build_ms": s.build_ms, "render_ms": s.render_ms,
                "status": _STATUS_NAMES.get(s.status, str(s.status)), "cached": bool(s.cached)})
        self.best_config = json.loads(text(lib.tt_tuning_best_json(ptr)))
        self.default_config = json.loads(text(lib.tt_tuning_default_json(ptr)))
        c = ctypes.c_double(COST_INFEASIBLE)
        lib.tt_tuning_best(ptr, None, ctypes.byref(c))
        self.best_cost = c.value
        c = ctypes.c_double(COST_INFEASIBLE)
        lib.tt_tuning_default_cost(ptr, ctypes.byref(c))
        self.default_cost = c.value
        self.mode = text(lib.tt_tuning_mode(ptr))
        st = _lib.TuningStats(struct_size=ctypes.sizeof(_lib.TuningStats))
        lib.tt_tuning_get_stats(ptr, ctypes.byref(st))
        self.stats = {f: getattr(st, f) for f, _ in _lib.TuningStats._fields_ if f != "struct_size"}
        self.db_path = db.path if db is not None else None
        self.verification = None

    def __repr__(self):
        return (f"<tunetrace.Tuning {self.mode}: {len(self.history)} samples, best cost "
                f"{self.best_cost:.6g}, default {self.default_cost:.6g}>")


class TuningDB(_Handle):
    """The tuning database (tunetrace/tunedb.h): one SQLite file of every measured (state,
    configuration) pair. TuningDB() opens the default one ($XDG_DATA_HOME/tunetrace/
    tuning.db); rows() reads it through the library, so the schema is the library's.
    TuningDB(path) reads an existing database and changes nothing in the file;
    TuningDB(path, write=True) also records into it (created if missing), as tune(db=...)
    does."""

    _what = "database"
    _free = staticmethod(lambda p: lib.tt_tunedb_close(p))

    def __init__(self, path=None, write=False):
        """Opens a database: `path`, or None for the per-user one. Without `write` it is read
        and nothing in the file changes; a file that does not exist raises NotFoundError (a
        FileNotFoundError) and none is created. write=True also records into it, creating
        it (and its folder) if missing, as tune(db=...) does."""
        if path is None:
            path = _lib.take_string(lib.tt_tunedb_default_path())
            if path is None:
                raise InvalidArgumentError(_ERR_ARG, "no $XDG_DATA_HOME or $HOME: give the "
                                           "database a path")
        raw = _path(path, "TuningDB")
        if not write and not os.path.exists(raw):
            raise _make_error(STATUS["TT_ERR_IO"], f"{os.fsdecode(raw)}: no such tuning "
                              "database (Session.tune(db=...) creates one)", raw, NotFoundError)
        ptr = ctypes.c_void_p()
        opener = lib.tt_tunedb_open if write else lib.tt_tunedb_open_readonly
        _check(opener(raw, ctypes.byref(ptr)), filename=raw)
        self._ptr = ptr

    @property
    def read_only(self):
        """True when opened without write=True."""
        return bool(lib.tt_tunedb_read_only(self._p))

    @property
    def bad_rows(self):
        """Rows the last rows() or export_csv() skipped: not rows of the schema."""
        return lib.tt_tunedb_bad_rows(self._p)

    @property
    def path(self):
        """The database file."""
        return text(lib.tt_tunedb_path(self._p))

    def count(self, plugin=None):
        """Rows (of `plugin`, or all)."""
        n = ctypes.c_uint64()
        _check(lib.tt_tunedb_count(self._p, _b(plugin, "plugin"), ctypes.byref(n)), "count")
        return n.value

    def __len__(self):
        return self.count()

    def rows(self, plugin=None):
        """Every row (of `plugin`, or all) in insertion order as dicts; camera, context,
        config and metrics are parsed JSON, indicators a list in the order of INDICATORS
        (None when unknown)."""
        out = []

        def one(_user, rp):
            r = rp.contents
            row = {}
            for f, _ in _lib.TunedbRow._fields_:
                if f == "struct_size":
                    continue
                v = getattr(r, f)
                if isinstance(v, bytes):
                    v = v.decode()
                row[f] = v
            for f in ("camera", "context", "config", "metrics"):
                if row[f]:
                    row[f] = json.loads(row[f])
            row["indicators"] = list(r.indicators) if r.has_indicators else None
            del row["has_indicators"]
            row["rank"] = r.rank if r.has_rank else None  # the MPI rank (host-mpi rows)
            del row["has_rank"]
            row["status"] = _STATUS_NAMES.get(r.status, str(r.status))
            out.append(row)
            return 0
        _check(lib.tt_tunedb_foreach(self._p, _b(plugin, "plugin"), _lib.ROW_FN(one), None),
               "rows")
        return out

    def export_csv(self, path):
        """Writes every row to a CSV file (the columns of host --export-csv)."""
        _check(lib.tt_tunedb_export_csv(self._p, _path(path, "export_csv")), "export")
