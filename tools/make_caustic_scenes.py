#!/usr/bin/env python3
"""Writes the caustic benchmark scenes of issue 45 (part 3) under scenes/caustics/: three small
glTF 2.0 scenes whose light reaches a diffuse surface mostly through a specular bounce from a
point or spot light (radius 0), the paths a path tracer cannot find.

Usage (from the project folder):

    python3 tools/make_caustic_scenes.py [OUT_DIR]

OUT_DIR defaults to scenes/caustics beside this tools/ folder. It writes ring.gltf,
glass-sphere.gltf, water.gltf, a .bin for each and caustics-tiles.png (their shared floor
texture), about 0.48 MB together; beside glass-sphere.gltf and water.gltf, a Mitsuba 3 twin of
each (glass-sphere.xml, water.xml, their meshes as binary PLY files NAME-MATERIAL.ply, about
0.6 MB together; see "Mitsuba 3 twins" below). Standard library only; the output is the same
bytes on every run. Units are metres, +y up, the floor or table at y = 0; lights in radiometric
units (docs/scene-conventions.md); every diffuse surface is Lambertian (KHR_materials_specular
specularFactor 0); no environment, no emitters: the punctual light is the only light.

- ring.gltf: a polished gold ring (a closed tube: 10 cm outer, 9.2 cm inner radius, 7 cm tall,
  160 segments, smooth normals; metallic 1, roughness 0, baseColor 1.0, 0.78, 0.34) lying on a
  light grey table, under a spot light (4 W/sr) 1 m to the side and 0.27 m up, 15 degrees above
  the table (cone 22 degrees, soft from 16): the inside of the ring focuses the light into the
  cardioid (nephroid) caustic on the table inside the ring, its cusp towards the light; the
  outside of the ring spreads a faint reflection over the table on the light's side. The camera
  looks down into the ring at about 55 degrees.
- glass-sphere.gltf: a clear glass sphere (icosphere, 5,120 triangles, smooth normals; radius
  15 cm, transmission 1, ior 1.5, roughness 0, KHR_materials_volume thicknessFactor 0.3 and no
  attenuation: a solid that refracts) held 10 cm above a tiled floor (caustics-tiles.png) under a
  small point light (2 W/sr) 1.3 m up and to the side: the ball focuses the light into a
  bright spot inside its shadow.
- water.gltf: a pool (tiled floor 1.2 m square, tiled walls 0.4 m tall) filled to 0.3 m with
  water whose surface is one sheet (a 96 x 96 height field: a sum of five sine waves of 1 to
  2.2 mm amplitude and 7 to 17 cm wavelength, analytic smooth normals; transmission 1, ior 1.33,
  roughness 0, KHR_materials_volume thicknessFactor 0.3 and no attenuation, so that both
  renderers refract at it; normals up, out of the water), under a small point light (1.6 W/sr)
  1.2 m above the surface: the net of caustics on the pool's floor and walls. The camera is
  under water (0.2 m above the floor, looking down the pool), so that it sees the floor
  directly: seen from above through the surface the caustic would be a specular-diffuse-
  specular path that neither a light tracer nor a path tracer can sample from a point light.

Mitsuba 3 twins: Mitsuba cannot read glTF, so that its light tracer `ptracer` can render the
same scenes (tools/compare_ptracer.py, the check of issue 45 that bdpt converges to it on
directly seen diffuse surfaces), glass-sphere.xml and water.xml hold the same scene in the
physical quantities raylab gives the glTF (docs/scene-conventions.md): the same float32 vertex
positions, smooth normals and texture coordinates (binary PLY, texture v as in glTF: Mitsuba's
`ply` does not flip it, and its v = 0 is the image's top row as in glTF); the tiles a `diffuse`
with a `bitmap` reflectance (sRGB-decoded per texel, then bilinear, repeating, as raylab reads
baseColorTexture); the glass and the water a smooth `dielectric` (int_ior the glTF ior,
ext_ior exactly 1, not Mitsuba's default for air); the point light's `intensity` the glTF
intensity times its colour (W/sr, as raylab reads KHR_lights_punctual); the camera the glTF
node's (rounded) translation and rotation, turned half a turn about its y axis (a Mitsuba camera
looks along its +z with +x to the left, a glTF one along -z with +x to the right), `fov` the
glTF yfov in degrees about the y axis. Film 160 x 120 with the box filter (`-D resx=...
-D resy=...` for another size, the same for both renderers), `path` with no depth limit. Two
differences remain, both of the glTF material against Mitsuba's: raylab's glTF transmission
takes Schlick's Fresnel term (F0 from the ior, the cosine on the air side) where Mitsuba's
`dielectric` takes the exact one, and raylab's glTF dielectrics do not scale radiance by 1/eta^2
across the interface (exact when camera and light are both in air, not for the pool's camera,
which is under water), where Mitsuba's and raylab's reading of the Mitsuba `dielectric` do.
Measured with raylab on both files (160 x 120, 2026-12-02): the ball's caustic is 1-2 % brighter
from the glTF (Schlick's term lets more through at oblique incidence), and under the water the
glTF's bdpt is 1.3 % darker and its path 0.56 (about 1/1.33^2) of the twin's (paths whose camera
side crosses the surface); the other diffuse surfaces agree to 0.1 %. The ring has no twin:
Mitsuba's spot light falls off linearly in angle (glTF: quadratically in the cosine) and no
Mitsuba conductor has the glTF metal's Schlick Fresnel.

Own work, CC0.
"""

