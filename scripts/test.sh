#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, and runs every test: the unit and
# slow tests (Release, build/), then the sanitizer subset and a short fuzz run (ASan + UBSan,
# build-sanitize/; docs/testing.md).
# Usage: scripts/test.sh              everything above
#        scripts/test.sh --sanitize   only the whole unit suite under ASan + UBSan
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ "${1:-}" == "--sanitize" ]]; then
  scripts/setup.sh
  exec scripts/sanitize.sh
elif [[ -n "${1:-}" ]]; then
  echo "usage: scripts/test.sh [--sanitize]" >&2
  exit 2
fi
scripts/build.sh
ctest --test-dir build --output-on-failure
scripts/sanitize.sh --subset
scripts/fuzz.sh --seconds 45
