# static.gp -- the mean axial stress in LPS, each case run dynamically
# (lines) and quasi-statically (points, pd-run --relax).
# gnuplot -e "out='static.png'; cases='iso alongx acrossx'" static.gp
set terminal pngcairo size 900,560
set output out
set xlabel 'time (ms): each end has moved 2 m/s x time'
set ylabel 'mean {/Symbol s}_{xx}, 100 < x < 200 mm (MPa)'
set title 'Beam in compression (lps): dynamic at 2 m/s (lines), quasi-static (points)'
set key bottom left
set grid
n = words(cases)
plot for [k=1:n] sprintf('stress-dynamic-%s.dat', word(cases, k)) w l lw 2 lc k \
         t sprintf('%s, dynamic', word(cases, k)), \
     for [k=1:n] sprintf('stress-static-%s.dat', word(cases, k)) w p pt 7 ps 1 lc k \
         t sprintf('%s, quasi-static', word(cases, k))
