#!/usr/bin/python3
"""ndcontour's own tables (docs/performance.md, "ndcontour's own tables"), written by
bench/run.sh after the peer benchmark:

1. Cost per solution cell against n: `ndcontour experiment bench/per-cell.toml --jobs 1`
   (rotated circles in R^3..R^8, rotated 2-spheres in R^3..R^7, depth 5), run 7 times (once
   with --quick), the median time of each stage per solution cell, next to the figures issue
   14 started from; then each manifold's smallest and largest n on one thread, alternated.
2. Thread speedup, when `solve` has `--threads`: the torus at depth 7 and the R^6 torus at
   depth 5 with one thread and with all cores, interleaved (at least 7 pairs), medians, spreads
   and the median of the pairs' ratios; the meshes of the two thread counts are compared byte
   for byte. Each pair runs the one-thread solve pinned to every core (up to 8) and keeps the
   fastest, and one one-thread solve per core all at once: their throughput bounds the
   pair's speedup (the *ceiling* column).
3. Output writing: the torus at depth 8 with `--out` (binary PLY) against `--json` (no files);
   writing is (wall - timing_s.total) of the first minus the same of the second.

Usage: bench/self.py [--quick] [--out FILE] [--bindir DIR] [--repeats R]
Writes between <!-- self-bench:begin --> and <!-- self-bench:end --> of FILE (appended when
the markers are missing). No time is asserted anywhere.
"""

import argparse
import concurrent.futures
import csv
import datetime
import filecmp
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
from tables import sh, spread, timed as run, write_section  # noqa: E402

BEGIN, END = "<!-- self-bench:begin -->", "<!-- self-bench:end -->"

# Issue 14's starting point, microseconds per solution cell at depth 5 (measured before the
# certificate and adaptive refinement of issue 12 existed, so the cells are not the same).
BEFORE = {("rotated-sphere", 3): 11, ("rotated-sphere", 4): 33, ("rotated-sphere", 5): 71,
          ("rotated-sphere", 6): 163, ("rotated-sphere", 7): 405, ("rotated-circle", 3): 23,
          ("rotated-circle", 8): 1562}
STAGES = ("subdivision", "projection", "connection", "analysis")


def core_speeds(ndc, quick):
    """Each core's speed against the fastest, from the torus on one thread pinned to each core
    (the smallest of 3 runs), and the fastest core; None where the process cannot pin.

    A virtual machine's cores need not be equal (one of this project's 2-core machines ran the
    same single-thread solve in 1.06 s on one core and 1.61 s on the other), so the per-cell
    one-thread runs are pinned to the fastest core (the thread rows measure their cores in each
    pair: threads())."""
    if not hasattr(os, "sched_getaffinity") or not shutil.which("taskset"):
        return None
    cores = sorted(os.sched_getaffinity(0))
    if len(cores) < 2:
        return None
    problem = os.path.join(ROOT, "experiments/problems/torus.toml")
    best = {c: float("inf") for c in cores}
    for _ in range(1 if quick else 3):
        for c in cores:
            _, text = run(["taskset", "-c", str(c), ndc, "solve", problem, "--depth",
                           "4" if quick else "6", "--threads", "1", "--json"])
            best[c] = min(best[c], json.loads(text)["timing_s"]["total"])
    fastest = min(best, key=best.get)
    speeds = {c: best[fastest] / t for c, t in best.items()}
    print("[cores] " + ", ".join(f"cpu{c} {v:.2f}" for c, v in speeds.items()), file=sys.stderr,
          flush=True)
    return speeds, fastest


def pinned(cores, cmd):
    """cmd on the fastest core, when the cores were measured."""
    return cmd if cores is None else ["taskset", "-c", str(cores[1])] + cmd


