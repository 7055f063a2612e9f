#!/bin/sh
# Convergence plot: bench/plot_convergence.sh NAME [TITLE]
# Draws MSE against render time on log-log axes from the logs bench/results/NAME/<method>-s1.csv written by
# equal_time.sh, into bench/results/NAME-convergence.png (gnuplot; installed from Debian when missing).
set -eu
name=$1; title=${2:-$1}
dir=bench/results/$name
command -v gnuplot > /dev/null || { apt-get update -qq && apt-get install -y -qq gnuplot-nox > /dev/null; }
plots=""
for m in path_tracer baseline elliptical_only da_only darts; do
    f=$dir/$m-s1.csv
    [ -f "$f" ] || continue
    plots="$plots${plots:+, }'$f' using 1:7 with linespoints pt 7 ps 0.5 title '$m'"
done
[ -n "$plots" ] || { echo "$0: no logs in $dir" >&2; exit 1; }
gnuplot <<GP
set terminal pngcairo size 900,600 noenhanced
set output '$dir-convergence.png'
set datafile separator ','
set key autotitle columnhead
set logscale xy
set grid
set xlabel 'render time (s)'
set ylabel 'MSE against the reference image'
set title '$title — $(date -u +%Y-%m-%d), $(nproc) cores'
plot $plots
GP
echo "wrote $dir-convergence.png"
