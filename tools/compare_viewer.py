#!/usr/bin/env python3
"""The viewer's frame, raylab against an Embree 3 renderer of the same frame, in one run.

Usage (from the project folder; needs Debian's libembree-dev and a release build of raylab):

    python3 tools/compare_viewer.py [--rounds R] [--raylab PATH] [--bin DIR] [--check]

The frame: the lab box (`cornell`) under `direct` at 500×500, one camera ray through
each pixel centre and one shadow ray per lit hit. tools/embree_frame.cpp renders it
with Embree 3 (single rays and 2×2 packets, 1 and 2 threads; it is built into
--bin, by default ../bench-data/bin, when missing or older than its source) and
reports the median of 64 frames after 10 of warm-up. raylab's frame time is that of
the viewer's 64 refinement frames,

    raylab render cornell --integrator direct --width 500 --height 500 --spp 64 --threads T

whose summary line gives the time of all 64 (sample 0 through the pixel centres, the
others jittered: the same work per frame): ms/frame = that / 64. The two are
alternated R times (default 3), one variant per run, and the best of each kept; a
run during which other processes used over 5 % of the machine is repeated (up to
--tries times) and flagged * when no run of that cell was clean. The table gives the
ratio raylab / best Embree variant (the goal: ≤ 0.5), and a line gives CPU time per
frame on one thread, which other load disturbs less. `cargo bench --bench frame`
(in the main checkout) gives raylab's in-process frame time for centre rays (median
of 40 renders after 10) for comparison. raylab: --raylab, by default this
checkout's target/release/raylab, else ../main/target/release/raylab.

--check also compares the pictures: Embree's frame against the Embree-made
reference assets/refs/cornell-direct-lab-500.exr and against
`raylab render cornell --integrator direct --spp 1` (max abs difference, pixels that
differ). Standard library only.
"""

import argparse
import os
import re
import resource
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.join(HERE, "embree_frame.cpp")
REF = os.path.join(ROOT, "assets", "refs", "cornell-direct-lab-500.exr")
SIZE = 500
SPP = 64


def default_raylab():
    for p in (os.path.join(ROOT, "target", "release", "raylab"),
              os.path.join(ROOT, "..", "main", "target", "release", "raylab")):
        if os.path.exists(p):
            return p
    return os.path.join(ROOT, "target", "release", "raylab")


def build(bindir):
    exe = os.path.join(bindir, "embree_frame")
    if os.path.exists(exe) and os.path.getmtime(exe) >= os.path.getmtime(SOURCE):
        return exe
    if not os.path.exists("/usr/include/embree3/rtcore.h"):
        sys.exit("libembree-dev is missing: apt-get install -y libembree-dev")
    os.makedirs(bindir, exist_ok=True)
    cmd = ["g++", "-O3", "-march=native", "-std=c++17", "-ffp-contract=off", "-pthread",
           SOURCE, "-o", exe, "-lembree3"]
    print("building:", " ".join(cmd), file=sys.stderr)
    subprocess.run(cmd, check=True)
    return exe


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def embree(exe, api, threads, quality):
    """Embree's ms per frame (median of 64 after 10 of warm-up) and CPU ms per frame."""
    out = run([exe, "--threads", str(threads), "--apis", api, "--quality", quality])
    for line in out.splitlines():
        kv = dict(re.findall(r"(\w+)=(\S+)", line))
        if "median_ms" in kv:
            return float(kv["median_ms"]), float(kv["cpu_ms"])
    sys.exit(f"unexpected embree_frame output: {out}")


def machine_busy_s():
    """CPU seconds the whole machine has been busy (from /proc/stat); 0 if unknown."""
    try:
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:9]]
    except (OSError, ValueError):
        return 0.0
    return (v[0] + v[1] + v[2] + v[5] + v[6] + v[7]) / os.sysconf("SC_CLK_TCK")


