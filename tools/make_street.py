#!/usr/bin/env python3
"""Writes scenes/street/street.gltf: a night street ending in a plaza, a many-light benchmark
scene (about 2,000 small emissive lamps and 50 spot lights) for issue 30's light selection.

Usage (from the project folder):

    python3 tools/make_street.py [OUT_DIR] [--assets DIR]

OUT_DIR defaults to scenes/street beside this tools/ folder. It writes street.gltf and
street.bin there (about 0.5 MB together). The DamagedHelmets' buffer and five JPEG textures
stay in <assets>/models/DamagedHelmet and are referenced by relative URIs (forward slashes,
percent-encoded; ../../assets/models/DamagedHelmet/... from scenes/street), as in
make_helmet_grid.py and make_helmet_venice.py. --assets defaults to the repository's assets/
folder. Standard library only; the output is the same bytes on every run.

The scene, in glTF units (metres, +y up; the street runs along -z), follows
docs/scene-conventions.md (radiometric light units, one-sided emission):

- a wet asphalt ground plane (dielectric, roughness 0.3), raised concrete sidewalks, two rows of
  box buildings (six plaster/brick colours, 7-22 m tall) with dark glossy windows, about a
  fifth of the upper windows and a quarter of the shop windows lit (dim emissive quads),
  emissive shop signs; a plaza at the end, closed by more buildings;
- about 2,000 small lamps: bulbs (octahedra of 3.5-4 cm radius, 8 emitting triangles each,
  emissiveFactor x KHR_materials_emissive_strength 25-80 in eight colours) on zig-zag festoon
  strings across the street, along every shop fascia and roofline, and on sixteen strings
  radiating from a maypole in the plaza; the 20 street lamps' lenses (emissive quads facing
  down);
- KHR_lights_punctual: 50 spot lights (one light per node), 20 street lamps (200 W/sr, cone
  0.6/0.95 rad, pointing down and a little towards the road) and 30 facade downlights over the
  shop doors (25 W/sr, cone 0.35/0.6 rad), plus two point lights (40 W/sr) in the plaza;
- five DamagedHelmets (15,452 triangles each; the helmet's textures, normal map and emission,
  but a uniform metallic 0.6 and roughness 0.35 instead of its metallic-roughness map, see
  build()): four standing on the street and one on a plinth in the plaza;
- no environment (black), one perspective camera (yfov 0.85, aspectRatio 4/3, default render
  size 800 x 600) 8 m up, looking down the street and over the festoons into the plaza, so that
  the lamps are seen from a few metres to 120 m away.

Most lamps are far from most shaded points, so choosing lights by power alone is a poor
strategy here.
"""

import argparse
import json
import math
import os
import random
import sys
import urllib.parse

sys.dont_write_bytecode = True  # leave no tools/__pycache__ behind
from gltfgen import (BufferBuilder, cross, look_along, normalize, quat_axis_angle,  # noqa: E402
                     quat_mul, r6, read_helmet, sub)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUT = os.path.join(ROOT, "scenes", "street")
DEFAULT_ASSETS = os.path.join(ROOT, "assets")
HELMET_DIR = os.path.join("models", "DamagedHelmet")
HELMET_GLTF = "DamagedHelmet.gltf"


# Layout (metres). The street: facades at |x| = FACADE_X, from z = STREET_Z0 down to STREET_Z1;
# the plaza beyond, |x| <= PLAZA_X, down to PLAZA_Z1.
FACADE_X = 9.0
ROAD_X = 5.5             # sidewalks from |x| = ROAD_X to FACADE_X
CURB = 0.12
STREET_Z0, STREET_Z1 = 14.0, -70.0
PLAZA_X, PLAZA_Z1 = 30.0, -105.0
BLOCK_DEPTH = 12.0
HELMET_METALLIC, HELMET_ROUGHNESS = 0.6, 0.35
# The camera looks down the street from 8 m up (a first-floor balcony). From eye height most of
# the wet road is seen at 84-89 degrees from its normal, where glTF's Appendix B dielectric and
# Cycles' Principled BSDF differ most (../shared/cycles/README.md, "Differences that remain" 1):
# there raylab's converged image came out 3 % brighter than Cycles' overall and up to 19 % on
# the far road; from 8 m up, 1 %.
CAMERA_EYE, CAMERA_TARGET = (1.0, 8.0, 14.0), (-0.3, 1.5, -60.0)


