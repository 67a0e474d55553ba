"""tools/taa's test-set tools, without rendering:
- make_test_set.py: one camera key per frame at f / 24 s, the first the scene's own first
  key; the per-frame step is small in frames 0-7, about 8x larger in 8-15 (fast), largest
  at 15 -> 16 (the jump, to the scene's third key), and medium after; the wrapper imports
  the scene file itself (imports do not nest); a bad --res or scene name is refused;
- test_report.py on a made-up evaluation (10 frames of 4x4, one emitter pixel of 100):
  the goal flags follow the ratios (RMSE x VCTAA <= 0.8, temporal <= 1, mean within 3%),
  the clamped mean of an output that clips the emitter to 1 is exactly 1 while its linear
  mean is far below; an eval.json without the vctaa row is refused naming the file;
- make_test_set.py --set train / val / test: the three sets' scenes (the files they import)
  are disjoint; --offset K starts at the path's key K and names the sequence NAME-kK; an
  offset past the path's keys is refused naming the file;
- moving_report.py on a made-up sequence (static camera, 4 pixels uncovered every frame):
  the disocclusion region is those pixels grown by one (16 of 64), the region errors are
  measured there only (an error outside it does not count), the ratios to VCTAA and goal
  flags follow; a sequence without the prevdepth AOV is refused naming the file and field;
- select_val.py's rule on a made-up validation: most goals met first, then the smallest
  network within 1% of the best geo-mean RMSE (a smaller one 0.5% behind is chosen, 1.5%
  behind is not; one that meets fewer goals is not, however good its RMSE);
- the shipped default: select_val.py on the committed validation evaluation
  (tools/taa/figures/validation_eval.json) chooses the network post_taa loads by default
  (`host --describe post_taa`'s `channels`), and the committed test-set and moving-object
  reports hold that network's rows."""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

from tools.tests import checks
from tools.tests.checks import check

root = os.environ.get("TT_SOURCE_ROOT", ".")


def run(*args):
    return subprocess.run([sys.executable, "-m", *args], capture_output=True, text=True, cwd=root)


def write_exr(path, px):
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(px.shape[1], px.shape[0], 3, "float"))
    out.write_image(px.astype(np.float32))
    out.close()


def test_make_test_set(tmp):
    r = run("tools.taa.make_test_set", tmp, "--scenes", "cornell-box,killeroos")
    check(r.returncode == 0, f"make_test_set runs ({r.stderr.strip()[:200]})")
    if r.returncode:
        return
    sc = json.load(open(os.path.join(tmp, "killeroos", "scene.json")))
    src = json.load(open(os.path.join(root, "scenes", "killeroos", "scene.json")))
    keys = sc["camera"]["path"]
    check(len(keys) == 24 and all(abs(k["time"] - f / 24) < 1e-9 for f, k in enumerate(keys)),
          "24 keys at f / 24 s")
    check(keys[0]["position"] == src["camera"]["path"][0]["position"], "frame 0 is the scene's first key")
    check(keys[16]["position"] == src["camera"]["path"][2]["position"], "frame 16 is the scene's third key")
    step = [float(np.linalg.norm(np.subtract(keys[f]["position"], keys[f - 1]["position"])))
            for f in range(1, 24)]
    slow, fast, jump, medium = max(step[0:7]), min(step[8:14]), step[15], max(step[16:])
    check(0 < slow * 5 < fast and fast * 3 < jump and medium * 3 < jump,
          f"slow {slow:.2f} < fast {fast:.2f} < jump {jump:.1f}, medium {medium:.2f}")
    check(sc["camera"]["resolution"] == [160, 90], "160x90 by default")
    check(os.path.exists(sc["import"]) and sc["import"].endswith("killeroo-simple.pbrt"),
          "imports the pbrt file the scene's wrapper imports")
    box = json.load(open(os.path.join(tmp, "cornell-box", "scene.json")))
    check(box["import"].endswith(os.path.join("cornell-box", "scene.json")),
          "cornell-box imports scene.json (path.json is a wrapper)")
    r = run("tools.taa.make_test_set", tmp, "--scenes", "nosuch")
    check(r.returncode != 0 and "unknown scene 'nosuch'" in r.stderr, "an unknown scene is refused")
    r = run("tools.taa.make_test_set", tmp, "--res", "160")
    check(r.returncode != 0 and "--res" in r.stderr, "a bad --res is refused")


