#!/usr/bin/env python3
"""The page of `ndcontour view` in headless Chromium (ctest `viewer`, docs/viewer.md).

Usage: viewer_test.py NDCONTOUR CHROMIUM [--keep DIR]

Solves two spheres in R^3 (two components), the Clifford torus in R^4, a circle in R^5 and a
problem whose zero set misses the domain, writes each result's page and loads it in headless
Chromium (WebGL by SwiftShader; the four at once), reads window.ndcView from the DOM (the page
copies it into #ndc-view-state) and checks:
- that it drew as many triangles or segments and vertices as mesh.ply holds;
- the names: the controls and the axis triad name the coordinates by summary.json's
  `variables`, or u0 .. u{n-1} where it has none (the circle's summary is stripped of them);
- the triad: arrow j is column j of the shown rows of R turned by the 3-D view, and the squared
  lengths add up to 3 (R is orthogonal);
- the first view: R is the rotation that the plane selects and the slider read (30 degrees in
  the plane u0 - u3 beyond R^3, none in R^3);
- the colour: by component by default where there are several, and the page's count of
  components equals summary.json's mesh.components; `#colour=plain` in the address;
- the PNG export (`#png` in the address: the page publishes the canvas as a PNG data URL): a
  PNG of the canvas' size, in which the mesh covers pixels outside the triad's corner;
- an empty result: a message saying that the zero set does not meet the domain;
- k >= 3 (a 3-sphere in R^4 and a 4-sphere in R^5 given as mesh.ply and summary.json, Kuhn's
  triangulation of the cube's boundary, tests/experiments/sphere_mesh.py): the slice by the
  hyperplane through the middle of the last coordinate draws as many triangles (k = 3) or
  segments (k = 4) as the cut computed here, the skeleton (#mode=skeleton) every edge once; the
  first view is the plain coordinates; the page says k and counts the simplices.
With --keep the screenshots (whole page) and the exported PNGs are kept.
"""
import base64
import html
import json
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib
from itertools import combinations

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sphere_mesh import ascii_ply, kuhn_sphere  # noqa: E402 (after its folder is on the path)
EMPTY = """name = "empty"
description = "A sphere of radius 1 centred 3 away from the domain: M does not meet it."
variables = ["p", "q", "r"]
domain = [[-1, 1], [-1, 1], [-1, 1]]
equations = ["(p - 3)^2 + q^2 + r^2 - 1"]
"""
CASES = [  # (name, problem, solve options, the page's address suffix, strip summary.variables)
    ("two-spheres", "two-spheres.toml", ["--depth", "4"], "#png", False),
    ("clifford", "clifford-torus.toml", ["--depth", "3"], "#png", False),
    ("circle-r5", "circle-r5.toml", ["--depth", "3"], "#png&colour=plain", True),
    ("empty", None, ["--depth", "3"], "", False),
    # k >= 3: no solve, a sphere given as files (k, the cube's cells per edge)
    ("s3-slice", (3, 3), [], "#png", False),
    ("s3-skeleton", (3, 3), [], "#png&mode=skeleton", False),
    ("s4-slice", (4, 2), [], "#png", False),
]
WIDTH, HEIGHT, TRIAD = 1000, 700, 170  # the window; the triad's corner (150 px and margins)
FLAGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
         "--enable-unsafe-swiftshader", "--hide-scrollbars", "--no-first-run",
         "--disable-dev-shm-usage", f"--window-size={WIDTH},{HEIGHT}",
         "--virtual-time-budget=8000"]


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


def view_state(dom, name):
    m = re.search(r'<pre id="ndc-view-state">(.*?)</pre>', dom, re.S)
    if not m or not m.group(1).strip():
        fail(name + ": the page published no ndcView (no WebGL?)")
    return json.loads(html.unescape(m.group(1)))


