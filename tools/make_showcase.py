#!/usr/bin/env python3
"""Writes the showcase glTF 2.0 scene: glass, metals, textures, instancing, lights.

Usage (from the project folder):

    python3 tools/make_showcase.py [OUT_DIR]

OUT_DIR defaults to scenes/showcase beside this tools/ folder. It writes showcase.gltf,
showcase.bin and five PNG textures there. Standard library only; the output is the same bytes
on every run.

The scene, in glTF units (metres, +y up), follows docs/scene-conventions.md:

- a tiled floor (two triangles, UVs repeated, REPEAT sampler; procedural base-colour PNG and a
  metallic-roughness PNG whose roughness changes from tile to tile) ending in a curved
  backdrop (a quarter-cylinder sweep into a back wall) so reflections have something to show;
- UV spheres (64 x 32 segments, one set of accessors shared by four meshes, sized by node
  scale): polished gold, rough aluminium, clear glass (KHR_materials_transmission + ior +
  volume with a faint blue attenuation) and a textured dielectric with a dimpled tangent-space
  normal map and no TANGENT attribute (the renderer must make MikkTSpace tangents);
- one torus mesh instanced by two nodes under a common parent: one lying on the floor, one
  standing, turned by a quaternion and scaled non-uniformly;
- an emissive "light panel" (a thin box standing at the back right, emissiveFactor (1, 0.9, 0.8)
  x KHR_materials_emissive_strength 8) and a dim emissive softbox (the same box scaled, strength
  1.5) overhead, out of view, that the metals and the glass reflect;
- KHR_lights_punctual: a spot light (key), a directional light (rim, from behind right) and a
  weak point light (fill); intensities are radiometric (W/sr, W/m^2) as the conventions say;
- one perspective camera, aspectRatio 1.5 (default render size 900 x 600), placed by a
  look-at quaternion.
"""

import json
import math
import os
import struct
import sys

from gltfgen import BufferBuilder, dot, look_along, normalize, png_bytes, quat_axis_angle, quat_mul, r6, sub

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUT = os.path.join(ROOT, "scenes", "showcase")

REPEAT, CLAMP_TO_EDGE = 10497, 33071
LINEAR, LINEAR_MIPMAP_LINEAR = 9729, 9987


# ---------------------------------------------------------------------------------------------
# PNG writing (8-bit RGB or RGBA, filter 0 on every row)





def to_byte(x):
    """[0, 1] -> 0..255, rounded and clamped."""
    return max(0, min(255, int(x * 255.0 + 0.5)))


def srgb_encode(linear):
    """Linear [0, 1] -> sRGB-encoded [0, 1] (for base colour texels chosen in linear terms)."""
    linear = max(0.0, min(1.0, linear))
    if linear <= 0.0031308:
        return 12.92 * linear
    return 1.055 * linear ** (1.0 / 2.4) - 0.055


def hash01(*ints):
    """A deterministic pseudo-random number in [0, 1) from integers (no global random state)."""
    h = 2166136261
    for v in ints:
        for b in struct.pack("<i", v):
            h = ((h ^ b) * 16777619) & 0xFFFFFFFF
    h ^= h >> 13
    h = (h * 0x5BD1E995) & 0xFFFFFFFF
    h ^= h >> 15
    return h / 4294967296.0


# ---------------------------------------------------------------------------------------------
# Textures

FLOOR_SIZE = 512          # floor textures: 512 x 512, 4 x 4 tiles of 128 px
FLOOR_TILES = 4
GROUT = 5                 # grout line half-width in texels


def floor_tile(px, py):
    """(tile column, tile row, in the grout?) for a floor texel."""
    cell = FLOOR_SIZE // FLOOR_TILES
    tx, ty = px // cell, py // cell
    lx, ly = px % cell, py % cell
    grout = min(lx, cell - 1 - lx) < GROUT or min(ly, cell - 1 - ly) < GROUT
    return tx, ty, grout


