"""Helpers shared by the scene generators (make_showcase.py, make_helmet_grid.py): a minimal
PNG writer and the vector and quaternion arithmetic that glTF node rotations need.
Standard library only."""

import math
import struct
import zlib


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
