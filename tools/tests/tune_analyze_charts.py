"""What tools/tuning/analyze.py's charts show, checked on the figures analyze.run returns,
over the data tune_analyze.sh gathers in DIR (e.db: host --explore; render.json and
build+render.json: tuning runs with --verify):
  leafsize, costs  the red marker of the best configurations has a legend entry;
  costs            log-axis ticks read as plain numbers (0.5, 1, 2; not 6x10^-1);
  blocksize        points (median, quartile bars) at the sampled sahBlockSize values only,
                   ticked at them: no steps or bands over values never sampled;
  convergence      each run's default line is the default as its tuning measured it (the
                   stats' default_cost, not the verify median), and each run has a best-so-far
                   line, the running minimum of its passes from that default.

  /usr/bin/python3 -m tools.tests.tune_analyze_charts DIR
"""
import json
import math
import sys

from tools.tttools import db


def legend_texts(ax):
    lg = ax.get_legend()
    return [t.get_text() for t in lg.get_texts()] if lg else []


def check_leafsize(analyze, d):
    fig = analyze.run(["leafsize", "--db", d + "/e.db", "-o", d + "/leaf2.png"])
    maps = [ax for ax in fig.axes if ax.get_xlabel() == "minLeafSize"]
    assert len(maps) == 3, len(maps)
    for ax in maps:
        red = [ln for ln in ax.get_lines() if ln.get_color() == "r"]
        assert red, "leafsize: no red marker"
        assert red[0].get_label() in legend_texts(ax), (red[0].get_label(), legend_texts(ax))


def check_costs(analyze, d):
    fig = analyze.run(["costs", "--db", d + "/e.db", "--metric", "total", "-o", d + "/costs2.png"])
    ax = fig.axes[0]
    red = [ln for ln in ax.get_lines() if ln.get_markeredgecolor() == "red"]
    assert len(red) == 1 and red[0].get_label() in legend_texts(ax), legend_texts(ax)
    fig.canvas.draw()
    labels = [t.get_text() for axis in (ax.xaxis, ax.yaxis)
              for t in axis.get_ticklabels(which="both") if t.get_text()]
    assert labels, "costs: no tick labels"
    for t in labels:
        try:
            float(t)
        except ValueError:
            raise AssertionError(f"costs: tick label {t!r} is not a plain number") from None


def check_blocksize(analyze, d):
    from matplotlib.collections import PolyCollection
    fig = analyze.run(["blocksize", "--db", d + "/e.db", "-o", d + "/block2.png"])
    sampled = {int(r["config"]["sahBlockSize"]) for r in db.samples(d + "/e.db", "accel_embree")
               if db.ok(r)}
    for ax in fig.axes:
        assert not any(isinstance(c, PolyCollection) for c in ax.collections), "blocksize: a band"
        for ln in ax.get_lines():
            assert ln.get_drawstyle() == "default" and ln.get_linestyle() in ("None", "none", ""), \
                ("blocksize: a line between values", ln.get_drawstyle(), ln.get_linestyle())
            assert {int(x) for x in ln.get_xdata()} <= sampled, (list(ln.get_xdata()), sampled)
    ticks = sorted(int(t) for t in fig.axes[1].get_xticks())
    assert ticks == sorted(sampled), (ticks, sampled)


def check_convergence(analyze, d):
    objs = ("render", "build+render")
    fig = analyze.run(["convergence"] + [f"{d}/{o}.json" for o in objs] + ["-o", d + "/conv2.png"])
    stats = {o: json.load(open(f"{d}/{o}.json"))["tuning"] for o in objs}
    for ax, obj in zip(fig.axes, objs):
        lines = {ln.get_label(): ln for ln in ax.get_lines()}
        t = stats[obj]
        dl = [ln for k, ln in lines.items() if k.endswith(f"tuned for {obj}: default (as tuning measured it)")]
        assert len(dl) == 1, list(lines)
        y = dl[0].get_ydata()[0]
        assert abs(y - t["default_cost"]) < 1e-9, (y, t["default_cost"])
        assert abs(y - t["verify"]["default"]["median_cost"]) > 1e-9, "the verify median"
        for o in objs:
            best = lines[f"tuner_random, tuned for {o}: best so far"].get_ydata()
            each = lines[f"tuner_random, tuned for {o}: each pass"].get_ydata()
            run = stats[o]["default_cost"] if o == obj else math.inf
            assert len(best) == len(each) > 0
            for b, e in zip(best, each):
                run = min(run, e)
                assert abs(b - run) < 1e-9, (o, list(best), list(each))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    from tools.tuning import analyze
    d = sys.argv[1]
    for check in (check_leafsize, check_costs, check_blocksize, check_convergence):
        check(analyze, d)
        print(f"tune_analyze_charts: {check.__name__[6:]} ok")


if __name__ == "__main__":
    main()
