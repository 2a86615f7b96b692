#!/usr/bin/env bash
# The largest source files and the longest functions of the tree, for keeping functions on a
# screen (docs/architecture.md: no function over about 80 lines in framework/ or strategies/,
# none over 120 anywhere).
# Usage: scripts/sizes.sh [N] [DIR...]   the N largest of each (default 15) under DIR
#                                         (default framework strategies pipeline applications experiments)
# A function is a brace block that opens at the end of a line holding a signature's closing
# parenthesis outside any other function (control statements and lambdas are not functions);
# its length runs from that line to its closing brace. It is a heuristic over the text, exact
# for clang-formatted code.
set -euo pipefail
cd "$(dirname "$0")/.."
count=15
if [[ $# -gt 0 && $1 =~ ^[0-9]+$ ]]; then count=$1; shift; fi
dirs=("$@")
[[ ${#dirs[@]} -gt 0 ]] || dirs=(framework strategies pipeline applications experiments)
mapfile -t files < <(find "${dirs[@]}" -name '*.cpp' -o -name '*.hpp' -o -name '*.inl' | sort)
[[ ${#files[@]} -gt 0 ]] || { echo "sizes: no sources under ${dirs[*]}" >&2; exit 2; }

echo "## Largest files (lines)"
wc -l "${files[@]}" | grep -v ' total$' | sort -rn | head -n "$count"

echo
echo "## Longest functions (lines, file:line, name)"
awk '
  FNR == 1 { depth = 0; inside = 0; prev1 = ""; prev2 = ""; prev3 = "" }
  {
    line = $0
    code = line
    sub(/\/\/.*$/, "", code)            # comments
    gsub(/"([^"\\]|\\.)*"/, "\"\"", code)  # string literals
    gsub(/'"'"'([^'"'"'\\]|\\.)*'"'"'/, "0", code)  # character literals
    trimmed = code
    sub(/[ \t]+$/, "", trimmed)
    if (!inside && trimmed ~ /\)[^;{}()]*\{$/ &&
        trimmed !~ /^[ \t]*(if|for|while|switch|catch|else|do)[ (]/ &&
        trimmed !~ /^[ \t]*\}/ && trimmed !~ /\]\(/ && trimmed !~ /\[[^]]*\][ \t]*\(/) {
      # The name: the identifier before the first "(" of the signature (this line or up to
      # three lines above).
      sig = prev3 "\n" prev2 "\n" prev1 "\n" code
      n = split(sig, parts, "\n")
      name = "?"
      for (i = 1; i <= n; i++) {
        if (match(parts[i], /[A-Za-z_][A-Za-z0-9_:~<>]*[ \t]*\(/)) {
          name = substr(parts[i], RSTART, RLENGTH)
          sub(/[ \t]*\($/, "", name)
          break
        }
      }
      inside = 1; start = FNR; startDepth = depth; fname = name
    }
    opens = gsub(/\{/, "{", code); closes = gsub(/\}/, "}", code)
    depth += opens - closes
    if (inside && depth <= startDepth) {
      printf "%6d  %s:%d  %s\n", FNR - start + 1, FILENAME, start, fname
      inside = 0
    }
    # The signature so far: the lines since the last statement, block or blank line.
    if (trimmed ~ /[;{}]$/ || trimmed ~ /^[ \t]*$/ || trimmed ~ /^[ \t]*#/) {
      prev3 = ""; prev2 = ""; prev1 = ""
    } else {
      prev3 = prev2; prev2 = prev1; prev1 = code
    }
  }
' "${files[@]}" | sort -rn | head -n "$count"
