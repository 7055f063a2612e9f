#!/bin/sh
# dartspp-mpi on one machine: the same iterations rendered by 1 process and by N ranks (oversubscribed past
# the cores), side by side, with the rounds' agreement and reduction time rank 0 reports:
#   bench/mpi_scaling.sh SCENE.json ITERATIONS "RANKSxTHREADS ..." [ROUNDS]
# e.g. bench/mpi_scaling.sh ../shared/scenes/cbox-trans/transient.json 12 "1x2 2x1 4x1" 2
# Prints per configuration: wall seconds, s/iteration, rank 0's seconds in agreement + reductions, the
# reductions and their size, the MSE of its image against the first configuration's, and the memory rank 0
# reports (the guard's estimate before the render / peak resident). Extra render arguments (e.g.
# "--set resolution=480") go in MPI_ARGS. "1x1 1x2 2x1" gives the thread scaling and the cost of the split.
# Output: out/mpi_scaling/<stem>/.
set -eu
scene=${1:?scene file}; its=${2:-12}; configs=${3:-1x2 2x1 4x1}; rounds=${4:-2}
mpirun="mpirun --allow-run-as-root --oversubscribe --mca plm_rsh_agent false --mca btl_vader_single_copy_mechanism none"
make build/dartspp build/dartspp-mpi >&2 # a stale dartspp-mpi would time older code
o=out/mpi_scaling/$(basename "$scene" .json)
rm -rf "$o" && mkdir -p "$o"
echo "date: $(date -u +%Y-%m-%dT%H:%MZ)  machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
echo "scene: $scene, $its iterations, seed 3, $rounds rounds alternating over: $configs"
echo
echo "render arguments: ${MPI_ARGS:-(none)}"
echo
echo "| ranks × threads | round | wall s | s/iteration | rank 0 in agreement + reductions | reductions | image vs the first | memory: estimate / peak |"
echo "|---|---|---|---|---|---|---|---|"
r=1
while [ "$r" -le "$rounds" ]; do
    for c in $configs; do
        n=${c%x*}; t=${c#*x}
        img=$o/$c-$r.exr
        start=$(date +%s.%N)
        if [ "$n" = 1 ]; then
            # shellcheck disable=SC2086
            build/dartspp render "$scene" --threads "$t" --spp "$its" --seed 3 ${MPI_ARGS:-} --quiet --output "$img" > "$o/$c-$r.txt" 2>&1
        else
            # shellcheck disable=SC2086
            $mpirun -np "$n" build/dartspp-mpi render "$scene" --threads "$t" --spp "$its" --seed 3 ${MPI_ARGS:-} --quiet --output "$img" \
                > "$o/$c-$r.txt" 2>&1
        fi
        end=$(date +%s.%N)
        wall=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }')
        per=$(awk -v w="$wall" -v n="$its" 'BEGIN { printf "%.3f", w / n }')
        cl=$(sed -n 's/^cluster: \([0-9]*\) film reductions of \(.*\) from each rank; rank 0 spent \([0-9.]*\) s.*/\3 s|\1 × \2/p' "$o/$c-$r.txt")
        [ -n "$cl" ] || cl="—|—"
        diff="—"
        [ "$c" = "$(echo "$configs" | cut -d' ' -f1)" ] || diff=$(build/dartspp compare "$img" "$o/$(echo "$configs" | cut -d' ' -f1)-$r.exr" | awk '$1 == "mse" { print "MSE " $2; exit }')
        mem=$(sed -n 's/^memory: estimated \(.*\) before the render, peak resident \(.*\)$/\1 \/ \2/p' "$o/$c-$r.txt" | head -1)
        echo "| $c | $r | $wall | $per | $cl | $diff | ${mem:-—} |"
    done
    r=$((r + 1))
done
