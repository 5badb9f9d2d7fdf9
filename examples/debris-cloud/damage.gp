# damage.gp -- particles of a frame coloured by damage (frames.py tables).
# gnuplot -e "data='top.dat'; out='top.png'; title='...'; xlab='x (mm)';
#             ylab='y (mm)'; xr=40; ylo=-40; yhi=40" damage.gp
# Colours as lammps-impact's damage.gp (0 blue, 0.5 yellow, 1 red).
if (!exists("data")) data = 'top.dat'
if (!exists("out")) out = 'top.png'
if (!exists("title")) title = ''
if (!exists("xlab")) xlab = 'x (mm)'
if (!exists("ylab")) ylab = 'y (mm)'
if (!exists("xr")) xr = 40
if (!exists("ylo")) ylo = -40
if (!exists("yhi")) yhi = 40
if (!exists("ps")) ps = 0.45
set terminal pngcairo size 900,820 font "Sans,11"
set output out
set title title
set size ratio -1
set xlabel xlab
set ylabel ylab
set xrange [-xr:xr]
set yrange [ylo:yhi]
set cblabel "damage"
set cbrange [0:1]
set palette defined (0 "blue", 0.5 "yellow", 1 "red")
set tics out
unset key
plot data using ($1*1e3):($2*1e3):3 with points pt 5 ps ps lc palette
