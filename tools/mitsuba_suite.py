#!/usr/bin/env python3
"""Mitsuba 3's render test suite on raylab's images (issue 43).

Runs every scene of a mitsuba-data checkout's `tests/scenes/<group>/*.xml`
that has an RGB reference (`refs/<name>_ref_rgb.exr` and its per-sample
variance `_ref_rgb_var.exr`), outside `participating_media` (with
`--media`: that group alone, issue 44), through
`raylab render` at Mitsuba's sample budget (spp = 2e6 // pixels, seed 0),
and applies Mitsuba's own test (`src/render/tests/test_renders.py` of
mitsuba-renderer/mitsuba3), written here from its definition:

* both images converted from linear sRGB to XYZ (the variance image by the
  same matrix, as Mitsuba's `Bitmap.convert` does);
* per pixel and channel, z = |raylab − reference| · sqrt(spp / max(var, 1e-4)),
  p = 2 (1 − Φ(z));
* a pixel-channel passes when p > α = 1 − (1 − 0.01)^(1/pixels) (Šidák);
* the scene passes when at least 99.75 % of the pixel-channels pass.

    python3 tools/mitsuba_suite.py --data ~/mitsuba-data [--only bsdf_spheres]
        [--raylab target/release/raylab] [--out DIR] [--budget 2000000]

The same test on scenes without references (raylab's own,
tests/data/mitsuba/suite/, which CI runs): `--scenes DIR --mitsuba PYTHON`
renders each scene's reference with Mitsuba 3 (`scalar_rgb`, the `moment`
integrator's mean and per-sample variance, seed 1, `--ref-spp` samples) by
the Python interpreter PYTHON that has the `mitsuba` package (3.7.1 is the
version raylab is checked with), caches it under `--cache` (keyed by the
scene's text, its files' and the sample count), then tests raylab's image
against it as above. The reference's own noise then counts too: the test
uses the reference's variance over `spp` plus over `ref_spp`.

Needs numpy and OpenEXR (`pip install numpy OpenEXR`). Prints one line per
scene and a summary; exits 1 if any scene fails or cannot be rendered
(unless --keep-going-ok). Scenes raylab refuses (a plugin it does not read
yet) are listed as "refused" with raylab's one-line reason.
"""

import argparse
import hashlib
import json
import math
import os
import subprocess
import sys
import time

import numpy as np
import OpenEXR

# Linear sRGB (Rec. 709, D65) to CIE XYZ: the matrix of Mitsuba's srgb_to_xyz.
RGB_TO_XYZ = np.array(
    [
        [0.412453, 0.357580, 0.180423],
        [0.212671, 0.715160, 0.072169],
        [0.019334, 0.119193, 0.950227],
    ]
)
SIGNIFICANCE = 0.01
PASS_FRACTION = 0.9975
VARIANCE_FLOOR = 1e-4


def read_rgb(path):
    """The R, G and B channels of an EXR file as an (h, w, 3) float64 array."""
    with OpenEXR.File(path) as f:
        channels = f.channels()
        if "RGB" in channels:
            return np.asarray(channels["RGB"].pixels, dtype=np.float64)[..., :3]
        if "RGBA" in channels:
            return np.asarray(channels["RGBA"].pixels, dtype=np.float64)[..., :3]
        return np.stack(
            [np.asarray(channels[c].pixels, dtype=np.float64) for c in "RGB"], axis=-1
        )


def to_xyz(rgb):
    return rgb @ RGB_TO_XYZ.T


def z_test(image, spp, reference, variance):
    """Mitsuba's per-pixel-channel p-values."""
    variance = np.maximum(variance, VARIANCE_FLOOR)
    z = np.abs(image - reference) * np.sqrt(spp / variance)
    # 2 (1 − Φ(z)) = erfc(z / √2)
    erfc = np.vectorize(math.erfc)
    return erfc(z / math.sqrt(2.0))


