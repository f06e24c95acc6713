#!/usr/bin/env python3
"""raylab against Blender Cycles (CPU) on glTF scenes: error, time and error × time, noisy and
denoised, each renderer judged against its own converged image.

Usage (from the project folder; the raylab binary must be built, ../shared beside the project for
the Cycles peer):

    python3 tools/compare_cycles.py [--scenes helmet-venice,showcase,cornell-glass,street,glass-lamps]
                                    [--spp 16,64] [--rounds 1] [--threads 2] [--ref-spp 1024]
                                    [--modes noisy,denoised] [--raylab-integrator path|bdpt|vcm]
                                    [--size 320x240] [--box-size 256x256] [--json PATH]
                                    [--raylab PATH] [--venv DIR] [--shared DIR] [--cache DIR]
                                    [--previews DIR] [--fresh-refs] [--timeout S]
                                    [--ladder 8,12,16,...] [--target-spp 16]
    python3 tools/compare_cycles.py --curve [--curve-spp 1,2,4,...,1024] [--curve-ref-spp 4096]
                                    [--csv PATH] [--plot docs/denoise-curve.png] [--scenes ...]
    python3 tools/compare_cycles.py --adaptive 0.1,0.03,0.01 [--adaptive-spp 1024] [--scenes ...]
                                    [--rounds 1] [--ref-spp 1024] [--json PATH] ...

Scenes (glTF 2.0, read by both renderers under docs/scene-conventions.md):
  helmet-venice  scenes/helmet-venice/helmet-venice.gltf (the DamagedHelmet, helmet-hdri.toml's
                 camera) under assets/envmaps/venice_sunset_1k.hdr turned 200° (both renderers
                 get `--env FILE --env-rotate 200`), --size (default 320×240);
  showcase       scenes/showcase/showcase.gltf (spot, sun, point and emissive lights, metals, glass,
                 textures), --size;
  cornell-glass  scenes/cornell-glass/cornell-glass.gltf (the lab box under its ceiling patch with a
                 mirror and a glass block, tools/make_cornell_glass.py), --box-size (default 256×256);
  street         scenes/street/street.gltf (a night street and plaza: about 2,000 small emissive
                 lamps, 50 spot and 2 point lights, five DamagedHelmets, no environment;
                 tools/make_street.py), --size;
  glass-lamps    scenes/glass-lamps/glass-lamps.gltf (small bright emissive spheres inside clear
                 glass tubes and a glass pane on a table with a high-frequency mosaic texture, two
                 point lights; made to fool a denoiser's blend, issue 42; tools/make_glass_lamps.py),
                 --size.
  showcase-fog   the showcase in fog (issue 44): raylab `--fog 0.15` (extinction 0.15 per unit,
                 all scattering, isotropic, over the meshes' bounding box); Cycles through
                 tools/cycles_fog.py, a Volume Scatter box of density 0.15 over the same box
                 (volume bounces as many as the others); not with --adaptive.
  caustic-ring   scenes/caustics/ring.gltf (issue 45: a polished gold ring on a table under a
                 spot light from the side: the cardioid caustic inside it;
                 tools/make_caustic_scenes.py), --size;
  caustic-glass  scenes/caustics/glass-sphere.gltf (a solid glass sphere over a tiled floor under
                 a point light: the focused caustic beside its shadow), --size;
  caustic-water  scenes/caustics/water.gltf (a pool seen from under its wavy water surface, one
                 refracting sheet, lit by a point light above: the net of caustics on the floor
                 and walls), --size.
  The default --scenes is all but the fog and caustic scenes. Every light of the caustic scenes is
  a punctual light of radius 0 on both sides (render_gltf.py sets shadow_soft_size 0): a path
  tracer finds none of their caustics, raylab's `bdpt` (light tracing) does, Cycles only through
  MNEE and only the refracted ones (see below).

Caustic scenes: raylab renders them with `--integrator bdpt` (--raylab-integrator overrides that
for every scene, e.g. `path` for its caustic-less image; bdpt takes the flags below: box filter,
no tiles, no adaptive sampling), and Cycles in each of its fair configurations, through
tools/cycles_caustics.py (render_gltf.py wrapped, as for the fog; see that script):
  Cycles               render_gltf.py unchanged (path guiding off, MNEE off);
  Cycles guiding       path guiding on (surface and volume, Blender's defaults: 128 training
                       samples, taken by the render itself, so counted in its time);
  Cycles MNEE          caustic-glass and caustic-water: manifold next-event estimation, the
                       light a caustics light, the glass/water a caustics caster, the other
                       meshes receivers (Cycles' MNEE does refraction only: not for the ring);
  Cycles MNEE+guiding  both.
  Configurations that differ only in guiding share one converged reference (guiding changes the
  noise, not the mean); MNEE has its own (it adds the caustic plain Cycles misses). The table lists
  every configuration, marks with ★ Cycles' best one per measure (lowest error × seconds) and
  gives raylab ÷ that one, then whether issue 45's target holds: raylab's error × seconds at most
  0.5 × the best Cycles configuration's, on both measures, at each spp. SCENE-refs.png has a row
  per Cycles reference. The two renderers' converged images of the ring (and, without MNEE, of
  the others) differ by the caustic itself: each is judged against its own.

Renderers, same size, same threads (--threads, default 2), same seeds:
  raylab  `raylab render SCENE --spp N --threads T --seed S --width W --height H
          --default-light off [--env F --env-rotate D] [--integrator bdpt] [--denoise] -o out.exr`,
          from a copy of the
          binary made at the start (a rebuild during the run changes nothing). Time: the render time
          of its summary line on stderr (`wrote out.exr: WxH, path, N spp, T ms, ...`: path tracing
          only, without loading the scene, building the BVH or writing the file). Denoised
          (`--denoise`: the EXR's RGB is the denoised image, layers noisy.R/G/B the noisy one, and
          the summary line ends in `; denoised in D ms by OIDN ...`): time T + D. Until
          `raylab render --help` lists --denoise, the denoised rows say "n/a (raylab has no
          --denoise)" and everything else runs.
  Cycles  ../shared/cycles/render_gltf.py (Blender 5.2.3 Cycles, CPU, threads FIXED, COMPAT light
          units, single-scatter GGX, box filter 1 px, adaptive sampling, clamping and denoising off,
          Blender's default blue-noise sampling pattern kept) in the CPython 3.13 venv of
          ../shared/cycles/setup.sh. Time: `cycles_path_trace_s` of its JSON line (Cycles' own
          render time from the EXR header, 10 ms resolution; without scene synchronization: BVH,
          shaders, textures, environment map). Denoised (`--denoise`: OIDN on the CPU, albedo +
          normal, prefilter accurate, quality high): a second render with the same seed; its
          `cycles_path_trace_s` includes the denoising (checked: the same render with --denoise
          takes longer by the OIDN time, e.g. 1.53 s → 1.93 s at 256×256, 16 spp; the table's
          footnote gives that difference, measured in the run, as "Cycles' denoise ≈").
  With equal spp the blue-noise pattern favours Cycles at low spp; raylab's `sobol` sampler is
  Owen-scrambled Sobol' for the pixel and the first two bounces.

Errors, each renderer against its own converged render (their BSDFs and samplers differ in detail,
so neither is the other's truth): rendered once per scene and renderer at --ref-spp (default 1024,
as two independent halves with different seeds, averaged; their difference gives the reference's
own noise, printed beside the table: it adds to every error) and cached in --cache under a key
hashed from the scene's files, the map, the size, the spp and the renderer (raylab: not the
binary, so that rebuilding does not re-render; the binary's hash is recorded and a warning printed
when it differs; --fresh-refs re-renders).
  relMSE  per pixel the mean over channels of (c − r)² / (r² + ε), ε = 0.01 · mean(r)² (mean over
          all pixels and channels), then the per-pixel values clamped at their 99.9th percentile
          (the worst 0.1 % of the pixels count as that quantile: fireflies do not dominate), mean.
  FLIP    mean LDR FLIP (PyPI flip-evaluator, default 67 pixels per degree) between the two images
          after one fixed display transform for every image: exposure 0, the Khronos PBR Neutral
          tone mapper (as raylab's `--tonemap khronos-pbr-neutral`), clamp to [0, 1], sRGB encoding.
  Figure of merit: error × seconds (lower is better; for relMSE it does not depend on spp while
  the error falls as 1/spp), and the ratio raylab ÷ Cycles (below 1: raylab is more efficient).

Measurements: --rounds rounds (default 1); in round k every scene, spp and mode (--modes, default
noisy and denoised) is rendered by both renderers (every Cycles configuration) with seed k, alternating which renderer goes first. The table gives
the best (smallest) time and the worst (largest) error of the rounds. All runs go into the JSON file
(--json, default CACHE/compare_cycles-last.json). The two renderers' converged images are also
compared with each other (mean ratio, 8×8-block mean |relative difference|), and PNG previews are
written to --previews (default CACHE/previews): `SCENE-refs.png` = raylab | Cycles | their
luminance ratio (blue: raylab darker, red: brighter, ±20 % full scale; a row per Cycles reference),
and `SCENE-SPPspp.png` = raylab noisy | raylab denoised | Cycles noisy | Cycles denoised of round 1
(the modes of --modes; then the same for every further Cycles configuration of the scene).

--ladder A,B,...: raylab --denoise is also rendered at these spp in every round (right after the
scene's other runs), and a table gives, per scene, the fewest of them whose worst errors (both
measures) are at most Cycles+OIDN's worst at --target-spp (default 16), with its best time over
Cycles+OIDN's best time: how soon raylab's denoised image is as good as Cycles'.

--adaptive T1,T2,...: adaptive sampling at equal noise thresholds. Per round, scene and threshold T:
  raylab adaptive  `raylab render SCENE --spp CAP --noise-threshold T ...` (CAP = --adaptive-spp,
                   default 1024); its average samples per pixel from the summary line's
                   `N.N spp on average` (the cap when the line has none, marked ‡). Until
                   `raylab render --help` lists --noise-threshold these rows say n/a and the rest
                   runs (raylab's fixed run then takes Cycles' adaptive average, marked *);
  Cycles adaptive  render_gltf.py through tools/cycles_adaptive.py, which turns on
                   scene.cycles.use_adaptive_sampling with adaptive_threshold T,
                   adaptive_min_samples 0 (Cycles' automatic minimum, Blender's default) and
                   samples CAP (render_gltf.py turns adaptive sampling off and lives in ../shared,
                   so it is wrapped, not edited); the average samples per pixel from Cycles'
                   "Debug Sample Count" pass (see that script: a compositor File Output node writes
                   the pass, the render's sample count comes from Cycles' progress reports). If
                   it cannot be read the row shows "?", the time is still compared, and Cycles'
                   fixed run is skipped;
  raylab fixed, Cycles fixed  each renderer with adaptive sampling off at the spp of its own
                   adaptive run's average, rounded: adaptive against fixed at an equal sample
                   budget.
  Each against its own --ref-spp reference, as above (they are the same cached files). The table
  gives per scene and threshold the mean spp, the best seconds, the worst relMSE and FLIP and
  their products with the seconds for the four runs, and the ratios raylab adaptive ÷ raylab
  fixed, Cycles adaptive ÷ Cycles fixed (below 1: adaptive sampling pays) and raylab adaptive ÷
  Cycles adaptive. Previews: SCENE-adaptive-T.png = raylab adaptive | raylab fixed | Cycles
  adaptive | Cycles fixed (round 1). JSON: --json, default CACHE/compare_cycles-adaptive-last.json.
  --spp, --ladder and the denoised runs are not used.

--curve: raylab only. For each scene, renders at --curve-spp (default 1, 2, 4, ..., 1024), noisy and
denoised (one `--denoise` run gives both, from the same samples; without --denoise only the noisy
curve), measures both errors against raylab's own --curve-ref-spp render (default 4096, cached),
writes a CSV (--csv, default CACHE/denoise_curve.csv) and a plot (--plot, default
CACHE/denoise_curve.png; e.g. docs/denoise-curve.png): relMSE and FLIP against spp, noisy solid,
denoised dashed. It lists every point where the denoised image is worse than the noisy one (by
more than 0.2 %: smaller differences, where the blend kept the noisy image all but everywhere, are
listed as ties) and then exits with status 3.

Set-up: the tool needs numpy, OpenEXR, flip-evaluator and matplotlib, and Cycles needs bpy in a
CPython 3.13 venv. If this Python cannot import them, the tool re-runs itself with --venv's Python
(default ~/.cache/raylab-cycles-venv), creating that venv first with ../shared/cycles/setup.sh
(downloads ~400 MB of bpy from PyPI) and adding flip-evaluator and matplotlib with pip.
Temporary files go to a temporary folder that is removed at the end (also on Ctrl-C or SIGTERM);
every render has a time limit (--timeout, default 3600 s). Errors are one line and exit status 1.
"""

