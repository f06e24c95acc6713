#!/usr/bin/env python3
"""Writes the fuzz targets' seed corpora into fuzz/corpus/<target>/.

Seeds are real files cut down to fuzzing size (the shared models' glTF files
with their buffers inlined, the shared HDRIs and JPEGs scaled down) and small
files written here to reach every feature a parser has. Run once; the fuzzers
then grow the corpora, and `fuzz/run --minimize` shrinks them back before they
are committed.

    python3 fuzz/make_corpus.py [--shared ../shared]

Needs Pillow for the PNG/JPEG seeds (`pip install pillow` in a venv); without
it those two targets get only the hand-written PNG seeds.
"""

import argparse
import base64
import io
import json
import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def put(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


# ---------------------------------------------------------------- OBJ and MTL

CUBE = """# a cube with every index form
mtllib in.mtl
o cube
v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1 1.0
vt 0 0
vt 1 0
vt 1 1
vt 0 1 0
vn 0 0 -1
vn 0 0 1
vn 0 -1 0
g front back
s 1
usemtl red
f 1/1/1 2/2/1 3/3/1 4/4/1
f -4//2 -3//2 -2//2 -1//2
usemtl lamp
f 1/1 2/2 6/3 5/4
s off
f 4 3 7 8
l 1 2
p 3
f 2 3 7 6
f 1 5 8 4
"""

MTL = """# every statement raylab reads
newmtl red
Ka 0.1 0.1 0.1
Kd 0.8 0.1 0.1
Ks 0.5 0.5 0.5
Ns 250
Ni 1.45
d 1.0
Tr 0.0
Tf 1 1 1
illum 2
map_Kd -s 2 2 1 -o 0.5 0 0 -clamp on fixture.png
map_Ks fixture.png
map_Ns fixture.png
map_d -imfchan r fixture.png
map_bump -bm 0.5 fixture.png
bump fixture.png
norm fixture.png
disp fixture.png
Pr 0.4
Pm 0.2
map_Pr fixture.png
map_Pm fixture.png
newmtl lamp
Kd 0 0 0
Ke 4 3 2
map_Ke fixture.png
newmtl glass
Kd 0 0 0
Ks 1 1 1
Ni 1.5
d 0.1
illum 7
newmtl mirror
Ks 1 1 1
illum 3
newmtl a
Kd 0.5 0.5 0.5
newmtl b
Tr 0.5
Ns 0
"""


def obj_seeds(shared):
    put("obj", "cube", CUBE + "\0" + MTL)
    put("obj", "fixture", open(os.path.join(HERE, "src", "lib.rs")).read().split('FIXTURE_OBJ: &str = "')[1].split('";')[0].replace("\\n\\\n", "\n").replace("\\n", "\n"))
    put("obj", "quads-negative", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\nf 1 2 3\n")
    # The first 150 lines of each shared mesh: real exporters' formatting.
    for name in ("teapot.obj", "stanford-bunny.obj", "ogre.obj"):
        path = os.path.join(shared, "models", name)
        if os.path.exists(path):
            with open(path, "rb") as f:
                lines = f.read().split(b"\n")
            vs = [l for l in lines if l.startswith(b"v ")][:60]
            others = [l for l in lines if l.startswith((b"vt", b"vn"))][:30]
            faces = [l for l in lines if l.startswith(b"f ")][:40]
            put("obj", "head-" + name, b"\n".join(vs + others + faces) + b"\n")
    put("mtl", "all", MTL)
    put("mtl", "small", "newmtl a\nKd 1 0 0\nnewmtl b\nKe 1 1 1\n")
    put("mtl", "textured", "newmtl m\nKd 1 1 1\nmap_Kd fixture.png\nnorm -bm 2 fixture.png\n")


# ----------------------------------------------------------------------- glTF

def f32(*v):
    return struct.pack("<%df" % len(v), *v)


def feature_gltf():
    """A glTF with most features raylab reads, and its binary buffer."""
    buf = bytearray()

    def view(data, stride=None, target=None):
        while len(buf) % 4:
            buf.append(0)
        off = len(buf)
        buf.extend(data)
        v = {"buffer": 0, "byteOffset": off, "byteLength": len(data)}
        if stride:
            v["byteStride"] = stride
        if target:
            v["target"] = target
        views.append(v)
        return len(views) - 1

    views, accessors = [], []

    def acc(view_i, ctype, count, typ, **kw):
        a = {"bufferView": view_i, "componentType": ctype, "count": count, "type": typ}
        a.update(kw)
        accessors.append(a)
        return len(accessors) - 1

    pos = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
    # Interleaved position + normal + uv.
    inter = b"".join(f32(*p) + f32(0, 0, 1) + f32((p[0] + 1) / 2, (p[1] + 1) / 2) for p in pos)
    iv = view(inter, stride=32)
    a_pos = acc(iv, 5126, 4, "VEC3", byteOffset=0, min=[-1, -1, 0], max=[1, 1, 0])
    a_nrm = acc(iv, 5126, 4, "VEC3", byteOffset=12)
    a_uv = acc(iv, 5126, 4, "VEC2", byteOffset=24)
    a_tan = acc(view(b"".join(f32(1, 0, 0, 1) for _ in pos)), 5126, 4, "VEC4")
    a_uv1 = acc(view(struct.pack("<8H", 0, 0, 65535, 0, 65535, 65535, 0, 65535)), 5123, 4, "VEC2", normalized=True)
    a_col = acc(view(struct.pack("<16B", *([255, 128, 0, 255] * 4))), 5121, 4, "VEC4", normalized=True)
    a_idx8 = acc(view(bytes([0, 1, 2, 0, 2, 3])), 5121, 6, "SCALAR")
    a_idx32 = acc(view(struct.pack("<4I", 0, 1, 3, 2)), 5125, 4, "SCALAR")
    # Quantized positions (KHR_mesh_quantization) and a sparse accessor.
    a_qpos = acc(view(struct.pack("<12h", -100, -100, 0, 100, -100, 0, 0, 100, 0, 0, 0, 0)), 5122, 4, "VEC3",
                 normalized=True, min=[-0.003, -0.003, 0], max=[0.003, 0.003, 0])
    sparse_idx = view(struct.pack("<2H", 1, 3))
    sparse_val = view(f32(2, 0, 0, 0, 2, 0))
    a_sparse = acc(views and iv, 5126, 4, "VEC3", byteOffset=0, min=[-1, -1, 0], max=[2, 2, 0],
                   sparse={"count": 2, "indices": {"bufferView": sparse_idx, "componentType": 5123},
                           "values": {"bufferView": sparse_val}})
    while len(buf) % 4:
        buf.append(0)
    png = base64.b64encode(fixture_png()).decode()
    doc = {
        "asset": {"version": "2.0", "generator": "raylab fuzz seeds"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_ior",
                           "KHR_materials_specular", "KHR_materials_transmission", "KHR_materials_volume",
                           "KHR_texture_transform", "KHR_mesh_quantization"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 5, "color": [1, 0.9, 0.8]},
            {"type": "spot", "intensity": 20, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
            {"type": "directional", "intensity": 2, "range": 10}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 5]}],
        "nodes": [
            {"children": [1, 2, 3, 4], "rotation": [0, 0.3826834, 0, 0.9238795]},
            {"mesh": 0, "translation": [0, 0, -1], "scale": [1, 1, -1]},
            {"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 2, 0, 0, 1]},
            {"camera": 0, "translation": [0, 0, 5]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 3, 3]},
            {"children": [6, 7], "camera": 1},
            {"mesh": 1, "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"mesh": 2, "extensions": {"KHR_lights_punctual": {"light": 2}}},
        ],
        "cameras": [
            {"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1, "zfar": 100}},
            {"type": "orthographic", "orthographic": {"xmag": 2, "ymag": 2, "znear": 0.1, "zfar": 10}},
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": a_pos, "NORMAL": a_nrm, "TEXCOORD_0": a_uv,
                                            "TANGENT": a_tan, "TEXCOORD_1": a_uv1, "COLOR_0": a_col},
                             "indices": a_idx8, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": a_pos}, "indices": a_idx32, "mode": 5, "material": 1},
                            {"attributes": {"POSITION": a_sparse}, "mode": 6, "material": 2},
                            {"attributes": {"POSITION": a_pos}, "mode": 1}]},
            {"primitives": [{"attributes": {"POSITION": a_qpos}, "material": 3}]},
        ],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.5],
                                      "baseColorTexture": {"index": 0, "texCoord": 1,
                                                           "extensions": {"KHR_texture_transform": {
                                                               "offset": [0.5, 0], "rotation": 0.3,
                                                               "scale": [2, 2]}}},
                                      "metallicRoughnessTexture": {"index": 0},
                                      "metallicFactor": 0.5, "roughnessFactor": 0.3},
             "normalTexture": {"index": 0, "scale": 0.7}, "occlusionTexture": {"index": 0},
             "emissiveTexture": {"index": 0}, "emissiveFactor": [1, 0.5, 0],
             "alphaMode": "BLEND", "doubleSided": True,
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4},
                            "KHR_materials_ior": {"ior": 1.7},
                            "KHR_materials_specular": {"specularFactor": 0.5, "specularColorFactor": [1, 0.5, 0.5]}}},
            {"alphaMode": "MASK", "alphaCutoff": 0.6,
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}}},
            {"extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.8},
                            "KHR_materials_volume": {"thicknessFactor": 0.5, "attenuationDistance": 2,
                                                     "attenuationColor": [0.9, 0.5, 0.5]}}},
            {"pbrMetallicRoughness": {"metallicFactor": 1, "roughnessFactor": 0}},
        ],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 33648, "wrapT": 33071, "magFilter": 9729}],
        "images": [{"uri": "data:image/png;base64," + png}],
        "buffers": [{"byteLength": len(buf)}],
        "bufferViews": views,
        "accessors": accessors,
    }
    return doc, bytes(buf)


