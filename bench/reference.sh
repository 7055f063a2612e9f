#!/bin/sh
# Path-tracer reference image of a scene: bench/reference.sh SCENE.json [SECONDS] [OUT.exr] [extra render args]
# Renders the scene with the reference path tracer (integrator type overridden) for SECONDS (default 600)
# on all cores, with checkpoints every minute, and writes OUT (default refs/<scene stem>-pt.exr) plus a
# sidecar OUT.txt recording the command, date, machine, passes and time: the reference's cost.
# References live in refs/ (ignored by git).
set -eu
[ $# -ge 1 ] || { echo "usage: $0 SCENE.json [SECONDS] [OUT.exr] [render args...]" >&2; exit 2; }
scene=$1; secs=${2:-600}
stem=$(basename "$scene" .json)
out=${3:-refs/$stem-pt.exr}
[ $# -ge 3 ] && shift 3 || shift $#
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
mkdir -p "$(dirname "$out")"
log="$out.txt"
{
    echo "reference: $scene, path tracer, $secs s"
    echo "date: $(date -u +%Y-%m-%dT%H:%MZ)  machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
    echo "command: $bin render $scene --set type=path_tracer --time $secs --seed 7919 --checkpoint 60 --output $out --quiet $*"
} > "$log"
"$bin" render "$scene" --set type=path_tracer --time "$secs" --seed 7919 --checkpoint 60 --output "$out" --quiet "$@" | tee -a "$log"