def children_cpu_s():
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def measured(fn, tries):
    """Runs fn() until a run is clean (other processes used under 5 % of the machine
    during it), at most `tries` times, sleeping 1 s after a disturbed run. Returns
    (value, clean): the clean run's value, or the smallest of the disturbed ones."""
    ncpu, tick = os.cpu_count() or 1, 1.0 / os.sysconf("SC_CLK_TCK")
    seen = []
    for _ in range(max(1, tries)):
        b0, c0, w0 = machine_busy_s(), children_cpu_s(), time.monotonic()
        value = fn()
        wall = time.monotonic() - w0
        foreign = (machine_busy_s() - b0) - (children_cpu_s() - c0)
        if foreign <= 0.05 * wall * ncpu + 2 * tick:
            return value, True
        seen.append(value)
        time.sleep(1)
    return min(seen), False


def raylab(exe, threads, out):
    cmd = [exe, "render", "cornell", "--integrator", "direct", "--width", str(SIZE),
           "--height", str(SIZE), "--spp", str(SPP), "--threads", str(threads), "-o", out]
    c0 = children_cpu_s()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    cpu = children_cpu_s() - c0
    # The summary line (`wrote ...: 500x500, direct, 64 spp, 815.4 ms, ...`) goes to stderr.
    text = (out.stdout + "\n" + out.stderr).replace("\r", "\n")
    found = re.findall(r"wrote .*: (\d+)x(\d+), direct, (\d+) spp, ([\d.]+) ms", text)
    if not found or int(found[-1][2]) != SPP:
        sys.exit(f"unexpected raylab output: {text.strip()[-300:]}")
    return float(found[-1][3]) / SPP, 1e3 * cpu / SPP


# --- Images: PFM and OpenEXR (scanline or single-level tiled; NONE, RLE, ZIPS, ZIP; float or half) ---

def read_pfm(path):
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(b"\n", 3)
    if parts[0] != b"PF":
        raise ValueError(f"{path}: not an RGB PFM")
    w, h = map(int, parts[1].split())
    scale = float(parts[2])
    fmt = "<" if scale < 0 else ">"
    vals = struct.unpack(f"{fmt}{3 * w * h}f", parts[3][:12 * w * h])
    rows = [vals[3 * w * y:3 * w * (y + 1)] for y in range(h)]
    return w, h, [v for row in reversed(rows) for v in row]  # top row first


def _undo_predictor_interleave(raw):
    t = bytearray(raw)
    for i in range(1, len(t)):
        t[i] = (t[i - 1] + t[i] - 128) & 0xFF
    half = (len(t) + 1) // 2
    out = bytearray(len(t))
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return bytes(out)


def _rle(data):
    out = bytearray()
    i = 0
    while i < len(data):
        n = struct.unpack_from("b", data, i)[0]
        i += 1
        if n < 0:
            out += data[i:i - n]
            i -= n
        else:
            out += data[i:i + 1] * (n + 1)
            i += 1
    return bytes(out)


def _half(bits):
    return struct.unpack("<e", struct.pack("<H", bits))[0]


