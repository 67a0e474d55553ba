#!/usr/bin/python3
"""host --aov for a still: the AOVs are named layers of the one EXR (depth.Z, normal.X/Y/Z,
albedo.R/G/B, motion.X/Y: what denoisers and compositors read), with known values on a plane
facing the camera (integrator_pt and integrator_pssmlt), anti-aliased like the colour (an edge pixel holds the mean over its
samples), motion against the previous frame of --camera-index; the colour is the same with
and without AOVs; sequences keep one file per AOV; a bad name is a usage error.

Reads the EXRs with OpenImageIO (python3-openimageio, tools/bootstrap.sh).
Environment: TT_BUILD_ROOT (tests/meson.build)."""
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tests", "support"))
from plane_scene import DISTANCE, MOVING_PATH, motion_pixels, pixel_size, plane, write  # noqa: E402

HOST = os.path.join(os.environ["TT_BUILD_ROOT"], "host", "host")
failures = checks = 0


def check(cond, what):
    global failures, checks
    checks += 1
    if not cond:
        failures += 1
        print(f"FAIL: {what}", file=sys.stderr)


def host(*args):
    r = subprocess.run([HOST, "--quiet", *args], capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


def read(path):
    """{channel name: (h, w) array}, the metadata dict."""
    inp = oiio.ImageInput.open(path)
    check(inp is not None, f"open {path}: {oiio.geterror()}")
    if inp is None:
        return {}, {}
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, spec.nchannels, "float")
    inp.close()
    meta = {a.name: a.value for a in spec.extra_attribs}
    return {n: px[:, :, i] for i, n in enumerate(spec.channelnames)}, meta