def test_report(tmp):
    n, skip = 10, 8
    ref = np.full((4, 4, 3), 0.5)
    ref[1, 1] = 100.0  # an emitter: most of the linear mean
    seq = os.path.join(tmp, "data", "box-spp1")
    os.makedirs(seq)
    frames = []
    for f in range(n):
        write_exr(os.path.join(seq, f"reference_{f:04d}.exr"), ref)
        frames.append({"index": f, "reference": f"reference_{f:04d}.exr"})
    json.dump({"frames": frames}, open(os.path.join(seq, "manifest.json"), "w"))
    ev = os.path.join(tmp, "eval")
    clipped = np.minimum(ref, 1.0)
    for m, img in (("input", ref), ("vctaa", clipped * 0.9), ("c12", clipped)):
        d = os.path.join(ev, "box-spp1", m)
        os.makedirs(d)
        for f in range(n):
            write_exr(os.path.join(d, f"post_{f:04d}.exr"), img)
        json.dump({"frames": [{"post": f"post_{f:04d}.exr"} for f in range(n)]},
                  open(os.path.join(d, "manifest.json"), "w"))
    rows = [("input", 0.1, 0.05, 1.0), ("vctaa", 0.02, 0.010, 0.9), ("c12", 0.015, 0.011, 0.98)]
    res = [{"sequence": "box-spp1", "folder": seq, "frames": n, "spp": 1,
            "methods": [{"method": m, "rmse": r, "temporal": t, "brightness": b} for m, r, t, b in rows]}]
    json.dump(res, open(os.path.join(ev, "eval.json"), "w"))
    out = os.path.join(tmp, "report.json")
    r = run("tools.taa.test_report", os.path.join(ev, "eval.json"), "--nets", "c12", "--json", out)
    check(r.returncode == 0, f"test_report runs ({r.stderr.strip()[:200]})")
    if r.returncode:
        return
    c = json.load(open(out))["sequences"][0]["methods"]["c12"]
    check(c["met"] == {"rmse": True, "temporal": False, "mean": True},
          f"goal flags: 0.75x RMSE yes, 1.1x temporal no, mean 0.98 yes ({c['met']})")
    check(abs(c["rmse_vs_vctaa"] - 0.75) < 1e-4 and abs(c["temporal_vs_vctaa"] - 1.1) < 1e-4,
          "ratios to VCTAA")
    check(c["clamped_mean_vs_reference"] == 1.0, f"clamped mean of the clipped output is 1 "
          f"({c['clamped_mean_vs_reference']})")
    lin = np.minimum(ref, 1.0).mean() / ref.mean()
    check(lin < 0.2, f"while its linear mean is {lin:.3f} of the reference's")
    check("c12: all three goals met on 0 of 1" in r.stdout, "the summary line counts sequences")
    res[0]["methods"] = res[0]["methods"][:1]
    bad = os.path.join(ev, "bad.json")
    json.dump(res, open(bad, "w"))
    r = run("tools.taa.test_report", bad, "--nets", "c12")
    check(r.returncode != 0 and "bad.json" in r.stderr and "no vctaa row" in r.stderr,
          "an evaluation without VCTAA is refused naming the file")


def test_sets(tmp):
    imports = {}
    for st in ("train", "val", "test"):
        d = os.path.join(tmp, st)
        r = run("tools.taa.make_test_set", d, "--set", st)
        check(r.returncode == 0, f"make_test_set --set {st} runs ({r.stderr.strip()[:200]})")
        if r.returncode:
            return
        names = sorted(os.listdir(d))
        imports[st] = {json.load(open(os.path.join(d, n, "scene.json")))["import"] for n in names}
        check(len(imports[st]) == len(names) >= 2, f"--set {st}: {len(names)} scenes, each its own file")
    check(not (imports["train"] & imports["val"]) and not (imports["train"] & imports["test"])
          and not (imports["val"] & imports["test"]), "training, validation and test scenes are disjoint")
    d = os.path.join(tmp, "off")
    r = run("tools.taa.make_test_set", d, "--scenes", "staircase", "--offset", "2")
    check(r.returncode == 0 and os.path.exists(os.path.join(d, "staircase-k2", "scene.json")),
          f"--offset 2 writes staircase-k2 ({r.stderr.strip()[:200]})")
    if r.returncode == 0:
        keys = json.load(open(os.path.join(d, "staircase-k2", "scene.json")))["camera"]["path"]
        src = json.load(open(os.path.join(root, "scenes", "staircase", "scene.json")))["camera"]["path"]
        check(keys[0]["position"] == src[2]["position"] and keys[16]["position"] == src[4]["position"],
              "--offset 2: frame 0 is key 2, frame 16 key 4")
    r = run("tools.taa.make_test_set", d, "--scenes", "killeroos", "--offset", "50")
    check(r.returncode != 0 and "camera.path" in r.stderr and "--offset 50" in r.stderr,
          f"an offset past the path's keys is refused ({r.stderr.strip()[:200]})")


