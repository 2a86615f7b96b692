# convex-hull.gp: bitangent planes of two freeform surfaces (paper Sec. 3.1, Figure 6): the input
# surfaces S1, S2 in light lines, the bitangent segments S1(u, v) - S2(s, t) (the developable
# pieces of the convex hull) in thin lines, and the contact curves on both surfaces in bold
# (mesh.ply: x y z = S1(u, v), x2 y2 z2 = S2(s, t)).
#   gnuplot -e "dir='results/convex-hull-bumps'" experiments/gnuplot/convex-hull.gp
# writes results/convex-hull-bumps/convex-hull.png (scripts/render.sh picks this script).
if (!exists("dir")) {
  print "convex-hull.gp: usage: gnuplot -e \"dir='RESULT_DIR'\" convex-hull.gp"
  exit status 2
}
problem = system("sed -n 's/.*\"problem\": *\"\\([^\"]*\\)\".*/\\1/p' '".dir."/summary.json' | head -n 1")
ply2dat = system("dirname '".ARG0."'")."/../../scripts/ply2dat.sh"
input = "< ".ply2dat." '".dir."/input.ply'"
ruling = "< ".ply2dat." --ruling '".dir."/mesh.ply'"
contact1 = "< ".ply2dat." '".dir."/mesh.ply'"
contact2 = "< ".ply2dat." --props x2,y2,z2 '".dir."/mesh.ply'"

# The view box: the input surfaces' bounding box grown by 0.02 times its diagonal.
stats input using 1 nooutput name "X"
stats input using 2 nooutput name "Y"
stats input using 3 nooutput name "Z"
grow = 0.02 * sqrt((X_max - X_min)**2 + (Y_max - Y_min)**2 + (Z_max - Z_min)**2)
set xrange [X_min - grow : X_max + grow]
set yrange [Y_min - grow : Y_max + grow]
set zrange [Z_min - grow : Z_max + grow]

set terminal pngcairo size 1200, 1000 font ",14"
set output dir."/convex-hull.png"
set title "convex hull (bitangent planes): ".problem noenhanced
set view 62, 35, 1.1
set view equal xyz
set xyplane 0
# Axes: a box with tics and labels, as in the paper's figures.
set border 4095 lw 0.5 lc rgb "#808080"
set tics font ",10"
set xlabel "x"; set ylabel "y"; set zlabel "z"
# The legend beside the box, off the data.
set key outside right top
# Each triangle or segment is its own block: without this, splot joins blocks of equal length
# as a grid and draws spurious lines between separate parts.
set surface explicit
splot input with lines lc rgb "#c0c0c0" lw 0.7 title "S_1, S_2", \
      ruling with lines lc rgb "#4a86d0" lw 0.8 title "bitangent segments", \
      contact1 with lines lc rgb "#c02020" lw 3 title "contact curves", \
      contact2 with lines lc rgb "#c02020" lw 3 notitle
