#!/usr/bin/env python3
"""Render the documentation's images with a raylab binary and record their hashes.

usage: check_images.py --bin BINARY --out DIR [--repo DIR] [--readme FILE ...]
                       [--extra] [--only NAME ...] [--threads N] [--oidn LIB] [--list]
       check_images.py --compare DIR_A DIR_B

A refactor that must not change any image can be checked with two runs of this
tool, one with the old binary and one with the new, and a comparison:

    nice -n 10 tools/check_images.py --bin old/raylab --out /tmp/img-old --extra
    nice -n 10 tools/check_images.py --bin target/release/raylab --out /tmp/img-new --extra
    tools/check_images.py --compare /tmp/img-old /tmp/img-new

Rendering. Every `raylab render ... -o docs/NAME.png` (or `.exr`) command of the
Markdown files (default: README.md and docs/*.md under --repo) is collected,
from inline code spans (`...`, which may wrap across lines) and from fenced
code blocks (```sh, ```bash, ```console or unlabelled; lines continued with a
trailing backslash are joined, `$ ` prompts and `# comments` dropped). Each is
run with BINARY in place of `raylab`, in the --repo folder (default: `.`, the
commands refer to scenes/ and assets/), with its output rewritten to
DIR/NAME.png and `--threads N` (default 2) added when the command has none.
Renders are deterministic: the same command, seed and inputs give the same
bytes on any number of threads, so the images' hashes are comparable across
runs and machines. `--extra` adds the commands of EXTRA below, which the
documentation does not spell out with an `-o docs/...` but whose images must
stay the same too (an EXR with every AOV, `--denoise`, a tiled render merged
with `raylab merge`, ...).

DIR/manifest.txt gets one tab-separated line per image:

    SHA256 <TAB> NAME <TAB> COMMAND <TAB> SECONDS

(lines starting with `#` are comments: the binary, the time of the run). A
command that fails gets `FAILED` in place of the hash, its error goes to
stderr and the tool exits 1 once all commands have run.

Comparing. `--compare DIR_A DIR_B` reads both manifests, matches the images by
name and prints a table; it exits 1 if any hash differs or an image is missing
from (or failed in) either. Byte identity is the requirement: raylab's EXR
headers hold no time or build information, only `raylab.spp` and
`raylab.render` (spp, seed, integrator), so equal pixels give equal files. When
an EXR differs and both files are still in the folders, the table says whether
only header attributes differ (naming them) or the pixel data too, decoding
the chunks (NONE, RLE, ZIPS and ZIP compressions) so that the verdict does not
depend on how the bytes were compressed.
"""

import argparse
import glob
import hashlib
import os
import re
import shlex
import struct
import subprocess
import sys
import tempfile
import time
import zlib

# Open Image Denoise for `--denoise` commands: RAYLAB_OIDN, or --oidn.
DEFAULT_OIDN = None  # RAYLAB_OIDN, or --oidn

# Commands whose images must stay identical although the documentation gives
# them without `-o docs/...`. Each entry: the image's name in DIR, and the
# steps, each an argument list after `raylab`. `{out}` is the image's path,
# `{tmp}` a temporary folder removed afterwards; a `render` step without
# `--threads` gets `--threads N`. `denoise` entries run with RAYLAB_OIDN set.
EXTRA = [
    {"name": "extra-box-direct-spp4.png",
     "steps": [["render", "--spp", "4", "-o", "{out}"]]},
    {"name": "extra-helmet-venice-rotate200.png",
     "steps": [["render", "assets/models/DamagedHelmet/DamagedHelmet.gltf",
                "--env", "assets/envmaps/venice_sunset_1k.hdr", "--env-rotate", "200",
                "--spp", "8", "--width", "320", "-o", "{out}"]]},
    {"name": "extra-showcase-denoise.png", "denoise": True,
     "steps": [["render", "scenes/showcase/showcase.gltf", "--spp", "8", "--width", "320",
                "--denoise", "-o", "{out}"]]},
    {"name": "extra-box-path-aovs.exr",
     "steps": [["render", "--integrator", "path", "--aov", "albedo,normal,depth,position,variance",
                "--spp", "8", "-o", "{out}"]]},
    # A render split into two tiles and merged: byte for byte the unsplit render.
    {"name": "extra-box-path-tiles-merged.png",
     "steps": [["render", "--integrator", "path", "--spp", "8", "--tile", "0/2", "-o", "{tmp}/part-0.exr"],
               ["render", "--integrator", "path", "--spp", "8", "--tile", "1/2", "-o", "{tmp}/part-1.exr"],
               ["merge", "{tmp}/part-0.exr", "{tmp}/part-1.exr", "-o", "{out}"]]},
    # README "Meshes": the bunny picture's command, which has no `-o`.
    {"name": "extra-cornell-bunny.png",
     "steps": [["render", "--add", "assets/models/stanford-bunny.obj", "--transform",
                "fit 0.7; rotate x 180; rotate y 30; translate -0.45 1 -0.55", "--spp", "16",
                "-o", "{out}"]]},
]

