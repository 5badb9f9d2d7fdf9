# damage.gp -- top view (x-z) of the disk coloured by damage.
# gnuplot -e "data='damage.dat'; out='damage.png'; step='2000'; code='pd'" damage.gp
# Colours as the seed's dump image (amap 0 1: min blue, 0.5 yellow, max red).
if (!exists("data")) data = 'damage.dat'
if (!exists("out")) out = 'damage.png'
if (!exists("step")) step = ''
if (!exists("code")) code = 'pd'
set terminal pngcairo size 900,820 font "Sans,11"
set output out
set title sprintf("%s: seed impact, top monolayer%s", code, step eq '' ? '' : ', step '.step)
set size ratio -1
set xlabel "x (mm)"
set ylabel "z (mm)"
set xrange [-40:40]
set yrange [-40:40]
set cblabel "damage"
set cbrange [0:1]
set palette defined (0 "blue", 0.5 "yellow", 1 "red")
set tics out
unset key
plot data using ($1*1e3):($2*1e3):3 with points pt 5 ps 0.45 lc palette
