#!/usr/bin/env python3
"""Writes the subsurface showcase: two Stanford bunnies on a floor, the left
one of wax that light scatters through (glTF `KHR_materials_volume_scatter`
behind `KHR_materials_diffuse_transmission`: raylab's random walk), the
right one its surface twin (an opaque diffuse material of the same colour),
lit by a low sun from behind and a camera in the file.

    python3 tools/make_subsurface_scene.py OUT.gltf [--obj BUNNY.obj]

The bunny scan has holes in its base; a volume must be closed, so each hole
(a loop of edges that only one triangle uses) is filled by a fan around its
centroid. The wax: multiscatterColor (0.85, 0.55, 0.3), mean free paths
(6, 3, 1.5) mm (extinction 1/mfp, as attenuationColor e^-1 over
attenuationDistance 1 mm would give per channel; written as one distance
and a colour), isotropic scattering, no specular layer (specularFactor 0),
so that Cycles' Principled BSDF with Subsurface Weight 1, method Random
Walk, Specular IOR Level 0 and radius 4 pi mfp is the same material
(tools/cycles_subsurface.py). Writes OUT.gltf and OUT.bin beside it.
"""
import argparse
import json
import math
import os
import struct

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("out")
ap.add_argument("--obj", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared",
                                               "models", "stanford-bunny.obj"))
a = ap.parse_args()

RHO = [0.85, 0.55, 0.3]
MFP_MM = [6.0, 3.0, 1.5]

# The mesh, welded by position.
pos, key, tris = [], {}, []
raw = []
for line in open(a.obj):
    p = line.split()
    if not p:
        continue
    if p[0] == "v":
        v = tuple(float(x) for x in p[1:4])
        raw.append(key.setdefault(v, len(key)))
        if len(key) > len(pos):
            pos.append(v)
    elif p[0] == "f":
        idx = [int(x.split("/")[0]) for x in p[1:]]
        idx = [raw[i - 1] if i > 0 else raw[len(raw) + i] for i in idx]
        for k in range(1, len(idx) - 1):
            t = (idx[0], idx[k], idx[k + 1])
            if len(set(t)) == 3:
                tris.append(t)

# Holes: directed edges whose reverse no triangle has, chained into loops.
count = {}
for t in tris:
    for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
        u = (min(e), max(e))
        count[u] = count.get(u, 0) + 1
nxt = {}
for t in tris:
    for i, j in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
        if count[(min(i, j), max(i, j))] % 2 == 1:
            nxt[j] = i  # the fill runs the other way
filled = 0
while nxt:
    start = next(iter(nxt))
    loop, v = [], start
    while v in nxt:
        loop.append(v)
        v = nxt.pop(v)
    c = [sum(pos[i][k] for i in loop) / len(loop) for k in range(3)]
    pos.append(tuple(c))
    ci = len(pos) - 1
    for i in range(len(loop)):
        tris.append((loop[i], loop[(i + 1) % len(loop)], ci))
    filled += 1

# Scale: 0.15 m tall, standing on y = 0, centred in x and z.
lo = [min(p[k] for p in pos) for k in range(3)]
hi = [max(p[k] for p in pos) for k in range(3)]
s = 0.15 / (hi[1] - lo[1])
mid = [(lo[k] + hi[k]) / 2 for k in range(3)]
pos = [((p[0] - mid[0]) * s, (p[1] - lo[1]) * s, (p[2] - mid[2]) * s) for p in pos]

# Smooth normals, area-weighted.
nrm = [[0.0, 0.0, 0.0] for _ in pos]
for t in tris:
    p0, p1, p2 = (pos[i] for i in t)
    e1 = [p1[k] - p0[k] for k in range(3)]
    e2 = [p2[k] - p0[k] for k in range(3)]
    n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
    for i in t:
        for k in range(3):
            nrm[i][k] += n[k]
for n in nrm:
    ln = math.sqrt(sum(x * x for x in n)) or 1.0
    for k in range(3):
        n[k] /= ln

lo = [min(p[k] for p in pos) for k in range(3)]
hi = [max(p[k] for p in pos) for k in range(3)]
blob = bytearray()


def view(data, target):
    off = len(blob)
    blob.extend(data)
    while len(blob) % 4:
        blob.append(0)
    views.append({"buffer": 0, "byteOffset": off, "byteLength": len(data), "target": target})
    return len(views) - 1


views, accessors = [], []
vp = view(b"".join(struct.pack("<3f", *p) for p in pos), 34962)
accessors.append({"bufferView": vp, "componentType": 5126, "count": len(pos), "type": "VEC3",
                  "min": lo, "max": hi})
vn = view(b"".join(struct.pack("<3f", *n) for n in nrm), 34962)
accessors.append({"bufferView": vn, "componentType": 5126, "count": len(nrm), "type": "VEC3"})
vi = view(b"".join(struct.pack("<3I", *t) for t in tris), 34963)
accessors.append({"bufferView": vi, "componentType": 5125, "count": 3 * len(tris), "type": "SCALAR"})
F = 2.0
floor = [(-F, 0, F), (F, 0, F), (F, 0, -F), (-F, 0, -F)]
vf = view(b"".join(struct.pack("<3f", *p) for p in floor), 34962)
accessors.append({"bufferView": vf, "componentType": 5126, "count": 4, "type": "VEC3",
                  "min": [-F, 0, -F], "max": [F, 0, F]})
