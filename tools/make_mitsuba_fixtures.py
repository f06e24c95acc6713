#!/usr/bin/env python3
"""Writes the small images of raylab's own Mitsuba test scenes
(tests/data/mitsuba/suite/textures/): a colour test pattern, a grey
leaf-like mask, and a field of round bumps as a height map and as the
normal map of the same heights, as 8-bit PNGs made here (no third-party data), with the
standard library only; and the signed distance grid of `sdfgrid_path.xml`
(tests/data/mitsuba/suite/grids/torus.vol: a torus's distances on 14³
samples over the unit cube, Mitsuba's `.vol` format), and the grids of
`media_grid_volpath.xml` (grids/puff.vol: a lumpy cloud's density on 12³
samples; grids/tint.vol: an RGB albedo on 6³). Run again to recreate
them; the output is deterministic."""

import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "tests", "data", "mitsuba", "suite", "textures")


def png(path, width, height, channels, pixel):
    """Writes an 8-bit PNG whose pixel (x, y) is pixel(x, y) (a tuple)."""
    kind = {1: 0, 3: 2}[channels]
    raw = b"".join(
        b"\x00" + bytes(v for x in range(width) for v in pixel(x, y)) for y in range(height)
    )

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))

    header = struct.pack(">IIBBBBB", width, height, 8, kind, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def pattern(x, y):
    # Smooth colour gradients with a few hard stripes: bilinear and nearest
    # lookups differ visibly, and every channel varies.
    r = int(255 * (0.5 + 0.5 * math.sin(x / 5.0)))
    g = int(255 * y / 63)
    b = 230 if (x // 8 + y // 8) % 2 == 0 else 40
    return (r, g, b)


def mask(x, y):
    # An ellipse with a notch: opaque inside (255), clear outside (0), a
    # soft rim between.
    u, v = (x - 31.5) / 28.0, (y - 31.5) / 20.0
    d = math.hypot(u, v)
    if abs(x - 40) < 4 and y < 32:
        d = 2.0
    return (max(0, min(255, int(255 * (1.2 - d) / 0.2))),)


def bump(x, y):
    """Height in [0, 1] of a 4 x 4 grid of round bumps (cosine profile) on
    a 64 x 64 image, and its gradient per texel."""
    cx, cy = (x % 16) - 7.5, (y % 16) - 7.5
    r = math.hypot(cx, cy)
    if r >= 7.0:
        return 0.0, 0.0, 0.0
    h = 0.5 + 0.5 * math.cos(math.pi * r / 7.0)
    dh_dr = -0.5 * math.pi / 7.0 * math.sin(math.pi * r / 7.0)
    return h, dh_dr * cx / max(r, 1e-9), dh_dr * cy / max(r, 1e-9)


def height(x, y):
    return (int(round(255 * bump(x, y)[0])),)


def normals(x, y):
    # The normal of the height field z = 4 h per texel, in tangent space
    # (x right, y down the image as v grows), mapped to [0, 1].
    _, gx, gy = bump(x, y)
    n = (-4.0 * gx, -4.0 * gy, 1.0)
    length = math.sqrt(sum(c * c for c in n))
    return tuple(int(round(255 * (0.5 + 0.5 * c / length))) for c in n)


def vol(path, n, distance, channels=1):
    """Writes a Mitsuba `.vol` grid (version 3, float32) of n^3 samples of
    distance(x, y, z) at (i, j, k) / (n - 1), x fastest; with 3 channels,
    distance returns three values."""
    data = b"VOL" + bytes([3]) + struct.pack("<iiiii", 1, n, n, n, channels)
    data += struct.pack("<6f", 0.0, 0.0, 0.0, 1.0, 1.0, 1.0)
    h = 1.0 / (n - 1)
    values = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                v = distance(i * h, j * h, k * h)
                values.extend(v if channels > 1 else [v])
    data += struct.pack("<%df" % len(values), *values)
    with open(path, "wb") as f:
        f.write(data)


def torus(x, y, z):
    """Signed distance to a torus about the z axis through (0.5, 0.5, 0.5):
    major radius 0.3, minor 0.13."""
    x, y, z = x - 0.5, y - 0.5, z - 0.5
    ring = math.sqrt(x * x + y * y) - 0.3
    return math.sqrt(ring * ring + z * z) - 0.13


def puff(x, y, z):
    """A lumpy cloud's density: two overlapping balls with a ripple, 0 at
    the cube's faces."""
    def ball(cx, cy, cz, r):
        d = math.sqrt((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / r
        return max(0.0, 1.0 - d) ** 1.5
    ripple = 0.75 + 0.25 * math.sin(17.0 * x) * math.sin(13.0 * y + 1.0) * math.sin(11.0 * z + 2.0)
    return (ball(0.42, 0.45, 0.4, 0.38) + 0.8 * ball(0.62, 0.55, 0.6, 0.3)) * ripple


def tint(x, y, z):
    """An albedo that turns from warm at the bottom to cool at the top."""
    return [0.95 - 0.5 * z, 0.7 + 0.2 * x, 0.45 + 0.5 * z]


def main():
    grids = os.path.join(OUT, "..", "grids")
    os.makedirs(grids, exist_ok=True)
    vol(os.path.join(grids, "torus.vol"), 14, torus)
    vol(os.path.join(grids, "puff.vol"), 12, puff)
    vol(os.path.join(grids, "tint.vol"), 6, tint, channels=3)
    os.makedirs(OUT, exist_ok=True)
    png(os.path.join(OUT, "pattern.png"), 64, 64, 3, pattern)
    png(os.path.join(OUT, "mask.png"), 64, 64, 1, mask)
    png(os.path.join(OUT, "height.png"), 64, 64, 1, height)
    png(os.path.join(OUT, "normals.png"), 64, 64, 3, normals)
    print("wrote", OUT)


if __name__ == "__main__":
    main()
