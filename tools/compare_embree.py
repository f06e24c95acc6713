#!/usr/bin/env python3
"""raylab against Embree 3 on the shared ray-casting workloads, in one run.

Usage (from the project folder, with the data of ../shared/bench/README.md made in
BENCH_DATA, by default ../bench-data):

    cargo build --release
    python3 tools/compare_embree.py [--data DIR] [--rounds R] [MESH ...]

For each mesh (default: bunny ogre) it alternates, R times, one run of Embree's
harness (MEDIUM quality, single-ray API rtc1 and packet API rtc8, 1 and 2 threads)
and one run of `raylab bench` on the same ray files (closest hit for primary and
incoherent rays, any hit over [0, tfar_shadow] for shadow rays), keeps the best
Mrays/s of each, and prints a Markdown table with the ratios. It also checks
raylab's hits against Embree's reference hits (hit/miss disagreements and prim
differences) and compares build times (`--build MESH` adds a mesh, e.g. bunny_sub2,
whose build alone is timed). Standard library only.
"""

import argparse
import json
import os
import re
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RAYLAB = os.path.join(ROOT, "target", "release", "raylab")
MODELS = os.path.join(ROOT, "..", "shared", "models")
OBJ = {"bunny": "stanford-bunny.obj", "ogre": "ogre.obj", "teapot": "teapot.obj"}


def obj_path(data, mesh):
    if mesh in OBJ:
        return os.path.join(MODELS, OBJ[mesh])
    return os.path.join(data, "mesh", mesh + ".obj")


def run(cmd):
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return out.stdout


def embree(data, mesh, build_only=False):
    """{(workload, api, threads): mrays} and the build time in ms."""
    cmd = [os.path.join(data, "bin", "embree3_bench"), data, mesh, "--quality", "medium"]
    cmd += ["--build-only"] if build_only else ["--apis", "1,8"]
    rates, build = {}, None
    for line in run(cmd).splitlines():
        f = line.split(",")
        if len(f) < 8 or f[0] != "embree3":
            continue
        if f[2] == "build":
            build = float(f[7])
        else:
            rates[(f[2], f[3].split("-")[1], int(f[4]))] = float(f[5])
    return rates, build


def raylab(data, mesh, workload, extra, hits=None):
    rays = os.path.join(data, "rays", f"{mesh}.{workload}.rays")
    cmd = [RAYLAB, "bench", obj_path(data, mesh), "--rays", rays, "--threads", "1,2"]
    cmd += ["--repeat", "5"] + extra + (["--hits", hits] if hits else [])
    rates, build = {}, None
    for line in run(cmd).splitlines():
        kv = dict(re.findall(r"(\w+)=(\S+)", line))
        if "build_ms" in kv:
            build = float(kv["build_ms"])
        elif "mrays_per_s" in kv:
            rates[int(kv["threads"])] = float(kv["mrays_per_s"])
    return rates, build


def read_hits(path):
    with open(path, "rb") as f:
        raw = f.read()
    n = len(raw) // 8
    vals = struct.unpack(f"<{2 * n}I", raw)
    return [(vals[2 * i], vals[2 * i + 1]) for i in range(n)]


def agreement(ours, ref, shadow):
    if shadow:
        a, b = open(ours, "rb").read(), open(ref, "rb").read()
        return sum(x != y for x, y in zip(a, b)), 0, len(b)
    inf = 0x7F800000
    a, b = read_hits(ours), read_hits(ref)
    hitmiss = sum((x[0] == inf) != (y[0] == inf) for x, y in zip(a, b))
    prims = sum(x[0] != inf and y[0] != inf and x[1] != y[1] for x, y in zip(a, b))
    return hitmiss, prims, len(b)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=os.path.join(ROOT, "..", "bench-data"))
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--build", action="append", default=[])
    ap.add_argument("meshes", nargs="*", default=["bunny", "ogre"])
    args = ap.parse_args()
    rows, builds, checks = [], [], []
    tmp = tempfile.mkdtemp()
    for mesh in args.meshes:
        meta = json.load(open(os.path.join(args.data, "rays", f"{mesh}.json")))
        shadow = ["--shadow", "--tfar", str(meta["tfar_shadow"])]
        work = [("primary", "primary", []), ("incoherent", "incoherent", []),
                ("shadow", "incoherent", shadow)]
        best_e, best_r, build_e, build_r = {}, {}, [], []
        for rnd in range(args.rounds):
            e, b = embree(args.data, mesh)
            build_e.append(b)
            for k, v in e.items():
                best_e[k] = max(best_e.get(k, 0), v)
            for name, rays, extra in work:
                hits = os.path.join(tmp, f"{mesh}.{name}") if rnd == 0 else None
                r, b = raylab(args.data, mesh, rays, extra, hits)
                build_r.append(b)
                for t, v in r.items():
                    best_r[(name, t)] = max(best_r.get((name, t), 0), v)
        for name, _, extra in work:
            for t in (1, 2):
                e1, r = best_e.get((name, "rtc1", t)), best_r.get((name, t))
                e8 = best_e.get((name, "rtc8", t))
                rows.append(f"| {mesh} | {name} | {t} | {r:.2f} | {e1:.2f} | {e8:.2f} | {r / e1:.2f} |")
            ref = "shadow.occ.bin" if extra else f"{name}.ref.bin"
            ref = os.path.join(args.data, "ref", f"{mesh}.{ref}")
            if os.path.exists(ref):
                hm, pd, n = agreement(os.path.join(tmp, f"{mesh}.{name}"), ref, bool(extra))
                checks.append(f"{mesh} {name}: {hm} hit/miss disagreements, {pd} prims differ, of {n}")
        builds.append(f"| {mesh} | {min(build_r):.1f} | {min(build_e):.1f} | {min(build_e) / min(build_r):.2f} |")
    for mesh in args.build:
        br, be = [], []
        for _ in range(args.rounds):
            be.append(embree(args.data, mesh, build_only=True)[1])
            one = os.path.join(tmp, "one.rays")
            open(one, "wb").write(struct.pack("<6f", 0, 0, 0, 0, 0, 1))
            cmd = [RAYLAB, "bench", obj_path(args.data, mesh), "--rays", one, "--repeat", "1"]
            br.append(float(re.search(r"build_ms=(\S+)", run(cmd)).group(1)))
        builds.append(f"| {mesh} | {min(br):.1f} | {min(be):.1f} | {min(be) / min(br):.2f} |")
    print("| mesh | workload | threads | raylab Mrays/s | Embree rtc1 | Embree rtc8 | ratio to rtc1 |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    print("\n".join(rows))
    print("\n| mesh | raylab build ms (all cores) | Embree MEDIUM ms (2 threads) | Embree / raylab |")
    print("| --- | --- | --- | --- |")
    print("\n".join(builds))
    print()
    print("\n".join(checks))


if __name__ == "__main__":
    sys.exit(main())