import json
import math
import os
import struct
import sys

sys.dont_write_bytecode = True  # leave no tools/__pycache__ behind
from gltfgen import BufferBuilder, look_along, normalize, png_bytes, r6, sub  # noqa: E402
from make_glass_lamps import Batches, srgb8  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUT = os.path.join(ROOT, "scenes", "caustics")
TEXTURE = "caustics-tiles.png"
TEX_SIZE, TEX_TILES, GROUT = 128, 4, 3     # 4 x 4 tiles, 3-texel grout lines
LIFT = 0.001                               # objects rest this far above the floor
LAMBERT = {"KHR_materials_specular": {"specularFactor": 0.0}}


def tiles_png():
    """The floor texture, RGB rows top first: 4 x 4 pale tiles, each a slightly different
    shade, between dark grout lines."""
    shades = [(0.78, 0.82, 0.85), (0.72, 0.78, 0.84), (0.80, 0.80, 0.78), (0.70, 0.76, 0.80)]
    grout = bytes(srgb8(x) for x in (0.08, 0.08, 0.09))
    step = TEX_SIZE // TEX_TILES
    rows = []
    for y in range(TEX_SIZE):
        row = bytearray()
        for x in range(TEX_SIZE):
            if x % step < GROUT or y % step < GROUT:
                row += grout
            else:
                c = shades[(x // step + 3 * (y // step)) % len(shades)]
                row += bytes(srgb8(v) for v in c)
        rows.append(bytes(row))
    return png_bytes(TEX_SIZE, TEX_SIZE, rows)


def pbr(colour, metallic=0.0, rough=1.0):
    return {"baseColorFactor": list(colour) + [1.0], "metallicFactor": metallic,
            "roughnessFactor": rough}


def textured(name):
    return {"name": name,
            "pbrMetallicRoughness": dict(pbr((1.0, 1.0, 1.0)), baseColorTexture={"index": 0}),
            "extensions": dict(LAMBERT)}


def dielectric(name, ior, thickness):
    return {"name": name, "pbrMetallicRoughness": pbr((1.0, 1.0, 1.0), rough=0.0),
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                           "KHR_materials_ior": {"ior": ior},
                           "KHR_materials_volume": {"thicknessFactor": thickness}}}


def quad_uv(g, mat, corners, normal, uvs):
    """A quad from four corners (counter-clockwise seen from the front) with its own UVs."""
    idx = [g.vertex(mat, p, normal, uv) for p, uv in zip(corners, uvs)]
    g.tri(mat, idx[0], idx[1], idx[2])
    g.tri(mat, idx[0], idx[2], idx[3])


def tiled_floor(g, mat, x0, x1, z0, z1, per_metre):
    """The floor y = 0 over [x0, x1] x [z0, z1], facing up, the texture repeated per_metre
    times per metre."""
    corners = [(x0, 0.0, z1), (x1, 0.0, z1), (x1, 0.0, z0), (x0, 0.0, z0)]
    quad_uv(g, mat, corners, (0.0, 1.0, 0.0),
            [(p[0] * per_metre, p[2] * per_metre) for p in corners])


def water_height(x, z):
    """The water surface's height above its mean level and the two slopes (dh/dx, dh/dz)."""
    waves = [(0.0022, 0.17, 0.3, 0.0), (0.0018, 0.13, 1.4, 1.0), (0.0015, 0.11, 2.3, 2.0),
             (0.0012, 0.09, 3.6, 0.5), (0.0010, 0.07, 5.0, 1.7)]
    h = dx = dz = 0.0
    for amp, length, angle, phase in waves:
        kx, kz = math.cos(angle) * 2 * math.pi / length, math.sin(angle) * 2 * math.pi / length
        s = kx * x + kz * z + phase
        h += amp * math.sin(s)
        dx += amp * kx * math.cos(s)
        dz += amp * kz * math.cos(s)
    return h, dx, dz


def water_sheet(g, mat, half, level, n):
    """An n x n height field over [-half, half]^2 at mean height `level`, normals up."""
    idx = []
    for j in range(n + 1):
        row = []
        for i in range(n + 1):
            x, z = -half + 2 * half * i / n, -half + 2 * half * j / n
            h, dx, dz = water_height(x, z)
            row.append(g.vertex(mat, (x, level + h, z), normalize((-dx, 1.0, -dz))))
        idx.append(row)
    for j in range(n):
        for i in range(n):
            a, b, c, d = idx[j][i], idx[j][i + 1], idx[j + 1][i + 1], idx[j + 1][i]
            # seen from +y, (a, d, c) is counter-clockwise (x right, z towards the viewer)
            g.tri(mat, a, d, c)
            g.tri(mat, a, c, b)


def write(out_dir, name, materials, g, lights, light_nodes, eye, target, yfov, note):
    """Assembles one scene: a mesh per material, the lights, a camera; writes NAME.gltf/.bin."""
    b = BufferBuilder()
    meshes, nodes, tri_total = g.meshes(b, materials)
    nodes += light_nodes
    nodes.append({"name": "camera", "camera": 0, "translation": r6(eye),
                  "rotation": r6(look_along(sub(target, eye)))})
    used = {"KHR_lights_punctual"}
    for m in materials:
        used |= set(m.get("extensions", {}))
    textured_any = any("baseColorTexture" in m["pbrMetallicRoughness"] for m in materials)
    gltf = {
        "asset": {"version": "2.0", "generator": "raylab tools/make_caustic_scenes.py",
                  "copyright": "raylab contributors, CC0"},
        "extensionsUsed": sorted(used),
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": name, "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"name": "camera", "type": "perspective",
                     "perspective": {"yfov": yfov, "aspectRatio": 4.0 / 3.0,
                                     "znear": 0.01, "zfar": 50.0}}],
        "meshes": meshes,
        "materials": materials,
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"uri": name + ".bin", "byteLength": len(b.bin)}],
    }
    if textured_any:
        gltf["textures"] = [{"sampler": 0, "source": 0}]
        gltf["samplers"] = [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497,
                             "wrapT": 10497}]
        gltf["images"] = [{"uri": TEXTURE, "mimeType": "image/png"}]
    files = {name + ".gltf": (json.dumps(gltf, indent=1) + "\n").encode(),
             name + ".bin": bytes(b.bin)}
    for fname, data in files.items():
        with open(os.path.join(out_dir, fname), "wb") as f:
            f.write(data)
        print("%-22s %7d bytes" % (fname, len(data)))
    print("  %s: %d triangles in %d meshes; %s" % (name, tri_total, len(meshes), note))


