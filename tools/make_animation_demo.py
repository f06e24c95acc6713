"""Writes scenes/animation/bend.gltf, the animation demo of docs/gltf.md: a square column
skinned to a chain of three joints that bends over and back in two seconds (rotations about
+z, LINEAR), a cube beside it that turns (rotation, CUBICSPLINE) and breathes (a morph
target, weights LINEAR), on a floor, lit by a sun, seen by a camera. Standard library only.

    python3 tools/make_animation_demo.py
"""

import base64
import json
import math
import os
import struct

from gltfgen import BufferBuilder, quat_axis_angle

SEGMENTS = 12  # rings along the column, bottom to top
HEIGHT = 2.4
HALF = 0.18  # half the column's width
JOINTS = 3  # joints up the column, evenly spaced from its foot
TIMES = [0.0, 0.5, 1.0, 1.5, 2.0]
BENDS = [0.0, 0.45, 0.7, 0.45, 0.0]  # each joint's turn about +z, radians


def column(b):
    """The column's primitive: rings of four corners, each vertex weighted between the two
    joints nearest its height."""
    corners = [(-HALF, -HALF), (HALF, -HALF), (HALF, HALF), (-HALF, HALF)]
    # Side s runs from corner s to corner s + 1 (counter-clockwise seen from +y).
    normals_of = [(0.0, 0.0, -1.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (-1.0, 0.0, 0.0)]
    positions, normals, joints, weights, tris = [], [], [], [], []
    step = HEIGHT / JOINTS
    for ring in range(SEGMENTS + 1):
        y = HEIGHT * ring / SEGMENTS
        # Joint k sits at height k·step: a vertex between joints k and k+1 blends them.
        at = min(y / step, JOINTS - 1.0)
        k = min(int(at), JOINTS - 2)
        w = at - k
        for side in range(4):
            # Two vertices per corner and side, so that each side has its own normal.
            for c in (side, (side + 1) % 4):
                x, z = corners[c]
                positions.append((x, y, z))
                normals.append(normals_of[side])
                joints.append((k, k + 1, 0, 0))
                weights.append((1.0 - w, w, 0.0, 0.0))
    per_ring = 8
    for ring in range(SEGMENTS):
        for side in range(4):
            a = ring * per_ring + 2 * side
            c = a + per_ring
            tris += [(a, c + 1, a + 1), (a, c, c + 1)]  # counter-clockwise from outside
    joint_data = struct.pack("<%dH" % (4 * len(joints)), *[j for row in joints for j in row])
    joint_acc = len(b.accessors)
    b.accessors.append({"bufferView": b.view(joint_data, 34962), "componentType": 5123,
                        "count": len(joints), "type": "VEC4"})
    return {"attributes": {"POSITION": b.floats(positions, "VEC3", with_bounds=True),
                           "NORMAL": b.floats(normals, "VEC3"), "JOINTS_0": joint_acc,
                           "WEIGHTS_0": b.floats(weights, "VEC4")},
            "indices": b.indices(tris, len(positions)), "material": 0}


def cube(b):
    """A unit cube (flat sides) with one morph target that moves every vertex out from the
    centre: at weight 1 the cube is 30 % larger."""
    positions, normals, tris = [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = sign
            u, v = [(axis + 1) % 3, (axis + 2) % 3]
            base = len(positions)
            for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis], p[u], p[v] = 0.5 * sign, 0.5 * du, 0.5 * dv
                positions.append(tuple(p))
                normals.append(tuple(n))
            quad = [(base, base + 1, base + 2), (base, base + 2, base + 3)]
            tris += quad if sign > 0 else [(i, k, j) for i, j, k in quad]
    push = [tuple(0.3 * c for c in p) for p in positions]
    return {"attributes": {"POSITION": b.floats(positions, "VEC3", with_bounds=True),
                           "NORMAL": b.floats(normals, "VEC3")},
            "targets": [{"POSITION": b.floats(push, "VEC3", with_bounds=True)}],
            "indices": b.indices(tris, len(positions)), "material": 1}


def main():
    b = BufferBuilder()
    floor = {"attributes": {"POSITION": b.floats([(-4, 0, 4), (4, 0, 4), (4, 0, -4), (-4, 0, -4)],
                                                 "VEC3", with_bounds=True),
                            "NORMAL": b.floats([(0, 1, 0)] * 4, "VEC3")},
             "indices": b.indices([(0, 1, 2), (0, 2, 3)], 4), "material": 2}
    meshes = [{"primitives": [column(b)]}, {"primitives": [cube(b)], "weights": [0.0]},
              {"primitives": [floor]}]
    step = HEIGHT / JOINTS
    # Nodes 0..JOINTS-1: the joint chain, each a child of the one below.
    nodes = []
    for k in range(JOINTS):
        node = {"name": "joint%d" % k, "translation": [0.0, step if k else 0.0, 0.0]}
        if k + 1 < JOINTS:
            node["children"] = [k + 1]
        nodes.append(node)
    ibms = []
    for k in range(JOINTS):
        ibms.append((1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -k * step, 0, 1))
    skin = {"joints": list(range(JOINTS)), "inverseBindMatrices": b.floats(ibms, "MAT4")}
    nodes.append({"name": "column", "mesh": 0, "skin": 0})
    cube_node = len(nodes)
    nodes.append({"name": "cube", "mesh": 1, "translation": [1.5, 0.5, 0.2]})
    nodes.append({"name": "floor", "mesh": 2})
    nodes.append({"name": "sun", "rotation": list(quat_axis_angle((-1.0, 0.6, 0.0), 0.95)),
                  "extensions": {"KHR_lights_punctual": {"light": 0}}})
    nodes.append({"name": "camera", "camera": 0, "translation": [0.4, 1.5, 7.0],
                  "rotation": list(quat_axis_angle((1.0, 0.0, 0.0), -0.08))})

    times = b.floats([(t,) for t in TIMES], "SCALAR", with_bounds=True)
    samplers, channels = [], []
    for k in range(1, JOINTS):
        turns = [quat_axis_angle((0.0, 0.0, 1.0), a) for a in BENDS]
        samplers.append({"input": times, "interpolation": "LINEAR",
                         "output": b.floats(turns, "VEC4")})
        channels.append({"sampler": len(samplers) - 1,
                         "target": {"node": k, "path": "rotation"}})
    # The cube: half a turn about +y over the two seconds, as a spline with zero tangents
    # (easing in and out), and its morph weight up to 1 and back.
    spin_times = b.floats([(0.0,), (2.0,)], "SCALAR", with_bounds=True)
    zero = (0.0, 0.0, 0.0, 0.0)
    spin = [zero, quat_axis_angle((0.0, 1.0, 0.0), 0.0), zero,
            zero, quat_axis_angle((0.0, 1.0, 0.0), math.pi * 0.999), zero]
    samplers.append({"input": spin_times, "interpolation": "CUBICSPLINE",
                     "output": b.floats(spin, "VEC4")})
    channels.append({"sampler": len(samplers) - 1,
                     "target": {"node": cube_node, "path": "rotation"}})
    samplers.append({"input": times, "interpolation": "LINEAR",
                     "output": b.floats([(w,) for w in (0.0, 0.6, 1.0, 0.6, 0.0)], "SCALAR")})
    channels.append({"sampler": len(samplers) - 1,
                     "target": {"node": cube_node, "path": "weights"}})

    uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(b.bin)).decode()
    gltf = {
        "asset": {"version": "2.0", "generator": "raylab tools/make_animation_demo.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "color": [1.0, 0.95, 0.85], "intensity": 3.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, JOINTS, cube_node, cube_node + 1, cube_node + 2,
                              cube_node + 3]}],
        "nodes": nodes,
        "meshes": meshes,
        "skins": [skin],
        "animations": [{"name": "bend", "samplers": samplers, "channels": channels}],
        "materials": [
            {"name": "column", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.35, 0.1, 1],
                                                        "metallicFactor": 0.0,
                                                        "roughnessFactor": 0.5}},
            {"name": "cube", "pbrMetallicRoughness": {"baseColorFactor": [0.15, 0.4, 0.8, 1],
                                                      "metallicFactor": 0.0,
                                                      "roughnessFactor": 0.3}},
            {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1],
                                                       "metallicFactor": 0.0,
                                                       "roughnessFactor": 0.9}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.75, "znear": 0.1,
                                                           "aspectRatio": 1.0}}],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": len(b.bin), "uri": uri}],
    }
    here = os.path.dirname(os.path.abspath(__file__))
    out = os.path.join(here, "..", "scenes", "animation", "bend.gltf")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w", encoding="utf-8") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")
    print("wrote", os.path.normpath(out))


if __name__ == "__main__":
    main()
