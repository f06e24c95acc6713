#!/usr/bin/env python3
"""A procedural flame as an OpenVDB file with two float grids, `density`
(soot and gas, in [0, 1]) and `temperature` (in [0, 1]: a scene scales it to
kelvin), for emissive media (docs/media.md, scenes/fire/fire.toml).

    PYTHONPATH=$BPY/5.2/python/lib/python3.13/site-packages LD_LIBRARY_PATH=$BPY/lib \\
        VENV/bin/python tools/make_fire_vdb.py OUT.vdb [--res 96] [--seed 3]

(BPY: the `bpy` folder of a venv that `shared/cycles/setup.sh` made; its
`openvdb` module writes the file.) The flame rises from a disc of radius
0.35 at y = 0 to about y = 2, `--res` voxels across its 1.2 wide base
(2.5 times as many tall); its tongues are fractal noise that rises with
it. The temperature is highest low in its core and falls with height and
with distance from the axis; the density is thin in the hot core and
thickens into smoke above it.
"""
import argparse
import sys

import numpy as np
import openvdb as vdb

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("out")
ap.add_argument("--res", type=int, default=96)
ap.add_argument("--seed", type=int, default=3)
a = ap.parse_args()

nx = nz = a.res
ny = int(a.res * 2.5)
voxel = 1.2 / a.res
rng = np.random.default_rng(a.seed)

# Voxel centres: x, z in [-0.6, 0.6], y in [0, 3].
x = (np.arange(nx) - nx / 2 + 0.5) * voxel
y = (np.arange(ny) + 0.5) * voxel
z = (np.arange(nz) - nz / 2 + 0.5) * voxel
X, Y, Z = np.meshgrid(x, y, z, indexing="ij")


def turbulence(shape, smooth):
    """Band-limited noise of unit variance: white noise low-passed in
    frequency by exp(-(k * smooth)^2)."""
    spec = np.fft.rfftn(rng.standard_normal(shape).astype(np.float32))
    freqs = [np.fft.fftfreq(n) for n in shape[:-1]] + [np.fft.rfftfreq(shape[-1])]
    k2 = sum(np.meshgrid(*[f * f for f in freqs], indexing="ij"))
    spec *= np.exp(-k2 * smooth * smooth)
    out = np.fft.irfftn(spec, s=shape, axes=(0, 1, 2)).astype(np.float32)
    return (out - out.mean()) / out.std()


h = Y / 2.0  # height along the flame, 0 at its base, 1 at its tip
# Sideways tongues: the axis sways with height, the radius flickers.
sway_x = 0.06 * np.sin(5.0 * Y + 1.0) * h
sway_z = 0.05 * np.cos(4.0 * Y) * h
radius = 0.35 * np.clip(1.0 - h, 0.0, None) ** 0.6 + 0.02
noise = 0.6 * turbulence((nx, ny, nz), 6.0) + 0.4 * turbulence((nx, ny, nz), 2.0)
r = np.sqrt((X - sway_x) ** 2 + (Z - sway_z) ** 2)
inside = 1.0 - r / radius + 0.35 * noise * (0.3 + h)
flame = np.clip(inside * 2.5, 0.0, 1.0)
temperature = (flame * np.clip(1.0 - 0.75 * h, 0.0, 1.0) ** 0.8).astype(np.float32)
# Smoke: a wider column above the flame's middle.
smoke_r = 0.25 + 0.2 * h
smoke = np.clip((1.0 - r / smoke_r + 0.4 * noise) * 2.0, 0.0, 1.0) * np.clip((h - 0.45) * 2.0, 0.0, 1.0)
density = np.clip(0.35 * flame + 0.8 * smoke, 0.0, 1.0).astype(np.float32)
for g in (density, temperature):
    g[0, :, :] = g[-1, :, :] = 0
    g[:, 0, :] = g[:, -1, :] = 0
    g[:, :, 0] = g[:, :, -1] = 0

grids = []
for name, values in (("density", density), ("temperature", temperature)):
    g = vdb.FloatGrid()
    g.copyFromArray(values, ijk=(-nx // 2, 0, -nz // 2), tolerance=0)
    g.name = name
    g.gridClass = vdb.GridClass.FOG_VOLUME
    g.transform = vdb.createLinearTransform(voxel)
    grids.append(g)
vdb.write(a.out, grids=grids)
print(f"{a.out}: {nx}x{ny}x{nz} voxels, density {grids[0].activeVoxelCount()} active, "
      f"temperature {grids[1].activeVoxelCount()} active", file=sys.stderr)
