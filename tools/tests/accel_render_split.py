"""tools/accel/render_split.py on the committed render-bench output of session 9
(tools/accel/data/render_bench_session9.txt): every table is read (6 scenes x 4 modes x 7
configurations), the parts add up to the render (camera + bounce + shadow = traversal,
traversal + rest = CPU ms), native default is the 1.000x reference, the chart is written;
and bad input (a file cut short inside a row, a bench output without the split, an unknown
mode) gets an error naming the file and line, not a traceback or a silent partial chart."""
import os
import subprocess
import sys
import tempfile

from tools.accel import render_split

ROOT = os.environ.get("TT_SOURCE_ROOT", ".")
DATA = os.path.join(ROOT, "tools", "accel", "data", "render_bench_session9.txt")
fails = 0


def run(*args):
    """The tool as a user runs it: returncode, stdout, stderr."""
    r = subprocess.run([sys.executable, "-m", "tools.accel.render_split", *args],
                       capture_output=True, text=True, cwd=ROOT)
    return r.returncode, r.stdout, r.stderr


def check(cond, what):
    global fails
    if not cond:
        fails += 1
        print("FAIL:", what)


def main():
    text = open(DATA, encoding="utf-8").read()
    data = render_split.parse(text, DATA)
    check(sorted(data) == sorted(["living-room", "bmw-m6", "staircase", "bathroom",
                                  "killeroos", "voxel-world"]), f"scenes: {sorted(data)}")
    for scene, modes in data.items():
        check(sorted(modes) == [(1, 3), (1, 8), (2, 3), (2, 8)], f"{scene}: modes {sorted(modes)}")
        for mode, rows in modes.items():
            check(len(rows) == 7, f"{scene} {mode}: {len(rows)} rows")
            check(rows[0]["label"] == "native default" and rows[0]["ratio"] == 1.0,
                  f"{scene} {mode}: first row {rows[0]}")
            for r in rows:
                parts = r["camera"] + r["bounce"] + r["shadow"]
                check(abs(parts - r["trav"]) <= 0.25, f"{scene} {mode} {r['label']}: parts "
                      f"{parts} != traversal {r['trav']}")
                check(0 < r["trav"] < r["cpu"] and r["rest"] > 0, f"{scene} {mode} {r}")
    lr = {r["label"]: r for r in data["living-room"][(1, 3)]}
    check(abs(lr["custom as native"]["cpu"] - 130.0) < 1e-9 and
          abs(lr["custom as native"]["ratio"] - 0.949) < 1e-9, f"living-room row {lr}")

    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "split.png")
        rc, out_text, err = run(DATA, "--mode", "t2 d8", "--out", out)
        check(rc == 0 and "custom as native" in out_text, f"run: {rc} {err}")
        with open(out, "rb") as f:
            check(f.read(8) == b"\x89PNG\r\n\x1a\n", "the chart is a PNG")

        # Cut short inside a configuration row: an error naming the file and the line.
        lines = text.splitlines()
        cut = next(i for i, l in enumerate(lines) if l.startswith("  custom as native"))
        short = os.path.join(tmp, "short.txt")
        with open(short, "w") as f:
            f.write("\n".join(lines[:cut]) + "\n" + lines[cut][:50])
        rc, _, err = run(short)
        check(rc != 0 and f"short.txt:{cut + 1}:" in err and "Traceback" not in err,
              f"cut short: {rc} {err!r}")
        # An older bench output without the traversal columns.
        old = os.path.join(tmp, "old.txt")
        with open(old, "w") as f:
            f.write("living-room: 143163 triangles, 160x120, 4 spp\n  threads 1, maxDepth 3: 0.48\n"
                    "  configuration  CPU ms  min  spread  wall ms  on-CPU |  vs native\n")
        rc, _, err = run(old)
        check(rc != 0 and "no traversal split" in err and "old.txt:3" in err,
              f"old output: {err!r}")
        # A mode the file does not have.
        rc, _, err = run(DATA, "--mode", "t4 d3")
        check(rc != 0 and "it has: t1 d3, t1 d8, t2 d3, t2 d8" in err, f"unknown mode: {err!r}")
    print("accel_render_split:", "FAILED" if fails else "passed", f"({fails} failures)")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
