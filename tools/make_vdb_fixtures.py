#!/usr/bin/env python3
"""Writes the OpenVDB fixtures of tests/data/vdb/ with OpenVDB's own writer
(the `openvdb` module Blender's `bpy` wheel ships) and, beside each, the
values OpenVDB reads back: `NAME.vdb.json` with the grid's name, its
index-to-world matrix (row vectors, OpenVDB's convention) and voxels
`[i, j, k, value]` sampled over and around the grid.

    PYTHONPATH=$BPY/5.2/python/lib/python3.13/site-packages LD_LIBRARY_PATH=$BPY/lib \\
        VENV/bin/python tools/make_vdb_fixtures.py [OUT_DIR]

where BPY is the venv's site-packages/bpy (shared/cycles/setup.sh makes the venv).
"""
import json
import math
import random
import sys
from pathlib import Path

import numpy as np
import openvdb as vdb

out = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent.parent / "tests/data/vdb")
out.mkdir(parents=True, exist_ok=True)


def blob(n, seed):
    """A smooth puff of density on an n^3 array, 0 at its border."""
    rng = np.random.default_rng(seed)
    x = np.linspace(-1, 1, n)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    d = np.zeros((n, n, n), np.float32)
    for _ in range(4):
        c = rng.uniform(-0.4, 0.4, 3)
        r = rng.uniform(0.3, 0.5)
        d += np.clip(1 - ((X - c[0]) ** 2 + (Y - c[1]) ** 2 + (Z - c[2]) ** 2) / r**2, 0, None) * rng.uniform(0.5, 2)
    return d.astype(np.float32)


def record(name, grid, extra=None, points=()):
    path = out / f"{name}.vdb"
    grids = [grid] + (extra or [])
    vdb.write(str(path), grids=grids)
    # Read it back with OpenVDB, as a reader of the file sees it.
    back = vdb.read(str(path), grid.name)
    acc = back.getConstAccessor()
    lo, hi = back.evalActiveVoxelBoundingBox()
    rng = random.Random(7)
    voxels = []
    for _ in range(400):
        p = [rng.randint(lo[k] - 9, hi[k] + 9) for k in range(3)]
        voxels.append(p + [float(acc.getValue(tuple(p)))])
    for p in points:
        voxels.append(list(p) + [float(acc.getValue(tuple(p)))])
    # Every active voxel of the first few leaves too (exact values, not just 0).
    for v in list(back.citerOnValues())[:200]:
        if v.count == 1:
            p = list(v.min)
            voxels.append(p + [float(v.value)])
    m = back.transform.indexToWorld((0, 0, 0)), back.transform.indexToWorld((1, 0, 0)), \
        back.transform.indexToWorld((0, 1, 0)), back.transform.indexToWorld((0, 0, 1))
    matrix = [[m[k + 1][j] - m[0][j] for j in range(3)] for k in range(3)] + [list(m[0])]
    info = {"grid": grid.name, "index_to_world_rows": matrix, "voxels": voxels}
    (out / f"{name}.vdb.json").write_text(json.dumps(info) + "\n")
    print(f"{path}: {path.stat().st_size} bytes, {back.leafCount()} leaves")


def float_grid(array, name="density", origin=(0, 0, 0), half=False, kind=vdb.FloatGrid):
    g = kind()
    g.copyFromArray(array, ijk=origin, tolerance=0)
    g.name = name
    g.gridClass = vdb.GridClass.FOG_VOLUME
    g.saveFloatAsHalf = half
    return g


# A puff of 24^3 voxels placed off the origin (negative indices too), voxel
# size 0.05 and a translation: a scale-translate map; blosc (OpenVDB's default).
g = float_grid(blob(24, 1), origin=(-13, 2, -5))
g.transform = vdb.createLinearTransform([[0.05, 0, 0, 0], [0, 0.05, 0, 0], [0, 0, 0.05, 0], [0.3, -0.2, 1.5, 1]])
record("puff", g)

# The same saved as half floats.
g = float_grid(blob(20, 2), half=True)
g.transform = vdb.createLinearTransform(0.1)
record("puff-half", g)

# A rotated, sheared grid: an affine map; doubles.
a = math.radians(30)
g = float_grid(blob(16, 3).astype(np.float64), kind=vdb.DoubleGrid)
g.transform = vdb.createLinearTransform([[math.cos(a) * 0.1, math.sin(a) * 0.1, 0, 0],
                                         [-math.sin(a) * 0.1, math.cos(a) * 0.1, 0.02, 0],
                                         [0, 0, 0.2, 0], [1, 2, 3, 1]])
record("rotated-double", g)

# Constant regions stored as tiles: a filled box of 160^3 voxels (internal
# node tiles of 128^3 and 8^3) with a puff beside it.
g = float_grid(blob(12, 4), origin=(200, 0, 0))
g.fill((0, 0, 0), (159, 159, 159), 0.25, True)
g.prune()
record("tiles", g)

# Inactive voxels holding values other than the background: a leaf with one
# such value, one with two, one with three (mask compression's cases: one
# inactive value stored, two and a selection mask, or every value).
g = float_grid(blob(24, 7))
acc = g.getAccessor()
for (i, j, k), v in [((1, 1, 1), 0.5), ((1, 2, 1), 0.5),
                     ((9, 9, 9), 0.5), ((9, 10, 9), 0.75),
                     ((17, 17, 17), 0.5), ((17, 18, 17), 0.75), ((18, 18, 17), 1.25)]:
    acc.setValueOff((i, j, k), v)
record("inactive", g, points=[(1, 1, 1), (1, 2, 1), (9, 9, 9), (9, 10, 9), (17, 17, 17),
                             (17, 18, 17), (18, 18, 17), (1, 1, 2), (9, 9, 10)])

# Two grids: the density is found by its name, after a temperature grid.
t = float_grid(blob(8, 5) * 300, name="temperature")
d = float_grid(blob(8, 6), name="density")
record("two-grids", d, extra=[t])
vdb.write(str(out / "two-grids.vdb"), grids=[t, d])

# A level set (a sphere's signed distance): not a density.
s = vdb.createLevelSetSphere(radius=1.0, center=(0, 0, 0), voxelSize=0.5, halfWidth=2.0)
s.name = "surface"
vdb.write(str(out / "level-set.vdb"), grids=[s])
print("level-set.vdb")
