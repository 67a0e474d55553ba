"""Where a render's time goes, per accel configuration (issue 16): a chart of the output of
plugins/accel_embree/tests/accel_embree_render_bench.

The render bench splits every render into traversal (CPU time inside the accel's stream
calls, by kind: camera rays, bounce rays, shadow rays) and the rest (shading, sampling,
the integrator). This tool reads its stdout and draws, for one (threads, maxDepth) mode,
one panel per scene with a stacked bar per configuration (camera, bounce, shadow, rest;
median CPU ms), each bar labelled with its render speed relative to native default. So the
bench's finding can be seen at a glance: the rest is the same for every tree, and only
traversal differs.

  TT_PLUGIN_PATH=build/plugins TT_SOURCE_ROOT=. build/plugins/accel_embree/tests/accel_embree_render_bench \\
      5 "" > bench.txt
  /usr/bin/python3 -m tools.accel.render_split bench.txt --mode "t1 d3" --out render_split.png   # also prints the table
"""
import argparse
import os
import re
import sys

SCENE_RE = re.compile(r"^(\S+): \d+ triangles, ")
MODE_RE = re.compile(r"^  threads (\d+), maxDepth (\d+):")


def parse(text, source="<input>"):
    """Returns {scene: {(threads, depth): [row, ...]}}, a row being a dict with the label and
    cpu, trav, camera, bounce, shadow, rest (median CPU ms) and ratio (render speed / native
    default). Raises ValueError naming the line when a table row does not parse."""
    out = {}
    scene = mode = None
    in_table = False
    for no, line in enumerate(text.splitlines(), 1):
        m = SCENE_RE.match(line)
        if m:
            scene, mode, in_table = m.group(1), None, False
            out.setdefault(scene, {})
            continue
        m = MODE_RE.match(line)
        if m and scene is not None:
            mode = (int(m.group(1)), int(m.group(2)))
            out[scene][mode] = []
            in_table = False
            continue
        if line.startswith("  configuration"):
            in_table = "CPU ms" in line and mode is not None
            if in_table and "camera" not in line:
                raise ValueError(f"{source}:{no}: this bench output has no traversal split "
                                 "(a bench from before session 9): expected the columns "
                                 "'trav ms ... camera bounce shadow'")
            continue
        if not in_table or not line.startswith("  ") or not line.strip():
            in_table = False
            continue
        if "(build failed)" in line:
            continue
        parts = line.split("|")
        try:
            if len(parts) != 4:
                raise ValueError(f"{len(parts)} '|'-separated parts, expected 4")
            left = parts[0].split()
            label = " ".join(left[:-5])
            cpu = float(left[-5])
            ratio = float(parts[1].split()[0].rstrip("x"))
            trav = float(parts[2].split()[0])
            camera, bounce, shadow = (float(v) for v in parts[3].split())
        except (ValueError, IndexError) as e:
            raise ValueError(f"{source}:{no}: a configuration row of the render bench was "
                             f"expected ({e}): {line.strip()!r}") from None
        out[scene][mode].append({"label": label, "cpu": cpu, "ratio": ratio, "trav": trav,
                                 "camera": camera, "bounce": bounce, "shadow": shadow,
                                 "rest": cpu - trav})
    return {s: modes for s, modes in out.items() if any(modes.values())}


def table(data, mode):
    lines = [f"{'scene':<14} {'configuration':<28} {'render':>7} {'camera':>7} {'bounce':>7} "
             f"{'shadow':>7} {'rest':>7} {'vs native':>9}"]
    for scene, modes in data.items():
        for r in modes.get(mode, []):
            lines.append(f"{scene:<14} {r['label']:<28} {r['cpu']:7.1f} {r['camera']:7.1f} "
                         f"{r['bounce']:7.1f} {r['shadow']:7.1f} {r['rest']:7.1f} "
                         f"{r['ratio']:8.3f}x")
    return "\n".join(lines)


def chart(data, mode, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = [s for s in data if data[s].get(mode)]
    cols = min(3, len(scenes))
    rows = (len(scenes) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 0.5 + 2.6 * rows), squeeze=False)
    parts = [("camera", "#4c72b0"), ("bounce", "#dd8452"), ("shadow", "#c44e52"),
             ("rest", "#bbbbbb")]
    for ax, scene in zip(axes.flat, scenes):
        rs = data[scene][mode]
        y = list(range(len(rs)))[::-1]
        left = [0.0] * len(rs)
        for key, color in parts:
            vals = [r[key] for r in rs]
            ax.barh(y, vals, left=left, color=color, label=key if scene == scenes[0] else None)
            left = [a + b for a, b in zip(left, vals)]
        for yi, r, x in zip(y, rs, left):
            ax.text(x, yi, f" {r['ratio']:.2f}x", va="center", fontsize=7)
        ax.set_yticks(y)
        ax.set_yticklabels([r["label"] for r in rs], fontsize=7)
        ax.set_xlim(0, max(left) * 1.18)
        ax.set_title(scene, fontsize=9)
        ax.set_xlabel("CPU ms per image", fontsize=7)
        ax.tick_params(axis="x", labelsize=7)
    for ax in list(axes.flat)[len(scenes):]:
        ax.axis("off")
    fig.legend(loc="lower center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle(f"accel_embree render bench, threads {mode[0]}, maxDepth {mode[1]}: traversal "
                 "by ray kind and the rest of the render (label: render speed / native default)",
                 fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 0.95))
    tmp = out + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    os.replace(tmp, out)  # atomic: an existing chart is never left half written


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("bench_output", help="stdout of accel_embree_render_bench")
    ap.add_argument("--mode", default="t1 d3", help="threads and maxDepth, e.g. 't2 d8'")
    ap.add_argument("--out", help="chart to write (PNG)")
    a = ap.parse_args(argv)
    m = re.fullmatch(r"t(\d+) d(\d+)", a.mode.strip())
    if not m:
        ap.error(f"--mode {a.mode!r}: expected 't<threads> d<maxDepth>', e.g. 't1 d3'")
    mode = (int(m.group(1)), int(m.group(2)))
    try:
        with open(a.bench_output, encoding="utf-8", errors="replace") as f:
            data = parse(f.read(), a.bench_output)
    except OSError as e:
        sys.exit(f"render_split: {a.bench_output}: {e.strerror}")
    except ValueError as e:
        sys.exit(f"render_split: {e}")
    if not any(mode in modes for modes in data.values()):
        have = sorted({f"t{t} d{d}" for modes in data.values() for (t, d) in modes})
        sys.exit(f"render_split: {a.bench_output}: no tables for mode '{a.mode}' "
                 f"(it has: {', '.join(have) or 'no tables at all'})")
    print(table(data, mode))
    if a.out:
        chart(data, mode, a.out)
        print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
