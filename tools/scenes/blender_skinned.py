"""Builds an animated glTF 2.0 scene with Blender for the per-frame update benchmarks: a
skinned tentacle (a finely subdivided tube bound to a chain of bones that sway), a sphere
breathing through two shape keys (morph targets), rigid boxes orbiting on keyframed
transforms, a ground plane and a camera that moves along the sequence. Run headless:

    blender -b --factory-startup -P tools/scenes/blender_skinned.py -- \
        --out /tmp/skinned/skinned.gltf [--frames 120] [--fps 24] [--bones 12] \
        [--rings 192] [--segments 48] [--boxes 24]

then render it as a sequence (frames at --fps; host's --fps must match):

    build/host/host --sequence 0:119 --out-dir /tmp/skinned/seq /tmp/skinned/skinned.gltf

The output is a .gltf with its .bin beside it (not committed: regenerate it). Everything
is deterministic (no random numbers), so two runs write the same geometry and keys. The
tentacle has rings * segments vertices (9216 by default), every one moved by up to four
bones, so the accel sees a deforming mesh each frame; the boxes are rigid (node
animation), the sphere deforms through morph weights. Blender exports skinning with its
weights normalised, sampled keys (one per frame, LINEAR) and the camera as a glTF
perspective camera, which tunetrace reads as the sequence's camera path.
"""
import argparse
import math
import os
import sys

import bpy
from mathutils import Vector


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="blender_skinned.py")
    ap.add_argument("--out", required=True, help="output .gltf (its .bin goes beside it)")
    ap.add_argument("--frames", type=int, default=120, help="animation length in frames")
    ap.add_argument("--fps", type=int, default=24)
    ap.add_argument("--bones", type=int, default=12, help="bones in the tentacle's chain")
    ap.add_argument("--rings", type=int, default=192, help="tube rings along the tentacle")
    ap.add_argument("--segments", type=int, default=48, help="vertices around each ring")
    ap.add_argument("--boxes", type=int, default=24, help="rigid orbiting boxes")
    a = ap.parse_args(argv)
    if not a.out.endswith(".gltf"):
        ap.error("--out must end in .gltf")
    for name in ("frames", "fps", "bones", "rings", "segments"):
        if getattr(a, name) < 2:
            ap.error(f"--{name} must be at least 2")
    if a.boxes < 0:
        ap.error("--boxes must be >= 0")
    return a


def clear():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def tentacle(a, height=4.0, radius=0.35):
    """A tube along +Z (Blender's up; glTF export turns it into +Y), skinned to a chain of
    bones by distance along the tube (two neighbouring bones per ring, weights summing to 1)."""
    mesh = bpy.data.meshes.new("tentacle")
    verts, faces = [], []
    for r in range(a.rings):
        z = height * r / (a.rings - 1)
        rad = radius * (1.0 - 0.7 * z / height)
        for s in range(a.segments):
            t = 2 * math.pi * s / a.segments
            verts.append((rad * math.cos(t), rad * math.sin(t), z))
    for r in range(a.rings - 1):
        for s in range(a.segments):
            i0 = r * a.segments + s
            i1 = r * a.segments + (s + 1) % a.segments
            faces.append((i0, i1, i1 + a.segments, i0 + a.segments))
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    obj = bpy.data.objects.new("tentacle", mesh)
    bpy.context.scene.collection.objects.link(obj)

    arm_data = bpy.data.armatures.new("spine")
    arm = bpy.data.objects.new("spine", arm_data)
    bpy.context.scene.collection.objects.link(arm)
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    seg = height / a.bones
    prev = None
    for b in range(a.bones):
        eb = arm_data.edit_bones.new(f"bone{b:02d}")
        eb.head = (0, 0, b * seg)
        eb.tail = (0, 0, (b + 1) * seg)
        if prev is not None:
            eb.parent = prev
            eb.use_connect = True
        prev = eb
    bpy.ops.object.mode_set(mode="OBJECT")

    groups = [obj.vertex_groups.new(name=f"bone{b:02d}") for b in range(a.bones)]
    for r in range(a.rings):
        z = height * r / (a.rings - 1)
        x = z / seg - 0.5  # position in bone units, centred on the bones' middles
        b0 = max(0, min(a.bones - 1, int(math.floor(x))))
        b1 = min(a.bones - 1, b0 + 1)
        f = min(1.0, max(0.0, x - b0))
        idx = list(range(r * a.segments, (r + 1) * a.segments))
        if b1 == b0:
            groups[b0].add(idx, 1.0, "REPLACE")
        else:
            groups[b0].add(idx, 1.0 - f, "REPLACE")
            groups[b1].add(idx, f, "REPLACE")
    mod = obj.modifiers.new("skin", "ARMATURE")
    mod.object = arm
    obj.parent = arm

    # sway: every bone bends about X and Z with a phase that travels up the chain
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="POSE")
    for pb in arm.pose.bones:
        pb.rotation_mode = "XYZ"
    for f in range(a.frames):
        ph = 2 * math.pi * f / a.frames
        for b, pb in enumerate(arm.pose.bones):
            pb.rotation_euler = (0.22 * math.sin(2 * ph - 0.5 * b), 0.0,
                                 0.18 * math.cos(ph - 0.4 * b))
            pb.keyframe_insert("rotation_euler", frame=f)
    bpy.ops.object.mode_set(mode="OBJECT")
    return obj


