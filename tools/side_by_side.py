#!/usr/bin/env python3
"""Two linear OpenEXR images of the same size side by side as one PNG (clamped,
sRGB-encoded, `--exposure` stops brighter), with their mean RGB and the mean
absolute difference printed, over the whole image or a `--box X0,Y0,X1,Y1`
of pixels.

    VENV/bin/python tools/side_by_side.py LEFT.exr RIGHT.exr -o OUT.png [--box ...] [--exposure E]

(VENV: any venv with numpy, OpenEXR and Pillow, e.g. the Mitsuba one.)
"""
import argparse
import sys

import numpy as np
import OpenEXR
from PIL import Image

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("left")
ap.add_argument("right")
ap.add_argument("-o", "--output", required=True)
ap.add_argument("--box", help="X0,Y0,X1,Y1: the pixels the numbers are taken over")
ap.add_argument("--exposure", type=float, default=0.0)
a = ap.parse_args()


def read(path):
    f = OpenEXR.File(path)
    ch = f.channels()
    if "RGB" in ch:
        return np.asarray(ch["RGB"].pixels, dtype=np.float64)[..., :3]
    try:
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float64) for c in "RGB"], -1)
    except KeyError:
        sys.exit(f"{path}: no R, G, B channels (has {sorted(ch)})")


left, right = read(a.left), read(a.right)
if left.shape != right.shape:
    sys.exit(f"sizes differ: {left.shape[1]}x{left.shape[0]} and {right.shape[1]}x{right.shape[0]}")
box = (slice(None), slice(None))
if a.box:
    x0, y0, x1, y1 = (int(v) for v in a.box.split(","))
    box = (slice(y0, y1), slice(x0, x1))
for name, img in (("left", left), ("right", right)):
    m = img[box].reshape(-1, 3).mean(0)
    print(f"{name}: mean RGB {m[0]:.4f} {m[1]:.4f} {m[2]:.4f}")
d = np.abs(left[box] - right[box]).reshape(-1, 3).mean(0)
rel = (left[box].reshape(-1, 3).mean(0) - right[box].reshape(-1, 3).mean(0)) / np.maximum(
    right[box].reshape(-1, 3).mean(0), 1e-12)
print(f"mean |left - right| {d[0]:.4f} {d[1]:.4f} {d[2]:.4f}; means differ by "
      f"{100 * rel[0]:+.1f} % {100 * rel[1]:+.1f} % {100 * rel[2]:+.1f} %")


def srgb(x):
    x = np.clip(x * 2.0 ** a.exposure, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


img = (srgb(np.concatenate([left, right], axis=1)) * 255 + 0.5).astype(np.uint8)
Image.fromarray(img).save(a.output)
print(f"wrote {a.output}")
