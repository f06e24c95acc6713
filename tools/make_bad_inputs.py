#!/usr/bin/env python3
"""Writes the small malformed files of tests/data/bad/ (the bad-input suite,
tests/bad_input.rs). Each file's name says what is wrong with it. Big or deep
cases (a 100 MB line, 10^6 nested brackets, 100000 nested nodes) are built by
the test itself, not committed. Run from the repository root:
    python3 tools/make_bad_inputs.py
"""
import base64
import json
import os
import struct
import zlib

OUT = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "bad")


def put(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(data)


# ---------------------------------------------------------------- OBJ / MTL
TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
put("obj-index-zero.obj", TRI + "f 1 0 2\n")
put("obj-index-past-end.obj", TRI + "f 1 2 9\n")
put("obj-negative-index-before-start.obj", TRI + "f -1 -2 -5\n")
put("obj-huge-negative-index.obj", TRI + "f 1 2 -9223372036854775808\n")
put("obj-index-2-40.obj", TRI + "f 1 2 1099511627776\n")
put("obj-index-not-a-number.obj", TRI + "f 1 x 2\n")
put("obj-index-overflows-i64.obj", TRI + "f 1 2 99999999999999999999999\n")
put("obj-nan-vertex.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
put("obj-inf-vertex.obj", "v 0 inf 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
put("obj-overflowing-vertex.obj", "v 0 1e39 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
put("obj-vertex-two-coordinates.obj", "v 0 0\n" + TRI + "f 2 3 4\n")
put("obj-face-one-vertex.obj", TRI + "f 1\n")
put("obj-face-two-vertices.obj", TRI + "f 1 2\n")
put("obj-texcoord-index-past-end.obj", TRI + "vt 0 0\nf 1/1 2/5 3/1\n")
put("obj-normal-index-past-end.obj", TRI + "vn 0 0 1\nf 1//1 2//1 3//7\n")
put("obj-normal-index-garbage.obj", TRI + "vn 0 0 1\nf 1//x 2//1 3//1\n")
put("obj-nan-texcoord.obj", TRI + "vt nan 0\nf 1/1 2/1 3/1\n")
put("obj-non-utf8.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n\xff\xfe\xfd garbage\nf 1 2 3\n")
put("obj-binary-garbage.obj", bytes(range(256)) * 4)
# MTL: the OBJ names the library; the error must name the .mtl.
MTL_OBJ = "mtllib {}\n" + TRI + "usemtl m\nf 1 2 3\n"
for stem, mtl in [
    ("mtl-kd-not-a-number", "newmtl m\nKd red green blue\n"),
    ("mtl-kd-nan", "newmtl m\nKd nan 0 0\n"),
    ("mtl-newmtl-without-name", "newmtl\nKd 1 1 1\n"),
    ("mtl-illum-garbage", "newmtl m\nillum fancy\n"),
    ("mtl-map-option-not-finite", "newmtl m\nmap_Kd -bm inf tex.png\n"),
    ("mtl-non-utf8", b"newmtl m\nKd 1 1 1\n\xff\xfe\n"),
]:
    put(stem + ".obj", MTL_OBJ.format(stem + ".mtl"))
    put(stem + ".mtl", mtl)

# ---------------------------------------------------------------- glTF
def buffer_uri(data):
    return "data:application/octet-stream;base64," + base64.b64encode(data).decode()


TRI_BYTES = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<3H", 0, 1, 2) + b"\0\0"


def gltf(**changes):
    """A valid one-triangle glTF, with `changes` applied to its top level."""
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": len(TRI_BYTES), "uri": buffer_uri(TRI_BYTES)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
        ],
    }
    for path, value in changes.items():
        node = doc
        keys = path.split("__")
        for k in keys[:-1]:
            node = node[int(k)] if k.isdigit() else node[k]
        last = keys[-1]
        if last.isdigit():
            node[int(last)] = value
        elif value is None:
            del node[last]
        else:
            node[last] = value
    return json.dumps(doc)


put("gltf-empty-file.gltf", "")
put("gltf-truncated.gltf", gltf()[:150])
put("gltf-not-json.gltf", bytes(range(256)))
put("gltf-no-asset.gltf", '{"scenes": []}')
put("gltf-accessors-wrong-type.gltf", gltf(accessors="lots"))
put("gltf-count-negative.gltf", gltf(accessors__0__count=-3))
put("gltf-count-is-string.gltf", gltf(accessors__0__count="3"))
put("gltf-accessor-past-buffer.gltf", gltf(accessors__0__count=300))
put("gltf-accessor-offset-past-view.gltf", gltf(accessors__0__byteOffset=4000))
put("gltf-accessor-2-31-elements.gltf", gltf(accessors__0__count=2**31))
put("gltf-accessor-2-32-elements.gltf", gltf(accessors__1__count=2**32 - 1))
put("gltf-accessor-without-view-huge.gltf",
    gltf(accessors__0__count=2**27, accessors__0__bufferView=None))
put("gltf-accessor-missing.gltf", gltf(meshes__0__primitives__0__attributes={"POSITION": 7}))
put("gltf-buffer-view-past-buffer.gltf", gltf(bufferViews__0__byteLength=4000))
put("gltf-buffer-view-offset-huge.gltf", gltf(bufferViews__1__byteOffset=2**53))
put("gltf-buffer-view-missing-buffer.gltf", gltf(bufferViews__0__buffer=5))
put("gltf-stride-smaller-than-element.gltf", gltf(bufferViews__0__byteStride=4))
put("gltf-buffer-shorter-than-declared.gltf", gltf(buffers__0__byteLength=1 << 20))
put("gltf-buffer-length-2-62.gltf", gltf(buffers__0__byteLength=2**62))
put("gltf-buffer-file-missing.gltf", gltf(buffers__0__uri="no-such-buffer.bin"))
put("gltf-buffer-bad-base64.gltf", gltf(buffers__0__uri="data:application/octet-stream;base64,@@@@"))
put("gltf-buffer-remote-uri.gltf", gltf(buffers__0__uri="https://example.com/b.bin"))
put("gltf-index-past-vertices.gltf", gltf(buffers__0__uri=buffer_uri(TRI_BYTES[:36] + struct.pack("<3H", 0, 1, 99) + b"\0\0")))
put("gltf-indices-are-floats.gltf", gltf(accessors__1__componentType=5126, accessors__1__count=1))
put("gltf-positions-are-scalars.gltf", gltf(accessors__0__type="SCALAR"))
put("gltf-unknown-component-type.gltf", gltf(accessors__0__componentType=9999))
put("gltf-cyclic-nodes.gltf", gltf(nodes=[{"mesh": 0, "children": [1]}, {"children": [0]}]))
put("gltf-node-own-child.gltf", gltf(nodes=[{"mesh": 0, "children": [0]}]))
put("gltf-node-missing.gltf", gltf(scenes=[{"nodes": [0, 12]}]))
put("gltf-mesh-missing.gltf", gltf(nodes=[{"mesh": 4}]))
put("gltf-scene-missing.gltf", gltf(scene=3))
put("gltf-material-missing.gltf", gltf(meshes__0__primitives__0__material=2))
put("gltf-required-extension.gltf", gltf(extensionsRequired=["EXT_from_the_future"], extensionsUsed=["EXT_from_the_future"]))
put("gltf-sparse-count-over-count.gltf", gltf(accessors__0__sparse={
    "count": 10, "indices": {"bufferView": 1, "componentType": 5123},
    "values": {"bufferView": 0}}))
put("gltf-sparse-index-outside.gltf", gltf(
    buffers__0__uri=buffer_uri(TRI_BYTES[:36] + struct.pack("<3H", 0, 1, 40) + b"\0\0"),
    accessors__0__sparse={"count": 3, "indices": {"bufferView": 1, "componentType": 5123},
                          "values": {"bufferView": 0}}))
put("gltf-matrix-too-short.gltf", gltf(nodes=[{"mesh": 0, "matrix": [1, 0, 0]}]))
put("gltf-scale-overflows-f32.gltf", gltf(nodes=[{"mesh": 0, "scale": [1e39, 1, 1]}]))
put("gltf-camera-zero-yfov.gltf", gltf(
    cameras=[{"type": "perspective", "perspective": {"yfov": 0, "znear": 0.1}}],
    nodes=[{"mesh": 0, "children": [1]}, {"camera": 0}]))
# EXT_mesh_gpu_instancing: attribute counts that differ, a rotation of 3 components.
INSTANCED = {"mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {}}}}
put("gltf-instancing-counts-differ.gltf", gltf(
    nodes=[{**INSTANCED, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 0, "SCALE": 2}}}}],
    accessors=[
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
        {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
        {"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3"},
    ]))
put("gltf-instancing-rotation-vec3.gltf", gltf(
    nodes=[{**INSTANCED, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"ROTATION": 0}}}}]))
