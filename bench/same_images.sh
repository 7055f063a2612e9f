#!/usr/bin/env bash
# Pixel data of two dartspp binaries side by side: the path tracer, baseline photon points, DARTS, DARTS with
# EDA and DARTS frame mode, on the demo and on the fog Cornell box; the path tracer, the DARTS path tracer and
# DARTS on the demo with its point light replaced by each other emitter type (spot, collimated beam parallel and
# diverging, directional_point, emissive quad and sphere) and on the demo with two pulses; DARTS on the paper's dragon at 64² with
# surface chains on (when the paper's scenes are beside the checkout), at a fixed seed and pass count. Prints one
# line per case, "identical" or "DIFFER", and exits 1 if any differs. A refactor that must not change
# behaviour is checked this way against the binary built from the commit before it:
#   git worktree add /tmp/base <commit> && make -C /tmp/base build/dartspp
#   bench/same_images.sh /tmp/base/build/dartspp build/dartspp
set -u
old=${1:?usage: same_images.sh OLD_DARTSPP NEW_DARTSPP}; new=${2:?usage: same_images.sh OLD_DARTSPP NEW_DARTSPP}
here=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
common="--spp 3 --seed 11 --threads 2 --quiet --set resolution=48"
baseline="--set enable_guiding=false --set enable_elliptical=false --set strict_time_width=false"
# every sensor output: frames and their cube, scattering-order layers, ground truth, the sensor's jitter and tail
sensor="--set frame_num=4 --set transient_time_width=0.5 --set start_time=5 --set bounce_orders=3 --set ground_truth=true --set sensor_jitter_fwhm=0.2 --set sensor_jitter_tail=0.1"
eda="--set eda=true --set eda_shape=[16,16,32] --set eda_table_dir=$work/tables"
paper=${DARTSPP_PAPER_SCENES:-$here/../shared/scenes}
# One scene per emitter type (gen:NAME): the demo fog box with its point light replaced, as in
# bench/emitter_costs.sh (a spot, a parallel and a diverging collimated beam, a directional_point, an emissive
# quad and sphere); scenes/fogbox/two-pulses.json has the pulses.
python3 - "$here/scenes/fogbox/fogbox.json" "$work" <<'PY' || exit 1
import json, sys
base = json.load(open(sys.argv[1]))
at, aim = [0, 1.75, 0.1], {"position": [0, 1.75, 0.1], "look_at": [0.3, 0, 0.3], "up": [0, 0, 1]}
lights = {
    'spot': {"type": "spot", "emission": 30, "coneangle": 40, "conedeltaangle": 10,
             "transform": {"position": at, "look_at": [0, 0, 0.1], "up": [0, 0, 1]}},
    'beam': {"type": "collimated", "radius": 0.05, "emission": 9600, "transform": aim},
    'diverging-beam': {"type": "collimated", "radius": 0.05, "divergence": 2, "emission": 9600, "transform": aim},
    'directional-point': {"type": "directional_point", "power": 75, "transform": aim},
    'quad': {"type": "quad", "bsdf": "white", "emission": 60, "int_medium": "fog",
             "transform": {"position": at, "scale": [0.2, 1, 0.2], "rotation": [180, 0, 0]}},
    'sphere': {"type": "sphere", "bsdf": "white", "emission": 19, "int_medium": "fog",
               "transform": {"position": at, "scale": 0.1}},
}
for name, light in lights.items():
    s = json.loads(json.dumps(base))
    s['primitives'] = [p for p in s['primitives'] if p['type'] != 'point'] + [dict(light, name=name, ext_medium="fog")]
    json.dump(s, open(f'{sys.argv[2]}/{name}.json', 'w'), indent=1)
