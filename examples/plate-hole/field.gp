# field.gp -- sigma_xx in the plate's mid-plane, the finest mesh run above
# the finest lattice run.
# gnuplot -e "mesh='slice-mesh-DX.txt'; lattice='slice-lattice-DX.txt'; out='field.png'" field.gp
# Reads cost.py --slice: x_mm y_mm sigma_xx_MPa.
if (!exists("out")) out = 'field.png'
set terminal pngcairo size 1000,900 font "Sans,11"
set output out
set multiplot layout 2,1 title "σ_{xx} in the mid-plane, the right grip pulled 1 µm (MPa)"
set size ratio -1
set xlabel "x (mm)"
set ylabel "y (mm)"
set cbrange [0:4]
set palette defined (0 "#30123b", 1 "#4686fb", 2 "#1ae4b6", 3 "#a2fc3c", 4 "#fabA39", 5 "#e4460a")
set title "gmsh tetrahedra (pd-mesh), particles at the cells' centroids"
plot mesh using 1:2:3 with points pt 7 ps 0.35 palette notitle
set title "lattice fill of the same surface (pd-lattice --inside)"
plot lattice using 1:2:3 with points pt 5 ps 0.35 palette notitle
unset multiplot