# ---------------------------------------------------------------------------------------------
# Materials: (name, base colour (linear), metallic, roughness, emissive colour or None, strength)

MATERIALS = [
    ("wet asphalt", (0.06, 0.06, 0.065), 0.0, 0.3, None, 0),
    ("sidewalk concrete", (0.32, 0.31, 0.29), 0.0, 0.85, None, 0),
    ("plaster white", (0.62, 0.6, 0.55), 0.0, 0.9, None, 0),
    ("brick red", (0.36, 0.12, 0.07), 0.0, 0.85, None, 0),
    ("sandstone", (0.55, 0.42, 0.26), 0.0, 0.9, None, 0),
    ("grey concrete", (0.3, 0.3, 0.31), 0.0, 0.8, None, 0),
    ("ochre plaster", (0.58, 0.38, 0.1), 0.0, 0.9, None, 0),
    ("dark green paint", (0.06, 0.16, 0.1), 0.0, 0.7, None, 0),
    ("window glass", (0.02, 0.022, 0.025), 0.0, 0.15, None, 0),
    ("lamp metal", (0.28, 0.28, 0.3), 1.0, 0.45, None, 0),
    ("plinth stone", (0.45, 0.44, 0.42), 0.0, 0.6, None, 0),
    # emitters (sRGB-free linear factors, each at most 1 as glTF requires)
    ("lamp lens", (0.8, 0.8, 0.8), 0.0, 0.2, (1.0, 0.88, 0.72), 20.0),
    ("lit window", (0.5, 0.5, 0.5), 0.0, 0.5, (1.0, 0.75, 0.45), 0.8),
    ("lit shop window", (0.5, 0.5, 0.5), 0.0, 0.5, (1.0, 0.85, 0.65), 1.5),
    ("sign red", (0.5, 0.5, 0.5), 0.0, 0.5, (1.0, 0.1, 0.15), 6.0),
    ("sign cyan", (0.5, 0.5, 0.5), 0.0, 0.5, (0.1, 0.9, 1.0), 5.0),
    ("sign violet", (0.5, 0.5, 0.5), 0.0, 0.5, (0.6, 0.15, 1.0), 6.0),
    ("bulb warm", (0.8, 0.8, 0.8), 0.0, 0.3, (1.0, 0.72, 0.42), 35.0),
    ("bulb soft white", (0.8, 0.8, 0.8), 0.0, 0.3, (1.0, 0.9, 0.75), 25.0),
    ("bulb cool", (0.8, 0.8, 0.8), 0.0, 0.3, (0.65, 0.8, 1.0), 30.0),
    ("bulb red", (0.8, 0.8, 0.8), 0.0, 0.3, (1.0, 0.12, 0.08), 60.0),
    ("bulb green", (0.8, 0.8, 0.8), 0.0, 0.3, (0.2, 1.0, 0.3), 40.0),
    ("bulb blue", (0.8, 0.8, 0.8), 0.0, 0.3, (0.15, 0.3, 1.0), 80.0),
    ("bulb amber", (0.8, 0.8, 0.8), 0.0, 0.3, (1.0, 0.5, 0.1), 45.0),
    ("bulb pink", (0.8, 0.8, 0.8), 0.0, 0.3, (1.0, 0.35, 0.7), 50.0),
]
MAT = {m[0]: i for i, m in enumerate(MATERIALS)}
FACADES = ["plaster white", "brick red", "sandstone", "grey concrete", "ochre plaster",
           "dark green paint"]
MULTI = ["bulb red", "bulb green", "bulb blue", "bulb amber", "bulb pink"]


# ---------------------------------------------------------------------------------------------
# Geometry, gathered per material (one glTF mesh per material, node transforms identity)

