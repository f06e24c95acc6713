#!/usr/bin/env python3
"""raylab's emissive media against pbrt-v4's: a glowing cube, and a glowing grid.

    PYTHONPATH=$BPY/5.2/python/lib/python3.13/site-packages LD_LIBRARY_PATH=$BPY/lib \
        VENV/bin/python tools/pbrt_glow.py --pbrt PATH/pbrt [--raylab target/release/raylab]
            [--kelvin 1500,2400,4000,6500] [--sigma 0.4] [--spp 64] [--grid-spp 1024]

(VENV: a venv with numpy and OpenEXR, e.g. the one ../shared/cycles/setup.sh makes, whose
bpy wheel's `openvdb` module writes the grid's `.vdb`; without `openvdb` the grid part is
skipped.)

1. A cube [-1, 1]^3 holding a homogeneous medium that absorbs (sigma_a = --sigma, no
scattering) and glows with a blackbody's colour at luminance 1 at each --kelvin (pbrt-v4:
`"blackbody Le" K`, which it divides by the spectrum's luminance; raylab: `temperature =
K` in the scene file's `[[medium]]`), seen straight on from afar (an 8-degree perspective
camera 20 units away, the same in both) under a black sky. The middle of the cube's face
shows `Le (1 - exp(-2 sigma))` (the chord is 2 to 0.03 %): the two renderers must agree on how a medium emits (pbrt-v4's
sigma_a Le per unit length) and on the blackbody's RGB (pbrt-v4 integrates the spectrum
against the CIE 1931 curves into its film's linear sRGB). Prints, per temperature, the
mean RGB of the face's middle in each renderer, their ratio, and the closed form.

2. A 16^3 grid of density and temperature (smooth puffs, zero on the border), purely
absorbing, glowing by its temperatures (`(T - 150) x 9` kelvin, times Lescale 0.05):
pbrt-v4's `uniformgrid` medium with "temperature", "Lescale", "temperatureoffset" and
"temperaturescale" against raylab's `.vdb` volume with `temperature`,
`temperature_offset`, `temperature_scale` and `emission_scale`, the same voxels placed
alike (OpenVDB's voxel centres at integer indices, pbrt's samples at cell centres of its
p0..p1 box). Prints the mean RGB over the grid's image in each renderer and their ratio.

pbrt-v4 is built by ../shared/pbrt-v4/setup.sh (CPU only).
"""
import argparse
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def read_exr(path):
    """An RGB EXR as a float array (OpenEXR's Python module)."""
    import OpenEXR
    import Imath

    f = OpenEXR.InputFile(str(path))
    dw = f.header()["dataWindow"]
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    chans = [np.frombuffer(f.channel(c, pt), np.float32).reshape(h, w) for c in "RGB"]
    return np.stack(chans, -1)


# The cube [-1, 1]^3: corners (x fastest), then quads facing out.
CORNERS = [(x, y, z) for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)]
QUADS = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
CUBE_OBJ = "".join(f"v {x} {y} {z}\n" for x, y, z in CORNERS) + "".join(
    "f " + " ".join(str(i + 1) for i in q) + "\n" for q in QUADS)


def cube_pbrt(lo, hi):
    """The box [lo, hi]^3 as a pbrt-v4 triangle mesh facing out."""
    points = " ".join(f"{lo if x < 0 else hi} {lo if y < 0 else hi} {lo if z < 0 else hi}"
                      for x, y, z in CORNERS)
    tris = " ".join(f"{a} {b} {c}  {a} {c} {d}" for a, b, c, d in QUADS)
    return f'Shape "trianglemesh" "point3 P" [ {points} ] "integer indices" [ {tris} ]\n'


def run(cmd, **kw):
    """Runs `cmd`; on failure, exits with its error output."""
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        sys.exit(f"pbrt_glow: {' '.join(map(str, cmd))} failed:\n{r.stderr}{r.stdout}")
    return r


def grid_values(n):
    """Density and temperature on an n^3 grid (x fastest when flattened in C order of
    [z][y][x]): smooth puffs, zero on the border."""
    i = np.arange(n)
    z, y, x = np.meshgrid(i, i, i, indexing="ij")
    c = (n - 1) / 2
    r2 = ((x - c) ** 2 + (y - c) ** 2 + (z - c) ** 2) / (0.42 * n) ** 2
    density = np.clip(1 - r2, 0, None) * (1 + 0.5 * np.sin(x * 0.9) * np.cos(y * 0.7))
    hot = ((x - c - 2) ** 2 + (y - c + 1) ** 2 + (z - c) ** 2) / (0.3 * n) ** 2
    temperature = 150 + 300 * np.clip(1 - hot, 0, None)
    for g in (density, temperature):
        g[0, :, :] = g[-1, :, :] = g[:, 0, :] = g[:, -1, :] = g[:, :, 0] = g[:, :, -1] = 0
    return density.astype(np.float32), temperature.astype(np.float32)


