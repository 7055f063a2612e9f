#!/bin/sh
# The references of the paper's fog Cornell box, dragon and staircase at the resolutions the equal-time
# comparisons use, and their checks:
#   bench/references.sh make box|dragon|staircase     long renders of ours, merged (refs/, about 1 h each on 2 cores)
#   bench/references.sh check box|dragon|staircase    the reference against estimators that share less of its code
# `make`: DARTS photon points as the paper's file asks (consistent: the radii shrink without end), 4 chunks
# of PASSES passes with seeds 7919.., merged by `dartspp merge`, whose chunk spread gives the reference's own
# noise (refs/<name>.pfm.var, subtracted by bench/peer_equal_time.sh with REF_NOISE). The path tracer cannot
# reach a useful noise level here (bench/results/references.md says by how much) and cannot render a point
# light through the dragon's mirror at all. glossy_regularization is set to 0, the unregularized estimator.
# `check`: (1) the image mean against our baseline photon points (DARTS off) and, with PEER_TUNGSTEN set,
# the authors' baseline (their `scene-points-short.json`); (2) tile by tile against CHECK_CHUNKS (default 4)
# renders of our DARTS path tracer of CHECK_SECONDS (default 120) each (bench/tile_check.py). The path
# tracer misses light through mirrors and glass from a point light (it warns): tiles that see them differ.
set -eu
what=${1:?usage: references.sh make|check box|dragon|staircase}; name=${2:?usage: references.sh make|check box|dragon|staircase}
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
case $name in
box) scene=../shared/scenes/cbox-trans/transient.json; res=512; passes=${PASSES:-2500} ;;
dragon) scene=../shared/scenes/dragon/scene-points-darts-short.json; res=480; passes=${PASSES:-500} ;;
staircase) scene=../shared/scenes/staircase/scene-points-darts-short.json; res=360; passes=${PASSES:-300} ;;
*) echo "$0: no reference named $name (box, dragon, staircase)" >&2; exit 2 ;;
esac
[ -f "$scene" ] || { echo "$0: $scene not found (the paper's scenes live in ../shared)" >&2; exit 2; }
ref=refs/$name-$res-pp.pfm
fixed="--set resolution=$res --set glossy_regularization=0 --threads 2"
case $what in
make)
    # shellcheck disable=SC2086
    METHOD=scene PASSES=$passes bench/reference.sh "$scene" 0 "$ref" $fixed ;;
check)
    [ -f "$ref" ] || { echo "$0: no $ref yet: bench/references.sh make $name" >&2; exit 2; }
    o=out/references/$name; mkdir -p "$o"
    secs=${CHECK_SECONDS:-120}; k=0; checks=""
    while [ "$k" -lt "${CHECK_CHUNKS:-4}" ]; do
        # shellcheck disable=SC2086
        "$bin" render "$scene" $fixed --set type=path_tracer --time "$secs" --seed $((31 + k)) --quiet --no-cube \
            --no-viewer --output "$o/darts-pt-$k.pfm" 2>&1 | grep '^rendered' | sed "s/^/DARTS PT $k: /"
        checks="$checks $o/darts-pt-$k.pfm"; k=$((k + 1))
    done
    # shellcheck disable=SC2086
    "$bin" render "$scene" $fixed --set enable_guiding=false --set enable_elliptical=false --set strict_time_width=false \
        --time "$secs" --seed 41 --quiet --no-cube --no-viewer --output "$o/baseline-pp.pfm" 2>&1 | grep '^rendered' |
        sed 's/^/our baseline photon points: /'
    if [ -n "${PEER_TUNGSTEN:-}" ]; then
        base=$(cd "$(dirname "$scene")" && pwd)/scene-points-short.json
        (cd "$o" && "$PEER_TUNGSTEN" -t 2 -s 41 --timeout "${secs}s" --spp 100000000 -c 0 -r -e "$(pwd)/peer-baseline.pfm" \
            -o "$(pwd)/peer-baseline.png" "$base" > peer-baseline.txt 2>&1)
        echo "the authors' baseline: $(grep -c '^Completed [0-9]*/' "$o/peer-baseline.txt") iterations"
    fi
    chunks=$(ls "${ref%.pfm}".chunk*.pfm)
    # shellcheck disable=SC2086
    bench/tile_check.py --tiles 8 --ref $chunks --check $checks
    for img in "$o/baseline-pp.pfm" "$o/peer-baseline.pfm"; do
        [ -f "$img" ] || continue
        /usr/bin/python3 -c "import sys; sys.path.insert(0, 'bench'); from tile_check import read_pfm
r, c = read_pfm(sys.argv[1]).mean(), read_pfm(sys.argv[2]).mean(); print(f'{sys.argv[2]}: image mean {c:.5g}, reference {r:.5g}, ratio {c / r:.4f}')" "$ref" "$img"
    done ;;
*) echo "$0: make or check" >&2; exit 2 ;;
esac
