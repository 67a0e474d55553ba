"""ctypes bindings of libtunetrace: finding the library, the C structs, the prototypes.

Internal: the public API is in tunetrace/__init__.py. Structs mirror the public headers
field by field (core/include/tunetrace/*.h); python/tests/python_abi.c prints the C layout and the
suite compares it with these (python/tests/python_api.py), so a header change that is not made
here too fails a test instead of corrupting memory.

The library is looked for, in order:
  1. $TT_LIBRARY: the path of libtunetrace.so.1 (or of the folder holding it);
  2. where the build put this package: the build tree's build/core/ (build/python is the
     package as the build tree has it), or, for an installed package, the library folder of
     the same installation prefix (paths relative to the package, so a --destdir staging
     copy or a moved prefix works), or, for a package `pip install ./python` built, the
     folder pkg-config named then;
  3. `pkg-config --variable=libdir tunetrace` (an install whose .pc is on PKG_CONFIG_PATH);
  4. the dynamic loader's own search (LD_LIBRARY_PATH, the ld.so cache): libtunetrace.so.1.
"""
import ctypes
import ctypes.util
import os
import subprocess

SONAME = "libtunetrace.so.1"

try:  # written by meson into the build tree's and the installed package (python/meson.build)
    from . import _paths
except ImportError:  # the source tree's python/ folder: no build to point at
    _paths = None


def _candidates():
    env = os.environ.get("TT_LIBRARY")
    if env:
        yield "$TT_LIBRARY", os.path.join(env, SONAME) if os.path.isdir(env) else env
        return  # an explicit choice is never silently replaced by another library
    here = os.path.dirname(os.path.abspath(__file__))
    if _paths is not None:
        if getattr(_paths, "BUILD_LIBRARY", None):
            yield "the build tree", _paths.BUILD_LIBRARY
        if getattr(_paths, "PACKAGE_TO_LIBDIR", None):
            yield "the installation prefix", os.path.normpath(
                os.path.join(here, _paths.PACKAGE_TO_LIBDIR, SONAME))
        if getattr(_paths, "LIBDIR", None):
            yield "pkg-config when the package was built", os.path.join(_paths.LIBDIR, SONAME)
    try:
        out = subprocess.run(["pkg-config", "--variable=libdir", "tunetrace"],
                             capture_output=True, text=True, timeout=10)
        if out.returncode == 0 and out.stdout.strip():
            yield "pkg-config", os.path.join(out.stdout.strip(), SONAME)
    except (OSError, subprocess.SubprocessError):
        pass
    yield "the dynamic loader's search path", ctypes.util.find_library("tunetrace") or SONAME


def _load():
    tried = []
    for where, path in _candidates():
        if os.sep in path and not os.path.exists(path):
            tried.append(f"{path} ({where}: no such file)")
            continue
        try:
            return ctypes.CDLL(path), path
        except OSError as e:
            tried.append(f"{path} ({where}: {e})")
    raise ImportError("tunetrace: cannot load libtunetrace; tried: " + "; ".join(tried) +
                      ". Set $TT_LIBRARY to the path of " + SONAME)


lib, LIBRARY_PATH = _load()

# ---- structs (field order and types exactly as in the headers) ----------------------

c_u8p = ctypes.c_char_p
c_vp = ctypes.c_void_p
TT_MAX_METRICS = 16
TT_SCENE_INDICATOR_COUNT = 17


class Plugin(ctypes.Structure):  # tt_plugin (plugin.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("abi_major", ctypes.c_uint16),
                ("abi_minor", ctypes.c_uint16), ("kind", ctypes.c_uint32),
                ("name", c_u8p), ("version", c_u8p), ("description", c_u8p),
                ("init", c_vp), ("deinit", c_vp), ("get_interface", c_vp)]


class Camera(ctypes.Structure):  # tt_camera (scene.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("position", ctypes.c_float * 3),
                ("target", ctypes.c_float * 3), ("up", ctypes.c_float * 3),
                ("fov_y", ctypes.c_float), ("width", ctypes.c_uint32),
                ("height", ctypes.c_uint32), ("key_count", ctypes.c_uint32), ("keys", c_vp)]


class Metric(ctypes.Structure):  # tt_metric (integrator.h)
    _fields_ = [("name", c_u8p), ("value", ctypes.c_double)]


