#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, runs every experiment config in
# experiments/configs/ (quick versions by default, full ones with --full), writes the tables,
# figures and results/report.md with `ndcontour report`, and builds the paper when pdflatex is
# installed. Results go to results/<id>/ (one id per artefact, the same as its config); finished
# runs are not run again.
#
# Usage: scripts/run.sh [--full] [--jobs N] [ID ...]
#   --full     the full grids (paper-scale depths and seeds) instead of the quick ones
#   --jobs N   runs at once (default: the number of cores)
#   ID ...     only these experiments (default: every experiments/configs/*.toml)
# Exit status: 0 when every run succeeded and every artefact was made, 1 otherwise (the report
# is written in every case), 2 for bad usage.
set -uo pipefail
cd "$(dirname "$0")/.."

mode=quick
jobs=$(nproc)
ids=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --full) mode=full ;;
    --quick) mode=quick ;;
    --jobs)
      [[ $# -ge 2 && "$2" =~ ^[1-9][0-9]*$ ]] || { echo "run.sh: --jobs needs a positive number" >&2; exit 2; }
      jobs=$2
      shift ;;
    -h | --help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "run.sh: unknown option '$1' (see scripts/run.sh --help)" >&2; exit 2 ;;
    *) ids+=("$1") ;;
  esac
  shift
done

start=$SECONDS
# The tool only (scripts/build.sh also builds the tests, which the experiments do not need).
scripts/setup.sh || { echo "run.sh: installing the dependencies failed" >&2; exit 1; }
{ cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null &&
  cmake --build build -j "$(nproc)" --target ndcontour; } ||
  { echo "run.sh: the build failed" >&2; exit 1; }
bin=build/bin/ndcontour
echo "run.sh: built $bin in $((SECONDS - start)) s"

configs=()
if [[ ${#ids[@]} -eq 0 ]]; then
  configs=(experiments/configs/*.toml)
else
  for id in "${ids[@]}"; do
    [[ -f "experiments/configs/$id.toml" ]] || { echo "run.sh: no experiments/configs/$id.toml" >&2; exit 2; }
    configs+=("experiments/configs/$id.toml")
  done
fi

flags=()
[[ $mode == quick ]] && flags+=(--quick)
mkdir -p results
status=0
failed=()
i=0
for config in "${configs[@]}"; do
  i=$((i + 1))
  id=$(basename "$config" .toml)
  t0=$SECONDS
  echo "run.sh: [$i/${#configs[@]}] $id ($mode, $jobs jobs)"
  "$bin" experiment "$config" --out results --jobs "$jobs" "${flags[@]}"
  rc=$?
  if [[ $rc -ne 0 ]]; then
    status=1
    failed+=("$id (exit $rc)")
    echo "run.sh: $id: exit status $rc after $((SECONDS - t0)) s (failures are listed in results/report.md)"
    # Interrupted (Ctrl-C): stop here, but still write the report of what is there.
    [[ $rc -eq 130 ]] && break
  else
    echo "run.sh: $id: done in $((SECONDS - t0)) s"
  fi
done

echo "run.sh: writing the report"
report_flags=(--results results --configs experiments/configs)
[[ $mode == quick ]] && report_flags+=(--quick)
"$bin" report "${report_flags[@]}" || status=1

# The paper, where TeX is installed (the configure step defines the target only then).
if command -v pdflatex > /dev/null 2>&1; then
  if cmake --build build --target paper > results/paper.log 2>&1; then
    echo "run.sh: built build/paper/ndcontour.pdf"
  else
    echo "run.sh: the paper did not build (see results/paper.log)" >&2
    status=1
  fi
else
  echo "run.sh: no paper: pdflatex is not installed (scripts/setup.sh --tex installs TeX, then run scripts/run.sh again)"
fi

echo "run.sh: $mode run finished in $((SECONDS - start)) s; see results/report.md"
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "run.sh: experiments with failed runs: ${failed[*]}" >&2
fi
exit $status