def gltf_text(doc, buf):
    d = json.loads(json.dumps(doc))
    d["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
    return json.dumps(d, separators=(",", ":"))


def glb(doc, buf):
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    buf = buf + b"\0" * (-len(buf) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js
    if buf:
        body += struct.pack("<II", len(buf), 0x004E4942) + buf
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def extension_gltf(doc):
    """The feature glTF with the extensions of issue 32's first part: unlit and
    specular-glossiness materials, variants mapping to them, GPU instancing."""
    d = json.loads(json.dumps(doc))
    d["extensionsUsed"] += ["KHR_materials_unlit", "KHR_materials_pbrSpecularGlossiness",
                            "KHR_materials_variants", "EXT_mesh_gpu_instancing"]
    d["materials"] += [
        {"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.6, 1, 1], "baseColorTexture": {"index": 0}},
         "extensions": {"KHR_materials_unlit": {}}},
        {"extensions": {"KHR_materials_pbrSpecularGlossiness": {
            "diffuseFactor": [0.5, 0.5, 0.5, 1], "diffuseTexture": {"index": 0},
            "specularFactor": [0.9, 0.7, 0.3], "glossinessFactor": 0.6,
            "specularGlossinessTexture": {"index": 0}}}},
    ]
    d["extensions"]["KHR_materials_variants"] = {"variants": [{"name": "unlit"}, {"name": "gloss"}]}
    d["meshes"][0]["primitives"][0]["extensions"] = {"KHR_materials_variants": {"mappings": [
        {"material": 4, "variants": [0]}, {"material": 5, "variants": [1]}]}}
    d["meshes"][2]["primitives"][0]["material"] = 5
    # Node 2 (mesh 0) instanced at the positions, scaled by the normals' accessor.
    d["nodes"][2]["extensions"] = {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 0, "SCALE": 1}}}
    return d


