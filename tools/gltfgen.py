"""Helpers shared by the scene generators (make_showcase.py, make_helmet_grid.py,
make_street.py): a minimal PNG writer, the vector and quaternion arithmetic that glTF node
rotations need, a builder of one binary buffer with its views and accessors, and reading the
DamagedHelmet's glTF. Standard library only."""

import json
import math
import os
import struct
import sys
import urllib.parse
import zlib

FLOAT, U16, U32 = 5126, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


class BufferBuilder:
    """One glTF binary buffer: 4-byte aligned buffer views, and accessors over them."""

    def __init__(self):
        self.bin = bytearray()
        self.views = []
        self.accessors = []

    def view(self, data, target):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.views.append({"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data),
                           "target": target})
        self.bin += data
        return len(self.views) - 1

    def floats(self, rows, kind, with_bounds=False):
        n = len(rows[0])
        data = struct.pack("<%df" % (n * len(rows)), *[c for r in rows for c in r])
        acc = {"bufferView": self.view(data, ARRAY_BUFFER), "componentType": FLOAT,
               "count": len(rows), "type": kind}
        if with_bounds:
            # bounds of the float32 values actually stored (exact: f32 -> f64 is exact)
            stored = struct.unpack("<%df" % (n * len(rows)), data)
            cols = [stored[k::n] for k in range(n)]
            acc["min"] = [min(c) for c in cols]
            acc["max"] = [max(c) for c in cols]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def indices(self, tris, vertex_count):
        flat = [i for t in tris for i in t]
        assert max(flat) < vertex_count
        if vertex_count <= 65535:
            ctype, data = U16, struct.pack("<%dH" % len(flat), *flat)
        else:
            ctype, data = U32, struct.pack("<%dI" % len(flat), *flat)
        self.accessors.append({"bufferView": self.view(data, ELEMENT_ARRAY_BUFFER),
                               "componentType": ctype, "count": len(flat), "type": "SCALAR",
                               "min": [min(flat)], "max": [max(flat)]})
        return len(self.accessors) - 1


def read_helmet(gltf_path):
    """The DamagedHelmet's glTF JSON, the path of its buffer (checked against the byte length
    the file gives; exits with one line if it differs), its one primitive and its triangle
    count."""
    with open(gltf_path, encoding="utf-8") as f:
        helmet = json.load(f)
    (hbuf,) = helmet["buffers"]
    bin_path = os.path.join(os.path.dirname(gltf_path), urllib.parse.unquote(hbuf["uri"]))
    if os.path.getsize(bin_path) != hbuf["byteLength"]:
        sys.exit("%s: %d bytes, the glTF says %d" % (bin_path, os.path.getsize(bin_path),
                                                      hbuf["byteLength"]))
    (hmesh,) = helmet["meshes"]
    (hprim,) = hmesh["primitives"]
    return helmet, bin_path, hprim, helmet["accessors"][hprim["indices"]]["count"] // 3


def _png_chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def png_bytes(width, height, rows, channels=3, level=9):
    """PNG file bytes (8-bit RGB or RGBA, filter 0 on every row) from `height` byte strings of
    width*channels bytes, top row first; `level` is the zlib compression level."""
    assert channels in (3, 4)
    color_type = 2 if channels == 3 else 6
    raw = bytearray()
    for row in rows:
        assert len(row) == width * channels
        raw += b"\x00"
        raw += row
    assert len(raw) == height * (width * channels + 1)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, color_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + _png_chunk(b"IHDR", ihdr)
            + _png_chunk(b"IDAT", zlib.compress(bytes(raw), level)) + _png_chunk(b"IEND", b""))


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def normalize(a):
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def canonical(q):
    """q and -q are the same rotation: keep the one with w >= 0."""
    return q if q[3] >= 0 else tuple(-c for c in q)


def quat_from_axes(x, y, z):
    """Unit quaternion (x, y, z, w), w >= 0, of the rotation whose matrix has columns x, y, z."""
    m00, m10, m20 = x
    m01, m11, m21 = y
    m02, m12, m22 = z
    tr = m00 + m11 + m22
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = ((m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s)
    elif m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2
        q = (0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s)
    elif m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2
        q = ((m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s)
    else:
        s = math.sqrt(1.0 + m22 - m00 - m11) * 2
        q = ((m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s)
    n = math.sqrt(sum(c * c for c in q))
    return canonical(tuple(c / n for c in q))


def look_along(direction, up=(0.0, 1.0, 0.0)):
    """Rotation pointing a node's local -z along `direction` with local +y towards `up`."""
    z = normalize(tuple(-c for c in direction))
    x = normalize(cross(up, z))
    y = cross(z, x)
    return quat_from_axes(x, y, z)


def quat_axis_angle(axis, angle):
    axis = normalize(axis)
    s = math.sin(angle / 2)
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2))


def quat_mul(a, b):
    """Hamilton product a*b (apply b first), quaternions as (x, y, z, w)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return canonical((aw * bx + ax * bw + ay * bz - az * by,
                      aw * by - ax * bz + ay * bw + az * bx,
                      aw * bz + ax * by - ay * bx + az * bw,
                      aw * bw - ax * bx - ay * by - az * bz))


def r6(v):
    """Numbers for the JSON: rounded to 6 decimals (exact enough, and stable text)."""
    if isinstance(v, (list, tuple)):
        return [r6(c) for c in v]
    out = round(v, 6)
    return 0.0 if out == 0 else out


def write_scene(gltf, *path):
    """Writes `gltf` (indented JSON, a newline at the end) to the repository's scenes/ folder
    at `path` (its folders made if missing), and prints where."""
    here = os.path.dirname(os.path.abspath(__file__))
    out = os.path.join(here, "..", "scenes", *path)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w", encoding="utf-8") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")
    print("wrote", os.path.normpath(out))


def generator_main(build, default_out, doc):
    """A generator's command line: `build(OUT_DIR)`, OUT_DIR the first argument or
    `default_out`; -h or --help prints `doc`."""
    out_dir = sys.argv[1] if len(sys.argv) > 1 else default_out
    if out_dir in ("-h", "--help"):
        print(doc)
        return
    build(out_dir)
