# sweep-silhouette.gp: the perspective silhouette of a general swept volume (paper Sec. 3.2,
# Figure 7): the silhouette curves (mesh.ply, x y z = A(t)[S(u, v)] on equations (4) and (5))
# in bold over the moving body at five instants (input.ply), seen from the direction of the eye
# point (orthographic: gnuplot has no perspective view). The eye is read from
# experiments/problems/PROBLEM.toml (PROBLEM from summary.json) or given as eye='x y z';
# without it the view is a fixed oblique one. envelope='DIR' adds the envelope surface of a
# sweep-envelope result of the same body and motion, in light grey.
#   gnuplot -e "dir='results/sweep-silhouette-boomerang'" experiments/gnuplot/sweep-silhouette.gp
# writes results/sweep-silhouette-boomerang/sweep-silhouette.png (scripts/render.sh picks it).
if (!exists("dir")) {
  print "sweep-silhouette.gp: usage: gnuplot -e \"dir='RESULT_DIR'\" sweep-silhouette.gp"
  exit status 2
}
root = system("dirname '".ARG0."'")."/../.."
ply2dat = root."/scripts/ply2dat.sh"
body = "< ".ply2dat." --pm3d '".dir."/input.ply'"
curves = "< ".ply2dat." '".dir."/mesh.ply'"

# The eye point: given, or the `eye = [x, y, z]` line of the example problem file.
if (!exists("eye")) {
  problem = system("sed -n 's/.*\"problem\": *\"\\([^\"]*\\)\".*/\\1/p' '".dir."/summary.json' | head -n 1")
  eye = system("sed -n 's/^eye *= *\\[\\(.*\\)\\].*/\\1/p' '".root."/experiments/problems/".problem.".toml' 2>/dev/null | tr ',' ' '")
}

# The box: the body's instants and the curves.
stats body using 1:2 nooutput name "B"
stats body using 3 nooutput name "BZ"
stats curves using 1:2 nooutput name "C"
stats curves using 3 nooutput name "CZ"
min(a, b) = a < b ? a : b
max(a, b) = a > b ? a : b
x0 = min(B_min_x, C_min_x); x1 = max(B_max_x, C_max_x)
y0 = min(B_min_y, C_min_y); y1 = max(B_max_y, C_max_y)
z0 = min(BZ_min, CZ_min); z1 = max(BZ_max, CZ_max)
pad = 0.02 * sqrt((x1 - x0)**2 + (y1 - y0)**2 + (z1 - z0)**2)
set xrange [x0 - pad : x1 + pad]
set yrange [y0 - pad : y1 + pad]
set zrange [z0 - pad : z1 + pad]

# View from the eye: gnuplot's `set view rx, rz` looks from the direction
# (sin rx sin rz, -sin rx cos rz, cos rx); aim it from the box centre to the eye.
rx = 62; rz = 35; seen = "an oblique view"
if (words(eye) == 3) {
  dx = real(word(eye, 1)) - 0.5 * (x0 + x1)
  dy = real(word(eye, 2)) - 0.5 * (y0 + y1)
  dz = real(word(eye, 3)) - 0.5 * (z0 + z1)
  d = sqrt(dx**2 + dy**2 + dz**2)
  rx = acos(dz / d) * 180 / pi
  rz = atan2(dx, -dy) * 180 / pi
  rz = rz < 0 ? rz + 360 : rz
  seen = "seen from the eye (".eye.")"
}

set terminal pngcairo size 1200, 1000 font ",14"
set output dir."/sweep-silhouette.png"
set title "sweep-silhouette: ".dir.", ".seen noenhanced
set view rx, rz, 1.6
set view equal xyz
set xyplane 0
set surface explicit
unset border
unset tics
unset colorbox
set key top right
set pm3d depthorder border lw 0.1 lc rgb "#909090"
set pm3d lighting primary 0.55 specular 0.2
if (exists("envelope")) {
  splot "< ".ply2dat." --pm3d '".envelope."/mesh.ply'" with pm3d fillcolor rgb "#d8e4f0" \
        title "envelope", \
        body with pm3d fillcolor rgb "#f0d8b0" title "body, five instants", \
        curves with lines lc rgb "#c02020" lw 3 title "silhouette, (4) and (5)"
} else {
  splot body with pm3d fillcolor rgb "#f0d8b0" title "body, five instants", \
        curves with lines lc rgb "#c02020" lw 3 title "silhouette, (4) and (5)"
}