def pointer_gltf(doc, buf):
    """The feature glTF with a first animation of KHR_animation_pointer channels (what the
    gltf_json and glb targets pose at 0.7 s): a material's base colour and texture offset, a
    light's colour, a camera's field of view, a node's visibility (STEP) and translation
    (CUBICSPLINE), and its buffer grown by their keyframes."""
    d = json.loads(json.dumps(doc))
    buf = bytearray(buf)

    def acc(data, ctype, count, typ):
        while len(buf) % 4:
            buf.append(0)
        d["bufferViews"].append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(data)})
        buf.extend(data)
        d["accessors"].append({"bufferView": len(d["bufferViews"]) - 1, "componentType": ctype,
                               "count": count, "type": typ})
        return len(d["accessors"]) - 1

    times = acc(f32(0, 1), 5126, 2, "SCALAR")
    d["accessors"][times].update({"min": [0], "max": [1]})
    channels = [
        ("/materials/0/pbrMetallicRoughness/baseColorFactor", "LINEAR",
         acc(f32(1, 0, 0, 1, 0, 0, 1, 1), 5126, 2, "VEC4")),
        ("/materials/0/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform/offset",
         "LINEAR", acc(f32(0, 0, 0.5, 0.25), 5126, 2, "VEC2")),
        ("/extensions/KHR_lights_punctual/lights/0/color", "LINEAR", acc(f32(1, 1, 1, 0, 0.5, 1), 5126, 2, "VEC3")),
        ("/cameras/0/perspective/yfov", "LINEAR", acc(f32(0.8, 0.4), 5126, 2, "SCALAR")),
        ("/nodes/1/extensions/KHR_node_visibility/visible", "STEP", acc(bytes([1, 0]), 5121, 2, "SCALAR")),
        ("/nodes/4/translation", "CUBICSPLINE", acc(f32(0, 0, 0, 0, 3, 3, 1, 0, 0, 0, 1, 0, 2, 3, 1, 0, 0, 0),
                                                    5126, 6, "VEC3")),
    ]
    d["nodes"][1]["extensions"] = {"KHR_node_visibility": {"visible": True}}
    d["extensionsUsed"] += ["KHR_animation_pointer", "KHR_node_visibility"]
    d["animations"] = [{"name": "pointers", "samplers": [
        {"input": times, "interpolation": i, "output": o} for _, i, o in channels], "channels": [
        {"sampler": k, "target": {"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": p}}}}
        for k, (p, _, _) in enumerate(channels)]}]
    d["buffers"][0]["byteLength"] = len(buf)
    return d, bytes(buf)


def animation_seeds():
    """The animation demo of docs/gltf.md (a skin, a morph target, every interpolation), as
    .gltf and .glb."""
    text = open(os.path.join(HERE, "..", "scenes", "animation", "bend.gltf")).read()
    put("gltf_json", "animation-bend.gltf", text)
    d = json.loads(text)
    buf = base64.b64decode(d["buffers"][0].pop("uri").split(",", 1)[1])
    put("glb", "animation-bend.glb", glb(d, buf))


def gltf_seeds(shared):
    animation_seeds()
    doc, buf = feature_gltf()
    put("gltf_json", "features.gltf", gltf_text(doc, buf))
    put("glb", "features.glb", glb(doc, buf))
    ext = extension_gltf(doc)
    put("gltf_json", "extensions.gltf", gltf_text(ext, buf))
    put("glb", "extensions.glb", glb(ext, buf))
    ptr, ptr_buf = pointer_gltf(doc, buf)
    put("gltf_json", "animation-pointer.gltf", gltf_text(ptr, ptr_buf))
    put("glb", "animation-pointer.glb", glb(ptr, ptr_buf))
    fixture = open(os.path.join(HERE, "src", "lib.rs")).read().split('FIXTURE_GLTF: &str = r#"')[1].split('"#;')[0]
    put("gltf_json", "fixture.gltf", fixture)
    put("gltf_json", "minimal.gltf", '{"asset":{"version":"2.0"}}')
    put("glb", "minimal.glb", glb({"asset": {"version": "2.0"}}, b""))
    for name in ("OrientationTest", "TextureCoordinateTest", "NormalTangentTest", "DamagedHelmet"):
        folder = os.path.join(shared, "models", name)
        path = os.path.join(folder, name + ".gltf")
        if not os.path.exists(path):
            continue
        d = json.load(open(path))
        # Images become the fixture texture (the real ones are too big to fuzz).
        for im in d.get("images", []):
            im.pop("mimeType", None)
            im.pop("bufferView", None)
            im["uri"] = "fixture.png"
        b = open(os.path.join(folder, d["buffers"][0]["uri"]), "rb").read()
        if len(b) <= 64 * 1024:
            put("gltf_json", name + ".gltf", gltf_text(d, b))
            dd = json.loads(json.dumps(d))
            dd["buffers"][0].pop("uri")
            put("glb", name + ".glb", glb(dd, b))
        else:
            # The big buffer stays outside: a seed for the JSON's structure.
            d["buffers"][0]["uri"] = "fixture.bin"
            put("gltf_json", name + "-structure.gltf", json.dumps(d, separators=(",", ":")))


# ------------------------------------------------------------------ scene files

