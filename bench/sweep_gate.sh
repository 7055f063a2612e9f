#!/bin/sh
# A sweep of the DARTS paper (paper §6.3, its Fig. 10: gate width, from delta-like to steady-like) on one scene:
# bench/sweep_gate.sh SCENE.json SECONDS SEEDS WIDTH... [-- render args...]
# For each gate width (centred on the scene's gate centre) every method of bench/compare_methods.sh renders
# for SECONDS, SEEDS seeds (>= 2), alternating; the table gives each method's variance at equal time from the
# spread of its seeds (half the MSE between seeds 1 and 2: no reference needed, which is the whole error of
# the unbiased path tracers; the photon methods' kernel bias is not in it) and its ratio to DARTS PT's.
# Output: bench/results/NAME-gate-sweep-SECONDSs.md (NAME = scene stem, or $NAME). Uses only the command line.
set -eu
[ $# -ge 4 ] || { echo "usage: $0 SCENE.json SECONDS SEEDS WIDTH... [-- render args...]" >&2; exit 2; }
scene=$1; secs=$2; seeds=$3; shift 3
[ "$seeds" -ge 2 ] || { echo "$0: SEEDS must be at least 2 (the variance comes from their spread)" >&2; exit 2; }
widths=""
while [ $# -gt 0 ] && [ "$1" != -- ]; do widths="$widths $1"; shift; done
[ $# -gt 0 ] && shift
name=${NAME:-$(basename "$scene" .json)}
bin=${DARTSPP:-build/dartspp}
table=bench/results/$name-gate-sweep-${secs}s.md
only=${METHODS:-uniform_pt pt darts_pt darts_pp}
rows=""
for w in $widths; do
    NAME_W="$name-gate-$w"
    METHODS="$only" bench/compare_methods.sh "$scene" "$secs" "$seeds" - "$NAME_W" --set transient_time_width="$w" "$@" \
        > /dev/null
    rows="$rows $w"
done
{
    echo "Gate-width sweep: \`$scene\` ${*:+(\`$*\`) }$secs s per run, $seeds seeds, variance from the seeds' spread"
    echo "($(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))"
    echo
    printf "| gate width |"; for m in $only; do printf " %s: variance (÷ DARTS PT) |" "$m"; done; echo
    printf "|---|"; for m in $only; do printf -- "---|"; done; echo
    for w in $rows; do
        sum=bench/results/$name-gate-$w/summary.txt
        d=$(awk '$1 == "darts_pt" { print $5 }' "$sum")
        printf "| %s |" "$w"
        for m in $only; do
            awk -v m="$m" -v d="$d" '$1 == m { printf(" %s (%s) |", $5, (d + 0 > 0 && $5 != "-") ? sprintf("%.2f", $5 / d) : "-") }' "$sum"
        done
        echo
    done
} | tee "$table"