def breathing_sphere(a):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=0.8,
                                         location=(2.5, 0.0, 1.0))
    sph = bpy.context.active_object
    sph.name = "sphere"
    sph.shape_key_add(name="basis")
    bulge = sph.shape_key_add(name="bulge")
    squash = sph.shape_key_add(name="squash")
    for i, v in enumerate(sph.data.vertices):
        x, y, z = v.co
        bulge.data[i].co = (x * 1.3, y * 1.3, z * 0.8)
        squash.data[i].co = (x * (1 + 0.25 * math.sin(6 * z)), y, z * 1.2)
    for f in range(a.frames):
        ph = 2 * math.pi * f / a.frames
        bulge.value = 0.5 + 0.5 * math.sin(ph)
        squash.value = 0.5 + 0.5 * math.cos(2 * ph)
        bulge.keyframe_insert("value", frame=f)
        squash.keyframe_insert("value", frame=f)


def boxes(a):
    for i in range(a.boxes):
        bpy.ops.mesh.primitive_cube_add(size=0.3)
        box = bpy.context.active_object
        box.name = f"box{i:02d}"
        r = 3.5 + 0.5 * (i % 3)
        for f in range(a.frames):
            ph = 2 * math.pi * (f / a.frames + i / max(1, a.boxes))
            box.location = (r * math.cos(ph), r * math.sin(ph), 0.4 + 0.3 * math.sin(3 * ph + i))
            box.rotation_euler = (ph * 2, ph, 0.0)
            box.keyframe_insert("location", frame=f)
            box.keyframe_insert("rotation_euler", frame=f)


def ground_and_camera(a):
    bpy.ops.mesh.primitive_plane_add(size=14.0, location=(0, 0, 0))
    bpy.context.active_object.name = "ground"
    cam_data = bpy.data.cameras.new("camera")
    cam_data.sensor_fit = "VERTICAL"
    cam_data.angle_y = math.radians(45.0)
    cam = bpy.data.objects.new("camera", cam_data)
    bpy.context.scene.collection.objects.link(cam)
    # keyed rotation looking at the tentacle (a constraint would not be exported)
    cam.rotation_mode = "QUATERNION"
    target = Vector((0.0, 0.0, 1.5))
    for f in range(a.frames):
        ph = 0.6 * math.pi * f / a.frames
        cam.location = (10 * math.cos(ph), -10 * math.sin(ph) - 2, 4.5)
        cam.rotation_quaternion = (target - cam.location).to_track_quat("-Z", "Y")
        cam.keyframe_insert("location", frame=f)
        cam.keyframe_insert("rotation_quaternion", frame=f)
    bpy.context.scene.camera = cam


def main():
    a = parse_args()
    clear()
    scene = bpy.context.scene
    scene.render.fps = a.fps
    scene.frame_start = 0  # frame f at time f / fps, as host's --sequence counts
    scene.frame_end = a.frames - 1
    tentacle(a)
    breathing_sphere(a)
    boxes(a)
    ground_and_camera(a)
    out = os.path.abspath(a.out)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    bpy.ops.export_scene.gltf(
        filepath=out, export_format="GLTF_SEPARATE", export_animations=True,
        export_frame_range=True, export_force_sampling=True, export_skins=True,
        export_morph=True, export_cameras=True, export_apply=False, export_yup=True,
        export_nla_strips=False)
    print(f"blender_skinned: wrote {out} ({a.frames} frames at {a.fps} fps)")


if __name__ == "__main__":  # blender -P runs the script as __main__
    main()
