#!/usr/bin/env python3
"""Writes helmet-grid.gltf, a load-time and memory benchmark scene built on the DamagedHelmet.

Usage (from the project folder):

    python3 tools/make_helmet_grid.py OUT_DIR [--assets DIR] [--cols 5] [--rows 4]

e.g. OUT_DIR = bench-data/helmet-grid (bench-data/ is ignored by git; the scene is about 1.2 MB of
PNGs plus the JSON, and needs the assets/ folder where it was made, as its URIs are relative).

--assets defaults to the repository's assets/ folder; a relative --assets is taken from the
current folder.

OUT_DIR/helmet-grid.gltf references the helmet's own buffer
<assets>/models/DamagedHelmet/DamagedHelmet.bin and its five JPEG textures by relative URIs
(forward slashes, percent-encoded), re-uses its accessors and buffer views unchanged, and places
its mesh cols x rows times in a wall-like grid (default 5 x 4 = 20 nodes, 20 x 15,452 = 309,040
triangles). The helmets use six material variants, one glTF mesh per variant (the six meshes
share the helmet's accessors and differ only in material):

  variant 0: the helmet's own material and five JPEG images;
  variants 1-5: five 1024 x 1024 PNG textures each, generated into OUT_DIR: base colour (tinted
  noise with stripes), metallic-roughness, a normal map (flat with grooves), an emissive map
  (black with a few bright spots) and an occlusion map.

So the scene has 5 + 25 = 30 distinct images, 24 of them used by the renderer (occlusion maps
are read and ignored). It also has a perspective camera that frames the
grid and one directional light (3 W/m^2, radiometric as in docs/scene-conventions.md).
Standard library only; the output is the same bytes on every run.
"""

import argparse
import json
import math
import os
import random
import sys
import time
import urllib.parse

from gltfgen import look_along, normalize, png_bytes, quat_mul, r6, read_helmet

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_ASSETS = os.path.join(ROOT, "assets")
HELMET_DIR = os.path.join("models", "DamagedHelmet")
HELMET_GLTF = "DamagedHelmet.gltf"

SIZE = 1024               # generated textures are SIZE x SIZE RGB
REPEAT, LINEAR, LINEAR_MIPMAP_LINEAR = 10497, 9729, 9987


# ---------------------------------------------------------------------------------------------
# PNG writing (8-bit RGB, filter 0 on every row)





# ---------------------------------------------------------------------------------------------
# Fast procedural rows: every image is built from 1-D byte rows with bytes.translate (a 256-entry
# lookup table per row), rotations (row[k:] + row[:k]) and strided slice assignment, so no
# per-pixel Python work is done for the 1024 x 1024 images.