def floor_textures():
    """Base colour (sRGB) and metallic-roughness (linear: G roughness, B metallic) of the floor."""
    light = (0.62, 0.57, 0.50)      # warm stone, linear
    dark = (0.13, 0.14, 0.16)       # slate, linear
    grout_colour = (0.20, 0.19, 0.18)
    cell = FLOOR_SIZE // FLOOR_TILES
    base_rows, mr_rows = [], []
    for py in range(FLOOR_SIZE):
        base = bytearray(FLOOR_SIZE * 3)
        mr = bytearray(FLOOR_SIZE * 3)
        for px in range(FLOOR_SIZE):
            tx, ty, grout = floor_tile(px, py)
            if grout:
                colour, rough = grout_colour, 0.9
            else:
                colour = light if (tx + ty) % 2 == 0 else dark
                # each tile a little lighter or darker, with a soft diagonal sheen of grain
                shade = 0.9 + 0.2 * hash01(tx, ty, 1)
                grain = 1.0 + 0.05 * math.sin(0.11 * (px + 0.7 * py) + 6.0 * hash01(tx, ty, 3))
                colour = tuple(c * shade * grain for c in colour)
                # roughness from polished (0.08) to matte (0.75), one value per tile
                rough = 0.08 + 0.67 * hash01(tx, ty, 2)
                # a slight wear towards the tile's centre
                lx, ly = px % cell - cell / 2, py % cell - cell / 2
                rough = min(1.0, rough + 0.08 * math.exp(-(lx * lx + ly * ly) / 1500.0))
            i = 3 * px
            base[i:i + 3] = bytes(to_byte(srgb_encode(c)) for c in colour)
            mr[i] = 255                     # R unused (occlusion), left white
            mr[i + 1] = to_byte(rough)      # G roughness
            mr[i + 2] = 0                   # B metallic
        base_rows.append(bytes(base))
        mr_rows.append(bytes(mr))
    return (png_bytes(FLOOR_SIZE, FLOOR_SIZE, base_rows),
            png_bytes(FLOOR_SIZE, FLOOR_SIZE, mr_rows))


BALL_W, BALL_H = 512, 256    # textured sphere: u around (2 : 1 like the sphere's parameters)
BALL_CELLS_U, BALL_CELLS_V = 16, 8


def ball_base_colour():
    """Checker of terracotta and cream with a teal ring in every cream cell (sRGB)."""
    terracotta = (0.55, 0.16, 0.07)
    cream = (0.80, 0.74, 0.60)
    teal = (0.03, 0.30, 0.33)
    cw, ch = BALL_W // BALL_CELLS_U, BALL_H // BALL_CELLS_V
    rows = []
    for py in range(BALL_H):
        row = bytearray(BALL_W * 3)
        for px in range(BALL_W):
            cx, cy = px // cw, py // ch
            if (cx + cy) % 2 == 0:
                colour = terracotta
            else:
                dx = (px % cw) + 0.5 - cw / 2
                dy = (py % ch) + 0.5 - ch / 2
                r = math.sqrt(dx * dx + dy * dy) / (cw / 2)
                colour = teal if 0.45 < r < 0.7 else cream
            row[3 * px:3 * px + 3] = bytes(to_byte(srgb_encode(c)) for c in colour)
        rows.append(bytes(row))
    return png_bytes(BALL_W, BALL_H, rows)


def ball_normal_map():
    """Tangent-space normal map (linear): a round dimple in the middle of every checker cell.

    Height h = -depth * (1 - r^2/rho^2)^2 inside the dimple. Tangent space: +x is +u (right in
    the image), +y is up in the image (decreasing v, i.e. decreasing row), +z the surface normal.
    So n = normalize(-dh/dx, +dh/drow, 1) with x, row in texels. The left wall of a dimple faces
    right (R > 128), its upper wall faces down (G < 128).
    """
    cw, ch = BALL_W // BALL_CELLS_U, BALL_H // BALL_CELLS_V
    rho = 0.42 * cw          # dimple radius in texels
    depth = 0.22 * rho       # its depth, same units: steepest wall about 30 degrees
    rows = []
    for py in range(BALL_H):
        row = bytearray(BALL_W * 3)
        for px in range(BALL_W):
            dx = (px % cw) + 0.5 - cw / 2
            dy = (py % ch) + 0.5 - ch / 2
            q = (dx * dx + dy * dy) / (rho * rho)
            if q < 1.0:
                # h = -depth (1 - q)^2, dh/dx = 4 depth (1 - q) dx / rho^2
                k = 4.0 * depth * (1.0 - q) / (rho * rho)
                dhdx, dhdrow = k * dx, k * dy
            else:
                dhdx = dhdrow = 0.0
            nx, ny, nz = -dhdx, dhdrow, 1.0
            inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
            row[3 * px] = to_byte(0.5 + 0.5 * nx * inv)
            row[3 * px + 1] = to_byte(0.5 + 0.5 * ny * inv)
            row[3 * px + 2] = to_byte(0.5 + 0.5 * nz * inv)
        rows.append(bytes(row))
    return png_bytes(BALL_W, BALL_H, rows)


