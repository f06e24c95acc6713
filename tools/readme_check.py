#!/usr/bin/env python3
"""Runs the README's tour and its Python example as written, from the project folder.

usage: readme_check.py --bin RAYLAB [--python PY] [--readme FILE] [--timeout S] [--list]

A user who has just cloned the repository copies the README's commands; they
must work from the clone alone (nothing beside it). This tool takes the fenced
`sh` block of the README's "A ten-line tour" section and the `python` block of
"Use it from Python", and runs each in the project folder (the folder holding
the README) exactly as written:

* a tour line starting with `raylab` runs with RAYLAB (the binary to test) as
  `raylab`: a temporary folder holding a `raylab` link to it goes first on
  PATH, so that tools the tour calls (tools/farm/slurm.sh) find it too;
* `raylab view` opens its window: the tool starts its own Xvfb display, waits
  for the window, lets it draw for two seconds, presses Esc and wants exit
  status 0 (Xvfb and xdotool must be installed, as for `cargo test`);
* `tools/farm/slurm.sh` needs a Slurm cluster: run the tool under
  `.ci/slurm-test.sh --then ...`, which starts one on localhost (as `.ci/run`
  does); without one (`sinfo` fails) the line fails and says so;
* the Python block runs with PY (an interpreter with the raylab package
  installed); without --python it fails and says so.

Every command must exit 0 within --timeout seconds (default 600), and every
file a command names after `-o` must exist afterwards and not be empty. The
files the commands write (cornell.png, helmet.png, box.farm/, ...) are
removed at the end: whatever is in the project folder afterwards that was not
there before (`git status --ignored`), so run it on a clean checkout.

Prints one line per command with its time; exits 1 if any command failed (its
output is shown), 0 otherwise.
"""

import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def section_blocks(text, heading):
    """The fenced code blocks of the Markdown section `## heading`: (language, text) each."""
    m = re.search(r"^## " + re.escape(heading) + r"\s*$", text, re.M)
    if not m:
        raise SystemExit(f"readme_check: the README has no section '## {heading}'")
    end = re.search(r"^## ", text[m.end():], re.M)
    body = text[m.end(): m.end() + end.start()] if end else text[m.end():]
    return re.findall(r"^```(\w*)\n(.*?)^```", body, re.M | re.S)


def tour_commands(text):
    """The tour's command lines, comments after `  #` dropped."""
    blocks = [b for lang, b in section_blocks(text, "A ten-line tour") if lang in ("sh", "bash", "")]
    if len(blocks) != 1:
        raise SystemExit(f"readme_check: expected one sh block in the tour, found {len(blocks)}")
    out = []
    for line in blocks[0].splitlines():
        line = re.sub(r"\s+#\s.*$", "", line).strip()
        if line and not line.startswith("#"):
            out.append(line)
    return out


def python_example(text):
    blocks = [b for lang, b in section_blocks(text, "Use it from Python") if lang == "python"]
    if len(blocks) != 1:
        raise SystemExit(f"readme_check: expected one python block in 'Use it from Python', found {len(blocks)}")
    return blocks[0]


def outputs(command):
    """The files a command names after -o (a `%` frame pattern is not checked)."""
    words = shlex.split(command)
    return [words[i + 1] for i, w in enumerate(words[:-1]) if w == "-o" and "%" not in words[i + 1]]


def project_state():
    """Paths git sees in the project folder besides tracked, unchanged files."""
    r = subprocess.run(["git", "status", "--porcelain", "--ignored", "--untracked-files=all",
                        "--", ".", ":(exclude)target"],
                       cwd=ROOT, capture_output=True, text=True, check=True)
    return {line[3:] for line in r.stdout.splitlines() if line[:2] in ("??", "!!")}


def free_display():
    for n in range(190, 290):
        if not os.path.exists(f"/tmp/.X{n}-lock") and not os.path.exists(f"/tmp/.X11-unix/X{n}"):
            return f":{n}"
    raise RuntimeError("no free X display number between :190 and :289")


