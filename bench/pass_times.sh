#!/bin/sh
# Time per iteration of each photon-points pass, two dartspp binaries side by side, alternating (A B A B
# ...) so that a slower spell of a shared machine hits both:
#   bench/pass_times.sh SCENE.json ITERATIONS ROUNDS A_BINARY [B_BINARY] [THREADS]
# For each binary and round: s/iteration of the photon pass, the map builds, the sensor pass and the whole
# iteration (from the render summary), then the mean of the rounds and the ratio A ÷ B. Same seed, so both
# binaries do the same work when their images are the same (the script says whether they are, bit for bit).
# Extra options for both in DARTSPP_ARGS. Output: out/pass_times/<stem>/.
set -eu
scene=${1:?scene file}; its=${2:-10}; rounds=${3:-3}; a=${4:?binary A}; b=${5:-}; threads=${6:-2}
[ -f "$scene" ] || { echo "$0: no scene $scene" >&2; exit 2; }
for x in "$a" $b; do [ -x "$x" ] || { echo "$0: $x is not an executable" >&2; exit 2; }; done
o=out/pass_times/$(basename "$scene" .json)
rm -rf "$o" && mkdir -p "$o"
echo "date: $(date -u +%Y-%m-%dT%H:%MZ)  machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
echo "scene: $scene, $its iterations, $threads threads, $rounds rounds; A = $a${b:+, B = $b}; options: ${DARTSPP_ARGS:-none}"
echo
echo "| binary | round | photon pass | map builds | sensor pass | iteration (s) |"
echo "|---|---|---|---|---|---|"
r=1
while [ "$r" -le "$rounds" ]; do
    for tag in A B; do
        bin=$([ "$tag" = A ] && echo "$a" || echo "$b")
        [ -n "$bin" ] || continue
        # shellcheck disable=SC2086
        "$bin" render "$scene" --threads "$threads" --spp "$its" --seed 7 ${DARTSPP_ARGS:-} --output "$o/$tag-$r.pfm" \
            > "$o/$tag-$r.txt" 2>&1 || { tail -5 "$o/$tag-$r.txt" >&2; exit 1; }
        sed -n 's/.*time in photon pass \([0-9.]*\) s, map builds \([0-9.]*\) s, sensor pass \([0-9.]*\) s.*/\1 \2 \3/p' \
            "$o/$tag-$r.txt" | awk -v n="$its" -v t="$tag" -v r="$r" '{ printf "%s %s %.4f %.4f %.4f %.4f\n", t, r, $1 / n, $2 / n, $3 / n, ($1 + $2 + $3) / n }' \
            >> "$o/times.txt"
        tail -1 "$o/times.txt" | awk '{ printf "| %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6 }'
    done
    r=$((r + 1))
done
echo
awk '{ n[$1]++; p[$1] += $3; m[$1] += $4; s[$1] += $5; t[$1] += $6 }
     END { for (k in n) printf "mean %s: photon pass %.3f s, maps %.3f s, sensor pass %.3f s, iteration %.3f s\n", k, p[k] / n[k], m[k] / n[k], s[k] / n[k], t[k] / n[k]
           if (n["B"]) printf "A / B: photon pass %.2f, sensor pass %.2f, iteration %.2f\n", (p["A"] / n["A"]) / (p["B"] / n["B"]), (s["A"] / n["A"]) / (s["B"] / n["B"]), (t["A"] / n["A"]) / (t["B"] / n["B"]) }' "$o/times.txt" | sort
if [ -n "$b" ]; then
    if cmp -s "$o/A-1.pfm" "$o/B-1.pfm"; then echo "images: A and B bit-identical"; else echo "images: A and B differ"; fi
fi
