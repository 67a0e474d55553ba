#!/usr/bin/python3
"""The Python API (python/tunetrace) end to end, from the build tree's package:

  - the ctypes structs have the C layout (python/tests/python_abi prints it);
  - errors raise tunetrace.Error carrying the library's message (file, field, expected);
  - plugins are listed and described as host --list-plugins / --describe do;
  - the numpy image equals, bit for bit, the EXR host writes for the same scene, plugins,
    parameters and seed;
  - AOVs at known pixels of a plane facing the camera: depth = distance along the view axis,
    normal = the plane's, albedo = its reflectance, motion = 0 for a still camera and the
    camera's translation (pixels) for a camera path;
  - a tuning session: history length = 1 + iterations, the database holds one row per
    sample with the same configurations and costs, and the same session again is answered
    from the database;
  - the example script (python/examples/render_and_tune.py) runs.

    python_api.py [PYTHON_ABI_EXE]
Environment: TT_BUILD_ROOT, TT_SOURCE_ROOT (tests/meson.build)."""
import json
import os
import sqlite3
import subprocess
import sys
import tempfile

BUILD = os.environ["TT_BUILD_ROOT"]
SOURCE = os.environ["TT_SOURCE_ROOT"]
sys.path.insert(0, os.path.join(BUILD, "python"))

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tests", "support"))
from plane_scene import MOVING_PATH, motion_pixels, plane, write  # noqa: E402

import tunetrace as tt  # noqa: E402
from tunetrace import _lib  # noqa: E402

failures = 0
checks = 0


def check(cond, what):
    global failures, checks
    checks += 1
    if not cond:
        failures += 1
        print(f"FAIL: {what}", file=sys.stderr)


def raises(fn, *needles):
    """Calls fn, expects tunetrace.Error whose message contains every needle."""
    try:
        fn()
    except tt.Error as e:
        msg = str(e)
        for n in needles:
            check(n in msg, f"error message {msg!r} contains {n!r}")
        check(e.status < 0 and e.status_name, f"error has a status ({e.status}, {e.status_name})")
        return msg
    check(False, f"expected tunetrace.Error with {needles}")
    return ""


def test_layout(abi_exe):
    c = json.loads(subprocess.run([abi_exe], check=True, capture_output=True, text=True).stdout)
    for name, cls in _lib.LAYOUTS.items():
        check(name in c, f"python_abi reports {name}")
        if name not in c:
            continue
        check(c[name]["size"] == __import__("ctypes").sizeof(cls),
              f"sizeof({name}) C {c[name]['size']} vs ctypes {__import__('ctypes').sizeof(cls)}")
        fields = {f: getattr(cls, f).offset for f, _ in cls._fields_}
        check(set(fields) == set(c[name]["fields"]),
              f"{name} fields: ctypes {sorted(fields)} vs C {sorted(c[name]['fields'])}")
        for f, off in c[name]["fields"].items():
            check(fields.get(f) == off, f"offsetof({name}, {f}) C {off} vs ctypes {fields.get(f)}")
    k = c["constants"]
    check(k["TT_MAX_METRICS"] == _lib.TT_MAX_METRICS, "TT_MAX_METRICS")
    check(k["TT_SCENE_INDICATOR_COUNT"] == _lib.TT_SCENE_INDICATOR_COUNT, "indicator count")
    check(k["TT_COST_INFEASIBLE"] == tt.COST_INFEASIBLE, "TT_COST_INFEASIBLE")


