#!/bin/sh
# DARTS behind mirrors, before and after (issue 18): bench/mirrors.sh [SECONDS] [REF_SECONDS] [SEEDS]
# The demo fog box (scenes/fogbox/fogbox.json, 128²) with its back wall made a mirror, and a glossy variant
# (the back wall rough silver, GGX α 0.1: continued by camera paths with the default glossy_gather_alpha).
# The camera sees the fog through the wall, where the camera leg is longer than the straight line. Reference
# per scene: baseline photon points for REF_SECONDS (default 300; the path tracer cannot be the reference:
# it misses all light the mirror reflects before a diffuse or medium vertex). For SECONDS (default 30) each,
# seeds 1..SEEDS (default 2): baseline, DARTS with darts_mirrors "full" (ours) and "straight" (the authors'
# behaviour, and ours before), each with strict time on and off, and DA distance sampling alone. Prints per
# method the mean over seeds of: MSE against the reference, baseline MSE ÷ that MSE (equal-time ratio), the
# mean over the pixels that see the wall first (bench/mirror_mask.c) ÷ the reference's, the image mean ÷
# the reference's; iterations.
set -eu
secs=${1:-30}; rsecs=${2:-300}; seeds=${3:-2}
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
out=bench/results/mirrors; mkdir -p "$out" refs
mask_bin=$out/mirror_mask
# shellcheck disable=SC2046
cc -std=c11 -D_GNU_SOURCE -O2 -fopenmp -Iinclude bench/mirror_mask.c build/libdartspp.a \
    -lembree3 -lOpenEXRCore-3_1 -lcjson -lpng -lstb -lflann -lm -fopenmp -o "$mask_bin"
base="--set enable_guiding=false --set enable_elliptical=false"
table=bench/results/mirrors.md
{
echo "DARTS behind mirrors: the demo fog box at 128² with its back wall a mirror or rough silver (α 0.1), $secs s per run,"
echo "seeds 1..$seeds, against $rsecs s of baseline photon points (seed 7). $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores,"
echo "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'). \`bench/mirrors.sh $secs $rsecs $seeds\`."
for variant in mirror glossy; do
    scene=refs/fogbox-$variant.json
    case $variant in
        mirror) wall='{ "type": "mirror" }' ;;
        glossy) wall='{ "type": "rough_conductor", "material": "Ag", "distribution": "ggx", "roughness": 0.1 }' ;;
    esac
    awk -v wall="$wall" '/"name": "back"/ { back = 1 } back && /"bsdf": "white"/ { sub(/"white"/, wall); back = 0 } { print }' \
        scenes/fogbox/fogbox.json > "$scene"
    grep -q '"back"' "$scene" && ! grep -A3 '"name": "back"' "$scene" | grep -q '"white"' ||
        { echo "$0: could not change the back wall" >&2; exit 1; }
    ref=refs/fogbox-$variant-pp$rsecs.exr
    # shellcheck disable=SC2086
    [ -f "$ref" ] || "$bin" render "$scene" --set resolution=128 $base --seed 7 --time "$rsecs" --quiet --output "$ref" > /dev/null
    mask=$out/$variant-mask.pfm
    "$mask_bin" "$scene" back "$mask" --set resolution=128 2>&1 | sed 's/^mirror_mask: //' > "$out/$variant-mask.txt"
    rwall=$("$bin" patch-mean "$ref" 0 0 128 128 --mask "$mask"); rall=$("$bin" patch-mean "$ref" 0 0 128 128)
    echo
    echo "### Back wall: $variant ($(cat "$out/$variant-mask.txt"))"
    echo
    echo "| method | iterations | MSE | baseline MSE ÷ MSE | wall mean ÷ reference | image mean ÷ reference |"
    echo "|---|---|---|---|---|---|"
    bmse=
    for m in "baseline|baseline photon points|$base" \
             "full-strict|DARTS, darts_mirrors full, strict on|--set strict_time_width=true" \
             "full|DARTS, darts_mirrors full, strict off|--set strict_time_width=false" \
             "straight-strict|DARTS, darts_mirrors straight (authors'), strict on|--set darts_mirrors=straight --set strict_time_width=true" \
             "straight|DARTS, darts_mirrors straight (authors'), strict off|--set darts_mirrors=straight --set strict_time_width=false" \
             "da-only|DA distance sampling only|--set enable_elliptical=false --set strict_time_width=false"; do
        slug=${m%%|*}; rest=${m#*|}; name=${rest%%|*}; sets=${rest#*|}
        sm=0; sw=0; sa=0; si=0
        s=1
        while [ "$s" -le "$seeds" ]; do
            f="$out/$variant-$slug-s$s.exr"
            # shellcheck disable=SC2086
            "$bin" render "$scene" --set resolution=128 $sets --seed "$s" --time "$secs" --output "$f" > "$out/$variant-$slug-s$s.txt" 2>&1
            it=$(sed -n 's/^rendered \([0-9]*\) passes.*/\1/p' "$out/$variant-$slug-s$s.txt")
            mse=$("$bin" compare "$f" "$ref" --csv | cut -d, -f1)
            w=$("$bin" patch-mean "$f" 0 0 128 128 --mask "$mask"); a=$("$bin" patch-mean "$f" 0 0 128 128)
            sm=$(awk -v x="$sm" -v y="$mse" 'BEGIN { print x + y }'); sw=$(awk -v x="$sw" -v y="$w" 'BEGIN { print x + y }')
            sa=$(awk -v x="$sa" -v y="$a" 'BEGIN { print x + y }'); si=$((si + it))
            s=$((s + 1))
        done
        [ -n "$bmse" ] || bmse=$(awk -v x="$sm" -v n="$seeds" 'BEGIN { print x / n }')
        awk -v n="$name" -v k="$seeds" -v m="$sm" -v w="$sw" -v a="$sa" -v i="$si" -v b="$bmse" -v rw="$rwall" -v ra="$rall" \
            'BEGIN { printf "| %s | %.0f | %.4g | %.2f | %.3f | %.3f |\n", n, i / k, m / k, b / (m / k), w / k / rw, a / k / ra }'
    done
done
} | tee "$table"
rm -f "$out"/*.exr "$mask_bin"