import argparse
import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_SHARED = os.path.normpath(os.path.join(ROOT, "..", "shared"))
DEFAULT_VENV = os.path.join(os.path.expanduser("~"), ".cache", "raylab-cycles-venv")
DEFAULT_CACHE = os.path.normpath(os.path.join(ROOT, "..", "bench-data", "cycles"))
MODULES = ("numpy", "OpenEXR", "flip_evaluator", "matplotlib")
EXTRA_PIP = ("flip-evaluator", "matplotlib")
REEXEC = "COMPARE_CYCLES_REEXEC"
PROG = "compare_cycles"

# name: (glTF file in the project, environment map under assets/ or None, rotation, box?,
#        fog density or None)
SCENES = {
    "helmet-venice": ("scenes/helmet-venice/helmet-venice.gltf",
                      "envmaps/venice_sunset_1k.hdr", 200.0, False, None),
    "showcase": ("scenes/showcase/showcase.gltf", None, 0.0, False, None),
    "cornell-glass": ("scenes/cornell-glass/cornell-glass.gltf", None, 0.0, True, None),
    "street": ("scenes/street/street.gltf", None, 0.0, False, None),
    "glass-lamps": ("scenes/glass-lamps/glass-lamps.gltf", None, 0.0, False, None),
    "showcase-fog": ("scenes/showcase/showcase.gltf", None, 0.0, False, 0.15),
    "caustic-ring": ("scenes/caustics/ring.gltf", None, 0.0, False, None),
    "caustic-glass": ("scenes/caustics/glass-sphere.gltf", None, 0.0, False, None),
    "caustic-water": ("scenes/caustics/water.gltf", None, 0.0, False, None),
}
# The caustic scenes (issue 45): raylab's integrator by default, and Cycles' configurations
# through tools/cycles_caustics.py: name -> (label, wrapper flags). "Cycles" (no flags) is
# render_gltf.py unchanged. MNEE only where a refracting object casts the caustic (it does
# nothing for the ring's metal).
CAUSTICS_WRAPPER = os.path.join(ROOT, "tools", "cycles_caustics.py")
CYCLES_GUIDING = [("Cycles", []), ("Cycles guiding", ["--guiding"])]
CYCLES_MNEE = CYCLES_GUIDING + [("Cycles MNEE", ["--mnee"]),
                                ("Cycles MNEE+guiding", ["--mnee", "--guiding"])]
CAUSTIC_SCENES = {"caustic-ring": ("bdpt", CYCLES_GUIDING),
                  "caustic-glass": ("bdpt", CYCLES_MNEE),
                  "caustic-water": ("bdpt", CYCLES_MNEE)}
INTEGRATORS = ("path", "bdpt", "vcm")
REF_SEED = 1 << 20
ADAPTIVE_WRAPPER = os.path.join(ROOT, "tools", "cycles_adaptive.py")
FOG_WRAPPER = os.path.join(ROOT, "tools", "cycles_fog.py")
# --curve: a denoised error at most this fraction above the noisy one is a tie, not worse.
TIE = 0.002


class Fail(Exception):
    """A failure to report as one line."""


def log(msg):
    print("# " + msg, file=sys.stderr, flush=True)


def one_line(text, limit=400):
    lines = [x.strip() for x in (text or "").strip().splitlines() if x.strip()]
    s = lines[-1] if lines else ""
    return s if len(s) <= limit else s[:limit] + " ..."


# ----------------------------------------------------------------------------------------------
# Set-up: find or make the venv, then run inside it.


def default_raylab():
    here = os.path.join(ROOT, "target", "release", "raylab")
    main = os.path.join(ROOT, "..", "main", "target", "release", "raylab")
    return here if os.path.exists(here) or not os.path.exists(main) else main


def missing_modules():
    import importlib.util
    return [m for m in MODULES if importlib.util.find_spec(m) is None]


def ensure_venv(args):
    shared = os.path.abspath(args.shared)
    script = os.path.join(shared, "cycles", "render_gltf.py")
    setup = os.path.join(shared, "cycles", "setup.sh")
    if not os.path.isfile(script):
        raise Fail(f"{script} not found: ../shared (the Cycles peer) must sit beside the project "
                   "folder, or pass --shared DIR")
    venv = os.path.abspath(args.venv)
    py = os.path.join(venv, "bin", "python")
    inside = os.path.realpath(sys.prefix) == os.path.realpath(venv)
    if inside:
        missing = missing_modules()
        if missing and not os.environ.get(REEXEC + "_PIP"):
            log(f"installing {' '.join(EXTRA_PIP)} into {venv} (pip)")
            r = subprocess.run([py, "-m", "pip", "install", "-q", *EXTRA_PIP])
            if r.returncode != 0:
                raise Fail(f"could not install {' '.join(EXTRA_PIP)} into {venv}; try "
                           f"{py} -m pip install {' '.join(EXTRA_PIP)}")
            os.environ[REEXEC + "_PIP"] = "1"
            os.execv(py, [py, os.path.abspath(__file__)] + sys.argv[1:])
        if missing:
            raise Fail(f"{py} cannot import {', '.join(missing)}")
        import importlib.util
        if importlib.util.find_spec("bpy") is None:
            raise Fail(f"the venv {venv} has no bpy: make it with {setup} {venv}")
        return
    if os.environ.get(REEXEC):
        raise Fail(f"re-ran with {sys.executable} but it is not the venv {venv}")
    if not os.path.exists(py):
        if args.no_setup:
            raise Fail(f"no venv at {venv}: make it with {setup} {venv} (or drop --no-setup)")
        log(f"creating the Cycles venv {venv} with {setup} (CPython 3.13, ~400 MB of bpy from "
            "PyPI, once)")
        r = subprocess.run(["bash", setup, venv])
        if r.returncode != 0 or not os.path.exists(py):
            raise Fail(f"{setup} {venv} failed (exit {r.returncode}); see its messages above")
    os.environ[REEXEC] = "1"
    os.execv(py, [py, os.path.abspath(__file__)] + sys.argv[1:])


# ----------------------------------------------------------------------------------------------
# Images and errors (numpy, inside the venv).


def read_exr(path):
    """{'rgb': HxWx3, 'noisy': HxWx3 if the file has noisy.R/G/B} as float64."""
    import numpy as np
    import OpenEXR

    try:
        with OpenEXR.File(path, separate_channels=True) as f:
            ch = f.channels()
            out = {}
            for key, prefix in (("rgb", ""), ("noisy", "noisy.")):
                names = [prefix + c for c in "RGB"]
                if all(n in ch for n in names):
                    out[key] = np.stack([np.asarray(ch[n].pixels, dtype=np.float64)
                                         for n in names], -1)
    except Exception as e:  # noqa: BLE001 - one line for any reader failure
        raise Fail(f"cannot read {path}: {e}")
    if "rgb" not in out:
        raise Fail(f"{path} has no R, G, B channels (has {', '.join(sorted(ch))})")
    return out


def write_exr(path, img):
    import numpy as np
    import OpenEXR

    img = np.asarray(img, dtype=np.float32)
    chans = {c: np.ascontiguousarray(img[:, :, i]) for i, c in enumerate("RGB")}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    tmp = path + f".{os.getpid()}.tmp"
    with OpenEXR.File(header, chans) as f:
        f.write(tmp)
    os.replace(tmp, path)


def finite(img, what, notes):
    import numpy as np

    bad = ~np.isfinite(img)
    if bad.any():
        notes.append(f"{what}: {int(bad.sum())} non-finite values set to 0")
        img = np.where(bad, 0.0, img)
    return img


def rel_mse_clamped(img, ref, quantile=99.9):
    """Per pixel mean over channels of (c − r)²/(r² + ε), ε = 0.01·mean(r)²; the per-pixel values
    clamped at their 99.9th percentile; mean."""
    import numpy as np

    eps = 0.01 * float(ref.mean()) ** 2
    e = (((img - ref) ** 2) / (ref * ref + eps)).mean(axis=2)
    cap = np.percentile(e, quantile)
    return float(np.minimum(e, cap).mean())