# KHR_materials_variants: a mapping to a variant the file does not define, a variant without a name.
put("gltf-variant-mapping-past-variants.gltf", gltf(
    materials=[{}],
    extensions={"KHR_materials_variants": {"variants": [{"name": "only"}]}},
    meshes__0__primitives__0__extensions={"KHR_materials_variants": {"mappings": [{"material": 0, "variants": [5]}]}}))
put("gltf-variant-without-name.gltf", gltf(
    extensions={"KHR_materials_variants": {"variants": [{}]}}))

# Images referenced by a glTF (a data URI, so the error names the glTF).
PNG_SIG = b"\x89PNG\r\n\x1a\n"


def chunk(kind, data, crc=None):
    c = zlib.crc32(kind + data) if crc is None else crc
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", c)


def png(w, h, raw=None, crc=None, color=2):
    ihdr = struct.pack(">IIBBBBB", w, h, 8, color, 0, 0, 0)
    channels = {0: 1, 2: 3, 6: 4}[color]
    if raw is None:
        raw = b"".join(b"\0" + b"\x80" * (w * channels) for _ in range(h))
    return PNG_SIG + chunk(b"IHDR", ihdr, crc) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def textured_gltf(image_uri):
    return gltf(
        materials=[{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        textures=[{"source": 0}],
        images=[{"uri": image_uri}],
        meshes=[{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 2},
                                 "indices": 1, "material": 0}]}],
        buffers=[{"byteLength": len(TRI_BYTES) + 24,
                  "uri": buffer_uri(TRI_BYTES + struct.pack("<6f", 0, 0, 1, 0, 0, 1))}],
        bufferViews=[
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6},
            {"buffer": 0, "byteOffset": 44, "byteLength": 24},
        ],
        accessors=[
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"},
        ],
    )


