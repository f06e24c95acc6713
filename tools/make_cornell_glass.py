#!/usr/bin/env python3
"""Writes the lab's glass-and-mirror box as a glTF 2.0 scene, for renderers that read glTF.

Usage (from the project folder):

    python3 tools/make_cornell_glass.py [OUT_DIR]

OUT_DIR defaults to scenes/cornell-glass beside this tools/ folder. It writes
cornell-glass.gltf and cornell-glass.bin there. Standard library only; the output is the same
bytes on every run.

The scene is raylab's `cornell-area --material tall=mirror,short=glass` (the box that
tools/compare_mitsuba.py also builds for Mitsuba), in glTF terms as
docs/scene-conventions.md reads them:

- geometry: the 30 triangles of src/load/cornell.rs (tools/compare_mitsuba.py's
  `box_triangles`: the box [-1, 1]^3 without its front wall, the short and the tall block) and
  the two triangles of the `cornell-area` ceiling patch. The lab's frame has y down; glTF's has
  +y up. The conversion is the half turn about z, (x, y, z) -> (-x, -y, z), as raylab's scene
  files turn the built-in box (a rotation, not a mirror: the image is not flipped). raylab's
  front side is that of normalize(cross(v2 - v0, v1 - v0)), glTF's that of the
  counter-clockwise winding, cross(v1 - v0, v2 - v0): every triangle is written as (v0, v2, v1)
  so that the front sides stay the same (it matters for the one-sided light and for which side
  of the glass is its inside). Each part is its own mesh and node (no node transforms), with
  flat per-face NORMALs;
- walls and floor: Lambertian with the lab's reflectances (baseColorFactor = rho, metallic 0,
  roughness 1, and KHR_materials_specular specularFactor 0, which removes the dielectric's
  specular layer: the conventions' dielectric_brdf becomes (1 - 0) rho / pi, and Cycles'
  importer maps factor 0 to Specular IOR Level 0, which ../shared/cycles/README.md checked to be
  pure Lambert);
- tall block: a perfect mirror (white, metallic 1, roughness 0: Schlick with F0 = 1 is 1 at
  every angle, as raylab's `mirror`);
- short block: solid clear glass of index 1.5 (white, metallic 0, roughness 0,
  KHR_materials_transmission 1, KHR_materials_ior 1.5, KHR_materials_volume thicknessFactor 1
  and no attenuation: with a volume the conventions and render_gltf.py both make a refracting
  interface into the block, not a thin wall);
- ceiling light: the `cornell-area` patch (0.48 x 0.38, 0.001 below the ceiling), one-sided
  (doubleSided false: only its lower, front face emits), reflecting nothing (base colour black,
  specularFactor 0). Its radiance is emissiveFactor x emissiveStrength (conventions, "Emission";
  no photometric units): emissiveFactor is limited to [0, 1] by glTF, so it is
  (1, 12/17, 4/17) x KHR_materials_emissive_strength 17 = (17, 12, 4) W sr^-1 m^-2;
- camera: the lab's, at (0, 0, -3) looking along +z with +y up (the camera node is turned half
  a turn about y, since a glTF camera looks along its local -z), vertical fov 2 atan(0.5)
  (the image plane at distance 1 spans [-0.5, 0.5]), aspectRatio 1 (default render size
  600 x 600; raylab's box renders are 500 x 500 by default: pass --width/--height).
"""

import json
import math
import os
import struct
import sys

sys.dont_write_bytecode = True  # leave no tools/__pycache__ behind
from compare_mitsuba import AREA_LIGHT_CORNERS, AREA_LIGHT_RADIANCE, PARTS, box_triangles  # noqa: E402
from gltfgen import cross, normalize, sub  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUT = os.path.join(ROOT, "scenes", "cornell-glass")
NAME = "cornell-glass"

FLOAT = 5126
ARRAY_BUFFER = 34962


def to_gltf(p):
    """Lab frame (y down) -> glTF frame (+y up): the half turn about z."""
    return (-p[0], -p[1], p[2])


def gltf_triangles(tris):
    """raylab-wound lab triangles -> counter-clockwise glTF triangles, same front sides."""
    out = []
    for a, b, c in tris:
        out.append((to_gltf(a), to_gltf(c), to_gltf(b)))
    return out


