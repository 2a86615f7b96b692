#!/usr/bin/env bash
# ctest "peer-bench-quick" (bench/CMakeLists.txt): bench/run.sh, the peer benchmark's and the own
# tables' generator, runs on tiny cases and writes tables with rows, into a scratch copy of
# docs/performance.md. No time is
# asserted. Usage: tests/peer_bench_quick.sh SOURCE_DIR BIN_DIR
set -euo pipefail
source_dir=$1
bin_dir=$2
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
cp "$source_dir/docs/performance.md" "$scratch/performance.md"
"$source_dir/bench/run.sh" --quick --bindir "$bin_dir" --out "$scratch/performance.md"
section=$(sed -n '/<!-- peer-bench:begin -->/,/<!-- peer-bench:end -->/p' "$scratch/performance.md")
rows=$(grep -c '^| torus | 3 | \(cgal\|gudhi\) |' <<<"$section" || true)
if [[ $rows -lt 1 ]]; then
  echo "peer-bench-quick: no matched torus row in the table:" >&2
  echo "$section" >&2
  exit 1
fi
grep -q '^| circle-r8 | gudhi |' <<<"$section" || { echo "no circle-r8 run" >&2; exit 1; }
own=$(sed -n '/<!-- self-bench:begin -->/,/<!-- self-bench:end -->/p' "$scratch/performance.md")
grep -q '^| rotated-sphere | 4 | 3 |' <<<"$own" || { echo "no per-cell row for the sphere in R^4" >&2; exit 1; }
grep -q '^| torus | 5 |' <<<"$own" || { echo "no output-writing row" >&2; exit 1; }
grep -q '^- rotated-sphere, one thread .*x per solution cell' <<<"$own" ||
  { echo "no one-thread growth of the sphere's cost per cell" >&2; exit 1; }
grep -q '^| torus.toml | 4 | [0-9]* | [0-9]* | [0-9.]* | .* | [0-9.]* |$' <<<"$own" ||
  { echo "no thread-speedup row" >&2; exit 1; }
echo "peer-bench-quick: $rows matched torus row(s); own tables written"