put("gltf-image-65536-png-header.gltf", textured_gltf(
    "data:image/png;base64," + base64.b64encode(png(65536, 65536, raw=b"\0" * 16)).decode()))
put("gltf-image-not-an-image.gltf", textured_gltf(
    "data:image/png;base64," + base64.b64encode(b"hello, not a png").decode()))

# ---------------------------------------------------------------- GLB
def glb(json_text, bin_data=None, total=None, chunks=None):
    def pad(b, fill):
        return b + fill * (-len(b) % 4)
    body = b""
    if chunks is None:
        j = pad(json_text.encode(), b" ")
        body = struct.pack("<II", len(j), 0x4E4F534A) + j
        if bin_data is not None:
            b = pad(bin_data, b"\0")
            body += struct.pack("<II", len(b), 0x004E4942) + b
    else:
        body = chunks
    length = 12 + len(body) if total is None else total
    return b"glTF" + struct.pack("<II", 2, length) + body


GLB_JSON = gltf(buffers=[{"byteLength": len(TRI_BYTES)}])
put("glb-header-truncated.glb", b"glTF\x02\0")
put("glb-version-1.glb", b"glTF" + struct.pack("<II", 1, 20) + b"\0" * 8)
put("glb-bad-magic.glb", b"glTX" + glb(GLB_JSON, TRI_BYTES)[4:])
put("glb-length-past-end.glb", glb(GLB_JSON, TRI_BYTES, total=1 << 20))
put("glb-chunk-past-end.glb", glb("", chunks=struct.pack("<II", 4000, 0x4E4F534A) + b"{}  "))
put("glb-chunk-4-gib.glb", glb("", chunks=struct.pack("<II", 0xFFFFFFFF, 0x4E4F534A) + b"{}  "))
put("glb-no-json-chunk.glb", glb("", chunks=struct.pack("<II", 4, 0x004E4942) + b"\0\0\0\0"))
put("glb-json-chunk-garbage.glb", glb("", chunks=struct.pack("<II", 8, 0x4E4F534A) + b"\xff\xfe{[}]\0\0"))
put("glb-no-bin-chunk.glb", glb(GLB_JSON))
put("glb-bin-chunk-short.glb", glb(GLB_JSON, TRI_BYTES[:20]))