def png_rows(data, name):
    """The size and the pixel rows (RGB or RGBA bytes) of an 8-bit PNG (zlib only, no PIL)."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail(name + ": not a PNG")
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
        fail(f"{name}: PNG of bit depth {depth}, colour type {colour} not read")
    bpp = 3 if colour == 2 else 4
    raw, stride = zlib.decompress(idat), width * bpp
    if len(raw) != height * (stride + 1):
        fail(f"{name}: PNG data of {len(raw)} bytes for {width}x{height}")
    previous, rows = bytearray(stride), []
    for y in range(height):
        kind, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if kind == 2:
            line = bytearray((p + q) & 255 for p, q in zip(line, previous))
        elif kind != 0:
            for x in range(stride):
                a = line[x - bpp] if x >= bpp else 0
                b = previous[x]
                c = previous[x - bpp] if x >= bpp else 0
                if kind == 1:
                    line[x] = (line[x] + a) & 255
                elif kind == 3:
                    line[x] = (line[x] + (a + b) // 2) & 255
                elif kind == 4:
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        previous = line
    return width, height, bpp, rows


def check_png(state, name, keep):
    """The exported PNG: of the canvas' size; the mesh outside the triad's corner."""
    url = state.get("png", "")
    if not url.startswith("data:image/png;base64,"):
        fail(f"{name}: the PNG export gave {url[:40]!r}")
    data = base64.b64decode(url.split(",", 1)[1])
    if keep:
        with open(os.path.join(keep, name + "-export.png"), "wb") as f:
            f.write(data)
    width, height, bpp, rows = png_rows(data, name + " export")
    if [width, height] != state["canvas"]:
        fail(f"{name}: the exported PNG is {width}x{height}, the canvas {state['canvas']}")
    # Pixels unlike the background (#f4f4f2) outside the triad's corner (lower right).
    ratio = width / WIDTH
    corner_x, corner_y = width - int(TRIAD * ratio), height - int(TRIAD * ratio)
    colours, drawn = set(), 0
    for y, row in enumerate(rows):
        end = corner_x * bpp if y >= corner_y else width * bpp
        for x in range(0, end, bpp):
            pixel = row[x:x + 3]
            if abs(pixel[0] - 0xf4) + abs(pixel[1] - 0xf4) + abs(pixel[2] - 0xf2) > 6:
                drawn += 1
                colours.add(pixel)
    if drawn < 500:
        fail(f"{name}: the exported PNG shows the mesh on only {drawn} pixels")
    return width, height, drawn, len(colours)


def check_names(state, summary, name, strip):
    n = summary["n"]
    variables = summary.get("variables")
    want = variables if variables else [f"u{j}" for j in range(n)]
    if strip and variables:
        fail(f"{name}: summary.json still holds variables")
    names = state["names"][-n:]
    labels = [t["label"] for t in state["triad"]][-n:]
    if names != want or labels != want:
        fail(f"{name}: the controls name {names}, the triad {labels}, expected {want}")
    return "summary.json's variables" if variables else "u0.. (no variables)"


def check_triad(state, name):
    """Arrow j = q (R[shown][:, j]), q the 3-D view; squared lengths add up to 3."""
    R, shown = state["rotation"], state["controls"]["shown"]
    qx, qy, qz, qw = state["view"]
    total = 0.0
    for j, arrow in enumerate(state["triad"]):
        v = [R[shown[m]][j] for m in range(3)]
        # v + 2 w (u x v) + 2 u x (u x v), u = (qx, qy, qz), w = qw
        u = [qx, qy, qz]
        c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        cc = [u[1] * c[2] - u[2] * c[1], u[2] * c[0] - u[0] * c[2], u[0] * c[1] - u[1] * c[0]]
        turned = [v[i] + 2 * qw * c[i] + 2 * cc[i] for i in range(3)]
        got = [arrow["x"], arrow["y"], arrow["z"]]
        if max(abs(a - b) for a, b in zip(turned, got)) > 1e-6:
            fail(f"{name}: triad arrow {arrow['label']} is {got}, the projection gives {turned}")
        total += sum(a * a for a in got)
    if abs(total - 3) > 1e-6:
        fail(f"{name}: the triad's squared lengths add up to {total}, not 3")


def check_rotation(state, name):
    """The first view: R = the rotation by the slider's angle in the selected plane."""
    R, controls = state["rotation"], state["controls"]
    d = len(R)
    i, j = controls["plane"]
    angle = controls["angle"]
    if angle != (30 if d > 3 and state["k"] < 3 else 0) or controls["angleText"] != f"{angle}°":
        fail(f"{name}: the slider reads {angle} ({controls['angleText']!r})")
    c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    want = [[float(r == col) for col in range(d)] for r in range(d)]
    if i != j:
        want[i][i], want[i][j], want[j][i], want[j][j] = c, -s, s, c
    if max(abs(R[r][col] - want[r][col]) for r in range(d) for col in range(d)) > 1e-9:
        fail(f"{name}: R = {R}, but the controls (plane {i}-{j}, {angle} degrees) give {want}")
    return f"plane {state['names'][i]}-{state['names'][j]} at {angle} deg"


