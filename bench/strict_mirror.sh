#!/bin/sh
# What strict time mode costs on mirrors: bench/strict_mirror.sh [SECONDS] [REF_SECONDS]
# The demo fog box with its back wall made a mirror (refs/fogbox-mirror.json, 128²). The camera sees the
# room and the fog through the mirror, where the camera leg is longer than the straight line the DARTS
# time bounds assume. The reference is baseline photon points run for REF_SECONDS (default 300): the path
# tracer cannot be the reference here, since it cannot connect to the point light through the mirror and
# so misses all light the mirror reflects before a diffuse or medium vertex; its 240 s image is shown as
# a row to measure that gap. For SECONDS each (default 30): baseline photon points (another seed) and
# DARTS photon points with strict time on and off; prints the mean of a central patch of the mirror's
# image [44, 84) × [36, 76) and of the whole image, each divided by the reference's.
set -eu
secs=${1:-30}; rsecs=${2:-300}
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
out=bench/results/strict-mirror; mkdir -p "$out" refs
scene=refs/fogbox-mirror.json
awk '/"name": "back"/ { back = 1 } back && /"bsdf": "white"/ { sub(/"white"/, "{ \"type\": \"mirror\" }"); back = 0 } { print }' \
    scenes/fogbox/fogbox.json > "$scene"
grep -q mirror "$scene" || { echo "$0: could not make the back wall a mirror" >&2; exit 1; }
base="--set enable_guiding=false --set enable_elliptical=false"
ref=refs/fogbox-mirror-pp$rsecs.exr
# shellcheck disable=SC2086
[ -f "$ref" ] || "$bin" render "$scene" --set resolution=128 $base --seed 7 --time "$rsecs" --quiet --output "$ref" > /dev/null
pt=refs/fogbox-mirror-pt.exr
[ -f "$pt" ] || CHUNKS=2 bench/reference.sh "$scene" 240 "$pt" --set resolution=128 > /dev/null
table=bench/results/strict-mirror.md
rm -f "$out"/*.exr "$out"/*.png
row() { # name image
    mm=$("$bin" patch-mean "$2" 44 36 84 76); ma=$("$bin" patch-mean "$2" 0 0 128 128)
    mse=$("$bin" compare "$2" "$ref" --csv | cut -d, -f1)
    awk -v n="$1" -v a="$mm" -v b="$rm_" -v c="$ma" -v d="$rall" -v e="$mse" \
        'BEGIN { printf "| %s | %.3f | %.3f | %.4g |\n", n, a / b, c / d, e }'
}
{
    echo "Strict time mode on a mirror: \`$scene\` (back wall a mirror), 128², $secs s per run, against $rsecs s of"
    echo "baseline photon points ($(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))"
    echo
    echo "| method | mirror patch mean ÷ reference | image mean ÷ reference | MSE |"
    echo "|---|---|---|---|"
    rm_=$("$bin" patch-mean "$ref" 44 36 84 76); rall=$("$bin" patch-mean "$ref" 0 0 128 128)
    row "path tracer, 240 s (no light via the mirror)" "$pt"
    for m in "baseline|baseline|$base" \
             "darts-strict|DARTS, strict on|--set strict_time_width=true" \
             "darts|DARTS, strict off|--set strict_time_width=false" \
             "da-only|DA distance sampling only, strict off|--set enable_elliptical=false --set strict_time_width=false"; do
        slug=${m%%|*}; rest=${m#*|}; name=${rest%%|*}; sets=${rest#*|}
        f="$out/$slug.exr"
        # shellcheck disable=SC2086
        "$bin" render "$scene" --set resolution=128 $sets --time "$secs" --quiet --output "$f" > /dev/null 2>&1
        row "$name, $secs s" "$f"
    done
} | tee "$table"
