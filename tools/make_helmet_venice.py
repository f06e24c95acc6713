#!/usr/bin/env python3
"""Writes scenes/helmet-venice/helmet-venice.gltf: the DamagedHelmet with scenes/helmet-hdri.toml's
camera, as one glTF file that Blender Cycles (../shared/cycles/render_gltf.py) can read too.

Usage (from the project folder):

    python3 tools/make_helmet_venice.py [OUT_DIR]

OUT_DIR defaults to scenes/helmet-venice beside this tools/ folder. Standard library only; the
output is the same bytes on every run. Only the .gltf is written: its buffer and its five JPEG
textures stay in assets/models/DamagedHelmet and are referenced by relative URIs
(../../assets/models/DamagedHelmet/...).

The file is assets/models/DamagedHelmet/DamagedHelmet.gltf unchanged (the same accessors,
materials, node and its rotation) plus one perspective camera node appended as a second root:
helmet-hdri.toml's [camera] (position (1.8, 0.45, 3.4), looking at the origin, +y up, vertical
fov 35 degrees), aspectRatio 4/3 (default render size 800 x 600).

The environment is not part of glTF: give both renderers the same map on the command line,

    raylab render scenes/helmet-venice/helmet-venice.gltf \\
        --env assets/envmaps/venice_sunset_1k.hdr --env-rotate 200
    VENV/bin/python ../shared/cycles/render_gltf.py scenes/helmet-venice/helmet-venice.gltf -o x.exr \\
        --env assets/envmaps/venice_sunset_1k.hdr --env-rotate 200 --spp N --threads T

which is what helmet-hdri.toml's [environment] does (strength 1, rotate 200).
"""

import json
import math
import os
import sys

sys.dont_write_bytecode = True  # leave no tools/__pycache__ behind
from gltfgen import look_along  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUT = os.path.join(ROOT, "scenes", "helmet-venice")
SOURCE = os.path.join(ROOT, "assets", "models", "DamagedHelmet", "DamagedHelmet.gltf")
URI_PREFIX = "../../assets/models/DamagedHelmet/"

# scenes/helmet-hdri.toml's [camera]
EYE = (1.8, 0.45, 3.4)
TARGET = (0.0, 0.0, 0.0)
FOV_DEG = 35.0
ASPECT = 4.0 / 3.0


def build(out_dir):
    if not os.path.exists(SOURCE):
        sys.exit(f"error: {os.path.relpath(SOURCE)} not found")
    with open(SOURCE) as f:
        doc = json.load(f)
    for coll in ("buffers", "images"):
        for item in doc.get(coll, []):
            item["uri"] = URI_PREFIX + item["uri"]
    doc["asset"]["generator"] = ("raylab tools/make_helmet_venice.py from "
                                 + doc["asset"].get("generator", "?"))
    doc["asset"]["copyright"] = ("DamagedHelmet: theblueturtle_, CC BY 4.0 (Khronos glTF sample "
                                 "models); camera: raylab contributors")
    doc.setdefault("cameras", []).append({
        "name": "helmet-hdri.toml camera", "type": "perspective",
        "perspective": {"yfov": math.radians(FOV_DEG), "aspectRatio": ASPECT,
                        "znear": 0.01, "zfar": 100.0}})
    direction = tuple(t - e for t, e in zip(TARGET, EYE))
    doc["nodes"].append({"name": "camera", "camera": len(doc["cameras"]) - 1,
                         "translation": list(EYE), "rotation": list(look_along(direction))})
    doc["scenes"][doc.get("scene", 0)]["nodes"].append(len(doc["nodes"]) - 1)

    os.makedirs(out_dir, exist_ok=True)
    path = os.path.join(out_dir, "helmet-venice.gltf")
    data = (json.dumps(doc, indent=1) + "\n").encode()
    with open(path, "wb") as f:
        f.write(data)
    print("%s %d bytes (camera rotation %s)" % (os.path.relpath(path), len(data),
                                                 doc["nodes"][-1]["rotation"]))


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else DEFAULT_OUT
    if out_dir in ("-h", "--help"):
        print(__doc__)
        return
    build(out_dir)


if __name__ == "__main__":
    main()
