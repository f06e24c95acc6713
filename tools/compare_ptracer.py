#!/usr/bin/env python3
"""raylab's `bdpt` against Mitsuba 3's light tracer `ptracer` on a scene with caustics.

Usage (with the Python of a venv that has `mitsuba` and `numpy`; the raylab binary built):

    /path/to/venv/bin/python tools/compare_ptracer.py --xml SCENE.xml [--raylab PATH]
        [--ref-spp 16384] [--spp 64,256,1024] [--max-depth N] [--out DIR] [--threads N]

A path tracer (raylab's and Mitsuba's `path`) cannot find light from a point or spot
light that reaches a diffuse surface through a delta lobe (glass, a mirror): such a
caustic has zero probability from the camera. Mitsuba's `ptracer` traces paths from the
lights only and splats them onto the image, so it finds those caustics and is a
reference independent of raylab; but it cannot see a specular surface from the camera
(black there). So the two are compared on the pixels that see diffuse surfaces: those
whose 3 × 3 neighbourhood is lit in Mitsuba's reference (which leaves out the specular
surfaces and the pixels on their edges).

The reference is Mitsuba's `ptracer` at --ref-spp (with the `max_depth` of the file's
integrator unless --max-depth is given, for both renderers; unbounded if neither says) in two halves, whose difference gives its own noise. raylab renders
the same file with `--integrator bdpt --filter box` at each --spp (and `path` at the
largest, to show what it misses). The file's film should use `<rfilter type="box"/>`:
raylab's `bdpt` renders with the box filter only. For each render the tool prints the
ratio of its mean to the reference's over the mask, in each of a 4 × 4 grid of image
cells that has enough masked pixels, and the relMSE over the mask (mean of
(c − r)² / (r² + 0.01·mean(r)²)), which for an unbiased render falls as 1/spp down to
the reference's own noise. Images are written to --out.

DRJIT_LIBLLVM_PATH, unless set, is /usr/lib/x86_64-linux-gnu/libLLVM-19.so.
"""

import argparse
import os
import re
import subprocess
import sys
import time

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")


def load_exr(mi, np, path):
    """An EXR's RGB as a float64 array (rows, columns, 3)."""
    bitmap = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)
    return np.array(bitmap, dtype=np.float64)[..., :3]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--xml", required=True, help="the Mitsuba 3 scene")
    parser.add_argument("--raylab", default="target/release/raylab")
    parser.add_argument("--ref-spp", type=int, default=16384)
    parser.add_argument("--spp", default="64,256,1024")
    parser.add_argument("--max-depth", type=int, default=None)
    parser.add_argument("--out", default="ptracer-out")
    parser.add_argument("--threads", type=int, default=None)
    args = parser.parse_args()
    try:
        import numpy as np
        import mitsuba as mi
    except ImportError as e:
        sys.exit(f"error: this Python lacks {e.name}: run the tool with a venv that has mitsuba and numpy")
    mi.set_variant("llvm_ad_rgb")
    if not os.path.isfile(args.xml):
        sys.exit(f"error: no scene file {args.xml}")
    if not os.access(args.raylab, os.X_OK):
        sys.exit(f"error: no raylab binary at {args.raylab} (cargo build --release)")
    os.makedirs(args.out, exist_ok=True)
    spps = [int(s) for s in args.spp.split(",")]

    # Mitsuba's light tracer, in two halves.
    scene = mi.load_file(args.xml)
    depth = args.max_depth
    if depth is None:
        # The file's integrator's, else unbounded.
        found = re.search(r'<integrator[^>]*>\s*<integer\s+name="max_depth"\s+value="(-?\d+)"',
                          open(args.xml).read())
        depth = int(found.group(1)) if found else -1
    integrator = mi.load_dict({"type": "ptracer", "max_depth": depth})
    halves = []
    start = time.time()
    for seed in (1, 2):
        image = mi.render(scene, integrator=integrator, spp=args.ref_spp // 2, seed=seed)
        halves.append(np.array(image, dtype=np.float64)[..., :3])
    ref = 0.5 * (halves[0] + halves[1])
    print(f"Mitsuba ptracer: {args.ref_spp} spp (max_depth {depth}) in {time.time() - start:.1f} s")
    mi.Bitmap(ref.astype(np.float32)).write(os.path.join(args.out, "mitsuba-ptracer.exr"))

    lit = ref.mean(-1) > 0
    mask = lit.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            mask &= np.roll(np.roll(lit, dy, 0), dx, 1)
    mask[0, :] = mask[-1, :] = mask[:, 0] = mask[:, -1] = False
    eps = 0.01 * ref[mask].mean() ** 2

    def rel_mse(a, b):
        return float(((a - b) ** 2 / (b ** 2 + eps))[mask].mean())

    print(f"mask: {mask.sum()} of {mask.size} pixels see lit diffuse surfaces")
    print(f"the reference's own relMSE (half against half / 4): {rel_mse(halves[0], halves[1]) / 4:.3e}")

    def cells(image):
        h, w = mask.shape
        out = []
        for i in range(4):
            row = []
            for j in range(4):
                m = mask[i * h // 4:(i + 1) * h // 4, j * w // 4:(j + 1) * w // 4]
                if m.sum() < 0.25 * m.size:
                    row.append("   -  ")
                    continue
                a = image[i * h // 4:(i + 1) * h // 4, j * w // 4:(j + 1) * w // 4][m].mean()
                b = ref[i * h // 4:(i + 1) * h // 4, j * w // 4:(j + 1) * w // 4][m].mean()
                row.append(f"{a / b:6.3f}")
            out.append(" ".join(row))
        return out

    runs = [("bdpt", s) for s in spps] + [("path", max(spps))]
    for name, spp in runs:
        path = os.path.join(args.out, f"raylab-{name}-{spp}.exr")
        cmd = [args.raylab, "render", args.xml, "--integrator", name, "--filter", "box",
               "--spp", str(spp), "-o", path, "-q"]
        if args.threads:
            cmd += ["--threads", str(args.threads)]
        if depth >= 1:
            cmd += ["--max-depth", str(depth)]
        start = time.time()
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0:
            sys.exit(f"error: {' '.join(cmd)}: {done.stderr.strip()}")
        seconds = time.time() - start
        image = load_exr(mi, np, path)
        ratio = image[mask].mean() / ref[mask].mean()
        print(f"raylab {name} {spp} spp ({seconds:.1f} s): mean over the mask {ratio:.4f} of "
              f"Mitsuba's, relMSE {rel_mse(image, ref):.3e}; by cell:")
        for line in cells(image):
            print("    " + line)


if __name__ == "__main__":
    main()
