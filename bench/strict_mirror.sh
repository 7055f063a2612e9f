#!/bin/sh
# What strict time mode costs on mirrors: bench/strict_mirror.sh [SECONDS] [REF_SECONDS]
# The demo fog box with its back wall made a mirror (refs/fogbox-mirror.json, 128²). The camera sees the
# room and the fog through the mirror, where the camera leg is longer than the straight line the DARTS
# time bounds assume. Renders a path-tracer reference (REF_SECONDS, default 240) and, for SECONDS each
# (default 30), baseline photon points and DARTS photon points with strict time on and off, and prints the
# mean of the mirror's image region [44, 84) × [36, 76) and of the whole image against the reference.
set -eu
secs=${1:-30}; rsecs=${2:-240}
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
out=bench/results/strict-mirror; mkdir -p "$out" refs
scene=refs/fogbox-mirror.json
awk '/"name": "back"/ { back = 1 } back && /"bsdf": "white"/ { sub(/"white"/, "{ \"type\": \"mirror\" }"); back = 0 } { print }' \
    scenes/fogbox/fogbox.json > "$scene"
grep -q mirror "$scene" || { echo "$0: could not make the back wall a mirror" >&2; exit 1; }
ref=refs/fogbox-mirror-pt.exr
[ -f "$ref" ] || CHUNKS=2 bench/reference.sh "$scene" "$rsecs" "$ref" --set resolution=128 > /dev/null
table=bench/results/strict-mirror.md
{
    echo "Strict time mode on a mirror: \`$scene\` (back wall a mirror), 128², $secs s per run, against a $rsecs s path-tracer reference"
    echo "($(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))"
    echo
    echo "| method | mirror region mean ÷ reference | image mean ÷ reference | MSE |"
    echo "|---|---|---|---|"
    rm_=$("$bin" patch-mean "$ref" 44 36 84 76); rall=$("$bin" patch-mean "$ref" 0 0 128 128)
    for m in "baseline|--set enable_guiding=false --set enable_elliptical=false" \
             "DARTS, strict on|--set strict_time_width=true" \
             "DARTS, strict off|--set strict_time_width=false"; do
        name=${m%%|*}; sets=${m#*|}
        f="$out/$(echo "$name" | tr -c 'a-z' '_').exr"
        # shellcheck disable=SC2086
        "$bin" render "$scene" --set resolution=128 $sets --time "$secs" --quiet --output "$f" > /dev/null
        mm=$("$bin" patch-mean "$f" 44 36 84 76); ma=$("$bin" patch-mean "$f" 0 0 128 128)
        mse=$("$bin" compare "$f" "$ref" --csv | cut -d, -f1)
        awk -v n="$name" -v a="$mm" -v b="$rm_" -v c="$ma" -v d="$rall" -v e="$mse" \
            'BEGIN { printf "| %s | %.3f | %.3f | %.4g |\n", n, a / b, c / d, e }'
    done
    echo
    echo "Reference noise V_ref = $(cat "$ref.var")."
} | tee "$table"
