#!/bin/sh
# Thread scaling of a render, phase by phase: bench/thread_scaling.sh OUTDIR [SCENE.json] [PASSES] [SEEDS]
#   [THREADS...]
# Renders SCENE (default the fog Cornell box at 512², scenes/cbox-fog/transient.json) PASSES passes (default 10)
# per run, SEEDS seeds (default 8), at each thread count (default 1 2 4 8 16), the order of the thread counts
# reversed on every other seed (a slow spell of the machine falls on all of them), and keeps each run's summary
# as OUTDIR/LABEL-tT-sS.txt (LABEL: $LABEL, default new). BINARIES="new:build/dartspp old:/path/to/dartspp"
# renders with several builds side by side, each run of one right after the same run of the other. Built for a
# many-core machine without the project's packages: copy the binaries and the libraries `ldd` lists (not libc)
# beside it and set LD_LIBRARY_PATH. bench/thread_table.py OUTDIR makes the table. Uses only the command line.
set -eu
[ $# -ge 1 ] || { echo "usage: $0 OUTDIR [SCENE.json] [PASSES] [SEEDS] [THREADS...]" >&2; exit 2; }
out=$1; scene=${2:-scenes/cbox-fog/transient.json}; passes=${3:-10}; seeds=${4:-8}
[ $# -ge 4 ] && shift 4 || shift $#
threads=${*:-1 2 4 8 16}
binaries=${BINARIES:-${LABEL:-new}:${DARTSPP:-build/dartspp}}
mkdir -p "$out"
{ date -u; grep -m1 'model name' /proc/cpuinfo; nproc; } > "$out/machine.txt"
reverse() { for x in "$@"; do r="$x ${r:-}"; done; echo "$r"; r=; }
s=1
while [ "$s" -le "$seeds" ]; do
    order=$threads
    [ $((s % 2)) = 0 ] && order=$(reverse $threads)
    for t in $order; do
        for b in $binaries; do
            label=${b%%:*}; bin=${b#*:}
            "$bin" render "$scene" --set resolution=512 --spp "$passes" --threads "$t" --seed "$s" \
                --output "$out/$label-t$t-s$s.exr" --quiet > "$out/$label-t$t-s$s.txt"
            rm -f "$out/$label-t$t-s$s.exr" "$out/$label-t$t-s$s.png"
        done
    done
    echo "seed $s of $seeds done" >&2
    s=$((s + 1))
done