def pbr_neutral(c):
    """Khronos PBR Neutral, as src/film/tonemap.rs (and its specification) give it."""
    import numpy as np

    f90, ks, kd = 0.04, 0.8 - 0.04, 0.15
    c = np.maximum(c, 0.0)
    x = c.min(axis=2, keepdims=True)
    f = np.where(x <= 2 * f90, x - x * x / (4 * f90), f90)
    c = c - f
    p = c.max(axis=2, keepdims=True)
    pn = 1 - (1 - ks) ** 2 / (p + 1 - 2 * ks)
    g = 1 / (kd * (p - pn) + 1)
    safe_p = np.where(p > 0, p, 1.0)
    high = c * (pn / safe_p * g) + pn * (1 - g)
    return np.clip(np.where(p <= ks, c, high), 0.0, 1.0)


def display(img):
    """The one display transform of every image: exposure 0, PBR Neutral, clamp, sRGB encoding."""
    import numpy as np

    x = pbr_neutral(img)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def flip_mean(img, ref):
    import flip_evaluator
    import numpy as np

    r = np.ascontiguousarray(display(ref), dtype=np.float32)
    t = np.ascontiguousarray(display(img), dtype=np.float32)
    _, mean, _ = flip_evaluator.evaluate(r, t, "LDR", inputsRGB=True, applyMagma=False)
    return float(mean)


def errors(img, ref):
    return {"relmse": rel_mse_clamped(img, ref), "flip": flip_mean(img, ref)}


def luminance(img):
    return img[:, :, 0] * 0.2126 + img[:, :, 1] * 0.7152 + img[:, :, 2] * 0.0722


def save_png(path, rows_of_images, gap=4):
    """Images (HxWx3 display values in [0, 1]) side by side, rows stacked, white gaps."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.image as mimg
    import numpy as np

    strips = []
    for row in rows_of_images:
        h = max(i.shape[0] for i in row)
        parts = []
        for k, i in enumerate(row):
            if k:
                parts.append(np.ones((h, gap, 3)))
            pad = np.ones((h, i.shape[1], 3))
            pad[: i.shape[0]] = i
            parts.append(pad)
        strips.append(np.concatenate(parts, axis=1))
    w = max(s.shape[1] for s in strips)
    out = []
    for k, s in enumerate(strips):
        if k:
            out.append(np.ones((gap, w, 3)))
        pad = np.ones((s.shape[0], w, 3))
        pad[:, : s.shape[1]] = s
        out.append(pad)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    mimg.imsave(path, np.clip(np.concatenate(out, axis=0), 0, 1))


def ratio_map(a, b, span=0.2, block=8):
    """Luminance ratio a/b per block×block block as colours: white 1, red > 1, blue < 1."""
    import matplotlib
    import numpy as np

    h, w = a.shape[:2]
    hb, wb = h // block * block, w // block * block
    la = luminance(a)[:hb, :wb].reshape(hb // block, block, wb // block, block).mean((1, 3))
    lb = luminance(b)[:hb, :wb].reshape(hb // block, block, wb // block, block).mean((1, 3))
    floor = 1e-3 * max(float(lb.mean()), 1e-12)
    r = (la + floor) / (lb + floor)
    x = np.clip((r - 1) / span, -1, 1) * 0.5 + 0.5
    rgb = matplotlib.colormaps["RdBu_r"](x)[:, :, :3]
    return np.repeat(np.repeat(rgb, block, 0), block, 1)


def compare_refs(a, b):
    """How raylab's converged image (a) differs from Cycles' (b)."""
    import numpy as np

    h, w = a.shape[:2]
    hb, wb = h // 8 * 8, w // 8 * 8
    la = luminance(a)[:hb, :wb].reshape(hb // 8, 8, wb // 8, 8).mean((1, 3))
    lb = luminance(b)[:hb, :wb].reshape(hb // 8, 8, wb // 8, 8).mean((1, 3))
    floor = 0.01 * float(lb.mean())
    block = np.abs(la - lb) / (lb + floor)
    return {"mean_ratio_rgb": [float(x) for x in a.mean((0, 1)) / np.maximum(b.mean((0, 1)), 1e-30)],
            "block8_mean_abs_rel_diff": float(block.mean()),
            "relmse_raylab_vs_cycles": rel_mse_clamped(a, b),
            "flip_raylab_vs_cycles": flip_mean(a, b)}


# ----------------------------------------------------------------------------------------------
# Renderers.


def run(cmd, timeout, what):
    """Runs cmd; (stdout, stderr, wall seconds). A failure or a timeout is one line."""
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                           stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise Fail(f"{what} took longer than --timeout {timeout:g} s (killed)")
    except OSError as e:
        raise Fail(f"{what}: cannot run {cmd[0]}: {e}")
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        why = one_line(p.stderr) or one_line(p.stdout) or "no message"
        raise Fail(f"{what} failed (exit {p.returncode}): {why}")
    return p.stdout, p.stderr, wall


class Scene:
    def __init__(self, name, args):
        rel, env, rotate, box, fog = SCENES[name]
        self.name, self.box, self.fog = name, box, fog
        self.file = os.path.join(ROOT, rel)
        if not os.path.isfile(self.file):
            hint = {"cornell-glass": " (python3 tools/make_cornell_glass.py makes it)",
                    "helmet-venice": " (python3 tools/make_helmet_venice.py makes it)",
                    "showcase": " (python3 tools/make_showcase.py makes it)",
                    "showcase-fog": " (python3 tools/make_showcase.py makes it)",
                    "street": " (python3 tools/make_street.py makes it)",
                    "glass-lamps": " (python3 tools/make_glass_lamps.py makes it)"}.get(
                        name, " (python3 tools/make_caustic_scenes.py makes it)")
            raise Fail(f"scene file {rel} not found{hint}")
        self.env = os.path.join(ROOT, "assets", env) if env else None
        if self.env and not os.path.isfile(self.env):
            raise Fail(f"environment map {self.env} not found")
        self.rotate = rotate
        self.width, self.height = args.box_size if box else args.size
        default, configs = CAUSTIC_SCENES.get(name, ("path", [("Cycles", [])]))
        self.integrator = args.raylab_integrator or default
        self.cycles_configs = configs

    def files(self):
        """The glTF file and every file it references (and the map), for the cache key."""
        with open(self.file) as f:
            doc = json.load(f)
        base = os.path.dirname(self.file)
        out = [self.file]
        for coll in ("buffers", "images"):
            for item in doc.get(coll, []):
                uri = item.get("uri")
                if uri and not uri.startswith("data:"):
                    from urllib.parse import unquote
                    out.append(os.path.normpath(os.path.join(base, unquote(uri))))
        if self.env:
            out.append(self.env)
        if self.fog is not None:
            out.append(FOG_WRAPPER)
        if self.name in CAUSTIC_SCENES:
            out.append(CAUSTICS_WRAPPER)
        return out

    def key(self, renderer_id, spp):
        h = hashlib.sha256()
        for p in self.files():
            with open(p, "rb") as f:
                h.update(hashlib.sha256(f.read()).digest())
        key = [renderer_id, self.rotate, self.width, self.height, spp, REF_SEED]
        if self.fog is not None:
            key.append(self.fog)
        h.update(json.dumps(key).encode())
        return h.hexdigest()[:12]

    def env_args(self):
        return ["--env", self.env, "--env-rotate", f"{self.rotate:g}"] if self.env else []

    def fog_args(self):
        return ["--fog", f"{self.fog:g}"] if self.fog is not None else []


class Result:
    def __init__(self, img, seconds, info, noisy=None, noisy_seconds=None):
        self.img, self.seconds, self.info = img, seconds, info
        self.noisy, self.noisy_seconds = noisy, noisy_seconds


SUMMARY = re.compile(r"^wrote .*?: (\d+)x(\d+), (\S+), (\d+) spp, (?:[^,\n]*, )*?([0-9.]+) ms.*$",
                     re.M)
SPP_MEAN = re.compile(r"([0-9.]+) spp on average")
DENOISED = re.compile(r"denoised in ([0-9.]+) ms([^;\n]*)")


class Raylab:
    name = "raylab"
    ref_id = "raylab render --default-light off (sobol)"

    def __init__(self, path, threads, tmp, timeout):
        if not os.path.isfile(path):
            raise Fail(f"raylab binary {path} not found: build it with `cargo build --release` "
                       "(or pass --raylab PATH)")
        self.source = path
        self.binary = os.path.join(tmp, "raylab")
        shutil.copy2(path, self.binary)
        with open(self.binary, "rb") as f:
            self.sha = hashlib.sha256(f.read()).hexdigest()[:12]
        self.mtime = time.strftime("%Y-%m-%d %H:%M", time.localtime(os.path.getmtime(path)))
        self.threads, self.tmp, self.timeout = threads, tmp, timeout
        out, _, _ = run([self.binary, "render", "--help"], 60, "raylab render --help")
        self.has_denoise = "--denoise" in out
        self.has_noise_threshold = "--noise-threshold" in out
        self.version = one_line(run([self.binary, "--version"], 60, "raylab --version")[0])

    def describe(self):
        return (f"{self.version} {self.source} (built {self.mtime}, sha256 {self.sha}; "
                f"--denoise {'yes' if self.has_denoise else 'not yet'}; "
                f"--noise-threshold {'yes' if self.has_noise_threshold else 'not yet'})")

    def render(self, scene, spp, seed, denoise=False, out=None, noise_threshold=None):
        """noise_threshold: adaptive sampling (`--noise-threshold T`, spp the cap); the result's
        info then has `spp_mean`, the summary line's `N spp on average` (spp when it has none)."""
        out = out or os.path.join(self.tmp, "raylab.exr")
        cmd = [self.binary, "render", scene.file, "--spp", str(spp), "--threads", str(self.threads),
               "--seed", str(seed), "--width", str(scene.width), "--height", str(scene.height),
               "--default-light", "off", *scene.env_args(), *scene.fog_args(), "-o", out]
        if scene.integrator != "path":
            cmd += ["--integrator", scene.integrator]
        if denoise:
            cmd.append("--denoise")
        if noise_threshold is not None:
            cmd += ["--noise-threshold", f"{noise_threshold:g}"]
        what = (f"raylab {scene.name} {scene.integrator} {spp} spp{' --denoise' if denoise else ''}"
                + (f" --noise-threshold {noise_threshold:g}" if noise_threshold is not None else ""))
        _, err, wall = run(cmd, self.timeout, what)
        m = SUMMARY.search(err)
        if not m:
            raise Fail(f"{what}: no summary line (`wrote ...: WxH, path, N spp, T ms, ...`) on "
                       f"stderr: {one_line(err)}")
        w, h, integrator, done, ms = m.groups()
        # adaptive: `N spp` is the cap, or at most the cap
        spp_ok = int(done) == spp or (noise_threshold is not None and int(done) <= spp)
        if (int(w), int(h)) != (scene.width, scene.height) or not spp_ok or integrator != scene.integrator:
            raise Fail(f"{what}: unexpected summary: {m.group(0)}")
        render_s = float(ms) / 1e3
        info = {"render_s": render_s, "wall_s": wall, "summary": m.group(0)}
        a = SPP_MEAN.search(m.group(0))
        info["spp_mean"] = float(a.group(1)) if a else float(spp)
        info["spp_mean_reported"] = bool(a)
        layers = read_exr(out)
        notes = []
        img = finite(layers["rgb"], what, notes)
        if denoise:
            d = DENOISED.search(m.group(0))
            if not d:
                raise Fail(f"{what}: the summary line has no `denoised in D ms` clause: {m.group(0)}")
            if "noisy" not in layers:
                raise Fail(f"{what}: {out} has no noisy.R/G/B layers")
            info["denoise_s"] = float(d.group(1)) / 1e3
            info["denoiser"] = d.group(2).strip()
            info["notes"] = notes
            noisy = finite(layers["noisy"], what + " (noisy layers)", notes)
            return Result(img, render_s + info["denoise_s"], info, noisy=noisy, noisy_seconds=render_s)
        info["notes"] = notes
        return Result(img, render_s, info)


