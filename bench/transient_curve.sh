#!/bin/sh
# Transient curve: bench/transient_curve.sh SCENE.json SECONDS X0 Y0 X1 Y1 [NAME] [render args...]
# Renders the scene's frames (the scene must set frame_num) and plots the mean of the pixel patch
# [X0, X1) × [Y0, Y1) of every frame against time, into bench/results/NAME-transient.png and .csv.
set -eu
[ $# -ge 6 ] || { echo "usage: $0 SCENE.json SECONDS X0 Y0 X1 Y1 [NAME] [render args...]" >&2; exit 2; }
scene=$1; secs=$2; x0=$3; y0=$4; x1=$5; y1=$6; name=${7:-$(basename "$scene" .json)}
[ $# -ge 7 ] && shift 7 || shift $#
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
out=bench/results/$name-transient; mkdir -p "$out"
"$bin" render "$scene" --time "$secs" --quiet --output "$out/frame.exr" "$@" > /dev/null
[ -f "$out/frame_frames.csv" ] || { echo "$0: $scene rendered no frames (set frame_num)" >&2; exit 1; }
csv=bench/results/$name-transient.csv
echo "frame,t_start,t_end,patch_mean" > "$csv"
tail -n +2 "$out/frame_frames.csv" | while IFS=, read -r k t0 t1; do
    f=$(ls "$out"/frame_*[0-9].exr | sed -n "$((k + 1))p")
    m=$("$bin" patch-mean "$f" "$x0" "$y0" "$x1" "$y1")
    echo "$k,$t0,$t1,$m" >> "$csv"
done
command -v gnuplot > /dev/null || { apt-get update -qq && apt-get install -y -qq gnuplot-nox > /dev/null; }
gnuplot <<GP
set terminal pngcairo size 900,500 noenhanced
set output 'bench/results/$name-transient.png'
set datafile separator ','
set grid
set xlabel 'time (optical path length, camera-warped)'
set ylabel 'patch mean radiance'
set title '$name: patch [$x0,$x1)x[$y0,$y1), $(date -u +%Y-%m-%d)'
plot '$csv' using ((\$2+\$3)/2):4 skip 1 with steps title 'frame mean'
GP
echo "wrote $csv and bench/results/$name-transient.png"