def run_view(command, env, timeout):
    """`raylab view` under a private Xvfb: its window appears, draws, and Esc ends it with 0."""
    for tool in ("Xvfb", "xdotool"):
        if not shutil.which(tool):
            return False, f"{tool} is not installed (apt-get install xvfb xdotool)"
    display = free_display()
    # -noreset: by default Xvfb resets when its last client leaves, and the
    # readiness probe below is a client: a viewer connecting during that reset
    # found no server (1 run in 3 or 4 failed so, before).
    xvfb = subprocess.Popen(["Xvfb", display, "-screen", "0", "1280x1024x24", "-nolisten", "tcp",
                             "-noreset"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    env = dict(env, DISPLAY=display)
    viewer = None
    try:
        for _ in range(100):
            if subprocess.run(["xdotool", "getmouselocation"], env=env,
                              capture_output=True).returncode == 0:
                break
            time.sleep(0.1)
        else:
            return False, f"Xvfb did not start on {display}"
        viewer = subprocess.Popen(command, shell=True, cwd=ROOT, env=env,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        deadline = time.time() + timeout
        window = ""
        while time.time() < deadline and viewer.poll() is None and not window:
            r = subprocess.run(["xdotool", "search", "--onlyvisible", "--name", "raylab"],
                               env=env, capture_output=True, text=True)
            window = r.stdout.split()[0] if r.returncode == 0 and r.stdout.split() else ""
            time.sleep(0.2)
        if not window:
            out = viewer.communicate(timeout=5)[0] if viewer.poll() is not None else ""
            return False, f"no viewer window appeared (exit {viewer.poll()}): {out.strip()}"
        time.sleep(2)
        if viewer.poll() is not None:
            return False, f"the viewer ended by itself (exit {viewer.returncode}): {viewer.communicate()[0].strip()}"
        subprocess.run(["xdotool", "windowfocus", "--sync", window], env=env, capture_output=True)
        subprocess.run(["xdotool", "key", "--window", window, "Escape"], env=env, capture_output=True)
        try:
            out = viewer.communicate(timeout=20)[0]
        except subprocess.TimeoutExpired:
            return False, "Esc did not close the viewer within 20 s"
        if viewer.returncode != 0:
            return False, f"exit status {viewer.returncode}: {out.strip()}"
        return True, out
    finally:
        if viewer is not None and viewer.poll() is None:
            viewer.kill()
            viewer.wait()
        xvfb.terminate()  # SIGTERM first: Xvfb then removes its lock file
        try:
            xvfb.wait(timeout=5)
        except subprocess.TimeoutExpired:
            xvfb.kill()
            xvfb.wait()


def slurm_up(env):
    """Whether a Slurm cluster answers (`sinfo`)."""
    return shutil.which("sinfo") is not None and subprocess.run(
        ["sinfo"], env=env, capture_output=True).returncode == 0


def run_command(command, env, timeout):
    try:
        r = subprocess.run(command, shell=True, cwd=ROOT, env=env, timeout=timeout,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    except subprocess.TimeoutExpired:
        return False, f"did not end within {timeout} s"
    if r.returncode != 0:
        return False, f"exit status {r.returncode}:\n{r.stdout.strip()}"
    missing = [o for o in outputs(command) if not os.path.isfile(os.path.join(ROOT, o))
               or os.path.getsize(os.path.join(ROOT, o)) == 0]
    if missing:
        return False, f"wrote no {', '.join(missing)}:\n{r.stdout.strip()}"
    return True, r.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", required=True, help="the raylab binary to run as `raylab`")
    ap.add_argument("--python", help="a Python with the raylab package installed, for the Python example")
    ap.add_argument("--readme", default=os.path.join(ROOT, "README.md"))
    ap.add_argument("--timeout", type=float, default=600, help="seconds each command may take")
    ap.add_argument("--list", action="store_true", help="print the commands and exit")
    args = ap.parse_args()

    text = open(args.readme, encoding="utf-8").read()
    tour = tour_commands(text)
    example = python_example(text)
    if args.list:
        for c in tour:
            print(c)
        print("python:\n" + example)
        return 0

    binary = os.path.abspath(args.bin)
    if not os.access(binary, os.X_OK):
        raise SystemExit(f"readme_check: {args.bin}: not an executable")
    before = project_state()
    bindir = tempfile.mkdtemp(prefix="readme-check-")
    os.symlink(binary, os.path.join(bindir, "raylab"))
    env = dict(os.environ, PATH=bindir + os.pathsep + os.environ.get("PATH", ""))
    env.pop("DISPLAY", None)  # renders need no display; the viewer gets its own
    failed = 0
    try:
        jobs = [("sh", c) for c in tour] + [("python", example)]
        for kind, command in jobs:
            t0 = time.time()
            if kind == "python":
                label = "the Python example"
                if not args.python:
                    ok, out = False, "needs --python (an interpreter with `pip install ./python` done)"
                else:
                    ok, out = run_command(shlex.quote(args.python) + " -c " + shlex.quote(command), env,
                                          args.timeout)
                    written = re.findall(r'raylab\.save\([^,]+,\s*"([^"]+)"\)', command)
                    if ok and not all(os.path.isfile(os.path.join(ROOT, w)) for w in written):
                        ok, out = False, f"wrote no {', '.join(written)}"
            else:
                label = command
                if command.split()[:2] == ["raylab", "view"]:
                    ok, out = run_view(command, env, min(args.timeout, 60))
                elif command.startswith("tools/farm/slurm.sh") and not slurm_up(env):
                    ok, out = False, ("needs a Slurm cluster: run this tool under "
                                      "`bash .ci/slurm-test.sh --then ...`, which starts one")
                else:
                    ok, out = run_command(command, env, args.timeout)
            print(f"{'ok  ' if ok else 'FAIL'} {time.time() - t0:6.1f} s  {label.splitlines()[0]}"
                  + (" ..." if "\n" in label.strip() else ""), flush=True)
            if not ok:
                failed += 1
                print("     " + out.strip().replace("\n", "\n     "), flush=True)
    finally:
        shutil.rmtree(bindir, ignore_errors=True)
        new = project_state() - before
        for rel in new:
            path = os.path.join(ROOT, rel)
            if os.path.isdir(path) and not os.path.islink(path):
                shutil.rmtree(path, ignore_errors=True)
            elif os.path.lexists(path):
                os.remove(path)
        # the folders the removed files leave empty (git lists files, not folders)
        folders = {os.path.dirname(r.rstrip("/")) for r in new}
        for rel in sorted((f for f in folders if f), key=len, reverse=True):
            path = os.path.join(ROOT, rel)
            while rel and os.path.isdir(path) and not os.listdir(path):
                os.rmdir(path)
                rel = os.path.dirname(rel)
                path = os.path.join(ROOT, rel)
    print(f"readme_check: {len(tour) + 1 - failed} of {len(tour) + 1} commands ran as written"
          + (f", {failed} failed" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
