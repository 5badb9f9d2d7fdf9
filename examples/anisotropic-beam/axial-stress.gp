# axial-stress.gp -- the mean axial stress of the five cases against time.
# gnuplot -e "out='axial-stress.png'; model='lps'" axial-stress.gp
set terminal pngcairo size 900,560
set output out
set xlabel 'time (ms)'
set ylabel 'mean {/Symbol s}_{xx}, 100 < x < 200 mm (MPa)'
set title sprintf('Beam in compression (%s): axial stress', model)
set key bottom left
set grid
plot 'stress-iso.dat' w lp pt 7 ps 0.5 t 'isotropic', \
     'stress-xy45.dat' w lp pt 7 ps 0.5 t 'u at 45° in x-y', \
     'stress-alongx.dat' w lp pt 7 ps 0.5 t 'u along x', \
     'stress-acrossx.dat' w lp pt 7 ps 0.5 t 'u along y (across x)', \
     'stress-two.dat' w lp pt 7 ps 0.5 t 'two: 45° in x-y and along y'