def ring(out_dir):
    materials = [
        {"name": "table", "pbrMetallicRoughness": pbr((0.7, 0.7, 0.68)),
         "extensions": dict(LAMBERT)},
        {"name": "gold", "pbrMetallicRoughness": pbr((1.0, 0.78, 0.34), metallic=1.0, rough=0.0)},
    ]
    g = Batches()
    g.quad(0, (0.0, 0.0, 0.0), (0.0, 0.0, 3.0), (3.0, 0.0, 0.0))          # the table, facing up
    g.tube(1, 0.0, 0.0, LIFT, 0.10, 0.092, 0.07, 160)
    pos, target = (-1.0, 0.27, 0.0), (0.0, 0.0, 0.0)
    lights = [{"name": "spot", "type": "spot", "color": [1.0, 0.97, 0.92], "intensity": 4.0,
               "spot": {"innerConeAngle": math.radians(16.0),
                        "outerConeAngle": math.radians(22.0)}}]
    light_nodes = [{"name": "spot", "translation": r6(pos),
                    "rotation": r6(look_along(sub(target, pos))),
                    "extensions": {"KHR_lights_punctual": {"light": 0}}}]
    write(out_dir, "ring", materials, g, lights, light_nodes,
          eye=(0.12, 0.5, 0.32), target=(0.0, 0.0, 0.0), yfov=0.5,
          note="a gold ring on a table, a spot light from the side")


