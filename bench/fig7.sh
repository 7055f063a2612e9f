#!/bin/sh
# The paper's Fig. 7 comparison on 2 cores: bench/fig7.sh [SECONDS] [SEEDS] [REF_SECONDS]
# For each scene and gate below: an unbiased reference (bench/reference.sh: our DARTS path tracer, which the
# scene's keys select once the integrator is the path tracer; 4 chunks, their spread is the reference noise),
# then bench/compare_methods.sh at equal time (SECONDS per run, default 30; SEEDS seeds, default 2). The fog
# Cornell box uses the shared unbiased 40-minute reference (../shared/references) at its own 512².
# Resolutions are reduced to fit 2 cores (the dragon 240² of 960², the staircase 180² of 720²); both gates
# of the paper's Fig. 7 for the dragon and the staircase. Needs ../shared (the paper's scenes).
set -eu
secs=${1:-30}; seeds=${2:-2}; ref_secs=${3:-600}
shared=${SHARED:-../shared}
[ -d "$shared/scenes" ] || { echo "$0: needs the paper's scenes in $shared/scenes" >&2; exit 2; }
mkdir -p refs
# the fog Cornell box: the shared reference and its noise (its README: the mean of two 40-minute renders has
# variance about 0.00031 per channel value)
cp "$shared/references/cbox-trans-gate16.15-dartspp-unbiased-40min.pfm" refs/cbox-trans-unbiased.pfm
echo 0.00031 > refs/cbox-trans-unbiased.pfm.var
bench/compare_methods.sh "$shared/scenes/cbox-trans/transient.json" "$secs" "$seeds" refs/cbox-trans-unbiased.pfm \
    fig7-cbox-trans
# name | scene | resolution | gate centre
configs="dragon-4.125|dragon/scene-points-darts-short.json|240|4.125
dragon-7.125|dragon/scene-points-darts-short.json|240|7.125
staircase-12.625|staircase/scene-points-darts-short.json|180|12.625
staircase-15.375|staircase/scene-points-darts-short.json|180|15.375"
echo "$configs" | while IFS='|' read -r name file res centre; do
    set -- --set resolution="$res" --set transient_time_center="$centre"
    ref=refs/$name-$res.exr
    [ -f "$ref" ] || bench/reference.sh "$shared/scenes/$file" "$ref_secs" "$ref" "$@"
    bench/compare_methods.sh "$shared/scenes/$file" "$secs" "$seeds" "$ref" "fig7-$name" "$@"
done