def read_exr(path):
    """(width, height, [r, g, b, ...] top row first) of an RGB OpenEXR file."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] != b"\x76\x2f\x31\x01":
        raise ValueError(f"{path}: not OpenEXR")
    flags = struct.unpack_from("<I", data, 4)[0]
    tiled = bool(flags & 0x200)
    pos, attrs = 8, {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        end2 = data.index(b"\0", end + 1)
        typ = data[end + 1:end2].decode()
        size = struct.unpack_from("<i", data, end2 + 1)[0]
        attrs[name] = (typ, data[end2 + 5:end2 + 5 + size])
        pos = end2 + 5 + size
    pos += 1
    chans, raw = [], attrs["channels"][1]
    i = 0
    while raw[i] != 0:
        end = raw.index(b"\0", i)
        ptype = struct.unpack_from("<i", raw, end + 1)[0]
        chans.append((raw[i:end].decode(), ptype))
        i = end + 17
    comp = attrs["compression"][1][0]
    x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"][1])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    size_of = {1: 2, 2: 4}
    planes = {name: [0.0] * (w * h) for name, _ in chans}

    def decode(block, nbytes):
        if comp == 0:
            return block
        if comp == 1:
            return _undo_predictor_interleave(_rle(block)) if len(block) < nbytes else block
        if comp in (2, 3):
            return _undo_predictor_interleave(zlib.decompress(block)) if len(block) < nbytes else block
        raise ValueError(f"{path}: compression {comp} not supported")

    def put(buf, bx, by, bw, bh):
        off = 0
        for yy in range(bh):
            for name, ptype in chans:
                n = size_of[ptype] * bw
                if ptype == 2:
                    vals = struct.unpack_from(f"<{bw}f", buf, off)
                else:
                    vals = [_half(b) for b in struct.unpack_from(f"<{bw}H", buf, off)]
                row = (by + yy) * w + bx
                planes[name][row:row + bw] = vals
                off += n

    pix = sum(size_of[p] for _, p in chans)
    if tiled:
        tx, ty = struct.unpack_from("<II", attrs["tiles"][1])
        ntiles = ((w + tx - 1) // tx) * ((h + ty - 1) // ty)
        offsets = struct.unpack_from(f"<{ntiles}Q", data, pos)
        for o in offsets:
            cx, cy, _, _, size = struct.unpack_from("<5i", data, o)
            bx, by = cx * tx, cy * ty
            bw, bh = min(tx, w - bx), min(ty, h - by)
            put(decode(data[o + 20:o + 20 + size], bw * bh * pix), bx, by, bw, bh)
    else:
        lines = {0: 1, 1: 1, 2: 1, 3: 16}[comp]
        nblocks = (h + lines - 1) // lines
        offsets = struct.unpack_from(f"<{nblocks}Q", data, pos)
        for o in offsets:
            yb, size = struct.unpack_from("<ii", data, o)
            by = yb - y0
            bh = min(lines, h - by)
            put(decode(data[o + 8:o + 8 + size], w * bh * pix), 0, by, w, bh)
    rgb = [0.0] * (3 * w * h)
    for k, name in enumerate("RGB"):
        rgb[k::3] = planes[name]
    return w, h, rgb


def read_image(path):
    return read_pfm(path) if path.endswith(".pfm") else read_exr(path)


def diff(a, b):
    """Max abs difference; pixels differing by > 1e-3, and how many of them lie on the
    image's diagonals (rays exactly through the box's corner edges: ties between a
    wall and the ceiling or floor); max abs difference over the other pixels."""
    (wa, ha, pa), (wb, hb, pb) = a, b
    if (wa, ha) != (wb, hb):
        raise ValueError("image sizes differ")
    worst, big, diag, rest = 0.0, 0, 0, 0.0
    for i in range(0, len(pa), 3):
        d = max(abs(pa[i + k] - pb[i + k]) for k in range(3))
        worst = max(worst, d)
        if d > 1e-3:
            big += 1
            x, y = (i // 3) % wa, (i // 3) // wa
            diag += x == y or x + y == wa - 1
        else:
            rest = max(rest, d)
    return worst, big, diag, rest


def check(exe, rl, tmp, quality):
    ours = os.path.join(tmp, "embree_frame.pfm")
    run([exe, "--threads", "1", "--apis", "single", "--quality", quality, "--warmup", "0", "--frames", "1",
         "--out", ours])
    ours4 = os.path.join(tmp, "embree_frame4.pfm")
    run([exe, "--threads", "2", "--apis", "packet4", "--quality", quality, "--warmup", "0", "--frames", "1",
         "--out", ours4])
    theirs = os.path.join(tmp, "raylab1.exr")
    run([rl, "render", "cornell", "--integrator", "direct", "--spp", "1", "--width", str(SIZE),
         "--height", str(SIZE), "-q", "-o", theirs])
    e1, e4, r = read_image(ours), read_image(ours4), read_image(theirs)
    lines = []
    for name, a, b in (("Embree single vs Embree 2×2", e1, e4),
                       ("Embree frame vs raylab --spp 1", e1, r)):
        lines.append((name, diff(a, b)))
    if os.path.exists(REF):
        ref = read_image(REF)
        lines.append(("Embree frame vs refs/cornell-direct-lab-500.exr", diff(e1, ref)))
        lines.append(("raylab --spp 1 vs refs/cornell-direct-lab-500.exr", diff(r, ref)))
    print("\n| images | max abs diff | pixels > 1e-3 (on the diagonals) | max abs diff elsewhere |")
    print("| --- | --- | --- | --- |")
    for name, (worst, big, diag, rest) in lines:
        print(f"| {name} | {worst:.3g} | {big} ({diag}) | {rest:.3g} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=3, help="alternated rounds (best kept)")
    ap.add_argument("--raylab", default=default_raylab(), help="raylab binary (default: %(default)s)")
    ap.add_argument("--bin", default=os.path.join(ROOT, "..", "bench-data", "bin"),
                    help="where embree_frame is built (default: %(default)s)")
    ap.add_argument("--quality", default="medium", choices=["low", "medium", "high"],
                    help="Embree build quality (medium, the default, and high trace this frame fastest)")
    ap.add_argument("--tries", type=int, default=4,
                    help="runs of a measurement until one is undisturbed by other processes")
    ap.add_argument("--check", action="store_true", help="also compare the pictures")
    args = ap.parse_args()
    exe = build(args.bin)
    if not os.path.exists(args.raylab):
        sys.exit(f"no raylab at {args.raylab}: cargo build --release, or pass --raylab")
    tmp = tempfile.mkdtemp()
    try:
        # (kind, threads) -> [(ms per frame, clean)], kind: raylab, single, packet4
        got = {}
        for rnd in range(args.rounds):
            for t in (1, 2):
                for api in ("single", "packet4"):
                    got.setdefault((api, t), []).append(
                        measured(lambda: embree(exe, api, t, args.quality), args.tries))
                got.setdefault(("raylab", t), []).append(
                    measured(lambda: raylab(args.raylab, t, os.path.join(tmp, "x.png")), args.tries))
            print(f"round {rnd + 1}/{args.rounds} done", file=sys.stderr)

        def best(key):
            runs = got[key]
            clean = [v[0] for v, ok in runs if ok]
            return (min(clean), "") if clean else (min(v[0] for v, _ in runs), "*")

        def cpu(key):
            return min(v[1] for v, _ in got[key])

        print(f"Lab box, `direct`, {SIZE}×{SIZE}: ms per frame, best of {args.rounds} alternated rounds "
              f"(Embree {args.quality} build quality: median of 64 frames after 10; "
              f"raylab: its {SPP}-spp render's time / {SPP})\n")
        print("| threads | raylab ms/frame | Embree single ms | Embree 2×2 ms | raylab / best Embree (goal ≤ 0.5) |")
        print("| --- | --- | --- | --- | --- |")
        flagged = False
        for t in (1, 2):
            (r, fr), (e1, f1), (e4, f4) = best(("raylab", t)), best(("single", t)), best(("packet4", t))
            flagged |= bool(fr or f1 or f4)
            print(f"| {t} | {r:.2f}{fr} | {e1:.2f}{f1} | {e4:.2f}{f4} | {r / min(e1, e4):.2f} |")
        clean = sum(ok for runs in got.values() for _, ok in runs)
        total = sum(len(runs) for runs in got.values())
        print(f"\n{clean} of {total} measurements undisturbed (other processes under 5 % of the machine)"
              + ("; * = every run of that cell was disturbed" if flagged else ""))
        r, e1, e4 = cpu(("raylab", 1)), cpu(("single", 1)), cpu(("packet4", 1))
        print(f"1 thread, CPU time per frame (less sensitive to other load; raylab's is its whole "
              f"process's / {SPP}, start-up included): raylab {r:.2f} ms, Embree single {e1:.2f} ms, "
              f"2×2 {e4:.2f} ms, ratio {r / min(e1, e4):.2f}")
        if args.check:
            check(exe, args.raylab, tmp, args.quality)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
