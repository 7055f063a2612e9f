#!/bin/sh
# Reference image of a scene: bench/reference.sh SCENE.json [SECONDS] [OUT.exr] [extra render args]
# Renders the scene with the reference path tracer (integrator type overridden) for SECONDS in all
# (default 600) on all cores, as CHUNKS (default 4) independent renders of SECONDS/CHUNKS with different
# seeds, merged by `dartspp merge` into OUT (default refs/<scene stem>-pt.exr).
# METHOD=scene renders with the scene file's own integrator instead (e.g. the paper's DARTS photon points,
# consistent: its radii shrink without end), for scenes where the path tracer cannot reach a useful noise
# level; check such a reference against the path tracer (bench/tile_check.py). PASSES=N makes each chunk
# N passes (--spp) instead of a wall time, so that the chunks can be paused (kill -STOP / -CONT) while the
# machine is needed for timing, and SECONDS is then only a label. The spread of the chunks
# gives the variance of the reference's own noise, written to OUT.var (one number, per channel value):
# every MSE measured against OUT is too high by about that much, and bench/equal_time.sh subtracts it.
# A sidecar OUT.txt records the command, date, machine and passes: the reference's cost.
# References live in refs/ (ignored by git).
set -eu
[ $# -ge 1 ] || { echo "usage: $0 SCENE.json [SECONDS] [OUT.exr] [render args...]" >&2; exit 2; }
scene=$1; secs=${2:-600}
stem=$(basename "$scene" .json)
out=${3:-refs/$stem-pt.exr}
[ $# -ge 3 ] && shift 3 || shift $#
chunks=${CHUNKS:-4}
[ "$chunks" -ge 2 ] || { echo "$0: CHUNKS must be at least 2 (the noise estimate needs a spread)" >&2; exit 2; }
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
mkdir -p "$(dirname "$out")"
log="$out.txt"
per=$(awk -v s="$secs" -v k="$chunks" 'BEGIN { printf "%g", s / k }')
case ${METHOD:-pt} in
pt) how="--set type=path_tracer"; what="path tracer" ;;
scene) how=""; what="the scene's own integrator" ;;
*) echo "$0: METHOD must be pt or scene" >&2; exit 2 ;;
esac
if [ -n "${PASSES:-}" ]; then budget="--spp $PASSES"; size="$PASSES passes"; else budget="--time $per"; size="$per s"; fi
{
    echo "reference: $scene, $what, $chunks chunks of $size"
    echo "date: $(date -u +%Y-%m-%dT%H:%MZ)  machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
    echo "command: $bin render $scene $how $budget --seed 7919+k --output ${out%.*}.chunkK.${out##*.} --quiet $*"
} > "$log"
parts=""
k=0
while [ "$k" -lt "$chunks" ]; do
    part="${out%.*}.chunk$k.${out##*.}"
    # shellcheck disable=SC2086
    "$bin" render "$scene" $how $budget --seed $((7919 + k)) --checkpoint 60 --output "$part" \
        --quiet "$@" | grep '^rendered' | sed "s/^/chunk $k: /" >> "$log"
    parts="$parts $part"
    k=$((k + 1))
done
# shellcheck disable=SC2086
"$bin" merge "$out" $parts | tee -a "$log" | sed -n 's/.*variance of the mean \([^ ]*\).*/\1/p' > "$out.var"
echo "reference noise (variance of the mean, per channel value): $(cat "$out.var")" | tee -a "$log"
