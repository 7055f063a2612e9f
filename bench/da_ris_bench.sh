#!/usr/bin/env bash
# DA-RIS cost before and after (docs/darts.md §6.5): builds bench/da_ris_bench.c with src/darts/da_distance.c
# as committed at REV (default HEAD; its function renamed da_sample_distance_rev) and as it is in the working
# tree, and times both, alternating, on the recorded inputs of the fog Cornell box (σs 0.15, σa 0.005).
#   bench/da_ris_bench.sh [REV] [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/.."
rev=${1:-HEAD}; rounds=${2:-50}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cc=${CC:-gcc}
cflags="-std=c11 -D_GNU_SOURCE -O3 -fno-math-errno -Iinclude"
git show "$rev:src/darts/da_distance.c" >"$work/da_distance_rev.c"
# shellcheck disable=SC2086
$cc $cflags -Dda_sample_distance=da_sample_distance_rev -c "$work/da_distance_rev.c" -o "$work/rev.o"
# shellcheck disable=SC2086
$cc $cflags bench/da_ris_bench.c src/darts/da_distance.c src/darts/ellipse.c src/core/rng.c src/core/sampling.c \
    src/core/error.c "$work/rev.o" -lm -o "$work/bench"
echo "revision: $rev"
"$work/bench" bench/data/da_inputs_cbox_fog.txt 0.15 0.005 "$rounds"
