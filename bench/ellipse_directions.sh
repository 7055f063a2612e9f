#!/bin/bash
# Per-pass variance and CPU time per pass of the DARTS path tracer with and without the directions toward the
# next elliptical connection (docs/darts.md §14.3), against the uniform-time path tracer, on a small render:
#   bench/ellipse_directions.sh [SCENE.json] [RES] [SPP] [SEEDS]   (defaults: the fog box, 64, 200, 12)
# SEED0 (default 1): the first seed; KEEP=DIR: the images are left in DIR (else a temporary folder, removed).
# Each method renders SEEDS independent images of SPP passes on one thread (nice 19, or NICE); the per-pixel variance of
# one image is the mean over seed pairs of `dartspp compare a b` MSE / 2 (MSE = mean over pixels and channels of
# (a − b)², whose expectation is twice the per-pixel variance), times SPP the per-pass variance. Time: user CPU
# seconds per pass (load-independent on a shared machine). METHODS="name|keys ..." overrides the set.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
scene=${1:-$root/scenes/cbox-fog/transient.json}
res=${2:-64}; spp=${3:-200}; seeds=${4:-12}
bin=${DARTSPP:-$root/build/dartspp}
first=${SEED0:-1}
if [ -n "${KEEP:-}" ]; then work=$KEEP; mkdir -p "$work"; else work=$(mktemp -d /tmp/ellip-dirs.XXXXXX); fi
pt="--set type=path_tracer --set eda=false"
darts="$pt --set enable_guiding=true --set enable_elliptical=true"
ell="$pt --set enable_guiding=false --set enable_elliptical=true"
default_methods="darts_no_dirs|$darts --set ellipse_directions=false
darts_dirs_0.25|$darts --set ellipse_direction_share=0.25
darts_dirs_0.5|$darts --set ellipse_direction_share=0.5
darts_dirs_0.75|$darts --set ellipse_direction_share=0.75
ell_no_dirs|$ell --set ellipse_directions=false
ell_dirs_0.5|$ell --set ellipse_direction_share=0.5
uniform_pt|$pt --set enable_guiding=false --set enable_elliptical=false --set time_sampling=uniform"
methods=${METHODS:-$default_methods}
names=(); keyset=()
while IFS='|' read -r name keys; do
    [ -n "$name" ] || continue
    names+=("$name"); keyset+=("$keys")
done <<< "$methods"
declare -A cpu
# seeds outermost, methods inside: a change of the machine's load falls on every method alike
for s in $(seq "$first" $((first + seeds - 1))); do
    for i in "${!names[@]}"; do
        name=${names[$i]}
        TIMEFORMAT=%U
        u=$( { time nice -n "${NICE:-19}" "$bin" render "$scene" ${keyset[$i]} --set resolution="$res" --spp "$spp" --threads 1 \
              --seed "$s" --output "$work/$name-$s.exr" --overwrite --no-cube --no-viewer --quiet >/dev/null 2>&1; } 2>&1 ) ||
            { echo "render failed: $name (${keyset[$i]})" >&2; exit 1; }
        cpu[$name]=$(awk -v a="${cpu[$name]:-0}" -v b="$u" 'BEGIN{print a+b}')
    done
done
# per_pass_variance: the mean over pairs (the variance, fireflies included); median_pair: the median pair's, the
# typical image without its rare outliers (the two differ where a few samples carry much of the variance)
echo "method,per_pass_variance,median_pair,cpu_s_per_pass,pairs,spp,res"
for name in "${names[@]}"; do
    for s in $(seq "$first" 2 $((first + seeds - 2))); do
        "$bin" compare "$work/$name-$s.exr" "$work/$name-$((s + 1)).exr" --csv | cut -d, -f1
    done | sort -g | awk -v n="$name" -v spp="$spp" -v c="${cpu[$name]}" -v k="$seeds" -v r="$res" \
        '{ v[NR] = $1; s += $1 } END { m = NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2;
           printf "%s,%.6g,%.6g,%.6g,%d,%d,%d\n", n, s / NR / 2 * spp, m / 2 * spp, c / (k * spp), NR, spp, r }'
done
[ -n "${KEEP:-}" ] || rm -rf "$work"