def main():
    with tempfile.TemporaryDirectory() as tmp:
        still = write(tmp, "plane.json", plane())
        exr = os.path.join(tmp, "still.exr")
        rc, out = host("--aov", "depth,normal,albedo,motion", "--spp", "4", "--out", exr, still)
        check(rc == 0, f"host --aov on a still: exit {rc}: {out}")
        ch, meta = read(exr)
        expected = {"R", "G", "B", "depth.Z", "normal.X", "normal.Y", "normal.Z", "albedo.R",
                    "albedo.G", "albedo.B", "motion.X", "motion.Y"}
        check(set(ch) == expected, f"EXR channels {sorted(ch)}")
        check("tunetrace:aovs" in meta, "the EXR says what the layers hold")
        if set(ch) == expected:
            check(np.allclose(ch["depth.Z"], 5.0, atol=1e-4), f"depth {ch['depth.Z'][6, 8]}")
            for c, v in zip("XYZ", (0, 0, -1)):
                check(np.allclose(ch["normal." + c], v, atol=1e-5), f"normal.{c} {ch['normal.' + c][6, 8]}")
            for c, v in zip("RGB", (0.2, 0.4, 0.6)):
                check(np.allclose(ch["albedo." + c], v, atol=1e-6), f"albedo.{c} {ch['albedo.' + c][6, 8]}")
            check(np.allclose(ch["motion.X"], 0) and np.allclose(ch["motion.Y"], 0),
                  "a still camera does not move")
            # the colour is the image rendered without AOVs, bit for bit
            plain = os.path.join(tmp, "plain.exr")
            rc, out = host("--spp", "4", "--out", plain, still)
            pc, _ = read(plain)
            check(rc == 0 and set(pc) == {"R", "G", "B"}, f"no --aov: RGB only ({sorted(pc)})")
            check(all(np.array_equal(pc[c], ch[c]) for c in "RGB" if c in pc),
                  "AOV layers leave the colour unchanged")
        check(os.path.exists(os.path.join(tmp, "still.png")), "the PNG is still written")

        # PSSMLT writes the same AOVs (a first-hit ray per pixel and pass of its own)
        mexr = os.path.join(tmp, "mlt.exr")
        rc, out = host("--plugin", "integrator_pssmlt", "--aov", "depth,normal,albedo", "--spp", "2",
                       "--out", mexr, still)
        mc, _ = read(mexr)
        check(rc == 0 and {"depth.Z", "normal.Z", "albedo.G"} <= set(mc), f"PSSMLT --aov: exit {rc}: {out}")
        if "depth.Z" in mc:
            check(np.allclose(mc["depth.Z"], 5.0, atol=1e-4) and np.allclose(mc["normal.Z"], -1, atol=1e-5)
                  and np.allclose(mc["albedo.G"], 0.4, atol=1e-6),
                  f"PSSMLT AOVs: depth {mc['depth.Z'][6, 8]}, normal.Z {mc['normal.Z'][6, 8]}, "
                  f"albedo.G {mc['albedo.G'][6, 8]}")

        # an edge through the middle of a pixel column: with 64 samples its albedo is the
        # covered fraction of the reflectance (anti-aliased), neither 0 nor 0.2
        half = 0.5 * pixel_size()  # the edge through the middle of a pixel column
        edge = write(tmp, "edge.json", plane(half_width=half))
        edge_exr = os.path.join(tmp, "edge.exr")
        rc, out = host("--aov", "albedo,depth", "--spp", "64", "--out", edge_exr, edge)
        ec, _ = read(edge_exr)
        row = ec.get("albedo.R", np.zeros((12, 16)))[6]
        mixed = [v for v in row if 0.03 < v < 0.17]
        check(rc == 0 and len(mixed) >= 1, f"an edge pixel averages its samples: row {np.round(row, 3)}")
        check(np.count_nonzero(np.isclose(row, 0.2, atol=1e-6)) >= 5 and
              np.count_nonzero(row == 0) >= 5, "covered and uncovered pixels on either side")

        # motion against the previous frame (1/24 s earlier) of a --camera-index sample: a
        # camera moving 1 unit/s along x, 5 units from the plane
        moving = write(tmp, "moving.json", plane(path=MOVING_PATH))
        mexr = os.path.join(tmp, "moving.exr")
        rc, out = host("--aov", "motion", "--camera-index", "50", "--spp", "2", "--out", mexr, moving)
        mc, _ = read(mexr)
        want = motion_pixels(1 / 24)
        mx = mc.get("motion.X", np.zeros((12, 16)))
        check(rc == 0 and np.allclose(mx, -want, rtol=1e-3),  # world +x is image left
              f"motion.X {mx[6, 8]} (expected {-want})")
        check(np.allclose(mc.get("motion.Y", np.ones(1)), 0, atol=1e-4), "motion.Y 0")

        # sequences keep one file per frame and AOV (normal and albedo too now)
        seq = os.path.join(tmp, "seq")
        rc, out = host("--frames", "0:1", "--out", seq + "/frame_%04d.exr", "--aov",
                       "depth,normal", "--spp", "1", moving)
        check(rc == 0, f"sequence with --aov: exit {rc}: {out}")
        for name, chans in [("frame_0000.exr", 3), ("frame_0001.exr", 3),
                            ("frame_0000.depth.exr", 1), ("frame_0001.normal.exr", 3)]:
            c, _ = read(os.path.join(seq, name))
            check(len(c) == chans, f"{name}: {len(c)} channels, expected {chans}")
        c, _ = read(os.path.join(seq, "frame_0001.normal.exr"))
        check(c and np.allclose(c.get("Z", np.zeros(1)), -1, atol=1e-5), "sequence normal.Z -1")
        check(not os.path.exists(os.path.join(seq, "frame_0000.motion.exr")), "motion not asked")

        # objects move too (tt_mesh.prev_positions): the plane translating +1 unit/s along x
        # under a still camera moves the other way in the image than under the moving camera
        # (to 1e-3 px: the analytic motion), with every integrator; plane and camera moving
        # together do not move in the image
        slide = {"keys": [{"time": 0, "translate": [0, 0, 0]}, {"time": 1, "translate": [1, 0, 0]}]}
        obj = plane()
        obj["meshes"][0]["animation"] = slide
        objpath = write(tmp, "object.json", obj)
        for integ in ("integrator_pt", "integrator_bdpt", "integrator_pssmlt"):
            oexr = os.path.join(tmp, f"object_{integ}.exr")
            rc, out = host("--plugin", integ, "--aov", "motion", "--camera-index", "50", "--spp", "2",
                           "--out", oexr, objpath)
            oc, _ = read(oexr)
            ox = oc.get("motion.X", np.zeros((12, 16)))
            check(rc == 0 and np.allclose(ox, want, atol=1e-3),
                  f"{integ}: a moving object: motion.X {ox[6, 8]} (expected {want}): {out}")
            check(np.allclose(oc.get("motion.Y", np.ones(1)), 0, atol=1e-3), f"{integ}: object motion.Y 0")
        both = plane(path=MOVING_PATH)
        both["meshes"][0]["animation"] = slide
        bexr = os.path.join(tmp, "both.exr")
        rc, out = host("--aov", "motion", "--camera-index", "50", "--spp", "2", "--out", bexr,
                       write(tmp, "both.json", both))
        bc, _ = read(bexr)
        check(rc == 0 and np.allclose(bc.get("motion.X", np.ones(1)), 0, atol=1e-3),
              f"object moving with the camera: motion.X {bc.get('motion.X', np.ones((12, 16)))[6, 8]}")
        # prevdepth of a sequence: the plane coming towards the camera at 1 unit/s was 1/24
        # unit farther one frame earlier
        towards = plane()
        towards["meshes"][0]["animation"] = {"keys": [{"time": 0, "translate": [0, 0, 0]},
                                                      {"time": 1, "translate": [0, 0, -1]}]}
        tdir = os.path.join(tmp, "towards")
        rc, out = host("--sequence", "11:11", "--aov", "depth,motion,prevdepth", "--spp", "1",
                       "--out-dir", tdir, write(tmp, "towards.json", towards))
        dc, _ = read(os.path.join(tdir, "depth_0011.exr"))
        pc, _ = read(os.path.join(tdir, "prevdepth_0011.exr"))
        d, p = dc.get("Z", np.zeros(1)), pc.get("Z", np.ones(1))
        check(rc == 0 and np.allclose(d, DISTANCE - 11 / 24, atol=1e-4), f"depth {d.flat[0]}: {out}")
        check(np.allclose(p, d + 1 / 24, atol=1e-4), f"prevdepth {p.flat[0]}, depth {d.flat[0]}")

        rc, out = host("--aov", "depth,shadow", still)
        check(rc == 2 and "shadow" in out and "albedo" in out, f"--aov shadow: exit {rc}: {out}")
    print(f"host_aov: {checks} checks, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