vfi = view(struct.pack("<6I", 0, 1, 2, 0, 2, 3), 34963)
accessors.append({"bufferView": vfi, "componentType": 5125, "count": 6, "type": "SCALAR"})

sigma = [1000.0 / m for m in MFP_MM]  # per metre
dist = 0.01  # attenuationDistance (m): colour e^(-sigma d)
no_spec = {"KHR_materials_specular": {"specularFactor": 0.0}}
materials = [
    {"name": "subsurface-wax",
     "pbrMetallicRoughness": {"baseColorFactor": RHO + [1], "metallicFactor": 0, "roughnessFactor": 0.5},
     "extensions": dict(no_spec, **{
         "KHR_materials_diffuse_transmission": {"diffuseTransmissionFactor": 1.0},
         "KHR_materials_volume": {"thicknessFactor": 0.05, "attenuationDistance": dist,
                                  "attenuationColor": [math.exp(-x * dist) for x in sigma]},
         "KHR_materials_volume_scatter": {"multiscatterColor": RHO, "scatterAnisotropy": 0.0}})},
    {"name": "surface-twin",
     "pbrMetallicRoughness": {"baseColorFactor": RHO + [1], "metallicFactor": 0, "roughnessFactor": 0.5},
     "extensions": no_spec},
    {"name": "floor",
     "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0,
                              "roughnessFactor": 0.8},
     "extensions": no_spec},
]
meshes = [
    {"name": "wax-bunny", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2,
                                          "material": 0}]},
    {"name": "twin-bunny", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2,
                                           "material": 1}]},
    {"name": "floor", "primitives": [{"attributes": {"POSITION": 3}, "indices": 4, "material": 2}]},
]


def look_at(eye, target):
    """A glTF node rotation (quaternion) looking from eye at target, +y up."""
    f = [target[k] - eye[k] for k in range(3)]
    ln = math.sqrt(sum(x * x for x in f))
    z = [-x / ln for x in f]  # the camera looks along -z
    up = [0, 1, 0]
    x = [up[1] * z[2] - up[2] * z[1], up[2] * z[0] - up[0] * z[2], up[0] * z[1] - up[1] * z[0]]
    ln = math.sqrt(sum(v * v for v in x))
    x = [v / ln for v in x]
    y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]]
    m = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        S = math.sqrt(tr + 1.0) * 2
        return [(m[2][1] - m[1][2]) / S, (m[0][2] - m[2][0]) / S, (m[1][0] - m[0][1]) / S, 0.25 * S]
    if m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        S = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        return [0.25 * S, (m[0][1] + m[1][0]) / S, (m[0][2] + m[2][0]) / S, (m[2][1] - m[1][2]) / S]
    if m[1][1] > m[2][2]:
        S = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        return [(m[0][1] + m[1][0]) / S, 0.25 * S, (m[1][2] + m[2][1]) / S, (m[0][2] - m[2][0]) / S]
    S = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
    return [(m[0][2] + m[2][0]) / S, (m[1][2] + m[2][1]) / S, 0.25 * S, (m[1][0] - m[0][1]) / S]


eye, target = [0.0, 0.12, 0.42], [0.0, 0.065, 0.0]
# The sun shines along its node's -z: from behind the bunnies, low.
sun_dir_from = [0.35, 0.45, -1.0]  # towards the sun
sun_rot = look_at([0, 0, 0], [-x for x in sun_dir_from])
nodes = [
    {"name": "wax", "mesh": 0, "translation": [-0.1, 0, 0]},
    {"name": "twin", "mesh": 1, "translation": [0.1, 0, 0]},
    {"name": "floor", "mesh": 2},
    {"name": "camera", "camera": 0, "translation": eye, "rotation": look_at(eye, target)},
    {"name": "sun", "rotation": sun_rot, "extensions": {"KHR_lights_punctual": {"light": 0}}},
]
doc = {
    "asset": {"version": "2.0", "generator": "raylab tools/make_subsurface_scene.py"},
    "extensionsUsed": ["KHR_materials_specular", "KHR_materials_diffuse_transmission",
                       "KHR_materials_volume", "KHR_materials_volume_scatter", "KHR_lights_punctual"],
    "scene": 0,
    "scenes": [{"nodes": list(range(len(nodes)))}],
    "nodes": nodes,
    "meshes": meshes,
    "materials": materials,
    "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(30), "znear": 0.01,
                                                          "aspectRatio": 16 / 9}}],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"type": "directional", "intensity": 3.0, "color": [1.0, 0.95, 0.9]}]}},
    "accessors": accessors,
    "bufferViews": views,
    "buffers": [{"byteLength": len(blob), "uri": os.path.basename(a.out)[:-5] + ".bin"}],
}
base = a.out[:-5] if a.out.endswith(".gltf") else a.out
with open(base + ".bin", "wb") as f:
    f.write(blob)
with open(base + ".gltf", "w") as f:
    json.dump(doc, f, indent=1)
print(f"wrote {base}.gltf: {len(pos)} vertices, {len(tris)} triangles, {filled} holes filled")