# ---------------------------------------------------------------- scene files
put("shot-syntax-error.toml", '[[model]\nfile = "x.obj"\n')
put("shot-wrong-type.toml", '[render]\nwidth = "wide"\n')
put("shot-unknown-key.toml", '[render]\nwidht = 64\n')
put("shot-unknown-section.toml", '[lighting]\npower = 3\n')
put("shot-model-missing.toml", '[[model]]\nfile = "no-such-model.obj"\n')
put("shot-model-bad.toml", '[[model]]\nfile = "obj-index-zero.obj"\n')
put("shot-absurd-width.toml", '[render]\nwidth = 4000000000\nheight = 16\n')
put("shot-negative-spp.toml", '[render]\nspp = -4\n')
put("shot-light-overflow.toml", '[[model]]\nbuiltin = "cornell"\n[[light]]\ntype = "point"\nposition = [0, 0, 0]\nintensity = 5\ncolor = [1, 0.91e38, 0.8]\n')
put("shot-time-1e300.toml", '[render]\ntime = 1e300\n[[model]]\nbuiltin = "cornell"\n')
put("shot-spp-over-limit.toml", '[render]\nspp = 4000000000\n[[model]]\nbuiltin = "cornell"\n')
put("shot-pixels-over-limit.toml", '[render]\nwidth = 16384\nheight = 16384\n[[model]]\nbuiltin = "cornell"\n')
put("shot-nan-fov.toml", '[[model]]\nfile = "../ok/one-triangle.obj"\n[camera]\nposition = [0, 0, 3]\ntarget = [0, 0, 0]\nfov = nan\n')
put("shot-environment-missing.toml", '[[model]]\nfile = "../ok/one-triangle.obj"\n[environment]\nfile = "no-such-sky.hdr"\n')
put("shot-non-utf8.toml", b'[render]\nwidth = 16\n# \xff\xfe\n')
put("shot-deep-arrays.toml", "x = " + "[" * 5000 + "]" * 5000 + "\n")

# ---------------------------------------------------------------- HDR
HDR_HEAD = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"
put("hdr-empty.hdr", b"")
put("hdr-no-magic.hdr", b"P6\n4 4\n255\n" + b"\0" * 48)
put("hdr-header-never-ends.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n")
put("hdr-bad-format.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\x80\x80\x80\x80")
put("hdr-no-resolution-line.hdr", HDR_HEAD)
put("hdr-resolution-garbage.hdr", HDR_HEAD + b"-Y many +X lots\n")
put("hdr-zero-size.hdr", HDR_HEAD + b"-Y 0 +X 16\n")
put("hdr-65536-square-10-bytes.hdr", HDR_HEAD + b"-Y 65536 +X 65536\n" + b"\x80" * 10)
put("hdr-lying-header-10-bytes.hdr", HDR_HEAD + b"-Y 8192 +X 16384\n" + b"\x80" * 10)
put("hdr-truncated-flat.hdr", HDR_HEAD + b"-Y 4 +X 4\n" + b"\x80\x80\x80\x80" * 14)
put("hdr-truncated-rle.hdr", HDR_HEAD + b"-Y 2 +X 16\n" + b"\x02\x02\x00\x10" + b"\x90\x80" * 4 + b"\x02\x02\x00\x10\x90")
put("hdr-run-past-scanline.hdr", HDR_HEAD + b"-Y 1 +X 16\n" + b"\x02\x02\x00\x10" + b"\xff\x80" * 4)
put("hdr-literal-zero.hdr", HDR_HEAD + b"-Y 1 +X 16\n" + b"\x02\x02\x00\x10" + b"\x00" * 8)
put("hdr-rle-width-mismatch.hdr", HDR_HEAD + b"-Y 1 +X 16\n" + b"\x02\x02\x00\x20" + b"\x90\x80" * 4)
put("hdr-repeat-before-pixel.hdr", HDR_HEAD + b"-Y 1 +X 4\n" + b"\x01\x01\x01\x04" * 2)

