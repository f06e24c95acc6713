"""Writes scenes/diffuse-transmission/lamp-and-leaves.gltf, the KHR_materials_diffuse_transmission
demo of docs/gltf.md: a paper lamp shade (an open cylinder of thin paper) with a point light
inside, and a spray of thin leaves backlit by a low sun behind them, on a floor, seen by a
camera. The shade and the leaves transmit part of their diffuse light to their other side
(warm for the paper, yellow-green for the leaves); without the extension (tools/gltf_without.py)
the shade is dark outside and the leaves show their shaded faces. Standard library only.

    python3 tools/make_diffuse_transmission_demo.py
"""

import base64
import json
import math
import os

from gltfgen import BufferBuilder, look_along, quat_axis_angle, quat_mul

SIDES = 48  # facets round the lamp shade
SHADE_RADIUS, SHADE_BOTTOM, SHADE_TOP = 0.42, 0.55, 1.35
LIGHT_AT = (-0.75, 0.95, 0.0)  # the bulb, inside the shade
LEAF_STEPS = 10  # rows of the leaf's outline, tip to tip


def shade(b):
    """The open cylinder of the lamp shade about the y axis, normals outward."""
    positions, normals, tris = [], [], []
    for k in range(SIDES + 1):
        a = 2.0 * math.pi * k / SIDES
        n = (math.cos(a), 0.0, math.sin(a))
        for y in (SHADE_BOTTOM, SHADE_TOP):
            positions.append((SHADE_RADIUS * n[0], y, SHADE_RADIUS * n[2]))
            normals.append(n)
    for k in range(SIDES):
        i = 2 * k
        tris += [(i, i + 1, i + 3), (i, i + 3, i + 2)]
    return {"attributes": {"POSITION": b.floats(positions, "VEC3", with_bounds=True),
                           "NORMAL": b.floats(normals, "VEC3")},
            "indices": b.indices(tris, len(positions)), "material": 0}


def leaf(b):
    """A flat leaf in the xy plane (front +z), tip at y = 1, base at y = 0, widest below the
    middle: a strip of rows between its two edges."""
    positions, tris = [], []
    for r in range(LEAF_STEPS + 1):
        t = r / LEAF_STEPS
        half = 0.32 * math.sin(math.pi * t) * (1.0 - 0.35 * t)
        positions += [(-half, t, 0.0), (half, t, 0.0)]
    for r in range(LEAF_STEPS):
        i = 2 * r
        tris += [(i, i + 1, i + 3), (i, i + 3, i + 2)]
    normals = [(0.0, 0.0, 1.0)] * len(positions)
    return {"attributes": {"POSITION": b.floats(positions, "VEC3", with_bounds=True),
                           "NORMAL": b.floats(normals, "VEC3")},
            "indices": b.indices(tris, len(positions)), "material": 1}


def floor(b):
    s = 6.0
    positions = [(-s, 0.0, -s), (-s, 0.0, s), (s, 0.0, s), (s, 0.0, -s)]
    return {"attributes": {"POSITION": b.floats(positions, "VEC3", with_bounds=True),
                           "NORMAL": b.floats([(0.0, 1.0, 0.0)] * 4, "VEC3")},
            "indices": b.indices([(0, 1, 2), (0, 2, 3)], 4), "material": 2}


def main():
    b = BufferBuilder()
    meshes = [{"name": "shade", "primitives": [shade(b)]},
              {"name": "leaf", "primitives": [leaf(b)]},
              {"name": "floor", "primitives": [floor(b)]}]
    nodes = [{"name": "shade", "mesh": 0, "translation": [LIGHT_AT[0], 0.0, LIGHT_AT[2]]},
             {"name": "floor", "mesh": 2}]
    # Leaves fanned about a stem at x = 0.8, leaning a little towards the camera.
    for k, (turn, lean, y, size) in enumerate([(-0.7, 0.25, 0.15, 0.9), (-0.25, 0.2, 0.35, 1.0),
                                              (0.2, 0.15, 0.3, 0.95), (0.65, 0.3, 0.1, 0.85),
                                              (0.0, 0.1, 0.75, 0.8)]):
        q = quat_mul(quat_axis_angle((1.0, 0.0, 0.0), -lean),
                     quat_axis_angle((0.0, 0.0, 1.0), turn))
        nodes.append({"name": "leaf %d" % k, "mesh": 1, "translation": [0.85, y, 0.0],
                      "rotation": list(q), "scale": [size, size, size]})
    light_node = len(nodes)
    nodes.append({"name": "bulb", "translation": list(LIGHT_AT),
                  "extensions": {"KHR_lights_punctual": {"light": 0}}})
    # The sun, low behind the scene, travelling towards the camera.
    sun_node = len(nodes)
    nodes.append({"name": "sun", "rotation": list(look_along((-0.15, -0.35, 1.0))),
                  "extensions": {"KHR_lights_punctual": {"light": 1}}})
    camera_node = len(nodes)
    eye, target = (0.0, 1.05, 3.6), (0.05, 0.75, 0.0)
    nodes.append({"name": "camera", "camera": 0, "translation": list(eye),
                  "rotation": list(look_along(tuple(t - e for t, e in zip(target, eye))))})

    uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(b.bin)).decode()
    dt = "KHR_materials_diffuse_transmission"
    gltf = {
        "asset": {"version": "2.0",
                  "generator": "raylab tools/make_diffuse_transmission_demo.py"},
        "extensionsUsed": ["KHR_lights_punctual", dt],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1.0, 0.85, 0.65], "intensity": 4.0},
            {"type": "directional", "color": [1.0, 0.93, 0.8], "intensity": 2.5}]}},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [
            {"name": "paper", "doubleSided": True,
             "pbrMetallicRoughness": {"baseColorFactor": [0.85, 0.82, 0.75, 1],
                                      "metallicFactor": 0.0, "roughnessFactor": 0.9},
             "extensions": {dt: {"diffuseTransmissionFactor": 0.6,
                                 "diffuseTransmissionColorFactor": [1.0, 0.75, 0.45]}}},
            {"name": "leaf", "doubleSided": True,
             "pbrMetallicRoughness": {"baseColorFactor": [0.12, 0.35, 0.06, 1],
                                      "metallicFactor": 0.0, "roughnessFactor": 0.55},
             "extensions": {dt: {"diffuseTransmissionFactor": 0.5,
                                 "diffuseTransmissionColorFactor": [0.55, 0.9, 0.15]}}},
            {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1],
                                                       "metallicFactor": 0.0,
                                                       "roughnessFactor": 0.9}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.05,
                                                           "aspectRatio": 4.0 / 3.0}}],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": len(b.bin), "uri": uri}],
    }
    here = os.path.dirname(os.path.abspath(__file__))
    out = os.path.join(here, "..", "scenes", "diffuse-transmission", "lamp-and-leaves.gltf")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w", encoding="utf-8") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")
    print("wrote", os.path.normpath(out))


if __name__ == "__main__":
    main()
