#!/bin/sh
# dartspp beside the authors' renderer (the DARTS Tungsten fork; ../shared/docs/peer-benchmark.md says how to
# build it outside this repository), at equal wall time on the same scene file, threads and seeds, the two
# runs of each seed one after the other:
#   PEER_TUNGSTEN=/path/to/tungsten bench/peer_equal_time.sh SCENE.json SECONDS SEEDS REFERENCE.pfm [THREADS]
# For each renderer: iterations, s/iteration, photon paths/s, camera rays/s (both per run), the image mean,
# the seed variance (half the mean MSE between two seeds' images) and the MSE of each run against the
# reference, and that MSE minus the reference's own noise (REF_NOISE, default 0.0003: see
# ../shared/references/README.md). Without PEER_TUNGSTEN it runs dartspp alone and says so. REFERENCE
# "none" (a scene without an unbiased reference, e.g. the dragon) leaves the MSE columns out.
# Seeds are 1..SEEDS for both (seed 99 made the authors' 40-minute image; use other seeds against it), or
# FIRST_SEED..FIRST_SEED+SEEDS−1 with FIRST_SEED set (an independent set; the files keep the names s1..sSEEDS); 8 or
# more (fewer refused unless FEW_SEEDS=1). After that table, bench/seed_stats.py's: the full and the trimmed MSE
# (the 0.1 % of pixels of largest error dropped), the seed variance and the bias² of the mean apart from the
# noise, each theirs ÷ ours with a 95 % bootstrap interval over seeds.
# Our extra options go in DARTSPP_ARGS (e.g. "--set volume_gather=beam"). Output: out/peer/<stem>-<s>s<TAG>/
# (TAG from PEER_TAG, so that variants do not overwrite each other). PEER_TABLE_ONLY=1 prints the table of
# an earlier run in that folder again without rendering.
set -eu
scene=${1:?scene file}; secs=${2:-90}; seeds=${3:-3}; ref=${4:?reference image}; threads=${5:-2}
bin=${DARTSPP:-build/dartspp}
peer=${PEER_TUNGSTEN:-}
noise=${REF_NOISE:-0.0003}
[ -x "$bin" ] || make build/dartspp >&2
[ -f "$scene" ] || { echo "$0: no scene $scene" >&2; exit 2; }
scene_abs=$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene") # the peer runs in the output folder
[ "$ref" = none ] || [ -f "$ref" ] || { echo "$0: no reference image $ref" >&2; exit 2; }
[ "$seeds" -ge 8 ] || [ "${FEW_SEEDS:-}" = 1 ] ||
    { echo "$0: $seeds seeds: ratios need 8 or more for their intervals (FEW_SEEDS=1 to try fewer)" >&2; exit 2; }
if [ -n "$peer" ] && [ ! -x "$peer" ]; then echo "$0: PEER_TUNGSTEN=$peer is not an executable" >&2; exit 2; fi
stem=$(basename "$scene" .json)
o=out/peer/$stem-${secs}s${PEER_TAG:-}
if [ -n "${PEER_TABLE_ONLY:-}" ]; then
    [ -f "$o/runs.txt" ] || { echo "$0: no earlier run in $o" >&2; exit 2; }
else
    rm -rf "$o" && mkdir -p "$o"
fi
o=$(cd "$o" && pwd) # absolute: the peer resolves paths against its scene
rm -f "$o/summary.txt"
# image size and photon paths per iteration, from the scene file
wh=$(python3 -c "import json,sys; d=json.load(open(sys.argv[1])); r=d['camera']['resolution']; r=r if isinstance(r,list) else [r,r]; print(r[0], r[1], int(d['integrator'].get('photon_count', 0)))" "$scene")
w=${wh%% *}; rest=${wh#* }; h=${rest%% *}; paths=${rest#* }

echo "date: $(date -u +%Y-%m-%dT%H:%MZ)  machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
first=${FIRST_SEED:-1}
echo "scene: $scene, ${secs} s per run, $threads threads, seeds $first..$((first + seeds - 1)), reference $(basename "$ref")"
echo "dartspp options: ${DARTSPP_ARGS:-(the scene file as it is)}"
[ -n "$peer" ] || echo "PEER_TUNGSTEN is not set: dartspp alone (build the authors' renderer per ../shared/docs/peer-benchmark.md)"
echo

s=1
[ -z "${PEER_TABLE_ONLY:-}" ] || s=$((seeds + 1))
while [ "$s" -le "$seeds" ]; do
    # shellcheck disable=SC2086
    "$bin" render "$scene" --threads "$threads" --seed "$((first + s - 1))" --time "$secs" ${DARTSPP_ARGS:-} --output "$o/ours-s$s.pfm" \
        > "$o/ours-s$s.txt" 2>&1 || { tail -5 "$o/ours-s$s.txt" >&2; exit 1; }
    its=$(sed -n 's/^rendered \([0-9]*\) passes in \([0-9.]*\) s.*/\1 \2/p' "$o/ours-s$s.txt")
    echo "ours $s $its" >> "$o/runs.txt"
    if [ -n "$peer" ]; then
        (cd "$o" && "$peer" -t "$threads" -s "$((first + s - 1))" --timeout "${secs}s" --spp 100000000 -c 0 -r -e "$o/theirs-s$s.pfm" \
            -o "$o/theirs-s$s.png" "$scene_abs" > "$o/theirs-s$s.txt" 2>&1) ||
            { tail -5 "$o/theirs-s$s.txt" >&2; exit 1; }
        n=$(grep -c '^Completed [0-9]*/' "$o/theirs-s$s.txt" || true)
        t=$(sed -n 's/^Finished render. Render time \(.*\)$/\1/p' "$o/theirs-s$s.txt" |
            awk '{ t = 0; for (i = 1; i <= NF; i++) { v = $i + 0; u = $i; sub(/^[0-9.]+/, "", u)
                   t += u == "ms" ? v / 1000 : u == "s" ? v : u == "m" ? 60 * v : u == "h" ? 3600 * v : u == "d" ? 86400 * v : 0 }
                   printf "%.2f", t }')
        echo "theirs $s $n $t" >> "$o/runs.txt"
    fi
    s=$((s + 1))
