#!/bin/sh
# Two pulsed emitters: bench/two_pulses.sh [SECONDS] [SCENE]
# Renders scenes/fogbox/two-pulses.json (a light firing at 0, a second one with a box pulse over [1.5, 1.8))
# in its 40 frames with the path tracer, baseline photon points and DARTS photon points, SECONDS each
# (default 60), and plots the mean of a fog patch left of the centre and one right of it against time, one
# curve per integrator, into bench/results/two-pulses-transient.png (data: two-pulses-transient.csv). It also
# keeps the DARTS render's viewer page and takes a screenshot of it in headless chromium
# (bench/results/two-pulses-viewer.png).
set -eu
secs=${1:-60}
scene=${2:-scenes/fogbox/two-pulses.json}
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
res=bench/results
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# patches (128² image): fog in front of the left and the right half of the back wall
L="30 40 50 60"
R="78 40 98 60"
for m in pt baseline darts; do
    case $m in
        pt) set -- --set type=path_tracer ;;
        baseline) set -- --set enable_guiding=false --set enable_elliptical=false --set strict_time_width=false ;;
        darts) set -- ;;
    esac
    echo "two_pulses: $m, $secs s" >&2
    "$bin" render "$scene" --time "$secs" --quiet --seed 1 --output "$work/$m.exr" "$@" > "$work/$m.log"
done
csv=$res/two-pulses-transient.csv
echo "frame,t_start,t_end,pt_left,baseline_left,darts_left,pt_right,baseline_right,darts_right" > "$csv"
tail -n +2 "$work/darts_frames.csv" | while IFS=, read -r k t0 t1; do
    row="$k,$t0,$t1"
    for patch in "$L" "$R"; do
        for m in pt baseline darts; do
            f=$(printf '%s/%s_%04d.exr' "$work" "$m" "$k")
            # shellcheck disable=SC2086
            row="$row,$("$bin" patch-mean "$f" $patch)"
        done
    done
    echo "$row" >> "$csv"
done
command -v gnuplot > /dev/null || { apt-get update -qq && apt-get install -y -qq gnuplot-nox > /dev/null; }
gnuplot <<GP
set terminal pngcairo size 1000,520 noenhanced
set output '$res/two-pulses-transient.png'
set datafile separator ','
set grid
set key top right
set xlabel 'time (optical path length, camera-warped)'
set ylabel 'patch mean radiance'
set title 'two pulsed lights (first at 0, second a box over [1.5, 1.8)), $secs s per integrator, $(date -u +%Y-%m-%d)'
plot '$csv' using ((\$2+\$3)/2):4 skip 1 with steps lw 2 lc rgb '#444444' title 'left patch, path tracer', \
     '' using ((\$2+\$3)/2):5 skip 1 with steps lc rgb '#1f77b4' title 'left, baseline photon points', \
     '' using ((\$2+\$3)/2):6 skip 1 with steps lc rgb '#d62728' title 'left, DARTS', \
     '' using ((\$2+\$3)/2):7 skip 1 with steps lw 2 lc rgb '#999999' dt 2 title 'right patch, path tracer', \
     '' using ((\$2+\$3)/2):8 skip 1 with steps lc rgb '#17becf' dt 2 title 'right, baseline photon points', \
     '' using ((\$2+\$3)/2):9 skip 1 with steps lc rgb '#ff7f0e' dt 2 title 'right, DARTS'
GP
# the viewer of the DARTS frames, opened at the frame after the second pulse's arrival and a patch selected
if command -v chromium > /dev/null; then
    chromium --headless --no-sandbox --disable-gpu --no-first-run --disable-background-networking \
        --disable-component-update --disable-sync --user-data-dir="$work/chromium" --hide-scrollbars \
        --window-size=1100,760 --screenshot="$res/two-pulses-viewer.png" \
        "file://$(cd "$work" && pwd)/darts_viewer.html#x=88&y=50&frame=22" > /dev/null 2>&1 || echo "two_pulses: no screenshot" >&2
fi
echo "wrote $csv, $res/two-pulses-transient.png and $res/two-pulses-viewer.png"
for m in pt baseline darts; do printf '%s: ' "$m"; grep '^rendered' "$work/$m.log"; done