OUT_RE = re.compile(r"^docs/([^/]+\.(?:png|exr))$")
FENCE_RE = re.compile(r"^ {0,3}(```+|~~~+)[ \t]*([\w+-]*)[^\n]*\n(.*?)^ {0,3}\1[ \t]*$", re.M | re.S)
SHELL_LANGS = {"", "sh", "bash", "shell", "console", "zsh"}


# ---------------------------------------------------------------- extraction

def shell_lines(block):
    """The commands of a shell code block: continuations joined, prompts dropped."""
    lines, cur = [], ""
    for raw in block.splitlines():
        line = raw.rstrip()
        if line.endswith("\\"):
            cur += line[:-1] + " "
            continue
        cur += line
        lines.append(cur.strip())
        cur = ""
    if cur.strip():
        lines.append(cur.strip())
    return [l[2:] if l.startswith("$ ") else l for l in lines]


def candidate_commands(text):
    """Code snippets of a Markdown text that may be commands, in document order."""
    out = []
    fenced = []
    for m in FENCE_RE.finditer(text):
        fenced.append((m.start(), m.end()))
        if m.group(2).lower() in SHELL_LANGS:
            out.extend((m.start(), l) for l in shell_lines(m.group(3)))
    # Inline code spans outside fenced blocks; a span may wrap across lines
    # but not across a blank line (a paragraph break).
    prose = list(text)
    for a, b in fenced:
        prose[a:b] = [" "] * (b - a)
    prose = "".join(prose)
    for m in re.finditer(r"(?<!`)(`+)(?!`)(.+?)(?<!`)\1(?!`)", prose, re.S):
        span = m.group(2)
        if "\n\n" in span:
            continue
        span = re.sub(r"\\\n", " ", span)
        out.append((m.start(), " ".join(span.split())))
    out.sort(key=lambda p: p[0])
    return [c for _, c in out]


def parse_raylab(cmd):
    """(args after `raylab`, output name) for a `raylab render ... -o docs/NAME` command, else None."""
    try:
        words = shlex.split(cmd, comments=True)
    except ValueError:
        return None
    if len(words) < 2 or words[0] != "raylab" or words[1] != "render":
        return None
    args = words[1:]
    for i, w in enumerate(args):
        value = None
        if w in ("-o", "--output") and i + 1 < len(args):
            value = args[i + 1]
        elif w.startswith("--output=") or w.startswith("-o="):
            value = w.split("=", 1)[1]
        if value is not None:
            m = OUT_RE.match(value)
            if m:
                return args, m.group(1)
    return None


def doc_commands(files):
    """[(name, args, source file)] of every documented image command, first occurrence kept."""
    found, seen = [], {}
    for path in files:
        with open(path, encoding="utf-8") as f:
            text = f.read()
        for cmd in candidate_commands(text):
            parsed = parse_raylab(cmd)
            if not parsed:
                continue
            args, name = parsed
            if name in seen:
                if seen[name] != args:
                    print(f"warning: {path}: {name} made by another command too, keeping the first:\n"
                          f"  {shlex.join(['raylab'] + seen[name])}\n  {shlex.join(['raylab'] + args)}",
                          file=sys.stderr)
                continue
            seen[name] = args
            found.append((name, args, path))
    return found


