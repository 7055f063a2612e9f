#!/bin/sh
# Equal-time comparison: bench/equal_time.sh SCENE.json REFERENCE.exr SECONDS [NAME] [SEEDS] [render args...]
# Renders the scene for the same wall time with the path tracer, baseline photon points, DARTS photon points
# and the DARTS ablations (elliptical only, DA only), each logging its error against REFERENCE, and prints
# a Markdown table of the final errors and their ratios to DARTS (mean over SEEDS seeds, default 1).
# Logs and images go to bench/results/NAME/ (NAME defaults to the scene stem); the table to
# bench/results/NAME-equal-time-SECONDSs.md. Uses only the command line.
# When REFERENCE.var exists (written by bench/reference.sh), the table also gives MSE − V_ref: the
# expected MSE against the reference is the MSE against the truth plus the reference's own variance V_ref,
# so subtracting it estimates the error against the truth, and the ratios are taken on that.
# With SEEDS >= 2 the table also gives each method's own variance at that time, measured without any
# reference from the spread of its seeds (MSE between seeds 1 and 2, halved), and its ratio to DARTS's.
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
# seeds outer, methods inner: the methods alternate, so a slow spell of the machine (shared hosts drift by
# 20 % over minutes) falls on all of them rather than on one
s=1
while [ "$s" -le "$seeds" ]; do
    echo "$methods" | while IFS='|' read -r label sets; do
        case " $only " in *" $label "*) ;; *) continue ;; esac
        # shellcheck disable=SC2086
        "$bin" render "$scene" $sets $extra --time "$secs" --seed "$s" --quiet --output "$out/$label-s$s.exr" \
            --reference "$ref" --log "$out/$label-s$s.csv" --log-every 1 > "$out/$label-s$s.txt"
    done
    s=$((s + 1))
done
vref=0
[ -f "$ref.var" ] && vref=$(cat "$ref.var")
# variance of each method from its first two seeds (no reference involved)
for label in $only; do
    v="-"
    if [ "$seeds" -ge 2 ]; then
        v=$("$bin" compare "$out/$label-s1.exr" "$out/$label-s2.exr" --csv | awk -F, '{ printf "%.6g", $1 / 2 }')
    fi
    echo "$label $v"
done > "$out/seed-variance.txt"
{
    echo "Equal time: \`$scene\` ${extra:+(\`$extra\`) }$secs s per run, $seeds seed(s), against \`$ref\`"
    echo "($(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))"
    if [ "$vref" != 0 ]; then echo "Reference noise V_ref = $vref (variance of the reference mean, from its chunks)."; fi
    echo
    echo "| method | iterations | photon paths | early exits | MSE | MSE − V_ref | relative MSE | MSE/q99² | (MSE − V_ref) ÷ DARTS's | variance (seeds) | ÷ DARTS's |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|"
    awk -F, -v seeds="$seeds" -v dir="$out" -v only="$only" -v vref="$vref" '
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
            while ((getline line < (dir "/seed-variance.txt")) > 0) { split(line, a, " "); sv[a[1]] = a[2] }
            d = mse[n] - vref
            for (i = 1; i <= n; i++) {
                vr = (sv[m[i]] != "-" && sv[m[n]] + 0 > 0) ? sprintf("%.2f", sv[m[i]] / sv[m[n]]) : "-"
                printf("| %s | %.0f | %.3g | %s | %.4g | %.4g | %.4g | %.4g | %.2f | %s | %s |\n", m[i], it[i], pp[i], ex[i],
                       mse[i], mse[i] - vref, rel[i], q[i], d > 0 ? (mse[i] - vref) / d : 0, sv[m[i]], vr)
            }
        }' /dev/null
} | tee "$table"
