"""tools/charts/sampler_choice.py (the sampler default's measurement):
- its arithmetic: the log-log fit recovers c and a of err = c * spp^-a; time to an error
  follows (k * (c / E)^(1/a)), so a sampler converging at a = 1 against one at a = 0.5 with
  the same cost and error at spp 1 is 4x faster at error 1/2 of that; the reference-noise
  estimate (half-difference / 2) of two halves with known Gaussian noise is that noise;
- end to end on the Cornell box at 16x16 (spp 1 and 4, one seed, a 16-spp reference):
  the JSON has every sampler with positive errors and times, independent's speed-up over
  itself is exactly 1, the chart is a PNG; a bad --spps and an unknown scene are refused;
- --integrator integrator_bdpt --samplers independent,sobol: BDPT's own reference and
  renders, only those samplers, written to sampler_choice_integrator_bdpt.json/.png (the
  integrator_pt files untouched), and --summarize recomputes the same speed-ups from that
  JSON; an unknown integrator and a sampler list without independent are refused, naming
  the option."""
import json
import math
import os
import subprocess
import sys
import tempfile
from types import SimpleNamespace

import numpy as np

from tools.charts import sampler_choice as sc

from tools.tests import checks
from tools.tests.checks import check

root = os.environ.get("TT_SOURCE_ROOT", ".")


def run(*args):
    return subprocess.run([sys.executable, "-m", "tools.charts.sampler_choice", *args],
                          capture_output=True, text=True, cwd=root)


def test_math():
    spps = [4, 16, 64]
    c, a = sc.fit(spps, [0.8 * s ** -0.7 for s in spps])
    check(abs(c - 0.8) < 1e-9 and abs(a - 0.7) < 1e-9, f"fit recovers c 0.8, a 0.7 ({c}, {a})")
    t_half = sc.time_to(1.0, 0.5, 2.0, 0.5)    # (1 / 0.5)^2 = 4 spp at 2 s
    t_one = sc.time_to(1.0, 1.0, 2.0, 0.5)     # 2 spp
    check(abs(t_half - 8.0) < 1e-12 and abs(t_one - 4.0) < 1e-12,
          f"time_to: a 0.5 needs 8 s, a 1 needs 4 s ({t_half}, {t_one})")
    # Two halves with noise sigma on a reference of 1: the mean's noise is sigma / sqrt(2).
    rng = np.random.default_rng(3)
    with tempfile.TemporaryDirectory() as tmp:
        sigma = 0.05
        shape = (200, 200, 3)
        os.makedirs(os.path.join(tmp, "s"))
        args = SimpleNamespace(work=tmp, ref_spp=8, res="200x200")
        for seed in (0, 1):
            px = (1.0 + sigma * rng.standard_normal(shape[:2]))[..., None].repeat(3, axis=2)
            sc.write_exr(os.path.join(tmp, "s", f"ref_half{seed}_8spp_200x200.exr"),
                         px.astype(np.float32))
        ref, noise = sc.reference(args, "s", "unused")
        want = sigma / math.sqrt(2) / math.sqrt(1 + 1e-3)
        check(abs(noise - want) < 0.05 * want, f"reference noise {noise:.5f} ~ {want:.5f}")
        check(ref.shape == shape and os.path.exists(os.path.join(tmp, "s", "ref_8spp_200x200.exr")),
              "the averaged reference is written")