def grid_part(a, tmp):
    """Part 2: the glowing grid in both renderers."""
    try:
        import openvdb as vdb
    except ImportError:
        print("(no openvdb module: the grid part is skipped)")
        return
    n, voxel, size = 16, 0.125, 48
    density, temperature = grid_values(n)
    grids = []
    for name, values in (("density", density), ("temperature", temperature)):
        g = vdb.FloatGrid()
        # OpenVDB's arrays are indexed [x][y][z].
        g.copyFromArray(np.ascontiguousarray(values.transpose(2, 1, 0)), ijk=(0, 0, 0),
                        tolerance=0)
        g.name = name
        g.gridClass = vdb.GridClass.FOG_VOLUME
        g.transform = vdb.createLinearTransform(voxel)
        grids.append(g)
    vdb.write(str(tmp / "glow.vdb"), grids=grids)
    centre = (n - 1) / 2 * voxel
    scale, offset, t_scale, le_scale = 6.0, 150.0, 9.0, 0.05
    camera = f"[{centre}, {centre}, 20]", f"[{centre}, {centre}, {centre}]"
    (tmp / "grid.toml").write_text(
        f"[render]\nwidth = {size}\nheight = {size}\nspp = {a.grid_spp}\nmax_depth = 4\n\n"
        "[environment]\ncolor = [0, 0, 0]\n\n"
        f"[camera]\nposition = {camera[0]}\ntarget = {camera[1]}\nfov = 8\n\n"
        f"[[medium]]\ntype = \"vdb\"\nfile = \"glow.vdb\"\ngrid = \"density\"\n"
        f"density = {scale}\ncolor = [0, 0, 0]\ntemperature = \"temperature\"\n"
        f"temperature_offset = {offset}\ntemperature_scale = {t_scale}\n"
        f"emission_scale = {le_scale}\n")
    run([a.raylab, "render", str(tmp / "grid.toml"), "--seed", str(a.seed), "-o", str(tmp / "rg.exr")])
    flat = lambda g: " ".join(f"{v:.6g}" for v in g.reshape(-1))
    lo, hi = -0.5 * voxel, (n - 0.5) * voxel
    box = cube_pbrt(lo, hi)
    (tmp / "grid.pbrt").write_text(
        # (pbrt's camera space is left-handed: mirrored in x, it sees what raylab sees.)
        "Scale -1 1 1\n"
        f"LookAt {centre} {centre} 20  {centre} {centre} {centre}  0 1 0\n"
        "Camera \"perspective\" \"float fov\" 8\n"
        f"Sampler \"independent\" \"integer pixelsamples\" {a.grid_spp} \"integer seed\" {a.seed}\n"
        "PixelFilter \"box\"\n"
        "Integrator \"volpath\" \"integer maxdepth\" 4\n"
        f"Film \"rgb\" \"integer xresolution\" {size} \"integer yresolution\" {size}\n"
        f"    \"string filename\" \"{tmp / 'pg.exr'}\"\n"
        "WorldBegin\n"
        "MakeNamedMedium \"glow\" \"string type\" \"uniformgrid\"\n"
        f"    \"integer nx\" {n} \"integer ny\" {n} \"integer nz\" {n}\n"
        f"    \"float density\" [ {flat(density)} ]\n"
        f"    \"float temperature\" [ {flat(temperature)} ]\n"
        f"    \"float Lescale\" [ {flat(np.full(n ** 3, le_scale))} ]\n"
        f"    \"float temperatureoffset\" {offset} \"float temperaturescale\" {t_scale}\n"
        f"    \"rgb sigma_a\" [ 1 1 1 ] \"rgb sigma_s\" [ 0 0 0 ] \"float scale\" {scale}\n"
        f"    \"point3 p0\" [ {lo} {lo} {lo} ] \"point3 p1\" [ {hi} {hi} {hi} ]\n"
        "AttributeBegin\n"
        "  MediumInterface \"glow\" \"\"\n"
        "  Material \"interface\"\n"
        f"  {box}"
        "AttributeEnd\n")
    run([a.pbrt, "--quiet", str(tmp / "grid.pbrt")], cwd=tmp)
    ours, theirs = read_exr(tmp / "rg.exr"), read_exr(tmp / "pg.exr")
    m_ours, m_theirs = ours.reshape(-1, 3).mean(0), theirs.reshape(-1, 3).mean(0)
    fmt = lambda v: ", ".join(f"{x:.4g}" for x in v)
    print(f"\ngrid {n}^3, {a.grid_spp} spp, mean over the {size} x {size} image:")
    print(f"raylab {fmt(m_ours)}; pbrt-v4 {fmt(m_theirs)}; raylab / pbrt-v4 "
          f"{fmt(m_ours / m_theirs)}")
    # Per 8 x 8 block, where the glow is not faint.
    b = lambda im: im.reshape(size // 8, 8, size // 8, 8, 3).mean((1, 3))
    bo, bt = b(ours), b(theirs)
    lum = lambda im: im @ np.array([0.2126, 0.7152, 0.0722])
    keep = lum(bt) > 0.02 * lum(bt).max()
    rel = np.abs(lum(bo)[keep] / lum(bt)[keep] - 1)
    print(f"8 x 8 blocks above 2 % of the brightest ({keep.sum()}): luminance ratio "
          f"within {rel.max() * 100:.1f} % (mean {rel.mean() * 100:.1f} %)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pbrt", required=True, help="pbrt-v4's pbrt binary")
    ap.add_argument("--raylab", default=str(ROOT / "target/release/raylab"))
    ap.add_argument("--kelvin", default="1500,2400,4000,6500")
    ap.add_argument("--sigma", type=float, default=0.4)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--grid-spp", type=int, default=4096)
    ap.add_argument("--seed", type=int, default=1, help="both renderers' seed")
    a = ap.parse_args()
    size = 48
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "cube.obj").write_text(CUBE_OBJ)
        print(f"cube of sigma_a {a.sigma}: closed form Le (1 - exp(-2 sigma)) = Le x "
              f"{1 - math.exp(-2 * a.sigma):.5f}; middle 16 x 16 pixels of {size} x {size}")
        print("| K | raylab R, G, B | pbrt-v4 R, G, B | raylab / pbrt-v4 |")
        print("| ---: | --- | --- | --- |")
        for k in [float(x) for x in a.kelvin.split(",")]:
            (tmp / "glow.toml").write_text(
                f"[render]\nwidth = {size}\nheight = {size}\nspp = {a.spp}\nmax_depth = 4\n\n"
                "[environment]\ncolor = [0, 0, 0]\n\n"
                "[camera]\nposition = [0, 0, 20]\ntarget = [0, 0, 0]\nfov = 8\n\n"
                "[[model]]\nname = \"cube\"\nfile = \"cube.obj\"\n"
                "materials = { \"*\" = \"glass:1.0\" }\n\n"
                f"[[medium]]\ntype = \"inside\"\nmodel = \"cube\"\ndensity = {a.sigma}\n"
                f"color = [0, 0, 0]\ntemperature = {k}\n")
            run([a.raylab, "render", str(tmp / "glow.toml"), "-o", str(tmp / "raylab.exr")])
            (tmp / "glow.pbrt").write_text(
                "LookAt 0 0 20  0 0 0  0 1 0\n"
                "Camera \"perspective\" \"float fov\" 8\n"
                f"Sampler \"independent\" \"integer pixelsamples\" {a.spp}\n"
                "Integrator \"volpath\" \"integer maxdepth\" 4\n"
                f"Film \"rgb\" \"integer xresolution\" {size} \"integer yresolution\" {size}\n"
                f"    \"string filename\" \"{tmp / 'pbrt.exr'}\"\n"
                "WorldBegin\n"
                "MakeNamedMedium \"glow\" \"string type\" \"homogeneous\"\n"
                f"    \"rgb sigma_a\" [ {a.sigma} {a.sigma} {a.sigma} ] \"rgb sigma_s\" [ 0 0 0 ]\n"
                f"    \"blackbody Le\" {k}\n"
                "AttributeBegin\n"
                "  MediumInterface \"glow\" \"\"\n"
                "  Material \"interface\"\n"
                f"  {cube_pbrt(-1, 1)}"
                "AttributeEnd\n")
            run([a.pbrt, "--quiet", str(tmp / "glow.pbrt")], cwd=tmp)
            mid = slice(size // 2 - 8, size // 2 + 8)
            ours = read_exr(tmp / "raylab.exr")[mid, mid].reshape(-1, 3).mean(0)
            theirs = read_exr(tmp / "pbrt.exr")[mid, mid].reshape(-1, 3).mean(0)
            ratio = [o / t if t > 0 else float("nan") for o, t in zip(ours, theirs)]
            fmt = lambda v: ", ".join(f"{x:.4g}" for x in v)
            print(f"| {k:.0f} | {fmt(ours)} | {fmt(theirs)} | {fmt(ratio)} |")
        grid_part(a, tmp)
    return 0


if __name__ == "__main__":
    sys.exit(main())