def test_errors(tmp):
    check(tt.library_path().startswith(BUILD), f"loaded the build tree's library ({tt.library_path()})")
    check(tt.version().count(".") == 2, "version")
    raises(lambda: tt.Session(os.path.join(tmp, "missing.json")), "missing.json")
    bad = os.path.join(tmp, "bad.json")
    with open(bad, "w") as f:
        f.write('{"version": 1, "camera": {"position": [0, 0, 0], "target": [0, 0, 1], '
                '"fov": 200}, "meshes": []}')
    raises(lambda: tt.Session(bad), "bad.json", "camera.fov", "(0, 180)")
    box = os.path.join(SOURCE, "scenes/cornell-box/scene.json")
    raises(lambda: tt.Session(box, plugins=["integrator_nope"]), "integrator_nope")
    with tt.Session(box, plugins=["integrator_pt"]) as s:
        raises(lambda: s.set("accel_nope.quality", 3), "no plugin \"accel_nope\" is loaded",
               "integrator_pt")
        raises(lambda: s.set("integrator_pt.maxDepth", "deep"), "maxDepth")
        raises(lambda: s.set("integrator_pt.noSuchParam", 1), "noSuchParam")
        raises(lambda: s.aov("normal"), "not rendered")
        s.set("integrator_pt.maxDepth", 5)
        check(s.config("integrator_pt")["maxDepth"] == 5, "set() changes the configuration")


def test_plugins():
    names = {p["name"]: p for p in tt.list_plugins() if p["name"]}
    for n, kind in [("accel_embree", "accel"), ("integrator_pt", "integrator"),
                    ("integrator_pssmlt", "integrator"), ("tuner_nm", "tuner")]:
        check(n in names and names[n]["kind"] == kind, f"list_plugins has {n} ({kind})")
    d = tt.describe("accel_embree")
    params = {p["name"] for p in d["parameters"]}
    check({"quality", "maxLeafSize"} <= params, f"describe(accel_embree) parameters {params}")
    raises(lambda: tt.describe("accel_nope"), "accel_nope")
    # the same JSON as host --describe
    host = subprocess.run([os.path.join(BUILD, "host/host"), "--describe", "accel_embree"],
                          capture_output=True, text=True, check=True).stdout
    hd = json.loads(host)
    check(hd["parameters"] == d["parameters"], "describe() = host --describe (parameters)")


def test_host_equal(tmp):
    """The numpy image is the EXR host writes, bit for bit."""
    box = os.path.join(SOURCE, "scenes/cornell-box/scene.json")
    exr = os.path.join(tmp, "host.exr")
    subprocess.run([os.path.join(BUILD, "host/host"), "--quiet", "--no-db", "--res", "32x24",
                    "--spp", "6", "--seed", "11", "--set", "integrator_pt.maxDepth=4",
                    "--out", exr, box], check=True)
    ref = tt.read_image(exr)
    with tt.Session(box, plugins=["integrator_pt"], params={"integrator_pt.maxDepth": 4},
                    resolution=(32, 24), seed=11) as s:
        img = s.render(spp=6)
        st = s.stats
    check(img.shape == (24, 32, 3) and img.dtype == np.float32, f"image shape {img.shape}")
    check(ref.shape == img.shape, f"host EXR shape {ref.shape}")
    check(ref.shape == img.shape and np.array_equal(ref, img),
          f"numpy image == host EXR (max diff "
          f"{np.abs(ref - img).max() if ref.shape == img.shape else 'n/a'})")
    check(float(img.mean()) > 0.01, f"the image is not black ({img.mean()})")
    check(st["spp"] == 6 and st["passes"] == 6 and st["seed"] == 11 and st["rays"] >= 32 * 24 * 6,
          f"stats {st}")
    # another seed gives another image (the seed reaches the passes)
    with tt.Session(box, resolution=(32, 24), seed=12) as s:
        check(not np.array_equal(s.render(spp=6), img), "another seed, another image")