# Run by the interpreter that has Mitsuba: renders one scene's reference
# (mean and per-sample variance, in XYZ as Mitsuba's moment integrator
# gives them) into an .npz file.
MITSUBA_SCRIPT = r"""
import sys, numpy as np, mitsuba as mi
scene_path, integrator, spp, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
mi.set_variant("scalar_rgb")
text = open(scene_path).read()
kwargs = {}
if "$spp" in text: kwargs["spp"] = spp
if "$integrator" in text: kwargs["integrator"] = integrator
scene = mi.load_file(scene_path, **kwargs)
scene.integrator().render(scene, seed=1, spp=spp, develop=True)
bmp = scene.sensors()[0].film().bitmap(raw=False)
split = bmp.split()
if len(split) < 3:
    sys.exit("the scene's integrator is not wrapped in a moment integrator")
m1 = np.array(split[1][1], copy=True).astype(np.float64)
m2 = np.array(split[2][1], copy=True).astype(np.float64)
np.savez(out, mean=m1, var=np.maximum(m2 - m1 * m1, 0.0), version=mi.__version__)
"""


def own_scenes(folder):
    for name in sorted(os.listdir(folder)):
        if name.endswith(".xml"):
            stem = name[:-4]
            yield os.path.join(folder, name), stem.rsplit("_", 1)[1]


def mitsuba_reference(python, scene, integrator, spp, cache):
    """The cached or newly rendered Mitsuba reference (mean, var in XYZ)."""
    h = hashlib.sha256()
    h.update(open(scene, "rb").read())
    folder = os.path.dirname(scene)
    for root, _, files in sorted(os.walk(folder)):
        for f in sorted(files):
            if not f.endswith(".xml"):
                h.update(f.encode())
                h.update(open(os.path.join(root, f), "rb").read())
    h.update(f"{integrator} {spp}".encode())
    os.makedirs(cache, exist_ok=True)
    path = os.path.join(cache, f"{os.path.basename(scene)[:-4]}-{h.hexdigest()[:16]}.npz")
    if not os.path.exists(path):
        tmp = path + ".tmp.npz"
        start = time.time()
        r = subprocess.run([python, "-c", MITSUBA_SCRIPT, scene, integrator, str(spp), tmp[:-4]],
                           capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"Mitsuba could not render {scene}: {r.stderr.strip()[-2000:]}")
        os.replace(tmp, path)
        print(f"# Mitsuba reference of {os.path.basename(scene)}: {spp} spp, {time.time() - start:.1f} s", flush=True)
    data = np.load(path)
    return data["mean"], data["var"]


