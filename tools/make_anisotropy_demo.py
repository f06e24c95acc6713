#!/usr/bin/env python3
"""Writes the KHR_materials_anisotropy demonstration scene (docs/gltf.md, "Anisotropy").

Usage (from the project folder):

    python3 tools/make_anisotropy_demo.py [OUT_DIR]

OUT_DIR defaults to scenes/anisotropy beside this tools/ folder. It writes anisotropy.gltf,
anisotropy.bin and disc_anisotropy.png there. Standard library only; the output is the same
bytes on every run.

The scene, in glTF units (metres, +y up):

- a circularly brushed metal disc lying on the floor: its grooves run round the centre, so it
  is rougher across them, radially. The direction comes from an anisotropyTexture (red and
  green: the radial direction in tangent space, blue: strength 1) over a constant TANGENT
  (+x, w = 1: the bitangent is N x T = -z, towards decreasing v as glTF's convention has it);
  anisotropyStrength 0.7 over roughness 0.15, so alpha_t = mix(0.0225, 1, 0.49) = 0.50 and
  alpha_b = 0.0225;
- four UV spheres behind it with a TANGENT attribute along their parallels (east, +u):
  three gold metals of roughness 0.3 and strength 0.8 with anisotropyRotation 0, pi/4 and pi/2
  (highlights stretched along the parallels, diagonally, along the meridians) and a red
  dielectric (strength 0.8, rotation 0: the white specular over the diffuse red stretches);
- a dark grey floor, one point light (KHR_lights_punctual, radiometric W/sr) whose highlights
  the disc and the spheres show, and one perspective camera (aspectRatio 1.5).

Render it with an environment (the docs use Poly Haven's aircraft workshop, whose ceiling
lights become streaks), and without the extension through tools/gltf_without.py.
"""

import json
import math
import os

from gltfgen import BufferBuilder, generator_main, look_along, normalize, png_bytes, r6, sub
from make_showcase import uv_sphere

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUT = os.path.join(ROOT, "scenes", "anisotropy")
EXT = "KHR_materials_anisotropy"
TEX = 128          # anisotropy texture size (texels per side)


def disc(radius=1.0, rings=32, segments=128):
    """A disc in the y = 0 plane facing +y: positions, normals, uvs (u = 0.5 + x / 2r,
    v = 0.5 + z / 2r) and counter-clockwise triangles."""
    pos, uv = [(0.0, 0.0, 0.0)], [(0.5, 0.5)]
    for j in range(1, rings + 1):
        r = radius * j / rings
        for i in range(segments):
            phi = 2 * math.pi * i / segments
            x, z = r * math.cos(phi), r * math.sin(phi)
            pos.append((x, 0.0, z))
            uv.append((0.5 + x / (2 * radius), 0.5 + z / (2 * radius)))
    tris = []
    ring = lambda j, i: 1 + (j - 1) * segments + i % segments  # noqa: E731
    for i in range(segments):
        tris.append((0, ring(1, i + 1), ring(1, i)))
    for j in range(1, rings):
        for i in range(segments):
            a, b = ring(j, i), ring(j, i + 1)
            c, d = ring(j + 1, i), ring(j + 1, i + 1)
            tris.append((a, b, d))
            tris.append((a, d, c))
    return pos, [(0.0, 1.0, 0.0)] * len(pos), uv, tris


def tangent_sphere():
    """make_showcase.py's unit UV sphere (u around, increasing to the right seen from +z; v from
    the north pole) with tangents along +u (east, d/d phi with phi = 2 pi u) and w = 1, so the
    bitangent N x T points north, towards decreasing v."""
    pos, nor, uv, tris = uv_sphere(64, 32)
    tan = [(-math.cos(2 * math.pi * u), 0.0, math.sin(2 * math.pi * u), 1.0) for u, _ in uv]
    return pos, nor, uv, tris, tan


def disc_texture():
    """The disc's anisotropyTexture: at texel centre (u, v), the radial direction (x, z) / r of
    the disc point (x, z) = (2u - 1, 2v - 1), in tangent space (T = +x, B = -z): (x, -z) / r,
    mapped from [-1, 1] to [0, 255]; blue (strength) 255. Outside the disc, the same."""
    rows = []
    for j in range(TEX):
        row = bytearray()
        for i in range(TEX):
            x, z = 2 * (i + 0.5) / TEX - 1, 2 * (j + 0.5) / TEX - 1
            r = math.hypot(x, z)
            dx, dy = x / r, -z / r
            row += bytes((round((dx + 1) * 127.5), round((dy + 1) * 127.5), 255))
        rows.append(bytes(row))
    return png_bytes(TEX, TEX, rows)