def per_cell(ndc, workdir, quick, runs, cores):
    """The per-cell table from `runs` experiment runs: each problem's median time."""
    cmd = [ndc, "experiment", os.path.join(HERE, "per-cell.toml"), "--jobs", "1", "--out",
           workdir] + (["--quick"] if quick else [])
    print(f"[per-cell] {runs} x " + " ".join(cmd), file=sys.stderr, flush=True)
    # The R^3 runs take a few milliseconds on both cores: one slow start moves a single run's
    # ratio by 1.5x, so every figure is the median of `runs` runs of the whole grid.
    samples = {}
    rows = []
    for _ in range(runs):
        shutil.rmtree(workdir, ignore_errors=True)
        run(cmd)
        rows = list(csv.DictReader(open(os.path.join(workdir, "per-cell", "per-cell.csv"))))
        for r in rows:
            samples.setdefault(r["problem"], []).append(r)
    lines = ["| manifold | n | depth | solution cells | certified cells | mesh vertices | total s | "
             "µs / solution cell (range) | " + " | ".join(f"{s} µs" for s in STAGES) +
             " | µs / mesh vertex | before µs / cell |", "|---" * (10 + len(STAGES)) + "|"]
    first = {}
    growth = []
    for r in rows:
        generator = r["problem"].rsplit("-n", 1)[0]
        n = int(r["n"])
        cells = max(1, int(r["cells.solution"]))
        runs_of = samples[r["problem"]]
        median = lambda key: statistics.median(float(x[key]) for x in runs_of)  # noqa: E731
        total = median("timing_s.total")
        us = 1e6 * total / cells
        lo = 1e6 * min(float(x["timing_s.total"]) for x in runs_of) / cells
        hi = 1e6 * max(float(x["timing_s.total"]) for x in runs_of) / cells
        stages = " | ".join(f"{1e6 * median('timing_s.' + s) / cells:.0f}" for s in STAGES)
        # Per mesh vertex: one per cell M crosses, whatever the bounding keeps besides.
        vertices = max(1, int(r["mesh.vertices"]))
        per_vertex = 1e6 * total / vertices
        before = BEFORE.get((generator, n)) if r["depth"] == "5" else None
        lines.append(f"| {generator} | {n} | {r['depth']} | {cells} | "
                     f"{r.get('topology.certified_cells', '')} | {vertices} | {total:.3g} | "
                     f"{us:.1f} ({lo:.1f}-{hi:.1f}) | {stages} | {per_vertex:.0f} | "
                     f"{before if before else '–'} |")
        first.setdefault(generator, (n, us, per_vertex))
        growth.append((generator, n, us, per_vertex))
    notes = []
    for generator, (n0, us0, pv0) in first.items():
        last = [g for g in growth if g[0] == generator][-1]
        if last[1] > n0:
            target = (last[1] / n0) ** 2
            notes.append(f"{generator}: {last[2] / us0:.1f}x per solution cell and "
                         f"{last[3] / pv0:.1f}x per mesh vertex from R^{n0} to R^{last[1]} "
                         f"(medians of {runs} runs; target at most (n/n0)^2 = {target:.1f}x)")
    notes += one_thread(ndc, os.path.join(workdir, "per-cell", "problems"), rows, runs, cores)
    shown = "experiment bench/per-cell.toml --jobs 1 --out DIR" + (" --quick" if quick else "")
    return shown, lines, notes


def one_thread(ndc, problems, rows, runs, cores):
    """Each manifold's growth from its smallest to its largest n on one thread.

    The grid runs each solve on all cores, where a run of the smallest problem is as much
    thread start-up as work; the cost per cell is a cost of work, so its growth is also measured
    with `--threads 1`, the two ends of each manifold alternated `runs` times on one core."""
    ends = {}
    for r in rows:
        ends.setdefault(r["problem"].rsplit("-n", 1)[0], []).append(r)
    notes = []
    for generator, of in ends.items():
        pair = (of[0], of[-1])
        if pair[0] is pair[1]:
            continue
        samples = {r["problem"]: [] for r in pair}
        for _ in range(runs):
            for r in pair:
                _, text = run(pinned(cores, [ndc, "solve",
                                             os.path.join(problems, r["problem"] + ".toml"),
                                             "--depth", r["depth"], "--threads", "1", "--json"]))
                summary = json.loads(text)
                samples[r["problem"]].append((summary["timing_s"]["total"],
                                              max(1, summary["cells"]["solution"]),
                                              max(1, summary["mesh"]["vertices"])))
        # Per cell and per vertex, each end's median time over its (fixed) counts.
        first, last = (samples[r["problem"]] for r in pair)
        per = lambda s, i: statistics.median(t for t, *_ in s) / s[0][i]  # noqa: E731
        ratios = sorted((b[0] / b[1]) / (a[0] / a[1]) for a, b in zip(first, last))
        n0, n1 = int(pair[0]["n"]), int(pair[1]["n"])
        notes.append(f"{generator}, one thread (`solve FILE --depth {pair[0]['depth']} "
                     f"--threads 1 --json`, R^{n0} and R^{n1} alternated {runs} time(s)"
                     f"{'' if cores is None else f' on cpu{cores[1]}'}): "
                     f"{per(last, 1) / per(first, 1):.1f}x per solution cell "
                     f"({1e6 * per(first, 1):.1f} -> {1e6 * per(last, 1):.1f} µs; the pairs' "
                     f"ratios {ratios[0]:.1f}-{ratios[-1]:.1f}x) and "
                     f"{per(last, 2) / per(first, 2):.1f}x per mesh vertex (target at most "
                     f"{(n1 / n0) ** 2:.1f}x)")
        print(f"[per-cell] {notes[-1]}", file=sys.stderr, flush=True)
    return notes