def write_sphere(out, k, g):
    """A result folder of a k-sphere in R^(k+1) without a solve: mesh.ply as `solve --ascii`
    writes it and the summary fields the page reads."""
    names = ["x", "y", "z", "w", "v"][:k + 1]
    vertices, simplices = kuhn_sphere(k, g)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "mesh.ply"), "w") as f:
        f.write(ascii_ply(vertices, simplices, f"s{k}", names))
    summary = {"schema": "ndcontour.summary/1", "problem": f"s{k}", "n": k + 1, "k": k,
               "variables": names, "mesh": {"vertices": len(vertices), "components": 1},
               "diagnostics": {"singular_points": []}, "topology": {"certified": True}}
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summary, f)


def float32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


def expected_cut(out, k):
    """What the page's slice draws at its first view: the simplices cut by u_{n-1} = t, t the
    middle of the float32 coordinates' range, as the page computes it: for k = 3 one triangle
    per tetrahedron with one vertex apart and two for a quad, for k > 3 a segment per cut
    triangle of each simplex. Also the distinct edges (the skeleton)."""
    lines = open(os.path.join(out, "mesh.ply")).read().splitlines()
    head = lines.index("end_header")
    counts = {w[1]: int(w[2]) for w in (line.split() for line in lines[:head]) if w[0] == "element"}
    rows = lines[head + 1:]
    last = [float32(float(row.split()[-1])) for row in rows[:counts["vertex"]]]
    simplices = [[int(x) for x in row.split()[1:]] for row in rows[counts["vertex"]:]]
    lo, hi = min(last), max(last)
    t = lo + (hi - lo) * 500 / 1000
    pieces = cut = 0
    for s in simplices:
        above = [last[v] - t > 0 for v in s]
        if not 0 < sum(above) < len(s):
            continue
        cut += 1
        if k == 3:
            pieces += 2 if sum(above) == 2 else 1
        else:
            pieces += sum(1 for tri in combinations(range(len(s)), 3)
                          if len({above[m] for m in tri}) == 2)
    edges = {tuple(sorted(e)) for s in simplices for e in combinations(s, 2)}
    return len(simplices), cut, pieces, len(edges)


def check_higher(state, out, name):
    """k >= 3: the page's counts, mode and slice against mesh.ply."""
    k = state["k"]
    simplices, cut, pieces, edges = expected_cut(out, k)
    mode = "skeleton" if "skeleton" in name else "slice"
    want = {"simplices": simplices, "mode": mode, "skeletonEdges": edges,
            "triangles": pieces if mode == "slice" and k == 3 else 0,
            "segments": edges if mode == "skeleton" else pieces if k > 3 else 0}
    got = {key: state.get(key) for key in want}
    if got != want:
        fail(f"{name}: the page drew {got}, mesh.ply gives {want}")
    slice_ = state["slice"]
    if slice_["axis"] != state["names"][-1] or slice_["simplices"] != cut:
        fail(f"{name}: the slice {slice_}, expected {cut} simplices cut along "
             f"{state['names'][-1]}")
    # The colour: u3, or the one before it when the slice is along u3 (k = 3 in R^4).
    colour = min(3, state["n"] - 1)
    colour = state["names"][colour - 1 if colour == state["n"] - 1 else colour]
    if state["colour"] != colour:
        fail(f"{name}: coloured by {state['colour']!r}, not {colour!r}")
    drawn = want["triangles"] or want["segments"]
    return (f"k = {k}, {simplices} simplices, {mode}: {drawn} "
            f"{'triangles' if want['triangles'] else 'segments'} ({cut} simplices cut)")


