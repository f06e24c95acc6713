#!/usr/bin/env python3
"""Mitsuba 3's documentation scenes on raylab, beside Mitsuba's own noise (issue 43).

For each top-level scene of a mitsuba-data checkout's `docs/scenes/*.xml` (the
`include/` fragments are read through them):

1. `raylab render` at the scene's own resolution; a scene raylab refuses (a plugin
   or parameter it does not read yet: one line, exit 1) is listed with that line.
   A perspective sensor's `focus_distance` (which Mitsuba's pinhole reads and
   ignores, and which raylab refuses today) is first tried as written; if that is
   the refusal, the scene is retried from a copy of the folder with that one
   parameter removed from perspective sensors only (`--no-patch`: don't), and the
   table says so. Every other refusal stands.
2. A Mitsuba reference (`--variant`, by the interpreter `--mitsuba`, the same
   threads): the spp is what fits in `--ref-seconds` by a timed pilot (at most
   `--max-ref-spp`), in two independent halves, cached in `--cache` keyed by the
   scene's text, its includes', the variant and the budget. The reference's own
   noise is reported as relMSE(half 0, half 1) / 4 (the halves' difference has
   twice a half's noise, which is twice the full reference's).
3. raylab and an independent Mitsuba render at the same spp (the scene's own
   `sample_count`, raised to `--min-spp`), each against the reference.

relMSE(a, b) = mean over pixels and the R, G, B channels of (a − b)² / (b² + 1e-2),
b the reference (linear radiance as both EXRs hold it).

Verdict: "agrees" when raylab's relMSE is at most 2× Mitsuba's at the same spp and
the 16×16-block means agree as well as Mitsuba's do (block relMSE at most 3×
Mitsuba's + 1e-5); "noisier" when only the first fails; "differs" when the block
means disagree (a bias, not noise). The per-channel ratio of image means
(raylab / reference) is in the table too.

Side-by-side PNGs (reference | Mitsuba same spp | raylab, tonemapped alike: exposure
from the reference's 99th percentile, clamp, sRGB) go to `--images`.

    python3 tools/mitsuba_docs.py --data <mitsuba-data checkout> \\
        --mitsuba <python with mitsuba==3.7.1> [--variant llvm_ad_rgb] \\
        [--raylab target/release/raylab] [--cache DIR] [--images DIR] [--out DIR] \\
        [--threads 2] [--ref-seconds 120] [--only NAME] [--table table.md]

Needs numpy, OpenEXR (and Pillow for the PNGs). `llvm_*` variants need
DRJIT_LIBLLVM_PATH; unless set, the first of Debian's libLLVM-19.so, -15.so.1,
-14.so.1 that exists is used.
"""

import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from compare_mitsuba import LIBLLVM  # noqa: E402
from mitsuba_suite import read_rgb  # noqa: E402

EPS = 1e-2
BLOCK = 16

