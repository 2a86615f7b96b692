#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, and runs the main job on every
# example problem in experiments/problems/, writing under results/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
bin=build/bin/ndcontour
mkdir -p results
status=0
for problem in experiments/problems/*.toml; do
  name=$(basename "$problem" .toml)
  mkdir -p "results/$name"
  "$bin" info "$problem" > "results/$name/info.txt"
  if "$bin" solve "$problem" --out "results/$name" > "results/$name/solve.log" 2>&1; then
    echo "solved $name: $(grep -o '"components": [0-9]*' "results/$name/summary.json")"
  else
    echo "FAILED $name (see results/$name/solve.log)"
    status=1
  fi
done
exit $status
