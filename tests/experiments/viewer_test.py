#!/usr/bin/env python3
"""The page of `ndcontour view` in headless Chromium (ctest `viewer`, docs/viewer.md).

Usage: viewer_test.py NDCONTOUR CHROMIUM [--keep DIR]

Solves a surface in R^3, a surface in R^4 and a curve in R^5, writes each result's page, loads it
in headless Chromium (WebGL by SwiftShader), reads window.ndcView from the DOM (the page copies it
into #ndc-view-state), checks that it drew as many triangles or segments and vertices as mesh.ply
holds, and that a screenshot of the page is not blank. With --keep the screenshots are kept.
"""
import html
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CASES = [  # (name, problem, solve options)
    ("torus", "torus.toml", ["--depth", "4"]),
    ("clifford", "clifford-torus.toml", ["--depth", "3"]),
    ("circle-r5", "circle-r5.toml", ["--depth", "3"]),
]
FLAGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
         "--enable-unsafe-swiftshader", "--hide-scrollbars", "--no-first-run",
         "--disable-dev-shm-usage", "--window-size=1000,700", "--virtual-time-budget=8000"]


def fail(message):
    print("viewer: FAILED: " + message)
    sys.exit(1)


def run(command, timeout=300):
    done = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL)
    if done.returncode != 0:
        fail(" ".join(command) + f": status {done.returncode}: {done.stderr.strip()[-500:]}")
    return done.stdout


def ply_counts(path):
    """The element counts of a PLY header: {'vertex': V, 'face': T} or {'vertex': V, 'edge': E}."""
    counts = {}
    with open(path, "rb") as f:
        for line in f:
            words = line.decode("ascii", "replace").split()
            if words[:1] == ["element"]:
                counts[words[1]] = int(words[2])
            if words[:1] == ["end_header"]:
                return counts
    fail(path + ": no end_header")


def chromium(browser, profile, page, *args):
    return run([browser, *FLAGS, "--user-data-dir=" + profile, *args, "file://" + page],
               timeout=180)


def view_state(dom):
    m = re.search(r'<pre id="ndc-view-state">(.*?)</pre>', dom, re.S)
    if not m or not m.group(1).strip():
        fail("the page published no ndcView (no WebGL?)")
    return json.loads(html.unescape(m.group(1)))


def png_pixels(path):
    """The distinct colours of an 8-bit RGB or RGBA PNG, and its size (zlib only, no PIL)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail(path + ": not a PNG")
    at, idat, header = 8, b"", None
    while at < len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        at += 12 + length
    width, height, depth, colour = header[:4]
    if depth != 8 or colour not in (2, 6):
        fail(f"{path}: PNG of bit depth {depth}, colour type {colour} not read")
    bpp = 3 if colour == 2 else 4
    raw, stride = zlib.decompress(idat), width * bpp
    previous, colours = bytearray(stride), set()
    for y in range(height):
        kind, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b = previous[x]
            c = previous[x - bpp] if x >= bpp else 0
            if kind == 1:
                line[x] = (line[x] + a) & 255
            elif kind == 2:
                line[x] = (line[x] + b) & 255
            elif kind == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        colours.update(bytes(line[x:x + 3]) for x in range(0, stride, bpp * 2))
        previous = line
    return colours, width, height


def check_case(ndcontour, browser, tmp, keep, name, problem, options):
    out = os.path.join(tmp, name)
    run([ndcontour, "solve", os.path.join(ROOT, "experiments", "problems", problem), *options,
         "--out", out])
    run([ndcontour, "view", out])
    page = os.path.join(out, "view.html")
    summary = json.load(open(os.path.join(out, "summary.json")))
    counts = ply_counts(os.path.join(out, "mesh.ply"))
    profile = os.path.join(tmp, "profile-" + name)
    state = view_state(chromium(browser, profile, page, "--dump-dom"))
    want = {"ready": True, "n": summary["n"], "vertices": counts.get("vertex", 0),
            "triangles": counts.get("face", 0), "segments": counts.get("edge", 0)}
    got = {key: state.get(key) for key in want}
    if got != want:
        fail(f"{name}: the page drew {got}, mesh.ply and summary.json hold {want}")
    if summary["mesh"]["triangles" if summary["k"] == 2 else "edges"] != max(
            want["triangles"], want["segments"]):
        fail(f"{name}: summary.json's mesh disagrees with mesh.ply")
    shot = os.path.join(tmp, name + ".png")
    chromium(browser, profile, page, "--screenshot=" + shot)
    colours, width, height = png_pixels(shot)
    if len(colours) < 50:
        fail(f"{name}: the screenshot ({width}x{height}) has only {len(colours)} colours")
    if keep:
        shutil.copy(shot, os.path.join(keep, name + ".png"))
    print(f"viewer: {name}: n = {want['n']}, {want['vertices']} vertices, "
          f"{want['triangles'] or want['segments']} {'triangles' if want['triangles'] else 'segments'}"
          f" drawn; screenshot {width}x{height}, {len(colours)} colours")


def main(argv):
    if len(argv) not in (3, 5) or (len(argv) == 5 and argv[3] != "--keep"):
        print("usage: viewer_test.py NDCONTOUR CHROMIUM [--keep DIR]", file=sys.stderr)
        return 2
    keep = argv[4] if len(argv) == 5 else None
    if keep:
        os.makedirs(keep, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="ndc-viewer-") as tmp:
        for case in CASES:
            check_case(argv[1], argv[2], tmp, keep, *case)
    print(f"viewer: {len(CASES)} passed, 0 failed")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