# ------------------------------------------------------------------ running

def with_output(args, out):
    """args with the -o/--output value replaced by out."""
    res, i = [], 0
    while i < len(args):
        w = args[i]
        if w in ("-o", "--output") and i + 1 < len(args):
            res += [w, out]
            i += 2
            continue
        if w.startswith("--output=") or w.startswith("-o="):
            w = w.split("=", 1)[0] + "=" + out
        res.append(w)
        i += 1
    return res


def with_threads(args, threads):
    if args[0] != "render" or any(a == "--threads" or a.startswith("--threads=") for a in args):
        return args
    return args + ["--threads", str(threads)]


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def run_job(binary, repo, name, steps, out_dir, threads, env):
    """Run one image's steps; (sha256 or None, display command, seconds, error)."""
    out = os.path.join(out_dir, name)
    if os.path.exists(out):
        os.remove(out)
    shown = []
    elapsed = 0.0
    with tempfile.TemporaryDirectory(prefix="check_images.") as tmp:
        for step in steps:
            args = [a.replace("{out}", out).replace("{tmp}", tmp) for a in step]
            args = with_threads(args, threads)
            shown.append(shlex.join(["raylab"] + [a.replace(tmp, "$TMP").replace(out_dir, "$OUT") for a in args]))
            t0 = time.monotonic()
            p = subprocess.run([binary] + args, cwd=repo, env=env, stdin=subprocess.DEVNULL,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            elapsed += time.monotonic() - t0
            if p.returncode != 0:
                err = (p.stderr.strip() or p.stdout.strip() or "(no message)").splitlines()[-1]
                return None, " && ".join(shown), elapsed, f"exit {p.returncode}: {err}"
    if not os.path.exists(out):
        return None, " && ".join(shown), elapsed, "no image written"
    return sha256(out), " && ".join(shown), elapsed, None


def render_all(opts):
    repo = os.path.abspath(opts.repo)
    binary = os.path.abspath(opts.bin)
    out_dir = os.path.abspath(opts.out) if opts.out else None
    files = opts.readme or [os.path.join(repo, "README.md")] + sorted(glob.glob(os.path.join(repo, "docs", "*.md")))
    jobs = []
    for name, args, src in doc_commands(files):
        jobs.append({"name": name, "steps": [with_output(args, "{out}")], "src": src})
    if opts.extra:
        for e in EXTRA:
            jobs.append(dict(e, src="EXTRA"))
    if opts.only:
        jobs = [j for j in jobs if j["name"] in opts.only]
    if opts.list:
        for j in jobs:
            print(f"{j['name']}\t{' && '.join(shlex.join(['raylab'] + s) for s in j['steps'])}\t({j['src']})")
        return 0
    os.makedirs(out_dir, exist_ok=True)
    manifest = os.path.join(out_dir, "manifest.txt")
    failures, total = [], 0.0
    version = subprocess.run([binary, "--version"], capture_output=True, text=True).stdout.strip()
    with open(manifest, "w", encoding="utf-8") as m:
        m.write(f"# check_images.py manifest: sha256 <TAB> name <TAB> command <TAB> seconds\n")
        m.write(f"# binary: {binary} ({version}, sha256 {sha256(binary)})\n")
        m.write(f"# repo: {repo}; threads: {opts.threads}; started {time.strftime('%Y-%m-%d %H:%M:%S')}\n")
        m.write(f"# sources: {' '.join(files)}{' + EXTRA' if opts.extra else ''}\n")
        for j in jobs:
            env = dict(os.environ)
            if j.get("denoise") and "RAYLAB_OIDN" not in env and opts.oidn:
                env["RAYLAB_OIDN"] = opts.oidn
            digest, shown, secs, err = run_job(binary, repo, j["name"], j["steps"], out_dir, opts.threads, env)
            total += secs
            status = digest[:16] if digest else "FAILED"
            print(f"{status:16}  {secs:8.2f} s  {j['name']}", flush=True)
            if err:
                failures.append((j["name"], shown, err))
                print(f"  error: {err}\n  command: {shown}", file=sys.stderr, flush=True)
            m.write(f"{digest or 'FAILED'}\t{j['name']}\t{shown}\t{secs:.2f}\n")
            m.flush()
        m.write(f"# total: {len(jobs)} images, {total:.1f} s, {len(failures)} failed\n")
    print(f"{len(jobs)} images, {total:.1f} s in all, {len(failures)} failed; manifest: {manifest}")
    return 1 if failures else 0


# ---------------------------------------------------------------- comparing

def read_manifest(d):
    path = os.path.join(d, "manifest.txt")
    rows = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            digest, name, cmd, secs = line.rstrip("\n").split("\t")
            rows[name] = (digest, cmd, float(secs))
    return rows


def exr_parts(path):
    """(header attributes {name: (type, bytes)}, digest of the decoded pixel data) of a
    single-part EXR, or None if it cannot be read here (multi-part, deep, unknown)."""
    try:
        with open(path, "rb") as f:
            d = f.read()
        if d[:4] != b"\x76\x2f\x31\x01":
            return None
        flags = struct.unpack_from("<I", d, 4)[0]
        if flags & 0x1800:  # multi-part or non-image (deep) data
            return None
        tiled = bool(flags & 0x200)
        p, attrs = 8, {}
        while d[p] != 0:
            e = d.index(b"\0", p); name = d[p:e].decode(); p = e + 1
            e = d.index(b"\0", p); typ = d[p:e].decode(); p = e + 1
            size = struct.unpack_from("<i", d, p)[0]; p += 4
            attrs[name] = (typ, d[p:p + size]); p += size
        p += 1
        comp = attrs["compression"][1][0]
        x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"][1])
        if "chunkCount" in attrs:
            count = struct.unpack("<i", attrs["chunkCount"][1])[0]
        elif tiled:
            return None
        else:
            per = {0: 1, 1: 1, 2: 1, 3: 16, 4: 32, 5: 16, 6: 32, 7: 32, 8: 16, 9: 256}.get(comp, 1)
            count = (y1 - y0 + per) // per
        offsets = struct.unpack_from(f"<{count}Q", d, p)
        chunks = {}
        for off in offsets:
            if tiled:
                key = struct.unpack_from("<4i", d, off); size = struct.unpack_from("<i", d, off + 16)[0]
                data = d[off + 20:off + 20 + size]
            else:
                key = struct.unpack_from("<i", d, off); size = struct.unpack_from("<i", d, off + 4)[0]
                data = d[off + 8:off + 8 + size]
            chunks[key] = data
        h = hashlib.sha256(attrs["channels"][1] + attrs["dataWindow"][1])
        for key in sorted(chunks):
            h.update(repr(key).encode())
            h.update(decode_chunk(chunks[key], comp))
        return attrs, h.hexdigest()
    except (OSError, KeyError, IndexError, ValueError, struct.error, zlib.error):
        return None


def decode_chunk(data, comp):
    """A chunk's uncompressed bytes for NONE, RLE, ZIPS and ZIP; other compressions'
    bytes tagged as they are (equal only under the same compression)."""
    if comp == 0:
        return data
    if comp == 1:
        out = bytearray(); i = 0
        while i < len(data):
            n = struct.unpack_from("b", data, i)[0]; i += 1
            if n < 0:
                out += data[i:i - n]; i -= n
            else:
                out += data[i:i + 1] * (n + 1); i += 1
    elif comp in (2, 3):
        try:
            out = bytearray(zlib.decompress(data))
        except zlib.error:
            return data  # stored uncompressed: the compressed form was not smaller
    else:
        return b"comp%d:" % comp + data
    # Undo the predictor and the interleaving of RLE and ZIP(S).
    for i in range(1, len(out)):
        out[i] = (out[i - 1] + out[i] - 128) & 0xFF
    half = (len(out) + 1) // 2
    res = bytearray(len(out))
    res[0::2] = out[:half]
    res[1::2] = out[half:]
    return bytes(res)


def explain_exr(path_a, path_b):
    a, b = exr_parts(path_a), exr_parts(path_b)
    if a is None or b is None:
        return "EXR not decoded here"
    names = sorted(n for n in set(a[0]) | set(b[0]) if a[0].get(n) != b[0].get(n))
    pixels = "pixels identical" if a[1] == b[1] else "pixels differ"
    if names:
        return f"{pixels}; header differs in {', '.join(names)}"
    return f"{pixels}; header identical"


def compare(dir_a, dir_b):
    a, b = read_manifest(dir_a), read_manifest(dir_b)
    names = list(a) + [n for n in b if n not in a]
    width = max([len(n) for n in names] + [5])
    print(f"{'image':{width}}  {'A sha256':16}  {'B sha256':16}  {'A s':>8}  {'B s':>8}  verdict")
    bad = 0
    for n in names:
        ra, rb = a.get(n), b.get(n)
        ha = ra[0][:16] if ra else "-"
        hb = rb[0][:16] if rb else "-"
        ta = f"{ra[2]:.2f}" if ra else "-"
        tb = f"{rb[2]:.2f}" if rb else "-"
        if ra is None or rb is None:
            verdict = f"MISSING in {'A' if ra is None else 'B'}"
        elif "FAILED" in (ra[0], rb[0]):
            verdict = "FAILED in " + " and ".join(x for x, r in (("A", ra), ("B", rb)) if r[0] == "FAILED")
        elif ra[0] == rb[0]:
            verdict = "same"
        else:
            verdict = "DIFFERENT"
            if n.endswith(".exr"):
                pa, pb = os.path.join(dir_a, n), os.path.join(dir_b, n)
                if os.path.exists(pa) and os.path.exists(pb) and sha256(pa) == ra[0] and sha256(pb) == rb[0]:
                    verdict += f" ({explain_exr(pa, pb)})"
        if ra and rb and verdict == "same" and ra[1] != rb[1]:
            verdict += " (commands differ)"
        if not verdict.startswith("same"):
            bad += 1
        print(f"{n:{width}}  {ha:16}  {hb:16}  {ta:>8}  {tb:>8}  {verdict}")
    ta = sum(r[2] for r in a.values())
    tb = sum(r[2] for r in b.values())
    print(f"{'total':{width}}  {'':16}  {'':16}  {ta:8.2f}  {tb:8.2f}  "
          f"{len(names) - bad} same, {bad} not (B/A time {tb / ta if ta else float('nan'):.3f})")
    return 1 if bad else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="See the module docstring (head of this file) for details.")
    ap.add_argument("--bin", help="the raylab binary to render with")
    ap.add_argument("--out", help="folder for the images and manifest.txt")
    ap.add_argument("--repo", default=".", help="folder the commands run in (default: .)")
    ap.add_argument("--readme", nargs="+", metavar="FILE",
                    help="Markdown files to take the commands from (default: REPO/README.md REPO/docs/*.md)")
    ap.add_argument("--extra", action="store_true", help="also render the EXTRA commands")
    ap.add_argument("--only", nargs="+", metavar="NAME", help="render only these images (by name)")
    ap.add_argument("--threads", type=int, default=2, help="--threads for renders that give none (default: 2)")
    ap.add_argument("--oidn", default=DEFAULT_OIDN, help="RAYLAB_OIDN for --denoise commands when unset")
    ap.add_argument("--list", action="store_true", help="print the commands and exit")
    ap.add_argument("--compare", nargs=2, metavar=("DIR_A", "DIR_B"), help="compare two runs' manifests")
    opts = ap.parse_args()
    if opts.compare:
        return compare(*opts.compare)
    if not opts.bin or (not opts.out and not opts.list):
        ap.error("--bin and --out are needed (or --compare DIR_A DIR_B)")
    return render_all(opts)


if __name__ == "__main__":
    sys.exit(main())
