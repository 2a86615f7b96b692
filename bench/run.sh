#!/usr/bin/env bash
# The benchmark tables of docs/performance.md, in one command: the peer benchmark, ndcontour
# against CGAL and GUDHI at matched error (bench/run.py), then ndcontour's own tables: cost per
# solution cell against n, thread speedup and output writing (bench/self.py). With --scale, only
# the scale benchmark: k-spheres in R^3..R^16 against GUDHI (bench/scale.py).
# Usage: bench/run.sh [--quick] [--out FILE] [--bindir DIR] [--repeats R] [--peers-only | --self-only | --scale]
# The peer benchmark needs the bench/ programs (scripts/setup.sh --bench, then build) and python3
# with numpy; --self-only writes only the own tables, which need neither.
set -euo pipefail
python=python3
if [[ -x /usr/bin/python3 ]]; then
  python=/usr/bin/python3  # Debian's, with python3-numpy
fi
here=$(dirname "$0")
args=()
peers=1 own=1 scale=0
for a in "$@"; do
  case "$a" in
    --peers-only) own=0 ;;
    --self-only) peers=0 ;;
    --scale) scale=1 peers=0 own=0 ;;
    *) args+=("$a") ;;
  esac
done
if [[ $peers -eq 1 ]]; then "$python" "$here/run.py" "${args[@]}"; fi
if [[ $own -eq 1 ]]; then "$python" "$here/self.py" "${args[@]}"; fi
if [[ $scale -eq 1 ]]; then "$python" "$here/scale.py" "${args[@]}"; fi
