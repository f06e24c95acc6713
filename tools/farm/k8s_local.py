#!/usr/bin/env python3
"""Run a Kubernetes Indexed Job manifest of raylab tiles locally, then check its merge.

    python3 tools/farm/k8s_local.py [--raylab PATH] [--keep] [deploy/k8s/raylab-tiles-job.yaml]

For every completion index i in 0..completions-1 (at most `parallelism` at once) it runs
the container's command + args the way the kubelet would start them: with
JOB_COMPLETION_INDEX=i and the manifest's literal `env` values in the environment, and
`$(VAR)` references expanded from that container environment as Kubernetes does (`$$` is
a literal `$`, an unknown `$(VAR)` stays as written). The volume mount path (/out) is
mapped to a temp dir and `raylab` to the local binary. The parts are then merged with
`raylab merge` into a PNG and an EXR, and both must be byte-identical to one `raylab
render` with the same args minus --tile/--samples/-o. Exit 0 if so, 1 on a mismatch or a
failed task, 2 on a manifest this parser does not understand.

Python 3 standard library only: instead of a YAML library, a small parser reads just
the keys it needs (completions, parallelism, the container's command/args/env and the
first mountPath) and refuses anything it does not understand, so keep those keys simple:
block lists or one-line flow lists of plain or quoted scalars.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


class ManifestError(Exception):
    pass


def scalar(text):
    """One YAML scalar on one line: "double", 'single' or plain (comment stripped)."""
    text = text.strip()
    if text.startswith('"'):
        end = text.rfind('"')
        if end <= 0:
            raise ManifestError(f"unterminated string: {text}")
        return json.loads(text[: end + 1])  # simple YAML double-quoted strings are JSON
    if text.startswith("'"):
        end = text.rfind("'")
        if end <= 0:
            raise ManifestError(f"unterminated string: {text}")
        return text[1:end].replace("''", "'")
    text = re.sub(r"\s+#.*$", "", text)
    if text[:1] in ("|", ">", "[", "{", "&", "*", "!"):
        raise ManifestError(f"unsupported YAML here: {text}")
    return text


def flow_list(text):
    """A one-line flow list of scalars: ["a", 'b', c]."""
    text = re.sub(r"\s+#.*$", "", text.strip())
    if not (text.startswith("[") and text.endswith("]")):
        raise ManifestError(f"expected a one-line [list]: {text}")
    items = re.findall(r'"(?:[^"\\]|\\.)*"|\'(?:[^\']|\'\')*\'|[^,\s][^,]*', text[1:-1])
    return [scalar(i) for i in items]


def parse_manifest(path):
    """The few fields this runner needs, from the first Job document of the file."""
    lines = []
    with open(path, encoding="utf-8") as f:
        for raw in f:
            if raw.strip() == "---" and lines:
                break  # only the first document
            if raw.strip() and not raw.lstrip().startswith("#"):
                lines.append(raw.rstrip("\n"))

    def indent(line):
        return len(line) - len(line.lstrip(" "))

    def find(key, start=0):
        for i in range(start, len(lines)):
            m = re.match(r"^(\s*)(-\s+)?" + re.escape(key) + r":(.*)$", lines[i])
            if m:
                return i, m.group(3).strip()
        return None, None

    def block_list(i, value):
        """The list value of the key on line i: inline [..] or `- item` lines below."""
        if value:
            return flow_list(value)
        items, base = [], indent(lines[i])
        for line in lines[i + 1:]:
            if indent(line) < base or (indent(line) == base and not line.lstrip().startswith("- ")):
                break
            stripped = line.strip()
            if not stripped.startswith("- "):
                raise ManifestError(f"not a list item of a one-line scalar: {line.strip()}")
            items.append(scalar(stripped[2:]))
        return items

    def number(key):
        i, value = find(key)
        if i is None:
            return None
        if not re.fullmatch(r"\d+", scalar(value)):
            raise ManifestError(f"{key}: expected a number, got {value}")
        return int(scalar(value))

    if find("kind")[1] != "Job" or find("completionMode")[1] != "Indexed":
        raise ManifestError("not an Indexed Job (kind: Job, completionMode: Indexed)")
    completions = number("completions")
    if not completions:
        raise ManifestError("an Indexed Job needs completions")
    parallelism = number("parallelism") or 1
    c, _ = find("containers")
    if c is None:
        raise ManifestError("no containers")
    command, args = [], []
    i, value = find("command", c)
    if i is not None:
        command = block_list(i, value)
    i, value = find("args", c)
    if i is not None:
        args = block_list(i, value)
    if not command and not args:
        raise ManifestError("the container has neither command nor args")
    # env: `- name: X` followed by `value: ...` (literal) or `valueFrom:` (left to the runner).
    env = {}
    e, _ = find("env", c)
    if e is not None:
        base = indent(lines[e])
        name = None
        for line in lines[e + 1:]:
            if indent(line) <= base and not (indent(line) == base and line.lstrip().startswith("- ")):
                break
            m = re.match(r"^\s*(-\s+)?(name|value):\s*(.*)$", line)
            if m and m.group(2) == "name":
                name = scalar(m.group(3))
            elif m and name is not None:
                env[name] = scalar(m.group(3))
    i, mount = find("mountPath", c)
    return {
        "completions": completions,
        "parallelism": parallelism,
        "argv": command + args,
        "env": env,
        "mount": scalar(mount) if mount else None,
    }


def expand(text, env):
    """Kubernetes' $(VAR) expansion of command and args."""
    out, i = [], 0
    while i < len(text):
        if text[i] == "$" and i + 1 < len(text):
            if text[i + 1] == "$":  # $$ -> $ (so $$(VAR) stays literal)
                out.append("$")
                i += 2
                continue
            if text[i + 1] == "(":
                end = text.find(")", i + 2)
                if end != -1:
                    name = text[i + 2 : end]
                    out.append(env.get(name, text[i : end + 1]))
                    i = end + 1
                    continue
        out.append(text[i])
        i += 1
    return "".join(out)


