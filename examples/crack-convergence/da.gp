# da.gp -- crack extension against time for every grid (seed 004 Fig. 7).
# gnuplot -e "grids='0.0005 0.00035 0.00025'; out='da.png'" da.gp
# Reads tip-DX.txt (pd-crack-tip): columns time_s, da_lower_m, da_upper_m;
# the curve is the mean of the two tips (the plate is symmetric).
if (!exists("grids")) grids = '0.0005 0.00035 0.00025'
if (!exists("out")) out = 'da.png'
set terminal pngcairo size 900,600 font "Sans,11"
set output out
set title "Centre-cracked plate (seed 004 section 5): crack growth per tip"
set xlabel "time (µs)"
set ylabel "Δa (mm)"
set key top left
set grid
set xrange [0:40]
plot for [g in grids] 'tip-'.g.'.txt' using ($2*1e6):(($5+$6)/2*1e3) \
     with steps lw 2 title sprintf("Δx = %g mm", g*1e3)
