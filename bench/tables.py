"""What bench/run.py and bench/self.py share: a shell helper, timed whole runs, spreads, and
rewriting one marked section of a Markdown file."""

import os
import subprocess
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
