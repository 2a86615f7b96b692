# bisector.gp: the bisector surface of two freeform surfaces (paper Sec. 3.3, Figure 8): the
# input surfaces S1, S2 in light lines, the bisector (mesh.ply, x y z = the bisector point P)
# shaded and bold. The view is the input's bounding box, slightly enlarged, so that far points of the
# untrimmed bisector (near the determinant's zero set) do not swamp the picture.
#   gnuplot -e "dir='results/bisector-fig8a'" experiments/gnuplot/bisector.gp
# writes results/bisector-fig8a/bisector.png (scripts/render.sh picks this script).
if (!exists("dir")) {
  print "bisector.gp: usage: gnuplot -e \"dir='RESULT_DIR'\" bisector.gp"
  exit status 2
}
problem = system("sed -n 's/.*\"problem\": *\"\\([^\"]*\\)\".*/\\1/p' '".dir."/summary.json' | head -n 1")
ply2dat = system("dirname '".ARG0."'")."/../../scripts/ply2dat.sh"
input = "< ".ply2dat." '".dir."/input.ply'"
mesh = "< ".ply2dat." --pm3d '".dir."/mesh.ply'"

# The view box: the input surfaces' bounding box grown by 0.15 times its diagonal.
stats input using 1 nooutput name "X"
stats input using 2 nooutput name "Y"
stats input using 3 nooutput name "Z"
grow = 0.15 * sqrt((X_max - X_min)**2 + (Y_max - Y_min)**2 + (Z_max - Z_min)**2)
set xrange [X_min - grow : X_max + grow]
set yrange [Y_min - grow : Y_max + grow]
set zrange [Z_min - grow : Z_max + grow]

set terminal pngcairo size 1200, 1000 font ",14"
set output dir."/bisector.png"
set title "bisector: ".problem noenhanced
set view 62, 35, 1.1
set view equal xyz
set xyplane 0
# Axes: a box with tics and labels, as in the paper's figures.
set border 4095 lw 0.5 lc rgb "#808080"
set tics font ",10"
set xlabel "x"; set ylabel "y"; set zlabel "z"
unset colorbox
# Lit and without edges (pm3d borders drew a dark mesh over the surface, in stripes on fine
# meshes); the legend beside the box, off the data.
set key outside right top
set pm3d depthorder noborder clip z
set pm3d lighting primary 0.5 specular 0.2
# Each triangle or segment is its own block: without this, splot joins blocks of equal length
# as a grid and draws spurious lines between separate parts.
set surface explicit
splot input with lines lc rgb "#b0b0b0" lw 0.7 title "S_1, S_2", \
      mesh with pm3d fillcolor rgb "#4a86d0" notitle, \
      keyentry with boxes fill solid 1.0 lc rgb "#4a86d0" title "bisector"