def test_moving_report(tmp):
    n, size = 12, 8
    seq = os.path.join(tmp, "mv", "obj-spp1")
    os.makedirs(seq)
    ref = np.full((size, size, 3), 0.25)
    one = np.ones((size, size, 3))
    zp = one.copy()
    zp[3:5, 3:5] = 2.0  # these 4 points were farther away one frame ago: uncovered now
    frames = []
    for f in range(n):
        for k, img in (("reference", ref), ("depth", one), ("prev_depth", zp),
                       ("motion", np.zeros((size, size, 3)))):
            write_exr(os.path.join(seq, f"{k}_{f:04d}.exr"), img)
        frames.append({"index": f, "jitter": [0.0, 0.0], "jitter_index": f % 8,
                       **{k: f"{k}_{f:04d}.exr" for k in ("reference", "depth", "prev_depth", "motion")}})
    json.dump({"frames": frames}, open(os.path.join(seq, "manifest.json"), "w"))
    ev = os.path.join(tmp, "mv", "eval")
    inside = np.zeros((size, size, 1), bool)
    inside[2:6, 2:6] = True
    for m, err_in, err_out in (("vctaa", 0.2, 0.0), ("c12", 0.1, 0.3)):
        d = os.path.join(ev, "obj-spp1", m)
        os.makedirs(d)
        img = ref + np.where(inside, err_in, err_out)
        for f in range(n):
            write_exr(os.path.join(d, f"post_{f:04d}.exr"), img)
        json.dump({"frames": [{"post": f"post_{f:04d}.exr"} for f in range(n)]},
                  open(os.path.join(d, "manifest.json"), "w"))
    rows = [("vctaa", 0.02, 0.010), ("c12", 0.015, 0.009)]
    res = [{"sequence": "obj-spp1", "folder": seq, "frames": n, "spp": 1,
            "methods": [{"method": m, "rmse": r, "temporal": t, "brightness": 1.0} for m, r, t in rows]}]
    json.dump(res, open(os.path.join(ev, "eval.json"), "w"))
    out = os.path.join(tmp, "mv", "report.json")
    r = run("tools.taa.moving_report", os.path.join(ev, "eval.json"), "--nets", "c12", "--json", out)
    check(r.returncode == 0, f"moving_report runs ({r.stderr.strip()[-600:]})")
    if r.returncode:
        return
    sq = json.load(open(out))["sequences"][0]
    check(abs(sq["region_fraction"] - 16 / 64) < 1e-9, f"region: 4 pixels grown by one = 16 of 64 "
          f"({sq['region_fraction']})")
    c, v = sq["methods"]["c12"], sq["methods"]["vctaa"]
    tm = lambda x: x / (1 + x)  # noqa: E731  (grey: max channel = the value)
    check(abs(v["region_rmse"] - (tm(0.45) - tm(0.25))) < 1e-5 and
          abs(c["region_rmse"] - (tm(0.35) - tm(0.25))) < 1e-5,
          f"region RMSE from the region's pixels only ({v['region_rmse']}, {c['region_rmse']})")
    check(c["region_temporal"] == 0.0, "a still output has no temporal error")
    check(c["met"] == {"rmse": True, "temporal": True} and abs(c["rmse_vs_vctaa"] - 0.75) < 1e-4,
          f"whole-frame goal flags from eval.json ({c['met']})")
    os.remove(os.path.join(seq, "manifest.json"))
    for fr in frames:
        del fr["prev_depth"]
    json.dump({"frames": frames}, open(os.path.join(seq, "manifest.json"), "w"))
    r = run("tools.taa.moving_report", os.path.join(ev, "eval.json"), "--nets", "c12")
    check(r.returncode != 0 and "manifest.json" in r.stderr and "prev_depth" in r.stderr,
          f"a sequence without prevdepth is refused naming file and field ({r.stderr.strip()[:200]})")


