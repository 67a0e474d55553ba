"""Renders a tunetrace scene.json with Blender Cycles (CPU) into a linear EXR: the peer
reference of issue 4. Run headless:

    blender -b --factory-startup -P tools/cycles/cycles_reference.py -- \
        --scene scenes/cornell-box/scene.json --spp 1024 --depth 3 --out ref.exr [--threads 2]

Conventions matched to tunetrace (so the two images are the same integral):
  * geometry is used as is (tunetrace's units and y-up axes; Cycles does not care which
    way is up when there is no sky), the camera by look-at with a vertical fov;
  * emission: a Cycles Emission closure of strength 1 on a surface *is* radiance (W/m^2/sr
    in scene units), so the emission colour is used directly; tunetrace emitters are
    one-sided unless twoSided, done with Geometry.Backfacing; the emitter's own albedo
    reflects (Diffuse + Emission), as in tunetrace;
  * depth: tunetrace maxDepth D scatters at most D times (D = 1 is direct lighting), Cycles
    max_bounces B = 0 is direct lighting, so B = D - 1 for every bounce type;
  * box pixel filter of width 1 px (tunetrace's default "box"), no clamping, no denoising,
    no adaptive sampling, light threshold 0 (no probabilistic shadow-ray skipping);
  * materials: diffuse -> Diffuse BSDF (Lambert), dielectric -> Glass BSDF (sharp, or GGX with
    roughness sqrt(alpha): Cycles squares its roughness), mirror -> sharp Glossy,
    conductor -> GGX Glossy tinted by `specular` (exact only when the conductor's Fresnel
    is ~1, e.g. eta = 1, k = 1000 as in the glossy variant of compare.py); plastic is
    refused (no exact Cycles equivalent).
Writes OUT (RGB float EXR) and OUT.json with the settings, the render's wall time and CPU
seconds (all threads; includes writing the EXR, a few ms).
"""
import argparse
import json
import math
import sys
import time

