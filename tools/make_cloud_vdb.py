#!/usr/bin/env python3
"""A procedural cumulus cloud as an OpenVDB file (float grid `density`), and
the same grid as a Mitsuba `.vol` for Mitsuba, which reads no `.vdb`.

    PYTHONPATH=$BPY/5.2/python/lib/python3.13/site-packages LD_LIBRARY_PATH=$BPY/lib \\
        VENV/bin/python tools/make_cloud_vdb.py OUT.vdb [--vol OUT.vol] [--res 256] [--seed 1]

(BPY: the `bpy` folder of a venv that `shared/cycles/setup.sh` made; its
`openvdb` module writes the file.) The cloud is a union of spheres eroded by
fractal noise, `--res` voxels wide (0.6 as tall and deep), a voxel being
2/res units: it spans about [-1, 1] x [-0.6, 0.6] x [-0.6, 0.6], its density
in [0, 1] (a scene scales it).

The `.vol` holds the voxels of the grid's active box and one voxel of zeros
around it, cell-centred as Mitsuba reads them; its header's box is that of
the cells in world space, so that `use_grid_bbox` places it where raylab
places the `.vdb` by its transform: the same trilinear field (beyond the
zero border both are 0).
"""
import argparse
import struct
import sys

import numpy as np
import openvdb as vdb

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("out")
ap.add_argument("--vol")
ap.add_argument("--res", type=int, default=256)
ap.add_argument("--seed", type=int, default=1)
a = ap.parse_args()

nx, ny, nz = a.res, int(a.res * 0.6), int(a.res * 0.6)
voxel = 2.0 / a.res
rng = np.random.default_rng(a.seed)


def fractal(shape, beta):
    """Gaussian noise with a 1/f^beta spectrum, unit variance."""
    w = rng.standard_normal(shape).astype(np.float32)
    f = np.fft.rfftn(w)
    k = [np.fft.fftfreq(n) for n in shape[:-1]] + [np.fft.rfftfreq(shape[-1])]
    K = np.sqrt(sum(np.meshgrid(*[kk**2 for kk in k], indexing="ij")))
    K[0, 0, 0] = 1.0
    f *= K ** (-beta)
    n = np.fft.irfftn(f, s=shape).astype(np.float32)
    return (n - n.mean()) / n.std()


# World coordinates of voxel centres (index i -> (i - n/2) * voxel).
x = (np.arange(nx) - nx / 2) * voxel
y = (np.arange(ny) - ny / 2) * voxel
z = (np.arange(nz) - nz / 2) * voxel
X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
shape = np.full((nx, ny, nz), -1.0, np.float32)
# A flat-bottomed heap of puffs.
for _ in range(14):
    c = np.array([rng.uniform(-0.6, 0.6), rng.uniform(-0.25, 0.15), rng.uniform(-0.3, 0.3)])
    r = rng.uniform(0.18, 0.38)
    d = np.sqrt((X - c[0]) ** 2 + (Y - c[1]) ** 2 + (Z - c[2]) ** 2) / r
    shape = np.maximum(shape, 1.0 - d)
shape = np.where(Y < -0.35, shape - (-0.35 - Y) * 8, shape)
noise = fractal((nx, ny, nz), 1.6)
density = np.clip((shape + 0.35 * noise) * 3.0, 0.0, 1.0).astype(np.float32)
density[0, :, :] = density[-1, :, :] = 0
density[:, 0, :] = density[:, -1, :] = 0
density[:, :, 0] = density[:, :, -1] = 0

g = vdb.FloatGrid()
g.copyFromArray(density, ijk=(-nx // 2, -ny // 2, -nz // 2), tolerance=0)
g.name = "density"
g.gridClass = vdb.GridClass.FOG_VOLUME
g.transform = vdb.createLinearTransform(voxel)
vdb.write(a.out, grids=[g])
lo, hi = g.evalActiveVoxelBoundingBox()
print(f"{a.out}: {nx}x{ny}x{nz} voxels, {g.activeVoxelCount()} active, {g.leafCount()} leaves, "
      f"active box {lo}..{hi}", file=sys.stderr)

if a.vol:
    lo = np.array(lo)
    hi = np.array(hi)
    n = hi - lo + 3  # one voxel of zeros each side
    dense = np.zeros(tuple(n), np.float32)
    src = density[tuple(slice(l + d, h + d + 1) for l, h, d in zip(lo, hi, (nx // 2, ny // 2, nz // 2)))]
    dense[1:-1, 1:-1, 1:-1] = src
    # Cells: sample k sits at index lo - 1 + k, so the unit cube spans
    # [lo - 1.5, hi + 1.5] in index space.
    box_lo = (lo - 1.5) * voxel
    box_hi = (hi + 1.5) * voxel
    with open(a.vol, "wb") as f:
        f.write(b"VOL" + bytes([3]))
        f.write(struct.pack("<i", 1))
        f.write(struct.pack("<3i", *[int(v) for v in n]))
        f.write(struct.pack("<i", 1))
        f.write(struct.pack("<6f", *box_lo, *box_hi))
        # x fastest, then y, then z.
        f.write(np.ascontiguousarray(dense.transpose(2, 1, 0)).tobytes())
    print(f"{a.vol}: {n[0]}x{n[1]}x{n[2]} samples, box {box_lo} .. {box_hi}", file=sys.stderr)
