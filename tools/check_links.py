#!/usr/bin/env python3
"""Checks the relative links of raylab's Markdown documentation.

Usage (from anywhere):  python3 tools/check_links.py [FILE.md ...]

Without arguments it checks README.md, ARCHITECTURE.md and docs/*.md. Every
relative link and image (inline `[text](target)`, reference definitions
`[id]: target`, HTML `href=`/`src=`) must point to a file or folder that
exists, and every `#anchor` to a heading of the target Markdown file (GitHub's
heading slugs, with `-1`, `-2` for repeated headings) or an explicit
`<a id=...>`/`<a name=...>`. Links inside code blocks and code spans are not
links. External links (`http:`, `https:`, `mailto:`) are not checked. A link
that leaves the repository (`../shared/...`) is checked when the folder it
names beside the repository exists, and only reported otherwise.

Prints one line per broken link and exits 1 if there is any; stdlib only.
"""

import re
import sys
import unicodedata
from pathlib import Path
from urllib.parse import unquote

ROOT = Path(__file__).resolve().parent.parent

INLINE = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*<?([^)\s>]*)>?(?:\s+[\"'(][^)]*)?\)")
REFERENCE = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+.*)?$")
HTML = re.compile(r"""\b(?:href|src)\s*=\s*["']([^"']*)["']""", re.IGNORECASE)
HTML_ANCHOR = re.compile(r"""<a\s+[^>]*\b(?:id|name)\s*=\s*["']([^"']+)["']""", re.IGNORECASE)
HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
FENCE = re.compile(r"^\s{0,3}(```+|~~~+)")
CODE_SPAN = re.compile(r"(`+)(.+?)\1")


def prose_lines(text):
    """(line number, line) of the lines outside fenced code blocks."""
    fence = None
    for number, line in enumerate(text.split("\n"), 1):
        m = FENCE.match(line)
        if m:
            mark = m.group(1)
            if fence is None:
                fence = mark[0] * len(mark)
                continue
            if mark.startswith(fence):
                fence = None
                continue
        if fence is None:
            yield number, line


def slug(heading):
    """GitHub's anchor for a heading's text."""
    text = CODE_SPAN.sub(lambda m: m.group(2), heading)
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # links: their text
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML tags
    text = text.strip().lower()
    kept = []
    for c in text:
        cat = unicodedata.category(c)
        if c in " -" or cat[0] in "LNM" or cat == "Pc":
            kept.append(c)
    return "".join(kept).replace(" ", "-")


_anchors = {}


def anchors(path):
    """The anchors a Markdown file defines."""
    if path not in _anchors:
        found, seen = set(), {}
        for _, line in prose_lines(path.read_text(encoding="utf-8")):
            m = HEADING.match(line)
            if m:
                base = slug(m.group(2))
                n = seen.get(base, 0)
                seen[base] = n + 1
                found.add(base if n == 0 else f"{base}-{n}")
            for a in HTML_ANCHOR.findall(line):
                found.add(a)
        _anchors[path] = found
    return _anchors[path]


def targets(text):
    """(line number, target) of every link in the prose of `text`."""
    for number, line in prose_lines(text):
        bare = CODE_SPAN.sub("", line)
        for m in INLINE.finditer(bare):
            yield number, m.group(1)
        m = REFERENCE.match(bare)
        if m:
            yield number, m.group(1)
        for t in HTML.findall(bare):
            yield number, t


def check(md):
    """The broken links of one file, and the ones that could not be checked."""
    broken, unchecked = [], []
    rel = md.relative_to(ROOT) if md.is_relative_to(ROOT) else md
    for number, target in targets(md.read_text(encoding="utf-8")):
        where = f"{rel}:{number}: {target}"
        if not target or re.match(r"^[a-z][a-z0-9+.-]*:|^//", target, re.IGNORECASE):
            if not target:
                broken.append(f"{where}(empty link)")
            continue
        path_part, _, fragment = target.partition("#")
        dest = (md.parent / unquote(path_part)).resolve() if path_part else md
        if not dest.exists():
            outside = not dest.is_relative_to(ROOT)
            if outside:
                # The first folder beside the repository that the link names.
                beside = ROOT.parent / dest.relative_to(ROOT.parent).parts[0] \
                    if dest.is_relative_to(ROOT.parent) else None
                if beside is None or not beside.exists():
                    unchecked.append(f"{where} (outside the repository; {beside or dest} is absent)")
                    continue
            broken.append(f"{where}: no such file")
            continue
        if fragment:
            if dest.suffix.lower() != ".md" or dest.is_dir():
                broken.append(f"{where}: an anchor into a file that is not Markdown")
            elif unquote(fragment) not in anchors(dest):
                broken.append(f"{where}: no heading with that anchor in {dest.name}")
    return broken, unchecked


def main(argv):
    if argv:
        files = [Path(a).resolve() for a in argv]
    else:
        files = [ROOT / "README.md", ROOT / "ARCHITECTURE.md"]
        files += sorted((ROOT / "docs").glob("*.md"))
        files = [f for f in files if f.exists()]
    broken, unchecked, links = [], [], 0
    for md in files:
        links += sum(1 for _ in targets(md.read_text(encoding="utf-8")))
        b, u = check(md)
        broken += b
        unchecked += u
    for line in unchecked:
        print(f"not checked: {line}")
    for line in broken:
        print(f"broken: {line}")
    print(f"{len(files)} files, {links} links, {len(broken)} broken, {len(unchecked)} not checked")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
