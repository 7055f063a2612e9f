#!/bin/sh
# Equal-time comparison: bench/equal_time.sh SCENE.json REFERENCE.exr SECONDS [NAME] [SEEDS] [render args...]
# Renders the scene for the same wall time with the path tracer, baseline photon points, DARTS photon points
# and the DARTS ablations (elliptical only, DA only), each logging its error against REFERENCE, and prints
# a Markdown table of the final errors and their ratios to DARTS (mean over SEEDS seeds, default 1).
# Logs and images go to bench/results/NAME/ (NAME defaults to the scene stem); the table to
# bench/results/NAME-equal-time-SECONDSs.md. Uses only the command line.
set -eu
[ $# -ge 3 ] || { echo "usage: $0 SCENE.json REFERENCE.exr SECONDS [NAME] [SEEDS]" >&2; exit 2; }
scene=$1; ref=$2; secs=$3; name=${4:-$(basename "$scene" .json)}; seeds=${5:-1}
[ $# -ge 5 ] && shift 5 || shift $#
extra="$*"
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
out=bench/results/$name; mkdir -p "$out"
table=bench/results/$name-equal-time-${secs}s.md
# method label | --set arguments
methods="path_tracer|--set type=path_tracer
baseline|--set enable_guiding=false --set enable_elliptical=false
elliptical_only|--set enable_guiding=false --set enable_elliptical=true
da_only|--set enable_guiding=true --set enable_elliptical=false
darts|--set enable_guiding=true --set enable_elliptical=true"
only=${METHODS:-path_tracer baseline elliptical_only da_only darts} # METHODS="baseline darts" runs a subset
echo "$methods" | while IFS='|' read -r label sets; do
    case " $only " in *" $label "*) ;; *) continue ;; esac
    s=1
    while [ "$s" -le "$seeds" ]; do
        # shellcheck disable=SC2086
        "$bin" render "$scene" $sets $extra --time "$secs" --seed "$s" --quiet --output "$out/$label-s$s.exr" \
            --reference "$ref" --log "$out/$label-s$s.csv" --log-every 1 > "$out/$label-s$s.txt"
        s=$((s + 1))
    done
done
{
    echo "Equal time: \`$scene\` ${extra:+(\`$extra\`) }$secs s per run, $seeds seed(s), against \`$ref\`"
    echo "($(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))"
    echo
    echo "| method | iterations | photon paths | early exits | MSE | relative MSE | MSE/q99² | MSE ÷ DARTS MSE |"
    echo "|---|---|---|---|---|---|---|---|"
    awk -F, -v seeds="$seeds" -v dir="$out" -v only="$only" '
        function last_row(file,   line, l) { l = ""; while ((getline line < file) > 0) l = line; close(file); return l }
        function early(file,   line, e) { e = "-"; while ((getline line < file) > 0) if (line ~ /^early exit:/) { split(line, a, " "); e = a[3] } close(file); return e }
        BEGIN {
            n = split(only, m, " ")
            for (i = 1; i <= n; i++) {
                it[i] = pp[i] = mse[i] = rel[i] = q[i] = 0
                for (s = 1; s <= seeds; s++) {
                    split(last_row(dir "/" m[i] "-s" s ".csv"), f, ",")
                    it[i] += f[2] / seeds; pp[i] += f[3] / seeds; mse[i] += f[7] / seeds; rel[i] += f[8] / seeds; q[i] += f[9] / seeds
                }
                ex[i] = early(dir "/" m[i] "-s1.txt")
            }
            for (i = 1; i <= n; i++)
                printf("| %s | %.0f | %.3g | %s | %.4g | %.4g | %.4g | %.2f |\n", m[i], it[i], pp[i], ex[i], mse[i], rel[i], q[i], mse[i] / mse[n])
        }' /dev/null
} | tee "$table"
