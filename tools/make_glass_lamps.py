#!/usr/bin/env python3
"""Writes scenes/glass-lamps/glass-lamps.gltf: small bright lamps inside glass shades on a table
with a high-frequency texture, a scene made to fool a denoiser's blend (issue 42).

Usage (from the project folder):

    python3 tools/make_glass_lamps.py [OUT_DIR]

OUT_DIR defaults to scenes/glass-lamps beside this tools/ folder. It writes glass-lamps.gltf,
glass-lamps.bin and glass-lamps-mosaic.png there (about 120 kB together). Standard library only;
the output is the same bytes on every run.

The scene, in glTF units (metres, +y up; the table top at y = 0), follows
docs/scene-conventions.md (radiometric light units, one-sided emission):

- a closed room (walls, floor and ceiling Lambertian: KHR_materials_specular specularFactor 0)
  around a table (1.6 m × 1.25 m) whose Lambertian top carries a 512 × 512 mosaic texture
  (glass-lamps-mosaic.png: a checker of 4-texel tiles, each tile's colour and brightness drawn
  at random, dark 1-texel grout lines every 32 texels; repeated once per metre across and 0.6
  times per metre in depth, so that at 320 × 240 a period of the checker covers about 3-4
  pixels): a denoiser that blurs it loses detail everywhere, and its albedo guide is all that
  tells texture from noise;
- three glass lamps on the table: hollow tubes of clear glass (index 1.5, KHR_materials_volume:
  a closed solid between a 7.5 cm outer and a 6.8 cm inner radius, 30 cm tall, open at the top)
  around a small emissive sphere (3 cm radius, one-sided, emissiveFactor x
  KHR_materials_emissive_strength 8 to 11: warm, cool and amber). Their light reaches the
  table only through the glass: caustic paths that a path tracer finds by BSDF sampling alone
  (its shadow rays stop at the glass), rare and bright samples; through the open tops the
  spheres light the ceiling directly;
- a pane of glass (2.5 cm thick, a closed solid of index 1.5) standing on the table in front of
  the middle lamp, turned 30 degrees, through which the camera sees the texture shifted and the
  lamp;
- two KHR_lights_punctual point lights outside the glass (a warm key light 1.15 m above the
  table, 4.5 W/sr, and a dim cool fill light, 1.2 W/sr), so that the whole texture is also lit
  directly. They are kept well away from walls and ceiling: a point light close to a wall makes
  a small bright spot there that the rest of the room sees as fireflies. The glass casts dark
  shadows in their light, in both renderers: light from a point through smooth glass is a
  caustic that no path tracer's path can reach;
- one perspective camera (yfov 0.75, aspectRatio 4/3, default render size 800 x 600) looking
  down at the table from 1.5 m away; the table fills most of the image, the wall a strip above.

The noise is where the lamps' light is: around them on the table (caustics) and in the glass,
and in sparse fireflies on the wall; the texture elsewhere is lit directly. At 320 x 240 and 16
spp raylab's clamped relMSE against a converged render is about 8e-2, most of it near the lamps.
Each lamp shows its sphere twice: through the tube's front wall (below), and mirrored by its
back wall (above: the Fresnel reflections of the wall's two surfaces, about 8 % together, so
dimmer and less white after tone mapping). 2,180 triangles. Own work, CC0.
"""

import json
import math
import os
import random
import sys

sys.dont_write_bytecode = True  # leave no tools/__pycache__ behind
from gltfgen import BufferBuilder, cross, look_along, normalize, png_bytes, r6, sub  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUT = os.path.join(ROOT, "scenes", "glass-lamps")
NAME = "glass-lamps"
TEXTURE = NAME + "-mosaic.png"
TEX_SIZE = 512
TILE = 4            # texels per checker tile (a period is 2 tiles)
GROUT = 32          # a dark 1-texel grout line every GROUT texels
UV_PER_METRE = (1.0, 0.6)   # texture repeats per metre along x and z on the table top