def check_case(tmp, keep, name, strip, out, chrome):
    try:
        done = chrome.communicate(timeout=180)
    except subprocess.TimeoutExpired:
        fail(name + ": chromium did not finish in 180 s")
    if chrome.returncode != 0:
        fail(f"{name}: chromium status {chrome.returncode}: {done[1].strip()[-500:]}")
    state = view_state(done[0], name)
    summary = json.load(open(os.path.join(out, "summary.json")))
    counts = ply_counts(os.path.join(out, "mesh.ply"))
    higher = summary["k"] >= 3
    want = {"ready": True, "n": summary["n"], "k": summary["k"], "vertices": counts.get("vertex", 0)}
    if not higher:
        want.update(triangles=counts.get("face", 0), segments=counts.get("edge", 0))
    got = {key: state.get(key) for key in want}
    if got != want:
        fail(f"{name}: the page drew {got}, mesh.ply and summary.json hold {want}")
    if not higher and summary["mesh"]["triangles" if summary["k"] == 2 else "edges"] != max(
            want["triangles"], want["segments"]):
        fail(f"{name}: summary.json's mesh disagrees with mesh.ply")
    if state["components"] != summary["mesh"]["components"]:
        fail(f"{name}: the page counts {state['components']} components, summary.json "
             f"{summary['mesh']['components']}")
    named = check_names(state, summary, name, strip)
    check_triad(state, name)
    turned = check_rotation(state, name)
    if keep:
        shutil.copy(os.path.join(tmp, name + ".png"), os.path.join(keep, name + ".png"))
    if name == "empty":
        if not summary["diagnostics"]["empty_zero_set"] or not state["empty"] or \
                "does not meet the domain" not in state["message"]:
            fail(f"{name}: the page's message is {state['message']!r}")
        print(f"viewer: {name}: message {state['message']!r}; names {named}")
        return
    if state["empty"] or state["message"]:
        fail(f"{name}: a message on a page with a mesh: {state['message']!r}")
    if higher:
        drew = check_higher(state, out, name)
        width, height, drawn, colours = check_png(state, name, keep)
        print(f"viewer: {name}: {drew}; names {named}; first view {turned}; PNG "
              f"{width}x{height}, {drawn} pixels of {colours} colours")
        return
    colour = {"two-spheres": "component", "clifford": state["names"][-1],
              "circle-r5": "plain"}[name]
    if state["colour"] != colour:
        fail(f"{name}: coloured by {state['colour']!r}, expected {colour!r}")
    width, height, drawn, colours = check_png(state, name, keep)
    print(f"viewer: {name}: n = {want['n']}, {want['vertices']} vertices, "
          f"{want['triangles'] or want['segments']} {'triangles' if want['triangles'] else 'segments'}"
          f", {state['components']} components drawn; names {named}; first view {turned}; "
          f"colour {state['colour']}; PNG {width}x{height}, {drawn} pixels of {colours} colours")


def main(argv):
    if len(argv) not in (3, 5) or (len(argv) == 5 and argv[3] != "--keep"):
        print("usage: viewer_test.py NDCONTOUR CHROMIUM [--keep DIR]", file=sys.stderr)
        return 2
    ndcontour, browser = argv[1], argv[2]
    keep = argv[4] if len(argv) == 5 else None
    if keep:
        os.makedirs(keep, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="ndc-viewer-") as tmp:
        # Solve and write the pages, then load them all at once (Chromium mostly waits).
        pages = []
        for name, problem, options, suffix, strip in CASES:
            out = os.path.join(tmp, name)
            if isinstance(problem, tuple):
                write_sphere(out, *problem)
            elif problem is None:
                problem = os.path.join(tmp, name + ".toml")
                with open(problem, "w") as f:
                    f.write(EMPTY)
            else:
                problem = os.path.join(ROOT, "experiments", "problems", problem)
            if not isinstance(problem, tuple):
                run([ndcontour, "solve", problem, *options, "--out", out])
            if strip:
                path = os.path.join(out, "summary.json")
                summary = json.load(open(path))
                summary.pop("variables", None)
                with open(path, "w") as f:
                    json.dump(summary, f)
            run([ndcontour, "view", out])
            command = [browser, *FLAGS, "--user-data-dir=" + os.path.join(tmp, "profile-" + name),
                       "--dump-dom", "--screenshot=" + os.path.join(tmp, name + ".png"),
                       "file://" + os.path.join(out, "view.html") + suffix]
            pages.append((name, strip, out, command))
        chromes = [subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                    stdin=subprocess.DEVNULL, text=True, cwd=tmp)
                   for _, _, _, command in pages]
        try:
            for (name, strip, out, command), chrome in zip(pages, chromes):
                check_case(tmp, keep, name, strip, out, chrome)
        finally:
            for chrome in chromes:
                if chrome.poll() is None:
                    chrome.kill()
                    chrome.communicate()
    print(f"viewer: {len(CASES)} passed, 0 failed")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