def toml_seeds(repo):
    put("scene_toml", "full.toml", """# every section
[render]
width = 64
height = 48
spp = 4
time = 1.5
integrator = "path"
max_depth = 5
exposure = 0.5
tonemap = "aces"
seed = 3

[camera]
position = [0, 1, 5]
target = [0, 0, 0]
up = [0, 1, 0]
fov = 40

[environment]
file = "fixture.hdr"
strength = 2.0
rotate = 90

[[model]]
name = "tri"
file = "fixture.obj"
translate = [0, 0, 0]
rotate = [0, 45, 0]
scale = 2.0
materials = { m = "gold:0.2", "*" = "glass:1.5" }

[[model]]
file = "fixture.gltf"
scale = [1, 2, 1]
fit = 1.5

[[model]]
builtin = "cornell-area"
materials = { tall = "mirror", short = "glass" }

[[material]]
name = "m"
base_color = [0.8, 0.2, 0.2]
roughness = 0.3
metallic = 0.0
ior = 1.4
transmission = 0.5
emission = [1, 1, 1]

[[light]]
type = "point"
position = [1, 3, 2]
intensity = 5
color = [1, 0.9, 0.8]

[[light]]
type = "spot"
position = [0, 3, 0]
target = [0, 0, 0]
intensity = 10
inner = 10
outer = 30

[[light]]
type = "directional"
direction = [0, -1, 0]
irradiance = 3

[[light]]
type = "area"
corner = [-0.5, 2, -0.5]
u = [1, 0, 0]
v = [0, 0, 1]
radiance = [4, 4, 4]
two_sided = true
""")
    put("scene_toml", "camera-model.toml", '[camera]\nmodel = "t"\nindex = 0\n[[model]]\nname = "t"\nfile = "fixture.gltf"\n[environment]\ncolor = [0.2, 0.3, 0.4]\n')
    import re
    for folder in ("scenes",):
        d = os.path.join(repo, folder)
        for name in sorted(os.listdir(d)):
            if name.endswith(".toml"):
                text = open(os.path.join(d, name)).read()
                # Models and maps become the fixtures beside the fuzz input.
                text = re.sub(r'file = "[^"]*\.(obj)"', 'file = "fixture.obj"', text)
                text = re.sub(r'file = "[^"]*\.(gltf|glb)"', 'file = "fixture.gltf"', text)
                text = re.sub(r'file = "[^"]*\.(hdr|exr)"', 'file = "fixture.hdr"', text)
                put("scene_toml", name, text)


# ------------------------------------------------------------ environment maps

def rgbe(c):
    m = max(c)
    if m < 1e-32:
        return bytes(4)
    e = math.frexp(m)[1]
    s = 256.0 / 2 ** e
    return bytes([int(c[0] * s), int(c[1] * s), int(c[2] * s), e + 128])


def hdr(width, height, pixel, rle=True, header=b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n"):
    out = bytearray(header + b"-Y %d +X %d\n" % (height, width))
    for y in range(height):
        row = [rgbe(pixel(x, y)) for x in range(width)]
        if rle and 8 <= width < 32768:
            out += bytes([2, 2, width >> 8, width & 255])
            for ch in range(4):
                vals = [p[ch] for p in row]
                i = 0
                while i < width:
                    run = 1
                    while i + run < width and vals[i + run] == vals[i] and run < 127:
                        run += 1
                    if run >= 3:
                        out += bytes([128 + run, vals[i]])
                        i += run
                    else:
                        n = min(128, width - i)
                        out += bytes([n]) + bytes(vals[i:i + n])
                        i += n
        else:
            out += b"".join(row)
    return bytes(out)


def env_seeds(shared):
    put("hdr", "flat-4x2.hdr", hdr(4, 2, lambda x, y: (1 + x, 1, 0.5 + y), rle=False))
    put("hdr", "rle-16x8.hdr", hdr(16, 8, lambda x, y: (x / 4, y / 8, 1.0 if x < 8 else 0.0)))
    put("hdr", "sun-32x16.hdr", hdr(32, 16, lambda x, y: (5e4, 5e4, 4e4) if (x, y) == (10, 3) else (0.2, 0.3, 0.5)))
    put("hdr", "x-first.hdr", hdr(4, 2, lambda x, y: (1, 1, 1), rle=False).replace(b"-Y 2 +X 4", b"+X 4 -Y 2"))
    # The shared HDRIs, scaled down to 32×16 (their first bytes keep the real header).
    for name in sorted(os.listdir(os.path.join(shared, "envmaps"))) if os.path.isdir(os.path.join(shared, "envmaps")) else []:
        data = open(os.path.join(shared, "envmaps", name), "rb").read()
        head_end = data.index(b"\n\n") + 2
        header = data[:head_end]
        put("hdr", "small-" + name, hdr(32, 16, lambda x, y: (2 - y / 8, 1.5 - y / 10, 1 + x / 32), header=header))
    exr_seeds()


def exr_seeds():
    """Tiny scanline EXRs, uncompressed, half and float channels."""
    def attr(name, typ, value):
        return name.encode() + b"\0" + typ.encode() + b"\0" + struct.pack("<i", len(value)) + value

    def exr(w, h, channels, ptype):  # ptype 1 = half, 2 = float
        size = 2 if ptype == 1 else 4
        chl = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", ptype, 0, 1, 1) for c in sorted(channels)) + b"\0"
        box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
        header = (struct.pack("<ii", 20000630, 2)
                  + attr("channels", "chlist", chl)
                  + attr("compression", "compression", b"\0")
                  + attr("dataWindow", "box2i", box)
                  + attr("displayWindow", "box2i", box)
                  + attr("lineOrder", "lineOrder", b"\0")
                  + attr("pixelAspectRatio", "float", struct.pack("<f", 1))
                  + attr("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0))
                  + attr("screenWindowWidth", "float", struct.pack("<f", 1))
                  + b"\0")
        table_at = len(header)
        offsets, blocks = [], b""
        start = table_at + 8 * h
        for y in range(h):
            row = b""
            for ci, c in enumerate(sorted(channels)):
                for x in range(w):
                    v = 0.5 + x / w + ci
                    row += struct.pack("<e", v) if ptype == 1 else struct.pack("<f", v)
            block = struct.pack("<ii", y, len(row)) + row
            offsets.append(start + len(blocks))
            blocks += block
        return header + b"".join(struct.pack("<Q", o) for o in offsets) + blocks

    put("exr", "rgb-half-4x2.exr", exr(4, 2, ["R", "G", "B"], 1))
    put("exr", "rgb-float-8x4.exr", exr(8, 4, ["R", "G", "B"], 2))
    put("exr", "rgba-half-4x2.exr", exr(4, 2, ["R", "G", "B", "A"], 1))
    put("exr", "y-half-4x2.exr", exr(4, 2, ["Y"], 1))


# --------------------------------------------------------------------- images

def fixture_png():
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    raw = bytes([0, 255, 0, 0, 0, 255, 0, 0, 0, 0, 255, 128, 128, 255])
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 2, 2, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def png(w, h, color_type, depth, pixel_bytes, palette=None):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    raw = b"".join(b"\0" + pixel_bytes(y) for y in range(h))
    out = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, color_type, 0, 0, 0))
    if palette:
        out += chunk(b"PLTE", palette)
    return out + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def image_seeds(shared):
    put("png", "fixture.png", fixture_png())
    put("png", "gray8.png", png(4, 4, 0, 8, lambda y: bytes(range(y * 16, y * 16 + 4))))
    put("png", "gray-alpha8.png", png(3, 2, 4, 8, lambda y: bytes([100, 255, 50, 128, 0, 0])))
    put("png", "rgba8.png", png(3, 3, 6, 8, lambda y: bytes([255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0])))
    put("png", "rgb16.png", png(2, 2, 2, 16, lambda y: struct.pack(">6H", 65535, 0, 1000, 0, 65535, 30000)))
    put("png", "palette.png", png(4, 2, 3, 8, lambda y: bytes([0, 1, 2, 1]), palette=bytes([255, 0, 0, 0, 255, 0, 0, 0, 255])))
    put("png", "gray1.png", png(8, 2, 0, 1, lambda y: bytes([0b10101010])))
    try:
        from PIL import Image
    except ImportError:
        print("no Pillow: JPEG seeds skipped")
        return
    sources = []
    for folder, name in (("DamagedHelmet", "Default_albedo.jpg"), ("DamagedHelmet", "Default_normal.jpg"),
                         ("TextureCoordinateTest", "TextureCoordinateTemplate.png"),
                         ("NormalTangentTest", "NormalTangentTest_Normal.png")):
        p = os.path.join(shared, "models", folder, name)
        if os.path.exists(p):
            sources.append((name.rsplit(".", 1)[0], Image.open(p).convert("RGB").resize((16, 16))))
    for stem, im in sources:
        for mode in ("RGB", "L"):
            b = io.BytesIO()
            im.convert(mode).save(b, "JPEG", quality=75)
            put("jpeg", "%s-%s.jpg" % (stem, mode), b.getvalue())
        b = io.BytesIO()
        im.save(b, "JPEG", quality=90, progressive=True)
        put("jpeg", stem + "-progressive.jpg", b.getvalue())
        b = io.BytesIO()
        im.save(b, "JPEG", quality=50, subsampling=2, optimize=True)
        put("jpeg", stem + "-420.jpg", b.getvalue())
        b = io.BytesIO()
        im.convert("CMYK").save(b, "JPEG")
        put("jpeg", stem + "-cmyk.jpg", b.getvalue())
        for mode, lossless in (("RGB", False), ("RGBA", True), ("RGB", True)):
            b = io.BytesIO()
            im.convert(mode).save(b, "WEBP", lossless=lossless, quality=70)
            put("webp", "%s-%s-%s.webp" % (stem, mode, "lossless" if lossless else "lossy"), b.getvalue())
        b = io.BytesIO()
        im.convert("RGBA").save(b, "PNG")
        put("png", stem + "-rgba.png", b.getvalue())
        b = io.BytesIO()
        im.save(b, "PNG", interlace=1) if False else im.convert("P").save(b, "PNG")
        put("png", stem + "-palette.png", b.getvalue())


