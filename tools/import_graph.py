#!/usr/bin/env python3
"""The library's import graph: which module of src/ names which other one.

Reads every .rs file under src/ except src/bin/ (Python 3 standard library
only), maps each file to its module path (src/foo.rs and src/foo/mod.rs ->
`foo`, src/foo/bar.rs -> `foo::bar`, src/lib.rs -> `crate`), and finds every
reference to another module of the crate:

* `use` and `pub use` items, grouped ones (`use crate::{a, b::{c, d}}`) too,
  starting with `crate::`, `super::`, `self::`, a child module's name or (in
  lib.rs) a top-level module's name;
* paths inside code: `crate::a::b::item`, `super::item`, `self::child::item`
  and `child::item` where `child` is a submodule of the file's module.

Each reference is resolved to the module file it names: the longest prefix of
the path that is a module of the crate. `mod child;` declarations are not
edges (a parent declaring a child is not an import); a parent that uses or
re-exports an item of its child is.

Comments (doc comments included), string and char literals are ignored, and so
is every item under `#[cfg(test)]` (test modules, test-only files and their
imports): they are counted and reported apart, and `--with-tests` puts them
back into the graph.

Prints the number of modules and edges at two levels, file (one node per .rs
file) and top-level module (`aov`, `cache`, `scene`, ... with every file under
src/scene/ one node `scene`), and the strongly connected components (Tarjan)
with more than one member at each level. A file-level circle is either between
files, or within one module split over its folder: the folder's mod.rs (which
declares the other files and uses or re-exports their items) is in it with
files below it, which use its items (`use super::...`), as `geometry/bvh/`'s
files implement `Bvh`'s methods. `--layers` also lists every import that goes
from a lower layer to a higher one in LAYERS below; `--edges` prints every edge
with the lines it comes from.

Exit status: 1 if the top-level-module graph has a circle, if the file-level
graph has a circle between files (`--strict`: any circle at all), or, with
`--layers`, if an import goes up a layer; 0 otherwise, so CI can run it:
`python3 tools/import_graph.py --layers`.
"""

import argparse
import os
import re
import sys
from collections import defaultdict

ROOT = "crate"

# The layer order of the top-level modules, lowest first. A module may import
# from its own layer and from layers below it, never from one above. (A circle
# inside one layer is still reported by the component check.)
LAYERS = [
    # plain utilities that know nothing of rendering
    ["fixed", "guard", "fingerprint", "memory", "limits", "simd"],
    # images and files: the film (buffers, tone mapping, atomic PNG/EXR
    # output) and the content-addressed disk cache
    ["film", "cache"],
    # numbers, rays and the acceleration structure
    ["sampling", "geometry"],
    # what a scene is made of
    ["textures", "materials", "media", "lights", "camera"],
    # the scene model
    ["scene"],
    # what is computed per pixel
    ["aov", "integrators"],
    # reading scenes (and scene files, which name an integrator) from files
    ["load"],
    # the render loop and what uses it
    ["render", "checkpoint", "denoise", "nan_check", "controls", "workload"],
    # many processes
    ["farm"],
    # the render job (the command line's policy) and the benchmark's timing
    ["job", "bench"],
    # a view that refines and denoises interactively (on the job's sessions)
    ["interactive"],
    # the crate root re-exports a few items of everything
    [ROOT],
]


