#!/usr/bin/env bash
# Stage timings of the pipeline on the benchmark problems of docs/performance.md (Release
# build). Usage: experiments/bench.sh [REPEAT]   (prints Markdown tables)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin/ndcontour
p=experiments/problems
repeat=${1:-5}
for connection in paper crossing; do
  for bounding in bernstein linearized; do
    echo
    echo "connection $connection, bounding $bounding, binary subdivision, double, depth 6, jitter 1:"
    echo
    "$bin" bench "$p/torus.toml" "$p/clifford-torus.toml" --depth 6 --bounding "$bounding" \
      --connection "$connection" --jitter 1 --repeat "$repeat"
    # The R^8 circle with bernstein bounding keeps ~167,000 cells: one run is enough to see it.
    r8repeat=$repeat
    [[ $bounding == bernstein ]] && r8repeat=1
    "$bin" bench "$p/circle-r8.toml" --depth 6 --bounding "$bounding" \
      --connection "$connection" --jitter 1 --repeat "$r8repeat" | tail -n 1
  done
done