# Layout (metres): the table top is x in [-TABLE_X, TABLE_X], z in [TABLE_Z0, TABLE_Z1], y = 0.
TABLE_X, TABLE_Z0, TABLE_Z1, TABLE_T = 0.8, -0.8, 0.45, 0.04
FLOOR_Y, CEILING_Y = -0.75, 1.85
ROOM_X, ROOM_Z0, ROOM_Z1 = 2.0, -2.2, 2.4
LIFT = 0.001        # glass rests this far above the table (no coincident faces)
TUBE_R_OUT, TUBE_R_IN, TUBE_H, TUBE_SEG = 0.075, 0.068, 0.3, 48
BULB_R, BULB_Y = 0.03, 0.12
# (x, z, emissive colour, strength)
LAMPS = [(-0.42, -0.12, (1.0, 0.78, 0.5), 9.0),
         (0.06, -0.3, (0.7, 0.85, 1.0), 11.0),
         (0.48, 0.04, (1.0, 0.6, 0.25), 8.0)]
PANE_C, PANE_W, PANE_H, PANE_T, PANE_YAW = (0.0, -0.06), 0.36, 0.24, 0.025, 30.0
# (name, position, intensity W/sr, colour)
POINTS = [("key lamp", (0.55, 1.15, 0.7), 4.5, (1.0, 0.9, 0.75)),
          ("fill lamp", (-1.2, 0.9, 1.0), 1.2, (0.75, 0.85, 1.0))]
CAMERA_EYE, CAMERA_TARGET, CAMERA_YFOV = (0.0, 0.95, 0.95), (0.0, -0.05, -0.2), 0.75


# ---------------------------------------------------------------------------------------------
# The texture


def srgb8(x):
    """Linear [0, 1] -> 8-bit sRGB."""
    x = min(1.0, max(0.0, x))
    s = 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055
    return int(round(255 * s))


