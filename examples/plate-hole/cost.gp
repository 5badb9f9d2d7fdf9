# cost.gp -- accuracy against cost: the error of the grip's reaction
# (against its limit delta -> 0, cost.py) against pd-run's wall time, for the
# tetrahedral mesh and the lattice fill of the same part.
# gnuplot -e "data='cost.txt'; out='cost.png'" cost.gp
# Reads cost.txt (cost.py): kind dx_mm particles bonds volume_mm3
# iterations wall_s updates_per_s peak_MiB force_N err_finest err_limit.
if (!exists("data")) data = 'cost.txt'
if (!exists("out")) out = 'cost.png'
set terminal pngcairo size 900,600 font "Sans,11"
set output out
set title "A plate with a hole: the reaction's error against its limit δ → 0, by wall time"
set xlabel "wall time of pd-run (s)"
set ylabel "relative error of the reaction force"
set logscale xy
set key top right
set grid
plot data using ($12 > 0 && strcol(1) eq "mesh" ? $7 : 1/0):12 with linespoints pt 7 ps 1.5 \
         lw 2 title "gmsh tetrahedra (pd-mesh)", \
     data using ($12 > 0 && strcol(1) eq "lattice" ? $7 : 1/0):12 with linespoints pt 5 \
         ps 1.5 lw 2 title "lattice fill (pd-lattice --inside)", \
     data using ($12 > 0 ? $7 : 1/0):12:(sprintf("%.3g mm", $2)) with labels offset 0,1 notitle
