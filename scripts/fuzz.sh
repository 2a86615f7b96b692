#!/usr/bin/env bash
# Builds the libFuzzer harnesses of tests/fuzz/ in the sanitized build (build-sanitize/, see
# scripts/sanitize.sh) and runs each for N seconds on a scratch copy of its seed corpus, with
# its dictionary (docs/testing.md).
# Usage: scripts/fuzz.sh [--seconds N] [--keep] [harness ...]
#   --seconds N  run time per harness (default 60)
#   --keep       continue from the corpus a previous run grew instead of a fresh seed copy
#   harness      fuzz_problem, fuzz_expression, fuzz_application (default: all)
# For hours: scripts/fuzz.sh --seconds 3600 --keep   (one hour per harness, as many at once as
# there are processors)
# A finding (crash, sanitizer report, uncaught exception, timeout past 10 s, more than 2 GB)
# stops that harness, keeps the input under build-sanitize/fuzz/<harness>/findings/ and makes
# the script exit 1 after the other harnesses ran. Exits 0 with a message when clang is not
# installed.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=60
keep=0
harnesses=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seconds) seconds="${2:?--seconds needs a number}"; shift 2 ;;
    --keep) keep=1; shift ;;
    fuzz_*) harnesses+=("$1"); shift ;;
    *) echo "usage: scripts/fuzz.sh [--seconds N] [--keep] [harness ...]" >&2; exit 2 ;;
  esac
done
if ! [[ $seconds =~ ^[1-9][0-9]*$ ]]; then
  echo "fuzz: --seconds must be a positive integer, got '$seconds'" >&2
  exit 2
fi
if [[ ${#harnesses[@]} -eq 0 ]]; then
  for f in tests/fuzz/fuzz_*.cpp; do harnesses+=("$(basename "$f" .cpp)"); done
fi

if ! command -v clang++ >/dev/null 2>&1 ||
   [[ ! -e "$(clang++ -print-resource-dir)/lib/linux/libclang_rt.fuzzer-x86_64.a" ]]; then
  echo "fuzz: clang++ or libFuzzer is not installed (Debian packages clang and" \
       "libclang-rt-14-dev; scripts/setup.sh installs them): nothing done"
  exit 0
fi
for h in "${harnesses[@]}"; do
  [[ -f tests/fuzz/$h.cpp ]] || { echo "fuzz: no harness tests/fuzz/$h.cpp" >&2; exit 2; }
done
scripts/sanitize.sh --build "${harnesses[@]}"

# fuzz_one HARNESS: one harness for $seconds s; its summary lines go to its work folder's
# report, and its exit status to status.
fuzz_one() {
  local h=$1 work=build-sanitize/fuzz/$1 max_len=8192 status=0 runs
  if [[ $keep -eq 0 || ! -d $work/corpus ]]; then
    rm -rf "$work/corpus"
    mkdir -p "$work/corpus"
    cp tests/fuzz/seeds/$h/* "$work/corpus/"
    # The file harnesses also start from the regression corpus (past findings, hostile files).
    if [[ $h != fuzz_expression ]] && compgen -G 'tests/corpus/*.toml' >/dev/null; then
      cp tests/corpus/*.toml "$work/corpus/"
    fi
  fi
  rm -f "$work/report" "$work/status"
  mkdir -p "$work/findings"
  [[ $h == fuzz_expression ]] && max_len=2048
  local options=(-max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -max_len=$max_len
                 -dict=tests/fuzz/$h.dict -artifact_prefix="$work/findings/" -print_final_stats=1)
  UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
    build-sanitize/bin/$h "${options[@]}" "$work/corpus" >"$work/fuzz.log" 2>&1 || status=$?
  runs=$(grep -o 'stat::number_of_executed_units: [0-9]*' "$work/fuzz.log" | grep -o '[0-9]*$' || true)
  {
    echo "fuzz: $h: ${runs:-?} executions, corpus $(ls "$work/corpus" | wc -l) inputs, exit status $status"
    if [[ $status -ne 0 ]]; then
      grep -E 'ERROR|SUMMARY|runtime error|Test unit written|fuzz: check failed|what\(\)|terminate' \
        "$work/fuzz.log" | head -20 || true
      # The stack of the finding and the input itself, so that a log from another machine (CI)
      # is enough to reproduce it: `base64 -d > input; build-sanitize/bin/<harness> input`.
      grep -E '^ +#[0-9]+ ' "$work/fuzz.log" | head -30 || true
      for f in "$work"/findings/*; do
        [[ -f $f ]] || continue
        echo "fuzz: input $(basename "$f") ($(stat -c %s "$f") bytes), base64:"
        head -c 4096 "$f" | base64
      done
      echo "fuzz: $h: finding kept in $work/findings/ (whole log: $work/fuzz.log)"
    fi
  } >"$work/report"
  echo "$status" >"$work/status"
}

# The harnesses run side by side, one per processor (each is one single-threaded process), so
# that the run takes $seconds s per round of processors rather than per harness.
jobs_max=$(nproc)
for h in "${harnesses[@]}"; do
  while [[ $(jobs -rp | wc -l) -ge $jobs_max ]]; do wait -n || true; done
  echo "fuzz: $h for $seconds s (log build-sanitize/fuzz/$h/fuzz.log)"
  fuzz_one "$h" &
done
wait
failed=()
for h in "${harnesses[@]}"; do
  work=build-sanitize/fuzz/$h
  if [[ $(cat "$work/status" 2>/dev/null || echo 1) -ne 0 ]]; then
    failed+=("$h")
    cat "$work/report" >&2
  else
    cat "$work/report"
  fi
done
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "fuzz: findings in ${failed[*]}" >&2
  exit 1
fi