# ----------------------------------------------------------- rays, BVH, CLI

def ray_seeds(shared):
    rays = []
    for i in range(16):
        a = 2 * math.pi * i / 16
        rays.append((3 * math.cos(a), 0.3, 3 * math.sin(a), -math.cos(a), -0.1, -math.sin(a)))
    rays.append((0, 0, 0, 1, 0, 0))  # from inside
    rays.append((0, 5, 0, 0, -1, 0))  # straight down through a vertex
    rays.append((0, 0, 5, 0, 0, 0))  # zero direction
    rays.append((float("nan"), 0, 0, 1, 0, 0))
    put("rays", "ring.rays", b"".join(struct.pack("<6f", *r) for r in rays))
    # Eight rays from one point (a packet), then eight incoherent ones.
    pack = [(0, 0, 4, 0.01 * i, 0.01 * (i % 3), -1) for i in range(8)]
    put("rays", "packet.rays", b"".join(struct.pack("<6f", *r) for r in pack + rays[:8]))
    put("rays", "one.rays", struct.pack("<6f", 0, 0, 3, 0, 0, -1))
    tri = lambda *v: struct.pack("<9f", *v)
    bvh = bytes([16]) + b"".join(struct.pack("<6f", *r) for r in rays[:16])
    bvh += tri(-1, -1, 0, 1, -1, 0, 0, 1, 0) + tri(-1, -1, 1, 1, -1, 1, 0, 1, 1) + tri(0, 0, 0, 0, 0, 0, 1, 1, 1)
    bvh += tri(-1, 0, -1, 1, 0, -1, 0, 0, 1) * 3
    put("bvh", "small", bvh)
    put("bvh", "grid", bytes([8]) + b"".join(struct.pack("<6f", *r) for r in pack) + b"".join(
        tri(x, y, 0, x + 1, y, 0, x, y + 1, 0) for x in range(-4, 4) for y in range(-4, 4)))


def checkpoint_seeds():
    """Checkpoints as `--checkpoint` writes them, without the trailing checksum
    (the target appends it)."""
    # Format 2: exact sums, i128 fixed point with 64 fraction bits (raylab::fixed).
    fixed = lambda x: (int(x * 2**64) & (2**128 - 1)).to_bytes(16, "little")

    def ckpt(w, h, spp, aov_nibbles=0, stride=0):
        out = b"RAYLABCP" + struct.pack("<II", 2, aov_nibbles) + struct.pack("<QQQ", 1, 2, 3)
        out += struct.pack("<IIII", w, h, spp, 0) + struct.pack("<QQQ", 10**9, 1234, 0)
        for i in range(w * h):
            out += fixed(0.5 * spp) + fixed(0.25 * spp) + fixed(i)
        out += fixed(0.5) * (w * h * stride)
        return out
    put("checkpoint", "plain-4x3", ckpt(4, 3, 7))
    put("checkpoint", "one-pixel", ckpt(1, 1, 1))
    put("checkpoint", "albedo-2x2", ckpt(2, 2, 3, aov_nibbles=1, stride=4))