import bpy
from mathutils import Matrix, Vector


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="cycles_reference.py")
    ap.add_argument("--scene", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--depth", type=int, default=None, help="tunetrace maxDepth (default: the scene's)")
    ap.add_argument("--threads", type=int, default=0, help="0: all CPUs")
    ap.add_argument("--res", default=None, help="WxH override")
    ap.add_argument("--seed", type=int, default=1)
    return ap.parse_args(argv)


def triples(a):
    """Flat [x,y,z,...] or nested [[x,y,z],...] -> list of tuples."""
    if a and isinstance(a[0], list):
        return [tuple(v) for v in a]
    return [tuple(a[i:i + 3]) for i in range(0, len(a), 3)]


def colour(v, default):
    if v is None:
        v = default
    if isinstance(v, (int, float)):
        return (float(v),) * 3
    return tuple(float(x) for x in v)


def make_material(name, m):
    """Cycles node material equivalent to a tunetrace material (see the module doc)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    typ = m.get("type", "diffuse")
    spec = colour(m.get("specular"), 1.0)
    alpha = m.get("alpha", 0.0 if typ == "dielectric" else 0.1)
    if isinstance(alpha, list):
        alpha = math.sqrt(alpha[0] * alpha[1])  # Cycles' Glass/Glossy nodes are isotropic
    if typ == "diffuse":
        bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
        bsdf.inputs["Color"].default_value = colour(m.get("albedo"), 0.5) + (1.0,)
        bsdf.inputs["Roughness"].default_value = 0.0
        if m.get("roughness", 0.0) > 0.0:
            raise SystemExit(f"material {name}: Oren-Nayar roughness has no exact Cycles equivalent")
    elif typ == "dielectric":
        bsdf = nt.nodes.new("ShaderNodeBsdfGlass")
        bsdf.distribution = "SHARP" if alpha <= 0.0 else "GGX"
        bsdf.inputs["Roughness"].default_value = math.sqrt(max(alpha, 0.0))
        bsdf.inputs["IOR"].default_value = m.get("ior", 1.5)
        bsdf.inputs["Color"].default_value = spec + (1.0,)
    elif typ in ("mirror", "conductor"):
        bsdf = nt.nodes.new("ShaderNodeBsdfGlossy")
        sharp = typ == "mirror" or alpha <= 1e-3
        bsdf.distribution = "SHARP" if sharp else "GGX"
        bsdf.inputs["Roughness"].default_value = 0.0 if sharp else math.sqrt(alpha)
        bsdf.inputs["Color"].default_value = spec + (1.0,)
    else:
        raise SystemExit(f"material {name}: type {typ} has no exact Cycles equivalent")
    shader = bsdf.outputs[0]
    emission = colour(m.get("emission"), 0.0)
    if max(emission) > 0.0:
        em = nt.nodes.new("ShaderNodeEmission")
        em.inputs["Color"].default_value = emission + (1.0,)
        em.inputs["Strength"].default_value = 1.0
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(shader, add.inputs[0])
        nt.links.new(em.outputs[0], add.inputs[1])
        shader = add.outputs[0]
        if not m.get("twoSided", False):
            geo = nt.nodes.new("ShaderNodeNewGeometry")
            mix = nt.nodes.new("ShaderNodeMixShader")
            nt.links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
            nt.links.new(shader, mix.inputs[1])
            nt.links.new(bsdf.outputs[0], mix.inputs[2])
            shader = mix.outputs[0]
    nt.links.new(shader, out.inputs["Surface"])
    return mat


def look_at(position, target, up):
    p, t, u = Vector(position), Vector(target), Vector(up)
    f = (t - p).normalized()
    r = f.cross(u).normalized()
    u2 = r.cross(f)
    m = Matrix.Identity(4)
    for i in range(3):
        m[i][0], m[i][1], m[i][2], m[i][3] = r[i], u2[i], -f[i], p[i]
    return m


def main():
    a = parse_args()
    with open(a.scene) as fh:
        sc = json.load(fh)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene

    mats = {name: make_material(name, m) for name, m in sc["materials"].items()}
    for i, mesh in enumerate(sc["meshes"]):
        if "file" in mesh or "transform" in mesh or "matrix" in mesh:
            raise SystemExit("only inline, untransformed meshes are supported")
        verts = triples(mesh["positions"])
        idx = mesh.get("indices") or list(range(len(verts)))
        faces = triples(idx)
        me = bpy.data.meshes.new(mesh.get("name", f"mesh{i}"))
        me.from_pydata(verts, [], [tuple(int(x) for x in f) for f in faces])
        me.update()
        me.materials.append(mats[mesh["material"]])
        ob = bpy.data.objects.new(me.name, me)
        scene.collection.objects.link(ob)

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    bg.inputs["Strength"].default_value = 0.0
    for light in sc.get("lights", []):
        if light["type"] != "environment" or "image" in light:
            raise SystemExit(f"light type {light['type']} is not translated")
        bg.inputs["Color"].default_value = colour(light.get("radiance"), 1.0) + (1.0,)
        bg.inputs["Strength"].default_value = 1.0
    scene.world = world

    cam_d = sc["camera"]
    cam = bpy.data.cameras.new("camera")
    cam.sensor_fit = "VERTICAL"
    cam.angle_y = math.radians(cam_d.get("fov", 45.0))
    cam.clip_start = 1e-3
    cam.clip_end = 1e7
    cam_ob = bpy.data.objects.new("camera", cam)
    cam_ob.matrix_world = look_at(cam_d["position"], cam_d["target"], cam_d.get("up", [0, 1, 0]))
    scene.collection.objects.link(cam_ob)
    scene.camera = cam_ob

    w, h = cam_d.get("resolution", [256, 256])
    if a.res:
        w, h = (int(x) for x in a.res.lower().split("x"))
    depth = a.depth if a.depth is not None else sc.get("render", {}).get("maxDepth", 3)
    bounces = max(depth - 1, 0)

    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
    r.film_transparent = False
    if a.threads > 0:
        r.threads_mode = "FIXED"
        r.threads = a.threads
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_mode = "RGB"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"
    c = scene.cycles
    c.device = "CPU"
    c.samples = a.spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = a.seed
    c.max_bounces = bounces
    c.diffuse_bounces = bounces
    c.glossy_bounces = bounces
    c.transmission_bounces = bounces
    c.volume_bounces = 0
    c.transparent_max_bounces = 0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.blur_glossy = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    r.filepath = a.out

    t0, c0 = time.perf_counter(), time.process_time()
    bpy.ops.render.render(write_still=True)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    info = {"renderer": "cycles", "blender": bpy.app.version_string, "scene": a.scene,
            "spp": a.spp, "depth": depth, "cycles_max_bounces": bounces, "threads": r.threads,
            "resolution": [w, h], "wall_s": wall, "cpu_s": cpu,
            "samples_per_s": w * h * a.spp / wall if wall > 0 else 0.0}
    with open(a.out + ".json", "w") as fh:
        json.dump(info, fh, indent=1)
    print("cycles_reference: %s: %d spp, depth %d (Cycles bounces %d), %.2f s, %.0f samples/s"
          % (a.out, a.spp, depth, bounces, wall, info["samples_per_s"]))


main()