class PassStats(ctypes.Structure):  # tt_pass_stats (integrator.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("time_ms", ctypes.c_double),
                ("rays", ctypes.c_uint64), ("samples", ctypes.c_uint64),
                ("nonfinite", ctypes.c_uint64), ("metric_count", ctypes.c_uint32),
                ("metrics", Metric * TT_MAX_METRICS)]


class AccelBuildStats(ctypes.Structure):  # tt_accel_build_stats (accel.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("build_ms", ctypes.c_double),
                ("memory_bytes", ctypes.c_uint64), ("nodes", ctypes.c_uint64),
                ("leaves", ctypes.c_uint64), ("sah_cost", ctypes.c_double),
                ("max_depth", ctypes.c_uint32), ("repaired", ctypes.c_int32)]


class SessionStats(ctypes.Structure):  # tt_session_stats (session.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("passes", ctypes.c_uint32),
                ("spp", ctypes.c_uint32), ("total_spp", ctypes.c_uint64),
                ("render_ms", ctypes.c_double), ("rays", ctypes.c_uint64),
                ("samples", ctypes.c_uint64), ("nonfinite", ctypes.c_uint64),
                ("build_ms", ctypes.c_double), ("build", AccelBuildStats),
                ("last_pass", PassStats), ("metric_sums", ctypes.c_double * TT_MAX_METRICS),
                ("seed", ctypes.c_uint64)]


class TuningState(ctypes.Structure):  # tt_tuning_state (tuning.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("scene_id", c_u8p), ("scene", c_u8p),
                ("camera", c_u8p), ("context", c_u8p), ("has_indicators", ctypes.c_int32),
                ("indicators", ctypes.c_double * TT_SCENE_INDICATOR_COUNT)]


class TuningSample(ctypes.Structure):  # tt_tuning_sample (tuning.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("iteration", ctypes.c_int32),
                ("config", c_u8p), ("cost", ctypes.c_double), ("build_ms", ctypes.c_double),
                ("render_ms", ctypes.c_double), ("status", ctypes.c_int32),
                ("cached", ctypes.c_int32), ("image", ctypes.POINTER(ctypes.c_float))]


class TuningMeasurement(ctypes.Structure):  # tt_tuning_measurement (tuning.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("status", ctypes.c_int),
                ("build_ms", ctypes.c_double), ("render_ms", ctypes.c_double),
                ("pass_", ctypes.POINTER(PassStats)), ("image", ctypes.POINTER(ctypes.c_float))]


APPLY_FN = ctypes.CFUNCTYPE(ctypes.c_int, c_vp, c_vp, ctypes.POINTER(ctypes.c_double))
RENDER_FN = ctypes.CFUNCTYPE(ctypes.c_int, c_vp, ctypes.c_uint32,
                             ctypes.POINTER(TuningMeasurement))
ON_SAMPLE_FN = ctypes.CFUNCTYPE(None, c_vp, ctypes.POINTER(TuningSample))


class TuningTarget(ctypes.Structure):  # tt_tuning_target (tuning.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("user", c_vp), ("apply", c_vp),
                ("render", c_vp)]


class TuningDesc(ctypes.Structure):  # tt_tuning_desc (tuning.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("host", c_vp), ("space", c_vp),
                ("start", c_vp), ("search", c_vp), ("objective", c_u8p), ("tuner", c_vp),
                ("tuner_settings", c_vp), ("tuner_name", c_u8p), ("seed", ctypes.c_uint64),
                ("iterations", ctypes.c_uint32), ("spp", ctypes.c_uint32),
                ("warmup_passes", ctypes.c_uint32), ("time_budget_s", ctypes.c_double),
                ("plugin", c_u8p), ("plugin_version", c_u8p), ("db", c_vp),
                ("state", ctypes.POINTER(TuningState)), ("run_id", c_u8p),
                ("width", ctypes.c_uint32), ("height", ctypes.c_uint32),
                ("reference_luminance", ctypes.POINTER(ctypes.c_double)),
                ("want_images", ctypes.c_int32), ("on_sample", ON_SAMPLE_FN), ("user", c_vp),
                ("mode", c_u8p)]  # appended for the hybrid loop


class TuningStats(ctypes.Structure):  # tt_tuning_stats (tuning.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("requested", ctypes.c_uint32),
                ("iterations", ctypes.c_uint32), ("measured", ctypes.c_uint32),
                ("cached", ctypes.c_uint32), ("infeasible", ctypes.c_uint32),
                ("failed", ctypes.c_uint32), ("converged", ctypes.c_int32),
                ("interrupted", ctypes.c_int32), ("tuning_ms", ctypes.c_double),
                ("unrecorded", ctypes.c_uint32), ("remeasured", ctypes.c_uint32)]