PY
bad=0
while IFS='|' read -r name scene args; do
  [ -n "$name" ] || continue
  case $scene in
    paper:*) scene=$paper/${scene#paper:}
             [ -f "$scene" ] || { echo "$name: skipped ($scene not found)"; continue; } ;;
    gen:*) scene=$work/${scene#gen:}.json ;;
    *) scene=$here/$scene ;;
  esac
  for which in old new; do
    bin=${!which}
    # shellcheck disable=SC2086
    "$bin" render "$scene" $common $args --output "$work/$which/$name.pfm" >/dev/null 2>"$work/$which-$name.err" ||
      { echo "$name: $which binary failed: $(tail -1 "$work/$which-$name.err")"; bad=1; continue 2; }
  done
  # the sensor-output cases: also the photon counts of the cube (a SPAD with pile-up and the Coates correction)
  if [ -e "$work/old/${name}_cube.npy" ] && [ "${name#sensor}" != "$name" ]; then
    for which in old new; do
      "${!which}" counts "$work/$which/${name}_cube.npy" --output "$work/$which/${name}_counts.npy" --pulses 1000 \
        --scale 50 --dark-rate 0.01 --dead-time 100 --coates --seed 5 >/dev/null 2>&1 ||
        { echo "$name: $which binary's counts failed"; bad=1; }
    done
  fi
  same=1
  # every image, frame, ground-truth image, cube, order layer and counts file the render wrote
  for f in "$work/old/$name".pfm "$work/old/$name"_*.pfm "$work/old/$name"_*.npy "$work/old/$name"_*.csv; do
    [ -e "$f" ] || continue
    cmp -s "$f" "$work/new/${f#"$work/old/"}" || same=0
  done
  if [ $same = 1 ]; then echo "$name: identical"; else echo "$name: DIFFER"; bad=1; fi
done <<CASES
demo-path-tracer|scenes/fogbox/fogbox.json|--set type=path_tracer --set enable_guiding=false --set enable_elliptical=false
demo-baseline|scenes/fogbox/fogbox.json|$baseline
demo-darts|scenes/fogbox/fogbox.json|
demo-darts-eda|scenes/fogbox/fogbox.json|$eda
demo-darts-frames|scenes/fogbox/fogbox.json|--set frame_num=4 --set transient_time_width=0.5 --set start_time=5
cbox-path-tracer|scenes/cbox-fog/path_tracer.json|
cbox-baseline|scenes/cbox-fog/transient.json|$baseline
cbox-darts|scenes/cbox-fog/transient.json|
cbox-darts-eda|scenes/cbox-fog/transient.json|$eda
cbox-darts-frames|scenes/cbox-fog/transient.json|--set frame_num=4 --set transient_time_width=0.2 --set start_time=15.8
spot-path-tracer|gen:spot|--set type=path_tracer --set enable_guiding=false --set enable_elliptical=false
spot-darts-pt|gen:spot|--set type=path_tracer
spot-darts|gen:spot|
beam-path-tracer|gen:beam|--set type=path_tracer --set enable_guiding=false --set enable_elliptical=false
beam-darts-pt|gen:beam|--set type=path_tracer
beam-darts|gen:beam|
diverging-beam-path-tracer|gen:diverging-beam|--set type=path_tracer --set enable_guiding=false --set enable_elliptical=false
diverging-beam-darts-pt|gen:diverging-beam|--set type=path_tracer
diverging-beam-darts|gen:diverging-beam|
directional-point-path-tracer|gen:directional-point|--set type=path_tracer --set enable_guiding=false --set enable_elliptical=false
directional-point-darts-pt|gen:directional-point|--set type=path_tracer
directional-point-darts|gen:directional-point|
quad-path-tracer|gen:quad|--set type=path_tracer --set enable_guiding=false --set enable_elliptical=false
quad-darts-pt|gen:quad|--set type=path_tracer
quad-darts|gen:quad|
sphere-path-tracer|gen:sphere|--set type=path_tracer --set enable_guiding=false --set enable_elliptical=false
sphere-darts-pt|gen:sphere|--set type=path_tracer
sphere-darts|gen:sphere|
pulses-path-tracer|scenes/fogbox/two-pulses.json|--set type=path_tracer --set enable_guiding=false --set enable_elliptical=false
pulses-darts-pt|scenes/fogbox/two-pulses.json|--set type=path_tracer
pulses-darts|scenes/fogbox/two-pulses.json|
sensor-outputs-darts|scenes/fogbox/two-pulses.json|$sensor
sensor-outputs-path-tracer|scenes/fogbox/two-pulses.json|$sensor --set type=path_tracer --set enable_guiding=false --set enable_elliptical=false
sensor-outputs-darts-pt|scenes/fogbox/two-pulses.json|$sensor --set type=path_tracer
dragon-darts-chains|paper:dragon/scene-points-darts-short.json|--set resolution=64 --set surface_chains=true
CASES
exit $bad
