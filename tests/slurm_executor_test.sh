#!/usr/bin/env bash
# `ndcontour experiment --executor slurm` on a real single-node Slurm cluster on localhost
# (scripts/slurm-cluster.sh; ctest test `slurm`, registered when Slurm and MUNGE are installed:
# scripts/setup.sh --slurm). Runs small grids with the local executor and with Slurm and checks
# that the combined CSVs agree, that provenance.json records the Slurm job, that a second
# invocation resumes (submits nothing), that failures and timeouts are recorded alike, and that
# `solve --split` gives the same mesh on Slurm as locally.
# Usage: tests/slurm_executor_test.sh NDCONTOUR   (as root; otherwise it exits 77: skipped)
set -euo pipefail
[[ $# -eq 1 ]] || {
  echo "usage: tests/slurm_executor_test.sh NDCONTOUR" >&2
  exit 2
}
if [[ $(id -u) -ne 0 ]]; then
  echo "slurm_executor_test: skipped: the single-node cluster needs root (slurmd)" >&2
  exit 77 # ctest: skipped (SKIP_RETURN_CODE)
fi
ndc=$(realpath "$1")
src=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/ndc-slurm-test.XXXXXX")
cluster=$work/cluster

cleanup() {
  local status=$?
  [[ -z ${watchdog:-} ]] || kill "$watchdog" 2>/dev/null || true
  "$src/scripts/slurm-cluster.sh" stop "$cluster" || true
  if [[ $status -ne 0 ]]; then
    for log in "$cluster"/log/*.log; do
      [[ -s $log ]] && { echo "--- last lines of $log" >&2; tail -n 20 "$log" >&2; }
    done
  fi
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# The whole test gives up after 540 s (each command below has its own limit), well within ctest's
# 900 s, so that the cluster is always stopped by the trap above.
(
  for _ in $(seq 540); do sleep 1; done
  echo "slurm_executor_test: FAIL: gave up after 540 s" >&2
  kill -TERM $$
) &
watchdog=$!

fail() {
  echo "slurm_executor_test: FAIL: $*" >&2
  exit 1
}

# A free port for the controller (and the next one for the node), so that runs do not collide.
for _ in $(seq 50); do
  port=$((20000 + RANDOM % 20000))
  if ! (echo >"/dev/tcp/127.0.0.1/$port") 2>/dev/null &&
    ! (echo >"/dev/tcp/127.0.0.1/$((port + 1))") 2>/dev/null; then
    break
  fi
done
NDC_SLURM_PORT=$port NDC_SLURM_WAIT=60 "$src/scripts/slurm-cluster.sh" start "$cluster"
export SLURM_CONF=$cluster/slurm.conf

# ndcontour experiment CONFIG OUT ARGS...: its exit status; stdout and stderr in OUT.{out,err}.
experiment() {
  local config=$1 out=$2
  shift 2
  local status=0
  timeout 120 "$ndc" experiment "$src/tests/slurm/$config.toml" --out "$out" --jobs 2 "$@" \
    >"$out.out" 2>"$out.err" || status=$?
  echo "$status"
}

# The combined CSV of OUT for CONFIG without its volatile columns: timing_s.* (the stage times
# of each run, measured inside the run); every other column (settings, status, exit code, error,
# expect_*, cell, mesh, accuracy, diagnostics, budget and topology numbers) must be identical.
stable_csv() {
  python3 - "$1/$2/$2.csv" <<'EOF'
import csv, sys
rows = list(csv.reader(open(sys.argv[1], newline="")))
keep = [i for i, name in enumerate(rows[0]) if not name.startswith("timing_s.")]
for row in rows:
    print(",".join(row[i] for i in keep))
EOF
}

compare() {
  local config=$1
  stable_csv "$work/local" "$config" >"$work/$config.local.csv"
  stable_csv "$work/slurm" "$config" >"$work/$config.slurm.csv"
  diff -u "$work/$config.local.csv" "$work/$config.slurm.csv" >&2 ||
    fail "$config: the CSVs of the local and Slurm executors differ"
  [[ $(wc -l <"$work/$config.slurm.csv") -gt 1 ]] || fail "$config: empty CSV"
}

# 1. Four good runs: the same CSV from both executors.
mkdir -p "$work/local" "$work/slurm"
status=$(experiment slurm-grid "$work/local")
[[ $status -eq 0 ]] || fail "local executor exited $status: $(tail -n 3 "$work/local.err")"
status=$(experiment slurm-grid "$work/slurm" --executor slurm)
[[ $status -eq 0 ]] || fail "Slurm executor exited $status: $(tail -n 3 "$work/slurm.err")"
grep -q "^slurm: submitted job [0-9]*: 4 tasks, at most 2 at once" "$work/slurm.err" ||
  fail "no 'submitted job' line on stderr"
grep -q "^slurm: job [0-9]* finished" "$work/slurm.err" || fail "no 'finished' line on stderr"
grep -q "4 runs: 4 ran, 0 skipped" "$work/slurm.out" || fail "unexpected report: $(cat "$work/slurm.out")"
compare slurm-grid

# 2. The provenance names the executor and the job.
grep -Eq '"executor": \{"name": "slurm", "job_id": "[0-9]+", "tasks": 4' \
  "$work/slurm/slurm-grid/provenance.json" || fail "provenance.json does not record the Slurm job"
grep -q '"executor": {"name": "local"}' "$work/local/slurm-grid/provenance.json" ||
  fail "provenance.json does not record the local executor"

# 3. Resume: every run finished, so a second invocation submits nothing and exits 0.
status=$(experiment slurm-grid "$work/slurm" --executor slurm)
[[ $status -eq 0 ]] || fail "resumed Slurm executor exited $status"
grep -q "^slurm: nothing to submit" "$work/slurm.err" || fail "the resumed invocation submitted"
grep -q "4 runs: 0 ran, 4 skipped" "$work/slurm.out" || fail "unexpected report: $(cat "$work/slurm.out")"
grep -q '"job_id": null' "$work/slurm/slurm-grid/provenance.json" ||
  fail "the resumed provenance.json names a job"
compare slurm-grid

# 4. A failing run is recorded alike (status, exit code, error line) and both exit 1.
status=$(experiment slurm-failing "$work/local")
[[ $status -eq 1 ]] || fail "local executor exited $status on the failing grid, not 1"
status=$(experiment slurm-failing "$work/slurm" --executor slurm)
[[ $status -eq 1 ]] || fail "Slurm executor exited $status on the failing grid, not 1"
compare slurm-failing
grep -q ",failed,2," "$work/slurm/slurm-failing/slurm-failing.csv" || fail "the failure is not recorded"

# 5. A run past its timeout is stopped and recorded alike.
status=$(experiment slurm-timeout "$work/local")
[[ $status -eq 1 ]] || fail "local executor exited $status on the timeout grid, not 1"
status=$(experiment slurm-timeout "$work/slurm" --executor slurm)
[[ $status -eq 1 ]] || fail "Slurm executor exited $status on the timeout grid, not 1"
compare slurm-timeout
grep -q ",timeout,,timed out after 0.2 s" "$work/slurm/slurm-timeout/slurm-timeout.csv" ||
  fail "the timeout is not recorded"

# 6. One solve split into pieces (solve --split, docs/split.md): the Slurm job array of the pieces
# glues to the same mesh, byte for byte, as the local executor, and to the certified topology.
for executor in local slurm; do
  timeout 180 "$ndc" solve "$src/experiments/problems/torus.toml" --depth 4 --split 8 \
    --executor "$executor" --out "$work/split-$executor" >"$work/split-$executor.out" \
    2>"$work/split-$executor.err" || fail "solve --split --executor $executor: $(tail -n 3 "$work/split-$executor.err")"
  grep -q "topology: certified" "$work/split-$executor.out" ||
    fail "solve --split --executor $executor is not certified: $(cat "$work/split-$executor.out")"
done
grep -q "^slurm: submitted job [0-9]*: 8 tasks" "$work/split-slurm.err" ||
  fail "solve --split --executor slurm submitted no job array of 8 tasks"
cmp "$work/split-local/mesh.ply" "$work/split-slurm/mesh.ply" ||
  fail "solve --split: the local and Slurm meshes differ"

echo "slurm_executor_test: ok (local and Slurm CSVs agree; provenance, resume, failures and" \
  "timeouts checked; a split solve gives the same mesh)"
