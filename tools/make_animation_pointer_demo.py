"""Writes scenes/animation-pointer/glow.gltf, the KHR_animation_pointer demo of docs/gltf.md:
a striped orb on a floor whose material changes over two seconds through animation
pointers: its base and emissive colours go from orange through magenta to blue (LINEAR),
its stripes (base colour and emissive textures) slide round it (KHR_texture_transform
offsets, LINEAR), and its glow rises and fades (KHR_materials_emissive_strength,
CUBICSPLINE); the point light above turns from warm to cool (KHR_lights_punctual colour,
LINEAR). Standard library only.

    python3 tools/make_animation_pointer_demo.py
"""

import base64
import math

from gltfgen import BufferBuilder, png_bytes, quat_axis_angle, write_scene

RINGS, SEGMENTS = 24, 48  # the orb's latitude and longitude divisions
RADIUS = 0.8
TIMES = [0.0, 1.0, 2.0]
COLOURS = [(0.9, 0.35, 0.08, 1.0), (0.75, 0.12, 0.55, 1.0), (0.08, 0.3, 0.9, 1.0)]
GLOW_COLOURS = [(1.0, 0.42, 0.1), (0.95, 0.15, 0.6), (0.15, 0.45, 1.0)]
OFFSETS = [(0.0, 0.0), (0.1875, 0.0), (0.375, 0.0)]  # 1.5 stripes over the two seconds
LIGHT_COLOURS = [(1.0, 0.78, 0.55), (0.95, 0.85, 0.9), (0.55, 0.72, 1.0)]
# Emissive strength: 0 at 0 s, 2 at 1 s, 0.4 at 2 s, a spline with flat ends and top.
GLOW_TIMES = [0.0, 1.0, 2.0]
GLOW = [(0.0, 0.0, 0.0), (0.0, 2.0, 0.0), (0.0, 0.4, 0.0)]  # (in-tangent, value, out-tangent)


def stripes():
    """A 32×2 PNG of four vertical stripes: warm white and dark slate, eight texels each."""
    light, dark = bytes((255, 236, 200)), bytes((46, 50, 66))
    row = b"".join((light if (x // 8) % 2 == 0 else dark) for x in range(32))
    return png_bytes(32, 2, [row, row])


def orb(b):
    """A UV sphere of RADIUS about (0, RADIUS, 0): u round the equator (the seam's column
    doubled), v from the top."""
    positions, normals, uvs, tris = [], [], [], []
    for i in range(RINGS + 1):
        theta = math.pi * i / RINGS
        for j in range(SEGMENTS + 1):
            phi = 2.0 * math.pi * j / SEGMENTS
            n = (math.sin(theta) * math.sin(phi), math.cos(theta), math.sin(theta) * math.cos(phi))
            positions.append((RADIUS * n[0], RADIUS + RADIUS * n[1], RADIUS * n[2]))
            normals.append(n)
            uvs.append((j / SEGMENTS, i / RINGS))
    row = SEGMENTS + 1
    for i in range(RINGS):
        for j in range(SEGMENTS):
            a, c = i * row + j, (i + 1) * row + j
            if i > 0:
                tris.append((a, c, a + 1))
            if i < RINGS - 1:
                tris.append((a + 1, c, c + 1))
    return {"attributes": {"POSITION": b.floats(positions, "VEC3", with_bounds=True),
                           "NORMAL": b.floats(normals, "VEC3"),
                           "TEXCOORD_0": b.floats(uvs, "VEC2")},
            "indices": b.indices(tris, len(positions)), "material": 0}


def pointer(sampler, target):
    return {"sampler": sampler, "target": {"path": "pointer", "extensions": {
        "KHR_animation_pointer": {"pointer": target}}}}


def main():
    b = BufferBuilder()
    floor = {"attributes": {"POSITION": b.floats([(-5, 0, 5), (5, 0, 5), (5, 0, -5), (-5, 0, -5)],
                                                 "VEC3", with_bounds=True),
                            "NORMAL": b.floats([(0, 1, 0)] * 4, "VEC3")},
             "indices": b.indices([(0, 1, 2), (0, 2, 3)], 4), "material": 1}
    meshes = [{"primitives": [orb(b)]}, {"primitives": [floor]}]
    nodes = [
        {"name": "orb", "mesh": 0},
        {"name": "floor", "mesh": 1},
        {"name": "lamp", "translation": [1.2, 3.2, 1.8],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "camera", "camera": 0, "translation": [0.0, 1.35, 3.9],
         "rotation": list(quat_axis_angle((1.0, 0.0, 0.0), -0.16))},
    ]
    transform = {"offset": [0.0, 0.0], "rotation": 0.0, "scale": [3.0, 1.0]}
    orb_material = {
        "name": "orb",
        "pbrMetallicRoughness": {
            "baseColorFactor": list(COLOURS[0]),
            "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": dict(transform)}},
            "metallicFactor": 0.0, "roughnessFactor": 0.5},
        "emissiveFactor": list(GLOW_COLOURS[0]),
        "emissiveTexture": {"index": 0, "extensions": {"KHR_texture_transform": dict(transform)}},
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 0.0}},
    }
    floor_material = {"name": "floor", "pbrMetallicRoughness": {
        "baseColorFactor": [0.55, 0.55, 0.58, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8}}

    times = b.floats([(t,) for t in TIMES], "SCALAR", with_bounds=True)
    glow_times = b.floats([(t,) for t in GLOW_TIMES], "SCALAR", with_bounds=True)
    samplers = [
        {"input": times, "interpolation": "LINEAR", "output": b.floats(COLOURS, "VEC4")},
        {"input": times, "interpolation": "LINEAR", "output": b.floats(OFFSETS, "VEC2")},
        {"input": glow_times, "interpolation": "CUBICSPLINE",
         "output": b.floats([(v,) for key in GLOW for v in key], "SCALAR")},
        {"input": times, "interpolation": "LINEAR", "output": b.floats(LIGHT_COLOURS, "VEC3")},
        {"input": times, "interpolation": "LINEAR", "output": b.floats(GLOW_COLOURS, "VEC3")},
    ]
    transform_of = "/materials/0/%s/extensions/KHR_texture_transform/offset"
    channels = [
        pointer(0, "/materials/0/pbrMetallicRoughness/baseColorFactor"),
        pointer(1, transform_of % "pbrMetallicRoughness/baseColorTexture"),
        pointer(1, transform_of % "emissiveTexture"),
        pointer(2, "/materials/0/extensions/KHR_materials_emissive_strength/emissiveStrength"),
        pointer(3, "/extensions/KHR_lights_punctual/lights/0/color"),
        pointer(4, "/materials/0/emissiveFactor"),
    ]

    uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(b.bin)).decode()
    png = "data:image/png;base64," + base64.b64encode(stripes()).decode()
    gltf = {
        "asset": {"version": "2.0", "generator": "raylab tools/make_animation_pointer_demo.py"},
        "extensionsUsed": ["KHR_animation_pointer", "KHR_lights_punctual",
                           "KHR_materials_emissive_strength", "KHR_texture_transform"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": list(LIGHT_COLOURS[0]), "intensity": 14.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": nodes,
        "meshes": meshes,
        "animations": [{"name": "glow", "samplers": samplers, "channels": channels}],
        "materials": [orb_material, floor_material],
        "textures": [{"source": 0}],
        "images": [{"uri": png}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1,
                                                           "aspectRatio": 1.0}}],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": len(b.bin), "uri": uri}],
    }
    write_scene(gltf, "animation-pointer", "glow.gltf")


if __name__ == "__main__":
    main()
