#!/usr/bin/env python3
"""Runs ../shared/cycles/render_gltf.py with Cycles' adaptive sampling on, and says how many
samples Cycles took per pixel on average: the Cycles side of tools/compare_cycles.py --adaptive.

Usage (with the Python of the Cycles venv, ../shared/cycles/setup.sh):

    python tools/cycles_adaptive.py --render-gltf PATH/render_gltf.py --noise-threshold T
                                    [--min-samples N]
                                    MODEL.gltf -o OUT.exr --spp CAP ... (render_gltf.py's own)

render_gltf.py turns adaptive sampling off (it renders a fixed number of samples) and lives
outside this tree, so it is not edited: this script loads it as a module, lets its
setup_cycles() run, then sets (Blender 5.2's Python API)

    scene.cycles.use_adaptive_sampling = True
    scene.cycles.adaptive_threshold = T     (Blender's "Noise Threshold")
    scene.cycles.adaptive_min_samples = N   (default 0: Cycles' automatic minimum, as in Blender)

render_gltf.py's --spp (scene.cycles.samples) is then the cap, Blender's "Max Samples".
Everything else is render_gltf.py's: the same import, material and light fixes, the same output
EXR, the same JSON line (printed once, with the fields below added).

The samples per pixel: the view layer's "Debug Sample Count" pass
(view_layer.cycles.pass_debug_sample_count) is on, and a compositor node tree writes it to a
temporary EXR with a File Output node (Blender's Python API cannot read a render result's passes,
and Image.save_render writes only the combined pass even as a multilayer EXR). Nothing is linked
to the composite, so the render result and the output EXR are the same as without it (checked:
bit for bit), and Cycles' render time in the EXR header does not include the compositor. Cycles
stores the pass as each pixel's samples divided by the samples the render took (the most any
pixel took), and that number is not in the EXR header (its `samples` is the cap): it is the
largest N of Cycles' `Sample N/M` progress reports (bpy.app.handlers.render_stats). The counts
(pass × N) are checked to be whole numbers.

Fields added to the JSON line:
  adaptive: {"threshold": T, "min_samples": N, "cap": CAP, "samples_done": N of the render}
  spp_mean: the mean over the pixels of the samples taken (null, with a warning, if unknown)
  spp_min, spp_max: the fewest and most samples of a pixel
"""

import argparse
import glob
import importlib.util
import json
import os
import re
import sys
import tempfile

sys.dont_write_bytecode = True  # no __pycache__ beside render_gltf.py

PASS = "Debug Sample Count"
SAMPLE = re.compile(r"\bSample (\d+)/(\d+)")


def load(path):
    spec = importlib.util.spec_from_file_location("render_gltf", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def add_sample_count_output(bpy, scene, directory):
    """The view layers' sample-count pass on, and a compositor that writes it to an EXR in
    `directory` (a File Output node; nothing reaches the composite, so the render result and
    render_gltf.py's EXR stay as they are)."""
    for vl in scene.view_layers:
        vl.cycles.pass_debug_sample_count = True
    tree = bpy.data.node_groups.new("cycles_adaptive sample count", "CompositorNodeTree")
    scene.compositing_node_group = tree
    layers = tree.nodes.new("CompositorNodeRLayers")
    out = tree.nodes.new("CompositorNodeOutputFile")
    out.directory = directory + os.sep
    out.file_name = "samples"
    out.format.file_format = "OPEN_EXR_MULTILAYER"
    out.format.color_depth = "32"
    out.file_output_items.new("FLOAT", "count")
    tree.links.new(layers.outputs[PASS], out.inputs["count"])
    scene.render.use_compositing = True
    scene.render.compositor_device = "CPU"


def read_fraction(directory):
    """The sample-count pass (samples of each pixel ÷ the samples of the render) as a flat
    array, from the File Output node's EXR in `directory`; None if there is none."""
    import numpy as np
    import OpenEXR

    files = sorted(glob.glob(os.path.join(directory, "*.exr")))
    if not files:
        return None
    with OpenEXR.File(files[0], separate_channels=True) as f:
        ch = f.channels()
        if not ch:
            return None
        return np.asarray(ch[sorted(ch)[0]].pixels, dtype=np.float64).ravel()


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], allow_abbrev=False)
    ap.add_argument("--render-gltf", required=True, help="../shared/cycles/render_gltf.py")
    ap.add_argument("--noise-threshold", type=float, required=True,
                    help="Cycles' adaptive_threshold, in (0, 1]")
    ap.add_argument("--min-samples", type=int, default=0,
                    help="Cycles' adaptive_min_samples (default 0: automatic)")
    a, rest = ap.parse_known_args(argv)
    if not 0.0 < a.noise_threshold <= 1.0:
        ap.error("--noise-threshold must be in (0, 1]")
    mod = load(os.path.abspath(a.render_gltf))
    seen = {"done": 0}
    tmp = tempfile.mkdtemp(prefix="cycles_adaptive_")

    def on_stats(text, *_):
        for m in SAMPLE.finditer(str(text)):
            seen["done"] = max(seen["done"], int(m.group(1)))

    setup = mod.setup_cycles

    def setup_adaptive(bpy, scene, args):
        setup(bpy, scene, args)
        cy = scene.cycles
        cy.use_adaptive_sampling = True
        cy.adaptive_threshold = a.noise_threshold
        cy.adaptive_min_samples = a.min_samples
        add_sample_count_output(bpy, scene, tmp)
        # after render_gltf.py's read_factory_settings, which clears the handlers
        bpy.app.handlers.render_stats.append(on_stats)
        seen["cap"] = args.spp

    mod.setup_cycles = setup_adaptive
    mod.json_line = lambda d: seen.__setitem__("info", d)
    try:
        mod.main(rest)
        if "info" not in seen:
            sys.exit("cycles_adaptive: render_gltf.py printed no JSON line")
        info = seen["info"]
        cap, done = seen["cap"], min(seen["done"], seen["cap"])
        counts, why = None, None
        try:
            frac = read_fraction(tmp)
            if frac is None:
                why = "no sample-count EXR from the compositor"
            elif done < 1:
                why = "Cycles reported no `Sample N/M` progress"
            else:
                counts = frac * done
                off = float(abs(counts - counts.round()).max())
                if off > 1e-3 or frac.max() > 1 + 1e-6:
                    why = (f"the sample-count pass times {done} samples is not a whole number "
                           f"(off by up to {off:.3g})")
                    counts = None
        except Exception as e:  # noqa: BLE001 - the render itself is fine; say why
            why = str(e)
    finally:
        import shutil
        shutil.rmtree(tmp, ignore_errors=True)
    info["adaptive"] = {"threshold": a.noise_threshold, "min_samples": a.min_samples, "cap": cap,
                        "samples_done": done}
    if counts is None:
        info.setdefault("warnings", []).append(f"cycles_adaptive: no sample count: {why}")
        info["spp_mean"] = info["spp_min"] = info["spp_max"] = None
    else:
        info["spp_mean"] = float(counts.mean())
        info["spp_min"], info["spp_max"] = float(counts.min()), float(counts.max())
    print(json.dumps(info), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
