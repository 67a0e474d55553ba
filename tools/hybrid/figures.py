"""Charts of tools/hybrid/evaluate.py (thesis Figures 3.16-3.21, leave-one-scene-out, the
model studies) from its per-camera rows. matplotlib only; PNGs into the output folder."""
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLORS = {"nn": "#1f77b4", "rbf": "#2ca02c", "static": "#7f7f7f"}
LABELS = {"nn": "nearest neighbour", "rbf": "RBF (Greedy-GQ)", "static": "best static"}
OBJ = {"render": "render time", "build+render": "build + render time"}


def _sel(rows, objective, variant="default", split=True):
    return [r for r in rows if r["variant"] == variant and r["objective"] == objective and
            r["protocol"].startswith(("split", "heldout") if split else "loso")]


def _boxes(ax, rows, key, scenes, models, log=False):
    width = 0.8 / len(models)
    for mi, m in enumerate(models):
        data = [[r[key] for r in rows if r["scene"] == s and r["model"] == m and
                 r[key] is not None and math.isfinite(r[key]) and (not log or r[key] > 0)]
                for s in scenes]
        pos = [i + (mi - (len(models) - 1) / 2) * width for i in range(len(scenes))]
        keep = [(p, d) for p, d in zip(pos, data) if d]
        if not keep:
            continue
        bp = ax.boxplot([d for _, d in keep], positions=[p for p, _ in keep], widths=width * 0.85,
                        patch_artist=True, showfliers=True, flierprops={"markersize": 3})
        for b in bp["boxes"]:
            b.set_facecolor(COLORS[m])
            b.set_alpha(0.55)
        ax.plot([], [], color=COLORS[m], lw=6, alpha=0.55, label=LABELS[m])
    ax.set_xticks(range(len(scenes)))
    ax.set_xticklabels(scenes, rotation=30, ha="right")
    if log:
        _log_y(ax)
    ax.axhline(1.0, color="k", lw=0.8, ls="--")
    ax.legend(fontsize=8)


def _log_y(ax):
    """A log y axis labelled in plain numbers (0.9, 1, 1.5 rather than 9 x 10^-1)."""
    from matplotlib.ticker import ScalarFormatter
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(ScalarFormatter())
    ax.yaxis.set_minor_formatter(ScalarFormatter())


def _save(fig, out, name):
    fig.tight_layout()
    fig.savefig(os.path.join(out, name), dpi=110)
    plt.close(fig)