# Run by the interpreter that has Mitsuba. argv: scene, defines (JSON), variant,
# threads, ref seconds, max ref spp, min spp, out (.npz). Renders in passes of
# at most 2^23 samples (llvm variants hold a whole pass in memory); every pass has
# the same spp, so the passes' mean is the image of all their samples.
MITSUBA_SCRIPT = r"""
import json, sys, time, numpy as np
import mitsuba as mi, drjit as dr
scene_path, defines, variant, threads = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3], int(sys.argv[4])
ref_seconds, max_ref_spp, min_spp, out = float(sys.argv[5]), int(sys.argv[6]), int(sys.argv[7]), sys.argv[8]
mi.set_variant(variant)
mi.set_log_level(mi.LogLevel.Error)
dr.set_thread_count(threads)
scene = mi.load_file(scene_path, **defines)
sensor = scene.sensors()[0]
w, h = [int(x) for x in sensor.film().size()]
own = int(sensor.sampler().sample_count())
spp = max(own, min_spp)
sampler = sensor.sampler().class_().name() if hasattr(sensor.sampler(), "class_") else str(type(sensor.sampler()))
cap = max(1, (1 << 23) // (w * h))
# A pass of the scene's own spp when it fits (stratified and other samplers want
# their own counts), else the largest that fits.
chunk = own if own <= cap else cap
def render(k, seed):
    return np.array(mi.render(scene, spp=k, seed=seed), dtype=np.float64)[:, :, :3]
def passes(total, seed0):
    acc, n, seed = 0.0, 0, seed0
    while n < total:
        acc = acc + render(chunk, seed); n += chunk; seed += 1
    return acc / (n // chunk), n
render(chunk, 999)  # warm-up (JIT)
t = time.time(); render(chunk, 998); per_spp = (time.time() - t) / chunk
half = int(ref_seconds / per_spp / 2) // chunk * chunk
half = max(chunk, min(half, max_ref_spp // 2 // chunk * chunk))
t = time.time()
h0, n0 = passes(half, 1 << 20)
h1, n1 = passes(half, 1 << 21)
ref_time = time.time() - t
# The same-spp image: the scene's own count in one render when it fits.
t = time.time()
if spp <= cap:
    same = render(spp, 7); same_spp = spp
else:
    k = chunk; acc, n, seed = 0.0, 0, 1 << 22
    while n < spp:
        acc = acc + render(k, seed); n += k; seed += 1
    same, same_spp = acc / (n // k), n
same_time = time.time() - t
np.savez(out, half0=h0, half1=h1, same=same, ref_spp=n0 + n1, same_spp=same_spp, own_spp=own,
         width=w, height=h, per_spp=per_spp, ref_time=ref_time, same_time=same_time,
         version=mi.__version__, variant=variant, chunk=chunk)
"""


def rel_mse(a, b):
    """mean over pixels and channels of (a − b)² / (b² + 1e-2)."""
    return float(np.mean((a - b) ** 2 / (b * b + EPS)))


def blocks(img):
    h, w = img.shape[0] // BLOCK * BLOCK, img.shape[1] // BLOCK * BLOCK
    return img[:h, :w].reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, 3).mean(axis=(1, 3))


def includes(path, seen=None):
    """The scene file and the files it includes (by <include filename=...>), in order."""
    seen = seen if seen is not None else []
    if path in seen or not os.path.exists(path):
        return seen
    seen.append(path)
    text = open(path, encoding="utf-8", errors="replace").read()
    for name in re.findall(r'<include\s+filename="([^"]+)"', text):
        includes(os.path.normpath(os.path.join(os.path.dirname(path), name)), seen)
    return seen


def scene_text(path):
    return "".join(open(p, encoding="utf-8", errors="replace").read() for p in includes(path))


def needs_spp(text):
    """-D spp=… is needed (and allowed) when $spp is used; it is needed when no
    <default name="spp"> gives it a value."""
    return "$spp" in text, bool(re.search(r'<default\s+name="spp"', text))


PERSPECTIVE = re.compile(r'(<sensor\s+type="perspective".*?</sensor>)', re.S)
FOCUS = re.compile(r'\s*<float\s+name="focus_distance"\s+value="[^"]*"\s*/>')


def strip_focus(text):
    return PERSPECTIVE.sub(lambda m: FOCUS.sub("", m.group(1)), text)


def patched_tree(data, root):
    """A copy of data/docs/scenes with `focus_distance` removed from perspective
    sensors (other files linked), beside a link to data/common."""
    src = os.path.join(data, "docs", "scenes")
    dst = os.path.join(root, "docs", "scenes")
    if os.path.isdir(dst):
        return dst
    for folder, _, files in os.walk(src):
        rel = os.path.relpath(folder, src)
        os.makedirs(os.path.join(dst, rel), exist_ok=True)
        for f in files:
            a, b = os.path.join(folder, f), os.path.join(dst, rel, f)
            if f.endswith(".xml"):
                with open(a, encoding="utf-8") as fa, open(b, "w", encoding="utf-8") as fb:
                    fb.write(strip_focus(fa.read()))
            else:
                os.symlink(os.path.abspath(a), b)
    common = os.path.join(root, "common")
    if not os.path.exists(common):
        os.symlink(os.path.abspath(os.path.join(data, "common")), common)
    return dst