def test_end_to_end():
    with tempfile.TemporaryDirectory() as tmp:
        p = run("--scenes", "cornell-box", "--res", "16x16", "--spps", "1,4", "--seeds", "1",
                "--ref-spp", "16", "--out", os.path.join(tmp, "out"), "--work", os.path.join(tmp, "w"))
        check(p.returncode == 0, f"a tiny run exits 0 ({p.returncode}: {p.stderr[-800:]})")
        if p.returncode != 0:
            return
        doc = json.load(open(os.path.join(tmp, "out", "sampler_choice.json")))
        r = doc["scenes"]["cornell-box"]
        check(set(r["samplers"]) == set(sc.SAMPLERS), "every sampler measured")
        ok = all(p_["rrmse"] > 0 and p_["cpu_s"] > 0 for q in r["samplers"].values()
                 for p_ in q["points"])
        check(ok, "every error and CPU time is positive")
        sp = r["samplers"]["independent"]["speedup_vs_independent"]
        check(all(abs(v - 1.0) < 1e-12 for v in sp.values()), f"independent vs itself is 1x ({sp})")
        check(r["reference_noise"] > 0, "the reference's noise is estimated")
        with open(os.path.join(tmp, "out", "sampler_choice.png"), "rb") as f:
            check(f.read(8) == b"\x89PNG\r\n\x1a\n", "the chart is a PNG")
        check("| cornell-box | sobol |" in p.stdout, "the table has a row per scene and sampler")
    p = run("--spps", "4,x")
    check(p.returncode != 0 and "--spps" in p.stderr, "a bad --spps is refused naming it")
    p = run("--scenes", "nowhere")
    check(p.returncode != 0 and "nowhere" in p.stderr, "an unknown scene is refused naming it")


def test_integrator_option():
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out")
        p = run("--integrator", "integrator_bdpt", "--samplers", "independent,sobol",
                "--scenes", "cornell-box", "--res", "16x16", "--spps", "1,4", "--seeds", "1",
                "--ref-spp", "16", "--out", out, "--work", os.path.join(tmp, "w"))
        check(p.returncode == 0, f"a tiny BDPT run exits 0 ({p.returncode}: {p.stderr[-800:]})")
        if p.returncode != 0:
            return
        jpath = os.path.join(out, "sampler_choice_integrator_bdpt.json")
        check(os.path.exists(jpath) and not os.path.exists(os.path.join(out, "sampler_choice.json")),
              "BDPT's figures go to sampler_choice_integrator_bdpt.json, not integrator_pt's file")
        doc = json.load(open(jpath))
        r = doc["scenes"]["cornell-box"]
        check(doc["integrator"] == "integrator_bdpt" and doc["samplers"] == ["independent", "sobol"],
              f"the JSON names the integrator and samplers ({doc.get('integrator')}, {doc.get('samplers')})")
        check(set(r["samplers"]) == {"independent", "sobol"}, "only the samplers asked for are measured")
        check(os.path.exists(os.path.join(tmp, "w", "integrator_bdpt", "cornell-box",
                                          "ref_16spp_16x16.exr")),
              "the reference is BDPT's own, kept apart from integrator_pt's")
        with open(os.path.join(out, "sampler_choice_integrator_bdpt.png"), "rb") as f:
            check(f.read(8) == b"\x89PNG\r\n\x1a\n", "BDPT's chart is a PNG")
        check("integrator_bdpt, 16x16" in p.stdout and "| cornell-box | halton |" not in p.stdout,
              "the table names the integrator and has no halton row")
        sp = r["samplers"]["sobol"]["speedup_vs_independent"]
        q = run("--integrator", "integrator_bdpt", "--summarize", "--out", out)
        check(q.returncode == 0, f"--summarize on BDPT's JSON exits 0 ({q.stderr[-400:]})")
        again = json.load(open(jpath))["scenes"]["cornell-box"]["samplers"]["sobol"]["speedup_vs_independent"]
        check(all(abs(again[k] - sp[k]) < 1e-12 for k in sp), f"--summarize recomputes the speed-ups ({sp}, {again})")
    p = run("--integrator", "integrator_nowhere")
    check(p.returncode != 0 and "--integrator" in p.stderr and "integrator_nowhere" in p.stderr,
          "an unknown integrator is refused naming the option and the value")
    p = run("--samplers", "sobol,halton")
    check(p.returncode != 0 and "--samplers" in p.stderr and "independent" in p.stderr,
          "a sampler list without independent is refused, saying it is needed")
    p = run("--samplers", "independent,owen")
    check(p.returncode != 0 and "--samplers" in p.stderr, "an unknown sampler is refused naming the option")


def main():
    test_math()
    test_end_to_end()
    test_integrator_option()
    print(f"sampler_choice: {checks.failures} failed")
    return 1 if checks.failures else 0


if __name__ == "__main__":
    sys.exit(main())
