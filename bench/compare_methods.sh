#!/bin/sh
# The DARTS paper's comparison set at equal time (its Fig. 7 and paper §6.1): bench/compare_methods.sh SCENE.json SECONDS
# SEEDS [REFERENCE.exr|-] [NAME] [render args...]
# Renders SCENE with each method for SECONDS of wall time, SEEDS seeds, the methods alternating inside each
# seed (a slow spell of the machine falls on all of them), and prints the paper's table: per method the
# passes, the MSE against REFERENCE (and MSE − V_ref when REFERENCE.var holds the reference's own noise), the
# papers' q99-normalised MSE, each relative to DARTS PT, and each method's own variance from the spread of
# its seeds (no reference needed; SEEDS >= 2). Methods (METHODS="..." picks a subset, in this order):
#   uniform_pt  uniform-time path tracer (Jarabo et al. 2014 as the DARTS supplement B.4 corrects it)
#   pt          plain path tracer
#   pp          baseline progressive photon points
#   darts_pt    DARTS path tracer (DA distance sampling + elliptical light connections), as the paper's files key it
#   darts_pt_eda  DARTS path tracer with elliptical light connections and EDA directions, DA off (not in the
#               default set: METHODS="... darts_pt_eda"; its EDA tables are cached in tables/)
#   darts_pp    DARTS photon points (DA + elliptical control vertices)
#   pb          baseline progressive transient photon beams (1-D kernel; docs/beams.md), not in the default set
#   darts_pb    DARTS photon beams (long beams from the DARTS photon pass), not in the default set
# The scene's own integrator keys (photon
# counts, radii, bounces, gate) are kept; only the method's keys are set. Images, logs and error-against-time
# rows (with REFERENCE, one per second) go to bench/results/NAME/; the table to
# bench/results/NAME-methods-SECONDSs.md. Uses only the command line.
set -eu
[ $# -ge 3 ] || { echo "usage: $0 SCENE.json SECONDS SEEDS [REFERENCE.exr|-] [NAME] [render args...]" >&2; exit 2; }
scene=$1; secs=$2; seeds=$3; ref=${4:--}; name=${5:-$(basename "$scene" .json)}
[ $# -ge 5 ] && shift 5 || shift $#
extra="$*"
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
[ "$ref" = - ] || [ -f "$ref" ] || { echo "$0: no reference image $ref" >&2; exit 2; }
out=bench/results/$name; mkdir -p "$out"
table=bench/results/$name-methods-${secs}s.md
pt="--set type=path_tracer"
pp="--set type=progressive_transient_photon_map --set volume_photon_type=points"
pb="--set type=progressive_transient_photon_map --set volume_photon_type=beams"
off="--set enable_guiding=false --set enable_elliptical=false --set eda=false"
on="--set enable_guiding=true --set enable_elliptical=true"
methods="uniform_pt|$pt $off --set time_sampling=uniform
pt|$pt $off
pp|$pp $off
darts_pt|$pt $on
darts_pt_eda|$pt --set enable_guiding=false --set enable_elliptical=true --set eda=true
darts_pp|$pp $on
pb|$pb $off
darts_pb|$pb $on"
only=${METHODS:-uniform_pt pt pp darts_pt darts_pp}
s=1
while [ "$s" -le "$seeds" ]; do
    echo "$methods" | while IFS='|' read -r label sets; do
        case " $only " in *" $label "*) ;; *) continue ;; esac
        log=""
        [ "$ref" = - ] || log="--reference $ref --log $out/$label-s$s.csv --log-every 1"
        echo "seed $s: $label" >&2
        # shellcheck disable=SC2086
        "$bin" render "$scene" $sets $extra --time "$secs" --seed "$s" --quiet --no-cube --no-viewer --overwrite \
            --output "$out/$label-s$s.exr" $log > "$out/$label-s$s.txt" 2> "$out/$label-s$s.err"
    done
    s=$((s + 1))
done
vref=0
[ "$ref" != - ] && [ -f "$ref.var" ] && vref=$(cat "$ref.var")
# per method: passes (mean over seeds), MSE and MSE/q99² against the reference (mean over seeds), seed variance
for label in $only; do
    passes=0; mse=0; q=0; s=1
    while [ "$s" -le "$seeds" ]; do
        p=$(sed -n 's/^rendered \([0-9]*\) passes.*/\1/p' "$out/$label-s$s.txt")
        passes=$(awk -v a="$passes" -v b="${p:-0}" -v n="$seeds" 'BEGIN { print a + b / n }')
        if [ "$ref" != - ]; then
            row=$("$bin" compare "$out/$label-s$s.exr" "$ref" --csv)
            mse=$(echo "$row" | awk -F, -v a="$mse" -v n="$seeds" '{ print a + $1 / n }')
            q=$(echo "$row" | awk -F, -v a="$q" -v n="$seeds" '{ print a + $4 / n }')
        fi
        s=$((s + 1))
    done
    v=-
    [ "$seeds" -ge 2 ] && v=$("$bin" compare "$out/$label-s1.exr" "$out/$label-s2.exr" --csv | awk -F, '{ printf "%.6g", $1 / 2 }')
    echo "$label $passes $mse $q $v"
done > "$out/summary.txt"
paper() {
    case $1 in
    uniform_pt) echo "2–4 (paper §6.1: DARTS PT reduces MSE 2–4× against uniform-time PT)" ;;
    pt) echo "≥ 10 at equal spp (paper §6.3, Fig. 11: at least an order of magnitude)" ;;
    pp) echo "> 1 in most scenes (paper §6.1)" ;;
    darts_pt) echo "1" ;;
    darts_pt_eda) echo "(not in the paper: its PT results use no EDA)" ;;
    darts_pp) echo "< 1 (paper §6.1: DARTS PP further increased the gap)" ;;
    esac
}
{
    echo "Methods at equal time: \`$scene\` ${extra:+(\`$extra\`) }$secs s per run, $seeds seed(s), reference \`$ref\`"
    echo "($(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))"
    [ "$vref" != 0 ] && echo "Reference noise V_ref = $vref (variance of the reference mean, from its chunks), subtracted below."
    echo
    echo "| method | passes | MSE − V_ref | ÷ DARTS PT | MSE/q99² | ÷ DARTS PT | variance (seeds) | ÷ DARTS PT | paper, ÷ DARTS PT |"
    echo "|---|---|---|---|---|---|---|---|---|"
    while read -r label passes mse q v; do
        set -- $(grep '^darts_pt ' "$out/summary.txt" || echo x 0 0 0 -)
        awk -v l="$label" -v p="$passes" -v m="$mse" -v q="$q" -v v="$v" -v dm="$3" -v dq="$4" -v dv="$5" \
            -v vref="$vref" -v paper="$(paper "$label")" 'BEGIN {
            e = m - vref; de = dm - vref
            r1 = de > 0 ? sprintf("%.2f", e / de) : "-"; r2 = dq > 0 ? sprintf("%.2f", q / dq) : "-"
            r3 = (v != "-" && dv != "-" && dv > 0) ? sprintf("%.2f", v / dv) : "-"
            printf("| %s | %.0f | %.4g | %s | %.4g | %s | %s | %s | %s |\n", l, p, e, r1, q, r2, v, r3, paper) }'
    done < "$out/summary.txt"
} | tee "$table"
