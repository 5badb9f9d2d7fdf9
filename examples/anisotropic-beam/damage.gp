# damage.gp -- damage in the mid-height plane of the beam, deformed.
# gnuplot -e "data='slice-iso.dat'; out='damage-iso.png'; title='iso'" damage.gp
set terminal pngcairo size 1100,260
set output out
set xlabel 'x (mm)'
set ylabel 'y (mm)'
set title sprintf('damage, mid-height plane: %s', title)
set size ratio -1
set cbrange [0:1]
set palette defined (0 '#2c4a8a', 0.3 '#7fb3d5', 0.6 '#f4d03f', 1 '#c0392b')
unset key
plot data u 1:2:3 w p pt 5 ps 0.6 lc palette
