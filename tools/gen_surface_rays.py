#!/usr/bin/env python3
"""Surface-ray workloads: rays that start on the mesh's surface (issue 11).

An extension of ../shared/bench/gen_workloads.py (same files, same formats; see
../shared/bench/README.md), which we do not edit. numpy only.

Usage: python3 tools/gen_surface_rays.py DATA [MESH ...]     (default MESH: every DATA/mesh/*.tri
                                                             that has its incoherent reference hits)
Inputs (all little-endian):
  DATA/mesh/NAME.tri                  u32 nverts, u32 ntris, f32 xyz[nverts][3], u32 idx[ntris][3]
  DATA/rays/NAME.incoherent.rays      f32 ox oy oz dx dy dz per ray (2^20 rays)
  DATA/ref/NAME.incoherent.ref.bin    Embree's reference hits: per ray f32 t, u32 prim
                                      (miss: t = +inf, prim = 0xFFFFFFFF)
Outputs:
  DATA/rays/NAME.bounce.rays          f32 ox oy oz dx dy dz per ray, closest hit, t in [0, inf)
  DATA/rays/NAME.surface_shadow.rays  same format, any hit, t in [0, TFAR_SHADOW] (0.9999 as f32)
  DATA/rays/NAME.surface.json         counts, eps, light, tfar values, seed, these definitions

Definitions. lo/hi = float32 vertex min/max, c = (lo+hi)/2, ext = max(hi-lo) (as in the shared README).
All arithmetic in float64; the rays are cast to float32 only when written.
  For every incoherent ray i (in file order) whose reference prim != 0xFFFFFFFF, one bounce ray and
  one surface-shadow ray, both with index k = rank of i among the hitting rays (so the count N of
  either file = number of hitting incoherent rays):
  p   = o_i + t_i * d_i                         (o_i, d_i, t_i: the float32 values of the files)
  n   = normalize((v1-v0) x (v2-v0)) of triangle prim_i, flipped so that n . d_i < 0 (it faces the
        side the incoming ray came from; a zero-area triangle would take n = -d_i, none is hit)
  eps = 1e-4 * ext
  o'  = float32(p + eps * n)
    Why the offset: a renderer spawns its secondary rays from a point offset off the surface (or
    with tnear > 0) so that they do not hit their own triangle again at t ~ 0 through rounding;
    offsetting the origin once, here, lets both kernels (Embree and raylab) start from the same
    float32 point with tnear = 0, so their answers are comparable bit for bit.
  bounce:          origin o', direction = cosine-distributed about n (unit):
                     (u1, u2) = rng.random((N, 2)) with rng = numpy.random.default_rng(SEED),
                     r = sqrt(u1), phi = 2 pi u2, local (r cos phi, r sin phi, sqrt(1 - u1)),
                     world = local.x * b1 + local.y * b2 + local.z * n with (b1, b2, n) the
                     orthonormal basis of Duff et al. 2017 ("Building an orthonormal basis, revisited"),
                     renormalised; closest hit, tfar = inf.
  surface_shadow:  origin o', direction = L - o' (NOT normalised; o' the float32 origin as written),
                     L = c + (0.3, 1.0, 0.6) * ext, a point light outside the bounding box (above it:
                     L.y - hi.y >= ext / 2); any hit, tfar = float32(1 - 1e-4), so the ray stops just
                     short of the light. Points that face away from L (n . (L - o') < 0) are kept:
                     their ray crosses the surface right away and is occluded, as in a renderer that
                     does not test n . l first.
"""
import json
import os
import sys

import numpy as np

SEED = 5678
EPS_REL = 1e-4
LIGHT_OFFSET = (0.3, 1.0, 0.6)
TFAR_SHADOW = float(np.float32(1.0 - 1e-4))
MISS = 0xFFFFFFFF


def read_tri(path):
    with open(path, "rb") as fh:
        nv, nt = np.frombuffer(fh.read(8), dtype="<u4")
        v = np.frombuffer(fh.read(int(nv) * 12), dtype="<f4").reshape(-1, 3)
        f = np.frombuffer(fh.read(int(nt) * 12), dtype="<u4").reshape(-1, 3)
    return v, f


def read_rays(path):
    return np.fromfile(path, dtype="<f4").reshape(-1, 6)


def read_ref(path):
    raw = np.fromfile(path, dtype="<u4").reshape(-1, 2)
    return raw[:, 0].copy().view("<f4"), raw[:, 1]


def write_rays(path, o, d):
    rays = np.empty((len(d), 6), dtype="<f4")
    rays[:, :3] = o
    rays[:, 3:] = d
    rays.tofile(path)