def test_select(tmp):
    os.makedirs(tmp)
    big = os.path.join(root, "plugins", "post_taa", "post_taa_c12.ttw")
    small = os.path.join(root, "plugins", "post_taa", "post_taa_c6.ttw")

    def evaluation(b_factor):
        # two sequences; vctaa RMSE 0.02 / temporal 0.01 on both
        res = []
        for i, sq in enumerate(("a-spp1", "a-spp8")):
            ms = [("vctaa", 0.02, 0.01), ("big", 0.014, 0.009), ("small", 0.014 * b_factor, 0.009),
                  ("tiny", 0.010, 0.011 if i else 0.009)]   # tiny misses temporal on one
            res.append({"sequence": sq, "spp": 1, "frames": 24,
                        "methods": [{"method": m, "rmse": r, "temporal": t, "brightness": 1.0}
                                    for m, r, t in ms]})
        path = os.path.join(tmp, f"eval{b_factor}.json")
        json.dump(res, open(path, "w"))
        return path

    nets = [f"big={big}", f"small={small}", f"tiny={small}"]
    for factor, want in ((1.005, "small"), (1.015, "big")):
        out = os.path.join(tmp, "sel.json")
        r = run("tools.taa.select_val", evaluation(factor), *nets, "--json", out)
        check(r.returncode == 0, f"select_val runs ({r.stderr.strip()[-300:]})")
        if r.returncode:
            return
        d = json.load(open(out))
        check(d["chosen"] == want, f"small network {100 * (factor - 1):.1f}% behind: {want} "
              f"chosen ({d['chosen']})")
        tiny = next(x for x in d["rows"] if x["net"] == "tiny")
        check(tiny["met"] == 1 and d["rows"][-1]["net"] == "tiny",
              "fewer goals met ranks last despite the lowest RMSE")
    r = run("tools.taa.select_val", evaluation(1.0), "big=" + os.path.join(tmp, "none.ttw"))
    check(r.returncode != 0 and "none.ttw" in r.stderr, "a missing weights file is refused naming it")


def test_shipped_default(tmp):
    os.makedirs(tmp)
    figs = os.path.join(root, "tools", "taa", "figures")
    nets = [f"c{w}=" + os.path.join(root, "plugins", "post_taa", f"post_taa_c{w}.ttw") for w in (12, 6)]
    out = os.path.join(tmp, "choice.json")
    r = run("tools.taa.select_val", os.path.join(figs, "validation_eval.json"), *nets, "--json", out)
    check(r.returncode == 0, f"select_val runs on the committed validation ({r.stderr.strip()[-300:]})")
    if r.returncode:
        return
    chosen = json.load(open(out))["chosen"]
    committed = json.load(open(os.path.join(figs, "validation_choice.json")))["chosen"]
    check(chosen == committed, f"the committed choice is the rule's ({committed} vs {chosen})")
    exe = os.environ.get("TT_HOST", os.path.join(root, "build", "host", "host"))
    d = subprocess.run([exe, "--describe", "post_taa"], capture_output=True, text=True)
    check(d.returncode == 0, f"host --describe post_taa runs ({d.stderr.strip()[-300:]})")
    if d.returncode:
        return
    par = {p["name"]: p for p in json.loads(d.stdout)["parameters"]}
    default = f"c{par['channels']['value']}"
    check(default == chosen, f"post_taa's default network {default} is the validation rule's {chosen}")
    for name in ("test_set.json", "moving_objects.json"):
        seqs = json.load(open(os.path.join(figs, name)))["sequences"]
        check(seqs and all(chosen in sq["methods"] for sq in seqs),
              f"{name} reports the shipped network {chosen} on all {len(seqs)} sequences")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        test_select(os.path.join(tmp, "sel"))
        test_shipped_default(os.path.join(tmp, "shipped"))
        test_make_test_set(os.path.join(tmp, "scenes"))
        test_report(tmp)
        test_sets(os.path.join(tmp, "sets"))
        test_moving_report(tmp)
    print(f"{checks.failures} failure(s)")
    sys.exit(1 if checks.failures else 0)


if __name__ == "__main__":
    main()
