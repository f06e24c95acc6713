#!/usr/bin/env python3
"""Writes the KHR_materials_dispersion demonstration scene (docs/gltf.md, "Dispersion"):

    python3 tools/make_dispersion_demo.py [OUT_DIR]     (default scenes/dispersion)

A dark room. At the left, a bright emitting strip shines through a slit in a black baffle: a
narrow beam that meets a glass prism (axis along z, apex up) standing on a white floor. The
prism refracts it down onto the floor to its right, where, with dispersion, it fans out into a
spectrum (red deviated least, violet most). In front, three glass spheres of increasing
dispersion look at a backdrop of thin white emitting bars, whose images they split into
coloured fringes. The glass is KHR_materials_transmission + KHR_materials_volume (a refracting
volume, ior 1.5, clear) with KHR_materials_dispersion; `tools/gltf_without.py` strips the
dispersion for the comparison picture.

The dispersions are exaggerated for the picture (the prism 4, V_d = 5; the spheres 1, 2 and 4,
V_d = 20, 10 and 5): with crown glass (0.33) the fan is a sixth as wide.

Standard library only; writes dispersion.gltf and dispersion.bin (about 0.3 MB), CC0.
"""

import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gltfgen import BufferBuilder, look_along, normalize, r6, sub  # noqa: E402

DEFAULT_OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes",
                           "dispersion")

PRISM_DISPERSION = 1.0
SPHERE_DISPERSIONS = (0.36, 1.0, 2.04)


def quad(p0, p1, p2, p3):
    """A quad p0 p1 p2 p3, counter-clockwise seen from its front (flat normal)."""
    n = normalize(crossp(sub(p1, p0), sub(p3, p0)))
    return [p0, p1, p2, p3], [n] * 4, [(0, 1, 2), (0, 2, 3)]


def outward(mesh, centre):
    """`mesh` (a convex solid's faces) with every triangle turned to face away from `centre`,
    its normals too."""
    pos, nor, tris = mesh
    nor = list(nor)
    out = []
    for a, b, c in tris:
        n = crossp(sub(pos[b], pos[a]), sub(pos[c], pos[a]))
        mid = tuple((pos[a][k] + pos[b][k] + pos[c][k]) / 3 for k in range(3))
        if sum(n[k] * (mid[k] - centre[k]) for k in range(3)) < 0:
            b, c = c, b
            n = tuple(-x for x in n)
        for v in (a, b, c):
            nor[v] = normalize(n)
        out.append((a, b, c))
    return pos, nor, out


def crossp(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def merge(*meshes):
    pos, nor, tris = [], [], []
    for p, n, t in meshes:
        base = len(pos)
        pos += p
        nor += n
        tris += [(a + base, b + base, c + base) for a, b, c in t]
    return pos, nor, tris


def prism_x(section, x0, x1):
    """A prism along x from x0 to x1 over the convex polygon `section` of (y, z) points, flat
    faces turned out."""
    n = len(section)

    def p3(x, q):
        return (x, q[0], q[1])
    sides = [quad(p3(x0, section[i]), p3(x0, section[(i + 1) % n]),
                  p3(x1, section[(i + 1) % n]), p3(x1, section[i])) for i in range(n)]
    ends = [([p3(x, q) for q in section], [(1.0, 0.0, 0.0)] * n,
             [(0, i, i + 1) for i in range(1, n - 1)]) for x in (x0, x1)]
    cy = sum(q[0] for q in section) / n
    cz = sum(q[1] for q in section) / n
    return outward(merge(*sides, *ends), ((x0 + x1) / 2, cy, cz))


def box_at(centre, size):
    """An axis-aligned box of `size` centred at `centre`, faces turned out."""
    lo = tuple(centre[k] - size[k] / 2 for k in range(3))
    hi = tuple(centre[k] + size[k] / 2 for k in range(3))
    return prism_x([(lo[1], lo[2]), (hi[1], lo[2]), (hi[1], hi[2]), (lo[1], hi[2])], lo[0],
                   hi[0])


def sphere(centre, radius, segments=64, rings=32):
    pos, nor, tris = [], [], []
    for j in range(rings + 1):
        theta = math.pi * j / rings
        for i in range(segments + 1):
            phi = 2 * math.pi * i / segments
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            nor.append(n)
            pos.append(tuple(centre[k] + radius * n[k] for k in range(3)))
    w = segments + 1
    for j in range(rings):
        for i in range(segments):
            a, b, c, d = j * w + i, j * w + i + 1, (j + 1) * w + i, (j + 1) * w + i + 1
            if j != 0:
                tris.append((a, c, b))
            if j != rings - 1:
                tris.append((b, c, d))
    return pos, nor, tris


def glass(name, dispersion):
    return {"name": name,
            "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0.0,
                                     "roughnessFactor": 0.0},
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                           "KHR_materials_volume": {"thicknessFactor": 1.0},
                           "KHR_materials_ior": {"ior": 1.5},
                           "KHR_materials_dispersion": {"dispersion": dispersion}}}