def smooth_noise(rng, n, periods, weights):
    """1-D value noise over n samples, periodic in n, in [0, 1]: octaves of cosine-interpolated
    random values, one every `period` samples."""
    out = [0.0] * n
    for period, weight in zip(periods, weights):
        knots = [rng.random() for _ in range(n // period)]
        m = len(knots)
        for x in range(n):
            t, k = math.modf(x / period)
            k = int(k)
            s = (1 - math.cos(math.pi * t)) / 2
            out[x] += weight * (knots[k % m] * (1 - s) + knots[(k + 1) % m] * s)
    lo, hi = min(out), max(out)
    return [(v - lo) / (hi - lo) for v in out]


def to_bytes(values):
    """[0, 1] floats -> bytes 0..255."""
    return bytes(max(0, min(255, int(v * 255 + 0.5))) for v in values)


def ramp_table(c0, c1, gain=1.0, offset=0.0):
    """Lookup table: byte i -> lerp(c0, c1, clamp(gain * i/255 + offset)) as a byte (c in 0..1)."""
    out = bytearray(256)
    for i in range(256):
        t = min(1.0, max(0.0, gain * i / 255.0 + offset))
        out[i] = max(0, min(255, int((c0 + (c1 - c0) * t) * 255 + 0.5)))
    return bytes(out)


def interleave(r, g, b):
    row = bytearray(3 * len(r))
    row[0::3] = r
    row[1::3] = g
    row[2::3] = b
    return bytes(row)


def rotate(row, k):
    k %= len(row)
    return row[k:] + row[:k]


# Per-variant looks: (dark colour, light colour) of the base colour in sRGB 0..1, stripe slope
# (pixels of shift per row: 1 = diagonal, 0 = vertical), stripe period, emissive spot colour.
VARIANTS = {
    1: {"c0": (0.10, 0.16, 0.30), "c1": (0.55, 0.70, 0.90), "slope": 1, "period": 96,
        "glow": (0.2, 0.9, 1.0), "metal_blocks": 0.35},
    2: {"c0": (0.30, 0.10, 0.05), "c1": (0.95, 0.62, 0.25), "slope": 0, "period": 64,
        "glow": (1.0, 0.45, 0.1), "metal_blocks": 0.6},
    3: {"c0": (0.08, 0.22, 0.08), "c1": (0.70, 0.82, 0.45), "slope": -2, "period": 128,
        "glow": (0.8, 1.0, 0.3), "metal_blocks": 0.15},
    4: {"c0": (0.25, 0.08, 0.28), "c1": (0.85, 0.55, 0.90), "slope": 2, "period": 80,
        "glow": (1.0, 0.3, 0.8), "metal_blocks": 0.45},
    5: {"c0": (0.20, 0.20, 0.22), "c1": (0.90, 0.90, 0.85), "slope": -1, "period": 112,
        "glow": (1.0, 1.0, 0.6), "metal_blocks": 0.25},
}


def make_base_colour(variant, rng):
    """Tinted noise with soft stripes; a slow per-row brightness wave (separable, fast)."""
    look = VARIANTS[variant]
    col = smooth_noise(rng, SIZE, (256, 64, 16, 4), (1.0, 0.5, 0.3, 0.15))
    period = look["period"]
    stripe = [0.5 + 0.5 * math.sin(2 * math.pi * x / period) for x in range(SIZE)]
    base = to_bytes(0.55 * c + 0.45 * s ** 3 for c, s in zip(col, stripe))
    row_wave = smooth_noise(rng, SIZE, (512, 128, 32), (1.0, 0.4, 0.2))
    levels = 32
    tables = []
    for q in range(levels):
        off = (q / (levels - 1) - 0.5) * 0.35
        tables.append([ramp_table(look["c0"][c], look["c1"][c], 1.0, off) for c in range(3)])
    rows = []
    for y in range(SIZE):
        line = rotate(base, look["slope"] * y)
        r_t, g_t, b_t = tables[int(row_wave[y] * (levels - 1) + 0.5)]
        rows.append(interleave(line.translate(r_t), line.translate(g_t), line.translate(b_t)))
    return png_bytes(SIZE, SIZE, rows, level=6)


def make_metallic_roughness(variant, rng):
    """R 255 (unused), G roughness from noise bands (0.2 .. 0.85), B metallic: 128-px blocks,
    a variant-dependent share of them metal (255), the rest dielectric (0)."""
    look = VARIANTS[variant]
    col = smooth_noise(rng, SIZE, (128, 32, 8), (1.0, 0.5, 0.25))
    col_b = to_bytes(col)
    row_noise = smooth_noise(rng, SIZE, (256, 64), (1.0, 0.5))
    levels = 16
    rough_tables = [ramp_table(0.2, 0.85, 0.6, 0.4 * q / (levels - 1)) for q in range(levels)]
    block = 128
    nb = SIZE // block
    metal = [[rng.random() < look["metal_blocks"] for _ in range(nb)] for _ in range(nb)]
    metal_rows = [b"".join((b"\xff" if metal[by][bx] else b"\x00") * block for bx in range(nb))
                  for by in range(nb)]
    red = b"\xff" * SIZE
    rows = []
    for y in range(SIZE):
        g = col_b.translate(rough_tables[int(row_noise[y] * (levels - 1) + 0.5)])
        rows.append(interleave(red, g, metal_rows[y // block]))
    return png_bytes(SIZE, SIZE, rows, level=6)


def make_normal(variant, rng):
    """Mostly flat (128, 128, 255); V-grooves along grid lines (every `pitch` pixels), the
    vertical ones tilting x, the horizontal ones tilting y (up in the image is +y)."""
    pitch = (128, 96, 160, 112, 144)[variant - 1]
    half = 6      # groove half-width in pixels
    tilt = 0.45   # sine of the groove walls' tilt

    def enc(nx, ny):
        nz = math.sqrt(max(0.0, 1.0 - nx * nx - ny * ny))
        return bytes((int((nx * 0.5 + 0.5) * 255 + 0.5), int((ny * 0.5 + 0.5) * 255 + 0.5),
                      int((nz * 0.5 + 0.5) * 255 + 0.5)))

    flat = enc(0.0, 0.0)
    # a row away from horizontal grooves: flat, with vertical grooves
    base = bytearray(flat * SIZE)
    offset = rng.randrange(pitch)
    for x in range(SIZE):
        d = (x - offset) % pitch
        if d < half:          # just right of a groove's centre: the wall faces left (-x)
            base[3 * x:3 * x + 3] = enc(-tilt, 0.0)
        elif d >= pitch - half:   # just left of it: the wall faces right (+x)
            base[3 * x:3 * x + 3] = enc(tilt, 0.0)
    base = bytes(base)
    below = enc(0.0, tilt)     # just below a groove's centre in the image the wall faces up
    above = enc(0.0, -tilt)
    rows = []
    for y in range(SIZE):
        d = (y - offset) % pitch
        if d < half:
            rows.append(below * SIZE)
        elif d >= pitch - half:
            rows.append(above * SIZE)
        else:
            rows.append(base)
    return png_bytes(SIZE, SIZE, rows, level=6)


def make_emissive(variant, rng):
    """Black with a dozen round bright spots (a bright core inside a dimmer halo)."""
    look = VARIANTS[variant]
    core = bytes(int(c * 255 + 0.5) for c in look["glow"])
    halo = bytes(int(c * 0.35 * 255 + 0.5) for c in look["glow"])
    spots = [(rng.randrange(40, SIZE - 40), rng.randrange(40, SIZE - 40), rng.randrange(8, 30))
             for _ in range(12)]
    black = bytes(3 * SIZE)
    rows = []
    for y in range(SIZE):
        row = None
        for (cx, cy, r) in spots:
            for colour, radius in ((halo, r * 1.6), (core, r)):
                dy = y - cy
                if abs(dy) >= radius:
                    continue
                w = int(math.sqrt(radius * radius - dy * dy))
                x0, x1 = max(0, cx - w), min(SIZE, cx + w + 1)
                if row is None:
                    row = bytearray(black)
                row[3 * x0:3 * x1] = colour * (x1 - x0)
        rows.append(bytes(row) if row is not None else black)
    return png_bytes(SIZE, SIZE, rows, level=6)


def make_occlusion(variant, rng):
    """Grey (R = G = B): mostly white, darkened where a column bump meets a row bump."""
    col = smooth_noise(rng, SIZE, (128, 32), (1.0, 0.4))
    row = smooth_noise(rng, SIZE, (128, 32), (1.0, 0.4))
    # sharpen into sparse bumps
    col_b = to_bytes(max(0.0, v - 0.45) / 0.55 for v in col)
    levels = 32
    tables = []
    for q in range(levels):
        k = 0.75 * q / (levels - 1)
        tables.append(bytes(int(255 * (1 - k * i / 255) + 0.5) for i in range(256)))
    rows = []
    for y in range(SIZE):
        strength = max(0.0, row[y] - 0.45) / 0.55
        grey = col_b.translate(tables[int(strength * (levels - 1) + 0.5)])
        rows.append(interleave(grey, grey, grey))
    return png_bytes(SIZE, SIZE, rows, level=6)


MAPS = [("basecolor", make_base_colour), ("metalrough", make_metallic_roughness),
        ("normal", make_normal), ("emissive", make_emissive), ("occlusion", make_occlusion)]


# ---------------------------------------------------------------------------------------------
# Geometry helpers













def uri_from(out_dir, target):
    """Relative URI from out_dir to the file `target`: forward slashes, percent-encoded.
    Real paths (symbolic links resolved), so that the file system resolves each ".." as here."""
    rel = os.path.relpath(os.path.realpath(target), os.path.realpath(out_dir))
    return urllib.parse.quote(rel.replace(os.sep, "/"), safe="/")


# ---------------------------------------------------------------------------------------------

def build(out_dir, assets, cols, rows):
    helmet_dir = os.path.join(assets, HELMET_DIR)
    helmet_path = os.path.join(helmet_dir, HELMET_GLTF)
    helmet, bin_path, hprim, helmet_tris = read_helmet(helmet_path)
    hbuf = helmet["buffers"][0]
    os.makedirs(out_dir, exist_ok=True)
    (hmat,) = helmet["materials"]

    # --- images: the helmet's five, then five generated per variant -----------------------
    images, textures = [], []
    for im in helmet["images"]:
        images.append({"uri": uri_from(out_dir, os.path.join(helmet_dir,
                                                             urllib.parse.unquote(im["uri"]))),
                       "mimeType": "image/jpeg", "name": "helmet " + im["uri"]})
    for ht in helmet["textures"]:
        textures.append({"sampler": 0, "source": ht["source"]})

    t0 = time.time()
    generated = {}
    variant_tex = {}
    for variant in sorted(VARIANTS):
        variant_tex[variant] = {}
        for k, (kind, make) in enumerate(MAPS):
            name = "helmet-grid-v%d-%s.png" % (variant, kind)
            rng = random.Random(1000 * variant + k)
            generated[name] = make(variant, rng)
            images.append({"uri": urllib.parse.quote(name), "mimeType": "image/png",
                           "name": "variant %d %s" % (variant, kind)})
            textures.append({"sampler": 0, "source": len(images) - 1})
            variant_tex[variant][kind] = len(textures) - 1
    gen_seconds = time.time() - t0

    # --- materials: the helmet's own (its texture indices kept), three generated ------------
    mat0 = json.loads(json.dumps(hmat))
    mat0["name"] = "variant 0: DamagedHelmet"
    materials = [mat0]
    for variant in sorted(VARIANTS):
        t = variant_tex[variant]
        materials.append({
            "name": "variant %d: generated" % variant,
            "pbrMetallicRoughness": {"baseColorTexture": {"index": t["basecolor"]},
                                     "metallicRoughnessTexture": {"index": t["metalrough"]},
                                     "metallicFactor": 1.0, "roughnessFactor": 1.0},
            "normalTexture": {"index": t["normal"], "scale": 1.0},
            "occlusionTexture": {"index": t["occlusion"], "strength": 1.0},
            "emissiveTexture": {"index": t["emissive"]},
            "emissiveFactor": [1.0, 1.0, 1.0],
        })

    meshes = []
    for v in range(len(VARIANTS) + 1):
        prim = {"attributes": dict(hprim["attributes"]), "indices": hprim["indices"],
                "material": v, "mode": 4}
        meshes.append({"name": "helmet variant %d" % v, "primitives": [prim]})

    # --- nodes: a wall of helmets facing +z ---------------------------------------------------
    spacing = 2.4
    helmet_rot = tuple(helmet["nodes"][0].get("rotation", (0.0, 0.0, 0.0, 1.0)))
    nodes = []
    for j in range(rows):
        for i in range(cols):
            n = j * cols + i
            x = (i - (cols - 1) / 2) * spacing
            y = ((rows - 1) / 2 - j) * spacing
            yaw = math.radians(25.0 * math.sin(1.7 * n + 0.5))
            q_yaw = (0.0, math.sin(yaw / 2), 0.0, math.cos(yaw / 2))
            nodes.append({"name": "helmet %d" % n, "mesh": n % (len(VARIANTS) + 1),
                          "translation": r6((x, y, 0.0)),
                          "rotation": r6(quat_mul(q_yaw, helmet_rot))})

    # camera: frames the grid's bounds (helmets reach about 1.0 m from their centres)
    half_h = ((rows - 1) / 2) * spacing + 1.15
    half_w = ((cols - 1) / 2) * spacing + 1.15
    yfov, aspect = 0.7, 1.5
    dist = max(half_h / math.tan(yfov / 2), half_w / (aspect * math.tan(yfov / 2))) + 1.2
    eye = (0.0, 0.12 * dist, dist)
    look_dir = normalize((0.0 - eye[0], 0.0 - eye[1], 0.0 - eye[2]))
    nodes.append({"name": "camera", "camera": 0, "translation": r6(eye),
                  "rotation": r6(look_along(look_dir))})
    sun_dir = normalize((0.45, -0.55, -1.0))
    nodes.append({"name": "sun", "rotation": r6(look_along(sun_dir)),
                  "extensions": {"KHR_lights_punctual": {"light": 0}}})

    gltf = {
        "asset": {"version": "2.0", "generator": "raylab tools/make_helmet_grid.py",
                  "copyright": "DamagedHelmet: theblueturtle_, CC BY 4.0 (see assets/README.md)"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "sun", "type": "directional", "color": [1.0, 0.97, 0.92], "intensity": 3.0}]}},
        "scene": 0,
        "scenes": [{"name": "helmet grid", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"name": "grid camera", "type": "perspective",
                     "perspective": {"yfov": yfov, "aspectRatio": aspect, "znear": 0.1,
                                     "zfar": 200.0}}],
        "meshes": meshes,
        "materials": materials,
        "textures": textures,
        "samplers": [{"magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR,
                      "wrapS": REPEAT, "wrapT": REPEAT}],
        "images": images,
        "accessors": helmet["accessors"],
        "bufferViews": helmet["bufferViews"],
        "buffers": [{"uri": uri_from(out_dir, bin_path), "byteLength": hbuf["byteLength"]}],
    }

    for name, data in generated.items():
        with open(os.path.join(out_dir, name), "wb") as f:
            f.write(data)
    with open(os.path.join(out_dir, "helmet-grid.gltf"), "w", encoding="utf-8") as f:
        f.write(json.dumps(gltf, indent=1) + "\n")

    n_helmets = rows * cols
    print("wrote %s: %d helmets x %d triangles = %d triangles; %d textures (%d distinct images: "
          "%d JPEG from the helmet, %d PNG generated in %.1f s, %.1f MB)"
          % (os.path.join(out_dir, "helmet-grid.gltf"), n_helmets, helmet_tris,
             n_helmets * helmet_tris, len(textures), len(images), len(helmet["images"]),
             len(generated), gen_seconds, sum(len(d) for d in generated.values()) / 1e6))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir", metavar="OUT_DIR")
    ap.add_argument("--assets", default=DEFAULT_ASSETS,
                    help="the folder holding models/DamagedHelmet (default: the repository's assets/, %(default)s)")
    ap.add_argument("--cols", type=int, default=5)
    ap.add_argument("--rows", type=int, default=4)
    a = ap.parse_args()
    if a.cols < 1 or a.rows < 1:
        ap.error("--cols and --rows must be at least 1")
    build(a.out_dir, a.assets, a.cols, a.rows)


if __name__ == "__main__":
    main()