class Batches:
    def __init__(self):
        self.pos = {}
        self.nor = {}
        self.tris = {}
        self.lamps = 0          # emissive objects (bulbs, lenses, signs, lit windows)

    def _get(self, mat):
        if mat not in self.pos:
            self.pos[mat], self.nor[mat], self.tris[mat] = [], [], []
        return self.pos[mat], self.nor[mat], self.tris[mat]

    def quad(self, mat, c, u, v):
        """Rectangle centred at c with edge vectors u and v; front face (CCW) along u x v."""
        pos, nor, tris = self._get(mat)
        n = normalize(cross(u, v))
        base = len(pos)
        for su, sv in ((-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)):
            pos.append(tuple(c[k] + su * u[k] + sv * v[k] for k in range(3)))
            nor.append(n)
        tris += [(base, base + 1, base + 2), (base, base + 2, base + 3)]

    def box(self, mat, lo, hi, skip=()):
        """Axis-aligned box from corner lo to corner hi, outward faces; `skip` names faces to
        leave out ('-y' for a bottom that rests on something)."""
        c = tuple((lo[k] + hi[k]) / 2 for k in range(3))
        s = tuple(hi[k] - lo[k] for k in range(3))
        ex, ey, ez = (s[0], 0, 0), (0, s[1], 0), (0, 0, s[2])
        neg = lambda a: tuple(-x for x in a)  # noqa: E731
        faces = {
            "+x": ((c[0] + s[0] / 2, c[1], c[2]), ey, ez),
            "-x": ((c[0] - s[0] / 2, c[1], c[2]), ez, ey),
            "+y": ((c[0], c[1] + s[1] / 2, c[2]), ez, ex),
            "-y": ((c[0], c[1] - s[1] / 2, c[2]), ex, ez),
            "+z": ((c[0], c[1], c[2] + s[2] / 2), ex, ey),
            "-z": ((c[0], c[1], c[2] - s[2] / 2), neg(ex), ey),
        }
        for name in ("+x", "-x", "+y", "-y", "+z", "-z"):
            if name not in skip:
                centre, u, v = faces[name]
                self.quad(mat, centre, u, v)

    def bulb(self, mat, c, r):
        """Octahedron of radius r at c: 8 outward (CCW) triangles, radial shading normals."""
        pos, nor, tris = self._get(mat)
        base = len(pos)
        dirs = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
        for d in dirs:
            pos.append((c[0] + r * d[0], c[1] + r * d[1], c[2] + r * d[2]))
            nor.append(tuple(float(x) for x in d))
        for sx in (0, 1):
            for sy in (2, 3):
                for sz in (4, 5):
                    a, b, cc = sx, sy, sz
                    n = (dirs[sx][0], dirs[sy][1], dirs[sz][2])
                    if sum(x * y for x, y in zip(cross(sub(dirs[b], dirs[a]),
                                                       sub(dirs[cc], dirs[a])), n)) < 0:
                        b, cc = cc, b
                    tris.append((base + a, base + b, base + cc))
        self.lamps += 1


def uri_from(out_dir, target):
    """Relative URI from out_dir to the file `target`: forward slashes, percent-encoded.
    Real paths (symbolic links resolved), so that the file system resolves each ".." as here."""
    rel = os.path.relpath(os.path.realpath(target), os.path.realpath(out_dir))
    return urllib.parse.quote(rel.replace(os.sep, "/"), safe="/")


def string_points(a, b, sag, spacing):
    """Points every `spacing` metres (about) along a sagging string from a to b (a parabola
    `sag` metres below the chord at its middle), ends excluded."""
    length = math.sqrt(sum((b[k] - a[k]) ** 2 for k in range(3)))
    n = max(1, int(round(length / spacing)))
    out = []
    for i in range(1, n):
        t = i / n
        p = [a[k] + t * (b[k] - a[k]) for k in range(3)]
        p[1] -= 4 * sag * t * (1 - t)
        out.append(tuple(p))
    return out


# ---------------------------------------------------------------------------------------------

