#!/bin/sh
# Photon-count study: bench/photon_count.sh SCENE.json REFERENCE.exr SECONDS [NAME] [EXTRA --set ARGS...]
# Sweeps photons per iteration (photon_count × volume_photon_count) at equal time with DARTS photon points
# (or whatever the extra --set arguments select) and prints a Markdown table of the final errors, also
# written to bench/results/NAME-photon-count.md. Uses only the command line.
set -eu
[ $# -ge 3 ] || { echo "usage: $0 SCENE.json REFERENCE.exr SECONDS [NAME] [--set k=v ...]" >&2; exit 2; }
scene=$1; ref=$2; secs=$3; name=${4:-$(basename "$scene" .json)}
[ $# -ge 4 ] && shift 4 || shift $#
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
out=bench/results/$name-photon-count; mkdir -p "$out"
{
    echo "Photon-count study: \`$scene\`, $secs s per run, extra arguments: \`${*:-none}\`"
    echo "($(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))"
    echo
    echo "| photon_count | volume_photon_count | iterations | MSE | relative MSE | MSE/q99² |"
    echo "|---|---|---|---|---|---|"
    for pc in 150000 600000 2400000; do
        for vc in 10000 40000 160000; do
            tag=p$pc-v$vc
            # shellcheck disable=SC2068
            "$bin" render "$scene" --set photon_count=$pc --set volume_photon_count=$vc $@ --time "$secs" --seed 1 \
                --quiet --output "$out/$tag.exr" --reference "$ref" --log "$out/$tag.csv" --log-every 1000000 > /dev/null
            tail -n 1 "$out/$tag.csv" | awk -F, -v pc=$pc -v vc=$vc '{ printf("| %d | %d | %d | %.4g | %.4g | %.4g |\n", pc, vc, $2, $7, $8, $9) }'
        done
    done
} | tee "bench/results/$name-photon-count.md"
