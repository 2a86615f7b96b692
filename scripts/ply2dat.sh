#!/usr/bin/env bash
# ply2dat.sh: PLY (as ndcontour writes it: mesh.ply, input.ply, ruled.ply) -> gnuplot data. A
# binary PLY (the default of solve) is read through scripts/ply2ascii.py (needs python3); an ASCII
# one (solve --ascii) directly.
#
#   scripts/ply2dat.sh [--props X,Y,Z] [--pm3d] [--part P] FILE.ply
#       the simplices (triangles or segments) of FILE in the vertex properties X Y Z (default
#       x,y,z; e.g. x2,y2,z2 for the second contact point of a convex-hull mesh). Each triangle
#       is a closed polyline a b c a and each segment a b, followed by two blank lines (separate
#       blocks, so that splot ... with lines draws no lines between them). --pm3d writes each
#       triangle as a 2 x 2 grid (a b / c m, m the midpoint of b and c) for `with pm3d` (shaded, lit). --part P keeps only faces whose last face property (`part` of input.ply) is P.
#   scripts/ply2dat.sh --eye EX,EY,EZ --target TX,TY,TZ [...] FILE.ply
#       the same, every point projected in perspective from the eye point E looking at T (world
#       z up): x y = the perspective image (right, up over the depth), z = minus the depth along
#       the view direction, so that `set view 0,0` shows the perspective picture and pm3d
#       depthorder sorts by distance (gnuplot itself only draws orthographic views).
#   scripts/ply2dat.sh --ruling [--every N] FILE.ply
#       one segment per N-th vertex from (x, y, z) to (x2, y2, z2): the rulings of a
#       convex-hull result (the bitangent segments); N = 0 (the default) picks N so that about
#       150 segments are drawn.
#
# Gnuplot reads it through a pipe: splot '< scripts/ply2dat.sh results/torus/mesh.ply' w l
set -euo pipefail

props="x,y,z"
mode="simplices"
every=0
part=""
eye=""
target=""
while [[ $# -gt 1 ]]; do
  case "$1" in
    --props) props="$2"; shift 2 ;;
    --pm3d) mode="pm3d"; shift ;;
    --ruling) mode="ruling"; shift ;;
    --every) every="$2"; shift 2 ;;
    --part) part="$2"; shift 2 ;;
    --eye) eye="$2"; shift 2 ;;
    --target) target="$2"; shift 2 ;;
    *) echo "ply2dat.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
if [[ $# -ne 1 || ! -r "$1" ]]; then
  echo "usage: ply2dat.sh [--props X,Y,Z] [--pm3d] [--part P] [--eye X,Y,Z --target X,Y,Z] [--ruling [--every N]] FILE.ply" >&2
  exit 2
fi
if [[ "$mode" == "ruling" ]]; then props="x,y,z,x2,y2,z2"; fi

# Whether the header's format line says binary (read up to end_header only).
is_binary() {
  local line n=0
  while IFS= read -r line && ((n++ < 1000)); do
    [[ "$line" == "format binary"* ]] && return 0
    [[ "$line" == end_header* ]] && return 1
  done <"$1"
  return 1
}
file="$1"
ascii_file="$1"
if is_binary "$file"; then
  if ! command -v python3 >/dev/null; then
    echo "ply2dat.sh: $file: reading binary PLY needs python3 (Debian package 'python3')" >&2
    exit 2
  fi
  ascii_file="$(mktemp)"
  trap 'rm -f "$ascii_file"' EXIT
  python3 "$(dirname "${BASH_SOURCE[0]}")/ply2ascii.py" "$file" >"$ascii_file" || exit 2
fi

awk -v file="$file" -v props="$props" -v mode="$mode" -v every="$every" -v part="$part" \
  -v eye="$eye" -v target="$target" '
  function fail(msg) { print "ply2dat.sh: " file ": " msg > "/dev/stderr"; bad = 1; exit 2 }
  BEGIN { header = 1; nwant = split(props, want, ","); nelem = 0; if (eye != "") camera() }
  # The perspective frame: forward F = (T - E) / |T - E|, right R = F x z, up U = R x F.
  function camera(   e, t, n) {
    if (split(eye, e, ",") != 3 || split(target, t, ",") != 3) fail("--eye and --target need X,Y,Z")
    for (i = 1; i <= 3; ++i) { E[i] = e[i]; F[i] = t[i] - e[i] }
    unit(F); R[1] = F[2]; R[2] = -F[1]; R[3] = 0
    if (R[1] == 0 && R[2] == 0) R[1] = 1
    unit(R); U[1] = R[2] * F[3] - R[3] * F[2]; U[2] = R[3] * F[1] - R[1] * F[3]
    U[3] = R[1] * F[2] - R[2] * F[1]
  }
  function unit(a,   n) { n = sqrt(a[1]^2 + a[2]^2 + a[3]^2); for (i = 1; i <= 3; ++i) a[i] /= n }
  # Header: the elements in order, their counts and the vertex properties.
  header && NR == 1 && $1 != "ply" { fail("not a PLY file") }
  header && $1 == "format" && $2 != "ascii" { fail("format " $2 " is not read") }
  header && $1 == "element" { name[++nelem] = $2; count[nelem] = $3; nprop[nelem] = 0; next }
  header && $1 == "property" { nprop[nelem]++; if (name[nelem] == "vertex") col[$NF] = nprop[nelem]; next }
  header && $1 == "end_header" {
    header = 0
    for (i = 1; i <= nwant; ++i) if (!(want[i] in col)) fail("no vertex property " want[i])
    e = 1; left = count[1]; v = 0
    if (every <= 0) { every = int(count[1] / 150); if (every < 1) every = 1 }
    next
  }
  header { next }
  # Body: the elements one after the other.
  {
    while (left == 0 && e < nelem) { ++e; left = count[e] }
    --left
    if (name[e] == "vertex") {
      for (i = 1; i <= nwant; ++i) coord[v, i] = $(col[want[i]])
      if (mode == "ruling" && v % every == 0) {
        print coord[v, 1], coord[v, 2], coord[v, 3]
        print coord[v, 4], coord[v, 5], coord[v, 6]
        print ""; print ""
      }
      ++v
      next
    }
    if (mode == "ruling") next
    if (name[e] == "face") {
      if (part != "" && $NF != part) next
      a = $2; b = $3; c = $4
      if (mode == "pm3d") {
        # m, the midpoint of b and c: every three corners of a b / c m span the triangle, so
        # that the lighting of gnuplot finds its normal (a b / c c has none: one flat colour).
        for (i = 1; i <= nwant; ++i) coord["m", i] = 0.5 * (coord[b, i] + coord[c, i])
        pt(a); pt(b); print ""; pt(c); pt("m"); print ""; print ""
      } else {
        pt(a); pt(b); pt(c); pt(a); print ""; print ""
      }
    } else if (name[e] == "edge") {
      pt($1); pt($2); print ""; print ""
    }
  }
  function pt(k,   d, j, x, y, z) {
    if (eye == "") { print coord[k, 1], coord[k, 2], coord[k, 3]; return }
    x = y = z = 0
    for (j = 1; j <= 3; ++j) { d = coord[k, j] - E[j]; x += d * R[j]; y += d * U[j]; z += d * F[j] }
    if (z < 1e-9) z = 1e-9
    print x / z, y / z, -z
  }
  END { if (!bad && header) fail("no end_header") }
' "$ascii_file"
