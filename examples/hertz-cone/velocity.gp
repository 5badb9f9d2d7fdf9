# velocity.gp -- the projectile's velocity along z against time.
# gnuplot -e "data='velocity.dat'; out='velocity.png'" velocity.gp
if (!exists("data")) data = 'velocity.dat'
if (!exists("out")) out = 'velocity.png'
if (!exists("title")) title = 'projectile velocity'
set terminal pngcairo size 900,560 font "Sans,11"
set output out
set title title
set xlabel "time (µs)"
set ylabel "v_z (m/s)"
set grid
set key bottom right
set zeroaxis
plot data using 1:4 with linespoints pt 7 ps 0.6 lw 2 title "sphere v_z"
