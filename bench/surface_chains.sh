#!/bin/sh
# Surface chains on and off at equal wall time (src/photon/surface_chain.c):
#   bench/surface_chains.sh SCENE.json SECONDS SEEDS REFERENCE|none [THREADS] [RESOLUTION]
# For each seed 1..SEEDS the two runs follow each other (the machine's drift hits both). Prints per setting:
# iterations, s/iteration, the surface photons stored per iteration, the image mean, the seed variance
# (half the mean MSE between two seeds' images: the per-pixel variance of one image) and, with a
# reference, the MSE of each run against it. RESOLUTION (e.g. 256) overrides the camera's. Output:
# out/chains/<stem>-<SECONDS>s/.
set -eu
scene=${1:?scene file}; secs=${2:-30}; seeds=${3:-3}; ref=${4:?reference image or none}; threads=${5:-2}; res=${6:-}
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
[ -f "$scene" ] || { echo "$0: no scene $scene" >&2; exit 2; }
[ "$ref" = none ] || [ -f "$ref" ] || { echo "$0: no reference image $ref" >&2; exit 2; }
stem=$(basename "$scene" .json)
o=out/chains/$stem-${secs}s
rm -rf "$o" && mkdir -p "$o"
extra=""
[ -z "$res" ] || extra="--set resolution=$res"
echo "date: $(date -u +%Y-%m-%dT%H:%MZ)  machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
echo "scene: $scene ${res:+at ${res}² }, ${secs} s per run, $threads threads, seeds 1..$seeds, reference $(basename "$ref")"
echo
s=1
while [ "$s" -le "$seeds" ]; do
    for on in true false; do
        # shellcheck disable=SC2086
        "$bin" render "$scene" --threads "$threads" --seed "$s" --time "$secs" --set surface_chains=$on $extra \
            --output "$o/$on-s$s.pfm" --no-cube --no-viewer > "$o/$on-s$s.txt" 2>&1 || { tail -5 "$o/$on-s$s.txt" >&2; exit 1; }
    done
    s=$((s + 1))
done

mse() { "$bin" compare "$1" "$2" | sed -n 's/^mse  *\([0-9][^ ]*\).*/\1/p'; }
echo "| surface chains | iterations | s/iteration | photons stored per iteration | image mean | seed variance | MSE vs reference |"
echo "|---|---|---|---|---|---|---|"
for on in true false; do
    its=""; spi=""; per=""; means=""; mses=""; msum=0
    s=1
    while [ "$s" -le "$seeds" ]; do
        f=$o/$on-s$s
        set -- $(sed -n 's/^rendered \([0-9]*\) passes in \([0-9.]*\) s.*/\1 \2/p' "$f.txt")
        n=$1; t=$2
        stored=$(sed -n 's/.* \([0-9.e+]*\) photons stored.*/\1/p' "$f.txt")
        its="$its${its:+, }$n"
        spi="$spi${spi:+, }$(awk -v n="$n" -v t="$t" 'BEGIN { printf "%.3f", t / n }')"
        per="$per${per:+, }$(awk -v n="$n" -v p="$stored" 'BEGIN { printf "%.0fk", p / n / 1000 }')"
        wh=$(sed -n 's/.*, \([0-9]*\)x\([0-9]*\), .*/\1 \2/p' "$f.txt" | head -1)
        means="$means${means:+, }$("$bin" patch-mean "$f.pfm" 0 0 $wh | awk '{ printf "%.4f", $1 }')"
        if [ "$ref" != none ]; then
            m=$(mse "$f.pfm" "$ref")
            mses="$mses${mses:+, }$(awk -v m="$m" 'BEGIN { printf "%.4g", m }')"
            msum=$(awk -v a="$msum" -v m="$m" 'BEGIN { print a + m }')
        fi
        s=$((s + 1))
    done
    var=$(s=1; while [ "$s" -le "$seeds" ]; do k=$((s + 1)); while [ "$k" -le "$seeds" ]; do
              mse "$o/$on-s$s.pfm" "$o/$on-s$k.pfm"; k=$((k + 1)); done; s=$((s + 1)); done |
          awk '{ v += $1 / 2; n++ } END { if (n) printf "%.4g", v / n; else printf "—" }')
    if [ "$ref" = none ]; then mcol="—"; else mcol="$mses (mean $(awk -v a="$msum" -v n="$seeds" 'BEGIN { printf "%.4g", a / n }'))"; fi
    echo "| $on | $its | $spi | $per | $means | $var | $mcol |"
    echo "$on $var $(awk -v a="$msum" -v n="$seeds" 'BEGIN { print a / n }')" >> "$o/summary.txt"
done
awk '{ v[$1] = $2; m[$1] = $3 } END {
       if (v["false"] > 0) printf "\nseed variance, on ÷ off: %.3f\n", v["true"] / v["false"]
       if (m["false"] > 0) printf "MSE, on ÷ off: %.3f\n", m["true"] / m["false"] }' "$o/summary.txt"
