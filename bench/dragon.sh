#!/bin/sh
# The paper's glossy dragon (../shared/scenes/dragon, MIT), its three files unchanged:
#   bench/dragon.sh timings            load time, memory, seconds per iteration of each file (2 passes each)
#   bench/dragon.sh reference SECONDS  a long baseline photon-points render of ours (seed 1): refs/dragon-base-ref.exr
#   bench/dragon.sh convergence N      the baseline again with seed 2 for N passes (N = the reference's passes),
#                                      its error against the reference logged every 60 s
#   bench/dragon.sh mirror [SECONDS] [SEEDS]
#                                      DARTS behind the mirror wall (issue 18): the DARTS file with darts_mirrors
#                                      "full" (ours) and "straight" (the authors' behaviour, ours before) and the
#                                      baseline file, SECONDS each (default 180), seeds 1..SEEDS (default 2), error
#                                      against refs/dragon-base-ref.exr logged every 20 s; the mean of the pixels
#                                      whose camera ray meets the mirror first (bench/mirror_mask.c) and of the
#                                      rest, each ÷ the reference's
# Why photon points and not the path tracer for the reference: the dragon has a mirror wall and smooth
# metal, which the path tracer cannot connect to the point light through (it warns), so its image misses
# those caustics. The reference's own noise: the seed-2 run is the same estimator, so at the reference's pass
# count its MSE against the reference is twice the reference's variance (the kernel biases of the two, at
# equal radii, cancel); the script prints MSE(t) − MSE(end)/2 as the seed-2 run's own error at time t.
# Results: bench/results/dragon.md.
set -eu
scenes=${DRAGON:-../shared/scenes/dragon}
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
[ -d "$scenes" ] || { echo "$0: no dragon scene at $scenes (set DRAGON=folder)" >&2; exit 2; }
mkdir -p refs out/dragon
what=${1:-timings}
case $what in
timings)
    echo "date: $(date -u +%Y-%m-%dT%H:%MZ)  machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
    for f in path_trace scene-points-short scene-points-darts-short; do
        /usr/bin/time -f "wall %e s, peak %M KiB" "$bin" render "$scenes/$f.json" --spp 2 --output "out/dragon/$f.exr" \
            --quiet > "out/dragon/$f.txt" 2> "out/dragon/$f.time" || { cat "out/dragon/$f.time" >&2; exit 1; }
        load=$(sed -n 's/.*(loaded in \([0-9.]*\) s.*/\1/p' "out/dragon/$f.txt")
        rendered=$(sed -n 's/^rendered \([0-9]*\) passes in \([0-9.]*\) s.*/\1 \2/p' "out/dragon/$f.txt")
        mem=$(sed -n 's/^memory: estimated \(.*\) before the render, peak resident \(.*\)$/\1 est., \2 peak/p' "out/dragon/$f.txt")
        echo "$f: load $load s; $(echo "$rendered" | awk '{ printf "%.2f s per iteration", $2 / $1 }'); memory $mem"
        grep -E '^photon points|^photon pass' "out/dragon/$f.txt" | sed 's/^/    /' || true
    done
    ;;
reference)
    secs=${2:-3000}
    "$bin" render "$scenes/scene-points-short.json" --seed 1 --time "$secs" --checkpoint 300 \
        --output refs/dragon-base-ref.exr
    ;;
convergence)
    n=${2:?passes of the reference}
    "$bin" render "$scenes/scene-points-short.json" --seed 2 --spp "$n" --reference refs/dragon-base-ref.exr \
        --log out/dragon/convergence.csv --log-every 60 --output out/dragon/seed2.exr --quiet
    awk -F, 'NR > 1 { t[NR] = $1; it[NR] = $2; m[NR] = $7; last = NR }
             END { v = m[last] / 2; printf "reference variance (MSE at the end / 2): %.4g\n", v;
                   print "seconds, iterations, MSE against the reference, minus its variance";
                   for (i = 2; i <= last; i++) printf "%8.0f %4d %.4g %.4g\n", t[i], it[i], m[i], m[i] - v }' \
        out/dragon/convergence.csv
    ;;
mirror)
    secs=${2:-180}; seeds=${3:-2}; ref=refs/dragon-base-ref.exr
    mirror=${MIRROR:-primitives[8]} # the mirror wall: the file's ninth primitive, unnamed
    [ -f "$ref" ] || { echo "$0: no $ref: run '$0 reference' first" >&2; exit 2; }
    cc -std=c11 -D_GNU_SOURCE -O2 -fopenmp -Iinclude bench/mirror_mask.c build/libdartspp.a \
        -lembree3 -lOpenEXRCore-3_1 -lcjson -lpng -lstb -lflann -lm -fopenmp -o out/dragon/mirror_mask
    mask=out/dragon/mirror-mask.pfm
    npix=$(out/dragon/mirror_mask "$scenes/scene-points-darts-short.json" "$mirror" "$mask" 2>&1 | sed -n 's/^mirror_mask: \([0-9]*\) of.*/\1/p')
    total=$((960 * 960))
    rm_=$("$bin" patch-mean "$ref" 0 0 960 960 --mask "$mask"); ra=$("$bin" patch-mean "$ref" 0 0 960 960)
    echo "date: $(date -u +%Y-%m-%dT%H:%MZ)  machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
    echo "mirror region: $npix of $total pixels; $secs s per run, seeds 1..$seeds"
    echo
    echo "| method | seed | iterations at 60 s | MSE at 60 s | iterations | MSE at the end | mirror mean ÷ reference | rest mean ÷ reference |"
    echo "|---|---|---|---|---|---|---|---|"
    for m in "full|DARTS, darts_mirrors full|scene-points-darts-short|" \
             "straight|DARTS, darts_mirrors straight (authors')|scene-points-darts-short|--set darts_mirrors=straight" \
             "baseline|baseline photon points|scene-points-short|"; do
        slug=${m%%|*}; rest=${m#*|}; name=${rest%%|*}; rest=${rest#*|}; file=${rest%%|*}; sets=${rest#*|}
        s=1
        while [ "$s" -le "$seeds" ]; do
            f=out/dragon/mirror-$slug-s$s
            # shellcheck disable=SC2086
            "$bin" render "$scenes/$file.json" --seed "$s" --time "$secs" $sets --reference "$ref" --log "$f.csv" \
                --log-every 20 --output "$f.exr" --quiet > "$f.txt" 2>&1
            mm=$("$bin" patch-mean "$f.exr" 0 0 960 960 --mask "$mask"); ma=$("$bin" patch-mean "$f.exr" 0 0 960 960)
            awk -F, -v n="$name" -v s="$s" -v mm="$mm" -v ma="$ma" -v rm="$rm_" -v ra="$ra" -v np="$npix" -v tot="$total" '
                NR > 1 { if ($1 <= 60) { i60 = $2; m60 = $7 } it = $2; mse = $7 }
                END { rest = (ma * tot - mm * np) / (tot - np); rrest = (ra * tot - rm * np) / (tot - np);
                      printf "| %s | %d | %s | %s | %d | %.4g | %.3f | %.3f |\n", n, s, i60 == "" ? "0" : i60,
                             m60 == "" ? "no pass yet" : sprintf("%.4g", m60), it, mse, mm / rm, rest / rrest }' "$f.csv"
            s=$((s + 1))
        done
    done
    ;;
*) echo "usage: $0 timings | reference SECONDS | convergence PASSES | mirror [SECONDS] [SEEDS]" >&2; exit 2 ;;
esac
