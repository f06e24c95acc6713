#!/usr/bin/env python3
"""raylab's path tracer against Mitsuba 3 (`llvm_ad_rgb`): time to quality, in one run.

Usage (from the project folder; the raylab binary must be built):

    python3 tools/compare_mitsuba.py [--rounds 2] [--scenes cornell,cornell-area]
                                     [--targets 1e-2,1e-3] [--threads N]
                                     [--raylab PATH] [--venv DIR] [--cache DIR]
                                     [--max-seconds S] [--ref-spp N]
    python3 tools/compare_mitsuba.py --check 4096   # the Mitsuba scene against assets/refs

Scenes, 256×256, both renderers' `path` integrator with unbounded depth:
  cornell       the lab box lit by its point light (P = 14 at (0, −0.5, −0.7)), judged
                against assets/refs/cornell-path-mitsuba-256.exr (Mitsuba, 16,384 spp);
  cornell-area  the box lit by the one-sided ceiling patch (radiance 17, 12, 4, facing
                down), tall block a perfect mirror, short block glass of IOR 1.5 (raylab:
                `cornell-area --material tall=mirror,short=glass`), judged against a
                Mitsuba reference rendered once by this tool (--ref-spp, default 16384,
                in two independent halves whose relMSE gives its own noise) and cached
                in --cache.
Mitsuba 3 XML scenes (--xml PATH[::NAME=VALUE,...], repeatable; the built-in scenes are
then left out unless --scenes names them): both renderers read the same file, at the
file's own size, with the same defines (`-D NAME=VALUE` for raylab, keyword arguments of
`mi.load_file` for Mitsuba; `spp` is added for raylab when the file uses `$spp`). The
reference is rendered by Mitsuba (--ref-spp, two halves, in passes of at most 2^23
samples) and cached like cornell-area's, keyed by the text of the file and its includes
and the defines. --mitsuba-spp N,... replaces --targets: each scene's targets are the
relMSE Mitsuba's pilot predicts at N spp (c / N plus the reference's own noise), i.e. the
time each renderer needs to reach Mitsuba's error at N spp. For example (2026-11-29,
docs/mitsuba-scenes.md, "Speed: time to Mitsuba's error on XML scenes"):

    python3 tools/compare_mitsuba.py --threads 2 --rounds 3 --ref-spp 1024 --mitsuba-spp 64 \
        --xml docs-copy/bsdf_twosided_cbox.xml \
        --xml "bitterli/cornell-box/mitsuba/scene_v3.xml::integrator=path,resx=512,resy=512"

The log's first line names raylab's BVH box test (AVX2 unless the CPU lacks it or
RAYLAB_NO_AVX2 is set).

relMSE as in assets/refs/README.md: mean over pixels and channels of
(c − r)² / (r² + ε), ε = 0.01·mean(r)².

For each scene, renderer and target relMSE it first finds the samples per pixel
needed (a pilot render gives c = relMSE·spp, then spp = c/target is rendered and
corrected until the render reaches the target with the spp no more than about 5 %
above what is needed), then times renders at those spp for --rounds rounds,
alternating raylab and Mitsuba, each with a new seed (the same seeds in every run),
and keeps the best time per renderer (3× --rounds rounds where both renders take
under 5 s). A target that the reference is too noisy to judge (its own noise above a
quarter of the target) or whose render would take longer than --max-seconds is not
rendered: its row is an estimate, spp = c/target at the time per spp of the
scene's largest timed render. Every timed render is checked against the reference;
the table gives the worst relMSE of the timed renders.

What is timed:
  raylab   the wall clock of the whole process (`raylab render ... -o x.exr -q`:
           start-up, scene and BVH build, render, EXR write), from a copy of the
           binary made at the start so that a rebuild during the run changes nothing;
  Mitsuba  `mi.render(scene, spp=N, seed=S)` plus `numpy.array(image)` (which waits
           for the result), in this process, after the scene is loaded and after one
           untimed render at the same spp (JIT compilation and kernel-cache warm-up
           excluded; the calibration render at that spp is that warm-up).
Both use the same number of threads (--threads, default all cores; Mitsuba via
`drjit.set_thread_count`).

Needs numpy and mitsuba (PyPI) with LLVM: on Debian `apt-get install libllvm19` (or 15;
DRJIT_LIBLLVM_PATH, unless set, is the first of libLLVM-19.so, libLLVM-15.so.1 and
libLLVM-14.so.1 in /usr/lib/x86_64-linux-gnu that exists). If this Python cannot import
mitsuba, the tool re-runs itself with --venv's Python, creating that venv (`python3 -m
venv DIR` and `DIR/bin/pip install mitsuba==3.7.1 numpy`) if it does not exist yet
(Mitsuba 3.9.1 aborts in LLVM on AMD Zen 5 CPUs: see MITSUBA below).
"""

