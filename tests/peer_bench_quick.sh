#!/usr/bin/env bash
# ctest "peer-bench-quick" (bench/CMakeLists.txt): the peer benchmark's table generator runs on a
# tiny case and writes a table with rows, into a scratch copy of docs/performance.md. No time is
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
echo "peer-bench-quick: $rows matched torus row(s)"