class Cycles:
    name = "Cycles"

    def __init__(self, venv, shared, threads, tmp, timeout, name="Cycles", flags=()):
        """name, flags: a configuration of tools/cycles_caustics.py (--guiding, --mnee) for the
        caustic scenes; "Cycles" without flags is render_gltf.py unchanged."""
        self.name, self.flags = name, list(flags)
        self.venv, self.shared = venv, shared
        self.py = os.path.join(os.path.abspath(venv), "bin", "python")
        self.script = os.path.join(os.path.abspath(shared), "cycles", "render_gltf.py")
        with open(self.script, "rb") as f:
            self.sha = hashlib.sha256(f.read()).hexdigest()[:12]
        req = os.path.join(os.path.dirname(self.script), "requirements.txt")
        self.bpy = "?"
        if os.path.exists(req):
            with open(req) as f:
                m = re.search(r"^bpy==(\S+)", f.read(), re.M)
                self.bpy = m.group(1) if m else "?"
        self.ref_id = f"cycles render_gltf.py {self.sha} bpy {self.bpy}"
        if self.flags:
            self.ref_id += " cycles_caustics.py " + " ".join(self.flags)
        self.threads, self.tmp, self.timeout = threads, tmp, timeout
        self.blender = None

    def variant(self, name, flags):
        """The same peer in another configuration of tools/cycles_caustics.py."""
        v = Cycles(self.venv, self.shared, self.threads, self.tmp, self.timeout, name, flags)
        v.blender = self.blender
        return v

    def ref_flags(self):
        """The flags of the render that is this configuration's converged image: path guiding
        changes the noise, not the mean (both converge to the same image: one reference for
        both), MNEE adds the caustic that plain path tracing misses (its own reference)."""
        return [f for f in self.flags if f != "--guiding"]

    def describe(self):
        return (f"Blender {self.blender or 'bpy ' + self.bpy} Cycles CPU via {self.script} "
                f"(sha256 {self.sha}), {self.py}")

    def render(self, scene, spp, seed, denoise=False, out=None, noise_threshold=None):
        """noise_threshold: Cycles' adaptive sampling at that threshold, spp the cap, through
        tools/cycles_adaptive.py; the result's info then has `spp_mean` (None if unknown)."""
        out = out or os.path.join(self.tmp, "cycles.exr")
        script = [self.script]
        if noise_threshold is not None:
            if scene.fog is not None:
                raise Fail(f"{scene.name}: --adaptive does not take the fog scene")
            script = [ADAPTIVE_WRAPPER, "--render-gltf", self.script,
                      "--noise-threshold", f"{noise_threshold:g}"]
        elif scene.fog is not None:
            # (The wrapper finds render_gltf.py by RAYLAB_RENDER_GLTF.)
            os.environ["RAYLAB_RENDER_GLTF"] = self.script
            script = [FOG_WRAPPER]
        elif self.flags:
            os.environ["RAYLAB_RENDER_GLTF"] = self.script
            script = [CAUSTICS_WRAPPER, *self.flags]
        cmd = [self.py, *script, scene.file, "-o", out, "--width", str(scene.width),
               "--height", str(scene.height), "--spp", str(spp), "--threads", str(self.threads),
               "--seed", str(seed), "--quiet", *scene.env_args(), *scene.fog_args()]
        if denoise:
            cmd.append("--denoise")
        what = (f"{self.name} {scene.name} {spp} spp{' --denoise' if denoise else ''}"
                + (f" adaptive {noise_threshold:g}" if noise_threshold is not None else ""))
        stdout, _, wall = run(cmd, self.timeout, what)
        info = None
        for line in reversed(stdout.splitlines()):
            if line.startswith("{"):
                try:
                    info = json.loads(line)
                    break
                except ValueError:
                    continue
        if info is None:
            raise Fail(f"{what}: no JSON line on stdout from render_gltf.py: {one_line(stdout)}")
        done = info.get("spp_done")
        if done is not None and (done > spp if noise_threshold is not None else done != spp):
            raise Fail(f"{what}: Cycles did {info['spp_done']} of {spp} spp")
        secs = info.get("cycles_path_trace_s")
        if secs is None:
            raise Fail(f"{what}: no cycles_path_trace_s in its JSON line (OpenEXR header unread?)")
        self.blender = info.get("blender", self.blender)
        info["wall_s"] = wall
        if noise_threshold is None:
            info["spp_mean"] = float(spp)
        notes = []
        img = finite(read_exr(out)["rgb"], what, notes)
        info["notes_tool"] = notes
        return Result(img, float(secs), info)


# ----------------------------------------------------------------------------------------------
# Converged references (cached).


