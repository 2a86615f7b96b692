#!/usr/bin/env bash
# The benchmark tables of docs/performance.md, in one command: ndcontour's own tables, cost per
# solution cell against n, thread speedup and output writing (bench/self.py), then the peer
# benchmark, ndcontour against CGAL and GUDHI at matched error (bench/run.py).
# Usage: bench/run.sh [--quick] [--out FILE] [--bindir DIR] [--repeats R] [--peers-only | --self-only]
# The peer benchmark needs the bench/ programs (scripts/setup.sh --bench, then build) and python3
# with numpy; --self-only writes only the own tables, which need neither.
set -euo pipefail
python=python3
if [[ -x /usr/bin/python3 ]]; then
  python=/usr/bin/python3  # Debian's, with python3-numpy
fi
here=$(dirname "$0")
args=()
peers=1 own=1
for a in "$@"; do
  case "$a" in
    --peers-only) own=0 ;;
    --self-only) peers=0 ;;
    *) args+=("$a") ;;
  esac
done
# The own tables first: right after the peer runs (which allocate gigabytes) the two-thread
# runs of a 2-core machine were 1.55x and 1.75x the one-thread runs, and 1.83x minutes later on
# the same build: something else takes a core then, which a one-thread run does not pay
# (docs/performance.md, "Threads").
if [[ $own -eq 1 ]]; then "$python" "$here/self.py" "${args[@]}"; fi
if [[ $peers -eq 1 ]]; then "$python" "$here/run.py" "${args[@]}"; fi