def together(ndc, file, depth, cores):
    """The throughput of one-thread solves run at once, one pinned to each core, in solves per
    second: what the cores give together when all of them are busy (a virtual machine's cores
    can share a physical core, or its memory bandwidth, with each other)."""
    cmd = [ndc, "solve", os.path.join(ROOT, file), "--depth", str(depth), "--threads", "1",
           "--json"]
    with concurrent.futures.ThreadPoolExecutor(len(cores[0])) as pool:
        walls = list(pool.map(lambda c: run(["taskset", "-c", str(c)] + cmd)[0], cores[0]))
    return sum(1 / w for w in walls)


def threads(ndc, workdir, quick, repeats, cores):
    """Thread speedup rows, or None when solve has no --threads.

    Each pair runs the problem with all cores and, pinned, with one thread on each core (on
    up to 8 cores; beyond, on the fastest core of core_speeds only): the pair's one-thread time
    is its fastest core's. Its *ceiling*, the speedup its cores allow, is the throughput of one
    one-thread solve per core run at once against that time: on a virtual machine the cores
    can slow each other down when all are busy, and their speeds drift within minutes, so the
    ceiling is measured in the same pair as the speedup."""
    help_text = subprocess.run([ndc, "solve", "--help"], capture_output=True, text=True).stdout
    if "--threads" not in help_text:
        return None
    count = os.cpu_count() or 1
    if cores is None:
        singles = [None]
    elif len(cores[0]) <= 8:
        singles = sorted(cores[0])
    else:
        singles = [cores[1]]
    cases = [("experiments/problems/torus.toml", 4 if quick else 7),
             ("experiments/problems/torus-r6.toml", 2 if quick else 5)]
    lines = ["| problem | depth | threads | pairs | median s | spread s | speedup | "
             "pair speedup | meshes identical | ceiling |", "|---|---|---|---|---|---|---|---|---|---|"]
    # At least 7 pairs: a two-thread run on a 2-core machine loses a whole core whenever another
    # process runs, and single runs spread by 15%; the median of the pairs' ratios (1 thread /
    # N threads, each pair run back to back) is robust to the machine's drift.
    pairs = repeats if quick else max(repeats, 7)
    for file, depth in cases:
        times = {1: [], count: []}
        ceilings = []
        outs = {}

        def solve(t, core):
            out = os.path.join(workdir, f"threads-{t}")
            shutil.rmtree(out, ignore_errors=True)
            cmd = [ndc, "solve", os.path.join(ROOT, file), "--depth", str(depth), "--threads",
                   str(t), "--out", out]
            seconds, _ = run(cmd if core is None else ["taskset", "-c", str(core)] + cmd)
            outs[t] = os.path.join(out, "mesh.ply")
            return seconds

        for _ in range(pairs):  # interleaved: the single cores, all cores, ..
            single = [solve(1, core) for core in singles]
            times[1].append(min(single))
            times[count].append(solve(count, None))
            ceilings.append(min(single) * together(ndc, file, depth, cores) if cores else
                            float(count))
        same = filecmp.cmp(outs[1], outs[count], shallow=False)
        m1 = statistics.median(times[1])
        ratios = [a / b for a, b in zip(times[1], times[count])]
        ceiling = statistics.median(ceilings)
        for t in (1, count):
            m = statistics.median(times[t])
            paired = statistics.median(ratios) if t == count else 1.0
            lines.append(f"| {os.path.basename(file)} | {depth} | {t} | {pairs} | {m:.3g} | "
                         f"{spread(times[t])} | {m1 / m:.2f} | {paired:.2f} | "
                         f"{'yes' if same else 'NO'} | "
                         f"{f'{ceiling:.2f}' if t == count else '1.00'} |")
        print(f"[threads] {file} depth {depth}: {m1:.3g} s / "
              f"{statistics.median(times[count]):.3g} s (ceiling {ceiling:.2f})", file=sys.stderr,
              flush=True)
    return lines


