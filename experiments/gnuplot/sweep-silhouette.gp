# sweep-silhouette.gp: the perspective silhouette of a general swept volume (paper Sec. 3.2,
# Figure 7): the silhouette curves (mesh.ply, x y z = A(t)[S(u, v)] on equations (4) and (5))
# in bold on the envelope of the swept volume, with the moving body at five instants
# (input.ply), in perspective from the eye point. Gnuplot only draws orthographic views, so
# scripts/ply2dat.sh --eye projects every point through the eye and the plot looks straight down
# the projected depth axis. The eye is read from experiments/problems/PROBLEM.toml (PROBLEM from
# summary.json) or given as eye='x y z'; without it the view is a fixed oblique orthographic one.
# The envelope is mesh.ply of a surface result over the same body and motion (an identical
# input.ply, e.g. sweep-envelope-fig9 for sweep-silhouette-boomerang) found beside DIR, or given
# as envelope='DIR'.
#   gnuplot -e "dir='results/sweep-silhouette-boomerang'" experiments/gnuplot/sweep-silhouette.gp
# writes results/sweep-silhouette-boomerang/sweep-silhouette.png (scripts/render.sh picks it).
if (!exists("dir")) {
  print "sweep-silhouette.gp: usage: gnuplot -e \"dir='RESULT_DIR'\" sweep-silhouette.gp"
  exit status 2
}
root = system("dirname '".ARG0."'")."/../.."
ply2dat = root."/scripts/ply2dat.sh"
problem = system("sed -n 's/.*\"problem\": *\"\\([^\"]*\\)\".*/\\1/p' '".dir."/summary.json' | head -n 1")

# The eye point: given, or the `eye = [x, y, z]` line of the example problem file.
if (!exists("eye")) {
  eye = system("sed -n 's/^eye *= *\\[\\(.*\\)\\].*/\\1/p' '".root."/experiments/problems/".problem.".toml' 2>/dev/null | tr ',' ' '")
}
# The envelope: a sibling result (results/NAME/ or results/fig-app-*/runs/RUN/) with the same
# input.ply whose mesh.ply has faces.
if (!exists("envelope")) {
  envelope = system("for d in '".dir."'/../*/ '".dir."'/../../../fig-app-*/runs/*/; do [ \"$(cd \"$d\" 2>/dev/null && pwd)\" != \"$(cd '".dir."' && pwd)\" ] && cmp -s \"$d/input.ply\" '".dir."/input.ply' && head -c 400 \"$d/mesh.ply\" | grep -a -q '^element face' && { echo \"${d%/}\"; break; }; done")
}

# The box of the body's instants and the curves (world coordinates): its centre is the target.
raw = "< ".ply2dat." '".dir."/input.ply'"
stats raw using 1:2 nooutput name "B"
stats raw using 3 nooutput name "BZ"
target = sprintf("%.9g,%.9g,%.9g", 0.5 * (B_min_x + B_max_x), 0.5 * (B_min_y + B_max_y), 0.5 * (BZ_min + BZ_max))
perspective = words(eye) == 3
project = perspective ? " --eye ".word(eye, 1).",".word(eye, 2).",".word(eye, 3)." --target ".target : ""
body = "< ".ply2dat.project." --pm3d '".dir."/input.ply'"
curves = "< ".ply2dat.project." '".dir."/mesh.ply'"
shell = "< ".ply2dat.project." --pm3d '".envelope."/mesh.ply'"

