#!/usr/bin/env bash
# DA-RIS cost before and after (docs/darts.md §6.5): builds bench/da_ris_bench.c twice, with
# src/darts/da_distance.c as committed at REV (default HEAD) and as it is in the working tree, and times
# both on the recorded inputs of the fog Cornell box (σs 0.15, σa 0.005).
#   bench/da_ris_bench.sh [REV] [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/.."
rev=${1:-HEAD}; rounds=${2:-200}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cc=${CC:-gcc}
cflags="-std=c11 -D_GNU_SOURCE -O3 -fno-math-errno -Iinclude"
git show "$rev:src/darts/da_distance.c" >"$work/da_distance_rev.c"
common="bench/da_ris_bench.c src/darts/ellipse.c src/core/rng.c src/core/sampling.c src/core/error.c"
# shellcheck disable=SC2086
$cc $cflags -Isrc/darts $common "$work/da_distance_rev.c" -lm -o "$work/bench_rev"
# shellcheck disable=SC2086
$cc $cflags $common src/darts/da_distance.c -lm -o "$work/bench_now"
inputs=bench/data/da_inputs_cbox_fog.txt
echo "$rev: $("$work/bench_rev" "$inputs" 0.15 0.005 "$rounds")"
echo "working tree: $("$work/bench_now" "$inputs" 0.15 0.005 "$rounds")"
