#!/usr/bin/env python3
"""raylab against Blender Cycles on the `.vdb` cloud (scenes/cloud/cloud.xml and
tools/cycles_cloud.py), in one run: interleaved rounds at the same spp, each
image's relMSE against a reference (Mitsuba's, from tools/compare_mitsuba.py's
cache), and the time each renderer needs to reach a given error.

    python3 tools/compare_cycles_cloud.py --ref REF.exr [--spp 32] [--rounds 2]
        [--raylab target/release/raylab] [--venv CYCLES_VENV] [--mi-venv MITSUBA_VENV]

Both renderers use 2 threads. raylab's seconds are its whole process; Cycles'
are `bpy.ops.render.render` only (Blender's start and the .vdb import left out).
Images are read with the OpenEXR module of --mi-venv. Results: docs/media.md.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

here = os.path.dirname(os.path.abspath(__file__))
root = os.path.dirname(here)
ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--ref", required=True, help="reference EXR of cloud.xml at 320x180")
ap.add_argument("--spp", type=int, default=32)
ap.add_argument("--rounds", type=int, default=2)
ap.add_argument("--raylab", default=os.path.join(root, "target/release/raylab"))
ap.add_argument("--venv", default="../venv-cy", help="CPython 3.13 venv with bpy")
ap.add_argument("--mi-venv", default="../venv-mi", help="a venv with numpy and OpenEXR")
a = ap.parse_args()

if os.environ.get("RAYLAB_CLOUD_CHILD") != "1":
    # Re-run inside the venv that has numpy and OpenEXR.
    env = dict(os.environ, RAYLAB_CLOUD_CHILD="1")
    sys.exit(subprocess.call([os.path.join(a.mi_venv, "bin/python"), *sys.argv], env=env))

import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402
import Imath  # noqa: E402


def read(path):
    f = OpenEXR.InputFile(path)
    dw = f.header()["dataWindow"]
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    return np.stack([np.frombuffer(f.channel(c, pt), np.float32).reshape(h, w) for c in "RGB"], -1)


def rel_mse(img, ref):
    """As assets/refs/README.md (and raylab::film::rel_mse) define it."""
    eps = 0.01 * ref.mean() ** 2
    return float((((img - ref) ** 2) / (ref * ref + eps)).mean())


ref = read(a.ref)
tmp = tempfile.mkdtemp(prefix="raylab-cloud-")
rows = {"raylab": [], "cycles": []}
for r in range(a.rounds):
    for who in rows:
        out = os.path.join(tmp, f"{who}-{r}.exr")
        if who == "raylab":
            t0 = time.perf_counter()
            subprocess.run([a.raylab, "render", os.path.join(root, "scenes/cloud/cloud.xml"),
                            f"-Dspp={a.spp}", "--spp", str(a.spp), "--seed", str(r + 1),
                            "--threads", "2", "-o", out, "-q"], check=True)
            secs = time.perf_counter() - t0
        else:
            p = subprocess.run([os.path.join(a.venv, "bin/python"), os.path.join(here, "cycles_cloud.py"),
                                os.path.join(root, "scenes/cloud/cloud.vdb"), "-o", out,
                                "--spp", str(a.spp), "--threads", "2", "--seed", str(r + 1)],
                               check=True, capture_output=True, text=True)
            secs = json.loads(p.stdout.strip().splitlines()[-1])["seconds"]
        img = read(out)
        e = rel_mse(img, ref)
        rows[who].append((secs, e))
        print(f"round {r + 1}: {who:6} {a.spp} spp {secs:7.2f} s relMSE {e:.3e} "
              f"mean/reference {img.mean() / ref.mean():.4f}", flush=True)
t = {}
print("\n| renderer | seconds (best) | c = relMSE x spp | time to a relMSE E |\n| --- | ---: | ---: | ---: |")
for who, rs in rows.items():
    best = min(s for s, _ in rs)
    c = float(np.mean([e for _, e in rs])) * a.spp
    t[who] = c * best / a.spp
    print(f"| {who} | {best:.2f} | {c:.3f} | {t[who]:.4f} / E |")
print(f"\nraylab / Cycles time to the same error: {t['raylab'] / t['cycles']:.2f}")
