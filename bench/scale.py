#!/usr/bin/python3
"""The scale benchmark (docs/performance.md, "Scale in n"): ndcontour against GUDHI's manifold
tracing on k-spheres of growing ambient dimension, at matched error, one thread each.

Usage: bench/run.sh --scale [--quick] [--out FILE] [--bindir DIR] [--repeats R] [--workdir DIR]
       (or bench/scale.py with the same options)

The family: the unit sphere of R^n cut by n - 1 - k affine hyperplanes a_i . x = b_i, with
orthonormal normals a_i (the first rows of a random orthogonal matrix: the Q factor of a Gaussian
matrix, signed by diag R) and offsets b_i uniform in [-0.1, 0.1], on the domain [-1.2, 1.2]^n:
a round k-sphere of radius sqrt(1 - |b|^2), one per (n, k, seed), from numpy's default_rng
seeded with 1000 seed + 10 n + k. k = 1 for n = 3..16, k = 2 for n = 3..10 (--quick: n = 3, 4).

1. ndcontour at depths 3..6 with its defaults (`solve --threads 1 --out`): wall time of the whole
   process, certified or the reason, solution cells, and the mesh measured by bench/measure.py
   (two-sided Hausdorff distance to the exact sphere).
2. GUDHI (bench/gudhi_trace section:FILE) at scales from coarse to fine, each once, until its
   error is below a quarter of ndcontour's finest or a run takes over 60 s.
3. Each ndcontour depth is paired with the GUDHI run of the nearest error (log scale, within a
   factor 4), and the pair is timed R times, interleaved (A B A B ...): medians.
4. Writes, between <!-- scale-bench:begin --> and <!-- scale-bench:end --> of FILE
   (docs/performance.md by default), the table, the monotonicity check (time at depth d at most
   the time at d + 1), the cost per solution cell against n with its fit (t = a n^p per k, least
   squares in log-log), and the plot docs/images/scale.png (gnuplot, log scale).
No time is asserted anywhere.
"""

import argparse
import datetime
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
import measure  # noqa: E402
from tables import find_bindir, nearest, sh, spread, timed, write_section  # noqa: E402

BEGIN, END = "<!-- scale-bench:begin -->", "<!-- scale-bench:end -->"
DEPTHS = [3, 4, 5, 6]
FULL = {1: list(range(3, 17)), 2: list(range(3, 11))}
QUICK = {1: [3, 4], 2: [3, 4]}
# GUDHI's scales, coarse to fine (the edge length of its Coxeter triangulation).
SCALES = [0.5, 0.35, 0.25, 0.18, 0.13, 0.09, 0.065, 0.045]
HALF_WIDTH = 1.2
PEER_SECONDS = 60.0


def k_sphere(n, k, seed=0):
    """The normals (rows of M) and offsets b of the k-sphere (n, k, seed)."""
    rng = np.random.default_rng(1000 * seed + 10 * n + k)
    q, r = np.linalg.qr(rng.standard_normal((n, n)))
    q = q * np.sign(np.diag(r))
    m = n - 1 - k
    return q[:, :m].T.copy(), rng.uniform(-0.1, 0.1, m)


def problem_text(name, a, b):
    """The problem file (docs/contracts.md) of the k-sphere with normals a and offsets b."""
    n = a.shape[1]
    k = n - 1 - a.shape[0]
    eqs = [" + ".join(f"x{j}^2" for j in range(n)) + " - 1"]
    for i in range(a.shape[0]):
        terms = " + ".join(f"({float(a[i, j])!r})*x{j}" for j in range(n))
        eqs.append(f"{terms} - ({float(b[i])!r})")
    text = f'name = "{name}"\n'
    text += (f'description = "The unit sphere of R^{n} cut by {a.shape[0]} hyperplanes with '
             f'orthonormal normals: a {k}-sphere (bench/scale.py)."\n')
    text += "variables = [" + ", ".join(f'"x{j}"' for j in range(n)) + "]\n"
    text += "domain = [" + ", ".join(f"[{-HALF_WIDTH}, {HALF_WIDTH}]" for _ in range(n)) + "]\n"
    text += "equations = [\n" + "".join(f'  "{e}",\n' for e in eqs) + "]\n"
    text += f"\n[expect]\ncomponents = 1\neuler_characteristic = {0 if k == 1 else 2}\n"
    return text