def mosaic():
    """The table's texture, RGB rows top first: a checker of TILE-texel tiles, light and dark
    tiles each with a random colour and brightness, and dark grout lines every GROUT texels."""
    rng = random.Random(42)
    n = TEX_SIZE // TILE
    light = [(0.62, 0.52, 0.36), (0.7, 0.64, 0.5), (0.55, 0.58, 0.6), (0.66, 0.45, 0.3)]
    dark = [(0.09, 0.05, 0.035), (0.14, 0.06, 0.04), (0.05, 0.07, 0.1), (0.12, 0.1, 0.07)]
    tiles = []
    for j in range(n):
        row = []
        for i in range(n):
            palette = light if (i + j) % 2 == 0 else dark
            c = palette[int(rng.random() * len(palette))]
            k = 0.65 + 0.35 * rng.random()
            row.append(bytes(srgb8(k * x) for x in c))
        tiles.append(row)
    grout = bytes(srgb8(x) for x in (0.02, 0.018, 0.015))
    rows = []
    for y in range(TEX_SIZE):
        if y % GROUT == 0:
            rows.append(grout * TEX_SIZE)
            continue
        tj = tiles[y // TILE]
        rows.append(b"".join(grout if x % GROUT == 0 else tj[x // TILE] for x in range(TEX_SIZE)))
    return png_bytes(TEX_SIZE, TEX_SIZE, rows)


# ---------------------------------------------------------------------------------------------
# Geometry, gathered per material (one glTF mesh per material, node transforms identity)


class Batches:
    def __init__(self):
        self.pos, self.nor, self.uv, self.tris = {}, {}, {}, {}

    def _get(self, mat):
        if mat not in self.pos:
            self.pos[mat], self.nor[mat], self.uv[mat], self.tris[mat] = [], [], [], []
        return self.pos[mat], self.nor[mat], self.uv[mat], self.tris[mat]

    def vertex(self, mat, p, n, uv=(0.0, 0.0)):
        pos, nor, uvs, _ = self._get(mat)
        pos.append(tuple(p))
        nor.append(tuple(n))
        uvs.append(tuple(uv))
        return len(pos) - 1

    def tri(self, mat, a, b, c):
        self._get(mat)[3].append((a, b, c))

    def quad(self, mat, c, u, v, uv=None):
        """Rectangle centred at c with edge vectors u and v; front face (CCW) along u x v.
        uv: a function of the corner's position giving its texture coordinate."""
        n = normalize(cross(u, v))
        idx = []
        for su, sv in ((-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)):
            p = tuple(c[k] + su * u[k] + sv * v[k] for k in range(3))
            idx.append(self.vertex(mat, p, n, uv(p) if uv else (0.0, 0.0)))
        self.tri(mat, idx[0], idx[1], idx[2])
        self.tri(mat, idx[0], idx[2], idx[3])

    def meshes(self, b, materials):
        """One mesh and node per material, in material order, into BufferBuilder `b` (texture
        coordinates where the material has a base colour texture; the buffer padded to 4
        bytes): the meshes, the nodes and the number of triangles."""
        meshes, nodes = [], []
        tri_total = 0
        for m in sorted(self.pos):
            pos, nor, uv, tris = self.pos[m], self.nor[m], self.uv[m], self.tris[m]
            attrs = {"POSITION": b.floats(pos, "VEC3", with_bounds=True),
                     "NORMAL": b.floats(nor, "VEC3")}
            if "baseColorTexture" in materials[m]["pbrMetallicRoughness"]:
                attrs["TEXCOORD_0"] = b.floats(uv, "VEC2")
            idx = b.indices(tris, len(pos))
            meshes.append({"name": materials[m]["name"],
                           "primitives": [{"attributes": attrs, "indices": idx, "material": m,
                                           "mode": 4}]})
            nodes.append({"name": materials[m]["name"], "mesh": len(meshes) - 1})
            tri_total += len(tris)
        while len(b.bin) % 4:
            b.bin.append(0)
        return meshes, nodes, tri_total

    def box(self, mat, lo, hi, skip=(), inward=False):
        """Axis-aligned box from corner lo to corner hi; faces outward (inward: towards the
        inside, for a room). `skip` names faces to leave out ('+y', ...)."""
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
            if name in skip:
                continue
            centre, u, v = faces[name]
            if inward:
                u, v = v, u
            self.quad(mat, centre, u, v)

    def tube(self, mat, x, z, y0, r_out, r_in, h, seg):
        """A closed solid between two coaxial cylinders (vertical axis through x, z; from y0 to
        y0 + h), faces pointing out of the solid: the outer wall away from the axis, the inner
        wall towards it, the annuli at both ends up and down. Smooth normals on the walls."""
        ring = [(math.cos(2 * math.pi * k / seg), math.sin(2 * math.pi * k / seg))
                for k in range(seg)]
        y1 = y0 + h

        def wall(r, sign):
            lo = [self.vertex(mat, (x + r * c, y0, z + r * s), (sign * c, 0.0, sign * s))
                  for c, s in ring]
            hi = [self.vertex(mat, (x + r * c, y1, z + r * s), (sign * c, 0.0, sign * s))
                  for c, s in ring]
            for k in range(seg):
                k1 = (k + 1) % seg
                # going round k -> k1 is counter-clockwise seen from +y; the outer wall's front
                # (outward) face is then (lo k, hi k, hi k1)
                if sign > 0:
                    self.tri(mat, lo[k], hi[k], hi[k1])
                    self.tri(mat, lo[k], hi[k1], lo[k1])
                else:
                    self.tri(mat, lo[k], hi[k1], hi[k])
                    self.tri(mat, lo[k], lo[k1], hi[k1])

        def annulus(y, up):
            n = (0.0, 1.0 if up else -1.0, 0.0)
            o = [self.vertex(mat, (x + r_out * c, y, z + r_out * s), n) for c, s in ring]
            i = [self.vertex(mat, (x + r_in * c, y, z + r_in * s), n) for c, s in ring]
            for k in range(seg):
                k1 = (k + 1) % seg
                if up:
                    self.tri(mat, o[k], i[k], i[k1])
                    self.tri(mat, o[k], i[k1], o[k1])
                else:
                    self.tri(mat, o[k], i[k1], i[k])
                    self.tri(mat, o[k], o[k1], i[k1])

        wall(r_out, 1.0)
        wall(r_in, -1.0)
        annulus(y1, True)
        annulus(y0, False)

    def sphere(self, mat, c, r, level=2):
        """Icosphere (20 x 4^level outward triangles), smooth radial normals."""
        t = (1 + math.sqrt(5)) / 2
        verts = [normalize(v) for v in [
            (-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
            (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]]
        faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9),
                 (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2),
                 (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
                 (8, 6, 7), (9, 8, 1)]
        for _ in range(level):
            mid = {}

            def midpoint(a, b):
                key = (min(a, b), max(a, b))
                if key not in mid:
                    verts.append(normalize(tuple((verts[a][k] + verts[b][k]) / 2
                                                 for k in range(3))))
                    mid[key] = len(verts) - 1
                return mid[key]

            new = []
            for a, b, cc in faces:
                ab, bc, ca = midpoint(a, b), midpoint(b, cc), midpoint(cc, a)
                new += [(a, ab, ca), (b, bc, ab), (cc, ca, bc), (ab, bc, ca)]
            faces = new
        idx = [self.vertex(mat, tuple(c[k] + r * v[k] for k in range(3)), v) for v in verts]
        for a, b, cc in faces:
            self.tri(mat, idx[a], idx[b], idx[cc])


# ---------------------------------------------------------------------------------------------

def build(out_dir):
    lambert = {"KHR_materials_specular": {"specularFactor": 0.0}}
    glass_ext = {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                 "KHR_materials_ior": {"ior": 1.5},
                 "KHR_materials_volume": {"thicknessFactor": 0.01}}

    def pbr(colour, metallic=0.0, rough=1.0):
        return {"baseColorFactor": list(colour) + [1.0], "metallicFactor": metallic,
                "roughnessFactor": rough}

    materials = [
        {"name": "walls", "pbrMetallicRoughness": pbr((0.5, 0.48, 0.45)),
         "extensions": dict(lambert)},
        {"name": "ceiling", "pbrMetallicRoughness": pbr((0.75, 0.75, 0.75)),
         "extensions": dict(lambert)},
        {"name": "floor", "pbrMetallicRoughness": pbr((0.22, 0.2, 0.18)),
         "extensions": dict(lambert)},
        {"name": "table wood", "pbrMetallicRoughness": pbr((0.25, 0.12, 0.06), rough=0.6)},
        {"name": "table top: mosaic",
         "pbrMetallicRoughness": dict(pbr((1.0, 1.0, 1.0)), baseColorTexture={"index": 0}),
         "extensions": dict(lambert)},
        {"name": "glass 1.5", "pbrMetallicRoughness": pbr((1.0, 1.0, 1.0), rough=0.0),
         "extensions": dict(glass_ext)},
    ]
    mat = {m["name"]: i for i, m in enumerate(materials)}
    bulb_mats = []
    for k, (_, _, colour, strength) in enumerate(LAMPS):
        bulb_mats.append(len(materials))
        materials.append({"name": "bulb %d" % k, "pbrMetallicRoughness": pbr((0.0, 0.0, 0.0)),
                          "emissiveFactor": list(colour),
                          "extensions": dict(lambert, KHR_materials_emissive_strength={
                              "emissiveStrength": strength})})

    g = Batches()
    # the room, faces inward; the table (top textured), four legs
    g.box(mat["walls"], (-ROOM_X, FLOOR_Y, ROOM_Z0), (ROOM_X, CEILING_Y, ROOM_Z1),
          skip=("+y", "-y"), inward=True)
    g.quad(mat["ceiling"], (0.0, CEILING_Y, (ROOM_Z0 + ROOM_Z1) / 2),
           (2 * ROOM_X, 0.0, 0.0), (0.0, 0.0, ROOM_Z1 - ROOM_Z0))
    g.quad(mat["floor"], (0.0, FLOOR_Y, (ROOM_Z0 + ROOM_Z1) / 2),
           (0.0, 0.0, ROOM_Z1 - ROOM_Z0), (2 * ROOM_X, 0.0, 0.0))

    def top_uv(p):
        return (p[0] * UV_PER_METRE[0], p[2] * UV_PER_METRE[1])

    g.box(mat["table wood"], (-TABLE_X, -TABLE_T, TABLE_Z0), (TABLE_X, 0.0, TABLE_Z1), skip=("+y",))
    g.quad(mat["table top: mosaic"], (0.0, 0.0, (TABLE_Z0 + TABLE_Z1) / 2),
           (0.0, 0.0, TABLE_Z1 - TABLE_Z0), (2 * TABLE_X, 0.0, 0.0),
           uv=top_uv)
    for sx in (-1, 1):
        for sz in (-1, 1):
            x = sx * (TABLE_X - 0.08)
            z = (TABLE_Z0 + 0.08) if sz < 0 else (TABLE_Z1 - 0.08)
            g.box(mat["table wood"], (x - 0.025, FLOOR_Y, z - 0.025),
                  (x + 0.025, -TABLE_T, z + 0.025), skip=("+y", "-y"))

    # the lamps: glass tubes around emissive spheres
    for k, (x, z, _, _) in enumerate(LAMPS):
        g.tube(mat["glass 1.5"], x, z, LIFT, TUBE_R_OUT, TUBE_R_IN, TUBE_H, TUBE_SEG)
        g.sphere(bulb_mats[k], (x, BULB_Y, z), BULB_R)

    # the pane: a thin box turned about +y
    yaw = math.radians(PANE_YAW)
    ux, uz = math.cos(yaw), -math.sin(yaw)          # along the pane's width
    nx, nz = math.sin(yaw), math.cos(yaw)           # its normal (towards the camera)
    cx, cz = PANE_C
    cy = LIFT + PANE_H / 2
    w = (PANE_W * ux, 0.0, PANE_W * uz)
    hgt = (0.0, PANE_H, 0.0)
    t = (PANE_T * nx, 0.0, PANE_T * nz)
    half = lambda v, s: tuple(s * x / 2 for x in v)  # noqa: E731
    add = lambda a, b: tuple(x + y for x, y in zip(a, b))  # noqa: E731
    c = (cx, cy, cz)
    neg = lambda a: tuple(-x for x in a)  # noqa: E731
    for centre, u, v in ((add(c, half(t, 1)), w, hgt), (add(c, half(t, -1)), neg(w), hgt),
                         (add(c, half(w, 1)), neg(t), hgt), (add(c, half(w, -1)), t, hgt),
                         (add(c, half(hgt, 1)), t, w), (add(c, half(hgt, -1)), w, t)):
        g.quad(mat["glass 1.5"], centre, u, v)

    # --- assemble ---------------------------------------------------------------------------
    b = BufferBuilder()
    meshes, nodes, tri_total = g.meshes(b, materials)

    lights = []
    for (name, p, inten, colour) in POINTS:
        nodes.append({"name": name, "translation": r6(p),
                      "extensions": {"KHR_lights_punctual": {"light": len(lights)}}})
        lights.append({"name": name, "type": "point", "color": list(colour), "intensity": inten})

    eye, target = CAMERA_EYE, CAMERA_TARGET
    nodes.append({"name": "camera", "camera": 0, "translation": r6(eye),
                  "rotation": r6(look_along(sub(target, eye)))})

    gltf = {
        "asset": {"version": "2.0", "generator": "raylab tools/make_glass_lamps.py",
                  "copyright": "raylab contributors, CC0"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength",
                           "KHR_materials_ior", "KHR_materials_specular",
                           "KHR_materials_transmission", "KHR_materials_volume"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": NAME, "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"name": "camera", "type": "perspective",
                     "perspective": {"yfov": CAMERA_YFOV, "aspectRatio": 4.0 / 3.0,
                                     "znear": 0.01, "zfar": 50.0}}],
        "meshes": meshes,
        "materials": materials,
        "textures": [{"sampler": 0, "source": 0}],
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497}],
        "images": [{"uri": TEXTURE, "mimeType": "image/png"}],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"uri": NAME + ".bin", "byteLength": len(b.bin)}],
    }

    os.makedirs(out_dir, exist_ok=True)
    files = {NAME + ".gltf": (json.dumps(gltf, indent=1) + "\n").encode(),
             NAME + ".bin": bytes(b.bin), TEXTURE: mosaic()}
    for name, data in files.items():
        with open(os.path.join(out_dir, name), "wb") as f:
            f.write(data)
    for name in sorted(files):
        print("%-28s %7d bytes" % (name, len(files[name])))
    print("%d triangles in %d meshes; %d emissive spheres in glass tubes, a glass pane, %d point "
          "lights; texture %d x %d" % (tri_total, len(meshes), len(LAMPS), len(POINTS),
                                       TEX_SIZE, TEX_SIZE))


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else DEFAULT_OUT
    if out_dir in ("-h", "--help"):
        print(__doc__)
        return
    build(out_dir)


if __name__ == "__main__":
    main()
