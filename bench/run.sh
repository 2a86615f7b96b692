#!/usr/bin/env bash
# The peer benchmark: ndcontour against CGAL and GUDHI at matched error (bench/run.py,
# docs/performance.md). Usage: bench/run.sh [--quick] [--out FILE] [--bindir DIR] [--repeats R]
# Needs the bench/ programs (scripts/setup.sh --bench, then build) and python3 with numpy.
set -euo pipefail
python=python3
if [[ -x /usr/bin/python3 ]]; then
  python=/usr/bin/python3  # Debian's, with python3-numpy
fi
exec "$python" "$(dirname "$0")/run.py" "$@"