def test_aovs(tmp):
    still = write(tmp, "plane.json", plane())
    with tt.Session(still, aovs=["depth", "normal", "albedo", "motion"]) as s:
        rgb = s.render(spp=4)
        depth, normal, albedo, motion = (s.aov(a) for a in ("depth", "normal", "albedo", "motion"))
    check(depth.shape == (12, 16) and normal.shape == (12, 16, 3) and motion.shape == (12, 16, 2),
          f"AOV shapes {depth.shape} {normal.shape} {motion.shape}")
    for y, x in [(0, 0), (6, 8), (11, 15), (3, 12)]:
        check(abs(depth[y, x] - 5.0) < 1e-4, f"depth at ({x}, {y}) = {depth[y, x]}, expected 5")
        check(np.allclose(normal[y, x], [0, 0, -1], atol=1e-5), f"normal at ({x}, {y}) = {normal[y, x]}")
        check(np.allclose(albedo[y, x], [0.2, 0.4, 0.6], atol=1e-6), f"albedo at ({x}, {y}) = {albedo[y, x]}")
        check(np.allclose(motion[y, x], 0, atol=1e-6), f"still camera: motion at ({x}, {y}) = {motion[y, x]}")
    # a lit Lambertian plane under a white environment: radiance = albedo (furnace-like)
    check(np.allclose(rgb.mean(axis=(0, 1)), [0.2, 0.4, 0.6], rtol=0.15),
          f"mean colour {rgb.mean(axis=(0, 1))} ~ albedo")
    raises(lambda: tt.Session(still, aovs=["shadow"]), "shadow", "depth, normal")
    with tt.Session(still, aovs=["depth"]) as s:
        s.render(spp=1)
        raises(lambda: s.aov("normal"), "not requested", "depth")

    # a camera path translating +1 world unit per second along x: at t = 0.5 with a frame
    # interval of 1/24 s the camera moved 1/24 units, i.e. f * (1/24) / 5 pixels with
    # f = (height / 2) / tan(fov / 2); world +x is image left (right = forward x up), so a
    # point seen one frame earlier, from 1/24 units further left, sat further left: -x
    path = write(tmp, "moving.json", plane(path=MOVING_PATH))
    expected = motion_pixels(1 / 24)
    with tt.Session(path, aovs=["motion", "depth"], camera_time=0.5) as s:
        s.render(spp=1)
        motion = s.aov("motion")
        depth = s.aov("depth")
    check(np.allclose(depth, 5.0, atol=1e-4), "moving camera: depth 5")
    check(np.allclose(motion[..., 0], -expected, rtol=1e-3),
          f"motion x {motion[6, 8, 0]} (expected {-expected})")
    check(np.allclose(motion[..., 1], 0, atol=1e-4), f"motion y {motion[6, 8, 1]}")