done

# the "mse" line of dartspp compare (not "mse / q99^2"): a number after the spaces
mse() { "$bin" compare "$1" "$2" | sed -n 's/^mse  *\([0-9][^ ]*\).*/\1/p'; }
echo "| renderer | iterations | s/iteration | photon paths/s | camera rays/s | image mean | seed variance | MSE vs reference | MSE − reference noise |"
echo "|---|---|---|---|---|---|---|---|---|"
for who in ours theirs; do
    [ "$(grep -c "^$who " "$o/runs.txt")" -eq "$seeds" ] || continue
    its=""; spi=""; pps=""; crs=""; means=""; mses=""; msum=0
    s=1
    while [ "$s" -le "$seeds" ]; do
        set -- $(grep "^$who $s " "$o/runs.txt")
        n=$3; t=$4
        its="$its${its:+, }$n"
        spi="$spi${spi:+, }$(awk -v n="$n" -v t="$t" 'BEGIN { printf "%.3f", t / n }')"
        pps="$pps${pps:+, }$(awk -v n="$n" -v t="$t" -v p="$paths" 'BEGIN { printf "%.2fM", n * p / t / 1e6 }')"
        crs="$crs${crs:+, }$(awk -v n="$n" -v t="$t" -v w="$w" -v h="$h" 'BEGIN { printf "%.2fM", n * w * h / t / 1e6 }')"
        means="$means${means:+, }$("$bin" patch-mean "$o/$who-s$s.pfm" 0 0 "$w" "$h" | awk '{ printf "%.4f", $1 }')"
        if [ "$ref" != none ]; then
            m=$(mse "$o/$who-s$s.pfm" "$ref")
            mses="$mses${mses:+, }$(awk -v m="$m" 'BEGIN { printf "%.4g", m }')"
            msum=$(awk -v a="$msum" -v m="$m" 'BEGIN { print a + m }')
        fi
        s=$((s + 1))
    done
    var=$(s=1; while [ "$s" -le "$seeds" ]; do k=$((s + 1)); while [ "$k" -le "$seeds" ]; do
              mse "$o/$who-s$s.pfm" "$o/$who-s$k.pfm"; k=$((k + 1)); done; s=$((s + 1)); done |
          awk '{ v += $1 / 2; n++ } END { if (n) printf "%.4g", v / n; else printf "—" }')
    mean_mse=$(awk -v a="$msum" -v n="$seeds" 'BEGIN { printf "%.4g", a / n }')
    net=$(awk -v a="$msum" -v n="$seeds" -v z="$noise" 'BEGIN { printf "%.4g", a / n - z }')
    name=$([ "$who" = ours ] && echo "dartspp" || echo "authors' renderer")
    if [ "$ref" = none ]; then mse_cols="— | —"; else mse_cols="$mses (mean $mean_mse) | $net"; fi
    echo "| $name | $its | $spi | $pps | $crs | $means | $var | $mse_cols |"
    echo "$who $mean_mse $net $var" >> "$o/summary.txt"
done
if grep -q '^theirs ' "$o/runs.txt"; then
    awk '$1 == "ours" { o += $3; to += $4 } $1 == "theirs" { t += $3; tt += $4 }
         END { printf "\niterations per second, ours ÷ theirs: %.2f\n", (o / to) / (t / tt) }' "$o/runs.txt"
    awk -v none="$([ "$ref" = none ] && echo 1 || echo 0)" '{ m[$1] = $2; n[$1] = $3; v[$1] = $4 }
         END { if (("ours" in v) && ("theirs" in v) && v["ours"] > 0) printf "seed variance, theirs ÷ ours: %.2f\n", v["theirs"] / v["ours"]
               if (!none && ("ours" in m) && ("theirs" in m) && m["ours"] > 0 && n["ours"] > 0)
                   printf "MSE, theirs ÷ ours: %.2f (minus the reference noise: %.2f)\n", m["theirs"] / m["ours"], n["theirs"] / n["ours"] }' "$o/summary.txt"
fi
# every ratio with its interval over seeds (theirs ÷ ours: BASE ours)
labels=ours
grep -q '^theirs ' "$o/runs.txt" && labels="ours theirs"
echo
[ "$ref" = none ] && sref=- || sref=$ref
DARTSPP=$bin /usr/bin/python3 bench/seed_stats.py "$o" ours "$labels" "$seeds" "$sref" "$noise"