import argparse
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED_REF = os.path.join(ROOT, "assets", "refs", "cornell-path-mitsuba-256.exr")
# Debian's LLVM libraries, newest first: the first that exists is Dr.Jit's (unless
# DRJIT_LIBLLVM_PATH is set).
LIBLLVM = ["/usr/lib/x86_64-linux-gnu/libLLVM-19.so", "/usr/lib/x86_64-linux-gnu/libLLVM-15.so.1",
           "/usr/lib/x86_64-linux-gnu/libLLVM-14.so.1"]
# The Mitsuba a new venv gets. 3.9.1 (Dr.Jit 1.5.0) aborts on the AMD EPYC (Zen 5, AVX-512)
# of 2026-11-27 in LLVM 15 and 19 alike ("LLVM ERROR: Cannot select: ... fminimum", its
# first kernel), whatever target CPU Dr.Jit is given; 3.7.1 (Dr.Jit 1.2.0) runs there and
# on the Xeons where 3.9.1 ran.
MITSUBA = "mitsuba==3.7.1"
SIZE = 256


# ----------------------------------------------------------------------------------
# Environment: make sure numpy and mitsuba can be imported, else use/create a venv.


def default_raylab():
    here = os.path.join(ROOT, "target", "release", "raylab")
    main = os.path.join(ROOT, "..", "main", "target", "release", "raylab")
    return here if os.path.exists(here) or not os.path.exists(main) else main


def ensure_mitsuba(args):
    found = next((p for p in LIBLLVM if os.path.exists(p)), None)
    if found:
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", found)
    try:
        import numpy  # noqa: F401
        import mitsuba  # noqa: F401
        return
    except ImportError:
        pass
    if os.environ.get("COMPARE_MITSUBA_REEXEC"):
        sys.exit(
            f"error: {sys.executable} cannot import numpy and mitsuba; install them with\n"
            f"  {sys.executable} -m pip install {MITSUBA} numpy"
        )
    venv = os.path.abspath(args.venv)
    py = os.path.join(venv, "bin", "python")
    if not os.path.exists(py):
        print(f"# creating the venv {venv} (python3 -m venv)", file=sys.stderr)
        subprocess.run([sys.executable, "-m", "venv", venv], check=True)
    ok = subprocess.run([py, "-c", "import numpy, mitsuba"], capture_output=True).returncode == 0
    if not ok:
        print(f"# installing {MITSUBA} and numpy into {venv} (pip)", file=sys.stderr)
        r = subprocess.run([py, "-m", "pip", "install", "-q", MITSUBA, "numpy"])
        if r.returncode != 0:
            sys.exit(
                f"error: could not install mitsuba into {venv}; do it by hand:\n"
                f"  python3 -m venv {venv} && {venv}/bin/pip install {MITSUBA} numpy\n"
                "Mitsuba's llvm variants also need LLVM (Debian: apt-get install libllvm19)."
            )
    os.environ["COMPARE_MITSUBA_REEXEC"] = "1"
    os.execv(py, [py, os.path.abspath(__file__)] + sys.argv[1:])


# ----------------------------------------------------------------------------------
# The lab box, as src/load/cornell.rs builds it (y down, box [-1, 1]³, no front wall).

