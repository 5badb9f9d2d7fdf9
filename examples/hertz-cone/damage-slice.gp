# damage-slice.gp -- a cross-section (x-z) of the cylinder coloured by damage.
# gnuplot -e "data='slice.dat'; out='damage-slice.png'; step='1000'" damage-slice.gp
# Colours as lammps-impact's damage.gp (0 blue, 0.5 yellow, 1 red).
if (!exists("data")) data = 'slice.dat'
if (!exists("out")) out = 'damage-slice.png'
if (!exists("step")) step = ''
if (!exists("title")) title = 'Hertzian cone: cross-section through the axis'
if (!exists("xr")) xr = 18
if (!exists("zlo")) zlo = -26
if (!exists("zhi")) zhi = 1
set terminal pngcairo size 900,760 font "Sans,11"
set output out
set title sprintf("%s%s", title, step eq '' ? '' : ', step '.step)
set size ratio -1
set xlabel "x (mm)"
set ylabel "z (mm)"
set xrange [-xr:xr]
set yrange [zlo:zhi]
set cblabel "damage"
set cbrange [0:1]
set palette defined (0 "blue", 0.5 "yellow", 1 "red")
set tics out
unset key
plot data using ($1*1e3):($2*1e3):3 with points pt 5 ps 0.55 lc palette
