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
#   bench/dragon.sh mirror-const [REF_SECONDS] [REF_SEEDS] [SEEDS]
#                                      the same question where noise cannot hide a bias: 240², constant radii (the
#                                      DARTS file's r_vol 0.15 and R 0.07 for every method, alpha = 1), one thread
#                                      per run. The reference is DARTS with DA distance sampling only
#                                      (enable_elliptical false: no control vertices, so nothing depends on the
#                                      camera leg's shape), seeds 101..100+REF_SEEDS, REF_SECONDS each (default 600,
#                                      4); then full, straight and the baseline file at 60 s and 180 s, seeds
#                                      1..SEEDS (default 3). Prints the mirror region's and the rest's means with
#                                      their standard errors over seeds, and each method's difference from the
#                                      reference in standard errors.
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
mirror-const)
    rsecs=${2:-600}; rseeds=${3:-4}; seeds=${4:-3}; mirror=${MIRROR:-primitives[8]}; o=out/dragon/const
    mkdir -p "$o"
    cc -std=c11 -D_GNU_SOURCE -O2 -fopenmp -Iinclude bench/mirror_mask.c build/libdartspp.a \
        -lembree3 -lOpenEXRCore-3_1 -lcjson -lpng -lstb -lflann -lm -fopenmp -o "$o/mirror_mask"
    cp "$bin" "$o/dartspp" # the runs take an hour: a rebuild meanwhile must not change the binary under them
    bin=$o/dartspp
    common="--set resolution=240 --set alpha=1 --set volume_alpha=1 --set volume_gather_radius=0.15 --set gather_radius=0.07 --threads 1 --quiet"
    "$o/mirror_mask" "$scenes/scene-points-darts-short.json" "$mirror" "$o/mask.pfm" --set resolution=240 >&2
    run() { # slug file seconds seed extra-sets...
        slug=$1; file=$2; secs=$3; seed=$4; shift 4; f=$o/$slug-$secs-s$seed
        [ -f "$f.exr" ] || "$bin" render "$scenes/$file.json" $common "$@" --seed "$seed" --time "$secs" --output "$f.exr" > "$f.txt" 2>&1
        printf '%s %s %s %s %s %s\n' "$slug" "$secs" "$seed" "$(sed -n 's/^rendered \([0-9]*\) passes.*/\1/p' "$f.txt")" \
            "$("$bin" patch-mean "$f.exr" 0 0 240 240 --mask "$o/mask.pfm")" "$("$bin" patch-mean "$f.exr" 0 0 240 240)" >> "$o/means.txt"
    }
    : > "$o/means.txt"
    s=1; while [ $s -le "$rseeds" ]; do run reference scene-points-darts-short "$rsecs" $((100 + s)) --set enable_elliptical=false; s=$((s + 1)); done
    for secs in 60 180; do
        s=1; while [ $s -le "$seeds" ]; do
            run full scene-points-darts-short "$secs" "$s"
            run straight scene-points-darts-short "$secs" "$s" --set darts_mirrors=straight
            run baseline scene-points-short "$secs" "$s"
            s=$((s + 1))
        done
    done
    # the reference image: the mean of the reference runs; each run's MSE against it (whole image)
    set -- $(ls "$o"/reference-"$rsecs"-s*.exr)
    if [ $# -ge 2 ]; then "$bin" merge "$o/reference.exr" "$@" > /dev/null; else cp "$1" "$o/reference.exr"; fi
    for f in "$o"/full-*.exr "$o"/straight-*.exr "$o"/baseline-*.exr; do
        [ -f "$f" ] || continue
        printf '%s %s\n' "$(basename "$f" .exr)" "$("$bin" compare "$f" "$o/reference.exr" | sed -n 's/^mse  *\([0-9][^ ]*\).*/\1/p')"
    done > "$o/mse.txt"
    npix=$("$bin" patch-mean "$o/mask.pfm" 0 0 240 240 | awk '{ printf "%d", $1 * 240 * 240 + 0.5 }')
    echo "date: $(date -u +%Y-%m-%dT%H:%MZ)  machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
    echo "240², constant radii r_vol 0.15, R 0.07, one thread per run; mirror region: $npix of 57600 pixels"
    echo
    awk -v np="$npix" 'function stats(key,   n, i, m, v, x) { n = cnt[key]; m = 0; for (i = 1; i <= n; i++) m += val[key, i]; m /= n;
                                    v = 0; for (i = 1; i <= n; i++) { x = val[key, i] - m; v += x * x } se = n > 1 ? sqrt(v / (n - 1) / n) : 0; return m }
        { rest = ($6 * 57600 - $5 * np) / (57600 - np); k = $1 " " $2
          if (!(k in cnt)) order[++nk] = k; cnt[k]++; its[k] = its[k] (its[k] == "" ? "" : ", ") $4
          val[k " mirror", cnt[k]] = $5; cnt[k " mirror"]++; val[k " rest", cnt[k]] = rest; cnt[k " rest"]++ }
        END { print "| method | seconds | runs | iterations | mirror mean ± s.e. | (mirror − ref) / s.e. | rest mean ± s.e. | (rest − ref) / s.e. |"
              print "|---|---|---|---|---|---|---|---|"
              for (j = 1; j <= nk; j++) { k = order[j]; split(k, a, " ")
                  mm = stats(k " mirror"); ms = se; rm = stats(k " rest"); rs = se
                  if (j == 1) { refm = mm; refms = ms; refr = rm; refrs = rs }
                  zm = j == 1 ? "—" : sprintf("%+.1f", (mm - refm) / sqrt(ms * ms + refms * refms))
                  zr = j == 1 ? "—" : sprintf("%+.1f", (rm - refr) / sqrt(rs * rs + refrs * refrs))
                  printf "| %s | %s | %d | %s | %.4f ± %.4f | %s | %.4f ± %.4f | %s |\n", a[1], a[2], cnt[k], its[k], mm, ms, zm, rm, rs, zr } }' "$o/means.txt"
    echo
    echo "MSE against the reference image (the mean of the reference runs; it carries their noise, the same for every row):"
    echo
    echo "| method | seconds | MSE per seed | mean |"
    echo "|---|---|---|---|"
    awk '{ n = split($1, a, "-"); k = a[1] " " a[2]; if (!(k in c)) o[++m] = k; c[k]++; v[k] = v[k] (v[k] == "" ? "" : ", ") sprintf("%.4g", $2); s[k] += $2 }
         END { for (i = 1; i <= m; i++) { split(o[i], a, " "); printf "| %s | %s | %s | %.4g |\n", a[1], a[2], v[o[i]], s[o[i]] / c[o[i]] } }' "$o/mse.txt"
    ;;
*) echo "usage: $0 timings | reference SECONDS | convergence PASSES | mirror [SECONDS] [SEEDS] | mirror-const [REF_SECONDS] [REF_SEEDS] [SEEDS]" >&2; exit 2 ;;
esac
