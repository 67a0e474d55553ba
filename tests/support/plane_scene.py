"""The AOV tests' scene (host/tests/host_aov.py, python/tests/python_api.py): a diffuse plane at z = 0
facing a camera 5 units away (16x12, fov 40), lit by a white environment, so every AOV has a
known value: depth 5, normal (0, 0, -1), albedo (0.2, 0.4, 0.6), no motion for a still."""
import json
import math
import os

ALBEDO = (0.2, 0.4, 0.6)
DISTANCE = 5.0
FOV = 40.0
WIDTH, HEIGHT = 16, 12


def plane(half_width=50.0, path=None):
    """The scene as a dict: the plane spans x in [-50, half_width]; `path` (camera keys)
    makes the camera move."""
    cam = {"position": [0, 0, -DISTANCE], "target": [0, 0, 0], "fov": FOV,
           "resolution": [WIDTH, HEIGHT]}
    if path:
        cam["path"] = path
    return {
        "version": 1, "camera": cam, "render": {"spp": 1, "maxDepth": 2, "seed": 3},
        "materials": {"paint": {"type": "diffuse", "albedo": list(ALBEDO)}},
        # (v1 - v0) x (v2 - v0) = (0, 0, -1): the plane faces the camera
        "meshes": [{"name": "wall", "material": "paint",
                    "positions": [[-50, -50, 0], [-50, 50, 0], [half_width, 50, 0],
                                  [half_width, -50, 0]],
                    "indices": [[0, 1, 2], [0, 2, 3]]}],
        "lights": [{"type": "environment", "radiance": [1, 1, 1]}],
    }


# A camera translating +1 world unit per second along x (position and target together).
MOVING_PATH = [{"time": 0, "position": [0, 0, -DISTANCE], "target": [0, 0, 0]},
               {"time": 1, "position": [1, 0, -DISTANCE], "target": [1, 0, 0]}]


def motion_pixels(frame_interval):
    """|motion.x| in pixels of a point on the plane for MOVING_PATH: the camera moves
    frame_interval units, f * that / distance pixels with f = (height / 2) / tan(fov / 2)."""
    f = (HEIGHT / 2) / math.tan(math.radians(FOV / 2))
    return f * frame_interval / DISTANCE


def pixel_size():
    """World size of one pixel on the plane."""
    return 2 * DISTANCE * math.tan(math.radians(FOV / 2)) / HEIGHT


def write(folder, name, scene):
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        json.dump(scene, f)
    return path