class Bench:
    def __init__(self, bindir, workdir, spacing):
        self.ndc = os.path.join(bindir, "ndcontour")
        self.gudhi = os.path.join(bindir, "gudhi_trace")
        self.workdir, self.spacing = workdir, spacing
        self.count = 0

    def setup(self, n, k):
        """Writes the problem and GUDHI's section file; registers the exact distance."""
        name = f"k-sphere-k{k}-n{n}"
        a, b = k_sphere(n, k)
        problem = os.path.join(self.workdir, name + ".toml")
        with open(problem, "w") as f:
            f.write(problem_text(name, a, b))
        section = os.path.join(self.workdir, name + ".section")
        # a . x = b is M x + d = 0 with M = a, d = -b.
        np.savetxt(section, np.column_stack([a, -b]).reshape(-1, n + 1), fmt="%.17g",
                   header=str(n), comments="")
        measure.PROBLEMS[name] = (n, k, measure._sphere_section(a, -b))
        return name, problem, section

    def ndcontour(self, name, problem, depth):
        self.count += 1
        out = os.path.join(self.workdir, f"{name}-d{depth}-{self.count}")
        cmd = [self.ndc, "solve", problem, "--depth", str(depth), "--threads", "1", "--out", out]
        return cmd, out

    def run_ndcontour(self, name, problem, depth):
        cmd, out = self.ndcontour(name, problem, depth)
        seconds, _ = timed(cmd)
        summary = json.load(open(os.path.join(out, "summary.json")))
        topo = summary.get("topology") or {}
        result = {"tool": "ndcontour", "depth": depth, "cmd": cmd, "time": seconds,
                  "cells": summary["cells"]["solution"], "certified": bool(topo.get("certified")),
                  "reason": topo.get("reason") or "", "stages": summary["timing_s"]}
        result.update(measure.measure(name, os.path.join(out, "mesh.ply"), self.spacing))
        shutil.rmtree(out, ignore_errors=True)
        return result

    def run_gudhi(self, name, section, scale):
        self.count += 1
        mesh = os.path.join(self.workdir, f"{name}-gudhi-{self.count}.ply")
        cmd = [self.gudhi, "section:" + section, "--scale", str(scale), "--out", mesh]
        seconds, _ = timed(cmd)
        result = {"tool": "gudhi", "scale": scale, "cmd": cmd, "time": seconds}
        result.update(measure.measure(name, mesh, self.spacing))
        os.remove(mesh)
        return result


def topology_text(r, k):
    t = f"{r['components']} comp, χ {r['euler']}"
    bad = r.get("boundary_edges", 0) + r.get("nonmanifold_edges", 0) + r.get("bad_vertices", 0)
    right = r["components"] == 1 and r["euler"] == (0 if k == 1 else 2) and bad == 0
    return t + ("" if right else " (wrong)")


def fit(points):
    """Least squares of log t = log a + p log n: (a, p)."""
    x = np.log([p[0] for p in points])
    y = np.log([p[1] for p in points])
    p, la = np.polyfit(x, y, 1)
    return math.exp(la), p


