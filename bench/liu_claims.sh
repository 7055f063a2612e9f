#!/bin/sh
# Liu, Jiao and Jarosz 2022's claims at equal time on their three example scenes (../shared/scenes/liu2022,
# unchanged): the score-based MIS of sliced balls and parallelepipeds (mis_volumes_balls, the files' own
# volume photon type) against progressive transient photon beams (pb: 1-D beams with the spatio-temporal
# schedule under the files' delta gate), each with the baseline photon pass, camera-unwarped as Liu rendered
# them (--set camera_unwarp=true). His protocol (Liu et al. 2022 §6): 8 cores of a Xeon E5-2640V3, 1.5 minutes (SUBSURFACE
# SCATTERING) and 10 minutes (CORNELL BOX, VOLUMETRIC CAUSTIC) at 1000×563 and 563²; he reports variance
# 20–40× lower on SUBSURFACE and 2–4× on CORNELL BOX. Ours: 2 cores, SECONDS per run, SEEDS seeds, a quarter
# of his resolution; the figure compared is the seed variance (no reference can be made for a delta gate by an
# estimator not under test: the path tracer cannot hit a delta), with its 95 % interval (bench/seed_stats.py).
# bench/liu_claims.sh [SECONDS] [SEEDS]; tables in bench/results/liu-<scene>-methods-<SECONDS>s.md.
set -eu
secs=${1:-20}; seeds=${2:-8}
shared=${SHARED:-../shared}
[ -d "$shared/scenes/liu2022" ] || { echo "$0: needs Liu's scenes in $shared/scenes/liu2022" >&2; exit 2; }
for cfg in subsurface-scattering:250x141 cornell-box:141x141 volumetric-caustic:250x141; do
    name=${cfg%%:*}; res=${cfg#*:}
    METHODS=${METHODS:-"pb mis_volumes_balls"} BASE=pb bench/compare_methods.sh "$shared/scenes/liu2022/$name/scene.json" \
        "$secs" "$seeds" - "liu-$name" --set camera_unwarp=true --set resolution="$res"
done
