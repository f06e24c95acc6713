#!/usr/bin/env python3
"""Writes a copy of a .gltf file with some extensions taken out, to render a
model side by side with an extension switched off (docs/gltf.md).

    python3 tools/gltf_without.py IN.gltf EXT[,EXT...] OUT.gltf

Every object's `extensions` entry of those names is removed (materials,
textures, nodes, the root), and so are the names in `extensionsUsed` and
`extensionsRequired`. Relative buffer and image URIs are rewritten relative to
OUT's folder, so the copy may live anywhere (e.g. /tmp) and still find the
original's files; data URIs are kept as they are. Only .gltf (JSON) input.
"""

import json
import os
import sys


def strip(value, names):
    """`value` with every `extensions` entry named in `names` removed."""
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            if key == "extensions" and isinstance(item, dict):
                item = {k: v for k, v in item.items() if k not in names}
                if not item:
                    continue
            out[key] = strip(item, names)
        return out
    if isinstance(value, list):
        return [strip(item, names) for item in value]
    return value


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__.strip().splitlines()[2].strip())
    src, names, dst = sys.argv[1], set(sys.argv[2].split(",")), sys.argv[3]
    try:
        with open(src, encoding="utf-8") as f:
            root = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"error: {src}: {e}")
    root = strip(root, names)
    for key in ("extensionsUsed", "extensionsRequired"):
        if key in root:
            root[key] = [n for n in root[key] if n not in names]
            if not root[key]:
                del root[key]
    src_dir = os.path.dirname(os.path.abspath(src))
    dst_dir = os.path.dirname(os.path.abspath(dst))
    for key in ("buffers", "images"):
        for item in root.get(key, []):
            uri = item.get("uri")
            if uri and not uri.startswith("data:") and "://" not in uri:
                item["uri"] = os.path.relpath(os.path.join(src_dir, uri), dst_dir)
    tmp = dst + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(root, f, indent=1)
    os.replace(tmp, dst)


if __name__ == "__main__":
    main()