def test_tuning(tmp):
    box = os.path.join(SOURCE, "scenes/cornell-box/scene.json")
    db_path = os.path.join(tmp, "tuning.db")
    kw = dict(plugins=["integrator_pt", "tuner_nm"], resolution=(16, 16), seed=5)
    with tt.Session(box, **dict(kw, plugins=["accel_embree"] + kw["plugins"])) as s:
        # maxLeafSize acts only with backend custom (with native it is not searched)
        s.set("accel_embree.backend", "custom")
        t = s.tune("accel_embree", tuner="tuner_nm", iterations=6, db=db_path,
                   params=["maxLeafSize", "quality"])
        after = s.config("accel_embree")
        img = s.render(spp=2)
        spp = s.stats["spp"]
    h = t.history
    check(len(h) == 7 and h[0]["iteration"] == -1, f"history: 1 default + 6 ({len(h)})")
    check(all(x["status"] in ("ok", "infeasible") for x in h), "samples measured")
    check(t.mode == "tune" and t.stats["requested"] == 6, f"stats {t.stats}")
    check(t.best_config == after, "the session keeps the best configuration")
    check(t.best_cost <= t.default_cost or t.best_config == t.default_config, "best <= default")
    # warm-up + 7 measurement passes + 2 = 10 spp in the film
    check(spp == 10 and img.shape == (16, 16, 3), f"tuning passes accumulate ({spp} spp)")
    with tt.TuningDB(db_path) as db:
        rows = db.rows("accel_embree")
        check(len(db) == len(rows) == len(h), f"database rows {len(rows)} = samples {len(h)}")
        check([r["config"] for r in rows] == [x["config"] for x in h], "rows' configs = history")
        check([r["iteration"] for r in rows] == [x["iteration"] for x in h], "rows' iterations")
        ok = [(r["cost"], x["cost"]) for r, x in zip(rows, h) if x["status"] == "ok"]
        check(all(abs(a - b) <= 1e-9 * max(1, abs(b)) for a, b in ok), "rows' costs = history")
        check(all(r["indicators"] and len(r["indicators"]) == 17 for r in rows), "indicators")
        # named as the file stores them (a JSON object by tt_scene_indicator_name)
        raw = sqlite3.connect(db_path).execute("SELECT indicators FROM samples ORDER BY id LIMIT 1")
        check(json.loads(raw.fetchone()[0]) == dict(zip(tt.INDICATORS, rows[0]["indicators"])),
              f"INDICATORS {tt.INDICATORS}")
        check(all(r["mode"] in ("default", "tune") and r["tuner"] in (None, "tuner_nm")
                  for r in rows), "mode and tuner")
        check(rows[0]["context"]["spp"] == 1 and "integrator_pt" in rows[0]["context"]["plugins"],
              f"context {rows[0]['context']}")
    # the same session again: every configuration is answered by the database
    with tt.Session(box, **dict(kw, plugins=["accel_embree"] + kw["plugins"])) as s:
        s.set("accel_embree.backend", "custom")
        t2 = s.tune("accel_embree", tuner="tuner_nm", iterations=6, db=db_path,
                    params=["maxLeafSize", "quality"])
    # (the default is measured again, and its noisy cost may steer the search elsewhere: a
    # configuration the first run measured must be answered, a new one may be measured)
    seen = {json.dumps(x["config"], sort_keys=True) for x in h if x["status"] == "ok"}
    check(t2.stats["cached"] >= 1 and all(x["cached"] for x in t2.history[1:] if x["status"] == "ok"
                                          and json.dumps(x["config"], sort_keys=True) in seen),
          f"second run answered from the database ({t2.stats})")
    with tt.TuningDB(db_path) as db:
        check(len(db) == len(h) + t2.stats["measured"], f"only new measurements are recorded ({len(db)})")
    # exploration without a tuner, PSSMLT's hint (target and objective from the plugin)
    with tt.Session(box, plugins=["integrator_pssmlt", "tuner_nm"], resolution=(16, 16)) as s:
        t3 = s.tune(tuner="tuner_nm", iterations=3, spp=1)
        check(t3.history and "sigma0" in json.dumps(t3.best_config) or "a1" in json.dumps(t3.best_config),
              f"PSSMLT's hint chooses the target ({list(t3.best_config)[:4]})")
    with tt.Session(box, resolution=(16, 16)) as s:
        t4 = s.tune("accel_embree", iterations=3)
        check(t4.mode == "explore" and len(t4.history) == 4, f"exploration ({t4.mode}, {len(t4.history)})")
        raises(lambda: s.tune("accel_embree", tuner="tuner_nm"), "tuner_nm", "not loaded")