def build(out_dir, assets):
    rng = random.Random(30)
    g = Batches()
    spots = []      # (name, position, direction, intensity, colour, inner, outer)
    points = []     # (name, position, intensity, colour)

    # --- ground and sidewalks -------------------------------------------------------------
    gx0, gx1, gz0, gz1 = -60.0, 60.0, PLAZA_Z1 - 20.0, STREET_Z0 + 30.0
    g.quad(MAT["wet asphalt"], ((gx0 + gx1) / 2, 0.0, (gz0 + gz1) / 2),
           (0.0, 0.0, gz1 - gz0), (gx1 - gx0, 0.0, 0.0))
    for side in (-1, 1):
        xa, xb = sorted((side * ROAD_X, side * FACADE_X))
        g.box(MAT["sidewalk concrete"], (xa, 0.0, STREET_Z1), (xb, CURB, STREET_Z0 + 20.0),
              skip=("-y",))

    # --- buildings along the street -------------------------------------------------------
    downlight_spots = []      # candidate (position, side)
    storefront_strings, rooflines = [], []
    for side in (-1, 1):
        z = STREET_Z0 + 20.0
        k = 0
        while z > STREET_Z1 + 1e-6:
            w = min(7.0 + 7.0 * rng.random(), z - STREET_Z1)
            if z - w - STREET_Z1 < 5.0:
                w = z - STREET_Z1
            h = 7.0 + 15.0 * rng.random()
            facade = FACADES[(k * 2 + (side > 0)) % len(FACADES)]
            z0, z1 = z - w, z
            fx = side * FACADE_X
            bx0, bx1 = sorted((fx, side * (PLAZA_X)))
            g.box(MAT[facade], (bx0, 0.0, z0), (bx1, h, z1), skip=("-y",))
            out = -side          # the facade's normal (+x for the left row)
            off = fx + out * 0.02
            # upper windows: dark glass, some lit
            floors = int((h - 5.0) // 3.3)
            cols = max(1, int((w - 1.5) // 2.6))
            for f in range(floors):
                y = 5.2 + 3.3 * f
                for ci in range(cols):
                    zc = z0 + w * (ci + 0.5) / cols
                    lit = rng.random() < 0.2
                    g.quad(MAT["lit window" if lit else "window glass"], (off, y, zc),
                           (0.0, 0.0, -out * 1.2), (0.0, 1.7, 0.0))
                    g.lamps += lit
            # shop windows on the ground floor, signs above them, piers between them
            shops = max(1, int((w - 1.0) // 3.4))
            for si in range(shops):
                zc = z0 + w * (si + 0.5) / shops
                lit = rng.random() < 0.25
                g.quad(MAT["lit shop window" if lit else "window glass"], (off, 1.75, zc),
                       (0.0, 0.0, -out * 2.4), (0.0, 2.3, 0.0))
                g.lamps += lit
                if rng.random() < 0.3:
                    sign = ("sign red", "sign cyan", "sign violet")[int(3 * rng.random())]
                    g.quad(MAT[sign], (fx + out * 0.05, 3.2, zc), (0.0, 0.0, -out * 1.6),
                           (0.0, 0.35, 0.0))
                    g.lamps += 1
                if si > 0:
                    downlight_spots.append(((fx + out * 0.3, 3.3, z0 + w * si / shops), out))
            storefront_strings.append((fx + out * 0.12, 3.7, z0, z1, k))
            rooflines.append((fx + out * 0.1, h - 0.3, z0, z1, k))
            z -= w
            k += 1

    # --- plaza: surrounding buildings --------------------------------------------------------
    plaza_back = []
    for side in (-1, 1):            # side rows, facades at |x| = PLAZA_X facing inward
        bx0, bx1 = sorted((side * PLAZA_X, side * (PLAZA_X + BLOCK_DEPTH)))
        g.box(MAT[FACADES[3 if side < 0 else 0]], (bx0, 0.0, PLAZA_Z1), (bx1, 14.0, STREET_Z1),
              skip=("-y",))
    x = -PLAZA_X
    k = 0
    while x < PLAZA_X - 1e-6:
        w = min(8.0 + 6.0 * rng.random(), PLAZA_X - x)
        if PLAZA_X - x - w < 5.0:
            w = PLAZA_X - x
        h = 10.0 + 12.0 * rng.random()
        g.box(MAT[FACADES[(k + 2) % len(FACADES)]], (x, 0.0, PLAZA_Z1 - BLOCK_DEPTH),
              (x + w, h, PLAZA_Z1), skip=("-y",))
        floors = int((h - 5.0) // 3.3)
        cols = max(1, int((w - 1.5) // 2.6))
        for f in range(floors):
            for ci in range(cols):
                lit = rng.random() < 0.2
                g.quad(MAT["lit window" if lit else "window glass"],
                       (x + w * (ci + 0.5) / cols, 5.2 + 3.3 * f, PLAZA_Z1 + 0.02),
                       (1.2, 0.0, 0.0), (0.0, 1.7, 0.0))
                g.lamps += lit
        plaza_back.append((x, x + w, h, k))
        x += w
        k += 1

    # --- bulbs ----------------------------------------------------------------------------
    bulbs = 0

    def bulb(mat_name, p, r=0.035):
        nonlocal bulbs
        g.bulb(MAT[mat_name], p, r)
        bulbs += 1

    storefront_colours = ["bulb warm", "bulb soft white", "bulb cool", "bulb amber"]
    roof_colours = ["bulb warm", "bulb cool", "bulb blue", "bulb soft white"]
    spacing = 0.45
    for (xf, y, z0, z1, k) in storefront_strings:
        n = int((z1 - z0) / spacing)
        colour = storefront_colours[(k + int(xf > 0)) % 4]
        for i in range(n):
            zz = z0 + (i + 0.5) * (z1 - z0) / n
            if zz < STREET_Z0 + 2.0:         # none behind the camera
                bulb(colour, (xf, y, zz))
    for (xf, y, z0, z1, k) in rooflines:
        n = int((z1 - z0) / spacing)
        colour = roof_colours[(k + 2 * int(xf > 0)) % 4]
        for i in range(n):
            zz = z0 + (i + 0.5) * (z1 - z0) / n
            if zz < STREET_Z0 + 2.0:
                bulb(colour, (xf, y, zz))
    for (x0, x1, h, k) in plaza_back:
        for y, colours in ((3.7, storefront_colours), (h - 0.3, roof_colours)):
            n = int((x1 - x0) / spacing)
            for i in range(n):
                bulb(colours[k % 4], (x0 + (i + 0.5) * (x1 - x0) / n, y, PLAZA_Z1 + 0.12))

    # festoons: zig-zag strings across the street, 7 m up, sagging 1 m
    for s in range(15):
        za = 8.0 - 5.0 * s
        a, b = (-FACADE_X + 0.1, 7.0, za), (FACADE_X - 0.1, 7.0, za - 5.0)
        if s % 2:
            a, b = (FACADE_X - 0.1, 7.0, za), (-FACADE_X + 0.1, 7.0, za - 5.0)
        for i, p in enumerate(string_points(a, b, 1.0, 0.55)):
            bulb("bulb warm" if s % 2 == 0 else MULTI[i % len(MULTI)], p, 0.04)

    # maypole: 16 strings from the top of a 13 m mast to posts 11 m away, 3 m up
    mast = (0.0, 0.0, -90.0)
    g.box(MAT["lamp metal"], (mast[0] - 0.12, 0.0, mast[2] - 0.12),
          (mast[0] + 0.12, 13.2, mast[2] + 0.12), skip=("-y",))
    top = (mast[0], 13.0, mast[2])
    for s in range(16):
        a = 2 * math.pi * (s + 0.5) / 16
        post = (mast[0] + 11.0 * math.sin(a), 3.0, mast[2] + 11.0 * math.cos(a))
        g.box(MAT["lamp metal"], (post[0] - 0.06, 0.0, post[2] - 0.06),
              (post[0] + 0.06, 3.05, post[2] + 0.06), skip=("-y",))
        for i, p in enumerate(string_points(top, post, 0.6, 0.6)):
            bulb(MULTI[(s + i) % len(MULTI)] if s % 2 else "bulb warm", p, 0.04)

    # --- street lamps: post, arm, head, emissive lens, spot light ------------------------------
    for side in (-1, 1):
        for i in range(10):
            z = 6.0 - 8.0 * i - (4.0 if side > 0 else 0.0)
            px = side * (ROAD_X + 0.4)
            ax = side * (ROAD_X - 0.7)          # the head's centre, over the road
            g.box(MAT["lamp metal"], (px - 0.07, CURB, z - 0.07), (px + 0.07, 6.3, z + 0.07),
                  skip=("-y",))
            lo_x, hi_x = sorted((px, ax))
            g.box(MAT["lamp metal"], (lo_x - 0.05, 6.2, z - 0.05), (hi_x + 0.05, 6.3, z + 0.05))
            g.box(MAT["lamp metal"], (ax - 0.3, 6.05, z - 0.18), (ax + 0.3, 6.2, z + 0.18),
                  skip=("-y",))
            g.quad(MAT["lamp lens"], (ax, 6.05, z), (0.6, 0.0, 0.0), (0.0, 0.0, 0.36))
            g.lamps += 1
            spots.append(("street lamp %d" % len(spots), (ax, 6.0, z),
                          normalize((-side * 0.25, -1.0, 0.0)), 200.0, (1.0, 0.88, 0.72),
                          0.6, 0.95))

    # --- facade downlights over the shop doors: 30 of the candidates, evenly -------------------
    n_down = 30
    picks = [downlight_spots[int((i + 0.5) * len(downlight_spots) / n_down)]
             for i in range(n_down)]
    for (p, out) in picks:
        spots.append(("downlight %d" % len(spots), p, normalize((out * 0.35, -1.0, 0.0)), 25.0,
                      (1.0, 0.8, 0.55), 0.35, 0.6))

    # --- plaza lanterns (point lights on posts) ----------------------------------------------
    for name, (x, z) in (("lantern west", (-12.0, -80.0)), ("lantern east", (12.0, -97.0))):
        g.box(MAT["lamp metal"], (x - 0.08, 0.0, z - 0.08), (x + 0.08, 4.2, z + 0.08),
              skip=("-y",))
        points.append((name, (x, 4.5, z), 40.0, (1.0, 0.78, 0.5)))

    # --- helmets ---------------------------------------------------------------------------
    helmet_dir = os.path.join(assets, HELMET_DIR)
    helmet, hbin, hprim, helmet_tris = read_helmet(os.path.join(helmet_dir, HELMET_GLTF))
    hbuf = helmet["buffers"][0]
    helmet_rot = tuple(helmet["nodes"][0].get("rotation", (0.0, 0.0, 0.0, 1.0)))
    # (x, z, scale, yaw in degrees, base height); the helmet reaches 0.901 below its centre
    plinth = (-7.0, -82.0)
    g.box(MAT["plinth stone"], (plinth[0] - 1.2, 0.0, plinth[1] - 1.2),
          (plinth[0] + 1.2, 1.0, plinth[1] + 1.2), skip=("-y",))
    helmet_places = [(-2.6, -3.0, 0.75, 20.0, 0.0), (3.2, -15.0, 0.75, -35.0, 0.0),
                     (-1.2, -28.0, 0.75, 10.0, 0.0), (2.4, -44.0, 0.75, -15.0, 0.0),
                     (plinth[0], plinth[1], 1.4, 25.0, 1.0)]

    # --- assemble ---------------------------------------------------------------------------
    b = BufferBuilder()
    materials = []
    for (name, base, metallic, rough, emissive, strength) in MATERIALS:
        m = {"name": name,
             "pbrMetallicRoughness": {"baseColorFactor": list(base) + [1.0],
                                      "metallicFactor": metallic, "roughnessFactor": rough}}
        if emissive:
            m["emissiveFactor"] = list(emissive)
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
        materials.append(m)
    meshes, nodes = [], []
    tri_total = emit_tris = 0
    for mat in sorted(g.pos):
        pos, nor, tris = g.pos[mat], g.nor[mat], g.tris[mat]
        attrs = {"POSITION": b.floats(pos, "VEC3", with_bounds=True),
                 "NORMAL": b.floats(nor, "VEC3")}
        idx = b.indices(tris, len(pos))
        meshes.append({"name": MATERIALS[mat][0],
                       "primitives": [{"attributes": attrs, "indices": idx, "material": mat,
                                       "mode": 4}]})
        nodes.append({"name": MATERIALS[mat][0], "mesh": len(meshes) - 1})
        tri_total += len(tris)
        if MATERIALS[mat][4]:
            emit_tris += len(tris)
    while len(b.bin) % 4:
        b.bin.append(0)

    # the helmet: its accessors and buffer views appended, on buffer 1
    acc0, view0 = len(b.accessors), len(b.views)
    for v in helmet["bufferViews"]:
        v = dict(v)
        v["buffer"] = 1
        b.views.append(v)
    for a in helmet["accessors"]:
        a = dict(a)
        a["bufferView"] += view0
        b.accessors.append(a)
    images = [{"uri": uri_from(out_dir, os.path.join(helmet_dir, urllib.parse.unquote(im["uri"]))),
               "mimeType": "image/jpeg"} for im in helmet["images"]]
    textures = [{"sampler": 0, "source": t["source"]} for t in helmet["textures"]]
    # The helmet's material without its metallic-roughness map: that map has roughness 0 on
    # about 1 % of its texels (6.7 % below 0.02), near-mirror metal that turns the 52 punctual
    # lights into glints of a few texels: rare, huge samples for raylab (alpha >= 1e-4) and none
    # at all for Cycles (alpha 0 is a singular BSDF that a delta light cannot reach).
    hmat = json.loads(json.dumps(helmet["materials"][0]))
    hmat["name"] = "DamagedHelmet, uniform metallic 0.6, roughness 0.35"
    pbr = hmat.setdefault("pbrMetallicRoughness", {})
    pbr.pop("metallicRoughnessTexture", None)
    pbr["metallicFactor"], pbr["roughnessFactor"] = HELMET_METALLIC, HELMET_ROUGHNESS
    materials.append(hmat)
    meshes.append({"name": "DamagedHelmet", "primitives": [{
        "attributes": {k: v + acc0 for k, v in hprim["attributes"].items()},
        "indices": hprim["indices"] + acc0, "material": len(materials) - 1, "mode": 4}]})
    for i, (x, z, s, yaw, base) in enumerate(helmet_places):
        q = quat_mul(quat_axis_angle((0, 1, 0), math.radians(yaw)), helmet_rot)
        nodes.append({"name": "helmet %d" % i, "mesh": len(meshes) - 1,
                      "translation": r6((x, base + 0.901 * s, z)), "rotation": r6(q),
                      "scale": r6((s, s, s))})
        tri_total += helmet_tris

    lights = []
    for (name, p, d, inten, colour, inner, outer) in spots:
        nodes.append({"name": name, "translation": r6(p),
                      "rotation": r6(look_along(d, up=(0.0, 0.0, -1.0))),
                      "extensions": {"KHR_lights_punctual": {"light": len(lights)}}})
        lights.append({"name": name, "type": "spot", "color": list(colour), "intensity": inten,
                       "spot": {"innerConeAngle": inner, "outerConeAngle": outer}})
    for (name, p, inten, colour) in points:
        nodes.append({"name": name, "translation": r6(p),
                      "extensions": {"KHR_lights_punctual": {"light": len(lights)}}})
        lights.append({"name": name, "type": "point", "color": list(colour), "intensity": inten})

    eye, target = CAMERA_EYE, CAMERA_TARGET
    nodes.append({"name": "camera", "camera": 0, "translation": r6(eye),
                  "rotation": r6(look_along(sub(target, eye)))})

    gltf = {
        "asset": {"version": "2.0", "generator": "raylab tools/make_street.py",
                  "copyright": "street: raylab contributors, CC0; DamagedHelmet: theblueturtle_, "
                               "CC BY 4.0 (see assets/README.md)"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": "street", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"name": "street camera", "type": "perspective",
                     "perspective": {"yfov": 0.85, "aspectRatio": 4.0 / 3.0, "znear": 0.05,
                                     "zfar": 500.0}}],
        "meshes": meshes,
        "materials": materials,
        "textures": textures,
        "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}],
        "images": images,
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"uri": "street.bin", "byteLength": len(b.bin)},
                    {"uri": uri_from(out_dir, hbin), "byteLength": hbuf["byteLength"]}],
    }

    os.makedirs(out_dir, exist_ok=True)
    files = {"street.gltf": (json.dumps(gltf, indent=1) + "\n").encode(),
             "street.bin": bytes(b.bin)}
    for name, data in files.items():
        with open(os.path.join(out_dir, name), "wb") as f:
            f.write(data)
    for name in sorted(files):
        print("%-12s %9d bytes" % (os.path.join(out_dir, name), len(files[name])))
    print("%d triangles (%d in %d helmets), %d of them emissive glTF material triangles "
          "outside the helmets; %d lamps (%d bulbs, %d other emissive quads); %d spot and %d "
          "point lights" % (tri_total, len(helmet_places) * helmet_tris, len(helmet_places),
                            emit_tris, g.lamps, bulbs, g.lamps - bulbs, len(spots),
                            len(points)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir", metavar="OUT_DIR", nargs="?", default=DEFAULT_OUT)
    ap.add_argument("--assets", default=DEFAULT_ASSETS,
                    help="the folder holding models/DamagedHelmet (default: the repository's assets/, %(default)s)")
    a = ap.parse_args()
    build(a.out_dir, a.assets)


if __name__ == "__main__":
    main()