def strip_split_args(argv):
    """argv without the options that make a part (--tile, --samples) and without -o."""
    out, skip = [], False
    for a in argv:
        if skip:
            skip = False
        elif a in ("--tile", "--samples", "-o", "--output"):
            skip = True
        elif not a.startswith(("--tile=", "--samples=", "--output=")):
            out.append(a)
    return out


def output_of(argv):
    for i, a in enumerate(argv):
        if a in ("-o", "--output") and i + 1 < len(argv):
            return argv[i + 1]
        if a.startswith("--output="):
            return a.split("=", 1)[1]
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("manifest", nargs="?", default=os.path.join(REPO, "deploy/k8s/raylab-tiles-job.yaml"))
    ap.add_argument("--raylab", default=os.environ.get("RAYLAB", os.path.join(REPO, "target/release/raylab")))
    ap.add_argument("--keep", action="store_true", help="keep the temp dir (its path is printed)")
    opts = ap.parse_args()
    try:
        job = parse_manifest(opts.manifest)
    except (ManifestError, ValueError) as e:
        print(f"k8s_local: {opts.manifest}: {e}", file=sys.stderr)
        return 2
    raylab = os.path.abspath(opts.raylab)
    if not os.access(raylab, os.X_OK):
        print(f"k8s_local: no raylab binary at {raylab} (use --raylab)", file=sys.stderr)
        return 2
    if os.path.basename(job["argv"][0]) != "raylab":
        print(f"k8s_local: the container runs {job['argv'][0]}, not raylab", file=sys.stderr)
        return 2
    tmp = tempfile.mkdtemp(prefix="raylab-k8s-")
    try:
        return run(job, raylab, tmp)
    finally:
        if opts.keep:
            print(f"kept {tmp}")
        else:
            shutil.rmtree(tmp, ignore_errors=True)


def run(job, raylab, tmp):
    mount = job["mount"]

    def local_path(a):  # /out/x -> TMP/x, as the volume mount would place it
        if mount and (a == mount or a.startswith(mount.rstrip("/") + "/")):
            return os.path.join(tmp, os.path.relpath(a, mount))
        return a

    def task(index):
        env = dict(job["env"], JOB_COMPLETION_INDEX=str(index))
        argv = [raylab] + [local_path(expand(a, env)) for a in job["argv"][1:]]
        proc = subprocess.run(argv, env=dict(os.environ, **env), capture_output=True, text=True)
        return index, argv, proc

    n = job["completions"]
    print(f"running {n} indexes, {min(job['parallelism'], n)} at a time: "
          f"{' '.join(job['argv'])} (with {mount} -> {tmp})")
    parts = []
    with ThreadPoolExecutor(max_workers=min(job["parallelism"], n)) as pool:
        for index, argv, proc in pool.map(task, range(n)):
            print(f"  index {index}: {' '.join(argv[1:])}: exit {proc.returncode}")
            if proc.returncode != 0:
                print(f"k8s_local: index {index} failed: {proc.stderr.strip()}", file=sys.stderr)
                return 1
            parts.append(output_of(argv))
    base = strip_split_args(job["argv"][1:])
    if base[:1] != ["render"]:
        print("k8s_local: expected `raylab render ...` in the manifest", file=sys.stderr)
        return 2
    for ext in ("png", "exr"):
        merged, ref = os.path.join(tmp, f"merged.{ext}"), os.path.join(tmp, f"single.{ext}")
        for argv in ([raylab, "merge", "-q", *parts, "-o", merged], [raylab, *base, "-q", "-o", ref]):
            proc = subprocess.run(argv, capture_output=True, text=True)
            if proc.returncode != 0:
                print(f"k8s_local: {' '.join(argv)} failed: {proc.stderr.strip()}", file=sys.stderr)
                return 1
        with open(merged, "rb") as a, open(ref, "rb") as b:
            if a.read() != b.read():
                print(f"k8s_local: MISMATCH: the merged {ext.upper()} differs from `raylab {' '.join(base)}`",
                      file=sys.stderr)
                return 1
        print(f"merged {len(parts)} parts: {ext.upper()} byte-identical to `raylab {' '.join(base)}`")
    return 0


if __name__ == "__main__":
    sys.exit(main())