class TuningVerification(ctypes.Structure):  # tt_tuning_verification (tuning.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("rounds", ctypes.c_uint32),
                ("spp", ctypes.c_uint32), ("median_build_ms", ctypes.c_double * 2),
                ("median_render_ms", ctypes.c_double * 2),
                ("median_total_ms", ctypes.c_double * 2), ("median_cost", ctypes.c_double * 2),
                ("render_ratio", ctypes.c_double), ("total_ratio", ctypes.c_double),
                ("cost_ratio", ctypes.c_double), ("rounds_ms", ctypes.POINTER(ctypes.c_double)),
                ("verdict", ctypes.c_int32), ("best_faster", ctypes.c_uint32),
                ("cost_difference", ctypes.c_double), ("reason", c_u8p)]


class TunedbRow(ctypes.Structure):  # tt_tunedb_row (tunedb.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("id", ctypes.c_int64),
                ("scene_id", c_u8p), ("scene", c_u8p), ("camera", c_u8p), ("context", c_u8p),
                ("has_indicators", ctypes.c_int32),
                ("indicators", ctypes.c_double * TT_SCENE_INDICATOR_COUNT),
                ("plugin", c_u8p), ("plugin_version", c_u8p), ("config", c_u8p),
                ("objective", c_u8p), ("build_ms", ctypes.c_double),
                ("render_ms", ctypes.c_double), ("cost", ctypes.c_double),
                ("status", ctypes.c_int32), ("mode", c_u8p), ("iteration", ctypes.c_int32),
                ("run_id", c_u8p), ("tuner", c_u8p), ("metrics", c_u8p), ("machine", c_u8p),
                ("cpu", c_u8p), ("timestamp", c_u8p), ("host", c_u8p),
                ("has_rank", ctypes.c_int32), ("rank", ctypes.c_int32)]


class TuningHint(ctypes.Structure):  # tt_tuning_hint (tuning_hint.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("objective", c_u8p),
                ("tunable", ctypes.POINTER(c_u8p)), ("setup", c_u8p)]


class TuningPlan(ctypes.Structure):  # tt_tuning_plan (session.h)
    _fields_ = [("struct_size", ctypes.c_uint32), ("target_index", ctypes.c_size_t),
                ("target", c_vp), ("space", c_vp), ("search", c_vp), ("objective", c_u8p)]


class OptionInfo(ctypes.Structure):  # tt_option_info (options.h)
    _fields_ = [("key", c_u8p), ("description", c_u8p)]


class OptionsIface(ctypes.Structure):  # tt_options_iface (options.h)
    _fields_ = [("struct_size", ctypes.c_uint32),
                ("count", ctypes.CFUNCTYPE(ctypes.c_uint32)),
                ("info", ctypes.CFUNCTYPE(ctypes.POINTER(OptionInfo), ctypes.c_uint32)),
                ("set", ctypes.CFUNCTYPE(ctypes.c_int, c_u8p, c_u8p)),
                ("get", ctypes.CFUNCTYPE(c_u8p, c_u8p))]


# Structs whose layout python/tests/python_abi.c reports: C name -> ctypes class.
LAYOUTS = {
    "tt_plugin": Plugin, "tt_camera": Camera, "tt_pass_stats": PassStats,
    "tt_accel_build_stats": AccelBuildStats, "tt_session_stats": SessionStats,
    "tt_tuning_state": TuningState, "tt_tuning_sample": TuningSample,
    "tt_tuning_measurement": TuningMeasurement, "tt_tuning_target": TuningTarget,
    "tt_tuning_desc": TuningDesc, "tt_tuning_stats": TuningStats,
    "tt_tuning_verification": TuningVerification, "tt_tunedb_row": TunedbRow,
    "tt_tuning_hint": TuningHint, "tt_tuning_plan": TuningPlan, "tt_option_info": OptionInfo,
    "tt_options_iface": OptionsIface,
}

# ---- prototypes ---------------------------------------------------------------------

LIST_FN = ctypes.CFUNCTYPE(None, c_vp, ctypes.c_char_p)
ROW_FN = ctypes.CFUNCTYPE(ctypes.c_int, c_vp, ctypes.POINTER(TunedbRow))
ERROR_FN = ctypes.CFUNCTYPE(None, c_vp, ctypes.c_int, ctypes.c_char_p)
LOG_FN = ctypes.CFUNCTYPE(None, c_vp, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p)