def run_raylab(args, scene, spp, out, seed=1):
    text = scene_text(scene)
    used, has_default = needs_spp(text)
    cmd = [args.raylab, "render", scene, "--spp", str(spp), "--seed", str(seed),
           "--threads", str(args.threads), "-o", out]
    if used:
        cmd += ["-D", f"spp={spp}"]
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=os.path.dirname(scene))
    seconds = time.perf_counter() - t
    lines = [x for x in r.stderr.splitlines() + r.stdout.splitlines() if x.strip()]
    return r.returncode, lines, seconds, cmd


def mitsuba_reference(args, scene, defines, key):
    os.makedirs(args.cache, exist_ok=True)
    name = os.path.basename(scene)[:-4]
    path = os.path.join(args.cache, f"{name}-{key}.npz")
    if not os.path.exists(path):
        tmp = path[:-4] + ".tmp"
        env = dict(os.environ)
        found = next((p for p in LIBLLVM if os.path.exists(p)), None)
        if found:
            env.setdefault("DRJIT_LIBLLVM_PATH", found)
        t = time.time()
        r = subprocess.run([args.mitsuba, "-c", MITSUBA_SCRIPT, scene, json.dumps(defines),
                            args.variant, str(args.threads), str(args.ref_seconds),
                            str(args.max_ref_spp), str(args.min_spp), tmp],
                           capture_output=True, text=True, cwd=os.path.dirname(scene), env=env)
        if r.returncode != 0:
            msg = [x for x in r.stderr.splitlines() if x.strip()]
            raise RuntimeError(" ".join(msg[-3:])[-400:] if msg else "(no message)")
        os.replace(tmp + ".npz", path)
        print(f"# Mitsuba reference of {name}: {time.time() - t:.0f} s", file=sys.stderr, flush=True)
    return dict(np.load(path))


def tonemap(img, scale):
    x = np.clip(img * scale, 0.0, 1.0)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (x * 255 + 0.5).astype(np.uint8)


def side_by_side(path, ref, same, ray):
    try:
        from PIL import Image, ImageDraw
    except ImportError:
        return False
    lum = ref @ np.array([0.2126, 0.7152, 0.0722])
    p = float(np.percentile(lum, 99)) or 1.0
    scale = 1.0 / p
    gap = np.full((ref.shape[0], 4, 3), 255, np.uint8)
    row = np.concatenate([tonemap(ref, scale), gap, tonemap(same, scale), gap, tonemap(ray, scale)], axis=1)
    im = Image.fromarray(row)
    d = ImageDraw.Draw(im)
    w = ref.shape[1] + 4
    for i, label in enumerate(["Mitsuba reference", "Mitsuba, same spp", "raylab"]):
        d.rectangle([i * w, 0, i * w + 8 * len(label) + 6, 14], fill=(0, 0, 0))
        d.text((i * w + 3, 2), label, fill=(255, 255, 255))
    im.save(path)
    return True