# ---------------------------------------------------------------- EXR
def exr_attr(name, kind, data):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data


def exr(w, h, channels=("B", "G", "R"), pixels=True, window=None, truncate=None, bad_offsets=False):
    chlist = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in channels) + b"\0"
    x1, y1 = (w - 1, h - 1) if window is None else window
    head = b"\x76\x2f\x31\x01" + struct.pack("<i", 2)
    head += exr_attr("channels", "chlist", chlist)
    head += exr_attr("compression", "compression", b"\0")
    head += exr_attr("dataWindow", "box2i", struct.pack("<4i", 0, 0, x1, y1))
    head += exr_attr("displayWindow", "box2i", struct.pack("<4i", 0, 0, x1, y1))
    head += exr_attr("lineOrder", "lineOrder", b"\0")
    head += exr_attr("pixelAspectRatio", "float", struct.pack("<f", 1))
    head += exr_attr("screenWindowCenter", "v2f", struct.pack("<2f", 0, 0))
    head += exr_attr("screenWindowWidth", "float", struct.pack("<f", 1))
    head += b"\0"
    rows = h if pixels else 0
    table_at = len(head)
    first = table_at + 8 * h
    line = 8 + 4 * w * len(channels)
    table = b"".join(struct.pack("<Q", (1 << 40) if bad_offsets else first + y * line) for y in range(h))
    body = b""
    for y in range(rows):
        body += struct.pack("<ii", y, 4 * w * len(channels)) + struct.pack("<f", 1.0) * (w * len(channels))
    out = head + table + body
    return out if truncate is None else out[:truncate]


put("exr-empty.exr", b"")
put("exr-not-exr.exr", b"this is not an OpenEXR file at all")
put("exr-truncated.exr", exr(4, 4, truncate=200))
put("exr-65536-square-header.exr", exr(1, 1, window=(65535, 65535)))
put("exr-zero-channels.exr", exr(4, 4, channels=()))
put("exr-only-luminance.exr", exr(4, 4, channels=("Y",)))
put("exr-offsets-past-end.exr", exr(4, 4, bad_offsets=True))
put("exr-inverted-window.exr", exr(4, 4, window=(-5, -5)))