_I, _U32, _U64, _D, _S, _P = (ctypes.c_int, ctypes.c_uint32, ctypes.c_uint64, ctypes.c_double,
                              ctypes.c_char_p, ctypes.c_void_p)
_PP = ctypes.POINTER(ctypes.c_void_p)
_PD = ctypes.POINTER(ctypes.c_double)
_PF = ctypes.POINTER(ctypes.c_float)

_PROTOTYPES = {
    # common.h
    "tt_version": (_S, []), "tt_last_error": (_S, []), "tt_clear_error": (None, []),
    "tt_status_string": (_S, [_I]), "tt_status_name": (_S, [_I]), "tt_free": (None, [_P]),
    # host.h
    "tt_default_host": (_P, []), "tt_default_host_set_threads": (_I, [_U32]),
    "tt_default_host_request_stop": (None, []), "tt_default_host_hold_stop": (None, [_I]),
    "tt_default_host_set_log_level": (None, [_I]),
    "tt_default_host_set_log_callback": (None, [LOG_FN, _P]),
    # plugin.h, loader.h
    "tt_plugin_kind_name": (_S, [_U32]),
    "tt_registry_create": (_P, [_P]), "tt_registry_destroy": (None, [_P]),
    "tt_registry_add_dir": (_I, [_P, _S]), "tt_registry_search_path": (_S, [_P]),
    "tt_registry_load": (_I, [_P, _S, _PP]),
    "tt_registry_probe": (_I, [_P, _S, ctypes.POINTER(Plugin)]),
    "tt_registry_list_files": (None, [_P, LIST_FN, _P]),
    "tt_registry_count": (ctypes.c_size_t, [_P]),
    "tt_registry_get": (_P, [_P, ctypes.c_size_t]),
    "tt_registry_find_name": (_P, [_P, _S]),
    "tt_loaded_plugin_entry": (ctypes.POINTER(Plugin), [_P]),
    "tt_loaded_plugin_path": (_S, [_P]),
    "tt_loaded_plugin_iface": (_P, [_P]),
    "tt_loaded_plugin_get": (_P, [_P, _S]),
    "tt_loaded_plugin_space": (_P, [_P]),
    # params.h
    "tt_space_to_json": (_P, [_P]), "tt_space_count": (ctypes.c_size_t, [_P]),
    "tt_space_find": (_I, [_P, _S]),
    "tt_space_destroy": (None, [_P]),
    "tt_space_subset": (_P, [_P, ctypes.POINTER(_S), ctypes.c_size_t, _P]),
    "tt_config_to_json": (_P, [_P]), "tt_config_from_json": (_I, [_P, _S, _S]),
    "tt_config_create": (_P, [_P]), "tt_config_destroy": (None, [_P]),
    # film.h, image.h
    "tt_film_width": (_U32, [_P]), "tt_film_height": (_U32, [_P]),
    "tt_film_aov_mask": (_U32, [_P]), "tt_film_resolve": (None, [_P, _PF]),
    "tt_film_aov_const": (_PF, [_P, _I]), "tt_aov_channels": (_U32, [_I]),
    "tt_image_read": (_I, [_S, ctypes.POINTER(_U32), ctypes.POINTER(_U32),
                           ctypes.POINTER(_U32), ctypes.POINTER(_PF)]),
    "tt_image_write_exr": (_I, [_S, _U32, _U32, _U32, _PF, ctypes.POINTER(_S), _P,
                                ctypes.c_size_t]),
    # scene.h
    "tt_scene_set_resolution": (_I, [_P, _U32, _U32]), "tt_scene_source": (_S, [_P]),
    "tt_scene_id": (_S, [_P]), "tt_scene_triangle_count": (_U64, [_P]),
    "tt_scene_indicator_name": (_S, [_U32]),
    # session.h
    "tt_session_create": (_I, [_P, _PP]), "tt_session_destroy": (None, [_P]),
    "tt_session_add_plugin_dir": (_I, [_P, _S]), "tt_session_load_scene": (_I, [_P, _S]),
    "tt_session_scene": (_P, [_P]),
    "tt_session_set_camera_time": (_I, [_P, _D, _D]),
    "tt_session_camera": (ctypes.POINTER(Camera), [_P]),
    "tt_session_load_plugin": (_I, [_P, _S, _PP]),
    "tt_session_load_defaults": (_I, [_P]), "tt_session_registry": (_P, [_P]),
    "tt_session_plugin_index": (_I, [_P, _S]),
    "tt_session_config_at": (_P, [_P, ctypes.c_size_t]),
    "tt_session_config": (_P, [_P, _S]),
    "tt_session_set": (_I, [_P, _S, _S, _S]), "tt_session_check": (_I, [_P]),
    "tt_session_plugin_options": (ctypes.POINTER(OptionsIface), [_P]),
    "tt_session_start": (_I, [_P, _U32]), "tt_session_started": (_I, [_P]),
    "tt_session_accel_plugin": (_P, [_P]), "tt_session_integrator_plugin": (_P, [_P]),
    "tt_session_film": (_P, [_P]),
    "tt_session_render_pass": (_I, [_P, _U32, ctypes.POINTER(PassStats)]),
    "tt_session_reset": (None, [_P]),
    "tt_session_apply": (_I, [_P, ctypes.c_size_t, _P, _PD]),
    "tt_session_get_stats": (None, [_P, ctypes.POINTER(SessionStats)]),
    "tt_session_set_seed": (None, [_P, _U64]),
    "tt_session_tuning_target": (_I, [_P, ctypes.c_size_t, _I, ctypes.POINTER(TuningTarget)]),
    "tt_session_tuning_state": (_I, [_P, ctypes.c_size_t, _U32, _S, _S, _I,
                                     ctypes.POINTER(TuningState)]),
    "tt_session_tuning_plan": (_I, [_P, _S, ctypes.POINTER(_S), ctypes.c_size_t,
                                    ctypes.POINTER(TuningPlan)]),
    "tt_tuning_plan_release": (None, [ctypes.POINTER(TuningPlan)]),
    # tuning.h
    "tt_tuning_create": (_I, [ctypes.POINTER(TuningDesc), _PP]),
    "tt_tuning_destroy": (None, [_P]),
    "tt_tuning_run": (_I, [_P, ctypes.POINTER(TuningTarget)]),
    "tt_tuning_best": (_I, [_P, _P, _PD]),
    "tt_tuning_best_json": (_S, [_P]), "tt_tuning_default_json": (_S, [_P]),
    "tt_tuning_kept_json": (_S, [_P]),
    "tt_tuning_default_cost": (_I, [_P, _PD]),
    "tt_tuning_sample_count": (ctypes.c_size_t, [_P]),
    "tt_tuning_sample_at": (ctypes.POINTER(TuningSample), [_P, ctypes.c_size_t]),
    "tt_tuning_get_stats": (None, [_P, ctypes.POINTER(TuningStats)]),
    "tt_tuning_mode": (_S, [_P]),
    "tt_tuning_verify": (_I, [_P, ctypes.POINTER(TuningTarget), _U32,
                              ctypes.POINTER(TuningVerification)]),
    "tt_tuning_apply_best": (_I, [_P, ctypes.POINTER(TuningTarget), _PD]),
    # limits.h
    "tt_limit_find": (_I, [_S, ctypes.POINTER(_I)]),
    "tt_limit_parse_uint": (_I, [_I, _S, ctypes.POINTER(_U64)]),
    "tt_limit_parse_real": (_I, [_I, _S, _PD]),
    "tt_limit_parse_resolution": (_I, [_S, ctypes.POINTER(_U32), ctypes.POINTER(_U32)]),
    # tunedb.h
    "tt_tunedb_default_path": (_P, []), "tt_tunedb_open": (_I, [_S, _PP]),
    "tt_tunedb_close": (None, [_P]), "tt_tunedb_path": (_S, [_P]),
    "tt_tunedb_foreach": (_I, [_P, _S, ROW_FN, _P]),
    "tt_tunedb_count": (_I, [_P, _S, ctypes.POINTER(_U64)]),
    "tt_tunedb_export_csv": (_I, [_P, _S]),
    "tt_tunedb_open_readonly": (_I, [_S, _PP]), "tt_tunedb_read_only": (_I, [_P]),
    "tt_tunedb_bad_rows": (_U64, [_P]),
}

for _name, (_res, _args) in _PROTOTYPES.items():
    _f = getattr(lib, _name)
    _f.restype = _res
    _f.argtypes = _args


def take_string(ptr):
    """Decodes a char * the library allocated ("free with tt_free") and frees it."""
    if not ptr:
        return None
    try:
        return ctypes.string_at(ptr).decode()
    finally:
        lib.tt_free(ptr)


def text(b):
    """bytes from the library -> str (None stays None)."""
    return b.decode() if b is not None else None
