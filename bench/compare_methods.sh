#!/bin/sh
# The DARTS paper's comparison set at equal time (its Fig. 7 and paper §6.1): bench/compare_methods.sh SCENE.json SECONDS
# SEEDS [REFERENCE.exr|-] [NAME] [render args...]
# Renders SCENE with each method for SECONDS of wall time, SEEDS seeds (8 or more: fewer are refused unless
# FEW_SEEDS=1), the methods alternating inside each seed (a slow spell of the machine falls on all of them), and
# prints the paper's table: per method the passes, the MSE against REFERENCE (and MSE − V_ref when
# REFERENCE.var holds the reference's own noise), the trimmed MSE (the 0.1 % of pixels of largest error
# dropped), the papers' q99-normalised MSE, each relative to DARTS PT, each method's own variance from the
# spread of its seeds (no reference needed), and the bias² of its seeds' mean apart from that noise, each ratio
# with a 95 % interval over seeds (bench/seed_stats.py; BASE=method picks the denominator, DARTS PT by default). Methods (METHODS="..." picks a subset, in this order):
#   uniform_pt  uniform-time path tracer (Jarabo et al. 2014 as the DARTS supplement B.4 corrects it)
#   pt          plain path tracer
#   pp          baseline progressive photon points
#   darts_pt    DARTS path tracer (DA distance sampling + elliptical light connections), as the paper's files key it
#   darts_pt_eda  DARTS path tracer with elliptical light connections and EDA directions, DA off (not in the
#               default set: METHODS="... darts_pt_eda"; its EDA tables are cached in tables/)
#   darts_pp    DARTS photon points (DA + elliptical control vertices)
#   pb          baseline progressive transient photon beams (1-D kernel; docs/beams.md), not in the default set
#   darts_pb    DARTS photon beams (long beams from the DARTS photon pass), not in the default set
#   balls volumes hypervolumes volumes_balls mis_volumes_balls planes planes_1d
#               Liu et al. 2022's temporally sliced photon primitives (docs/sliced_primitives.md), baseline
#               photon pass, not in the default set
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
[ "$seeds" -ge 8 ] || [ "${FEW_SEEDS:-}" = 1 ] ||
    { echo "$0: $seeds seeds: ratios need 8 or more for their intervals (FEW_SEEDS=1 to try fewer)" >&2; exit 2; }
out=bench/results/$name; mkdir -p "$out"
table=bench/results/$name-methods-${secs}s.md
pt="--set type=path_tracer"
pp="--set type=progressive_transient_photon_map --set volume_photon_type=points"
pb="--set type=progressive_transient_photon_map --set volume_photon_type=beams"
sliced="--set type=progressive_transient_photon_map --set volume_photon_type"
off="--set enable_guiding=false --set enable_elliptical=false --set eda=false"
on="--set enable_guiding=true --set enable_elliptical=true"
methods="uniform_pt|$pt $off --set time_sampling=uniform
pt|$pt $off
pp|$pp $off
darts_pt|$pt $on
darts_pt_eda|$pt --set enable_guiding=false --set enable_elliptical=true --set eda=true
darts_pp|$pp $on
pb|$pb $off
darts_pb|$pb $on
balls|$sliced=balls $off
volumes|$sliced=volumes $off
hypervolumes|$sliced=hypervolumes $off
volumes_balls|$sliced=volumes_balls $off
mis_volumes_balls|$sliced=mis_volumes_balls $off
planes|$sliced=planes $off
planes_1d|$sliced=planes_1d $off"
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
# the table: bench/seed_stats.py (per method passes, MSE and MSE/q99² against REFERENCE over all seeds, the seed
# variance from disjoint pairs of seeds, each ratio to BASE with a 95 % bootstrap interval over seeds)
base=${BASE:-darts_pt}
case " $only " in *" $base "*) ;; *) base=${only%% *} ;; esac
paper() {
    case $1 in
    uniform_pt) echo "2–4 (paper §6.1: DARTS PT reduces MSE 2–4× against uniform-time PT)" ;;
    pt) echo "≥ 10 at equal spp (paper §6.3, Fig. 11: at least an order of magnitude)" ;;
    pp) echo "> 1 in most scenes (paper §6.1)" ;;
    darts_pt) echo "1" ;;
    darts_pt_eda) echo "(not in the paper: its PT results use no EDA)" ;;
    darts_pp) echo "< 1 (paper §6.1: DARTS PP further increased the gap)" ;;
    pb) echo "> 1 (paper §6.1, Fig. 7: 1-D progressive transient photon beams behind DARTS PT and PP)" ;;
    darts_pb) echo "below pb, above darts_pp (supplement §C.3, Fig. VI)" ;;
    mis_volumes_balls) echo "(Liu et al. 2022 §6: 20–40× less variance than pb on SUBSURFACE, 2–4× on CORNELL BOX)" ;;
    balls|volumes|hypervolumes|volumes_balls|planes|planes_1d) echo "(not in the paper)" ;;
    esac
}
{
    echo "Methods at equal time: \`$scene\` ${extra:+(\`$extra\`) }$secs s per run, $seeds seed(s), reference \`$ref\`"
    echo "($(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))"
    [ "$vref" != 0 ] && echo "Reference noise V_ref = $vref (variance of the reference mean, from its chunks), subtracted below."
    echo
    DARTSPP=$bin /usr/bin/python3 bench/seed_stats.py "$out" "$base" "$only" "$seeds" "$ref" "$vref"
    echo
    echo "The paper's ratios to DARTS PT, for comparison:"
    for label in $only; do echo "- $label: $(paper "$label")"; done
} | tee "$table"