def uses(lines):
    """raylab's load summary (`Mitsuba scene: 1 integrator (path), ...`), shortened to
    the integrator, shapes, BSDFs, emitters and textures: `path; obj ×8; diffuse ×5`."""
    for line in lines:
        if line.startswith("Mitsuba scene:"):
            s = line.split(":", 1)[1].strip()
            parts = [p.strip() for p in re.split(r",\s*(?=\d+ )", s)]
            keep = []
            for p in parts:
                m = re.match(r"\d+ (integrator|shapes?|bsdfs?|emitters?|textures?) \((.*)\)$", p)
                if m:
                    keep.append(m.group(2))
            return "; ".join(keep) or s
    return ""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True, help="mitsuba-data checkout (docs/scenes and common/)")
    ap.add_argument("--mitsuba", required=True, help="a Python interpreter with the mitsuba package")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (default llvm_ad_rgb)")
    ap.add_argument("--raylab", default="target/release/raylab")
    ap.add_argument("--cache", default="mitsuba-docs-cache", help="Mitsuba references (and the patched copy)")
    ap.add_argument("--images", default="mitsuba-docs-images", help="side-by-side PNGs")
    ap.add_argument("--out", default="mitsuba-docs-out", help="raylab's EXRs")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--ref-seconds", type=float, default=120.0, help="Mitsuba time per reference")
    ap.add_argument("--max-ref-spp", type=int, default=8192)
    ap.add_argument("--min-spp", type=int, default=32, help="the same-spp renders take at least this")
    ap.add_argument("--only", help="only scenes whose name contains this (comma-separated list)")
    ap.add_argument("--no-patch", action="store_true", help="don't retry without focus_distance")
    ap.add_argument("--table", help="also write the Markdown table to this file")
    args = ap.parse_args()
    args.raylab = os.path.abspath(args.raylab)
    for a in ("cache", "images", "out"):
        setattr(args, a, os.path.abspath(getattr(args, a)))
    os.makedirs(args.out, exist_ok=True)
    os.makedirs(args.images, exist_ok=True)
    folder = os.path.join(args.data, "docs", "scenes")
    names = sorted(f for f in os.listdir(folder) if f.endswith(".xml"))
    if args.only:
        names = [n for n in names if any(o in n for o in args.only.split(","))]
    rows, refused, failed = [], [], []
    start = time.time()
    for name in names:
        stem = name[:-4]
        scene = os.path.join(folder, name)
        exr = os.path.join(args.out, stem + ".exr")
        # Probe: loading is all a refused scene does; a tiny render for the others.
        rc, lines, _, _ = run_raylab(args, scene, 1, exr)
        patched = False
        if rc != 0 and "'focus_distance'" in lines[-1] and not args.no_patch:
            scene = os.path.join(patched_tree(args.data, os.path.join(args.cache, "patched")), name)
            rc, lines, _, _ = run_raylab(args, scene, 1, exr)
            patched = True
        if rc != 0:
            reason = re.sub(r"^error:\s*", "", lines[-1] if lines else "(no message)")
            reason = reason.replace(os.path.dirname(scene) + os.sep, "")
            refused.append((stem, reason, patched))
            print(f"REFUSED  {stem}: {reason}", flush=True)
            continue
        text = scene_text(scene)
        used, has_default = needs_spp(text)
        key_src = hashlib.sha256()
        for p in includes(scene):
            key_src.update(open(p, "rb").read())
        key_src.update(f"{args.variant} {args.ref_seconds} {args.max_ref_spp} {args.min_spp} {args.threads}".encode())
        # Mitsuba reads the scene as written (the patch removes nothing it uses).
        original = os.path.join(folder, name)
        defines = {"spp": 1} if used and not has_default else {}
        try:
            m = mitsuba_reference(args, original, defines, key_src.hexdigest()[:12])
        except RuntimeError as e:
            failed.append((stem, f"Mitsuba cannot render it: {e}"))
            print(f"MITSUBA  {stem}: {e}", flush=True)
            continue
        spp = int(m["same_spp"])
        rc, lines, seconds, cmd = run_raylab(args, scene, spp, exr, seed=1)
        if rc != 0:
            failed.append((stem, lines[-1] if lines else "(no message)"))
            continue
        ray = read_rgb(exr)
        h0, h1, same = m["half0"], m["half1"], m["same"]
        ref = 0.5 * (h0 + h1)
        if ray.shape != ref.shape:
            failed.append((stem, f"size {ray.shape} != {ref.shape}"))
            continue
        noise = rel_mse(h0, h1) / 4
        e_ray, e_mi = rel_mse(ray, ref), rel_mse(same, ref)
        b_ray, b_mi = rel_mse(blocks(ray), blocks(ref)), rel_mse(blocks(same), blocks(ref))
        ratio = ray.mean(axis=(0, 1)) / np.maximum(ref.mean(axis=(0, 1)), 1e-12)
        if b_ray > 3 * b_mi + 1e-5:
            verdict = "differs"
        elif e_ray > 2 * e_mi:
            verdict = "noisier"
        else:
            verdict = "agrees"
        warn = [x for x in lines if x.startswith("warning:")]
        png = os.path.join(args.images, stem + ".png")
        side_by_side(png, ref, same, ray)
        rows.append(dict(scene=stem, uses=uses(lines), patched=patched, w=int(m["width"]),
                         h=int(m["height"]), spp=spp, own=int(m["own_spp"]), ref_spp=int(m["ref_spp"]),
                         ref_time=float(m["ref_time"]), noise=noise, ray=e_ray, mi=e_mi, bray=b_ray,
                         bmi=b_mi, ratio=[float(x) for x in ratio], verdict=verdict,
                         ray_s=seconds, mi_s=float(m["same_time"]), warnings=warn,
                         version=str(m["version"])))
        print(f"{verdict.upper():8} {stem}: {m['width']}×{m['height']} {spp} spp: raylab relMSE "
              f"{e_ray:.3e} ({seconds:.1f} s), Mitsuba {e_mi:.3e} ({float(m['same_time']):.1f} s); "
              f"blocks {b_ray:.2e} / {b_mi:.2e}; reference {int(m['ref_spp'])} spp, own noise "
              f"{noise:.1e}; mean ratio " + " ".join(f"{x:.4f}" for x in ratio), flush=True)

    version = rows[0]["version"] if rows else None
    out = []
    out.append("| scene | what it uses | size, spp | raylab relMSE | Mitsuba relMSE (same spp) "
               "| 16² blocks: raylab / Mitsuba | raylab mean / ref (R G B) | reference spp (own noise) | verdict |")
    out.append("| --- | --- | --- | ---: | ---: | ---: | --- | --- | --- |")
    for r in rows:
        mark = " †" if r["patched"] else ""
        out.append(
            f"| `{r['scene']}`{mark} | {r['uses']} | {r['w']}×{r['h']}, {r['spp']} | {r['ray']:.2e} | "
            f"{r['mi']:.2e} | {r['bray']:.1e} / {r['bmi']:.1e} | "
            + " ".join(f"{x:.3f}" for x in r["ratio"])
            + f" | {r['ref_spp']} ({r['noise']:.0e}) | {r['verdict']} |")
    out.append("")
    out.append(f"† read from a copy with the perspective sensor's `focus_distance` removed "
               f"(raylab refuses it; Mitsuba reads it and a pinhole ignores it).")
    out.append("")
    out.append("Refused by raylab (its one-line reason; † after removing `focus_distance`):")
    out.append("")
    for stem, reason, patched in refused:
        out.append(f"- `{stem}`{' †' if patched else ''}: {reason}")
    for stem, reason in failed:
        out.append(f"- `{stem}`: not compared: {reason}")
    out.append("")
    out.append(f"{len(rows)} scenes compared, {len(refused)} refused, {len(failed)} not compared; "
               f"Mitsuba {version or '?'} `{args.variant}`, {args.threads} threads each; "
               f"run took {time.time() - start:.0f} s.")
    table = "\n".join(out)
    print()
    print(table)
    if args.table:
        with open(args.table, "w") as f:
            f.write(table + "\n")
        with open(args.table + ".json", "w") as f:
            json.dump(dict(rows=rows, refused=refused, failed=failed), f, indent=1)


if __name__ == "__main__":
    main()