def reference(renderer, scene, spp, args):
    """(image, meta): the renderer's own converged image of the scene, in two halves."""
    os.makedirs(args.cache, exist_ok=True)
    rid, label = renderer.ref_id, renderer.name.lower().replace(" ", "-").replace("+", "-")
    if isinstance(renderer, Raylab) and scene.integrator != "path":
        rid += f" --integrator {scene.integrator}"   # (path keeps the keys it always had)
        label += "-" + scene.integrator
    key = scene.key(rid, spp)
    base = os.path.join(args.cache, f"{scene.name}-{label}-{scene.width}x"
                        f"{scene.height}-{spp}spp-{key}")
    if args.fresh_refs or not (os.path.exists(base + ".exr") and os.path.exists(base + ".json")):
        half = max(1, spp // 2)
        log(f"rendering the {scene.name} reference with {renderer.name}: 2 × {half} spp "
            f"(once; cached in {args.cache})")
        halves, secs = [], 0.0
        for k in range(2):
            r = renderer.render(scene, half, REF_SEED + k)
            halves.append(r.img)
            secs += r.seconds
        full = 0.5 * (halves[0] + halves[1])
        write_exr(base + ".exr", full)
        meta = {"scene": scene.name, "renderer": renderer.name, "spp": 2 * half,
                "size": [scene.width, scene.height], "seeds": [REF_SEED, REF_SEED + 1],
                # relMSE(h0, h1) ≈ 2 × a half's own ≈ 4 × the average's own noise.
                "own_relmse": rel_mse_clamped(halves[0], halves[1]) / 4,
                "halves_flip": flip_mean(halves[0], halves[1]),
                "seconds": secs, "key": key, "made": time.strftime("%Y-%m-%d %H:%M:%S"),
                "renderer_id": rid}
        if isinstance(renderer, Raylab):
            meta["raylab_sha256"] = renderer.sha
        else:
            meta["blender"] = renderer.blender
        tmp = base + f".json.{os.getpid()}.tmp"
        with open(tmp, "w") as f:
            json.dump(meta, f, indent=1)
        os.replace(tmp, base + ".json")
    with open(base + ".json") as f:
        meta = json.load(f)
    if isinstance(renderer, Raylab) and meta.get("raylab_sha256") != renderer.sha:
        log(f"note: the cached {scene.name} raylab reference was made by another raylab binary "
            f"(sha256 {meta.get('raylab_sha256')}); --fresh-refs re-renders it")
    meta["path"] = base + ".exr"
    return read_exr(base + ".exr")["rgb"], meta


# ----------------------------------------------------------------------------------------------
# Comparison mode.


def div(a, b):
    return a / b if b else None


def fmt_e(x):
    return "n/a" if x is None else f"{x:.2e}"


def fmt_f(x):
    return "n/a" if x is None else f"{x:.4f}"


def fmt_s(x):
    return "n/a" if x is None else (f"{x:.3f}" if x < 10 else f"{x:.1f}")


def fmt_r(x):
    return "n/a" if x is None else f"{x:.2f}"


def both_references(scenes, raylab, cycles, args, variants=None):
    """Each renderer's converged image of each scene (cached), how the two differ, and a preview
    SCENE-refs.png of them: (refs, ref_meta, cross), refs and ref_meta keyed by (scene, renderer
    name) for raylab and every Cycles configuration of `variants` (scene name -> list, default
    [cycles]; configurations that differ only in path guiding share one reference), cross by
    scene (raylab against plain Cycles) and by "SCENE vs NAME" for the other Cycles references
    (MNEE), each a row of SCENE-refs.png."""
    refs, ref_meta, cross = {}, {}, {}
    for sc in scenes:
        r = raylab
        refs[(sc.name, r.name)], ref_meta[(sc.name, r.name)] = reference(r, sc, args.ref_spp, args)
        made, rows = {}, []
        for v in (variants or {}).get(sc.name, [cycles]):
            flags = v.ref_flags()
            if tuple(flags) not in made:
                src = v if flags == v.flags else next(
                    (w for w in variants[sc.name] if w.flags == flags), None) or cycles.variant(
                    "Cycles" + (" MNEE" if "--mnee" in flags else ""), flags)
                made[tuple(flags)] = (src.name,) + reference(src, sc, args.ref_spp, args)
                if not cycles.blender:
                    cycles.blender = made[tuple(flags)][2].get("blender")
            src_name, img, meta = made[tuple(flags)]
            refs[(sc.name, v.name)], ref_meta[(sc.name, v.name)] = img, dict(meta, ref_of=src_name)
        for src_name, img, _ in made.values():
            key = sc.name if src_name == "Cycles" else f"{sc.name} vs {src_name}"
            cross[key] = c = compare_refs(refs[(sc.name, "raylab")], img)
            c["cycles"] = src_name
            log(f"{sc.name}: converged raylab ({sc.integrator}) / {src_name} mean R G B "
                + " ".join(f"{x:.4f}" for x in c["mean_ratio_rgb"])
                + f"; 8×8-block mean |rel. diff| {100 * c['block8_mean_abs_rel_diff']:.1f} %")
            rows.append([display(refs[(sc.name, "raylab")]), display(img),
                         ratio_map(refs[(sc.name, "raylab")], img)])
        save_png(os.path.join(args.previews, f"{sc.name}-refs.png"), rows)
    log(f"Cycles: {cycles.describe()}")
    return refs, ref_meta, cross


def compare(args, tmp):
    import numpy as np

    scenes = [Scene(s, args) for s in args.scenes]
    raylab = Raylab(args.raylab, args.threads, tmp, args.timeout)
    cycles = Cycles(args.venv, args.shared, args.threads, tmp, args.timeout)
    # Every scene's Cycles configurations (the caustic scenes: guiding, MNEE; else plain Cycles).
    variants = {sc.name: [cycles if not flags else cycles.variant(name, flags)
                          for name, flags in sc.cycles_configs] for sc in scenes}
    per_scene = {sc.name: [raylab] + variants[sc.name] for sc in scenes}
    log(f"raylab: {raylab.describe()}")
    start = time.perf_counter()
    refs, ref_meta, cross = both_references(scenes, raylab, cycles, args, variants)

    runs, ladder_runs = [], []
    modes = tuple(args.modes)
    previews = {}
    for rnd in range(args.rounds):
        seed = rnd + 1
        for si, sc in enumerate(scenes):
            renderers = per_scene[sc.name]
            for pi, spp in enumerate(args.spp):
                order = renderers if (rnd + si + pi) % 2 == 0 else renderers[::-1]
                for mode in modes:
                    for r in order:
                        if mode == "denoised" and r is raylab and not raylab.has_denoise:
                            continue
                        res = r.render(sc, spp, seed, denoise=(mode == "denoised"))
                        e = errors(res.img, refs[(sc.name, r.name)])
                        rec = {"round": rnd + 1, "seed": seed, "scene": sc.name, "renderer": r.name,
                               "mode": mode, "spp": spp, "seconds": res.seconds, **e,
                               "info": res.info}
                        if res.noisy is not None:
                            # raylab --denoise also wrote the noisy image: it must be the noisy
                            # run's (same seed).
                            prev = previews.get((sc.name, spp, r.name, "noisy", rnd))
                            if prev is not None:
                                rec["noisy_layer_max_abs_diff_vs_noisy_run"] = float(
                                    np.abs(res.noisy - prev).max())
                        runs.append(rec)
                        previews[(sc.name, spp, r.name, mode, rnd)] = res.img
                        log(f"round {rnd + 1}: {r.name:6} {sc.name} {spp:4} spp {mode:8} "
                            f"{res.seconds:7.3f} s  relMSE {e['relmse']:.3e}  FLIP {e['flip']:.4f}")
                # previews of round 1, then free memory of the images
                if rnd == 0:
                    row = []
                    for r in renderers:
                        for mode in modes:
                            img = previews.get((sc.name, spp, r.name, mode, rnd))
                            row.append(display(img) if img is not None
                                       else 0.5 * np.ones_like(display(refs[(sc.name, r.name)])))
                    save_png(os.path.join(args.previews, f"{sc.name}-{spp}spp.png"), [row])
                for k in [k for k in previews if k[0] == sc.name and k[1] == spp]:
                    del previews[k]
            # The target: Cycles+OIDN at --target-spp. raylab --denoise on a ladder of spp, in
            # the same round, to find the fewest samples (the least time) that reach both of its
            # errors.
            if args.ladder and raylab.has_denoise:
                for spp in args.ladder:
                    res = raylab.render(sc, spp, seed, denoise=True)
                    e = errors(res.img, refs[(sc.name, "raylab")])
                    ladder_runs.append({"round": rnd + 1, "seed": seed, "scene": sc.name,
                                        "spp": spp, "seconds": res.seconds, **e, "info": res.info})
                    log(f"round {rnd + 1}: ladder raylab {sc.name} {spp:4} spp denoised "
                        f"{res.seconds:7.3f} s  relMSE {e['relmse']:.3e}  FLIP {e['flip']:.4f}")

    # Summary: best time, worst errors over the rounds.
    summary = []
    for sc in scenes:
        renderers = per_scene[sc.name]
        for spp in args.spp:
            for mode in modes:
                row = {"scene": sc.name, "spp": spp, "mode": mode,
                       "renderers": [r.name for r in renderers]}
                for r in renderers:
                    rs = [x for x in runs if (x["scene"], x["spp"], x["mode"], x["renderer"])
                          == (sc.name, spp, mode, r.name)]
                    if not rs:
                        row[r.name] = None
                        continue
                    s = min(x["seconds"] for x in rs)
                    rel = max(x["relmse"] for x in rs)
                    fl = max(x["flip"] for x in rs)
                    row[r.name] = {"seconds": s, "relmse": rel, "flip": fl,
                                   "relmse_x_s": rel * s, "flip_x_s": fl * s, "runs": len(rs)}
                # Cycles' best configuration per measure: the lowest error × seconds.
                row["best"] = {}
                for m in ("relmse_x_s", "flip_x_s"):
                    got = [(row[v.name][m], v.name) for v in variants[sc.name] if row[v.name]]
                    row["best"][m] = min(got)[1] if got else None
                a = row["raylab"]
                bm, bf = (row[row["best"][m]] if row["best"][m] else None
                          for m in ("relmse_x_s", "flip_x_s"))
                row["ratio"] = None if not (a and bm and bf) else {
                    "seconds": a["seconds"] / bm["seconds"] if bm["seconds"] > 0 else None,
                    "relmse": div(a["relmse"], bm["relmse"]),
                    "relmse_x_s": (a["relmse_x_s"] / bm["relmse_x_s"]) if bm["relmse_x_s"] > 0 else None,
                    "flip": div(a["flip"], bf["flip"]),
                    "flip_x_s": (a["flip_x_s"] / bf["flip_x_s"]) if bf["flip_x_s"] > 0 else None}
                summary.append(row)

    # Cycles' denoise time: denoised − noisy path-trace time, same seed and spp.
    cyc_dn = {}
    for x in runs:
        if x["renderer"] == "Cycles" and x["mode"] == "denoised":
            for y in runs:
                if (y["renderer"], y["mode"], y["scene"], y["spp"], y["seed"]) == (
                        "Cycles", "noisy", x["scene"], x["spp"], x["seed"]):
                    cyc_dn.setdefault(x["scene"], []).append(x["seconds"] - y["seconds"])
    ray_dn = {}
    for x in runs:
        if x["renderer"] == "raylab" and x["mode"] == "denoised":
            ray_dn.setdefault(x["scene"], []).append(x["info"].get("denoise_s"))

    took = time.perf_counter() - start
    print()
    print(f"raylab ÷ Cycles, {args.threads} threads each, seeds 1..{args.rounds} "
          f"({args.rounds} round{'s' if args.rounds > 1 else ''}); seconds: the best of the rounds "
          "(raylab: render time of its summary line, + denoise; Cycles: cycles_path_trace_s, "
          "denoising included); errors: the worst of the rounds, against the renderer's own "
          f"{args.ref_spp}-spp render; relMSE: per-pixel values clamped at their 99.9th "
          "percentile; FLIP: mean LDR FLIP after PBR Neutral + sRGB at exposure 0. "
          f"Run took {took:.0f} s.")
    print()
    print("| scene | spp | mode | renderer | seconds | relMSE | relMSE × s | FLIP | FLIP × s |")
    print("| --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: |")
    marked = False
    several = any(len(v) > 1 for v in variants.values())
    for row in summary:
        head = [row["scene"], str(row["spp"]), row["mode"]]
        for r in per_scene[row["scene"]]:
            v = row[r.name]
            if v is None:
                why = ("n/a (raylab has no --denoise)" if r is raylab and row["mode"] == "denoised"
                       else "n/a")
                print("| " + " | ".join(head + [r.name, why, "", "", "", ""]) + " |")
            else:
                # † : the reference's own noise is over a quarter of this error (it is inflated).
                own = ref_meta[(row["scene"], r.name)]["own_relmse"]
                mark = "†" if own > 0.25 * v["relmse"] else ""
                marked = marked or bool(mark)
                # ★: Cycles' best configuration of the row by that measure's error × seconds.
                star = {m: " ★" if several and row["best"][m] == r.name else ""
                        for m in ("relmse_x_s", "flip_x_s")}
                label = r.name + (f" ({sc_integrator(scenes, row['scene'])})"
                                  if r is raylab and several else "")
                print("| " + " | ".join(head + [label, fmt_s(v["seconds"]), fmt_e(v["relmse"]) + mark,
                                              fmt_e(v["relmse_x_s"]) + star["relmse_x_s"],
                                              fmt_f(v["flip"]),
                                              fmt_e(v["flip_x_s"]) + star["flip_x_s"]]) + " |")
            head = ["", "", ""]
        q = row["ratio"]
        vs = "raylab ÷ Cycles ★" if several else "raylab ÷ Cycles"
        if q is None:
            print("| " + " | ".join(head + [vs, "n/a", "", "n/a", "", "n/a"]) + " |")
        else:
            print("| " + " | ".join(head + [
                f"**{vs}**", fmt_r(q["seconds"]), fmt_r(q["relmse"]),
                f"**{fmt_r(q['relmse_x_s'])}**", fmt_r(q["flip"]),
                f"**{fmt_r(q['flip_x_s'])}**"]) + " |")
    if marked:
        print()
        print("† the reference's own noise (below) is more than a quarter of this relMSE, which it "
              "inflates (relMSE against a reference ≈ the image's own + the reference's): raise "
              "--ref-spp for denoised errors.")
    if several:
        print()
        print("★ Cycles' best configuration of the row by that measure (lowest error × seconds); "
              "the raylab ÷ Cycles ★ row divides raylab's numbers by that configuration's (seconds "
              "and relMSE by the relMSE-best one's, FLIP by the FLIP-best one's). Issue 45's target, "
              "raylab at Cycles' best error in at most half its time, is an error × seconds ratio "
              "≤ 0.5 on both measures (relMSE × s does not depend on spp; FLIP × s only roughly):")
        print()
        for row in summary:
            q = row["ratio"]
            if q is None or len(variants[row["scene"]]) < 2:
                continue
            ok = [k for k in ("relmse_x_s", "flip_x_s") if q[k] is not None and q[k] <= 0.5]
            print(f"* {row['scene']} {row['spp']} spp {row['mode']}: relMSE × s "
                  f"{fmt_r(q['relmse_x_s'])} (vs {row['best']['relmse_x_s']}), FLIP × s "
                  f"{fmt_r(q['flip_x_s'])} (vs {row['best']['flip_x_s']}): "
                  + ("target met" if len(ok) == 2 else
                     "target met on " + ok[0] + " only" if ok else "target not met"))
    reach = []
    if ladder_runs:
        print()
        print(f"Time to Cycles+OIDN's {args.target_spp}-spp errors: raylab --denoise at the fewest "
              "spp of the ladder whose worst errors (over the rounds) are at most Cycles+OIDN's "
              "worst (both measures), its best time, against Cycles+OIDN's best time:")
        print()
        print("| scene | Cycles+OIDN spp / s / relMSE / FLIP | raylab --denoise spp / s / relMSE / FLIP "
              "| time ratio raylab ÷ Cycles |")
        print("| --- | --- | --- | ---: |")
        for sc in scenes:
            t = next((row["Cycles"] for row in summary if (row["scene"], row["spp"], row["mode"])
                      == (sc.name, args.target_spp, "denoised")), None)
            if not t:
                continue
            got = None
            for spp in sorted(args.ladder):
                rs = [x for x in ladder_runs if (x["scene"], x["spp"]) == (sc.name, spp)]
                rel, fl = max(x["relmse"] for x in rs), max(x["flip"] for x in rs)
                secs = min(x["seconds"] for x in rs)
                if rel <= t["relmse"] and fl <= t["flip"]:
                    got = (spp, secs, rel, fl)
                    break
            cyc = f"{args.target_spp} / {fmt_s(t['seconds'])} / {fmt_e(t['relmse'])} / {fmt_f(t['flip'])}"
            if got is None:
                top = max(args.ladder)
                rs = [x for x in ladder_runs if (x["scene"], x["spp"]) == (sc.name, top)]
                print(f"| {sc.name} | {cyc} | not reached by {top} spp ({fmt_s(min(x['seconds'] for x in rs))}"
                      f" / {fmt_e(max(x['relmse'] for x in rs))} / {fmt_f(max(x['flip'] for x in rs))}) | — |")
                reach.append({"scene": sc.name, "target": t, "reached": None})
            else:
                spp, secs, rel, fl = got
                ratio = secs / t["seconds"] if t["seconds"] > 0 else None
                print(f"| {sc.name} | {cyc} | {spp} / {fmt_s(secs)} / {fmt_e(rel)} / {fmt_f(fl)} | "
                      f"**{fmt_r(ratio)}** |")
                reach.append({"scene": sc.name, "target": t, "reached": {
                    "spp": spp, "seconds": secs, "relmse": rel, "flip": fl, "ratio": ratio}})
    print()
    print("Converged references (each renderer's own; `own noise` = relMSE between its two halves "
          "/ 4) and how they differ from each other:")
    print()
    print("| scene | size | raylab ref s | raylab own noise | Cycles ref s | Cycles own noise "
          "| raylab / Cycles mean R, G, B | 8×8-block mean abs rel. diff | relMSE (raylab vs Cycles) "
          "| FLIP (raylab vs Cycles) |")
    print("| --- | --- | ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: |")
    for sc, key in [(sc, k) for sc in scenes for k in cross
                    if k == sc.name or k.startswith(sc.name + " vs ")]:
        c = cross[key]
        a, b = ref_meta[(sc.name, "raylab")], ref_meta[(sc.name, c["cycles"])]
        name = sc.name if c["cycles"] == "Cycles" and not several else f"{sc.name}: raylab " \
            f"{sc.integrator} vs {c['cycles']}"
        print(f"| {name} | {sc.width}×{sc.height} | {fmt_s(a['seconds'])} | "
              f"{a['own_relmse']:.1e} | {fmt_s(b['seconds'])} | {b['own_relmse']:.1e} | "
              + ", ".join(f"{x:.3f}" for x in c["mean_ratio_rgb"])
              + f" | {100 * c['block8_mean_abs_rel_diff']:.1f} % | "
              f"{c['relmse_raylab_vs_cycles']:.2e} | {c['flip_raylab_vs_cycles']:.4f} |")
    print()
    for sc in scenes:
        d = cyc_dn.get(sc.name)
        rd = [x for x in ray_dn.get(sc.name, []) if x is not None]
        bits = []
        if d:
            bits.append(f"Cycles' denoise ≈ {sorted(d)[len(d) // 2]:.2f} s (median of denoised − "
                        "noisy cycles_path_trace_s at equal seeds)")
        if rd:
            span = f"{min(rd) * 1e3:.0f}" + (f"–{max(rd) * 1e3:.0f}" if max(rd) > min(rd) else "")
            bits.append(f"raylab's denoise {span} ms")
        if bits:
            print(f"* {sc.name}: " + "; ".join(bits))
    print(f"* previews: {args.previews} (SCENE-refs.png: raylab | Cycles | luminance ratio, a row "
          "per Cycles reference; SCENE-Nspp.png: raylab, then each Cycles configuration, each "
          f"{' | '.join(modes)})")
    bad = [x for x in runs if x.get("noisy_layer_max_abs_diff_vs_noisy_run", 0) > 0]
    if bad:
        print(f"* warning: raylab --denoise's noisy layers differ from the noisy run at the same "
              f"seed in {len(bad)} run(s) (largest {max(x['noisy_layer_max_abs_diff_vs_noisy_run'] for x in bad):.3g})")

    out = {"tool": "tools/compare_cycles.py", "date": time.strftime("%Y-%m-%d %H:%M:%S"),
           "argv": sys.argv[1:], "threads": args.threads, "rounds": args.rounds,
           "spp": args.spp, "ref_spp": args.ref_spp,
           "aggregation": "seconds: best of the rounds; errors: worst of the rounds",
           "error_measures": {
               "relmse": "per pixel mean_c (c-r)^2/(r^2+eps), eps = 0.01 mean(r)^2, clamped at "
                         "the 99.9th percentile of the per-pixel values, mean",
               "flip": "mean LDR FLIP (flip-evaluator, 67 ppd) of PBR Neutral + sRGB at exposure 0"},
           "raylab": {"binary": raylab.source, "sha256": raylab.sha, "version": raylab.version,
                      "has_denoise": raylab.has_denoise},
           "cycles": {"blender": cycles.blender, "render_gltf_sha256": cycles.sha,
                      "python": cycles.py},
           "scenes": {sc.name: {"file": os.path.relpath(sc.file, ROOT), "size": [sc.width, sc.height],
                                "env": sc.env, "env_rotate": sc.rotate,
                                "raylab_integrator": sc.integrator,
                                "cycles_configurations": {n: f for n, f in sc.cycles_configs}}
                      for sc in scenes},
           "references": {f"{k[0]}/{k[1]}": v for k, v in ref_meta.items()},
           "raylab_vs_cycles_references": cross,
           "cycles_denoise_s": cyc_dn, "raylab_denoise_s": ray_dn,
           "summary": summary, "runs": runs, "ladder_runs": ladder_runs, "reach": reach,
           "seconds": took}
    write_json(args.json, out)
    print(f"* all numbers: {args.json}")


def sc_integrator(scenes, name):
    return next(sc.integrator for sc in scenes if sc.name == name)


def write_json(path, obj):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = path + f".{os.getpid()}.tmp"
    with open(tmp, "w") as f:
        json.dump(obj, f, indent=1)
    os.replace(tmp, path)


# ----------------------------------------------------------------------------------------------
# Adaptive mode: each renderer's adaptive sampling at equal noise thresholds, and each against
# itself at fixed spp (its adaptive run's average).

RUNS = (("raylab", "adaptive"), ("raylab", "fixed"), ("Cycles", "adaptive"), ("Cycles", "fixed"))


def adaptive(args, tmp):
    import numpy as np

    scenes = [Scene(s, args) for s in args.scenes]
    raylab = Raylab(args.raylab, args.threads, tmp, args.timeout)
    cycles = Cycles(args.venv, args.shared, args.threads, tmp, args.timeout)
    log(f"raylab: {raylab.describe()}")
    if not raylab.has_noise_threshold:
        log("raylab has no --noise-threshold yet: its adaptive rows are n/a, and its fixed-spp runs "
            "take Cycles' adaptive average")
    start = time.perf_counter()
    refs, ref_meta, cross = both_references(scenes, raylab, cycles, args)
    cap = args.adaptive_spp

    runs = []

    def one(r, sc, t, seed, mode, spp=None, spp_from=None):
        """One render (adaptive at threshold t, or `spp` fixed), its errors: (record, image)."""
        if mode == "adaptive":
            res = r.render(sc, cap, seed, noise_threshold=t)
            spp = res.info.get("spp_mean")
        else:
            res = r.render(sc, spp, seed)
        e = errors(res.img, refs[(sc.name, r.name)])
        rec = {"round": seed, "seed": seed, "scene": sc.name, "threshold": t, "renderer": r.name,
               "mode": mode, "cap": cap if mode == "adaptive" else None, "spp": spp,
               "spp_from": spp_from, "seconds": res.seconds, **e, "info": res.info}
        runs.append(rec)
        log(f"round {seed}: {r.name:6} {sc.name} T={t:g} {mode:8} "
            f"{'?' if spp is None else f'{spp:.1f}':>6} spp {res.seconds:7.3f} s  "
            f"relMSE {e['relmse']:.3e}  FLIP {e['flip']:.4f}")
        return rec, res.img

    for rnd in range(args.rounds):
        seed = rnd + 1
        for si, sc in enumerate(scenes):
            for ti, t in enumerate(args.adaptive):
                order = (raylab, cycles) if (rnd + si + ti) % 2 == 0 else (cycles, raylab)
                got, imgs = {}, {}
                for r in order:
                    if r is not raylab or raylab.has_noise_threshold:
                        got[(r.name, "adaptive")], imgs[(r.name, "adaptive")] = one(
                            r, sc, t, seed, "adaptive")
                # Fixed spp: the adaptive run's average, rounded (raylab without --noise-threshold:
                # Cycles' average, so that its row still says something).
                for r in order:
                    src, spp_from = got.get((r.name, "adaptive")), f"{r.name} adaptive"
                    if src is None and r is raylab:
                        src, spp_from = got.get(("Cycles", "adaptive")), "Cycles adaptive"
                    if src is None or src["spp"] is None:
                        log(f"round {rnd + 1}: {r.name} {sc.name} T={t:g}: no average spp to match, "
                            "no fixed-spp run")
                        continue
                    got[(r.name, "fixed")], imgs[(r.name, "fixed")] = one(
                        r, sc, t, seed, "fixed", max(1, int(round(src["spp"]))), spp_from)
                if rnd == 0:
                    row = []
                    for name, mode in RUNS:
                        img = imgs.get((name, mode))
                        row.append(display(img) if img is not None
                                   else 0.5 * np.ones_like(display(refs[(sc.name, name)])))
                    save_png(os.path.join(args.previews, f"{sc.name}-adaptive-{t:g}.png"), [row])

    # Summary: mean spp, best time and worst errors over the rounds.
    summary = []
    for sc in scenes:
        for t in args.adaptive:
            row = {"scene": sc.name, "threshold": t}
            for name, mode in RUNS:
                rs = [x for x in runs if (x["scene"], x["threshold"], x["renderer"], x["mode"])
                      == (sc.name, t, name, mode)]
                if not rs:
                    row[f"{name} {mode}"] = None
                    continue
                spps = [x["spp"] for x in rs]
                s = min(x["seconds"] for x in rs)
                rel, fl = max(x["relmse"] for x in rs), max(x["flip"] for x in rs)
                row[f"{name} {mode}"] = {
                    "spp": None if None in spps else sum(spps) / len(spps), "seconds": s,
                    "relmse": rel, "flip": fl, "relmse_x_s": rel * s, "flip_x_s": fl * s,
                    "runs": len(rs), "spp_from": rs[0]["spp_from"]}

            def ratio(a, b):
                a, b = row[a], row[b]
                if not (a and b):
                    return None
                return {k: div(a[k], b[k]) if a[k] is not None and b[k] is not None else None
                        for k in ("spp", "seconds", "relmse", "relmse_x_s", "flip", "flip_x_s")}

            row["ratios"] = {
                "raylab adaptive ÷ fixed": ratio("raylab adaptive", "raylab fixed"),
                "Cycles adaptive ÷ fixed": ratio("Cycles adaptive", "Cycles fixed"),
                "raylab ÷ Cycles, adaptive": ratio("raylab adaptive", "Cycles adaptive")}
            summary.append(row)

    took = time.perf_counter() - start
    print()
    print(f"Adaptive sampling at equal noise thresholds (cap {cap} spp), and each renderer at fixed "
          f"spp equal to its adaptive run's average (rounded); {args.threads} threads each, seeds "
          f"1..{args.rounds}; spp: the mean over the rounds of the samples per pixel on average "
          "(raylab: its summary line's `spp on average`; Cycles: its sample-count pass, "
          "tools/cycles_adaptive.py); seconds: the best of the rounds (raylab: render time of its "
          "summary line; Cycles: cycles_path_trace_s); errors: the worst of the rounds, against the "
          f"renderer's own {args.ref_spp}-spp render (relMSE clamped at the 99.9th percentile; FLIP "
          f"after PBR Neutral + sRGB). Run took {took:.0f} s.")
    print()
    print("| scene | threshold | run | spp | seconds | relMSE | relMSE × s | FLIP | FLIP × s |")
    print("| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    marked = nominal = borrowed = False
    for row in summary:
        head = [row["scene"], f"{row['threshold']:g}"]
        for name, mode in RUNS:
            v = row[f"{name} {mode}"]
            label = f"{name} {mode}"
            if v is None:
                why = ("n/a (raylab has no --noise-threshold)" if name == "raylab" and mode == "adaptive"
                       and not raylab.has_noise_threshold else "n/a")
                print("| " + " | ".join(head + [label, "", why, "", "", "", ""]) + " |")
            else:
                own = ref_meta[(row["scene"], name)]["own_relmse"]
                mark = "†" if own > 0.25 * v["relmse"] else ""
                marked = marked or bool(mark)
                spp = "?" if v["spp"] is None else f"{v['spp']:.1f}"
                if name == "raylab" and mode == "adaptive" and any(
                        not x["info"].get("spp_mean_reported", True) for x in runs
                        if (x["scene"], x["threshold"], x["renderer"], x["mode"])
                        == (row["scene"], row["threshold"], name, mode)):
                    spp += "‡"
                    nominal = True
                if mode == "fixed" and v["spp_from"] != f"{name} adaptive":
                    spp += "*"
                    borrowed = True
                print("| " + " | ".join(head + [label, spp, fmt_s(v["seconds"]),
                                              fmt_e(v["relmse"]) + mark, fmt_e(v["relmse_x_s"]),
                                              fmt_f(v["flip"]), fmt_e(v["flip_x_s"])]) + " |")
            head = ["", ""]
        for label, q in row["ratios"].items():
            if q is None:
                print("| " + " | ".join(head + [label, "n/a", "", "", "", "", ""]) + " |")
                continue
            print("| " + " | ".join(head + [
                f"**{label}**", fmt_r(q["spp"]), fmt_r(q["seconds"]), fmt_r(q["relmse"]),
                f"**{fmt_r(q['relmse_x_s'])}**", fmt_r(q["flip"]), f"**{fmt_r(q['flip_x_s'])}**"]) + " |")
    print()
    print("Ratios below 1 favour the first of the two: adaptive ÷ fixed below 1 means adaptive "
          "sampling pays (less error × time than the same samples spread evenly); raylab ÷ Cycles "
          "below 1 means raylab's adaptive sampling is the more efficient.")
    if marked:
        print("† the reference's own noise is more than a quarter of this relMSE, which it inflates: "
              "raise --ref-spp.")
    if nominal:
        print(f"‡ raylab's summary line did not say `spp on average`: the cap ({cap}) is shown and "
              "its fixed run used it.")
    if borrowed:
        print("* raylab has no --noise-threshold: its fixed run takes Cycles' adaptive average.")
    unknown = [x for x in runs if x["renderer"] == "Cycles" and x["mode"] == "adaptive"
               and x["spp"] is None]
    if unknown:
        print("* Cycles' samples per pixel were not known in "
              f"{len(unknown)} run(s) (" + "; ".join(sorted({w for x in unknown
                                                             for w in x["info"].get("warnings", [])
                                                             if "cycles_adaptive" in w}))
              + "): no fixed-spp run for them, time only.")
    print(f"* previews: {args.previews} (SCENE-adaptive-T.png: raylab adaptive | raylab fixed | "
          "Cycles adaptive | Cycles fixed, round 1; grey: not rendered)")

    out = {"tool": "tools/compare_cycles.py --adaptive", "date": time.strftime("%Y-%m-%d %H:%M:%S"),
           "argv": sys.argv[1:], "threads": args.threads, "rounds": args.rounds,
           "thresholds": args.adaptive, "cap_spp": cap, "ref_spp": args.ref_spp,
           "aggregation": "spp: mean of the rounds; seconds: best of the rounds; errors: worst of "
                          "the rounds",
           "raylab": {"binary": raylab.source, "sha256": raylab.sha, "version": raylab.version,
                      "has_noise_threshold": raylab.has_noise_threshold},
           "cycles": {"blender": cycles.blender, "render_gltf_sha256": cycles.sha,
                      "python": cycles.py, "wrapper": os.path.relpath(ADAPTIVE_WRAPPER, ROOT)},
           "scenes": {sc.name: {"file": os.path.relpath(sc.file, ROOT), "size": [sc.width, sc.height],
                                "env": sc.env, "env_rotate": sc.rotate} for sc in scenes},
           "references": {f"{k[0]}/{k[1]}": v for k, v in ref_meta.items()},
           "raylab_vs_cycles_references": cross,
           "summary": summary, "runs": runs, "seconds": took}
    write_json(args.json, out)
    print(f"* all numbers: {args.json}")
    return 0


# ----------------------------------------------------------------------------------------------
# Curve mode (raylab only).


def curve(args, tmp):
    scenes = [Scene(s, args) for s in args.scenes]
    raylab = Raylab(args.raylab, args.threads, tmp, args.timeout)
    log(f"raylab: {raylab.describe()}")
    if not raylab.has_denoise:
        log("raylab has no --denoise yet: the noisy curve only")
    rows, metas = [], {}
    seed = 1
    for sc in scenes:
        ref, metas[sc.name] = reference(raylab, sc, args.curve_ref_spp, args)
        log(f"{sc.name}: reference {metas[sc.name]['path']} (own relMSE ≈ "
            f"{metas[sc.name]['own_relmse']:.1e})")
        for spp in args.curve_spp:
            res = raylab.render(sc, spp, seed, denoise=raylab.has_denoise)
            pairs = [("noisy", res.noisy if res.noisy is not None else res.img,
                      res.noisy_seconds if res.noisy is not None else res.seconds)]
            if raylab.has_denoise:
                pairs.append(("denoised", res.img, res.seconds))
            for mode, img, secs in pairs:
                e = errors(img, ref)
                rows.append({"scene": sc.name, "spp": spp, "mode": mode, "seconds": secs, **e})
                log(f"{sc.name} {spp:5} spp {mode:8} {secs:8.3f} s  relMSE {e['relmse']:.3e}  "
                    f"FLIP {e['flip']:.4f}")

    os.makedirs(os.path.dirname(os.path.abspath(args.csv)), exist_ok=True)
    with open(args.csv, "w") as f:
        f.write("scene,spp,mode,seconds,relmse,flip\n")
        for r in rows:
            f.write(f"{r['scene']},{r['spp']},{r['mode']},{r['seconds']:.6f},{r['relmse']:.6e},"
                    f"{r['flip']:.6f}\n")
    plot_curve(args, scenes, rows, raylab)

    worse, ties = [], []
    for r in rows:
        if r["mode"] != "denoised":
            continue
        n = next(x for x in rows if (x["scene"], x["spp"], x["mode"]) == (r["scene"], r["spp"], "noisy"))
        for m in ("relmse", "flip"):
            if r[m] > n[m] * (1 + TIE):
                worse.append(f"{r['scene']} {r['spp']} spp {m}: denoised {r[m]:.4g} > noisy {n[m]:.4g}")
            elif r[m] > n[m]:
                ties.append(f"{r['scene']} {r['spp']} spp {m} +{100 * (r[m] / n[m] - 1):.3f} %")
    print()
    print(f"raylab noisy{' and denoised' if raylab.has_denoise else ''} against its own "
          f"{args.curve_ref_spp}-spp render ({args.threads} threads; relMSE clamped at the 99.9th "
          "percentile; FLIP after PBR Neutral + sRGB):")
    print()
    print("| scene | spp | noisy relMSE | denoised relMSE | noisy FLIP | denoised FLIP | noisy s | denoised s |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for sc in scenes:
        for spp in args.curve_spp:
            n = next(x for x in rows if (x["scene"], x["spp"], x["mode"]) == (sc.name, spp, "noisy"))
            d = next((x for x in rows if (x["scene"], x["spp"], x["mode"]) == (sc.name, spp, "denoised")), None)
            g = (lambda k: d[k]) if d else (lambda k: None)
            print(f"| {sc.name} | {spp} | {fmt_e(n['relmse'])} | {fmt_e(g('relmse'))} | "
                  f"{fmt_f(n['flip'])} | {fmt_f(g('flip'))} | {fmt_s(n['seconds'])} | {fmt_s(g('seconds'))} |")
    print()
    print(f"* CSV: {args.csv}; plot: {args.plot}")
    if ties:
        print(f"* denoised above noisy by less than {100 * TIE:g} % (ties: the blend kept the noisy "
              "image almost everywhere; such differences are far below the reference's own noise): "
              + "; ".join(ties))
    if worse:
        print("* DENOISED WORSE THAN NOISY at " + "; ".join(worse))
        return 3
    if raylab.has_denoise:
        print(f"* denoised is never worse than noisy (both measures, every scene and spp; ties within "
              f"{100 * TIE:g} % listed above)")
    return 0


def plot_curve(args, scenes, rows, raylab):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker  # noqa: F401

    n = len(scenes)
    fig, axes = plt.subplots(2, n, figsize=(4.2 * n, 6.4), squeeze=False)
    for j, sc in enumerate(scenes):
        for i, (m, label) in enumerate((("relmse", "relMSE (99.9 % clamped)"), ("flip", "mean FLIP"))):
            ax = axes[i][j]
            for mode, style in (("noisy", "-o"), ("denoised", "--s")):
                pts = [(r["spp"], r[m]) for r in rows if r["scene"] == sc.name and r["mode"] == mode]
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], style, ms=3.5, label=mode)
            ax.set_xscale("log", base=2)
            ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
            ax.set_yscale("log")
            ax.grid(True, which="both", alpha=0.3)
            ax.set_xlabel("samples per pixel")
            if j == 0:
                ax.set_ylabel(label)
            if i == 0:
                ax.set_title(f"{sc.name} ({sc.width}×{sc.height})")
            ax.legend(fontsize=8)
    fig.suptitle(f"raylab against its own {args.curve_ref_spp}-spp render"
                 + ("" if raylab.has_denoise else " (no --denoise yet: noisy only)"), fontsize=11)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(args.plot)), exist_ok=True)
    fig.savefig(args.plot, dpi=100)
    plt.close(fig)


