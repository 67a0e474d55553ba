#!/usr/bin/python3
"""Bench (prints figures, asserts nothing about speed): the Python API against host on the
same job, side by side, interleaved, medians. Cornell box 128x128, 16 spp, 2 threads, seed 1:
  - render_ms of the passes (host's --stats vs Session.stats): the same library session, so
    the ratio should be 1 within noise;
  - wall time per job: a host process (start-up, scene, plugins, render, EXR + PNG) vs a
    Session in a running Python (scene, plugins, render into numpy);
  - whether the two images are bit-identical.

    meson test -C build --suite bench python_bench --verbose
    TT_BUILD_ROOT=build TT_SOURCE_ROOT=. /usr/bin/python3 python/tests/python_bench.py [ROUNDS]
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

BUILD = os.environ["TT_BUILD_ROOT"]
SOURCE = os.environ["TT_SOURCE_ROOT"]
sys.path.insert(0, os.path.join(BUILD, "python"))
import tunetrace as tt  # noqa: E402


def main():
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    box = os.path.join(SOURCE, "scenes/cornell-box/scene.json")
    tt.set_threads(2)
    host_ms, py_ms, host_wall, py_wall, same = [], [], [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(rounds):
            t0 = time.perf_counter()
            subprocess.run([os.path.join(BUILD, "host/host"), "--quiet", "--threads", "2",
                            "--res", "128x128", "--spp", "16", "--seed", "1", "--stats",
                            f"{tmp}/s.json", "--out", f"{tmp}/h.exr", box], check=True)
            host_wall.append(time.perf_counter() - t0)
            with open(f"{tmp}/s.json") as f:
                host_ms.append(json.load(f)["render_ms"])
            t0 = time.perf_counter()
            with tt.Session(box, resolution=(128, 128), seed=1) as s:
                img = s.render(spp=16)
                py_ms.append(s.stats["render_ms"])
            py_wall.append(time.perf_counter() - t0)
            same.append(bool((tt.read_image(f"{tmp}/h.exr") == img).all()))
    med = statistics.median
    print(f"python_bench: {rounds} rounds, load {os.getloadavg()[0]:.1f}")
    print(f"  render_ms  host {med(host_ms):8.1f}  python {med(py_ms):8.1f}  ratio python/host "
          f"{med([p / h for p, h in zip(py_ms, host_ms)]):.3f} (median of per-round ratios)")
    print(f"  wall s/job host {med(host_wall):8.2f}  python {med(py_wall):8.2f}  (a process vs a "
          "session in a running interpreter)")
    print(f"  images bit-identical: {sum(same)}/{len(same)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