def glass_sphere(out_dir):
    materials = [textured("tiled floor"), dielectric("glass 1.5", 1.5, 0.3)]
    g = Batches()
    tiled_floor(g, 0, -2.0, 2.0, -2.0, 2.0, 2.5)
    g.sphere(1, (0.0, 0.25, 0.0), 0.15, level=4)
    pos = (-0.45, 1.3, -0.15)
    lights = [{"name": "lamp", "type": "point", "color": [1.0, 0.96, 0.9], "intensity": 2.0}]
    light_nodes = [{"name": "lamp", "translation": r6(pos),
                    "extensions": {"KHR_lights_punctual": {"light": 0}}}]
    view = dict(eye=(0.0, 0.85, 1.25), target=(0.08, 0.08, 0.0), yfov=0.6,
                note="a glass sphere over a tiled floor, a point light")
    write(out_dir, "glass-sphere", materials, g, lights, light_nodes, **view)
    write_mitsuba(out_dir, "glass-sphere", materials, g, (lights[0], light_nodes[0]), **view)


def water(out_dir):
    half, level, wall_h = 0.6, 0.3, 0.4
    materials = [textured("pool tiles"), dielectric("water 1.33", 1.33, 0.3)]
    g = Batches()
    tiled_floor(g, 0, -half, half, -half, half, 3.0)
    # the four walls, facing into the pool, tiled (u along the wall, v up)
    k = 3.0
    walls = [((-half, 0.0, -half), (half, 0.0, -half), (0.0, 0.0, 1.0)),
             ((half, 0.0, -half), (half, 0.0, half), (-1.0, 0.0, 0.0)),
             ((half, 0.0, half), (-half, 0.0, half), (0.0, 0.0, -1.0)),
             ((-half, 0.0, half), (-half, 0.0, -half), (1.0, 0.0, 0.0))]
    for a, b, n in walls:
        corners = [a, b, (b[0], wall_h, b[2]), (a[0], wall_h, a[2])]
        u = [0.0, 2 * half * k, 2 * half * k, 0.0]
        quad_uv(g, 0, corners, n, [(u[i], corners[i][1] * k) for i in range(4)])
    water_sheet(g, 1, half, level, 96)
    pos = (0.25, 1.5, -0.2)
    lights = [{"name": "lamp", "type": "point", "color": [1.0, 0.97, 0.92], "intensity": 1.6}]
    light_nodes = [{"name": "lamp", "translation": r6(pos),
                    "extensions": {"KHR_lights_punctual": {"light": 0}}}]
    view = dict(eye=(0.0, 0.2, 0.5), target=(0.0, 0.0, -0.25), yfov=0.95,
                note="a pool with a wavy water surface, a point light")
    write(out_dir, "water", materials, g, lights, light_nodes, **view)
    write_mitsuba(out_dir, "water", materials, g, (lights[0], light_nodes[0]), **view)


def ply_bytes(pos, nor, uv, tris):
    """A binary little-endian PLY of one mesh: float32 positions, normals and (if `uv`)
    texture coordinates, triangles as uchar-counted int lists."""
    head = ["ply", "format binary_little_endian 1.0", "element vertex %d" % len(pos)]
    head += ["property float %s" % c for c in ("x", "y", "z", "nx", "ny", "nz")]
    if uv:
        head += ["property float u", "property float v"]
    head += ["element face %d" % len(tris), "property list uchar int vertex_indices",
             "end_header"]
    out = bytearray(("\n".join(head) + "\n").encode())
    for k in range(len(pos)):
        row = list(pos[k]) + list(nor[k]) + (list(uv[k]) if uv else [])
        out += struct.pack("<%df" % len(row), *row)
    for t in tris:
        out += struct.pack("<B3i", 3, *t)
    return bytes(out)


