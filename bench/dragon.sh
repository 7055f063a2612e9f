#!/bin/sh
# The paper's glossy dragon (../shared/scenes/dragon, MIT), its three files unchanged:
#   bench/dragon.sh timings            load time, memory, seconds per iteration of each file (2 passes each)
#   bench/dragon.sh reference SECONDS  a long baseline photon-points render of ours (seed 1): refs/dragon-base-ref.exr
#   bench/dragon.sh convergence N      the baseline again with seed 2 for N passes (N = the reference's passes),
#                                      its error against the reference logged every 60 s
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
*) echo "usage: $0 timings | reference SECONDS | convergence PASSES" >&2; exit 2 ;;
esac
