#!/usr/bin/env python3
"""How soon the viewer shows a denoised frame after the camera stops.

Usage (from the project folder; the raylab binary must be built, OIDN findable as
`raylab view --denoise` finds it, Xvfb and xdotool installed):

    python3 tools/viewer_denoise_latency.py [--rounds 5] [--raylab PATH]
                                            [SCENE] [-- VIEW_ARGS...]

SCENE defaults to scenes/helmet-hdri.toml (the DamagedHelmet under the Venice HDRI,
640×480 from the file). The tool starts Xvfb on a free display, opens `raylab view
SCENE --denoise VIEW_ARGS`, lets it settle, then per round turns the camera with one
key press (Left and Right in turn: the camera moves, then rests) and times, from the
press, (1) when the window's title stops saying `denoised at` (the viewer took the
move) and (2) when it says `denoised at N spp in M ms` again (a denoised frame of the
new view is on screen). The title is polled every 10 ms with xdotool, so the times
are good to about 20 ms. It prints each round and the median and worst of (2).

The issue's target: within 1.5 s of the camera stopping on two cores (the press is
the camera's last move, so the time from the press is an upper bound).
"""

import argparse
import os
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def xdotool(display, *args):
    out = subprocess.run(["xdotool", *args], env=dict(os.environ, DISPLAY=display),
                         capture_output=True, text=True, timeout=20)
    if out.returncode != 0:
        raise RuntimeError(f"xdotool {' '.join(args)}: {out.stderr.strip()}")
    return out.stdout.strip()


def start_xvfb():
    for n in range(120, 200):
        if os.path.exists(f"/tmp/.X{n}-lock"):
            continue
        proc = subprocess.Popen(["Xvfb", f":{n}", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for _ in range(100):
            if os.path.exists(f"/tmp/.X11-unix/X{n}"):
                return proc, f":{n}"
            if proc.poll() is not None:
                break
            time.sleep(0.05)
        proc.kill()
    sys.exit("error: could not start Xvfb on displays :120 to :199")


def wait_title(display, window, pred, timeout):
    start = time.monotonic()
    while time.monotonic() - start < timeout:
        title = xdotool(display, "getwindowname", window)
        if pred(title):
            return time.monotonic(), title
        time.sleep(0.01)
    return None, xdotool(display, "getwindowname", window)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene", nargs="?", default=os.path.join(ROOT, "scenes", "helmet-hdri.toml"))
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--raylab", default=os.path.join(ROOT, "target", "release", "raylab"))
    ap.add_argument("view_args", nargs="*")
    args = ap.parse_args()
    for tool in ("Xvfb", "xdotool"):
        if subprocess.run(["sh", "-c", f"command -v {tool}"], capture_output=True).returncode:
            sys.exit(f"error: {tool} is missing (apt-get install xvfb xdotool)")
    if not os.path.exists(args.raylab):
        sys.exit(f"error: no raylab binary at {args.raylab} (cargo build --release)")
    xvfb, display = start_xvfb()
    viewer = None
    try:
        viewer = subprocess.Popen([args.raylab, "view", args.scene, "--denoise", *args.view_args],
                                  env=dict(os.environ, DISPLAY=display), stdin=subprocess.DEVNULL,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        window = xdotool(display, "search", "--sync", "--name", "^raylab").splitlines()[0]
        xdotool(display, "windowfocus", "--sync", window)
        t, title = wait_title(display, window, lambda s: "denoised at" in s, 60)
        if t is None:
            sys.exit(f"error: no denoised frame within 60 s: {title}")
        print(f"# {title}")
        times = []
        for r in range(args.rounds):
            time.sleep(1.5)
            key = "Left" if r % 2 == 0 else "Right"
            pressed = time.monotonic()
            xdotool(display, "key", "--window", window, key)
            taken, _ = wait_title(display, window, lambda s: "denoised at" not in s, 10)
            shown, title = wait_title(display, window, lambda s: "denoised at" in s, 30)
            if taken is None or shown is None:
                sys.exit(f"error: round {r + 1}: no new denoised frame: {title}")
            times.append(shown - pressed)
            print(f"round {r + 1}: move taken after {taken - pressed:.2f} s, denoised frame after "
                  f"{shown - pressed:.2f} s  [{title}]")
        print(f"median {statistics.median(times):.2f} s, worst {max(times):.2f} s "
              f"from the key press to the denoised frame ({len(times)} rounds)")
    finally:
        if viewer is not None:
            viewer.kill()
            viewer.wait()
        xvfb.kill()
        xvfb.wait()


if __name__ == "__main__":
    main()