def cli_seeds():
    lines = [
        ["render"],
        ["render", "--spp", "16", "-o", "docs/cornell.png"],
        ["render", "--integrator", "flat", "--spp", "16", "-o", "x.png"],
        ["render", "cornell-area", "--integrator", "path", "--material", "tall=mirror,short=glass", "--spp", "512"],
        ["render", "--integrator", "path", "--material", "floor=gold:0.2,left=mirror", "--spp", "256", "-o", "gold.exr"],
        ["render", "model.glb", "--env", "sky.hdr", "--env-rotate", "200", "--env-strength", "2"],
        ["render", "--camera-pos=-0.3,0.2,-2", "--yaw", "10", "--pitch", "-5", "--light-pos", "0,-0.5,-0.7"],
        ["render", "--width", "640", "--height", "480", "--time", "2.5", "--seed", "7", "--threads", "2"],
        ["render", "--aov", "albedo,normal,depth,position", "-o", "out.exr", "--exposure", "1.5", "--tonemap", "aces"],
        ["render", "mesh.obj", "--add", "a.obj", "--transform", "scale=0.5,rotate-y=30,translate=0,0.2,0"],
        ["render", "scene.toml", "--camera", "1", "--default-light", "off", "--env-color", "0.1,0.2,0.3"],
        ["render", "--max-depth", "8", "--sampler", "independent", "--ambient", "0.2", "--light-power", "20", "--quiet"],
        ["render", "--tile", "1/4", "--samples", "16..64", "--spp", "64", "-o", "part.exr", "--cache", "c"],
        ["render", "mesh.obj", "--frames", "0..8", "--orbit", "45", "-o", "out-%04d.png"],
        ["merge", "a.part.exr", "b.part.exr", "-o", "out.png", "--quiet"],
        ["view", "--width", "300"],
        ["bench", "mesh.obj", "--rays", "r.bin", "--hits", "h.bin", "--tfar", "10", "--threads", "1,2", "--api", "all"],
    ]
    for i, words in enumerate(lines):
        put("cli", "args%02d" % i, "\0".join(words))


# ------------------------------------------------------------------ meshopt

# The fuzz target's view table (fuzz/src/targets.rs, MESHOPT_VIEWS), in
# order: extension, mode, filter, byte stride.
MESHOPT_VIEWS = [
    ("EXT", "ATTRIBUTES", "NONE", 12), ("EXT", "ATTRIBUTES", "NONE", 4),
    ("KHR", "ATTRIBUTES", "NONE", 8), ("KHR", "ATTRIBUTES", "EXPONENTIAL", 12),
    ("EXT", "ATTRIBUTES", "OCTAHEDRAL", 8), ("KHR", "ATTRIBUTES", "OCTAHEDRAL", 4),
    ("EXT", "ATTRIBUTES", "QUATERNION", 8), ("KHR", "ATTRIBUTES", "COLOR", 4),
    ("KHR", "ATTRIBUTES", "COLOR", 8), ("EXT", "TRIANGLES", "NONE", 2),
    ("KHR", "TRIANGLES", "NONE", 4), ("EXT", "INDICES", "NONE", 2), ("KHR", "INDICES", "NONE", 4),
]


def meshopt_seeds():
    """Every compressed stream of the gltfpack-made test files
    (tests/data/compressed/), each prefixed with the target's pick of a view
    of its extension, mode and stride (the filters may differ: the target
    then filters the stream's bytes anyway) and its element count."""
    data = os.path.join(HERE, "..", "tests", "data", "compressed")
    for name in sorted(os.listdir(data)):
        path = os.path.join(data, name)
        if name.endswith(".glb"):
            b = open(path, "rb").read()
            n = struct.unpack("<I", b[12:16])[0]
            doc = json.loads(b[20:20 + n])
            bins = [b[28 + n:]]
        elif name.startswith("meshopt") and name.endswith(".gltf"):
            doc = json.load(open(path))
            bins = [open(os.path.join(data, doc["buffers"][0]["uri"]), "rb").read()]
        else:
            continue
        for i, v in enumerate(doc.get("bufferViews", [])):
            for ext in ("EXT", "KHR"):
                e = v.get("extensions", {}).get(ext + "_meshopt_compression")
                if not e or e["buffer"] != 0:
                    continue
                stride, mode, flt = e["byteStride"], e["mode"], e.get("filter", "NONE")
                picks = [k for k, (x, m, f, s) in enumerate(MESHOPT_VIEWS)
                         if (x, m, s) == (ext, mode, stride)]
                picks.sort(key=lambda k: MESHOPT_VIEWS[k][2] != flt)
                if not picks:
                    continue
                count = e["count"] // 3 if mode == "TRIANGLES" else e["count"]
                start = e.get("byteOffset", 0)
                stream = bins[0][start:start + e["byteLength"]]
                put("meshopt", "%s-view%d" % (name.rsplit(".", 1)[0], i),
                    bytes([picks[0]]) + struct.pack("<H", count) + stream)


# ------------------------------------------------------------------ ktx2


def ktx2_seeds():
    """The KTX2 files of tests/data/compressed/ (made by Binomial's encoder:
    UASTC, UASTC + Zstandard, ETC1S + BasisLZ)."""
    data = os.path.join(HERE, "..", "tests", "data", "compressed")
    for name in sorted(os.listdir(data)):
        if name.endswith(".ktx2"):
            put("ktx2", name, open(os.path.join(data, name), "rb").read())


# ------------------------------------------------------------------ draco