def plot(rows, path):
    """Time against n (log scale): ndcontour at each depth's best pairing, GUDHI matched."""
    if not shutil.which("gnuplot"):
        return False
    data = path + ".dat"
    with open(data, "w") as f:
        for k in (1, 2):
            for depth in DEPTHS:
                f.write(f"# k={k} depth={depth}\n")
                for r in rows:
                    if r["k"] == k and r["depth"] == depth:
                        peer = r["peer_time"] if r["peer_time"] is not None else "NaN"
                        f.write(f"{r['n']} {r['time']} {peer}\n")
                f.write("\n\n")
    script = f"""set terminal pngcairo size 1100,480 font ',10'
set output '{path}'
set multiplot layout 1,2
set logscale y
set xlabel 'n'
set ylabel 'wall time (s), one thread'
set key top left
do for [k=1:2] {{
  set title sprintf('%d-spheres in R^n', k)
  plot for [d=0:{len(DEPTHS) - 1}] '{data}' index (k - 1) * {len(DEPTHS)} + d using 1:2 \\
         with linespoints title sprintf('ndcontour depth %d', d + {DEPTHS[0]}), \\
       for [d=0:{len(DEPTHS) - 1}] '{data}' index (k - 1) * {len(DEPTHS)} + d using 1:3 \\
         with points pt 6 lc rgb 'black' title (d == 0 ? 'GUDHI at matched error' : '')
}}
unset multiplot
"""
    ok = subprocess.run(["gnuplot"], input=script, text=True, capture_output=True).returncode == 0
    os.remove(data)
    return ok


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "performance.md"))
    ap.add_argument("--bindir", default=None)
    ap.add_argument("--repeats", type=int, default=None)
    ap.add_argument("--workdir", default=None)
    ap.add_argument("--k", type=int, choices=(1, 2), default=None, help="one family only")
    ap.add_argument("--max-n", type=int, default=None)
    args = ap.parse_args(argv)
    bindir = find_bindir(ROOT, args.bindir, ("ndcontour", "gudhi_trace"), "bench/scale.py")
    family = QUICK if args.quick else FULL
    if args.k:
        family = {args.k: family[args.k]}
    if args.max_n:
        family = {k: [n for n in ns if n <= args.max_n] for k, ns in family.items()}
    depths = [3] if args.quick else DEPTHS
    repeats = args.repeats or (1 if args.quick else 3)
    workdir = args.workdir or tempfile.mkdtemp(prefix="ndc-scale-bench-")
    os.makedirs(workdir, exist_ok=True)
    bench = Bench(bindir, workdir, 0.05)
    load_start = open("/proc/loadavg").read().split()[:3]
    started = datetime.datetime.now(datetime.timezone.utc)
    rows = []
    for k, ns in family.items():
        for n in ns:
            name, problem, section = bench.setup(n, k)
            nd = []
            for d in depths:
                r = bench.run_ndcontour(name, problem, d)
                nd.append(r)
                print(f"[scale] {name} depth {d}: {r['time']:.3g} s, error {r['error']:.3g}, "
                      f"{topology_text(r, k)}, certified {r['certified']}", file=sys.stderr,
                      flush=True)
            finest = min(r["error"] for r in nd)
            peers = []
            for s in SCALES:
                p = bench.run_gudhi(name, section, s)
                peers.append(p)
                print(f"[scale] {name} GUDHI scale {s}: {p['time']:.3g} s, error {p['error']:.3g}, "
                      f"{topology_text(p, k)}", file=sys.stderr, flush=True)
                if p["error"] < finest / 4 or p["time"] > PEER_SECONDS:
                    break
            for r in nd:
                peer = nearest(r, peers)
                ta, tb = [r["time"]], []
                for _ in range(repeats - 1 if repeats > 1 else 0):
                    ta.append(timed(bench.ndcontour(name, problem, r["depth"])[0])[0])
                    if peer:
                        tb.append(timed(peer["cmd"])[0])
                if peer:
                    tb.append(peer["time"])
                rows.append({"k": k, "n": n, "depth": r["depth"], "time": statistics.median(ta),
                             "spread": spread(ta), "cells": r["cells"], "error": r["error"],
                             "topology": topology_text(r, k), "certified": r["certified"],
                             "reason": r["reason"], "stages": r["stages"],
                             "peer_scale": peer["scale"] if peer else None,
                             "peer_time": statistics.median(tb) if peer else None,
                             "peer_error": peer["error"] if peer else None,
                             "peer_topology": topology_text(peer, k) if peer else None})
    load_end = open("/proc/loadavg").read().split()[:3]
    section_text = render(rows, started, load_start, load_end, repeats, args)
    write_section(args.out, BEGIN, END, "Scale in n", section_text)
    print(f"bench/scale.py: wrote {len(rows)} rows to {args.out}", file=sys.stderr)
    return 0