def test_sessions_side_by_side():
    """Sessions never free each other: two alive and closed in either order, `s = Session()`
    re-assigned in a loop after a tuning run, a session per thread (the library releases the
    GIL-free C calls; each thread's error message is its own)."""
    import threading
    box = os.path.join(SOURCE, "scenes/cornell-box/scene.json")
    kw = dict(plugins=["accel_embree", "integrator_pt"], resolution=(16, 12), seed=7)
    with tt.Session(box, **kw) as s:
        ref = s.render(spp=2)
    for older_first in (True, False):
        a, b = tt.Session(box, **kw), tt.Session(box, **kw)
        a.render(spp=1)
        b.render(spp=1)
        gone, kept = (a, b) if older_first else (b, a)
        gone.close()
        kept.reset()
        check(np.array_equal(kept.render(spp=2), ref),
              f"the other session renders on ({'older' if older_first else 'newer'} closed first)")
        raises(lambda: kept.set("accel_embree.quality", 7), "accel_embree.quality",
               "is not one of 1, 2, 3")
        kept.close()
    s = tt.Session(box, **kw)
    for i in range(5):
        s.tune("accel_embree", iterations=2)
        s = tt.Session(box, **kw)  # the old session is freed after the new one exists
        raises(lambda: s.set("accel_embree.quality", 7), "is not one of 1, 2, 3")
        check(np.array_equal(s.render(spp=2), ref), f"re-assigned session {i} renders the same image")
    s.close()

    results = {}

    def worker(k):
        out = results.setdefault(k, [])
        try:
            for _ in range(2):
                with tt.Session(box, **kw) as t:
                    img = t.render(spp=2)
                    try:
                        t.set(f"integrator_pt.noSuchParam{k}", 1)
                        msg = ""
                    except tt.Error as e:
                        msg = str(e)
                    t.tune("accel_embree", iterations=2)
                    out.append((np.array_equal(img, ref), f"noSuchParam{k}" in msg))
        except Exception as e:  # reported below
            out.append((False, repr(e)))
    threads = [threading.Thread(target=worker, args=(k,)) for k in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k, out in sorted(results.items()):
        check(len(out) == 2 and all(a is True and b is True for a, b in out),
              f"thread {k}: images equal a lone session's and its own error message ({out})")


def test_python_errors(tmp):
    """Errors are tunetrace.Error and the built-in exception Python code catches for them;
    argument types are refused before any library call; nothing reads a path cut short."""
    import errno
    box = os.path.join(SOURCE, "scenes/cornell-box/scene.json")
    missing = os.path.join(tmp, "missing.json")

    def expect(cls, fn, *needles):
        try:
            fn()
        except tt.Error as e:
            check(isinstance(e, cls), f"{type(e).__name__} is a {cls.__name__} ({e})")
            for n in needles:
                check(n in str(e), f"message {str(e)!r} contains {n!r}")
            return e
        except Exception as e:  # noqa: BLE001 (reported as a failed check)
            check(False, f"expected tunetrace.Error and {cls.__name__}, got {type(e).__name__}: {e}")
            return None
        check(False, f"expected {cls.__name__} with {needles}")
        return None

    e = expect(FileNotFoundError, lambda: tt.Session(missing), "missing.json")
    check(e is not None and e.errno == errno.ENOENT and e.filename == missing,
          f"errno and filename of a missing scene ({getattr(e, 'errno', None)}, "
          f"{getattr(e, 'filename', None)})")
    expect(FileNotFoundError, lambda: tt.read_image(os.path.join(tmp, "missing.exr")))
    expect(FileNotFoundError, lambda: tt.Session(box, plugins=["integrator_nope"]), "integrator_nope")
    typo = os.path.join(tmp, "typo.db")
    expect(FileNotFoundError, lambda: tt.TuningDB(typo), "typo.db")
    check(not os.path.exists(typo), "TuningDB(typo) creates no file")
    bad = os.path.join(tmp, "bad_fov.json")
    with open(bad, "w") as f:
        f.write('{"version": 1, "camera": {"position": [0, 0, 0], "target": [0, 0, 1], '
                '"fov": 200}, "meshes": []}')
    expect(ValueError, lambda: tt.Session(bad), "camera.fov")
    with tt.Session(box, plugins="integrator_pt", resolution=(8, 8)) as s:
        check([p["name"] for p in s.plugins] == ["integrator_pt"], "plugins=\"integrator_pt\" "
              f"is one plugin ({[p['name'] for p in s.plugins]})")
        k = expect(KeyError, lambda: s.set("integrator_pt.noSuchParam", 1), "noSuchParam")
        check(k is not None and not isinstance(k, ValueError), "an unknown key is no ValueError")
        v = expect(ValueError, lambda: s.set("integrator_pt.maxDepth", "deep"), "maxDepth")
        check(v is not None and not isinstance(v, KeyError), "a bad value is no KeyError")
        expect(KeyError, lambda: s.config("accel_nope"), "accel_nope")
        expect(TypeError, lambda: s.render(spp="4"), "spp: expected an integer, got str '4'")
        expect(TypeError, lambda: s.render(spp=2.5), "spp", "float")
        expect(TypeError, lambda: s.tune("accel_embree", iterations="3"), "iterations")
        check(s.stats["passes"] == 0, "a refused argument rendered nothing")
        # a NUL character is refused, never read cut short
        expect(ValueError, lambda: s.set("integrator_pt.max\0Depth", 3), "NUL")
    expect(ValueError, lambda: tt.Session(box + "\0.json"), "NUL", "scene")
    expect(ValueError, lambda: tt.Session(os.path.join(tmp, "a\0b.json")), "NUL")
    expect(ValueError, lambda: tt.read_image("a\0b.exr"), "NUL")
    expect(ValueError, lambda: tt.Session(box, plugins=["integrator_pt\0x"]), "NUL")
    expect(TypeError, lambda: tt.Session(box, resolution=("16", 16)), "resolution width")
    expect(TypeError, lambda: tt.Session(box, seed="7"), "seed")
    expect(TypeError, lambda: tt.Session(box, plugins=3), "plugins")
    with tt.Session(box, aovs="normal", resolution=(8, 8)) as s:
        s.render(spp=1)
        check(s.aov("normal").shape == (8, 8, 3), "aovs=\"normal\" is one AOV")
    # every status the library names maps to its class; out of memory is a MemoryError
    from tunetrace import _errors
    for name, cls in [("TT_ERR_OUT_OF_MEMORY", MemoryError), ("TT_ERR_PARSE", ValueError),
                      ("TT_ERR_INVALID_ARGUMENT", ValueError), ("TT_ERR_IO", OSError),
                      ("TT_ERR_NUMERIC", ArithmeticError)]:
        err = _errors.make_error(tt.STATUS[name], "x")
        check(isinstance(err, cls) and isinstance(err, tt.Error) and str(err) == "x",
              f"{name} -> {type(err).__name__}")


def test_names_from_library(abi_exe):
    """Status codes and plugin kinds come from the library (by name), with the numbers the
    C header has; __version__ is the library's."""
    c = json.loads(subprocess.run([abi_exe], check=True, capture_output=True, text=True).stdout)
    k = c["constants"]
    want = {n: v for n, v in k.items() if n.startswith("TT_OK") or n.startswith("TT_ERR_")
            or n in ("TT_DONE", "TT_REPAIRED")}
    check(tt.STATUS == want, f"STATUS {tt.STATUS} = the header's {want}")
    check(sorted(tt.KINDS) == list(range(1, k["TT_KIND_COUNT"] + 1)) and
          tt.KINDS[1] == "accel" and tt.KINDS[3] == "tuner", f"KINDS {tt.KINDS}")
    check(tt.__version__ == tt.version() and tt.__version__.count(".") == 2,
          f"__version__ {tt.__version__}")
    for name in tt.__all__:
        obj = getattr(tt, name)
        if callable(obj) or isinstance(obj, type):
            check(bool(getattr(obj, "__doc__", None)), f"tt.{name} has a docstring")
    for cls in (tt.Session, tt.TuningDB, tt.Tuning):
        for attr, obj in vars(cls).items():
            if not attr.startswith("_") and (callable(obj) or isinstance(obj, property)):
                check(bool(obj.__doc__), f"tt.{cls.__name__}.{attr} has a docstring")


def test_on_demand_plugins(tmp):
    """params= and set() before the first render load the plugin they name, as host loads
    its defaults before --set; the image is host's with the same settings."""
    box = os.path.join(SOURCE, "scenes/cornell-box/scene.json")
    with tt.Session(box, params={"integrator_pt.maxDepth": 4}, resolution=(8, 8)) as s:
        check(s.config("integrator_pt")["maxDepth"] == 4, "params= loads integrator_pt")
        s.set("accel_embree.quality", 2)
        check(s.config("accel_embree")["quality"] == 2, "set() loads accel_embree")
        s.render(spp=1)
        check(sorted(p["name"] for p in s.plugins) == ["accel_embree", "integrator_pt"],
              f"loaded once each: {[p['name'] for p in s.plugins]}")
        raises(lambda: s.set("integrator_pssmlt.chains", 8), "integrator_pssmlt")  # started
    with tt.Session(box, resolution=(8, 8)) as s:
        s.set("integrator_pssmlt.binning", False)
        check([p["name"] for p in s.plugins] == ["integrator_pssmlt"], "set() loads PSSMLT")
        raises(lambda: s.set("accel_nope.quality", 3), "no plugin \"accel_nope\" is loaded")
    # the tuner of tune() too, before the session starts
    with tt.Session(box, resolution=(8, 8)) as s:
        t = s.tune("accel_embree", tuner="tuner_nm", iterations=2, db=False)
        check(t.mode == "tune" and len(t.history) == 3, f"tuner loaded by tune() ({t.mode})")


def test_plan_and_logging(tmp, fixture_short):
    """tune() plans through the library: a hint whose struct_size ends before `objective`
    is ignored (as host does); the library's messages reach the `tunetrace` logger, not
    stderr; tune() records into the per-user database unless db=False (host's rule)."""
    import logging
    box = os.path.join(SOURCE, "scenes/cornell-box/scene.json")
    with tt.Session(box, plugins=[fixture_short], resolution=(8, 8)) as s:
        t = s.tune("fixture_hint_short", iterations=1, db=False)
        check(len(t.history) == 2 and all(x["status"] == "ok" for x in t.history),
              f"a 12-byte hint's objective is not read ({[x['status'] for x in t.history]})")
    # the user's value wins over PSSMLT's setup (binning on)
    with tt.Session(box, plugins=["integrator_pssmlt"], resolution=(8, 8)) as s:
        s.set("integrator_pssmlt.binning", False)
        s.tune(iterations=1, db=False)
        check(s.config("integrator_pssmlt")["binning"] is False, "set() wins over the hint")

    records = []

    class Keep(logging.Handler):
        def emit(self, record):
            records.append(record)
    logger = logging.getLogger("tunetrace")
    handler = Keep()
    logger.addHandler(handler)
    logger.setLevel(logging.DEBUG)
    try:
        noisy = os.path.join(tmp, "noisy.json")
        with open(box) as f:
            scene = json.load(f)
        scene["colour_typo"] = 1
        scene.setdefault("meshes", [])
        for m in scene["meshes"]:
            if "file" in m and not os.path.isabs(m["file"]):
                m["file"] = os.path.join(os.path.dirname(box), m["file"])
        with open(noisy, "w") as f:
            json.dump(scene, f)
        with tt.Session(noisy, resolution=(8, 8)) as s:
            s.tune("accel_embree", iterations=1, db=False)
    finally:
        logger.removeHandler(handler)
        logger.setLevel(logging.NOTSET)
    warn = [r for r in records if r.levelno == logging.WARNING and "colour_typo" in r.getMessage()]
    check(len(warn) == 1 and warn[0].name == "tunetrace", f"the scene loader's warning as a "
          f"WARNING record of 'tunetrace' ({[(r.name, r.levelname, r.getMessage()) for r in records][:4]})")
    check(any(r.levelno == logging.INFO and "tuning" in r.getMessage() for r in records),
          "the tuning session's INFO messages")
    # a script run as is prints nothing of the library's info (logging's default: warnings)
    code = ("import sys; sys.path.insert(0, %r); import tunetrace as tt\n"
            "s = tt.Session(%r, resolution=(8, 8)); s.tune('accel_embree', iterations=1, "
            "db=False); s.render(1); s.close()\n") % (os.path.join(BUILD, "python"), box)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    check(r.returncode == 0 and r.stderr == "", f"nothing on stderr: {r.stderr[:300]!r}")

    # tune() without db: the per-user database ($XDG_DATA_HOME, set to tmp by main())
    default_db = os.path.join(os.environ["XDG_DATA_HOME"], "tunetrace", "tuning.db")
    before = tt.TuningDB(default_db).count() if os.path.exists(default_db) else 0
    with tt.Session(box, resolution=(8, 8), seed=3) as s:
        t = s.tune("accel_embree", iterations=2)
    check(t.db_path == default_db and os.path.exists(default_db),
          f"tune() records into the per-user database ({t.db_path})")
    with tt.TuningDB() as db:
        check(db.path == default_db and db.count() == before + t.stats["measured"],
              f"rows {db.count()} = {before} + {t.stats['measured']} measured")
        n = db.count()
    with tt.Session(box, resolution=(8, 8), seed=4) as s:
        s.tune("accel_embree", iterations=2, db=False)
    with tt.TuningDB() as db:
        check(db.count() == n, "db=False records nothing")


def test_example(tmp):
    script = os.path.join(SOURCE, "python/examples/render_and_tune.py")
    env = dict(os.environ, PYTHONPATH=os.path.join(BUILD, "python"))
    r = subprocess.run([sys.executable, script, "--res", "24x24", "--spp", "2", "--iterations",
                        "3", "--out", os.path.join(tmp, "example")], capture_output=True,
                       text=True, env=env, cwd=SOURCE)
    check(r.returncode == 0, f"example script: {r.stderr}")
    check(os.path.exists(os.path.join(tmp, "example.exr")), "example wrote its EXR")


def test_readme_snippet(tmp):
    """The README's Python example (the ```python block of "## Python") run as written, in a
    folder holding only a link to the checkout's scenes/: it renders, tunes into tuning.db
    there and prints the best configuration and the counts."""
    readme = open(os.path.join(SOURCE, "README.md"), encoding="utf-8").read()
    part = readme.split("\n## Python\n", 1)
    check(len(part) == 2 and "```python\n" in part[1], "README.md has a ## Python section with code")
    if len(part) != 2 or "```python\n" not in part[1]:
        return
    code = part[1].split("```python\n", 1)[1].split("```", 1)[0]
    work = os.path.join(tmp, "readme_python")
    os.makedirs(work)
    os.symlink(os.path.join(SOURCE, "scenes"), os.path.join(work, "scenes"))
    env = dict(os.environ, PYTHONPATH=os.path.join(BUILD, "python"))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                       cwd=work, timeout=600)
    check(r.returncode == 0, f"README's Python example: {r.stderr[-2000:]}")
    check(os.path.exists(os.path.join(work, "tuning.db")), "README's example wrote tuning.db")
    out = r.stdout.split()
    check(len(out) >= 2 and out[-1].isdigit() and int(out[-1]) > 0 and out[-2].isdigit()
          and int(out[-2]) > 0, f"README's example printed its history and rows: {r.stdout!r}")


def main():
    abi = sys.argv[1] if len(sys.argv) > 1 else os.path.join(BUILD, "python/tests/python_abi")
    fixture_short = (sys.argv[2] if len(sys.argv) > 2 else
                     os.path.join(BUILD, "tests/fixtures/fixture_hint_short.so"))
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["XDG_DATA_HOME"] = tmp  # never the user's database
        for test in (lambda: test_layout(abi), lambda: test_errors(tmp), test_plugins,
                     lambda: test_host_equal(tmp), lambda: test_aovs(tmp),
                     lambda: test_tuning(tmp), test_sessions_side_by_side,
                     lambda: test_python_errors(tmp), lambda: test_names_from_library(abi),
                     lambda: test_on_demand_plugins(tmp),
                     lambda: test_plan_and_logging(tmp, fixture_short),
                     lambda: test_example(tmp), lambda: test_readme_snippet(tmp)):
            test()
    print(f"python_api: {checks} checks, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
