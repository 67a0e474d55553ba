"""The evaluation of issue #19, one command: every validation (or test) sequence through the C plugin
(host --sequence ... --post post_taa, the way users run it) in modes none (the raw input),
vctaa (the thesis' baseline, tonemapped resolve), vctaa with resolve=linear, and each
network, then RMSE / temporal error / FLIP against the references (eval.py), the mean
brightness of each output against the reference's (the darkening of noisy input), per-frame
curves as PNG, a markdown table with the goals of the issue, eval.json and summary.png (every
method's RMSE and temporal error relative to VCTAA's per sequence, and the jump frames).

  /usr/bin/python3 -m tools.taa.evaluate --out OUT SEQ_DIR... [--net LABEL=W.ttw ...]
              [--default LABEL] [--threads 2] [--no-flip] [--jumps pillars:80:84] [--host PATH]

SEQ_DIR: a sequence folder of render_noisy.sh (render.args replays its input) or of
render_dataset.sh / render_real.sh (DATA/NAME with DATA/scenes/NAME/scene.json, maxDepth
1). Folders already rendered in OUT are reused (delete them to re-render). Needs only
bootstrap's packages (numpy, OpenImageIO, matplotlib, scipy for FLIP)."""
import json
import os
import shlex
import sys

import numpy as np

from tools.taa import eval as ev
from tools.taa import flip as flipmod
from tools.tttools import cli, host


def fail(msg):
    sys.exit(f"evaluate.py: {msg}")


def render_args(seq):
    """Host arguments that reproduce the sequence's input frames."""
    ra = os.path.join(seq, "render.args")
    if os.path.exists(ra):
        return shlex.split(open(ra).read())
    name = os.path.basename(os.path.normpath(seq))
    scene = os.path.join(os.path.dirname(os.path.normpath(seq)), "scenes", name, "scene.json")
    if not os.path.exists(scene):
        fail(f"{seq}: no render.args and no {scene}: cannot re-render the input")
    man = json.load(open(os.path.join(seq, "manifest.json")))
    return ["--spp", str(man.get("spp", 1)), "--set", "integrator_pt.maxDepth=1", scene]


def luma(x):
    return x[..., 0] * 0.2126 + x[..., 1] * 0.7152 + x[..., 2] * 0.0722


def run_method(a, seq, out, mode_args, nframes):
    man = os.path.join(out, "manifest.json")
    if os.path.exists(man) and len(json.load(open(man))["frames"]) == nframes:
        return
    env = dict(os.environ)
    env.pop("TT_POST_TAA_WEIGHTS", None)
    host.run(a.host, ["--quiet", "--threads", str(a.threads), "--sequence", str(nframes),
                      "--out-dir", out, "--aov", "none", "--post", "post_taa"] +
             mode_args + render_args(seq), env=env, capture=True)


def evaluate_seq(a, seq, methods):
    name = os.path.basename(os.path.normpath(seq))
    man = ev.manifest(seq)
    n = len(man["frames"])
    ref = ev.frames(seq, "reference", man)
    ref_srgb = None if a.no_flip else flipmod.srgb_encode(np.stack([ev.tm(x) for x in ref[a.skip:]]))
    ref_l = np.array([luma(x).mean() for x in ref])
    rows = []
    for label, margs in methods:
        out = os.path.join(a.out, name, label)
        run_method(a, seq, out, margs, n)
        outs = ev.frames(out, "post")
        rmse, tmp, per = ev.metrics(outs, ref, a.skip)
        row = {"method": label, "rmse": rmse, "temporal": tmp,
               "rmse_per_frame": [float(v) for v in per],
               "brightness_per_frame": [float(luma(o).mean() / max(r, 1e-12))
                                        for o, r in zip(outs, ref_l)]}
        row["brightness"] = float(np.mean(row["brightness_per_frame"][a.skip:]))
        if not a.no_flip:
            fl = ev.flip_frames(outs, ref_srgb, a.skip, a.ppd)
            row["flip"], row["flip_per_frame"] = float(fl.mean()), [float(v) for v in fl]
        pm = [f.get("post_ms", 0.0) for f in json.load(open(os.path.join(out, "manifest.json")))["frames"]]
        row["post_ms"] = float(np.median(pm))
        rows.append(row)
        print(f"{name:22s} {label:14s} RMSE {rmse:.5f} temporal {tmp:.5f}" +
              ("" if a.no_flip else f" FLIP {row['flip']:.5f}") +
              f" brightness {row['brightness']:.3f}", flush=True)
    return {"sequence": name, "folder": os.path.abspath(seq), "frames": n, "spp": man.get("spp"),
            "methods": rows}