set terminal pngcairo size 1200, 1000 font ",14"
set output dir."/sweep-silhouette.png"
set xyplane 0
set surface explicit
unset colorbox
# The legend beside the picture, off the data; surfaces lit.
set key outside right top samplen 2
set pm3d depthorder noborder
set pm3d lighting primary 0.5 specular 0.2
if (perspective) {
  set title problem.": perspective from the eye (".eye.")" noenhanced
  # Looking down the projected depth axis shows the perspective picture; the image axes are
  # not world axes, so the world axes are drawn as a projected frame instead.
  set view 0, 0, 1.7
  set view equal xy
  unset border
  unset tics
  # The camera of scripts/ply2dat.sh --eye, to draw the world axes x, y, z from the box's
  # lowest corner as a projected frame with their end values.
  ex = real(word(eye, 1)); ey = real(word(eye, 2)); ez = real(word(eye, 3))
  fx = 0.5 * (B_min_x + B_max_x) - ex; fy = 0.5 * (B_min_y + B_max_y) - ey; fz = 0.5 * (BZ_min + BZ_max) - ez
  fn = sqrt(fx**2 + fy**2 + fz**2); fx = fx / fn; fy = fy / fn; fz = fz / fn
  rn = sqrt(fx**2 + fy**2); rx = fy / rn; ry = -fx / rn; rz = 0
  ux = ry * fz - rz * fy; uy = rz * fx - rx * fz; uz = rx * fy - ry * fx
  depth(x, y, z) = (x - ex) * fx + (y - ey) * fy + (z - ez) * fz
  px(x, y, z) = ((x - ex) * rx + (y - ey) * ry + (z - ez) * rz) / depth(x, y, z)
  py(x, y, z) = ((x - ex) * ux + (y - ey) * uy + (z - ez) * uz) / depth(x, y, z)
  pz(x, y, z) = -depth(x, y, z)
  ox = B_min_x; oy = B_min_y; oz = BZ_min
  set arrow 1 from px(ox, oy, oz), py(ox, oy, oz), pz(ox, oy, oz) to px(B_max_x, oy, oz), py(B_max_x, oy, oz), pz(B_max_x, oy, oz) lw 1.5 lc rgb "#404040" front
  set arrow 2 from px(ox, oy, oz), py(ox, oy, oz), pz(ox, oy, oz) to px(ox, B_max_y, oz), py(ox, B_max_y, oz), pz(ox, B_max_y, oz) lw 1.5 lc rgb "#404040" front
  set arrow 3 from px(ox, oy, oz), py(ox, oy, oz), pz(ox, oy, oz) to px(ox, oy, BZ_max), py(ox, oy, BZ_max), pz(ox, oy, BZ_max) lw 1.5 lc rgb "#404040" front
  set label 1 sprintf("x = %.2g", B_max_x) at px(B_max_x, oy, oz), py(B_max_x, oy, oz), pz(B_max_x, oy, oz) offset 0.5, 0 front
  set label 2 sprintf("y = %.2g", B_max_y) at px(ox, B_max_y, oz), py(ox, B_max_y, oz), pz(ox, B_max_y, oz) offset 0.5, 0 front
  set label 3 sprintf("z = %.2g", BZ_max) at px(ox, oy, BZ_max), py(ox, oy, BZ_max), pz(ox, oy, BZ_max) offset 0.5, 0 front
  set label 4 sprintf("(%.2g, %.2g, %.2g)", ox, oy, oz) at px(ox, oy, oz), py(ox, oy, oz), pz(ox, oy, oz) offset -2, -1 front
} else {
  set title problem.": an oblique view" noenhanced
  set view 62, 35, 1.0
  set view equal xyz
  set border 4095 lw 0.5 lc rgb "#808080"
  set xlabel "x"; set ylabel "y"; set zlabel "z"
}
# The body touches the envelope along the characteristic curves: drawn a little farther from the
# viewer (along the view direction, so at the same place of the picture), it lies behind the
# envelope there, and depth sorting does not interleave their triangles in stripes.
back = 0.01 * sqrt((B_max_x - B_min_x)**2 + (B_max_y - B_min_y)**2 + (BZ_max - BZ_min)**2)
vx = perspective ? 0 : sin(62 * pi / 180) * sin(35 * pi / 180)
vy = perspective ? 0 : -sin(62 * pi / 180) * cos(35 * pi / 180)
vz = perspective ? 1 : cos(62 * pi / 180)
if (strlen(envelope) > 0) {
  splot shell with pm3d fillstyle transparent solid 0.6 fillcolor rgb "#9ecae1" notitle, \
        keyentry with boxes fill transparent solid 0.6 lc rgb "#9ecae1" title "envelope of the swept volume", \
        body using ($1 - back * vx):($2 - back * vy):($3 - back * vz) with pm3d fillcolor rgb "#f0d8b0" notitle, \
        keyentry with boxes fill solid 1.0 lc rgb "#f0d8b0" title "body, five instants", \
        curves with lines lc rgb "#a50f15" lw 4 title "silhouette, (4) and (5)"
} else {
  splot body with pm3d fillcolor rgb "#f0d8b0" notitle, \
        keyentry with boxes fill solid 1.0 lc rgb "#f0d8b0" title "body, five instants", \
        curves with lines lc rgb "#a50f15" lw 4 title "silhouette, (4) and (5)"
}