def scenes(data, only, media):
    root = os.path.join(data, "tests", "scenes")
    for group in sorted(os.listdir(root)):
        if (group == "participating_media") != media:
            continue
        folder = os.path.join(root, group)
        if not os.path.isdir(folder):
            continue
        for name in sorted(os.listdir(folder)):
            if not name.endswith(".xml") or (only and only not in f"{group}/{name}"):
                continue
            stem = name[:-4]
            base, integrator = stem.rsplit("_", 1)
            ref = os.path.join(folder, "refs", f"{base}_ref_rgb.exr")
            var = ref.replace(".exr", "_var.exr")
            if os.path.exists(ref) and os.path.exists(var):
                yield group, os.path.join(folder, name), integrator, ref, var


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", help="a mitsuba-data checkout")
    ap.add_argument("--scenes", help="a folder of scenes without references (raylab's own)")
    ap.add_argument("--mitsuba", help="a Python interpreter with the mitsuba package (for --scenes)")
    ap.add_argument("--cache", default="mitsuba-suite-cache", help="where --scenes' references go")
    ap.add_argument("--ref-spp", type=int, default=16384, help="samples per pixel of --scenes' references")
    ap.add_argument("--raylab", default="target/release/raylab")
    ap.add_argument("--only", help="only scenes whose group/file name contains this")
    ap.add_argument("--out", default="mitsuba-suite-out", help="where renders go")
    ap.add_argument("--budget", type=int, default=2_000_000, help="samples per image")
    ap.add_argument("--media", action="store_true",
                    help="run the participating_media group (only it) instead of the others")
    args = ap.parse_args()
    if bool(args.data) == bool(args.scenes):
        ap.error("give either --data (Mitsuba's suite) or --scenes (with --mitsuba)")
    if args.scenes and not args.mitsuba:
        ap.error("--scenes needs --mitsuba PYTHON (an interpreter with the mitsuba package)")
    os.makedirs(args.out, exist_ok=True)
    results = []
    if args.data:
        jobs = [
            (f"{group}/{os.path.basename(scene)}", scene, integrator, (ref, var), 0)
            for group, scene, integrator, ref, var in scenes(args.data, args.only, args.media)
        ]
    else:
        jobs = [
            (os.path.basename(scene), scene, integrator, None, args.ref_spp)
            for scene, integrator in own_scenes(args.scenes)
            if not args.only or args.only in scene
        ]
    for name, scene, integrator, refs, ref_spp in jobs:
        if refs:
            reference = to_xyz(read_rgb(refs[0]))
            variance = to_xyz(read_rgb(refs[1]))
        else:
            reference, variance = mitsuba_reference(args.mitsuba, scene, integrator, ref_spp, args.cache)
        h, w = reference.shape[:2]
        pixels = h * w
        spp = args.budget // pixels
        out = os.path.join(args.out, os.path.basename(scene)[:-4] + ".exr")
        text = open(scene, encoding="utf-8", errors="replace").read()
        cmd = [args.raylab, "render", scene, "--spp", str(spp), "--seed", "0", "-o", out]
        if "$spp" in text:
            cmd += ["-D", f"spp={spp}"]
        if "$integrator" in text:
            cmd += ["-D", f"integrator={integrator}"]
        # A scene of ours may ask for raylab options in a comment line
        # `raylab-suite-args: NAME=VALUE ...` (each becomes `--NAME VALUE`;
        # say, Mitsuba's uniform choice among lights, where the z-test's
        # premise, raylab's variance no larger than Mitsuba's, needs it).
        for line in text.splitlines():
            if "raylab-suite-args:" in line:
                for arg in line.split("raylab-suite-args:", 1)[1].replace("-->", "").split():
                    option, _, value = arg.partition("=")
                    cmd += [f"--{option}", value]
        start = time.time()
        run = subprocess.run(cmd, capture_output=True, text=True)
        seconds = time.time() - start
        if run.returncode != 0:
            reason = (run.stderr.strip().splitlines() or ["(no message)"])[-1]
            results.append((name, "refused", None, None, seconds, reason))
            print(f"REFUSED {name}: {reason}", flush=True)
            continue
        image = to_xyz(read_rgb(out))
        if image.shape != reference.shape:
            results.append((name, "fail", 0.0, None, seconds, f"size {image.shape} != {reference.shape}"))
            print(f"FAIL    {name}: image size {image.shape[:2]} != reference {reference.shape[:2]}")
            continue
        # With a reference of ref_spp samples, its own noise adds: the
        # variance of the difference is var/spp + var/ref_spp.
        effective = spp if not ref_spp else 1.0 / (1.0 / spp + 1.0 / ref_spp)
        p = z_test(image, effective, reference, variance)
        alpha = 1.0 - (1.0 - SIGNIFICANCE) ** (1.0 / pixels)
        passed = np.count_nonzero(p > alpha) / 3 / pixels
        ok = passed >= PASS_FRACTION
        rel = float(np.mean((image - reference) ** 2) / max(np.mean(reference**2), 1e-12))
        status = "pass" if ok else "fail"
        note = f"{100 * passed:.2f}% pixel-channels pass, min p {p.min():.2e} (α {alpha:.2e}), spp {spp}, relMSE {rel:.2e}"
        results.append((name, status, passed, float(p.min()), seconds, note))
        print(f"{status.upper():7} {name}: {note}, {seconds:.1f} s", flush=True)
        if not ok:
            bad = (p <= alpha).any(axis=-1)
            np.save(os.path.join(args.out, os.path.basename(scene)[:-4] + "_fail_mask.npy"), bad)
    n = len(results)
    passed = sum(1 for r in results if r[1] == "pass")
    refused = sum(1 for r in results if r[1] == "refused")
    print(f"\n{passed} of {n} scenes pass, {n - passed - refused} fail, {refused} refused")
    sys.exit(0 if passed == n and n > 0 else 1)


if __name__ == "__main__":
    main()
