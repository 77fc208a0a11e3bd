# wp.gp: one work-precision diagram from a `drape bench` CSV
# (docs/performance.md): error (x, log) against time (y, log), one line per
# integrator, sweep rows with status ok only.  Writes OUT.png and OUT.svg.
#
#   gnuplot -e "csv='docs/performance/cusick.csv'; out='docs/performance/cusick-pos'; \
#               err='err_pos_rel'; time='cpu_s'; integrators='cvode-bdf gsl-msbdf'; \
#               title='Cusick, 0.1 s'; xlabel='max position error / specimen size'; \
#               default='cvode-bdf'" scripts/bench/wp.gp
#
# Variables: csv, out, err (error column), time (wall_s or cpu_s),
# integrators (space-separated), title, xlabel, default (marked in the key),
# machine (a line under the title; may be empty), nopoints (integrators
# without a finished point, marked in the key).
if (!exists("time")) time = "cpu_s"
if (!exists("default")) default = ""
if (!exists("machine")) machine = ""
if (!exists("nopoints")) nopoints = ""
set datafile separator ","
set datafile columnheaders
set logscale xy
set format x "10^{%T}"
set format y "10^{%T}"
set grid xtics ytics mxtics mytics lc rgb "#dddddd"
set key outside right top box
set xlabel xlabel
set ylabel (time eq "cpu_s" ? "CPU time of the run (s), min over repeats" : "wall time of the run (s), min over repeats")
set title (machine eq "" ? title : title."\n{/*0.8 ".machine."}")
set xrange [*:*] reverse
ok(i) = strcol("role") eq "sweep" && strcol("status") eq "ok" && strcol("integrator") eq i && column(err) > 0
label(i) = i . (i eq default ? " (default)" : "") . (i eq "gsl-msbdf" ? " (paper: Gear)" : "") \
           . (strstrt(" ".nopoints." ", " ".i." ") > 0 ? ": no point finished" : "")
do for [fmt in "png svg"] {
    if (fmt eq "png") { set terminal pngcairo size 900,600 enhanced font ",10" } \
    else { set terminal svg size 900,600 enhanced font "sans,11" dynamic }
    set output out.".".fmt
    plot for [i in integrators] csv using (ok(i) ? column(err) : NaN):(ok(i) ? column(time) : NaN) \
         with linespoints lw (i eq default ? 3 : 1.5) pt 7 ps 0.8 title label(i)
    unset output
}