def ball_metallic_roughness():
    """Roughness 0.35 on the cells, a little rougher (0.6) in the dimples; metallic 0."""
    cw, ch = BALL_W // BALL_CELLS_U, BALL_H // BALL_CELLS_V
    rho = 0.42 * cw
    rows = []
    for py in range(BALL_H):
        row = bytearray(BALL_W * 3)
        for px in range(BALL_W):
            dx = (px % cw) + 0.5 - cw / 2
            dy = (py % ch) + 0.5 - ch / 2
            q = (dx * dx + dy * dy) / (rho * rho)
            rough = 0.35 + 0.25 * max(0.0, 1.0 - q) ** 0.5
            row[3 * px] = 255
            row[3 * px + 1] = to_byte(rough)
            row[3 * px + 2] = 0
        rows.append(bytes(row))
    return png_bytes(BALL_W, BALL_H, rows)


# ---------------------------------------------------------------------------------------------
# Vector and quaternion helpers













def look_at_quat(eye, target, up=(0.0, 1.0, 0.0)):
    """Rotation that points a node's local -z from `eye` at `target`, local +y towards `up`."""
    return look_along(sub(target, eye), up)








# ---------------------------------------------------------------------------------------------
# Meshes: lists of positions, normals, uvs (tuples) and triangles (index triples, CCW = front)

def uv_sphere(segments=64, rings=32):
    """Unit sphere. u goes around (seam at the back, -z; u increases to the right seen from +z),
    v from 0 at the north pole (+y) to 1 at the south pole, so the image is upright."""
    pos, nor, uv = [], [], []
    for j in range(rings + 1):
        v = j / rings
        theta = math.pi * v
        for i in range(segments + 1):
            u = i / segments
            if j in (0, rings) and i < segments:
                u = (i + 0.5) / segments      # pole vertex: centred in its triangle's column
            phi = 2 * math.pi * (i / segments)
            st = math.sin(theta)
            p = (-st * math.sin(phi), math.cos(theta), -st * math.cos(phi))
            if j in (0, rings):
                p = (0.0, 1.0 if j == 0 else -1.0, 0.0)
            pos.append(p)
            nor.append(p)
            uv.append((u, v))
    tris = []
    w = segments + 1
    for j in range(rings):
        for i in range(segments):
            a, b = j * w + i, j * w + i + 1               # upper ring
            c, d = (j + 1) * w + i, (j + 1) * w + i + 1   # lower ring
            if j != 0:
                tris.append((a, c, b))
            if j != rings - 1:
                tris.append((b, c, d))
    return pos, nor, uv, tris


def torus(major=1.0, minor=0.3, segments=72, sides=28):
    """Torus around the local y axis (lying in the xz plane)."""
    pos, nor, uv = [], [], []
    for j in range(sides + 1):
        v = j / sides
        t = 2 * math.pi * v
        for i in range(segments + 1):
            u = i / segments
            p_ = 2 * math.pi * u
            cx, cz = math.cos(p_), -math.sin(p_)
            n = (math.cos(t) * cx, math.sin(t), math.cos(t) * cz)
            r = major + minor * math.cos(t)
            pos.append((r * cx, minor * math.sin(t), r * cz))
            nor.append(n)
            uv.append((u, v))
    tris = []
    w = segments + 1
    for j in range(sides):
        for i in range(segments):
            a, b = j * w + i, j * w + i + 1
            c, d = (j + 1) * w + i, (j + 1) * w + i + 1
            tris.append((a, b, c))
            tris.append((b, d, c))
    return pos, nor, uv, tris