L = 555.0
GREEN, PURPLE, YELLOW = (0.15, 0.75, 0.15), (0.75, 0.15, 0.75), (0.75, 0.75, 0.15)
CYAN, WHITE = (0.15, 0.75, 0.75), (0.75, 0.75, 0.75)
RED, BLUE = (0.75, 0.15, 0.15), (0.15, 0.15, 0.75)
LIGHT_POSITION = (0.0, -0.5, -0.7)
LIGHT_POWER = 14.0
AREA_LIGHT_CORNERS = [(-0.24, -0.999, -0.19), (0.24, -0.999, -0.19),
                      (0.24, -0.999, 0.19), (-0.24, -0.999, 0.19)]
AREA_LIGHT_RADIANCE = (17.0, 12.0, 4.0)
PARTS = {"floor": (0, 2), "left": (2, 4), "right": (4, 6), "ceiling": (6, 8),
         "back": (8, 10), "short": (10, 20), "tall": (20, 30)}


def normalise(p):
    q = [c * (2.0 / L) - 1.0 for c in p]
    return (-q[0], -q[1], q[2])


def box_triangles():
    """The 30 triangles (as raylab orders their vertices) and their reflectances."""
    tris, rho = [], []

    def push(a, b, c, color):
        tris.append((normalise(a), normalise(b), normalise(c)))
        rho.append(color)

    a, b, c, d = (L, 0, 0), (0, 0, 0), (L, 0, L), (0, 0, L)
    e, f, g, h = (L, L, 0), (0, L, 0), (L, L, L), (0, L, L)
    push(c, b, a, GREEN)
    push(c, d, b, GREEN)
    push(a, e, c, PURPLE)
    push(c, e, g, PURPLE)
    push(f, b, d, YELLOW)
    push(h, f, d, YELLOW)
    push(e, f, g, CYAN)
    push(f, h, g, CYAN)
    push(g, d, c, WHITE)
    push(g, h, d, WHITE)
    blocks = [([(290, 114), (130, 65), (240, 272), (82, 225)], 165.0, RED),
              ([(423, 247), (265, 296), (472, 406), (314, 456)], 330.0, BLUE)]
    for base, height, color in blocks:
        a, b, c, d = [(x, 0.0, z) for x, z in base]
        e, f, g, h = [(x, height, z) for x, z in base]
        for p, q, r in [(e, b, a), (e, f, b), (f, d, b), (f, h, d), (h, c, d),
                        (h, g, c), (g, e, c), (e, a, c), (g, f, e), (g, h, f)]:
            push(p, q, r, color)
    return tris, rho


def write_obj(path, tris):
    """Writes triangles with their winding reversed: raylab's front normal is
    normalize(cross(v2 − v0, v1 − v0)), Mitsuba's normalize(cross(v1 − v0, v2 − v0)),
    so (v0, v2, v1) gives Mitsuba the same front side (it matters for the one-sided
    area light and for which side of the glass is inside)."""
    with open(path, "w") as out:
        for t in tris:
            for v in (t[0], t[2], t[1]):
                out.write("v %.9g %.9g %.9g\n" % v)
        for i in range(len(tris)):
            out.write("f %d %d %d\n" % (3 * i + 1, 3 * i + 2, 3 * i + 3))


SCENES = {
    # name: (raylab arguments, materials of parts other than diffuse, area light)
    "cornell": (["cornell"], {}, False),
    "cornell-area": (["cornell-area", "--material", "tall=mirror,short=glass"],
                     {"tall": "mirror", "short": "glass"}, True),
}


# Mitsuba XML scenes given with --xml (name -> (path, {define: value})): the same
# file is read by both renderers, each at the file's own resolution.
XML = {}


def parse_xml_arg(arg):
    """`PATH[::NAME=VALUE,...]` (defines for both renderers, as `-D`) -> name, path, defines.
    A define written `raylab:NAME=VALUE` is raylab's only (e.g. a `.vdb` file where
    Mitsuba reads the same grid converted to `.vol`: tools/vdb_to_vol.py).
    The name is the file's stem, or, for `scene*.xml`, its folder's name (the folder
    above a `mitsuba` folder: `cornell-box/mitsuba/scene_v3.xml` is `cornell-box`)."""
    path, _, rest = arg.partition("::")
    path = os.path.abspath(path)
    defines = dict(kv.split("=", 1) for kv in rest.split(",") if kv)
    stem = os.path.basename(path)[:-4]
    name = stem
    if stem.startswith("scene"):
        folder = os.path.dirname(path)
        if os.path.basename(folder) == "mitsuba":
            folder = os.path.dirname(folder)
        name = os.path.basename(folder)
    return name, path, defines


