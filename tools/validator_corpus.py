#!/usr/bin/env python3
"""Runs raylab over the Khronos glTF-Validator's own test corpus and checks
issue 32's rule: every file the validator reports without errors loads, and
every file it reports with errors loads or is refused in one line, never
with a panic, a hang or a crash.

    python3 tools/validator_corpus.py VALIDATOR_TEST_DIR [RAYLAB]

VALIDATOR_TEST_DIR is the `test/` folder of a checkout of
github.com/KhronosGroup/glTF-Validator (each `X.gltf`/`X.glb` beside its
`X.gltf.report.json`); RAYLAB defaults to target/release/raylab. Each file
is rendered at 8×8, 1 spp. Prints the counts, every file that breaks the
rule, and exits 1 if any does.
"""

import collections
import json
import os
import subprocess
import sys
import tempfile


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    root = sys.argv[1]
    exe = sys.argv[2] if len(sys.argv) > 2 else "target/release/raylab"
    counts, broken = collections.Counter(), []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.png")
        for folder, _, files in sorted(os.walk(root)):
            for name in sorted(files):
                path = os.path.join(folder, name)
                report = path + ".report.json"
                if not name.endswith((".gltf", ".glb")) or not os.path.exists(report):
                    continue
                with open(report) as f:
                    valid = json.load(f)["issues"]["numErrors"] == 0
                try:
                    run = subprocess.run(
                        [exe, "render", path, "--width", "8", "--height", "8",
                         "--spp", "1", "-o", out],
                        capture_output=True, text=True, timeout=60)
                    code, errors = run.returncode, [
                        l for l in run.stderr.splitlines() if l.startswith("error")]
                except subprocess.TimeoutExpired:
                    code, errors = "hang", []
                outcome = "loads" if code == 0 else "refused" if code == 1 else "CRASH"
                counts[("valid" if valid else "with errors", outcome)] += 1
                where = os.path.relpath(path, root)
                if code == 1 and len(errors) != 1:
                    broken.append(f"{where}: refused without exactly one error line")
                elif outcome == "CRASH":
                    broken.append(f"{where}: exit {code}: {run.stderr.strip()[:300]}")
                elif valid and code != 0:
                    broken.append(f"{where}: valid but refused: {errors[0]}")
    for (kind, outcome), n in sorted(counts.items()):
        print(f"{kind:12} {outcome:8} {n}")
    for line in broken:
        print("BROKEN:", line)
    sys.exit(1 if broken else 0)


if __name__ == "__main__":
    main()