def plot_seq(a, res):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(13, 4))
    for r in res["methods"]:
        ls = "--" if r["method"].startswith("vctaa") else ":" if r["method"] == "input" else "-"
        ax[0].plot(r["rmse_per_frame"], ls, label=r["method"], lw=1.2)
        ax[1].plot(r["brightness_per_frame"], ls, label=r["method"], lw=1.2)
    ax[0].set_title(f"{res['sequence']}: RMSE per frame (tonemapped)")
    ax[0].set_xlabel("frame")
    ax[0].axvline(a.skip, color="grey", lw=0.5)
    ax[1].set_title("mean luminance / reference's")
    ax[1].axhline(1.0, color="grey", lw=0.5)
    ax[1].set_xlabel("frame")
    ax[0].legend(fontsize=7)
    fig.tight_layout()
    path = os.path.join(a.out, res["sequence"], "curves.png")
    fig.savefig(path + ".tmp.png", dpi=90)
    os.replace(path + ".tmp.png", path)
    plt.close(fig)
    return path


def plot_summary(a, results):
    """summary.png: RMSE and temporal error of every method relative to VCTAA's, per
    sequence (grouped bars; the goal lines at 0.8 and 1.0), and the jump frames' RMSE."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    labels = [m for m, _ in a.methods if m != "vctaa"]
    # one colour per method in every panel (the jump panel also shows VCTAA itself)
    colour = {m: f"C{i}" for i, (m, _) in enumerate(a.methods)}
    seqs = [r["sequence"] for r in results]
    panels = [("rmse", "RMSE / VCTAA's", 0.8), ("temporal", "temporal error / VCTAA's", 1.0)]
    has_jumps = any("jumps" in r for r in results)
    fig, ax = plt.subplots(1, len(panels) + has_jumps, figsize=(5.2 * (len(panels) + has_jumps), 4.2))
    w = 0.8 / max(1, len(labels))
    x = np.arange(len(seqs))
    for k, (key, title, goal) in enumerate(panels):
        for i, m in enumerate(labels):
            vals = []
            for r in results:
                by = {q["method"]: q for q in r["methods"]}
                vals.append(by[m][key] / by["vctaa"][key])
            ax[k].bar(x + (i - (len(labels) - 1) / 2) * w, vals, w, label=m, color=colour[m])
        ax[k].axhline(1.0, color="k", lw=0.8)
        if goal != 1.0:
            ax[k].axhline(goal, color="r", lw=0.8, ls="--", label=f"goal {goal}x")
        ax[k].set_xticks(x, seqs, rotation=20, fontsize=8)
        ax[k].set_title(title + " (lower is better)", fontsize=10)
    if has_jumps:
        jr = [r for r in results if "jumps" in r]
        xj = np.arange(len(jr))
        ms = [m for m, _ in a.methods]
        wj = 0.8 / len(ms)
        for i, m in enumerate(ms):
            ax[-1].bar(xj + (i - (len(ms) - 1) / 2) * wj, [r["jumps"]["rmse"][m] for r in jr], wj,
                       label=m, color=colour[m])
        f0, f1 = jr[0]["jumps"]["frames"]
        ax[-1].set_xticks(xj, [r["sequence"] for r in jr], rotation=20, fontsize=8)
        ax[-1].set_title(f"camera jump: mean RMSE of frames {f0}-{f1} (lower is better)",
                         fontsize=10)
        ax[-1].legend(fontsize=7)
    ax[0].legend(fontsize=7)
    fig.tight_layout()
    path = os.path.join(a.out, "summary.png")
    fig.savefig(path + ".tmp.png", dpi=90)
    os.replace(path + ".tmp.png", path)
    plt.close(fig)
    return path


def table(a, results, nets):
    lines = ["| sequence | spp | " + " | ".join(m for m, _ in a.methods) + " |",
             "|---" * (2 + len(a.methods)) + "|"]
    goals = []
    for res in results:
        by = {r["method"]: r for r in res["methods"]}
        vc = by.get("vctaa")
        cells = []
        for m, _ in a.methods:
            r = by[m]
            c = f"{r['rmse']:.4f}"
            if vc and m not in ("vctaa", "input"):
                c += f" ({r['rmse'] / vc['rmse']:.2f}x)"
            c += f" / {r['temporal']:.4f}"
            if "flip" in r:
                c += f" / {r['flip']:.4f}"
            cells.append(c)
        lines.append(f"| {res['sequence']} | {res['spp']} | " + " | ".join(cells) + " |")
        if a.default and vc:
            d = by[a.default]
            goals.append((res["sequence"], d["rmse"] <= 0.8 * vc["rmse"], d["temporal"] <= vc["temporal"],
                          d["rmse"] / vc["rmse"], d["temporal"] / vc["temporal"]))
    out = "\n".join(lines) + "\n\nCells: RMSE (x VCTAA) / temporal / FLIP, frames %d.., tonemapped space.\n" % a.skip
    if goals:
        out += (f"\nGoals for the default network `{a.default}` (RMSE <= 0.8 x VCTAA, temporal <= "
                "VCTAA, every sequence given):\n\n| sequence | RMSE / VCTAA | temporal / VCTAA | met |\n|---|---|---|---|\n")
        for s, g1, g2, r1, r2 in goals:
            out += f"| {s} | {r1:.3f} | {r2:.3f} | {'yes' if g1 and g2 else 'NO'} |\n"
    return out


def jumps(a, results):
    """RMSE over the given frames (the pillars jump, issue #19: frames 80-84)."""
    out = ""
    for spec in a.jumps:
        name, f0, f1 = spec.split(":")
        f0, f1 = int(f0), int(f1)
        for res in results:
            if res["sequence"] != name and not res["sequence"].startswith(name + "-"):
                continue
            vals = {r["method"]: float(np.mean(r["rmse_per_frame"][f0:f1 + 1])) for r in res["methods"]}
            out += (f"{res['sequence']} frames {f0}-{f1} mean RMSE: " +
                    ", ".join(f"{m} {v:.4f}" for m, v in vals.items()) + "\n")
            res["jumps"] = {"frames": [f0, f1], "rmse": vals}
    return out


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("seqs", nargs="*")
    ap.add_argument("--replot", action="store_true",
                    help="redraw OUT/summary.png from OUT/eval.json (no rendering)")
    ap.add_argument("--out", required=True)
    ap.add_argument("--net", action="append", default=[], help="LABEL=W.ttw (repeatable)")
    ap.add_argument("--default", default=None, help="the label whose goals the table checks")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--skip", type=int, default=8)
    ap.add_argument("--ppd", type=float, default=67.0)
    ap.add_argument("--no-flip", action="store_true")
    ap.add_argument("--no-linear", action="store_true", help="leave out vctaa resolve=linear")
    ap.add_argument("--jumps", action="append", default=[], help="NAME:F0:F1 (e.g. pillars:80:84)")
    a = ap.parse_args()
    if a.replot:
        try:
            results = json.load(open(os.path.join(a.out, "eval.json")))
            a.methods = [(q["method"], None) for q in results[0]["methods"]]
        except (OSError, ValueError, KeyError, IndexError) as e:
            fail(f"--replot: {os.path.join(a.out, 'eval.json')}: {e}")
        print(f"chart: {plot_summary(a, results)}")
        return
    if not a.seqs:
        fail("expected SEQ_DIR... (or --replot --out OUT)")
    a.host = host.find(a.host)
    methods = [("input", ["--set", "post_taa.mode=none"]), ("vctaa", ["--set", "post_taa.mode=vctaa"])]
    if not a.no_linear:
        methods.append(("vctaa-linear", ["--set", "post_taa.mode=vctaa", "--set",
                                         "post_taa.resolve=linear"]))
    nets = []
    for spec in a.net:
        if "=" not in spec:
            fail(f"--net {spec}: expected LABEL=FILE.ttw")
        label, w = spec.split("=", 1)
        if not os.path.exists(w):
            fail(f"--net {spec}: {w} does not exist")
        nets.append(label)
        methods.append((label, ["--set", "post_taa.mode=network", "--set",
                                f"post_taa.weights={os.path.abspath(w)}"]))
    a.methods = methods
    if a.default and a.default not in nets:
        fail(f"--default {a.default}: not one of the --net labels ({', '.join(nets)})")
    os.makedirs(a.out, exist_ok=True)
    results = []
    for seq in a.seqs:
        res = evaluate_seq(a, seq, methods)
        res["curves"] = plot_seq(a, res)
        results.append(res)
    text = table(a, results, nets) + "\n" + jumps(a, results)
    print("\n" + text)
    print(f"chart: {plot_summary(a, results)}")
    with open(os.path.join(a.out, "table.md.tmp"), "w") as f:
        f.write(text)
    os.replace(os.path.join(a.out, "table.md.tmp"), os.path.join(a.out, "table.md"))
    json.dump(results, open(os.path.join(a.out, "eval.json.tmp"), "w"), indent=1)
    os.replace(os.path.join(a.out, "eval.json.tmp"), os.path.join(a.out, "eval.json"))


if __name__ == "__main__":
    main()