def xml_text(path):
    """The file and the files it includes, for cache keys and for `$spp`."""
    import re

    out, todo, seen = [], [path], set()
    while todo:
        p = todo.pop(0)
        if p in seen or not os.path.exists(p):
            continue
        seen.add(p)
        text = open(p, encoding="utf-8", errors="replace").read()
        out.append(text)
        todo += [os.path.normpath(os.path.join(os.path.dirname(p), f))
                 for f in re.findall(r'<include\s+filename="([^"]+)"', text)]
    return "".join(out)


def mitsuba_scene_dict(name, objdir):
    """The Mitsuba 3 scene for `name` (built from OBJ files written into objdir)."""
    import mitsuba as mi

    _, materials, area = SCENES[name]
    tris, rho = box_triangles()
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": math.degrees(2.0 * math.atan(0.5)),
            # Camera space of the lab: x right, y down (image rows), z forward.
            "to_world": mi.ScalarTransform4f().look_at(
                origin=[0, 0, -3], target=[0, 0, 0], up=[0, -1, 0]),
            "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": 1},
        },
    }
    # One mesh per (part, colour): the room's parts and the two blocks.
    for part, (lo, hi) in PARTS.items():
        path = os.path.join(objdir, f"{name}-{part}.obj")
        write_obj(path, tris[lo:hi])
        kind = materials.get(part, "diffuse")
        if kind == "diffuse":
            bsdf = {"type": "twosided", "bsdf": {
                "type": "diffuse",
                "reflectance": {"type": "rgb", "value": list(rho[lo])}}}
        elif kind == "mirror":
            # raylab's `mirror`: reflectance 1 at every angle.
            bsdf = {"type": "conductor", "material": "none"}
        elif kind == "glass":
            # raylab's `glass`: a smooth interface between index 1 and 1.5.
            bsdf = {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}
        else:
            raise ValueError(kind)
        d[part] = {"type": "obj", "filename": path, "face_normals": True, "bsdf": bsdf}
    if area:
        a, b, c, dd = AREA_LIGHT_CORNERS
        path = os.path.join(objdir, f"{name}-light.obj")
        write_obj(path, [(a, b, c), (a, c, dd)])
        d["light"] = {
            "type": "obj", "filename": path, "face_normals": True,
            # Emits from its front (lower, +y) side only and reflects nothing.
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}},
            "emitter": {"type": "area",
                        "radiance": {"type": "rgb", "value": list(AREA_LIGHT_RADIANCE)}},
        }
    else:
        d["light"] = {
            "type": "point",
            "position": list(LIGHT_POSITION),
            # Power P per channel: intensity P/(4π) W/sr.
            "intensity": {"type": "rgb", "value": [LIGHT_POWER / (4 * math.pi)] * 3},
        }
    return d


def scene_key(name):
    """A hash of everything that defines a scene, so that cached references follow it."""
    if name in XML:
        path, defines = XML[name]
        src = xml_text(path) + json.dumps(sorted(defines.items()))
        return hashlib.sha256(src.encode()).hexdigest()[:10]
    src = json.dumps([SCENES[name], box_triangles(), AREA_LIGHT_CORNERS, AREA_LIGHT_RADIANCE,
                      LIGHT_POSITION, LIGHT_POWER, SIZE, "path max_depth -1 box independent"])
    return hashlib.sha256(src.encode()).hexdigest()[:10]


# ----------------------------------------------------------------------------------
# Images and errors.


def read_exr(path):
    import mitsuba as mi
    import numpy as np

    bmp = mi.Bitmap(path)
    if bmp.pixel_format() != mi.Bitmap.PixelFormat.RGB:
        bmp = bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False)
    return np.array(bmp, dtype=np.float64)[:, :, :3]


def write_exr(path, img):
    import mitsuba as mi
    import numpy as np

    mi.Bitmap(np.asarray(img, dtype=np.float32), mi.Bitmap.PixelFormat.RGB).write(path)