def box(sx, sy, sz):
    """Axis-aligned box centred at the origin, 4 vertices per face, outward normals."""
    hx, hy, hz = sx / 2, sy / 2, sz / 2
    faces = [  # normal, u axis, v axis (v axis points down the image)
        ((1, 0, 0), (0, 0, -1), (0, -1, 0)),
        ((-1, 0, 0), (0, 0, 1), (0, -1, 0)),
        ((0, 1, 0), (1, 0, 0), (0, 0, 1)),
        ((0, -1, 0), (1, 0, 0), (0, 0, -1)),
        ((0, 0, 1), (1, 0, 0), (0, -1, 0)),
        ((0, 0, -1), (-1, 0, 0), (0, -1, 0)),
    ]
    pos, nor, uv, tris = [], [], [], []
    h = (hx, hy, hz)
    for n, ua, va in faces:
        base = len(pos)
        for (su, sv) in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            p = tuple(h[k] * (n[k] + su * ua[k] + sv * va[k]) for k in range(3))
            pos.append(p)
            nor.append(tuple(float(c) for c in n))
            uv.append(((su + 1) / 2, (sv + 1) / 2))
        tris.append((base, base + 2, base + 1))
        tris.append((base, base + 3, base + 2))
    return pos, nor, uv, tris


FLOOR_X = (-9.0, 9.0)
FLOOR_Z = (-2.6, 12.0)       # the backdrop's sweep starts at the far edge
TILE_PERIOD = 2.0            # metres per texture repeat (4 tiles of 0.5 m)
SWEEP_RADIUS = 2.2
WALL_TOP = 9.0


def floor():
    (x0, x1), (z0, z1) = FLOOR_X, FLOOR_Z
    pos = [(x0, 0.0, z0), (x1, 0.0, z0), (x1, 0.0, z1), (x0, 0.0, z1)]
    # u to the right (+x), v towards the camera (+z); v = 0 at the far edge
    uv = [((p[0] - x0) / TILE_PERIOD, (p[2] - z0) / TILE_PERIOD) for p in pos]
    nor = [(0.0, 1.0, 0.0)] * 4
    return pos, nor, uv, [(0, 2, 1), (0, 3, 2)]


def backdrop(arc_steps=24):
    """Cyclorama: from the floor's far edge a quarter cylinder sweeps up into a vertical wall."""
    (x0, x1), z0 = FLOOR_X, FLOOR_Z[0]
    r = SWEEP_RADIUS
    profile = []   # (y, z, ny, nz, arc length)
    for k in range(arc_steps + 1):
        a = (math.pi / 2) * k / arc_steps
        # centre of the arc at (y = r, z = z0); starts at the floor (y = 0), ends facing +z
        profile.append((r - r * math.cos(a), z0 - r * math.sin(a), math.cos(a), math.sin(a), r * a))
    y_end, z_end = profile[-1][0], profile[-1][1]
    profile.append((WALL_TOP, z_end, 0.0, 1.0, r * math.pi / 2 + (WALL_TOP - y_end)))
    pos, nor, uv, tris = [], [], [], []
    for (y, z, ny, nz, s) in profile:
        for x in (x0, x1):
            pos.append((x, y, z))
            nor.append((0.0, ny, nz))
            uv.append(((x - x0) / TILE_PERIOD, -s / TILE_PERIOD))
    for k in range(len(profile) - 1):
        a, b, c, d = 2 * k, 2 * k + 1, 2 * k + 2, 2 * k + 3
        tris.append((a, b, d))
        tris.append((a, d, c))
    return pos, nor, uv, tris


# ---------------------------------------------------------------------------------------------
# glTF assembly

class Builder(BufferBuilder):
    """The buffer, and meshes of positions, normals and UVs."""

    def geometry(self, mesh):
        pos, nor, uv, tris = mesh
        attrs = {"POSITION": self.floats(pos, "VEC3", with_bounds=True),
                 "NORMAL": self.floats([normalize(n) for n in nor], "VEC3"),
                 "TEXCOORD_0": self.floats(uv, "VEC2")}
        return attrs, self.indices(tris, len(pos)), len(tris)


