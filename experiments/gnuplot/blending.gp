# blending.gp: the blending surface of two freeform surfaces (paper Sec. 3.5, Figure 10): the
# input surfaces S1, S2 in light lines, the blend (mesh.ply, x y z = S1 + a1 N1) shaded and bold.
#   gnuplot -e "dir='results/blending-fig10a'" experiments/gnuplot/blending.gp
# writes results/blending-fig10a/blending.png (scripts/render.sh picks this script).
if (!exists("dir")) {
  print "blending.gp: usage: gnuplot -e \"dir='RESULT_DIR'\" blending.gp"
  exit status 2
}
problem = system("sed -n 's/.*\"problem\": *\"\\([^\"]*\\)\".*/\\1/p' '".dir."/summary.json' | head -n 1")
ply2dat = system("dirname '".ARG0."'")."/../../scripts/ply2dat.sh"
input = "< ".ply2dat." '".dir."/input.ply'"
mesh = "< ".ply2dat." --pm3d '".dir."/mesh.ply'"

# The view box: the input surfaces' bounding box grown by 0.02 times its diagonal.
stats input using 1 nooutput name "X"
stats input using 2 nooutput name "Y"
stats input using 3 nooutput name "Z"
grow = 0.02 * sqrt((X_max - X_min)**2 + (Y_max - Y_min)**2 + (Z_max - Z_min)**2)
set xrange [X_min - grow : X_max + grow]
set yrange [Y_min - grow : Y_max + grow]
set zrange [Z_min - grow : Z_max + grow]

set terminal pngcairo size 1200, 1000 font ",14"
set output dir."/blending.png"
set title "blending: ".problem noenhanced
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
set pm3d depthorder noborder
set pm3d lighting primary 0.5 specular 0.2
# Each triangle or segment is its own block: without this, splot joins blocks of equal length
# as a grid and draws spurious lines between separate parts.
set surface explicit
splot input with lines lc rgb "#b0b0b0" lw 0.7 title "S_1, S_2", \
      mesh with pm3d fillcolor rgb "#e08a3c" notitle, \
      keyentry with boxes fill solid 1.0 lc rgb "#e08a3c" title "blend S_1 + {/Symbol a}_1 N_1"