# ---------------------------------------------------------------- textures (through an MTL map_Kd)
good = png(4, 4)
put("png-truncated.png", good[: len(good) // 2])
put("png-65536-square-header.png", png(65536, 65536, raw=b"\0" * 16))
put("png-16384-square-header-tiny.png", png(16384, 16384, raw=b"\0" * 16, color=6))
put("png-crc-error.png", png(4, 4, crc=0x12345678))
# A palette of 4 bytes (not whole RGB entries): the png crate 0.18.1 panics on it.
put("png-palette-4-bytes.png", PNG_SIG + chunk(b"IHDR", struct.pack(">IIBBBBB", 1, 1, 8, 3, 0, 0, 0))
    + chunk(b"PLTE", b"\x10\x20\x30\x40") + chunk(b"IDAT", zlib.compress(b"\0\0")) + chunk(b"IEND", b""))
put("png-zero-by-zero.png", png(0, 0, raw=b""))
put("png-idat-garbage.png", PNG_SIG + chunk(b"IHDR", struct.pack(">IIBBBBB", 4, 4, 8, 2, 0, 0, 0)) + chunk(b"IDAT", b"not zlib at all") + chunk(b"IEND", b""))
put("png-signature-only.png", PNG_SIG)
put("jpg-truncated.jpg", b"\xff\xd8\xff\xe0\x00\x10JFIF\x00\x01\x01\x00\x00\x01\x00\x01\x00\x00\xff\xdb\x00\x43\x00")
put("jpg-65535-square-header.jpg",
    b"\xff\xd8\xff\xdb\x00\x43\x00" + bytes([1] * 64)
    + b"\xff\xc0\x00\x0b\x08\xff\xff\xff\xff\x01\x01\x11\x00"
    + b"\xff\xc4\x00\x14\x00\x01" + b"\x00" * 15 + b"\x00" + b"\xff\xda\x00\x08\x01\x01\x00\x00\x3f\x00" + b"\x00" * 8 + b"\xff\xd9")
put("jpg-not-jpeg.jpg", b"GIF89a not a jpeg")

# ---------------------------------------------------------------- ray files (raylab bench --rays)
put("rays-length-not-multiple-of-24.rays", b"\0" * 30)
put("rays-nan-origin.rays", struct.pack("<6f", float("nan"), 0, 0, 0, 0, -1))
put("rays-zero-direction.rays", struct.pack("<6f", 0, 0, 5, 0, 0, 0))
put("rays-inf-direction.rays", struct.pack("<6f", 0, 0, 5, 0, float("inf"), -1))
put("rays-empty.rays", b"")

# ---------------------------------------------------------------- strange but valid (tests/data/ok)
OK = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "ok")


def put_ok(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(OK, name), "wb") as f:
        f.write(data)


put_ok("one-triangle.obj", TRI + "f 1 2 3\n")
put_ok("empty.obj", "# nothing here\n")
put_ok("empty.gltf", json.dumps({"asset": {"version": "2.0"}}))
put_ok("empty-scene.gltf", json.dumps({"asset": {"version": "2.0"}, "scenes": [{"nodes": []}], "scene": 0}))
put_ok("all-degenerate.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nv 0 0 0\nf 1 2 3\nf 1 1 1\nf 1 4 1\nf 2 3 1\n")
put_ok("nan-normals.obj", TRI + "vn nan nan nan\nvn inf 0 0\nf 1//1 2//1 3//2\n")
nan_normals = TRI_BYTES + struct.pack("<9f", *([float("nan")] * 9))
put_ok("nan-normals.gltf", gltf(
    meshes=[{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 2}, "indices": 1}]}],
    buffers=[{"byteLength": len(nan_normals), "uri": buffer_uri(nan_normals)}],
    bufferViews=[{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                 {"buffer": 0, "byteOffset": 36, "byteLength": 6},
                 {"buffer": 0, "byteOffset": 44, "byteLength": 36}],
    accessors=[{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0, 0, 0], "max": [1, 1, 0]},
               {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
               {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3"}]))
# All UVs equal: tangent generation divides by a zero UV area.
put_ok("normal-map.png", png(1, 1, raw=b"\0\x80\x80\xff"))
put_ok("one-texel.png", png(1, 1, raw=b"\0\xc0\x40\x20"))
put_ok("zero-area-uvs.mtl", "newmtl m\nKd 0.8 0.8 0.8\nmap_Kd one-texel.png\nnorm normal-map.png\n")
put_ok("zero-area-uvs.obj", "mtllib zero-area-uvs.mtl\n" + TRI + "v 1 1 0\nvt 0.5 0.5\nvn 0 0 1\nusemtl m\nf 1/1/1 2/1/1 3/1/1\nf 2/1/1 4/1/1 3/1/1\n")
put_ok("huge-coordinates.obj", "v -1e30 -1e30 0\nv 1e30 -1e30 0\nv 0 1e30 0\nv 0 0 1e30\nf 1 2 3\nf 1 2 4\nf 2 3 4\nf 1 3 4\n")
put_ok("tiny-extent.obj", "v 0 0 0\nv 1e-30 0 0\nv 0 1e-30 0\nv 0 0 1e-30\nf 1 2 3\nf 1 2 4\nf 2 3 4\nf 1 3 4\n")
put_ok("one-texel.hdr", HDR_HEAD + b"-Y 1 +X 1\n" + bytes([128, 128, 128, 129]))
put_ok("missing-mtllib.obj", "mtllib no-such-library.mtl\n" + TRI + "usemtl m\nf 1 2 3\n")