def diffuse(name, c):
    return {"name": name, "pbrMetallicRoughness": {"baseColorFactor": [c, c, c, 1],
                                                   "metallicFactor": 0.0, "roughnessFactor": 1.0}}


def emitter(name, strength):
    return {"name": name, "emissiveFactor": [1.0, 1.0, 1.0],
            "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0,
                                     "roughnessFactor": 1.0},
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}}


def build(out_dir):
    b = BufferBuilder()
    # The backdrop: a black wall at z = -3 with a grid of thin emitting bars, the scene's only
    # light, sharp bright-on-dark edges for the glass to split.
    floor = quad((-8.0, 0.0, 6.0), (8.0, 0.0, 6.0), (8.0, 0.0, -3.0), (-8.0, 0.0, -3.0))
    backdrop = quad((-8.0, 0.0, -3.0), (8.0, 0.0, -3.0), (8.0, 6.0, -3.0), (-8.0, 6.0, -3.0))
    bar = 0.03
    bars = merge(*[quad((-8.0, y, -2.99), (8.0, y, -2.99), (8.0, y + bar, -2.99),
                        (-8.0, y + bar, -2.99)) for y in [0.35 + 0.45 * k for k in range(12)]],
                 *[quad((x, 0.0, -2.98), (x + bar, 0.0, -2.98), (x + bar, 6.0, -2.98),
                        (x, 6.0, -2.98)) for x in [-4.5 + 0.6 * k for k in range(16)]])
    # The prism lies along x, apex down, on two black blocks: looking through it the camera
    # sees the bars above, turned by some 40 degrees.
    side, py, pz = 0.55, 0.62, 0.4
    apex = side * math.sqrt(3) / 2
    the_prism = prism_x([(py - 2 * apex / 3, pz), (py + apex / 3, pz - side / 2),
                         (py + apex / 3, pz + side / 2)], -1.3, 1.3)
    blocks = merge(*[box_at((x, (py - apex / 3) / 2, pz), (0.3, py - apex / 3, 0.3))
                     for x in (-1.15, 1.15)])
    spheres = [sphere((x, 0.26, 1.45), 0.26) for x in (-0.75, 0.0, 0.75)]

    materials = [
        diffuse("floor", 0.3),
        diffuse("black", 0.01),
        emitter("bars", 4.0),
        glass("prism glass", PRISM_DISPERSION),
    ] + [glass("sphere glass %g" % d, d) for d in SPHERE_DISPERSIONS]

    def mesh(name, geo, material):
        pos, nor, tris = geo
        # Every triangle's winding agrees with its normals (emitters light their front).
        for t in tris:
            n = crossp(sub(pos[t[1]], pos[t[0]]), sub(pos[t[2]], pos[t[0]]))
            assert all(sum(n[k] * nor[v][k] for k in range(3)) > 0 for v in t), name
        attrs = {"POSITION": b.floats(pos, "VEC3", with_bounds=True),
                 "NORMAL": b.floats([normalize(n) for n in nor], "VEC3")}
        return {"name": name, "primitives": [{"attributes": attrs,
                                              "indices": b.indices(tris, len(pos)),
                                              "material": material, "mode": 4}]}

    meshes = [mesh("floor", floor, 0), mesh("backdrop", backdrop, 1), mesh("bars", bars, 2),
              mesh("blocks", blocks, 1), mesh("prism", the_prism, 3)]
    meshes += [mesh("sphere %g" % d, s, 4 + k)
               for k, (d, s) in enumerate(zip(SPHERE_DISPERSIONS, spheres))]

    eye = (0.0, 0.95, 4.2)
    look = (0.0, 0.75, 0.0)
    nodes = [{"name": m["name"], "mesh": k} for k, m in enumerate(meshes)]
    nodes.append({"name": "camera", "camera": 0, "translation": r6(eye),
                  "rotation": r6(look_along(sub(look, eye)))})
    gltf = {
        "asset": {"version": "2.0", "generator": "raylab tools/make_dispersion_demo.py",
                  "copyright": "raylab contributors, CC0"},
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_volume",
                           "KHR_materials_ior", "KHR_materials_dispersion",
                           "KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": "dispersion", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"name": "camera", "type": "perspective",
                     "perspective": {"yfov": 0.62, "aspectRatio": 1.5, "znear": 0.05,
                                     "zfar": 100.0}}],
        "meshes": meshes,
        "materials": materials,
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"uri": "dispersion.bin", "byteLength": len(b.bin)}],
    }
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "dispersion.gltf"), "w", encoding="utf-8") as f:
        f.write(json.dumps(gltf, indent=1) + "\n")
    with open(os.path.join(out_dir, "dispersion.bin"), "wb") as f:
        f.write(bytes(b.bin))
    print("wrote %s: %d bytes of geometry" % (os.path.join(out_dir, "dispersion.gltf"),
                                              len(b.bin)))


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else DEFAULT_OUT
    if out_dir in ("-h", "--help"):
        sys.exit(__doc__.strip())
    build(out_dir)


if __name__ == "__main__":
    main()