def rel_mse(img, ref):
    """As assets/refs/README.md (and raylab::film::rel_mse) define it."""
    eps = 0.01 * ref.mean() ** 2
    return float((((img - ref) ** 2) / (ref * ref + eps)).mean())


# ----------------------------------------------------------------------------------
# Renderers.


class Raylab:
    name = "raylab"

    def __init__(self, binary, threads, tmp):
        self.binary, self.threads, self.tmp = binary, threads, tmp
        self.seed = 1000

    def render(self, scene, spp, warm_up=None):
        """(image, seconds): the whole process, wall clock (nothing to warm up)."""
        self.seed += 1
        out = os.path.join(self.tmp, "raylab.exr")
        if scene in XML:
            path, defines = XML[scene]
            d = {k: v for k, v in defines.items() if not k.startswith("raylab:")}
            d.update({k[7:]: v for k, v in defines.items() if k.startswith("raylab:")})
            if "$spp" in xml_text(path):
                d["spp"] = spp
            cmd = [self.binary, "render", path, *[f"-D{k}={v}" for k, v in d.items()],
                   "--spp", str(spp), "--seed", str(self.seed), "--threads", str(self.threads),
                   "-o", out, "-q"]
        else:
            cmd = [self.binary, "render", *SCENES[scene][0], "--integrator", "path",
                   "--width", str(SIZE), "--height", str(SIZE), "--spp", str(spp),
                   "--seed", str(self.seed), "--threads", str(self.threads), "-o", out, "-q"]
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True)
        t = time.perf_counter() - t0
        return read_exr(out), t


class Mitsuba:
    name = "Mitsuba"

    def __init__(self, threads, tmp):
        import drjit as dr
        import mitsuba as mi

        mi.set_variant("llvm_ad_rgb")
        mi.set_log_level(mi.LogLevel.Warn)
        dr.set_thread_count(threads)
        self.mi, self.tmp = mi, tmp
        self.scenes, self.warm = {}, set()
        self.seed = 1000

    def scene(self, name):
        if name not in self.scenes:
            if name in XML:
                path, defines = XML[name]
                mine = {k: v for k, v in defines.items() if not k.startswith("raylab:")}
                self.scenes[name] = self.mi.load_file(path, **mine)
            else:
                self.scenes[name] = self.mi.load_dict(mitsuba_scene_dict(name, self.tmp))
        return self.scenes[name]

    def render(self, scene, spp, seed=None, warm_up=True):
        """(image, seconds): mi.render + numpy.array, after an untimed warm-up render
        at the same spp if this process has not rendered this scene at it yet."""
        import numpy as np

        s = self.scene(scene)
        if warm_up and (scene, spp) not in self.warm:
            self.seed += 1
            np.array(self.mi.render(s, spp=spp, seed=self.seed))
        self.warm.add((scene, spp))
        if seed is None:
            self.seed += 1
            seed = self.seed
        t0 = time.perf_counter()
        img = np.array(self.mi.render(s, spp=spp, seed=seed), dtype=np.float64)
        t = time.perf_counter() - t0
        return img[:, :, :3], t

    def pixels(self, scene):
        w, h = self.scene(scene).sensors()[0].film().size()
        return int(w) * int(h)


# ----------------------------------------------------------------------------------
# References.


