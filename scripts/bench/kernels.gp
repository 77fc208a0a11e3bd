# kernels.gp: cost of one evaluation against lattice size from
# `drape bench --kernels` (docs/performance.md): log-log, one line per
# kernel.  Writes OUT.png and OUT.svg.
#
#   gnuplot -e "csv='docs/performance/kernels.csv'; out='docs/performance/kernels'" \
#           scripts/bench/kernels.gp
if (!exists("machine")) machine = ""
set datafile separator ","
set datafile columnheaders
set logscale xy
set format x "10^{%T}"
set format y "10^{%T}"
set grid xtics ytics mxtics mytics lc rgb "#dddddd"
set key left top box
set xlabel "free particles"
set ylabel "CPU time per call (ms), min of 5 batches"
set title (machine eq "" ? "Kernels on square hang lattices" : "Kernels on square hang lattices\n{/*0.8 ".machine."}")
do for [fmt in "png svg"] {
    if (fmt eq "png") { set terminal pngcairo size 900,600 enhanced font ",10" } \
    else { set terminal svg size 900,600 enhanced font "sans,11" dynamic }
    set output out.".".fmt
    plot csv using (column("free_particles")):(column("rhs_ms")) with linespoints pt 7 title "right-hand side (forces)", \
         csv using (column("free_particles")):(column("jac_ms")) with linespoints pt 5 title "K and D", \
         csv using (column("free_particles")):(column("jac_first_order_ms")) with linespoints pt 9 title "first-order J", \
         csv using (column("free_particles")):(column("schur_factor_ms")) with linespoints pt 11 title "CHOLMOD factor of S", \
         csv using (column("free_particles")):(column("schur_solve_ms")) with linespoints pt 13 title "CHOLMOD solve with S"
    unset output
}