def floats(x):
    """Exactly representable in float32 (so the JSON and the .bin agree)."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def build(out_dir):
    tris, rho = box_triangles()
    a, b, c, d = AREA_LIGHT_CORNERS
    light_tris = [(a, b, c), (a, c, d)]  # as src/load/cornell.rs pushes them

    parts = [(name, tris[lo:hi], rho[lo]) for name, (lo, hi) in PARTS.items()]
    parts.append(("light", light_tris, (0.0, 0.0, 0.0)))

    lambert_ext = {"KHR_materials_specular": {"specularFactor": 0.0}}
    radiance = AREA_LIGHT_RADIANCE
    strength = max(radiance)
    materials, mat_index = [], {}
    for name, _, colour in parts:
        if name == "tall":
            m = {"name": "tall: mirror",
                 "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                                          "metallicFactor": 1.0, "roughnessFactor": 0.0}}
        elif name == "short":
            m = {"name": "short: glass 1.5",
                 "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                                          "metallicFactor": 0.0, "roughnessFactor": 0.0},
                 "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                                "KHR_materials_ior": {"ior": 1.5},
                                "KHR_materials_volume": {"thicknessFactor": 1.0}}}
        elif name == "light":
            m = {"name": "ceiling light",
                 "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0],
                                          "metallicFactor": 0.0, "roughnessFactor": 1.0},
                 "emissiveFactor": [r / strength for r in radiance],
                 "extensions": dict(lambert_ext, KHR_materials_emissive_strength={
                     "emissiveStrength": strength})}
        else:
            m = {"name": f"{name}: Lambert",
                 "pbrMetallicRoughness": {"baseColorFactor": [*colour, 1.0],
                                          "metallicFactor": 0.0, "roughnessFactor": 1.0},
                 "extensions": dict(lambert_ext)}
        mat_index[name] = len(materials)
        materials.append(m)

    bin_ = bytearray()
    views, accessors, meshes, nodes = [], [], [], []

    def add(rows, kind, bounds):
        data = struct.pack("<%df" % (3 * len(rows)), *[x for r in rows for x in r])
        views.append({"buffer": 0, "byteOffset": len(bin_), "byteLength": len(data),
                      "target": ARRAY_BUFFER})
        bin_.extend(data)
        acc = {"bufferView": len(views) - 1, "componentType": FLOAT, "count": len(rows),
               "type": kind}
        if bounds:
            acc["min"] = [floats(min(r[k] for r in rows)) for k in range(3)]
            acc["max"] = [floats(max(r[k] for r in rows)) for k in range(3)]
        accessors.append(acc)
        return len(accessors) - 1

    for name, part_tris, _ in parts:
        pos, nor = [], []
        for t in gltf_triangles(part_tris):
            n = normalize(cross(sub(t[1], t[0]), sub(t[2], t[0])))
            for v in t:
                pos.append(tuple(floats(x) for x in v))
                nor.append(n)
        prim = {"attributes": {"POSITION": add(pos, "VEC3", True), "NORMAL": add(nor, "VEC3", False)},
                "material": mat_index[name], "mode": 4}
        meshes.append({"name": name, "primitives": [prim]})
        nodes.append({"name": name, "mesh": len(meshes) - 1})

    yfov = 2.0 * math.atan(0.5)
    cameras = [{"name": "lab camera", "type": "perspective",
                "perspective": {"yfov": yfov, "aspectRatio": 1.0, "znear": 0.01, "zfar": 100.0}}]
    # Half a turn about +y: local -z (the view) becomes +z, local +y stays +y.
    nodes.append({"name": "lab camera", "camera": 0, "translation": [0.0, 0.0, -3.0],
                  "rotation": [0.0, 1.0, 0.0, 0.0]})

    gltf = {
        "asset": {"version": "2.0", "generator": "raylab tools/make_cornell_glass.py",
                  "copyright": "raylab contributors, CC0"},
        "extensionsUsed": ["KHR_materials_emissive_strength", "KHR_materials_ior",
                           "KHR_materials_specular", "KHR_materials_transmission",
                           "KHR_materials_volume"],
        "scene": 0,
        "scenes": [{"name": NAME, "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": cameras,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": NAME + ".bin", "byteLength": len(bin_)}],
    }
    os.makedirs(out_dir, exist_ok=True)
    files = {NAME + ".gltf": (json.dumps(gltf, indent=1) + "\n").encode(), NAME + ".bin": bytes(bin_)}
    for name, data in files.items():
        with open(os.path.join(out_dir, name), "wb") as f:
            f.write(data)
    for name in sorted(files):
        print("%-20s %7d bytes" % (name, len(files[name])))
    print("%d triangles in %d meshes; light radiance %s = emissiveFactor %s x strength %g"
          % (len(tris) + 2, len(meshes), list(radiance),
             [round(x, 6) for x in materials[mat_index["light"]]["emissiveFactor"]], strength))


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else DEFAULT_OUT
    if out_dir in ("-h", "--help"):
        print(__doc__)
        return
    build(out_dir)


if __name__ == "__main__":
    main()