def strip_code(text):
    """Blanks comments, string literals and char literals (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 20]) and (
            i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")
        ):
            m = re.match(r'r(#*)"', text[i:])
            close = '"' + m.group(1)
            j = text.find(close, i + len(m.group(0)))
            j = n if j < 0 else j + len(close)
            out.append('""' + re.sub(r"[^\n]", " ", text[i + 2:j]))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            j += 1
            out.append('""' + re.sub(r"[^\n]", " ", text[i + 2:j]))
            i = j
        elif c == "'":
            m = re.match(r"'(\\u\{[0-9a-fA-F]+\}|\\x[0-9a-fA-F]{2}|\\.|[^\\'\n])'", text[i:])
            if m:
                out.append("' '" + " " * (len(m.group(0)) - 3))
                i += len(m.group(0))
            else:  # a lifetime
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def skip_item(code, i):
    """The end of the item starting at i: after its `;` or its `{ ... }`."""
    n = len(code)
    depth_paren = 0
    while i < n:
        c = code[i]
        if c in "([":
            depth_paren += 1
        elif c in ")]":
            depth_paren -= 1
        elif c == ";" and depth_paren <= 0:
            return i + 1
        elif c == "{":
            depth = 1
            i += 1
            while i < n and depth:
                if code[i] == "{":
                    depth += 1
                elif code[i] == "}":
                    depth -= 1
                i += 1
            return i
        i += 1
    return n


# `#[cfg(test)]` and `#[cfg(all(test, ...))]`: code that only tests compile.
CFG_TEST = re.compile(r"#\s*\[\s*cfg\s*\(\s*(?:test|all\s*\(\s*test\s*,[^\]]*)\)\s*\]")
ATTR = re.compile(r"\s*#\s*\[[^\]]*\]")


def split_tests(code):
    """(code without #[cfg(test)] items, the test items' text, test child modules)."""
    kept, tests, test_mods = [], [], set()
    pos = 0
    for m in CFG_TEST.finditer(code):
        if m.start() < pos:
            continue
        kept.append(code[pos:m.start()])
        j = m.end()
        while True:
            a = ATTR.match(code, j)
            if not a:
                break
            j = a.end()
        end = skip_item(code, j)
        item = code[m.start():end]
        mm = re.match(r"\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;", code[j:end])
        if mm:
            test_mods.add(mm.group(1))
        tests.append(item)
        kept.append(re.sub(r"[^\n]", " ", item))
        pos = end
    kept.append(code[pos:])
    return "".join(kept), "".join(tests), test_mods


def module_of(rel):
    """src-relative file path -> module path (a tuple of segments)."""
    parts = rel[:-3].split(os.sep)
    if parts == ["lib"]:
        return ()
    if parts[-1] == "mod":
        parts = parts[:-1]
    return tuple(parts)


def name(mod):
    return "::".join(mod) if mod else ROOT


def parse_use_tree(s):
    """`a::{b, c::d as e}` -> list of paths (lists of segments); globs end in '*'."""
    s = re.sub(r"\s+", " ", s).strip()
    pos = 0

    def tree(prefix):
        nonlocal pos
        paths = []
        segs = list(prefix)
        while True:
            while pos < len(s) and s[pos] == " ":
                pos += 1
            if pos >= len(s):
                paths.append(segs)
                return paths
            if s[pos] == "{":
                pos += 1
                while True:
                    while pos < len(s) and s[pos] in " ,":
                        pos += 1
                    if pos >= len(s) or s[pos] == "}":
                        pos += 1
                        return paths
                    paths.extend(tree(segs))
            m = re.match(r"(\*|\w+)\s*", s[pos:])
            if not m:
                paths.append(segs)
                return paths
            segs = segs + [m.group(1)]
            pos += len(m.group(0))
            if s.startswith("::", pos):
                pos += 2
                continue
            a = re.match(r"as\s+\w+\s*", s[pos:])
            if a:
                pos += len(a.group(0))
            paths.append(segs)
            return paths

    out = []
    while pos < len(s):
        out.extend(tree([]))
        while pos < len(s) and s[pos] in " ,}":
            pos += 1
    return out


USE = re.compile(r"(?<![\w:])use\s+((?:::)?[^;]*);")
CODE_PATH = re.compile(r"(?<![\w:$])((?:crate|super|self)\b(?:\s*::\s*(?:\w+))+)")
CHILD_PATH = re.compile(r"(?<![\w:$.])(\w+)\s*::\s*(\w+)")


class Graph:
    def __init__(self, src, with_tests):
        self.files = {}  # module -> rel path
        self.code = {}  # module -> stripped code
        self.test_refs = 0
        self.test_files = set()
        for dirpath, dirnames, filenames in os.walk(src):
            rel_dir = os.path.relpath(dirpath, src)
            if rel_dir == "bin" or rel_dir.startswith("bin" + os.sep):
                dirnames[:] = []
                continue
            dirnames.sort()
            for f in sorted(filenames):
                if not f.endswith(".rs"):
                    continue
                rel = os.path.normpath(os.path.join(rel_dir, f))
                with open(os.path.join(src, rel), encoding="utf-8") as fh:
                    self.files[module_of(rel)] = rel
                    self.code[module_of(rel)] = strip_code(fh.read())
        self.modules = set(self.files)
        # test-only code and files
        self.tests = {}
        test_children = set()
        for mod, code in self.code.items():
            kept, tests, test_mods = split_tests(code)
            if not with_tests:
                self.code[mod] = kept
            self.tests[mod] = tests
            test_children |= {mod + (c,) for c in test_mods}
        self.test_files = {m for m in self.modules if any(m[: len(t)] == t for t in test_children)}
        if not with_tests:
            self.modules -= self.test_files
        # edges: (from, to) -> list of (line, text)
        self.edges = defaultdict(list)
        for mod in sorted(self.modules):
            for to, line, what in self.refs(mod, self.code[mod]):
                if to != mod:
                    self.edges[(mod, to)].append((line, what))
        if not with_tests:
            for mod in sorted(set(self.files) - self.modules) + sorted(self.modules):
                src_code = self.code[mod] if mod in self.test_files else self.tests[mod]
                self.test_refs += sum(1 for to, _, _ in self.refs(mod, src_code) if to != mod)

    def children(self, mod):
        return {m[-1] for m in self.modules | self.test_files if len(m) == len(mod) + 1 and m[: len(mod)] == mod}

    def resolve(self, mod, segs):
        """The module a path names from inside `mod`, or None (another crate, a local name)."""
        segs = [x for x in segs if x != "*"]
        if not segs:
            return None
        if segs[0] == "crate":
            base, rest = (), segs[1:]
        elif segs[0] in ("super", "self"):
            base, rest = mod, segs
            while rest and rest[0] in ("super", "self"):
                if rest[0] == "super":
                    base = base[:-1]
                rest = rest[1:]
        elif segs[0] in self.children(mod):
            base, rest = mod, segs
        else:
            return None
        best = base if base in self.files else None
        cur = base
        for s in rest:
            cur = cur + (s,)
            if cur in self.files:
                best = cur
            else:
                break
        return best

    def refs(self, mod, code):
        """(module, line, text) of every reference in `code` of module `mod`."""
        found = []
        use_spans = []
        for m in USE.finditer(code):
            use_spans.append((m.start(), m.end()))
            line = code.count("\n", 0, m.start()) + 1
            text = re.sub(r"\s+", " ", m.group(0))
            for path in parse_use_tree(m.group(1)):
                if path and path[0] == "":
                    continue
                to = self.resolve(mod, path)
                if to is not None:
                    found.append((to, line, text))

        def in_use(pos):
            return any(a <= pos < b for a, b in use_spans)

        for m in CODE_PATH.finditer(code):
            if in_use(m.start()):
                continue
            segs = [s.strip() for s in m.group(1).split("::")]
            to = self.resolve(mod, segs)
            if to is not None:
                line = code.count("\n", 0, m.start()) + 1
                found.append((to, line, re.sub(r"\s+", "", m.group(1))))
        kids = self.children(mod)
        for m in CHILD_PATH.finditer(code):
            if m.group(1) not in kids or in_use(m.start()):
                continue
            to = self.resolve(mod, [m.group(1), m.group(2)])
            if to is not None:
                line = code.count("\n", 0, m.start()) + 1
                found.append((to, line, m.group(1) + "::" + m.group(2)))
        return found


def tarjan(nodes, succ):
    """Strongly connected components, each a sorted list."""
    index, low, on, stack, comps = {}, {}, set(), [], []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(succ.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            comps.append(sorted(comp))

    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return comps


def common_prefix(mods):
    """The longest module path that every one of `mods` starts with."""
    out = ()
    for parts in zip(*mods):
        if len(set(parts)) != 1:
            break
        out += (parts[0],)
    return out


def top(mod):
    return mod[0] if mod else ROOT


def layer_of(t):
    for i, layer in enumerate(LAYERS):
        if t in layer:
            return i
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--src", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src"))
    ap.add_argument("--layers", action="store_true", help="list imports that go up the layer order")
    ap.add_argument("--edges", action="store_true", help="print every edge and where it comes from")
    ap.add_argument("--with-tests", action="store_true", help="count #[cfg(test)] code too")
    ap.add_argument(
        "--strict",
        action="store_true",
        help="also fail on circles within one module's folder (its mod.rs and the files below it)",
    )
    args = ap.parse_args()

    g = Graph(os.path.normpath(args.src), args.with_tests)
    bad = False

    # file level
    succ = defaultdict(set)
    for a, b in g.edges:
        succ[name(a)].add(name(b))
    nodes = [name(m) for m in g.modules]
    comps = [c for c in tarjan(nodes, succ) if len(c) > 1]
    inside, crossing = [], []
    for c in comps:
        root = common_prefix([tuple(m.split("::")) if m != ROOT else () for m in c])
        # (the crate root's "folder" is all of src/: a circle through it is
        # one between modules)
        (inside if root and name(root) in c else crossing).append((c, root))
    print(
        f"file level: {len(nodes)} modules, {len(g.edges)} edges, {len(comps)} circle(s): "
        f"{len(crossing)} between files, {len(inside)} within a module split over its folder"
    )
    tests_note = "counted" if args.with_tests else f"left out: {len(g.test_files)} test-only file(s), {g.test_refs} reference(s) in test code"
    print(f"  (#[cfg(test)] code {tests_note})")
    for c, root in sorted(crossing, key=lambda x: len(x[0]), reverse=True):
        print(f"  circle of {len(c)} between files: {', '.join(c)}")
    for c, root in sorted(inside, key=lambda x: len(x[0]), reverse=True):
        print(f"  circle of {len(c)} within {name(root)} (its mod.rs and files below it): {', '.join(c)}")
    bad |= bool(crossing) or (args.strict and bool(inside))

    # top-level-module level
    tsucc = defaultdict(set)
    tedges = defaultdict(list)
    for (a, b), refs in g.edges.items():
        if top(a) != top(b):
            tsucc[top(a)].add(top(b))
            tedges[(top(a), top(b))].append((a, b, refs))
    tnodes = sorted({top(m) for m in g.modules})
    tcomps = [c for c in tarjan(tnodes, tsucc) if len(c) > 1]
    print(f"top-level-module level: {len(tnodes)} modules, {len(tedges)} edges, {len(tcomps)} circle(s)")
    for c in sorted(tcomps, key=len, reverse=True):
        print(f"  circle of {len(c)}: {', '.join(c)}")
        for (a, b), via in sorted(tedges.items()):
            if a in c and b in c:
                files = sorted({f"{g.files[x]}" for x, _, _ in via})
                print(f"    {a} -> {b}  ({', '.join(files)})")
    bad |= bool(tcomps)

    if args.layers:
        unlayered = [t for t in tnodes if layer_of(t) is None]
        if unlayered:
            print(f"not in any layer: {', '.join(unlayered)}")
            bad = True
        ups = []
        for (a, b), via in sorted(tedges.items()):
            la, lb = layer_of(a), layer_of(b)
            if la is not None and lb is not None and lb > la:
                for x, y, refs in via:
                    for line, what in sorted(set(refs)):
                        ups.append(f"  {g.files[x]}:{line}: {name(x)} -> {name(y)}: {what}")
        print(f"imports up the layer order: {len(ups)}")
        for u in ups:
            print(u)
        bad |= bool(ups)

    if args.edges:
        print("edges:")
        for (a, b), refs in sorted(g.edges.items()):
            lines = ", ".join(str(line) for line in sorted({line for line, _ in refs}))
            print(f"  {name(a)} -> {name(b)}  ({g.files[a]}: {lines})")

    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