def render(rows, started, load_start, load_end, repeats, args):
    commit = sh("git -C " + ROOT + " rev-parse --short HEAD")
    cpu = sh("grep -m1 'model name' /proc/cpuinfo | cut -d: -f2").strip()
    out = [BEGIN, ""]
    out.append(f"Measured {started:%Y-%m-%d %H:%M} UTC on {os.cpu_count()} cores ({cpu}), commit "
               f"{commit}, load {' '.join(load_start)} before and {' '.join(load_end)} after; "
               f"medians of {repeats} interleaved runs, one thread each, whole processes. "
               "Regenerate with `bench/run.sh --scale` (a few minutes; `--quick` for n = 3, 4).")
    out.append("")
    out.append("| k | n | depth | ndcontour s | certified | solution cells | error | topology "
               "| GUDHI scale | GUDHI s | GUDHI error | GUDHI topology | ndcontour / GUDHI |")
    out.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        cert = "yes" if r["certified"] else "no: " + r["reason"][:90]
        if r["peer_time"] is not None:
            peer = (f"{r['peer_scale']:g} | {r['peer_time']:.3g} | {r['peer_error']:.2g} | "
                    f"{r['peer_topology']} | {r['time'] / r['peer_time']:.2f}")
        else:
            peer = "– | – | – | no run within a factor 4 of the error | –"
        out.append(f"| {r['k']} | {r['n']} | {r['depth']} | {r['time']:.3g} ({r['spread']}) | "
                   f"{cert} | {r['cells']} | {r['error']:.2g} | {r['topology']} | {peer} |")
    out.append("")
    # Monotone in depth: the time at depth d at most the time at d + 1.
    bad = []
    for r in rows:
        finer = [s for s in rows if s["k"] == r["k"] and s["n"] == r["n"] and
                 s["depth"] == r["depth"] + 1]
        if finer and r["time"] > finer[0]["time"]:
            bad.append(f"k = {r['k']}, n = {r['n']}: depth {r['depth']} {r['time']:.3g} s > "
                       f"depth {r['depth'] + 1} {finer[0]['time']:.3g} s")
    out.append("Time monotone in depth: " + ("yes, in every row." if not bad else
                                            "no: " + "; ".join(bad) + "."))
    out.append("")
    # Cost per solution cell (connection + projection + subdivision, without process start).
    out.append("Cost per solution cell at depth 5 (the stages' time, without the process, over "
               "the solution cells), and its fit t = a n^p:")
    out.append("")
    out.append("| k | n | µs per solution cell |")
    out.append("|---|---|---|")
    for k in (1, 2):
        points = []
        for r in rows:
            if r["k"] == k and r["depth"] == 5 and r["cells"] > 0:
                t = r["stages"]["total"] / r["cells"] * 1e6
                points.append((r["n"], t))
                out.append(f"| {k} | {r['n']} | {t:.3g} |")
        if len(points) >= 3:
            a, p = fit(points)
            out.append(f"| {k} | fit | {a:.3g} n^{p:.2f} |")
    out.append("")
    image = os.path.join(ROOT, "docs", "images", "scale.png")
    os.makedirs(os.path.dirname(image), exist_ok=True)
    if not args.quick and plot(rows, image):
        out.append("![Time against n, k = 1 and 2, ndcontour at depths 3 to 6 and GUDHI at "
                   "matched error](images/scale.png)")
        out.append("")
    out.append(END)
    return "\n".join(out)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
