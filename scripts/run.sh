#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, and solves every example problem
# in experiments/problems/ with the crossing connection, writing results/<problem>/ and a table
# results/summary.md that sets each result beside the problem's [expect] ground truth.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
bin=build/bin/ndcontour
depth=${NDC_DEPTH:-6}
mkdir -p results
table=results/summary.md
{
  echo "# ndcontour: example problems (crossing connection, depth $depth, jitter 1)"
  echo
  echo "| problem | n | k | components (expected) | euler (expected) | boundary edges | non-manifold edges | open ends | max residual | seconds |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
} > "$table"
json() { grep -o "\"$1\": [^,}]*" "$2" | head -1 | sed 's/.*: //'; }
expect() { sed -n '/^\[expect\]/,$p' "$2" | grep -E "^$1 *=" | head -1 | sed 's/.*= *//'; }
status=0
for problem in experiments/problems/*.toml; do
  name=$(basename "$problem" .toml)
  out="results/$name"
  mkdir -p "$out"
  "$bin" info "$problem" > "$out/info.txt"
  if "$bin" solve "$problem" --depth "$depth" --connection crossing --jitter 1 --out "$out" \
      > "$out/solve.log" 2>&1; then
    s="$out/summary.json"
    row="| $name | $(json n "$s") | $(json k "$s") | $(json components "$s") ($(expect components "$problem")) | $(json euler_characteristic "$s") ($(expect euler_characteristic "$problem")) | $(json boundary_edges "$s") | $(json nonmanifold_edges "$s") | $(json open_ends "$s") | $(printf '%.1e' "$(json max_residual "$s")") | $(printf '%.3f' "$(json total "$s")") |"
    echo "$row" >> "$table"
    echo "solved $name"
  else
    echo "| $name | failed: see $out/solve.log |||||||||" >> "$table"
    echo "FAILED $name (see $out/solve.log)"
    status=1
  fi
done
echo "wrote $table"
exit $status