# ----------------------------------------------------------------------------------------------


def parse_size(text):
    m = re.fullmatch(r"(\d+)[x×](\d+)", text.strip())
    if not m or int(m.group(1)) < 1 or int(m.group(2)) < 1:
        raise argparse.ArgumentTypeError(f"expected WxH, got {text!r}")
    return int(m.group(1)), int(m.group(2))


def parse_list(text):
    try:
        out = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers separated by commas, got {text!r}")
    if not out or min(out) < 1:
        raise argparse.ArgumentTypeError(f"expected positive numbers, got {text!r}")
    return out


def parse_thresholds(text):
    try:
        out = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected numbers separated by commas, got {text!r}")
    if not out or min(out) <= 0 or max(out) > 1:
        raise argparse.ArgumentTypeError(f"expected noise thresholds in (0, 1], got {text!r}")
    return out


def parse_modes(text):
    out = [x.strip() for x in text.split(",") if x.strip()]
    if not out or any(x not in ("noisy", "denoised") for x in out):
        raise argparse.ArgumentTypeError(f"expected noisy, denoised or both, got {text!r}")
    return out


def parse_scenes(text):
    out = [x.strip() for x in text.split(",") if x.strip()]
    for s in out:
        if s not in SCENES:
            raise argparse.ArgumentTypeError(f"unknown scene {s!r} (known: {', '.join(SCENES)})")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="See the module docstring (the top of this file) for details.")
    ap.add_argument("--scenes", type=parse_scenes,
                    default=[s for s, v in SCENES.items() if v[4] is None and s not in CAUSTIC_SCENES],
                    help=f"comma-separated, from {', '.join(SCENES)} (default all but the fog "
                    "and caustic scenes)")
    ap.add_argument("--spp", type=parse_list, default=[16, 64], help="default 16,64")
    ap.add_argument("--rounds", type=int, default=1, help="interleaved rounds, seeds 1..N (default 1)")
    ap.add_argument("--modes", type=parse_modes, default=["noisy", "denoised"],
                    help="noisy, denoised or both (default noisy,denoised)")
    ap.add_argument("--raylab-integrator", choices=INTEGRATORS,
                    help="raylab's --integrator for every scene (default: bdpt for the caustic "
                         "scenes, path for the others)")
    ap.add_argument("--threads", type=int, default=2, help="threads of each renderer (default 2)")
    ap.add_argument("--ref-spp", type=int, default=1024,
                    help="spp of each renderer's own converged render (default 1024)")
    ap.add_argument("--size", type=parse_size, default=(320, 240),
                    help="WxH of helmet-venice, showcase, street and glass-lamps (default 320x240)")
    ap.add_argument("--box-size", type=parse_size, default=(256, 256),
                    help="WxH of cornell-glass (default 256x256)")
    ap.add_argument("--raylab", default=default_raylab(),
                    help="raylab binary (default target/release/raylab, else ../main's)")
    ap.add_argument("--venv", default=DEFAULT_VENV,
                    help="CPython 3.13 venv with bpy (../shared/cycles/setup.sh), created if "
                         "missing (default ~/.cache/raylab-cycles-venv)")
    ap.add_argument("--no-setup", action="store_true", help="fail instead of creating the venv")
    ap.add_argument("--shared", default=DEFAULT_SHARED, help="the shared folder holding the Cycles peer, cycles/ (default ../shared)")
    ap.add_argument("--cache", default=DEFAULT_CACHE,
                    help="converged references and outputs (default ../bench-data/cycles)")
    ap.add_argument("--fresh-refs", action="store_true", help="re-render the references")
    ap.add_argument("--json", help="all numbers (default CACHE/compare_cycles-last.json)")
    ap.add_argument("--previews", help="PNG previews folder (default CACHE/previews)")
    ap.add_argument("--timeout", type=float, default=3600.0,
                    help="seconds any one render may take (default 3600)")
    ap.add_argument("--ladder", type=parse_list, default=[],
                    help="raylab --denoise at these spp too, to find the fewest that reach "
                         "Cycles+OIDN's errors at --target-spp (e.g. 8,12,16,24,32,48,64,96,128)")
    ap.add_argument("--target-spp", type=int, default=16,
                    help="the Cycles+OIDN run that --ladder aims at (one of --spp; default 16)")
    ap.add_argument("--curve", action="store_true",
                    help="raylab only: error against spp, noisy and denoised, CSV + plot")
    ap.add_argument("--curve-spp", type=parse_list,
                    default=[1 << k for k in range(11)], help="default 1,2,4,...,1024")
    ap.add_argument("--curve-ref-spp", type=int, default=4096, help="default 4096")
    ap.add_argument("--adaptive", type=parse_thresholds, metavar="T1,T2,...",
                    help="adaptive sampling at these noise thresholds (e.g. 0.1,0.03,0.01): raylab "
                         "--noise-threshold against Cycles' adaptive sampling, and each at fixed spp")
    ap.add_argument("--adaptive-spp", type=int, default=1024,
                    help="the cap of the adaptive runs' samples per pixel (default 1024)")
    ap.add_argument("--csv", help="curve CSV (default CACHE/denoise_curve.csv)")
    ap.add_argument("--plot", help="curve plot PNG (default CACHE/denoise_curve.png)")
    args = ap.parse_args()
    if args.rounds < 1 or args.threads < 1 or args.ref_spp < 2 or args.curve_ref_spp < 2:
        ap.error("--rounds and --threads must be at least 1, the reference spp at least 2")
    if args.adaptive and args.curve:
        ap.error("--adaptive and --curve are two different runs")
    if args.adaptive_spp < 1:
        ap.error("--adaptive-spp must be at least 1")
    args.cache = os.path.abspath(args.cache)
    args.json = args.json or os.path.join(
        args.cache, "compare_cycles-adaptive-last.json" if args.adaptive else "compare_cycles-last.json")
    args.previews = args.previews or os.path.join(args.cache, "previews")
    args.csv = args.csv or os.path.join(args.cache, "denoise_curve.csv")
    args.plot = args.plot or os.path.join(args.cache, "denoise_curve.png")

    # SIGTERM ends like Ctrl-C: the children are killed and the temporary folder removed.
    def on_term(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, on_term)
    try:
        if not args.curve:
            ensure_venv(args)
        elif missing_modules():
            ensure_venv(args)
        with tempfile.TemporaryDirectory(prefix="compare_cycles.") as tmp:
            if args.curve:
                status = curve(args, tmp)
            elif args.adaptive:
                status = adaptive(args, tmp)
            else:
                status = compare(args, tmp)
    except Fail as e:
        print(f"{PROG}: error: {e}", file=sys.stderr)
        sys.exit(1)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        sys.exit(130)
    sys.exit(status or 0)


if __name__ == "__main__":
    main()