def build(out_dir):
    b = BufferBuilder()

    def geometry(pos, nor, uv, tris, tangents):
        attrs = {"POSITION": b.floats(pos, "VEC3", with_bounds=True),
                 "NORMAL": b.floats([normalize(n) for n in nor], "VEC3"),
                 "TEXCOORD_0": b.floats(uv, "VEC2"),
                 "TANGENT": b.floats(tangents, "VEC4")}
        return attrs, b.indices(tris, len(pos))

    dpos, dnor, duv, dtris = disc()
    geo_disc = geometry(dpos, dnor, duv, dtris, [(1.0, 0.0, 0.0, 1.0)] * len(dpos))
    spos, snor, suv, stris, stan = tangent_sphere()
    geo_sphere = geometry(spos, snor, suv, stris, stan)
    fpos = [(-6.0, 0.0, -6.0), (6.0, 0.0, -6.0), (6.0, 0.0, 6.0), (-6.0, 0.0, 6.0)]
    geo_floor = geometry(fpos, [(0.0, 1.0, 0.0)] * 4, [(0, 0), (1, 0), (1, 1), (0, 1)],
                         [(0, 2, 1), (0, 3, 2)], [(1.0, 0.0, 0.0, 1.0)] * 4)

    def metal(name, colour, roughness, aniso):
        m = {"name": name,
             "pbrMetallicRoughness": {"baseColorFactor": list(colour) + [1.0],
                                      "metallicFactor": 1.0, "roughnessFactor": roughness}}
        if aniso is not None:
            m["extensions"] = {EXT: aniso}
        return m

    gold = (1.0, 0.766, 0.336)
    materials = [
        {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.18, 0.18, 0.19, 1.0],
                                                   "metallicFactor": 0.0,
                                                   "roughnessFactor": 0.8}},
        metal("brushed disc", (0.91, 0.92, 0.92), 0.15,
              {"anisotropyStrength": 0.7, "anisotropyTexture": {"index": 0}}),
        metal("gold, rotation 0", gold, 0.3, {"anisotropyStrength": 0.8}),
        metal("gold, rotation pi/4", gold, 0.3,
              {"anisotropyStrength": 0.8, "anisotropyRotation": r6(math.pi / 4)}),
        metal("gold, rotation pi/2", gold, 0.3,
              {"anisotropyStrength": 0.8, "anisotropyRotation": r6(math.pi / 2)}),
        {"name": "red plastic, rotation 0",
         "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.05, 0.04, 1.0],
                                  "metallicFactor": 0.0, "roughnessFactor": 0.3},
         "extensions": {EXT: {"anisotropyStrength": 0.8}}},
    ]

    def prim(geo, material):
        attrs, idx = geo
        return {"attributes": attrs, "indices": idx, "material": material}

    meshes = [{"name": "floor", "primitives": [prim(geo_floor, 0)]},
              {"name": "disc", "primitives": [prim(geo_disc, 1)]}]
    meshes += [{"name": materials[k]["name"], "primitives": [prim(geo_sphere, k)]}
               for k in range(2, 6)]

    eye, look = (0.0, 2.3, 3.9), (0.0, 0.25, -0.3)
    light_pos = (0.6, 2.6, -2.4)
    nodes = [{"name": "floor", "mesh": 0, "translation": [0.0, -0.001, 0.0]},
             {"name": "disc", "mesh": 1, "translation": [0.0, 0.0, 0.65], "scale": [1.1, 1.0, 1.1]}]
    radius = 0.42
    for k, x in enumerate((-1.65, -0.55, 0.55, 1.65)):
        nodes.append({"name": meshes[2 + k]["name"], "mesh": 2 + k,
                      "translation": r6((x, radius, -1.0)), "scale": r6((radius,) * 3)})
    nodes.append({"name": "light", "translation": r6(light_pos),
                  "extensions": {"KHR_lights_punctual": {"light": 0}}})
    nodes.append({"name": "camera", "camera": 0, "translation": r6(eye),
                  "rotation": r6(look_along(sub(look, eye)))})

    gltf = {
        "asset": {"version": "2.0", "generator": "raylab tools/make_anisotropy_demo.py",
                  "copyright": "raylab contributors, CC0"},
        "extensionsUsed": ["KHR_lights_punctual", EXT],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "key", "type": "point", "color": [1.0, 0.95, 0.9], "intensity": 12.0}]}},
        "scene": 0,
        "scenes": [{"name": "anisotropy", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"name": "camera", "type": "perspective",
                     "perspective": {"yfov": 0.62, "aspectRatio": 1.5, "znear": 0.05,
                                     "zfar": 100.0}}],
        "meshes": meshes,
        "materials": materials,
        "textures": [{"sampler": 0, "source": 0}],
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071}],
        "images": [{"uri": "disc_anisotropy.png", "mimeType": "image/png"}],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"uri": "anisotropy.bin", "byteLength": len(b.bin)}],
    }
    os.makedirs(out_dir, exist_ok=True)
    files = {"anisotropy.gltf": (json.dumps(gltf, indent=1) + "\n").encode(),
             "anisotropy.bin": bytes(b.bin),
             "disc_anisotropy.png": disc_texture()}
    for name, data in files.items():
        with open(os.path.join(out_dir, name), "wb") as f:
            f.write(data)
    for name in sorted(files):
        print("%-22s %9d bytes" % (name, len(files[name])))


if __name__ == "__main__":
    generator_main(build, DEFAULT_OUT, __doc__)