def draco_seeds():
    """The Draco stream of every Draco test file (tests/data/compressed/),
    prefixed with the target's pick of the attribute ids its producer uses
    (fuzz/src/targets.rs, DRACO_LAYOUTS: 0 gltf-transform's, 1 DracoPy's)."""
    data = os.path.join(HERE, "..", "tests", "data", "compressed")
    for name in sorted(os.listdir(data)):
        if not name.startswith("draco"):
            continue
        raw = open(os.path.join(data, name), "rb").read()
        if name.endswith(".glb"):
            n = struct.unpack("<I", raw[12:16])[0]
            doc = json.loads(raw[20:20 + n])
            buf = raw[28 + n:]
        else:
            doc = json.loads(raw)
            buf = base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1])
        ext = doc["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
        v = doc["bufferViews"][ext["bufferView"]]
        start = v.get("byteOffset", 0)
        pick = 0 if ext["attributes"]["POSITION"] == 0 else 1
        put("draco", name.rsplit(".", 1)[0], bytes([pick]) + buf[start:start + v["byteLength"]])

# ---------------------------------------------------------------- Mitsuba XML

MITSUBA_FULL = """<?xml version="1.0" encoding="utf-8"?>
<scene version="3.0.0">
    <default name="spp" value="16"/>
    <path value="."/>
    <include filename="fixture.xml"/>
    <integrator type="path"><integer name="max_depth" value="8"/></integrator>
    <sensor type="perspective" id="cam">
        <float name="fov" value="39.3"/>
        <transform name="to_world">
            <translate value="1, 2 3"/><rotate x="1" y="1" z="1" angle="120"/>
            <scale value="2"/><scale x="1" y="-1"/>
            <matrix value="1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"/>
            <matrix value="1 0 0 0 1 0 0 0 1"/>
            <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>
            <lookat origin="0 0 0" target="0 0 1"/>
        </transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm"><integer name="width" value="64"/><rfilter type="box"/></film>
    </sensor>
    <bsdf type="twosided" id="m"><bsdf type="diffuse"><texture name="reflectance" type="checkerboard"/></bsdf></bsdf>
    <alias id="m" as="m2"/>
    <shape type="obj"><string name="filename" value="fixture.obj"/><ref id="m2"/><ref name="other" id="fixture_bsdf"/></shape>
    <shape type="sphere"><point name="center" value="0 1 0"/><vector name="v" x="1" y="2" z="3"/>
        <boolean name="flip_normals" value="true"/><ref id="later"/>
        <emitter type="area"><rgb name="radiance" value="1"/><spectrum name="s" value="400:1, 500:2"/></emitter>
    </shape>
    <bsdf type="dielectric" id="later"><string name="int_ior" value="bk7"/><spectrum name="k" value="0.5"/></bsdf>
    <emitter type="envmap"><spectrum name="irradiance" type="blackbody"><float name="temperature" value="5000"/></spectrum></emitter>
    <string name="escaped" value="\\$spp"/>
</scene>
"""

MITSUBA_OLD = """<scene version="0.6.0">
    <integrator type="path"><integer name="maxDepth" value="5"/></integrator>
    <sensor type="perspective"><transform name="toWorld"><lookAt origin="0,0,5" target="0,0,0" up="0,1,0"/></transform></sensor>
    <bsdf type="diffuse"><texture type="bitmap" name="diffuseReflectance"><float name="uscale" value="4"/><float name="voffset" value="0.5"/></texture></bsdf>
</scene>
"""


def mitsuba_seeds():
    put("mitsuba_xml", "full.xml", MITSUBA_FULL)
    put("mitsuba_xml", "old-0.6.xml", MITSUBA_OLD)
    put("mitsuba_xml", "root-bsdf.xml", '<bsdf version="2.1.0" type="roughconductor"><float name="alpha" value="0.1"/></bsdf>\n')
    put("mitsuba_xml", "self-include.xml", '<scene version="3.0.0"><include filename="in.xml"/></scene>\n')
    put("mitsuba_xml", "cycle.xml", '<scene version="3.0.0"><bsdf type="a" id="a"><bsdf type="b"><ref id="a"/></bsdf></bsdf></scene>\n')
    put("mitsuba_xml", "dtd.xml", '<?xml version="1.0"?>\n<!DOCTYPE scene [<!ENTITY v "3.0.0">]>\n<scene version="&v;"><float name="x" value="1e39"/></scene>\n')


def ply_file(fmt, header, records):
    """A PLY file: `records` are lists of (struct code, value) pairs."""
    out = ("ply\nformat %s 1.0\ncomment raylab fuzz seed\n%send_header\n" % (fmt, header)).encode()
    for r in records:
        if fmt == "ascii":
            out += (" ".join(str(v) for _, v in r) + "\n").encode()
        else:
            end = ">" if fmt == "binary_big_endian" else "<"
            out += b"".join(struct.pack(end + c, v) for c, v in r)
    return out


PLY_FULL_HEADER = """element vertex 4
property float x
property float y
property float z
property float nx
property float ny
property float nz
property float u
property float v
property uchar red
property uchar green
property uchar blue
property float temp_0
property double dir_x
property double dir_y
property double dir_z
element face 2
property list uchar int vertex_indices
property float weight_0
property float c_r
property float c_g
property float c_b
"""


def ply_full_records():
    r = []
    for i in range(4):
        r.append([("f", i), ("f", i * 2 - 1), ("f", -i), ("f", 0), ("f", 1), ("f", i / 4), ("f", i / 3), ("f", 0.25 + i / 8),
                  ("B", 255), ("B", 128), ("B", i * 10), ("f", 100 + i), ("d", 0.5 * i), ("d", -1.5), ("d", 1e-3)])
    r.append([("B", 3), ("i", 0), ("i", 1), ("i", 2), ("f", 0.5), ("f", 0.1), ("f", 0.2), ("f", 0.3)])
    r.append([("B", 3), ("i", 0), ("i", 2), ("i", 3), ("f", 2.5), ("f", 0.4), ("f", 0.5), ("f", 0.6)])
    return r


def serialized_shape(version, n, normals, uvs, colors, double, name=b"shape"):
    """One compressed shape stream of n vertices in a fan of n - 2 triangles."""
    flags = (1 if normals else 0) | (2 if uvs else 0) | (8 if colors else 0) | (0x2000 if double else 0x1000)
    raw = struct.pack("<I", flags)
    if version == 4:
        raw += name + b"\0"
    raw += struct.pack("<QQ", n, n - 2)
    fmt = "<d" if double else "<f"
    def floats(values):
        return b"".join(struct.pack(fmt, v) for v in values)
    raw += floats(v for i in range(n) for v in (i, i * 0.5, -i))
    if normals:
        raw += floats(v for i in range(n) for v in (0, 1, i / 8))
    if uvs:
        raw += floats(v for i in range(n) for v in (i / 4, 0.5))
    if colors:
        raw += floats(v for i in range(n) for v in (0.5, i / 10, 1))
    raw += b"".join(struct.pack("<III", 0, i, i + 1) for i in range(1, n - 1))
    return zlib.compress(raw)


def serialized_file(version, streams):
    out, offsets = b"", []
    for s in streams:
        offsets.append(len(out))
        out += struct.pack("<HH", 0x041C, version) + s
    out += b"".join(struct.pack("<I" if version == 3 else "<Q", o) for o in offsets)
    return out + struct.pack("<I", len(streams))


def mitsuba_mesh_seeds():
    tri = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    tri_records = [[("f", 0), ("f", 0), ("f", 0)], [("f", 1), ("f", 0), ("f", 0)], [("f", 0), ("f", 1), ("f", 0)]]
    face = "element face 1\nproperty list uchar int vertex_indices\n"
    for fmt, name in [("ascii", "full-ascii.ply"), ("binary_little_endian", "full-le.ply"), ("binary_big_endian", "full-be.ply")]:
        put("mitsuba_ply", name, ply_file(fmt, PLY_FULL_HEADER, ply_full_records()))
    put("mitsuba_ply", "triangle.ply", ply_file("ascii", tri + face, tri_records + [[("B", 3), ("i", 0), ("i", 1), ("i", 2)]]))
    put("mitsuba_ply", "quad.ply", ply_file("binary_little_endian", tri + face, tri_records + [[("B", 4), ("i", 0), ("i", 1), ("i", 2), ("i", 0)]]))
    put("mitsuba_ply", "skipped-edge.ply", ply_file(
        "binary_little_endian",
        tri + "element edge 1\nproperty list uchar int vertices\nproperty uchar flag\n" + face,
        tri_records + [[("B", 2), ("i", 0), ("i", 1), ("B", 7)], [("B", 3), ("i", 2), ("i", 1), ("i", 0)]]))
    put("mitsuba_ply", "types.ply", ply_file(
        "binary_little_endian",
        "element vertex 3\nproperty short x\nproperty ushort y\nproperty half z\nproperty texture_u int\n"
        .replace("property texture_u int", "property int texture_u") +
        "property uint texture_v\nproperty char r\nproperty int8 g\nproperty uint8 b\nproperty uint16 a\n"
        "property long k_1\nproperty ulong k_2\nproperty float64 k_3\nproperty float32 k_4\n"
        "element face 1\nproperty list ushort uint vertex_index\nproperty uint32 id_0\n",
        [[("h", i), ("H", i), ("e", 0.5), ("i", i), ("I", i), ("b", -i), ("b", i), ("B", i), ("H", i),
          ("q", i), ("Q", i), ("d", i), ("f", i)] for i in range(3)] + [[("H", 3), ("I", 0), ("I", 1), ("I", 2), ("I", 7)]]))
    put("mitsuba_serialized", "v4-full.serialized", serialized_file(4, [serialized_shape(4, 5, True, True, True, False)]))
    put("mitsuba_serialized", "v4-double.serialized", serialized_file(4, [serialized_shape(4, 4, True, False, False, True)]))
    put("mitsuba_serialized", "v3-three-shapes.serialized", serialized_file(3, [
        serialized_shape(3, 3, False, False, False, False),
        serialized_shape(3, 4, True, True, False, False),
        serialized_shape(3, 5, False, True, True, True)]))
    put("mitsuba_serialized", "v4-two-shapes.serialized", serialized_file(4, [
        serialized_shape(4, 3, False, True, False, False, b"a"),
        serialized_shape(4, 6, True, False, True, False, b"second")]))


def vol_file(n, channels, values):
    data = b"VOL" + bytes([3]) + struct.pack("<iiiii", 1, n, n, n, channels)
    data += struct.pack("<6f", 0.0, 0.0, 0.0, 1.0, 1.0, 1.0)
    return data + struct.pack("<%df" % len(values), *values)


def vol_seeds():
    put("mitsuba_vol", "density.vol", vol_file(3, 1, [float(i % 5) for i in range(27)]))
    put("mitsuba_vol", "rgb.vol", vol_file(2, 3, [0.1 * i for i in range(24)]))
    put("mitsuba_vol", "sdf.vol", vol_file(2, 1, [-0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--shared", default=os.path.join(HERE, "..", "..", "shared"))
    a = ap.parse_args()
    repo = os.path.join(HERE, "..")
    obj_seeds(a.shared)
    gltf_seeds(a.shared)
    toml_seeds(repo)
    env_seeds(a.shared)
    image_seeds(a.shared)
    ray_seeds(a.shared)
    checkpoint_seeds()
    cli_seeds()
    meshopt_seeds()
    ktx2_seeds()
    draco_seeds()
    mitsuba_seeds()
    mitsuba_mesh_seeds()
    vol_seeds()
    for t in sorted(os.listdir(os.path.join(HERE, "corpus"))):
        files = os.listdir(os.path.join(HERE, "corpus", t))
        size = sum(os.path.getsize(os.path.join(HERE, "corpus", t, f)) for f in files)
        print("%-12s %3d seeds, %7d bytes" % (t, len(files), size))


if __name__ == "__main__":
    main()
