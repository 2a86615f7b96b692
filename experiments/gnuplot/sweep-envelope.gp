# sweep-envelope.gp: the envelope of a general sweep (paper Sec. 3.4, Figure 9), in two panels
# like Fig. 9: (a) the moving body at five instants of its motion (input.ply, one part per
# instant) and (b) the envelope surface of the swept volume (mesh.ply, x y z = A(t)[S(u, v)]),
# shaded, with the instants in light grey (shaded too: `with lines` on ply2dat.sh's 4-point
# blocks lets splot join equal-length blocks as a grid).
#   gnuplot -e "dir='results/sweep-envelope-fig9'" experiments/gnuplot/sweep-envelope.gp
# writes results/sweep-envelope-fig9/sweep-envelope.png (scripts/render.sh picks this script).
if (!exists("dir")) {
  print "sweep-envelope.gp: usage: gnuplot -e \"dir='RESULT_DIR'\" sweep-envelope.gp"
  exit status 2
}
problem = system("sed -n 's/.*\"problem\": *\"\\([^\"]*\\)\".*/\\1/p' '".dir."/summary.json' | head -n 1")
ply2dat = system("dirname '".ARG0."'")."/../../scripts/ply2dat.sh"
input = "< ".ply2dat." '".dir."/input.ply'"
shaded = "< ".ply2dat." --pm3d '".dir."/input.ply'"
mesh = "< ".ply2dat." --pm3d '".dir."/mesh.ply'"

# One box for both panels: the bounding box of the body's instants and of the envelope.
stats input using 1:2 nooutput name "I"
stats input using 3 nooutput name "IZ"
stats mesh using 1:2 nooutput name "M"
stats mesh using 3 nooutput name "MZ"
min(a, b) = a < b ? a : b
max(a, b) = a > b ? a : b
x0 = min(I_min_x, M_min_x); x1 = max(I_max_x, M_max_x)
y0 = min(I_min_y, M_min_y); y1 = max(I_max_y, M_max_y)
z0 = min(IZ_min, MZ_min); z1 = max(IZ_max, MZ_max)
pad = 0.02 * sqrt((x1 - x0)**2 + (y1 - y0)**2 + (z1 - z0)**2)
set xrange [x0 - pad : x1 + pad]
set yrange [y0 - pad : y1 + pad]
set zrange [z0 - pad : z1 + pad]

set terminal pngcairo size 1800, 800 font ",14"
set output dir."/sweep-envelope.png"
set view 58, 28, 1.25
set view equal xyz
set xyplane 0
set surface explicit
# Axes: a box with tics and labels, as in the paper's figures.
set border 4095 lw 0.5 lc rgb "#808080"
set tics font ",10"
set xlabel "x"; set ylabel "y"; set zlabel "z"
unset colorbox
# Lit and without edges (pm3d borders drew a dark mesh over the surface, in stripes on fine
# meshes); the legend beside the box, off the data.
set key outside right top
set pm3d depthorder noborder
set pm3d lighting primary 0.5 specular 0.2
# The body touches the envelope along the characteristic curves: drawn a little farther from the
# viewer (along the view direction, so at the same place of the picture), it lies behind the
# envelope there, and depth sorting does not interleave their triangles in stripes.
vx = sin(58 * pi / 180) * sin(28 * pi / 180); vy = -sin(58 * pi / 180) * cos(28 * pi / 180)
vz = cos(58 * pi / 180); back = 0.03 * sqrt((x1 - x0)**2 + (y1 - y0)**2 + (z1 - z0)**2)
set multiplot layout 1, 2 title "sweep-envelope: ".problem noenhanced
set title "(a) the moving body A(t)[S]"
splot shaded with pm3d fillcolor rgb "#d08a3c" notitle, \
      keyentry with boxes fill solid 1.0 lc rgb "#d08a3c" title "five instants"
set title "(b) the envelope, equation (4)"
splot shaded using ($1 - back * vx):($2 - back * vy):($3 - back * vz) with pm3d fillstyle transparent solid 0.5 fillcolor rgb "#c8c8c8" notitle, \
      keyentry with boxes fill transparent solid 0.5 lc rgb "#c8c8c8" title "body", \
      mesh with pm3d fillcolor rgb "#4a86d0" notitle, \
      keyentry with boxes fill solid 1.0 lc rgb "#4a86d0" title "envelope"
unset multiplot
