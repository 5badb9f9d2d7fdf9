# cost.gp -- accuracy against cost: the error of the arrest length and of
# the largest crack speed (against the finest grid) against wall time.
# gnuplot -e "data='cost.txt'; out='cost.png'" cost.gp
# Reads cost.txt (convergence.py): dx_mm particles bonds steps wall_s
# updates_per_s peak_MiB arrest_mm speed_m_s err_arrest_mm err_speed_m_s.
if (!exists("data")) data = 'cost.txt'
if (!exists("out")) out = 'cost.png'
set terminal pngcairo size 900,600 font "Sans,11"
set output out
set title "What accuracy costs: error against the finest grid, by wall time"
set xlabel "wall time of pd-run (s)"
set ylabel "relative error"
set logscale xy
set key top right
set grid
plot data using 5:($10 > 0 ? $10/$8 : 1/0):(sprintf("%g mm", $1)) \
         with linespoints pt 7 ps 1.5 lw 2 title "arrest length Δa", \
     data using 5:($11 > 0 ? $11/$9 : 1/0) with linespoints pt 5 ps 1.5 lw 2 \
         title "largest crack speed", \
     data using 5:($10 > 0 ? $10/$8 : 1/0):(sprintf("%g mm", $1)) with labels offset 0,1 notitle
