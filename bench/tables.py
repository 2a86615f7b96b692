"""What bench/run.py and bench/self.py share: a shell helper, timed whole runs, spreads, and
rewriting one marked section of a Markdown file."""

import math
import os
import subprocess
import sys
import time


def sh(cmd):
    """A shell command's standard output, stripped ('' on failure)."""
    return subprocess.run(cmd, shell=True, capture_output=True, text=True).stdout.strip()


def timed(cmd):
    """Runs a command; returns (wall seconds, stdout); raises with its stderr on failure."""
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}): {proc.stderr[-2000:]}")
    return seconds, proc.stdout


def spread(times):
    """min–max of several times, or – for one."""
    return f"{min(times):.3g}–{max(times):.3g}" if len(times) > 1 else "–"


def write_section(path, begin, end, heading, section):
    """Replaces the text from marker `begin` to marker `end` of the file with `section` (which
    holds both markers); appends it under `## heading` when the markers are missing."""
    text = open(path).read() if os.path.exists(path) else ""
    if begin in text and end in text:
        text = text[:text.index(begin)] + section + text[text.index(end) + len(end):]
    else:
        text = text.rstrip("\n") + ("\n\n" if text else "") + f"## {heading}\n\n" + section + "\n"
    with open(path, "w") as f:
        f.write(text)


def find_bindir(root, given, programs, tool):
    """The folder with the bench/ programs: `given`, or build/bin or build-bench/bin under root
    (the first with gudhi_trace); exits with a message when one of `programs` is missing."""
    bindir = given
    if bindir is None:
        for b in ("build/bin", "build-bench/bin"):
            if os.path.exists(os.path.join(root, b, "gudhi_trace")):
                bindir = os.path.join(root, b)
                break
    if bindir is None:
        sys.exit(f"{tool}: no build with bench/ programs (scripts/setup.sh --bench, then "
                 "build; or pass --bindir)")
    for p in programs:
        if not os.access(os.path.join(bindir, p), os.X_OK):
            sys.exit(f"{tool}: {bindir}/{p} missing")
    return bindir


def nearest(run, peers, limit=4.0):
    """The run of `peers` whose error is nearest to run's (log scale), if within a factor
    `limit`; runs with no finite error are skipped."""
    best = None
    for p in peers:
        if not (0 < p["error"] < math.inf and 0 < run["error"] < math.inf):
            continue
        gap = abs(math.log(p["error"] / run["error"]))
        if best is None or gap < best[0]:
            best = (gap, p)
    return best[1] if best and best[0] < math.log(limit) else None
