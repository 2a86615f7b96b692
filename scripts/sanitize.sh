#!/usr/bin/env bash
# Builds build-sanitize/ (clang++, AddressSanitizer + UndefinedBehaviorSanitizer, -DNDC_SANITIZE=ON)
# and runs the unit tests under the sanitizers (docs/testing.md).
# Usage: scripts/sanitize.sh [--subset]      the whole unit suite ("~[slow]~[.]"), or a subset
#                                            (parsing, problems, application files, hostile
#                                            input, Bernstein, subdivision, connection,
#                                            certificate)
#        scripts/sanitize.sh --build TARGET...  configure if needed and build only TARGETs
#                                            (scripts/fuzz.sh: `--build fuzzers`)
# The tests run the sanitized CLI as a child process; a report from the test process or from any
# child is written to build-sanitize/sanitizer-logs/ and fails the run, whatever the test
# concluded from the child's exit status. Exits 0 with a message when clang is not installed.
set -euo pipefail
cd "$(dirname "$0")/.."

# The subset: these tags of tests/ (every folder), without the [slow] and hidden tests (a Catch2 v2 test
# spec: a comma is "or", juxtaposition "and").
subset=
# ([applications] is left out: its solves take minutes each under ASan, e.g. 340 s for the
# rolling-ball blend; application files are read by [geometry], [hostile] and [corpus].)
for tag in problem expression geometry hostile bernstein form-rounding subdivision connection certificate analysis \
  corpus ply glue; do
  subset+="${subset:+,}[$tag]~[slow]~[.]"
done

mode=full
targets=()
case "${1:-}" in
  "") ;;
  --subset) mode=subset ;;
  --build)
    mode=build
    shift
    targets=("$@")
    [[ ${#targets[@]} -gt 0 ]] || { echo "usage: scripts/sanitize.sh --build TARGET..." >&2; exit 2; }
    ;;
  *) echo "usage: scripts/sanitize.sh [--subset | --build TARGET...]" >&2; exit 2 ;;
esac

# clang++ and its sanitizer and libFuzzer runtimes (Debian: clang, libclang-rt-14-dev).
if ! command -v clang++ >/dev/null 2>&1 ||
   [[ ! -e "$(clang++ -print-resource-dir)/lib/linux/libclang_rt.fuzzer-x86_64.a" ]]; then
  echo "sanitize: clang++ or its sanitizer runtime is not installed (Debian packages clang and" \
       "libclang-rt-14-dev; scripts/setup.sh installs them): nothing done"
  exit 0
fi

dir=build-sanitize
if [[ ! -f $dir/CMakeCache.txt ]]; then
  CC=clang CXX=clang++ cmake -S . -B $dir -DNDC_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug >/dev/null
fi
if [[ $mode == build ]]; then
  cmake --build $dir -j "$(nproc)" --target "${targets[@]}"
  exit 0
fi
cmake --build $dir -j "$(nproc)" --target ndcontour_tests ndcontour

logs=$dir/sanitizer-logs
rm -rf "$logs"
mkdir -p "$logs"
# halt_on_error: the first report ends the process (the build has -fno-sanitize-recover=all);
# detect_leaks: LeakSanitizer at exit; the reports go to files named by process id.
export ASAN_OPTIONS="log_path=$PWD/$logs/asan:detect_leaks=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="log_path=$PWD/$logs/ubsan:print_stacktrace=1:halt_on_error=1"

spec='~[slow]~[.]'
[[ $mode == subset ]] && spec="$subset"
echo "sanitize: $dir/bin/ndcontour_tests \"$spec\" under ASan and UBSan"
start=$SECONDS
status=0
$dir/bin/ndcontour_tests "$spec" --durations no || status=$?
echo "sanitize: tests took $((SECONDS - start)) s, exit status $status"

if compgen -G "$logs/*" >/dev/null; then
  echo "sanitize: sanitizer reports (in $logs/):" >&2
  for f in "$logs"/*; do
    echo "--- $f" >&2
    cat "$f" >&2
  done
  exit 1
fi
exit $status