def reference(name, args, mitsuba):
    """The reference image of `name`, its own noise (relMSE against the exact image)
    and a note on where it comes from."""
    if name == "cornell" and name not in XML:
        # assets/refs/README.md: its two 8,192-spp halves differ by 1.2e-4.
        return (read_exr(args.ref), 3e-5,
                f"{os.path.relpath(args.ref)} (Mitsuba 3.9.1, 16,384 spp, own noise ≈ 3e-5)")
    import numpy as np

    os.makedirs(args.cache, exist_ok=True)
    spp = args.ref_spp
    size = "xml" if name in XML else SIZE
    base = os.path.join(args.cache, f"{name}-mitsuba-{size}-{spp}spp-{scene_key(name)}")
    if not os.path.exists(base + ".exr"):
        # Passes of at most 2^23 samples: llvm variants hold a whole pass in memory.
        chunk = max(1, min(512, spp // 2, (1 << 23) // mitsuba.pixels(name)))
        halves = []
        t0 = time.perf_counter()
        print(f"# rendering the {name} reference with Mitsuba: {spp} spp in passes of "
              f"{chunk} (once; cached in {args.cache})", file=sys.stderr, flush=True)
        seed = 1 << 20
        for _ in range(2):
            acc, n = 0.0, 0
            while n < spp // 2:
                k = min(chunk, spp // 2 - n)
                seed += 1
                img, _ = mitsuba.render(name, k, seed=seed, warm_up=False)
                acc = acc + img * k
                n += k
            halves.append(acc / n)
        write_exr(base + "-half0.exr", halves[0])
        write_exr(base + "-half1.exr", halves[1])
        full = 0.5 * (halves[0] + halves[1])
        write_exr(base + ".exr", full)
        noise = rel_mse(halves[0], halves[1])
        meta = {"scene": name, "spp": spp, "halves_rel_mse": noise,
                "seconds": time.perf_counter() - t0, "scene_key": scene_key(name)}
        with open(base + ".json", "w") as f:
            json.dump(meta, f, indent=1)
    with open(base + ".json") as f:
        meta = json.load(f)
    noise = meta["halves_rel_mse"]
    ref = read_exr(base + ".exr")
    return ref, noise / 4, (f"{os.path.relpath(base)}.exr (Mitsuba {spp} spp; relMSE between its "
                 f"two halves {noise:.2e}, so its own noise ≈ {noise / 4:.1e})")


# ----------------------------------------------------------------------------------
# Finding the spp for a target, and timing.


class Calibration:
    """What the untimed renders of one renderer on one scene found: c (relMSE × spp,
    with the reference's own noise taken out) and the time per spp."""

    def __init__(self, renderer, scene, ref, noise, log):
        self.r, self.scene, self.ref, self.noise, self.log = renderer, scene, ref, noise, log
        self.c, self.per_spp, self.reached = None, None, {}

    def render(self, spp, warm_up=False):
        img, t = self.r.render(self.scene, spp, warm_up=warm_up)
        e = rel_mse(img, self.ref)
        self.c = max(e - self.noise, 1e-12) * spp
        self.per_spp = t / spp
        ratio = img.mean(axis=(0, 1)) / self.ref.mean(axis=(0, 1))
        self.log(f"{self.r.name:7} {self.scene}: {spp} spp relMSE {e:.3e} "
                 f"(c = {self.c:.3f}) {t:.2f} s; mean / reference's R G B "
                 + " ".join(f"{x:.4f}" for x in ratio))
        return e

    def needed(self, target):
        """spp for relMSE ≤ target against the reference, 3 % to spare."""
        return max(1, math.ceil(self.c / (target - self.noise) * 1.03))

    def find(self, target, max_seconds):
        """The smallest spp found to reach target (None: too slow, see estimate)."""
        best, spp = None, self.needed(target)
        for _ in range(4):
            if spp * self.per_spp > max_seconds:
                self.log(f"{self.r.name:7} {self.scene}: {target:g} needs ≈ {spp} spp, "
                         f"≈ {spp * self.per_spp:.0f} s > --max-seconds: estimated only")
                return best
            e = self.render(spp)
            if e <= target:
                best = spp if best is None else min(best, spp)
            nxt = self.needed(target)
            if (e <= target and nxt >= 0.95 * spp) or (best is not None and nxt >= best):
                break
            spp = nxt
        return best if best is not None else spp


def fmt_t(s):
    return f"{s:.2f}" if s < 10 else f"{s:.1f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", default=None,
                    help="built-in scenes (default cornell,cornell-area; none when --xml is given)")
    ap.add_argument("--xml", action="append", default=[], metavar="PATH[::NAME=VALUE,...]",
                    help="a Mitsuba 3 XML scene, read by both renderers at its own resolution "
                    "(repeatable); NAME=VALUE are defines for both (`-D`), "
                    "raylab:NAME=VALUE raylab's only")
    ap.add_argument("--targets", default="1e-2,1e-3")
    ap.add_argument("--mitsuba-spp", default=None, metavar="N,...",
                    help="targets per scene instead of --targets: the relMSE Mitsuba's pilot "
                    "predicts at N spp (c_Mitsuba / N + the reference's noise)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--max-seconds", type=float, default=90.0,
                    help="a target whose render would take longer than this (for either "
                    "renderer), or that the reference is too noisy to judge, is estimated "
                    "from c and the time per spp instead of rendered (default 90)")
    ap.add_argument("--raylab", default=default_raylab(),
                    help="raylab binary (default: target/release/raylab, else ../main's)")
    ap.add_argument("--venv", default=os.path.join(ROOT, "..", "venv"),
                    help="venv with mitsuba and numpy, created if missing (default ../venv)")
    ap.add_argument("--cache", default=os.path.join(ROOT, "..", "bench-data", "mitsuba"),
                    help="where Mitsuba references of cornell-area are kept")
    ap.add_argument("--ref", default=SHARED_REF, help="reference of `cornell`")
    ap.add_argument("--ref-spp", type=int, default=16384,
                    help="spp of the cornell-area reference rendered by Mitsuba")
    ap.add_argument("--check", type=int, metavar="SPP",
                    help="only render `cornell` with Mitsuba at SPP and compare it with --ref")
    args = ap.parse_args()
    ensure_mitsuba(args)

    import drjit as dr
    import mitsuba as mi

    for arg in args.xml:
        name, path, defines = parse_xml_arg(arg)
        if not os.path.exists(path):
            sys.exit(f"no such scene file: {path}")
        XML[name] = (path, defines)
    scenes = (args.scenes or ("" if XML else "cornell,cornell-area")).split(",")
    scenes = [s for s in scenes if s] + list(XML)
    for s in scenes:
        if s not in SCENES and s not in XML:
            sys.exit(f"unknown scene {s} (known: {', '.join(SCENES)})")
    targets = sorted((float(x) for x in args.targets.split(",")), reverse=True)
    mitsuba_spp = [int(x) for x in args.mitsuba_spp.split(",")] if args.mitsuba_spp else None
    scene_targets = {}
    log = lambda msg: print("# " + msg, file=sys.stderr, flush=True)  # noqa: E731
    start = time.perf_counter()

    with tempfile.TemporaryDirectory(prefix="compare_mitsuba.") as tmp:
        mitsuba = Mitsuba(args.threads, tmp)
        if args.check:
            ref = read_exr(args.ref)
            img, t = mitsuba.render("cornell", args.check, warm_up=False)
            e = rel_mse(img, ref)
            print(f"Mitsuba cornell {args.check} spp: relMSE {e:.3e} against {args.ref} "
                  f"(expected ≈ 0.50/spp + 3e-5 = {0.5 / args.check + 3e-5:.3e}); "
                  f"mean ratio {img.mean() / ref.mean():.5f}; {t:.1f} s")
            return

        binary = os.path.join(tmp, "raylab")
        shutil.copy2(args.raylab, binary)
        with open(binary, "rb") as f:
            digest = hashlib.sha256(f.read()).hexdigest()[:12]
        mtime = time.strftime("%Y-%m-%d %H:%M", time.localtime(os.path.getmtime(args.raylab)))
        raylab = Raylab(binary, args.threads, tmp)
        renderers = (raylab, mitsuba)
        avx2 = "avx2" in open("/proc/cpuinfo").read() if os.path.exists("/proc/cpuinfo") else False
        no_avx2 = os.environ.get("RAYLAB_NO_AVX2", "") not in ("", "0")
        isa = "AVX2 (8-wide box test)" if avx2 and not no_avx2 else "portable (4-wide box test)"
        log(f"raylab: {args.raylab} (built {mtime}, sha256 {digest}), BVH ISA {isa}; "
            f"Mitsuba {mi.__version__} llvm_ad_rgb, drjit {dr.__version__}; "
            f"{args.threads} threads each")

        # Untimed: the spp each renderer needs for each target.
        refs, notes, cal, spps = {}, {}, {}, {}
        for scene in scenes:
            ref, noise, notes[scene] = reference(scene, args, mitsuba)
            refs[scene] = ref
            log(f"{scene}: reference {notes[scene]}")
            for r in renderers:
                cal[(scene, r.name)] = Calibration(r, scene, ref, noise, log)
                # Pilot (Mitsuba's warmed up, for a fair time per spp).
                cal[(scene, r.name)].render(16, warm_up=True)
            if mitsuba_spp:
                c_mi = cal[(scene, "Mitsuba")].c
                scene_targets[scene] = [noise + c_mi / n for n in mitsuba_spp]
                log(f"{scene}: targets " + ", ".join(
                    f"{t:.3e} (Mitsuba at {n} spp)" for t, n in zip(scene_targets[scene], mitsuba_spp)))
            else:
                scene_targets[scene] = targets
            for target in scene_targets[scene]:
                found = {}
                for r in renderers:
                    k = cal[(scene, r.name)]
                    if noise > target / 4:
                        log(f"{scene} {target:g}: the reference's own noise ({noise:.1e}) is "
                            "too large to judge it: estimated only")
                        break
                    found[r.name] = k.find(target, args.max_seconds)
                    if found[r.name] is None:
                        break
                else:
                    for name, spp in found.items():
                        spps[(scene, name, target)] = spp

        # Timed: alternating the renderers, a new seed each time.
        times, errs = {}, {}
        # Short renders (under 5 s each, by the calibration) get 3× the rounds: on a
        # shared machine one busy second shifts them most.
        short = {(scene, target): all(
            spps[(scene, r.name, target)] * cal[(scene, r.name)].per_spp < 5 for r in renderers)
            for (scene, _, target) in spps}
        for rnd in range(3 * args.rounds):
            for scene in scenes:
                for target in scene_targets[scene]:
                    if (scene, "raylab", target) not in spps:
                        continue
                    if rnd >= args.rounds and not short[(scene, target)]:
                        continue
                    order = renderers if rnd % 2 == 0 else renderers[::-1]
                    for r in order:
                        key = (scene, r.name, target)
                        img, t = r.render(scene, spps[key])
                        e = rel_mse(img, refs[scene])
                        times.setdefault(key, []).append(t)
                        errs.setdefault(key, []).append(e)
                        log(f"round {rnd + 1}: {r.name:7} {scene} {target:g}: {spps[key]} spp "
                            f"{t:.2f} s relMSE {e:.3e}")

    print()
    size = f"{SIZE}×{SIZE}" if not XML else "XML scenes at their own size"
    print(f"{size}, {args.threads} threads each; seconds: the best of {args.rounds} "
          "timed renders (3× that for renders under 5 s; raylab: whole process; Mitsuba: "
          "mi.render after warm-up); relMSE: "
          "the worst of them (! above the target); est.: not rendered, spp = c / target and "
          "seconds = spp × the time per spp of the largest timed render of the scene (else of "
          "the last calibration render). Run took "
          f"{time.perf_counter() - start:.0f} s.")
    print()
    print("| scene | target | raylab spp | raylab s | raylab relMSE "
          "| Mitsuba spp | Mitsuba s | Mitsuba relMSE | raylab / Mitsuba time |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for scene in scenes:
        for target in scene_targets[scene]:
            row = [scene, f"{target:.3g}"]
            secs = {}
            for r in renderers:
                key = (scene, r.name, target)
                if key in times:
                    secs[r.name] = min(times[key])
                    worst = max(errs[key])
                    row += [str(spps[key]), fmt_t(secs[r.name]),
                            f"{worst:.2e}" + ("!" if worst > target else "")]
                else:
                    k = cal[(scene, r.name)]
                    spp = math.ceil(k.c / target)
                    # Time per spp of the largest timed render of the scene, if any.
                    timed = [(spps[x], min(t)) for x, t in times.items() if x[:2] == key[:2]]
                    n, t = max(timed) if timed else (1, k.per_spp)
                    secs[r.name] = spp * t / n
                    row += [f"≈ {spp}", f"≈ {fmt_t(secs[r.name])}", "est."]
            row.append(f"{secs['raylab'] / secs['Mitsuba']:.2f}")
            print("| " + " | ".join(row) + " |")
    print()
    for scene in scenes:
        cs = ", ".join(f"{r.name} {cal[(scene, r.name)].c:.3f}" for r in renderers)
        print(f"* {scene}: reference {notes[scene]}; c = relMSE × spp (last calibration "
              f"render, reference noise taken out): {cs}")


if __name__ == "__main__":
    main()
