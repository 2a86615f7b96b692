#!/usr/bin/env bash
# render.sh: renders a solved application result directory to PNG, like the paper's Figures 6-10.
#
#   scripts/render.sh RESULT_DIR        e.g. scripts/render.sh results/bisector-fig8a
#
# RESULT_DIR is what `ndcontour solve APP.toml --out RESULT_DIR` wrote (mesh.ply, input.ply,
# summary.json). The application is read from summary.json's "application" field, else from the
# "problem" name's prefix (convex-hull-*, bisector-*, ...); then
#   gnuplot -e "dir='RESULT_DIR'" experiments/gnuplot/APPLICATION.gp
# writes RESULT_DIR/APPLICATION.png. Needs gnuplot (Debian gnuplot-nox, scripts/setup.sh) and,
# for binary PLY (the default of solve; scripts/ply2dat.sh reads it), python3.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ $# -ne 1 || ! -f "$1/summary.json" ]]; then
  echo "usage: render.sh RESULT_DIR (a directory holding summary.json, mesh.ply, input.ply)" >&2
  exit 2
fi
dir="${1%/}"
# "application": {"name": "bisector", ...} (or a plain string), else the problem name's prefix.
app="$(sed -n 's/.*"application": *\({ *"name": *\)\{0,1\}"\([^"]*\)".*/\2/p' "$dir/summary.json" | head -n 1)"
if [[ -z "$app" ]]; then
  problem="$(sed -n 's/.*"problem": *"\([^"]*\)".*/\1/p' "$dir/summary.json" | head -n 1)"
  for a in convex-hull sweep-silhouette sweep-envelope bisector blending; do
    if [[ "$problem" == "$a"* ]]; then app="$a"; break; fi
  done
fi
script="$here/experiments/gnuplot/$app.gp"
if [[ -z "$app" || ! -f "$script" ]]; then
  echo "render.sh: $dir: not an application result (no gnuplot script for '${app:-?}')" >&2
  exit 2
fi
if ! command -v gnuplot >/dev/null; then
  echo "render.sh: gnuplot is missing: install the Debian package 'gnuplot-nox'" >&2
  exit 2
fi
if ! command -v python3 >/dev/null && ! grep -a -q '^format ascii' <(head -c 200 "$dir/mesh.ply"); then
  echo "render.sh: python3 is missing (it reads binary PLY): install the Debian package 'python3'" >&2
  exit 2
fi
gnuplot -e "dir='$dir'" "$script"
echo "$dir/$app.png"
