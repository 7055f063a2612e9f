#!/bin/sh
# EDA on vs off at equal time: bench/eda.sh SECONDS SEEDS
# DARTS photon points (DA distance sampling, control vertices, strict time) with EDA direction sampling off
# and on for several α, on the demo fog box with Henyey–Greenstein g = 0.5 and g = −0.3 (128², variants
# written to refs/), and on the paper's fog Cornell box (512²). Error: each configuration's own variance at
# SECONDS, from the spread of its seeds (MSE between seeds 1 and 2, halved): EDA changes the sampling, not
# the kernels, so at equal time the variance is what differs. Table: bench/results/eda-equal-time.md.
set -eu
secs=${1:-20}; seeds=${2:-2}
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
out=bench/results/eda; mkdir -p "$out" refs
for g in 0.5 -0.3; do
    sed "s/\"g\": 0.3/\"g\": $g/" scenes/fogbox/fogbox.json > "refs/fogbox-g$g.json"
done
configs="off|--set eda=false
a0.25|--set eda=true --set eda_alpha=0.25
a0.5|--set eda=true --set eda_alpha=0.5
a1|--set eda=true --set eda_alpha=1"
table=bench/results/eda-equal-time.md
{
    echo "EDA on vs off, DARTS photon points, $secs s per run, $seeds seeds ($(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))"
    echo
    echo "| scene | EDA | iterations | photon paths | variance (seeds) | ÷ EDA off |"
    echo "|---|---|---|---|---|---|"
} > "$table"
for sc in "refs/fogbox-g0.5.json|fogbox g 0.5 (128²)|--set resolution=128" \
          "refs/fogbox-g-0.3.json|fogbox g −0.3 (128²)|--set resolution=128" \
          "../shared/scenes/cbox-trans/transient.json|cbox-trans, isotropic (512²)|"; do
    scene=${sc%%|*}; rest=${sc#*|}; label=${rest%%|*}; extra=${rest#*|}
    stem=$(basename "$scene" .json)
    # build the table first so that no run pays for it
    # shellcheck disable=SC2086
    "$bin" render "$scene" $extra --set eda=true --spp 1 --quiet --output "$out/$stem-warm.exr" > /dev/null
    voff=""
    echo "$configs" | while IFS='|' read -r name sets; do
        s=1
        while [ "$s" -le "$seeds" ]; do
            # shellcheck disable=SC2086
            "$bin" render "$scene" $extra $sets --time "$secs" --seed "$s" --quiet --output "$out/$stem-$name-s$s.exr" \
                > "$out/$stem-$name-s$s.txt"
            s=$((s + 1))
        done
        v=$("$bin" compare "$out/$stem-$name-s1.exr" "$out/$stem-$name-s2.exr" --csv | awk -F, '{ printf "%.6g", $1 / 2 }')
        [ "$name" = off ] && echo "$v" > "$out/$stem-voff"
        voff=$(cat "$out/$stem-voff")
        it=$(sed -n 's/^rendered \([0-9]*\) passes.*/\1/p' "$out/$stem-$name-s1.txt")
        pp=$(sed -n 's/^photon points: \([^ ]*\) photon paths.*/\1/p' "$out/$stem-$name-s1.txt")
        echo "| $label | $name | $it | $pp | $v | $(awk -v a="$v" -v b="$voff" 'BEGIN { printf "%.2f", a / b }') |" >> "$table"
    done
done
cat "$table"