def onb(n):
    """Duff et al. 2017: b1, b2 with (b1, b2, n) orthonormal, n unit, row-wise."""
    s = np.where(n[:, 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (s + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    b1 = np.stack([1.0 + s * n[:, 0] ** 2 * a, s * b, -s * n[:, 0]], axis=1)
    b2 = np.stack([b, s + n[:, 1] ** 2 * a, -n[:, 1]], axis=1)
    return b1, b2


def make(data, name):
    v32, f = read_tri(os.path.join(data, "mesh", f"{name}.tri"))
    rays = read_rays(os.path.join(data, "rays", f"{name}.incoherent.rays"))
    t32, prim = read_ref(os.path.join(data, "ref", f"{name}.incoherent.ref.bin"))
    if len(t32) != len(rays):
        raise SystemExit(f"{name}: {len(rays)} rays but {len(t32)} reference hits")
    lo = v32.min(axis=0).astype(np.float64)
    hi = v32.max(axis=0).astype(np.float64)
    c = (lo + hi) / 2
    ext = float((hi - lo).max())
    eps = EPS_REL * ext
    light = c + np.array(LIGHT_OFFSET) * ext

    hit = prim != MISS
    idx = np.nonzero(hit)[0]
    o = rays[idx, :3].astype(np.float64)
    d = rays[idx, 3:].astype(np.float64)
    t = t32[idx].astype(np.float64)
    p = o + t[:, None] * d

    v = v32.astype(np.float64)
    tri = f[prim[idx]].astype(np.int64)
    v0, v1, v2 = v[tri[:, 0]], v[tri[:, 1]], v[tri[:, 2]]
    n = np.cross(v1 - v0, v2 - v0)
    length = np.linalg.norm(n, axis=1)
    degenerate = length == 0
    n = np.where(degenerate[:, None], -d, n / np.where(degenerate, 1.0, length)[:, None])
    n = np.where((np.einsum("ij,ij->i", n, d) > 0)[:, None], -n, n)

    origin = (p + eps * n).astype(np.float32)

    rng = np.random.default_rng(SEED)
    u = rng.random((len(idx), 2))
    r = np.sqrt(u[:, 0])
    phi = 2.0 * np.pi * u[:, 1]
    b1, b2 = onb(n)
    bounce = (r * np.cos(phi))[:, None] * b1 + (r * np.sin(phi))[:, None] * b2 \
        + np.sqrt(1.0 - u[:, 0])[:, None] * n
    bounce /= np.linalg.norm(bounce, axis=1, keepdims=True)

    to_light = light - origin.astype(np.float64)

    write_rays(os.path.join(data, "rays", f"{name}.bounce.rays"), origin, bounce)
    write_rays(os.path.join(data, "rays", f"{name}.surface_shadow.rays"), origin, to_light)

    facing_away = int((np.einsum("ij,ij->i", n, to_light) < 0).sum())
    meta = {
        "mesh": f"mesh/{name}.tri",
        "source": f"rays/{name}.incoherent.rays hit by ref/{name}.incoherent.ref.bin",
        "n_incoherent": int(len(rays)),
        "n_rays": int(len(idx)),
        "n_bounce": int(len(idx)),
        "n_surface_shadow": int(len(idx)),
        "bbox_lo": lo.tolist(), "bbox_hi": hi.tolist(), "center": c.tolist(), "max_extent": ext,
        "eps": eps, "eps_rel": EPS_REL,
        "light": light.tolist(), "light_offset_rel": list(LIGHT_OFFSET),
        "tnear": 0.0,
        "tfar_bounce": "inf",
        "tfar_surface_shadow": TFAR_SHADOW,
        "seed": SEED,
        "degenerate_normals": int(degenerate.sum()),
        "shadow_points_facing_away": facing_away,
        "definitions": {
            "origin": "float32(p + eps*n), p = o + t*d of a hitting incoherent ray (float64), n the "
                      "unit geometric normal of its triangle flipped so that n.d < 0, eps = 1e-4*ext",
            "bounce": "closest hit; direction cosine-distributed about n (unit), "
                      "numpy default_rng(seed).random((N,2)); tnear 0, tfar inf",
            "surface_shadow": "any hit; direction L - origin (not normalised), "
                              "L = center + light_offset_rel*max_extent; tnear 0, tfar tfar_surface_shadow",
        },
    }
    with open(os.path.join(data, "rays", f"{name}.surface.json"), "w") as fh:
        json.dump(meta, fh, indent=1)
    print(f"{name}: {len(idx)} surface rays of {len(rays)} incoherent rays, eps={eps:.3g}, "
          f"{facing_away} shadow origins face away from the light")


def main():
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    data = sys.argv[1]
    names = sys.argv[2:]
    if not names:
        names = sorted(fn[:-4] for fn in os.listdir(os.path.join(data, "mesh")) if fn.endswith(".tri")
                       and os.path.exists(os.path.join(data, "ref", f"{fn[:-4]}.incoherent.ref.bin")))
    for name in names:
        make(data, name)


if __name__ == "__main__":
    main()
