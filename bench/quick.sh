#!/bin/sh
# make bench-quick: a < 5 minute tour of the benchmarks on the demo scene at 128x128 (2 cores):
# a 90 s path-tracer reference, the equal-time table (5 methods x 20 s), the convergence plot and a
# 30-frame transient curve (20 s). Results: bench/results/quick-*.{md,csv,png}.
set -eu
bin=${DARTSPP:-build/dartspp}
scene=scenes/fogbox/fogbox.json
mkdir -p refs bench/results
ref=refs/quick-fogbox128-pt.exr
if [ ! -f "$ref" ]; then
    echo "quick: 90 s path-tracer reference -> $ref"
    bench/reference.sh "$scene" 90 "$ref" --set resolution=128 > /dev/null
fi
echo "quick: equal time, 5 methods x 20 s"
bench/equal_time.sh "$scene" "$ref" 20 quick-fogbox 1 --set resolution=128
bench/plot_convergence.sh quick-fogbox "demo fog box 128x128, equal time 20 s"
echo "quick: transient curve, 30 frames"
bench/transient_curve.sh "$scene" 20 48 48 80 80 quick-fogbox --set resolution=128 \
    --set frame_num=30 --set start_time=4.5 --set transient_time_width=0.15
