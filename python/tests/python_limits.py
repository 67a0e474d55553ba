#!/usr/bin/python3
"""Numbers the Python API refuses as the host refuses them (tunetrace/limits.h, one check
for both): resolution (2**32 + 8, 8), seed -1, render(2**40), render(-1), tune(iterations=-1),
set_threads(-1) each raise tunetrace.Error with the message the host prints for the same
value of its option (after the option's name), and nothing is wrapped into range; the
session is still usable afterwards.

Environment: TT_BUILD_ROOT, TT_SOURCE_ROOT (tests/meson.build)."""
import os
import subprocess
import sys

BUILD = os.environ["TT_BUILD_ROOT"]
SOURCE = os.environ["TT_SOURCE_ROOT"]
sys.path.insert(0, os.path.join(BUILD, "python"))

import tunetrace as tt  # noqa: E402

SCENE = os.path.join(SOURCE, "scenes", "cornell-box", "scene.json")
failures = 0


def check(cond, what):
    global failures
    if not cond:
        failures += 1
        print(f"FAIL: {what}", file=sys.stderr)


def host_message(option, value):
    """What the host says after "OPTION: " when given `value` (exit 2 expected)."""
    r = subprocess.run([os.path.join(BUILD, "host", "host"), option, value, SCENE],
                       capture_output=True, text=True)
    check(r.returncode == 2, f"host {option} {value}: exit {r.returncode}, expected 2")
    marker = f"{option}: "
    line = next((ln for ln in r.stderr.splitlines() if marker in ln), "")
    check(line, f"host {option} {value} names the option: {r.stderr!r}")
    return line.split(marker, 1)[1] if line else "?"


def refused(fn, name, host_option, host_value):
    """fn() raises tt.Error "NAME: <the host's message for HOST_OPTION HOST_VALUE>"."""
    want = f"{name}: {host_message(host_option, host_value)}"
    try:
        fn()
    except tt.Error as e:
        check(str(e) == want, f"message {str(e)!r}, expected {want!r}")
        return
    check(False, f"{name}: accepted, expected the error {want!r}")


def main():
    refused(lambda: tt.Session(SCENE, resolution=(2**32 + 8, 8)), "resolution", "--res",
            "4294967304x8")
    refused(lambda: tt.Session(SCENE, resolution=(8, 2**32 + 1)), "resolution", "--res",
            "8x4294967297")
    refused(lambda: tt.Session(SCENE, seed=-1), "seed", "--seed", "-1")
    refused(lambda: tt.Session(SCENE, seed=2**64), "seed", "--seed", str(2**64))
    refused(lambda: tt.set_threads(-1), "threads", "--threads", "-1")
    with tt.Session(SCENE, plugins=["tuner_nm"], resolution=(8, 8), seed=2**64 - 1) as s:
        refused(lambda: s.render(2**40), "spp", "--spp", str(2**40))
        refused(lambda: s.render(-1), "spp", "--spp", "-1")
        refused(lambda: s.render(4, pass_spp=0), "pass_spp", "--spp", "0")
        refused(lambda: s.tune("accel_embree", tuner="tuner_nm", iterations=-1), "iterations",
                "--iterations", "-1")
        refused(lambda: s.tune("accel_embree", tuner="tuner_nm", iterations=2, verify=-1),
                "verify", "--verify", "-1")
        refused(lambda: s.tune("accel_embree", tuner="tuner_nm", iterations=2,
                               time_budget=-1.0), "time_budget", "--time", "-1.0")
        check(s.stats["spp"] == 0, f"a refused call rendered: {s.stats}")
        img = s.render(2)
        check(img.shape == (8, 8, 3) and s.stats["spp"] == 2,
              f"the session renders after refusals: {img.shape}, {s.stats}")
        check(s.stats["seed"] == 2**64 - 1, f"seed 2**64-1 kept: {s.stats['seed']}")
    try:
        tt.Session(SCENE, resolution=(8.5, 8))
        check(False, "a resolution of 8.5 was accepted")
    except TypeError:
        pass
    if failures:
        print(f"python_limits: {failures} failure(s)", file=sys.stderr)
        return 1
    print("python_limits: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