def mitsuba_camera(eye, target):
    """The 4 x 4 to_world (rows) of a Mitsuba camera where the glTF camera node is: the node's
    rounded translation and rotation (normalised) as the glTF holds them, times a half turn
    about y (Mitsuba's camera looks along +z with +x to the left)."""
    t = r6(eye)
    x, y, z, w = r6(look_along(sub(target, eye)))
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    rot = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
           [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
           [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    flip = (-1.0, 1.0, -1.0)
    return [[rot[i][j] * flip[j] for j in range(3)] + [t[i]] for i in range(3)] + \
        [[0.0, 0.0, 0.0, 1.0]]


def num(v):
    """A number for the XML: the shortest text that reads back as the same double."""
    return str(int(v)) if v == int(v) else repr(float(v))


def write_mitsuba(out_dir, name, materials, g, light, eye, target, yfov, note):
    """The Mitsuba 3 twin of a scene written by write(): NAME.xml and one NAME-MATERIAL.ply per
    material (see the module's documentation). `light`: the point light's (glTF light, node)."""
    files = {}
    bsdfs, shapes = [], []
    for m in sorted(g.pos):
        mat = materials[m]
        tag = mat["name"].split()[0]
        textured = "baseColorTexture" in mat["pbrMetallicRoughness"]
        mesh = "%s-%s.ply" % (name, tag)
        files[mesh] = ply_bytes(g.pos[m], g.nor[m], g.uv[m] if textured else None, g.tris[m])
        if textured:
            # baseColorFactor white, KHR_materials_specular 0: a Lambertian of the texture
            assert mat["pbrMetallicRoughness"]["baseColorFactor"] == [1.0, 1.0, 1.0, 1.0]
            assert mat["extensions"] == LAMBERT
            bsdfs.append(
                '  <bsdf type="diffuse" id="%s">\n'
                '    <texture type="bitmap" name="reflectance">\n'
                '      <string name="filename" value="%s"/>\n'
                '      <boolean name="raw" value="false"/>\n'
                '      <string name="filter_type" value="bilinear"/>\n'
                '      <string name="wrap_mode" value="repeat"/>\n'
                '    </texture>\n'
                '  </bsdf>' % (tag, TEXTURE))
        else:
            ext = mat["extensions"]
            assert mat["pbrMetallicRoughness"]["roughnessFactor"] == 0.0
            assert ext["KHR_materials_transmission"]["transmissionFactor"] == 1.0
            assert ext["KHR_materials_volume"]["thicknessFactor"] > 0
            bsdfs.append(
                '  <bsdf type="dielectric" id="%s">\n'
                '    <float name="int_ior" value="%s"/>\n'
                '    <float name="ext_ior" value="1"/>\n'
                '  </bsdf>' % (tag, num(ext["KHR_materials_ior"]["ior"])))
        shapes.append('  <shape type="ply">\n'
                      '    <string name="filename" value="%s"/>\n'
                      '    <ref id="%s"/>\n'
                      '  </shape>' % (mesh, tag))
    lamp, node = light
    assert lamp["type"] == "point"
    intensity = [num(lamp["intensity"] * c) for c in lamp["color"]]
    matrix = " ".join(num(v) for row in mitsuba_camera(eye, target) for v in row)
    xml = "\n".join([
        '<scene version="3.0.0">',
        '  <!-- The Mitsuba 3 twin of %s.gltf (%s),',
        '       written by tools/make_caustic_scenes.py: the same scene in the quantities',
        '       raylab reads the glTF as (see that file). 160 x 120 unless -D resx=, resy=. -->',
        '  <default name="resx" value="160"/>',
        '  <default name="resy" value="120"/>',
        '  <default name="spp" value="64"/>',
        '  <integrator type="path"><integer name="max_depth" value="-1"/></integrator>',
        '  <sensor type="perspective">',
        '    <string name="fov_axis" value="y"/>',
        '    <float name="fov" value="%s"/>' % num(math.degrees(yfov)),
        '    <transform name="to_world"><matrix value="%s"/></transform>' % matrix,
        '    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>',
        '    <film type="hdrfilm">',
        '      <integer name="width" value="$resx"/><integer name="height" value="$resy"/>',
        '      <rfilter type="box"/><string name="pixel_format" value="rgb"/>',
        '    </film>',
        '  </sensor>'] + bsdfs + shapes + [
        '  <emitter type="point">',
        '    <point name="position" value="%s"/>' % ", ".join(num(v) for v in node["translation"]),
        '    <rgb name="intensity" value="%s"/>' % ", ".join(intensity),
        '  </emitter>',
        '</scene>', '']) % (name, note)
    files[name + ".xml"] = xml.encode()
    for fname, data in files.items():
        with open(os.path.join(out_dir, fname), "wb") as f:
            f.write(data)
        print("%-22s %7d bytes" % (fname, len(data)))


def build(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    data = tiles_png()
    with open(os.path.join(out_dir, TEXTURE), "wb") as f:
        f.write(data)
    print("%-22s %7d bytes" % (TEXTURE, len(data)))
    ring(out_dir)
    glass_sphere(out_dir)
    water(out_dir)


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else DEFAULT_OUT
    if out_dir in ("-h", "--help"):
        print(__doc__)
        return
    build(out_dir)


if __name__ == "__main__":
    main()
