#!/usr/bin/env python3
"""Writes scenes/obj-room/: a small room as Wavefront OBJ + MTL with textures,
for raylab's OBJ/MTL example and tests. Every statement raylab maps is used:
vt/vn, groups, usemtl, map_Kd, Ke (a ceiling light), glass (illum 7, Ni),
a mirror (illum 3), the PBR extension (Pm/Pr), a cut-out (map_d) and a normal
map (norm).

    python3 tools/make_obj_room.py [OUT_DIR]    (default scenes/obj-room)
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gltfgen import png_bytes  # noqa: E402


def checker(size, cells, a, b):
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            c = a if ((x * cells // size) + (y * cells // size)) % 2 == 0 else b
            row.extend(c)
        rows.append(bytes(row))
    return png_bytes(size, size, rows)


def leaf_mask(size):
    """RGBA: a green disc on transparent (a cut-out for map_d)."""
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            dx, dy = (x + 0.5) / size - 0.5, (y + 0.5) / size - 0.5
            inside = dx * dx + dy * dy < 0.2
            row.extend([60, 160, 60, 255 if inside else 0])
        rows.append(bytes(row))
    return png_bytes(size, size, rows, channels=4)


def bumps_normal_map(size, n):
    """A tangent-space normal map of n × n round bumps."""
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            u = (x + 0.5) / size * n % 1.0 - 0.5
            v = (y + 0.5) / size * n % 1.0 - 0.5
            r2 = u * u + v * v
            if r2 < 0.16:
                nx, ny = u * 1.5, -v * 1.5
            else:
                nx, ny = 0.0, 0.0
            nz = math.sqrt(max(0.0, 1.0 - nx * nx - ny * ny))
            row.extend(int(round((c * 0.5 + 0.5) * 255)) for c in (nx, ny, nz))
        rows.append(bytes(row))
    return png_bytes(size, size, rows)


class Obj:
    def __init__(self):
        self.lines = []
        self.v = self.vt = self.vn = 0

    def quad(self, corner, u, v, normal, uv_scale=1.0):
        """A quad with texture coordinates and a normal, counter-clockwise
        seen from the side the normal points to."""
        p = [corner,
             [corner[i] + u[i] for i in range(3)],
             [corner[i] + u[i] + v[i] for i in range(3)],
             [corner[i] + v[i] for i in range(3)]]
        for q in p:
            self.lines.append("v %g %g %g" % tuple(q))
        for t in [(0, 0), (uv_scale, 0), (uv_scale, uv_scale), (0, uv_scale)]:
            self.lines.append("vt %g %g" % t)
        self.lines.append("vn %g %g %g" % tuple(normal))
        # Relative indices, to exercise them: -4 is the first of the four.
        self.lines.append("f -4/-4/-1 -3/-3/-1 -2/-2/-1 -1/-1/-1")
        self.v += 4
        self.vt += 4
        self.vn += 1

    def sphere(self, centre, radius, segments=32, rings=16):
        """A UV sphere with smooth vertex normals (absolute indices)."""
        first_v, first_n = self.v + 1, self.vn + 1
        for r in range(rings + 1):
            theta = math.pi * r / rings
            for s in range(segments + 1):
                phi = 2 * math.pi * s / segments
                n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
                self.lines.append("v %g %g %g" % tuple(centre[i] + radius * n[i] for i in range(3)))
                self.lines.append("vn %g %g %g" % n)
                self.v += 1
                self.vn += 1
        w = segments + 1
        for r in range(rings):
            for s in range(segments):
                a = r * w + s
                b, c, d = a + 1, a + w, a + w + 1
                idx = lambda k: "%d//%d" % (first_v + k, first_n + k)  # noqa: E731
                if r != 0:
                    self.lines.append("f %s %s %s" % (idx(a), idx(c), idx(b)))
                if r != rings - 1:
                    self.lines.append("f %s %s %s" % (idx(b), idx(c), idx(d)))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "obj-room")
    os.makedirs(os.path.join(out, "textures"), exist_ok=True)
    with open(os.path.join(out, "textures", "checker.png"), "wb") as f:
        f.write(checker(256, 8, (235, 225, 200), (60, 70, 90)))
    with open(os.path.join(out, "textures", "leaf.png"), "wb") as f:
        f.write(leaf_mask(128))
    with open(os.path.join(out, "textures", "bumps_normal.png"), "wb") as f:
        f.write(bumps_normal_map(256, 6))

    mtl = """# raylab's OBJ/MTL example (made by tools/make_obj_room.py)
newmtl floor
Kd 1 1 1
Ks 0.5 0.5 0.5
Ns 20
map_Kd -s 2 2 textures/checker.png

newmtl wall
Kd 0.7 0.7 0.72
Ks 0 0 0

newmtl bumpy_wall
Kd 0.75 0.45 0.3
Ks 0.5 0.5 0.5
Ns 60
norm textures/bumps_normal.png

newmtl light
Kd 0 0 0
Ke 12 11 9

newmtl glass
Kd 1 1 1
Ks 1 1 1
Ns 10000
Ni 1.5
illum 7

newmtl mirror
Ks 0.95 0.95 0.95
Ns 10000
illum 3

newmtl gold
Kd 1.0 0.78 0.34
Pm 1
Pr 0.3

newmtl leaf
Kd 1 1 1
map_Kd textures/leaf.png
map_d textures/leaf.png
"""
    with open(os.path.join(out, "room.mtl"), "w") as f:
        f.write(mtl)

    o = Obj()
    o.lines += ["# raylab's OBJ/MTL example (made by tools/make_obj_room.py)", "mtllib room.mtl"]
    s = 2.0
    o.lines += ["g floor", "usemtl floor"]
    o.quad([-s, 0, s], [2 * s, 0, 0], [0, 0, -2 * s], [0, 1, 0])
    o.lines += ["g walls", "usemtl wall"]
    o.quad([-s, 0, -s], [2 * s, 0, 0], [0, 2 * s, 0], [0, 0, 1])      # back
    o.quad([s, 0, -s], [0, 0, 2 * s], [0, 2 * s, 0], [-1, 0, 0])      # right
    o.quad([-s, 2 * s, s], [0, 0, -2 * s], [2 * s, 0, 0], [0, -1, 0])  # ceiling (faces down)
    o.lines += ["g left_wall", "usemtl bumpy_wall"]
    o.quad([-s, 0, s], [0, 0, -2 * s], [0, 2 * s, 0], [1, 0, 0], uv_scale=2.0)
    o.lines += ["g lamp", "usemtl light"]
    o.quad([-0.5, 2 * s - 0.01, 0.5], [0, 0, -1], [1, 0, 0], [0, -1, 0])
    o.lines += ["g glass_ball", "usemtl glass"]
    o.sphere([-0.9, 0.6, 0.3], 0.6)
    o.lines += ["g mirror_ball", "usemtl mirror"]
    o.sphere([0.9, 0.5, -0.6], 0.5)
    o.lines += ["g gold_ball", "usemtl gold"]
    o.sphere([0.6, 0.35, 0.9], 0.35)
    o.lines += ["g leaf", "usemtl leaf"]
    o.quad([-1.6, 0.2, -1.2], [1.0, 0, 0.2], [0, 1.2, 0], [-0.2, 0, 1])
    o.lines.append("")
    with open(os.path.join(out, "room.obj"), "w") as f:
        f.write("\n".join(o.lines))
    print("wrote", out)


if __name__ == "__main__":
    main()