def writing(ndc, workdir, quick, repeats):
    """Output-writing rows: --out against --json at the same depth."""
    depth = 5 if quick else 8
    problem = os.path.join(ROOT, "experiments/problems/torus.toml")
    out = os.path.join(workdir, "writing")
    samples = {"out": [], "json": []}
    # At least 5 pairs: a write may wait for the kernel to write back the previous run's 26 MB
    # (0.06 s of extra time one run, 0.16 s the next on the same build), and the median of 3
    # takes that wait whenever two of them hit it.
    for _ in range(repeats if quick else max(repeats, 5)):
        shutil.rmtree(out, ignore_errors=True)
        wall, _ = run([ndc, "solve", problem, "--depth", str(depth), "--out", out])
        total = json.load(open(os.path.join(out, "summary.json")))["timing_s"]["total"]
        samples["out"].append((wall, total))
        wall, text = run([ndc, "solve", problem, "--depth", str(depth), "--json"])
        samples["json"].append((wall, json.loads(text)["timing_s"]["total"]))
    extra = {k: statistics.median(w - t for w, t in v) for k, v in samples.items()}
    spread = {k: (min(w - t for w, t in v), max(w - t for w, t in v)) for k, v in samples.items()}
    wall_out = statistics.median(w for w, _ in samples["out"])
    write = max(0.0, extra["out"] - extra["json"])
    size = os.path.getsize(os.path.join(out, "mesh.ply"))
    return [f"| torus | {depth} | {wall_out:.3g} | {extra['out']:.3f} "
            f"({spread['out'][0]:.3f}–{spread['out'][1]:.3f}) | {extra['json']:.3f} | "
            f"{write:.3f} | {100 * write / wall_out:.1f}% | {size / 1e6:.1f} MB |"]


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "performance.md"))
    ap.add_argument("--bindir", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--repeats", type=int, default=None)
    args, _ = ap.parse_known_args(argv)
    ndc = os.path.join(args.bindir, "ndcontour")
    if not os.access(ndc, os.X_OK):
        sys.exit(f"bench/self.py: {ndc} missing (scripts/build.sh)")
    repeats = args.repeats or (1 if args.quick else 3)
    cell_runs = 1 if args.quick else 7
    workdir = tempfile.mkdtemp(prefix="ndc-self-bench-")
    load_start = open("/proc/loadavg").read().split()[:3]
    started = datetime.datetime.now(datetime.timezone.utc)
    try:
        cores = core_speeds(ndc, args.quick)
        command, cell_lines, notes = per_cell(ndc, os.path.join(workdir, "per-cell"), args.quick,
                                              cell_runs, cores)
        thread_lines = threads(ndc, workdir, args.quick, repeats, cores)
        write_lines = writing(ndc, workdir, args.quick, repeats)
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    load_end = open("/proc/loadavg").read().split()[:3]
    commit = sh(f"git -C {ROOT} rev-parse --short HEAD 2>/dev/null") or "unknown"
    cmdline = "bench/self.py" + "".join(f" {a}" for a in argv)
    lines = [BEGIN, "",
             f"Measured {started:%Y-%m-%d %H:%M} UTC by `{cmdline}` (run by `bench/run.sh`) on "
             f"{os.cpu_count()} cores, commit {commit}; load average {' '.join(load_start)} at "
             f"the start and {' '.join(load_end)} at the end; {repeats} interleaved run(s) per "
             "timed command (the thread rows: their pairs)" + (
                 "." if cores is None else
                 "; the cores' speeds (`solve experiments/problems/torus.toml --depth "
                 f"{4 if args.quick else 6} --threads 1` pinned to each with taskset, the "
                 f"smallest of {1 if args.quick else 3}, against the fastest): " +
                 ", ".join(f"cpu{c} {v:.2f}" for c, v in cores[0].items()) +
                 f"; the per-cell one-thread runs are pinned to cpu{cores[1]}."), "",
             f"**Cost per solution cell against n** (`ndcontour {command}`, run {cell_runs} "
             "time(s); the "
             "median total and stage times per solution cell, the runs' range in brackets; *before*: the figures issue 14 was filed with, before the "
             "certificate and adaptive refinement of issue 12, which the connection column now "
             "includes):", ""] + cell_lines + [""] + [f"- {n}" for n in notes] + [""]
    if thread_lines is None:
        lines += ["**Thread speedup**: this build's `solve` has no `--threads`.", ""]
    else:
        lines += ["**Thread speedup** (`ndcontour solve FILE --depth L --threads T --out DIR`, "
                  "whole processes, one thread and all cores alternated; *speedup*: the ratio "
                  "of the medians, *pair speedup*: the median of the pairs' ratios; the meshes "
                  "of the two thread counts compared byte for byte; one thread: each pair runs "
                  "it pinned to every core and keeps the fastest; *ceiling*: the median over "
                  "the pairs of the speedup the cores allow when all are busy, the throughput "
                  "of one one-thread solve pinned to each core, all at once, against the "
                  "fastest core's one-thread time):", ""] + thread_lines + [""]
    lines += ["**Output writing** (`solve --out DIR` against `solve --json`, which writes no "
              "file; *extra* is wall - timing_s.total, writing the difference of the two; "
              "medians of at least 5 pairs, the --out extras' range in brackets):", "",
              "| problem | depth | wall s | extra with --out s | extra with --json s | "
              "writing s | writing / wall | mesh.ply |", "|---|---|---|---|---|---|---|---|"]
    lines += write_lines + ["", END]
    section = "\n".join(lines)
    write_section(args.out, BEGIN, END, "ndcontour's own tables", section)
    print(f"bench/self.py: tables -> {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