def draw(rows, summary, out):
    models = [m for m in ("nn", "rbf", "static") if any(r["model"] == m for r in rows)]
    scenes = sorted({r["scene"] for r in rows})
    figs = {"render": ("fig3_17_speedup_render.png", "fig3_18_roofline_render.png"),
            "build+render": ("fig3_20_speedup_total.png", "fig3_21_roofline_total.png")}
    for o, (fs, fr) in figs.items():
        sel = _sel(rows, o)
        if not sel:
            continue
        fig, ax = plt.subplots(figsize=(9, 4.2))
        _boxes(ax, sel, "speedup", scenes, models, log=True)
        ax.set_ylabel("speed-up over the search (log)")
        t = summary["table"]
        ax.set_title(f"Prediction vs Nelder-Mead search, {OBJ[o]} (geo-means: " +
                     ", ".join(f"{m} {t[f'{o}/{m}']['speedup']:.2f}" for m in models if f"{o}/{m}" in t) + ")",
                     fontsize=10)
        _save(fig, out, fs)
        fig, ax = plt.subplots(figsize=(9, 4.2))
        for mi, m in enumerate(models):
            for si, s in enumerate(scenes):
                ys = [r["roofline"] for r in sel if r["scene"] == s and r["model"] == m]
                xs = [si + (mi - (len(models) - 1) / 2) * 0.25 + 0.04 * ((k * 7919) % 11 - 5) / 5
                      for k in range(len(ys))]
                ax.scatter(xs, ys, s=9, color=COLORS[m], alpha=0.6, label=LABELS[m] if si == 0 else None)
        ax.axhline(1.0, color="k", lw=0.8, ls="--")
        ax.set_xticks(range(len(scenes)))
        ax.set_xticklabels(scenes, rotation=30, ha="right")
        _log_y(ax)
        ax.set_ylabel("roofline / predicted cost\n(1: as good as the search's best)")
        ax.set_title(f"Fraction of the roofline per camera, {OBJ[o]} (geo-means: " +
                     ", ".join(f"{m} {t[f'{o}/{m}']['roofline']:.3f}" for m in models if f"{o}/{m}" in t) + ")",
                     fontsize=10)
        ax.legend(fontsize=8)
        _save(fig, out, fr)
    # Fig. 3.16: one camera's search curve, its roofline and the predictions (render time)
    ex = summary.get("example")
    if ex:
        fig, ax = plt.subplots(figsize=(8, 4))
        d = ex["default_ms"]
        ys = [c * d for c in ex["search"]]
        xs = list(range(len(ys)))
        b = ex["roofline"] * d
        ax.plot(xs, ys, color="k", lw=1.2, label="Nelder-Mead search (measured per iteration)")
        ax.fill_between(xs, [b] * len(xs), ys, where=[y > b for y in ys], color="#ff7f0e", alpha=0.35,
                        label=f"search overhead over its best: {sum(y - b for y in ys if y > b) / d:.1f} default frames")
        ax.axhline(b, color="#9467bd", ls="--", lw=1.5, label="roofline (the search's best)")
        for m, p in sorted(ex["predicted"].items()):
            if p is None:
                continue
            ax.axhline(p * d, color=COLORS[m], lw=1.5, label=f"{LABELS[m]} prediction ({ex['roofline'] / p:.2f} of the roofline)")
            if m == "nn":
                ax.fill_between(xs, [b] * len(xs), [p * d] * len(xs), facecolor="none", hatch="//",
                                edgecolor=COLORS[m], lw=0)
        ax.set_xlabel("iteration (frame)")
        ax.set_ylabel(f"{OBJ[ex['objective']]} per frame (ms, CPU)")
        ax.set_title(f"Tuning vs prediction at {ex['scene']} camera {ex['camera']} ({ex['protocol']}: "
                     f"camera not in the training set)", fontsize=9)
        ax.legend(fontsize=7)
        _save(fig, out, "fig3_16_example.png")
    # Fig. 3.19: break-even iterations (render)
    sel = _sel(rows, "render")
    if sel:
        fig, ax = plt.subplots(figsize=(8, 4))
        for m in models:
            be = [r["break_even"] for r in sel if r["model"] == m and math.isfinite(r["break_even"])]
            pos = [x for x in be if 0 < x < 10000]
            neg = sum(1 for x in be if x < 0)
            if pos:
                ax.hist(pos, bins=[10 ** (k / 8) for k in range(0, 33)], alpha=0.5, color=COLORS[m],
                        label=f"{LABELS[m]}: mean {sum(pos) / len(pos):.0f}, {neg} of {len(be)} negative")
        ax.set_xscale("log")
        ax.set_xlabel("search iterations to break even with the prediction")
        ax.set_ylabel("cameras x splits")
        ax.set_title("Break-even points of the search (render time); negative (not shown): the "
                     "prediction beat the search", fontsize=9)
        ax.legend(fontsize=8)
        _save(fig, out, "fig3_19_break_even_render.png")
    # leave-one-scene-out against in-scene
    for o in ("render", "build+render"):
        ps = summary["per_scene"]
        if not any(f"{o}/{m}" in ps for m in models):
            continue
        fig, ax = plt.subplots(figsize=(9, 4))
        w = 0.8 / (2 * len(models))
        for mi, m in enumerate(models):
            d = ps.get(f"{o}/{m}", {})
            for j, (key, hatch) in enumerate((("speedup", None), ("loso_speedup", "//"))):
                xs = [i + (2 * mi + j - len(models) + 0.5) * w for i in range(len(scenes))]
                ys = [d.get(s, {}).get(key, float("nan")) for s in scenes]
                ax.bar(xs, ys, width=w, color=COLORS[m], alpha=0.6, hatch=hatch,
                       label=f"{LABELS[m]}{' (scene left out)' if j else ' (80/20)'}")
        ax.axhline(1.0, color="k", lw=0.8, ls="--")
        ax.set_xticks(range(len(scenes)))
        ax.set_xticklabels(scenes, rotation=30, ha="right")
        ax.set_ylabel("geo-mean speed-up over the search")
        ax.set_title(f"In-scene (80/20 x splits) vs leave-one-scene-out, {OBJ[o]}", fontsize=10)
        ax.legend(fontsize=7, ncol=2)
        _save(fig, out, f"loso_{o.replace('+', '_')}.png")
    # model size: RBF features and NN table size
    st = summary.get("studies", {})
    for study, model, label in (("features", "rbf", "RBF features"), ("table", "nn", "NN stored states")):
        for o in ("render", "build+render"):
            pts = []
            for k, v in st.items():
                name, obj, m = k.split("/")
                if name.startswith(study + "-") and obj == o and m == model:
                    pts.append((v["entries"], v["roofline"], v["memory_bytes"], v["predict_ms_median"]))
            base = summary["table"].get(f"{o}/{model}")
            if base:
                pts.append((base["entries"], base["roofline"], base["memory_bytes"], base["predict_ms_median"]))
            pts = sorted(p for p in pts if p[0])
            if len(pts) < 2:
                continue
            fig, ax = plt.subplots(figsize=(6, 3.6))
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", color=COLORS[model])
            ax.set_xscale("log")
            ax.set_xlabel(label)
            ax.set_ylabel("fraction of the roofline (geo-mean)")
            ax2 = ax.twinx()
            ax2.plot([p[0] for p in pts], [p[2] / 1024 for p in pts], "s--", color="#d62728", alpha=0.6)
            ax2.set_ylabel("model memory (KiB)", color="#d62728")
            ax.set_title(f"{label}: quality and size, {OBJ[o]}", fontsize=10)
            _save(fig, out, f"size_{study}_{o.replace('+', '_')}.png")