def build(out_dir):
    b = Builder()
    geo_floor = b.geometry(floor())
    geo_backdrop = b.geometry(backdrop())
    geo_sphere = b.geometry(uv_sphere(64, 32))
    geo_torus = b.geometry(torus(0.32, 0.11, 72, 28))
    geo_panel = b.geometry(box(1.0, 1.6, 0.05))
    while len(b.bin) % 4:
        b.bin.append(0)

    images = [
        ("floor_basecolor.png", "image/png"),
        ("floor_metalrough.png", "image/png"),
        ("ball_basecolor.png", "image/png"),
        ("ball_metalrough.png", "image/png"),
        ("ball_normal.png", "image/png"),
    ]
    png_data = {}
    png_data["floor_basecolor.png"], png_data["floor_metalrough.png"] = floor_textures()
    png_data["ball_basecolor.png"] = ball_base_colour()
    png_data["ball_metalrough.png"] = ball_metallic_roughness()
    png_data["ball_normal.png"] = ball_normal_map()

    samplers = [
        # 0: floor, tiles repeat both ways
        {"magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR, "wrapS": REPEAT, "wrapT": REPEAT},
        # 1: sphere, repeats around (u), clamps at the poles (v)
        {"magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR, "wrapS": REPEAT,
         "wrapT": CLAMP_TO_EDGE},
    ]
    textures = [
        {"sampler": 0, "source": 0, "name": "floor base colour"},
        {"sampler": 0, "source": 1, "name": "floor metallic-roughness"},
        {"sampler": 1, "source": 2, "name": "ball base colour"},
        {"sampler": 1, "source": 3, "name": "ball metallic-roughness"},
        {"sampler": 1, "source": 4, "name": "ball normal"},
    ]

    materials = [
        {"name": "floor tiles",
         "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                  "metallicRoughnessTexture": {"index": 1},
                                  "metallicFactor": 1.0, "roughnessFactor": 1.0}},
        {"name": "backdrop",
         "pbrMetallicRoughness": {"baseColorFactor": [0.42, 0.45, 0.5, 1.0],
                                  "metallicFactor": 0.0, "roughnessFactor": 0.85}},
        {"name": "polished gold",
         "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.766, 0.336, 1.0],
                                  "metallicFactor": 1.0, "roughnessFactor": 0.05}},
        {"name": "rough aluminium",
         "pbrMetallicRoughness": {"baseColorFactor": [0.913, 0.922, 0.924, 1.0],
                                  "metallicFactor": 1.0, "roughnessFactor": 0.4}},
        {"name": "clear glass",
         "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                                  "metallicFactor": 0.0, "roughnessFactor": 0.0},
         "extensions": {
             "KHR_materials_transmission": {"transmissionFactor": 1.0},
             "KHR_materials_ior": {"ior": 1.5},
             "KHR_materials_volume": {"thicknessFactor": 1.0,
                                      "attenuationColor": [0.9, 0.95, 1.0],
                                      "attenuationDistance": 2.0}}},
        {"name": "dimpled ceramic",
         "pbrMetallicRoughness": {"baseColorTexture": {"index": 2},
                                  "metallicRoughnessTexture": {"index": 3},
                                  "metallicFactor": 1.0, "roughnessFactor": 1.0},
         "normalTexture": {"index": 4, "scale": 1.0}},
        {"name": "red lacquer",
         "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.045, 0.03, 1.0],
                                  "metallicFactor": 0.0, "roughnessFactor": 0.2}},
        {"name": "light panel",
         "pbrMetallicRoughness": {"baseColorFactor": [0.05, 0.05, 0.05, 1.0],
                                  "metallicFactor": 0.0, "roughnessFactor": 0.5},
         "emissiveFactor": [1.0, 0.9, 0.8],
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 8.0}}},
        {"name": "softbox",
         "pbrMetallicRoughness": {"baseColorFactor": [0.05, 0.05, 0.05, 1.0],
                                  "metallicFactor": 0.0, "roughnessFactor": 0.5},
         "emissiveFactor": [1.0, 1.0, 1.0],
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 1.5}}},
    ]
    # The metallic-roughness textured materials: the factors multiply the texture (1 = as is).
    # The dimpled ceramic's texture has B = 0 (metallic 0) and G = roughness 0.35 .. 0.6.

    def prim(geo, material):
        attrs, idx, _ = geo
        return {"attributes": dict(attrs), "indices": idx, "material": material, "mode": 4}

    meshes = [
        {"name": "floor", "primitives": [prim(geo_floor, 0)]},
        {"name": "backdrop", "primitives": [prim(geo_backdrop, 1)]},
        {"name": "gold sphere", "primitives": [prim(geo_sphere, 2)]},
        {"name": "aluminium sphere", "primitives": [prim(geo_sphere, 3)]},
        {"name": "glass sphere", "primitives": [prim(geo_sphere, 4)]},
        {"name": "dimpled sphere", "primitives": [prim(geo_sphere, 5)]},
        {"name": "torus", "primitives": [prim(geo_torus, 6)]},
        {"name": "light panel", "primitives": [prim(geo_panel, 7)]},
        {"name": "softbox", "primitives": [prim(geo_panel, 8)]},
    ]
    mesh_triangles = [geo_floor[2], geo_backdrop[2], geo_sphere[2], geo_sphere[2], geo_sphere[2],
                      geo_sphere[2], geo_torus[2], geo_panel[2], geo_panel[2]]

    # --- lights: radiometric (scene-conventions.md) ---------------------------------------
    # Budget on the floor at the group's centre (W/m^2): key spot ~1.8 (2.6 facing it, at 5.95 m
    # and 43 degrees from the vertical), rim sun ~1.3 (1.8 at 44 degrees), light panel ~0.2,
    # softbox ~0.4, fill point ~0.1: about 3.7 W/m^2 in all, so the light tiles (albedo ~0.6)
    # have a radiance of about 0.6 x 3.7 / pi ~ 0.7: bright under the Khronos PBR Neutral tone
    # mapper but not clipped; the shadows get the indirect light and the fill.
    target = (0.0, 0.45, 0.0)
    spot_pos = (-2.6, 4.6, 3.4)
    spot_dist2 = dot(sub(spot_pos, target), sub(spot_pos, target))
    spot_intensity = round(2.6 * spot_dist2)     # I = E r^2 (here 92 W/sr)
    lights = [
        {"name": "key spot", "type": "spot", "color": [1.0, 0.97, 0.92],
         "intensity": float(spot_intensity),
         "spot": {"innerConeAngle": 0.32, "outerConeAngle": 0.5}},
        {"name": "rim sun", "type": "directional", "color": [1.0, 0.93, 0.82], "intensity": 1.8},
        {"name": "fill point", "type": "point", "color": [0.8, 0.88, 1.0], "intensity": 5.0},
    ]
    # the sun shines from behind on the right, down towards the front left
    sun_dir = normalize((-0.5, -0.72, 0.48))              # direction the light travels
    sun_pos = (4.0, 6.0, -4.0)
    sun_rot = look_at_quat(sun_pos, (sun_pos[0] + sun_dir[0], sun_pos[1] + sun_dir[1],
                                     sun_pos[2] + sun_dir[2]))

    # --- camera ---------------------------------------------------------------------------
    eye = (0.3, 1.25, 6.3)
    look = (0.1, 0.62, 0.0)
    cameras = [{"name": "showcase camera", "type": "perspective",
                "perspective": {"yfov": 0.6, "aspectRatio": 1.5, "znear": 0.05, "zfar": 100.0}}]

    # --- nodes -------------------------------------------------------------------------------
    def sphere_node(name, mesh, centre, radius):
        return {"name": name, "mesh": mesh,
                "translation": r6((centre[0], radius + centre[1], centre[2])),
                "scale": r6((radius, radius, radius))}

    # torus instances: local frame of the parent "rings" node
    torus_extent = 0.32 + 0.11
    standing_scale = (0.95, 1.0, 1.35)  # an upright oval once stood up: 0.95 wide, 1.35 tall
    standing_rot = quat_mul(quat_axis_angle((0, 1, 0), math.radians(-28)),
                            quat_axis_angle((1, 0, 0), math.radians(90)))
    # The light panel (a thin box) stands at the back right and turns its +z face to the group:
    # a look-at points local -z at the target, so add half a turn about local y.
    panel_pos = (2.95, 0.95, -2.05)
    panel_q = quat_mul(look_at_quat(panel_pos, (0.3, 0.9, 0.0)),
                       quat_axis_angle((0, 1, 0), math.pi))

    # A dim overhead softbox out of the camera's view (the same thin box, scaled, its emitting
    # +z face turned down): the metals and the glass reflect it instead of the black sky.
    softbox_pos = (0.0, 4.6, 1.6)
    softbox_q = quat_axis_angle((1, 0, 0), math.pi / 2)
    softbox_scale = (3.5, 1.2, 1.0)

    nodes = [
        {"name": "floor", "mesh": 0},
        {"name": "backdrop", "mesh": 1},
        sphere_node("gold sphere", 2, (-1.95, 0.0, -0.35), 0.6),
        sphere_node("aluminium sphere", 3, (2.05, 0.0, -0.55), 0.55),
        sphere_node("glass sphere", 4, (-0.55, 0.0, 1.05), 0.5),
        sphere_node("dimpled sphere", 5, (0.55, 0.0, -0.8), 0.62),
        {"name": "rings", "translation": r6((1.15, 0.0, 1.0)), "children": [7, 8]},
        {"name": "ring lying", "mesh": 6, "translation": r6((0.25, 0.11, 0.45))},
        {"name": "ring standing", "mesh": 6,
         "translation": r6((-0.05, standing_scale[2] * torus_extent - 0.004, -0.25)),
         "rotation": r6(standing_rot), "scale": r6(standing_scale)},
        {"name": "light panel", "mesh": 7, "translation": r6(panel_pos), "rotation": r6(panel_q)},
        {"name": "softbox", "mesh": 8, "translation": r6(softbox_pos), "rotation": r6(softbox_q),
         "scale": r6(softbox_scale)},
        {"name": "key spot", "translation": r6(spot_pos),
         "rotation": r6(look_at_quat(spot_pos, target)),
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "rim sun", "translation": r6(sun_pos), "rotation": r6(sun_rot),
         "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"name": "fill point", "translation": r6((3.2, 2.4, 3.6)),
         "extensions": {"KHR_lights_punctual": {"light": 2}}},
        {"name": "camera", "camera": 0, "translation": r6(eye),
         "rotation": r6(look_at_quat(eye, look))},
    ]

    children = {c for n in nodes for c in n.get("children", [])}
    roots = [i for i in range(len(nodes)) if i not in children]

    gltf = {
        "asset": {"version": "2.0", "generator": "raylab tools/make_showcase.py",
                  "copyright": "raylab contributors, CC0"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission",
                           "KHR_materials_ior", "KHR_materials_volume",
                           "KHR_materials_emissive_strength"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": "showcase", "nodes": roots}],
        "nodes": nodes,
        "cameras": cameras,
        "meshes": meshes,
        "materials": materials,
        "textures": textures,
        "samplers": samplers,
        "images": [{"uri": name, "mimeType": mime} for name, mime in images],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"uri": "showcase.bin", "byteLength": len(b.bin)}],
    }

    os.makedirs(out_dir, exist_ok=True)
    files = {"showcase.gltf": (json.dumps(gltf, indent=1) + "\n").encode(),
             "showcase.bin": bytes(b.bin)}
    files.update(png_data)
    for name, data in files.items():
        with open(os.path.join(out_dir, name), "wb") as f:
            f.write(data)

    tri_total = sum(mesh_triangles[n["mesh"]] for n in nodes if "mesh" in n)
    total = sum(len(d) for d in files.values())
    for name in sorted(files):
        print("%-22s %9d bytes" % (name, len(files[name])))
    print("total %d bytes, %d triangles in %d mesh instances; spot %g W/sr, sun %g W/m^2, "
          "point %g W/sr" % (total, tri_total, sum(1 for n in nodes if "mesh" in n),
                             lights[0]["intensity"], lights[1]["intensity"],
                             lights[2]["intensity"]))


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else DEFAULT_OUT
    if out_dir in ("-h", "--help"):
        print(__doc__)
        return
    build(out_dir)


if __name__ == "__main__":
    main()
