#!/usr/bin/env python3
"""Writes src/load/mitsuba/scene/conductors.rs: the RGB complex index of
refraction (eta, k) of each of Mitsuba 3's named conductors (`material="Au"`
of `conductor`/`roughconductor`), as Mitsuba's RGB variants compute them
from its measured spectra (`data/ior/<name>.{eta,k}.spd`, in the
mitsuba-data repository's `ior/`): `spectrum_list_to_srgb(λ, values,
bounded=false, d65=false)`, evaluated by Mitsuba itself.

    python3 tools/make_conductor_table.py --ior <mitsuba-data>/ior --mitsuba PYTHON

PYTHON is an interpreter with the mitsuba package (3.7.1). Only the derived
numbers are written, not the spectra."""

import argparse
import os
import subprocess
import sys

SCRIPT = r"""
import sys, os, json, mitsuba as mi
mi.set_variant("scalar_rgb")
folder = sys.argv[1]
out = {}
for f in sorted(os.listdir(folder)):
    if not f.endswith(".eta.spd"):
        continue
    name = f[:-8]
    row = []
    for part in ("eta", "k"):
        w, v = [], []
        for line in open(os.path.join(folder, f"{name}.{part}.spd")):
            line = line.split("#")[0].strip()
            if not line:
                continue
            a, b = line.split()[:2]
            w.append(float(a)); v.append(float(b))
        c = mi.spectrum_list_to_srgb(w, v, False, False)
        row.append([float(c[0]), float(c[1]), float(c[2])])
    out[name] = row
print("JSON:" + json.dumps(out))
"""

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ior", required=True)
    ap.add_argument("--mitsuba", required=True)
    args = ap.parse_args()
    import json
    r = subprocess.run([args.mitsuba, "-c", SCRIPT, args.ior], capture_output=True, text=True, check=True)
    line = [l for l in r.stdout.splitlines() if "JSON:" in l][0]
    table = json.loads(line[line.index("JSON:") + 5 :])
    here = os.path.dirname(os.path.abspath(__file__))
    path = os.path.join(here, "..", "src", "load", "mitsuba", "scene", "conductors.rs")
    lines = [
        "//! Mitsuba 3's named conductors (`material=\"Au\"`) as the RGB complex",
        "//! indices of refraction its RGB variants use: each measured spectrum",
        "//! (`data/ior/<name>.{eta,k}.spd`) integrated against the CIE curves",
        "//! (unbounded, no D65 weighting). Made by `tools/make_conductor_table.py`",
        "//! with Mitsuba 3.7.1's own `spectrum_list_to_srgb`; only these derived",
        "//! numbers are kept.",
        "",
        "/// (name, eta RGB, k RGB).",
        "#[rustfmt::skip]",
        "#[allow(clippy::excessive_precision)]",
        f"const PRESETS: [(&str, [f32; 3], [f32; 3]); {len(table)}] = [",
    ]
    for name, (eta, k) in sorted(table.items()):
        f = lambda c: "[" + ", ".join(f"{x:.7}" if abs(x) >= 1e-3 else f"{x:.7e}" for x in c) + "]"
        lines.append(f'    ("{name}", {f(eta)}, {f(k)}),')
    lines += [
        "];",
        "",
        "/// The eta and k (RGB) of Mitsuba's conductor `name`.",
        "pub(super) fn preset(name: &str) -> Option<([f32; 3], [f32; 3])> {",
        "    PRESETS.iter().find(|p| p.0 == name).map(|p| (p.1, p.2))",
        "}",
        "",
        "/// Every name, for messages.",
        "pub(super) fn names() -> Vec<&'static str> {",
        "    PRESETS.iter().map(|p| p.0).collect()",
        "}",
        "",
    ]
    open(path, "w").write("\n".join(lines))
    print(f"wrote {path}: {len(table)} conductors")


if __name__ == "__main__":
    main()
