#!/usr/bin/python3
"""Renders the Cornell box with the path tracer into numpy, tunes Embree's BVH parameters for
render time with Nelder-Mead (thesis ch. 3), renders on with the best configuration, and
writes the image with its normal and albedo AOVs (what a denoiser takes) as one EXR.

    PYTHONPATH=build/python /usr/bin/python3 python/examples/render_and_tune.py
        [--scene scenes/cornell-box/scene.json] [--res 128x128] [--spp 16]
        [--iterations 10] [--out example]
"""
import argparse

import numpy as np

import tunetrace as tt


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="scenes/cornell-box/scene.json")
    ap.add_argument("--res", default="128x128", help="WIDTHxHEIGHT")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--iterations", type=int, default=10)
    ap.add_argument("--db", default=None,
                    help="tuning database (default: the per-user one, as host)")
    ap.add_argument("--no-db", action="store_true", help="tune without a database")
    ap.add_argument("--out", default="example", help="output stem: STEM.exr")
    a = ap.parse_args()
    w, h = (int(v) for v in a.res.split("x"))

    with tt.Session(a.scene, plugins=["integrator_pt", "tuner_nm"], resolution=(w, h),
                    aovs=["normal", "albedo"]) as s:
        s.set("integrator_pt.maxDepth", 5)
        t = s.tune("accel_embree", tuner="tuner_nm", iterations=a.iterations,
                   db=False if a.no_db else a.db)
        print(f"tuning: {len(t.history)} samples, default {t.default_cost:.2f} ms, "
              f"best {t.best_cost:.2f} ms: {t.best_config}")
        rgb = s.render(spp=a.spp)
        normal, albedo = s.aov("normal"), s.aov("albedo")
        st = s.stats
        print(f"rendered {st['spp']} spp in {st['render_ms']:.0f} ms; mean RGB "
              f"{np.round(rgb.mean(axis=(0, 1)), 4)}")

    # one EXR, the layers named as denoisers and compositors read them
    tt.write_exr(f"{a.out}.exr", np.concatenate([rgb, normal, albedo], axis=2),
                 ["R", "G", "B", "normal.X", "normal.Y", "normal.Z", "albedo.R", "albedo.G",
                  "albedo.B"], {"software": f"tunetrace {tt.version()} (Python)"})
    print(f"wrote {a.out}.exr")


if __name__ == "__main__":
    main()
