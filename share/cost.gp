# cost.gp -- accuracy against cost for an example's `make convergence`: the
# relative errors of its figures against pd-run's wall time, one panel per
# sweep.  Reads cost.txt (share/pdcost.py's columns: sweep setting ...
# wall_s in column 7, then the example's figures and errors).
#
#   gnuplot -e "data='cost.txt'; out='cost.png'; title='...'; \
#       sweeps='safety skin'; names='time-step safety factor|contact skin / dx'; \
#       errs='13 14'; keys='broken bonds|damaged particles'" cost.gp
#
# sweeps: the values of column 1 to draw, one panel each (names: their axis
# titles, '|' between); errs: the columns of the relative errors (keys:
# their titles, '|' between).  An error of 0 (the reference itself)
# cannot sit on a log axis and is not drawn.  The sweeps listed in walls
# (optional) change no figure at all: their panel draws the wall time
# against the setting instead.  program (optional, default pd-run): whose
# wall time it is.
if (!exists("data")) data = 'cost.txt'
if (!exists("out")) out = 'cost.png'
if (!exists("title")) title = 'What accuracy costs'
if (!exists("walls")) walls = ''
if (!exists("program")) program = 'pd-run'
field(s, i) = (i == 1 ? (strstrt(s, "|") ? s[1:strstrt(s, "|") - 1] : s) : \
              field(s[strstrt(s, "|") + 1:], i - 1))
n = words(sweeps)
set terminal pngcairo size (n > 1 ? 1400 : 900), 600 font "Sans,11" noenhanced
set output out
set multiplot layout 1, n title title
set logscale xy
set grid
set format xy "%g"
if (!exists("keypos")) keypos = "bottom left"
eval("set key " . keypos)
y(c) = (column(c) > 0 ? column(c) : 1/0)
do for [i = 1:n] {
    s = word(sweeps, i)
    set title field(names, i)
    if (strstrt(" " . walls . " ", " " . s . " ")) {
        set xlabel "setting"
        set ylabel "wall time of " . program . " (s)"
        plot data using (strcol(1) eq s ? $2 : 1/0):7 with linespoints pt 7 ps 1.3 lw 2 \
                 title "every setting: the same figures"
        continue
    }
    set xlabel "wall time of " . program . " (s)"
    set ylabel "relative error"
    plot for [k = 1:words(errs)] data \
             using (strcol(1) eq s ? $7 : 1/0):(y(int(word(errs, k)))) \
             with linespoints pt 7 ps 1.3 lw 2 title field(keys, k), \
         data using (strcol(1) eq s ? $7 : 1/0):(y(int(word(errs, 1)))):(strcol(2)) \
             with labels offset 0, 1 notitle
}
unset multiplot
