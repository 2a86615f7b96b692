#!/usr/bin/env bash
# Golden outputs for refactoring: records the outputs of a fixed set of solves (every bounding
# model, both scalars, curves and surfaces, applications) and later compares a new build's
# outputs with them byte for byte. summary.json is compared without its wall times (timing_s)
# and the thread count (settings.threads; the outputs do not depend on it, docs/performance.md).
# Every solve writes ASCII PLY and cells.csv (--ascii --cells) when the binary has those options
# (builds before them always wrote both), so that records of older builds stay comparable.
#
#   scripts/golden.sh record DIR [BINARY]   # before the change
#   scripts/golden.sh compare DIR [BINARY]  # after it: exit status 1 on any difference
#
# BINARY defaults to build/bin/ndcontour. DIR must be a folder of its own.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
mode="${1:-}"
dir="${2:-}"
bin="${3:-$root/build/bin/ndcontour}"
if [[ "$mode" != record && "$mode" != compare ]] || [[ -z "$dir" ]]; then
  echo "usage: scripts/golden.sh record|compare DIR [BINARY]" >&2
  exit 2
fi
[[ -x "$bin" ]] || { echo "golden.sh: no executable $bin (run scripts/build.sh)" >&2; exit 2; }
help="$("$bin" solve --help)"
text_outputs=""
if [[ "$help" == *--ascii* && "$help" == *--cells* ]]; then text_outputs="--ascii --cells"; fi

# name | problem | options
runs=(
  "circle-l6|circle|--depth 6"
  "circle-r5|circle-r5|--depth 4"
  "space-curve-r4|space-curve-r4|--depth 5"
  "two-circles-mpfr|two-circles|--depth 5 --scalar mpfr"
  "sphere-bernstein|sphere|--depth 4 --bounding bernstein"
  "sphere-interval|sphere|--depth 4 --bounding interval"
  "sphere-linearized|sphere|--depth 4"
  "torus-l5|torus|--depth 5"
  "torus-paper|torus|--depth 4 --connection paper"
  "torus-naive-uniform|torus|--depth 4 --connection naive --subdivision uniform"
  "sphere-r4|sphere-r4|--depth 4"
  "clifford|clifford-torus|--depth 4"
  "genus2|genus2|--depth 4"
  "cylinder-mpfr|cylinder|--depth 3 --scalar mpfr"
  "torus-jitter|torus|--depth 4 --jitter 3"
  "bisector-8a|bisector-fig8a|--depth 4"
  "convex-hull-cap|convex-hull-sphere-cap|--depth 4"
  "blend-10a|blending-fig10a|--depth 4"
  "sweep-drop|sweep-silhouette-drop|--depth 4"
)

# summary.json without the wall times and the thread count.
strip_times() {
  python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); d.pop("timing_s",None); d.get("settings",{}).pop("threads",None); print(json.dumps(d,sort_keys=True,indent=1))' "$1"
}

mkdir -p "$dir"
failed=0
for entry in "${runs[@]}"; do
  IFS='|' read -r name problem options <<<"$entry"
  target="$dir/$name"
  [[ "$mode" == compare ]] && target="$dir/$name.new"
  rm -rf "$target"
  # shellcheck disable=SC2086
  if ! "$bin" solve "$root/experiments/problems/$problem.toml" $options $text_outputs --out "$target" >/dev/null 2>&1; then
    echo "golden.sh: $name: the solve failed" >&2
    failed=1
    continue
  fi
  strip_times "$target/summary.json" >"$target/summary.stripped"
  [[ "$mode" == record ]] && { echo "recorded $name"; continue; }
  same=1
  for f in mesh.ply cells.csv singular.csv input.ply ruled.ply summary.stripped; do
    [[ -e "$dir/$name/$f" || -e "$target/$f" ]] || continue
    if ! cmp -s "$dir/$name/$f" "$target/$f"; then
      echo "DIFFERS $name/$f"
      same=0
    fi
  done
  if ((same)); then echo "same    $name"; rm -rf "$target"; else failed=1; fi
done
exit "$failed"
